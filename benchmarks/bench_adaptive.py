"""Trials to a threshold of a given precision: QUEST+ against constant stimuli, on the
same simulated observers; and the time of one QUEST+ next level against questplus's.

Run: python benchmarks/bench_adaptive.py [--observers 200] [--max-trials 300]
     [--figure docs/img/adaptive_benchmark.png] [--quick]

Observers: :func:`flipstudy.analysis.adaptive.population` (x* ~ N(25, 8) %, widths
8–40 %, yes/no base rates 0.05–0.45, lapse 0.02), the same observers for every
method.  Each method's answers are scored by the same grid posterior (the
analysis's psychometric function), so the methods differ only in the levels shown:

* QUEST+: the level of least expected entropy on a 1 % grid, 0–60 %;
* constant stimuli, the paper's levels (0, 17, 25, 37, 50 %; 2AFC without 0) in
  shuffled blocks — the baseline of the issue;
* constant stimuli over a 5 % grid (0–60 %), a second baseline.

Printed per task and target width of the 95 % interval of x*: the median (and
90th percentile) number of trials until an observer's interval is that narrow,
and the ratio QUEST+ / constant (the issue's target: at most 1/3).

Speed: one ``Quest.next_level()`` (closed-form expected entropy, four matrix–vector
products) against ``questplus.QuestPlus.next_stim`` (xarray) on the same posterior,
which pick the same level (checked here, and in tests/analysis/test_adaptive.py).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from _common import best_s  # noqa: E402

from flipstudy.analysis.adaptive import Quest, QuestSettings, population, quest_model  # noqa: E402
from flipstudy.analysis.adaptive_sim import simulate  # noqa: E402

PAPER = [0.0, 17.0, 25.0, 37.0, 50.0]
GRID5 = list(np.arange(0, 61, 5.0))
QUEST_GRID = list(np.arange(0, 61, 1.0))
SETTINGS = QuestSettings(threshold_prior=(0.0, 60.0))


def fmt(x, cap):
    return f"{x:.0f}" if np.isfinite(x) else f">{cap}"


def trials_table(task, n, max_trials, targets, seed):
    obs = population(n, np.random.default_rng(seed), task)
    sims = {}
    t0 = time.perf_counter()
    for name, levels, method in (("QUEST+", QUEST_GRID, "quest+"), ("constant, paper's levels", PAPER, "constant"),
                                 ("constant, 5 % grid", GRID5, "constant")):
        lv = [v for v in levels if task == "yes-no" or v > 0]
        model = quest_model(lv, task, SETTINGS)
        sims[name] = simulate(model, obs, max_trials, np.random.default_rng(seed + 1), method=method,
                              constant_levels=lv)
    print(f"\n{task}: {n} observers, up to {max_trials} trials each ({time.perf_counter() - t0:.0f} s)")
    print(f"  {'target width':>12}  {'method':<26} {'median':>7} {'p90':>6} {'reached':>8}  ratio QUEST+/this")
    ratios = {}
    for w in targets:
        need = {k: s.trials_to_width(w) for k, s in sims.items()}
        q_med = np.median(need["QUEST+"])
        for k, v in need.items():
            med, p90 = np.median(v), np.quantile(v, 0.9, method="inverted_cdf")
            ratio = q_med / med if k != "QUEST+" and np.isfinite(med) else np.nan
            if k != "QUEST+":
                ratios[(w, k)] = ratio
            r = "" if k == "QUEST+" else (f"{ratio:.2f}" if np.isfinite(ratio) else f"< {q_med / max_trials:.2f}")
            print(f"  {w:>10g} %  {k:<26} {fmt(med, max_trials):>7} {fmt(p90, max_trials):>6} "
                  f"{np.mean(np.isfinite(v)):>7.0%}  {r}")
    cover = {k: float(np.mean(s.covered)) for k, s in sims.items()}
    print("  coverage of the final 95 % intervals: " + ", ".join(f"{k} {v:.0%}" for k, v in cover.items()))
    return sims, ratios


def speed(levels, task="yes-no"):
    model = quest_model(levels, task)
    q = Quest.new(model)
    rng = np.random.default_rng(0)
    for _ in range(10):
        lv = q.next_level()
        q.update(lv, bool(rng.random() < 0.5))
    same = q.next_level() == q.qp.next_stim["intensity"]
    ours = best_s(q.next_level, 7, warmup=True)
    theirs = best_s(lambda: q.qp.next_stim, 3, warmup=True)
    upd = best_s(lambda: Quest.from_json(model, q.to_json()).update(lv, True), 5, warmup=True)
    print(f"  {len(model.levels):4d} levels × {model.prior.size} grid cells: next_level {1e3 * ours:7.2f} ms, "
          f"questplus next_stim {1e3 * theirs:8.1f} ms, ratio {theirs / ours:5.0f}×, same level: {same}; "
          f"resume from JSON + update {1e3 * upd:5.1f} ms")


def figure(sims_by_task, path):
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from flipstudy.analysis.figures import OKABE_ITO, style
    with style():
        fig = Figure(figsize=(7.2, 3.0), layout="constrained")
        axes = fig.subplots(1, len(sims_by_task), sharey=True)
        for ax, (task, sims) in zip(np.atleast_1d(axes), sims_by_task.items()):
            for (name, s), c in zip(sims.items(), OKABE_ITO):
                w = s.width
                t = np.arange(w.shape[0])
                ax.plot(t, np.median(w, axis=1), color=c, lw=1.6, label=name)
                ax.fill_between(t, *np.quantile(w, [0.25, 0.75], axis=1), color=c, alpha=0.15, lw=0)
            ax.axhline(15, color="0.5", ls=":", lw=0.8)
            ax.set_title(task, fontsize=9)
            ax.set_xlabel("trials per participant")
            ax.set_ylim(0, 60)
        np.atleast_1d(axes)[0].set_ylabel("95 % interval of x* (%)\nmedian, quartiles")
        np.atleast_1d(axes)[0].legend(frameon=False, fontsize=7)
        fig.suptitle("Same simulated observers: QUEST+ against constant stimuli", fontsize=9)
        fig.savefig(path, dpi=150, metadata={"Software": "flipstudy benchmarks/bench_adaptive.py"})
    print(f"wrote {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--observers", type=int, default=200)
    ap.add_argument("--max-trials", type=int, default=300)
    ap.add_argument("--seed", type=int, default=19)
    ap.add_argument("--figure", type=Path, default=None, help="write the width-vs-trials figure (PNG)")
    ap.add_argument("--quick", action="store_true", help="60 observers, 150 trials")
    a = ap.parse_args()
    if a.quick:
        a.observers, a.max_trials = 60, 150
    print("Speed of one QUEST+ next level (the session calls it once per trial):")
    speed(QUEST_GRID)
    speed(list(np.arange(0, 60.01, 0.15)))
    targets = (20.0, 15.0, 10.0)
    sims, worst = {}, []
    for task in ("yes-no", "2afc"):
        sims[task], ratios = trials_table(task, a.observers, a.max_trials, targets, a.seed)
        worst += [r for (w, k), r in ratios.items() if k.endswith("paper's levels")]
    fin = [r for r in worst if np.isfinite(r)]
    print(f"\nQUEST+ / constant (paper's levels), median trials, over both tasks and targets: "
          f"{min(fin):.2f}–{max(fin):.2f} (the issue's target: ≤ 0.33)" if fin else "")
    if a.figure:
        figure(sims, a.figure)


if __name__ == "__main__":
    main()
