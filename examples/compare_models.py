"""Make a comparison study's sources: ground truth from real CMU clips and two
degraded "model" outputs, plus the design that compares them.

    python examples/compare_models.py --out /tmp/cmp [--mocap ../shared/mocap]

writes ``/tmp/cmp/{gt,jitter,floaty}/ITEM.bvh`` (metres, the clip's true frame
rate) and ``/tmp/cmp/design.toml`` (three ``[[sources]]``, 2AFC against ``gt``).
The README's "Comparing given motions" section runs the rest: build, render,
simulated panel, ranking.

* ``gt``: the CMU takes, read with the fixes ``../shared/mocap/SOURCES.md`` asks
  for: subjects 87 and 88 are 60 Hz although the una-dinosauria headers say
  120 Hz (``fps=60``), frame 1 of every raw CMU file is a T-pose (dropped), the
  ASF length unit is 0.056444 m (the loader's unit guess finds it).
* ``jitter``: temporal jitter: frame k is the take at time k + e_k frames,
  e_k ~ N(0, 0.35), so poses arrive early or late (a model with an unsteady clock).
* ``floaty``: a smoothed, floating copy: root and joint rotations smoothed over
  time (Gaussian, σ = 3 frames: contacts and take-offs lose their snap) and the
  body rising by 0 → 6 cm over the clip (its feet leave the floor they stand on).

The sources are written as BVH: the joint-position reader (HumanML3D layout) is a
separate piece of work; once it is in, the ground truth may be given as joint
positions through the same loading rule, with no change to the study.
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


def ground_truth(mocap: Path, name: str, fps):
    """A CMU take in metres at its true rate, without the leading T-pose frame."""
    from flipstudy.stimuli.loading import load_clip
    from flipstudy.stimuli.motion.clip import Clip
    file, rate = TAKES[name]
    c = load_clip(str(mocap / file), fps=rate)
    return Clip(c.skeleton, c.fps, c.root_pos[1:], c.rotations[1:], None, {"name": name})


def jittered(clip, rng, sd_frames: float = 0.35):
    """Frame k at time k + N(0, sd) frames (the slerp sampler of the editors)."""
    from flipstudy.stimuli.edit.timing import sample
    t = np.arange(clip.num_frames) + rng.normal(0.0, sd_frames, clip.num_frames)
    return sample(clip, np.clip(t, 0, clip.num_frames - 1))


def smoothed_floating(clip, sigma_frames: float = 3.0, lift_m: float = 0.06):
    """Root and rotations smoothed over time, the body rising 0 → ``lift_m``."""
    from flipstudy.stimuli.motion.clip import Clip
    q = clip.rotations.copy()                                     # (F, J, 4) unit quaternions
    flip = np.cumprod(np.where(np.sum(q[1:] * q[:-1], -1) < 0, -1.0, 1.0), axis=0)
    q[1:] *= flip[..., None]                                      # one hemisphere along time
    q = gaussian_filter1d(q, sigma_frames, axis=0, mode="nearest")
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    root = gaussian_filter1d(clip.root_pos, sigma_frames, axis=0, mode="nearest")
    root[:, 1] += np.linspace(0.0, lift_m, clip.num_frames)
    return Clip(clip.skeleton, clip.fps, root, q, None, dict(clip.meta))


def make_sources(out: Path, mocap: Path, seed: int = 31) -> Path:
    """Write the three sources and the design into ``out``; returns the design's path."""
    from flipstudy import save_bvh
    rng = np.random.default_rng(seed)
    for s in ("gt", "jitter", "floaty"):
        (out / s).mkdir(parents=True, exist_ok=True)
    for name in TAKES:
        gt = ground_truth(mocap, name, TAKES[name][1])
        save_bvh(gt, out / "gt" / f"{name}.bvh")
        save_bvh(jittered(gt, rng), out / "jitter" / f"{name}.bvh")
        save_bvh(smoothed_floating(gt), out / "floaty" / f"{name}.bvh")
    (out / "design.toml").write_text(DESIGN)
    return out / "design.toml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, type=Path, help="folder for the sources and the design")
    ap.add_argument("--mocap", type=Path, default=Path(__file__).resolve().parents[1] / ".." / "shared" / "mocap",
                    help="the CMU clips (default ../shared/mocap beside the checkout)")
    ap.add_argument("--seed", type=int, default=31)
    a = ap.parse_args()
    p = make_sources(a.out, a.mocap, a.seed)
    print(f"wrote {', '.join(f'{s}/' for s in ('gt', 'jitter', 'floaty'))} ({len(TAKES)} items each) "
          f"and {p}")


if __name__ == "__main__":
    main()
