"""Options shared by the commands, defined once: a CLIP with ``--scale``/``--fps``,
``--mass``, ``--json``, ``--out``, a STUDY_DIR.  A command whose option means something more
particular (``concat``'s two files) passes its own help text; type, default and
destination stay the same everywhere."""
from __future__ import annotations

import argparse

from flipstudy.stimuli.loading import load_clip

__all__ = ["load_clip", "add_clip", "add_units", "add_clip_args", "add_mass", "add_json", "add_out",
           "add_study_dir", "add_cluster", "reader_options"]


def add_clip(p: argparse.ArgumentParser) -> None:
    """The positional CLIP: a built-in name or a BVH path (see :func:`load_clip`)."""
    p.add_argument("clip", metavar="CLIP", help="built-in name (backflip, frontflip, jump), BVH path, joint "
                   "positions (.npy/.npz) or AMASS .npz")


def add_units(p: argparse.ArgumentParser, *,
              scale_help: str = "metres per file unit (default: guessed from the skeleton's size)",
              fps_help: str = "the clip's frames per second, overriding the file's Frame Time",
              gate: bool = True) -> None:
    """``--scale`` and ``--fps`` of the clips a command loads (see :func:`load_clip`), and
    with ``gate`` ``--accept-unphysical``, the way past the physics gate."""
    p.add_argument("--scale", type=float, default=None, help=scale_help)
    p.add_argument("--fps", type=float, default=None, help=fps_help)
    if gate:
        p.add_argument("--accept-unphysical", action="store_true",
                       help="use a clip whose apparent gravity or body height contradicts physics "
                            "as it is (default: refuse it, naming the --fps/--scale that fix it)")
    add_readers(p)


def add_readers(p: argparse.ArgumentParser) -> None:
    """``--layout``, ``--up`` and ``--body-model`` of the joint-position and AMASS
    readers (see :func:`load_clip`; pass them on with :func:`reader_options`)."""
    p.add_argument("--layout", default=None, metavar="NAME|FILE",
                   help="joints of a .npy/.npz position array: humanml3d-22 (default for 22 joints) "
                        "or a JSON/TOML layout file of joint names and parents")
    p.add_argument("--up", choices=("y", "z"), default=None,
                   help="up axis of a position or AMASS file (default: y; z for AMASS)")
    p.add_argument("--body-model", default=None, metavar="PATH",
                   help="your licensed SMPL/SMPL-H/SMPL-X body model (.npz) to read an AMASS file")


def reader_options(args) -> dict:
    """The reader options a command's ``args`` carry, as :func:`load_clip` keywords."""
    return {k: getattr(args, k, None) for k in ("layout", "up", "body_model")}


def add_clip_args(p: argparse.ArgumentParser, gate: bool = True) -> None:
    """CLIP with ``--scale`` and ``--fps`` (and ``--accept-unphysical`` with ``gate``)."""
    add_clip(p)
    add_units(p, gate=gate)


def add_mass(p: argparse.ArgumentParser, default: float = 70.0, *, what: str = "total body mass") -> None:
    p.add_argument("--mass", type=float, default=default,
                   help=f"{what} in kg (default {default:g})")


def add_json(p: argparse.ArgumentParser, help: str = "print one JSON object") -> None:
    p.add_argument("--json", action="store_true", help=help)


def add_out(p: argparse.ArgumentParser, metavar: str, help: str | None = None) -> None:
    """The required ``--out`` file or folder a command writes."""
    p.add_argument("--out", required=True, metavar=metavar, help=help)


def add_study_dir(p: argparse.ArgumentParser, help: str | None = None) -> None:
    """The positional STUDY_DIR, the study folder a command works on."""
    p.add_argument("study_dir", metavar="STUDY_DIR", help=help)


def add_cluster(p: argparse.ArgumentParser) -> None:
    """``--cluster ADDRESS``: run the work on Dask distributed (see
    :mod:`flipstudy.study.cluster`)."""
    p.add_argument("--cluster", metavar="ADDRESS", default=None,
                   help="run on Dask distributed: tcp://HOST:PORT of a running `dask scheduler`, "
                        "or local:N for a LocalCluster of N worker processes; the workers need "
                        "the study folder at the same path (shared filesystem) and the same "
                        "versions as this client")
