"""Editing operations: retiming, repositioning (and the papers' algorithms)."""
from .timing import ratio_retime_frames, retime, sample, source_times
from .reposition import ballistic_path, move_com, rotate
from flipstudy.errors import FlipEditError
from .multiflip import k_star, multiflip
from .animator import repair_momentum, straighten

__all__ = ["sample", "retime", "source_times", "ratio_retime_frames", "move_com", "ballistic_path", "rotate",
           "multiflip", "k_star", "FlipEditError", "straighten", "repair_momentum"]
