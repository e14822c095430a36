"""Experimenter output: the response table and the participants table.

``responses.csv`` is DESIGN.md's long format, one row per answered trial::

    participant, session, trial, stimulus, group, level, repetition, response,
    rt_ms, shown_ms, timestamp, clip, kind, late_frames, replays, input,
    simulated, complete

(``trial`` and ``repetition`` 1-based, ``level`` the nominal error in percent,
``timestamp`` ISO 8601 UTC of the moment the answer was stored, ``simulated``
``true`` for an answer of a simulated participant (``flipstudy simulate``),
``complete`` ``false`` for an answer of a session that did not answer every
trial).  When the study's ``manifest.csv`` has a ``style`` column (a design that
sets a character style), a ``style`` column follows ``kind``: the style of each
trial's stimulus, from its manifest row, so the analysis splits by style
without a join; without one the table is as above.  ``participants.csv`` (next to it) has one row per session:
participant, session, source (browser/simulated), age (empty: not given),
gender, animation_experience, gymnastics_experience, started, finished,
answered, n_trials, simulated, complete.  ``dataset_description.json`` (Psych-DS,
:mod:`flipstudy.study.psychds`) beside them names the columns, the design, the
stimuli's hashes and the software versions.

Simulated participants are left out of both files unless
``include_simulated=True`` (``flipstudy export --include-simulated``); when
included, every one of their rows says ``simulated=true``.  Both files are
written to a temporary file in the same folder and renamed into place
(``os.replace``), so a reader never sees half a file.
"""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyValueError

import csv
import io
from pathlib import Path

from flipstudy.stimuli._io import atomic_write_text

from . import store

RESPONSE_COLUMNS = ["participant", "session", "trial", "stimulus", "group", "level", "repetition",
                    "response", "rt_ms", "shown_ms", "timestamp", "clip", "kind", "late_frames",
                    "replays", "input", "simulated", "complete"]
PARTICIPANT_COLUMNS = ["participant", "session", "source", "age", "gender", "animation_experience",
                       "gymnastics_experience", "started", "finished", "answered", "n_trials",
                       "simulated", "complete"]


def _flag(v) -> str:
    return "true" if v else "false"


def _csv(columns, rows) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow(["" if r.get(c) is None else r[c] for c in columns])
    return buf.getvalue()


def _fmt_response(r: dict) -> dict:
    out = dict(r)
    out["group"] = r["group_name"]
    out["level"] = f"{r['level']:g}"
    out["rt_ms"] = f"{r['rt_ms']:.1f}"
    out["shown_ms"] = f"{r['shown_ms']:.1f}"
    out["simulated"], out["complete"] = _flag(r["simulated"]), _flag(r["complete"])
    return out


def _manifest_styles(study_dir: Path) -> dict | None:
    """Stimulus → character style from ``manifest.csv``, or None when the
    manifest (or its ``style`` column) is absent."""
    p = study_dir / "manifest.csv"
    if not p.is_file():
        return None
    with p.open(newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        if "style" not in (reader.fieldnames or ()):
            return None
        return {r["stimulus"]: (r.get("style") or "").strip() for r in reader}


def response_columns(styled: bool) -> list[str]:
    """The columns of ``responses.csv``: :data:`RESPONSE_COLUMNS`, with ``style``
    after ``kind`` for a study whose manifest has a style.

    >>> response_columns(True)[11:14]
    ['clip', 'kind', 'style']
    >>> response_columns(False) == RESPONSE_COLUMNS
    True
    """
    if not styled:
        return list(RESPONSE_COLUMNS)
    k = RESPONSE_COLUMNS.index("kind") + 1
    return RESPONSE_COLUMNS[:k] + ["style"] + RESPONSE_COLUMNS[k:]


def export_responses(study_dir, out=None, *, participants_out=None,
                     include_simulated: bool = False) -> dict:
    """Write ``responses.csv`` (default ``STUDY_DIR/responses.csv``) and
    ``participants.csv`` beside it.  Returns ``{"responses": path, "participants":
    path, "rows": n, "sessions": m, "real": [IDs], "simulated": [IDs written],
    "simulated_left_out": [IDs], "incomplete": ["P07/1 (6/18)", ...]}``."""
    study_dir = Path(study_dir)
    out = Path(out) if out is not None else study_dir / "responses.csv"
    pout = Path(participants_out) if participants_out is not None else out.parent / "participants.csv"
    if pout.resolve() == out.resolve():
        raise FlipstudyValueError(f"{out}: the responses and participants tables need different files")
    conn = store.connect(study_dir, create=False)
    try:
        rows = [_fmt_response(r) for r in store.response_rows(conn, include_simulated=include_simulated)]
        parts = store.participant_rows(conn, include_simulated=True)
    finally:
        conn.close()
    styles = _manifest_styles(study_dir)
    columns = response_columns(styles is not None)
    if styles is not None:
        for r in rows:
            r["style"] = styles.get(r["stimulus"], "")
    sims = sorted({p["participant"] for p in parts if p["simulated"]})
    written = [p for p in parts if include_simulated or not p["simulated"]]
    for p in written:
        p["simulated"], p["complete"] = _flag(p["simulated"]), _flag(p["complete"])
    atomic_write_text(out, _csv(columns, rows))
    atomic_write_text(pout, _csv(PARTICIPANT_COLUMNS, written))
    from .psychds import write_dataset_description      # Psych-DS metadata beside them
    write_dataset_description(out.parent, study_dir, columns, source="local sessions")
    return {"responses": out, "participants": pout, "rows": len(rows), "sessions": len(written),
            "real": sorted({p["participant"] for p in written if p["simulated"] == "false"}),
            "simulated": sims if include_simulated else [],
            "simulated_left_out": [] if include_simulated else sims,
            "incomplete": [f"{p['participant']}/{p['session']} ({p['answered']}/{p['n_trials']})"
                           for p in written if p["complete"] == "false"]}


def status(study_dir) -> list[dict]:
    """One dict per session: participant, session, source, answered, total,
    started, last_answer, finished (timestamp or None)."""
    conn = store.connect(study_dir, create=False)
    try:
        return store.status_rows(conn)
    finally:
        conn.close()
