"""The built-in humanoid skeleton with anthropometric proportions.

Segment lengths are fractions of the standing height ``H`` after Winter
(*Biomechanics and Motor Control of Human Movement*, Fig. 4.1, after Drillis &
Contini): thigh 0.245 H, shank 0.246 H, ankle height 0.039 H, foot length
0.152 H, upper arm 0.186 H, forearm 0.146 H, hand 0.108 H, shoulder width
0.259 H, hip width 0.191 H, hip joint → shoulder joint 0.288 H, neck + head
0.182 H (shoulder level 0.818 H to the vertex at H).  The hip width is the
bitrochanteric width; the hip *joint centres* sit 0.55 of it apart (0.105 H).
The shoulder joint centres are 0.259 H apart.

Rest pose: standing upright, arms hanging down, facing +Z with the left side at
+X (Y up, right-handed), the lowest foot points (ball of the foot and toe tip)
on the floor ``y = 0``.  Joint names follow the CMU convention so
:meth:`flipstudy.stimuli.body.Body.from_skeleton` maps the skeleton without a mapping.
"""

from __future__ import annotations

import numpy as np

from ..motion.skeleton import Skeleton

ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation")
JOINT_CHANNELS = ("Zrotation", "Yrotation", "Xrotation")

#: Winter's segment-length fractions of height used by :func:`make_skeleton`.
FRACTIONS = {
    "thigh": 0.245, "shank": 0.246, "ankle_height": 0.039, "foot_length": 0.152,
    "upper_arm": 0.186, "forearm": 0.146, "hand": 0.108, "shoulder_width": 0.259,
    "hip_width": 0.191, "hip_to_shoulder": 0.288, "neck_head": 0.182,
}

# fractions of H fixed here (not in Winter's figure): where the foot's length sits
# relative to the ankle, and how the trunk is split between the spine joints
_HEEL_BEHIND_ANKLE = 0.037      # heel → ankle (so ankle → toe tip = 0.115 H)
_BALL_FRAC = 0.70               # ball of the foot at 70 % of ankle → toe tip
_HIP_BELOW_PELVIS = 0.030       # Hips (pelvis centre) above the hip joint centres
_HIP_JOINT_HALF_WIDTH = 0.5 * 0.191 * 0.55   # hip joint centres lie well inside the
                                             # trochanters (0.105 H apart)


def make_skeleton(height: float = 1.75) -> Skeleton:
    """A 21-joint humanoid of standing ``height`` metres (rest pose standing,
    arms down, facing +Z, left at +X, feet on the floor y = 0).

    Joints, depth first (``parents[j] < j``, each subtree right after its
    parent): Hips (root; channels Xposition Yposition Zposition Zrotation
    Yrotation Xrotation), LeftUpLeg, LeftLeg, LeftFoot, LeftToeBase (+ toe-tip
    End Site), the same Right*, Spine, Spine1, Neck, Head (+ vertex End Site),
    LeftShoulder (clavicle), LeftArm, LeftForeArm, LeftHand (+ fingertip End
    Site), the same Right*.  Other joints have channels Zrotation Yrotation
    Xrotation.

    Parameters
    ----------
    height : float
        Standing height, metres.

    Returns
    -------
    Skeleton

    Examples
    --------
    >>> sk = make_skeleton(1.75)
    >>> round(sk.rest_height(), 3)
    1.75
    """
    H = float(height)
    if not (np.isfinite(H) and H > 0):
        raise ValueError(f"make_skeleton: height must be a positive number of metres, got {height!r}")
    f = FRACTIONS
    ankle_y = f["ankle_height"] * H
    knee_y = ankle_y + f["shank"] * H
    hip_y = knee_y + f["thigh"] * H                     # hip joint centres, 0.530 H
    pelvis_y = hip_y + _HIP_BELOW_PELVIS * H
    shoulder_y = hip_y + f["hip_to_shoulder"] * H       # 0.818 H
    neck_y = shoulder_y + 0.012 * H                     # C7, just above the shoulder line
    head_y = neck_y + 0.060 * H                         # skull base / atlanto-occipital
    toe_len = f["foot_length"] * H - _HEEL_BEHIND_ANKLE * H   # ankle → toe tip, forward
    ball_z = _BALL_FRAC * toe_len
    hx = _HIP_JOINT_HALF_WIDTH * H
    sx = 0.5 * f["shoulder_width"] * H
    clav_x = 0.020 * H
    spine_y = pelvis_y + 0.060 * H
    spine1_y = spine_y + 0.100 * H
    clav_y = shoulder_y - 0.008 * H

    names, parents, offsets, channels, ends = [], [], [], [], []

    def add(name, parent, offset, end=None):
        names.append(name)
        parents.append(-1 if parent is None else names.index(parent))
        offsets.append(offset)
        channels.append(ROOT_CHANNELS if parent is None else JOINT_CHANNELS)
        if end is not None:
            ends.append((len(names) - 1, np.asarray(end, float)))

    add("Hips", None, [0.0, 0.0, 0.0])
    for side, s in (("Left", 1.0), ("Right", -1.0)):
        add(f"{side}UpLeg", "Hips", [s * hx, hip_y - pelvis_y, 0.0])
        add(f"{side}Leg", f"{side}UpLeg", [0.0, -f["thigh"] * H, 0.0])
        add(f"{side}Foot", f"{side}Leg", [0.0, -f["shank"] * H, 0.0])
        add(f"{side}ToeBase", f"{side}Foot", [0.0, -ankle_y, ball_z],
            end=[0.0, 0.0, toe_len - ball_z])
    add("Spine", "Hips", [0.0, spine_y - pelvis_y, 0.0])
    add("Spine1", "Spine", [0.0, spine1_y - spine_y, 0.0])
    add("Neck", "Spine1", [0.0, neck_y - spine1_y, 0.0])
    add("Head", "Neck", [0.0, head_y - neck_y, 0.0], end=[0.0, H - head_y, 0.0])
    for side, s in (("Left", 1.0), ("Right", -1.0)):
        add(f"{side}Shoulder", "Spine1", [s * clav_x, clav_y - spine1_y, 0.0])
        add(f"{side}Arm", f"{side}Shoulder", [s * (sx - clav_x), shoulder_y - clav_y, 0.0])
        add(f"{side}ForeArm", f"{side}Arm", [0.0, -f["upper_arm"] * H, 0.0])
        add(f"{side}Hand", f"{side}ForeArm", [0.0, -f["forearm"] * H, 0.0],
            end=[0.0, -f["hand"] * H, 0.0])
    # the root offset stays zero: a clip's root_pos carries the pelvis height
    return Skeleton(names, parents, offsets, channels, ends)


def standing_root_height(sk: Skeleton) -> float:
    """Height of the root (Hips) above the floor in the rest pose of a skeleton
    made by :func:`make_skeleton` (the lowest foot point on the floor)."""
    P = sk.rest_positions()
    if sk.end_sites:
        P = np.concatenate([P, np.array([P[p] + o for p, o in sk.end_sites])])
    return -float(P[:, 1].min())
