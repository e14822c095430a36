"""One server per participant: an exclusive lock per (study folder, participant).

``flipstudy run`` holds ``STUDY_DIR/.locks/run-<participant>.lock`` locked with
``fcntl.flock`` while it serves; the file says who holds it (pid, host name,
URL, since when).  A second ``run`` for the same participant is refused at once
with that information.  The kernel releases a ``flock`` when its holder dies,
even by SIGKILL, so a lock left by a dead server is simply taken over.

Examples
--------
>>> import tempfile
>>> study = tempfile.TemporaryDirectory()                  # stands for a study folder
>>> lock = ParticipantLock(study.name, "P01").acquire()
>>> lock.update(url="http://127.0.0.1:41233/")
>>> lock.info["participant"], lock.info["url"]
('P01', 'http://127.0.0.1:41233/')
>>> ParticipantLock(study.name, "P01").acquire()           # a second server for P01
Traceback (most recent call last):
    ...
flipstudy.errors.ParticipantBusy: participant P01 of ... is already being served by another `flipstudy run` (pid ...
>>> lock.release()
>>> ParticipantLock(study.name, "P01").acquire().release()  # free again
>>> study.cleanup()
"""
from __future__ import annotations

import fcntl
import json
import os
import socket
from pathlib import Path

from flipstudy.errors import ParticipantBusy, StudyInUse

LOCK_DIR = ".locks"


def _utc_now() -> str:
    from datetime import datetime, timezone
    return datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")


class ParticipantLock:
    """The lock of one participant of one study folder (see the module docstring)."""

    def __init__(self, study_dir, participant: str):
        self.study_dir = Path(study_dir)
        self.participant = participant
        self.path = self.study_dir / LOCK_DIR / f"run-{participant}.lock"
        self.fd: int | None = None
        self.info: dict = {}
        self.previous: dict | None = None     # what a dead holder had written (taken over)

    def _read(self, fd) -> dict:
        try:
            os.lseek(fd, 0, os.SEEK_SET)
            data = os.read(fd, 65536)
            return json.loads(data.decode()) if data.strip() else {}
        except (OSError, ValueError):
            return {}

    def acquire(self, **info) -> "ParticipantLock":
        """Take the lock or raise :class:`ParticipantBusy` naming its holder."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                held = self._read(fd)
                os.close(fd)
                who = ", ".join(f"{k} {held[k]}" for k in ("pid", "host", "url") if held.get(k))
                raise ParticipantBusy(
                    f"participant {self.participant} of {self.study_dir} is already being served "
                    f"by another `flipstudy run` ({who or 'holder unknown'}"
                    f"{', since ' + held['since'] if held.get('since') else ''}; lock file "
                    f"{self.path}); two pages for one participant would mix their answers: use "
                    f"that one, or stop it first (Ctrl-C in its terminal)") from None
            try:                 # the file may have been unlinked by a holder that just released
                same = os.fstat(fd).st_ino == os.stat(self.path).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        old = self._read(fd)
        self.previous = old or None
        self.fd = fd
        self.info = {"participant": self.participant, "pid": os.getpid(),
                     "host": socket.gethostname(), "since": _utc_now(), **info}
        self._write()
        return self

    def _write(self) -> None:
        data = (json.dumps(self.info) + "\n").encode()
        os.ftruncate(self.fd, 0)
        os.pwrite(self.fd, data, 0)
        os.fsync(self.fd)

    def update(self, **info) -> None:
        """Add to what the lock file says (e.g. the URL once the port is known)."""
        self.info.update(info)
        self._write()

    def release(self) -> None:
        if self.fd is None:
            return
        try:
            os.unlink(self.path)          # while still locked: no one holds the old inode
        except FileNotFoundError:
            pass
        os.close(self.fd)
        self.fd = None

    def __enter__(self):
        return self if self.fd is not None else self.acquire()

    def __exit__(self, *exc):
        self.release()


# --- a serving study is held open -------------------------------------------------------------
#
# Every ``flipstudy run`` holds ``STUDY_DIR/.locks/open.lock`` with a *shared* ``flock`` for as
# long as it serves; a command that would replace, move or rebuild the study (``stimuli
# --force``, ``archive``, ``init --force`` into it, ``reproduce --force`` onto it) takes the
# same file *exclusively* (:func:`study_closed`) for as long as it works, so it is refused at
# once while any server has the study open (the message names each server: pid, URL,
# participant, from its ``run-<participant>.lock``), and a server cannot start while such a
# command works.  The kernel drops a dead holder's lock (even after SIGKILL).

OPEN_LOCK = "open.lock"


def _open_lock_path(study_dir) -> Path:
    return Path(study_dir) / LOCK_DIR / OPEN_LOCK


def live_servers(study_dir) -> list[dict]:
    """What each live ``flipstudy run`` server of ``study_dir`` says about itself
    (``participant``, ``pid``, ``url``, ...): the ``run-*.lock`` files whose process
    is alive.  Only read (no lock is taken, so a server starting now is not disturbed);
    used to name the servers once :class:`study_closed` found the study held."""
    out = []
    for p in sorted((Path(study_dir) / LOCK_DIR).glob("run-*.lock")):
        try:
            info = json.loads(p.read_text() or "{}")
        except (OSError, ValueError):
            continue
        if not isinstance(info, dict):
            continue
        pid = info.get("pid")
        if isinstance(pid, int) and pid > 0 and info.get("host") in (None, socket.gethostname()):
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                continue                     # a dead server's file (SIGKILL leaves it)
            except PermissionError:
                pass
        out.append(info or {"participant": p.stem[4:]})
    return out


def describe_servers(servers: list[dict]) -> str:
    """``"pid 123 at http://127.0.0.1:4000/ serving participant R01"``, joined by ``; ``."""
    return "; ".join(
        " ".join(x for x in (f"pid {s['pid']}" if s.get("pid") else "",
                             f"at {s['url']}" if s.get("url") else "",
                             f"serving participant {s['participant']}" if s.get("participant") else "")
                 if x) or "a server" for s in servers) or "a `flipstudy run` server"


class StudyOpen:
    """The shared hold of one serving ``flipstudy run`` on its study (module text above)."""

    def __init__(self, study_dir):
        self.study_dir = Path(study_dir)
        self.fd: int | None = None

    def acquire(self) -> "StudyOpen":
        path = _open_lock_path(self.study_dir)
        while True:
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
                fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
            except FileNotFoundError:         # removed by a command that just finished: again
                continue
            try:
                fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
            except BlockingIOError:
                data = os.pread(fd, 4096, 0).decode(errors="replace").strip()
                os.close(fd)
                raise StudyInUse(f"{self.study_dir}: {data or 'another command'} is replacing this "
                                 f"study right now (lock {path}); start the session when it has "
                                 f"finished") from None
            try:                              # the file a command removed on release: lock anew
                same = os.fstat(fd).st_ino == os.stat(path).st_ino
            except FileNotFoundError:
                same = False
            if same:
                self.fd = fd
                return self
            os.close(fd)

    def release(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


class study_closed:
    """``with study_closed(STUDY_DIR, "stimuli --force"):`` hold the study closed to
    servers while a command replaces, moves or rebuilds it; raises :class:`StudyInUse`
    naming the servers that have it open.  A path that is not an existing folder
    holds nothing (nothing can be serving it).

    >>> import tempfile
    >>> tmp = tempfile.TemporaryDirectory()
    >>> server = StudyOpen(tmp.name).acquire()
    >>> with study_closed(tmp.name, "archive"):
    ...     pass
    Traceback (most recent call last):
        ...
    flipstudy.errors.StudyInUse: ... is open in a `flipstudy run` server ...
    >>> server.release()
    >>> with study_closed(tmp.name, "archive"):
    ...     StudyOpen(tmp.name).acquire()
    Traceback (most recent call last):
        ...
    flipstudy.errors.StudyInUse: ...: flipstudy archive (pid ...) is replacing this study right now ...
    >>> tmp.cleanup()
    """

    def __init__(self, study_dir, what: str):
        self.study_dir, self.what = Path(study_dir), what
        self.fd: int | None = None

    def __enter__(self):
        d = self.study_dir
        if d.is_symlink() or not d.is_dir():
            return self
        path = _open_lock_path(d)
        try:
            self.made_dir = not path.parent.is_dir()
            path.parent.mkdir(exist_ok=True)
            self.made_file = not path.exists()
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
            self.dir_fd = os.open(path.parent, os.O_RDONLY | os.O_DIRECTORY)
            self.study_fd = os.open(d, os.O_RDONLY | os.O_DIRECTORY)
        except OSError:                      # a read-only study: nothing of ours can serve it
            return self
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            self._close_dirs()
            raise StudyInUse(
                f"{d} is open in a `flipstudy run` server ({describe_servers(live_servers(d))}); "
                f"`flipstudy {self.what}` would take the study away under the participant's "
                f"answers. Stop the server first (Ctrl-C in its terminal), then run this again"
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"flipstudy {self.what} (pid {os.getpid()})".encode(), 0)
        self.fd = fd
        return self

    def _close_dirs(self):
        for name in ("dir_fd", "study_fd"):
            fd = getattr(self, name, None)
            if fd is not None:
                os.close(fd)
                setattr(self, name, None)

    def __exit__(self, *exc):
        """Release; what this hold made (the lock file, ``.locks/``) is removed again,
        through the folder's descriptors, so a study moved meanwhile (``archive``)
        keeps no trace either.  A server that opened the removed file sees that it
        is no longer the one at the path and locks the new one (:class:`StudyOpen`)."""
        if self.fd is None:
            return
        try:
            os.ftruncate(self.fd, 0)
            if self.made_file:               # unlinked while still locked: no one holds the old inode
                os.unlink(OPEN_LOCK, dir_fd=self.dir_fd)
            if self.made_dir:
                os.rmdir(LOCK_DIR, dir_fd=self.study_fd)
        except OSError:                      # e.g. a server made its lock there meanwhile
            pass
        os.close(self.fd)
        self.fd = None
        self._close_dirs()
