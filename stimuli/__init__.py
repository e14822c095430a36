"""flipstudy.stimuli: motion in, stimuli out (clips, BVH, body model, physics).

Stable entry points::

    from flipstudy.stimuli import load_bvh, save_bvh, builtin, analyse
"""
from flipstudy._lazy import attach
from flipstudy.errors import FlipstudyError
from .loading import load_clip

# each public name and the module it is defined in, imported on first use: the
# motion modules need scipy, and ``import flipstudy.stimuli`` (the CLI's parser)
# should not load it
attach(__name__, {".motion": ["BVHError", "Clip", "Skeleton", "load_bvh", "save_bvh"],
                  ".body": ["Body"], ".analyse": ["Analysis", "analyse"],
                  ".contract": ["Stimulus", "StimulusSet"]})


BUILTIN_NAMES = ("backflip", "frontflip", "jump")


def builtin(name: str, **params) -> "Clip":
    """A built-in, physically exact synthetic clip: ``"backflip"``, ``"frontflip"``
    or ``"jump"`` (see :mod:`flipstudy.stimuli.synth`; keyword parameters such as
    ``fps`` go to :func:`flipstudy.stimuli.synth.builtin`).

    Parameters
    ----------
    name : str
        ``"backflip"``, ``"frontflip"`` or ``"jump"``.
    **params
        The clip's parameters, e.g. ``fps`` (frames per second, default 120).

    Returns
    -------
    Clip
        In metres, Y up; ``clip.meta`` holds the exact flight's frames.

    Raises
    ------
    FlipstudyError
        For an unknown name (the message lists the valid ones).

    Examples
    --------
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
           "analyse", "builtin", "load_clip", "BUILTIN_NAMES", "Stimulus", "StimulusSet"]
