"""Skeletons, clips, BVH reading and writing, forward kinematics."""
from .skeleton import Skeleton
from .clip import Clip, finite_difference, angular_velocity
from flipstudy.errors import BVHError
from .bvh import load_bvh, save_bvh, bvh_text, guess_scale

__all__ = ["Skeleton", "Clip", "BVHError", "load_bvh", "save_bvh", "bvh_text", "guess_scale",
           "finite_difference", "angular_velocity"]
