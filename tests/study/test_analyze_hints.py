"""`flipstudy analyze` on a study without answers names commands that work (issue 42):
none yet → run or simulate; only simulated ones → --include-simulated."""
import re

import pytest

from flipstudy.study.cli import main
from flipstudy.study.demo import make_demo_study

FAST = ["--psychometric", "none", "--no-gee", "--no-figures", "--n-boot", "50"]


@pytest.fixture
def study(tmp_path):
    return make_demo_study(tmp_path / "s", videos=False)


def _error(capsys, argv):
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    return err


def test_no_sessions_yet_suggests_run_or_simulate_and_the_pilot_commands_work(study, capsys):
    err = _error(capsys, ["analyze", str(study)])
    assert "no sessions yet" in err and f"flipstudy run {study}" in err
    pilot = re.findall(r"`flipstudy ([^`]*)`", err.split("pilot it with", 1)[1])
    assert [c.split()[0] for c in pilot] == ["simulate", "export", "analyze"]
    for cmd in pilot:                               # the suggested pilot runs as written
        extra = FAST if cmd.startswith("analyze") else []
        assert main(cmd.split() + extra) == 0, cmd


def test_only_simulated_answers_name_include_simulated(study, capsys):
    assert main(["simulate", str(study), "--participants", "2"]) == 0
    err = _error(capsys, ["analyze", str(study)])
    assert f"flipstudy export {study} --include-simulated" in err
    assert main(["export", str(study)]) == 0         # writes a table without a row
    err = _error(capsys, ["analyze", str(study)])
    assert "holds no answers" in err and "--include-simulated" in err
    assert f"flipstudy analyze {study} --include-simulated" in err
