"""Animator edits in flight and their momentum repair (Majkowska & Faloutsos
2007, Section 5.5).

An animator changes the pose in flight — here by overriding joint rotations,
e.g. straightening the legs of a tucked flip (:func:`override_joints`, blended
in and out).  The inertia changes, so with the old timing |L| is no longer
conserved.  :func:`repair_momentum` retimes the flight non-uniformly with the
paper's rule ``next_frame = last_frame + 1/ratio(last_frame)``, ratio(f) =
|L_modified(f)| / |L_original(f)|, where in-between frames are interpolated
(slerp) and their angular momentum computed from the interpolated poses; then
the COM is put back on an exact parabola for the new flight duration, keeping
the take-off velocity's direction scaled to the new flight time, and everything
after landing follows on.
"""
from __future__ import annotations

from flipstudy.errors import AnimatorEditError
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..analyse import Analysis
from ..motion.clip import Clip, derived_meta
from ..physics import center_of_mass, momentum
from ..result import Result
from .report import Report
from .reposition import ballistic_path
from .timing import ratio_retime_frames, sample

#: joint groups an animator can straighten, by body landmark
GROUPS = {"legs": ("hip_l", "knee_l", "hip_r", "knee_r"),
          "arms": ("shoulder_l", "elbow_l", "shoulder_r", "elbow_r")}


def override_joints(clip: Clip, joints, target: np.ndarray, t0: float, t1: float,
                    blend: float = 0.08) -> Clip:
    """``clip`` with the local rotations of ``joints`` (indices) turned towards
    ``target`` ((len(joints), 4) quaternions) between ``t0`` and ``t1`` seconds:
    blended in over ``blend`` s after ``t0``, held, blended out over ``blend`` s
    before ``t1`` (smoothstep weights, slerp)."""
    if not (0 <= t0 < t1 <= clip.duration):
        raise AnimatorEditError(f"edit times must satisfy 0 <= from < to <= {clip.duration:.3f} s, "
                                f"got {t0!r}, {t1!r}")
    joints = np.asarray(joints, int)
    t = clip.times
    b = max(min(blend, (t1 - t0) / 2), 1e-9)
    w = np.clip(np.minimum((t - t0) / b, (t1 - t) / b), 0.0, 1.0)
    w = w * w * (3.0 - 2.0 * w)                                     # (F,)
    cur = Rotation.from_quat(clip.rotations[:, joints].reshape(-1, 4))
    tgt = Rotation.from_quat(np.broadcast_to(target, (clip.num_frames,) + np.shape(target)).reshape(-1, 4))
    rel = (cur.inv() * tgt).as_rotvec() * np.repeat(w, joints.size)[:, None]
    rot = clip.rotations.copy()
    rot[:, joints] = (cur * Rotation.from_rotvec(rel)).as_quat().reshape(clip.num_frames, joints.size, 4)
    return clip.replace(rotations=rot, meta=derived_meta(clip.meta, "override joints"))


def straighten(a: Analysis, group: str = "legs", t0: float | None = None, t1: float | None = None,
               blend: float = 0.16) -> Clip:
    """The analysed clip with a joint group (``"legs"``: hips and knees, ``"arms"``)
    held straight — as in the clip's first frame, standing — from ``t0`` to ``t1``
    seconds (default: 0.1 s after take-off to 0.1 s before landing).

    Parameters
    ----------
    a : Analysis
    group : {"legs", "arms"}
    t0, t1 : float, optional
        Seconds.
    blend : float
        Seconds over which the hold blends in and out.

    Returns
    -------
    Clip

    Examples
    --------
    >>> from flipstudy import analyse, builtin
    >>> a = analyse(builtin("backflip"))
    >>> straight = straighten(a)                    # the tuck's legs held straight
    >>> straight.num_frames == a.clip.num_frames
    True
    """
    if group not in GROUPS:
        raise AnimatorEditError(f"unknown joint group {group!r}; expected one of {sorted(GROUPS)}")
    sk = a.clip.skeleton
    joints = [sk.index(a.body.landmarks[k]) for k in GROUPS[group]]
    if a.flight is None:
        raise AnimatorEditError("the clip has no flight phase to edit")
    t0 = a.takeoff / a.clip.fps + 0.1 if t0 is None else float(t0)
    t1 = a.landing / a.clip.fps - 0.1 if t1 is None else float(t1)
    return override_joints(a.clip, joints, a.clip.rotations[0, joints], t0, t1, blend)


@dataclass
class RepairReport(Report):
    """What :func:`repair_momentum` did: the retiming rule, the largest |L| error
    of the edit before and after, flight time and jump height before and after."""
    rule: str
    max_error_before_pct: float
    max_error_after_pct: float
    flight_s_before: float
    flight_s_after: float
    jump_height_before_m: float
    jump_height_after_m: float


@dataclass
class Repair(Result[RepairReport]):
    """The repaired clip, its flight and the :class:`RepairReport`
    (:func:`repair_momentum`), with the retiming and the errors per frame."""
    src: np.ndarray              # fractional frame of the edited clip shown at each new frame
    error_before: np.ndarray     # |L| relative error per flight frame of the edit, before
    error_after: np.ndarray      # ... after the repair (against the original at the same source frame)


def _L_on_grid(clip: Clip, body, start: int, stop: int, sub: int) -> tuple[np.ndarray, np.ndarray]:
    """|L| at fractional frames start, start + 1/sub, ..., stop, from interpolated
    poses (velocities by differences at the fine step)."""
    grid = np.arange(start * sub, stop * sub + 1) / sub
    fine = sample(clip, grid).with_fps(clip.fps * sub)
    return grid, np.linalg.norm(momentum(fine, body).L, axis=1)


def retime_flight(clip: Clip, body, to: int, ld: int, grid: np.ndarray, ratio: np.ndarray,
                  path: np.ndarray, midpoint: bool = False, keep_landing_point: bool = True):
    """The flight ``to..ld`` of ``clip`` retimed by ``next = last + 1/ratio(last)``
    (``ratio`` sampled at fractional frames ``grid``), the rest at rate 1, then the
    flight's COM put on the exact parabola of the new duration (gravity and
    horizontal velocity from ``path``, the flight's fitted COM path; with
    ``keep_landing_point`` the horizontal velocity is scaled so the flight lands
    where it did).  Returns (clip, source frames, new landing frame, new flight
    seconds, take-off vertical velocity)."""
    fps = clip.fps

    def r_of(f):
        return float(np.interp(f, grid, ratio))

    flight = ratio_retime_frames(r_of, float(to), float(ld), midpoint=midpoint)
    tail = np.arange(flight[-1] + 1.0, clip.num_frames - 1 + 1e-9, 1.0)
    src = np.concatenate([np.arange(to, dtype=float), flight, tail])
    new = sample(clip, src)
    ld_n = to + flight.size - 1
    G = -2.0 * path[1, 0]
    com = center_of_mass(new, body)
    Tn = (ld_n - to) / fps
    c0, y_end = com[to].copy(), com[ld_n, 1]
    vy = (y_end - c0[1] + 0.5 * G * Tn ** 2) / Tn
    vh = path[[0, 2], 1] * (((ld - to) / fps) / Tn if keep_landing_point else 1.0)
    target = ballistic_path(c0, np.array([vh[0], vy, vh[1]]), G, np.arange(ld_n - to + 1) / fps)
    shift = np.zeros_like(new.root_pos)
    shift[to:ld_n + 1] = target - com[to:ld_n + 1]
    shift[ld_n + 1:] = shift[ld_n]
    return new.replace(root_pos=new.root_pos + shift), src, ld_n, Tn, vy


def repair_momentum(original: Analysis, edited: Clip, sub: int = 8, midpoint: bool = False) -> Repair:
    """Retime the flight of ``edited`` (the original's timing, poses changed by an
    animator) so its |L| follows the original's again, then reposition the COM.
    ``sub``: in-between frames per frame for the ratio; ``midpoint``: the
    second-order variant of the paper's rule (see :func:`ratio_retime_frames`).

    Parameters
    ----------
    original : Analysis
    edited : Clip
        The original's timing, poses changed.
    sub : int
    midpoint : bool

    Returns
    -------
    Repair

    Examples
    --------
    >>> from flipstudy import analyse, builtin
    >>> a = analyse(builtin("backflip"))
    >>> fixed = repair_momentum(a, straighten(a))
    >>> type(fixed).__name__, fixed.takeoff < fixed.landing
    ('Repair', True)
    """
    body, fps = original.body, original.clip.fps
    to, ld = original.takeoff, original.landing
    if edited.num_frames != original.clip.num_frames:
        raise AnimatorEditError("the edited clip must have the original's frames (an edit, not a retime)")
    g0, L_orig = _L_on_grid(original.clip, body, to, ld, sub)
    g1, L_mod = _L_on_grid(edited, body, to, ld, sub)
    ratio = L_mod / L_orig
    if not (np.all(np.isfinite(ratio)) and ratio.min() > 0.05 and ratio.max() < 20):
        raise AnimatorEditError(f"the edit changes |L| by a factor {ratio.min():.2f}–{ratio.max():.2f}: "
                                f"too much for retiming (blend the edit in and out more slowly, or "
                                f"keep it inside the flight)")

    out, src, ld_n, Tn, vy = retime_flight(edited, body, to, ld, g1, ratio, original.path,
                                           midpoint=midpoint)
    out = out.replace(meta=derived_meta(out.meta, "animator edit, momentum repaired"))
    path, G, T0 = original.path, -2.0 * original.path[1, 0], (ld - to) / fps
    # errors, per frame, against the original at the same source frame
    L_new = np.linalg.norm(momentum(out, body).L, axis=1)
    k = np.arange(to + 2, ld_n - 1)
    err_after = L_new[k] / np.interp(src[k], g0, L_orig) - 1.0
    kb = np.arange(to + 2, ld - 1)
    L_ed = np.linalg.norm(momentum(edited, body).L, axis=1)
    err_before = L_ed[kb] / np.linalg.norm(original.L[kb], axis=1) - 1.0
    rep = RepairReport(rule="midpoint" if midpoint else "paper",
                       max_error_before_pct=float(100 * np.abs(err_before).max()),
                       max_error_after_pct=float(100 * np.abs(err_after).max()),
                       flight_s_before=T0, flight_s_after=Tn,
                       jump_height_before_m=float(path[1, 1] ** 2 / (2 * G)),
                       jump_height_after_m=float(vy ** 2 / (2 * G)))
    return Repair(out, to, ld_n, rep, src=src, error_before=err_before, error_after=err_after)
