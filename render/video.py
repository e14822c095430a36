"""The one H.264 encoder (imageio-ffmpeg) of every video flipstudy writes: the
rendered stimuli and the demo study's placeholders."""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyValueError


def h264_writer(path, size, fps: float, *, crf: int = 18, preset: str = "medium"):
    """A primed imageio-ffmpeg generator writing ``path``: H.264 High in MP4,
    yuv420p (plays in browsers), ``+faststart``; send it (H, W, 3) uint8 RGB frames,
    then ``close()`` it.  Width and height must be even (yuv420p)."""
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
