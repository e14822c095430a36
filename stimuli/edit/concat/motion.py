"""One motion as the concatenation sees it (Shum, Komura & Yadav 2009): its
angular momentum, moment arms, foot contacts, torso facing and phases, computed
once (:func:`motion_of`), turned about the vertical (:func:`transformed`), and
the rule two motions suggest (:func:`suggest_rule`).

>>> from flipstudy.stimuli import analyse, builtin
>>> from flipstudy.stimuli.edit.concat import motion_of, suggest_rule
>>> clip = builtin("backflip")
>>> m = motion_of(clip, analyse(clip).body)
>>> m.phases.main[0] < m.phases.tm < m.phases.main[1]
True
>>> suggest_rule(m, m)
'forward'
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...analyse import analyse
from ...body import Body
from ...flight import body_size, contact_mask, effector_points
from ...motion.clip import Clip
from ...physics import momentum, piece_positions
from ..reposition import rotate
from .phases import UP, Phases, align_angle, phases, yaw


@dataclass
class Motion:
    """What the concatenation needs of one motion, computed once (:func:`motion_of`).

    Attributes
    ----------
    clip : Clip
    body : Body
    L, com : ndarray, shape (F, 3)
        Angular momentum about the COM and the COM.
    arms : ndarray, shape (F, P, 3)
        Piece COM − body COM.
    foot_l, foot_r : ndarray of bool, shape (F,)
        Foot contact.
    feet_centre, facing : ndarray, shape (F, 3)
        Mid-point of the balls of the feet; unit torso facing on the ground.
    phases : Phases

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> m = motion_of(builtin("backflip"))
    >>> m.phases.main, bool(m.double_support[0]), round(m.main_peak) > 0
    ((108, 247), True, True)
    """

    clip: Clip
    body: Body
    L: np.ndarray            # (F,3)
    com: np.ndarray          # (F,3)
    arms: np.ndarray         # (F,P,3) piece COM − body COM
    foot_l: np.ndarray       # (F,) bool foot contact
    foot_r: np.ndarray
    feet_centre: np.ndarray  # (F,3) mid-point of the balls of the two feet (toe tips)
    facing: np.ndarray       # (F,3) unit torso facing direction on the ground
    phases: Phases

    @property
    def double_support(self) -> np.ndarray:
        return self.foot_l & self.foot_r

    @property
    def main_peak(self) -> float:
        a, b = self.phases.main
        return float(np.linalg.norm(self.L[a:b + 1], axis=1).max())

    @property
    def main_L(self) -> np.ndarray:
        a, b = self.phases.main
        return self.L[a:b + 1].mean(axis=0)


def _lm_index(body: Body, key: str) -> int:
    v = body.landmarks[key]
    return body.skeleton.index(v if isinstance(v, str) else v[0])


def torso_facing(clip: Clip, body: Body) -> np.ndarray:
    """(F,3) unit facing direction of the torso projected on the ground: the
    left-to-right axis of hips and shoulders, turned a quarter about the vertical.

    Parameters
    ----------
    clip : Clip
    body : Body

    Returns
    -------
    ndarray, shape (F, 3)

    Examples
    --------
    >>> from flipstudy import Body, builtin
    >>> clip = builtin("backflip")
    >>> torso_facing(clip, Body.from_clip(clip))[0].round(3)      # facing +Z
    array([0., 0., 1.])
    """
    P = clip.joint_positions()
    left = (P[:, _lm_index(body, "hip_l")] - P[:, _lm_index(body, "hip_r")]
            + P[:, _lm_index(body, "shoulder_l")] - P[:, _lm_index(body, "shoulder_r")])
    f = np.cross(left, UP)
    f[:, 1] = 0.0
    n = np.linalg.norm(f, axis=1, keepdims=True)
    return f / np.where(n > 1e-9, n, 1.0)


def foot_contacts(clip: Clip, body: Body) -> tuple[np.ndarray, np.ndarray]:
    """(F,) bool left and right foot contact (ankle or toe tip still and low, the
    flight detector's rule).

    Parameters
    ----------
    clip : Clip
    body : Body

    Returns
    -------
    left, right : ndarray of bool, shape (F,)

    Examples
    --------
    >>> from flipstudy import Body, builtin
    >>> clip = builtin("backflip")
    >>> left, right = foot_contacts(clip, Body.from_clip(clip))
    >>> bool(left[0]), bool(left[200])                           # standing, in the air
    (True, False)
    """
    size = body_size(clip) / 1.7
    C = contact_mask(clip, body, v_thr=1.0 * size, margin=0.10 * size, touch=0.03 * size)
    _, names = effector_points(clip, body)
    ix = {n: i for i, n in enumerate(names)}
    return (C[:, ix["toe_tip_l"]] | C[:, ix["ankle_l"]], C[:, ix["toe_tip_r"]] | C[:, ix["ankle_r"]])


def motion_of(clip: Clip, body: Body | None = None, *, tm: int | None = None,
              main: tuple[int, int] | None = None) -> Motion:
    """The :class:`Motion` of ``clip``: momenta, moment arms, contacts, facing and
    phases (``tm``, ``main``: see :func:`~flipstudy.stimuli.edit.concat.phases`);
    ``body`` defaults to the analyser's.

    Parameters
    ----------
    clip : Clip
    body : Body, optional
    tm : int, optional
    main : tuple of int, optional

    Returns
    -------
    Motion

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> motion_of(builtin("backflip")).phases.as_dict()["main"]
    (108, 247)
    """
    if body is None:
        body = analyse(clip).body
    m = momentum(clip, body)
    arms = piece_positions(clip, body) - m.com[:, None]
    fl, fr = foot_contacts(clip, body)
    E, names = effector_points(clip, body)
    ix = {n: i for i, n in enumerate(names)}
    centre = 0.5 * (E[:, ix["toe_tip_l"]] + E[:, ix["toe_tip_r"]])
    return Motion(clip, body, m.L, m.com, arms, fl, fr, centre, torso_facing(clip, body),
                  phases(m.L, tm, clip.fps, main=main))


def transformed(mo: Motion, theta: float, shift: np.ndarray) -> Motion:
    """Motion 2 turned by θ about the vertical through the origin, then shifted.

    Parameters
    ----------
    mo : Motion
    theta : float
        Radians.
    shift : ndarray, shape (3,)
        Metres.

    Returns
    -------
    Motion

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> m = motion_of(builtin("backflip"))
    >>> t = transformed(m, np.pi, np.zeros(3))                # half a turn: L's x flips sign
    >>> bool(np.allclose(t.L[:, 0], -m.L[:, 0], atol=1e-6))
    True
    """
    R = yaw(theta)
    turned = rotate(mo.clip, R, np.zeros(3))
    clip = turned.replace(root_pos=turned.root_pos + shift)
    F, P = mo.arms.shape[:2]
    return Motion(clip, mo.body, R.apply(np.array(mo.L)), R.apply(np.array(mo.com)) + shift,
                  R.apply(np.array(mo.arms).reshape(-1, 3)).reshape(F, P, 3), mo.foot_l, mo.foot_r,
                  R.apply(np.array(mo.feet_centre)) + shift, R.apply(np.array(mo.facing)), mo.phases)


def suggest_rule(m1: Motion, m2: Motion) -> str:
    """The rule needing the smaller turn of motion 2 about the vertical (eq. 2 for
    both rules; the torso facing test favours the smaller turn).

    Parameters
    ----------
    m1, m2 : Motion

    Returns
    -------
    str
        ``"forward"`` or ``"reverse"``.

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> m = motion_of(builtin("backflip"))
    >>> suggest_rule(m, m)
    'forward'
    """
    tf = abs(align_angle(m1.main_L, m2.main_L, "forward"))
    tr = abs(align_angle(m1.main_L, m2.main_L, "reverse"))
    return "forward" if tf <= tr else "reverse"

