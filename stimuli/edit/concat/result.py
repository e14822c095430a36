"""What the concatenation returns (Shum, Komura & Yadav 2009): the
:class:`Concatenation` result and the typed reports of
:func:`~flipstudy.stimuli.edit.concat.concatenate`
(:class:`ConcatReport`, with the feet's :class:`FeetReport`) and of the
motion-graph baseline (:class:`MotionGraphReport`)."""
from __future__ import annotations

from dataclasses import dataclass

from ...result import Result
from ..report import Report


@dataclass
class FeetReport(Report):
    """What :func:`~flipstudy.stimuli.edit.concat.pin_feet` did: foot slide while
    pinned, the pinned and released feet (``side:first-last`` frames), the floor
    height and the lowest foot above it.

    Attributes
    ----------
    foot_slide_cm : float
        Horizontal motion of the pinned points while in contact.
    pinned, released : list of str
        The feet pinned (``side:first-last``) and how each was let go.
    floor, lowest_foot_above_floor_cm : float

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import concatenate
    >>> c = builtin("backflip")
    >>> feet = concatenate(c, c).report.feet
    >>> feet.pinned, feet.foot_slide_cm < 1.0
    (['l:239-256', 'r:239-256'], True)
    """
    foot_slide_cm: float
    pinned: list
    released: list
    floor: float
    lowest_foot_above_floor_cm: float


@dataclass
class ConcatReport(Report):
    """What :func:`~flipstudy.stimuli.edit.concat.concatenate` did and measured (eqs. 2-9 of Shum et al. 2009).

    Attributes
    ----------
    rule, suggested_rule : str
        The rule used and the one the data suggest.
    theta_deg : float
        Motion 2's turn about the vertical (eq. 2).
    phases_a, phases_b : dict
        Each motion's phases (:meth:`Phases.as_dict`).
    case, support : str
        The blendable periods paired and the support they were truncated to.
    blendable_a, blendable_b, blend, blend_out : list of int
        First and last frames: the periods, the blend window before and after smoothing.
    T, f_T : int
        Motion 2's offset and the blending centre.
    F, F_dm, F_inertia, F_time, threshold : float
        The optimal cost (eqs. 3-7), its terms and the refusal threshold.
    feet : FeetReport or None
    flights : list
        |L| coefficient of variation per flight of the result.

    The other fields measure |L| over the blend, the alignment and the lengths.

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import concatenate
    >>> c = builtin("backflip")
    >>> rep = concatenate(c, c).report
    >>> rep.rule, rep.T, rep.f_T, rep.support
    ('forward', 82, 237, 'double support')
    >>> sorted(rep.to_dict())[:3]
    ['F', 'F_dm', 'F_inertia']
    """
    rule: str
    suggested_rule: str
    theta_deg: float
    phases_a: dict
    phases_b: dict
    case: str
    support: str
    blendable_a: list
    blendable_b: list
    T: int
    f_T: int
    F: float
    F_dm: float
    F_inertia: float
    F_time: float
    threshold: float
    blend: list
    blend_widened: object
    smoothing_s: float
    blend_out: list
    smoothing: dict | None
    L_target_blend: float
    facing_deg_at_fT: float
    shift_m: list
    aligned_at: int
    L_peak_blend_before: float
    L_peak_blend: float
    L_mean_blend: float
    L_main_peak_a: float
    L_main_peak_b: float
    frames: int
    duration_s: float
    frames_a: int
    frames_b: int
    #: the support feet pinned (``None`` without ``fix_feet``)
    feet: FeetReport | None
    #: |L| coefficient of variation per flight of the result
    flights: list

    def to_dict(self) -> dict:
        """The JSON keys: the feet's flattened in (when pinned), then the flights."""
        d = super().to_dict()
        feet, flights = d.pop("feet"), d.pop("flights")
        return {**d, **(feet or {}), "flights": flights}


@dataclass
class MotionGraphReport(Report):
    """The motion-graph transition of :func:`~flipstudy.stimuli.edit.concat.motion_graph_join`.

    Attributes
    ----------
    transition_a, transition_b : int
        The first frame of the window in each motion.
    window : int
        Frames blended.
    distance, theta_deg : float
        Kovar et al.'s point-cloud distance and motion 2's turn about the vertical.
    frames : int
    duration_s : float

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import motion_graph_join
    >>> c = builtin("backflip")
    >>> rep = motion_graph_join(c, c).report
    >>> rep.transition_a, rep.transition_b, rep.window, rep.frames
    (357, 0, 40, 754)
    """
    transition_a: int
    transition_b: int
    window: int
    distance: float
    theta_deg: float
    frames: int
    duration_s: float


@dataclass
class Concatenation(Result["ConcatReport | MotionGraphReport"]):
    """The concatenated clip, its flight (``takeoff``, ``landing``: ``None`` where
    it has not exactly one) and what was done and measured: a
    :class:`ConcatReport` (:func:`~flipstudy.stimuli.edit.concat.concatenate`) or
    a :class:`MotionGraphReport` (:func:`~flipstudy.stimuli.edit.concat.motion_graph_join`).

    Attributes
    ----------
    clip : Clip
    takeoff, landing : float or None
    report : ConcatReport or MotionGraphReport

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import concatenate
    >>> c = builtin("backflip")
    >>> r = concatenate(c, c)
    >>> r.clip.num_frames == r.report.frames, r.takeoff, type(r.report).__name__
    (True, None, 'ConcatReport')
    """
