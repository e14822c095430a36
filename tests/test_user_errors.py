"""User errors from the command line: one line naming the file and line or the field,
exit status 1, no traceback; nothing written."""
from __future__ import annotations

import pytest

from flipstudy.errors import FlipstudyError
from flipstudy.study.cli import main

from _bvh_gen import many_joints_bvh


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def one_line_error(capsys, argv, *phrases):
    code, out, err = run(capsys, *argv)
    assert code == 1, (code, err)
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for p in phrases:
        assert p in err, (p, err)
    return err


def test_bvh_refusals_are_one_line(capsys, tmp_path):
    p = tmp_path / "fast.bvh"
    p.write_text(many_joints_bvh(4, n_frames=5).replace("Frame Time: 0.0083333", "Frame Time: 1e-320"))
    one_line_error(capsys, ["inspect", str(p)], "fast.bvh, line", "frames per second")
    one_line_error(capsys, ["inspect", str(tmp_path)], "is a directory")
    one_line_error(capsys, ["inspect", "backflip", "--fps", "5"], "fps")


@pytest.mark.parametrize("argv,phrases", [
    (["concat", "backflip", "backflip", "--range-a", "5:2", "--out", "{d}/c.bvh"], ["F0 < F1", "5:2"]),
    (["concat", "backflip", "backflip", "--range-a", "0:100000", "--out", "{d}/c.bvh"], ["--range-a"]),
    (["jump", "--k", "bogus", "--out", "{d}/j.bvh"], ["k: unknown preset"]),
    (["jump", "--mass", "-3", "--out", "{d}/j.bvh"], ["mass"]),
    (["analyze", "{d}/missing.csv"], ["missing.csv: no such file"]),
])
def test_bad_values_name_their_field(capsys, tmp_path, argv, phrases):
    argv = [a.replace("{d}", str(tmp_path)) for a in argv]
    one_line_error(capsys, argv, *phrases)
    assert not any(tmp_path.iterdir())                  # nothing written


def test_analyze_bad_correction_and_bad_table(capsys, tmp_path):
    csv = tmp_path / "r.csv"
    csv.write_text("participant,group,level,response\nP1,g,0,correct\nP1,g,10,maybe\n")
    one_line_error(capsys, ["analyze", str(csv), "--out", str(tmp_path / "a")], "r.csv: line 3",
                   "'maybe'")
    csv.write_text("participant,group,level,response\nP1,g,0,correct\nP1,g,10,incorrect\n")
    one_line_error(capsys, ["analyze", str(csv), "--out", str(tmp_path / "a"), "--correction",
                            "bogus"], "correction")


def test_library_user_errors_are_of_the_family():
    from flipstudy.stimuli import builtin
    from flipstudy.stimuli.control.muscles import parse_k
    with pytest.raises(FlipstudyError, match="fps"):
        builtin("backflip", fps=3)
    with pytest.raises(FlipstudyError, match="^k: "):
        parse_k("bogus")
    with pytest.raises(ValueError):                     # still a ValueError for old callers
        parse_k("bogus")
