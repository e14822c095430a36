"""The sessions ``import-web`` wrote (``STUDY/web/participants.csv``), in the form
``flipstudy status`` lists the local ones (:func:`flipstudy.study.store.status_rows`)."""
from __future__ import annotations

import csv
from pathlib import Path


def web_status(study_dir) -> list[dict]:
    """One dict per imported web session (participant, session, source, answered,
    total, started, last_answer, finished, simulated, complete), from
    ``STUDY/web/participants.csv`` and the last answer's time in
    ``STUDY/web/responses.csv``; empty before the first ``import-web``.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     web_status(tmp)
    []
    """
    web = Path(study_dir) / "web"
    part = web / "participants.csv"
    if not part.is_file():
        return []
    last: dict = {}
    if (web / "responses.csv").is_file():
        with open(web / "responses.csv", newline="", encoding="utf-8") as f:
            for r in csv.DictReader(f):
                key = (r.get("participant"), str(r.get("session")))
                if r.get("timestamp") and r["timestamp"] > last.get(key, ""):
                    last[key] = r["timestamp"]
    out = []
    with open(part, newline="", encoding="utf-8") as f:
        for r in csv.DictReader(f):
            out.append({
                "participant": r["participant"], "session": int(r["session"] or 1),
                "source": r.get("source") or "web", "total": int(r.get("n_trials") or 0),
                "started": r.get("started") or None, "finished": r.get("finished") or None,
                "answered": int(r.get("answered") or 0),
                "last_answer": last.get((r["participant"], str(r["session"]))),
                "simulated": (r.get("simulated") or "").lower() == "true",
                "complete": (r.get("complete") or "").lower() == "true"})
    return out
