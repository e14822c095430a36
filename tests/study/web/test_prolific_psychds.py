"""Issue 32, item 7: `export` and `import-web` write a Psych-DS dataset: data files under
data/, keyword names with the _data.csv suffix, every column in variableMeasured, and
the design's exclusion rules in the metadata."""
import csv
import json
import re

import pytest

from _prolific import CATCH_GROUP, web_records, write_jsonl

from flipstudy.study.demo import make_demo_study
from flipstudy.study.export import export_responses
from flipstudy.study.owned import owner
from flipstudy.study.session import load_study, open_session, submit_answer
from flipstudy.study.web.importer import import_web

# Psych-DS: keyword-value pairs (lowercase keyword, alphanumeric value) joined by "_", then _data.csv
PSYCHDS_NAME = re.compile(r"([a-z]+-[a-zA-Z0-9]+)(_[a-z]+-[a-zA-Z0-9]+)*_data\.csv")
RULES = CATCH_GROUP + """
[exclusions]
catch_groups = ["catch"]
min_catch_accuracy_pct = 75.0
min_median_rt_ms = 150.0
"""


@pytest.fixture
def study(tmp_path):
    return make_demo_study(tmp_path / "study", name="pilot_2", videos=False, levels=(0, 25),
                           repetitions=1, extra=RULES)


def header(path):
    with open(path, newline="") as f:
        return next(csv.reader(f))


def check_dataset(folder, source):
    desc = json.loads((folder / "dataset_description.json").read_text())
    assert desc["@type"] == "Dataset" and desc["schemaVersion"].startswith("Psych-DS")
    files = sorted((folder / "data").iterdir())
    assert [f.name for f in files] == [f"study-pilot2_source-{source}_data.csv",
                                       f"study-pilot2_source-{source}_table-participants_data.csv"]
    measured = {v["name"] for v in desc["variableMeasured"]}
    for f in files:
        assert PSYCHDS_NAME.fullmatch(f.name), f.name
        missing = set(header(f)) - measured
        assert not missing, f"{f.name}: columns not in variableMeasured: {sorted(missing)}"
    # the data files are the tables beside them, byte for byte
    assert files[0].read_bytes() == (folder / "responses.csv").read_bytes()
    assert files[1].read_bytes() == (folder / "participants.csv").read_bytes()
    return desc


def test_export_writes_the_psychds_layout_with_the_exclusion_rules(study):
    s = open_session(load_study(study), "L01")
    for t in s.trials:
        submit_answer(s, {"participant": "L01", "session": 1, "trial": t.trial, "stimulus": t.stimulus,
                          "response": "incorrect" if t.level else "correct", "rt_ms": 700.0,
                          "shown_ms": 400.0, "late_frames": 0})
    s.close()
    export_responses(study)
    desc = check_dataset(study, "local")
    rules = [c["text"] for c in desc["comment"]]
    assert any(r.startswith("catch accuracy: catch groups catch") and "75 %" in r for r in rules)
    assert any(r.startswith("response time") and "150 ms" in r for r in rules)
    assert "Exclusion rules stated in the design" in desc["description"]
    # the data folder is the study's export: no other command may write there
    assert owner(study / "data" / "anything.csv") is not None


def test_import_web_writes_the_psychds_layout(study, tmp_path):
    import_web(study, [write_jsonl(tmp_path / "w.jsonl", web_records(study, "W01"))])
    desc = check_dataset(study / "web", "web")
    assert len(desc["comment"]) == 2
