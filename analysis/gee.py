"""Each level against its group's original: generalised estimating equations
(part of :mod:`flipstudy.analysis.stats`, which re-exports :func:`gee_levels`).

Per group, a marginal logistic model of P(judged incorrect) on the level as a
category (reference: level 0, the original), fitted by generalised estimating
equations (statsmodels ``GEE``, Binomial family, logit link, exchangeable working
correlation, participants as clusters) with the Mancl–DeRouen bias-reduced
sandwich covariance (few clusters).  Reported per level ≠ 0: odds ratio, its 95 %
Wald CI, the Wald p value and Holm's adjustment over all the levels of all groups.
"""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from .io import group_order, level_order

_COLUMNS = ["group", "level", "gee_or", "gee_ci_low", "gee_ci_high", "gee_p", "gee_p_holm",
            "gee_note"]


def gee_levels(df: pd.DataFrame, ci: float = 0.95, cov_type: str = "bias_reduced") -> pd.DataFrame:
    """Each level ≠ 0 against level 0 of its group: GEE odds ratios (see module doc).

    Returns one row per (group, level ≠ 0): ``group, level, gee_or, gee_ci_low,
    gee_ci_high, gee_p, gee_p_holm, gee_note``.  A group whose model cannot be
    fitted (no original, one level, a single participant, a singular design)
    gets NaN with the reason in ``gee_note``; this function does not raise on
    such data.

    Parameters
    ----------
    df : pandas.DataFrame
        A checked response table (:func:`load_responses`).
    ci : float, default 0.95
    cov_type : str
        statsmodels' covariance of the GEE fit.

    Returns
    -------
    pandas.DataFrame

    Examples
    --------
    >>> from flipstudy.analysis import gee_levels, load_responses
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> g = gee_levels(load_responses(paper_panel(12, seed=3)))
    >>> list(g.columns[:4]), len(g) > 0
    (['group', 'level', 'gee_or', 'gee_ci_low'], True)
    """
    from scipy.stats import norm
    try:
        from statsmodels.genmod import cov_struct, families   # not statsmodels.api: all of it
        from statsmodels.genmod.generalized_estimating_equations import GEE
        from statsmodels.stats.multitest import multipletests
    except ImportError:
        GEE = multipletests = None
    fit = None if GEE is None else (GEE, families, cov_struct)

    zq = norm.ppf(0.5 + ci / 2)
    rows = []
    for g in group_order(df["group"].unique()):
        rows += _group_rows(g, df[df["group"] == g], fit, cov_type, zq)
    out = pd.DataFrame(rows, columns=[c for c in _COLUMNS if c != "gee_p_holm"])
    out["gee_p_holm"] = np.nan
    okp = out["gee_p"].notna().to_numpy()
    if okp.any() and multipletests is not None:
        out.loc[okp, "gee_p_holm"] = multipletests(out.loc[okp, "gee_p"].to_numpy(), method="holm")[1]
    return out[_COLUMNS]


def _group_rows(g, sub: pd.DataFrame, fit, cov_type: str, zq: float) -> list[tuple]:
    """The rows of :func:`gee_levels` of one group ``g`` (its trials ``sub``); ``fit``
    is statsmodels' (GEE, families, cov_struct), None without statsmodels."""
    levels = level_order(sub["level"].unique())
    others = [lv for lv in levels if lv != 0]
    if not others:
        return []

    def fail(msg):
        return [(g, lv, np.nan, np.nan, np.nan, np.nan, msg) for lv in others]
    if fit is None:
        return fail("statsmodels is not installed (pip install statsmodels): no GEE")
    if 0.0 not in levels:
        return fail("no original (level 0) in this group")
    n_clusters = sub["participant"].nunique()
    if n_clusters < 2:
        return fail("GEE needs at least 2 participants")
    cat = pd.Categorical(sub["level"], categories=levels)
    X = pd.get_dummies(cat, drop_first=True, dtype=float).to_numpy()
    X = np.column_stack([np.ones(len(sub)), X])
    y = sub["incorrect"].to_numpy(float)
    # perfect prediction: a level (or the original) with all answers alike
    kn = sub.groupby("level")["incorrect"].agg(["sum", "count"])
    flat = [lv for lv in levels if kn.loc[lv, "sum"] in (0, kn.loc[lv, "count"])]
    note = ""
    if flat:
        note = ("all answers alike at level(s) " + ", ".join(f"{lv:g}" for lv in flat)
                + ": odds ratio at the boundary, interval unreliable")
    try:
        beta, se, p, note = _fit_one(fit, sub, X, y, n_clusters, cov_type, note)
    except Exception as e:  # noqa: BLE001 — any failure becomes a note, never a crash
        return fail(f"GEE failed: {type(e).__name__}: {e}")
    rows = []
    for j, lv in enumerate(others, start=1):
        ok = np.isfinite(se[j]) and se[j] > 0
        rows.append((g, lv, float(np.exp(beta[j])),
                     float(np.exp(beta[j] - zq * se[j])) if ok else np.nan,
                     float(np.exp(beta[j] + zq * se[j])) if ok else np.nan,
                     float(p[j]) if ok else np.nan, note))
    return rows


def _fit_one(fit, sub: pd.DataFrame, X: np.ndarray, y: np.ndarray, n_clusters: int, cov_type: str,
             note: str):
    """One group's GEE: (coefficients, standard errors, p values, the note with what the
    fit warned of); raises when it fails."""
    GEE, families, cov_struct = fit
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = GEE(y, X, groups=sub["participant"].to_numpy(),
                    family=families.Binomial(), cov_struct=cov_struct.Exchangeable())
        res = model.fit(cov_type=cov_type if n_clusters > X.shape[1] else "robust")
        beta, se = np.asarray(res.params), np.asarray(res.bse)
        p = np.asarray(res.pvalues)
    if not np.all(np.isfinite(beta)):
        raise FloatingPointError("non-finite coefficients")
    msgs = sorted({str(w.message).split("\n")[0] for w in caught
                   if "converge" in str(w.message).lower()})
    if msgs:
        note = "; ".join(filter(None, [note, "GEE: " + msgs[0]]))
    if n_clusters <= X.shape[1]:
        note = "; ".join(filter(None, [note, "too few participants for the bias-reduced "
                                       "covariance: robust sandwich used"]))
    return beta, se, p, note


__all__ = ["gee_levels"]
