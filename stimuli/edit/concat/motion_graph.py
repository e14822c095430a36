"""The motion-graph baseline (Kovar, Gleicher & Pighin 2002) that Shum, Komura &
Yadav compare against (step 7 of :mod:`flipstudy.stimuli.edit.concat`): the two
motions joined at their most similar poses, by the point-cloud distance over a
window minimised over a turn about the vertical and a ground translation in
closed form, blended with a cubic ease."""
from __future__ import annotations

import numpy as np

from ...analyse import analyse
from ...body import Body
from ...motion.clip import Clip, derived_meta
from ..reposition import rotate
from ..timing import sample, slerp
from .motion import Motion, motion_of
from flipstudy.errors import ConcatError
from .phases import yaw
from .result import Concatenation, MotionGraphReport


def _cloud(P: np.ndarray, start: np.ndarray, k: int):
    """Windows of k frames of joint positions P (F,J,3) starting at ``start`` (n,):
    horizontal points as complex numbers z + i·x, centred; heights; weights equal."""
    idx = start[:, None] + np.arange(k)[None]
    W = P[idx].reshape(start.size, -1, 3)                 # (n, k·J, 3)
    c = W[..., 2] + 1j * W[..., 0]
    mean = c.mean(axis=1, keepdims=True)
    return c - mean, mean[:, 0], W[..., 1]


def point_cloud_distance(P1: np.ndarray, P2: np.ndarray, s1: np.ndarray, s2: np.ndarray, k: int):
    """Kovar et al.'s distance between the windows of P1 starting at ``s1`` and of
    P2 at ``s2``, all pairs: Σ‖p − T_{θ,x0,z0} p'‖² minimised over a rotation θ
    about the vertical and a ground translation, in closed form (a rotation about
    Y is a multiplication of z + i·x by e^{iθ}).  Returns D (n1,n2), θ (n1,n2)
    and the window means (for the translation).

    Parameters
    ----------
    P1, P2 : ndarray, shape (F, J, 3)
        Joint positions.
    s1, s2 : ndarray of int, shape (n1,) and (n2,)
        First frames of the windows.
    k : int
        Frames per window.

    Returns
    -------
    D, theta : ndarray, shape (n1, n2)
    mean1, mean2 : ndarray of complex

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> P = builtin("backflip").joint_positions()
    >>> D, theta, _, _ = point_cloud_distance(P, P, np.array([0, 100]), np.array([0, 100]), 10)
    >>> bool(D[0, 0] < 1e-9), bool(D[0, 1] > 1.0), bool(np.allclose(D, D.T))
    (True, True, True)
    """
    a, ma, ya = _cloud(P1, s1, k)
    b, mb, yb = _cloud(P2, s2, k)
    cross = a @ np.conj(b).T                              # Σ a·conj(b) for every pair
    D = (np.sum(np.abs(a) ** 2, 1)[:, None] + np.sum(np.abs(b) ** 2, 1)[None]
         - 2 * np.abs(cross)
         + np.sum(ya ** 2, 1)[:, None] + np.sum(yb ** 2, 1)[None] - 2 * ya @ yb.T)
    theta = np.angle(cross)
    return np.maximum(D, 0.0), theta, ma, mb


def motion_graph_join(a: Clip, b: Clip, *, body: Body | None = None, window_s: float = 1 / 3,
                      m1: Motion | None = None, m2: Motion | None = None) -> Concatenation:
    """The motion-graph criterion the paper compares against (its Figures 1, 7, 8):
    a transition from ``a`` to ``b`` at the most similar poses (Kovar et al.'s
    point-cloud distance over a ``window_s`` window), taken after ``a``'s main
    phase has ended and before ``b``'s begins, so both motions are performed in
    full; ``b`` is aligned by the optimal rotation about the vertical and ground
    translation and the window is blended with Kovar's cubic ease.  Returns a
    :class:`~flipstudy.stimuli.edit.concat.Concatenation` (no flight detected:
    ``takeoff`` and ``landing`` are ``None``) with a :class:`MotionGraphReport`.

    Parameters
    ----------
    a, b : Clip
    body : Body, optional
    window_s : float
        Seconds of the compared windows.
    m1, m2 : Motion, optional
        The motions, when already made.

    Returns
    -------
    Concatenation

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import motion_graph_join
    >>> c = builtin("backflip")
    >>> g = motion_graph_join(c, c)
    >>> g.report.transition_a > g.report.transition_b, g.clip.num_frames > c.num_frames
    (True, True)
    """
    if a.skeleton.joint_names != b.skeleton.joint_names:
        raise ConcatError("the two motions must share a skeleton")
    if abs(a.fps - b.fps) > 1e-9:
        b = sample(b, np.arange(0, b.num_frames - 1 + 1e-9, b.fps / a.fps)).with_fps(a.fps)
    body = body if body is not None else analyse(a).body
    m1 = m1 or motion_of(a, body)
    m2 = m2 or motion_of(b, body)
    k = max(2, int(round(window_s * a.fps)))
    i0 = m1.phases.main[1] + 1
    j1 = m2.phases.main[0] - k
    s1 = np.arange(min(i0, a.num_frames - k), a.num_frames - k + 1)
    s2 = np.arange(0, max(j1, 0) + 1)
    P1, P2 = a.joint_positions(), b.joint_positions()
    D, th, ma, mb = point_cloud_distance(P1, P2, s1, s2, k)
    ii, jj = np.unravel_index(int(np.argmin(D)), D.shape)
    i, j = int(s1[ii]), int(s2[jj])
    theta = float(th[ii, jj])
    # rotation about Y by θ multiplies z + i·x by e^{iθ}; then the means coincide
    R = yaw(theta)
    mb_rot = mb[jj] * np.exp(1j * theta)
    d = ma[ii] - mb_rot
    shift = np.array([d.imag, 0.0, d.real])
    b2 = rotate(b, R, np.zeros(3))
    b2 = b2.replace(root_pos=b2.root_pos + shift)
    p = (np.arange(k) + 1) / k
    alpha = 2 * p ** 3 - 3 * p ** 2 + 1                    # 1 → 0 (Kovar et al. 2002)
    q = slerp(a.rotations[i:i + k], b2.rotations[j:j + k], (1 - alpha)[:, None])
    root = alpha[:, None] * a.root_pos[i:i + k] + (1 - alpha)[:, None] * b2.root_pos[j:j + k]
    rot = np.concatenate([a.rotations[:i], q, b2.rotations[j + k:]])
    pos = np.concatenate([a.root_pos[:i], root, b2.root_pos[j + k:]])
    out = Clip(a.skeleton, a.fps, pos, rot, None, derived_meta(a.meta, "motion-graph join"))
    return Concatenation(out, None, None, MotionGraphReport(transition_a=i, transition_b=j, window=k,
                                                distance=float(D[ii, jj]), theta_deg=float(np.degrees(theta)),
                                                frames=out.num_frames, duration_s=out.duration))

