"""The drawn character: the Body's mass ellipsoids as one merged, posable mesh.

Each body piece (``Body.joint/prox/dist/radius``) is drawn as the solid
ellipsoid the physics weighs: semi-axes ``(max(|dist − prox|/2, 2 cm), radius,
radius)``, centred at the bone midpoint, long axis along the bone, rigid in the
frame of the piece's joint.  The template points and normals of every piece
are computed once in joint-local coordinates; posing a frame is one vectorised
transform ``world = R_joint @ local + P_joint`` written in place into the VTK
point array (no new mesh, no new actor).

Also here: sampling a clip at display times (:func:`resample`), and the world
points of the body over frames (:func:`body_points`, used to fit cameras).
"""
from __future__ import annotations

import numpy as np

from stimuli.body import Body
from stimuli.motion.clip import Clip


def unit_sphere(n_around: int = 20, n_along: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Points (V,3) of a unit UV sphere whose poles lie on ±x (the bone axis)
    and its triangles (T,3).  ``n_along`` ≥ 2 is the number of latitude bands."""
    n_around = max(int(n_around), 3)
    n_along = max(int(n_along), 2)
    phi = np.linspace(0.0, np.pi, n_along + 1)[1:-1]              # latitudes without poles
    th = np.linspace(0.0, 2 * np.pi, n_around, endpoint=False)
    ring = np.stack([np.cos(phi)[:, None].repeat(n_around, 1),
                     (np.sin(phi)[:, None] * np.cos(th)[None]),
                     (np.sin(phi)[:, None] * np.sin(th)[None])], axis=-1).reshape(-1, 3)
    pts = np.vstack([[1.0, 0.0, 0.0], ring, [-1.0, 0.0, 0.0]])
    V = pts.shape[0]
    tris = []
    a = np.arange(n_around)
    b = (a + 1) % n_around
    # cap at +x
    tris.append(np.stack([np.zeros(n_around, int), 1 + b, 1 + a], 1))
    for r in range(n_along - 2):
        o0, o1 = 1 + r * n_around, 1 + (r + 1) * n_around
        tris.append(np.stack([o0 + a, o0 + b, o1 + b], 1))
        tris.append(np.stack([o0 + a, o1 + b, o1 + a], 1))
    last = 1 + (n_along - 2) * n_around
    tris.append(np.stack([np.full(n_around, V - 1), last + a, last + b], 1))
    tris = np.vstack(tris)[:, ::-1]            # counter-clockwise seen from outside
    return pts, np.ascontiguousarray(tris)


def _perp_basis(axis: np.ndarray) -> np.ndarray:
    """(P,3,3) rotations whose first column is each unit ``axis`` (P,3)."""
    P = axis.shape[0]
    helper = np.zeros((P, 3))
    helper[np.arange(P), np.argmin(np.abs(axis), axis=1)] = 1.0
    e2 = np.cross(axis, helper)
    e2 /= np.linalg.norm(e2, axis=1, keepdims=True)
    e3 = np.cross(axis, e2)
    return np.stack([axis, e2, e3], axis=-1)


def piece_frames(body: Body) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre (P,3), rotation (P,3,3) and semi-axes (P,3) of every body piece's
    ellipsoid in its joint's local frame."""
    d = body.dist - body.prox
    L = np.linalg.norm(d, axis=1)
    axis = np.where(L[:, None] > 1e-12, d / np.maximum(L, 1e-12)[:, None], [0.0, 1.0, 0.0])
    a = np.maximum(L / 2.0, 0.02)
    semi = np.stack([a, body.radius, body.radius], axis=1)
    return (body.prox + body.dist) / 2.0, _perp_basis(axis), semi


def piece_templates(body: Body, resolution=(20, 12)):
    """Joint-local template points (P,V,3), unit normals (P,V,3) and triangles
    (T,3) of one ellipsoid per piece (triangle indices within one piece)."""
    u, tris = unit_sphere(*resolution)
    centre, Q, semi = piece_frames(body)
    pts = np.einsum("pab,pb,vb->pva", Q, semi, u) + centre[:, None]
    nrm = np.einsum("pab,pb,vb->pva", Q, 1.0 / semi, u)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    return pts, nrm, tris


def resample(clip: Clip, fps: float, start: float = 0.0, stop: float | None = None) -> Clip:
    """The clip sampled at display times ``start, start + 1/fps, …, ≤ stop``
    (seconds; default the whole clip): rotations slerped, root and joint
    translations linear (no uneven frame dropping).  The result has ``fps``
    frames per second and ``meta["source_frames"]`` (fractional source frames).

    Example
    -------
    >>> v = resample(clip, 60.0)                      # doctest: +SKIP
    >>> v.fps, v.duration <= clip.duration            # doctest: +SKIP
    (60.0, True)
    """
    from stimuli.edit.timing import sample
    fps = float(fps)
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"resample: fps must be a positive number, got {fps!r}")
    stop = clip.duration if stop is None else min(float(stop), clip.duration)
    n = int(np.floor((stop - start) * fps + 1e-9)) + 1
    src = (start + np.arange(max(n, 1)) / fps) * clip.fps
    if clip.num_frames == 1:
        return clip.replace(fps=fps)
    if np.isclose(fps, clip.fps) and abs(start * clip.fps - round(start * clip.fps)) < 1e-9:
        i0 = int(round(start * clip.fps))
        out = clip.slice(i0, i0 + n).with_fps(fps)
        out.meta["source_frames"] = np.arange(i0, i0 + out.num_frames, dtype=float)
        return out
    return sample(clip, src).with_fps(fps)


def poses_at(clip: Clip, times) -> Clip:
    """A clip whose frames are ``clip`` at the given times (seconds, any order),
    interpolated as in :func:`resample`."""
    from stimuli.edit.timing import sample
    t = np.atleast_1d(np.asarray(times, dtype=float))
    return sample(clip, np.clip(t * clip.fps, 0, clip.num_frames - 1))


def body_points(clip: Clip, body: Body, resolution=(8, 5), frames=slice(None)) -> np.ndarray:
    """(F, P·V, 3) world points of the body's ellipsoids (a coarse template) in
    every frame: what a camera must keep in view."""
    pts, _, _ = piece_templates(body, resolution)
    R = clip.joint_rotations()[frames][:, body.joint]          # (F,P,3,3)
    P = clip.joint_positions()[frames][:, body.joint]          # (F,P,3)
    w = np.einsum("fpab,pvb->fpva", R, pts) + P[:, :, None]
    return w.reshape(w.shape[0], -1, 3)


class BodyMesh:
    """One merged :class:`pyvista.PolyData` for a whole body, posed in place.

    ``inflate`` (metres) pushes the surface out along its normals, so a second
    character drawn over an identical pose covers it cleanly (no z-fighting).

    Example
    -------
    >>> bm = BodyMesh(body)                                             # doctest: +SKIP
    >>> bm.pose(clip.joint_rotations()[0], clip.joint_positions()[0])   # doctest: +SKIP
    >>> bm.mesh.n_points == body.num_pieces * bm.points_per_piece       # doctest: +SKIP
    True
    """

    def __init__(self, body: Body, resolution=(20, 12), inflate: float = 0.0):
        from ._pv import pv
        self._pv = pv
        self.resolution = tuple(resolution)
        self.inflate = float(inflate)
        self.mesh = pv.PolyData()
        self.set_body(body)

    def set_body(self, body: Body) -> None:
        """Switch to another body (another skeleton or masses).  The PolyData
        object stays the same (actors keep drawing it); its arrays are replaced
        only when the number of pieces changes."""
        pv = self._pv
        pts, nrm, tris = piece_templates(body, self.resolution)
        if self.inflate:
            pts = pts + self.inflate * nrm        # a shell just outside (drawn over a twin)
        self.body = body
        self.joint = np.asarray(body.joint)
        self._local_pts = pts
        self._local_nrm = nrm
        P, V, _ = pts.shape
        self.points_per_piece = V
        if self.mesh.n_points != P * V:
            faces = (tris[None] + (np.arange(P) * V)[:, None, None]).reshape(-1, 3)
            cells = np.hstack([np.full((faces.shape[0], 1), 3), faces]).ravel()
            new = pv.PolyData(pts.reshape(-1, 3).copy(), cells)
            new.point_data["Normals"] = nrm.reshape(-1, 3).copy()
            new.point_data.active_normals_name = "Normals"
            self.mesh.copy_from(new, deep=True)
            self.mesh.point_data.active_normals_name = "Normals"
        self._pts = np.asarray(self.mesh.points)                  # views of the VTK arrays
        self._nrm = np.asarray(self.mesh.point_data["Normals"])
        if self._pts.dtype != np.float64 or not self._pts.flags.writeable:
            raise RuntimeError("BodyMesh: VTK point array is not a writable float64 view")

    def pose(self, R: np.ndarray, P: np.ndarray) -> None:
        """Pose from world joint rotations ``R`` (J,3,3) and positions ``P`` (J,3)
        of one frame (in place)."""
        Rp = R[self.joint]
        n = self._local_pts.shape[1]
        out = self._pts.reshape(-1, n, 3)
        np.einsum("pab,pvb->pva", Rp, self._local_pts, out=out)
        out += P[self.joint][:, None, :]
        np.einsum("pab,pvb->pva", Rp, self._local_nrm, out=self._nrm.reshape(-1, n, 3))
        self.mesh.GetPoints().Modified()
        self.mesh.GetPointData().GetNormals().Modified()
        self.mesh.Modified()

    def world_points(self) -> np.ndarray:
        return self._pts
