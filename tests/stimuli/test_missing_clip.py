"""A clip file that is not there: the error says which folder a relative path was
resolved against and suggests the closest name in the folder (issue 42)."""
import pytest

from flipstudy.errors import DesignError, FlipstudyFileNotFoundError
from flipstudy.stimuli import load_clip
from flipstudy.stimuli.design import load_design
from flipstudy.stimuli.stimset import load_base_clip

DESIGN = """[study]
name = "t"
seed = 1

[[clips]]
name = "mine"
source = "clips/bakflip_01.bvh"

[[groups]]
name = "smooth-increase"
kind = "angular-momentum"
profile = "smooth"
sign = 1
levels = [0, 25]
"""


def test_a_misspelt_design_clip_gets_a_did_you_mean_and_the_design_folder(tmp_path):
    (tmp_path / "clips").mkdir()
    (tmp_path / "clips" / "backflip_01.bvh").write_text("")
    (tmp_path / "design.toml").write_text(DESIGN)
    design = load_design(tmp_path / "design.toml")
    with pytest.raises(DesignError) as e:
        load_base_clip(design.clips[0], design)
    msg = str(e.value)
    assert "did you mean 'clips/backflip_01.bvh'?" in msg
    assert f"resolved against {tmp_path.resolve()}" in msg and "\n" not in msg


def test_a_misspelt_clip_on_the_command_line_gets_a_did_you_mean(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "backflip_01.bvh").write_text("")
    with pytest.raises(FlipstudyFileNotFoundError, match=r"did you mean .backflip_01.bvh."):
        load_clip("bakflip_01.bvh")
    with pytest.raises(FlipstudyFileNotFoundError, match=r"or 'backflip'\?"):
        load_clip("backflp")                        # a built-in name, misspelt
    with pytest.raises(FlipstudyFileNotFoundError, match="the folder nope does not exist"):
        load_clip("nope/x.bvh")
