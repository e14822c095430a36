"""The still ground rendered once (issue 34): a video frame is the characters
rendered alone and put on the plate by depth, its FXAA redone only around them.
The frames must be the very frames the whole scene renders to."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as hs

from flipstudy import builtin
from flipstudy.render.antialias import REACH, fxaa, fxaa_update
from flipstudy.render.scene import scene_for
from flipstudy.render.staging import stage, translate
from flipstudy.render.style import Style
from flipstudy.render.video import iter_frames

SIZE = (160, 120)


def _both_ways(clip, style=None, every=7, lower=0.0):
    """Every ``every``-th frame of the clip rendered whole and on the plate
    (the staged clip ``lower`` metres further down)."""
    st = stage([clip], size=SIZE, style=Style.from_dict(style or {}))
    if lower:
        st.clips[0] = translate(st.clips[0], (0.0, -lower, 0.0))
    whole, plated = [], []
    with scene_for(st) as sc:
        ch = sc.character("main", st.bodies[0])
        ch.look(sc.style.body_color, 1.0)
        plate = sc.plate()
        assert plate is not None
        R, P = st.clips[0].joint_rotations(), st.clips[0].joint_positions()
        for i in range(0, len(R), every):
            ch.pose(R[i], P[i])
            whole.append(sc.grab())
            plated.append(sc.grab(plate=plate))
    return np.array(whole), np.array(plated)


@pytest.mark.parametrize("style", [{}, {"character": "capsules"}, {"anti_aliasing": "none"}])
def test_plated_frames_are_the_whole_scenes_frames(style):
    whole, plated = _both_ways(builtin("frontflip"), style, every=13)
    assert np.array_equal(whole, plated)
    # and the character is really in them, moving: not two empty grounds compared
    assert len({f.tobytes() for f in plated}) > len(plated) // 2


def test_feet_below_the_ground_stay_hidden_as_in_the_whole_scene():
    # a take whose soles go 3 cm under the ground: the ground hides them in the whole
    # scene; on the plate the depth test must hide them too
    whole, plated = _both_ways(builtin("jump"), every=5, lower=0.03)
    assert np.array_equal(whole, plated)
    # the plate is not blind to depth: without the test the soles would show
    st = stage([builtin("jump")], size=SIZE)
    with scene_for(st) as sc:
        ch = sc.character("main", st.bodies[0])
        ch.look(sc.style.body_color, 1.0)
        R, P = st.clips[0].joint_rotations(), st.clips[0].joint_positions()
        ch.pose(R[0], P[0] - [0.0, 0.03, 0.0])
        plate = sc.plate()
        sc.show_ground(False)
        bare = sc.grab()
        sc.show_ground(True)
        assert not np.array_equal(bare, sc.grab(plate=plate))


def test_real_clip_plated_frames_equal():
    from _shared import shared_file

    from flipstudy.stimuli import load_clip
    clip = load_clip(shared_file("88_01.bvh"), fps=60)
    whole, plated = _both_ways(clip, every=11)
    assert np.array_equal(whole, plated)


def test_plate_refuses_scenes_it_cannot_hold():
    st = stage([builtin("backflip")], size=SIZE)
    with scene_for(st) as sc:
        ch = sc.character("main", st.bodies[0])
        ch.look(sc.style.body_color, 0.5)                 # a translucent body: rendered whole
        assert sc.plate() is None
        ch.look(sc.style.body_color, 1.0)
        assert sc.plate() is not None
        m = sc.markers("trail", 4, "red")                 # something else moving
        m.set(np.zeros((2, 3)))
        assert sc.plate() is None
        m.set(np.zeros((0, 3)))
        plate = sc.plate()
        sc.set_size((SIZE[0] * 2, SIZE[1] * 2))           # a plate of another size
        with pytest.raises(ValueError, match="another camera, ground or size"):
            sc.grab(plate=plate)


def test_a_video_uses_the_plate():
    st = stage([builtin("jump")], size=SIZE)
    with scene_for(st) as sc:
        made = []
        real = sc.plate

        def spy():
            made.append(real())
            return made[-1]
        sc.plate = spy
        frames = list(iter_frames(st.clips[0], sc, 10, body=st.bodies[0]))
    assert len(made) == 1 and made[0] is not None and len(frames) > 5


# ------------------------------------------------------------ FXAA's locality
def _scene(draw, H, W):
    """An image of flat regions with long, shallow edges (FXAA's longest searches)."""
    img = np.full((H, W, 3), draw(hs.integers(0, 255)), np.uint8)
    for _ in range(draw(hs.integers(1, 6))):
        col = draw(hs.lists(hs.integers(0, 255), min_size=3, max_size=3))
        y0, slope = draw(hs.integers(0, H - 1)), draw(hs.floats(-0.3, 0.3))
        x0, x1 = sorted(draw(hs.lists(hs.integers(0, W), min_size=2, max_size=2)))
        yy = np.arange(H)[:, None]
        xx = np.arange(W)[None, :]
        m = (yy >= y0 + slope * xx) & (xx >= x0) & (xx < x1)
        img[m] = col
    return img


@settings(max_examples=60, deadline=None)
@given(hs.data())
def test_fxaa_redone_around_a_change_equals_fxaa_of_the_whole(data):
    H, W = data.draw(hs.integers(8, 90)), data.draw(hs.integers(8, 90))
    a = _scene(data.draw, H, W)
    y0 = data.draw(hs.integers(0, H - 1))
    x0 = data.draw(hs.integers(0, W - 1))
    y1 = data.draw(hs.integers(y0 + 1, H))
    x1 = data.draw(hs.integers(x0 + 1, W))
    b = a.copy()
    b[y0:y1, x0:x1] = _scene(data.draw, H, W)[y0:y1, x0:x1]
    got = fxaa_update(fxaa(a), b, (slice(y0, y1), slice(x0, x1)))
    assert np.array_equal(got, fxaa(b))


def test_a_change_is_felt_far_along_an_edge_and_within_reach():
    # one pixel flipped at a step of a shallow staircase edge (16-pixel steps): FXAA's
    # endpoint search carries the change about 11 pixels along the edge, far beyond the
    # 3x3 neighbourhood, and no further than REACH (what fxaa_update redoes around a box)
    H, W = 40, 120
    yy, xx = np.mgrid[0:H, 0:W]
    a = np.zeros((H, W, 3), np.uint8)
    a[yy >= 20 + xx / 16.0] = 255
    b = a.copy()
    b[21, 20] = 255 - b[21, 20]
    ys, xs = np.nonzero(np.any(fxaa(a) != fxaa(b), axis=-1))
    far = max(np.abs(xs - 20).max(), np.abs(ys - 21).max())
    assert 8 <= far <= REACH, far
