"""Issue 42, item 1: catch trials by construction.  A catch group's rows are the catch
trials, counted once per showing; the shared original stays in group ``original`` (the
level 0 every error group compares against, kept in the tables), whatever the order of
the rows."""
import pandas as pd
import pytest
from hypothesis import example, given, settings, strategies as st

from flipstudy.analysis.pipeline import analyze

RULES = {"catch_groups": ["catch"], "min_catch_accuracy_pct": 75.0}
#: the sessions guide's catch group without an original of its own (levels = [100]) beside
#: two groups that share the clip's original and a take-off group with its own
STIMULI = [("backflip_original", "original", "angular-momentum", 0.0),
           ("backflip_smooth-increase_25", "smooth-increase", "angular-momentum", 25.0),
           ("backflip_abrupt-decrease_25", "abrupt-decrease", "angular-momentum", 25.0),
           ("backflip_takeoff-increase_0", "takeoff-increase", "takeoff-angle", 0.0),
           ("backflip_takeoff-increase_20", "takeoff-increase", "takeoff-angle", 20.0),
           ("backflip_catch_100", "catch", "angular-momentum", 100.0)]
#: attentive (right everywhere), "correct" to everything (misses the catch trials)
ANSWER = {"att": lambda level: "incorrect" if level else "correct", "yes": lambda level: "correct"}


def table(reps=2):
    rows = []
    for p, answer in ANSWER.items():
        for rep in range(1, reps + 1):
            for stim, group, kind, level in STIMULI:
                rows.append({"participant": p, "session": 1, "trial": len(rows) % 12 + 1, "stimulus": stim,
                             "group": group, "kind": kind, "clip": "backflip", "level": level,
                             "repetition": rep, "response": answer(level), "rt_ms": 800.0})
    return pd.DataFrame(rows)


def _analyse(df, out=None):
    return analyze(df, out, psychometric="none", gee=False, n_boot=20, figures=False, exclusions=RULES)


def _check(res, reps=2):
    part = res.exclusions.participants.set_index("participant")
    assert part["catch_trials"].to_dict() == {"att": reps, "yes": reps}      # what each saw
    assert part.loc["att", "catch_accuracy_pct"] == 100.0 and not part.loc["att", "excluded"]
    assert part.loc["yes", "exclusion_rule"] == "catch accuracy"
    cells = res.table.set_index(["group", "level"])["n"]
    # the original's answers (the attentive one's two) are the level 0 of both sharing groups
    assert cells[("smooth-increase", 0.0)] == cells[("abrupt-decrease", 0.0)] == reps
    assert "catch" not in set(res.table["group"])


def _shuffled(seed):
    return table().sample(frac=1.0, random_state=seed).reset_index(drop=True)


@settings(max_examples=8, deadline=None)
@given(st.integers(0, 2**32 - 1))
@example(next(s for s in range(100) if _shuffled(s)["group"].iloc[0] == "catch"))   # a catch trial first
def test_catch_counts_and_the_original_do_not_depend_on_the_row_order(seed):
    _check(_analyse(_shuffled(seed)))


@pytest.mark.parametrize("catch_first", [True, False])
def test_the_original_keeps_its_own_group_in_the_rows_written(tmp_path, catch_first):
    df = table()
    df = pd.concat([df[df["group"] == "catch"], df[df["group"] != "catch"]]) if catch_first else df
    _check(_analyse(df.reset_index(drop=True), tmp_path))
    rows = pd.read_csv(tmp_path / "responses_exclusions.csv", keep_default_na=False)
    orig = rows[rows["stimulus"] == "backflip_original"]
    assert len(orig) == 4 and set(orig["group"]) == {"original"} and not orig["catch"].any()
    assert rows.groupby("participant")["catch"].sum().to_dict() == {"att": 2, "yes": 2}
    assert set(rows.loc[rows["catch"], "stimulus"]) == {"backflip_catch_100"}
