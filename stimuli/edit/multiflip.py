"""Multi-flip editing (Majkowska & Faloutsos 2007, Section 5 and Appendix B).

A single flip becomes a double, triple or quadruple one in four steps:

1. **Search** (5.2): in the flight, a self-looping sequence F_B = f_m … f_n−1
   whose end pose is its start pose turned by φ about the angular-momentum axis
   (Appendix A distance, :mod:`flipstudy.stimuli.edit.similarity`).
2. **Sequencing** (5.2): F_S, then F_B repeated r+1 times, the k-th copy turned
   by kφ about the axis along L through the COM, r = ⌈(2π·flips − φ_S − φ_E)/φ⌉;
   a second search joins a frame f of the last copies to a frame g of the rest
   of the flight so that the character still lands upright (the pair's turn
   error, at most ``max_turn_error`` degrees, is spread over the copies so the
   landing is exact); joins are cross-faded with slerp over a few frames.
3. **Retiming** (5.3, Appendix B): take-off, flight and landing play k times
   faster, k = ``k_ratio``·k* (default k*; the paper chose 0.7·k*),
   k* = sqrt(½ g T / (v0 − Δy/T)), T the sequenced
   flight's duration before retiming.  With k = k* the linear momentum is
   continuous at take-off and landing; other k leave a jump, which is measured
   and reported.
4. **Repositioning** (5.4): the flight's COM is put on the exact parabola from
   the take-off point (horizontal velocity k·v_h) to the landing height, and
   everything after landing follows on from where the flight now ends.

The rotation and angular momentum of the result are then measured by the
analyser (:func:`~flipstudy.stimuli.edit.flight_measures.measure`).

>>> from flipstudy.stimuli import analyse, builtin
>>> from flipstudy.stimuli.edit.multiflip import flip_source, multiflip
>>> source = flip_source(analyse(builtin("backflip")))   # once per clip
>>> double = multiflip(source, 2)
>>> double.flips, double.takeoff < double.landing, round(double.report.k_ratio, 2)
(2, True, 1.0)
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..analyse import Analysis, analyse
from ..motion import quat
from ..motion.clip import Clip, derived_meta
from ..physics import center_of_mass
from ..result import Result
from flipstudy.errors import FlipEditError
from .flight_measures import _jumps, flight_axis, standing_span, unwrapped_turn
from .report import Report
from .reposition import ballistic_path
from .similarity import distance_matrix, pose_features
from .timing import slerp, smoothstep


def k_star(g: float, T: float, v0: float, dy: float) -> float:
    """Appendix B: the retiming factor that keeps linear momentum continuous,
    k* = sqrt(½ g T / (v0 − Δy/T)), for a flight of T seconds (before retiming)
    that took off with vertical velocity v0 and lands Δy higher.

    Parameters
    ----------
    g : float
        Gravity, m/s².
    T : float
        The flight's seconds before retiming.
    v0 : float
        Vertical take-off velocity, m/s.
    dy : float
        Landing height above the take-off, m.

    Returns
    -------
    float

    Examples
    --------
    A flight that already lasts what its take-off velocity gives needs no retiming:

    >>> round(k_star(9.81, 1.0, 4.905, 0.0), 6)
    1.0
    """
    den = v0 - dy / T
    if not (T > 0 and den > 0):
        raise FlipEditError(f"k*: the flight needs T > 0 and v0 > Δy/T (T={T:.3f} s, v0={v0:.3f} m/s, "
                            f"Δy={dy:.3f} m)")
    return math.sqrt(0.5 * g * T / den)


@dataclass
class SelfLoop:
    m: int                 # first frame of F_B (source)
    n: int                 # frame reached after F_B: R(f_m, φ) ≈ f_n
    phi: float             # radians, about the flight axis
    distance: float


@functools.lru_cache(maxsize=16)
def _pairs(n: int, k: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.triu_indices(n, k)``, read-only and kept: the search asks for the same
    flight's pairs at every edit."""
    i, j = np.triu_indices(n, k=k)
    i.setflags(write=False)
    j.setflags(write=False)
    return i, j


def find_self_loop(D: np.ndarray, phi: np.ndarray, frames: np.ndarray, fps: float, *,
                   min_turn_deg: float = 45.0, max_turn_deg: float = 300.0,
                   min_seconds: float = 0.05) -> SelfLoop:
    """The pair (m, n), m < n, of least distance whose turn φ (about the axis, in
    the flip's direction) lies in [min_turn, max_turn]; ties go to the larger φ.
    Raises :class:`FlipEditError` when no pair qualifies."""
    i, j = _pairs(D.shape[0], max(1, int(round(min_seconds * fps))))
    # unwrap: the turn from i to j, counted along the flip (positive), can exceed π
    turn = np.mod(phi[i, j], 2.0 * np.pi)
    ok = (turn >= np.radians(min_turn_deg)) & (turn <= np.radians(max_turn_deg))
    if not np.any(ok):
        raise FlipEditError(f"no self-looping sequence: no two flight frames are {min_turn_deg:g}°–"
                            f"{max_turn_deg:g}° apart about the angular-momentum axis")
    i, j, turn = i[ok], j[ok], turn[ok]
    cost = D[i, j] - 1e-6 * turn                 # least distance, then the longest turn
    k = int(np.argmin(cost))
    return SelfLoop(int(frames[i[k]]), int(frames[j[k]]), float(turn[k]), float(D[i[k], j[k]]))


@dataclass
class SelfLoopReport(Report):
    """The self-looping sequence: frames ``m``..``n`` of the source, turning ``phi_deg``."""
    m: int
    n: int
    phi_deg: float
    distance: float


@dataclass
class LandingJoinReport(Report):
    """Where the last copy joins the landing: source frame ``f_source`` of copy
    ``f_copy`` → frame ``g``, pose distance, turn error."""
    f_source: int
    f_copy: int
    g: int
    distance: float
    turn_error_deg: float


@dataclass
class MultiFlipReport(Report):
    """What :func:`multiflip` did and measured."""
    self_loop: SelfLoopReport
    phi_S_deg: float
    phi_E_deg: float
    repetitions: int
    landing_join: LandingJoinReport
    flight_s_before_retiming: float
    k_star: float
    k: float
    k_ratio: float
    k_landing: float
    flight_s: float
    takeoff: int
    landing: int
    gravity: float
    #: linear-momentum jumps at take-off and landing
    #: (:func:`~flipstudy.stimuli.edit.flight_measures.momentum_jumps`)
    dp_takeoff: float
    dp_landing: float
    p_takeoff: float
    dp_takeoff_pct: float
    dp_landing_pct: float


@dataclass
class MultiFlip(Result[MultiFlipReport]):
    """The edited clip, its flight (the first and last frames strictly inside it)
    and what the method did (:func:`multiflip`); ``flips``: the number of flips made."""

    flips: int


@dataclass
class FlipSource:
    """The pre-processing of a single flip for :func:`multiflip`: what depends on the
    source alone, computed once (the paper's pre-processing stage, Section 4, plus the
    per-frame tables its run-time search reads).  Build it with :func:`flip_source`
    and pass it to :func:`multiflip` as often as needed.

    ``D``/``phi`` are the Appendix A distances and turns of every pair of flight
    frames; ``theta`` the root's unwrapped turn about ``axis`` per frame (radians);
    ``stand`` the last standing frame before take-off and the first after landing;
    ``com`` the source's COM per frame; ``path`` the flight's COM parabola;
    ``step`` (F−1, J−1, 3) the rotation vector log(q_f⁻¹ q_f+1) of every joint but
    the root from each frame to the next (what a slerp between them needs), ``unit``
    (F, J−1, 4) those joints' quaternions normalised as the slerp takes them."""

    analysis: Analysis
    axis: np.ndarray
    frames: np.ndarray
    D: np.ndarray
    phi: np.ndarray
    theta: np.ndarray
    stand: tuple[int, int]
    com: np.ndarray
    path: np.ndarray
    step: np.ndarray
    unit: np.ndarray


def flip_source(source: Clip | Analysis) -> FlipSource:
    """The :class:`FlipSource` of a single flip (a clip or its analysis): its
    pre-processing for :func:`multiflip`."""
    a = source if isinstance(source, Analysis) else analyse(source)
    if a.flight is None:
        raise FlipEditError(f"{a.clip.meta.get('name', 'clip')}: no flight phase to add flips to")
    clip, body, fps = a.clip, a.body, a.clip.fps
    to, ld = a.takeoff, a.landing
    u = flight_axis(a)
    frames = np.arange(to, ld + 1)
    D, phi = distance_matrix(pose_features(clip, body, u, frames))
    theta = unwrapped_turn(clip, u)                                      # radians, unwrapped
    q = clip.rotations[:, 1:]
    q0 = Rotation.from_quat(q[:-1])
    step = (q0.inv() * Rotation.from_quat(q[1:])).as_rotvec()
    return FlipSource(a, u, frames, D, phi, theta, standing_span(clip, body, to, ld),
                      center_of_mass(clip, body), a.path, step, quat.normalized(q))


def _turned(clip: Clip, com: np.ndarray, s: np.ndarray, rotvec: np.ndarray):
    """Rotations (n,J,4) and root positions (n,3) of source frames ``s`` (whole
    numbers), each turned by ``rotvec`` (n,3) about its own COM: the COM stays.
    Frames turned by nothing keep the source's numbers."""
    s = np.clip(s, 0, clip.num_frames - 1).astype(np.int64)
    rot = clip.rotations[s]
    pos = clip.root_pos[s]
    t = np.flatnonzero(np.any(rotvec != 0, axis=1))
    if t.size:
        turn = quat.from_rotvec(rotvec[t])
        rot[t, 0] = quat.mul(turn, quat.normalized(rot[t, 0]))
        cc = com[s[t]]
        pos[t] = cc + quat.apply(turn, pos[t] - cc)
    return rot, pos


def _retimed(pre: "FlipSource", rot: np.ndarray, root_pos: np.ndarray, s_src: np.ndarray,
             plain: np.ndarray, src: np.ndarray):
    """:func:`~flipstudy.stimuli.edit.timing.sample` of the sequenced frames (``rot``,
    ``root_pos``) at fractional frames ``src``.  A sequenced frame i is ``plain``
    when it is source frame ``s_src[i]`` with only its root turned; between two
    plain frames that are consecutive source frames, the joints below the root
    slerp with the source's prepared steps log(q⁻¹q').  The root, and every joint
    elsewhere (cross-fades, joins), slerps from scratch."""
    N, J = rot.shape[:2]
    i0 = np.minimum(np.floor(src).astype(np.int64), N - 2)
    i1 = i0 + 1
    u = src - i0
    out = rot[i0]
    f = np.flatnonzero(u != 0)
    a0, a1 = i0[f], i1[f]
    quick = plain[a0] & plain[a1] & (s_src[a1] == s_src[a0] + 1)
    fq, ff = f[quick], f[~quick]
    if f.size:
        # log(q0⁻¹ q1) from scratch for the root of the quick frames and every joint of
        # the others; then one batch q0 · exp(u · log) for all of them
        a = quat.normalized(np.concatenate([rot[i0[fq], 0], rot[i0[ff]].reshape(-1, 4)]))
        b = quat.normalized(np.concatenate([rot[i1[fq], 0], rot[i1[ff]].reshape(-1, 4)]))
        log = quat.as_rotvec(quat.mul(quat.inv(a), b))
        nq = fq.size * (J - 1)
        s0 = s_src[i0[fq]]           # a plain frame's joints below the root are its source's
        q0 = np.concatenate([pre.unit[s0].reshape(-1, 4), a])
        step = np.concatenate([pre.step[s0].reshape(-1, 3), log])
        uu = np.concatenate([np.repeat(u[fq], J - 1), u[fq], np.repeat(u[ff], J)])
        q = quat.mul(q0, quat.from_rotvec(step * uu[:, None]))
        out[fq, 1:] = q[:nq].reshape(fq.size, J - 1, 4)
        out[fq, 0] = q[nq:nq + fq.size]
        out[ff] = q[nq + fq.size:].reshape(ff.size, J, 4)
    root = root_pos[i0] * (1 - u)[:, None] + root_pos[i1] * u[:, None]
    return out, root


def multiflip(source: Clip | Analysis | FlipSource, flips: int = 2, *, k_ratio: float = 1.0,
              k: float | None = None, blend_s: float = 0.025, max_turn_error: float = 10.0,
              takeoff_height: float = 0.0, min_turn_deg: float = 45.0) -> MultiFlip:
    """Make a ``flips``-flip motion from a single flip (a clip, its analysis or its
    pre-processing from :func:`flip_source`, which saves redoing it for every edit).

    ``k_ratio``: retiming factor as a fraction of k* (default 1: k*, linear momentum
    continuous at take-off and landing; the paper's 0.7 gives higher jumps with slower
    rotation but a velocity jump at take-off, e.g. 3.0 → 6.1 m/s upward in one frame on
    the built-in backflip: an option, not the default); ``k`` overrides it.  ``blend_s``: half-width of
    the slerp cross-fade at each join.  ``takeoff_height``: metres added to the
    take-off (everything before the flight is raised, Figure 4c), the landing
    height stays.  Returns a :class:`MultiFlip` whose ``report`` holds the
    search, sequencing, k*, k and the measured momentum jumps.

    Parameters
    ----------
    source : Clip, Analysis or FlipSource
        A single flip.
    flips : int
        1 to 6.
    k_ratio, k : float
        The retiming factor, as a fraction of k* or itself.
    blend_s : float
        Seconds, half-width of each join's cross-fade.
    max_turn_error : float
        Degrees the landing join may miss whole turns by.
    takeoff_height : float
        Metres added to the take-off.
    min_turn_deg : float
        The least turn of the self-looping sequence, degrees.

    Returns
    -------
    MultiFlip

    Raises
    ------
    FlipEditError

    Examples
    --------
    >>> from flipstudy import builtin
    >>> double = multiflip(builtin("backflip"), 2)
    >>> double.flips, double.takeoff < double.landing
    (2, True)
    """
    if isinstance(flips, bool) or not isinstance(flips, (int, np.integer)) or not 1 <= flips <= 6:
        raise FlipEditError(f"flips must be a whole number from 1 to 6, got {flips!r}")
    pre = source if isinstance(source, FlipSource) else flip_source(source)
    a = pre.analysis
    clip, body, fps = a.clip, a.body, a.clip.fps
    to = a.takeoff
    theta = pre.theta

    # the source must be one flip: its root turns about 360° from stand to stand
    s0, s1 = pre.stand
    total = theta[s1] - theta[s0]
    if abs(abs(total) - 2 * np.pi) > np.radians(60):
        raise FlipEditError(f"the source turns {np.degrees(total):.0f}° about its angular momentum "
                            f"from stand to stand, not one flip (360°): multiflip needs a single flip")
    want = 2.0 * np.pi * flips

    # 1. search
    loop = find_self_loop(pre.D, pre.phi, pre.frames, fps, min_turn_deg=min_turn_deg)
    m, n, ph = loop.m, loop.n, loop.phi
    phi_S = theta[m] - theta[s0]
    phi_E = theta[s1] - theta[n]
    r = max(1, int(math.ceil((abs(want) - abs(phi_S) - abs(phi_E)) / ph)))

    # 2. sequencing: the second search, the copies and the cross-fades
    c_f, s_f, g, turn_err, d_land = _landing_join(pre, loop, r, want, flips, max_turn_error)
    sq = _sequenced(pre, loop, c_f, s_f, g, turn_err, blend_s)

    # 3. retiming by k over take-off, flight and landing
    G = 9.81                                   # the new flight falls at earth's gravity
    dy = sq.com[sq.landing, 1] - (sq.com[to, 1] + takeoff_height)
    kst = k_star(G, sq.flight_s, pre.path[1, 1], dy)
    kk = float(k) if k is not None else k_ratio * kst
    if not (0.2 < kk < 5):
        raise FlipEditError(f"retiming factor k = {kk:.3f} is out of range (0.2, 5)")
    rot_n, root_n, to_n, ld_n, kL = _retime(pre, sq, kk, dy, G)

    # 4. repositioning: the exact parabola, then everything after follows on
    root_out, com_out, Tn = _reposition(pre, rot_n, root_n, to_n, ld_n, kk, takeoff_height, G)
    out = Clip(clip.skeleton, fps, root_out, rot_n, None, derived_meta(clip.meta, f"multiflip {flips}"))

    report = MultiFlipReport(
        self_loop=SelfLoopReport(m, n, float(np.degrees(ph)), loop.distance),
        phi_S_deg=float(np.degrees(phi_S)), phi_E_deg=float(np.degrees(phi_E)), repetitions=r,
        landing_join=LandingJoinReport(s_f, c_f, g, d_land, float(np.degrees(turn_err))),
        flight_s_before_retiming=sq.flight_s, k_star=kst, k=kk, k_ratio=kk / kst, k_landing=kL,
        flight_s=Tn, takeoff=to_n, landing=ld_n, gravity=G,
        # the output's COM: the new frames' moved by the raise and the repositioning
        **_jumps(com_out, fps, body.total_mass, to_n, ld_n))
    return MultiFlip(out, to_n, ld_n, report, flips=flips)


# the named steps of :func:`multiflip` (Section 5.2–5.4)

def _landing_join(pre: FlipSource, loop: SelfLoop, r: int, want: float, flips: int,
                  max_turn_error: float) -> tuple[int, int, int, float, float]:
    """The second search (5.2): f in copies r−1, r (source frame s_f, copy c_f) and g in
    [m+1, landing] whose orientations differ by (flips − 1) whole turns: (c_f, s_f, g,
    the turn error in radians, the pose distance of f and g)."""
    a, theta, D = pre.analysis, pre.theta, pre.D
    to, ld = a.takeoff, a.landing
    m, n, ph = loop.m, loop.n, loop.phi
    src_f = np.arange(m, n)
    g_idx = np.arange(m + 1, ld + 1)
    Dg = D[m - to:n - to, m + 1 - to:]                                   # (|F_B|, |g|)
    best = None
    for c in (r - 1, r):
        if c < 0:
            continue
        # unwrapped orientation of f (copy c) minus that of g: must be (flips−1) turns
        err = (theta[src_f][:, None] + c * ph - theta[g_idx][None, :]) - (abs(want) - 2 * np.pi)
        ok = np.abs(err) <= np.radians(max_turn_error)
        if not np.any(ok):
            continue
        cost = np.where(ok, Dg + 0.5 * np.abs(err), np.inf)
        i, j = np.unravel_index(int(np.argmin(cost)), cost.shape)
        if best is None or cost[i, j] < best[0]:
            best = (float(cost[i, j]), c, int(src_f[i]), int(g_idx[j]), float(err[i, j]), float(Dg[i, j]))
    if best is None:
        raise FlipEditError(f"no landing join within {max_turn_error:g}° of {flips} full turns: no frame "
                            f"of the last repetitions matches the end of the flight (try another "
                            f"--flips or a larger max_turn_error)")
    return best[1:]


@dataclass(frozen=True)
class _Sequenced:
    """The sequenced timeline before retiming (5.2): per new frame its rotations,
    root, source frame, cross-fade weight and COM (NaN where never read); its
    landing frame and flight duration."""
    rot: np.ndarray
    root_pos: np.ndarray
    s_src: np.ndarray
    alpha: np.ndarray
    com: np.ndarray
    landing: int
    flight_s: float


def _sequenced(pre: FlipSource, loop: SelfLoop, c_f: int, s_f: int, g: int, turn_err: float,
               blend_s: float) -> _Sequenced:
    """F_S, the copies of F_B turned by kφ, the rest of the flight after g, cross-faded
    at every join."""
    a = pre.analysis
    clip, body, fps = a.clip, a.body, a.clip.fps
    to, ld = a.takeoff, a.landing
    m, n, ph = loop.m, loop.n, loop.phi
    # segments of the new timeline: (first source frame, last source frame, copy index)
    segs = [(0, m - 1, None)] if m > 0 else []
    for c in range(c_f):
        segs.append((m, n - 1, c))
    segs.append((m, s_f, c_f))
    segs.append((g + 1, clip.num_frames - 1, "end"))     # f ≈ g, so after f comes g + 1
    src, cop = [], []
    for a0, a1, c in segs:
        src.append(np.arange(a0, a1 + 1, dtype=float))
        cop.append(np.full(a1 - a0 + 1, -1.0 if c is None else (-2.0 if c == "end" else float(c))))
    src = np.concatenate(src)
    copy = np.concatenate(cop)
    N = src.size
    # turn of every new frame: copies k·φ, with the landing join's error spread over the copies
    n_rep = np.flatnonzero(copy >= 0)
    frac = np.zeros(N)
    if n_rep.size:
        frac[n_rep] = np.linspace(0.0, 1.0, n_rep.size)
        frac[n_rep[-1] + 1:] = 1.0
    ang = np.where(copy >= 0, copy * ph, 0.0) - turn_err * frac
    # after the landing join: g's orientation must equal f's, which differs from the
    # original's by c_f·φ + θ(s_f) − θ(g) − err = (flips − 1) whole turns: no rotation
    ang[copy == -2] = 0.0
    srcA, angA, srcB, angB, alpha = _cross_fades(src, ang, segs, max(1, int(round(blend_s * fps))))
    # every sequenced frame is a whole source frame turned about its COM (which the
    # turn keeps): its COM is the source's; only the cross-fades need their own
    x = np.flatnonzero(alpha > 0)                # the cross-fades: a few frames per join
    # A (every frame) and B (the cross-fades) turned in one batch
    rot, root_pos = _turned(clip, pre.com, np.concatenate([srcA, srcB[x]]),
                            pre.axis[None] * np.concatenate([angA, angB[x]])[:, None])
    rot, rB = rot[:N], rot[N:]
    root_pos, pB = root_pos[:N], root_pos[N:]
    s_src = np.clip(srcA, 0, clip.num_frames - 1).astype(np.int64)
    end0 = int(np.flatnonzero(copy == -2)[0])        # the end segment starts at g + 1
    # landing after the join: found in the end segment; on the join frame g itself:
    # the frame before the end segment (the last copy's f, which is g)
    ld_seq = int(np.flatnonzero((copy == -2) & (src == ld))[0]) if ld > g else (end0 - 1 if ld == g else end0)
    # the COM of the sequenced frames is read up to take-off and from landing on (the
    # retiming's bounds); a turned source frame has the source's COM; a cross-fade
    # there needs its own (NaN marks what is never read)
    com_seq = pre.com[s_src]
    if x.size:
        rot[x] = slerp(rot[x], rB, alpha[x, None])
        root_pos[x] = root_pos[x] * (1 - alpha[x])[:, None] + pB * alpha[x][:, None]
        com_seq[x] = np.nan
        xr = x[(x <= to + 1) | (x >= ld_seq - 1)]
        if xr.size:
            com_seq[xr] = center_of_mass(Clip(clip.skeleton, fps, root_pos[xr], rot[xr]), body)
    return _Sequenced(rot, root_pos, s_src, alpha, com_seq, ld_seq, (ld_seq - to) / fps)


def _cross_fades(src: np.ndarray, ang: np.ndarray, segs: list, w: int):
    """Cross-fades of half-width ``w`` frames at every join: frame J+i blends the
    previous segment continued (A) into the next segment run backwards (B).  Returns
    (source frames A, turns A, source frames B, turns B, weights of B)."""
    N = src.size
    srcA, angA = src.copy(), ang.copy()
    srcB, angB = src.copy(), ang.copy()
    alpha = np.zeros(N)
    starts = np.cumsum([0] + [s[1] - s[0] + 1 for s in segs])[1:-1]      # first new index of segs 2..
    for Jn in starts:
        i = np.arange(-w, w)
        idx = Jn + i
        keep = (idx >= 0) & (idx < N)
        i, idx = i[keep], idx[keep]
        srcA[idx] = src[Jn - 1] + 1 + i           # previous segment, continued
        angA[idx] = ang[Jn - 1]
        srcB[idx] = src[Jn] + i                   # next segment, before its start
        angB[idx] = ang[Jn]
        alpha[idx] = smoothstep((i + w + 0.5) / (2 * w))
    return srcA, angA, srcB, angB, alpha


def _retime(pre: FlipSource, sq: _Sequenced, kk: float, dy: float, G: float):
    """Retiming (5.3): take-off and flight k times faster, the landing at k_L; returns
    (rotations, roots, take-off and landing frame of the output, k_L)."""
    fps, to = pre.analysis.clip.fps, pre.analysis.takeoff
    ld_seq, N = sq.landing, sq.s_src.size
    vy = np.gradient(sq.com[:, 1], 1.0 / fps)
    pre_ = np.flatnonzero(vy[:to + 1] <= 0)
    p0 = int(pre_[-1]) if pre_.size else 0               # bottom of the crouch
    post = np.flatnonzero(vy[ld_seq:] >= 0)
    p1 = int(ld_seq + post[0]) if post.size else N - 1   # bottom of the landing
    # the flight's rate: a whole number of output frames from take-off to landing
    n_fl = max(1, int(round((ld_seq - to) / kk)))
    k_fl = (ld_seq - to) / n_fl
    Tn = sq.flight_s / k_fl
    # landing phase: retimed by k_L so that it continues the vertical velocity the
    # parabola lands with (k_L = k when take-off and landing are at the same height)
    vy_land_new = (dy + 0.5 * G * Tn ** 2) / Tn - G * Tn
    vy_land_old = vy[ld_seq]
    kL = vy_land_new / vy_land_old if vy_land_old < -1e-6 else kk
    kL = float(min(max(kL, 0.5 * kk), 2.0 * kk))            # np.clip on floats, without its overhead
    # source frame of each output frame: rate 1, k from the crouch's bottom to the
    # landing, k_L to the bottom of the landing, then 1
    # (the take-off phase at the flight's exact rate: its start moves to a whole
    # number of flight steps before take-off)
    p0 = to - math.floor((to - p0) / k_fl) * k_fl
    out_src = piecewise_source([0, p0, to, ld_seq, p1, N - 1], [1.0, k_fl, k_fl, kL, 1.0])
    out_src = np.clip(out_src, 0.0, N - 1)
    rot_n, root_n = _retimed(pre, sq.rot, sq.root_pos, sq.s_src, sq.alpha == 0, out_src)
    to_n = int(np.flatnonzero(_close(out_src, to))[0])
    ld_n = int(np.flatnonzero(_close(out_src, ld_seq))[0])
    return rot_n, root_n, to_n, ld_n, kL


def _reposition(pre: FlipSource, rot_n, root_n, to_n: int, ld_n: int, kk: float,
                takeoff_height: float, G: float):
    """Repositioning (5.4): the flight's COM on the exact parabola, everything after
    following on; the COM is needed from a frame before take-off to a frame after
    landing only.  Returns (the output's roots, its COM (NaN where not computed), the
    flight's duration)."""
    clip, body, fps = pre.analysis.clip, pre.analysis.body, pre.analysis.clip.fps
    M = root_n.shape[0]
    lo, hi = max(to_n - 1, 0), min(ld_n + 1, M - 1)
    com_new = np.full((M, 3), np.nan)
    com_new[lo:hi + 1] = center_of_mass(Clip(clip.skeleton, fps, root_n[lo:hi + 1],
                                             rot_n[lo:hi + 1]), body)
    Tn = (ld_n - to_n) / fps
    c0 = com_new[to_n].copy()
    raise_before = np.zeros_like(root_n)
    if takeoff_height:
        raise_before[:to_n + 1, 1] = takeoff_height
        c0[1] += takeoff_height
    y_end = com_new[ld_n, 1]
    vh = kk * pre.path[[0, 2], 1]
    vyn = (y_end - c0[1] + 0.5 * G * Tn ** 2) / Tn
    tt = np.arange(ld_n - to_n + 1) / fps
    target = ballistic_path(c0, np.array([vh[0], vyn, vh[1]]), G, tt)
    shift = np.zeros_like(root_n)
    shift[to_n:ld_n + 1] = target - com_new[to_n:ld_n + 1]
    shift[ld_n + 1:] = target[-1] - com_new[ld_n]
    return root_n + raise_before + shift, com_new + raise_before + shift, Tn


def _close(x: np.ndarray, v: float) -> np.ndarray:
    """``np.isclose(x, v)`` for finite ``x`` and ``v`` (its default tolerances), without
    its general-case overhead."""
    return np.abs(x - v) <= 1e-8 + 1e-5 * abs(v)


def piecewise_source(bounds, rates) -> np.ndarray:
    """Fractional source frames of an output that plays ``bounds[i]`` →
    ``bounds[i+1]`` at about ``rates[i]`` source frames per output frame, every
    bound hit exactly by an output frame (each span takes a whole number of
    steps, so its rate is rounded: (b − a)/round((b − a)/rate))."""
    out = []
    for a, b, r in zip(bounds[:-1], bounds[1:], rates):
        if b <= a:
            continue
        n = max(1, int(round((b - a) / r)))
        out.append(np.linspace(a, b, n + 1)[:-1])
    out.append(np.array([float(bounds[-1])]))
    return np.concatenate(out)
