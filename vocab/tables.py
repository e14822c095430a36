"""The tables of a design below ``[study]``: the ``[[clips]]``, ``[[sources]]`` and
``[[groups]]`` entries and the ``[session]`` settings, each a frozen type valid when it
exists, with the bounds of every number (see :mod:`flipstudy.vocab.design`, which
re-exports every name here)."""
from __future__ import annotations

import difflib
import json
import warnings
from dataclasses import InitVar, dataclass

from flipstudy.errors import DesignError
from . import kinds
from ._designkeys import _between, _check_keys, _get, _name_ok, _show
from .groupkeys import (METHODS, QUEST_KEYS, TASKS, QuestSpec, check_levels, check_quest, levels_table,
                        quest_table, read_levels)


OLD_SESSION_KEYS = ("replay", "break_every")   # also read from [study], as designs wrote them before
#: the character styles a design may choose (drawn by flipstudy.render.characters)
CHARACTER_STYLES = ("ellipsoids", "capsules", "stick", "point-light", "mannequin")
REFERENCE_KEYS = ("clips",)
SECTIONS = ("study", "session", "clips", "groups", "reference", "sources", "online", "exclusions")
ORIGINAL_MODES = ("shared", "per-group")   # [study] original
GROUP_ORIGINAL = ("shared", "own")         # [[groups]] original
#: the group name of the shared original in the manifest and the responses
SHARED_ORIGINAL_GROUP = "original"
RESERVED_GROUP_NAMES = ("reference", SHARED_ORIGINAL_GROUP)

#: bounds of every number of a design (inclusive unless said otherwise)
MAX_SEED = 2 ** 63 - 1
FPS_RANGE = (10.0, 1000.0)
REPETITIONS_MAX = 20
MASS_RANGE = (20.0, 200.0)            # kg
TOLERANCE_MAX = 50.0                  # percent
#: percentage points: a measured error is exact to about 1e-9 points on a built-in (its
#: floating-point arithmetic), so a smaller tolerance refuses exact stimuli
TOLERANCE_MIN = 1e-6
BREAK_EVERY_MAX = 10000
SCALE_RANGE = (1e-4, 100.0)           # metres per file unit (mm is 0.001, m is 1)
#: level bounds in percent by (kind, sign): (largest magnitude, is it excluded)
#: (the built-in kinds' as this module was imported; a group reads its kind's entry of
#: the registry, :mod:`flipstudy.vocab.kinds`)
LEVEL_BOUNDS = kinds.level_bounds()
MAX_DESIGN_BYTES = 1_000_000



def _field(obj, key: str, typ, where: str, check=None, optional: bool = False):
    """Check field ``key`` of a design type being made (type, finite, ``check``), store
    it as read (an int where a number is expected becomes a float) and return it."""
    v = getattr(obj, key)
    if v is None and optional:
        return None
    v = _get({key: v}, key, typ, where, check=check)
    object.__setattr__(obj, key, v)
    return v


def _kinds_that(flag: str) -> str:
    """The names of the injected kinds with ``flag`` set, for a refusal's message."""
    return ", ".join(k.name for k in kinds.study_kinds() if getattr(k, flag))


def _one_of(values):
    return lambda v: None if v in values else f"must be one of {list(values)}"


#: what each type's fields may hold, by TOML key: (type, default, check); the
#: default ``...`` means the key must be given, None that it may be left out
CLIP_FIELDS = {
    "name": (str, ..., None),          # checked by _name_ok (defined below)
    "source": (str, ..., lambda v: None if 0 < len(v) <= 4096 else "expected a built-in name or a path"),
    "scale": (float, None, _between(*SCALE_RANGE, " metres per file unit")),
    "fps": (float, None, _between(*FPS_RANGE, " frames per second")),
    "flips": (int, None, lambda v: None if 1 <= v <= 6 else "expected a whole number of flips from 1 to 6"),
    "k_ratio": (float, 0.7, lambda v: None if 0.2 <= v <= 2 else "expected a fraction of k* from 0.2 to 2"),
    "accept_unphysical": (bool, False, None),
}


class _TableSpec:
    """An entry of an array of tables (``[[clips]]``, ``[[sources]]``) whose keys are
    its ``FIELDS`` (TOML key → (type, default, check); ``...``: required, None: may
    be left out): checked on construction, read by :meth:`from_dict`, written by
    :meth:`to_dict`.  ``SECTION`` names the array in errors."""
    FIELDS: dict = {}
    SECTION = ""

    def __post_init__(self, where):
        w = where or self.SECTION
        _field(self, "name", str, w, _name_ok)
        for key, (typ, default, check) in self.FIELDS.items():
            if key != "name":
                _field(self, key, typ, w, check, optional=default is None)

    @classmethod
    def from_dict(cls, c: dict, where: str | None = None):
        where = where or cls.SECTION
        if not isinstance(c, dict):
            raise DesignError(f"{where}: expected a table")
        _check_keys(c, tuple(cls.FIELDS), where + (f" ({c['name']})" if isinstance(c.get("name"), str) else ""))
        for key, (typ, default, check) in cls.FIELDS.items():
            if default is ... and key not in c:
                raise DesignError(f"{where}: missing field '{key}'")
        return cls(**c, where=where)

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.FIELDS if getattr(self, k) is not None}


@dataclass(frozen=True)
class ClipSpec(_TableSpec):
    """A ``[[clips]]`` entry, valid when it exists (every field checked against
    :data:`CLIP_FIELDS`; ``where`` names the file and entry in errors)."""
    name: str
    source: str                 # built-in name or BVH path (relative to the design file)
    scale: float | None = None  # metres per file unit (BVH); None: guess
    fps: float | None = None    # override the file's frame rate (BVH)
    flips: int | None = None    # turn the clip into an N-flip one first (flipstudy edit)
    k_ratio: float = 0.7        # its retiming factor as a fraction of k*
    accept_unphysical: bool = False  # build it although its gravity or height contradicts physics
    where: InitVar[str | None] = None
    FIELDS = CLIP_FIELDS
    SECTION = "clips"


#: what a ``[[sources]]`` entry may hold (see :class:`SourceSpec`)
SOURCE_FIELDS = {
    "name": (str, ..., None),          # checked by _name_ok
    "folder": (str, ..., lambda v: None if 0 < len(v) <= 4096 else "expected a folder path"),
    "scale": (float, None, _between(*SCALE_RANGE, " metres per file unit")),
    "fps": (float, None, _between(*FPS_RANGE, " frames per second")),
    "accept_unphysical": (bool, False, None),
}
#: the kind of a stimulus that is a source's clip as given (no error injected)
GIVEN_KIND = "given"


def pair_group(shown: str, comparison: str) -> str:
    """The group of a comparison design's 2AFC trials that show ``shown``'s clip beside
    ``comparison``'s (other than the first source's, whose are the source's own group)."""
    return f"{shown}-vs-{comparison}"


@dataclass(frozen=True)
class SourceSpec(_TableSpec):
    """A ``[[sources]]`` entry of a comparison design: a named folder of clips (ground
    truth, model A, ...), each clip read by the one loading rule of every CLIP
    (:func:`flipstudy.stimuli.loading.load_clip`, with this entry's ``scale`` and
    ``fps``); clips of different sources are the same item when their file stems
    are equal.  ``folder`` is relative to the design file."""
    name: str
    folder: str
    scale: float | None = None
    fps: float | None = None
    accept_unphysical: bool = False
    where: InitVar[str | None] = None
    FIELDS = SOURCE_FIELDS
    SECTION = "sources"


@dataclass(frozen=True)
class SourceGroup:
    """The group of one source's clips in a comparison design (made by :class:`Design`
    from ``[[sources]]``, never written): its stimuli are the source's clips as
    given (kind :data:`GIVEN_KIND`, level 0).  With ``task = "2afc"`` each clip of a
    source other than the first is shown beside the first source's clip of the same
    item (its ``original``); the first source's clips are the comparisons, not
    trials.  It answers what the session code asks of a :class:`Group`."""
    name: str
    task: str = "yes-no"
    kind: str = GIVEN_KIND
    profile: None = None
    sign: int = 1
    levels: tuple = (0.0,)
    original: str = "own"
    style: None = None
    method: str = "constant"
    quest: None = None
    policy: None = None
    axis: None = None
    span: None = None
    adaptive = False

    def trial_levels(self) -> list[float]:
        return [0.0]


GROUP_FIELDS = {
    "name": (str, ..., None), "kind": (str, ..., lambda v: _one_of(kinds.study_kind_names())(v)),
    "profile": (str, None, _one_of(kinds.AM.variants)), "sign": (int, 1, lambda v: None if v in (1, -1) else "must be 1 or -1"),
    "levels": (list, ..., None), "original": (str, "own", _one_of(GROUP_ORIGINAL)),
    "style": (str, None, None), "method": (str, "constant", _one_of(METHODS)),
    "task": (str, "yes-no", _one_of(TASKS)),
    "policy": (str, None, None), "axis": (str, None, None), "span": (str, None, None),
}


@dataclass(frozen=True)
class Group:
    """A ``[[groups]]`` entry, valid when it exists: kind, profile, sign, its kind's
    option, levels in the kind's range (:data:`LEVEL_BOUNDS`), method, task and a
    quest+ group's settings are checked on construction (``where`` names the file
    and group in errors).  What depends on the whole design (a reserved or repeated
    name, a shared original in another style) is checked by :class:`Design`."""
    name: str
    kind: str                   # an injected kind of the registry (flipstudy.vocab.kinds)
    profile: str | None         # "smooth" | "abrupt" (angular momentum only)
    sign: int                   # +1 increase, -1 decrease
    levels: tuple[float, ...]   # nominal error in percent (magnitude; 0 = original), sorted
    original: str = "own"       # "shared": its level 0 is the clip's shared original
    style: str | None = None    # character style of its stimuli (None: the study's)
    method: str = "constant"    # "constant" stimuli | "quest+" (adaptive over the levels)
    task: str = "yes-no"        # "yes-no" | "2afc" (original and modified, which was correct?)
    quest: QuestSpec | None = None   # a quest+ group's settings
    policy: str | None = None   # gravity: what stays ("takeoff-velocity" | "apex-height" | "flight-time")
    axis: str | None = None     # acceleration: "horizontal" | "vertical"
    span: str | None = None     # time-scale: "flight" | "whole"
    where: InitVar[str | None] = None

    def __post_init__(self, where):
        w0 = where or "groups"
        name = _field(self, "name", str, w0, _name_ok)
        wg = f"{w0} ({name})"
        kind = _field(self, "kind", str, wg, _one_of(kinds.study_kind_names()))
        entry = kinds.get(kind)
        if entry.profiled:
            only_original = isinstance(self.levels, (list, tuple)) and list(self.levels) == [0]
            if self.profile is None and not only_original:    # (the shared original has none)
                raise DesignError(f"{wg}: missing field 'profile'")
            _field(self, "profile", str, wg, _one_of(entry.variants), optional=only_original)
        elif self.profile is not None:
            raise DesignError(f"{wg}.profile: only {_kinds_that('profiled')} groups have a profile")
        sign = _field(self, "sign", int, wg, GROUP_FIELDS["sign"][2])
        options = kinds.kind_options()
        key = options.get(kind, (None,))[0]
        for other in ("policy", "axis", "span"):
            if getattr(self, other) is not None and other != key:
                owner = [k for k, v in options.items() if v[0] == other][0]
                raise DesignError(f"{wg}.{other}: only {owner} groups have a{'n' if other[0] in 'a' else ''} "
                                  f"{other}")
        if kind == kinds.POSE_RATE.name and sign != 1:
            raise DesignError(f"{wg}.sign: a pose-rate group's levels are poses per second; its sign is 1")
        if key is not None:
            _, default, values = options[kind]
            if getattr(self, key) is None:
                if default is None:
                    raise DesignError(f"{wg}: missing field '{key}'")
                object.__setattr__(self, key, default)
            _field(self, key, str, wg, _one_of(values))
        if sign not in entry.bounds:
            raise DesignError(f"{wg}.sign: a {kind} group's sign is {_show(entry.signs[0])}")
        top, excluded = entry.bounds[sign]
        lv = check_levels(self.levels, wg, kind, sign, top, excluded)
        object.__setattr__(self, "levels", lv)
        method = _field(self, "method", str, wg, _one_of(METHODS))
        task = _field(self, "task", str, wg, _one_of(TASKS))
        object.__setattr__(self, "quest", check_quest(self.quest, wg, method, task, lv))
        if method == "quest+" and kind == kinds.POSE_RATE.name:
            raise DesignError(f"{wg}.method: QUEST+ assumes the error grows with the level, and a "
                              f"pose rate's error grows as the level (poses per second) falls; run "
                              f"pose-rate groups with method = \"constant\"")
        if task == "2afc" and (0.0 not in lv or len(lv) < 2):
            raise DesignError(f"{wg}.levels: a 2afc group shows each level beside the original, so "
                              f"its levels need 0 (the original) and at least one error level, got "
                              f"{_show(list(lv))}")
        orig = _field(self, "original", str, wg, _one_of(GROUP_ORIGINAL))
        if orig == "shared" and not entry.shares_original:
            raise DesignError(f"{wg}.original: only {_kinds_that('shares_original')} groups share their original "
                              f"(the paper's take-off group had its own); use original = \"own\"")
        _field(self, "style", str, wg, _style_ok, optional=True)

    @classmethod
    def from_dict(cls, g: dict, where: str = "groups", study_task: str = "yes-no",
                  study_original: str = "per-group") -> "Group":
        """A group from its TOML table (``levels`` a list or a grid; the quest+ keys at
        the top level); ``study_task`` and ``study_original`` give the defaults the
        ``[study]`` table sets."""
        if not isinstance(g, dict):
            raise DesignError(f"{where}: expected a table")
        _check_keys(g, GROUP_KEYS, where + (f" ({g['name']})" if isinstance(g.get("name"), str) else ""))
        name = _get(g, "name", str, where, check=_name_ok)
        wg = f"{where} ({name})"
        kind = _get(g, "kind", str, wg, check=_one_of(kinds.study_kind_names()))
        if kinds.get(kind).profiled:
            _get(g, "profile", str, wg, check=_one_of(kinds.get(kind).variants))
        kw = {k: g[k] for k in GROUP_FIELDS if k in g and k != "levels"}
        kw["levels"] = read_levels(g, wg)
        kw.setdefault("profile", None)
        kw.setdefault("sign", 1)
        kw.setdefault("task", study_task)
        kw.setdefault("original", "shared" if study_original == "shared" and kinds.get(kind).shares_original
                      else "own")
        return cls(**kw, quest=quest_table(g), where=where)

    def to_dict(self) -> dict:
        """The group's TOML table (what :meth:`from_dict` reads back to an equal group)."""
        out = {"name": self.name, "kind": self.kind}
        if self.profile is not None:
            out["profile"] = self.profile
        out.update(sign=self.sign, levels=levels_table(self.levels), original=self.original,
                   method=self.method, task=self.task)
        for k in ("style", "policy", "axis", "span"):
            if getattr(self, k) is not None:
                out[k] = getattr(self, k)
        if self.quest is not None:
            for k in QUEST_KEYS:
                v = getattr(self.quest, k)
                if v is not None:
                    out[k] = list(v) if isinstance(v, tuple) else v
        return out

    @property
    def adaptive(self) -> bool:
        """Does the session choose this group's levels (quest+)?"""
        return self.method == "quest+"

    def trial_levels(self) -> list[float]:
        """The levels its trials show: level 0 is a 2AFC group's comparison, not a trial
        level, and a shared original is shown as the group ``original``."""
        return [v for v in self.levels
                if v != 0 or (self.task == "yes-no" and (self.adaptive or self.original != "shared"))]


SESSION_FIELDS = {
    "replay": (bool, False, None),
    "break_every": (int, 40, _between(1, BREAK_EVERY_MAX, " trials")),
    "max_dropped_pct": (float, 10.0, _between(0, 100, " percent of a video's frames")),
    "repeat_dropped": (bool, False, None),
}


@dataclass(frozen=True)
class SessionSettings:
    """How the sessions present a design's stimuli: the design file's ``[session]``
    table.  None of these changes a stimulus; the session code in
    :mod:`flipstudy.study` reads them from ``design.session``."""

    replay: bool = False              # may a participant replay a motion before answering
    break_every: int = 40             # trials between breaks
    max_dropped_pct: float = 10.0     # web: flag a trial whose video dropped more % of its frames
    repeat_dropped: bool = False      # web: show the flagged trials once more at the end
    where: InitVar[str | None] = None

    def __post_init__(self, where):
        for key, (typ, _, check) in SESSION_FIELDS.items():
            _field(self, key, typ, where or "[session]", check)

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in SESSION_FIELDS}


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):                  # JSON's escapes are TOML's; TOML also wants DEL escaped
        return json.dumps(v, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML for {v!r}")


def _toml(d: dict) -> str:
    """TOML text of a design's tables (tables and arrays of tables of plain values)."""
    out = []
    for section, body in d.items():
        for table in (body if isinstance(body, list) else [body]):
            out.append(f"[[{section}]]" if isinstance(body, list) else f"[{section}]")
            out += [f"{k} = {_toml_value(v)}" for k, v in table.items()]
            out.append("")
    return "\n".join(out)


def _parse_session(d: dict, st: dict, src: str) -> SessionSettings:
    """The ``[session]`` table; its keys written in ``[study]`` (designs before the
    table) are read the same way, with a ``FutureWarning``."""
    se = d.get("session", {})
    if not isinstance(se, dict):
        raise DesignError(f"{src}: [session]: expected a table ({', '.join(SESSION_KEYS)})")
    _check_keys(se, SESSION_KEYS, f"{src}: [session]")
    old = [k for k in OLD_SESSION_KEYS if k in st]
    for k in old:
        if k in se:
            raise DesignError(f"{src}: [study].{k} and [session].{k} are both given; {k} is a "
                              f"session setting: keep the one in [session]")
    values = {}
    for key, (typ, default, check) in SESSION_FIELDS.items():
        table, where = (st, f"{src}: [study]") if key in st else (se, f"{src}: [session]")
        values[key] = _get(table, key, typ, where, default, check)
    settings = SessionSettings(**values, where=f"{src}: [session]")
    if old:
        warnings.warn(f"{src}: [study] {', '.join(old)}: session settings go in a [session] table "
                      f"now; read as [session] {', '.join(old)} (move them there)",
                      FutureWarning, stacklevel=4)
    return settings


def _style_ok(v: str):
    """None if ``v`` is a character style, else what is wrong (with a did-you-mean)."""
    if v in CHARACTER_STYLES:
        return None
    close = difflib.get_close_matches(v, CHARACTER_STYLES, n=1, cutoff=0.5)
    hint = f" (did you mean '{close[0]}'?)" if close else ""
    return f"unknown character style{hint}; expected one of {', '.join(CHARACTER_STYLES)}"


#: the keys each section may hold (anything else is refused with a did-you-mean): the types' fields
SESSION_KEYS = tuple(SESSION_FIELDS)
CLIP_KEYS = tuple(CLIP_FIELDS)
GROUP_KEYS = (*GROUP_FIELDS, *QUEST_KEYS)
