"""BVH reading of very many joints: load time against the time of its numbers alone.

Run: python benchmarks/bench_bvh_joints.py [--joints 30000 ...] [--frames 10] [--repeat 3]

For each joint count, a generated file (tests/_support/_bvh_gen.py: a root with 100 chains,
ZXY rotations, root positions) is timed, best of N, as

* ``load_bvh(path)``: the whole reader (hierarchy, numbers, bounds, quaternions, Clip);
* ``np.loadtxt`` of the MOTION lines alone (the numbers, nothing else).

It prints both and their ratio.  Joint names were once checked against a list, which
made the hierarchy quadratic in the joints (30,000 joints: 18 s on the issue's machine);
a dict keeps it linear, so the ratio stays bounded as the joints grow.  No timing is
asserted anywhere; the script only prints.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "_support"))

from _common import best_s  # noqa: E402

from _bvh_gen import many_joints_bvh  # noqa: E402
from flipstudy.stimuli import load_bvh  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--joints", type=int, nargs="+", default=[1000, 10_000, 30_000, 100_000])
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    print(f"{'joints':>8} {'frames':>6} {'load_bvh s':>11} {'loadtxt s':>10} {'ratio':>6}")
    with tempfile.TemporaryDirectory() as d:
        for J in args.joints:
            p = Path(d) / f"j{J}.bvh"
            p.write_text(many_joints_bvh(J, n_frames=args.frames))
            lines = p.read_text().split("\n")
            m = lines.index("MOTION")
            data = [ln for ln in lines[m + 3:] if ln]
            clip = load_bvh(p)
            assert clip.skeleton.num_joints == J
            t_load = best_s(lambda: load_bvh(p), args.repeat)
            t_num = best_s(lambda: np.loadtxt(data, ndmin=2), args.repeat)
            print(f"{J:>8} {args.frames:>6} {t_load:>11.3f} {t_num:>10.3f} {t_load / t_num:>6.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
