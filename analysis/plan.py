"""Power analysis before recruiting: how many trials per participant, and how many
participants, each method needs for a target precision of the threshold x*.

Simulated observers drawn from a population (:func:`~.adaptive.population`: known
x*, width, base rate) answer a group twice, on the same observers: as QUEST+
over the group's dense grid, and as constant stimuli (every level in shuffled
blocks).  Both are scored by the same posterior (:mod:`.adaptive`; the analysis's
psychometric function), so they differ only in which levels are shown.

* **trials per participant**: the number of trials after which ``coverage``
  (default 90 %) of the observers have a 95 % interval of x* narrower than the
  target width (``inf`` when that share is not reached within ``max_trials``);
* **participants**: the smallest N for which the group's mean x* has a 95 %
  confidence interval (t, N − 1) narrower than the same target, given the SD of
  the per-participant estimates after that many trials (population spread plus
  measurement error).

>>> rows = plan_group("g", "2afc", quest_levels=range(0, 61), constant_levels=[17, 25, 37, 50],
...                   target_width=20.0, n_observers=40, max_trials=120, seed=1)
>>> [r["method"] for r in rows], rows[0]["trials"] < rows[1]["trials"]
(['quest+', 'constant'], True)
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.stats import t as t_dist

from flipstudy.errors import FlipstudyValueError

from .adaptive import QuestSettings, population, quest_model
from .adaptive_sim import simulate

COLUMNS = ["group", "task", "method", "levels", "trials", "trials_median", "share_reached",
           "sd_between", "participants", "total_trials"]


def participants_for_width(sd: float, width: float, n_max: int = 10000) -> float:
    """Smallest N ≥ 2 with a 95 % t interval of a mean narrower than ``width``,
    ``2 t(.975, N − 1) sd / √N < width`` (inf beyond ``n_max``).

    >>> participants_for_width(10.0, 10.0)             # about (2 · 1.96 · 10 / 10)² = 15.4
    18
    """
    if not np.isfinite(sd):
        return np.inf
    n = np.arange(2, n_max + 1)
    ok = 2 * t_dist.ppf(0.975, n - 1) * sd / np.sqrt(n) < width
    return int(n[np.argmax(ok)]) if ok.any() else np.inf


def plan_group(name: str, task: str, quest_levels, constant_levels, *, target_width: float,
               settings: QuestSettings | None = None, n_observers: int = 200, max_trials: int = 300,
               coverage: float = 0.9, seed=0, observers=None, **population_kw) -> list[dict]:
    """The two rows (QUEST+, constant stimuli) of one group: see the module doc.

    ``quest_levels``: the grid QUEST+ chooses from; ``constant_levels``: the levels
    constant stimuli show (2AFC: without 0); ``settings``: the group's QUEST+
    settings (its ``threshold_prior`` is set, when None, to the range both grids
    share, so both methods use one prior); ``observers``: the simulated
    observers (default: :func:`population` with ``population_kw``)."""
    if not target_width > 0:
        raise FlipstudyValueError(f"target width: a positive width in percent, got {target_width!r}")
    settings = settings or QuestSettings()
    top = float(max(np.max(np.asarray(list(quest_levels), float)),
                    np.max(np.asarray(list(constant_levels), float))))
    if settings.threshold_prior is None:
        settings = replace(settings, threshold_prior=(0.0, top))
    rng = np.random.default_rng(seed)
    obs = observers if observers is not None else population(n_observers, rng, task, **population_kw)
    rows = []
    for method, levels in (("quest+", quest_levels), ("constant", constant_levels)):
        lv = np.unique(np.asarray(list(levels), float))
        if task == "2afc":
            lv = lv[lv > 0]
        model = quest_model(lv, task, settings)
        sim = simulate(model, obs, max_trials, np.random.default_rng(rng.integers(2**63)),
                       method=method, constant_levels=lv)
        need = sim.trials_to_width(target_width)
        q = np.quantile(need, coverage, method="inverted_cdf")
        at = int(q) if np.isfinite(q) else max_trials
        sd = float(np.std(sim.threshold[at], ddof=1))
        n_part = participants_for_width(sd, target_width)
        rows.append({"group": name, "task": task, "method": method,
                     "levels": (f"{len(lv)} levels, {lv[0]:g}–{lv[-1]:g} %"),
                     "trials": float(q), "trials_median": float(np.median(need)),
                     "share_reached": float(np.mean(np.isfinite(need))), "sd_between": sd,
                     "participants": n_part,
                     "total_trials": (float(q) * n_part if np.isfinite(q) else np.inf)})
    return rows


def format_plan(rows: list[dict], target_width: float, coverage: float = 0.9, max_trials: int = 300) -> str:
    """The plan as a text table."""
    head = (f"Target: 95 % interval of x* narrower than {target_width:g} % — per participant "
            f"(for {coverage:.0%} of simulated observers) and for the group's mean x*.")
    gw = max([22] + [len(r["group"]) + 1 for r in rows])
    lines = [head, "", f"{'group':<{gw}} {'task':<7} {'method':<9} {'trials/participant':>19} "
                       f"{'(median)':>9} {'participants':>13} {'total trials':>13}"]
    for r in rows:
        tr = f"{r['trials']:.0f}" if np.isfinite(r["trials"]) else f"> {max_trials}"
        n = f"{r['participants']}" if np.isfinite(r["participants"]) else "—"
        tot = f"{r['total_trials']:.0f}" if np.isfinite(r["total_trials"]) else "—"
        med = f"{r['trials_median']:.0f}" if np.isfinite(r["trials_median"]) else f"> {max_trials}"
        lines.append(f"{r['group']:<{gw}} {r['task']:<7} {r['method']:<9} {tr:>19} {med:>9} {n:>13} {tot:>13}")
    return "\n".join(lines)
