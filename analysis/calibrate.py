"""Calibrations from perception studies (``flipstudy calibrate``) and the shipped
default made from FwP's Table 2, as plain JSON-ready dicts of the schema that
:mod:`flipstudy.stimuli.calibration` reads (analysis imports no stimuli module; the
study layer, :mod:`flipstudy.study.calibrate`, reads study folders and designs).

Per error kind, variant (the angular-momentum profile), sign, task and character
style, the answers are pooled over participants and fitted with the analysis's
psignifit fit (:func:`~.stats.fit_psignifit`: the same function, priors and
threshold definition ``P(x*) = (1 + γ)/2`` as ``flipstudy analyze``).  Each kind
with more than one (variant, sign) also gets an entry pooled over them
(``pooled``), which the score uses only for a variant or sign that has no entry
of its own.  Simulated participants are left out unless ``include_simulated``
(then the file says so, and counts them).

The default calibration: Majkowska & Faloutsos 2007 (*Flipping with Physics*),
Section 7, Table 2: 19 participants, each motion (single forward and backward
somersaults: 2 clips, as :func:`~.simulate.paper_panel` assumes) shown twice, so
76 answers per cell; a rating r (% judged correct) is ``k = round(76 (1 − r))``
"incorrect" answers.  The four angular-momentum groups share one original (72 %),
the take-off group has its own (63 %); the empty smooth-increase 37 % cell is
left out (not filled).  Reitsma & Pollard 2003 report thresholds in their own
units (not FwP's percentages of the kinds measured here) and no table of
detection rates we could transcribe with certainty, so no other kind is
calibrated by default: those kinds are measured, not scored.

>>> t = fwp_counts()                       # what the default is fitted on
>>> t.head(2).to_dict("records")
[{'group': 'smooth-increase', 'level': 0.0, 'k': 21, 'n': 76, 'shared': True}, {'group': 'smooth-increase', 'level': 17.0, 'k': 22, 'n': 76, 'shared': False}]
>>> fn = fit_function((kinds.AM.name, "abrupt", -1, None), [0, 17, 25, 37, 50],
...                   [21, 13, 24, 51, 59], [76] * 5, n_real=19, n_samples=50)
>>> fn["kind"], fn["n_real"], len(fn["samples"]["threshold"]), 25 < fn["threshold"] < 45
('angular-momentum', 19, 50, True)
"""
from __future__ import annotations

import hashlib

import numpy as np
import pandas as pd

from flipstudy.errors import CalibrationError
from flipstudy.vocab import kinds

from .simulate import PAPER_TABLE2
from .stats import fit_psignifit, pooled_magnitudes, psychometric_curve
from .units import magnitude_unit

#: the file format :mod:`flipstudy.stimuli.calibration` reads
FORMAT = "flipstudy-calibration/1"
_PARAMS = ("threshold", "width", "gamma", "lambda")

#: FwP Section 7: participants, and answers per cell (19 × 2 clips × 2 showings)
FWP_PARTICIPANTS, FWP_N = 19, 76
FWP_SOURCE = {
    "name": "Majkowska & Faloutsos 2007, Table 2",
    "citation": ("A. Majkowska, P. Faloutsos. Flipping with Physics: Motion Editing for Acrobatics. "
                 "Eurographics/ACM SIGGRAPH Symposium on Computer Animation 2007, Section 7, Table 2"),
    "data": ("mean ratings (% judged correct) of 19 participants, each motion shown twice "
             "(2 clips: 76 answers per cell, k = round(76 (1 - rating))); minus signs lost in the "
             "text's d' parentheses restored; the empty smooth-increase 37 % cell left out"),
    "participants": FWP_PARTICIPANTS, "simulated": 0,
}
#: FwP group → (kind, variant, sign)
FWP_GROUPS = {"smooth-increase": (kinds.AM.name, "smooth", 1),
              "smooth-decrease": (kinds.AM.name, "smooth", -1),
              "abrupt-increase": (kinds.AM.name, "abrupt", 1),
              "abrupt-decrease": (kinds.AM.name, "abrupt", -1),
              "takeoff-increase": (kinds.TAKEOFF_ANGLE.name, None, 1)}


def _stable_seed(seed: int, key) -> int:
    return (int(seed) * 1_000_003 + int.from_bytes(hashlib.sha256(repr(key).encode()).digest()[:4], "big")) % 2**32


def _num(v):
    return None if v is None or not np.isfinite(v) else round(float(v), 4)


def fit_function(key: tuple, x, k, n, *, task="yes-no", n_real=0, n_simulated=0, source=0,
                 pooled=False, seed=0, n_samples=400, unit="%") -> dict:
    """One calibrated function (a ``functions`` entry of the file): psignifit on pooled
    counts (x magnitudes, k detected of n); ``key`` = (kind, variant, sign, style)."""
    kind, variant, sign, style = key
    fit = fit_psignifit(kind, np.asarray(x, float), np.asarray(k, float), np.asarray(n, float),
                        seed=_stable_seed(seed, key), n_samples=n_samples, task=task, unit=unit)
    return {"kind": kind, "variant": variant or None, "sign": int(sign), "task": task, "style": style,
            "pooled": bool(pooled), "unit": unit,
            "params": {a: round(float(v), 6) for a, v in fit.params.items()},
            "samples": {a: [round(float(v), 5) for v in fit.param_samples[a]] for a in _PARAMS},
            "threshold": _num(fit.threshold), "threshold_ci": [_num(fit.ci_low), _num(fit.ci_high)],
            "data": {"x": [float(v) for v in fit.x], "k": [float(v) for v in fit.k],
                     "n": [float(v) for v in fit.n]},
            "max_level": float(np.max(fit.x)), "n_real": int(n_real), "n_simulated": int(n_simulated),
            "source": int(source)}


def calibration_dict(functions, sources, description, include_simulated=False) -> dict:
    """The whole file."""
    return {"format": FORMAT, "description": description, "include_simulated": bool(include_simulated),
            "sources": list(sources), "functions": list(functions)}


def fwp_counts(groups=None) -> pd.DataFrame:
    """Table 2 as counts: group, level, k (judged incorrect), n (= 76), shared (the
    angular-momentum original, one cell for the four groups)."""
    rows = []
    for g, t in PAPER_TABLE2.items():
        if groups is not None and g not in groups:
            continue
        for lv, r in zip(t["levels"], t["rating"]):
            if r is None:
                continue
            rows.append((g, float(lv), round(FWP_N * (1 - r / 100)), FWP_N,
                         lv == 0 and FWP_GROUPS[g][0] == kinds.AM.name))
    return pd.DataFrame(rows, columns=["group", "level", "k", "n", "shared"])


def fwp_calibration(groups=None, *, pooled: bool = True, seed=0, n_samples=400) -> dict:
    """The default calibration from FwP Table 2 (module doc); ``groups``: only these
    of its groups (e.g. three angular-momentum groups, to predict the fourth);
    ``pooled``: add an entry per kind pooled over its groups (the shared original
    counted once)."""
    c = fwp_counts(groups)
    fns = []
    for g, sub in c.groupby("group", sort=False):
        kind, variant, sign = FWP_GROUPS[g]
        fns.append(fit_function((kind, variant, sign, None), sub["level"], sub["k"], sub["n"],
                                n_real=FWP_PARTICIPANTS, seed=seed, n_samples=n_samples))
    if pooled:
        for kind in dict.fromkeys(FWP_GROUPS[g][0] for g in c["group"]):
            sub = c[c["group"].map(lambda g: FWP_GROUPS[g][0]) == kind]
            if sub["group"].nunique() < 2:
                continue
            sub = sub[~sub["shared"]].pipe(lambda s: pd.concat([s, c[(c["group"].isin(sub["group"]))
                                                                 & c["shared"]].head(1)]))
            agg = sub.groupby("level")[["k", "n"]].sum().reset_index()
            fns.append(fit_function((kind, None, 0, None), agg["level"], agg["k"], agg["n"],
                                    n_real=FWP_PARTICIPANTS, pooled=True, seed=seed, n_samples=n_samples))
    src = dict(FWP_SOURCE, groups=sorted(c["group"].unique()))
    desc = ("Default calibration: real human data only (FwP 2007 Table 2). Kinds not listed are "
            "measured but not scored.")
    return calibration_dict(fns, [src], desc, False)


# ---------------------------------------------------------------- from studies

def calibrate_answers(df: pd.DataFrame, sources, *, seed: int = 0, n_samples: int = 400) -> dict:
    """A calibration from checked answers (:func:`~.io.load_responses`, participants
    already selected) with the columns ``kind_, variant, sign, task_, style_`` (each
    group's key), ``source`` (index into ``sources``), ``pid`` (a participant id unique
    over the sources) and ``simulated_``; ``sources``: one dict per study (name, path,
    sha256 of its files, participants, simulated)."""
    if df.empty:
        raise CalibrationError("no answers to calibrate on (simulated participants are left out "
                               "unless --include-simulated)")
    fns = []
    df = df.assign(detected_=np.where(df["task_"] == "2afc", df["detected"], df["incorrect"]))
    for key, sub in df.groupby(["kind_", "variant", "sign", "task_", "style_"], sort=False, dropna=False):
        fns += _fit_rows(sub, key, pooled=False, seed=seed, n_samples=n_samples)
    for (kind, task, style), sub in df.groupby(["kind_", "task_", "style_"], sort=False, dropna=False):
        if sub.groupby(["variant", "sign"], dropna=False).ngroups > 1:
            if "shared_copy" in sub.columns:          # a shared original counted once
                sub = sub[~sub["shared_copy"].astype(bool)]
            fns += _fit_rows(sub, (kind, None, 0, task, style), pooled=True, seed=seed, n_samples=n_samples)
    sim = bool(df["simulated_"].any())
    desc = (f"Calibrated by flipstudy calibrate from {len(sources)} stud{'y' if len(sources) == 1 else 'ies'}"
            + ("; INCLUDES SIMULATED PARTICIPANTS (--include-simulated): it describes the observer "
               "model, not people" if sim else "; real participants only"))
    return calibration_dict(fns, sources, desc, sim)


def _fit_rows(sub, key, *, pooled, seed, n_samples):
    kind, variant, sign, task, style = (None if isinstance(v, float) and np.isnan(v) else v for v in key)
    x, k, n = pooled_magnitudes(sub.assign(incorrect=sub["detected_"]), kind)
    if len(x) < 2:
        return []
    sim = sub["simulated_"].to_numpy(bool)
    return [fit_function((kind, variant, int(sign), style), x, k, n, task=task,
                         n_real=sub.loc[~sim, "pid"].nunique(), n_simulated=sub.loc[sim, "pid"].nunique(),
                         source=int(sub["source"].iloc[0]), pooled=pooled, seed=seed,
                         n_samples=n_samples, unit=magnitude_unit(kind))]


# ---------------------------------------------------------------- checks

AM_GROUPS = ("smooth-increase", "smooth-decrease", "abrupt-increase", "abrupt-decrease")


def _samples(fn: dict) -> np.ndarray:
    return np.column_stack([np.asarray(fn["samples"][a], float) for a in _PARAMS])


def predict_ratings(fn: dict, levels) -> pd.DataFrame:
    """Predicted mean rating (% judged correct) = 100 (1 − P(incorrect | x)) at each
    level under a calibrated function, the posterior median with its 95 % interval."""
    x = np.abs(np.asarray(levels, float))
    s = _samples(fn)
    P = psychometric_curve(x[None], s[:, 0:1], s[:, 1:2], s[:, 2:3], s[:, 3:4])
    med, lo, hi = np.quantile(100 * (1 - P), [0.5, 0.025, 0.975], axis=0)
    return pd.DataFrame({"level": x, "predicted": med, "pred_low": lo, "pred_high": hi})


def leave_one_out(seed: int = 0, n_samples: int = 400) -> pd.DataFrame:
    """Each angular-momentum group of FwP Table 2 predicted from the other three:
    calibrated on those three (:func:`fwp_calibration`), the held-out group (a variant
    and sign the calibration lacks) is scored by the entry pooled over them.  One row
    per held-out group and level: observed rating, predicted (95 % interval), error
    (predicted − observed, rating points)."""
    rows = []
    table = fwp_counts()
    for g in AM_GROUPS:
        cal = fwp_calibration([h for h in AM_GROUPS if h != g], seed=seed, n_samples=n_samples)
        # the held-out variant and sign have no entry: the score's lookup falls back to
        # the kind's pooled entry (flipstudy.stimuli.calibration.Calibration.lookup)
        fn = next(f for f in cal["functions"] if f["kind"] == kinds.AM.name and f["pooled"])
        obs = table[table["group"] == g]
        pred = predict_ratings(fn, obs["level"])
        rows.append(pred.assign(group=g, observed=[
            float(PAPER_TABLE2[g]["rating"][PAPER_TABLE2[g]["levels"].index(int(lv))]) for lv in obs["level"]]))
    out = pd.concat(rows, ignore_index=True)
    out["error"] = out["predicted"] - out["observed"]
    return out[["group", "level", "observed", "predicted", "pred_low", "pred_high", "error"]]


def simulated_check(*, truth=(30.0, 25.0, 0.2, 0.02), levels=(0, 10, 20, 30, 40, 50),
                    n_participants=19, repetitions=4, n_test=4000, bins=8, seed=0) -> dict:
    """Observers with a known psychometric function (``truth`` = threshold m, width,
    γ, λ): a simulated panel answers ``repetitions`` times per level, a function is
    calibrated on its answers (:func:`fit_function`), and ``n_test`` fresh answers at
    uniformly random magnitudes (0 … 1.2 × the largest level) are compared with what
    the calibration predicts: binned by predicted P(judged incorrect), each bin's
    observed rate with its 95 % Clopper–Pearson interval, and the prediction's 95 %
    interval over the calibration's posterior; ``inside``: the two intervals meet.
    Returns ``{"function", "bins": DataFrame(pred, pred_low, pred_high, observed, n, k,
    ci_low, ci_high, inside)}``."""
    from scipy.stats import beta
    rng = np.random.default_rng(seed)
    lv = np.asarray(levels, float)
    n = np.full(lv.shape, n_participants * repetitions, float)
    k = rng.binomial(n.astype(int), psychometric_curve(lv, *truth))
    fn = fit_function(("simulated", None, 1, None), lv, k, n, n_real=0, n_simulated=n_participants,
                      seed=seed)
    x = rng.uniform(0, 1.2 * lv.max(), n_test)
    answered = rng.random(n_test) < psychometric_curve(x, *truth)
    m_, w_, g_, l_ = (fn["params"][a] for a in _PARAMS)
    pred = psychometric_curve(x, m_, w_, g_, l_)
    edges = np.quantile(pred, np.linspace(0, 1, bins + 1))
    idx = np.clip(np.searchsorted(edges, pred, side="right") - 1, 0, bins - 1)
    rows = []
    for b in range(bins):
        m = idx == b
        nb, kb = int(m.sum()), int(answered[m].sum())
        lo = beta.ppf(0.025, kb, nb - kb + 1) if kb > 0 else 0.0
        hi = beta.ppf(0.975, kb + 1, nb - kb) if kb < nb else 1.0
        ps = _samples(fn)
        pb = psychometric_curve(x[m][None], ps[:, 0:1], ps[:, 1:2], ps[:, 2:3], ps[:, 3:4]).mean(1)
        plo, phi = np.quantile(pb, [0.025, 0.975])
        rows.append((float(pred[m].mean()), float(plo), float(phi), kb / nb, nb, kb, float(lo), float(hi)))
    t = pd.DataFrame(rows, columns=["pred", "pred_low", "pred_high", "observed", "n", "k", "ci_low",
                                    "ci_high"])
    # on the diagonal: the observed rate's binomial interval meets the prediction's interval
    t["inside"] = (t["pred_low"] <= t["ci_high"]) & (t["pred_high"] >= t["ci_low"])
    return {"function": fn, "bins": t}
