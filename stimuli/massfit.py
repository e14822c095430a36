"""Mass-distribution estimation (Majkowska & Faloutsos 2007, Section 4.2).

In flight the COM moves on a line horizontally and a parabola vertically.  The
segment masses ``m`` and the path parameters are found together by one
constrained linear least-squares problem over the flight frames t:

    min  mean_t ‖ Σ_g (m_g / M) pos_g(t) − COM(t) ‖² / 3  +  W ‖m − m⁰‖²
    s.t. Σ_g m_g = M,  m_g ≥ 0,
    COM(t) = [a_x t + b_x,  a_y t² + b_y t + c_y,  a_z t + b_z]

with left and right limbs sharing one mass (symmetry), ``pos_g`` the COM of
segment group g, and m⁰ the de Leva prior.  The regulariser is the paper's,
W‖m − m⁰‖² in kg², so W is in m²/kg²: moving 1 kg away from the prior must
buy W m² of mean-square COM residual (per axis and frame).  The data term is a
mean, not the paper's sum over frames, so that W does not depend on the frame
rate or the flight's length.  ``DEFAULT_W`` was chosen by parameter recovery
on the built-in flips with known non-table masses and joint noise, and on the
CMU flips (see ``DEFAULT_W``).

The prior is also a plausibility check: a group whose fitted mass leaves the
band m⁰·(1 ± ``band``) (default ±35 %) is not a body's, so the data contradict
the prior (noise and soft tissue the fit "explains" by moving mass, the
paper's over-fitting); the fit then keeps the prior masses and says so
(``MassFit.status == "prior kept"``, ``MassFit.message``).

Gravity is not assumed: the fit returns a_y, and s = −2 a_y / g is the scale
factor between the clip's units/time and the real world (1 for a clip in
metres at the right frame rate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from .body import GROUPS, Body
from .motion.clip import Clip, finite_difference
from .physics import piece_positions

G = 9.81

#: Weight of the regulariser W‖m − m⁰‖² (m²/kg²).  At 1e-5 a kilogram moved
#: away from the prior must lower the mean-square COM residual by (3.2 mm)²,
#: the residual that real motion capture keeps whatever the masses (87_03 at
#: 60 fps: 7.7 mm with the prior, 3.2 mm unregularised).  Chosen on a
#: half-decade grid as the smallest W at which the fits of the CMU flips 87_03
#: and 90_11 stay in the band (at 3e-6 87_03's hands and feet leave it; 88_05
#: needs 5e-5 and 88_01 1e-4, and below that they keep the prior).  It is a prior
#: for real data: an exact built-in flight would need W ≤ 1e-10 to recover its
#: trunk and thighs (the COM path of a flip moves < 1 mm per kg between them),
#: and at 1e-5 reduces its momentum deviation by 24–31 % without recovering them.
DEFAULT_W = 1e-5

#: Plausible band around the prior: each group within m⁰·(1 ± BAND).
BAND = 0.35


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
    W: float                   # regulariser weight, m²/kg²
    band: float | None = BAND  # plausible band, fraction of the prior (None: none)
    status: str = "fitted"     # "fitted" or "prior kept" (the data contradict the prior)
    message: str = ""          # why the prior was kept (groups outside the band)
    fitted: dict | None = None # group → kg the least squares gave (also when not kept)

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
                    W: float = DEFAULT_W, prior: dict | None = None,
                    band: float = BAND) -> MassFit:
    """Estimate the segment-group masses from the flight ``takeoff..landing``.

    ``prior`` (group → kg) replaces the body's own masses as m⁰ (the total stays
    the body's).  ``W`` weighs W‖m − m⁰‖² (m²/kg²).  When a group's fitted mass
    leaves m⁰·(1 ± band) the prior is kept (``status == "prior kept"``;
    ``message`` names the groups, ``fitted`` holds the rejected solution);
    ``band=None`` accepts any solution.  Example::

        fit = estimate_masses(clip, body, a.takeoff, a.landing)
        fit.status, fit.masses["trunk"], fit.scale_factor, fit.p_dev_reduction_pct
    """
    if not (np.isfinite(W) and W >= 0):
        raise ValueError(f"W must be a weight >= 0 (m²/kg²), got {W!r}")
    if band is not None and not (np.isfinite(band) and band > 0):
        raise ValueError(f"band must be a fraction > 0 of the prior (0.35: ±35 %) or None, got {band!r}")
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
    # regularisation rows: sqrt(W) (m_g - m0_g), in kg (the paper's W‖m − m⁰‖²)
    R = np.zeros((Gn, Gn + 7))
    R[np.arange(Gn), np.arange(Gn)] = np.sqrt(W)
    rb = np.sqrt(W) * m0
    # equality Σm = M as a stiff row (satisfied to ~1e-9 relative, then renormalised)
    E = np.zeros((1, Gn + 7))
    E[0, :Gn] = 1e3 / M
    A_all = np.vstack([A, R, E])
    b_all = np.concatenate([b, rb, [1e3]])
    lb = np.concatenate([np.zeros(Gn), np.full(7, -np.inf)])
    ub = np.full(Gn + 7, np.inf)
    res = lsq_linear(A_all, b_all, bounds=(lb, ub), method="bvls", lsmr_tol=None)
    m_fit = np.maximum(res.x[:Gn], 0.0)     # bvls may return -1e-16 at the bound
    m_fit = m_fit * (M / m_fit.sum())
    rel = m_fit / m0 - 1.0
    out = np.zeros(Gn, bool) if band is None else np.abs(rel) > band
    status, message, m = "fitted", "", m_fit
    if np.any(out):
        status, m = "prior kept", m0
        message = ("the data contradict the prior: " +
                   ", ".join(f"{g} {m0[k]:.1f} → {m_fit[k]:.1f} kg ({100 * rel[k]:+.0f} %)"
                             for k, g in enumerate(GROUPS) if out[k]) +
                   f" leave the band ±{100 * band:.0f} % around de Leva; the prior masses are kept")
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
    pos_all = group_positions(clip, body)

    def p_dev(mv):
        com_all = np.einsum("fga,g->fa", pos_all, mv) / M
        p = M * finite_difference(com_all, clip.fps)[frames]
        return ballistic_p_deviation(p, clip.fps)

    g_app = float(-2.0 * coef[1, 0])
    return MassFit(body=new_body, prior={g: float(v) for g, v in zip(GROUPS, m0)}, masses=masses,
                   coef=coef, apparent_gravity=g_app, scale_factor=g_app / G,
                   com_rms_prior=rms0, com_rms=rms1, p_dev_prior=p_dev(m0), p_dev=p_dev(m), W=W,
                   band=band, status=status, message=message,
                   fitted={g: float(v) for g, v in zip(GROUPS, m_fit)})
