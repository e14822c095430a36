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
flipstudy.errors.ParticipantBusyError: participant P01 of ... is already being served by another `flipstudy run` (pid ...
>>> lock.release()
>>> ParticipantLock(study.name, "P01").acquire().release()  # free again
>>> study.cleanup()
"""
from __future__ import annotations

import fcntl
import json
import os
import socket
import threading
from pathlib import Path

from flipstudy.errors import ParticipantBusyError, StudyInUseError

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
        """Take the lock or raise :class:`ParticipantBusyError` naming its holder."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                held = self._read(fd)
                os.close(fd)
                who = ", ".join(f"{k} {held[k]}" for k in ("pid", "host", "url") if held.get(k))
                raise ParticipantBusyError(
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
                raise StudyInUseError(f"{self.study_dir}: {data or 'another command'} is replacing this "
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
    servers while a command replaces, moves or rebuilds it; raises :class:`StudyInUseError`
    naming the servers that have it open.  A path that is not an existing folder
    holds nothing (nothing can be serving it).

    >>> import tempfile
    >>> tmp = tempfile.TemporaryDirectory()
    >>> server = StudyOpen(tmp.name).acquire()
    >>> with study_closed(tmp.name, "archive"):
    ...     pass
    Traceback (most recent call last):
        ...
    flipstudy.errors.StudyInUseError: ... is open in a `flipstudy run` server ...
    >>> server.release()
    >>> with study_closed(tmp.name, "archive"):
    ...     StudyOpen(tmp.name).acquire()
    Traceback (most recent call last):
        ...
    flipstudy.errors.StudyInUseError: ...: flipstudy archive (pid ...) is replacing this study right now ...
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
            raise StudyInUseError(
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


# --- one writer at a time ---------------------------------------------------------------------
#
# Every command that writes into a study (``import-web``, ``simulate``, ``run``'s session
# creation, ``stimuli``, ``render``, ``export``, ``export-web``'s site record, ``archive``) holds
# ``STUDY_DIR/.locks/study.lock`` exclusively (``fcntl.flock``) while it reads what it will
# rewrite and writes it back, so two of them never interleave (two ``import-web`` runs each
# rewriting ``web/responses.csv`` from what it read would drop the other's participant).  A
# second writer waits for the first up to ``FLIPSTUDY_LOCK_WAIT`` seconds (default 60; 0:
# refuse at once), then fails in one line naming the holder.  The hold is re-entrant within
# one thread (``simulate`` opens sessions through ``run``'s path); the file is removed on
# release (and ``.locks/`` when this hold made it), so a study keeps no trace of it.

STUDY_LOCK = "study.lock"
#: the environment variable with the seconds a writer waits for another (default
#: :data:`DEFAULT_LOCK_WAIT`; 0: refuse at once)
LOCK_WAIT_ENV = "FLIPSTUDY_LOCK_WAIT"
DEFAULT_LOCK_WAIT = 60.0
_POLL = 0.02
_held = threading.local()                 # per thread: resolved study path -> [depth]


def lock_wait() -> float:
    """The seconds a writer waits for the study lock (``FLIPSTUDY_LOCK_WAIT``).

    >>> import os
    >>> os.environ["FLIPSTUDY_LOCK_WAIT"] = "2.5"; lock_wait()
    2.5
    >>> os.environ["FLIPSTUDY_LOCK_WAIT"] = "soon"; lock_wait()
    Traceback (most recent call last):
        ...
    flipstudy.errors.FlipstudyValueError: FLIPSTUDY_LOCK_WAIT='soon': expected the seconds a command waits for another writing the same study (a number >= 0; 0: refuse at once)
    >>> del os.environ["FLIPSTUDY_LOCK_WAIT"]; lock_wait()
    60.0
    """
    import math

    from flipstudy.errors import FlipstudyValueError
    text = os.environ.get(LOCK_WAIT_ENV, "").strip()
    if not text:
        return DEFAULT_LOCK_WAIT
    try:
        v = float(text)
    except ValueError:
        v = -1.0
    if not (math.isfinite(v) and v >= 0):
        raise FlipstudyValueError(
            f"{LOCK_WAIT_ENV}={text!r}: expected the seconds a command waits for another writing "
            f"the same study (a number >= 0; 0: refuse at once)")
    return v


class StudyLock:
    """``with StudyLock(STUDY_DIR, "import-web"):`` the one writer of a study (module text
    above).  Waits up to :func:`lock_wait` seconds for another holder, then raises
    :class:`~flipstudy.errors.StudyInUseError` naming it (command, pid, since).  A path that
    is not an existing folder, or one that cannot be written, holds nothing (the
    command then fails, or reads, on its own).

    >>> import tempfile, os
    >>> tmp = tempfile.TemporaryDirectory()
    >>> with StudyLock(tmp.name, "simulate"):
    ...     with StudyLock(tmp.name, "run"):             # re-entrant in one thread
    ...         os.environ["FLIPSTUDY_LOCK_WAIT"] = "0"
    ...         import threading; out = []
    ...         t = threading.Thread(target=lambda: out.append(StudyLock.probe(tmp.name, "export")))
    ...         t.start(); t.join(); del os.environ["FLIPSTUDY_LOCK_WAIT"]
    >>> print(out[0].split(": ", 1)[1])
    `flipstudy simulate` (pid ..., since ...) is writing this study; `flipstudy export` waited 0 s for it (FLIPSTUDY_LOCK_WAIT): run it again once that has finished (lock ...)
    >>> os.listdir(tmp.name)                               # no trace left
    []
    >>> tmp.cleanup()
    """

    def __init__(self, study_dir, command: str):
        self.study_dir, self.command = Path(study_dir), command
        self.fd = self.dir_fd = self.study_fd = None
        self.reentered = False
        self.made_dir = False

    @staticmethod
    def probe(study_dir, command: str) -> str | None:
        """Take and release the lock at once; the refusal's message, or None when it was free."""
        try:
            with StudyLock(study_dir, command):
                return None
        except StudyInUseError as e:
            return str(e)

    def _key(self) -> str:
        return os.path.realpath(self.study_dir)

    def acquire(self) -> "StudyLock":
        held = _held.__dict__.setdefault("depth", {})
        key = self.key = self._key()          # kept: the folder may be moved while held (archive)
        if held.get(key):
            held[key] += 1
            self.reentered = True
            return self
        wait = lock_wait()
        import time
        end = time.monotonic() + wait
        while True:
            got = self._try_once()
            if got is None:                  # nothing to hold: no folder, or read-only
                return self
            if got == "again":               # the file its last holder removed: lock anew
                continue
            if got:
                break
            if time.monotonic() >= end:
                raise self._refusal(wait)
            time.sleep(_POLL)
        held[key] = 1
        info = {"command": self.command, "pid": os.getpid(), "host": socket.gethostname(),
                "since": _utc_now()}
        os.ftruncate(self.fd, 0)
        os.pwrite(self.fd, (json.dumps(info) + "\n").encode(), 0)
        return self

    def _try_once(self):
        """One attempt: True (held), False (another holds it), ``"again"`` (the file or
        ``.locks/`` was removed meanwhile), None (nothing to hold)."""
        d = self.study_dir
        self._close()
        try:
            self.study_fd = os.open(d, os.O_RDONLY | os.O_DIRECTORY)
        except OSError:
            return None
        try:
            try:
                os.mkdir(LOCK_DIR, dir_fd=self.study_fd)
                self.made_dir = True
            except FileExistsError:
                self.made_dir = False
            self.dir_fd = os.open(LOCK_DIR, os.O_RDONLY | os.O_DIRECTORY, dir_fd=self.study_fd)
            self.fd = os.open(STUDY_LOCK, os.O_RDWR | os.O_CREAT, 0o644, dir_fd=self.dir_fd)
        except FileNotFoundError:            # .locks/ removed by a holder that just released
            self._close()
            return "again" if self.study_dir.is_dir() else None
        except OSError:                      # a read-only study: no writer of ours can write it
            self._close()
            return None
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self.holder = self._read()
            self._close()
            return False
        def ident(st):
            return st.st_dev, st.st_ino
        try:                                 # still the file at STUDY/.locks/study.lock?
            same = (ident(os.fstat(self.fd)) == ident(os.stat(STUDY_LOCK, dir_fd=self.dir_fd))
                    and ident(os.fstat(self.dir_fd)) == ident(os.stat(LOCK_DIR, dir_fd=self.study_fd))
                    and ident(os.fstat(self.study_fd)) == ident(os.stat(d)))
        except OSError:
            same = False
        if not same:
            self._close()
            return "again" if self.study_dir.is_dir() else None
        return True

    def _read(self) -> dict:
        try:
            got = json.loads(os.pread(self.fd, 4096, 0).decode() or "{}")
            return got if isinstance(got, dict) else {}
        except (OSError, ValueError):
            return {}

    def _refusal(self, wait: float) -> StudyInUseError:
        h = getattr(self, "holder", {}) or {}
        who = (f"`flipstudy {h['command']}`" if h.get("command") else "another command") + " (" + \
            ", ".join(x for x in (f"pid {h['pid']}" if h.get("pid") else "",
                                  f"since {h['since']}" if h.get("since") else "") if x) + ")"
        return StudyInUseError(
            f"{self.study_dir}: {who.replace(' ()', '')} is writing this study; `flipstudy "
            f"{self.command}` waited {wait:g} s for it ({LOCK_WAIT_ENV}): run it again once that "
            f"has finished (lock {self.study_dir / LOCK_DIR / STUDY_LOCK})")

    def _close(self) -> None:
        for name in ("fd", "dir_fd", "study_fd"):
            fd = getattr(self, name)
            if fd is not None:
                os.close(fd)
                setattr(self, name, None)

    def release(self) -> None:
        held = _held.__dict__.setdefault("depth", {})
        key = getattr(self, "key", None)
        if self.reentered:
            held[key] -= 1
            self.reentered = False
            return
        if self.fd is None:
            return
        held.pop(key, None)
        try:                                 # unlinked while still locked: no one holds the old inode
            os.unlink(STUDY_LOCK, dir_fd=self.dir_fd)
            if self.made_dir:
                os.rmdir(LOCK_DIR, dir_fd=self.study_fd)
        except OSError:                      # e.g. a server made its lock there meanwhile
            pass
        self._close()

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()


def study_writer(command: str, arg: str = "study_dir"):
    """Decorate a function that writes into the study named by its argument ``arg`` (a
    path, a :class:`~flipstudy.study.session.Study` or a
    :class:`~flipstudy.stimuli.contract.StimulusSet`) so that it runs holding that
    study's :class:`StudyLock` for ``flipstudy command``."""
    import functools
    import inspect

    def deco(fn):
        sig = inspect.signature(fn)

        @functools.wraps(fn)
        def wrapper(*args, **kwargs):
            where = sig.bind_partial(*args, **kwargs).arguments.get(arg)
            where = getattr(where, "dir", None) or getattr(where, "folder", None) or where
            if where is None:
                return fn(*args, **kwargs)
            with StudyLock(where, command):
                return fn(*args, **kwargs)
        return wrapper
    return deco
