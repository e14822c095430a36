"""The one progress bar of every long command (stimuli, render, reproduce …).

On a terminal it is a :mod:`tqdm` bar on stderr; elsewhere (a log, a pipe, CI, a
notebook) one line every :data:`EVERY_S` seconds, ``label: n/total (p %), 12 s, about
30 s left (last: what)``, and one summary line when the work is done, ``label:
n/total in 12.3 s``; with ``enabled=False`` nothing at all (the commands' ``--quiet``)."""
from __future__ import annotations

import sys
import time


#: seconds between two progress lines when the output is not a terminal
EVERY_S = 15.0


class Progress:
    """``step(what)`` after each of ``total`` pieces of work; ``close()`` (or the
    last step) ends the bar."""

    def __init__(self, total: int, label: str, enabled: bool = True, stream=None, unit: str = "it",
                 every: float | None = None):
        self.total, self.label, self.enabled, self.n = int(total), label, enabled, 0
        self.stream = stream or sys.stderr
        self.t0 = self._last = time.perf_counter()
        self.every = EVERY_S if every is None else float(every)
        self._bar = None
        self._closed = False
        if enabled and self.stream.isatty():
            from tqdm import tqdm         # only for a terminal (an import of 20 ms)
            self._bar = tqdm(total=self.total, desc=label, file=self.stream, unit=unit,
                             leave=True)

    def step(self, what: str = "") -> None:
        self.n += 1
        if self._bar is not None:
            if what:
                self._bar.set_postfix_str(str(what)[:40], refresh=False)
            self._bar.update(1)
        elif self.enabled and self.n < self.total:
            now = time.perf_counter()
            if now - self._last >= self.every:          # a log gets a line now and then
                self._last = now
                el = now - self.t0
                left = el * (self.total - self.n) / self.n
                tail = f" (last: {str(what)[:40]})" if what else ""
                self.stream.write(f"{self.label}: {self.n}/{self.total} ({100 * self.n / self.total:.0f} %), "
                                  f"{el:.0f} s, about {left:.0f} s left{tail}\n")
                self.stream.flush()
        if self.n >= self.total:
            self.close()

    def close(self) -> None:
        if self._closed or not self.enabled:
            self._closed = True
            return
        self._closed = True
        if self._bar is not None:
            self._bar.close()
        else:
            self.stream.write(f"{self.label}: {self.n}/{self.total} in {time.perf_counter() - self.t0:.1f} s\n")
            self.stream.flush()


class Heartbeat:
    """A line every ``every`` seconds while a long step without countable pieces runs
    (``analyze``'s fits, ``plan``'s simulations), when ``stream`` is not a terminal:
    ``label: still working, 45 s``.  A context manager; nothing on a terminal (the
    command's own output shows there) or with ``enabled=False``."""

    def __init__(self, label: str, enabled: bool = True, stream=None, every: float | None = None):
        import threading
        self.label, self.stream = label, stream or sys.stderr
        self.every = EVERY_S if every is None else float(every)
        self.enabled = enabled and not self.stream.isatty()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        t0 = time.perf_counter()
        while not self._stop.wait(self.every):
            self.stream.write(f"{self.label}: still working, {time.perf_counter() - t0:.0f} s\n")
            self.stream.flush()

    def __enter__(self):
        if self.enabled:
            self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
