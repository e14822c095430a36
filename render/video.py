"""Stimulus videos: the clip resampled to a display rate (rotations slerped,
root linear) and drawn frame by frame in one reused scene (:func:`iter_frames`),
encoded by the one H.264 writer of every video flipstudy writes
(:func:`h264_writer`: the rendered stimuli and the demo study's placeholders).

PyVista is imported only when a video is rendered (the demo's placeholders need
the encoder alone).
"""
from __future__ import annotations

import contextlib
from pathlib import Path

import numpy as np

from flipstudy.stimuli.body import Body
from flipstudy.errors import FlipstudyValueError
from flipstudy.stimuli.motion.clip import Clip

from .geometry import resample


#: The encoder settings of every video (recorded in ``render.json``).  The preset
#: was chosen by ``benchmarks/bench_encoder.py`` on real stimuli at 640x480: at
#: CRF 18 ``veryfast`` costs about two thirds of ``medium``'s CPU per frame for
#: files within a few per cent of the size and PSNR/SSIM as good (README, Benchmarks).
ENCODER = {"codec": "libx264", "crf": 18, "preset": "veryfast", "profile": "high",
           "pix_fmt": "yuv420p"}


def h264_writer(path, size, fps: float, *, crf: int = ENCODER["crf"],
                preset: str = ENCODER["preset"]):
    """A primed imageio-ffmpeg generator writing ``path``: H.264 High in MP4,
    yuv420p (plays in browsers), ``+faststart``, the settings of :data:`ENCODER`;
    send it (H, W, 3) uint8 RGB frames, then ``close()`` it.  Width and height
    must be even (yuv420p)."""
    import imageio_ffmpeg
    W, H = int(size[0]), int(size[1])
    if W % 2 or H % 2:
        raise FlipstudyValueError(f"video size {W}x{H}: width and height must be even for H.264 yuv420p")
    writer = imageio_ffmpeg.write_frames(
        str(path), (W, H), fps=float(fps), codec="libx264", pix_fmt_in="rgb24",
        pix_fmt_out="yuv420p", quality=None, macro_block_size=1, ffmpeg_log_level="error",
        output_params=["-crf", str(int(crf)), "-preset", preset, "-profile:v", "high",
                       "-movflags", "+faststart"])
    writer.send(None)
    return writer


def iter_frames(clip: Clip, scene, fps: float = 60.0, *, other: Clip | None = None,
                body: Body | None = None, other_body: Body | None = None, gizmos=None,
                colors=None):
    """Yield the frames (H,W,3 uint8) of ``clip`` sampled at ``fps`` in a
    scene set up for it (camera and ground set, e.g. by
    :func:`~flipstudy.render.scene.scene_for`).  The same buffer is reused: copy a
    frame to keep it.  ``other`` draws a second clip (overlay) in
    ``colors[1]``, over ``clip`` in ``colors[0]``.

    Parameters
    ----------
    clip : Clip
    scene : Scene
        Set up for the clip (camera and ground).
    fps : float
    other : Clip, optional
        A second clip drawn over the first.
    body, other_body : Body, optional
    gizmos : Gizmos, optional
    colors : tuple, optional

    Yields
    ------
    ndarray, shape (H, W, 3), uint8

    Examples
    --------
    >>> from flipstudy import builtin
    >>> from flipstudy.render import iter_frames, stage
    >>> from flipstudy.render.scene import scene_for
    >>> st = stage([builtin("jump")], size=(64, 48))
    >>> with scene_for(st) as sc:
    ...     shapes = {f.shape for f in iter_frames(st.clips[0], sc, fps=5, body=st.bodies[0])}
    >>> shapes
    {(48, 64, 3)}
    """
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
    # one character on a still ground: the ground rendered once (Scene.plate)
    plate = scene.plate() if other is None and gizmos is None else None
    for k in range(n):
        i = min(k, v.num_frames - 1)
        ch.pose(R[i], P[i])
        if other is not None:
            j = min(k, w.num_frames - 1)
            ch2.pose(R2[j], P2[j])
        if gizmos is not None:
            gizmos.draw(scene, i / fps, (0.0, i / fps), st.ground_height)
        yield scene.grab(out=buf, plate=plate)


def render_video(what, path, *, fps: float = 60.0, scene=None, debug=(), frames_dir=None,
                 crf: int = ENCODER["crf"]) -> Path:
    """Render a stimulus video of a :class:`~flipstudy.render.staging.Stage` (or a
    clip, staged with the defaults): its clip sampled at ``fps`` display
    frames per second (rotations slerped, root linear), at the stage's size,
    H.264 in MP4, yuv420p (plays in browsers); ``frames_dir`` also writes every
    frame as PNG.  A stage of two clips overlays the second (e.g. the edited
    one) in the second overlay colour.  ``scene``: a
    :class:`~flipstudy.render.scene.Scene` to reuse (e.g. one per worker);
    ``debug``: gizmos (see :mod:`flipstudy.render.gizmos`).

    Parameters
    ----------
    what : Stage or Clip
    path : str or pathlib.Path
        The ``.mp4`` to write.
    fps : float
        Display frames per second.
    scene : Scene, optional
    debug : sequence of str
    frames_dir : str or pathlib.Path, optional
    crf : int
        H.264 quality (lower: better, larger).

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from flipstudy import builtin
    >>> from flipstudy.render.staging import stage
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     mp4 = render_video(stage([builtin("backflip")], size=(160, 120)),
    ...                        pathlib.Path(tmp) / "backflip.mp4", fps=15)
    ...     mp4.name, mp4.stat().st_size > 1000
    ('backflip.mp4', True)
    """
    from .compose import write_png
    from .gizmos import debug_gizmos
    from .scene import scene_for
    from .staging import staged
    st = staged(what)
    W, H = st.size
    if W % 2 or H % 2:
        raise FlipstudyValueError(f"video size {W}x{H}: width and height must be even for H.264 yuv420p")
    if len(st.clips) > 2:
        raise FlipstudyValueError(f"render_video draws one clip, or two overlaid; this stage holds "
                                  f"{len(st.clips)} (pass stage.only(k))")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if frames_dir is not None:
        Path(frames_dir).mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    writer = h264_writer(tmp, (W, H), fps, crf=crf)
    try:
        with scene_for(st, scene) as sc:
            gz = debug_gizmos(debug, st.clips[0], st.bodies[0])
            for k, frame in enumerate(iter_frames(
                    st.clips[0], sc, fps, other=st.clips[1] if len(st.clips) > 1 else None,
                    body=st.bodies[0], other_body=st.bodies[-1], gizmos=gz)):
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


__all__ = ["ENCODER", "h264_writer", "iter_frames", "render_video"]
