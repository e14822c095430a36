"""Building and rendering a grid study locally and on Dask (LocalCluster of 1 and 2 workers).

Builds a grid design of about ``--n`` stimuli (default 1000: the built-in
backflip and frontflip × groups of 20 levels, angular-momentum and take-off
angle errors, both signs) and renders its videos at a small size, three ways,
each into a fresh folder:

* **local**: ``build_stimuli`` in this process, ``render_study(jobs=1)`` (one
  worker: this process);
* **cluster 1**: ``--cluster local:1`` (one Dask worker process);
* **cluster 2**: ``--cluster local:2`` (two Dask worker processes).

Prints the seconds of each step, the speed-ups against the local run measured
in the same run, and the per-task overhead of the cluster (cluster-1 time minus
local time, per stimulus; the cluster's start-up, with the workers' imports, is
timed apart, and this process imports the same modules before timing).  It also
checks that the three builds wrote the same bytes (manifest, BVH, NPZ) and the
same decoded video frames (the same renderer here).

The ceiling of the speed-up is the number of free cores: on a machine with
two cores shared with other work, LocalCluster(2) cannot reach 2×.

Usage: ``python benchmarks/bench_cluster.py [--n 1000] [--size 96x72] [--video-fps 10]``.
"""
from __future__ import annotations

import argparse
import hashlib
import importlib
import math
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from flipstudy.vocab.kinds import AM, TAKEOFF_ANGLE  # noqa: E402

KINDS = [(AM.name, "smooth", 1), (AM.name, "abrupt", 1),
         (AM.name, "smooth", -1), (TAKEOFF_ANGLE.name, None, 1),
         (TAKEOFF_ANGLE.name, None, -1), (AM.name, "abrupt", -1)]


#: modules imported before timing, here and (as start-up) on the workers
WARM = ("flipstudy.stimuli.stimset", "flipstudy.render.workers", "flipstudy.render.video",
        "flipstudy.render.figures", "flipstudy.render.scene", "vtk", "pyvista")


def grid_design(n: int) -> str:
    """A design of about ``n`` stimuli: 2 clips × groups × up to 20 levels."""
    clips = ["backflip", "frontflip"]
    groups = max(1, math.ceil(n / (len(clips) * 20)))
    per = max(1, math.ceil(n / (len(clips) * groups)))
    parts = ['[study]\nname = "grid"\nseed = 3\nrepetitions = 1\n']
    for c in clips:
        parts.append(f'[[clips]]\nname = "{c}"\nsource = "{c}"\n')
    for j in range(groups):
        kind, profile, sign = KINDS[j % len(KINDS)]
        levels = [round(1.0 + k + 0.01 * j, 2) for k in range(per)]
        parts.append(f'[[groups]]\nname = "g{j:02d}"\nkind = "{kind}"\nsign = {sign}\n'
                     + (f'profile = "{profile}"\n' if profile else "")
                     + f"levels = {levels}\n")
    return "\n".join(parts)


def digest(folder: Path) -> str:
    h = hashlib.sha256()
    for p in sorted(folder.iterdir()):
        if p.is_file():
            h.update(p.name.encode() + p.read_bytes())
    return h.hexdigest()


def frames_digest(folder: Path) -> str:
    import imageio_ffmpeg
    h = hashlib.sha256()
    for p in sorted(folder.glob("*.mp4")):
        for f in list(imageio_ffmpeg.read_frames(str(p)))[1:]:
            h.update(f)
    return h.hexdigest()


def run(mode: str, design, root: Path, size, fps) -> dict:
    from flipstudy.render.study import render_study
    from flipstudy.stimuli.stimset import build_stimuli
    from flipstudy.study.cluster import Cluster
    study = root / mode.replace(":", "")
    t = time.perf_counter()
    cluster = Cluster(mode) if mode != "local" else None
    if cluster is not None:              # the workers' imports: start-up, not per-task cost
        for m in WARM:
            cluster.client.run(importlib.import_module, m)
    t_start = time.perf_counter() - t
    try:
        t = time.perf_counter()
        rows = build_stimuli(design, study, progress=False, cluster=cluster).rows
        t_build = time.perf_counter() - t
        t = time.perf_counter()
        render_study(study, what="video", size=size, fps=fps, jobs=1, progress=False,
                     cluster=cluster)
        t_render = time.perf_counter() - t
    finally:
        if cluster is not None:
            cluster.close()
    return {"n": len(rows), "start": t_start, "build": t_build, "render": t_render,
            "bytes": digest(study), "frames": frames_digest(study / "render")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=1000, help="about this many stimuli (default 1000)")
    ap.add_argument("--size", default="96x72", help="video size (default 96x72)")
    ap.add_argument("--video-fps", type=float, default=10.0, help="video frame rate (default 10)")
    args = ap.parse_args()
    from flipstudy.render.study import parse_size
    from flipstudy.stimuli.design import parse_design
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    size = parse_size(args.size)
    for m in WARM:
        importlib.import_module(m)
    design = parse_design(grid_design(args.n))
    res = {}
    with tempfile.TemporaryDirectory() as tmp:
        for mode in ("local", "local:1", "local:2"):
            res[mode] = r = run(mode, design, Path(tmp), size, args.video_fps)
            print(f"{mode:8s} {r['n']} stimuli: start {r['start']:6.1f} s  build {r['build']:7.1f} s  "
                  f"render {r['render']:7.1f} s", flush=True)
    base = res["local"]
    n = base["n"]
    print(f"\n{n} stimuli, videos {size[0]}x{size[1]} at {args.video_fps:g} fps, "
          f"{os.cpu_count()} CPUs (load average {os.getloadavg()[0]:.1f})")
    print(f"{'':10s}{'build':>10s}{'render':>10s}{'both':>10s}   speed-up vs local (build, render, both)")
    for mode, r in res.items():
        both, b0 = r["build"] + r["render"], base["build"] + base["render"]
        print(f"{mode:10s}{r['build']:9.1f}s{r['render']:9.1f}s{both:9.1f}s   "
              f"{base['build'] / r['build']:.2f}×  {base['render'] / r['render']:.2f}×  {b0 / both:.2f}×")
    one = res["local:1"]
    print(f"per-task overhead of the cluster (LocalCluster(1) − local, per stimulus): build "
          f"{1000 * (one['build'] - base['build']) / n:+.1f} ms, render "
          f"{1000 * (one['render'] - base['render']) / n:+.1f} ms; cluster start-up "
          f"{one['start']:.1f} s (1 worker), {res['local:2']['start']:.1f} s (2 workers)")
    same_b = len({r["bytes"] for r in res.values()}) == 1
    same_f = len({r["frames"] for r in res.values()}) == 1
    print(f"same manifest/BVH/NPZ bytes in all three: {same_b}; same decoded video frames: {same_f}")
    if not (same_b and same_f):
        sys.exit(1)


if __name__ == "__main__":
    main()
