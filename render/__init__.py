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
from flipstudy._lazy import attach

# PyVista (and scipy) load with the first name used: ``import flipstudy.render`` costs
# 0.4 ms, its names eagerly 1.2 s
attach(__name__, {
    ".style": ["Style", "DEFAULT_STYLE"],
    ".camera": ["Camera", "fit_camera"],
    ".staging": ["Stage", "stage", "Framing", "align_takeoff", "jump_direction", "translate", "place",
                 "orient_yaws"],
    ".geometry": ["BodyMesh", "resample", "poses_at", "body_points"],
    ".scene": ["Scene"],
    ".video": ["render_video", "iter_frames"],
    ".figures": ["ghost_image", "trail_image", "strip_image", "composite_image", "overlay_image",
                 "TRAIL_JOINTS"],
    ".gizmos": ["Gizmos"],
    ".compose": ["write_png", "read_image"],
    ".study": ["render_study"],
    ".record": ["RENDER_KINDS", "check_rendered"],
})

__all__ = ["Style", "DEFAULT_STYLE", "Camera", "fit_camera", "Stage", "stage", "Framing",
           "align_takeoff", "jump_direction", "translate", "place", "orient_yaws", "BodyMesh",
           "resample", "poses_at", "body_points", "Scene", "render_video", "iter_frames",
           "ghost_image", "trail_image", "strip_image", "composite_image", "overlay_image",
           "Gizmos", "TRAIL_JOINTS", "write_png", "read_image", "render_study", "RENDER_KINDS",
           "check_rendered"]
