"""The figure sheet shows its ghost and trail images at least at their own
pixel size (issue 33: a 640x480 ghost's legend came out about 7 px high)."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest


@pytest.mark.parametrize("size", [(640, 480), (320, 240)])
def test_sheet_images_are_drawn_at_least_at_their_pixel_size(tmp_path, size):
    import OpenImageIO as oiio
    from matplotlib.image import AxesImage
    from flipstudy.analysis.figures import PNG_DPI, sheet_figure
    W, H = size
    images = {}
    for k in range(4):
        p = tmp_path / f"img{k}.png"
        px = np.full((H, W, 3), 200, np.uint8)
        px[H // 4:H // 2, W // 4:W // 2] = (30, 60, 120)
        spec = oiio.ImageSpec(W, H, 3, oiio.UINT8)
        out = oiio.ImageOutput.create(str(p))
        out.open(str(p), spec)
        out.write_image(px)
        out.close()
        images[f"panel {k}\nsecond line"] = p
    fig, notes = sheet_figure([], pd.DataFrame({"group": ["smooth-increase"]}), images)
    assert notes == []
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    FigureCanvasAgg(fig)
    fig.set_dpi(PNG_DPI)
    fig.canvas.draw()          # constrained layout done: the axes have their final size
    shown = [im for ax in fig.get_axes() for im in ax.get_images() if isinstance(im, AxesImage)]
    assert len(shown) == 4
    for im in shown:
        box = im.get_window_extent()                     # display pixels at PNG_DPI
        assert box.width >= 0.99 * W and box.height >= 0.99 * H, (box.width, box.height, size)
