"""Muscles as linear springs across the hips, knees and ankles (Ooi 2016, 3.2.3).

A muscle crosses one joint; the bones on either side are square prisms of
width ``r`` and the muscle a spring between them (Figure 3.3).  With θ the
angle *between the bones* (π for a straight knee — not the joint angle a
rig stores, which is 0 there: the thesis names that bug in 5.5), the law of
sines gives the spring's displacement, and Hooke's law its force and energy:

    s = r · sin(π − θ) / sin(θ / 2)        (= 2 r cos(θ/2))
    F = k · s,    E = ½ · k · s²

Table 3.3 of the thesis tabulates these for a knee with r = 0.05 m.

Joints that rest bent (the ankle, whose foot points forward) use the angle
relative to rest: the muscle sees θ_eff = π − (θ_rest − θ), stretched only
when the joint flexes past rest (dorsiflexion for the calf).  The hip muscle
runs from the pelvis (its upward axis) over the hip to the knee, so a
standing hip is straight (θ = π) like the knee.

Spring constants are per muscle in the order of Table 5.1: left hip, left
knee, left ankle, right hip, right knee, right ankle; its five trials are the
presets.
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

import numpy as np

#: the Table 5.1 constants are multiplied by this (see :func:`~flipstudy.stimuli.control.controller.jump`).  With the
#: angle between the bones (the corrected θ) the thesis's k = 20000 stores at
#: most 190 J in a balanced crouch of a 70 kg, 1.75 m jumper, less than any of
#: its 1–2 m jumps needs (a 1 m jump: 262 J); its jumps worked with the flawed
#: angle, which stretches the springs most when the legs are straight.  3 is the
#: smallest round factor with which every scene of Chapter 5 can be reached
#: (1.9 m forward, the 0.75 m box, the jump-over); the longest standing jump of
#: "global-normal" is then 2.2 m (t_air 0.5 s), near the thesis's calibration of
#: "normal" (a maximum of 1.5–2 m, 1.9 m "highly athletic").
STRENGTH = 3.0

#: muscle order (Table 5.1's columns)
MUSCLES = ("hip_l", "knee_l", "ankle_l", "hip_r", "knee_r", "ankle_r")
#: Table 5.1 — spring constants (kg/s²) of the thesis's trials
PRESETS = {
    "global-normal": (20000, 20000, 20000, 20000, 20000, 20000),
    "varying-normal": (20000, 24000, 16000, 20000, 24000, 16000),
    "uneven-global-normal": (16000, 16000, 16000, 24000, 24000, 24000),
    "uneven-varying-normal": (24000, 28000, 20000, 16000, 20000, 12000),
    "global-super": (1e10, 1e10, 1e10, 1e10, 1e10, 1e10),
}
#: bone width of the thesis (m)
BONE_WIDTH = 0.05


def spring_displacement(theta, r: float = BONE_WIDTH) -> np.ndarray:
    """s = r sin(π − θ) / sin(θ/2) for θ (radians) in (0, π], the angle between the bones.

    Parameters
    ----------
    theta : float or ndarray
        Radians.
    r : float
        The spring's attachment radius, metres.

    Returns
    -------
    ndarray
        Metres.

    Examples
    --------
    >>> float(spring_displacement(np.pi)), float(spring_displacement(np.pi / 2).round(4))   # straight: none
    (0.0, 0.0707)
    """
    th = np.asarray(theta, dtype=float)
    if np.any(~np.isfinite(th)) or np.any(th <= 0) or np.any(th > np.pi + 1e-9):
        raise FlipstudyValueError("theta: the angle between the bones must be in (0, π] radians "
                         "(π = straight); got values outside")
    return r * np.sin(np.pi - th) / np.sin(th / 2.0)


def spring_force(k, s) -> np.ndarray:
    """|F| = k s (N): Hooke's law, the restoring force's magnitude.

    Parameters
    ----------
    k : float or ndarray
        Spring constants.
    s : float or ndarray
        Displacements, metres.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> float(spring_force(100.0, 0.1))
    10.0
    """
    return np.asarray(k, float) * np.asarray(s, float)


def spring_energy(k, s) -> np.ndarray:
    """E = ½ k s² (J).

    Parameters
    ----------
    k : float or ndarray
        Spring constants.
    s : float or ndarray
        Displacements, metres.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> round(float(spring_energy(100.0, 0.1)), 6)
    0.5
    """
    return 0.5 * np.asarray(k, float) * np.asarray(s, float) ** 2


def utilisation(theta) -> np.ndarray:
    """The thesis's muscle utilisation in [0, 1]: (1 + cos θ)/2 of the angle
    between the bones (0 = straight, unused; 1 = folded)."""
    return (1.0 + np.cos(np.asarray(theta, float))) / 2.0


def bone_angle(a, centre, b) -> np.ndarray:
    """Angle (rad) between the bones centre→a and centre→b, points (...,3)."""
    u = np.asarray(a, float) - np.asarray(centre, float)
    w = np.asarray(b, float) - np.asarray(centre, float)
    c = np.einsum("...i,...i->...", u, w) / (np.linalg.norm(u, axis=-1) * np.linalg.norm(w, axis=-1))
    return np.arccos(np.clip(c, -1.0, 1.0))


def parse_k(spec) -> np.ndarray:
    """Spring constants (6,) from a preset name (:data:`PRESETS`), one number
    (all muscles) or six numbers (a sequence or a comma-separated string in
    the order of :data:`MUSCLES`).

    Parameters
    ----------
    spec : str, float or sequence of float
        A preset name, one number, or six.

    Returns
    -------
    ndarray, shape (6,)

    Examples
    --------
    >>> parse_k(2.0).tolist(), parse_k("1,2,3,4,5,6").tolist()
    ([2.0, 2.0, 2.0, 2.0, 2.0, 2.0], [1.0, 2.0, 3.0, 4.0, 5.0, 6.0])"""
    if isinstance(spec, str):
        key = spec.strip().lower()
        if key in PRESETS:
            return np.array(PRESETS[key], dtype=float)
        try:
            vals = [float(v) for v in key.split(",")]
        except ValueError:
            raise FlipstudyValueError(f"k: unknown preset {spec!r}; expected one of {', '.join(PRESETS)}, "
                             f"one number or six comma-separated numbers "
                             f"({', '.join(MUSCLES)})") from None
    else:
        vals = list(np.atleast_1d(np.asarray(spec, dtype=float)))
    if len(vals) == 1:
        vals = vals * 6
    if len(vals) != 6 or not all(np.isfinite(v) and v > 0 for v in vals):
        raise FlipstudyValueError(f"k: expected a preset ({', '.join(PRESETS)}), one positive number or six "
                         f"positive numbers ({', '.join(MUSCLES)}), got {spec!r}")
    return np.array(vals, dtype=float)
