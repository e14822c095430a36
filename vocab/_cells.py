"""Typed manifest cells: how a :mod:`flipstudy.vocab.contract` record coerces a value,
parses a cell and formats it (the machinery of ``Stimulus`` and ``Ballistic``)."""
from __future__ import annotations

import math
import operator
from dataclasses import fields
from pathlib import PurePosixPath
from typing import Mapping

import numpy as np

from flipstudy.errors import ManifestError


def _fmt_float(v: float) -> str:
    if not math.isfinite(v):
        return "nan"
    s = f"{v:.6f}"
    return "0.000000" if s == "-0.000000" else s


class _Typed:
    """Per field type: coerce a value, parse a manifest cell, format a cell."""

    @staticmethod
    def coerce(kind, v, name):
        if kind is float:
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
                raise TypeError(f"{name}: expected a number, got {v!r}")
            return float(v)
        if kind is int:
            if isinstance(v, (bool, np.bool_)):
                raise TypeError(f"{name}: expected an integer, got {v!r}")
            return int(operator.index(v))
        if kind is bool:
            if not isinstance(v, (bool, np.bool_)):
                raise TypeError(f"{name}: expected true or false, got {v!r}")
            return bool(v)
        if kind is PurePosixPath:
            p = PurePosixPath(v)
            if not str(v) or p.is_absolute() or ".." in p.parts or str(p) != str(v):
                raise TypeError(f"{name}: expected a file name inside the study folder, got {v!r}")
            return p
        if not isinstance(v, str):
            raise TypeError(f"{name}: expected text, got {v!r}")
        if any(c in v for c in "\r\n\x00"):            # a manifest cell is one line
            raise TypeError(f"{name}: expected one line of text, got {v!r}")
        return v

    @staticmethod
    def parse(kind, text: str):
        if kind is float:
            v = float(text)                     # "nan" is a missing value
            if math.isinf(v):
                raise ValueError(text)
            return v
        if kind is int:
            return int(text)
        if kind is bool:
            if text not in ("true", "false"):
                raise ValueError(text)
            return text == "true"
        if kind is PurePosixPath:
            return PurePosixPath(text) if text else text
        return text

    @staticmethod
    def format(kind, v) -> str:
        if kind is float:
            return _fmt_float(v)
        if kind is bool:
            return "true" if v else "false"
        return str(v)


_WORD = {float: "a number", int: "an integer", bool: "true or false",
         PurePosixPath: "a file name inside the study folder", str: "text"}


def _same(a, b) -> bool:
    return a == b or (isinstance(a, float) and isinstance(b, float) and a != a and b != b)


#: the annotation of a manifest column → its type (other fields are not columns)
_COLUMN_TYPES = {"str": str, "float": float, "int": int, "bool": bool, "PurePosixPath": PurePosixPath}


class _Record:
    """Typed, frozen manifest columns: coercion on construction, NaN-aware equality.
    A field is a column when its annotation is one of :data:`_COLUMN_TYPES`."""

    _types: dict = {}

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        cls._types = {n: _COLUMN_TYPES[a] for n, a in cls.__annotations__.items() if a in _COLUMN_TYPES}

    def __post_init__(self):
        for f in fields(self):
            t = self._types.get(f.name)
            if t is None:
                continue
            v = getattr(self, f.name)
            if v is None and f.name in ("bvh", "npz"):
                v = f"{self.stimulus}.{f.name}"
            object.__setattr__(self, f.name, _Typed.coerce(t, v, f.name))

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        return all(_same(getattr(self, f.name), getattr(other, f.name)) for f in fields(self))

    def __hash__(self):
        return hash(tuple(getattr(self, f.name) for f in fields(self)
                          if not isinstance(getattr(self, f.name), float)))

    @classmethod
    def columns(cls) -> list[str]:
        return [f.name for f in fields(cls) if f.name in cls._types]

    def cells(self) -> list[str]:
        """The manifest cells of these columns."""
        return [_Typed.format(self._types[c], getattr(self, c)) for c in self.columns()]

    @classmethod
    def parse(cls, row: Mapping[str, str], where, **extra):
        """From manifest cells (strings); a bad cell raises :class:`ManifestError`
        naming ``where`` (file and line) and the column."""
        vals = {}
        for c in cls.columns():
            t = cls._types[c]
            text = row.get(c)
            if text is None:                    # an older manifest without this column
                if t is float:
                    vals[c] = math.nan          # not measured by the build that wrote it
                continue
            try:
                vals[c] = _Typed.parse(t, text)
            except ValueError:
                raise ManifestError(f"{where}, column {c!r}: {text!r} is not {_WORD[t]}") from None
        try:
            return cls(**vals, **extra)
        except TypeError as e:
            raise ManifestError(f"{where}, column {e}") from None
