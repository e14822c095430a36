"""Contact instants, stencils that stay in their phase, errors over the whole
airborne span — checked against the built-ins' known instants and against the
feet's own geometry, computed here from joint positions (not the analyser's
window)."""
import numpy as np
import pytest

from flipstudy.stimuli import analyse, builtin, load_bvh
from flipstudy.stimuli.body import Body
from flipstudy.stimuli.design import PAPER_DESIGN, parse_design
from flipstudy.errors import StimulusError
from flipstudy.stimuli.injection import (AIR_MARGIN, Injected, check, inject_angular_momentum,
                            inject_takeoff_angle, measure)
from flipstudy.stimuli.motion.bvh import bvh_text
from flipstudy.stimuli.physics import center_of_mass, momentum
from flipstudy.stimuli.stimset import plan

from _shared import shared_file

G = 9.81


def lowest_point(clip):
    """(F,) height of the body's lowest joint or end site."""
    J = clip.joint_positions()[..., 1].min(1)
    E = clip.end_site_positions()[..., 1].min(1) if clip.skeleton.end_sites else J
    return np.minimum(J, E)


def geometric_airborne(clip, thr=3e-3):
    """Longest run of frames whose lowest point is more than ``thr`` above the
    floor (the median of the lowest point: the built-ins stand most of the time;
    not a low percentile, which a low-gravity edit at a kept flight time drags
    below the floor: its feet dip through it just after take-off, and every
    standing frame after the landing then counted as airborne)."""
    h = lowest_point(clip)
    air = h > np.median(h) + thr
    m = np.diff(np.concatenate([[0], air.astype(int), [0]]))
    st, en = np.flatnonzero(m == 1), np.flatnonzero(m == -1) - 1
    i = int(np.argmax(en - st))
    return int(st[i]), int(en[i])


# ------------------------------------------------------------ the instants
@pytest.mark.parametrize("name", ["backflip", "frontflip", "jump"])
@pytest.mark.parametrize("fps", [30, 60, 120])
def test_builtin_instants_recovered(name, fps):
    clip = builtin(name, fps=fps)
    a = analyse(clip)
    i_to, i_td = clip.meta["takeoff"], clip.meta["touchdown"]
    assert abs(a.takeoff_time * fps - i_to) <= 0.5
    assert abs(a.landing_time * fps - i_td) <= 0.5
    # frames strictly inside
    assert (a.takeoff, a.landing) == (i_to + 1, i_td - 1)
    assert a.flight_s == pytest.approx(clip.meta["flight_s"], abs=0.5 / fps)
    # the COM really is in free fall on every frame strictly inside, and the
    # ground pushes on the frame before (independent second differences)
    com = center_of_mass(clip, Body.from_skeleton(clip.skeleton, 70.0,
                                                  segment_masses=clip.meta["segment_masses"]))
    acc = (com[2:, 1] - 2 * com[1:-1, 1] + com[:-2, 1]) * fps ** 2
    inside = acc[a.takeoff:a.landing - 1]           # centred on takeoff+1 .. landing-1
    assert np.abs(inside + G).max() < 1e-6
    d = a.to_dict()
    assert d["takeoff_time"] == pytest.approx(a.takeoff_time, abs=1e-4)
    assert d["landing_time"] == pytest.approx(a.landing_time, abs=1e-4)


@pytest.fixture(scope="module", params=["88_01.bvh", "87_03.bvh"])
def cmu(request):
    return load_bvh(shared_file(request.param), fps=60)


def _foot_geometry(clip):
    """Per frame the lowest of each foot's points (foot joint, toe joint, toe
    end site) above that foot's standing level (median over the first 20
    moving frames after the T-pose), from joint positions alone."""
    sk = clip.skeleton
    J = clip.joint_positions()
    E = clip.end_site_positions()
    out = []
    for side in ("Left", "Right"):
        joints = [sk.index(f"{side}Foot"), sk.index(f"{side}ToeBase")]
        ends = [k for k, (p, _) in enumerate(sk.end_sites) if p == sk.index(f"{side}ToeBase")]
        h = np.minimum(J[:, joints, 1].min(1), E[:, ends, 1].min(1))
        out.append(h)
    return np.stack(out, 1)


def test_cmu_takeoff_and_landing_match_foot_geometry(cmu):
    a = analyse(cmu)
    h = _foot_geometry(cmu)
    fps = cmu.fps
    to, ld = a.takeoff, a.landing
    # standing levels: each foot's low level (10th percentile) over the second
    # before the analyser's window and the half-second after it
    pre = np.percentile(h[max(1, to - 60):to], 10, axis=0)
    post = np.percentile(h[ld + 1:ld + 31], 10, axis=0)
    up = h - pre[None] > 0.02                             # foot more than 2 cm off
    rising = np.gradient(h, 1 / fps, axis=0) > 0.2
    # geometric take-off: the first frame from which both feet are off and rising
    both = up.all(1) & rising.all(1)
    geo_to = int(np.flatnonzero(both[to - 15:to + 15])[0]) + to - 15
    down = (h - post[None] < 0.02).any(1)
    geo_td = int(np.flatnonzero(down[ld - 10:ld + 15])[0]) + ld - 10
    assert abs(to - geo_to) <= 1, (to, geo_to)
    assert abs((ld + 1) - geo_td) <= 1, (ld, geo_td)
    assert a.takeoff_time * fps < to and a.landing_time * fps > ld


# --------------------------------------------------------------- stencils
@pytest.mark.parametrize("name,flips", [("backflip", 2), ("backflip", 3), ("backflip", 4),
                                        ("frontflip", 2)])
def test_multiflip_flight_L_conserved_after_bvh_round_trip(tmp_path, name, flips):
    from flipstudy.stimuli.edit.multiflip import multiflip
    res = multiflip(analyse(builtin(name)), flips)
    p = tmp_path / "x.bvh"
    p.write_text(bvh_text(res.clip, 1.0))
    a = analyse(load_bvh(p))
    assert a.L_cv_pct <= 0.5


def test_momentum_breaks_keep_stencils_in_their_phase():
    from flipstudy.stimuli.edit.multiflip import multiflip
    clip = multiflip(analyse(builtin("backflip")), 2, k_ratio=0.7).clip   # 0.7·k*: momentum breaks at the contacts
    a = analyse(clip)
    fr = a.flight_frames
    whole = np.linalg.norm(momentum(clip, a.body).L, axis=1)[fr]
    split = a.L_norm[fr]
    cv = lambda x: 100 * x.std() / x.mean()  # noqa: E731
    # the whole-clip central stencil at the flight's last frame reaches the ground
    assert cv(whole) > 1.0
    assert cv(split) <= 0.5
    # the flight's own frames, differenced alone, give the same |L|
    inside = clip.slice(a.takeoff, a.landing + 1)
    alone = np.linalg.norm(momentum(inside, a.body).L, axis=1)
    assert np.allclose(alone, split, rtol=1e-9)
    # and the ground phases are differenced on their own too
    before = clip.slice(0, a.takeoff)
    assert np.allclose(np.linalg.norm(momentum(before, a.body).L, axis=1), a.L_norm[:a.takeoff],
                       rtol=1e-9)


# ------------------------------------------------- errors over the airborne span
def _design_stimuli(name):
    a = analyse(builtin(name))
    d = parse_design(PAPER_DESIGN)
    out = []
    for stim, spec, group, level in plan(d):
        if spec.name != name or group is None or level == 0:
            continue
        e = group.sign * level / 100.0
        inj = (inject_angular_momentum(a, e, group.profile, d.com_policy)
               if group.kind == "angular-momentum" else inject_takeoff_angle(a, e))
        out.append((stim, group, inj))
    return a, out


@pytest.fixture(scope="module", params=["backflip", "frontflip"])
def design_stimuli(request):
    return request.param, *_design_stimuli(request.param)


def test_every_default_stimulus_is_ballistic_over_its_geometric_airborne_span(design_stimuli):
    name, a, stims = design_stimuli
    clip0 = builtin(name)
    body = Body.from_skeleton(clip0.skeleton, 70.0, segment_masses=clip0.meta["segment_masses"])
    assert len(stims) == 20
    for stim, group, inj in stims:
        s, e = geometric_airborne(inj.clip)
        # the injection's airborne span covers the feet-off-the-floor frames
        assert inj.takeoff <= s and e <= inj.landing, stim
        assert e - s + 1 >= 0.9 * (inj.landing - inj.takeoff + 1), stim
        com = center_of_mass(inj.clip, body)[s:e + 1]
        t = np.arange(com.shape[0]) / inj.clip.fps
        g = -2.0 * np.polyfit(t, com[:, 1], 2)[0]
        assert g == pytest.approx(G, abs=0.02), stim
        acc = (com[2:] - 2 * com[1:-1] + com[:-2]) * inj.clip.fps ** 2
        acc[:, 1] += G
        assert np.linalg.norm(acc, axis=1).max() < 1.0, stim
        # x and z: straight lines
        for ax in (0, 2):
            assert np.abs(np.polyfit(t, com[:, ax], 1, full=True)[1]).max() < 1e-8


def test_abrupt_step_sits_at_the_midpoint_of_the_airborne_span(design_stimuli):
    name, a, stims = design_stimuli
    for stim, group, inj in stims:
        if group.profile != "abrupt":
            continue
        fps = inj.clip.fps
        # |L| of the stimulus differenced inside its span only; the step is
        # where it jumps
        Ln = np.linalg.norm(momentum(inj.clip, a.body, [inj.takeoff, inj.landing + 1]).L, axis=1)
        x = Ln[inj.takeoff:inj.landing + 1]
        k = inj.takeoff + int(np.argmax(np.abs(np.diff(x)))) + 0.5   # between two frames
        mid = (inj.takeoff_time + inj.landing_time) / 2 * fps
        assert abs(k - mid) <= 1.0, (stim, k, mid)
        m = measure(a, inj)
        assert m["L_error_touchdown_pct"] == pytest.approx(100 * inj.error, abs=1.0)


def test_manifest_measures_contact_velocity_changes_and_in_air_departure(design_stimuli):
    name, a, stims = design_stimuli
    for stim, group, inj in stims:
        m = measure(a, inj)
        # exact flights: what is left is the estimated masses' few grams off the
        # built-in's own (the fit moves the light segments), ~2e-5 m/s²
        assert m["air_acc_dev"] < 1e-3 and m["air_acc_dev_original"] < 1e-3
        check(m, inj, 1.0, stim)                     # not refused
        # a changed take-off velocity moves the feet near the floor: reported, and
        # a few millimetres at most (independently: the lowest joint or end site)
        depth = 1000 * max(0.0, lowest_point(a.clip).min() - lowest_point(inj.clip).min())
        assert m["below_floor_mm"] == pytest.approx(depth, abs=1e-6)
        assert m["below_floor_mm"] < 8.0
        # everything up to the take-off instant is the original's, bit for bit
        n0 = inj.takeoff
        assert np.array_equal(inj.clip.rotations[:n0], a.clip.rotations[:n0])
        assert np.array_equal(inj.clip.root_pos[:n0], a.clip.root_pos[:n0])
        if group.kind == "takeoff-angle":
            # the horizontal velocity changes by e·v_h at take-off and back at touchdown
            vh = np.hypot(a.takeoff_velocity[0], a.takeoff_velocity[2])
            assert m["dv_takeoff"] == pytest.approx(abs(inj.error) * vh, rel=0.05)
            assert m["dv_landing"] == pytest.approx(abs(inj.error) * vh, rel=0.05)
        else:
            assert m["dv_takeoff"] > 0.1
            if group.profile == "smooth":
                assert m["L_error_touchdown_pct"] == pytest.approx(100 * inj.error, abs=1.0)


def test_a_mid_air_jolt_is_refused_with_its_numbers():
    a = analyse(builtin("backflip"))
    inj = inject_takeoff_angle(a, 0.2)
    # the old bug: the error switched on three frames after the real take-off
    clip = inj.clip
    t = np.arange(clip.num_frames) / clip.fps - (a.takeoff + 3) / clip.fps
    v = 0.2 * a.takeoff_velocity * np.array([1.0, 0.0, 1.0])
    jolted = clip.replace(root_pos=a.clip.root_pos + v[None] * np.clip(t, 0, None)[:, None])
    bad = Injected(jolted, "takeoff-angle", None, 0.2, inj.takeoff, inj.landing, None,
                   inj.flight_s, inj.takeoff_time, inj.landing_time)
    m = measure(a, bad)
    assert m["air_acc_dev"] > AIR_MARGIN
    with pytest.raises(StimulusError, match=r"leaves free fall in the air.*m/s²"):
        check(m, bad, 100.0, "jolted")
