"""Session storage, export, status and simulated observers (no browser)."""
import csv
import math
import sqlite3

import numpy as np
import pytest

from flipstudy.study import store
from flipstudy.study.demo import make_demo_study
from flipstudy.study.export import PARTICIPANT_COLUMNS, RESPONSE_COLUMNS, export_responses, status
from flipstudy.study.order import trial_order
from flipstudy.errors import ModelError, RequestError, SessionError
from flipstudy.study.session import load_study, open_session, submit_answer, submit_demographics
from flipstudy.study.cli import main as cli
from flipstudy.study.simulate import DEFAULT_MODEL, parse_model, simulate

DESIGN_COLS = ["participant", "session", "trial", "stimulus", "group", "level", "repetition",
               "response", "rt_ms", "shown_ms", "timestamp"]


@pytest.fixture
def study_dir(tmp_path):
    return make_demo_study(tmp_path / "study", videos=False, levels=(0, 25, 50))


def answer(session, trial, response="correct", **kw):
    t = session.trials[trial - 1]
    body = {"participant": session.participant, "session": session.session, "trial": trial,
            "stimulus": t.stimulus, "response": response, "rt_ms": 640.5, "shown_ms": 1000.0,
            "late_frames": 0}
    body.update(kw)
    return submit_answer(session, body)


def demographics(session, **kw):
    body = {"participant": session.participant, "session": session.session, "age": 24,
            "gender": "man", "animation_experience": "none", "gymnastics_experience": "some"}
    body.update(kw)
    return submit_demographics(session, body)


def rows(study_dir, table):
    conn = sqlite3.connect(study_dir / "sessions.sqlite")
    try:
        return conn.execute(f"SELECT COUNT(*) FROM {table}").fetchone()[0]
    finally:
        conn.close()


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_database_is_wal_with_full_sync(study_dir):
    conn = store.connect(study_dir)
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    assert conn.execute("PRAGMA synchronous").fetchone()[0] == 2      # FULL
    assert conn.execute("PRAGMA foreign_keys").fetchone()[0] == 1


def test_order_is_stored_before_the_first_trial_and_resumed(study_dir):
    study = load_study(study_dir)
    s = open_session(study, "P01")
    assert rows(study_dir, "trials") == s.n_trials == 12 and rows(study_dir, "responses") == 0
    assert s.trials == trial_order(study.design, study.manifest, "P01")
    answer(s, 1)
    answer(s, 2, "incorrect")
    again = open_session(load_study(study_dir), "P01")
    assert again.resumed and again.session == 1 and again.trials == s.trials
    assert again.state() == {"answered": 2, "next_trial": 3, "finished": False, "demographics": False}


def test_double_submit_is_idempotent_and_conflicts_are_refused(study_dir):
    s = open_session(load_study(study_dir), "P01")
    assert answer(s, 1)["status"] == "stored"
    assert answer(s, 1, rt_ms=999.0)["status"] == "duplicate"        # a retried post
    with pytest.raises(RequestError) as e:
        answer(s, 1, "incorrect")
    assert e.value.status == 409 and "already answered" in e.value.message
    with pytest.raises(RequestError) as e:                           # not the current trial
        answer(s, 3)
    assert e.value.status == 409
    with pytest.raises(RequestError) as e:                           # wrong stimulus for trial 2
        answer(s, 2, stimulus=s.trials[3].stimulus if s.trials[3].stimulus != s.trials[1].stimulus
               else s.trials[4].stimulus)
    assert e.value.status == 409
    assert rows(study_dir, "responses") == 1
    conn = store.connect(study_dir)
    r = conn.execute("SELECT response, rt_ms FROM responses").fetchone()
    assert (r["response"], r["rt_ms"]) == ("correct", 640.5)         # the first answer is kept


def test_demographics_once(study_dir):
    s = open_session(load_study(study_dir), "P01")
    assert demographics(s)["status"] == "stored"
    assert demographics(s)["status"] == "duplicate"
    with pytest.raises(RequestError) as e:
        demographics(s, age=None)
    assert e.value.status == 409
    with pytest.raises(RequestError) as e:
        demographics(s, gender="robot")
    assert e.value.status == 400
    s2 = open_session(load_study(study_dir), "P02")
    demographics(s2, age=None, gender="prefer-not-to-say")
    assert rows(study_dir, "demographics") == 2


def test_finished_participant_is_not_overwritten(study_dir, capsys):
    study = load_study(study_dir)
    s = open_session(study, "P01")
    for i in range(1, s.n_trials + 1):
        r = answer(s, i, "correct" if i % 3 else "incorrect")
    assert r["finished"]
    with pytest.raises(SessionError, match="already finished.*--new-session"):
        open_session(study, "P01")
    assert cli(["run", str(study_dir), "--participant", "P01", "--no-browser"]) == 1
    assert "already finished" in capsys.readouterr().err
    s2 = open_session(study, "P01", new_session=True)
    assert s2.session == 2 and not s2.resumed
    assert [t.stimulus for t in s2.trials] != [t.stimulus for t in s.trials]
    answer(s2, 1)
    st = {(r["participant"], r["session"]): r for r in status(study_dir)}
    assert st[("P01", 1)]["answered"] == 12 and st[("P01", 1)]["finished"]
    assert st[("P01", 2)]["answered"] == 1 and st[("P01", 2)]["finished"] is None


def test_changed_manifest_refuses_to_resume(study_dir):
    s = open_session(load_study(study_dir), "P01")
    answer(s, 1)
    with open(study_dir / "manifest.csv", "a") as f:
        f.write("\n")
    with pytest.raises(SessionError, match="changed"):
        open_session(load_study(study_dir), "P01")


@pytest.mark.parametrize("pid", ["", "a b", "../x", "P01/..", "x" * 33, "é", "P;DROP", "-" * 0])
def test_bad_participant_ids_are_refused(study_dir, pid, capsys):
    with pytest.raises(SessionError, match="not valid"):
        open_session(load_study(study_dir), pid)
    assert cli(["run", str(study_dir), "--participant", pid, "--no-browser"]) == 1
    assert not (study_dir / "sessions.sqlite").exists() or rows(study_dir, "sessions") == 0


def test_run_refuses_a_study_without_videos(study_dir, capsys):
    assert cli(["run", str(study_dir), "--participant", "P01", "--no-browser"]) == 1
    assert "flipstudy render" in capsys.readouterr().err


def test_export_long_format_and_participants(study_dir, tmp_path, capsys):
    study = load_study(study_dir)
    s = open_session(study, "P01")
    demographics(s, age=None)
    given = []
    for i in range(1, 6):
        resp = "incorrect" if i % 2 else "correct"
        answer(s, i, resp, rt_ms=100.0 + i, shown_ms=1000.25, late_frames=i % 2, input="key")
        given.append(resp)
    out = tmp_path / "out" / "responses.csv"
    assert cli(["export", str(study_dir), "--out", str(out)]) == 0
    assert "wrote 5 responses" in capsys.readouterr().out
    rs = read_csv(out)
    assert list(rs[0].keys()) == RESPONSE_COLUMNS and RESPONSE_COLUMNS[:11] == DESIGN_COLS
    assert len(rs) == 5
    for i, r in enumerate(rs, start=1):
        t = s.trials[i - 1]
        assert (r["participant"], r["session"], r["trial"], r["stimulus"], r["group"], r["level"],
                r["repetition"], r["response"]) == ("P01", "1", str(i), t.stimulus, t.group,
                                                    f"{t.level:g}", str(t.repetition), given[i - 1])
        assert r["rt_ms"] == f"{100.0 + i:.1f}" and r["shown_ms"] == "1000.2"
        assert r["late_frames"] == str(i % 2) and r["clip"] == "backflip"
        assert r["kind"] == "angular-momentum" and r["input"] == "key"
        assert r["timestamp"].endswith("Z") and "T" in r["timestamp"]
        from datetime import datetime
        datetime.fromisoformat(r["timestamp"].replace("Z", "+00:00"))
    ps = read_csv(out.parent / "participants.csv")
    assert list(ps[0].keys()) == PARTICIPANT_COLUMNS
    assert ps[0]["participant"] == "P01" and ps[0]["age"] == "" and ps[0]["gender"] == "man"
    assert ps[0]["answered"] == "5" and ps[0]["finished"] == ""
    # atomic: no temporary files left, and a second export replaces the first
    answer(s, 6)
    export_responses(study_dir, out)
    assert len(read_csv(out)) == 6
    assert sorted(p.name for p in out.parent.iterdir()) == ["data", "dataset_description.json",   # data/: Psych-DS
                                                            "participants.csv", "responses.csv"]
    assert not [p for p in (out.parent / "data").iterdir() if p.name.startswith(".")]


def test_analysis_reads_the_export(study_dir, tmp_path):
    from flipstudy.analysis.io import load_responses
    simulate(study_dir, 3, seed=1)
    out = tmp_path / "responses.csv"
    export_responses(study_dir, out, include_simulated=True)
    df = load_responses(out)
    assert len(df) == 3 * 12 and set(df["response"]) <= {"correct", "incorrect"}


def test_status_command(study_dir, capsys):
    assert cli(["status", str(study_dir)]) == 0
    assert "no sessions yet" in capsys.readouterr().out
    assert cli(["status", str(study_dir / "render")]) == 1           # not a study
    s = open_session(load_study(study_dir), "P01")
    answer(s, 1)
    assert cli(["status", str(study_dir)]) == 0
    out = capsys.readouterr().out
    assert "P01" in out and "1/12" in out and "1 session(s), 0 finished" in out


def test_simulate_and_export_leave_real_rows_alone_and_mark_or_omit_simulated(study_dir, tmp_path,
                                                                             capsys):
    """Real answers are exported the same with or without simulated participants
    in the store; these are left out by default and marked on every row when asked."""
    s = open_session(load_study(study_dir), "P01")
    demographics(s)
    for i in range(1, 13):
        answer(s, i, "incorrect" if i % 3 else "correct", input="key")
    p2 = open_session(load_study(study_dir), "P02")       # stopped after 4 of 12
    for i in range(1, 5):
        answer(p2, i)
    real_only = read_csv(export_responses(study_dir, tmp_path / "before.csv").responses)
    assert len(real_only) == 16
    assert cli(["simulate", str(study_dir), "--participants", "3", "--seed", "2"]) == 0
    assert "--include-simulated" in capsys.readouterr().out
    assert cli(["export", str(study_dir), "--out", str(tmp_path / "after.csv")]) == 0
    msg = capsys.readouterr().out
    assert "2 real participant(s)" in msg and "left out 3 simulated" in msg
    assert "P02/1 (4/12)" in msg and "complete=false" in msg
    after = read_csv(tmp_path / "after.csv")
    assert after == real_only                              # byte for byte the same rows
    assert {r["simulated"] for r in after} == {"false"}
    assert {(r["participant"], r["complete"]) for r in after} == {("P01", "true"), ("P02", "false")}
    ps = read_csv(tmp_path / "participants.csv")
    assert [(p["participant"], p["simulated"], p["complete"]) for p in ps] == [
        ("P01", "false", "true"), ("P02", "false", "false")]
    # asked for: every simulated row says so, and the real rows are unchanged
    r = export_responses(study_dir, tmp_path / "all.csv", include_simulated=True)
    assert r.simulated == ("sim001", "sim002", "sim003") and r.real == ("P01", "P02")
    both = read_csv(tmp_path / "all.csv")
    assert [x for x in both if x["simulated"] == "false"] == real_only
    sim = [x for x in both if x["simulated"] == "true"]
    assert len(sim) == 36 and {x["participant"] for x in sim} == {"sim001", "sim002", "sim003"}
    assert all(x["input"] == "simulated" for x in sim)
    # status flags the incomplete session and counts real and simulated participants
    assert cli(["status", str(study_dir)]) == 0
    out = capsys.readouterr().out
    line = next(ln for ln in out.splitlines() if ln.startswith("P02"))
    assert "4/12" in line and "INCOMPLETE" in line
    assert "INCOMPLETE" not in next(ln for ln in out.splitlines() if ln.startswith("P01"))
    assert "2 real participant(s), 3 simulated" in out and "P02/1 4/12" in out


def test_analyze_leaves_out_simulated_and_incomplete_and_says_who(study_dir, tmp_path, capsys):
    from flipstudy.study.cli import main as analyze_cli
    from flipstudy.analysis.pipeline import analyze
    for pid in ("P01", "P02", "P03"):
        s = open_session(load_study(study_dir), pid)
        for i in range(1, 13):
            answer(s, i, "incorrect" if (i + len(pid)) % 3 == 0 else "correct")
    p4 = open_session(load_study(study_dir), "P04")
    for i in range(1, 7):
        answer(p4, i)
    simulate(study_dir, 5, seed=1)
    csv_all = export_responses(study_dir, tmp_path / "r.csv", include_simulated=True).responses
    res = analyze(csv_all, tmp_path / "a", psychometric="none", gee=False, n_boot=50)
    who = res.settings["participants"]
    assert who["real"] == ["P01", "P02", "P03"] and who["simulated"] == []
    assert who["simulated_left_out"] == [f"sim00{i}" for i in range(1, 6)]
    assert who["incomplete_left_out"] == ["P04/1 (6 answers)"]
    assert res.settings["n_participants"] == 3
    assert int(res.table["n"].sum()) == 3 * 12
    label = res.settings["participants_label"]
    assert label == "N = 3 participants (3 real, 0 simulated); left out: 5 simulated, 1 incomplete session"
    notes = (tmp_path / "a" / "notes.md").read_text()
    assert label in notes and "not meaningful" in notes and "95% coverage" not in notes
    assert label in (tmp_path / "a" / "table_paper.md").read_text()
    assert label in (tmp_path / "a" / "table_paper.tex").read_text()
    import json
    assert json.loads((tmp_path / "a" / "summary.json").read_text())["settings"]["participants"] == who
    # asked for: simulated kept and said so
    res2 = analyze(csv_all, None, psychometric="none", gee=False, n_boot=50, include_simulated=True,
                   include_incomplete=True)
    assert res2.settings["participants"]["simulated"] == [f"sim00{i}" for i in range(1, 6)]
    assert res2.settings["n_participants"] == 9 and int(res2.table["n"].sum()) == 3 * 12 + 6 + 5 * 12
    assert any("describe the observer model" in n for n in res2.notes)
    # the command prints the counts
    assert analyze_cli(["analyze", str(csv_all), "--out", str(tmp_path / "b"), "--psychometric",
                        "none", "--no-gee", "--no-figures", "--n-boot", "50"]) == 0
    out = capsys.readouterr().out
    assert "left out 5 simulated participant(s)" in out and "left out 1 incomplete session(s)" in out
    # a study with only simulated participants: nothing to analyse, and the error says why
    only = make_demo_study(tmp_path / "sim", videos=False, levels=(0, 25, 50))
    simulate(only, 2, seed=1)
    csv_sim = export_responses(only, tmp_path / "s.csv", include_simulated=True).responses
    from flipstudy.errors import ResponsesError
    with pytest.raises(ResponsesError, match="--include-simulated"):
        analyze(csv_sim, None, psychometric="none", gee=False, n_boot=50)


# --- simulated observers ------------------------------------------------------------------

def test_default_model_is_the_papers_table_2():
    m = DEFAULT_MODEL
    assert m.p_correct("smooth-increase", 0) == pytest.approx(0.72)
    assert m.p_correct("smooth-increase", 37) == pytest.approx(0.72 + (0.41 - 0.72) * 12 / 25)
    assert m.p_correct("abrupt-decrease", 50) == pytest.approx(0.22)
    assert m.p_correct("takeoff-increase", 10) == pytest.approx(0.81)
    assert m.p_correct("smooth-decrease", 21) == pytest.approx(0.79 + (0.78 - 0.79) * 4 / 8)
    assert m.sigma == 0.3
    with pytest.raises(ModelError, match="no group"):
        m.p_correct("wobble", 0)
    with pytest.raises(ModelError, match="outside"):
        m.p_correct("takeoff-increase", 50)


def test_random_effect_keeps_the_ratings_in_expectation():
    m = DEFAULT_MODEL
    u = np.random.default_rng(0).normal(0, m.sigma, 400_000)
    for g, lv in [("abrupt-decrease", 50), ("smooth-decrease", 17), ("takeoff-increase", 20)]:
        p = 1 / (1 + np.exp(-(m.base_logit(g, lv) + u)))
        assert p.mean() == pytest.approx(m.p_correct(g, lv), abs=0.002)


def test_model_file(tmp_path):
    m = parse_model('sigma = 0\n[groups.g]\nlevels = [0, 50]\np_correct = [90, 10]\n')
    assert m.p_correct("g", 25) == pytest.approx(0.5) and m.sigma == 0
    for bad, msg in [("sigma = -1\n[groups.g]\nlevels=[0]\np_correct=[0.5]", "sigma"),
                     ("[groups.g]\nlevels=[0, 0]\np_correct=[0.5, 0.5]", "increase"),
                     ("[groups.g]\nlevels=[0, 1]\np_correct=[0.5]", "same"),
                     ("[groups.g]\nlevels=[0]\np_correct=[-0.5]", "probabilities"),
                     ("[wat]", "unknown")]:
        with pytest.raises(ModelError, match=msg):
            parse_model(bad)


def test_simulate_answers_every_trial_deterministically(study_dir, tmp_path, capsys):
    model = tmp_path / "m.toml"
    model.write_text("sigma = 0.3\n[groups.smooth-increase]\nlevels = [0, 50]\np_correct = [1, 0]\n"
                     "[groups.abrupt-decrease]\nlevels = [0, 50]\np_correct = [0.5, 0.5]\n")
    assert cli(["simulate", str(study_dir), "--participants", "4", "--model", str(model),
                "--seed", "3"]) == 0
    export_responses(study_dir, tmp_path / "a.csv", include_simulated=True)
    a = read_csv(tmp_path / "a.csv")
    assert len(a) == 4 * 12
    assert sorted({r["participant"] for r in a}) == ["sim001", "sim002", "sim003", "sim004"]
    for r in a:
        assert r["input"] == "simulated" and 150 <= float(r["rt_ms"]) <= 20000
        assert r["simulated"] == "true" and r["complete"] == "true"
        assert abs(float(r["shown_ms"]) - 1000.0) < 60      # 30 frames at 30 fps
        if r["group"] == "smooth-increase" and r["level"] in ("0", "50"):
            assert r["response"] == ("correct" if r["level"] == "0" else "incorrect")
    st = status(study_dir)
    assert all(x["finished"] and x["source"] == "simulated" for x in st)
    # the same seed gives the same answers in a fresh study; simulating again changes nothing
    other = make_demo_study(tmp_path / "other", videos=False, levels=(0, 25, 50))
    simulate(other, 4, model=model, seed=3)
    simulate(other, 4, model=model, seed=3)
    export_responses(other, tmp_path / "b.csv", include_simulated=True)
    b = read_csv(tmp_path / "b.csv")
    key = lambda rows: [(r["participant"], r["trial"], r["stimulus"], r["response"], r["rt_ms"])  # noqa: E731
                        for r in rows]
    assert key(a) == key(b)
    # simulated and browser participants do not mix
    with pytest.raises(SessionError, match="simulated participant"):
        open_session(load_study(study_dir), "sim001")


def test_simulate_resumes_an_interrupted_participant(study_dir, tmp_path):
    simulate(study_dir, 1, seed=9)
    full = read_csv(export_responses(study_dir, tmp_path / "full.csv", include_simulated=True).responses)
    other = make_demo_study(tmp_path / "other", videos=False, levels=(0, 25, 50))
    # a simulated participant stopped after 5 answers, then resumed
    import flipstudy.study.simulate as sim
    s = open_session(load_study(other), "sim001", source="simulated")
    for t in s.trials[:5]:
        r = next(x for x in full if int(x["trial"]) == t.trial)
        submit_answer(s, {"participant": "sim001", "session": 1, "trial": t.trial,
                          "stimulus": t.stimulus, "response": r["response"], "rt_ms": float(r["rt_ms"]),
                          "shown_ms": float(r["shown_ms"]), "late_frames": int(r["late_frames"]),
                          "input": "simulated"})
    sim.simulate(other, 1, seed=9)
    resumed = read_csv(export_responses(other, tmp_path / "resumed.csv", include_simulated=True).responses)
    assert [(r["trial"], r["response"]) for r in resumed] == [(r["trial"], r["response"]) for r in full]


def test_simulate_refuses_unknown_groups_before_storing(tmp_path):
    d = make_demo_study(tmp_path / "s", videos=False,
                        groups=(("wobble", "takeoff-angle", None, 1),), levels=(0, 10))
    with pytest.raises(ModelError, match="wobble"):
        simulate(d, 2)
    assert not (d / "sessions.sqlite").exists() or rows(d, "sessions") == 0


@pytest.mark.slow
def test_simulated_panel_reproduces_table_2(tmp_path):
    """A large panel's rating per cell lands near the model (the paper's Table 2)."""
    d = make_demo_study(tmp_path / "s", videos=False, repetitions=1,
                        groups=(("abrupt-decrease", "angular-momentum", "abrupt", -1),),
                        levels=(0, 17, 25, 37, 50))
    simulate(d, 80, seed=2)
    rs = read_csv(export_responses(d, tmp_path / "r.csv", include_simulated=True).responses)
    for lv, p in zip((0, 17, 25, 37, 50), (0.72, 0.83, 0.68, 0.33, 0.22)):
        cell = [r["response"] == "correct" for r in rs if r["level"] == str(lv)]
        assert len(cell) == 80
        se = math.sqrt(p * (1 - p) / 80) * 1.3
        assert abs(np.mean(cell) - p) < 4 * se, (lv, np.mean(cell), p)


@pytest.mark.shared("mocap/88_01.bvh")
def test_sessions_on_a_stimulus_set_built_from_motion_capture(tmp_path):
    """The manifest ``flipstudy stimuli`` writes (not the demo's) drives a session."""
    from conftest import SHARED_DIR
    from flipstudy.stimuli.design import parse_design
    from flipstudy.stimuli.stimset import build_stimuli
    from flipstudy.study.demo import demo_design_text
    text = demo_design_text(seed=11, levels=(0, 25)).replace(
        'source = "backflip"', f'source = "{SHARED_DIR / "mocap" / "88_01.bvh"}"\nfps = 60')
    text = text.replace("[study]", "[study]\ntolerance_pct = 12")
    (tmp_path / "d.toml").write_text(text)
    build_stimuli(parse_design(text, tmp_path / "d.toml"), tmp_path / "study", progress=False)
    d = tmp_path / "study"
    study = load_study(d)
    assert [r.stimulus for r in study.references] == ["backflip_reference"]
    simulate(d, 2, seed=4)
    rs = read_csv(export_responses(d, tmp_path / "r.csv", include_simulated=True).responses)
    assert len(rs) == 2 * 2 * 2 * 2
    assert {(r["group"], r["level"]) for r in rs} == {
        (g, lv) for g in ("smooth-increase", "abrupt-decrease") for lv in ("0", "25")}
    shown = [float(r["shown_ms"]) for r in rs]
    frames = study.by_name[rs[0]["stimulus"]].frames
    assert np.mean(shown) == pytest.approx(1000 * frames / 60.0, rel=0.05)
