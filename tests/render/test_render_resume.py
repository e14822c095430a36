"""Interrupting and resuming `flipstudy render` (and Ctrl-C in `flipstudy stimuli`).

Real subprocesses, signals as a terminal sends them (Ctrl-C goes to the whole
process group), and the process table (/proc) read for what is left: every
descendant of the command seen while it ran must be gone within a few
seconds.  Tiny stimuli (64x48 videos) keep the file fast."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flipstudy.errors import StaleRenderError
from flipstudy.render.record import check_rendered
from flipstudy.render.study import render_study
from test_render import _write_study, jumper

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")


def _ppids() -> dict[int, int]:
    out = {}
    for e in os.listdir("/proc"):
        if e.isdigit():
            try:
                st = Path(f"/proc/{e}/stat").read_text()
            except OSError:
                continue
            out[int(e)] = int(st.rsplit(")", 1)[1].split()[1])
    return out


def descendants(pid: int) -> dict[int, bytes]:
    """pid -> command line of every process below ``pid`` now."""
    ps, found, front = _ppids(), set(), {pid}
    while front:
        front = {c for c, pp in ps.items() if pp in front} - found
        found |= front
    out = {}
    for p in found:
        try:
            out[p] = Path(f"/proc/{p}/cmdline").read_bytes()
        except OSError:
            pass
    return out


def running(pids) -> list[str]:
    """The pids still alive (zombies count as gone), with their command lines."""
    alive = []
    for p in pids:
        try:
            state = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()[0]
            if state != "Z":
                alive.append(f"{p}: " + Path(f"/proc/{p}/cmdline").read_bytes()
                             .replace(b"\0", b" ").decode(errors="replace")[:120])
        except OSError:
            pass
    return alive


def wait_gone(pids, seconds=10.0) -> list[str]:
    t_end = time.monotonic() + seconds
    while (alive := running(pids)) and time.monotonic() < t_end:
        time.sleep(0.2)
    return alive


def start(args):
    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONUNBUFFERED="1")
    return subprocess.Popen([sys.executable, "-m", "flipstudy.study.cli", *args], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)     # its own group, like a terminal job


def n_recorded(study) -> int:
    try:
        return len(json.loads((study / "render" / "render.json").read_text())["outputs"])
    except (OSError, ValueError, KeyError):
        return 0


def wait_for(proc, cond, seen: dict, seconds=90.0) -> None:
    """Poll ``cond()`` while collecting ``proc``'s descendants (pid -> cmdline)."""
    t_end = time.monotonic() + seconds
    while time.monotonic() < t_end:
        seen.update(descendants(proc.pid))
        if cond():
            seen.update(descendants(proc.pid))
            return
        assert proc.poll() is None, f"exited early: {proc.communicate()}"
        time.sleep(0.05)
    proc.kill()
    raise AssertionError(f"timed out: {proc.communicate()}")


def snapshot(study) -> dict:
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns, p.stat().st_size)
            for p in (study / "render").glob("*.mp4")}


def tiny_study(folder: Path, n: int) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    a, t0, t1 = jumper(flip=2.0)
    _write_study(folder, [(f"s{k:02d}", a, 0 if k == 0 else k) for k in range(n)], t0, t1)
    return folder


RENDER = ["--size", "64x48", "--video-fps", "30", "--jobs", "2", "--quiet"]


@pytest.mark.slow
def test_ctrl_c_stops_render_at_once_and_a_rerun_makes_only_the_rest(tmp_path, monkeypatch):
    n = 6
    study = tiny_study(tmp_path / "study", n)
    proc = start(["render", str(study), *RENDER])
    seen: dict = {}
    wait_for(proc, lambda: n_recorded(study) >= 1, seen)
    assert len(seen) >= 3                                   # two workers and the tracker
    os.killpg(proc.pid, signal.SIGINT)                      # Ctrl-C in the terminal
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    assert err.splitlines() == ["flipstudy render: interrupted"]
    assert wait_gone(seen) == []
    # nothing half-written: only complete, recorded outputs under their names
    rec = json.loads((study / "render" / "render.json").read_text())
    made = set(rec["outputs"])
    assert 1 <= len(made) < n, "the render was not interrupted mid-way"
    names = {p.name for p in (study / "render").iterdir()}
    assert names == made | {"render.json"}, names
    before = snapshot(study)

    # the rerun (in this process, one worker) makes only what is missing
    rec2 = render_study(study, size=(64, 48), fps=30.0, jobs=1, progress=False)
    assert rec2.made == n - len(made) and rec2.up_to_date == len(made)
    after = snapshot(study)
    assert {k: after[k] for k in before} == before         # not one of them touched
    assert check_rendered(study)["size"] == [64, 48]

    # a rerun of a finished render touches no video
    rec3 = render_study(study, size=(64, 48), fps=30.0, jobs=1, progress=False)
    assert rec3.made == 0 and rec3.up_to_date == n and snapshot(study) == after
    # a stimulus changed after rendering: only its video is stale
    bvh = study / "s03.bvh"
    bvh.write_text(bvh.read_text().replace("Frame Time:", "Frame Time:", 1) + "\n")
    rec4 = render_study(study, size=(64, 48), fps=30.0, jobs=1, progress=False)
    assert rec4.made == 1
    assert {k for k, v in snapshot(study).items() if v != after[k]} == {"s03.mp4"}

    # a re-render at another size, interrupted after two stimuli: mixed sizes, refused
    import flipstudy.render.workers as rs
    real, calls = rs._render_task, []

    def interrupted(task):
        if len(calls) == 2:
            raise KeyboardInterrupt
        calls.append(task["stimulus"])
        return real(task)
    monkeypatch.setattr(rs, "_render_task", interrupted)
    with pytest.raises(KeyboardInterrupt):
        render_study(study, size=(96, 64), fps=30.0, jobs=1, progress=False)
    assert not list((study / "render").glob(".partial-*"))
    with pytest.raises(StaleRenderError) as e:
        check_rendered(study)
    msg = str(e.value)
    assert f"{calls[0]}.mp4, {calls[1]}.mp4: 2 made with 96x64 at 30 fps" in msg
    assert f"the other {n - 2} with 64x48 at 30 fps" in msg
    assert f"flipstudy render {study}" in msg


@pytest.mark.slow
def test_sigkill_of_render_leaves_no_worker(tmp_path):
    study = tiny_study(tmp_path / "study", 6)
    proc = start(["render", str(study), *RENDER])
    seen: dict = {}
    wait_for(proc, lambda: n_recorded(study) >= 1, seen)
    workers = {p for p, cmd in seen.items() if b"spawn_main" in cmd}
    assert len(workers) >= 2, seen
    os.kill(proc.pid, signal.SIGKILL)                        # the parent only
    proc.communicate(timeout=10)
    assert wait_gone(seen, 10.0) == []
    # what the killed run was writing never appears under an output's name, and
    # the next run clears it and finishes the job
    from flipstudy.render.record import file_sha256
    outputs = json.loads((study / "render" / "render.json").read_text())["outputs"]
    made = set(outputs)
    assert made and all(file_sha256(study / "render" / f) == o["sha256"] for f, o in outputs.items())
    rec = render_study(study, size=(64, 48), fps=30.0, jobs=1, progress=False)
    assert rec.made == 6 - len(made) and not list((study / "render").glob(".partial-*"))


def test_ctrl_c_in_stimuli_is_one_line_and_leaves_nothing(tmp_path):
    from flipstudy.stimuli.design import PAPER_DESIGN
    design = tmp_path / "design.toml"
    design.write_text(PAPER_DESIGN)
    out = tmp_path / "study"
    proc = start(["stimuli", str(design), "--out", str(out), "--quiet"])
    seen: dict = {}
    wait_for(proc, lambda: any(tmp_path.glob(".study.tmp-*/*.bvh")), seen)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    assert err.splitlines() == ["flipstudy stimuli: interrupted"]
    assert wait_gone({*seen, proc.pid}) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design.toml"]
