"""Mass-distribution estimation (Majkowska & Faloutsos 2007, Section 4.2).

In flight the COM moves on a line horizontally and a parabola vertically.  The
segment masses ``m`` and the path parameters are found together by one
constrained linear least-squares problem over the flight frames t:

    min  Σ_t ‖ Σ_g (m_g / M) pos_g(t) − COM(t) ‖²  +  W Σ_g ((m_g − m⁰_g) / m⁰_g)²
    s.t. Σ_g m_g = M,  m_g ≥ 0,
    COM(t) = [a_x t + b_x,  a_y t² + b_y t + c_y,  a_z t + b_z]

with left and right limbs sharing one mass (symmetry), ``pos_g`` the COM of
segment group g, and m⁰ the de Leva prior.  W (m²) keeps the solution near the
prior unless the data clearly prefer otherwise (the paper's fix for
over-fitting).  Gravity is not assumed: the fit returns a_y, and
s = −2 a_y / g is the scale factor between the clip's units/time and the real
world (1 for a clip in metres at the right frame rate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from .body import GROUPS, Body
from .motion.clip import Clip, finite_difference
from .physics import piece_positions

G = 9.81


@dataclass
class MassFit:
    """Result of :func:`estimate_masses`."""

    body: Body                 # the body with the estimated masses
    prior: dict                # group → kg (prior)
    masses: dict               # group → kg (estimated)
    coef: np.ndarray           # (3,3) path, rows x,y,z, columns t², t, 1
    apparent_gravity: float    # −2 a_y, m/s² in the clip's units and time
    scale_factor: float        # s = apparent_gravity / 9.81
    com_rms_prior: float       # COM residual from the best path with the prior masses, m
    com_rms: float             # ... with the estimated masses, m
    p_dev_prior: float         # RMS deviation of p(t) from the ballistic pattern, prior, kg·m/s
    p_dev: float               # ... estimated masses
    W: float

    @property
    def p_dev_reduction_pct(self) -> float:
        """How much the estimated masses reduce the deviation of linear momentum
        from the ballistic pattern in flight, in percent of the prior's."""
        if self.p_dev_prior <= 0:
            return 0.0
        return 100.0 * (1.0 - self.p_dev / self.p_dev_prior)


def group_positions(clip: Clip, body: Body, frames: slice | np.ndarray = slice(None)) -> np.ndarray:
    """(F,G,3) COM of each symmetric segment group (both sides pooled at their
    prior mass ratio)."""
    c = piece_positions(clip, body)[frames]
    gi = np.array([GROUPS.index(body.segment_names[s].split("_")[0]) for s in body.segment])
    W = np.zeros((len(GROUPS), body.num_pieces))
    W[gi, np.arange(body.num_pieces)] = body.mass
    W /= W.sum(1, keepdims=True)
    return np.einsum("gp,fpa->fga", W, c)


def _path_design(t: np.ndarray) -> np.ndarray:
    """(F*3, 7) columns a_x, b_x, a_y, b_y, c_y, a_z, b_z for stacked x,y,z rows."""
    F = t.size
    D = np.zeros((F, 3, 7))
    D[:, 0, 0], D[:, 0, 1] = t, 1.0
    D[:, 1, 2], D[:, 1, 3], D[:, 1, 4] = t ** 2, t, 1.0
    D[:, 2, 5], D[:, 2, 6] = t, 1.0
    return D.reshape(F * 3, 7)


def _coef_from_params(x: np.ndarray) -> np.ndarray:
    return np.array([[0.0, x[0], x[1]], [x[2], x[3], x[4]], [0.0, x[5], x[6]]])


def ballistic_p_deviation(p: np.ndarray, fps: float) -> float:
    """RMS deviation of linear momentum p (F,3) from the ballistic pattern: p_x,
    p_z constant and p_y linear in time (slope free)."""
    t = np.arange(p.shape[0]) / fps
    dev = [p[:, 0] - p[:, 0].mean(), p[:, 2] - p[:, 2].mean()]
    A = np.stack([t, np.ones_like(t)], 1)
    dev.append(p[:, 1] - A @ np.linalg.lstsq(A, p[:, 1], rcond=None)[0])
    return float(np.sqrt(np.mean(np.concatenate(dev) ** 2)))


def estimate_masses(clip: Clip, body: Body, takeoff: int, landing: int,
                    W: float = 1e-6, prior: dict | None = None) -> MassFit:
    """Estimate the segment-group masses from the flight ``takeoff..landing``.

    ``prior`` (group → kg) replaces the body's own masses as m⁰ (the total stays
    the body's).  Example::

        fit = estimate_masses(clip, body, a.takeoff, a.landing)
        fit.masses["trunk"], fit.scale_factor, fit.p_dev_reduction_pct
    """
    frames = slice(takeoff, landing + 1)
    pos = group_positions(clip, body, frames)                 # (F,G,3)
    F, Gn, _ = pos.shape
    if F < 4:
        raise ValueError(f"mass estimation needs at least 4 flight frames, got {F}")
    M = body.total_mass
    m0 = np.array([(prior or body.group_masses())[g] for g in GROUPS], dtype=float)
    m0 = m0 * (M / m0.sum())
    t = np.arange(F) / clip.fps
    A_m = pos.transpose(0, 2, 1).reshape(F * 3, Gn) / M        # (3F, G)
    A_p = -_path_design(t)                                      # (3F, 7)
    n = 3 * F
    # data rows are scaled by 1/sqrt(n): the data term is a mean square (m²)
    A = np.hstack([A_m, A_p]) / np.sqrt(n)
    b = np.zeros(n)
    # regularisation rows: sqrt(W) (m_g - m0_g)/m0_g
    R = np.zeros((Gn, Gn + 7))
    R[np.arange(Gn), np.arange(Gn)] = np.sqrt(W) / m0
    rb = np.sqrt(W) * np.ones(Gn)
    # equality Σm = M as a stiff row (satisfied to ~1e-9 relative, then renormalised)
    E = np.zeros((1, Gn + 7))
    E[0, :Gn] = 1e3 / M
    A_all = np.vstack([A, R, E])
    b_all = np.concatenate([b, rb, [1e3]])
    lb = np.concatenate([np.zeros(Gn), np.full(7, -np.inf)])
    ub = np.full(Gn + 7, np.inf)
    res = lsq_linear(A_all, b_all, bounds=(lb, ub), method="bvls", lsmr_tol=None)
    m = np.maximum(res.x[:Gn], 0.0)         # bvls may return -1e-16 at the bound
    m = m * (M / m.sum())
    masses = {g: float(v) for g, v in zip(GROUPS, m)}
    new_body = body.with_segment_masses(masses)

    def fit_rms(mv):
        com = np.einsum("fga,g->fa", pos, mv) / M
        x = np.linalg.lstsq(-A_p, com.reshape(-1), rcond=None)[0]
        return float(np.sqrt(np.mean((com.reshape(-1) + A_p @ x) ** 2))), x

    rms0, _ = fit_rms(m0)
    rms1, x1 = fit_rms(m)
    coef = _coef_from_params(x1)
    # linear momentum deviation from the ballistic pattern, prior vs estimate
    def p_dev(mv):
        com_all = np.einsum("fga,g->fa", group_positions(clip, body), mv) / M
        p = M * finite_difference(com_all, clip.fps)[frames]
        return ballistic_p_deviation(p, clip.fps)

    g_app = float(-2.0 * coef[1, 0])
    return MassFit(body=new_body, prior={g: float(v) for g, v in zip(GROUPS, m0)}, masses=masses,
                   coef=coef, apparent_gravity=g_app, scale_factor=g_app / G,
                   com_rms_prior=rms0, com_rms=rms1, p_dev_prior=p_dev(m0), p_dev=p_dev(m), W=W)
