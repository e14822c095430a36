"""What a built jump is checked for (Ooi 2016, 3.6; :func:`check`): rays cast
down from the soles find the touch-down (it must be the planned frame), no body
point may enter a box in flight, the feet stay still in the windup and the
balls of the feet in the thrust, and the feet land on the target.
"""
from __future__ import annotations

import numpy as np

from flipstudy.errors import FlipstudyValueError
from ..motion.clip import Clip
from .course import Course
from .model import SIDES, Jumper
from .stages import Stages

RAY_TOLERANCE = 5e-4            # m: a sole this close to the surface under it touches it
#: the fields of the report that :func:`check` fills
CHECKED = ("touchdown_detected", "lowest_sole_gap_m", "obstacle_clearance_m", "windup_foot_motion_m",
           "thrust_ball_motion_m", "windup_lowest_sole_m", "landing_point", "landing_error_m")


def sole_points(jumper: Jumper, clip: Clip) -> np.ndarray:
    """(F,6,3) heel, ball and toe tip of both feet."""
    j = jumper
    pts, loc = [], []
    for s in SIDES:
        a, t = j.idx[f"ankle_{s}"], j.idx[f"toe_{s}"]
        pts += [a, t, t]
        loc += [np.array([0.0, -j.ankle_height, -j.heel_back]), np.zeros(3), j.toe_tip]
    return clip.points(np.array(pts), np.array(loc))


def check(jumper: Jumper, sc: Course, clip: Clip, stages: Stages) -> dict:
    """Ray casts for contact, collisions with boxes, foot motion in the windup,
    landing error: the fields of :class:`.controller.JumpReport` they fill.
    Raises :class:`~flipstudy.errors.FlipstudyValueError` when the
    feet meet a surface before the planned touch-down or the body a box."""
    i_to, i_td = stages.takeoff, stages.touchdown
    F1 = np.asarray(sc.target, float)
    soles = sole_points(jumper, clip)
    F = clip.num_frames
    xz = soles[..., [0, 2]].reshape(-1, 2)
    gap = soles[..., 1] - sc.surface(xz).reshape(F, -1)
    # contact: the first frame after take-off where a ray down from a sole point
    # meets the surface under it (within RAY_TOLERANCE)
    after = np.arange(F) > i_to
    hit = np.nonzero(after & (gap.min(axis=1) <= RAY_TOLERANCE))[0]
    td_detected = int(hit[0]) if hit.size else None
    if td_detected is None or td_detected != i_td:
        raise FlipstudyValueError(f"landing: the feet meet a surface at frame {td_detected}, not at the "
                                  f"planned touch-down {i_td}; the jump hits something: use a longer --air")
    below = float(gap.min())
    # collisions in flight: body points inside a box
    P = clip.joint_positions()
    E = clip.end_site_positions()
    pts = np.concatenate([P, E, soles], axis=1)[i_to:i_td]
    clear = np.inf
    for b in sc.boxes:
        if np.any(b.contains(pts, margin=0.005)):
            fr = i_to + int(np.nonzero(b.contains(pts, 0.005).any(1))[0][0])
            raise FlipstudyValueError(f"the jump hits the box {b.to_list()} at frame {fr}; use a longer "
                                      f"--air, another target or --scene")
        top = b.hi[1]
        if top <= F1[1] + 1e-9 and b.contains(np.array([F1[0], top - 0.01, F1[2]])):
            continue                                      # the box landed on: the ray casts check it
        xzin = ((pts[..., 0] >= b.lo[0]) & (pts[..., 0] <= b.hi[0]) &
                (pts[..., 2] >= b.lo[2]) & (pts[..., 2] <= b.hi[2]))
        if xzin.any():
            clear = min(clear, float((pts[..., 1][xzin] - top).min()))
    # windup: feet still (every sole point); thrust: the balls of the feet still
    w0, w1 = stages.windup_frames
    ws = soles[w0:w1 + 1]
    foot_motion = float(np.linalg.norm(ws - ws[:1], axis=-1).max())
    th = soles[w1 + 1:i_to][:, [1, 4]]
    ball_motion = float(np.linalg.norm(th - soles[w0][None, [1, 4]], axis=-1).max()) if len(th) else 0.0
    ank = P[i_td, [jumper.idx["ankle_l"], jumper.idx["ankle_r"]]].mean(0)
    land = np.array([ank[0], soles[i_td, :, 1].mean(), ank[2]])
    return {"touchdown_detected": td_detected, "lowest_sole_gap_m": below,
            "obstacle_clearance_m": None if not np.isfinite(clear) else clear,
            "windup_foot_motion_m": foot_motion, "thrust_ball_motion_m": ball_motion,
            "windup_lowest_sole_m": float(gap[w0:w1 + 1].min()),
            "landing_point": land.tolist(), "landing_error_m": float(np.linalg.norm(land - F1))}
