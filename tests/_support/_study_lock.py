"""Issue 45's writer-lock tests: the study lock held by another process, and two
``flipstudy`` commands started at once."""
import os
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path

_HOLD = ("import sys\n"
         "from flipstudy.study.lock import StudyLock\n"
         "lock = StudyLock(sys.argv[1], sys.argv[2]).acquire()\n"
         "print('held', flush=True)\n"
         "sys.stdin.read()\n"
         "lock.release()\n")


@contextmanager
def held_elsewhere(study_dir, command: str = "simulate"):
    """Another process holds ``study_dir``'s study lock as ``flipstudy command`` until
    the block ends; yields its pid."""
    p = subprocess.Popen([sys.executable, "-c", _HOLD, str(study_dir), command],
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = p.stdout.readline().strip()
        assert line == "held", p.stderr.read()
        yield p.pid
    finally:
        p.stdin.close()
        p.wait(timeout=60)


def flipstudy_bin() -> str:
    """The ``flipstudy`` console script beside this interpreter."""
    return str(Path(sys.executable).with_name("flipstudy"))


def run_together(*argvs, env=None, timeout: float = 300):
    """Start every ``flipstudy ARGV`` at once (processes); their
    ``subprocess.CompletedProcess``-like (returncode, stdout, stderr) triples."""
    env = {**os.environ, **(env or {})}
    procs = [subprocess.Popen([flipstudy_bin(), *map(str, a)], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, env=env) for a in argvs]
    out = []
    for p in procs:
        so, se = p.communicate(timeout=timeout)
        out.append((p.returncode, so, se))
    return out
