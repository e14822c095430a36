"""Error injection: the controlled physical errors that are the conditions of the
paper's study (Section 7), and the measurement that checks each stimulus.

The motion is split into the COM path and the motion relative to the COM.

* **Angular momentum** (``inject_angular_momentum``): the relative motion over
  the whole airborne span (take-off instant to touchdown instant) is retimed
  with a rate r(τ) — *abrupt*: 1 until the midpoint of the stimulus' airborne
  span, then 1+e; *smooth*: rising linearly from 1 at take-off to 1+e at
  touchdown.
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

The kinds of the wider perception literature (gravity, take-off velocity
components, added accelerations, time scale, pose rate) are built the same way
in :mod:`flipstudy.stimuli.ballistic` and measured in
:mod:`flipstudy.stimuli.ballistic_measure`.

Every stimulus is then *measured* by the analyser (:func:`measure`), and
:func:`check` refuses one whose measured error misses the nominal, or whose
COM in the air leaves free fall by more than the original's own measurement
noise (+ ``AIR_MARGIN``): an error may change the COM velocity only at the
contact instants (what a different push or landing would do), never in the air.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .analyse import Analysis, analyse
from .edit.reposition import ballistic_path
from .edit.timing import sample
from flipstudy.errors import FlipstudyValueError, StimulusError
from .flight import path_values
from .motion.clip import Clip, derived_meta
from .physics import center_of_mass
from flipstudy.vocab import kinds

#: the kinds a design may inject, as registered (:mod:`flipstudy.vocab.kinds`) when
#: this module was imported (the design reads the registry itself)
KINDS = kinds.study_kind_names()
PROFILES = kinds.AM.variants
COM_POLICIES = kinds.COM_POLICIES


@dataclass
class Injected:
    """An edited clip and what was done to it (the nominal side)."""

    clip: Clip
    kind: str
    profile: str | None
    error: float                 # fraction, e.g. 0.25
    takeoff: int                 # frames strictly inside the new clip's airborne span
    landing: int
    rate_src: np.ndarray | None  # source frame of every new frame (AM errors)
    flight_s: float
    takeoff_time: float = float("nan")    # contact instants of the new clip, seconds
    landing_time: float = float("nan")
    opts: dict = field(default_factory=dict)   # the kind's options (policy, axis, span, rate)
    air_acc: np.ndarray | None = None          # the COM's acceleration in the air it was built
                                               # with (None: free fall at the original's g)


def _need_flight(a: Analysis) -> None:
    if a.flight is None:
        raise StimulusError(f"{a.clip.meta.get('name', 'clip')}: no flight phase, so no physical "
                            f"error can be injected into it")


def _inside(t_to: float, t_ld: float, fps: float) -> tuple[int, int]:
    """First and last frame strictly between two instants (seconds)."""
    return int(np.floor(t_to * fps + 1e-6)) + 1, int(np.ceil(t_ld * fps - 1e-6)) - 1


def _rate_map(profile: str, e: float, T: float):
    """New airborne duration and the map τ → source seconds s(τ) (both from the
    take-off instant).  *abrupt*: rate 1, then 1+e from the midpoint of the new
    airborne span; *smooth*: rate rising linearly from 1 at take-off to 1+e at
    touchdown."""
    if profile == "abrupt":
        Tn = 2.0 * T / (2.0 + e)

        def s(tau):
            return np.where(tau <= Tn / 2, tau, Tn / 2 + (1 + e) * (tau - Tn / 2))
    elif profile == "smooth":
        Tn = T / (1 + e / 2)

        def s(tau):
            return tau + e * tau ** 2 / (2 * Tn)
    else:
        raise FlipstudyValueError(f"profile must be one of {PROFILES}, got {profile!r}")
    return Tn, s


def inject_angular_momentum(a: Analysis, error: float, profile: str = "smooth",
                            com_policy: str = "angle") -> Injected:
    """Retime the airborne span's relative motion so |L| changes by ``error``
    (fraction, −0.5 … +0.5) with the given profile.  ``a`` is the original's
    analysis.  The span runs from the take-off instant to the touchdown instant;
    its COM is an exact parabola from the take-off instant, so the COM velocity
    changes only there and at the new touchdown.

    Examples
    --------
    >>> import numpy as np
    >>> from flipstudy import analyse, builtin
    >>> from flipstudy.stimuli.physics import momentum
    >>> a = analyse(builtin("backflip"))
    >>> stim = inject_angular_momentum(a, 0.25, "abrupt")
    >>> stim.clip.meta["edit"]
    'angular-momentum abrupt +0.250'
    >>> L0 = np.linalg.norm(a.L[a.takeoff:a.landing + 1], axis=1).mean()   # the original's flight mean
    >>> L = np.linalg.norm(momentum(stim.clip, a.body).L, axis=1)
    >>> round(float(L[stim.takeoff] / L0), 2), round(float(L[stim.landing] / L0), 2)   # +25 % at mid-flight
    (1.0, 1.25)
    """
    _need_flight(a)
    if not (-0.9 < error < 5.0):
        raise StimulusError(f"angular-momentum error {error!r} out of range (-0.9, 5)")
    if com_policy not in COM_POLICIES:
        raise FlipstudyValueError(f"com_policy must be one of {COM_POLICIES}, got {com_policy!r}")
    clip, fps = a.clip, a.clip.fps
    t_to, t_ld = a.takeoff_time, a.landing_time
    T = t_ld - t_to
    Tn, s_of = _rate_map(profile, error, T)
    t_end = (clip.num_frames - 1) / fps
    n_new = int(np.floor((t_end - T + Tn) * fps + 1e-9)) + 1
    t = np.arange(n_new) / fps                        # new clip's times
    tau = t - t_to
    src_t = np.where(tau <= 0, t, np.where(tau <= Tn, t_to + s_of(np.clip(tau, 0.0, Tn)),
                                           t_ld + (tau - Tn)))
    # frames up to the take-off instant are the source's own (whole frames exactly)
    src = np.where(tau <= 0, np.arange(n_new, dtype=float), src_t * fps)
    new = sample(clip, src)
    t_ld_new = t_to + Tn
    to, ld_new = _inside(t_to, t_ld_new, fps)
    # COM: exact parabola strictly inside the airborne span, continuity after
    body = a.body
    com_s = center_of_mass(new, body)
    g = -2.0 * a.path[1, 0]
    c0 = a.path_at(np.array([t_to]))[0]
    c_end = a.path_at(np.array([t_ld]))[0]
    v0 = a.takeoff_velocity
    dy = c_end[1] - c0[1]
    vy = (dy + 0.5 * g * Tn ** 2) / Tn
    vh = v0[[0, 2]]
    if com_policy == "angle":
        vh_new = vh * (vy / v0[1]) if abs(v0[1]) > 1e-9 else vh
    else:
        vh_new = (c_end[[0, 2]] - c0[[0, 2]]) / Tn
    v_new = np.array([vh_new[0], vy, vh_new[1]])
    fr = slice(to, ld_new + 1)
    target = ballistic_path(c0, v_new, g, tau[fr])
    shift = np.zeros_like(new.root_pos)
    shift[fr] = target - com_s[fr]
    # after touchdown: offset by where the flight now ends relative to where it ended
    end_new = ballistic_path(c0, v_new, g, np.array([Tn]))[0]
    shift[ld_new + 1:] = end_new - c_end
    out = new.replace(root_pos=new.root_pos + shift,
                      meta=derived_meta(clip.meta, f"angular-momentum {profile} {error:+.3f}"))
    return Injected(out, kinds.AM.name, profile, float(error), to, ld_new, src, Tn,
                    float(t_to), float(t_ld_new))


def inject_takeoff_angle(a: Analysis, error: float) -> Injected:
    """Scale the horizontal COM velocity over the airborne span (take-off
    instant to touchdown instant) by ``1 + error``; vertical velocity, duration
    and angular momentum stay."""
    _need_flight(a)
    if not (-1.0 < error < 10.0):
        raise StimulusError(f"take-off error {error!r} out of range (-1, 10)")
    clip, fps = a.clip, a.clip.fps
    t_to, t_ld = a.takeoff_time, a.landing_time
    vh = a.takeoff_velocity
    vh[1] = 0.0
    if np.linalg.norm(vh) < 1e-6:
        raise StimulusError(f"{clip.meta.get('name', 'clip')}: the jump has no horizontal velocity, "
                            f"so a take-off angle error along its direction is undefined")
    t = np.arange(clip.num_frames) / fps - t_to
    T = t_ld - t_to
    shift = error * vh[None] * np.clip(t, 0.0, T)[:, None]
    out = clip.replace(root_pos=clip.root_pos + shift,
                       meta=derived_meta(clip.meta, f"takeoff-angle {error:+.3f}"))
    return Injected(out, kinds.TAKEOFF_ANGLE.name, None, float(error), a.takeoff, a.landing, None, T,
                    float(t_to), float(t_ld))


#: a stimulus whose in-air COM acceleration leaves gravity by more than the
#: original's own departure plus this (m/s²) is refused
AIR_MARGIN = 0.5


def air_departure(com: np.ndarray, fps: float, takeoff: int, landing: int, g: float = 9.81) -> float:
    """Largest |a − g| (m/s²) of the COM's second differences over the frames
    strictly inside an airborne span (each stencil entirely in the air)."""
    c = com[takeoff:landing + 1]
    if c.shape[0] < 3:
        return float("nan")
    acc = (c[2:] - 2 * c[1:-1] + c[:-2]) * fps ** 2
    acc[:, 1] += g
    return float(np.linalg.norm(acc, axis=1).max())


def contact_velocity_changes(com: np.ndarray, fps: float, takeoff: int, landing: int,
                             t_to: float, t_ld: float) -> tuple[float, float]:
    """|Δv| of the COM (m/s) at the take-off and touchdown instants: the airborne
    parabola's velocity (fitted to the frames strictly inside) against the ground
    phases' own one-sided velocities at the contact frames (NaN when a ground
    phase has fewer than 3 frames)."""
    from .flight import fit_path
    coef = fit_path(com[takeoff:landing + 1], fps)
    t0 = takeoff / fps

    def v_air(t):
        v = coef[:, 1].copy()
        v[1] += 2.0 * coef[1, 0] * (t - t0)
        return v
    F = com.shape[0]
    f0 = takeoff - 1                                  # last ground frame before
    f1 = landing + 1                                  # first ground frame after
    dv_to = dv_ld = float("nan")
    if f0 >= 2:
        v_g = (3 * com[f0] - 4 * com[f0 - 1] + com[f0 - 2]) * fps / 2
        dv_to = float(np.linalg.norm(v_air(f0 / fps) - v_g))
    if f1 + 2 < F:
        v_g = (-3 * com[f1] + 4 * com[f1 + 1] - com[f1 + 2]) * fps / 2
        dv_ld = float(np.linalg.norm(v_air(f1 / fps) - v_g))
    return dv_to, dv_ld


def measure(original: Analysis, inj: Injected) -> dict:
    """What a stimulus really contains, measured with the original's body (same
    masses), against the original, over the airborne span the stimulus was
    built with (momenta differenced within each phase).

    Keys: ``measured_error_pct`` (the error of the stimulus' kind: |L| ratio −1
    where fully applied for AM, horizontal take-off velocity ratio −1 for take-off
    errors), ``L_ratio_window`` (mean |L| ratio over the last 10 % of flight
    (smooth) or its second half (abrupt)), ``L_error_touchdown_pct`` (|L| ratio
    −1 at the touchdown instant: a line through the last five airborne frames), ``takeoff_angle_deg``,
    ``takeoff_angle_change_deg``, ``flight_s``, ``jump_height_m``,
    ``jump_length_m``, ``dp_takeoff``/``dp_landing`` (jump in linear momentum
    across take-off/landing, kg·m/s), ``dv_takeoff``/``dv_landing`` (COM
    velocity change at the contact instants, m/s), ``air_acc_dev`` (largest
    in-air |a − g| of the COM, m/s²) and ``air_acc_dev_original``,
    ``below_floor_mm`` (how far the stimulus' lowest point goes below the
    original's lowest: a changed take-off velocity moves the feet near the
    floor), ``L_change_pct`` (mean |L| in flight vs the original, for take-off errors),
    ``takeoff``/``landing`` found by the analyser."""
    from .physics import momentum
    stim = analyse(inj.clip, body=original.body, estimate=False)
    if stim.flight is None:
        raise StimulusError("the analyser finds no flight in the stimulus")
    fps = inj.clip.fps
    out: dict = {}
    out["takeoff"], out["landing"] = stim.takeoff, stim.landing
    mo = momentum(inj.clip, original.body, [inj.takeoff, inj.landing + 1])
    com = mo.com
    fr = slice(inj.takeoff, inj.landing + 1)
    path = _fit(com[fr], fps)
    v = path[:, 1].copy()
    v[1] += 2.0 * path[1, 0] * (inj.takeoff_time - inj.takeoff / fps)   # at the instant
    ang = float(np.degrees(np.arctan2(v[1], np.hypot(v[0], v[2]))))
    out["takeoff_angle_deg"] = ang
    out["takeoff_angle_change_deg"] = ang - original.takeoff_angle
    T = inj.landing_time - inj.takeoff_time
    out["flight_s"] = T
    g = -2.0 * path[1, 0]
    out["jump_height_m"] = float(v[1] ** 2 / (2 * g)) if g > 0 else float("nan")
    c_to = path_values(path, np.array([inj.takeoff_time - inj.takeoff / fps]))[0]
    end = path_values(path, np.array([inj.landing_time - inj.takeoff / fps]))[0]
    out["jump_length_m"] = float(np.hypot(*(end - c_to)[[0, 2]]))
    Ln = np.linalg.norm(mo.L, axis=1)
    Lo = original.L_norm
    k = np.arange(inj.takeoff, inj.landing + 1)
    n = k.size
    if inj.kind == kinds.AM.name:
        src = inj.rate_src[k]
        # the original's |L| at the source instants, from its own airborne frames only
        ko = np.arange(original.takeoff, original.landing + 1)
        ratio = Ln[k] / np.interp(src, ko, Lo[ko])
        tau = k / fps - inj.takeoff_time
        Tn = inj.landing_time - inj.takeoff_time
        if inj.profile == "smooth":
            # r(τ) rises linearly from the take-off instant; fit the per-frame ratio
            # and read it at touchdown, where the error is fully applied (the
            # end frames, differenced one-sidedly, are left out: on captured data
            # their noise is the largest)
            A = np.stack([np.ones(n), tau / Tn], 1)
            inner = slice(1, n - 1) if n > 6 else slice(0, n)
            c = np.linalg.lstsq(A[inner], ratio[inner], rcond=None)[0]
            full = c[0] + c[1]
            win = slice(int(np.floor(0.9 * (n - 1))), n)
        else:
            # the rate switches at the midpoint of the stimulus' airborne span
            half = int(np.searchsorted(tau, Tn / 2, side="right"))
            win = slice(min(half + 1, n - 2), n - 1) if n > 6 else slice(min(half, n - 1), n)
            full = float(np.mean(ratio[win]))
        out["measured_error_pct"] = 100.0 * (full - 1.0)
        out["L_ratio_window"] = float(np.mean(ratio[win]))
        # a line through the last five airborne frames, read at the touchdown instant
        m5 = min(5, n)
        if m5 >= 2:
            c5 = np.polyfit(tau[-m5:], ratio[-m5:], 1)
            out["L_error_touchdown_pct"] = 100.0 * (float(np.polyval(c5, Tn)) - 1.0)
        else:
            out["L_error_touchdown_pct"] = 100.0 * (float(ratio[-1]) - 1.0)
        out["L_change_pct"] = 100.0 * (float(np.mean(Ln[fr])) / original.L_mean - 1.0)
    else:
        v0 = original.takeoff_velocity
        out["measured_error_pct"] = 100.0 * (np.hypot(v[0], v[2]) / np.hypot(v0[0], v0[2]) - 1.0)
        out["L_ratio_window"] = float(np.mean(Ln[fr]) / original.L_mean)
        out["L_change_pct"] = 100.0 * (out["L_ratio_window"] - 1.0)
        end = slice(max(inj.landing - 2, inj.takeoff), inj.landing + 1)
        end0 = slice(max(original.landing - 2, original.takeoff), original.landing + 1)
        out["L_error_touchdown_pct"] = 100.0 * (float(np.median(Ln[end]))
                                                / float(np.median(Lo[end0])) - 1.0)
    p = mo.p
    out["dp_takeoff"] = float(np.linalg.norm(p[inj.takeoff] - p[max(inj.takeoff - 2, 0)]))
    last = min(inj.landing + 2, p.shape[0] - 1)
    out["dp_landing"] = float(np.linalg.norm(p[last] - p[inj.landing]))
    out["dv_takeoff"], out["dv_landing"] = contact_velocity_changes(
        com, fps, inj.takeoff, inj.landing, inj.takeoff_time, inj.landing_time)
    out["below_floor_mm"] = 1000.0 * max(0.0, _lowest(original.clip) - _lowest(inj.clip))
    out["air_acc_dev"] = air_departure(com, fps, inj.takeoff, inj.landing)
    out["air_acc_dev_original"] = air_departure(original.com, original.clip.fps,
                                                original.takeoff, original.landing)
    return out


def _lowest(clip: Clip) -> float:
    """Height of the lowest joint or end site over the whole clip (m)."""
    h = clip.joint_positions()[..., 1].min()
    if clip.skeleton.end_sites:
        h = min(h, clip.end_site_positions()[..., 1].min())
    return float(h)


def _fit(com: np.ndarray, fps: float) -> np.ndarray:
    from .flight import fit_path
    return fit_path(com, fps)


def check(measured: dict, inj: Injected, tol_pct: float, name: str = "stimulus",
          tolerance_is: str = "the tolerance") -> None:
    """Refuse a stimulus whose measured error misses the nominal by more than
    ``tol_pct`` percentage points (``tolerance_is``: what the refusal calls the
    tolerance, e.g. the design field that set it)."""
    dev, floor = measured.get("air_acc_dev"), measured.get("air_acc_dev_original")
    if dev is not None and floor is not None and np.isfinite(dev) and np.isfinite(floor) \
            and dev > floor + AIR_MARGIN:
        raise StimulusError(
            f"{name}: its COM leaves free fall in the air: largest in-air |a - g| {dev:.2f} m/s² "
            f"(frames {inj.takeoff}-{inj.landing}), the original's own {floor:.2f} m/s² + "
            f"{AIR_MARGIN:g} allowed; velocity change at take-off {measured.get('dv_takeoff', float('nan')):.3f} m/s, "
            f"at touchdown {measured.get('dv_landing', float('nan')):.3f} m/s; not written")
    nominal = 100.0 * inj.error
    got = measured["measured_error_pct"]
    if not np.isfinite(got) or abs(got - nominal) > tol_pct:
        raise StimulusError(
            f"{name}: measured {inj.kind} error {got:+.2f} % misses the nominal {nominal:+.2f} % by "
            f"more than {tol_pct:g} points; not written (raise {tolerance_is} for noisy data, or "
            f"check the clip's flight)")
