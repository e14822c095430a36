"""The one result type of the editing methods and the jump controller.

Every method that makes a clip returns a :class:`Result` (or a subclass that
adds what only that method knows): the clip, the frames of its flight, and the
method's typed report (a :class:`~flipstudy.stimuli.edit.report.Report`
dataclass whose :meth:`to_dict` gives the JSON keys the CLI prints).
``Clip.meta`` holds provenance only; what a method measured is in ``report``.

>>> from flipstudy.stimuli import builtin
>>> from flipstudy.stimuli.result import Result
>>> from flipstudy.stimuli.edit.report import Report
>>> r = Result(builtin("backflip"), 157, 237, Report())
>>> r.flight_frames
81
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Generic, TypeVar

from .motion.clip import Clip

R = TypeVar("R")


@dataclass
class Result(Generic[R]):
    """A made clip, its flight (first and last frame strictly inside the
    airborne span, ``None`` where the method makes no single flight) and the
    method's typed report."""

    clip: Clip
    takeoff: int | None
    landing: int | None
    report: R

    @property
    def flight_frames(self) -> int | None:
        """The number of frames strictly inside the flight."""
        if self.takeoff is None or self.landing is None:
            return None
        return self.landing - self.takeoff + 1


__all__ = ["Result"]
