"""Angular-momentum guided motion concatenation (Shum, Komura & Yadav 2009).

Two full-body motions (flips, cartwheels, kicks, punches) are joined the way
people chain them, with the angular momentum L(t) about the COM as the cue:

1. **Phases** (:func:`phases`): from t_m (the frame of largest |L|, or given)
   backwards and forwards to the first frame with L(t)·L(t_m) < 0: preparatory,
   main and posterior phases, each possibly absent, borders overridable.
2. **Rule and alignment**: the *forward* rule (L of both motions the same way:
   the first's momentum is kept up to start the second) or the *reverse* rule
   (opposite: the end of the first prepares the second).  Motion 2 is turned
   about the vertical by θ₂ = arg max|min L̄₁·R_y(θ)L̄₂ (eq. 2), in closed form
   (:func:`align_angle`), then translated so the centres of the feet coincide at
   the first blended frame.  Torso facing directions (projected on the ground)
   more than π/4 apart at the blend are refused.
3. **Blendable periods** from the rule and the phases (forward: latter half of
   main 1, initial half of main 2; reverse: latter half of main 1 with the latter
   half of preparatory 2, or initial half of posterior 1 with initial half of
   main 2), truncated to double support.  When double support leaves nothing
   (a kick lands its foot only at the very end) the period falls back to the
   frames where the same foot supports in both motions, and the report says so.
4. **Optimal timing** (:func:`optimal_timing`): F(T) = F_dm + F_inertia + F_time
   (eqs. 3-7) for every offset T of motion 2, with f_T the frame of least
   ‖L₁(f) − L₂(f − T)‖² (eq. 5): one (n₁ × n₂) array of all frame pairs, every
   T a diagonal of it; :func:`optimal_timing_bruteforce` is the paper's loop,
   kept as the reference.  A threshold refuses motions too different.
5. **Blending**: slerp per joint, linear root, α from 1 to 0 over
   [f_t0, f_t1], traced from f_T outwards while ‖ΔL‖² stays under a threshold
   and inside both blendable periods (eq. 8); then **angular-momentum smoothing**
   (eq. 9): the blended period is played at rate s, the ratio of the mean of
   |L| at its two ends to its mean |L|, and the result is measured again.
6. **Foot sliding**: each support foot in contact over the transition is pinned
   (analytic two-bone IK, foot orientation kept) at where it stood when the
   blend began, the correction faded out after it lifts; nothing goes below the
   floor; the slide left is measured in centimetres.
7. **Motion-graph baseline** (:func:`motion_graph_join`): the two motions joined
   where their poses are most similar after the first's main phase and before
   the second's (Kovar, Gleicher & Pighin 2002: point-cloud distance over a
   window, minimised over a rotation about the vertical and a ground
   translation, in closed form; a cubic ease over the window).

Units are the library's: metres, seconds, kg; L in kg·m²/s.
"""
from __future__ import annotations

from ..exceptions import FlipstudyError
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from ..analyse import analyse
from ..body import Body
from ..flight import _runs, contact_mask, effector_points
from ..motion.clip import Clip
from ..physics import momentum, piece_positions
from .report import Report
from .reposition import rotate
from .timing import ratio_retime_frames, sample, slerp, smoothstep

UP = np.array([0.0, 1.0, 0.0])


class ConcatError(FlipstudyError, ValueError):
    """Two motions that cannot be concatenated; the message says why."""


# ---------------------------------------------------------------------- phases
@dataclass
class Phases:
    """Frame ranges (inclusive; ``None`` when the phase is absent) of a motion's
    preparatory, main and posterior phases, and the frame t_m they grew from."""

    tm: int
    prep: tuple[int, int] | None
    main: tuple[int, int]
    post: tuple[int, int] | None

    def as_dict(self) -> dict:
        return {"tm": self.tm, "preparatory": self.prep, "main": self.main, "posterior": self.post}


def phases(L: np.ndarray, tm: int | None = None, fps: float = 120.0, *,
           main: tuple[int, int] | None = None, smooth_s: float = 0.1) -> Phases:
    """Preparatory / main / posterior phases from the sign of L(t)·L(t_m).

    ``tm`` defaults to the frame of largest |L| (after a moving average over
    ``smooth_s`` seconds, so one noisy frame does not decide it).  From t_m the
    main phase extends backwards and forwards while L(t)·L(t_m) ≥ 0 (the paper's
    rule, Section "Typical Angular Momentum Trajectories").  ``main=(a, b)``
    overrides the borders (the paper lets the user fine-tune them)."""
    L = np.asarray(L, float)
    F = L.shape[0]
    n = np.linalg.norm(L, axis=1)
    if tm is None:
        w = max(1, int(round(smooth_s * fps)))
        ns = np.convolve(n, np.ones(w) / w, mode="same")
        tm = int(np.argmax(ns))
    if not 0 <= tm < F:
        raise ConcatError(f"t_m = {tm} is outside the motion's frames 0–{F - 1}")
    if main is None:
        s = L @ L[tm]
        neg = s < 0
        before = np.flatnonzero(neg[:tm])
        after = np.flatnonzero(neg[tm + 1:])
        a = int(before[-1]) + 1 if before.size else 0
        b = tm + int(after[0]) if after.size else F - 1
    else:
        a, b = int(main[0]), int(main[1])
        if not 0 <= a <= b < F:
            raise ConcatError(f"main phase {a}:{b} must lie within frames 0–{F - 1} with start ≤ end")
    return Phases(tm=tm, prep=(0, a - 1) if a > 0 else None, main=(a, b),
                  post=(b + 1, F - 1) if b < F - 1 else None)


# ------------------------------------------------------------------ alignment
def align_angle(L1: np.ndarray, L2: np.ndarray, rule: str = "forward") -> float:
    """Eq. 2 in closed form: the angle θ (radians) about the vertical that
    maximises (forward) or minimises (reverse) L̄₁·R_y(θ)L̄₂.

    With R_y(θ) taking (x, z) to (x cos θ + z sin θ, −x sin θ + z cos θ), the
    dot product is A cos θ + B sin θ + C with A = x₁x₂ + z₁z₂, B = x₁z₂ − z₁x₂,
    C = y₁y₂, so the maximum is at atan2(B, A) and the minimum half a turn away."""
    a, b = np.asarray(L1, float), np.asarray(L2, float)
    A = a[0] * b[0] + a[2] * b[2]
    B = a[0] * b[2] - a[2] * b[0]
    th = float(np.arctan2(B, A))
    if rule == "reverse":
        th = th + np.pi
    elif rule != "forward":
        raise ConcatError(f"rule must be 'forward' or 'reverse', got {rule!r}")
    return float((th + np.pi) % (2 * np.pi) - np.pi)


def yaw(theta: float) -> Rotation:
    """R_y(θ): rotation by θ about the vertical (Y) axis."""
    return Rotation.from_rotvec([0.0, float(theta), 0.0])


# ------------------------------------------------------------- optimal timing
@dataclass
class Timing:
    T: int                 # motion 2's frame g is played at motion 1's frame g + T
    fT: int                # blending centre, in motion 1's frames
    F: float               # F_dm + F_inertia + F_time at the optimum
    F_dm: float
    F_inertia: float
    F_time: float
    costs: dict = field(default_factory=dict)   # T → F for every offset examined


def _inertia_pairs(r1: np.ndarray, r2: np.ndarray, m: np.ndarray) -> np.ndarray:
    """(n1, n2) F_inertia of eq. 6 for all frame pairs: Σ_j m_j (r¹_j·(r²_j − r¹_j))²."""
    d12 = np.einsum("fpa,gpa->fgp", r1, r2)
    d11 = np.einsum("fpa,fpa->fp", r1, r1)
    return np.einsum("p,fgp->fg", m, (d12 - d11[:, None, :]) ** 2)


def optimal_timing(L1, L2, r1, r2, m, frames1, frames2, f_start: int | None = None,
                   allowed: np.ndarray | None = None) -> Timing:
    """The offset T minimising F = F_dm + F_inertia + F_time (eqs. 3-7).

    ``L1`` (F1,3), ``L2`` (F2,3) angular momenta; ``r1`` (F1,P,3), ``r2`` (F2,P,3)
    moment arms (piece COM − body COM) and ``m`` (P,) masses; ``frames1`` and
    ``frames2`` the blendable frames of each motion; ``f_start`` the first frame of
    motion 1's blendable period (default ``frames1[0]``).  ``allowed`` (n1, n2)
    bool masks pairs out (e.g. facing too different).  Every frame pair (f, g) is
    one cell of an (n1 × n2) array; the offset T = f − g is its diagonal, sheared
    into a column, and f_T, F_dm, F_inertia and F_time are read off per column —
    no loop over T or f."""
    L1, L2 = np.asarray(L1, float), np.asarray(L2, float)
    f1, f2 = np.asarray(frames1, int), np.asarray(frames2, int)
    if f1.size == 0 or f2.size == 0:
        raise ConcatError("an empty blendable period: nothing to blend")
    f_start = int(f1[0]) if f_start is None else int(f_start)
    A, B = L1[f1], L2[f2]
    D = ((A[:, 0, None] - B[None, :, 0]) ** 2 + (A[:, 1, None] - B[None, :, 1]) ** 2
         + (A[:, 2, None] - B[None, :, 2]) ** 2)                                # (n1, n2) eq. 5
    if allowed is not None:
        D = np.where(allowed, D, np.inf)
    # shear the pairs onto a grid whose columns are the offsets: frame f1[i] (row
    # r = f1[i] − a1) and f2[j] (s = f2[j] − a2) go to column r − s + n2 − 1, so
    # T = a1 − a2 + column − (n2 − 1); the least D down each column is f_T (the
    # first, i.e. the earliest f, on ties — as the loop finds it)
    a1, a2 = int(f1.min()), int(f2.min())
    n1, n2 = int(f1.max()) - a1 + 1, int(f2.max()) - a2 + 1
    rr = (f1 - a1)[:, None]
    cc = rr - (f2 - a2)[None, :] + n2 - 1
    S = np.full((n1, n1 + n2 - 1), np.inf)
    S[np.broadcast_to(rr, D.shape), cc] = D
    row = np.argmin(S, axis=0)
    col = np.arange(S.shape[1])
    ok = np.isfinite(S[row, col])
    if not ok.any():
        raise ConcatError("no frame pair of the blendable periods is allowed (torso facing directions "
                          "differ by more than π/4 everywhere)")
    row, col = row[ok], col[ok]
    fa = a1 + row                                   # f_T per offset
    Ts = a1 - a2 + col - (n2 - 1)
    fb = fa - Ts
    F_dm = S[row, col]
    F_in = np.einsum("p,kp->k", np.asarray(m, float),
                     (np.einsum("kpa,kpa->kp", r1[fa], r2[fb])
                      - np.einsum("kpa,kpa->kp", r1[fa], r1[fa])) ** 2)
    F_t = np.sum((L1[fa] - L1[f_start]) ** 2, axis=-1)
    F = F_dm + F_in + F_t
    k = int(np.argmin(F))
    return Timing(T=int(Ts[k]), fT=int(fa[k]), F=float(F[k]), F_dm=float(F_dm[k]),
                  F_inertia=float(F_in[k]), F_time=float(F_t[k]),
                  costs={int(t): float(c) for t, c in zip(Ts, F)})


def optimal_timing_bruteforce(L1, L2, r1, r2, m, frames1, frames2, f_start: int | None = None,
                              allowed: np.ndarray | None = None) -> Timing:
    """The paper's search, as written: for every offset T, scan every frame for
    f_T, then evaluate F(T).  A plain Python loop, the reference for
    :func:`optimal_timing` (same result)."""
    f1, f2 = [int(x) for x in frames1], [int(x) for x in frames2]
    f_start = f1[0] if f_start is None else int(f_start)
    pos2 = {g: jj for jj, g in enumerate(f2)}
    best = None
    costs = {}
    for T in range(f1[0] - f2[-1], f1[-1] - f2[0] + 1):
        fT, dm = None, np.inf
        for ii, f in enumerate(f1):
            g = f - T
            if g not in pos2 or (allowed is not None and not allowed[ii, pos2[g]]):
                continue
            d = float(np.sum((L1[f] - L2[g]) ** 2))
            if d < dm:
                fT, dm = f, d
        if fT is None:
            continue
        g = fT - T
        fin = 0.0
        for p in range(len(m)):
            fin += m[p] * float(r1[fT, p] @ (r2[g, p] - r1[fT, p])) ** 2
        ft = float(np.sum((L1[fT] - L1[f_start]) ** 2))
        F = dm + fin + ft
        costs[T] = F
        if best is None or F < best.F:
            best = Timing(T=T, fT=fT, F=F, F_dm=dm, F_inertia=fin, F_time=ft)
    if best is None:
        raise ConcatError("no frame pair of the blendable periods is allowed")
    best.costs = costs
    return best


# ------------------------------------------------------------------- a motion
@dataclass
class Motion:
    """What the concatenation needs of one motion, computed once."""

    clip: Clip
    body: Body
    L: np.ndarray            # (F,3)
    com: np.ndarray          # (F,3)
    arms: np.ndarray         # (F,P,3) piece COM − body COM
    foot_l: np.ndarray       # (F,) bool foot contact
    foot_r: np.ndarray
    feet_centre: np.ndarray  # (F,3) mid-point of the balls of the two feet (toe tips)
    facing: np.ndarray       # (F,3) unit torso facing direction on the ground
    phases: Phases

    @property
    def double_support(self) -> np.ndarray:
        return self.foot_l & self.foot_r

    @property
    def main_peak(self) -> float:
        a, b = self.phases.main
        return float(np.linalg.norm(self.L[a:b + 1], axis=1).max())

    @property
    def main_L(self) -> np.ndarray:
        a, b = self.phases.main
        return self.L[a:b + 1].mean(axis=0)


def _lm_index(body: Body, key: str) -> int:
    v = body.landmarks[key]
    return body.skeleton.index(v if isinstance(v, str) else v[0])


def torso_facing(clip: Clip, body: Body) -> np.ndarray:
    """(F,3) unit facing direction of the torso projected on the ground: the
    left-to-right axis of hips and shoulders, turned a quarter about the vertical."""
    P = clip.joint_positions()
    left = (P[:, _lm_index(body, "hip_l")] - P[:, _lm_index(body, "hip_r")]
            + P[:, _lm_index(body, "shoulder_l")] - P[:, _lm_index(body, "shoulder_r")])
    f = np.cross(left, UP)
    f[:, 1] = 0.0
    n = np.linalg.norm(f, axis=1, keepdims=True)
    return f / np.where(n > 1e-9, n, 1.0)


def foot_contacts(clip: Clip, body: Body) -> tuple[np.ndarray, np.ndarray]:
    """(F,) bool left and right foot contact (ankle or toe tip still and low, the
    flight detector's rule)."""
    from ..flight import body_size
    size = body_size(clip) / 1.7
    C = contact_mask(clip, body, v_thr=1.0 * size, margin=0.10 * size, touch=0.03 * size)
    _, names = effector_points(clip, body)
    ix = {n: i for i, n in enumerate(names)}
    return (C[:, ix["toe_tip_l"]] | C[:, ix["ankle_l"]], C[:, ix["toe_tip_r"]] | C[:, ix["ankle_r"]])


def prepare(clip: Clip, body: Body | None = None, *, tm: int | None = None,
            main: tuple[int, int] | None = None) -> Motion:
    """Momenta, moment arms, contacts, facing and phases of one motion."""
    if body is None:
        body = analyse(clip).body
    m = momentum(clip, body)
    arms = piece_positions(clip, body) - m.com[:, None]
    fl, fr = foot_contacts(clip, body)
    E, names = effector_points(clip, body)
    ix = {n: i for i, n in enumerate(names)}
    centre = 0.5 * (E[:, ix["toe_tip_l"]] + E[:, ix["toe_tip_r"]])
    return Motion(clip, body, m.L, m.com, arms, fl, fr, centre, torso_facing(clip, body),
                  phases(m.L, tm, clip.fps, main=main))


def transformed(mo: Motion, theta: float, shift: np.ndarray) -> Motion:
    """Motion 2 turned by θ about the vertical through the origin, then shifted."""
    R = yaw(theta)
    turned = rotate(mo.clip, R, np.zeros(3))
    clip = turned.replace(root_pos=turned.root_pos + shift)
    F, P = mo.arms.shape[:2]
    return Motion(clip, mo.body, R.apply(np.array(mo.L)), R.apply(np.array(mo.com)) + shift,
                  R.apply(np.array(mo.arms).reshape(-1, 3)).reshape(F, P, 3), mo.foot_l, mo.foot_r,
                  R.apply(np.array(mo.feet_centre)) + shift, R.apply(np.array(mo.facing)), mo.phases)


# ------------------------------------------------------------ blendable period
def _half(mo: Motion, r, which: str) -> np.ndarray:
    """The initial or latter half of phase ``r`` = (a, b), split where its |L| is
    largest (for the main phase: t_m) — the dotted lines of the paper's Figure 2."""
    a, b = r
    if r == mo.phases.main:
        mid = mo.phases.tm
    else:
        mid = a + int(np.argmax(np.linalg.norm(mo.L[a:b + 1], axis=1)))
    return np.arange(mid, b + 1) if which == "latter" else np.arange(a, mid + 1)


def blendable_periods(m1: Motion, m2: Motion, rule: str) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The candidate (case, frames of motion 1, frames of motion 2) of the rule,
    before the support truncation (the halves the paper lists)."""
    p1, p2 = m1.phases, m2.phases
    if rule == "forward":
        return [("latter half of main 1 + initial half of main 2",
                 _half(m1, p1.main, "latter"), _half(m2, p2.main, "initial"))]
    out = []
    if p2.prep is not None:
        out.append(("latter half of main 1 + latter half of preparatory 2",
                    _half(m1, p1.main, "latter"), _half(m2, p2.prep, "latter")))
    if p1.post is not None:
        out.append(("initial half of posterior 1 + initial half of main 2",
                    _half(m1, p1.post, "initial"), _half(m2, p2.main, "initial")))
    if not out:
        raise ConcatError("reverse rule: motion 1 has no posterior phase and motion 2 no preparatory "
                          "phase, so there is nothing to blend (try --rule forward)")
    return out


def _truncate(m1: Motion, m2: Motion, f1: np.ndarray, f2: np.ndarray):
    """Keep the frames in double support; when that leaves either period empty,
    the frames where one and the same foot supports in both motions."""
    d1, d2 = f1[m1.double_support[f1]], f2[m2.double_support[f2]]
    if d1.size and d2.size:
        return d1, d2, "double support"
    best = None
    for side in ("l", "r"):
        c1 = getattr(m1, f"foot_{side}")
        c2 = getattr(m2, f"foot_{side}")
        s1, s2 = f1[c1[f1]], f2[c2[f2]]
        if s1.size and s2.size and (best is None or s1.size + s2.size > best[0].size + best[1].size):
            best = (s1, s2, f"single support on the {'left' if side == 'l' else 'right'} foot "
                            f"(no double support in the blendable period)")
    if best is None:
        raise ConcatError("the blendable periods have no frame where a foot supports the body in both "
                          "motions (the paper blends only in support)")
    return best


# ------------------------------------------------------------------- blending
def blend(c1: Clip, c2: Clip, T: int, f0: int, f1: int, ease: bool = True) -> Clip:
    """Eq. 8: motion 1 up to f0, the blend over [f0, f1] (α from 1 to 0, motion
    2's frame f − T), then motion 2.  ``c2`` is already aligned.  The paper's α
    falls linearly; with ``ease`` it falls as 1 − (3x² − 2x³), which has the same
    ends and mean but no kink, so joint velocities do not jump where the window
    begins and ends."""
    F2 = c2.num_frames
    f = np.arange(f0, f1 + 1)
    x = (f - f0) / max(f1 - f0, 1)
    alpha = 1.0 - (smoothstep(x) if ease else x)
    q = slerp(c1.rotations[f], c2.rotations[f - T], (1.0 - alpha)[:, None])
    root = alpha[:, None] * c1.root_pos[f] + (1 - alpha)[:, None] * c2.root_pos[f - T]
    rot = np.concatenate([c1.rotations[:f0], q, c2.rotations[f1 - T + 1:F2]])
    pos = np.concatenate([c1.root_pos[:f0], root, c2.root_pos[f1 - T + 1:F2]])
    if rot.shape[0] != f1 + 1 + (F2 - (f1 - T + 1)):
        raise AssertionError("blend: frame bookkeeping")
    return Clip(c1.skeleton, c1.fps, pos, rot, None, {**c1.meta, "edit": "concatenated"})


def smoothing_factor(Ln: np.ndarray, f0: int, f1: int, ends: tuple[float, float] | None = None) -> float:
    """Eq. 9: s = ½(|L(f_t0)| + |L(f_t1)|) / mean of |L| over [f_t0, f_t1].

    The paper divides the sum over the f_t1 − f_t0 + 1 frames of the window by
    f_t1 − f_t0; we take the mean over its frames, so that after playing the
    window at rate s its mean |L| is the stated one, the mean of its two ends
    (on a window of 5 frames the printed divisor would leave it 20 % low).

    ``ends`` gives |L| at the two ends; by default they are read off ``Ln``.  The
    concatenation passes the source motions' own values there (motion 1 at f_t0,
    motion 2 at f_t1 − T): a finite difference at a window end straddles the blend
    and would carry its fast movement into the target."""
    mean = float(np.mean(Ln[f0:f1 + 1]))
    if mean <= 0:
        return 1.0
    e0, e1 = (Ln[f0], Ln[f1]) if ends is None else ends
    return float(0.5 * (e0 + e1) / mean)


# ------------------------------------------------------------------------ IK
def _axis_angle_between(u: np.ndarray, v: np.ndarray) -> Rotation:
    """(n,) rotations taking directions u (n,3) to v (n,3) by the shortest arc."""
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    ax = np.cross(u, v)
    s = np.linalg.norm(ax, axis=1)
    c = np.einsum("na,na->n", u, v)
    ang = np.arctan2(s, c)
    ax = np.where(s[:, None] > 1e-12, ax / np.where(s > 1e-12, s, 1.0)[:, None], 0.0)
    return Rotation.from_rotvec(ax * ang[:, None])


def two_bone_ik(clip: Clip, hip: int, knee: int, ankle: int, frames: np.ndarray, target: np.ndarray,
                lateral: np.ndarray | None = None) -> Clip:
    """Analytic two-bone IK: in ``frames`` put the ``ankle`` joint at ``target``
    (n,3) by bending the knee about the leg's plane and turning the thigh about
    the hip, keeping the foot's world orientation.  Vectorised over frames; exact
    where the target is in reach (otherwise the leg is stretched towards it)."""
    frames = np.asarray(frames, int)
    if frames.size == 0:
        return clip
    sk = clip.skeleton
    R = clip.joint_rotations()[frames]
    P = clip.joint_positions()[frames]
    H, K, A = P[:, hip], P[:, knee], P[:, ankle]
    a = np.linalg.norm(K - H, axis=1)
    b = np.linalg.norm(A - K, axis=1)
    d = np.clip(np.linalg.norm(target - H, axis=1), np.abs(a - b) + 1e-6, a + b - 1e-6)
    cur = np.clip((a ** 2 + b ** 2 - np.sum((A - H) ** 2, axis=1)) / (2 * a * b), -1, 1)
    want = np.clip((a ** 2 + b ** 2 - d ** 2) / (2 * a * b), -1, 1)
    delta = np.arccos(cur) - np.arccos(want)                  # rotate the shank by +δ about n
    n = np.cross(K - H, A - K)
    nn = np.linalg.norm(n, axis=1)
    if lateral is None:
        lateral = np.tile([1.0, 0.0, 0.0], (frames.size, 1))
    n = np.where(nn[:, None] > 1e-6, n / np.where(nn > 1e-6, nn, 1.0)[:, None], lateral)
    bend = Rotation.from_rotvec(n * delta[:, None])
    A1 = K + bend.apply(A - K)
    swing = _axis_angle_between(A1 - H, target - H)
    par_h = sk.parents[hip]
    par_k = sk.parents[knee]
    par_a = sk.parents[ankle]
    Rh = Rotation.from_matrix(R[:, hip])
    Rk = Rotation.from_matrix(R[:, knee])
    Ra = Rotation.from_matrix(R[:, ankle])
    Rph = Rotation.from_matrix(R[:, par_h])
    Rpk = Rotation.from_matrix(R[:, par_k])
    Rpa = Rotation.from_matrix(R[:, par_a])
    rot = clip.rotations.copy()
    # bend: knee subtree turned about the knee; then swing: hip subtree about the hip
    rot[frames, knee] = (Rpk.inv() * bend * Rk).as_quat()
    rot[frames, hip] = (Rph.inv() * swing * Rh).as_quat()
    # ankle: its parent now (swing·bend·R_pa) — keep the foot's world orientation
    if par_a == knee:
        new_pa = swing * bend * Rk
    else:
        new_pa = swing * bend * Rpa
    rot[frames, ankle] = (new_pa.inv() * Ra).as_quat()
    return clip.replace(rotations=rot)


def pin_feet(clip: Clip, body: Body, window: tuple[int, int], fade_s: float = 0.5,
             floor: float | None = None, release_in_contact: float = 0.01) -> tuple[Clip, dict]:
    """Pin every foot that is in contact during the transition ``window`` (f0, f1)
    where it stands, for as long as it stays in contact.

    The pinned point is the ball of the foot (the toe tip landmark): a foot rolls
    over it when the heel rises to push off and touches down on it, so holding it
    still holds the foot; the ankle target follows from the foot's own (blended)
    orientation, which the IK keeps.  The target is where the ball of the foot is
    when the blend begins (a foot already planted) or where it touches down inside
    the blend.  When the foot lifts off, the offset left between the pinned place
    and where the second motion puts the foot is let go: within the last 0.1 s of
    contact when it is at most ``release_in_contact`` metres (the foot unloading;
    flight untouched), otherwise — the two motions' stances differ — while the
    foot is in the air, eased over its swing (at most ``fade_s``), never while it
    supports the body.  Frames where a foot would go below ``floor`` are lifted onto it.
    Returns the clip and the measured slide (horizontal motion of the pinned
    points while in contact, cm) and floor clearance."""
    f0, f1 = window
    F = clip.num_frames
    fl, fr = foot_contacts(clip, body)
    E0, names = effector_points(clip, body)
    ix = {n: i for i, n in enumerate(names)}
    feet_ix = [ix["ankle_l"], ix["ankle_r"], ix["toe_tip_l"], ix["toe_tip_r"]]
    if floor is None:
        hl = E0[:, [ix["ankle_l"], ix["toe_tip_l"]], 1].min(axis=1)
        hr = E0[:, [ix["ankle_r"], ix["toe_tip_r"]], 1].min(axis=1)
        lows = np.concatenate([hl[fl], hr[fr]])
        # the floor: where the feet rest (the lowest point of a foot in contact)
        floor = float(np.percentile(lows, 5)) if lows.size else float(min(hl.min(), hr.min()))
    fade = max(1, int(round(fade_s * clip.fps)))
    from ..flight import body_size
    size = body_size(clip) / 1.7
    out = clip
    pinned, released = [], []
    air = np.zeros(F, bool)
    P = clip.joint_positions()
    lat = P[:, _lm_index(body, "hip_l")] - P[:, _lm_index(body, "hip_r")]
    lat = lat / np.linalg.norm(lat, axis=1, keepdims=True)
    for side, c in (("l", fl), ("r", fr)):
        hip, knee, ankle = (_lm_index(body, f"{k}_{side}") for k in ("hip", "knee", "ankle"))
        runs = _runs(c)
        for k, (s, e) in enumerate(runs):
            if e < f0 or s > f1:
                continue
            start = max(s, f0)
            E = effector_points(out, body)[0]
            toe = E[:, ix[f"toe_tip_{side}"]]
            ank = E[:, ix[f"ankle_{side}"]]
            # the ball of the foot stays where it is when the blend begins (or where
            # it touches down inside it)
            tgt = toe[start].copy()
            tgt[1] = max(tgt[1], floor)
            nxt = runs[k + 1][0] if k + 1 < len(runs) else F
            if e < F - 1:
                # a foot that takes off: the pin holds while the ball of the foot is
                # down (the detector's 3 cm 'touch' rule still counts a lifting foot)
                up = np.flatnonzero(toe[start:e + 1, 1] > tgt[1] + 0.01 * size)
                if up.size and up[0] >= 2:
                    e = start + int(up[0]) - 1
            idx = np.arange(start, e + 1)
            corr = tgt[None] - toe[idx]
            if e == F - 1:
                frames = idx                  # in contact to the end of the clip: stays pinned
                released.append("none (in contact to the end)")
            elif np.linalg.norm(corr[-1][[0, 2]]) <= release_in_contact:
                # a small offset is let go over the last contact frames (the foot
                # unloading), so the airborne frames stay as they were
                n = min(int(round(0.1 * clip.fps)), max(1, idx.size // 3))
                x = (np.arange(n) + 1) / (n + 1)
                corr[-n:] *= (1.0 - smoothstep(x))[:, None]
                frames = idx
                released.append("in contact")
            else:
                # a larger one (the two motions' stances differ) is released as the
                # foot leaves the ground, eased over its swing (at most ``fade_s``),
                # so no supporting foot slides
                tail = np.arange(e + 1, min(nxt, e + 1 + fade))
                x = (np.arange(tail.size) + 1) / (tail.size + 1)
                w = 1.0 - smoothstep(x)
                frames = np.concatenate([idx, tail])
                corr = np.concatenate([corr, w[:, None] * corr[-1][None]])
                released.append(f"in the air ({100 * np.linalg.norm(corr[idx.size - 1][[0, 2]]):.1f} cm)")
            out = two_bone_ik(out, hip, knee, ankle, frames, ank[frames] + corr, lat[frames])
            pinned.append((side, idx))
            air[frames[idx.size:]] = True
    # a leg moved in the air must not move the body's COM off its path there: where
    # no foot touches, the root is shifted so the COM is where it was before the IK
    air &= ~(fl | fr)
    if air.any():
        from ..physics import center_of_mass
        d = center_of_mass(clip, body)[air] - center_of_mass(out, body)[air]
        root = out.root_pos.copy()
        root[air] += d
        out = out.replace(root_pos=root)
    # measured: the slide of the pinned points, and the floor clearance
    E = effector_points(out, body)[0]
    slide = 0.0
    for side, idx in pinned:
        x = E[idx, ix[f"toe_tip_{side}"]]
        slide = max(slide, float(np.linalg.norm((x - x[0])[:, [0, 2]], axis=1).max()))
    lo = float(E[..., 1][:, feet_ix].min())
    if lo < floor - 1e-4:
        # lift the frames where a foot went under the floor onto it
        lift = np.maximum(floor - E[..., 1][:, feet_ix].min(axis=1), 0.0)
        root = out.root_pos.copy()
        root[:, 1] += lift
        out = out.replace(root_pos=root)
        E = effector_points(out, body)[0]
        lo = float(E[..., 1][:, feet_ix].min())
    return out, {"foot_slide_cm": 100.0 * slide,
                 "pinned": [f"{sd}:{int(i[0])}-{int(i[-1])}" for sd, i in pinned], "released": released,
                 "floor": floor, "lowest_foot_above_floor_cm": 100.0 * (lo - floor)}


# ---------------------------------------------------------------- the method
@dataclass
class FeetReport(Report):
    """What :func:`pin_feet` did: foot slide while pinned, the pinned and released
    feet (``side:first-last`` frames), the floor height and the lowest foot above it."""
    foot_slide_cm: float
    pinned: list
    released: list
    floor: float
    lowest_foot_above_floor_cm: float


@dataclass
class ConcatReport(Report):
    """What :func:`concatenate` did and measured (eqs. 2-9 of Shum et al. 2009)."""
    rule: str
    suggested_rule: str
    theta_deg: float
    phases_a: dict
    phases_b: dict
    case: str
    support: str
    blendable_a: list
    blendable_b: list
    T: int
    f_T: int
    F: float
    F_dm: float
    F_inertia: float
    F_time: float
    threshold: float
    blend: list
    blend_widened: object
    smoothing_s: float
    blend_out: list
    smoothing: dict | None
    L_target_blend: float
    facing_deg_at_fT: float
    shift_m: list
    aligned_at: int
    L_peak_blend_before: float
    L_peak_blend: float
    L_mean_blend: float
    L_main_peak_a: float
    L_main_peak_b: float
    frames: int
    duration_s: float
    frames_a: int
    frames_b: int
    #: the support feet pinned (``None`` without ``fix_feet``)
    feet: FeetReport | None
    #: |L| coefficient of variation per flight of the result
    flights: list

    def to_dict(self) -> dict:
        """The JSON keys: the feet's flattened in (when pinned), then the flights."""
        d = super().to_dict()
        feet, flights = d.pop("feet"), d.pop("flights")
        return {**d, **(feet or {}), "flights": flights}


@dataclass
class MotionGraphReport(Report):
    """The motion-graph transition of :func:`motion_graph_join`."""
    transition_a: int
    transition_b: int
    window: int
    distance: float
    theta_deg: float
    frames: int
    duration_s: float


@dataclass
class Concatenation:
    """The concatenated clip and what was done and measured."""

    clip: Clip
    report: ConcatReport | MotionGraphReport


def suggest_rule(m1: Motion, m2: Motion) -> str:
    """The rule needing the smaller turn of motion 2 about the vertical (eq. 2 for
    both rules; the torso facing test favours the smaller turn)."""
    tf = abs(align_angle(m1.main_L, m2.main_L, "forward"))
    tr = abs(align_angle(m1.main_L, m2.main_L, "reverse"))
    return "forward" if tf <= tr else "reverse"


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
    never a cut."""
    if a.skeleton.joint_names != b.skeleton.joint_names:
        raise ConcatError("the two motions must share a skeleton (the same joints, in the same order): "
                          "blending is per joint")
    if abs(a.fps - b.fps) > 1e-9:
        b = sample(b, np.arange(0, b.num_frames - 1 + 1e-9, b.fps / a.fps)).with_fps(a.fps)
    if body is None:
        body = analyse(a).body
    m1 = prepare(a, body, tm=tm_a, main=main_a)
    m2_raw = prepare(b, body, tm=tm_b, main=main_b)
    suggested = suggest_rule(m1, m2_raw)
    rule = rule or suggested
    theta = align_angle(m1.main_L, m2_raw.main_L, rule)
    m2r = transformed(m2_raw, theta, np.zeros(3))
    peak = max(m1.main_peak, m2_raw.main_peak)
    max_cost = peak ** 2 if max_cost is None else float(max_cost)
    best = None
    tried = []
    for case, f1, f2 in blendable_periods(m1, m2r, rule):
        try:
            s1, s2, support = _truncate(m1, m2r, f1, f2)
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
    if best is None:
        raise ConcatError(f"the motions cannot be concatenated under the {rule} rule: " + "; ".join(tried))
    tmg, case, s1, s2, support, allowed = best
    if tmg.F > max_cost:
        raise ConcatError(f"the motions are too different to blend: F = {tmg.F:.1f} at the best offset "
                          f"exceeds the threshold {max_cost:.1f} (angular momenta {np.sqrt(tmg.F_dm):.1f} "
                          f"kg·m²/s apart at the blending centre)")
    T, fT = tmg.T, tmg.fT
    # the blend window, traced from f_T while ΔL² stays small and inside both periods
    ok1 = np.zeros(m1.clip.num_frames, bool)
    ok1[s1] = True
    ok2 = np.zeros(m2r.clip.num_frames, bool)
    ok2[s2] = True
    thr = (trace_frac * peak) ** 2
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
    want = int(round(min_blend_s * a.fps))

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
    shift = m1.feet_centre[fa] - m2r.feet_centre[fa - T]
    shift[1] = 0.0
    m2 = transformed(m2_raw, theta, shift)
    blended = blend(m1.clip, m2.clip, T, f0, f1, ease=ease)
    Lb = np.linalg.norm(momentum(blended, body).L, axis=1)
    # |L| at the window's ends from the motions themselves (a difference at a
    # window end straddles the blend)
    ends = (float(np.linalg.norm(m1.L[f0])), float(np.linalg.norm(m2.L[f1 - T])))
    s = smoothing_factor(Lb, f0, f1, ends)
    out = blended
    w0, w1 = f0, f1
    applied = None
    if smoothing == "uniform" and abs(s - 1.0) > 1e-6:
        # the paper as printed: the whole window played at rate s
        steps = max(1, int(round((f1 - f0) / s)))
        src = np.concatenate([np.arange(f0, dtype=float), np.linspace(f0, f1, steps + 1),
                              np.arange(f1 + 1, blended.num_frames, dtype=float)])
        out = sample(blended, src)
        w1 = f0 + steps
        applied = {"mode": "uniform", "rate": (f1 - f0) / steps}
    elif smoothing == "profile" and f1 - f0 >= 2:
        # eq. 9's mean reached without a jump in speed at the window's ends: the
        # window is retimed by the rule next = last + 1/ratio(last) (Majkowska &
        # Faloutsos 5.5) with ratio = |L| / the straight line between the ends,
        # so |L| follows that line (its mean is eq. 9's ½(|L(f_t0)| + |L(f_t1)|));
        # measured again and corrected, up to ``passes`` times
        Lw = Lb
        ratios = []
        ease_frames = 2.0
        for _ in range(passes):
            fr = np.arange(w0, w1 + 1, dtype=float)
            line = np.interp(fr, [w0, w1], ends)
            ratio = np.clip(Lw[w0:w1 + 1] / np.maximum(line, 1e-6), 0.05, 20.0)
            # the rate eases back to 1 towards both ends, so the speed does not
            # jump where the window meets the motions
            x = np.minimum(np.arange(ratio.size), np.arange(ratio.size)[::-1]) / ease_frames
            x = np.clip(x, 0.0, 1.0)
            ratio = 1.0 + (ratio - 1.0) * smoothstep(x)
            ratios.append((float(ratio.min()), float(ratio.max())))
            if np.all(np.abs(ratio - 1.0) < tol):
                break
            src2 = ratio_retime_frames(lambda x: float(np.interp(x, fr, ratio)), float(w0), float(w1),
                                       midpoint=True)
            tail = np.arange(src2[-1] + 1.0, out.num_frames - 1 + 1e-9, 1.0)
            out = sample(out, np.concatenate([np.arange(w0, dtype=float), src2, tail]))
            w1 = w0 + src2.size - 1
            Lw = np.linalg.norm(momentum(out, body).L, axis=1)
        applied = {"mode": "profile", "rate": (f1 - f0) / max(w1 - w0, 1), "passes": ratios}
    elif smoothing not in ("uniform", "profile", "none"):
        raise ConcatError(f"smoothing must be 'profile', 'uniform' or 'none', got {smoothing!r}")
    feet = {}
    if fix_feet:
        out, feet = pin_feet(out, body, (w0, w1))
    mo = momentum(out, body)
    Ln = np.linalg.norm(mo.L, axis=1)
    # what an observer of the result sees in its flights (the release of a pinned
    # foot in the air moves a leg there): |L| coefficient of variation per flight
    from ..flight import detect_flights
    flights = [{"takeoff": fl.takeoff, "landing": fl.landing,
                "L_cv_pct": float(100 * Ln[fl.takeoff:fl.landing + 1].std()
                                  / max(Ln[fl.takeoff:fl.landing + 1].mean(), 1e-9))}
               for fl in sorted(detect_flights(out, body, mo.com), key=lambda f: f.takeoff)]
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
        feet=FeetReport(**feet) if feet else None, flights=flights)
    out.meta.update({"name": f"{a.meta.get('name', 'a')}+{b.meta.get('name', 'b')}", "edit": "concatenated"})
    return Concatenation(out, report)


# --------------------------------------------------------- motion-graph baseline
def _cloud(P: np.ndarray, start: np.ndarray, k: int):
    """Windows of k frames of joint positions P (F,J,3) starting at ``start`` (n,):
    horizontal points as complex numbers z + i·x, centred; heights; weights equal."""
    idx = start[:, None] + np.arange(k)[None]
    W = P[idx].reshape(start.size, -1, 3)                 # (n, k·J, 3)
    c = W[..., 2] + 1j * W[..., 0]
    mean = c.mean(axis=1, keepdims=True)
    return c - mean, mean[:, 0], W[..., 1]


def point_cloud_distance(P1: np.ndarray, P2: np.ndarray, s1: np.ndarray, s2: np.ndarray, k: int):
    """Kovar et al.'s distance between the windows of P1 starting at ``s1`` and of
    P2 at ``s2``, all pairs: Σ‖p − T_{θ,x0,z0} p'‖² minimised over a rotation θ
    about the vertical and a ground translation, in closed form (a rotation about
    Y is a multiplication of z + i·x by e^{iθ}).  Returns D (n1,n2), θ (n1,n2)
    and the window means (for the translation)."""
    a, ma, ya = _cloud(P1, s1, k)
    b, mb, yb = _cloud(P2, s2, k)
    cross = a @ np.conj(b).T                              # Σ a·conj(b) for every pair
    D = (np.sum(np.abs(a) ** 2, 1)[:, None] + np.sum(np.abs(b) ** 2, 1)[None]
         - 2 * np.abs(cross)
         + np.sum(ya ** 2, 1)[:, None] + np.sum(yb ** 2, 1)[None] - 2 * ya @ yb.T)
    theta = np.angle(cross)
    return np.maximum(D, 0.0), theta, ma, mb


def motion_graph_join(a: Clip, b: Clip, *, body: Body | None = None, window_s: float = 1 / 3,
                      m1: Motion | None = None, m2: Motion | None = None) -> Concatenation:
    """The motion-graph criterion the paper compares against (its Figures 1, 7, 8):
    a transition from ``a`` to ``b`` at the most similar poses (Kovar et al.'s
    point-cloud distance over a ``window_s`` window), taken after ``a``'s main
    phase has ended and before ``b``'s begins, so both motions are performed in
    full; ``b`` is aligned by the optimal rotation about the vertical and ground
    translation and the window is blended with Kovar's cubic ease."""
    if a.skeleton.joint_names != b.skeleton.joint_names:
        raise ConcatError("the two motions must share a skeleton")
    if abs(a.fps - b.fps) > 1e-9:
        b = sample(b, np.arange(0, b.num_frames - 1 + 1e-9, b.fps / a.fps)).with_fps(a.fps)
    body = body if body is not None else analyse(a).body
    m1 = m1 or prepare(a, body)
    m2 = m2 or prepare(b, body)
    k = max(2, int(round(window_s * a.fps)))
    i0 = m1.phases.main[1] + 1
    j1 = m2.phases.main[0] - k
    s1 = np.arange(min(i0, a.num_frames - k), a.num_frames - k + 1)
    s2 = np.arange(0, max(j1, 0) + 1)
    P1, P2 = a.joint_positions(), b.joint_positions()
    D, th, ma, mb = point_cloud_distance(P1, P2, s1, s2, k)
    ii, jj = np.unravel_index(int(np.argmin(D)), D.shape)
    i, j = int(s1[ii]), int(s2[jj])
    theta = float(th[ii, jj])
    # rotation about Y by θ multiplies z + i·x by e^{iθ}; then the means coincide
    R = yaw(theta)
    mb_rot = mb[jj] * np.exp(1j * theta)
    d = ma[ii] - mb_rot
    shift = np.array([d.imag, 0.0, d.real])
    b2 = rotate(b, R, np.zeros(3))
    b2 = b2.replace(root_pos=b2.root_pos + shift)
    p = (np.arange(k) + 1) / k
    alpha = 2 * p ** 3 - 3 * p ** 2 + 1                    # 1 → 0 (Kovar et al. 2002)
    q = slerp(a.rotations[i:i + k], b2.rotations[j:j + k], (1 - alpha)[:, None])
    root = alpha[:, None] * a.root_pos[i:i + k] + (1 - alpha)[:, None] * b2.root_pos[j:j + k]
    rot = np.concatenate([a.rotations[:i], q, b2.rotations[j + k:]])
    pos = np.concatenate([a.root_pos[:i], root, b2.root_pos[j + k:]])
    out = Clip(a.skeleton, a.fps, pos, rot, None, {**a.meta, "edit": "motion-graph join"})
    return Concatenation(out, MotionGraphReport(transition_a=i, transition_b=j, window=k,
                                                distance=float(D[ii, jj]), theta_deg=float(np.degrees(theta)),
                                                frames=out.num_frames, duration_s=out.duration))


# ---------------------------------------------------------------- mirroring
def mirror_pairs(sk) -> np.ndarray:
    """(J,) index of each joint's left/right partner (itself for the joints on the
    midline), paired by name ('LeftArm' ↔ 'RightArm', 'CC_Base_L_Thigh' ↔
    'CC_Base_R_Thigh', ...)."""
    from ..body import _split_name
    sp = [_split_name(n) for n in sk.joint_names]
    key = {(s, p, sk.depth()[j]): j for j, (s, p) in enumerate(sp) if s}
    out = np.arange(sk.num_joints)
    for j, (s, p) in enumerate(sp):
        if s:
            k = key.get(("r" if s == "l" else "l", p, sk.depth()[j]))
            if k is None:
                raise ConcatError(f"mirror: joint {sk.joint_names[j]!r} has no partner on the other side")
            out[j] = k
    return out


def mirror(clip: Clip, plane: str = "sagittal", body: Body | None = None) -> Clip:
    """The motion mirrored left ↔ right: a right kick becomes a left kick.

    ``plane="sagittal"`` mirrors across the performer's own midline plane at the
    first frame (vertical, through the root, along the torso's facing), so the
    mirrored motion starts where and as the original does; ``plane="x"`` across
    the world's x = 0 plane.  Joints are mirrored in their rest frames (BVH rest
    frames are the world's, and the rest pose is symmetric about its x = 0
    plane): each local rotation R becomes M R M with M = diag(−1, 1, 1), i.e. the
    quaternion (x, y, z, w) → (x, −y, −z, w), left and right joints swap, and the
    root takes the world reflection (R₀ → M_n R₀ M, p → M_n p).  The offsets stay
    the skeleton's own, so an asymmetric rest pose mirrors approximately: the
    largest left/right difference of the rest pose is in
    ``meta['mirror_asymmetry_m']`` (and the joint in ``meta['mirror_asymmetry_joint']``)."""
    sk = clip.skeleton
    pair = mirror_pairs(sk)
    Mx = np.diag([-1.0, 1.0, 1.0])
    if plane == "x":
        Mn = Mx
    elif plane == "sagittal":
        body = body if body is not None else Body.from_skeleton(sk)
        f = torso_facing(clip.slice(0, 1), body)[0]
        lat = np.cross(f, UP)
        lat /= np.linalg.norm(lat)
        Mn = np.eye(3) - 2.0 * np.outer(lat, lat)
    else:
        raise ConcatError(f"mirror plane must be 'sagittal' or 'x', got {plane!r}")
    q = clip.rotations[:, pair] * np.array([1.0, -1.0, -1.0, 1.0])     # M R M for every joint
    Q = Rotation.from_matrix(Mn @ Mx)                                    # a turn about the vertical
    q[:, 0] = (Q * Rotation.from_quat(q[:, 0])).as_quat()                # root: M_n R₀ M
    p0 = clip.root_pos[0]
    root = (np.array(clip.root_pos) - p0) @ Mn.T + p0
    P = sk.rest_positions()
    d = np.linalg.norm(P * np.diag(Mx) - P[pair], axis=1)
    meta = {**clip.meta, "name": f"{clip.meta.get('name', 'clip')}-mirrored",
            "mirror_asymmetry_m": float(d.max()), "mirror_asymmetry_joint": sk.joint_names[int(np.argmax(d))]}
    jp = None if clip.joint_pos is None else clip.joint_pos[:, pair] * np.diag(Mx)
    return clip.replace(root_pos=root, rotations=q, joint_pos=jp, meta=meta)
