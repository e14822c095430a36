"""Controlled physical errors: the conditions of the paper's study (Section 7).

The motion is split into the COM path and the motion relative to the COM.

* **Angular momentum** (``inject_angular_momentum``): the relative motion in
  flight is retimed with a rate r(τ) — *abrupt*: 1 until mid-flight, then 1+e;
  *smooth*: rising linearly from 1 at take-off to 1+e at the last flight frame.
  L keeps its direction and its magnitude follows r.  The flight's duration
  changes, so its COM path is rebuilt as an exact parabola: by default keeping
  the take-off angle (``com_policy="angle"``: height and length scale with the
  new duration), or keeping the landing point (``com_policy="landing"``).
  Frames before take-off are unchanged; everything after landing follows
  continuously.
* **Take-off angle** (``inject_takeoff_angle``): the horizontal COM velocity in
  flight is scaled by 1+e (the paper's "linear velocity along the direction of
  the jump"); vertical velocity, duration and L are untouched; the landing and
  everything after it move along the jump direction.

Every stimulus is then *measured* by the analyser (:func:`measure`), and
:func:`check` refuses one whose measured error misses the nominal.
"""

from __future__ import annotations

from .exceptions import FlipstudyValueError

from .exceptions import FlipstudyError
from dataclasses import dataclass

import numpy as np

from .analyse import Analysis, analyse
from .edit.reposition import ballistic_path
from .edit.timing import sample
from .flight import path_values
from .motion.clip import Clip
from .physics import center_of_mass

KINDS = ("angular-momentum", "takeoff-angle")
PROFILES = ("smooth", "abrupt")
COM_POLICIES = ("angle", "landing")


class StimulusError(FlipstudyError, ValueError):
    """A stimulus that cannot be made or whose measured error misses the nominal."""


@dataclass
class Injected:
    """An edited clip and what was done to it (the nominal side)."""

    clip: Clip
    kind: str
    profile: str | None
    error: float                 # fraction, e.g. 0.25
    takeoff: int                 # flight frames of the new clip
    landing: int
    rate_src: np.ndarray | None  # source frame of every new frame (AM errors)
    flight_s: float


def _need_flight(a: Analysis) -> None:
    if a.flight is None:
        raise StimulusError(f"{a.clip.meta.get('name', 'clip')}: no flight phase, so no physical "
                            f"error can be injected into it")


def _rate_map(profile: str, e: float, T: float):
    """New flight duration and the map τ → source seconds s(τ) in flight."""
    if profile == "abrupt":
        Tn = T / 2 + (T / 2) / (1 + e)

        def s(tau):
            return np.where(tau <= T / 2, tau, T / 2 + (1 + e) * (tau - T / 2))
    elif profile == "smooth":
        Tn = T / (1 + e / 2)

        def s(tau):
            return tau + e * tau ** 2 / (2 * Tn)
    else:
        raise FlipstudyValueError(f"profile must be one of {PROFILES}, got {profile!r}")
    return Tn, s


def inject_angular_momentum(a: Analysis, error: float, profile: str = "smooth",
                            com_policy: str = "angle") -> Injected:
    """Retime the flight's relative motion so |L| changes by ``error`` (fraction,
    −0.5 … +0.5) with the given profile.  ``a`` is the original's analysis.

    Example
    -------
    >>> a = analyse(builtin("backflip"))                         # doctest: +SKIP
    >>> stim = inject_angular_momentum(a, 0.25, "abrupt").clip     # doctest: +SKIP
    """
    _need_flight(a)
    if not (-0.9 < error < 5.0):
        raise StimulusError(f"angular-momentum error {error!r} out of range (-0.9, 5)")
    if com_policy not in COM_POLICIES:
        raise FlipstudyValueError(f"com_policy must be one of {COM_POLICIES}, got {com_policy!r}")
    clip, fps = a.clip, a.clip.fps
    to, ld = a.takeoff, a.landing
    T = (ld - to) / fps
    Tn, s_of = _rate_map(profile, error, T)
    tail = (clip.num_frames - 1 - ld) / fps           # source seconds after landing
    n_after = int(np.floor((Tn + tail) * fps + 1e-9)) + 1
    tau = np.arange(n_after) / fps
    s = np.where(tau <= Tn, s_of(np.minimum(tau, Tn)), T + (tau - Tn))
    src = np.concatenate([np.arange(to, dtype=float), to + s * fps])
    new = sample(clip, src)
    ld_new = to + int(np.floor(Tn * fps + 1e-9))
    # COM: exact parabola in flight, continuity after
    body = a.body
    com_s = center_of_mass(new, body)
    path = a.path                                     # original flight path (t from take-off)
    g = -2.0 * path[1, 0]
    c0 = path_values(path, np.array([0.0]))[0]
    c_end = path_values(path, np.array([T]))[0]
    v0 = path[:, 1].copy()
    dy = c_end[1] - c0[1]
    vy = (dy + 0.5 * g * Tn ** 2) / Tn
    vh = v0[[0, 2]]
    if com_policy == "angle":
        vh_new = vh * (vy / v0[1]) if abs(v0[1]) > 1e-9 else vh
    else:
        vh_new = (c_end[[0, 2]] - c0[[0, 2]]) / Tn
    v_new = np.array([vh_new[0], vy, vh_new[1]])
    fr = slice(to, ld_new + 1)
    tf = (np.arange(to, ld_new + 1) - to) / fps
    target = ballistic_path(c0, v_new, g, tf)
    shift = np.zeros_like(new.root_pos)
    shift[fr] = target - com_s[fr]
    # after landing: offset by where the flight now ends relative to where it ended
    end_new = ballistic_path(c0, v_new, g, np.array([Tn]))[0]
    shift[ld_new + 1:] = end_new - c_end
    out = new.replace(root_pos=new.root_pos + shift,
                      meta={**clip.meta, "edit": f"angular-momentum {profile} {error:+.3f}"})
    out.meta.pop("source_frames", None)
    return Injected(out, "angular-momentum", profile, float(error), to, ld_new, src, Tn)


def inject_takeoff_angle(a: Analysis, error: float) -> Injected:
    """Scale the horizontal COM velocity in flight by ``1 + error``; vertical
    velocity, duration and angular momentum stay."""
    _need_flight(a)
    if not (-1.0 < error < 10.0):
        raise StimulusError(f"take-off error {error!r} out of range (-1, 10)")
    clip, fps = a.clip, a.clip.fps
    to, ld = a.takeoff, a.landing
    vh = a.path[:, 1].copy()
    vh[1] = 0.0
    if np.linalg.norm(vh) < 1e-6:
        raise StimulusError(f"{clip.meta.get('name', 'clip')}: the jump has no horizontal velocity, "
                            f"so a take-off angle error along its direction is undefined")
    t = (np.arange(clip.num_frames) - to) / fps
    T = (ld - to) / fps
    shift = error * vh[None] * np.clip(t, 0.0, T)[:, None]
    out = clip.replace(root_pos=clip.root_pos + shift,
                       meta={**clip.meta, "edit": f"takeoff-angle {error:+.3f}"})
    return Injected(out, "takeoff-angle", None, float(error), to, ld, None, T)


def measure(original: Analysis, inj: Injected) -> dict:
    """What a stimulus really contains, measured by the analyser with the
    original's body (same masses), against the original.

    Keys: ``measured_error_pct`` (the error of the stimulus' kind: |L| ratio −1
    where fully applied for AM, horizontal take-off velocity ratio −1 for take-off
    errors), ``L_ratio_window`` (mean |L| ratio over the last 10 % of flight
    (smooth) or its second half (abrupt)), ``takeoff_angle_deg``,
    ``takeoff_angle_change_deg``, ``flight_s``, ``jump_height_m``,
    ``jump_length_m``, ``dp_takeoff``/``dp_landing`` (jump in linear momentum
    across take-off/landing, kg·m/s), ``L_change_pct`` (mean |L| in flight vs
    the original, for take-off errors), ``takeoff``/``landing`` found."""
    stim = analyse(inj.clip, body=original.body, estimate=False)
    if stim.flight is None:
        raise StimulusError("the analyser finds no flight in the stimulus")
    fps = inj.clip.fps
    out: dict = {}
    # the analyser's own flight, but measured over the flight we built
    out["takeoff"], out["landing"] = stim.takeoff, stim.landing
    fr = slice(inj.takeoff, inj.landing + 1)
    path = _fit(stim.com[fr], fps)
    v = path[:, 1]
    ang = float(np.degrees(np.arctan2(v[1], np.hypot(v[0], v[2]))))
    out["takeoff_angle_deg"] = ang
    out["takeoff_angle_change_deg"] = ang - original.takeoff_angle
    T = (inj.landing - inj.takeoff) / fps
    out["flight_s"] = T
    g = -2.0 * path[1, 0]
    out["jump_height_m"] = float(v[1] ** 2 / (2 * g)) if g > 0 else float("nan")
    end = path_values(path, np.array([T]))[0]
    out["jump_length_m"] = float(np.hypot(*(end - path[:, 2])[[0, 2]]))
    Ln = np.linalg.norm(stim.L, axis=1)
    Lo = np.linalg.norm(original.L, axis=1)
    if inj.kind == "angular-momentum":
        k = np.arange(inj.takeoff, inj.landing + 1)
        src = inj.rate_src[k]
        ratio = Ln[k] / np.interp(src, np.arange(Lo.size), Lo)
        tau = (k - inj.takeoff) / fps
        n = k.size
        if inj.profile == "smooth":
            # r(τ) rises linearly; fit the per-frame ratio over the flight (ends
            # excluded: one-sided differences at the momentum jumps) and read it at
            # the last flight frame, where the error is fully applied
            inner = slice(2, n - 2)
            A = np.stack([np.ones(n), tau / tau[-1]], 1)[inner]
            c = np.linalg.lstsq(A, ratio[inner], rcond=None)[0]
            full = c[0] + c[1]
            win = slice(int(np.floor(0.9 * (n - 1))), n)
        else:
            # the rate switches at half the *original* flight time, which is past the
            # middle of a shortened (sped-up) flight and before that of a slowed one
            T0 = (original.landing - original.takeoff) / fps
            half = min(int(np.ceil(T0 / 2 * fps - 1e-9)), n - 1)
            win = slice(half + 2, n - 2) if n - 4 > half + 2 else slice(half, n)
            full = float(np.mean(ratio[win]))
        out["measured_error_pct"] = 100.0 * (full - 1.0)
        out["L_ratio_window"] = float(np.mean(ratio[win]))
        out["L_change_pct"] = 100.0 * (float(np.mean(Ln[fr])) / original.L_mean - 1.0)
    else:
        v0 = original.path[:, 1]
        out["measured_error_pct"] = 100.0 * (np.hypot(v[0], v[2]) / np.hypot(v0[0], v0[2]) - 1.0)
        out["L_ratio_window"] = float(np.mean(Ln[fr]) / original.L_mean)
        out["L_change_pct"] = 100.0 * (out["L_ratio_window"] - 1.0)
    p = stim.p
    out["dp_takeoff"] = float(np.linalg.norm(p[inj.takeoff] - p[max(inj.takeoff - 2, 0)]))
    last = min(inj.landing + 2, p.shape[0] - 1)
    out["dp_landing"] = float(np.linalg.norm(p[last] - p[inj.landing]))
    return out


def _fit(com: np.ndarray, fps: float) -> np.ndarray:
    from .flight import fit_path
    return fit_path(com, fps)


def check(measured: dict, inj: Injected, tol_pct: float, name: str = "stimulus") -> None:
    """Refuse a stimulus whose measured error misses the nominal by more than
    ``tol_pct`` percentage points."""
    nominal = 100.0 * inj.error
    got = measured["measured_error_pct"]
    if not np.isfinite(got) or abs(got - nominal) > tol_pct:
        raise StimulusError(
            f"{name}: measured {inj.kind} error {got:+.2f} % misses the nominal {nominal:+.2f} % by "
            f"more than {tol_pct:g} points; not written (raise the tolerance for noisy data, or "
            f"check the clip's flight)")
