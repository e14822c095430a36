"""The concatenation itself (Shum, Komura & Yadav 2009): :func:`concatenate`
chains the steps of :mod:`flipstudy.stimuli.edit.concat` and returns a
:class:`Concatenation` with a :class:`ConcatReport`."""
from __future__ import annotations

import numpy as np

from ...analyse import analyse
from ...body import Body
from ...flight import _runs, detect_flights
from ...motion.clip import Clip, derived_meta
from ...physics import momentum
from ..timing import sample
from .blend import blend, smooth, smoothing_factor
from .feet import pin_feet
from .motion import motion_of, suggest_rule, transformed
from .periods import blendable_periods, support_frames
from flipstudy.errors import ConcatError
from .phases import align_angle
from .result import ConcatReport, Concatenation
from .search import optimal_timing


def concatenate(a: Clip, b: Clip, *, rule: str | None = None, body: Body | None = None,
                tm_a: int | None = None, tm_b: int | None = None,
                main_a: tuple[int, int] | None = None, main_b: tuple[int, int] | None = None,
                max_facing_deg: float = 45.0, max_cost: float | None = None,
                trace_frac: float = 0.35, min_blend_s: float = 0.1, smoothing: str = "profile",
                ease: bool = True, passes: int = 5, tol: float = 0.01, fix_feet: bool = True) -> Concatenation:
    """Join motion ``a`` then motion ``b`` (same skeleton) with the angular
    momentum as the cue (Shum, Komura & Yadav 2009).

    ``rule``: ``"forward"``, ``"reverse"`` or ``None`` (suggested from the data).
    ``max_cost``: refuse when the optimal F exceeds it (default: the square of the
    larger main-phase peak |L|: a mismatch as large as the motion itself).  ``trace_frac``:
    the blend window grows from f_T while ‖ΔL‖ < ``trace_frac`` × peak |L| (the
    paper's "predefined threshold").  ``min_blend_s``: a window shorter than this
    is widened (inside the blendable periods if they allow it), so the blend is
    never a cut.  ``smoothing``, ``passes``, ``tol``: see
    :func:`~flipstudy.stimuli.edit.concat.smooth`; ``fix_feet``: pin the support
    feet (:func:`~flipstudy.stimuli.edit.concat.pin_feet`).

    Returns a :class:`Concatenation`: the clip, its flight (``None`` unless it
    has exactly one; the report's ``flights`` lists them all) and a
    :class:`ConcatReport`.

    Parameters
    ----------
    a, b : Clip
        The two motions, one skeleton.
    rule : {"forward", "reverse"}, optional
    body : Body, optional
    tm_a, tm_b, main_a, main_b : int, tuple of int, optional
        Each motion's frame of largest |L| and main phase (default: found).
    max_facing_deg, max_cost, trace_frac, min_blend_s, tol : float
    smoothing : str
    ease, fix_feet : bool
    passes : int

    Returns
    -------
    Concatenation

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import concatenate
    >>> c = builtin("backflip")
    >>> r = concatenate(c, c)                    # a double backflip
    >>> r.report.rule, len(r.report.flights), r.takeoff
    ('forward', 2, None)
    >>> r.clip.meta["edit"]
    'concatenated'
    """
    if a.skeleton.joint_names != b.skeleton.joint_names:
        raise ConcatError("the two motions must share a skeleton (the same joints, in the same order): "
                          "blending is per joint")
    b, body = _prepared(a, b, body)
    m1 = motion_of(a, body, tm=tm_a, main=main_a)
    m2_raw = motion_of(b, body, tm=tm_b, main=main_b)
    suggested = suggest_rule(m1, m2_raw)
    rule = rule or suggested
    theta, m2r, best, tried = _best_period(m1, m2_raw, rule, body, max_facing_deg)
    peak = max(m1.main_peak, m2_raw.main_peak)
    max_cost = peak ** 2 if max_cost is None else float(max_cost)
    if best is None:
        _refuse(m1, m2_raw, rule, body, max_facing_deg, tried)
    tmg, case, s1, s2, support, allowed = best
    _check_cost(tmg, max_cost)
    T, fT = tmg.T, tmg.fT
    f0, f1, widened, fa = _blend_window(m1, m2r, T, fT, s1, s2, (trace_frac * peak) ** 2,
                                        int(round(min_blend_s * a.fps)))
    # translate motion 2 so the centres of the feet coincide at the first blended frame
    shift = m1.feet_centre[fa] - m2r.feet_centre[fa - T]
    shift[1] = 0.0
    m2 = transformed(m2_raw, theta, shift)
    out, Lb, Ln, ends, s, w1, applied, feet, flights = _blended(
        m1, m2, body, T, (f0, f1), ease=ease, smoothing=smoothing, passes=passes, tol=tol, fix_feet=fix_feet)
    w0 = f0
    report = ConcatReport(
        rule=rule, suggested_rule=suggested, theta_deg=float(np.degrees(theta)),
        phases_a=m1.phases.as_dict(), phases_b=m2_raw.phases.as_dict(),
        case=case, support=support,
        blendable_a=[int(s1[0]), int(s1[-1])], blendable_b=[int(s2[0]), int(s2[-1])],
        T=T, f_T=fT, F=tmg.F, F_dm=tmg.F_dm, F_inertia=tmg.F_inertia,
        F_time=tmg.F_time, threshold=max_cost,
        blend=[f0, f1], blend_widened=widened, smoothing_s=s,
        blend_out=[w0, w1], smoothing=applied,
        L_target_blend=float(0.5 * (ends[0] + ends[1])),
        facing_deg_at_fT=float(np.degrees(np.arccos(np.clip(m1.facing[fT] @ m2.facing[fT - T], -1, 1)))),
        shift_m=[float(x) for x in shift], aligned_at=int(fa),
        L_peak_blend_before=float(Lb[f0:f1 + 1].max()),
        L_peak_blend=float(Ln[w0:w1 + 1].max()),
        L_mean_blend=float(Ln[w0:w1 + 1].mean()),
        L_main_peak_a=m1.main_peak, L_main_peak_b=m2_raw.main_peak,
        frames=out.num_frames, duration_s=out.duration,
        frames_a=a.num_frames, frames_b=b.num_frames,
        feet=feet, flights=flights)
    out = out.replace(meta={**derived_meta(out.meta, "concatenated"),
                            "name": f"{a.meta.get('name', 'a')}+{b.meta.get('name', 'b')}"})
    # the clip's flight where it has one; two flips have two (the report's flights)
    one = flights[0] if len(flights) == 1 else {"takeoff": None, "landing": None}
    return Concatenation(out, one["takeoff"], one["landing"], report)


def _prepared(a: Clip, b: Clip, body):
    """Motion 2 at motion 1's frame rate, and the body (default: motion 1's analysis's)."""
    if abs(a.fps - b.fps) > 1e-9:
        b = sample(b, np.arange(0, b.num_frames - 1 + 1e-9, b.fps / a.fps)).with_fps(a.fps)
    if body is None:
        body = analyse(a).body
    return b, body


def _check_cost(tmg, max_cost: float) -> None:
    """Refuse a blend whose optimal F exceeds ``max_cost``."""
    if tmg.F > max_cost:
        raise ConcatError(f"the motions are too different to blend: F = {tmg.F:.1f} at the best offset "
                          f"exceeds the threshold {max_cost:.1f} (angular momenta {np.sqrt(tmg.F_dm):.1f} "
                          f"kg·m²/s apart at the blending centre)")


def _blended(m1, m2, body, T: int, window: tuple, *, ease: bool, smoothing: str, passes: int, tol: float,
             fix_feet: bool):
    """The two motions blended over ``window``, smoothed (eq. 9) and the feet pinned:
    (clip, |L| of the blend before smoothing, |L| after, |L| at the window's ends,
    s, the window's new end, the smoothing applied, the feet's report, the flights)."""
    f0, f1 = window
    blended = blend(m1.clip, m2.clip, T, f0, f1, ease=ease)
    Lb = np.linalg.norm(momentum(blended, body).L, axis=1)
    # |L| at the window's ends from the motions themselves (a difference at a
    # window end straddles the blend)
    ends = (float(np.linalg.norm(m1.L[f0])), float(np.linalg.norm(m2.L[f1 - T])))
    s = smoothing_factor(Lb, f0, f1, ends)
    out, w1, applied = smooth(blended, body, (f0, f1), Lb, ends, smoothing, passes=passes, tol=tol)
    feet = None
    if fix_feet:
        out, feet = pin_feet(out, body, (f0, w1))
    mo = momentum(out, body)
    Ln = np.linalg.norm(mo.L, axis=1)
    return out, Lb, Ln, ends, s, w1, applied, feet, _flights(out, body, mo)


def _refuse(m1, m2_raw, rule: str, body, max_facing_deg: float, tried: list):
    """No blendable period under ``rule``: raise, naming what failed and whether the
    other rule works."""
    other = "forward" if rule == "reverse" else "reverse"
    th, _, works, _ = _best_period(m1, m2_raw, other, body, max_facing_deg)
    hint = (f"; --rule {other} works (θ = {np.degrees(th):.1f}°)" if works is not None else
            f"; --rule {other} fails too (try --range-a/--range-b or --mirror-b)")
    raise ConcatError(f"the motions cannot be concatenated under the {rule} rule: " + "; ".join(tried)
                      + hint)


def _blend_window(m1, m2r, T: int, fT: int, s1, s2, thr: float, want: int):
    """The blend window [f0, f1], traced from f_T while ‖ΔL‖² stays under ``thr`` and
    inside both blendable periods, widened towards ``want`` frames if shorter: (f0, f1,
    how it was widened or None, the first blended frame in both periods)."""
    # the blend window, traced from f_T while ΔL² stays small and inside both periods
    ok1 = np.zeros(m1.clip.num_frames, bool)
    ok1[s1] = True
    ok2 = np.zeros(m2r.clip.num_frames, bool)
    ok2[s2] = True
    # frames f where both motions exist (motion 2 at f − T), and which of them lie
    # in both blendable periods ("both") with ‖ΔL‖² under the threshold ("close")
    lo, hi = max(0, T), min(ok1.size - 1, ok2.size - 1 + T)
    fr = np.arange(lo, hi + 1)
    both = ok1[fr] & ok2[fr - T]
    close = both & (np.sum((m1.L[fr] - m2r.L[fr - T]) ** 2, axis=1) <= thr)
    close[fT - lo] = True

    def run_at(mask):
        """The frames (first, last) of the run of ``mask`` that holds f_T."""
        s, e = next((s, e) for s, e in _runs(mask) if s <= fT - lo <= e)
        return lo + s, lo + e

    f0, f1 = run_at(close)                      # eq. 8's tracing rule, outwards from f_T

    def grow(f0, f1, a_, b_):
        """[f0, f1] widened towards ``want`` frames inside [a_, b_], half on each side."""
        need = want - (f1 - f0)
        if need <= 0:
            return f0, f1
        left = min(f0 - a_, (need + 1) // 2)
        right = min(b_ - f1, need - left)
        left = min(f0 - a_, need - right)
        return f0 - left, f1 + right

    widened = None
    if f1 - f0 < want:
        # a window this short would be a cut: widen it, inside the blendable
        # periods first, then beyond them (reported)
        f0, f1 = grow(f0, f1, *run_at(both))
        f0, f1 = grow(f0, f1, lo, hi)
        widened = "inside the blendable periods" if (ok1[f0] and ok1[f1] and ok2[f0 - T] and ok2[f1 - T]) \
            else "beyond the blendable periods"
    # translate motion 2 so the centres of the feet coincide at the first blended frame
    # (the first blended frame in both blendable periods, i.e. in support, if the
    # window was widened beyond them)
    fa = f0 + int(np.flatnonzero(both[f0 - lo:f1 - lo + 1])[0])
    return f0, f1, widened, fa


def _flights(out: Clip, body, mo) -> list[dict]:
    """What an observer of the result sees in its flights (the release of a pinned foot
    in the air moves a leg there): |L| coefficient of variation per flight."""
    Ln = np.linalg.norm(mo.L, axis=1)
    return [{"takeoff": fl.takeoff, "landing": fl.landing,
             "L_cv_pct": float(100 * Ln[fl.takeoff:fl.landing + 1].std()
                               / max(Ln[fl.takeoff:fl.landing + 1].mean(), 1e-9))}
            for fl in sorted(detect_flights(out, body, mo.com), key=lambda f: f.takeoff)]


def _best_period(m1, m2_raw, rule: str, body, max_facing_deg: float):
    """(θ, motion 2 turned by θ, the least-cost blend ``(timing, case, s1, s2, support,
    allowed)`` or None, why each blendable period failed) under ``rule``."""
    theta = align_angle(m1.main_L, m2_raw.main_L, rule)
    m2r = transformed(m2_raw, theta, np.zeros(3))
    best = None
    tried = []
    for case, f1, f2 in blendable_periods(m1, m2r, rule):
        try:
            s1, s2, support = support_frames(m1, m2r, f1, f2)
        except ConcatError as e:
            tried.append(f"{case}: {e}")
            continue
        cosang = np.einsum("ia,ja->ij", m1.facing[s1], m2r.facing[s2])
        allowed = cosang >= np.cos(np.radians(max_facing_deg))
        if not allowed.any():
            ang = np.degrees(np.arccos(np.clip(cosang.max(), -1, 1)))
            tried.append(f"{case}: torso facing directions differ by at least {ang:.0f}° "
                         f"(more than {max_facing_deg:g}°)")
            continue
        tmg = optimal_timing(m1.L, m2r.L, m1.arms, m2r.arms, body.mass, s1, s2,
                             f_start=int(s1[0]), allowed=allowed)
        if best is None or tmg.F < best[0].F:
            best = (tmg, case, s1, s2, support, allowed)
    return theta, m2r, best, tried
