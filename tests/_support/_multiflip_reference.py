"""A test's reference copy, kept on purpose: the plain multi-flip implementation
(one call does everything, nothing prepared or cached) that
``tests/stimuli/test_fast_paths.py`` compares :mod:`flipstudy.stimuli.edit.multiflip`
with, result for result.  It repeats much of that module by design (the
``duplicates`` pairs between the two are this copy); the package never imports it.

Multi-flip editing (Majkowska & Faloutsos 2007, Section 5 and Appendix B).

A single flip becomes a double, triple or quadruple one in four steps:

1. **Search** (5.2): in the flight, a self-looping sequence F_B = f_m … f_n−1
   whose end pose is its start pose turned by φ about the angular-momentum axis
   (Appendix A distance, :mod:`stimuli.edit.similarity`).
2. **Sequencing** (5.2): F_S, then F_B repeated r+1 times, the k-th copy turned
   by kφ about the axis along L through the COM, r = ⌈(2π·flips − φ_S − φ_E)/φ⌉;
   a second search joins a frame f of the last copies to a frame g of the rest
   of the flight so that the character still lands upright (the pair's turn
   error, at most ``max_turn_error`` degrees, is spread over the copies so the
   landing is exact); joins are cross-faded with slerp over a few frames.
3. **Retiming** (5.3, Appendix B): take-off, flight and landing play k times
   faster, k = ``k_ratio``·k*, k* = sqrt(½ g T / (v0 − Δy/T)), T the sequenced
   flight's duration before retiming.  With k = k* the linear momentum is
   continuous at take-off and landing; other k leave a jump, which is measured
   and reported.
4. **Repositioning** (5.4): the flight's COM is put on the exact parabola from
   the take-off point (horizontal velocity k·v_h) to the landing height, and
   everything after landing follows on from where the flight now ends.

The rotation and angular momentum of the result are then measured by the
analyser (:func:`measure`).
"""
# The implementation of stimuli/edit/multiflip.py before its pre-processing was split
# out (commit 36cbc1e): the functions the fast path changed, kept verbatim as the plain
# path tests/stimuli/test_fast_paths.py compares the fast one with; the rest is imported (the
# flight measures it shares with the module from stimuli/edit/flight_measures.py; its
# own copy of measure, which no test called, is gone).
from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from flipstudy.stimuli.analyse import Analysis, analyse
from flipstudy.stimuli.motion.clip import Clip, derived_meta
from flipstudy.stimuli.physics import center_of_mass
from flipstudy.stimuli.edit.reposition import ballistic_path
from flipstudy.stimuli.edit.similarity import distance_matrix, pose_features
# unchanged by the fast path: shared with the module rather than copied
from flipstudy.errors import FlipEditError
from flipstudy.stimuli.edit.multiflip import (MultiFlip, SelfLoop, find_self_loop,  # noqa: F401
                                    k_star, piecewise_source)
from flipstudy.stimuli.edit.flight_measures import flight_axis, momentum_jumps, standing_span
from flipstudy.stimuli.edit.timing import smoothstep as _smooth


def sample(clip: Clip, src: np.ndarray) -> Clip:
    """flipstudy.stimuli.edit.timing.sample as it was: slerp over every frame and joint."""
    src = np.clip(np.asarray(src, dtype=np.float64), 0.0, clip.num_frames - 1)
    i0 = np.floor(src).astype(np.int64)
    i0 = np.minimum(i0, clip.num_frames - 2) if clip.num_frames > 1 else i0
    i1 = np.minimum(i0 + 1, clip.num_frames - 1)
    u = src - i0
    q0 = Rotation.from_quat(clip.rotations[i0])
    q1 = Rotation.from_quat(clip.rotations[i1])
    rel = (q0.inv() * q1).as_rotvec()
    rot = (q0 * Rotation.from_rotvec(rel * u[:, None, None])).as_quat()
    exact0 = u == 0
    rot[exact0] = clip.rotations[i0[exact0]]
    root = clip.root_pos[i0] * (1 - u)[:, None] + clip.root_pos[i1] * u[:, None]
    jp = None
    if clip.joint_pos is not None:
        jp = clip.joint_pos[i0] * (1 - u)[:, None, None] + clip.joint_pos[i1] * u[:, None, None]
    meta = dict(clip.meta)
    meta["source_frames"] = src
    return Clip(clip.skeleton, clip.fps, root, rot, jp, meta)


def multiflip(source: Clip | Analysis, flips: int = 2, *, k_ratio: float = 1.0, k: float | None = None,
              blend_s: float = 0.025, max_turn_error: float = 10.0, takeoff_height: float = 0.0,
              min_turn_deg: float = 45.0) -> MultiFlip:
    """Make a ``flips``-flip motion from a single flip (a clip or its analysis).

    ``k_ratio``: retiming factor as a fraction of k* (1 by default, as the library's
    multiflip since issue 30; the paper's 0.7 is an option;
    1 gives continuous momentum); ``k`` overrides it.  ``blend_s``: half-width of
    the slerp cross-fade at each join.  ``takeoff_height``: metres added to the
    take-off (everything before the flight is raised, Figure 4c), the landing
    height stays.  Returns a :class:`MultiFlip` whose ``report`` holds the
    search, sequencing, k*, k and the measured momentum jumps.
    """
    if isinstance(flips, bool) or not isinstance(flips, (int, np.integer)) or not 1 <= flips <= 6:
        raise FlipEditError(f"flips must be a whole number from 1 to 6, got {flips!r}")
    a = source if isinstance(source, Analysis) else analyse(source)
    if a.flight is None:
        raise FlipEditError(f"{a.clip.meta.get('name', 'clip')}: no flight phase to add flips to")
    clip, body, fps = a.clip, a.body, a.clip.fps
    to, ld = a.takeoff, a.landing
    u = flight_axis(a)
    frames = np.arange(to, ld + 1)
    feat = pose_features(clip, body, u, frames)
    D, phi = distance_matrix(feat)

    # the source must be one flip: its root turns about 360° from stand to stand
    s0, s1 = standing_span(clip, body, to, ld)
    w_u = clip.angular_velocities()[:, 0] @ u
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (w_u[1:] + w_u[:-1]) / fps)])   # radians, unwrapped
    total = theta[s1] - theta[s0]
    if abs(abs(total) - 2 * np.pi) > np.radians(60):
        raise FlipEditError(f"the source turns {np.degrees(total):.0f}° about its angular momentum "
                            f"from stand to stand, not one flip (360°): multiflip needs a single flip")
    want = 2.0 * np.pi * flips

    # 1. search
    loop = find_self_loop(D, phi, frames, fps, min_turn_deg=min_turn_deg)
    m, n, ph = loop.m, loop.n, loop.phi
    phi_S = theta[m] - theta[s0]
    phi_E = theta[s1] - theta[n]
    r = max(1, int(math.ceil((abs(want) - abs(phi_S) - abs(phi_E)) / ph)))
    L_len = n - m

    # 2. second search: f in copies r-1, r (source s_f, copy c) and g in [m+1, ld]
    pos = {int(f): i for i, f in enumerate(frames)}
    src_f = np.arange(m, n)
    g_idx = np.arange(m + 1, ld + 1)
    Dg = D[np.ix_([pos[s] for s in src_f], [pos[g] for g in g_idx])]      # (|F_B|, |g|)
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
    _, c_f, s_f, g, turn_err, d_land = best

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
    # cross-fades at every join: frame J+i blends the previous segment continued (A)
    # into the next segment run backwards (B)
    w = max(1, int(round(blend_s * fps)))
    srcA, angA = src.copy(), ang.copy()
    srcB, angB = src.copy(), ang.copy()
    alpha = np.zeros(N)
    starts = np.cumsum([0] + [s[1] - s[0] + 1 for s in segs])[1:-1]      # first new index of segs 2..
    for J in starts:
        i = np.arange(-w, w)
        idx = J + i
        keep = (idx >= 0) & (idx < N)
        i, idx = i[keep], idx[keep]
        srcA[idx] = src[J - 1] + 1 + i            # previous segment, continued
        angA[idx] = ang[J - 1]
        srcB[idx] = src[J] + i                    # next segment, before its start
        angB[idx] = ang[J]
        alpha[idx] = _smooth((i + w + 0.5) / (2 * w))
    com_src = center_of_mass(clip, body)

    def posed(s, an):
        c = sample(clip, s)
        cc = np.array([np.interp(s, np.arange(clip.num_frames), com_src[:, k]) for k in range(3)]).T
        R = Rotation.from_rotvec(u[None] * an[:, None])
        root = Rotation.from_quat(c.rotations[:, 0])
        rot = c.rotations.copy()
        rot[:, 0] = (R * root).as_quat()
        return rot, cc + R.apply(c.root_pos - cc)

    rot, root_pos = posed(srcA, angA)
    x = np.flatnonzero(alpha > 0)                # the cross-fades: a few frames per join
    if x.size:
        rB, pB = posed(srcB[x], angB[x])
        qa, qb = Rotation.from_quat(rot[x].reshape(-1, 4)), Rotation.from_quat(rB.reshape(-1, 4))
        al = np.repeat(alpha[x], clip.skeleton.num_joints)
        rot[x] = (qa * Rotation.from_rotvec((qa.inv() * qb).as_rotvec() * al[:, None])).as_quat() \
            .reshape(x.size, -1, 4)
        root_pos[x] = root_pos[x] * (1 - alpha[x])[:, None] + pB * alpha[x][:, None]
    seq = Clip(clip.skeleton, fps, root_pos, rot, None,
               derived_meta(clip.meta, f"multiflip {flips}"))
    seq.meta.pop("source_frames", None)
    end0 = int(np.flatnonzero(copy == -2)[0])
    # a landing on the join frame g itself: the frame before the end segment
    ld_seq = int(np.flatnonzero((copy == -2) & (src == ld))[0]) if ld > g else (
        end0 - 1 if ld == g else end0)
    T_seq = (ld_seq - to) / fps

    # 3. retiming by k over take-off, flight and landing
    path = a.path
    G = 9.81                                   # the new flight falls at earth's gravity
    v0 = path[1, 1]
    com_seq = center_of_mass(seq, body)
    dy = com_seq[ld_seq, 1] - (com_seq[to, 1] + takeoff_height)
    kst = k_star(G, T_seq, v0, dy)
    kk = float(k) if k is not None else k_ratio * kst
    if not (0.2 < kk < 5):
        raise FlipEditError(f"retiming factor k = {kk:.3f} is out of range (0.2, 5)")
    vy = np.gradient(com_seq[:, 1], 1.0 / fps)
    pre = np.flatnonzero(vy[:to + 1] <= 0)
    p0 = int(pre[-1]) if pre.size else 0                 # bottom of the crouch
    post = np.flatnonzero(vy[ld_seq:] >= 0)
    p1 = int(ld_seq + post[0]) if post.size else N - 1   # bottom of the landing
    # the flight's rate: a whole number of output frames from take-off to landing
    n_fl = max(1, int(round((ld_seq - to) / kk)))
    k_fl = (ld_seq - to) / n_fl
    Tn = T_seq / k_fl
    # landing phase: retimed by k_L so that it continues the vertical velocity the
    # parabola lands with (k_L = k when take-off and landing are at the same height)
    vy_land_new = (dy + 0.5 * G * Tn ** 2) / Tn - G * Tn
    vy_land_old = vy[ld_seq]
    kL = vy_land_new / vy_land_old if vy_land_old < -1e-6 else kk
    kL = float(np.clip(kL, 0.5 * kk, 2.0 * kk))
    # source frame of each output frame: rate 1, k from the crouch's bottom to the
    # landing, k_L to the bottom of the landing, then 1
    # (the take-off phase at the flight's exact rate: its start moves to a whole
    # number of flight steps before take-off)
    p0 = to - math.floor((to - p0) / k_fl) * k_fl
    out_src = piecewise_source([0, p0, to, ld_seq, p1, N - 1], [1.0, k_fl, k_fl, kL, 1.0])
    new = sample(seq, out_src)
    new.meta.pop("source_frames", None)
    to_n = int(np.flatnonzero(np.isclose(out_src, to))[0])
    ld_n = int(np.flatnonzero(np.isclose(out_src, ld_seq))[0])

    # 4. repositioning: the exact parabola, then everything after follows on
    com_new = center_of_mass(new, body)
    Tn = (ld_n - to_n) / fps
    c0 = com_new[to_n].copy()
    if takeoff_height:
        raise_before = np.zeros_like(new.root_pos)
        raise_before[:to_n + 1, 1] = takeoff_height
        new = new.replace(root_pos=new.root_pos + raise_before)
        c0[1] += takeoff_height
    y_end = com_new[ld_n, 1]
    vh = kk * path[[0, 2], 1]
    vyn = (y_end - c0[1] + 0.5 * G * Tn ** 2) / Tn
    tt = np.arange(ld_n - to_n + 1) / fps
    target = ballistic_path(c0, np.array([vh[0], vyn, vh[1]]), G, tt)
    shift = np.zeros_like(new.root_pos)
    shift[to_n:ld_n + 1] = target - com_new[to_n:ld_n + 1]
    shift[ld_n + 1:] = target[-1] - com_new[ld_n]
    out = new.replace(root_pos=new.root_pos + shift,
                      meta=new.meta)

    report = {"self_loop": {"m": m, "n": n, "phi_deg": float(np.degrees(ph)), "distance": loop.distance},
              "phi_S_deg": float(np.degrees(phi_S)), "phi_E_deg": float(np.degrees(phi_E)),
              "repetitions": r, "landing_join": {"f_source": s_f, "f_copy": c_f, "g": g,
                                                 "distance": d_land,
                                                 "turn_error_deg": float(np.degrees(turn_err))},
              "flight_s_before_retiming": T_seq, "k_star": kst, "k": kk, "k_ratio": kk / kst,
              "k_landing": kL,
              "flight_s": Tn, "takeoff": to_n, "landing": ld_n, "gravity": G}
    report.update(momentum_jumps(out, body, to_n, ld_n))
    return MultiFlip(out, to_n, ld_n, report, flips=flips)
