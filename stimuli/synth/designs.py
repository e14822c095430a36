"""The designs of the built-in clips: each motion's key poses, timings and
speeds (:data:`DESIGNS`), the keyword parameters :func:`~flipstudy.stimuli.synth.builtin`
accepts (:data:`PARAMS`) and their check (:func:`check_params`).

>>> d, height = check_params("backflip", 120, 70.0, {"tuck": 0.8})
>>> d["tuck"], d["turns"], d["flight_time"], height
(0.8, -1, 0.68, 1.75)
"""
from __future__ import annotations

import numpy as np

from flipstudy.errors import FlipstudyValueError
from .planar import D, IX

G = 9.81
BUILTIN_NAMES = ("backflip", "frontflip", "jump")
SUBSTEPS = 16            # fine integration grid per frame in flight
REF_HEIGHT = 1.75        # lengths of the designs below are for this height


def dof_vector(**kw) -> np.ndarray:
    """A DOF vector (D,) of :mod:`.planar` with the named angles set, the rest zero."""
    q = np.zeros(D)
    for k, v in kw.items():
        q[IX[k]] = v
    return q


# The designs: angles in radians (DOF signs as in .planar), lengths in metres for a
# 1.75 m body (scaled with height), times in seconds.
_COMMON = dict(
    t_stand=0.30, t_crouch=1.06, t_takeoff=1.30,     # end of the hold, crouch bottom, take-off
    a_bottom=9.81,                                   # COM acceleration at the crouch bottom
    recover=0.80, hold=0.30,                         # after the absorb
    tuck_in=0.38, tuck_out=0.70,                     # tuck reached / left (fractions of flight)
    heel=0.35, heel_rate=16.0,                       # foot pitch about the ball at take-off, rad/s
    absorb_depth=0.25,                               # COM drop after touch-down, m
)
DESIGNS = {
    "backflip": dict(
        _COMMON, turns=-1, flight_time=0.68, horizontal_speed=-0.45, tuck=1.0, crouch_depth=0.40,
        crouch=dict(pitch=0.55, spine=0.15, neck=0.0, shoulder=0.9, elbow=-0.3),
        takeoff=dict(pitch=-0.22, knee=0.80, spine=-0.20, neck=-0.15, shoulder=-2.3, elbow=-0.1),
        takeoff_rates=dict(spine=-3.0, neck=-1.0, shoulder=-10.0, elbow=0.0),
        takeoff_com_ahead=-0.18,
        layout=dof_vector(hip=-0.15, knee=0.1, ankle=0.45, spine=-0.15, neck=-0.2, shoulder=-2.9, elbow=-0.1),
        tucked=dof_vector(hip=-2.2, knee=2.3, ankle=0.5, spine=0.45, neck=0.35, shoulder=-0.8, elbow=-1.1),
        landing=dict(pitch=0.35, hip=-0.75, knee=0.55, spine=0.10, neck=0.0, shoulder=-1.5, elbow=-0.3),
        absorb_pose=dict(pitch=0.45, spine=0.15, neck=0.05, shoulder=-1.3, elbow=-0.4),
    ),
    "frontflip": dict(
        _COMMON, turns=+1, flight_time=0.68, horizontal_speed=0.70, tuck=1.0, crouch_depth=0.40,
        crouch=dict(pitch=0.50, spine=0.15, neck=0.0, shoulder=-2.8, elbow=-0.3),
        takeoff=dict(pitch=0.40, knee=0.80, spine=0.15, neck=0.2, shoulder=-2.2, elbow=-0.1),
        takeoff_rates=dict(spine=2.0, neck=1.0, shoulder=5.0, elbow=0.0),
        takeoff_com_ahead=0.0,
        layout=dof_vector(hip=-0.3, knee=0.1, ankle=0.45, spine=0.2, neck=0.2, shoulder=-2.9, elbow=-0.1),
        tucked=dof_vector(hip=-2.2, knee=2.3, ankle=0.5, spine=0.5, neck=0.5, shoulder=-0.8, elbow=-1.1),
        landing=dict(pitch=0.30, hip=-0.70, knee=0.60, spine=0.10, neck=0.0, shoulder=-1.6, elbow=-0.3),
        absorb_pose=dict(pitch=0.60, spine=0.20, neck=0.05, shoulder=-1.3, elbow=-0.4),
    ),
    "jump": dict(
        _COMMON, turns=0, flight_time=0.50, horizontal_speed=0.10, tuck=0.3, crouch_depth=0.32,
        crouch=dict(pitch=0.50, spine=0.15, neck=0.0, shoulder=0.9, elbow=-0.3),
        takeoff=dict(pitch=0.15, knee=0.80, spine=0.0, neck=0.0, shoulder=-2.5, elbow=-0.1),
        takeoff_rates=dict(spine=0.0, neck=0.0, shoulder=-1.0, elbow=0.0),
        takeoff_com_ahead=-0.10,
        layout=dof_vector(hip=-0.1, knee=0.1, ankle=0.45, spine=0.0, neck=0.0, shoulder=-2.9, elbow=-0.1),
        tucked=dof_vector(hip=-1.6, knee=2.0, ankle=0.5, spine=0.3, neck=0.2, shoulder=-2.2, elbow=-0.6),
        landing=dict(pitch=0.20, hip=-0.45, knee=0.45, spine=0.05, neck=0.0, shoulder=-1.2, elbow=-0.3),
        absorb_pose=dict(pitch=0.45, spine=0.15, neck=0.05, shoulder=-1.0, elbow=-0.4),
        absorb_depth=0.20,
    ),
}

#: the keyword parameters :func:`builtin` accepts (besides fps and total_mass)
PARAMS = ("height", "flight_time", "tuck", "horizontal_speed", "crouch_depth", "turns", "shape")
#: body shapes in flight: "tuck" (hips and knees flexed), "pike" (hips flexed, knees
#: straight), "layout" (body straight; the same as tuck = 0)
SHAPES = ("tuck", "pike", "layout")


def check_params(name, fps, total_mass, params):
    """The design of built-in ``name`` with ``params`` applied, and the body's
    height; refuses an unknown name or parameter or a value out of range,
    naming it."""
    if name not in DESIGNS:
        raise FlipstudyValueError(f"unknown built-in clip {name!r}; valid names: {', '.join(BUILTIN_NAMES)}")
    bad = [k for k in params if k not in PARAMS]
    if bad:
        raise FlipstudyValueError(f"builtin({name!r}): unknown parameter(s) {bad}; valid: "
                         f"{', '.join(PARAMS)} (and fps, total_mass)")
    if not (isinstance(fps, (int, float, np.number)) and np.isfinite(fps) and fps >= 10):
        raise FlipstudyValueError(f"fps must be a number of frames per second >= 10, got {fps!r}")
    if not (np.isfinite(total_mass) and total_mass > 0):
        raise FlipstudyValueError(f"total_mass must be a positive number of kg, got {total_mass!r}")
    d = dict(DESIGNS[name])
    for k in ("flight_time", "tuck", "horizontal_speed", "crouch_depth", "turns"):
        if k in params:
            d[k] = params[k]
    shape = params.get("shape", "tuck")
    if shape not in SHAPES:
        raise FlipstudyValueError(f"shape must be one of {', '.join(SHAPES)}, got {shape!r}")
    if shape == "pike":                   # hips folded further, knees straight
        d["tucked"] = d["tucked"].copy()
        d["tucked"][IX["hip"]] = -2.5
        d["tucked"][IX["knee"]] = 0.05
    elif shape == "layout":
        d["tuck"] = 0.0
    H = float(params.get("height", REF_HEIGHT))
    if not (np.isfinite(H) and 1.0 <= H <= 2.5):
        raise FlipstudyValueError(f"height must be between 1.0 and 2.5 m, got {H!r}")
    if not (0.0 <= float(d["tuck"]) <= 1.0):
        raise FlipstudyValueError(f"tuck must be between 0 (layout) and 1 (full tuck), got {d['tuck']!r}")
    if not (0.3 <= float(d["flight_time"]) <= 1.2):
        raise FlipstudyValueError(f"flight_time must be between 0.3 and 1.2 s, got {d['flight_time']!r}")
    if not (abs(float(d["horizontal_speed"])) <= 3.0):
        raise FlipstudyValueError(f"horizontal_speed must be within ±3 m/s, got {d['horizontal_speed']!r}")
    if not (0.10 <= float(d["crouch_depth"]) <= 0.45):
        raise FlipstudyValueError(f"crouch_depth must be between 0.10 and 0.45 m, got {d['crouch_depth']!r}")
    turns = d["turns"]
    if name == "jump":
        if turns != 0:
            raise FlipstudyValueError("turns: the jump does not rotate; use 'backflip' or 'frontflip'")
    else:
        if int(turns) != turns or abs(turns) < 1 or abs(turns) > 3:
            raise FlipstudyValueError(f"turns must be a whole number of somersaults from 1 to 3 (the clip "
                             f"ends standing at the same facing), got {turns!r}")
        turns = (-1 if name == "backflip" else 1) * abs(int(turns))
    d["turns"] = turns
    return d, H
