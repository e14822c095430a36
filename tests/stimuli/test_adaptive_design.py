"""Design keys of issue 19: dense grids, method, task and the quest+ settings."""
from __future__ import annotations

import csv

import pytest
from hypothesis import given, settings, strategies as st

from flipstudy.errors import DesignError
from flipstudy.stimuli.design import GRID_MAX, TRIALS_MAX, QuestSpec, parse_design
from flipstudy.stimuli.groupkeys import grid_levels

HEAD = """[study]
name = "g"
seed = 1
{study}
[[clips]]
name = "backflip"
source = "backflip"

[[groups]]
name = "am"
kind = "angular-momentum"
profile = "smooth"
"""


def design(group: str, study: str = "") -> str:
    return HEAD.format(study=study) + group


def test_a_grid_group_has_every_level_and_a_quest_group_counts_its_trials():
    d = parse_design(design('levels = {from = 0, to = 60, step = 1}\nmethod = "quest+"\ntrials = 35\n'
                            'threshold_prior = [5, 50]\nlapse = 0.01\n'))
    g = d.groups[0]
    assert list(g.levels) == [float(i) for i in range(61)] and g.adaptive and g.task == "yes-no"
    assert g.quest == QuestSpec(trials=35, threshold_prior=(5.0, 50.0), lapse=0.01)
    assert d.trials_per_participant() == 35
    assert len(d.stimulus_names()) == 1 + 60         # the shared original and 60 modified levels
    c = parse_design(design("levels = {from = 0, to = 60, step = 1}\n"))
    assert not c.groups[0].adaptive and c.trials_per_participant() == 2 * 61


def test_the_study_task_is_the_groups_default_and_2afc_levels_leave_out_0():
    d = parse_design(design('levels = [0, 10, 20]\noriginal = "own"\n', 'task = "2afc"'))
    g = d.groups[0]
    assert d.task == g.task == "2afc" and g.trial_levels() == [10.0, 20.0]
    assert d.trials_per_participant() == 2 * 2            # repetitions × levels 10, 20
    assert not d.shows_shared_original
    y = parse_design(design('levels = [0, 10, 20]\ntask = "yes-no"\n', 'task = "2afc"'))
    assert y.groups[0].task == "yes-no" and y.trials_per_participant() == 2 * 3


@pytest.mark.parametrize("group, study, where, what", [
    ("levels = {from = 0, to = 60, step = 0.1}\n", "", "groups[0] (am).levels", "at most 401"),
    ("levels = {from = 0, to = 60.5, step = 1}\n", "", "groups[0] (am).levels.to", "not on the grid"),
    ("levels = {from = 0, to = 60, step = 0}\n", "", "groups[0] (am).levels.step", "more than 0"),
    ("levels = {from = 0, to = 60, stp = 1}\n", "", "groups[0] (am).levels", "did you mean 'step'"),
    ("levels = {from = 0, to = 95, step = 5}\nsign = -1\n", "", "groups[0] (am).levels",
     "out of range"),
    ("levels = [" + ", ".join(str(i) for i in range(21)) + "]\n", "", "groups[0] (am).levels",
     "at most 20"),
    ("levels = [0, 10]\ntrials = 30\n", "", "groups[0] (am).trials", "only quest+ groups"),
    ('levels = [0, 10, 20]\nmethod = "quest"\n', "", "groups[0] (am).method", "must be one of"),
    ('levels = [0, 10, 20]\ntask = "2AFC"\n', "", "groups[0] (am).task", "must be one of"),
    ('levels = [0, 10]\nmethod = "quest+"\n', "", "groups[0] (am).levels", "at least 3 levels"),
    ('levels = [10, 20]\ntask = "2afc"\n', "", "groups[0] (am).levels", "need 0"),
    ('levels = {from = 0, to = 60, step = 5}\nmethod = "quest+"\nthreshold_prior = [0, 70]\n', "",
     "groups[0] (am).threshold_prior", "within the grid"),
    ('levels = {from = 0, to = 60, step = 5}\nmethod = "quest+"\nwidth_prior = [5]\n', "",
     "groups[0] (am).width_prior", "two numbers"),
    ('levels = {from = 0, to = 60, step = 5}\nmethod = "quest+"\nlapse = 0.3\n', "",
     "groups[0] (am).lapse", "below 0.2"),
    ('levels = {from = 0, to = 60, step = 5}\nmethod = "quest+"\ntrials = 0\n', "",
     "groups[0] (am).trials", "1 to 1000"),
    ('levels = {from = 0, to = 60, step = 5}\nmethod = "quest+"\nstop_width = -1\n', "",
     "groups[0] (am).stop_width", "more than 0"),
    ("levels = [0, 10]\n", 'task = "forced"', "[study].task", "must be one of"),
])
def test_invalid_keys_name_file_group_and_key(group, study, where, what):
    with pytest.raises(DesignError) as e:
        parse_design(design(group, study), "study/design.toml")
    msg = str(e.value)
    assert msg.startswith("study/design.toml: ") and where in msg and what in msg, msg


def test_quest_trials_count_against_the_trials_per_participant_bound():
    groups = "".join(f"""
[[groups]]
name = "q{i}"
kind = "takeoff-angle"
levels = {{from = 0, to = 40, step = 1}}
method = "quest+"
trials = 1000
""" for i in range(4))
    text = HEAD.format(study="").split("[[groups]]")[0] + groups
    with pytest.raises(DesignError, match=f"4000 test trials per participant.*q0: 1000.*at most {TRIALS_MAX}"):
        parse_design(text)
    assert parse_design(text.replace("trials = 1000", "trials = 700")).trials_per_participant() == 2800


@settings(max_examples=60, deadline=None)
@given(lo=st.integers(0, 50), step_c=st.integers(1, 200), n=st.integers(1, GRID_MAX - 1))
def test_grid_levels_are_evenly_spaced_from_from_to_to(lo, step_c, n):
    step = step_c / 100.0                                   # 0.01 … 2 percent
    hi = lo + n * step_c / 100.0
    lv = grid_levels({"from": lo, "to": hi, "step": step}, "d: g")
    assert len(lv) == n + 1 and lv[0] == lo and lv[-1] == pytest.approx(hi, abs=1e-9)
    assert all(abs((b - a) - step) < 1e-7 for a, b in zip(lv, lv[1:]))
    assert len({f"{v:g}" for v in lv}) == len(lv)            # every level names its own stimulus


def test_a_grid_group_builds_every_level_within_tolerance(tmp_path):
    from flipstudy.stimuli.stimset import build_stimuli
    d = parse_design(design('levels = {from = 0, to = 30, step = 7.5}\noriginal = "own"\n'
                            'method = "quest+"\n', "tolerance_pct = 1.0\nfps = 60"))
    rows = build_stimuli(d, tmp_path / "s", progress=False).rows
    with open(tmp_path / "s" / "manifest.csv", newline="") as f:
        manifest = list(csv.DictReader(f))
    assert [r["stimulus"] for r in manifest] == [f"backflip_am_{v:g}" for v in (0, 7.5, 15, 22.5, 30)]
    assert len(rows) == 5
    for r in manifest:
        assert abs(float(r["measured_error_pct"]) - float(r["nominal_error_pct"])) <= 1.0
        assert (tmp_path / "s" / r["bvh"]).is_file()


def test_a_pose_rate_group_is_refused_as_quest_plus_and_runs_as_constant_stimuli():
    """QUEST+ assumes the error grows with the level; a pose rate's falls with it."""
    text = """[study]
name = "p"
seed = 1
fps = 60

[[clips]]
name = "backflip"
source = "backflip"

[[groups]]
name = "pr"
kind = "pose-rate"
levels = [0, 10, 15, 20, 30]
"""
    assert parse_design(text).groups[0].method == "constant"
    with pytest.raises(DesignError, match=r"groups\[0\] \(pr\)\.method: QUEST\+ assumes"):
        parse_design(text + 'method = "quest+"\n')
