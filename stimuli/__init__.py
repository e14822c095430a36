"""flipstudy.stimuli: motion in, stimuli out (clips, BVH, body model, physics)."""
from .motion import BVHError, Clip, Skeleton, load_bvh, save_bvh
from .body import Body

__all__ = ["BVHError", "Clip", "Skeleton", "load_bvh", "save_bvh", "Body"]
