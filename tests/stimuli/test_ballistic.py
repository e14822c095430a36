"""The ballistic error kinds on the built-ins, checked from the joint geometry:
the airborne frames are those whose lowest joint or end site is off the floor,
the COM is computed with the built-in's true segment masses, and what the
stimulus should be comes from the built-in's exact facts (g, v0, flight time)
in closed form, not from the injector's numbers."""
import dataclasses
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from flipstudy.stimuli import analyse, builtin
from flipstudy.stimuli.ballistic import inject_kind, held_times
from flipstudy.stimuli.ballistic_measure import measure_ballistic
from flipstudy.stimuli.body import Body
from flipstudy.errors import DesignError, StimulusError
from flipstudy.stimuli.design import parse_design
from flipstudy.stimuli.injection import check
from flipstudy.stimuli.physics import center_of_mass, momentum

from test_contact import geometric_airborne, lowest_point

CLIPS = ("backflip", "frontflip", "jump")
#: (kind, option, error): both signs of every kind and policy
CASES = [("gravity", "takeoff-velocity", 0.3), ("gravity", "takeoff-velocity", -0.3),
         ("gravity", "apex-height", 0.25), ("gravity", "apex-height", -0.25),
         ("gravity", "flight-time", 0.3), ("gravity", "flight-time", -0.3),
         ("horizontal-velocity", None, 0.4), ("horizontal-velocity", None, -0.4),
         ("vertical-velocity", None, 0.1), ("vertical-velocity", None, -0.15),
         ("acceleration", "horizontal", 0.2), ("acceleration", "horizontal", -0.2),
         ("acceleration", "vertical", 0.2), ("acceleration", "vertical", -0.2),
         ("time-scale", "flight", 0.5), ("time-scale", "flight", -0.3),
         ("time-scale", "whole", 1.0), ("time-scale", "whole", -0.5)]


class Truth:
    """A built-in's exact flight: g, take-off velocity, instants, COM heights."""

    def __init__(self, name):
        self.clip = clip = builtin(name)
        m = clip.meta
        self.body = Body.from_skeleton(clip.skeleton, 70.0, segment_masses=m["segment_masses"])
        self.fps, self.g, self.v0, self.T = clip.fps, m["g"], np.array(m["v0"]), m["flight_s"]
        self.t_to = m["takeoff"] / clip.fps
        com = center_of_mass(clip, self.body)
        self.c0, self.c1 = com[m["takeoff"]], com[m["touchdown"]]
        self.dy = self.c1[1] - self.c0[1]
        self.floor = lowest_point(clip).min()
        self.L = np.linalg.norm(momentum(clip, self.body, [m["takeoff"] + 1, m["touchdown"]]).L
                                [m["takeoff"] + 1:m["touchdown"]], axis=1).mean()
        self.a = analyse(clip)


@pytest.fixture(scope="module", params=CLIPS)
def truth(request):
    return Truth(request.param)


def flight_of(clip, body, fps, t_to):
    """From the geometry: the airborne frames, their COM, the free quadratic fit
    (t from the take-off instant ``t_to``): acceleration, take-off velocity and
    the largest departure of any in-air second difference from that acceleration."""
    s, e = geometric_airborne(clip)
    com = center_of_mass(clip, body)[s:e + 1]
    t = np.arange(s, e + 1) / fps - t_to
    coef = np.array([np.polyfit(t, com[:, k], 2) for k in range(3)])
    acc2 = (com[2:] - 2 * com[1:-1] + com[:-2]) * fps ** 2
    return s, e, 2 * coef[:, 0], coef[:, 1], acc2


def expected(tr: Truth, kind, opt, e):
    """Closed forms from the built-in's exact facts: (acceleration, take-off
    velocity, flight time)."""
    g, v0, T, dy = tr.g, tr.v0.copy(), tr.T, tr.dy
    land = lambda vy, gg: (vy + np.sqrt(vy * vy - 2 * gg * dy)) / gg   # noqa: E731
    acc = np.array([0.0, -g, 0.0])
    if kind == "gravity":
        gn = (1 + e) * g
        acc = np.array([0.0, -gn, 0.0])
        if opt == "takeoff-velocity":
            return acc, v0, land(v0[1], gn)
        if opt == "apex-height":
            return acc, v0 * np.sqrt(1 + e), T / np.sqrt(1 + e)
        v0[1] = (dy + 0.5 * gn * T * T) / T
        return acc, v0, T
    if kind == "horizontal-velocity":
        return acc, v0 * [1 + e, 1, 1 + e], T
    if kind == "vertical-velocity":
        v0[1] *= 1 + e
        return acc, v0, land(v0[1], g)
    if kind == "acceleration":
        if opt == "horizontal":
            u = v0 * [1, 0, 1] / np.hypot(v0[0], v0[2])
            return acc + e * 9.81 * u, v0, T
        acc[1] += e * 9.81
        return acc, v0, land(v0[1], -acc[1])
    k = 1 + e
    return acc * k * k, v0 * k, T / k


@pytest.mark.parametrize("kind,opt,e", CASES)
def test_kind_is_exact_from_the_geometry(truth, kind, opt, e):
    tr = truth
    inj = inject_kind(tr.a, kind, e, opt)
    k = 1 + e if (kind, opt) == ("time-scale", "whole") else 1.0
    t_to = tr.t_to / k
    s, en, acc, v, acc2 = flight_of(inj.clip, tr.body, tr.fps, t_to)
    acc_x, v_x, T_x = expected(tr, kind, opt, e)
    # the airborne frames are the injection's (the feet leave and meet the floor there;
    # a lower vertical take-off velocity keeps the toes near the floor a few frames
    # longer, which the manifest reports as below_floor_mm)
    m = measure_ballistic(tr.a, inj)
    assert inj.takeoff <= s and en <= inj.landing
    assert s - inj.takeoff <= (5 if m["below_floor_mm"] > 3 else 2) / k and inj.landing - en <= 2 / k
    assert m["below_floor_mm"] < 12.0
    assert (en + 1) / tr.fps - t_to == pytest.approx(T_x, abs=1.5 / tr.fps)
    # in the air: the acceleration is g' (or g + the added one) on every frame, no jolt
    assert np.abs(acc2 - acc_x).max() < 0.02
    assert acc == pytest.approx(acc_x, abs=1e-3)
    assert v == pytest.approx(v_x, abs=1e-3)
    # the landing meets the ground: the lowest point comes back to the floor, not through it
    low = lowest_point(inj.clip)
    assert low[en + 1:].min() == pytest.approx(tr.floor, abs=2e-3)
    assert low[-1] == pytest.approx(lowest_point(tr.clip)[-1], abs=1e-6)
    # the analyser's measurement: the nominal within 0.5 points, and check() accepts it
    assert m["measured_error_pct"] == pytest.approx(100 * e, abs=0.5)
    check(m, inj, 0.5, kind)
    assert abs(m["landing_height_change_mm"]) < 0.5


def _kept(tr, kind, opt, e):
    """What each kind and policy keeps, measured from the geometry against the
    original's own geometry: apex height, flight frames, landing point, |L|,
    take-off angle."""
    inj = inject_kind(tr.a, kind, e, opt)
    k = 1 + e if (kind, opt) == ("time-scale", "whole") else 1.0
    s, en, acc, v, _ = flight_of(inj.clip, tr.body, tr.fps, tr.t_to / k)
    s0, en0, acc0, v0, _ = flight_of(tr.clip, tr.body, tr.fps, tr.t_to)
    com, com0 = center_of_mass(inj.clip, tr.body), center_of_mass(tr.clip, tr.body)
    apex, apex0 = com[s:en + 1, 1].max(), com0[s0:en0 + 1, 1].max()
    land = com[-1] - com[0]                       # the last frame: where the motion ends
    land0 = com0[-1] - com0[0]
    L = np.linalg.norm(momentum(inj.clip, tr.body, [inj.takeoff, inj.landing + 1]).L
                       [inj.takeoff:inj.landing + 1], axis=1).mean()
    angle = lambda w: np.degrees(np.arctan2(w[1], np.hypot(w[0], w[2])))   # noqa: E731
    return {"apex": apex - apex0, "frames": (en - s) - (en0 - s0), "landing": np.hypot(*(land - land0)[[0, 2]]),
            "L": L / tr.L - 1, "angle": angle(v) - angle(v0), "v": v - v0}


@pytest.mark.parametrize("kind,opt,e,keeps", [
    ("gravity", "takeoff-velocity", 0.3, ("angle", "v")),
    ("gravity", "apex-height", -0.25, ("apex", "landing", "angle")),
    ("gravity", "flight-time", 0.3, ("frames", "landing", "L")),
    ("horizontal-velocity", None, 0.4, ("apex", "frames", "L")),
    ("vertical-velocity", None, -0.15, ()),
    ("acceleration", "horizontal", -0.2, ("apex", "frames", "L", "angle", "v")),
    ("acceleration", "vertical", 0.2, ("angle", "v")),
    ("time-scale", "flight", 0.5, ("apex", "landing", "angle")),
    ("time-scale", "whole", -0.5, ("apex", "landing", "angle")),
])
def test_what_each_kind_keeps(truth, kind, opt, e, keeps):
    got = _kept(truth, kind, opt, e)
    tol = {"apex": 1e-3, "frames": 1, "landing": 1e-3, "L": 0.01, "angle": 0.05, "v": 1e-3}
    for q in keeps:
        assert np.all(np.abs(got[q]) <= tol[q]), (q, got[q])
    # and what it changes, it changes (the stated consequences)
    if kind == "gravity" and opt == "flight-time":
        assert got["apex"] > 0.05                 # stronger gravity in the same time: higher
    if kind in ("horizontal-velocity", "acceleration") and opt != "vertical":
        assert got["landing"] > 0.01
    if kind == "time-scale":
        assert got["L"] == pytest.approx(e, abs=0.01)


@pytest.mark.parametrize("rate", [10, 15, 30, 40])
def test_pose_rate_holds_the_originals_poses(truth, rate):
    tr = truth
    inj = inject_kind(tr.a, "pose-rate", rate / tr.fps - 1, rate=rate)
    P, P0 = inj.clip.joint_positions(), tr.clip.joint_positions()
    # N divides 120: frame k shows the original's frame ⌊k N / fps⌋ fps / N (in the
    # air moved onto the analyser's parabola, a micrometre from the true COM)
    src = (np.arange(inj.clip.num_frames) * rate // int(tr.fps)) * int(tr.fps) // rate
    assert np.abs(P - P0[src]).max() < 1e-5
    assert np.array_equal(inj.clip.rotations, tr.clip.rotations[src])
    m = measure_ballistic(tr.a, inj)
    assert m["measured_value"] == pytest.approx(rate, rel=1e-4)
    assert m["measured_error_pct"] == pytest.approx(100 * (rate / tr.fps - 1), abs=0.5)
    check(m, inj, 0.5, "pose-rate")
    # the distinct poses in the air, at their own instants, fall freely at g
    com = center_of_mass(tr.clip, tr.body)[src]
    air = np.unique(src[(src > tr.clip.meta["takeoff"]) & (src < tr.clip.meta["touchdown"])])
    c = center_of_mass(tr.clip, tr.body)[air]
    a2 = (c[2:] - 2 * c[1:-1] + c[:-2]) * rate ** 2
    assert np.abs(a2[:, 1] + tr.g).max() < 1e-6 and com.shape[0] == inj.clip.num_frames


@settings(max_examples=12, deadline=None)
@given(e=st.floats(-0.6, 1.5), policy=st.sampled_from(["takeoff-velocity", "apex-height", "flight-time"]))
def test_gravity_recovered_at_any_level(jump_truth, e, policy):
    inj = inject_kind(jump_truth.a, "gravity", e, policy)
    _, _, acc, _, acc2 = flight_of(inj.clip, jump_truth.body, jump_truth.fps, jump_truth.t_to)
    assert -acc[1] == pytest.approx((1 + e) * 9.81, abs=1e-3)
    assert np.abs(acc2[:, 1] - acc[1]).max() < 0.02
    assert measure_ballistic(jump_truth.a, inj)["measured_error_pct"] == pytest.approx(100 * e, abs=0.5)


@pytest.fixture(scope="module")
def jump_truth():
    return Truth("jump")


@settings(max_examples=15, deadline=None)
@given(case=st.sampled_from([(k, o) for k, o, _ in CASES[::2]]), e=st.floats(-0.45, 0.45),
       name=st.sampled_from(CLIPS))
def test_any_kind_at_any_level_is_measured_within_half_a_point(truths, case, e, name):
    kind, opt = case
    tr = truths[name]
    inj = inject_kind(tr.a, kind, e, opt)
    k = 1 + e if (kind, opt) == ("time-scale", "whole") else 1.0
    _, _, acc, v, acc2 = flight_of(inj.clip, tr.body, tr.fps, tr.t_to / k)
    acc_x, v_x, _ = expected(tr, kind, opt, e)
    assert np.abs(acc2 - acc_x).max() < 0.02 and v == pytest.approx(v_x, abs=1e-3)
    m = measure_ballistic(tr.a, inj)
    assert m["measured_error_pct"] == pytest.approx(100 * e, abs=0.5)


@pytest.fixture(scope="module")
def truths():
    return {n: Truth(n) for n in CLIPS}


def test_impossible_flights_are_refused(jump_truth):
    a = jump_truth.a
    with pytest.raises(StimulusError, match="poses per second"):
        inject_kind(a, "pose-rate", 0.0, rate=200)
    with pytest.raises(StimulusError, match="out of range"):
        inject_kind(a, "acceleration", -1.2, "vertical")


def test_held_times():
    assert held_times(7, 120.0, 30.0).tolist() == [0, 0, 0, 0, 1 / 30, 1 / 30, 1 / 30]


BASE = """[study]
name = "k"
seed = 1
[[clips]]
name = "jump"
source = "jump"
[[groups]]
name = "g"
"""


@pytest.mark.parametrize("group,match", [
    ('kind = "gravity"\nlevels = [0, 10]', "missing field 'policy'"),
    ('kind = "gravity"\npolicy = "apex"\nlevels = [0, 10]', "policy: must be one of"),
    ('kind = "acceleration"\naxis = "sideways"\nlevels = [10]', "axis: must be one of"),
    ('kind = "time-scale"\npolicy = "flight-time"\nlevels = [10]', "only gravity groups have a policy"),
    ('kind = "horizontal-velocity"\nspan = "whole"\nlevels = [10]', "only time-scale groups have a span"),
    ('kind = "pose-rate"\nsign = -1\nlevels = [10]', "its sign is 1"),
    ('kind = "gravity"\npolicy = "flight-time"\nsign = -1\nlevels = [100]', "below 100"),
    ('kind = "acceleration"\naxis = "vertical"\nlevels = [100]', "below 100"),
])
def test_kind_keys_are_checked(group, match):
    with pytest.raises(DesignError, match=match):
        parse_design(BASE + group, "k.toml")


def test_kind_keys_parse():
    d = parse_design(BASE + 'kind = "time-scale"\nlevels = [0, 10]', "k.toml")
    assert (d.groups[0].span, d.groups[0].policy) == ("flight", None)
    d = parse_design(BASE + 'kind = "gravity"\npolicy = "apex-height"\nsign = -1\nlevels = [0, 50]')
    assert (d.groups[0].policy, d.groups[0].sign) == ("apex-height", -1)


def test_a_study_of_the_new_kinds_builds_and_records_them(tmp_path):
    from flipstudy.stimuli.ballistic_measure import EXTRA_COLUMNS
    from flipstudy.stimuli.design import PAPER_DESIGN
    from flipstudy.stimuli.contract import StimulusSet
    from flipstudy.stimuli.stimset import MANIFEST_COLUMNS, build_stimuli
    text = BASE + ('kind = "gravity"\npolicy = "flight-time"\nsign = -1\nlevels = [0, 20]\n'
                   '[[groups]]\nname = "poses"\nkind = "pose-rate"\nlevels = [0, 15]\n'
                   '[[groups]]\nname = "am"\nkind = "angular-momentum"\nprofile = "abrupt"\nlevels = [0, 25]\n')
    build_stimuli(parse_design(text), tmp_path / "s", progress=False)
    rows = StimulusSet.read(tmp_path / "s", files=False, design=False).rows()
    header = (tmp_path / "s" / "manifest.csv").read_text().splitlines()[0].split(",")
    assert header == MANIFEST_COLUMNS + EXTRA_COLUMNS
    by = {r["stimulus"]: r for r in rows}
    g = by["jump_g_20"]
    assert (g["policy"], g["unit"]) == ("flight-time", "m/s²")
    assert float(g["nominal_value"]) == pytest.approx(0.8 * 9.81, abs=1e-3)
    assert float(g["measured_value"]) == pytest.approx(float(g["nominal_value"]), abs=1e-3)
    assert abs(float(g["flight_s_change_pct"])) < 1e-6 and float(g["apex_change_pct"]) < -15
    p = by["jump_poses_15"]
    assert float(p["measured_value"]) == pytest.approx(15.0, rel=1e-4)
    assert float(p["nominal_error_pct"]) == pytest.approx(-87.5)
    assert by["jump_poses_0"]["pose_rate"] == 120.0
    for r in rows:
        assert abs(float(r["measured_error_pct"]) - float(r["nominal_error_pct"])) <= 0.5
        assert np.isfinite([r["air_acc_dev"], r["measured_value"]]).all()
    # a study without them keeps the manifest it always had
    paper = PAPER_DESIGN.replace('name = "frontflip"\nsource = "frontflip"', 'name = "jump"\nsource = "jump"')
    paper = paper.replace('clips = ["backflip", "jump"]', 'clips = []').replace("levels = [0, 17, 25, 37, 50]", "levels = [0, 50]")
    d = parse_design(paper.replace('clips = ["backflip", "frontflip"]', 'clips = []'))
    d = dataclasses.replace(d, clips=d.clips[:1])      # a Design is frozen
    build_stimuli(d, tmp_path / "p", progress=False)
    assert (tmp_path / "p" / "manifest.csv").read_text().splitlines()[0].split(",") == MANIFEST_COLUMNS


def test_a_level_the_clip_cannot_take_is_refused_naming_the_stimulus(tmp_path):
    from flipstudy.stimuli.stimset import build_stimuli
    d = parse_design(BASE + 'kind = "pose-rate"\nlevels = [0, 150]')      # the study runs at 120 fps
    # refused before the build, naming group and level (a DesignError since issue 28)
    with pytest.raises(DesignError, match=r"groups\[0\] \(g\).levels: 150 poses per second on clip "
                                          r"'jump': a pose rate must be below the clip's 120"):
        build_stimuli(d, tmp_path / "s", progress=False)
    assert not (tmp_path / "s").exists()
    with pytest.raises(DesignError, match="at most 1000 poses per second"):
        parse_design(BASE + 'kind = "pose-rate"\nlevels = [2000]')


@pytest.mark.shared("mocap/88_01.bvh")
@pytest.mark.parametrize("kind,opt,e", [("gravity", "takeoff-velocity", -0.3), ("gravity", "flight-time", 0.3),
                                        ("horizontal-velocity", None, 0.3), ("vertical-velocity", None, -0.1),
                                        ("acceleration", "horizontal", -0.2), ("time-scale", "whole", 0.5)])
def test_kinds_on_a_captured_flip(real88, kind, opt, e):
    """CMU 88_01 at its true 60 fps: the flight carries its capture noise (the
    original's own in-air departure is ~145 m/s²); the stimulus' COM is the exact
    path, within the real-data tolerance of its nominal."""
    inj = inject_kind(real88, kind, e, opt)
    m = measure_ballistic(real88, inj)
    assert m["measured_error_pct"] == pytest.approx(100 * e, abs=2.0)
    assert m["air_acc_dev"] < 0.05 < m["air_acc_dev_original"]
    assert abs(m["landing_height_change_mm"]) < 0.5
    check(m, inj, 2.0, kind)


@pytest.fixture(scope="module")
def real88():
    from _shared import shared_file
    from flipstudy.stimuli import load_bvh
    return analyse(load_bvh(shared_file("88_01.bvh"), fps=60))


@pytest.mark.parametrize("e", [1.0, -0.5])
def test_time_scale_whole_plays_the_ground_phases_at_the_same_speed(jump_truth, e):
    tr = jump_truth
    inj = inject_kind(tr.a, "time-scale", e, "whole")
    k = 1 + e
    P, P0 = inj.clip.joint_positions(), tr.clip.joint_positions()
    # frame i shows the original at frame k·i: whole frames where k·i is one
    i = np.arange(inj.clip.num_frames)
    whole = np.flatnonzero(np.isclose(k * i, np.round(k * i)))
    ground = whole[(whole < inj.takeoff) | (whole > inj.landing)]
    assert ground.size > 100
    assert np.abs(P[ground] - P0[np.round(k * ground).astype(int)]).max() < 1e-9
    assert inj.clip.num_frames == int((tr.clip.num_frames - 1) / k) + 1
