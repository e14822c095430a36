"""import-web: JATOS, Pavlovia and download files into STUDY/web/responses.csv — every
record checked (file and line named on refusal), nothing doubled or overwritten, web
and local participants kept apart — and analyze on web and local answers together;
the Psych-DS dataset_description.json beside both exports."""
import csv
import io
import json
import zipfile

import pytest

from flipstudy.errors import FlipstudyError, WebImportError
from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.export import export_responses
from flipstudy.study.session import load_study, open_session, submit_answer
from flipstudy.study.web.importer import import_web, read_records
from flipstudy.study.web.order import order_groups, web_trial_order
from flipstudy.study.web.site import FORMAT, site_config
from _site_names import as_site_writes, nothing_imported


@pytest.fixture
def study(tmp_path):
    return make_demo_study(tmp_path / "study", videos=False, levels=(0, 25), repetitions=2)


def run_records(study_dir, pid, *, run="r1", n=None, host="jatos", responses=None, flag=(), site_names=True):
    """The records a site run writes (start, demographics, answers, end), in its opaque names
    (``site_names=False``: in the study's names, to be changed and then given to
    :func:`as_site_writes`)."""
    st = load_study(study_dir)
    trials = web_trial_order(order_groups(st.design, st.manifest), st.design.repetitions,
                             st.design.seed, pid)
    base = {"format": FORMAT, "site_id": "s", "study": st.design.name,
            "manifest_sha256": st.manifest_sha256, "host": host, "participant": pid, "run_id": run,
            "run_started": "2026-01-05T10:00:00.000Z", "timestamp": "2026-01-05T10:00:01.000Z"}
    recs = [dict(base, record="start", n_trials=len(trials), order=" ".join(t.stimulus for t in trials),
                 refresh_hz=60.0, participant_from="PROLIFIC_PID", user_agent="test")]
    recs.append(dict(base, record="demographics", age=30, gender="woman", animation_experience="none",
                     gymnastics_experience="some"))
    for t in trials[:n]:
        dropped = 6 if t.trial in flag else 0
        recs.append(dict(base, record="answer", trial=t.trial, stimulus=t.stimulus, group=t.group,
                         level=t.level, repetition=t.repetition, clip=t.clip, kind=t.kind,
                         response=(responses or {}).get(t.trial, "correct" if t.trial % 2 else "incorrect"),
                         rt_ms=512.3, shown_ms=400.1, input="key" if t.trial % 3 else "click", replays=0,
                         frames_expected=12, frames_presented=12 - dropped, frames_dropped=dropped,
                         dropped_pct=round(100 * dropped / 12, 1), playback_ms=410.0, video_ms=400.0,
                         refresh_hz=60.0, timing="rvfc", playback_flagged=t.trial in flag,
                         max_dropped_pct=10.0, frames_seen=12))
    if n is None:
        recs.append(dict(base, record="end", answered=len(trials), n_trials=len(trials)))
    return as_site_writes(study_dir, recs) if site_names else recs


def jsonl(path, recs):
    path.write_text("".join(json.dumps(r) + "\n" for r in recs))
    return path


def pavlovia_csv(path, recs):
    """As the site uploads it: the records as one CSV (columns: the union, in order)."""
    cols = []
    for r in recs:
        cols += [k for k in r if k not in cols]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for r in recs:
        w.writerow(["" if r.get(c) is None else (json.dumps(r[c]) if isinstance(r[c], bool) else r[c])
                    for c in cols])
    path.write_text(buf.getvalue())
    return path


def rows(study):
    with open(study / "web" / "responses.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_jatos_pavlovia_download_read_alike_and_nothing_doubles(study, tmp_path):
    recs = run_records(study, "W01", flag={3})
    a = jsonl(tmp_path / "jatos.txt", recs)
    b = pavlovia_csv(tmp_path / "demo_W01_r1.csv", [dict(r, host="jatos") for r in recs])
    assert [r for _, r in read_records(a)] == recs
    out = import_web(study, [a])
    assert out.answers == 8 and out.files[0].new_answers == 8
    first = (study / "web" / "responses.csv").read_bytes()
    out = import_web(study, [b, a])                       # the same answers as CSV, and a again
    # issue 28.9: a file adding no new record is read but not kept
    assert [f.status for f in out.files] == ["nothing new", "already imported"]
    assert out.files[0].new_answers == 0 and out.answers == 8
    assert (study / "web" / "responses.csv").read_bytes() == first
    got = rows(study)
    assert [r["trial"] for r in got] == [str(i) for i in range(1, 9)]
    assert {r["source"] for r in got} == {"web-jatos"} and {r["session"] for r in got} == {"1"}
    assert [r["playback_flagged"] for r in got] == ["true" if i == 3 else "false" for i in range(1, 9)]
    assert got[2]["frames_dropped"] == "6" and got[2]["late_frames"] == "6"
    assert got[0]["source_file"].endswith("-jatos.txt")
    assert sorted(p.name.split("-", 1)[1] for p in (study / "web" / "imports").iterdir()) == \
           ["jatos.txt"]
    d = json.loads((study / "web" / "dataset_description.json").read_text())
    assert d["schemaVersion"].startswith("Psych-DS") and "playback_flagged" in [v["name"] for v in d["variableMeasured"]]
    assert any(x.get("name") == "manifest.csv" and len(x["sha256"]) == 64 for x in d["isBasedOn"])


def test_jatos_archive_and_incomplete_runs(study, tmp_path):
    zpath = tmp_path / "jatos_results_20260105.zip"
    with zipfile.ZipFile(zpath, "w") as z:
        z.writestr("study_result_1/comp-result_1/data.txt",
                   "".join(json.dumps(r) + "\n" for r in run_records(study, "W01", n=5)))
        z.writestr("study_result_2/comp-result_2/data.txt",
                   "".join(json.dumps(r) + "\n" for r in run_records(study, "W02", run="r2")))
    out = import_web(study, [zpath])
    assert out.participants == 2 and out.answers == 13 and out.incomplete == ("W01/1 (5/8)",)
    assert {r["complete"] for r in rows(study) if r["participant"] == "W01"} == {"false"}


def test_a_second_run_is_a_second_session(study, tmp_path):
    a = jsonl(tmp_path / "a.jsonl", run_records(study, "W01", run="r1", n=3))
    b = jsonl(tmp_path / "b.jsonl", [dict(r, run_started="2026-01-06T09:00:00.000Z")
                                     for r in run_records(study, "W01", run="r2")])
    import_web(study, [b, a])
    got = rows(study)
    assert [(r["session"], r["run_id"]) for r in got][:3] == [("1", "r1")] * 3
    assert {r["session"] for r in got if r["run_id"] == "r2"} == {"2"} and len(got) == 11


@pytest.mark.parametrize("change, message", [
    (lambda r: r.update(response="maybe"), "response: must be one of correct, incorrect"),
    (lambda r: r.update(stimulus="backflip_abrupt-decrease_25" if r["stimulus"] != "backflip_abrupt-decrease_25"
                        else "backflip_abrupt-decrease_0"), "trial 3: stimulus"),
    (lambda r: r.update(stimulus="backflip_abrupt-decrease_99"),    # not a stimulus: its name unknown to the map
     r"stimulus '[0-9a-f]{16}' is not one of the opaque names in .*site-map.json"),
    (lambda r: r.update(rt_ms="fast"), "rt_ms: expected a number"),
    (lambda r: r.update(format="other/1"), "this flipstudy reads flipstudy-web/1"),
    (lambda r: r.update(manifest_sha256="0" * 64), "exported from other stimuli"),
    (lambda r: r.pop("frames_dropped"),                      # a CSV has the column, empty
     r"missing field\(s\) frames_dropped|frames_dropped: expected a number, got None"),
    (lambda r: r.update(frames_dropped=3), "frames_dropped 3 is not frames_expected - frames_presented"),
])
def test_a_malformed_row_is_refused_with_its_line_and_nothing_is_written(study, tmp_path, change, message):
    recs = run_records(study, "W01", site_names=False)
    change(recs[4])                                        # trial 3: the file's line 5
    recs = as_site_writes(study, recs)
    for f in (jsonl(tmp_path / "bad.jsonl", recs), pavlovia_csv(tmp_path / "bad.csv", recs)):
        with pytest.raises(WebImportError, match=message) as e:
            import_web(study, [f])
        assert f"{f}: line {5 if f.suffix == '.jsonl' else 6}:" in str(e.value)
        assert nothing_imported(study)


def test_a_different_answer_to_an_imported_trial_is_kept_aside_never_overwritten(study, tmp_path):
    import_web(study, [jsonl(tmp_path / "a.jsonl", run_records(study, "W01"))])
    before = (study / "web" / "responses.csv").read_bytes()
    other = jsonl(tmp_path / "b.jsonl", run_records(study, "W01", responses={4: "correct"}))
    out = import_web(study, [other])                      # issue 45.9: set aside, the rest imported
    assert out.quarantined == (f"W01 run r1 trial 4: conflict: differs from the one kept from "
                               f"imports/{next((study / 'web' / 'imports').glob('*-a.jsonl')).name}: line 6, "
                               f"which stays",)
    assert (study / "web" / "responses.csv").read_bytes() == before
    assert len(list((study / "web" / "imports").iterdir())) == 2      # the evidence is kept
    import_web(study, [other])                                          # and decided so again
    assert (study / "web" / "responses.csv").read_bytes() == before


def test_not_a_results_file(study, tmp_path):
    p = tmp_path / "notes.csv"
    p.write_text("a,b\n1,2\n")
    with pytest.raises(WebImportError, match="line 1: not a flipstudy results file"):
        import_web(study, [p])
    p = tmp_path / "broken.jsonl"
    p.write_text(json.dumps(run_records(study, "W01")[0]) + "\n{not json\n")
    with pytest.raises(WebImportError, match="broken.jsonl: line 2: not a JSON record"):
        import_web(study, [p])


def _local_session(study, pid):
    s = open_session(load_study(study), pid)
    for t in s.trials:
        submit_answer(s, {"participant": pid, "session": 1, "trial": t.trial, "stimulus": t.stimulus,
                          "response": "incorrect" if t.level else "correct", "rt_ms": 700.0,
                          "shown_ms": 400.0, "late_frames": 0})
    s.close()


def test_local_and_web_answers_analysed_together_never_mixed(study, tmp_path):
    _local_session(study, "L01")
    exp = export_responses(study)
    desc = json.loads((study / "dataset_description.json").read_text())
    assert desc["@type"] == "Dataset" and [v["name"] for v in desc["variableMeasured"]][:3] == \
           ["participant", "session", "trial"]
    assert exp.rows == 8
    with pytest.raises(WebImportError, match="L01 also has local sessions"):
        import_web(study, [jsonl(tmp_path / "clash.jsonl", run_records(study, "L01"))])
    import_web(study, [jsonl(tmp_path / "w.jsonl", run_records(study, "W01"))])
    out = tmp_path / "both"
    assert cli(["analyze", str(study / "responses.csv"), str(study / "web" / "responses.csv"), "--out",
                str(out), "--no-figures", "--no-gee", "--psychometric", "none", "--n-boot", "50"]) == 0
    with open(out / "table.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert sum(int(t["n"]) for t in table) == 16
    # the same table twice is refused: one participant in two tables
    assert cli(["analyze", str(study / "web" / "responses.csv"), str(study / "web"), "--out",
                str(tmp_path / "x"), "--no-figures", "--no-gee", "--psychometric", "none"]) == 1


def test_cli_import_web_prints_what_it_did(study, tmp_path, capsys):
    f = jsonl(tmp_path / "w.jsonl", run_records(study, "W01", flag={2}))
    assert cli(["import-web", str(study), str(f)]) == 0
    assert cli(["import-web", str(study), str(f)]) == 0
    text = capsys.readouterr().out
    assert "8 new answers" in text and "already imported (same content), nothing new" in text
    assert "playback_flagged=true: W01/1 trial 2" in text
    bad = tmp_path / "bad.jsonl"
    bad.write_text("{}\n")
    assert cli(["import-web", str(study), str(bad)]) == 1
    assert "bad.jsonl: line 1: missing field(s)" in capsys.readouterr().err


def test_site_config_carries_the_design_and_threshold(study):
    cfg = site_config(load_study(study), host="pavlovia", max_dropped_pct=5.0)
    assert cfg["max_dropped_pct"] == 5.0 and cfg["repetitions"] == 2 and cfg["n_trials"] == 8
    assert cfg["texts"]["instructions"][1].startswith("Some of these motions are physically correct")
    assert "PROLIFIC_PID" == cfg["participant_params"][0]
    with pytest.raises(FlipstudyError, match="choose one of static, jatos, pavlovia"):
        site_config(load_study(study), host="ftp")


def test_repeats_of_flagged_trials_are_kept_beside_the_first_answer(study, tmp_path):
    recs = run_records(study, "W09", flag={3}, responses={3: "correct"})
    end = recs.pop()
    rep = dict(next(r for r in recs if r.get("trial") == 3), repeat=1, response="incorrect",
               frames_presented=12, frames_dropped=0, dropped_pct=0.0, playback_flagged=False)
    out = import_web(study, [pavlovia_csv(tmp_path / "run.csv", recs + [rep, end])])
    assert out.answers == 9 and out.incomplete == () and out.repeats == ("W09/1 trial 3",)
    got = rows(study)
    assert [(r["trial"], r["repeat"]) for r in got][2:4] == [("3", "0"), ("3", "1")]
    assert [(r["response"], r["playback_flagged"]) for r in got][2:4] == [("correct", "true"),
                                                                          ("incorrect", "false")]
    assert {r["repeat"] for r in got if r["trial"] != "3"} == {"0"}     # records without 'repeat'
    # a repeat of a trial that was not flagged, or a second repeat, is refused
    bad = dict(next(r for r in recs if r.get("trial") == 4), repeat=1)
    with pytest.raises(WebImportError, match=r"line \d+: trial 4 .* repeat = 1, but its first answer"):
        import_web(study, [jsonl(tmp_path / "bad.jsonl", recs + [bad])])
    twice = dict(rep, response="correct")                 # a second repeat: kept out (issue 45.9)
    out = import_web(study, [jsonl(tmp_path / "twice.jsonl", recs + [rep, twice])])
    assert [q.split(": ")[:2] for q in out.quarantined] == [["W09 run r1 trial 3 (repeat)", "conflict"]]
    assert len(rows(study)) == 9
    # analyze: the repeat stands in for the flagged first answer
    from flipstudy.analysis.io import load_responses
    df = load_responses(study / "web")
    assert len(df[df["trial"] == 3]) == 1 and df.loc[df["trial"] == 3, "response"].item() == "incorrect"
    assert len(df) == 8


# --- 2AFC records ------------------------------------------------------------------------------

def _2afc_records(study_dir, pid):
    """A 2AFC run's records, in the study's names (:func:`as_site_writes` gives the site's):
    each answer carries task, first and original."""
    st = load_study(study_dir)
    trials = {t.trial: t for t in web_trial_order(order_groups(st.design, st.manifest),
                                                  st.design.repetitions, st.design.seed, pid)}
    recs = run_records(study_dir, pid, responses={i: "first" if i % 2 else "second" for i in trials},
                       site_names=False)
    for r in recs:
        if r["record"] == "answer" and trials[r["trial"]].task == "2afc":
            t = trials[r["trial"]]
            r.update(task="2afc", first=t.first, original=t.original, frames_expected=24,
                     frames_presented=24)
        elif r["record"] == "answer":
            r["response"] = "correct"
    return recs, trials



@pytest.fixture
def study_2afc(tmp_path):
    from _kinds import design_text, make_study
    groups = [{"name": "up", "sign": 1, "levels": [0, 25, 50], "task": "2afc"},
              {"name": "down", "sign": -1, "levels": [0, 40]}]
    return make_study(tmp_path / "s2", design_text(groups), videos=False)


def test_2afc_records_import_with_first_and_comparison(study_2afc, tmp_path):
    recs, trials = _2afc_records(study_2afc, "F01")
    out = import_web(study_2afc, [jsonl(tmp_path / "f.jsonl", as_site_writes(study_2afc, recs))])
    assert out.answers == len(trials) == 8
    got = rows(study_2afc)
    assert [(r["task"], r["first"], r["original_stimulus"], r["method"]) for r in got] == [
        (t.task, t.first, t.original, "constant") for t in trials.values()]
    assert {r["response"] for r in got if r["task"] == "2afc"} == {"first", "second"}


@pytest.mark.parametrize("change, message", [
    (lambda r: r.update(first="modified" if r["first"] == "original" else "original"), r"first '\w+', but trial"),
    (lambda r: r.update(original="backflip_down_0"), r"original 'backflip_down_0', but trial"),
    (lambda r: r.update(response="correct"), "response: must be one of first, second, got 'correct'"),
    (lambda r: r.pop("task"), "task None, but trial"),
])
def test_a_2afc_record_that_does_not_fit_its_trial_is_refused(study_2afc, tmp_path, change, message):
    recs, trials = _2afc_records(study_2afc, "F02")
    bad = next(r for r in recs if r["record"] == "answer" and r.get("task") == "2afc")
    change(bad)
    with pytest.raises(WebImportError, match=message):
        import_web(study_2afc, [jsonl(tmp_path / "bad.jsonl", as_site_writes(study_2afc, recs))])
    assert nothing_imported(study_2afc)


def test_a_yes_no_record_with_a_2afc_answer_is_refused(study_2afc, tmp_path):
    recs, trials = _2afc_records(study_2afc, "F03")
    bad = next(r for r in recs if r["record"] == "answer" and "task" not in r)
    bad["response"] = "first"
    with pytest.raises(WebImportError, match="response: must be one of correct, incorrect, got 'first'"):
        import_web(study_2afc, [jsonl(tmp_path / "bad.jsonl", as_site_writes(study_2afc, recs))])


def _add_styles(study_dir):
    """Give the demo study's manifest a ``style`` column (as ``flipstudy stimuli`` writes
    it for a styled design): alternate stick / point-light by stimulus."""
    p = study_dir / "manifest.csv"
    with open(p, newline="") as f:
        rd = csv.DictReader(f)
        fields, recs = list(rd.fieldnames), list(rd)
    styles = {}
    for i, r in enumerate(recs):
        r["style"] = styles[r["stimulus"]] = ("stick", "point-light")[i % 2]
    with open(p, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields + ["style"], lineterminator="\n")
        w.writeheader()
        w.writerows(recs)
    return styles


def test_import_web_carries_the_manifest_style_like_export(study, tmp_path):
    # no style column in the manifest: none in the table either
    import_web(study, [jsonl(tmp_path / "plain.jsonl", run_records(study, "W01"))])
    assert "style" not in (study / "web" / "responses.csv").read_text().splitlines()[0].split(",")
    styled = make_demo_study(tmp_path / "styled", videos=False, levels=(0, 25), repetitions=2)
    styles = _add_styles(styled)
    assert len(set(styles.values())) == 2
    _local_session(styled, "L01")
    local = export_responses(styled).responses.read_text().splitlines()[0].split(",")
    import_web(styled, [jsonl(tmp_path / "w.jsonl", run_records(styled, "W01"))])
    web = (styled / "web" / "responses.csv").read_text().splitlines()[0].split(",")
    assert web[:len(local)] == local and web[web.index("kind") + 1] == "style"   # export's position
    got = rows(styled)
    assert len(got) == 8 and [r["style"] for r in got] == [styles[r["stimulus"]] for r in got]
    d = json.loads((styled / "web" / "dataset_description.json").read_text())
    assert "style" in [v["name"] for v in d["variableMeasured"]]
