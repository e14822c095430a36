"""``flipstudy concat``: angular-momentum guided concatenation of two motions
(Shum, Komura & Yadav 2009), with the motion-graph join as a baseline."""
from __future__ import annotations

import json

from .common import add_json, add_mass, add_out, add_units, reader_options


def cmd_concat(args) -> int:
    from flipstudy.study.motions import concat
    res = concat(args.a, args.b, args.out, scale=args.scale, fps=args.fps,
                 readers=reader_options(args), range_a=args.range_a,
                 range_b=args.range_b, mirror_b=args.mirror_b, mass=args.mass, rule=args.rule,
                 tm_a=args.tm_a, tm_b=args.tm_b, main_a=args.main_a, main_b=args.main_b,
                 smoothing=args.smoothing, baseline=args.baseline, plot=args.plot, ghost=args.ghost,
                 ghost_interval=args.ghost_interval, ghost_margin=args.ghost_margin,
                 ghost_view=args.ghost_view, accept_unphysical=args.accept_unphysical)
    print(json.dumps(res.report, indent=2) if args.json else res.summary())
    return 0


def add_commands(subparsers) -> None:
    """Add the ``concat`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "concat", help="join two motions with the angular momentum as the cue (Shum et al. 2009)",
        description="Concatenate motion A then motion B (same skeleton) the way people chain full-body "
                    "motions: phases from the sign of L, the forward or reverse rule, alignment about the "
                    "vertical (eq. 2), the optimal timing (eqs. 3-7), a blend (eq. 8) smoothed in time "
                    "(eq. 9), support feet pinned. Prints rule, θ, T, f_T, blend window, smoothing "
                    "factor and foot slide.")
    p.add_argument("a", metavar="A", help="first motion: built-in name or BVH path")
    p.add_argument("b", metavar="B", help="second motion: built-in name or BVH path")
    p.add_argument("--rule", choices=["forward", "reverse"], default=None,
                   help="forward: L of both the same way; reverse: opposite (default: suggested from the data)")
    p.add_argument("--range-a", metavar="F0:F1", help="use frames F0..F1-1 of A (e.g. one punch of a long take)")
    p.add_argument("--range-b", metavar="F0:F1", help="use frames F0..F1-1 of B")
    p.add_argument("--mirror-b", action="store_true",
                   help="mirror B left/right first (a right kick or punch becomes a left one)")
    p.add_argument("--tm-a", type=int, default=None, metavar="F",
                   help="a frame in the middle of A's main phase (default: largest |L|)")
    p.add_argument("--tm-b", type=int, default=None, metavar="F", help="the same for B")
    p.add_argument("--main-a", metavar="F0:F1", help="override A's main-phase borders")
    p.add_argument("--main-b", metavar="F0:F1", help="override B's main-phase borders")
    p.add_argument("--smoothing", choices=["profile", "uniform", "none"], default="profile",
                   help="angular-momentum smoothing of the blend: profile (eq. 9's mean with no jump in "
                        "speed, default), uniform (eq. 9 as printed), none")
    p.add_argument("--baseline", choices=["motion-graph"], default=None,
                   help="also join the two at their most similar poses (Kovar et al. 2002), written "
                        "beside OUT as OUT_motion-graph.bvh")
    add_mass(p)
    add_units(p, scale_help="metres per file unit (both files)", fps_help="frames per second (both files)")
    add_out(p, "OUT.bvh")
    p.add_argument("--plot", metavar="L.png", help="|L|(t) against the baseline (Figure 8 style)")
    p.add_argument("--ghost", metavar="GHOST.png", help="ghost composite of the transition")
    p.add_argument("--ghost-interval", type=float, default=0.15, metavar="S",
                   help="seconds between ghosts (default 0.15)")
    p.add_argument("--ghost-margin", type=float, default=0.4, metavar="S",
                   help="seconds shown before and after the blend (default 0.4)")
    p.add_argument("--ghost-view", choices=["across-L", "side", "three-quarter"], default="across-L",
                   help="ghost camera: across the first motion's angular momentum (default: a flip or "
                        "cartwheel seen in profile), the performer's side, or three-quarter front")
    add_json(p, "print the report as JSON")
    p.set_defaults(func=cmd_concat)
