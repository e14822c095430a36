"""``flipstudy concat``: angular-momentum guided concatenation of two motions
(Shum, Komura & Yadav 2009), with the motion-graph join as a baseline."""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyValueError

import json
import sys
from pathlib import Path

from .common import add_json, add_mass, add_out, add_units, reader_options


def _range(text: str) -> tuple[int, int]:
    try:
        a, b = text.split(":")
        a, b = int(a), int(b)
    except ValueError:
        raise FlipstudyValueError(f"a frame range is F0:F1 with whole frame numbers, got {text!r}") from None
    if not 0 <= a < b:
        raise FlipstudyValueError(f"a frame range F0:F1 needs 0 <= F0 < F1, got {text!r}")
    return a, b


def _pick(clip, rng, label: str, spec: str):
    if rng is None:
        return clip
    a, b = _range(rng)
    if b > clip.num_frames:
        raise FlipstudyValueError(f"--range-{label} {rng}: {spec} has only {clip.num_frames} frames")
    out = clip.slice(a, b)
    out.meta["name"] = f"{clip.meta.get('name', Path(spec).stem)}[{a}:{b}]"
    return out


def cmd_concat(args) -> int:
    from flipstudy.stimuli import analyse, save_bvh
    from flipstudy.stimuli.edit.concat import ConcatError, concatenate, mirror, motion_graph_join
    from .common import load_clip
    try:
        a = _pick(load_clip(args.a, args.scale, args.fps, **reader_options(args)), args.range_a, "a", args.a)
        b = _pick(load_clip(args.b, args.scale, args.fps, **reader_options(args)), args.range_b, "b", args.b)
        if args.mirror_b:
            b = mirror(b)
        body = analyse(a, total_mass=args.mass).body
        main_a = _range(args.main_a) if args.main_a else None
        main_b = _range(args.main_b) if args.main_b else None
        res = concatenate(a, b, rule=args.rule, body=body, tm_a=args.tm_a, tm_b=args.tm_b,
                          main_a=main_a, main_b=main_b, smoothing=args.smoothing)
        base = motion_graph_join(a, b, body=body) if args.baseline else None
    except ConcatError as e:
        print(f"flipstudy concat: error: {args.a} + {args.b}: {e}", file=sys.stderr)
        return 1
    save_bvh(res.clip, args.out)
    r = res.report
    out = {"out": str(args.out), **r.to_dict()}
    if base is not None:
        bpath = Path(args.out).with_name(Path(args.out).stem + "_motion-graph.bvh")
        save_bvh(base.clip, bpath)
        out["baseline"] = {"out": str(bpath), **base.report.to_dict()}
    if args.plot:
        from flipstudy.render.plots import plot_concat
        srcs = [("motion 1", a, 0), ("motion 2 at T (before smoothing)", b, r.T)]
        plot_concat(res, body, args.plot, baseline=base, sources=srcs,
                    title=f"{Path(args.out).stem}: {r.rule} rule")
        out["plot"] = str(args.plot)
    if args.ghost:
        from flipstudy.render.figures import ghost_image
        from flipstudy.render.staging import stage
        w0, w1 = r.blend_out
        fps = res.clip.fps
        t0 = max(0.0, w0 / fps - args.ghost_margin)
        t1 = min(res.clip.duration, w1 / fps + args.ghost_margin)
        import numpy as np
        from flipstudy.render.camera import transition_camera
        f0, f1 = int(t0 * fps), int(np.ceil(t1 * fps)) + 1
        cam = transition_camera(res.clip, a, body, args.ghost_view, main=r.phases_a["main"],
                                at=r.blend_out[0], frames=(f0, f1))
        ghost_image(stage([res.clip], bodies=[body], camera=cam), args.ghost, span=(t0, t1),
                    interval=args.ghost_interval)
        out["ghost"] = str(args.ghost)
    from flipstudy.stimuli.score import score
    scored = score(res.clip).clips[0]
    if args.json:
        print(json.dumps({**out, "score": scored.to_dict()}, indent=2, default=float))
        return 0
    pa, pb = r.phases_a, r.phases_b
    print(f"{args.a} + {args.b} → {args.out}: {res.clip.num_frames} frames "
          f"({res.clip.duration:.2f} s at {res.clip.fps:g} fps; the two motions: {r.frames_a} + {r.frames_b})")
    print(f"  phases                motion 1 main {pa['main'][0]}–{pa['main'][1]} (t_m {pa['tm']}), "
          f"motion 2 main {pb['main'][0]}–{pb['main'][1]} (t_m {pb['tm']})")
    print(f"  rule                  {r.rule} (suggested: {r.suggested_rule}); motion 2 turned "
          f"θ = {r.theta_deg:.1f}° about the vertical, shifted {r.shift_m[0]:+.2f}, {r.shift_m[2]:+.2f} m; "
          f"torso facing {r.facing_deg_at_fT:.0f}° apart at f_T")
    print(f"  blendable             {r.case}: motion 1 {r.blendable_a[0]}–{r.blendable_a[1]}, "
          f"motion 2 {r.blendable_b[0]}–{r.blendable_b[1]} ({r.support})")
    print(f"  timing                T = {r.T} frames, f_T = {r.f_T}; F = {r.F:.2f} "
          f"(F_dm {r.F_dm:.2f} + F_inertia {r.F_inertia:.2f} + F_time {r.F_time:.2f}; "
          f"threshold {r.threshold:.1f})")
    wid = f", widened {r.blend_widened}" if r.blend_widened else ""
    print(f"  blend                 frames {r.blend[0]}–{r.blend[1]}{wid}; |L| peak "
          f"{r.L_peak_blend_before:.1f} before smoothing")
    sm = r.smoothing
    mode = "none" if sm is None else sm["mode"]
    print(f"  smoothing             eq. 9 factor s = {r.smoothing_s:.3f} ({mode}); window now "
          f"{r.blend_out[0]}–{r.blend_out[1]}; |L| peak {r.L_peak_blend:.1f}, mean "
          f"{r.L_mean_blend:.1f} (target {r.L_target_blend:.1f}; main-phase peaks "
          f"{r.L_main_peak_a:.1f} and {r.L_main_peak_b:.1f})")
    if r.feet is not None:
        ft = r.feet
        print(f"  feet                  pinned {', '.join(ft.pinned) or 'none'} (released "
              f"{', '.join(ft.released) or '-'}); slide {ft.foot_slide_cm:.2f} cm while pinned; "
              f"lowest foot {ft.lowest_foot_above_floor_cm:+.2f} cm from the floor")
    if r.flights:
        print("  flights               " + "; ".join(
            f"{f['takeoff']}–{f['landing']} |L| CV {f['L_cv_pct']:.1f} %" for f in r.flights))
    if base is not None:
        br = base.report
        print(f"  motion graph          transition {br.transition_a} → {br.transition_b} "
              f"(window {br.window} frames, distance {br.distance:.2f}): {br.frames} frames "
              f"({br.duration_s:.2f} s) → {out['baseline']['out']}")
    for k in ("plot", "ghost"):
        if k in out:
            print(f"  {k:<22}{out[k]}")
    print("\n".join("  score: " + ln for ln in scored.summary(brief=True).splitlines()))
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
