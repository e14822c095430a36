"""Angular-momentum guided concatenation (Shum, Komura & Yadav 2009)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from flipstudy.stimuli import analyse, builtin
from flipstudy.stimuli.edit import concat as C
from flipstudy.stimuli.physics import momentum

from _shared import shared_file

vec = st.lists(st.floats(-50, 50, allow_nan=False), min_size=3, max_size=3).map(np.array)


# ------------------------------------------------------------------ eq. 2
@settings(max_examples=200, deadline=None)
@given(vec, vec, st.sampled_from(["forward", "reverse"]))
def test_eq2_closed_form_matches_a_dense_scan(L1, L2, rule):
    th = np.linspace(-np.pi, np.pi, 20001)
    dots = Rotation.from_rotvec(th[:, None] * [0.0, 1.0, 0.0]).apply(L2) @ L1
    best = dots.max() if rule == "forward" else dots.min()
    got = L1 @ C.yaw(C.align_angle(L1, L2, rule)).apply(L2)
    # the closed form is at least as good as the best of 20001 angles (to their spacing)
    tol = 1e-6 + np.hypot(L1[0], L1[2]) * np.hypot(L2[0], L2[2]) * (th[1] - th[0]) ** 2
    if rule == "forward":
        assert got >= best - tol
    else:
        assert got <= best + tol


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def test_eq2_turns_a_motion_back_onto_itself():
    L = np.array([3.0, 1.0, -2.0])
    for a in (-2.0, 0.3, 1.7):
        turned = C.yaw(a).apply(L)
        assert _wrap(C.align_angle(L, turned, "forward") + a) == pytest.approx(0.0, abs=1e-12)
        assert abs(_wrap(C.align_angle(L, turned, "reverse") + a)) == pytest.approx(np.pi, abs=1e-12)


# ------------------------------------------------------------ optimal timing
def _random_inputs(rng, F1, F2, P=5):
    L1 = rng.normal(size=(F1, 3)) * 10
    L2 = rng.normal(size=(F2, 3)) * 10
    r1 = rng.normal(size=(F1, P, 3)) * 0.3
    r2 = rng.normal(size=(F2, P, 3)) * 0.3
    m = rng.uniform(1, 10, P)
    a0 = int(rng.integers(0, F1 // 2))
    f1 = np.arange(a0, a0 + int(rng.integers(3, F1 - a0)))
    b0 = int(rng.integers(0, F2 // 2))
    f2 = np.arange(b0, b0 + int(rng.integers(3, F2 - b0)))
    return L1, L2, r1, r2, m, f1, f2


@pytest.mark.parametrize("seed", range(25))
def test_vectorised_timing_equals_the_brute_force_loop(seed):
    rng = np.random.default_rng(seed)
    L1, L2, r1, r2, m, f1, f2 = _random_inputs(rng, 40, 35)
    allowed = rng.random((f1.size, f2.size)) > 0.3 if seed % 2 else None
    a = C.optimal_timing(L1, L2, r1, r2, m, f1, f2, allowed=allowed)
    b = C.optimal_timing_bruteforce(L1, L2, r1, r2, m, f1, f2, allowed=allowed)
    assert (a.T, a.fT) == (b.T, b.fT)
    assert a.F == pytest.approx(b.F, rel=1e-12)
    assert a.F_dm == pytest.approx(b.F_dm, rel=1e-12)
    assert a.F_inertia == pytest.approx(b.F_inertia, rel=1e-9, abs=1e-12)
    assert set(a.costs) == set(b.costs)
    for T in b.costs:
        assert a.costs[T] == pytest.approx(b.costs[T], rel=1e-12)


def test_timing_finds_a_planted_offset():
    """Motion 2 is motion 1 delayed by 17 frames: F_dm is zero at T = 17, and
    F_time pulls f_T to the start of the blendable period."""
    rng = np.random.default_rng(3)
    L1 = np.cumsum(rng.normal(size=(80, 3)), axis=0)
    r1 = rng.normal(size=(80, 4, 3))
    L2 = np.concatenate([rng.normal(size=(17, 3)), L1])[:80]
    r2 = np.concatenate([rng.normal(size=(17, 4, 3)), r1])[:80]
    t = C.optimal_timing(L1, L2, r1, r2, np.ones(4), np.arange(30, 60), np.arange(20, 70))
    assert t.T == -17 and t.F_dm == 0.0 and t.F_inertia == 0.0 and t.fT == 30


# ----------------------------------------------------------------- phases
def test_phases_from_the_sign_of_L():
    L = np.zeros((100, 3))
    L[:20, 0] = -1.0           # preparatory: opposite to the main phase
    L[20:70, 0] = np.sin(np.linspace(0, np.pi, 50)) * 10 + 0.1
    L[70:, 0] = -2.0           # posterior
    p = C.phases(L, fps=100)
    assert p.main == (20, 69) and p.prep == (0, 19) and p.post == (70, 99)
    assert 40 <= p.tm <= 50
    # absent phases, and the user's borders
    q = C.phases(np.abs(L), fps=100)
    assert q.prep is None and q.post is None and q.main == (0, 99)
    r = C.phases(L, fps=100, main=(25, 60))
    assert r.main == (25, 60) and r.prep == (0, 24) and r.post == (61, 99)
    with pytest.raises(C.ConcatError, match="main phase"):
        C.phases(L, fps=100, main=(60, 25))


# ---------------------------------------------------------------- eq. 9
def test_eq9_gives_its_stated_mean():
    rng = np.random.default_rng(0)
    Ln = rng.uniform(5, 50, 40)
    s = C.smoothing_factor(Ln, 10, 30)
    assert np.mean(Ln[10:31]) * s == pytest.approx(0.5 * (Ln[10] + Ln[30]))
    s2 = C.smoothing_factor(Ln, 10, 30, ends=(7.0, 9.0))
    assert np.mean(Ln[10:31]) * s2 == pytest.approx(8.0)


@pytest.fixture(scope="module")
def backflip():
    c = builtin("backflip")
    return c, analyse(c).body


@pytest.mark.parametrize("mode", ["uniform", "profile"])
def test_smoothed_blend_has_the_eq9_mean(backflip, mode):
    """After smoothing, the mean |L| over the blended period is eq. 9's
    ½(|L(f_t0)| + |L(f_t1)|), measured on the result (not assumed)."""
    c, body = backflip
    r = C.concatenate(c, c, body=body, smoothing=mode, fix_feet=False)
    rep = r.report
    w0, w1 = rep.blend_out
    L = np.linalg.norm(momentum(r.clip, body).L, axis=1)
    before = rep.L_peak_blend_before
    assert before > 2 * rep.L_target_blend           # the raw blend is much too fast ...
    assert L[w0:w1 + 1].mean() == pytest.approx(rep.L_target_blend, rel=0.1)   # ... smoothed: eq. 9
    assert w1 - w0 > rep.blend[1] - rep.blend[0]   # by playing it slower


def test_copy_of_itself_keeps_the_direction_of_L(backflip):
    c, body = backflip
    r = C.concatenate(c, c, rule="forward", body=body)
    assert r.report.theta_deg == pytest.approx(0.0, abs=1e-9)
    L = momentum(r.clip, body).L
    n = np.linalg.norm(L, axis=1)
    u = C.motion_of(c, body).main_L
    u = u / np.linalg.norm(u)
    # from motion 1's main phase to the second landing (the final posterior phase,
    # the landing absorbing the rotation, turns the other way in the original too)
    span = np.zeros(n.size, bool)
    span[r.report.phases_a["main"][0]:r.report.flights[-1]["landing"] + 1] = True
    big = span & (n > 0.2 * n.max())
    ang = np.degrees(np.arccos(np.clip((L[big] @ u) / n[big], -1, 1)))
    assert ang.max() < 5.0
    # two flips: two flights, the second one after the first, both rotating one way
    fl = r.report.flights
    assert len(fl) == 2 and fl[1]["takeoff"] > fl[0]["landing"]


def test_double_backflip_from_the_builtin(backflip):
    c, body = backflip
    r = C.concatenate(c, c, body=body)
    g = C.motion_graph_join(c, c, body=body)
    rep = r.report
    assert rep.rule == "forward" == rep.suggested_rule
    # no higher than the main phases' peak (within 2 %: 53.55 against 52.79 with the
    # trunk's COM at de Leva's 56.9 % of mid-hip → mid-shoulder)
    assert rep.L_peak_blend <= 1.02 * max(rep.L_main_peak_a, rep.L_main_peak_b)
    assert rep.feet.foot_slide_cm < 2.0
    assert rep.feet.lowest_foot_above_floor_cm > -0.1
    assert r.clip.num_frames < g.clip.num_frames
    # the motion graph has to wait for the standing pose: it joins after motion 1 has ended
    assert g.report.transition_a > rep.phases_a["main"][1]


# ------------------------------------------------------------- IK, mirror
def test_two_bone_ik_reaches_and_keeps_the_foot(backflip):
    c, body = backflip
    from flipstudy.stimuli.edit.concat.motion import _lm_index
    hip, knee, ankle = (_lm_index(body, f"{k}_l") for k in ("hip", "knee", "ankle"))
    frames = np.arange(0, 150, 7)
    P = c.joint_positions()
    tgt = P[frames, ankle] + np.array([0.04, 0.03, -0.05])
    out = C.two_bone_ik(c, hip, knee, ankle, frames, tgt)
    assert np.abs(out.joint_positions()[frames, ankle] - tgt).max() < 1e-9
    assert np.abs(out.joint_rotations()[frames, ankle] - c.joint_rotations()[frames, ankle]).max() < 1e-9
    assert np.abs(out.joint_positions()[frames, hip] - P[frames, hip]).max() < 1e-12
    other = [j for j in range(c.skeleton.num_joints) if j not in (hip, knee, ankle)]
    assert np.allclose(out.rotations[:, other], c.rotations[:, other])


def test_mirror_swaps_sides_and_is_its_own_inverse(backflip):
    c, body = backflip
    m = C.mirror(c, plane="x")
    P, Q = c.joint_positions(), m.joint_positions()
    pair = C.mirror_pairs(c.skeleton)
    assert np.allclose(Q, P[:, pair] * np.array([-1, 1, 1]), atol=1e-9)
    back = C.mirror(m, plane="x")
    assert np.allclose(back.joint_positions(), P, atol=1e-9)
    # the sagittal mirror starts where the original does
    s = C.mirror(c)
    assert np.allclose(s.root_pos[0], c.root_pos[0])
    # L is an axial vector: mirrored across x = 0 it becomes (L_x, −L_y, −L_z) —
    # a mirrored backflip still turns the same way about the somersault axis
    La, Lb = momentum(c, body).L, momentum(m, body).L
    assert np.allclose(Lb, La * np.array([1.0, -1.0, -1.0]), atol=1e-6 * np.abs(La).max())


def test_point_cloud_distance_is_invariant_to_turns_and_shifts(backflip):
    c, _ = backflip
    R = C.yaw(0.7)
    rot = c.rotations.copy()
    rot[:, 0] = (R * Rotation.from_quat(c.rotations[:, 0])).as_quat()
    moved = c.replace(root_pos=R.apply(np.array(c.root_pos)) + [1.0, 0.0, -2.0], rotations=rot)
    s = np.arange(0, 300, 10)
    D, th, _, _ = C.point_cloud_distance(c.joint_positions(), moved.joint_positions(), s, s, 12)
    assert np.allclose(np.diag(D), 0.0, atol=1e-9)
    # the optimal turn brings the moved clip back: −0.7 rad about the vertical
    assert np.allclose(np.diag(th), -0.7, atol=1e-9)


# ------------------------------------------------------------ refusals
def test_different_skeletons_are_refused(backflip):
    from flipstudy.stimuli import Skeleton
    c, body = backflip
    sk = c.skeleton
    names = list(sk.joint_names)
    names[-1] = names[-1] + "_other"
    bad = Skeleton(names, sk.parents, sk.offsets, sk.channels, sk.end_sites)
    with pytest.raises(C.ConcatError, match="share a skeleton"):
        C.concatenate(c, c.replace(skeleton=bad), body=body)


def test_a_high_threshold_refuses(backflip):
    c, body = backflip
    with pytest.raises(C.ConcatError, match="too different"):
        C.concatenate(c, C.mirror(c), body=body, max_cost=1e-6)


# --------------------------------------------------- the paper's examples
CASES = [
    ("88_01.bvh", 60.0, {}, "forward"),
    ("87_03.bvh", 60.0, {}, "forward"),
    ("mass_cartwheel.bvh", None, {}, "forward"),
    ("02_05_iclone-retarget.bvh", None, {"range": (40, 136), "mirror": True}, "reverse"),
]


@pytest.mark.parametrize("name,fps,opts,rule", CASES, ids=[c[0] for c in CASES])
def test_real_concatenations_meet_the_measures(name, fps, opts, rule):
    from flipstudy.stimuli import load_bvh
    clip = load_bvh(shared_file(name), fps=fps)
    if "range" in opts:
        clip = clip.slice(*opts["range"])
    b = C.mirror(clip) if opts.get("mirror") else clip
    body = analyse(clip).body
    r = C.concatenate(clip, b, body=body)
    g = C.motion_graph_join(clip, b, body=body)
    rep = r.report
    assert rep.rule == rule                     # the suggestion from the data is the paper's rule
    assert rep.L_peak_blend <= max(rep.L_main_peak_a, rep.L_main_peak_b)
    assert r.clip.num_frames < g.clip.num_frames   # the momentum is reused: shorter than the motion graph
    assert rep.feet.foot_slide_cm < 2.0
    assert rep.feet.lowest_foot_above_floor_cm > -0.5
    assert rep.facing_deg_at_fT <= 45.0


def test_the_mass_kick_and_its_mirror_are_refused_with_the_reason():
    """The MASS kick turns the body ~120° about the vertical: a mirrored kick faces
    more than π/4 away at every blendable frame, and the paper's test refuses it."""
    from flipstudy.stimuli import load_bvh
    clip = load_bvh(shared_file("mass_kick.bvh"))
    with pytest.raises(C.ConcatError, match="torso facing directions differ"):
        C.concatenate(clip, C.mirror(clip), rule="reverse")


# ------------------------------------------------------------------- CLI
def test_cli_concat(tmp_path, capsys):
    from flipstudy.study.cli import main
    out = tmp_path / "double.bvh"
    assert main(["concat", "backflip", "backflip", "--baseline", "motion-graph", "--out", str(out),
                 "--plot", str(tmp_path / "L.png")]) == 0
    text = capsys.readouterr().out
    for key in ("rule", "θ =", "T =", "f_T", "blend", "smoothing", "slide", "motion graph"):
        assert key in text
    assert out.exists() and (tmp_path / "double_motion-graph.bvh").exists() and (tmp_path / "L.png").exists()
    from flipstudy.stimuli import load_bvh
    back = load_bvh(out)
    a = analyse(back, estimate=False)
    assert len(a.flights) == 2
    assert main(["concat", "backflip", "backflip", "--range-a", "9:3", "--out", str(out)]) == 1
    assert "F0 < F1" in capsys.readouterr().err


def test_facing_rule_refuses_the_half_twist_and_blends_turn_only_about_L(backflip):
    """The join's twist (a frontflip turned 180° so its L lies along a backflip's)
    cannot happen here: the π/4 facing rule refuses it, naming the 180°; and the
    blend concat makes (in double support) turns the body about the axes ⟂ L only
    by what L explains (measured with the join's cross-fade measure)."""
    from flipstudy.stimuli.edit.join import crossfade_rotation
    from flipstudy.stimuli.physics import momentum
    c, body = backflip
    with pytest.raises(C.ConcatError, match=r"facing directions differ by at least 180°"):
        C.concatenate(c, builtin("frontflip"), rule="forward", body=body)
    r = C.concatenate(c, c, body=body)
    w0, w1 = r.report.blend_out
    L = momentum(r.clip, body).L[w0:w1 + 1].mean(0)
    x = crossfade_rotation(r.clip, body, w0, w1 - w0, L, pad=0)
    assert x["unexplained_deg"] < 1.0 and x["turned_about_L_deg"] > 20
