"""What the flip editing methods measure of a flip (Majkowska & Faloutsos 2007,
Section 5): its angular-momentum axis, the root's turn about it, the standing
frames around the flight, the linear-momentum jumps at take-off and landing,
and :func:`measure`, the analyser's account of an edited flip; shared by the
multi-flip (:mod:`~flipstudy.stimuli.edit.multiflip`) and the join in flight
(:mod:`~flipstudy.stimuli.edit.join`).

>>> from flipstudy.stimuli import analyse, builtin
>>> from flipstudy.stimuli.edit.flight_measures import measure
>>> from flipstudy.stimuli.result import Result
>>> a = analyse(builtin("backflip"))
>>> m = measure(Result(a.clip, a.takeoff, a.landing, None), a)
>>> round(m.turn_deg / 360)                  # one flip
1
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..analyse import Analysis, analyse
from flipstudy.errors import FlipEditError
from ..flight import fit_path, path_values
from ..motion.clip import Clip
from ..physics import center_of_mass, momentum
from ..result import Result
from .report import Report


def flight_axis(a: Analysis) -> np.ndarray:
    """Unit direction of the mean angular momentum in flight."""
    L = a.L[a.takeoff:a.landing + 1].mean(axis=0)
    n = np.linalg.norm(L)
    if n < 1e-6:
        raise FlipEditError("the flight has no angular momentum to turn about (a jump, not a flip)")
    return L / n


def turn_angle(clip: Clip, axis, a: int = 0, b: int | None = None) -> float:
    """Degrees the root turns about ``axis`` from frame ``a`` to ``b``: the root's
    angular velocity along the axis, integrated (trapezoid)."""
    b = clip.num_frames - 1 if b is None else b
    w = clip.angular_velocities()[a:b + 1, 0] @ (np.asarray(axis, float) / np.linalg.norm(axis))
    return float(np.degrees(np.trapezoid(w, dx=1.0 / clip.fps))) if w.size > 1 else 0.0


def unwrapped_turn(clip: Clip, u: np.ndarray) -> np.ndarray:
    """(F,) radians the root has turned about the unit axis ``u`` since frame 0,
    unwrapped: its angular velocity along ``u`` integrated (trapezoid).  Written out
    rather than ``scipy.integrate.cumulative_trapezoid``: that rounds differently
    (~1e-17), enough to move the multi-flip's discrete choices (its test against
    ``tests/_support/_multiflip_reference.py`` then differs by 6e-5)."""
    w = clip.angular_velocities()[:, 0] @ u
    return np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) / clip.fps)])


def standing_span(clip: Clip, body, takeoff: int, landing: int, still: float = 0.05,
                  drop: float = 0.05) -> tuple[int, int]:
    """(last standing frame before take-off, first standing frame after landing).
    Standing: the COM moves slower than ``still`` m/s and is at most ``drop`` m
    below its height in the clip's first (before) or last (after) frame — so the
    bottom of a crouch, where the COM also stops, is not taken for standing.  The
    clip's ends when no frame qualifies."""
    m = momentum(clip, body)
    v = np.linalg.norm(m.v_com, axis=1)
    y = m.com[:, 1]
    before = np.flatnonzero((v[:takeoff + 1] < still) & (y[:takeoff + 1] >= y[0] - drop))
    after = np.flatnonzero((v[landing:] < still) & (y[landing:] >= y[-1] - drop))
    return (int(before[-1]) if before.size else 0,
            int(landing + after[0]) if after.size else clip.num_frames - 1)


def momentum_jumps(clip: Clip, body, takeoff: int, landing: int) -> dict:
    """Linear-momentum discontinuity at take-off and landing: the COM velocity
    one frame either side of each (one-sided differences), as a fraction of the
    take-off momentum."""
    return _jumps(center_of_mass(clip, body), clip.fps, body.total_mass, takeoff, landing)


def _jumps(com: np.ndarray, fps: float, M: float, takeoff: int, landing: int) -> dict:
    """:func:`momentum_jumps` from the COM (F,3); only the frames next to take-off and
    landing are read."""
    v_in = (com[takeoff] - com[takeoff - 1]) * fps if takeoff >= 1 else np.zeros(3)
    v_out = (com[takeoff + 1] - com[takeoff]) * fps
    l_in = (com[landing] - com[landing - 1]) * fps
    l_out = (com[landing + 1] - com[landing]) * fps if landing + 1 < com.shape[0] else l_in
    g = np.array([0.0, -9.81, 0.0])
    # gravity alone changes the velocity by g/fps over a frame; remove that part
    dp_to = M * np.linalg.norm(v_out - v_in - g / fps)
    dp_ld = M * np.linalg.norm(l_out - l_in - g / fps)
    p_to = M * np.linalg.norm(v_out)
    return {"dp_takeoff": float(dp_to), "dp_landing": float(dp_ld), "p_takeoff": float(p_to),
            "dp_takeoff_pct": float(100 * dp_to / p_to), "dp_landing_pct": float(100 * dp_ld / p_to)}


@dataclass
class FlipMeasure(Report):
    """What an edited flip has, by the analyser (:func:`measure`): the root's turn
    about L (degrees) over ``turn_span`` (the standing frames around the flight),
    the flight's |L| mean and CV, the COM's RMS distance from a parabola in flight,
    the flight the analyser finds and its apparent gravity."""
    turn_deg: float
    turn_span: list
    L_mean: float
    L_cv_pct: float
    com_rms_mm: float
    analyser_flight: list | None
    apparent_gravity: float | None


def measure(result: Result, original: Analysis) -> FlipMeasure:
    """What the edited clip of ``result`` (its ``clip``, ``takeoff`` and
    ``landing``) has, by the analyser with the original's body: the root's turn
    about the original's L from the last standing frame before take-off to the
    first after landing, flight |L| CV, COM residual from a parabola in flight."""
    clip = result.clip
    a = analyse(clip, body=original.body, estimate=False)
    u = flight_axis(original)
    to, ld = result.takeoff, result.landing
    s0, s1 = standing_span(clip, original.body, to, ld)
    Lm = np.linalg.norm(a.L[to + 2:ld - 1], axis=1)
    com = a.com[to:ld + 1]
    coef = fit_path(com, clip.fps)
    res = com - path_values(coef, np.arange(com.shape[0]) / clip.fps)
    return FlipMeasure(turn_deg=turn_angle(clip, u, s0, s1), turn_span=[s0, s1],
                       L_mean=float(Lm.mean()), L_cv_pct=float(100 * Lm.std() / Lm.mean()),
                       com_rms_mm=float(1000 * np.sqrt(np.mean(np.sum(res ** 2, axis=1)))),
                       analyser_flight=[a.takeoff, a.landing] if a.flight is not None else None,
                       apparent_gravity=a.apparent_gravity)
