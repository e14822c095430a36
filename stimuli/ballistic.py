"""The ballistic errors of the perception literature beyond angular momentum:
gravity, take-off velocity components, added in-flight accelerations, playback
speed and pose update rate (Reitsma & Pollard 2003; McManus et al. 2011; La
Scaleia et al. 2020; McDonnell, Newell & O'Sullivan 2007).

Every kind but ``pose-rate`` follows one construction, the one of
:func:`flipstudy.stimuli.injection.inject_angular_momentum`: the airborne span
runs from the original's take-off instant to a new touchdown instant ``Tn``
seconds later; the motion about the COM over it is the original's airborne
motion retimed *uniformly* (source seconds per stimulus second ``T/Tn``, so |L|
is scaled by ``T/Tn`` and the landing pose is the original's); the COM over it
is replaced by an exact path ``c0 + v·τ + ½·a·τ²`` (take-off velocity ``v``,
constant acceleration ``a``); everything after touchdown is the original's
landing and ground phase, moved by where the flight now ends.  ``Tn`` is always
chosen so that the COM comes down to the original's touchdown height: the
landing pose then meets the ground (only the horizontal landing point may move),
and the velocity of the COM changes only at the two contact instants.

========================  =====================================================
kind (options)            the flight
========================  =====================================================
gravity, policy =         ``g' = (1+e)·g``.
  "takeoff-velocity"      v stays (angle too); Tn from the landing height; apex
                          height ×1/(1+e), landing distance ×Tn/T, |L| ×T/Tn.
  "apex-height"           the same path in space traversed ``√(1+e)`` times
                          faster: apex, landing point and angle stay; v
                          ×√(1+e), Tn = T/√(1+e), |L| ×√(1+e).  (It *is* the
                          flight played at √(1+e) speed.)
  "flight-time"           Tn = T: |L|, horizontal velocity and landing point
                          stay; the vertical take-off velocity is what makes the
                          COM land in T under g'; apex and angle change.
horizontal-velocity       horizontal take-off velocity ×(1+e); vertical
                          velocity, Tn, apex and |L| stay; landing moves by e·v_h·T.
vertical-velocity         vertical take-off velocity ×(1+e), g stays; Tn from
                          the landing height, apex ×(1+e)², landing distance
                          ×Tn/T, |L| ×T/Tn.
acceleration, axis =      a constant added acceleration of e·9.81 m/s² in the air,
  "horizontal"            along the horizontal travel at take-off (e < 0: a
                          deceleration); v, Tn, apex and |L| stay; landing moves by
                          ½·e·9.81·T² (a velocity change at touchdown).
  "vertical"              along the take-off's vertical travel: up (e < 0: down),
                          so gravity in the air is ``g − e·9.81``; v stays; Tn, apex,
                          landing distance and |L| as for gravity "takeoff-velocity".
time-scale, span =        played at k = 1+e speed:
  "flight"                the airborne span only: the same path in space, v ×k,
                          g ×k², Tn = T/k, |L| ×k; the ground phases unchanged.
  "whole"                 the whole clip resampled at k× its times (every
                          velocity ×k, no extra change at a contact; fewer or more
                          frames at the same fps).
pose-rate                 the pose shown at frame time t is the original's at
                          ⌊t·N⌋/N: N poses per second on the same video frame
                          rate; nothing else changes (the held poses lie on the
                          original's parabola).  The level is N.
========================  =====================================================
"""

from __future__ import annotations

import numpy as np

from .analyse import Analysis
from .edit.timing import sample
from flipstudy.errors import FlipstudyValueError, StimulusError
from .injection import Injected, _inside, _need_flight
from .motion.clip import Clip, derived_meta
from .physics import center_of_mass
from flipstudy.vocab import kinds

#: the standard gravity that ``acceleration`` levels are fractions of, m/s²
G0 = 9.81

GRAVITY_POLICIES = kinds.GRAVITY.option[2]
AXES = kinds.get("acceleration").option[2]
SPANS = kinds.get("time-scale").option[2]
#: design level bounds in percent by (kind, sign): (largest magnitude, is it excluded),
#: of this module's kinds (declared in the registry, :mod:`flipstudy.vocab.kinds`)
BALLISTIC_LEVEL_BOUNDS = {ks: b for ks, b in kinds.level_bounds().items()
                          if kinds.get(ks[0]).family == "ballistic"}
#: the design option (a group key) each kind takes and its values (the default, or
#: None when the key must be given)
KIND_OPTIONS = kinds.kind_options()
#: the longest flight a stimulus may have, seconds: human flights (jumps, flips,
#: trampolines, ski jumps) last well under this; a level whose flight would be longer
#: (a gravity or vertical acceleration that nearly cancels the fall) is refused before
#: anything is built (its stimulus would hold minutes of frames)
MAX_FLIGHT_S = 10.0
#: the longest stimulus, seconds (a time-scale "whole" slows the whole clip down)
MAX_CLIP_S = 120.0
#: kinds this module makes, and the group option each one takes (None: none)
BALLISTIC_KINDS = {k.name: (k.option[0] if k.option else None) for k in kinds.study_kinds()
                   if k.family == "ballistic"}


def _flight(a: Analysis):
    """Take-off instant, touchdown instant, the fitted path's COM at both, the
    take-off velocity and the original's own gravity (m/s², from its parabola)."""
    _need_flight(a)
    t_to, t_ld = a.takeoff_time, a.landing_time
    c0 = a.path_at(np.array([t_to]))[0]
    c1 = a.path_at(np.array([t_ld]))[0]
    return t_to, t_ld, c0, c1, a.takeoff_velocity, float(a.apparent_gravity)


def _horizontal_unit(v: np.ndarray, name: str) -> np.ndarray:
    h = np.array([v[0], 0.0, v[2]])
    n = np.linalg.norm(h)
    if n < 1e-6:
        raise StimulusError(f"{name}: the jump has no horizontal velocity, so a horizontal error "
                            f"along its direction is undefined")
    return h / n


def _landing_time(vy: float, g: float, dy: float, what: str) -> float:
    """Seconds until a COM leaving at ``vy`` under ``g`` comes down to ``dy``
    above its take-off height (the later root)."""
    disc = vy * vy - 2.0 * g * dy
    if g <= 0 or disc < 0 or vy + np.sqrt(max(disc, 0.0)) <= 0:
        raise StimulusError(f"{what}: the COM would not come down to the landing height "
                            f"(vertical take-off velocity {vy:.3f} m/s, gravity {g:.3f} m/s², landing "
                            f"{dy:+.3f} m from the take-off height)")
    return float((vy + np.sqrt(disc)) / g)


def planned_flight(a: Analysis, kind: str, error: float, option: str | None = None,
                   rate: float | None = None) -> tuple[float, float]:
    """(flight seconds, stimulus seconds) of what :func:`inject_kind` makes, in closed
    form from the original's take-off velocity, gravity and landing height (nothing
    is built); raises :class:`StimulusError` when the COM would never come down.

    >>> from flipstudy import analyse, builtin
    >>> a = analyse(builtin("backflip"))
    >>> Tn, _ = planned_flight(a, "acceleration", 0.9999, "vertical")   # g nearly cancelled
    >>> Tn > 1000 * a.flight_s
    True
    """
    t_to, t_ld, c0, c1, v0, g = _flight(a)
    T, dy, vy = t_ld - t_to, c1[1] - c0[1], float(v0[1])
    clip_s = (a.clip.num_frames - 1) / a.clip.fps
    what = f"{kind} {rate:g} poses/s" if kind == "pose-rate" else f"{kind} {error:+.4g}"
    if kind == "gravity":
        gn = (1.0 + error) * g
        Tn = _landing_time(vy, gn, dy, what) if option == "takeoff-velocity" else \
            T / np.sqrt(1.0 + error) if option == "apex-height" else T
    elif kind == "vertical-velocity":
        Tn = _landing_time(vy * (1.0 + error), g, dy, what)
    elif kind == "acceleration" and option == "vertical":
        Tn = _landing_time(vy, g - error * G0, dy, what)
    elif kind == "time-scale":
        Tn = T / (1.0 + error)
        if option == "whole":
            return float(Tn), float(clip_s / (1.0 + error))
    else:                          # horizontal velocity or acceleration, pose rate: T stays
        Tn = T
    return float(Tn), float(clip_s - T + Tn)


def flight_problem(a: Analysis, kind: str, error: float, option: str | None = None,
                   rate: float | None = None) -> str | None:
    """Why the stimulus of this level cannot be made (its flight would not land within
    :data:`MAX_FLIGHT_S`, the stimulus would last longer than :data:`MAX_CLIP_S`, no
    pose of a pose rate falls inside the flight), or None."""
    try:
        Tn, total = planned_flight(a, kind, error, option, rate)
    except StimulusError as e:
        return str(e)
    if kind == "pose-rate":
        ts = held_times(a.clip.num_frames, a.clip.fps, rate)
        if not np.any((ts > a.takeoff_time) & (ts < a.landing_time)):
            return (f"at {rate:g} poses per second no pose is shown inside the "
                    f"{a.flight_s:.3f} s flight (a pose every {1 / rate:.3g} s)")
        return None
    v0, g = a.takeoff_velocity, float(a.apparent_gravity)
    if not Tn <= MAX_FLIGHT_S:
        return (f"the flight would last {Tn:.4g} s (take-off velocity {v0[1]:.3f} m/s up, "
                f"original flight {a.flight_s:.3f} s under {g:.3f} m/s²); a flight must land "
                f"within {MAX_FLIGHT_S:g} s")
    if not total <= MAX_CLIP_S:
        return f"the stimulus would last {total:.4g} s; at most {MAX_CLIP_S:g} s"
    return None


def check_design_flights(design, analyses: dict) -> None:
    """Refuse, before anything is built, a design level whose stimulus cannot be made
    from a base clip (:func:`flight_problem`: e.g. a flight that would not land within
    :data:`MAX_FLIGHT_S`): a :class:`~flipstudy.stimuli.design.DesignError` naming the
    design file, group, level and clip.  ``analyses``: clip name → its Analysis."""
    from ._designkeys import DesignError
    src = design.path if design.path is not None else "<design>"
    for i, g in enumerate(design.groups):
        if g.kind not in BALLISTIC_KINDS:
            continue
        for name, a in analyses.items():
            if a.flight is None:
                continue
            for level in g.levels:
                if level == 0:
                    continue
                if g.kind == "pose-rate" and not level < a.clip.fps:
                    problem = (f"a pose rate must be below the clip's {a.clip.fps:g} frames "
                               f"per second")
                else:
                    problem = flight_problem(a, g.kind, g.sign * level / 100.0,
                                             g.policy or g.axis or g.span, rate=level)
                if problem:
                    raise DesignError(f"{src}: groups[{i}] ({g.name}).levels: {level:g} "
                                      f"{'poses per second' if g.kind == 'pose-rate' else '%'} "
                                      f"on clip '{name}': {problem}")


def _meta(clip: Clip, tag: str, gravity_changed: bool) -> dict:
    meta = derived_meta(clip.meta, tag)
    if gravity_changed and "g" in meta:        # the source's gravity is no longer the flight's
        meta.setdefault("source_facts", {})["g"] = meta.pop("g")
    return meta


def rebuild_flight(a: Analysis, Tn: float, v: np.ndarray, acc: np.ndarray, tag: str) -> tuple:
    """The original with its airborne span replaced: relative motion retimed
    uniformly into ``Tn`` seconds, COM on ``c0 + v τ + ½ acc τ²``, the landing and
    after moved by the new end of the flight.  Returns (clip, first frame, last
    frame strictly inside, touchdown instant)."""
    clip, fps = a.clip, a.clip.fps
    t_to, t_ld, c0, c1, _, _ = _flight(a)
    T = t_ld - t_to
    if Tn == T:                                  # rate 1: the source frames as they are
        new, n_new = clip, clip.num_frames
        tau = np.arange(n_new) / fps - t_to
    else:
        t_end = (clip.num_frames - 1) / fps
        n_new = int(np.floor((t_end - T + Tn) * fps + 1e-9)) + 1
        t = np.arange(n_new) / fps
        tau = t - t_to
        src_t = np.where(tau <= Tn, t_to + tau * (T / Tn), t_ld + (tau - Tn))
        src = np.where(tau <= 0, np.arange(n_new, dtype=float), src_t * fps)
        new = sample(clip, src)
    t_ld_new = t_to + Tn
    to, ld = _inside(t_to, t_ld_new, fps)
    com = center_of_mass(new, a.body)
    shift = np.zeros_like(new.root_pos)
    fr = slice(to, ld + 1)
    tt = tau[fr, None]
    shift[fr] = c0 + v * tt + 0.5 * acc * tt ** 2 - com[fr]
    end = c0 + v * Tn + 0.5 * acc * Tn ** 2
    shift[ld + 1:] = end - c1
    out = new.replace(root_pos=new.root_pos + shift,
                      meta=_meta(clip, tag, not np.allclose(acc, [0.0, -2.0 * a.path[1, 0], 0.0])))
    return out, to, ld, float(t_ld_new)


def _inj(a, clip, kind, error, to, ld, Tn, t_ld_new, acc, **opts) -> Injected:
    return Injected(clip, kind, None, float(error), to, ld, None, float(Tn), float(a.takeoff_time),
                    float(t_ld_new), opts=dict(opts), air_acc=np.asarray(acc, float))


def inject_gravity(a: Analysis, error: float, policy: str) -> Injected:
    """The flight under ``g' = (1 + error)·g`` (``g`` the original's own); what
    stays is ``policy`` (see the module's table).

    Examples
    --------
    >>> from flipstudy import analyse, builtin
    >>> a = analyse(builtin("jump"))
    >>> s = inject_gravity(a, -0.2, "flight-time")
    >>> round(s.flight_s / a.flight_s, 6), round(float(-s.air_acc[1] / a.apparent_gravity), 6)
    (1.0, 0.8)
    """
    if policy not in GRAVITY_POLICIES:
        raise FlipstudyValueError(f"policy must be one of {GRAVITY_POLICIES}, got {policy!r}")
    if not (-1.0 < error <= 10.0):
        raise StimulusError(f"gravity error {error!r} out of range (-1, 10]")
    t_to, t_ld, c0, c1, v0, g = _flight(a)
    T, dy, gn = t_ld - t_to, c1[1] - c0[1], (1.0 + error) * g
    v = v0.copy()
    if policy == "takeoff-velocity":
        Tn = _landing_time(v0[1], gn, dy, f"gravity {error:+.3f} keeping the take-off velocity")
    elif policy == "apex-height":
        s = np.sqrt(1.0 + error)
        v, Tn = v0 * s, T / s
    else:
        Tn = T
        v[1] = (dy + 0.5 * gn * T * T) / T
    acc = np.array([0.0, -gn, 0.0])
    clip, to, ld, t1 = rebuild_flight(a, Tn, v, acc, f"gravity {policy} {error:+.3f}")
    return _inj(a, clip, "gravity", error, to, ld, Tn, t1, acc, policy=policy)


def inject_velocity(a: Analysis, error: float, component: str) -> Injected:
    """The take-off velocity's ``component`` ("horizontal" or "vertical") times
    ``1 + error``; gravity stays (see the module's table)."""
    t_to, t_ld, c0, c1, v0, g = _flight(a)
    T, dy = t_ld - t_to, c1[1] - c0[1]
    v = v0.copy()
    if component == "horizontal":
        if not (-1.0 < error <= 10.0):
            raise StimulusError(f"horizontal-velocity error {error!r} out of range (-1, 10]")
        _horizontal_unit(v0, a.clip.meta.get("name", "clip"))
        v[[0, 2]] *= 1.0 + error
        Tn = T
    elif component == "vertical":
        if not (-1.0 < error <= 10.0) or v0[1] <= 0:
            raise StimulusError(f"vertical-velocity error {error!r} out of range (-1, 10], or the "
                                f"take-off is not upwards ({v0[1]:.3f} m/s)")
        v[1] *= 1.0 + error
        Tn = _landing_time(v[1], g, dy, f"vertical-velocity {error:+.3f}")
    else:
        raise FlipstudyValueError(f"component must be 'horizontal' or 'vertical', got {component!r}")
    acc = np.array([0.0, -g, 0.0])
    kind = f"{component}-velocity"
    clip, to, ld, t1 = rebuild_flight(a, Tn, v, acc, f"{kind} {error:+.3f}")
    return _inj(a, clip, kind, error, to, ld, Tn, t1, acc)


def inject_acceleration(a: Analysis, error: float, axis: str) -> Injected:
    """A constant added acceleration of ``error``·9.81 m/s² in the air along
    ``axis`` ("horizontal": the horizontal travel at take-off; "vertical": up);
    a negative error is a deceleration.  The take-off velocity stays."""
    if axis not in AXES:
        raise FlipstudyValueError(f"axis must be one of {AXES}, got {axis!r}")
    t_to, t_ld, c0, c1, v0, g = _flight(a)
    T, dy = t_ld - t_to, c1[1] - c0[1]
    if not (-1.0 < error < 1.0):
        raise StimulusError(f"acceleration error {error!r} out of range (-1, 1) (fractions of g)")
    acc = np.array([0.0, -g, 0.0])
    if axis == "horizontal":
        acc = acc + error * G0 * _horizontal_unit(v0, a.clip.meta.get("name", "clip"))
        Tn = T
    else:
        acc[1] += error * G0
        Tn = _landing_time(v0[1], -acc[1], dy, f"vertical acceleration {error:+.3f} g")
    clip, to, ld, t1 = rebuild_flight(a, Tn, v0, acc, f"acceleration {axis} {error:+.3f}")
    return _inj(a, clip, "acceleration", error, to, ld, Tn, t1, acc, axis=axis)


def inject_time_scale(a: Analysis, error: float, span: str = "flight") -> Injected:
    """The flight (``span = "flight"``) or the whole clip (``"whole"``) played at
    ``1 + error`` speed at the same frame rate.

    Examples
    --------
    >>> from flipstudy import analyse, builtin
    >>> a = analyse(builtin("backflip"))
    >>> s = inject_time_scale(a, 0.25, "whole")
    >>> round(s.flight_s / a.flight_s, 6), s.clip.num_frames < a.clip.num_frames
    (0.8, True)
    """
    if span not in SPANS:
        raise FlipstudyValueError(f"span must be one of {SPANS}, got {span!r}")
    if not (-1.0 < error <= 10.0):
        raise StimulusError(f"time-scale error {error!r} out of range (-1, 10]")
    t_to, t_ld, c0, c1, v0, g = _flight(a)
    k, T = 1.0 + error, t_ld - t_to
    acc = np.array([0.0, -g * k * k, 0.0])
    tag = f"time-scale {span} {error:+.3f}"
    if span == "flight":
        clip, to, ld, t1 = rebuild_flight(a, T / k, v0 * k, acc, tag)
        return _inj(a, clip, "time-scale", error, to, ld, T / k, t1, acc, span=span)
    src, fps = a.clip, a.clip.fps
    n_new = int(np.floor((src.num_frames - 1) / k + 1e-9)) + 1
    new = sample(src, np.arange(n_new) * k)
    t0n, t1n = t_to / k, t_ld / k
    to, ld = _inside(t0n, t1n, fps)
    fr = slice(to, ld + 1)
    tt = (np.arange(n_new)[fr] / fps - t0n)[:, None]
    shift = np.zeros_like(new.root_pos)
    shift[fr] = c0 + v0 * k * tt + 0.5 * acc * tt ** 2 - center_of_mass(new, a.body)[fr]
    clip = new.replace(root_pos=new.root_pos + shift, meta=_meta(src, tag, True))
    out = Injected(clip, "time-scale", None, float(error), to, ld, None, T / k, float(t0n), float(t1n),
                   opts={"span": span}, air_acc=acc)
    return out


def held_times(n_frames: int, fps: float, rate: float) -> np.ndarray:
    """(F,) the source time shown at each frame when poses update ``rate`` times a
    second: ⌊t·rate⌋ / rate.

    >>> held_times(6, 120.0, 40.0) * 120
    array([0., 0., 0., 3., 3., 3.])
    """
    return held_frames(n_frames, fps, rate) / fps


def held_frames(n_frames: int, fps: float, rate: float) -> np.ndarray:
    """(F,) the source frame (fractional) shown at each frame: update j = ⌊k·rate/fps⌋
    is source frame j·fps/rate (a whole frame when the rate divides fps)."""
    j = np.floor(np.arange(n_frames) * (rate / fps) + 1e-9)
    return j * (fps / rate)


def inject_pose_rate(a: Analysis, rate: float) -> Injected:
    """The clip with its poses updated ``rate`` times a second (each held for
    1/rate s) at the same video frame rate.  Inside the airborne span the held
    poses' COM lies exactly on the original's parabola at their own instants.
    The Injected's instants are the display times of the first airborne and the
    first landed pose; ``error`` is ``rate / fps − 1``."""
    clip, fps = a.clip, a.clip.fps
    if not (0 < rate < fps):
        raise StimulusError(f"pose-rate {rate!r} poses per second: expected more than 0 and fewer "
                            f"than the clip's {fps:g} frames per second")
    t_to, t_ld, c0, c1, v0, g = _flight(a)
    src = held_frames(clip.num_frames, fps, rate)
    ts = src / fps
    new = sample(clip, src)
    air = (ts > t_to) & (ts < t_ld)
    shift = np.zeros_like(new.root_pos)
    shift[air] = a.path_at(ts[air]) - center_of_mass(new, a.body)[air]
    out = new.replace(root_pos=new.root_pos + shift, meta=_meta(clip, f"pose-rate {rate:g}", False))
    idx = np.flatnonzero(air)
    j_air = np.floor(t_to * rate + 1e-9) + 1            # first pose update after take-off
    j_land = np.ceil(t_ld * rate - 1e-9)                 # first update at or after touchdown
    return Injected(out, "pose-rate", None, rate / fps - 1.0, int(idx[0]), int(idx[-1]), None,
                    float((j_land - j_air) / rate), float(j_air / rate), float(j_land / rate),
                    opts={"rate": float(rate)}, air_acc=np.array([0.0, -g, 0.0]))


def inject_kind(a: Analysis, kind: str, error: float, option: str | None = None,
                rate: float | None = None) -> Injected:
    """One of :data:`BALLISTIC_KINDS`: ``error`` a fraction (``rate`` in poses per
    second for pose-rate), ``option`` the group's policy, axis or span.  A level
    whose flight would not land within :data:`MAX_FLIGHT_S` (see
    :func:`flight_problem`) raises :class:`StimulusError` before anything is built."""
    if kind == "pose-rate":                 # the level is the rate; ``error`` is not used
        checkable = rate is not None and 0 < rate < a.clip.fps
    else:
        checkable = kind in BALLISTIC_KINDS and error is not None and error > -1.0
    if checkable:
        problem = flight_problem(a, kind, error, option, rate)
        if problem:
            raise StimulusError(problem)
    if kind == "gravity":
        return inject_gravity(a, error, option)
    if kind in ("horizontal-velocity", "vertical-velocity"):
        return inject_velocity(a, error, kind.split("-")[0])
    if kind == "acceleration":
        return inject_acceleration(a, error, option)
    if kind == "time-scale":
        return inject_time_scale(a, error, option or "flight")
    if kind == "pose-rate":
        return inject_pose_rate(a, rate)
    raise FlipstudyValueError(f"kind must be one of {list(BALLISTIC_KINDS)}, got {kind!r}")
