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
``level`` 0.  With ``[study] task = "2afc"`` a row of every source but the first
has as its ``original`` the first source's row of the same item: the session
shows the two side by side in time (which comes first balanced within each
source and recorded, as for every 2AFC group) and asks which moved in a
physically possible way; the first source's rows are the comparisons, not
trials.  With ``task = "yes-no"`` every row is a trial of its own.

An item missing in one source's folder (or a folder without clips) is a
:class:`SourceMismatchError` naming the folder and the item.

>>> from flipstudy.stimuli.compare import stimulus_name
>>> stimulus_name("88_01", "gt")
'88_01_gt'
"""
from __future__ import annotations

import hashlib
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from flipstudy.errors import SourceMismatchError

from .analyse import analyse
from .design import GIVEN_KIND, Design, DesignError, SourceSpec
from .exceptions import FlipstudyFileNotFoundError
from .motion.bvh import bvh_text

#: the file suffixes of a source folder read as clips: those the loading rule reads
#: (BVH today; joint-position and AMASS readers add theirs to ``loading.CLIP_SUFFIXES``)
DEFAULT_SUFFIXES = (".bvh",)


def clip_suffixes() -> tuple[str, ...]:
    from . import loading
    return tuple(getattr(loading, "CLIP_SUFFIXES", DEFAULT_SUFFIXES))


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
    names = [stimulus_name(i, s.name) for i in items for s in design.sources]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise SourceMismatchError(f"{where}item and source names give the stimulus name {dup[0]!r} twice; "
                                  f"rename a source")
    return {i: {s.name: found[s.name][i] for s in design.sources} for i in items}


def load_source_clip(design: Design, s: SourceSpec, item: str, path: Path):
    """One given clip through the loading rule, resampled to ``[study] fps`` when the
    design writes it, its analysis after the physics gate."""
    from .loading import load_clip
    from .stimset import physics_gate, resample
    clip = load_clip(str(path), scale=s.scale, fps=s.fps)
    if design.fps_given and abs(clip.fps - design.fps) > 1e-9 * design.fps:
        clip = resample(clip, design.fps)
    clip.meta["name"] = item
    a = analyse(clip, total_mass=design.total_mass)
    spec = SimpleNamespace(name=f"{item} of source {s.name}", source=str(path), scale=s.scale,
                           accept_unphysical=s.accept_unphysical)
    try:
        physics_gate(spec, a, design)
    except DesignError as e:
        raise DesignError(str(e).replace("[[clips]] entry", f"[[sources]] entry '{s.name}'")) from None
    return a


def plan_comparison(design: Design) -> list[tuple]:
    """(stimulus, item, source, file, original) of every stimulus, in manifest order:
    item by item, sources in the design's order."""
    first = design.sources[0].name
    rows = []
    for item, files in match_items(design).items():
        for s in design.sources:
            orig = stimulus_name(item, first) if design.task == "2afc" and s.name != first else ""
            rows.append((stimulus_name(item, s.name), item, s, files[s.name], orig))
    return rows


def make_given_stimulus(design: Design, a, item: tuple, folder) -> dict:
    """Write one given clip (``item`` of :func:`plan_comparison`) as ``.bvh`` and
    ``.npz`` into ``folder``; its manifest row (measured like a reference motion
    when it has a flight; NaN measures when it has none)."""
    from .stimset import clip_arrays, derived_seed, make_stimulus, npz_bytes
    name, it, s, path, orig = item
    spec = SimpleNamespace(name=it, accept_unphysical=s.accept_unphysical)
    if a.flight is not None:
        row = make_stimulus(design, a, (name, spec, None, 0.0), folder)
    else:
        data = bvh_text(a.clip, 1.0).encode()
        (Path(folder) / f"{name}.bvh").write_bytes(data)
        (Path(folder) / f"{name}.npz").write_bytes(npz_bytes(clip_arrays(a.clip, 0, 0)))
        row = {"stimulus": name, "clip": it, "level": 0.0, "takeoff": 0, "landing": 0,
               "seed": derived_seed(design.seed, name), "sha256": hashlib.sha256(data).hexdigest(),
               "frames": a.clip.num_frames, "fps": a.clip.fps, "bvh": f"{name}.bvh", "npz": f"{name}.npz",
               "accept_unphysical": bool(s.accept_unphysical),
               **({"style": design.style or "ellipsoids"} if design.styled else {})}
        row.update({k: np.nan for k in ("takeoff_angle_deg", "flight_s", "jump_height_m", "jump_length_m",
                                        "takeoff_time", "landing_time")})
    row.update(group=s.name, kind=GIVEN_KIND, profile="", original=orig, source=s.name)
    return row


def build_comparison(design: Design, tmp: Path, bar=None) -> list[dict]:
    """The rows of a comparison design's stimuli, written into ``tmp`` (the build's
    staging folder; :func:`flipstudy.stimuli.stimset.build_stimuli` installs it)."""
    rows = []
    for item in plan_comparison(design):
        a = load_source_clip(design, item[2], item[1], item[3])
        rows.append(make_given_stimulus(design, a, item, tmp))
        if bar is not None:
            bar.step(item[0])
    return rows


__all__ = ["SourceMismatchError", "match_items", "plan_comparison", "build_comparison", "stimulus_name",
           "source_clips", "source_folder", "GIVEN_KIND"]
