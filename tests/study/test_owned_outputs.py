"""Issue 45, items 1, 3 and 6: a command deletes or replaces only what it made itself.

Each failed on the code before this change (checked by stashing it):

1. ``export-web --force`` deleted a study two folders inside the old site folder
   (``proj/studies/s1`` with its answers); the owned-path check looked one level down.
3. ``stimuli --force`` deleted the researcher's ``consent.md`` / ``debrief.md`` (even
   with no answers at all) and the raw web results ``web/imports/*`` once
   ``web/responses.csv`` was gone.
6. ``score --figure`` and ``jump --composite`` wrote over a study's render
   (``STUDY/render/<stimulus>_ghost.png``).

The same rule for the other replacing paths, each failing before too:
``reproduce --force`` deleted a study deep inside OUT and a file it did not make,
``stimuli --force`` deleted a study inside its --out and (after a build killed
after the swap) a file written meanwhile, and ``render`` wrote over a file in
``render/`` that its ``render.json`` does not list.
"""
import hashlib
import shutil

import pytest

from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study, open_session, submit_answer
from flipstudy.study.simulate import simulate
from flipstudy.study.web.importer import import_web
from test_web_import import jsonl, run_records


def snapshot(folder):
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def answer(study, pid, n):
    s = open_session(load_study(study), pid)
    for t in s.trials[:n]:
        submit_answer(s, {"participant": pid, "session": s.session, "trial": t.trial,
                          "stimulus": t.stimulus, "response": "correct", "rt_ms": 500.0,
                          "shown_ms": 900.0, "late_frames": 0})
    s.close()


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.fixture(scope="module")
def jspsych(tmp_path_factory):
    from flipstudy.study.web import jspsych as jsp
    if shutil.which("npm") is None and not jsp.cache_root().is_dir():
        pytest.skip("needs npm to fetch jsPsych (apt-get install npm)")
    try:
        return str(jsp.fetch()[0])
    except jsp.JsPsychFetchError as e:
        pytest.skip(f"npm could not fetch jsPsych: {e}")


# --- 1: export-web --force and what is below its --out ------------------------------------------

def test_export_web_force_never_deletes_a_study_two_folders_down(tmp_path, jspsych, capsys):
    demo = make_demo_study(tmp_path / "demo")
    proj = tmp_path / "proj"
    assert cli(["export-web", str(demo), "--out", str(proj), "--jspsych-dir", jspsych]) == 0
    s1 = make_demo_study(proj / "studies" / "s1")
    answer(s1, "P01", 2)
    before = snapshot(proj)
    capsys.readouterr()
    code = cli(["export-web", str(s1), "--out", str(proj), "--force", "--jspsych-dir", jspsych])
    line = one_line(capsys.readouterr().err)
    assert code == 1 and str(s1) in line and "holds the study" in line
    assert snapshot(proj) == before                 # the site, the study and its answers


def test_export_web_force_replaces_only_the_earlier_sites_files(tmp_path, jspsych, capsys):
    demo = make_demo_study(tmp_path / "demo")
    site = tmp_path / "site"
    assert cli(["export-web", str(demo), "--out", str(site), "--jspsych-dir", jspsych]) == 0
    (site / "notes" / "deep").mkdir(parents=True)
    (site / "notes" / "deep" / "mine.txt").write_text("not the site's")
    capsys.readouterr()
    assert cli(["export-web", str(demo), "--out", str(site), "--force", "--jspsych-dir", jspsych]) == 1
    line = one_line(capsys.readouterr().err)
    assert "notes/deep/mine.txt" in line and "replaces only what it made itself" in line
    assert (site / "notes" / "deep" / "mine.txt").read_text() == "not the site's"
    (site / "notes" / "deep" / "mine.txt").unlink()
    assert cli(["export-web", str(demo), "--out", str(site), "--force", "--jspsych-dir", jspsych]) == 0


def test_a_study_is_recognised_at_any_depth(tmp_path):
    from flipstudy.study.owned import files_below, not_made, study_below
    deep = make_demo_study(tmp_path / "a" / "b" / "c" / "d", videos=False)
    assert study_below(tmp_path) == deep
    assert study_below(deep) is None and study_below(tmp_path / "a" / "b" / "c" / "d" / "render") is None
    (tmp_path / "x.txt").write_text("x")
    assert not_made(tmp_path, set(files_below(tmp_path)) - {"x.txt"}) == ["x.txt"]


def test_reproduce_force_never_deletes_a_study_deep_inside_or_a_file_it_did_not_make(tmp_path):
    from flipstudy.errors import FlipstudyError
    from flipstudy.study.reproduce import reproduce
    out = tmp_path / "paper"
    s1 = make_demo_study(out / "a" / "b" / "s1", videos=False)
    answer(s1, "P01", 2)
    before = snapshot(out)
    with pytest.raises(FlipstudyError, match=f"holds the study {s1}"):
        reproduce(out, participants=2, size=(160, 120), quiet=True, force=True)
    assert snapshot(out) == before
    shutil.rmtree(out / "a")
    (out / "notes.txt").write_text("mine")
    with pytest.raises(FlipstudyError, match="notes.txt"):
        reproduce(out, participants=2, size=(160, 120), quiet=True, force=True)
    assert (out / "notes.txt").read_text() == "mine"


def test_what_a_run_recorded_making_may_be_replaced_and_nothing_else(tmp_path):
    from flipstudy.errors import OwnedPathError
    from flipstudy.study.owned import made_by_record, record_made, refuse_not_made
    out = tmp_path / "paper"
    (out / "study" / ".locks").mkdir(parents=True)
    (out / "design.toml").write_text("x")
    (out / "analysis").mkdir()
    (out / "analysis" / "table.csv").write_text("x")
    record_made(out, "reproduce")
    (out / "study" / ".locks" / "open.lock").write_text("")      # a server's lock: no one's data
    (out / "analysis" / "table.csv").write_text("changed")          # its own file, changed: its own
    refuse_not_made(out, made_by_record(out), "reproduce --force", "the earlier run")
    (out / "analysis" / "mine.png").write_bytes(b"png")
    with pytest.raises(OwnedPathError, match="analysis/mine.png"):
        refuse_not_made(out, made_by_record(out), "reproduce --force", "the earlier run")


# --- 3: stimuli --force keeps what the researcher wrote and refuses raw web results --------------

def test_stimuli_force_keeps_the_researchers_files(tmp_path, capsys):
    st = make_demo_study(tmp_path / "st", videos=False)
    assert cli(["stimuli", str(st / "design.toml"), "--out", str(st), "--force", "--quiet"]) == 0
    simulate(st, 1, seed=1)                        # only simulated answers: the study may go
    (st / "consent.md").write_text("# Consent\n\nI agree.\n")
    (st / "debrief.md").write_text("Thank you.\n")
    (st / "analysis").mkdir()
    (st / "analysis" / "notes.txt").write_text("my notes")
    capsys.readouterr()
    assert cli(["stimuli", str(st / "design.toml"), "--out", str(st), "--force", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "sessions.sqlite" in out and "kept" in out and "consent.md" in out
    assert (st / "consent.md").read_text() == "# Consent\n\nI agree.\n"
    assert (st / "debrief.md").read_text() == "Thank you.\n"
    assert (st / "analysis" / "notes.txt").read_text() == "my notes"
    assert not (st / "sessions.sqlite").exists()    # the simulated answers went with the old set
    assert not [p for p in tmp_path.iterdir() if p.name != "st"]     # nothing left beside it


def test_a_killed_replace_leaves_the_researchers_files_to_the_next_build(tmp_path):
    st = make_demo_study(tmp_path / "st", videos=False)
    assert cli(["stimuli", str(st / "design.toml"), "--out", str(st), "--force", "--quiet"]) == 0
    old = tmp_path / ".st.old-4242"                # what a build SIGKILLed after the swap leaves
    shutil.copytree(st, old)
    (old / "late.txt").write_text("written while the killed build ran")
    assert cli(["stimuli", str(st / "design.toml"), "--out", str(st), "--force", "--quiet"]) == 0
    kept = [p for p in tmp_path.iterdir() if p.name.startswith("st.kept-")]
    assert len(kept) == 1 and (kept[0] / "late.txt").read_text() == "written while the killed build ran"
    assert sorted(p.name for p in kept[0].rglob("*") if p.is_file()) == ["late.txt"]
    assert not old.exists()


def test_stimuli_force_never_deletes_a_study_inside_it(tmp_path, capsys):
    st = make_demo_study(tmp_path / "st", videos=False)
    inner = make_demo_study(st / "old" / "pilot", videos=False)
    answer(inner, "P01", 2)
    before = snapshot(st)
    capsys.readouterr()
    assert cli(["stimuli", str(st / "design.toml"), "--out", str(st), "--force", "--quiet"]) == 1
    line = one_line(capsys.readouterr().err)
    assert f"holds the study {inner}" in line
    assert snapshot(st) == before


def test_stimuli_force_refuses_a_study_with_raw_web_results(tmp_path, capsys):
    st = make_demo_study(tmp_path / "st", videos=False)
    import_web(st, [jsonl(tmp_path / "w.jsonl", run_records(st, "W01"))])
    (st / "web" / "responses.csv").unlink()        # as in the issue: the tables are gone,
    shutil.rmtree(st / "web" / "data")              # only the raw results are left
    before = snapshot(st)
    assert [f for f in before if f.startswith("web/imports/")]
    capsys.readouterr()
    assert cli(["stimuli", str(st / "design.toml"), "--out", str(st), "--force", "--quiet"]) == 1
    line = one_line(capsys.readouterr().err)
    assert "raw web result" in line and "web/imports/" in line
    assert snapshot(st) == before
    assert cli(["init", str(st / "design.toml"), "--force", "--preset", "gravity"]) == 1   # frozen
    assert "raw web result" in one_line(capsys.readouterr().err)
    assert snapshot(st) == before


# --- 6: score --figure and jump --composite onto a study's render ------------------------------

@pytest.mark.parametrize("argv", [["score", "backflip", "--figure"],
                                  ["jump", "--out", "{tmp}/j.bvh", "--composite"]])
def test_figures_never_write_over_a_studys_render(tmp_path, argv, capsys):
    st = make_demo_study(tmp_path / "st")
    target = st / "render" / "backflip_reference_ghost.png"
    target.write_bytes(b"the study's ghost")
    capsys.readouterr()
    assert cli([a.format(tmp=tmp_path) for a in argv] + [str(target)]) == 1
    line = one_line(capsys.readouterr().err)
    assert str(target) in line and "does not write over a study's own files" in line
    assert target.read_bytes() == b"the study's ghost"


def test_render_never_writes_over_a_file_it_did_not_make(tmp_path, capsys):
    demo = make_demo_study(tmp_path / "demo", videos=False)
    st = tmp_path / "st"
    assert cli(["stimuli", str(demo / "design.toml"), "--out", str(st), "--quiet"]) == 0
    mine = st / "render" / "backflip_reference_ghost.png"
    mine.parent.mkdir()
    mine.write_bytes(b"the researcher's picture")
    capsys.readouterr()
    assert cli(["render", str(st), "--what", "ghost", "--size", "64x48", "--quiet"]) == 1
    line = one_line(capsys.readouterr().err)
    assert str(mine) in line and "not made by `flipstudy render`" in line
    assert mine.read_bytes() == b"the researcher's picture"
