"""Statistics a reviewer asks for: each level against its group's original (GEE),
and a psychometric function per group with a detection threshold.

GEE
    Per group, a marginal logistic model of P(judged incorrect) on the level
    as a category (reference: level 0, the original), fitted by generalised
    estimating equations (statsmodels ``GEE``, Binomial family, logit link,
    exchangeable working correlation, participants as clusters) with the
    Mancl–DeRouen bias-reduced sandwich covariance (few clusters).  Reported per
    level ≠ 0: odds ratio, its 95 % Wald CI, the Wald p value and Holm's
    adjustment over all the levels of all groups.

Psychometric function
    Per group, ``P(incorrect | x) = γ + (1 − γ − λ) Φ((x − m) / s)`` against the
    error magnitude ``x = |level|`` (trials pooled over participants and signed
    levels; of a ``pose-rate`` group the hold time ``1000/N`` ms, see
    :mod:`.units`), with ``γ`` the base rate (lower asymptote: originals and
    undetectable errors), ``λ`` the lapse rate, ``m`` psignifit's threshold of
    the unscaled sigmoid and width ``w = s (Φ⁻¹(.95) − Φ⁻¹(.05))``.

    **Detection threshold** (our definition, reported as ``threshold``): the
    error magnitude at which P(incorrect) is halfway between the base rate and
    certainty, ``P(x*) = (1 + γ) / 2``, i.e. ``x* = m + s Φ⁻¹(F*)`` with
    ``F* = (1 − γ) / (2 (1 − γ − λ))``.  It is "not reached" (NaN, with a note)
    when ``x*`` lies beyond the largest tested level or the fitted curve never
    climbs that high (``F* ≥ 1``).

    The one fit is Bayesian, with psignifit 4 (Schütt,
    Harmeling, Macke & Wichmann 2016, *Painfree and accurate Bayesian estimation
    of psychometric functions for (potentially) overdispersed data*, Vision
    Research 122, 105–123): yes/no design, cumulative normal, overdispersion
    ``η`` free, a uniform prior on ``γ`` over [0, 0.9] (the base rate of an
    "is this motion correct?" task is not a small guess rate), psignifit's
    default priors elsewhere.  Point estimate: MAP; interval: 95 % credible
    interval of ``x*`` from posterior samples.  psignifit is a dependency of
    flipstudy, validated by its authors, and its overdispersion term and
    credible intervals suit pooled answers of few participants; an own
    maximum-likelihood fit beside it was removed (one fit path).

>>> x, n = np.array([0, 17, 25, 37, 50.0]), np.full(5, 76.0)
>>> k = np.round(n * psychometric_curve(x, 32, 15, 0.25, 0.0))     # a curve's counts
>>> f = fit_psignifit("smooth-increase", x, k, n, seed=0)
>>> f.method, f.reached, bool(f.ci_low <= detection_threshold(32, 15, 0.25, 0.0) <= f.ci_high)
('psignifit', True, True)
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.special import ndtr, ndtri

from flipstudy.vocab.psychometric import WIDTH_SCALE, detection_threshold, psychometric_curve  # noqa: F401

from .io import group_order, level_order
from .units import group_kinds, magnitude_unit, magnitudes
from .gee import gee_levels  # noqa: F401  (GEE, re-exported here)

_WSCALE = WIDTH_SCALE      # width = scale * 3.29 (psignifit, alpha = .05)


# ------------------------------------------------------------- psychometric functions

@dataclass
class PsychometricFit:
    """One group's fitted psychometric function and detection threshold.

    Attributes
    ----------
    group : str
        The error group.
    method : str
        ``"psignifit"``.
    x, k, n : ndarray
        Magnitudes, answers "incorrect" and trials per magnitude.
    params : dict
        threshold, width, gamma, lambda (MAP).
    threshold, ci_low, ci_high : float
        The detection threshold x* and its credible interval.
    unit : str
        Of ``x`` (``"%"``, or ``"ms"`` for pose-rate groups).

    Examples
    --------
    >>> from flipstudy.analysis import fit_psychometric, load_responses
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> df = load_responses(paper_panel(19, seed=1))
    >>> fits, notes = fit_psychometric(df[df["group"] == "abrupt-decrease"])
    >>> fits[0].group, fits[0].unit, bool(0 < fits[0].threshold < 60)
    ('abrupt-decrease', '%', True)
    """
    group: str
    method: str
    x: np.ndarray                    # tested |levels|
    k: np.ndarray                    # "incorrect" answers per |level|
    n: np.ndarray                    # trials per |level|
    params: dict                     # threshold (m), width, gamma, lambda, eta
    threshold: float                 # x*, NaN when not reached
    ci_low: float
    ci_high: float                   # NaN when the upper limit is open
    p_reached: float                 # share of posterior samples with x* <= max level
    threshold_extrapolated: float    # x* of the point estimate, even beyond the range (inf: never)
    note: str = ""
    samples: np.ndarray = field(default=None, repr=False)
    #: posterior samples of the parameters (threshold, width, gamma, lambda), for calibrations
    param_samples: dict = field(default=None, repr=False)
    unit: str = "%"                  # of x and the thresholds: "%" or "ms" (pose-rate hold)

    @property
    def reached(self) -> bool:
        return bool(np.isfinite(self.threshold))

    def curve(self, x):
        p = self.params
        return psychometric_curve(x, p["threshold"], p["width"], p["gamma"], p["lambda"])

    def row(self) -> dict:
        p = self.params
        return {"group": self.group, "method": self.method,
                "threshold": self.threshold, "threshold_ci_low": self.ci_low,
                "threshold_ci_high": self.ci_high, "reached": self.reached,
                "p_reached": self.p_reached, "threshold_extrapolated": self.threshold_extrapolated,
                "p_at_threshold": 0.5 * (1 + p["gamma"]),
                "gamma": p["gamma"], "lambda": p["lambda"], "m": p["threshold"], "width": p["width"],
                "eta": p.get("eta", np.nan), "max_level": float(self.x.max()), "note": self.note}


def pooled_magnitudes(sub: pd.DataFrame, kind=None):
    """(magnitude, k incorrect, n trials) of one group, pooled over participants and
    signs: the magnitude is ``|level|``, or for ``kind="pose-rate"`` the hold time
    ``1000/N`` ms (:func:`.units.magnitudes`; the original at 0)."""
    mag = magnitudes(sub["level"].to_numpy(float), kind)
    xs = np.unique(mag)
    idx = np.searchsorted(xs, mag)
    n = np.bincount(idx, minlength=len(xs)).astype(float)
    k = np.bincount(idx, weights=sub["incorrect"].to_numpy(float), minlength=len(xs))
    return xs.astype(float), k, n


def shows_sensitivity(x, k, n) -> bool:
    """Whether the answers grow with the error size at all: the n-weighted least-squares
    slope of the share k/n against x is positive (a check that shares no assumption of
    the fitted curve; answers alike at every level have slope 0 and no threshold).

    >>> shows_sensitivity([0, 10, 20], [5, 5, 5], [5, 5, 5]), shows_sensitivity([0, 10, 20], [1, 3, 5], [5, 5, 5])
    (False, True)
    """
    x, k, n = (np.asarray(a, float) for a in (x, k, n))
    w = n / n.sum()
    p = k / np.maximum(n, 1)
    return bool(np.sum(w * (x - w @ x) * (p - w @ p)) > 1e-12)


def _summarise_samples(group, method, x, k, n, params, xs_samples, ci, extra_note="", unit="%"):
    x_hat = float(detection_threshold(params["threshold"], params["width"], params["gamma"],
                                      params["lambda"]))
    xmax = float(x.max())
    a = (1 - ci) / 2
    lo, hi = np.quantile(xs_samples, [a, 1 - a], method="inverted_cdf")
    p_reached = float(np.mean(xs_samples <= xmax))
    notes = [extra_note] if extra_note else []
    xmin = float(x.min())
    if not shows_sensitivity(x, k, n):
        thr = np.nan
        notes.append("not reached: the data show no sensitivity (the share of 'incorrect' answers "
                     "does not grow with the error size), so no level is a threshold")
    elif np.isfinite(x_hat) and x_hat < xmin - 1e-9 * max(1.0, abs(xmin)):
        thr = np.nan
        notes.append(f"no threshold: P(incorrect) is above (1 + γ)/2 = {0.5 * (1 + params['gamma']):.2f} "
                     f"already at the smallest tested level ({xmin:g} {unit}; x* = {x_hat:.1f} by "
                     f"extrapolation): the original is judged incorrect about as often as the errors")
    elif np.isfinite(x_hat) and x_hat <= xmax:
        thr = x_hat
    else:
        thr = np.nan
        if np.isfinite(x_hat):
            notes.append(f"not reached: P(incorrect) = (1 + γ)/2 = {0.5 * (1 + params['gamma']):.2f} "
                         f"only beyond the largest tested level ({xmax:g} {unit}), extrapolated at {x_hat:.1f} {unit}")
        else:
            notes.append(f"not reached: the fitted curve stays below (1 + γ)/2 = "
                         f"{0.5 * (1 + params['gamma']):.2f} (flat or lapse-limited)")
    if not np.isfinite(hi):
        notes.append(f"upper limit of the interval open (x* never reached in "
                     f"{np.mean(~np.isfinite(xs_samples)):.0%} of the samples)")
        hi = np.nan
    if not np.isfinite(lo):
        lo = np.nan
    if lo < xmin:            # an error size below the smallest tested one is an extrapolation
        notes.append(f"lower limit of the interval at the smallest tested level ({xmin:g} {unit}; "
                     f"the posterior reaches {lo:.1f})")
        lo = xmin
    if lo > xmax:            # the whole posterior lies beyond the tested levels
        notes.append(f"lower limit of the interval beyond the largest tested level ({xmax:g} {unit}; "
                     f"the posterior starts at {lo:.1f})")
        lo = xmax
    if hi > xmax:
        notes.append(f"upper limit of the interval open (beyond the largest tested level, at {hi:.1f})")
        hi = np.nan
    return PsychometricFit(group, method, x, k, n, params, thr, float(lo), float(hi), p_reached,
                           x_hat, "; ".join(notes), samples=xs_samples, unit=unit)


#: the values of ``method`` (of :func:`fit_psychometric`, ``analyze`` and ``--psychometric``)
METHODS = ("psignifit", "none")

#: psignifit's posterior grid, coarser than its default (40/40/20/20/20) to keep a fit near 1 s;
#: the MAP and credible intervals move by well under a grid step on the paper's design
PSIGNIFIT_GRID = {"threshold": 30, "width": 25, "lambda": 12, "gamma": 15, "eta": 10}
PSIGNIFIT_MOVING = {"threshold": 10, "width": 10, "lambda": 5, "gamma": 5, "eta": 5}


# psignifit evaluates its sigmoid and priors a few thousand times per fit (the grid,
# then the simplex search), and its defaults reach the normal distribution through
# scipy.stats: a generic argument check per call and, in the width prior, a frozen
# distribution built on every call.  These are the same formulas on scipy.special's
# ndtr/ndtri, the very functions scipy.stats.norm ends in, so every value comes out
# bit for bit as before (tests/analysis/test_psignifit_calls.py compares them) at a
# few microseconds a call instead of ~100.

_NORM_PDF_C = np.sqrt(2 * np.pi)


def _sigmoid(alpha: float = 0.05):
    """psignifit's cumulative-normal sigmoid (``sigmoid="norm"``) with scipy.stats'
    ``norm.ppf/cdf/pdf(x, loc, scale)`` evaluated directly: NaN where scale ≤ 0 (or
    a probability outside [0, 1]), as scipy.stats returns."""
    from psignifit.sigmoids import Gaussian

    class NormalSigmoid(Gaussian):
        _spread: tuple = (None, None)

        def _standard_parameters(self, threshold, width):
            # Gaussian's: scale = width / (ppf(1 − α) − ppf(α)), loc = threshold −
            # ppf(PC, 0, scale), with the standard quantiles computed once per (α, PC)
            if self._spread[0] != (self.alpha, self._PC):
                self._spread = ((self.alpha, self._PC),
                                self._ppf(1 - self.alpha) - self._ppf(self.alpha), ndtri(self._PC))
            scale = np.asarray(width / self._spread[1])
            return [threshold - np.where(scale > 0, self._spread[2] * scale + 0, np.nan)[()], scale[()]]

        def __call__(self, stimulus_level, threshold, width, gamma=0, lambd=0):
            # psignifit's simplex search asks for one point at a time, level by level
            # (about 15,000 calls an analysis), as arrays of one element: there, the
            # same operations in the same order on floats, without the array round trips
            one = _one_point(stimulus_level, threshold, width, gamma, lambd)
            if one is None or self.negative:
                return super().__call__(stimulus_level, threshold, width, gamma=gamma, lambd=lambd)
            x, t, w, g, lam, shape = one
            if self._spread[0] != (self.alpha, self._PC):
                self._standard_parameters(t, w)
            scale = w / float(self._spread[1])
            if scale > 0:
                loc = t - (float(self._spread[2]) * scale + 0)
                v = g + (1.0 - lam - g) * float(ndtr((x - loc) / scale))
            else:
                v = float("nan")
            return np.full(shape, v) if shape else v

        def _ppf(self, x, loc=0, scale=1):
            x, loc, scale = np.asarray(x), np.asarray(loc), np.asarray(scale)
            ok = (scale > 0) & (loc == loc) & (x >= 0) & (x <= 1)
            with np.errstate(invalid="ignore"):
                return np.where(ok, ndtri(x) * scale + loc, np.nan)[()]

        def _cdf(self, x, loc=0, scale=1):
            scale = np.asarray(scale)
            with np.errstate(divide="ignore", invalid="ignore"):
                return np.where(scale > 0, ndtr((np.asarray(x) - loc) / scale), np.nan)[()]

        def _pdf(self, x, loc=0, scale=1):
            scale = np.asarray(scale)
            with np.errstate(divide="ignore", invalid="ignore"):
                z = (np.asarray(x) - loc) / scale
                return np.where(scale > 0, np.exp(-z ** 2 / 2.0) / _NORM_PDF_C / scale, np.nan)[()]

    return NormalSigmoid(alpha=alpha)


def _one_point(*args):
    """``args`` as floats and their broadcast shape, when every one is a number or an
    array of one element (one point of psignifit's parameter space); else ``None``."""
    vals, nd = [], 0
    for a in args:
        if isinstance(a, np.ndarray):
            if a.size != 1:
                return None
            nd = max(nd, a.ndim)
            vals.append(float(a.reshape(-1)[0]))
        elif isinstance(a, (float, int, np.floating, np.integer)):
            vals.append(float(a))
        else:
            return None
    return (*vals, (1,) * nd)


def _width_prior(levels, alpha: float = 0.05):
    """psignifit's default width prior for ``levels`` (its ``width_prior`` with the
    bounds ``psignifit()`` derives from the data: twice the least spacing of the
    levels to their range, cosine fall-offs to the least spacing and to three
    times the range), its normal quantiles computed once instead of per call."""
    u = np.unique(np.asarray(levels, float))
    wmin, wmax = np.diff(u).min(), u.max() - u.min()
    r95, r_alpha = ndtri(.95) - ndtri(.05), ndtri(1 - alpha) - ndtri(alpha)

    def prior(x):
        if isinstance(x, np.ndarray) and x.size == 1:          # the simplex search's one point
            return np.full(x.shape, one(x.reshape(-1)[0]))
        y = x * r95 / r_alpha
        p = np.zeros_like(x)
        p[((2 * wmin) < y) & (y < wmax)] = 1.
        left = (wmin <= y) & (y <= (2 * wmin))
        p[left] = (1 - np.cos(np.pi * (y[left] - wmin) / wmin)) / 2
        right = (wmax <= y) & (y <= (3 * wmax))
        p[right] = (1 + np.cos(np.pi / 2 * (y[right] - wmax) / wmax)) / 2
        return p

    def one(v):
        # the masks above for one value, the later assignment winning where they overlap
        y = v * r95 / r_alpha
        if wmax <= y <= 3 * wmax:
            return (1 + np.cos(np.pi / 2 * (y - wmax) / wmax)) / 2
        if wmin <= y <= 2 * wmin:
            return (1 - np.cos(np.pi * (y - wmin) / wmin)) / 2
        return 1.0 if 2 * wmin < y < wmax else 0.0
    return prior


def _psignifit_calls(levels):
    """The sigmoid and the priors handed to psignifit: its cumulative normal and its
    default width, lapse and overdispersion priors, evaluated directly (above)."""
    return _sigmoid(), {"width": _width_prior(levels), "lambda": _beta_prior(10), "eta": _beta_prior(10)}


def _posterior_samples(res, n: int, rng) -> dict:
    """``res.posterior_samples(n, random_state=rng)``: the same draw from the same
    generator, the grid indices unravelled instead of every grid point's
    parameters built first (psignifit stacks the whole grid, about a million rows
    of five, to pick ``n``)."""
    values = res.parameter_values
    p = res.debug["posteriors"]
    shape = tuple(len(v) for v in values.values())
    idx = rng.choice(np.arange(int(np.prod(shape))), size=(n,), replace=True, p=p.flatten())
    where = np.unravel_index(idx, shape)
    return {name: np.asarray(v)[i] for (name, v), i in zip(values.items(), where)}


def _beta_prior(b: float):
    """psignifit's default lapse (``b`` = 10) and overdispersion (``b`` = its
    ``beta_prior``, 10) priors, ``scipy.stats.beta.pdf(x, 1, b)``: the density
    scipy.stats evaluates (``beta._pdf``), zero outside [0, 1], NaN at NaN,
    without the generic argument handling around it on every call."""
    from scipy.stats import beta

    def prior(x):
        x = np.asarray(x, float)
        if x.size == 1:                                        # the simplex search's one point
            v = x.reshape(-1)[0]
            if not 0 <= v <= 1:
                return np.full(x.shape, np.nan if v != v else 0.0)[()]
            return np.full(x.shape, beta._pdf(x.reshape(1), 1.0, float(b))[0])[()]
        inside = (0 <= x) & (x <= 1)
        out = np.zeros(x.shape)
        out[np.isnan(x)] = np.nan
        if inside.any():
            out[inside] = beta._pdf(x[inside], 1.0, float(b))
        return out[()]
    return prior


def fit_psignifit(group, x, k, n, *, ci=0.95, seed=0, n_samples=4000, task="yes-no",
                  unit="%") -> PsychometricFit:
    """Bayesian fit with psignifit 4 (see module doc).  ``task="2afc"``: ``k`` counts
    correct choices and psignifit's 2AFC experiment type fixes γ = ½ (x*: P = 0.75).
    ``unit``: of ``x`` (``"%"``, or ``"ms"`` for a pose-rate group's hold time)."""
    import psignifit
    data = np.column_stack([x, k, n])
    if task == "2afc":
        kw = {"experiment_type": "2AFC"}
        grid = {a: b for a, b in PSIGNIFIT_GRID.items() if a != "gamma"}
        moving = {a: b for a, b in PSIGNIFIT_MOVING.items() if a != "gamma"}
    else:
        kw = {"experiment_type": "yes/no", "bounds": {"gamma": (0.0, 0.9)},
              "priors": {"gamma": lambda v: np.ones_like(v)}}
        grid, moving = dict(PSIGNIFIT_GRID), dict(PSIGNIFIT_MOVING)
    sigmoid, priors = _psignifit_calls(x)
    kw["priors"] = {**kw.get("priors", {}), **priors}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = psignifit.psignifit(data, sigmoid=sigmoid, verbose=False, debug=True, grid_steps=grid,
                                  steps_moving_bounds=moving, **kw)
    note = "95 % credible interval (psignifit posterior)"
    if task == "2afc":
        note += "; 2AFC: γ = ½ fixed (psignifit experiment type 2AFC)"
    est = res.parameter_estimate_MAP
    if not (0 <= est["gamma"] <= 0.9 and 0 <= est["lambda"] <= 0.5 and est["width"] > 0
            and est["gamma"] + est["lambda"] < 1 and 0 <= est["eta"] < 1):
        # psignifit refines the MAP with an unbounded simplex search, which can leave the
        # parameter space on degenerate data (every answer alike): use the posterior mean
        est = res.parameter_estimate_mean
        note += "; MAP outside the parameter bounds (degenerate data): posterior mean used"
    params = {"threshold": float(est["threshold"]), "width": float(est["width"]),
              "gamma": float(est["gamma"]), "lambda": float(est["lambda"]), "eta": float(est["eta"])}
    s = _posterior_samples(res, n_samples, np.random.default_rng(seed))
    gam = s["gamma"] if "gamma" in s else np.full_like(s["threshold"], params["gamma"])
    xs = detection_threshold(s["threshold"], s["width"], gam, s["lambda"])
    fit = _summarise_samples(group, "psignifit", x, k, n, params, xs, ci, note, unit)
    fit.param_samples = {"threshold": np.asarray(s["threshold"], float),
                         "width": np.asarray(s["width"], float), "gamma": np.asarray(gam, float),
                         "lambda": np.asarray(s["lambda"], float)}
    return fit


def fit_psychometric(df: pd.DataFrame, method: str = "psignifit", *, ci=0.95,
                     seed=0, task: str = "yes-no") -> tuple[list[PsychometricFit], list[str]]:
    """One :class:`PsychometricFit` per group (a group with fewer than two
    magnitudes, or one psignifit cannot fit, is skipped with a note), and notes.
    ``method``: ``"psignifit"`` or ``"none"`` (no fits).  ``task="2afc"``: the
    answers are 2AFC (correct choices counted from column ``detected``), γ = ½.
    A ``pose-rate`` group (column ``kind``) is fitted against its hold time
    ``1000/N`` ms (:mod:`.units`; its fit's ``unit`` is ``"ms"``).

    Parameters
    ----------
    df : pandas.DataFrame
        A checked response table (:func:`load_responses`).
    method : {"psignifit", "none"}
    ci : float, default 0.95
        Level of the credible intervals.
    seed : int
        Of the posterior samples.
    task : {"yes-no", "2afc"}

    Returns
    -------
    fits : list of PsychometricFit
    notes : list of str

    Examples
    --------
    >>> from flipstudy.analysis import fit_psychometric, load_responses
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> fits, notes = fit_psychometric(load_responses(paper_panel(8, seed=2)), "none")
    >>> fits
    []
    """
    method = method.lower()
    if method not in METHODS:
        hint = " (the own maximum-likelihood fit was removed: psignifit is the one fit)" \
            if method == "mle" else ""
        raise FlipstudyValueError(f"unknown psychometric method {method!r}: expected psignifit or "
                                  f"none{hint}")
    fits, notes = [], []
    if method == "none":
        return fits, notes
    if task == "2afc":
        df = df.assign(incorrect=df["detected"])
    kinds = group_kinds(df)
    for g in group_order(df["group"].unique()):
        x, k, n = pooled_magnitudes(df[df["group"] == g], kinds.get(g))
        if len(x) < 2:
            notes.append(f"{g}: a single error magnitude, no psychometric function fitted")
            continue
        try:
            fits.append(fit_psignifit(g, x, k, n, ci=ci, seed=seed, task=task,
                                      unit=magnitude_unit(kinds.get(g))))
        except Exception as e:  # noqa: BLE001 — a group psignifit cannot fit is a note, never a crash
            notes.append(f"{g}: psignifit failed ({type(e).__name__}: {e}); no psychometric function fitted")
    return fits, notes
