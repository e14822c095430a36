"""Per-participant detection thresholds x* with 95 % posterior intervals, for
adaptive (QUEST+) and constant-stimuli groups alike, and each group's distribution.

Every participant's answers to a group are replayed through the group's QUEST+
model (:mod:`.adaptive`: the analysis's psychometric function, the grid posterior
over m, width and γ): QUEST+ rows through :class:`~.adaptive.Quest` in the order
they were answered, which recomputes the state the session stored, and constant
rows through the same posterior (:class:`~.adaptive_sim.QuestBatch`), so both
kinds of group give x* with the one definition, ``P(x*) = (1 + γ)/2``.

A group's model needs its grid and quest+ settings, which the design holds and
the responses do not: ``specs`` maps a group to ``(levels, task, QuestSettings)``
(``flipstudy analyze`` reads them from the study's design).  Without a spec a
QUEST+ group's last stored ``quest_threshold`` / ``quest_ci_*`` is used, and a
constant group's model is built on the levels it was answered at.

A constant ``pose-rate`` group (column ``kind``) is replayed against the hold
time 1000/N ms of its levels N (:mod:`.units`), as its pooled fit is, so its x*
are in ms; a QUEST+ pose-rate group is replayed on N as its session ran it.

>>> import pandas as pd
>>> from flipstudy.analysis.adaptive import Observer
>>> o, rng = Observer(20.0, 10.0, 0.5, 0.02, "2afc"), np.random.default_rng(0)
>>> lv = np.tile([10.0, 20.0, 30.0, 40.0], 10)
>>> df = pd.DataFrame({"participant": "P1", "group": "g", "task": "2afc", "method": "constant",
...                    "level": lv, "detected": [o.answer(x, rng) for x in lv]})
>>> t, notes = participant_thresholds(df)
>>> row = t.iloc[0]
>>> int(row["n_trials"]), bool(row["ci_low"] < 20 < row["ci_high"]), row["source"]
(40, True, 'replayed')
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .adaptive import LEVEL_ATOL, Quest, QuestSettings, quest_model
from .adaptive_sim import QuestBatch
from flipstudy.errors import ResponsesError
from .io import group_order
from .units import group_kinds, is_pose_rate, magnitudes

PARTICIPANT_COLUMNS = ["participant", "group", "task", "method", "n_trials", "threshold", "ci_low",
                       "ci_high", "sd", "source", "stored_threshold", "stored_ci_low",
                       "stored_ci_high", "stored_matches"]
GROUP_COLUMNS = ["group", "task", "method", "n_participants", "mean", "sd", "q25", "median", "q75",
                 "mean_ci_width", "pooled_threshold", "pooled_ci_low", "pooled_ci_high"]
STORED = ("quest_threshold", "quest_ci_low", "quest_ci_high")
#: a replayed threshold equals the stored one within this (percent; responses.csv has 4 decimals)
STORED_ATOL = 1e-3


def _col(df, name, default):
    return df[name] if name in df.columns else pd.Series(default, index=df.index)


def _answer_order(sub: pd.DataFrame) -> pd.DataFrame:
    keys = [c for c in ("session", "trial") if c in sub.columns]
    if not keys:
        return sub
    s = sub.assign(_s=pd.to_numeric(sub["session"], errors="coerce") if "session" in keys else 0,
                   _t=pd.to_numeric(sub["trial"], errors="coerce") if "trial" in keys else 0)
    return s.sort_values(["_s", "_t"], kind="stable").drop(columns=["_s", "_t"])


def participant_thresholds(df: pd.DataFrame, specs: dict | None = None) -> tuple[pd.DataFrame, list[str]]:
    """One row per participant × group (columns :data:`PARTICIPANT_COLUMNS`) and notes.

    ``df``: checked answers (:func:`~.io.load_responses`) with column ``detected``;
    ``task`` / ``method`` default to yes-no / constant.  ``source``: ``replayed``
    (through the model) or ``stored`` (the session's last QUEST+ state, no spec);
    ``stored_matches``: whether a replay equals the stored state to
    :data:`STORED_ATOL` (NaN when nothing was stored)."""
    specs = specs or {}
    task = _col(df, "task", "yes-no")
    method = _col(df, "method", "constant")
    rows, notes, mismatched = [], [], []
    kinds = group_kinds(df)
    for g in group_order(df["group"].unique()):
        in_g = (df["group"] == g).to_numpy()
        for (t, m) in dict.fromkeys(zip(task[in_g], method[in_g])):
            sub_g = df[in_g & (task == t).to_numpy() & (method == m).to_numpy()]
            spec = specs.get(g)
            kind = kinds.get(g) if m == "constant" else None       # a hold time in ms: constant only
            if spec is not None:
                levels = np.unique(magnitudes(spec[0], kind)) if is_pose_rate(kind) else spec[0]
                model = quest_model(levels, spec[1], spec[2])
            elif m == "constant":
                mags = np.unique(magnitudes(sub_g["level"].to_numpy(float), kind))
                if len(mags[mags > 0] if t == "2afc" else mags) < 2:
                    notes.append(f"{g}: answers at a single error magnitude, no per-participant "
                                 f"thresholds")
                    continue
                model = quest_model(mags, t, QuestSettings())
            else:
                model = None
                notes.append(f"{g}: no design for this quest+ group (its grid and settings): the "
                             f"session's stored thresholds are used, not recomputed")
            for pid, sub in sub_g.groupby("participant", sort=True):
                sub = _answer_order(sub)
                x = magnitudes(sub["level"].to_numpy(float), kind)
                det = sub["detected"].to_numpy().astype(bool)
                stored = [float(pd.to_numeric(sub[c], errors="coerce").iloc[-1]) if c in sub.columns
                          else np.nan for c in STORED]
                if model is None:
                    est = dict(zip(("threshold", "ci_low", "ci_high"), stored), sd=np.nan)
                    source = "stored"
                elif m == "quest+":
                    q = Quest.new(model)
                    for lv, d in zip(x, det):
                        q.update(lv, d)
                    est, source = q.threshold(), "replayed"
                else:
                    idx = np.abs(x[:, None] - model.levels[None, :]).argmin(1)
                    ok = np.abs(model.levels[idx] - x) <= LEVEL_ATOL
                    if not ok.all():
                        raise ResponsesError(f"group {g}: participant {pid} answered level "
                                             f"{x[~ok][0]:g}, which is not on the group's grid "
                                             f"({model.levels[0]:g} … {model.levels[-1]:g})")
                    nl = len(model.levels)
                    b = QuestBatch.from_counts(model, np.bincount(idx, det, nl), np.bincount(idx, None, nl))
                    est, source = {k: float(v[0]) for k, v in b.summary().items()}, "replayed"
                match = np.nan
                if source == "replayed" and np.isfinite(stored[0]):
                    # the export writes 4 decimals: equal to that precision
                    match = bool(np.allclose([est["threshold"], est["ci_low"], est["ci_high"]], stored,
                                             rtol=0, atol=STORED_ATOL))
                    if not match:
                        mismatched.append(f"{pid}/{g}")
                rows.append([pid, g, t, m, len(sub), est["threshold"], est["ci_low"], est["ci_high"],
                             est["sd"], source, *stored, match])
    if mismatched:
        notes.append("Replayed QUEST+ thresholds differ from the ones the session stored for "
                      + ", ".join(mismatched) + " (the design's grid or settings changed since?)")
    out = pd.DataFrame(rows, columns=PARTICIPANT_COLUMNS)
    return out, notes


def group_thresholds(per_participant: pd.DataFrame, fits=()) -> pd.DataFrame:
    """Each group's distribution of per-participant x* (mean, SD, quartiles, mean
    interval width) beside the pooled psignifit x* of constant groups (``fits``)."""
    pooled = {f.group: f for f in fits}
    rows = []
    for (g, t, m), sub in per_participant.groupby(["group", "task", "method"], sort=False):
        x = sub["threshold"].to_numpy(float)
        x = x[np.isfinite(x)]
        q25, med, q75 = np.quantile(x, [0.25, 0.5, 0.75]) if len(x) else (np.nan,) * 3
        f = pooled.get(g) if m == "constant" else None
        rows.append([g, t, m, len(x), x.mean() if len(x) else np.nan,
                     x.std(ddof=1) if len(x) > 1 else np.nan, q25, med, q75,
                     float(np.nanmean(sub["ci_high"] - sub["ci_low"])) if len(sub) else np.nan,
                     f.threshold if f else np.nan, f.ci_low if f else np.nan, f.ci_high if f else np.nan])
    out = pd.DataFrame(rows, columns=GROUP_COLUMNS)
    order = {g: i for i, g in enumerate(group_order(out["group"]))}
    return out.sort_values("group", key=lambda s: s.map(order), kind="stable").reset_index(drop=True)
