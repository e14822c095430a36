"""A study's design is frozen once it has an answer.

The first answer stored in ``sessions.sqlite`` records the SHA-256 and the text of
the study's ``design.toml`` in the ``meta`` table (keys ``design_sha256`` and
``design_toml``, in the answer's own transaction; no schema change, no row
touched).  From then on:

* ``flipstudy init STUDY/design.toml --force`` is refused while the study holds
  any answer (local, simulated, or imported from the web: :func:`flipstudy.study.archive.answers_in`)
  or while a server has it open (:func:`write_design`);
* ``run``, ``export`` and ``analyze`` refuse a study whose ``design.toml`` no longer
  has the recorded hash, and ``status`` flags it on every call
  (:func:`design_change` names the file and the keys that changed).

Examples
--------
>>> import tempfile, pathlib
>>> from flipstudy.study.demo import make_demo_study
>>> from flipstudy.study.simulate import simulate
>>> tmp = tempfile.TemporaryDirectory()
>>> st = make_demo_study(pathlib.Path(tmp.name) / "st")
>>> _ = simulate(st, 1)
>>> design_change(st) is None
True
>>> _ = (st / "design.toml").write_text((st / "design.toml").read_text().replace("seed = 7", "seed = 8"))
>>> msg = design_change(st)
>>> "st/design.toml changed since the study's first answer (study.seed: 7 → 8)" in msg
True
>>> tmp.cleanup()
"""
from __future__ import annotations

import hashlib
import sqlite3
from pathlib import Path

from flipstudy.errors import DesignFrozenError

from .store import DB_NAME


def design_sha256(text: bytes | str) -> str:
    return hashlib.sha256(text.encode() if isinstance(text, str) else text).hexdigest()


def recorded_design(study_dir) -> tuple[str, str] | None:
    """``(sha256, text)`` of the design recorded with the study's first answer, or None
    (no database, no answer yet, or a database from before this record); read only."""
    db = Path(study_dir) / DB_NAME
    if not db.is_file():
        return None
    try:
        conn = sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=30.0)
    except sqlite3.Error:
        return None
    try:
        rows = dict(conn.execute("SELECT key, value FROM meta WHERE key IN "
                                 "('design_sha256', 'design_toml')").fetchall())
    except sqlite3.Error:
        return None
    finally:
        conn.close()
    if "design_sha256" not in rows:
        return None
    return rows["design_sha256"], rows.get("design_toml", "")


def _changed_keys(old: str, new: str) -> list[str]:
    """Dotted keys whose values differ between two design texts (TOML)."""
    import tomllib
    try:
        a, b = tomllib.loads(old), tomllib.loads(new)
    except tomllib.TOMLDecodeError:
        return []
    out: list[str] = []

    def walk(x, y, path):
        if isinstance(x, dict) and isinstance(y, dict):
            for k in sorted(set(x) | set(y), key=str):
                walk(x.get(k), y.get(k), f"{path}.{k}" if path else str(k))
        elif isinstance(x, list) and isinstance(y, list) and len(x) == len(y) and \
                all(isinstance(v, dict) for v in x + y):
            for i, (u, v) in enumerate(zip(x, y)):
                walk(u, v, f"{path}[{i}]")
        elif x != y:
            out.append(f"{path}: {'(none)' if x is None else x} → {'(none)' if y is None else y}")
    walk(a, b, "")
    return out


def design_change(study_dir) -> str | None:
    """A sentence naming ``design.toml`` and what changed since the study's first
    answer, or None when it is unchanged (or no answer recorded a design)."""
    d = Path(study_dir)
    rec = recorded_design(d)
    if rec is None:
        return None
    path = d / "design.toml"
    try:
        now = path.read_bytes()
    except OSError:
        return f"{path} is missing; the study's answers were given under the design recorded in {d / DB_NAME}"
    if design_sha256(now) == rec[0]:
        return None
    keys = _changed_keys(rec[1], now.decode("utf-8", errors="replace"))
    what = "; ".join(keys[:6]) + ("; ..." if len(keys) > 6 else "") if keys else "its text"
    return (f"{path} changed since the study's first answer ({what}); the answers were given "
            f"under the design recorded in {d / DB_NAME} (meta design_toml): restore that design, "
            f"or build a new study for the new one")


def refuse_changed_design(study_dir, command: str) -> None:
    """Raise :class:`DesignFrozenError` when :func:`design_change` finds a change."""
    msg = design_change(study_dir)
    if msg is not None:
        raise DesignFrozenError(f"{msg}; `flipstudy {command}` refuses a study whose design changed")


def write_design(out, text: str, *, force: bool = False) -> None:
    """Write a design file (``flipstudy init``).  Into a study folder only while it
    holds no answer and no server has it open; never over an existing file
    without ``force``."""
    from flipstudy.stimuli._io import atomic_write_text

    from .archive import answers_in, describe, holds_answers
    from .lock import StudyLock, study_closed
    from .owned import is_study
    out = Path(out)
    if out.exists() and not force:
        from flipstudy.errors import FlipstudyFileExistsError
        raise FlipstudyFileExistsError(f"{out} exists; pass --force to overwrite")
    folder = out.parent
    if not is_study(folder):
        atomic_write_text(out, text)
        return
    with StudyLock(folder, "init"), study_closed(folder, "init --force"):
        a = answers_in(folder)
        if holds_answers(a) or a["simulated_answers"] or recorded_design(folder) is not None:
            raise DesignFrozenError(
                f"{out} is the design of the study {folder}, which holds {describe(a)}: a study's "
                f"design is frozen once it has an answer (every participant must see the same "
                f"design). Write the new design elsewhere and build a new study from it")
        atomic_write_text(out, text)
