"""Simulated observers with known thresholds answer quest+, 2AFC and constant
groups through the session's answer path; the truth is stored and exported."""
from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from scipy.stats import norm

from flipstudy.study import session as session_mod
from flipstudy.study import store
from flipstudy.study.demo import make_demo_study
from flipstudy.study.export import ADAPTIVE_COLUMNS, RESPONSE_COLUMNS, TRUTH_FILE, export_responses
from flipstudy.errors import ModelError
from flipstudy.study.simulate import simulate

from _adaptive import make_study


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def p_detect(level, t):
    """P(detected) from a truth row, in closed form (x* → m; not the engine's Observer)."""
    x, w, g, lam = (float(t[k]) for k in ("threshold", "width", "gamma", "lapse"))
    s = w / (2 * norm.ppf(0.95))
    m = x - s * norm.ppf((1 - g) / (2 * (1 - g - lam)))
    return g + (1 - g - lam) * norm.cdf((level - m) / s)


def test_observers_answer_every_group_and_their_truth_is_exported(tmp_path):
    study = make_study(tmp_path / "s", groups=("yn", "quest", "twoafc", "quest2afc"), trials=8)
    assert simulate(study, 2, seed=4) == ["sim001", "sim002"]
    res = export_responses(study, include_simulated=True)
    rows = read(res.responses)
    assert list(rows[0]) == RESPONSE_COLUMNS + ADAPTIVE_COLUMNS
    assert len(rows) == 2 * (4 + 8 + 4 + 8) and all(r["complete"] == "true" for r in rows)
    for r in rows:
        two = r["task"] == "2afc"
        assert r["response"] in (("first", "second") if two else ("correct", "incorrect"))
        assert (r["first"] in ("original", "modified")) == two
        assert bool(r["quest_threshold"]) == (r["method"] == "quest+")
        if r["method"] == "quest+":
            assert float(r["quest_ci_low"]) <= float(r["quest_threshold"]) <= float(r["quest_ci_high"])
            assert r["stimulus"] == f"backflip_{r['group']}_{r['level']}"
    truth = read(tmp_path / "s" / TRUTH_FILE)
    assert res.truth == tmp_path / "s" / TRUTH_FILE and len(truth) == 2 * 4
    conn = store.connect(study)
    stored = {r["participant"]: json.loads(r["simulated_truth"]) for r in store.truth_rows(conn)}
    conn.close()
    for t in truth:
        o = stored[t["participant"]]["groups"][t["group"]]
        assert float(t["threshold"]) == o["threshold"] and t["task"] == o["task"]
    for pid in ("sim001", "sim002"):
        mine = {t["group"]: t for t in truth if t["participant"] == pid}
        assert mine["yn"]["gamma"] == mine["quest"]["gamma"]          # one base rate per person
        assert mine["twoafc"]["gamma"] == mine["quest2afc"]["gamma"] == "0.5"
    export_responses(study)                                # simulated left out: no truth file
    assert not read(tmp_path / "s" / "responses.csv")


def test_two_afc_answers_follow_the_observers_psychometric_functions(tmp_path):
    text = open(make_study(tmp_path / "d", groups=("twoafc",)) / "design.toml").read()
    study = make_study(tmp_path / "s", text.replace("repetitions = 2", "repetitions = 20"))
    simulate(study, 10, seed=2)
    export_responses(study, include_simulated=True)
    rows = read(tmp_path / "s" / "responses.csv")
    truth = {t["participant"]: t for t in read(tmp_path / "s" / TRUTH_FILE)}
    for level in (20, 40):
        mine = [r for r in rows if r["level"] == str(level)]
        chose_original = np.array([(r["response"] == "first") == (r["first"] == "original") for r in mine])
        expected = np.array([p_detect(level, truth[r["participant"]]) for r in mine])
        assert len(mine) == 10 * 20
        se = np.sqrt(np.sum(expected * (1 - expected))) / len(mine)
        assert abs(chose_original.mean() - expected.mean()) < 4 * se
    firsts = [r["first"] for r in rows]
    assert firsts.count("original") == firsts.count("modified")     # balanced per group


def test_a_simulation_stopped_midway_resumes_to_the_same_answers(tmp_path, monkeypatch):
    kw = dict(groups=("yn", "quest"), trials=10)
    whole, cut = make_study(tmp_path / "whole", **kw), make_study(tmp_path / "cut", **kw)
    simulate(whole, 1, seed=5)
    real = session_mod.submit_answer
    calls = {"n": 0}

    def crash_after_six(s, payload, **k):
        calls["n"] += 1
        if calls["n"] > 6:
            raise KeyboardInterrupt
        return real(s, payload, **k)
    monkeypatch.setattr("flipstudy.study.simulate.submit_answer", crash_after_six)
    with pytest.raises(KeyboardInterrupt):
        simulate(cut, 1, seed=5)
    monkeypatch.setattr("flipstudy.study.simulate.submit_answer", real)
    simulate(cut, 1, seed=5)
    keep = ("trial", "stimulus", "level", "response", "rt_ms", "quest_threshold", "first")
    a, b = (sorted(tuple(r[k] for k in keep) for r in read(export_responses(
        d, include_simulated=True).responses)) for d in (whole, cut))
    assert a == b and len(a) == 14


def test_quest_intervals_cover_the_simulated_truth_through_the_session_path(tmp_path):
    """Recovery through storage: 2AFC quest+ groups of 30 trials, 8 observers; the
    final 95 % interval should hold the truth for nearly all of them."""
    study = make_study(tmp_path / "s", groups=("quest2afc",), trials=30)
    simulate(study, 8, seed=8, population={"threshold": (30.0, 8.0), "width": (5.0, 20.0)})
    export_responses(study, include_simulated=True)
    rows = read(tmp_path / "s" / "responses.csv")
    truth = {t["participant"]: float(t["threshold"]) for t in read(tmp_path / "s" / TRUTH_FILE)}
    last = {r["participant"]: r for r in rows}                        # each one's final posterior
    covered = [float(r["quest_ci_low"]) <= truth[p] <= float(r["quest_ci_high"]) for p, r in last.items()]
    assert len(covered) == 8 and sum(covered) >= 6
    errors = [abs(float(r["quest_threshold"]) - truth[p]) for p, r in last.items()]
    assert np.median(errors) < 8.0                                    # percent, on a 5..60 grid


def test_the_paper_style_study_keeps_its_columns_and_model(tmp_path):
    study = make_demo_study(tmp_path / "s", videos=False)
    simulate(study, 2, seed=1)
    res = export_responses(study, include_simulated=True)
    with open(res.responses) as f:
        assert f.readline().strip().split(",") == RESPONSE_COLUMNS
    assert res.truth is None and not (tmp_path / "s" / TRUTH_FILE).exists()
    two = make_study(tmp_path / "t", groups=("twoafc",))
    with pytest.raises(ModelError, match="2afc"):
        simulate(two, 1, model=tmp_path / "nothing.toml")
