"""Windup by energy (Ooi 2016, 3.6): the choice of a crouch from the sample
field (:mod:`.samples`) and its approach by the PD controller.

**Choice.**  Candidates satisfy E_k − E_el ≤ ε E_k (ε = 0.05), bend the
knees at least as far as the thesis's minimum limb usage (utilisation ≥ ε),
keep the COM over the support polygon (its balance target the centre of
pressure of the legs' springs, :func:`.uneven.balance_target`), and leave room for
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

The energy assignment problem the sampling approximates (3.6.2) is solved
directly in :mod:`.assignment`.
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

from dataclasses import dataclass

import numpy as np

from .balance import balance_error, pd_lean
from .ik import heel_pitch, reach, solve_legs
from .model import SIDES, Jumper
from .muscles import spring_displacement, utilisation
from .samples import SampleField
from .uneven import leg_asymmetry, pelvis_roll

EPSILON = 0.05                 # the thesis's error allowance
KP_WINDUP = 0.25               # Table 3.2
KD_WINDUP = 0.25
EXTENDED_UTILISATION = 0.1     # 3.6.3: fully extended below this utilisation
MAX_HEEL_PITCH = np.radians(60.0)
BALANCE_BIN = 0.005            # m: balance errors this close count as equal (then the smaller lean)
REACH_MARGIN = 0.012           # m kept in hand when testing the thrust's reach (the estimate's error)
BEST_EFFORT_BALANCE = 0.02     # m: a best-effort (landing) crouch is chosen among those balanced this well


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
           best_effort: bool = False, takeoff_offset=None, cheapest=None) -> Choice:
    """The least-balance-error sample with E_k − E_el ≤ ε E_k (and room for a
    thrust of ``travel`` when given).  ``best_effort``: when no sample stores
    enough, take the most energetic one (landings that must dissipate the rest)
    of those the upper body balances within :data:`BEST_EFFORT_BALANCE`,
    instead of raising ``ValueError``.  ``cheapest``: ``(t_air, E_k)`` of the air time
    that needs the least energy, named in the refusal.

    Parameters
    ----------
    field : SampleField
    k : ndarray, shape (6,)
    required : float
        E_k, J.
    travel, takeoff_offset : sequence of 3 float, optional
    eps : float
    best_effort : bool
    cheapest : tuple of float, optional

    Returns
    -------
    Choice

    Examples
    --------
    >>> from flipstudy.stimuli.control import STRENGTH, Jumper, parse_k, sample_field
    >>> k = parse_k("global-normal") * STRENGTH
    >>> f = sample_field(Jumper(), spacing=(0.03, 0.03, 0.03))
    >>> c = choose(f, k, 300.0)
    >>> c.satisfied, c.energy >= 0.95 * 300.0, c.candidates > 1
    (True, True, True)
    >>> choose(f, k, 1e5)
    Traceback (most recent call last):
    ...
    flipstudy.errors.FlipstudyValueError: target unreachable: the jump needs E_k = 100000 J ...
    """
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
                f"--air time nearer the cheapest one"
                + ("" if cheapest is None else
                   f" (--air {cheapest[0]:.2f}: E_k = {cheapest[1]:.0f} J"
                   + (", within reach)" if cheapest[1] <= emax / (1 - eps) else ", still out of reach)")))
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
    goal's :func:`.uneven.pelvis_roll`)."""

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

