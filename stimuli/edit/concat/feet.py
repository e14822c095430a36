"""Foot pinning by analytic two-bone IK (Shum, Komura & Yadav 2009; step 6 of
:mod:`flipstudy.stimuli.edit.concat`): every foot that supports the body over
the transition is held where it stood, the correction let go after it lifts,
nothing below the floor, and the slide left measured.

(The jump controller's legs, :mod:`flipstudy.stimuli.control.ik`, are solved
by cyclic coordinate descent on its own model with joint limits; the analytic
solution here works on any clip's hip, knee and ankle.)

>>> import numpy as np
>>> from flipstudy.stimuli import builtin
>>> from flipstudy.stimuli.edit.concat import two_bone_ik
>>> clip = builtin("backflip")
>>> hip, knee, ankle = (clip.skeleton.index(n) for n in ("LeftUpLeg", "LeftLeg", "LeftFoot"))
>>> target = clip.joint_positions()[:5, ankle] + [0.0, 0.05, 0.0]
>>> moved = two_bone_ik(clip, hip, knee, ankle, np.arange(5), target)
>>> bool(np.allclose(moved.joint_positions()[:5, ankle], target))
True
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ...body import Body
from ...flight import _runs, body_size, effector_points
from ...motion.clip import Clip
from ...physics import center_of_mass
from ..timing import smoothstep
from .motion import _lm_index, foot_contacts
from .result import FeetReport


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
    where the target is in reach (otherwise the leg is stretched towards it).

    Parameters
    ----------
    clip : Clip
    hip, knee, ankle : int
        Joint indices of the leg.
    frames : ndarray of int, shape (n,)
    target : ndarray, shape (n, 3)
    lateral : ndarray, shape (n, 3), optional
        The body's left-right axis, to keep the knee's plane.

    Returns
    -------
    Clip

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> clip = builtin("backflip")
    >>> hip, knee, ankle = (clip.skeleton.index(n) for n in ("LeftUpLeg", "LeftLeg", "LeftFoot"))
    >>> target = clip.joint_positions()[:3, ankle] + [0.02, 0.05, 0.0]
    >>> out = two_bone_ik(clip, hip, knee, ankle, np.arange(3), target)
    >>> bool(np.allclose(out.joint_positions()[:3, ankle], target))
    True
    """
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


def _floor(E0: np.ndarray, ix: dict, fl: np.ndarray, fr: np.ndarray) -> float:
    """The floor: where the feet rest (the lowest point of a foot in contact)."""
    hl = E0[:, [ix["ankle_l"], ix["toe_tip_l"]], 1].min(axis=1)
    hr = E0[:, [ix["ankle_r"], ix["toe_tip_r"]], 1].min(axis=1)
    lows = np.concatenate([hl[fl], hr[fr]])
    return float(np.percentile(lows, 5)) if lows.size else float(min(hl.min(), hr.min()))


def _release(idx: np.ndarray, corr: np.ndarray, to_the_end: bool, nxt: int, fade: int,
             release_in_contact: float, fps: float) -> tuple[np.ndarray, np.ndarray, str]:
    """How a pinned foot's offset ``corr`` (over its contact frames ``idx``) is let go:
    (frames moved, their corrections, how it was released)."""
    e = int(idx[-1])
    if to_the_end:
        return idx, corr, "none (in contact to the end)"   # in contact to the end: stays pinned
    if np.linalg.norm(corr[-1][[0, 2]]) <= release_in_contact:
        # a small offset is let go over the last contact frames (the foot
        # unloading), so the airborne frames stay as they were
        n = min(int(round(0.1 * fps)), max(1, idx.size // 3))
        x = (np.arange(n) + 1) / (n + 1)
        corr[-n:] *= (1.0 - smoothstep(x))[:, None]
        return idx, corr, "in contact"
    # a larger one (the two motions' stances differ) is released as the
    # foot leaves the ground, eased over its swing (at most ``fade_s``),
    # so no supporting foot slides
    tail = np.arange(e + 1, min(nxt, e + 1 + fade))
    x = (np.arange(tail.size) + 1) / (tail.size + 1)
    w = 1.0 - smoothstep(x)
    frames = np.concatenate([idx, tail])
    corr = np.concatenate([corr, w[:, None] * corr[-1][None]])
    return frames, corr, f"in the air ({100 * np.linalg.norm(corr[idx.size - 1][[0, 2]]):.1f} cm)"


def _measured(out: Clip, body: Body, pinned: list, ix: dict, feet_ix: list, floor: float):
    """The slide of the pinned points and the floor clearance, measured, after lifting
    the frames where a foot went under the floor onto it: (clip, slide m, lowest foot)."""
    E = effector_points(out, body)[0]
    slide = 0.0
    for side, idx in pinned:
        x = E[idx, ix[f"toe_tip_{side}"]]
        slide = max(slide, float(np.linalg.norm((x - x[0])[:, [0, 2]], axis=1).max()))
    lo = float(E[..., 1][:, feet_ix].min())
    if lo < floor - 1e-4:
        lift = np.maximum(floor - E[..., 1][:, feet_ix].min(axis=1), 0.0)
        root = out.root_pos.copy()
        root[:, 1] += lift
        out = out.replace(root_pos=root)
        E = effector_points(out, body)[0]
        lo = float(E[..., 1][:, feet_ix].min())
    return out, slide, lo


def pin_feet(clip: Clip, body: Body, window: tuple[int, int], fade_s: float = 0.5,
             floor: float | None = None, release_in_contact: float = 0.01) -> tuple[Clip, FeetReport]:
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
    Returns the clip and a :class:`FeetReport`: the measured slide (horizontal
    motion of the pinned points while in contact, cm) and floor clearance.

    Parameters
    ----------
    clip : Clip
    body : Body
    window : tuple of int
    fade_s, release_in_contact : float
    floor : float, optional

    Returns
    -------
    Clip, FeetReport

    Examples
    --------
    >>> from flipstudy.stimuli import analyse, builtin
    >>> clip = builtin("backflip")
    >>> out, rep = pin_feet(clip, analyse(clip).body, (0, 20))
    >>> rep.pinned, rep.released, rep.foot_slide_cm < 1.0
    (['l:0-158', 'r:0-158'], ['in contact', 'in contact'], True)
    """
    f0, f1 = window
    F = clip.num_frames
    fl, fr = foot_contacts(clip, body)
    E0, names = effector_points(clip, body)
    ix = {n: i for i, n in enumerate(names)}
    feet_ix = [ix["ankle_l"], ix["ankle_r"], ix["toe_tip_l"], ix["toe_tip_r"]]
    if floor is None:
        floor = _floor(E0, ix, fl, fr)
    fade = max(1, int(round(fade_s * clip.fps)))
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
            frames, corr, how = _release(idx, corr, e == F - 1, nxt, fade, release_in_contact, clip.fps)
            released.append(how)
            out = two_bone_ik(out, hip, knee, ankle, frames, ank[frames] + corr, lat[frames])
            pinned.append((side, idx))
            air[frames[idx.size:]] = True
    # a leg moved in the air must not move the body's COM off its path there: where
    # no foot touches, the root is shifted so the COM is where it was before the IK
    air &= ~(fl | fr)
    if air.any():
        d = center_of_mass(clip, body)[air] - center_of_mass(out, body)[air]
        root = out.root_pos.copy()
        root[air] += d
        out = out.replace(root_pos=root)
    out, slide, lo = _measured(out, body, pinned, ix, feet_ix, floor)
    return out, FeetReport(foot_slide_cm=100.0 * slide,
                           pinned=[f"{sd}:{int(i[0])}-{int(i[-1])}" for sd, i in pinned], released=released,
                           floor=floor, lowest_foot_above_floor_cm=100.0 * (lo - floor))
