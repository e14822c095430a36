"""Phases of a motion from its angular momentum, and eq. 2's alignment about the
vertical (Shum, Komura & Yadav 2009, steps 1 and 2 of
:mod:`flipstudy.stimuli.edit.concat`).

>>> import numpy as np
>>> from flipstudy.stimuli.edit.concat import align_angle, phases
>>> L = np.zeros((10, 3)); L[2:8, 0] = 1.0; L[:2, 0] = L[8:, 0] = -1.0
>>> p = phases(L, tm=4)
>>> p.prep, p.main, p.post
((0, 1), (2, 7), (8, 9))
>>> round(float(np.degrees(align_angle([1, 0, 0], [0, 0, 1]))), 6)
90.0
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from flipstudy.errors import ConcatError

UP = np.array([0.0, 1.0, 0.0])


@dataclass
class Phases:
    """Frame ranges (inclusive; ``None`` when the phase is absent) of a motion's
    preparatory, main and posterior phases, and the frame t_m they grew from.

    Attributes
    ----------
    tm : int
        The frame the main phase grew from (largest |L|, or given).
    prep, main, post : tuple of int or None
        First and last frame of each phase.

    Examples
    --------
    >>> p = Phases(tm=4, prep=(0, 1), main=(2, 7), post=None)
    >>> p.as_dict()
    {'tm': 4, 'preparatory': (0, 1), 'main': (2, 7), 'posterior': None}
    """

    tm: int
    prep: tuple[int, int] | None
    main: tuple[int, int]
    post: tuple[int, int] | None

    def as_dict(self) -> dict:
        return {"tm": self.tm, "preparatory": self.prep, "main": self.main, "posterior": self.post}


def phases(L: np.ndarray, tm: int | None = None, fps: float = 120.0, *,
           main: tuple[int, int] | None = None, smooth_s: float = 0.1) -> Phases:
    """Preparatory / main / posterior phases from the sign of L(t)·L(t_m).

    ``tm`` defaults to the frame of largest |L| (after a moving average over
    ``smooth_s`` seconds, so one noisy frame does not decide it).  From t_m the
    main phase extends backwards and forwards while L(t)·L(t_m) ≥ 0 (the paper's
    rule, Section "Typical Angular Momentum Trajectories").  ``main=(a, b)``
    overrides the borders (the paper lets the user fine-tune them).

    Parameters
    ----------
    L : ndarray, shape (F, 3)
        Angular momentum per frame.
    tm : int, optional
    fps : float
    main : tuple of int, optional
    smooth_s : float
        Seconds of the moving average.

    Returns
    -------
    Phases

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import motion_of
    >>> phases(motion_of(builtin("backflip")).L, fps=120.0).as_dict()["tm"]
    234
    """
    L = np.asarray(L, float)
    F = L.shape[0]
    n = np.linalg.norm(L, axis=1)
    if tm is None:
        w = max(1, int(round(smooth_s * fps)))
        ns = np.convolve(n, np.ones(w) / w, mode="same")
        tm = int(np.argmax(ns))
    if not 0 <= tm < F:
        raise ConcatError(f"t_m = {tm} is outside the motion's frames 0–{F - 1}")
    if main is None:
        s = L @ L[tm]
        neg = s < 0
        before = np.flatnonzero(neg[:tm])
        after = np.flatnonzero(neg[tm + 1:])
        a = int(before[-1]) + 1 if before.size else 0
        b = tm + int(after[0]) if after.size else F - 1
    else:
        a, b = int(main[0]), int(main[1])
        if not 0 <= a <= b < F:
            raise ConcatError(f"main phase {a}:{b} must lie within frames 0–{F - 1} with start ≤ end")
    return Phases(tm=tm, prep=(0, a - 1) if a > 0 else None, main=(a, b),
                  post=(b + 1, F - 1) if b < F - 1 else None)


def align_angle(L1: np.ndarray, L2: np.ndarray, rule: str = "forward") -> float:
    """Eq. 2 in closed form: the angle θ (radians) about the vertical that
    maximises (forward) or minimises (reverse) L̄₁·R_y(θ)L̄₂.

    With R_y(θ) taking (x, z) to (x cos θ + z sin θ, −x sin θ + z cos θ), the
    dot product is A cos θ + B sin θ + C with A = x₁x₂ + z₁z₂, B = x₁z₂ − z₁x₂,
    C = y₁y₂, so the maximum is at atan2(B, A) and the minimum half a turn away.

    Parameters
    ----------
    L1, L2 : ndarray, shape (3,)
        The two motions' main-phase angular momenta.
    rule : {"forward", "reverse"}

    Returns
    -------
    float
        Radians.

    Examples
    --------
    >>> L1, L2 = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    >>> round(align_angle(L1, L2), 6), round(align_angle(L1, L2, "reverse"), 6)
    (1.570796, -1.570796)
    """
    a, b = np.asarray(L1, float), np.asarray(L2, float)
    A = a[0] * b[0] + a[2] * b[2]
    B = a[0] * b[2] - a[2] * b[0]
    th = float(np.arctan2(B, A))
    if rule == "reverse":
        th = th + np.pi
    elif rule != "forward":
        raise ConcatError(f"rule must be 'forward' or 'reverse', got {rule!r}")
    return float((th + np.pi) % (2 * np.pi) - np.pi)


def yaw(theta: float) -> Rotation:
    """R_y(θ): rotation by θ about the vertical (Y) axis.

    Parameters
    ----------
    theta : float
        Radians.

    Returns
    -------
    scipy.spatial.transform.Rotation

    Examples
    --------
    >>> yaw(np.pi / 2).apply([1.0, 0.0, 0.0]).round(6)
    array([ 0.,  0., -1.])
    """
    return Rotation.from_rotvec([0.0, float(theta), 0.0])

