"""Construction of the built-in, physically exact clips (see :func:`builtin`).

The motion is sagittal and left/right symmetric (rotations about X only, see
:mod:`flipstudy.stimuli.synth.planar`).  Phases (times for the defaults, 120 fps):

1. **stand, crouch** (0–1.06 s).  Joint angles are quintics in the DOFs of
   :mod:`.planar`, feet flat.  The crouch is placed by analytic two-bone leg IK
   with the centre of mass over the same point of the feet as when standing;
   it is reached at rest but already pushed upward (COM acceleration
   ``a_bottom``: a counter-movement).
2. **push** (to 1.30 s).  The COM follows a degree-7 piece matching position,
   velocity, acceleration and jerk at both ends: from the crouch to the
   flight's initial position, velocity ``v0`` and acceleration −g with zero
   jerk (the ground force fades to zero tangentially as the foot unrolls).
   Pitch, spine, neck and arms are quintics; the heel rises about the ball of
   the foot (foot pitch ``heel0 τ³``); the shank and thigh pitches are solved
   frame by frame (vectorised Newton) so that the body's COM is on that curve.
3. **flight** (0.68 s for the flips).  Joint angles are quintics take-off →
   tuck → hold → landing pose.  The root pitch rate follows from conservation
   of the angular momentum about the COM, Ω(t) = (L − h(t)) / I(t), with I the
   whole-body inertia about the lateral axis and h the angular momentum of the
   joint motion relative to the root, both exact (analytic rates) on a grid 16×
   finer than the frames; L = (Δθ + ∫h/I dt) / ∫1/I dt makes the flight rotate
   by exactly Δθ, and the pitch is the cumulative Simpson integral of Ω.  The
   root position is the ballistic COM parabola minus the COM offset of the pose
   (forward kinematics + :class:`flipstudy.stimuli.body.Body`, as
   :func:`flipstudy.stimuli.physics.center_of_mass` computes it), so the COM is an exact
   parabola.
4. **touch-down, absorb**.  The feet arrive flat on the floor and stop there
   (the impact: the leg joint rates jump).  The COM keeps its velocity and
   decelerates to rest along c(τ) = c_L + v_L T_a/3 · (1 − (1 − τ)³) (the
   largest ground force at impact, fading to body weight); pitch and upper body
   keep their rates and ease into the absorbed pose; the legs are solved for
   the COM again.
5. **recover, hold**.  Quintics from the absorbed crouch up to the rest pose,
   at the same facing after the whole number of somersaults.

Take-off continuity: at the take-off instant the ball of the foot is pinned and
the ground force is zero, so the shank and thigh rates and accelerations follow
from the COM velocity ``v0`` and acceleration −g (:func:`_contact_rates`, two
2×2 systems).  The flight's angular momentum depends on them, and the push's
pitch rate and acceleration must equal the flight's Ω(0) and Ω̇(0): that fixed
point is solved by a chord-Newton iteration.  Everything (COM, every joint
angle, rate and acceleration, hence L) is continuous across take-off.

Feet: in every ground frame the root position is the pinned ball of the foot
minus the chain's forward kinematics, so the toes never move (to rounding);
the ankle rises only while the heel does, before take-off.
"""

from __future__ import annotations

from ..exceptions import FlipstudyValueError

from ..exceptions import FlipstudyError

import time

import numpy as np
from scipy.optimize import brentq, fsolve

from ..body import Body
from ..motion.clip import Clip
from ..physics import center_of_mass
from .planar import D, IX, HermiteSegment, PlanarModel, QuinticSpline, cumulative_simpson, rot_x
from .skeleton import make_skeleton

G = 9.81
BUILTIN_NAMES = ("backflip", "frontflip", "jump")
SUBSTEPS = 16            # fine integration grid per frame in flight
REF_HEIGHT = 1.75        # lengths of the designs below are for this height

def _vec(**kw) -> np.ndarray:
    q = np.zeros(D)
    for k, v in kw.items():
        q[IX[k]] = v
    return q


# The designs: angles in radians (DOF signs as in .planar), lengths in metres for a
# 1.75 m body (scaled with height), times in seconds.
_COMMON = dict(
    t_stand=0.30, t_crouch=1.06, t_takeoff=1.30,     # end of the hold, crouch bottom, take-off
    a_bottom=9.81,                                   # COM acceleration at the crouch bottom
    recover=0.80, hold=0.30,                         # after the absorb
    tuck_in=0.38, tuck_out=0.70,                     # tuck reached / left (fractions of flight)
    heel=0.35, heel_rate=16.0,                       # foot pitch about the ball at take-off, rad/s
    absorb_depth=0.25,                               # COM drop after touch-down, m
)
DESIGNS = {
    "backflip": dict(
        _COMMON, turns=-1, flight_time=0.68, horizontal_speed=-0.45, tuck=1.0, crouch_depth=0.40,
        crouch=dict(pitch=0.55, spine=0.15, neck=0.0, shoulder=0.9, elbow=-0.3),
        takeoff=dict(pitch=-0.22, knee=0.80, spine=-0.20, neck=-0.15, shoulder=-2.3, elbow=-0.1),
        takeoff_rates=dict(spine=-3.0, neck=-1.0, shoulder=-10.0, elbow=0.0),
        takeoff_com_ahead=-0.18,
        layout=_vec(hip=-0.15, knee=0.1, ankle=0.45, spine=-0.15, neck=-0.2, shoulder=-2.9, elbow=-0.1),
        tucked=_vec(hip=-2.2, knee=2.3, ankle=0.5, spine=0.45, neck=0.35, shoulder=-0.8, elbow=-1.1),
        landing=dict(pitch=0.35, hip=-0.75, knee=0.55, spine=0.10, neck=0.0, shoulder=-1.5, elbow=-0.3),
        absorb_pose=dict(pitch=0.45, spine=0.15, neck=0.05, shoulder=-1.3, elbow=-0.4),
    ),
    "frontflip": dict(
        _COMMON, turns=+1, flight_time=0.68, horizontal_speed=0.70, tuck=1.0, crouch_depth=0.40,
        crouch=dict(pitch=0.50, spine=0.15, neck=0.0, shoulder=-2.8, elbow=-0.3),
        takeoff=dict(pitch=0.40, knee=0.80, spine=0.15, neck=0.2, shoulder=-2.2, elbow=-0.1),
        takeoff_rates=dict(spine=2.0, neck=1.0, shoulder=5.0, elbow=0.0),
        takeoff_com_ahead=0.0,
        layout=_vec(hip=-0.3, knee=0.1, ankle=0.45, spine=0.2, neck=0.2, shoulder=-2.9, elbow=-0.1),
        tucked=_vec(hip=-2.2, knee=2.3, ankle=0.5, spine=0.5, neck=0.5, shoulder=-0.8, elbow=-1.1),
        landing=dict(pitch=0.30, hip=-0.70, knee=0.60, spine=0.10, neck=0.0, shoulder=-1.6, elbow=-0.3),
        absorb_pose=dict(pitch=0.60, spine=0.20, neck=0.05, shoulder=-1.3, elbow=-0.4),
    ),
    "jump": dict(
        _COMMON, turns=0, flight_time=0.50, horizontal_speed=0.10, tuck=0.3, crouch_depth=0.32,
        crouch=dict(pitch=0.50, spine=0.15, neck=0.0, shoulder=0.9, elbow=-0.3),
        takeoff=dict(pitch=0.15, knee=0.80, spine=0.0, neck=0.0, shoulder=-2.5, elbow=-0.1),
        takeoff_rates=dict(spine=0.0, neck=0.0, shoulder=-1.0, elbow=0.0),
        takeoff_com_ahead=-0.10,
        layout=_vec(hip=-0.1, knee=0.1, ankle=0.45, spine=0.0, neck=0.0, shoulder=-2.9, elbow=-0.1),
        tucked=_vec(hip=-1.6, knee=2.0, ankle=0.5, spine=0.3, neck=0.2, shoulder=-2.2, elbow=-0.6),
        landing=dict(pitch=0.20, hip=-0.45, knee=0.45, spine=0.05, neck=0.0, shoulder=-1.2, elbow=-0.3),
        absorb_pose=dict(pitch=0.45, spine=0.15, neck=0.05, shoulder=-1.0, elbow=-0.4),
        absorb_depth=0.20,
    ),
}

#: the keyword parameters :func:`builtin` accepts (besides fps and total_mass)
PARAMS = ("height", "flight_time", "tuck", "horizontal_speed", "crouch_depth", "turns", "shape")
#: body shapes in flight: "tuck" (hips and knees flexed), "pike" (hips flexed, knees
#: straight), "layout" (body straight; the same as tuck = 0)
SHAPES = ("tuck", "pike", "layout")


class SynthError(FlipstudyError, ValueError):
    """Parameters for which no consistent motion exists (the message says which)."""


# ------------------------------------------------------------------ poses
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


def _rel(model: PlanarModel, q: np.ndarray) -> np.ndarray:
    """COM − ball of the (left) foot for DOF vectors q (...,D)."""
    q2 = np.atleast_2d(q)
    out = model.com(q2) - model.ball_pos(q2)
    return out[0] if np.ndim(q) == 1 else out


def _crouch_pose(model: PlanarModel, pitch: float, depth: float, upper: dict) -> np.ndarray:
    """A balanced, flat-footed crouch: the root ``depth`` metres below its
    standing height, pitch and upper body given; the root's forward position is
    found so that the COM is over the same point of the feet as when standing,
    and the legs follow from two-bone IK."""
    sk = model.sk
    l1, l2 = _leg_lengths(model)
    ball0 = model.ball_pos(np.zeros((1, D)))[0]             # ball relative to the root at rest
    ankle_rel_ball = -sk.offsets[sk.index("LeftToeBase")]    # flat foot
    off_hip = sk.offsets[sk.index("LeftUpLeg")]
    bal = _rel(model, np.zeros(D))[2]
    base = _vec(pitch=pitch, **upper)

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


def _takeoff_pose(model: PlanarModel, d: dict, H: float) -> np.ndarray:
    """The take-off pose: on the balls of the feet (heel raised by ``heel``),
    knee, pitch and upper body as designed; the hip angle places the COM
    ``takeoff_com_ahead`` metres ahead of the balls of the feet."""
    to = d["takeoff"]
    heel = d["heel"]
    ahead = d["takeoff_com_ahead"] * H / REF_HEIGHT

    def pose(hip):
        q = _vec(**to)
        q[IX["hip"]] = hip
        q[IX["ankle"]] = heel - to["pitch"] - hip - to["knee"]
        q[IX["toe"]] = -heel
        return q

    def f(hip):
        return float(_rel(model, pose(hip))[2]) - ahead

    lo, hi = _bracket(f, -1.5, 1.5)
    return pose(brentq(f, lo, hi, xtol=1e-14))


def _landing_pose(d: dict) -> np.ndarray:
    q = _vec(**d["landing"])
    q[IX["ankle"]] = -(q[IX["pitch"]] + q[IX["hip"]] + q[IX["knee"]])    # feet flat
    return q


# ---------------------------------------------------------- legs from COM
#: DOF-rate fields of the two leg unknowns: shank and thigh world pitch (the foot
#: and everything above the hip keep their world/relative angles)
_N_LEG = np.zeros((D, 2))
_N_LEG[IX["ankle"]] = (-1.0, 0.0)
_N_LEG[IX["knee"]] = (1.0, -1.0)
_N_LEG[IX["hip"]] = (0.0, 1.0)


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


def _legs_for_com(model, Q, foot, target, shank, thigh, what, flat=0.0):
    """Solve the shank and thigh pitches (N,) so that COM − ball = ``target``
    (N,3, y and z used) frame by frame (vectorised Newton from the given start);
    ``foot`` (N,) is the world pitch of the foot (heel raised about the ball)."""
    N = Q.shape[0]
    for _ in range(50):
        q = _assemble_legs(Q, foot, shank, thigh, flat)
        r = _rel(model, q)[:, 1:] - target[:, 1:]
        if np.max(np.abs(r)) < 1e-12:
            return q
        Jc = np.stack([model.pinned_com_velocity(q, np.repeat(_N_LEG[:, k][None], N, 0))[:, 1:]
                       for k in range(2)], axis=-1)                      # (N,2,2)
        step = np.linalg.solve(Jc, r[..., None])[..., 0]
        step = np.clip(step, -0.3, 0.3)
        shank, thigh = shank - step[:, 0], thigh - step[:, 1]
    raise SynthError(f"{what}: the legs cannot put the centre of mass on the planned path "
                     f"(residual {np.max(np.abs(r)) * 1000:.1f} mm); use other parameters")


def _leg_pitches(q: np.ndarray):
    """(shank, thigh) world pitches of DOF vectors q (...,D)."""
    thigh = q[..., IX["pitch"]] + q[..., IX["hip"]]
    return thigh + q[..., IX["knee"]], thigh


# --------------------------------------------------------------- take-off
def _contact_rates(model, q, v, Om, dOm, upper_rates, heel_rate, heel_acc):
    """Joint rates and accelerations of a pose whose ball of the foot is pinned
    (toes flat) such that the COM moves with velocity ``v`` and acceleration −g
    (no ground force: the instant of take-off).

    The pitch rate/acceleration, the upper body's rates (accelerations zero) and
    the foot's pitch rate/acceleration about the ball are given; the shank and
    thigh rates and accelerations are solved (two 2×2 systems)."""
    J = model.pinned_jacobian(q)[1:]                       # rows y, z
    base = _vec(pitch=Om, **upper_rates)
    base[IX["hip"]] = -Om
    base[IX["ankle"]] = heel_rate
    base[IX["toe"]] = -heel_rate
    A = J @ _N_LEG
    u = np.linalg.solve(A, v[1:] - J @ base)
    qd = base + _N_LEG @ u
    base_a = _vec(pitch=dOm)
    base_a[IX["hip"]] = -dOm
    base_a[IX["ankle"]] = heel_acc
    base_a[IX["toe"]] = -heel_acc
    bias = model.pinned_bias(q, qd)[1:]
    a = np.linalg.solve(A, np.array([-G, 0.0]) - bias - J @ base_a)
    return qd, base_a + _N_LEG @ a


def _flight_spline(d, q0, qd0, qdd0, qL, T, tuck):
    """Joint angles in flight (pitch excluded): take-off state → tuck (reached at
    ``tuck_in``·T, held to ``tuck_out``·T) → landing pose at rest."""
    q_mid = d["layout"] + tuck * (d["tucked"] - d["layout"])
    t_in, t_out = d["tuck_in"] * T, d["tuck_out"] * T
    P = np.stack([q0, q_mid, q_mid, qL])
    V = np.stack([qd0, np.zeros(D), np.zeros(D), np.zeros(D)])
    A = np.stack([qdd0, np.zeros(D), np.zeros(D), np.zeros(D)])
    P[:, IX["pitch"]] = V[:, IX["pitch"]] = A[:, IX["pitch"]] = 0.0   # pitch comes from L
    return QuinticSpline([0.0, t_in, t_out, T], P, V, A)


def _flight_rotation(model, spline, T, n_fine, dtheta):
    """Flight pitch from conservation of angular momentum about the COM.

    Returns L, Ω at the fine samples, the pitch change since take-off at the
    even fine samples, and h, I at the fine samples."""
    t = np.linspace(0.0, T, n_fine + 1)
    _, _, h, I = model.mass_properties(spline(t), spline(t, 1))
    dt = T / n_fine
    S_inv = cumulative_simpson(1.0 / I, dt)
    S_h = cumulative_simpson(h / I, dt)
    L = (dtheta + S_h[-1]) / S_inv[-1]
    return L, (L - h) / I, L * S_inv - S_h, h, I


# ------------------------------------------------------------------- build
def _check_params(name, fps, total_mass, params):
    if name not in DESIGNS:
        raise FlipstudyValueError(f"unknown built-in clip {name!r}; valid names: {', '.join(BUILTIN_NAMES)}")
    bad = [k for k in params if k not in PARAMS]
    if bad:
        raise FlipstudyValueError(f"builtin({name!r}): unknown parameter(s) {bad}; valid: "
                         f"{', '.join(PARAMS)} (and fps, total_mass)")
    if not (isinstance(fps, (int, float, np.number)) and np.isfinite(fps) and fps >= 10):
        raise FlipstudyValueError(f"fps must be a number of frames per second >= 10, got {fps!r}")
    if not (np.isfinite(total_mass) and total_mass > 0):
        raise FlipstudyValueError(f"total_mass must be a positive number of kg, got {total_mass!r}")
    d = dict(DESIGNS[name])
    for k in ("flight_time", "tuck", "horizontal_speed", "crouch_depth", "turns"):
        if k in params:
            d[k] = params[k]
    shape = params.get("shape", "tuck")
    if shape not in SHAPES:
        raise FlipstudyValueError(f"shape must be one of {', '.join(SHAPES)}, got {shape!r}")
    if shape == "pike":                   # hips folded further, knees straight
        d["tucked"] = d["tucked"].copy()
        d["tucked"][IX["hip"]] = -2.5
        d["tucked"][IX["knee"]] = 0.05
    elif shape == "layout":
        d["tuck"] = 0.0
    H = float(params.get("height", REF_HEIGHT))
    if not (np.isfinite(H) and 1.0 <= H <= 2.5):
        raise FlipstudyValueError(f"height must be between 1.0 and 2.5 m, got {H!r}")
    if not (0.0 <= float(d["tuck"]) <= 1.0):
        raise FlipstudyValueError(f"tuck must be between 0 (layout) and 1 (full tuck), got {d['tuck']!r}")
    if not (0.3 <= float(d["flight_time"]) <= 1.2):
        raise FlipstudyValueError(f"flight_time must be between 0.3 and 1.2 s, got {d['flight_time']!r}")
    if not (abs(float(d["horizontal_speed"])) <= 3.0):
        raise FlipstudyValueError(f"horizontal_speed must be within ±3 m/s, got {d['horizontal_speed']!r}")
    if not (0.10 <= float(d["crouch_depth"]) <= 0.45):
        raise FlipstudyValueError(f"crouch_depth must be between 0.10 and 0.45 m, got {d['crouch_depth']!r}")
    turns = d["turns"]
    if name == "jump":
        if turns != 0:
            raise FlipstudyValueError("turns: the jump does not rotate; use 'backflip' or 'frontflip'")
    else:
        if int(turns) != turns or abs(turns) < 1 or abs(turns) > 3:
            raise FlipstudyValueError(f"turns must be a whole number of somersaults from 1 to 3 (the clip "
                             f"ends standing at the same facing), got {turns!r}")
        turns = (-1 if name == "backflip" else 1) * abs(int(turns))
    d["turns"] = turns
    return d, H


def build(name: str, fps: float = 120.0, total_mass: float = 70.0,
          segment_masses: dict | None = None, **params) -> Clip:
    """See :func:`flipstudy.stimuli.synth.builtin`."""
    t_start = time.perf_counter()
    d, H = _check_params(name, fps, total_mass, params)
    turns = d["turns"]
    scale = H / REF_HEIGHT
    fps = float(fps)
    sk = make_skeleton(H)
    body = Body.from_skeleton(sk, total_mass, segment_masses=segment_masses)
    if segment_masses:
        total_mass = body.total_mass              # the sum, when segment masses are given
    model = PlanarModel(sk, body)

    # take-off and touch-down on the frame grid: the flight lasts whole frames
    snap = lambda x: max(1, int(round(x * fps)))  # noqa: E731
    i_to = snap(d["t_takeoff"])
    n_flight = snap(d["flight_time"])
    i_td = i_to + n_flight
    T = n_flight / fps
    t_to, t_td = i_to / fps, i_td / fps

    # key poses and the ballistic path
    q0 = _takeoff_pose(model, d, H)
    qL = _landing_pose(d)
    q_crouch = _crouch_pose(model, d["crouch"]["pitch"], d["crouch_depth"] * scale,
                            {k: v for k, v in d["crouch"].items() if k != "pitch"})
    rel0, relL = _rel(model, q0), _rel(model, qL)
    v0 = np.array([0.0, (relL[1] - rel0[1] + 0.5 * G * T ** 2) / T, float(d["horizontal_speed"])])
    vL = v0 - np.array([0.0, G * T, 0.0])
    dtheta = (qL[IX["pitch"]] + 2 * np.pi * turns) - q0[IX["pitch"]]

    fl = _solve_flight(name, model, d, q0, qL, v0, T, n_flight, dtheta)
    heel_dur = 3.0 * d["heel"] / d["heel_rate"]
    if heel_dur >= t_to - d["t_crouch"]:
        raise SynthError(f"builtin({name!r}): the heel rise ({heel_dur:.2f} s) does not fit in the push")

    # ground before take-off (the left ball of the foot at its rest position)
    ball_rest = model.ball_pos(np.zeros((1, D)))[0]
    B = np.array([ball_rest[0], 0.0, ball_rest[2]])
    tp = np.arange(0, i_to) / fps
    Q_pre, push_rise = _ground_before(model, d, tp, q_crouch, q0, fl["qd0"], fl["qdd0"], rel0, v0,
                                      t_to, heel_dur)
    root_pre = B[None] - model.ball_pos(Q_pre)

    # flight: the pitch from L, the root from the parabola and the body's COM
    tf = np.arange(0, n_flight + 1) / fps
    Q_fl = fl["spline"](tf)
    Q_fl[:, IX["pitch"]] = q0[IX["pitch"]] + fl["theta"][::SUBSTEPS // 2]
    c0 = B + rel0
    parab = c0[None] + v0[None] * tf[:, None] - 0.5 * G * np.outer(tf ** 2, [0.0, 1.0, 0.0])
    rel_clip = Clip(sk, fps, np.zeros((len(tf), 3)), model.quaternions(Q_fl))
    root_fl = parab - center_of_mass(rel_clip, body)
    ball_td = root_fl[-1] + model.ball_pos(Q_fl[-1][None])[0]
    B_td = np.array([ball_td[0], 0.0, ball_td[2]])

    # ground after touch-down
    qd_td = fl["spline"](T, 1)[0]
    qd_td[IX["pitch"]] = fl["Om"][-1]
    Q_post = _ground_after(model, d, fps, scale, turns, i_td, t_td, qL, qd_td, relL, vL)
    root_post = B_td[None] - model.ball_pos(Q_post)

    Q = np.concatenate([Q_pre, Q_fl, Q_post])
    root = np.concatenate([root_pre, root_fl, root_post])
    meta = {
        "name": name, "source": "builtin",
        "takeoff": int(i_to), "landing": int(i_td - 1), "touchdown": int(i_td),
        "flight_s": float(T),
        "L_flight": [float(fl["L"]), 0.0, 0.0], "v0": [float(v) for v in v0], "g": G,
        "total_mass": float(total_mass), "height": H,
        "segment_masses": body.segment_masses(),
        "rotation_deg": float(np.degrees(2 * np.pi * turns)),
        "flight_rotation_deg": float(np.degrees(dtheta)),
        "takeoff_pitch_rate": float(fl["Om"][0]), "landing_pitch_rate": float(fl["Om"][-1]),
        "max_pitch_rate": float(np.abs(fl["Om"]).max()),
        "com_rise_m": float(v0[1] ** 2 / (2 * G)), "push_rise_m": push_rise,
        "heel_off": int(np.floor((t_to - heel_dur) * fps)) + 1,
        "params": {"height": H, "flight_time": float(T), "tuck": float(d["tuck"]),
                   "horizontal_speed": float(d["horizontal_speed"]),
                   "crouch_depth": float(d["crouch_depth"]), "turns": int(abs(turns))},
        "warnings": [],
    }
    clip = Clip(sk, fps, root, model.quaternions(Q), meta=meta)
    clip.meta["build_s"] = time.perf_counter() - t_start
    return clip


def _solve_flight(name, model, d, q0, qL, v0, T, n_flight, dtheta) -> dict:
    """The flight's joint angles, L and pitch, with the take-off fixed point solved:
    the take-off leg rates/accelerations depend on the pitch rate Ω0 and pitch
    acceleration Ω̇0 (the pinned chain must give the COM v0 and −g), L depends on
    the leg motion, and Ω0, Ω̇0 must be the flight's (L − h)/I and its rate."""
    heel_rate = d["heel_rate"]
    heel_acc = (2.0 / 3.0) * heel_rate ** 2 / d["heel"]   # foot pitch heel0 τ³ at its end

    def state(x, sub=SUBSTEPS):
        qd0, qdd0 = _contact_rates(model, q0, v0, x[0], x[1], d["takeoff_rates"], heel_rate, heel_acc)
        spl = _flight_spline(d, q0, qd0, qdd0, qL, T, float(d["tuck"]))
        L, Om, theta, h, I = _flight_rotation(model, spl, T, n_flight * sub, dtheta)
        hs = T / (n_flight * sub)
        dOm0 = (-25 * Om[0] + 48 * Om[1] - 36 * Om[2] + 16 * Om[3] - 3 * Om[4]) / (12 * hs)
        return dict(qd0=qd0, qdd0=qdd0, spline=spl, L=L, Om=Om, theta=theta, I=I, h=h,
                    x=np.array([Om[0], dOm0]))

    wts = np.array([1.0, 0.01])                            # Ω̇ is ~100× Ω in size

    def resid(x, sub=SUBSTEPS):
        try:
            return (state(x, sub)["x"] - x) * wts
        except np.linalg.LinAlgError:
            return np.full(2, 1e3)

    # chord-Newton: a few damped steps for a sane start, the Jacobian by
    # differences on a coarse grid, iterations on the coarse then the fine grid
    x = np.array([dtheta / T * 0.4, 0.0])
    for _ in range(3):
        x = 0.5 * x + 0.5 * state(x, 2)["x"]
    r = resid(x, 2)
    Jr = np.empty((2, 2))
    for k, step in enumerate((1e-4, 1e-2)):
        e = np.zeros(2)
        e[k] = step
        Jr[:, k] = (resid(x + e, 2) - r) / step
    for sub, tol in ((2, 1e-9), (SUBSTEPS, 1e-12)):
        r = resid(x, sub)
        for _ in range(40):
            if np.max(np.abs(r)) < tol:
                break
            x = x - np.linalg.solve(Jr, r)
            r = resid(x, sub)
    if not np.max(np.abs(r)) < 1e-9:                       # fall back on a full root solve
        x, info, ier, msg = fsolve(resid, x, full_output=True, xtol=1e-13)
        if np.max(np.abs(resid(x))) > 1e-9:
            raise SynthError(f"builtin({name!r}): the take-off state did not converge ({msg}); "
                             f"try other parameters")
    return state(x)


def _ground_before(model, d, tp, q_crouch, q0, qd0, qdd0, rel0, v0, t_to, heel_dur):
    """DOF vectors (N,D) at the times ``tp`` before take-off, and the COM rise of
    the push.  Down into the crouch: quintics in the joint angles (feet flat)
    arriving at rest with the COM accelerating upward at ``a_bottom``.  Up to
    take-off: the COM on a degree-7 piece, the legs solved for it."""
    t_stand, t_crouch = d["t_stand"], d["t_crouch"]
    z3 = np.zeros(3)
    Jc = model.pinned_jacobian(q_crouch)
    a_b = np.array([0.0, d["a_bottom"], 0.0])
    qdd_c = _N_LEG @ np.linalg.solve(Jc[1:] @ _N_LEG, a_b[1:])    # legs give the COM a_b
    down = QuinticSpline([t_stand, t_crouch], np.stack([np.zeros(D), q_crouch]),
                         np.zeros((2, D)), np.stack([np.zeros(D), qdd_c]))
    Q = down(tp)
    up_body = QuinticSpline([t_crouch, t_to], np.stack([q_crouch, q0]), np.stack([np.zeros(D), qd0]),
                            np.stack([qdd_c, qdd0]))
    rel_c = _rel(model, q_crouch)
    jerk_c = Jc @ down(t_crouch, 3)[0]                      # COM jerk at the bottom (rates are 0)
    up = HermiteSegment(t_crouch, t_to, [rel_c, z3, a_b, jerk_c],
                        [rel0, v0, np.array([0.0, -G, 0.0]), z3])
    mv = tp > t_crouch
    if mv.any():
        tk = tp[mv]
        foot = d["heel"] * np.clip((tk - (t_to - heel_dur)) / heel_dur, 0.0, None) ** 3
        w = (tk - t_crouch) / (t_to - t_crouch)
        (s_c, t_c), (s_0, t_0) = _leg_pitches(q_crouch), _leg_pitches(q0)
        Q[mv] = _legs_for_com(model, up_body(tk), foot, up(tk), s_c + w * (s_0 - s_c),
                              t_c + w * (t_0 - t_c), "take-off")
    return Q, float(rel0[1] - rel_c[1])


def _ground_after(model, d, fps, scale, turns, i_td, t_td, qL, qd_td, relL, vL):
    """DOF vectors (N,D) of the frames after touch-down: absorb (COM-driven,
    legs solved), recover (quintics to the rest pose), hold."""
    T_a = 3.0 * d["absorb_depth"] * scale / abs(vL[1])
    t_abs = t_td + T_a
    t_rec = t_abs + d["recover"]
    F = int(np.floor((t_rec + d["hold"]) * fps)) + 1
    tq = np.arange(i_td + 1, F) / fps
    foot = 2 * np.pi * turns                               # feet flat, after the somersaults
    qL_abs = qL.copy()
    qL_abs[IX["pitch"]] += foot
    absorb_to = _vec(**d["absorb_pose"])
    absorb_to[IX["pitch"]] += foot
    upper = QuinticSpline([t_td, t_abs], np.stack([qL_abs, absorb_to]), np.stack([qd_td, np.zeros(D)]))
    shift = vL * T_a / 3.0

    def com_path(t):
        tau = ((t - t_td) / T_a)[:, None]
        return relL[None] + shift[None] * (1.0 - (1.0 - tau) ** 3)

    s_L, t_L = _leg_pitches(qL_abs)
    q_A = _legs_for_com(model, upper(np.array([t_abs])), np.full(1, foot), (relL + shift)[None],
                        np.array([s_L]), np.array([t_L]), "absorb", foot)[0]
    Q = np.empty((len(tq), D))
    ab = tq <= t_abs
    if ab.any():
        w = (tq[ab] - t_td) / T_a
        s_A, t_A = _leg_pitches(q_A)
        Q[ab] = _legs_for_com(model, upper(tq[ab]), np.full(ab.sum(), foot), com_path(tq[ab]),
                              s_L + w * (s_A - s_L), t_L + w * (t_A - t_L), "absorb", foot)
    rest = ~ab
    if rest.any():
        recover = QuinticSpline([t_abs, t_rec], np.stack([q_A, _vec(pitch=foot)]))
        Q[rest] = recover(tq[rest])
        Q[rest, IX["ankle"]] = foot - (Q[rest, IX["pitch"]] + Q[rest, IX["hip"]] + Q[rest, IX["knee"]])
        Q[rest, IX["toe"]] = 0.0
    return Q
