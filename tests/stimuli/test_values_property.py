"""Issue 28's "Done when" property: over every design key and every style key, a
value drawn from valid, boundary and hostile ones (nan, inf, huge, tiny, negative,
the wrong type), the build of one stimulus of a built-in clip (and, for a style, a
render of it at 160x120) ends within 60 s with a study or a ``FlipstudyError``
whose message names the file and the field, never another exception.

Each example runs in a child process (60 s, 2 GB of address space), so a value
that hangs or eats memory fails the example instead of the machine.  The default
run draws a handful of examples; ``-m slow`` runs many.
"""
import json
import os
import re
import subprocess
import sys

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flipstudy.render.style import STYLE_RANGES
from flipstudy.stimuli.design import (CLIP_KEYS, GROUP_KEYS, REFERENCE_KEYS, SESSION_KEYS, STUDY_KEYS,
                                      _toml_value)

TIMEOUT_S = 60
FIELD = re.compile(r"\[(study|session|reference)\]|\[\[(clips|groups)\]\]|(clips|groups)\[\d+\]|clips '")
HOSTILE = [float("nan"), float("inf"), float("-inf"), 1e308, -1e308, 1e-308, -1, 0, 0.0, -0.0,
           2 ** 63 - 1, -(2 ** 63), 1e-9, 99.99, 100, 500, 1000, 1e12, "", "x", "notacolor",
           "a" * 5000, True, False, [], [1], [3000, 3000], [0, 1e-9], ["a", "b"], {"a": 1},
           {"from": 0, "to": 100, "step": 1e-308}]
#: plausible values of each design key (valid or at a bound)
VALID = {"name": ["s", "g2"], "seed": [0, 7, 2 ** 63 - 1], "fps": [10, 60, 1000, 119.5],
         "repetitions": [1, 20], "total_mass": [20, 200, 70.5], "com_policy": ["angle", "landing"],
         "tolerance_pct": [50, 1e-6], "original": ["shared", "per-group", "own"],
         "style": ["stick", "point-light", "capsules"], "task": ["2afc", "yes-no"],
         "replay": [True], "break_every": [1, 10000], "max_dropped_pct": [0, 100],
         "repeat_dropped": [True], "source": ["backflip", "frontflip", "nofile.bvh"],
         "scale": [1e-4, 100, 0.01], "flips": [1, 2, 6], "k_ratio": [0.2, 2],
         "accept_unphysical": [True], "kind": ["angular-momentum", "gravity", "pose-rate",
                                              "time-scale", "acceleration", "vertical-velocity"],
         "profile": ["smooth", "abrupt"], "sign": [1, -1],
         "levels": [[0, 20], [99.99], [499.99], [89.99], [1e-9], [300], {"from": 0, "to": 40, "step": 10}],
         "method": ["quest+", "constant"], "policy": ["takeoff-velocity", "apex-height", "flight-time"],
         "axis": ["horizontal", "vertical"], "span": ["flight", "whole"], "trials": [1, 1000],
         "stop_width": [1e-9, 1000], "threshold_prior": [[0, 40], [10, 20]],
         "width_prior": [[0.1, 1000], [5, 60]], "lapse": [0, 0.1999], "clips": [["c"], ["c", "c"], []]}

DESIGN_KEYS = ([("study", k) for k in STUDY_KEYS] + [("session", k) for k in SESSION_KEYS]
               + [("clips", k) for k in CLIP_KEYS] + [("groups", k) for k in GROUP_KEYS]
               + [("reference", k) for k in REFERENCE_KEYS])
#: a group each key means something in (its kind's option, quest+ for the quest keys)
GROUP_FOR = {"profile": {"kind": "angular-momentum", "profile": "smooth", "levels": [20]},
             "policy": {"kind": "gravity", "policy": "takeoff-velocity", "levels": [20]},
             "axis": {"kind": "acceleration", "axis": "vertical", "levels": [20]},
             "span": {"kind": "time-scale", "span": "flight", "levels": [20]}}
QUEST = {"kind": "takeoff-angle", "method": "quest+", "levels": {"from": 0, "to": 40, "step": 20}}

RUN = r"""
import json, resource, sys, warnings
resource.setrlimit(resource.RLIMIT_AS, (2_000_000_000,) * 2)
warnings.simplefilter("ignore")
kind, src, out = sys.argv[1], sys.argv[2], sys.argv[3]
try:
    from flipstudy.errors import FlipstudyError
    if kind == "design":
        from flipstudy.stimuli.design import load_design
        from flipstudy.stimuli.stimset import build_stimuli
        rows = build_stimuli(load_design(src), out, progress=False).rows
        print(json.dumps({"ok": len(rows)}))
    else:
        from flipstudy import builtin
        from flipstudy.render.figures import ghost_image, trail_image
        from flipstudy.render.staging import stage
        from flipstudy.render.style import Style
        st = stage([builtin("jump")], size=(160, 120), style=Style.from_toml(src))
        ghost_image(st, None)
        trail_image(st, None)
        print(json.dumps({"ok": 1}))
except BaseException as e:
    print(json.dumps({"ok": 0, "type": type(e).__name__, "flipstudy": isinstance(e, FlipstudyError),
                      "message": str(e)}))
"""


def run_child(kind: str, src, out) -> dict:
    try:
        r = subprocess.run([sys.executable, "-c", RUN, kind, str(src), str(out)], capture_output=True,
                           text=True, timeout=TIMEOUT_S, env={**os.environ, "OMP_NUM_THREADS": "1"})
    except subprocess.TimeoutExpired:
        pytest.fail(f"{src}: not done in {TIMEOUT_S} s:\n{open(src).read()}")
    lines = [ln for ln in r.stdout.splitlines() if ln.startswith("{")]
    assert lines, f"the child died ({r.returncode}): {r.stderr[-3000:]}\n{open(src).read()}"
    return json.loads(lines[-1])


def value_for(key: str):
    return st.one_of(st.sampled_from(VALID.get(key, [1])), st.sampled_from(HOSTILE),
                     st.floats(allow_nan=True, allow_infinity=True), st.integers(-2 ** 63, 2 ** 63 - 1),
                     st.text(max_size=12))


@st.composite
def design_cases(draw):
    section, key = draw(st.sampled_from(DESIGN_KEYS))
    value = draw(value_for(key))
    study = {"name": "prop", "seed": 1}
    clip = {"name": "c", "source": "jump"}
    group = dict(QUEST if key in ("method", "trials", "stop_width", "threshold_prior", "width_prior", "lapse")
                 else GROUP_FOR.get(key, {"kind": "takeoff-angle", "levels": [20]}))
    group = {"name": "g", **group}
    tables = {"study": study, "session": {}, "clips": clip, "groups": group, "reference": {}}
    tables[section][key] = value
    return section, key, value, tables


def design_text(tables) -> str:
    out = []
    for section in ("study", "session", "clips", "groups", "reference"):
        t = tables[section]
        if not t:
            continue
        out.append(f"[[{section}]]" if section in ("clips", "groups") else f"[{section}]")
        out += [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in t.items()]
    return "\n".join(out) + "\n"


def check_design(tmp_path, case):
    section, key, value, tables = case
    p = tmp_path / "design.toml"
    p.write_text(design_text(tables))
    out = tmp_path / "out"
    res = run_child("design", p, out)
    if res["ok"]:
        assert (out / "manifest.csv").exists()
        return
    msg = res["message"]
    assert res["flipstudy"], f"{res['type']}: {msg}\n{p.read_text()}"
    assert str(p) in msg, f"no file named: {msg}\n{p.read_text()}"
    # the drawn key, or the section and field the error lies in (a key can make another
    # field wrong: [study] task = "2afc" asks the group's levels for a 0)
    assert key in msg or FIELD.search(msg), f"no field named: {msg}\n{p.read_text()}"
    assert not out.exists()


def style_cases():
    return st.sampled_from(sorted(STYLE_RANGES)).flatmap(
        lambda k: st.tuples(st.just(k), st.one_of(st.sampled_from(HOSTILE), st.floats(),
                                                  st.integers(-10 ** 6, 10 ** 6), st.text(max_size=8),
                                                  st.lists(st.floats(0, 300), max_size=4))))


def check_style(tmp_path, case):
    key, value = case
    p = tmp_path / "style.toml"
    p.write_text(f"[style]\n{json.dumps(key)} = {_toml_value(value)}\n")
    res = run_child("style", p, tmp_path)
    if res["ok"]:
        return
    msg = res["message"]
    assert res["flipstudy"], f"{res['type']}: {msg}\n{p.read_text()}"
    assert msg.startswith(f"{p}: [style] {key}"), msg


FAST = settings(max_examples=3, deadline=None, suppress_health_check=list(HealthCheck))
SLOW = settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))


@FAST
@given(case=design_cases())
def test_every_design_key_ends_in_a_study_or_an_error_naming_file_and_field(tmp_path_factory, case):
    check_design(tmp_path_factory.mktemp("d"), case)


@FAST
@given(case=style_cases())
def test_every_style_key_ends_in_a_render_or_an_error_naming_file_and_key(tmp_path_factory, case):
    check_style(tmp_path_factory.mktemp("s"), case)


@pytest.mark.slow
@SLOW
@given(case=design_cases())
def test_every_design_key_many_values(tmp_path_factory, case):
    check_design(tmp_path_factory.mktemp("d"), case)


@pytest.mark.slow
@SLOW
@given(case=style_cases())
def test_every_style_key_many_values(tmp_path_factory, case):
    check_style(tmp_path_factory.mktemp("s"), case)


@pytest.mark.parametrize("section, key", DESIGN_KEYS)
def test_every_design_key_refuses_nan_naming_file_and_field(tmp_path, section, key):
    """Every key once, with nan (a number nowhere valid): refused when read, the file
    and the key or its section named; a build of the rest cannot start."""
    tables = {"study": {"name": "prop", "seed": 1}, "session": {}, "clips": {"name": "c", "source": "jump"},
              "groups": {"name": "g", "kind": "takeoff-angle", "levels": [20]}, "reference": {}}
    tables[section][key] = float("nan")
    p = tmp_path / "design.toml"
    p.write_text(design_text(tables))
    from flipstudy.errors import FlipstudyError
    from flipstudy.stimuli.design import load_design
    with pytest.raises(FlipstudyError) as e:
        load_design(p)
    msg = str(e.value)
    assert str(p) in msg and (re.search(rf"\b{re.escape(key)}\b", msg) or section in msg), msg
