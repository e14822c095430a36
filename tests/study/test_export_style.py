"""The character style travels from the design to the exported responses and
splits the analysis (design → stimuli → simulate → export → analyze)."""
import csv

import pandas as pd

from flipstudy.analysis.pipeline import analyze
from flipstudy.stimuli.design import parse_design
from flipstudy.stimuli.stimset import build_stimuli
from flipstudy.study.export import RESPONSE_COLUMNS, export_responses
from flipstudy.study.simulate import simulate

DESIGN = '''
[study]
name = "two-styles"
seed = 5
repetitions = 2
[[clips]]
name = "backflip"
source = "backflip"
[[groups]]
name = "smooth-increase"
kind = "angular-momentum"
profile = "smooth"
sign = 1
levels = [0, 25, 50]
original = "own"
{a}
[[groups]]
name = "abrupt-decrease"
kind = "angular-momentum"
profile = "abrupt"
sign = -1
levels = [0, 25, 50]
original = "own"
{b}
'''


def _study(tmp_path, a="", b="", study_style=None):
    """A study of the design (styles: group a, group b, the study), with four
    simulated participants' answers."""
    text = DESIGN.format(a=a, b=b)
    if study_style:
        text = text.replace("seed = 5", f'seed = 5\nstyle = "{study_style}"')
    d = tmp_path / "study"
    build_stimuli(parse_design(text), d, progress=False)
    (d / "design.toml").write_text(text)      # what `flipstudy stimuli` keeps beside the manifest
    simulate(d, 4, seed=2)
    return d


def test_export_carries_the_manifest_style_and_analysis_splits_by_it(tmp_path):
    d = _study(tmp_path, a='style = "stick"', b='style = "point-light"')
    res = export_responses(d, include_simulated=True)
    header = res.responses.read_text().splitlines()[0].split(",")
    k = header.index("kind")
    assert header[k + 1] == "style" and [c for c in header if c != "style"] == RESPONSE_COLUMNS
    rs = pd.read_csv(res.responses)
    with open(d / "manifest.csv", newline="") as f:
        man = {r["stimulus"]: r["style"] for r in csv.DictReader(f)}
    assert set(man.values()) == {"stick", "point-light"}
    # every row's style is its stimulus's manifest style (a join done here, not by the export)
    assert rs["style"].tolist() == [man[s] for s in rs["stimulus"]]
    assert set(rs.loc[rs["group"] == "smooth-increase", "style"]) == {"stick"}
    assert set(rs.loc[rs["group"] == "abrupt-decrease", "style"]) == {"point-light"}
    # the analysis reads the exported file and splits its table by style
    r = analyze(res.responses, None, psychometric="none", gee=False, n_boot=50,
                include_simulated=True)
    assert list(r.table.columns[:2]) == ["group", "style"]
    by = r.table.groupby("style")["group"].agg(set).to_dict()
    assert by == {"stick": {"smooth-increase"}, "point-light": {"abrupt-decrease"}}
    # the cells count the exported answers of their style
    n = r.table.groupby("style")["n"].sum().to_dict()
    assert n == rs.groupby("style").size().to_dict()
    assert any(nt.startswith("Character styles: point-light: abrupt-decrease; stick: smooth-increase")
               for nt in r.notes)
    import json
    desc = json.loads((d / "dataset_description.json").read_text())
    assert "style" in [v["name"] for v in desc["variableMeasured"]]


def test_export_without_a_style_has_no_style_column(tmp_path):
    d = _study(tmp_path)
    res = export_responses(d, include_simulated=True)
    header = res.responses.read_text().splitlines()[0].split(",")
    assert header == RESPONSE_COLUMNS
    r = analyze(res.responses, None, psychometric="none", gee=False, n_boot=50,
                include_simulated=True)
    assert "style" not in r.table.columns


def test_one_study_wide_style_is_exported_but_does_not_split(tmp_path):
    d = _study(tmp_path, study_style="mannequin")
    rs = pd.read_csv(export_responses(d, include_simulated=True).responses)
    assert set(rs["style"]) == {"mannequin"}
    r = analyze(d / "responses.csv", None, psychometric="none", gee=False, n_boot=50,
                include_simulated=True)
    assert "style" not in r.table.columns
