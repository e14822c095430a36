"""Issue 32, item 4: between-subject conditions ([online] between): least-filled first
through JATOS's batch session (ten participants in headless Chromium, a stand-in batch
session with JATOS's versioned set), by the participant ID's hash on other hosts (the
JavaScript twin agrees with Python), and import-web checks each run's order against
its recorded condition."""
import collections
import json
import os
import shutil
import subprocess
from pathlib import Path
from urllib.parse import urlparse

import pandas as pd
import pytest

from _prolific import web_records, write_jsonl
from _site_names import study_names
from test_session_browser import CHROMIUM, jspsych_dir, page, pw  # noqa: F401 (fixtures)
import test_web_browser

import flipstudy.study.web as web_pkg
from flipstudy.errors import DesignError, WebImportError
from flipstudy.study.demo import make_demo_study
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.order import balanced_latin_square, condition_by_hash
from flipstudy.study.web.site import export_site

JS = Path(web_pkg.__file__).parent / "static" / "flipstudy-order.js"
GROUPS = (("smooth-increase", "angular-momentum", "smooth", 1), ("abrupt-decrease", "angular-momentum", "abrupt", -1),
          ("takeoff-increase", "takeoff-angle", None, 1))
BETWEEN = ["smooth-increase", "abrupt-decrease"]


@pytest.fixture
def study(tmp_path):
    return make_demo_study(tmp_path / "study", levels=(0, 25), repetitions=1, groups=GROUPS, video_frames=12,
                           size=(96, 72), extra=f"[online]\nbetween = {json.dumps(BETWEEN)}\n")


def test_a_between_list_must_name_groups_of_equal_size(tmp_path):
    with pytest.raises(DesignError, match=r"\[online\].between: 'nope' is not one of the groups"):
        make_demo_study(tmp_path / "a", videos=False, groups=GROUPS, extra='[online]\nbetween = ["nope", "takeoff-increase"]\n')
    with pytest.raises(DesignError, match=r"\[online\].between: group names, each once, at least two"):
        make_demo_study(tmp_path / "b", videos=False, groups=GROUPS, extra='[online]\nbetween = ["takeoff-increase"]\n')


@pytest.mark.skipif(shutil.which("node") is None, reason="needs node to run the site's JavaScript")
def test_hash_assignment_twin_and_spread():
    ids = [f"P{i:03d}" for i in range(200)]
    script = (f"const o = require({json.dumps(str(JS))});"
              f"console.log(JSON.stringify({json.dumps(ids)}.map((p) => o.conditionByHash(p, {json.dumps(BETWEEN)}))));")
    js = json.loads(subprocess.run(["node", "-e", script], capture_output=True, text=True, check=True).stdout)
    assert js == [condition_by_hash(p, BETWEEN) for p in ids]
    counts = collections.Counter(js)
    assert set(counts) == set(BETWEEN) and min(counts.values()) > 70     # equally likely, not exactly filled


def test_import_checks_the_order_of_the_recorded_condition(study, tmp_path):
    a = web_records(study, "P1", condition="abrupt-decrease")            # (built without the condition's filter)
    with pytest.raises(WebImportError, match="trial order is not this study's order"):
        import_web(study, [write_jsonl(tmp_path / "a.jsonl", a)])
    with pytest.raises(WebImportError, match="condition: must be one of"):
        import_web(study, [write_jsonl(tmp_path / "b.jsonl", web_records(study, "P1", condition="takeoff-increase"))])


#: JATOS's batch session as the site uses it: get() reads the local copy, set() sends the
#: whole object with the version it was read at and fails when another run wrote first
BATCH_STANDIN = test_web_browser.JATOS_STANDIN.replace("onLoad(cb) { setTimeout(cb, 0); },", """
  onLoad(cb) { fetch('/__batch').then((r) => r.json()).then((b) => { this._batch = b; cb(); }); },
  batchSession: {
    get(key) { return window.jatos._batch.data[key]; },
    set(key, value) {
      const b = window.jatos._batch;
      const data = Object.assign({}, b.data, {[key]: value});
      return fetch('/__batch', {method: 'POST', body: JSON.stringify({version: b.version, data})})
        .then((r) => r.json()).then((res) => { window.jatos._batch = res.batch; if (!res.ok) throw new Error('conflict'); });
    },
  },""")


def _jatos_runs(page, site, pids, monkeypatch, race_at=None):
    """Open the JATOS site for each of ``pids`` (up to the instructions, so the run has
    started) beside a stand-in batch session; returns each run's checkpoint state, the batch
    session, the conflicting sets, the blocked requests and the host."""
    monkeypatch.setattr(test_web_browser, "JATOS_STANDIN", BATCH_STANDIN)
    batch = {"version": 0, "data": {}}
    conflicts, blocked, race = [], [], {"now": False}
    with test_web_browser._Host(site) as host:
        origin = f"127.0.0.1:{host.port}"

        def gate(route):
            u = urlparse(route.request.url)
            if u.netloc != origin:
                blocked.append(route.request.url)
                route.abort()
            elif u.path == "/__batch":
                if route.request.method == "POST":
                    want = json.loads(route.request.post_data)
                    ok = want["version"] == batch["version"]
                    if ok:
                        batch.update(version=batch["version"] + 1, data=want["data"])
                    else:
                        conflicts.append(want)
                    route.fulfill(status=200, content_type="application/json", body=json.dumps({"ok": ok, "batch": batch}))
                else:
                    route.fulfill(status=200, content_type="application/json", body=json.dumps(batch))
                    if race["now"]:                      # another run writes after this run has read
                        batch["version"] += 1
                        race["now"] = False
            else:
                route.continue_()
        page.route("**/*", gate)
        states = {}
        for i, pid in enumerate(pids):
            race["now"] = i == race_at                   # this run's first set meets a newer version
            page.goto(f"http://{origin}/index.html?PROLIFIC_PID={pid}")
            page.wait_for_selector('#jspsych-target[data-screen-id="instructions"]')
            states[pid] = page.evaluate("() => ({condition: window.flipstudyState.checkpoint.s.condition || null, "
                                        "row: window.flipstudyState.checkpoint.s.latin_row ?? null, "
                                        "groups: window.flipstudyState.trials.map((t) => t.group)})")
        page.wait_for_function("() => window.flipstudyState.checkpoint.s.sent >= 1")
    return states, batch, conflicts, blocked, host


def _import_runs(study, tmp_path, host):
    f = write_jsonl(tmp_path / "jatos.jsonl", [json.loads(x) for b in host.bodies for x in b.splitlines() if x])
    import_web(study, [f])
    return pd.read_csv(study / "web" / "participants.csv", dtype=str)


@pytest.mark.slow
@pytest.mark.skipif(not os.path.exists(CHROMIUM), reason=f"needs Debian's chromium at {CHROMIUM}")
def test_ten_jatos_participants_fill_two_conditions_five_and_five(page, study, tmp_path, jspsych_dir,  # noqa: F811
                                                                 monkeypatch):
    site = tmp_path / "site"
    export_site(study, site, host="jatos", iti_ms=20, jspsych_dir=jspsych_dir)
    states, batch, conflicts, blocked, host = _jatos_runs(page, site, [f"PP{i:02d}" for i in range(10)],
                                                         monkeypatch, race_at=3)
    gn = study_names(study, "group")                         # the browser knows the groups' opaque names only
    assert not set(BETWEEN) & set(batch["data"]["flipstudy-conditions"])
    got = {p: gn[s["condition"]] for p, s in states.items()}
    for p, s in states.items():
        groups = [gn[g] for g in s["groups"]]
        assert groups.count(got[p]) == 2 and not set(groups) & (set(BETWEEN) - {got[p]})
    assert collections.Counter(got.values()) == {BETWEEN[0]: 5, BETWEEN[1]: 5}
    assert {gn[c]: k for c, k in batch["data"]["flipstudy-conditions"].items()} == {BETWEEN[0]: 5, BETWEEN[1]: 5}
    assert blocked == [] and len(conflicts) == 1             # the conflicting set was retried
    parts = _import_runs(study, tmp_path, host)
    assert dict(zip(parts["participant"], parts["condition"])) == got


@pytest.mark.slow
@pytest.mark.skipif(not os.path.exists(CHROMIUM), reason=f"needs Debian's chromium at {CHROMIUM}")
def test_jatos_latin_square_rows_are_filled_evenly(page, tmp_path, jspsych_dir, monkeypatch):  # noqa: F811
    study = make_demo_study(tmp_path / "study", levels=(0, 25), repetitions=1, groups=GROUPS, video_frames=12,
                            size=(96, 72), extra='[online]\nblock_order = "latin-square"\n')
    site = tmp_path / "site"
    export_site(study, site, host="jatos", iti_ms=20, jspsych_dir=jspsych_dir)
    states, batch, conflicts, blocked, host = _jatos_runs(page, site, [f"Q{i:02d}" for i in range(12)], monkeypatch)
    square = balanced_latin_square(3)                        # 3 groups: 6 rows (odd: each row and its mirror)
    names = [g for g, *_ in GROUPS]
    gn = study_names(study, "group")                         # the browser knows the groups' opaque names only
    assert collections.Counter(s["row"] for s in states.values()) == {r: 2 for r in range(6)}
    for s in states.values():                               # each run's blocks follow its row
        assert [gn[g] for g in dict.fromkeys(s["groups"])] == [names[i] for i in square[s["row"]]]
    # over the 12 runs every group is in every position, and after every other, equally often
    firsts = collections.Counter(list(dict.fromkeys(s["groups"]))[0] for s in states.values())
    assert set(firsts.values()) == {4}
    assert blocked == []
    parts = _import_runs(study, tmp_path, host)
    assert dict(zip(parts["participant"], parts["latin_row"].astype(int))) == {p: s["row"] for p, s in states.items()}


def _conditions(study, source):
    import sqlite3
    with sqlite3.connect(study / "sessions.sqlite") as conn:
        rows = conn.execute("SELECT DISTINCT t.participant, t.group_name FROM trials t JOIN sessions s "
                            "ON s.participant = t.participant AND s.session = t.session WHERE s.source = ?",
                            (source,)).fetchall()
    return {p: g for p, g in rows if g in BETWEEN}


def test_ten_simulated_participants_in_the_local_runner_fill_five_and_five(study):
    from flipstudy.study.session import load_study, open_session
    from flipstudy.study.simulate import simulate
    ids = simulate(study, 10, seed=3)
    got = _conditions(study, "simulated")
    assert sorted(got) == sorted(ids) and collections.Counter(got.values()) == {BETWEEN[0]: 5, BETWEEN[1]: 5}
    # browser sessions are counted apart, least-filled first in the design's order on ties
    st = load_study(study)
    order = [open_session(st, f"L{i}").trials for i in range(3)]
    seen = [next(t.group for t in trials if t.group in BETWEEN) for trials in order]
    assert seen == [BETWEEN[0], BETWEEN[1], BETWEEN[0]]
    for trials in order:                                   # one condition each, every other group too
        groups = {t.group for t in trials}
        assert len(groups & set(BETWEEN)) == 1 and "takeoff-increase" in groups
