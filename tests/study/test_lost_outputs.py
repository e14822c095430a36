"""Issue 28, case 2 (and issue 33's participants.csv): no output path of any
command may be a file the study owns.

Before this change ``export st --out st/sessions.sqlite`` replaced the database
with CSV (``status`` then failed with a DatabaseError), and ``export
--include-simulated --out st/all.csv`` silently replaced ``st/participants.csv``;
every case below failed there (checked).  Each refusal names the path and leaves
every file of the study byte for byte as it was.
"""
import hashlib

import pytest

from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.owned import OwnedPathError, owner, refuse_owned
from flipstudy.study.simulate import simulate


def snapshot(folder):
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture
def st(tmp_path):
    st = make_demo_study(tmp_path / "st", video_frames=6)
    simulate(st, 2, seed=3)
    (st / "web").mkdir()
    (st / "web" / "responses.csv").write_text("participant,response\nW01,correct\n")
    return st


OWNED = ["sessions.sqlite", "manifest.csv", "design.toml", "web/responses.csv",
         "render/render.json", "sessions.sqlite-wal"]


@pytest.mark.parametrize("name", OWNED)
def test_export_out_into_a_study_file_is_refused_naming_it(st, name, capsys):
    before = snapshot(st)
    target = st / name
    assert cli(["export", str(st), "--out", str(target)]) == 1
    err = capsys.readouterr().err
    assert str(target) in err and "study" in err
    assert snapshot(st) == before
    assert cli(["status", str(st)]) == 0                       # the database still reads


@pytest.mark.parametrize("opt,name", [("--participants-out", "sessions.sqlite"),
                                      ("--participants-out", "manifest.csv"),
                                      ("--participants-out", "web/participants.csv")])
def test_participants_out_into_the_study_is_refused(st, opt, name, tmp_path, capsys):
    before = snapshot(st)
    assert cli(["export", str(st), "--out", str(tmp_path / "r.csv"), opt, str(st / name)]) == 1
    assert str(st / name) in capsys.readouterr().err
    assert snapshot(st) == before


def test_other_commands_refuse_study_files_as_outputs(st, tmp_path, capsys):
    before = snapshot(st)
    cases = [
        ["analyze", str(st / "responses.csv"), "--out", str(st / "render")],
        ["analyze", str(st / "responses.csv"), "--out", str(st)],
        ["figure", "backflip", "--out", str(st / "manifest.csv")],
        ["export-web", str(st), "--out", str(st / "web")],
        ["export-web", str(st), "--out", str(st)],
        ["edit", "backflip", "--flips", "2", "--out", str(st / "design.toml")],
        ["inspect", "backflip", "--plot", str(st / "sessions.sqlite")],
        ["jump", "--out", str(st / "manifest.csv")],
    ]
    for argv in cases:
        code = cli(argv)
        err = capsys.readouterr().err
        assert code != 0, argv
        assert "does not write over a study's own files" in err, (argv, err)
    assert snapshot(st) == before


def test_export_to_another_name_does_not_replace_the_default_participants(st, tmp_path, capsys):
    """Issue 33: ``export --include-simulated --out st/all.csv`` replaced st/participants.csv."""
    assert cli(["export", str(st)]) == 0                       # the default pair, real only
    default = (st / "participants.csv").read_bytes()
    assert cli(["export", str(st), "--include-simulated", "--out", str(st / "all.csv")]) == 1
    err = capsys.readouterr().err
    assert str(st / "participants.csv") in err and "--participants-out" in err
    assert (st / "participants.csv").read_bytes() == default
    assert not (st / "all.csv").exists()
    # with its own participants file it is written, and the default pair is untouched
    assert cli(["export", str(st), "--include-simulated", "--out", str(st / "all.csv"),
                "--participants-out", str(st / "all-participants.csv")]) == 0
    assert (st / "participants.csv").read_bytes() == default
    assert b"sim001" in (st / "all-participants.csv").read_bytes()


def test_the_default_export_and_the_users_folders_are_still_written(st, tmp_path):
    assert cli(["export", str(st)]) == 0                       # export owns its default tables
    assert cli(["export", str(st)]) == 0                       # and rewrites them
    assert (st / "responses.csv").is_file()
    assert owner(st / "analysis" / "table.csv") is None
    refuse_owned(tmp_path / "elsewhere.csv", "export --out")
    with pytest.raises(OwnedPathError, match="responses.csv"):
        # another study's export tables are not this command's to write
        other = make_demo_study(tmp_path / "other", videos=False)
        from flipstudy.study.export import export_responses
        export_responses(st, other / "responses.csv")


def test_a_symlink_into_a_study_is_the_studys_file(st, tmp_path, capsys):
    link = tmp_path / "innocent.csv"
    link.symlink_to(st / "sessions.sqlite")
    before = snapshot(st)
    assert cli(["export", str(st), "--out", str(link)]) == 1
    assert "the answer database of the study" in capsys.readouterr().err
    assert snapshot(st) == before
