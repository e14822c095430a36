"""``flipstudy inspect | init | stimuli | archive | edit``: clips and stimulus sets."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


from .common import add_clip_args, add_cluster, add_json, add_mass, add_out, add_study_dir, load_clip, reader_options

#: the names of flipstudy.stimuli.presets.PRESETS (written out: building the parser
#: imports no numpy; a test checks they agree)
PRESET_NAMES = ("flipping-with-physics-2007", "reitsma-pollard-2003", "reitsma-andrews-pollard-2008",
                "gravity", "time-scale", "pose-rate")


def cmd_inspect(args) -> int:
    from flipstudy.stimuli import analyse
    clip = load_clip(args.clip, args.scale, args.fps, **reader_options(args))
    original = None
    if args.compare:
        original = analyse(load_clip(args.compare, args.scale, args.fps, **reader_options(args)), total_mass=args.mass,
                           estimate=not args.prior_masses)
        # measure the stimulus with the original's body (same masses)
        a = analyse(clip, body=original.body, estimate=False)
    else:
        a = analyse(clip, total_mass=args.mass, estimate=not args.prior_masses)
    d = a.to_dict()
    if args.plot:
        from flipstudy.render.plots import plot_analysis, plot_compare
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
        print(f"  flight          frames {d['takeoff']}–{d['landing']} (contact instants at frame "
              f"{d['takeoff_time'] * d['fps']:.2f} and {d['landing_time'] * d['fps']:.2f}: {d['flight_s']:.3f} s)"
              + (f"; {len(a.flights) - 1} shorter flight(s): "
                 + ", ".join(f"{f.takeoff}–{f.landing}" for f in a.flights[1:]) if len(a.flights) > 1 else ""))
        print(f"  gravity         {d['apparent_gravity']:.2f} m/s² apparent (9.81 expected)")
        print(f"  take-off angle  {d['takeoff_angle_deg']:.1f}° above horizontal")
        print(f"  |L| in flight   mean {d['L_mean']:.2f} kg·m²/s, CV {d['L_cv_pct']:.2f} %")
        mf = d["mass_fit"]
        if mf and mf["status"] == "fitted":
            band = "no band" if mf["band_pct"] is None else f"every group within ±{mf['band_pct']:.0f} % of de Leva"
            print(f"  mass fit        fitted (W = {mf['W']:g} m²/kg², {band}): COM residual {mf['com_rms_prior_mm']:.1f} → {mf['com_rms_mm']:.1f} mm, "
                  f"momentum deviation {mf['p_dev_prior']:.3g} → {mf['p_dev']:.3g} kg·m/s "
                  f"(−{mf['p_dev_reduction_pct']:.1f} %); " +
                  ", ".join(f"{k} {mf['prior'][k]:.1f} → {v:.1f}" for k, v in mf["fitted"].items()) + " kg")
        elif mf:
            print(f"  mass fit        prior kept (W = {mf['W']:g} m²/kg²): {mf['message']}")
    masses = d["segment_masses"]
    print(f"  segment masses  (total {d['total_mass']:g} kg) " +
          ", ".join(f"{k} {v:.1f}" for k, v in masses.items()))
    for w in d["warnings"]:
        print(f"  warning: {w}")
    if args.plot:
        print(f"  plot            {args.plot}")
    return 0


def cmd_init(args) -> int:
    from flipstudy.stimuli.design import parse_design
    from flipstudy.stimuli.presets import PRESETS
    from flipstudy.study.frozen import write_design
    out = Path(args.design)
    if out.exists() and not args.force:
        print(f"flipstudy init: {out} exists; pass --force to overwrite", file=sys.stderr)
        return 1
    preset = args.preset or "flipping-with-physics-2007"
    text = PRESETS[preset]
    d = parse_design(text)              # the template must always be valid
    write_design(out, text, force=args.force)   # never the design of a study with answers
    if args.preset is None:
        print(f"wrote {out}: the design of Majkowska & Faloutsos 2007, Section 7 "
              f"(backflip and frontflip; 5 error groups × 5 levels; each motion shown twice)")
    else:
        print(f"wrote {out}: the preset {preset} ({', '.join(c.name for c in d.clips)}; "
              f"{len(d.groups)} error groups, {d.n_test_stimuli()} test stimuli; each motion shown "
              f"{d.repetitions} times); its comments say what was assumed")
    print(f"next: flipstudy stimuli {out} --out STUDY_DIR")
    return 0


def cmd_stimuli(args) -> int:
    from flipstudy.stimuli.design import load_design
    from flipstudy.stimuli.stimset import build_stimuli
    from flipstudy.study.archive import describe, refuse_real_answers
    design = load_design(args.design)
    replaced = {}

    def replace_check(folder, foreign):
        # refuses while the study holds any real answer; otherwise notes what goes
        replaced["answers"] = refuse_real_answers(folder, foreign, shown=Path(args.out))
        replaced["foreign"] = foreign

    from flipstudy.study.cluster import open_cluster
    from flipstudy.study.lock import study_closed
    with study_closed(args.out, "stimuli --force"), open_cluster(args.cluster) as cluster:
        rows = build_stimuli(design, args.out, force=args.force, progress=not args.quiet,
                             replace_check=replace_check, cluster=cluster)
    if replaced:
        print(f"replaced {args.out}: it held no real participant's answers "
              f"({describe(replaced['answers'])}); removed with it: {', '.join(replaced['foreign'])}")
    worst = max((abs(float(r["measured_error_pct"]) - float(r["nominal_error_pct"])) for r in rows), default=0.0)
    print(f"wrote {len(rows)} stimuli to {args.out} (manifest.csv, .bvh, .npz); largest gap between "
          f"measured and nominal error {worst:.2f} points (tolerance {design.tolerance_pct:g})")
    return 0


def cmd_archive(args) -> int:
    from flipstudy.study.archive import answers_in, archive_study, describe
    what = describe(answers_in(args.study_dir))
    dest = archive_study(args.study_dir, args.to)
    print(f"moved {args.study_dir} to {dest} (everything kept: {what})")
    print(f"next: flipstudy stimuli DESIGN.toml --out {args.study_dir} builds a fresh study there")
    return 0


def cmd_edit(args) -> int:
    """``flipstudy edit``: more flips (Section 5.2-5.4) and/or an animator edit
    with momentum repair (5.5), measured (:func:`flipstudy.stimuli.edit.pipeline.edit`)."""
    from flipstudy.stimuli import analyse, save_bvh
    from flipstudy.stimuli.edit.animator import AnimatorEditError
    from flipstudy.stimuli.edit.flight_measures import FlipEditError
    from flipstudy.stimuli.edit.pipeline import edit
    if args.flips is None and not args.straighten and not args.join:
        print("flipstudy edit: error: nothing to do: give --flips N, --straighten legs|arms or --join OTHER",
              file=sys.stderr)
        return 2
    clip = load_clip(args.clip, args.scale, args.fps, **reader_options(args))
    other = load_clip(args.join, args.scale, args.fps, **reader_options(args)) if args.join else None
    try:
        res = edit(clip, flips=args.flips, k_ratio=args.k_ratio, straighten=args.straighten,
                   t_from=args.t_from, t_to=args.t_to, midpoint=args.midpoint, join=other,
                   total_mass=args.mass)
    except (FlipEditError, AnimatorEditError) as e:
        print(f"flipstudy edit: error: {args.clip}: {e}", file=sys.stderr)
        return 1
    out_clip, steps, lines = res.clip, res.steps, []
    if steps.join is not None:
        r = res.report.join
        lines.append(f"join {args.join}: turned {r.yaw_deg:.0f}° about the vertical, retimed ×"
                     f"{r.retime:.3f} to match |L|; joined at frame {r.join.first} → its "
                     f"frame {r.join.second} (distance {r.join.distance:.2f})")
        xf = r.join.crossfade
        lines.append(f"cross-fade            root orientations {r.join.swing_deg:.1f}° apart ⟂ L; turns "
                     f"{xf['turned_perp_deg']:.1f}° ⟂ L ({xf['explained_perp_deg']:.1f}° explained by L, "
                     f"{xf['unexplained_deg']:.1f}° not) and {xf['turned_about_L_deg']:.1f}° about L "
                     f"({xf['explained_about_L_deg']:.1f}° explained)")
        lines.append(f"measured              turn {r.turn_deg:.1f}°, flight |L| mean {r.L_mean:.2f} "
                     f"(first {r.L_first:.2f}) CV {r.L_cv_pct:.1f} %, momentum jump take-off "
                     f"{r.dp_takeoff_pct:.1f} %, landing {r.dp_landing_pct:.1f} %")
    if steps.repair is not None:
        r = res.report.repair
        lines.append(f"straighten {args.straighten}: |L| error {r.max_error_before_pct:.0f} % before "
                     f"retiming, {r.max_error_after_pct:.1f} % after ({r.rule} rule); flight "
                     f"{r.flight_s_before:.3f} → {r.flight_s_after:.3f} s, height "
                     f"{r.jump_height_before_m:.2f} → {r.jump_height_after_m:.2f} m")
    if steps.multiflip is not None:
        r, m = res.report.multiflip, res.report.measured
        lines += [
            f"self-looping sequence  frames {r.self_loop.m}–{r.self_loop.n} "
            f"(turn {r.self_loop.phi_deg:.1f}°, distance {r.self_loop.distance:.3f}), "
            f"repeated {r.repetitions + 1}×; landing join {r.landing_join.f_source} → "
            f"{r.landing_join.g} (turn error {r.landing_join.turn_error_deg:+.1f}°, spread)",
            f"retiming              k* = {r.k_star:.3f}, k = {r.k:.3f} ({r.k_ratio:.2f} k*), "
            f"landing phase {r.k_landing:.3f}; flight {r.flight_s_before_retiming:.3f} → "
            f"{r.flight_s:.3f} s",
            f"momentum jump         take-off {r.dp_takeoff_pct:.1f} %, landing "
            f"{r.dp_landing_pct:.1f} % of the take-off momentum",
            f"measured              turn {m.turn_deg:.1f}° (frames {m.turn_span[0]}–"
            f"{m.turn_span[1]}), flight |L| mean {m.L_mean:.2f} kg·m²/s CV {m.L_cv_pct:.2f} %, "
            f"COM residual {m.com_rms_mm:.2f} mm, gravity {m.apparent_gravity:.2f} m/s²"]
    save_bvh(out_clip, args.out)
    print(f"{args.clip} → {args.out}: {out_clip.num_frames} frames at {out_clip.fps:g} fps")
    from .score import score_lines
    for ln in lines + score_lines(out_clip, res.analysis.clip):
        print("  " + ln)
    if args.plot:
        from flipstudy.render.plots import plot_compare, plot_repair
        if steps.repair is not None and args.flips is None:
            plot_repair(steps.repair, args.plot, title=f"{Path(str(args.clip)).stem}: straight {args.straighten}")
        else:
            orig = res.analysis
            plot_compare(analyse(out_clip, body=orig.body, estimate=False), orig, args.plot,
                         title=f"{Path(args.out).stem} over {Path(str(args.clip)).stem}")
        print(f"  plot                  {args.plot}")
    return 0


def add_commands(subparsers) -> None:
    p = subparsers.add_parser("inspect", help="flight analysis of one clip (units, gravity, momentum, masses)",
                       description="Find the flight, estimate segment masses, measure momentum and "
                                   "check units and frame time against gravity.")
    add_clip_args(p)
    add_json(p)
    p.add_argument("--plot", metavar="FILE.png", help="draw |L|(t), |p|(t) and COM height")
    add_mass(p)
    p.add_argument("--prior-masses", action="store_true",
                   help="use the de Leva table masses instead of estimating them from the flight")
    p.add_argument("--compare", metavar="ORIGINAL",
                   help="plot |L|(t) of CLIP over ORIGINAL (a stimulus over its base clip) to --plot")
    p.set_defaults(func=cmd_inspect)

    p = subparsers.add_parser("init", help="write a study design (TOML): the paper's design",
                       description="Write the design of the paper's study (Section 7) as a TOML file to edit.")
    p.add_argument("design", metavar="DESIGN.toml")
    p.add_argument("--force", action="store_true", help="overwrite an existing file")
    p.add_argument("--preset", metavar="NAME", choices=PRESET_NAMES,
                   help="a ready design of another study instead: " + ", ".join(PRESET_NAMES))
    p.set_defaults(func=cmd_init)

    p = subparsers.add_parser("stimuli", help="generate, measure and write the stimuli of a design",
                       description="Inject the design's errors into its clips, measure every stimulus "
                                   "with the analyser and write .bvh, .npz and manifest.csv (atomically).")
    p.add_argument("design", metavar="DESIGN.toml")
    add_out(p, "STUDY_DIR")
    p.add_argument("--force", action="store_true",
                   help="replace an existing STUDY_DIR, unless it holds any real participant's "
                        "answer (then move it aside with `flipstudy archive STUDY_DIR`); a study "
                        "with only simulated answers is replaced, and the command says so")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_cluster(p)
    p.set_defaults(func=cmd_stimuli)

    p = subparsers.add_parser("archive", help="move a whole study folder aside (STUDY-archived-DATE)",
                       description="Move STUDY_DIR, with everything in it (answers, renders, "
                                   "exports), to STUDY_DIR-archived-YYYYMMDDTHHMMSSZ beside it "
                                   "(one rename: nothing is copied or deleted), so that a fresh "
                                   "study can be built at STUDY_DIR. Waits for no build: fails "
                                   "at once while a build holds the study.")
    add_study_dir(p)
    p.add_argument("--to", metavar="DIR", default=None,
                   help="where to move it (default: STUDY_DIR-archived-DATE beside it; same file system)")
    p.set_defaults(func=cmd_archive)

    p = subparsers.add_parser("edit", help="more flips, or an animator edit in flight, with momentum repaired",
                       description="Multi-flip editing (Majkowska & Faloutsos 2007, Section 5): turn a single "
                                   "flip into N flips (self-looping search, sequencing, retiming by k, COM "
                                   "repositioning), and/or straighten the legs or arms in flight and repair "
                                   "|L| by non-uniform retiming (5.5). Prints what it did and measured.")
    add_clip_args(p)
    p.add_argument("--flips", type=int, default=None, metavar="N", help="number of flips of the result (1-6)")
    p.add_argument("--k-ratio", type=float, default=1.0,
                   help="retiming factor as a fraction of k* (default 1: linear momentum continuous at "
                        "take-off and landing; 0.7, the paper's choice, jumps higher and rotates slower "
                        "but leaves a velocity jump the score reports)")
    p.add_argument("--straighten", choices=["legs", "arms"], help="hold a joint group straight in flight")
    p.add_argument("--from", dest="t_from", type=float, default=None, metavar="T0",
                   help="edit start, seconds (default 0.1 s after take-off)")
    p.add_argument("--to", dest="t_to", type=float, default=None, metavar="T1",
                   help="edit end, seconds (default 0.1 s before landing)")
    p.add_argument("--join", metavar="OTHER",
                   help="join CLIP's take-off and early flight to OTHER's late flight and landing "
                        "(same skeleton; |L| matched by retiming)")
    p.add_argument("--midpoint", action="store_true",
                   help="second-order variant of the paper's retiming rule for the repair")
    add_mass(p)
    add_out(p, "OUT.bvh")
    p.add_argument("--plot", metavar="FILE.png",
                   help="|L|(t) of the result over the original (with --straighten alone: the error "
                        "before/after repair, the paper's Figure 3)")
    p.set_defaults(func=cmd_edit)
