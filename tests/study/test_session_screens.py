"""The screens of 2AFC and adaptive trials (study.timeline) and the server's
``GET /api/trial/{n}`` (study.server), without a browser."""
import json
import urllib.error
import urllib.request

import pytest

from _kinds import design_text, make_study
from _site_names import study_names
from flipstudy.study.server import ServerThread, create_app
from flipstudy.study.session import load_study, open_session, submit_answer
from flipstudy.study.timeline import INSTRUCTIONS, KEYS_2AFC, PROMPT_2AFC, build_timeline, trial_screen

YES_NO = {"name": "up", "sign": 1, "levels": [0, 25]}
TWO_AFC = {"name": "down", "sign": -1, "levels": [0, 20, 40], "task": "2afc"}
QUEST = {"name": "steps", "sign": 1, "levels": {"from": 0, "to": 60, "step": 5}, "method": "quest+",
         "trials": 4}
OLD_TRIAL_KEYS = ["type", "id", "trial", "of", "stimulus", "video", "replay", "iti_ms", "prompt", "submit"]


def _session(tmp_path, groups, pid="P01", **kw):
    return open_session(load_study(make_study(tmp_path / "s", design_text(groups, **kw), videos=False)), pid)


def _state(answered=0, demographics=False):
    return {"answered": answered, "demographics": demographics}


def test_yes_no_constant_screens_are_the_old_ones(tmp_path):
    s = _session(tmp_path, [YES_NO, dict(YES_NO, name="up2")])
    tl = build_timeline(s, _state())
    trials = [x for x in tl["timeline"] if x["type"] == "trial"]
    assert len(trials) == s.n_trials and all(list(x) == OLD_TRIAL_KEYS for x in trials)
    assert tl["timeline"][0]["paragraphs"][:4] == INSTRUCTIONS


def test_2afc_screen_shows_the_pair_in_the_stored_order(tmp_path):
    s = _session(tmp_path, [TWO_AFC], repetitions=2, replay=True)
    tl = build_timeline(s, _state())
    screens = [x for x in tl["timeline"] if x["type"] == "trial-2afc"]
    assert len(screens) == s.n_trials == 4                  # 20 and 40 twice; 0 is the comparison
    for x, t in zip(screens, s.trials):
        pair = [f"/stimuli/{t.original}.mp4", f"/stimuli/{t.stimulus}.mp4"]
        assert x["videos"] == (pair if t.first == "original" else pair[::-1])
        assert x["stimuli"] == [v[len("/stimuli/"):-len(".mp4")] for v in x["videos"]]
        assert "first" not in x and "stimulus" not in x        # nothing says which is the original
        assert (x["keys"], x["prompt"]) == (KEYS_2AFC, PROMPT_2AFC)
        assert x["replay"] is True and x["labels"] == ["1", "2"] and x["gap_ms"] > 0
    assert sorted(t.first for t in s.trials) == ["modified", "modified", "original", "original"]
    text = " ".join(tl["timeline"][0]["paragraphs"])
    assert "two motions" in text and "F = the first motion" in text and "incorrect" not in text


def test_mixed_study_explains_both_tasks_and_marks_yes_no_screens(tmp_path):
    s = _session(tmp_path, [YES_NO, TWO_AFC])
    tl = build_timeline(s, _state())
    text = " ".join(tl["timeline"][0]["paragraphs"])
    assert "mark it either as correct" in text and "the first or the second" in text
    assert "F = correct" in text and "F = the first" in text
    kinds = {x["type"]: x for x in tl["timeline"] if x["type"].startswith("trial")}
    assert kinds["trial"]["task"] == "yes-no" and kinds["trial-2afc"]["task"] == "2afc"
    tl = build_timeline(s, _state(answered=2, demographics=True))
    resume = tl["timeline"][tl["start"]]
    assert "continues with trial 3 of" in " ".join(resume["paragraphs"])


def test_adaptive_slots_are_placeholders_until_served(tmp_path):
    s = _session(tmp_path, [YES_NO, QUEST], repetitions=1)
    tl = build_timeline(s, _state())
    slots = [x for x in tl["timeline"] if x.get("adaptive")]
    assert len(slots) == 4 and all(set(x) == {"type", "id", "trial", "of", "adaptive", "task"} for x in slots)
    t = next(t for t in s.trials if t.method == "quest+")
    filled = trial_screen(s.resolve(t.trial), s.n_trials, replay=False, iti_ms=0, tagged=True)
    assert filled["adaptive"] is True and filled["stimulus"] == s.resolve(t.trial).stimulus
    assert filled["video"] == f"/stimuli/{filled['stimulus']}.mp4"


def _get(url):
    try:
        with urllib.request.urlopen(url) as r:
            return r.status, json.load(r)
    except urllib.error.HTTPError as e:
        return e.code, json.load(e)


def test_api_trial_serves_the_current_trial_only(tmp_path):
    s = _session(tmp_path, [QUEST, YES_NO], repetitions=1)
    with ServerThread(create_app(s, iti_ms=0)) as srv:
        names = study_names(s.study.dir)          # the page's (opaque) names → the stimuli
        for n in range(1, s.n_trials + 1):
            status, screen = _get(srv.url + f"api/trial/{n}")
            assert status == 200 and screen["trial"] == n
            want = s.resolve(n)
            assert names[screen["stimulus"]] == want.stimulus and want.stimulus in s.study.by_name
            if n < s.n_trials:
                assert _get(srv.url + f"api/trial/{n + 1}")[0] == 409       # not yet
            level = s.study.by_name[want.stimulus].level
            submit_answer(s, {"participant": "P01", "session": 1, "trial": n, "stimulus": want.stimulus,
                              "response": "incorrect" if level > 20 else "correct", "rt_ms": 500.0,
                              "shown_ms": 400.0, "late_frames": 0})
            assert _get(srv.url + f"api/trial/{n}")[0] == 409                # answered
        for bad in ("0", str(s.n_trials + 1), "x", "-1"):
            assert _get(srv.url + f"api/trial/{bad}")[0] == 404, bad
    s.close()


@pytest.mark.parametrize("task", ["yes-no", "2afc"])
def test_served_adaptive_levels_follow_quest(tmp_path, task):
    """The levels /api/trial serves are the engine's picks after the stored answers."""
    from flipstudy.analysis.adaptive import Quest, QuestSettings, quest_model
    s = _session(tmp_path, [dict(QUEST, task=task, trials=6)], repetitions=1)
    g = s.study.design.groups[0]
    levels = [v for v in g.levels if not (task == "2afc" and v == 0)]
    q = Quest.new(quest_model(levels, task, QuestSettings(**vars(g.quest))))
    with ServerThread(create_app(s, iti_ms=0)) as srv:
        names = study_names(s.study.dir)          # the page's (opaque) names → the stimuli
        for n in range(1, s.n_trials + 1):
            _, screen = _get(srv.url + f"api/trial/{n}")
            if task == "2afc":                 # the modified one of the two, and what came first
                a, b = (names[x] for x in screen["stimuli"])
                first = "original" if s.study.by_name[b].original == a else "modified"
                stimulus = b if first == "original" else a
            else:
                stimulus = names[screen["stimulus"]]
            level = s.study.by_name[stimulus].level
            assert level == q.next_level()
            if task == "2afc":
                seen = "first" if level < 30 else ("first" if first == "original" else "second")
                detected = (seen == "first") == (first == "original")
            else:
                seen = "incorrect" if level >= 30 else "correct"
                detected = seen == "incorrect"
            submit_answer(s, {"participant": "P01", "session": 1, "trial": n, "stimulus": stimulus,
                              "response": seen, "rt_ms": 500.0, "shown_ms": 400.0, "late_frames": 0})
            q.update(level, detected)
    s.close()
