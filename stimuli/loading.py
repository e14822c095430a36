"""Loading a CLIP the same way everywhere: a built-in name or a BVH path."""
from __future__ import annotations

from pathlib import Path

from flipstudy.errors import FlipstudyFileNotFoundError


def load_clip(spec: str, scale: float | None = None, fps: float | None = None):
    """A clip by name: a built-in name (backflip, frontflip, jump) or a BVH path.
    The same loading rules for every command: ``scale`` (metres per file unit;
    default guessed) and ``fps`` (default: the header's) override the file.  A name
    that is neither raises :class:`~flipstudy.errors.FlipstudyFileNotFoundError`.

    Parameters
    ----------
    spec : str
        A built-in name or the path of a BVH file.
    scale : float, optional
        Metres per file unit; default: guessed from the flight (BVH) or 1.0.
    fps : float, optional
        Frames per second, overriding the file's.

    Returns
    -------
    Clip

    Raises
    ------
    FlipstudyFileNotFoundError
        When ``spec`` is neither a built-in name nor an existing file.
    BVHError
        For a malformed BVH file (naming its line).

    Examples
    --------
    >>> from flipstudy.stimuli import load_clip
    >>> load_clip("backflip", fps=60).fps
    60.0
    """
    from .motion import load_bvh          # the modules, not this package's __init__ (which imports us)
    from .synth import BUILTIN_NAMES, builtin
    if spec in BUILTIN_NAMES:
        clip = builtin(spec, **({"fps": fps} if fps else {}))
        if scale not in (None, 1.0):
            clip = clip.scaled(scale)
        return clip
    p = Path(spec)
    if not p.exists():
        raise FlipstudyFileNotFoundError(f"{spec}: neither a built-in clip ({', '.join(BUILTIN_NAMES)}) "
                                  f"nor an existing BVH file")
    return load_bvh(p, scale=scale, fps=fps)
