"""Reading the site's results files (:mod:`flipstudy.study.web.importer`): JATOS data
or archive, Pavlovia CSV, the participant's download, each as ``[(where, record)]``,
unchecked; ``where`` names file and line.

What one import reads is bounded: a file at most :data:`MAX_FILE` bytes, and the
files of one import together, a zip archive's entries counted uncompressed, at most
:data:`MAX_IMPORT` bytes (a zip whose entries say they hold more is refused before
any is read; an entry holding more than it says is stopped when the total is reached).

>>> b = Budget(10)
>>> b.take(4, "a.txt"); b.left
6
>>> b.take(7, "b.txt")
Traceback (most recent call last):
...
flipstudy.errors.WebImportError: b.txt: the files of one import hold more than 10 bytes uncompressed (at least 11); import-web reads at most 0 MiB of results at once: import the files in several runs
"""
from __future__ import annotations

import csv
import io
import json
import math
import stat as st_
import zipfile
from pathlib import Path

from flipstudy.errors import WebImportError

MAX_FILE = 256 * 1024 * 1024
#: the files of one import together, a zip's entries counted uncompressed
MAX_IMPORT = 256 * 1024 * 1024
_CHUNK = 1 << 20


class Budget:
    """What is left of an import's :data:`MAX_IMPORT` bytes (``take`` raises when one
    more file or entry would go over it)."""

    def __init__(self, limit: int | None = None):
        self.limit = self.left = int(MAX_IMPORT if limit is None else limit)

    def take(self, n: int, where: str) -> None:
        if n > self.left:
            raise WebImportError(
                f"{where}: the files of one import hold more than {self.limit} bytes uncompressed "
                f"(at least {self.limit - self.left + n}); import-web reads at most "
                f"{self.limit >> 20} MiB of results at once: import the files in several runs")
        self.left -= n


def _loads(text: str, where: str, what: str = "valid JSON"):
    """``json.loads`` whose every failure (bad JSON, nesting too deep for the parser) is
    a :class:`WebImportError` naming ``where``."""
    try:
        return json.loads(text, parse_constant=lambda c: math.nan)
    except ValueError as e:
        raise WebImportError(f"{where}: not {what} ({e})") from None
    except RecursionError:
        raise WebImportError(f"{where}: JSON nested too deeply to be a flipstudy record") from None


def _ndjson(text: str, where: str):
    for i, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        obj = _loads(line, f"{where}: line {i}", "a JSON record")
        if not isinstance(obj, dict):
            raise WebImportError(f"{where}: line {i}: expected a JSON object, got {type(obj).__name__}")
        yield f"{where}: line {i}", obj


def _json_array(text: str, where: str):
    arr = _loads(text, where)
    if not isinstance(arr, list):
        raise WebImportError(f"{where}: expected a JSON array of records")
    for i, obj in enumerate(arr, start=1):
        if not isinstance(obj, dict):
            raise WebImportError(f"{where}: record {i}: expected a JSON object")
        yield f"{where}: record {i}", obj


def _csv(text: str, where: str):
    reader = csv.DictReader(io.StringIO(text))
    if not reader.fieldnames or "record" not in reader.fieldnames or "format" not in reader.fieldnames:
        raise WebImportError(f"{where}: line 1: not a flipstudy results file (a CSV needs the columns "
                             f"'format' and 'record'; JSON lines start with '{{')")
    for i, row in enumerate(reader, start=2):
        if None in row:
            raise WebImportError(f"{where}: line {i}: more cells than the header has columns")
        yield f"{where}: line {i}", {k: (None if v == "" else v) for k, v in row.items()}


def _text_records(data: bytes, where: str):
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise WebImportError(f"{where}: not UTF-8 text ({e})") from None
    head = text.lstrip()[:1]
    if not head:
        return iter(())
    if head == "{":
        return _ndjson(text, where)
    if head == "[":
        return _json_array(text, where)
    if head == "\0":
        raise WebImportError(f"{where}: binary data (NUL bytes), not a results file")
    return _csv(text, where)


def _entries(z: zipfile.ZipFile, path: Path, budget: Budget) -> list:
    """The text entries of a results archive, in name order; their sizes as the archive
    states them are taken from ``budget`` before any is read."""
    infos = [i for i in sorted(z.infolist(), key=lambda i: i.filename)
             if not i.is_dir() and i.filename.rsplit("/", 1)[-1].endswith((".txt", ".jsonl", ".json", ".csv"))]
    big = next((i for i in infos if i.file_size > MAX_FILE), None)
    if big is not None:
        raise WebImportError(f"{path}:{big.filename}: {big.file_size >> 20} MiB uncompressed; a results "
                             f"file holds at most {MAX_FILE >> 20} MiB")
    budget.take(sum(i.file_size for i in infos), f"{path}")
    return infos


def _read_entry(z: zipfile.ZipFile, info, where: str) -> bytes:
    """An entry's bytes, read in chunks and stopped past the size the archive states (an
    entry that holds more than it says is a broken archive, not read to its end)."""
    out = bytearray()
    with z.open(info) as f:
        while True:
            chunk = f.read(_CHUNK)
            if not chunk:
                break
            out += chunk
            if len(out) > info.file_size:
                raise WebImportError(f"{where}: holds more than the {info.file_size} bytes its archive "
                                     f"states; a broken or hostile zip archive")
    return bytes(out)


def read_records(path, data: bytes | None = None, budget: Budget | None = None) -> list[tuple[str, dict]]:
    """``[(where, record), ...]`` of one results file (JATOS data or archive,
    Pavlovia CSV, download), unchecked; ``where`` names file and line.  ``data``: its
    bytes, already read; ``budget``: what the import may still read (default: a fresh
    :data:`MAX_IMPORT`)."""
    path = Path(path)
    budget = Budget() if budget is None else budget
    data = read_results_file(path) if data is None else data
    if data[:4] == b"PK\x03\x04":
        out = []
        try:
            with zipfile.ZipFile(io.BytesIO(data)) as z:
                for info in _entries(z, path, budget):
                    where = f"{path}:{info.filename}"
                    out += list(_text_records(_read_entry(z, info, where), where))
        except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, EOFError) as e:
            raise WebImportError(f"{path}: a broken zip archive ({e})") from None
        return out
    budget.take(len(data), str(path))
    return list(_text_records(data, str(path)))


def read_results_file(path: Path) -> bytes:
    """The bytes of a results file; a folder, a FIFO or device, a missing or too large
    file is a :class:`WebImportError` saying which."""
    try:
        st = path.stat()
    except FileNotFoundError:
        raise WebImportError(f"{path}: no such file") from None
    except OSError as e:
        raise WebImportError(f"{path}: cannot be read ({e.strerror})") from None
    if st_.S_ISDIR(st.st_mode):
        raise WebImportError(f"{path}: a folder; import-web takes the results files themselves "
                             f"(e.g. {path}/*.jsonl, a JATOS .zip or a Pavlovia .csv)")
    if not st_.S_ISREG(st.st_mode):
        raise WebImportError(f"{path}: not a regular file (a FIFO, socket or device); save the "
                             f"results to a file first")
    if st.st_size > MAX_FILE:
        raise WebImportError(f"{path}: larger than {MAX_FILE >> 20} MiB; not a results file")
    try:
        return path.read_bytes()
    except OSError as e:
        raise WebImportError(f"{path}: cannot be read ({e.strerror})") from None
