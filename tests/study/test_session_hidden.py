"""Issue 42, item 2, on the local runner: conditions hidden from the participant.

The local runner's server (uvicorn on a socket, in a thread: :class:`ServerThread`)
serves a study with a yes/no group, a 2AFC group and the sessions guide's catch group;
``flipstudy run`` (a subprocess, tests/_support/_run_server.py) one that also has a
QUEST+ group (slow: QUEST+'s model takes a second to build).  Each test does over HTTP
what the participant's page does: it loads the page and every file it names, the
timeline, each trial's screen and videos, posts the demographics and every answer, and
at each trial what a curious participant might try (another trial's video, a stimulus's
real name as a video or in an answer).  No response names a stimulus, a
group, an error kind, a profile or a level: the page's own files (config.js, index.html)
and every JSON reply are searched for each of them, the site's code (flipstudy's scripts
and CSS, jsPsych's bundles) must be the package's bytes, the same for every study, and no
trial screen or reply carries a clip, kind, group or level.  Each answer is stored under
its real stimulus, group and level (``sessions.sqlite`` and the exported
``responses.csv``), mapped back through the study's ``web/site-map.json``.
"""
import csv
import http.client
import json
import re

import pytest

from _kinds import design_text, make_study
from _prolific import CATCH_GROUP
from _run_server import Run
from _site_names import condition_words
from test_session_browser import jspsych_dir  # noqa: F401 (fixture)

from flipstudy.study.export import export_responses
from flipstudy.study.server import ServerThread, create_app
from flipstudy.study.session import load_study, open_session
from flipstudy.study.web.site import OWN_FILES, STATIC, lib_files

GROUPS = [{"name": "lift-up", "sign": 1, "levels": [0, 37.5]},
          {"name": "pair-down", "sign": -1, "levels": [0, 62.5], "task": "2afc"}]
QUEST = {"name": "quest-walk", "sign": 1, "levels": {"from": 0, "to": 60, "step": 7.5}, "method": "quest+",
         "trials": 3}
#: levels as a page could show them (the others are the stimulus names' ends, searched too)
LEVEL_WORDS = ["37.5", "62.5", "7.5", "52.5"]
#: what a trial screen and an answer's reply may carry (no clip, kind, group or level)
SCREEN_KEYS = {"type", "id", "trial", "of", "stimulus", "stimuli", "video", "videos", "replay", "iti_ms", "prompt",
               "submit", "task", "adaptive", "labels", "gap_ms", "keys"}
#: what would say which of a 2AFC trial's two videos is the original (the correct answer)
WHICH_IS_WHICH = {"original", "modified"}
REPLY_KEYS = {"status", "trial", "next_trial", "finished"}
HIDDEN_KEYS = {"level", "kind", "group", "clip", "profile", "original", "condition"}


class Page:
    """The participant's page over HTTP: every response it gets is kept in ``seen``, as
    (path, body, whether it answered a probe)."""

    def __init__(self, url):
        self.port = int(url.rsplit(":", 1)[1].strip("/"))
        self.seen = []

    def req(self, method, path, body=None, probe=False):
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=20)
        headers = {"Host": f"127.0.0.1:{self.port}"}
        if body is not None:
            body = json.dumps(body).encode()
            headers["Content-Type"] = "application/json"
        conn.request(method, path, body=body, headers=headers)
        r = conn.getresponse()
        data = r.read()
        conn.close()
        self.seen.append((path, data, probe))
        return r.status, data

    def json(self, method, path, body=None, expect=200):
        """The JSON ``path`` answers with (status ``expect``)."""
        st, data = self.req(method, path, body)
        assert st == expect, (path, st, data)
        return json.loads(data)


def _walk(obj, key=None):
    """(key, value) of every value of a JSON document, and ("key", k) of every key."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield "key", k
            yield from _walk(v, k)
    elif isinstance(obj, list):
        for v in obj:
            yield from _walk(v, key)
    else:
        yield key, obj


def _answer(n, stimulus, response):
    """The page's answer: a 2AFC trial's names its two videos (a list) as shown."""
    shown = {"stimuli": stimulus} if isinstance(stimulus, list) else {"stimulus": stimulus}
    return {"participant": "P01", "session": 1, "trial": n, **shown, "response": response,
            "rt_ms": 500.0, "shown_ms": 130.0, "late_frames": 0}


def _study(tmp_path, groups):
    return make_study(tmp_path / "study", design_text(groups, repetitions=2) + CATCH_GROUP, frames=4, size=(32, 24))


def _run_session(page):
    """What the page asks for in a whole session, and at each trial the probes; returns
    the timeline and {trial: (the page's name of its stimulus, the response given)}."""
    st, html = page.req("GET", "/")
    assert st == 200
    for ref in re.findall(r'(?:src|href)="([^":]+)"', html.decode()):
        assert page.req("GET", "/" + ref)[0] == 200, ref
    tl = page.json("GET", "/api/session")
    examples = [s for s in tl["timeline"] if s["type"] == "examples"]
    assert examples
    for ex in examples[0]["stimuli"]:
        assert page.req("GET", ex["video"])[0] == 200
    page.json("POST", "/api/demographics", {"participant": "P01", "session": 1, "age": None, "gender": "other",
                                            "animation_experience": "none", "gymnastics_experience": "none"})
    trials = [s for s in tl["timeline"] if s.get("trial")]
    given = {}
    for s in trials:
        n = s["trial"]
        screen = page.json("GET", f"/api/trial/{n}")        # as the page fills a QUEST+ trial
        for video in screen.get("videos") or [screen["video"]]:
            assert page.req("GET", video)[0] == 200, video
        two = screen["type"] == "trial-2afc"
        response = (("first", "second") if two else ("correct", "incorrect"))[n % 2]
        mine = screen["stimuli"] if two else screen["stimulus"]
        other = next(t["stimulus"] for t in trials if t.get("stimulus") not in (None, mine))
        assert page.req("POST", "/api/answer", _answer(n, other, response), probe=True)[0] == 409
        assert page.req("POST", "/api/answer", _answer(n, "backflip_catch_100", response), probe=True)[0] == 400
        assert page.req("GET", "/stimuli/backflip_catch_100.mp4", probe=True)[0] == 404
        if two:              # the pair in the other order is not what the trial showed
            assert page.req("POST", "/api/answer", _answer(n, mine[::-1], response), probe=True)[0] == 409
        reply = page.json("POST", "/api/answer", _answer(n, mine, response))
        assert reply["status"] == "stored"
        given[n] = (mine, response)
    assert tl["n_trials"] == len(given)
    return tl, given


def _check(study, page, tl, given, jspsych_dir, tmp_path):
    """Nothing the page was sent names a condition; each answer stored by its stimulus."""
    words = condition_words(study) + LEVEL_WORDS
    assert {"catch", "lift-up", "pair-down", "angular-momentum", "backflip_catch_100"} <= set(words)
    code = dict(lib_files(jspsych_dir), **{f: (STATIC / f).read_bytes() for f in OWN_FILES})
    searched = 0
    for path, body, probe in page.seen:
        assert probe or not [w for w in words if w in path], path      # (the probes name them)
        name = path.lstrip("/")
        if name in code:                                     # the site's code: every study's bytes
            assert body == code[name], name
        elif probe or not name.endswith(".mp4"):             # (a video's bytes are its own)
            text = body.decode()
            assert not [w for w in words if w in text], (path, [w for w in words if w in text])
            searched += 1
    assert searched >= len(given) * 5 + 4          # the page, config.js, each screen, reply and refusal
    # no screen or reply says what a trial is but by its video
    replies = [json.loads(b) for p, b, _ in page.seen if p.startswith("/api/")]
    examples = [ex for s in tl["timeline"] if s["type"] == "examples" for ex in s["stimuli"]]
    assert all(set(ex) == {"video", "label"} for ex in examples)
    cfg = json.loads(next(b for p, b, _ in page.seen if p == "/config.js").decode().split("= ", 1)[1]
                     .rstrip().rstrip(";\n"))
    assert not HIDDEN_KEYS & {v for k, v in _walk([cfg["videos"], cfg["references"]]) if k == "key"}
    screens = [s for s in tl["timeline"] if s.get("trial")] + [r for r in replies if "type" in r]
    assert len(screens) == 2 * len(given) and all(set(s) <= SCREEN_KEYS for s in screens), screens
    # nor which of a 2AFC trial's two videos is the original: no field's value, no "first"
    pairs = [s for s in screens if s["type"] == "trial-2afc"]
    assert pairs and all(len(s["stimuli"]) == 2 and "stimulus" not in s and "first" not in s for s in pairs)
    assert not [(k, v) for s in screens + replies for k, v in _walk(s) if v in WHICH_IS_WHICH]
    assert all(set(r) == REPLY_KEYS for r in replies if "status" in r and "trial" in r)

    # the round trip: each answer stored under the stimulus its video is, as given
    site_map = json.loads((study / "web" / "site-map.json").read_text())["stimuli"]
    out = export_responses(study, tmp_path / "export" / "responses.csv")
    with open(out.responses, newline="") as f:
        stored = {int(r["trial"]): r for r in csv.DictReader(f)}
    assert stored.keys() == given.keys()
    manifest = {r.stimulus: r for r in load_study(study).manifest}
    for trial, (name, response) in given.items():
        if isinstance(name, list):     # 2AFC: the modified one of the two, the order as shown
            a, b = (site_map[x] for x in name)
            first = "original" if manifest[b].original == a else "modified"
            name = name[1] if first == "original" else name[0]
            assert (r := stored[trial])["first"] == first, trial
            assert r["original_stimulus"] == manifest[site_map[name]].original
        r, real = stored[trial], manifest[site_map[name]]
        assert (r["stimulus"], r["group"], float(r["level"]), r["response"]) == \
            (real.stimulus, real.group, real.level, response), trial
    return {r["group"] for r in stored.values()}


def test_the_local_page_names_no_condition_and_answers_are_stored_by_stimulus(jspsych_dir, tmp_path):  # noqa: F811
    study = _study(tmp_path, GROUPS)
    session = open_session(load_study(study), "P01")
    page = None
    try:
        with ServerThread(create_app(session, iti_ms=20)) as srv:
            page = Page(srv.url)
            tl, given = _run_session(page)
    finally:
        session.close()
    assert len(given) == 4 + 2 + 2              # yes/no (its original too), 2AFC, catch
    assert _check(study, page, tl, given, jspsych_dir, tmp_path) == {"lift-up", "pair-down", "catch"}


@pytest.mark.slow
def test_flipstudy_run_hides_the_levels_quest_picks_too(jspsych_dir, tmp_path):  # noqa: F811
    study = _study(tmp_path, GROUPS + [QUEST])
    run = Run(study, "P01", "--iti-ms", "20")
    page = Page(run.start())
    try:
        tl, given = _run_session(page)
    finally:
        run.stop()
    assert len(given) == 4 + 2 + 2 + 3
    assert _check(study, page, tl, given, jspsych_dir, tmp_path) == {"lift-up", "pair-down", "catch", "quest-walk"}
