"""What ``import-web`` keeps out of the tables (:mod:`flipstudy.study.web.importer`):
runs without a recorded agreement to the consent text, runs whose records conflict,
and the browser's free text made safe for spreadsheets.

A run enters ``web/responses.csv``, ``participants.csv`` and the Psych-DS files only
when its ``start`` record is there and, for a design with an ``[online] consent``
text, that record carries the time the participant agreed (``consent``, ISO 8601).
A run that holds two different records for one trial (two tabs or two devices on one
checkpoint) is quarantined whole; when the run was already in the tables, its rows
stay as they were and only the differing records are set aside.  Everything set
aside is listed with its reason in ``web/quarantine.csv``; the records themselves
stay in the kept files under ``web/imports/``.

>>> spreadsheet_safe('=HYPERLINK("http://evil.example/")'), spreadsheet_safe("Mozilla/5.0")
('\\'=HYPERLINK("http://evil.example/")', 'Mozilla/5.0')
>>> bool(ISO_RE.fullmatch("2026-01-05T10:00:00.500Z")), bool(ISO_RE.fullmatch("yes"))
(True, False)
"""
from __future__ import annotations

import re

from flipstudy.errors import WebImportError

#: a time as the site writes it (``Date.toISOString()``; an offset is accepted too)
ISO_RE = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(?:\.\d{1,9})?(?:Z|[+-]\d\d:?\d\d)?")
#: an id the site makes or passes on (run ids, site ids): no formula can be spelled with these
ID_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_-]{0,63}")
WINDOW_RE = re.compile(r"\d{1,6}x\d{1,6}")
MAX_TEXT = 1000
#: a cell starting with one of these is a formula to a spreadsheet
FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
CONSENT, CONFLICT = "no consent", "conflict"
QUARANTINE_COLUMNS = ["participant", "run_id", "what", "reason", "detail", "where"]


def spreadsheet_safe(text: str) -> str:
    """``text`` with a ``'`` before a leading ``=``, ``+``, ``-``, ``@``, tab or carriage
    return, so a spreadsheet opening the CSV shows it as text and runs no formula."""
    return "'" + text if text.startswith(FORMULA_START) else text


def check_id(v, where: str, key: str, pattern=ID_RE, what: str = "1-64 letters, digits, '_' or '-', "
             "not starting with '-'"):
    """``v`` when it is a string matching ``pattern``, else a :class:`WebImportError`."""
    if not isinstance(v, str) or not pattern.fullmatch(v):
        raise WebImportError(f"{where}: {key} {str(v)[:40]!r} is not valid ({what})")
    return v


def check_text(v, where: str, key: str):
    """Free text from the browser (a user agent): None or a string of at most
    :data:`MAX_TEXT` printable characters, returned :func:`spreadsheet_safe`."""
    if v in (None, ""):
        return None
    if not isinstance(v, str) or len(v) > MAX_TEXT or not v.isprintable():
        raise WebImportError(f"{where}: {key}: expected up to {MAX_TEXT} printable characters, "
                             f"got {str(v)[:40]!r}")
    return spreadsheet_safe(v)


def check_time(v, where: str, key: str, optional: bool = False):
    """An ISO 8601 time as the site writes it (``optional``: None or "" is None)."""
    if optional and v in (None, ""):
        return None
    return check_id(v, where, key, ISO_RE, "an ISO 8601 time such as 2026-01-05T10:00:00.000Z")


def consent_of(v):
    """The time of agreement a start record carries, or None (no agreement: a null, an
    empty string, an object, anything that is not a time)."""
    return v if isinstance(v, str) and ISO_RE.fullmatch(v) else None


def _what(key) -> str:
    return f"trial {key[2]}" + (" (repeat)" if key[3] else "") if key[1] == "answer" else f"{key[1]} record"


def set_aside(merged: dict, conflicts: list, quarantined: dict, established, consent_required: bool,
              settled=()):
    """Split ``merged`` (``{key: (record, where, file)}``) into what the tables take and
    what is kept out.

    ``conflicts``: ``[(key, where, where_kept, file)]`` of records that differ from the
    one kept for their key; ``quarantined``: ``{run_id: reason}`` decided by earlier
    imports; ``established``: the runs already in the tables (None: every conflict is
    one with rows already in the tables, as when the kept files are read again);
    ``settled``: conflicts among the kept files, decided so before.

    Returns ``(tables, rows, new)``: the merged records the tables take, the rows of
    ``web/quarantine.csv``, and ``{run_id: reason}`` of runs quarantined now.
    """
    run_of = {k[0]: r["participant"] for k, (r, _w, _f) in merged.items()}
    rows, new = [], {}
    settled = {c[:3] for c in settled}
    for key, where, kept, _file in conflicts:
        run = key[0]
        if run in quarantined or run in new:
            continue
        if established is None or run in established or (key, where, kept) in settled:
            rows.append({"participant": run_of[run], "run_id": run, "what": _what(key), "reason": CONFLICT,
                         "detail": f"differs from the one kept from {kept}, which stays", "where": where})
        else:
            new[run] = (f"{_what(key)} differs between {kept} and {where} (two tabs or devices "
                        f"on one run?); the whole run is kept out")
    out, listed = {}, set()
    for key, item in merged.items():
        run = key[0]
        reason = quarantined.get(run) or new.get(run)
        if reason is None:
            start = merged.get((run, "start"))
            if start is None:
                reason = (CONSENT, "no start record, where the agreement to take part is recorded")
            elif consent_required and start[0].get("consent") is None:
                reason = (CONSENT, f"the start record ({start[1]}) records no agreement to the consent "
                                   f"text (consent {start[0].get('consent_given')!r})")
            if reason is not None:
                quarantine_reason = reason
            else:
                out[key] = item
                continue
        else:
            quarantine_reason = (CONFLICT, reason)
        if run not in listed:
            listed.add(run)
            rows.append({"participant": item[0]["participant"], "run_id": run, "what": "run",
                         "reason": quarantine_reason[0], "detail": quarantine_reason[1], "where": item[1]})
    return out, rows, new
