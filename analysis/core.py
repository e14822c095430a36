"""Ratings and d′ per error group and level: pooled, per participant, bootstrap.

Everything here is array arithmetic on a participants × cells table of counts
(a *cell* is one (group, level)); the bootstrap resamples participants with
replacement and is one matrix product per block of resamples.
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .io import group_order, level_order
from .sdt import CORRECTION_TEXT, normalise_correction, rates, z

BOOT_BLOCK = 256          # resamples per matrix product (bounds memory for large panels)


@dataclass
class Counts:
    """Trials (``n``) and "incorrect" answers (``k``) per participant × cell.

    ``cells`` lists the cells (columns ``group``, ``level``) in table order;
    ``orig[j]`` is the column of cell ``j``'s original (level 0 of the same
    group), −1 when the group has no level 0.
    """
    participants: np.ndarray          # (P,) participant ids (str)
    cells: pd.DataFrame               # (K,) group, level
    k: np.ndarray                     # (P, K) float
    n: np.ndarray                     # (P, K) float
    orig: np.ndarray                  # (K,) int

    @property
    def groups(self) -> list[str]:
        return list(dict.fromkeys(self.cells["group"]))


def count_cells(df: pd.DataFrame) -> Counts:
    """Counts per participant × (group, level) of a checked response table.

    Parameters
    ----------
    df : pandas.DataFrame
        A checked response table (:func:`load_responses`).

    Returns
    -------
    Counts
        Trials and answers "incorrect" per participant (rows) and cell (columns).

    Examples
    --------
    >>> from flipstudy.analysis import count_cells, load_responses
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> cnt = count_cells(load_responses(paper_panel(4, seed=0)))
    >>> cnt.n.shape[0]                                  # participants
    4
    """
    groups = group_order(df["group"].unique())
    cells = []
    for g in groups:
        for lv in level_order(df.loc[df["group"] == g, "level"].unique()):
            cells.append((g, lv))
    cells_df = pd.DataFrame(cells, columns=["group", "level"])
    key = {c: i for i, c in enumerate(cells)}
    cell_idx = pd.MultiIndex.from_tuples(cells, names=["group", "level"]).get_indexer(
        pd.MultiIndex.from_arrays([df["group"], df["level"]])).astype(np.int64)
    p_codes, participants = pd.factorize(df["participant"], sort=True)
    P, K = len(participants), len(cells)
    flat = p_codes.astype(np.int64) * K + cell_idx
    n = np.bincount(flat, minlength=P * K).reshape(P, K).astype(float)
    k = np.bincount(flat, weights=df["incorrect"].to_numpy(dtype=float), minlength=P * K).reshape(P, K)
    orig = np.array([key.get((g, 0.0), -1) for g, _ in cells], dtype=np.int64)
    return Counts(np.asarray(participants, dtype=str), cells_df, k, n, orig)


def _dprime_c(kh, nh, kf, nf, correction):
    """d′, c and the corrected flag where all totals are positive; NaN elsewhere."""
    ok = (nh > 0) & (nf > 0)
    one = np.ones_like(nh)
    H, F, corr = rates(np.where(ok, kh, 0), np.where(ok, nh, one), np.where(ok, kf, 0),
                       np.where(ok, nf, one), correction)
    zh, zf = z(H), z(F)
    d = np.where(ok, zh - zf, np.nan)
    c = np.where(ok, -(zh + zf) / 2.0, np.nan)
    return d, c, corr & ok


def participant_dprimes(cnt: Counts, correction: str) -> np.ndarray:
    """(P, K) d′ of each participant in each cell (NaN where a participant lacks
    the cell or its original).

    Parameters
    ----------
    cnt : Counts
        From :func:`count_cells`.
    correction : {"loglinear", "loglinear-all", "1/(2N)"}

    Returns
    -------
    ndarray, shape (P, K)

    Examples
    --------
    >>> from flipstudy.analysis import count_cells, load_responses, participant_dprimes
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> cnt = count_cells(load_responses(paper_panel(4, seed=0)))
    >>> participant_dprimes(cnt, "loglinear").shape == cnt.n.shape
    True
    """
    has = cnt.orig >= 0
    o = np.where(has, cnt.orig, 0)
    d, _, _ = _dprime_c(cnt.k, cnt.n, cnt.k[:, o], cnt.n[:, o], correction)
    d[:, ~has] = np.nan
    return d


def bootstrap_counts(n_participants: int, n_boot: int, seed, block: int = BOOT_BLOCK):
    """Yield (b, P) matrices: how often each participant is drawn in a resample."""
    rng = np.random.default_rng(seed)
    P = n_participants
    done = 0
    while done < n_boot:
        b = min(block, n_boot - done)
        idx = rng.integers(0, P, size=(b, P))
        idx += (np.arange(b) * P)[:, None]
        yield np.bincount(idx.ravel(), minlength=b * P).reshape(b, P).astype(float)
        done += b


def expanded_level(ci: float, n_clusters: int) -> float:
    """Coverage to ask of the bootstrap percentiles so that the interval has
    ``ci`` coverage with ``n_clusters`` participants: the *expanded percentile*
    interval (Hesterberg 2015, "What teachers should know about the bootstrap",
    The American Statistician 69(4)), which widens the plain percentile interval
    by ``sqrt(n/(n−1)) · t_{n−1} / z`` to undo its small-sample narrowness."""
    from scipy.stats import norm, t
    if n_clusters < 2:
        return ci
    a = (1 - ci) / 2
    zq = np.sqrt(n_clusters / (n_clusters - 1)) * t.ppf(1 - a, n_clusters - 1)
    return float(1 - 2 * norm.sf(zq))


def _quantiles(x: np.ndarray, ci: float) -> tuple[np.ndarray, np.ndarray]:
    a = (1 - ci) / 2
    if np.isnan(x).any():
        with warnings.catch_warnings():            # all-NaN columns (no original) stay NaN
            warnings.simplefilter("ignore", RuntimeWarning)
            lo, hi = np.nanquantile(x, [a, 1 - a], axis=0)
    else:
        lo, hi = np.quantile(x, [a, 1 - a], axis=0)
    return lo, hi


def summarize(df: pd.DataFrame, correction: str = "loglinear", n_boot: int = 2000, seed=0,
              ci: float = 0.95) -> tuple[pd.DataFrame, pd.DataFrame, list[str]]:
    """The long table (one row per group and level), the per-participant d′
    table, and notes.

    Columns of the long table:

    ``group, level, n`` (trials), ``n_incorrect``, ``n_participants``,
    ``rating_pct`` (percent of answers "correct", pooled), ``rating_ci_low/high``
    (bootstrap over participants), ``p_incorrect``, ``dprime`` (pooled counts,
    as in the paper), ``criterion`` (pooled), ``dprime_pooled_ci_low/high``
    (bootstrap over participants of the pooled d′), ``dprime_mean_participants``
    (mean of the participants' own d′), ``dprime_ci_low/high`` (bootstrap CI of
    that mean), ``n_participants_dprime``, ``correction`` (the rule in force)
    and ``corrected`` (whether it changed this row's pooled rates).

    Parameters
    ----------
    df : pandas.DataFrame
        A checked response table (:func:`load_responses`).
    correction : {"loglinear", "loglinear-all", "1/(2N)"}
    n_boot : int, default 2000
        Bootstrap resamples over participants.
    seed : int
    ci : float, default 0.95

    Returns
    -------
    table : pandas.DataFrame
    participants : pandas.DataFrame
    notes : list of str

    Examples
    --------
    >>> from flipstudy.analysis import load_responses, summarize
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> table, per_participant, notes = summarize(load_responses(paper_panel(19, seed=0)), n_boot=100)
    >>> row = table.iloc[0]
    >>> row["group"], float(row["level"]), int(row["n"])
    ('smooth-increase', 0.0, 76)
    """
    correction = normalise_correction(correction)
    if not 0 < ci < 1:
        raise FlipstudyValueError(f"ci must lie between 0 and 1, got {ci}")
    if n_boot < 1:
        raise FlipstudyValueError(f"n_boot must be at least 1, got {n_boot}")
    cnt = count_cells(df)
    P, K = cnt.k.shape
    has = cnt.orig >= 0
    o = np.where(has, cnt.orig, 0)

    # pooled over participants (the paper's numbers)
    Kp, Np = cnt.k.sum(0), cnt.n.sum(0)
    d_pool, c_pool, corr = _dprime_c(Kp, Np, Kp[o], Np[o], correction)
    d_pool[~has], c_pool[~has], corr[~has] = np.nan, np.nan, False

    # per participant
    D = participant_dprimes(cnt, correction)
    M = ~np.isnan(D)
    D0 = np.where(M, D, 0.0)
    n_part_d = M.sum(0)
    with np.errstate(invalid="ignore", divide="ignore"):
        d_mean = D0.sum(0) / n_part_d
    d_mean[n_part_d == 0] = np.nan

    level = expanded_level(ci, P)
    (r_lo, r_hi), (dp_lo, dp_hi), (dm_lo, dm_hi) = _bootstrap(cnt, D0, M, o, has, correction,
                                                             n_boot, seed, level)

    with np.errstate(invalid="ignore", divide="ignore"):
        p_inc = Kp / Np
    table = cnt.cells.copy()
    table["n"] = Np.astype(int)
    table["n_incorrect"] = Kp.astype(int)
    table["n_participants"] = (cnt.n > 0).sum(0)
    table["rating_pct"] = 100.0 * (1.0 - p_inc)
    table["rating_ci_low"], table["rating_ci_high"] = r_lo, r_hi
    table["p_incorrect"] = p_inc
    table["dprime"] = d_pool
    table["criterion"] = c_pool
    table["dprime_pooled_ci_low"], table["dprime_pooled_ci_high"] = dp_lo, dp_hi
    table["dprime_mean_participants"] = d_mean
    table["dprime_ci_low"], table["dprime_ci_high"] = dm_lo, dm_hi
    table["n_participants_dprime"] = n_part_d
    table["correction"] = correction
    table["corrected"] = corr

    notes = _summary_notes(cnt, correction, corr, ci, level, n_boot, seed)
    part = pd.DataFrame({
        "participant": np.repeat(cnt.participants, K),
        "group": np.tile(cnt.cells["group"].to_numpy(), P),
        "level": np.tile(cnt.cells["level"].to_numpy(), P),
        "n": cnt.n.ravel().astype(int),
        "n_incorrect": cnt.k.ravel().astype(int),
        "dprime": D.ravel(),
    })
    part = part[part["n"] > 0].reset_index(drop=True)
    return table, part, notes


def _bootstrap(cnt: Counts, D0, M, o, has, correction: str, n_boot: int, seed, level: float):
    """Percentile intervals at ``level`` of the bootstrap over participants, vectorised
    (one (b, P) @ (P, K) product per block): (low, high) of the rating, the pooled d′
    and the mean of the participants' d′."""
    P = cnt.k.shape[0]
    rating_b, dpool_b, dmean_b = [], [], []
    Mf = M.astype(float)
    for C in bootstrap_counts(P, n_boot, seed):
        kb, nb = C @ cnt.k, C @ cnt.n
        with np.errstate(invalid="ignore", divide="ignore"):
            rating_b.append(100.0 * (1.0 - kb / nb))
            dmean_b.append((C @ D0) / (C @ Mf))
        d, _, _ = _dprime_c(kb, nb, kb[:, o], nb[:, o], correction)
        d[:, ~has] = np.nan
        dpool_b.append(d)
    return (_quantiles(np.concatenate(rating_b), level), _quantiles(np.concatenate(dpool_b), level),
            _quantiles(np.concatenate(dmean_b), level))


def _summary_notes(cnt: Counts, correction: str, corr, ci: float, level: float, n_boot: int,
                   seed) -> list[str]:
    """The notes :func:`summarize` returns: d′, the correction, the intervals."""
    P, K = cnt.k.shape
    notes = ["d′ = z(P(incorrect | modified)) − z(P(incorrect | original)), the original being "
             "level 0 of the same group; criterion c = −(z(H) + z(F))/2.",
             f"Rates of 0 or 1: {CORRECTION_TEXT[correction]}; the pooled rates of "
             f"{int(corr.sum())} of {K} rows were corrected (column 'corrected'), and "
             f"{int(_n_corrected_participant_cells(cnt, correction))} participant × cell d′ values.",
             (f"Confidence intervals: {ci:.0%} expanded-percentile bootstrap over participants "
              f"(Hesterberg 2015: the {level:.2%} percentile interval, which has {ci:.0%} coverage "
              f"with {P} participants; {n_boot} resamples, seed {seed})." if P >= 5 else
              f"Intervals: percentile bootstrap over participants ({n_boot} resamples, seed {seed}); "
              f"with {P} participant{'s' if P != 1 else ''} a bootstrap over participants has no "
              f"known coverage (it needs at least 5), so these intervals are not {ci:.0%} "
              f"confidence intervals."),
             "Levels with negative d′ (modified motions judged correct more often than the "
             "original) are kept as they are."]
    missing = [g for g in cnt.groups if cnt.orig[(cnt.cells["group"] == g).to_numpy()][0] < 0]
    if missing:
        notes.append("No original (level 0) in group(s) " + ", ".join(missing)
                     + ": their d′ and criterion are left empty.")
    return notes


def _n_corrected_participant_cells(cnt: Counts, correction: str) -> int:
    has = cnt.orig >= 0
    o = np.where(has, cnt.orig, 0)
    _, _, corr = _dprime_c(cnt.k, cnt.n, cnt.k[:, o], cnt.n[:, o], correction)
    corr[:, ~has] = False
    return int(corr.sum())
