"""Trial orders of designs that mix constant, quest+, yes/no and 2AFC groups
(property tests over random designs)."""
from __future__ import annotations

from collections import Counter

from hypothesis import given, settings, strategies as st

from flipstudy.stimuli.contract import Stimulus
from flipstudy.stimuli.design import parse_design
from flipstudy.stimuli.stimset import original_of, plan
from flipstudy.study.order import trial_order

GROUP = st.fixed_dictionaries({
    "kind": st.sampled_from(["am", "takeoff"]),
    "method": st.sampled_from(["constant", "quest+"]),
    "task": st.sampled_from(["yes-no", "2afc"]),
    "levels": st.sampled_from(["[0, 10, 20]", "[0, 15]", "[0, 5, 10, 30]", "{from = 0, to = 40, step = 10}"]),
    "trials": st.integers(1, 13),
    "original": st.sampled_from(["shared", "own"]),
})


QUEST_LEVELS = "{from = 0, to = 40, step = 5}"     # a quest+ group needs 3 or more levels


def design_text(groups, reps, two_clips):
    text = f'[study]\nname = "p"\nseed = 5\nrepetitions = {reps}\n\n[[clips]]\nname = "b"\nsource = "backflip"\n'
    if two_clips:
        text += '\n[[clips]]\nname = "f"\nsource = "frontflip"\n'
    for i, g in enumerate(groups):
        am = g["kind"] == "am"
        text += (f'\n[[groups]]\nname = "g{i}"\nkind = "{"angular-momentum" if am else "takeoff-angle"}"\n'
                 + ('profile = "smooth"\n' if am else "")
                 + f'levels = {g["levels"] if g["method"] == "constant" else QUEST_LEVELS}\nmethod = "{g["method"]}"\ntask = "{g["task"]}"\n'
                 + f'original = "{g["original"] if am else "own"}"\n')
        if g["method"] == "quest+":
            text += f'trials = {g["trials"]}\n'
    return text


def manifest(d):
    return [Stimulus(n, c.name, g.name if g else "reference", g.kind if g else "reference", level=lv,
                     original=original_of(d, c.name, g)) for n, c, g, lv in plan(d)]


@settings(max_examples=60, deadline=None)
@given(groups=st.lists(GROUP, min_size=1, max_size=4), reps=st.integers(1, 3), two_clips=st.booleans(),
       pid=st.sampled_from(["P01", "P02", "z9"]))
def test_mixed_orders_hold_every_trial_once_per_repetition_and_balance_2afc(groups, reps, two_clips, pid):
    d = parse_design(design_text(groups, reps, two_clips))
    m = manifest(d)
    trials = trial_order(d, m, pid)
    assert trials == trial_order(d, m, pid)                          # deterministic
    assert len(trials) == d.trials_per_participant()
    assert [t.trial for t in trials] == list(range(1, len(trials) + 1))
    names = {r.stimulus for r in m}
    const = Counter(t.stimulus for t in trials if not t.adaptive)
    assert all(n == reps for n in const.values()) and set(const) <= names
    for g in d.groups:
        mine = [t for t in trials if t.group == g.name]
        assert all(t.task == g.task and t.method == g.method for t in mine)
        if g.adaptive:
            assert len(mine) == g.quest.trials and all(t.stimulus == "" for t in mine)
            per_clip = Counter(t.clip for t in mine).values()
            assert max(per_clip) - min(per_clip, default=0) <= 1 and len(per_clip) <= len(d.clips)
        else:
            assert sorted({t.level for t in mine}) == g.trial_levels()
        if g.task == "2afc":
            f = Counter(t.first for t in mine)
            assert abs(f["original"] - f["modified"]) <= 1 and set(f) <= {"original", "modified"}
            assert all(t.original in names and t.original != t.stimulus for t in mine)
            assert all(t.level != 0 for t in mine if not t.adaptive)
        else:
            assert all(t.first == "" and t.original == "" for t in mine)
    shared = [t for t in trials if t.group == "original"]
    assert bool(shared) == d.shows_shared_original
