"""The drawn character: the Body's mass ellipsoids as one merged, posable mesh.

Each body segment is drawn as the solid ellipsoid of constant density the
physics weighs: long semi-axis half the segment's length, short semi-axes its
``radius``.  A segment on one bone (thigh, forearm...) is exactly its physics
piece, rigid in its joint's frame.  A segment the physics splits over several
bones (the trunk over the spine joints, the head over the neck joints, CMU's
hands and feet) has pieces as short as 5 cm with the segment's 17 cm radius —
flat discs, if drawn one by one — so it is drawn as one ellipsoid from the
segment's first to its last end, rigid in the frame of the joint at the middle
of the chain (the pieces' masses and volumes add up to that ellipsoid's).  The
template points and normals are computed once in joint-local coordinates;
posing a frame is one vectorised transform ``world = R_joint @ local + P_joint``
written in place into the VTK point array (no new mesh, no new actor).

Also here: the world points of the body over frames (:func:`body_points`, used to
fit cameras); sampling a clip at display times (:func:`resample`, :func:`poses_at`)
is a motion operation of :mod:`flipstudy.stimuli.edit.reposition`, re-exported here.
"""
from __future__ import annotations

import numpy as np

from flipstudy.stimuli.body import Body
from flipstudy.stimuli.edit.reposition import poses_at, resample  # noqa: F401  (motion operations)
from flipstudy.stimuli.motion.clip import Clip


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


def piece_frames(body: Body) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Joint (S,), centre (S,3), rotation (S,3,3) and semi-axes (S,3) of every drawn
    ellipsoid (one per segment) in its joint's local frame."""
    d = body.dist - body.prox
    L = np.linalg.norm(d, axis=1)
    if body.reference is not None:
        Pref, Rref = body.reference
    else:
        Pref = body.skeleton.rest_positions()[None]
        Rref = np.broadcast_to(np.eye(3), (1, body.skeleton.num_joints, 3, 3))
    joints, ends = [], []
    for s in range(len(body.segment_names)):
        k = np.flatnonzero(body.segment == s)           # pieces in chain order
        if k.size == 0:
            continue
        if k.size == 1:
            joints.append(body.joint[k[0]])
            ends.append((body.prox[k[0]], body.dist[k[0]]))
            continue
        cum = np.cumsum(L[k])
        a = body.joint[k[int(np.searchsorted(cum, cum[-1] / 2.0))]]   # joint mid-chain
        j0, j1 = body.joint[k[0]], body.joint[k[-1]]
        x0 = Pref[:, j0] + np.einsum("fab,b->fa", Rref[:, j0], body.prox[k[0]])
        x1 = Pref[:, j1] + np.einsum("fab,b->fa", Rref[:, j1], body.dist[k[-1]])
        to_a = lambda x: np.einsum("fba,fb->fa", Rref[:, a], x - Pref[:, a]).mean(axis=0)  # noqa: E731
        joints.append(a)
        ends.append((to_a(x0), to_a(x1)))
    joints = np.array(joints)
    prox = np.array([e[0] for e in ends])
    dist = np.array([e[1] for e in ends])
    radius = np.array([body.radius[body.segment == s].max()
                       for s in range(len(body.segment_names)) if np.any(body.segment == s)])
    dd = dist - prox
    n = np.linalg.norm(dd, axis=1)
    axis = np.where(n[:, None] > 1e-12, dd / np.maximum(n, 1e-12)[:, None], [0.0, 1.0, 0.0])
    semi = np.stack([np.maximum(n / 2.0, 0.02), radius, radius], axis=1)
    return joints, (prox + dist) / 2.0, _perp_basis(axis), semi


def piece_templates(body: Body, resolution=(20, 12)):
    """Joints (S,), joint-local template points (S,V,3), unit normals (S,V,3) and
    triangles (T,3) of one ellipsoid per drawn segment (indices within one)."""
    u, tris = unit_sphere(*resolution)
    joint, centre, Q, semi = piece_frames(body)
    pts = np.einsum("pab,pb,vb->pva", Q, semi, u) + centre[:, None]
    nrm = np.einsum("pab,pb,vb->pva", Q, 1.0 / semi, u)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    return joint, pts, nrm, tris


def body_points(clip: Clip, body: Body, resolution=(8, 5), frames=slice(None)) -> np.ndarray:
    """(F, P·V, 3) world points of the body's ellipsoids (a coarse template) in
    every frame: what a camera must keep in view.

    Parameters
    ----------
    clip : Clip
    body : Body
    resolution : tuple of int
        Of the coarse ellipsoid template.
    frames : slice
        The frames to take.

    Returns
    -------
    ndarray, shape (F, P·V, 3)

    Examples
    --------
    >>> from flipstudy import Body, builtin
    >>> from flipstudy.render import body_points
    >>> clip = builtin("jump")
    >>> pts = body_points(clip, Body.from_clip(clip), frames=slice(0, 2))
    >>> pts.shape[0], pts.shape[2]
    (2, 3)
    """
    joint, pts, _, _ = piece_templates(body, resolution)
    R = clip.joint_rotations()[frames][:, joint]               # (F,P,3,3)
    P = clip.joint_positions()[frames][:, joint]               # (F,P,3)
    w = np.einsum("fpab,pvb->fpva", R, pts) + P[:, :, None]
    return w.reshape(w.shape[0], -1, 3)


class BodyMesh:
    """One merged :class:`pyvista.PolyData` for a whole body, posed in place.

    ``inflate`` (metres) pushes the surface out along its normals, so a second
    character drawn over an identical pose covers it cleanly (no z-fighting).

    Parameters
    ----------
    body : Body
        The segment model to draw.
    resolution : tuple of int
        Ellipsoid resolution (around, along).
    inflate : float
        Metres added to every semi-axis.

    Examples
    --------
    >>> from flipstudy import Body, builtin
    >>> clip = builtin("backflip")
    >>> bm = BodyMesh(Body.from_clip(clip))
    >>> bm.pose(clip.joint_rotations()[0], clip.joint_positions()[0])
    >>> bm.mesh.n_points == len(bm.joint) * bm.points_per_piece
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
        joint, pts, nrm, tris = piece_templates(body, self.resolution)
        if self.inflate:
            pts = pts + self.inflate * nrm        # a shell just outside (drawn over a twin)
        self.body = body
        self.joint = np.asarray(joint)
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
        Rt = R[self.joint].transpose(0, 2, 1)     # local row vectors times R^T
        n = self._local_pts.shape[1]
        out = self._pts.reshape(-1, n, 3)
        np.matmul(self._local_pts, Rt, out=out)    # 10x faster than einsum here
        out += P[self.joint][:, None, :]
        np.matmul(self._local_nrm, Rt, out=self._nrm.reshape(-1, n, 3))
        self.mesh.GetPoints().Modified()
        self.mesh.GetPointData().GetNormals().Modified()
        self.mesh.Modified()

    def world_points(self) -> np.ndarray:
        return self._pts
