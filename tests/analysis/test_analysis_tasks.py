"""Analysis of 2AFC and QUEST+ answers: d′ = √2·z(P correct) against the
two-interval observer it describes, 2AFC psignifit fits, per-participant
thresholds replayed through QUEST+ (equal to the stored state), the group table,
and the yes/no rows analysed exactly as before."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.special import ndtr

from flipstudy.analysis import analyze, load_responses
from flipstudy.analysis.adaptive import Observer, Quest, QuestSettings, quest_model
from flipstudy.errors import ResponsesError
from flipstudy.analysis.simulate import paper_panel

GRID = list(np.arange(0, 61, 2.0))


def afc_rows(pid, group, level, chose_original, rng):
    """2AFC answers: which interval was chosen, with a balanced random order."""
    first = np.where(rng.random(len(level)) < 0.5, "original", "modified")
    resp = np.where(chose_original == (first == "original"), "first", "second")
    return pd.DataFrame({"participant": pid, "group": group, "level": level, "response": resp,
                         "first": first, "task": "2afc", "method": "constant"})


def quest_rows(pid, group, task, observer, settings, rng, n=None):
    """A QUEST+ run as the session stores it: levels, answers and the state after each."""
    model = quest_model(GRID, task, settings)
    q = Quest.new(model)
    rows = []
    for t in range(n or settings.trials):
        lv = q.next_level()
        det = observer.answer(lv, rng)
        q.update(lv, det)
        s = q.threshold()
        if task == "2afc":
            first = "original" if rng.random() < 0.5 else "modified"
            resp = "first" if det == (first == "original") else "second"
        else:
            first, resp = "", "incorrect" if det else "correct"
        rows.append({"participant": pid, "group": group, "level": lv, "response": resp, "trial": t + 1,
                     "first": first, "task": task, "method": "quest+", "quest_threshold": s["threshold"],
                     "quest_ci_low": s["ci_low"], "quest_ci_high": s["ci_high"]})
    return pd.DataFrame(rows), q


def test_2afc_dprime_recovers_the_two_interval_observer():
    """Observers compare an internal value of the original, N(d, 1), with one of the
    modified motion, N(0, 1), and choose the larger: P correct = Φ(d/√2), so the
    table's √2·z(P correct) must give back d (independent of the code's formula)."""
    rng = np.random.default_rng(5)
    truth = {10.0: 0.4, 20.0: 1.0, 30.0: 1.8}
    frames = []
    for p in range(12):
        for lv, d in truth.items():
            orig, mod = rng.normal(d, 1, 300), rng.normal(0, 1, 300)
            frames.append(afc_rows(f"P{p:02d}", "g", np.full(300, lv), orig > mod, rng))
    r = analyze(pd.concat(frames, ignore_index=True), None, psychometric="none", n_boot=200)
    t = r.table.set_index("level")
    for lv, d in truth.items():
        assert t.loc[lv, "task"] == "2afc"
        se = np.sqrt(2) * np.sqrt(0.25 / 3600) / 0.3          # generous delta-method bound
        assert abs(t.loc[lv, "dprime"] - d) < 3 * se
        assert t.loc[lv, "dprime_pooled_ci_low"] < d < t.loc[lv, "dprime_pooled_ci_high"]
        assert t.loc[lv, "p_correct"] == pytest.approx(ndtr(d / np.sqrt(2)), abs=0.02)
    assert np.isnan(t["rating_pct"]).all() and not t["corrected"].any()


def test_yes_no_rows_unchanged_beside_2afc_and_2afc_fit_has_gamma_half():
    yn = paper_panel(8, seed=3)
    rng = np.random.default_rng(1)
    obs = Observer(22.0, 15.0, 0.5, 0.02, "2afc")
    lv = np.repeat([10.0, 20.0, 30.0, 40.0, 50.0], 60)
    afc = pd.concat([afc_rows(f"Q{p}", "afc", lv, np.array([obs.answer(x, rng) for x in lv]), rng)
                     for p in range(4)], ignore_index=True)
    alone = analyze(yn, None, psychometric="none", gee=False, n_boot=100)
    both = analyze(pd.concat([yn, afc], ignore_index=True), None, psychometric="none", gee=False,
                   n_boot=100)
    t_yn = both.table[both.table["task"] == "yes-no"].drop(columns=["task", "n_correct", "p_correct"])
    t_yn = t_yn.reset_index(drop=True)
    t_yn["n_incorrect"] = t_yn["n_incorrect"].astype(int)
    pd.testing.assert_frame_equal(t_yn, alone.table, check_dtype=False)
    assert "afc" in both.paper["group"].tolist()
    only = analyze(afc, None, gee=False, n_boot=100)               # psignifit, 2AFC
    fit = only.fits[0]
    assert fit.params["gamma"] == 0.5 and fit.task == "2afc"
    assert fit.ci_low < 22.0 < fit.ci_high
    row = only.thresholds.iloc[0]
    assert row["task"] == "2afc" and row["p_at_threshold"] == 0.75
    per = both.participant_thresholds
    assert set(per["group"]) == set(both.table["group"])         # constant groups too
    assert (per.loc[per["group"] == "afc", "source"] == "replayed").all()


@pytest.mark.parametrize("task", ["yes-no", "2afc"])
def test_quest_rows_replayed_equal_the_stored_state(task, tmp_path):
    settings = QuestSettings(trials=30)
    rng = np.random.default_rng(2)
    truths = [12.0, 25.0, 33.0, 41.0]
    frames = []
    for i, x in enumerate(truths):
        o = Observer(x, 12.0, 0.25 if task == "yes-no" else 0.5, 0.02, task)
        rows, _ = quest_rows(f"P{i}", "adaptive", task, o, settings, rng)
        frames.append(rows)
    df = pd.concat(frames, ignore_index=True).sample(frac=1, random_state=0)   # any row order
    df[["quest_threshold", "quest_ci_low", "quest_ci_high"]] = \
        df[["quest_threshold", "quest_ci_low", "quest_ci_high"]].round(4)         # as exported
    specs = {"adaptive": (GRID, task, settings)}
    r = analyze(df, tmp_path / "out", quest_specs=specs, n_boot=50, figures=True)
    per = r.participant_thresholds.set_index("participant")
    assert (per["source"] == "replayed").all() and per["stored_matches"].all()
    assert (per["n_trials"] == 30).all() and (per["method"] == "quest+").all()
    np.testing.assert_allclose(per["threshold"], per["stored_threshold"], atol=5e-5)
    g = r.group_thresholds.iloc[0]
    assert g["n_participants"] == 4 and g["median"] == pytest.approx(np.median(per["threshold"]))
    assert g["q25"] <= g["median"] <= g["q75"] and np.isnan(g["pooled_threshold"])
    for name in ("thresholds_participants.csv", "thresholds_groups.csv", "thresholds_participants.png"):
        assert (tmp_path / "out" / name).is_file()
    assert len(r.table) == 0                      # no d′ table for adaptive answers
    # without the design: the stored thresholds, said so
    r2 = analyze(df, None, n_boot=50)
    assert (r2.participant_thresholds["source"] == "stored").all()
    assert any("no design" in n for n in r2.notes)
    # another model than the session's: the replay differs and a note says so
    r3 = analyze(df, None, n_boot=50, quest_specs={"adaptive": (GRID, task, QuestSettings(lapse=0.05))})
    assert not r3.participant_thresholds["stored_matches"].any()
    assert any("differ from the ones the session stored" in n for n in r3.notes)


def test_2afc_answers_are_checked_with_their_line(tmp_path):
    rng = np.random.default_rng(0)
    df = afc_rows("P1", "g", np.full(4, 10.0), np.array([True, False, True, True]), rng)
    df.loc[2, "response"] = "correct"
    p = tmp_path / "r.csv"
    df.to_csv(p, index=False)
    with pytest.raises(ResponsesError, match=r"line 4: 2AFC response 'correct'"):
        load_responses(p)
    df.loc[2, "response"] = "first"
    df.loc[1, "first"] = ""
    df.to_csv(p, index=False)
    with pytest.raises(ResponsesError, match=r"line 3: a 2AFC answer needs column 'first'"):
        load_responses(p)
    df.loc[1, "first"] = "original"
    df.loc[0, "task"] = "3afc"
    df.to_csv(p, index=False)
    with pytest.raises(ResponsesError, match=r"line 2: task '3afc'"):
        load_responses(p)
    df.loc[0, "task"] = "2afc"
    df.to_csv(p, index=False)
    d = load_responses(p)
    want = [(r == "first") == (f == "original") for r, f in zip(df["response"], df["first"])]
    assert d["detected"].astype(bool).tolist() == want


def test_quest_track_figure_draws_the_replayed_track():
    from flipstudy.analysis.figures import quest_track_figure
    model = quest_model(GRID, "2afc", QuestSettings(trials=12))
    o = Observer(20.0, 10.0, 0.5, 0.02, "2afc")
    _, q = quest_rows("P1", "g", "2afc", o, QuestSettings(trials=12), np.random.default_rng(0))
    fig = quest_track_figure(q, o)
    ax = fig.axes[0]
    step = ax.lines[0]                     # the posterior mean after each trial
    assert len(step.get_ydata()) == 13 and step.get_ydata()[-1] == pytest.approx(q.threshold()["threshold"])
    shown = np.concatenate([ln.get_ydata() for ln in ax.lines[1:3]])
    assert sorted(shown) == sorted(lv for lv, _ in q.history)
    assert model.key == q.model.key


def test_analyze_command_on_adaptive_and_2afc_answers(tmp_path, capsys):
    """`flipstudy analyze` on a responses CSV without a design beside it: the stored QUEST+
    thresholds, the 2AFC table, the new files, a summary.json that is valid JSON."""
    import json

    from flipstudy.study.cli import main
    rng = np.random.default_rng(11)
    frames = []
    for i in range(3):
        o = Observer(20.0 + 5 * i, 12.0, 0.5, 0.02, "2afc")
        rows, _ = quest_rows(f"P{i}", "adaptive", "2afc", o, QuestSettings(trials=15), rng)
        lv = np.repeat([10.0, 20.0, 30.0, 40.0], 6)
        frames += [rows, afc_rows(f"P{i}", "constant", lv, np.array([o.answer(x, rng) for x in lv]), rng)]
    csv = tmp_path / "responses.csv"
    pd.concat(frames, ignore_index=True).to_csv(csv, index=False)
    assert main(["analyze", str(csv), "--out", str(tmp_path / "a"), "--no-figures", "--n-boot", "50",
                 "--psychometric", "none"]) == 0
    out = capsys.readouterr().out
    assert "per-participant thresholds" in out and "adaptive" in out and "no design" in out
    per = pd.read_csv(tmp_path / "a" / "thresholds_participants.csv")
    assert set(per.loc[per["group"] == "adaptive", "source"]) == {"stored"}
    assert set(per.loc[per["group"] == "constant", "source"]) == {"replayed"}
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert {r["group"] for r in summary["thresholds_groups"]} == {"adaptive", "constant"}
    assert all(r["task"] == "2afc" for r in summary["table"])
