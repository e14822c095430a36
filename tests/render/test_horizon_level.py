"""Issue 33: 87_03's video showed a slightly tilted horizon.  The ground is an axis-aligned
rectangle; a camera looking across a diagonal travel saw its far edge slanted.  The stage
now turns the clips to travel along the nearest ground axis.  Measured on rendered frames:
the boundary between sky and ground, found per column, is level within 0.5°."""
import numpy as np
import pytest

from flipstudy.render.scene import scene_for
from flipstudy.render.staging import stage
from flipstudy.render.style import Style
from flipstudy.render.video import iter_frames
from flipstudy.stimuli import load_bvh

from _shared import shared_file


def horizon_tilt_deg(img) -> float:
    """Slope (degrees) of the first row, per column, where the picture leaves the sky colour
    (columns whose boundary lies in the upper 70 %: the sky/ground edge, not a body)."""
    sky = img[0, :, :].astype(int)
    differs = np.abs(img.astype(int) - sky[None]).sum(-1) > 24
    rows = np.argmax(differs, axis=0).astype(float)
    cols = np.arange(img.shape[1])
    ok = differs.any(0) & (rows > 2)
    med = np.median(rows[ok])
    ok &= np.abs(rows - med) < 4                        # a body above the edge: left out
    slope = np.polyfit(cols[ok], rows[ok], 1)[0]
    return float(np.degrees(np.arctan(slope)))


@pytest.mark.parametrize("name", ["87_03.bvh", "88_01.bvh"])
def test_a_diagonal_traveller_is_seen_with_a_level_horizon(name):
    clip = load_bvh(shared_file(name), fps=60)
    st = stage([clip], size=(320, 240), style=Style.from_dict({"legend": False}))
    assert abs(st.direction[0]) + abs(st.direction[2]) == 1.0      # along a ground axis
    with scene_for(st) as sc:
        frames = [f.copy() for k, f in enumerate(iter_frames(st.clips[0], sc, fps=10,
                                                              body=st.bodies[0])) if k in (0, 5)]
    for img in frames:
        assert abs(horizon_tilt_deg(img)) < 0.5
