"""One server per participant: an exclusive lock per (study folder, participant).

``flipstudy run`` holds ``STUDY_DIR/.locks/run-<participant>.lock`` locked with
``fcntl.flock`` while it serves; the file says who holds it (pid, host name,
URL, since when).  A second ``run`` for the same participant is refused at once
with that information.  The kernel releases a ``flock`` when its holder dies,
even by SIGKILL, so a lock left by a dead server is simply taken over.

Example
-------
>>> import tempfile
>>> study = tempfile.TemporaryDirectory()                  # stands for a study folder
>>> lock = ParticipantLock(study.name, "P01").acquire()
>>> lock.update(url="http://127.0.0.1:41233/")
>>> lock.info["participant"], lock.info["url"]
('P01', 'http://127.0.0.1:41233/')
>>> ParticipantLock(study.name, "P01").acquire()           # a second server for P01
Traceback (most recent call last):
    ...
flipstudy.study.lock.ParticipantBusy: participant P01 of ... is already being served by another `flipstudy run` (pid ...
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

from flipstudy.errors import ParticipantBusy

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
