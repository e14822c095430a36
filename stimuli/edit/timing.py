"""Retiming: resampling a clip at fractional source frames (Section 5.1 and 5.5).

Rotations are interpolated on the sphere (slerp, through scipy ``Rotation``:
q0 · exp(u · log(q0⁻¹ q1))), positions linearly.  Uniform retiming by a factor
n plays the motion n times faster, which scales linear and angular momentum by
n; non-uniform retiming follows a rate profile r(t) (source seconds per output
second) or the paper's frame rule ``next = last + 1/ratio(last)``.
"""

from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

from typing import Callable

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.spatial.transform import Rotation

from ..motion.clip import Clip
from ..motion import quat


def sample(clip: Clip, src: np.ndarray) -> Clip:
    """A clip whose frame k is the source clip at fractional frame ``src[k]``
    (clamped to the clip).  Same fps and ``meta`` (provenance only: the source
    frames are ``src``, clamped, and not stored in it).

    Parameters
    ----------
    clip : Clip
    src : ndarray
        Fractional source frames, one per output frame.

    Returns
    -------
    Clip

    Examples
    --------
    >>> import numpy as np
    >>> from flipstudy import builtin
    >>> clip = builtin("backflip")
    >>> half = sample(clip, np.arange(0, clip.num_frames - 1, 0.5))   # 2× slower
    >>> half.num_frames, half.fps, round(half.duration / clip.duration, 2)
    (792, 120.0, 2.0)
    """
    src = np.clip(np.asarray(src, dtype=np.float64), 0.0, clip.num_frames - 1)
    rot, root, jp = _sample_arrays(clip.rotations, clip.root_pos, clip.joint_pos, src)
    return Clip(clip.skeleton, clip.fps, root, rot, jp, dict(clip.meta))


def _sample_arrays(rotations: np.ndarray, root_pos: np.ndarray, joint_pos: np.ndarray | None,
                   src: np.ndarray):
    """The arrays of :func:`sample` at source frames ``src`` (already clamped):
    rotations (slerp), root position and joint translations (linear).  Frames that
    fall on a source frame take its quaternions as they are, so the slerp runs only
    on the fractional ones."""
    F = rotations.shape[0]
    i0 = np.floor(src).astype(np.int64)
    i0 = np.minimum(i0, F - 2) if F > 1 else i0
    i1 = np.minimum(i0 + 1, F - 1)
    u = src - i0
    rot = rotations[i0]                       # a copy: the exact source quaternions
    frac = np.flatnonzero(u != 0)
    if frac.size:
        rot[frac] = slerp(rot[frac], rotations[i1[frac]], u[frac, None])
    root = root_pos[i0] * (1 - u)[:, None] + root_pos[i1] * u[:, None]
    jp = None
    if joint_pos is not None:
        jp = joint_pos[i0] * (1 - u)[:, None, None] + joint_pos[i1] * u[:, None, None]
    return rot, root, jp


def slerp(q0: np.ndarray, q1: np.ndarray, u) -> np.ndarray:
    """Spherical interpolation of quaternions (..., 4) (scipy's x, y, z, w) by
    ``u`` (broadcastable to their leading shape; 0 gives q0, 1 gives q1):
    q0 · exp(u · log(q0⁻¹ q1)).  Stacks of more than one leading axis (frames ×
    joints) take :func:`flipstudy.stimuli.motion.quat.slerp`, the same arithmetic
    without the objects."""
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    if q0.ndim >= 3 and q1.ndim >= 3:
        return quat.slerp(q0, q1, u)
    a = Rotation.from_quat(q0)
    rel = (a.inv() * Rotation.from_quat(q1)).as_rotvec()
    return (a * Rotation.from_rotvec(rel * np.asarray(u, float)[..., None])).as_quat()


def smoothstep(x):
    """3x² − 2x³: an ease from 0 to 1 on [0, 1] with zero slope at both ends."""
    return x * x * (3.0 - 2.0 * x)


def retime(clip: Clip, factor: float) -> Clip:
    """Uniform retiming: the motion plays ``factor`` times faster (``factor`` < 1:
    slower) at the same frame rate, so velocities, p and L scale by ``factor``.

    Parameters
    ----------
    clip : Clip
    factor : float
        How many times faster.

    Returns
    -------
    Clip

    Examples
    --------
    >>> from flipstudy import builtin
    >>> clip = builtin("jump")
    >>> clip.num_frames, retime(clip, 2.0).num_frames            # twice as fast
    (377, 189)"""
    if not (np.isfinite(factor) and factor > 0):
        raise FlipstudyValueError(f"retime factor must be a positive number, got {factor!r}")
    n = int(np.floor((clip.num_frames - 1) / factor + 1e-9)) + 1
    return sample(clip, np.arange(n) * factor)


def source_times(rate: Callable[[np.ndarray], np.ndarray] | np.ndarray, duration: float,
                 fps: float, substeps: int = 16) -> np.ndarray:
    """Integrate a rate profile r(τ) (source seconds per output second) over the
    output frames 0, 1/fps, ... up to where ``duration`` source seconds are used.
    Returns source seconds per output frame (the last one may exceed nothing:
    frames stop at or before ``duration``).

    Parameters
    ----------
    rate : callable or ndarray
        r(τ) of output seconds τ, vectorised, or its values on the output frames.
    duration : float
        Source seconds to use.
    fps : float
        Output frames per second.
    substeps : int
        Integration steps per output frame.

    Returns
    -------
    ndarray
        Source seconds, one per output frame.

    Examples
    --------
    >>> import numpy as np
    >>> t = source_times(lambda tau: np.full_like(tau, 0.5), 1.0, 10.0)   # half speed
    >>> t[:4], len(t)
    (array([0.  , 0.05, 0.1 , 0.15]), 21)"""
    dt = 1.0 / fps / substeps
    if callable(rate):
        # integrate on a fine grid (trapezoid) until the source duration is reached
        n = int(np.ceil(duration * fps * 4 + 8)) * substeps
        tau = np.arange(n + 1) * dt
        r = np.asarray(rate(tau), dtype=float)
        if np.any(r <= 0):
            raise ValueError("retiming rate must stay positive")
        s = cumulative_trapezoid(r, dx=dt, initial=0.0)
        frames = s[::substeps]
    else:
        frames = np.asarray(rate, dtype=float)
    return frames[frames <= duration + 1e-9]


def ratio_retime_frames(ratio: Callable[[float], float], start: float, stop: float,
                        max_frames: int = 100000, midpoint: bool = False) -> np.ndarray:
    """The paper's rule (Section 5.5): ``next = last + 1/ratio(last)`` from
    ``start`` while below ``stop``; returns the fractional source frames.
    ``midpoint=True`` takes the step with the ratio half a step ahead,
    ``next = last + 1/ratio(last + ½/ratio(last))`` (second order: it follows a
    ratio that changes within a step, e.g. while an edit blends in).

    The rule is sequential by nature (each step depends on the previous one), so
    this is a scalar loop over output frames; ``ratio`` is evaluated once (twice
    with ``midpoint``) per step.

    Parameters
    ----------
    ratio : callable
        ratio(f) of the source frame f.
    start, stop : float
        Source frames.
    max_frames : int
        A bound on the output frames.
    midpoint : bool
        The second-order step.

    Returns
    -------
    ndarray
        Fractional source frames.

    Examples
    --------
    >>> ratio_retime_frames(lambda f: 2.0, 0.0, 3.0)
    array([0. , 0.5, 1. , 1.5, 2. , 2.5, 3. ])"""
    out = [float(start)]
    f = float(start)
    while True:
        r = float(ratio(f))
        if midpoint and np.isfinite(r) and r > 0:
            r = float(ratio(f + 0.5 / r))
        if not (np.isfinite(r) and r > 0):
            raise ValueError(f"ratio at frame {f:.2f} must be positive, got {r!r}")
        f = f + 1.0 / r
        if f > stop + 1e-9 or len(out) >= max_frames:
            break
        out.append(f)
    return np.array(out)
