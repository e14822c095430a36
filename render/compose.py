"""Image files and 2D compositing with OpenImageIO.

Arrays are ``uint8`` images ``img[y, x, c]`` (top row first), RGB or RGBA;
RGBA from :meth:`flipstudy.render.scene.Scene.grab` has *premultiplied* colour (VTK
blends onto a transparent background), which is what ``ImageBufAlgo.over``
expects.
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyOSError

import glob
import os
from functools import lru_cache
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

_FONT_CANDIDATES = ("DejaVuSans.ttf", "LiberationSans-Regular.ttf", "Arial.ttf", "arial.ttf",
                    "FreeSans.ttf", "NotoSans-Regular.ttf", "Roboto-Regular.ttf")
_FONT_DIRS = ("/usr/share/fonts", "/usr/local/share/fonts", "/Library/Fonts",
              "/System/Library/Fonts", "C:/Windows/Fonts", os.path.expanduser("~/.fonts"),
              os.path.expanduser("~/.local/share/fonts"))


@lru_cache(maxsize=1)
def find_font() -> str | None:
    """Path of a sans-serif TrueType font for OIIO's ``render_text`` (OIIO
    needs a path here), or ``None`` when the system has none (labels are then
    drawn by VTK's built-in font before the screenshot)."""
    env = os.environ.get("FLIPSTUDY_FONT")
    if env and Path(env).is_file():
        return env
    for name in _FONT_CANDIDATES:
        for d in _FONT_DIRS:
            hits = glob.glob(os.path.join(d, "**", name), recursive=True)
            if hits:
                return sorted(hits)[0]
    return None


def to_buf(img: np.ndarray) -> oiio.ImageBuf:
    """An ImageBuf holding a copy of a uint8 image array."""
    img = np.ascontiguousarray(img)
    h, w = img.shape[:2]
    c = 1 if img.ndim == 2 else img.shape[2]
    buf = oiio.ImageBuf(oiio.ImageSpec(w, h, c, oiio.UINT8))
    if not buf.set_pixels(oiio.ROI(0, w, 0, h, 0, 1, 0, c), img):
        raise RuntimeError(f"OpenImageIO: set_pixels failed: {buf.geterror()}")
    if c == 4:
        buf.specmod().alpha_channel = 3
    return buf


def from_buf(buf: oiio.ImageBuf) -> np.ndarray:
    """uint8 array (H,W,C) of an ImageBuf."""
    return np.asarray(buf.get_pixels(oiio.UINT8))


def write_png(path, img, *, compression: int = 6) -> Path:
    """Write an image array (or ImageBuf) as PNG with OpenImageIO; parent folders
    are created.  Returns the path.

    Parameters
    ----------
    path : str or pathlib.Path
    img : ndarray, shape (H, W, C), or OpenImageIO.ImageBuf
    compression : int, default 6
        zlib's level (6, zlib's default: half the CPU of 9 for files about 10 %
        larger, measured on stimulus frames).

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> from flipstudy.render import read_image, write_png
    >>> img = np.arange(24, dtype=np.uint8).reshape(2, 4, 3)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     back = read_image(write_png(pathlib.Path(tmp) / "sub" / "a.png", img))
    >>> bool((back == img).all())
    True
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    buf = img if isinstance(img, oiio.ImageBuf) else to_buf(img)
    buf.specmod().attribute("png:compressionLevel", int(compression))
    buf.specmod().attribute("oiio:UnassociatedAlpha", 0)
    if not buf.write(str(path)):
        raise FlipstudyOSError(f"{path}: cannot write PNG: {buf.geterror() or oiio.geterror()}")
    return path


def read_image(path) -> np.ndarray:
    """An image file as a uint8 array (H,W,C).

    Parameters
    ----------
    path : str or pathlib.Path
        Any image file OpenImageIO reads.

    Returns
    -------
    ndarray, shape (H, W, C), uint8

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> from flipstudy.render import read_image, write_png
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     img = read_image(write_png(pathlib.Path(tmp) / "a.png", np.zeros((3, 5, 3), np.uint8)))
    >>> img.shape, img.dtype.name
    ((3, 5, 3), 'uint8')
    """
    buf = oiio.ImageBuf(str(path))
    if buf.has_error:
        raise FlipstudyOSError(f"{path}: cannot read image: {buf.geterror()}")
    return from_buf(buf)


def over(layers, opacities=None) -> np.ndarray:
    """Composite premultiplied RGBA layers (first = bottom) with
    ``ImageBufAlgo.over``; ``opacities`` (one per layer) scale each layer
    (colour and alpha, as premultiplied alpha requires).  The result is RGBA."""
    layers = list(layers)
    if not layers:
        raise ValueError("over: no layers")
    opacities = [1.0] * len(layers) if opacities is None else list(opacities)
    acc = None
    for img, o in zip(layers, opacities):
        buf = to_buf(img)
        if o != 1.0:
            scaled = oiio.ImageBuf()
            oiio.ImageBufAlgo.mul(scaled, buf, float(o))
            buf = scaled
        if acc is None:
            acc = buf
            continue
        out = oiio.ImageBuf()
        if not oiio.ImageBufAlgo.over(out, buf, acc):
            raise RuntimeError(f"OpenImageIO over failed: {out.geterror()}")
        acc = out
    return from_buf(acc)


def flatten(rgba: np.ndarray, background) -> np.ndarray:
    """RGB of a premultiplied RGBA image over an opaque colour or RGB image."""
    rgba = rgba.astype(np.float32) / 255.0
    bg = np.asarray(background, np.float32)
    if np.asarray(background).dtype == np.uint8 or bg.max() > 1.0:
        bg = bg / 255.0
    bg = np.broadcast_to(bg, rgba.shape[:2] + (3,))
    out = rgba[..., :3] + bg * (1.0 - rgba[..., 3:4])
    return np.clip(np.rint(out * 255.0), 0, 255).astype(np.uint8)


def draw_text(img: np.ndarray, text: str, x: int, y: int, size: int, color=(0, 0, 0),
              align: str = "left") -> bool:
    """Draw ``text`` into ``img`` (in place) with OIIO ``render_text``, the
    baseline at ``y``; returns False when no font is available."""
    font = find_font()
    if font is None:
        return False
    buf = to_buf(img)
    c = np.asarray(color, float)
    c = c / 255.0 if c.max() > 1 else c
    col = tuple(c) + ((1.0,) if img.shape[2] == 4 else ())
    if align != "left":
        roi = oiio.ImageBufAlgo.text_size(text, size, font)
        w = roi.xend - roi.xbegin
        x = x - (w // 2 if align == "center" else w)
    ok = oiio.ImageBufAlgo.render_text(buf, int(x), int(y), text, int(size), font, col)
    if not ok:
        buf.geterror()
        return False
    img[...] = from_buf(buf)
    return True


def grid(panels, columns: int | None = None, gap: int = 4, background=(255, 255, 255)) -> np.ndarray:
    """Panels (equal-size arrays) pasted left to right (wrapping after
    ``columns``) with ``ImageBufAlgo.paste``."""
    panels = list(panels)
    if not panels:
        raise ValueError("grid: no panels")
    h, w, c = panels[0].shape
    n = len(panels)
    cols = n if not columns else min(int(columns), n)
    rows = -(-n // cols)
    W, H = cols * w + (cols - 1) * gap, rows * h + (rows - 1) * gap
    out = oiio.ImageBuf(oiio.ImageSpec(W, H, c, oiio.UINT8))
    bg = np.asarray(background, float)
    bg = tuple(bg / 255.0 if bg.max() > 1 else bg) + ((1.0,) if c == 4 and len(bg) == 3 else ())
    oiio.ImageBufAlgo.fill(out, bg[:c])
    for i, p in enumerate(panels):
        r, k = divmod(i, cols)
        if not oiio.ImageBufAlgo.paste(out, k * (w + gap), r * (h + gap), 0, 0, to_buf(p)):
            raise RuntimeError(f"OpenImageIO paste failed: {out.geterror()}")
    return from_buf(out)


def draw_legend(img: np.ndarray, entries, font_size: int, *, loc: str = "auto",
                text_color=(34, 34, 34), box_color=(255, 255, 255), box_opacity: float = 0.88,
                pad: int | None = None, background=None) -> bool:
    """Draw a legend — a filled disc of each colour and its label in dark text
    — into ``img`` (RGB uint8, in place), in a light box at ``loc`` ("upper
    left", "upper right", or "auto": the one covering fewer pixels that differ
    from ``background``).  Returns False when no font is available (use the
    VTK legend then).  ``entries``: (label, (r, g, b) 0..255) pairs."""
    font = find_font()
    if font is None or not entries:
        return False
    fs = int(font_size)
    pad = pad if pad is not None else max(4, fs // 3)
    widths = []
    for lab, _ in entries:
        roi = oiio.ImageBufAlgo.text_size(str(lab), fs, font)
        widths.append(max(0, roi.xend - roi.xbegin))
    line = int(round(fs * 1.3))
    r = max(3, int(round(fs * 0.36)))
    bw = pad * 3 + 2 * r + max(widths)
    bh = pad * 2 + line * len(entries)
    H, W = img.shape[:2]
    if loc == "auto":        # the upper corner that hides less of the picture
        ref = img[H - 1, W // 2, :3].astype(int) if background is None else np.asarray(background, int)
        busy = [np.abs(img[pad:pad + bh, x:x + bw, :3].astype(int) - ref).max(-1).__gt__(12).mean()
                for x in (pad, max(0, W - bw - pad))]
        loc = "upper left" if busy[0] <= busy[1] else "upper right"
    x0 = pad if loc == "upper left" else W - bw - pad
    y0 = pad
    x1, y1 = min(W, x0 + bw), min(H, y0 + bh)
    region = img[y0:y1, x0:x1, :3].astype(np.float32)
    img[y0:y1, x0:x1, :3] = np.rint(region * (1 - box_opacity)
                                    + np.asarray(box_color, np.float32) * box_opacity).astype(np.uint8)
    border = np.asarray((160, 160, 160), np.uint8)
    img[y0, x0:x1, :3] = border
    img[y1 - 1, x0:x1, :3] = border
    img[y0:y1, x0, :3] = border
    img[y0:y1, x1 - 1, :3] = border
    yy, xx = np.mgrid[0:H, 0:W]
    for i, (lab, col) in enumerate(entries):
        cy = y0 + pad + line * i + line // 2
        cx = x0 + pad + r
        d2 = (xx[cy - r - 1:cy + r + 2, cx - r - 1:cx + r + 2] - cx) ** 2 + \
            (yy[cy - r - 1:cy + r + 2, cx - r - 1:cx + r + 2] - cy) ** 2
        patch = img[cy - r - 1:cy + r + 2, cx - r - 1:cx + r + 2, :3]
        patch[d2 <= (r + 1) ** 2] = np.asarray(text_color, np.uint8)[:3]   # a ring: white shows too
        patch[d2 <= (r - 0.5) ** 2] = np.asarray(col, np.uint8)[:3]
        draw_text(img, str(lab), cx + r + pad, cy + int(round(fs * 0.36)), fs, text_color)
    return True
