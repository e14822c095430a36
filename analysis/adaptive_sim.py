"""Many simulated QUEST+ (or constant-stimuli) runs at once: a numpy twin of
:class:`~flipstudy.analysis.adaptive.Quest`.

:class:`QuestBatch` holds one posterior per observer as the rows of an array,
over the same model (grid, prior, likelihood) as :class:`Quest`; it chooses the
same next levels (the same expected-entropy code, on all rows in one matrix
product) and multiplies the same likelihood rows, so its posteriors equal
questplus's (tests/analysis/test_adaptive_sim.py checks both on answer sequences drawn by
hypothesis).  It is what parameter recovery, ``flipstudy plan`` and the
benchmark use: 200 observers × 40 trials take a second or two, where questplus
updates one observer at a time through xarray.

>>> from flipstudy.analysis.adaptive import quest_model, population
>>> model = quest_model(range(0, 61), "2afc")
>>> obs = population(50, np.random.default_rng(0), "2afc")
>>> sim = simulate(model, obs, 40, np.random.default_rng(1))
>>> sim.width.shape, bool(np.mean(sim.covered) > 0.85)
((41, 50), True)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flipstudy.errors import FlipstudyValueError

from .adaptive import ALPHA, Observer, QuestModel
from .stats import psychometric_curve

METHODS = ("quest+", "constant")


class QuestBatch:
    """``n`` QUEST+ posteriors over one model, updated together (rows of ``post``)."""

    def __init__(self, model: QuestModel, n: int):
        self.model = model
        self.post = np.tile(model.prior, (n, 1))

    @classmethod
    def from_counts(cls, model: QuestModel, k: np.ndarray, n: np.ndarray) -> "QuestBatch":
        """Posteriors after ``n[j, i]`` trials at ``model.levels[i]`` of which ``k[j, i]``
        were detected (order does not matter without adaptive choices): one row per
        row of ``k``, computed in log space as one matrix product."""
        L = model.p_detect
        with np.errstate(divide="ignore"):
            lL, l1 = np.log(L), np.log1p(-L)
        k, n = np.atleast_2d(np.asarray(k, float)), np.atleast_2d(np.asarray(n, float))
        # 0 · log 0 = 0: a cell with L = 0 (or 1) is only impossible where it was observed
        ll = np.where(k > 0, k, 0) @ np.where(np.isfinite(lL), lL, -1e300) \
            + np.where(n - k > 0, n - k, 0) @ np.where(np.isfinite(l1), l1, -1e300)
        ll += np.log(model.prior)
        ll -= ll.max(axis=1, keepdims=True)
        b = cls(model, len(k))
        b.post = np.exp(ll)
        b.post /= b.post.sum(1, keepdims=True)
        return b

    def next_index(self) -> np.ndarray:
        """Per row, the index (into ``model.levels``) of least expected entropy."""
        return np.argmin(self.model.expected_entropy(self.post), axis=-1)

    def update(self, index: np.ndarray, detected: np.ndarray) -> None:
        """Multiply each row by the likelihood of its answer and renormalise."""
        L = self.model.p_detect[np.asarray(index)]
        self.post *= np.where(np.asarray(detected, bool)[:, None], L, 1.0 - L)
        self.post /= self.post.sum(-1, keepdims=True)

    def summary(self) -> dict[str, np.ndarray]:
        """Per row: x*'s posterior mean, 95 % interval and SD (as :meth:`Quest.threshold`)."""
        m = self.model
        cdf = np.cumsum(self.post[:, m._order], axis=1)
        cdf /= cdf[:, -1:]
        last = cdf.shape[1] - 1
        xs = m.xstar[m._order]
        lo = xs[np.minimum((cdf < ALPHA / 2).sum(1), last)]
        hi = xs[np.minimum((cdf < 1 - ALPHA / 2).sum(1), last)]
        tot = self.post.sum(1)
        mean = self.post @ m.xstar / tot
        var = (self.post @ m.xstar ** 2) / tot - mean ** 2
        return {"threshold": mean, "ci_low": lo, "ci_high": hi, "sd": np.sqrt(np.maximum(var, 0))}


def observer_params(observers: list[Observer]) -> dict[str, np.ndarray]:
    """The observers' true x*, m, width, γ and λ as arrays."""
    return {k: np.array([getattr(o, k) for o in observers], float)
            for k in ("threshold", "m", "width", "gamma", "lapse")}


@dataclass
class Simulation:
    """Trial-by-trial record of simulated runs: row t holds the state after t trials.

    ``levels``/``detected``: (trials, observers); ``threshold``, ``ci_low``,
    ``ci_high``, ``sd``: (trials + 1, observers); ``truth``: the observers' x*.
    """
    method: str
    levels: np.ndarray
    detected: np.ndarray
    threshold: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    sd: np.ndarray
    truth: np.ndarray
    posterior: np.ndarray

    @property
    def width(self) -> np.ndarray:
        """95 % interval width of x* after each trial."""
        return self.ci_high - self.ci_low

    @property
    def covered(self) -> np.ndarray:
        """Whether the final 95 % interval holds the observer's true x*."""
        return (self.ci_low[-1] <= self.truth) & (self.truth <= self.ci_high[-1])

    def trials_to_width(self, target: float) -> np.ndarray:
        """Per observer, the first trial count whose interval is narrower than
        ``target`` (np.inf when it never is within the simulated trials)."""
        ok = self.width < target
        first = np.argmax(ok, axis=0).astype(float)
        first[~ok.any(axis=0)] = np.inf
        return first


def constant_sequence(levels, n_trials: int, n_observers: int, rng) -> np.ndarray:
    """(trials, observers) levels of constant stimuli: each observer sees the levels
    in shuffled blocks (every level once per block), as the session orders them."""
    lv = np.asarray(levels, float)
    blocks = -(-n_trials // len(lv))
    seq = np.concatenate([rng.permuted(np.tile(lv, (n_observers, 1)), axis=1)
                          for _ in range(blocks)], axis=1)
    return seq[:, :n_trials].T


def simulate(model: QuestModel, observers: list[Observer], n_trials: int, rng, *,
             method: str = "quest+", constant_levels=None, every_trial: bool = True) -> Simulation:
    """Every observer answers ``n_trials`` trials of ``method``: ``"quest+"`` (the
    model picks each level) or ``"constant"`` (``constant_levels``, default the
    model's levels, in shuffled blocks); the posterior is the model's either way.
    ``every_trial=False`` summarises x* only before the first and after the last
    trial (the other rows of the summaries stay NaN)."""
    if method not in METHODS:
        raise FlipstudyValueError(f"method {method!r}: expected one of {', '.join(METHODS)}")
    n = len(observers)
    p = observer_params(observers)
    batch = QuestBatch(model, n)
    index_of = {float(v): i for i, v in enumerate(model.levels)}
    if method == "constant":
        seq = constant_sequence(model.levels if constant_levels is None else constant_levels,
                                n_trials, n, rng)
        try:
            seq_idx = np.vectorize(index_of.__getitem__, otypes=[int])(seq)
        except KeyError as e:
            raise FlipstudyValueError(f"constant level {e.args[0]:g} is not on the model's grid") from None
    levels = np.zeros((n_trials, n))
    detected = np.zeros((n_trials, n), bool)
    out = {k: np.full((n_trials + 1, n), np.nan) for k in ("threshold", "ci_low", "ci_high", "sd")}
    for k, v in batch.summary().items():
        out[k][0] = v
    for t in range(n_trials):
        idx = batch.next_index() if method == "quest+" else seq_idx[t]
        x = model.levels[idx]
        pd_ = psychometric_curve(x, p["m"], p["width"], p["gamma"], p["lapse"])
        det = rng.random(n) < pd_
        batch.update(idx, det)
        levels[t], detected[t] = x, det
        if not (every_trial or t == n_trials - 1):
            continue
        for k, v in batch.summary().items():
            out[k][t + 1] = v
    return Simulation(method, levels, detected, truth=p["threshold"], posterior=batch.post, **out)
