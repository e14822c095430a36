"""The key poses of the built-in clips and the legs solved for the centre of
mass: a balanced crouch (two-bone IK), the take-off and landing poses, the leg
pitches that put the COM on a path (vectorised Newton), and the joint rates of
the take-off instant (ball of the foot pinned, no ground force).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from flipstudy.errors import SynthError
from .designs import G, REF_HEIGHT, dof_vector
from .planar import D, IX, PlanarModel, rot_x

def _two_bone_ik(hip_pos, ankle_pos, l1, l2):
    """Planar two-bone IK in the (y, z) plane, knee bending forward (+Z).

    Returns the world pitches (thigh, shank) of the bones hip → knee → ankle
    (pitch 0 = pointing down; positive rotates the lower end backward)."""
    d = np.asarray(ankle_pos, float) - np.asarray(hip_pos, float)
    dist = np.hypot(d[..., 1], d[..., 2])
    if np.any(dist > l1 + l2 - 1e-9) or np.any(dist < abs(l1 - l2) + 1e-9):
        raise SynthError("leg IK: the hip is out of the leg's reach (crouch too deep or too shallow)")
    alpha = np.arctan2(-d[..., 2], -d[..., 1])
    k = np.arccos(np.clip((dist ** 2 - l1 ** 2 - l2 ** 2) / (2 * l1 * l2), -1, 1))
    beta = np.arccos(np.clip((l1 ** 2 + dist ** 2 - l2 ** 2) / (2 * l1 * dist), -1, 1))
    thigh = alpha - beta
    return thigh, thigh + k


def _leg_lengths(model: PlanarModel):
    sk = model.sk
    return (float(-sk.offsets[sk.index("LeftLeg")][1]), float(-sk.offsets[sk.index("LeftFoot")][1]))


def com_from_ball(model: PlanarModel, q: np.ndarray) -> np.ndarray:
    """COM − ball of the (left) foot for DOF vectors q (...,D)."""
    q2 = np.atleast_2d(q)
    out = model.com(q2) - model.ball_pos(q2)
    return out[0] if np.ndim(q) == 1 else out


def crouch_pose(model: PlanarModel, pitch: float, depth: float, upper: dict) -> np.ndarray:
    """A balanced, flat-footed crouch: the root ``depth`` metres below its
    standing height, pitch and upper body given; the root's forward position is
    found so that the COM is over the same point of the feet as when standing,
    and the legs follow from two-bone IK."""
    sk = model.sk
    l1, l2 = _leg_lengths(model)
    ball0 = model.ball_pos(np.zeros((1, D)))[0]             # ball relative to the root at rest
    ankle_rel_ball = -sk.offsets[sk.index("LeftToeBase")]    # flat foot
    off_hip = sk.offsets[sk.index("LeftUpLeg")]
    bal = com_from_ball(model, np.zeros(D))[2]
    base = dof_vector(pitch=pitch, **upper)

    def pose(root_z):
        root = np.array([0.0, -ball0[1] - depth, root_z])   # relative to the ball
        hip = root + rot_x(np.asarray(pitch, float), off_hip)
        thigh, shank = _two_bone_ik(hip, ankle_rel_ball, l1, l2)
        q = base.copy()
        q[IX["hip"]] = thigh - pitch
        q[IX["knee"]] = shank - thigh
        q[IX["ankle"]] = -shank
        return q, root

    def f(root_z):
        q, root = pose(root_z)
        return float(model.com(q[None])[0, 2] + root[2]) - bal

    lo, hi = _bracket(f, -1.2 * l1, 0.6 * l1, n=73)
    q, _ = pose(brentq(f, lo, hi, xtol=1e-13))
    return q


def _bracket(f, lo, hi, n=41):
    xs = np.linspace(lo, hi, n)
    vals = []
    for x in xs:
        try:
            vals.append(f(x))
        except SynthError:
            vals.append(np.nan)
    vals = np.array(vals)
    for i in range(n - 1):
        if np.isfinite(vals[i]) and np.isfinite(vals[i + 1]) and vals[i] * vals[i + 1] <= 0:
            return xs[i], xs[i + 1]
    raise SynthError("no balanced pose found for these parameters (the centre of mass cannot be "
                     "brought over the feet); use a smaller crouch_depth")


def takeoff_pose(model: PlanarModel, d: dict, H: float) -> np.ndarray:
    """The take-off pose: on the balls of the feet (heel raised by ``heel``),
    knee, pitch and upper body as designed; the hip angle places the COM
    ``takeoff_com_ahead`` metres ahead of the balls of the feet."""
    to = d["takeoff"]
    heel = d["heel"]
    ahead = d["takeoff_com_ahead"] * H / REF_HEIGHT

    def pose(hip):
        q = dof_vector(**to)
        q[IX["hip"]] = hip
        q[IX["ankle"]] = heel - to["pitch"] - hip - to["knee"]
        q[IX["toe"]] = -heel
        return q

    def f(hip):
        return float(com_from_ball(model, pose(hip))[2]) - ahead

    lo, hi = _bracket(f, -1.5, 1.5)
    return pose(brentq(f, lo, hi, xtol=1e-14))


def landing_pose(d: dict) -> np.ndarray:
    q = dof_vector(**d["landing"])
    q[IX["ankle"]] = -(q[IX["pitch"]] + q[IX["hip"]] + q[IX["knee"]])    # feet flat
    return q


# ---------------------------------------------------------- legs from COM
#: DOF-rate fields of the two leg unknowns: shank and thigh world pitch (the foot
#: and everything above the hip keep their world/relative angles)
N_LEG = np.zeros((D, 2))
N_LEG[IX["ankle"]] = (-1.0, 0.0)
N_LEG[IX["knee"]] = (1.0, -1.0)
N_LEG[IX["hip"]] = (0.0, 1.0)


def _assemble_legs(Q: np.ndarray, foot: np.ndarray, shank: np.ndarray, thigh: np.ndarray,
                   flat: float = 0.0) -> np.ndarray:
    """DOF vectors from pitch/upper body in Q, the world pitches of foot, shank
    and thigh (ball of the foot on the floor, toes flat: their world pitch is
    ``flat``, 0 or a whole number of turns after somersaults)."""
    Q = Q.copy()
    Q[:, IX["hip"]] = thigh - Q[:, IX["pitch"]]
    Q[:, IX["knee"]] = shank - thigh
    Q[:, IX["ankle"]] = foot - shank
    Q[:, IX["toe"]] = flat - foot
    return Q


def legs_for_com(model, Q, foot, target, shank, thigh, what, flat=0.0):
    """Solve the shank and thigh pitches (N,) so that COM − ball = ``target``
    (N,3, y and z used) frame by frame (vectorised Newton from the given start);
    ``foot`` (N,) is the world pitch of the foot (heel raised about the ball)."""
    N = Q.shape[0]
    for _ in range(50):
        q = _assemble_legs(Q, foot, shank, thigh, flat)
        r = com_from_ball(model, q)[:, 1:] - target[:, 1:]
        if np.max(np.abs(r)) < 1e-12:
            return q
        Jc = np.stack([model.pinned_com_velocity(q, np.repeat(N_LEG[:, k][None], N, 0))[:, 1:]
                       for k in range(2)], axis=-1)                      # (N,2,2)
        step = np.linalg.solve(Jc, r[..., None])[..., 0]
        step = np.clip(step, -0.3, 0.3)
        shank, thigh = shank - step[:, 0], thigh - step[:, 1]
    raise SynthError(f"{what}: the legs cannot put the centre of mass on the planned path "
                     f"(residual {np.max(np.abs(r)) * 1000:.1f} mm); use other parameters")


def leg_pitches(q: np.ndarray):
    """(shank, thigh) world pitches of DOF vectors q (...,D)."""
    thigh = q[..., IX["pitch"]] + q[..., IX["hip"]]
    return thigh + q[..., IX["knee"]], thigh


# --------------------------------------------------------------- take-off
def contact_rates(model, q, v, Om, dOm, upper_rates, heel_rate, heel_acc):
    """Joint rates and accelerations of a pose whose ball of the foot is pinned
    (toes flat) such that the COM moves with velocity ``v`` and acceleration −g
    (no ground force: the instant of take-off).

    The pitch rate/acceleration, the upper body's rates (accelerations zero) and
    the foot's pitch rate/acceleration about the ball are given; the shank and
    thigh rates and accelerations are solved (two 2×2 systems)."""
    J = model.pinned_jacobian(q)[1:]                       # rows y, z
    base = dof_vector(pitch=Om, **upper_rates)
    base[IX["hip"]] = -Om
    base[IX["ankle"]] = heel_rate
    base[IX["toe"]] = -heel_rate
    A = J @ N_LEG
    u = np.linalg.solve(A, v[1:] - J @ base)
    qd = base + N_LEG @ u
    base_a = dof_vector(pitch=dOm)
    base_a[IX["hip"]] = -dOm
    base_a[IX["ankle"]] = heel_acc
    base_a[IX["toe"]] = -heel_acc
    bias = model.pinned_bias(q, qd)[1:]
    a = np.linalg.solve(A, np.array([-G, 0.0]) - bias - J @ base_a)
    return qd, base_a + N_LEG @ a
