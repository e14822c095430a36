"""What ``--force`` may delete when a new stimulus set replaces a study folder: only
what a command made and recorded, never a file it did not write, at any depth.

A build owns ``manifest.csv``, ``design.toml`` and the stimulus files its manifest
lists (:func:`own_files`).  The caller's ``replace_check`` may name more files that
flipstudy commands made and recorded and that go with the old stimuli (render
outputs listed in ``render.json``, a database of simulated answers, …).  Every other
file below the old folder (``consent.md``, ``debrief.md``, ``analysis/``, a note in
``render/``) is *kept*: hard-linked (or copied) into the new build before the swap
(:func:`carry`), and after the swap the old folder loses only what it may lose
(:func:`discard_old`); anything that arrived meanwhile stays, in ``NAME.kept-PID``
beside the study.

Examples
--------
>>> import tempfile, pathlib
>>> tmp = pathlib.Path(tempfile.mkdtemp())
>>> old, new = tmp / "old", tmp / "new"
>>> (old / "analysis").mkdir(parents=True); new.mkdir()
>>> _ = (old / "manifest.csv").write_text("stimulus,bvh,npz\\n")
>>> _ = (old / "consent.md").write_text("I agree")
>>> _ = (old / "analysis" / "t.csv").write_text("x")
>>> kept_files(old, removable=())
['analysis/t.csv', 'consent.md']
>>> carry(old, new, kept_files(old, removable=()))
>>> sorted(p.relative_to(new).as_posix() for p in new.rglob("*") if p.is_file())
['analysis/t.csv', 'consent.md']
>>> discard_old(old, new, removable=()), old.exists()
([], False)
>>> import shutil; shutil.rmtree(tmp)
"""
from __future__ import annotations

import os
import shutil
from pathlib import Path

from flipstudy.errors import ManifestError, StudyFolderError

from .contract import StimulusSet

__all__ = ["BUILD_FILES", "own_files", "all_files", "kept_files", "carry", "discard_old"]

BUILD_FILES = ("manifest.csv", "design.toml")


def own_files(folder) -> set[str]:
    """What a build wrote into ``folder``: ``manifest.csv``, ``design.toml`` and the
    ``.bvh`` / ``.npz`` files its manifest lists (only the first two when the
    manifest does not read), and the locks folder ``.locks``."""
    ours = set(BUILD_FILES) | {".locks"}  # who serves or replaces the study: no data of it
    try:
        for r in StimulusSet.read(Path(folder), files=False, design=False):
            ours.update((str(r.bvh), str(r.npz)))
    except (OSError, ManifestError):
        pass
    return ours


def all_files(folder) -> list[str]:
    """Every file and symbolic link at any depth below ``folder`` (links to folders are
    not followed), as sorted relative POSIX names."""
    folder = Path(folder)
    out = []
    for top, dirs, files in os.walk(folder, followlinks=False):
        links = [d for d in dirs if os.path.islink(os.path.join(top, d))]
        dirs[:] = [d for d in dirs if d not in links]
        out += [(Path(top) / f).relative_to(folder).as_posix() for f in files + links]
    return sorted(out)


def _made(rel: str, names) -> bool:
    """``rel`` is one of ``names`` or below one of them (a recorded folder)."""
    return any(rel == n or rel.startswith(n.rstrip("/") + "/") for n in names)


def kept_files(folder, removable) -> list[str]:
    """The files below ``folder`` that a replacing build keeps: neither its own
    (:func:`own_files`) nor ``removable`` (recorded outputs the caller lets go)."""
    gone = own_files(folder) | set(removable)
    return [f for f in all_files(folder) if not _made(f, gone)]


def carry(old: Path, new: Path, names) -> None:
    """Put each of ``names`` (files below ``old``) at the same place below ``new``:
    a hard link (the same file, no copy), a copy where links are refused; symbolic
    links as links.  Refuses a name the new build wrote itself."""
    for rel in names:
        src, dst = old / rel, new / rel
        if dst.exists() or dst.is_symlink():
            raise StudyFolderError(f"{src}: the new build writes a file of this name; this file was "
                                   f"not made by a build, so it is not replaced: move it out first")
        dst.parent.mkdir(parents=True, exist_ok=True)
        if src.is_symlink():
            os.symlink(os.readlink(src), dst)
            continue
        try:
            os.link(src, dst, follow_symlinks=False)
        except OSError:
            shutil.copy2(src, dst)


def _same(a: Path, b: Path) -> bool:
    try:
        x, y = os.lstat(a), os.lstat(b)
    except OSError:
        return False
    if (x.st_ino, x.st_dev) == (y.st_ino, y.st_dev):
        return True
    try:                                  # a copy (no hard links here), or a link carried as a link
        if os.path.islink(a):
            return os.path.islink(b) and os.readlink(a) == os.readlink(b)
        return x.st_size == y.st_size and Path(a).read_bytes() == Path(b).read_bytes()
    except OSError:
        return False


def discard_old(old: Path, new: Path, removable) -> list[str]:
    """Delete from the swapped-out folder ``old`` only what may go: its build's own
    files, ``removable`` and what :func:`carry` put in ``new`` (the same file there).
    Whatever is left (a file that arrived after the carry) stays, the folder renamed to
    ``NAME.kept-PID`` beside ``new``; returns those names (``[]``: ``old`` is gone)."""
    gone = own_files(old) | set(removable)
    for top, dirs, files in os.walk(old, topdown=False, followlinks=False):
        for f in files + [d for d in dirs if os.path.islink(os.path.join(top, d))]:
            p = Path(top) / f
            rel = p.relative_to(old).as_posix()
            if _made(rel, gone) or _same(p, new / rel):
                p.unlink()
        for d in dirs:
            try:
                os.rmdir(os.path.join(top, d))
            except OSError:
                pass                      # not empty: something in it is kept
    try:
        os.rmdir(old)
        return []
    except OSError:
        left = all_files(old)
        keep = new.parent / f"{new.name}.kept-{os.getpid()}"
        os.rename(old, keep)
        return left
