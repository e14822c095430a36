"""``flipstudy plan``: the power analysis (analysis/plan.py) and its command."""
from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.stats import t as t_dist

from flipstudy.analysis.adaptive import population
from flipstudy.analysis.plan import participants_for_width, plan_group
from flipstudy.study.cli import main
from flipstudy.study.pipeline import group_grids


@pytest.mark.parametrize("sd,width", [(10.0, 10.0), (5.0, 12.0), (8.0, 3.0)])
def test_participants_for_width_is_the_smallest_n(sd, width):
    n = participants_for_width(sd, width)
    half = lambda k: t_dist.ppf(0.975, k - 1) * sd / np.sqrt(k)
    assert 2 * half(n) < width <= 2 * half(n - 1) or n == 2
    assert n >= (2 * 1.959964 * sd / width) ** 2          # the normal bound is never beaten


def test_plan_rows_same_observers_and_quest_needs_fewer_trials():
    obs = population(60, np.random.default_rng(3), "2afc")
    rows = plan_group("g", "2afc", range(0, 61), [17, 25, 37, 50], target_width=18.0,
                      observers=obs, max_trials=120, seed=2)
    q, c = rows
    assert (q["method"], c["method"]) == ("quest+", "constant")
    assert q["levels"] == "60 levels, 1–60 %" and c["levels"] == "4 levels, 17–50 %"
    assert q["trials_median"] < c["trials_median"]
    assert 0 < q["share_reached"] <= 1 and q["participants"] >= 2
    assert q["total_trials"] == q["trials"] * q["participants"]


def test_group_grids():
    quest, const = group_grids([0, 17, 25, 37, 50], "yes-no")
    assert quest[0] == 0 and quest[-1] == 50 and len(quest) == 51 and const.tolist() == [0, 17, 25, 37, 50]
    quest, const = group_grids(np.arange(0, 61, 1.0), "2afc")
    assert len(quest) == 61 and const.tolist() == [15, 30, 45, 60]


def test_plan_command(tmp_path, capsys):
    from flipstudy.stimuli.design import PAPER_DESIGN
    d = tmp_path / "design.toml"
    d.write_text(PAPER_DESIGN)
    assert main(["plan", str(d), "--group", "smooth-increase", "--task", "2afc", "--observers", "20",
                 "--max-trials", "40", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["method"] for r in rows] == ["quest+", "constant"] and rows[0]["group"] == "smooth-increase"
    assert main(["plan", str(d), "--group", "nope"]) == 1
    assert "no group nope" in capsys.readouterr().err
