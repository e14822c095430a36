"""``flipstudy plan``: a power analysis of a design before anyone is recruited.

    from flipstudy.study.cli.plan import add_commands
    add_commands(subparsers)          # adds `plan`, func=handler

The QUEST+ models of a design's groups (:func:`flipstudy.study.pipeline.quest_specs`,
:func:`~flipstudy.study.pipeline.group_grids`) are library code, below the CLI.
"""
from __future__ import annotations

import argparse
import json

from .common import add_json


def add_commands(subparsers) -> None:
    """Add the ``plan`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "plan", help="power analysis: trials and participants per method for a target precision",
        description=(
            "Simulated observers drawn from a population (known thresholds, widths and base rates) "
            "answer each group of DESIGN.toml twice, on the same observers: as QUEST+ over a dense "
            "grid and as constant stimuli. For a target width of the 95 % interval of the detection "
            "threshold x*, prints the trials per participant each method needs (for 90 % of "
            "observers) and the participants needed for the group's mean x* to that width."),
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=("examples:\n"
                "  flipstudy plan design.toml\n"
                "  flipstudy plan design.toml --target-width 10 --observers 400 --group smooth-increase\n"
                "  flipstudy plan design.toml --task 2afc      # as if every group were 2AFC"))
    p.add_argument("design", metavar="DESIGN.toml", help="the study design")
    p.add_argument("--target-width", type=float, default=15.0,
                   help="width of the 95 %% interval of x*, in percent (default 15)")
    p.add_argument("--observers", type=int, default=200, help="simulated observers (default 200)")
    p.add_argument("--seed", type=int, default=0, help="seed of the observers and answers (default 0)")
    p.add_argument("--max-trials", type=int, default=200,
                   help="trials simulated per observer and method (default 200)")
    p.add_argument("--group", action="append", default=[], metavar="NAME",
                   help="plan only this group (repeatable; default: every group)")
    p.add_argument("--task", choices=("yes-no", "2afc"), default=None,
                   help="the task to plan for (default: each group's own)")
    p.add_argument("--threshold", type=float, nargs=2, default=(25.0, 8.0), metavar=("MEAN", "SD"),
                   help="population of thresholds x*, percent (default 25 8)")
    add_json(p, "print the rows as JSON")
    p.set_defaults(func=handler)


def handler(args) -> int:
    """Run ``flipstudy plan``; returns the exit code."""
    from flipstudy.stimuli._progress import Heartbeat
    from flipstudy.study.pipeline import plan
    with Heartbeat("plan"):                        # a log hears from it now and then
        res = plan(args.design, groups=args.group, task=args.task, target_width=args.target_width,
                   observers=args.observers, seed=args.seed, max_trials=args.max_trials,
                   threshold=args.threshold)
    print(json.dumps([r.to_dict() for r in res.rows], indent=2) if args.json else res.summary())
    return 0
