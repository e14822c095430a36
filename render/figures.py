"""Ooi's still visualisations (Ooi 2016, Chapter 4) of a staged clip.

* :func:`ghost_image` — semi-transparent copies at a fixed interval (Fig. 4.2);
* :func:`trail_image` — markers on joints at 10 per second, with a legend (Fig. 4.1);
* :func:`strip_image` — an animation strip of labelled panels;
* :func:`composite_image` — layered frames, first opaque, the rest at 75 %,
  matted from the renderer's alpha channel (Fig. 4.3, which Ooi painted by hand);
* :func:`overlay_image` — an original and an edited clip in yellow and
  turquoise (Majkowska & Faloutsos 2007, Fig. 4);
* ``debug=`` on all but the overlay — COM and its path, angular momentum and
  velocity arrows at the COM, support polygon while in contact (Ooi's gizmos,
  Fig. 4.5; :mod:`flipstudy.render.gizmos`).

Every function draws a :class:`~flipstudy.render.staging.Stage` — the placed
clip, its body and flight, the camera, the image size, the
:class:`~flipstudy.render.style.Style`, the ground and its boxes — made once
by :func:`~flipstudy.render.staging.stage` and passed first; a bare clip is
staged with the defaults (take-off COM to the origin, one fitted side camera,
640×480, the default style, the flight :func:`flipstudy.stimuli.analyse`
finds).  The other keywords are the picture's own: which times (``span``,
``interval``, ``times``), ``scene`` (a :class:`~flipstudy.render.scene.Scene` to
reuse, e.g. one per worker, of the stage's style) and ``path`` (write a PNG
with OpenImageIO).  Images are returned as ``uint8`` arrays ``(H, W, 3)``.
Videos are :func:`flipstudy.render.video.render_video`.
"""
from __future__ import annotations

import numpy as np

from flipstudy.stimuli.body import Body
from flipstudy.errors import FlipstudyValueError
from flipstudy.stimuli.motion.clip import Clip
from flipstudy.stimuli.physics import center_of_mass

from .camera import fit_camera
from .compose import draw_text
from .geometry import body_points, poses_at
from .gizmos import debug_gizmos
from .scene import scene_for
from .staging import Stage, one_clip, staged
from .style import rgb8
from ._stills import _fk, _legend, _legend_after, _regular_times, _save, _span
from .strips import STRIP_DT, composite_image, jump_figures, overlay_image, strip_image  # noqa: F401

#: Default trail joints (Ooi used the pelvis and the leg joints; a legend is a must): the
#: extremities and the COM, five colours of the style's palette and black — few enough to
#: tell apart (the pelvis follows the COM, the knees the feet)
TRAIL_JOINTS = ("head", "hand_l", "hand_r", "foot_l", "foot_r", "com")
_LANDMARK_OF = {"hand_l": "wrist_l", "hand_r": "wrist_r", "foot_l": "ankle_l", "foot_r": "ankle_r"}
_LABEL = {"pelvis": "pelvis", "head": "head", "hand_l": "left hand", "hand_r": "right hand",
          "knee_l": "left knee", "knee_r": "right knee", "foot_l": "left foot",
          "foot_r": "right foot", "com": "centre of mass", "elbow_l": "left elbow",
          "elbow_r": "right elbow", "hip_l": "left hip", "hip_r": "right hip",
          "shoulder_l": "left shoulder", "shoulder_r": "right shoulder", "neck": "neck"}


# -------------------------------------------------------------------- ghosts
def key_times(clip: Clip, body: Body, takeoff, landing, *, between: int = 1,
              margin: float = 0.25) -> tuple[np.ndarray, list[str]]:
    """The instants a ghost picture shows, in seconds, and their names: the
    crouch ``margin`` s before take-off, take-off, ``between`` evenly spaced
    instants, the apex (highest COM), ``between`` more, landing, and ``margin``
    s after it (dropped when ``margin`` is 0).  Without a flight: ``2·between + 3``
    instants evenly over the clip, unnamed.

    Examples
    --------
    >>> from flipstudy import Body, builtin
    >>> clip = builtin("backflip")
    >>> ts, names = key_times(clip, Body.from_clip(clip), 157, 237)
    >>> names
    ['before', 'take-off', '', 'apex', '', 'landing', 'after']
    >>> bool(abs(ts[1] - 157 / clip.fps) < 1e-9 and abs(ts[5] - 237 / clip.fps) < 1e-9)
    True
    """
    between = max(0, int(between))
    if takeoff is None or landing is None or landing <= takeoff:
        return np.linspace(0.0, clip.duration, 2 * between + 3), [""] * (2 * between + 3)
    com = center_of_mass(clip.slice(int(takeoff), int(landing) + 1), body)
    t_to, t_la = takeoff / clip.fps, landing / clip.fps
    t_ap = (int(takeoff) + int(np.argmax(com[:, 1]))) / clip.fps
    up = np.linspace(t_to, t_ap, between + 2)
    down = np.linspace(t_ap, t_la, between + 2)
    ts = list(up) + list(down[1:])
    names = ["take-off"] + [""] * between + ["apex"] + [""] * between + ["landing"]
    if margin > 0:
        ts = [max(0.0, t_to - margin)] + ts + [min(clip.duration, t_la + margin)]
        names = ["before"] + names + ["after"]
    return np.asarray(ts, float), names


def _ramp(colors, n: int) -> list:
    """``n`` colours evenly along the ramp ``colors`` (interpolated in RGB)."""
    c = np.asarray([rgb8(x) for x in colors], float)
    if n <= 1:
        return [tuple(c[0] / 255.0)] * max(n, 0)
    u = np.linspace(0.0, len(c) - 1, n)
    i = np.minimum(u.astype(int), len(c) - 2)
    f = (u - i)[:, None]
    return [tuple(v) for v in ((c[i] * (1 - f) + c[i + 1] * f) / 255.0)]


def _ghost_looks(style, n: int) -> list[tuple]:
    """(colour, opacity) of each of ``n`` ghosts, earliest first: a time cue,
    the colour running along ``style.ghost_ramp`` (light to dark, so it reads
    in grey too; one ``ghost_color`` when set) and the opacity from
    ``ghost_opacity`` to ``ghost_late_opacity``; the last pose opaque in the
    body colour."""
    if n <= 0:
        return []
    m = n - 1
    cols = [style.ghost_color] * m if style.ghost_color else _ramp(style.ghost_ramp, m)
    ops = np.linspace(style.ghost_opacity, style.ghost_late_opacity, m) if m > 1 else \
        [style.ghost_opacity] * m
    return list(zip(cols, (float(o) for o in ops))) + [(style.body_color, style.ghost_last_opacity)]


#: metres between successive ghosts' centres of mass along the travel (:func:`auto_spread`)
GHOST_GAP = 0.45


def auto_spread(along, gap: float = GHOST_GAP) -> float:
    """The spread (metres per ghost) that puts successive ghosts' centres of mass,
    at ``along`` (their positions along the travel, in time order), at least ``gap``
    apart where the motion alone does not (0 for a motion that travels that far).

    >>> auto_spread([0.0, 0.05, 0.1]), auto_spread([0.0, 0.6, 1.2])
    (0.4, 0.0)
    """
    step = np.diff(np.asarray(along, float))
    return float(round(max(0.0, gap - step.min()), 6)) if step.size else 0.0


def _legend_room(st: Stage, n: int) -> float:
    """The fraction of the height a legend of ``n`` entries takes at the top (as
    :func:`~flipstudy.render.compose.draw_legend` sizes it), kept free of ghosts."""
    H = st.size[1]
    fs = max(9, int(round(st.style.font_size * 0.5 * H)))
    pad = max(4, fs // 3)
    return min(0.5, (2 * pad + int(round(fs * 1.3)) * n + pad) / H)


def _travel(st: Stage) -> np.ndarray:
    """Horizontal unit vector of the travel: the camera's right, on the ground."""
    r = np.asarray(st.camera.basis()[0], float)
    r = np.array([r[0], 0.0, r[2]])
    return r / np.linalg.norm(r)


def _scale_bar(img: np.ndarray, st: Stage, length: float = 1.0) -> None:
    """Draw a ``length`` m bar (in place) on the ground plane, at the depth of
    the take-off spot, where it covers the fewest pixels of the picture's
    action; labelled with its length."""
    cam, (W, H) = st.camera, st.size
    right = _travel(st)
    y = st.style.ground_height
    anchor = np.array([0.0, y, 0.0])               # the take-off spot, under the camera's focus
    bg = np.asarray(rgb8(st.style.background), int)
    busy = np.abs(img.astype(int) - bg).max(-1) > 60
    best = None
    for s in np.arange(-4.0, 4.01, 0.25):
        a, b = cam.project([anchor + s * right, anchor + (s + length) * right], (W, H))
        x0, x1, yy = int(round(a[0])), int(round(b[0])), int(round(0.5 * (a[1] + b[1])))
        if x0 < 6 or x1 > W - 6 or not 20 < yy < H - 4:
            continue
        cost = busy[max(0, yy - 18):yy + 4, x0:x1].mean()
        if best is None or cost < best[0] - 1e-9:
            best = (cost, x0, x1, yy)
    if best is None:
        return
    _, x0, x1, yy = best
    t = max(2, H // 160)
    col = np.asarray(rgb8(st.style.label_color), np.uint8)
    img[yy - t // 2:yy - t // 2 + t, x0:x1] = col
    img[yy - 3 * t:yy + t, x0:x0 + t] = col
    img[yy - 3 * t:yy + t, x1 - t:x1] = col
    fs = max(9, int(round(st.style.font_size * 0.45 * H)))
    draw_text(img, f"{length:g} m", (x0 + x1) // 2, yy - 3 * t - 3, fs, tuple(col), align="center")


def ghost_image(what, path=None, *, interval: float | None = None, span="flight",
                margin: float = 0.25, times=None, between: int = 1, spread: float | None = None,
                legend: bool | None = None, scene=None, debug=()) -> np.ndarray:
    """Ghosts that tell time: copies at the flight's key instants
    (:func:`key_times`: before take-off, take-off, apex, landing, after, and
    ``between`` evenly between; or every ``interval`` seconds over the
    ``span`` — ``"flight"`` ± ``margin`` s, ``"clip"``, ``(t0, t1)`` — or at
    ``times``), coloured and faded from early to late along the style's ramp,
    the last pose opaque in the body colour (Ooi, Fig. 4.2); transparency
    sorted by depth peeling.  ``spread`` (default ``style.ghost_spread``)
    metres moves each ghost that much further along the travel than the one
    before (the camera fitted again to keep them all); 0 spreads a motion that
    stays in place (a standing back flip) just enough that successive ghosts'
    centres of mass lie :data:`GHOST_GAP` m apart along the travel, so time reads
    from position as well as colour (:func:`auto_spread`).  A legend (default
    ``style.legend``) gives each colour's time and instant; a 1 m scale bar lies
    on the ground (``style.scale_bar``; the ground's checker tiles are
    ``style.ground_tile`` = 0.5 m).  ``what``: a
    :class:`~flipstudy.render.staging.Stage` of one clip, or a clip.

    Parameters
    ----------
    what : Stage or Clip
        A stage of one clip, or a clip (staged with the defaults).
    path : str or pathlib.Path, optional
        Where to write the PNG (None: only return the image).
    span : str or tuple of float
        ``"flight"`` (the flight ± ``margin`` s), ``"clip"`` (all of it) or
        ``(t0, t1)`` seconds: the part of the motion drawn.
    margin : float
        Seconds drawn before the take-off and after the landing.
    scene : Scene, optional
        A scene to draw in (default: the stage's).
    debug : sequence of str
        Debug gizmos to add (:data:`~flipstudy.render.gizmos.DEBUG_ALL`).

    Returns
    -------
    ndarray, shape (H, W, 3)
        The image, uint8.

    Examples
    --------
    >>> from flipstudy import builtin
    >>> from flipstudy.render.staging import stage
    >>> img = ghost_image(stage([builtin("backflip")], size=(160, 120)), None)  # a path writes a PNG
    >>> img.shape
    (120, 160, 3)
    """
    st = one_clip(staged(what), "ghost_image")
    c, b = st.clips[0], st.bodies[0]
    if times is None and interval is None:
        ts, names = key_times(c, b, st.takeoffs[0], st.landings[0], between=between, margin=margin)
        if span != "flight":
            t0, t1 = _span(c, span, margin, st.takeoffs[0], st.landings[0])
            ts, names = np.linspace(t0, t1, len(ts)), [""] * len(ts)
    else:
        ts = np.asarray(times, float) if times is not None else \
            _regular_times(*_span(c, span, margin, st.takeoffs[0], st.landings[0]), interval)
        names = [""] * len(ts)
    R, P, pc = _fk(c, ts)
    spread = st.style.ghost_spread if spread is None else float(spread)
    if not spread and len(ts) > 1:
        spread = auto_spread(center_of_mass(pc, b) @ _travel(st))
    shift = np.zeros((len(ts), 3))
    show = st.style.legend if legend is None else legend
    room = _legend_room(st, len(ts)) if show and len(ts) > 1 else 0.0
    if spread or (room and st.framing is not None):      # fitted again: spread, legend room
        shift = np.outer(np.arange(len(ts)) * spread, _travel(st))
        P = P + shift[:, None, :]
        fr = st.framing
        pts = (body_points(pc, b) + shift[:, None, :]).reshape(-1, 3)
        st = st.with_camera(fit_camera(pts, _travel(st), st.size,
                                       view_angle=fr.view_angle if fr else st.camera.view_angle,
                                       elevation=fr.elevation if fr else 8.0,
                                       margin=st.style.frame_margin, top=room))
    looks = []
    with scene_for(st, scene) as sc:
        looks = _ghost_looks(sc.style, len(ts))
        for i, (color, opacity) in enumerate(looks):
            ch = sc.character(("ghost", i), b)
            ch.look(color, opacity)
            ch.pose(R[i], P[i])
        gz = debug_gizmos(debug, c, b)
        if gz is not None:
            gz.draw(sc, ts[-1], (ts[0], ts[-1]), sc.style.ground_height)
        show = sc.style.legend if legend is None else legend
        t_ref = (st.takeoffs[0] or 0) / c.fps
        entries = [(("take-off" if n == "take-off" else f"{n or 'take-off'} {t - t_ref:+.2f} s")
                    if any(names) else f"t = {t:.2f} s", col)
                   for t, n, (col, _) in zip(ts, names, looks)] if len(ts) > 1 else []
        fs, paint = _legend(sc, st.size, entries, show and bool(entries))
        img = sc.grab()
        if paint is not None:
            paint(img)
    if sc.style.scale_bar and sc.style.ground:
        _scale_bar(img, st)
    _legend_after(img, sc, entries, fs, show and bool(entries))
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



def trail_image(what, path=None, *, joints=TRAIL_JOINTS, rate: float | None = None, span="flight",
                margin: float = 0.25, at: float | None = None, legend: bool | None = None,
                labels=None, scene=None, debug=()) -> np.ndarray:
    """Marker trails (Ooi, Fig. 4.1): markers on ``joints`` at ``rate`` per
    second (default ``style.trail_rate`` = 10), one colour-blind-safe colour per
    joint, a thin line through each path, a legend naming the colours (Ooi found
    the trails unreadable without one; ``legend`` default ``style.legend``),
    and the character at time ``at`` (default the last marker) drawn
    translucent.  ``what``: a :class:`~flipstudy.render.staging.Stage` of one
    clip, or a clip.

    Parameters
    ----------
    what : Stage or Clip
        A stage of one clip, or a clip (staged with the defaults).
    path : str or pathlib.Path, optional
        Where to write the PNG (None: only return the image).
    span : str or tuple of float
        ``"flight"`` (the flight ± ``margin`` s), ``"clip"`` (all of it) or
        ``(t0, t1)`` seconds: the part of the motion drawn.
    margin : float
        Seconds drawn before the take-off and after the landing.
    scene : Scene, optional
        A scene to draw in (default: the stage's).
    debug : sequence of str
        Debug gizmos to add (:data:`~flipstudy.render.gizmos.DEBUG_ALL`).

    Returns
    -------
    ndarray, shape (H, W, 3)
        The image, uint8.

    Examples
    --------
    >>> from flipstudy import builtin
    >>> from flipstudy.render.staging import stage
    >>> img = trail_image(stage([builtin("backflip")], size=(160, 120)), None,
    ...                   joints=("pelvis", "foot_l", "com"))
    >>> img.shape
    (120, 160, 3)
    """
    st = one_clip(staged(what), "trail_image")
    c, b = st.clips[0], st.bodies[0]
    rate = float(rate or st.style.trail_rate)
    t0, t1 = _span(c, span, margin, st.takeoffs[0], st.landings[0])
    tm = _regular_times(t0, t1, 1.0 / rate)
    tl = np.linspace(t0, t1, max(2, int(round((t1 - t0) * 60)) + 1))
    t_at = tm[-1] if at is None else float(at)
    joints = list(joints)
    labels = list(labels) if labels is not None else [_LABEL.get(j, j) for j in joints]
    with scene_for(st, scene) as sc:
        sty = sc.style
        pal = sty.trail_palette
        entries = []
        k = 0
        for i, name in enumerate(joints):
            if name == "com":
                col = sty.trail_com_color
            else:
                col, k = pal[k % len(pal)], k + 1
            sc.markers(("trail", i), len(tm), col).set(_trail_points(c, b, name, tm))
            if sty.trail_line:
                sc.polyline(("trail", i), len(tl), col, sty.trail_line_width).set(
                    _trail_points(c, b, name, tl))
            entries.append((labels[i], col))
        if len([j for j in joints if j != "com"]) > len(pal):
            raise FlipstudyValueError(f"trail_image: {len(joints)} trails but {len(pal)} colours in "
                                      f"the style's trail_palette (colours would repeat)")
        R, P, _ = _fk(c, [t_at])
        ch = sc.character("main", b)
        ch.look(sty.trail_body_color, sty.trail_body_opacity)
        ch.pose(R[0], P[0])
        gz = debug_gizmos(debug, c, b)
        if gz is not None:
            gz.draw(sc, t_at, (t0, t1), sty.ground_height)
        show = sty.legend if legend is None else legend
        fs, paint = _legend(sc, st.size, entries, show)
        img = sc.grab()
        if paint is not None:
            paint(img)
    if sty.scale_bar and sty.ground:
        _scale_bar(img, st)
    _legend_after(img, sc, entries, fs, show)
    return _save(img, path)


__all__ = ["TRAIL_JOINTS", "STRIP_DT", "jump_figures", "ghost_image", "trail_image", "strip_image",
           "composite_image", "overlay_image"]
