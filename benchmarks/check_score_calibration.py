"""The score's calibration checked against people and against known observers.

Run: python benchmarks/check_score_calibration.py [--png docs/img/score_calibration.png]

1. Against people (FwP 2007, Table 2): each angular-momentum group predicted from
   a calibration made on the other three (:func:`flipstudy.analysis.calibrate.leave_one_out`);
   prints the error per level (predicted − observed rating, points) and its mean.
   Then the same through the score itself: the held-out group's stimuli made from
   the built-in backflip and frontflip (as the default design makes them), scored
   with that calibration (measured sizes, every scored error combined), predicted
   rating = 100 (1 − (γ + (1 − γ) P(anything noticed))), averaged over the 2 clips.
2. Against simulated observers with a known psychometric function
   (:func:`~flipstudy.analysis.calibrate.simulated_check`, three seeds): predicted vs
   observed P(judged incorrect) per bin, with the prediction's posterior interval
   and the observed rate's binomial interval; prints how many bins meet.
"""
from __future__ import annotations

import argparse

import numpy as np


def score_leave_one_out(seed: int = 0):
    """Each AM group's stimuli scored with a calibration made on the other three."""
    import pandas as pd

    from flipstudy.analysis.calibrate import AM_GROUPS, FWP_GROUPS, fwp_calibration
    from flipstudy.analysis.simulate import PAPER_TABLE2
    from flipstudy.stimuli import analyse, builtin
    from flipstudy.stimuli.calibration import Calibration
    from flipstudy.stimuli.injection import inject_angular_momentum
    from flipstudy.stimuli.score import score
    bases = [analyse(builtin(n)) for n in ("backflip", "frontflip")]
    rows = []
    for g in AM_GROUPS:
        cal = Calibration.from_dict(fwp_calibration([h for h in AM_GROUPS if h != g], seed=seed))
        kind, variant, sign = FWP_GROUPS[g]
        gamma = cal.lookup(kind, variant, sign).params["gamma"]
        for lv, r in zip(PAPER_TABLE2[g]["levels"], PAPER_TABLE2[g]["rating"]):
            if r is None:
                continue
            clips = [inject_angular_momentum(a, sign * lv / 100, variant).clip if lv else a.clip
                     for a in bases]
            p_any = np.array([c.p_any for c in score(clips, cal).clips])
            rows.append((g, float(lv), float(r), float(np.mean(100 * (1 - (gamma + (1 - gamma) * p_any))))))
    t = pd.DataFrame(rows, columns=["group", "level", "observed", "predicted"])
    t["error"] = t["predicted"] - t["observed"]
    return t


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--png", default=None, help="write the calibration plot here")
    args = ap.parse_args()
    import pandas as pd

    from flipstudy.analysis.calibrate import leave_one_out, simulated_check
    pd.set_option("display.width", 160)
    loo = leave_one_out()
    print("FwP Table 2, each angular-momentum group predicted from the other three "
          "(ratings, % judged correct):")
    print(loo.round(1).to_string(index=False))
    print("mean |error| per held-out group (points):")
    print(loo.assign(abs_error=loo["error"].abs()).groupby("group", sort=False)["abs_error"]
          .mean().round(1).to_string())
    via = score_leave_one_out()
    print("the same through `score` on the held-out group's stimuli (backflip, frontflip):")
    print(via.round(1).to_string(index=False))
    print("mean |error| per held-out group (points):")
    print(via.assign(abs_error=via["error"].abs()).groupby("group", sort=False)["abs_error"]
          .mean().round(1).to_string())
    sims = [simulated_check(seed=s) for s in range(3)]
    inside = sum(int(r["bins"]["inside"].sum()) for r in sims)
    total = sum(len(r["bins"]) for r in sims)
    print(f"simulated observers (m = 30, w = 25, γ = 0.2, λ = 0.02; 19 × 4 answers per level): "
          f"{inside}/{total} bins on the diagonal within the intervals")
    if args.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4.6), dpi=110)
        for r, mk in zip(sims, "osD"):
            b = r["bins"]
            a1.errorbar(b["pred"], b["observed"], yerr=[b["observed"] - b["ci_low"], b["ci_high"] - b["observed"]],
                        xerr=[b["pred"] - b["pred_low"], b["pred_high"] - b["pred"]], fmt=mk, ms=4,
                        capsize=2, alpha=0.8)
        a1.plot([0, 1], [0, 1], color="0.4", lw=1, ls="--")
        a1.set(xlim=(0, 1), ylim=(0, 1), xlabel="predicted P(judged incorrect) (calibration)",
               ylabel="observed rate (fresh simulated answers)",
               title=f"known observers: {inside}/{total} bins on the diagonal")
        cols = plt.get_cmap("tab10")
        for i, (g, sub) in enumerate(loo.groupby("group", sort=False)):
            a2.errorbar(sub["observed"] + 0.4 * (i - 1.5), sub["predicted"],
                        yerr=[sub["predicted"] - sub["pred_low"], sub["pred_high"] - sub["predicted"]],
                        fmt="o", ms=4, capsize=2, color=cols(i), label=g)
        a2.plot([0, 100], [0, 100], color="0.4", lw=1, ls="--")
        a2.set(xlim=(15, 95), ylim=(15, 95), xlabel="FwP Table 2 rating (% judged correct)",
               ylabel="predicted from the other three groups",
               title="people: each AM group held out")
        a2.legend(fontsize=8, loc="upper left")
        for a in (a1, a2):
            a.set_aspect("equal")
            a.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(args.png)
        print(f"wrote {args.png}")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
