"""Position-only motions made from the CMU BVH clips, as a motion-generation model
or HumanML3D would write them, and a synthetic SMPL-format body model."""
from __future__ import annotations

import numpy as np

from flipstudy.stimuli.motion.positions import CMU_AS_SMPL22, SMPL22_NAMES, SMPL22_PARENTS  # noqa: F401


def cmu_humanml3d(clip, fps: float = 20.0) -> np.ndarray:
    """(F, 22, 3) float32 joint positions of a CMU clip in the HumanML3D layout at
    ``fps`` (the clip resampled with the project's slerp sampler), Y up, metres."""
    from flipstudy.stimuli.stimset import resample
    c = resample(clip, fps) if abs(clip.fps - fps) > 1e-9 else clip
    idx = [c.skeleton.index(CMU_AS_SMPL22[n]) for n in SMPL22_NAMES]
    return c.joint_positions()[:, idx].astype(np.float32)


def synthetic_body_model(seed: int = 0, V: int = 300, B: int = 10) -> tuple[dict, np.ndarray]:
    """A body-model file's arrays in the SMPL .npz format (v_template, shapedirs,
    J_regressor, kintree_table, posedirs, weights) whose regressed rest joints,
    for betas = 0, are ``rest`` (22, 3): an adult in a T-pose, metres, Y up.  Each
    joint is the mean of its own cluster of vertices (so the regressor is a real
    averaging matrix, 24 rows as SMPL's); beta 0 scales the body by 5 % about the
    template's centroid, the other betas add small random per-vertex offsets."""
    rng = np.random.default_rng(seed)
    rest = np.array([
        [0, 0.93, 0], [0.09, 0.85, 0], [-0.09, 0.85, 0], [0, 1.04, -0.01], [0.10, 0.47, 0.01],
        [-0.10, 0.47, 0.01], [0, 1.17, 0], [0.10, 0.07, -0.03], [-0.10, 0.07, -0.03], [0, 1.23, 0.01],
        [0.11, 0.02, 0.10], [-0.11, 0.02, 0.10], [0, 1.45, -0.01], [0.08, 1.38, 0], [-0.08, 1.38, 0],
        [0, 1.55, 0.02], [0.18, 1.40, -0.01], [-0.18, 1.40, -0.01], [0.44, 1.40, -0.02],
        [-0.44, 1.40, -0.02], [0.69, 1.40, 0], [-0.69, 1.40, 0]])
    per = V // 22
    owner = np.repeat(np.arange(22), per)
    noise = rng.normal(0, 0.02, (len(owner), 3))
    for j in range(22):                                  # each cluster's mean is exactly its joint
        noise[owner == j] -= noise[owner == j].mean(axis=0)
    v_template = rest[owner] + noise
    n = len(owner)
    J_regressor = np.zeros((24, n))                      # SMPL: 24 joints (2 hands beyond the body's 22)
    for j in range(22):
        J_regressor[j, owner == j] = 1.0 / per
    J_regressor[22, owner == 20] = J_regressor[23, owner == 21] = 1.0 / per
    shapedirs = np.zeros((n, 3, B))
    shapedirs[:, :, 0] = 0.05 * (v_template - v_template[:, None].mean(0))   # beta 0: overall size
    shapedirs[:, :, 1:] = rng.normal(0, 0.002, (n, 3, B - 1))
    parents = np.array(list(SMPL22_PARENTS) + [20, 21])
    kintree = np.stack([np.where(parents < 0, 2 ** 32 - 1, parents), np.arange(24)]).astype(np.uint32)
    return {"v_template": v_template, "shapedirs": shapedirs, "J_regressor": J_regressor,
            "kintree_table": kintree, "posedirs": np.zeros((n, 3, 207)),
            "weights": np.eye(24)[np.minimum(owner, 23)]}, rest
