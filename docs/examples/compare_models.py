"""Make a comparison study's sources: ground truth from real CMU clips as joint
positions, two degraded "model" outputs, and the design that compares them.

    python docs/examples/compare_models.py --out /tmp/cmp [--mocap ../shared/mocap]

writes ``/tmp/cmp/{gt,jitter,floaty}/ITEM.npz`` (joint positions in the HumanML3D
layout: the 22 SMPL body joints in SMPL order, Y up, metres, with the take's frame
rate as ``fps``) and ``/tmp/cmp/design.toml`` (three ``[[sources]]``, 2AFC against
``gt``).  The user guide's "Comparing given motions" section runs the rest: build,
render, simulated panel, ranking.

* ``gt``: the CMU takes, read with the fixes ``../shared/mocap/SOURCES.md`` asks
  for: subjects 87 and 88 are 60 Hz although the una-dinosauria headers say
  120 Hz (``fps=60``), frame 1 of every raw CMU file is a T-pose (the loader drops it), the
  ASF length unit is 0.056444 m (the loader's unit guess finds it); their joints
  at the SMPL body joints
  (:data:`flipstudy.stimuli.motion.positions.CMU_AS_SMPL22`), as a motion-generation model
  writes them.
* ``jitter``: temporal jitter: frame k is the take at time k + e_k frames,
  e_k ~ N(0, 0.35) (positions interpolated linearly), so poses arrive early or
  late (a model with an unsteady clock).
* ``floaty``: a smoothed, floating copy: the joint trajectories smoothed over time
  (Gaussian, σ = 3 frames: contacts and take-offs lose their snap) and the body
  rising by 0 → 6 cm over the clip (its feet leave the floor they stood on).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter1d

#: item → (file, its true frame rate or None for the header's); SOURCES.md: 87/88 are 60 Hz
TAKES = {"88_01": ("88_01.bvh", 60.0), "87_03": ("87_03.bvh", 60.0), "90_11": ("90_11.bvh", None)}

DESIGN = """# A comparison study: which source's motions look physically possible?
[study]
name = "compare-models-example"
seed = 31
task = "2afc"          # each model's clip beside the ground truth's, order balanced
repetitions = 2
fps = 60
style = "capsules"

[[sources]]
name = "gt"
folder = "gt"

[[sources]]
name = "jitter"
folder = "jitter"
accept_unphysical = true   # a model's output is judged as it is, not refused by the gate

[[sources]]
name = "floaty"
folder = "floaty"
accept_unphysical = true
"""


def ground_truth(mocap: Path, name: str) -> tuple[np.ndarray, float]:
    """A CMU take as (F, 22, 3) joint positions in the HumanML3D layout (metres, Y up)
    at its true rate, without the leading T-pose frame (the loader drops it:
    ``meta["dropped_frames"] == [0]``; every frame it keeps is the take's); and that rate."""
    from flipstudy.stimuli.loading import load_clip
    from flipstudy.stimuli.motion.positions import CMU_AS_SMPL22, SMPL22_NAMES
    file, rate = TAKES[name]
    c = load_clip(str(mocap / file), fps=rate)
    idx = [c.skeleton.index(CMU_AS_SMPL22[n]) for n in SMPL22_NAMES]
    return c.joint_positions()[:, idx], c.fps


def jittered(X: np.ndarray, rng, sd_frames: float = 0.35) -> np.ndarray:
    """Frame k at time k + N(0, sd) frames (positions interpolated linearly)."""
    F = len(X)
    t = np.clip(np.arange(F) + rng.normal(0.0, sd_frames, F), 0, F - 1)
    k = np.minimum(np.floor(t).astype(int), F - 2)
    w = (t - k)[:, None, None]
    return (1 - w) * X[k] + w * X[k + 1]


def smoothed_floating(X: np.ndarray, sigma_frames: float = 3.0, lift_m: float = 0.06) -> np.ndarray:
    """Joint trajectories smoothed over time, the body rising 0 → ``lift_m``."""
    Y = gaussian_filter1d(X, sigma_frames, axis=0, mode="nearest")
    Y[..., 1] += np.linspace(0.0, lift_m, len(X))[:, None]
    return Y


def make_sources(out: Path, mocap: Path, seed: int = 31) -> Path:
    """Write the three sources and the design into ``out``; returns the design's path."""
    rng = np.random.default_rng(seed)
    for s in ("gt", "jitter", "floaty"):
        (out / s).mkdir(parents=True, exist_ok=True)
    for name in TAKES:
        X, fps = ground_truth(mocap, name)
        for s, Y in (("gt", X), ("jitter", jittered(X, rng)), ("floaty", smoothed_floating(X))):
            np.savez(out / s / f"{name}.npz", joints=Y.astype(np.float32), fps=np.float64(fps))
    (out / "design.toml").write_text(DESIGN)
    return out / "design.toml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, type=Path, help="folder for the sources and the design")
    ap.add_argument("--mocap", type=Path, default=Path(__file__).resolve().parents[2] / ".." / "shared" / "mocap",
                    help="the CMU clips (default ../shared/mocap beside the checkout)")
    ap.add_argument("--seed", type=int, default=31)
    a = ap.parse_args()
    p = make_sources(a.out, a.mocap, a.seed)
    print(f"wrote {', '.join(f'{s}/' for s in ('gt', 'jitter', 'floaty'))} ({len(TAKES)} items each) "
          f"and {p}")


if __name__ == "__main__":
    main()
