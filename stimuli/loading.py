"""Loading a CLIP the same way everywhere: a built-in name or a BVH path."""
from __future__ import annotations

from pathlib import Path

from flipstudy.errors import FlipstudyFileNotFoundError


def load_clip(spec: str, scale: float | None = None, fps: float | None = None,
              accept_unphysical: bool = False, check: bool = True):
    """A clip by name: a built-in name (backflip, frontflip, jump) or a BVH path.
    The same loading rules for every command: ``scale`` (metres per file unit;
    default guessed) and ``fps`` (default: the header's) override the file.  A name
    that is neither raises :class:`~flipstudy.errors.FlipstudyFileNotFoundError`.

    Every clip then passes the one physics gate, :func:`checked_clip` (``check=False``
    skips it: ``inspect``, which reports the same findings as warnings).

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
            return checked_clip(clip, spec, accept_unphysical) if check else clip
        return clip                         # physically exact at any fps
    p = Path(spec)
    if not p.exists():
        raise FlipstudyFileNotFoundError(f"{spec}: neither a built-in clip ({', '.join(BUILTIN_NAMES)}) "
                                  f"nor an existing BVH file")
    clip = load_bvh(p, scale=scale, fps=fps)
    return checked_clip(clip, spec, accept_unphysical) if check else clip


def checked_clip(clip, spec: str, accept_unphysical: bool = False):
    """The physics gate every command that takes a CLIP runs: ``clip`` itself, unless
    physics contradicts it (the apparent gravity of its flight, or the body's height
    from its skeleton; see :func:`flipstudy.stimuli.analyse.physics_advice`); then
    :class:`~flipstudy.errors.UnphysicalClipError` names the options that fix it
    (``--fps``/``--scale``) and ``--accept-unphysical``.

    >>> from flipstudy.stimuli import builtin
    >>> checked_clip(builtin("backflip"), "backflip").fps
    120.0
    """
    if accept_unphysical:
        return clip
    from flipstudy.errors import UnphysicalClipError
    from .analyse import analyse, gravity_warning
    a = analyse(clip, estimate=False)
    msg = gravity_warning(a.apparent_gravity, clip)
    if msg is None:
        return clip
    raise UnphysicalClipError(f"{spec}: {msg.rstrip('.')}; or pass --accept-unphysical to use it as it is.")
