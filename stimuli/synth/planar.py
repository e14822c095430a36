"""Sagittal (planar) kinematics and mass properties of the synthetic humanoid.

Every scripted motion of :mod:`flipstudy.stimuli.synth` rotates joints about the lateral X
axis only, the same on the left and the right.  A pose is then a short vector of
*degrees of freedom* (:data:`DOFS`, radians, rotations about +X):

``pitch``     root (Hips) pitch; positive tips the trunk forward (head to +Z)
``hip``       thigh relative to the pelvis; negative = flexion (knee forward/up)
``knee``      shank relative to the thigh; positive = flexion
``ankle``     foot relative to the shank; positive = plantar flexion (toes down)
``toe``       toes relative to the foot; the toes stay flat on the floor while the
              heel rises when ``toe = -(pitch + hip + knee + ankle)``
``spine``     trunk flexion, split equally between Spine and Spine1
``neck``      split equally between Neck and Head; positive = chin to chest
``shoulder``  arm swing; negative = forward and up (-pi: arms overhead)
``elbow``     negative = flexion (forearm forward)

Because every rotation is about X and the body is left/right symmetric, angular
momentum is along X, whole-body inertia about X is invariant under the root
pitch, and joint angular velocities are sums of the DOF rates along the chain:
all of it is evaluated here in closed form (no finite differences).

The mass properties use the pieces of :class:`flipstudy.stimuli.body.Body` (the model the
analyser weighs), so ``com`` agrees with :func:`flipstudy.stimuli.physics.center_of_mass`.
"""

from __future__ import annotations

import numpy as np

from ..body import Body
from ..motion.skeleton import Skeleton

DOFS = ("pitch", "hip", "knee", "ankle", "toe", "spine", "neck", "shoulder", "elbow")
D = len(DOFS)
IX = {n: i for i, n in enumerate(DOFS)}

#: joint name (without side) → (DOF, share of the DOF's angle)
_JOINT_DOF = {
    "Hips": ("pitch", 1.0), "UpLeg": ("hip", 1.0), "Leg": ("knee", 1.0),
    "Foot": ("ankle", 1.0), "ToeBase": ("toe", 1.0),
    "Spine": ("spine", 0.5), "Spine1": ("spine", 0.5),
    "Neck": ("neck", 0.5), "Head": ("neck", 0.5),
    "Arm": ("shoulder", 1.0), "ForeArm": ("elbow", 1.0),
}


def rot_x(angle: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v`` (...,3) about +X by ``angle`` (...) radians."""
    c, s = np.cos(angle), np.sin(angle)
    out = np.empty(np.broadcast_shapes(np.shape(angle) + (3,), np.shape(v)))
    out[..., 0] = v[..., 0]
    out[..., 1] = c * v[..., 1] - s * v[..., 2]
    out[..., 2] = s * v[..., 1] + c * v[..., 2]
    return out


def cross_x(w: np.ndarray, r: np.ndarray) -> np.ndarray:
    """(w x̂) × r for scalar rates ``w`` (...) and vectors ``r`` (...,3)."""
    out = np.zeros(np.broadcast_shapes(np.shape(w) + (3,), np.shape(r)))
    out[..., 1] = -w * r[..., 2]
    out[..., 2] = w * r[..., 1]
    return out


class PlanarModel:
    """DOF vector ↔ joint angles, forward kinematics and mass properties for the
    sagittal motions of a skeleton made by :func:`flipstudy.stimuli.synth.make_skeleton`."""

    def __init__(self, skeleton: Skeleton, body: Body):
        self.sk = skeleton
        self.body = body
        J = skeleton.num_joints
        A = np.zeros((J, D))
        for j, name in enumerate(skeleton.joint_names):
            base = name[4:] if name.startswith("Left") else name[5:] if name.startswith("Right") else name
            if base in _JOINT_DOF:
                dof, share = _JOINT_DOF[base]
                A[j, IX[dof]] = share
        self.A = A                                       # (J,D) joint X-angle per DOF
        # ancestor-or-self matrix: world angle = local angles summed along the path
        anc = np.zeros((J, J))
        for j in range(J):
            anc[j, skeleton.path_to_root(j)] = 1.0
        self.world_map = anc @ A                         # (J,D)
        chain = anc.copy()
        chain[:, 0] = 0.0                                # the root's own offset is not a bone
        self.chain = chain                               # P_j = Σ_k chain[j,k] R(W_par(k)) off_k
        self.levels = skeleton.levels()
        self.offsets = skeleton.offsets
        self.parents = skeleton.parents
        self._par = np.maximum(skeleton.parents, 0)
        self.mass = body.mass
        self.M = float(body.mass.sum())
        self.piece_joint = body.joint
        self.piece_com = body.com
        self.piece_Ixx = body.inertia[:, 0, 0]
        self.ball = skeleton.index("LeftToeBase")

    # ----------------------------------------------------------------- angles
    def joint_angles(self, q: np.ndarray) -> np.ndarray:
        """(...,J) local X-angle of every joint for DOF vectors q (...,D)."""
        return q @ self.A.T

    def quaternions(self, q: np.ndarray) -> np.ndarray:
        """(...,J,4) local joint rotations (scalar-last) for DOF vectors q (...,D)."""
        a = 0.5 * self.joint_angles(q)
        out = np.zeros(a.shape + (4,))
        out[..., 0] = np.sin(a)
        out[..., 3] = np.cos(a)
        return out

    # --------------------------------------------------------------------- FK
    def fk(self, q: np.ndarray):
        """World joint X-angles (N,J) and joint positions (N,J,3) with the root at
        the origin, for DOF vectors q (N,D)."""
        q = np.atleast_2d(q)
        W = q @ self.world_map.T
        P = self.chain @ rot_x(W[:, self._par], self.offsets[None])
        return W, P

    def pieces(self, q: np.ndarray):
        """Piece COM positions (N,P,3) (root at the origin) and world angles."""
        W, P = self.fk(q)
        j = self.piece_joint
        c = P[:, j] + rot_x(W[:, j], self.piece_com[None])
        return c, W, P

    def com(self, q: np.ndarray) -> np.ndarray:
        """(N,3) whole-body COM relative to the root."""
        c, _, _ = self.pieces(q)
        return np.einsum("npa,p->na", c, self.mass) / self.M

    def ball_pos(self, q: np.ndarray) -> np.ndarray:
        """(N,3) position of the left ball of the foot (LeftToeBase) relative to the root."""
        return self.fk(q)[1][:, self.ball]

    # -------------------------------------------------------------- velocities
    def velocities(self, q: np.ndarray, qd: np.ndarray):
        """Exact point velocities for DOF rates ``qd`` with the root *position* fixed
        (the root pitch rate is ``qd[..., pitch]``).

        Returns piece COMs c (N,P,3), piece velocities v (N,P,3), piece angular
        rates w (N,P) about X, and joint positions / velocities (N,J,3)."""
        q, qd = np.atleast_2d(q), np.atleast_2d(qd)
        W = q @ self.world_map.T
        Wd = qd @ self.world_map.T
        r = rot_x(W[:, self._par], self.offsets[None])              # bones in world axes
        P = self.chain @ r
        V = self.chain @ cross_x(Wd[:, self._par], r)
        j = self.piece_joint
        rc = rot_x(W[:, j], self.piece_com[None])
        c = P[:, j] + rc
        v = V[:, j] + cross_x(Wd[:, j], rc)
        return c, v, Wd[:, j], P, V

    def mass_properties(self, q: np.ndarray, qd: np.ndarray):
        """COM (N,3) and COM velocity (N,3) relative to a root whose position is
        fixed, angular momentum about the COM along X (N,) and whole-body inertia
        about the COM about X (N,) for DOF vectors q and rates qd (N,D)."""
        c, v, w, _, _ = self.velocities(q, qd)
        m = self.mass
        com = np.einsum("npa,p->na", c, m) / self.M
        vc = np.einsum("npa,p->na", v, m) / self.M
        r = c - com[:, None]
        u = v - vc[:, None]
        Lx = (m * (r[..., 1] * u[..., 2] - r[..., 2] * u[..., 1])).sum(1) + (self.piece_Ixx * w).sum(1)
        Ixx = (m * (r[..., 1] ** 2 + r[..., 2] ** 2)).sum(1) + self.piece_Ixx.sum()
        return com, vc, Lx, Ixx

    def pinned_com_velocity(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """(N,3) COM velocity when the ball of the foot is pinned to the floor
        (the whole body translates so that the ball does not move)."""
        _, v, _, _, V = self.velocities(q, qd)
        vc = np.einsum("npa,p->na", v, self.mass) / self.M
        return vc - V[:, self.ball]

    def pinned_jacobian(self, q: np.ndarray) -> np.ndarray:
        """(3,D) d(COM − ball)/dq at one pose q (D,)."""
        Q = np.repeat(np.asarray(q, float)[None], D, axis=0)
        return self.pinned_com_velocity(Q, np.eye(D)).T

    def pinned_bias(self, q: np.ndarray, qd: np.ndarray, eps: float = 1e-5) -> np.ndarray:
        """(3,) the velocity-product part of the pinned COM acceleration,
        d/dt[J(q)] q̇ = (J(q + ε q̇) − J(q − ε q̇)) q̇ / 2ε."""
        q, qd = np.asarray(q, float), np.asarray(qd, float)
        Q = np.stack([q + eps * qd, q - eps * qd])
        v = self.pinned_com_velocity(Q, np.stack([qd, qd]))
        return (v[0] - v[1]) / (2 * eps)


# ------------------------------------------------------------- quintic splines
def quintic_coefficients(T, p0, v0, a0, p1, v1, a1):
    """Coefficients c0..c5 (each shaped like p0) of the quintic on [0, T] with the
    given position, velocity and acceleration at both ends."""
    p0, v0, a0, p1, v1, a1 = (np.asarray(x, float) for x in (p0, v0, a0, p1, v1, a1))
    d = p1 - p0
    c3 = (20 * d - (8 * v1 + 12 * v0) * T - (3 * a0 - a1) * T ** 2) / (2 * T ** 3)
    c4 = (-30 * d + (14 * v1 + 16 * v0) * T + (3 * a0 - 2 * a1) * T ** 2) / (2 * T ** 4)
    c5 = (12 * d - 6 * (v1 + v0) * T - (a0 - a1) * T ** 2) / (2 * T ** 5)
    return np.stack([p0, v0, 0.5 * a0, c3, c4, c5])


class QuinticSpline:
    """Piecewise quintic through knots with position, velocity and acceleration
    given at every knot (C² by construction), vectorised over D channels.

    ``knots``: increasing times (K,); ``P, V, A``: (K,D).  Outside the knots the
    end values are held (zero rate)."""

    def __init__(self, knots, P, V=None, A=None):
        self.t = np.asarray(knots, float)
        P = np.atleast_2d(np.asarray(P, float))
        V = np.zeros_like(P) if V is None else np.atleast_2d(np.asarray(V, float))
        A = np.zeros_like(P) if A is None else np.atleast_2d(np.asarray(A, float))
        if np.any(np.diff(self.t) <= 0):
            raise ValueError(f"QuinticSpline: knot times must increase, got {self.t.tolist()}")
        self.P = P
        self.coef = np.stack([quintic_coefficients(self.t[k + 1] - self.t[k], P[k], V[k], A[k],
                                                   P[k + 1], V[k + 1], A[k + 1])
                              for k in range(len(self.t) - 1)])       # (K-1,6,D)

    def __call__(self, t, deriv: int = 0) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        seg = np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.t) - 2)
        tau = t - self.t[seg]
        c = self.coef[seg]                                              # (N,6,D)
        k = np.arange(6)
        if deriv == 0:
            f = np.ones(6)
            pw = k
        elif deriv == 1:
            f, pw = k.astype(float), np.maximum(k - 1, 0)
        elif deriv == 2:
            f, pw = (k * (k - 1)).astype(float), np.maximum(k - 2, 0)
        elif deriv == 3:
            f, pw = (k * (k - 1) * (k - 2)).astype(float), np.maximum(k - 3, 0)
        else:
            raise ValueError("QuinticSpline: deriv must be 0..3")
        basis = f[None] * tau[:, None] ** pw[None]                      # (N,6)
        out = np.einsum("nk,nkd->nd", basis, c)
        before, after = t < self.t[0], t > self.t[-1]
        if before.any():
            out[before] = self.P[0] if deriv == 0 else 0.0
        if after.any():
            out[after] = self.P[-1] if deriv == 0 else 0.0
        return out


class HermiteSegment:
    """One polynomial on [t0, t1] with position and its first ``k`` derivatives
    given at both ends (degree 2k+1), vectorised over channels: e.g. ``k = 3``
    matches position, velocity, acceleration and jerk (degree 7).

    ``start``/``end``: sequences of k+1 arrays (D,): value, 1st, 2nd ... derivative."""

    def __init__(self, t0, t1, start, end):
        self.t0, self.t1 = float(t0), float(t1)
        start = [np.atleast_1d(np.asarray(x, float)) for x in start]
        end = [np.atleast_1d(np.asarray(x, float)) for x in end]
        k = len(start) - 1
        n = 2 * (k + 1)
        T = self.t1 - self.t0
        M = np.zeros((n, n))
        rhs = np.zeros((n,) + start[0].shape)
        for r in range(k + 1):
            # derivative r at tau = 0 and tau = T of sum c_i tau^i
            for i in range(r, n):
                fac = np.prod(np.arange(i - r + 1, i + 1)) if r > 0 else 1.0
                if i == r:
                    M[r, i] = fac
                M[k + 1 + r, i] = fac * T ** (i - r)
            rhs[r] = start[r]
            rhs[k + 1 + r] = end[r]
        self.coef = np.linalg.solve(M, rhs.reshape(n, -1)).reshape(rhs.shape)   # (n,D)
        self.n = n

    def __call__(self, t, deriv: int = 0) -> np.ndarray:
        tau = np.atleast_1d(np.asarray(t, float)) - self.t0
        i = np.arange(self.n)
        f = np.ones(self.n)
        for r in range(deriv):
            f = f * (i - r)
        pw = np.maximum(i - deriv, 0)
        return (f[None] * tau[:, None] ** pw[None]) @ self.coef


def cumulative_simpson(f: np.ndarray, h: float) -> np.ndarray:
    """Cumulative Simpson integral of samples ``f`` (N, N odd) with spacing ``h``,
    returned at the even samples (N//2 + 1 values, the first 0)."""
    f = np.asarray(f, float)
    if f.shape[0] % 2 != 1:
        raise ValueError("cumulative_simpson needs an odd number of samples")
    panels = (f[:-2:2] + 4.0 * f[1:-1:2] + f[2::2]) * (h / 3.0)
    return np.concatenate([np.zeros((1,) + f.shape[1:]), np.cumsum(panels, axis=0)])
