"""The motion of the built-in clips phase by phase: the flight (joint angles
take-off → tuck → landing, the pitch from the conserved angular momentum, the
take-off fixed point solved), the ground before take-off (crouch and push) and
after touch-down (absorb, recover, hold).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import fsolve

from flipstudy.errors import SynthError
from .designs import G, SUBSTEPS, dof_vector
from .planar import D, IX, HermiteSegment, QuinticSpline, cumulative_simpson
from .poses import N_LEG, com_from_ball, contact_rates, leg_pitches, legs_for_com

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


def solve_flight(name, model, d, q0, qL, v0, T, n_flight, dtheta) -> dict:
    """The flight's joint angles, L and pitch, with the take-off fixed point solved:
    the take-off leg rates/accelerations depend on the pitch rate Ω0 and pitch
    acceleration Ω̇0 (the pinned chain must give the COM v0 and −g), L depends on
    the leg motion, and Ω0, Ω̇0 must be the flight's (L − h)/I and its rate."""
    heel_rate = d["heel_rate"]
    heel_acc = (2.0 / 3.0) * heel_rate ** 2 / d["heel"]   # foot pitch heel0 τ³ at its end

    def state(x, sub=SUBSTEPS):
        qd0, qdd0 = contact_rates(model, q0, v0, x[0], x[1], d["takeoff_rates"], heel_rate, heel_acc)
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


def ground_before(model, d, tp, q_crouch, q0, qd0, qdd0, rel0, v0, t_to, heel_dur):
    """DOF vectors (N,D) at the times ``tp`` before take-off, and the COM rise of
    the push.  Down into the crouch: quintics in the joint angles (feet flat)
    arriving at rest with the COM accelerating upward at ``a_bottom``.  Up to
    take-off: the COM on a degree-7 piece, the legs solved for it."""
    t_stand, t_crouch = d["t_stand"], d["t_crouch"]
    z3 = np.zeros(3)
    Jc = model.pinned_jacobian(q_crouch)
    a_b = np.array([0.0, d["a_bottom"], 0.0])
    qdd_c = N_LEG @ np.linalg.solve(Jc[1:] @ N_LEG, a_b[1:])    # legs give the COM a_b
    down = QuinticSpline([t_stand, t_crouch], np.stack([np.zeros(D), q_crouch]),
                         np.zeros((2, D)), np.stack([np.zeros(D), qdd_c]))
    Q = down(tp)
    up_body = QuinticSpline([t_crouch, t_to], np.stack([q_crouch, q0]), np.stack([np.zeros(D), qd0]),
                            np.stack([qdd_c, qdd0]))
    rel_c = com_from_ball(model, q_crouch)
    jerk_c = Jc @ down(t_crouch, 3)[0]                      # COM jerk at the bottom (rates are 0)
    up = HermiteSegment(t_crouch, t_to, [rel_c, z3, a_b, jerk_c],
                        [rel0, v0, np.array([0.0, -G, 0.0]), z3])
    mv = tp > t_crouch
    if mv.any():
        tk = tp[mv]
        foot = d["heel"] * np.clip((tk - (t_to - heel_dur)) / heel_dur, 0.0, None) ** 3
        w = (tk - t_crouch) / (t_to - t_crouch)
        (s_c, t_c), (s_0, t_0) = leg_pitches(q_crouch), leg_pitches(q0)
        Q[mv] = legs_for_com(model, up_body(tk), foot, up(tk), s_c + w * (s_0 - s_c),
                              t_c + w * (t_0 - t_c), "take-off")
    return Q, float(rel0[1] - rel_c[1])


def ground_after(model, d, fps, scale, turns, i_td, t_td, qL, qd_td, relL, vL):
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
    absorb_to = dof_vector(**d["absorb_pose"])
    absorb_to[IX["pitch"]] += foot
    upper = QuinticSpline([t_td, t_abs], np.stack([qL_abs, absorb_to]), np.stack([qd_td, np.zeros(D)]))
    shift = vL * T_a / 3.0

    def com_path(t):
        tau = ((t - t_td) / T_a)[:, None]
        return relL[None] + shift[None] * (1.0 - (1.0 - tau) ** 3)

    s_L, t_L = leg_pitches(qL_abs)
    q_A = legs_for_com(model, upper(np.array([t_abs])), np.full(1, foot), (relL + shift)[None],
                        np.array([s_L]), np.array([t_L]), "absorb", foot)[0]
    Q = np.empty((len(tq), D))
    ab = tq <= t_abs
    if ab.any():
        w = (tq[ab] - t_td) / T_a
        s_A, t_A = leg_pitches(q_A)
        Q[ab] = legs_for_com(model, upper(tq[ab]), np.full(ab.sum(), foot), com_path(tq[ab]),
                              s_L + w * (s_A - s_L), t_L + w * (t_A - t_L), "absorb", foot)
    rest = ~ab
    if rest.any():
        recover = QuinticSpline([t_abs, t_rec], np.stack([q_A, dof_vector(pitch=foot)]))
        Q[rest] = recover(tq[rest])
        Q[rest, IX["ankle"]] = foot - (Q[rest, IX["pitch"]] + Q[rest, IX["hip"]] + Q[rest, IX["knee"]])
        Q[rest, IX["toe"]] = 0.0
    return Q
