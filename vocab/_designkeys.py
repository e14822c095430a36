"""The design file's field readers: each reads one TOML value, checks its type and
bounds, and raises :class:`DesignError` naming file, section and key and the value
as written (shared by :mod:`flipstudy.stimuli.design` and
:mod:`flipstudy.stimuli.groupkeys`).

>>> _get({"fps": 120}, "fps", float, "d.toml: [study]")
120.0
>>> _get({"fps": "fast"}, "fps", float, "d.toml: [study]")
Traceback (most recent call last):
...
flipstudy.errors.DesignError: d.toml: [study].fps: expected a number, got 'fast'
"""
from __future__ import annotations

import difflib
import math
import re

from flipstudy.errors import DesignError


#: test trials per participant (repetitions × stimuli, quest+ trials)
TRIALS_MAX = 3000


def _name_ok(v: str):
    """None if ``v`` can name files (a group, clip, source or item), else what is wrong."""
    return None if re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}", v) else \
        "must be 1-64 letters, digits, '_', '.', '-' (it names files)"


def _typename(typ) -> str:
    names = {"str": "a string", "int": "a whole number", "float": "a number", "bool": "true or false",
             "list": "an array", "dict": "a table"}
    return names.get(typ.__name__, typ.__name__)


def _get(d: dict, key: str, typ, where: str, default=..., check=None):
    if key not in d:
        if default is ...:
            raise DesignError(f"{where}: missing field '{key}'")
        return default
    v = d[key]
    if typ is float and isinstance(v, int) and not isinstance(v, bool):
        v = float(v)
    if not isinstance(v, typ) or isinstance(v, bool) and typ is not bool:
        raise DesignError(f"{where}.{key}: expected {_typename(typ)}, got {_show(v)}")
    if typ is float and not math.isfinite(v):
        raise DesignError(f"{where}.{key}: expected a finite number, got {_show(v)}")
    if check is not None:
        msg = check(v)
        if msg:
            raise DesignError(f"{where}.{key}: {msg}, got {_show(v)}")
    return v


def _show(v) -> str:
    """A value as the user wrote it in TOML (short)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if v != v else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return repr(v if len(v) <= 60 else v[:57] + "...")
    if isinstance(v, (list, dict)):
        r = repr(v)
        return r if len(r) <= 60 else r[:57] + "..."
    return repr(v)


def _pct(v) -> str:
    """A level as written, in percent: 200, 17.5, 99.999999 (not rounded to 100), inf."""
    return _show(v) if isinstance(v, float) and not math.isfinite(v) else f"{v:.12g}"


def _between(lo, hi, unit: str = ""):
    return lambda v: None if lo <= v <= hi else f"expected {lo:g} to {hi:g}{unit}"


def _check_keys(table: dict, allowed, where: str) -> None:
    """Refuse keys a section does not know, suggesting the closest known one."""
    for k in table:
        if k in allowed:
            continue
        close = difflib.get_close_matches(str(k), allowed, n=1, cutoff=0.6)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise DesignError(f"{where}: unknown key '{k}'{hint} (known keys: {', '.join(allowed)})")
