"""The pipeline's typed steps: each returns a frozen result that round-trips through
JSON, and the CLI prints exactly its ``summary()``."""
from __future__ import annotations

import dataclasses
import json
import math
import typing
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flipstudy import results
from flipstudy.errors import FlipstudyError
from flipstudy.records import Record, ReproduceFiles, StageSeconds, Threshold
from flipstudy.results import (AnalyzeResult, BuildResult, CompareResult, MotionResult, ExportResult, ImportResult,
                               PlanResult, RenderResult, ReproduceResult, SimulateResult, StatusResult,
                               StepResult)
from flipstudy.study import pipeline
from flipstudy.study.cli import main
from flipstudy.study.demo import make_demo_study

RESULTS = [BuildResult, RenderResult, SimulateResult, ExportResult, ImportResult, AnalyzeResult,
           ReproduceResult, StatusResult, PlanResult, MotionResult, CompareResult]

# ---- strategies: any value of a field's declared type that JSON can carry
text = st.text(st.characters(blacklist_categories=("Cs",)), max_size=12)
paths = st.lists(st.text("abcxyz_-.", min_size=1, max_size=6).filter(lambda s: s not in (".", "..")),
                 min_size=1, max_size=3).map(lambda parts: Path(*parts))
json_leaf = st.none() | st.booleans() | st.integers(-10**6, 10**6) | \
    st.floats(allow_nan=False, allow_infinity=False) | text
json_doc = st.recursive(json_leaf, lambda inner: st.lists(inner, max_size=3)
                        | st.dictionaries(text, inner, max_size=3), max_leaves=8)


def strategy(hint):
    origin = typing.get_origin(hint)
    if hint is Path:
        return paths
    if hint is str:
        return text
    if hint is int:
        return st.integers(0, 10**6)
    if hint is float:
        return st.floats(-1e6, 1e6, allow_nan=False)
    if hint is dict:
        return st.dictionaries(text, json_doc, max_size=4)
    if hint is bool:
        return st.booleans()
    if hint is object:                        # any JSON value
        return json_doc
    if isinstance(hint, type) and issubclass(hint, Record):
        return records_of(hint)
    if origin in (typing.Union, getattr(__import__("types"), "UnionType")):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        return st.none() | strategy(args[0])
    if origin is tuple:
        args = typing.get_args(hint)
        if len(args) == 2 and args[1] is Ellipsis:
            return st.lists(strategy(args[0]), max_size=4).map(tuple)
        return st.tuples(*(strategy(a) for a in args))
    if origin is dict:
        k, v = typing.get_args(hint)
        return st.dictionaries(strategy(k), strategy(v), max_size=4)
    raise AssertionError(f"no strategy for {hint}")


def records_of(cls):
    """Any record of ``cls``, its open columns (``extra``) named unlike its fields."""
    hints = typing.get_type_hints(cls)
    declared = {f.name for f in dataclasses.fields(cls)} - {"extra"}
    kw = {n: strategy(hints[n]) for n in declared}
    if "extra" in hints:
        kw["extra"] = st.dictionaries(text.filter(lambda k: k not in declared), json_doc, max_size=3)
    return st.builds(cls, **kw)


def instances(cls):
    hints = typing.get_type_hints(cls)
    return st.builds(cls, **{f.name: strategy(hints[f.name]) for f in dataclasses.fields(cls)})


@pytest.mark.parametrize("cls", RESULTS, ids=lambda c: c.__name__)
@settings(max_examples=30, deadline=None)
@given(data=st.data())
def test_every_result_round_trips_through_json(cls, data, tmp_path_factory):
    r = data.draw(instances(cls))
    path = tmp_path_factory.mktemp("rt") / "r.json"
    back = cls.load_json(r.save_json(path))
    assert back == r
    assert type(back) is cls
    assert json.loads(path.read_text()) == r.to_dict()
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(r, dataclasses.fields(cls)[0].name, None)


def test_results_module_lists_every_step():
    assert set(results.__all__) == {c.__name__ for c in RESULTS} | {"StepResult"}
    for cls in RESULTS:
        assert issubclass(cls, StepResult) and cls.summary is not StepResult.summary, cls


def test_a_file_that_is_not_a_saved_result_is_refused(tmp_path):
    p = tmp_path / "x.json"
    p.write_text("[1, 2]")
    with pytest.raises(FlipstudyError, match="x.json: not a saved ExportResult"):
        ExportResult.load_json(p)
    p.write_text("{")
    with pytest.raises(FlipstudyError, match="x.json"):
        ExportResult.load_json(p)
    with pytest.raises(FlipstudyError, match="unknown field"):
        SimulateResult.from_dict({"study": "s", "participants": [], "colour": 1})


def test_the_steps_that_returned_dicts_return_results():
    """``build_stimuli``, ``render_study``, ``export_responses``, ``import_web`` and
    ``reproduce`` are annotated with (and, below, return) their result types."""
    from flipstudy.render.study import render_study
    from flipstudy.stimuli.stimset import build_stimuli
    from flipstudy.study.export import export_responses
    from flipstudy.study.reproduce import reproduce
    from flipstudy.study.web.importer import import_web
    for fn, cls in [(build_stimuli, "BuildResult"), (render_study, "RenderResult"),
                    (export_responses, "ExportResult"), (import_web, "ImportResult"),
                    (reproduce, "ReproduceResult")]:
        assert fn.__annotations__["return"] == cls, fn.__name__
    for name in pipeline.__all__[:7]:
        assert getattr(pipeline, name).__annotations__["return"].endswith("Result"), name


def _run(capsys, argv):
    status = main(argv)
    captured = capsys.readouterr()
    return status, captured.out


def test_simulate_export_analyze_print_their_results_summaries(tmp_path, capsys):
    """On a real (placeholder) study: the CLI's output is the step's ``summary()``, and the
    saved results load back equal."""
    study = make_demo_study(tmp_path / "cli", videos=False)
    twin = make_demo_study(tmp_path / "lib", videos=False)
    status, out = _run(capsys, ["simulate", str(study), "--participants", "3", "--seed", "2"])
    assert status == 0
    sim = pipeline.simulate(twin, 3, seed=2)
    assert out == sim.summary().replace(str(twin), str(study)) + "\n"
    assert sim.participants == ("sim001", "sim002", "sim003")

    status, out = _run(capsys, ["export", str(study), "--include-simulated"])
    assert status == 0
    exp = pipeline.export(twin, include_simulated=True)
    assert out == exp.summary().replace(str(twin), str(study)) + "\n"
    assert exp.rows == 3 * 8 and exp.simulated == sim.participants and exp.real == ()
    rows = (twin / "responses.csv").read_text().splitlines()
    assert len(rows) == 1 + exp.rows                  # what the result says is what is on disk

    opts = ["--psychometric", "none", "--no-gee", "--no-figures", "--n-boot", "50", "--include-simulated"]
    status, out = _run(capsys, ["analyze", str(study), *opts])
    assert status == 0
    ana = pipeline.analyze(twin, psychometric="none", gee=False, figures=False, n_boot=50,
                           include_simulated=True)
    assert out == ana.summary().replace(str(twin), str(study)) + "\n"
    assert ana.out == twin / "analysis" and (ana.out / "table.csv").is_file()
    assert ana.report.settings.n_trials == exp.rows
    back = AnalyzeResult.load_json(ana.save_json(tmp_path / "analyze.json"))
    assert back.summary() == ana.summary()

    status, out = _run(capsys, ["analyze", str(study), *opts, "--json"])
    assert json.loads(out)["settings"]["n_trials"] == exp.rows


def test_reproduce_summary_matches_the_counts_it_states():
    """A ReproduceResult's summary states its counts and files (thresholds of None shown
    as not reached)."""
    files = ReproduceFiles(**{f.name: f"p/{f.name}" for f in dataclasses.fields(ReproduceFiles)})
    r = ReproduceResult(out="p", files=files, seconds=StageSeconds(*[1.0] * 6), n_stimuli=46,
                        worst_gap_pct=0.25, n_videos=46, n_responses=88, n_simulated=1, table_md="| t |",
                        thresholds=(Threshold("g", reached=False), Threshold("h", True, 12.34)))
    s = r.summary()
    assert "p/manifest  46 stimuli" in s and "(largest gap 0.25 points)" in s
    assert "  g                  not reached within the tested levels" in s
    assert "  h                  12.3 %" in s
    assert not math.isnan(ReproduceResult.from_dict(json.loads(json.dumps(r.to_dict()))).worst_gap_pct)


def test_every_cli_command_body_is_short():
    """Parse, one library call, print the result's summary: no command body over 25 lines."""
    import ast
    cli = Path(pipeline.__file__).parent / "cli"
    long = []
    for p in sorted(cli.glob("*.py")):
        for node in ast.parse(p.read_text()).body:
            if isinstance(node, ast.FunctionDef) and (node.name.startswith("cmd_") or node.name == "handler"):
                n = node.end_lineno - node.lineno + 1
                if n > 25:
                    long.append(f"{p.name}: {node.name} has {n} lines")
    assert not long, "\n".join(long)


#: fields still holding JSON documents, and why: a build's rows are the manifest's
#: CSV rows (column → text; the typed stimulus is flipstudy.stimuli.contract.Stimulus),
#: and a motion command's report is the method's own report, different per command
OPEN_FIELDS = {("BuildResult", "rows"), ("MotionResult", "report")}


def _holds_dict(hint) -> bool:
    if hint is dict or typing.get_origin(hint) is dict:
        return True
    return any(_holds_dict(a) for a in typing.get_args(hint))


def test_no_result_is_indexed_like_a_dict():
    """No class of flipstudy.results defines ``__getitem__`` (results are read by
    attribute), and each step result's fields hold typed records, not dicts."""
    classes = [c for c in vars(results).values() if isinstance(c, type) and c.__module__ == results.__name__]
    assert {c.__name__ for c in classes} >= {c.__name__ for c in RESULTS}
    assert [c.__name__ for c in classes if "__getitem__" in vars(c)] == []
    for cls in RESULTS:
        assert not hasattr(cls, "__getitem__"), cls            # not inherited either
        hints = typing.get_type_hints(cls)
        dicts = [f.name for f in dataclasses.fields(cls) if _holds_dict(hints[f.name])
                 and (cls.__name__, f.name) not in OPEN_FIELDS]
        assert dicts == [], f"{cls.__name__} holds dicts in {dicts}"


def test_every_summary_follows_one_convention():
    """``summary()``: no arguments, text without a trailing newline (what the command prints)."""
    import inspect
    for cls in RESULTS:
        sig = inspect.signature(cls.summary)
        assert list(sig.parameters) == ["self"] and sig.return_annotation in (str, "str"), cls


def test_records_read_back_the_json_the_steps_wrote_key_for_key(tmp_path):
    """A record read from a step's JSON object writes it back with the same keys in
    the same order (so ``--json`` output is unchanged), open columns included."""
    from flipstudy.records import AnalyzeReport, SessionStatus
    doc = {"settings": {"correction": "loglinear", "n_boot": 50,
                        "participants": {"n": 1, "real": ["P01"], "marked": {"simulated": True}},
                        "participants_label": "N = 1", "n_trials": 8, "groups": ["g"]},
           "table": [{"group": "g", "level": 0.0, "n": 8, "dprime": None}],
           "thresholds": [{"group": "g", "method": "none", "threshold": None, "reached": False}],
           "flow": [{"stage": "recruited", "n": 1}], "notes": ["a"], "files": {"t": "x/t.csv"}}
    rep = AnalyzeReport.from_dict(doc)
    assert rep.settings.participants.real == ("P01",) and rep.table[0].extra["n"] == 8
    assert json.dumps(rep.to_dict()) == json.dumps(doc)
    r = AnalyzeResult(out=tmp_path, report=rep, table_markdown="| t |")
    assert AnalyzeResult.load_json(r.save_json(tmp_path / "a.json")).report.to_dict() == doc
    with pytest.raises(FlipstudyError, match="SessionStatus: unknown field"):
        SessionStatus.from_dict({"participant": "P", "colour": 1})


def test_the_results_and_their_records_import_none_of_the_four_parts():
    """Like flipstudy.errors, the root modules results.py and records.py sit below the
    parts: every part can return its step's result."""
    import ast
    root = Path(results.__file__).parent
    for name in ("results.py", "records.py"):
        tree = ast.parse((root / name).read_text())
        mods = [n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
        mods += [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
        parts = [m for m in mods if m.removeprefix("flipstudy.").split(".")[0]
                 in ("stimuli", "render", "study", "analysis")]
        assert parts == [], f"{name} imports {parts}"
