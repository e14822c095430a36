"""flipstudy.stimuli: motion in, stimuli out (clips, BVH, body model, physics).

Stable entry points::

    from flipstudy.stimuli import load_bvh, save_bvh, builtin, analyse
"""
from .exceptions import FlipstudyError
from .motion import BVHError, Clip, Skeleton, load_bvh, save_bvh
from .body import Body
from .analyse import Analysis, analyse
from .loading import load_clip


BUILTIN_NAMES = ("backflip", "frontflip", "jump")


def builtin(name: str, **params) -> Clip:
    """A built-in, physically exact synthetic clip: ``"backflip"``, ``"frontflip"``
    or ``"jump"`` (see :mod:`flipstudy.stimuli.synth`; keyword parameters such as
    ``fps`` go to :func:`flipstudy.stimuli.synth.builtin`).

    Example
    -------
    >>> from flipstudy import builtin
    >>> clip = builtin("backflip", fps=60)
    >>> clip.fps, clip.skeleton.joint_names[0]
    (60.0, 'Hips')
    >>> clip.meta["takeoff"] < clip.meta["landing"]      # frames of the exact flight
    True
    """
    from .synth import builtin as _builtin
    return _builtin(name, **params)


__all__ = ["FlipstudyError", "BVHError", "Clip", "Skeleton", "load_bvh", "save_bvh", "Body", "Analysis",
           "analyse", "builtin", "load_clip", "BUILTIN_NAMES"]
