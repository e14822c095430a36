"""The built-in synthetic clips (stimuli.synth): physics measured the way the
analyser measures it (physics.momentum on Body.from_skeleton at the clip's
frame rate), feet, floor, rotation, BVH round trip, parameters."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from flipstudy.stimuli import analyse, load_bvh, save_bvh
from flipstudy.stimuli import builtin as top_builtin
from flipstudy.stimuli.body import Body
from flipstudy.stimuli.motion import Clip, finite_difference
from flipstudy.stimuli.motion.bvh import bvh_text
from flipstudy.stimuli.physics import center_of_mass, momentum
from flipstudy.errors import SynthError
from flipstudy.stimuli.synth import BUILTIN_NAMES, builtin, make_skeleton
from flipstudy.stimuli.synth.planar import D, PlanarModel, QuinticSpline, cumulative_simpson

G = 9.81
FLIPS = ("backflip", "frontflip")
_CACHE: dict = {}


def get(name, **kw):
    """Clip, its momentum (70 kg body, as the analyser builds it) and meta, cached."""
    key = (name, tuple(sorted(kw.items())))
    if key not in _CACHE:
        clip = builtin(name, **kw)
        body = Body.from_skeleton(clip.skeleton, clip.meta["total_mass"])
        _CACHE[key] = (clip, momentum(clip, body))
    return _CACHE[key]


def flight(clip):
    return slice(clip.meta["takeoff"], clip.meta["landing"] + 1)


def L_cv(clip, m):
    n = np.linalg.norm(m.L[flight(clip)], axis=1)
    return n.std() / n.mean()


def root_pitch(clip):
    """Unwrapped root rotation about X (rad) per frame, and the largest other component."""
    q = clip.rotations[:, 0]
    return np.unwrap(2 * np.arctan2(q[:, 0], q[:, 3])), np.abs(q[:, 1:3]).max()


# ----------------------------------------------------------------- skeleton
def test_skeleton_proportions_names_and_body_mapping():
    H = 1.75
    sk = make_skeleton(H)
    for n in ("Hips", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase", "RightToeBase", "Spine",
              "Spine1", "Neck", "Head", "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand",
              "RightHand"):
        assert n in sk
    assert sk.channels[0] == ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation",
                              "Xrotation")
    assert np.all(sk.parents[1:] < np.arange(1, sk.num_joints))
    bvh_text(Clip(sk, 30, np.zeros((1, 3)), np.tile([0, 0, 0, 1.0], (1, sk.num_joints, 1))))  # depth first
    P = sk.rest_positions()
    ends = np.array([P[p] + o for p, o in sk.end_sites])
    allp = np.concatenate([P, ends])
    assert allp[:, 1].max() - allp[:, 1].min() == pytest.approx(H)
    seg = lambda a, b: np.linalg.norm(P[sk.index(a)] - P[sk.index(b)]) / H  # noqa: E731
    assert seg("LeftUpLeg", "LeftLeg") == pytest.approx(0.245)
    assert seg("LeftLeg", "LeftFoot") == pytest.approx(0.246)
    assert seg("LeftArm", "LeftForeArm") == pytest.approx(0.186)
    assert seg("LeftForeArm", "LeftHand") == pytest.approx(0.146)
    assert seg("LeftArm", "RightArm") == pytest.approx(0.259)
    assert (P[sk.index("LeftArm"), 1] - P[sk.index("LeftUpLeg"), 1]) / H == pytest.approx(0.288)
    floor = allp[:, 1].min()
    assert (P[sk.index("LeftFoot"), 1] - floor) / H == pytest.approx(0.039)
    # left at +X, facing +Z (toes ahead of the ankle), Y up
    assert P[sk.index("LeftArm"), 0] > 0 > P[sk.index("RightArm"), 0]
    assert P[sk.index("LeftToeBase"), 2] > P[sk.index("LeftFoot"), 2]
    body = Body.from_skeleton(sk, total_mass=70.0)
    assert sum(body.segment_masses().values()) == pytest.approx(70.0)
    assert body.landmarks["hip_l"] == "LeftUpLeg" and body.landmarks["shoulder_r"] == "RightArm"
    assert body.landmarks["toe_tip_l"][0] == "LeftToeBase"
    assert make_skeleton(1.5).rest_height() == pytest.approx(1.5)
    with pytest.raises(ValueError):
        make_skeleton(-1)


def test_planar_model_matches_the_analysers_momentum():
    """The exact (analytic-rate) mass properties used to build the flight agree
    with stimuli.physics on the same body."""
    sk = make_skeleton()
    body = Body.from_skeleton(sk, 70.0)
    model = PlanarModel(sk, body)
    fps = 2000.0
    t = np.arange(0, 0.4, 1 / fps)
    rng = np.random.default_rng(3)
    a, w = rng.normal(size=D), rng.normal(size=D) * 3
    Q = a + np.sin(w * t[:, None])
    Qd = w * np.cos(w * t[:, None])
    clip = Clip(sk, fps, np.zeros((len(t), 3)), model.quaternions(Q))
    m = momentum(clip, body)
    com, _, Lx, Ixx = model.mass_properties(Q, Qd)
    assert np.allclose(com, m.com, atol=1e-12)
    assert np.allclose(com, center_of_mass(clip, body), atol=1e-12)
    assert np.allclose(Ixx, m.inertia[:, 0, 0], rtol=1e-12)
    assert np.abs(Lx - m.L[:, 0])[1:-1].max() < 1e-4 * np.abs(Lx).max()
    assert np.abs(m.L[:, 1:]).max() < 1e-10                # sagittal: L along X only


def test_spline_and_quadrature_helpers():
    s = QuinticSpline([0, 1, 3], [[0.0], [2.0], [1.0]], [[0.0], [1.0], [0.0]], [[1.0], [0.0], [0.0]])
    assert s([0, 1, 3]).ravel() == pytest.approx([0, 2, 1])
    assert s([0, 1, 3], 1).ravel() == pytest.approx([0, 1, 0])
    assert s([0, 1 - 1e-9, 1 + 1e-9], 2).ravel() == pytest.approx([1, 0, 0], abs=1e-6)
    x = np.linspace(0, 2, 201)
    assert cumulative_simpson(np.exp(x), 0.01)[-1] == pytest.approx(np.exp(2) - 1, rel=1e-9)


# ------------------------------------------------------------------ physics
@pytest.mark.parametrize("name", FLIPS)
def test_flip_angular_momentum_is_conserved_in_flight(name):
    clip, m = get(name)
    L = m.L[flight(clip)]
    assert L_cv(clip, m) < 0.01
    u = L / np.linalg.norm(L, axis=1, keepdims=True)
    assert np.all(u @ u.mean(0) > 0.9999)                  # constant direction
    L_meta = np.asarray(clip.meta["L_flight"])
    assert np.allclose(L.mean(0), L_meta, rtol=0.01, atol=0.01 * np.linalg.norm(L_meta))
    assert 25 < np.linalg.norm(L_meta) < 90                # a standing tucked somersault, 70 kg


def test_jump_angular_momentum_is_small_and_conserved():
    clip, m = get("jump")
    L = m.L[flight(clip)]
    L_meta = np.asarray(clip.meta["L_flight"])
    assert np.linalg.norm(L_meta) < 10
    assert np.abs(L - L_meta).max() < 0.3                  # kg·m²/s, vs ~45 in the flips
    assert L_cv(clip, m) < 0.02


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_com_is_a_ballistic_parabola_in_flight(name):
    clip, m = get(name)
    com = m.com[flight(clip)]
    t = np.arange(com.shape[0]) / clip.fps
    A = np.stack([t ** 2, t, np.ones_like(t)], 1)
    cy = np.linalg.lstsq(A, com[:, 1], rcond=None)[0]
    res = [com[:, 1] - A @ cy]
    for ax in (0, 2):
        res.append(com[:, ax] - A[:, 1:] @ np.linalg.lstsq(A[:, 1:], com[:, ax], rcond=None)[0])
    assert np.sqrt(sum(r ** 2 for r in res)).max() < 1e-3
    assert -2 * cy[0] == pytest.approx(G, rel=0.01)
    assert cy[1] == pytest.approx(clip.meta["v0"][1], rel=1e-3)      # take-off velocity


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_takeoff_is_continuous(name):
    clip, m = get(name)
    i0 = clip.meta["takeoff"]
    v0 = np.asarray(clip.meta["v0"])
    # finite-difference COM velocity of the last ground frames against the
    # flight parabola's velocity at the same instants
    v_fd = finite_difference(m.com, clip.fps)
    for k in (1, 2):
        v_par = v0 + np.array([0.0, G * k / clip.fps, 0.0])
        assert np.linalg.norm(v_fd[i0 - k] - v_par) < 0.02 * np.linalg.norm(v0)
    # the ground force fades out smoothly: vertical COM acceleration (second
    # difference) rises to -g over the last ground frames
    y = m.com[:, 1]
    grf = ((y[2:] - 2 * y[1:-1] + y[:-2]) * clip.fps ** 2 + G) / G     # grf[k]: frame k + 1
    last = grf[i0 - 7:i0]                                  # frames i0-6 .. i0
    assert np.all(np.diff(last) < 0) and last[0] > 0.3
    assert last[-1] < 0.05 and abs(grf[i0]) < 1e-6         # frame i0 + 1: ballistic
    # angular momentum: the first flight frame has the flight's value, and L
    # arrives there without a jump (the ground torque fades to zero too): the
    # last step is small against the steps while the push builds L up
    L_meta = np.asarray(clip.meta["L_flight"])
    assert np.linalg.norm(m.L[i0] - L_meta) < 0.01 * max(np.linalg.norm(L_meta), 10.0)
    steps = np.linalg.norm(np.diff(m.L[clip.meta["heel_off"] - 20:i0 + 1], axis=0), axis=1)
    assert steps[-1] < 0.25 * steps.max()
    assert np.linalg.norm(np.diff(m.L[i0:i0 + 3], axis=0), axis=1).max() < 0.05 * steps.max()


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_feet_planted_on_the_ground_and_nothing_below_the_floor(name):
    clip, _ = get(name)
    sk = clip.skeleton
    P = clip.joint_positions()
    E = clip.end_site_positions()
    i0, td, heel_off = clip.meta["takeoff"], clip.meta["touchdown"], clip.meta["heel_off"]
    assert 0 < heel_off < i0
    toes = [sk.index("LeftToeBase"), sk.index("RightToeBase")]
    tips = [e for e, (p, _) in enumerate(sk.end_sites) if p in toes]
    ankles = [sk.index("LeftFoot"), sk.index("RightFoot")]
    for frames in (slice(0, i0 + 1), slice(td, None)):
        for pts in (P[frames][:, toes], E[frames][:, tips]):
            assert np.abs(pts - pts[:1]).max() < 0.01
    for frames in (slice(0, heel_off), slice(td, None)):
        assert np.abs(P[frames][:, ankles] - P[frames][:1, ankles]).max() < 0.01
    # the heel does rise before take-off (about the ball of the foot)
    assert P[i0, ankles[0], 1] - P[0, ankles[0], 1] > 0.02
    allp = np.concatenate([P, E], 1)
    assert allp[..., 1].min() > -0.01
    assert allp[0, :, 1].min() == pytest.approx(0.0, abs=1e-9)      # standing on the floor
    assert allp[-1, :, 1].min() == pytest.approx(0.0, abs=1e-9)        # and again at the end
    # the feet leave the floor in flight
    assert E[(i0 + td) // 2, tips, 1].min() > 0.1


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_ground_force_is_plausible(name):
    clip, m = get(name)
    a = finite_difference(finite_difference(m.com, clip.fps), clip.fps)[:, 1]
    grf = (a + G) / G                                       # body weights
    td = clip.meta["touchdown"]
    ground = np.r_[2:clip.meta["takeoff"] - 1, td + 3:clip.num_frames - 2]
    assert grf[ground].min() > 0.0                          # the floor never pulls
    assert grf[ground].max() < 6.0


def test_rotation_sign_convention_and_upright_end():
    expect = {"backflip": -360.0, "frontflip": 360.0, "jump": 0.0}
    for name, deg in expect.items():
        clip, m = get(name)
        pitch, other = root_pitch(clip)
        assert other < 1e-12                                # pure rotation about X
        assert np.degrees(pitch[-1] - pitch[0]) == pytest.approx(deg, abs=3.0)
        # ends upright at the same facing, as it started
        R0 = Rotation.from_quat(clip.rotations[0])
        R1 = Rotation.from_quat(clip.rotations[-1])
        assert np.all((R0.inv() * R1).magnitude() < 1e-6)
        assert np.sign(clip.meta["L_flight"][0]) == np.sign(deg) or deg == 0
    # the backflip travels backward a little, the frontflip forward
    assert -1.0 < get("backflip")[0].meta["v0"][2] < 0 < get("frontflip")[0].meta["v0"][2] < 1.5
    b, f = get("backflip")[1], get("frontflip")[1]
    assert b.com[-1, 2] < b.com[0, 2] and f.com[-1, 2] > f.com[0, 2]


@pytest.mark.parametrize("name", FLIPS)
def test_tuck_speeds_up_the_rotation(name):
    clip, m = get(name)
    pitch, _ = root_pitch(clip)
    rate = np.abs(finite_difference(pitch, clip.fps))[flight(clip)]
    assert rate.max() > 2.0 * rate[0]
    assert rate.max() > 2.0 * rate[-1]
    inertia = m.inertia[flight(clip), 0, 0]
    assert inertia.min() < 0.5 * inertia[0]
    # a layout needs more angular momentum for the same somersault
    layout, _ = get(name, tuck=0.0)
    assert abs(layout.meta["L_flight"][0]) > 1.5 * abs(clip.meta["L_flight"][0])


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_phases_and_meta(name):
    clip, m = get(name)
    meta = clip.meta
    for k in ("name", "takeoff", "landing", "flight_s", "L_flight", "v0", "g", "total_mass", "source"):
        assert k in meta
    assert "build_s" not in meta            # provenance only: no transient timing
    assert sum(meta["segment_masses"].values()) == pytest.approx(meta["total_mass"])
    assert meta["name"] == name and meta["source"] == "builtin" and meta["g"] == G
    assert meta["total_mass"] == 70.0 and clip.fps == 120
    assert meta["touchdown"] == meta["landing"] + 1
    assert meta["flight_s"] == pytest.approx((meta["touchdown"] - meta["takeoff"]) / clip.fps)
    assert 2.5 <= clip.duration <= 3.5
    rise = meta["v0"][1] ** 2 / (2 * G)
    if name in FLIPS:
        assert 0.6 <= meta["flight_s"] <= 0.75 and 0.45 <= rise <= 0.7
    else:
        assert meta["flight_s"] == pytest.approx(0.5, abs=0.02)
        assert 0 < meta["v0"][2] < 0.3                      # a take-off angle is defined
    # in the last flight frame the feet are above the floor, at touch-down on it
    E = clip.end_site_positions()
    tips = [e for e, (p, _) in enumerate(clip.skeleton.end_sites)
            if clip.skeleton.joint_names[p].endswith("ToeBase")]
    assert E[meta["landing"], tips, 1].min() > 0.005
    assert E[meta["touchdown"], tips, 1].max() == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_bvh_round_trip(name, tmp_path):
    clip, _ = get(name)
    path = save_bvh(clip, tmp_path / f"{name}.bvh")
    back = load_bvh(path, scale=1.0)
    assert back.num_frames == clip.num_frames and back.fps == clip.fps
    assert back.skeleton.joint_names == clip.skeleton.joint_names
    assert np.abs(back.joint_positions() - clip.joint_positions()).max() < 1e-6
    assert np.abs(back.end_site_positions() - clip.end_site_positions()).max() < 1e-6


@pytest.mark.parametrize("name", FLIPS)
def test_frame_rate_parameter(name):
    c120, m120 = get(name)
    c60, m60 = get(name, fps=60)
    assert c60.fps == 60 and c60.num_frames == pytest.approx(c120.num_frames / 2, abs=2)
    assert c60.meta["flight_s"] == pytest.approx(c120.meta["flight_s"], abs=1 / 60)
    assert L_cv(c120, m120) < 0.01
    assert L_cv(c60, m60) < 0.02
    com = m60.com[flight(c60)]
    t = np.arange(com.shape[0]) / 60
    cy = np.polyfit(t, com[:, 1], 2)
    assert np.abs(np.polyval(cy, t) - com[:, 1]).max() < 1e-6 and -2 * cy[0] == pytest.approx(G)


def test_parameters_height_mass_flight_time():
    base, _ = get("backflip")
    heavy, mh = get("backflip", total_mass=90.0)
    # heavier: more angular momentum (the segment ellipsoids also get thicker at
    # the same densities, so a little more than in proportion)
    assert 90 / 70 <= heavy.meta["L_flight"][0] / base.meta["L_flight"][0] < (90 / 70) ** 1.5
    assert L_cv(heavy, mh) < 0.01
    tall, m = get("backflip", height=1.95)
    assert tall.skeleton.rest_height() == pytest.approx(1.95)
    assert L_cv(tall, m) < 0.01
    long, _ = get("frontflip", flight_time=0.74)
    assert long.meta["flight_s"] == pytest.approx(0.74, abs=1 / 240)
    assert long.meta["v0"][1] > get("frontflip")[0].meta["v0"][1]
    double, m2 = get("backflip", turns=2, flight_time=0.9)
    pitch, _ = root_pitch(double)
    assert np.degrees(pitch[-1]) == pytest.approx(-720.0, abs=3.0) and L_cv(double, m2) < 0.01
    still = builtin("jump", horizontal_speed=0.0)
    assert still.meta["v0"][2] == 0.0


def test_deterministic():
    a = builtin("backflip")
    b = builtin("backflip")
    assert np.array_equal(a.root_pos, b.root_pos) and np.array_equal(a.rotations, b.rotations)
    c = top_builtin("backflip", fps=120)                     # the package entry point
    assert np.array_equal(c.rotations, a.rotations)


def test_errors_name_the_problem():
    with pytest.raises(ValueError, match="backflip, frontflip, jump"):
        builtin("cartwheel")
    with pytest.raises(ValueError, match="flight_time"):
        builtin("backflip", flighttime=0.7)
    with pytest.raises(ValueError, match="tuck"):
        builtin("backflip", tuck=1.5)
    with pytest.raises(ValueError, match="turns"):
        builtin("jump", turns=1)
    with pytest.raises(ValueError, match="whole number"):
        builtin("frontflip", turns=1.5)
    with pytest.raises(ValueError, match="fps"):
        builtin("jump", fps=0)
    assert issubclass(SynthError, ValueError)


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_the_analyser_finds_the_flight(name):
    clip, _ = get(name)
    a = analyse(clip)
    assert a.flight is not None and not a.warnings
    assert clip.meta["takeoff"] <= a.takeoff < a.landing <= clip.meta["landing"]
    assert a.apparent_gravity == pytest.approx(G, rel=0.01)
    assert clip.fps == 120 and a.flight.rms < 1e-3          # the analyser's own parabola fit
    if name in FLIPS:
        assert a.L_cv_pct < 1.0


@pytest.mark.parametrize("name", FLIPS)
def test_body_shapes_tuck_pike_layout(name):
    """The three somersault shapes are exact too; a straighter body needs more |L|
    for the same turn (larger inertia)."""
    L = {}
    for shape in ("tuck", "pike", "layout"):
        clip = builtin(name, shape=shape)
        a = analyse(clip)
        assert a.L_cv_pct < 1.0 and abs(abs(clip.meta["rotation_deg"]) - 360) < 1e-6
        L[shape] = abs(clip.meta["L_flight"][0])
    assert L["tuck"] < L["pike"] < L["layout"]
    assert L["layout"] > 2 * L["tuck"]
    with pytest.raises(ValueError, match="shape"):
        builtin(name, shape="straddle")
