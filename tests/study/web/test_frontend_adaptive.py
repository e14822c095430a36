"""A QUEST+ group that stops early (``stop_width``), interleaved with a yes/no group, on
the one site in the local runner (headless Chromium, Debian's, through Playwright).

The group's interval is narrower than ``stop_width`` after its first answer, so the
server skips its other slots: the page must pass them over (never asking the server
for a trial that is not the current one), before and after a reload, and end with
every trial it showed stored once and nothing else.
"""
import os
import time

import pytest

from test_session_browser import APP, CHROMIUM, TIMEOUT, answers_in_db, jspsych_dir, page, pw  # noqa: F401
from test_session_2afc_browser import _intro
from _kinds import design_text, make_study

from flipstudy.study.server import ServerThread, create_app
from flipstudy.study.session import load_study, open_session

pytestmark = pytest.mark.skipif(not os.path.exists(CHROMIUM),
                                reason=f"needs Debian's chromium at {CHROMIUM} (apt-get install -y chromium)")

GROUPS = [{"name": "smooth-increase", "sign": 1, "levels": [0, 25]},
          {"name": "smooth-decrease", "sign": -1, "levels": {"from": 0, "to": 60, "step": 5},
           "method": "quest+", "trials": 6, "stop_width": 1000}]


@pytest.mark.slow
def test_skipped_quest_slots_are_passed_over_before_and_after_a_reload(page, tmp_path):  # noqa: F811
    study_dir = make_study(tmp_path / "study", design_text(GROUPS, repetitions=2, break_every=40))
    session = open_session(load_study(study_dir), "S01")
    adaptive = [t.trial for t in session.trials if t.method == "quest+"]
    assert session.n_trials == 10 and len(adaptive) == 6
    shown, reloaded = [], False
    with ServerThread(create_app(session, iti_ms=30)) as srv:
        page.goto(srv.url)
        _intro(page)
        deadline = time.monotonic() + 10 * TIMEOUT / 1000
        while True:
            assert time.monotonic() < deadline, f"no end (shown {shown})"
            sid = page.get_attribute(APP, "data-screen-id") or ""
            if sid == "end":
                break
            assert sid != "error", page.inner_text(APP)
            if sid in ("resume",) or sid.startswith("break-"):
                page.click("#jspsych-html-button-response-btngroup button")
                page.wait_for_selector(f'{APP}:not([data-screen-id="{sid}"])')
                continue
            if sid.startswith("trial-") and page.query_selector("button.fs-correct:enabled"):
                trial = int(sid.split("-")[1])
                page.keyboard.press("f")
                # the page moves on only once the server has stored the answer
                page.wait_for_selector(f'{APP}:not([data-screen-id="{sid}"])', state="attached")
                shown.append(trial)
                if trial in adaptive and not reloaded:
                    reloaded = True                 # the group has stopped: reload the page
                    page.reload()
                    page.wait_for_selector(f'{APP}[data-screen-id="resume"]')
                continue
            time.sleep(0.02)
        assert "saved" in page.inner_text(APP)
    skipped = session.skipped()
    session.close()
    assert len([t for t in shown if t in adaptive]) == 1 and skipped == adaptive[1:]
    assert [t for t, _ in answers_in_db(study_dir)] == shown == sorted(shown)     # each shown once, stored once
    assert len(shown) == 5
