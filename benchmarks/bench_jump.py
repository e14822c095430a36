"""The energy-based jump controller (Ooi 2016, stimuli.control): the sample field
alone, and one jump end to end after it (plan with the windup choice, the PD
windup, thrust, flight, landing, checks and the BVH written), against the
issue's 0.5 s target and against a naive per-sample Python loop of the field
measured in the same run (the loop is timed on a few hundred samples and scaled
to the field's size; its values are checked against the vectorised field).

Run: python benchmarks/bench_jump.py        (target: under 0.5 s per jump after the field, 2 cores)
"""
from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from _common import median_s  # noqa: E402
TARGET_S = 0.5
NAIVE_SAMPLES = 300


def main() -> int:
    import numpy as np
    from flipstudy.stimuli import save_bvh
    from flipstudy.stimuli.control import Jumper, jump, make_course
    from flipstudy.stimuli.control import samples as W

    def fresh_field():
        W._CACHE.clear()
        return W.sample_field(Jumper())

    t_field = median_s(fresh_field, 3, warmup=True)
    f = W.sample_field(Jumper())
    t0 = time.perf_counter()
    naive = W.sample_field_naive(Jumper(), limit=NAIVE_SAMPLES)
    t_naive = (time.perf_counter() - t0) * f.size / NAIVE_SAMPLES
    ok = naive["ok"]
    assert np.array_equal(ok, f.ok[:NAIVE_SAMPLES])
    assert np.allclose(naive["s"][ok], f.s[:NAIVE_SAMPLES][ok], atol=1e-4)
    print(f"sample field: {f.size} pelvis samples ({int(f.ok.sum())} valid), {os.cpu_count()} cores")
    print(f"  vectorised {t_field:.2f} s; naive per-sample loop {t_naive:.1f} s (timed on "
          f"{NAIVE_SAMPLES} samples, scaled) = {t_naive / t_field:.0f}x slower; same values")
    cases = [("forward 1.3 m", dict(target=(0.0, 0.0, 1.3))),
             ("forward 1.9 m", dict(target=(0.0, 0.0, 1.9))),
             ("sideways 1.3 m", dict(target=(-1.3, 0.0, 0.0), course="sideways")),
             ("box 0.75 m", dict(course=make_course("box", box_height=0.75))),
             ("jump-over", dict(course="over"))]
    tmp = Path(tempfile.mkdtemp())
    print(f"one jump after the field (plan, windup PD, thrust, flight, landing, checks, BVH); "
          f"target {TARGET_S:.1f} s")
    print(f"{'jump':>16s} {'frames':>7s} {'s/jump':>7s} {'target/ours':>12s}")
    worst = 0.0
    for name, kw in cases:
        def run():
            res = jump(kw.get("target"), **{k: v for k, v in kw.items() if k != "target"})
            save_bvh(res.clip, tmp / "j.bvh")
            return res
        t = median_s(run, 5, warmup=True)
        worst = max(worst, t)
        print(f"{name:>16s} {run().clip.num_frames:7d} {t:7.3f} {TARGET_S / t:11.2f}x")
    verdict = "met" if worst < TARGET_S else "missed"
    print(f"target under {TARGET_S} s per jump after the field: {verdict} (slowest {worst:.3f} s); "
          f"CCD batches over the frames of each phase dominate, the field is computed once per "
          f"(height, mass) and its energies once per k")
    return 0


if __name__ == "__main__":
    sys.exit(main())
