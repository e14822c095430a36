"""Every physical inconsistency of one motion, measured in the unit of the study
kind that injects it, so that a study's fitted psychometric function applies to
the number directly.

``measure(clip)`` needs nothing but the motion: the analyser
(:func:`flipstudy.stimuli.analyse.analyse`, by default without the mass fit:
a fit of the masses to the very flight being judged could absorb part of its
errors; on the built-ins' angular-momentum stimuli it changes no reading) finds the ballistic phases and their contact instants; between them
lie the ground phases (``ground 0`` before the first flight, ``ground i`` after
flight ``i``).  What is measured, and the sign of each size:

=======================  ==========  ====================================================
kind (variant)           unit        measured as
=======================  ==========  ====================================================
**in flight i** (phase ``flight i``; COM: a free quadratic in every axis fitted to
the frames strictly inside the flight, no gravity assumed)
gravity                  % of 9.81   apparent gravity / 9.81 − 1 (the injector's
                                     ``gravity`` kind: e·g of the original)
acceleration             % of 9.81   horizontal: the in-air horizontal acceleration
  (horizontal)                       along the flight's horizontal travel (negative:
                                     a deceleration); / 9.81
acceleration (vertical)  % of 9.81   up is positive: −(gravity); the *same* departure
                                     as ``gravity`` (``same_as``), not another one
time-scale               %           √(apparent gravity / 9.81) − 1: the playback rate
                                     the parabola shows (``same_as`` gravity)
angular-momentum         %           |L| over the flight fitted with a line and a step
  (smooth / abrupt)                  (:func:`split_trend_step`): smooth = the line's
                                     change from take-off to touchdown, abrupt = the
                                     step, each / |L| just before it (FwP's smooth
                                     and abrupt injections)
air-jolt                 m/s         the largest velocity step of the COM in the air
                                     (a hinge added to the parabola)
**at take-off i** (phase ``takeoff i``; the air side: the flight's quadratic at the
contact instant; the ground side: a quadratic through the last ground frames
before it, extrapolated to the instant)
takeoff-angle            %           horizontal COM speed along the push-off's
                                     direction, air / ground − 1 (FwP's take-off
                                     error: a % change of the horizontal velocity)
horizontal-velocity      %           the same number (``same_as`` takeoff-angle)
vertical-velocity        %           vertical COM velocity, air / ground − 1
takeoff-velocity-jump    m/s         |v_air − v_ground|
**at landing i** (phase ``landing i``; the same, the ground side after the instant)
landing-velocity-jump    m/s, %      "" |Δv| in m/s; "horizontal", "vertical": the
                                     component's air / ground − 1 in %
**whole clip** (phase ``clip``)
pose-rate                poses/s     N when the poses update N < fps times a second
                                     (held frames), else 0 (the design's level 0)
**on the ground i** (phase ``ground i``; the feet's and hands' points as the
analyser follows them, each against its own contact level)
foot-skate               mm          largest horizontal extent a foot point covers
                                     while it stays within 2 cm of its contact level
penetration              mm          deepest any point goes below its contact level
floating                 mm          largest height of the lowest point above its
                                     contact level while the COM is held up (not
                                     falling freely: a hop is not floating)
=======================  ==========  ====================================================

Items that are the same physical departure in another kind's unit carry
``same_as`` (the kind they repeat): a combination of probabilities must count
them once.

Published thresholds (for a calibration to cite; none is used here): foot
sliding was studied perceptually by Pražák, Hoyet & O'Sullivan (2011,
"Perceptual evaluation of footskate cleanup", SCA); their thresholds are not
reproduced here because the paper is not among the project's sources.  For
penetration and floating no perceptual threshold is known to this module.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from .analyse import Analysis, analyse
from .ballistic import G0
from .ballistic_measure import fit_free, pose_updates
from .flight import contact_mask, effector_points, foot_points
from .measure_fits import _ground_fit, _ground_velocity, _quad, split_trend_step, velocity_jolt  # noqa: F401
from .motion.clip import Clip
from flipstudy.vocab import kinds

#: frames of a ground phase through which a quadratic gives its velocity at a contact
#: instant (the last three before take-off, the first three after touchdown: on the
#: built-ins, whose push ends at free fall with zero jerk and whose landing brakes
#: along a cubic, this is within 0.2 % of the exact velocity at 120 fps, 1.3 % at
#: 60 fps, 6.6 % at 30 fps; more frames average a capture's noise but bend toward
#: the push's mean acceleration.  A cubic ending at free fall (the ground force
#: fading at toe-off) reads the built-ins at 30 fps within 1.1 %, but on the CMU
#: captures, whose COM leaves the parabola over the flight's first frames, it reads
#: 88_01's take-off as +76 % where the quadratic reads +19 %: not used)
GROUND_FRAMES = 3
#: a component slower than this (m/s) has no meaningful % change (a vertical jump's
#: horizontal velocity): its % items are left out with a warning
MIN_SPEED = 0.05
#: ground frames within this (m, for a 1.7 m body; or 3 RMS of the flight's own fit) of the
#: flight's parabola are the flight's, at most EXTEND_S seconds beside the contact
#: instant (on exact synthetic data the push's last frame leaves the parabola by
#: 8 µm, a velocity changed at the instant by millimetres)
ON_PATH = 3e-6
EXTEND_S = 0.05
#: an instant within this many frames of the nearest frame on the parabola is at that
#: frame (the frame is both sides'): where the two sides' positions meet is known to
#: about a tenth of a frame for a velocity change of 0.3 m/s
AT_FRAME = 0.25
#: the percentile of a point's heights in contact that is its contact level (the floor; the
#: analyser's resting-level convention): a penetration lasting longer than this share of
#: a point's contact time lowers its level and reads less deep
LEVEL_PCT = 5
#: half-width (s) of the COM's second difference that tells a held body from a falling one
HOLD_S = 0.033
#: |L| below this (kg·m²/s for a 70 kg body) is too small for its % changes to mean much
SMALL_L = 10.0
#: a foot point is on the floor while within this (m, for a 1.7 m body) of its contact level
SKATE_TOUCH = 0.02

#: kind -> the unit of its measured sizes (the registry's, :mod:`flipstudy.vocab.kinds`)
UNITS = kinds.measured_units()


@dataclass(frozen=True)
class Inconsistency:
    """One physical inconsistency of a motion.

    ``kind``: the study kind that injects it (a kind of the registry, :mod:`flipstudy.vocab.kinds`)
    or one of the extra kinds; ``variant``: "smooth"/"abrupt" (angular momentum),
    "horizontal"/"vertical" (acceleration, landing components), else "";
    ``phase``: "flight 1", "takeoff 1", "landing 1", "ground 0", "clip";
    ``size``: signed, in ``unit``; ``t0``, ``t1``: the span it concerns and
    ``worst_t`` its worst moment (seconds); ``same_as``: the kind whose item this
    one repeats in another unit ("" when it is its own)."""

    kind: str
    variant: str
    phase: str
    size: float
    unit: str
    t0: float
    t1: float
    worst_t: float
    same_as: str = ""


@dataclass(frozen=True)
class Measurement:
    """What :func:`measure` found in one clip: its phases ``(name, "ground"/"flight",
    t0, t1)`` (seconds, contact instants as the analyser finds them), the
    inconsistencies and the warnings."""

    name: str
    fps: float
    duration: float
    phases: tuple
    items: tuple = field(default_factory=tuple)
    warnings: tuple = field(default_factory=tuple)

    def get(self, kind: str, variant: str = "", phase: str | None = None) -> list[Inconsistency]:
        """The items of ``kind`` and ``variant`` (in ``phase``, when given)."""
        return [i for i in self.items if i.kind == kind and i.variant == variant
                and (phase is None or i.phase == phase)]

    def to_dict(self) -> dict:
        return {"name": self.name, "fps": self.fps, "duration": self.duration,
                "phases": [{"name": p[0], "kind": p[1], "t0": p[2], "t1": p[3]} for p in self.phases],
                "items": [asdict(i) for i in self.items], "warnings": list(self.warnings)}

    @classmethod
    def from_dict(cls, d: dict) -> "Measurement":
        """The inverse of :meth:`to_dict` (a JSON file read back).

        >>> from flipstudy import builtin
        >>> m = measure(builtin("jump"))
        >>> Measurement.from_dict(m.to_dict()) == m
        True
        """
        return cls(str(d["name"]), float(d["fps"]), float(d["duration"]),
                   tuple((p["name"], p["kind"], float(p["t0"]), float(p["t1"])) for p in d["phases"]),
                   tuple(Inconsistency(**i) for i in d["items"]), tuple(d["warnings"]))

    def table(self):
        """The items as a pandas DataFrame (one row each)."""
        import pandas as pd
        return pd.DataFrame([asdict(i) for i in self.items],
                            columns=[f for f in Inconsistency.__dataclass_fields__])


# ------------------------------------------------------------------ measure
def _pct(a: float, b: float) -> float:
    return 100.0 * (a / b - 1.0)


def measure(clip: Clip, analysis: Analysis | None = None) -> Measurement:
    """Every physical inconsistency of ``clip`` (see the module's table).

    ``analysis``: the clip's own analysis, when already made (its body is used;
    default :func:`analyse` with the table masses, ``estimate=False``).

    Examples
    --------
    >>> from flipstudy import builtin
    >>> m = measure(builtin("backflip"))
    >>> [p[0] for p in m.phases]
    ['ground 0', 'flight 1', 'ground 1']
    >>> abs(m.get("gravity", phase="flight 1")[0].size) < 0.01      # exact free fall
    True
    """
    frames, rate, u0 = pose_updates(clip)
    if np.isfinite(rate) and rate < 0.95 * clip.fps and frames.size >= 10:
        return _held(clip, frames, rate, u0)
    a = analysis if analysis is not None else analyse(clip, estimate=False)
    clip = a.clip
    fps = float(clip.fps)
    F = clip.num_frames
    dur = (F - 1) / fps
    name = str(clip.meta.get("name", "clip"))
    warnings = list(a.warnings)
    if fps < 60:
        warnings.append(f"{fps:g} frames per second: the take-off, landing and |L| items are "
                        f"finite differences over coarse frames (the built-in backflip at 30 fps "
                        f"reads up to 7 % where it has none)")
    items: list[Inconsistency] = []
    flights = sorted(a.flights, key=lambda f: f.takeoff)
    com, Ln = a.com, np.linalg.norm(a.L, axis=1)
    frame_t = np.arange(F) / fps
    from .flight import body_size
    size = body_size(clip) / 1.7

    # phases
    phases, edges = [], [0.0]
    for f in flights:
        edges += [float(f.takeoff_time), float(f.landing_time)]
    edges.append(dur)
    for i in range(len(flights) + 1):
        t0, t1 = max(0.0, edges[2 * i]), min(dur, edges[2 * i + 1])
        if t1 > t0:
            phases.append((f"ground {i}", "ground", t0, t1))
        if i < len(flights):
            phases.append((f"flight {i + 1}", "flight", edges[2 * i + 1], edges[2 * i + 2]))
    phases.sort(key=lambda p: p[2])

    def add(kind, variant, phase, size, t0, t1, worst, same_as=""):
        unit = "%" if kind == "landing-velocity-jump" and variant else kinds.get(kind).unit
        items.append(Inconsistency(kind, variant, phase, float(size), unit, float(t0),
                                   float(t1), float(worst), same_as))

    for i, f in enumerate(flights, 1):
        ph = f"flight {i}"
        t_to, t_ld = float(f.takeoff_time), float(f.landing_time)
        fr = np.arange(f.takeoff, f.landing + 1)
        t = frame_t[fr]
        if fr.size < 5:
            warnings.append(f"{ph}: {fr.size} frames in the air, too few to measure")
            continue
        cf = fit_free(com[fr], t)
        acc = 2.0 * cf[:, 0]
        g = -acc[1]
        v_air = lambda s: 2.0 * cf[:, 0] * s + cf[:, 1]         # noqa: E731
        mid = 0.5 * (t_to + t_ld)
        add("gravity", "", ph, _pct(g, G0), t_to, t_ld, mid)
        add("acceleration", "vertical", ph, -_pct(g, G0), t_to, t_ld, mid, "gravity")
        if g > 0:
            add("time-scale", "", ph, 100.0 * (np.sqrt(g / G0) - 1.0), t_to, t_ld, mid, "gravity")
        vh = v_air(t_to)[[0, 2]]
        ah = acc[[0, 2]]
        if np.linalg.norm(vh) > MIN_SPEED:
            along = float(ah @ vh / np.linalg.norm(vh))
        else:
            along = float(np.linalg.norm(ah))
            warnings.append(f"{ph}: no horizontal travel at take-off; the horizontal acceleration "
                            f"is given as a magnitude")
        add("acceleration", "horizontal", ph, 100.0 * along / G0, t_to, t_ld, mid)

        inst = _contacts(add, warnings, com, frame_t, fps, fr, t, cf, size, flights, i, t_to, t_ld, v_air)

        # |L| over the flight, from the instants where the COM joins and leaves its parabola
        t0_, t1_ = inst.get(-1, t_to), inst.get(1, t_ld)
        smooth, step, t_step, L0 = split_trend_step(t - t0_, Ln[fr], t1_ - t0_)
        if L0 < SMALL_L * clip_mass(a) / 70.0:
            warnings.append(f"{ph}: |L| is {L0:.1f} kg·m²/s, small (a flip's is 25-50): its "
                            f"changes in % are large for small absolute changes")
        add(kinds.AM.name, "smooth", ph, smooth, t_to, t_ld, t_ld)
        add(kinds.AM.name, "abrupt", ph, step, t_to, t_ld,
            t0_ + t_step if np.isfinite(t_step) else mid)
        jolt, t_j = velocity_jolt(t, com[fr])
        add("air-jolt", "", ph, jolt, t_to, t_ld, t_j)

    add("pose-rate", "", "clip", 0.0, 0.0, dur, 0.0)

    _ground(add, warnings, clip, a, phases, fps)
    _registered(add, clip, a)
    return Measurement(name, fps, float(dur), tuple(phases), tuple(items), tuple(warnings))


def _contacts(add, warnings, com, frame_t, fps, fr, t, cf, size, flights, i, t_to, t_ld, v_air) -> dict:
    """The take-off and landing items of flight ``i`` (1-based; ``fr``, ``t``: its
    frames and their times, ``cf``: its fitted parabola, ``v_air``: its velocity) and
    the instants where the COM joins and leaves the parabola, ``{-1: take-off, 1: landing}``."""
    # contacts: the ground phase before (after) against the flight.  Frames beside the
    # flight that still lie on its parabola are the flight's (a stimulus whose feet stay
    # at the floor a few frames after its velocity changed): the velocity changes where
    # the COM leaves the parabola, which is where the two sides are compared
    res = com[fr] - _quad(cf, t)
    thr = max(3.0 * float(np.sqrt(np.mean(np.sum(res * res, 1)))), ON_PATH * size)
    prev_end = flights[i - 2].landing_time if i > 1 else -np.inf
    next_start = flights[i].takeoff_time if i < len(flights) else np.inf
    inst = {}
    for p, t_c, side in ((f"takeoff {i}", t_to, -1), (f"landing {i}", t_ld, 1)):
        lim = (frame_t >= prev_end - 1e-9) if side < 0 else (frame_t <= next_start + 1e-9)
        near = (frame_t <= t_c + 1e-9) if side < 0 else (frame_t >= t_c - 1e-9)
        g_fr = np.flatnonzero(lim & near)
        g_fr = g_fr[::-1] if side < 0 else g_fr                  # nearest the contact first
        k = g_fr[:int(round(EXTEND_S * fps))]
        on = np.linalg.norm(com[k] - _quad(cf, frame_t[k]), axis=1) <= thr
        n_on = int(np.argmin(on)) if not on.all() else on.size
        n_on = n_on if n_on > 1 else 0          # the frame at the instant is both sides'
        if n_on:
            if n_on < k.size:                    # where the position meets: the instant
                tt = np.linspace(k[n_on], k[n_on - 1], 41) / fps
                gq = _ground_fit(com, fps, np.sort(g_fr[n_on:][:GROUND_FRAMES]), tt)
                t_c = float(tt[np.argmin(np.linalg.norm(gq - _quad(cf, tt), axis=1))])
                if abs(t_c * fps - k[n_on - 1]) < AT_FRAME:   # at a frame: both sides'
                    t_c, n_on = float(k[n_on - 1] / fps), n_on - 1
            warnings.append(f"{p}: the COM stays on the flight's parabola {n_on} frames into the "
                            f"ground phase the analyser finds; its velocity changes at "
                            f"{t_c:.4f} s, where the sides are compared")
        gf = np.sort(g_fr[n_on:][:GROUND_FRAMES])
        if gf.size < 3:
            warnings.append(f"{p}: fewer than 3 ground frames beside it; not measured")
            continue
        vg, va = _ground_velocity(com, fps, gf, t_c), v_air(t_c)
        if not n_on and np.linalg.norm(va - vg) > 0.05 and g_fr.size:
            # the velocity changes: the instant is where the two sides' positions meet,
            # between the nearest ground frame and the flight's nearest frame
            tt = np.linspace(g_fr[0], g_fr[0] - side, 41) / fps
            gq = _ground_fit(com, fps, gf, tt)
            t_c = float(tt[np.argmin(np.linalg.norm(gq - _quad(cf, tt), axis=1))])
            vg, va = _ground_velocity(com, fps, gf, t_c), v_air(t_c)
        inst[side] = t_c
        add(f"{p.split()[0]}-velocity-jump", "", p, np.linalg.norm(va - vg), t_c, t_c, t_c)
        _components(add, warnings, p, va, vg, t_c, takeoff=side < 0)
    return inst


def _registered(add, clip: Clip, a: Analysis) -> None:
    """The items of the kinds registered with a measure of their own (:mod:`flipstudy.vocab.kinds`)."""
    for entry in kinds.all_kinds():
        extra = entry.measurer()
        if extra is not None:
            extra(clip, a, add)


def clip_mass(a: Analysis) -> float:
    return float(a.body.mass.sum())


def _held(clip: Clip, frames: np.ndarray, rate: float, u0: float) -> Measurement:
    """A clip whose poses are held over several frames: its distinct poses, at the
    instants they appear, measured as a clip at ``rate`` poses per second (a
    velocity differenced across a held pose would be zero, then a jump), plus
    the pose-rate item."""
    from dataclasses import replace
    pc = Clip(clip.skeleton, rate, clip.root_pos[frames], clip.rotations[frames],
              None if clip.joint_pos is None else clip.joint_pos[frames], dict(clip.meta))
    m = measure(pc)
    dur = (clip.num_frames - 1) / clip.fps
    sh = lambda x: x + u0                                           # noqa: E731
    items = tuple(replace(i, t0=sh(i.t0), t1=sh(i.t1), worst_t=sh(i.worst_t)) for i in m.items
                  if i.kind != "pose-rate")
    items += (Inconsistency("pose-rate", "", "clip", float(rate), UNITS["pose-rate"], 0.0, dur, 0.0),)
    phases = tuple((p[0], p[1], sh(p[2]), sh(p[3])) for p in m.phases)
    return Measurement(m.name, float(clip.fps), float(dur), phases, items,
                       (f"poses held: {rate:.4g} new poses per second on {clip.fps:g} frames per "
                        f"second; measured on the distinct poses",) + m.warnings)


def _components(add, warnings, phase, va, vg, t, takeoff: bool):
    """The horizontal (along the ground side's direction) and vertical % changes."""
    hg = vg[[0, 2]]
    nh = np.linalg.norm(hg)
    if takeoff:
        kinds = (("takeoff-angle", ""), ("vertical-velocity", ""))
    else:
        kinds = (("landing-velocity-jump", "horizontal"), ("landing-velocity-jump", "vertical"))
    if nh > MIN_SPEED:
        size = _pct(float(va[[0, 2]] @ hg / nh), nh)
        add(*kinds[0], phase, size, t, t, t)
        if takeoff:
            add("horizontal-velocity", "", phase, size, t, t, t, "takeoff-angle")
    else:
        warnings.append(f"{phase}: horizontal COM speed {nh:.3f} m/s on the ground side, too slow "
                        f"for a % change; its horizontal items are left out")
    if abs(vg[1]) > MIN_SPEED:
        add(*kinds[1], phase, _pct(float(va[1]), float(vg[1])), t, t, t)
    else:
        warnings.append(f"{phase}: vertical COM speed {vg[1]:.3f} m/s on the ground side, too slow "
                        f"for a % change; its vertical item is left out")


def _ground(add, warnings, clip, a, phases, fps):
    """foot-skate, penetration and floating per ground phase (mm)."""
    from .flight import body_size
    size = body_size(clip) / 1.7
    P, names = effector_points(clip, a.body)                   # (F,E,3)
    contact = contact_mask(clip, a.body, v_thr=1.0 * size, margin=0.10 * size, touch=0.03 * size)
    h = P[..., 1]
    # each point's contact level: a low percentile of its heights where the analyser has it in
    # contact (as the analyser's own resting level: a heel raised in contact is not the floor)
    lev = _column_percentile(h, contact, LEVEL_PCT)
    feet = np.array([n.startswith(("toe", "ankle")) for n in names])
    # only points that rest on the floor support the body (a hand hanging still is
    # "in contact" for the analyser's still rule, hundreds of mm up)
    used = np.isfinite(lev)
    if (used & feet).any():
        used &= lev < np.nanmin(np.where(feet, lev, np.nan)) + 0.35 * size
    if not used.any():
        warnings.append("no foot or hand is ever in contact: ground phases not measured")
        return
    feet &= used
    d = h[:, used] - lev[used][None]                            # clearance per point
    low = d.min(axis=1)
    F = h.shape[0]
    t = np.arange(F) / fps
    # a foot point supports while it is on the floor and the lowest of its foot (a heel
    # rising about the ball of the foot moves the ankle forward: a pivot, not a slide)
    dd = h - lev[None]
    side = np.array([n[-1] for n in names])
    foot_min = np.full_like(dd, np.inf)
    for s in ("l", "r"):
        k = feet & (side == s)
        if k.any():
            foot_min[:, k] = dd[:, k].min(axis=1, keepdims=True)
    on = (dd < SKATE_TOUCH * size) & (dd <= foot_min + 0.002 * size) & feet[None]
    # floating: only where something holds the body up (its COM is not falling freely:
    # a second difference over ±HOLD_S seconds above −g/2, the analyser's own rule); a
    # short hop the analyser does not call a flight is not floating
    s_ = max(1, int(round(HOLD_S * fps)))
    ay = np.full(F, np.inf)
    if F > 2 * s_:
        y = a.com[:, 1]
        ay[s_:-s_] = (y[2 * s_:] - 2 * y[s_:-s_] + y[:-2 * s_]) * (fps / s_) ** 2
    held = ay > -G0 / 2
    for name, kind, t0, t1 in phases:
        if kind != "ground":
            continue
        sel = np.flatnonzero((t >= t0 - 1e-9) & (t <= t1 + 1e-9))
        if sel.size == 0:
            continue
        lo = low[sel]
        k = int(np.argmin(lo))
        add("penetration", "", name, 1000.0 * max(0.0, -float(lo[k])), t0, t1, t[sel[k]])
        up = np.where(held[sel], lo, -np.inf)
        k = int(np.argmax(up))
        fl = float(up[k]) if np.isfinite(up[k]) else 0.0
        add("floating", "", name, 1000.0 * max(0.0, fl), t0, t1, t[sel[k]])
        skate, ts = _skate(P[sel][..., [0, 2]], on[sel], t[sel])
        add("foot-skate", "", name, 1000.0 * skate, t0, t1, ts)


def _column_percentile(x: np.ndarray, mask: np.ndarray, q: float) -> np.ndarray:
    """(E,) the ``q``-th percentile (linear) of each column of ``x`` over its ``mask``ed
    rows; NaN for a column without any (``np.nanpercentile`` without its per-column loop).

    >>> x = np.arange(10.0)[:, None] * [1, 2]
    >>> _column_percentile(x, x < 9, 50).tolist()
    [4.0, 4.0]
    """
    n = mask.sum(0)
    srt = np.sort(np.where(mask, x, np.inf), axis=0)
    pos = np.maximum(n - 1, 0) * q / 100.0
    lo = np.floor(pos).astype(int)
    hi = np.minimum(lo + 1, np.maximum(n - 1, 0))
    cols = np.arange(x.shape[1])
    with np.errstate(invalid="ignore"):                   # inf - inf of an empty column
        out = srt[lo, cols] + (pos - lo) * (srt[hi, cols] - srt[lo, cols])
    return np.where(n > 0, out, np.nan)


def _skate(xz: np.ndarray, on: np.ndarray, t: np.ndarray) -> tuple[float, float]:
    """Largest horizontal extent (m) a point covers during one run of ``on`` frames,
    and the time of that run's middle.  ``xz`` (n,E,2), ``on`` (n,E)."""
    n, E = on.shape
    m = np.concatenate([np.zeros((1, E), bool), on, np.zeros((1, E), bool)]).astype(np.int8)
    dm = np.diff(m, axis=0)
    st_e, st_f = np.nonzero(dm.T == 1)
    en_e, en_f = np.nonzero(dm.T == -1)
    if st_f.size == 0:
        return 0.0, float(t[n // 2])
    # runs: point st_e, frames st_f..en_f-1 (np.nonzero on the transpose orders by point)
    flat = xz.transpose(1, 0, 2).reshape(E * n, 2)                # point-major
    starts = st_e * n + st_f
    ends = en_e * n + en_f
    idx = np.stack([starts, ends], 1).ravel()
    hi = np.maximum.reduceat(np.concatenate([flat, flat[-1:]]), idx, axis=0)[::2]
    lo = np.minimum.reduceat(np.concatenate([flat, flat[-1:]]), idx, axis=0)[::2]
    ext = np.linalg.norm(hi - lo, axis=1)
    j = int(np.argmax(ext))
    return float(ext[j]), float(t[(st_f[j] + en_f[j] - 1) // 2])
