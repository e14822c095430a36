"""Issue 33, tried as a new user: every command that takes a CLIP runs the one physics gate,
and every refusal names what would work."""
import json

import numpy as np
import pytest

from flipstudy.study.cli import main

from _shared import shared_file


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("argv", [
    ("edit", "{c}", "--flips", "2", "--out", "{t}/e.bvh"),
    ("concat", "{c}", "{c}", "--out", "{t}/c.bvh"),
    ("figure", "{c}", "--out", "{t}/f.png", "--size", "160x120"),
])
def test_every_clip_command_refuses_the_wrong_header_rate_and_names_the_fix(capsys, tmp_path, argv):
    c = shared_file("88_01.bvh")
    argv = [a.format(c=c, t=tmp_path) for a in argv]
    code, out, err = run(capsys, *argv)
    assert code == 1 and err.startswith(f"flipstudy {argv[0]}: error: {c}: apparent gravity")
    assert "Rerun with --fps 60" in err and "--accept-unphysical" in err
    assert list(tmp_path.iterdir()) == []             # nothing written


def test_score_measures_what_the_gate_would_refuse(capsys):
    """``score`` is the command that measures physical errors, so the gate's finding (a
    gravity 4x too high) is its measurement and a warning naming the fix, not a refusal."""
    c = shared_file("88_01.bvh")
    code, out, err = run(capsys, "score", c)
    assert code == 0, err
    assert "gravity" in out and "--fps 60" in out


def test_edit_runs_with_the_fix_at_the_true_rate(capsys, tmp_path):
    """The issue's k* = 0.675 came from the header's 120 fps; at 60 fps the retiming differs."""
    code, out, err = run(capsys, "edit", shared_file("87_03.bvh"), "--fps", "60", "--flips", "2",
                         "--out", tmp_path / "e.bvh")
    assert code == 0, err
    assert (tmp_path / "e.bvh").exists() and "k* = " in out


def test_concat_refusal_names_the_rule_that_works(capsys, tmp_path):
    a, b = shared_file("87_03.bvh"), shared_file("88_01.bvh")
    code, out, err = run(capsys, "concat", a, b, "--fps", "60", "--out", tmp_path / "c.bvh")
    assert code == 1 and "under the reverse rule" in err
    assert "--rule forward works (θ = " in err
    theta = float(err.split("θ = ")[1].split("°")[0])
    code, out, err = run(capsys, "concat", a, b, "--fps", "60", "--rule", "forward", "--json",
                         "--out", tmp_path / "c.bvh")
    assert code == 0, err
    assert json.loads(out)["theta_deg"] == pytest.approx(theta, abs=0.05)   # the angle it named


def test_jump_refusal_names_the_cheapest_air_time_which_is_the_least_energy(capsys, tmp_path):
    code, out, err = run(capsys, "jump", "--to", "2.2,0,0", "--air", "0.2", "--out", tmp_path / "j.bvh")
    assert code == 1 and "--air " in err.split("cheapest one")[1]
    t_named = float(err.split("(--air ")[1].split(":")[0])
    assert "within reach" in err
    # independent of the closed form: E_k = ½ m |d/T − g T/2|² over a grid of air times
    from flipstudy.stimuli.control.path import estimate_path
    d0 = np.array([2.2, 0, 0]) * np.array([0.78, 1, 0.78]) - np.array([0, 0.08, 0])
    ts = np.linspace(0.2, 1.5, 1301)
    e = [estimate_path(d0, t).kinetic_energy(70) for t in ts]
    assert t_named == pytest.approx(ts[int(np.argmin(e))], abs=0.01)
    code, out, err = run(capsys, "jump", "--to", "2.2,0,0", "--air", str(t_named),
                         "--out", tmp_path / "j.bvh")
    assert code == 0, err                               # the named air time works


def test_a_nan_in_a_bvh_is_shown_as_written_with_its_line(capsys, tmp_path):
    lines = shared_file("87_03.bvh").read_text().split("\n")
    i = next(k for k, ln in enumerate(lines) if ln.startswith("Frame Time")) + 50
    v = lines[i].split()
    v[5] = "nan"
    lines[i] = " ".join(v)
    bad = tmp_path / "nan.bvh"
    bad.write_text("\n".join(lines))
    code, out, err = run(capsys, "edit", bad, "--fps", "60", "--flips", "2", "--out", tmp_path / "e.bvh")
    assert code == 1 and f"{bad}, line {i + 1}: non-finite value 'nan' in frame 50, channel 6" in err
    assert "np.float64" not in err


def test_a_missing_clip_in_a_design_names_the_design_file(capsys, tmp_path):
    d = tmp_path / "d.toml"
    assert run(capsys, "init", d)[0] == 0
    d.write_text(d.read_text().replace('source = "frontflip"', 'source = "nothere.bvh"'))
    code, out, err = run(capsys, "stimuli", d, "--out", tmp_path / "s", "--quiet")
    assert code == 1 and f"error: {d}: clips 'frontflip': source 'nothere.bvh'" in err
    assert not (tmp_path / "s").exists()


def test_an_angular_momentum_level_of_500_is_refused_by_the_design_check(capsys, tmp_path):
    d = tmp_path / "d.toml"
    assert run(capsys, "init", d)[0] == 0
    d.write_text(d.read_text().replace("levels = [0, 17, 25, 37, 50]", "levels = [0, 17, 25, 37, 500]", 1))
    from flipstudy.errors import DesignError
    from flipstudy.stimuli.design import load_design
    with pytest.raises(DesignError, match=r"500 % is out of range: an increase of the angular "
                                          r"momentum must be below 500 %"):
        load_design(d)


def test_version_is_the_installed_distribution_version(capsys):
    from importlib.metadata import version
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out == f"flipstudy {version('flipstudy')}\n"
