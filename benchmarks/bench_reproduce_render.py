"""``flipstudy reproduce``'s render phase, old code against this checkout, in one run.

Builds the paper's stimuli (reproduce's stage 2) once, then renders them as
reproduce's stage 3 does (``render_study``: video, ghost and trail of every
stimulus at ``--size``, reproduce's style, ``--jobs`` worker processes) with
the code of an old commit (``--old``, default the merge base with ``main``;
checked out into a temporary git worktree) and with this checkout, in turn
(``--repeat`` rounds of old then new), each in a fresh Python process whose
import path puts that code first.  Prints per run the CPU-seconds (the
process and everything it waited for: workers, their ffmpeg encoders), the
wall seconds, and the new/old ratio of the CPU-seconds.

Usage: ``python benchmarks/bench_reproduce_render.py [--old REV] [--stimuli N] [--size 640x480] [--jobs 2] [--repeat 1]``.
"""
from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

RENDER = r"""
import sys
from flipstudy.stimuli.contract import StimulusSet
from flipstudy.render.study import render_study
from flipstudy.study.reproduce import STYLE
study, out, n, size, jobs = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], int(sys.argv[5])
s = StimulusSet.read(study)
s = StimulusSet(s.folder, s.stimuli[:n] if n > 0 else s.stimuli, s.design, s.manifest_sha256)
w, h = (int(v) for v in size.split("x"))
res = render_study(s, what=("video", "ghost", "trail"), size=(w, h), jobs=jobs, style=STYLE,
                   progress=False, out=out)
# a RenderResult (its render.json record in .record) since issue 29, a dict before it
rec = getattr(res, "record", res)
made = res.made if hasattr(res, "made") else res["made"]
print(made, rec.get("anti_aliasing", {}).get("method", "(not recorded)"),
      rec.get("encoder", {}).get("preset", "(not recorded: medium)"))
"""


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _shim(code: Path, where: Path) -> Path:
    """A folder whose ``flipstudy`` is ``code`` (put first on PYTHONPATH)."""
    where.mkdir(parents=True, exist_ok=True)
    (where / "flipstudy").symlink_to(code, target_is_directory=True)
    return where


def run(shim: Path, study: Path, out: Path, n: int, size: str, jobs: int) -> tuple[float, float, str]:
    env = {**os.environ, "PYTHONPATH": str(shim),
           "VTK_DEFAULT_OPENGL_WINDOW": "vtkEGLRenderWindow"}
    c, t = _children_cpu(), time.perf_counter()
    r = subprocess.run([sys.executable, "-c", RENDER, str(study), str(out), str(n), size, str(jobs)],
                       env=env, capture_output=True, text=True, cwd=shim)
    wall, cpu = time.perf_counter() - t, _children_cpu() - c
    if r.returncode:
        raise SystemExit(f"render failed:\n{r.stderr[-3000:]}")
    return cpu, wall, r.stdout.strip().splitlines()[-1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old", default=None, help="the old commit (default: merge base of HEAD and main)")
    ap.add_argument("--stimuli", type=int, default=0, help="only the first N stimuli (default all)")
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args(argv)
    git = ["git", "-C", str(ROOT)]
    old = args.old or subprocess.run(git + ["merge-base", "HEAD", "main"], capture_output=True,
                                     text=True, check=True).stdout.strip()
    with tempfile.TemporaryDirectory(prefix="bench-reproduce-") as d:
        d = Path(d)
        subprocess.run(git + ["worktree", "add", "--detach", str(d / "old"), old], check=True,
                       capture_output=True)
        try:
            shims = {"old": _shim(d / "old", d / "shim-old"), "new": _shim(ROOT, d / "shim-new")}
            from flipstudy.stimuli.design import PAPER_DESIGN, load_design
            from flipstudy.stimuli.stimset import build_stimuli
            (d / "design.toml").write_text(PAPER_DESIGN, encoding="utf-8")
            build_stimuli(load_design(d / "design.toml"), d / "study", progress=False)
            print(f"reproduce's render phase: {args.stimuli or 'all'} stimuli of the paper's design, "
                  f"video + ghost + trail at {args.size}, jobs={args.jobs}; old = {old[:10]}, new = "
                  f"this checkout; load average {os.getloadavg()[0]:.1f}")
            cpu = {"old": [], "new": []}
            for k in range(args.repeat):
                for name in ("old", "new"):
                    c, w, info = run(shims[name], d / "study", d / f"out-{name}-{k}", args.stimuli,
                                     args.size, args.jobs)
                    cpu[name].append(c)
                    print(f"  {name}: {c:7.1f} CPU-s {w:7.1f} s wall  (made, AA, preset: {info})",
                          flush=True)
            print(f"new / old CPU-seconds: {min(cpu['new']) / min(cpu['old']):.2f}x "
                  f"(least of {args.repeat}); load average {os.getloadavg()[0]:.1f}")
        finally:
            subprocess.run(git + ["worktree", "remove", "--force", str(d / "old")], capture_output=True)
            subprocess.run(git + ["worktree", "prune"], capture_output=True)


if __name__ == "__main__":
    main()
