"""Editing operations: retiming, repositioning (and the papers' algorithms)."""
from flipstudy._lazy import attach
from flipstudy.errors import FlipEditError

# imported on first use: the motion operations of .reposition, which render re-exports,
# should not load the editing algorithms (0.2 s)
attach(__name__, {".timing": ["sample", "retime", "source_times", "ratio_retime_frames"],
                  ".reposition": ["move_com", "ballistic_path", "rotate"],
                  ".multiflip": ["multiflip", "k_star"],
                  ".animator": ["straighten", "repair_momentum"]})

__all__ = ["sample", "retime", "source_times", "ratio_retime_frames", "move_com", "ballistic_path", "rotate",
           "multiflip", "k_star", "FlipEditError", "straighten", "repair_momentum"]
