"""Issue 32: the exclusion rules of the design's [exclusions] table, applied by analyze
before anything is computed, reported as a flow table (+ figure), excluded rows kept."""
import json

import pandas as pd
import pytest
from hypothesis import given, settings, strategies as st

from flipstudy.analysis.exclusions import RULES, apply_exclusions
from flipstudy.analysis.pipeline import analyze
from flipstudy.analysis.simulate import paper_panel

RULES_CATCH = {"catch_groups": ["catch"], "min_catch_accuracy_pct": 75.0, "min_median_rt_ms": 200.0}


def panel_with_catch(n=8, seed=3):
    """A simulated panel plus 4 catch trials per participant (a gross error, right answer
    'incorrect'); P02 misses 3 of them, P03 answers everything in 100 ms."""
    df = paper_panel(n, seed=seed)
    extra = []
    for p in df["participant"].unique():
        for k in range(4):
            wrong = p == "P02" and k < 3
            extra.append({"participant": p, "session": f"{p}-S1", "trial": 1000 + k, "stimulus": f"backflip_catch_{k}",
                          "group": "catch", "level": 300.0, "repetition": 1, "response": "correct" if wrong else "incorrect",
                          "rt_ms": 900, "shown_ms": 2000, "timestamp": "2026-01-05T12:00:00", "clip": "backflip",
                          "kind": "angular-momentum"})
    df = pd.concat([df, pd.DataFrame(extra)], ignore_index=True)
    df.loc[df["participant"] == "P03", "rt_ms"] = 100
    return df


def test_rules_name_the_participants_who_fail_them():
    rep = apply_exclusions(panel_with_catch(), RULES_CATCH)
    part = rep.participants.set_index("participant")
    assert part.at["P02", "exclusion_rule"] == "catch accuracy"
    assert part.at["P02", "catch_accuracy_pct"] == pytest.approx(25.0)
    assert part.at["P03", "exclusion_rule"] == "response time"
    assert part.at["P03", "median_rt_ms"] == 100
    assert set(part.index[part["excluded"]]) == {"P02", "P03"}
    flow = dict(zip(rep.flow["stage"], rep.flow["n"]))
    assert flow == {"recruited": 8, "completed": 8, "excluded: catch accuracy": 1, "excluded: dropped frames": 0,
                    "excluded: response time": 1, "analysed": 6}
    # every row kept, the rule named on each row of an excluded participant
    assert len(rep.rows) == len(panel_with_catch())
    assert set(rep.rows.loc[rep.rows["participant"] == "P02", "exclusion_rule"]) == {"catch accuracy"}
    kept = rep.kept()
    assert not kept["catch"].any() and set(kept["participant"]) == set(part.index) - {"P02", "P03"}


def test_dropped_frames_and_incomplete_rules():
    df = panel_with_catch()
    df["playback_flagged"] = False
    df.loc[(df["participant"] == "P04") & (df["trial"] % 2 == 0), "playback_flagged"] = True   # about half
    df["complete"] = df["participant"] != "P05"
    rep = apply_exclusions(df, {"max_flagged_pct": 20.0, "require_complete": True})
    part = rep.participants.set_index("participant")
    assert part.at["P04", "exclusion_rule"] == "dropped frames" and 40 < part.at["P04", "flagged_pct"] < 60
    assert part.at["P05", "exclusion_rule"] == "incomplete"
    flow = dict(zip(rep.flow["stage"], rep.flow["n"]))
    assert flow["completed"] == 7 and flow["analysed"] == 6


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 4), st.integers(50, 2000), st.booleans(), st.booleans()),
                min_size=1, max_size=12),
       st.floats(0, 100), st.floats(0, 100), st.floats(0, 1500), st.booleans())
def test_the_flow_adds_up(people, min_catch, max_flag, min_rt, require):
    rows = []
    for i, (hits, rt, flagged, complete) in enumerate(people):
        for k in range(4):
            rows.append({"participant": f"p{i}", "group": "catch", "response": "incorrect" if k < hits else "correct",
                         "rt_ms": rt, "playback_flagged": flagged and k == 0, "complete": complete})
        rows.append({"participant": f"p{i}", "group": "g", "response": "correct", "rt_ms": rt,
                     "playback_flagged": False, "complete": complete})
    rep = apply_exclusions(pd.DataFrame(rows), {"catch_groups": ["catch"], "min_catch_accuracy_pct": min_catch,
                                                "max_flagged_pct": max_flag, "min_median_rt_ms": min_rt,
                                                "require_complete": require})
    f = dict(zip(rep.flow["stage"], rep.flow["n"]))
    assert f["recruited"] == len(people)
    assert f["completed"] - sum(f[f"excluded: {k}"] for k in RULES[1:]) == f["analysed"]
    # the analysed participants pass every rule, measured here from the raw rows
    for i, (hits, rt, flagged, complete) in enumerate(people):
        # no complete session: left out (analyze's default) whether or not require_complete
        passes = complete and (hits / 4 * 100 >= min_catch or min_catch == 0) \
            and (100 / 5 * flagged <= max_flag) and rt >= min_rt
        assert passes == (f"p{i}" in set(rep.kept()["participant"])), (i, hits, rt, flagged, complete)


def test_analyze_applies_the_rules_before_anything_and_reports_the_flow(tmp_path):
    df = panel_with_catch()
    r = analyze(df, tmp_path, exclusions=RULES_CATCH, psychometric="none", gee=False, n_boot=50)
    # the same analysis of the rows selected by hand (independent of the rule code)
    by_hand = df[~df["participant"].isin(["P02", "P03"]) & (df["group"] != "catch")]
    ref = analyze(by_hand, None, psychometric="none", gee=False, n_boot=50)
    pd.testing.assert_frame_equal(r.table, ref.table)
    assert "catch" not in set(r.table["group"])
    flow = pd.read_csv(tmp_path / "flow.csv")
    assert flow["stage"].tolist()[0] == "recruited" and flow["n"].tolist()[-1] == 6
    assert (tmp_path / "flow.png").stat().st_size > 1000 and (tmp_path / "flow.pdf").is_file()
    kept = pd.read_csv(tmp_path / "responses_exclusions.csv", keep_default_na=False)
    assert len(kept) == len(df)                               # excluded rows stay in the data
    assert set(kept.loc[kept["participant"] == "P03", "exclusion_rule"]) == {"response time"}
    notes = (tmp_path / "notes.md").read_text()
    assert "## Exclusions" in notes and "catch accuracy" in notes and "| analysed | 6 |" in notes
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["flow"][-1] == {"stage": "analysed", "n": 6} and len(summary["exclusion_rules"]) == 2
