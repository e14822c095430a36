"""The one psychometric function: what a calibration (:mod:`flipstudy.vocab.calibration`)
evaluates and what the analysis (:mod:`flipstudy.analysis.stats`) fits.

psignifit's cumulative-normal sigmoid with its (threshold m, width w) convention:
``w = s (Φ⁻¹(.95) − Φ⁻¹(.05))``.
"""
from __future__ import annotations

import numpy as np
from scipy.special import ndtr, ndtri

#: psignifit's width convention: w = s (Φ⁻¹(.95) − Φ⁻¹(.05)) (about 3.29 s)
WIDTH_SCALE = float(ndtri(0.95) - ndtri(0.05))


def psychometric_curve(x, threshold, width, gamma, lam):
    """``γ + (1 − γ − λ) Φ((x − m)/s)`` with psignifit's (threshold m, width w).

    Parameters
    ----------
    x : float or array_like
        Error magnitudes.
    threshold, width : float
        psignifit's threshold m and width w.
    gamma, lam : float
        Guess and lapse rates.

    Returns
    -------
    ndarray
        P(judged incorrect | x).

    Examples
    --------
    >>> from flipstudy.analysis import psychometric_curve
    >>> p = psychometric_curve([0.0, 30.0, 1e3], 30.0, 20.0, 0.2, 0.05)
    >>> [round(float(v), 3) for v in p]
    [0.2, 0.575, 0.95]
    """
    s = np.asarray(width, float) / WIDTH_SCALE
    return gamma + (1 - gamma - lam) * ndtr((np.asarray(x, float) - threshold) / s)


def detection_threshold(threshold, width, gamma, lam):
    """``x*`` where P(incorrect) = (1 + γ)/2 (vectorised; +inf where never reached).

    Parameters
    ----------
    threshold, width : float or array_like
        psignifit's threshold m and width w (``w = 3.29 s``).
    gamma, lam : float or array_like
        Guess and lapse rates.

    Returns
    -------
    float or ndarray

    Examples
    --------
    >>> from flipstudy.analysis import detection_threshold, psychometric_curve
    >>> x = detection_threshold(30.0, 20.0, 0.2, 0.0)
    >>> round(float(psychometric_curve(x, 30.0, 20.0, 0.2, 0.0)), 6)    # (1 + 0.2) / 2
    0.6
    """
    threshold, width, gamma, lam = np.broadcast_arrays(*(np.asarray(a, float)
                                                          for a in (threshold, width, gamma, lam)))
    amp = 1 - gamma - lam
    with np.errstate(divide="ignore", invalid="ignore"):
        F = (1 - gamma) / (2 * amp)
        x = threshold + width / WIDTH_SCALE * ndtri(np.clip(F, 0, 1))
    return np.where((amp > 0) & (F < 1), x, np.inf)[()]


__all__ = ["WIDTH_SCALE", "detection_threshold", "psychometric_curve"]
