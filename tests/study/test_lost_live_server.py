"""Issue 28, case 1: a serving session holds its study.

A real ``flipstudy run`` subprocess on 127.0.0.1 takes answers over HTTP while
other processes try to rebuild, archive, re-init or reproduce onto the study.
Afterwards every answer the server acknowledged as "stored" is in the study's
``sessions.sqlite``.  On the code before this change the rebuild succeeded
(``stimuli --out st --force``: the study had no real answers yet), the server
went on answering "stored" into the replaced database and the answers were lost
(checked: this file failed there with the acknowledged answers missing).
"""
import http.client
import json
import os
import shutil
import sqlite3
import subprocess
import sys

import pytest

from _run_server import ROOT, Run
from flipstudy.study.demo import make_demo_study


def _cli(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "flipstudy.study.cli", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, env=env, timeout=120)


class Page:
    """What the participant page does: fetch the current trial, post its answer."""

    def __init__(self, url):
        self.port = int(url.rsplit(":", 1)[1].strip("/"))

    def req(self, method, path, body=None):
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=20)
        headers = {"Host": f"127.0.0.1:{self.port}"}
        data = None
        if body is not None:
            data = json.dumps(body).encode()
            headers["Content-Type"] = "application/json"
        conn.request(method, path, body=data, headers=headers)
        r = conn.getresponse()
        out = json.loads(r.read() or b"{}")
        conn.close()
        return r.status, out

    def answer(self, participant, n, response="correct"):
        """(status, body) of answering trial ``n`` (its screen first, as the page does)."""
        st, screen = self.req("GET", f"/api/trial/{n}")
        if st != 200:
            return st, screen
        stim = screen.get("stimulus") or screen["trial"]["stimulus"]
        return self.req("POST", "/api/answer", {
            "participant": participant, "session": 1, "trial": n, "stimulus": stim,
            "response": response, "rt_ms": 500.0, "shown_ms": 1000.0, "late_frames": 0})


def _stored(study, participant):
    db = study / "sessions.sqlite"
    if not db.exists():
        return set()
    conn = sqlite3.connect(db)
    try:
        return {r[0] for r in conn.execute("SELECT trial FROM responses WHERE participant=?",
                                           (participant,))}
    finally:
        conn.close()


@pytest.fixture
def study(tmp_path):
    st = make_demo_study(tmp_path / "st", video_frames=6)
    shutil.copyfile(st / "design.toml", tmp_path / "design.toml")
    return st


def test_live_server_holds_its_study_and_never_acknowledges_a_lost_answer(study, tmp_path):
    server = Run(study, "R01")
    acked = set()
    try:
        url = server.start()
        page = Page(url)
        # the rebuild of the issue (the study has no answer yet), while the server serves:
        # refused, naming the server
        r = _cli("stimuli", tmp_path / "design.toml", "--out", study, "--force", "--quiet")
        assert r.returncode == 1, r.stdout + r.stderr
        assert f"pid {server.proc.pid}" in r.stderr and url in r.stderr and "R01" in r.stderr
        assert (study / "sessions.sqlite").exists() and (study / "render").is_dir()
        for n in (1, 2):
            st, body = page.answer("R01", n)
            assert st == 200 and body["status"] == "stored", body
            acked.add(n)
        # the other commands that would replace or move the study: refused the same way
        r = _cli("archive", study)
        assert r.returncode == 1 and f"pid {server.proc.pid}" in r.stderr, r.stderr
        assert study.is_dir()
        r = _cli("init", study / "design.toml", "--force", "--preset", "gravity")
        assert r.returncode == 1 and "R01" in r.stderr, r.stderr
        assert (study / "design.toml").read_bytes() == (tmp_path / "design.toml").read_bytes()
        r = _cli("reproduce", "--out", tmp_path, "--force", "--quiet")   # onto its parent folder
        assert r.returncode == 1 and f"pid {server.proc.pid}" in r.stderr, r.stderr
        r = _cli("render", study, "--force", "--size", "64x48", "--quiet")
        assert r.returncode == 1 and f"pid {server.proc.pid}" in r.stderr, r.stderr
        assert study.is_dir() and (study / "render" / "render.json").is_file()
        # the server goes on storing into the same study
        st, body = page.answer("R01", 3)
        assert st == 200 and body["status"] == "stored", body
        acked.add(3)
        # the folder replaced by hand (not a flipstudy command): the server stops acknowledging
        moved = tmp_path / "st-moved"
        os.rename(study, moved)
        shutil.copytree(moved, study)
        for n in (4, 5):
            st, body = page.answer("R01", n)
            assert st == 410, body
            assert "tell the experimenter" in body["error"] and "not" in body["error"].lower()
        st, body = page.req("GET", "/api/session")
        assert st == 410 and "changed" in body["error"]
        assert "no more answers are taken" in server.text()
    finally:
        server.stop()
    assert acked == {1, 2, 3}
    assert acked <= _stored(study, "R01")          # every acknowledged answer is in the study
    assert _stored(study, "R01") == {1, 2, 3}


def test_a_database_replaced_under_the_server_is_never_acknowledged_into(study, tmp_path):
    """The rebuild that removes ``sessions.sqlite`` (what `stimuli --force` did): the
    server's open connection would still commit into the deleted file; it must answer
    an error, not "stored"."""
    server = Run(study, "R02")
    try:
        page = Page(server.start())
        st, body = page.answer("R02", 1)
        assert st == 200 and body["status"] == "stored"
        for suffix in ("", "-wal", "-shm"):
            p = study / f"sessions.sqlite{suffix}"
            if p.exists():
                p.unlink()
        st, body = page.answer("R02", 2)
        assert st == 410 and "sessions.sqlite" in body["error"], body
    finally:
        server.stop()
    assert _stored(study, "R02") == set()          # the file is gone; nothing claims otherwise


def test_a_server_cannot_start_while_a_command_replaces_the_study(study):
    from flipstudy.study.lock import study_closed
    with study_closed(study, "stimuli --force"):
        run = Run(study, "R03")
        run.start(expect_url=False)
    assert run.proc.returncode == 1
    assert "stimuli --force" in run.text() and "replacing this study" in run.text()
    assert not (study / ".locks" / "open.lock").exists()     # the hold leaves no trace
    again = Run(study, "R03")                                # and, released, serves again
    try:
        page = Page(again.start())
        assert page.answer("R03", 1)[1]["status"] == "stored"
    finally:
        again.stop()
    assert _stored(study, "R03") == {1}
