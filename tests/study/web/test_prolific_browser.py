"""Issue 32 in headless Chromium, every non-loopback request blocked: a Prolific link
through the exported JATOS site (consent, preload with a progress bar, the recruiter's
ids on every row, the completion redirect taken), a catch trial answered wrongly that
`analyze` excludes with the rule named, consent refused (nothing recorded), and a
host that answers with errors and then recovers (every answer stored once).

Set ``FLIPSTUDY_SCREENSHOTS=DIR`` to keep the screenshots (docs/img/web_consent.png
and docs/img/web_preload.png come from there)."""
import json
import os
import time
from urllib.parse import parse_qs, urlparse

import pandas as pd
import pytest

from test_session_browser import CHROMIUM, TIMEOUT, jspsych_dir, page, pw  # noqa: F401 (fixtures)
from test_web_browser import _Host
from _screenshots import screenshot as _shot
from _prolific import CATCH_GROUP, web_records, write_jsonl

from flipstudy.study.demo import make_demo_study
from flipstudy.study.pipeline import analyze
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.site import export_site

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason=f"needs Debian's chromium at {CHROMIUM}")]

PID, STUDY_ID, SESSION_ID, CODE = "5f1a2b3c4d5e6f7a8b9c0d1e", "63aa01", "sess42", "C7XK2P"
ONLINE = CATCH_GROUP + f"""
[online]
completion_code = "{CODE}"
consent = "consent.md"
debrief = "debrief.md"
min_width = 320
min_height = 240

[exclusions]
catch_groups = ["catch"]
min_catch_accuracy_pct = 100.0
"""
CONSENT = """# Taking part

You will watch short animations of a figure doing a flip and say whether each motion is
**physically correct**. It takes about 5 minutes.

- Your answers are stored with your Prolific ID only.
- You may stop at any time by closing the page.
"""


@pytest.fixture
def study(tmp_path):
    d = make_demo_study(tmp_path / "study", levels=(0, 25), repetitions=1, video_frames=12, size=(96, 72),
                        extra=ONLINE)
    (d / "consent.md").write_text(CONSENT)
    (d / "debrief.md").write_text("Some motions were changed on purpose. Thank you!")
    return d


def _site(study, tmp_path, jspsych_dir, host="jatos"):
    site = tmp_path / f"site-{host}"
    export_site(study, site, host=host, iti_ms=20, jspsych_dir=jspsych_dir)
    return site


def _route(page, origin, blocked, fail=None, hold=None):
    """Only the test server; ``fail(request)`` True: answer HTTP 500 in its place;
    ``hold``: {"pass": k, "held": []}: videos after the first k wait in ``held``."""
    def gate(route):
        u = urlparse(route.request.url)
        if u.netloc != origin:
            blocked.append(route.request.url)
            route.abort()
        elif fail is not None and fail(route.request):
            route.fulfill(status=500, body="down")
        elif hold is not None and u.path.endswith(".mp4") and hold["pass"] <= 0 and hold["on"]:
            hold["held"].append(route)
        else:
            if hold is not None and u.path.endswith(".mp4"):
                hold["pass"] -= 1
            route.continue_()
    page.route("**/*", gate)


def _screen(page):
    return page.get_attribute("#jspsych-target", "data-screen-id")


def _through(page, n, answer, consent=True):
    """From the consent screen (``consent`` False: after it) to the end: agree,
    instructions, demographics, the example, then the n trials answered by ``answer(stimulus)``."""
    if consent:
        page.click("#fs-consent-yes")
    page.wait_for_selector('#jspsych-target[data-screen-id="instructions"]')
    page.click("#jspsych-instructions-next")
    page.wait_for_selector('#jspsych-target[data-screen-id="demographics"]')
    page.check("#fs-age-none")
    page.check('input[name=gender][value="other"]')
    page.check('input[name=animation_experience][value="none"]')
    page.check('input[name=gymnastics_experience][value="none"]')
    page.click("#jspsych-survey-html-form-next")
    page.wait_for_selector("button.fs-next:enabled")
    page.click("button.fs-next")
    for i in range(1, n + 1):
        page.wait_for_selector(f'#jspsych-target[data-screen-id="trial-{i}"]')
        page.wait_for_selector("button.fs-correct:enabled")
        stim = page.get_attribute("#jspsych-target", "data-stimulus")
        page.click(f"button.fs-{answer(stim)}")
        page.wait_for_function(f"() => window.flipstudyState.checkpoint.answers().length >= {i}")


def _records(bodies):
    return [json.loads(line) for b in bodies for line in b.splitlines() if line.strip()]


def test_prolific_link_end_to_end_ids_redirect_catch_exclusion(page, study, tmp_path, jspsych_dir):  # noqa: F811
    site = _site(study, tmp_path, jspsych_dir)
    cfg = json.loads((site / "config.js").read_text().split("= ", 1)[1].rstrip().rstrip(";"))
    n = cfg["n_trials"]
    assert n == 5 and "<strong>physically correct</strong>" in cfg["online"]["consent_html"]
    blocked = []
    with _Host(site) as host:
        origin = f"127.0.0.1:{host.port}"
        hold = {"pass": 2, "held": [], "on": True}
        _route(page, origin, blocked, hold=hold)
        page.goto(f"http://{origin}/index.html?PROLIFIC_PID={PID}&STUDY_ID={STUDY_ID}&SESSION_ID={SESSION_ID}")
        page.wait_for_selector('#jspsych-target[data-screen-id="consent"]')
        assert "Prolific ID only" in page.inner_text("#jspsych-target")
        # the text's own heading is the page's title: no "Consent" above it (issue 42)
        assert page.locator(".fs-consent h1, .fs-consent h2").all_inner_texts() == ["Taking part"]
        assert host.bodies == []                                   # nothing before consent
        _shot(page, "web_consent.png", tmp_path)
        page.click("#fs-consent-yes")
        page.wait_for_selector('#jspsych-target[data-screen-id="preload"]')
        page.wait_for_selector("#jspsych-loading-progress-bar-container")
        page.wait_for_function("() => parseFloat(document.getElementById('jspsych-loading-progress-bar')"
                               ".style.width) > 0")                    # two of six videos in
        _shot(page, "web_preload.png", tmp_path)
        hold["on"] = False
        for route in hold["held"]:
            route.continue_()
        # everything answered "correct": the catch trial (a gross error) is answered wrongly
        _through(page, n, lambda stim: "correct", consent=False)
        page.wait_for_selector('#jspsych-target[data-saved="1"]')
        assert CODE in page.inner_text("#fs-code") and "changed on purpose" in page.inner_text("#jspsych-target")
        deadline = time.monotonic() + TIMEOUT / 1000
        while not any("prolific.com" in u for u in blocked):       # the completion redirect, taken
            assert time.monotonic() < deadline, blocked
            page.wait_for_timeout(50)
    redirect, = [u for u in blocked if "prolific.com" in u]
    assert urlparse(redirect).path == "/submissions/complete" and parse_qs(urlparse(redirect).query) == {"cc": [CODE]}
    assert all("prolific.com" in u for u in blocked)               # nothing else left the machine
    recs = _records(host.bodies)
    assert recs[0]["record"] == "start" and recs[0]["consent"] and recs[0]["screen_ok"] is True
    assert all(r["PROLIFIC_PID"] == PID and r["STUDY_ID"] == STUDY_ID and r["SESSION_ID"] == SESSION_ID for r in recs)

    f = tmp_path / "jatos.jsonl"
    f.write_text("".join(host.bodies))
    # a second participant (records as the site writes them) who answers the catch trial right
    other = "6a0b1c2d3e4f5a6b7c8d9e0f"
    f2 = write_jsonl(tmp_path / "other.jsonl", web_records(
        study, other, run="r2", site_id=recs[0]["site_id"], PROLIFIC_PID=other,
        response=lambda t: "incorrect" if t.level else "correct"))
    import_web(study, [f, f2])
    rows = pd.read_csv(study / "web" / "responses.csv", dtype=str, keep_default_na=False)
    mine = rows[rows["participant"] == PID]
    assert len(mine) == n and set(mine["PROLIFIC_PID"]) == {PID} and set(mine["STUDY_ID"]) == {STUDY_ID} \
        and set(mine["SESSION_ID"]) == {SESSION_ID}
    res = analyze([study / "web" / "responses.csv"], tmp_path / "analysis", psychometric="none", gee=False,
                  n_boot=50, figures=True)
    flow = {f.stage: f.n for f in res.report.flow}
    assert flow["recruited"] == 2 and flow["excluded: catch accuracy"] == 1 and flow["analysed"] == 1
    kept = pd.read_csv(tmp_path / "analysis" / "responses_exclusions.csv", dtype=str, keep_default_na=False)
    assert set(kept.loc[kept["participant"] == PID, "exclusion_rule"]) == {"catch accuracy"}
    assert (tmp_path / "analysis" / "flow.png").is_file()


def test_consent_refused_ends_the_study_without_data(page, study, tmp_path, jspsych_dir):  # noqa: F811
    site = _site(study, tmp_path, jspsych_dir)
    blocked = []
    with _Host(site) as host:
        origin = f"127.0.0.1:{host.port}"
        _route(page, origin, blocked)
        page.goto(f"http://{origin}/index.html?PROLIFIC_PID={PID}")
        page.wait_for_selector('#jspsych-target[data-screen-id="consent"]')
        page.click("#fs-consent-no")
        page.wait_for_selector('#jspsych-target[data-screen-id="no-consent"]')
        assert "Nothing was recorded" in page.inner_text("#jspsych-target")
        page.wait_for_timeout(500)
        kept = page.evaluate("() => Object.keys(localStorage).filter((k) => k.startsWith('flipstudy:'))")
    assert host.bodies == [] and host.ends == [] and kept == [] and blocked == []


def test_host_errors_then_recovery_lose_nothing(page, study, tmp_path, jspsych_dir):  # noqa: F811
    site = _site(study, tmp_path, jspsych_dir)
    n = 5
    blocked, seen = [], {"posts": 0}
    down = {"on": True}

    def fail(request):
        if "/__jatos/resultData" not in request.url:
            return False
        seen["posts"] += 1
        return down["on"] and (seen["posts"] % 2 == 1)            # every other send fails while "on"
    with _Host(site) as host:
        origin = f"127.0.0.1:{host.port}"
        _route(page, origin, blocked, fail=fail)
        page.goto(f"http://{origin}/index.html?PROLIFIC_PID={PID}")
        page.wait_for_selector('#jspsych-target[data-screen-id="consent"]')
        _through(page, n - 1, lambda stim: "incorrect")
        seen_before = seen["posts"]
        page.unroute("**/*")
        _route(page, origin, blocked, fail=lambda r: "/__jatos/resultData" in r.url and down["on"])
        page.wait_for_selector(f'#jspsych-target[data-screen-id="trial-{n}"]')
        page.wait_for_selector("button.fs-correct:enabled")
        page.click("button.fs-correct")
        page.wait_for_selector('#jspsych-target[data-send-failing="1"]', timeout=40_000)
        assert "download" in page.inner_text("#fs-end-status").lower()
        with page.expect_download() as dl:                         # offered while it keeps failing
            page.click("#fs-download")
        saved = [json.loads(x) for x in open(dl.value.path()).read().splitlines()]
        assert sum(r["record"] == "answer" for r in saved) == n
        down["on"] = False                                         # the host recovers
        page.wait_for_selector('#jspsych-target[data-saved="1"]', timeout=40_000)
        assert seen_before > 0
    recs = _records(host.bodies)
    answers = [r for r in recs if r["record"] == "answer"]
    assert sorted(r["trial"] for r in answers) == list(range(1, n + 1))       # each once, none lost
    assert [r["record"] for r in recs].count("start") == 1 and [r["record"] for r in recs].count("end") == 1
    assert [r for r in blocked if "prolific.com" not in r] == []
