"""Generated BVH text for tests and benchmarks (no shared data needed)."""
from __future__ import annotations

import numpy as np


def many_joints_bvh(n_joints: int, n_frames: int = 10, fan: int = 100, seed: int = 0) -> str:
    """A BVH file of ``n_joints`` joints: a root with ``fan`` chains of equal length
    (so the tree is ``n_joints / fan`` deep), centimetre offsets, ZXY rotations on
    every joint, root positions, ``n_frames`` frames of small random angles."""
    rng = np.random.default_rng(seed)
    out = ["HIERARCHY", "ROOT Hips", "{", "\tOFFSET 0 90 0",
           "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    rest = n_joints - 1
    per = [rest // fan + (1 if k < rest % fan else 0) for k in range(fan)]
    j = 0
    for k, n in enumerate(per):
        for d in range(n):
            j += 1
            out.append(f"JOINT J{j}")
            out.append("{")
            out.append(f"\tOFFSET {0.1 * (k % 7):g} {0.5:g} 0")
            out.append("\tCHANNELS 3 Zrotation Xrotation Yrotation")
        if n:
            out += ["End Site", "{", "\tOFFSET 0 0.5 0", "}"]
        out += ["}"] * n
    out.append("}")
    C = 6 + 3 * (n_joints - 1)
    vals = rng.normal(0, 5, size=(n_frames, C))
    vals[:, :3] = [0, 90, 0]
    out += ["MOTION", f"Frames: {n_frames}", "Frame Time: 0.0083333"]
    out += [" ".join(f"{v:.4f}" for v in row) for row in vals]
    return "\n".join(out) + "\n"
