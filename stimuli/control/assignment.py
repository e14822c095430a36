"""The energy assignment problem (Ooi 2016, 3.6.2) solved directly:
:func:`assign_energy` solves the problem the sampling of :mod:`.windup`
approximates with ``scipy.optimize`` (SLSQP over the pelvis position, the same
constraints), for comparison with the sampled answer (``tests/stimuli/test_control.py``:
the two crouches are millimetres apart).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from .balance import balance_error
from .ik import reach, solve_legs
from .model import SIDES
from .muscles import spring_displacement
from .samples import SampleField
from .uneven import pelvis_roll
from .windup import EPSILON, EXTENDED_UTILISATION, Choice


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
    balanced box, by SLSQP from the sampled answer.

    Parameters
    ----------
    field : SampleField
    k : ndarray, shape (6,)
    required : float
        The energy E_k to store, J.
    choice : Choice
        The sampled answer (:func:`.windup.choose`).
    travel : sequence of 3 float, optional
    eps : float

    Returns
    -------
    Assignment

    Examples
    --------
    >>> from flipstudy.stimuli.control import STRENGTH, Jumper, choose, parse_k, sample_field
    >>> k = parse_k("global-normal") * STRENGTH
    >>> f = sample_field(Jumper(), spacing=(0.03, 0.03, 0.03))      # a coarse field, quick
    >>> a = assign_energy(f, k, 300.0, choose(f, k, 300.0))
    >>> a.success, a.distance < 0.02, a.energy >= 0.95 * 300.0      # next to the sampled crouch
    (True, True, True)
    """
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
