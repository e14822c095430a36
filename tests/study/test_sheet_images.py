"""Issue 33: ``analyze STUDY`` puts the study's own ghosts and trails on the figure sheet,
the pair ``reproduce`` shows (an original and its clip's strongest error)."""
import pytest

from pathlib import Path

from flipstudy.stimuli.contract import Stimulus, StimulusSet
from flipstudy.study.reproduce import sheet_images


def _set(tmp_path, rows):
    return StimulusSet(Path(tmp_path), tuple(rows), None)


def _touch(render, *names):
    render.mkdir(exist_ok=True)
    for n in names:
        for what in ("ghost", "trail"):
            (render / f"{n}_{what}.png").write_bytes(b"\x89PNG")


def test_a_study_of_its_own_shows_its_original_and_largest_error(tmp_path):
    rows = [Stimulus("jump_original", "jump", "original", "gravity"),
            Stimulus("jump_lower-gravity_10", "jump", "lower-gravity", "gravity", "", 10.0,
                     nominal_error_pct=-10.0),
            Stimulus("jump_lower-gravity_50", "jump", "lower-gravity", "gravity", "", 50.0,
                     nominal_error_pct=-50.0)]
    render = tmp_path / "render"
    _touch(render, "jump_original", "jump_lower-gravity_50")
    imgs = sheet_images(_set(tmp_path, rows), render)
    assert sorted(p.name for p in imgs.values()) == sorted(
        f"{n}_{w}.png" for n in ("jump_original", "jump_lower-gravity_50") for w in ("ghost", "trail"))
    assert any("−50 %" in k for k in imgs) and any("original (no error)" in k for k in imgs)


def test_nothing_rendered_gives_no_images(tmp_path):
    rows = [Stimulus("backflip_reference", "backflip", "reference", "reference")]
    assert sheet_images(_set(tmp_path, rows), tmp_path / "render") == {}


def test_the_default_study_keeps_reproduces_pair(tmp_path):
    rows = [Stimulus("backflip_reference", "backflip", "reference", "reference"),
            Stimulus("backflip_abrupt-decrease_50", "backflip", "abrupt-decrease", "angular-momentum",
                     "abrupt", 50.0, nominal_error_pct=-50.0),
            Stimulus("backflip_smooth-increase_50", "backflip", "smooth-increase", "angular-momentum",
                     "smooth", 50.0, nominal_error_pct=50.0)]
    _touch(tmp_path / "render", "backflip_reference", "backflip_abrupt-decrease_50",
           "backflip_smooth-increase_50")
    imgs = sheet_images(_set(tmp_path, rows), tmp_path / "render")
    assert {p.name.rsplit("_", 1)[0] for p in imgs.values()} == {"backflip_reference",
                                                                "backflip_abrupt-decrease_50"}


@pytest.mark.slow
def test_analyze_of_a_studys_own_responses_table_shows_its_ghosts(tmp_path):
    # `analyze STUDY/responses.csv` (the table `export` writes into the study) draws the sheet
    # with the study's ghosts and trails, as `analyze STUDY` does; a copy of the table
    # elsewhere has no study beside it and says how to get them
    import json
    import shutil

    from flipstudy.study.cli import main as cli
    (tmp_path / "d.toml").write_text('[study]\nname = "s"\nseed = 3\nrepetitions = 1\n\n'
                                     '[[clips]]\nname = "jump"\nsource = "jump"\n\n'
                                     '[[groups]]\nname = "takeoff-increase"\nkind = "takeoff-angle"\n'
                                     'levels = [0, 20]\n')
    st = tmp_path / "st"
    assert cli(["stimuli", str(tmp_path / "d.toml"), "--out", str(st), "--quiet"]) == 0
    assert cli(["render", str(st), "--what", "ghost,trail", "--size", "64x48", "--quiet"]) == 0
    assert cli(["simulate", str(st), "--participants", "2", "--seed", "1"]) == 0
    assert cli(["export", str(st), "--include-simulated"]) == 0
    shutil.copy(st / "responses.csv", tmp_path / "elsewhere.csv")
    fast = ["--include-simulated", "--psychometric", "none", "--no-gee", "--n-boot", "50", "--json"]
    notes = {}
    for name, table in (("own", st / "responses.csv"), ("copy", tmp_path / "elsewhere.csv")):
        from contextlib import redirect_stdout
        from io import StringIO
        buf = StringIO()
        with redirect_stdout(buf):
            assert cli(["analyze", str(table), "--out", str(tmp_path / name), *fast]) == 0
        notes[name] = " ".join(json.loads(buf.getvalue()).get("notes", []))
    assert "no images given" not in notes["own"]
    assert "no images given" in notes["copy"] and "render STUDY --what ghost,trail" in notes["copy"]
