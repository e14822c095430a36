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
flipstudy.errors.DesignError: d.toml: groups[0] (g).levels.to: 1 % is not on the grid from 0 % in steps of 0.3 % (its last level would be 0.9 %); choose to = 0.9 or a step that divides 1
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from flipstudy.errors import DesignError
from . import kinds
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
    if not span + 1 <= GRID_MAX + 1e-6:        # also a step so small the count overflows
        count = f"{math.floor(span + 1e-9) + 1}" if span < 1e6 else "over a million"
        raise DesignError(f"{w}.step: from {lo:g} to {hi:g} in steps of {step:g} is {count} "
                          f"levels; a grid has at most {GRID_MAX} (a step of at least "
                          f"{(hi - lo) / (GRID_MAX - 1):g})")
    n = round(span)
    if abs(n - span) > 1e-6 * max(1.0, span):
        last = round(lo + math.floor(span) * step, 9)
        raise DesignError(f"{w}.to: {hi:g} % is not on the grid from {lo:g} % in steps of {step:g} % "
                          f"(its last level would be {last:g} %); choose to = {last:g} or a step "
                          f"that divides {hi - lo:g}")
    return [round(lo + i * step, 9) for i in range(n + 1)]


def read_levels(g: dict, where: str) -> list:
    """A group table's ``levels`` as written: a list (at most :data:`LEVELS_MAX`) or
    a grid table (:func:`grid_levels`); the values are checked by :func:`check_levels`."""
    if "levels" not in g:
        raise DesignError(f"{where}: missing field 'levels'")
    levels = g["levels"]
    if isinstance(levels, dict):
        return grid_levels(levels, where)
    if isinstance(levels, list):
        if len(levels) > LEVELS_MAX:
            raise DesignError(f"{where}.levels: {len(levels)} levels; at most {LEVELS_MAX} per group "
                              f"as a list (a dense grid is written levels = {{from = 0, to = 60, "
                              f"step = 1}}, at most {GRID_MAX} levels)")
        return levels
    raise DesignError(f"{where}.levels: expected an array of levels or a grid table "
                      f"{{from, to, step}}, got {_show(levels)}")


def levels_table(levels) -> list | dict:
    """``levels`` as a design writes them: a list, or (more than :data:`LEVELS_MAX`) the
    grid table :func:`grid_levels` reads back to the same levels."""
    if len(levels) <= LEVELS_MAX:
        return list(levels)
    lo, hi, n = levels[0], levels[-1], len(levels) - 1
    for step in (round((hi - lo) / n, 9), (hi - lo) / n):
        t = {"from": lo, "to": hi, "step": step}
        try:
            if grid_levels(t, "") == list(levels):
                return t
        except DesignError:
            pass
    raise DesignError(f"levels: {len(levels)} levels that are not a grid; at most {LEVELS_MAX} as a list")


def check_levels(values, where: str, kind: str, sign: int, top: float, excluded: bool) -> tuple:
    """A group's levels checked: at least one, at most :data:`GRID_MAX`, each in
    0..``top`` percent (``top`` itself refused when ``excluded``), no two alike or
    naming the same stimulus; returned sorted, as a tuple of floats.  Levels all
    below 1 % (fractions where percent was meant) warn (a ``UserWarning``)."""
    if isinstance(values, (str, bytes, dict)) or not hasattr(values, "__len__"):
        raise DesignError(f"{where}.levels: expected an array of levels or a grid table "
                          f"{{from, to, step}}, got {_show(values)}")
    if not len(values):
        raise DesignError(f"{where}.levels: at least one level is needed")
    if len(values) > GRID_MAX:
        raise DesignError(f"{where}.levels: {len(values)} levels; a group has at most {GRID_MAX}")
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
            why = " (it stops the rotation)" if kind == kinds.AM.name and sign < 0 else ""
            if kind == kinds.POSE_RATE.name:
                what, limit = "a pose rate", f"at most {top:g} poses per second"
            raise DesignError(f"{where}.levels: {_pct(v)} % is out of range: {what} must be "
                              f"{limit}{why}")
        lv.append(float(v))
    if len(set(lv)) != len(lv):
        raise DesignError(f"{where}.levels: duplicate levels in {_show(list(values))}")
    names: dict[str, float] = {}
    for v in lv:                      # the level names its stimulus (f"{level:g}")
        if f"{v:g}" in names:
            raise DesignError(f"{where}.levels: {names[f'{v:g}']!r} and {v!r} % give the same "
                              f"stimulus name ({v:g}); levels differ in their first 6 digits")
        names[f"{v:g}"] = v
    if kind != kinds.POSE_RATE.name and 0 < max(lv) < 1:     # fractions where percent was meant?
        import warnings
        warnings.warn(f"{where}.levels: every level is below 1 % ({_show(sorted(lv))}); levels are "
                      f"percent (25 is a 25 % error): if these are fractions, multiply them by 100",
                      UserWarning, stacklevel=4)
    return tuple(sorted(lv))


def _pair(t: dict, key: str, where: str, lo: float, hi: float, unit: str):
    v = t[key]
    if (not isinstance(v, (list, tuple)) or len(v) != 2
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v)):
        raise DesignError(f"{where}.{key}: expected two numbers [low, high] ({unit}), got {_show(v)}")
    a, b = float(v[0]), float(v[1])
    if not (math.isfinite(a) and math.isfinite(b) and lo <= a < b <= hi):
        raise DesignError(f"{where}.{key}: expected {lo:g} <= low < high <= {hi:g} ({unit}), "
                          f"got {_show(v)}")
    return a, b


def quest_table(g: dict) -> QuestSpec | None:
    """The quest+ keys a group table writes, as a :class:`QuestSpec` (unchecked; None
    when it writes none)."""
    given = {k: g[k] for k in QUEST_KEYS if k in g}
    return QuestSpec(**given) if given else None


def check_quest(q: QuestSpec | None, where: str, method: str, task: str, levels) -> QuestSpec | None:
    """A group's quest+ settings checked (a constant group has none; a quest+ group
    without them gets the defaults)."""
    if method != "quest+":
        if q is not None:
            given = [k for k in QUEST_KEYS if getattr(q, k) != getattr(QuestSpec, k)] or ["trials"]
            raise DesignError(f"{where}.{given[0]}: only quest+ groups have {', '.join(QUEST_KEYS)}; "
                              f"add method = \"quest+\" or remove it")
        return None
    q = q if q is not None else QuestSpec()
    grid = [v for v in levels if not (task == "2afc" and v == 0)]
    if len(grid) < 3:
        raise DesignError(f"{where}.levels: a quest+ group needs at least 3 levels to choose from"
                          f"{' besides 0 (the 2AFC comparison)' if task == '2afc' else ''}, got "
                          f"{len(grid)}; write a grid such as levels = {{from = 0, to = 60, step = 1}}")
    lo, hi = min(grid), max(grid)
    t = {k: getattr(q, k) for k in QUEST_KEYS}
    trials = _get(t, "trials", int, where,
                  check=lambda v: None if 1 <= v <= QUEST_TRIALS_MAX else f"expected 1 to {QUEST_TRIALS_MAX} trials")
    stop = None if q.stop_width is None else _get(
        t, "stop_width", float, where,
        check=lambda v: None if 0 < v <= 1000 else "expected more than 0 and at most 1000 (percent)")
    tprior = None if q.threshold_prior is None else _pair(
        t, "threshold_prior", where, lo, hi, f"percent, within the grid {lo:g} to {hi:g}")
    wprior = _pair(t, "width_prior", where, *WIDTH_PRIOR_RANGE, "percent")
    lapse = _get(t, "lapse", float, where,
                 check=lambda v: None if 0 <= v < LAPSE_MAX else f"expected 0 or more and below {LAPSE_MAX:g}")
    return QuestSpec(trials, stop, tprior, wprior, lapse)
