"""``flipstudy score`` and ``flipstudy calibrate`` (what ``edit``, ``concat`` and ``jump``
print about their output is :func:`flipstudy.stimuli.score.score_lines`)."""
from __future__ import annotations

import glob
import sys
from pathlib import Path

from .common import add_json, add_units, load_clip, reader_options


def _expand(specs) -> list[str]:
    """CLIP arguments: built-in names, BVH paths, folders (their *.bvh) and globs."""
    out = []
    for s in specs:
        p = Path(s)
        if p.is_dir():
            out += sorted(str(f) for f in p.glob("*.bvh"))
        elif any(c in s for c in "*?[") and not p.exists():
            out += sorted(glob.glob(s))
        else:
            out.append(s)
    return out


def cmd_score(args) -> int:
    from flipstudy.errors import FlipstudyValueError
    from flipstudy.stimuli.score import score
    names = _expand(args.clips)
    if not names:
        raise FlipstudyValueError(f"no clips found in {' '.join(args.clips)}")
    if args.figure and len(names) != 1:
        raise FlipstudyValueError("--figure draws one clip: give a single CLIP")
    # score measures what is physically wrong (a gravity error included): the gate's findings are
    # measured and reported, not refused
    clips = [load_clip(n, args.scale, args.fps, check=False, **reader_options(args)) for n in names]
    res = score(clips, args.calibration, task=args.task, style=args.style)
    print(res.to_json(indent=2) if args.json else res.summary())
    if args.figure:
        from flipstudy.render.score_figure import score_figure
        score_figure(clips[0], res.clips[0], args.figure)
        print(f"figure: {args.figure}", file=sys.stderr if args.json else sys.stdout)
    return 0


def cmd_calibrate(args) -> int:
    from flipstudy.study.calibrate import calibrate
    cal = calibrate(args.studies, include_simulated=args.include_simulated, seed=args.seed)
    cal.save(args.out)
    print(f"wrote {args.out}: {len(cal.functions)} psychometric functions ({cal.description})")
    for f in cal.functions:
        thr = (f"x* = {f.threshold:.1f} {f.unit}" if f.threshold is not None else "x* not reached")
        print(f"  {f.describe()}: {thr}")
    return 0


def add_commands(subparsers) -> None:
    p = subparsers.add_parser(
        "score", help="how likely a viewer notices each physical error of a motion",
        description=("Measure every physical inconsistency of each CLIP (per ballistic and ground "
                     "phase, in the unit of the study kind that injects it) and give each the "
                     "probability of being noticed, with a 95 % interval, from a calibration (the "
                     "default: FwP 2007 Table 2, real participants). P(anything noticed) = "
                     "1 − Π(1 − p_i), independent detectors. A kind without calibration is "
                     "measured, not scored."))
    p.add_argument("clips", metavar="CLIP", nargs="+",
                   help="built-in name, BVH path, a folder of BVH files, or a quoted glob")
    add_units(p, gate=False)             # score measures the physics findings it would refuse
    p.add_argument("--calibration", metavar="FILE", default=None,
                   help="a calibration file from `flipstudy calibrate` (default: the shipped one)")
    p.add_argument("--task", choices=("yes-no", "2afc"), default="yes-no",
                   help="whose functions to use (default yes-no)")
    p.add_argument("--style", default=None, help="the character style viewers see (default: any)")
    p.add_argument("--figure", metavar="OUT.png", default=None,
                   help="timeline with phases and each error's probability, and the worst moment")
    add_json(p)
    p.set_defaults(func=cmd_score)

    p = subparsers.add_parser(
        "calibrate", help="fit a calibration file from perception studies",
        description=("Per error kind, variant, sign, task and character style: the psychometric "
                     "function (psignifit, as `analyze`) with credible intervals, the numbers of "
                     "real and simulated participants and the studies' file hashes. Simulated "
                     "participants are left out unless --include-simulated (the file then says so)."))
    p.add_argument("studies", metavar="STUDY", nargs="+", help="study folders (responses.csv, design.toml)")
    p.add_argument("--out", required=True, metavar="FILE.json", help="the calibration file to write")
    p.add_argument("--include-simulated", action="store_true",
                   help="fit simulated participants too (the file says so)")
    p.add_argument("--seed", type=int, default=0, help="seed of the posterior samples (default 0)")
    p.set_defaults(func=cmd_calibrate)
