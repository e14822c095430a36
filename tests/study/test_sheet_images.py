"""Issue 33: ``analyze STUDY`` puts the study's own ghosts and trails on the figure sheet,
the pair ``reproduce`` shows (an original and its clip's strongest error)."""
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
