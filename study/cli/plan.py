"""``flipstudy plan``: a power analysis of a design before anyone is recruited.

    from flipstudy.study.cli.plan import add_commands
    add_commands(subparsers)          # adds `plan`, func=handler

Also :func:`quest_specs`: a design's groups as the analysis's QUEST+ models
(levels, task, settings), which ``flipstudy analyze`` uses to replay answers.
"""
from __future__ import annotations

import argparse
import json
from dataclasses import asdict

from .common import add_json

#: a group with at most this many levels is a constant-stimuli design as it stands;
#: QUEST+ then chooses from a 1 % grid over its range
CONSTANT_MAX_LEVELS = 10


def _settings(group):
    from flipstudy.analysis.adaptive import QuestSettings
    q = getattr(group, "quest", None)
    if q is None:
        return QuestSettings()
    if isinstance(q, QuestSettings):
        return q
    return QuestSettings(**asdict(q))


def _task(design, group, override=None) -> str:
    return override or getattr(group, "task", None) or getattr(design, "task", None) or "yes-no"


def quest_specs(design) -> dict:
    """group name → (levels, task, QuestSettings) of every group of a loaded design."""
    return {g.name: (list(g.levels), _task(design, g), _settings(g)) for g in design.groups}


def group_grids(levels, task: str):
    """(QUEST+ grid, constant levels) for a group's levels: a dense grid is QUEST+'s and
    constant stimuli get 5 levels spread over it; a few levels are the constant design and
    QUEST+ gets a 1 % grid over their range."""
    import numpy as np
    lv = np.unique(np.abs(np.asarray(levels, float)))
    top = float(lv.max())
    if len(lv) > CONSTANT_MAX_LEVELS:
        quest = lv
        constant = np.unique(np.round(np.linspace(0, top, 5) / (lv[1] - lv[0])) * (lv[1] - lv[0]))
    else:
        quest, constant = np.arange(0.0, np.floor(top) + 1.0), lv
    if task == "2afc":
        constant = constant[constant > 0]
    return quest, constant


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
    from flipstudy.analysis.plan import format_plan, plan_group
    from flipstudy.stimuli.design import load_design
    from flipstudy.stimuli.exceptions import FlipstudyValueError

    design = load_design(args.design)
    groups = [g for g in design.groups if not args.group or g.name in args.group]
    missing = set(args.group) - {g.name for g in design.groups}
    if missing:
        raise FlipstudyValueError(f"{args.design}: no group {', '.join(sorted(missing))} (groups: "
                                  f"{', '.join(g.name for g in design.groups)})")
    if args.observers < 10 or args.max_trials < 5:
        raise FlipstudyValueError("--observers: at least 10; --max-trials: at least 5")
    rows = []
    for g in groups:
        task = _task(design, g, args.task)
        quest, constant = group_grids(g.levels, task)
        rows += plan_group(g.name, task, quest, constant, target_width=args.target_width,
                           settings=_settings(g), n_observers=args.observers,
                           max_trials=args.max_trials, seed=args.seed,
                           threshold=tuple(args.threshold))
    if args.json:
        print(json.dumps([{k: (v if not isinstance(v, float) or v == v and abs(v) != float("inf")
                               else None) for k, v in r.items()} for r in rows], indent=2))
        return 0
    print(format_plan(rows, args.target_width, max_trials=args.max_trials))
    print(f"\n{args.observers} simulated observers per group (x* ~ N({args.threshold[0]:g}, "
          f"{args.threshold[1]:g}) %, widths 8–40 %, yes/no base rates 0.05–0.45, lapse 0.02), "
          f"seed {args.seed}; both methods scored by the same posterior (flipstudy.analysis.adaptive).")
    return 0
