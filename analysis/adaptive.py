"""QUEST+ over a group's stimulus grid, with the analysis's psychometric function.

The model is the one :mod:`flipstudy.analysis.stats` fits to constant stimuli,
``P(detected | x) = γ + (1 − γ − λ) Φ((x − m)/s)`` (:func:`~.stats.psychometric_curve`,
width ``w = s·3.29``), and the threshold is the same ``x*`` with
``P(x*) = (1 + γ)/2`` (:func:`~.stats.detection_threshold`), so adaptive and
constant-stimuli thresholds stand in one table.

* yes/no: "detected" is the answer ``incorrect``; ``γ`` (how often an unmodified
  motion is judged incorrect) is unknown, on :data:`GAMMA_GRID`;
* 2AFC: "detected" is choosing the original as the physically correct one;
  ``γ = ½``, so ``x*`` is where P(correct) = 0.75.

The posterior lives on a grid of ``m`` (uniform prior over ``threshold_prior``,
default the levels' range), ``w`` (log-uniform over ``width_prior``) and ``γ``
(uniform, yes/no only), with ``λ`` fixed; every grid cell has its ``x*``, which
gives the threshold's posterior.  The ``questplus`` package (Watson 2017's
QUEST+, by Höchenberger) holds that posterior and updates it; the next level is
QUEST+'s: the level of least expected posterior entropy, computed here with the
identity ``E[H] = Σ_o [p_o log p_o − Σ_θ π L_o log(π L_o)]`` as four
matrix–vector products (questplus's own ``next_stim`` gives the same level, see
the tests, at ~20× the time on a 61-level grid).

>>> model = quest_model(range(0, 61), "yes-no", QuestSettings(trials=30))
>>> q = Quest.new(model)
>>> observer = Observer(threshold=20.0, width=15.0, gamma=0.2, lapse=0.02, task="yes-no")
>>> rng = np.random.default_rng(1)
>>> while not q.finished():
...     level = q.next_level()
...     q.update(level, observer.answer(level, rng))
>>> t = q.threshold()
>>> q.n_trials, bool(t["ci_low"] <= 20.0 <= t["ci_high"])
(30, True)
>>> q2 = Quest.from_json(model, q.to_json())          # a resumed session
>>> q2.next_level() == q.next_level(), q2.threshold() == t
(True, True)
"""
from __future__ import annotations

import base64
import copy
import hashlib
import json
import zlib
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.special import ndtri, xlogy

from flipstudy.errors import FlipstudyValueError
from flipstudy.vocab import groupkeys

from .stats import _WSCALE, detection_threshold, psychometric_curve

TASKS = groupkeys.TASKS          # the design's tasks (flipstudy.vocab.groupkeys)
#: base rates γ the yes/no posterior considers (the paper's originals: 0.28)
GAMMA_GRID = np.round(np.arange(0.0, 0.7001, 0.05), 2)
#: grid points of m and of the width
N_THRESHOLD, N_WIDTH = 41, 10
#: the JSON state's format tag
FORMAT = "flipstudy-quest+/1"
#: a level given to :meth:`Quest.update` is the grid level within this (percent)
LEVEL_ATOL = 1e-6
#: share of the posterior an interval leaves out (95 % intervals)
ALPHA = 0.05


@dataclass(frozen=True)
class QuestSettings:
    """What a design's ``method = "quest+"`` group says.

    ``trials``: stop after this many trials; ``stop_width``: or once the 95 %
    interval of ``x*`` is narrower than this (percent); ``threshold_prior``:
    the range of the uniform prior on ``m`` (percent; None: the levels' range);
    ``width_prior``: the range of the width ``w = s·3.29`` (log-uniform);
    ``lapse``: the fixed lapse rate ``λ``.
    """
    trials: int = 40
    stop_width: float | None = None
    threshold_prior: tuple[float, float] | None = None
    width_prior: tuple[float, float] = (5.0, 60.0)
    lapse: float = 0.02

    def __post_init__(self):
        if not isinstance(self.trials, (int, np.integer)) or isinstance(self.trials, bool) \
                or self.trials < 1:
            raise FlipstudyValueError(f"quest+ trials: a whole number ≥ 1, got {self.trials!r}")
        if self.stop_width is not None and not (np.isfinite(self.stop_width) and self.stop_width > 0):
            raise FlipstudyValueError(f"quest+ stop_width: a positive width in percent, got "
                                      f"{self.stop_width!r}")
        for name in ("threshold_prior", "width_prior"):
            v = getattr(self, name)
            if v is None:
                continue
            if len(v) != 2 or not all(np.isfinite(float(a)) for a in v) or not v[0] < v[1]:
                raise FlipstudyValueError(f"quest+ {name}: [low, high] with low < high (percent), "
                                          f"got {v!r}")
            object.__setattr__(self, name, (float(v[0]), float(v[1])))
        if self.width_prior[0] <= 0:
            raise FlipstudyValueError(f"quest+ width_prior: widths are positive, got {self.width_prior!r}")
        if not 0 <= self.lapse < 0.2:
            raise FlipstudyValueError(f"quest+ lapse: a rate in [0, 0.2), got {self.lapse!r}")


@dataclass(frozen=True, eq=False)
class QuestModel:
    """A group's QUEST+ model: its candidate levels and the parameter grid.

    ``levels``: what :meth:`Quest.next_level` returns (ascending; 2AFC: without
    0, the comparison); ``m``, ``width``, ``gamma``: the grid axes; ``prior``,
    ``xstar`` and the rows of ``p_detect`` are flat over the grid (C order m,
    width, γ); ``p_detect[i]`` is P(detected | levels[i]) in every cell.
    """
    levels: np.ndarray
    task: str
    settings: QuestSettings
    m: np.ndarray
    width: np.ndarray
    gamma: np.ndarray
    lapse: float
    prior: np.ndarray
    p_detect: np.ndarray
    xstar: np.ndarray
    key: str
    _ent: tuple = field(repr=False)
    _order: np.ndarray = field(repr=False)
    _qp: object = field(repr=False)

    @property
    def shape(self) -> tuple[int, int, int]:
        """The grid's shape (m, width, γ)."""
        return len(self.m), len(self.width), len(self.gamma)

    def expected_entropy(self, post: np.ndarray) -> np.ndarray:
        """QUEST+'s expected posterior entropy after one trial at each level,
        for posteriors ``post`` of shape (..., cells) (rows summing to 1)."""
        n = len(self.levels)
        post = np.asarray(post, float)
        plp = xlogy(post, post)
        A0, A1 = self._ent                              # L log L, (1 − L) log(1 − L)
        p0 = post @ self.p_detect.T                     # P(detected), (..., levels)
        p1 = post.sum(-1)[..., None] - p0
        lp = plp @ self.p_detect.T                      # Σ π log π · L
        t0 = lp + post @ A0.T                           # Σ π L log(π L)
        t1 = (plp.sum(-1)[..., None] - lp) + post @ A1.T
        return xlogy(p0, p0) + xlogy(p1, p1) - t0 - t1

    def summary(self, post: np.ndarray) -> dict:
        """``{"threshold", "ci_low", "ci_high", "sd"}`` of x* under the posterior ``post``
        (posterior mean, 95 % equal-tailed interval, SD)."""
        order = self._order
        cdf = np.cumsum(post[order])
        cdf /= cdf[-1]
        lo, hi = np.searchsorted(cdf, [ALPHA / 2, 1 - ALPHA / 2])
        xs = self.xstar[order]
        mean = float(post @ self.xstar / post.sum())
        var = float(post @ (self.xstar - mean) ** 2 / post.sum())
        return {"threshold": mean, "ci_low": float(xs[min(lo, len(xs) - 1)]),
                "ci_high": float(xs[min(hi, len(xs) - 1)]), "sd": float(np.sqrt(max(var, 0.0)))}


_MODELS: dict = {}


def quest_model(levels, task: str = "yes-no", settings: QuestSettings | None = None) -> QuestModel:
    """The QUEST+ model of a group with these levels (percent), task and settings.

    Models are cached (a session asks for its group's model at every trial).

    >>> m = quest_model([0, 10, 20, 30, 40], "2afc")
    >>> m.levels.tolist(), m.shape, float(m.gamma[0])
    ([10.0, 20.0, 30.0, 40.0], (41, 10, 1), 0.5)
    """
    settings = settings or QuestSettings()
    if task not in TASKS:
        raise FlipstudyValueError(f"task {task!r}: expected one of {', '.join(TASKS)}")
    lv = np.asarray(list(levels), float)
    if lv.ndim != 1 or not np.all(np.isfinite(lv)) or np.any(lv < 0):
        raise FlipstudyValueError(f"quest+ levels: error magnitudes in percent (≥ 0), got {levels!r}")
    lv = np.unique(lv)
    top = float(lv.max()) if len(lv) else 0.0
    if task == "2afc":
        lv = lv[lv > 0]                                 # level 0 is the comparison
    if len(lv) < 2:
        raise FlipstudyValueError(f"quest+ levels: at least two levels to choose from"
                                  f"{' besides 0 (the comparison) in 2AFC' if task == '2afc' else ''}, "
                                  f"got {sorted(set(np.asarray(list(levels), float).tolist()))}")
    key = hashlib.sha256(json.dumps([lv.tolist(), task, asdict(settings), GAMMA_GRID.tolist(),
                                     N_THRESHOLD, N_WIDTH]).encode()).hexdigest()[:16]
    if key in _MODELS:
        return _MODELS[key]
    lo, hi = settings.threshold_prior or (0.0, top)
    m = np.linspace(lo, hi, N_THRESHOLD)
    w = np.geomspace(*settings.width_prior, N_WIDTH)
    g = GAMMA_GRID.copy() if task == "yes-no" else np.array([0.5])
    lam = float(settings.lapse)
    M, W, G = np.meshgrid(m, w, g, indexing="ij")
    L = psychometric_curve(lv[:, None, None, None], M, W, G, lam)       # (levels, m, w, γ)
    xstar = detection_threshold(M, W, G, lam).ravel()
    prior = np.full(M.size, 1.0 / M.size)
    Lf = np.ascontiguousarray(L.reshape(len(lv), -1))
    ent = (xlogy(Lf, Lf), xlogy(1 - Lf, 1 - Lf))
    qp = _questplus(lv, m, w, g, lam, L, prior.reshape(M.shape))
    model = QuestModel(lv, task, settings, m, w, g, lam, prior, Lf, xstar, key, ent,
                       np.argsort(xstar, kind="stable"), qp)
    _MODELS[key] = model
    return model


def _questplus(x, m, w, g, lam, L, prior):
    """A ``questplus.QuestPlus`` over this grid whose likelihood is the analysis's curve."""
    import questplus
    qp = questplus.QuestPlus(
        stim_domain={"intensity": x}, outcome_domain={"response": ["detected", "not"]},
        param_domain={"mean": m, "sd": w / _WSCALE, "lower_asymptote": g, "lapse_rate": [lam]},
        prior={"mean": np.ones_like(m), "sd": np.ones_like(w), "lower_asymptote": np.ones_like(g),
               "lapse_rate": [1.0]},
        func="norm_cdf", stim_scale="linear")
    # questplus's norm_cdf is this same curve (tests check it); use the analysis's values
    qp.likelihoods = qp.likelihoods.copy(data=np.stack([L, 1 - L])[..., None])
    qp.prior = qp.prior.copy(data=prior[..., None])
    qp.posterior = qp.prior.copy()
    return qp


class Quest:
    """One participant's QUEST+ run on one group (see the module doc)."""

    def __init__(self, model: QuestModel, qp):
        self.model = model
        self.qp = qp

    @classmethod
    def new(cls, model: QuestModel) -> "Quest":
        """A run at the prior."""
        qp = copy.copy(model._qp)                       # shares the (read-only) likelihoods
        qp.posterior = model._qp.prior.copy()
        qp.stim_history, qp.resp_history = [], []
        return cls(model, qp)

    @property
    def posterior(self) -> np.ndarray:
        """The posterior, flat over the grid (a view; do not modify)."""
        return self.qp.posterior.values.reshape(-1)

    @property
    def n_trials(self) -> int:
        """Trials answered so far."""
        return len(self.qp.stim_history)

    @property
    def history(self) -> list[tuple[float, bool]]:
        """(level, detected) of every trial so far."""
        return [(float(s["intensity"]), r["response"] == "detected")
                for s, r in zip(self.qp.stim_history, self.qp.resp_history)]

    def next_level(self) -> float:
        """The level of least expected posterior entropy (first such level on ties)."""
        eh = self.model.expected_entropy(self.posterior)
        return float(self.model.levels[int(np.argmin(eh))])

    def update(self, level: float, detected: bool) -> None:
        """Add one answer: ``detected`` is True for "incorrect" (yes/no) or the
        original chosen as correct (2AFC)."""
        lv = self.model.levels
        i = np.flatnonzero(np.abs(lv - float(level)) <= LEVEL_ATOL)     # a level read back from text
        if not len(i):
            raise FlipstudyValueError(f"quest+ update: level {level!r} is not one of the group's "
                                      f"levels ({lv[0]:g} … {lv[-1]:g}, {len(lv)} levels)")
        self.qp.update(stim={"intensity": lv[i[0]]},
                       outcome={"response": "detected" if bool(detected) else "not"})

    def finished(self) -> bool:
        """The group's trials are done, or the 95 % interval of x* is narrower than ``stop_width``."""
        s = self.model.settings
        if self.n_trials >= s.trials:
            return True
        if s.stop_width is not None:
            t = self.threshold()
            return t["ci_high"] - t["ci_low"] < s.stop_width
        return False

    def threshold(self) -> dict:
        """``{"threshold", "ci_low", "ci_high", "sd"}`` of x* (posterior mean, 95 % interval, SD)."""
        return self.model.summary(self.posterior)

    def to_json(self) -> str:
        """The whole state as compact JSON: the model's key, the history and the
        posterior's float64 bytes (zlib, base64)."""
        post = np.ascontiguousarray(self.posterior, dtype="<f8")
        h = self.history
        return json.dumps({"format": FORMAT, "model": self.model.key, "task": self.model.task,
                           "levels": [lv for lv, _ in h], "detected": [int(d) for _, d in h],
                           "posterior": base64.b64encode(zlib.compress(post.tobytes(), 6)).decode()},
                          separators=(",", ":"))

    @classmethod
    def from_json(cls, model: QuestModel, text: str) -> "Quest":
        """The run :meth:`to_json` wrote, on this model: the same posterior bytes and
        history, hence the same next level.  A state of another model (the group's
        levels, task or settings changed) is refused."""
        try:
            d = json.loads(text)
            ok = isinstance(d, dict) and d.get("format") == FORMAT
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise FlipstudyValueError(f"not a QUEST+ state ({FORMAT}): {str(text)[:60]!r}")
        if d["model"] != model.key:
            raise FlipstudyValueError(
                f"this QUEST+ state belongs to another model (key {d['model']}, task {d.get('task')}); "
                f"the group's levels, task or quest+ settings changed since it was stored "
                f"(now key {model.key})")
        post = np.frombuffer(zlib.decompress(base64.b64decode(d["posterior"])), dtype="<f8")
        if post.size != model.prior.size or len(d["levels"]) != len(d["detected"]):
            raise FlipstudyValueError("QUEST+ state: posterior or history of the wrong size")
        q = cls.new(model)
        q.qp.posterior = model._qp.prior.copy(data=post.astype(float).reshape(model._qp.prior.shape))
        for lv, det in zip(d["levels"], d["detected"]):
            q.qp.stim_history.append({"intensity": float(lv)})
            q.qp.resp_history.append({"response": "detected" if det else "not"})
        return q


# ------------------------------------------------------------------ simulated observers

@dataclass(frozen=True)
class Observer:
    """A simulated observer with known parameters: threshold ``x*`` (percent),
    width ``w``, base rate ``γ`` (2AFC: ½), lapse ``λ``, task.

    >>> o = Observer(threshold=20.0, width=10.0, gamma=0.25, lapse=0.02, task="yes-no")
    >>> round(float(o.p_detect(20.0)), 3)            # (1 + γ)/2 at the threshold
    0.625
    """
    threshold: float
    width: float
    gamma: float
    lapse: float
    task: str = "yes-no"

    @property
    def m(self) -> float:
        """The curve's m (psignifit's threshold of the unscaled sigmoid) for this x*."""
        F = (1 - self.gamma) / (2 * (1 - self.gamma - self.lapse))
        return float(self.threshold - self.width / _WSCALE * ndtri(F))

    def p_detect(self, levels):
        """P(detected) at these levels (|level|, percent)."""
        return psychometric_curve(np.abs(np.asarray(levels, float)), self.m, self.width,
                                  self.gamma, self.lapse)

    def answer(self, level: float, rng: np.random.Generator) -> bool:
        """One simulated answer: detected or not."""
        return bool(rng.random() < self.p_detect(level))


def population(n: int, rng: np.random.Generator, task: str = "yes-no", *,
               threshold: tuple[float, float] = (25.0, 8.0), width: tuple[float, float] = (8.0, 40.0),
               gamma: tuple[float, float] = (0.05, 0.45), lapse: float = 0.02,
               bounds: tuple[float, float] = (3.0, 57.0)) -> list[Observer]:
    """``n`` observers: x* normal (mean, SD) truncated to ``bounds``, width
    log-uniform over ``width``, γ uniform over ``gamma`` (2AFC: ½), fixed lapse.

    >>> obs = population(3, np.random.default_rng(0), "2afc")
    >>> [o.gamma for o in obs], all(3 <= o.threshold <= 57 for o in obs)
    ([0.5, 0.5, 0.5], True)
    """
    if task not in TASKS:
        raise FlipstudyValueError(f"task {task!r}: expected one of {', '.join(TASKS)}")
    xs = rng.normal(threshold[0], threshold[1], size=4 * n + 16)
    xs = xs[(xs >= bounds[0]) & (xs <= bounds[1])]
    while len(xs) < n:
        more = rng.normal(threshold[0], threshold[1], size=4 * n + 16)
        xs = np.concatenate([xs, more[(more >= bounds[0]) & (more <= bounds[1])]])
    ws = np.exp(rng.uniform(np.log(width[0]), np.log(width[1]), size=n))
    gs = rng.uniform(gamma[0], gamma[1], size=n) if task == "yes-no" else np.full(n, 0.5)
    return [Observer(float(x), float(w), float(g), float(lapse), task)
            for x, w, g in zip(xs[:n], ws, gs)]
