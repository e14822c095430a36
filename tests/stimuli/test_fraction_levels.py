"""Levels written as fractions where percent is meant (`levels = [0, 0.25, 0.5]`) build
0.25 % errors: a warning names the design file and group (issue 42)."""
import warnings

import pytest

from flipstudy.stimuli.design import load_design
from flipstudy.study.cli import main

DESIGN = """[study]
name = "t"
seed = 1

[[clips]]
name = "backflip"
source = "backflip"

[[groups]]
name = "smooth-increase"
kind = "angular-momentum"
profile = "smooth"
sign = 1
levels = {levels}
"""


def test_every_level_below_one_percent_warns_naming_file_and_group(tmp_path):
    path = tmp_path / "design.toml"
    path.write_text(DESIGN.format(levels="[0, 0.25, 0.5]"))
    with pytest.warns(UserWarning, match=r"design\.toml: groups\[0\] \(smooth-increase\)\.levels: "
                                         r"every level is below 1 %.*multiply them by 100"):
        load_design(path)


@pytest.mark.parametrize("levels", ["[0, 25, 50]", "[0, 0.5, 5]", "[0]"])
def test_percent_levels_do_not_warn(tmp_path, levels):
    path = tmp_path / "design.toml"
    path.write_text(DESIGN.format(levels=levels))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_design(path)


def test_the_cli_prints_the_warning_in_one_line(tmp_path, capsys):
    path = tmp_path / "design.toml"
    path.write_text(DESIGN.format(levels="[0, 0.25, 0.5]"))
    assert main(["stimuli", str(path), "--out", str(tmp_path / "study")]) == 0
    err = [ln for ln in capsys.readouterr().err.splitlines() if "WARNING" in ln]
    assert err == [f"flipstudy stimuli: WARNING: {path}: groups[0] (smooth-increase).levels: every "
                   f"level is below 1 % ([0.0, 0.25, 0.5]); levels are percent (25 is a 25 % error): "
                   f"if these are fractions, multiply them by 100"]
