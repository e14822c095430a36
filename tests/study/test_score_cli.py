"""`flipstudy score`: one clip, many (folder, glob), JSON, the figure; unscored kinds
get no number; the combination rule; a real CMU clip."""
import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flipstudy.stimuli import analyse, builtin, load_bvh, save_bvh
from flipstudy.stimuli.calibration import default_calibration
from flipstudy.stimuli.injection import inject_angular_momentum
from flipstudy.stimuli.measure import Inconsistency
from flipstudy.stimuli.score import score, score_measurement
from flipstudy.study.cli import main

from _shared import shared_file


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    d = tmp_path_factory.mktemp("clips")
    a = analyse(builtin("frontflip"))
    for e in (-0.5, -0.25):
        save_bvh(inject_angular_momentum(a, e, "abrupt").clip, d / f"abrupt{int(e * 100)}.bvh")
    save_bvh(builtin("frontflip"), d / "original.bvh")
    return d


def test_probability_grows_with_the_injected_error_and_unscored_kinds_get_none(clips):
    r = score([builtin("frontflip")] + [load_bvh(clips / f"abrupt{v}.bvh") for v in (-25, -50)])
    cal = default_calibration()
    ps = []
    for c in r.clips:
        e = [x for x in c.errors if x.kind == "angular-momentum" and x.variant == "abrupt"][0]
        ps.append(e.p)
        assert e.p_low <= e.p <= e.p_high
        for x in c.errors:                 # a number exactly where the calibration has a function
            f = cal.lookup(x.kind, x.variant, 1 if x.size >= 0 else -1)
            assert (x.p is None) == (f is None), x
    assert ps[0] < 0.05 < ps[1] < ps[2]
    assert r.clips[2].errors[[x.label() for x in r.clips[2].errors].index("angular-momentum abrupt")].size \
        == pytest.approx(-50, abs=1)       # the measured size, in the study's unit
    d = json.loads(r.to_json())
    assert d["rule"].startswith("P(anything noticed) = 1 − Π(1 − p_i)")
    assert all(e["p"] is None for e in d["clips"][0]["errors"] if e["kind"] == "foot-skate")


def test_combination_rule_counts_a_repeated_departure_once():
    cal = default_calibration()
    a = Inconsistency("angular-momentum", "abrupt", "flight 1", -40.0, "%", 0.0, 1.0, 0.5)
    b = Inconsistency("angular-momentum", "smooth", "flight 1", 50.0, "%", 0.0, 1.0, 1.0)
    rep = Inconsistency("horizontal-velocity", "", "takeoff 1", 50.0, "%", 0.0, 0.0, 0.0, "takeoff-angle")
    errs, (p_any, lo, hi) = score_measurement([a, b], cal)
    p1, p2 = errs[0].p, errs[1].p
    assert lo <= p_any <= hi
    # medians of a product are not products of medians: the rule holds to a few points
    assert p_any == pytest.approx(1 - (1 - p1) * (1 - p2), abs=0.05)
    assert p_any > max(p1, p2)
    _, (p_rep, _, _) = score_measurement([a, b, rep], cal)
    assert p_rep == pytest.approx(p_any, abs=1e-12)        # unscored or repeated: no change


def test_cli_table_json_and_figure(clips, tmp_path, capsys):
    assert main(["score", str(clips)]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") >= 4 and "abrupt-50" in out and "unscored" in out
    assert main(["score", str(clips / "abrupt*.bvh"), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert [c["name"] for c in d["clips"]] == ["abrupt-25", "abrupt-50"]
    fig = tmp_path / "s.png"
    assert main(["score", str(clips / "abrupt-50.bvh"), "--figure", str(fig)]) == 0
    assert fig.read_bytes()[:4] == b"\x89PNG" and fig.stat().st_size > 30_000
    assert main(["score", str(tmp_path / "none*.bvh")]) == 1
    assert "no clips found" in capsys.readouterr().err


def test_real_clip_wrong_frame_time_shows_as_gravity(capsys):
    path = shared_file("88_01.bvh")
    assert main(["score", str(path), "--json"]) == 0    # measured, not refused by the loading gate
    c = json.loads(capsys.readouterr().out)["clips"][0]
    g = [e for e in c["errors"] if e["kind"] == "gravity"]
    assert g and g[0]["size"] > 100 and g[0]["p"] is None      # measured, not scored
    assert any("--fps 60" in w for w in c["warnings"])


def test_calibrate_needs_the_design_and_names_it(tmp_path, capsys):
    study = tmp_path / "s"
    study.mkdir()
    (study / "responses.csv").write_text("participant,group,level,response\nP1,g,0,correct\n")
    assert main(["calibrate", str(study), "--out", str(tmp_path / "c.json")]) == 1
    err = capsys.readouterr().err
    assert "design.toml" in err and "Traceback" not in err and not (tmp_path / "c.json").exists()


@settings(max_examples=60, deadline=None)
@given(i=st.integers(0, 5), x=st.floats(0, 150), dx=st.floats(0, 50),
       sizes=st.lists(st.floats(-80, 80), min_size=1, max_size=4))
def test_probabilities_are_monotone_bounded_and_combine_upwards(i, x, dx, sizes):
    cal = default_calibration()
    f = cal.functions[i]
    p, lo, hi = f.p_noticed(x)
    assert 0 <= lo <= p <= hi <= 1
    assert f.p_noticed(x + dx)[0] >= p - 1e-12          # a larger error is never less noticed
    items = [Inconsistency("angular-momentum", v, "flight 1", s, "%", 0.0, 1.0, 0.5)
             for s, v in zip(sizes, ["smooth", "abrupt"] * 2)]
    errs, (p_any, a_lo, a_hi) = score_measurement(items, cal)
    assert 0 <= a_lo <= p_any <= a_hi <= 1
    assert p_any >= max(e.p for e in errs) - 0.02       # medians: to a couple of points
