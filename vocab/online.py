"""The design file's ``[online]`` and ``[exclusions]`` tables (issue 32): what an online
study (Prolific, JATOS, Pavlovia) needs besides its stimuli, and the exclusion rules
stated before any data came in.

``[online]``::

    recruit_params  = ["PROLIFIC_PID", "STUDY_ID", "SESSION_ID"]  # URL parameters kept on every row
    completion_code = "C1A2B3"      # shown at the end (and put into completion_url's {code})
    completion_url  = ""            # "": Prolific's https://app.prolific.com/submissions/complete?cc={code}
    consent         = "consent.md"  # Markdown in the study folder (beside its design.toml); "" = none
    debrief         = "debrief.md"  # shown at the end; "" = none
    demographics    = true          # the demographics form
    min_refresh_hz  = 0.0           # screen check: below it the participant is told and stopped
    min_width       = 0             # window size (CSS pixels) the videos need
    min_height      = 0
    preload         = true          # every video fetched (progress bar) before the first trial
    block_order     = "interleaved" # or "latin-square": one block per group, blocks ordered by a
                                    # balanced Latin square row (the participant ID's hash picks it)
    between         = ["a", "b"]    # between-subject conditions: each participant sees one of these
                                    # groups (and every other group); least-filled first on JATOS
                                    # (its batch session), by the participant ID's hash elsewhere

``[exclusions]`` (participants; applied by ``analyze``, reported as a flow table)::

    catch_groups          = ["catch"]   # groups whose motions are attention checks (gross errors)
    min_catch_accuracy_pct = 75.0       # catch trials answered right, at least
    max_flagged_pct       = 100.0       # trials flagged for dropped frames, at most (percent)
    require_complete      = false       # sessions that did not answer every trial
    min_median_rt_ms      = 0.0         # median response time, at least

A catch group is an ordinary ``[[groups]]`` entry (kind and size of its gross error:
its ``kind`` and ``levels``; its rate: its share of the trials), interleaved by the
trial order like every group; ``analyze`` leaves it out of the tables.  Its trials, and
only they, are the catch trials: the right answer to its gross errors is "incorrect";
with ``original = "own"`` it may also show its own original (level 0, right answer
"correct", which catches a participant answering "incorrect" to everything).  The
shared original is never a catch trial: it stays the level 0 of the error groups.

>>> o = OnlineSettings.from_dict({"completion_code": "ABC"}, "d.toml: [online]")
>>> o.redirect_url()
'https://app.prolific.com/submissions/complete?cc=ABC'
>>> OnlineSettings.from_dict(o.to_dict()) == o
True
>>> Exclusions.from_dict({"min_median_rt_ms": -1}, "d.toml: [exclusions]")
Traceback (most recent call last):
...
flipstudy.errors.DesignError: d.toml: [exclusions].min_median_rt_ms: expected 0 to 60000 ms, got -1.0
"""
from __future__ import annotations

import re
from dataclasses import InitVar, dataclass, fields

from flipstudy.errors import DesignError

from ._designkeys import _between, _check_keys, _get, _show

PROLIFIC_PARAMS = ("PROLIFIC_PID", "STUDY_ID", "SESSION_ID")
#: the web trial order: groups interleaved (flipstudy.study.order's rule) or one block per
#: group, the blocks' order a row of a balanced Latin square
BLOCK_ORDERS = ("interleaved", "latin-square")
PROLIFIC_COMPLETE = "https://app.prolific.com/submissions/complete?cc={code}"
_PARAM = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")


def _params_ok(v):
    bad = [x for x in v if not isinstance(x, str) or not _PARAM.fullmatch(x)]
    if bad:
        return f"URL parameter names are letters, digits and '_' ({_show(bad[0])} is not)"
    return "listed twice" if len(set(v)) != len(v) else None


def _file_ok(v):
    return None if v == "" or re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}", v) else \
        "a file name beside the design (letters, digits, '_', '.', '-')"


def _url_ok(v):
    return None if v == "" or re.fullmatch(r"https://[^\s\"'<>]+", v) else "an https:// URL"


def _code_ok(v):
    return None if re.fullmatch(r"[A-Za-z0-9_-]{0,64}", v) else "letters, digits, '_' and '-'"


class _Table:
    """A frozen table of the design file read by its ``FIELDS``: key → (type, default, check)."""
    FIELDS: dict = {}
    SECTION = ""

    def __post_init__(self, where):
        w = where or f"[{self.SECTION}]"
        for key, (typ, _, check) in self.FIELDS.items():
            v = getattr(self, key)
            v = _get({key: list(v) if isinstance(v, tuple) else v}, key, typ, w, check=check)
            object.__setattr__(self, key, tuple(v) if typ is list else v)

    @classmethod
    def from_dict(cls, d: dict, where: str | None = None):
        w = where or f"[{cls.SECTION}]"
        if not isinstance(d, dict):
            raise DesignError(f"{w}: expected a table ({', '.join(cls.FIELDS)})")
        _check_keys(d, tuple(cls.FIELDS), w)
        return cls(**{k: _get(d, k, typ, w, default, check)
                      for k, (typ, default, check) in cls.FIELDS.items()}, where=w)

    def to_dict(self) -> dict:
        return {f.name: list(v) if isinstance(v := getattr(self, f.name), tuple) else v
                for f in fields(self)}

    @property
    def is_default(self) -> bool:
        return self == type(self)()


ONLINE_FIELDS = {
    "recruit_params": (list, list(PROLIFIC_PARAMS), _params_ok),
    "completion_code": (str, "", _code_ok),
    "completion_url": (str, "", _url_ok),
    "consent": (str, "", _file_ok),
    "debrief": (str, "", _file_ok),
    "demographics": (bool, True, None),
    "min_refresh_hz": (float, 0.0, _between(0, 1000, " Hz")),
    "min_width": (int, 0, _between(0, 10000, " pixels")),
    "min_height": (int, 0, _between(0, 10000, " pixels")),
    "preload": (bool, True, None),
    "between": (list, [], lambda v: None if all(isinstance(x, str) for x in v) and len(set(v)) == len(v)
                and len(v) != 1 else "group names, each once, at least two (or none)"),
    "block_order": (str, "interleaved", lambda v: None if v in BLOCK_ORDERS else f"must be one of {list(BLOCK_ORDERS)}"),
}


@dataclass(frozen=True)
class OnlineSettings(_Table):
    """The ``[online]`` table (see the module docstring)."""
    FIELDS = ONLINE_FIELDS
    SECTION = "online"
    recruit_params: tuple[str, ...] = PROLIFIC_PARAMS
    completion_code: str = ""
    completion_url: str = ""
    consent: str = ""
    debrief: str = ""
    demographics: bool = True
    min_refresh_hz: float = 0.0
    min_width: int = 0
    min_height: int = 0
    preload: bool = True
    block_order: str = "interleaved"
    between: tuple[str, ...] = ()
    where: InitVar[str | None] = None

    def __post_init__(self, where):
        _Table.__post_init__(self, where)

    def redirect_url(self) -> str:
        """Where the participant is sent at the end ("" = nowhere): ``completion_url`` with
        ``{code}`` filled in, or Prolific's completion URL when only a code is given."""
        url = self.completion_url or (PROLIFIC_COMPLETE if self.completion_code else "")
        return url.replace("{code}", self.completion_code)


EXCLUSION_FIELDS = {
    "catch_groups": (list, [], lambda v: None if all(isinstance(x, str) for x in v) and len(set(v)) == len(v)
                     else "group names, each once"),
    "min_catch_accuracy_pct": (float, 0.0, _between(0, 100, " percent")),
    "max_flagged_pct": (float, 100.0, _between(0, 100, " percent")),
    "require_complete": (bool, False, None),
    "min_median_rt_ms": (float, 0.0, _between(0, 60000, " ms")),
}


@dataclass(frozen=True)
class Exclusions(_Table):
    """The ``[exclusions]`` table: participant exclusion rules (see the module docstring)."""
    FIELDS = EXCLUSION_FIELDS
    SECTION = "exclusions"
    catch_groups: tuple[str, ...] = ()
    min_catch_accuracy_pct: float = 0.0
    max_flagged_pct: float = 100.0
    require_complete: bool = False
    min_median_rt_ms: float = 0.0
    where: InitVar[str | None] = None

    def __post_init__(self, where):
        _Table.__post_init__(self, where)
