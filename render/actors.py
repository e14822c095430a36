"""The things a :class:`~flipstudy.render.scene.Scene` draws, each one VTK actor
created once and updated in place: a posable :class:`Character` (a
:class:`~flipstudy.render.geometry.BodyMesh`), :class:`Markers` (spheres),
a :class:`Polyline` and an :class:`Arrow`."""
from __future__ import annotations

import numpy as np

from flipstudy.stimuli.body import Body

from ._pv import pv
from .characters import character_mesh, joint_sides, side_tones
from .style import Style, rgb


class Character:
    """A posable body drawn by one actor (created once per scene slot), in the
    style's character style (:mod:`flipstudy.render.characters`), its left and
    right limbs in two tones of the colour (``Style.sided``)."""

    def __init__(self, plotter, body: Body, style: Style, name: str, inflate: float = 0.0):
        self.style = style
        self.inflate = float(inflate)
        self.plotter = plotter
        self.name = name
        self.actor = None
        self._build(body)

    def _build(self, body: Body) -> None:
        st = self.style
        self.body_mesh = character_mesh(body, st, self.inflate)
        mesh = self.body_mesh.mesh
        mesh.point_data["rgb"] = np.zeros((mesh.n_points, 3), np.uint8)
        self._rgb = np.asarray(mesh.point_data["rgb"])
        flat = st.character == "point-light"
        old = self.actor
        vis = True if old is None else bool(old.GetVisibility())
        self.actor = self.plotter.add_mesh(
            mesh, scalars="rgb", rgb=True, show_scalar_bar=False, smooth_shading=False,
            name=self.name, reset_camera=False, ambient=1.0 if flat else st.ambient,
            diffuse=0.0 if flat else st.diffuse, specular=0.0 if flat else st.specular,
            specular_power=st.specular_power)
        self.actor.prop.interpolation = "gouraud"
        # PyVista puts a Python VTK filter (its ActiveScalarsAlgorithm: a shallow
        # copy with "rgb" made active) between the mesh and the mapper, which runs
        # again on every frame the points move (~1 ms of Python per frame): make
        # "rgb" the mesh's own active scalars and feed the mapper the mesh itself
        mesh.GetPointData().SetActiveScalars("rgb")
        self.actor.mapper.SetInputData(mesh)
        self.actor.SetVisibility(vis)
        self._look = None
        self._look_args = getattr(self, "_look_args", None)
        if self._look_args is not None:
            self.look(*self._look_args)

    def set_body(self, body: Body) -> None:
        if body is self.body_mesh.body:
            return
        bm = self.body_mesh
        if self.style.character == "ellipsoids" and bm.joint.size == \
                len(set(body.segment.tolist())):
            bm.set_body(body)                       # same number of pieces: arrays kept
            bm.side = np.repeat(joint_sides(body.skeleton)[bm.joint], bm.points_per_piece)
            self._look = None
            if self._look_args is not None:
                self.look(*self._look_args)
        else:
            self._build(body)

    def tones(self, color) -> np.ndarray:
        """(3,3) trunk, left and right colours (0..1) the body is drawn in."""
        st = self.style
        if not st.sided:
            return np.array([rgb(color)] * 3)
        if st.side_colors is not None and str(color) == str(st.body_color):
            return np.array([rgb(c) for c in st.side_colors])
        return side_tones(color, st.side_lightness)

    def look(self, color, opacity: float = 1.0) -> None:
        """Colour (in sided tones) and opacity; translucent bodies cull back
        faces so a ghost reads as one layer."""
        key = (str(color), float(opacity))
        self._look_args = (color, opacity)
        if key == self._look:
            return
        self._look = key
        t = np.rint(self.tones(color) * 255).astype(np.uint8)
        self._rgb[:] = t[self.body_mesh.side]
        self.body_mesh.mesh.GetPointData().GetArray("rgb").Modified()
        self.body_mesh.mesh.Modified()
        p = self.actor.prop
        p.opacity = float(opacity)
        p.culling = "back" if opacity < 1.0 else "none"

    def pose(self, R: np.ndarray, P: np.ndarray) -> None:
        self.body_mesh.pose(R, P)

    @property
    def visible(self) -> bool:
        return bool(self.actor.GetVisibility())

    @visible.setter
    def visible(self, v: bool) -> None:
        self.actor.SetVisibility(bool(v))


class Markers:
    """Up to ``capacity`` spheres of one colour, in one actor (glyphs rebuilt
    from a fixed-size point set; unused points are parked on the first one)."""

    def __init__(self, plotter, name: str, capacity: int, radius: float, color, style: Style):
        self.capacity = int(capacity)
        self.points = pv.PolyData(np.zeros((self.capacity, 3)))
        sphere = pv.Sphere(radius=radius, theta_resolution=12, phi_resolution=8)
        self._glyph = self.points.glyph(geom=sphere, orient=False, scale=False)
        self.actor = plotter.add_mesh(self._glyph, color=color, name=name, reset_camera=False,
                                      smooth_shading=True, ambient=0.35, diffuse=0.7, specular=0.1)
        self.actor.mapper.scalar_visibility = False
        self._sphere_pts = np.asarray(sphere.points).copy()
        self._n = self._sphere_pts.shape[0]
        self._gpts = np.asarray(self._glyph.points)

    def set(self, pts: np.ndarray) -> None:
        pts = np.asarray(pts, float).reshape(-1, 3)
        if pts.shape[0] > self.capacity:
            raise ValueError(f"Markers: {pts.shape[0]} markers, capacity {self.capacity}")
        full = np.empty((self.capacity, 3))
        if pts.shape[0]:
            full[: pts.shape[0]] = pts
            full[pts.shape[0]:] = pts[0]
        else:
            full[:] = 0.0
        out = self._gpts.reshape(self.capacity, self._n, 3)
        np.add(full[:, None, :], self._sphere_pts[None], out=out)
        self._glyph.GetPoints().Modified()
        self._glyph.Modified()
        self.actor.SetVisibility(pts.shape[0] > 0)


class Polyline:
    """A polyline of up to ``capacity`` points (unused points repeat the last)."""

    def __init__(self, plotter, name: str, capacity: int, color, width: float, closed=False,
                 opacity: float = 1.0):
        self.capacity = int(capacity)
        n = self.capacity + (1 if closed else 0)
        idx = np.arange(n) % self.capacity
        self.mesh = pv.PolyData(np.zeros((self.capacity, 3)), lines=np.hstack([[n], idx]))
        self.actor = plotter.add_mesh(self.mesh, color=color, line_width=width, name=name,
                                      reset_camera=False, lighting=False, opacity=opacity)
        self._pts = np.asarray(self.mesh.points)

    def set(self, pts: np.ndarray) -> None:
        pts = np.asarray(pts, float).reshape(-1, 3)[: self.capacity]
        if pts.shape[0] == 0:
            self.actor.SetVisibility(False)
            return
        self._pts[: pts.shape[0]] = pts
        self._pts[pts.shape[0]:] = pts[-1]
        self.mesh.GetPoints().Modified()
        self.mesh.Modified()
        self.actor.SetVisibility(True)


class Arrow:
    """An arrow from a point along a vector, posed in place (template along +x)."""

    def __init__(self, plotter, name: str, color):
        tmpl = pv.Arrow(start=(0, 0, 0), direction=(1, 0, 0), tip_length=0.25, tip_radius=0.08,
                        shaft_radius=0.03, scale=1.0)
        self._tmpl = np.asarray(tmpl.points).copy()
        self.mesh = tmpl
        self.actor = plotter.add_mesh(self.mesh, color=color, name=name, reset_camera=False,
                                      ambient=0.4, diffuse=0.7)
        self._pts = np.asarray(self.mesh.points)

    def set(self, start, vec, thickness: float = 1.0) -> None:
        v = np.asarray(vec, float)
        L = float(np.linalg.norm(v))
        if L < 1e-6:
            self.actor.SetVisibility(False)
            return
        x = v / L
        h = np.array([0.0, 1.0, 0.0]) if abs(x[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
        y = np.cross(h, x)
        y /= np.linalg.norm(y)
        z = np.cross(x, y)
        # length along x; a fixed girth (tip radius 4 cm, shaft 1.5 cm) except for
        # short arrows, which are thinned so they still look like arrows
        s = 0.5 * thickness * min(1.0, L / 0.25)
        M = np.stack([x * L, y * s, z * s], axis=1)
        self._pts[:] = self._tmpl @ M.T + np.asarray(start, float)
        self.mesh.GetPoints().Modified()
        self.mesh.Modified()
        self.actor.SetVisibility(True)


__all__ = ["Character", "Markers", "Polyline", "Arrow"]
