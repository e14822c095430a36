"""Editing primitives and their effect on momentum (Section 5.1 of the paper)."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.spatial.transform import Rotation

from flipstudy.stimuli import analyse, load_bvh
from flipstudy.stimuli.body import Body
from flipstudy.stimuli.edit import ballistic_path, move_com, ratio_retime_frames, retime, rotate, sample, source_times
from flipstudy.stimuli.physics import center_of_mass, momentum

from _shared import shared_file


@pytest.fixture(scope="module")
def flip():
    clip = load_bvh(shared_file("88_01.bvh"), fps=60)
    return clip, Body.from_skeleton(clip.skeleton)


def test_sample_at_integer_frames_is_identity(flip):
    clip, _ = flip
    s = sample(clip, np.arange(clip.num_frames, dtype=float))
    assert np.allclose(s.joint_positions(), clip.joint_positions(), atol=1e-12)


def test_sample_midpoint_is_slerp(flip):
    clip, _ = flip
    s = sample(clip, np.array([10.5]))
    r0 = Rotation.from_quat(clip.rotations[10])
    r1 = Rotation.from_quat(clip.rotations[11])
    mid = Rotation.from_quat(s.rotations[0])
    # the midpoint is equally far from both ends, on the geodesic
    d0 = (r0.inv() * mid).magnitude()
    d1 = (mid.inv() * r1).magnitude()
    full = (r0.inv() * r1).magnitude()
    assert np.allclose(d0, d1, atol=1e-9) and np.allclose(d0 + d1, full, atol=1e-9)
    assert np.allclose(s.root_pos[0], (clip.root_pos[10] + clip.root_pos[11]) / 2)


@pytest.mark.parametrize("n", [0.5, 0.8, 1.25, 2.0])
def test_uniform_retime_scales_p_and_L_by_n(n):
    # a smooth synthetic motion: a rigid two-bone body spinning and flying, so the
    # finite differences are accurate and the scaling can be checked tightly
    from _tiny import tiny_body_clip
    clip, body = tiny_body_clip(fps=240, seconds=1.0)
    m = momentum(clip, body)
    fast = retime(clip, n)
    mf = momentum(fast, body)
    # frame k of the retimed clip is source frame k*n
    k = np.arange(5, fast.num_frames - 5)
    src = k * n
    keep = src < clip.num_frames - 6
    k, src = k[keep], src[keep]
    Lo = np.stack([np.interp(src, np.arange(clip.num_frames), m.L[:, a]) for a in range(3)], 1)
    po = np.stack([np.interp(src, np.arange(clip.num_frames), m.p[:, a]) for a in range(3)], 1)
    assert np.allclose(mf.L[k], n * Lo, rtol=2e-3, atol=1e-3 * np.abs(Lo).max())
    assert np.allclose(mf.p[k], n * po, rtol=2e-3, atol=1e-3 * np.abs(po).max())


@settings(max_examples=25, deadline=None)
@given(angle=st.floats(-3.0, 3.0), frame=st.integers(50, 75))
def test_rotation_about_L_through_com_keeps_L(angle, frame):
    clip = load_bvh(shared_file("88_01.bvh"), fps=60)
    body = Body.from_skeleton(clip.skeleton)
    m = momentum(clip, body)
    axis = m.L[frame] / np.linalg.norm(m.L[frame])
    R = Rotation.from_rotvec(axis * angle)
    r = rotate(clip, R, m.com)
    m2 = momentum(r, body)
    assert np.allclose(m2.L[frame], m.L[frame], atol=1e-6 * np.linalg.norm(m.L[frame]) + 1e-9)
    # and in general L is rotated with the body
    assert np.allclose(m2.L, R.apply(m.L), atol=1e-6 * np.abs(m.L).max())


def test_repositioning_keeps_L_and_puts_com_on_the_path(flip):
    clip, body = flip
    a = analyse(clip, body=body, estimate=False)
    fr = a.flight_frames
    t = (np.arange(clip.num_frames)[fr] - a.takeoff) / clip.fps
    target = ballistic_path(a.com[a.takeoff], [0.3, 3.5, -0.2], 9.81, t)
    moved = move_com(clip, body, fr, target)
    m2 = momentum(moved, body)
    assert np.allclose(center_of_mass(moved, body)[fr], target, atol=1e-9)
    inner = np.arange(clip.num_frames)[fr][1:-1]   # L is untouched where the shift is smooth
    assert np.allclose(m2.L[inner], a.L[inner], atol=1e-6 * np.abs(a.L).max())
    # after the flight the motion continues from where the new flight ends
    jump = moved.root_pos[a.landing + 1] - moved.root_pos[a.landing]
    orig = clip.root_pos[a.landing + 1] - clip.root_pos[a.landing]
    assert np.allclose(jump, orig, atol=1e-12)


def test_source_times_of_a_linear_rate():
    # r(τ) = 1 + τ  ⇒  s(τ) = τ + τ²/2
    s = source_times(lambda tau: 1 + tau, 2.0, fps=100)
    tau = np.arange(s.size) / 100
    assert np.allclose(s, tau + tau ** 2 / 2, atol=1e-6)
    assert s[-1] <= 2.0 and s[-1] + (1 + tau[-1]) / 100 > 2.0 - 1e-9


def test_ratio_rule_next_frame():
    # ratio 2 everywhere: steps of half a frame
    f = ratio_retime_frames(lambda x: 2.0, 10, 20)
    assert np.allclose(np.diff(f), 0.5) and f[0] == 10 and f[-1] == 20
    with pytest.raises(ValueError, match="positive"):
        ratio_retime_frames(lambda x: 0.0, 0, 5)


def test_edit_pipeline_straightens_then_flips_the_repaired_clip():
    from flipstudy.stimuli import analyse, builtin
    from flipstudy.stimuli.edit.animator import repair_momentum, straighten
    from flipstudy.errors import FlipEditError
    from flipstudy.stimuli.edit.multiflip import multiflip
    from flipstudy.stimuli.edit.pipeline import edit
    clip = builtin("backflip")
    r = edit(clip, straighten="arms", flips=2)
    a = analyse(clip)
    rep = repair_momentum(a, straighten(a, "arms"))
    by_hand = multiflip(analyse(rep.clip, body=a.body, estimate=False), 2)
    np.testing.assert_array_equal(r.clip.rotations, by_hand.clip.rotations)
    np.testing.assert_array_equal(r.clip.root_pos, by_hand.clip.root_pos)
    assert r.steps.repair is not None and r.steps.join is None
    assert r.report.measured.turn_deg == pytest.approx(720.0, abs=5.0)
    with pytest.raises(FlipEditError, match="nothing to do"):
        edit(clip)
    with pytest.raises(FlipEditError, match="no flight"):
        edit(clip.slice(0, 30), flips=2)


def test_sample_keeps_meta_as_provenance_only():
    from flipstudy.stimuli import builtin
    clip = builtin("backflip")
    s = sample(clip, np.arange(0, 20, 0.5))
    assert set(s.meta) == set(clip.meta)


def test_editing_methods_return_results_with_provenance_only_meta():
    """Every editing method returns a Result (clip, flight, typed report); the
    clip's meta is the source's provenance plus the edit's description (the
    built-in's exact facts moved under ``source_facts``), with nothing the method measured (flight frames, flips, asymmetry) in it."""
    from flipstudy.stimuli import analyse, builtin
    from flipstudy.stimuli.edit.animator import repair_momentum, straighten
    from flipstudy.stimuli.edit.concat import concatenate, mirror, motion_graph_join
    from flipstudy.stimuli.edit.join import join_in_flight
    from flipstudy.stimuli.edit.multiflip import multiflip
    from flipstudy.stimuli.edit.pipeline import edit
    from flipstudy.stimuli.edit.report import Report
    from flipstudy.stimuli.motion.clip import SOURCE_FACTS
    from flipstudy.stimuli.result import Result
    clip = builtin("backflip")
    a = analyse(clip)
    source = set(clip.meta)
    results = {"multiflip": multiflip(a, 2), "repair": repair_momentum(a, straighten(a, "legs")),
               "join": join_in_flight(a, a), "concat": concatenate(clip, clip, body=a.body),
               "motion graph": motion_graph_join(clip, clip, body=a.body), "edit": edit(a, flips=2)}
    for name, r in results.items():
        assert isinstance(r, Result) and isinstance(r.report, Report), name
        assert set(r.clip.meta) - source <= {"edit", "source_facts"}, (name, set(r.clip.meta) - source)
        # the built-in's exact facts are its own, not the edit's: kept apart, never as the clip's
        assert not set(r.clip.meta) & set(SOURCE_FACTS), (name, set(r.clip.meta) & set(SOURCE_FACTS))
        assert r.clip.meta["source_facts"]["takeoff"] == clip.meta["takeoff"], name
        if name not in ("concat", "motion graph"):
            # the clip's flight, where the analyser finds it
            b = analyse(r.clip, body=a.body, estimate=False)
            assert abs(b.takeoff - r.takeoff) <= 2 and abs(b.landing - r.landing) <= 2, name
    assert results["multiflip"].clip.meta["edit"] == "multiflip 2" and results["multiflip"].flips == 2
    # two flips: no single flight (the report lists both)
    c = results["concat"]
    assert (c.takeoff, c.landing) == (None, None) and len(c.report.flights) == 2
    assert (results["edit"].takeoff, results["edit"].landing) == (results["edit"].steps.multiflip.takeoff,
                                                                  results["edit"].steps.multiflip.landing)
    assert set(mirror(clip).meta) - source <= {"edit", "source_facts"}


def test_rest_asymmetry_names_the_joint_mirroring_cannot_match():
    from flipstudy.stimuli import Skeleton, builtin
    from flipstudy.stimuli.edit.concat import rest_asymmetry
    sk = builtin("backflip").skeleton
    assert rest_asymmetry(sk)[0] < 1e-9
    off = np.array(sk.offsets, float)
    off[sk.index("LeftHand"), 0] += 0.03               # a left forearm 3 cm longer (the hand a leaf)
    d, joint = rest_asymmetry(Skeleton(sk.joint_names, sk.parents, off, sk.channels, sk.end_sites))
    assert d == pytest.approx(0.03) and joint in ("LeftHand", "RightHand")
