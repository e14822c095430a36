"""Standing jumps to a target by the energy-based controller of Ooi 2016 (3.6),
written as keyframed clips — with a landing, which the thesis left out.

Stages (continuous time, sampled at ``fps``):

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

The plan makes the stages meet: the take-off COM depends on the crouch, the
crouch on the energy of v0, v0 on the take-off and touch-down COM, the
touch-down COM on the landing crouch (the absorbing path must start along
v_L).  :func:`plan` iterates that fixed point; the feet land on the target.
"""
from __future__ import annotations

from ..exceptions import FlipstudyValueError

import time
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.integrate import cumulative_trapezoid, trapezoid
from scipy.spatial.transform import Rotation

from ..edit.timing import slerp

from .ik import EX, heel_pitch, reach, solve_legs
from .model import SIDES, Jumper
from .muscles import MUSCLES, STRENGTH, parse_k
from .path import SCENES, estimate_path, gravity_vector, kinetic_energy
from .samples import sample_field
from .uneven import leg_asymmetry, pelvis_roll
from .windup import EPSILON, MAX_HEEL_PITCH, Choice, approach, choose

T_STAND, T_CROUCH, T_RECOVER, T_HOLD = 0.3, 0.8, 0.8, 0.4
TOUCHDOWN_EXTENSION = 0.96      # hip–ankle distance at touch-down / leg length
TAKEOFF_LEAN = np.radians(10.0)  # upper body leaning into the jump at take-off
RAY_TOLERANCE = 5e-4            # m: a sole this close to the surface under it touches it
IK_STOP = 2e-4                  # m: CCD stop distance for the feet on the ground


# ------------------------------------------------------------------ scenes
@dataclass(frozen=True)
class Box:
    """An axis-aligned box (metres): corners ``lo`` and ``hi``."""

    lo: tuple
    hi: tuple

    def contains(self, pts: np.ndarray, margin: float = 0.0) -> np.ndarray:
        p = np.asarray(pts, float)
        return np.all((p > np.asarray(self.lo) + margin) & (p < np.asarray(self.hi) - margin), axis=-1)

    def to_list(self) -> list:
        return [list(map(float, self.lo)), list(map(float, self.hi))]


@dataclass(frozen=True)
class Scene:
    """Where the jump starts and ends and what stands around: ``start`` and
    ``target`` are the feet's midpoint (between the ankles, on the surface)."""

    name: str
    start: tuple
    target: tuple
    boxes: tuple = ()
    tuck: float = 0.3
    t_air: float = 0.5
    t_windup: float = 0.2

    def surface(self, xz: np.ndarray) -> np.ndarray:
        """Height (N,) of the surface under ground points (N,2) x, z: the
        highest box top containing them, else the floor (0)."""
        xz = np.atleast_2d(xz)
        h = np.zeros(xz.shape[0])
        for b in self.boxes:
            m = ((xz[:, 0] >= b.lo[0]) & (xz[:, 0] <= b.hi[0]) &
                 (xz[:, 1] >= b.lo[2]) & (xz[:, 1] <= b.hi[2]))
            h = np.where(m, np.maximum(h, b.hi[1]), h)
        return h


def make_scene(name: str = "forward", distance: float | None = None, box_height: float | None = None,
               target=None) -> Scene:
    """The scenes of Chapter 5.

    ``forward``  jump ``distance`` (1.0 m) along +Z (the facing direction);
    ``sideways`` jump ``distance`` (1.0 m) to the right (−X) without turning;
    ``box``      onto a box ``box_height`` (0.5 m) high, 1 m wide, 0.8 m deep,
                 its front 0.5 m ahead of the ankles (Fig. 5.2 puts it "0.75 m
                 in front"), landing 0.8 m ahead on its top; thrust 0.15 s
                 (with 0.2 s the 0.75 m box needs a crouch deeper than the
                 balanced region allows);
    ``over``     from standing on a 1 m box, over a 1.4 m obstacle (0.2 m
                 deep, 1.0–1.2 m ahead), landing on the floor 2.4 m ahead
                 (Fig. 5.1); flight 0.9 s (a 0.5 s flight cannot clear it).

    ``target`` (x, y, z) overrides the landing point (y must be the height of
    the surface there)."""
    if name not in SCENES:
        raise FlipstudyValueError(f"scene: expected one of {', '.join(SCENES)}, got {name!r}")
    if distance is not None and not (np.isfinite(distance) and distance > 0):
        raise FlipstudyValueError(f"distance: expected a positive number of metres, got {distance!r}")
    if name == "forward":
        sc = Scene("forward", (0.0, 0.0, 0.0), (0.0, 0.0, float(distance or 1.0)), tuck=0.8)
    elif name == "sideways":
        sc = Scene("sideways", (0.0, 0.0, 0.0), (-float(distance or 1.0), 0.0, 0.0), tuck=0.8)
    elif name == "box":
        h = float(0.5 if box_height is None else box_height)
        if not (0.1 <= h <= 1.2):
            raise FlipstudyValueError(f"box_height: expected 0.1–1.2 m, got {box_height!r}")
        sc = Scene("box", (0.0, 0.0, 0.0), (0.0, h, 0.8), (Box((-0.5, 0.0, 0.5), (0.5, h, 1.3)),),
                   tuck=1.0, t_windup=0.15)
    else:
        sc = Scene("over", (0.0, 1.0, 0.0), (0.0, 0.0, 2.4),
                   (Box((-0.5, 0.0, -0.6), (0.5, 1.0, 0.35)), Box((-0.6, 0.0, 1.0), (0.6, 1.4, 1.2))),
                   tuck=1.0, t_air=0.9)
    if target is not None:
        t = np.asarray(target, float)
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise FlipstudyValueError(f"to: expected X,Y,Z in metres, got {target!r}")
        sc = Scene(sc.name, sc.start, tuple(t), sc.boxes, sc.tuck, sc.t_air, sc.t_windup)
    _check_surface(sc, "start", sc.start)
    _check_surface(sc, "to", sc.target)
    return sc


def _check_surface(sc: Scene, what: str, p) -> None:
    h = float(sc.surface(np.array([[p[0], p[2]]]))[0])
    if abs(h - p[1]) > 0.01:
        raise FlipstudyValueError(f"{what}: there is no surface at height {p[1]:g} m under x={p[0]:g}, "
                         f"z={p[2]:g} in the {sc.name!r} scene (the surface there is at {h:g} m); "
                         f"give Y = {h:g}" + (" or use --scene box" if sc.name != "box" else ""))


# ------------------------------------------------------------------- plan
@dataclass
class Plan:
    """The consistent plan of a jump (world coordinates)."""

    path: object               # JumpPath: v0, a, displacement (take-off → touch-down COM)
    windup: Choice
    landing: Choice
    crouch_pelvis: np.ndarray
    crouch_com: np.ndarray
    crouch_lean: np.ndarray
    approach: object
    takeoff_com: np.ndarray
    touchdown_com: np.ndarray
    touchdown_pelvis: np.ndarray
    touchdown_lean: np.ndarray
    stop_pelvis: np.ndarray
    stop_com: np.ndarray
    stop_lean: np.ndarray
    absorb_time: float
    iterations: int


def _pose(jumper, pelvis, lean, feet, pitch=None, warm=None, roll=None):
    """Legs solved for pelvis positions (N,3) with leans (N,2); returns (quats,
    stance); ``roll`` (N,): the pelvis's roll (:func:`.uneven.pelvis_roll`)."""
    pelvis = np.atleast_2d(pelvis)
    N = pelvis.shape[0]
    Q = jumper.rest_quats(N)
    lq = jumper.lean_quats(np.broadcast_to(np.atleast_2d(lean), (N, 2)))
    Q[:, jumper.idx["spine"]] = lq
    Q[:, jumper.idx["spine1"]] = lq
    st = solve_legs(jumper, pelvis, Q, {s: np.broadcast_to(feet[s], (N, 3)) for s in SIDES}, pitch, warm,
                    stop=IK_STOP, roll=roll)
    return st.quats, st


def _balanced(jumper, pelvis, feet, centre, k, required):
    """Balance PD at a fixed pelvis (the landing crouch): lean and COM."""
    ap = approach(jumper, pelvis, pelvis, feet, k, 0.0, centre)
    return ap.lean[-1], ap.com[-1]


def _touchdown(jumper, feet1, F1, delta, lean):
    """Pelvis of the touch-down pose: ``delta`` (2,) horizontal offset from the
    feet's midpoint, height such that the legs are TOUCHDOWN_EXTENSION of their
    length; and its COM."""
    L = TOUCHDOWN_EXTENSION * (jumper.thigh + jumper.shank)
    dh = float(np.hypot(*delta))
    if dh >= 0.95 * L:
        raise FlipstudyValueError("target unreachable: the landing needs the feet "
                         f"{dh:.2f} m ahead of the hips; use a longer --air or a shorter jump")
    y = F1[1] + jumper.ankle_height + np.sqrt(L ** 2 - dh ** 2) - jumper.hip_offset["l"][1]
    p = np.array([F1[0] + delta[0], y, F1[2] + delta[1]])
    Q, st = _pose(jumper, p, lean, feet1)
    return p, jumper.com(p[None], Q)[0]


def plan(jumper: Jumper, scene: Scene, k, t_air: float, t_windup: float, g, max_iter: int = 12) -> Plan:
    """Solve the jump's fixed point (see the module docstring)."""
    field_ = sample_field(jumper, k=k)                # uneven legs: the pelvis rolls in a crouch
    gv = gravity_vector(g)
    F0, F1 = np.asarray(scene.start, float), np.asarray(scene.target, float)
    feet0, feet1 = jumper.feet(F0), jumper.feet(F1)
    targets = field_.balanced(k).target           # balance targets relative to the feet, per sample
    up = np.array([0.0, 1.0, 0.0])
    m = jumper.mass
    # first guess: the COM travels ~0.78 of the feet's horizontal displacement
    # (it takes off ahead of the feet and lands behind them) and ~8 cm less high
    d0 = (F1 - F0) * np.array([0.78, 1.0, 0.78]) - np.array([0.0, 0.08, 0.0])
    path = estimate_path(d0, t_air, t_windup, gv)
    v0 = path.v0
    # COM − pelvis of an extended take-off pose (standing legs, leaning into the jump)
    def takeoff_offset(v):
        d = v[[0, 2]] / max(np.hypot(*v[[0, 2]]), 1e-9)
        lean = TAKEOFF_LEAN * np.array([d[1], -d[0]])
        Q = jumper.rest_quats(1)
        Q[0, jumper.idx["spine"]] = Q[0, jumper.idx["spine1"]] = jumper.lean_quats(lean[None])[0]
        return jumper.com(np.zeros((1, 3)), Q)[0]
    delta = np.zeros(2)
    c_td = None
    for it in range(1, max_iter + 1):
        travel = 0.5 * v0 * t_windup
        wc = choose(field_, k, kinetic_energy(m, v0), travel, takeoff_offset=takeoff_offset(v0))
        p_c = F0 + wc.pelvis
        c_c = p_c + field_.balanced(k).com_bal[wc.index] - wc.pelvis      # balanced by the upper body
        c_to = c_c + travel
        vL = v0 + gv * t_air
        lc = choose(field_, k, kinetic_energy(m, vL), None, best_effort=True)
        p_s = F1 + lc.pelvis
        c_s = p_s + field_.balanced(k).com_bal[lc.index] - lc.pelvis
        lean_td = np.zeros(2)
        for _ in range(30):
            p_td, c_td = _touchdown(jumper, feet1, F1, delta, lean_td)
            o = c_td - p_td
            vLy = (c_td[1] - c_to[1]) / t_air + gv[1] * t_air / 2.0
            if vLy >= -0.05:
                raise FlipstudyValueError(f"target unreachable: the feet would reach the surface at "
                                 f"y = {F1[1]:g} m still rising (vertical velocity {vLy:+.2f} m/s); "
                                 f"use a longer --air")
            T_a = 3.0 * (c_s[1] - c_td[1]) / vLy
            r = T_a / (3.0 * t_air)
            ch = (c_s[[0, 2]] + r * c_to[[0, 2]] - (T_a / 3.0) * gv[[0, 2]] * t_air / 2.0) / (1.0 + r)
            new = ch - F1[[0, 2]] - o[[0, 2]]
            if np.max(np.abs(new - delta)) < 1e-7:
                delta = new
                break
            delta = new
        c_td = np.array([ch[0], p_td[1] + o[1], ch[1]])
        v_new = (c_td - c_to) / t_air - gv * t_air / 2.0
        done = np.max(np.abs(v_new - v0)) < 1e-6
        v0 = v_new
        if done:
            break
    # the crouch approached by the PD controllers, and the landing crouch balanced
    start = F0 + up * jumper.standing_pelvis
    ap = approach(jumper, start, p_c, feet0, k, wc.required, F0[[0, 2]] + targets[wc.index])
    lean_s, c_s_exact = _balanced(jumper, p_s, feet1, F1[[0, 2]] + targets[lc.index], k, lc.required)
    c_c = ap.com[-1]
    c_to = c_c + 0.5 * v0 * t_windup
    # final v0 from the exact crouch COM (the approach balances to < 1 mm)
    v0 = (c_td - c_to) / t_air - gv * t_air / 2.0
    path = estimate_path(c_td - c_to, t_air, t_windup, gv)
    if kinetic_energy(m, path.v0) - ap.energy[-1] > EPSILON * kinetic_energy(m, path.v0):
        raise FlipstudyValueError("windup: the crouch reached does not store the energy of the final "
                         "take-off velocity; use a slightly shorter jump")
    vL = path.v_land
    T_a = 3.0 * (c_s_exact[1] - c_td[1]) / vL[1]
    return Plan(path, wc, lc, p_c, c_c, ap.lean[-1], ap, c_to, c_td, p_td, lean_td, p_s, c_s_exact,
                lean_s, float(T_a), it)


# ---------------------------------------------------------------- motion
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
        Q, st = _pose(jumper, root, lean, ankles, pitch, roll=roll)
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


@dataclass
class JumpResult:
    clip: object
    plan: Plan
    report: dict = field(default_factory=dict)


def jump(target=None, *, scene: str | Scene = "forward", t_air: float | None = None,
         t_windup: float | None = None,
         k="global-normal", strength: float = STRENGTH, g=9.81, mass: float = 70.0, height: float = 1.75,
         fps: float = 120.0, crouch_time: float = T_CROUCH, check: bool = True) -> JumpResult:
    """A standing jump to ``target`` (the feet's landing midpoint, metres; default
    the scene's) by the energy-based controller, as a clip.

    ``k``: a Table 5.1 preset name, one number or six (left hip, knee, ankle,
    right hip, knee, ankle), in the thesis's units; the springs used are
    ``strength`` × k (default :data:`STRENGTH`; ``strength=1`` is the thesis's
    literal constants, which with the corrected angle cannot store a 1 m jump).
    ``t_air`` defaults to the scene's (0.5 s; 0.9 s for ``over``).

    Raises ``ValueError`` naming the parameter for bad input and saying what
    to change for an unreachable target."""
    t0 = time.perf_counter()
    sc = scene if isinstance(scene, Scene) else make_scene(scene, target=target)
    if isinstance(scene, Scene) and target is not None:
        t = np.asarray(target, float)
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise FlipstudyValueError(f"to: expected X,Y,Z in metres, got {target!r}")
        sc = replace(scene, target=tuple(t))
        _check_surface(sc, "to", sc.target)
    t_air = sc.t_air if t_air is None else t_air
    t_windup = sc.t_windup if t_windup is None else t_windup
    for name, v in (("air", t_air), ("windup", t_windup), ("crouch_time", crouch_time)):
        if not (isinstance(v, (int, float, np.number)) and np.isfinite(v) and v > 0):
            raise FlipstudyValueError(f"{name}: expected a positive time in seconds, got {v!r}")
    if not (isinstance(fps, (int, float, np.number)) and np.isfinite(fps) and 30 <= fps <= 1000):
        raise FlipstudyValueError(f"fps: expected 30–1000 frames per second, got {fps!r}")
    if not (np.isfinite(strength) and strength > 0):
        raise FlipstudyValueError(f"strength: expected a positive factor on k, got {strength!r}")
    k_table = parse_k(k)
    k_eff = k_table * float(strength)
    jumper = Jumper(height, mass)
    gv = gravity_vector(g)
    pl = plan(jumper, sc, k_eff, float(t_air), float(t_windup), gv)
    clip, rep = _build(jumper, sc, pl, k_eff, float(fps), float(crouch_time), check)
    rep.update({"k": k_table.tolist(), "k_used": k_eff.tolist(), "strength": float(strength),
                "build_s": time.perf_counter() - t0})
    clip.meta.update(rep)
    return JumpResult(clip, pl, rep)


def _build(jumper: Jumper, sc: Scene, pl: Plan, k, fps: float, T_c: float, check: bool = True):
    path = pl.path
    t_w, t_air = path.t_windup, path.t_air
    gv = path.g
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
    Qw, st_w = _pose(jumper, pel, lean, feet0, roll=roll_w)
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
    Q_td, _ = _pose(jumper, pl.touchdown_pelvis, pl.touchdown_lean, feet1)
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
    Qr, st_r = _pose(jumper, pel, lean, feet1, roll=roll_s * (1 - w[:, 0]) if c else None)
    root[m], Q[m] = pel, Qr
    # the whole motion, checked
    i_to = int(np.ceil(t_to * fps - 1e-9))
    i_td = int(np.ceil(t_td * fps - 1e-9))
    meta = {"name": f"jump_{sc.name}", "source": "control", "scene": sc.name,
            "start": list(map(float, F0)), "target": list(map(float, F1)),
            "boxes": [b.to_list() for b in sc.boxes], "g": float(-gv[1]),
            "total_mass": jumper.mass, "height": jumper.height,
            "takeoff_s": float(t_to), "touchdown_s": float(t_td), "takeoff": i_to, "touchdown": i_td,
            "windup_frames": [int(np.ceil(t_c0 * fps)), int(np.ceil(t_c1 * fps)) - 1],
            "thrust_frames": [int(np.ceil(t_c1 * fps)), i_to - 1],
            "t_air": t_air, "t_windup": t_w, "crouch_time": T_c, "absorb_s": float(T_a),
            "v0": path.v0.tolist(), "a": path.a.tolist(), "displacement": path.displacement.tolist(),
            "v_land": path.v_land.tolist(),
            "E_k": kinetic_energy(jumper.mass, path.v0), "E_el_crouch": float(ap.energy[-1]),
            "E_land": kinetic_energy(jumper.mass, path.v_land), "E_el_landing": pl.landing.energy,
            "landing_energy_met": pl.landing.satisfied,
            "crouch_pelvis": pl.crouch_pelvis.tolist(), "crouch_lean_deg": np.degrees(pl.crouch_lean).tolist(),
            "candidates": pl.windup.candidates, "windup_iterations": K,
            "energy_met_at_iteration": ap.energy_met_at, "plan_iterations": pl.iterations,
            "ik_error_mm": float(1000 * max(st_w.error.max(), st_th.error.max(), st_ab.error.max(),
                                            st_r.error.max())),
            "muscles": list(MUSCLES), "warnings": []}
    clip = jumper.clip(root, Q, fps, meta)
    rep = _check(jumper, sc, clip, i_to, i_td, feet0, feet1, F1) if check else {}
    return clip, rep


def _sole_points(jumper, clip):
    """(F,6,3) heel, ball and toe tip of both feet."""
    j = jumper
    pts, loc = [], []
    for s in SIDES:
        a, t = j.idx[f"ankle_{s}"], j.idx[f"toe_{s}"]
        pts += [a, t, t]
        loc += [np.array([0.0, -j.ankle_height, -j.heel_back]), np.zeros(3), j.toe_tip]
    return clip.points(np.array(pts), np.array(loc))


def _check(jumper, sc, clip, i_to, i_td, feet0, feet1, F1) -> dict:
    """Ray casts for contact, collisions with boxes, foot motion in the windup,
    landing error."""
    soles = _sole_points(jumper, clip)
    F = clip.num_frames
    xz = soles[..., [0, 2]].reshape(-1, 2)
    gap = soles[..., 1] - sc.surface(xz).reshape(F, -1)
    # contact: the first frame after take-off where a ray down from a sole point
    # meets the surface under it (within RAY_TOLERANCE)
    after = np.arange(F) > i_to
    hit = np.nonzero(after & (gap.min(axis=1) <= RAY_TOLERANCE))[0]
    td_detected = int(hit[0]) if hit.size else None
    if td_detected is None or td_detected != i_td:
        raise FlipstudyValueError(f"landing: the feet meet a surface at frame {td_detected}, not at the planned "
                         f"touch-down {i_td}; the jump hits something: use a longer --air")
    below = float(gap.min())
    # collisions in flight: body points inside a box
    P = clip.joint_positions()
    E = clip.end_site_positions()
    pts = np.concatenate([P, E, soles], axis=1)[i_to:i_td]
    clear = np.inf
    for b in sc.boxes:
        if np.any(b.contains(pts, margin=0.005)):
            fr = i_to + int(np.nonzero(b.contains(pts, 0.005).any(1))[0][0])
            raise FlipstudyValueError(f"the jump hits the box {b.to_list()} at frame {fr}; use a longer --air, "
                             f"another target or --scene")
        top = b.hi[1]
        if top <= F1[1] + 1e-9 and b.contains(np.array([F1[0], top - 0.01, F1[2]])):
            continue                                      # the box landed on: the ray casts check it
        xzin = ((pts[..., 0] >= b.lo[0]) & (pts[..., 0] <= b.hi[0]) &
                (pts[..., 2] >= b.lo[2]) & (pts[..., 2] <= b.hi[2]))
        if xzin.any():
            clear = min(clear, float((pts[..., 1][xzin] - top).min()))
    # windup: feet still (every sole point); thrust: the balls of the feet still
    w0, w1 = clip.meta["windup_frames"]
    ws = soles[w0:w1 + 1]
    foot_motion = float(np.linalg.norm(ws - ws[:1], axis=-1).max())
    th = soles[w1 + 1:i_to][:, [1, 4]]
    ball_motion = float(np.linalg.norm(th - soles[w0][None, [1, 4]], axis=-1).max()) if len(th) else 0.0
    ank = P[i_td, [jumper.idx["ankle_l"], jumper.idx["ankle_r"]]].mean(0)
    land = np.array([ank[0], soles[i_td, :, 1].mean(), ank[2]])
    return {"touchdown_detected": td_detected, "lowest_sole_gap_m": below,
            "obstacle_clearance_m": None if not np.isfinite(clear) else clear,
            "windup_foot_motion_m": foot_motion, "thrust_ball_motion_m": ball_motion,
            "windup_lowest_sole_m": float(gap[w0:w1 + 1].min()),
            "landing_point": land.tolist(), "landing_error_m": float(np.linalg.norm(land - F1))}


__all__ = ["STRENGTH", "SCENES", "Box", "Scene", "make_scene", "Plan", "plan", "JumpResult", "jump"]
