"""Limits of a comparison design (``[[sources]]``): how many sources, how many
stimuli it would build, folders told apart after normalising their paths, and item
names (the clips' file stems) that can name stimulus files.

Every check runs before anything is built, and each refusal names the number the
design would build:

* at most :data:`MAX_SOURCES` sources;
* the stimuli of one item (each source's clip, its error levels, and with
  ``compare = "all"`` the pairs without the first source) times ``repetitions``
  within :data:`~flipstudy.stimuli._designkeys.TRIALS_MAX` trials per participant, first
  for one item (when the design is read) and then for the items the folders hold
  (when it is built), so a design ``run`` would refuse is never built.

>>> stimuli_per_item(3, [2], "all")
10
"""
from __future__ import annotations

import os
from pathlib import Path

from flipstudy.errors import DesignError
from ._designkeys import TRIALS_MAX, _name_ok

#: Sources a comparison design may name (ground truth and models).
MAX_SOURCES = 64


def stimuli_per_item(n_sources: int, error_levels, compare: str, task: str = "2afc") -> int:
    """Stimuli one item gives: each source's clip and its ``error_levels`` (the
    number of levels other than 0 of each error group), plus, with ``compare =
    "all"`` in 2AFC, the pairs of sources other than the first."""
    per_source = 1 + sum(error_levels)
    pairs = (n_sources - 1) * (n_sources - 2) // 2 if compare == "all" and task == "2afc" else 0
    return n_sources * per_source + pairs


def _count_text(design, n_items: int | None = None) -> tuple[int, str]:
    S = len(design.sources)
    levels = [sum(1 for lv in g.levels if lv != 0) for g in design.error_groups]
    per = stimuli_per_item(S, levels, design.compare, design.task)
    pairs = per - S * (1 + sum(levels))
    what = f"{S} sources" + (f" × {1 + sum(levels)} (the clip and {sum(levels)} error levels)" if sum(levels) else "") \
        + (f" + {pairs:,} pairs (compare = \"all\")" if pairs else "")
    return per, what


def check_sources(design, src: str) -> None:
    """Refuse a comparison design beyond :data:`MAX_SOURCES` sources, whose one item
    alone would exceed the trials of a session, or whose folders are one folder
    written twice (``gt``, ``gt/``, ``./gt``)."""
    S = len(design.sources)
    per, what = _count_text(design)
    if S > MAX_SOURCES:
        raise DesignError(f"{src}: [[sources]]: {S:,} sources, at most {MAX_SOURCES} (they would build "
                          f"{per:,} stimuli per item: {what})")
    if per * design.repetitions > TRIALS_MAX:
        raise DesignError(f"{src}: [[sources]]: {what} = {per:,} stimuli per item, × repetitions "
                          f"{design.repetitions} = {per * design.repetitions:,} trials per participant "
                          f"with a single item; at most {TRIALS_MAX} (fewer sources, error levels or "
                          f"repetitions, or compare = \"first\")")
    for what_, key in (("name", lambda x: x.name), ("folder", lambda x: _folder_key(design, x.folder))):
        vals = [key(x) for x in design.sources]
        if len(set(vals)) != len(vals):
            dup = sorted({x.name if what_ == "name" else x.folder for x, v in zip(design.sources, vals)
                          if vals.count(v) > 1})
            raise DesignError(f"{src}: [[sources]]: duplicate source {what_}s {dup}"
                              + (" (one folder, written differently)" if what_ == "folder" else ""))


def _folder_key(design, folder: str) -> str:
    """A source folder as a normalised path (relative to the design file when it has one)."""
    p = Path(folder)
    if not p.is_absolute() and design.path is not None:
        p = Path(design.path).parent / p
    return os.path.normcase(os.path.normpath(os.path.abspath(p) if design.path is not None else str(p)))


def check_items(design, items, where: str) -> None:
    """Refuse, before building, item names (file stems) that cannot name a stimulus
    file, and more stimuli than a session may show (naming the number)."""
    for item, files in items.items():
        msg = _name_ok(item)
        if msg:
            f = next(iter(files.values()))
            shown = item if len(item) <= 40 else item[:37] + "..."
            raise DesignError(f"{f}: the item name {shown!r} (the file's name without its suffix) {msg}; "
                              f"rename the file in every source folder")
    per, what = _count_text(design)
    n = len(items) * per
    if n * design.repetitions > TRIALS_MAX:
        raise DesignError(f"{where}[[sources]]: {len(items):,} items × {per:,} stimuli per item ({what}) would "
                          f"build {n:,} stimuli, × repetitions {design.repetitions} = "
                          f"{n * design.repetitions:,} trials per participant; at most {TRIALS_MAX} (fewer "
                          f"items, sources, error levels or repetitions)")


__all__ = ["MAX_SOURCES", "stimuli_per_item", "check_sources", "check_items"]
