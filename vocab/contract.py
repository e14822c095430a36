"""The study folder as one typed contract: :class:`Stimulus` and :class:`StimulusSet`.

A stimulus set is a folder with ``manifest.csv`` (one row per stimulus), the
stimuli as ``.bvh`` and ``.npz`` and a copy of the design.  :meth:`StimulusSet.read`
reads and checks it once (columns, numbers, names, files, content hashes), each
problem a :class:`~flipstudy.errors.ManifestError` naming the file, line and
column; every later stage (render, sessions, export, the web export, analysis)
takes the typed :class:`StimulusSet` instead of parsing the manifest again.
:meth:`StimulusSet.write` writes the manifest byte for byte as the build always
has (floats with six decimals, ``nan`` for a missing value, ``true``/``false``).

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> from flipstudy.vocab.contract import Stimulus, StimulusSet
>>> from flipstudy.vocab.kinds import AM
>>> s = Stimulus("b_am_10", "b", "am", AM.name, "smooth", level=10.0,
...              nominal_error_pct=10.0, measured_error_pct=9.9999996, takeoff=5, landing=30)
>>> s.level, s.bvh, s.measured_error_pct
(10.0, PurePosixPath('b_am_10.bvh'), 9.9999996)
>>> d = Path(tempfile.mkdtemp())
>>> StimulusSet(d, (s,)).write().name
'manifest.csv'
>>> back = StimulusSet.read(d, files=False, design=False)
>>> back["b_am_10"].measured_error_pct        # six decimals, as the manifest holds it
10.0
>>> back.stimuli[0].takeoff + 1
6
"""
from __future__ import annotations

import csv
import hashlib
import io
import math
import re
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Iterator, Mapping

from flipstudy.errors import FlipstudyFileNotFoundError, ManifestError

#: a stimulus name is a plain file name (it names files and URLs)
STIMULUS_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,200}")

#: the pseudo-group of the example motions shown before the trials
REFERENCE_GROUP = "reference"


from ._cells import _COLUMN_TYPES, _WORD, _Record, _Typed, _fmt_float, _same  # noqa: F401


@dataclass(frozen=True, eq=False)
class Ballistic(_Record):
    """The columns of the ballistic kinds (gravity, velocities, acceleration,
    time-scale, pose-rate; :data:`flipstudy.stimuli.ballistic_measure.EXTRA_COLUMNS`),
    present for every row of a design that uses one of them."""
    policy: str = ""
    axis: str = ""
    span: str = ""
    quantity: str = ""
    unit: str = ""
    nominal_value: float = 0.0
    measured_value: float = 0.0
    apparent_gravity: float = math.nan
    takeoff_vh: float = math.nan
    takeoff_vy: float = math.nan
    air_acc_h: float = math.nan
    air_acc_v: float = math.nan
    flight_s_change_pct: float = 0.0
    apex_change_pct: float = 0.0
    landing_shift_m: float = 0.0
    landing_height_change_mm: float = 0.0
    playback_rate: float = 1.0
    pose_rate: float = math.nan


@dataclass(frozen=True, eq=False)
class Stimulus(_Record):
    """One stimulus: one row of ``manifest.csv``, every column a typed field
    (numbers as numbers, file names as paths relative to the study folder,
    ``accept_unphysical`` as a bool).  ``style`` is the character style (None
    when the design chooses none: no ``style`` column); ``ballistic`` the
    columns of the ballistic kinds (None when the design uses none); ``source``
    the ``[[sources]]`` entry a comparison study's clip comes from (None in other
    studies: no ``source`` column).

    Angles are in degrees, errors in percent, times in seconds, lengths in
    metres unless the name says otherwise (``_mm``); ``takeoff``/``landing`` are
    the first and last frame strictly inside the flight, ``takeoff_time`` /
    ``landing_time`` the contact instants.  ``original`` is the stimulus its d′
    compares with ("" for reference rows and groups without a level 0).

    Parameters
    ----------
    stimulus : str
        Its name (a plain file name: letters, digits, ``_``, ``.``, ``-``).
    clip, group, kind : str
        Its base clip, error group and error kind.
    **columns
        One keyword per manifest column (see the Formats page, or
        :data:`MANIFEST_COLUMNS`), each converted to its field's type.

    Raises
    ------
    TypeError
        For a value that is not of its column's type.

    Examples
    --------
    >>> from flipstudy.vocab.contract import Stimulus
    >>> from flipstudy.vocab.kinds import AM
    >>> s = Stimulus("bf_abrupt_inc_50", clip="backflip", group="abrupt-increase",
    ...              kind=AM.name, level=50, frames=397, fps=120)
    >>> s.level, str(s.bvh), round(s.duration_s, 3)
    (50.0, 'bf_abrupt_inc_50.bvh', 3.308)
    >>> s.as_dict()["group"]
    'abrupt-increase'
    """
    stimulus: str
    clip: str
    group: str
    kind: str
    profile: str = ""
    level: float = 0.0
    nominal_error_pct: float = 0.0
    measured_error_pct: float = 0.0
    takeoff_angle_deg: float = math.nan
    takeoff_angle_change_deg: float = 0.0
    takeoff: int = 0
    landing: int = 0
    seed: int = 0
    sha256: str = ""
    L_ratio_window: float = 1.0
    L_change_pct: float = 0.0
    flight_s: float = math.nan
    jump_height_m: float = math.nan
    jump_length_m: float = math.nan
    dp_takeoff: float = 0.0
    dp_landing: float = 0.0
    frames: int = 0
    fps: float = math.nan
    bvh: PurePosixPath = None           # default: STIMULUS.bvh
    npz: PurePosixPath = None           # default: STIMULUS.npz
    original: str = ""
    accept_unphysical: bool = False
    takeoff_time: float = math.nan
    landing_time: float = math.nan
    air_acc_dev: float = 0.0
    air_acc_dev_original: float = 0.0
    dv_takeoff: float = 0.0
    dv_landing: float = 0.0
    L_error_touchdown_pct: float = 0.0
    below_floor_mm: float = 0.0
    style: str | None = None
    ballistic: Ballistic | None = None
    source: str | None = None

    def __post_init__(self):
        if not STIMULUS_RE.fullmatch(_Typed.coerce(str, self.stimulus, "stimulus")):
            raise TypeError(f"stimulus: {self.stimulus!r} is not a plain file name (letters, digits, "
                            f"'_', '.', '-')")
        super().__post_init__()
        if self.style is not None:
            _Typed.coerce(str, self.style, "style")
        if self.source is not None:
            _Typed.coerce(str, self.source, "source")
        if self.ballistic is not None and not isinstance(self.ballistic, Ballistic):
            raise TypeError(f"ballistic: expected Ballistic, got {self.ballistic!r}")

    @property
    def is_reference(self) -> bool:
        """Is it an example motion shown before the trials (not a trial)?"""
        return self.group == REFERENCE_GROUP

    @property
    def duration_s(self) -> float:
        """Its length in seconds (frames / fps; NaN without a frame rate)."""
        return self.frames / self.fps if self.fps > 0 else math.nan

    def cells(self) -> list[str]:
        out = super().cells()
        if self.style is not None:
            out.append(self.style)
        if self.ballistic is not None:
            out += self.ballistic.cells()
        if self.source is not None:
            out.append(self.source)
        return out

    @classmethod
    def from_values(cls, row: Mapping) -> "Stimulus":
        """From a mapping of column → value (a build's row; numbers, not text)."""
        base = {c: row[c] for c in cls.columns() if c in row}
        b = {c: row[c] for c in Ballistic.columns() if c in row}
        return cls(**base, style=row.get("style"), ballistic=Ballistic(**b) if b else None,
                   source=row.get("source"))

    def as_dict(self) -> dict:
        """Column → typed value, as a flat mapping (paths as text), in manifest order."""
        d = {c: getattr(self, c) for c in self.columns()}
        d["bvh"], d["npz"] = str(self.bvh), str(self.npz)
        if self.style is not None:
            d["style"] = self.style
        if self.ballistic is not None:
            d.update({c: getattr(self.ballistic, c) for c in Ballistic.columns()})
        if self.source is not None:
            d["source"] = self.source
        return d


#: the manifest's columns (then ``style`` when the design chooses one, then the
#: ballistic kinds' columns when it uses one)
MANIFEST_COLUMNS = Stimulus.columns()
EXTRA_COLUMNS = Ballistic.columns()


#: the columns every manifest has had (a manifest of an older build may lack the
#: others; they read as NaN, "" or 0 and :meth:`StimulusSet.write` writes them all)
REQUIRED_COLUMNS = MANIFEST_COLUMNS[:MANIFEST_COLUMNS.index("sha256") + 1]


def manifest_columns(styled: bool, ballistic: bool, sourced: bool = False) -> list[str]:
    """The header of a manifest with or without ``style``, the ballistic columns and
    ``source`` (a comparison study's)."""
    return MANIFEST_COLUMNS + (["style"] if styled else []) + (EXTRA_COLUMNS if ballistic else []) \
        + (["source"] if sourced else [])


@dataclass(frozen=True, eq=False)
class StimulusSet:
    """A study's stimuli as one typed value: its folder, design (None when the
    folder has no ``design.toml`` or it was not asked for), its stimuli in
    manifest order, and the sha256 of its ``manifest.csv`` (what sessions record).

    Iterating gives the stimuli; ``set[name]`` one by name.  Read one with
    :meth:`read` (every problem a ``ManifestError`` naming file and line), write it
    with :meth:`write` (byte-identical to what was read).

    Parameters
    ----------
    folder : str or pathlib.Path
        The stimulus set's folder (where ``manifest.csv`` is).
    stimuli : sequence of Stimulus
        The rows, in manifest order; names must be unique.
    design : Design, optional
        The study's design, when known.
    manifest_sha256 : str, optional
        The sha256 of the manifest it was read from.

    Examples
    --------
    >>> import tempfile
    >>> from flipstudy.vocab.contract import Stimulus, StimulusSet
    >>> from flipstudy.vocab.kinds import AM
    >>> rows = [Stimulus("bf_0", "backflip", "original", AM.name, level=0),
    ...         Stimulus("bf_50", "backflip", "abrupt-increase", AM.name, level=50)]
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     s = StimulusSet(tmp, rows)
    ...     _ = s.write()
    ...     back = StimulusSet.read(tmp, files=False)
    >>> back.names, back["bf_50"].level, len(back)
    (['bf_0', 'bf_50'], 50.0, 2)
    """
    folder: Path
    stimuli: tuple[Stimulus, ...]
    design: object = None
    manifest_sha256: str = ""
    _by_name: dict = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "folder", Path(self.folder))
        object.__setattr__(self, "stimuli", tuple(self.stimuli))
        by = {}
        for i, s in enumerate(self.stimuli):
            if not isinstance(s, Stimulus):
                raise TypeError(f"stimuli[{i}]: expected a Stimulus, got {type(s).__name__}")
            if s.stimulus in by:
                raise ManifestError(f"{self.manifest_path}: stimulus {s.stimulus!r} is listed more than "
                                    f"once; rebuild the stimuli with `flipstudy stimuli`")
            by[s.stimulus] = s
        if self.stimuli:
            first = self.stimuli[0]
            for s in self.stimuli:
                if (s.style is None) != (first.style is None) or \
                        (s.ballistic is None) != (first.ballistic is None) or \
                        (s.source is None) != (first.source is None):
                    raise ManifestError(f"{self.manifest_path}: stimulus {s.stimulus!r} has other "
                                        f"columns than {first.stimulus!r} (style, ballistic or source "
                                        f"columns)")
        object.__setattr__(self, "_by_name", by)

    # --- access -------------------------------------------------------------------------
    def __iter__(self) -> Iterator[Stimulus]:
        return iter(self.stimuli)

    def __len__(self) -> int:
        return len(self.stimuli)

    def __getitem__(self, name: str) -> Stimulus:
        return self._by_name[name]

    def __contains__(self, name) -> bool:
        return name in self._by_name

    def __eq__(self, other):
        if not isinstance(other, StimulusSet):
            return NotImplemented
        return self.folder == other.folder and self.stimuli == other.stimuli

    __hash__ = None

    @property
    def manifest_path(self) -> Path:
        return self.folder / "manifest.csv"

    @property
    def names(self) -> list[str]:
        return [s.stimulus for s in self.stimuli]

    @property
    def hashes(self) -> dict[str, str]:
        """Stimulus name → the sha256 of its ``.bvh`` (as the manifest records it)."""
        return {s.stimulus: s.sha256 for s in self.stimuli}

    @property
    def styled(self) -> bool:
        """Does the manifest have a ``style`` column?"""
        return bool(self.stimuli) and self.stimuli[0].style is not None

    @property
    def references(self) -> list[Stimulus]:
        """The reference stimuli (example motions), in manifest order."""
        return [s for s in self.stimuli if s.is_reference]

    @property
    def tests(self) -> list[Stimulus]:
        """The non-reference stimuli, in manifest order."""
        return [s for s in self.stimuli if not s.is_reference]

    def line_of(self, name: str) -> int:
        """The manifest line of stimulus ``name`` (the header is line 1)."""
        return self.names.index(name) + 2

    def path(self, s: Stimulus | str, what: str = "bvh") -> Path:
        """The file ``what`` (``"bvh"`` or ``"npz"``) of a stimulus, in the folder."""
        s = self[s] if isinstance(s, str) else s
        return self.folder / getattr(s, what)

    def rows(self) -> list[dict]:
        """Every stimulus as a flat mapping of column → typed value (e.g. for
        ``pandas.DataFrame(stimuli.rows())``)."""
        return [s.as_dict() for s in self.stimuli]

    @property
    def columns(self) -> list[str]:
        return manifest_columns(self.styled, bool(self.stimuli) and self.stimuli[0].ballistic is not None,
                                self.sourced)

    @property
    def sourced(self) -> bool:
        """Is it a comparison study's set (a ``source`` column)?"""
        return bool(self.stimuli) and self.stimuli[0].source is not None

    def sources(self) -> list[str]:
        """The sources of a comparison study's stimuli, in manifest order ([] elsewhere)."""
        return list(dict.fromkeys(s.source for s in self.stimuli if s.source is not None))

    # --- the manifest -------------------------------------------------------------------
    def manifest_text(self) -> str:
        """``manifest.csv`` as text (what :meth:`write` writes)."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.columns)
        for s in self.stimuli:
            w.writerow(s.cells())
        return buf.getvalue()

    def write(self, folder=None) -> Path:
        """Write ``manifest.csv`` into ``folder`` (default: the set's own); returns its path."""
        p = Path(folder if folder is not None else self.folder) / "manifest.csv"
        p.write_text(self.manifest_text())
        return p

    @classmethod
    def from_rows(cls, folder, rows, design=None) -> "StimulusSet":
        """From a build's rows (mappings of column → value)."""
        return cls(Path(folder), tuple(Stimulus.from_values(r) for r in rows), design)

    @classmethod
    def read(cls, folder, *, files: bool = True, design: bool = True) -> "StimulusSet":
        """Read and check the stimulus set in ``folder``: its manifest's columns
        (those of :data:`REQUIRED_COLUMNS` at least; a column an older build did
        not write reads as NaN, "" or 0), every number, stimulus names (plain,
        unique), and with ``files`` that
        every ``.bvh``/``.npz`` exists and each ``.bvh`` has the sha256 the
        manifest records.  With ``design``, ``design.toml`` is read too when
        there is one.  Each problem is a :class:`ManifestError` naming the file
        and line (and column)."""
        folder = Path(folder)
        p = folder / "manifest.csv"
        if not p.is_file():
            raise FlipstudyFileNotFoundError(
                f"{p}: no manifest; make the stimuli first (flipstudy stimuli DESIGN.toml --out DIR)")
        data = p.read_bytes()
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise ManifestError(f"{p}: not UTF-8 text ({e})") from None
        stimuli = _parse(p, text)
        dsg = None
        if design and (folder / "design.toml").is_file():
            from .design import load_design
            dsg = load_design(folder / "design.toml")
        out = cls(folder, stimuli, dsg, hashlib.sha256(data).hexdigest())
        if files:
            out.check_files()
        return out

    def check_files(self) -> None:
        """Every stimulus's ``.bvh`` and ``.npz`` is in the folder and each ``.bvh``
        has the sha256 the manifest records; else a :class:`ManifestError` naming
        the manifest line."""
        for i, s in enumerate(self.stimuli, start=2):
            where = f"{self.manifest_path} line {i}: stimulus {s.stimulus!r}"
            for what in ("bvh", "npz"):
                f = self.folder / getattr(s, what)
                if not f.is_file():
                    raise ManifestError(f"{where}: no file {f}; make the stimuli again "
                                        f"(flipstudy stimuli DESIGN.toml --out {self.folder} --force)")
            h = file_sha256(self.folder / s.bvh)
            if s.sha256 and h != s.sha256.lower():
                raise ManifestError(f"{where}: {s.bvh} has sha256 {h[:12]}…, the manifest says "
                                    f"{s.sha256[:12]}…; the file changed after `flipstudy stimuli` "
                                    f"wrote it (make the stimuli again)")


def file_sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _parse(p: Path, text: str) -> list[Stimulus]:
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = next(reader, None)
        if not header:
            raise ManifestError(f"{p} line 1: no header (an empty manifest)")
        styled = "style" in header
        ballistic = EXTRA_COLUMNS[0] in header
        sourced = "source" in header
        want = manifest_columns(styled, ballistic, sourced)
        if header != want:                  # an older build's manifest lacks some measured columns
            need = REQUIRED_COLUMNS + (EXTRA_COLUMNS if ballistic else [])
            missing = [c for c in need if c not in header]
            extra = [c for c in header if c not in want]
            twice = [c for c in header if header.count(c) > 1]
            if missing or extra or twice:
                why = (f"no column {missing[0]!r}" if missing else f"unknown column {extra[0]!r}"
                       if extra else f"column {twice[0]!r} twice")
                raise ManifestError(f"{p} line 1: {why}; make the stimuli again (flipstudy stimuli "
                                    f"DESIGN.toml --out DIR --force)")
        out = []
        line = reader.line_num
        for cells in reader:
            where = f"{p} line {line + 1}"
            line = reader.line_num
            if not cells:                       # a blank line (as csv.DictReader, skipped)
                continue
            if len(cells) != len(header):
                raise ManifestError(f"{where}: {len(cells)} cells, the header has {len(header)}")
            row = dict(zip(header, cells))
            b = Ballistic.parse(row, where) if ballistic else None
            out.append(Stimulus.parse(row, where, style=row["style"] if styled else None, ballistic=b,
                                      source=row["source"] if sourced else None))
    except csv.Error as e:
        raise ManifestError(f"{p} line {reader.line_num}: {e}") from None
    return out


__all__ = ["Stimulus", "StimulusSet", "Ballistic", "MANIFEST_COLUMNS", "EXTRA_COLUMNS",
           "manifest_columns", "STIMULUS_RE", "REFERENCE_GROUP", "file_sha256"]
