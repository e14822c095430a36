"""Session storage: SQLite (stdlib) at ``STUDY_DIR/sessions.sqlite``.

WAL journal, ``synchronous=FULL`` (every commit reaches the disk before the
answer is acknowledged), foreign keys on.  Every write is one ``BEGIN
IMMEDIATE … COMMIT`` transaction, so a killed server (even ``kill -9``) leaves
either the whole answer or none of it.

Schema (version 2, also in ``PRAGMA user_version``)::

    meta(key PRIMARY KEY, value)                      schema_version
    sessions(participant, session, source, seed, manifest_sha256, n_trials,
             started, finished,
             simulated_truth)                         PRIMARY KEY (participant, session)
    trials(participant, session, trial, stimulus, clip, group_name, kind,
           level, repetition,
           method, task, first, original, skipped)    PRIMARY KEY (participant, session, trial)
    responses(participant, session, trial, response, rt_ms, shown_ms,
              late_frames, replays, input, timestamp,
              shown_stimulus, shown_level, quest_state,
              quest_threshold, quest_ci_low, quest_ci_high)
                                                      PRIMARY KEY (participant, session, trial)
    demographics(participant, session, age, gender, animation_experience,
                 gymnastics_experience, timestamp)    PRIMARY KEY (participant, session)

The trial order is written (``trials``) in the same transaction that creates
the session, before the first trial is served.  The responses' primary key makes
a second answer to the same trial impossible.  Timestamps are ISO 8601 UTC with
milliseconds (``2026-01-05T10:00:00.123Z``).

Version 2 (adaptive and 2AFC groups) added the nullable columns after each line
break: a trial's ``method`` (constant / quest+), ``task`` (yes-no / 2afc),
``first`` (what a 2AFC trial shows first), ``original`` (its comparison) and
``skipped`` (1: a quest+ slot left out, its group stopped early); an answer's
``shown_stimulus``/``shown_level`` (what an adaptive slot showed; the slot is
stored with stimulus ``""`` and level :data:`SLOT_LEVEL`), ``quest_state`` (the
group's QUEST+ state after it, JSON) and the threshold's posterior mean and 95 %
interval then; a simulated session's ``simulated_truth`` (JSON).  NULL reads as
version 1 did (constant, yes-no, not skipped).  New databases also accept the
2AFC responses "first" and "second".  A version-1 database is migrated when
opened: the columns are added (``ALTER TABLE … ADD COLUMN``) in one transaction
that also sets the version; its rows stay as they were.  SQLite cannot widen its
responses CHECK in place, so a migrated database takes no 2AFC answers
(:func:`accepts_2afc`): a 2AFC study needs a new study folder.
"""
from __future__ import annotations

from flipstudy.errors import ConflictError, CorruptDatabaseError, FlipstudyFileNotFoundError, FlipstudyStateError

import sqlite3
from contextlib import contextmanager
from datetime import datetime, timezone
from pathlib import Path

from .order import Trial
from .storefile import check_file, check_tables

DB_NAME = "sessions.sqlite"
SCHEMA_VERSION = 2
#: the stored level of an adaptive slot before it is shown (what it showed is in responses)
SLOT_LEVEL = -1.0

SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (
    key   TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS sessions (
    participant     TEXT    NOT NULL,
    session         INTEGER NOT NULL CHECK (session >= 1),
    source          TEXT    NOT NULL CHECK (source IN ('browser', 'simulated')),
    seed            TEXT    NOT NULL,
    manifest_sha256 TEXT    NOT NULL,
    n_trials        INTEGER NOT NULL CHECK (n_trials >= 1),
    started         TEXT    NOT NULL,
    finished        TEXT,
    simulated_truth TEXT,
    PRIMARY KEY (participant, session)
);
CREATE TABLE IF NOT EXISTS trials (
    participant TEXT    NOT NULL,
    session     INTEGER NOT NULL,
    trial       INTEGER NOT NULL CHECK (trial >= 1),
    stimulus    TEXT    NOT NULL,
    clip        TEXT    NOT NULL,
    group_name  TEXT    NOT NULL,
    kind        TEXT    NOT NULL,
    level       REAL    NOT NULL,
    repetition  INTEGER NOT NULL CHECK (repetition >= 1),
    method      TEXT,
    task        TEXT,
    first       TEXT,
    original    TEXT,
    skipped     INTEGER,
    PRIMARY KEY (participant, session, trial),
    FOREIGN KEY (participant, session) REFERENCES sessions (participant, session)
);
CREATE TABLE IF NOT EXISTS responses (
    participant TEXT    NOT NULL,
    session     INTEGER NOT NULL,
    trial       INTEGER NOT NULL,
    response    TEXT    NOT NULL CHECK (response IN ('correct', 'incorrect', 'first', 'second')),
    rt_ms       REAL    NOT NULL CHECK (rt_ms >= 0),
    shown_ms    REAL    NOT NULL CHECK (shown_ms >= 0),
    late_frames INTEGER NOT NULL CHECK (late_frames >= 0),
    replays     INTEGER NOT NULL DEFAULT 0 CHECK (replays >= 0),
    input       TEXT    NOT NULL,
    timestamp   TEXT    NOT NULL,
    shown_stimulus  TEXT,
    shown_level     REAL,
    quest_state     TEXT,
    quest_threshold REAL,
    quest_ci_low    REAL,
    quest_ci_high   REAL,
    PRIMARY KEY (participant, session, trial),
    FOREIGN KEY (participant, session, trial) REFERENCES trials (participant, session, trial)
);
CREATE TABLE IF NOT EXISTS demographics (
    participant           TEXT    NOT NULL,
    session               INTEGER NOT NULL,
    age                   INTEGER,
    gender                TEXT    NOT NULL,
    animation_experience  TEXT    NOT NULL,
    gymnastics_experience TEXT    NOT NULL,
    timestamp             TEXT    NOT NULL,
    PRIMARY KEY (participant, session),
    FOREIGN KEY (participant, session) REFERENCES sessions (participant, session)
);
"""

#: version 1 → 2: nullable columns only (the rows stay as they are)
MIGRATE_1_TO_2 = [
    "ALTER TABLE sessions ADD COLUMN simulated_truth TEXT",
    "ALTER TABLE trials ADD COLUMN method TEXT",
    "ALTER TABLE trials ADD COLUMN task TEXT",
    "ALTER TABLE trials ADD COLUMN first TEXT",
    "ALTER TABLE trials ADD COLUMN original TEXT",
    "ALTER TABLE trials ADD COLUMN skipped INTEGER",
    "ALTER TABLE responses ADD COLUMN shown_stimulus TEXT",
    "ALTER TABLE responses ADD COLUMN shown_level REAL",
    "ALTER TABLE responses ADD COLUMN quest_state TEXT",
    "ALTER TABLE responses ADD COLUMN quest_threshold REAL",
    "ALTER TABLE responses ADD COLUMN quest_ci_low REAL",
    "ALTER TABLE responses ADD COLUMN quest_ci_high REAL",
]


def utc_now() -> str:
    """Now as ISO 8601 UTC with milliseconds, e.g. ``2026-01-05T10:00:00.123Z``."""
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def db_path(study_dir) -> Path:
    return Path(study_dir) / DB_NAME


def connect(study_dir, *, create: bool = True) -> sqlite3.Connection:
    """Open (and on first use create) the study's database.  The connection is
    in autocommit mode; use :func:`transaction` for writes.  It may be shared
    between threads if the caller serialises its use (the server does)."""
    path = db_path(study_dir)
    check_file(path)                      # a dangling link, a folder, /dev/zero: damaged, not new
    if not create and not path.exists():
        raise FlipstudyFileNotFoundError(f"{path}: no sessions yet (run `flipstudy run` or `flipstudy simulate`)")
    existed = path.exists() and path.stat().st_size > 0
    conn = sqlite3.connect(path, timeout=30.0, isolation_level=None, check_same_thread=False)
    try:
        if existed:
            _check_readable(conn, path)
            v = conn.execute("PRAGMA user_version").fetchone()[0]
            if v in (0, 1, SCHEMA_VERSION):       # a table missing: damaged, never taken for empty
                check_tables(conn, path, SCHEMA, columns=v != 1)   # version 1: before migrating
        conn.row_factory = sqlite3.Row
        _set_wal(conn)
        conn.execute("PRAGMA synchronous=FULL")
        conn.execute("PRAGMA foreign_keys=ON")
        version = conn.execute("PRAGMA user_version").fetchone()[0]
        if version == 0:
            with transaction(conn):
                if conn.execute("PRAGMA user_version").fetchone()[0] == 0:   # not raced
                    for stmt in SCHEMA.split(";"):
                        if stmt.strip():
                            conn.execute(stmt)
                    conn.execute("INSERT OR REPLACE INTO meta VALUES ('schema_version', ?)",
                                 (str(SCHEMA_VERSION),))
                    conn.execute(f"PRAGMA user_version={SCHEMA_VERSION}")
        elif version == 1:
            with transaction(conn):
                if conn.execute("PRAGMA user_version").fetchone()[0] == 1:   # not raced
                    for stmt in MIGRATE_1_TO_2:
                        conn.execute(stmt)
                    conn.execute("INSERT OR REPLACE INTO meta VALUES ('schema_version', ?)",
                                 (str(SCHEMA_VERSION),))
                    conn.execute(f"PRAGMA user_version={SCHEMA_VERSION}")
            check_tables(conn, path, SCHEMA)
        elif version != SCHEMA_VERSION:
            raise FlipstudyStateError(f"{path}: schema version {version}; this flipstudy reads versions "
                               f"1 and {SCHEMA_VERSION}")
    except BaseException:
        conn.close()
        raise
    return conn


def corrupt(path, e: Exception) -> CorruptDatabaseError:
    """The error for a damaged database: names the file, says what to do, touches nothing."""
    why = " ".join(str(e).split())[:200]
    return CorruptDatabaseError(
        f"{path}: not a readable SQLite database ({why}); it was left exactly as it is. It may "
        f"have been truncated or overwritten: restore it from a backup or from the study's "
        f"archive (`flipstudy archive` keeps everything), or move the study aside with "
        f"`flipstudy archive` and ask for help recovering it (sqlite3 {path.name} '.recover')")


def _check_readable(conn: sqlite3.Connection, path: Path) -> None:
    """Before anything is written: the file is a database whose pages read
    (``PRAGMA quick_check``); :class:`CorruptDatabaseError` otherwise."""
    try:
        row = conn.execute("PRAGMA quick_check(1)").fetchone()
    except sqlite3.OperationalError as e:
        if "locked" in str(e) or "busy" in str(e):
            return                           # a writer holds it: checked by the next opener
        raise corrupt(path, e) from None
    except sqlite3.DatabaseError as e:
        raise corrupt(path, e) from None
    if row is None or row[0] != "ok":
        raise corrupt(path, row[0] if row else "quick_check answered nothing")


def _set_wal(conn: sqlite3.Connection, wait: float = 30.0) -> None:
    """``PRAGMA journal_mode=WAL``.  Switching a new database to WAL (or opening one
    whose WAL another connection is recovering) can answer "database is locked" at
    once, without SQLite's busy handler; several openers of a new study race there, so
    the switch is retried for up to ``wait`` seconds like any other lock."""
    import time
    end = time.monotonic() + wait
    while True:
        try:
            conn.execute("PRAGMA journal_mode=WAL")
            return
        except sqlite3.OperationalError as e:
            if "locked" not in str(e) or time.monotonic() > end:
                raise
            time.sleep(0.02)


@contextmanager
def transaction(conn: sqlite3.Connection):
    """``BEGIN IMMEDIATE`` … ``COMMIT`` (``ROLLBACK`` on any exception)."""
    conn.execute("BEGIN IMMEDIATE")
    try:
        yield conn
    except BaseException:
        conn.execute("ROLLBACK")
        raise
    conn.execute("COMMIT")


# --- sessions -------------------------------------------------------------------------------

def latest_session(conn, participant: str):
    """The participant's newest session row (``sqlite3.Row``) or None."""
    return conn.execute("SELECT * FROM sessions WHERE participant=? ORDER BY session DESC LIMIT 1",
                        (participant,)).fetchone()


def create_session(conn, participant: str, session: int, source: str, seed: int,
                   manifest_sha256: str, trials) -> list[Trial]:
    """Create a session and store its whole trial order, in one transaction; returns
    the trials stored.  ``trials``: the order, or a function ``trials(conn)`` that
    makes it inside the transaction, so what it reads (a between-subject condition's
    count of sessions, :func:`condition_counts`) no other session can change before
    this one is stored.  Raises :class:`ConflictError` if another connection created that
    session first (two processes opening the same new participant at once)."""
    try:
        with transaction(conn):
            if callable(trials):
                trials = trials(conn)
            conn.execute("INSERT INTO sessions (participant, session, source, seed, "
                         "manifest_sha256, n_trials, started) VALUES (?,?,?,?,?,?,?)",
                         (participant, session, source, str(seed), manifest_sha256, len(trials),
                          utc_now()))
            _insert_trials(conn, participant, session, trials)
    except sqlite3.IntegrityError as e:
        raise ConflictError(f"session {session} of participant {participant} was created by another "
                       f"process at the same time ({e})") from None
    return trials


def _insert_trials(conn, participant: str, session: int, trials: list[Trial]) -> None:
    conn.executemany(
        "INSERT INTO trials (participant, session, trial, stimulus, clip, group_name, kind, level, "
        "repetition, method, task, first, original) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?)",
        [(participant, session, t.trial, t.stimulus, t.clip, t.group, t.kind,
          SLOT_LEVEL if t.adaptive else t.level, t.repetition, t.method, t.task, t.first,
          t.original) for t in trials])


def load_trials(conn, participant: str, session: int) -> list[Trial]:
    """The stored trial order (an adaptive slot's level is NaN; NULLs of a version-1
    row read as constant, yes-no)."""
    rows = conn.execute("SELECT * FROM trials WHERE participant=? AND session=? ORDER BY trial",
                        (participant, session)).fetchall()
    out = []
    for r in rows:
        method = r["method"] or "constant"
        out.append(Trial(r["trial"], r["stimulus"], r["clip"], r["group_name"], r["kind"],
                         float("nan") if method == "quest+" else r["level"], r["repetition"],
                         method, r["task"] or "yes-no", r["first"] or "", r["original"] or ""))
    return out


def accepts_2afc(conn) -> bool:
    """Does the responses table accept "first"/"second" (a database created at
    version 2; a migrated version-1 one keeps its CHECK)?"""
    sql = conn.execute("SELECT sql FROM sqlite_master WHERE type='table' AND name='responses'"
                       ).fetchone()[0]
    return "'second'" in sql


def next_open_trial(conn, participant: str, session: int) -> int | None:
    """The current trial: the first one neither answered nor skipped (None: done)."""
    return conn.execute("""
        SELECT MIN(t.trial) FROM trials t
        WHERE t.participant=? AND t.session=? AND COALESCE(t.skipped, 0) = 0
          AND NOT EXISTS (SELECT 1 FROM responses r WHERE r.participant = t.participant
                          AND r.session = t.session AND r.trial = t.trial)""",
                        (participant, session)).fetchone()[0]


def skipped_trials(conn, participant: str, session: int) -> list[int]:
    """The session's skipped quest+ slots (their group stopped early)."""
    return [r[0] for r in conn.execute(
        "SELECT trial FROM trials WHERE participant=? AND session=? AND skipped=1 ORDER BY trial",
        (participant, session))]


def last_quest_state(conn, participant: str, session: int, group: str) -> str | None:
    """The QUEST+ state stored with the group's latest answer (None: no answer yet)."""
    row = conn.execute("""
        SELECT r.quest_state FROM responses r JOIN trials t
             ON t.participant = r.participant AND t.session = r.session AND t.trial = r.trial
        WHERE r.participant=? AND r.session=? AND t.group_name=? AND r.quest_state IS NOT NULL
        ORDER BY r.trial DESC LIMIT 1""", (participant, session, group)).fetchone()
    return None if row is None else row[0]


def set_simulated_truth(conn, participant: str, session: int, truth_json: str) -> None:
    """Record a simulated session's observer parameters (JSON) once: the same
    value again is accepted, a different one is a :class:`ConflictError`."""
    with transaction(conn):
        row = conn.execute("SELECT source, simulated_truth FROM sessions WHERE participant=? AND "
                           "session=?", (participant, session)).fetchone()
        if row is None or row["source"] != "simulated":
            raise ConflictError(f"{participant}/{session} is not a simulated session")
        if row["simulated_truth"] not in (None, truth_json):
            raise ConflictError(f"{participant}/{session}: another simulated truth is stored")
        conn.execute("UPDATE sessions SET simulated_truth=? WHERE participant=? AND session=?",
                     (truth_json, participant, session))


def truth_rows(conn) -> list[dict]:
    """(participant, session, simulated_truth JSON) of the simulated sessions that have one."""
    return [dict(r) for r in conn.execute(
        "SELECT participant, session, simulated_truth FROM sessions WHERE simulated_truth IS NOT "
        "NULL ORDER BY participant, session")]


def answered_trials(conn, participant: str, session: int) -> dict[int, sqlite3.Row]:
    rows = conn.execute("SELECT * FROM responses WHERE participant=? AND session=? ORDER BY trial",
                        (participant, session)).fetchall()
    return {r["trial"]: r for r in rows}


def count_answers(conn, participant: str, session: int) -> int:
    return conn.execute("SELECT COUNT(*) FROM responses WHERE participant=? AND session=?",
                        (participant, session)).fetchone()[0]


# --- answers --------------------------------------------------------------------------------

def insert_answer(conn, participant: str, session: int, n_trials: int, answer: dict,
                  timestamp: str | None = None, adaptive=None, design_text: str | None = None) -> str:
    """Store one checked answer (see :func:`flipstudy.study.validate.parse_answer`).

    Returns ``"stored"``, or ``"duplicate"`` when the same response to the same
    trial is already stored (nothing is written).  Raises :class:`ConflictError` when
    the trial was answered differently (the first answer is kept) or is not the
    participant's current trial (the first one neither answered nor skipped).

    An adaptive (quest+) trial needs ``adaptive(conn, trial_row)``: called inside
    the transaction, after the checks, it returns ``shown_stimulus``,
    ``shown_level``, ``quest_state``, ``quest_threshold``, ``quest_ci_low``,
    ``quest_ci_high`` and ``skip`` (trial numbers of the group's slots to leave
    out) or raises :class:`ConflictError`; everything is written in the one
    transaction.  The session is marked finished with its last open trial.

    ``design_text``: the study's ``design.toml``; the first answer records it and its
    SHA-256 in ``meta`` (``design_toml``, ``design_sha256``), in the same
    transaction; a different design with a recorded one is a :class:`ConflictError`
    (:mod:`flipstudy.study.frozen`).
    """
    trial = answer["trial"]
    with transaction(conn):
        old = conn.execute("SELECT response FROM responses WHERE participant=? AND session=? "
                           "AND trial=?", (participant, session, trial)).fetchone()
        if old is not None:
            if old["response"] == answer["response"]:
                return "duplicate"
            raise ConflictError(f"trial {trial} is already answered ({old['response']}); "
                           f"the first answer is kept")
        current = next_open_trial(conn, participant, session)
        if trial != current:
            raise ConflictError(f"trial {trial} is not the current trial (" +
                           (f"trial {current} is next)" if current else "the session is finished)"))
        row = conn.execute("SELECT * FROM trials WHERE participant=? AND session=? AND trial=?",
                           (participant, session, trial)).fetchone()
        if row is None:
            raise ConflictError(f"trial {trial} does not exist in this session")
        extra = {}
        if (row["method"] or "constant") == "quest+":
            if adaptive is None:
                raise ConflictError(f"trial {trial} is adaptive (quest+); its level is chosen by the session")
            extra = adaptive(conn, row)
        elif row["stimulus"] != answer["stimulus"]:
            raise ConflictError(f"trial {trial} shows {row['stimulus']!r}, not {answer['stimulus']!r}")
        ts = timestamp or utc_now()
        try:
            conn.execute(
                "INSERT INTO responses (participant, session, trial, response, rt_ms, shown_ms, "
                "late_frames, replays, input, timestamp, shown_stimulus, shown_level, quest_state, "
                "quest_threshold, quest_ci_low, quest_ci_high) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)",
                (participant, session, trial, answer["response"], answer["rt_ms"],
                 answer["shown_ms"], answer["late_frames"], answer.get("replays", 0),
                 answer.get("input", "click"), ts, extra.get("shown_stimulus"),
                 extra.get("shown_level"), extra.get("quest_state"), extra.get("quest_threshold"),
                 extra.get("quest_ci_low"), extra.get("quest_ci_high")))
        except sqlite3.IntegrityError as e:
            if "CHECK" in str(e) and not accepts_2afc(conn):
                raise FlipstudyStateError(
                    f"response {answer['response']!r}: this study's sessions.sqlite was made by "
                    f"an older flipstudy (schema 1) and accepts only correct/incorrect; run a 2AFC "
                    f"study in a new study folder") from None
            raise
        if design_text is not None:
            record_design(conn, design_text)
        skip = [int(t) for t in extra.get("skip", ())]
        if skip:
            conn.executemany("UPDATE trials SET skipped=1 WHERE participant=? AND session=? AND "
                             "trial=? AND method='quest+' AND NOT EXISTS (SELECT 1 FROM responses r "
                             "WHERE r.participant=trials.participant AND r.session=trials.session "
                             "AND r.trial=trials.trial)", [(participant, session, t) for t in skip])
        if next_open_trial(conn, participant, session) is None:
            conn.execute("UPDATE sessions SET finished=? WHERE participant=? AND session=?",
                         (ts, participant, session))
    return "stored"


def record_design(conn, design_text: str) -> None:
    """Inside a write transaction: record the design with the first answer; refuse
    (:class:`ConflictError`) an answer given under another design than the recorded one."""
    import hashlib
    sha = hashlib.sha256(design_text.encode()).hexdigest()
    old = conn.execute("SELECT value FROM meta WHERE key='design_sha256'").fetchone()
    if old is None:
        conn.executemany("INSERT INTO meta VALUES (?, ?)",
                         [("design_sha256", sha), ("design_toml", design_text)])
    elif old[0] != sha:
        raise ConflictError("the study's design.toml changed since its first answer; this answer was "
                       "not stored (the design of a study with answers is frozen)")


def insert_demographics(conn, participant: str, session: int, values: dict) -> str:
    """Store the demographics once; ``"duplicate"`` for the same values again,
    :class:`ConflictError` for different ones."""
    cols = ("age", "gender", "animation_experience", "gymnastics_experience")
    with transaction(conn):
        old = conn.execute("SELECT * FROM demographics WHERE participant=? AND session=?",
                           (participant, session)).fetchone()
        if old is not None:
            if all(old[c] == values[c] for c in cols):
                return "duplicate"
            raise ConflictError("the demographics of this session are already stored")
        conn.execute("INSERT INTO demographics VALUES (?,?,?,?,?,?,?)",
                     (participant, session, *(values[c] for c in cols), utc_now()))
    return "stored"


def has_demographics(conn, participant: str, session: int) -> bool:
    return conn.execute("SELECT 1 FROM demographics WHERE participant=? AND session=?",
                        (participant, session)).fetchone() is not None


# --- reading for the experimenter -----------------------------------------------------------

def status_rows(conn) -> list[dict]:
    """One dict per session: participant, session, source, answered, total,
    started, last_answer, finished, simulated (bool), complete (bool: every
    trial answered)."""
    rows = conn.execute(f"""
        SELECT s.participant, s.session, s.source, s.n_trials AS total, s.started, s.finished,
               COUNT(r.trial) AS answered, MAX(r.timestamp) AS last_answer, {_SKIPPED} AS skipped
        FROM sessions s LEFT JOIN responses r
             ON r.participant = s.participant AND r.session = s.session
        GROUP BY s.participant, s.session
        ORDER BY s.participant, s.session""").fetchall()
    out = [dict(r) for r in rows]
    for r in out:
        r["simulated"] = r["source"] == "simulated"
        r["complete"] = r["answered"] + r["skipped"] >= r["total"]
        del r["skipped"]
    return out


#: SQL: the skipped slots of session ``s``
_SKIPPED = ("(SELECT COUNT(*) FROM trials tk WHERE tk.participant = s.participant AND "
            "tk.session = s.session AND tk.skipped = 1)")


def response_rows(conn, *, include_simulated: bool = False) -> list[dict]:
    """Every answered trial joined with its trial row, ordered by participant,
    session, trial; ``simulated`` (0/1: a simulated participant's) and
    ``complete`` (0/1: its session has every trial answered or skipped) on every
    row; ``stimulus`` and ``level`` are what was shown (an adaptive slot's from
    its answer); ``method``, ``task``, ``first``, ``original_stimulus`` and the
    quest+ posterior after the answer (``quest_threshold``, ``quest_ci_low``,
    ``quest_ci_high``; None for constant trials)."""
    rows = conn.execute(f"""
        SELECT t.participant, t.session, t.trial, COALESCE(r.shown_stimulus, t.stimulus) AS stimulus,
               t.group_name, COALESCE(r.shown_level, t.level) AS level, t.repetition,
               r.response, r.rt_ms, r.shown_ms, r.timestamp, t.clip, t.kind, r.late_frames,
               r.replays, r.input, s.source, s.source = 'simulated' AS simulated,
               (SELECT COUNT(*) FROM responses r2 WHERE r2.participant = s.participant
                    AND r2.session = s.session) + {_SKIPPED} >= s.n_trials AS complete,
               COALESCE(t.method, 'constant') AS method, COALESCE(t.task, 'yes-no') AS task,
               COALESCE(t.first, '') AS first, COALESCE(t.original, '') AS original_stimulus,
               r.quest_threshold, r.quest_ci_low, r.quest_ci_high
        FROM responses r
        JOIN trials t ON t.participant = r.participant AND t.session = r.session AND t.trial = r.trial
        JOIN sessions s ON s.participant = r.participant AND s.session = r.session
        {"" if include_simulated else "WHERE s.source != 'simulated'"}
        ORDER BY t.participant, t.session, t.trial""").fetchall()
    return [dict(r) for r in rows]


def participant_rows(conn, *, include_simulated: bool = False) -> list[dict]:
    rows = conn.execute(f"""
        SELECT s.participant, s.session, s.source, d.age, d.gender, d.animation_experience,
               d.gymnastics_experience, s.started, s.finished, s.n_trials,
               (SELECT COUNT(*) FROM responses r WHERE r.participant = s.participant
                    AND r.session = s.session) AS answered,
               s.source = 'simulated' AS simulated, {_SKIPPED} AS skipped
        FROM sessions s LEFT JOIN demographics d
             ON d.participant = s.participant AND d.session = s.session
        {"" if include_simulated else "WHERE s.source != 'simulated'"}
        ORDER BY s.participant, s.session""").fetchall()
    out = [dict(r) for r in rows]
    for r in out:
        r["complete"] = int(r["answered"] + r.pop("skipped") >= r["n_trials"])
    return out


def condition_counts(conn, conditions, source: str) -> dict[str, int]:
    """Sessions of ``source`` in each between-subject condition (``[online] between``): a
    session's condition is the group of ``conditions`` its stored trials show."""
    conditions = list(conditions)
    marks = ",".join("?" * len(conditions))
    rows = conn.execute(
        f"SELECT t.group_name, COUNT(DISTINCT t.participant || '/' || t.session) FROM trials t "
        f"JOIN sessions s ON s.participant = t.participant AND s.session = t.session "
        f"WHERE s.source = ? AND t.group_name IN ({marks}) GROUP BY t.group_name",
        (source, *conditions)).fetchall()
    return {**{c: 0 for c in conditions}, **{r[0]: int(r[1]) for r in rows}}
