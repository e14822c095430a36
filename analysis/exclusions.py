"""Participant exclusions stated in the design before any data (its ``[exclusions]``
table), applied by ``analyze`` and reported as a flow table and figure
(recruited → completed → excluded, by rule → analysed).

The rules, in the order they are checked (a participant is counted under the
first rule they fail; ``exclusion_rules`` lists every rule they fail):

``incomplete``      (``require_complete``) a session that did not answer every trial
``catch accuracy``  percent of catch trials (``catch_groups``) answered "incorrect" below
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

from dataclasses import dataclass

import numpy as np
import pandas as pd

RULES = ("incomplete", "catch accuracy", "dropped frames", "response time")
DEFAULTS = {"catch_groups": [], "min_catch_accuracy_pct": 0.0, "max_flagged_pct": 100.0,
            "require_complete": False, "min_median_rt_ms": 0.0}


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
        out.append(f"catch accuracy: catch groups {', '.join(r['catch_groups'])} (gross errors; the right "
                   f"answer is 'incorrect'); a participant answering fewer than "
                   f"{r['min_catch_accuracy_pct']:g} % of them 'incorrect' is excluded")
    if r["max_flagged_pct"] < 100:
        out.append(f"dropped frames: a participant with more than {r['max_flagged_pct']:g} % of trials "
                   f"flagged for dropped frames is excluded")
    if r["min_median_rt_ms"] > 0:
        out.append(f"response time: a participant whose median response time is below "
                   f"{r['min_median_rt_ms']:g} ms is excluded")
    return out


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


def apply_exclusions(df: pd.DataFrame, rules: dict | None, *, include_incomplete: bool = False
                     ) -> ExclusionReport:
    """Apply the ``[exclusions]`` ``rules`` (a dict of its keys; missing keys: no rule)
    to a response table (one row per answer; rows marked ``shared_copy`` are copies and
    are not counted).  A participant none of whose sessions is complete (column
    ``complete``) is counted as not completed (rule ``incomplete``) unless
    ``include_incomplete``; with ``require_complete`` one incomplete session is enough."""
    r = {**DEFAULTS, **(rules or {})}
    rows = df.copy()
    own = ~rows["shared_copy"].astype(bool) if "shared_copy" in rows.columns else pd.Series(True, index=rows.index)
    rows["catch"] = rows["group"].astype(str).isin(set(r["catch_groups"]))
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
    hit = (catch["response"].astype(str) == "incorrect").groupby(bp[catch.index])
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


def flow_figure(flow: pd.DataFrame):
    """The flow as a figure: one horizontal bar per stage, its N written beside it."""
    import matplotlib.pyplot as plt
    from .figures import style
    with style():
        fig, ax = plt.subplots(figsize=(5.5, 0.45 * len(flow) + 1.0))
        y = np.arange(len(flow))[::-1]
        colours = ["#0072B2" if not s.startswith("excluded") else "#D55E00" for s in flow["stage"]]
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
