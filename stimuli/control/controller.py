"""Standing jumps to a target by the energy-based controller of Ooi 2016 (3.6),
written as keyframed clips — with a landing, which the thesis left out.

:func:`jump` plans the jump on its course (:mod:`.course`: where it starts and
ends, the boxes around), makes the stages meet (:mod:`.planning`), builds its frames
stage by stage — stand, windup, thrust, flight, landing (:mod:`.stages`) — and
checks them (:mod:`.checks`: ray casts for the touch-down, collisions, the feet
in the windup, the landing point).  It returns a :class:`JumpResult`: the clip
(whose ``meta`` says how it was made), its flight frames, the plan and a typed
:class:`JumpReport` of what was planned and measured.

>>> res = jump((0, 0, 1.3), fps=30)
>>> res.takeoff <= res.landing < res.report.touchdown
True
>>> res.clip.meta["source"], res.clip.meta["scene"], res.report.landing_error_m < 0.05
('control', 'forward', True)
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..edit.report import Report
from flipstudy.errors import FlipstudyValueError
from ..motion.clip import Clip
from ..result import Result
from .checks import CHECKED
from .checks import check as check_jump
from .course import Course, make_course
from .model import Jumper
from .muscles import MUSCLES, STRENGTH, parse_k
from .path import gravity_vector, kinetic_energy
from .planning import Plan, plan
from .stages import T_CROUCH, build


@dataclass(kw_only=True)
class JumpReport(Report):
    """What :func:`jump` planned, built and measured.  :meth:`to_dict` gives the
    keys of ``flipstudy jump --json``; the fields the checks fill
    (:func:`.checks.check`) are ``None`` with ``check=False``.

    Lengths in metres, times in seconds, velocities m/s, energies J, spring
    constants in the thesis's units; ``scene`` is the course's name.

    Attributes
    ----------
    scene : str
    start, target, landing_point : list of float
        The feet's midpoint at the start, planned and measured at the landing.
    landing_error_m : float or None
    t_air, t_windup : float
    v0, a, displacement : list of float
        The path (3.5.1).
    E_k, E_el_crouch, E_land, E_el_landing : float
        Kinetic energy at take-off and elastic energy stored in the crouch; the same at landing.
    takeoff, touchdown : int
        The first frames at or after the take-off and touch-down instants.

    The other fields are listed with their comments in the source.

    Examples
    --------
    >>> rep = jump((0, 0, 1.3), fps=30).report
    >>> rep.scene, rep.target, rep.E_el_crouch >= 0.95 * rep.E_k
    ('forward', [0.0, 0.0, 1.3], True)
    >>> "landing_error_m" in rep.to_dict()
    True
    """

    scene: str
    start: list
    target: list
    #: where the feet's midpoint landed (checks) and how far from ``target``
    landing_point: list | None
    landing_error_m: float | None
    t_air: float
    t_windup: float
    #: the path (3.5.1): take-off velocity, thrust acceleration, COM displacement
    v0: list
    a: list
    displacement: list
    #: kinetic energy at take-off, elastic energy stored in the crouch; the same at landing
    E_k: float
    E_el_crouch: float
    E_land: float
    E_el_landing: float
    landing_energy_met: bool
    k: list
    k_used: list
    strength: float
    #: the crouch's pelvis (from the feet's midpoint) and the upper body's lean there
    crouch_pelvis: list
    crouch_lean_deg: list
    #: the first frames at or after the take-off and touch-down instants, and the instants
    takeoff: int
    touchdown: int
    takeoff_s: float
    touchdown_s: float
    windup_foot_motion_m: float | None
    obstacle_clearance_m: float | None
    windup_iterations: int
    energy_met_at_iteration: int | None
    build_s: float
    crouch_time: float
    absorb_s: float
    v_land: list
    #: first and last frames of the windup and of the thrust
    windup_frames: list
    thrust_frames: list
    #: crouches that met the windup's criteria, rounds of the plan's fixed point
    candidates: int
    plan_iterations: int
    ik_error_mm: float
    #: checks: the touch-down frame the ray casts found, the lowest sole (m
    #: above its surface), the balls of the feet's motion in the thrust, the
    #: lowest sole in the windup
    touchdown_detected: int | None
    lowest_sole_gap_m: float | None
    thrust_ball_motion_m: float | None
    windup_lowest_sole_m: float | None


@dataclass
class JumpResult(Result[JumpReport]):
    """The jump's clip, its flight (``takeoff`` and ``landing``: the first and
    last frames strictly inside it), its typed report and the plan it was
    built from.

    Attributes
    ----------
    clip : Clip
    takeoff, landing : int
    report : JumpReport
    plan : Plan

    Examples
    --------
    >>> res = jump((0, 0, 1.3), fps=30)
    >>> res.clip.fps, res.takeoff < res.landing, res.plan.iterations > 0
    (30.0, True, True)
    """

    clip: Clip
    takeoff: int
    landing: int
    report: JumpReport
    plan: Plan


def jump(target=None, *, course: str | Course = "forward", t_air: float | None = None,
         t_windup: float | None = None,
         k="global-normal", strength: float = STRENGTH, g=9.81, mass: float = 70.0, height: float = 1.75,
         fps: float = 120.0, crouch_time: float = T_CROUCH, check: bool = True) -> JumpResult:
    """A standing jump to ``target`` (the feet's landing midpoint, metres; default
    the course's) by the energy-based controller, as a clip.

    ``course``: a :class:`~.course.Course` or the name of one of Chapter 5's
    scenes (:data:`~.course.COURSES`, :func:`~.course.make_course`).
    ``k``: a Table 5.1 preset name, one number or six (left hip, knee, ankle,
    right hip, knee, ankle), in the thesis's units; the springs used are
    ``strength`` × k (default :data:`STRENGTH`; ``strength=1`` is the thesis's
    literal constants, which with the corrected angle cannot store a 1 m jump).
    ``t_air`` defaults to the course's (0.5 s; 0.9 s for ``over``).
    ``check=False`` skips the checks of the built frames (:mod:`.checks`).

    Raises ``ValueError`` naming the parameter for bad input and saying what
    to change for an unreachable target.

    Parameters
    ----------
    target : sequence of 3 float, optional
    course : str or Course
    t_air, t_windup, crouch_time : float, optional
        Seconds in the air, of the windup and of the crouch.
    k : str, float or sequence of 6 float
    strength, mass, height, fps : float
    g : float or sequence of 3 float
    check : bool

    Returns
    -------
    JumpResult

    Examples
    --------
    >>> res = jump((0, 0, 1.3), fps=30)
    >>> res.report.landing_error_m < 0.05, res.clip.meta["scene"]
    (True, 'forward')
    >>> jump((0, 0, 1.3), t_air=-1)
    Traceback (most recent call last):
    ...
    flipstudy.errors.FlipstudyValueError: air: expected a positive time in seconds, got -1
    """
    t0 = time.perf_counter()
    if isinstance(course, Course):
        sc = course if target is None else course.with_target(target)
    else:
        sc = make_course(course, target=target)
    t_air = sc.t_air if t_air is None else t_air
    t_windup = sc.t_windup if t_windup is None else t_windup
    for name, v in (("air", t_air), ("windup", t_windup), ("crouch_time", crouch_time)):
        if not (isinstance(v, (int, float, np.number)) and np.isfinite(v) and v > 0):
            raise FlipstudyValueError(f"{name}: expected a positive time in seconds, got {v!r}")
    if not (isinstance(fps, (int, float, np.number)) and np.isfinite(fps) and 30 <= fps <= 1000):
        raise FlipstudyValueError(f"fps: expected 30–1000 frames per second, got {fps!r}")
    if not (np.isfinite(strength) and strength > 0):
        raise FlipstudyValueError(f"strength: expected a positive factor on k, got {strength!r}")
    k_table = parse_k(k)
    k_eff = k_table * float(strength)
    jumper = Jumper(height, mass)
    gv = gravity_vector(g)
    pl = plan(jumper, sc, k_eff, float(t_air), float(t_windup), gv)
    fps, T_c = float(fps), float(crouch_time)
    st = build(jumper, sc, pl, k_eff, fps, T_c)
    path, ap = pl.path, pl.approach
    # provenance: what the clip was made from (what was measured is in the report)
    meta = {"name": f"jump_{sc.name}", "source": "control", "scene": sc.name,
            "start": list(map(float, sc.start)), "target": list(map(float, sc.target)),
            "boxes": [b.to_list() for b in sc.boxes], "g": float(-path.g[1]),
            "total_mass": jumper.mass, "height": jumper.height,
            "t_air": path.t_air, "t_windup": path.t_windup, "crouch_time": T_c,
            "k": k_table.tolist(), "k_used": k_eff.tolist(), "strength": float(strength),
            "muscles": list(MUSCLES), "warnings": []}
    clip = jumper.clip(st.root, st.quats, fps, meta)
    checks = check_jump(jumper, sc, clip, st) if check else dict.fromkeys(CHECKED)
    report = JumpReport(
        scene=sc.name, start=list(meta["start"]), target=list(meta["target"]),
        t_air=path.t_air, t_windup=path.t_windup,
        v0=path.v0.tolist(), a=path.a.tolist(), displacement=path.displacement.tolist(),
        E_k=kinetic_energy(jumper.mass, path.v0), E_el_crouch=float(ap.energy[-1]),
        E_land=kinetic_energy(jumper.mass, path.v_land), E_el_landing=pl.landing.energy,
        landing_energy_met=pl.landing.satisfied, k=k_table.tolist(), k_used=k_eff.tolist(),
        strength=float(strength), crouch_pelvis=pl.crouch_pelvis.tolist(),
        crouch_lean_deg=np.degrees(pl.crouch_lean).tolist(), takeoff=st.takeoff, touchdown=st.touchdown,
        takeoff_s=st.takeoff_s, touchdown_s=st.touchdown_s, windup_iterations=len(ap.pelvis) - 1,
        energy_met_at_iteration=ap.energy_met_at, crouch_time=T_c, absorb_s=float(pl.absorb_time),
        v_land=path.v_land.tolist(), windup_frames=st.windup_frames, thrust_frames=st.thrust_frames,
        candidates=pl.windup.candidates, plan_iterations=pl.iterations, ik_error_mm=st.ik_error_mm,
        build_s=time.perf_counter() - t0, **checks)
    return JumpResult(clip, st.takeoff, st.touchdown - 1, report, pl)


__all__ = ["STRENGTH", "JumpReport", "JumpResult", "jump"]
