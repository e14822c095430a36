"""The base of the editing methods' typed reports."""
from __future__ import annotations

from dataclasses import asdict


class Report:
    """A typed report (a dataclass); :meth:`to_dict` gives its JSON keys, nested
    reports as dicts."""

    def to_dict(self) -> dict:
        return asdict(self)
