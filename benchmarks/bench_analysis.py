"""The analysis core on a large panel: 1,000 participants × 100 trials.

Run: python benchmarks/bench_analysis.py [--participants 1000] [--quick]

Synthetic responses: the paper's design (5 groups × 5 levels × 2 clips × 2
repetitions = 100 trials per participant, answers drawn from the paper's Table 2
ratings), written to a temporary CSV.

Timed core (target: under 2 s): read the CSV, check it, count, pooled ratings,
d′ and criterion, every participant's d′, and the bootstrap over participants
(2,000 resamples) of the rating, the pooled d′ and the participants' mean d′ —
everything in ``table.csv`` except the GEE columns.

Baseline, measured in the same run: the same quantities written the way one
would at first — pandas ``groupby().apply`` with a Python function per
participant, and a Python loop over the 2,000 resamples that re-aggregates
the resampled participants with pandas.  It is fed the *same* resamples, and
the script checks that both give the same numbers (to 1e-9) before comparing
times.

GEE, psychometric fits and figures are outside the timed core; they are timed
separately below it.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import norm

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from _common import wall_times  # noqa: E402

from flipstudy.analysis import load_responses, summarize  # noqa: E402
from flipstudy.analysis.core import bootstrap_counts, expanded_level  # noqa: E402
from flipstudy.analysis.simulate import paper_panel  # noqa: E402

N_BOOT = 2000
TARGET_S = 2.0


def best_of(fn, n=3):
    times, out = wall_times(fn, n)
    return min(times), out


def core(csv: Path):
    return summarize(load_responses(csv), n_boot=N_BOOT, seed=0)


# ------------------------------------------------------------------ baseline

def _ll(k, n):
    """log-linear correction only when a rate is 0 or 1 (as analysis.sdt, pairwise)."""
    return (k + 0.5) / (n + 1.0)


def _pair_dprime(kh, nh, kf, nf):
    h, f = kh / nh, kf / nf
    if h in (0.0, 1.0) or f in (0.0, 1.0):
        h, f = _ll(kh, nh), _ll(kf, nf)
    return norm.ppf(h) - norm.ppf(f)


def baseline(csv: Path):
    """Per participant with groupby-apply, the bootstrap as a Python loop of pandas aggregations."""
    df = pd.read_csv(csv, dtype={"participant": str})
    df = df[df["group"] != "reference"]
    df["inc"] = (df["response"].str.strip().str.lower() == "incorrect").astype(int)

    def per_participant(sub):
        counts = sub.groupby(["group", "level"])["inc"].agg(["sum", "count"])
        out = {}
        for (g, lv), r in counts.iterrows():
            o = counts.loc[(g, 0.0)]
            out[(g, lv)] = _pair_dprime(r["sum"], r["count"], o["sum"], o["count"])
        return pd.Series(out)
    D = df.groupby("participant").apply(per_participant, include_groups=False)          # (P, K)
    counts = df.groupby(["participant", "group", "level"])["inc"].agg(["sum", "count"])
    K = counts["sum"].unstack(["group", "level"]).fillna(0)
    N = counts["count"].unstack(["group", "level"]).fillna(0)
    K, N, D = K[D.columns], N[D.columns], D.loc[K.index]

    def pooled(kk, nn):
        res = {}
        for (g, lv) in kk.index:
            res[(g, lv)] = _pair_dprime(kk[(g, lv)], nn[(g, lv)], kk[(g, 0.0)], nn[(g, 0.0)])
        return pd.Series(res)
    P = len(D)
    rat, dpool, dmean = [], [], []
    for C in bootstrap_counts(P, N_BOOT, 0):                        # the same resamples as the core
        for c in C:
            idx = np.repeat(np.arange(P), c.astype(int))
            kk, nn = K.iloc[idx].sum(), N.iloc[idx].sum()
            rat.append(100 * (1 - kk / nn))
            dpool.append(pooled(kk, nn))
            dmean.append(D.iloc[idx].mean())
    level = expanded_level(0.95, P)
    a = (1 - level) / 2
    q = lambda rows: pd.DataFrame(rows).quantile([a, 1 - a])  # noqa: E731
    return D.mean(), q(rat), q(dpool), q(dmean)


def check_same(table, base):
    dmean, rat, dpool, dm = base
    t = table.set_index(["group", "level"])
    for (g, lv), v in dmean.items():
        assert abs(t.loc[(g, lv), "dprime_mean_participants"] - v) < 1e-9, (g, lv)
    for name, q in (("rating", rat), ("dprime_pooled", dpool), ("dprime", dm)):
        for (g, lv) in q.columns:
            lo, hi = q[(g, lv)].to_numpy()
            assert abs(t.loc[(g, lv), f"{name}_ci_low"] - lo) < 1e-9, (name, g, lv)
            assert abs(t.loc[(g, lv), f"{name}_ci_high"] - hi) < 1e-9, (name, g, lv)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--participants", type=int, default=1000)
    ap.add_argument("--quick", action="store_true", help="skip the baseline and the psignifit timing")
    args = ap.parse_args(argv)
    from flipstudy.analysis.stats import fit_psychometric, gee_levels
    with tempfile.TemporaryDirectory() as d:
        csv = Path(d) / "responses.csv"
        df = paper_panel(args.participants, seed=0)
        df.to_csv(csv, index=False)
        print(f"{args.participants} participants × {len(df) // args.participants} trials = {len(df):,} rows "
              f"({csv.stat().st_size / 1e6:.1f} MB CSV), {N_BOOT} bootstrap resamples")
        t_core, (table, _, _) = best_of(lambda: core(csv))
        print(f"{'core: CSV → table (pooled, per participant, bootstrap)':58s} {t_core:8.3f} s  "
              f"(target < {TARGET_S:g} s: {'ok' if t_core < TARGET_S else 'MISSED'})")
        if not args.quick:
            t = time.perf_counter()
            base = baseline(csv)
            t_base = time.perf_counter() - t
            check_same(table, base)
            print(f"{'baseline: groupby-apply + Python bootstrap loop':58s} {t_base:8.3f} s  "
                  f"(same numbers to 1e-9; core is {t_base / t_core:.0f}x faster)")
        checked = load_responses(csv)
        t_gee, _ = best_of(lambda: gee_levels(checked), n=1)
        print(f"{'  outside the core: GEE, 5 groups':58s} {t_gee:8.3f} s")
        if not args.quick:
            t_ps, _ = best_of(lambda: fit_psychometric(checked, "psignifit"), n=1)
            print(f"{'  outside the core: psychometric fits, psignifit (5 groups)':58s} {t_ps:8.3f} s")
        from flipstudy.analysis.figures import dprime_figure, ratings_figure, save
        t_fig, _ = best_of(lambda: (save(ratings_figure(table), Path(d) / "r"),
                                    save(dprime_figure(table), Path(d) / "d")), n=1)
        print(f"{'  outside the core: ratings + d′ figures (PDF + PNG)':58s} {t_fig:8.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
