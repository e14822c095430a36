"""One offscreen plotter, reused: ground, lights, posable characters, gizmos.

A :class:`Scene` owns a single :class:`pyvista.Plotter` (VTK through EGL).
Everything in it is created once and then updated in place: characters are
:class:`~flipstudy.render.geometry.BodyMesh` objects whose points are rewritten each
frame, extra characters (ghosts) come from a pool and are hidden when unused,
markers and gizmos have fixed topology (the actors are in
:mod:`flipstudy.render.actors`).  Frames are read back into a reused buffer.
Close the scene (or use it as a context manager) when done; :func:`scene_for`
sets one up for a :class:`~flipstudy.render.staging.Stage`.

Rendering notes (VTK 9.7, Mesa llvmpipe through EGL): depth peeling is on for
correct transparency; MSAA breaks depth peeling there (translucent surfaces
vanish), so the anti-aliasing (``Style.anti_aliasing``) is FXAA: by default
run on the read-back frame (:mod:`flipstudy.render.antialias`, the same
algorithm as VTK's filter at a fraction of its cost on llvmpipe), or VTK's FXAA
filter (``"vtk-fxaa"``: the renderer's ``UseFXAA``, which PyVista refuses on
EGL and replaces by SSAA), or VTK's SSAA pass.
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass

import numpy as np

from flipstudy.stimuli.body import Body

from flipstudy.errors import FlipstudyValueError

from ._pv import pv
from .actors import Arrow, Character, Markers, Polyline
from .camera import Camera
from .style import DEFAULT_STYLE, Style, rgb

#: colour of the boxes of :meth:`Scene.set_boxes` (light wood)
BOX_COLOR = "#cdb793"


@dataclass
class Plate:
    """The still part of a frame (:meth:`Scene.plate`): ``rgb`` (H, W, 3) uint8
    and ``depth`` (H, W) float32, rows top-down, the camera, ground and size
    they hold for, and (made on first use) the FXAA of ``rgb``."""
    key: tuple
    rgb: np.ndarray
    depth: np.ndarray
    smooth: np.ndarray | None = None


class Scene:
    """An offscreen plotter with a ground, lights and posable characters.

    Parameters
    ----------
    body : Body, optional
        The character's segment model.
    style : Style, optional
        Default :data:`~flipstudy.render.style.DEFAULT_STYLE`.
    size : tuple of int
        (width, height) in pixels.
    camera : Camera, optional
    ground_bounds : tuple of float, optional
        (x0, x1, z0, z1) metres; None: no ground until set.

    Examples
    --------
    >>> from flipstudy import Body, builtin
    >>> from flipstudy.render.staging import stage
    >>> clip = builtin("backflip")
    >>> st = stage([clip], size=(320, 240))
    >>> with Scene(Body.from_clip(clip), size=(320, 240), camera=st.camera) as sc:
    ...     ch = sc.character(0)
    ...     ch.pose(clip.joint_rotations()[0], clip.joint_positions()[0])
    ...     img = sc.grab()
    >>> img.shape, img.dtype.name
    ((240, 320, 3), 'uint8')
    """

    def __init__(self, body: Body | None = None, style: Style | None = None, size=(640, 480),
                 camera: Camera | None = None, ground_bounds=None):
        self.style = style or DEFAULT_STYLE
        self.size = (int(size[0]), int(size[1]))
        self.plotter = pv.Plotter(off_screen=True, window_size=list(self.size),
                                  lighting="none" if self.style.lighting == "key-fill" else "light kit")
        pl = self.plotter
        pl.render_window.SetMultiSamples(0)
        pl.set_background(self.style.background)
        if self.style.lighting == "key-fill":
            key = pv.Light(position=(-0.6, 1.2, 1.0), light_type="camera light", intensity=0.85)
            fill = pv.Light(position=(0.8, 0.3, 0.6), light_type="camera light", intensity=0.35)
            pl.add_light(key)
            pl.add_light(fill)
        pl.enable_depth_peeling(number_of_peels=self.style.depth_peels, occlusion_ratio=0.0)
        if self.style.anti_aliasing == "vtk-fxaa":
            pl.renderer.SetUseFXAA(True)          # works offscreen on EGL/llvmpipe, with depth peeling
        elif self.style.anti_aliasing == "ssaa":
            import warnings
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                pl.enable_anti_aliasing("ssaa")
        self.body = body
        self._chars: dict = {}
        self._markers: dict = {}
        self._lines: dict = {}
        self._arrows: dict = {}
        self._texts: dict = {}
        self._legend = None
        self._overlay = None
        self.ground_actor = None
        self._ground_key = None
        self.boxes_actor = None
        self._boxes_key = ()
        self.camera: Camera | None = None
        if camera is not None:
            self.set_camera(camera)
        if ground_bounds is not None and self.style.ground:
            self.set_ground(ground_bounds)
        self._readback: dict = {}
        self._closed = False

    # ---------------------------------------------------------------- setup
    def set_camera(self, camera: Camera) -> None:
        self.camera = camera
        pl = self.plotter
        pl.camera_position = [camera.position, camera.focal_point, camera.view_up]
        pl.camera.view_angle = camera.view_angle
        self._clip_range()

    def _clip_range(self) -> None:
        # fixed, generous clipping range shared by both layers (gizmos may stick
        # out of the main layer's bounds); depth precision stays far below 1 mm
        if self.camera is not None:
            far = 10.0 * self.camera.distance + 100.0
            self.plotter.renderer.GetActiveCamera().SetClippingRange(0.1, far)

    def set_size(self, size) -> None:
        size = (int(size[0]), int(size[1]))
        if size != self.size:
            self.size = size
            self.plotter.window_size = list(size)

    def set_ground(self, bounds) -> None:
        """A checkerboard plane at ``style.ground_height`` covering ``bounds``
        (x0, x1, z0, z1), tiles of ``style.ground_tile`` metres aligned to the
        origin (the take-off spot is a tile corner)."""
        st = self.style
        if not st.ground:
            return
        t = st.ground_tile
        x0, x1 = np.floor(bounds[0] / t) * t, np.ceil(bounds[1] / t) * t
        z0, z1 = np.floor(bounds[2] / t) * t, np.ceil(bounds[3] / t) * t
        key = (x0, x1, z0, z1)
        if key == self._ground_key:
            return
        self._ground_key = key
        nx, nz = int(round((x1 - x0) / t)), int(round((z1 - z0) / t))
        xs, zs = np.linspace(x0, x1, nx + 1), np.linspace(z0, z1, nz + 1)
        grid = pv.RectilinearGrid(xs, np.array([st.ground_height]), zs).extract_surface(
            algorithm=None).triangulate()
        cx = ((grid.cell_centers().points[:, 0] - x0) // t).astype(int)
        cz = ((grid.cell_centers().points[:, 2] - z0) // t).astype(int)
        grid.cell_data["tile"] = ((cx + cz) % 2).astype(np.uint8)
        colors = np.array([rgb(c) for c in st.ground_colors])
        grid.cell_data["rgb"] = (colors[grid.cell_data["tile"]] * 255).astype(np.uint8)
        if self.ground_actor is not None:
            self.plotter.remove_actor(self.ground_actor)
        self.ground_actor = self.plotter.add_mesh(grid, scalars="rgb", rgb=True, name="ground",
                                                  reset_camera=False, ambient=0.5, diffuse=0.5,
                                                  specular=0.0, show_scalar_bar=False)

    def set_boxes(self, boxes=(), color=BOX_COLOR) -> None:
        """Axis-aligned boxes standing in the scene (``[(lo, hi), ...]``, corners
        (x, y, z) in metres), drawn with the ground and hidden with it; ``()``
        removes them.  Used for the box and jump-over scenes of the jump
        controller."""
        key = tuple(tuple(float(v) for v in np.ravel(b)) for b in boxes)
        if key == self._boxes_key:
            return
        self._boxes_key = key
        if self.boxes_actor is not None:
            self.plotter.remove_actor(self.boxes_actor)
            self.boxes_actor = None
        if not key:
            return
        mesh = None
        for b in key:
            x0, y0, z0, x1, y1, z1 = b
            m = pv.Box(bounds=(x0, x1, y0, y1, z0, z1))
            mesh = m if mesh is None else mesh.merge(m)
        self.boxes_actor = self.plotter.add_mesh(mesh, color=color, name="boxes", reset_camera=False,
                                                 ambient=0.35, diffuse=0.7, specular=0.05,
                                                 show_edges=True, edge_color="#7a6a52", line_width=1.0)
        if self.ground_actor is not None:
            self.boxes_actor.SetVisibility(self.ground_actor.GetVisibility())

    def set_body(self, body: Body) -> None:
        """Switch every character to another body (another skeleton)."""
        self.body = body
        for ch in self._chars.values():
            ch.set_body(body)

    # ------------------------------------------------------------- contents
    def character(self, key=0, body: Body | None = None, inflate: float = 0.0) -> Character:
        """The character in slot ``key`` (created on first use, then reused),
        made visible.  ``inflate``: see :class:`~flipstudy.render.geometry.BodyMesh`."""
        body = body or self.body
        if body is None:
            raise ValueError("Scene: no body; pass body= to Scene() or character()")
        ch = self._chars.get(key)
        if ch is None:
            ch = Character(self.plotter, body, self.style, f"character-{key}", inflate)
            self._chars[key] = ch
        else:
            ch.set_body(body)
        ch.visible = True
        return ch

    def _top(self):
        """The overlay renderer (layer 1, same camera, own depth buffer): what is
        added there is drawn over everything, like Unity's gizmos."""
        if self._overlay is None:
            from vtkmodules.vtkRenderingCore import vtkRenderer
            r = vtkRenderer()
            r.SetLayer(1)
            r.InteractiveOff()
            r.SetActiveCamera(self.plotter.renderer.GetActiveCamera())
            rw = self.plotter.render_window
            rw.SetNumberOfLayers(2)
            rw.AddRenderer(r)
            self._overlay = r
        return self._overlay

    def _place(self, obj, on_top: bool, old=None) -> None:
        if old is not None:
            ren = self._top() if getattr(old, "on_top", False) else self.plotter.renderer
            ren.RemoveActor(old.actor)
        obj.on_top = on_top
        if on_top:
            self.plotter.renderer.RemoveActor(obj.actor)
            self._top().AddActor(obj.actor)

    def markers(self, key, capacity: int, color, radius: float | None = None,
                on_top: bool = False) -> Markers:
        """Up to ``capacity`` marker spheres in slot ``key`` (reused);
        ``on_top`` draws them over everything (gizmos)."""
        m = self._markers.get(key)
        if m is None or m.capacity < capacity:
            new = Markers(self.plotter, f"markers-{key}", max(capacity, 8),
                          radius or self.style.marker_size, color, self.style)
            self._place(new, on_top, m)
            m = self._markers[key] = new
        m.actor.prop.color = color
        return m

    def polyline(self, key, capacity: int, color, width: float = 2.0, closed=False,
                 opacity: float = 1.0, on_top: bool = False) -> Polyline:
        """A polyline of up to ``capacity`` points in slot ``key`` (reused)."""
        ln = self._lines.get(key)
        if ln is None or ln.capacity < capacity:
            new = Polyline(self.plotter, f"line-{key}", max(capacity, 2), color, width, closed, opacity)
            self._place(new, on_top, ln)
            ln = self._lines[key] = new
        ln.actor.prop.color = color
        ln.actor.prop.line_width = width
        ln.actor.prop.opacity = opacity
        return ln

    def arrow(self, key, color, on_top: bool = False) -> Arrow:
        """An arrow in slot ``key`` (reused)."""
        a = self._arrows.get(key)
        if a is None:
            a = Arrow(self.plotter, f"arrow-{key}", color)
            self._place(a, on_top)
            self._arrows[key] = a
        a.actor.prop.color = color
        return a

    def text(self, key, text: str, position, font_size: int, color=None, background=None,
             background_opacity: float = 0.85):
        """A 2D label (VTK's built-in font) in slot ``key``: lower-left corner
        at pixel ``position`` (x, y from the bottom left), ``font_size`` in
        pixels, optional box ``background``."""
        from vtkmodules.vtkRenderingCore import vtkTextActor
        t = self._texts.get(key)
        if t is None:
            t = vtkTextActor()
            self.plotter.renderer.AddViewProp(t)
            self._texts[key] = t
        t.SetInput(str(text))
        t.SetDisplayPosition(int(position[0]), int(position[1]))
        tp = t.GetTextProperty()
        tp.SetFontFamilyToArial()
        tp.SetFontSize(int(font_size))
        tp.SetColor(*rgb(color or self.style.label_color))
        tp.SetJustificationToLeft()
        tp.SetVerticalJustificationToBottom()
        if background is not None:
            tp.SetBackgroundColor(*rgb(background))
            tp.SetBackgroundOpacity(float(background_opacity))
        else:
            tp.SetBackgroundOpacity(0.0)
        t.SetVisibility(True)
        return t

    def legend(self, entries, font_size: int):
        """A legend drawn with VTK's built-in font (for systems without a font
        file for OpenImageIO): dark labels on light boxes, top left.  The
        colour discs are painted into the image afterwards: call the returned
        function on the grabbed image."""
        self.clear_legend()
        H = self.size[1]
        fs = int(round(font_size * 1.25))        # VTK's points look smaller than OIIO's pixels
        line = int(round(fs * 1.3))
        pad = max(4, fs // 3)
        r = max(3, int(round(fs * 0.36)))
        discs = []
        for i, (lab, col) in enumerate(entries):
            top = pad + i * line
            self.text(("legend", i), f" {lab} ", (pad + 2 * r + 2, H - top - line + 2), fs,
                      background="white")
            discs.append((pad + r, top + line // 2, col))
        self._legend = len(entries)

        def paint(img: np.ndarray) -> np.ndarray:
            yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]]
            for cx, cy, col in discs:
                ys = slice(max(0, cy - line // 2), cy + line // 2 + 1)
                xs = slice(max(0, cx - r - 2), cx + r + 3)
                img[ys, xs, :3] = np.rint(img[ys, xs, :3] * 0.15 + 255 * 0.85).astype(np.uint8)
                m = (xx - cx) ** 2 + (yy - cy) ** 2 <= r * r
                img[m, :3] = np.asarray(rgb(col)) * 255
            return img
        return paint

    def clear_legend(self) -> None:
        for k, t in self._texts.items():
            if isinstance(k, tuple) and k and k[0] == "legend":
                t.SetVisibility(False)
        self._legend = None

    def hide(self, key) -> None:
        """Hide the character in slot ``key`` (if there is one)."""
        ch = self._chars.get(key)
        if ch is not None:
            ch.visible = False

    def hide_all(self) -> None:
        """Hide every character, marker, line, arrow, text and the legend
        (ground stays)."""
        for d in (self._chars, self._markers, self._lines, self._arrows):
            for v in d.values():
                v.actor.SetVisibility(False) if hasattr(v, "actor") else None
        for t in self._texts.values():
            t.SetVisibility(False)
        self.clear_legend()

    def show_ground(self, visible: bool = True) -> None:
        """Show or hide the ground (and the boxes standing on it)."""
        if self.ground_actor is not None:
            self.ground_actor.SetVisibility(bool(visible))
        if self.boxes_actor is not None:
            self.boxes_actor.SetVisibility(bool(visible))

    # --------------------------------------------------------------- output
    def plate(self) -> "Plate | None":
        """What stays still while the characters move: the frame of the ground
        and background alone, with its depth, for :meth:`grab`'s ``plate``.
        ``None`` when the scene holds more than the ground and opaque
        characters (boxes, markers, lines, arrows, labels, an overlay layer, a
        translucent body): those frames are rendered whole."""
        from vtkmodules.vtkCommonCore import vtkFloatArray, vtkUnsignedCharArray
        if self.style.anti_aliasing not in ("fxaa", "none") or self.ground_actor is None \
                or not self.ground_actor.GetVisibility() or self.boxes_actor is not None or self._overlay is not None or self._legend:
            return None
        others = [v.actor for d in (self._markers, self._lines, self._arrows) for v in d.values()]
        if any(a.GetVisibility() for a in others) or any(t.GetVisibility() for t in self._texts.values()):
            return None
        shown = [c for c in self._chars.values() if c.visible]
        if any(c.actor.prop.opacity < 1.0 for c in shown):
            return None
        for c in shown:
            c.visible = False
        try:
            self._render_raw()
            rgb_, z = self._read_rgb_depth(vtkUnsignedCharArray(), vtkFloatArray())
        finally:
            for c in shown:
                c.visible = True
        return Plate(self._plate_key(), rgb_.copy(), z.copy())

    def _read_rgb_depth(self, rgb_buf, z_buf) -> tuple:
        """The rendered frame's colours (H, W, 3) and depth (H, W), read into the
        given VTK arrays and viewed as numpy, rows top-down."""
        from vtkmodules.util.numpy_support import vtk_to_numpy
        rw = self.plotter.render_window
        w, h = rw.GetSize()
        rw.GetPixelData(0, 0, w - 1, h - 1, 1, rgb_buf, 0)
        rw.GetZbufferData(0, 0, w - 1, h - 1, z_buf)
        return vtk_to_numpy(rgb_buf).reshape(h, w, 3)[::-1], vtk_to_numpy(z_buf).reshape(h, w)[::-1]

    def _plate_key(self) -> tuple:
        cam = self.plotter.renderer.GetActiveCamera()
        return (self.size, self._ground_key, cam.GetPosition(), cam.GetFocalPoint(),
                cam.GetViewUp(), cam.GetViewAngle())

    def _render_raw(self) -> None:
        """Render without VTK's anti-aliasing (the read-back frame's own FXAA
        runs after the plate is composited)."""
        self.plotter.renderer.SetUseFXAA(False)
        self._clip_range()
        self.plotter.render_window.Render()

    def _grab_on_plate(self, plate: "Plate", out: np.ndarray | None) -> np.ndarray:
        # the characters rendered alone, then put on the still ground where they
        # are nearer than it (less or equal: VTK's depth test, the ground drawn
        # first): the frame the whole scene renders to, without drawing the
        # ground on every frame (its lit, full-screen fill is half a frame's cost);
        # the FXAA of the plate is kept, and redone only around the characters
        from vtkmodules.vtkCommonCore import vtkFloatArray, vtkUnsignedCharArray
        from .antialias import fxaa, fxaa_update
        if plate.key != self._plate_key():
            raise ValueError("Scene.grab: the plate is of another camera, ground or size")
        ga = self.ground_actor
        ga.SetVisibility(False)
        try:
            self._render_raw()
        finally:
            ga.SetVisibility(True)
        h, w = plate.depth.shape
        bufs = self._readback.get("plate")
        if bufs is None or bufs[2].shape != (h, w, 3):
            bufs = self._readback["plate"] = (vtkUnsignedCharArray(), vtkFloatArray(),
                                              np.empty((h, w, 3), np.uint8))
        rgb_, z = self._read_rgb_depth(bufs[0], bufs[1])
        near = z <= plate.depth
        near &= z < 1.0                                     # drawn on (not the far plane)
        aa = self.style.anti_aliasing == "fxaa"
        if aa and plate.smooth is None:
            plate.smooth = fxaa(plate.rgb)
        if out is None:
            out = np.empty((h, w, 3), np.uint8)
        np.copyto(out, plate.smooth if aa else plate.rgb)
        rows, cols = np.flatnonzero(near.any(1)), np.flatnonzero(near.any(0))
        if not len(rows):
            return out
        box = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
        raw = bufs[2] if aa else out
        if aa:
            np.copyto(raw, plate.rgb)
        np.copyto(raw[box], rgb_[box], where=near[box][..., None])
        if aa:
            fxaa_update(out, raw, box)
        return out

    def grab(self, alpha: bool = False, out: np.ndarray | None = None,
             plate: "Plate | None" = None) -> np.ndarray:
        """Render and read the frame: (H, W, 3) uint8, or (H, W, 4) with
        ``alpha=True`` (transparent background: the alpha channel is the matte,
        colours premultiplied).  ``out`` receives the pixels when given.
        ``plate`` (from :meth:`plate`, same camera, ground and size): the
        characters are rendered alone and put on it, the same frame at a
        fraction of the cost."""
        from vtkmodules.util.numpy_support import vtk_to_numpy
        if plate is not None and not alpha:
            return self._grab_on_plate(plate, out)
        pl = self.plotter
        ren = pl.renderer
        if alpha:
            # black, fully transparent background: VTK then writes premultiplied
            # colour (what OIIO's over expects) and alpha is the matte
            bg = ren.GetBackground()
            ren.SetBackground(0.0, 0.0, 0.0)
            ren.SetBackgroundAlpha(0.0)
            pl.render_window.SetAlphaBitPlanes(1)
        # "fxaa": FXAA on the read-back frame (render.antialias), a fraction of the cost
        # of VTK's filter; frames read with alpha (premultiplied layers) keep VTK's
        fxaa = self.style.anti_aliasing == "fxaa" and not alpha
        ren.SetUseFXAA(self.style.anti_aliasing == "vtk-fxaa" or
                       (self.style.anti_aliasing == "fxaa" and alpha))
        self._clip_range()
        if self._overlay is not None:
            self._overlay.SetActiveCamera(ren.GetActiveCamera())
        rw = pl.render_window
        rw.Render()
        # read the front buffer straight into a reused array (what
        # vtkWindowToImageFilter does, without its image copy and pipeline)
        buf = self._readback.get(alpha)
        if buf is None:
            from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
            buf = self._readback[alpha] = vtkUnsignedCharArray()
        w, h = rw.GetSize()
        if alpha:
            rw.GetRGBACharPixelData(0, 0, w - 1, h - 1, 1, buf, 0)
        else:
            rw.GetPixelData(0, 0, w - 1, h - 1, 1, buf, 0)
        arr = vtk_to_numpy(buf).reshape(h, w, -1)
        if alpha:
            ren.SetBackground(*bg)
            ren.SetBackgroundAlpha(1.0)
        if out is None:
            out = arr[::-1].copy()
        else:
            np.copyto(out, arr[::-1])
        if fxaa:
            from .antialias import fxaa as fxaa_
            fxaa_(out, out)
        return out

    def close(self) -> None:
        """Release the plotter and its OpenGL context."""
        if self._closed:
            return
        self._closed = True
        self._readback.clear()
        self._overlay = None
        self._chars.clear()
        self._markers.clear()
        self._lines.clear()
        self._arrows.clear()
        self._texts.clear()
        try:
            self.plotter.close()
            self.plotter.deep_clean()
        except Exception:  # noqa: BLE001 — closing twice or after a failed init
            pass

    def __enter__(self) -> "Scene":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


@contextlib.contextmanager
def scene_for(stage, scene: Scene | None = None, size=None):
    """A scene set up for a :class:`~flipstudy.render.staging.Stage` (its first
    body, camera, ground and boxes) at ``size`` (default the stage's): ``scene``
    reused (resized, everything in it hidden before and after; its style must
    be the stage's), or a new one closed on exit."""
    size = stage.size if size is None else size
    if scene is None:
        sc = Scene(stage.bodies[0], stage.style, size, stage.camera, stage.ground_bounds)
        try:
            sc.set_boxes(stage.boxes)
            yield sc
        finally:
            sc.close()
        return
    if scene.style != stage.style:
        raise FlipstudyValueError("scene: its style is not the stage's (stage the clips with "
                                  "style=scene.style)")
    scene.set_size(size)
    scene.set_body(stage.bodies[0])
    scene.set_camera(stage.camera)
    scene.set_ground(stage.ground_bounds)
    scene.show_ground(True)
    scene.hide_all()
    scene.set_boxes(stage.boxes)
    try:
        yield scene
    finally:
        scene.hide_all()


__all__ = ["Scene", "Plate", "scene_for", "BOX_COLOR"]
