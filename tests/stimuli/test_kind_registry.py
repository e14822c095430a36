"""The error-kind registry (flipstudy.vocab.kinds): a new kind is one module and one
entry.  This module is that module: it registers a toy kind and shows it accepted by
design validation, built into stimuli, measured and listed by ``score``, and drawn in
the documentation's format table, with no other file edited."""
from __future__ import annotations

import dataclasses
import importlib.util
from pathlib import Path

import pytest

from flipstudy.errors import DesignError
from flipstudy.vocab import kinds
from flipstudy.vocab.design import load_design, parse_design

TOY = "toy-push"
EXT = Path(__file__).resolve().parents[2] / "docs" / "_ext" / "flipstudy_formats.py"


def build_toy(a, group, level, design):
    """The toy's injector: a take-off angle change under its own name."""
    from flipstudy.stimuli.injection import inject_takeoff_angle
    return dataclasses.replace(inject_takeoff_angle(a, group.sign * level / 100.0), kind=TOY)


def measure_toy(clip, analysis, add):
    """The toy's measure of a motion: one item over the whole clip (1.5 %)."""
    add(TOY, "", "clip", 1.5, 0.0, (clip.num_frames - 1) / clip.fps, 0.0)


ENTRY = kinds.ErrorKind(
    TOY, unit="%", bounds={1: (50.0, False), -1: (50.0, True)},
    inject=f"{__name__}:build_toy", check_measure="flipstudy.stimuli.injection:measure",
    measure=f"{__name__}:measure_toy", quantity=("horizontal take-off velocity change", "%"),
    side_effects=("none (a test)",), doc="a toy kind registered by a test")

DESIGN = f"""[study]
name = "toy"
seed = 3
repetitions = 1
[[clips]]
name = "backflip"
source = "backflip"
[[groups]]
name = "push"
kind = "{TOY}"
levels = [0, LEVEL]
"""


@pytest.fixture
def toy():
    kinds.register(ENTRY)
    try:
        yield ENTRY
    finally:
        kinds.unregister(TOY)


def test_a_toy_kind_is_accepted_built_measured_scored_and_documented(toy, tmp_path):
    # design validation reads the registry: the toy's bounds hold
    f = tmp_path / "toy.toml"
    f.write_text(DESIGN.replace("LEVEL", "20"))
    d = load_design(f)
    assert d.groups[0].kind == TOY and d.groups[0].levels == (0.0, 20.0)
    with pytest.raises(DesignError, match=r"toy.toml: groups\[0\] \(push\)\.levels: 60 %"):
        parse_design(DESIGN.replace("LEVEL", "60"), "toy.toml")
    # stimulus building: the registry's injector, checked by the registry's measure
    from flipstudy.stimuli.stimset import build_stimuli
    rows = {r["stimulus"]: r for r in build_stimuli(d, tmp_path / "s", progress=False).rows}
    row = rows["backflip_push_20"]
    assert row["kind"] == TOY and row["measured_error_pct"] == pytest.approx(20.0, abs=1.0)
    # the measure and the score: measured, listed, not scored (no calibration)
    from flipstudy import builtin
    from flipstudy.stimuli.score import score
    clip = score(builtin("backflip")).clips[0]
    toy_items = [e for e in clip.errors if e.kind == TOY]
    assert [(e.size, e.unit, e.scored) for e in toy_items] == [(1.5, "%", False)]
    assert TOY in clip.note
    # the docs' format table
    pytest.importorskip("docutils", reason="the docs extra (sphinx, docutils) is not installed")
    spec = importlib.util.spec_from_file_location("flipstudy_formats", EXT)
    formats = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(formats)
    rows = {r[0].strip("`"): r for r in formats._rows("error-kinds")}
    assert rows[TOY][1] == "a toy kind registered by a test" and rows[TOY][2].startswith("+50 %")


def test_unregistered_the_toy_is_refused_by_name():
    with pytest.raises(DesignError, match=f"kind: .*must be one of"):
        parse_design(DESIGN.replace("LEVEL", "20"), "toy.toml")


def test_every_kind_is_declared_once_with_its_unit_and_the_design_reads_it():
    from flipstudy.stimuli import measure
    from flipstudy.vocab import design
    names = [k.name for k in kinds.all_kinds()]
    assert len(names) == len(set(names))
    assert {"angular-momentum", "takeoff-angle", "gravity", "horizontal-velocity", "vertical-velocity",
            "acceleration", "time-scale", "pose-rate", "foot-skate", "penetration", "floating",
            "takeoff-velocity-jump", "landing-velocity-jump"} <= set(names)
    assert {k: measure.UNITS[k] for k in names} == kinds.measured_units()
    assert {ks: design.LEVEL_BOUNDS[ks] for ks in kinds.level_bounds()} == kinds.level_bounds()
    assert all(k.injected == (k.family != "measured") for k in kinds.all_kinds())
    with pytest.raises(Exception, match="already registered"):
        kinds.register(dataclasses.replace(kinds.AM, unit="mm"))


def test_the_declared_calibration_sources_are_the_shipped_ones():
    """A kind that declares the FwP Table 2 source has functions in the shipped default
    calibration, and only those kinds have."""
    from flipstudy.vocab.calibration import default_calibration
    shipped = {f.kind for f in default_calibration().functions}
    assert shipped == {k.name for k in kinds.all_kinds() if kinds.FWP_TABLE2 in k.calibration}
