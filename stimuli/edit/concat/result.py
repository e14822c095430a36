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
    height and the lowest foot above it."""
    foot_slide_cm: float
    pinned: list
    released: list
    floor: float
    lowest_foot_above_floor_cm: float


@dataclass
class ConcatReport(Report):
    """What :func:`~flipstudy.stimuli.edit.concat.concatenate` did and measured (eqs. 2-9 of Shum et al. 2009)."""
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
    """The motion-graph transition of :func:`~flipstudy.stimuli.edit.concat.motion_graph_join`."""
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
    a :class:`MotionGraphReport` (:func:`~flipstudy.stimuli.edit.concat.motion_graph_join`)."""
