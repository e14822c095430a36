"""Issue 32, item 7: `export` and `import-web` write a Psych-DS dataset: data files under
data/, keyword names with the _data.csv suffix, every column in variableMeasured, and
the design's exclusion rules in the metadata."""
import csv
import json
import re

import pytest

from flipstudy.study.demo import make_demo_study
from flipstudy.study.export import export_responses
from flipstudy.study.owned import owner
from flipstudy.study.session import load_study, open_session, submit_answer
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.order import order_groups, web_trial_order
from flipstudy.study.web.site import FORMAT

# Psych-DS: keyword-value pairs (lowercase keyword, alphanumeric value) joined by "_", then _data.csv
PSYCHDS_NAME = re.compile(r"([a-z]+-[a-zA-Z0-9]+)(_[a-z]+-[a-zA-Z0-9]+)*_data\.csv")
RULES = """
[[groups]]
name = "catch"
kind = "angular-momentum"
profile = "abrupt"
sign = 1
levels = [100]

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
    st = load_study(study)
    trials = web_trial_order(order_groups(st.design, st.manifest), st.design.repetitions, st.design.seed, "W01")
    base = {"format": FORMAT, "site_id": "s", "study": st.design.name, "manifest_sha256": st.manifest_sha256,
            "host": "jatos", "participant": "W01", "run_id": "r1", "run_started": "2026-01-05T10:00:00.000Z",
            "timestamp": "2026-01-05T10:00:01.000Z"}
    recs = [dict(base, record="start", n_trials=len(trials), order=" ".join(t.stimulus for t in trials),
                 refresh_hz=60.0, participant_from="PROLIFIC_PID", user_agent="test")]
    recs += [dict(base, record="answer", trial=t.trial, stimulus=t.stimulus, group=t.group, level=t.level,
                  repetition=t.repetition, clip=t.clip, kind=t.kind, response="incorrect", rt_ms=500.0,
                  shown_ms=400.0, input="key", replays=0, frames_expected=12, frames_presented=12,
                  frames_dropped=0, dropped_pct=0.0, playback_ms=400.0, video_ms=400.0, timing="rvfc",
                  playback_flagged=False, max_dropped_pct=10.0, refresh_hz=60.0) for t in trials]
    recs.append(dict(base, record="end", answered=len(trials), n_trials=len(trials)))
    f = tmp_path / "w.jsonl"
    f.write_text("".join(json.dumps(r) + "\n" for r in recs))
    import_web(study, [f])
    desc = check_dataset(study / "web", "web")
    assert len(desc["comment"]) == 2
