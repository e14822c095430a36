"""Schema 2: a database made by the version-1 code is migrated in place (its rows
untouched), new databases take 2AFC answers; the default design's order is the one
the code before issue 19 made."""
from __future__ import annotations

import sqlite3
import subprocess
import sys
import types
from pathlib import Path

import pytest

from flipstudy.errors import FlipstudyError, SessionError
from flipstudy.study import store
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study, open_session, submit_answer

from _adaptive import answer, make_study

# the schema exactly as flipstudy wrote it before schema 2 (study/store.py at 200504d)
V1_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS sessions (
    participant     TEXT    NOT NULL,
    session         INTEGER NOT NULL CHECK (session >= 1),
    source          TEXT    NOT NULL CHECK (source IN ('browser', 'simulated')),
    seed            TEXT    NOT NULL,
    manifest_sha256 TEXT    NOT NULL,
    n_trials        INTEGER NOT NULL CHECK (n_trials >= 1),
    started         TEXT    NOT NULL,
    finished        TEXT,
    PRIMARY KEY (participant, session));
CREATE TABLE IF NOT EXISTS trials (
    participant TEXT NOT NULL, session INTEGER NOT NULL, trial INTEGER NOT NULL CHECK (trial >= 1),
    stimulus TEXT NOT NULL, clip TEXT NOT NULL, group_name TEXT NOT NULL, kind TEXT NOT NULL,
    level REAL NOT NULL, repetition INTEGER NOT NULL CHECK (repetition >= 1),
    PRIMARY KEY (participant, session, trial),
    FOREIGN KEY (participant, session) REFERENCES sessions (participant, session));
CREATE TABLE IF NOT EXISTS responses (
    participant TEXT NOT NULL, session INTEGER NOT NULL, trial INTEGER NOT NULL,
    response    TEXT    NOT NULL CHECK (response IN ('correct', 'incorrect')),
    rt_ms REAL NOT NULL CHECK (rt_ms >= 0), shown_ms REAL NOT NULL CHECK (shown_ms >= 0),
    late_frames INTEGER NOT NULL CHECK (late_frames >= 0),
    replays INTEGER NOT NULL DEFAULT 0 CHECK (replays >= 0),
    input TEXT NOT NULL, timestamp TEXT NOT NULL,
    PRIMARY KEY (participant, session, trial),
    FOREIGN KEY (participant, session, trial) REFERENCES trials (participant, session, trial));
CREATE TABLE IF NOT EXISTS demographics (
    participant TEXT NOT NULL, session INTEGER NOT NULL, age INTEGER, gender TEXT NOT NULL,
    animation_experience TEXT NOT NULL, gymnastics_experience TEXT NOT NULL,
    timestamp TEXT NOT NULL,
    PRIMARY KEY (participant, session),
    FOREIGN KEY (participant, session) REFERENCES sessions (participant, session));
"""


def v1_database(study_dir: Path, answered: int = 3) -> list[tuple]:
    """A version-1 sessions.sqlite with P01's session (the demo order) and its first
    ``answered`` answers, written with plain SQL as the old code did; returns the rows."""
    from flipstudy.study.order import trial_order
    study = load_study(study_dir)
    trials = trial_order(study.design, study.manifest, "P01")
    conn = sqlite3.connect(study_dir / store.DB_NAME)
    conn.executescript(V1_SCHEMA)
    conn.execute("INSERT INTO meta VALUES ('schema_version', '1')")
    conn.execute("PRAGMA user_version=1")
    with conn:
        conn.execute("INSERT INTO sessions VALUES ('P01', 1, 'browser', '42', ?, ?, "
                     "'2026-01-05T10:00:00.000Z', NULL)", (study.manifest_sha256, len(trials)))
        conn.executemany("INSERT INTO trials VALUES ('P01', 1, ?,?,?,?,?,?,?)",
                         [(t.trial, t.stimulus, t.clip, t.group, t.kind, t.level, t.repetition)
                          for t in trials])
        conn.executemany("INSERT INTO responses VALUES ('P01', 1, ?, ?, 600.5, 2000.0, 0, 0, 'key', ?)",
                         [(i, "correct" if i % 2 else "incorrect", f"2026-01-05T10:00:0{i}.000Z")
                          for i in range(1, answered + 1)])
    conn.close()
    return dump(study_dir)


def dump(study_dir: Path) -> dict:
    conn = sqlite3.connect(study_dir / store.DB_NAME)
    cols = {"sessions": "participant, session, source, seed, manifest_sha256, n_trials, started",
            "trials": "participant, session, trial, stimulus, clip, group_name, kind, level, repetition",
            "responses": "participant, session, trial, response, rt_ms, shown_ms, late_frames, "
                         "replays, input, timestamp"}
    out = {t: conn.execute(f"SELECT {c} FROM {t} ORDER BY 1, 2, 3").fetchall() for t, c in cols.items()}
    conn.close()
    return out


def test_a_version_1_database_is_migrated_and_its_answers_kept(tmp_path):
    study_dir = make_demo_study(tmp_path / "s", videos=False)
    before = v1_database(study_dir)
    conn = store.connect(study_dir)
    assert conn.execute("PRAGMA user_version").fetchone()[0] == 2
    assert conn.execute("SELECT value FROM meta WHERE key='schema_version'").fetchone()[0] == "2"
    new = {r[1] for r in conn.execute("PRAGMA table_info(responses)")}
    assert {"shown_stimulus", "shown_level", "quest_state", "quest_threshold"} <= new
    assert not store.accepts_2afc(conn)
    conn.close()
    assert dump(study_dir) == before                      # every old row as it was
    s = open_session(load_study(study_dir), "P01")       # resumed on the migrated database
    assert s.resumed and s.state()["next_trial"] == 4
    assert all(t.method == "constant" and t.task == "yes-no" for t in s.trials)
    r = submit_answer(s, answer(s, s.trials[3], "correct"))
    assert r["status"] == "stored" and r["next"]["trial"] == 5
    after = dump(study_dir)
    assert after["responses"][:3] == before["responses"][:3] and len(after["responses"]) == 4
    with s.db() as c:
        rows = store.response_rows(c)
    assert [r["method"] for r in rows] == ["constant"] * 4 and rows[0]["task"] == "yes-no"


def test_a_failed_migration_leaves_version_1(tmp_path, monkeypatch):
    study_dir = make_demo_study(tmp_path / "s", videos=False)
    before = v1_database(study_dir)
    monkeypatch.setattr(store, "MIGRATE_1_TO_2", store.MIGRATE_1_TO_2 + ["ALTER TABLE nowhere ADD x"])
    with pytest.raises(sqlite3.OperationalError):
        store.connect(study_dir)
    conn = sqlite3.connect(study_dir / store.DB_NAME)
    assert conn.execute("PRAGMA user_version").fetchone()[0] == 1
    assert "quest_state" not in {r[1] for r in conn.execute("PRAGMA table_info(responses)")}
    conn.close()
    assert dump(study_dir) == before


def test_a_migrated_database_refuses_a_2afc_study_with_a_clear_error(tmp_path):
    study_dir = make_study(tmp_path / "s", groups=("twoafc",))
    conn = sqlite3.connect(study_dir / store.DB_NAME)
    conn.executescript(V1_SCHEMA)
    conn.execute("PRAGMA user_version=1")
    conn.close()
    with pytest.raises(SessionError, match="schema 1"):
        open_session(load_study(study_dir), "P01")
    assert issubclass(SessionError, FlipstudyError)


def test_new_databases_store_2afc_answers_and_new_columns(tmp_path):
    study_dir = make_study(tmp_path / "s", groups=("twoafc",))
    s = open_session(load_study(study_dir), "P01")
    t = s.trials[0]
    submit_answer(s, answer(s, t, "second"))
    with s.db() as c:
        assert store.accepts_2afc(c)
        row = c.execute("SELECT t.task, t.first, t.original, r.response FROM trials t JOIN "
                        "responses r USING (participant, session, trial)").fetchone()
    assert tuple(row) == ("2afc", t.first, t.original, "second")


def _old_order_module():
    root = Path(__file__).resolve().parents[2]
    try:
        src = subprocess.run(["git", "-C", str(root), "show", "200504d:study/order.py"],
                             capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("no git history with commit 200504d (the code before issue 19)")
    src = src.replace("flipstudy.stimuli.exceptions", "flipstudy.errors")   # where the error family lives now
    mod = types.ModuleType("order_before_issue19")
    sys.modules[mod.__name__] = mod
    exec(compile(src, "order_before_issue19.py", "exec"), mod.__dict__)
    return mod


def test_the_paper_design_order_is_the_one_before_adaptive_groups():
    from flipstudy.stimuli.design import PAPER_DESIGN, parse_design
    from flipstudy.stimuli.stimset import original_of, plan
    from flipstudy.stimuli.contract import Stimulus
    from flipstudy.study.order import trial_order
    old = _old_order_module()
    d = parse_design(PAPER_DESIGN)
    manifest = [{"stimulus": n, "clip": c.name, "group": g.name if g else "reference",
                 "kind": g.kind if g else "reference", "level": f"{lv:.6f}",
                 "original": original_of(d, c.name, g)} for n, c, g, lv in plan(d)]
    stimuli = [Stimulus(r["stimulus"], r["clip"], r["group"], r["kind"], level=float(r["level"]),
                        original=r["original"]) for r in manifest]       # the same rows, typed
    for pid, session in (("P01", 1), ("P02", 1), ("x-7", 3)):
        a = old.trial_order(d, manifest, pid, session)
        b = trial_order(d, stimuli, pid, session)
        assert [tuple(vars(t).values()) for t in a] == \
            [(t.trial, t.stimulus, t.clip, t.group, t.kind, t.level, t.repetition) for t in b]
        assert all(t.method == "constant" and t.task == "yes-no" and not t.first for t in b)
