"""Issue 42, item 2: conditions hidden from participants on every host.  The folder
``export-web`` writes (the one a researcher uploads to JATOS, Pavlovia or a static host)
names no stimulus, group, kind or level in any file name or string; the key and the map
of its opaque names stay in the study (``STUDY/web/site-map.json``); ``import-web`` maps
the answers back exactly, stimulus by stimulus, and refuses a name the map does not know
(or a missing map) in one line naming the file."""
import contextlib
import csv
import io
import json
import random
import shutil
import zipfile

import pytest

from _prolific import CATCH_GROUP
from _site_names import condition_words
from test_session_browser import jspsych_dir  # noqa: F401 (fixture)

from flipstudy.errors import WebImportError
from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.order import order_groups, web_trial_order
from flipstudy.study.web.site import FORMAT, OWN_FILES, STATIC, export_site, lib_files

HOSTS = ("jatos", "pavlovia")
#: where the sessions guide says the map and key are kept: STUDY/web/site-map.json
MAP_FILE = "site-map.json"


@pytest.fixture(scope="module")
def built(tmp_path_factory, jspsych_dir):  # noqa: F811
    """The guide's catch group on the demo design, exported for JATOS and for Pavlovia."""
    tmp = tmp_path_factory.mktemp("opaque")
    study = make_demo_study(tmp / "study", levels=(0, 25), repetitions=2, video_frames=4, size=(32, 24),
                            extra=CATCH_GROUP)
    sites = {h: tmp / f"site-{h}" for h in HOSTS}
    export_site(study, sites["jatos"], host="jatos", iti_ms=20, jspsych_dir=jspsych_dir)
    said = io.StringIO()
    with contextlib.redirect_stdout(said):                   # the command says where the map is
        assert cli(["export-web", str(study), "--out", str(sites["pavlovia"]), "--host", "pavlovia",
                    "--iti-ms", "20", "--jspsych-dir", str(jspsych_dir)]) == 0
    assert f"mapped in {study / 'web' / MAP_FILE} (keep it with the study; never upload it)" in said.getvalue()
    return study, sites, jspsych_dir


def _copy(built, tmp_path):
    """A copy of the built study (a test that imports into it leaves the others' alone)."""
    return shutil.copytree(built[0], tmp_path / "study")


def _config(site):
    return json.loads((site / "config.js").read_text().split("= ", 1)[1].rstrip().rstrip(";\n"))


def _strings(obj, keys=()):
    """Every key and every string value of a JSON document (keys apart)."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _strings(v, keys)
            yield ("key", k)
    elif isinstance(obj, list):
        for v in obj:
            yield from _strings(v, keys)
    elif isinstance(obj, str):
        yield ("value", obj)


def test_no_file_name_or_string_of_the_uploaded_site_names_a_condition(built):
    study, sites, folder = built
    words = condition_words(study)
    assert {"catch", "smooth-increase", "abrupt-decrease", "backflip_catch_100", "angular-momentum"} <= set(words)
    st = load_study(study)
    for host, site in sites.items():
        files = {p.relative_to(site).as_posix(): p for p in sorted(site.rglob("*")) if p.is_file()}
        for rel in files:                                     # no file name names a condition
            assert not [w for w in words if w in rel], rel
        assert MAP_FILE not in " ".join(files)
        # the files every study's site has alike: jsPsych's and flipstudy's own, byte for byte
        same = dict(lib_files(folder), **{f: (STATIC / f).read_bytes() for f in OWN_FILES})
        assert {rel: files[rel].read_bytes() for rel in same} == same
        own = [rel for rel in files if rel not in same and not rel.endswith(".mp4")]
        assert sorted(own) == ["config.js", "flipstudy-site.json", "index.html"]
        for rel in ("index.html", "flipstudy-site.json"):
            text = files[rel].read_text()
            assert not [w for w in words if w in text], (host, rel)
        cfg = _config(site)
        for what, s in _strings(cfg):                          # config.js: no key is a name, no text holds one
            hits = [w for w in words if (w == s if what == "key" else w in s)]
            assert not hits, (host, what, s, hits)
        for _, rows in cfg["groups"]:                         # a trial is its video's opaque name only
            assert all(set(r) == {"stimulus"} for r in rows), rows
        stimuli = [cfg["groups"], cfg["videos"], cfg["references"]]      # what the site knows of each video
        assert not {"level", "kind", "clip", "profile", "group"} & {s for w, s in _strings(stimuli) if w == "key"}
        smap = json.loads((study / "web" / MAP_FILE).read_text())     # the study's, not the site's
        for rel in own:                                       # its key is in none of the site's files
            assert smap["key"] not in files[rel].read_text()
        # every video is a stimulus's, under the name the study's map gives it
        assert {f"stimuli/{v}.mp4" for v in smap["stimuli"]} == {r for r in files if r.endswith(".mp4")}
        for oid, name in smap["stimuli"].items():
            assert files[f"stimuli/{oid}.mp4"].read_bytes() == st.video_path(name).read_bytes()
        assert cfg["videos"].keys() == smap["stimuli"].keys()
        # the between conditions and groups are the map's opaque group names, in the design's order
        assert [smap["groups"][g] for g, _ in cfg["groups"]] == [g for g, _ in order_groups(st.design, st.manifest)]


def _site_records(site, pid, answer, run="r1"):
    """The records the site's browser writes for ``pid`` (flipstudy-web.js: the start
    record, then one answer per trial of its order over config.js, then the end), each
    trial answered by ``answer(trial)``."""
    cfg = _config(site)
    trials = web_trial_order(cfg["groups"], cfg["repetitions"], cfg["design_seed"], pid)
    base = {"format": FORMAT, "site_id": cfg["site_id"], "study": cfg["study"],
            "manifest_sha256": cfg["manifest_sha256"], "host": cfg["host"], "participant": pid,
            "run_id": run, "run_started": "2026-01-05T10:00:00.000Z", "timestamp": "2026-01-05T10:00:01.000Z"}
    recs = [dict(base, record="start", n_trials=len(trials), participant_from="participant",
                 order=" ".join(t.stimulus for t in trials), refresh_hz=60.0, window="900x760", screen_ok=True)]
    recs += [dict(base, record="answer", trial=t.trial, stimulus=t.stimulus, group=t.group, repetition=t.repetition,
                  response=answer(t), rt_ms=500.0, input="key", replays=0, repeat=0, refresh_hz=60.0,
                  max_dropped_pct=10.0, shown_ms=133.3, frames_expected=4, frames_presented=4, frames_dropped=0,
                  frames_seen=4, dropped_pct=0.0, playback_ms=133.3, video_ms=133.3, timing="rvfc",
                  playback_flagged=False) for t in trials]
    return recs + [dict(base, record="end", answered=len(trials), repeats=0, n_trials=len(trials))]


def _pavlovia_csv(recs):
    """As flipstudy-web.js's csvOf: the union of the keys, in order; JSON for non-strings."""
    cols = list(dict.fromkeys(k for r in recs for k in r))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for r in recs:
        w.writerow(["" if r.get(c) is None else r[c] if isinstance(r[c], str) else json.dumps(r[c]) for c in cols])
    return buf.getvalue()


def test_import_web_maps_the_answers_back_exactly(built, tmp_path):
    study = _copy(built, tmp_path)
    sites = built[1]
    st = load_study(study)
    truth, answered, files = {}, {}, []
    for pid, host, how in (("A1", "jatos", "lines"), ("A2", "jatos", "zip"), ("A3", "pavlovia", "csv")):
        rng = random.Random(pid)
        real = web_trial_order(order_groups(st.design, st.manifest), st.design.repetitions, st.design.seed, pid)
        truth[pid] = {t.trial: (t.stimulus, t.group, t.level, t.repetition) for t in real}
        answered[pid] = {t.trial: rng.choice(["correct", "incorrect"]) for t in real}
        recs = _site_records(sites[host], pid, lambda t: answered[pid][t.trial], run=f"r{pid}")
        text = "".join(json.dumps(r) + "\n" for r in recs)
        f = tmp_path / f"{pid}.{ {'lines': 'txt', 'zip': 'zip', 'csv': 'csv'}[how] }"
        if how == "zip":
            with zipfile.ZipFile(f, "w") as z:
                z.writestr("study_result_2/comp-result_2/data.txt", text)
        else:
            f.write_text(_pavlovia_csv(recs) if how == "csv" else text)
        files.append(f)
    out = import_web(study, files)
    assert out.answers == sum(len(a) for a in answered.values()) and out.incomplete == ()
    with open(study / "web" / "responses.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    got = {(r["participant"], int(r["trial"])): r for r in rows}
    assert len(got) == len(rows)
    manifest = {r.stimulus: r for r in st.manifest}
    for pid in truth:                                          # stimulus by stimulus, as answered
        for trial, (stim, group, level, rep) in truth[pid].items():
            r = got[pid, trial]
            assert (r["stimulus"], r["group"], float(r["level"]), int(r["repetition"]), r["response"]) == \
                (stim, group, level, rep, answered[pid][trial]), (pid, trial)
            assert (r["clip"], r["kind"]) == (manifest[stim].clip, manifest[stim].kind)
    catch = [r for r in rows if r["group"] == "catch"]
    assert {r["stimulus"] for r in catch} == {"backflip_catch_100"} and len(catch) == 3 * st.design.repetitions


def test_an_unknown_opaque_name_or_a_missing_map_is_refused_in_one_line(built, tmp_path, capsys):
    study = _copy(built, tmp_path)
    recs = _site_records(built[1]["jatos"], "B1", lambda t: "correct")
    ans = next(i for i, r in enumerate(recs) if r["record"] == "answer")
    cases = [(dict(recs[ans], stimulus="0123456789abcdef"), "stimulus '0123456789abcdef'"),
             (dict(recs[ans], group="fedcba9876543210"), "group 'fedcba9876543210'"),
             (dict(recs[ans], stimulus="backflip_catch_100"), "stimulus 'backflip_catch_100'"),   # a study name
             (dict(recs[0], order="0123456789abcdef " + recs[0]["order"]), "order '0123456789abcdef'")]
    for k, (bad, said) in enumerate(cases):
        i = ans if bad["record"] == "answer" else 0
        f = tmp_path / f"bad{k}.jsonl"
        f.write_text("".join(json.dumps(bad if j == i else r) + "\n" for j, r in enumerate(recs)))
        with pytest.raises(WebImportError, match=f"{f}: line {i + 1}: {said} is not one of the opaque names "
                                                 f"in {study / 'web' / MAP_FILE}"):
            import_web(study, [f])
        assert not (study / "web" / "responses.csv").exists()
    good = tmp_path / "good.jsonl"
    good.write_text("".join(json.dumps(r) + "\n" for r in recs))
    (study / "web" / MAP_FILE).rename(tmp_path / "moved-away.json")
    assert cli(["import-web", str(study), str(good)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and f"{study / 'web' / MAP_FILE}: missing" in err and "Traceback" not in err
    assert not (study / "web" / "responses.csv").exists()
    (tmp_path / "moved-away.json").rename(study / "web" / MAP_FILE)
    assert import_web(study, [good]).answers == len(recs) - 2


def test_the_key_is_the_studys_own(built, tmp_path):
    """The names cannot be computed from the public design: another study of the same design
    (a new key) names every stimulus otherwise; exporting again keeps a study's names."""
    from flipstudy.study.web.opaque import site_map
    study, sites, folder = built
    other = shutil.copytree(study, tmp_path / "other")
    (other / "web" / MAP_FILE).unlink()
    mine, theirs = site_map(load_study(study)), site_map(load_study(other))
    assert mine.key != theirs.key and not set(mine.names["stimulus"]) & set(theirs.names["stimulus"])
    assert (other / "web" / MAP_FILE).stat().st_mode & 0o077 == 0           # the key: the owner's only
    again = tmp_path / "again"
    export_site(study, again, host="jatos", iti_ms=20, jspsych_dir=folder)
    assert (again / "config.js").read_bytes() == (sites["jatos"] / "config.js").read_bytes()
