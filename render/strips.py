"""Ooi's still visualisations of frames side by side or on top of one another
(Ooi 2016, Chapter 4), part of :mod:`flipstudy.render.figures`, which re-exports them.

* :func:`strip_image` — an animation strip of labelled panels;
* :func:`composite_image` — layered frames, first opaque, the rest at 75 %,
  matted from the renderer's alpha channel (Fig. 4.3);
* :func:`overlay_image` — an original and an edited clip in yellow and
  turquoise (Majkowska & Faloutsos 2007, Fig. 4);
* :func:`jump_figures` — the strip and the composite of a controlled jump.

They draw a :class:`~flipstudy.render.staging.Stage` (or stage a bare clip with the
defaults), like the ghosts and trails of :mod:`flipstudy.render.figures`.
"""
from __future__ import annotations

import numpy as np

from flipstudy.errors import FlipstudyValueError
from flipstudy.stimuli.motion.clip import Clip
from flipstudy.stimuli.physics import center_of_mass

from .camera import fit_camera
from .compose import draw_text, find_font, flatten, grid, over
from .geometry import body_points
from .gizmos import debug_gizmos
from .scene import scene_for
from .staging import Stage, one_clip, staged
from .style import rgb8
from ._stills import _fk, _legend, _legend_after, _posed, _regular_times, _save, _span


# --------------------------------------------------------------------- strip
def _strip_times(c: Clip, t0: float, t1: float, every, dt, times) -> np.ndarray:
    if times is not None:
        return np.asarray(times, float)
    if every is not None:
        return np.arange(int(np.ceil(t0 * c.fps - 1e-9)), int(np.floor(t1 * c.fps + 1e-9)) + 1,
                         int(every)) / c.fps
    return _regular_times(t0, t1, float(dt))



def _tracking(st: Stage, pc: Clip, size) -> tuple[Stage, np.ndarray]:
    """The stage under a camera that follows the COM horizontally (same zoom in
    every panel), and each panel's offset (T,3) of that camera."""
    cam = st.camera
    right = cam.basis()[0]
    right_h = np.array([right[0], 0.0, right[2]])
    right_h /= np.linalg.norm(right_h)
    com = center_of_mass(pc, st.bodies[0])
    offsets = np.outer(com @ right_h - (com @ right_h).mean(), right_h)
    pts = body_points(pc, st.bodies[0]) - offsets[:, None, :]
    cam = fit_camera(pts.reshape(-1, 3), direction=right_h, size=size, view_angle=cam.view_angle,
                     elevation=float(np.degrees(np.arcsin(np.clip(cam.basis()[2][1], -1, 1)))))
    return st.with_camera(cam), offsets



def strip_image(what, path=None, *, every: int | None = None, dt: float | None = 0.1,
                times=None, span="flight", margin: float = 0.25, panel_size=(200, 300),
                columns: int | None = None, track: bool = True, label: str = "t = {t:.2f} s",
                time_origin: str = "clip", scene=None, debug=()) -> np.ndarray:
    """An animation strip: the pose every ``every``-th source frame (or every
    ``dt`` seconds, or at ``times``) over ``span``, panels of ``panel_size``
    side by side (wrapped after ``columns``), each labelled with its time
    (``label`` format; ``time_origin="takeoff"`` counts from take-off).  With
    ``track`` every panel's camera follows the COM horizontally (same zoom in
    all panels; the ground shows the travel).  Panels are pasted with
    OpenImageIO; labels use OIIO ``render_text`` when a font file exists, else
    VTK's built-in font.  ``what``: a :class:`~flipstudy.render.staging.Stage` of
    one clip (its camera fitted again for the panels, its boxes drawn with the
    ground), or a clip.

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
    >>> img = strip_image(builtin("backflip"), None, dt=0.15, panel_size=(80, 120), columns=4)
    >>> img.shape                                     # 4 × 2 panels of 80 × 120, 4 px apart
    (244, 332, 3)
    """
    pw, ph = int(panel_size[0]), int(panel_size[1])
    st = one_clip(staged(what), "strip_image")
    fs = max(8, int(round(st.style.font_size * ph)))
    font = find_font()
    band = fs + 8 if font is not None else 0          # a label band above each render
    rh = ph - band
    st = st.resized((pw, rh))
    c, b = st.clips[0], st.bodies[0]
    t0, t1 = _span(c, span, margin, st.takeoffs[0], st.landings[0])
    ts = _strip_times(c, t0, t1, every, dt, times)
    R, P, pc = _fk(c, ts)
    offsets = np.zeros((len(ts), 3))
    if track:
        st, offsets = _tracking(st, pc, (pw, rh))
    t_ref = 0.0 if time_origin == "clip" else (st.takeoffs[0] or 0) / c.fps
    texts = [label.format(t=t - t_ref) for t in ts]
    panels = []
    with scene_for(st, scene) as sc:
        sty = sc.style
        bg = rgb8(sty.background)
        gz = debug_gizmos(debug, c, b)
        ch = sc.character("main", b)
        ch.look(sty.body_color, 1.0)
        for i in range(len(ts)):
            sc.set_camera(st.camera.translated(offsets[i]))
            ch.pose(R[i], P[i])
            if gz is not None:
                gz.draw(sc, ts[i], (ts[0], ts[i]), sty.ground_height)
            if font is None:
                sc.text("label", texts[i], (6, ph - fs - 6), fs)
            img = sc.grab()
            if font is not None:
                panel = np.empty((ph, pw, 3), np.uint8)
                panel[:] = bg
                panel[band:] = img
                draw_text(panel, texts[i], 6, fs + 2, fs, rgb8(sty.label_color))
                img = panel
            panels.append(img)
    return _save(grid(panels, columns, gap=4, background=bg), path)



# ----------------------------------------------------------------- composite
def composite_image(what, path=None, *, interval: float = 0.2, span="flight", margin: float = 0.25,
                    times=None, opacity: float | None = None, scene=None, debug=()) -> np.ndarray:
    """Composited frames (Ooi, Fig. 4.3): each pose rendered alone with a
    transparent background (the renderer's alpha channel is the matte), layered
    with ``ImageBufAlgo.over`` over a background plate — the first opaque, the
    rest at ``opacity`` (default ``style.layer_opacity`` = 75 %), later poses
    on top.  The matte painting Ooi did by hand, automated.  The stage's boxes
    are part of the background plate.  ``what``: a
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
    >>> img = composite_image(stage([builtin("backflip")], size=(160, 120)), None, interval=0.15)
    >>> img.shape
    (120, 160, 3)
    """
    st = one_clip(staged(what), "composite_image")
    c, b, ts, R, P = _posed(st, span, margin, times, interval)
    with scene_for(st, scene) as sc:
        sty = sc.style
        op = sty.layer_opacity if opacity is None else float(opacity)
        plate = sc.grab()                                   # ground and background only
        sc.show_ground(False)
        ch = sc.character("main", b)
        ch.look(sty.body_color, 1.0)
        layers = []
        for i in range(len(ts)):
            ch.pose(R[i], P[i])
            layers.append(sc.grab(alpha=True))
        ch.visible = False
        gz = debug_gizmos(debug, c, b)
        if gz is not None:
            gz.draw(sc, ts[-1], (ts[0], ts[-1]), sty.ground_height)
            layers.append(sc.grab(alpha=True))
        sc.show_ground(True)
    comp = over(layers, [1.0] + [op] * (len(ts) - 1) + ([1.0] if gz is not None else []))
    return _save(flatten(comp, plate), path)



# ------------------------------------------------------------------- overlay
def overlay_image(what, path=None, *, interval: float = 0.2, span="flight", margin: float = 0.25,
                  times=None, labels=("original", "edited"), colors=None, legend: bool = True,
                  scene=None) -> np.ndarray:
    """An original and an edited clip as ghosts in two colours (``colors``,
    default the style's yellow and turquoise, as in Majkowska & Faloutsos,
    Fig. 4), under one camera; the last pose of each is opaque.  ``what``: a
    :class:`~flipstudy.render.staging.Stage` of the two clips, or the two clips
    (staged together: same take-off spot).

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
    >>> from flipstudy import analyse, builtin
    >>> from flipstudy.render.staging import stage
    >>> from flipstudy.stimuli.injection import inject_angular_momentum
    >>> original = builtin("backflip")
    >>> edited = inject_angular_momentum(analyse(original), 0.5, "smooth").clip
    >>> img = overlay_image(stage([original, edited], size=(160, 120)), None)
    >>> img.shape
    (120, 160, 3)
    """
    st = staged(what)
    if len(st.clips) != 2:
        raise FlipstudyValueError(f"overlay_image draws two clips; this stage holds {len(st.clips)}")
    spans = [_span(c, span, margin, t, l) for c, t, l in zip(st.clips, st.takeoffs, st.landings)]
    t0, t1 = min(s[0] for s in spans), max(s[1] for s in spans)
    ts = np.asarray(times, float) if times is not None else _regular_times(t0, t1, interval)
    with scene_for(st, scene) as sc:
        sty = sc.style
        cols = colors or sty.overlay_colors
        for k, (c, b) in enumerate(zip(st.clips, st.bodies)):
            tk = ts[ts <= c.duration + 1e-9]
            R, P, _ = _fk(c, tk)
            for i in range(len(tk)):
                last = i == len(tk) - 1
                ch = sc.character(("overlay", k, i), b, inflate=0.004 * k)
                ch.look(cols[k], 1.0 if last else sty.overlay_opacity)
                ch.pose(R[i], P[i])
        entries = list(zip(labels, cols))
        fs, paint = _legend(sc, st.size, entries, legend)
        img = sc.grab()
        if paint is not None:
            paint(img)
    _legend_after(img, sc, entries, fs, legend)
    return _save(img, path)



#: the strip of the thesis: frames collected at 10 fps, one in five shown (5.3)
STRIP_DT = 0.5



def jump_figures(res, strip=None, composite=None, *, strip_dt: float = STRIP_DT, size=(640, 480),
                 interval: float = 0.1) -> dict:
    """The animation strip (one frame in five at 10 fps, the whole clip) and the
    composite (flight ± 0.25 s every ``interval`` s) of a jump
    (:class:`flipstudy.stimuli.control.JumpResult`), with the boxes of its
    course.  Returns the paths written."""
    from .staging import stage
    clip = res.clip
    st = stage([clip], [res.takeoff], [max(res.landing, res.takeoff)],
               size=size, boxes=[tuple(b) for b in clip.meta.get("boxes", [])])
    out = {}
    if strip:
        h = size[1]
        strip_image(st, strip, dt=strip_dt, span="clip", panel_size=(2 * int(round(0.35 * h)), h),
                    label="t = {t:.1f} s")
        out["strip"] = str(strip)
    if composite:
        composite_image(st, composite, interval=interval, span="flight", margin=0.25)
        out["composite"] = str(composite)
    return out
