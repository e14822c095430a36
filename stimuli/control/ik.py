"""Inverse kinematics for the legs: cyclic coordinate descent (Ooi 2016, 3.4,
Algorithm 3.1), vectorised over many chains at once.

A leg is the single chain hip (ball joint, Euler-angle limits clamped after
every rotation, as the thesis does) → knee (hinge about its local X axis,
limits on the angle) → ankle (the end effector).  Each iteration visits the
joints from the end effector to the root: the knee turns about its hinge axis
by the signed angle between (ankle − knee) and (target − knee) projected on
the plane of the hinge; the hip turns by the rotation taking (ankle − hip) to
(target − hip).  Iterations stop when every chain is within ``stop`` metres
of its target or after ``iterations`` (30–100 in the thesis).  Chains that
converged drop out of the batch.

The foot is placed afterwards: flat, or pitched about the ball of the foot
(heel raised) when the hip is beyond the leg's reach with the heel down —
:func:`heel_pitch` finds that pitch.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from .model import LIMITS, SIDES, Jumper

EX = np.array([1.0, 0.0, 0.0])
EZ = np.array([0.0, 0.0, 1.0])


def clamp_euler(rot: Rotation, spec) -> tuple[Rotation, np.ndarray]:
    """Clamp a ball joint's rotation to Euler-angle limits ``spec`` = (order,
    lows, highs) in degrees; returns the clamped rotation and whether it was
    clamped (N,)."""
    order, lo, hi = spec
    e = rot.as_euler(order, degrees=True)
    c = np.clip(e, lo, hi)
    return Rotation.from_euler(order, c, degrees=True), np.any(np.abs(c - e) > 1e-9, axis=-1)


def within_limits(rot: Rotation, spec, tol: float = 1e-6) -> np.ndarray:
    order, lo, hi = spec
    e = rot.as_euler(order, degrees=True)
    return np.all((e >= np.asarray(lo) - tol) & (e <= np.asarray(hi) + tol), axis=-1)


@dataclass
class LegSolution:
    hip: np.ndarray       # (N,4) local hip quaternions
    knee: np.ndarray      # (N,) knee hinge angle, rad
    error: np.ndarray     # (N,) distance ankle → target, m
    iterations: int       # CCD iterations run


def ccd_leg(hip_pos, target, thigh: float, shank: float, hip0=None, knee0=None, *,
            iterations: int = 100, stop: float = 1e-3, hip_limits=LIMITS["hip"],
            knee_limits=LIMITS["knee"]) -> LegSolution:
    """CCD for N hip→knee→ankle chains (pelvis frame = world axes).

    ``hip_pos``, ``target`` (N,3); ``hip0`` (N,4) and ``knee0`` (N,) start the
    search (default: hip straight, the knee seeded from the hip–target distance)."""
    H = np.atleast_2d(np.asarray(hip_pos, float))
    T = np.atleast_2d(np.asarray(target, float))
    N = H.shape[0]
    if not (10 <= iterations <= 1000):
        raise ValueError(f"iterations: expected 10–1000 CCD iterations, got {iterations!r}")
    q = np.tile([0.0, 0.0, 0.0, 1.0], (N, 1)) if hip0 is None else np.array(hip0, float).reshape(N, 4)
    if knee0 is None:
        # seed the knee from the hip–target distance (law of cosines): CCD cannot
        # bend a straight chain towards a target in line with it
        d = np.clip(np.linalg.norm(T - H, axis=1), abs(thigh - shank) + 1e-6, thigh + shank)
        c = (thigh ** 2 + shank ** 2 - d ** 2) / (2 * thigh * shank)
        beta = np.maximum(np.pi - np.arccos(np.clip(c, -1.0, 1.0)), 0.05)
    else:
        beta = np.array(knee0, float).reshape(N)
    lo, hi = np.radians(knee_limits[0]), np.radians(knee_limits[1])
    beta = np.clip(beta, lo, hi)
    t_loc = np.array([0.0, -thigh, 0.0])
    s_loc = np.array([0.0, -shank, 0.0])
    if hip0 is None:
        # aim the seeded chain at the target (the minimal rotation, no twist)
        A0 = t_loc + Rotation.from_rotvec(beta[:, None] * EX).apply(s_loc)
        q = _align(A0, T - H).as_quat()
    err = np.full(N, np.inf)
    active = np.arange(N)
    it = 0

    def ends(Rh, b, h):
        K = h + Rh.apply(t_loc)
        Rs = Rh * Rotation.from_rotvec(b[:, None] * EX)
        return K, K + Rs.apply(s_loc)

    while active.size and it < iterations:
        it += 1
        Rh = Rotation.from_quat(q[active])
        b = beta[active]
        h, tg = H[active], T[active]
        # knee: hinge about the thigh's local X axis
        K, A = ends(Rh, b, h)
        n = Rh.apply(EX)
        u, w = A - K, tg - K
        u -= np.einsum("ij,ij->i", u, n)[:, None] * n
        w -= np.einsum("ij,ij->i", w, n)[:, None] * n
        phi = np.arctan2(np.einsum("ij,ij->i", n, np.cross(u, w)), np.einsum("ij,ij->i", u, w))
        b = np.clip(b + phi, lo, hi)
        # hip: the rotation taking (ankle − hip) to (target − hip), then the limits
        _, A = ends(Rh, b, h)
        u, w = A - h, tg - h
        Rh, _ = clamp_euler(_align(u, w) * Rh, hip_limits)
        _, A = ends(Rh, b, h)
        e = np.linalg.norm(A - tg, axis=1)
        q[active] = Rh.as_quat()
        beta[active] = b
        err[active] = e
        active = active[e >= stop]
    return LegSolution(q, beta, err, it)


def _align(u: np.ndarray, w: np.ndarray) -> Rotation:
    """The minimal rotations taking directions u (N,3) to w (N,3)."""
    ax = np.cross(u, w)
    sn = np.linalg.norm(ax, axis=1)
    ang = np.arctan2(sn, np.einsum("ij,ij->i", u, w))
    rv = np.where(sn[:, None] > 1e-12, ax / np.maximum(sn, 1e-12)[:, None] * ang[:, None], 0.0)
    return Rotation.from_rotvec(rv)


def reach(thigh: float, shank: float, knee_flexion: float) -> float:
    """Hip–ankle distance with the knee flexed by ``knee_flexion`` rad."""
    th = np.pi - knee_flexion
    return float(np.sqrt(thigh ** 2 + shank ** 2 - 2 * thigh * shank * np.cos(th)))


def foot_rotation(pitch) -> Rotation:
    """World rotation of a foot facing +Z pitched by ``pitch`` (N,) about X
    (positive: heel up, about the ball)."""
    p = np.atleast_1d(np.asarray(pitch, float))
    return Rotation.from_rotvec(p[:, None] * EX)


def heel_pitch(hip, ball, ball_offset, length: float, max_pitch: float, n: int = 101) -> np.ndarray:
    """Foot pitch (N,) about the ball that puts the ankle ``length`` from the
    hip: 0 when the flat foot's ankle is already within ``length``; NaN when
    even ``max_pitch`` is not enough.  ``ball_offset`` is ankle → ball in the
    foot's frame."""
    hip = np.atleast_2d(hip)
    ball = np.atleast_2d(ball)
    ph = np.linspace(0.0, max_pitch, n)
    off = foot_rotation(ph).apply(ball_offset)                       # (n,3)
    ank = ball[:, None, :] - off[None]                               # (N,n,3)
    d = np.linalg.norm(hip[:, None, :] - ank, axis=-1)               # (N,n)
    out = np.full(hip.shape[0], np.nan)
    ok0 = d[:, 0] <= length
    out[ok0] = 0.0
    below = d <= length
    first = np.argmax(below, axis=1)
    mid = ~ok0 & below.any(axis=1)
    i = first[mid]
    d0, d1 = d[mid, i - 1], d[mid, i]
    f = (d0 - length) / np.maximum(d0 - d1, 1e-12)
    out[mid] = ph[i - 1] + f * (ph[i] - ph[i - 1])
    return out


@dataclass
class Stance:
    """Legs solved for N poses: quaternions (N,J,4) (legs, feet; the rest as
    given), per-side IK error (N,2), ankle-limit flags (N,2) and the joint
    positions (N,J,3)."""

    quats: np.ndarray
    error: np.ndarray
    ankle_ok: np.ndarray
    positions: np.ndarray | None = None
    warm: dict | None = None

    @property
    def ok(self) -> np.ndarray:
        return np.all(self.error < 2e-3, axis=1) & np.all(self.ankle_ok, axis=1)


def solve_legs(jumper: Jumper, root, quats, ankles: dict, pitch: dict | None = None, warm: dict | None = None,
               iterations: int = 100, stop: float = 1e-3, roll=None) -> Stance:
    """Place both legs of N poses: CCD from the hips (pelvis at ``root``, upright,
    or rolled by ``roll`` (N,) rad about the forward axis Z — positive lowers the
    right hip, see :func:`.uneven.pelvis_roll`) to the ankle targets
    ``ankles[side]`` (N,3), the feet pitched by ``pitch[side]`` (N,) about the
    ball (0 = flat) and the toes flat on the ground.  ``quats`` (N,J,4) supplies
    the other joints (its root rotation is replaced when ``roll`` is given);
    ``warm`` is a previous result's ``warm`` to start CCD from.  A rolled
    pelvis is solved in the pelvis's frame, so the hip limits stay the hip's."""
    root = np.atleast_2d(np.asarray(root, float))
    N = root.shape[0]
    Q = np.array(quats, float, copy=True).reshape(N, jumper.J, 4)
    Rp = None
    if roll is not None:
        r = np.broadcast_to(np.asarray(roll, float), (N,))
        if np.any(r != 0.0):
            Rp = Rotation.from_rotvec(r[:, None] * EZ)
            Q[:, 0] = Rp.as_quat()
    err = np.zeros((N, 2))
    aok = np.zeros((N, 2), bool)
    new_warm = {}
    for k, s in enumerate(SIDES):
        hip = root + jumper.hip_offset[s]
        tgt = np.broadcast_to(np.asarray(ankles[s], float), (N, 3))
        if Rp is not None:                  # the chain in the pelvis's frame
            hip = np.broadcast_to(jumper.hip_offset[s], (N, 3))
            tgt = Rp.inv().apply(tgt - root)
        w = (warm or {}).get(s)
        # start from the previous solution when given, else from the seed (knee from
        # the hip–target distance, chain aimed at the target): CCD then polishes it
        # within the limits in a few iterations (it is slow near a straight knee)
        sol = ccd_leg(hip, tgt, jumper.thigh, jumper.shank, None if w is None else w[0],
                      None if w is None else w[1], iterations=iterations, stop=stop)
        new_warm[s] = (sol.hip.copy(), sol.knee.copy())
        Rh = Rotation.from_quat(sol.hip)
        Rk = Rotation.from_rotvec(sol.knee[:, None] * EX)
        p = np.zeros(N) if pitch is None else np.broadcast_to(np.asarray(pitch[s], float), (N,))
        Rf = foot_rotation(p)                               # the foot in the world
        Ra = (Rh * Rk).inv() * (Rf if Rp is None else Rp.inv() * Rf)
        aok[:, k] = within_limits(Ra, LIMITS["ankle"])
        Q[:, jumper.idx[f"hip_{s}"]] = sol.hip
        Q[:, jumper.idx[f"knee_{s}"]] = Rk.as_quat()
        Q[:, jumper.idx[f"ankle_{s}"]] = Ra.as_quat()
        Q[:, jumper.idx[f"toe_{s}"]] = Rf.inv().as_quat()
        err[:, k] = sol.error
    return Stance(Q, err, aok, warm=new_warm)
