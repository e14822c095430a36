"""Field checks of the site's records (:mod:`flipstudy.study.web.importer`): each
raises :class:`WebImportError` naming where the record came from and the field.

>>> _num("12.5", "f: line 3", "rt_ms", 0, 100)
12.5
>>> _str("maybe", "f: line 3", "response", ("first", "second"))
Traceback (most recent call last):
...
flipstudy.errors.WebImportError: f: line 3: response: must be one of first, second, got 'maybe'
"""
from __future__ import annotations

import math

from flipstudy.errors import WebImportError


def _num(v, where, key, lo=0.0, hi=math.inf, *, integer=False, optional=False):
    if v is None and optional:
        return None
    if isinstance(v, bool) or v is None:
        raise WebImportError(f"{where}: {key}: expected a number, got {v!r}")
    if isinstance(v, str):
        try:
            v = float(v)
        except ValueError:
            raise WebImportError(f"{where}: {key}: expected a number, got {v!r}") from None
    v = float(v)
    if not math.isfinite(v) or not lo <= v <= hi:
        raise WebImportError(f"{where}: {key}: {v:g} is outside {lo:g}..{hi:g}")
    if integer:
        if v != int(v):
            raise WebImportError(f"{where}: {key}: expected a whole number, got {v:g}")
        return int(v)
    return v


def _bool(v, where, key):
    if isinstance(v, bool):
        return v
    if isinstance(v, str) and v.lower() in ("true", "false"):
        return v.lower() == "true"
    raise WebImportError(f"{where}: {key}: expected true or false, got {v!r}")


def _str(v, where, key, options=None):
    if not isinstance(v, str) or not v:
        raise WebImportError(f"{where}: {key}: expected text, got {v!r}")
    if options is not None and v not in options:
        raise WebImportError(f"{where}: {key}: must be one of {', '.join(options)}, got {v!r}")
    return v


def _need(rec, where, keys):
    missing = [k for k in keys if k not in rec]
    if missing:
        raise WebImportError(f"{where}: missing field(s) {', '.join(missing)}")
