"""Issue 28, case 3: a study's design is frozen once it has an answer.

Before this change ``init st/design.toml --force --preset gravity`` rewrote the
design of a study with answers, the next participant got another number of
trials and ``status``/``export`` noticed nothing (this file failed there,
checked).  Now: ``init --force`` into a study with answers (local, simulated or
imported from the web) is refused; the design is recorded with the first answer;
a design.toml edited by hand afterwards is refused by ``run``, ``simulate``,
``export`` and ``analyze`` and flagged by ``status``, naming the file and the keys.
"""
import sqlite3

import pytest

from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study, open_session, submit_answer
from flipstudy.study.simulate import simulate


@pytest.fixture
def st(tmp_path):
    return make_demo_study(tmp_path / "st", video_frames=6)


def _answer(s, n=1):
    t = s.trials[n - 1]
    return submit_answer(s, {"participant": s.participant, "session": s.session, "trial": n,
                             "stimulus": t.stimulus, "response": "correct", "rt_ms": 300.0,
                             "shown_ms": 900.0, "late_frames": 0})


@pytest.mark.parametrize("preset", ["gravity", "time-scale", "flipping-with-physics-2007"])
def test_init_force_is_refused_on_a_study_with_a_local_answer(st, preset, capsys):
    before = (st / "design.toml").read_bytes()
    s = open_session(load_study(st), "P01")
    assert _answer(s)["status"] == "stored"
    assert cli(["init", str(st / "design.toml"), "--force", "--preset", preset]) == 1
    err = capsys.readouterr().err
    assert str(st / "design.toml") in err and "frozen" in err
    assert (st / "design.toml").read_bytes() == before


def test_init_force_is_refused_with_simulated_or_web_answers_only(st, tmp_path, capsys):
    simulate(st, 1, seed=1)
    assert cli(["init", str(st / "design.toml"), "--force", "--preset", "gravity"]) == 1
    other = make_demo_study(tmp_path / "web-only", videos=False)
    (other / "web").mkdir()
    (other / "web" / "responses.csv").write_text("participant,response\nW01,correct\n")
    assert cli(["init", str(other / "design.toml"), "--force", "--preset", "gravity"]) == 1
    assert "frozen" in capsys.readouterr().err
    # a study without any answer may still get another design
    fresh = make_demo_study(tmp_path / "fresh", videos=False)
    assert cli(["init", str(fresh / "design.toml"), "--force", "--preset", "gravity"]) == 0


def test_the_design_is_recorded_with_the_first_answer(st):
    text = (st / "design.toml").read_bytes()
    s = open_session(load_study(st), "P01")
    conn = sqlite3.connect(st / "sessions.sqlite")
    assert conn.execute("SELECT value FROM meta WHERE key='design_sha256'").fetchone() is None
    _answer(s)
    import hashlib
    rec = dict(conn.execute("SELECT key, value FROM meta").fetchall())
    conn.close()
    assert rec["design_sha256"] == hashlib.sha256(text).hexdigest()
    assert rec["design_toml"].encode() == text


def test_a_design_edited_after_the_first_answer_is_refused_and_flagged(st, tmp_path, capsys):
    s = open_session(load_study(st), "P01")
    _answer(s)
    assert cli(["export", str(st)]) == 0
    capsys.readouterr()
    path = st / "design.toml"
    path.write_text(path.read_text().replace("repetitions = 2", "repetitions = 3"))
    for argv in (["export", str(st)], ["analyze", str(st / "responses.csv"), "--out",
                                       str(tmp_path / "a")],
                 ["simulate", str(st), "--participants", "1"]):
        assert cli(argv) != 0, argv
        err = capsys.readouterr().err
        assert str(path) in err and "repetitions: 2 → 3" in err, (argv, err)
    with pytest.raises(Exception, match="repetitions: 2 → 3"):
        open_session(load_study(st), "P02")                   # what `run` opens
    assert cli(["status", str(st)]) == 0                       # status still shows, loudly
    err = capsys.readouterr().err
    assert "WARNING" in err and str(path) in err
    # the design restored: everything works again
    path.write_text(path.read_text().replace("repetitions = 3", "repetitions = 2"))
    assert cli(["export", str(st)]) == 0
    # an open session whose study's design changed under it stores nothing more
    path.write_text(path.read_text().replace("repetitions = 2", "repetitions = 3"))
    s.study.design_text = path.read_text()
    from flipstudy.study.validate import RequestError
    with pytest.raises(RequestError, match="frozen"):
        _answer(s, 2)
