"""Issue 45: ``score --figure x.csv`` ended in matplotlib's traceback; it is one line
naming the option and the formats a figure is written as."""
from __future__ import annotations

from flipstudy.study.cli import main


def test_score_figure_with_a_csv_name_is_one_line(tmp_path, capsys):
    out = tmp_path / "x.csv"
    assert main(["score", "backflip", "--figure", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and f"--figure {out}" in err and ".png" in err
    assert not out.exists()
