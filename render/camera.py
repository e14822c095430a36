"""One camera and one take-off spot for a whole study.

Majkowska & Faloutsos (2007, Section 7): "All animations were rendered in the
same style with the same camera configuration and the same take-off position."
:func:`stage` does both: it moves every clip horizontally so that its take-off
centre of mass is at the origin, then fits one side-view camera that keeps every
frame of every clip in the picture.

The take-off spot is the COM in the *last frame on the ground* (``takeoff − 1``,
the first airborne frame being ``takeoff``): edits of the flight may already
change the first airborne frame (a retimed flight samples it between source
frames), and the anchor must not move with the edit, or stimuli of one base
clip would no longer match before take-off.

The camera is data (:class:`Camera`: position, focal point, view-up, vertical
view angle) and round-trips through a dict / JSON.
"""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyValueError

import json
from dataclasses import dataclass, field

import numpy as np

from flipstudy.stimuli.body import Body
from flipstudy.stimuli.motion.clip import Clip
from flipstudy.stimuli.physics import center_of_mass

from .geometry import body_points

UP = np.array([0.0, 1.0, 0.0])


@dataclass
class Camera:
    """A perspective camera (VTK conventions: ``view_angle`` is the vertical
    field of view in degrees).

    Example
    -------
    >>> cam = Camera((0, 1, 6), (0, 1, 0), (0, 1, 0), 25.0)
    >>> Camera.from_json(cam.to_json()) == cam
    True
    >>> cam.project([[0, 1, 0]], (640, 480)).round(1).tolist()
    [[320.0, 240.0]]
    """

    position: tuple
    focal_point: tuple
    view_up: tuple = (0.0, 1.0, 0.0)
    view_angle: float = 25.0

    def __post_init__(self):
        self.position = tuple(float(v) for v in self.position)
        self.focal_point = tuple(float(v) for v in self.focal_point)
        self.view_up = tuple(float(v) for v in self.view_up)
        self.view_angle = float(self.view_angle)
        if len(self.position) != 3 or len(self.focal_point) != 3 or len(self.view_up) != 3:
            raise FlipstudyValueError("Camera: position, focal_point and view_up must be 3-vectors")
        if not 0.0 < self.view_angle < 180.0:
            raise FlipstudyValueError(f"Camera.view_angle must be in (0, 180) degrees, got {self.view_angle}")
        if np.linalg.norm(np.subtract(self.position, self.focal_point)) < 1e-9:
            raise FlipstudyValueError("Camera: position and focal_point coincide")

    # ------------------------------------------------------------ conversions
    def to_dict(self) -> dict:
        return {"position": list(self.position), "focal_point": list(self.focal_point),
                "view_up": list(self.view_up), "view_angle": self.view_angle}

    @classmethod
    def from_dict(cls, d: dict) -> "Camera":
        try:
            return cls(d["position"], d["focal_point"], d.get("view_up", (0, 1, 0)),
                       d.get("view_angle", 25.0))
        except KeyError as e:
            raise FlipstudyValueError(f"Camera: missing field {e.args[0]!r} "
                             f"(need position, focal_point)") from None

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @classmethod
    def from_json(cls, text: str) -> "Camera":
        return cls.from_dict(json.loads(text))

    # ----------------------------------------------------------------- maths
    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, back) unit vectors; ``back`` points from the focal point to
        the camera; ``up`` is the view-up made orthogonal (as VTK does)."""
        back = np.subtract(self.position, self.focal_point)
        back = back / np.linalg.norm(back)
        right = np.cross(self.view_up, back)
        right = right / np.linalg.norm(right)
        return right, np.cross(back, right), back

    @property
    def distance(self) -> float:
        return float(np.linalg.norm(np.subtract(self.position, self.focal_point)))

    def project(self, points, size) -> np.ndarray:
        """Pixel coordinates (N,2) — x to the right, y down from the top-left
        corner, as in an image array ``img[y, x]`` — of world points (N,3) in an
        image of ``size = (width, height)``."""
        W, H = size
        X = np.atleast_2d(np.asarray(points, float)) - np.asarray(self.position)
        r, u, b = self.basis()
        depth = -(X @ b)
        t = np.tan(np.radians(self.view_angle) / 2.0)
        nx = (X @ r) / depth / (t * W / H)
        ny = (X @ u) / depth / t
        return np.stack([(nx + 1.0) * W / 2.0, (1.0 - ny) * H / 2.0], axis=1)

    def translated(self, offset) -> "Camera":
        o = np.asarray(offset, float)
        return Camera(np.add(self.position, o), np.add(self.focal_point, o), self.view_up,
                      self.view_angle)

    def apply(self, renderer) -> None:
        """Set a VTK/PyVista renderer's active camera to this one."""
        cam = renderer.GetActiveCamera()
        cam.SetPosition(*self.position)
        cam.SetFocalPoint(*self.focal_point)
        cam.SetViewUp(*self.view_up)
        cam.SetViewAngle(self.view_angle)
        cam.SetParallelProjection(False)
        cam.OrthogonalizeViewUp()


def side_direction(direction) -> np.ndarray:
    """Unit horizontal vector from the action towards a camera that sees the
    horizontal ``direction`` of travel going from left to right."""
    d = np.asarray(direction, float).copy()
    d[1] = 0.0
    n = np.linalg.norm(d)
    d = d / n if n > 1e-9 else np.array([0.0, 0.0, 1.0])
    s = np.cross(d, UP)
    return s / np.linalg.norm(s)


def view_basis(direction, elevation: float = 8.0) -> np.ndarray:
    """Rows (right, up, back) of the side-view camera across ``direction``,
    raised by ``elevation`` degrees."""
    s = side_direction(direction)
    el = np.radians(elevation)
    back = np.cos(el) * s + np.sin(el) * UP
    right = np.cross(UP, back)
    right /= np.linalg.norm(right)
    return np.stack([right, np.cross(back, right), back])


def fit_camera(points, direction=(0.0, 0.0, 1.0), size=(640, 480), *, view_angle: float = 25.0,
               elevation: float = 8.0, margin: float = 0.06) -> Camera:
    """The camera looking across ``direction`` (side view: travel goes left to
    right), raised by ``elevation`` degrees, that keeps every point (N,3) inside
    an image of ``size`` with ``margin`` (fraction of width/height) on each side.

    Example
    -------
    >>> import numpy as np
    >>> pts = np.random.default_rng(0).random((100, 3))
    >>> cam = fit_camera(pts, size=(320, 240))
    >>> px = cam.project(pts, (320, 240))                    # (100, 2) pixels
    >>> bool(((px >= 0) & (px <= [320, 240])).all())          # every point in the picture
    True
    """
    X = np.asarray(points, float).reshape(-1, 3)
    if X.shape[0] == 0 or not np.all(np.isfinite(X)):
        raise ValueError("fit_camera: need finite points to frame")
    W, H = size
    right, up, back = view_basis(direction, elevation)
    tv = np.tan(np.radians(view_angle) / 2.0) * (1.0 - 2.0 * margin)
    th = np.tan(np.radians(view_angle) / 2.0) * (W / H) * (1.0 - 2.0 * margin)
    centre = 0.5 * (X.min(0) + X.max(0))
    a, b, w = (X - centre) @ right, (X - centre) @ up, (X - centre) @ back
    ac, bc = 0.5 * (a.min() + a.max()), 0.5 * (b.min() + b.max())
    for _ in range(8):
        D = float(np.max(w + np.maximum(np.abs(a - ac) / th, np.abs(b - bc) / tv)))
        D = max(D, float(w.max()) + 0.1)
        depth = D - w
        x, y = (a - ac) / depth, (b - bc) / depth
        # recentre the projected extents (in the focal plane) and refit
        dx, dy = 0.5 * (x.min() + x.max()), 0.5 * (y.min() + y.max())
        if abs(dx) < 1e-6 * th and abs(dy) < 1e-6 * tv:
            break
        ac += dx * D
        bc += dy * D
    D = float(np.max(w + np.maximum(np.abs(a - ac) / th, np.abs(b - bc) / tv)))
    focal = centre + ac * right + bc * up
    return Camera(focal + D * back, focal, tuple(UP), view_angle)


@dataclass
class Stage:
    """Clips placed for one study: each clip moved by ``offsets[k]`` (K,3) so
    its take-off COM is at the origin (horizontally), then turned by
    ``yaws[k]`` degrees about the vertical axis through it (see :func:`place`);
    the common ``camera``, the jump ``direction`` and the ground ``bounds``
    (x0, x1, z0, z1)."""

    clips: list
    offsets: np.ndarray
    takeoffs: list
    landings: list
    bodies: list
    camera: Camera
    direction: np.ndarray
    ground_bounds: tuple
    size: tuple = (640, 480)
    yaws: list = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"camera": self.camera.to_dict(), "direction": [float(v) for v in self.direction],
                "ground_bounds": [float(v) for v in self.ground_bounds], "size": list(self.size),
                "offsets": [[float(v) for v in o] for o in self.offsets],
                "yaws_deg": [float(v) for v in self.yaws],
                "takeoffs": list(self.takeoffs), "landings": list(self.landings)}


#: views of :func:`transition_camera`
TRANSITION_VIEWS = ("across-L", "side", "three-quarter")


def transition_camera(joined: Clip, first: Clip, body: Body, view: str = "across-L", *,
                      main: tuple[int, int], at: int, frames: tuple[int, int],
                      size=(640, 480)) -> Camera:
    """The camera for a picture of a concatenation's transition (``flipstudy concat --ghost``).

    ``view`` chooses the direction of travel the camera looks across (see :func:`fit_camera`):

    * ``"across-L"`` — across the mean angular momentum of ``first`` (the first
      motion) over its main phase, frames ``main[0]``–``main[1]`` inclusive: the
      camera looks along L, so a flip or a cartwheel is seen in profile;
    * ``"side"`` — the torso facing of ``joined`` at frame ``at`` (the blend's first
      frame): the performer seen from the side;
    * ``"three-quarter"`` — that facing turned 45° about the vertical (clockwise
      seen from above): a three-quarter front view.

    A direction of zero length (no momentum) falls back to +z.  The camera keeps
    the joints of ``joined``'s frames ``frames[0]``..``frames[1] - 1`` in the image.
    """
    from flipstudy.stimuli.edit.concat import torso_facing
    from flipstudy.stimuli.physics import momentum
    if view not in TRANSITION_VIEWS:
        raise FlipstudyValueError(f"view must be one of {', '.join(TRANSITION_VIEWS)}, got {view!r}")
    if view == "across-L":
        L = momentum(first, body).L
        d = np.cross(UP, L[main[0]:main[1] + 1].mean(axis=0))
    else:
        d = torso_facing(joined, body)[at]
        if view == "three-quarter":
            # -45° about the vertical (the y axis)
            d = np.array([[0.7071, 0, -0.7071], [0, 1, 0], [0.7071, 0, 0.7071]]) @ d
    f0, f1 = frames
    return fit_camera(joined.joint_positions()[f0:f1], direction=d if np.linalg.norm(d) > 1e-6 else (0, 0, 1),
                      size=size)


def translate(clip: Clip, offset) -> Clip:
    """The clip moved by ``offset`` (3,) metres."""
    o = np.asarray(offset, float)
    if not np.any(o):
        return clip
    return clip.replace(root_pos=clip.root_pos + o)


def place(clip: Clip, offset, yaw_deg: float = 0.0) -> Clip:
    """The clip moved by ``offset`` (3,), then turned by ``yaw_deg`` degrees
    about the vertical axis through the origin (the study's take-off spot)."""
    clip = translate(clip, offset)
    if yaw_deg:
        from scipy.spatial.transform import Rotation

        from flipstudy.stimuli.edit.reposition import rotate
        clip = rotate(clip, Rotation.from_rotvec([0.0, np.radians(yaw_deg), 0.0]), np.zeros(3))
    return clip


def takeoff_com(clip: Clip, body: Body, takeoff: int | None) -> np.ndarray:
    """COM of the take-off spot: the last frame on the ground, ``takeoff − 1``
    (``takeoff`` is the first airborne frame); frame 0 without a flight."""
    f = 0 if takeoff is None else int(np.clip(takeoff - 1, 0, clip.num_frames - 1))
    return center_of_mass(clip.slice(f, f + 1), body)[0]


def align_takeoff(clips, takeoffs, bodies=None) -> tuple[list, np.ndarray]:
    """Clips moved horizontally so each take-off COM (:func:`takeoff_com`) is at
    x = z = 0 (heights are kept: the ground stays at its level).  Returns
    (clips, offsets (K,3))."""
    bodies = bodies or [Body.from_clip(c) for c in clips]
    out, offs = [], []
    for c, t, b in zip(clips, takeoffs, bodies):
        com = takeoff_com(c, b, t)
        o = np.array([-com[0], 0.0, -com[2]])
        out.append(translate(c, o))
        offs.append(o)
    return out, np.array(offs).reshape(-1, 3)


def travel_direction(clip: Clip, body: Body, takeoff: int | None, landing: int | None,
                     tiny: float = 0.05) -> np.ndarray | None:
    """Horizontal unit direction of the COM's travel from take-off to landing,
    or ``None`` when it travels less than ``tiny`` metres or has no flight."""
    if takeoff is None or landing is None:
        return None
    com = center_of_mass(clip.slice(int(takeoff), int(landing) + 1), body)
    d = com[-1] - com[0]
    d[1] = 0.0
    n = np.linalg.norm(d)
    return d / n if n >= tiny else None


def jump_direction(clip: Clip, body: Body, takeoff: int | None, landing: int | None,
                   tiny: float = 0.05) -> np.ndarray:
    """Horizontal unit direction of the COM's travel from take-off to landing;
    +Z when the travel is under ``tiny`` metres or there is no flight."""
    d = travel_direction(clip, body, takeoff, landing, tiny)
    return np.array([0.0, 0.0, 1.0]) if d is None else d


def _prefix_key(clip: Clip, takeoff: int | None) -> str:
    """Identity of a clip's motion before take-off (its first ``takeoff``
    frames): stimuli made from one base clip by editing the flight share it."""
    import hashlib
    n = clip.num_frames if takeoff is None else max(1, int(takeoff))
    h = hashlib.sha256()
    h.update(str((n, clip.skeleton.joint_names)).encode())
    for a in (clip.skeleton.offsets, clip.root_pos[:n], clip.rotations[:n]):
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return h.hexdigest()


def orient_yaws(clips, bodies, takeoffs, landings, direction) -> list[float]:
    """Degrees to turn each clip about the vertical so that it travels along
    ``direction``.  Clips with the same motion before take-off (one base clip
    and its edits) get one angle, from the first of them, so they stay
    identical before take-off; clips that hardly travel are not turned."""
    target = np.asarray(direction, float)
    yaw_of: dict = {}
    out = []
    for c, b, t0, t1 in zip(clips, bodies, takeoffs, landings):
        key = _prefix_key(c, t0)
        if key not in yaw_of:
            d = travel_direction(c, b, t0, t1)
            if d is None:
                yaw_of[key] = 0.0
            else:
                ang = np.arctan2(np.cross(d, target) @ UP, d @ target)
                yaw_of[key] = float(np.degrees(ang))
        out.append(yaw_of[key])
    return out


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


def stage(clips, takeoffs=None, landings=None, *, bodies=None, size=(640, 480), direction=None,
          view_angle: float = 25.0, elevation: float = 8.0, margin: float = 0.06,
          ground_margin: float = 4.0, align: bool = True, orient: bool = True) -> Stage:
    """Place clips for one study: same take-off spot, one camera.

    ``takeoffs``/``landings`` (frame indices, one per clip) default to what
    :func:`flipstudy.stimuli.analyse` finds.  ``bodies`` default to the table body of each
    skeleton (the same for every stimulus of one base clip, so the drawn
    character and the take-off spot do not depend on the edit).  ``direction``
    (horizontal vector) defaults to the first clip's take-off→landing COM travel
    (+Z if tiny); the camera looks across it.  With ``orient`` every other base
    clip is also turned about the vertical through its take-off spot to travel
    the same way (a front flip captured going −X and a back flip going +Z both
    cross the picture left to right; see :func:`orient_yaws`).

    Example
    -------
    A back flip and a front flip (built to travel opposite ways) under one camera:

    >>> from flipstudy import builtin
    >>> st = stage([builtin("backflip"), builtin("frontflip")], size=(320, 240))
    >>> st.camera.to_dict()["view_angle"], st.takeoffs, st.yaws    # the front flip turned round
    (25.0, [157, 157], [0.0, 180.0])
    """
    clips = list(clips)
    if not clips:
        raise ValueError("stage: no clips")
    bodies = _bodies_for(clips, bodies)
    if takeoffs is None or landings is None:
        from flipstudy.stimuli import analyse
        found = [analyse(c, body=b, estimate=False) for c, b in zip(clips, bodies)]
        takeoffs = [a.takeoff for a in found] if takeoffs is None else takeoffs
        landings = [a.landing for a in found] if landings is None else landings
    takeoffs = [None if t is None else int(t) for t in takeoffs]
    landings = [None if t is None else int(t) for t in landings]
    if align:
        placed, offsets = align_takeoff(clips, takeoffs, bodies)
    else:
        placed, offsets = clips, np.zeros((len(clips), 3))
    if direction is None:
        direction = jump_direction(placed[0], bodies[0], takeoffs[0], landings[0])
    direction = np.asarray(direction, float)
    yaws = [0.0] * len(placed)
    if orient:
        yaws = orient_yaws(placed, bodies, takeoffs, landings, direction)
        placed = [place(c, np.zeros(3), y) for c, y in zip(placed, yaws)]
    basis = view_basis(direction, elevation)
    allp = np.concatenate([_extremes(body_points(c, b), basis).reshape(-1, 3)
                           for c, b in zip(placed, bodies)])
    cam = fit_camera(allp, direction, size, view_angle=view_angle, elevation=elevation, margin=margin)
    lo, hi = allp.min(0), allp.max(0)
    g = float(ground_margin) + 0.5 * cam.distance
    bounds = (lo[0] - g, hi[0] + g, lo[2] - g, hi[2] + g)
    return Stage(placed, offsets, takeoffs, landings, bodies, cam, direction, bounds, tuple(size),
                 yaws)
