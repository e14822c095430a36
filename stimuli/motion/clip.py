"""A motion clip: a skeleton, a frame rate, root translation and local joint rotations.

Conventions
-----------
* frames are the leading axis of every array;
* ``root_pos`` (F,3) is the world position of the root joint in metres (the BVH
  reader has already resolved how the file's root OFFSET and position channels
  combine);
* ``rotations`` (F,J,4) are the local joint rotations as unit quaternions in
  scipy's scalar-last ``(x, y, z, w)`` order, so ``Rotation.from_quat`` reads them;
* ``joint_pos`` (F,J,3), optional, is the animated local translation of joints
  that carry position channels (replacing their OFFSET); ``None`` when only the
  root moves;
* world frame: metres, seconds, Y up, right-handed.

A clip is immutable in spirit: operations return new clips.  Derived arrays
(forward kinematics) are computed once and cached.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from .skeleton import Skeleton
from . import quat


class Clip:
    """Motion of a skeleton over ``F`` frames at ``fps`` frames per second.

    Immutable in spirit: editing operations return new clips.  Units are metres,
    seconds and radians, Y up.

    Parameters
    ----------
    skeleton : Skeleton
        The joint hierarchy (``J`` joints).
    fps : float
        Frames per second (positive).
    root_pos : array_like, shape (F, 3)
        Root translation per frame, metres.
    rotations : array_like, shape (F, J, 4)
        Local joint rotations as unit quaternions (x, y, z, w; normalised on
        construction).
    joint_pos : array_like, shape (F, J, 3), optional
        Per-frame local joint positions, for formats that animate them.
    meta : dict, optional
        Free-form facts about the clip (its name, source, warnings).

    Raises
    ------
    ValueError
        For arrays of the wrong shape, a non-finite value, a zero quaternion or
        a frame rate that is not positive.

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> clip = builtin("backflip")
    >>> P = clip.joint_positions()      # (F, J, 3) metres
    >>> P.shape[0] == clip.num_frames
    True
    """

    def __init__(self, skeleton: Skeleton, fps: float, root_pos, rotations,
                 joint_pos=None, meta: dict[str, Any] | None = None):
        root_pos = np.asarray(root_pos, dtype=np.float64)
        rotations = np.asarray(rotations, dtype=np.float64)
        F = root_pos.shape[0]
        J = skeleton.num_joints
        if root_pos.shape != (F, 3):
            raise ValueError(f"Clip: root_pos must be (F,3), got {root_pos.shape}")
        if rotations.shape != (F, J, 4):
            raise ValueError(f"Clip: rotations must be (F={F}, J={J}, 4), got {rotations.shape}")
        if not (np.isfinite(fps) and fps > 0):
            raise ValueError(f"Clip: fps must be a positive number, got {fps!r}")
        if not np.all(np.isfinite(root_pos)) or not np.all(np.isfinite(rotations)):
            raise ValueError("Clip: root_pos and rotations must be finite")
        norms = quat.norm(rotations)             # = np.linalg.norm(axis=-1), faster
        if np.any(norms < 1e-9):
            raise ValueError("Clip: zero quaternion in rotations")
        rotations = rotations / norms
        if joint_pos is not None:
            joint_pos = np.asarray(joint_pos, dtype=np.float64)
            if joint_pos.shape != (F, J, 3):
                raise ValueError(f"Clip: joint_pos must be (F,J,3), got {joint_pos.shape}")
        self.skeleton = skeleton
        self.fps = float(fps)
        self.root_pos = root_pos
        self.rotations = rotations
        self.joint_pos = joint_pos
        self.meta = dict(meta or {})
        for a in (self.root_pos, self.rotations, self.joint_pos):
            if a is not None:
                a.setflags(write=False)
        self._cache: dict[str, Any] = {}

    # ------------------------------------------------------------------ basics
    @property
    def num_frames(self) -> int:
        return self.root_pos.shape[0]

    @property
    def dt(self) -> float:
        return 1.0 / self.fps

    @property
    def duration(self) -> float:
        return (self.num_frames - 1) / self.fps

    @property
    def times(self) -> np.ndarray:
        return np.arange(self.num_frames) / self.fps

    def __len__(self) -> int:
        return self.num_frames

    def __repr__(self) -> str:
        name = self.meta.get("name", "")
        return (f"Clip({name!r}, {self.num_frames} frames @ {self.fps:g} fps, "
                f"{self.skeleton.num_joints} joints)")

    def replace(self, **kw) -> "Clip":
        """A new clip with some fields replaced (skeleton, fps, root_pos, rotations,
        joint_pos, meta)."""
        args = dict(skeleton=self.skeleton, fps=self.fps, root_pos=self.root_pos,
                    rotations=self.rotations, joint_pos=self.joint_pos, meta=self.meta)
        args.update(kw)
        return Clip(**args)

    def slice(self, start: int | None = None, stop: int | None = None) -> "Clip":
        """Frames ``start:stop`` as a new clip."""
        s = slice(start, stop)
        jp = None if self.joint_pos is None else self.joint_pos[s]
        return self.replace(root_pos=self.root_pos[s], rotations=self.rotations[s], joint_pos=jp)

    def with_fps(self, fps: float) -> "Clip":
        """Same frames, another frame time (fixing a wrong header, not resampling)."""
        return self.replace(fps=fps)

    def scaled(self, s: float) -> "Clip":
        """All lengths multiplied by ``s`` (unit conversion)."""
        jp = None if self.joint_pos is None else self.joint_pos * s
        return self.replace(skeleton=self.skeleton.scaled(s), root_pos=self.root_pos * s,
                            joint_pos=jp)

    def local_rotations(self) -> Rotation:
        """Local joint rotations as a scipy ``Rotation`` of shape (F, J)."""
        return Rotation.from_quat(self.rotations)

    # ------------------------------------------------------- forward kinematics
    def _fk(self):
        """World rotations (F,J,3,3) and positions (F,J,3), one tree level at a time.

        The products run on component-major copies, ``R[a, b]`` of shape (J, F) for
        each of the nine matrix entries, so every multiply-add is one contiguous numpy
        operation over the frames of a whole level (a stack of (3,3) ``matmul``/
        ``einsum`` calls costs several times more); the results are transposed back
        once.  ``tests/stimuli/test_fast_paths.py`` checks them against the plain stacked
        products on the shared files."""
        if "fk" in self._cache:
            return self._cache["fk"]
        sk = self.skeleton
        F, J = self.num_frames, sk.num_joints
        # the local matrices straight into that layout: Rotation.from_quat(q).as_matrix()'s
        # arithmetic (normalise, then scipy's expressions), the same bits, no transpose
        qc = quat.normalized(self.rotations).transpose(2, 1, 0).copy()       # (4,J,F)
        L = np.empty((3, 3, J, F))
        for a, row in enumerate(quat.matrix_entries(*qc)):
            for b, m in enumerate(row):
                L[a, b] = m
        del qc         # (arrays are freed as soon as they are done with: less memory to map)
        if self.joint_pos is not None:
            trans = np.where(sk.has_position[None, :, None], self.joint_pos, sk.offsets[None])
            T = trans.transpose(2, 1, 0).copy()                               # (3,J,F)
        else:
            T = sk.offsets.T[:, :, None]                                      # (3,J,1)
        R = np.empty((3, 3, J, F))
        P = np.empty((3, J, F))
        R[:, :, 0] = L[:, :, 0]
        P[:, 0] = self.root_pos.T
        for idx in sk.levels()[1:]:
            par = sk.parents[idx]
            pR = R[:, :, par]                                                 # (3,3,n,F)
            Li = L[:, :, idx]
            # world = parent @ local: sum over b of pR[a, b] * Li[b, c]
            R[:, :, idx] = (pR[:, 0, None] * Li[None, 0] + pR[:, 1, None] * Li[None, 1]
                            + pR[:, 2, None] * Li[None, 2])
            t = T[:, idx]
            P[:, idx] = P[:, par] + pR[:, 0] * t[0] + pR[:, 1] * t[1] + pR[:, 2] * t[2]
        del L, T
        world_R = np.ascontiguousarray(R.transpose(3, 2, 0, 1))
        del R
        world_P = np.ascontiguousarray(P.transpose(2, 1, 0))
        world_R.setflags(write=False)
        world_P.setflags(write=False)
        self._cache["fk"] = (world_R, world_P)
        return world_R, world_P

    def joint_positions(self) -> np.ndarray:
        """(F,J,3) world joint positions in metres."""
        return self._fk()[1]

    def joint_rotations(self) -> np.ndarray:
        """(F,J,3,3) world rotation matrices of the joint frames."""
        return self._fk()[0]

    def end_site_positions(self) -> np.ndarray:
        """(F,E,3) world positions of the end sites, in skeleton order."""
        R, P = self._fk()
        if not self.skeleton.end_sites:
            return np.zeros((self.num_frames, 0, 3))
        par = np.array([p for p, _ in self.skeleton.end_sites])
        off = np.stack([o for _, o in self.skeleton.end_sites])
        return P[:, par] + np.einsum("fjab,jb->fja", R[:, par], off)

    def points(self, joint: np.ndarray, local: np.ndarray) -> np.ndarray:
        """(F,K,3) world positions of K points fixed in the frames of ``joint`` (K,)
        at ``local`` (K,3) offsets."""
        R, P = self._fk()
        joint = np.asarray(joint)
        return P[:, joint] + np.einsum("fkab,kb->fka", R[:, joint], np.asarray(local, float))

    # -------------------------------------------------------------- velocities
    def derivative(self, x: np.ndarray) -> np.ndarray:
        """Time derivative of an array with frames first (central differences,
        one-sided at the ends), consistent with ``fps``."""
        return finite_difference(x, self.fps)

    def joint_velocities(self) -> np.ndarray:
        """(F,J,3) world linear velocity of every joint, propagated along the chain:
        v_j = v_parent + ω_parent × (p_j − p_parent) (+ the parent-frame rate of an
        animated translation).  With the root's position differenced and ω from the
        rotation group, a rigid motion (ballistic flight, constant spin) is
        differentiated exactly — differencing every point instead would shrink
        rotational velocities by sin(θ)/θ, θ = |ω|/fps."""
        if "vel" in self._cache:
            return self._cache["vel"]
        sk = self.skeleton
        R, P = self._fk()
        w = self.angular_velocities()
        V = np.empty_like(P)
        V[:, 0] = finite_difference(self.root_pos, self.fps)
        dtrans = None
        if self.joint_pos is not None:
            dtrans = finite_difference(self.joint_pos, self.fps)
        for idx in sk.levels()[1:]:
            par = sk.parents[idx]
            V[:, idx] = V[:, par] + np.cross(w[:, par], P[:, idx] - P[:, par])
            if dtrans is not None:
                moving = sk.has_position[idx]
                if moving.any():
                    ii, pp = idx[moving], par[moving]
                    V[:, ii] += np.einsum("fjab,fjb->fja", R[:, pp], dtrans[:, ii])
        self._cache["vel"] = V
        return V

    def point_velocities(self, joint: np.ndarray, local: np.ndarray) -> np.ndarray:
        """(F,K,3) world velocities of points fixed in joint frames (see
        :meth:`points`): v_joint + ω_joint × (x − p_joint)."""
        joint = np.asarray(joint)
        x = self.points(joint, local)
        P = self.joint_positions()[:, joint]
        return self.joint_velocities()[:, joint] + np.cross(self.angular_velocities()[:, joint], x - P)

    def angular_velocities(self) -> np.ndarray:
        """(F,J,3) world-frame angular velocity of every joint frame, rad/s."""
        if "omega" not in self._cache:
            self._cache["omega"] = angular_velocity(self.joint_rotations(), self.fps)
        return self._cache["omega"]


#: What a built-in knows exactly of its own motion (:mod:`flipstudy.stimuli.synth`):
#: true of that clip only.  A clip made from it by an edit or an injected error
#: keeps them under ``meta["source_facts"]`` (see :func:`derived_meta`), never
#: as its own: its flight is in the method's result and its analysis.
SOURCE_FACTS = ("takeoff", "landing", "touchdown", "flight_s", "L_flight", "v0",
                "rotation_deg", "flight_rotation_deg", "takeoff_pitch_rate",
                "landing_pitch_rate", "max_pitch_rate", "com_rise_m", "push_rise_m", "heel_off")


def derived_meta(meta: dict, edit: str) -> dict:
    """The provenance of a clip made from one with ``meta`` by ``edit``: the
    source's provenance, the edit, and the source's own exact facts
    (:data:`SOURCE_FACTS`) moved under ``"source_facts"``.

    >>> m = derived_meta({"name": "backflip", "takeoff": 157, "g": 9.81}, "multiflip 2")
    >>> m == {"name": "backflip", "g": 9.81, "edit": "multiflip 2", "source_facts": {"takeoff": 157}}
    True
    >>> derived_meta(m, "mirrored")["source_facts"]        # an edit of an edit: the first source's
    {'takeoff': 157}
    """
    own = {k: v for k, v in meta.items() if k not in SOURCE_FACTS}
    facts = {k: meta[k] for k in SOURCE_FACTS if k in meta}
    if facts:
        own["source_facts"] = facts
    own["edit"] = edit
    return own


def finite_difference(x: np.ndarray, fps: float) -> np.ndarray:
    """d/dt along axis 0: central differences inside, one-sided second-order at the
    ends (exact for quadratics), so a ballistic parabola differentiates exactly.

    Parameters
    ----------
    x : ndarray
        Frames along axis 0.
    fps : float
        Frames per second.

    Returns
    -------
    ndarray
        Same shape as ``x``.

    Examples
    --------
    >>> t = np.arange(5) / 10.0
    >>> finite_difference(t ** 2, 10.0)                     # d(t²)/dt = 2t, ends too
    array([0. , 0.2, 0.4, 0.6, 0.8])"""
    x = np.asarray(x, dtype=np.float64)
    if x.shape[0] < 3:
        if x.shape[0] < 2:
            return np.zeros_like(x)
        return np.gradient(x, 1.0 / fps, axis=0)
    return np.gradient(x, 1.0 / fps, axis=0, edge_order=2)


def rotation_log(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (…,3) of rotation matrices (…,3,3): the axis times the angle.

    Closed form, θ = atan2(|s|, (tr R − 1)/2) with s the skew part, accurate for the
    small and moderate turns between nearby frames; turns beyond 2.5 rad (where the
    skew part vanishes towards π) go through scipy's ``Rotation``."""
    s = 0.5 * np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                        R[..., 1, 0] - R[..., 0, 1]], -1)
    sn = np.linalg.norm(s, axis=-1)
    c = 0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0)
    th = np.arctan2(sn, c)
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(sn > 1e-12, th / sn, 1.0 + th * th / 6.0)
    out = s * k[..., None]
    big = th > 2.5
    if np.any(big):
        out[big] = Rotation.from_matrix(R[big]).as_rotvec()
    return out


def angular_velocity(R: np.ndarray, fps: float) -> np.ndarray:
    """World-frame angular velocity from world rotation matrices R (F,...,3,3).

    Central difference on the rotation group: ``ω(t) = log(R(t+1) R(t-1)ᵀ) / 2Δt``,
    one-sided (second order) at the ends.  Exact for a constant angular velocity.

    Parameters
    ----------
    R : ndarray, shape (F, ..., 3, 3)
        World rotation matrices, frames first.
    fps : float
        Frames per second.

    Returns
    -------
    ndarray, shape (F, ..., 3)
        Radians per second, world axes.

    Examples
    --------
    >>> from scipy.spatial.transform import Rotation
    >>> R = Rotation.from_rotvec(np.outer(np.arange(5) / 10.0, [0, 2.0, 0])).as_matrix()
    >>> angular_velocity(R, 10.0)[:, 1].round(6)          # 2 rad/s about Y at 10 fps
    array([2., 2., 2., 2., 2.])
    """
    R = np.asarray(R, dtype=np.float64)
    F = R.shape[0]
    out = np.zeros(R.shape[:-1])
    if F < 2:
        return out

    def log(a, b):                      # log(R_a R_bᵀ) for frame index arrays/slices
        return rotation_log(R[a] @ np.swapaxes(R[b], -1, -2))
    if F >= 3:
        out[1:-1] = log(slice(2, None), slice(None, -2)) * (fps / 2.0)
        # one-sided, second order at the ends (like np.gradient's edge_order=2):
        # ω₀ ≈ [4 log(R₁R₀ᵀ) − log(R₂R₀ᵀ)] / 2Δt, still exact for a constant spin
        out[0] = (2.0 * log(1, 0) - 0.5 * log(2, 0)) * fps
        out[-1] = (2.0 * log(-1, -2) - 0.5 * log(-1, -3)) * fps
        return out
    out[0] = log(1, 0) * fps
    out[-1] = out[0]
    return out
