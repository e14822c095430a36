"""The optimal timing of the second motion (Shum, Komura & Yadav 2009, eqs. 3-7;
step 4 of :mod:`flipstudy.stimuli.edit.concat`): F(T) = F_dm + F_inertia + F_time
for every offset T, all frame pairs at once, and the paper's loop as the
reference it is tested against.

>>> import numpy as np
>>> from flipstudy.stimuli.edit.concat import optimal_timing
>>> L = np.cumsum(np.ones((30, 3)), axis=0); r = np.zeros((30, 2, 3))
>>> t = optimal_timing(L, L[5:], r, r[5:], np.ones(2), np.arange(10, 20), np.arange(0, 20))
>>> t.T, t.F_dm
(5, 0.0)
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from flipstudy.errors import ConcatError


@dataclass
class Timing:
    """The optimal offset of the second motion and its cost terms (eqs. 3-7), as
    :func:`optimal_timing` and :func:`optimal_timing_bruteforce` return it.

    Attributes
    ----------
    T : int
        Motion 2's frame g is played at motion 1's frame g + T.
    fT : int
        The blending centre f_T, in motion 1's frames.
    F, F_dm, F_inertia, F_time : float
        The cost at the optimum and its three terms.
    costs : dict
        T → F for every offset examined.

    Examples
    --------
    >>> t = Timing(T=5, fT=10, F=3.0, F_dm=1.0, F_inertia=1.0, F_time=1.0)
    >>> t.T, t.F_dm + t.F_inertia + t.F_time == t.F
    (5, True)
    """

    T: int                 # motion 2's frame g is played at motion 1's frame g + T
    fT: int                # blending centre, in motion 1's frames
    F: float               # F_dm + F_inertia + F_time at the optimum
    F_dm: float
    F_inertia: float
    F_time: float
    costs: dict = field(default_factory=dict)   # T → F for every offset examined


def optimal_timing(L1, L2, r1, r2, m, frames1, frames2, f_start: int | None = None,
                   allowed: np.ndarray | None = None) -> Timing:
    """The offset T minimising F = F_dm + F_inertia + F_time (eqs. 3-7).

    ``L1`` (F1,3), ``L2`` (F2,3) angular momenta; ``r1`` (F1,P,3), ``r2`` (F2,P,3)
    moment arms (piece COM − body COM) and ``m`` (P,) masses; ``frames1`` and
    ``frames2`` the blendable frames of each motion; ``f_start`` the first frame of
    motion 1's blendable period (default ``frames1[0]``).  ``allowed`` (n1, n2)
    bool masks pairs out (e.g. facing too different).  Every frame pair (f, g) is
    one cell of an (n1 × n2) array; the offset T = f − g is its diagonal, sheared
    into a column, and f_T, F_dm, F_inertia and F_time are read off per column —
    no loop over T or f.

    Parameters
    ----------
    L1, L2 : ndarray, shape (F1, 3) and (F2, 3)
        Angular momenta of the two motions.
    r1, r2 : ndarray, shape (F1, P, 3) and (F2, P, 3)
        Moment arms (piece COM − body COM).
    m : ndarray, shape (P,)
        Piece masses.
    frames1, frames2 : array of int
        The blendable frames of each motion.
    f_start : int, optional
    allowed : ndarray of bool, shape (n1, n2), optional

    Returns
    -------
    Timing
        Raises :class:`~flipstudy.errors.ConcatError` when no pair is allowed.

    Examples
    --------
    >>> L = np.cumsum(np.ones((30, 3)), axis=0); r = np.zeros((30, 2, 3))
    >>> t = optimal_timing(L, L[5:], r, r[5:], np.ones(2), np.arange(10, 20), np.arange(0, 20))
    >>> t.T, t.fT, t.F, t.costs[4]              # motion 2 is motion 1 five frames on
    (5, 10, 0.0, 3.0)
    """
    L1, L2 = np.asarray(L1, float), np.asarray(L2, float)
    f1, f2 = np.asarray(frames1, int), np.asarray(frames2, int)
    if f1.size == 0 or f2.size == 0:
        raise ConcatError("an empty blendable period: nothing to blend")
    f_start = int(f1[0]) if f_start is None else int(f_start)
    A, B = L1[f1], L2[f2]
    D = ((A[:, 0, None] - B[None, :, 0]) ** 2 + (A[:, 1, None] - B[None, :, 1]) ** 2
         + (A[:, 2, None] - B[None, :, 2]) ** 2)                                # (n1, n2) eq. 5
    if allowed is not None:
        D = np.where(allowed, D, np.inf)
    # shear the pairs onto a grid whose columns are the offsets: frame f1[i] (row
    # r = f1[i] − a1) and f2[j] (s = f2[j] − a2) go to column r − s + n2 − 1, so
    # T = a1 − a2 + column − (n2 − 1); the least D down each column is f_T (the
    # first, i.e. the earliest f, on ties — as the loop finds it)
    a1, a2 = int(f1.min()), int(f2.min())
    n1, n2 = int(f1.max()) - a1 + 1, int(f2.max()) - a2 + 1
    rr = (f1 - a1)[:, None]
    cc = rr - (f2 - a2)[None, :] + n2 - 1
    S = np.full((n1, n1 + n2 - 1), np.inf)
    S[np.broadcast_to(rr, D.shape), cc] = D
    row = np.argmin(S, axis=0)
    col = np.arange(S.shape[1])
    ok = np.isfinite(S[row, col])
    if not ok.any():
        raise ConcatError("no frame pair of the blendable periods is allowed (torso facing directions "
                          "differ by more than π/4 everywhere)")
    row, col = row[ok], col[ok]
    fa = a1 + row                                   # f_T per offset
    Ts = a1 - a2 + col - (n2 - 1)
    fb = fa - Ts
    F_dm = S[row, col]
    F_in = np.einsum("p,kp->k", np.asarray(m, float),
                     (np.einsum("kpa,kpa->kp", r1[fa], r2[fb])
                      - np.einsum("kpa,kpa->kp", r1[fa], r1[fa])) ** 2)
    F_t = np.sum((L1[fa] - L1[f_start]) ** 2, axis=-1)
    F = F_dm + F_in + F_t
    k = int(np.argmin(F))
    return Timing(T=int(Ts[k]), fT=int(fa[k]), F=float(F[k]), F_dm=float(F_dm[k]),
                  F_inertia=float(F_in[k]), F_time=float(F_t[k]),
                  costs={int(t): float(c) for t, c in zip(Ts, F)})


def optimal_timing_bruteforce(L1, L2, r1, r2, m, frames1, frames2, f_start: int | None = None,
                              allowed: np.ndarray | None = None) -> Timing:
    """The paper's search, as written: for every offset T, scan every frame for
    f_T, then evaluate F(T).  A plain Python loop, the reference for
    :func:`optimal_timing` (same result).

    Parameters
    ----------
    L1, L2, r1, r2, m, frames1, frames2, f_start, allowed
        As for :func:`optimal_timing`.

    Returns
    -------
    Timing

    Examples
    --------
    >>> L = np.cumsum(np.ones((30, 3)), axis=0); r = np.zeros((30, 2, 3))
    >>> args = (L, L[5:], r, r[5:], np.ones(2), np.arange(10, 20), np.arange(0, 20))
    >>> t = optimal_timing_bruteforce(*args)
    >>> t.T, t.fT, t.costs == optimal_timing(*args).costs
    (5, 10, True)
    """
    f1, f2 = [int(x) for x in frames1], [int(x) for x in frames2]
    f_start = f1[0] if f_start is None else int(f_start)
    pos2 = {g: jj for jj, g in enumerate(f2)}
    best = None
    costs = {}
    for T in range(f1[0] - f2[-1], f1[-1] - f2[0] + 1):
        fT, dm = None, np.inf
        for ii, f in enumerate(f1):
            g = f - T
            if g not in pos2 or (allowed is not None and not allowed[ii, pos2[g]]):
                continue
            d = float(np.sum((L1[f] - L2[g]) ** 2))
            if d < dm:
                fT, dm = f, d
        if fT is None:
            continue
        g = fT - T
        fin = 0.0
        for p in range(len(m)):
            fin += m[p] * float(r1[fT, p] @ (r2[g, p] - r1[fT, p])) ** 2
        ft = float(np.sum((L1[fT] - L1[f_start]) ** 2))
        F = dm + fin + ft
        costs[T] = F
        if best is None or F < best.F:
            best = Timing(T=T, fT=fT, F=F, F_dm=dm, F_inertia=fin, F_time=ft)
    if best is None:
        raise ConcatError("no frame pair of the blendable periods is allowed")
    best.costs = costs
    return best

