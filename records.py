"""The typed records the step results of :mod:`flipstudy.results` hold.

A :class:`Record` is a JSON object with declared, typed fields: the step
results hold records (a session's status, a threshold, the settings of an
analysis) where they held plain dicts.  ``Record.from_dict`` reads the object a
step writes and ``to_dict`` gives it back with the same keys in the same order,
so what ``--json`` prints and what the results save is unchanged.  A record
whose object has open columns (a table row carries the columns of its task)
keeps the undeclared ones in ``extra``, in their order.  Like
:mod:`flipstudy.errors`, the module sits at the package root and imports none of
the four parts.

Examples
--------
>>> s = SessionStatus.from_dict({"participant": "P01", "session": 1, "source": "local",
...     "total": 8, "started": "t0", "finished": None, "answered": 3, "last_answer": "t1",
...     "simulated": False, "complete": False})
>>> s.participant, s.answered, s.finished
('P01', 3, None)
>>> list(s.to_dict())[:4]
['participant', 'session', 'source', 'total']
>>> FlowStage.from_dict({"stage": "recruited", "n": 12, "why": "x"}).extra
{'why': 'x'}
"""
from __future__ import annotations

import dataclasses
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path


def to_json(value):
    """``value`` as JSON carries it: records and dicts as objects, paths as strings,
    tuples as lists."""
    if isinstance(value, Record):
        return value.to_dict()
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, (tuple, list)):
        return [to_json(v) for v in value]
    if isinstance(value, dict):
        return {str(k): to_json(v) for k, v in value.items()}
    return value


def from_json(hint, value):
    """``value`` (as JSON gave it) turned back into the field type ``hint``."""
    if value is None:
        return None
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        return from_json(args[0], value) if len(args) == 1 else value
    if isinstance(hint, type) and issubclass(hint, Record):
        return hint.from_dict(value)
    if hint is Path:
        return Path(value)
    if origin is tuple:
        args = typing.get_args(hint)
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(from_json(args[0], v) for v in value)
        return tuple(from_json(a, v) for a, v in zip(args, value))
    if origin is dict:
        _, vt = typing.get_args(hint)
        return {k: from_json(vt, v) for k, v in value.items()}
    return value


def _refuse(cls, what: str):
    from flipstudy.errors import FlipstudyValueError
    raise FlipstudyValueError(f"{cls.__name__}: {what}")


@dataclass(frozen=True)
class Record:
    """A JSON object with declared fields.  ``from_dict`` keeps the order of the
    object's keys (and leaves out of ``to_dict`` the declared keys it did not
    have); a record built directly writes its fields in declared order.  A
    subclass with an ``extra`` field keeps the keys it does not declare there."""

    @classmethod
    def _declared(cls) -> dict:
        return {f.name: f for f in dataclasses.fields(cls) if f.name != "extra"}

    @classmethod
    def _open(cls) -> bool:
        return any(f.name == "extra" for f in dataclasses.fields(cls))

    def to_dict(self) -> dict:
        """The record as the JSON object it was read from (keys in the same order)."""
        declared = self._declared()
        extra = getattr(self, "extra", {}) if self._open() else {}
        keys = getattr(self, "_keys", None) or (*declared, *extra)
        out = {k: to_json(getattr(self, k) if k in declared else extra[k])
               for k in keys if k in declared or k in extra}
        out.update((k, to_json(v)) for k, v in extra.items() if k not in out)
        return out

    @classmethod
    def from_dict(cls, data: dict):
        """The record of a JSON object (each declared field as its type)."""
        if not isinstance(data, dict):
            _refuse(cls, f"expected a JSON object, not {type(data).__name__}")
        hints = typing.get_type_hints(cls)
        declared = cls._declared()
        kw, extra = {}, {}
        for k, v in data.items():
            if k in declared:
                kw[k] = from_json(hints[k], v)
            else:
                extra[k] = v
        if extra and not cls._open():
            _refuse(cls, f"unknown field(s) {', '.join(sorted(extra))}")
        missing = [n for n, f in declared.items() if n not in kw and f.default is dataclasses.MISSING
                   and f.default_factory is dataclasses.MISSING]
        if missing:
            _refuse(cls, f"missing field(s) {', '.join(missing)}")
        obj = cls(**kw, **({"extra": extra} if cls._open() else {}))
        object.__setattr__(obj, "_keys", tuple(data))
        return obj


def _extra():
    return field(default_factory=dict, kw_only=True)


# ---- status: one session (flipstudy.study.export.status)

@dataclass(frozen=True)
class SessionStatus(Record):
    """One session of a study: who, which session, how far, when."""
    participant: str
    session: int
    source: str
    total: int
    started: str | None
    finished: str | None
    answered: int
    last_answer: str | None
    simulated: bool
    complete: bool


# ---- import-web: what happened to one file

@dataclass(frozen=True)
class ImportedFile(Record):
    """One web results file of an import: ``status`` is "imported", "already
    imported" or "nothing new" (every record already kept, the file not kept)."""
    file: str
    status: str
    records: int
    new_answers: int
    extra: dict = _extra()


# ---- plan: one group and method of a power analysis

@dataclass(frozen=True)
class PlanRow(Record):
    """One group and method of ``flipstudy plan`` (non-finite numbers as None)."""
    group: str
    task: str
    method: str
    levels: str
    trials: float | None
    trials_median: float | None
    share_reached: float | None
    sd_between: float | None
    participants: int | None
    total_trials: float | None


# ---- analyze: the pieces its summary reads (flipstudy.analysis.pipeline.Result.to_dict)

@dataclass(frozen=True)
class Threshold(Record):
    """One group's detection threshold (the columns of ``thresholds.csv``; the
    fit's own columns in ``extra``)."""
    group: str
    reached: bool
    threshold: float | None = None
    threshold_ci_low: float | None = None
    threshold_ci_high: float | None = None
    extra: dict = _extra()


@dataclass(frozen=True)
class GroupThresholds(Record):
    """The per-participant thresholds of one group, summarised."""
    group: str
    method: str
    task: str
    n_participants: int
    median: float | None
    q25: float | None
    q75: float | None
    mean_ci_width: float | None
    extra: dict = _extra()


@dataclass(frozen=True)
class ParticipantThreshold(Record):
    """One participant's threshold x* in one group (``thresholds_participants.csv``)."""
    group: str
    extra: dict = _extra()


@dataclass(frozen=True)
class FlowStage(Record):
    """One stage of the participant flow of ``[exclusions]``."""
    stage: str
    n: int
    extra: dict = _extra()


@dataclass(frozen=True)
class Participants(Record):
    """Whose answers an analysis holds and whom it left out."""
    n: int
    real: tuple[str, ...] = ()
    simulated: tuple[str, ...] = ()
    simulated_left_out: tuple[str, ...] = ()
    incomplete_left_out: tuple[str, ...] = ()
    incomplete_kept: tuple[str, ...] = ()
    extra: dict = _extra()


@dataclass(frozen=True)
class AnalyzeSettings(Record):
    """The settings an analysis ran with and what it counted."""
    correction: str
    participants: Participants
    participants_label: str
    n_trials: int
    groups: tuple[str, ...]
    extra: dict = _extra()


@dataclass(frozen=True)
class TableRow(Record):
    """One group and level of ``table.csv`` (its other columns in ``extra``)."""
    group: str
    level: float
    extra: dict = _extra()


@dataclass(frozen=True)
class AnalyzeReport(Record):
    """What ``flipstudy analyze --json`` prints: settings, table, thresholds, the
    participant flow, notes and the files written."""
    settings: AnalyzeSettings
    table: tuple[TableRow, ...]
    thresholds: tuple[Threshold, ...]
    notes: tuple[str, ...]
    files: dict[str, str]
    thresholds_participants: tuple[ParticipantThreshold, ...] | None = None
    thresholds_groups: tuple[GroupThresholds, ...] | None = None
    exclusion_rules: tuple[str, ...] | None = None
    flow: tuple[FlowStage, ...] | None = None


# ---- reproduce: the outputs and the seconds per stage

@dataclass(frozen=True)
class ReproduceFiles(Record):
    """The outputs of ``flipstudy reproduce`` (paths as text)."""
    design: str
    manifest: str
    stimuli: str
    videos: str
    render_settings: str
    sessions: str
    responses: str
    participants: str
    analysis: str
    table: str
    table_paper: str
    table_latex: str
    figure_ratings: str
    figure_dprime: str
    figure_psychometric: str
    figure_sheet: str
    notes: str


@dataclass(frozen=True)
class StageSeconds(Record):
    """The seconds each stage of ``flipstudy reproduce`` took."""
    design: float
    stimuli: float
    render: float
    sessions: float
    analysis: float
    total: float


# ---- analyze of a comparison study (flipstudy.analysis.compare.ComparisonAnalysis.to_dict)

@dataclass(frozen=True)
class Strength(Record):
    """One source's Bradley–Terry strength θ (logits) and its interval."""
    source: str
    strength: float
    low: float
    high: float
    wins: int
    n: int
    extra: dict = _extra()


@dataclass(frozen=True)
class Agreement(Record):
    """How well one per-clip number predicts people's choices (None where not measured)."""
    metric: str
    n: int | None = None
    accuracy: float | None = None
    accuracy_low: float | None = None
    accuracy_high: float | None = None
    auc: float | None = None
    auc_low: float | None = None
    auc_high: float | None = None
    extra: dict = _extra()


@dataclass(frozen=True)
class CompareReport(Record):
    """What ``flipstudy analyze --json`` prints for a comparison study."""
    participants: int
    choices: int
    ranking: tuple[Strength, ...]
    reference: str
    ci: float
    method: str
    agreement: tuple[Agreement, ...]
    files: dict[str, str]
    notes: tuple[str, ...]
    participants_label: str = ""      # "N = … (… real, … simulated)", on the figure and in notes.md


# ---- render: the render.json record (flipstudy.render.study.render_study)

@dataclass(frozen=True)
class RenderedStimulus(Record):
    """One stimulus of a render: its files (kind → file name) and what it was made from."""
    files: dict[str, str]
    style: object = None
    extra: dict = _extra()


@dataclass(frozen=True)
class RenderedOutput(Record):
    """One output file of a render, its content hash and what rendered it."""
    sha256: str
    style: object = None
    renderer: dict | None = None
    extra: dict = _extra()


@dataclass(frozen=True)
class RenderRecord(Record):
    """``render/render.json``: the settings of a render (``camera`` and ``style`` as the
    render part writes them), the stimuli and the outputs."""
    study: str
    what: tuple[str, ...]
    size: tuple[int, int]
    fps: float
    jobs: int
    camera: dict
    style: dict
    seconds: float
    made: int
    up_to_date: int
    stimuli: dict[str, RenderedStimulus]
    outputs: dict[str, RenderedOutput]
    extra: dict = _extra()


__all__ = ["RenderedStimulus", "RenderedOutput", "RenderRecord", "Strength", "Agreement", "CompareReport", "Record", "to_json", "from_json", "SessionStatus", "ImportedFile", "PlanRow", "Threshold",
           "GroupThresholds", "ParticipantThreshold", "FlowStage", "Participants", "AnalyzeSettings", "TableRow", "AnalyzeReport",
           "ReproduceFiles", "StageSeconds"]
