"""Issue 33: in the square side view the far arm and leg hid behind the near ones
mid-flight.  The stage now turns the clips :data:`THREE_QUARTER_DEG` about the
vertical (travel going away from the camera); the camera stays square to the
ground, so the horizon stays level.

Measured on rendered pixels (tests/_support/_far_limbs.py: the far arm and leg in
colours of their own, against the same limbs drawn alone), over the middle third
of the flight.  Square to the side the far limbs show 6–8 % of their picture
(far leg 4–9 %) in the built-in backflip and frontflip and in CMU 88_01; turned
20° 26–37 % (far leg 25–41 %).  The threshold, a fifth, is what a turn of about
15° or more gives (a hip 0.2 m wide moves the far leg sin 20° × 0.2 m ≈ 7 cm
sideways on a thigh about 15 cm thick) and three times the square view's."""
from __future__ import annotations

import numpy as np
import pytest

from _far_limbs import far_limb_visibility
from _shared import shared_file
from flipstudy import builtin
from flipstudy.render.staging import THREE_QUARTER_DEG, stage
from flipstudy.render.style import Style
from flipstudy.stimuli.physics import center_of_mass

SIZE = (160, 120)
VISIBLE = 0.20          # of the far arm and leg (and of the far leg alone), mid-flight
SQUARE = 0.12           # the square side view shows less than this


def middle_third(st, k=0) -> np.ndarray:
    t0, t1 = st.takeoffs[k], st.landings[k]
    n = t1 - t0
    return np.arange(t0 + n // 3, t1 - n // 3 + 1)


def check_far_limbs_show(clip):
    st = stage([clip], size=SIZE)
    r = far_limb_visibility(st, 0, middle_third(st))
    limbs, leg = np.nanmean(r["limbs"]), np.nanmean(r["leg"])
    sq = stage([clip], size=SIZE, turn=0)
    square = np.nanmean(far_limb_visibility(sq, 0, middle_third(sq))["limbs"])
    assert r["leg_px"].min() > 50 and r["arm_px"].min() > 10          # the limbs are drawn
    assert limbs >= VISIBLE and leg >= VISIBLE, (limbs, leg)
    assert square < SQUARE, square                                     # what it was
    return limbs, leg, square


@pytest.mark.parametrize("name", ["backflip", "frontflip"])
def test_the_far_limbs_show_mid_flight_in_the_built_in_flips(name):
    check_far_limbs_show(builtin(name))


def test_the_far_limbs_show_mid_flight_in_a_cmu_backflip():
    from flipstudy import load_bvh
    check_far_limbs_show(load_bvh(shared_file("88_01.bvh"), fps=60))


def test_the_turn_is_added_to_the_orientation_and_the_travel_goes_away():
    clips = [builtin("backflip"), builtin("frontflip")]
    st = stage(clips, size=SIZE)
    square = stage(clips, size=SIZE, turn=0)
    assert square.yaws == [0.0, 180.0]                 # turned to travel along one ground axis
    for y, y0 in zip(st.yaws, square.yaws):
        assert (y - y0 - THREE_QUARTER_DEG) % 360.0 == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_array_equal(st.direction, square.direction)      # same camera axis
    right, up, back = st.camera.basis()
    assert abs(back @ [0, 1, 0] - np.sin(np.radians(8.0))) < 1e-9      # elevation kept
    for c, b, t0, t1 in zip(st.clips, st.bodies, st.takeoffs, st.landings):
        com = center_of_mass(c, b)
        d = com[t1] - com[t0]
        d[1] = 0.0
        d /= np.linalg.norm(d)
        assert d @ right == pytest.approx(np.cos(np.radians(THREE_QUARTER_DEG)), abs=0.02)
        side = back - (back @ [0, 1, 0]) * np.array([0, 1, 0])
        side /= np.linalg.norm(side)
        # away from the camera, by sin(turn) of the travel
        assert d @ side == pytest.approx(-np.sin(np.radians(THREE_QUARTER_DEG)), abs=0.02)


def test_an_explicit_direction_and_orient_false_are_not_turned():
    clips = [builtin("backflip"), builtin("frontflip")]
    assert stage(clips, size=SIZE, orient=False).yaws == [0.0, 0.0]
    given = stage(clips, size=SIZE, direction=(0, 0, -1))
    assert given.yaws == [0.0, 180.0]


def test_a_turn_that_is_not_a_number_is_refused():
    from flipstudy.errors import FlipstudyValueError
    with pytest.raises(FlipstudyValueError, match="turn must be a finite number"):
        stage([builtin("backflip")], size=SIZE, turn=float("nan"))


def test_the_horizon_stays_level_in_the_three_quarter_view():
    from test_horizon_level import horizon_tilt_deg
    from flipstudy.render.scene import scene_for
    from flipstudy.render.video import iter_frames
    st = stage([builtin("backflip"), builtin("frontflip")], size=(320, 240),
               style=Style.from_dict({"legend": False}))
    assert st.yaws[0] == THREE_QUARTER_DEG
    for k in range(2):
        one = st.only(k)
        with scene_for(one) as sc:
            frames = [f.copy() for i, f in enumerate(iter_frames(one.clips[0], sc, fps=10,
                                                                  body=one.bodies[0])) if i in (0, 8)]
        for img in frames:
            assert abs(horizon_tilt_deg(img)) < 0.5
