"""2AFC and adaptive (QUEST+) sessions in headless Chromium (Debian's, through Playwright),
every request but the page's own (127.0.0.1) blocked.  The page is the jsPsych site of
``export-web`` in its ``local`` host mode, served by the local runner.

* A 2AFC study (one clip, two groups, levels 25 and 50 against each group's own
  original, shown twice: 8 trials) is answered by key and by click.  On two trials the
  frame on the stage is read while motion 1 and motion 2 play: each is the video the
  stored trial's ``first`` says (the placeholder videos have one colour each).  The
  answers are stored as "first"/"second", exported, and ``analyze`` gives each cell
  the 2AFC d′ = √2·z(P correct) — recomputed here from the exported rows with scipy.
* A yes/no constant-stimuli group interleaved with a QUEST+ group (yes/no, a grid of
  13 levels, 6 trials) runs in the page, with a reload in the middle: the adaptive
  trial shown after the reload is the one shown before it, and every adaptive level
  the page showed is the one a fresh QUEST+ (the engine, fed the stored answers one by
  one) picks.
"""
import csv
import math
import os
import time
from urllib.parse import urlparse

import pytest

from test_session_browser import ARGS, CHROMIUM, TIMEOUT, jspsych_dir, pw  # noqa: F401 (fixtures)
from _kinds import INTERVAL_COLOUR_JS, colour_of, design_text, make_study, nearest
from _site_names import study_names
from _screenshots import screenshot

pytestmark = pytest.mark.skipif(not os.path.exists(CHROMIUM),
                                reason=f"needs Debian's chromium at {CHROMIUM} (apt-get install -y chromium)")

from flipstudy.study.cli import main as cli  # noqa: E402
from flipstudy.study.export import export_responses  # noqa: E402
from flipstudy.study.server import ServerThread, create_app  # noqa: E402
from flipstudy.study.session import load_study, open_session  # noqa: E402


@pytest.fixture
def page(pw, tmp_path, jspsych_dir):  # noqa: F811
    """A Chromium page that reaches 127.0.0.1 only (every other request is aborted and
    noted in ``page.blocked``)."""
    ctx = pw.chromium.launch_persistent_context(
        str(tmp_path / "profile"), executable_path=CHROMIUM, headless=True, args=ARGS,
        viewport={"width": 900, "height": 820})
    pg = ctx.pages[0] if ctx.pages else ctx.new_page()
    pg.set_default_timeout(TIMEOUT)
    errors, blocked = [], []

    def gate(route):
        if urlparse(route.request.url).hostname == "127.0.0.1":
            route.continue_()
        else:
            blocked.append(route.request.url)
            route.abort()
    pg.route("**/*", gate)
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.blocked = blocked
    yield pg
    ctx.close()
    assert not errors, errors
    assert not blocked, blocked


APP = "#jspsych-target"


def _screen_id(page):
    return page.get_attribute(APP, "data-screen-id")


def _intro(page):
    page.wait_for_selector(f'{APP}[data-screen-id="instructions"]')
    page.click("#jspsych-instructions-next")
    page.wait_for_selector(f'{APP}[data-screen-id="demographics"]')
    page.check("#fs-age-none")
    page.check('input[name=gender][value="other"]')
    page.check('input[name=animation_experience][value="some"]')
    page.check('input[name=gymnastics_experience][value="none"]')
    page.click("#jspsych-survey-html-form-next")
    page.wait_for_selector(f'{APP}[data-screen-id="example-1"]')
    page.wait_for_selector("button.fs-next:enabled")
    page.click("button.fs-next")


def _reach(page, trial):
    """Wait for trial ``trial``'s screen, clicking through breaks and the resume screen."""
    deadline = time.monotonic() + TIMEOUT / 1000
    while True:
        sid = _screen_id(page)
        if sid == f"trial-{trial}":
            return page.get_attribute(APP, "data-screen")
        if sid and (sid.startswith("break-") or sid == "resume"):
            page.click("#jspsych-html-button-response-btngroup button")
            page.wait_for_selector(f'{APP}:not([data-screen-id="{sid}"])')
            continue
        assert time.monotonic() < deadline, f"trial {trial} never came (screen {sid})"
        time.sleep(0.02)


def _answer(page, trial, response, how):
    kind = _reach(page, trial)
    page.wait_for_selector(f"button.fs-{response}:enabled")
    keys = {"correct": "f", "incorrect": "j", "first": "f", "second": "j"}
    if how == "key":
        page.keyboard.press(keys[response])
    else:
        page.click(f"button.fs-{response}")
    # the next screen comes only once the server has stored the answer
    page.wait_for_selector(f'{APP}:not([data-screen-id="trial-{trial}"])')
    return kind


def _rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _seen_colour(page, interval):
    """The colour of the video on the stage while motion ``interval`` (1 or 2) plays."""
    c = page.evaluate(INTERVAL_COLOUR_JS, interval)
    assert c is not None, f"no frame of motion {interval} seen"
    return nearest(c)


TWO_AFC = [{"name": "smooth-increase", "sign": 1, "levels": [0, 25, 50], "task": "2afc"},
           {"name": "smooth-decrease", "sign": -1, "levels": [0, 25, 50], "task": "2afc"}]


@pytest.mark.slow
def test_2afc_session_in_chromium_stored_and_analysed(page, tmp_path):
    study_dir = make_study(tmp_path / "study", design_text(TWO_AFC, repetitions=2, replay=True, break_every=5))
    session = open_session(load_study(study_dir), "A01")
    trials = session.trials
    assert session.n_trials == 8 and {t.task for t in trials} == {"2afc"}
    assert {t.level for t in trials} == {25.0, 50.0}                # level 0 is the comparison
    firsts = [t.first for t in trials]
    assert sorted(set(firsts)) == ["modified", "original"]
    # the original chosen at 50 %, the modified motion at 25 %: d′ > 0 and d′ < 0
    resp = ["first" if (t.first == "original") == (t.level == 50) else "second" for t in trials]
    assert set(resp) == {"first", "second"}
    how = ["click", "key", "key", "click", "click", "key", "key", "click"]    # 1: the early F is not it
    with ServerThread(create_app(session, iti_ms=50)) as srv:
        page.goto(srv.url)
        page.wait_for_selector(f'{APP}[data-screen-id="instructions"]')
        text = page.inner_text(APP)
        assert "two motions" in text and "which one was physically correct" in text
        _intro(page)
        for i, t in enumerate(trials, start=1):
            if i in (1, 4):
                _reach(page, i)
                if i == 1:           # before both motions were shown, nothing answers
                    assert page.query_selector("button.fs-first") is None
                    page.keyboard.press("f")
                shown = [_seen_colour(page, 1), _seen_colour(page, 2)]
                order = [t.original, t.stimulus] if t.first == "original" else [t.stimulus, t.original]
                assert shown == [colour_of(study_dir, s) for s in order], (i, t.first)
                if i == 1:
                    assert page.text_content(f"{APP} .fs-interval") == "2"
                    shot = screenshot(page, "session_2afc.png", tmp_path)
                    assert shot.stat().st_size <= 200_000
            if i == 3:                                               # replay both, then answer
                _reach(page, i)
                page.wait_for_selector("button.fs-replay:enabled")
                page.click("button.fs-replay")                       # the pair plays again, no answer
                page.wait_for_selector(f'{APP}[data-interval="1"][data-playing="1"]')
                assert page.query_selector("button.fs-first") is None
            assert _answer(page, i, resp[i - 1], how[i - 1]) == "trial-2afc"
        page.wait_for_selector(f'{APP}[data-screen-id="end"]')
    session.close()

    out = export_responses(study_dir, tmp_path / "export" / "responses.csv")
    rows = _rows(out.responses)
    assert [r["response"] for r in rows] == resp and [r["input"] for r in rows] == how
    assert [r["first"] for r in rows] == firsts
    assert [r["task"] for r in rows] == ["2afc"] * 8
    assert [r["original_stimulus"] for r in rows] == [t.original for t in trials]
    assert [r["replays"] for r in rows] == ["0", "0", "1"] + ["0"] * 5
    # both motions were shown: 2 x 12 frames at 30 fps
    assert all(600 <= float(r["shown_ms"]) <= 4000 for r in rows), [r["shown_ms"] for r in rows]

    res = tmp_path / "analysis"
    assert cli(["analyze", str(out.responses), "--out", str(res), "--no-figures", "--no-gee",
                "--psychometric", "none", "--n-boot", "50"]) == 0
    table = _rows(res / "table.csv")
    from scipy.stats import norm
    for t in table:
        cell = [r for r in rows if r["group"] == t["group"] and float(r["level"]) == float(t["level"])]
        assert len(cell) == int(t["n"]) == 2
        # correct = the original chosen as the physically correct one
        k = sum((r["response"] == "first") == (r["first"] == "original") for r in cell)
        assert t["task"] == "2afc" and int(t["n_correct"]) == k
        n = len(cell)           # the log-linear correction (the default) only for 0 or 1
        pc = (k + 0.5) / (n + 1) if k in (0, n) else k / n
        assert float(t["dprime"]) == pytest.approx(math.sqrt(2) * norm.ppf(pc), abs=1e-6), t
        assert (float(t["dprime"]) > 0) == (float(t["level"]) == 50)


MIXED = [{"name": "smooth-increase", "sign": 1, "levels": [0, 25]},
         {"name": "smooth-decrease", "sign": -1, "levels": {"from": 0, "to": 60, "step": 5},
          "method": "quest+", "trials": 6}]


@pytest.mark.slow
def test_adaptive_group_interleaved_with_yes_no_survives_a_reload(page, tmp_path):
    from flipstudy.analysis.adaptive import Quest, QuestSettings, quest_model
    study_dir = make_study(tmp_path / "study", design_text(MIXED, repetitions=2, break_every=40))
    study = load_study(study_dir)
    session = open_session(study, "Q01")
    n = session.n_trials
    assert n == 4 + 6
    adaptive = [t.trial for t in session.trials if t.method == "quest+"]
    assert len(adaptive) == 6 and 1 < len([i for i in range(1, n + 1) if i not in adaptive])
    # a simulated observer: "incorrect" above 30 %, so QUEST+ has something to find
    answer = {}
    reload_at = adaptive[2]
    with ServerThread(create_app(session, iti_ms=30)) as srv:
        names = study_names(study_dir)
        page.goto(srv.url)
        page.wait_for_selector(f'{APP}[data-screen-id="instructions"]')
        assert "Judging motions" in page.inner_text(APP)
        _intro(page)
        for i in range(1, n + 1):
            kind = _reach(page, i)
            assert kind == "trial"
            page.wait_for_selector(f'{APP}[data-playing="0"] button.fs-correct:enabled')
            stim = page.get_attribute(APP, "data-stimulus")
            if i == reload_at:                                  # reload before answering
                page.reload()
                page.wait_for_selector(f'{APP}[data-screen-id="resume"]')
                assert f"continues with motion {i} of {n}" in page.inner_text(APP)
                _reach(page, i)
                page.wait_for_selector(f'{APP}[data-playing="0"] button.fs-correct:enabled')
                assert page.get_attribute(APP, "data-stimulus") == stim     # the same level
            level = study.by_name[names[stim]].level              # the page knows it by its opaque name
            answer[i] = "incorrect" if level > 30 else "correct"
            _answer(page, i, answer[i], "key" if i % 2 else "click")
        page.wait_for_selector(f'{APP}[data-screen-id="end"]')
        # only the current trial is served, and none once the session is finished
        status = page.evaluate("async () => (await fetch('/api/trial/1')).status")
        assert status == 409
    session.close()

    rows = _rows(export_responses(study_dir, tmp_path / "export" / "responses.csv").responses)
    assert [r["response"] for r in rows] == [answer[i] for i in range(1, n + 1)]
    quest_rows = [r for r in rows if r["method"] == "quest+"]
    assert [int(r["trial"]) for r in quest_rows] == adaptive
    g = next(g for g in study.design.groups if g.method == "quest+")
    q = Quest.new(quest_model(g.levels, "yes-no", QuestSettings(**vars(g.quest))))
    for r in quest_rows:
        assert float(r["level"]) == q.next_level()             # the level the engine picks
        q.update(float(r["level"]), r["response"] == "incorrect")
    assert float(quest_rows[-1]["quest_threshold"]) == pytest.approx(q.threshold()["threshold"])
