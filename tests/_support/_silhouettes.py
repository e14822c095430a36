"""What a rendered video shows, measured on its pixels: the frames of an mp4 and
the box of everything that differs from a plain background (render with the
ground off, so that only the character differs)."""
from __future__ import annotations

import numpy as np


def video_frames(mp4) -> np.ndarray:
    """(F, H, W, 3) uint8 frames of a video file (imageio-ffmpeg)."""
    import imageio_ffmpeg
    rd = imageio_ffmpeg.read_frames(str(mp4))
    meta = next(rd)
    W, H = meta["size"]
    return np.stack([np.frombuffer(f, np.uint8).reshape(H, W, 3) for f in rd])


def silhouette_union(frames: np.ndarray, background, threshold: int = 40) -> np.ndarray:
    """(H, W) bool: the pixels that differ from ``background`` in any frame."""
    return (np.abs(frames.astype(int) - np.asarray(background, int)).max(-1) > threshold).any(0)


def box(mask: np.ndarray) -> tuple:
    """(x0, x1, y0, y1) pixels of the True pixels of ``mask`` (end exclusive)."""
    ys, xs = np.nonzero(mask)
    return xs.min(), xs.max() + 1, ys.min(), ys.max() + 1


def span_and_offset(mask: np.ndarray) -> tuple[float, float, float]:
    """(fill, dx, dy): the larger of the box's width and height fractions, and its
    centre's offset from the frame's centre as fractions of width and height."""
    H, W = mask.shape
    x0, x1, y0, y1 = box(mask)
    return (max((x1 - x0) / W, (y1 - y0) / H), (0.5 * (x0 + x1) - W / 2) / W,
            (0.5 * (y0 + y1) - H / 2) / H)
