"""`flipstudy reproduce`: the whole pipeline on the embedded default, end to end
(small videos and a small panel to keep the suite fast)."""
import csv
import json

import pytest

from flipstudy.study.cli import main
from flipstudy.errors import ReproduceError
from flipstudy.study.reproduce import reproduce


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("rp") / "paper"
    r = reproduce(out, participants=4, size=(160, 120), jobs=2, quiet=True)
    return out, r


@pytest.mark.slow
def test_every_stage_leaves_its_outputs(run):
    out, r = run
    man = list(csv.DictReader(open(out / "study" / "manifest.csv")))
    assert len(man) == r.n_stimuli == 46          # 2 references + 2 × (16 + 1 shared original + 5)
    for row in man:
        assert (out / "study" / "render" / f"{row['stimulus']}.mp4").stat().st_size > 1000
        assert (out / "study" / "render" / f"{row['stimulus']}_ghost.png").exists()
        assert (out / "study" / "render" / f"{row['stimulus']}_trail.png").exists()
    assert r.worst_gap_pct <= 1.0                # the design's tolerance, measured
    responses = list(csv.DictReader(open(out / "study" / "responses.csv")))
    assert len(responses) == r.n_responses == 4 * 88         # each of 44 motions twice
    assert {x["participant"] for x in responses} == {"sim001", "sim002", "sim003", "sim004"}
    table = list(csv.DictReader(open(out / "analysis" / "table.csv")))
    assert len(table) == 25                         # 5 groups × 5 levels (AM level 0: the shared original)
    zero = [t for t in table if float(t["level"]) == 0]
    assert all(abs(float(t["dprime"])) < 1e-12 for t in zero)   # d′ of an original is 0
    for name in ("ratings", "dprime", "psychometric", "sheet"):
        assert (out / "analysis" / f"{name}.png").stat().st_size > 10_000
        assert (out / "analysis" / f"{name}.pdf").exists()
    md = (out / "analysis" / "table_paper.md").read_text()
    assert "abrupt-decrease" in md and "(.00)" in md
    settings = json.loads((out / "study" / "render" / "render.json").read_text())
    assert settings["size"] == [160, 120] and settings["style"]["anti_aliasing"] == "fxaa"
    assert not list(out.parent.glob(".paper.partial-*"))
    assert settings["study"] == str((out / "study").resolve())
    assert ".partial-" not in (out / "analysis" / "summary.json").read_text()


@pytest.mark.slow
def test_existing_output_is_refused(run, tmp_path):
    out, _ = run
    with pytest.raises(ReproduceError, match="not empty"):
        reproduce(out, participants=2, size=(160, 120), quiet=True)


def test_a_failing_stage_leaves_nothing_behind(tmp_path, monkeypatch):
    import flipstudy.analysis.pipeline
    from flipstudy import analysis
    def boom(*a, **k):
        raise RuntimeError("analysis failed on purpose")

    monkeypatch.setattr(analysis.pipeline, "analyze", boom)
    import flipstudy.render.study
    from flipstudy import render
    def fake_render(study_dir, **k):                # skip the minutes of rendering
        return {"stimuli": {}}

    monkeypatch.setattr(render.study, "render_study", fake_render)
    out = tmp_path / "paper"
    with pytest.raises(RuntimeError, match="on purpose"):
        reproduce(out, participants=2, quiet=True)
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_cli_refuses_a_nonempty_folder_cleanly(tmp_path, capsys):
    (tmp_path / "x").mkdir()
    (tmp_path / "x" / "keep.txt").write_text("mine")
    assert main(["reproduce", "--out", str(tmp_path / "x"), "--quiet"]) == 1
    assert "not empty" in capsys.readouterr().err
    assert (tmp_path / "x" / "keep.txt").read_text() == "mine"


@pytest.mark.slow
def test_simulated_panel_is_marked_and_real_participants_go_elsewhere(run):
    out, r = run
    responses = list(csv.DictReader(open(out / "study" / "responses.csv")))
    assert {x["simulated"] for x in responses} == {"true"}
    notes = (out / "analysis" / "notes.md").read_text()
    assert "N = 4 participants (0 real, 4 simulated)" in notes
    assert "describe the observer model" in notes and "not meaningful" in notes
    text = r.summary()
    assert "4 simulated participants" in text and "fresh study" in text
    assert f"flipstudy run {out / 'study'}" not in text
    assert "--out mystudy" in text and "flipstudy run mystudy --participant P01" in text


@pytest.mark.slow
def test_force_refused_while_the_study_holds_a_real_answer(run, tmp_path):
    import hashlib
    import shutil

    from flipstudy.study.session import load_study, open_session, submit_answer
    out, _ = run
    copy = tmp_path / "paper"
    shutil.copytree(out, copy)
    s = open_session(load_study(copy / "study"), "P01")
    t = s.trials[0]
    submit_answer(s, {"participant": "P01", "session": 1, "trial": 1, "stimulus": t.stimulus,
                      "response": "correct", "rt_ms": 700.0, "shown_ms": 2000.0, "late_frames": 0})
    s.close()

    def snap():
        return {str(p.relative_to(copy)): hashlib.sha256(p.read_bytes()).hexdigest()
                for p in sorted(copy.rglob("*")) if p.is_file()}
    before = snap()
    with pytest.raises(OSError, match="1 answer of 1 real participant"):
        reproduce(copy, participants=2, size=(160, 120), quiet=True, force=True)
    assert snap() == before and sorted(p.name for p in tmp_path.iterdir()) == ["paper"]


@pytest.mark.slow                                   # builds the stimuli (about 5 s)
def test_the_records_name_the_output_not_the_build_folder(tmp_path, monkeypatch):
    """render.json and summary.json are written inside the hidden build folder; once it
    is moved to OUT they name OUT (the build folder no longer exists)."""
    import types

    import pandas as pd

    from flipstudy import analysis, render
    import flipstudy.analysis.pipeline  # noqa: F401
    import flipstudy.analysis.tables  # noqa: F401
    import flipstudy.render.study  # noqa: F401
    from flipstudy.render.record import write_record

    def fake_render(stimuli, **k):                  # records the study as render_study does
        rd = stimuli.folder / "render"
        rd.mkdir(exist_ok=True)
        rec = {"study": str(stimuli.folder.resolve()), "stimuli": {}}
        write_record(rd, rec)
        return types.SimpleNamespace(record=types.SimpleNamespace(stimuli={}))   # a RenderRecord with no stimulus

    def fake_analyze(responses, out, **k):          # records its files as analyze does
        out.mkdir(parents=True)
        names = ["table.csv", "table_paper.md", "table_paper.tex", "ratings.png", "dprime.png",
                 "psychometric.png", "sheet.png", "notes.md"]
        for n in names:
            (out / n).write_text("x")
        (out / "summary.json").write_text(json.dumps({"files": {n: str(out / n) for n in names}}))
        return types.SimpleNamespace(table=pd.DataFrame({"a": [1]}),
                                     to_dict=lambda: {"thresholds": []})

    monkeypatch.setattr(render.study, "render_study", fake_render)
    monkeypatch.setattr(analysis.pipeline, "analyze", fake_analyze)
    monkeypatch.setattr(analysis.tables, "to_markdown", lambda table: "")
    out = tmp_path / "paper"
    reproduce(out, participants=2, quiet=True)
    rec = json.loads((out / "study" / "render" / "render.json").read_text())
    assert rec["study"] == str((out / "study").resolve())
    summary = json.loads((out / "analysis" / "summary.json").read_text())
    assert summary["files"]["notes.md"] == str(out / "analysis" / "notes.md")
    for f in ("study/render/render.json", "analysis/summary.json"):
        assert ".partial-" not in (out / f).read_text()
