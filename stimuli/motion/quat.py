"""Unit quaternions (..., 4), scalar last, as plain numpy arrays: the products,
logs and exps of the editing hot paths without a ``Rotation`` object per call.

Each function is the arithmetic scipy's ``Rotation`` performs on arrays of
more than one leading dimension (its array-API backend, which multiflip's
batches always took), operation for operation, so the results are the same
bit for bit (``tests/stimuli/test_quat_arrays.py`` compares them with scipy on
random and real quaternions).  What goes is the wrapping around it: dtype
promotion, namespace dispatch and a new object for every product, which cost
more than the arithmetic on a few hundred quaternions.

Inputs are float64 arrays; nothing here checks them (the callers hold unit
quaternions of a clip): a zero quaternion gives NaN instead of scipy's error.
"""
from __future__ import annotations

import numpy as np


def norm(x: np.ndarray) -> np.ndarray:
    """Euclidean norm over the last axis, kept: numpy's ``linalg.norm``
    (``sqrt(add.reduce(x·x))``, which adds the squares in order), written out
    per component, about seven times faster on (n, 4) arrays."""
    sq = x * x                  # the squares in one pass, then added in order, in place
    s = sq[..., 0] + sq[..., 1]
    for i in range(2, x.shape[-1]):
        s += sq[..., i]
    return np.sqrt(s, out=s)[..., None]


def normalized(q: np.ndarray) -> np.ndarray:
    """``q`` scaled to unit length (what ``Rotation.from_quat`` stores)."""
    return q / norm(q)


def inv(q: np.ndarray) -> np.ndarray:
    """The inverse (conjugate) of unit quaternions."""
    out = q.copy()
    out[..., :3] *= -1
    return out


def mul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The product p·q (apply q, then p), normalised: ``(Rotation(p) * Rotation(q)).as_quat()``
    for unit ``p`` and ``q`` (broadcast)."""
    if p.ndim == 1 and q.ndim == 1:            # one product: the in-place steps need arrays
        return mul(p[None], q[None])[0]
    px, py, pz, pw = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qx, qy, qz, qw = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    # scipy's expressions, evaluated in the same order, in place: fewer temporaries
    # x = pw * qx + qw * px + (py * qz - pz * qy)
    x = pw * qx
    x += qw * px
    t = py * qz
    t -= pz * qy
    x += t
    y = pw * qy                                # pw * qy + qw * py + (pz * qx - px * qz)
    y += qw * py
    np.multiply(pz, qx, out=t)
    t -= px * qz
    y += t
    z = pw * qz                                # pw * qz + qw * pz + (px * qy - py * qx)
    z += qw * pz
    np.multiply(px, qy, out=t)
    t -= py * qx
    z += t
    w = pw * qw                                # pw * qw - px * qx - py * qy - pz * qz
    w -= px * qx
    w -= py * qy
    w -= pz * qz
    n = np.multiply(x, x, out=t)               # sqrt(x * x + y * y + z * z + w * w)
    n += y * y
    n += z * z
    n += w * w
    np.sqrt(n, out=n)
    out = np.empty(x.shape + (4,))
    for i, c in enumerate((x, y, z, w)):
        np.divide(c, n, out=out[..., i])
    return out


def from_rotvec(v: np.ndarray) -> np.ndarray:
    """exp: rotation vectors (..., 3) to unit quaternions (..., 4)."""
    angle = norm(v)
    small = angle <= 1e-3
    h = angle / 2
    scale = np.sin(h) / (angle + small.astype(angle.dtype))
    if small.any():             # the series near 0 (computed only when it is used)
        angle2 = angle ** 2
        scale = np.where(small, 0.5 - angle2 / 48 + angle2 ** 2 / 3840, scale)
    out = np.empty(v.shape[:-1] + (4,))
    np.multiply(v, scale, out=out[..., :3])
    np.cos(h, out=out[..., 3:])
    return out


def as_rotvec(q: np.ndarray) -> np.ndarray:
    """log: unit quaternions (..., 4) to rotation vectors (..., 3), angle in [0, π]."""
    w = q[..., 3]
    flip = w < 0                # scipy's canonical sign; w = 0: the first non-zero of x, y, z
    zero = w == 0
    if zero.any():
        x, y, z = q[..., 0], q[..., 1], q[..., 2]
        flip = flip | (zero & ((x < 0) | ((x == 0) & ((y < 0) | ((y == 0) & (z < 0))))))
    q = np.where(flip[..., None], -q, q)
    angle = 2 * np.arctan2(norm(q[..., :3]), q[..., 3][..., None])
    small = angle <= 1e-3
    scale = angle / (np.sin(angle / 2.0) + small.astype(angle.dtype))
    if small.any():
        angle2 = angle ** 2
        scale = np.where(small, 2 + angle2 / 12 + 7 * angle2 ** 2 / 2880, scale)
    return scale * q[..., :3]


def matrix_entries(x, y, z, w):
    """The rotation matrix of unit quaternions given by their components (arrays of
    any one shape), as ``[[m00, m01, m02], [m10, m11, m12], [m20, m21, m22]]``:
    scipy's ``Rotation.as_matrix`` expressions, so the same bits."""
    x2, y2, z2, w2 = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    return [[x2 - y2 - z2 + w2, 2 * (xy - zw), 2 * (xz + yw)],
            [2 * (xy + zw), -x2 + y2 - z2 + w2, 2 * (yz - xw)],
            [2 * (xz - yw), 2 * (yz + xw), -x2 - y2 + z2 + w2]]


def as_matrix(q: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4) to rotation matrices (..., 3, 3):
    ``Rotation.from_quat(q).as_matrix()`` for unit ``q``."""
    m = matrix_entries(q[..., 0], q[..., 1], q[..., 2], q[..., 3])
    out = np.empty(q.shape[:-1] + (3, 3))
    for a in range(3):
        for b in range(3):
            out[..., a, b] = m[a][b]
    return out


def apply(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Vectors ``v`` (n, 3) rotated by unit quaternions ``q`` (n, 4):
    ``Rotation.from_quat(q).apply(v)`` (its matrix, then the product scipy forms: one
    rotation by a matrix product, more by an einsum)."""
    m = as_matrix(q)
    if len(q) == 1:
        return np.dot(v, m[0].T)
    return np.einsum("ijk,ik->ij", m, v)


def relative(q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """log(q0⁻¹ q1): the rotation vector from ``q0`` to ``q1`` (unit or not)."""
    return as_rotvec(mul(inv(normalized(q0)), normalized(q1)))


def slerp(q0: np.ndarray, q1: np.ndarray, u) -> np.ndarray:
    """q0 · exp(u · log(q0⁻¹ q1)) for quaternions (..., 4) and ``u`` broadcastable
    to their leading shape."""
    a = normalized(q0)
    rel = as_rotvec(mul(inv(a), normalized(q1)))
    return mul(a, from_rotvec(rel * np.asarray(u, float)[..., None]))
