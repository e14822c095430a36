"""Balance (Ooi 2016, 3.3): the support polygon of the feet, the COM's offset
from its centre, and the PD controller that bends the upper body to remove it.

The support polygon is the convex hull of the corners of the flat feet on the
ground (their outer edges, the toe line and the heel line: a quad for
parallel feet).  The balance error is the COM projected on the ground minus
the polygon's centre (x, z).  The PD controller (k_p = k_d = 1, Table 3.2)
turns it into a lean of the upper body, u = k_p e(t) + k_d (e(t) − e(t−1)),
applied as radians about X (forward) and Z (sideways), shared by the two spine
joints and clamped to their limits.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

from .model import LIMITS

KP_BALANCE = 1.0
KD_BALANCE = 1.0


def support_polygon(corners: np.ndarray) -> np.ndarray:
    """(K,2) counter-clockwise hull (x, z) of foot corners (...,3)."""
    pts = np.asarray(corners, float).reshape(-1, 3)[:, [0, 2]]
    hull = ConvexHull(pts)
    return pts[hull.vertices]


def polygon_centre(poly: np.ndarray) -> np.ndarray:
    """Area centroid (2,) of a polygon (K,2)."""
    x, z = poly[:, 0], poly[:, 1]
    x1, z1 = np.roll(x, -1), np.roll(z, -1)
    cr = x * z1 - x1 * z
    A = cr.sum() / 2.0
    return np.array([((x + x1) * cr).sum(), ((z + z1) * cr).sum()]) / (6.0 * A)


def inside(poly: np.ndarray, pts: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """(N,) whether ground points (N,2) are inside a convex CCW polygon by at
    least ``margin`` metres."""
    p = np.atleast_2d(pts)
    a = poly
    b = np.roll(poly, -1, axis=0)
    e = b - a
    n = np.stack([e[:, 1], -e[:, 0]], 1) / np.linalg.norm(e, axis=1)[:, None]   # outward for CCW
    d = np.einsum("nkc,kc->nk", p[:, None, :] - a[None], n)
    return np.all(d <= -margin, axis=1)


def balance_error(com: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(N,2) ground-plane offset (x, z) of the COM from the support centre."""
    return np.atleast_2d(com)[:, [0, 2]] - np.asarray(centre)[None]


def lean_limits() -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) of the whole lean (about X, about Z), radians: two spine joints."""
    _, lo, hi = LIMITS["spine"]
    return 2 * np.radians([lo[0], lo[1]]), 2 * np.radians([hi[0], hi[1]])


def pd_lean(lean: np.ndarray, e: np.ndarray, e_prev: np.ndarray, kp: float = KP_BALANCE,
            kd: float = KD_BALANCE) -> np.ndarray:
    """One step of the balance PD controller: the new lean (2,) from the balance
    error e (2,) = (x, z) and the previous one.  A COM ahead (+z) leans the
    upper body back (−X); a COM to +x leans it toward −x (+Z)."""
    u = kp * e + kd * (e - e_prev)
    lo, hi = lean_limits()
    return np.clip(lean + np.array([-u[1], u[0]]), lo, hi)
