"""Issue 33: ghosts of an in-place back flip piled into one blob (time only by colour).
With the default spread, successive ghosts stand GHOST_GAP apart along the travel, so time
reads from position: measured on the rendered picture, early (yellow) ghosts lie left of
late (blue) ones."""
import numpy as np

from flipstudy.render.figures import GHOST_GAP, _travel, auto_spread, ghost_image, key_times
from flipstudy.render.geometry import poses_at
from flipstudy.render.staging import stage
from flipstudy.render.style import Style
from flipstudy.stimuli import builtin
from flipstudy.stimuli.physics import center_of_mass


def test_successive_ghosts_of_an_in_place_flip_stand_a_gap_apart():
    st = stage([builtin("backflip")], size=(160, 120))
    c, b = st.clips[0], st.bodies[0]
    ts, _ = key_times(c, b, st.takeoffs[0], st.landings[0])
    along = center_of_mass(poses_at(c, ts), b) @ _travel(st)
    assert np.diff(along).min() < GHOST_GAP               # in place: they would pile up
    s = auto_spread(along)
    placed = along + s * np.arange(len(ts))
    assert np.diff(placed).min() >= GHOST_GAP - 1e-9
    assert auto_spread(along + 2 * GHOST_GAP * np.arange(len(ts))) == 0.0   # travelling: as it is


def test_rendered_ghosts_go_from_early_on_the_left_to_late_on_the_right():
    style = Style.from_dict({"ground": False, "legend": False, "scale_bar": False})
    img = ghost_image(stage([builtin("backflip")], size=(160, 120), style=style), None).astype(int)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    bg = np.abs(img - img[0, 0]).sum(-1) > 30
    early = bg & (r > b + 40) & (g > b + 40)              # yellow-green: the first ghosts
    late = bg & (b > r + 40)                             # blue: the last ghosts
    xs = np.arange(img.shape[1])[None, :].repeat(img.shape[0], 0)
    assert early.sum() > 50 and late.sum() > 50
    assert xs[early].mean() + 20 < xs[late].mean()


def test_a_white_legend_swatch_has_a_dark_ring_on_the_light_box():
    """The point-light ghost's "after" entry (white) was drawn white on white."""
    import pytest
    from flipstudy.render.compose import draw_legend, find_font
    if find_font() is None:
        pytest.skip("no font file: the VTK legend is used")
    img = np.zeros((80, 160, 3), np.uint8)
    assert draw_legend(img, [("after", (255, 255, 255))], 14, loc="upper left")
    box = img[:40, :40].astype(int)
    white = (box == 255).all(-1)
    dark = box.sum(-1) < 200
    ys, xs = np.nonzero(white & (np.abs(np.arange(40)[None, :] - 10) < 12))
    assert white.sum() > 10 and dark.sum() > 10          # the disc, and a ring around it
    cy, cx = ys.mean(), xs.mean()
    ring = [(int(round(cy)), x) for x in range(int(cx), 40) if not white[int(round(cy)), x]][0]
    assert dark[ring]                                    # leaving the disc, the first pixel is dark


def test_the_legend_room_is_free_of_ghosts():
    """`concat --ghost`'s first ghosts lay under the legend: the fitted camera keeps the
    legend's rows (``top``) empty and still fits every point with its margins."""
    from flipstudy.render.camera import fit_camera
    from flipstudy.render.geometry import body_points
    st = stage([builtin("backflip")], size=(320, 240))
    pts = body_points(st.clips[0], st.bodies[0]).reshape(-1, 3)
    for top in (0.0, 0.3):
        cam = fit_camera(pts, _travel(st), (320, 240), margin=0.06, top=top)
        px = cam.project(pts, (320, 240))
        assert px[:, 1].min() >= (0.06 + top) * 240 - 1.0          # nothing in the room
        assert px[:, 1].max() <= 0.94 * 240 + 1.0 and px[:, 0].min() >= 0.06 * 320 - 1.0
        assert px[:, 1].max() - px[:, 1].min() >= (0.88 - top) * 240 - 2.0 or \
            px[:, 0].max() - px[:, 0].min() >= 0.88 * 320 - 2.0      # and it still fills
