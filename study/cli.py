"""The `flipstudy` command line."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def load_clip(spec: str, scale: float | None = None, fps: float | None = None):
    """A CLIP argument: a built-in name (backflip, frontflip, jump) or a BVH path.
    The same loading rules for every command: ``scale`` (metres per file unit;
    default guessed) and ``fps`` (default: the header's) override the file."""
    from stimuli import BUILTIN_NAMES, builtin, load_bvh
    if spec in BUILTIN_NAMES:
        clip = builtin(spec, **({"fps": fps} if fps else {}))
        if scale not in (None, 1.0):
            clip = clip.scaled(scale)
        return clip
    p = Path(spec)
    if not p.exists():
        from stimuli import BUILTIN_NAMES
        raise SystemExit(f"flipstudy: {spec!r} is neither a built-in clip "
                         f"({', '.join(BUILTIN_NAMES)}) nor an existing BVH file")
    return load_bvh(p, scale=scale, fps=fps)


def _add_clip_args(p: argparse.ArgumentParser):
    p.add_argument("clip", metavar="CLIP", help="built-in name (backflip, frontflip, jump) or BVH path")
    p.add_argument("--scale", type=float, default=None,
                   help="metres per file unit (default: guessed from the skeleton's size)")
    p.add_argument("--fps", type=float, default=None,
                   help="frames per second, overriding the file's Frame Time")


def cmd_inspect(args) -> int:
    from stimuli import analyse
    clip = load_clip(args.clip, args.scale, args.fps)
    original = None
    if args.compare:
        original = analyse(load_clip(args.compare, args.scale, args.fps), total_mass=args.mass,
                           estimate=not args.prior_masses)
        # measure the stimulus with the original's body (same masses)
        a = analyse(clip, body=original.body, estimate=False)
    else:
        a = analyse(clip, total_mass=args.mass, estimate=not args.prior_masses)
    d = a.to_dict()
    if args.plot:
        from render.plots import plot_analysis, plot_compare
        if original is not None:
            plot_compare(a, original, args.plot)
        else:
            plot_analysis(a, args.plot)
    elif args.compare:
        print("flipstudy inspect: --compare draws into the --plot file; add --plot FILE.png", file=sys.stderr)
    if args.json:
        print(json.dumps(d, indent=2))
        return 0
    fmt = lambda x, f="{:.3f}": "—" if x is None else f.format(x)  # noqa: E731
    print(f"{d['name']}: {d['frames']} frames at {d['fps']:g} fps "
          f"(header {fmt(d['header_fps'], '{:g}')}, {d['fps_source']})")
    print(f"  units           {d['scale']:.6g} m per file unit ({d['scale_source']})")
    if d["root_convention"]:
        print(f"  root            {d['root_convention']}")
    if a.flight is None:
        print("  flight          none")
    else:
        print(f"  flight          frames {d['takeoff']}–{d['landing']} ({d['flight_s']:.3f} s)"
              + (f"; {len(a.flights) - 1} shorter flight(s): "
                 + ", ".join(f"{f.takeoff}–{f.landing}" for f in a.flights[1:]) if len(a.flights) > 1 else ""))
        print(f"  gravity         {d['apparent_gravity']:.2f} m/s² apparent (9.81 expected)")
        print(f"  take-off angle  {d['takeoff_angle_deg']:.1f}° above horizontal")
        print(f"  |L| in flight   mean {d['L_mean']:.2f} kg·m²/s, CV {d['L_cv_pct']:.2f} %")
        mf = d["mass_fit"]
        if mf:
            print(f"  mass fit        COM residual {mf['com_rms_prior_mm']:.1f} → {mf['com_rms_mm']:.1f} mm, "
                  f"momentum deviation −{mf['p_dev_reduction_pct']:.0f} % (W = {mf['W']:g})")
    masses = d["segment_masses"]
    print(f"  segment masses  (total {d['total_mass']:g} kg) " +
          ", ".join(f"{k} {v:.1f}" for k, v in masses.items()))
    for w in d["warnings"]:
        print(f"  warning: {w}")
    if args.plot:
        print(f"  plot            {args.plot}")
    return 0


def cmd_init(args) -> int:
    from stimuli.design import PAPER_DESIGN, parse_design
    from stimuli.motion.bvh import atomic_write_text
    out = Path(args.design)
    if out.exists() and not args.force:
        print(f"flipstudy init: {out} exists; pass --force to overwrite", file=sys.stderr)
        return 1
    parse_design(PAPER_DESIGN)          # the template must always be valid
    atomic_write_text(out, PAPER_DESIGN)
    print(f"wrote {out}: the design of Majkowska & Faloutsos 2007, Section 7 "
          f"(backflip and frontflip; 5 error groups × 5 levels; each motion shown twice)")
    print(f"next: flipstudy stimuli {out} --out STUDY_DIR")
    return 0


def cmd_stimuli(args) -> int:
    from stimuli.design import load_design
    from stimuli.stimset import build_stimuli
    design = load_design(args.design)
    rows = build_stimuli(design, args.out, force=args.force, progress=not args.quiet)
    worst = max((abs(float(r["measured_error_pct"]) - float(r["nominal_error_pct"])) for r in rows), default=0.0)
    print(f"wrote {len(rows)} stimuli to {args.out} (manifest.csv, .bvh, .npz); largest gap between "
          f"measured and nominal error {worst:.2f} points (tolerance {design.tolerance_pct:g})")
    return 0


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="flipstudy", description=(
        "Perception studies of ballistic character motion: stimuli, rendering, sessions, analysis."))
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")
    p = sub.add_parser("inspect", help="flight analysis of one clip (units, gravity, momentum, masses)",
                       description="Find the flight, estimate segment masses, measure momentum and "
                                   "check units and frame time against gravity.")
    _add_clip_args(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE.png", help="draw |L|(t), |p|(t) and COM height")
    p.add_argument("--mass", type=float, default=70.0, help="total body mass in kg (default 70)")
    p.add_argument("--prior-masses", action="store_true",
                   help="use the de Leva table masses instead of estimating them from the flight")
    p.add_argument("--compare", metavar="ORIGINAL",
                   help="plot |L|(t) of CLIP over ORIGINAL (a stimulus over its base clip) to --plot")
    p.set_defaults(func=cmd_inspect)

    p = sub.add_parser("init", help="write a study design (TOML): the paper's design",
                       description="Write the design of the paper's study (Section 7) as a TOML file to edit.")
    p.add_argument("design", metavar="DESIGN.toml")
    p.add_argument("--force", action="store_true", help="overwrite an existing file")
    p.set_defaults(func=cmd_init)

    p = sub.add_parser("stimuli", help="generate, measure and write the stimuli of a design",
                       description="Inject the design's errors into its clips, measure every stimulus "
                                   "with the analyser and write .bvh, .npz and manifest.csv (atomically).")
    p.add_argument("design", metavar="DESIGN.toml")
    p.add_argument("--out", required=True, metavar="STUDY_DIR")
    p.add_argument("--force", action="store_true", help="replace an existing STUDY_DIR")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_stimuli)

    from render.cli import add_commands as add_render
    from study.session_cli import add_commands as add_session
    from analysis.cli import add_commands as add_analysis
    add_render(sub)
    add_session(sub)
    add_analysis(sub)
    from study.reproduce import add_commands as add_reproduce
    add_reproduce(sub)
    return ap


def main(argv: list[str] | None = None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    if not getattr(args, "func", None):
        ap.print_help()
        return 2
    try:
        return args.func(args)
    except (ValueError, OSError, KeyError) as e:   # BVHError, DesignError...: no traceback
        print(f"flipstudy {args.command}: error: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
