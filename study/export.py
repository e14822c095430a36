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

A study with a quest+ or 2AFC group gets seven more columns at the end of
``responses.csv``: ``method`` (constant / quest+), ``task`` (yes-no / 2afc),
``first`` (what a 2AFC trial showed first: original / modified), and
``original_stimulus`` (a 2AFC trial's comparison), and on quest+ rows
``quest_threshold``, ``quest_ci_low``, ``quest_ci_high`` (the group's QUEST+
posterior of the threshold x* after that answer: mean and 95 % interval, percent).
``stimulus`` and ``level`` are what the trial showed (an adaptive trial's level is
QUEST+'s choice).  Other studies' files keep the columns above, byte for byte.

With simulated participants included, ``simulated_truth.csv`` beside them holds
each simulated session's known observer parameters per group (participant,
session, group, task, threshold, width, gamma, lapse: the psychometric function
the simulated answers were drawn from, :mod:`flipstudy.study.simulate`), so an
analysis can check that it recovers them.

Simulated participants are left out of both files unless
``include_simulated=True`` (``flipstudy export --include-simulated``); when
included, every one of their rows says ``simulated=true``.  Both files are
written to a temporary file in the same folder and renamed into place
(``os.replace``), so a reader never sees half a file.
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError
from flipstudy.results import ExportResult

import csv
import io
from pathlib import Path

from flipstudy.stimuli.contract import StimulusSet
from flipstudy.stimuli._io import atomic_write_text
from flipstudy.vocab import answers

from . import store
from .lock import study_writer

#: the columns, as the answer record declares them (:mod:`flipstudy.vocab.answers`)
RESPONSE_COLUMNS = list(answers.RESPONSE_COLUMNS)
ADAPTIVE_COLUMNS = list(answers.ADAPTIVE_COLUMNS)
TRUTH_FILE = "simulated_truth.csv"
TRUTH_COLUMNS = list(answers.TRUTH_COLUMNS)
PARTICIPANT_COLUMNS = list(answers.PARTICIPANT_COLUMNS)


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
    for k in ("quest_threshold", "quest_ci_low", "quest_ci_high"):
        out[k] = "" if r.get(k) is None else f"{r[k]:.4f}"
    return out


def _adaptive_study(conn, study_dir: Path) -> bool:
    """Has the study a quest+ or 2AFC group (its design) or trial (its database)?"""
    design = study_dir / "design.toml"
    if design.is_file():
        from flipstudy.stimuli.design import load_design
        try:
            if any(g.adaptive or g.task != "yes-no" for g in load_design(design).groups):
                return True
        except Exception:                      # an unreadable design: the database says
            pass
    return conn.execute("SELECT 1 FROM trials WHERE method = 'quest+' OR task = '2afc' LIMIT 1"
                        ).fetchone() is not None


def truth_table(rows: list[dict]) -> list[dict]:
    """The rows of ``simulated_truth.csv`` from :func:`flipstudy.study.store.truth_rows`."""
    import json
    out = []
    for r in rows:
        truth = json.loads(r["simulated_truth"])
        for g, o in truth.get("groups", {}).items():
            out.append({"participant": r["participant"], "session": r["session"], "group": g,
                        **{k: o[k] for k in TRUTH_COLUMNS[3:]}})
    return out


def study_stimuli(study) -> StimulusSet | None:
    """A study's :class:`~flipstudy.stimuli.contract.StimulusSet`: ``study`` itself
    when it is one, else read from the folder ``study`` (checked once; the motion
    files are not needed to export answers); None when the folder has no manifest."""
    if isinstance(study, StimulusSet):
        return study
    if not (Path(study) / "manifest.csv").is_file():
        return None
    return StimulusSet.read(study, files=False, design=False)


def _manifest_styles(stimuli: StimulusSet | None) -> dict | None:
    """Stimulus → character style, or None when there are no stimuli or the
    manifest has no ``style`` column."""
    if stimuli is None or not stimuli.styled:
        return None
    return {s.stimulus: s.style.strip() for s in stimuli}


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


@study_writer("export")
def export_responses(study_dir, out=None, *, participants_out=None,
                     include_simulated: bool = False) -> ExportResult:
    """Write ``responses.csv`` (default ``STUDY_DIR/responses.csv``; ``study_dir``: the
    study folder or its :class:`~flipstudy.stimuli.contract.StimulusSet`) and
    ``participants.csv`` beside it (and ``simulated_truth.csv`` when simulated
    sessions with known observers are included).  Returns an
    :class:`~flipstudy.results.ExportResult`: the paths (``truth`` None when not
    written), ``rows``, ``sessions``, the ``real`` and ``simulated`` IDs written,
    ``simulated_left_out`` and ``incomplete`` (``"P07/1 (6/18)"``, ...)."""
    from .owned import EXPORT_FILES, refuse_owned
    stimuli = study_stimuli(study_dir)
    study_dir = stimuli.folder if stimuli is not None else Path(study_dir)
    out = Path(out) if out is not None else study_dir / "responses.csv"
    pout = Path(participants_out) if participants_out is not None else out.parent / "participants.csv"
    if pout.resolve() == out.resolve():
        raise FlipstudyValueError(f"{out}: the responses and participants tables need different files")
    for path, flag in ((out, "--out"), (pout, "--participants-out"),
                       (out.parent / TRUTH_FILE, "--out (its simulated_truth.csv)")):
        refuse_owned(path, f"export {flag}", study=study_dir, allow=tuple(EXPORT_FILES))
    if out.name != "responses.csv":
        # a table under another name must not replace the default export's tables beside it
        from .owned import OwnedPathError, owner
        for path, what in (((pout, "--participants-out FILE") if participants_out is None else (None, "")),
                           (out.parent / TRUTH_FILE, "another --out folder")):
            if path is not None and path.exists() and owner(path) is not None:
                raise OwnedPathError(
                    f"--out {out} would also write {path}, the table of the study's default export "
                    f"(that goes with {out.parent / 'responses.csv'}); pass {what}, or export to "
                    f"{out.parent / 'responses.csv'} or a folder outside the study")
    from .frozen import refuse_changed_design
    refuse_changed_design(study_dir, "export")
    conn = store.connect(study_dir, create=False)
    try:
        rows = [_fmt_response(r) for r in store.response_rows(conn, include_simulated=include_simulated)]
        parts = store.participant_rows(conn, include_simulated=True)
        adaptive = _adaptive_study(conn, study_dir)
        truth = truth_table(store.truth_rows(conn)) if include_simulated else []
    finally:
        conn.close()
    styles = _manifest_styles(stimuli)
    columns = response_columns(styles is not None) + (ADAPTIVE_COLUMNS if adaptive else [])
    if styles is not None:
        for r in rows:
            r["style"] = styles.get(r["stimulus"], "")
    sims = sorted({p["participant"] for p in parts if p["simulated"]})
    written = [p for p in parts if include_simulated or not p["simulated"]]
    for p in written:
        p["simulated"], p["complete"] = _flag(p["simulated"]), _flag(p["complete"])
    atomic_write_text(out, _csv(columns, rows))
    atomic_write_text(pout, _csv(PARTICIPANT_COLUMNS, written))
    tout = None
    if truth:
        tout = out.parent / TRUTH_FILE
        atomic_write_text(tout, _csv(TRUTH_COLUMNS, truth))
    from .psychds import write_data_files, write_dataset_description   # Psych-DS: data/ and metadata
    name = study_dir.name
    if (study_dir / "design.toml").is_file():
        from flipstudy.stimuli.design import load_design
        name = load_design(study_dir / "design.toml").name
    write_data_files(out.parent, name, "local", {"": _csv(columns, rows),
                                                 "participants": _csv(PARTICIPANT_COLUMNS, written)})
    write_dataset_description(out.parent, study_dir, list(dict.fromkeys(columns + PARTICIPANT_COLUMNS)),
                              source="local sessions", stimuli=stimuli)
    return ExportResult(
        responses=out, participants=pout, truth=tout, rows=len(rows), sessions=len(written),
        real=tuple(sorted({p["participant"] for p in written if p["simulated"] == "false"})),
        simulated=tuple(sims) if include_simulated else (),
        simulated_left_out=() if include_simulated else tuple(sims),
        incomplete=tuple(f"{p['participant']}/{p['session']} ({p['answered']}/{p['n_trials']})"
                         for p in written if p["complete"] == "false"))


def status(study_dir) -> list[dict]:
    """One dict per session: participant, session, source, answered, total,
    started, last_answer, finished (timestamp or None)."""
    conn = store.connect(study_dir, create=False)
    try:
        return store.status_rows(conn)
    finally:
        conn.close()


def _has_rows(path: Path) -> bool:
    with open(path, newline="", encoding="utf-8") as f:
        rows = csv.reader(f)
        next(rows, None)                                   # the header
        return any(any(cell.strip() for cell in row) for row in rows)


def refuse_no_answers(path) -> None:
    """Before ``flipstudy analyze``: a study folder without ``responses.csv``, or a
    study's ``responses.csv`` without a row, raises :class:`~flipstudy.errors.NeedsExportError`
    whose message names the commands that work from what the study's sessions hold
    (none yet: ``run`` or ``simulate``; only simulated ones: ``--include-simulated``).
    Anything else (a table with rows, a file outside a study) passes.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from flipstudy.errors import NeedsExportError
    >>> from flipstudy.study.demo import make_demo_study
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     study = make_demo_study(pathlib.Path(tmp) / "s", videos=False)
    ...     try:
    ...         refuse_no_answers(study)
    ...     except NeedsExportError as e:
    ...         print("no sessions yet" in str(e), "flipstudy simulate" in str(e))
    True True
    """
    from flipstudy.errors import NeedsExportError
    p = Path(path)
    d, csv_path = (p, p / "responses.csv") if p.is_dir() else (p.parent, p)
    if not (d / "manifest.csv").is_file() or (not p.is_dir() and not p.is_file()):
        return
    if csv_path.is_file() and _has_rows(csv_path):
        return
    what = f"{csv_path} holds no answers" if csv_path.is_file() else \
        f"{d} is a study folder without responses.csv"
    sessions = status(d) if store.db_path(d).exists() else []
    n_real = sum(1 for s in sessions if not s["simulated"])
    n_sim = len(sessions) - n_real
    if n_real:
        raise NeedsExportError(f"{what}: run `flipstudy export {d}` first, then `flipstudy analyze {d}`")
    if n_sim:
        raise NeedsExportError(f"{what}: its {n_sim} session(s) are all simulated, which export and "
                          f"analyze leave out by default: run `flipstudy export {d} "
                          f"--include-simulated`, then `flipstudy analyze {d} --include-simulated`")
    web = (f"; answers imported from the web are analysed with `flipstudy analyze {d / 'web'}`"
           if (d / "web" / "responses.csv").is_file() else "")
    raise NeedsExportError(f"{what} and no sessions yet: run `flipstudy run {d} --participant ID`, then "
                      f"`flipstudy export {d}` and `flipstudy analyze {d}`; or pilot it with "
                      f"`flipstudy simulate {d} --participants 4`, `flipstudy export {d} "
                      f"--include-simulated` and `flipstudy analyze {d} --include-simulated`{web}")
