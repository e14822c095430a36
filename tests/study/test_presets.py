"""The ready designs (``flipstudy init --preset NAME``): each builds completely
(every stimulus within its tolerance), and a small copy (its first clip, level 0
and the largest level of each group) runs stimuli → render → simulate → export →
analyze."""
import re

import numpy as np
import pytest

from flipstudy.analysis.pipeline import analyze
from flipstudy.render.study import render_study
from flipstudy.stimuli.design import load_design, parse_design
from flipstudy.stimuli.presets import PRESETS
from flipstudy.stimuli.contract import StimulusSet
from flipstudy.stimuli.stimset import build_stimuli
from flipstudy.study.cli.motion import PRESET_NAMES
from flipstudy.study.export import export_responses
from flipstudy.study.simulate import ObserverModel, simulate

NEW = [n for n in PRESETS if n != "flipping-with-physics-2007"]


def test_the_cli_offers_every_preset():
    assert PRESET_NAMES == tuple(PRESETS)
    assert next(iter(PRESETS)) == "flipping-with-physics-2007"      # the default stays first


def small(text: str) -> str:
    """The preset with its first clip only, the first group of each kind and
    option (policy, axis, span) and of each style, and levels [0, largest]."""
    d = parse_design(text)
    first, *rest = [c.name for c in d.clips]
    for c in rest:
        text = text.replace(f'[[clips]]\nname = "{c}"\nsource = "{c}"\n\n', "")
    text = re.sub(r"\[reference\]\nclips = \[[^\]]*\]", f'[reference]\nclips = ["{first}"]', text)
    head, *groups = text.split("[[groups]]\n")
    seen, styles, keep = set(), set(), []
    for g in groups:
        key = tuple(re.findall(r'^(?:kind|profile|policy|axis|span) = .*$', g, re.M))
        style = tuple(re.findall(r'^style = .*$', g, re.M))
        if key not in seen or style not in styles:
            seen.add(key)
            styles.add(style)
            keep.append(g)
    text = head + "".join("[[groups]]\n" + g for g in keep)
    return re.sub(r"levels = \[([^\]]*)\]",
                  lambda m: f"levels = [0, {m.group(1).split(',')[-1].strip()}]", text)


# the two largest presets build in the slow run; the others keep the path in the default one
@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n.startswith("reitsma-") else n
                                  for n in NEW])
def test_preset_builds_and_runs_end_to_end(tmp_path, name):
    d = parse_design(PRESETS[name])
    rows = build_stimuli(d, tmp_path / "full", progress=False).rows
    assert [r["stimulus"] for r in rows] == d.stimulus_names()
    assert all(abs(float(r["measured_error_pct"]) - float(r["nominal_error_pct"])) <= d.tolerance_pct
               for r in rows)
    assert {r["kind"] for r in rows} - {"reference"} == {g.kind for g in d.groups}
    # the small copy through every stage
    path = tmp_path / "design.toml"
    path.write_text(small(PRESETS[name]))
    sd = load_design(path)
    study = tmp_path / "study"
    build_stimuli(sd, study, progress=False)
    rec = render_study(study, size=(32, 24), jobs=1, fps=10, progress=False)
    assert len(rec.record.stimuli) == len(StimulusSet.read(study, files=False, design=False).rows())
    model = ObserverModel({g.name: (np.array([0.0, max(g.levels)]), np.array([0.9, 0.1]))
                           for g in sd.groups}, sigma=0.1, source="test")
    assert simulate(study, 3, model=model, seed=1) == ["sim001", "sim002", "sim003"]
    exp = export_responses(study, include_simulated=True)
    res = analyze(exp.responses, tmp_path / "analysis", include_simulated=True, n_boot=50,
                  psychometric="none", gee=False, figures=False)
    tab = res.table
    assert set(tab["group"]) == {g.name for g in sd.groups}
    # the simulated observers answer "incorrect" more often at the largest level
    for g in sd.groups:
        sub = tab[tab["group"] == g.name].set_index("level")
        assert sub.loc[max(g.levels), "dprime"] > 0 and np.isfinite(sub.loc[max(g.levels), "dprime"])
    assert (tmp_path / "analysis" / "table.csv").exists()


def test_init_writes_a_preset(tmp_path, capsys):
    from flipstudy.study.cli import main
    out = tmp_path / "g.toml"
    assert main(["init", str(out), "--preset", "gravity"]) == 0
    assert out.read_text() == PRESETS["gravity"]
    assert "preset gravity" in capsys.readouterr().out
    assert main(["init", str(tmp_path / "d.toml")]) == 0
    assert (tmp_path / "d.toml").read_text() == PRESETS["flipping-with-physics-2007"]
    with pytest.raises(SystemExit):
        main(["init", str(tmp_path / "x.toml"), "--preset", "moon"])
