"""The plan of a jump (Ooi 2016, 3.5–3.6): the crouch, the take-off, the
touch-down and the landing crouch, made to meet.

The take-off COM depends on the crouch, the crouch on the energy of v0, v0 on
the take-off and touch-down COM, the touch-down COM on the landing crouch (the
absorbing path must start along v_L).  :func:`plan` iterates that fixed point;
the feet land on the target.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flipstudy.errors import FlipstudyValueError
from .course import Course
from .ik import solve_legs
from .model import SIDES, Jumper
from .path import JumpPath, estimate_path, gravity_vector, kinetic_energy
from .samples import sample_field
from .windup import EPSILON, Approach, Choice, approach, choose

TOUCHDOWN_EXTENSION = 0.96      # hip–ankle distance at touch-down / leg length
TAKEOFF_LEAN = np.radians(10.0)  # upper body leaning into the jump at take-off
IK_STOP = 2e-4                  # m: CCD stop distance for the feet on the ground


@dataclass
class Plan:
    """The consistent plan of a jump (world coordinates)."""

    path: JumpPath             # v0, a, displacement (take-off → touch-down COM)
    windup: Choice
    landing: Choice
    crouch_pelvis: np.ndarray
    crouch_com: np.ndarray
    crouch_lean: np.ndarray
    approach: Approach
    takeoff_com: np.ndarray
    touchdown_com: np.ndarray
    touchdown_pelvis: np.ndarray
    touchdown_lean: np.ndarray
    stop_pelvis: np.ndarray
    stop_com: np.ndarray
    stop_lean: np.ndarray
    absorb_time: float
    iterations: int


def pose_legs(jumper, pelvis, lean, feet, pitch=None, warm=None, roll=None):
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
    Q, st = pose_legs(jumper, p, lean, feet1)
    return p, jumper.com(p[None], Q)[0]


def plan(jumper: Jumper, course: Course, k, t_air: float, t_windup: float, g, max_iter: int = 12) -> Plan:
    """Solve the jump's fixed point (see the module docstring).

    Parameters
    ----------
    jumper : Jumper
    course : Course
    k : ndarray, shape (6,)
        The springs used (thesis units × strength).
    t_air, t_windup : float
    g : float or sequence of 3 float
    max_iter : int

    Returns
    -------
    Plan
        Raises ``ValueError`` saying what to change for an unreachable target.

    Examples
    --------
    >>> from flipstudy.stimuli.control import STRENGTH, Jumper, make_course, parse_k
    >>> pl = plan(Jumper(), make_course("forward"), parse_k("global-normal") * STRENGTH, 0.5, 0.2, 9.81)
    >>> pl.iterations < 12, pl.windup.satisfied, bool(pl.path.v0[1] > 0)   # converged, enough energy, upwards
    (True, True, True)
    """
    field_ = sample_field(jumper, k=k)                # uneven legs: the pelvis rolls in a crouch
    gv = gravity_vector(g)
    F0, F1 = np.asarray(course.start, float), np.asarray(course.target, float)
    feet0, feet1 = jumper.feet(F0), jumper.feet(F1)
    targets = field_.balanced(k).target           # balance targets relative to the feet, per sample
    up = np.array([0.0, 1.0, 0.0])
    m = jumper.mass
    # first guess: the COM travels ~0.78 of the feet's horizontal displacement
    # (it takes off ahead of the feet and lands behind them) and ~8 cm less high
    d0 = (F1 - F0) * np.array([0.78, 1.0, 0.78]) - np.array([0.0, 0.08, 0.0])
    path = estimate_path(d0, t_air, t_windup, gv)
    v0 = path.v0
    # |v0|² = |d|²/T² − d·g + |g|²T²/4 is least at T = √(2|d|/|g|): the cheapest air time
    t_cheap = float(np.sqrt(2.0 * np.linalg.norm(d0) / np.linalg.norm(gv)))
    cheapest = (t_cheap, kinetic_energy(m, estimate_path(d0, t_cheap, t_windup, gv).v0))
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
        wc = choose(field_, k, kinetic_energy(m, v0), travel, takeoff_offset=takeoff_offset(v0),
                    cheapest=cheapest)
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
