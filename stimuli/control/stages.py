"""The frames of a planned jump (:func:`build`), stage by stage, in continuous
time sampled at ``fps``:

1. **stand** (0.3 s), then **windup**: the windup PD controller's iterations
   (:func:`.windup.approach`) from standing to the chosen crouch, one
   iteration per equal time step, eased in and out over ``crouch_time``; the
   balance PD controller bends the upper body; feet flat and fixed.  Uneven
   legs: the pelvis rolls down on the stronger side as it sinks, so the
   stronger leg bends more (:func:`.uneven.pelvis_roll`; the roll grows in
   proportion to the depth); it unwinds with the lean over the thrust (level
   at take-off), comes back over the landing's absorption (level at
   touch-down) and unwinds again as the jumper stands up.
2. **thrust** (``t_windup``): explicit Euler of the planned acceleration
   a = v0 / t_windup from rest; the whole-body COM follows c_c + ½ a τ² (the
   root solved from it each frame, legs by CCD, heels rising about the balls
   of the feet once the hips are beyond the flat-footed reach) until take-off
   with the legs extended and the COM velocity exactly v0.
3. **flight** (``t_air``): the COM on the exact parabola c_to + v0 t + ½ g t²
   — the root is the desired COM minus the pose's COM offset, so whatever the
   legs do the COM path is exact; the legs tuck and reach forward for the
   landing while the whole body turns (pitches back as the legs come forward)
   so that the angular momentum about the COM stays constant and the body is
   upright again at touch-down.  Contact is found by casting rays down from
   the soles onto the surfaces (floor and box tops).
4. **landing** (the windup reversed): the feet stop where they touch; the COM
   decelerates to rest along c_td + v_L T/3 (1 − (1 − τ)³) into the crouch the
   sample field picks for the landing's kinetic energy; then the jumper stands
   up (0.8 s) and holds (0.3 s).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid, trapezoid
from scipy.spatial.transform import Rotation

from ..edit.timing import slerp
from flipstudy.errors import FlipstudyValueError
from .course import Course
from .ik import EX, heel_pitch, reach
from .model import SIDES, Jumper
from .planning import TAKEOFF_LEAN, Plan, pose_legs
from .uneven import leg_asymmetry, pelvis_roll
from .windup import MAX_HEEL_PITCH

T_STAND, T_CROUCH, T_RECOVER, T_HOLD = 0.3, 0.8, 0.8, 0.4


@dataclass
class Stages:
    """A jump's frames as built: the root (F,3) and the joint rotations
    (F,J,4); the take-off and touch-down instants (s) and the first frames at
    or after them; the first and last frames of the windup and of the thrust;
    the largest distance of a foot from its IK target (mm)."""

    root: np.ndarray
    quats: np.ndarray
    takeoff_s: float
    touchdown_s: float
    takeoff: int
    touchdown: int
    windup_frames: list
    thrust_frames: list
    ik_error_mm: float


def _smooth(x):
    x = np.clip(x, 0.0, 1.0)
    return x ** 3 * (10 - 15 * x + 6 * x ** 2)


def _solve_com(jumper, com, lean, feet, heel: bool, root0, iterations: int = 10, tol: float = 3e-4,
               roll=None):
    """Root (N,3) and quats so the COM is ``com`` (N,3), legs to ``feet`` (flat,
    or heels raised when ``heel`` and the flat foot is out of reach): the root
    moves by the COM error until it is below ``tol`` (the legs' share of the
    mass makes this a contraction; 3–5 rounds, down to the CCD's own stop
    distance)."""
    root = np.array(root0, float, copy=True)
    L_ext = reach(jumper.thigh, jumper.shank, np.radians(1.5))
    for _ in range(iterations):
        pitch = None
        if heel:
            pitch = {}
            Rp = None
            if roll is not None:                                  # the hips of a rolled pelvis
                Rp = Rotation.from_rotvec(np.asarray(roll, float)[:, None] * np.array([0.0, 0.0, 1.0]))
            for s in SIDES:
                hip = root + (jumper.hip_offset[s] if Rp is None else Rp.apply(jumper.hip_offset[s]))
                ball = np.broadcast_to(feet[s] + jumper.ball_offset, hip.shape)
                ph = heel_pitch(hip, ball, jumper.ball_offset, L_ext, MAX_HEEL_PITCH)
                if np.any(~np.isfinite(ph)):
                    raise FlipstudyValueError("thrust: the legs cannot reach the ground from the planned "
                                     "take-off (heels raised 60°); use a longer --windup or a shorter jump")
                pitch[s] = ph
        ankles = {}
        for s in SIDES:
            if heel:
                R = Rotation.from_rotvec(pitch[s][:, None] * EX)
                ankles[s] = feet[s] + jumper.ball_offset - R.apply(jumper.ball_offset)
            else:
                ankles[s] = np.broadcast_to(feet[s], root.shape)
        Q, st = pose_legs(jumper, root, lean, ankles, pitch, roll=roll)
        err = com - jumper.com(root, Q)
        if np.max(np.abs(err)) < tol:
            return root, Q, st
        root = root + err
    raise FlipstudyValueError(f"the legs cannot carry the COM on its planned path (COM error "
                     f"{1000 * np.max(np.abs(err)):.2f} mm after {iterations} rounds)")


def _conserve_momentum(jumper, Qf, com, tf, T, fps, rounds: int = 3):
    """Turn the whole body in flight (the root's rotation) so that its angular
    momentum about the COM is constant while the legs tuck and reach: ω(t) =
    I(t)⁻¹ (L0 − L_joints(t)), with L0 the constant for which the body ends the
    flight upright again (∫ω dt = 0 from take-off to touch-down, so the landing
    pose is the planned one).  A few rounds, each measured with
    :func:`flipstudy.stimuli.physics.momentum` on the posed frames."""
    from ..physics import momentum
    n = len(tf)
    if n < 4:
        return Qf
    tg = np.concatenate([[0.0], tf, [T]])            # take-off … touch-down
    rv = np.zeros((n, 3))
    for _ in range(rounds):
        Q = Qf.copy()
        Q[:, 0] = Rotation.from_rotvec(rv).as_quat()
        off = jumper.com(np.zeros((n, 3)), Q)
        mo = momentum(jumper.clip(com - off, Q, fps), jumper.body)
        Iinv = np.linalg.inv(mo.inertia)                               # (n,3,3)
        w_now = np.gradient(rv, tf, axis=0, edge_order=2)
        ext = lambda a: np.concatenate([a[:1], a, a[-1:]])            # noqa: E731
        A = trapezoid(ext(Iinv.reshape(n, 9)), tg, axis=0).reshape(3, 3)   # ∫ I⁻¹ dt
        b = trapezoid(ext(np.einsum("nab,nb->na", Iinv, mo.L)), tg, axis=0) - rv[-1] * 0.0
        c = trapezoid(ext(w_now), tg, axis=0)
        L0 = np.linalg.solve(A, b - c)
        w = w_now + np.einsum("nab,nb->na", Iinv, L0[None] - mo.L)
        acc = cumulative_trapezoid(ext(w), tg, axis=0, initial=0.0)
        rv = acc[1:-1] - (tg[1:-1] / T)[:, None] * acc[-1][None]       # exactly upright at touch-down
    Q = Qf.copy()
    Q[:, 0] = Rotation.from_rotvec(rv).as_quat()
    return Q


def _slerp_pose(qa, qb, w):
    """Per-joint slerp of two poses (J,4) at weights w (N,) or (N,J) → (N,J,4)."""
    w = np.clip(np.asarray(w, float), 0.0, 1.0)
    w = np.broadcast_to(w[:, None] if w.ndim == 1 else w, (w.shape[0], qa.shape[0]))
    return slerp(np.broadcast_to(qa, w.shape + (4,)), np.broadcast_to(qb, w.shape + (4,)), w)


def _tuck_pose(jumper, q_to, amount, lean):
    q = q_to.copy()
    for s in SIDES:
        q[jumper.idx[f"hip_{s}"]] = Rotation.from_rotvec([-amount * np.radians(60.0), 0, 0]).as_quat()
        q[jumper.idx[f"knee_{s}"]] = Rotation.from_rotvec([amount * np.radians(130.0) + 0.15, 0, 0]).as_quat()
        q[jumper.idx[f"ankle_{s}"]] = Rotation.from_rotvec([np.radians(5.0), 0, 0]).as_quat()
    lq = jumper.lean_quats(lean[None])[0]
    q[jumper.idx["spine"]] = q[jumper.idx["spine1"]] = lq
    return q


def build(jumper: Jumper, sc: Course, pl: Plan, k, fps: float, T_c: float) -> Stages:
    """The frames of a planned jump at ``fps``, the windup's easing over ``T_c``
    seconds (the stages of the module docstring)."""
    path = pl.path
    t_w, t_air = path.t_windup, path.t_air
    F0, F1 = np.asarray(sc.start, float), np.asarray(sc.target, float)
    feet0, feet1 = jumper.feet(F0), jumper.feet(F1)
    up = np.array([0.0, 1.0, 0.0])
    # timing: take-off just after a frame (frame k before it still on the ground)
    t_c0 = T_STAND
    t_to = np.ceil((t_c0 + T_c + t_w) * fps) / fps + 0.1 / fps
    t_c1 = t_to - t_w
    t_c0 = t_c1 - T_c
    t_td = t_to + t_air
    T_a = pl.absorb_time
    t_ab = t_td + T_a
    t_rec = t_ab + T_RECOVER
    F = int(np.floor((t_rec + T_HOLD) * fps)) + 1
    t = np.arange(F) / fps
    root = np.zeros((F, 3))
    Q = jumper.rest_quats(F)
    # 1. stand
    m = t < t_c0
    root[m] = F0 + up * jumper.standing_pelvis
    # 2. windup: the PD iterations, equal time each, eased
    ap = pl.approach
    K = len(ap.pelvis) - 1
    m = (t >= t_c0) & (t < t_c1)
    u = _smooth((t[m] - t_c0) / T_c) * K
    it = np.arange(K + 1)
    pel = np.stack([np.interp(u, it, ap.pelvis[:, a]) for a in range(3)], 1)
    lean = np.stack([np.interp(u, it, ap.lean[:, a]) for a in range(2)], 1)
    c = leg_asymmetry(k)
    roll_w = np.interp(u, it, ap.roll) if c else None
    Qw, st_w = pose_legs(jumper, pel, lean, feet0, roll=roll_w)
    root[m], Q[m] = pel, Qw
    # 3. thrust: explicit Euler of a from rest (exact for constant a) — the COM path
    m = (t >= t_c1) & (t < t_to)
    tt = np.concatenate([t[m], [t_to]])
    tau = tt - t_c1
    com_th = pl.crouch_com[None] + 0.5 * path.a[None] * tau[:, None] ** 2
    d_h = path.v0[[0, 2]] / max(np.hypot(*path.v0[[0, 2]]), 1e-9)
    lean_to = TAKEOFF_LEAN * np.array([d_h[1], -d_h[0]])
    w = _smooth(tau / t_w)[:, None]
    lean_th = (1 - w) * pl.crouch_lean[None] + w * lean_to[None]
    root0 = com_th - (pl.crouch_com - pl.crouch_pelvis)[None]
    # uneven legs: the crouch's roll unwinds with the lean, level at take-off
    roll_th = ap.roll[-1] * (1 - w[:, 0]) if c else None
    r_th, Q_th, st_th = _solve_com(jumper, com_th, lean_th, feet0, True, root0, roll=roll_th)
    root[m], Q[m] = r_th[:-1], Q_th[:-1]
    q_to = Q_th[-1]
    # 4. flight: exact parabola of the whole-body COM; legs tuck, then reach for the landing
    Q_td, _ = pose_legs(jumper, pl.touchdown_pelvis, pl.touchdown_lean, feet1)
    q_td = Q_td[0]
    q_tk = _tuck_pose(jumper, q_to, sc.tuck, lean_to)
    m = (t >= t_to) & (t < t_td)
    tf = t[m] - t_to
    t_mid = 0.4 * t_air
    # knees and ankles fold at once (the feet leave the ground briskly), the hips follow
    tau1 = np.clip(tf / t_mid, 0, 1)
    w1 = np.repeat((1.0 - (1.0 - tau1) ** 4)[:, None], jumper.J, 1)
    for s_ in SIDES:
        w1[:, jumper.idx[f"hip_{s_}"]] = _smooth(tau1)
    w2 = _smooth((tf - t_mid) / (0.92 * t_air - t_mid))      # feet set for the landing before it
    Qf = np.where((tf < t_mid)[:, None, None], _slerp_pose(q_to, q_tk, w1), _slerp_pose(q_tk, q_td, w2))
    c_f = pl.takeoff_com[None] + path.position(tf)
    Qf = _conserve_momentum(jumper, Qf, c_f, tf, t_air, fps)
    off = jumper.com(np.zeros((len(tf), 3)), Qf)
    root[m], Q[m] = c_f - off, Qf
    # 5. landing: absorb (feet fixed), recover, hold
    m = (t >= t_td) & (t < t_ab)
    ta = np.concatenate([[t_td], t[m]])
    s = (ta - t_td) / T_a
    com_ab = pl.touchdown_com[None] + (path.v_land * T_a / 3.0)[None] * (1 - (1 - s[:, None]) ** 3)
    w = _smooth(s)[:, None]
    lean_ab = (1 - w) * pl.touchdown_lean[None] + w * pl.stop_lean[None]
    root0 = com_ab - (pl.touchdown_com - pl.touchdown_pelvis)[None]
    # uneven legs: level at touch-down, rolling into the landing crouch's roll
    roll_s = pelvis_roll(jumper, c, jumper.standing_pelvis - (pl.stop_pelvis[1] - F1[1]))[0]
    roll_ab = roll_s * w[:, 0] if c else None
    r_ab, Q_ab, st_ab = _solve_com(jumper, com_ab, lean_ab, feet1, False, root0, roll=roll_ab)
    root[m], Q[m] = r_ab[1:], Q_ab[1:]
    m = t >= t_ab
    w = _smooth((t[m] - t_ab) / T_RECOVER)[:, None]
    stand1 = F1 + up * jumper.standing_pelvis
    pel = (1 - w) * pl.stop_pelvis[None] + w * stand1[None]
    lean = (1 - w) * pl.stop_lean[None]
    Qr, st_r = pose_legs(jumper, pel, lean, feet1, roll=roll_s * (1 - w[:, 0]) if c else None)
    root[m], Q[m] = pel, Qr
    i_to = int(np.ceil(t_to * fps - 1e-9))
    i_td = int(np.ceil(t_td * fps - 1e-9))
    return Stages(root, Q, float(t_to), float(t_td), i_to, i_td,
                  [int(np.ceil(t_c0 * fps)), int(np.ceil(t_c1 * fps)) - 1],
                  [int(np.ceil(t_c1 * fps)), i_to - 1],
                  float(1000 * max(st_w.error.max(), st_th.error.max(), st_ab.error.max(), st_r.error.max())))
