"""The courses of the jumps (Ooi 2016, Chapter 5): where a jump starts and
ends and the boxes around it, as the controller plans them and the renderer
draws them (the boxes).  The thesis calls them scenes; so does the CLI's
``--scene``.  (What is drawn, the camera, lights and actors, is a
:class:`flipstudy.render.scene.Scene`.)
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from flipstudy.errors import FlipstudyValueError

#: the scenes of Chapter 5, by name (:func:`make_course`)
COURSES = ("forward", "sideways", "box", "over")


@dataclass(frozen=True)
class Box:
    """An axis-aligned box (metres): corners ``lo`` and ``hi``.

    Attributes
    ----------
    lo, hi : tuple of float
        The lowest and the highest corner, metres.

    Examples
    --------
    >>> b = Box((0.0, 0.0, 0.0), (1.0, 0.5, 1.0))
    >>> b.contains(np.array([[0.5, 0.2, 0.5], [0.5, 0.7, 0.5]])).tolist(), b.to_list()[1]
    ([True, False], [1.0, 0.5, 1.0])
    """

    lo: tuple
    hi: tuple

    def contains(self, pts: np.ndarray, margin: float = 0.0) -> np.ndarray:
        p = np.asarray(pts, float)
        return np.all((p > np.asarray(self.lo) + margin) & (p < np.asarray(self.hi) - margin), axis=-1)

    def to_list(self) -> list:
        return [list(map(float, self.lo)), list(map(float, self.hi))]


@dataclass(frozen=True)
class Course:
    """The course of a jump: where it starts and ends and the boxes that stand
    around (to land on or to clear), with the jump's defaults there (``tuck``,
    ``t_air``, ``t_windup``).  ``start`` and ``target`` are the feet's midpoint
    (between the ankles, on the surface); ``name`` is the scene's (Chapter 5,
    the CLI's ``--scene``).

    Attributes
    ----------
    name : str
    start, target : tuple of float
        The feet's midpoint at the start and at the landing, metres.
    boxes : tuple of Box
    tuck, t_air, t_windup : float
        The jump's defaults on this course (seconds for the times).

    Examples
    --------
    >>> c = make_course("box")
    >>> c.name, c.target, c.boxes[0].hi
    ('box', (0.0, 0.5, 0.8), (0.5, 0.5, 1.3))
    >>> c.surface(np.array([[0.0, 0.8], [0.0, 2.0]])).tolist()    # on the box, beyond it
    [0.5, 0.0]
    >>> c.with_target((0.0, 0.5, 1.0)).target
    (0.0, 0.5, 1.0)
    """

    name: str
    start: tuple
    target: tuple
    boxes: tuple = ()
    tuck: float = 0.3
    t_air: float = 0.5
    t_windup: float = 0.2

    def surface(self, xz: np.ndarray) -> np.ndarray:
        """Height (N,) of the surface under ground points (N,2) x, z: the
        highest box top containing them, else the floor (0)."""
        xz = np.atleast_2d(xz)
        h = np.zeros(xz.shape[0])
        for b in self.boxes:
            m = ((xz[:, 0] >= b.lo[0]) & (xz[:, 0] <= b.hi[0]) &
                 (xz[:, 1] >= b.lo[2]) & (xz[:, 1] <= b.hi[2]))
            h = np.where(m, np.maximum(h, b.hi[1]), h)
        return h

    def with_target(self, target) -> "Course":
        """The same course landing at ``target`` (x, y, z), which must be on a
        surface (y its height there)."""
        t = np.asarray(target, float)
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise FlipstudyValueError(f"to: expected X,Y,Z in metres, got {target!r}")
        course = replace(self, target=tuple(map(float, t)))
        check_surface(course, "to", course.target)
        return course


def make_course(name: str = "forward", distance: float | None = None, box_height: float | None = None,
                target=None) -> Course:
    """The course of one of the scenes of Chapter 5 (:data:`COURSES`).

    ``forward``  jump ``distance`` (1.0 m) along +Z (the facing direction);
    ``sideways`` jump ``distance`` (1.0 m) to the right (−X) without turning;
    ``box``      onto a box ``box_height`` (0.5 m) high, 1 m wide, 0.8 m deep,
                 its front 0.5 m ahead of the ankles (Fig. 5.2 puts it "0.75 m
                 in front"), landing 0.8 m ahead on its top; thrust 0.15 s
                 (with 0.2 s the 0.75 m box needs a crouch deeper than the
                 balanced region allows);
    ``over``     from standing on a 1 m box, over a 1.4 m obstacle (0.2 m
                 deep, 1.0–1.2 m ahead), landing on the floor 2.4 m ahead
                 (Fig. 5.1); flight 0.9 s (a 0.5 s flight cannot clear it).

    ``target`` (x, y, z) overrides the landing point (y must be the height of
    the surface there).

    Parameters
    ----------
    name : str
        One of :data:`COURSES`.
    distance, box_height : float, optional
        Metres (defaults above).
    target : tuple of float, optional

    Returns
    -------
    Course

    Examples
    --------
    >>> c = make_course("forward", distance=1.5)
    >>> c.start, c.target
    ((0.0, 0.0, 0.0), (0.0, 0.0, 1.5))
    """
    if name not in COURSES:
        raise FlipstudyValueError(f"scene: expected one of {', '.join(COURSES)}, got {name!r}")
    if distance is not None and not (np.isfinite(distance) and distance > 0):
        raise FlipstudyValueError(f"distance: expected a positive number of metres, got {distance!r}")
    if name == "forward":
        sc = Course("forward", (0.0, 0.0, 0.0), (0.0, 0.0, float(distance or 1.0)), tuck=0.8)
    elif name == "sideways":
        sc = Course("sideways", (0.0, 0.0, 0.0), (-float(distance or 1.0), 0.0, 0.0), tuck=0.8)
    elif name == "box":
        h = float(0.5 if box_height is None else box_height)
        if not (0.1 <= h <= 1.2):
            raise FlipstudyValueError(f"box_height: expected 0.1–1.2 m, got {box_height!r}")
        sc = Course("box", (0.0, 0.0, 0.0), (0.0, h, 0.8), (Box((-0.5, 0.0, 0.5), (0.5, h, 1.3)),),
                    tuck=1.0, t_windup=0.15)
    else:
        sc = Course("over", (0.0, 1.0, 0.0), (0.0, 0.0, 2.4),
                    (Box((-0.5, 0.0, -0.6), (0.5, 1.0, 0.35)), Box((-0.6, 0.0, 1.0), (0.6, 1.4, 1.2))),
                    tuck=1.0, t_air=0.9)
    check_surface(sc, "start", sc.start)
    return sc if target is None else sc.with_target(target)


def check_surface(sc: Course, what: str, p) -> None:
    """Refuse a point ``p`` (x, y, z) of the course that is not on a surface,
    naming the option (``what``) to change."""
    h = float(sc.surface(np.array([[p[0], p[2]]]))[0])
    if abs(h - p[1]) > 0.01:
        raise FlipstudyValueError(f"{what}: there is no surface at height {p[1]:g} m under x={p[0]:g}, "
                                  f"z={p[2]:g} in the {sc.name!r} scene (the surface there is at {h:g} "
                                  f"m); give Y = {h:g}" + (" or use --scene box" if sc.name != "box" else ""))


__all__ = ["COURSES", "Box", "Course", "make_course", "check_surface"]
