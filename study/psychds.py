"""A Psych-DS ``dataset_description.json`` beside the response tables.

Psych-DS (psych-ds.github.io) describes a dataset with a schema.org ``Dataset``
in JSON-LD: ``name``, ``description``, ``schemaVersion`` and ``variableMeasured``
(here one ``PropertyValue`` per column, with what it means) are required.  The
file also names what the answers were given to: the design and the manifest
with their SHA-256 (``isBasedOn``, schema.org ``MediaObject``), every stimulus
with the hash of its motion (BVH) and of its video where ``render.json`` records
one, and the software with its versions.

>>> import tempfile, pathlib, json
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = pathlib.Path(tempfile.mkdtemp())
>>> study = make_demo_study(tmp / "study")
>>> p = write_dataset_description(study, study, ["participant", "response"], source="local sessions")
>>> d = json.loads(p.read_text())
>>> d["@type"], d["schemaVersion"], [v["name"] for v in d["variableMeasured"]]
('Dataset', 'Psych-DS 0.1.0', ['participant', 'response'])
>>> COLUMNS["kind"]
'kind of error (angular-momentum, takeoff-angle, gravity, horizontal-velocity, vertical-velocity, acceleration, time-scale, pose-rate)'
"""
from __future__ import annotations

import hashlib
import json
import platform
from pathlib import Path

from flipstudy.stimuli._io import atomic_write_text
from flipstudy.vocab.answers import meanings

FILE = "dataset_description.json"
DATA_DIR = "data"              # Psych-DS: every data file lives under data/
SCHEMA_VERSION = "Psych-DS 0.1.0"

#: what each column of the response tables means: the declared answer record's
#: (:mod:`flipstudy.vocab.answers`), then the columns only some tables carry
COLUMNS = {
    **meanings(),
    "style": "character style the stimulus was drawn in (ellipsoids, capsules, stick, "
             "point-light, mannequin; from manifest.csv)",
    "run_id": "the browser run the answer came from (web sessions)",
    "refresh_hz": "display refresh rate measured at the start of the run",
    "repeat": "1: a trial flagged for dropped frames shown once more at the end (its first "
              "answer, repeat 0, is the row before); the analysis uses the repeat in its place",
    "source_file": "the imported file the answer was first read from",
}


COLUMNS.update({
    "catch": "true: an attention (catch) trial, a trial of a catch group: a gross error (right answer "
             "incorrect) or the group's own original (right answer correct)",
    "condition": "between-subject condition the participant was assigned to",
    "block_order": "the participant's order of blocks (balanced Latin square row)",
    "latin_row": "the participant's row of the balanced Latin square (0-based)",
    "PROLIFIC_PID": "Prolific participant ID (URL parameter, checked like every participant ID)",
    "STUDY_ID": "Prolific study ID (URL parameter)",
    "SESSION_ID": "Prolific session ID (URL parameter)",
    "consent": "consent given on the consent screen (ISO 8601 time)",
    "window": "browser window size at the screen check, CSS pixels (WxH)",
    "screen_ok": "true when the screen met the design's minimum refresh rate and window size",
    "host": "where the web session ran (static, jatos, pavlovia)",
    "participant_from": "the URL parameter the participant ID was read from",
    "user_agent": "the browser's user agent",
})


def keyword(value: str) -> str:
    """A Psych-DS keyword value: letters and digits only (``my_study-2`` → ``mystudy2``)."""
    v = "".join(ch for ch in str(value) if ch.isascii() and ch.isalnum())
    return v or "x"


def data_file_name(study: str, source: str, table: str | None = None) -> str:
    """The Psych-DS name of a data file: ``study-<name>_source-<source>[_table-<table>]_data.csv``.

    >>> data_file_name("paper replication", "web"), data_file_name("s", "local", "participants")
    ('study-paperreplication_source-web_data.csv', 'study-s_source-local_table-participants_data.csv')
    """
    parts = [f"study-{keyword(study)}", f"source-{keyword(source)}"]
    if table:
        parts.append(f"table-{keyword(table)}")
    return "_".join(parts) + "_data.csv"


def write_data_files(folder, study: str, source: str, tables: dict[str, str]) -> list[Path]:
    """Write the tables (``{"": responses CSV text, "participants": ...}``) as Psych-DS
    data files under ``folder/data/``; returns their paths."""
    out = []
    for table, text in tables.items():
        path = Path(folder) / DATA_DIR / data_file_name(study, source, table or None)
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(path, text)
        out.append(path)
    return out


def _sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _software() -> list[dict]:
    from importlib.metadata import PackageNotFoundError, version
    out = [{"@type": "SoftwareApplication", "name": "python", "softwareVersion": platform.python_version()}]
    for name in ("flipstudy", "numpy", "scipy", "pandas", "pyvista", "vtk"):
        try:
            out.append({"@type": "SoftwareApplication", "name": name, "softwareVersion": version(name)})
        except PackageNotFoundError:
            pass
    return out


def write_dataset_description(folder, study_dir, columns, *, source: str, extra_software=(),
                              stimuli=None, exclusion_rules=None) -> Path:
    """Write ``folder/dataset_description.json`` for the response tables of
    ``study_dir`` with these ``columns`` (``source``: "local sessions", "web
    sessions", …; ``stimuli``: the study's :class:`~flipstudy.stimuli.contract.StimulusSet`
    when the caller has read it, else it is read here; ``exclusion_rules``: the design's
    ``[exclusions]`` as sentences, else read from the design); returns its path."""
    folder, study_dir = Path(folder), Path(study_dir)
    name = study_dir.name
    based = []
    design = study_dir / "design.toml"
    if design.is_file():
        try:
            from flipstudy.stimuli.design import load_design
            d = load_design(design)
            name = d.name
            if exclusion_rules is None and not d.exclusions.is_default:
                from flipstudy.analysis.exclusions import rule_sentences
                exclusion_rules = rule_sentences(d.exclusions.to_dict())
        except Exception:                      # a description never blocks an export
            pass
        based.append({"@type": "MediaObject", "name": "design.toml", "sha256": _sha256(design)})
    manifest = study_dir / "manifest.csv"
    stimuli = []
    if manifest.is_file():
        based.append({"@type": "MediaObject", "name": "manifest.csv", "sha256": _sha256(manifest)})
        from flipstudy.stimuli.contract import StimulusSet
        if stimuli is None:
            stimuli = StimulusSet.read(study_dir, files=False, design=False)
        videos = {}
        rec = study_dir / "render" / "render.json"
        if rec.is_file():
            try:
                outputs = json.loads(rec.read_text()).get("outputs", {})
                videos = {v.get("stimulus"): v.get("sha256") for k, v in outputs.items()
                          if isinstance(v, dict) and v.get("kind") == "video"}
            except ValueError:
                videos = {}
        for r in stimuli:
            s = {"@type": "MediaObject", "name": r.stimulus, "sha256": r.sha256}
            if videos.get(r.stimulus):
                s["video_sha256"] = videos[r.stimulus]
            stimuli.append(s)
    desc = {
        "@context": "https://schema.org/",
        "@type": "Dataset",
        "name": f"{name}: responses ({source})",
        "description": (f"Answers of the perception study '{name}' ({source}): one row per trial "
                        f"in responses.csv (long format), one row per session in participants.csv; the same "
                        f"tables as Psych-DS data files under {DATA_DIR}/ (*_data.csv). "
                        f"Written by flipstudy."
                        + (" Exclusion rules stated in the design before any data, applied by "
                           "flipstudy analyze: " + "; ".join(exclusion_rules) + "."
                           if exclusion_rules else "")),
        "schemaVersion": SCHEMA_VERSION,
        "keywords": ["perception", "character animation", "physical plausibility", "flipstudy"],
        "variableMeasured": [{"@type": "PropertyValue", "name": c, "description": COLUMNS.get(c, c)}
                             for c in columns],
        **({"comment": [{"@type": "Comment", "name": "exclusion rule", "text": t}
                        for t in exclusion_rules]} if exclusion_rules else {}),
        "isBasedOn": based + [{"@type": "CreativeWork", "name": "stimuli", "hasPart": stimuli}]
                     + _software() + list(extra_software),
    }
    path = folder / FILE
    atomic_write_text(path, json.dumps(desc, indent=2, ensure_ascii=False) + "\n")
    return path
