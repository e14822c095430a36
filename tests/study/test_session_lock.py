"""One server per participant, no IntegrityError escaping, a Host check on every
address, and `run` serving only videos made from the current stimuli with one
set of settings.

Servers run as real `flipstudy run` subprocesses (bounded waits)."""
import http.client
import json
import os
import signal
import socket
import sqlite3
import threading

import pytest

from _run_server import Run
from flipstudy.study import store
from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.server import allowed_host_names
from flipstudy.errors import SessionError
from flipstudy.study.session import load_study, open_session


@pytest.fixture
def demo(tmp_path):
    return make_demo_study(tmp_path / "study", video_frames=6)


def get(port, path, host_header):
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    conn.request("GET", path, headers={"Host": host_header})
    r = conn.getresponse()
    body = r.read()
    conn.close()
    return r.status, body


def test_second_server_for_a_participant_is_refused_and_a_dead_ones_lock_taken_over(demo):
    first = Run(demo, "P01")
    try:
        url = first.start()
        port = int(url.rsplit(":", 1)[1].strip("/"))
        second = Run(demo, "P01")
        second.start(expect_url=False)
        assert second.proc.returncode == 1
        msg = second.text()
        assert "already being served" in msg and f"pid {first.proc.pid}" in msg and url in msg
        assert "since 20" in msg
        # the first one still serves, and is the only session of P01
        assert get(port, "/api/session", f"127.0.0.1:{port}")[0] == 200
        # another participant is not blocked; the same one is, in this process too
        from flipstudy.errors import ParticipantBusyError
        from flipstudy.study.lock import ParticipantLock
        with ParticipantLock(demo, "P02"):
            assert json.loads((demo / ".locks" / "run-P02.lock").read_text())["pid"] == os.getpid()
        with pytest.raises(ParticipantBusyError, match=f"pid {first.proc.pid}"):
            ParticipantLock(demo, "P01").acquire()
        # SIGKILL leaves the lock file behind, but the kernel released the lock
        os.kill(first.proc.pid, signal.SIGKILL)
        first.proc.wait(timeout=10)
        assert (demo / ".locks" / "run-P01.lock").exists()
        third = Run(demo, "P01")
        try:
            third.start()
            assert f"took over the lock of a server that is gone (pid {first.proc.pid}" in third.text()
        finally:
            third.stop()
        assert third.proc.returncode == 0 and not (demo / ".locks" / "run-P01.lock").exists()
    finally:
        first.stop()
    conn = sqlite3.connect(demo / "sessions.sqlite")
    assert conn.execute("SELECT participant, session FROM sessions ORDER BY participant").fetchall() \
        == [("P01", 1)]
    conn.close()


def test_non_loopback_host_keeps_the_host_check(demo):
    names = allowed_host_names("0.0.0.0", ["study.lab"])
    assert {"study.lab", "127.0.0.1", "localhost", socket.gethostname().lower()} <= names
    assert "0.0.0.0" not in names and "evil.example" not in names
    srv = Run(demo, "P01", "--host", "0.0.0.0", "--allowed-host", "Study.Lab")
    try:
        url = srv.start()
        port = int(url.rsplit(":", 1)[1].strip("/"))
        assert "reachable from the network" in srv.text() and "study.lab" in srv.text()
        st, body = get(port, "/api/session", f"evil.example:{port}")     # DNS rebinding
        assert st == 400 and "not served here" in json.loads(body)["error"]
        assert get(port, "/api/session", f"study.lab:{port}")[0] == 200
        assert get(port, "/api/session", f"{socket.gethostname()}:{port}")[0] == 200
        assert get(port, "/api/session", f"127.0.0.1:{port}")[0] == 200
    finally:
        srv.stop()


def test_two_openers_of_a_new_participant_get_one_session(demo):
    """Threads racing to create P0k's first session: no IntegrityError, one
    session, the same stored trial order for all."""
    study = load_study(demo)
    for k in range(6):
        pid, results, errors = f"P{k:02d}", [], []
        barrier = threading.Barrier(4)

        def opener():
            try:
                barrier.wait()
                results.append(open_session(study, pid))
            except BaseException as e:           # noqa: BLE001 — recorded and asserted below
                errors.append(e)
        ts = [threading.Thread(target=opener) for _ in range(4)]
        for t in ts:
            t.start()
        for t in ts:
            t.join(60)
        assert not errors, errors
        assert {s.session for s in results} == {1}
        assert len({tuple(t.stimulus for t in s.trials) for s in results}) == 1
    conn = store.connect(demo)
    assert conn.execute("SELECT COUNT(*) FROM sessions").fetchone()[0] == 6
    conn.close()


def test_session_created_between_read_and_write_is_resumed(demo, monkeypatch):
    study = load_study(demo)
    first = open_session(study, "P01")
    with pytest.raises(store.ConflictError, match="created by another process"):
        conn = store.connect(demo)
        try:
            store.create_session(conn, "P01", 1, "browser", 1, study.manifest_sha256, first.trials)
        finally:
            conn.close()
    real = store.latest_session
    calls = []

    def stale(conn, participant):                # the read happened before the other's write
        calls.append(participant)
        return None if len(calls) == 1 else real(conn, participant)
    monkeypatch.setattr(store, "latest_session", stale)
    again = open_session(study, "P01")
    assert again.resumed and again.session == 1 and len(calls) == 2
    assert [t.stimulus for t in again.trials] == [t.stimulus for t in first.trials]


def test_run_refuses_stale_mixed_or_unrecorded_videos(demo, capsys):
    render = demo / "render"
    names = sorted(p.name for p in render.glob("*.mp4"))
    rec = json.loads((render / "render.json").read_text())
    # a video replaced by another (e.g. a half-finished re-render)
    keep = (render / names[0]).read_bytes()
    (render / names[0]).write_bytes((render / names[1]).read_bytes())
    assert cli(["run", str(demo), "--participant", "P01", "--no-browser"]) == 1
    err = capsys.readouterr().err
    assert names[0] in err and "differs" in err and f"flipstudy render {demo}" in err
    (render / names[0]).write_bytes(keep)
    # two videos made with other settings (another --size)
    mixed = json.loads(json.dumps(rec))
    mixed["settings_records"]["other"] = {"size": [320, 240], "fps": 60.0}
    for n in names[:2]:
        mixed["outputs"][n]["settings"] = "other"
    (render / "render.json").write_text(json.dumps(mixed))
    assert cli(["run", str(demo), "--participant", "P01", "--no-browser"]) == 1
    err = capsys.readouterr().err
    assert f"{names[0]}, {names[1]}: 2 made with 320x240 at 60 fps" in err
    assert f"the other {len(names) - 2} with 64x48 at 30 fps" in err
    # a video made from another version of its stimulus
    stale = json.loads(json.dumps(rec))
    stale["outputs"][names[2]]["stimulus_sha256"] = "1" * 64
    (render / "render.json").write_text(json.dumps(stale))
    assert cli(["run", str(demo), "--participant", "P01", "--no-browser"]) == 1
    assert f"{names[2]}: made from another version" in capsys.readouterr().err
    # nothing records what the videos were made from
    (render / "render.json").unlink()
    assert cli(["run", str(demo), "--participant", "P01", "--no-browser"]) == 1
    assert "no render.json" in capsys.readouterr().err
    assert not (demo / "sessions.sqlite").exists() or \
        sqlite3.connect(demo / "sessions.sqlite").execute("SELECT COUNT(*) FROM sessions").fetchone()[0] == 0
    with pytest.raises(SessionError):            # the library path refuses too
        from flipstudy.study.server import serve
        serve(demo, "P01", open_browser=False)
