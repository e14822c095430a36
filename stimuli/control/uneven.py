"""Uneven legs (Table 5.1's uneven trials, Ooi 2016 5.4): how two legs of
different stiffness share a crouch.  :func:`leg_asymmetry` measures the
difference, :func:`pelvis_roll` the roll of the pelvis it calls for (down on
the stronger side, the physics in its docstring), :func:`hip_compression`
what that roll does to each hip, and :func:`balance_target` where the balance
controller puts the COM: over the centre of pressure of the legs' springs.

>>> from flipstudy.stimuli.control import Jumper, parse_k
>>> round(leg_asymmetry(parse_k("uneven-global-normal")), 3)     # the right leg stronger
0.2
>>> float(pelvis_roll(Jumper(), 0.0, 0.2)[0])                    # equal legs do not roll
0.0
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from .model import SIDES, Jumper

PELVIS_ROLL_LIMIT = np.radians(8.0)   # the pelvis's frontal tilt (obliquity, a hip hike) in a crouch


def balance_target(jumper: Jumper, k, centre=(0.0, 0.0), compression=None) -> np.ndarray:
    """Where the balance controller puts the COM (x, z), relative to the feet's
    midpoint: the centre of pressure of the legs' springs.  Each leg is a
    spring of stiffness K = k_hip + k_knee + k_ankle compressed by its hip's
    drop δ below standing (``compression`` (N,2), left and right); it pushes
    with F = K δ, and the COM must be over the point where those forces act.
    Without ``compression`` (or where the legs stand straight) the legs are
    taken as compressed alike, F ∝ K: (2,).  Equal legs: the support
    polygon's centre (the thesis); a stronger leg draws the COM over itself
    and so carries more load — the more so as it bends more (:func:`pelvis_roll`)."""
    k = np.asarray(k, float).reshape(6)
    K = np.array([k[:3].sum(), k[3:].sum()])
    feet = jumper.feet()
    mid = np.array([jumper.foot_corners(feet[s])[:, [0, 2]].mean(0) for s in SIDES])
    if compression is None:
        return (K[:, None] * mid).sum(0) / K.sum() + np.asarray(centre)
    d = np.atleast_2d(np.asarray(compression, float))
    w = K[None] * (np.maximum(d, 0.0) + 1e-6)                 # F = K δ (straight legs: F ∝ K)
    return (w @ mid) / w.sum(1, keepdims=True) + np.asarray(centre)[None]


def leg_asymmetry(k) -> float:
    """c = (K_r − K_l) / (K_r + K_l) of the legs' stiffnesses K (each the sum of
    its hip, knee and ankle springs): 0 for equal legs, > 0 when the right
    leg is the stronger.  Table 5.1's uneven presets: ±0.2."""
    k = np.asarray(k, float).reshape(6)
    Kl, Kr = k[:3].sum(), k[3:].sum()
    return float((Kr - Kl) / (Kr + Kl))


def pelvis_roll(jumper: Jumper, asymmetry: float, depth) -> np.ndarray:
    """(N,) roll of the pelvis (rad, about the forward axis Z; positive lowers
    the right hip) in a crouch ``depth`` (N,) metres below the standing
    pelvis height, for legs of asymmetry c (:func:`leg_asymmetry`).

    Why.  The legs are two springs in parallel under one body (here each a
    linear spring K in its hip's drop δ below standing).  A pelvis that only
    translates compresses both by the same δ, so the stiffer leg pushes
    harder (F = K δ) and carries more weight, but both knees bend alike.
    Statics ties the share of the weight to where the COM is, and that is the
    controller's choice, so it does not fix how the bend is shared: the
    crouch is the store of the take-off energy, E = Σ ½ K δ², and the jumper
    chooses it.  Per unit of bend a stiffer spring stores more (dE/dδ = K δ):
    lowering the hip of the stronger leg by a and raising the weaker one's by
    a changes the energy of a crouch of depth D by (K_s − K_w) D a +
    ½ (K_s + K_w) a², a gain at first order, so the same energy is stored in
    a shallower crouch (which the choice prefers); the opposite tilt — the
    weaker leg sagging, as equal forces F_l = F_r would make it — loses
    energy (−½ (K_s + K_w) c² D² at a = −c D) and puts the load on the leg
    least able to return it.  So the pelvis rolls
    down on the stronger side.  The energy gives the direction, not the
    amount (the gain keeps growing with the tilt); the amount is a rule: each
    leg's compression follows its own spring, δ_i ∝ K_i, i.e. δ_s,w =
    D (1 ± c), as far as the pelvis's obliquity allows
    (:data:`PELVIS_ROLL_LIMIT`, reached below D ≈ 6 cm for c = 0.2).  The
    stronger leg bends more and, its force K δ larger, carries still more of
    the weight (the balance target follows, :func:`balance_target`); the
    weaker leg straightens — the thesis's "dangling" weaker leg (5.4).  Equal
    legs (c = 0): no roll, mirror-image legs.  Standing (D ≤ 0): no roll."""
    D = np.maximum(np.atleast_1d(np.asarray(depth, float)), 0.0)
    if asymmetry == 0.0:
        return np.zeros(D.shape)
    w = abs(float(jumper.hip_offset["r"][0]))
    a = np.arcsin(np.clip(abs(asymmetry) * D / w, 0.0, 1.0))
    return np.sign(asymmetry) * np.minimum(a, PELVIS_ROLL_LIMIT)


def hip_compression(jumper: Jumper, roll) -> np.ndarray:
    """(N,2) how far a roll (N,) lowers each hip (left, right) relative to the
    pelvis's centre (m; negative: raised) — add the crouch depth for each
    hip's drop below standing, the leg's compression δ."""
    r = np.atleast_1d(np.asarray(roll, float))
    R = Rotation.from_rotvec(r[:, None] * np.array([0.0, 0.0, 1.0]))
    return np.stack([-(R.apply(jumper.hip_offset[s])[:, 1] - jumper.hip_offset[s][1]) for s in SIDES], 1)

