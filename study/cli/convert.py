"""``flipstudy convert``: a clip from any reader written as BVH."""
from __future__ import annotations

from .common import add_clip, add_out, add_units, reader_options


def cmd_convert(args) -> int:
    from flipstudy.stimuli.convert import convert
    r = convert(args.clip, args.out, force=args.force, scale=args.scale, fps=args.fps,
                accept_unphysical=args.accept_unphysical, **reader_options(args))
    print(r.summary())
    return 0


def add_commands(subparsers) -> None:
    p = subparsers.add_parser(
        "convert", help="write a clip (BVH, joint positions, AMASS/SMPL) as BVH",
        description="Read CLIP by the loading rule of every command (a joint-position .npy/.npz "
                    "with --layout, an AMASS .npz with --body-model, a BVH file or a built-in; the "
                    "physics gate runs) and write it as BVH in metres.")
    add_clip(p)
    add_units(p)
    add_out(p, "OUT.bvh", "the BVH file to write")
    p.add_argument("--force", action="store_true", help="replace OUT if it exists")
    p.set_defaults(func=cmd_convert)
