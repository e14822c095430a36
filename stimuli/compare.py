"""Studies that compare given motions: the stimuli of a design with ``[[sources]]``.

A comparison design (:class:`flipstudy.stimuli.design.Design` with ``sources``)
names folders of clips — the ground truth, model A, model B — and the clips of
different sources are the same *item* when their file stems are equal
(``gt/88_01.bvh`` and ``modelA/88_01.bvh``).  Every clip is read by the one
loading rule of every command that takes a CLIP
(:func:`flipstudy.stimuli.loading.load_clip`, with the source's ``scale`` and
``fps``), resampled to ``[study] fps`` when the design writes one, and passes the
same physics gate as a design's base clips.

The manifest holds one row per item and source: stimulus ``ITEM_SOURCE``,
``clip`` = the item (so the renderer fits one camera per item, over all its
sources), ``group`` = ``source`` = the source's name, ``kind`` = ``given``,
``level`` 0.  Error ``[[groups]]`` are injected into every source's clip of every
item (``ITEM_SOURCE_GROUP_LEVEL``, ``source`` the source's, ``original`` the
source's clip as given: their level 0), judged with the study's task.  ``[study] compare = "all"`` adds, per item, the
pairs of sources other than the first (``ITEM_B-vs-A``: B's clip written again,
group ``B-vs-A``, beside A's clip), so every pair of sources is compared directly.  With ``[study] task = "2afc"`` a row of every source but the first
has as its ``original`` the first source's row of the same item: the session
shows the two side by side in time (which comes first balanced within each
source and recorded, as for every 2AFC group) and asks which moved in a
physically possible way; the first source's rows are the comparisons, not
trials.  With ``task = "yes-no"`` every row is a trial of its own.

The build (:func:`flipstudy.stimuli.stimset.build_stimuli`) reads each clip
(:func:`flipstudy.stimuli.stimset.load_source_clip`) and writes it as a stimulus
(:func:`flipstudy.stimuli.stimset.make_given_stimulus`), staged and installed like
every build.  An item missing in one source's folder (or a folder without clips) is a
:class:`SourceMismatchError` naming the folder and the item.

>>> from flipstudy.stimuli.compare import stimulus_name
>>> stimulus_name("88_01", "gt")
'88_01_gt'
"""
from __future__ import annotations

from pathlib import Path

from flipstudy.errors import FlipstudyFileNotFoundError, SourceMismatchError

from ._sourcelimits import check_items
from .design import GIVEN_KIND, Design, SourceSpec, pair_group

def clip_suffixes() -> tuple[str, ...]:
    from .loading import POSITION_SUFFIXES
    return tuple(dict.fromkeys((".bvh", *POSITION_SUFFIXES)))


def stimulus_name(item: str, source: str) -> str:
    """The stimulus of ``item`` as ``source`` gives it."""
    return f"{item}_{source}"


def source_folder(design: Design, s: SourceSpec) -> Path:
    """A source's folder (relative to the design file)."""
    p = Path(s.folder)
    if not p.is_absolute() and design.path is not None:
        p = design.path.parent / p
    return p


def source_clips(design: Design, s: SourceSpec) -> dict[str, Path]:
    """Item (file stem) → file of one source's folder, sorted by item."""
    folder = source_folder(design, s)
    where = f"{design.path}: " if design.path is not None else ""
    if not folder.is_dir():
        raise FlipstudyFileNotFoundError(f"{where}sources '{s.name}': folder {folder} does not exist")
    suffixes = clip_suffixes()
    out: dict[str, Path] = {}
    for f in sorted(folder.iterdir()):
        if f.suffix.lower() not in suffixes or not f.is_file():
            continue
        if f.stem in out:
            raise SourceMismatchError(f"{where}sources '{s.name}': folder {folder} holds item "
                                      f"{f.stem!r} twice ({out[f.stem].name} and {f.name}); keep one")
        out[f.stem] = f
    if not out:
        raise SourceMismatchError(f"{where}sources '{s.name}': folder {folder} holds no clip "
                                  f"({', '.join(suffixes)})")
    return out


def match_items(design: Design) -> dict[str, dict[str, Path]]:
    """Item → {source name → file}, items sorted; every source must hold every item
    (else :class:`SourceMismatchError` naming the folder that lacks one and where it is)."""
    found = {s.name: source_clips(design, s) for s in design.sources}
    items = sorted(set().union(*found.values()))
    where = f"{design.path}: " if design.path is not None else ""
    for s in design.sources:
        missing = [i for i in items if i not in found[s.name]]
        if missing:
            other = next(o for o in design.sources if missing[0] in found[o.name])
            raise SourceMismatchError(
                f"{where}sources '{s.name}': folder {source_folder(design, s)} has no clip for item "
                f"{missing[0]!r} (found in '{other.name}': {found[other.name][missing[0]]})"
                + (f" and {len(missing) - 1} more" if len(missing) > 1 else "")
                + "; every source holds the same items, matched by file name")
    return {i: {s.name: found[s.name][i] for s in design.sources} for i in items}


def plan_comparison(design: Design) -> list[tuple]:
    """(stimulus, item, source, file, original, group, level) of every stimulus, in
    manifest order: item by item, sources in the design's order, each source's clip as
    given (group None, level 0) followed by its error groups' levels other than 0
    (``ITEM_SOURCE_GROUP_LEVEL``, their original the source's clip as given); with
    ``compare = "all"`` then the pairs without the first source (``ITEM_B-vs-A``: B's
    clip again, in the pair's group, beside A's)."""
    first = design.sources[0].name
    by = {x.name: x for x in design.sources}
    groups = {g.name: g for g in design.groups}
    rows = []
    items = match_items(design)
    check_items(design, items, f"{design.path}: " if design.path is not None else "")
    for item, files in items.items():
        for s in design.sources:
            given = stimulus_name(item, s.name)
            orig = stimulus_name(item, first) if design.task == "2afc" and s.name != first else ""
            rows.append((given, item, s, files[s.name], orig, None, 0.0))
            for g in design.error_groups:
                rows += [(f"{given}_{g.name}_{lv:g}", item, s, files[s.name], given, g, lv)
                         for lv in g.levels if lv != 0]
        for a, b in design.source_pairs():      # compare = "all": b's clip again, beside a's
            if a != first:
                g = groups[pair_group(b, a)]
                rows.append((stimulus_name(item, g.name), item, by[b], files[b], stimulus_name(item, a), g, 0.0))
    names = [r[0] for r in rows]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        where = f"{design.path}: " if design.path is not None else ""
        raise SourceMismatchError(f"{where}item, source and group names give the stimulus name {dup[0]!r} "
                                  f"twice; rename a source or group")
    return rows


__all__ = ["SourceMismatchError", "match_items", "plan_comparison", "stimulus_name",
           "source_clips", "source_folder", "GIVEN_KIND"]
