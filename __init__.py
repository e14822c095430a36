"""flipstudy: perception studies of ballistic character motion.

One import package of four parts, in the order data flows:

* :mod:`flipstudy.stimuli` — motion in, stimuli out: clips, BVH, the body model,
  momenta, flight phases, the built-in exact flips, editing methods, error injection;
* :mod:`flipstudy.render` — offscreen PyVista renders: videos, ghosts, trails, strips;
* :mod:`flipstudy.study` — sessions, storage, export, ``reproduce`` and the CLI;
* :mod:`flipstudy.analysis` — ratings, d′, psychometric fits, tables and figures.

The stable entry points are here:

>>> import flipstudy
>>> clip = flipstudy.builtin("backflip")
>>> a = flipstudy.analyse(clip)
>>> a.takeoff < a.landing
True

Every user error is a :class:`FlipstudyError`.
"""
from flipstudy.stimuli import (BVHError, Body, Clip, FlipstudyError, Skeleton, analyse, builtin, load_bvh,
                      save_bvh)
from flipstudy.stimuli.analyse import Analysis

__version__ = "0.1.0"

__all__ = ["load_bvh", "save_bvh", "builtin", "analyse", "Analysis", "Clip", "Skeleton", "Body",
           "FlipstudyError", "BVHError", "__version__"]
