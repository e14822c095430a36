"""One front end: the local runner (``flipstudy run``) serves the jsPsych site that
``export-web`` builds, in its ``local`` host mode, with the server as its data endpoint.

* The site's code (flipstudy's scripts and CSS, jsPsych's bundles under ``lib/``) is the
  same bytes whether the local server serves it or ``export-web`` writes it for JATOS or
  Pavlovia; only ``config.js`` (the host) and ``index.html`` (JATOS's script tag,
  Pavlovia's API in the CSP) differ.
* In headless Chromium (Debian's, through Playwright), every request not to 127.0.0.1
  blocked and none seen, one study is run three times on that code: by the local runner
  (a subprocess killed with SIGKILL twice mid-session: once while the page is open and
  an answer is on its way, once followed by a restart and a page reload), on a JATOS
  stand-in (with a reload) and on a Pavlovia stand-in.  Every answer given is stored
  exactly once: one row per trial in ``sessions.sqlite``, one answer record per trial in
  JATOS's result data and in Pavlovia's saved file, each with the response clicked or
  keyed.
"""
import csv
import io
import json
import os
import sqlite3
from urllib.parse import urlparse

import pytest

from test_session_browser import (CHROMIUM, Server, _free_port, answer_trial, do_intro, jspsych_dir,  # noqa: F401
                                  page, plan, pw, screen)
from test_web_browser import _Host, _answer, _intro

from flipstudy.study.demo import make_demo_study
from flipstudy.study.server import local_site
from flipstudy.study.session import load_study, open_session
from flipstudy.study.web.site import OWN_FILES, export_site

pytestmark = pytest.mark.skipif(not os.path.exists(CHROMIUM),
                                reason=f"needs Debian's chromium at {CHROMIUM} (apt-get install -y chromium)")

#: the site's code: what must be the same bytes on every host
CODE = set(OWN_FILES) | {"lib/jspsych.js", "lib/jspsych.css", "lib/plugin-video-button-response.js"}


@pytest.fixture
def study(tmp_path):
    return make_demo_study(tmp_path / "study", levels=(0, 25), repetitions=2, break_every=3,
                           video_frames=12, video_fps=30.0, size=(96, 72))


def _code_requests(page, origin, seen, blocked):
    """Let only ``origin`` through (others are aborted and noted in ``blocked``) and note
    the site's code files the page loads in ``seen``."""
    def gate(route):
        u = urlparse(route.request.url)
        if u.netloc != origin:
            blocked.append(route.request.url)
            return route.abort()
        name = u.path.lstrip("/")
        if name.endswith((".js", ".css")) and name not in ("config.js", "jatos.js"):
            seen.add(name)
        route.continue_()
    page.unroute("**/*")
    page.route("**/*", gate)


def test_local_server_serves_the_bytes_export_web_writes(study, tmp_path, jspsych_dir):  # noqa: F811
    session = open_session(load_study(study), "P01")
    served = local_site(session, iti_ms=50, jspsych_dir=jspsych_dir)
    session.close()
    assert CODE <= set(served)
    for host in ("jatos", "pavlovia"):
        site = tmp_path / host
        export_site(study, site, host=host, iti_ms=50, jspsych_dir=jspsych_dir)
        written = {p.relative_to(site).as_posix() for p in site.rglob("*") if p.is_file()}
        code = {n for n in written if n.endswith((".js", ".css")) and n != "config.js"}
        assert code == {n for n in served if n.endswith((".js", ".css")) and n != "config.js"}
        for name in code:
            assert (site / name).read_bytes() == served[name], (host, name)
        cfg = json.loads((site / "config.js").read_text().split("=", 1)[1].rstrip().rstrip(";"))
        assert cfg["host"] == host
    cfg = json.loads(served["config.js"].decode().split("=", 1)[1].rstrip().rstrip(";"))
    assert cfg["host"] == "local" and cfg["n_trials"] == 8 and cfg["groups"] == []


def _rows_in_db(study_dir):
    conn = sqlite3.connect(study_dir / "sessions.sqlite")
    try:
        return conn.execute("SELECT participant, trial, response, input FROM responses "
                            "ORDER BY participant, trial").fetchall()
    finally:
        conn.close()


@pytest.mark.slow             # ~35 s of three browser sessions; tests/study/test_session_browser.py and
# test_frontend_errors.py drive the same site by default
def test_local_jatos_and_pavlovia_sessions_drive_the_same_site(page, study, tmp_path, jspsych_dir):  # noqa: F811
    resp, how = plan(8)
    blocked, loaded = [], {}

    # 1. the local runner, killed twice
    port = _free_port()
    srv = Server(study, "L01", port)
    loaded["local"] = set()
    try:
        url = srv.start()
        _code_requests(page, f"127.0.0.1:{port}", loaded["local"], blocked)
        page.goto(url)
        do_intro(page, age=None)
        for i in (1, 2, 3):
            answer_trial(page, i, resp[i - 1], how[i - 1])
        screen(page, "break-3")
        srv.kill9()                                   # the page is open, trial 4 comes next
        answer_trial(page, 4, resp[3], how[3])        # its answer waits for the server
        page.wait_for_selector("#fs-banner:not([hidden])")
        assert len(_rows_in_db(study)) == 3
        srv.start()
        screen(page, "trial-5")                       # stored once the server was back
        answer_trial(page, 5, resp[4], how[4])
        screen(page, "trial-6")
        srv.kill9()
        srv.start()
        page.goto(url)                                # a reload resumes from the server's state
        screen(page, "resume")
        for i in (6, 7, 8):
            answer_trial(page, i, resp[i - 1], how[i - 1])
        screen(page, "end")
    finally:
        srv.stop()
    assert _rows_in_db(study) == [("L01", i, resp[i - 1], how[i - 1]) for i in range(1, 9)]

    # 2. JATOS and 3. Pavlovia: the exported sites of the same study, on stand-ins
    results = {}
    for host in ("jatos", "pavlovia"):
        site = tmp_path / f"site-{host}"
        export_site(study, site, host=host, iti_ms=50, jspsych_dir=jspsych_dir)
        loaded[host] = set()
        with _Host(site) as h:
            origin = f"127.0.0.1:{h.port}"
            _code_requests(page, origin, loaded[host], blocked)
            page.goto(f"http://{origin}/index.html?participant=W{host[0].upper()}1")
            _intro(page)
            for i in range(1, 9):
                if i == 5 and host == "jatos":
                    page.reload()                     # resumes from the checkpoint
                _answer(page, i, resp[i - 1], how[i - 1])
            page.wait_for_selector('#jspsych-target[data-saved="1"]')
            results[host] = (list(h.bodies), dict(h.saved))

    assert blocked == []
    assert loaded["local"] == loaded["jatos"] == loaded["pavlovia"]
    assert CODE <= loaded["local"]

    bodies, _ = results["jatos"]
    records = [json.loads(line) for b in bodies for line in b.splitlines() if line.strip()]
    answers = [r for r in records if r["record"] == "answer"]
    assert [(r["trial"], r["response"], r["input"]) for r in answers] == \
        [(i, resp[i - 1], how[i - 1]) for i in range(1, 9)]          # each once, in order
    _, saved = results["pavlovia"]
    (key, text), = saved.items()
    rows = [r for r in csv.DictReader(io.StringIO(text)) if r["record"] == "answer"]
    assert [(int(r["trial"]), r["response"], r["input"]) for r in rows] == \
        [(i, resp[i - 1], how[i - 1]) for i in range(1, 9)]
