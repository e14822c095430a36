"""The one progress bar of every long command (stimuli, render, reproduce …).

On a terminal it is a :mod:`tqdm` bar on stderr; elsewhere (a log, a pipe, CI)
one summary line when the work is done, ``label: n/total in 12.3 s``; with
``enabled=False`` nothing at all (the commands' ``--quiet``)."""
from __future__ import annotations

import sys
import time

from tqdm import tqdm


class Progress:
    """``step(what)`` after each of ``total`` pieces of work; ``close()`` (or the
    last step) ends the bar."""

    def __init__(self, total: int, label: str, enabled: bool = True, stream=None, unit: str = "it"):
        self.total, self.label, self.enabled, self.n = int(total), label, enabled, 0
        self.stream = stream or sys.stderr
        self.t0 = time.perf_counter()
        self._bar = None
        self._closed = False
        if enabled and self.stream.isatty():
            self._bar = tqdm(total=self.total, desc=label, file=self.stream, unit=unit,
                             leave=True)

    def step(self, what: str = "") -> None:
        self.n += 1
        if self._bar is not None:
            if what:
                self._bar.set_postfix_str(str(what)[:40], refresh=False)
            self._bar.update(1)
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
