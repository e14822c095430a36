"""The camera as data, and fitting one to what it must show.

:class:`Camera` (position, focal point, view-up, vertical view angle) round-trips
through a dict / JSON; :func:`fit_camera` finds the side view across a direction
of travel that keeps given points in the picture; :func:`transition_camera`
frames a concatenation's transition.  Placing clips for a study (one take-off
spot, one camera) is :func:`flipstudy.render.staging.stage`.
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

import json
from dataclasses import dataclass

import numpy as np

from flipstudy.stimuli.body import Body
from flipstudy.stimuli.motion.clip import Clip

UP = np.array([0.0, 1.0, 0.0])


@dataclass
class Camera:
    """A perspective camera (VTK conventions: ``view_angle`` is the vertical
    field of view in degrees).

    Parameters
    ----------
    position, focal_point : tuple of float
        Where the camera is and what it looks at, metres.
    view_up : tuple of float
        The picture's up direction.
    view_angle : float
        Vertical field of view, degrees.

    Examples
    --------
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
               elevation: float = 8.0, margin: float = 0.06, top: float = 0.0) -> Camera:
    """The camera looking across ``direction`` (side view: travel goes left to
    right), raised by ``elevation`` degrees, that keeps every point (N,3) inside
    an image of ``size`` with ``margin`` (fraction of width/height) on each side,
    and ``top`` (a fraction of the height) more above them: room for a legend.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        What must be in the picture, metres.
    direction : array_like, shape (3,)
        The horizontal direction of travel.
    size : tuple of int
        The image's (width, height) in pixels.
    view_angle, elevation : float
        Degrees.
    margin : float
        Fraction of the width and height kept free on each side.

    Returns
    -------
    Camera

    Examples
    --------
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
    t2 = np.tan(np.radians(view_angle) / 2.0)
    tv = t2 * (1.0 - 2.0 * margin - float(top))
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
    bc += float(top) * t2 * D           # the points sit that much lower: the room is above
    focal = centre + ac * right + bc * up
    return Camera(focal + D * back, focal, tuple(UP), view_angle)




def recentre(camera: Camera, groups, size, floor: float = 0.02, iterations: int = 3) -> Camera:
    """``camera`` moved sideways and up or down (view direction and scale kept) so
    that the point sets ``groups`` (each (N,3), e.g. the stimuli of one base clip
    over all their frames) are centred as a family: the middle of the range of their
    picture centres goes to the image centre, as far as the union of all of them
    stays ``floor`` (a fraction of the width/height) inside the image.

    One camera for several motions fits their union; a motion that rises less
    (a flip with more angular momentum has a shorter, lower flight) then sits low
    in the picture, by half the difference in height.  Centring the family instead
    of the union splits that offset between the highest and the lowest motion
    (issue 33: every video of the default study centred within 10 % of the frame).

    Examples
    --------
    >>> import numpy as np
    >>> low = np.array([[0, 0, 0], [0, 1.0, 0]]); high = np.array([[0, 0, 0], [0, 2.0, 0]])
    >>> cam = fit_camera(np.r_[low, high], size=(320, 240), margin=0.06)
    >>> new = recentre(cam, [low, high], (320, 240))
    >>> def below_centre(c):             # pixels each motion's centre sits below the image's
    ...     return [round(float(c.project(g, (320, 240))[:, 1].mean()) - 120, 1) for g in (low, high)]
    >>> below_centre(cam), below_centre(new)        # the low one rises, the high one shares
    ([54.2, -0.0], [44.8, -9.6])
    """
    W, H = size
    groups = [np.asarray(g, float).reshape(-1, 3) for g in groups]
    if len(groups) < 2:
        return camera
    right, up, _ = camera.basis()
    lim = np.array([W, H], float)
    for _ in range(iterations):
        boxes = np.array([[p.min(0), p.max(0)] for p in (camera.project(g, size) for g in groups)])
        centres = boxes.mean(axis=1)                                  # (K, 2)
        want = lim / 2.0 - 0.5 * (centres.min(0) + centres.max(0))    # pixels, content moves by
        lo, hi = boxes[:, 0].min(0), boxes[:, 1].max(0)               # the union's box
        shift = np.clip(want, np.minimum(floor * lim - lo, 0.0), np.maximum(lim * (1 - floor) - hi, 0.0))
        if np.all(np.abs(shift) < 0.05):
            break
        mpp = 2.0 * camera.distance * np.tan(np.radians(camera.view_angle) / 2.0) / H
        # content right (+x) and down (+y, image rows): the camera goes left and up
        camera = camera.translated(mpp * (-shift[0] * right + shift[1] * up))
    return camera


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
