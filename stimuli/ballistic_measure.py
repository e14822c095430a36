"""Measuring a stimulus of the ballistic kinds (:mod:`flipstudy.stimuli.ballistic`)
from its own joints, with the original's body, against the original.

The COM over the frames strictly inside the stimulus' airborne span is fitted
with a free quadratic in every axis (no gravity assumed): its t² terms are the
in-flight acceleration (the apparent gravity is minus the vertical one), its
slope at the take-off instant the take-off velocity.  Of a ``pose-rate``
stimulus only the distinct poses are used, at the update instants read off the
frames where the pose changes.  The result has every key of
:func:`flipstudy.stimuli.injection.measure` (so :func:`~flipstudy.stimuli.injection.check`
judges it alike: ``air_acc_dev`` is the largest in-air departure from the
acceleration the stimulus was built with) and the keys of :data:`EXTRA_COLUMNS`.
"""

from __future__ import annotations

import numpy as np

from .analyse import Analysis
from .ballistic import G0
from flipstudy.errors import StimulusError
from .injection import Injected, _lowest
from .motion.clip import Clip
from .physics import momentum
from flipstudy.vocab import kinds

#: the manifest's extra columns of a study that uses a ballistic kind (its rows of
#: every kind have them; the default study's manifest does not)
from .contract import EXTRA_COLUMNS  # the ballistic columns are part of the contract

#: per kind: what is changed (quantity, unit), as the registry declares it
QUANTITY = {**{k.name: k.quantity for k in kinds.study_kinds()}, "reference": ("none", "")}


def fit_free(com: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(3,3) least-squares quadratic of ``com`` (n,3) at times ``t`` in every
    axis: rows x,y,z; columns t², t, 1."""
    A = np.stack([t ** 2, t, np.ones_like(t)], 1)
    return np.linalg.lstsq(A, com, rcond=None)[0].T


def _at(coef: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity of a fitted quadratic at ``t``."""
    return coef[:, 0] * t * t + coef[:, 1] * t + coef[:, 2], 2.0 * coef[:, 0] * t + coef[:, 1]


def pose_updates(clip: Clip) -> tuple[np.ndarray, float, float]:
    """The frames where a new pose appears (the first frame and every frame whose
    root or rotations differ from the previous one), the update rate in poses
    per second and the instant of update 0.  The rate is the slope of a line
    fitted to the update frames' times against their index (a gap of several
    periods, where the motion stands still, counts as several updates); an update
    at instant u shows on the first frame at or after it, so update 0 is at the
    latest instant every update allows: min(frame time − index / rate)."""
    d = np.abs(np.diff(clip.rotations, axis=0)).reshape(clip.num_frames - 1, -1).max(1)
    d = np.maximum(d, np.abs(np.diff(clip.root_pos, axis=0)).max(1))
    frames = np.concatenate([[0], np.flatnonzero(d > 0) + 1])
    if frames.size < 3:
        return frames, float("nan"), 0.0
    gaps = np.diff(frames)
    step = np.concatenate([[0], np.maximum(1, np.round(gaps / np.median(gaps)))]).cumsum()
    slope = np.polyfit(step, frames / clip.fps, 1)[0]
    return frames, float(1.0 / slope), float(np.min(frames / clip.fps - step * slope))


def _sequence(a: Analysis, inj: Injected):
    """The poses the stimulus shows and their times: the frames of the airborne
    span and three either side, or for pose-rate the distinct poses at their
    update instants (a clip at the update rate); the first and last index
    strictly inside the airborne span; their momenta (each phase differenced
    on its own)."""
    clip, fps = inj.clip, inj.clip.fps
    if inj.kind != "pose-rate":              # the flight and three frames either side
        lo, hi = max(0, inj.takeoff - 3), min(clip.num_frames, inj.landing + 4)
        mo = momentum(clip.slice(lo, hi), a.body, [inj.takeoff - lo, inj.landing + 1 - lo])
        return np.arange(lo, hi) / fps, mo, inj.takeoff - lo, inj.landing - lo
    frames, rate, t0 = pose_updates(clip)
    t = t0 + np.round((frames / fps - t0) * rate) / rate
    pc = Clip(clip.skeleton, rate, clip.root_pos[frames], clip.rotations[frames],
              None if clip.joint_pos is None else clip.joint_pos[frames], dict(clip.meta))
    inside = np.flatnonzero((t > a.takeoff_time + 1e-9) & (t < a.landing_time - 1e-9))
    mo = momentum(pc, a.body, [inside[0], inside[-1] + 1])
    return t, mo, int(inside[0]), int(inside[-1])


def _departure(t: np.ndarray, com: np.ndarray, acc: np.ndarray) -> float:
    """Largest |second difference − acc| (m/s²) of a COM sampled at times ``t``."""
    if com.shape[0] < 3:
        return float("nan")
    h0, h1 = np.diff(t)[:-1, None], np.diff(t)[1:, None]
    a2 = 2.0 * ((com[2:] - com[1:-1]) / h1 - (com[1:-1] - com[:-2]) / h0) / (h0 + h1)
    return float(np.linalg.norm(a2 - acc, axis=1).max())


def _ground_dv(com: np.ndarray, t: np.ndarray, to: int, ld: int, vel) -> tuple[float, float]:
    """|Δv| at the contacts: the flight's velocity ``vel(time)`` at the sample
    beside each ground phase against that phase's one-sided velocity (uniform
    samples at times ``t``; NaN: ground phase too short)."""
    F, rate = com.shape[0], 1.0 / float(t[1] - t[0])
    f0, f1 = to - 1, ld + 1
    dv_to = dv_ld = float("nan")
    if f0 >= 2:
        dv_to = float(np.linalg.norm(vel(t[f0]) - (3 * com[f0] - 4 * com[f0 - 1] + com[f0 - 2]) * rate / 2))
    if f1 + 2 < F:
        dv_ld = float(np.linalg.norm(vel(t[f1]) - (-3 * com[f1] + 4 * com[f1 + 1] - com[f1 + 2]) * rate / 2))
    return dv_to, dv_ld


def measure_ballistic(original: Analysis, inj: Injected) -> dict:
    """What a ballistic-kind stimulus contains: the keys of
    :func:`flipstudy.stimuli.injection.measure` and of :data:`EXTRA_COLUMNS`.
    ``measured_error_pct`` is the kind's changed quantity against the original's,
    in percent (gravity: apparent gravity ratio − 1; velocities: the component's
    ratio − 1; acceleration: the added acceleration along its axis / 9.81;
    time-scale: √(gravity ratio) − 1, the playback rate the parabola shows;
    pose-rate: updates per second / frame rate − 1)."""
    o, clip, fps = original, inj.clip, inj.clip.fps
    if o.flight is None:
        raise StimulusError("the original has no flight")
    held = inj.kind == "pose-rate"
    ts, mo, i0, i1 = _sequence(o, inj)
    t, com = ts[i0:i1 + 1], mo.com[i0:i1 + 1]
    cf, Ln = fit_free(com, t), np.linalg.norm(mo.L[i0:i1 + 1], axis=1)
    # the instants of the motion shown (pose-rate: the original's, which its held
    # poses sample; its display instants are inj's)
    t_to, t_ld = (o.takeoff_time, o.landing_time) if held else (inj.takeoff_time, inj.landing_time)
    # the original: the analyser's own ballistic path (the one every stimulus is
    # built from: x and z straight, y a parabola), at its own instants
    to_o, ld_o = o.takeoff, o.landing
    g_o = float(o.apparent_gravity)
    c0_o, c1_o = o.path_at(np.array([o.takeoff_time, o.landing_time]))
    v_o = o.takeoff_velocity
    c0, v = _at(cf, t_to)
    c1, _ = _at(cf, t_ld)
    acc, acc_o = 2.0 * cf[:, 0], np.array([0.0, -g_o, 0.0])
    g = -acc[1]
    vh, vh_o = np.hypot(v[0], v[2]), np.hypot(v_o[0], v_o[2])
    u = np.array([v_o[0], 0.0, v_o[2]]) / vh_o if vh_o > 1e-9 else np.zeros(3)
    out: dict = {"takeoff": inj.takeoff, "landing": inj.landing}
    ang = float(np.degrees(np.arctan2(v[1], vh)))
    out["takeoff_angle_deg"] = ang
    out["takeoff_angle_change_deg"] = ang - o.takeoff_angle
    T, T_o = inj.landing_time - inj.takeoff_time, o.flight_s
    out["flight_s"] = T
    out["jump_height_m"] = float(v[1] ** 2 / (2 * g)) if g > 0 else float("nan")
    out["jump_length_m"] = float(np.hypot(*(c1 - c0)[[0, 2]]))
    L_mean = float(np.mean(Ln))
    out["L_ratio_window"] = L_mean / o.L_mean
    out["L_change_pct"] = 100.0 * (out["L_ratio_window"] - 1.0)
    Lo = o.L_norm
    out["L_error_touchdown_pct"] = 100.0 * (float(np.median(Ln[-3:])) /
                                            float(np.median(Lo[max(ld_o - 2, to_o):ld_o + 1])) - 1.0)
    expected = inj.air_acc if inj.air_acc is not None else np.array([0.0, -g_o, 0.0])
    out["air_acc_dev"] = _departure(t, com, expected)
    out["air_acc_dev_original"] = _departure(np.arange(to_o, ld_o + 1) / o.clip.fps,
                                             o.com[to_o:ld_o + 1], acc_o)
    p = mo.p
    out["dp_takeoff"] = float(np.linalg.norm(p[i0] - p[max(i0 - 2, 0)]))
    out["dp_landing"] = float(np.linalg.norm(p[min(i1 + 2, p.shape[0] - 1)] - p[i1]))
    out["dv_takeoff"], out["dv_landing"] = _ground_dv(mo.com, ts, i0, i1, lambda s: _at(cf, s)[1])
    out["below_floor_mm"] = 1000.0 * max(0.0, _lowest(o.clip) - _lowest(clip))
    # the extras: what changed and what the kind keeps
    out["apparent_gravity"] = g
    out["takeoff_vh"], out["takeoff_vy"] = float(vh), float(v[1])
    out["air_acc_h"] = float((acc - acc_o) @ u)
    out["air_acc_v"] = float(acc[1] - acc_o[1])
    out["flight_s_change_pct"] = 100.0 * (T / T_o - 1.0)
    apex_o = v_o[1] ** 2 / (2 * g_o)
    out["apex_change_pct"] = 100.0 * (out["jump_height_m"] / apex_o - 1.0)
    out["landing_shift_m"] = float(np.hypot(*((c1 - c0) - (c1_o - c0_o))[[0, 2]]))
    out["landing_height_change_mm"] = 1000.0 * float((c1[1] - c0[1]) - (c1_o[1] - c0_o[1]))
    out["playback_rate"] = float(np.sqrt(g / g_o)) if g > 0 else float("nan")
    out["pose_rate"] = pose_updates(clip)[1] if held else float(fps)
    out.update(_quantity(inj, out, g_o, vh_o, v_o, fps))
    return out


def _quantity(inj: Injected, m: dict, g_o: float, vh_o: float, v_o: np.ndarray, fps: float) -> dict:
    """quantity, unit, nominal and measured value and ``measured_error_pct``."""
    kind, e = inj.kind, inj.error
    entry = kinds.find(kind)
    q, unit = entry.quantity if entry is not None else QUANTITY.get(kind, (kind, ""))
    if kind == "gravity":
        nom, got, err = (1 + e) * g_o, m["apparent_gravity"], m["apparent_gravity"] / g_o - 1
    elif kind == "horizontal-velocity":
        nom, got = (1 + e) * vh_o, m["takeoff_vh"]
        err = got / vh_o - 1
    elif kind == "vertical-velocity":
        nom, got = (1 + e) * v_o[1], m["takeoff_vy"]
        err = got / v_o[1] - 1
    elif kind == "acceleration":
        axis = inj.opts.get("axis", "horizontal")
        nom, got = e * G0, m["air_acc_h"] if axis == "horizontal" else m["air_acc_v"]
        err = got / G0
    elif kind == "time-scale":
        nom, got, err = 1 + e, m["playback_rate"], m["playback_rate"] - 1
    elif kind == "pose-rate":
        rate = inj.opts.get("rate", fps * (1 + e))
        nom, got, err = rate, m["pose_rate"], m["pose_rate"] / fps - 1
    else:                                       # a level-0 row of any kind, or the originals
        nom = got = err = 0.0
    return {"quantity": q, "unit": unit, "nominal_value": float(nom), "measured_value": float(got),
            "measured_error_pct": 100.0 * float(err),
            "policy": inj.opts.get("policy", ""), "axis": inj.opts.get("axis", ""),
            "span": inj.opts.get("span", "")}
