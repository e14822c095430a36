"""The blendable periods of two motions (Shum, Komura & Yadav 2009; step 3 of
:mod:`flipstudy.stimuli.edit.concat`): the halves of their phases the rule
pairs, truncated to the frames where the feet support the body.

>>> from flipstudy.stimuli import analyse, builtin
>>> from flipstudy.stimuli.edit.concat import blendable_periods, motion_of
>>> clip = builtin("backflip")
>>> m = motion_of(clip, analyse(clip).body)
>>> [case for case, _, _ in blendable_periods(m, m, "forward")]
['latter half of main 1 + initial half of main 2']
"""
from __future__ import annotations

import numpy as np

from .motion import Motion
from flipstudy.errors import ConcatError


def _half(mo: Motion, r, which: str) -> np.ndarray:
    """The initial or latter half of phase ``r`` = (a, b), split where its |L| is
    largest (for the main phase: t_m) — the dotted lines of the paper's Figure 2."""
    a, b = r
    if r == mo.phases.main:
        mid = mo.phases.tm
    else:
        mid = a + int(np.argmax(np.linalg.norm(mo.L[a:b + 1], axis=1)))
    return np.arange(mid, b + 1) if which == "latter" else np.arange(a, mid + 1)


def blendable_periods(m1: Motion, m2: Motion, rule: str) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The candidate (case, frames of motion 1, frames of motion 2) of the rule,
    before the support truncation (the halves the paper lists).

    Parameters
    ----------
    m1, m2 : Motion
        The two motions (:func:`~flipstudy.stimuli.edit.concat.motion_of`).
    rule : {"forward", "reverse"}

    Returns
    -------
    list of (str, ndarray, ndarray)
        Raises :class:`~flipstudy.errors.ConcatError` when the reverse rule finds
        no phase to blend.

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import motion_of
    >>> m = motion_of(builtin("backflip"))
    >>> (case, f1, f2), = blendable_periods(m, m, "forward")
    >>> case, (int(f1[0]), int(f1[-1])), (int(f2[0]), int(f2[-1]))   # t_m = 234
    ('latter half of main 1 + initial half of main 2', (234, 247), (108, 234))
    """
    p1, p2 = m1.phases, m2.phases
    if rule == "forward":
        return [("latter half of main 1 + initial half of main 2",
                 _half(m1, p1.main, "latter"), _half(m2, p2.main, "initial"))]
    out = []
    if p2.prep is not None:
        out.append(("latter half of main 1 + latter half of preparatory 2",
                    _half(m1, p1.main, "latter"), _half(m2, p2.prep, "latter")))
    if p1.post is not None:
        out.append(("initial half of posterior 1 + initial half of main 2",
                    _half(m1, p1.post, "initial"), _half(m2, p2.main, "initial")))
    if not out:
        raise ConcatError("reverse rule: motion 1 has no posterior phase and motion 2 no preparatory "
                          "phase, so there is nothing to blend (try --rule forward)")
    return out


def support_frames(m1: Motion, m2: Motion, f1: np.ndarray, f2: np.ndarray):
    """The frames of ``f1`` (motion 1's period) and ``f2`` (motion 2's) in double
    support, and which support it is (a phrase for the report); when that leaves
    either period empty, the frames where one and the same foot supports in both
    motions.  Raises :class:`ConcatError` when no foot supports both.

    Parameters
    ----------
    m1, m2 : Motion
    f1, f2 : ndarray of int
        The blendable frames of each motion (:func:`blendable_periods`).

    Returns
    -------
    s1, s2 : ndarray of int
        The frames kept of each period.
    support : str

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import motion_of
    >>> m = motion_of(builtin("backflip"))
    >>> (_, f1, f2), = blendable_periods(m, m, "forward")
    >>> s1, s2, support = support_frames(m, m, f1, f2)
    >>> support, int(s1[0]), int(s2[-1])        # the take-off frames of the main phase
    ('double support', 237, 159)
    """
    d1, d2 = f1[m1.double_support[f1]], f2[m2.double_support[f2]]
    if d1.size and d2.size:
        return d1, d2, "double support"
    best = None
    for side in ("l", "r"):
        c1 = getattr(m1, f"foot_{side}")
        c2 = getattr(m2, f"foot_{side}")
        s1, s2 = f1[c1[f1]], f2[c2[f2]]
        if s1.size and s2.size and (best is None or s1.size + s2.size > best[0].size + best[1].size):
            best = (s1, s2, f"single support on the {'left' if side == 'l' else 'right'} foot "
                            f"(no double support in the blendable period)")
    if best is None:
        raise ConcatError("the blendable periods have no frame where a foot supports the body in both "
                          "motions (the paper blends only in support)")
    return best

