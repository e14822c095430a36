"""Flight analysis of one clip: the pre-processing stage of the paper (Section 4).

``analyse(clip)`` finds the flight (ballistic) phases, estimates the mass
distribution from the main flight, computes COM, linear and angular momentum,
the take-off angle, and checks units and frame time against gravity: a
contradiction becomes a warning that names the likely frame time and the
``--fps`` / ``--scale`` options, never a silent wrong answer.
"""

from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

from dataclasses import dataclass, field

import numpy as np

from .body import Body
from .flight import Flight, detect_flights, fit_path, path_values
from .massfit import DEFAULT_W, G, MassFit, estimate_masses
from .motion.clip import Clip
from .physics import Momentum, momentum

#: apparent gravity further than this (relative) from 9.81 m/s² raises a warning
GRAVITY_TOLERANCE = 0.25


@dataclass
class Analysis:
    """What :func:`analyse` found.  Arrays have frames first.

    Attributes
    ----------
    clip : Clip
        The clip analysed.
    body : Body
        The segment model the momenta were computed with (with the masses
        estimated from the flight when :func:`analyse` was asked to).
    com : ndarray, shape (F, 3)
        Centre of mass, metres.
    p : ndarray, shape (F, 3)
        Linear momentum, kg·m/s.
    L : ndarray, shape (F, 3)
        Angular momentum about the centre of mass, kg·m²/s.
    flights : list
        The ballistic phases found (``takeoff``, ``landing``, ``takeoff_time``
        and ``landing_time`` describe the first).
    mass_fit : MassFit or None
        The mass estimate, when one was made.
    warnings : list of str
        Sentences about what the clip contradicts (e.g. its frame time).

    Examples
    --------
    >>> from flipstudy import analyse, builtin
    >>> a = analyse(builtin("jump"))
    >>> a.takeoff < a.landing, a.flight_s > 0
    (True, True)
    >>> a.warnings
    []
    """

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
        """First frame strictly inside the flight (after the take-off instant)."""
        return None if self.flight is None else self.flight.takeoff

    @property
    def landing(self) -> int | None:
        """Last frame strictly inside the flight (before the touchdown instant)."""
        return None if self.flight is None else self.flight.landing

    @property
    def takeoff_time(self) -> float | None:
        """The take-off instant, seconds (sub-frame): the body's lowest point leaves
        its support; frames strictly after it are airborne."""
        return None if self.flight is None else float(self.flight.takeoff_time)

    @property
    def landing_time(self) -> float | None:
        """The touchdown instant, seconds (sub-frame)."""
        return None if self.flight is None else float(self.flight.landing_time)

    def path_at(self, t: np.ndarray) -> np.ndarray:
        """(n,3) the flight's fitted COM path at clip times ``t`` (seconds)."""
        return path_values(self.path, np.asarray(t, float) - self.takeoff / self.clip.fps)

    @property
    def flight_frames(self) -> slice:
        if self.flight is None:
            raise FlipstudyValueError(f"{self.clip.meta.get('name', 'clip')}: no flight phase")
        return slice(self.takeoff, self.landing + 1)

    @property
    def flight_s(self) -> float | None:
        """Seconds from the take-off instant to the touchdown instant."""
        return None if self.flight is None else self.landing_time - self.takeoff_time

    @property
    def path(self) -> np.ndarray | None:
        """(3,3) ballistic COM path of the flight, rows x,y,z; columns t², t, 1 with
        t in seconds from the first frame strictly inside the flight (``takeoff``;
        :meth:`path_at` takes clip times), fitted to the frames strictly inside."""
        if self.flight is None:
            return None
        return fit_path(self.com[self.flight_frames], self.clip.fps)

    @property
    def apparent_gravity(self) -> float | None:
        """m/s²: −2× the t² coefficient of the flight's COM parabola."""
        return None if self.flight is None else float(-2.0 * self.path[1, 0])

    @property
    def takeoff_velocity(self) -> np.ndarray | None:
        """COM velocity at the take-off instant from the fitted path (m/s)."""
        if self.flight is None:
            return None
        v = self.path[:, 1].copy()
        v[1] += 2.0 * self.path[1, 0] * (self.takeoff_time - self.takeoff / self.clip.fps)
        return v

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
        """Coefficient of variation of ``|L|`` in flight, percent."""
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
            "takeoff_time": r(self.takeoff_time, 5),
            "landing_time": r(self.landing_time, 5),
            "flight_s": r(self.flight_s),
            "takeoff_angle_deg": r(self.takeoff_angle, 2),
            "takeoff_velocity": None if self.flight is None else [r(v) for v in self.takeoff_velocity],
            "L_mean": r(self.L_mean),
            "L_cv_pct": r(self.L_cv_pct, 3),
            "L_direction": None if self.flight is None else [r(v) for v in self.L_direction],
            "flights": [{"takeoff": f.takeoff, "landing": f.landing,
                         "takeoff_time": round(f.takeoff_time, 5),
                         "landing_time": round(f.landing_time, 5),
                         "com_rms_mm": round(f.rms * 1000, 2)} for f in self.flights],
            "total_mass": self.body.total_mass,
            "segment_masses": {k: round(v, 3) for k, v in self.body.segment_masses().items()},
            "mass_fit": None if self.mass_fit is None else {
                "W": self.mass_fit.W,
                "scale_factor": round(self.mass_fit.scale_factor, 4),
                "com_rms_prior_mm": round(self.mass_fit.com_rms_prior * 1000, 2),
                "com_rms_mm": round(self.mass_fit.com_rms * 1000, 2),
                "p_dev_reduction_pct": round(self.mass_fit.p_dev_reduction_pct, 1),
                "p_dev_prior": round(self.mass_fit.p_dev_prior, 4),
                "p_dev": round(self.mass_fit.p_dev, 4),
                "status": self.mass_fit.status,
                "message": self.mass_fit.message,
                "band_pct": None if self.mass_fit.band is None else 100 * self.mass_fit.band,
                "prior": {k: round(v, 3) for k, v in self.mass_fit.prior.items()},
                "fitted": {k: round(v, 3) for k, v in (self.mass_fit.fitted or {}).items()},
            },
            "warnings": list(self.warnings),
        }
        return out


#: the body height of an adult as :func:`body_height` measures it, metres.  The joints
#: stop short of the soles and the top of the head, so a skeleton measures less than
#: its stature (CMU's 88_01: 1.31 m from toe to head joint, 1.56 m from its hip height);
#: unit errors are factors of 2.2 (inch vs CMU units) to 100, far outside either bound.
BODY_HEIGHT_RANGE = (1.2, 2.2)
#: standing hip (greater trochanter) height / stature (Drillis & Contini 1966)
HIP_HEIGHT_RATIO = 0.530


def body_height(clip: Clip) -> float:
    """The body's height in metres from the rest skeleton alone: the larger of its
    largest extent (height, or span in a T-pose) and its hip height above the
    lowest point divided by :data:`HIP_HEIGHT_RATIO`.  Lengths only: a wrong length
    scale shows here, a wrong frame time does not."""
    from .flight import body_size
    sk = clip.skeleton
    P = sk.rest_positions()
    pts = np.concatenate([P, np.array([P[p] + o for p, o in sk.end_sites])]) if sk.end_sites else P
    hip = float(P[0, 1] - pts[:, 1].min())
    return max(body_size(clip), hip / HIP_HEIGHT_RATIO)


@dataclass
class PhysicsAdvice:
    """What contradicts physics in a clip and the fix: a frame rate, a length
    scale, or both (``None`` where that one is right)."""

    problem: str                # the measurements, one or two sentences
    fps: float | None           # the frame rate to read the clip at (its own rate, before resampling)
    scale: float | None         # metres per file unit to read it with
    scale_unit: str | None      # what that scale is ("CMU/ASF length units (1/0.45 in)")
    height_m: float             # the body's height at the scale read
    g_fixed: float              # the apparent gravity after the fix

    def _parts(self, fps_fmt: str, scale_fmt: str) -> list[str]:
        return ([fps_fmt.format(self.fps)] if self.fps is not None else []) + \
               ([scale_fmt.format(self.scale)] if self.scale is not None else [])

    def options(self) -> str:
        """The fix as command-line options (``--fps 60 --scale 0.0564``)."""
        return " ".join(self._parts("--fps {:g}", "--scale {:.4g}"))

    def keys(self) -> str:
        """The fix as design keys (``fps = 60``, ``scale = 0.0564``)."""
        return ", ".join(self._parts("fps = {:g}", "scale = {:.4g}"))


def physics_advice(g_app: float | None, clip: Clip) -> PhysicsAdvice | None:
    """Weigh frame time against length scale; None when the clip agrees with physics.

    Two measurements that do not share an assumption: the body's height from the
    skeleton (lengths only) and the apparent gravity of the flight (lengths / time²).
    A height outside :data:`BODY_HEIGHT_RANGE` means the length scale is wrong; the
    scale that makes the body an adult (the file unit closest to 1.70 m, as
    ``load_bvh`` guesses it) is proposed, and gravity is judged after that fix
    (gravity is proportional to the scale).  Whatever gravity is still off is the
    frame time: a factor of two when one fits (frame-time errors are), else the
    exact rate.  ``g_app`` None (no flight): the height alone is judged.
    """
    from .motion.bvh import STANDING_HEIGHT_M, UNIT_CANDIDATES
    fps = float(clip.meta.get("fps_read", clip.fps))       # the rate the file was read at
    scale = float(clip.meta.get("scale", 1.0))
    h = body_height(clip)
    lo, hi = BODY_HEIGHT_RANGE
    new_scale = unit = None
    problem = []
    g = g_app
    if not lo <= h <= hi:
        extent_file = h / scale
        s_new, unit = min(UNIT_CANDIDATES, key=lambda u: abs(np.log(extent_file * u[0] / STANDING_HEIGHT_M)))
        if not lo <= extent_file * s_new <= hi:            # no unit fits: make it 1.70 m
            s_new, unit = STANDING_HEIGHT_M / extent_file, "a 1.70 m body"
        new_scale = s_new
        problem.append(f"the body is {h:.2f} m tall at {scale:.4g} m per file unit (its skeleton), "
                       f"not an adult's {lo:g}–{hi:g} m: the length scale is wrong (at {s_new:.4g}, {unit}, it is "
                       f"{extent_file * s_new:.2f} m).")
        if g is not None:
            g = g * s_new / scale
    new_fps = None
    if g is not None and abs(g / G - 1.0) > GRAVITY_TOLERANCE:
        head = (f"apparent gravity in flight is {g_app:.1f} m/s², not 9.81"
                + (f" ({g:.1f} at the right scale)" if new_scale is not None else "") + ": ")
        if g <= 0:
            problem.append(head + "the flight does not fall; the clip's time axis is wrong.")
        else:
            factor = lambda f: abs(np.log(g * (f / fps) ** 2 / G))    # noqa: E731
            best = min((fps * 2.0 ** k for k in (-2, -1, 1, 2)), key=factor)
            g_best = g * (best / fps) ** 2
            if abs(g_best / G - 1.0) <= GRAVITY_TOLERANCE:
                problem.append(head + f"at {best:g} fps instead of {fps:g} it would be {g_best:.1f} "
                               f"m/s², so the frame time is wrong (header says "
                               f"{clip.meta.get('header_fps', fps):g} fps).")
                new_fps, g = best, g_best
            else:
                # no factor of two is enough: the lengths are scaled too (a retargeted or
                # resized skeleton) if the body stays an adult at the scale that fixes
                # gravity; else the frame time is simply another rate
                near = min((fps * 2.0 ** k for k in (-2, -1, 0, 1, 2)), key=factor)
                g_near = g * (near / fps) ** 2
                s_fix = G / g_near
                h_now = h if new_scale is None else h * new_scale / scale
                if lo <= h_now * s_fix <= hi:
                    new_scale = (new_scale if new_scale is not None else scale) * s_fix
                    unit = "lengths scaled to make gravity 9.81"
                    new_fps = near if near != fps else None
                    at = f"at {near:g} fps it would be {g_near:.1f} m/s², still" if new_fps else "that is"
                    problem.append(head + f"{at} {100 * (g_near / G - 1):+.0f} % off, so the lengths "
                                   f"are probably scaled too (a retargeted or resized skeleton; at "
                                   f"{new_scale:.4g} m per file unit the body is {h_now * s_fix:.2f} m, "
                                   f"still an adult).")
                else:
                    new_fps = float(np.round(fps * np.sqrt(G / g), 2))
                    problem.append(head + f"the body's height ({h_now:.2f} m) rules out a scale "
                                   f"error, so the frame rate is {new_fps:g} fps, not {fps:g}.")
                g = G
    if not problem:
        return None
    return PhysicsAdvice(" ".join(problem), new_fps, new_scale, unit, h,
                         float("nan") if g is None else float(g))


def gravity_warning(g_app: float, clip: Clip) -> str | None:
    """A sentence when the apparent gravity or the body's height contradicts
    physics, naming the fix (``--fps`` and/or ``--scale``) that the body's height
    picks: a height outside an adult's says the scale is wrong, gravity that
    is still off after that says the frame time is (see :func:`physics_advice`)."""
    adv = physics_advice(g_app, clip)
    if adv is None:
        return None
    fix = adv.options()
    if adv.scale is not None and clip.meta.get("scale_source") == "given" and \
            adv.scale_unit and "1.70 m" not in adv.scale_unit:
        fix += " (or without --scale: it is guessed from the skeleton)"
    return f"{adv.problem} Rerun with {fix}." if fix else adv.problem


def flight_breaks(flights) -> list[int]:
    """The phase starts of :func:`flipstudy.stimuli.physics.momentum` for these flights."""
    return sorted({b for f in flights for b in (f.takeoff, f.landing + 1)})


def analyse(clip: Clip, body: Body | None = None, total_mass: float = 70.0,
            estimate: bool = True, W: float = DEFAULT_W) -> Analysis:
    """Flight analysis of one clip.

    Parameters
    ----------
    clip : Clip
        The motion, in metres.
    body : Body, optional
        The segment model; default ``Body.from_clip(clip, total_mass)`` (trunk and
        head measured on the clip's poses).
    total_mass : float, default 70.0
        Kilograms, for the default body.
    estimate : bool, default True
        Estimate segment masses from the flight (Section 4.2) and use them for
        the momenta; with ``False`` the given/table masses are used.
    W : float
        Regularisation weight of the mass fit, W‖m − m⁰‖² (m²/kg²; see
        ``flipstudy.stimuli.massfit.DEFAULT_W``).

    Returns
    -------
    Analysis
        Centre of mass, momenta and the flight phases (``takeoff``, ``landing``,
        ``takeoff_time``, ``landing_time``, ``takeoff_angle``).

    Examples
    --------
    >>> from flipstudy import analyse, builtin
    >>> a = analyse(builtin("backflip"))
    >>> a.takeoff, a.landing, round(a.takeoff_angle)            # frames inside the flight, degrees
    (157, 237, 82)
    >>> a.takeoff_time, round(a.landing_time, 4)                # the contact instants, seconds
    (1.3, 1.9833)
    >>> a.com.shape == a.L.shape == (a.clip.num_frames, 3)
    True
    """
    body0 = body if body is not None else Body.from_clip(clip, total_mass)
    m0: Momentum = momentum(clip, body0)
    flights = detect_flights(clip, body0, m0.com)
    warnings = list(clip.meta.get("warnings", []))
    fit = None
    final_body, m = body0, m0
    if flights and estimate:
        f = flights[0]
        # the fit leaves out the flight's first and last frame: on a capture the contact
        # instants are known to about a frame (88_01's take-off: instant at 45.0, feet 2 cm
        # up at 47), and a frame still pushed would be fitted as mass; 87_03's fit stays
        # within the band only without them (foot −35 % with, −10 % without)
        k = 1 if f.frames >= 10 else 0
        fit = estimate_masses(clip, body0, f.takeoff + k, f.landing - k, W=W)
        final_body = fit.body
    if flights:
        m = momentum(clip, final_body, flight_breaks(flights))
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
