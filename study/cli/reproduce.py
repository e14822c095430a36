"""``flipstudy reproduce``: the paper's study end to end on the embedded default."""
from __future__ import annotations

from .common import add_cluster


def cmd_reproduce(args) -> int:
    from flipstudy.study.pipeline import reproduce
    print(reproduce(args.out, cluster=args.cluster, participants=args.participants, seed=args.seed,
                    jobs=args.jobs, force=args.force, quiet=args.quiet).summary())
    return 0


def add_commands(subparsers) -> None:
    p = subparsers.add_parser(
        "reproduce", help="the whole pipeline on the embedded default: design → stimuli → render → "
                          "simulated sessions → analysis",
        description="Reproduce the study of Majkowska & Faloutsos 2007 (Section 7) on the built-in "
                    "flips: the paper's design, its 46 stimuli (measured), videos and composites, a "
                    "simulated panel of participants, the analysis, the Table-2 layout and the "
                    "figures. Built in a hidden folder beside OUT and moved into place at the end.")
    p.add_argument("--out", default="flipstudy-paper", metavar="OUT",
                   help="output folder (default: flipstudy-paper)")
    p.add_argument("--participants", type=int, default=19,
                   help="simulated participants (default 19, as in the paper)")
    p.add_argument("--seed", type=int, default=1, help="seed of the simulated answers and bootstraps")
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="render worker processes (default: number of CPUs)")
    p.add_argument("--force", action="store_true", help="replace OUT if it exists")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    add_cluster(p)
    p.set_defaults(func=cmd_reproduce)
