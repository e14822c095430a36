"""Strict designs, the physics gate for base clips, and the paper's shared originals."""
import collections
import csv
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _shared import shared_file
from flipstudy.stimuli.analyse import analyse, gravity_warning, physics_advice
from flipstudy.errors import DesignError
from flipstudy.stimuli.design import PAPER_DESIGN, load_design, parse_design
from flipstudy.stimuli.motion.bvh import load_bvh
from flipstudy.stimuli.stimset import build_stimuli, plan

CMU_SCALE = 0.0254 / 0.45          # CMU/ASF length unit in metres

ONE_CLIP = """\
[study]
name = "t"
seed = 1
{study}

[[clips]]
name = "c"
source = "{source}"
{clip}

[[groups]]
name = "ti"
kind = "takeoff-angle"
levels = [0, 20]
"""


def design_file(tmp_path, study="", clip="", source="backflip", text=None):
    p = tmp_path / "design.toml"
    p.write_text(text if text is not None else ONE_CLIP.format(study=study, clip=clip, source=source))
    return p


def refused(tmp_path, **kw):
    p = design_file(tmp_path, **kw)
    with pytest.raises(DesignError) as e:
        load_design(p)
    msg = str(e.value)
    assert str(p) in msg, msg                          # every refusal names the file
    return msg


# ------------------------------------------------------------------ strict keys
@pytest.mark.parametrize("where, line, section, wrong, right", [
    ("study", "repetitons = 1", "[study]", "repetitons", "repetitions"),
    ("study", "tolerence_pct = 2", "[study]", "tolerence_pct", "tolerance_pct"),
    ("clip", "fsp = 60", "clips[0]", "fsp", "fps"),
    ("clip", "accept_unphysica = true", "clips[0]", "accept_unphysica", "accept_unphysical"),
])
def test_a_misspelt_key_is_refused_with_did_you_mean(tmp_path, where, line, section, wrong, right):
    msg = refused(tmp_path, **{where: line})
    assert section in msg and f"unknown key '{wrong}'" in msg and f"did you mean '{right}'" in msg


def test_misspelt_group_key_and_section(tmp_path):
    text = ONE_CLIP.format(study="", clip="", source="backflip").replace('levels = [0, 20]',
                                                                         'levels = [0, 20]\nsing = -1')
    msg = refused(tmp_path, text=text)
    assert "groups[0] (ti)" in msg and "'sing'" in msg and "did you mean 'sign'" in msg
    msg = refused(tmp_path, text=text.replace("sing = -1", "") + "\n[refernce]\nclips = []\n")
    assert "unknown section [refernce]" in msg and "did you mean [reference]" in msg


# ------------------------------------------------------------------ bounds
@pytest.mark.parametrize("line, field, shown", [
    ("repetitions = 1000000000", "[study].repetitions", "1000000000"),
    ("repetitions = 0", "[study].repetitions", "0"),
    ("tolerance_pct = inf", "[study].tolerance_pct", "inf"),
    ("tolerance_pct = nan", "[study].tolerance_pct", "nan"),
    ("tolerance_pct = 0", "[study].tolerance_pct", "0"),
    ("tolerance_pct = 60", "[study].tolerance_pct", "60"),
    ("fps = 0.5", "[study].fps", "0.5"),
    ("total_mass = 7000", "[study].total_mass", "7000"),
    ("break_every = -3", "[study].break_every", "-3"),
    ('original = "each"', "[study].original", "'each'"),
])
def test_numbers_are_bounded_and_reported_as_written(tmp_path, line, field, shown):
    msg = refused(tmp_path, study=line)
    assert field in msg and f"got {shown}" in msg, msg


# ------------------------------------------------------------------ session settings
def test_session_settings_are_read_from_the_session_table(tmp_path):
    text = ONE_CLIP.format(study="", clip="", source="backflip") + "\n[session]\nreplay = true\nbreak_every = 7\n"
    d = load_design(design_file(tmp_path, text=text))
    assert d.session.replay is True and d.session.break_every == 7
    assert parse_design(PAPER_DESIGN).session.replay is False
    assert parse_design(PAPER_DESIGN).session.break_every == 40
    msg = refused(tmp_path, text=text.replace("break_every = 7", "break_every = -3"))
    assert "[session].break_every" in msg and "got -3" in msg, msg
    msg = refused(tmp_path, text=text.replace("replay = true", "replya = true"))
    assert "[session]" in msg and "unknown key 'replya'" in msg and "did you mean 'replay'" in msg


def test_dropped_frame_threshold_and_repeat_are_session_settings(tmp_path):
    d = parse_design(PAPER_DESIGN)
    assert d.session.max_dropped_pct == 10.0 and d.session.repeat_dropped is False
    assert "max_dropped_pct = 10" in PAPER_DESIGN and "repeat_dropped = false" in PAPER_DESIGN
    base = ONE_CLIP.format(study="", clip="", source="backflip") + "\n[session]\n"
    d = load_design(design_file(tmp_path, text=base + "max_dropped_pct = 2.5\nrepeat_dropped = true\n"))
    assert d.session.max_dropped_pct == 2.5 and d.session.repeat_dropped is True
    assert load_design(design_file(tmp_path, text=base + "max_dropped_pct = 0\n")).session.max_dropped_pct == 0
    for line, shown in (("max_dropped_pct = 101", "101"), ("max_dropped_pct = -1", "-1"),
                        ("max_dropped_pct = nan", "nan"), ('max_dropped_pct = "10"', "'10'")):
        msg = refused(tmp_path, text=base + line + "\n")
        assert "design.toml: [session].max_dropped_pct" in msg and f"got {shown}" in msg, msg
    msg = refused(tmp_path, text=base + "repeat_dropped = 1\n")
    assert "[session].repeat_dropped: expected true or false, got 1" in msg, msg
    msg = refused(tmp_path, text=base + "repeat_droped = true\n")
    assert "did you mean 'repeat_dropped'" in msg, msg
    msg = refused(tmp_path, study="max_dropped_pct = 5")      # new keys live in [session] only
    assert "[study]" in msg and "unknown key 'max_dropped_pct'" in msg, msg


def test_session_settings_in_the_study_table_are_still_read_with_a_note(tmp_path):
    p = design_file(tmp_path, study="replay = true\nbreak_every = 7")
    with pytest.warns(FutureWarning, match=r"\[study\] replay, break_every: .*\[session\]") as w:
        d = load_design(p)
    assert str(p) in str(w[0].message)
    assert d.session.replay is True and d.session.break_every == 7
    text = p.read_text() + "\n[session]\nreplay = false\n"
    msg = refused(tmp_path, text=text)
    assert "[study].replay and [session].replay are both given" in msg, msg


def test_seed_must_be_a_non_negative_whole_number(tmp_path):
    text = ONE_CLIP.format(study="", clip="", source="backflip")
    assert "[study].seed" in refused(tmp_path, text=text.replace("seed = 1", "seed = -1"))
    assert "whole number" in refused(tmp_path, text=text.replace("seed = 1", "seed = 1.5"))


def test_clip_scale_and_fps_are_bounded(tmp_path):
    assert "clips[0].scale" in refused(tmp_path, clip="scale = 0.0")
    assert "clips[0].fps" in refused(tmp_path, clip="fps = 1e9")


@pytest.mark.parametrize("kind_lines, levels, expect", [
    ('kind = "takeoff-angle"', "[0, 200]", "200 % is out of range"),
    ('kind = "takeoff-angle"\nsign = -1', "[0, 100]", "100 % is out of range"),
    ('kind = "angular-momentum"\nprofile = "smooth"\nsign = -1', "[0, 95]", "95 % is out of range"),
    ('kind = "angular-momentum"\nprofile = "smooth"', "[0, 600]", "600 % is out of range"),
    ('kind = "angular-momentum"\nprofile = "smooth"', "[0, -1]", "-1 %"),
    ('kind = "angular-momentum"\nprofile = "smooth"', "[0, 25, 25]", "duplicate levels"),
])
def test_levels_out_of_range_in_percent_with_field_and_file(tmp_path, kind_lines, levels, expect):
    text = ONE_CLIP.format(study="", clip="", source="backflip").replace(
        'kind = "takeoff-angle"\nlevels = [0, 20]', f"{kind_lines}\nlevels = {levels}")
    msg = refused(tmp_path, text=text)
    assert "groups[0] (ti).levels" in msg and expect in msg, msg
    assert "-0.01" not in msg and "(-1, 10)" not in msg          # never the internal fraction


@settings(max_examples=60, deadline=None)
@given(level=st.floats(-50, 1200, allow_nan=False), sign=st.sampled_from([1, -1]),
       kind=st.sampled_from(["angular-momentum", "takeoff-angle"]))
def test_level_bounds_property(level, sign, kind):
    """A level is accepted exactly when it lies in its kind's range (AM −90…+500 %,
    both ends excluded: the injection's own range; take-off −100…+100 %), and a
    refusal quotes it in percent, as written (12 significant digits)."""
    prof = 'profile = "abrupt"\n' if kind == "angular-momentum" else ""
    text = ONE_CLIP.format(study="", clip="", source="backflip").replace(
        'kind = "takeoff-angle"\nlevels = [0, 20]',
        f'kind = "{kind}"\n{prof}sign = {sign}\nlevels = [{level!r}]')
    top = {("angular-momentum", 1): 500, ("angular-momentum", -1): 90,
           ("takeoff-angle", 1): 100, ("takeoff-angle", -1): 100}[(kind, sign)]
    ok = 0 <= level and (level <= top if sign > 0 and kind == "takeoff-angle" else level < top)
    if ok:
        assert list(parse_design(text, "d.toml").groups[0].levels) == [level]
    else:
        with pytest.raises(DesignError, match=re.escape(f"{level:.12g} %")):
            parse_design(text, "d.toml")


def test_trials_per_participant_are_bounded(tmp_path):
    msg = refused(tmp_path, text=PAPER_DESIGN.replace("repetitions = 2 ", "repetitions = 20 ").replace(
        "levels = [0, 17, 25, 37, 50]", "levels = [" + ", ".join(str(v) for v in range(0, 80, 4)) + "]"))
    assert "trials per participant" in msg and "at most 3000" in msg


def test_duplicates_are_refused(tmp_path):
    text = ONE_CLIP.format(study="", clip="", source="backflip")
    msg = refused(tmp_path, text=text + '\n[reference]\nclips = ["c", "c"]\n')
    assert "[reference].clips" in msg and "more than once" in msg
    msg = refused(tmp_path, text=text + '\n[[clips]]\nname = "d"\nsource = "backflip"\n')
    assert "clips[1] (d)" in msg and "same source" in msg
    msg = refused(tmp_path, text=text.replace('name = "ti"', 'name = "original"'))
    assert "reserved" in msg


def test_deep_nesting_is_a_design_error_naming_the_file(tmp_path):
    deep = "x = " + "[" * 100000 + "]" * 100000 + "\n"
    msg = refused(tmp_path, text=deep + ONE_CLIP.format(study="", clip="", source="backflip"))
    assert "nested too deeply" in msg or "not valid TOML" in msg


def test_the_paper_design_is_valid_and_init_writes_it():
    d = parse_design(PAPER_DESIGN)
    assert d.original == "shared" and d.repetitions == 2
    assert [g.original for g in d.groups] == ["shared"] * 4 + ["own"]


# ------------------------------------------------------------------ physics gate
@pytest.fixture(scope="module")
def cmu():
    return shared_file("88_01.bvh")


def test_88_01_at_its_header_frame_rate_is_refused_naming_fps_60(tmp_path, cmu):
    p = design_file(tmp_path, source=cmu)
    with pytest.raises(DesignError) as e:
        build_stimuli(load_design(p), tmp_path / "out", progress=False)
    msg = str(e.value)
    assert str(p) in msg and "clips 'c'" in msg and "fps = 60" in msg and "scale =" not in msg
    assert "accept_unphysical = true" in msg
    assert not (tmp_path / "out").exists() and not list(tmp_path.glob(".out.tmp-*"))


def test_scale_0_01_is_refused_naming_the_scale_not_fps(tmp_path, cmu):
    p = design_file(tmp_path, source=cmu, clip="fps = 60\nscale = 0.01")
    with pytest.raises(DesignError) as e:
        build_stimuli(load_design(p), tmp_path / "out", progress=False)
    msg = str(e.value)
    assert f"scale = {CMU_SCALE:.4g}" in msg and "omit scale" in msg and "fps = " not in msg
    assert "0.28 m tall" in msg


def test_accept_unphysical_builds_and_the_manifest_records_it(tmp_path, cmu):
    p = design_file(tmp_path, source=cmu, clip="accept_unphysical = true")
    rows = build_stimuli(load_design(p), tmp_path / "out", progress=False).rows
    with open(tmp_path / "out" / "manifest.csv", newline="") as f:
        man = list(csv.DictReader(f))
    assert [r["stimulus"] for r in man] == [r["stimulus"] for r in rows] == ["c_ti_0", "c_ti_20"]
    assert {r["accept_unphysical"] for r in man} == {"true"}
    assert {r["original"] for r in man} == {"c_ti_0"}


def test_inspect_advice_weighs_frame_time_against_scale(cmu):
    """--fps 60 --scale 0.01: the height (0.28 m) says the scale is wrong, and at the
    right scale gravity is 11.9 m/s², so the frame rate is kept."""
    c = load_bvh(cmu, fps=60, scale=0.01)
    a = analyse(c)
    w = gravity_warning(a.apparent_gravity, c)
    assert w is not None and f"--scale {CMU_SCALE:.4g}" in w and "--fps" not in w
    # independent check of the measurement: gravity is proportional to the scale (to
    # 10 %: the flight detector's thresholds are in metres, so its window moves a little,
    # and the mass fit keeps the prior at one scale and not at the other),
    # and the skeleton read at the CMU unit is an adult
    a_ok = analyse(load_bvh(cmu, fps=60))
    assert a.apparent_gravity * CMU_SCALE / 0.01 == pytest.approx(a_ok.apparent_gravity, rel=0.10)
    assert physics_advice(a_ok.apparent_gravity, a_ok.clip) is None
    # header rate: the height is right, so the fix is the frame rate (a factor of two)
    c120 = load_bvh(cmu)
    adv = physics_advice(analyse(c120).apparent_gravity, c120)
    assert adv.fps == 60 and adv.scale is None
    # both wrong: both named
    cboth = load_bvh(cmu, scale=0.01)
    adv = physics_advice(analyse(cboth).apparent_gravity, cboth)
    assert adv.fps == 60 and adv.scale == pytest.approx(CMU_SCALE)


def test_builtins_pass_the_gate():
    from flipstudy.stimuli import builtin
    for name in ("backflip", "frontflip", "jump"):
        c = builtin(name)
        assert physics_advice(analyse(c).apparent_gravity, c) is None, name


def test_study_fps_resamples_bvh_clips(tmp_path, cmu):
    """[study] fps = 120 with a clip read at 60: the stimuli are at 120 fps, twice the
    frames, the same motion in time (flight duration and take-off angle kept)."""
    p60 = design_file(tmp_path, source=cmu, clip="fps = 60")
    r60 = build_stimuli(load_design(p60), tmp_path / "o60", progress=False).rows
    p120 = design_file(tmp_path, source=cmu, clip="fps = 60", study="fps = 120")
    r120 = build_stimuli(load_design(p120), tmp_path / "o120", progress=False).rows
    assert r60[0]["fps"] == 60 and r120[0]["fps"] == 120
    assert r120[0]["frames"] == 2 * r60[0]["frames"] - 1
    assert r120[0]["flight_s"] == pytest.approx(r60[0]["flight_s"], abs=2 / 60)
    assert r120[0]["takeoff_angle_deg"] == pytest.approx(r60[0]["takeoff_angle_deg"], abs=1.5)
    # the hips' path at the shared instants is the source's (frame 2k at 120 = frame k at 60)
    a = np.load(tmp_path / "o60" / "c_ti_0.npz")["root_pos"]
    b = np.load(tmp_path / "o120" / "c_ti_0.npz")["root_pos"]
    np.testing.assert_allclose(b[::2], a, atol=1e-9)


# ------------------------------------------------------------------ shared originals
def test_a_session_of_the_default_design_shows_each_motion_file_as_designed(tmp_path):
    """Built for real: each stimulus twice; the unmodified clip (by content) twice as the
    angular-momentum groups' shared original and twice as the take-off group's own —
    before, level 0 of each of the five groups was shown twice: 10 times in all."""
    from flipstudy.study.session import load_study, open_session
    dp = tmp_path / "paper.toml"
    dp.write_text(PAPER_DESIGN)
    out = tmp_path / "study"
    build_stimuli(load_design(dp), out, progress=False)
    study = load_study(out)
    s = open_session(study, "P01")
    d = study.design
    per_stim = collections.Counter(t.stimulus for t in s.trials)
    assert set(per_stim.values()) == {d.repetitions} and len(per_stim) == 2 * (4 * 4 + 1 + 5)
    sha = {r.stimulus: r.sha256 for r in study.manifest}
    per_file = collections.Counter(sha[t.stimulus] for t in s.trials)
    for clip in ("backflip", "frontflip"):
        orig = sha[f"{clip}_original"]
        assert sha[f"{clip}_takeoff-increase_0"] == orig        # the same motion file
        assert per_file[orig] == 2 * d.repetitions
        groups = collections.Counter(t.group for t in s.trials if sha[t.stimulus] == orig)
        assert groups == {"original": 2, "takeoff-increase": 2}
    assert max(v for k, v in per_file.items()) == 2 * d.repetitions
    man = study.by_name
    assert man["backflip_original"].group == "original"
    assert man["backflip_original"].kind == "angular-momentum"
    assert man["backflip_abrupt-decrease_37"].original == "backflip_original"
    assert man["backflip_takeoff-increase_20"].original == "backflip_takeoff-increase_0"


def test_shared_original_end_to_end_simulate_export_analyze(tmp_path):
    """Demo study with the shared original: simulated answers, exported, analysed:
    every sharing group's level 0 is the same answers, d′ against them."""
    import pandas as pd

    from flipstudy.analysis.pipeline import analyze
    from flipstudy.study.demo import make_demo_study
    from flipstudy.study.export import export_responses
    from flipstudy.study.simulate import simulate
    d = make_demo_study(tmp_path / "study", videos=False, levels=(0, 25, 50), original=None)
    simulate(d, 5, seed=3)
    res = export_responses(d, include_simulated=True)   # simulated answers are kept apart
    rs = pd.read_csv(res.responses)
    assert res.rows == 5 * 2 * 5                        # 5 stimuli (1 original), twice
    assert (rs["group"] == "original").sum() == 5 * 2
    r = analyze(d, None, psychometric="none", gee=False, n_boot=50, include_simulated=True)
    t = r.table.set_index(["group", "level"])
    n0 = t.loc[("smooth-increase", 0.0)]
    m0 = t.loc[("abrupt-decrease", 0.0)]
    assert n0["n"] == m0["n"] == 10 and n0["n_incorrect"] == m0["n_incorrect"]
    k_orig = int((rs.loc[rs["group"] == "original", "response"] == "incorrect").sum())
    assert n0["n_incorrect"] == k_orig
    assert "original" not in set(r.table["group"])
    assert r.settings["n_trials"] == len(rs)
    # d′ of a level against the shared answers, from the counts (log-linear when extreme)
    from flipstudy.analysis.sdt import dprime
    row = t.loc[("abrupt-decrease", 50.0)]
    assert row["dprime"] == pytest.approx(dprime(row["n_incorrect"], row["n"], k_orig, 10))


def test_a_session_refuses_a_manifest_with_duplicate_or_too_many_trials(tmp_path):
    from flipstudy.study.demo import make_demo_study
    from flipstudy.errors import SessionError
    from flipstudy.study.session import load_study
    d = make_demo_study(tmp_path / "s", videos=False)
    man = (d / "manifest.csv").read_text().splitlines()
    (d / "manifest.csv").write_text("\n".join(man + [man[-1]]) + "\n")
    from flipstudy.errors import ManifestError
    with pytest.raises(ManifestError, match="listed more than once"):
        load_study(d)
    row = man[-1].split(",")
    extra = [",".join([f"x{i}"] + row[1:]) for i in range(1600)]
    (d / "manifest.csv").write_text("\n".join(man + extra) + "\n")
    with pytest.raises(SessionError, match="at most 3000"):
        load_study(d)


def test_a_group_may_keep_its_own_original():
    """original = "own" in one AM group: that group has its level 0, the other three
    share; plan() and Design.stimulus_names() agree."""
    text = PAPER_DESIGN.replace('name = "abrupt-decrease"', 'name = "abrupt-decrease"\noriginal = "own"')
    d = parse_design(text)
    names = [n for n, *_ in plan(d)]
    assert names == d.stimulus_names() and len(set(names)) == len(names)
    assert "backflip_abrupt-decrease_0" in names and "backflip_smooth-increase_0" not in names
    assert "backflip_original" in names and len(names) == 2 + 2 * (3 * 4 + 1 + 5 + 5)
    for variant in (PAPER_DESIGN, PAPER_DESIGN.replace('original = "shared"', 'original = "per-group"')):
        dv = parse_design(variant)
        assert [n for n, *_ in plan(dv)] == dv.stimulus_names()
    with pytest.raises(DesignError, match="only angular-momentum groups share"):
        parse_design(PAPER_DESIGN.replace('kind = "takeoff-angle"', 'kind = "takeoff-angle"\noriginal = "shared"'))


def test_shared_answers_go_only_to_groups_of_their_kind():
    import pandas as pd

    from flipstudy.errors import ResponsesError
    from flipstudy.analysis.io import load_responses
    rows = []
    for p in ("P1", "P2"):
        for g, kind, lv in [("original", "angular-momentum", 0), ("am", "angular-momentum", 25),
                            ("to", "takeoff-angle", 10), ("to", "takeoff-angle", 20)]:
            rows.append({"participant": p, "group": g, "kind": kind, "level": lv, "response": "correct"})
    df = load_responses(pd.DataFrame(rows))
    assert sorted(df.loc[df["level"] == 0, "group"].unique()) == ["am"]     # not the take-off group
    assert len(df) == len(rows) and not df["shared_copy"].any()
    # without a kind column every group lacking a level 0 shares it
    df2 = load_responses(pd.DataFrame(rows).drop(columns="kind"))
    assert sorted(df2.loc[df2["level"] == 0, "group"].unique()) == ["am", "to"]
    assert int((~df2["shared_copy"]).sum()) == len(rows)
    bad = [dict(r, level=5) if r["group"] == "original" else r for r in rows]
    with pytest.raises(ResponsesError, match="level 0"):
        load_responses(pd.DataFrame(bad))
