"""The ``[[groups]]`` keys that say how a group's levels are chosen and asked:
``levels`` (a list, or a dense grid ``{from, to, step}``), ``method``
(``"constant"`` stimuli or adaptive ``"quest+"``), ``task`` (``"yes-no"`` or
``"2afc"``) and a quest+ group's settings (``trials``, ``stop_width``,
``threshold_prior``, ``width_prior``, ``lapse``; read into :class:`QuestSpec`,
whose fields are those of the adaptive engine's ``QuestSettings``).

Every invalid value raises :class:`~flipstudy.stimuli.design.DesignError` naming
file, group and key, like the rest of the design.

>>> grid_levels({"from": 0, "to": 1, "step": 0.25}, "d.toml: groups[0] (g)")
[0.0, 0.25, 0.5, 0.75, 1.0]
>>> grid_levels({"from": 0, "to": 1, "step": 0.3}, "d.toml: groups[0] (g)")
Traceback (most recent call last):
...
flipstudy.stimuli.design.DesignError: d.toml: groups[0] (g).levels.to: 1 % is not on the grid from 0 % in steps of 0.3 % (its last level would be 0.9 %); choose to = 0.9 or a step that divides 1
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from flipstudy.errors import DesignError
from ._designkeys import _check_keys, _get, _pct, _show

METHODS = ("constant", "quest+")
TASKS = ("yes-no", "2afc")
QUEST_KEYS = ("trials", "stop_width", "threshold_prior", "width_prior", "lapse")
GRID_KEYS = ("from", "to", "step")
LEVELS_MAX = 20          # levels of a group written as a list
GRID_MAX = 401           # levels of a grid
QUEST_TRIALS_MAX = 1000  # trials of one quest+ group per participant
LAPSE_MAX = 0.2          # exclusive
WIDTH_PRIOR_RANGE = (0.1, 1000.0)   # percent (psignifit width w = s * 3.29)


@dataclass(frozen=True)
class QuestSpec:
    """A quest+ group's settings as the design writes them (percent).  The fields
    are those of :class:`flipstudy.analysis.adaptive.QuestSettings` (the session
    builds that from this; the stimuli layer does not import the analysis)."""
    trials: int = 40                                     # stop after this many trials
    stop_width: float | None = None                      # or once the 95 % interval of x* is narrower
    threshold_prior: tuple[float, float] | None = None   # uniform prior on m; None: the grid's range
    width_prior: tuple[float, float] = (5.0, 60.0)       # uniform prior on the width w
    lapse: float = 0.02                                  # fixed lapse rate


def grid_levels(t: dict, where: str) -> list[float]:
    """The levels of a grid table ``{from, to, step}`` (percent): from, from + step, …, to.
    ``to`` must lie on the grid; at most :data:`GRID_MAX` levels."""
    w = f"{where}.levels"
    _check_keys(t, GRID_KEYS, w)
    lo = _get(t, "from", float, w, check=lambda v: None if v >= 0 else "expected 0 or more (percent)")
    hi = _get(t, "to", float, w, check=lambda v: None if v > lo else f"expected more than from = {lo:g}")
    step = _get(t, "step", float, w, check=lambda v: None if v > 0 else "expected more than 0 (percent)")
    span = (hi - lo) / step
    if span + 1 > GRID_MAX + 1e-6:
        raise DesignError(f"{w}: from {lo:g} to {hi:g} in steps of {step:g} is {math.floor(span + 1e-9) + 1} "
                          f"levels; a grid has at most {GRID_MAX} (a larger step)")
    n = round(span)
    if abs(n - span) > 1e-6 * max(1.0, span):
        last = round(lo + math.floor(span) * step, 9)
        raise DesignError(f"{w}.to: {hi:g} % is not on the grid from {lo:g} % in steps of {step:g} % "
                          f"(its last level would be {last:g} %); choose to = {last:g} or a step "
                          f"that divides {hi - lo:g}")
    return [round(lo + i * step, 9) for i in range(n + 1)]


def parse_levels(g: dict, where: str, kind: str, sign: int, top: float, excluded: bool) -> list[float]:
    """A group's ``levels``: a list (at most :data:`LEVELS_MAX`) or a grid table; each
    in 0..``top`` percent (``top`` itself refused when ``excluded``); sorted."""
    if "levels" not in g:
        raise DesignError(f"{where}: missing field 'levels'")
    levels = g["levels"]
    if isinstance(levels, dict):
        values = grid_levels(levels, where)
    elif isinstance(levels, list):
        if not levels:
            raise DesignError(f"{where}.levels: at least one level is needed")
        if len(levels) > LEVELS_MAX:
            raise DesignError(f"{where}.levels: {len(levels)} levels; at most {LEVELS_MAX} per group "
                              f"as a list (a dense grid is written levels = {{from = 0, to = 60, "
                              f"step = 1}}, at most {GRID_MAX} levels)")
        values = levels
    else:
        raise DesignError(f"{where}.levels: expected an array of levels or a grid table "
                          f"{{from, to, step}}, got {_show(levels)}")
    what = f"{'an increase' if sign > 0 else 'a decrease'} of the {kind.replace('-', ' ')}"
    lv = []
    for v in values:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise DesignError(f"{where}.levels: each level is a number (percent), got {_show(v)}")
        if not math.isfinite(v) or v < 0:
            raise DesignError(f"{where}.levels: {_pct(v)} %: each level is the size of the error in "
                              f"percent, 0 or more (the direction is the group's sign = {sign})")
        if v > top or (excluded and v >= top):
            limit = f"below {top:g} %" if excluded else f"at most {top:g} %"
            why = " (it stops the rotation)" if kind == "angular-momentum" and sign < 0 else ""
            if kind == "pose-rate":
                what, limit = "a pose rate", f"at most {top:g} poses per second"
            raise DesignError(f"{where}.levels: {_pct(v)} % is out of range: {what} must be "
                              f"{limit}{why}")
        lv.append(float(v))
    if len(set(lv)) != len(lv):
        raise DesignError(f"{where}.levels: duplicate levels in {_show(levels)}")
    names: dict[str, float] = {}
    for v in lv:                      # the level names its stimulus (f"{level:g}")
        if f"{v:g}" in names:
            raise DesignError(f"{where}.levels: {names[f'{v:g}']!r} and {v!r} % give the same "
                              f"stimulus name ({v:g}); levels differ in their first 6 digits")
        names[f"{v:g}"] = v
    return sorted(lv)


def parse_method_task(g: dict, where: str, study_task: str) -> tuple[str, str]:
    """A group's ``method`` (default ``"constant"``) and ``task`` (default the study's)."""
    method = _get(g, "method", str, where, "constant",
                  lambda v: None if v in METHODS else f"must be one of {list(METHODS)}")
    task = _get(g, "task", str, where, study_task,
                lambda v: None if v in TASKS else f"must be one of {list(TASKS)}")
    return method, task


def _pair(t: dict, key: str, where: str, lo: float, hi: float, unit: str):
    v = t[key]
    if (not isinstance(v, list) or len(v) != 2
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v)):
        raise DesignError(f"{where}.{key}: expected two numbers [low, high] ({unit}), got {_show(v)}")
    a, b = float(v[0]), float(v[1])
    if not (math.isfinite(a) and math.isfinite(b) and lo <= a < b <= hi):
        raise DesignError(f"{where}.{key}: expected {lo:g} <= low < high <= {hi:g} ({unit}), "
                          f"got {_show(v)}")
    return a, b


def parse_quest(g: dict, where: str, method: str, task: str, levels: list[float]) -> QuestSpec | None:
    """A quest+ group's :class:`QuestSpec` (None for a constant group, which may not
    write these keys)."""
    given = [k for k in QUEST_KEYS if k in g]
    if method != "quest+":
        if given:
            raise DesignError(f"{where}.{given[0]}: only quest+ groups have {', '.join(QUEST_KEYS)}; "
                              f"add method = \"quest+\" or remove it")
        return None
    grid = [v for v in levels if not (task == "2afc" and v == 0)]
    if len(grid) < 3:
        raise DesignError(f"{where}.levels: a quest+ group needs at least 3 levels to choose from"
                          f"{' besides 0 (the 2AFC comparison)' if task == '2afc' else ''}, got "
                          f"{len(grid)}; write a grid such as levels = {{from = 0, to = 60, step = 1}}")
    lo, hi = min(grid), max(grid)
    trials = _get(g, "trials", int, where, 40,
                  lambda v: None if 1 <= v <= QUEST_TRIALS_MAX else f"expected 1 to {QUEST_TRIALS_MAX} trials")
    stop = _get(g, "stop_width", float, where, None,
                lambda v: None if 0 < v <= 1000 else "expected more than 0 and at most 1000 (percent)")
    tprior = _pair(g, "threshold_prior", where, lo, hi,
                   f"percent, within the grid {lo:g} to {hi:g}") if "threshold_prior" in g else None
    wprior = _pair(g, "width_prior", where, *WIDTH_PRIOR_RANGE, "percent") \
        if "width_prior" in g else QuestSpec.width_prior
    lapse = _get(g, "lapse", float, where, QuestSpec.lapse,
                 lambda v: None if 0 <= v < LAPSE_MAX else f"expected 0 or more and below {LAPSE_MAX:g}")
    return QuestSpec(trials, stop, tprior, wprior, lapse)
