"""Sessions with quest+ and 2AFC groups: resolve(), the answer path, the stored
QUEST+ state (SIGKILL resume), interleaving, stop_width, the 2AFC order."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from flipstudy.analysis.adaptive import Observer, Quest
from flipstudy.study import store
from flipstudy.study.session import detected, load_study, open_session, submit_answer
from flipstudy.errors import RequestError

from _adaptive import answer, design_text, make_study

OBSERVER = Observer(threshold=22.0, width=15.0, gamma=0.2, lapse=0.02, task="yes-no")


def respond(t, rule_seed: int = 0) -> str:
    """A fixed answer rule: the observer's answer with a generator seeded by the trial."""
    rng = np.random.default_rng([rule_seed, t.trial])
    if t.task == "2afc":
        o = Observer(22.0, 15.0, 0.5, 0.02, "2afc")
        chose_original = o.answer(t.level, rng)
        return "first" if chose_original == (t.first == "original") else "second"
    return "incorrect" if OBSERVER.answer(t.level, rng) else "correct"


def run(session, upto: int | None = None) -> list:
    """Answer trials from the current one (through submit_answer) up to ``upto``."""
    out = []
    while True:
        st = session.state()
        if st["finished"] or (upto is not None and st["next_trial"] > upto):
            return out
        t = session.resolve(st["next_trial"])
        r = submit_answer(session, answer(session, t, respond(t)))
        assert r["status"] == "stored"
        out.append((t, r))


def test_yes_no_and_quest_groups_interleave_and_quest_picks_the_levels(tmp_path):
    study = load_study(make_study(tmp_path / "s", groups=("yn", "quest"), trials=12))
    s = open_session(study, "P01")
    kinds = [t.method for t in s.trials]
    assert kinds.count("quest+") == 12 and kinds.count("constant") == 4
    assert s.n_trials == study.design.trials_per_participant()
    q_at = [i for i, k in enumerate(kinds) if k == "quest+"]
    assert any(k == "constant" for k in kinds[q_at[0]:q_at[-1]])      # interleaved, not a block
    assert all(not t.stimulus and np.isnan(t.level) for t in s.trials if t.adaptive)
    done = run(s)
    assert len(done) == 16 and s.state()["finished"]
    # every "next" the answer returned is what resolve() then showed
    for (t, r), (t2, _) in zip(done, done[1:]):
        assert r["next"] == t2.to_dict()
    assert done[-1][1]["next"] is None
    # the session's levels are QUEST+'s: an independent run fed the same answers picks them
    q = Quest.new(study.quest_model("quest"))
    for t, _ in done:
        if t.adaptive:
            assert t.level == q.next_level()
            assert t.stimulus == f"backflip_quest_{t.level:g}"
            q.update(t.level, detected(t, respond(t)))
    stored = s.quest("quest")
    assert np.array_equal(stored.posterior, q.posterior) and stored.history == q.history
    with s.db() as conn:
        rows = store.response_rows(conn)
    last = [r for r in rows if r["method"] == "quest+"][-1]
    assert last["quest_threshold"] == pytest.approx(q.threshold()["threshold"], rel=0, abs=1e-12)
    assert last["quest_ci_low"] <= last["quest_threshold"] <= last["quest_ci_high"]
    shown = {r["trial"]: (r["stimulus"], r["level"]) for r in rows}
    assert all(shown[t.trial] == (t.stimulus, t.level) for t, _ in done)


def test_an_adaptive_answer_must_name_the_resolved_stimulus_and_fit_the_task(tmp_path):
    study = load_study(make_study(tmp_path / "s", groups=("quest", "twoafc"), trials=6))
    s = open_session(study, "P01")
    t = s.resolve(s.state()["next_trial"])
    wrong = next(lv for lv in range(0, 65, 5) if lv != t.level) if t.adaptive else None
    while not t.adaptive:                   # answer up to the first adaptive slot
        submit_answer(s, answer(s, t, respond(t)))
        t = s.resolve(s.state()["next_trial"])
        wrong = next(lv for lv in range(0, 65, 5) if lv != t.level)
    bad = dict(answer(s, t, "correct"), stimulus=f"backflip_quest_{wrong:g}")
    with pytest.raises(RequestError) as e:
        submit_answer(s, bad)
    assert e.value.status == 409 and t.stimulus in e.value.message
    with pytest.raises(RequestError) as e:
        submit_answer(s, answer(s, t, "first"))            # a 2AFC response to a yes/no trial
    assert e.value.status == 400
    assert s.state()["answered"] == t.trial - 1              # nothing stored
    two = next(x for x in s.trials if x.task == "2afc")
    with pytest.raises(RequestError) as e:
        submit_answer(s, answer(s, two, "correct"))
    assert e.value.status == 400


def test_two_afc_trials_balance_first_and_name_their_original(tmp_path):
    study = load_study(make_study(tmp_path / "s", groups=("twoafc", "quest2afc"), trials=10,
                                  two_clips=True))
    orders = {}
    for pid in ("P01", "P02"):
        trials = open_session(study, pid).trials
        orders[pid] = [(t.stimulus, t.first) for t in trials]
        const = [t for t in trials if t.group == "twoafc"]
        assert len(const) == 2 * 2 * 2                      # repetitions × clips × levels 20, 40
        assert {t.level for t in const} == {20.0, 40.0}       # level 0 is the comparison
        assert all(t.original == f"{t.clip}_twoafc_0" for t in const)
        for g in ("twoafc", "quest2afc"):
            firsts = [t.first for t in trials if t.group == g]
            assert firsts.count("original") == firsts.count("modified") == len(firsts) // 2
        slots = [t for t in trials if t.group == "quest2afc"]
        assert [t.clip for t in slots].count("backflip") == 5 and len(slots) == 10
        assert all(t.original == f"{t.clip}_quest2afc_0" for t in slots)
        assert all(t.task == "2afc" for t in trials)
    assert orders["P01"] != orders["P02"]
    again = open_session(load_study(study.dir), "P01")           # resumed: the stored order
    assert [(t.stimulus, t.first) for t in again.trials] == orders["P01"]


def test_a_two_afc_session_is_answered_and_stored(tmp_path):
    study = load_study(make_study(tmp_path / "s", groups=("twoafc", "quest2afc"), trials=8))
    s = open_session(study, "P01")
    done = run(s)
    assert s.state()["finished"] and len(done) == 4 + 8
    with s.db() as conn:
        rows = store.response_rows(conn)
    assert {r["response"] for r in rows} <= {"first", "second"}
    assert all(r["task"] == "2afc" and r["first"] in ("original", "modified") for r in rows)
    q = Quest.new(study.quest_model("quest2afc"))
    for t, _ in done:
        if t.adaptive:
            assert t.level > 0 and t.level == q.next_level()
            q.update(t.level, detected(t, respond(t)))
    assert np.array_equal(s.quest("quest2afc").posterior, q.posterior)


def test_stop_width_ends_a_quest_group_and_skips_its_slots(tmp_path):
    text = design_text(("yn", "quest"), trials=12, extra="stop_width = 1000\n")
    study = load_study(make_study(tmp_path / "s", text))
    s = open_session(study, "P01")
    done = run(s)
    adaptive = [t for t, _ in done if t.adaptive]
    assert len(adaptive) == 1                       # the interval is narrower than 1000 % at once
    skipped = s.skipped()
    assert len(skipped) == 11 and all(s.trials[i - 1].adaptive for i in skipped)
    st = s.state()
    assert st["finished"] and st["answered"] == 5
    with s.db() as conn:
        (row,) = store.status_rows(conn)
        assert row["complete"] and row["finished"]


CHILD = textwrap.dedent("""
    import sys
    sys.path.insert(0, {tests!r})
    from flipstudy.study.session import load_study, open_session, submit_answer
    from test_adaptive_session import respond
    from _adaptive import answer
    s = open_session(load_study({study!r}), "P01")
    while not s.state()["finished"]:
        t = s.resolve(s.state()["next_trial"])
        submit_answer(s, answer(s, t, respond(t)))
        print("stored", t.trial, flush=True)
        if {wait}:
            sys.stdin.readline()                  # wait: the parent kills us here
""")


@pytest.mark.parametrize("wait", [True, False], ids=["between-answers", "while-answering"])
def test_a_sigkilled_session_resumes_with_the_same_posterior_and_next_level(tmp_path, wait):
    """``wait``: the child stops after each stored answer and is killed there; else it
    runs on and is killed wherever it is (computing or writing the next answer)."""
    killed = make_study(tmp_path / "killed", groups=("yn", "quest"), trials=12)
    calm = make_study(tmp_path / "calm", groups=("yn", "quest"), trials=12)
    tests = str(Path(__file__).parent)
    proc = subprocess.Popen([sys.executable, "-c", CHILD.format(tests=tests, study=str(killed),
                                                                 wait=wait)],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": os.pathsep.join([tests, str(Path(__file__).parents[1] / "_support")])})
    study_k = load_study(killed)
    slots = [t.trial for t in open_session(study_k, "P01").trials if t.adaptive]
    kill_at = slots[4]                             # killed after the 5th adaptive answer
    try:
        while True:
            line = proc.stdout.readline()
            assert line.startswith("stored"), line
            if int(line.split()[1]) == kill_at:
                break
            if wait:
                proc.stdin.write("\n")
                proc.stdin.flush()
        os.kill(proc.pid, signal.SIGKILL)
        assert proc.wait(timeout=60) == -signal.SIGKILL
    finally:
        if proc.poll() is None:
            proc.kill()
    resumed = open_session(load_study(killed), "P01")
    stop_after = resumed.state()["answered"]          # the kill may have let one more through
    assert resumed.resumed and (stop_after == kill_at if wait else stop_after >= kill_at)
    uninterrupted = open_session(load_study(calm), "P01")
    run(uninterrupted, upto=stop_after)
    a, b = resumed.quest("quest"), uninterrupted.quest("quest")
    assert np.array_equal(a.posterior, b.posterior) and a.history == b.history
    nxt = next((t for t in slots if t > stop_after), None)
    assert nxt is not None or not wait
    if nxt is not None:                                # the same next level, resolved alike
        assert resumed.resolve(nxt) == uninterrupted.resolve(nxt)
        assert resumed.resolve(nxt).level == b.next_level()
    run(resumed)
    run(uninterrupted)
    with resumed.db() as c1, uninterrupted.db() as c2:
        s1 = [r["quest_state"] for r in c1.execute("SELECT quest_state FROM responses ORDER BY trial")]
        s2 = [r["quest_state"] for r in c2.execute("SELECT quest_state FROM responses ORDER BY trial")]
    assert s1 == s2 and sum(x is not None for x in s1) == 12
    assert json.loads(s1[-1])["levels"] == [resumed.resolve(i).level for i in slots]


def test_level_0_of_a_quest_group_sharing_the_original_shows_the_shared_original(tmp_path):
    text = design_text(("quest",), trials=20).replace('original = "per-group"\n', "")
    study = load_study(make_study(tmp_path / "s", text))
    assert study.group("quest").original == "shared" and not study.design.shows_shared_original
    assert study.stimulus_at("quest", "backflip", 0) == "backflip_original"
    s = open_session(study, "P01")
    assert all(t.adaptive for t in s.trials)           # the shared original is no trial of its own
    shown = []
    while not s.state()["finished"]:                   # "incorrect" mostly: QUEST+ goes down to 0
        t = s.resolve(s.state()["next_trial"])
        shown.append(t.stimulus)
        submit_answer(s, answer(s, t, "incorrect" if t.trial % 3 else "correct"))
    assert "backflip_original" in shown and all(x in study.by_name for x in shown)


def test_a_session_resumed_after_its_quest_settings_changed_is_refused(tmp_path):
    from flipstudy.errors import SessionError
    study = load_study(make_study(tmp_path / "s", groups=("yn", "quest"), trials=12))
    s = open_session(study, "P01")
    run(s, upto=next(t.trial for t in s.trials if t.adaptive))
    design = tmp_path / "s" / "design.toml"
    design.write_text(design.read_text().replace("method", "lapse = 0.05\nmethod"))
    # issue 28: the design of a study with answers is frozen; refused before the QUEST+ check
    from flipstudy.errors import FlipstudyError
    with pytest.raises(FlipstudyError, match="design.toml changed since the study's first answer"):
        open_session(load_study(tmp_path / "s"), "P01")
    from flipstudy.study import store                  # a database from before that record:
    conn = store.connect(tmp_path / "s")               # the QUEST+ check still refuses it
    conn.execute("DELETE FROM meta WHERE key IN ('design_sha256', 'design_toml')")
    conn.close()
    with pytest.raises(SessionError, match="QUEST\\+ state of group 'quest' does not fit"):
        open_session(load_study(tmp_path / "s"), "P01")
