"""Response tables with 2AFC or QUEST+ rows: which rows go where.

Rows carry ``task`` (``yes-no`` | ``2afc``) and ``method`` (``constant`` |
``quest+``); a table without these columns is yes/no constant stimuli, analysed
as it always was (:mod:`.core`, :mod:`.stats`).  Here:

* yes/no constant rows: the yes/no table, GEE and psignifit fits, unchanged;
* 2AFC constant rows: :mod:`.forced_choice` (d′ = √2·z(P correct)) and psignifit
  fits with γ = ½;
* QUEST+ rows: no d′ table (their levels are chosen by the procedure); a
  per-participant threshold each (:mod:`.thresholds`);
* every group, adaptive or constant: per-participant x* with the same model, and
  the group's distribution.

>>> import pandas as pd
>>> has_tasks(pd.DataFrame({"task": ["yes-no"], "method": ["constant"]}))
False
>>> has_tasks(pd.DataFrame({"task": ["2afc"]}))
True
"""
from __future__ import annotations

import pandas as pd

from .core import summarize
from .forced_choice import summarize_2afc
from .stats import fit_psychometric


def _col(df, name, default):
    return df[name] if name in df.columns else pd.Series(default, index=df.index)


def has_tasks(df: pd.DataFrame) -> bool:
    """Whether the answers hold 2AFC or QUEST+ rows (otherwise: the yes/no analysis as before)."""
    return bool((_col(df, "task", "yes-no") == "2afc").any()
                or (_col(df, "method", "constant") == "quest+").any())


def split(df: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """(yes/no constant, 2AFC constant, QUEST+) rows."""
    task, method = _col(df, "task", "yes-no"), _col(df, "method", "constant")
    quest = (method == "quest+").to_numpy()
    afc = (task == "2afc").to_numpy() & ~quest
    return (df[~quest & ~afc].reset_index(drop=True), df[afc].reset_index(drop=True),
            df[quest].reset_index(drop=True))


def summarize_tasks(df: pd.DataFrame, correction, n_boot, seed, ci):
    """The long table (``task`` column after ``level``; 2AFC rows add ``n_correct``,
    ``p_correct``), the per-participant d′ and notes, over the constant-stimuli rows."""
    yn, afc, quest = split(df)
    tables, parts, notes = [], [], []
    if len(yn):
        t, p, n = summarize(yn, correction=correction, n_boot=n_boot, seed=seed, ci=ci)
        t.insert(2, "task", "yes-no")
        p.insert(3, "task", "yes-no")
        tables.append(t), parts.append(p), notes.extend(n)
    if len(afc):
        t, p, n = summarize_2afc(afc, correction=correction, n_boot=n_boot, seed=seed, ci=ci)
        tables.append(t), parts.append(p), notes.extend(n)
    if len(quest):
        notes.append(f"QUEST+ groups ({', '.join(dict.fromkeys(quest['group']))}): "
                     f"{len(quest)} answers at levels the procedure chose; they have no d′ table, "
                     f"their thresholds are per participant (thresholds_participants.csv).")
    if not tables:
        return pd.DataFrame(columns=["group", "level", "task", "n"]), pd.DataFrame(
            columns=["participant", "group", "level", "task", "n", "dprime"]), notes
    cols = list(dict.fromkeys(c for t in tables for c in t.columns))
    table = pd.concat([t.reindex(columns=cols) for t in tables], ignore_index=True)
    for c in ("n_incorrect", "n_correct"):
        if c in table:
            table[c] = table[c].astype("Int64")
    if "corrected" in table:
        table["corrected"] = table["corrected"].astype(bool)
    part = pd.concat(parts, ignore_index=True)
    for c in ("n_incorrect", "n_correct"):
        if c in part:
            part[c] = part[c].astype("Int64")
    return table, part, notes


def fit_tasks(df: pd.DataFrame, psychometric, ci, seed):
    """psignifit fits of the constant groups: yes/no as before, 2AFC with γ = ½; and notes."""
    yn, afc, _ = split(df)
    fits, notes = [], []
    for sub, task in ((yn, "yes-no"), (afc, "2afc")):
        if len(sub):
            f, n = fit_psychometric(sub, psychometric, ci=ci, seed=seed, task=task)
            for x in f:
                x.task = task
            fits += f
            notes += n
    return fits, notes


def thresholds_frame(fits) -> pd.DataFrame:
    """One row per fitted group, with its task."""
    if not fits:
        return pd.DataFrame(columns=["group", "task", "method", "threshold", "threshold_ci_low",
                                     "threshold_ci_high", "reached"])
    t = pd.DataFrame([f.row() for f in fits])
    t.insert(1, "task", [getattr(f, "task", "yes-no") for f in fits])
    return t
