"""Stimulus videos and Ooi's still visualisations (Ooi 2016, Chapter 4).

* :func:`render_video` — the clip resampled to a display rate, H.264 MP4;
* :func:`ghost_image` — semi-transparent copies at a fixed interval (Fig. 4.2);
* :func:`trail_image` — markers on joints at 10 per second, with a legend (Fig. 4.1);
* :func:`strip_image` — an animation strip of labelled panels;
* :func:`composite_image` — layered frames, first opaque, the rest at 75 %,
  matted from the renderer's alpha channel (Fig. 4.3, which Ooi painted by hand);
* :func:`overlay_image` — an original and an edited clip in yellow and
  turquoise (Majkowska & Faloutsos 2007, Fig. 4);
* ``debug=`` on all of them — COM and its path, angular momentum and velocity
  arrows at the COM, support polygon while in contact (Ooi's gizmos, Fig. 4.5).

Every function takes the same keywords: ``size`` (w, h), ``style``
(:class:`~flipstudy.render.style.Style`), ``camera`` (:class:`~flipstudy.render.camera.Camera`;
``None`` stages the clip — take-off COM to the origin — and fits one),
``body`` (the :class:`flipstudy.stimuli.Body` to draw; default the table body of the
skeleton), ``takeoff``/``landing`` (frames; default found by
:func:`flipstudy.stimuli.analyse`), ``scene`` (a :class:`~flipstudy.render.scene.Scene` to reuse,
e.g. one per worker) and ``path`` (write a PNG with OpenImageIO).  Images
are returned as ``uint8`` arrays ``(H, W, 3)``.
"""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyValueError

import contextlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flipstudy.stimuli.body import Body
from flipstudy.stimuli.motion.clip import Clip
from flipstudy.stimuli.physics import center_of_mass, momentum

from .camera import Camera, fit_camera, stage
from .compose import draw_legend, draw_text, find_font, flatten, grid, over, write_png
from .geometry import body_points, poses_at, resample
from .scene import Scene
from .style import DEFAULT_STYLE, Style, rgb8
from .video import h264_writer

#: Default trail joints (Ooi used the pelvis and the leg joints; a legend is a must).
TRAIL_JOINTS = ("pelvis", "head", "hand_l", "hand_r", "knee_l", "knee_r", "foot_l", "foot_r", "com")
_LANDMARK_OF = {"hand_l": "wrist_l", "hand_r": "wrist_r", "foot_l": "ankle_l", "foot_r": "ankle_r"}
_LABEL = {"pelvis": "pelvis", "head": "head", "hand_l": "left hand", "hand_r": "right hand",
          "knee_l": "left knee", "knee_r": "right knee", "foot_l": "left foot",
          "foot_r": "right foot", "com": "centre of mass", "elbow_l": "left elbow",
          "elbow_r": "right elbow", "hip_l": "left hip", "hip_r": "right hip",
          "shoulder_l": "left shoulder", "shoulder_r": "right shoulder", "neck": "neck"}
DEBUG_ALL = ("com", "path", "L", "v", "support")


# ---------------------------------------------------------------- preparation
@dataclass
class Prepared:
    """Clips placed under one camera, with what the figures need."""

    clips: list
    bodies: list
    takeoffs: list
    landings: list
    camera: Camera
    ground_bounds: tuple


def _ground_bounds(clips, bodies, margin: float, camera: Camera) -> tuple:
    pts = np.concatenate([body_points(c, b, (6, 3), slice(None, None, 4)).reshape(-1, 3)
                          for c, b in zip(clips, bodies)])
    lo, hi = pts.min(0), pts.max(0)
    g = margin + 0.5 * camera.distance
    return (lo[0] - g, hi[0] + g, lo[2] - g, hi[2] + g)


def prepare(clips, *, bodies=None, takeoffs=None, landings=None, camera: Camera | None = None,
            size=(640, 480), ground_bounds=None, style: Style | None = None) -> Prepared:
    """Place clips for drawing.  Without a ``camera`` they are staged (take-off
    COM at the origin, one fitted side camera, see :func:`flipstudy.render.camera.stage`);
    with one they are drawn where they are."""
    clips = list(clips)
    style = style or DEFAULT_STYLE
    if bodies is None:
        bodies = []
        for c in clips:
            same = [b for c2, b in zip(clips, bodies) if c2.skeleton is c.skeleton]
            bodies.append(same[0] if same else Body.from_clip(c))
    bodies = list(bodies)
    if takeoffs is None or landings is None:
        from flipstudy.stimuli import analyse
        found = [analyse(c, body=b, estimate=False) for c, b in zip(clips, bodies)]
        takeoffs = [a.takeoff for a in found] if takeoffs is None else list(takeoffs)
        landings = [a.landing for a in found] if landings is None else list(landings)
    if camera is None:
        st = stage(clips, takeoffs, landings, bodies=bodies, size=size,
                   ground_margin=style.ground_margin)
        return Prepared(st.clips, bodies, list(takeoffs), list(landings), st.camera,
                        ground_bounds or st.ground_bounds)
    gb = ground_bounds or _ground_bounds(clips, bodies, style.ground_margin, camera)
    return Prepared(clips, bodies, list(takeoffs), list(landings), camera, gb)


def _prepare1(clip, body, takeoff, landing, camera, size, style, ground_bounds) -> Prepared:
    one = lambda v: None if v is None else [v]  # noqa: E731
    return prepare([clip], bodies=one(body), takeoffs=one(takeoff), landings=one(landing),
                   camera=camera, size=size, style=style, ground_bounds=ground_bounds)


@contextlib.contextmanager
def _scene(scene: Scene | None, prep: Prepared, style: Style | None, size):
    """Reuse ``scene`` (reconfigured, contents hidden) or make a temporary one."""
    if scene is None:
        sc = Scene(prep.bodies[0], style or DEFAULT_STYLE, size, prep.camera, prep.ground_bounds)
        try:
            yield sc
        finally:
            sc.close()
        return
    scene.set_size(size)
    scene.set_body(prep.bodies[0])
    scene.set_camera(prep.camera)
    scene.set_ground(prep.ground_bounds)
    scene.show_ground(True)
    scene.hide_all()
    try:
        yield scene
    finally:
        scene.hide_all()


def _span(clip: Clip, span, margin: float, takeoff, landing) -> tuple[float, float]:
    """(t0, t1) seconds: ``"flight"`` (± margin; the whole clip without a
    flight), ``"clip"``, or explicit ``(t0, t1)``."""
    if isinstance(span, str):
        if span == "clip" or takeoff is None or landing is None:
            if span not in ("clip", "flight"):
                raise FlipstudyValueError(f"span must be 'flight', 'clip' or (t0, t1) seconds, got {span!r}")
            return 0.0, clip.duration
        if span != "flight":
            raise FlipstudyValueError(f"span must be 'flight', 'clip' or (t0, t1) seconds, got {span!r}")
        return (max(0.0, takeoff / clip.fps - margin), min(clip.duration, landing / clip.fps + margin))
    t0, t1 = (float(v) for v in span)
    if not (0.0 <= t0 <= t1):
        raise FlipstudyValueError(f"span (t0, t1) must satisfy 0 <= t0 <= t1, got {span!r}")
    return t0, min(t1, clip.duration)


def _regular_times(t0: float, t1: float, step: float) -> np.ndarray:
    if not (np.isfinite(step) and step > 0):
        raise FlipstudyValueError(f"interval must be a positive number of seconds, got {step!r}")
    n = int(np.floor((t1 - t0) / step + 1e-9)) + 1
    return t0 + step * np.arange(n)


def _fk(clip: Clip, times) -> tuple[np.ndarray, np.ndarray, Clip]:
    pc = poses_at(clip, times)
    return pc.joint_rotations(), pc.joint_positions(), pc


def _posed(clip, body, takeoff, landing, camera, size, style, ground_bounds, span, margin, times, interval):
    """One staged clip posed at ``times`` (or every ``interval`` s over ``span``):
    (prepared, its clip, its body, times, joint rotations, joint positions)."""
    prep = _prepare1(clip, body, takeoff, landing, camera, size, style, ground_bounds)
    c, b = prep.clips[0], prep.bodies[0]
    t0, t1 = _span(c, span, margin, prep.takeoffs[0], prep.landings[0])
    ts = np.asarray(times, float) if times is not None else _regular_times(t0, t1, interval)
    R, P, _ = _fk(c, ts)
    return prep, c, b, ts, R, P


def _placed_boxes(boxes, clip: Clip, placed: Clip) -> list:
    """Boxes (lo, hi) moved like the clip was when staged (a translation: one
    clip is never turned)."""
    if not boxes:
        return []
    o = placed.root_pos[0] - clip.root_pos[0]
    return [(np.asarray(lo, float) + o, np.asarray(hi, float) + o) for lo, hi in boxes]


def _save(img: np.ndarray, path) -> np.ndarray:
    if path is not None:
        write_png(path, img)
    return img


# ------------------------------------------------------------------- gizmos
class Gizmos:
    """Debug quantities of a clip at any time: COM, its velocity, the angular
    momentum about it, and the support polygon of the effectors in contact.

    Example
    -------
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

    def draw(self, scene: Scene, t: float, path_span=None, ground: float = 0.0) -> None:
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


def _gizmos(debug, clip, body) -> Gizmos | None:
    if not debug:
        return None
    return Gizmos(clip, body, DEBUG_ALL if debug is True else tuple(debug))


# --------------------------------------------------------------------- video
def iter_frames(clip: Clip, scene: Scene, fps: float = 60.0, *, other: Clip | None = None,
                body: Body | None = None, other_body: Body | None = None, gizmos: Gizmos | None = None,
                colors=None):
    """Yield the frames (H,W,3 uint8) of ``clip`` sampled at ``fps`` in a
    prepared scene (camera, ground set).  The same buffer is reused: copy a
    frame to keep it.  ``other`` draws a second clip (overlay) in
    ``colors[1]``, over ``clip`` in ``colors[0]``."""
    st = scene.style
    v = resample(clip, fps)
    R, P = v.joint_rotations(), v.joint_positions()
    n = v.num_frames
    ch = scene.character("main", body)
    if other is not None:
        colors = colors or st.overlay_colors
        ch.look(colors[0], 1.0)
        w = resample(other, fps)
        R2, P2 = w.joint_rotations(), w.joint_positions()
        n = max(n, w.num_frames)
        ch2 = scene.character("other", other_body or body, inflate=0.004)
        ch2.look(colors[1], st.overlay_opacity)
    else:
        ch.look(st.body_color, 1.0)
        scene.hide("other")
    buf = np.empty((scene.size[1], scene.size[0], 3), np.uint8)
    for k in range(n):
        i = min(k, v.num_frames - 1)
        ch.pose(R[i], P[i])
        if other is not None:
            j = min(k, w.num_frames - 1)
            ch2.pose(R2[j], P2[j])
        if gizmos is not None:
            gizmos.draw(scene, i / fps, (0.0, i / fps), st.ground_height)
        yield scene.grab(out=buf)


def render_video(clip: Clip, path, *, fps: float = 60.0, size=(640, 480), style: Style | None = None,
                 camera: Camera | None = None, body: Body | None = None, takeoff=None, landing=None,
                 scene: Scene | None = None, ground_bounds=None, other: Clip | None = None, debug=(),
                 frames_dir=None, crf: int = 18) -> Path:
    """Render a stimulus video: the clip sampled at ``fps`` display frames per
    second (rotations slerped, root linear), H.264 in MP4, yuv420p (plays in
    browsers); ``frames_dir`` also writes every frame as PNG.  ``other``
    overlays a second clip (e.g. the edited one) in the second overlay colour.

    Example
    -------
    >>> import tempfile, pathlib
    >>> from flipstudy import builtin
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     mp4 = render_video(builtin("backflip"), pathlib.Path(tmp) / "backflip.mp4",
    ...                        fps=15, size=(160, 120))
    ...     mp4.name, mp4.stat().st_size > 1000
    ('backflip.mp4', True)
    """
    W, H = int(size[0]), int(size[1])
    if W % 2 or H % 2:
        raise FlipstudyValueError(f"video size {W}x{H}: width and height must be even for H.264 yuv420p")
    clips = [clip] + ([other] if other is not None else [])
    prep = prepare(clips, bodies=None if body is None else [body] * len(clips),
                   takeoffs=None if takeoff is None else [takeoff] * len(clips),
                   landings=None if landing is None else [landing] * len(clips),
                   camera=camera, size=(W, H), style=style, ground_bounds=ground_bounds)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if frames_dir is not None:
        Path(frames_dir).mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    writer = h264_writer(tmp, (W, H), fps, crf=crf)
    try:
        with _scene(scene, prep, style, (W, H)) as sc:
            gz = _gizmos(debug, prep.clips[0], prep.bodies[0])
            for k, frame in enumerate(iter_frames(
                    prep.clips[0], sc, fps, other=prep.clips[1] if other is not None else None,
                    body=prep.bodies[0], other_body=prep.bodies[-1], gizmos=gz)):
                writer.send(frame)
                if frames_dir is not None:
                    write_png(Path(frames_dir) / f"{path.stem}_{k:05d}.png", frame)
        writer.close()
    except BaseException:
        with contextlib.suppress(Exception):
            writer.close()
        tmp.unlink(missing_ok=True)
        raise
    tmp.replace(path)
    return path


# -------------------------------------------------------------------- ghosts
def ghost_image(clip: Clip, path=None, *, interval: float = 0.2, span="flight", margin: float = 0.25,
                times=None, size=(640, 480), style: Style | None = None, camera: Camera | None = None,
                body: Body | None = None, takeoff=None, landing=None, scene: Scene | None = None,
                ground_bounds=None, debug=()) -> np.ndarray:
    """Ghosts: semi-transparent copies every ``interval`` seconds over the
    ``span`` (``"flight"`` ± ``margin`` s, ``"clip"``, or ``(t0, t1)``), the last
    pose opaque (Ooi, Fig. 4.2); transparency sorted by depth peeling.

    Example
    -------
    >>> from flipstudy import builtin
    >>> img = ghost_image(builtin("backflip"), None, interval=0.2, size=(160, 120))  # a path writes a PNG
    >>> img.shape
    (120, 160, 3)
    """
    prep, c, b, ts, R, P = _posed(clip, body, takeoff, landing, camera, size, style, ground_bounds,
                                  span, margin, times, interval)
    with _scene(scene, prep, style, size) as sc:
        st = sc.style
        for i in range(len(ts)):
            ch = sc.character(("ghost", i), b)
            last = i == len(ts) - 1
            ch.look(st.body_color if last else st.ghost,
                    st.ghost_last_opacity if last else st.ghost_opacity)
            ch.pose(R[i], P[i])
        gz = _gizmos(debug, c, b)
        if gz is not None:
            gz.draw(sc, ts[-1], (ts[0], ts[-1]), st.ground_height)
        img = sc.grab()
    return _save(img, path)


# -------------------------------------------------------------------- trails
def _trail_points(clip: Clip, body: Body, name: str, times) -> np.ndarray:
    """(T,3) world positions of a trail target: a landmark of the body
    (pelvis, head, hand_l, knee_r, foot_l, ...), a skeleton joint name, or "com"."""
    pc = poses_at(clip, times)
    if name == "com":
        return center_of_mass(pc, body)
    key = _LANDMARK_OF.get(name, name)
    j = body.landmarks.get(key)
    if isinstance(j, str):
        return pc.joint_positions()[:, clip.skeleton.index(j)]
    if isinstance(j, tuple):                                  # a tip: (joint, end site)
        jj, e = j
        jj = clip.skeleton.index(jj) if isinstance(jj, str) else int(jj)
        off = clip.skeleton.end_sites[e][1] if e is not None else np.zeros(3)
        return pc.points(np.array([jj]), off[None])[:, 0]
    if name in clip.skeleton.joint_names:
        return pc.joint_positions()[:, clip.skeleton.index(name)]
    raise FlipstudyValueError(f"trail joint {name!r}: not a body landmark ({sorted(body.landmarks)}), "
                     f"'com', or a joint of the skeleton")


def trail_image(clip: Clip, path=None, *, joints=TRAIL_JOINTS, rate: float | None = None, span="flight",
                margin: float = 0.25, at: float | None = None, legend: bool | None = None,
                labels=None, size=(640, 480), style: Style | None = None, camera: Camera | None = None,
                body: Body | None = None, takeoff=None, landing=None, scene: Scene | None = None,
                ground_bounds=None, debug=()) -> np.ndarray:
    """Marker trails (Ooi, Fig. 4.1): markers on ``joints`` at ``rate`` per
    second (default ``style.trail_rate`` = 10), one colour-blind-safe colour per
    joint, a thin line through each path, a legend naming the colours (Ooi found
    the trails unreadable without one), and the character at time ``at``
    (default the last marker) drawn translucent.

    Example
    -------
    >>> from flipstudy import builtin
    >>> img = trail_image(builtin("backflip"), None, joints=("pelvis", "foot_l", "com"), size=(160, 120))
    >>> img.shape
    (120, 160, 3)
    """
    prep = _prepare1(clip, body, takeoff, landing, camera, size, style, ground_bounds)
    c, b = prep.clips[0], prep.bodies[0]
    st0 = scene.style if scene is not None else (style or DEFAULT_STYLE)
    rate = float(rate or st0.trail_rate)
    t0, t1 = _span(c, span, margin, prep.takeoffs[0], prep.landings[0])
    tm = _regular_times(t0, t1, 1.0 / rate)
    tl = np.linspace(t0, t1, max(2, int(round((t1 - t0) * 60)) + 1))
    t_at = tm[-1] if at is None else float(at)
    joints = list(joints)
    labels = list(labels) if labels is not None else [_LABEL.get(j, j) for j in joints]
    with _scene(scene, prep, style, size) as sc:
        st = sc.style
        pal = st.trail_palette
        entries = []
        k = 0
        for i, name in enumerate(joints):
            if name == "com":
                col = st.trail_com_color
            else:
                col, k = pal[k % len(pal)], k + 1
            sc.markers(("trail", i), len(tm), col).set(_trail_points(c, b, name, tm))
            if st.trail_line:
                sc.polyline(("trail", i), len(tl), col, st.trail_line_width).set(
                    _trail_points(c, b, name, tl))
            entries.append((labels[i], col))
        R, P, _ = _fk(c, [t_at])
        ch = sc.character("main", b)
        ch.look(st.trail_body_color, st.trail_body_opacity)
        ch.pose(R[0], P[0])
        gz = _gizmos(debug, c, b)
        if gz is not None:
            gz.draw(sc, t_at, (t0, t1), st.ground_height)
        show = st.legend if legend is None else legend
        fs = max(9, int(round(st.font_size * 0.5 * size[1])))
        paint = sc.legend(entries, fs) if show and find_font() is None else None  # VTK's font
        img = sc.grab()
        if paint is not None:
            paint(img)
    if show and find_font() is not None:
        draw_legend(img, [(lab, rgb8(col)) for lab, col in entries], fs,
                    background=rgb8(sc.style.background))
    return _save(img, path)


# --------------------------------------------------------------------- strip
def strip_image(clip: Clip, path=None, *, every: int | None = None, dt: float | None = 0.1,
                times=None, span="flight", margin: float = 0.25, panel_size=(200, 300),
                columns: int | None = None, track: bool = True, label: str = "t = {t:.2f} s",
                time_origin: str = "clip", style: Style | None = None, camera: Camera | None = None,
                body: Body | None = None, takeoff=None, landing=None, scene: Scene | None = None,
                ground_bounds=None, debug=(), boxes=()) -> np.ndarray:
    """An animation strip: the pose every ``every``-th source frame (or every
    ``dt`` seconds, or at ``times``) over ``span``, panels side by side
    (wrapped after ``columns``), each labelled with its time (``label`` format;
    ``time_origin="takeoff"`` counts from take-off).  With ``track`` every
    panel's camera follows the COM horizontally (same zoom in all panels; the
    ground shows the travel).  Panels are pasted with OpenImageIO; labels use
    OIIO ``render_text`` when a font file exists, else VTK's built-in font.
    ``boxes``: axis-aligned boxes ``[(lo, hi), ...]`` in the clip's coordinates
    (moved with it when it is staged), drawn with the ground.

    Example
    -------
    >>> from flipstudy import builtin
    >>> img = strip_image(builtin("backflip"), None, dt=0.15, panel_size=(80, 120), columns=4)
    >>> img.shape                                     # 4 × 2 panels of 80 × 120, 4 px apart
    (244, 332, 3)
    """
    pw, ph = int(panel_size[0]), int(panel_size[1])
    st0 = scene.style if scene is not None else (style or DEFAULT_STYLE)
    fs = max(8, int(round(st0.font_size * ph)))
    font = find_font()
    band = fs + 8 if font is not None else 0          # a label band above each render
    rh = ph - band
    prep = _prepare1(clip, body, takeoff, landing, camera, (pw, rh), style, ground_bounds)
    c, b = prep.clips[0], prep.bodies[0]
    t0, t1 = _span(c, span, margin, prep.takeoffs[0], prep.landings[0])
    if times is not None:
        ts = np.asarray(times, float)
    elif every is not None:
        ts = np.arange(int(np.ceil(t0 * c.fps - 1e-9)), int(np.floor(t1 * c.fps + 1e-9)) + 1,
                       int(every)) / c.fps
    else:
        ts = _regular_times(t0, t1, float(dt))
    R, P, pc = _fk(c, ts)
    cam = prep.camera
    offsets = np.zeros((len(ts), 3))
    if track:
        right = cam.basis()[0]
        right_h = np.array([right[0], 0.0, right[2]])
        right_h /= np.linalg.norm(right_h)
        com = center_of_mass(pc, b)
        offsets = np.outer(com @ right_h - (com @ right_h).mean(), right_h)
        pts = body_points(pc, b) - offsets[:, None, :]
        cam = fit_camera(pts.reshape(-1, 3), direction=right_h, size=(pw, rh),
                         view_angle=prep.camera.view_angle,
                         elevation=float(np.degrees(np.arcsin(np.clip(cam.basis()[2][1], -1, 1)))))
    if track and ground_bounds is None:
        gb = _ground_bounds([c], [b], (style or DEFAULT_STYLE).ground_margin, cam)
    else:
        gb = prep.ground_bounds
    prep = Prepared(prep.clips, prep.bodies, prep.takeoffs, prep.landings, cam, gb)
    t_ref = 0.0 if time_origin == "clip" else (prep.takeoffs[0] or 0) / c.fps
    texts = [label.format(t=t - t_ref) for t in ts]
    panels = []
    with _scene(scene, prep, style, (pw, rh)) as sc:
        sc.set_boxes(_placed_boxes(boxes, clip, c))
        st = sc.style
        bg = rgb8(st.background)
        gz = _gizmos(debug, c, b)
        ch = sc.character("main", b)
        ch.look(st.body_color, 1.0)
        for i in range(len(ts)):
            sc.set_camera(cam.translated(offsets[i]))
            ch.pose(R[i], P[i])
            if gz is not None:
                gz.draw(sc, ts[i], (ts[0], ts[i]), st.ground_height)
            if font is None:
                sc.text("label", texts[i], (6, ph - fs - 6), fs)
            img = sc.grab()
            if font is not None:
                panel = np.empty((ph, pw, 3), np.uint8)
                panel[:] = bg
                panel[band:] = img
                draw_text(panel, texts[i], 6, fs + 2, fs, rgb8(st.label_color))
                img = panel
            panels.append(img)
    return _save(grid(panels, columns, gap=4, background=bg), path)


# ----------------------------------------------------------------- composite
def composite_image(clip: Clip, path=None, *, interval: float = 0.2, span="flight", margin: float = 0.25,
                    times=None, opacity: float | None = None, size=(640, 480),
                    style: Style | None = None, camera: Camera | None = None, body: Body | None = None,
                    takeoff=None, landing=None, scene: Scene | None = None, ground_bounds=None,
                    debug=(), boxes=()) -> np.ndarray:
    """Composited frames (Ooi, Fig. 4.3): each pose rendered alone with a
    transparent background (the renderer's alpha channel is the matte), layered
    with ``ImageBufAlgo.over`` over a background plate — the first opaque, the
    rest at ``opacity`` (default ``style.layer_opacity`` = 75 %), later poses
    on top.  The matte painting Ooi did by hand, automated.  ``boxes`` (see
    :func:`strip_image`) are part of the background plate.

    Example
    -------
    >>> from flipstudy import builtin
    >>> img = composite_image(builtin("backflip"), None, interval=0.15, size=(160, 120))
    >>> img.shape
    (120, 160, 3)
    """
    prep, c, b, ts, R, P = _posed(clip, body, takeoff, landing, camera, size, style, ground_bounds,
                                  span, margin, times, interval)
    with _scene(scene, prep, style, size) as sc:
        sc.set_boxes(_placed_boxes(boxes, clip, c))
        st = sc.style
        op = st.layer_opacity if opacity is None else float(opacity)
        plate = sc.grab()                                   # ground and background only
        sc.show_ground(False)
        ch = sc.character("main", b)
        ch.look(st.body_color, 1.0)
        layers = []
        for i in range(len(ts)):
            ch.pose(R[i], P[i])
            layers.append(sc.grab(alpha=True))
        ch.visible = False
        gz = _gizmos(debug, c, b)
        if gz is not None:
            gz.draw(sc, ts[-1], (ts[0], ts[-1]), st.ground_height)
            layers.append(sc.grab(alpha=True))
        sc.show_ground(True)
    comp = over(layers, [1.0] + [op] * (len(ts) - 1) + ([1.0] if gz is not None else []))
    return _save(flatten(comp, plate), path)


# ------------------------------------------------------------------- overlay
def overlay_image(clip: Clip, other: Clip, path=None, *, interval: float = 0.2, span="flight",
                  margin: float = 0.25, times=None, labels=("original", "edited"), colors=None,
                  legend: bool = True, size=(640, 480), style: Style | None = None,
                  camera: Camera | None = None, body: Body | None = None, takeoff=None, landing=None,
                  scene: Scene | None = None, ground_bounds=None) -> np.ndarray:
    """An original and an edited clip as ghosts in two colours (yellow and
    turquoise, as in Majkowska & Faloutsos, Fig. 4), both placed at the same
    take-off spot under one camera; the last pose of each is opaque.

    Example
    -------
    >>> from flipstudy import analyse, builtin
    >>> from flipstudy.stimuli.injection import inject_angular_momentum
    >>> original = builtin("backflip")
    >>> edited = inject_angular_momentum(analyse(original), 0.5, "smooth").clip
    >>> img = overlay_image(original, edited, None, size=(160, 120))
    >>> img.shape
    (120, 160, 3)
    """
    prep = prepare([clip, other], bodies=None if body is None else [body, body],
                   takeoffs=None if takeoff is None else [takeoff, takeoff],
                   landings=None if landing is None else [landing, landing], camera=camera, size=size,
                   style=style, ground_bounds=ground_bounds)
    spans = [_span(c, span, margin, t, l) for c, t, l in
             zip(prep.clips, prep.takeoffs, prep.landings)]
    t0, t1 = min(s[0] for s in spans), max(s[1] for s in spans)
    ts = np.asarray(times, float) if times is not None else _regular_times(t0, t1, interval)
    with _scene(scene, prep, style, size) as sc:
        st = sc.style
        cols = colors or st.overlay_colors
        for k, (c, b) in enumerate(zip(prep.clips, prep.bodies)):
            tk = ts[ts <= c.duration + 1e-9]
            R, P, _ = _fk(c, tk)
            for i in range(len(tk)):
                last = i == len(tk) - 1
                ch = sc.character(("overlay", k, i), b, inflate=0.004 * k)
                ch.look(cols[k], 1.0 if last else st.overlay_opacity)
                ch.pose(R[i], P[i])
        fs = max(9, int(round(st.font_size * 0.5 * size[1])))
        paint = sc.legend(list(zip(labels, cols)), fs) if legend and find_font() is None else None
        img = sc.grab()
        if paint is not None:
            paint(img)
    if legend and find_font() is not None:
        draw_legend(img, [(lab, rgb8(col)) for lab, col in zip(labels, cols)], fs,
                    background=rgb8(sc.style.background))
    return _save(img, path)


__all__ = ["TRAIL_JOINTS", "DEBUG_ALL", "Prepared", "prepare", "Gizmos", "support_polygon",
           "iter_frames", "render_video", "ghost_image", "trail_image", "strip_image",
           "composite_image", "overlay_image"]
