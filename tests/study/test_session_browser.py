"""Whole sessions in headless Chromium (Playwright for Python, sync API).

The page is the jsPsych site ``export-web`` builds, served by the local runner in its
``local`` host mode (the server is its data endpoint).

A tiny study (1 clip, 2 groups × 2 levels, 2 repetitions = 8 trials, a break
every 3 trials, 0.4 s videos) is run end to end: instructions, demographics,
the example of a correct motion, every trial answered by key or by click, and
the export checked row by row.  A second test kills the server with SIGKILL in
the middle of the session, twice, and finishes the session in the browser.

Chromium is Debian's (``/usr/bin/chromium``), never a Playwright download.
Set ``FLIPSTUDY_SCREENSHOTS=DIR`` to keep the screenshots.
"""
import csv
import os
import shutil
import socket
import sqlite3
import time
from pathlib import Path

import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]

pytestmark = pytest.mark.skipif(not os.path.exists(CHROMIUM),
                                reason=f"needs Debian's chromium at {CHROMIUM} "
                                       f"(apt-get install -y chromium)")
sync_api = pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install playwright)")

from _run_server import Run  # noqa: E402
from flipstudy.study.demo import make_demo_study  # noqa: E402
from flipstudy.study import store  # noqa: E402
from flipstudy.study.export import export_responses  # noqa: E402
from flipstudy.study.order import trial_order  # noqa: E402
from flipstudy.study.server import ServerThread, create_app  # noqa: E402
from flipstudy.study.session import load_study, open_session  # noqa: E402
from _screenshots import screenshot  # noqa: E402
from _site_names import study_names  # noqa: E402

BREAK_EVERY = 3
TIMEOUT = 15_000          # ms, for any one screen


@pytest.fixture(scope="session")
def jspsych_dir():
    """The pinned jsPsych packages (npm, cached): the page's lib/ (the local runner's too);
    skips when npm cannot fetch them."""
    from flipstudy.study.web import jspsych as jsp
    if shutil.which("npm") is None and not jsp.cache_root().is_dir():
        pytest.skip("needs npm to fetch jsPsych (apt-get install npm)")
    try:
        folder, _ = jsp.fetch()
    except jsp.JsPsychFetchError as e:
        pytest.skip(f"npm could not fetch jsPsych: {e}")
    return folder


@pytest.fixture(scope="module")
def pw():
    with sync_api.sync_playwright() as p:
        yield p


@pytest.fixture
def page(pw, tmp_path, jspsych_dir):
    ctx = pw.chromium.launch_persistent_context(
        str(tmp_path / "profile"), executable_path=CHROMIUM, headless=True, args=ARGS,
        viewport={"width": 900, "height": 760})
    pg = ctx.pages[0] if ctx.pages else ctx.new_page()
    pg.set_default_timeout(TIMEOUT)
    errors = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    yield pg
    ctx.close()
    assert not errors, errors


@pytest.fixture(scope="module")
def tiny_template(tmp_path_factory):
    return make_demo_study(tmp_path_factory.mktemp("tiny") / "study", levels=(0, 25), repetitions=2,
                           break_every=BREAK_EVERY, video_frames=12, video_fps=30.0)


@pytest.fixture
def tiny(tiny_template, tmp_path):
    d = tmp_path / "study"
    shutil.copytree(tiny_template, d)
    return d


@pytest.fixture
def tiny_replay(tiny):
    """The tiny study with replay = true in its design."""
    p = tiny / "design.toml"
    p.write_text(p.read_text().replace("replay = false", "replay = true"))
    return tiny




APP = "#jspsych-target"


def screen(page, sid):
    return page.wait_for_selector(f'{APP}[data-screen-id="{sid}"]')


def do_intro(page, *, age="23"):
    screen(page, "instructions")
    assert "some of them are not" in page.inner_text(APP)
    page.click("#jspsych-instructions-next")
    screen(page, "demographics")
    if age is None:
        page.check("#fs-age-none")
    else:
        page.fill("#fs-age", age)
    page.check('input[name=gender][value="woman"]')
    page.check('input[name=animation_experience][value="none"]')
    page.check('input[name=gymnastics_experience][value="some"]')
    page.click("#jspsych-survey-html-form-next")
    screen(page, "example-1")
    assert "correct motion" in page.inner_text(APP).lower()
    page.wait_for_selector("button.fs-next:enabled")
    page.click("button.fs-next")


def answer_trial(page, trial, response, how, replay=False):
    """Wait for ``trial`` (clicking through a break before it), check the buttons
    wait for the motion, then answer by key or click."""
    deadline = time.monotonic() + TIMEOUT / 1000
    while True:
        sid = page.get_attribute(APP, "data-screen-id")
        if sid == f"trial-{trial}":
            break
        if sid and sid.startswith("break-") or sid == "resume":
            page.click("#jspsych-html-button-response-btngroup button")
            page.wait_for_selector(f'{APP}:not([data-screen-id="{sid}"])')
            continue
        assert time.monotonic() < deadline, f"trial {trial} never came (screen {sid})"
        time.sleep(0.02)
    page.wait_for_selector("button.fs-correct:enabled")
    if replay:
        page.click("button.fs-replay")
        assert page.is_disabled("button.fs-correct")          # while the motion plays again
        page.wait_for_selector("button.fs-correct:enabled")
    if how == "key":
        page.keyboard.press("f" if response == "correct" else "j")
    else:
        page.click(f"button.fs-{response}")


def plan(n):
    """What the test answers: a mixed pattern, some by key and some by click."""
    resp = ["correct", "incorrect", "incorrect", "correct", "correct", "incorrect", "correct",
            "incorrect"][:n]
    how = ["key", "click", "click", "key", "click", "key", "key", "click"][:n]
    return resp, how


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def check_export(study_dir, tmp_path, participant, trials, resp, how, replayed=()):
    out = export_responses(study_dir, tmp_path / "export" / "responses.csv")
    rows = read_csv(out.responses)
    assert len(rows) == len(trials)
    for i, (r, t) in enumerate(zip(rows, trials), start=1):
        assert r["participant"] == participant and r["session"] == "1"
        assert r["trial"] == str(i) == str(t.trial)
        assert r["stimulus"] == t.stimulus and r["group"] == t.group
        assert r["level"] == f"{t.level:g}" and r["repetition"] == str(t.repetition)
        assert r["response"] == resp[i - 1], f"trial {i}"
        assert r["input"] == how[i - 1], f"trial {i}"
        assert 0 < float(r["rt_ms"]) < 60_000
        # a 12-frame clip at 30 fps is shown for ~400 ms
        assert 250 <= float(r["shown_ms"]) <= 2000, r["shown_ms"]
        assert int(r["late_frames"]) >= 0
        assert r["replays"] == ("1" if i in replayed else "0"), f"trial {i}"
        assert r["timestamp"].endswith("Z")
    return rows, read_csv(out.participants)


@pytest.mark.slow
def test_whole_session_in_chromium(page, tiny_replay, tmp_path):
    tiny = tiny_replay
    session = open_session(load_study(tiny), "P01")
    resp, how = plan(session.n_trials)
    assert session.n_trials == 8
    with ServerThread(create_app(session, iti_ms=50)) as srv:
        page.goto(srv.url)
        screen(page, "instructions")
        # which tone is the left side: the sentence and the picture (issue 42)
        assert "left arm and leg are the lighter tone" in page.inner_text(".fs-sides figcaption")
        assert page.eval_on_selector(".fs-sides img", "i => i.complete && i.naturalWidth") == 520
        shot = screenshot(page, "session_instructions.png", tmp_path)
        assert shot.stat().st_size <= 150_000
        do_intro(page)
        for i in range(1, session.n_trials + 1):
            if i == 2:
                # buttons are disabled and keys ignored until the motion has been shown
                page.wait_for_selector(f'{APP}[data-screen-id="trial-2"][data-playing="1"]')
                # the page knows the trial's stimulus by its opaque name only (issue 42)
                assert study_names(tiny)[page.get_attribute(APP, "data-stimulus")] == session.trials[1].stimulus
                assert page.is_disabled("button.fs-correct") and page.is_disabled("button.fs-incorrect")
                page.keyboard.press("f")
                shot = screenshot(page, "session_trial.png", tmp_path)
                assert shot.stat().st_size <= 150_000
            answer_trial(page, i, resp[i - 1], how[i - 1], replay=i == 5)
        screen(page, "end")
        assert "saved" in page.inner_text(APP)
    session.close()
    rows, parts = check_export(tiny, tmp_path, "P01", session.trials, resp, how, replayed={5})
    assert [(p["participant"], p["age"], p["gender"], p["animation_experience"],
             p["gymnastics_experience"], p["answered"]) for p in parts] == [
        ("P01", "23", "woman", "none", "some", "8")]
    assert parts[0]["finished"] == rows[-1]["timestamp"]


# --- kill -9 in the middle of a session ----------------------------------------------------

def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def Server(study_dir, participant, port):
    """``flipstudy run … --no-browser --port P`` as a subprocess."""
    return Run(study_dir, participant, "--port", str(port), "--iti-ms", "50")


def answers_in_db(study_dir):
    conn = sqlite3.connect(study_dir / "sessions.sqlite")
    try:
        return conn.execute("SELECT trial, response FROM responses ORDER BY trial").fetchall()
    finally:
        conn.close()


@pytest.mark.slow
def test_server_killed_mid_session_resumes_and_loses_nothing(page, tiny, tmp_path):
    port = _free_port()
    srv = Server(tiny, "K01", port)
    resp, how = plan(8)
    try:
        url = srv.start()
        assert url == f"http://127.0.0.1:{port}/"
        page.goto(url)
        do_intro(page, age=None)
        for i in (1, 2, 3):
            answer_trial(page, i, resp[i - 1], how[i - 1])
        screen(page, "break-3")                       # trial 3's answer is committed
        assert answers_in_db(tiny) == [(i, resp[i - 1]) for i in (1, 2, 3)]

        srv.kill9()                                   # 1: killed while the page is open
        answer_trial(page, 4, resp[3], how[3])        # the video was preloaded; the post waits
        page.wait_for_selector("#fs-banner:not([hidden])")
        assert "retrying" in page.inner_text("#fs-banner")
        assert len(answers_in_db(tiny)) == 3
        srv.start()
        screen(page, "trial-5")                       # the retried post went through
        answer_trial(page, 5, resp[4], how[4])
        screen(page, "trial-6")

        srv.kill9()                                   # 2: killed, restarted, page reloaded
        assert answers_in_db(tiny) == [(i, resp[i - 1]) for i in range(1, 6)]
        srv.start()
        page.goto(url)
        screen(page, "resume")
        assert "continues with motion 6 of 8" in page.inner_text(APP)
        for i in (6, 7, 8):
            answer_trial(page, i, resp[i - 1], how[i - 1])
        screen(page, "end")
    finally:
        srv.stop()
    conn = store.connect(tiny)
    trials = store.load_trials(conn, "K01", 1)
    conn.close()
    study = load_study(tiny)
    assert trials == trial_order(study.design, study.manifest, "K01")   # the saved order
    rows, parts = check_export(tiny, tmp_path, "K01", trials, resp, how)
    assert len({r["trial"] for r in rows}) == 8                          # each exactly once
    assert parts[0]["age"] == "" and parts[0]["finished"]
