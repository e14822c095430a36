"""Signal detection for a yes/no "correct / incorrect" judgement.

Conventions (DESIGN.md):

* the *signal* is a modified motion, the *noise* the original (level 0 of the
  same error group); a "hit" is a modified motion judged ``incorrect``, a
  "false alarm" an original judged ``incorrect``;
* ``d′ = z(H) − z(F)`` with ``H = P(incorrect | modified)`` and
  ``F = P(incorrect | original)``; ``z`` is the standard normal quantile
  (``scipy.stats.norm.ppf``);
* criterion ``c = −(z(H) + z(F)) / 2`` (Macmillan & Creelman 2005): positive
  ``c`` is a bias towards answering "correct";
* two-alternative forced choice (an original and a modified motion, "which was
  physically correct?"): ``d′ = √2 · z(P correct)`` (Macmillan & Creelman 2005,
  ch. 7), :func:`dprime_2afc`; a proportion of 0 or 1 is corrected by the same
  rules (``"loglinear"``: ``(k + 0.5)/(n + 1)`` when it is 0 or 1);
* rates of 0 or 1 make ``z`` infinite and are corrected:

  ``"loglinear"`` (default)
      Hautus (1995): add 0.5 to the count and 1 to the total,
      ``P = (k + 0.5) / (n + 1)``, applied to *both* rates of a comparison
      when either of them is 0 or 1 (so the two rates are treated alike).
  ``"loglinear-all"``
      the same formula applied to every rate, extreme or not (Hautus's own
      recommendation; shrinks every d′ slightly towards 0).
  ``"1/(2N)"``
      Macmillan & Kaplan (1985): only the extreme rate is replaced,
      0 → ``1/(2N)`` and 1 → ``1 − 1/(2N)``.

Every function is vectorised: counts may be scalars or arrays of any
broadcastable shape.

>>> round(float(dprime(59, 100, 28, 100)), 4)      # the paper's 41 % vs 72 % "correct"
0.8104
>>> corrected_rate(0, 20, "loglinear") == 0.5 / 21
True
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

import numpy as np
from scipy.special import ndtri

CORRECTIONS = ("loglinear", "loglinear-all", "1/(2N)")
_ALIASES = {
    "loglinear": "loglinear", "log-linear": "loglinear", "hautus": "loglinear",
    "loglinear-all": "loglinear-all", "log-linear-all": "loglinear-all",
    "1/(2n)": "1/(2N)", "1/2n": "1/(2N)", "half-n": "1/(2N)", "macmillan-kaplan": "1/(2N)",
}
CORRECTION_TEXT = {
    "loglinear": ("log-linear correction (Hautus 1995): when a hit or false-alarm rate of a "
                  "comparison is 0 or 1, both rates become (k + 0.5) / (n + 1)"),
    "loglinear-all": ("log-linear correction (Hautus 1995) applied to every rate: "
                      "(k + 0.5) / (n + 1)"),
    "1/(2N)": ("1/(2N) rule (Macmillan & Kaplan 1985): a rate of 0 becomes 1/(2N) and a rate "
               "of 1 becomes 1 − 1/(2N); other rates are left as they are"),
}


def normalise_correction(correction: str) -> str:
    """The canonical name of a correction (``"loglinear"``, ``"loglinear-all"``
    or ``"1/(2N)"``); aliases such as ``"1/2N"`` and ``"log-linear"`` are accepted."""
    key = str(correction).strip().lower()
    if key not in _ALIASES:
        raise FlipstudyValueError(f"unknown correction {correction!r}: expected one of "
                         f"{', '.join(CORRECTIONS)} (aliases: 1/2N, log-linear)")
    return _ALIASES[key]


def _out(a):
    """A Python float for a 0-d result, the array otherwise."""
    a = np.asarray(a)
    return float(a) if a.ndim == 0 else a


def z(p):
    """Standard normal quantile, ``scipy.stats.norm.ppf`` (``ndtri``).

    Parameters
    ----------
    p : float or array_like
        Probabilities in (0, 1).

    Returns
    -------
    float or ndarray

    Examples
    --------
    >>> from flipstudy.analysis import z
    >>> round(float(z(0.975)), 4), float(z(0.5))
    (1.96, 0.0)
    """
    return ndtri(np.asarray(p, dtype=float))


def _counts(k, n):
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    if np.any(n <= 0):
        raise ValueError("every total (number of trials) must be positive")
    if np.any(k < 0) or np.any(k > n):
        raise ValueError("counts must lie between 0 and the number of trials")
    return k, n


def corrected_rate(k, n, correction: str = "loglinear"):
    """One rate ``k / n`` passed through a correction's formula.

    ``"loglinear"`` and ``"loglinear-all"`` give ``(k + 0.5) / (n + 1)`` for
    every rate; ``"1/(2N)"`` changes only rates of 0 (→ ``1/(2N)``) and 1
    (→ ``1 − 1/(2N)``).  *When* the log-linear formula is applied is decided by
    :func:`rates`; this function is the formula.

    Parameters
    ----------
    k, n : int or array_like
        Count and number of trials.
    correction : {"loglinear", "loglinear-all", "1/(2N)"}

    Returns
    -------
    float or ndarray

    Examples
    --------
    >>> corrected_rate(0, 20, "loglinear"), corrected_rate(20, 20, "loglinear")  # 0.5/21, 20.5/21
    (0.023809523809523808, 0.9761904761904762)
    >>> corrected_rate(0, 20, "1/(2N)"), corrected_rate(20, 20, "1/(2N)")        # 1/40, 39/40
    (0.025, 0.975)
    """
    c = normalise_correction(correction)
    k, n = _counts(k, n)
    if c == "1/(2N)":
        p = k / n
        return _out(np.where(k == 0, 1.0 / (2 * n), np.where(k == n, 1.0 - 1.0 / (2 * n), p)))
    return _out((k + 0.5) / (n + 1.0))


def rates(hits, n_signal, false_alarms, n_noise, correction: str = "loglinear"):
    """Hit and false-alarm rates after the correction, and where it applied.

    Returns ``(H, F, corrected)``: arrays broadcast to a common shape;
    ``corrected`` is True where a rate was changed.

    Parameters
    ----------
    hits : int or array_like
        Modified motions judged incorrect.
    n_signal : int or array_like
        Trials of modified motions.
    false_alarms : int or array_like
        Originals judged incorrect.
    n_noise : int or array_like
        Trials of originals.
    correction : {"loglinear", "loglinear-all", "1/(2N)"}
        How rates of 0 or 1 are corrected (see :func:`rates`).

    Returns
    -------
    H, F : ndarray
        Hit and false-alarm rates.
    corrected : ndarray of bool

    Examples
    --------
    >>> from flipstudy.analysis import rates
    >>> H, F, corrected = rates(20, 20, 5, 20)             # a hit rate of 1: corrected
    >>> float(H), float(F), bool(corrected)
    (0.9761904761904762, 0.2619047619047619, True)
    """
    c = normalise_correction(correction)
    kh, nh = _counts(hits, n_signal)
    kf, nf = _counts(false_alarms, n_noise)
    kh, nh, kf, nf = np.broadcast_arrays(kh, nh, kf, nf)
    h_raw, f_raw = kh / nh, kf / nf
    h_ext = (kh == 0) | (kh == nh)
    f_ext = (kf == 0) | (kf == nf)
    if c == "loglinear-all":
        corrected = np.ones(h_raw.shape, dtype=bool)
        H, F = (kh + 0.5) / (nh + 1.0), (kf + 0.5) / (nf + 1.0)
    elif c == "loglinear":
        corrected = h_ext | f_ext
        H = np.where(corrected, (kh + 0.5) / (nh + 1.0), h_raw)
        F = np.where(corrected, (kf + 0.5) / (nf + 1.0), f_raw)
    else:
        corrected = h_ext | f_ext
        H = np.where(kh == 0, 0.5 / nh, np.where(kh == nh, 1.0 - 0.5 / nh, h_raw))
        F = np.where(kf == 0, 0.5 / nf, np.where(kf == nf, 1.0 - 0.5 / nf, f_raw))
    return H, F, corrected


def dprime(hits, n_signal, false_alarms, n_noise, correction: str = "loglinear"):
    """Sensitivity ``d′ = z(H) − z(F)`` from counts.

    ``hits``: modified motions judged incorrect, out of ``n_signal``;
    ``false_alarms``: originals judged incorrect, out of ``n_noise``.
    Negative values (modified motions judged *more* correct than the original)
    are returned as they are.

    Parameters
    ----------
    hits : int or array_like
        Modified motions judged incorrect.
    n_signal : int or array_like
        Trials of modified motions.
    false_alarms : int or array_like
        Originals judged incorrect.
    n_noise : int or array_like
        Trials of originals.
    correction : {"loglinear", "loglinear-all", "1/(2N)"}
        How rates of 0 or 1 are corrected (see :func:`rates`).

    Returns
    -------
    float or ndarray
        d′ (judged incorrect | modified against | original).

    Examples
    --------
    >>> from scipy.stats import norm
    >>> bool(np.isclose(dprime(59, 100, 28, 100), norm.ppf(.59) - norm.ppf(.28)))
    True
    """
    H, F, _ = rates(hits, n_signal, false_alarms, n_noise, correction)
    return _out(z(H) - z(F))


def criterion(hits, n_signal, false_alarms, n_noise, correction: str = "loglinear"):
    """Criterion ``c = −(z(H) + z(F)) / 2`` from counts (same correction as :func:`dprime`).

    Parameters
    ----------
    hits : int or array_like
        Modified motions judged incorrect.
    n_signal : int or array_like
        Trials of modified motions.
    false_alarms : int or array_like
        Originals judged incorrect.
    n_noise : int or array_like
        Trials of originals.
    correction : {"loglinear", "loglinear-all", "1/(2N)"}
        How rates of 0 or 1 are corrected (see :func:`rates`).

    Returns
    -------
    float or ndarray
        ``c``; positive: a bias towards answering "correct".

    Examples
    --------
    >>> from flipstudy.analysis import criterion
    >>> round(float(criterion(30, 100, 30, 100)), 4)      # H = F = 0.3: c = -z(0.3)
    0.5244
    """
    H, F, _ = rates(hits, n_signal, false_alarms, n_noise, correction)
    return _out(-(z(H) + z(F)) / 2.0)


def dprime_from_rates(H, F):
    """``z(H) − z(F)`` for rates already strictly between 0 and 1 (no correction)."""
    H, F = np.asarray(H, float), np.asarray(F, float)
    if np.any((H <= 0) | (H >= 1) | (F <= 0) | (F >= 1)):
        raise ValueError("rates of 0 or 1 need a correction: use dprime() with counts")
    return _out(z(H) - z(F))


def dprime_2afc(k_correct, n, correction: str = "loglinear"):
    """2AFC sensitivity ``d′ = √2 · z(P correct)`` from counts, and where the
    correction applied: returns ``(d′, corrected)``.

    ``"loglinear"`` corrects a proportion of 0 or 1 to ``(k + 0.5)/(n + 1)``,
    ``"loglinear-all"`` every proportion, ``"1/(2N)"`` moves 0 and 1 by ``1/(2N)``.

    Parameters
    ----------
    k_correct : int or array_like
        Correct choices.
    n : int or array_like
        Trials.
    correction : {"loglinear", "loglinear-all", "1/(2N)"}

    Returns
    -------
    dprime : ndarray
    corrected : ndarray of bool

    Examples
    --------
    >>> d, corrected = dprime_2afc(76, 100)            # 76 % correct
    >>> round(float(d), 4), bool(corrected)
    (0.9989, False)
    >>> d, corrected = dprime_2afc(20, 20)             # perfect: (20.5 / 21)
    >>> bool(np.isclose(d, np.sqrt(2) * z(20.5 / 21))), bool(corrected)
    (True, True)
    """
    c = normalise_correction(correction)
    k, n = _counts(k_correct, n)
    k, n = np.broadcast_arrays(k, n)
    ext = (k == 0) | (k == n)
    if c == "loglinear-all":
        corrected = np.ones(k.shape, bool)
        p = (k + 0.5) / (n + 1.0)
    elif c == "loglinear":
        corrected = ext
        p = np.where(ext, (k + 0.5) / (n + 1.0), k / n)
    else:
        corrected = ext
        p = np.where(k == 0, 0.5 / n, np.where(k == n, 1.0 - 0.5 / n, k / n))
    d = np.sqrt(2.0) * z(p)
    return _out(d), (bool(corrected) if np.ndim(corrected) == 0 else corrected)
