"""Issue 45 item 14 and the calibration tracebacks: a calibration file is read only
when every number is in its range (λ = 2 gave "P(anything noticed) = 0.0 %", NaN
samples "= - [-, -]", exit 0), and a file that is not UTF-8, is nested too deeply
or has ``sources`` that are not objects is one line naming file and field."""
from __future__ import annotations

import copy
import json

import pytest

from flipstudy.errors import CalibrationError
from flipstudy.stimuli.calibration import Calibration, default_calibration
from flipstudy.study.cli import main


def good() -> dict:
    return copy.deepcopy(default_calibration().to_dict())


def _set(path, value):
    def edit(d):
        node = d
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
        return d
    return edit


CASES = {
    "lambda = 2": (_set(["functions", 0, "params", "lambda"], 2.0), r"functions\[0\]\.params\.lambda: expected a rate in \[0, 1\), got 2\.0"),
    "gamma negative": (_set(["functions", 0, "params", "gamma"], -0.1), r"functions\[0\]\.params\.gamma: expected a rate"),
    "gamma + lambda = 1": (lambda d: (_set(["functions", 0, "params", "gamma"], 0.6)(d),
                                      _set(["functions", 0, "params", "lambda"], 0.4)(d))[0],
                           r"functions\[0\]\.params: expected gamma \+ lambda < 1"),
    "width 0": (_set(["functions", 0, "params", "width"], 0.0), r"params\.width: expected a positive width"),
    "threshold infinite": (_set(["functions", 0, "params", "threshold"], float("inf")), r"params\.threshold: expected a finite number"),
    "a NaN sample": (lambda d: (d["functions"][0]["samples"]["threshold"].__setitem__(3, float("nan")), d)[1],
                     r"functions\[0\]\.samples\.threshold\[3\]: expected finite numbers, got nan"),
    "a sample lambda of 1.5": (lambda d: (d["functions"][1]["samples"]["lambda"].__setitem__(0, 1.5), d)[1],
                               r"functions\[1\]\.samples\.lambda\[0\]: expected finite numbers in \[0, 1\)"),
    "k above n": (lambda d: (d["functions"][0]["data"]["k"].__setitem__(0, 1e6), d)[1], r"functions\[0\]\.data: expected"),
    "threshold a string": (_set(["functions", 0, "threshold"], "low"), r"functions\[0\]\.threshold: expected a finite number or null"),
    "sources entry not an object": (_set(["sources"], ["FwP 2007"]), r"c\.json: sources\[0\]: expected a list of objects"),
    "functions an object": (_set(["functions"], {"a": 1}), r"c\.json: functions: expected a list of objects"),
    "sign infinite": (_set(["functions", 0, "sign"], float("inf")), r"functions\[0\]: OverflowError"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_an_impossible_calibration_is_refused_naming_the_field(case, tmp_path):
    edit, expect = CASES[case]
    p = tmp_path / "c.json"
    p.write_text(json.dumps(edit(good())))
    with pytest.raises(CalibrationError, match=expect) as e:
        Calibration.load(p)
    assert "\n" not in str(e.value) and "c.json" in str(e.value)


@pytest.mark.parametrize("raw, expect", [
    (b'{"format": "flipstudy-calibration/1", "description": "\xff\xfe"}', r"c\.json: not UTF-8 text"),
    (b"[" * 100_000 + b"]" * 100_000, r"c\.json: not a calibration file \(JSON nested too deeply\)"),
])
def test_a_file_that_is_not_utf8_json_is_one_line(raw, expect, tmp_path):
    (tmp_path / "c.json").write_bytes(raw)
    with pytest.raises(CalibrationError, match=expect):
        Calibration.load(tmp_path / "c.json")


def test_score_with_lambda_2_exits_with_one_line_instead_of_a_probability(tmp_path, capsys):
    """The CLI: ``score --calibration`` of the file above (before: exit 0, 0.0 %)."""
    p = tmp_path / "c.json"
    d = good()
    for f in d["functions"]:
        f["params"]["lambda"] = 2.0
    p.write_text(json.dumps(d))
    assert main(["score", "backflip", "--calibration", str(p)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "c.json: functions[0].params.lambda" in err


def test_the_shipped_calibration_is_in_range():
    assert len(default_calibration().functions) > 0
