"""The motion commands' library side: ``flipstudy inspect``, ``edit``, ``concat``
and ``jump`` as one call each that returns a typed
:class:`~flipstudy.results.MotionResult` (its ``report`` is what ``--json``
prints, ``summary()`` the text)."""
from __future__ import annotations

import json

import numpy as np
from pathlib import Path

from flipstudy.errors import FlipstudyUsageError, FlipstudyValueError
from flipstudy.results import MotionResult


def _range(text: str) -> tuple[int, int]:
    try:
        a, b = text.split(":")
        a, b = int(a), int(b)
    except ValueError:
        raise FlipstudyValueError(f"a frame range is F0:F1 with whole frame numbers, got {text!r}") from None
    if not 0 <= a < b:
        raise FlipstudyValueError(f"a frame range F0:F1 needs 0 <= F0 < F1, got {text!r}")
    return a, b


def _signed(v: float) -> str:
    """``v`` to 0.1 with its sign, the minus a true minus (``−2.6``, ``+2.6``)."""
    return f"{v:+.1f}".replace("-", "−")


def _pick(clip, rng, label: str, spec: str):
    if rng is None:
        return clip
    a, b = _range(rng)
    if b > clip.num_frames:
        raise FlipstudyValueError(f"--range-{label} {rng}: {spec} has only {clip.num_frames} frames")
    out = clip.slice(a, b)
    out.meta["name"] = f"{clip.meta.get('name', Path(spec).stem)}[{a}:{b}]"
    return out


def concat(a_spec: str, b_spec: str, out_path, *, scale=None, fps=None,
           readers=None, range_a=None, range_b=None,
           mirror_b: bool = False, mass: float = 70.0, rule=None, tm_a=None, tm_b=None, main_a=None,
           main_b=None, smoothing: str = "profile", baseline=None, plot=None, ghost=None,
           ghost_interval: float = 0.15, ghost_margin: float = 0.4, ghost_view: str = "across-L",
           accept_unphysical: bool = False) -> MotionResult:
    """``flipstudy concat``: motions ``a_spec`` and ``b_spec`` (built-in names or BVH
    paths) joined with the angular momentum as the cue
    (:func:`flipstudy.stimuli.edit.concat.concatenate`), written to ``out_path``; with
    ``baseline="motion-graph"`` the motion-graph join beside it, with ``plot`` the
    |L|(t) figure, with ``ghost`` a ghost composite of the transition.  Frame ranges
    are ``"F0:F1"`` strings."""
    from flipstudy.stimuli import analyse, save_bvh
    from flipstudy.errors import ConcatError
    from flipstudy.stimuli.edit.concat import concatenate, mirror, motion_graph_join
    from flipstudy.stimuli.loading import load_clip
    try:
        a = _pick(load_clip(a_spec, scale, fps, accept_unphysical, **(readers or {})), range_a, "a", a_spec)
        b = _pick(load_clip(b_spec, scale, fps, accept_unphysical, **(readers or {})), range_b, "b", b_spec)
        if mirror_b:
            b = mirror(b)
        body = analyse(a, total_mass=mass).body
        main_a = _range(main_a) if main_a else None
        main_b = _range(main_b) if main_b else None
        res = concatenate(a, b, rule=rule, body=body, tm_a=tm_a, tm_b=tm_b,
                          main_a=main_a, main_b=main_b, smoothing=smoothing)
        base = motion_graph_join(a, b, body=body) if baseline else None
    except ConcatError as e:                 # the message names the two motions
        raise ConcatError(f"{a_spec} + {b_spec}: {e}") from None
    save_bvh(res.clip, out_path)
    r = res.report
    out = {"out": str(out_path), **r.to_dict()}
    if base is not None:
        bpath = Path(out_path).with_name(Path(out_path).stem + "_motion-graph.bvh")
        save_bvh(base.clip, bpath)
        out["baseline"] = {"out": str(bpath), **base.report.to_dict()}
    if plot:
        from flipstudy.render.plots import plot_concat
        srcs = [("motion 1", a, 0), ("motion 2 at T (before smoothing)", b, r.T)]
        plot_concat(res, body, plot, baseline=base, sources=srcs,
                    title=f"{Path(out_path).stem}: {r.rule} rule")
        out["plot"] = str(plot)
    if ghost:
        _concat_ghost(res, a, body, ghost, ghost_margin, ghost_interval, ghost_view)
        out["ghost"] = str(ghost)
    lines = _concat_lines(a_spec, b_spec, out_path, res, base, out)
    for k in ("plot", "ghost"):
        if k in out:
            lines.append(f"  {k:<22}{out[k]}")
    from flipstudy.stimuli.score import score
    scored = score(res.clip).clips[0]
    lines += ["  score: " + ln for ln in scored.summary(brief=True).splitlines()]
    out["score"] = scored.to_dict()
    return MotionResult(command="concat", out=Path(out_path),
                        report=json.loads(json.dumps(out, default=float)), lines=tuple(lines))


def _concat_ghost(res, a, body, ghost, ghost_margin: float, ghost_interval: float, ghost_view: str):
    """The ghost composite of a concatenation's transition, written to ``ghost``."""
    from flipstudy.render.figures import ghost_image
    from flipstudy.render.staging import stage
    r = res.report
    w0, w1 = r.blend_out
    fps = res.clip.fps
    t0 = max(0.0, w0 / fps - ghost_margin)
    t1 = min(res.clip.duration, w1 / fps + ghost_margin)
    import numpy as np
    from flipstudy.render.camera import transition_camera
    f0, f1 = int(t0 * fps), int(np.ceil(t1 * fps)) + 1
    cam = transition_camera(res.clip, a, body, ghost_view, main=r.phases_a["main"],
                            at=r.blend_out[0], frames=(f0, f1))
    ghost_image(stage([res.clip], bodies=[body], camera=cam), ghost, span=(t0, t1),
                interval=ghost_interval)


def _concat_lines(a_spec: str, b_spec: str, out_path, res, base, out: dict) -> list[str]:
    """What ``flipstudy concat`` prints of a concatenation (before the paths and the score)."""
    r = res.report
    lines = []
    pa, pb = r.phases_a, r.phases_b
    lines.append(f"{a_spec} + {b_spec} → {out_path}: {res.clip.num_frames} frames "
                 f"({res.clip.duration:.2f} s at {res.clip.fps:g} fps; the two motions: {r.frames_a} + {r.frames_b})")
    lines.append(f"  phases                motion 1 main {pa['main'][0]}–{pa['main'][1]} (t_m {pa['tm']}), "
                 f"motion 2 main {pb['main'][0]}–{pb['main'][1]} (t_m {pb['tm']})")
    lines.append(f"  rule                  {r.rule} (suggested: {r.suggested_rule}); motion 2 turned "
                 f"θ = {r.theta_deg:.1f}° about the vertical, shifted {r.shift_m[0]:+.2f}, {r.shift_m[2]:+.2f} m; "
                 f"torso facing {r.facing_deg_at_fT:.0f}° apart at f_T")
    lines.append(f"  blendable             {r.case}: motion 1 {r.blendable_a[0]}–{r.blendable_a[1]}, "
                 f"motion 2 {r.blendable_b[0]}–{r.blendable_b[1]} ({r.support})")
    lines.append(f"  timing                T = {r.T} frames, f_T = {r.f_T}; F = {r.F:.2f} "
                 f"(F_dm {r.F_dm:.2f} + F_inertia {r.F_inertia:.2f} + F_time {r.F_time:.2f}; "
                 f"threshold {r.threshold:.1f})")
    wid = f", widened {r.blend_widened}" if r.blend_widened else ""
    lines.append(f"  blend                 frames {r.blend[0]}–{r.blend[1]}{wid}; |L| peak "
                 f"{r.L_peak_blend_before:.1f} before smoothing")
    sm = r.smoothing
    mode = "none" if sm is None else sm["mode"]
    lines.append(f"  smoothing             eq. 9 factor s = {r.smoothing_s:.3f} ({mode}); window now "
                 f"{r.blend_out[0]}–{r.blend_out[1]}; |L| peak {r.L_peak_blend:.1f}, mean "
                 f"{r.L_mean_blend:.1f} (target {r.L_target_blend:.1f}; main-phase peaks "
                 f"{r.L_main_peak_a:.1f} and {r.L_main_peak_b:.1f})")
    if r.feet is not None:
        ft = r.feet
        lines.append(f"  feet                  pinned {', '.join(ft.pinned) or 'none'} (released "
                     f"{', '.join(ft.released) or '-'}); slide {ft.foot_slide_cm:.2f} cm while pinned; "
                     f"lowest foot {ft.lowest_foot_above_floor_cm:+.2f} cm from the floor")
    if r.flights:
        lines.append("  flights               " + "; ".join(
                   f"{f['takeoff']}–{f['landing']} |L| CV {f['L_cv_pct']:.1f} %" for f in r.flights))
    if base is not None:
        br = base.report
        lines.append(f"  motion graph          transition {br.transition_a} → {br.transition_b} "
                     f"(window {br.window} frames, distance {br.distance:.2f}): {br.frames} frames "
                     f"({br.duration_s:.2f} s) → {out['baseline']['out']}")
    return lines


def inspect(clip_spec: str, *, scale=None, fps=None, readers=None, mass: float = 70.0, compare=None,
            prior_masses: bool = False, plot=None) -> MotionResult:
    """``flipstudy inspect``: the flight analysis of one clip (units, flight, gravity,
    momentum, masses); with ``compare`` measured with that original's body, drawn
    against it into ``plot``.  ``readers`` (here and in :func:`concat`, :func:`edit`,
    :func:`figure`): the position and AMASS readers' keywords of
    :func:`~flipstudy.stimuli.loading.load_clip` (``layout``, ``up``, ``body_model``)."""
    from flipstudy.stimuli import analyse
    from flipstudy.stimuli.loading import load_clip
    clip = load_clip(clip_spec, scale, fps, check=False, **(readers or {}))      # its findings are warnings here
    original = None
    if compare:
        original = analyse(load_clip(compare, scale, fps, check=False, **(readers or {})), total_mass=mass,
                           estimate=not prior_masses)
        # measure the stimulus with the original's body (same masses)
        a = analyse(clip, body=original.body, estimate=False)
    else:
        a = analyse(clip, total_mass=mass, estimate=not prior_masses)
    d = a.to_dict()
    if plot:
        from flipstudy.render.plots import plot_analysis, plot_compare
        if original is not None:
            plot_compare(a, original, plot)
        else:
            plot_analysis(a, plot)
    lines = []
    fmt = lambda x, f="{:.3f}": "—" if x is None else f.format(x)  # noqa: E731
    lines.append(f"{d['name']}: {d['frames']} frames at {d['fps']:g} fps "
                 f"(header {fmt(d['header_fps'], '{:g}')}, {d['fps_source']})")
    lines.append(f"  units           {d['scale']:.6g} m per file unit ({d['scale_source']})")
    if d["root_convention"]:
        lines.append(f"  root            {d['root_convention']}")
    if a.flight is None:
        lines.append("  flight          none")
    else:
        lines.append(f"  flight          frames {d['takeoff']}–{d['landing']} (contact instants at frame "
                     f"{d['takeoff_time'] * d['fps']:.2f} and {d['landing_time'] * d['fps']:.2f}: {d['flight_s']:.3f} s)"
                     + (f"; {len(a.flights) - 1} shorter flight(s): "
                        + ", ".join(f"{f.takeoff}–{f.landing}" for f in a.flights[1:]) if len(a.flights) > 1 else ""))
        lines.append(f"  gravity         {d['apparent_gravity']:.2f} m/s² apparent (9.81 expected)")
        lines.append(f"  take-off angle  {d['takeoff_angle_deg']:.1f}° above horizontal")
        lines.append(f"  |L| in flight   mean {d['L_mean']:.2f} kg·m²/s, CV {d['L_cv_pct']:.2f} %")
        mf = d["mass_fit"]
        if mf and mf["status"] == "fitted":
            band = "no band" if mf["band_pct"] is None else f"every group within ±{mf['band_pct']:.0f} % of de Leva"
            lines.append(f"  mass fit        fitted (W = {mf['W']:g} m²/kg², {band}): COM residual {mf['com_rms_prior_mm']:.1f} → {mf['com_rms_mm']:.1f} mm, "
                         f"momentum deviation {mf['p_dev_prior']:.3g} → {mf['p_dev']:.3g} kg·m/s "
                         f"({_signed(-mf['p_dev_reduction_pct'])} %); " +
                         ", ".join(f"{k} {mf['prior'][k]:.1f} → {v:.1f}" for k, v in mf["fitted"].items()) + " kg")
        elif mf:
            lines.append(f"  mass fit        prior kept (W = {mf['W']:g} m²/kg²): {mf['message']}")
    masses = d["segment_masses"]
    lines.append(f"  segment masses  (total {d['total_mass']:g} kg) " +
                 ", ".join(f"{k} {v:.1f}" for k, v in masses.items()))
    if original is not None:
        from flipstudy.stimuli.lchange import l_change
        ch = l_change(a, original)
        lines.append(f"  against {compare}: " + (ch.summary() if ch is not None else
                                                   "no flight in one of the two, nothing to compare"))
        d["compare"] = None if ch is None else {
            "original": str(compare), "L_mean": ch.L_mean_stim, "L_mean_original": ch.L_mean_orig,
            "flight_s": ch.flight_s_stim, "flight_s_original": ch.flight_s_orig,
            "L_change_pct_median": float(np.median(ch.pct)) if ch.pct.size else None,
            "L_change_pct_min": float(ch.pct.min()) if ch.pct.size else None,
            "L_change_pct_max": float(ch.pct.max()) if ch.pct.size else None}
    for w in d["warnings"]:
        lines.append(f"  warning: {w}")
    if plot:
        lines.append(f"  plot            {plot}")
    return MotionResult(command="inspect", out=None, report=json.loads(json.dumps(d)),
                        lines=tuple(lines))


def edit(clip_spec: str, out, *, scale=None, fps=None, readers=None, flips=None, k_ratio: float = 1.0,
         straighten=None, t_from=None, t_to=None, midpoint: bool = False, join_spec=None,
         mass: float = 70.0, plot=None, accept_unphysical: bool = False) -> MotionResult:
    """``flipstudy edit``: more flips (Section 5.2-5.4) and/or an animator edit with
    momentum repair (5.5), measured (:func:`flipstudy.stimuli.edit.pipeline.edit`),
    written to ``out``."""
    from flipstudy.stimuli import analyse, save_bvh
    from flipstudy.errors import AnimatorEditError, FlipEditError
    from flipstudy.stimuli.edit.pipeline import edit as edit_clip
    from flipstudy.stimuli.loading import load_clip
    if flips is None and not straighten and not join_spec:
        raise FlipstudyUsageError("nothing to do: give --flips N, --straighten legs|arms or --join OTHER")
    clip = load_clip(clip_spec, scale, fps, accept_unphysical, **(readers or {}))
    other = load_clip(join_spec, scale, fps, accept_unphysical, **(readers or {})) if join_spec else None
    try:
        res = edit_clip(clip, flips=flips, k_ratio=k_ratio, straighten=straighten,
                   t_from=t_from, t_to=t_to, midpoint=midpoint, join=other,
                   total_mass=mass)
    except (FlipEditError, AnimatorEditError) as e:       # the message names the clip
        raise type(e)(f"{clip_spec}: {e}") from None
    out_clip, steps, notes = res.clip, res.steps, []
    if steps.join is not None:
        r = res.report.join
        notes.append(f"join {join_spec}: turned {r.yaw_deg:.0f}° about the vertical, retimed ×"
                     f"{r.retime:.3f} to match |L|; joined at frame {r.join.first} → its "
                     f"frame {r.join.second} (distance {r.join.distance:.2f})")
        xf = r.join.crossfade
        notes.append(f"cross-fade            root orientations {r.join.swing_deg:.1f}° apart ⟂ L; turns "
                     f"{xf['turned_perp_deg']:.1f}° ⟂ L ({xf['explained_perp_deg']:.1f}° explained by L, "
                     f"{xf['unexplained_deg']:.1f}° not) and {xf['turned_about_L_deg']:.1f}° about L "
                     f"({xf['explained_about_L_deg']:.1f}° explained)")
        notes.append(f"measured              turn {r.turn_deg:.1f}°, flight |L| mean {r.L_mean:.2f} "
                     f"(first {r.L_first:.2f}) CV {r.L_cv_pct:.1f} %, momentum jump take-off "
                     f"{r.dp_takeoff_pct:.1f} %, landing {r.dp_landing_pct:.1f} %")
    if steps.repair is not None:
        r = res.report.repair
        notes.append(f"straighten {straighten}: |L| error {r.max_error_before_pct:.0f} % before "
                     f"retiming, {r.max_error_after_pct:.1f} % after ({r.rule} rule); flight "
                     f"{r.flight_s_before:.3f} → {r.flight_s_after:.3f} s, height "
                     f"{r.jump_height_before_m:.2f} → {r.jump_height_after_m:.2f} m")
    if steps.multiflip is not None:
        r, m = res.report.multiflip, res.report.measured
        notes += [
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
    save_bvh(out_clip, out)
    lines = []
    lines.append(f"{clip_spec} → {out}: {out_clip.num_frames} frames at {out_clip.fps:g} fps")
    from flipstudy.stimuli.score import score_lines
    lines += ["  " + ln for ln in notes + score_lines(out_clip, res.analysis.clip)]
    if plot:
        from flipstudy.render.plots import plot_compare, plot_repair
        if steps.repair is not None and flips is None:
            plot_repair(steps.repair, plot, title=f"{Path(str(clip_spec)).stem}: straight {straighten}")
        else:
            orig = res.analysis
            plot_compare(analyse(out_clip, body=orig.body, estimate=False), orig, plot,
                         title=f"{Path(out).stem} over {Path(str(clip_spec)).stem}", label="edited")
        lines.append(f"  plot                  {plot}")
    return MotionResult(command="edit", out=Path(out), report={"out": str(out),
                        "frames": out_clip.num_frames, "fps": float(out_clip.fps)}, lines=tuple(lines))


def jump(to, out, *, scene="forward", air=None, windup=None, k="global-normal", strength=None,
         gravity: float = 9.81, mass: float = 70.0, height: float = 1.75, fps: float = 120.0,
         strip=None, composite=None) -> MotionResult:
    """``flipstudy jump``: a standing jump to ``to`` (x, y, z in metres) from the
    energy-based controller of Ooi (2016), written to ``out`` (with ``strip`` and
    ``composite`` figures); ``strength`` None is the controller's default."""
    from flipstudy.stimuli import save_bvh
    from flipstudy.stimuli.control import jump as make_jump
    from flipstudy.stimuli.control import STRENGTH, make_course
    strength = STRENGTH if strength is None else strength
    course = scene
    if scene == "box" and to is not None:
        course = make_course("box", box_height=to[1], target=to)
    res = make_jump(to, course=course, t_air=air, t_windup=windup, k=k,
                    strength=strength, g=gravity, mass=mass, height=height,
                    fps=fps)
    clip = res.clip
    save_bvh(clip, out)
    from flipstudy.render.figures import jump_figures
    figs = jump_figures(res, strip, composite) if (strip or composite) else {}
    r = res.report
    lines = []
    f3 = lambda v: "(" + ", ".join(f"{x:.3f}" for x in v) + ")"  # noqa: E731
    lines.append(f"jump ({r.scene}): {f3(r.start)} → {f3(r.target)}, {clip.num_frames} frames at "
                 f"{clip.fps:g} fps, written to {out}")
    lines.append(f"  path       v0 {f3(r.v0)} m/s, thrust a {f3(r.a)} m/s² over {r.t_windup:g} s, "
                 f"{r.t_air:g} s in the air (COM displacement {f3(r.displacement)} m)")
    lines.append(f"  windup     E_k {r.E_k:.0f} J, stored {r.E_el_crouch:.0f} J in the crouch (pelvis "
                 f"{f3(r.crouch_pelvis)} from the feet, upper body leaning {r.crouch_lean_deg[0]:+.1f}° (+ forward)); "
                 f"PD: {r.windup_iterations} iterations, energy met at {r.energy_met_at_iteration}; "
                 f"feet moved {1000 * r.windup_foot_motion_m:.2f} mm")
    land = "absorbed" if r.landing_energy_met else "partly absorbed (the rest dissipated)"
    lines.append(f"  landing    touch-down frame {r.touchdown}, {100 * r.landing_error_m:.2f} cm from the "
                 f"target; E {r.E_land:.0f} J {land} by a {r.E_el_landing:.0f} J crouch")
    if r.obstacle_clearance_m is not None:
        lines.append(f"  clearance  {100 * r.obstacle_clearance_m:.1f} cm over the obstacle")
    lines.append(f"  springs    k = {', '.join(f'{v:g}' for v in r.k)} × strength {r.strength:g}")
    for k, v in figs.items():
        lines.append(f"  {k:<10s} {v}")
    from flipstudy.stimuli.score import score
    scored = score(clip).clips[0]
    lines += ["  score: " + ln for ln in scored.summary(brief=True).splitlines()]
    report = json.loads(json.dumps({**r.to_dict(), "out": out, **figs, "score": scored.to_dict()}))
    return MotionResult(command="jump", out=Path(out), report=report, lines=tuple(lines))


def figure(clip_spec: str, out, *, kind: str = "ghost", overlay=None, scale=None, fps=None, readers=None,
           size=(640, 480), style=None, interval=None, debug: bool = False,
           accept_unphysical: bool = False) -> MotionResult:
    """``flipstudy figure``: one still of one clip into ``out``: ``kind`` ghost, trail,
    strip or composite (with ``debug`` gizmos), or overlay (the clip over ``overlay``)."""
    from flipstudy.render import figures as fg
    from flipstudy.render.staging import stage
    from flipstudy.stimuli.loading import load_clip
    clips = [load_clip(clip_spec, scale, fps, accept_unphysical, **(readers or {}))]
    if kind == "overlay":
        clips.append(load_clip(overlay, scale, fps, accept_unphysical, **(readers or {})))
    st = stage(clips, size=size, style=style)
    gizmos = ("com", "path", "L", "v", "support") if debug else ()
    if kind == "overlay":
        labels = (Path(clip_spec).stem, Path(overlay).stem)
        fg.overlay_image(st, out, interval=interval or 0.2, labels=labels)
    elif kind == "trail":
        fg.trail_image(st, out, debug=gizmos)
    elif kind == "strip":
        h = size[1]
        fg.strip_image(st, out, dt=interval or 0.1, panel_size=(2 * int(round(0.35 * h)), h),
                       debug=gizmos)
    elif kind == "composite":
        fg.composite_image(st, out, interval=interval or 0.2, debug=gizmos)
    else:
        fg.ghost_image(st, out, interval=interval, debug=gizmos)
    return MotionResult(command="figure", out=Path(out), report={"kind": kind, "out": str(out)},
                        lines=(f"{kind} figure of {clip_spec}: {out}",))
