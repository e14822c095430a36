"""Measuring (flipstudy.stimuli.measure) 1,000 clips of 200 frames, against
running the analyser (``analyse``) on each: what measuring every physical
inconsistency adds to the flight analysis it starts from, and scoring them
(``flipstudy.stimuli.score.score``, when the checkout has it: measuring plus the
calibration's probabilities).

Run: python benchmarks/bench_score.py [N]
The clips are 200-frame windows (frames 100-299, the whole flight and both
contacts) of the built-in backflip, frontflip and jump at 120 fps and of
stimuli made from them (angular momentum ±20 %, take-off ±20 %, gravity ±20 %),
cycled to N (default 1000); nothing is written.  Each clip is measured with its
own analysis (``measure(clip)`` runs the analyser without the mass fit); the
ratios are against ``analyse(clip)`` as a user runs it (with the mass fit), and
the analyser without it is printed too.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def clips():
    from flipstudy import analyse, builtin
    from flipstudy.stimuli.ballistic import inject_kind
    from flipstudy.stimuli.injection import inject_angular_momentum, inject_takeoff_angle
    out = []
    for name in ("backflip", "frontflip", "jump"):
        a = analyse(builtin(name))
        out.append(a.clip)
        for e in (0.2, -0.2):
            out.append(inject_angular_momentum(a, e, "smooth").clip)
            out.append(inject_takeoff_angle(a, e).clip)
            out.append(inject_kind(a, "gravity", e, "takeoff-velocity").clip)
    return [c.slice(100, 300) for c in out]


def main() -> int:
    from flipstudy import analyse
    from flipstudy.stimuli.measure import measure
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    base = clips()
    todo = [base[i % len(base)] for i in range(n)]
    assert all(c.num_frames == 200 for c in todo)
    measure(todo[0])                                       # imports, caches
    t = time.perf_counter()
    for c in todo:
        analyse(c)
    t_an = time.perf_counter() - t
    t = time.perf_counter()
    ms = [measure(c) for c in todo]
    t_me = time.perf_counter() - t
    t = time.perf_counter()
    for c in todo:
        analyse(c, estimate=False)
    t_an0 = time.perf_counter() - t
    items = sum(len(m.items) for m in ms)
    print(f"{n} clips of 200 frames ({len(base)} distinct), {items} inconsistencies measured")
    print(f"analyse (with the mass fit) on each:    {t_an:.2f} s ({1000 * t_an / n:.1f} ms/clip)")
    print(f"analyse (without the mass fit) on each: {t_an0:.2f} s ({1000 * t_an0 / n:.1f} ms/clip)")
    print(f"measure on each:                        {t_me:.2f} s ({1000 * t_me / n:.1f} ms/clip)")
    print(f"ratio measure / analyse: {t_me / t_an:.2f}")
    try:
        from flipstudy.stimuli.score import score
    except ImportError:
        print("score: not in this checkout")
        return 0
    score(todo[:1])                                        # the calibration loaded once
    t = time.perf_counter()
    score(todo)
    t_sc = time.perf_counter() - t
    print(f"score on all:                           {t_sc:.2f} s ({1000 * t_sc / n:.1f} ms/clip)")
    print(f"ratio score / analyse: {t_sc / t_an:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
