"""flipstudy: perception studies of ballistic character motion.

One import package of four parts, in the order data flows:

* :mod:`flipstudy.stimuli` — motion in, stimuli out: clips, BVH, the body model,
  momenta, flight phases, the built-in exact flips, editing methods, error injection;
* :mod:`flipstudy.render` — offscreen PyVista renders: videos, ghosts, trails, strips;
* :mod:`flipstudy.study` — sessions, storage, export, ``reproduce`` and the CLI;
* :mod:`flipstudy.analysis` — ratings, d′, psychometric fits, tables and figures.

The stable entry points are here:

>>> import flipstudy
>>> clip = flipstudy.builtin("backflip")          # a Clip: 120 fps, metres, Y up
>>> clip.fps, clip.num_frames, clip.joint_positions().shape
(120.0, 397, (397, 21, 3))
>>> a = flipstudy.analyse(clip)                   # flight phases, COM, momenta
>>> a.takeoff < a.landing
True
>>> body = flipstudy.Body.from_clip(clip)         # the segment model the physics weighs
>>> round(body.total_mass, 6)
70.0

A BVH file round-trips (here in a temporary folder):

>>> import tempfile, pathlib
>>> with tempfile.TemporaryDirectory() as tmp:
...     path = flipstudy.save_bvh(clip, pathlib.Path(tmp) / "backflip.bvh")
...     flipstudy.load_bvh(path, scale=1.0).num_frames
397

Every user error is a :class:`FlipstudyError`:

>>> try:
...     flipstudy.builtin("cartwheel")
... except flipstudy.FlipstudyError as e:
...     print(e)
unknown built-in clip 'cartwheel'; valid names: backflip, frontflip, jump
"""
from flipstudy.errors import FlipstudyError
from flipstudy._lazy import attach

# imported on first use, so that ``import flipstudy.study.cli`` loads no scipy
attach(__name__, {"flipstudy.stimuli": ["BVHError", "Body", "Clip", "Skeleton", "analyse", "builtin",
                                        "load_bvh", "save_bvh", "Analysis"]})

__version__ = "0.1.0"

__all__ = ["load_bvh", "save_bvh", "builtin", "analyse", "Analysis", "Clip", "Skeleton", "Body",
           "FlipstudyError", "BVHError", "__version__"]
