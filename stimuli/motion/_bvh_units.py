"""How a BVH file's numbers become metres and seconds when the file does not say:
the unit guessed from the size of the rest skeleton, the frame rate snapped from
the header's rounded Frame Time, and the range of frame rates accepted.

>>> from flipstudy.stimuli.motion import guess_scale
>>> from flipstudy.stimuli.synth import make_skeleton
>>> guess_scale(make_skeleton().scaled(100.0))      # the built-in body in centimetres
(0.01, 'cm')
>>> header_fps(0.0083333, "0.0083333")               # the rounded frame time of 120 fps
120.0
"""
from __future__ import annotations

from decimal import Decimal, InvalidOperation

import numpy as np

from flipstudy.errors import FlipstudyValueError
from .skeleton import Skeleton

#: Length units a BVH file is commonly written in: (metres per unit, name).
UNIT_CANDIDATES = (
    (1.0, "m"),
    (0.01, "cm"),
    (0.001, "mm"),
    (0.0254, "in"),
    (0.0254 / 0.45, "CMU/ASF length units (1/0.45 in)"),
    (0.3048, "ft"),
)
STANDING_HEIGHT_M = 1.70
#: Frame rates a BVH file may declare (or ``fps=`` give), frames per second.
FPS_RANGE = (1.0, 10_000.0)


def guess_scale(skeleton: Skeleton) -> tuple[float, str]:
    """Guess file units → metres from the size of the rest skeleton.

    The rest pose of every file we know is standing (T- or A-pose), so its largest
    extent (height, or arm span in a T-pose) is about an adult's height.  The unit
    whose conversion puts it closest to 1.70 m (in log scale) wins.

    Parameters
    ----------
    skeleton : Skeleton
        The rest skeleton, in file units.

    Returns
    -------
    scale : float
        Metres per file unit.
    unit : str
        Its name.

    Examples
    --------
    >>> from flipstudy import builtin
    >>> clip = builtin("jump")                              # metres
    >>> guess_scale(clip.skeleton), guess_scale(clip.scaled(100).skeleton)
    ((1.0, 'm'), (0.01, 'cm'))"""
    P = skeleton.rest_positions()
    pts = [P]
    if skeleton.end_sites:
        pts.append(np.array([P[p] + o for p, o in skeleton.end_sites]))
    pts = np.concatenate(pts)
    extent = float(np.max(pts.max(0) - pts.min(0)))
    if extent <= 0:
        return 1.0, "m (skeleton has no extent; assumed)"
    best = min(UNIT_CANDIDATES, key=lambda u: abs(np.log(extent * u[0] / STANDING_HEIGHT_M)))
    return best[0], best[1]


def header_fps(frame_time: float, text: str) -> float:
    """Frames per second from the header's Frame Time.

    Headers store a rounded frame time (".0083333", ".016667"): snap to the whole rate
    it stands for, but only when that rate's frame time rounds to the digits written
    (so a frame time written with 10 decimals for 119.99 fps stays 119.99)."""
    fps = 1.0 / frame_time
    whole = round(fps)
    if whole < 1 or abs(fps - whole) >= 2e-4 * fps:
        return fps
    try:
        half_unit = 0.5 * 10.0 ** Decimal(text).as_tuple().exponent
    except (InvalidOperation, TypeError, ValueError):
        return fps
    if abs(frame_time - 1.0 / whole) <= half_unit * (1 + 1e-9):
        return float(whole)
    return fps


def check_fps(fps, field: str = "fps") -> float:
    """A frame rate given by the caller, in :data:`FPS_RANGE`."""
    try:
        v = float(fps)
    except (TypeError, ValueError):
        v = float("nan")
    lo, hi = FPS_RANGE
    if not (np.isfinite(v) and lo <= v <= hi):
        raise FlipstudyValueError(f"{field}: expected a frame rate between {lo:g} and {hi:g} frames "
                                  f"per second, got {fps!r}")
    return v

