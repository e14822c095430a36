"""Issue 42's "done when", item 1, in headless Chromium (every non-loopback request
blocked): the sessions guide's Prolific design — ``flipstudy init``'s design with the
guide's catch group, [online] and [exclusions] added, shown once (``repetitions = 1``, to
keep the test short) — exported for JATOS and answered by three participants: one
attentive, one answering "incorrect" to everything, one answering at random.  After
``import-web`` and ``analyze`` the attentive one is kept and the other two are excluded
by the catch rule, the tables keep the shared original's trials, and the same answers
given through the local session path give the same groups."""
import hashlib
import json
import os
import time
from urllib.parse import urlparse

import pandas as pd
import pytest

import test_web_browser
from test_session_browser import CHROMIUM, TIMEOUT, jspsych_dir, page, pw  # noqa: F401 (fixtures)
from test_prolific_between import BATCH_STANDIN
from _prolific import guide_prolific_tables
from _site_names import study_names

from flipstudy.stimuli.presets import PRESETS
from flipstudy.study.demo import write_demo_record, write_placeholder_study, write_test_video
from flipstudy.study.export import export_responses
from flipstudy.study.pipeline import analyze
from flipstudy.study.session import load_study, open_session, submit_answer
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.site import export_site

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason=f"needs Debian's chromium at {CHROMIUM}")]

FRAMES, FPS, SIZE = 6, 30.0, (96, 72)


def guide_design() -> str:
    """What the guide's first command writes (``flipstudy init``), shown once, with the
    guide's tables added."""
    text = PRESETS["flipping-with-physics-2007"]
    assert "repetitions = 2 " in text
    return text.replace("repetitions = 2 ", "repetitions = 1 ") + "\n" + guide_prolific_tables()


@pytest.fixture
def study(tmp_path):
    d = tmp_path / "study"
    rows = write_placeholder_study(d, guide_design(), frames=FRAMES, fps=FPS)
    for i, r in enumerate(rows):
        write_test_video(d / "render" / f"{r.stimulus}.mp4", size=SIZE, frames=FRAMES, fps=FPS,
                         color=((40 * i) % 255, 160, 90))
    write_demo_record(d, rows, size=SIZE, fps=FPS)
    (d / "consent.md").write_text("# Taking part\n\nYou will judge short animations. You may stop at any time.\n")
    (d / "debrief.md").write_text("Some motions were changed on purpose. Thank you!\n")
    return d


def _coin(stimulus: str) -> str:
    """A fair coin per motion (fixed, so that both paths give the same answers; this one
    is right on two of the four catch trials, as a coin is most often)."""
    return "incorrect" if hashlib.sha256(f"rnd3:{stimulus}".encode()).digest()[0] % 2 else "correct"


def answers(study):
    """role → answer(stimulus): right everywhere; "incorrect" to everything; a coin per motion."""
    level = {r.stimulus: r.level for r in load_study(study).manifest}
    return {"att": lambda s: "incorrect" if level[s] else "correct", "inc": lambda s: "incorrect", "rnd": _coin}


def _through(page, answer, think_ms=0, real=None):
    """Consent to the end screen, every trial answered by ``answer(stimulus)`` ``think_ms``
    after the buttons are shown (the examples and breaks clicked through); returns how many
    trials were answered.  ``real``: the study's map of the page's opaque names (the page
    names no stimulus)."""
    page.click("#fs-consent-yes")
    page.wait_for_selector('#jspsych-target[data-screen-id="instructions"]', timeout=60_000)
    page.click("#jspsych-instructions-next")
    page.wait_for_selector('#jspsych-target[data-screen-id="demographics"]')
    page.check("#fs-age-none")
    page.check('input[name=gender][value="other"]')
    page.check('input[name=animation_experience][value="none"]')
    page.check('input[name=gymnastics_experience][value="none"]')
    page.click("#jspsych-survey-html-form-next")
    n = page.evaluate("() => window.flipstudyState.trials.length")
    for i in range(1, n + 1):
        deadline = time.monotonic() + TIMEOUT / 1000
        while (sid := page.get_attribute("#jspsych-target", "data-screen-id")) != f"trial-{i}":
            if sid and sid.startswith(("break-", "example-")):      # the examples (one per clip), breaks
                button = "button.fs-next:enabled" if sid.startswith("example-") else \
                    "#jspsych-html-button-response-btngroup button"
                page.click(button)
                page.wait_for_function(f"() => document.getElementById('jspsych-target').dataset.screenId !== '{sid}'")
            assert time.monotonic() < deadline, f"trial {i} never came (screen {sid})"
            page.wait_for_timeout(10)
        page.wait_for_selector("button.fs-correct:enabled")
        if think_ms:
            page.wait_for_timeout(think_ms)
        shown = page.get_attribute('#jspsych-target', 'data-stimulus')
        page.click(f"button.fs-{answer(real[shown] if real is not None else shown)}")
        page.wait_for_function(f"() => window.flipstudyState.checkpoint.answers().length >= {i}")
    page.wait_for_selector('#jspsych-target[data-saved="1"]')
    return n


def _web(page, study, tmp_path, jspsych_dir, monkeypatch):  # noqa: F811
    """The three participants on the JATOS site (its batch session stand-in), imported."""
    site = tmp_path / "site"
    export_site(study, site, host="jatos", iti_ms=20, jspsych_dir=jspsych_dir)
    monkeypatch.setattr(test_web_browser, "JATOS_STANDIN", BATCH_STANDIN)
    batch, blocked = {"version": 0, "data": {}}, []
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
                    route.fulfill(status=200, content_type="application/json", body=json.dumps({"ok": ok, "batch": batch}))
                else:
                    route.fulfill(status=200, content_type="application/json", body=json.dumps(batch))
            else:
                route.continue_()
        page.route("**/*", gate)
        for role, answer in answers(study).items():
            page.goto(f"http://{origin}/index.html?PROLIFIC_PID=W{role}&STUDY_ID=63aa01&SESSION_ID=s{role}")
            page.wait_for_selector('#jspsych-target[data-screen-id="consent"]', timeout=60_000)
            n = _through(page, answer, think_ms=300 if role == "att" else 0,   # (the guide's min_median_rt_ms)
                         real=study_names(study))
    assert n == 48 and all("prolific.com" in u for u in blocked)          # only the completion redirects
    f = tmp_path / "jatos_results.txt"
    f.write_text("".join(host.bodies))
    import_web(study, [f])
    return study / "web" / "responses.csv"


def _local(study):
    """The same answers through the local session path (what `flipstudy run` stores)."""
    st = load_study(study)
    for role, answer in answers(study).items():
        s = open_session(st, f"L{role}")
        for t in s.trials:
            submit_answer(s, {"participant": s.participant, "session": s.session, "trial": t.trial,
                              "stimulus": t.stimulus, "response": answer(t.stimulus), "rt_ms": 700.0,
                              "shown_ms": 200.0, "late_frames": 0, "replays": 0, "input": "key"})
        s.close()
    export_responses(study)
    return study / "responses.csv"


def _analysed(csv, out):
    res = analyze([csv], out, psychometric="none", gee=False, n_boot=50, figures=False)
    rows = pd.read_csv(out / "responses_exclusions.csv", keep_default_na=False)
    rows["role"] = rows["participant"].str[1:]
    part = pd.read_csv(out / "exclusions_participants.csv", keep_default_na=False)
    return res, rows, part.assign(role=part["participant"].str[1:]).set_index("role"), pd.read_csv(out / "table.csv")


def test_the_guides_prolific_design_keeps_the_attentive_and_excludes_the_careless(
        page, study, tmp_path, jspsych_dir, monkeypatch):  # noqa: F811
    web = _analysed(_web(page, study, tmp_path, jspsych_dir, monkeypatch), tmp_path / "results")
    res, rows, part, table = web
    catch = rows[rows["group"] == "catch"]
    # the random one's answers to the catch trials (as its page gave them): under the guide's 75 %
    rnd = catch[catch["role"] == "rnd"]
    right = ((rnd["level"] == 0) == (rnd["response"] == "correct")).mean() * 100
    assert len(rnd) == 4 and right < 75
    flow = {f.stage: f.n for f in res.report.flow}
    assert flow["recruited"] == 3 and flow["excluded: catch accuracy"] == 2 and flow["analysed"] == 1
    assert part["exclusion_rule"].to_dict() == {"att": "", "inc": "catch accuracy", "rnd": "catch accuracy"}
    assert part["catch_trials"].to_dict() == {"att": 4, "inc": 4, "rnd": 4}    # what each saw: 2 clips × 2
    assert part.loc["rnd", "catch_accuracy_pct"] == right and part.loc["inc", "catch_accuracy_pct"] == 50
    # the shared original stays in its own group, never a catch trial, and its trials stay in the tables
    orig = rows[rows["stimulus"].str.endswith("_original")]
    assert len(orig) == 3 * 2 and set(orig["group"]) == {"original"} and not orig["catch"].any()
    assert set(rows.loc[rows["catch"], "group"]) == {"catch"} and rows["catch"].sum() == 3 * 4
    cells = table.set_index(["group", "level"])["n"]
    for g in ("smooth-increase", "smooth-decrease", "abrupt-increase", "abrupt-decrease"):
        assert cells[(g, 0.0)] == 2                                 # the attentive one's two originals
    assert cells[("takeoff-increase", 0.0)] == 2 and "catch" not in set(table["group"])
    assert res.report.settings.n_trials == 48 - 4              # the kept one's trials, catch ones left out
    # the local path: the same answers give the same groups, catch trials and exclusions
    _, lrows, lpart, ltable = _analysed(_local(study), tmp_path / "local")
    key = ["role", "stimulus", "group", "level", "catch", "response", "excluded", "exclusion_rule"]
    same = [r[key].sort_values(["role", "stimulus"]).reset_index(drop=True) for r in (lrows, rows)]
    pd.testing.assert_frame_equal(*same)
    pd.testing.assert_frame_equal(ltable, table)
    assert lpart["exclusion_rule"].to_dict() == part["exclusion_rule"].to_dict()
