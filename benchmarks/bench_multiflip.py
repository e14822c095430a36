"""Run-time multi-flip generation (Majkowska & Faloutsos 2007, Section 5):
search + sequencing + retiming + repositioning, after pre-processing, for 2-, 3-
and 4-flip jumps from the built-in backflip, printed against the paper's
3.69 / 4.60 / 5.09 ms and against a naive version of the search measured in the
same run (the Appendix A distance computed pair by pair in Python, the way the
search reads in the paper).

Pre-processing is what depends on the source alone, done once per clip: the
paper's (``analyse``: flight, masses, momentum) and ``flip_source`` (pose features,
the all-pairs distance table the search reads, the root's turn, standing
frames, COM).  The table also prints ``flip_source`` + run time, i.e. the cost when
the distance table is counted as part of the run-time search instead.

Times are CPU time (``time.process_time``, median of repeated calls), so other
work on a shared machine inflates them less than wall time; the paper's figures
are wall time on its 2007 machine.  Target (issue 34): two flips in at most half
the paper's 3.69 ms.

Run: python benchmarks/bench_multiflip.py        (paper target: under 1 ms for two flips)
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import statistics  # noqa: E402

from _common import cpu_times  # noqa: E402
PAPER_MS = {2: 3.69, 3: 4.60, 4: 5.09}


def median_ms(fn, n=15):
    """Median CPU milliseconds of ``n`` calls (after one untimed call)."""
    return 1000 * statistics.median(cpu_times(fn, n, warmup=True))


def naive_distances(feat):
    """The Appendix A distance for every pair, one pair at a time."""
    import numpy as np
    from flipstudy.stimuli.edit.similarity import distance_matrix
    F = feat.frames.size
    D = np.zeros((F, F))
    for i in range(F):
        for j in range(F):
            sub_a = _one(feat, i)
            sub_b = _one(feat, j)
            D[i, j] = distance_matrix(sub_a, sub_b)[0][0, 0]
    return D


def _one(f, i):
    from flipstudy.stimuli.edit.similarity import PoseFeatures
    return PoseFeatures(f.frames[i:i + 1], f.axis, f.root_q[i:i + 1], f.root_w[i:i + 1],
                        f.part_R[i:i + 1], f.part_w[i:i + 1], f.weights, f.names)


def main() -> int:
    import numpy as np
    from flipstudy.stimuli import analyse, builtin
    from flipstudy.stimuli.edit.flight_measures import flight_axis
    from flipstudy.stimuli.edit.multiflip import flip_source, multiflip
    from flipstudy.stimuli.edit.similarity import distance_matrix, pose_features
    a = analyse(builtin("backflip"))
    t_pre = median_ms(lambda: analyse(builtin("backflip")), 5)
    t_prep = median_ms(lambda: flip_source(a), 10)
    pre = flip_source(a)
    u = flight_axis(a)
    feat = pose_features(a.clip, a.body, u, np.arange(a.takeoff, a.landing + 1))
    t_vec = median_ms(lambda: distance_matrix(feat), 20)
    t0 = time.process_time()
    Dn = naive_distances(feat)
    t_naive = 1000 * (time.process_time() - t0)
    assert np.allclose(Dn, distance_matrix(feat)[0], atol=1e-9)
    print(f"built-in backflip, 120 fps, flight {feat.frames.size} frames; pre-processing: "
          f"analyse {t_pre:.0f} ms, flip_source {t_prep:.1f} ms")
    print(f"all-pairs distance (in flip_source): vectorised {t_vec:.2f} ms, naive pair loop "
          f"{t_naive:.0f} ms ({t_naive / t_vec:.0f}x), same values")
    print(f"{'flips':>5s} {'ours CPU ms':>11s} {'paper ms':>9s} {'ours/paper':>11s} {'flip_source+ours ms':>16s}")
    run = {}
    for n in (2, 3, 4):
        run[n] = t = median_ms(lambda: multiflip(pre, n, k_ratio=1.0), 41)
        t_all = median_ms(lambda: multiflip(a, n, k_ratio=1.0), 7)
        print(f"{n:5d} {t:11.2f} {PAPER_MS[n]:9.2f} {t / PAPER_MS[n]:10.2f}x {t_all:16.1f}")
    print("ours: multiflip(flip_source(analysis), n) — search (on the prepared distance table) +")
    print("sequencing + slerp joins + retiming + repositioning + momentum report; CPU ms, median of 41")
    half = 0.5 * PAPER_MS[2]
    print(f"issue 34, two flips in at most half the paper's time ({half:.3g} ms CPU): "
          f"{'met' if run[2] <= half else 'missed'} ({run[2]:.2f} ms = {run[2] / PAPER_MS[2]:.2f}x the paper)")
    met = "met" if run[2] < 1.0 else "missed"
    print(f"the paper's target, under 1 ms for two flips: {met} ({run[2]:.2f} ms)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
