"""Stimulus generation: error injection, measurement, designs, manifests."""
import hashlib
import os

import numpy as np
import pytest

from flipstudy.stimuli import analyse, load_bvh
from flipstudy.errors import DesignError, StimulusError
from flipstudy.stimuli.design import PAPER_DESIGN, load_design, parse_design
from flipstudy.stimuli.injection import check, inject_angular_momentum, inject_takeoff_angle, measure
from flipstudy.stimuli.contract import StimulusSet
from flipstudy.stimuli.stimset import build_stimuli

from _shared import MOCAP, shared_file


@pytest.fixture(scope="module")
def real():
    return analyse(load_bvh(shared_file("88_01.bvh"), fps=60))


# ------------------------------------------------------------------ injection
@pytest.mark.parametrize("profile", ["smooth", "abrupt"])
@pytest.mark.parametrize("e", [-0.37, -0.17, 0.17, 0.37])
def test_am_error_both_signs_on_real_flip(real, profile, e):
    inj = inject_angular_momentum(real, e, profile)
    m = measure(real, inj)
    # real data is noisy: within 5 points (the documented real-data tolerance is larger)
    assert m["measured_error_pct"] == pytest.approx(100 * e, abs=5.0)
    assert np.sign(m["L_change_pct"]) == np.sign(e)
    # the direction of L is unchanged
    a2 = analyse(inj.clip, body=real.body, estimate=False)
    assert np.dot(a2.L_direction, real.L_direction) > 0.99
    # the take-off angle is kept under the default policy
    assert abs(m["takeoff_angle_change_deg"]) < 0.5
    # the flight's duration changed the right way
    assert (inj.flight_s < real.flight_s) == (e > 0)
    # frames before take-off are the original's
    assert np.allclose(inj.clip.root_pos[:real.takeoff], real.clip.root_pos[:real.takeoff])


def test_landing_policy_keeps_the_landing_point(real):
    inj = inject_angular_momentum(real, 0.37, "smooth", com_policy="landing")
    a2 = analyse(inj.clip, body=real.body, estimate=False)
    T0 = real.flight_s
    land0 = real.path[:, 2] + real.path[:, 1] * T0 + real.path[:, 0] * T0 ** 2
    Tn = inj.flight_s
    land1 = a2.com[inj.takeoff] + (a2.com[inj.landing] - a2.com[inj.takeoff]) * (Tn / ((inj.landing - inj.takeoff) / 60))
    assert np.allclose(land1[[0, 2]], land0[[0, 2]], atol=0.02)
    # while the angle policy moves it
    inj2 = inject_angular_momentum(real, 0.37, "smooth", com_policy="angle")
    m2 = measure(real, inj2)
    assert abs(m2["takeoff_angle_change_deg"]) < 0.5


@pytest.mark.parametrize("e", [0.1, 0.4, -0.2])
def test_takeoff_error_changes_horizontal_velocity_not_L(real, e):
    inj = inject_takeoff_angle(real, e)
    m = measure(real, inj)
    assert m["measured_error_pct"] == pytest.approx(100 * e, abs=0.5)
    assert abs(m["L_change_pct"]) < 1.0
    assert m["flight_s"] == pytest.approx(real.flight_s)
    # a faster horizontal velocity flattens the take-off
    assert np.sign(m["takeoff_angle_change_deg"]) == -np.sign(e)


def test_refusal_names_the_miss(real):
    inj = inject_angular_momentum(real, 0.5, "abrupt")
    m = measure(real, inj)
    m["measured_error_pct"] = 40.0
    with pytest.raises(StimulusError, match="misses the nominal"):
        check(m, inj, 1.0, "x")


# ------------------------------------------------------------------ designs
def test_paper_design_parses():
    d = parse_design(PAPER_DESIGN)
    assert [g.name for g in d.groups] == ["smooth-increase", "smooth-decrease", "abrupt-increase",
                                          "abrupt-decrease", "takeoff-increase"]
    assert list(d.groups[0].levels) == [0, 17, 25, 37, 50] and list(d.groups[-1].levels) == [0, 10, 20, 30, 40]
    assert d.repetitions == 2 and {c.name for c in d.clips} == {"backflip", "frontflip"}


@pytest.mark.parametrize("old,new,field", [
    ('seed = 20070803', 'seed = "x"', "seed"),
    ('kind = "takeoff-angle"', 'kind = "gravitation"', "kind"),
    ('kind = "takeoff-angle"', 'kind = "gravity"', "missing field 'policy'"),
    ('profile = "abrupt"\nsign = 1', 'profile = "sudden"\nsign = 1', "profile"),
    ('sign = -1', 'sign = 2', "sign"),
    ('levels = [0, 10, 20, 30, 40]', 'levels = [0, -10]', "levels"),
    ('clips = ["backflip", "frontflip"]', 'clips = ["cartwheel"]', "reference"),
    ('repetitions = 2 ', 'repetitions = 0 ', "repetitions"),
    ('name = "backflip"\nsource', 'name = "back flip/x"\nsource', "name"),
    ('[study]', '[stduy]', "unknown section"),
])
def test_invalid_designs_name_the_field(old, new, field):
    assert old in PAPER_DESIGN
    with pytest.raises(DesignError, match=field):
        parse_design(PAPER_DESIGN.replace(old, new, 1), "d.toml")


def test_design_missing_clip_file(tmp_path):
    p = tmp_path / "d.toml"
    p.write_text(PAPER_DESIGN.replace('source = "backflip"', 'source = "nope.bvh"'))
    with pytest.raises(DesignError, match="nope.bvh"):
        build_stimuli(load_design(p), tmp_path / "out", progress=False)
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ sets
def _real_design(tmp_path, tol=2.0, groups=None):
    text = PAPER_DESIGN.replace('source = "backflip"', f'source = "{MOCAP / "88_01.bvh"}"\nfps = 60')
    text = text.replace('source = "frontflip"', f'source = "{MOCAP / "87_03.bvh"}"\nfps = 60')
    text = text.replace("tolerance_pct = 1.0", f"tolerance_pct = {tol}")
    p = tmp_path / "real.toml"
    p.write_text(text)
    return load_design(p)


@pytest.mark.slow
def test_default_design_on_builtin_flips_is_exact(tmp_path):
    """The paper's design on the built-in flips: every stimulus within ±1 point of
    its nominal error (measured by the analyser), AM stimuli keep the take-off
    angle to 0.5° (default policy), take-off stimuli keep |L| to 1 %."""
    d = parse_design(PAPER_DESIGN)
    build_stimuli(d, tmp_path / "study", progress=False)
    man = StimulusSet.read(tmp_path / "study", files=False, design=False).rows()
    assert len(man) == 2 + 2 * (4 * 4 + 1 + 5)      # the AM groups share one original per clip
    kinds = {r["kind"] for r in man}
    assert {"angular-momentum", "takeoff-angle"} <= kinds
    for r in man:
        if r["kind"] == "reference":
            continue
        nominal, got = float(r["nominal_error_pct"]), float(r["measured_error_pct"])
        assert abs(got - nominal) <= 1.0, (r["stimulus"], got, nominal)
        if r["kind"] == "angular-momentum":
            assert abs(float(r["takeoff_angle_change_deg"])) < 0.5, r["stimulus"]
        else:
            assert abs(float(r["L_change_pct"])) < 1.0, r["stimulus"]
    # both signs and both profiles are there, up to ±50 %
    am = [float(r["nominal_error_pct"]) for r in man if r["kind"] == "angular-momentum"]
    assert min(am) == -50.0 and max(am) == 50.0
    assert {r["profile"] for r in man if r["kind"] == "angular-momentum"
            and r["group"] != "original"} == {"smooth", "abrupt"}
    # the shared originals: one per clip, unmodified (no profile, level 0), and every AM
    # stimulus names it as the original its d' is computed against
    orig = [r for r in man if r["group"] == "original"]
    assert [r["stimulus"] for r in orig] == ["backflip_original", "frontflip_original"]
    assert all(r["profile"] == "" and float(r["level"]) == 0 for r in orig)
    assert {r["original"] for r in man if r["kind"] == "angular-momentum"} == {r["stimulus"] for r in orig}


@pytest.mark.slow
def test_default_design_from_real_cmu_flips(tmp_path):
    shared_file("88_01.bvh")
    d = _real_design(tmp_path)
    rows = build_stimuli(d, tmp_path / "study", progress=False).rows
    man = StimulusSet.read(tmp_path / "study", files=False, design=False).rows()
    assert len(man) == len(rows) == 2 + 2 * (4 * 4 + 1 + 5)   # shared AM original per clip
    for r in man:
        assert (tmp_path / "study" / r["bvh"]).exists() and (tmp_path / "study" / r["npz"]).exists()
        got = float(r["measured_error_pct"])
        assert abs(got - float(r["nominal_error_pct"])) <= 2.0      # the documented real-data tolerance
        data = (tmp_path / "study" / r["bvh"]).read_bytes()
        assert hashlib.sha256(data).hexdigest() == r["sha256"]
    # the stimuli read back as clips with the flight where the manifest says
    r = next(r for r in man if r["stimulus"] == "backflip_smooth-increase_37")
    clip = load_bvh(tmp_path / "study" / r["bvh"], scale=1.0)
    npz = np.load(tmp_path / "study" / r["npz"])
    assert np.allclose(npz["root_pos"], clip.root_pos, atol=1e-8)
    assert int(npz["takeoff"]) == int(r["takeoff"]) and clip.num_frames == int(r["frames"])


@pytest.mark.slow
def test_same_design_same_bytes_and_atomic_replace(tmp_path):
    shared_file("88_01.bvh")
    d = _real_design(tmp_path)
    build_stimuli(d, tmp_path / "a", progress=False)
    build_stimuli(d, tmp_path / "b", progress=False)
    assert (tmp_path / "a" / "manifest.csv").read_bytes() == (tmp_path / "b" / "manifest.csv").read_bytes()
    for f in os.listdir(tmp_path / "a"):
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes(), f
    with pytest.raises(FileExistsError):
        build_stimuli(d, tmp_path / "a", progress=False)
    build_stimuli(d, tmp_path / "a", force=True, progress=False)
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


@pytest.mark.slow
def test_interrupted_run_leaves_nothing(tmp_path, monkeypatch):
    shared_file("88_01.bvh")
    d = _real_design(tmp_path)
    import flipstudy.stimuli.injection as ss    # the measure the kinds registry names (injection:measure)
    calls = {"n": 0, "armed": False}
    real_measure = ss.measure

    def flaky(*a, **k):
        calls["n"] += 1
        if calls["armed"] and calls["n"] == 20:
            raise RuntimeError("simulated crash")
        return real_measure(*a, **k)

    monkeypatch.setattr(ss, "measure", flaky)
    build_stimuli(d, tmp_path / "keep", progress=False)          # an existing study ...
    before = (tmp_path / "keep" / "manifest.csv").read_bytes()
    calls["n"], calls["armed"] = 0, True
    with pytest.raises(RuntimeError, match="simulated crash"):
        build_stimuli(d, tmp_path / "keep", force=True, progress=False)
    # ... is untouched by the interrupted replacement, and no temporary folder is left
    assert (tmp_path / "keep" / "manifest.csv").read_bytes() == before
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


@pytest.mark.slow
def test_tolerance_refuses_noisy_real_stimuli(tmp_path):
    shared_file("88_01.bvh")
    d = _real_design(tmp_path, tol=0.5)
    with pytest.raises(StimulusError, match="misses the nominal"):
        build_stimuli(d, tmp_path / "strict", progress=False)
    assert not (tmp_path / "strict").exists()


@pytest.mark.slow
def test_design_with_a_multiflip_base_clip(tmp_path):
    """The paper's study run on the method's own output: a double backflip base clip."""
    text = PAPER_DESIGN.replace('source = "backflip"', 'source = "backflip"\nflips = 2\nk_ratio = 1.0')
    d = parse_design(text)
    assert d.clips[0].flips == 2 and d.clips[0].k_ratio == 1.0
    rows = build_stimuli(d, tmp_path / "study", progress=False).rows
    ref = next(r for r in rows if r["stimulus"] == "backflip_reference")
    orig = next(r for r in rows if r["stimulus"] == "frontflip_reference")
    assert float(ref["flight_s"]) > float(orig["flight_s"])          # a longer flight: two turns
    for r in rows:
        if r["kind"] != "reference" and r["clip"] == "backflip":
            assert abs(float(r["measured_error_pct"]) - float(r["nominal_error_pct"])) <= 1.0, r["stimulus"]
    with pytest.raises(DesignError, match=r"flips.*whole number"):
        parse_design(PAPER_DESIGN.replace('source = "backflip"', 'source = "backflip"\nflips = 9'))
    with pytest.raises(DesignError, match="not one flip"):
        build_stimuli(parse_design(PAPER_DESIGN.replace('source = "backflip"', 'source = "jump"\nflips = 2')),
                      tmp_path / "s2", progress=False)
