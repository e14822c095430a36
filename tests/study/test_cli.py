"""The command line as a user runs it."""
import json
import subprocess
import sys

import pytest

from flipstudy.study.cli import main

from _shared import shared_file

KEYS = {"frames", "fps", "scale", "apparent_gravity", "takeoff", "landing", "flight_s",
        "takeoff_angle_deg", "L_mean", "L_cv_pct", "segment_masses", "warnings"}


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_inspect_json_has_the_design_keys_real_clip(capsys):
    code, out, _ = run(capsys, "inspect", str(shared_file("88_01.bvh")), "--json")
    assert code == 0
    d = json.loads(out)
    assert KEYS <= set(d)
    assert d["fps"] == 120 and d["scale"] == pytest.approx(0.0254 / 0.45)
    assert d["apparent_gravity"] > 25
    assert any("--fps 60" in w for w in d["warnings"])
    assert sum(d["segment_masses"].values()) == pytest.approx(70.0, abs=0.01)


def test_inspect_fps_and_scale_overrides(capsys):
    code, out, _ = run(capsys, "inspect", str(shared_file("88_01.bvh")), "--fps", "60", "--json")
    d = json.loads(out)
    assert d["fps"] == 60 and d["fps_source"] == "given"
    assert d["apparent_gravity"] == pytest.approx(9.81, rel=0.25)
    code, out, _ = run(capsys, "inspect", str(shared_file("88_01.bvh")), "--fps", "60",
                       "--scale", "0.1", "--json")
    d2 = json.loads(out)
    assert d2["scale"] == 0.1 and d2["scale_source"] == "given"
    # lengths ×(0.1/0.0564): apparent gravity scales with them
    assert d2["apparent_gravity"] / d["apparent_gravity"] == pytest.approx(0.1 / (0.0254 / 0.45), rel=0.05)


def test_inspect_no_flight_clip(capsys):
    code, out, _ = run(capsys, "inspect", str(shared_file("mass_kick.bvh")), "--json")
    d = json.loads(out)
    assert code == 0 and d["takeoff"] is None and d["apparent_gravity"] is None


def test_inspect_plot_is_written(capsys, tmp_path):
    png = tmp_path / "p.png"
    code, out, _ = run(capsys, "inspect", str(shared_file("87_03.bvh")), "--fps", "60", "--plot", str(png))
    assert code == 0 and "flight" in out
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20000


def test_inspect_builtin_text_and_json(capsys):
    code, out, _ = run(capsys, "inspect", "backflip", "--json")
    d = json.loads(out)
    assert code == 0 and d["apparent_gravity"] == pytest.approx(9.81, rel=0.01)
    assert d["L_cv_pct"] < 1.0 and not any("gravity" in w for w in d["warnings"])


def test_bad_file_gives_a_clear_error_not_a_traceback(capsys, tmp_path):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Qrotation\n}\nMOTION\n")
    code, out, err = run(capsys, "inspect", str(bad))
    assert code == 1 and "bad.bvh, line 5" in err and "Qrotation" in err and "Traceback" not in err
    code, out, err = run(capsys, "inspect", str(tmp_path / "missing.bvh"))
    assert code == 1 and "missing.bvh: neither a built-in clip" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_an_internal_bug_shows_its_traceback_and_asks_for_a_report(capsys, monkeypatch):
    """Only user errors (FlipstudyError) are one line: a bug inside the library, here a
    ZeroDivisionError injected into the analyser, keeps its traceback, asks to be reported
    and exits with EX_SOFTWARE (70), not the user-error status 1."""
    from flipstudy import stimuli
    def broken(*a, **kw):
        return 1 / 0

    monkeypatch.setattr(stimuli, "analyse", broken)
    code, out, err = run(capsys, "inspect", "backflip")
    assert code == 70
    assert "Traceback (most recent call last)" in err and "ZeroDivisionError" in err
    assert "in broken" in err                      # the frame of the bug is shown
    assert "bug in flipstudy" in err and "please report it" in err
    # a ValueError is not a user error either (the old CLI printed it as one line)
    monkeypatch.setattr(stimuli, "analyse", lambda *a, **kw: float("x"))
    code, out, err = run(capsys, "inspect", "backflip")
    assert code == 70 and "Traceback" in err and "ValueError" in err


def test_a_refused_output_file_is_one_line(capsys, tmp_path):
    """An OSError about a file the user named (here a folder that cannot be created) is the
    machine refusing it, not a bug: one line naming the file, status 1."""
    (tmp_path / "f").write_text("x")
    code, out, err = run(capsys, "edit", "backflip", "--flips", "2", "--out",
                         str(tmp_path / "f" / "sub" / "x.bvh"))
    assert code == 1 and "Traceback" not in err and str(tmp_path / "f") in err


def test_console_script_help():
    r = subprocess.run([sys.executable, "-m", "flipstudy.study.cli", "--help"], capture_output=True, text=True)
    assert r.returncode == 0 and "inspect" in r.stdout


def test_edit_makes_a_double_flip_and_refuses_a_jump(capsys, tmp_path):
    from flipstudy.stimuli import analyse, load_bvh
    out = tmp_path / "double.bvh"
    code, text, _ = run(capsys, "edit", "backflip", "--flips", "2", "--k-ratio", "1", "--out", str(out),
                        "--plot", str(tmp_path / "L.png"))
    assert code == 0 and "k* = " in text and "turn 72" in text
    clip = load_bvh(out, scale=1.0)
    assert analyse(clip).flight is not None
    assert (tmp_path / "L.png").stat().st_size > 10_000
    code, _, err = run(capsys, "edit", "jump", "--flips", "2", "--out", str(tmp_path / "x.bvh"))
    assert code == 1 and "not one flip" in err and not (tmp_path / "x.bvh").exists()
    code, _, err = run(capsys, "edit", "backflip", "--out", str(tmp_path / "y.bvh"))
    assert code == 2 and "nothing to do" in err


def test_edit_join_refuses_a_twist_and_inspect_names_the_mass_fit(capsys, tmp_path):
    """`edit backflip --join frontflip` is refused with the numbers and writes
    nothing; `inspect` says whether the mass fit was kept."""
    code, _, err = run(capsys, "edit", "backflip", "--join", "frontflip", "--out", str(tmp_path / "j.bvh"))
    assert code == 1 and "face different ways" in err and "⟂ L" in err and "180°" in err
    assert "Traceback" not in err and not (tmp_path / "j.bvh").exists()
    code, out, _ = run(capsys, "inspect", "backflip")
    line = next(x for x in out.splitlines() if "mass fit" in x)
    assert code == 0 and "fitted (W = 1e-05 m²/kg²" in line and "±35 %" in line
    code, out, _ = run(capsys, "inspect", "backflip", "--json")
    mf = json.loads(out)["mass_fit"]
    assert mf["status"] == "fitted" and set(mf["prior"]) == set(mf["fitted"]) and mf["W"] == 1e-5


def test_building_the_parser_imports_no_heavy_library():
    # every command's options are read without pandas, scipy, pyvista, …: each
    # command imports what it needs when it runs
    heavy = {"pandas", "pyvista", "vtk", "matplotlib", "scipy", "statsmodels", "psignifit"}
    code = ("import sys; from flipstudy.study.cli import build_parser; build_parser(); "
            f"print(sorted(m for m in sys.modules if m.split('.')[0] in {heavy!r}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
