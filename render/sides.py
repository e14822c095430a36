"""Sided colours: which side of the body each joint is on (from its name), and
three tones of one colour — trunk, left lighter, right darker in CIE L* — that
stay apart in colour and in grey scale (:func:`side_tones`).  CIELAB
conversions and ΔE (CIE76) in numpy.

>>> from flipstudy.stimuli.motion import Skeleton
>>> [joint_side(n) for n in ("LeftUpLeg", "RHipJoint", "lhip", "Spine")]
[1, 2, 1, 0]
>>> t = side_tones("#3d6a9e")
>>> bool(delta_e(rgb_to_lab(t[1]), rgb_to_lab(t[2])) >= 15)
True
"""
from __future__ import annotations

import re
import warnings

import numpy as np

TRUNK, LEFT, RIGHT = 0, 1, 2

_BODY_WORDS = ("hip", "knee", "ankle", "foot", "toe", "shoulder", "elbow", "wrist", "hand", "arm",
               "leg", "collar", "clavicle", "thigh", "shin", "calf", "up", "low", "fore", "finger",
               "thumb", "index", "eye", "ear", "heel", "ball", "femur", "tibia", "humerus")


def joint_side(name: str) -> int:
    """0 (no side), 1 (left) or 2 (right) from a joint's name.

    Examples
    --------
    >>> [joint_side(n) for n in ("LeftUpLeg", "RHipJoint", "lhip", "mixamorig:RightArm",
    ...                          "thigh_l", "Hips", "LowerBack", "Neck")]
    [1, 2, 1, 2, 1, 0, 0, 0]
    """
    n = str(name).split(":")[-1].split("|")[-1]
    low = n.lower()
    for side, word, letter in ((LEFT, "left", "l"), (RIGHT, "right", "r")):
        if low.startswith(word) or low.endswith(word) or re.search(rf"[_.\s-]{word}", low):
            return side
        if re.match(rf"{letter.upper()}[A-Z_]", n) and not re.match(r"LowerBack|Low", n):
            return side
        if low[:1] == letter and any(low[1:].lstrip("_").startswith(w) for w in _BODY_WORDS):
            return side
        if re.search(rf"[_.\s-]{letter}\d*$", low) or re.search(rf"[_.\s-]{letter}[_.\s-]", low):
            return side
    return TRUNK


_WARNED: set = set()


def joint_sides(skeleton) -> np.ndarray:
    """(J,) side of every joint (see :func:`joint_side`); a skeleton without
    any left and right names is all trunk, and a warning says so (once per
    skeleton)."""
    s = np.array([joint_side(n) for n in skeleton.joint_names], dtype=np.int8)
    if not (np.any(s == LEFT) and np.any(s == RIGHT)):
        key = tuple(skeleton.joint_names)
        if key not in _WARNED:
            _WARNED.add(key)
            warnings.warn("render: the skeleton's joint names say no left and right "
                          f"({', '.join(skeleton.joint_names[:4])}, …); the body is drawn "
                          "in one colour", stacklevel=3)
        s[:] = TRUNK
    return s


# ------------------------------------------------------------------ colours
def _srgb_to_linear(c):
    c = np.asarray(c, float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _linear_to_srgb(c):
    c = np.clip(np.asarray(c, float), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


_M = np.array([[0.4124564, 0.3575761, 0.1804375],
               [0.2126729, 0.7151522, 0.0721750],
               [0.0193339, 0.1191920, 0.9503041]])
_WHITE = _M.sum(axis=1)


def rgb_to_lab(rgb) -> np.ndarray:
    """CIELAB (D65) of sRGB colours in 0..1 (…,3).

    >>> rgb_to_lab([1.0, 1.0, 1.0]).round(1).tolist()
    [100.0, 0.0, 0.0]
    """
    xyz = _srgb_to_linear(rgb) @ _M.T / _WHITE
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]),
                     200 * (f[..., 1] - f[..., 2])], axis=-1)


def lab_to_rgb(lab) -> np.ndarray:
    """sRGB in 0..1 of CIELAB colours (clipped to the gamut)."""
    lab = np.asarray(lab, float)
    fy = (lab[..., 0] + 16) / 116
    f = np.stack([fy + lab[..., 1] / 500, fy, fy - lab[..., 2] / 200], axis=-1)
    xyz = np.where(f > 6 / 29, f ** 3, 3 * (6 / 29) ** 2 * (f - 4 / 29)) * _WHITE
    return _linear_to_srgb(xyz @ np.linalg.inv(_M).T)


def delta_e(a, b) -> np.ndarray:
    """CIE76 colour difference ΔE*ab of sRGB colours in 0..1."""
    return np.linalg.norm(rgb_to_lab(a) - rgb_to_lab(b), axis=-1)


def side_tones(color, lightness: float = 20.0) -> np.ndarray:
    """(3,3) sRGB 0..1 tones of ``color`` for trunk, left and right: the trunk
    the colour itself, left ``lightness`` CIE L* lighter and right as much
    darker (both moved together to stay within 0..100).

    Examples
    --------
    >>> t = side_tones("#3d6a9e")
    >>> bool(delta_e(t[1], t[2]) >= 15), bool(rgb_to_lab(t[1])[0] > rgb_to_lab(t[2])[0])
    (True, True)
    """
    from .style import rgb
    lab = rgb_to_lab(np.asarray(rgb(color)))
    d = float(lightness)
    shift = min(0.0, 100.0 - (lab[0] + d)) + max(0.0, 2.0 - (lab[0] - d))
    tones = np.array([lab, lab + [d + shift, 0, 0], lab + [-d + shift, 0, 0]])
    if shift:
        tones[0, 0] = np.clip(lab[0] + shift, 0, 100)
    return lab_to_rgb(tones)
