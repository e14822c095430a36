"""flipstudy.render: offscreen rendering of clips and studies (PyVista/VTK via EGL).

Stimulus videos and the visualisations of Ooi (2016, Chapter 4): ghosts,
marker trails, animation strips, layered composites, original/edited overlays
and debug gizmos — all with one style, one camera and one take-off spot per
study.  ::

    from flipstudy.render import stage, render_video, ghost_image, overlay_image
    st = stage([clip_a, clip_b], size=(640, 480))     # same take-off spot, one camera
    render_video(st.only(0), "a.mp4")                  # each picture drawn from the Stage
    overlay_image(st, "a_over_b.png")
    ghost_image(clip, "ghost.png")                     # stages a single clip itself

The :class:`Stage` (:mod:`flipstudy.render.staging`) holds what every picture
needs: the placed clips, their bodies and flights, the camera, the size, the
:class:`Style`, the ground and its boxes.  Modules: ``staging`` and ``camera``
(placing, framing), ``scene`` and ``actors`` (the reused plotter), ``video``
and ``figures`` (what is drawn), ``gizmos`` (debug overlays), ``study``,
``workers`` and ``record`` (a whole study, its worker processes and
``render.json``).

PyVista is imported lazily (``flipstudy.render.plots`` is matplotlib only), and in EGL
offscreen mode (no X server).
"""
from __future__ import annotations

import importlib

_EXPORTS = {
    "Style": "style", "DEFAULT_STYLE": "style",
    "Camera": "camera", "fit_camera": "camera",
    "Stage": "staging", "stage": "staging", "Framing": "staging",
    "align_takeoff": "staging", "jump_direction": "staging", "translate": "staging", "place": "staging",
    "orient_yaws": "staging",
    "BodyMesh": "geometry", "resample": "geometry", "poses_at": "geometry", "body_points": "geometry",
    "Scene": "scene",
    "render_video": "video", "iter_frames": "video",
    "ghost_image": "figures", "trail_image": "figures", "strip_image": "figures",
    "composite_image": "figures", "overlay_image": "figures", "Gizmos": "gizmos",
    "TRAIL_JOINTS": "figures",
    "write_png": "compose", "read_image": "compose",
    "render_study": "study", "RENDER_KINDS": "record", "check_rendered": "record",
}


def __getattr__(name):
    mod = _EXPORTS.get(name)
    if mod is None:
        raise AttributeError(f"module 'render' has no attribute {name!r}")
    return getattr(importlib.import_module(f".{mod}", __name__), name)


def __dir__():
    return sorted(list(globals()) + list(_EXPORTS))


__all__ = list(_EXPORTS)
