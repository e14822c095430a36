"""``flipstudy analyze``: wired into the main CLI with :func:`add_commands`.

    from flipstudy.study.cli.analyze import add_commands
    add_commands(subparsers)          # adds `analyze`, func=handler
"""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyError

import argparse
import json
import sys
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


def _design_specs(sources):
    """The QUEST+ models of the groups of the study folder's design.toml (beside the first
    responses table), to replay adaptive answers; None without a design."""
    from flipstudy.analysis.io import resolve_responses_path
    from flipstudy.stimuli.design import load_design

    from .plan import quest_specs
    design = resolve_responses_path(sources[0]).parent / "design.toml"
    return quest_specs(load_design(design)) if design.is_file() else None


def handler(args) -> int:
    """Run ``flipstudy analyze``; returns the exit code."""
    from flipstudy.analysis.io import NeedsExport, combine_responses, resolve_responses_path
    from flipstudy.analysis.pipeline import analyze
    from .compare import analyze_comparison_cmd, wants_comparison
    if wants_comparison(args):                 # a study with [[sources]]: the ranking of the sources
        return analyze_comparison_cmd(args)
    try:
        src = resolve_responses_path(args.responses[0])
        from ..frozen import refuse_changed_design
        for r in args.responses:           # a study whose design changed after its answers
            refuse_changed_design(resolve_responses_path(r).parent, "analyze")
        out = Path(args.out) if args.out else src.parent / "analysis"
        if len(args.responses) > 1:
            src = combine_responses(args.responses)
        res = analyze(src, out, correction=args.correction, images=_images(args.image) or None,
                      quest_specs=_design_specs(args.responses),
                      seed=args.seed, n_boot=args.n_boot, ci=args.ci, psychometric=args.psychometric,
                      gee=not args.no_gee, figures=not args.no_figures,
                      include_simulated=args.include_simulated,
                      include_incomplete=args.include_incomplete)
    except NeedsExport as e:
        print(f"flipstudy analyze: {e}", file=sys.stderr)
        return 2
    except FlipstudyError as e:
        print(f"flipstudy analyze: error: {e}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(res.to_dict(), indent=2, ensure_ascii=False))
        return 0
    s = res.settings
    who = s["participants"]
    print(f"analysed {s['n_trials']} trials of {s['participants_label']} "
          f"({len(s['groups'])} groups); correction for rates of 0 or 1: {s['correction']}")
    if who["simulated_left_out"]:
        print(f"left out {len(who['simulated_left_out'])} simulated participant(s) "
              f"(--include-simulated to keep them)")
    if who["incomplete_left_out"]:
        print(f"left out {len(who['incomplete_left_out'])} incomplete session(s) "
              f"(--include-incomplete to keep them): {', '.join(who['incomplete_left_out'][:8])}"
              + (", ..." if len(who["incomplete_left_out"]) > 8 else ""))
    if who["n"] < 5:
        print(f"note: with {who['n']} participant(s), intervals and tests over participants are "
              f"not meaningful (notes.md)")
    print()
    from flipstudy.analysis.tables import to_markdown
    print(to_markdown(res.table))
    if len(res.thresholds):
        print("detection thresholds (P(incorrect) = (1 + γ)/2):")
        for _, t in res.thresholds.iterrows():
            if t["reached"]:
                hi = "open" if t["threshold_ci_high"] != t["threshold_ci_high"] else f"{t['threshold_ci_high']:.1f}"
                print(f"  {t['group']:20s} {t['threshold']:5.1f} %  [{t['threshold_ci_low']:.1f}, {hi}]")
            else:
                print(f"  {t['group']:20s} not reached")
    if res.group_thresholds is not None and len(res.group_thresholds):
        print("per-participant thresholds x* (thresholds_participants.csv), per group:")
        for _, t in res.group_thresholds.iterrows():
            print(f"  {t['group']:20s} {t['method']:8s} {t['task']:6s} N = {t['n_participants']:<3d} "
                  f"median {t['median']:5.1f} %  quartiles [{t['q25']:.1f}, {t['q75']:.1f}]  "
                  f"mean 95 % interval width {t['mean_ci_width']:.1f} %")
    notable = [n for n in res.notes if "not found" in n or "no images" in n or "failed" in n
               or "differ from the ones the session stored" in n or "no design" in n]
    for n in notable:
        print(f"note: {n}")
    print(f"\nwrote {len(res.files)} files to {out}/ (table.csv, table_paper.md/.tex, figures, notes.md)")
    return 0
