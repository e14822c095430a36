"""The staging object: clips placed under one camera, with everything a picture needs.

Majkowska & Faloutsos (2007, Section 7): "All animations were rendered in the
same style with the same camera configuration and the same take-off position."
:func:`stage` does both: it moves every clip horizontally so that its take-off
centre of mass is at the origin, then fits one side-view camera that keeps every
frame of every clip in the picture.  What it returns, a :class:`Stage`, is what
every image function of :mod:`flipstudy.render` draws: the placed clips, their
bodies and flights, the camera, the image size, the :class:`~flipstudy.render.style.Style`,
the ground and the boxes standing on it.  Made once, it is passed to each of
``render_video``, ``ghost_image``, ``trail_image``, ``strip_image``,
``composite_image`` and ``overlay_image``; those functions also take a bare
clip and stage it with the defaults.

The take-off spot is the COM in the *last frame on the ground* (``takeoff − 1``,
the first airborne frame being ``takeoff``): edits of the flight may already
change the first airborne frame (a retimed flight samples it between source
frames), and the anchor must not move with the edit, or stimuli of one base
clip would no longer match before take-off.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from flipstudy.stimuli.body import Body
from flipstudy.errors import FlipstudyValueError
from flipstudy.stimuli.motion.clip import Clip

from .camera import Camera, fit_camera, recentre, view_basis
from .geometry import body_points
from .placement import (align_takeoff, base_clip_groups, jump_direction,  # noqa: F401
                        nearest_axis, orient_yaws, place, takeoff_com, translate, travel_direction)
from .style import DEFAULT_STYLE, Style


@dataclass(eq=False)
class Framing:
    """How a fitted camera frames a stage: it looks across the horizontal
    ``direction`` of travel from ``elevation`` degrees up, with a vertical view
    of ``view_angle`` degrees, and keeps ``points`` (N,3) inside the picture with
    ``margin`` (a fraction of the width and height) on each side.  A stage keeps
    its framing so that another image size gets the camera fitted again, to the
    same points (see :meth:`Stage.resized`).

    Parameters
    ----------
    points : ndarray, shape (N, 3)
    direction : ndarray, shape (3,)
    view_angle, elevation : float
        Degrees.
    margin : float

    Examples
    --------
    >>> import numpy as np
    >>> from flipstudy.render import Framing
    >>> f = Framing(np.zeros((1, 3)), np.array([0.0, 0.0, 1.0]))
    >>> f.view_angle, f.elevation
    (25.0, 8.0)
    """

    points: np.ndarray = field(repr=False)
    direction: np.ndarray
    view_angle: float = 25.0
    elevation: float = 8.0
    margin: float = 0.06
    #: points per motion (``points`` is their concatenation, in order): given, the
    #: camera fitted to the union is moved to centre the motions as a family
    #: (:func:`~flipstudy.render.camera.recentre`, keeping a third of ``margin``)
    parts: tuple = ()

    def camera(self, size) -> Camera:
        """The camera of this framing for an image of ``size`` (w, h)."""
        cam = fit_camera(self.points, self.direction, size, view_angle=self.view_angle,
                         elevation=self.elevation, margin=self.margin)
        if len(self.parts) > 1:
            groups = np.split(self.points, np.cumsum(self.parts)[:-1])
            cam = recentre(cam, groups, size, floor=self.margin / 3.0)
        return cam

    def ground(self, camera: Camera, margin: float) -> tuple:
        """Ground bounds (x0, x1, z0, z1): the framed points, ``margin`` metres
        and half the camera's distance around them."""
        lo, hi = self.points.min(0), self.points.max(0)
        g = float(margin) + 0.5 * camera.distance
        return (lo[0] - g, hi[0] + g, lo[2] - g, hi[2] + g)


def ground_around(clips, bodies, margin: float, camera: Camera) -> tuple:
    """Ground bounds (x0, x1, z0, z1) around the bodies of ``clips`` (every
    fourth frame), ``margin`` metres and half the camera's distance around them:
    the ground of clips drawn under a given camera."""
    pts = np.concatenate([body_points(c, b, (6, 3), slice(None, None, 4)).reshape(-1, 3)
                          for c, b in zip(clips, bodies)])
    lo, hi = pts.min(0), pts.max(0)
    g = margin + 0.5 * camera.distance
    return (lo[0] - g, hi[0] + g, lo[2] - g, hi[2] + g)


@dataclass(eq=False)
class Stage:
    """Clips placed under one camera, with what a picture of them needs.

    One entry per clip in ``clips`` (placed: moved to the take-off spot and
    turned, see :func:`stage`), ``bodies`` (the :class:`flipstudy.stimuli.Body`
    drawn), ``takeoffs`` and ``landings`` (the flight's frames, or ``None``);
    then for the picture the ``camera``, the image ``size`` (w, h) in pixels,
    the ``style``, the ground (``ground``: bounds (x0, x1, z0, z1) given, or
    ``None`` to fit them; the bounds in use are :attr:`ground_bounds`) and the
    ``boxes`` standing on it (``[(lo, hi), ...]`` corners in metres, in the
    stage's coordinates).  How :func:`stage` placed the clips: ``offsets`` (K,3)
    metres, then ``yaws`` degrees about the vertical, and the jump
    ``direction`` the camera looks across; ``framing`` (:class:`Framing`) is how
    the camera was fitted, ``None`` for a camera that was given.

    Parameters
    ----------
    clips, bodies : list
        The placed clips and the bodies drawn.
    takeoffs, landings : list of int or None
    camera : Camera
    size : tuple of int
        (width, height) in pixels.
    style : Style, optional
    ground : tuple of float, optional
        (x0, x1, z0, z1) metres.
    boxes : list of (lo, hi)
    offsets : ndarray, shape (K, 3), optional
    yaws : list of float, optional
    direction : ndarray, shape (3,), optional
    framing : Framing, optional

    Examples
    --------
    >>> from flipstudy import builtin
    >>> st = stage([builtin("backflip"), builtin("frontflip")], size=(320, 240))
    >>> one = st.only(1)                                  # the front flip, same camera
    >>> one.clips[0] is st.clips[1], one.camera == st.camera, one.yaws
    (True, True, [-160.0])
    >>> st.resized((160, 240)).camera.position == st.camera.position   # fitted again
    False
    """

    clips: list
    bodies: list
    takeoffs: list
    landings: list
    camera: Camera
    size: tuple = (640, 480)
    style: Style | None = None
    ground: tuple | None = None
    boxes: list = field(default_factory=list)
    offsets: np.ndarray | None = None
    yaws: list | None = None
    direction: np.ndarray | None = None
    framing: Framing | None = None

    def __post_init__(self):
        self.clips, self.bodies = list(self.clips), list(self.bodies)
        self.takeoffs, self.landings = list(self.takeoffs), list(self.landings)
        n = len(self.clips)
        if n == 0:
            raise FlipstudyValueError("Stage: no clips")
        if not len(self.bodies) == len(self.takeoffs) == len(self.landings) == n:
            raise FlipstudyValueError(
                f"Stage: {n} clip(s) but {len(self.bodies)} bodies, {len(self.takeoffs)} take-offs "
                f"and {len(self.landings)} landings (one of each per clip)")
        self.size = (int(self.size[0]), int(self.size[1]))
        self.style = self.style or DEFAULT_STYLE
        self.boxes = list(self.boxes)
        self.offsets = np.zeros((n, 3)) if self.offsets is None else np.asarray(self.offsets, float)
        self.yaws = [0.0] * n if self.yaws is None else list(self.yaws)

    @cached_property
    def ground_bounds(self) -> tuple:
        """(x0, x1, z0, z1) of the ground: the given ``ground``, else fitted
        around the framed points (a fitted camera) or the clips' bodies (a given one)."""
        if self.ground is not None:
            return tuple(self.ground)
        if self.framing is not None:
            return self.framing.ground(self.camera, self.style.ground_margin)
        return ground_around(self.clips, self.bodies, self.style.ground_margin, self.camera)

    def __repr__(self) -> str:
        names = ", ".join(repr(c.meta.get("name", "?")) for c in self.clips)
        how = "fitted" if self.framing is not None else "given"
        return f"Stage([{names}], size={self.size[0]}x{self.size[1]}, {how} camera)"

    def only(self, *which: int) -> "Stage":
        """The stage with only the clips ``which`` (indices), under the same
        camera, on the same ground."""
        if not which:
            raise FlipstudyValueError("Stage.only: name at least one clip")
        ks = [int(k) for k in which]
        pick = lambda xs: [xs[k] for k in ks]  # noqa: E731
        return replace(self, clips=pick(self.clips), bodies=pick(self.bodies),
                       takeoffs=pick(self.takeoffs), landings=pick(self.landings),
                       offsets=self.offsets[ks], yaws=pick(self.yaws), ground=self.ground_bounds)

    def refit(self, *which: int) -> "Stage":
        """The stage with only the clips ``which`` (indices), under a camera
        fitted to their bodies alone (the same view direction, angle, elevation
        and margin), on the same ground: one camera per base clip, fitted to
        the union of that clip's stimuli (see :func:`base_clip_groups`), so
        each base clip's action is centred and fills the frame.

        Examples
        --------
        >>> from flipstudy import builtin
        >>> st = stage([builtin("backflip"), builtin("frontflip")], size=(320, 240))
        >>> st.refit(0).camera == st.camera, st.refit(0).clips[0] is st.clips[0]
        (False, True)
        """
        if self.framing is None:
            raise FlipstudyValueError("Stage.refit: the stage's camera was given, not fitted")
        one = self.only(*which)
        basis = view_basis(self.framing.direction, self.framing.elevation)
        each = [_extremes(body_points(c, b), basis).reshape(-1, 3)
                for c, b in zip(one.clips, one.bodies)]
        framing = replace(self.framing, points=np.concatenate(each),
                          parts=tuple(len(p) for p in each))
        return replace(one, camera=framing.camera(self.size), framing=framing)

    def resized(self, size) -> "Stage":
        """The stage for an image of another ``size`` (w, h): a fitted camera is
        fitted again to the same points (and a fitted ground with it), a given
        camera is kept."""
        size = (int(size[0]), int(size[1]))
        if size == self.size:
            return self
        if self.framing is None:
            return replace(self, size=size)
        return replace(self, size=size, camera=self.framing.camera(size))

    def with_camera(self, camera: Camera) -> "Stage":
        """The stage under another camera (e.g. one that follows the action):
        a fitted ground is fitted again around the clips, a given one is kept."""
        return replace(self, camera=camera, framing=None)

    def to_dict(self) -> dict:
        d = None if self.direction is None else [float(v) for v in self.direction]
        return {"camera": self.camera.to_dict(), "direction": d,
                "ground_bounds": [float(v) for v in self.ground_bounds], "size": list(self.size),
                "offsets": [[float(v) for v in o] for o in self.offsets],
                "yaws_deg": [float(v) for v in self.yaws],
                "takeoffs": list(self.takeoffs), "landings": list(self.landings)}


#: Degrees :func:`stage` turns the clips about the vertical beyond travelling along
#: the ground axis the camera looks across: the travel then goes that much away from
#: the camera, and the camera sees the motion three-quarter.  Square to the side of a
#: flip the camera looks along the axis the body turns about, so mid-flight the far
#: arm and leg hide behind the near ones and the trunk: measured on rendered pixels
#: (far limbs in colours of their own, tests/render/test_far_limbs.py), over the
#: middle third of the flight the far leg showed 4–9 % of its picture in the built-in
#: backflip and frontflip and in CMU 88_01 (60 fps).  Turned 20° it shows 25–41 %
#: (arm and leg together 26–37 %, square 6–8 %); 15° left the frontflip's far leg at
#: 18 %; at 20° the travel's depth is a third of its length (sin 20°), going away.  The camera is not
#: turned instead: the ground stays axis-aligned and square to it, its far edge (the
#: horizon) level.
THREE_QUARTER_DEG = 20.0


def _half_open(deg: float) -> float:
    """``deg`` in (−180, 180]."""
    d = (float(deg) + 180.0) % 360.0 - 180.0
    return 180.0 if d <= -180.0 + 1e-9 else d


_DIRS = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)
                  if (i, j, k) != (0, 0, 0)], float)


def _extremes(points: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """(F,26,3): per frame, the points (F,N,3) farthest along 26 directions of
    the camera ``basis`` (rows right, up, back) — the few points that decide
    whether a frame fits the picture."""
    proj = np.einsum("fnc,dc->fdn", points, _DIRS @ basis)
    idx = proj.argmax(-1)                                          # (F,26)
    return np.take_along_axis(points, idx[..., None], axis=1)


def _bodies_for(clips, bodies):
    if bodies is not None:
        return list(bodies)
    cache: dict = {}
    out = []
    for c in clips:
        key = id(c.skeleton)
        if key not in cache:
            cache[key] = Body.from_clip(c)
        out.append(cache[key])
    return out


def _placed_boxes(boxes, clip: Clip, placed: Clip) -> list:
    """Boxes (lo, hi) moved like ``clip`` was when placed (a translation)."""
    if not boxes:
        return []
    o = placed.root_pos[0] - clip.root_pos[0]
    return [(np.asarray(lo, float) + o, np.asarray(hi, float) + o) for lo, hi in boxes]


def _flight_frames(clips, bodies, takeoffs, landings) -> tuple[list, list]:
    """Each clip's take-off and landing frame (int or None): as given, else what
    :func:`flipstudy.stimuli.analyse` finds."""
    if takeoffs is None or landings is None:
        from flipstudy.stimuli import analyse
        found = [analyse(c, body=b, estimate=False) for c, b in zip(clips, bodies)]
        takeoffs = [a.takeoff for a in found] if takeoffs is None else takeoffs
        landings = [a.landing for a in found] if landings is None else landings
    return ([None if t is None else int(t) for t in takeoffs],
            [None if t is None else int(t) for t in landings])


def _oriented(placed, bodies, takeoffs, landings, direction, *, orient: bool, boxes,
              turn: float | None) -> tuple[list, list, np.ndarray]:
    """The step of :func:`stage` that turns the placed clips: (clips, yaws in degrees,
    the horizontal direction the camera looks across)."""
    auto = direction is None
    if direction is None:
        direction = jump_direction(placed[0], bodies[0], takeoffs[0], landings[0])
    direction = np.asarray(direction, float)
    if auto and orient and not boxes:
        # travel along a ground axis, so the camera looks square at the (axis-aligned)
        # ground and its far edge, the horizon, is level (issue 33: 87_03 travels diagonally)
        direction = nearest_axis(direction)
    yaws = [0.0] * len(placed)
    if orient:
        yaws = orient_yaws(placed, bodies, takeoffs, landings, direction)
        if auto and not boxes:
            turn = THREE_QUARTER_DEG if turn is None else float(turn)
            if not np.isfinite(turn):
                raise FlipstudyValueError(f"stage: turn must be a finite number of degrees, got {turn}")
            yaws = [_half_open(y + turn) for y in yaws]
        placed = [place(c, np.zeros(3), y) for c, y in zip(placed, yaws)]
    return placed, yaws, direction


def stage(clips, takeoffs=None, landings=None, *, bodies=None, camera: Camera | None = None,
          size=(640, 480), style: Style | None = None, ground_bounds=None, boxes=(),
          direction=None, view_angle: float = 25.0, elevation: float = 8.0, margin: float | None = None,
          align: bool = True, orient: bool = True, turn: float | None = None) -> Stage:
    """Place clips for one study or one picture: same take-off spot, one camera.

    ``takeoffs``/``landings`` (frame indices, one per clip) default to what
    :func:`flipstudy.stimuli.analyse` finds.  ``bodies`` default to the table body of each
    skeleton (the same for every stimulus of one base clip, so the drawn
    character and the take-off spot do not depend on the edit).

    Without a ``camera`` the clips are placed (``align``: take-off COM to the
    origin) and one camera is fitted to every frame of every clip for an image
    of ``size``: it looks across ``direction`` (a horizontal vector; default
    the first clip's take-off→landing COM travel, +Z if tiny) from
    ``elevation`` degrees up, ``view_angle`` degrees of vertical view and
    ``margin`` on each side (see :func:`~flipstudy.render.camera.fit_camera`).  With
    ``orient`` every other base clip is also turned about the vertical through
    its take-off spot to travel the same way (a front flip captured going −X
    and a back flip going +Z both cross the picture left to right; see
    :func:`orient_yaws`).  With ``orient`` and no ``direction`` (nor ``boxes``) every
    clip is then turned ``turn`` degrees more (default :data:`THREE_QUARTER_DEG`): its
    travel goes that much away from the camera, so the camera, still square to the
    ground, sees the far arm and leg beside the near ones.  With a ``camera`` the
    clips are drawn where they are.

    ``style`` (default :data:`~flipstudy.render.style.DEFAULT_STYLE`) is how they
    are drawn; its ``ground_margin`` sizes the ground, unless ``ground_bounds``
    (x0, x1, z0, z1) are given.  ``boxes`` (``[(lo, hi), ...]``, axis-aligned, in
    the first clip's coordinates) are moved with it.

    Parameters
    ----------
    clips : sequence of Clip
    takeoffs, landings : sequence of int or None, optional
        Default: what :func:`flipstudy.analyse` finds.
    bodies : sequence of Body, optional
    camera : Camera, optional
        Given: the clips are drawn where they are.
    size : tuple of int
        (width, height) in pixels.
    style : Style, optional
    ground_bounds : tuple of float, optional
    boxes : sequence of (lo, hi)
    direction : array_like, shape (3,), optional
    view_angle, elevation : float
        Degrees.
    margin : float, optional
        Default: the style's ``frame_margin``.
    align, orient : bool
        Move the take-off COM to the origin; turn the other base clips.
    turn : float, optional
        Degrees of the three-quarter view (``orient`` without ``direction``);
        default :data:`THREE_QUARTER_DEG`, 0 for the square side view.

    Returns
    -------
    Stage

    Examples
    --------
    A back flip and a front flip (built to travel opposite ways) under one camera:

    >>> from flipstudy import builtin
    >>> st = stage([builtin("backflip"), builtin("frontflip")], size=(320, 240))
    >>> st.camera.to_dict()["view_angle"], st.takeoffs, st.yaws    # the front flip turned round
    (25.0, [157, 157], [20.0, -160.0])
    >>> stage([builtin("backflip"), builtin("frontflip")], turn=0).yaws        # square side view
    [0.0, 180.0]
    """
    clips = list(clips)
    if not clips:
        raise ValueError("stage: no clips")
    style = style or DEFAULT_STYLE
    margin = style.frame_margin if margin is None else float(margin)
    bodies = _bodies_for(clips, bodies)
    takeoffs, landings = _flight_frames(clips, bodies, takeoffs, landings)
    common = dict(bodies=bodies, takeoffs=takeoffs, landings=landings, size=size, style=style,
                  ground=ground_bounds)
    if camera is not None:
        return Stage(clips, camera=camera, boxes=_placed_boxes(boxes, clips[0], clips[0]), **common)
    if align:
        placed, offsets = align_takeoff(clips, takeoffs, bodies)
    else:
        placed, offsets = clips, np.zeros((len(clips), 3))
    placed, yaws, direction = _oriented(placed, bodies, takeoffs, landings, direction,
                                        orient=orient, boxes=boxes, turn=turn)
    if boxes and yaws[0]:
        raise FlipstudyValueError(f"stage: boxes are axis-aligned and the first clip is turned by "
                                  f"{yaws[0]:.1f}° to travel along direction; place them yourself "
                                  f"(orient=False, or no direction)")
    basis = view_basis(direction, elevation)
    allp = np.concatenate([_extremes(body_points(c, b), basis).reshape(-1, 3)
                           for c, b in zip(placed, bodies)])
    framing = Framing(allp, direction, view_angle, elevation, margin)
    return Stage(placed, camera=framing.camera(size), boxes=_placed_boxes(boxes, clips[0], placed[0]),
                 offsets=offsets, yaws=yaws, direction=direction, framing=framing, **common)


def staged(what) -> Stage:
    """What an image function draws: a :class:`Stage` as it is; a clip, or a
    list or tuple of clips, staged with the defaults of :func:`stage`."""
    if isinstance(what, Stage):
        return what
    if isinstance(what, Clip):
        return stage([what])
    if isinstance(what, (list, tuple)) and what and all(isinstance(c, Clip) for c in what):
        return stage(list(what))
    raise FlipstudyValueError(f"expected a Stage (flipstudy.render.staging), a Clip or a list of "
                              f"clips, got {type(what).__name__}")


def one_clip(st: Stage, what: str) -> Stage:
    """``st``, checked to hold one clip (for the images that draw one)."""
    if len(st.clips) != 1:
        raise FlipstudyValueError(f"{what} draws one clip; this stage holds {len(st.clips)} "
                                  f"(pass stage.only(k))")
    return st


__all__ = ["Stage", "Framing", "stage", "staged", "ground_around", "translate", "place",
           "takeoff_com", "align_takeoff", "travel_direction", "jump_direction", "orient_yaws",
           "base_clip_groups", "THREE_QUARTER_DEG"]
