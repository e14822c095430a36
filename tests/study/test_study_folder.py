"""A study folder with answers is never deleted or replaced: --force refused while
real answers are there, one build at a time (lock), SIGKILLed builds never leave
--out without a complete study, leftovers cleaned, `flipstudy archive`."""
import hashlib
import os
import random
import signal
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import pytest

from flipstudy.stimuli.design import parse_design
from flipstudy.errors import StudyFolderError, StudyHasAnswersError, StudyLockedError
from flipstudy.stimuli.contract import StimulusSet
from flipstudy.stimuli.stimset import (build_stimuli,
                             study_lock)
from flipstudy.study.archive import answers_in, refuse_real_answers
from flipstudy.study.cli import main as flipstudy
from flipstudy.study.session import load_study, open_session, submit_answer

ROOT = Path(__file__).resolve().parents[2]

DESIGN = """[study]
name = "tiny"
seed = {seed}
repetitions = 1

[[clips]]
name = "backflip"
source = "backflip"

[reference]
clips = ["backflip"]

[[groups]]
name = "smooth-increase"
kind = "angular-momentum"
profile = "smooth"
sign = 1
levels = [0, 25]
"""


def design_file(tmp_path, seed=3) -> Path:
    p = tmp_path / f"d{seed}.toml"
    p.write_text(DESIGN.format(seed=seed))
    return p


def snapshot(folder: Path) -> dict:
    """Every file below ``folder`` → its SHA-256 (sqlite side files included)."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def complete(folder: Path) -> str:
    """'' when ``folder`` holds a complete build (manifest, every listed file with
    the manifest's hash, nothing else but design.toml); else what is wrong."""
    if not folder.is_dir():
        return "missing"
    try:
        rows = StimulusSet.read(folder, files=False, design=False).rows()
    except FileNotFoundError:
        return "no manifest"
    want = {"manifest.csv"} | {r["bvh"] for r in rows} | {r["npz"] for r in rows}
    have = {p.name for p in folder.iterdir()} - {"design.toml"}   # absent when built from text
    if have != want:
        return f"files {sorted(have ^ want)}"
    for r in rows:
        if hashlib.sha256((folder / r["bvh"]).read_bytes()).hexdigest() != r["sha256"]:
            return f"{r['bvh']}: hash"
    return ""


def answer(session, n, pid="P01"):
    for t in session.trials[:n]:
        submit_answer(session, {"participant": pid, "session": session.session, "trial": t.trial,
                                "stimulus": t.stimulus, "response": "correct", "rt_ms": 500.0,
                                "shown_ms": 900.0, "late_frames": 0})


def leftovers(parent: Path, name: str) -> list[str]:
    return sorted(p.name for p in parent.iterdir() if p.name.startswith(f".{name}."))


@pytest.fixture
def study(tmp_path):
    d = design_file(tmp_path)
    assert flipstudy(["stimuli", str(d), "--out", str(tmp_path / "study"), "--quiet"]) == 0
    return tmp_path / "study"


# --- --force and answers ---------------------------------------------------------------------

def test_force_refused_on_a_study_with_real_answers_and_nothing_changes(study, tmp_path, capsys):
    s = open_session(load_study(study), "P01")
    answer(s, 2)
    s.close()
    before = snapshot(study)
    assert "sessions.sqlite" in before
    capsys.readouterr()
    code = flipstudy(["stimuli", str(design_file(tmp_path, 4)), "--out", str(study), "--force",
                      "--quiet"])
    err = capsys.readouterr().err
    assert code == 1
    assert "2 answers of 1 real participant" in err and f"flipstudy archive {study}" in err
    assert snapshot(study) == before
    assert leftovers(tmp_path, "study") == []
    # the library refuses too, without any check passed in: sessions.sqlite is not a build file
    with pytest.raises(StudyFolderError, match="sessions.sqlite"):
        build_stimuli(parse_design(DESIGN.format(seed=4)), study, force=True, progress=False)
    with pytest.raises(StudyHasAnswersError):
        build_stimuli(parse_design(DESIGN.format(seed=4)), study, force=True, progress=False,
                      replace_check=refuse_real_answers)
    assert snapshot(study) == before


def test_force_replaces_a_study_with_only_simulated_answers_and_says_so(study, tmp_path, capsys):
    from flipstudy.study.simulate import simulate
    simulate(study, 2, seed=1)
    assert answers_in(study)["real_answers"] == 0
    capsys.readouterr()
    assert flipstudy(["stimuli", str(design_file(tmp_path, 4)), "--out", str(study), "--force",
                      "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "simulated participant" in out and "sessions.sqlite" in out
    assert complete(study) == "" and StimulusSet.read(study, files=False, design=False).rows()[0]["seed"] != ""
    assert leftovers(tmp_path, "study") == []


def test_an_exported_response_table_of_real_participants_also_protects(study, tmp_path):
    (study / "responses.csv").write_text("participant,group,level,response,input\n"
                                         "P07,g,0,correct,click\n")
    with pytest.raises(StudyHasAnswersError, match="1 answer of 1 real participant"):
        build_stimuli(parse_design(DESIGN.format(seed=4)), study, force=True, progress=False,
                      replace_check=refuse_real_answers)
    # an unreadable database counts as holding answers
    (study / "responses.csv").unlink()
    (study / "sessions.sqlite").write_bytes(b"not a database at all, but maybe someone's answers")
    with pytest.raises(StudyHasAnswersError, match="could not be read"):
        refuse_real_answers(study)


def test_archive_moves_everything_then_a_fresh_build(study, tmp_path, capsys):
    s = open_session(load_study(study), "P01")
    answer(s, 2)
    s.close()
    before = snapshot(study)
    capsys.readouterr()
    assert flipstudy(["archive", str(study)]) == 0
    out = capsys.readouterr().out
    dest = [p for p in tmp_path.iterdir() if p.name.startswith("study-archived-")]
    assert len(dest) == 1 and str(dest[0]) in out and "2 answers of 1 real" in out
    assert snapshot(dest[0]) == before and not study.exists()
    assert flipstudy(["stimuli", str(design_file(tmp_path)), "--out", str(study), "--quiet"]) == 0
    assert complete(study) == "" and snapshot(dest[0]) == before


# --- one build at a time ---------------------------------------------------------------------

SLOW_BUILD = """
import os, sys, time
import flipstudy.stimuli.stimset as ss
from flipstudy.stimuli.design import load_design
orig_clean, orig_measure = ss._recover_and_clean, ss.measure
def clean(out):
    orig_clean(out)
    print("locked", flush=True)
def measure(*a, **k):                    # hold the build until the test says go
    t0 = time.time()
    while not os.path.exists(sys.argv[3]) and time.time() - t0 < 60:
        time.sleep(0.02)
    return orig_measure(*a, **k)
ss._recover_and_clean, ss.measure = clean, measure
ss.build_stimuli(load_design(sys.argv[1]), sys.argv[2], progress=False)
print("built", flush=True)
"""


def _env():
    return {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}


@contextmanager
def slow_build(tmp_path, seed, out):
    """A ``SLOW_BUILD`` subprocess of the design of ``seed`` into ``out``, holding the
    lock (it has printed "locked") until ``tmp_path / "go"`` exists; yields the
    process and that path, and kills the process on the way out if it still runs."""
    go = tmp_path / "go"
    a = subprocess.Popen([sys.executable, "-c", SLOW_BUILD, str(design_file(tmp_path, seed)), str(out),
                          str(go)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env())
    try:
        assert a.stdout.readline().strip() == "locked"
        yield a, go
    finally:
        if a.poll() is None:
            a.kill()
            a.wait()


def test_two_concurrent_builds_the_second_fails_at_once(tmp_path):
    out = tmp_path / "study"
    with slow_build(tmp_path, 3, out) as (a, go):
        b = subprocess.run([sys.executable, "-m", "flipstudy.study.cli", "stimuli",
                            str(design_file(tmp_path, 4)), "--out", str(out), "--force", "--quiet"],
                           capture_output=True, text=True, env=_env(), timeout=60)
        assert a.poll() is None                         # the first build still runs ...
        assert b.returncode == 1
        assert "is writing this study folder right now" in b.stderr and "pid" in b.stderr
        go.touch()
        assert a.wait(timeout=60) == 0, a.stderr.read()
    assert complete(out) == "" and StimulusSet.read(out, files=False, design=False).rows()[0]["seed"] != ""
    # the study is the first build's (design seed 3), and the lock file is gone
    assert (out / "design.toml").read_text() == DESIGN.format(seed=3)
    assert leftovers(tmp_path, "study") == []


def test_lock_is_exclusive_in_process_and_released(tmp_path):
    out = tmp_path / "s"
    with study_lock(out):
        with pytest.raises(StudyLockedError, match="is writing"):
            build_stimuli(parse_design(DESIGN.format(seed=3)), out, progress=False)
        with pytest.raises(StudyLockedError):
            with study_lock(out):
                pass
    build_stimuli(parse_design(DESIGN.format(seed=3)), out, progress=False)
    assert complete(out) == "" and leftovers(tmp_path, "s") == []


def test_a_study_copied_to_out_while_a_build_runs_is_kept(study, tmp_path):
    out = tmp_path / "late"
    with slow_build(tmp_path, 4, out) as (a, go):
        s = open_session(load_study(study), "P01")
        answer(s, 1)
        s.close()
        import shutil
        shutil.copytree(study, out)
        before = snapshot(out)
        go.touch()
        assert a.wait(timeout=60) != 0
        assert "appeared while the build ran" in a.stderr.read()
    assert snapshot(out) == before and leftovers(tmp_path, "late") == []


# --- SIGKILL at random moments -----------------------------------------------------------------

LOOP_BUILD = """
import os, shutil, sys, time
import flipstudy.stimuli.stimset as ss
from flipstudy.stimuli.design import load_design
from flipstudy.stimuli.stimset import build_stimuli

def slow(fn):                             # widen every folder step, so that kills land there too
    def f(*a, **k):
        time.sleep(0.1)
        r = fn(*a, **k)
        time.sleep(0.1)
        return r
    return f
ss._renameat2, os.rename, shutil.rmtree = slow(ss._renameat2), slow(os.rename), slow(shutil.rmtree)
designs = [load_design(p) for p in sys.argv[2:]]
print("ready", flush=True)
i = 0
while True:
    build_stimuli(designs[i % len(designs)], sys.argv[1], force=True, progress=False)
    i += 1
    print("built", i, flush=True)
"""


@pytest.mark.slow
def test_sigkilled_builds_never_leave_out_without_a_complete_study(tmp_path):
    out = tmp_path / "study"
    d3, d4 = design_file(tmp_path, 3), design_file(tmp_path, 4)
    t0 = time.perf_counter()
    build_stimuli(parse_design(d3.read_text(), d3), out, progress=False)
    span = 3.0 * (time.perf_counter() - t0) + 0.4        # a few builds' time on this machine now
    rng = random.Random(15)
    seen, builds = set(), 0
    for k in range(10):
        now = d3 if (out / "design.toml").read_text() == d3.read_text() else d4
        order = [d4, d3] if now == d3 else [d3, d4]     # the first build changes the study
        p = subprocess.Popen([sys.executable, "-c", LOOP_BUILD, str(out), *map(str, order)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env())
        try:
            assert p.stdout.readline().strip() == "ready", p.stderr.read()
            time.sleep(rng.uniform(0.1, span))          # inside some build, swap or clean-up
        finally:
            p.send_signal(signal.SIGKILL)
            p.wait()
        builds += sum(1 for ln in p.stdout.read().splitlines() if ln.startswith("built"))
        assert complete(out) == "", f"kill {k}: {complete(out)}"
        seen.add((out / "design.toml").read_text())
    assert builds >= 2                                  # the kills fell among real builds
    assert len(seen) == 2                               # and the study did change between them
    # the next build cleans what the killed ones left
    build_stimuli(parse_design(d3.read_text(), d3), out, force=True, progress=False)
    assert complete(out) == "" and leftovers(tmp_path, "study") == []


def test_without_exchange_a_build_killed_between_the_renames_is_restored(tmp_path, monkeypatch):
    """The fallback scheme (no renameat2): out renamed to .NAME.old-PID, then the kill."""
    import flipstudy.stimuli.stimset as ss
    out = tmp_path / "study"
    d = parse_design(DESIGN.format(seed=3))
    build_stimuli(d, out, progress=False)
    before = snapshot(out)
    monkeypatch.setattr(ss, "_renameat2", lambda *a: False)
    os.rename(out, tmp_path / ".study.old-999999")      # the state the kill leaves
    (tmp_path / ".study.tmp-999999-x").mkdir()          # and a half-written build
    with pytest.raises(FileExistsError):                # the next build restores the study first
        build_stimuli(d, out, progress=False)
    assert snapshot(out) == before and leftovers(tmp_path, "study") == []
    build_stimuli(parse_design(DESIGN.format(seed=4)), out, force=True, progress=False)
    assert complete(out) == "" and snapshot(out) != before
    assert leftovers(tmp_path, "study") == []
