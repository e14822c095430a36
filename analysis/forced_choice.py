"""Two-alternative forced choice: proportion correct and d′ = √2·z(P correct) per group
and level, pooled and per participant, with bootstrap intervals over participants.

A 2AFC trial shows the original and a modified motion one after the other (order
in column ``first``) and asks which was physically correct; a *correct* answer
chooses the original (column ``detected`` of :func:`~.io.load_responses`).  There
is no level-0 cell: the original is in every trial.  The rows have the columns of
the yes/no table (:func:`~.core.summarize`) with ``task`` = ``2afc``, plus
``n_correct`` and ``p_correct``; the yes/no-only columns (``n_incorrect``,
``rating_*``, ``p_incorrect``, ``criterion``) are empty.

>>> import pandas as pd
>>> df = pd.DataFrame({"participant": ["P1"] * 4 + ["P2"] * 4, "group": "g", "level": 20.0,
...                    "detected": [1, 1, 1, 0, 1, 1, 0, 0]})
>>> t, part, notes = summarize_2afc(df, n_boot=50)
>>> t[["group", "task", "level", "n", "n_correct", "p_correct"]].values.tolist()
[['g', '2afc', 20.0, 8, 5, 0.625]]
>>> round(float(t["dprime"].iloc[0]), 4)                 # √2 · z(5/8)
0.4506
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .core import bootstrap_counts, count_cells, expanded_level, _quantiles
from .sdt import CORRECTION_TEXT, dprime_2afc, normalise_correction

YESNO_ONLY = ("n_incorrect", "rating_pct", "rating_ci_low", "rating_ci_high", "p_incorrect", "criterion")


def _d2(k, n, correction):
    """2AFC d′ and corrected flag where n > 0 (NaN elsewhere)."""
    ok = n > 0
    d, corr = dprime_2afc(np.where(ok, k, 0), np.where(ok, n, 1), correction)
    return np.where(ok, d, np.nan), np.asarray(corr) & ok


def summarize_2afc(df: pd.DataFrame, correction: str = "loglinear", n_boot: int = 2000, seed=0,
                   ci: float = 0.95) -> tuple[pd.DataFrame, pd.DataFrame, list[str]]:
    """The 2AFC rows of the long table, the per-participant d′ and notes (see the module
    doc).  ``df``: the 2AFC answers (columns participant, group, level, detected)."""
    correction = normalise_correction(correction)
    cnt = count_cells(df.assign(incorrect=df["detected"]))    # k counts correct choices here
    P, K = cnt.k.shape
    Kp, Np = cnt.k.sum(0), cnt.n.sum(0)
    d_pool, corr = _d2(Kp, Np, correction)
    D, _ = _d2(cnt.k, cnt.n, correction)
    M = cnt.n > 0
    D0 = np.where(M, D, 0.0)
    n_part = M.sum(0)
    with np.errstate(invalid="ignore", divide="ignore"):
        d_mean = D0.sum(0) / n_part
    dpool_b, dmean_b = [], []
    Mf = M.astype(float)
    for C in bootstrap_counts(P, n_boot, seed):
        kb, nb = C @ cnt.k, C @ cnt.n
        dpool_b.append(_d2(kb, nb, correction)[0])
        with np.errstate(invalid="ignore", divide="ignore"):
            dmean_b.append((C @ D0) / (C @ Mf))
    level = expanded_level(ci, P)
    dp_lo, dp_hi = _quantiles(np.concatenate(dpool_b), level)
    dm_lo, dm_hi = _quantiles(np.concatenate(dmean_b), level)
    t = cnt.cells.copy()
    t["task"] = "2afc"
    t["n"] = Np.astype(int)
    for c in YESNO_ONLY:
        t[c] = np.nan
    t["n_participants"] = n_part
    t["dprime"] = d_pool
    t["dprime_pooled_ci_low"], t["dprime_pooled_ci_high"] = dp_lo, dp_hi
    t["dprime_mean_participants"] = d_mean
    t["dprime_ci_low"], t["dprime_ci_high"] = dm_lo, dm_hi
    t["n_participants_dprime"] = n_part
    t["correction"] = correction
    t["corrected"] = corr
    t["n_correct"] = Kp.astype(int)
    t["p_correct"] = Kp / Np
    part = pd.DataFrame({"participant": np.repeat(cnt.participants, K),
                         "group": np.tile(cnt.cells["group"].to_numpy(), P),
                         "level": np.tile(cnt.cells["level"].to_numpy(), P),
                         "task": "2afc", "n": cnt.n.ravel().astype(int),
                         "n_correct": cnt.k.ravel().astype(int), "dprime": D.ravel()})
    part = part[part["n"] > 0].reset_index(drop=True)
    notes = [f"2AFC groups ({', '.join(cnt.groups)}): d′ = √2·z(P correct), P correct = share of "
             f"trials whose original was chosen as the physically correct motion (Macmillan & "
             f"Creelman 2005); proportions of 0 or 1: {CORRECTION_TEXT[correction]} (for 2AFC: "
             f"applied to P correct); {int(corr.sum())} of {K} pooled rows corrected (column "
             f"'corrected'). Intervals: bootstrap over participants as for yes/no."]
    return t, part, notes
