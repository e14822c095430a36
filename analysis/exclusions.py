"""Participant exclusions stated in the design before any data (its ``[exclusions]``
table), applied by ``analyze`` and reported as a flow table and figure
(recruited → completed → excluded, by rule → analysed).

The rules, in the order they are checked (a participant is counted under the
first rule they fail; ``exclusion_rules`` lists every rule they fail):

``incomplete``      (``require_complete``) a session that did not answer every trial
``catch accuracy``  percent of catch trials (the rows of the ``catch_groups``: the trials
                    the participant saw there, never the shared original) answered right
                    ("incorrect" to a gross error, "correct" to the group's own original) below
                    ``min_catch_accuracy_pct`` (a participant with no catch trial fails it
                    when the rule is set: the check could not be made)
``dropped frames``  percent of trials flagged for dropped frames (``playback_flagged``,
                    first showings) above ``max_flagged_pct``
``response time``   median ``rt_ms`` below ``min_median_rt_ms``

Excluded participants' rows stay in the data (columns ``excluded``,
``exclusion_rule``); catch trials are never analysed as test trials.

>>> df = pd.DataFrame({"participant": ["a", "a", "b", "b"], "group": ["catch", "g"] * 2,
...                    "response": ["incorrect", "correct", "correct", "correct"],
...                    "rt_ms": [800, 900, 700, 650]})
>>> rep = apply_exclusions(df, {"catch_groups": ["catch"], "min_catch_accuracy_pct": 50})
>>> rep.flow["n"].tolist(), rep.rows["exclusion_rule"].tolist()
([2, 2, 1, 0, 0, 1], ['', '', 'catch accuracy', 'catch accuracy'])
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from flipstudy.errors import ResponsesError
from flipstudy.vocab.online import EXCLUSION_FIELDS

RULES = ("incomplete", "catch accuracy", "dropped frames", "response time")
#: each rule's default (no participant excluded): the design's ``[exclusions]`` table's own
DEFAULTS = {k: list(d) if isinstance(d, list) else d for k, (_, d, _) in EXCLUSION_FIELDS.items()}


def _truthy(col: pd.Series) -> pd.Series:
    if col.dtype == bool:
        return col
    return col.astype(str).str.strip().str.lower().isin({"1", "true", "yes", "1.0"})


def rule_sentences(rules: dict) -> list[str]:
    """The rules as sentences (for ``notes.md`` and the Psych-DS metadata)."""
    r = {**DEFAULTS, **(rules or {})}
    out = []
    if r["require_complete"]:
        out.append("incomplete: a participant with a session that did not answer every trial is excluded")
    if r["catch_groups"]:
        out.append(f"catch accuracy: catch groups {', '.join(r['catch_groups'])} (gross errors, whose right "
                   f"answer is 'incorrect', and any original of their own, whose right answer is "
                   f"'correct'); a participant answering fewer than {r['min_catch_accuracy_pct']:g} % of "
                   f"them right is excluded")
    if r["max_flagged_pct"] < 100:
        out.append(f"dropped frames: a participant with more than {r['max_flagged_pct']:g} % of trials "
                   f"flagged for dropped frames is excluded")
    if r["min_median_rt_ms"] > 0:
        out.append(f"response time: a participant whose median response time is below "
                   f"{r['min_median_rt_ms']:g} ms is excluded")
    return out


def right_answer(catch: pd.DataFrame) -> np.ndarray:
    """Was each catch trial answered right: "incorrect" to a gross error, "correct" to
    the catch group's own original (level 0)?

    >>> right_answer(pd.DataFrame({"level": [100, 100, 0, 0],
    ...                            "response": ["incorrect", "correct", "correct", "incorrect"]})).tolist()
    [True, False, True, False]
    """
    resp = catch["response"].astype(str).to_numpy()
    if "level" not in catch.columns:
        return resp == "incorrect"
    original = pd.to_numeric(catch["level"], errors="coerce").to_numpy() == 0
    return np.where(original, resp == "correct", resp == "incorrect")


@dataclass
class ExclusionReport:
    """``rows``: the table with ``catch`` (bool), ``excluded`` (bool), ``exclusion_rule``
    (first rule failed, "" if none) and ``exclusion_rules`` (every rule failed, "; ");
    ``participants``: one row per participant with the measures and the rule;
    ``flow``: ``stage``, ``n`` (recruited, completed, one row per rule, analysed);
    ``rules``: the rules as sentences."""
    rows: pd.DataFrame
    participants: pd.DataFrame
    flow: pd.DataFrame
    rules: list

    def kept(self) -> pd.DataFrame:
        """The rows the analysis uses: not excluded, not catch trials."""
        return self.rows[~self.rows["excluded"] & ~self.rows["catch"]].reset_index(drop=True)

    def answers(self) -> pd.DataFrame:
        """The answers as given, once each, every one in its own group: a shared
        original's answer in group ``original`` (not in the group that holds its first
        copy); without the analysis's helper columns."""
        from .io import SHARED_ORIGINAL
        rows = self.rows
        if "shared_copy" in rows.columns:
            rows = rows[~rows["shared_copy"].astype(bool)].copy()
            rows.loc[rows["shared_original"].astype(bool), "group"] = SHARED_ORIGINAL
        return rows.drop(columns=[c for c in ("shared_copy", "shared_original", "incorrect", "detected")
                                  if c in rows.columns])


def apply_exclusions(df: pd.DataFrame, rules: dict | None, *, include_incomplete: bool = False
                     ) -> ExclusionReport:
    """Apply the ``[exclusions]`` ``rules`` (a dict of its keys; missing keys: no rule)
    to a response table (one row per answer; rows marked ``shared_copy`` are copies and
    are not counted).  A participant none of whose sessions is complete (column
    ``complete``) is counted as not completed (rule ``incomplete``) unless
    ``include_incomplete``; with ``require_complete`` one incomplete session is enough.
    A catch trial is a row of a catch group: a shared original's answer never is one
    (read the table with ``load_responses(..., catch_groups=...)``, which gives a
    catch group none of its copies)."""
    r = {**DEFAULTS, **(rules or {})}
    rows = df.copy()
    own = ~rows["shared_copy"].astype(bool) if "shared_copy" in rows.columns else pd.Series(True, index=rows.index)
    shared = rows["shared_original"].astype(bool) if "shared_original" in rows.columns \
        else pd.Series(False, index=rows.index)
    in_catch = rows["group"].astype(str).isin(set(r["catch_groups"]))
    if (in_catch & shared).any():
        g = rows.loc[in_catch & shared, "group"].iloc[0]
        raise ResponsesError(f"responses table: the shared originals' answers were copied into the catch "
                             f"group {g!r}; read the table with load_responses(..., catch_groups="
                             f"{list(r['catch_groups'])!r})")
    rows["catch"] = in_catch
    pid = rows["participant"].astype(str)
    base = rows[own]
    bp = pid[own]
    people = list(dict.fromkeys(bp))
    m = pd.DataFrame(index=pd.Index(people, name="participant"))
    m["trials"] = bp.value_counts().reindex(people).to_numpy()
    if "complete" in base.columns:
        done = _truthy(base["complete"]).groupby(bp)
        m["complete"] = done.all().reindex(people).to_numpy()
        m["finished"] = done.any().reindex(people).to_numpy()
    else:
        m["complete"] = m["finished"] = True
    catch = base[base["catch"]]
    hit = pd.Series(right_answer(catch), index=catch.index).groupby(bp[catch.index])
    m["catch_trials"] = hit.size().reindex(people).fillna(0).astype(int).to_numpy()
    m["catch_accuracy_pct"] = (hit.mean() * 100).reindex(people).to_numpy()
    if "playback_flagged" in base.columns:
        first = base["repeat"].fillna(0).astype(float) == 0 if "repeat" in base.columns else pd.Series(True, index=base.index)
        m["flagged_pct"] = (_truthy(base["playback_flagged"])[first].groupby(bp[first]).mean() * 100
                            ).reindex(people).to_numpy()
    else:
        m["flagged_pct"] = np.nan
    m["median_rt_ms"] = pd.to_numeric(base["rt_ms"], errors="coerce").groupby(bp).median().reindex(
        people).to_numpy() if "rt_ms" in base.columns else np.nan
    fails = {
        "incomplete": ~m["complete" if r["require_complete"] else "finished"].astype(bool)
        if r["require_complete"] or not include_incomplete else pd.Series(False, index=m.index),
        "catch accuracy": (m["catch_accuracy_pct"].isna() | (m["catch_accuracy_pct"] < r["min_catch_accuracy_pct"]))
        if r["catch_groups"] and r["min_catch_accuracy_pct"] > 0 else pd.Series(False, index=m.index),
        "dropped frames": (m["flagged_pct"] > r["max_flagged_pct"]).fillna(False),
        "response time": (m["median_rt_ms"] < r["min_median_rt_ms"]).fillna(False),
    }
    failed = pd.DataFrame(fails).astype(bool)
    m["exclusion_rules"] = ["; ".join(k for k in RULES if failed.at[p, k]) for p in m.index]
    m["exclusion_rule"] = [next((k for k in RULES if failed.at[p, k]), "") for p in m.index]
    m["excluded"] = m["exclusion_rule"] != ""
    rows["excluded"] = pid.map(m["excluded"]).fillna(False).astype(bool)
    rows["exclusion_rule"] = pid.map(m["exclusion_rule"]).fillna("")
    rows["exclusion_rules"] = pid.map(m["exclusion_rules"]).fillna("")
    first_rule = m["exclusion_rule"]
    n = len(m)
    flow = [("recruited", n), ("completed", n - int((first_rule == "incomplete").sum()))]
    flow += [(f"excluded: {k}", int((first_rule == k).sum())) for k in RULES[1:]]
    flow += [("analysed", int((~m["excluded"]).sum()))]
    return ExclusionReport(rows=rows, participants=m.reset_index(),
                           flow=pd.DataFrame(flow, columns=["stage", "n"]), rules=rule_sentences(r))


#: the table ``import-web`` writes beside ``web/responses.csv``: the runs it kept out
KEPT_OUT = "quarantine.csv"


def kept_out_at_import(tables) -> dict:
    """``{reason: runs}`` that ``import-web`` kept out of the response tables ``tables``
    (paths; each one's ``quarantine.csv`` beside it, rows naming a whole run), e.g.
    ``{"no consent": 2, "conflict": 1}``; empty for tables without one."""
    out = {}
    for t in tables:
        p = Path(t).parent / KEPT_OUT
        if not p.is_file():
            continue
        with open(p, newline="", encoding="utf-8") as f:
            for row in csv.DictReader(f):
                if row.get("what") == "run" and row.get("reason"):
                    out[row["reason"]] = out.get(row["reason"], 0) + 1
    return out


def with_kept_out(flow: pd.DataFrame, kept_out: dict | None) -> pd.DataFrame:
    """``flow`` with a first stage per reason ``import-web`` kept runs out of the
    tables (``kept out at import: no consent``, ...), when it kept any.

    >>> f = pd.DataFrame([("recruited", 3), ("analysed", 3)], columns=["stage", "n"])
    >>> with_kept_out(f, {"no consent": 1})["stage"].tolist()
    ['kept out at import: no consent', 'recruited', 'analysed']
    """
    if not kept_out:
        return flow
    first = pd.DataFrame([(f"kept out at import: {k}", int(n)) for k, n in sorted(kept_out.items())],
                         columns=["stage", "n"])
    return pd.concat([first, flow], ignore_index=True)


def flow_figure(flow: pd.DataFrame):
    """The flow as a figure: one horizontal bar per stage, its N written beside it."""
    import matplotlib.pyplot as plt
    from .figures import style
    with style():
        fig, ax = plt.subplots(figsize=(5.5, 0.45 * len(flow) + 1.0))
        y = np.arange(len(flow))[::-1]
        colours = ["#0072B2" if not s.startswith(("excluded", "kept out")) else "#D55E00" for s in flow["stage"]]
        ax.barh(y, flow["n"], color=colours)
        for yi, v in zip(y, flow["n"]):
            ax.text(v, yi, f" {v}", va="center", fontsize=8)
        ax.set_yticks(y, flow["stage"])
        ax.set_xlabel("participants")
        ax.set_xlim(0, max(1, int(flow["n"].max())) * 1.15)
        from matplotlib.ticker import MaxNLocator
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))     # whole participants
        ax.set_title("Participant flow (exclusion rules stated in the design)")
        fig.tight_layout()
    return fig
