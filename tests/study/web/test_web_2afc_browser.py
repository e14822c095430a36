"""2AFC on the exported jsPsych site, in headless Chromium (Debian's, through Playwright),
every request but the local static server's blocked; and export-web's refusal of
adaptive (QUEST+) groups.

The 2AFC study (one clip, a 2AFC group and a yes/no group, shown twice) is exported
for JATOS and run: the page's trial order and ``first`` are the Python twin's
(:func:`flipstudy.study.web.order.web_trial_order`); while each motion of a 2AFC pair
plays, the frame on the stage is read back and is the video ``first`` says; answers
by key and by click, a reload in the middle resumes at the next trial; ``import-web``
reads the JATOS data and ``analyze`` gives the 2AFC cells d′ = √2·z(P correct) —
recomputed here from the imported rows with scipy.
"""
import json
import math
import os
import time

import pytest

from test_session_browser import CHROMIUM, TIMEOUT, page, pw  # noqa: F401 (fixtures)
from test_web_browser import _config, _csv, _Host, _gate, _intro, _screen, _wait_screen, jspsych_dir  # noqa: F401
from _kinds import INTERVAL_COLOUR_JS, colour_of, design_text, make_study, nearest
from _screenshots import screenshot
from _site_names import study_names

from flipstudy.study.cli import main as cli
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.order import order_groups, web_trial_order
from flipstudy.errors import SiteError
from flipstudy.study.web.site import export_site, site_config
from flipstudy.study.session import load_study

pytestmark = pytest.mark.skipif(not os.path.exists(CHROMIUM),
                                reason=f"needs Debian's chromium at {CHROMIUM} (apt-get install -y chromium)")

GROUPS = [{"name": "smooth-increase", "sign": 1, "levels": [0, 25, 50], "task": "2afc"},
          {"name": "smooth-decrease", "sign": -1, "levels": [0, 40]}]
PID = "T01"

def _colour_while(page, interval):
    """The colour of the site's video while motion ``interval`` (1 or 2) plays."""
    c = page.evaluate(INTERVAL_COLOUR_JS, interval)
    assert c is not None, f"no frame of motion {interval} seen"
    return nearest(c)


def _answer(page, t, response, how, n_answers, check_colours=None, shot=None):
    """Answer trial ``t`` (2AFC or yes/no), clicking through breaks and the resume screen."""
    deadline = time.monotonic() + TIMEOUT / 1000
    sid = f"trial-{t.trial}"
    while True:
        cur = _screen(page)
        # colours: from the loading of the pair on, so the first motion is not missed
        if cur == sid or (check_colours is not None and cur in (f"load-{sid}", f"iti-{sid}")):
            break
        if cur and (cur.startswith("break-") or cur == "resume"):
            page.click("#jspsych-html-button-response-btngroup button")
            page.wait_for_function(f"() => document.getElementById('jspsych-target').dataset.screenId !== '{cur}'")
            continue
        assert time.monotonic() < deadline, f"{sid} never came (screen {cur})"
        time.sleep(0.02)
    if check_colours is not None:
        check_colours.append((_colour_while(page, 1), _colour_while(page, 2)))
        if shot is not None:
            screenshot(page, "web_2afc.png", shot)
    page.wait_for_selector(f"button.fs-{response}:enabled")
    keys = {"correct": "f", "incorrect": "j", "first": "f", "second": "j"}
    if how == "key":
        page.keyboard.press(keys[response])
    else:
        page.click(f"button.fs-{response}")
    page.wait_for_function(f"() => window.flipstudyState.checkpoint.answers().length >= {n_answers}")


@pytest.mark.slow
def test_2afc_site_session_import_analyze(page, tmp_path, jspsych_dir):  # noqa: F811
    study = make_study(tmp_path / "study", design_text(GROUPS, repetitions=2, break_every=3))
    site = tmp_path / "site"
    r = export_site(study, site, host="jatos", iti_ms=30, jspsych_dir=jspsych_dir)
    cfg = _config(site)
    site_twin = web_trial_order(cfg["groups"], 2, cfg["design_seed"], PID)      # in the site's opaque names
    st = load_study(study)
    twin = web_trial_order(order_groups(st.design, st.manifest), 2, cfg["design_seed"], PID)
    names = study_names(study)
    assert [(names[t.stimulus], names.get(t.original, ""), t.first) for t in site_twin] == \
        [(t.stimulus, t.original, t.first) for t in twin]      # the same trials, named by the map
    assert r["n_trials"] == len(twin) == 2 * 2 + 2 * 2      # 2AFC: 25 and 50 (0 is the comparison)
    two = [t for t in twin if t.task == "2afc"]
    assert sorted(t.first for t in two) == ["modified", "modified", "original", "original"]
    assert "two motions" in " ".join(cfg["texts"]["instructions"])
    yes = {"correct": "correct", "incorrect": "incorrect"}
    # 2AFC: the original chosen at 50 %, the modified motion at 25 % (d′ > 0 and d′ < 0)
    resp = {t.trial: (("first" if (t.first == "original") == (t.level == 50) else "second")
                      if t.task == "2afc" else list(yes)[t.trial % 2]) for t in twin}
    how = {t.trial: "key" if t.trial % 3 else "click" for t in twin}
    blocked, colours = [], {}
    with _Host(site) as host:
        origin = f"127.0.0.1:{host.port}"
        _gate(page, origin, blocked)
        page.goto(f"http://{origin}/index.html?participant={PID}")
        _intro(page)
        state = page.evaluate("window.flipstudyState.trials")
        assert [(s["trial"], s["stimulus"], s.get("task", "yes-no"), s.get("first", ""), s.get("original", ""))
                for s in state] == [(t.trial, t.stimulus, t.task, t.first, t.original) for t in site_twin]
        for k, t in enumerate(twin, start=1):
            if k == 5:
                page.reload()                                   # resume at trial 5
                _wait_screen(page, "resume")
                assert "continues with trial 5 of 8" in page.inner_text("#jspsych-target")
            seen = [] if t.task == "2afc" else None
            _answer(page, t, resp[t.trial], how[t.trial], k, seen,
                    shot=tmp_path if t == two[0] else None)
            if seen:
                colours[t.trial] = seen[0]
        _wait_screen(page, "end")
        page.wait_for_selector('#jspsych-target[data-saved="1"]')
    assert blocked == []
    for t in two:                                               # what was shown first
        order = [t.original, t.stimulus] if t.first == "original" else [t.stimulus, t.original]
        assert colours[t.trial] == tuple(colour_of(study, s) for s in order), t

    data = tmp_path / "jatos.txt"
    data.write_text("".join(host.bodies))
    imp = import_web(study, [data])
    assert imp.answers == 8 and imp.incomplete == ()
    rows = _csv(study / "web" / "responses.csv")
    assert [r["response"] for r in rows] == [resp[t.trial] for t in twin]
    assert [(r["task"], r["first"], r["original_stimulus"]) for r in rows] == [
        (t.task, t.first, t.original) for t in twin]
    assert all(int(r["frames_expected"]) == (24 if r["task"] == "2afc" else 12) for r in rows)

    out = tmp_path / "analysis"
    assert cli(["analyze", str(study / "web"), "--out", str(out), "--no-figures", "--no-gee",
                "--psychometric", "none", "--n-boot", "50"]) == 0
    from scipy.stats import norm
    table = [t for t in _csv(out / "table.csv") if t["group"] == "smooth-increase"]
    assert {t["task"] for t in _csv(out / "table.csv") if t["group"] == "smooth-decrease"} == {"yes-no"}
    assert sorted(float(t["level"]) for t in table) == [25.0, 50.0]
    for t in table:
        cell = [r for r in rows if r["group"] == t["group"] and float(r["level"]) == float(t["level"])]
        k = sum((r["response"] == "first") == (r["first"] == "original") for r in cell)
        assert t["task"] == "2afc" and int(t["n_correct"]) == k
        n = len(cell)           # the log-linear correction (the default) only for 0 or 1
        pc = (k + 0.5) / (n + 1) if k in (0, n) else k / n
        assert float(t["dprime"]) == pytest.approx(math.sqrt(2) * norm.ppf(pc), abs=1e-6), t
        assert (float(t["dprime"]) > 0) == (float(t["level"]) == 50)


def test_export_web_refuses_quest_groups_by_name(tmp_path):
    groups = [{"name": "steady", "sign": 1, "levels": [0, 25]},
              {"name": "staircase", "sign": -1, "levels": {"from": 0, "to": 60, "step": 5},
               "method": "quest+", "trials": 10}]
    study = make_study(tmp_path / "study", design_text(groups), videos=False)
    with pytest.raises(SiteError, match=r"'staircase'.*QUEST\+ runs in the local session runner"):
        site_config(load_study(study))
    with pytest.raises(SiteError, match="staircase"):
        export_site(study, tmp_path / "site", jspsych_dir=tmp_path)
    assert not (tmp_path / "site").exists()
    assert cli(["export-web", str(study), "--out", str(tmp_path / "site")]) != 0
    assert not (tmp_path / "site").exists()
    json.dumps(site_config(load_study(make_study(tmp_path / "ok", design_text(GROUPS), videos=False))))


@pytest.mark.slow
def test_2afc_replay_on_the_site_plays_both_again(page, tmp_path, jspsych_dir):  # noqa: F811
    """[session] replay = true: "Replay both" runs the pair again (nothing to answer while
    it plays); the answer is kept once with replays = 1."""
    study = make_study(tmp_path / "study", design_text(GROUPS[:1], repetitions=1, replay=True))
    site = tmp_path / "site"
    export_site(study, site, host="static", iti_ms=20, jspsych_dir=jspsych_dir)
    blocked = []
    with _Host(site) as host:
        origin = f"127.0.0.1:{host.port}"
        _gate(page, origin, blocked)
        page.goto(f"http://{origin}/index.html?participant={PID}")
        _intro(page)
        page.wait_for_selector("button.fs-replay:enabled")
        page.click("button.fs-replay")
        page.wait_for_selector('#jspsych-target[data-interval="1"][data-playing="1"]')
        assert page.query_selector("button.fs-first") is None          # no answer while it plays
        page.keyboard.press("f")
        page.wait_for_selector('#jspsych-target[data-interval="2"]')
        page.wait_for_selector("button.fs-second:enabled")
        assert page.evaluate("window.flipstudyState.checkpoint.answers().length") == 0
        page.click("button.fs-second")
        page.wait_for_function("() => window.flipstudyState.checkpoint.answers().length === 1")
        _answer(page, web_trial_order(_config(site)["groups"], 1, _config(site)["design_seed"], PID)[1],
                "first", "key", 2)
        answers = page.evaluate("window.flipstudyState.checkpoint.answers()")
    assert blocked == []
    assert [(a["trial"], a["replays"], a["response"], a["input"]) for a in answers] == [
        (1, 1, "second", "click"), (2, 0, "first", "key")]
