"""``flipstudy convert``: any clip the loading rule reads (BVH, joint positions,
AMASS/SMPL) written as BVH.

>>> import tempfile, pathlib
>>> from flipstudy.stimuli.convert import convert
>>> with tempfile.TemporaryDirectory() as tmp:
...     r = convert("jump", pathlib.Path(tmp) / "jump.bvh")
>>> r.frames > 0, r.out.name
(True, 'jump.bvh')
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from flipstudy.errors import FlipstudyFileExistsError
from flipstudy.results import StepResult
from .loading import load_clip


@dataclass(frozen=True)
class Converted(StepResult):
    """What :func:`convert` wrote: the source, the BVH file, frames, rate, joints, and
    (for a position source) the largest distance of the written joints from the
    given positions (``fit_mm``; None for a clip of rotations)."""

    source: str
    out: Path
    frames: int
    fps: float
    joints: int
    fit_mm: float | None
    warnings: tuple[str, ...]

    def summary(self) -> str:
        fit = "" if self.fit_mm is None else f"; joints within {self.fit_mm:.2g} mm of the positions"
        return (f"{self.source} → {self.out}: {self.frames} frames at {self.fps:g} fps, {self.joints} joints"
                f"{fit}" + "".join(f"\n  warning: {w}" for w in self.warnings))


def convert(spec: str, out, force: bool = False, **load_options) -> Converted:
    """Read ``spec`` with :func:`~flipstudy.stimuli.loading.load_clip` (``load_options``:
    ``scale``, ``fps``, ``accept_unphysical``, ``layout``, ``up``, ``body_model``; the physics gate runs) and
    write it as BVH in metres to ``out`` (refused when it exists, unless ``force``)."""
    from .motion import save_bvh
    out = Path(out)
    if out.exists() and not force:
        raise FlipstudyFileExistsError(f"{out} exists; choose another --out or pass --force to replace it")
    clip = load_clip(spec, **load_options)
    save_bvh(clip, out)
    return Converted(str(spec), out, clip.num_frames, clip.fps, clip.skeleton.num_joints,
                     clip.meta.get("fit_mm"), tuple(clip.meta.get("warnings", [])))


__all__ = ["Converted", "convert"]
