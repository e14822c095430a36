"""What a study folder holds, the guard that keeps answers from being replaced,
and ``flipstudy archive`` (move a whole study aside, under a dated name).

"Real answers" are answers of participants who are not simulated: rows of
``sessions.sqlite`` whose session's ``source`` is not ``simulated`` (or that have no
session row), the raw web results ``import-web`` keeps (``web/imports/*``), and rows of
any exported or imported response table in the folder (a ``*.csv`` with
``participant`` and ``response`` columns) that are not marked simulated (column
``simulated`` true, or ``input`` = ``simulated`` in tables exported before that
column existed).  A database that cannot be read, or that lacks one of its tables,
counts as holding real answers.

Examples
--------
A tiny study with two simulated participants:

>>> import tempfile, pathlib
>>> from flipstudy.study.demo import make_demo_study
>>> from flipstudy.study.simulate import simulate
>>> tmp = tempfile.TemporaryDirectory()
>>> study = make_demo_study(pathlib.Path(tmp.name) / "study")
>>> simulate(study, 2, seed=1)
['sim001', 'sim002']
>>> answers_in(study)
{'real_answers': 0, 'real_participants': [], 'simulated_answers': 16, 'simulated_participants': ['sim001', 'sim002'], ...}
>>> archive_study(study).name                            # moved aside, under a dated name
'study-archived-...Z'
>>> study.exists()
False
>>> tmp.cleanup()
"""
from __future__ import annotations

import csv
import os
import sqlite3
from datetime import datetime, timezone
from pathlib import Path

from flipstudy.errors import ArchiveError, StudyHasAnswersError

from .store import DB_NAME, SCHEMA

TRUE = {"1", "true", "yes", "y", "t"}
#: where ``import-web`` keeps the raw web results it read
RAW_DIR = "web/imports"


def _db_answers(path: Path) -> tuple[dict, dict]:
    """(real, simulated): participant → number of answers, from ``sessions.sqlite``."""
    from .storefile import file_problem, missing_tables, what_is_missing
    real: dict = {}
    sim: dict = {}
    problem = file_problem(path)
    if problem is not None:
        raise sqlite3.DatabaseError(problem)
    uri = f"file:{path}?mode=rw"           # never creates; as the last reader it removes the -wal/-shm it made
    conn = sqlite3.connect(uri, uri=True, timeout=30.0)
    try:
        tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        if not tables:
            return real, sim                 # an empty database: a store not used yet
        gone = missing_tables(conn, SCHEMA,        # a version-1 store lacks version 2's columns
                              columns=conn.execute("PRAGMA user_version").fetchone()[0] != 1)
        if gone:                             # answers may be in what is left: never "none"
            raise sqlite3.DatabaseError(what_is_missing(gone))
        for pid, source, n in conn.execute(  # an answer without its session row is a real one
                "SELECT r.participant, s.source, COUNT(*) FROM responses r LEFT JOIN sessions s "
                "ON s.participant = r.participant AND s.session = r.session "
                "GROUP BY r.participant, s.source"):
            d = sim if source == "simulated" else real
            d[pid] = d.get(pid, 0) + n
    finally:
        conn.close()
    return real, sim


def _csv_answers(path: Path) -> tuple[dict, dict] | None:
    """(real, simulated) answer counts of a response table, None if it is not one."""
    real: dict = {}
    sim: dict = {}
    try:
        with path.open(newline="", encoding="utf-8", errors="replace") as f:
            r = csv.DictReader(f)
            if not r.fieldnames or not {"participant", "response"} <= set(r.fieldnames):
                return None
            for row in r:
                simulated = ((row.get("simulated") or "").strip().lower() in TRUE
                             or (row.get("input") or "").strip() == "simulated")
                d = sim if simulated else real
                d[row["participant"]] = d.get(row["participant"], 0) + 1
    except (OSError, csv.Error):
        return {"<unreadable>": 1}, {}
    return real, sim


def answers_in(study_dir) -> dict:
    """What answers a study folder holds: ``real_answers``, ``real_participants``
    (sorted IDs), ``simulated_answers``, ``simulated_participants``, ``where``
    (the files holding real answers) and ``unreadable`` (files that could not be
    read, counted as holding real answers)."""
    d = Path(study_dir)
    real: dict = {}
    sim: dict = {}
    where, unreadable = [], []
    db = d / DB_NAME
    if db.exists() or db.is_symlink():
        try:
            r, s = _db_answers(db)
        except sqlite3.Error as e:
            unreadable.append(f"{db.name} ({e})")
            r, s = {}, {}
        if r:
            where.append(db.name)
        for k, v in r.items():
            real[k] = real.get(k, 0) + v
        for k, v in s.items():
            sim[k] = sim.get(k, 0) + v
    if d.is_dir():
        for p in sorted(d.rglob("*.csv")):
            if p.name == "manifest.csv" or "analysis" in p.relative_to(d).parts[:-1]:
                continue
            got = _csv_answers(p)
            if got is None:
                continue
            r, s = got
            rel = str(p.relative_to(d))
            if "<unreadable>" in r:
                unreadable.append(rel)
                continue
            if r:
                where.append(rel)
            for k, v in r.items():          # an export repeats the database: count once
                real[k] = max(real.get(k, 0), v)
            for k, v in s.items():
                sim[k] = max(sim.get(k, 0), v)
    raw = _raw_imports(d)
    if raw:
        where.append(f"{RAW_DIR}/")
    return {"real_answers": sum(real.values()), "real_participants": sorted(real),
            "simulated_answers": sum(sim.values()), "simulated_participants": sorted(sim),
            "where": where, "unreadable": unreadable, "raw_imports": raw}


def _raw_imports(d: Path) -> list[str]:
    """The raw web results ``import-web`` keeps (``web/imports/*``): participants'
    answers as they came, whatever the tables say."""
    from .owned import files_below
    imports = d / RAW_DIR
    if not imports.is_dir() or imports.is_symlink():
        return [RAW_DIR] if imports.exists() or imports.is_symlink() else []
    return [f"{RAW_DIR}/{f}" for f in files_below(imports)]


def holds_answers(a: dict) -> bool:
    """Does the :func:`answers_in` summary ``a`` count anything a command must not
    replace: a real answer, a file that could not be read, a raw web result?"""
    return bool(a["real_answers"] or a["unreadable"] or a.get("raw_imports"))


def describe(a: dict) -> str:
    """``"300 answers of 12 real participant(s) (sessions.sqlite)"`` and so on."""
    parts = []

    def answers(n: int) -> str:
        return f"{n} answer{'' if n == 1 else 's'}"
    if a["real_answers"]:
        parts.append(f"{answers(a['real_answers'])} of {len(a['real_participants'])} real "
                     f"participant(s) ({', '.join(a['where'])})")
    if a["unreadable"]:
        parts.append(f"file(s) that could not be read ({', '.join(a['unreadable'])})")
    if a.get("raw_imports"):
        parts.append(f"{len(a['raw_imports'])} raw web result file(s) kept by import-web ({RAW_DIR}/)")
    if a["simulated_answers"]:
        parts.append(f"{answers(a['simulated_answers'])} of {len(a['simulated_participants'])} "
                     f"simulated participant(s)")
    return "; ".join(parts) or "no answers"


def refuse_real_answers(folder, foreign=(), *, shown=None, command: str = "stimuli --force"):
    """Raise :class:`StudyHasAnswersError` when ``folder`` holds any real answer (or a
    file that cannot be read); return the :func:`answers_in` summary otherwise.
    Used as ``replace_check`` of :func:`flipstudy.stimuli.stimset.build_stimuli`."""
    shown = Path(shown) if shown is not None else Path(folder)
    a = answers_in(folder)
    if holds_answers(a):
        raise StudyHasAnswersError(
            f"{shown} holds {describe(a)}; `flipstudy {command}` never replaces a study with "
            f"participants' answers. Move it aside first with `flipstudy archive {shown}` (it "
            f"keeps everything, under {shown.name}-archived-DATE), or build into another --out")
    return a


def archive_name(study_dir, now: datetime | None = None) -> Path:
    d = Path(study_dir)
    stamp = (now or datetime.now(timezone.utc)).strftime("%Y%m%dT%H%M%SZ")
    dest = d.with_name(f"{d.name}-archived-{stamp}")
    i = 2
    while dest.exists():
        dest = d.with_name(f"{d.name}-archived-{stamp}-{i}")
        i += 1
    return dest


def archive_study(study_dir, dest=None) -> Path:
    """Move the whole study folder to ``dest`` (default ``NAME-archived-DATE``
    beside it) with one rename (nothing is copied or deleted), holding the
    study's build lock so that no build writes it meanwhile.  Returns ``dest``."""
    from flipstudy.stimuli.stimset import _renameat2, RENAME_NOREPLACE, study_lock
    d = Path(study_dir)
    if d.is_symlink() or not d.is_dir():
        raise ArchiveError(f"{d}: no such study folder")
    dest = Path(dest) if dest is not None else archive_name(d)
    if dest.exists():
        raise ArchiveError(f"{dest} exists; choose another --to")
    dest.parent.mkdir(parents=True, exist_ok=True)
    from .lock import StudyLock, study_closed
    with study_lock(d, "archive"), StudyLock(d, "archive"), study_closed(d, "archive"):
        try:
            if not _renameat2(d, dest, RENAME_NOREPLACE):
                if dest.exists():
                    raise ArchiveError(f"{dest} exists; choose another --to")
                os.rename(d, dest)
        except OSError as e:
            if isinstance(e, ArchiveError):
                raise
            raise ArchiveError(f"cannot move {d} to {dest}: {e.strerror} (the archive must be on "
                               f"the same file system; nothing was moved)") from None
    return dest
