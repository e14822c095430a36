"""psignifit called with what it needs once (issue 34, item 6): the normal sigmoid,
the default priors and the posterior draw of :mod:`flipstudy.analysis.stats` must give
psignifit's own numbers bit for bit — each piece against the library's, and whole
fits against fits made with the library's defaults (``sigmoid="norm"``, no priors
given, ``Result.posterior_samples``), on the paper's panel and on 2AFC counts."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

psignifit = pytest.importorskip("psignifit")
from psignifit import _priors  # noqa: E402

from flipstudy.analysis import stats as S  # noqa: E402


def _same(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape
    assert np.array_equal(a, b, equal_nan=True), np.nanmax(np.abs(a - b))


EDGES = np.array([0.0, 1.0, 1e-300, 0.5, 0.05, 0.95, 1 - 1e-16, -0.1, 1.1, np.nan, np.inf, -np.inf])


@pytest.mark.filterwarnings("ignore::RuntimeWarning")      # scipy.stats' own, at scale 0
def test_sigmoid_quantiles_and_cdf_are_scipy_stats_norm():
    norm = scipy.stats.norm
    sig = S._sigmoid()
    rng = np.random.default_rng(0)
    q = np.concatenate([EDGES, rng.uniform(0, 1, 200)])
    x = np.concatenate([EDGES, rng.normal(0, 30, 200)])
    for loc, scale in [(0.0, 1.0), (3.7, 0.2), (-12.0, 55.0), (1.0, 0.0), (1.0, -2.0), (np.nan, 1.0),
                       (rng.normal(size=q.size), rng.uniform(-0.5, 3, q.size))]:
        _same(sig._ppf(q, loc, scale), norm.ppf(q, loc=loc, scale=scale))
        _same(sig._cdf(x, loc, scale), norm.cdf(x, loc=loc, scale=scale))
        _same(sig._pdf(x, loc, scale), norm.pdf(x, loc=loc, scale=scale))


def test_sigmoid_values_equal_psignifits_gaussian():
    from psignifit.sigmoids import sigmoid_by_name
    ref, sig = sigmoid_by_name("norm", PC=0.5, alpha=0.05), S._sigmoid()
    th, w = np.meshgrid(np.linspace(-5, 60, 31), np.r_[np.linspace(0.5, 90, 25), 0.0, -1.0])
    for level in (0.0, 17.0, 25.0, 50.0):
        _same(sig(level, th, w, gamma=0.2, lambd=0.03), ref(level, th, w, gamma=0.2, lambd=0.03))
    for a, b in zip(sig.standard_parameters(31.0, 12.0), ref.standard_parameters(31.0, 12.0)):
        _same(a, b)


@pytest.mark.parametrize("levels", [[0, 17, 25, 37, 50], [0, 10, 20, 30, 40], [40.0, 62.5, 125, 250]])
def test_priors_equal_psignifits_defaults(levels):
    u = np.unique(levels)
    wmin, wmax = np.diff(u).min(), u.max() - u.min()
    x = np.concatenate([np.linspace(-1, 4 * wmax, 3001), [wmin, 2 * wmin, wmax, 3 * wmax]])
    _same(S._width_prior(levels)(x), _priors.width_prior(x, alpha=0.05, wmin=wmin, wmax=wmax))
    p = np.concatenate([np.linspace(-0.2, 1.2, 1401), [0.0, 1.0, np.nan]])
    _same(S._beta_prior(10)(p), _priors.lambda_prior(p))
    _same(S._beta_prior(10)(p), _priors.eta_prior(p, 10))
    _same(S._beta_prior(10)(0.3), _priors.lambda_prior(0.3))            # scalars too


def _library_defaults(monkeypatch):
    monkeypatch.setattr(S, "_psignifit_calls", lambda levels: ("norm", {}))
    monkeypatch.setattr(S, "_posterior_samples",
                        lambda res, n, rng: res.posterior_samples(n, random_state=rng))


def _fit_values(f):
    return [f.params[k] for k in sorted(f.params)] + [f.threshold, f.ci_low, f.ci_high] + \
        [v for k in sorted(f.param_samples) for v in f.param_samples[k]]


CASES = [  # (x, k, n, task): a yes/no group of the paper's panel, 2AFC counts, then slow:
    ([0, 17, 25, 37, 50], [21, 29, 23, 39, 43], [76, 76, 76, 76, 76], "yes-no"),
    ([5, 10, 20, 40], [21, 25, 33, 39], [40, 40, 40, 40], "2afc"),
    # a steep group and a flat one (the same rate at every level)
    pytest.param([0, 10, 20, 30, 40], [31, 9, 42, 32, 66], [76, 76, 76, 76, 76], "yes-no",
                 marks=pytest.mark.slow),
    pytest.param([0, 17, 25, 37, 50], [10, 10, 10, 10, 10], [40, 40, 40, 40, 40], "yes-no",
                 marks=pytest.mark.slow),
]


@pytest.mark.parametrize("x, k, n, task", CASES)
def test_fits_are_the_librarys_bit_for_bit(x, k, n, task, monkeypatch):
    x, k, n = (np.asarray(v, float) for v in (x, k, n))
    ours = S.fit_psignifit("g", x, k, n, seed=3, n_samples=500, task=task)
    _library_defaults(monkeypatch)
    lib = S.fit_psignifit("g", x, k, n, seed=3, n_samples=500, task=task)
    _same(_fit_values(ours), _fit_values(lib))
    assert ours.note == lib.note


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_one_point_sigmoid_equals_psignifits_gaussian():
    # the simplex search's calls: one point of the parameter space as one-element arrays
    # of the meshgrid's shape, or plain numbers; the values must be psignifit's bit for bit
    from psignifit.sigmoids import sigmoid_by_name
    ref, sig = sigmoid_by_name("norm", PC=0.5, alpha=0.05), S._sigmoid()
    rng = np.random.default_rng(3)
    for _ in range(300):
        level = float(rng.choice([0.0, 17.0, 25.0, 37.0, 50.0]))
        th, w = rng.normal(30, 20), rng.choice([rng.uniform(0.01, 90), 0.0, -3.0])
        g, lam = rng.uniform(0, 0.9), rng.uniform(0, 0.5)
        one = [np.full((1, 1, 1, 1, 1), v) for v in (th, w, g, lam)]
        got, want = sig(level, *one[:2], gamma=one[2], lambd=one[3]), \
            ref(level, *one[:2], gamma=one[2], lambd=one[3])
        assert np.shape(got) == np.shape(want) == (1, 1, 1, 1, 1)
        _same(got, want)
        _same(sig(level, float(th), float(w), gamma=float(g), lambd=float(lam)),
              ref(level, float(th), float(w), gamma=float(g), lambd=float(lam)))


@pytest.mark.parametrize("levels", [[0.0, 17.0, 25.0, 37.0, 50.0],
                                    [0.0, 50.0]])          # here the two fall-offs overlap
def test_one_point_priors_equal_their_array_values(levels):
    # the simplex search's one-element arrays take a shortcut; every value, boundaries of
    # the cosine fall-offs included, must be what the whole-array path gives
    u = np.unique(levels)
    wmin, wmax = np.diff(u).min(), u.max() - u.min()
    edges = np.array([wmin, 2 * wmin, wmax, 3 * wmax])     # alpha = .05: y = x
    xs = np.concatenate([edges, np.nextafter(edges, np.inf), np.nextafter(edges, -np.inf),
                         np.random.default_rng(2).uniform(-10, 200, 300), [0.0, -1.0, np.nan]])
    width = S._width_prior(np.asarray(levels))
    beta = S._beta_prior(10)
    bx = np.concatenate([xs / 150, [0.0, 1.0, np.nextafter(1.0, 2.0), -0.0, np.nan]])
    for prior, values in ((width, xs), (beta, bx)):
        whole = prior(np.r_[values, 0.5])[:-1]        # the array path (more than one element)
        one = np.array([prior(np.full((1, 1, 1, 1, 1), v)).reshape(-1)[0] for v in values])
        _same(one, whole)
