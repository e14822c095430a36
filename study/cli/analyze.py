"""``flipstudy analyze``: wired into the main CLI with :func:`add_commands`.

    from flipstudy.study.cli.analyze import add_commands
    add_commands(subparsers)          # adds `analyze`, func=handler
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from .common import add_json


def add_commands(subparsers) -> None:
    """Add the ``analyze`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "analyze", help="ratings, d′, statistics, tables and figures from a response table",
        description=(
            "Analyse a response table (one row per trial: participant, group, level, response, ...). "
            "Per error group and level: mean rating (% judged correct), d′ = z(P(incorrect | modified)) "
            "− z(P(incorrect | original)) pooled and per participant with bootstrap CIs, the criterion, "
            "a GEE test of each level against its original, a psychometric function with a detection "
            "threshold per group; tables (CSV, Markdown, LaTeX) and figures (PDF + PNG)."),
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=("examples:\n"
                "  flipstudy analyze responses.csv --out results/\n"
                "  flipstudy analyze STUDY_DIR            # reads STUDY_DIR/responses.csv\n"
                "  flipstudy analyze STUDY_DIR/responses.csv STUDY_DIR/web/responses.csv --out both/\n"
                "  flipstudy analyze responses.csv --out results/ --correction 1/2N --json\n"
                "  flipstudy analyze responses.csv --out results/ --image ghost_orig.png "
                "--image 'ghost strongest error=ghost_50.png'"))
    p.add_argument("responses", metavar="RESPONSES", nargs="+",
                   help="responses CSV, or a study folder holding responses.csv; several are "
                        "analysed together (e.g. STUDY/responses.csv STUDY/web/responses.csv), "
                        "refused if one participant ID is in two of them")
    p.add_argument("--out", metavar="DIR", default=None,
                   help="output folder (default: RESPONSES' folder/analysis)")
    p.add_argument("--correction", default="loglinear",
                   help="rates of 0 or 1: loglinear (default; Hautus 1995), loglinear-all, or 1/2N")
    p.add_argument("--seed", type=int, default=0, help="seed of every random draw (default 0)")
    p.add_argument("--n-boot", type=int, default=2000, help="bootstrap resamples (default 2000)")
    p.add_argument("--ci", type=float, default=0.95, help="confidence level (default 0.95)")
    p.add_argument("--psychometric", choices=("psignifit", "none"), default="psignifit",
                   help="psychometric fit: psignifit (Bayesian, the default) or none")
    p.add_argument("--include-simulated", action="store_true",
                   help="keep simulated participants (column simulated=true; left out by default)")
    p.add_argument("--include-incomplete", action="store_true",
                   help="keep sessions that did not answer every trial (column complete=false; left "
                        "out by default)")
    p.add_argument("--no-gee", action="store_true", help="skip the GEE tests")
    p.add_argument("--no-figures", action="store_true", help="tables only")
    p.add_argument("--image", action="append", default=[], metavar="[LABEL=]PNG",
                   help="an image for the figure sheet (repeatable; without labels the order is: ghost "
                        "original, ghost strongest error, trail original, trail strongest error)")
    add_json(p, "print the summary as one JSON object")
    p.set_defaults(func=handler)


def _images(specs):
    from flipstudy.analysis.pipeline import IMAGE_SLOTS
    out = {}
    for i, s in enumerate(specs):
        if "=" in s and not Path(s).exists():
            label, path = s.split("=", 1)
        else:
            label, path = (IMAGE_SLOTS[i] if i < len(IMAGE_SLOTS) else Path(s).stem), s
        out[label.strip()] = Path(path)
    return out





def handler(args) -> int:
    """Run ``flipstudy analyze``; returns the exit code."""
    from .compare import analyze_comparison_cmd, wants_comparison
    if wants_comparison(args):                 # a study with [[sources]]: the ranking of the sources
        return analyze_comparison_cmd(args)
    from flipstudy.stimuli._progress import Heartbeat
    from flipstudy.study.pipeline import analyze
    with Heartbeat("analyze"):                     # a log hears from it now and then
        res = analyze(args.responses, args.out, correction=args.correction,
                      images=_images(args.image), seed=args.seed, n_boot=args.n_boot, ci=args.ci,
                      psychometric=args.psychometric, gee=not args.no_gee,
                      figures=not args.no_figures, include_simulated=args.include_simulated,
                      include_incomplete=args.include_incomplete)
    print(json.dumps(res.report.to_dict(), indent=2, ensure_ascii=False) if args.json else res.summary())
    return 0
