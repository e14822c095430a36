"""Which files a study folder owns, and the one check every command makes before
it writes an output: no output path may be a file or folder of a study.

A *study folder* is a folder with ``manifest.csv`` and ``design.toml`` (what
``flipstudy stimuli`` writes) or with ``sessions.sqlite``.  It owns:

* ``sessions.sqlite`` (and its ``-wal``, ``-shm``, ``-journal``), ``manifest.csv``,
  ``design.toml``, the researcher's ``consent.md`` and ``debrief.md`` and the
  stimulus files (``*.bvh``, ``*.npz``) at its top;
* everything under ``render/`` (videos, ``render.json``), ``web/`` (imported
  results, ``web/responses.csv``, ``web/participants.csv``) and ``.locks/``;
* the tables ``flipstudy export`` writes there (``responses.csv``,
  ``participants.csv``, ``simulated_truth.csv``, ``dataset_description.json``):
  only ``export`` of that study may write them;
* the folder itself (an output folder may not be a study, hold one at any depth,
  or be one of the owned folders above).

``analysis/`` and any other name are the user's: ``analyze`` and ``figure`` write
there freely.

What a ``--force`` may delete or replace is one rule: only what the command made
itself, as recorded when it made it (``export-web``: its ``flipstudy-site.json``;
``reproduce``: :data:`MADE_RECORD`; ``stimuli``: its ``manifest.csv`` and the
outputs other commands recorded, :func:`recorded_outputs`), never a file it did
not write, at any depth (:func:`not_made`, :func:`refuse_not_made`); a study is
recognised by its files at any depth below (:func:`study_below`).

Examples
--------
>>> import tempfile, pathlib
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = tempfile.TemporaryDirectory()
>>> st = make_demo_study(pathlib.Path(tmp.name) / "st")
>>> owner(st / "sessions.sqlite")[1]
'the answer database'
>>> owner(st / "analysis" / "table.csv") is None
True
>>> refuse_owned(st / "manifest.csv", "export --out")
Traceback (most recent call last):
    ...
flipstudy.errors.OwnedPathError: .../st/manifest.csv is the stimulus list of the study .../st; `flipstudy export --out` does not write over a study's own files: choose a path outside it (or under .../st/analysis/)
>>> tmp.cleanup()
"""
from __future__ import annotations

import os
from pathlib import Path

from flipstudy.errors import OwnedPathError

#: top-level files of a study folder and what they are
STUDY_FILES = {
    "sessions.sqlite": "the answer database",
    "sessions.sqlite-wal": "the answer database's write-ahead log",
    "sessions.sqlite-shm": "the answer database's shared memory",
    "sessions.sqlite-journal": "the answer database's journal",
    "manifest.csv": "the stimulus list",
    "design.toml": "the design",
    "consent.md": "the researcher's consent text",
    "debrief.md": "the researcher's debrief text",
}
#: what ``flipstudy export`` writes into the study it exports (only it may)
EXPORT_FILES = {
    "responses.csv": "the exported answers",
    "participants.csv": "the exported participants",
    "simulated_truth.csv": "the simulated observers' parameters",
    "dataset_description.json": "the exported tables' description",
    "data": "the exported tables as Psych-DS data files (data/*_data.csv)",
}
#: at most this many files and folders are looked through below an output folder
WALK_LIMIT = 200_000
#: what SQLite writes beside a database, which goes with it
SIDE_FILES = ("-wal", "-shm", "-journal")
#: folders of a study folder whose every file it owns
STUDY_DIRS = {"render": "the rendered videos", "web": "the web results",
              ".locks": "the server locks"}


def is_study(folder) -> bool:
    """Is ``folder`` a study folder (``manifest.csv`` with ``design.toml``, or ``sessions.sqlite``)?"""
    f = Path(folder)
    try:
        return ((f / "manifest.csv").is_file() and (f / "design.toml").is_file()) or \
            (f / "sessions.sqlite").exists()
    except OSError:
        return False


def _resolved(path) -> Path:
    p = Path(path).expanduser()
    try:
        return p.resolve()
    except (OSError, RuntimeError):
        return p.absolute()


def owner(path) -> tuple[Path, str, str] | None:
    """``(study folder, what the path is to it, relative name)`` when ``path`` is a
    file or folder that a study owns (module docstring), else None.  Symbolic links
    are followed: a link into a study is the study's file."""
    p = _resolved(path)
    if p.is_dir() and is_study(p):
        return p, "the study folder itself", "."
    for parent in p.parents:
        if not is_study(parent):
            continue
        rel = p.relative_to(parent)
        top = rel.parts[0]
        if len(rel.parts) == 1:
            if top in STUDY_FILES:
                return parent, STUDY_FILES[top], top
            if top in EXPORT_FILES:
                return parent, EXPORT_FILES[top], top
            if top in STUDY_DIRS:
                return parent, STUDY_DIRS[top], top
            if top.endswith((".bvh", ".npz")):
                return parent, "a stimulus file", top
        elif top in STUDY_DIRS:
            return parent, f"one of {STUDY_DIRS[top]} ({top}/)", str(rel)
        elif top in EXPORT_FILES:           # data/: export's Psych-DS data files
            return parent, f"one of {EXPORT_FILES[top]}", str(rel)
        return None                       # inside a study, but the user's (analysis/, ...)
    if p.is_dir():                        # a folder holding a study at any depth below
        inner = study_below(p)
        if inner is not None:
            return inner, "inside the output folder", "."
    return None


def _walk(folder: Path, limit: int):
    """``(folder, dirnames, filenames)`` below ``folder`` (symbolic links to folders are
    not followed: they are files here); more than ``limit`` entries refuse."""
    seen = 0
    for top, dirs, files in os.walk(folder, followlinks=False):
        seen += len(dirs) + len(files)
        if seen > limit:
            raise OwnedPathError(f"{folder} holds more than {limit} files and folders; flipstudy does "
                                 f"not replace or write into a folder it cannot look through for a "
                                 f"study's files: choose a new or smaller folder")
        links = [d for d in dirs if os.path.islink(os.path.join(top, d))]
        dirs[:] = [d for d in dirs if d not in links]
        yield Path(top), dirs, files + links


def study_below(folder, *, limit: int = WALK_LIMIT) -> Path | None:
    """The first study folder (:func:`is_study`) at any depth strictly below ``folder``,
    recognised by its files (``sessions.sqlite``, or ``manifest.csv`` with
    ``design.toml``); None when there is none."""
    folder = Path(folder)
    for top, dirs, files in _walk(folder, limit):
        names = set(dirs) | set(files)
        if top != folder and ("sessions.sqlite" in names or {"manifest.csv", "design.toml"} <= names):
            return top
    return None


def files_below(folder, *, limit: int = WALK_LIMIT) -> list[str]:
    """Every file (and symbolic link) at any depth below ``folder``, as sorted relative
    POSIX names (``render/a.mp4``)."""
    folder = Path(folder)
    return sorted((top / f).relative_to(folder).as_posix() for top, _, files in _walk(folder, limit)
                  for f in files)


def not_made(folder, made, *, limit: int = WALK_LIMIT) -> list[str]:
    """The files below ``folder`` that are not in ``made`` (relative POSIX names: what a
    command recorded as it made them); a database's ``-wal``/``-shm``/``-journal``
    go with it, and lock files (``.locks/``) are no one's.  What a ``--force`` may
    replace is a folder where this is empty."""
    made = set(made)
    return [f for f in files_below(folder, limit=limit)
            if f not in made and ".locks" not in f.split("/")[:-1]      # locks: no one's data
            and not any(f == m + side for m in made for side in SIDE_FILES)]


def refuse_owned(path, command: str, *, study=None, allow=()) -> None:
    """Raise :class:`OwnedPathError`, naming the path, when ``path`` is owned by a
    study (:func:`owner`); ``allow``: names (relative to the study) that ``command``
    may write, but only in ``study`` (``export``: its own tables)."""
    got = owner(path)
    if got is None:
        return
    folder, what, rel = got
    if study is not None and rel in allow and folder == _resolved(study):
        return
    if what == "inside the output folder":
        msg = f"{path} holds the study {folder}"
    elif rel == ".":
        msg = f"{path} is the study folder {folder}"
    else:
        msg = f"{path} is {what} of the study {folder}"
    raise OwnedPathError(f"{msg}; `flipstudy {command}` does not write over a study's own files: "
                         f"choose a path outside it (or under {folder}/analysis/)")


#: what ``import-web`` and ``export-web`` write under ``web/`` (``web/imports/``: never)
WEB_MADE = ("sites.json", "imports.json", "responses.csv", "participants.csv",
            "dataset_description.json")


def recorded_outputs(study_dir) -> set[str]:
    """The files below a study folder that flipstudy commands made and recorded, which
    go with its stimulus set when ``stimuli --force`` replaces it (relative POSIX
    names): ``render/render.json`` and the outputs it lists, ``sessions.sqlite`` and
    its side files, ``export``'s tables (:data:`EXPORT_FILES`, ``data/*_data.csv``) and
    the tables of ``web/`` (:data:`WEB_MADE`, ``web/data/*_data.csv``).  Raw web
    results (``web/imports/``) are never among them: they are answers."""
    d = Path(study_dir)
    made = {"sessions.sqlite" + side for side in ("", *SIDE_FILES)}
    try:
        import json
        outputs = json.loads((d / "render" / "render.json").read_text(encoding="utf-8")).get("outputs")
        if isinstance(outputs, dict):
            made |= {"render/render.json"} | {f"render/{k}" for k in outputs if isinstance(k, str)}
    except (OSError, ValueError, AttributeError):
        pass
    made |= {k for k in EXPORT_FILES if k != "data"} | {f"web/{k}" for k in WEB_MADE}
    for sub in ("data", "web/data"):
        if (d / sub).is_dir():
            made |= {f"{sub}/{f}" for f in files_below(d / sub) if f.endswith("_data.csv") and "/" not in f}
    return made


#: the record of a folder a command makes whole (``reproduce``'s OUT): every file it wrote
MADE_RECORD = ".flipstudy-made.json"


def record_made(folder, command: str) -> None:
    """Write :data:`MADE_RECORD` into ``folder``: ``command`` and every file below it
    now, the files that command may replace later (:func:`made_by_record`)."""
    import json
    files = [f for f in files_below(folder) if f != MADE_RECORD]
    (Path(folder) / MADE_RECORD).write_text(json.dumps({"command": command, "files": files},
                                                       indent=1) + "\n", encoding="utf-8")


def made_by_record(folder) -> set[str]:
    """The files :func:`record_made` recorded in ``folder`` (and the record), or only
    the record when there is none: then nothing else is known to be the command's."""
    import json
    try:
        files = json.loads((Path(folder) / MADE_RECORD).read_text(encoding="utf-8")).get("files")
    except (OSError, ValueError, AttributeError):
        files = None
    return {f for f in files if isinstance(f, str)} | {MADE_RECORD} if isinstance(files, list) \
        else {MADE_RECORD}


def refuse_not_made(folder, made, command: str, what: str) -> None:
    """Raise :class:`OwnedPathError` when ``folder`` holds a file not in ``made``
    (:func:`not_made`) or a study at any depth: ``command`` replaces ``folder`` only
    when everything in it is what it made itself (``what``: "the earlier site")."""
    folder = Path(folder)
    inner = study_below(folder)
    if inner is not None:
        raise OwnedPathError(f"{folder} holds the study {inner}; `flipstudy {command}` never deletes "
                             f"a study: move it out first, or choose another --out")
    extra = not_made(folder, made)
    if extra:
        listed = ", ".join(extra[:4]) + (f" and {len(extra) - 4} more" if len(extra) > 4 else "")
        raise OwnedPathError(f"{folder} holds file(s) that {what} did not have ({listed}); `flipstudy "
                             f"{command}` replaces only what it made itself: move them out first, "
                             f"or choose another --out")


#: the options whose values are paths a command writes (checked before every command runs)
OUTPUT_OPTIONS = ("out", "participants_out", "plot", "ghost", "strip", "figure", "composite")
#: commands whose ``--out`` is a study they build themselves (they guard it their own way)
BUILDS_STUDY = ("stimuli", "reproduce")


def check_outputs(command: str, args) -> None:
    """Refuse (:func:`refuse_owned`) every output path of a parsed command line that
    a study owns; ``export`` may write its own tables into the study it exports."""
    for opt in OUTPUT_OPTIONS:
        if opt == "out" and command in BUILDS_STUDY:
            continue
        value = getattr(args, opt, None)
        if not isinstance(value, (str, Path)) or not str(value):
            continue
        flag = "--" + opt.replace("_", "-")
        if command == "export":
            refuse_owned(value, f"{command} {flag}", study=getattr(args, "study_dir", None),
                         allow=tuple(EXPORT_FILES))
        else:
            refuse_owned(value, f"{command} {flag}")
