"""The exported jsPsych site, run in headless Chromium (Debian's, through Playwright).

A tiny study (1 clip, 2 groups x 2 levels, 2 repetitions = 8 trials, a break every 3)
is exported for JATOS and served from a local static server on 127.0.0.1 beside a
stand-in for JATOS's jatos.js (:data:`JATOS_STANDIN`: the calls the site makes —
``jatos.onLoad``, ``jatos.urlQueryParameters``, ``jatos.appendResultData``,
``jatos.endStudyAjax``, ``jatos.endStudy`` — each a POST to the test server, which
keeps the bodies as JATOS keeps a component's result data).  The session is run
end to end: instructions, demographics, the example (watched twice), trials answered
by key and by click, a page reload in the middle that must resume at the next trial,
the end screen's download.  Every request to anything but the test server is
blocked and recorded.  Then ``import-web`` reads the stand-in's data and the
download, and ``analyze`` makes the table.

One stimulus's video is made at 240 fps: a 60 Hz display cannot present three of its
every four frames, so its trials must be flagged as dropping frames; with the design's
``[session] repeat_dropped = true`` they come back once more after the last trial
(a reload in the middle of the repeats resumes them), and ``analyze`` counts the
repeat in place of the flagged first answer.  With ``[session] replay = true`` a
motion is replayed before the answer: the replays are counted, the answer kept once.

Set ``FLIPSTUDY_SCREENSHOTS=DIR`` to keep the screenshots (docs/img/web_trial.png
comes from there).
"""
import csv
import functools
import json
import contextlib
import os
import threading
import time
import zipfile
from email import policy
from email.parser import BytesParser
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import urlparse

import pytest

from test_session_browser import ARGS, CHROMIUM, TIMEOUT, jspsych_dir, page, pw  # noqa: F401 (fixtures)

from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study, write_demo_record, write_test_video
from flipstudy.stimuli.contract import StimulusSet
from flipstudy.study.web import jspsych as jsp
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.order import web_trial_order
from flipstudy.study.web.site import export_site
from _screenshots import screenshot as _shot  # noqa: E402
from _site_names import condition_words, site_name, study_names  # noqa: E402

pytestmark = pytest.mark.skipif(not os.path.exists(CHROMIUM),
                                reason=f"needs Debian's chromium at {CHROMIUM} (apt-get install -y chromium)")

FAST = "backflip_abrupt-decrease_25"       # its video: 240 fps, frames must drop at 60 Hz
PID = "W01"
PAVLOVIA_API = "/api/v2/experiments/42/sessions"

#: A stand-in for jatos.js with the calls the site makes, posting to the test server.
JATOS_STANDIN = """
window.jatos = {
  urlQueryParameters: Object.fromEntries(new URLSearchParams(location.search)),
  onLoad(cb) { setTimeout(cb, 0); },
  appendResultData(data) {
    return fetch('/__jatos/resultData', {method: 'POST', body: data,
      headers: {'Content-Type': 'text/plain; charset=UTF-8'}}).then((r) => { if (!r.ok) throw new Error(r.status); });
  },
  endStudyAjax(successful, message) {
    return fetch('/__jatos/end?successful=' + successful, {method: 'POST', body: message || ''});
  },
  endStudy(successful) { return this.endStudyAjax(successful, 'endStudy'); },
};
"""


class _Host:
    """A static server of the site folder with the JATOS stand-in beside it."""

    def __init__(self, site: Path):
        self.bodies, self.ends, self.paths, self.pavlovia, self.saved = [], [], [], [], {}
        host = self

        class Handler(SimpleHTTPRequestHandler):
            def log_message(self, *a):
                pass

            def do_GET(self):
                host.paths.append(self.path)
                if self.path.split("?")[0] == "/config.json":    # what Pavlovia serves beside the site
                    self._json({"experiment": {"name": "demo", "fullpath": "lab/demo"},
                                "pavlovia": {"URL": f"http://127.0.0.1:{host.port}"},
                                "gitlab": {"projectId": 42}})
                    return
                if self.path.split("?")[0] == "/jatos.js":
                    body = JATOS_STANDIN.encode()
                    self.send_response(200)
                    self.send_header("Content-Type", "text/javascript")
                    self.send_header("Content-Length", str(len(body)))
                    self.end_headers()
                    self.wfile.write(body)
                    return
                super().do_GET()

            def _json(self, obj):
                body = json.dumps(obj).encode()
                self.send_response(200)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def do_DELETE(self):
                host.pavlovia.append(("DELETE", self.path, self._form()))
                self._json({})

            def _form(self):
                n = int(self.headers.get("Content-Length") or 0)
                raw = self.rfile.read(n)
                msg = BytesParser(policy=policy.default).parsebytes(
                    b"Content-Type: " + self.headers["Content-Type"].encode() + b"\r\n\r\n" + raw)
                return {part.get_param("name", header="content-disposition"): part.get_content()
                        for part in msg.iter_parts()} if msg.is_multipart() else {}

            def do_POST(self):
                if self.path.startswith(PAVLOVIA_API):           # Pavlovia's experiment API
                    form = self._form()
                    host.pavlovia.append(("POST", self.path, form))
                    if self.path.endswith("/sessions"):
                        self._json({"token": "T1", "experiment": {"status2": "RUNNING", "saveFormat": "CSV"}})
                    else:
                        host.saved[form["key"]] = form["value"]
                        self._json({})
                    return
                n = int(self.headers.get("Content-Length") or 0)
                body = self.rfile.read(n).decode()
                if self.path.startswith("/__jatos/resultData"):
                    host.bodies.append(body)
                elif self.path.startswith("/__jatos/end"):
                    host.ends.append(self.path)
                else:
                    self.send_error(404)
                    return
                self.send_response(200)
                self.send_header("Content-Length", "0")
                self.end_headers()

        self.srv = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Handler, directory=str(site)))
        self.port = self.srv.server_port
        self.thread = threading.Thread(target=self.srv.serve_forever, daemon=True)

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.srv.shutdown()
        self.srv.server_close()


@pytest.fixture
def study(tmp_path):
    d = make_demo_study(tmp_path / "study", levels=(0, 25), repetitions=2, break_every=3,
                        video_frames=12, video_fps=30.0, size=(160, 120))
    write_test_video(d / "render" / f"{FAST}.mp4", size=(160, 120), frames=96, fps=240.0)
    write_demo_record(d, StimulusSet.read(d, files=False), size=(160, 120), fps=30.0)
    return d




def _screen(page):
    return page.get_attribute("#jspsych-target", "data-screen-id")


def _wait_screen(page, sid):
    page.wait_for_selector(f'#jspsych-target[data-screen-id="{sid}"]')


def _answer(page, trial, response, how):
    _answer_on(page, f"trial-{trial}", response, how, trial)


def _answer_on(page, screen, response, how, n_answers):
    """Answer on the trial screen ``screen`` (clicking through breaks, the resume and
    the repeats screen on the way) and wait until ``n_answers`` answers are kept."""
    deadline = time.monotonic() + TIMEOUT / 1000
    while True:
        sid = _screen(page)
        if sid == screen:
            break
        if sid and (sid.startswith("break-") or sid in ("resume", "repeats")):
            page.click("#jspsych-html-button-response-btngroup button")
            page.wait_for_function(f"() => document.getElementById('jspsych-target').dataset.screenId !== '{sid}'")
            continue
        assert time.monotonic() < deadline, f"{screen} never came (screen {sid})"
        time.sleep(0.02)
    page.wait_for_selector("button.fs-correct:enabled")
    if how == "key":
        page.keyboard.press("f" if response == "correct" else "j")
    else:
        page.click(f"button.fs-{response}")
    page.wait_for_function(f"() => window.flipstudyState.checkpoint.answers().length >= {n_answers}")


RESP = ["correct", "incorrect", "incorrect", "correct", "correct", "incorrect", "correct", "incorrect"]
HOW = ["key", "click", "click", "key", "click", "key", "key", "click"]


def _csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _gate(page, origin, blocked):
    def gate(route):
        if urlparse(route.request.url).netloc == origin:
            route.continue_()
        else:
            blocked.append(route.request.url)
            route.abort()
    page.route("**/*", gate)


def _intro(page):
    _wait_screen(page, "instructions")
    page.click("#jspsych-instructions-next")
    _wait_screen(page, "demographics")
    page.fill("#fs-age", "41")
    page.check('input[name=gender][value="man"]')
    page.check('input[name=animation_experience][value="significant"]')
    page.check('input[name=gymnastics_experience][value="none"]')
    page.click("#jspsych-survey-html-form-next")
    page.wait_for_selector("button.fs-next:enabled")
    page.click("button.fs-next")


@contextlib.contextmanager
def _opened(page, site, participant, blocked):
    """The site served on 127.0.0.1, every other request blocked (and noted in
    ``blocked``), opened for ``participant`` and past the instructions and
    demographics; yields the host."""
    with _Host(site) as host:
        origin = f"127.0.0.1:{host.port}"
        _gate(page, origin, blocked)
        page.goto(f"http://{origin}/index.html?participant={participant}")
        _intro(page)
        yield host


@pytest.mark.slow
def test_pavlovia_site_saves_after_every_answer(page, tmp_path, jspsych_dir):  # noqa: F811
    """Pavlovia's protocol: a session opened, the records saved after each answer, closed at the end."""
    study = make_demo_study(tmp_path / "study", levels=(0, 25), repetitions=1, video_frames=12,
                            size=(96, 72))
    site = tmp_path / "site"
    export_site(study, site, host="pavlovia", iti_ms=20, jspsych_dir=jspsych_dir)
    assert "https://pavlovia.org" in (site / "index.html").read_text()     # connect-src: its API only
    blocked = []
    with _opened(page, site, "V07", blocked) as host:
        for i in (1, 2):
            _answer(page, i, RESP[i - 1], HOW[i - 1])
        page.wait_for_function("() => window.flipstudyState.checkpoint.s.sent >= "
                               "window.flipstudyState.checkpoint.records.length")
        (key, text), = host.saved.items()                  # one file per run, replaced each time
        assert key.startswith("demo_V07_r") and key.endswith(".csv")
        assert text.count(",answer,") == 2
        for i in (3, 4):
            _answer(page, i, RESP[i - 1], HOW[i - 1])
        page.wait_for_selector('#jspsych-target[data-saved="1"]')
    assert blocked == []
    assert [m for m, *_ in host.pavlovia][0] == "POST" and host.pavlovia[-1][0] == "DELETE"
    assert host.pavlovia[-1][2] == {"isCompleted": "true"}
    (key, text), = host.saved.items()
    f = tmp_path / key
    f.write_text(text)
    out = import_web(study, [f])
    assert out.answers == 4 and out.incomplete == ()
    got = _csv(study / "web" / "responses.csv")
    assert [r["response"] for r in got] == RESP[:4] and {r["source"] for r in got} == {"web-pavlovia"}
    assert _csv(study / "web" / "participants.csv")[0]["age"] == "41"


@pytest.mark.slow
def test_jatos_site_session_reload_import_analyze(page, study, jspsych_dir, tmp_path):  # noqa: F811
    site = tmp_path / "site"
    r = export_site(study, site, host="jatos", iti_ms=50, max_dropped_pct=10.0, jspsych_dir=jspsych_dir)
    assert r["n_trials"] == 8
    record = json.loads((site / "flipstudy-site.json").read_text())
    assert record["jspsych"]["version"] == jsp.PACKAGES["jspsych"] == "8.3.0"
    assert set(record["jspsych"]["packages"]) == set(jsp.PACKAGES)
    assert all(p["integrity"].startswith("sha512-") for p in record["jspsych"]["packages"].values())
    assert "lib/jspsych.js" in record["files"] and "node_modules" not in json.dumps(record["files"])
    html = (site / "index.html").read_text()
    assert "http" not in html.replace("http-equiv", "")          # no absolute URL at all

    blocked = []
    with _Host(site) as host:
        origin = f"127.0.0.1:{host.port}"

        def gate(route):
            u = urlparse(route.request.url)
            if u.netloc == origin:
                route.continue_()
            else:
                blocked.append(route.request.url)
                route.abort()
        page.route("**/*", gate)
        page.goto(f"http://{origin}/index.html?PROLIFIC_PID={PID}&STUDY_ID=s1")
        _wait_screen(page, "instructions")
        assert "some of them are not" in page.inner_text("#jspsych-target")
        # which tone is the left side: the sentence and the picture, as in the local runner
        assert "left arm and leg are the lighter tone" in page.inner_text(".fs-sides figcaption")
        assert page.eval_on_selector(".fs-sides img", "i => i.complete && i.naturalWidth") == 520
        page.click("#jspsych-instructions-next")
        _wait_screen(page, "demographics")
        page.check("#fs-age-none")
        page.check('input[name=gender][value="other"]')
        page.check('input[name=animation_experience][value="some"]')
        page.check('input[name=gymnastics_experience][value="none"]')
        page.click("#jspsych-survey-html-form-next")
        _wait_screen(page, "example-1")
        page.wait_for_selector("button.fs-again:enabled")
        page.click("button.fs-again")                          # watched again, then on
        page.wait_for_selector("button.fs-next:enabled")
        assert "Start the test" in page.inner_text("button.fs-next")
        page.click("button.fs-next")

        state = page.evaluate("window.flipstudyState.trials")
        twin = web_trial_order(json.loads((site / "config.js").read_text().split("= ", 1)[1].rstrip().rstrip(";"))["groups"],
                               2, 7, PID)
        assert [(t["trial"], t["stimulus"], t["repetition"]) for t in state] == \
               [(t.trial, t.stimulus, t.repetition) for t in twin]
        for i in range(1, 5):
            if i == 2:
                page.wait_for_selector('#jspsych-target[data-screen-id="trial-2"][data-playing="1"]')
                assert page.is_disabled("button.fs-correct")   # no answer while the motion plays
                page.keyboard.press("f")
                _shot(page, "web_trial.png", tmp_path)
            _answer(page, i, RESP[i - 1], HOW[i - 1])

        page.reload()                                          # in the middle: resume at trial 5
        _wait_screen(page, "resume")
        assert "continues with motion 5 of 8" in page.inner_text("#jspsych-target")
        for i in range(5, 9):
            _answer(page, i, RESP[i - 1], HOW[i - 1])
        _wait_screen(page, "end")
        page.wait_for_selector('#jspsych-target[data-saved="1"]')
        with page.expect_download() as dl:
            page.click("#fs-download")
        download = tmp_path / "download.jsonl"
        dl.value.save_as(download)
        assert host.ends, "the site did not end the JATOS study run"
        kept = page.evaluate("() => JSON.stringify(Object.assign({}, window.localStorage))")
        shown = page.get_attribute("#jspsych-target", "data-stimulus")
    assert blocked == []
    assert all(not p.startswith("/__") for p in host.paths)

    jatos_file = tmp_path / "jatos_result_data.txt"
    jatos_file.write_text("".join(host.bodies))
    lines = [json.loads(x) for x in jatos_file.read_text().splitlines()]
    assert [x["record"] for x in lines].count("start") == 1
    assert sorted(x["trial"] for x in lines if x["record"] == "answer") == list(range(1, 9))
    # issue 42: what the browser keeps and sends names no stimulus, group, kind or level
    words = condition_words(study)
    assert not [w for w in words if w in kept or w in jatos_file.read_text() or w in shown]
    assert not {"level", "kind", "clip"} & {k for x in lines for k in x}
    assert {x["stimulus"] for x in lines if x["record"] == "answer"} <= set(study_names(study))

    # JATOS's results archive (Export results: one data.txt per component result)
    archive = tmp_path / "jatos_results.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.write(jatos_file, "study_result_1/comp-result_1/data.txt")
    assert download.read_bytes() == jatos_file.read_bytes()     # the same records, in order
    imp = import_web(study, [archive, download])
    # issue 28.9: the download repeats the archive's records, so it is read but not kept
    assert [f.status for f in imp.files] == ["imported", "nothing new"]
    assert imp.files[0].new_answers == 8 and imp.files[1].new_answers == 0
    table_before = (study / "web" / "responses.csv").read_bytes()
    again = import_web(study, [download, archive, jatos_file])
    assert [f.status for f in again.files] == ["already imported"] * 3
    assert (study / "web" / "responses.csv").read_bytes() == table_before

    rows = _csv(study / "web" / "responses.csv")
    assert [r["trial"] for r in rows] == [str(i) for i in range(1, 9)]
    assert [r["response"] for r in rows] == RESP and [r["input"] for r in rows] == HOW
    assert {r["participant"] for r in rows} == {PID} and {r["source"] for r in rows} == {"web-jatos"}
    assert all(r["complete"] == "true" and r["simulated"] == "false" for r in rows)
    names = study_names(study)                                 # the site's opaque names mapped back
    assert [r["stimulus"] for r in rows] == [names[t.stimulus] for t in twin]
    fast = [r for r in rows if r["stimulus"] == FAST]
    slow = [r for r in rows if r["stimulus"] != FAST]
    assert len(fast) == 2 and all(r["playback_flagged"] == "true" for r in fast), fast
    assert all(int(r["frames_expected"]) == 96 and int(r["frames_dropped"]) > 9 for r in fast)
    assert any(r["playback_flagged"] == "false" for r in slow)
    assert all(r["timing"] == "rvfc" and int(r["frames_expected"]) == 12 for r in slow)
    assert all(float(r["refresh_hz"]) > 0 and float(r["video_ms"]) > 0 for r in rows)
    parts = _csv(study / "web" / "participants.csv")
    assert [(p["participant"], p["age"], p["gender"], p["answered"]) for p in parts] == [(PID, "", "other", "8")]
    assert json.loads((study / "web" / "dataset_description.json").read_text())["@type"] == "Dataset"

    out = tmp_path / "analysis"
    assert cli(["analyze", str(study / "web"), "--out", str(out), "--no-figures", "--no-gee",
                "--psychometric", "none", "--n-boot", "50"]) == 0
    table = _csv(out / "table.csv")
    assert sum(int(t["n"]) for t in table) == 8                # every answer exactly once
    cells = {(t["group"], float(t["level"])): int(t["n"]) for t in table}
    assert set(cells.values()) == {2}


def _config(site):
    return json.loads((site / "config.js").read_text().split("= ", 1)[1].rstrip().rstrip(";"))


def _download(page, tmp_path, name="download.jsonl"):
    _wait_screen(page, "end")
    page.wait_for_selector('#jspsych-target[data-saved="1"]')
    with page.expect_download() as dl:
        page.click("#fs-download")
    path = tmp_path / name
    dl.value.save_as(path)
    return path


@pytest.mark.slow
def test_flagged_trials_are_repeated_at_the_end(page, tmp_path, jspsych_dir):  # noqa: F811
    """[session] repeat_dropped = true: the 240 fps stimulus's two trials (flagged) come
    back after trial 8, in the trials' order, once each, with a reload between them;
    import-web keeps both answers of each; analyze counts the repeats instead."""
    study = make_demo_study(tmp_path / "study", levels=(0, 25), repetitions=2, break_every=3,
                            video_frames=12, video_fps=30.0, size=(160, 120), repeat_dropped=True,
                            max_dropped_pct=20)
    write_test_video(study / "render" / f"{FAST}.mp4", size=(160, 120), frames=96, fps=240.0)
    write_demo_record(study, StimulusSet.read(study, files=False), size=(160, 120), fps=30.0)
    site = tmp_path / "site"
    r = export_site(study, site, host="static", iti_ms=20, jspsych_dir=jspsych_dir)
    assert (r["max_dropped_pct"], r["repeat_dropped"]) == (20.0, True)      # the design's
    record = json.loads((site / "flipstudy-site.json").read_text())
    assert record["max_dropped_pct_from"] == "design" and record["repeat_dropped"] is True
    cfg = _config(site)
    assert cfg["max_dropped_pct"] == 20.0 and cfg["repeat_dropped"] is True
    twin = web_trial_order(cfg["groups"], 2, 7, PID)
    fast = [t.trial for t in twin if t.stimulus == site_name(study, FAST)]
    assert len(fast) == 2
    again = {fast[0]: "incorrect", fast[1]: "incorrect"}        # the repeats' answers
    first = {t.trial: "correct" for t in twin}                  # every first answer: correct
    blocked = []
    with _opened(page, site, PID, blocked) as host:
        for i in range(1, 9):
            _answer(page, i, first[i], HOW[i - 1])
        _wait_screen(page, "repeats")
        assert "2 motions did not play smoothly" in page.inner_text("#jspsych-target")
        page.click("#jspsych-html-button-response-btngroup button")
        _wait_screen(page, f"repeat-{fast[0]}")
        assert f"Once more: motion {fast[0]} of 8" in page.inner_text("#jspsych-target")
        _answer_on(page, f"repeat-{fast[0]}", again[fast[0]], "key", 9)
        page.reload()                                          # in the middle of the repeats
        _wait_screen(page, "resume")
        assert "Your first 8 answers are saved" in page.inner_text("#jspsych-target")
        _answer_on(page, f"repeat-{fast[1]}", again[fast[1]], "click", 10)
        download = _download(page, tmp_path)
        state = page.evaluate("window.flipstudyState.checkpoint.answers()")
    assert blocked == []
    assert [(a["trial"], a["repeat"]) for a in state] == \
        [(i, 0) for i in range(1, 9)] + [(fast[0], 1), (fast[1], 1)]  # each flagged trial once more
    lines = [json.loads(x) for x in download.read_text().splitlines()]
    assert lines[-1]["record"] == "end" and (lines[-1]["answered"], lines[-1]["repeats"]) == (8, 2)

    imp = import_web(study, [download])
    assert imp.answers == 10 and imp.incomplete == () and len(imp.repeats) == 2
    rows = _csv(study / "web" / "responses.csv")
    assert [(int(r["trial"]), r["repeat"]) for r in rows] == sorted(
        [(i, "0") for i in range(1, 9)] + [(fast[0], "1"), (fast[1], "1")])
    for t in fast:                                             # both answers of a flagged trial
        f0, f1 = [r for r in rows if int(r["trial"]) == t]
        assert (f0["repeat"], f0["response"], f0["playback_flagged"]) == ("0", "correct", "true")
        assert (f1["repeat"], f1["response"], f1["stimulus"]) == ("1", "incorrect", FAST)
        assert f1["max_dropped_pct"] == "20"
    assert all(r["playback_flagged"] == "false" for r in rows if r["stimulus"] != FAST)
    assert _csv(study / "web" / "participants.csv")[0]["answered"] == "8"

    out = tmp_path / "analysis"
    assert cli(["analyze", str(study / "web"), "--out", str(out), "--no-figures", "--no-gee",
                "--psychometric", "none", "--n-boot", "50"]) == 0
    table = _csv(out / "table.csv")
    assert sum(int(t["n"]) for t in table) == 8                # each trial once: the repeat for the flagged
    m = StimulusSet.read(study, files=False)[FAST]
    cells = {(t["group"], float(t["level"])): int(t["n_incorrect"]) for t in table}
    assert cells.pop((m.group, m.level)) == 2     # the repeats' "incorrect", not "correct"
    assert set(cells.values()) == {0}
    assert "Repeats: 2 trial(s)" in (out / "notes.md").read_text()


@pytest.mark.slow
def test_replay_is_counted_and_the_answer_kept_once(page, tmp_path, jspsych_dir):  # noqa: F811
    """[session] replay = true: a Replay button once the motion has been shown; while the
    replay plays no answer can be given; the answer's record counts the replays."""
    study = make_demo_study(tmp_path / "study", levels=(0, 25), repetitions=1, replay=True,
                            video_frames=12, size=(96, 72))
    site = tmp_path / "site"
    export_site(study, site, host="static", iti_ms=20, jspsych_dir=jspsych_dir)
    assert _config(site)["replay"] is True
    blocked = []
    with _opened(page, site, PID, blocked) as host:
        _wait_screen(page, "trial-1")
        for k in (1, 2):                                       # replayed twice
            page.wait_for_selector("button.fs-replay:enabled")
            assert page.is_enabled("button.fs-correct")
            locked = page.evaluate("""() => {
                document.querySelector('button.fs-replay').click();
                return ['correct', 'incorrect', 'replay'].map(
                    (c) => document.querySelector('button.fs-' + c).disabled); }""")
            assert locked == [True, True, True], k           # nothing to press while it plays again
            page.keyboard.press("f")                           # ignored: the answer waits for the end
            assert page.evaluate("window.flipstudyState.checkpoint.answers().length") == 0
        _answer(page, 1, "incorrect", "key")
        _answer(page, 2, "correct", "click")                   # not replayed
        for i in range(3, 5):
            _answer(page, i, RESP[i - 1], HOW[i - 1])
        download = _download(page, tmp_path)
        state = page.evaluate("window.flipstudyState.checkpoint.answers()")
    assert blocked == []
    assert [(a["trial"], a["replays"], a["response"]) for a in state[:2]] == \
        [(1, 2, "incorrect"), (2, 0, "correct")]
    assert [a["trial"] for a in state] == [1, 2, 3, 4]         # every answer stored once
    import_web(study, [download])
    rows = _csv(study / "web" / "responses.csv")
    assert [(r["trial"], r["replays"], r["response"]) for r in rows] == \
        [("1", "2", "incorrect"), ("2", "0", "correct")] + [(str(i), "0", RESP[i - 1]) for i in (3, 4)]
