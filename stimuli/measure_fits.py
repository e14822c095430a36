"""The fits :mod:`flipstudy.stimuli.measure` reads its items from: a trend and a step
in |L| over a flight, the jolt of the COM's velocity in the air, the COM's parabola
and the ground phases' low-order fits beside a contact (re-exported by
:mod:`flipstudy.stimuli.measure`)."""
from __future__ import annotations

import numpy as np


def _batched_lstsq(X: np.ndarray, y: np.ndarray, w: np.ndarray):
    """Weighted least squares for K designs at once: ``X`` (K,n,p), ``y`` (n,d),
    ``w`` (K,n) 0/1 weights.  Returns coefficients (K,p,d) and the residual sum
    of squares (K,) over the weighted samples."""
    Xw = X * w[..., None]
    A = np.einsum("knp,knq->kpq", Xw, X)
    b = np.einsum("knp,nd->kpd", Xw, y)
    coef = np.linalg.solve(A + 1e-12 * np.eye(A.shape[-1]), b)
    r = y[None] - np.einsum("knp,kpd->knd", X, coef)
    return coef, np.einsum("kn,knd->k", w, r * r)



def _candidates(n: int, edge: int) -> np.ndarray:
    return np.arange(edge, n - edge + 1)



def split_trend_step(tau: np.ndarray, L: np.ndarray, T: float) -> tuple[float, float, float, float]:
    """|L| over a flight as ``c0 + c1·τ/T + c2·[τ ≥ τ_k]``: a trend (smooth) and a
    step (abrupt) at the sample ``k`` that fits best (the two samples whose
    differencing stencil straddles the step are left out of that fit; the first
    and last sample, differenced one-sidedly, are always left out).  Returns the
    smooth change over the flight in % of |L| at take-off, the step in % of the
    line at the step's instant (halfway between the samples either side), that
    instant and |L| at take-off.  A step that explains less than half of what the
    line alone leaves is 0.

    >>> tau = np.linspace(0, 0.6, 61)
    >>> L = 40 * np.where(tau < 0.3, 1.0, 1.2)
    >>> [round(float(x), 3) for x in split_trend_step(tau, L, 0.6)[:2]]
    [0.0, 20.0]
    """
    n = tau.size
    u = tau / T
    base = np.ones(n)
    base[[0, -1]] = 0.0
    if n < 8:
        c = np.polyfit(u[1:-1] if n > 4 else u, L[1:-1] if n > 4 else L, 1)
        return 100.0 * c[0] / c[1], 0.0, float("nan"), float(c[1])
    ks = _candidates(n, 3)
    H = (np.arange(n)[None] >= ks[:, None]).astype(float)            # (K,n)
    X = np.stack([np.broadcast_to(np.ones(n), H.shape), np.broadcast_to(u, H.shape), H], -1)
    w = np.broadcast_to(base, H.shape).copy()
    rows = np.arange(ks.size)
    w[rows, ks - 1] = 0.0
    w[rows, ks] = 0.0
    coef, rss = _batched_lstsq(X, L[:, None], w)
    # a step must explain more than dropping two samples does: compare with the
    # trend alone over the same samples
    X0 = X[..., :2]
    _, rss0 = _batched_lstsq(X0, L[:, None], w)
    gain = rss0 - rss
    # a step between samples fits equally with its border sample on either side (the
    # straddling samples are left out): of the candidates whose residual is the least
    # (within 1e-9 of the line's) the middle one
    best = np.flatnonzero(rss <= rss.min() + 1e-9 * max(float(rss0.max()), 1e-300))
    j = int(best[best.size // 2])
    c0, c1, c2 = coef[j, :, 0]
    k = ks[j]
    if gain[j] < 0.5 * rss0[j]:
        # the step explains less than half of what the line leaves: no step (the line
        # alone, over every inner sample, gives the trend)
        c1, c0 = np.polyfit(u[1:-1], L[1:-1], 1)
        return 100.0 * c1 / c0, 0.0, float(0.5 * (tau[k - 1] + tau[k])), float(c0)
    t_step = 0.5 * (tau[k - 1] + tau[k])
    before = c0 + c1 * t_step / T                     # the line at the step's instant
    return 100.0 * c1 / c0, 100.0 * c2 / before, float(t_step), float(c0)



def velocity_jolt(t: np.ndarray, com: np.ndarray) -> tuple[float, float]:
    """The largest velocity step of a COM in the air: for every instant between
    samples a parabola plus a hinge ``Δv·max(0, t − t_k)`` is fitted in every axis;
    the instant whose hinge explains most of the residual gives |Δv| (m/s) and
    its time.  A pure parabola gives 0."""
    n = t.size
    if n < 10:
        return 0.0, float(t[n // 2]) if n else float("nan")
    ks = _candidates(n, 3)
    tk = 0.5 * (t[ks - 1] + t[ks])
    s = t - t[0]
    hinge = np.maximum(0.0, t[None] - tk[:, None])
    K = ks.size
    X = np.stack([np.broadcast_to(s * s, (K, n)), np.broadcast_to(s, (K, n)),
                  np.ones((K, n)), hinge], -1)
    coef, rss = _batched_lstsq(X, com, np.ones((K, n)))
    j = int(np.argmin(rss))
    return float(np.linalg.norm(coef[j, 3])), float(tk[j])



def _quad(cf: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(n,3) a fitted quadratic's positions at times ``t``."""
    return cf[:, 0] * t[:, None] ** 2 + cf[:, 1] * t[:, None] + cf[:, 2]



def _ground_fit(com: np.ndarray, fps: float, frames: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(n,3) positions at times ``t`` of a quadratic through ``frames``."""
    tf = frames / fps
    A = np.stack([tf * tf, tf, np.ones_like(tf)], 1)
    c = np.linalg.lstsq(A, com[frames], rcond=None)[0]
    return np.stack([t * t, t, np.ones_like(t)], 1) @ c



def _ground_velocity(com: np.ndarray, fps: float, frames: np.ndarray, t: float) -> np.ndarray:
    """COM velocity at instant ``t`` from a quadratic through ``frames`` (a ground phase's)."""
    tf = frames / fps - t
    A = np.stack([tf * tf, tf, np.ones_like(tf)], 1)
    c = np.linalg.lstsq(A, com[frames], rcond=None)[0]
    return c[1]
