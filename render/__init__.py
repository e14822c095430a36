"""flipstudy.render: offscreen rendering of clips and studies (PyVista/VTK via EGL).

Stimulus videos and the visualisations of Ooi (2016, Chapter 4): ghosts,
marker trails, animation strips, layered composites, original/edited overlays
and debug gizmos — all with one style, one camera and one take-off spot per
study.  ::

    from flipstudy.render import stage, render_video, ghost_image, trail_image, strip_image
    st = stage([clip_a, clip_b])                       # same take-off spot, one camera
    render_video(st.clips[0], "a.mp4", camera=st.camera)
    ghost_image(clip, "ghost.png")                     # stages a single clip itself

PyVista is imported lazily (``flipstudy.render.plots`` is matplotlib only), and in EGL
offscreen mode (no X server).
"""
from __future__ import annotations

import importlib

_EXPORTS = {
    "Style": "style", "DEFAULT_STYLE": "style",
    "Camera": "camera", "Stage": "camera", "stage": "camera", "fit_camera": "camera",
    "align_takeoff": "camera", "jump_direction": "camera", "translate": "camera", "place": "camera",
    "orient_yaws": "camera",
    "BodyMesh": "geometry", "resample": "geometry", "poses_at": "geometry", "body_points": "geometry",
    "Scene": "scene",
    "prepare": "figures", "render_video": "figures", "iter_frames": "figures",
    "ghost_image": "figures", "trail_image": "figures", "strip_image": "figures",
    "composite_image": "figures", "overlay_image": "figures", "Gizmos": "figures",
    "TRAIL_JOINTS": "figures",
    "write_png": "compose", "read_image": "compose",
    "render_study": "study", "RENDER_KINDS": "study", "add_commands": "cli",
}


def __getattr__(name):
    mod = _EXPORTS.get(name)
    if mod is None:
        raise AttributeError(f"module 'render' has no attribute {name!r}")
    return getattr(importlib.import_module(f".{mod}", __name__), name)


def __dir__():
    return sorted(list(globals()) + list(_EXPORTS))


__all__ = list(_EXPORTS)
