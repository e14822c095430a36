"""Joining two motions in flight (Majkowska & Faloutsos 2007, end of 5.2 and
Figure 4c).

The first motion's take-off and early flight are joined to the second motion's
late flight and landing at a pair of similar frames.  The angular momenta must
point the same way: the second motion is first turned about the vertical so its
flight L lies along the first's (refused beyond ``max_axis_deg``), then retimed
uniformly so |L| matches (retiming by s scales L by s, Section 5.1).  The join
(i in the first flight, j in the second) minimises the Appendix A distance among
pairs whose remaining turn about L is within ``max_turn_error`` of a whole turn,
so the joined motion lands upright (the small error is spread over the second
part's flight frames); the join is cross-faded with slerp; the flight's COM is
put on the exact parabola from the first take-off to the second landing height
(the second part keeps its own heights, so it lands on its floor).

Turning the second motion so the angular momenta agree can leave its body
facing another way than the first's (a frontflip turned 180° about the vertical
to join a backflip faces backwards): a cross-fade between them would turn the
body about an axis ⟂ L that no angular momentum explains, a half twist in
mid-air.  So the pairs are also limited to root orientations that agree up to
``max_swing_deg`` once the turn about L is removed, and the joined motion is
measured: over the cross-fade the root's rotation about the axes ⟂ L must be
what the flight's angular momentum explains (∫ I(t)⁻¹ L dt, L the first
flight's mean angular momentum, I(t) the joined body's inertia) within
``max_unexplained_deg``, and the joined flight's |L| CV must stay within
``max_L_cv_pct`` (or the larger CV of the two motions it is made of: real
captures have 14–19 %); otherwise the join is refused with the numbers.  The
30° default: the CMU flights themselves turn 3–8° ⟂ L unexplained (median; up
to 40° at a glitch of 87_03) over such a window at 60 fps, their joins 8–19°;
the frontflip-onto-backflip join turned 179°.

The flight must last what the first take-off's vertical velocity and the landing
height give, T = (v0 + sqrt(v0² − 2gΔy))/g (Appendix B's reasoning for k*),
or the parabola would leave the ground faster or slower than the take-off
delivered.  At the first motion's |L| each candidate pair has its own duration,
so the pair's duration mismatch enters its cost, and what is left is spread over
the flight as a small uniform change of |L|.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..analyse import Analysis, analyse
from ..motion.clip import Clip, derived_meta
from ..physics import center_of_mass, momentum
from ..result import Result
from flipstudy.errors import FlipEditError
from .flight_measures import flight_axis, momentum_jumps, standing_span, turn_angle, unwrapped_turn
from .report import Report
from .reposition import rotate
from .similarity import distance_matrix, pose_features, twist_angles
from .timing import retime, sample, slerp, smoothstep


@dataclass
class JoinPointReport(Report):
    """Where the two motions are joined: ``first``'s frame ``first`` → ``second``'s
    frame ``second`` (pose distance, turn error, the root orientations' swing ⟂ L,
    and what the cross-fade turns: :func:`crossfade_rotation`)."""
    first: int
    second: int
    distance: float
    turn_error_deg: float
    flight_frames_at_L_first: int
    swing_deg: float
    crossfade: dict


@dataclass
class JoinReport(Report):
    """What :func:`join_in_flight` did and measured."""
    yaw_deg: float
    axis_error_deg: float
    retime: float
    join: JoinPointReport
    turn_deg: float
    L_cv_pct: float
    L_mean: float
    L_first: float
    L_second_before: float
    L_target: float
    L_spread_pct: float
    flight_s: float
    flight_s_required: float
    takeoff: int
    landing: int
    analyser_flight: list | None
    #: linear-momentum jumps at take-off and landing (:func:`momentum_jumps`)
    dp_takeoff: float
    dp_landing: float
    p_takeoff: float
    dp_takeoff_pct: float
    dp_landing_pct: float
    L_cv_bound_pct: float


@dataclass
class Join(Result[JoinReport]):
    """The joined clip, its flight and the report (:func:`join_in_flight`)."""


def _assemble(a: Analysis, bc: Clip, b: Analysis, u: np.ndarray, fi: int, gj: int, e: float,
              blend_s: float) -> tuple[Clip, int]:
    """``a``'s frames up to ``fi`` followed by ``bc``'s (retimed second) from
    ``gj + 1``, cross-faded; the second part turned back by ``e`` about ``u`` at the
    join and released over its flight.  Returns (clip, landing frame)."""
    body, fps = a.body, a.clip.fps
    # the second part is turned back by φ at the join (g_j onto f_i), and the turn
    # is released over its flight so that it ends upright as it was captured
    n2 = bc.num_frames - (gj + 1)
    ramp = np.clip((np.arange(n2) + 1) / max(b.landing - gj, 1), 0.0, 1.0)
    ang = -e * (1.0 - ramp)
    part_b = bc.slice(gj + 1, bc.num_frames)
    com_b = center_of_mass(part_b, body)
    part_b = rotate(part_b, Rotation.from_rotvec(u[None] * ang[:, None]), com_b)
    # cross-fade: the first continued past f_i, blended into the second's frames
    w = max(1, int(round(blend_s * fps)))
    head = a.clip.slice(0, fi + 1)
    cont = sample(a.clip, np.arange(fi + 1, fi + 1 + w, dtype=float))
    x = (np.arange(w) + 0.5) / w
    rot_b = part_b.rotations.copy()
    rot_b[:w] = slerp(cont.rotations, part_b.rotations[:w], smoothstep(x)[:, None])
    rot = np.concatenate([head.rotations, rot_b])
    # the second part follows on horizontally, but keeps its own heights: it lands
    # on its floor (the flight's COM is put on a parabola afterwards, so the step
    # at the join does not remain; carrying it on would sink the landing and
    # everything after it by the two flights' height difference at the join)
    step = head.root_pos[-1] - part_b.root_pos[0]
    step[1] = 0.0
    root = np.concatenate([head.root_pos, part_b.root_pos + step])
    joined = Clip(a.clip.skeleton, fps, root, rot, None, derived_meta(a.clip.meta, "joined in flight"))
    return joined, fi + 1 + (b.landing - (gj + 1))


def _steps_to(ratio_of, start: float, n: int) -> float:
    """Where the paper's rule ``next = last + 1/ratio(last)`` is after ``n`` steps."""
    f = float(start)
    for _ in range(n):
        f += 1.0 / ratio_of(f)
    return f


def join_in_flight(first: Clip | Analysis, second: Clip | Analysis, *, max_axis_deg: float = 30.0,
                   max_turn_error: float = 15.0, blend_s: float = 0.04,
                   duration_weight: float = 10.0, max_swing_deg: float = 30.0,
                   max_unexplained_deg: float = 30.0, max_L_cv_pct: float = 10.0) -> Join:
    """Join ``first``'s take-off and early flight to ``second``'s late flight and
    landing.  Both need the same skeleton.  Returns a :class:`Join` (clip, flight,
    :class:`JoinReport`).

    The joined flight must last what ``first``'s take-off velocity v0 and the
    landing height (Δy above the take-off) give a ballistic flight,
    T = (v0 + sqrt(v0² − 2gΔy))/g, or the parabola put on it would take off with
    another vertical velocity than the ground phase delivered (a momentum jump).
    At the first motion's |L| every candidate pair gives its own flight duration
    (the poses after the join, and the turn error released over them, decide how
    long the body takes to turn): the pair chosen minimises the Appendix A
    distance plus ``duration_weight`` times the relative duration mismatch, and the
    mismatch left is spread over the flight as a uniform |L| change (the flight is
    retimed towards |L| ≈ L_first·(duration at L_first)/T, which lasts T; the
    report's ``L_spread_pct``)."""
    a = first if isinstance(first, Analysis) else analyse(first)
    b0 = second if isinstance(second, Analysis) else analyse(second)
    u, yaw, axis_err, s, bc, b = _aligned_second(a, b0, max_axis_deg)
    fa, fb, D, phi, swing, ok = _candidate_pairs(a, b, bc, u, yaw, max_turn_error, max_swing_deg)
    from .animator import retime_flight
    body, fps, to = a.body, a.clip.fps, a.takeoff
    best = _best_pair(a, b, bc, u, (fa, fb, D, phi, ok), blend_s, duration_weight)
    _, i, j, fi, gj, e, joined, ld, n_free, T_req, n_req = best
    xf = crossfade_rotation(joined, body, fi, max(1, int(round(blend_s * fps))), u * a.L_mean)
    if xf["unexplained_deg"] > max_unexplained_deg:
        raise FlipEditError(
            f"the cross-fade at frame {fi} → its frame {gj} (distance {D[i, j]:.2f}) turns the body "
            f"{xf['turned_perp_deg']:.0f}° about the axes ⟂ L (about the vertical {xf['turned_vertical_deg']:+.0f}°), "
            f"of which the flight's angular momentum explains {xf['explained_perp_deg']:.0f}° "
            f"({xf['unexplained_deg']:.0f}° unexplained, at most {max_unexplained_deg:g}°): they cannot be joined")

    c, grid, ratio = _spread(a, joined, to, ld, n_free, n_req)
    out, _, ld, T, _ = retime_flight(joined, body, to, ld, grid, ratio, a.path, keep_landing_point=False)
    m = analyse(out, body=body, estimate=False)
    Lm = np.linalg.norm(m.L[to + 2:ld - 1], axis=1)
    s0, s1 = standing_span(out, body, to, ld)
    cv = float(100 * Lm.std() / Lm.mean())
    cv_bound = max(max_L_cv_pct, a.L_cv_pct, b0.L_cv_pct)
    report = JoinReport(
        yaw_deg=float(np.degrees(yaw)), axis_error_deg=float(axis_err), retime=float(s),
        join=JoinPointReport(first=fi, second=gj, distance=float(D[i, j]),
                             turn_error_deg=float(np.degrees(e)), flight_frames_at_L_first=n_free,
                             swing_deg=float(np.degrees(swing[i, j])), crossfade=xf),
        turn_deg=turn_angle(out, u, s0, s1), L_cv_pct=cv,
        L_mean=float(Lm.mean()), L_first=a.L_mean, L_second_before=b0.L_mean,
        L_target=float(a.L_mean / c), L_spread_pct=float(100 * (1.0 / c - 1.0)),
        flight_s=T, flight_s_required=float(T_req), takeoff=to, landing=ld,
        analyser_flight=[m.takeoff, m.landing] if m.flight is not None else None,
        **momentum_jumps(out, body, to, ld), L_cv_bound_pct=float(cv_bound))
    if report.L_cv_pct > cv_bound:
        raise FlipEditError(
            f"the joined flight's |L| varies by CV {report.L_cv_pct:.1f} % (at most {cv_bound:.3g} %: "
            f"{max_L_cv_pct:g} % or the two motions' own, {a.L_cv_pct:.1f} % and {b0.L_cv_pct:.1f} %; "
            f"join at frame {fi} → its frame {gj}, distance {D[i, j]:.2f}, cross-fade turning "
            f"{xf['turned_perp_deg']:.0f}° ⟂ L of which {xf['explained_perp_deg']:.0f}° explained): "
            f"the angular momentum is not conserved; they cannot be joined")
    return Join(out, to, ld, report)


def _aligned_second(a: Analysis, b0: Analysis, max_axis_deg: float):
    """The second motion turned about the vertical so its L lies along the first's, at
    the first's frame rate and retimed to its |L|: (the first's axis u, the yaw, the axes'
    angle left, the retiming factor, the second's clip, its analysis)."""
    for x, label in ((a, "first"), (b0, "second")):
        if x.flight is None:
            raise FlipEditError(f"the {label} motion has no flight phase")
    if a.clip.skeleton.joint_names != b0.clip.skeleton.joint_names:
        raise FlipEditError("the two motions must share a skeleton (the same joints)")
    body, fps = a.body, a.clip.fps
    u = flight_axis(a)
    ub = flight_axis(b0)
    # turn the second about the vertical so its L lies along the first's
    yaw = np.arctan2(u[0], u[2]) - np.arctan2(ub[0], ub[2])
    Ry = Rotation.from_rotvec([0.0, yaw, 0.0])
    axis_err = np.degrees(np.arccos(np.clip(Ry.apply(ub) @ u, -1, 1)))
    if axis_err > max_axis_deg:
        raise FlipEditError(f"the angular momenta point {axis_err:.0f}° apart even after turning the second "
                            f"motion about the vertical (at most {max_axis_deg:g}°): they cannot be joined")
    bc = b0.clip if abs(b0.clip.fps - fps) < 1e-9 else sample(b0.clip, np.arange(
        0, b0.clip.num_frames - 1 + 1e-9, b0.clip.fps / fps)).with_fps(fps)
    bc = rotate(bc, Ry, center_of_mass(bc, body)[0])
    # |L| matched by uniform retiming
    s = a.L_mean / b0.L_mean
    if not (0.33 < s < 3.0):
        raise FlipEditError(f"|L| differs by a factor {s:.2f}: too much to match by retiming (0.33-3)")
    bc = retime(bc, s)
    b = analyse(bc, body=body, estimate=False)
    if b.flight is None:
        raise FlipEditError("the second motion has no flight after retiming")
    return u, yaw, axis_err, s, bc, b


def _candidate_pairs(a: Analysis, b: Analysis, bc: Clip, u, yaw: float, max_turn_error: float,
                     max_swing_deg: float):
    """Flight frames of the first (``fa``) and of the second (``fb``) and which pairs may
    join (``ok``): (fa, fb, Appendix A distances, turns about L, swings ⟂ L, ok)."""
    body = a.body
    th_a, th_b = unwrapped_turn(a.clip, u), unwrapped_turn(bc, u)
    fa = np.arange(a.takeoff + 2, a.landing - 1)
    fb = np.arange(b.takeoff + 2, b.landing - 1)
    pf_a, pf_b = pose_features(a.clip, body, u, fa), pose_features(bc, body, u, fb)
    D, phi = distance_matrix(pf_a, pf_b)
    _, swing = twist_angles(pf_a.root_q, pf_b.root_q, u)       # what is left ⟂ L
    # the second part then turns from j to its standing end; the whole must be one turn
    s0a, _ = standing_span(a.clip, body, a.takeoff, a.landing)
    _, s1b = standing_span(bc, body, b.takeoff, b.landing)
    total = (th_a[fa] - th_a[s0a])[:, None] + (th_b[s1b] - th_b[fb])[None, :]
    # both motions stand upright at their ends, so a pair whose root orientations
    # differ by φ about L leaves the joined motion ending φ off upright: keep |φ| small
    ok = (np.abs(phi) <= np.radians(max_turn_error)) & (total >= np.pi)
    # a real mix: at least a third of the first flight, and of the second, is used
    ok &= (fa[:, None] - a.takeoff >= (a.landing - a.takeoff) / 3)
    ok &= (b.landing - fb[None, :] >= (b.landing - b.takeoff) / 3)
    if not np.any(ok):
        raise FlipEditError(f"no pair of flight frames joins with the root orientations within "
                            f"{max_turn_error:g}° about L")
    # and the orientations must agree about the axes ⟂ L: a cross-fade cannot turn
    # the body there (no angular momentum about them)
    agree = ok & (swing <= np.radians(max_swing_deg))
    if not np.any(agree):
        k = np.unravel_index(np.argmin(np.where(ok, swing, np.inf)), swing.shape)
        raise FlipEditError(
            f"the two motions face different ways in flight: after turning the second by "
            f"{np.degrees(yaw):.0f}° about the vertical so the angular momenta agree, the root "
            f"orientations of every candidate pair differ by {np.degrees(swing[ok].min()):.0f}° or more "
            f"about an axis ⟂ L (at most {max_swing_deg:g}°; closest pair: frame {fa[k[0]]} → its frame "
            f"{fb[k[1]]}, distance {D[k]:.2f}); a cross-fade would twist the body by that much with no "
            f"angular momentum about that axis: they cannot be joined")
    return fa, fb, D, phi, swing, agree


def _best_pair(a: Analysis, b: Analysis, bc: Clip, u, cand: tuple, blend_s: float,
               duration_weight: float) -> tuple:
    """The pair of least cost (distance plus ``duration_weight`` × the duration
    mismatch at |L| = L_first) and its joined motion: (cost, i, j, first frame, second
    frame, turn error, joined clip, landing, frames at L_first, T required, frames
    required)."""
    fa, fb, D, phi, ok = cand
    body, fps = a.body, a.clip.fps
    # the flight the first take-off implies (Appendix B's reasoning for k*: linear
    # momentum is continuous when the flight lasts what v0 and Δy give)
    from .animator import _L_on_grid
    to = a.takeoff
    G = -2.0 * a.path[1, 0]                      # the gravity retime_flight's parabola uses
    v0 = a.path[1, 1]
    y_to = center_of_mass(a.clip.slice(to, to + 1), body)[0, 1]

    def required(joined, ld):
        dy = center_of_mass(joined.slice(ld, ld + 1), body)[0, 1] - y_to
        disc = v0 * v0 - 2.0 * G * dy
        if not (v0 > 0 and disc > 0):
            raise FlipEditError(f"the first take-off (vertical velocity {v0:.2f} m/s) cannot reach the "
                                f"second landing {dy:+.2f} m above it")
        T = (v0 + np.sqrt(disc)) / G
        return T, max(2, int(round(T * fps)))

    # candidates by distance; a pair's cost adds its duration mismatch at |L| = L_first,
    # which is never negative, so the search stops once D alone exceeds the best cost
    I, Jx = np.nonzero(ok)
    order = np.argsort(D[I, Jx], kind="stable")
    best = None
    for k in order:
        i, j = int(I[k]), int(Jx[k])
        if best is not None and D[i, j] >= best[0]:
            break
        fi, gj, e = int(fa[i]), int(fb[j]), float(phi[i, j])
        joined, ld = _assemble(a, bc, b, u, fi, gj, e, blend_s)
        grid, L = _L_on_grid(joined, body, to, ld, 2)       # 2 substeps: within 0.02 frames of 8
        n_free = float(np.trapezoid(np.clip(L / a.L_mean, 0.2, 5.0), grid))   # frames at |L| = L_first
        T_req, n_req = required(joined, ld)
        mismatch = n_free / n_req - 1.0
        cost = float(D[i, j]) + duration_weight * abs(mismatch)
        if best is None or cost < best[0]:
            best = (cost, i, j, fi, gj, e, joined, ld, n_free, T_req, n_req)
    return best


def _spread(a: Analysis, joined: Clip, to: int, ld: int, n_free: float, n_req: int):
    """The duration mismatch left, spread over the flight: (c, the |L| grid, the rate
    ratio on it)."""
    from .animator import _L_on_grid
    body = a.body
    # the mismatch left is spread over the flight: |L| towards L_first/c, the rule's
    # ratio scaled by c (≈ n_req/n_free) so that exactly n_req steps end on the
    # landing frame (bisection: the end moves back as c grows)
    grid, L = _L_on_grid(joined, body, to, ld, 8)
    base = np.clip(L / a.L_mean, 0.2, 5.0)
    lo, hi = 0.5 * n_free / n_req, 2.0 * n_free / n_req
    for _ in range(50):
        c = 0.5 * (lo + hi)
        if _steps_to(lambda f: float(np.interp(f, grid, c * base)), to, n_req) > ld:
            lo = c
        else:
            hi = c
    c = hi
    ratio = c * base
    return c, grid, ratio


def crossfade_rotation(clip: Clip, body, f: int, w: int, L: np.ndarray, pad: int = 1) -> dict:
    """How far the body turns about the axes ⟂ L over the frames ``f − pad`` …
    ``f + w + pad`` (a cross-fade of ``w`` frames after frame ``f``), against what
    the angular momentum ``L`` (a conserved flight value, world axes) explains.

    Turned: ∫ ω_root dt, the root's world angular velocity from the clip's own
    rotations.  Explained: ∫ I(t)⁻¹ L dt with I(t) the body's inertia about its
    COM in each frame (the composite angular velocity a body with that L must
    have).  Both are split along u = L/|L| and the plane ⟂ u; the vertical part
    is the component along the vertical projected ⟂ u.  Returns degrees."""
    lo, hi = max(0, f - pad), min(clip.num_frames - 1, f + w + pad)
    part = clip.slice(lo, hi + 1)
    u = L / np.linalg.norm(L)
    w_root = part.angular_velocities()[:, 0]
    w_L = np.linalg.solve(momentum(part, body).inertia, np.broadcast_to(L, w_root.shape)[..., None])[..., 0]
    dt = 1.0 / clip.fps
    turned = np.trapezoid(w_root, dx=dt, axis=0)
    explained = np.trapezoid(w_L, dx=dt, axis=0)
    perp = lambda x: x - (x @ u) * u              # noqa: E731
    ev = perp(np.array([0.0, 1.0, 0.0]))
    ev = ev / np.linalg.norm(ev) if np.linalg.norm(ev) > 1e-6 else np.zeros(3)
    deg = np.degrees
    return {"frames": [int(lo), int(hi)],
            "turned_about_L_deg": float(deg(turned @ u)), "explained_about_L_deg": float(deg(explained @ u)),
            "turned_perp_deg": float(deg(np.linalg.norm(perp(turned)))),
            "explained_perp_deg": float(deg(np.linalg.norm(perp(explained)))),
            "turned_vertical_deg": float(deg(turned @ ev)), "explained_vertical_deg": float(deg(explained @ ev)),
            "unexplained_deg": float(deg(np.linalg.norm(perp(turned) - perp(explained))))}
