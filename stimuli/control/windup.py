"""Windup by energy (Ooi 2016, 3.6): the sample field, the choice of a crouch
and its approach by the PD controller.

**Sample field.**  Pelvis positions on a regular grid over the balanced region
— above the support polygon's bounding rectangle, from low down up to the
standing pelvis height — each with both legs solved by CCD (feet flat where
they stand), its six spring displacements, its COM (the project's de Leva
body, upper body upright) and the balance error.  Equal legs crouch with the
pelvis level; uneven legs (Table 5.1's uneven trials) with the pelvis rolled
down on the stronger side, each leg's compression following its own spring up
to 8° of pelvic obliquity (which crouches deeper than ~6 cm reach), so that
the stronger leg bends more (:func:`pelvis_roll` gives the physics).  The
geometry depends on k only
through that roll (the legs' asymmetry): the field is computed once per jumper
(height, mass), grid and asymmetry and cached; the energies E_el = Σ ½ k_i s_i²
are computed once per k and cached on the field.

**Choice.**  Candidates satisfy E_k − E_el ≤ ε E_k (ε = 0.05), bend the
knees at least as far as the thesis's minimum limb usage (utilisation ≥ ε),
keep the COM over the support polygon (its balance target the centre of
pressure of the legs' springs, :func:`balance_target`), and leave room for
the thrust: after the planned ½ v0 t_windup of travel the legs must be
extended (utilisation below the thesis's 0.1) yet still reach the ground, on
the balls of the feet if need be.  Of those, the one with the least balance error is chosen — the
error left once the upper body has leaned as far as its limits allow (the
field stores that lean; in 5 mm bins, then the smaller lean, then the
shallower crouch).

**Approach.**  The windup PD controller (k_p = k_d = 0.25, Table 3.2) moves
the pelvis toward the chosen sample, u(i) = k_p e(i−1) + k_d (e(i−1) − e(i−2)),
the legs solved by CCD each iteration, while the balance PD controller bends
the upper body; it stops when the pelvis is within 1 mm of the sample, the
energy criterion holds and the balance error is below 1 mm.  The pelvis of
uneven legs rolls on the way down in proportion to the depth, reaching the
sample's roll there.

**Energy assignment (3.6.2).**  :func:`assign_energy` solves the problem the
sampling approximates directly with ``scipy.optimize`` (SLSQP over the pelvis
position, the same constraints), for comparison with the sampled answer.
"""
from __future__ import annotations

from ..exceptions import FlipstudyValueError

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from .balance import balance_error, inside, lean_limits, pd_lean, polygon_centre, support_polygon
from .ik import heel_pitch, reach, solve_legs
from .model import SIDES, Jumper
from .muscles import spring_displacement, utilisation

EPSILON = 0.05                 # the thesis's error allowance
KP_WINDUP = 0.25               # Table 3.2
KD_WINDUP = 0.25
EXTENDED_UTILISATION = 0.1     # 3.6.3: fully extended below this utilisation
MAX_HEEL_PITCH = np.radians(60.0)
SPACING = (0.02, 0.01, 0.02)   # grid of the field (x, y, z), metres
LOWEST_PELVIS = 0.35           # fraction of the standing pelvis height
BALANCE_BIN = 0.005            # m: balance errors this close count as equal (then the smaller lean)
REACH_MARGIN = 0.012           # m kept in hand when testing the thrust's reach (the estimate's error)
BEST_EFFORT_BALANCE = 0.02     # m: a best-effort (landing) crouch is chosen among those balanced this well
PELVIS_ROLL_LIMIT = np.radians(8.0)   # the pelvis's frontal tilt (obliquity, a hip hike) in a crouch


@dataclass
class Balanced:
    """The field balanced for one set of spring constants: per sample the
    balance target (N,2) (the centre of pressure of the legs' springs, over
    the stronger leg, see :func:`balance_target`), the upright error from it
    (N,2), the best lean within limits (N,2), the COM with it (N,3), the error
    left (N,2) and whether that COM is over the support polygon (2 cm inside)."""

    target: np.ndarray
    balance: np.ndarray
    lean: np.ndarray
    com_bal: np.ndarray
    residual: np.ndarray
    inside: np.ndarray


@dataclass
class SampleField:
    """Pelvis samples relative to the feet (their midpoint on the surface at the
    origin, standing stance).  Arrays (N,...)."""

    jumper: Jumper
    pelvis: np.ndarray      # (N,3)
    ok: np.ndarray          # (N,) legs reach, within joint limits
    s: np.ndarray           # (N,6) spring displacements, m (order of MUSCLES)
    theta: np.ndarray       # (N,6) effective angles between the bones, rad
    com: np.ndarray         # (N,3) COM, upper body upright
    balance: np.ndarray     # (N,2) COM − support-polygon centre (x, z), upper body upright
    polygon: np.ndarray     # (K,2)
    centre: np.ndarray      # (2,)
    spacing: tuple
    lean_table: tuple       # (leans (L,2), COM shifts (L,3)): the upper body's effect
    roll: np.ndarray | None = None        # (N,) pelvis roll, rad (see :func:`pelvis_roll`)
    compression: np.ndarray | None = None  # (N,2) each hip's drop below standing (left, right), m
    asymmetry: float = 0.0                # the legs' c of :func:`leg_asymmetry` the field is for
    seconds: float = 0.0
    _energy: dict = field(default_factory=dict, repr=False)
    _balanced: dict = field(default_factory=dict, repr=False)

    @property
    def size(self) -> int:
        return self.pelvis.shape[0]

    def energy(self, k) -> np.ndarray:
        """(N,) elastic energy Σ ½ k_i s_i² (J) for spring constants k (6,);
        computed once per k."""
        key = _key(k)
        if key not in self._energy:
            self._energy[key] = 0.5 * (self.s ** 2) @ np.asarray(key)
        return self._energy[key]

    def balanced(self, k) -> Balanced:
        """The balance of every sample for spring constants k (computed once per k)."""
        key = _key(k)
        if key not in self._balanced:
            target = balance_target(self.jumper, np.asarray(key), compression=self.compression)
            target = np.broadcast_to(target, (self.size, 2))
            b = self.com[:, [0, 2]] - target
            L, D = self.lean_table
            best = np.empty(b.shape[0], int)
            for a in range(0, b.shape[0], 2048):
                r = b[a:a + 2048, None, :] + D[None, :, [0, 2]]
                cost = np.einsum("nlc,nlc->nl", r, r) + 1e-8 * np.einsum("lc,lc->l", L, L)[None]
                best[a:a + 2048] = np.argmin(cost, axis=1)
            com_bal = self.com + D[best]
            self._balanced[key] = Balanced(target, b, L[best], com_bal, com_bal[:, [0, 2]] - target,
                                           inside(self.polygon, com_bal[:, [0, 2]], margin=0.02))
        return self._balanced[key]

    def max_energy(self, k) -> float:
        E = self.energy(k)
        m = self.ok & self.balanced(k).inside
        return float(E[m].max()) if m.any() else 0.0


def _key(k) -> tuple:
    return tuple(float(v) for v in np.asarray(k, float).reshape(6))


def balance_target(jumper: Jumper, k, centre=(0.0, 0.0), compression=None) -> np.ndarray:
    """Where the balance controller puts the COM (x, z), relative to the feet's
    midpoint: the centre of pressure of the legs' springs.  Each leg is a
    spring of stiffness K = k_hip + k_knee + k_ankle compressed by its hip's
    drop δ below standing (``compression`` (N,2), left and right); it pushes
    with F = K δ, and the COM must be over the point where those forces act.
    Without ``compression`` (or where the legs stand straight) the legs are
    taken as compressed alike, F ∝ K: (2,).  Equal legs: the support
    polygon's centre (the thesis); a stronger leg draws the COM over itself
    and so carries more load — the more so as it bends more (:func:`pelvis_roll`)."""
    k = np.asarray(k, float).reshape(6)
    K = np.array([k[:3].sum(), k[3:].sum()])
    feet = jumper.feet()
    mid = np.array([jumper.foot_corners(feet[s])[:, [0, 2]].mean(0) for s in SIDES])
    if compression is None:
        return (K[:, None] * mid).sum(0) / K.sum() + np.asarray(centre)
    d = np.atleast_2d(np.asarray(compression, float))
    w = K[None] * (np.maximum(d, 0.0) + 1e-6)                 # F = K δ (straight legs: F ∝ K)
    return (w @ mid) / w.sum(1, keepdims=True) + np.asarray(centre)[None]


def leg_asymmetry(k) -> float:
    """c = (K_r − K_l) / (K_r + K_l) of the legs' stiffnesses K (each the sum of
    its hip, knee and ankle springs): 0 for equal legs, > 0 when the right
    leg is the stronger.  Table 5.1's uneven presets: ±0.2."""
    k = np.asarray(k, float).reshape(6)
    Kl, Kr = k[:3].sum(), k[3:].sum()
    return float((Kr - Kl) / (Kr + Kl))


def pelvis_roll(jumper: Jumper, asymmetry: float, depth) -> np.ndarray:
    """(N,) roll of the pelvis (rad, about the forward axis Z; positive lowers
    the right hip) in a crouch ``depth`` (N,) metres below the standing
    pelvis height, for legs of asymmetry c (:func:`leg_asymmetry`).

    Why.  The legs are two springs in parallel under one body (here each a
    linear spring K in its hip's drop δ below standing).  A pelvis that only
    translates compresses both by the same δ, so the stiffer leg pushes
    harder (F = K δ) and carries more weight, but both knees bend alike.
    Statics ties the share of the weight to where the COM is, and that is the
    controller's choice, so it does not fix how the bend is shared: the
    crouch is the store of the take-off energy, E = Σ ½ K δ², and the jumper
    chooses it.  Per unit of bend a stiffer spring stores more (dE/dδ = K δ):
    lowering the hip of the stronger leg by a and raising the weaker one's by
    a changes the energy of a crouch of depth D by (K_s − K_w) D a +
    ½ (K_s + K_w) a², a gain at first order, so the same energy is stored in
    a shallower crouch (which the choice prefers); the opposite tilt — the
    weaker leg sagging, as equal forces F_l = F_r would make it — loses
    energy (−½ (K_s + K_w) c² D² at a = −c D) and puts the load on the leg
    least able to return it.  So the pelvis rolls
    down on the stronger side.  The energy gives the direction, not the
    amount (the gain keeps growing with the tilt); the amount is a rule: each
    leg's compression follows its own spring, δ_i ∝ K_i, i.e. δ_s,w =
    D (1 ± c), as far as the pelvis's obliquity allows
    (:data:`PELVIS_ROLL_LIMIT`, reached below D ≈ 6 cm for c = 0.2).  The
    stronger leg bends more and, its force K δ larger, carries still more of
    the weight (the balance target follows, :func:`balance_target`); the
    weaker leg straightens — the thesis's "dangling" weaker leg (5.4).  Equal
    legs (c = 0): no roll, mirror-image legs.  Standing (D ≤ 0): no roll."""
    D = np.maximum(np.atleast_1d(np.asarray(depth, float)), 0.0)
    if asymmetry == 0.0:
        return np.zeros(D.shape)
    w = abs(float(jumper.hip_offset["r"][0]))
    a = np.arcsin(np.clip(abs(asymmetry) * D / w, 0.0, 1.0))
    return np.sign(asymmetry) * np.minimum(a, PELVIS_ROLL_LIMIT)


def hip_compression(jumper: Jumper, roll) -> np.ndarray:
    """(N,2) how far a roll (N,) lowers each hip (left, right) relative to the
    pelvis's centre (m; negative: raised) — add the crouch depth for each
    hip's drop below standing, the leg's compression δ."""
    r = np.atleast_1d(np.asarray(roll, float))
    R = Rotation.from_rotvec(r[:, None] * np.array([0.0, 0.0, 1.0]))
    return np.stack([-(R.apply(jumper.hip_offset[s])[:, 1] - jumper.hip_offset[s][1]) for s in SIDES], 1)


_CACHE: dict = {}


def sample_field(jumper: Jumper, spacing=SPACING, k=None) -> SampleField:
    """The sample field of a jumper (cached per height, mass and spacing, and
    per the legs' asymmetry of ``k``: uneven legs crouch with the pelvis
    rolled, :func:`pelvis_roll`; equal legs or no ``k``: upright)."""
    import time
    c = 0.0 if k is None else round(leg_asymmetry(k), 9)
    key = (round(jumper.height, 9), round(jumper.mass, 9), tuple(spacing)) + ((c,) if c else ())
    if key in _CACHE:
        return _CACHE[key]
    t0 = time.perf_counter()
    feet = jumper.feet()
    corners = np.concatenate([jumper.foot_corners(feet[s]) for s in SIDES])
    poly = support_polygon(corners)
    lo, hi = corners.min(0), corners.max(0)
    dx, dy, dz = spacing
    xs = _axis(lo[0], hi[0], dx)
    zs = _axis(lo[2], hi[2], dz)
    ys = np.arange(jumper.standing_pelvis, LOWEST_PELVIS * jumper.standing_pelvis - 1e-9, -dy)[::-1]
    X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
    P = np.stack([X.ravel(), Y.ravel(), Z.ravel()], 1)
    depth = jumper.standing_pelvis - P[:, 1]
    roll = pelvis_roll(jumper, c, depth)
    st = solve_legs(jumper, P, jumper.rest_quats(P.shape[0]), feet, roll=roll)
    pos = jumper.positions(P, st.quats)
    theta = jumper.muscle_angles(pos)
    com = jumper.com(P, st.quats)
    centre = polygon_centre(poly)
    f = SampleField(jumper, P, st.ok, spring_displacement(theta), theta, com,
                    balance_error(com, centre), poly, centre, tuple(spacing), _lean_table(jumper),
                    roll, depth[:, None] + hip_compression(jumper, roll), c)
    f.seconds = time.perf_counter() - t0
    _CACHE[key] = f
    return f


def _lean_table(jumper: Jumper, step: float = np.radians(2.0)):
    """Leans on a grid within the limits and the COM shift each causes.  The
    upper body hangs from the pelvis, so the shift of a lean is the same for
    every leg pose: one table, one FK batch."""
    lo, hi = lean_limits()
    gx = np.arange(lo[0], hi[0] + 1e-9, step)
    gz = np.arange(lo[1], hi[1] + 1e-9, step)
    L = np.stack(np.meshgrid(gx, gz, indexing="ij"), -1).reshape(-1, 2)
    Q = jumper.rest_quats(L.shape[0])
    lq = jumper.lean_quats(L)
    Q[:, jumper.idx["spine"]] = lq
    Q[:, jumper.idx["spine1"]] = lq
    root = np.zeros((L.shape[0], 3))
    D = jumper.com(root, Q) - jumper.com(root[:1], jumper.rest_quats(1))
    return L, D


def _axis(a: float, b: float, d: float) -> np.ndarray:
    """Samples every ``d`` over [a, b], symmetric about the middle, which is one."""
    half = int(np.floor((b - a) / (2 * d) + 1e-9))
    return 0.5 * (a + b) + d * np.arange(-half, half + 1)


def sample_field_naive(jumper: Jumper, spacing=SPACING, limit: int | None = None) -> dict:
    """The same field one sample at a time (the baseline of the benchmark): a
    Python loop over pelvis positions, CCD, FK and COM per sample, on the first
    ``limit`` samples (all by default).  Returns ``pelvis``, ``ok``, ``s``, ``com``."""
    f = sample_field(jumper, spacing)
    feet = jumper.feet()
    ok, S, C = [], [], []
    P = f.pelvis if limit is None else f.pelvis[:limit]
    for p in P:
        st = solve_legs(jumper, p[None], jumper.rest_quats(1), feet)
        pos = jumper.positions(p[None], st.quats)
        S.append(spring_displacement(jumper.muscle_angles(pos))[0])
        C.append(jumper.com(p[None], st.quats)[0])
        ok.append(bool(st.ok[0]))
    return {"pelvis": P, "ok": np.array(ok), "s": np.array(S), "com": np.array(C)}


# ------------------------------------------------------------------ choice
@dataclass
class Choice:
    """The chosen sample and why."""

    index: int
    pelvis: np.ndarray            # relative to the feet
    energy: float                 # J
    required: float               # J (E_k)
    balance: float                # m
    candidates: int
    satisfied: bool               # the energy criterion holds (False: best effort, landing)


def thrust_ok(field: SampleField, travel: np.ndarray, takeoff_offset=None, subset=None, k=None) -> np.ndarray:
    """(N,) whether a thrust moving the COM by ``travel`` (3,) from each sample
    (balanced: COM over the support centre) ends with the legs extended and
    the feet still reaching the ground (heels raised up to 60° if need be).
    ``takeoff_offset`` (3,) is COM − pelvis of the take-off pose (default: the
    sample's own, i.e. the pelvis moves like the COM).  ``subset``: indices to
    test (the rest are False); ``k`` the springs whose balance is used."""
    j = field.jumper
    feet = j.feet()
    idx = np.arange(field.size) if subset is None else np.asarray(subset, int)
    bal = field.balanced(np.full(6, 1.0) if k is None else k)
    com = bal.com_bal[idx]
    off = (bal.com_bal[idx] - field.pelvis[idx] if takeoff_offset is None
           else np.asarray(takeoff_offset)[None])
    pelvis_to = com + np.asarray(travel)[None] - off
    L_ext = reach(j.thigh, j.shank, np.radians(2.0)) - REACH_MARGIN
    th_min = np.arccos(2 * EXTENDED_UTILISATION - 1.0)       # utilisation 0.1 ↔ 143°
    L_min = reach(j.thigh, j.shank, np.pi - th_min)
    ok = np.ones(idx.size, bool)
    for s in SIDES:
        hip = pelvis_to + j.hip_offset[s][None]
        d = np.linalg.norm(hip - feet[s][None], axis=1)
        ball = feet[s] + j.ball_offset
        ph = heel_pitch(hip, np.broadcast_to(ball, hip.shape), j.ball_offset, L_ext, MAX_HEEL_PITCH)
        ok &= (d >= L_min) & np.isfinite(ph)
    out = np.zeros(field.size, bool)
    out[idx] = ok
    return out


def choose(field: SampleField, k, required: float, travel=None, eps: float = EPSILON,
           best_effort: bool = False, takeoff_offset=None) -> Choice:
    """The least-balance-error sample with E_k − E_el ≤ ε E_k (and room for a
    thrust of ``travel`` when given).  ``best_effort``: when no sample stores
    enough, take the most energetic one (landings that must dissipate the rest)
    of those the upper body balances within :data:`BEST_EFFORT_BALANCE`,
    instead of raising ``ValueError``."""
    E = field.energy(k)
    bal = field.balanced(k)
    base = field.ok & bal.inside
    knee_use = np.minimum(utilisation(field.theta[:, 1]), utilisation(field.theta[:, 4]))
    usable = base & (knee_use >= eps)
    enough = required - E <= eps * required
    pre = usable & enough
    room = (thrust_ok(field, np.asarray(travel, float), takeoff_offset, np.nonzero(pre)[0], k)
            if travel is not None else np.ones(field.size, bool))
    cand = pre & room
    if not cand.any():
        if best_effort:
            # the most energetic of the well-balanced ones (the rolled field of
            # uneven legs stores most far off to the side, where the upper body
            # cannot balance the COM), else of all
            res = np.linalg.norm(bal.residual, axis=1)
            good = usable & (res <= BEST_EFFORT_BALANCE)
            i = int(np.argmax(np.where(good if good.any() else usable, E, -np.inf)))
            return Choice(i, field.pelvis[i].copy(), float(E[i]), float(required),
                          float(np.linalg.norm(bal.residual[i])), 0, False)
        emax = float(E[usable].max()) if usable.any() else 0.0
        if emax < (1 - eps) * required:
            raise FlipstudyValueError(
                f"target unreachable: the jump needs E_k = {required:.0f} J but the muscles "
                f"(k = {', '.join(f'{v:g}' for v in np.asarray(k))}) store at most {emax:.0f} J in "
                f"a balanced crouch; use stronger muscles (--k / --strength), a shorter jump, or an "
                f"--air time nearer the cheapest one")
        if not pre.any():
            raise FlipstudyValueError(f"target unreachable: no balanced crouch stores {required:.0f} J")
        raise FlipstudyValueError(
            f"target unreachable: crouches storing {required:.0f} J exist, but none leaves room "
            f"for the thrust (the legs must extend over {np.linalg.norm(travel):.2f} m and keep the "
            f"feet on the ground); use another --windup time or a shorter jump")
    idx = np.nonzero(cand)[0]
    # the balance error the jumper is left with once the upper body has leaned
    # (what the balance controller cannot remove), then the smaller lean, then
    # the shallower crouch (nearer the rest pose)
    b = np.linalg.norm(bal.residual[idx], axis=1)
    order = np.lexsort((-field.pelvis[idx, 1], np.round(np.linalg.norm(bal.lean[idx], axis=1), 3),
                        np.floor(b / BALANCE_BIN)))
    i = int(idx[order[0]])
    return Choice(i, field.pelvis[i].copy(), float(E[i]), float(required), float(b[order[0]]),
                  int(idx.size), True)


# ---------------------------------------------------------------- approach
@dataclass
class Approach:
    """The windup controller's iterations: pelvis (K,3), lean (K,2), energy
    (K,), balance error (K,2), COM (K,3), leg quaternions (K,J,4), pelvis
    roll (K,) (uneven legs: growing in proportion to the depth, to the
    goal's :func:`pelvis_roll`)."""

    pelvis: np.ndarray
    lean: np.ndarray
    energy: np.ndarray
    balance: np.ndarray
    com: np.ndarray
    quats: np.ndarray
    roll: np.ndarray
    energy_met_at: int | None


def approach(jumper: Jumper, start: np.ndarray, goal: np.ndarray, feet: dict, k, required: float,
             centre: np.ndarray, eps: float = EPSILON, kp: float = KP_WINDUP, kd: float = KD_WINDUP,
             lean0=(0.0, 0.0), tol: float = 1e-3, max_iter: int = 300) -> Approach:
    """Run the windup PD controller from pelvis ``start`` to ``goal`` (world),
    the balance PD controller bending the upper body every iteration."""
    k = np.asarray(k, float)
    c = leg_asymmetry(k)
    floor = float(np.mean([feet[s_][1] for s_ in SIDES])) - jumper.ankle_height
    # the goal's roll, reached in proportion to the depth on the way down
    d_goal = jumper.standing_pelvis - (float(goal[1]) - floor)
    r_goal = float(pelvis_roll(jumper, c, d_goal)[0])
    p = np.asarray(start, float).copy()
    e_prev = goal - p
    lean = np.asarray(lean0, float).copy()
    b_prev = None
    rec = {n: [] for n in ("pelvis", "lean", "energy", "balance", "com", "quats", "roll")}
    met = None
    for i in range(max_iter + 1):
        Q = jumper.rest_quats(1)
        lq = jumper.lean_quats(lean[None])
        Q[0, jumper.idx["spine"]] = Q[0, jumper.idx["spine1"]] = lq[0]
        d = jumper.standing_pelvis - (p[1] - floor)
        roll = r_goal * float(np.clip(d / d_goal, 0.0, 1.0)) if r_goal else 0.0
        st = solve_legs(jumper, p[None], Q, feet, roll=np.array([roll]))
        pos = jumper.positions(p[None], st.quats)
        E = float(0.5 * (spring_displacement(jumper.muscle_angles(pos))[0] ** 2) @ k)
        com = jumper.com(p[None], st.quats)[0]
        b = balance_error(com, centre)[0]
        for n, v in (("pelvis", p.copy()), ("lean", lean.copy()), ("energy", E), ("balance", b),
                     ("com", com), ("quats", st.quats[0]), ("roll", roll)):
            rec[n].append(v)
        if met is None and required - E <= eps * required:
            met = i
        e = goal - p
        settled = np.linalg.norm(b) < tol or (i > 2 and np.max(np.abs(rec["lean"][-1] - rec["lean"][-2])) < 1e-5)
        if np.linalg.norm(e) < tol and settled and met is not None:
            break
        # windup PD: move the pelvis; balance PD: bend the upper body
        u = kp * e + kd * (e - e_prev)
        e_prev = e
        p = p + u
        lean = pd_lean(lean, b, b if b_prev is None else b_prev)
        b_prev = b
    else:
        raise FlipstudyValueError(f"windup: the PD controllers did not settle in {max_iter} iterations "
                         f"(pelvis error {np.linalg.norm(goal - p) * 1000:.1f} mm, balance error "
                         f"{np.linalg.norm(b) * 1000:.1f} mm, lean {np.degrees(lean).round(1).tolist()}°, "
                         f"energy {E:.0f} of {required:.0f} J)")
    return Approach(*(np.array(rec[n]) for n in ("pelvis", "lean", "energy", "balance", "com", "quats",
                                                  "roll")),
                    energy_met_at=met)


# --------------------------------------------------------- energy assignment
@dataclass
class Assignment:
    """The direct answer of :func:`assign_energy` beside the sampled one."""

    pelvis: np.ndarray
    energy: float
    balance: float                # m, upper body upright
    success: bool
    message: str
    sampled_pelvis: np.ndarray
    sampled_energy: float
    sampled_balance: float        # m, upper body upright
    qcqp_s: np.ndarray            # the literal QCQP's answer (6,) spring displacements
    qcqp_energy: float

    @property
    def distance(self) -> float:
        """Distance between the direct and the sampled pelvis positions (m)."""
        return float(np.linalg.norm(self.pelvis - self.sampled_pelvis))


def assign_energy(field: SampleField, k, required: float, choice: Choice, travel=None,
                  eps: float = EPSILON) -> Assignment:
    """Solve the energy assignment problem (3.6.2) directly with scipy.optimize.

    Two forms.  (1) The thesis's QCQP literally: minimise sᵀQs subject to
    sᵀ(−Q)s ≤ −2(1−ε)E_k, Q = diag(k), bounds 0 ≤ s_i ≤ 2r (the joint range):
    the least stored energy that still suffices — every point of the ellipsoid
    shell is optimal, so its answer says nothing about the pose.  (2) What the
    sampling actually solves: over the pelvis position p (feet fixed, legs by
    CCD), minimise the balance error |b(p)|² subject to E_el(p) ≥ (1−ε)E_k,
    the thrust's room (legs extended after ``travel``, feet reaching) and the
    balanced box, by SLSQP from the sampled answer."""
    j = field.jumper
    k = np.asarray(k, float)
    feet = j.feet()
    # (1) the literal QCQP, in y = s / 2r ∈ [0, 1] and energies relative to the target
    r = 0.05
    w = k * (2 * r) ** 2 / (2 * (1 - eps) * required)     # ½ sᵀQs / ((1−ε)E_k) = Σ w y²
    y0 = np.full(6, min(1.0, 1.2 / np.sqrt(w.sum())))
    res1 = minimize(lambda y: float(w @ y ** 2), y0, jac=lambda y: 2 * w * y,
                    constraints=[{"type": "ineq", "fun": lambda y: float(w @ y ** 2) - 1.0,
                                  "jac": lambda y: 2 * w * y}],
                    bounds=[(0.0, 1.0)] * 6, method="SLSQP", options={"ftol": 1e-12})
    s_q = res1.x * 2 * r
    Q = np.diag(k)
    # (2) over the pelvis position
    L_min = reach(j.thigh, j.shank, np.pi - np.arccos(2 * EXTENDED_UTILISATION - 1.0))
    lo = field.pelvis.min(0)
    hi = field.pelvis.max(0)
    scale = 10.0   # decimetres: better-conditioned steps

    def state(x):
        p = np.asarray(x, float) / scale
        st = solve_legs(j, p[None], j.rest_quats(1), feet, iterations=200, stop=1e-5,
                        roll=pelvis_roll(j, field.asymmetry, j.standing_pelvis - p[1]))
        pos = j.positions(p[None], st.quats)
        E = float(0.5 * (spring_displacement(j.muscle_angles(pos))[0] ** 2) @ k)
        b = balance_error(j.com(p[None], st.quats), field.balanced(k).target[choice.index])[0]
        return p, E, b, float(st.error.max())

    def room(x):
        p = np.asarray(x, float) / scale
        if travel is None:
            return np.zeros(2)
        out = []
        for s in SIDES:
            hip = p + np.asarray(travel) + j.hip_offset[s]
            out.append(np.linalg.norm(hip - feet[s]) - L_min)
        return np.array(out)

    cons = [{"type": "ineq", "fun": lambda x: state(x)[1] / required - (1 - eps)},
            {"type": "ineq", "fun": lambda x: 2e-3 - state(x)[3]},
            {"type": "ineq", "fun": room}]
    x0 = choice.pelvis * scale
    res2 = minimize(lambda x: float(np.sum(state(x)[2] ** 2)) * 1e4, x0, method="SLSQP",
                    bounds=list(zip(lo * scale, hi * scale)), constraints=cons,
                    options={"maxiter": 60, "ftol": 1e-10, "eps": 1e-4})
    p, E, b, _ = state(res2.x)
    b_sampled = float(np.linalg.norm(field.balanced(k).balance[choice.index]))   # upright, like b(p)
    return Assignment(p, E, float(np.linalg.norm(b)), bool(res2.success), str(res2.message),
                      choice.pelvis.copy(), choice.energy, b_sampled, s_q,
                      float(0.5 * s_q @ Q @ s_q))
