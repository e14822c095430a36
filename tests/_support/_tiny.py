"""A tiny, smooth, analytic test motion: a rigid body made of a few bones,
flying on a parabola and spinning at a varying rate."""
import numpy as np
from scipy.spatial.transform import Rotation

from flipstudy.stimuli.motion import Clip, Skeleton


def tiny_body_clip(fps=240, seconds=1.0):
    from flipstudy.stimuli.body import Body
    names = ["Hips", "Spine", "Neck", "Head", "LeftUpLeg", "LeftLeg", "LeftFoot",
             "RightUpLeg", "RightLeg", "RightFoot", "LeftArm", "LeftForeArm", "LeftHand",
             "RightArm", "RightForeArm", "RightHand"]
    parents = [-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 2, 10, 11, 2, 13, 14]
    offs = [[0, 0, 0], [0, 0.25, 0], [0, 0.25, 0], [0, 0.1, 0],
            [0.1, -0.05, 0], [0, -0.42, 0], [0, -0.42, 0],
            [-0.1, -0.05, 0], [0, -0.42, 0], [0, -0.42, 0],
            [0.18, 0, 0], [0.28, 0, 0], [0.25, 0, 0],
            [-0.18, 0, 0], [-0.28, 0, 0], [-0.25, 0, 0]]
    ends = [(3, [0, 0.15, 0]), (6, [0, -0.05, 0.15]), (9, [0, -0.05, 0.15]),
            (12, [0.08, 0, 0]), (15, [-0.08, 0, 0])]
    sk = Skeleton(names, parents, offs, end_sites=ends)
    F = int(seconds * fps) + 1
    t = np.arange(F) / fps
    q = np.zeros((F, len(names), 4))
    q[..., 3] = 1
    q[:, 0] = Rotation.from_rotvec(np.stack([2 * t + 3 * t ** 2, 0.3 * t, 0 * t], 1)).as_quat()
    q[:, 5] = Rotation.from_rotvec(np.stack([0.8 * np.sin(3 * t), 0 * t, 0 * t], 1)).as_quat()
    q[:, 11] = Rotation.from_rotvec(np.stack([0 * t, 0.5 * np.sin(2 * t), 0 * t], 1)).as_quat()
    root = np.stack([0.5 * t, 1.0 + 3 * t - 4.9 * t ** 2, 0.2 * t], 1)
    clip = Clip(sk, fps, root, q)
    return clip, Body.from_skeleton(sk)
