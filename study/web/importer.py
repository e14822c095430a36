"""``flipstudy import-web``: the site's records back into the study.

The files a researcher gets back, each read by its content:

* JATOS: the result data (``Export results → data``: the component's appended
  lines, one JSON record per line) or the results archive (``.zip``, each
  ``data.txt`` inside read the same way);
* Pavlovia: the CSV the site saved in the project's ``data/`` folder (one record
  per row);
* the participant's download (``flipstudy-STUDY-ID-RUN.jsonl``, one JSON record per
  line), also a JSON array of records.

Every record is checked before anything is written: its format, the study's
name (the design's) and manifest hash (a site of other stimuli is refused), its
site id (one of the sites ``export-web`` exported from this study, listed in
``STUDY/web/sites.json``; a study without that list, exported by an older
flipstudy, checks the name and manifest only), each field's type and range,
and each answer's stimulus, group, level and repetition against the
participant's trial order recomputed with :func:`flipstudy.study.web.order.web_trial_order`.
A bad record refuses the whole import, naming the file and the line or row.

Nothing is overwritten and nothing is counted twice.  Each imported file is kept
as it was, under ``STUDY/web/imports/`` named by its SHA-256 (``web/imports.json``
lists them in the order they were imported, with when and what they added), and
``STUDY/web/responses.csv`` (with ``participants.csv`` and a Psych-DS
``dataset_description.json``) is rebuilt from all kept files: the same record
read twice (a file imported again, a JATOS export and the participant's
download of the same run, a record resent after a reload) is one row; a file
already imported is skipped and reported, and a file whose every record is
already kept is read but not kept (nor re-read by later imports).  Runs without a
recorded agreement to the consent text, and runs with two different records for one
trial, are kept out of the tables and listed in ``web/quarantine.csv`` (see
:mod:`flipstudy.study.web._runs`); the rest is imported.  Web participants are kept apart from local ones:
an ID that also has sessions in ``sessions.sqlite`` is refused.  Each browser
run of a participant is a session, numbered by the run's start time.

The rows are the local export's columns (``source`` = ``web-jatos``,
``web-pavlovia`` or ``web-static``; ``style`` after ``kind`` when the manifest
has a style column, as ``flipstudy export`` writes it) plus the playback record: ``frames_expected,
frames_presented, frames_dropped, dropped_pct, playback_ms, video_ms,
refresh_hz, timing, playback_flagged, max_dropped_pct``, ``repeat`` and ``run_id``,
``source_file``.

A site exported with ``[session] repeat_dropped = true`` shows each flagged trial
once more at the end; that answer is a second row of the same trial with
``repeat = 1`` (the first, ``repeat = 0``, is kept with its flag).  A repeat of a
trial whose first answer was not flagged, or a second repeat, is refused.
``complete`` and ``answered`` count first answers only.
"""
from __future__ import annotations

import csv
import hashlib
import io
import json
import re
from pathlib import Path

from flipstudy.stimuli._io import atomic_write_text
from flipstudy.vocab import answers

from .. import store
from ..lock import study_writer
from ..export import (ADAPTIVE_COLUMNS, PARTICIPANT_COLUMNS, RESPONSE_COLUMNS, _manifest_styles,
                      response_columns)
from ..psychds import write_dataset_description
from ..session import load_study
from ..validate import DEMOGRAPHIC_FIELDS, MAX_REPLAYS, MAX_RT_MS, MAX_SHOWN_MS, PARTICIPANT_RE
from flipstudy.errors import WebImportError
from flipstudy.records import ImportedFile
from flipstudy.results import ImportResult
from ._fields import _bool, _need, _num, _str
from ._read import MAX_FILE, MAX_IMPORT, Budget, read_records, read_results_file  # noqa: F401 (public here)
from ._runs import (QUARANTINE_COLUMNS, WINDOW_RE, check_id, check_text, check_time, consent_of,
                    set_aside)
from .opaque import Revealer
from .order import balanced_latin_square, condition_groups, order_groups, web_trial_order
from .sites import SITES, read_sites as _sites
from .site import FORMAT, HOSTS, PARTICIPANT_PARAMS

WEB_DIR = "web"
IMPORTS = "imports"
WEB_COLUMNS = ["source", "run_id", "frames_expected", "frames_presented", "frames_dropped",
               "dropped_pct", "playback_ms", "video_ms", "refresh_hz", "timing", "playback_flagged",
               "max_dropped_pct", "repeat", "source_file"]
COLUMNS = RESPONSE_COLUMNS + WEB_COLUMNS
#: a study with 2AFC groups: the local export's task columns too (no quest+ online)
COLUMNS_2AFC = RESPONSE_COLUMNS + [c for c in ADAPTIVE_COLUMNS if not c.startswith("quest_")] + WEB_COLUMNS


def web_columns(two_afc: bool, styled: bool) -> list[str]:
    """The columns of ``web/responses.csv``: :data:`COLUMNS` or :data:`COLUMNS_2AFC`,
    with ``style`` after ``kind`` (as ``flipstudy export`` writes it) when the
    manifest has a style column.

    >>> web_columns(False, True)[11:14], web_columns(True, False) == COLUMNS_2AFC
    (['clip', 'kind', 'style'], True)
    """
    task = [c for c in ADAPTIVE_COLUMNS if not c.startswith("quest_")] if two_afc else []
    return response_columns(styled) + task + WEB_COLUMNS
WEB_PARTICIPANT_COLUMNS = PARTICIPANT_COLUMNS + ["run_id", "host", "participant_from", "refresh_hz",
                                                 "user_agent", "consent", "window", "screen_ok", "block_order", "latin_row", "condition"]
RECRUIT_RE = re.compile(r"[A-Za-z0-9_-]{1,64}")
KINDS = ("start", "demographics", "answer", "end")
#: the answers each task takes: yes/no judges one motion, 2AFC names the interval judged
#: physically correct
RESPONSES_BY_TASK = {"yes-no": ("correct", "incorrect"), "2afc": ("first", "second")}


# --- checking --------------------------------------------------------------------------------

COMMON = ("format", "record", "site_id", "study", "manifest_sha256", "host", "participant", "run_id",
          "run_started", "timestamp")
#: a web answer record's fields, as the answer record declares them (flipstudy.vocab.answers)
ANSWER = answers.WEB_ANSWER


class _Checker:
    def __init__(self, study):
        self.study = study
        self.groups = order_groups(study.design, study.manifest)
        self.orders = {}
        #: the site ids exported from this study (None: exported before they were recorded)
        self.sites = _sites(study.dir / WEB_DIR / SITES)
        self.design_sha256 = hashlib.sha256(study.design_text.encode()).hexdigest()
        #: the recruiter's URL parameters the site keeps on every record ([online] recruit_params)
        self.recruit = tuple(study.design.online.recruit_params)
        self.between = tuple(study.design.online.between)
        #: the site's opaque names read back through STUDY/web/site-map.json
        self.reveal = Revealer(study, self.sites)

    def order(self, pid, condition=None, row=None):
        if (pid, condition, row) not in self.orders:
            groups = condition_groups(self.groups, self.between, condition) if self.between else self.groups
            self.orders[pid, condition, row] = web_trial_order(groups, self.study.design.repetitions,
                                                               self.study.design.seed, pid,
                                                               self.study.design.online.block_order, row)
        return self.orders[pid, condition, row]

    def check(self, where: str, rec: dict) -> dict:
        _need(rec, where, COMMON)
        if rec["format"] != FORMAT:
            raise WebImportError(f"{where}: format {rec['format']!r}: this flipstudy reads {FORMAT}")
        kind = _str(rec["record"], where, "record", KINDS)
        name = self.study.design.name
        site_id = check_id(rec["site_id"], where, "site_id")     # a list or object is no site id
        if rec["study"] != name:
            raise WebImportError(
                f"{where}: study {str(rec['study'])[:60]!r}, but this is the study {name!r} "
                f"({self.study.dir / 'design.toml'}); import it into the study it was exported from")
        if self.sites is not None and site_id not in self.sites:
            raise WebImportError(
                f"{where}: site {str(rec['site_id'])[:40]!r} was not exported from this study "
                f"({self.study.dir / WEB_DIR / SITES} lists {', '.join(sorted(self.sites)) or 'none'}); "
                f"import it into the study it was exported from")
        if rec["manifest_sha256"] != self.study.manifest_sha256:
            raise WebImportError(
                f"{where}: the site was exported from other stimuli (manifest sha256 "
                f"{str(rec['manifest_sha256'])[:12]}…, this study's is {self.study.manifest_sha256[:12]}…); "
                f"import it into the study it was exported from")
        if self.sites is not None and self.sites[rec["site_id"]].get("design_sha256") not in \
                (None, self.design_sha256):
            raise WebImportError(
                f"{where}: site {rec['site_id']} was exported when {self.study.dir / 'design.toml'} "
                f"was another design (its SHA-256 then: "
                f"{self.sites[rec['site_id']]['design_sha256'][:12]}…); a study's design is frozen "
                f"once it has answers: restore the design the site was exported with")
        rec = self.reveal(where, rec)          # the site's opaque names back to the study's
        pid = rec["participant"]
        if not isinstance(pid, str) or not PARTICIPANT_RE.fullmatch(pid) or pid.startswith("-"):
            raise WebImportError(f"{where}: participant {str(pid)[:40]!r} is not a valid participant ID "
                                 f"(1-32 letters, digits, '_' or '-', not starting with '-')")
        out = {"record": kind, "participant": pid, "host": _str(rec["host"], where, "host", HOSTS),
               "run_id": check_id(rec["run_id"], where, "run_id"),
               "run_started": check_time(rec["run_started"], where, "run_started"),
               "timestamp": check_time(rec["timestamp"], where, "timestamp"),
               "site_id": site_id}
        for name in self.recruit:              # checked as the site checks them (and participant IDs)
            v = rec.get(name)
            if v not in (None, ""):
                if not isinstance(v, str) or not RECRUIT_RE.fullmatch(v) or v.startswith("-"):
                    raise WebImportError(f"{where}: {name} {str(v)[:40]!r} is not a valid recruiter ID "
                                         f"(1-64 letters, digits, '_' or '-', not starting with '-')")
                out[name] = v
        prolific = rec.get("PROLIFIC_PID")     # the site takes the participant ID from it first
        if prolific not in (None, "") and prolific != pid:
            raise WebImportError(f"{where}: PROLIFIC_PID {str(prolific)[:40]!r} is not the participant ID "
                                 f"{pid!r}; the site takes the ID from PROLIFIC_PID, so the record was "
                                 f"changed after it was written")
        cond = row = None
        if self.between:                       # the run's between-subject condition sets its order
            cond = out["condition"] = _str(rec.get("condition"), where, "condition", self.between)
        if self.study.design.online.block_order == "latin-square" and rec.get("latin_row") not in (None, ""):
            seen = condition_groups(self.groups, self.between, cond) if self.between else self.groups
            row = out["latin_row"] = _num(rec["latin_row"], where, "latin_row", 0,
                                          len(balanced_latin_square(len(seen))) - 1, integer=True)
        if kind == "answer":
            self._check_answer(rec, where, pid, cond, row, out)
        elif kind == "demographics":
            for f in DEMOGRAPHIC_FIELDS:
                _need(rec, where, (f["name"],))
                v = rec[f["name"]]
                if f["kind"] == "number":
                    out[f["name"]] = _num(v, where, f["name"], f["min"], f["max"], integer=True,
                                          optional=True)
                else:
                    out[f["name"]] = _str(v, where, f["name"], [o[0] for o in f["options"]])
        elif kind == "start":
            self._check_start(rec, where, pid, cond, row, out)
        return out

    def _check_answer(self, rec: dict, where: str, pid: str, cond, row, out: dict) -> None:
        """The fields of an ``answer`` record into ``out``, checked against the trial
        the participant's order has at its place."""
        _need(rec, where, ANSWER)
        trials = self.order(pid, cond, row)
        t = _num(rec["trial"], where, "trial", 1, len(trials), integer=True)
        want = trials[t - 1]
        got = {"stimulus": rec["stimulus"], "group": rec["group"],
               "level": _num(rec["level"], where, "level", -1e6, 1e6),
               "repetition": _num(rec["repetition"], where, "repetition", 1, 1000, integer=True)}
        task = getattr(want, "task", "") or "yes-no"
        if task == "2afc":          # which motion came first, and the comparison, as the order says
            got.update(task=rec.get("task"), first=rec.get("first"), original=rec.get("original"))
        elif rec.get("task", "yes-no") != "yes-no":
            got["task"] = rec.get("task")
        for k in got:
            if got[k] != getattr(want, k):
                raise WebImportError(f"{where}: trial {t}: {k} {got[k]!r}, but trial {t} of "
                                     f"participant {pid} is {getattr(want, k)!r} ({want.stimulus})")
        got.pop("original", None)
        out.update(got, trial=t, clip=want.clip, kind=want.kind, method="constant", task=task,
                   first=getattr(want, "first", "") or "",
                   original_stimulus=getattr(want, "original", "") or "",
                   response=_str(rec["response"], where, "response", RESPONSES_BY_TASK[task]),
                   rt_ms=_num(rec["rt_ms"], where, "rt_ms", 0, MAX_RT_MS),
                   shown_ms=_num(rec["shown_ms"], where, "shown_ms", 0, MAX_SHOWN_MS),
                   input=_str(rec["input"], where, "input", ("key", "click")),
                   replays=_num(rec["replays"], where, "replays", 0, MAX_REPLAYS, integer=True),
                   timing=_str(rec["timing"], where, "timing", ("rvfc", "raf")),
                   playback_flagged=_bool(rec["playback_flagged"], where, "playback_flagged"),
                   refresh_hz=_num(rec.get("refresh_hz"), where, "refresh_hz", 0, 1000, optional=True),
                   repeat=_num(0 if rec.get("repeat") is None else rec["repeat"], where, "repeat", 0, 1,
                              integer=True))
        for k in ("frames_expected", "frames_presented", "frames_dropped"):
            out[k] = _num(rec[k], where, k, 0, 10_000_000, integer=True)
        for k in ("dropped_pct", "max_dropped_pct"):
            out[k] = _num(rec[k], where, k, 0, 100)
        for k in ("playback_ms", "video_ms"):
            out[k] = _num(rec[k], where, k, 0, MAX_SHOWN_MS)
        if out["frames_dropped"] != max(0, out["frames_expected"] - out["frames_presented"]):
            raise WebImportError(f"{where}: frames_dropped {out['frames_dropped']} is not "
                                 f"frames_expected - frames_presented")

    def _check_start(self, rec: dict, where: str, pid: str, cond, row, out: dict) -> None:
        """The fields of a ``start`` record into ``out``: the order, the display and
        the browser's strings, and the consent (its time of agreement, or None)."""
        _need(rec, where, ("n_trials", "order"))
        n = _num(rec["n_trials"], where, "n_trials", 1, 100_000, integer=True)
        order = " ".join(t.stimulus for t in self.order(pid, cond, row))
        if n != len(self.order(pid, cond, row)) or rec["order"] != order:
            raise WebImportError(f"{where}: the run's trial order is not this study's order for "
                                 f"{pid} (another design or trial-order rule)")
        if self.study.design.online.block_order == "latin-square":
            blocks = " ".join(dict.fromkeys(t.group for t in self.order(pid, cond, row)))
            if rec.get("block_order") != blocks:
                raise WebImportError(f"{where}: block_order {rec.get('block_order')!r} is not {pid}'s "
                                     f"Latin-square row ({blocks!r})")
        elif rec.get("block_order") not in (None, ""):
            raise WebImportError(f"{where}: block_order {str(rec['block_order'])[:40]!r}, but this "
                                 f"design has no Latin-square block order")
        out.update(n_trials=n, refresh_hz=_num(rec.get("refresh_hz"), where, "refresh_hz", 0, 1000,
                                               optional=True),
                   participant_from=None if rec.get("participant_from") in (None, "") else
                   _str(rec["participant_from"], where, "participant_from", PARTICIPANT_PARAMS + ("generated",)),
                   user_agent=check_text(rec.get("user_agent"), where, "user_agent"),
                   consent=consent_of(rec.get("consent")),
                   window=None if rec.get("window") in (None, "") else
                   check_id(rec["window"], where, "window", WINDOW_RE, "WIDTHxHEIGHT in pixels"),
                   block_order=rec.get("block_order") or None,
                   screen_ok=None if rec.get("screen_ok") in (None, "") else
                   _bool(rec["screen_ok"], where, "screen_ok"))
        if out["consent"] is None and rec.get("consent") is not None:
            out["consent_given"] = str(rec["consent"])[:40]    # not a time of agreement: said why


# --- merging and writing ---------------------------------------------------------------------

def _key(r: dict):
    if r["record"] == "answer":
        return (r["run_id"], "answer", r["trial"], r["repeat"])
    return (r["run_id"], r["record"])


def _merge(items, local_ids) -> tuple[dict, int, list]:
    """``({key: (record, where, file)}, duplicates, conflicts)`` from ``[(where, file,
    record)]``: identical records once; of two different ones for one key the first is
    kept and the other is a conflict ``(key, where, where_kept)``
    (:func:`~flipstudy.study.web._runs.set_aside` decides what the tables take)."""
    merged, dup, conflicts = {}, 0, []
    runs = {}
    for where, fname, r in items:
        k = _key(r)
        if r["run_id"] in runs and runs[r["run_id"]] != r["participant"]:
            raise WebImportError(f"{where}: run {r['run_id']} belongs to participant "
                                 f"{runs[r['run_id']]}, not {r['participant']}")
        runs[r["run_id"]] = r["participant"]
        if r["participant"] in local_ids:
            raise WebImportError(f"{where}: participant {r['participant']} also has local sessions in "
                                 f"sessions.sqlite; web and local answers are never mixed under one ID "
                                 f"(give web participants their own IDs)")
        if k in merged:
            old = merged[k][0]
            if r != old and not (r["record"] in ("start", "end") and _same_but_time(r, old)):
                conflicts.append((k, where, merged[k][1], fname))
            else:
                dup += 1
            continue
        merged[k] = (r, where, fname)
    for k, (r, where, _f) in merged.items():
        if k[1] == "answer" and r["repeat"]:
            first = merged.get(k[:3] + (0,))
            if first is not None and not first[0]["playback_flagged"]:
                raise WebImportError(f"{where}: trial {r['trial']} of participant {r['participant']} "
                                     f"(run {r['run_id']}) is marked repeat = 1, but its first answer "
                                     f"({first[1]}) was not flagged; only flagged trials are repeated")
    return merged, dup, conflicts


def _same_but_time(a, b):
    return {k: v for k, v in a.items() if k != "timestamp"} == {k: v for k, v in b.items() if k != "timestamp"}


def _fmt(v):
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.0f}" if v == int(v) else repr(v)
    return str(v)


def _tables(merged: dict, n_trials: int, columns=COLUMNS, recruit=(), part_columns=None):
    runs = {}
    for (run, *_), (r, _w, _f) in merged.items():
        runs.setdefault(run, {"participant": r["participant"], "run_started": r["run_started"],
                              "host": r["host"]})
    sessions = {}
    by_pid = {}
    for run, info in runs.items():
        by_pid.setdefault(info["participant"], []).append((info["run_started"], run))
    for pid, lst in by_pid.items():
        for i, (_, run) in enumerate(sorted(lst), start=1):
            sessions[run] = i
    answers = [(r, f) for (r, _w, f) in merged.values() if r["record"] == "answer"]
    count = {}
    for r, _ in answers:
        if r["trial"] <= n_trials and not r["repeat"]:
            count[r["run_id"]] = count.get(r["run_id"], 0) + 1
    rows = []
    for r, f in sorted(answers, key=lambda x: (x[0]["participant"], sessions[x[0]["run_id"]], x[0]["trial"],
                                               x[0]["repeat"])):
        row = {c: r.get(c) for c in columns}
        row.update(session=sessions[r["run_id"]], late_frames=r["frames_dropped"], simulated=False,
                   complete=count.get(r["run_id"], 0) >= n_trials, source=f"web-{r['host']}",
                   source_file=f, rt_ms=f"{r['rt_ms']:.1f}", shown_ms=f"{r['shown_ms']:.1f}",
                   level=f"{r['level']:g}")
        rows.append({c: _fmt(row.get(c)) for c in columns})
    parts = []
    for run, info in sorted(runs.items(), key=lambda x: (x[1]["participant"], sessions[x[0]])):
        demo = merged.get((run, "demographics"), ({},))[0]
        start = merged.get((run, "start"), ({},))[0]
        run_answers = [r for r, _ in answers if r["run_id"] == run and not r["repeat"]]
        last = max((r["timestamp"] for r in run_answers), default=None)
        done = count.get(run, 0) >= n_trials
        p = {"participant": info["participant"], "session": sessions[run], "source": f"web-{info['host']}",
             "started": info["run_started"], "finished": last if done else None,
             "answered": len(run_answers), "n_trials": n_trials, "simulated": False, "complete": done,
             "run_id": run, "host": info["host"], "participant_from": start.get("participant_from"),
             "refresh_hz": start.get("refresh_hz"), "user_agent": start.get("user_agent"),
             "consent": start.get("consent"), "window": start.get("window"), "screen_ok": start.get("screen_ok"),
             "block_order": start.get("block_order"), "latin_row": start.get("latin_row"),
             "condition": start.get("condition")}
        p.update({k: v for k, v in start.items() if k in recruit})
        for f in DEMOGRAPHIC_FIELDS:
            p[f["name"]] = demo.get(f["name"])
        parts.append({c: _fmt(p.get(c)) for c in (part_columns or WEB_PARTICIPANT_COLUMNS)})
    return rows, parts


def _table_text(columns, rows) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([r.get(c, "") for c in columns])
    return buf.getvalue()


def _local_participants(study_dir: Path) -> set:
    db = store.db_path(study_dir)
    if not (db.exists() or db.is_symlink()):        # a dangling link is a damaged store, not none
        return set()
    conn = store.connect(study_dir, create=False)
    try:
        return {r[0] for r in conn.execute("SELECT DISTINCT participant FROM sessions")}
    finally:
        conn.close()


LEDGER = "imports.json"
#: what was kept out of the tables, and why (rebuilt by every import)
QUARANTINE = "quarantine.csv"


def _kept(d: Path) -> list[Path]:
    """The kept files in the order they were imported (``web/imports.json``; a file the
    ledger misses, after a crash between the two writes, comes last)."""
    imports = d / IMPORTS
    if not imports.is_dir():
        return []
    files = {p.name: p for p in imports.iterdir() if p.is_file() and not p.name.startswith(".")}
    order = []
    if (d / LEDGER).is_file():
        order = [e["stored"] for e in json.loads((d / LEDGER).read_text()) if e["stored"] in files]
    return [files[n] for n in order] + [files[n] for n in sorted(files) if n not in order]


def _ledger(d: Path) -> list:
    return json.loads((d / LEDGER).read_text()) if (d / LEDGER).is_file() else []


def _read_new(files, checker, known: set):
    """The records of the files not imported before (``known``: the hashes of those
    that were), their report rows and bytes, within one import's :data:`MAX_IMPORT`."""
    items, report, new_files, seen, budget = [], [], [], set(), Budget()
    for f in files:
        f = Path(f)
        data = read_results_file(f)
        sha = hashlib.sha256(data).hexdigest()[:16]
        if sha in known or sha in seen:
            report.append({"file": str(f), "status": "already imported", "records": 0, "new_answers": 0})
            continue
        seen.add(sha)
        stored = f"{sha}-" + re.sub(r"[^A-Za-z0-9._-]", "_", f.name)[:120]
        recs = [(where, stored, checker.check(where, rec)) for where, rec in read_records(f, data, budget)]
        if not recs:
            raise WebImportError(f"{f}: no flipstudy records in this file")
        items += recs
        new_files.append((stored, data))
        report.append({"file": str(f), "status": "imported", "records": len(recs), "new_answers": 0,
                       "stored": stored})
    return items, report, new_files


def _write_files(d: Path, new_files, report, new_quarantine) -> None:
    """The new files as they were, then the ledger naming them (and the runs quarantined
    by this import, on its first file's entry)."""
    from ..store import utc_now
    imports = d / IMPORTS
    imports.mkdir(parents=True, exist_ok=True)
    for stored, data in new_files:
        target = imports / stored
        tmp = target.with_name(f".{target.name}.tmp")
        tmp.write_bytes(data)
        tmp.replace(target)
    ledger = _ledger(d)
    names = {e["stored"] for e in ledger}
    ledger += [{"stored": p.name, "imported": None} for p in _kept(d) if p.name not in names
               and p.name not in {s for s, _ in new_files}]
    ledger += [{"stored": None, "kept": False, "sha256": r["stored"].split("-", 1)[0], "file": r["file"],
                "imported": utc_now(), "records": r["records"], "new_answers": 0}
               for r in report if r["status"] == "nothing new"]
    new = [{"stored": r["stored"], "file": r["file"], "imported": utc_now(), "records": r["records"],
            "new_answers": r["new_answers"]} for r in report if r["status"] == "imported"]
    if new and new_quarantine:
        new[0]["quarantined"] = dict(sorted(new_quarantine.items()))
    atomic_write_text(d / LEDGER, json.dumps(ledger + new, indent=1) + "\n")


@study_writer("import-web")
def import_web(study_dir, files) -> ImportResult:
    """Import results files into ``STUDY_DIR/web/`` (see the module docstring).

    Returns an :class:`~flipstudy.results.ImportResult`: ``files`` (per file: "file",
    "status" ("imported" | "already imported" | "nothing new": every record already kept,
    so the file is not kept), "records", "new_answers"), ``answers``,
    ``participants``, ``sessions``, ``incomplete``, ``flagged``, ``repeats``,
    ``duplicates``, ``quarantined`` (what was kept out of the tables and why: see
    :mod:`flipstudy.study.web._runs`) and the tables written (``responses``,
    ``participants_csv``, ``description``, ``quarantine_csv``)."""
    study = load_study(study_dir)
    d = study.dir / WEB_DIR
    checker = _Checker(study)
    # (between-subject conditions have as many trials each: the design checks it)
    n_trials = len(checker.order("x", checker.between[0] if checker.between else None)) if checker.groups else 0
    kept_sha = {p.name.split("-", 1)[0]: p for p in _kept(d)}
    ledger = _ledger(d)
    # files read before that added nothing (not kept): known by their hash in the ledger
    read_not_kept = {e.get("sha256") for e in ledger if e.get("kept") is False}
    # runs earlier imports quarantined whole, with their reasons
    quarantined = {run: why for e in ledger for run, why in (e.get("quarantined") or {}).items()}
    consent_required = bool(study.design.online.consent)
    local = _local_participants(study.dir)
    items = []
    for p in kept_sha.values():                 # each was within the limits when it was imported
        for where, rec in read_records(p, budget=Budget(1 << 62)):
            where = where.replace(str(p), f"{IMPORTS}/{p.name}")
            items.append((where, p.name, checker.check(where, rec)))
    full_before, _, settled = _merge(items, local)
    before, _, _ = set_aside(full_before, settled, quarantined, None, consent_required)
    new_items, report, new_files = _read_new(files, checker, set(kept_sha) | read_not_kept)
    full, dup, conflicts = _merge(items + new_items, local)
    merged, aside, new_quarantine = set_aside(full, conflicts, quarantined, {k[0] for k in before},
                                              consent_required, settled=settled)
    for r in report:
        if r["status"] == "imported":
            r["new_answers"] = sum(1 for k, (_rec, _w, fn) in merged.items()
                                   if k[1] == "answer" and fn == r["stored"] and k not in before)
            if not any(fn == r["stored"] and k not in full_before for k, (_rec, _w, fn) in full.items()) \
                    and not any(c[3] == r["stored"] for c in conflicts):
                # every record of it is already kept: the file is not kept (nor re-read later)
                r["status"], r["records_read"] = "nothing new", r["records"]
                new_files = [(s, b) for s, b in new_files if s != r["stored"]]
    styles = _manifest_styles(study.stimuli)
    columns = web_columns(any(g.task == "2afc" for g in study.design.groups), styles is not None)
    # the recruiter's parameters that came with the records: columns of both tables
    recruit = [k for k in checker.recruit if any(k in r for r, _w, _f in merged.values())]
    columns = columns + recruit
    part_columns = WEB_PARTICIPANT_COLUMNS + recruit
    rows, parts = _tables(merged, n_trials, columns, recruit, part_columns)
    if styles is not None:                      # the stimulus's character style, as `export` has it
        for r in rows:
            r["style"] = styles.get(r["stimulus"], "")
    # write: the files as they were first, then the tables built from all of them
    _write_files(d, new_files, report, new_quarantine)
    out = d / "responses.csv"
    atomic_write_text(out, _table_text(columns, rows))
    atomic_write_text(d / "participants.csv", _table_text(part_columns, parts))
    atomic_write_text(d / QUARANTINE, _table_text(QUARANTINE_COLUMNS, aside))
    from ..psychds import write_data_files
    write_data_files(d, study.design.name, "web", {"": _table_text(columns, rows),
                                                   "participants": _table_text(part_columns, parts)})
    desc = write_dataset_description(d, study.dir, list(dict.fromkeys(columns + part_columns)),
                                     source="web sessions", stimuli=study.stimuli)
    return ImportResult(
        files=tuple(ImportedFile.from_dict({k: str(v) if isinstance(v, Path) else v for k, v in r.items()})
                    for r in report),
        answers=len(rows), participants=len({p["participant"] for p in parts}), sessions=len(parts),
        incomplete=tuple(f"{p['participant']}/{p['session']} ({p['answered']}/{p['n_trials']})"
                         for p in parts if p["complete"] != "true"),
        flagged=tuple(f"{r['participant']}/{r['session']} trial {r['trial']} ({r['dropped_pct']} % dropped)"
                      + (" repeat" if r["repeat"] == "1" else "") for r in rows
                      if r["playback_flagged"] == "true"),
        repeats=tuple(f"{r['participant']}/{r['session']} trial {r['trial']}" for r in rows
                      if r["repeat"] == "1"),
        duplicates=dup, responses=out, participants_csv=d / "participants.csv",
        description=Path(desc) if desc is not None else None, study=str(study_dir),
        quarantined=tuple(f"{a['participant']} run {a['run_id']}" + ("" if a["what"] == "run" else f" {a['what']}")
                          + f": {a['reason']}: {a['detail']}" for a in aside), quarantine_csv=d / QUARANTINE)
