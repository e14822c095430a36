"""flipstudy.stimuli: motion in, stimuli out (clips, BVH, body model, physics).

Stable entry points::

    from flipstudy.stimuli import load_bvh, save_bvh, builtin, analyse
"""
import importlib
import sys
import types

from flipstudy.errors import FlipstudyError
from .loading import load_clip

#: each public name and the module it is defined in, imported on first use: the
#: motion modules need scipy, and ``import flipstudy.stimuli`` (the CLI's parser)
#: should not load it
_WHERE = {**dict.fromkeys(("BVHError", "Clip", "Skeleton", "load_bvh", "save_bvh"), ".motion"),
          "Body": ".body", "Analysis": ".analyse", "analyse": ".analyse",
          "Stimulus": ".contract", "StimulusSet": ".contract"}


class _Package(types.ModuleType):
    """This package, whose names of :data:`_WHERE` load on first use."""

    def __getattr__(self, name: str):
        if name not in _WHERE:
            raise AttributeError(f"module {self.__name__!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(_WHERE[name], self.__name__), name)
        self.__dict__[name] = value
        return value

    def __setattr__(self, name: str, value) -> None:
        # importing the submodule flipstudy.stimuli.analyse binds it here; the name
        # stays the function analyse(), as when it was imported eagerly
        if name in _WHERE and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)

    def __dir__(self):
        return sorted(set(self.__dict__) | set(_WHERE))


sys.modules[__name__].__class__ = _Package


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
