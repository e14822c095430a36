"""``flipstudy run STUDY --participant ID --no-browser ...`` as a subprocess, for
the tests that start real servers (bounded waits)."""
import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


class Run:
    """``flipstudy run STUDY --participant ID --no-browser *extra`` as a subprocess;
    :meth:`start` returns the participant page's URL once the server prints it."""

    def __init__(self, study_dir, participant, *extra):
        self.args = [sys.executable, "-m", "flipstudy.study.cli", "run", str(study_dir), "--participant",
                     participant, "--no-browser", *extra]
        self.proc = None
        self.lines: queue.Queue = queue.Queue()
        self.out: list[str] = []

    def start(self, expect_url=True, timeout=40):
        env = dict(os.environ, PYTHONUNBUFFERED="1", PYTHONPATH=str(ROOT))
        self.proc = subprocess.Popen(self.args, cwd=ROOT, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True, env=env)
        threading.Thread(target=self._pump, args=(self.proc,), daemon=True).start()
        if not expect_url:
            self.proc.wait(timeout=timeout)
            time.sleep(0.1)
            return None
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                line = self.lines.get(timeout=0.5)
            except queue.Empty:
                assert self.proc.poll() is None, f"server exited: {''.join(self.out)}"
                continue
            if line.startswith("participant page: "):
                return line.split(": ", 1)[1].strip()
        raise AssertionError(f"the server did not print its URL: {''.join(self.out)}")

    def _pump(self, proc):
        for line in proc.stdout:
            self.out.append(line)
            self.lines.put(line)

    def text(self) -> str:
        return "".join(self.out)

    def kill9(self):
        os.kill(self.proc.pid, signal.SIGKILL)
        assert self.proc.wait(timeout=10) == -signal.SIGKILL

    def stop(self):
        if self.proc and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
