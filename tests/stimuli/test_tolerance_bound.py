"""``[study] tolerance_pct``: the least tolerance a design may ask is the measurement's
own precision; below it even an exact built-in stimulus is refused, and the design
check says so naming the field (hypothesis found 2.2e-48 accepted, then every
stimulus refused with a message that named no field)."""
from __future__ import annotations

import pytest

from flipstudy.errors import FlipstudyError
from flipstudy.stimuli.design import TOLERANCE_MIN, parse_design
from flipstudy.stimuli.stimset import build_stimuli

DESIGN = """
[study]
name = "tol"
seed = 1
tolerance_pct = {tol}

[[clips]]
name = "c"
source = "jump"

[[groups]]
name = "g"
kind = "{kind}"
{extra}levels = [20]
"""


@pytest.mark.parametrize("tol", [2.2e-48, 1e-9, 0.0, -1.0])
def test_a_tolerance_below_the_measurements_precision_is_refused_naming_the_field(tol):
    with pytest.raises(FlipstudyError, match=r"\[study\].*tolerance_pct|tolerance_pct"):
        parse_design(DESIGN.format(tol=tol, kind="takeoff-angle", extra=""))


@pytest.mark.parametrize("kind,extra", [("takeoff-angle", ""), ("gravity", 'policy = "flight-time"\n')])
def test_exact_builtin_stimuli_pass_the_least_tolerance(tmp_path, kind, extra):
    res = build_stimuli(parse_design(DESIGN.format(tol=TOLERANCE_MIN, kind=kind, extra=extra)), tmp_path / "s",
                        progress=False)
    row = [r for r in res.rows if r["group"] == "g"][0]
    assert abs(float(row["measured_error_pct"]) - 20.0) <= TOLERANCE_MIN
