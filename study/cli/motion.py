"""``flipstudy inspect | init | stimuli | archive | edit``: clips and stimulus sets."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


from .common import add_clip_args, add_cluster, add_json, add_mass, add_out, add_study_dir, reader_options

#: the names of flipstudy.stimuli.presets.PRESETS (written out: building the parser
#: imports no numpy; a test checks they agree)
PRESET_NAMES = ("flipping-with-physics-2007", "reitsma-pollard-2003", "reitsma-andrews-pollard-2008",
                "gravity", "time-scale", "pose-rate")


def cmd_inspect(args) -> int:
    from flipstudy.study.motions import inspect
    res = inspect(args.clip, scale=args.scale, fps=args.fps,
                  readers=reader_options(args), mass=args.mass, compare=args.compare,
                  prior_masses=args.prior_masses, plot=args.plot)
    print(json.dumps(res.report, indent=2) if args.json else res.summary())
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
    from flipstudy.study.pipeline import build
    res = build(args.design, args.out, force=args.force, progress=not args.quiet, cluster=args.cluster)
    print(res.summary())
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
    with momentum repair (5.5), measured (:func:`flipstudy.study.motions.edit`)."""
    from flipstudy.study.motions import edit
    res = edit(args.clip, args.out, scale=args.scale, fps=args.fps,
               readers=reader_options(args), flips=args.flips,
               k_ratio=args.k_ratio, straighten=args.straighten, t_from=args.t_from, t_to=args.t_to,
               midpoint=args.midpoint, join_spec=args.join, mass=args.mass, plot=args.plot,
               accept_unphysical=args.accept_unphysical)
    print(res.summary())
    return 0


def add_commands(subparsers) -> None:
    p = subparsers.add_parser("inspect", help="flight analysis of one clip (units, gravity, momentum, masses)",
                       description="Find the flight, estimate segment masses, measure momentum and "
                                   "check units and frame time against gravity.")
    add_clip_args(p, gate=False)
    add_json(p)
    p.add_argument("--plot", metavar="FILE.png", help="draw |L|(t), |p|(t) and COM height")
    add_mass(p)
    p.add_argument("--prior-masses", action="store_true",
                   help="use the de Leva table masses instead of estimating them from the flight")
    p.add_argument("--compare", metavar="ORIGINAL",
                   help="measure CLIP against ORIGINAL (a stimulus against its base clip): flight |L| "
                        "and time of both, |L| change while both fly; with --plot drawn")
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
