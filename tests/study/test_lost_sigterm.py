"""Issue 28, case 10: SIGTERM of ``stimuli`` or ``render`` is handled like Ctrl-C.

Real subprocesses.  Before this change SIGTERM killed them with no message,
leaving ``.NAME.lock`` and ``.NAME.tmp-*`` beside the study (checked: this file
failed there, status -15).  Now: one line ``flipstudy CMD: terminated``, exit
status 143 (128 + SIGTERM, what a shell reports for a SIGTERM death, so a
scheduler still sees the cause), and nothing half-written or locked is left.
"""
import pytest
import json
import os
import signal

from test_render_resume import RENDER, n_recorded, start, tiny_study, wait_for, wait_gone

from flipstudy.study.cli import main as cli


def _leftovers(parent, name):
    return sorted(p.name for p in parent.iterdir() if p.name.startswith(f".{name}."))


def _stimuli_terminated(tmp_path, design, out, *extra):
    proc = start(["stimuli", str(design), "--out", str(out), "--quiet", *extra])
    seen: dict = {}
    wait_for(proc, lambda: any(p.name.startswith(f".{out.name}.tmp-") and any(p.iterdir())
                               for p in tmp_path.iterdir() if p.is_dir()), seen)
    os.kill(proc.pid, signal.SIGTERM)                        # `kill PID`: the process only
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert err.splitlines() == ["flipstudy stimuli: terminated"]
    assert _leftovers(tmp_path, out.name) == []              # no .st.lock, no .st.tmp-*


@pytest.mark.slow
def test_sigterm_of_stimuli_leaves_no_lock_no_staging_and_the_old_study(tmp_path):
    from flipstudy.study.demo import demo_design_text
    design = tmp_path / "design.toml"
    assert cli(["init", str(design)]) == 0                   # the paper's design: ~50 stimuli
    out = tmp_path / "st"
    _stimuli_terminated(tmp_path, design, out)
    assert not out.exists()
    small = tmp_path / "small.toml"
    small.write_text(demo_design_text())
    assert cli(["stimuli", str(small), "--out", str(out), "--quiet"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    _stimuli_terminated(tmp_path, design, out, "--force")    # the previous study stays as it was
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.slow
def test_sigterm_of_render_stops_its_workers_and_leaves_only_recorded_videos(tmp_path):
    n = 6
    study = tiny_study(tmp_path / "study", n)
    proc = start(["render", str(study), *RENDER])
    seen: dict = {}
    wait_for(proc, lambda: n_recorded(study) >= 1, seen)
    os.kill(proc.pid, signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert err.splitlines() == ["flipstudy render: terminated"]
    assert wait_gone(seen) == []                             # no worker left running
    rec = json.loads((study / "render" / "render.json").read_text())
    made = set(rec["outputs"])
    assert 1 <= len(made) < n, "the render was not stopped mid-way"
    from flipstudy.stimuli.contract import file_sha256
    for name, entry in rec["outputs"].items():               # each recorded file is whole
        assert file_sha256(study / "render" / name) == entry["sha256"], name
    assert {p.name for p in (study / "render").iterdir()} == made | {"render.json"}
    assert _leftovers(tmp_path, "study") == []
    assert not any(p.name.endswith((".lock", ".tmp")) or ".tmp-" in p.name
                   for p in study.rglob("*")), sorted(map(str, study.rglob("*")))
