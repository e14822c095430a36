"""`flipstudy render` never replaces the videos of a study holding real answers: the
participants answered them as they are, and the next one would see other pictures
(found by trying `render paper/study --framing stimulus` as a new user: it remade all
46 videos of a study with answers).  Simulated answers only, or none: it renders."""
from __future__ import annotations

import hashlib

import pytest

from flipstudy.study.cli import main as cli
from flipstudy.study.session import load_study, open_session, submit_answer

DESIGN = """[study]
name = "seen"
seed = 2
repetitions = 1

[[clips]]
name = "jump"
source = "jump"

[[groups]]
name = "takeoff-increase"
kind = "takeoff-angle"
levels = [0, 20]
"""


def _study(tmp_path):
    (tmp_path / "d.toml").write_text(DESIGN)
    st = tmp_path / "st"
    assert cli(["stimuli", str(tmp_path / "d.toml"), "--out", str(st), "--quiet"]) == 0
    assert cli(["render", str(st), "--size", "64x48", "--video-fps", "10", "--quiet"]) == 0
    return st


def _videos(st) -> dict:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in (st / "render").glob("*.mp4")}


def _real_answer(st) -> None:
    s = open_session(load_study(st), "P01")
    t = s.trials[0]
    assert submit_answer(s, {"participant": s.participant, "session": s.session, "trial": 1,
                             "stimulus": t.stimulus, "response": "correct", "rt_ms": 300.0,
                             "shown_ms": 900.0, "late_frames": 0})["status"] == "stored"
    s.close()


@pytest.mark.slow
@pytest.mark.parametrize("args", [["--size", "80x60"], ["--framing", "stimulus"], ["--force"]])
def test_render_refuses_to_replace_videos_real_participants_saw(tmp_path, capsys, args):
    st = _study(tmp_path)
    _real_answer(st)
    before = _videos(st)
    record = (st / "render" / "render.json").read_bytes()
    assert before
    capsys.readouterr()
    assert cli(["render", str(st), "--video-fps", "10", "--quiet", *(args if "--size" in args
                                                                     else ["--size", "64x48", *args])]) == 1
    err = capsys.readouterr().err
    assert "1 answer of 1 real participant" in err and "video(s)" in err
    assert f"flipstudy archive {st}" in err and "--out NEW" in err
    assert _videos(st) == before and (st / "render" / "render.json").read_bytes() == record
    assert not [p for p in (st / "render").iterdir() if p.name.startswith(".")]


@pytest.mark.slow
def test_render_remakes_videos_of_a_study_with_simulated_answers_only(tmp_path, capsys):
    from flipstudy.study.simulate import simulate
    st = _study(tmp_path)
    simulate(st, 1, seed=1)
    before = _videos(st)
    assert cli(["render", str(st), "--size", "80x60", "--video-fps", "10", "--quiet"]) == 0
    after = _videos(st)
    assert after.keys() == before.keys() and all(after[k] != before[k] for k in after)
