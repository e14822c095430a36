"""Rendering speed: the reused plotter against naive rendering, and a small study.

Prints, in one run:

* frames per second at 640x480 and 1280x720 for
  - **reused**: one plotter, one merged body mesh whose points are rewritten in
    place each frame (``render.video.iter_frames``);
  - **naive, new actors**: one plotter, but every frame clears it and adds a
    new mesh per body piece and a new ground (what a first script does);
  - **naive, new plotter**: a new plotter (OpenGL context) per frame;
* the ratios reused / naive (target ≥ 5×), with SSAA (the default style) and
  without anti-aliasing;
* the time to render all videos of a 10-stimulus study (``render_study``,
  640x480, 60 fps, all CPUs), with and without SSAA, and of the default study
  (the paper's design, 52 stimuli; without anti-aliasing as ``reproduce``
  renders it, ``--default-study-aa ssaa|both`` for the final quality).

On a software rasteriser (Mesa llvmpipe, no GPU) SSAA makes the render itself
cost 5-8× more, so with SSAA every path is render-bound and the ratios shrink;
without anti-aliasing they show the per-frame overhead that reuse removes.

Usage: ``python benchmarks/bench_render.py [--frames N] [--quick] [--default-study-aa none|ssaa|both]``.
The clip is the built-in backflip when ``stimuli/synth`` exists, else the
CMU flip 88_01 (at 60 fps) from ``../shared``, else a synthetic jumper.
"""
from __future__ import annotations

import argparse
import csv
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from flipstudy.render._pv import pv  # noqa: E402  (EGL offscreen before anything else)
from flipstudy.vocab.kinds import AM  # noqa: E402
from flipstudy.render.geometry import piece_frames, resample  # noqa: E402
from flipstudy.render.scene import Scene  # noqa: E402
from flipstudy.render.staging import stage  # noqa: E402
from flipstudy.render.style import Style  # noqa: E402
from flipstudy.render.video import iter_frames  # noqa: E402


def load_clip():
    if (ROOT / "stimuli" / "synth" / "__init__.py").exists():
        from flipstudy.stimuli import builtin
        return builtin("backflip"), "built-in backflip"
    p = ROOT.parent / "shared" / "mocap" / "88_01.bvh"
    if p.exists():
        from flipstudy.stimuli import load_bvh
        return load_bvh(p, fps=60), "CMU 88_01 (60 fps)"
    sys.path.insert(0, str(ROOT / "tests"))
    from test_render import jumper
    return jumper(flip=6.0)[0], "synthetic jumper"


def _gl_renderer() -> str:
    sc = Scene(None, Style(), (16, 16))
    sc.grab()
    info = sc.plotter.render_window.ReportCapabilities()
    sc.close()
    for line in info.splitlines():
        if "renderer string" in line:
            return line.split(":", 1)[1].strip()
    return "unknown GL renderer"


def bench_reused(prep, size, n, style):
    t = time.perf_counter()
    sc = Scene(prep.bodies[0], style, size, prep.camera, prep.ground_bounds)
    setup = time.perf_counter() - t
    clip = resample(prep.clips[0], 60.0)
    clip = clip.slice(0, n) if clip.num_frames >= n else clip
    it = iter_frames(clip, sc, 60.0)
    next(it)                                               # first frame compiles shaders
    t = time.perf_counter()
    k = 0
    for _ in it:
        k += 1
    dt = time.perf_counter() - t
    sc.close()
    return k / dt, setup


def _naive_frame(pl, body, R, P, style, ground):
    """One frame the naive way: a new mesh and actor per body piece and a new
    ground actor, then one render and a screenshot (``render=False`` on every
    ``add_mesh``, or PyVista would re-render the scene after each one)."""
    joint, centre, Q, semi = piece_frames(body)
    for p in range(len(joint)):
        j = joint[p]
        e = pv.ParametricEllipsoid(semi[p, 0], semi[p, 1], semi[p, 2], u_res=20, v_res=12, w_res=0)
        M = np.eye(4)
        M[:3, :3] = R[j] @ Q[p]
        M[:3, 3] = R[j] @ centre[p] + P[j]
        pl.add_mesh(e.transform(M, inplace=False), color=style.body_color, smooth_shading=True,
                    reset_camera=False, render=False)
    pl.add_mesh(ground, scalars="rgb", rgb=True, reset_camera=False, render=False)
    pl.render()
    return pl.screenshot(return_img=True)


def _ground(prep, style):
    sc = Scene(None, style, (32, 32), prep.camera, prep.ground_bounds)
    g = sc.ground_actor.mapper.dataset.copy()
    sc.close()
    return g


def _plotter(size, style, cam):
    pl = pv.Plotter(off_screen=True, window_size=list(size))
    pl.render_window.SetMultiSamples(0)
    pl.set_background(style.background)
    pl.enable_depth_peeling(number_of_peels=style.depth_peels, occlusion_ratio=0.0)
    if style.anti_aliasing == "ssaa":
        import warnings
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            pl.enable_anti_aliasing("ssaa")
    pl.camera_position = [cam.position, cam.focal_point, cam.view_up]
    pl.camera.view_angle = cam.view_angle
    return pl


def bench_naive_actors(prep, size, n, style, ground):
    clip = resample(prep.clips[0], 60.0)
    R, P = clip.joint_rotations(), clip.joint_positions()
    body = prep.bodies[0]
    pl = _plotter(size, style, prep.camera)
    _naive_frame(pl, body, R[0], P[0], style, ground)
    t = time.perf_counter()
    for k in range(1, n + 1):
        pl.clear_actors()
        _naive_frame(pl, body, R[k % len(R)], P[k % len(R)], style, ground)
    dt = time.perf_counter() - t
    pl.close()
    return n / dt


def bench_naive_plotter(prep, size, n, style, ground):
    clip = resample(prep.clips[0], 60.0)
    R, P = clip.joint_rotations(), clip.joint_positions()
    body = prep.bodies[0]
    t = time.perf_counter()
    for k in range(n):
        pl = _plotter(size, style, prep.camera)
        _naive_frame(pl, body, R[k % len(R)], P[k % len(R)], style, ground)
        pl.close()
    return n / (time.perf_counter() - t)


def bench_study(clip, n_stimuli=10, jobs=None, size=(640, 480), style=None):
    from scipy.spatial.transform import Rotation

    from flipstudy.render.study import render_study
    from flipstudy.stimuli import analyse, save_bvh
    a = analyse(clip)
    t0, t1 = a.takeoff, a.landing
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        rows = []
        for i in range(n_stimuli):
            q = clip.rotations.copy()
            if i:
                ramp = np.clip((np.arange(clip.num_frames) - t0) / max(1, t1 - t0), 0, 1)[:, None]
                extra = Rotation.from_rotvec(np.array([0.05 * i, 0, 0]) * ramp)
                q[:, 0] = (extra * Rotation.from_quat(q[:, 0])).as_quat()
            name = f"s{i:02d}"
            save_bvh(clip.replace(rotations=q), d / f"{name}.bvh", scale=1.0)
            rows.append({"stimulus": name, "clip": "base", "group": "g",
                         "kind": "reference" if i == 0 else AM.name, "profile": "smooth",
                         "level": 5 * i, "takeoff": t0, "landing": t1, "bvh": f"{name}.bvh"})
        with open(d / "manifest.csv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
        t = time.perf_counter()
        rec = render_study(d, what=["video"], size=size, jobs=jobs, fps=60.0, progress=False,
                           style=style)
        dt = time.perf_counter() - t
        frames = sum(int(np.floor(clip.duration * 60 + 1e-9)) + 1 for _ in rows)
    return dt, frames, rec.jobs


def bench_default_study(style, jobs=None, size=(640, 480)):
    """All videos of the default study: the paper's design (`flipstudy init`), its
    stimuli built and measured, every stimulus rendered (render time only)."""
    from flipstudy.render.study import render_study
    from flipstudy.stimuli.design import PAPER_DESIGN, load_design
    from flipstudy.stimuli.stimset import build_stimuli
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        (d / "design.toml").write_text(PAPER_DESIGN, encoding="utf-8")
        rows = build_stimuli(load_design(d / "design.toml"), d / "study", progress=False).rows
        t = time.perf_counter()
        rec = render_study(d / "study", what=["video"], size=size, jobs=jobs, fps=60.0, progress=False,
                           style=style)
        return time.perf_counter() - t, len(rows), rec.jobs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=60, help="frames per measurement (reused path)")
    ap.add_argument("--quick", action="store_true", help="fewer frames, no study")
    ap.add_argument("--default-study-aa", choices=["none", "ssaa", "both"], default="none",
                    help="anti-aliasing for the default-study timing (ssaa takes several minutes)")
    args = ap.parse_args(argv)
    n = 20 if args.quick else args.frames
    clip, what = load_clip()
    print(f"clip: {what}, {clip.num_frames} frames at {clip.fps:g} fps; renderer: VTK "
          f"{'.'.join(map(str, pv.vtk_version_info))}, {_gl_renderer()}, {os.cpu_count()} CPU(s), "
          f"load average {os.getloadavg()[0]:.1f}")
    print(f"{'size':>10} {'AA':>5} {'reused':>10} {'new actors':>11} {'new plotter':>12} "
          f"{'ratio/actors':>13} {'ratio/plotter':>14}")
    for size in ((640, 480), (1280, 720)):
        for aa in ("ssaa", "none"):
            st = Style(anti_aliasing=aa)
            prep = stage([clip], size=size, style=st)
            ground = _ground(prep, st)
            fr, setup = bench_reused(prep, size, n, st)
            fa = bench_naive_actors(prep, size, max(5, n // 4), st, ground)
            fp = bench_naive_plotter(prep, size, max(3, n // 6), st, ground)
            print(f"{size[0]:>5}x{size[1]:<4} {aa:>5} {fr:7.1f} fps {fa:7.1f} fps {fp:8.2f} fps "
                  f"{fr / fa:12.1f}× {fr / fp:13.1f}×")
    if not args.quick:
        for aa in ("ssaa", "none"):
            dt, frames, jobs = bench_study(clip, style=Style(anti_aliasing=aa))
            print(f"study: 10 stimuli, all videos at 640x480 / 60 fps, AA {aa} ({frames} frames, "
                  f"H.264) in {dt:.1f} s with {jobs} worker(s) = {frames / dt:.1f} frames/s overall")
        aas = ("none", "ssaa") if args.default_study_aa == "both" else (args.default_study_aa,)
        for aa in aas:
            dt, n_st, jobs = bench_default_study(Style(anti_aliasing=aa))
            print(f"default study (the paper's design, `flipstudy init`): all {n_st} videos at 640x480 / "
                  f"60 fps, AA {aa}, in {dt:.1f} s with {jobs} worker(s) ({dt / n_st:.2f} s per stimulus)")


if __name__ == "__main__":
    main()
