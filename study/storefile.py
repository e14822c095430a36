"""Is a study's ``sessions.sqlite`` whole?  The checks every opener makes before it
reads or writes a single row, so that a damaged store is named in one line and never
taken for an empty one.

A store is damaged (:class:`~flipstudy.errors.CorruptDatabaseError`, the file left exactly
as it is) when it is:

* a symbolic link to nothing (a dangling link: an unmounted disk, a moved folder),
  a folder, or anything else that is not a regular file (``/dev/zero``, a pipe);
* not a SQLite database, or one whose pages do not read (checked by :mod:`.store`);
* a database without one of the tables of :data:`flipstudy.study.store.SCHEMA`, or
  with a table lacking one of its columns (a ``DROP TABLE sessions`` by hand, the
  database of another program).

An empty file, or a database holding no table at all, is a new store: it holds no
answer.

Examples
--------
>>> import tempfile, pathlib, sqlite3
>>> tmp = tempfile.TemporaryDirectory()
>>> db = pathlib.Path(tmp.name) / "sessions.sqlite"
>>> check_file(db)                                # absent: a store not made yet
>>> db.symlink_to(pathlib.Path(tmp.name) / "gone.sqlite")
>>> check_file(db)
Traceback (most recent call last):
    ...
flipstudy.errors.CorruptDatabaseError: .../sessions.sqlite: a symbolic link to .../gone.sqlite, which does not exist; ...
>>> db.unlink()
>>> conn = sqlite3.connect(db)
>>> _ = conn.execute("CREATE TABLE responses (participant TEXT)")
>>> from flipstudy.study.store import SCHEMA
>>> check_tables(conn, db, SCHEMA)
Traceback (most recent call last):
    ...
flipstudy.errors.CorruptDatabaseError: .../sessions.sqlite: table sessions is missing (and ... more), ...
>>> conn.close(); tmp.cleanup()
"""
from __future__ import annotations

import os
import sqlite3
import stat
from functools import lru_cache
from pathlib import Path

from flipstudy.errors import CorruptDatabaseError

__all__ = ["file_problem", "check_file", "check_tables", "missing_tables", "what_is_missing", "damaged"]


def damaged(path, what: str) -> CorruptDatabaseError:
    """The one-line error for a store that is not whole: names the file and what is wrong."""
    return CorruptDatabaseError(
        f"{path}: {what}; it was left exactly as it is and no answer in it is taken for none. "
        f"Restore it from a backup, or move the study aside with `flipstudy archive` (it keeps "
        f"everything) and ask for help recovering it")


def file_problem(path) -> str | None:
    """What makes ``path`` no SQLite database file ("a folder", ...), None when it is
    absent or a regular file (a symbolic link to one is)."""
    p = Path(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        return f"a symbolic link to {os.readlink(p)}, which does not exist" if p.is_symlink() else None
    except OSError as e:
        return f"cannot be looked at ({e.strerror})"
    if stat.S_ISDIR(st.st_mode):
        return "a folder, not a SQLite database file"
    if not stat.S_ISREG(st.st_mode):
        return "not a regular file (a device, pipe or socket), so not a SQLite database"
    return None


def check_file(path) -> None:
    """Raise :func:`damaged` unless ``path`` is absent or a regular file (:func:`file_problem`)."""
    problem = file_problem(path)
    if problem is not None:
        raise damaged(path, problem)


#: the tables named first when several are missing (where the answers are)
FIRST = ("sessions", "responses", "trials")


@lru_cache(maxsize=2)
def expected_columns(schema: str) -> dict[str, frozenset]:
    """Table → column names of a new store made by ``schema`` (SQL, e.g.
    :data:`flipstudy.study.store.SCHEMA`)."""
    conn = sqlite3.connect(":memory:")
    try:
        conn.executescript(schema)
        return {t: frozenset(r[1] for r in conn.execute(f"PRAGMA table_info({t})"))
                for (t,) in conn.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    finally:
        conn.close()


def missing_tables(conn: sqlite3.Connection, schema: str, tables=None, *,
                   columns: bool = True) -> list[str]:
    """``"sessions"``, ``"responses.rt_ms"``, ...: the tables (or columns) of ``schema``
    that the database of ``conn`` lacks; ``[]`` for a whole store and for a database
    with no table at all (a new store).  ``tables``: only these (default: all);
    ``columns`` False: the tables only (a version-1 store lacks version 2's columns)."""
    want = expected_columns(schema)
    have = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    if not have:
        return []
    tables = list(tables or sorted(want, key=lambda t: (t not in FIRST, FIRST.index(t) if t in FIRST
                                                        else 0, t)))
    gone = [t for t in tables if t not in have]
    for t in tables if columns else ():
        if t in have:
            cols = {r[1] for r in conn.execute(f"PRAGMA table_info({t})")}
            gone += [f"{t}.{c}" for c in sorted(want[t] - cols)]
    return gone


def check_tables(conn: sqlite3.Connection, path, schema: str, tables=None, *,
                 columns: bool = True) -> None:
    """Raise :func:`damaged` naming the first missing table (or column) of ``schema``."""
    gone = missing_tables(conn, schema, tables, columns=columns)
    if gone:
        raise damaged(path, f"{what_is_missing(gone)}, so it is not a whole flipstudy answer database")


def what_is_missing(gone: list[str]) -> str:
    """``"table sessions is missing (and 2 more)"`` for :func:`missing_tables`' list."""
    what = (f"table {gone[0]} is missing" if "." not in gone[0] else
            f"column {gone[0].split('.')[1]} of table {gone[0].split('.')[0]} is missing")
    return what + (f" (and {len(gone) - 1} more)" if len(gone) > 1 else "")
