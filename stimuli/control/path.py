"""Jump path estimation (Ooi 2016, Section 3.5.1).

The character is a point mass in a vacuum: given the displacement Δx of the
jump, the time in the air ``t_air``, gravity ``g`` and the time the thrust
lasts ``t_windup``, the take-off velocity and the thrust's constant
acceleration are

    v0 = Δx / t_air − g · t_air / 2
    a  = (v0 − v_i) / t_windup

with ``v_i`` the velocity before the jump (0 from standing).  ``g`` is a
vector (Y up): ``(0, −9.81, 0)``; a positive number is taken as its magnitude.

>>> p = estimate_path((0, 0, 1), t_air=0.5, t_windup=0.2, g=10.0)
>>> p.v0.tolist(), p.a.tolist()
([0.0, 2.5, 2.0], [0.0, 12.5, 10.0])
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

from dataclasses import dataclass

import numpy as np

G = 9.81


def gravity_vector(g) -> np.ndarray:
    """(3,) gravity: a number is its magnitude (pointing down, −Y); a vector is used as is."""
    arr = np.asarray(g, dtype=float)
    if arr.ndim == 0:
        if not (np.isfinite(arr) and arr > 0):
            raise FlipstudyValueError(f"gravity: expected a positive magnitude in m/s² (e.g. 9.81) or a "
                             f"vector, got {g!r}")
        return np.array([0.0, -float(arr), 0.0])
    if arr.shape != (3,) or not np.all(np.isfinite(arr)) or arr[1] >= 0:
        raise FlipstudyValueError(f"gravity: expected a vector (gx, gy, gz) with gy < 0 (Y up), got {g!r}")
    return arr.copy()


@dataclass(frozen=True)
class JumpPath:
    """The estimate of Section 3.5.1 (SI units, Y up).

    Attributes
    ----------
    displacement : ndarray
        Δx of the COM, take-off → touch-down (m).
    t_air, t_windup : float
        Seconds in the air, of the thrust.
    g, v_i, v0, a : ndarray
        Gravity, the velocity before the jump, the take-off velocity, the thrust
        acceleration.

    Examples
    --------
    >>> p = estimate_path((0.0, 0.0, 1.0), 0.5)
    >>> p.t_air, p.g.tolist()
    (0.5, [0.0, -9.81, 0.0])
    """

    displacement: np.ndarray    # Δx of the COM, take-off → touch-down (m)
    t_air: float                # s
    t_windup: float             # s, duration of the thrust
    g: np.ndarray               # m/s², vector
    v_i: np.ndarray             # velocity before the jump, m/s
    v0: np.ndarray              # take-off velocity, m/s
    a: np.ndarray               # thrust acceleration, m/s²

    @property
    def v_land(self) -> np.ndarray:
        """Velocity at touch-down, v0 + g t_air."""
        return self.v0 + self.g * self.t_air

    def position(self, t) -> np.ndarray:
        """(N,3) offset from the take-off point after ``t`` seconds of flight."""
        t = np.atleast_1d(np.asarray(t, float))[:, None]
        return self.v0[None] * t + 0.5 * self.g[None] * t ** 2

    def kinetic_energy(self, mass: float) -> float:
        """E_k = ½ m |v0|² at take-off (J): what the muscles must store (3.6.1)."""
        return kinetic_energy(mass, self.v0)


def kinetic_energy(mass: float, v) -> float:
    """½ m |v|², joules.

    Parameters
    ----------
    mass : float
        kg.
    v : array_like, shape (3,)
        m/s.

    Returns
    -------
    float

    Examples
    --------
    >>> kinetic_energy(70.0, (3.0, 4.0, 0.0))
    875.0
    """
    v = np.asarray(v, float)
    return 0.5 * float(mass) * float(v @ v)


def estimate_path(displacement, t_air: float, t_windup: float = 0.2, g=G, v_i=(0.0, 0.0, 0.0)) -> JumpPath:
    """Take-off velocity and thrust acceleration for a jump (Section 3.5.1).

    ``displacement`` (3,) metres, ``t_air`` and ``t_windup`` seconds (> 0),
    ``g`` gravity (magnitude or vector), ``v_i`` the initial velocity.
    Raises ``ValueError`` naming the parameter for bad input.

    Parameters
    ----------
    displacement : array_like, shape (3,)
        Metres.
    t_air, t_windup : float
        Seconds.
    g : float or array_like
        Gravity, m/s².
    v_i : array_like, shape (3,)
        m/s.

    Returns
    -------
    JumpPath

    Examples
    --------
    One metre forward in half a second of flight:

    >>> p = estimate_path((0.0, 0.0, 1.0), 0.5)
    >>> p.v0.tolist(), p.a.tolist()
    ([0.0, 2.4525, 2.0], [0.0, 12.2625, 10.0])"""
    d = np.asarray(displacement, dtype=float)
    if d.shape != (3,) or not np.all(np.isfinite(d)):
        raise FlipstudyValueError(f"displacement: expected three finite numbers (x, y, z) in metres, got {displacement!r}")
    for name, v in (("t_air", t_air), ("t_windup", t_windup)):
        if not (isinstance(v, (int, float, np.number)) and np.isfinite(v) and v > 0):
            raise FlipstudyValueError(f"{name}: expected a positive time in seconds, got {v!r}")
    vi = np.asarray(v_i, dtype=float)
    if vi.shape != (3,) or not np.all(np.isfinite(vi)):
        raise FlipstudyValueError(f"v_i: expected three finite numbers (m/s), got {v_i!r}")
    gv = gravity_vector(g)
    t_air, t_windup = float(t_air), float(t_windup)
    v0 = d / t_air - gv * t_air / 2.0
    a = (v0 - vi) / t_windup
    return JumpPath(d, t_air, t_windup, gv, vi, v0, a)
