"""What the still images of :mod:`flipstudy.render.figures` share: the times a
picture shows (a span around the flight, a regular grid), the clip posed at
them, the legend, and writing the PNG."""
from __future__ import annotations

import numpy as np

from flipstudy.errors import FlipstudyValueError
from flipstudy.stimuli.motion.clip import Clip

from .compose import draw_legend, find_font, write_png
from .geometry import poses_at
from .staging import Stage
from .style import rgb8


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



def _posed(st: Stage, span, margin: float, times, interval: float):
    """The stage's one clip posed at ``times`` (or every ``interval`` s over
    ``span``): (its clip, its body, times, joint rotations, joint positions)."""
    c, b = st.clips[0], st.bodies[0]
    t0, t1 = _span(c, span, margin, st.takeoffs[0], st.landings[0])
    ts = np.asarray(times, float) if times is not None else _regular_times(t0, t1, interval)
    R, P, _ = _fk(c, ts)
    return c, b, ts, R, P


def _save(img: np.ndarray, path) -> np.ndarray:
    if path is not None:
        write_png(path, img)
    return img


def _legend(sc, img_size, entries, legend: bool):
    """Draw a legend of ``entries`` [(label, colour)]: with VTK's font when no
    font file exists (returns the painter of its colour discs, to call on the
    grabbed image), else nothing yet (see :func:`_legend_after`)."""
    fs = max(9, int(round(sc.style.font_size * 0.5 * img_size[1])))
    paint = sc.legend(entries, fs) if legend and find_font() is None else None  # VTK's font
    return fs, paint


def _legend_after(img, sc, entries, fs: int, legend: bool) -> None:
    """The legend drawn onto the grabbed image with OpenImageIO (a font file exists)."""
    if legend and find_font() is not None:
        draw_legend(img, [(lab, rgb8(col)) for lab, col in entries], fs,
                    background=rgb8(sc.style.background))
