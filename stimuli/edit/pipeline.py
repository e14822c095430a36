"""The edit pipeline of ``flipstudy edit``: a join in flight, or straightening
with momentum repair (Majkowska & Faloutsos 2007, Section 5.5) followed by more
flips (5.2-5.4), re-analysed between the steps.

>>> from flipstudy.stimuli import builtin
>>> from flipstudy.stimuli.edit.pipeline import edit
>>> r = edit(builtin("backflip"), flips=2)
>>> r.clip.num_frames > r.analysis.clip.num_frames    # a longer flight
True
>>> round(r.report.measured.turn_deg / 360), (r.takeoff, r.landing) == (r.steps.multiflip.takeoff,
...                                                                     r.steps.multiflip.landing)
(2, True)
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..analyse import Analysis, analyse
from ..motion.clip import Clip
from ..result import Result
from .animator import Repair, RepairReport, repair_momentum, straighten as straighten_group
from flipstudy.errors import FlipEditError
from .flight_measures import FlipMeasure, measure
from .multiflip import MultiFlip, MultiFlipReport, multiflip
from .report import Report

if TYPE_CHECKING:
    from .join import Join, JoinReport


@dataclass
class EditSteps:
    """What each step of :func:`edit` made (``None``: not run)."""
    #: :func:`~flipstudy.stimuli.edit.join.join_in_flight`'s result
    join: Join | None = None
    #: the straightening's :func:`~flipstudy.stimuli.edit.animator.repair_momentum`
    repair: Repair | None = None
    #: :func:`~flipstudy.stimuli.edit.multiflip.multiflip`'s result
    multiflip: MultiFlip | None = None


@dataclass
class EditReport(Report):
    """What each step of :func:`edit` did and measured (``None``: not run)."""
    join: JoinReport | None = None
    repair: RepairReport | None = None
    multiflip: MultiFlipReport | None = None
    #: :func:`~flipstudy.stimuli.edit.flight_measures.measure` of the multi-flip against its base
    measured: FlipMeasure | None = None


@dataclass
class EditResult(Result[EditReport]):
    """The edited clip, its flight (the last step's), the steps' reports, the
    analysis of the input clip and the steps' results."""
    analysis: Analysis
    steps: EditSteps


def edit(clip: Clip | Analysis, *, flips: int | None = None, k_ratio: float = 1.0,
         straighten: str | None = None, t_from: float | None = None, t_to: float | None = None,
         midpoint: bool = False, join: Clip | Analysis | None = None,
         total_mass: float = 70.0) -> EditResult:
    """Edit ``clip``: join its take-off and early flight to the late flight and
    landing of ``join`` (alone), or straighten the ``"legs"`` or ``"arms"`` from
    ``t_from`` to ``t_to`` seconds and repair |L| by retiming (``midpoint``: the
    second-order rule), then make ``flips`` flips (``k_ratio`` × k*; default k*, momentum
    continuous) of the result,
    re-analysed with the original's body.  ``clip`` is analysed with
    ``total_mass`` kg (a given :class:`Analysis` is used as it is).

    Raises :class:`~flipstudy.stimuli.edit.flight_measures.FlipEditError` (nothing
    to do, no flight, a join with other steps) or the steps' errors.
    """
    if flips is None and not straighten and join is None:
        raise FlipEditError("nothing to do: give flips, straighten or join")
    a = clip if isinstance(clip, Analysis) else analyse(clip, total_mass=total_mass)
    if a.flight is None:
        raise FlipEditError("no flight phase found")
    steps, report = EditSteps(), EditReport()
    last: Result | None = None
    if join is not None:
        from .join import join_in_flight
        steps.join = last = join_in_flight(a, join)
        report.join = last.report
        if flips is not None or straighten:
            raise FlipEditError("--join is made on its own (not with --flips or --straighten)")
    base = a
    if straighten:
        edited = straighten_group(a, straighten, t_from, t_to)
        steps.repair = last = repair_momentum(a, edited, midpoint=midpoint)
        report.repair = last.report
        if flips is not None:
            base = analyse(last.clip, body=a.body, estimate=False)
    if flips is not None:
        steps.multiflip = last = multiflip(base, flips, k_ratio=k_ratio)
        report.multiflip = last.report
        report.measured = measure(last, base)
    return EditResult(last.clip, last.takeoff, last.landing, report, analysis=a, steps=steps)
