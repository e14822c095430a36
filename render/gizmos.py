"""Debug gizmos (Ooi 2016, Fig. 4.5): the centre of mass and its path, the
angular momentum and velocity arrows at it, and the support polygon of the
effectors in contact, drawn over everything (``debug=`` of the image functions
and videos)."""
from __future__ import annotations

import numpy as np

from flipstudy.stimuli.body import Body
from flipstudy.errors import FlipstudyValueError
from flipstudy.stimuli.motion.clip import Clip
from flipstudy.stimuli.physics import momentum

#: every overlay ``debug=`` can ask for (``debug=True``: all of them)
DEBUG_ALL = ("com", "path", "L", "v", "support")


class Gizmos:
    """Debug quantities of a clip at any time: COM, its velocity, the angular
    momentum about it, and the support polygon of the effectors in contact.

    Parameters
    ----------
    clip : Clip
    body : Body
        The segment model the momenta are computed with.
    what : sequence of str
        Which gizmos to draw: ``"com"``, ``"path"``, ``"L"``, ``"v"``, ``"support"``.

    Examples
    --------
    >>> import numpy as np
    >>> from flipstudy import Body, builtin
    >>> clip = builtin("backflip")
    >>> gz = Gizmos(clip, Body.from_clip(clip))
    >>> mid = gz.at(1.5)                                       # seconds: in the air
    >>> round(float(np.linalg.norm(mid["L"])), 1), len(mid["support"])
    (46.7, 0)
    >>> len(gz.at(0.5)["support"])                             # standing: the feet's corners
    4
    """

    def __init__(self, clip: Clip, body: Body, what=DEBUG_ALL):
        from flipstudy.stimuli.flight import contact_mask, effector_points
        self.what = tuple(DEBUG_ALL if what is True else what)
        bad = set(self.what) - set(DEBUG_ALL)
        if bad:
            raise FlipstudyValueError(f"debug: unknown overlay(s) {sorted(bad)}; choose from {DEBUG_ALL}")
        self.clip, self.body = clip, body
        m = momentum(clip, body)
        self.com, self.v, self.L = m.com, m.v_com, m.L
        self.eff, _ = effector_points(clip, body)
        self.contact = contact_mask(clip, body) if "support" in self.what else None

    def _lerp(self, a: np.ndarray, t: float) -> np.ndarray:
        f = np.clip(t * self.clip.fps, 0, self.clip.num_frames - 1)
        i = int(min(np.floor(f), self.clip.num_frames - 2)) if self.clip.num_frames > 1 else 0
        u = f - i
        return a[i] if u == 0 or self.clip.num_frames == 1 else (1 - u) * a[i] + u * a[i + 1]

    def at(self, t: float) -> dict:
        out = {"com": self._lerp(self.com, t), "v": self._lerp(self.v, t), "L": self._lerp(self.L, t)}
        if self.contact is not None:
            f = int(np.clip(round(t * self.clip.fps), 0, self.clip.num_frames - 1))
            out["support"] = self.eff[f][self.contact[f]]
        return out

    def draw(self, scene, t: float, path_span=None, ground: float = 0.0) -> None:
        st = scene.style
        q = self.at(t)
        if "com" in self.what:
            scene.markers("gizmo-com", 1, st.com_color, st.com_radius, on_top=True).set(q["com"][None])
        if "path" in self.what and path_span is not None:
            tt = np.linspace(path_span[0], path_span[1], 200)
            pts = np.array([self._lerp(self.com, x) for x in tt])
            scene.polyline("gizmo-path", 200, st.com_color, 3.0, on_top=True).set(pts)
        if "L" in self.what:
            scene.arrow("gizmo-L", st.L_color, on_top=True).set(q["com"], q["L"] * st.L_scale)
        if "v" in self.what:
            scene.arrow("gizmo-v", st.v_color, on_top=True).set(q["com"], q["v"] * st.v_scale)
        if "support" in self.what:
            scene.polyline("gizmo-support", 9, st.support_color, 4.0, closed=True, on_top=True).set(
                support_polygon(q["support"], ground))


def support_polygon(points: np.ndarray, ground: float = 0.0) -> np.ndarray:
    """Convex hull (in order) of contact points projected onto the ground plane
    (lifted 5 mm so it draws over the tiles); fewer than 3 points are returned
    as they are."""
    p = np.asarray(points, float).reshape(-1, 3).copy()
    if p.shape[0] == 0:
        return p
    p[:, 1] = ground + 0.005
    if p.shape[0] >= 3:
        from scipy.spatial import QhullError

        from flipstudy.stimuli.control.balance import support_polygon as ground_hull
        try:
            xz = ground_hull(p)                               # (K,2) counter-clockwise
            return np.column_stack([xz[:, 0], np.full(len(xz), ground + 0.005), xz[:, 1]])
        except QhullError:
            pass
        d = p[:, [0, 2]] - p[:, [0, 2]].mean(0)
        ax = np.linalg.svd(d, full_matrices=False)[2][0]
        s = d @ ax
        return p[[int(np.argmin(s)), int(np.argmax(s))]]
    return p


def debug_gizmos(debug, clip: Clip, body: Body) -> Gizmos | None:
    """The gizmos ``debug`` asks for (``True``: all, a sequence of names from
    :data:`DEBUG_ALL`), or ``None`` for none."""
    if not debug:
        return None
    return Gizmos(clip, body, DEBUG_ALL if debug is True else tuple(debug))


__all__ = ["DEBUG_ALL", "Gizmos", "support_polygon", "debug_gizmos"]
