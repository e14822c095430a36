"""Blending and angular-momentum smoothing (Shum, Komura & Yadav 2009, eqs. 8
and 9; step 5 of :mod:`flipstudy.stimuli.edit.concat`): the per-joint slerp
over the blend window, the smoothing factor s, and the window retimed so its
|L| has eq. 9's mean.

>>> import numpy as np
>>> from flipstudy.stimuli.edit.concat import smoothing_factor
>>> L = np.array([10.0, 30.0, 50.0, 30.0, 10.0])
>>> smoothing_factor(L, 0, 4)                 # ½(10 + 10) / mean 26
0.38461538461538464
"""
from __future__ import annotations

import numpy as np

from ...body import Body
from ...motion.clip import Clip, derived_meta
from ...physics import momentum
from ..timing import ratio_retime_frames, sample, slerp, smoothstep
from flipstudy.errors import ConcatError


def blend(c1: Clip, c2: Clip, T: int, f0: int, f1: int, ease: bool = True) -> Clip:
    """Eq. 8: motion 1 up to f0, the blend over [f0, f1] (α from 1 to 0, motion
    2's frame f − T), then motion 2.  ``c2`` is already aligned.  The paper's α
    falls linearly; with ``ease`` it falls as 1 − (3x² − 2x³), which has the same
    ends and mean but no kink, so joint velocities do not jump where the window
    begins and ends.

    Parameters
    ----------
    c1, c2 : Clip
    T : int
        Motion 2's frame offset.
    f0, f1 : int
        The blend window, frames of motion 1.
    ease : bool

    Returns
    -------
    Clip

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> c = builtin("jump")
    >>> out = blend(c, c, 100, 150, 160)
    >>> out.num_frames == 100 + c.num_frames
    True
    """
    F2 = c2.num_frames
    f = np.arange(f0, f1 + 1)
    x = (f - f0) / max(f1 - f0, 1)
    alpha = 1.0 - (smoothstep(x) if ease else x)
    q = slerp(c1.rotations[f], c2.rotations[f - T], (1.0 - alpha)[:, None])
    root = alpha[:, None] * c1.root_pos[f] + (1 - alpha)[:, None] * c2.root_pos[f - T]
    rot = np.concatenate([c1.rotations[:f0], q, c2.rotations[f1 - T + 1:F2]])
    pos = np.concatenate([c1.root_pos[:f0], root, c2.root_pos[f1 - T + 1:F2]])
    if rot.shape[0] != f1 + 1 + (F2 - (f1 - T + 1)):
        raise AssertionError("blend: frame bookkeeping")
    return Clip(c1.skeleton, c1.fps, pos, rot, None, derived_meta(c1.meta, "concatenated"))


def smoothing_factor(Ln: np.ndarray, f0: int, f1: int, ends: tuple[float, float] | None = None) -> float:
    """Eq. 9: s = ½(|L(f_t0)| + |L(f_t1)|) / mean of |L| over [f_t0, f_t1].

    The paper divides the sum over the f_t1 − f_t0 + 1 frames of the window by
    f_t1 − f_t0; we take the mean over its frames, so that after playing the
    window at rate s its mean |L| is the stated one, the mean of its two ends
    (on a window of 5 frames the printed divisor would leave it 20 % low).

    ``ends`` gives |L| at the two ends; by default they are read off ``Ln``.  The
    concatenation passes the source motions' own values there (motion 1 at f_t0,
    motion 2 at f_t1 − T): a finite difference at a window end straddles the blend
    and would carry its fast movement into the target.

    Parameters
    ----------
    Ln : ndarray, shape (F,)
        |L| per frame.
    f0, f1 : int
        The window's first and last frame.
    ends : tuple of float, optional

    Returns
    -------
    float

    Examples
    --------
    >>> smoothing_factor(np.array([1.0, 2.0, 3.0]), 0, 2)      # ½(1 + 3) / 2
    1.0
    """
    mean = float(np.mean(Ln[f0:f1 + 1]))
    if mean <= 0:
        return 1.0
    e0, e1 = (Ln[f0], Ln[f1]) if ends is None else ends
    return float(0.5 * (e0 + e1) / mean)


def smooth(blended: Clip, body: Body, window: tuple[int, int], L: np.ndarray,
           ends: tuple[float, float], mode: str = "profile", passes: int = 5,
           tol: float = 0.01) -> tuple[Clip, int, dict | None]:
    """Eq. 9 applied to the blend window ``(f0, f1)`` of ``blended`` (whose |L| per
    frame is ``L``; ``ends``: |L| at the window's ends, see :func:`smoothing_factor`).

    ``mode="uniform"``: the paper as printed, the whole window played at rate s;
    ``"profile"``: eq. 9's mean reached without a jump in speed at the window's
    ends (measured again and corrected, up to ``passes`` times, until the rate is
    within ``tol`` of 1); ``"none"``.  Returns the clip, the window's last frame
    in it and what was applied (``None``: nothing).

    Parameters
    ----------
    blended : Clip
    body : Body
    window : tuple of int
    L : ndarray, shape (F,)
    ends : tuple of float
    mode : {"profile", "uniform", "none"}
    passes : int
    tol : float

    Returns
    -------
    clip : Clip
    last : int
    applied : dict or None

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import motion_of
    >>> m = motion_of(builtin("backflip"))
    >>> Ln = np.linalg.norm(m.L, axis=1)
    >>> out, last, applied = smooth(m.clip, m.body, (200, 220), Ln, (Ln[200], Ln[220]), mode="uniform")
    >>> out.num_frames, last, applied["mode"]
    (397, 220, 'uniform')
    """
    if mode not in ("uniform", "profile", "none"):
        raise ConcatError(f"smoothing must be 'profile', 'uniform' or 'none', got {mode!r}")
    f0, f1 = window
    s = smoothing_factor(L, f0, f1, ends)
    out = blended
    w0, w1 = f0, f1
    applied = None
    if mode == "uniform" and abs(s - 1.0) > 1e-6:
        # the paper as printed: the whole window played at rate s
        steps = max(1, int(round((f1 - f0) / s)))
        src = np.concatenate([np.arange(f0, dtype=float), np.linspace(f0, f1, steps + 1),
                              np.arange(f1 + 1, blended.num_frames, dtype=float)])
        out = sample(blended, src)
        w1 = f0 + steps
        applied = {"mode": "uniform", "rate": (f1 - f0) / steps}
    elif mode == "profile" and f1 - f0 >= 2:
        # eq. 9's mean reached without a jump in speed at the window's ends: the
        # window is retimed by the rule next = last + 1/ratio(last) (Majkowska &
        # Faloutsos 5.5) with ratio = |L| / the straight line between the ends,
        # so |L| follows that line (its mean is eq. 9's ½(|L(f_t0)| + |L(f_t1)|));
        # measured again and corrected, up to ``passes`` times
        Lw = L
        ratios = []
        ease_frames = 2.0
        for _ in range(passes):
            fr = np.arange(w0, w1 + 1, dtype=float)
            line = np.interp(fr, [w0, w1], ends)
            ratio = np.clip(Lw[w0:w1 + 1] / np.maximum(line, 1e-6), 0.05, 20.0)
            # the rate eases back to 1 towards both ends, so the speed does not
            # jump where the window meets the motions
            x = np.minimum(np.arange(ratio.size), np.arange(ratio.size)[::-1]) / ease_frames
            x = np.clip(x, 0.0, 1.0)
            ratio = 1.0 + (ratio - 1.0) * smoothstep(x)
            ratios.append((float(ratio.min()), float(ratio.max())))
            if np.all(np.abs(ratio - 1.0) < tol):
                break
            src2 = ratio_retime_frames(lambda x: float(np.interp(x, fr, ratio)), float(w0), float(w1),
                                       midpoint=True)
            tail = np.arange(src2[-1] + 1.0, out.num_frames - 1 + 1e-9, 1.0)
            out = sample(out, np.concatenate([np.arange(w0, dtype=float), src2, tail]))
            w1 = w0 + src2.size - 1
            Lw = np.linalg.norm(momentum(out, body).L, axis=1)
        applied = {"mode": "profile", "rate": (f1 - f0) / max(w1 - w0, 1), "passes": ratios}
    return out, w1, applied
