"""Options shared by the commands, defined once: a CLIP with ``--scale``/``--fps``,
``--mass``, ``--json``."""
from __future__ import annotations

import argparse

from flipstudy.stimuli.loading import load_clip

__all__ = ["load_clip", "add_clip_args", "add_mass", "add_json"]


def add_clip_args(p: argparse.ArgumentParser):
    p.add_argument("clip", metavar="CLIP", help="built-in name (backflip, frontflip, jump) or BVH path")
    p.add_argument("--scale", type=float, default=None,
                   help="metres per file unit (default: guessed from the skeleton's size)")
    p.add_argument("--fps", type=float, default=None,
                   help="frames per second, overriding the file's Frame Time")


def add_mass(p: argparse.ArgumentParser, default: float = 70.0) -> None:
    p.add_argument("--mass", type=float, default=default,
                   help=f"total body mass in kg (default {default:g})")


def add_json(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="print one JSON object")
