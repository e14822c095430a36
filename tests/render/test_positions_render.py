"""A position-only motion renders in every character style, and draws the same
body as the BVH it was made from.

CMU 88_01 as a HumanML3D array (22 joints, 20 fps) and the BVH resampled to
20 fps are staged together (one camera, the same take-off spot) and drawn one at
a time at 160x120, on black without ground.  Measured at three instants (standing,
in the air, landed), the foreground masks overlap with IoU 0.75–0.83 for the solid
styles (ellipsoids, capsules, mannequin; asserted 0.65) and 0.49–0.60 for the thin
ones (stick, point-light: the 22 joints have no fingers or toes tips, and a line
one pixel off halves the overlap; asserted 0.35); the masks' centroids lie within
a few pixels (asserted 4 px for every style).
"""
from __future__ import annotations

import numpy as np
import pytest

from _positions import cmu_humanml3d
from _shared import shared_file
from flipstudy import load_bvh
from flipstudy.render.characters import CHARACTER_STYLES
from flipstudy.render.compose import read_image
from flipstudy.render.figures import ghost_image
from flipstudy.render.scene import scene_for
from flipstudy.render.staging import stage
from flipstudy.render.style import Style
from flipstudy.render.video import iter_frames, render_video
from flipstudy.stimuli import load_clip
from flipstudy.stimuli.stimset import resample

SOLID = ("ellipsoids", "capsules", "mannequin")


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    bvh = load_bvh(shared_file("88_01.bvh"), fps=60)
    path = tmp_path_factory.mktemp("pos") / "88_01.npy"
    np.save(path, cmu_humanml3d(bvh))
    return resample(bvh, 20.0), load_clip(str(path))


def compare(clips, character, tmp_path, video: bool):
    style = Style(ground=False, background="#000000", anti_aliasing="none").with_character(character)
    st = stage(list(clips), size=(160, 120), style=style)
    with scene_for(st) as sc:
        frames = [np.array([f.copy() for f in iter_frames(c, sc, fps=20.0, body=b)])
                  for c, b in zip(st.clips, st.bodies)]
    for k in (5, 20, 40):                                      # standing, in the air, landed
        m = [f[k].sum(axis=-1) > 30 for f in frames]
        assert m[1].sum() > 20, f"{character}: nothing drawn at frame {k}"
        iou = (m[0] & m[1]).sum() / (m[0] | m[1]).sum()
        assert iou > (0.65 if character in SOLID else 0.35), f"{character} frame {k}: IoU {iou:.2f}"
        c0, c1 = (np.array(np.nonzero(x)).mean(axis=1) for x in m)
        assert np.linalg.norm(c0 - c1) < 4.0, f"{character} frame {k}: centroids {c0} vs {c1}"
    pos_only = stage([clips[1]], size=(160, 120), style=style)
    img = ghost_image(pos_only, tmp_path / f"{character}.png")
    assert read_image(tmp_path / f"{character}.png").shape[:2] == (120, 160) and img.std() > 5
    if video:
        render_video(pos_only, tmp_path / f"{character}.mp4", fps=20.0)
        assert (tmp_path / f"{character}.mp4").stat().st_size > 1000


def test_a_position_only_clip_draws_the_bvh_body(clips, tmp_path):
    compare(clips, "ellipsoids", tmp_path, video=False)


@pytest.mark.slow
@pytest.mark.parametrize("character", CHARACTER_STYLES)
def test_a_position_only_clip_renders_in_every_style(clips, character, tmp_path):
    compare(clips, character, tmp_path, video=True)
