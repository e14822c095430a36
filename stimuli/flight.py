"""Ballistic (flight) phase detection, after Section 4.1 of Majkowska & Faloutsos.

1. **Contact from end effectors.**  Toe tips, ankles, finger tips and wrists that
   are nearly still *and* low (near the level where that effector rests) are in
   contact.  Hands count: the hand-supported phases of a round-off or a
   handspring are not flight.
2. **Candidates** are the runs of frames with no effector in contact.
3. **Ballistic check.**  In flight the COM moves on a line horizontally and a
   parabola vertically.  The ends of each candidate are trimmed while the COM
   there leaves the fitted path by much more than it does inside (the ground
   still pushing at take-off, already braking at landing: the paper's momentum
   build-up/release pattern); a candidate whose COM does not fit a downward
   parabola within ``tol`` (RMS) is not a flight.
4. **Contact instants.**  Around each surviving flight the lowest point of the
   body (toe tips, balls of the feet, ankles, hand tips, wrists: the points that
   were in contact just before / just after) is followed relative to its own
   support level (its median height while in contact there: the floor, a box
   top, the hands' floor).  Take-off is the last frame before the flight where
   that clearance is within the measurement noise of the support, landing the
   first after it; the instants are the sub-frame zero crossings of the
   clearance, clipped to the frame interval beside that contact frame (the
   built-ins' exact instants lie on frames and are recovered exactly).  The
   flight's frames are those strictly between the instants.
5. The flight is the longest surviving interval; all of them are reported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .body import Body
from .motion.clip import Clip, finite_difference


@dataclass
class Flight:
    """A ballistic phase: ``takeoff`` and ``landing`` are the first and last
    frames strictly inside the airborne span (inclusive); ``takeoff_time`` and
    ``landing_time`` are the contact instants in seconds (sub-frame): the
    lowest point of the body leaves / reaches its support.  The COM fit is
    y = a t² + b t + c with t in seconds from the take-off frame, x and z
    linear, fitted to the frames strictly inside."""

    takeoff: int
    landing: int
    coef: np.ndarray          # (3,3): rows x,y,z; columns t², t, 1
    rms: float                # COM residual from the fitted path, metres
    takeoff_time: float = float("nan")
    landing_time: float = float("nan")

    @property
    def frames(self) -> int:
        return self.landing - self.takeoff + 1

    def apparent_gravity(self) -> float:
        return float(-2.0 * self.coef[1, 0])


def effector_points(clip: Clip, body: Body) -> tuple[np.ndarray, list[str]]:
    """(F,E,3) world positions of the contact candidates: toe tips, ankles, hand
    tips and wrists of both sides."""
    sk = clip.skeleton
    lm = body.landmarks
    joints, local, names = [], [], []
    for key in ("toe_tip_l", "toe_tip_r", "ankle_l", "ankle_r",
                "hand_tip_l", "hand_tip_r", "wrist_l", "wrist_r"):
        v = lm[key]
        if isinstance(v, str):
            joints.append(sk.index(v))
            local.append(np.zeros(3))
        else:
            j, e = v
            joints.append(sk.index(j))
            local.append(sk.end_sites[e][1] if e is not None else np.zeros(3))
        names.append(key)
    return clip.points(np.array(joints), np.array(local)), names


def contact_mask(clip: Clip, body: Body, v_thr: float = 1.0, margin: float = 0.10,
                 touch: float = 0.03, min_stand: float = 0.3) -> np.ndarray:
    """(F,E) bool contact of the effectors of :func:`effector_points`.

    An effector is in contact when it is nearly still (speed < ``v_thr`` m/s)
    within ``margin`` metres of its own resting level (the 5th percentile of its
    height over the frames where it is still), or — at any speed — within
    ``touch`` metres of it (a foot landing or pushing off touches the floor
    before it stops or after it starts moving).  The touch rule applies to hands
    only when they rest on the floor somewhere in the clip.  Feet standing still
    for ``min_stand`` seconds on something higher than their resting level (a
    box top) are in contact there too (see :func:`_raised_contact`)."""
    P, names = effector_points(clip, body)
    speed = np.linalg.norm(finite_difference(P, clip.fps), axis=-1)
    still = speed < v_thr
    h = P[..., 1]
    masked = np.where(still, h, np.nan)
    with np.errstate(all="ignore"):
        rest = np.nanpercentile(masked, 5, axis=0) if still.any() else np.full(h.shape[1], np.nan)
    rest = np.where(np.isfinite(rest), rest, np.nanmin(h, axis=0))
    feet = np.array([n.startswith(("toe", "ankle")) for n in names])
    floor = rest[feet].min()
    touches = feet | (rest < floor + 0.35)
    contact = (still & (h < rest[None] + margin)) | (touches[None] & (h < rest[None] + touch))
    return contact | _raised_contact(h, still, feet, rest, clip.fps, margin, touch, min_stand)


def _raised_contact(h, still, feet, rest, fps, margin, touch, min_stand):
    """Contact of feet on a raised surface (a box top): a foot that stands still
    for ``min_stand`` seconds higher than its resting level + ``margin`` stands on
    something; during such a stand and 0.15 s either side it is in contact when
    still within ``margin`` of that level, or at any speed within ``touch`` of it
    (landing on the box, pushing off it)."""
    F, E = h.shape
    out = np.zeros((F, E), bool)
    n_min = max(2, int(round(min_stand * fps)))
    for e in np.flatnonzero(feet):
        stands = [(a, b, float(np.percentile(h[a:b + 1, e], 5))) for a, b in _runs(still[:, e])
                  if b - a + 1 >= n_min]
        stands = [(a, b, lv) for a, b, lv in stands if lv > rest[e] + margin]
        if not stands:
            continue
        # the stand's own frames and a short time either side (stepping off, landing
        # on): a foot passing that height elsewhere (falling past a box) is not on it
        w = max(1, int(round(0.15 * fps)))
        prev = np.full(F, np.nan)
        nxt = np.full(F, np.nan)
        for a, b, lv in stands:
            prev[a:min(F, b + 1 + w)] = lv
        for a, b, lv in reversed(stands):
            nxt[max(0, a - w):b + 1] = lv
        for lv in (prev, nxt):
            ok = np.isfinite(lv)
            d = np.where(ok, h[:, e] - lv, np.inf)
            out[:, e] |= ok & ((still[:, e] & (np.abs(d) < margin)) | (np.abs(d) < touch))
    return out


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Inclusive (start, end) of the runs of True."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    starts = np.nonzero(d == 1)[0]
    ends = np.nonzero(d == -1)[0] - 1
    return list(zip(starts.tolist(), ends.tolist()))


def trim_to_ballistic(com: np.ndarray, fps: float, min_frames: int, k: float = 3.0,
                      floor: float = 0.015):
    """Trim the ends of a candidate flight while the COM there leaves the fitted
    ballistic path: an end frame whose residual exceeds ``max(k × median
    residual, floor)`` is still being pushed by the ground (take-off) or already
    stopped by it (landing).  Returns (start, end, rms) relative to ``com`` or
    None when too little is left.  Each step is one vectorised fit; there are at
    most as many steps as trimmed frames."""
    s, e = 0, com.shape[0] - 1
    while e - s + 1 >= min_frames:
        seg = com[s:e + 1]
        coef = fit_path(seg, fps)
        r = np.linalg.norm(seg - path_values(coef, np.arange(seg.shape[0]) / fps), axis=1)
        thr = max(k * float(np.median(r)), floor)
        if r[0] > thr and r[0] >= r[-1]:
            s += 1
        elif r[-1] > thr:
            e -= 1
        elif r[0] > thr:
            s += 1
        else:
            return s, e, float(np.sqrt(np.mean(r ** 2))), coef
    return None


def fit_path(com: np.ndarray, fps: float) -> np.ndarray:
    """(3,3) least-squares ballistic path of ``com`` (N,3): rows x,y,z, columns
    t², t, 1 (t from the first frame, seconds); x and z have no t² term."""
    t = np.arange(com.shape[0]) / fps
    coef = np.zeros((3, 3))
    A = np.stack([t ** 2, t, np.ones_like(t)], 1)
    coef[1] = np.linalg.lstsq(A, com[:, 1], rcond=None)[0]
    for ax in (0, 2):
        coef[ax, 1:] = np.linalg.lstsq(A[:, 1:], com[:, ax], rcond=None)[0]
    return coef


def path_values(coef: np.ndarray, t: np.ndarray) -> np.ndarray:
    return coef[:, 0][None] * t[:, None] ** 2 + coef[:, 1][None] * t[:, None] + coef[:, 2][None]


def body_size(clip: Clip) -> float:
    """Largest extent of the rest skeleton in metres (height, or span in a T-pose)."""
    sk = clip.skeleton
    P = sk.rest_positions()
    if sk.end_sites:
        P = np.concatenate([P, np.array([P[p] + o for p, o in sk.end_sites])])
    ext = float(np.max(P.max(0) - P.min(0)))
    return ext if ext > 0 else 1.7


def foot_points(clip: Clip, body: Body) -> tuple[np.ndarray, list[str]]:
    """(F,K,3) the points whose contact is followed at take-off and landing: the
    effectors of :func:`effector_points` and the balls of the feet (the toe
    joint, when the toe tip is an end site of it)."""
    P, names = effector_points(clip, body)
    sk, lm = clip.skeleton, body.landmarks
    extra, en = [], []
    for key in ("toe_tip_l", "toe_tip_r"):
        v = lm[key]
        if not isinstance(v, str) and v[1] is not None:
            extra.append(sk.index(v[0]))
            en.append(key.replace("toe_tip", "ball"))
    if extra:
        P = np.concatenate([P, clip.joint_positions()[:, extra]], axis=1)
        names = names + en
    return P, names


def contact_instants(h: np.ndarray, contact: np.ndarray, com_y: np.ndarray, fps: float,
                     s: int, e: int, size: float = 1.0, window: float = 0.25,
                     eps_min: float = 2e-4, eps_max: float = 0.02, g: float = 9.81
                     ) -> tuple[float, float]:
    """Take-off and landing instants (seconds) of the airborne run ``s..e``.

    ``h`` (F,K) heights of the followed points, ``contact`` (F,K) their contact
    (a ball follows its toe tip), ``com_y`` (F,) the COM height.  On each side
    the points in contact within ``window`` seconds of the run give the
    support: each its median height there.  The clearance is the lowest point's
    height above its support.  The contact frame is bracketed by geometry: the
    last (take-off) / first (landing) frame whose clearance is within the
    measurement noise (5 robust σ of the supporting points' frame-to-frame
    jitter, at least ``eps_min`` × ``size`` m) and the one within ``eps_max`` ×
    ``size`` (captured markers sit off the skin and drift on a rolling foot);
    inside the bracket the COM decides: the contact frame is the latest
    (take-off) / earliest (landing) whose COM acceleration (the second
    difference reaching into the flight side) is not yet / already away from
    free fall (above −g/2).  The instant is the
    zero crossing of the clearance on the frame interval beside the contact
    frame (clipped to it).  A run touching the clip's start or end has its
    instant half a frame outside the first/last frame."""
    F = h.shape[0]
    w = max(3, int(round(window * fps)))
    # one-sided second differences reaching toward the flight: a frame is still
    # pushed (take-off) / already braked (landing) when its COM leaves the path
    # through the next (previous) two frames
    acc_to = np.full(F, -np.inf)
    acc_ld = np.full(F, -np.inf)
    if F >= 3:
        a2 = (com_y[2:] - 2 * com_y[1:-1] + com_y[:-2]) * fps ** 2
        acc_to[:-2] = a2
        acc_ld[2:] = a2

    def clearance(lo, hi):
        sel = contact[lo:hi]
        pts = np.flatnonzero(sel.any(0))
        if pts.size == 0:
            return None, None
        lev = np.array([np.median(h[lo:hi][sel[:, k], k]) for k in pts])
        d = (h[:, pts] - lev[None]).min(axis=1)
        hh, ss = h[lo:hi, pts], sel[:, pts]
        dd = np.diff(hh, 2, axis=0)[ss[:-2] & ss[1:-1] & ss[2:]] if hh.shape[0] >= 3 else []
        sig = (1.4826 * float(np.median(np.abs(dd - np.median(dd)))) / np.sqrt(6.0)
               if len(dd) else 0.0)
        eps = max(5.0 * sig, eps_min * size)
        return d, min(eps, eps_max * size)

    d = clearance(max(0, s - w), s)[0] if s > 0 else None
    if d is None:
        t_to = s - 0.5
    else:
        eps = clearance(max(0, s - w), s)[1]
        head = d[:s + 1]
        lo_ = int(np.flatnonzero(head <= eps)[-1]) if (head <= eps).any() else s - 1
        hi_ = int(np.flatnonzero(head <= eps_max * size)[-1]) if (head <= eps_max * size).any() else lo_
        hi_ = max(hi_, lo_)
        push = np.flatnonzero(acc_to[lo_:hi_ + 1] > -g / 2)
        f0 = min(lo_ + int(push[-1]) if push.size else lo_, F - 2)
        den = d[f0 + 1] - d[f0]
        t_to = f0 + (float(np.clip(-d[f0] / den, 0.0, 1.0)) if den > 0 else 0.0)
    d = clearance(e + 1, min(F, e + 1 + w)) if e < F - 1 else (None, None)
    d, eps = d
    if d is None:
        t_ld = e + 0.5
    else:
        tail = d[e:]
        lo_ = e + int(np.flatnonzero(tail <= eps_max * size)[0]) if (tail <= eps_max * size).any() else e + 1
        hi_ = e + int(np.flatnonzero(tail <= eps)[0]) if (tail <= eps).any() else lo_
        hi_ = max(hi_, lo_)
        brake = np.flatnonzero(acc_ld[lo_:hi_ + 1] > -g / 2)
        f1 = max(lo_ + int(brake[0]) if brake.size else hi_, 1)
        den = d[f1 - 1] - d[f1]
        t_ld = f1 - (float(np.clip(d[f1] / den, 0.0, 1.0)) if den > 0 else 0.0)
    return t_to / fps, t_ld / fps


def detect_flights(clip: Clip, body: Body, com: np.ndarray | None = None, *,
                   v_thr: float = 1.0, margin: float = 0.10, tol: float = 0.06,
                   min_duration: float = 0.1) -> list[Flight]:
    """All ballistic phases of a clip, longest first (empty list: no flight)."""
    from .physics import center_of_mass
    if com is None:
        com = center_of_mass(clip, body)
    # thresholds are for an adult of 1.7 m; a bigger (retargeted or mis-scaled)
    # skeleton gets proportionally larger ones
    size = body_size(clip) / 1.7
    v_thr, margin, tol = v_thr * size, margin * size, tol * size
    contact = contact_mask(clip, body, v_thr=v_thr, margin=margin, touch=0.03 * size)
    airborne = ~contact.any(axis=1)
    P, names = foot_points(clip, body)
    H = P[..., 1]
    ne = contact.shape[1]
    C = np.concatenate([contact, contact[:, [names.index(n.replace("ball", "toe_tip"))
                                             for n in names[ne:]]]], axis=1)
    min_frames = max(4, int(np.ceil(min_duration * clip.fps)))
    flights = []
    for s, e in _runs(airborne):
        if e - s + 1 < min_frames:
            continue
        found = trim_to_ballistic(com[s:e + 1], clip.fps, min_frames)
        if found is None:
            continue
        a, b, rms, coef = found
        if rms > tol or coef[1, 0] >= 0:      # not ballistic: no downward parabola
            continue
        t_to, t_ld = contact_instants(H, C, com[:, 1], clip.fps, s, e, size)
        to = int(np.floor(t_to * clip.fps + 1e-6)) + 1
        ld = int(np.ceil(t_ld * clip.fps - 1e-6)) - 1
        # the instants cannot cut into the ballistic core, and the frames they add
        # to it must follow its COM path within 5× the core's median residual or
        # 5 cm (a hand still on the floor, which the effector rule missed, keeps
        # the COM far off it)
        to, ld = min(max(to, 0), s + a), max(min(ld, clip.num_frames - 1), s + b)
        core = com[s + a:s + b + 1]
        t_core = np.arange(core.shape[0]) / clip.fps
        r_core = np.linalg.norm(core - path_values(coef, t_core), axis=1)
        thr = max(5.0 * float(np.median(r_core)), 0.05 * size)
        fr = np.arange(to, ld + 1)
        r = np.linalg.norm(com[fr] - path_values(coef, (fr - (s + a)) / clip.fps), axis=1)
        off = r > thr
        pre, post = off[:s + a - to], off[s + b + 1 - to:]
        if pre.any():                 # the geometry missed a contact: mid-interval
            to = to + int(np.flatnonzero(pre)[-1]) + 1
            t_to = (to - 0.5) / clip.fps
        if post.any():
            ld = s + b + int(np.flatnonzero(post)[0])
            t_ld = (ld + 0.5) / clip.fps
        t_to = min(t_to, (to - 0.5) / clip.fps)
        t_ld = max(t_ld, (ld + 0.5) / clip.fps)
        seg = com[to:ld + 1]
        coef = fit_path(seg, clip.fps)
        r = np.linalg.norm(seg - path_values(coef, np.arange(seg.shape[0]) / clip.fps), axis=1)
        flights.append(Flight(to, ld, coef, float(np.sqrt(np.mean(r ** 2))), t_to, t_ld))
    flights.sort(key=lambda f: -f.frames)
    return flights
