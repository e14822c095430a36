"""Flight analysis of one clip: the pre-processing stage of the paper (Section 4).

``analyse(clip)`` finds the flight (ballistic) phases, estimates the mass
distribution from the main flight, computes COM, linear and angular momentum,
the take-off angle, and checks units and frame time against gravity: a
contradiction becomes a warning that names the likely frame time and the
``--fps`` / ``--scale`` options, never a silent wrong answer.
"""

from __future__ import annotations

from .exceptions import FlipstudyValueError

from dataclasses import dataclass, field

import numpy as np

from .body import Body
from .flight import Flight, detect_flights, fit_path
from .massfit import G, MassFit, estimate_masses
from .motion.clip import Clip
from .physics import Momentum, momentum

#: apparent gravity further than this (relative) from 9.81 m/s² raises a warning
GRAVITY_TOLERANCE = 0.25
DEFAULT_W = 1e-4


@dataclass
class Analysis:
    """What :func:`analyse` found.  Arrays have frames first."""

    clip: Clip
    body: Body
    com: np.ndarray
    p: np.ndarray
    L: np.ndarray
    flights: list[Flight]
    mass_fit: MassFit | None
    warnings: list[str] = field(default_factory=list)

    # --------------------------------------------------------------- flight
    @property
    def flight(self) -> Flight | None:
        return self.flights[0] if self.flights else None

    @property
    def takeoff(self) -> int | None:
        return None if self.flight is None else self.flight.takeoff

    @property
    def landing(self) -> int | None:
        return None if self.flight is None else self.flight.landing

    @property
    def flight_frames(self) -> slice:
        if self.flight is None:
            raise FlipstudyValueError(f"{self.clip.meta.get('name', 'clip')}: no flight phase")
        return slice(self.takeoff, self.landing + 1)

    @property
    def flight_s(self) -> float | None:
        return None if self.flight is None else (self.landing - self.takeoff) / self.clip.fps

    @property
    def path(self) -> np.ndarray | None:
        """(3,3) ballistic COM path of the flight, rows x,y,z; columns t², t, 1 with
        t in seconds from take-off (estimated masses)."""
        if self.flight is None:
            return None
        return fit_path(self.com[self.flight_frames], self.clip.fps)

    @property
    def apparent_gravity(self) -> float | None:
        """m/s²: −2× the t² coefficient of the flight's COM parabola."""
        return None if self.flight is None else float(-2.0 * self.path[1, 0])

    @property
    def takeoff_velocity(self) -> np.ndarray | None:
        """COM velocity at take-off from the fitted path (m/s)."""
        return None if self.flight is None else self.path[:, 1].copy()

    @property
    def takeoff_angle(self) -> float | None:
        """Degrees above the horizontal of the take-off COM velocity."""
        v = self.takeoff_velocity
        if v is None:
            return None
        return float(np.degrees(np.arctan2(v[1], np.hypot(v[0], v[2]))))

    @property
    def L_norm(self) -> np.ndarray:
        return np.linalg.norm(self.L, axis=1)

    @property
    def L_mean(self) -> float | None:
        return None if self.flight is None else float(self.L_norm[self.flight_frames].mean())

    @property
    def L_cv_pct(self) -> float | None:
        """Coefficient of variation of |L| in flight, percent."""
        if self.flight is None:
            return None
        x = self.L_norm[self.flight_frames]
        return float(100.0 * x.std() / x.mean()) if x.mean() > 0 else None

    @property
    def L_direction(self) -> np.ndarray | None:
        if self.flight is None:
            return None
        m = self.L[self.flight_frames].mean(0)
        n = np.linalg.norm(m)
        return m / n if n > 0 else m

    def to_dict(self) -> dict:
        """The machine-readable summary (``flipstudy inspect --json``)."""
        c = self.clip
        r = lambda x, n=4: None if x is None else round(float(x), n)  # noqa: E731
        out = {
            "name": c.meta.get("name"),
            "frames": c.num_frames,
            "fps": c.fps,
            "header_fps": c.meta.get("header_fps"),
            "fps_source": c.meta.get("fps_source"),
            "scale": c.meta.get("scale", 1.0),
            "scale_source": c.meta.get("scale_source", "metres"),
            "root_convention": c.meta.get("root_convention"),
            "dropped_frames": c.meta.get("dropped_frames", []),
            "apparent_gravity": r(self.apparent_gravity, 3),
            "takeoff": self.takeoff,
            "landing": self.landing,
            "flight_s": r(self.flight_s),
            "takeoff_angle_deg": r(self.takeoff_angle, 2),
            "takeoff_velocity": None if self.flight is None else [r(v) for v in self.takeoff_velocity],
            "L_mean": r(self.L_mean),
            "L_cv_pct": r(self.L_cv_pct, 3),
            "L_direction": None if self.flight is None else [r(v) for v in self.L_direction],
            "flights": [{"takeoff": f.takeoff, "landing": f.landing,
                         "com_rms_mm": round(f.rms * 1000, 2)} for f in self.flights],
            "total_mass": self.body.total_mass,
            "segment_masses": {k: round(v, 3) for k, v in self.body.segment_masses().items()},
            "mass_fit": None if self.mass_fit is None else {
                "W": self.mass_fit.W,
                "scale_factor": round(self.mass_fit.scale_factor, 4),
                "com_rms_prior_mm": round(self.mass_fit.com_rms_prior * 1000, 2),
                "com_rms_mm": round(self.mass_fit.com_rms * 1000, 2),
                "p_dev_reduction_pct": round(self.mass_fit.p_dev_reduction_pct, 1),
            },
            "warnings": list(self.warnings),
        }
        return out


def gravity_warning(g_app: float, clip: Clip) -> str | None:
    """A sentence when the apparent gravity contradicts 9.81 m/s², naming the
    likely frame rate (frame-time errors are factors of two) and, when that is
    not enough, the length scale."""
    ratio = g_app / G
    if abs(ratio - 1.0) <= GRAVITY_TOLERANCE:
        return None
    fps = clip.fps
    cands = [fps * 2.0 ** k for k in (-2, -1, 1, 2)]
    best = min(cands, key=lambda f: abs(np.log(g_app * (f / fps) ** 2 / G)))
    g_best = g_app * (best / fps) ** 2
    head = (f"apparent gravity in flight is {g_app:.1f} m/s², not 9.81: the clip's time or "
            f"length scale is wrong.")
    if abs(g_best / G - 1.0) <= GRAVITY_TOLERANCE:
        return (f"{head} At {best:g} fps instead of {fps:g} it would be {g_best:.1f} m/s², so the "
                f"frame time is probably wrong (header says {clip.meta.get('header_fps', fps):g} fps): "
                f"rerun with --fps {best:g}.")
    s = g_best / G
    scale = clip.meta.get("scale", 1.0)
    return (f"{head} At {best:g} fps it would be {g_best:.1f} m/s², still {100 * (s - 1):+.0f} % off, "
            f"so the lengths are probably scaled too (a retargeted or resized skeleton): try "
            f"--fps {best:g} --scale {scale / s:.4g} (now {scale:.4g} m per file unit).")


def analyse(clip: Clip, body: Body | None = None, total_mass: float = 70.0,
            estimate: bool = True, W: float = DEFAULT_W) -> Analysis:
    """Flight analysis of one clip.

    Parameters
    ----------
    body : the segment model; default ``Body.from_clip(clip, total_mass)`` (trunk and
        head measured on the clip's poses).
    estimate : estimate segment masses from the flight (Section 4.2) and use them
        for the momenta; with ``False`` the given/table masses are used.
    W : regularisation weight of the mass fit (m²).

    Example
    -------
    >>> a = analyse(builtin("backflip"))                        # doctest: +SKIP
    >>> a.takeoff, a.landing, round(a.takeoff_angle)            # doctest: +SKIP
    """
    body0 = body if body is not None else Body.from_clip(clip, total_mass)
    m0: Momentum = momentum(clip, body0)
    flights = detect_flights(clip, body0, m0.com)
    warnings = list(clip.meta.get("warnings", []))
    fit = None
    final_body, m = body0, m0
    if flights and estimate:
        f = flights[0]
        fit = estimate_masses(clip, body0, f.takeoff, f.landing, W=W)
        final_body = fit.body
        m = momentum(clip, final_body)
    a = Analysis(clip=clip, body=final_body, com=m.com, p=m.p, L=m.L, flights=flights,
                 mass_fit=fit, warnings=warnings)
    if a.flight is None:
        warnings.append("no flight phase: in every frame a foot or hand is in contact (still and "
                        "near its resting level); the clip has no ballistic phase to analyse")
    else:
        w = gravity_warning(a.apparent_gravity, clip)
        if w:
            warnings.append(w)
    return a
