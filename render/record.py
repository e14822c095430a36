"""The render record: ``STUDY/render/render.json``, the outputs' hashes, and the check.

``render.json`` records, for every output of :func:`flipstudy.render.study.render_study`,
what it was made from (the stimulus's sha256, its placement, the settings that
change pixels, the library versions) and the file's size and sha256; a rerun
makes only what is missing or stale.  :func:`check_rendered` is what
``flipstudy run`` asks before serving the videos.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from flipstudy.errors import StaleRenderError, StudyRenderError
from flipstudy.stimuli.contract import StimulusSet, file_sha256

#: What ``--what`` can ask for, and the file each writes (``{s}`` = stimulus).
RENDER_KINDS = {
    "video": "{s}.mp4",
    "ghost": "{s}_ghost.png",
    "trail": "{s}_trail.png",
    "strip": "{s}_strip.png",
    "composite": "{s}_composite.png",
    "overlay": "{s}_overlay.png",     # the stimulus over its clip's reference (level 0)
}




def versions() -> dict:
    """Versions of what renders (recorded in render.json)."""
    import imageio_ffmpeg
    import OpenImageIO as oiio
    # the one VTK module pyvista has loaded already: `import vtk` would load all of
    # VTK's Python modules, about a CPU-second in every render worker
    from vtkmodules.vtkCommonCore import vtkVersion

    from ._pv import pv
    try:
        from importlib.metadata import version
        fs = version("flipstudy")
    except Exception:  # noqa: BLE001 — not installed
        fs = None
    try:
        ff = imageio_ffmpeg.get_ffmpeg_version()
    except Exception:  # noqa: BLE001
        ff = None
    return {"flipstudy": fs, "python": sys.version.split()[0], "numpy": np.__version__,
            "pyvista": pv.__version__, "vtk": vtkVersion.GetVTKVersion(),
            "openimageio": oiio.__version__, "imageio_ffmpeg": imageio_ffmpeg.__version__,
            "ffmpeg": ff}


def canonical_id(obj) -> str:
    """A short id (16 hex digits) of a JSON-serialisable value, independent of key order."""
    import hashlib
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()[:16]


def read_record(out_dir) -> dict | None:
    """``render.json`` of a render folder (None if there is none)."""
    p = Path(out_dir) / "render.json"
    if not p.is_file():
        return None
    try:
        return json.loads(p.read_text())
    except (OSError, ValueError) as e:
        raise StudyRenderError(f"{p}: not readable as JSON ({e}); delete it to re-render "
                               f"everything") from None


def up_to_date(out: Path, fname: str, have: dict | None, want: dict) -> bool:
    """Whether ``out/fname`` is the output recorded as ``have`` and that record
    says it was made as ``want`` says (same stimulus, settings, placement)."""
    if not have or {k: v for k, v in have.items() if k not in ("bytes", "sha256", "renderer")} != want:
        return False
    f = out / fname
    try:
        if f.stat().st_size != have.get("bytes"):
            return False
    except OSError:
        return False
    if want.get("frames") and not (out / "frames" / want["stimulus"]).is_dir():
        return False
    return file_sha256(f) == have.get("sha256")


def write_record(out: Path, rec: dict) -> dict:
    """Write ``rec`` as ``out/render.json`` atomically (a temporary file renamed)."""
    tmp = out / ".render.json.tmp"
    tmp.write_text(json.dumps(rec, indent=2) + "\n")
    tmp.replace(out / "render.json")
    return rec


def check_rendered(stimuli, kind: str = "video", hash_files: bool = True) -> dict:
    """Check that every stimulus of a study (a :class:`~flipstudy.stimuli.contract.StimulusSet`,
    or its folder) has its ``kind`` output, made from the stimulus as it is now,
    intact, and all with one settings record.  Returns that settings record;
    raises :class:`StaleRenderError` naming the offending files and the fix.

    Parameters
    ----------
    stimuli : StimulusSet or str or pathlib.Path
    kind : str
        The output to check (``video``, ``ghost``, ...).
    hash_files : bool
        Check each file's sha256 too (not only its size).

    Returns
    -------
    dict

    Raises
    ------
    StaleRenderError

    Examples
    --------
    >>> import tempfile
    >>> from flipstudy.errors import StaleRenderError
    >>> from flipstudy.render import check_rendered
    >>> from flipstudy.stimuli import Stimulus, StimulusSet
    >>> from flipstudy.vocab.kinds import AM
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     s = StimulusSet(tmp, [Stimulus("bf_0", "backflip", "original", AM.name)])
    ...     try:
    ...         check_rendered(s)
    ...     except StaleRenderError as e:
    ...         print("flipstudy render" in str(e))
    True
    """
    if not isinstance(stimuli, StimulusSet):
        stimuli = StimulusSet.read(stimuli, files=False, design=False)
    study_dir = stimuli.folder
    out = study_dir / "render"
    rows = stimuli.stimuli
    fix = f"run `flipstudy render {study_dir}` to bring them up to date"
    rec = read_record(out)
    if rec is None or "outputs" not in rec:
        what = "no render.json" if rec is None else "render.json without per-output records " \
                                                     "(an older flipstudy made it)"
        raise StaleRenderError(f"{out}: {what}, so nothing says what the videos were made from; "
                               f"{fix}")
    outputs = rec["outputs"]
    problems, by_settings = [], {}
    for i, r in enumerate(rows, start=2):
        name = r.stimulus
        fname = RENDER_KINDS[kind].format(s=name)
        o_ = outputs.get(fname)
        f = out / fname
        if not f.is_file():
            problems.append(f"{fname}: missing")
            continue
        if not isinstance(o_, dict) or o_.get("kind") != kind:
            problems.append(f"{fname}: not recorded in render.json (made by something else, or "
                            f"by a render that was interrupted)")
            continue
        want = r.sha256.strip().lower()
        if not want:
            p = stimuli.path(r)
            want = file_sha256(p) if p.is_file() else ""
        if o_.get("stimulus_sha256") != want:
            problems.append(f"{fname}: made from another version of stimulus {name!r} "
                            f"(manifest.csv line {i})")
            continue
        if f.stat().st_size != o_.get("bytes") or (hash_files and file_sha256(f) != o_.get("sha256")):
            problems.append(f"{fname}: the file differs from the one render.json records "
                            f"(changed or half-written)")
            continue
        by_settings.setdefault(o_.get("settings"), []).append(fname)
    if len(by_settings) > 1:
        recs = rec.get("settings_records") or {}
        groups = sorted(by_settings.items(), key=lambda kv: -len(kv[1]))

        def describe(k):
            s = recs.get(k) or {}
            if not s:
                return f"settings {k}"
            return f"{s['size'][0]}x{s['size'][1]} at {s['fps']:g} fps (settings {k})"
        for k, files in groups[1:]:
            problems.append(f"{', '.join(files[:4])}{' …' if len(files) > 4 else ''}: "
                            f"{len(files)} made with {describe(k)}, the other "
                            f"{sum(len(v) for kk, v in groups if kk != k)} with "
                            f"{describe(groups[0][0])}")
    if problems:
        n = len(problems)
        raise StaleRenderError(f"{out}: {n} problem{'s' if n > 1 else ''} with the {kind}s: "
                               + "; ".join(problems[:6]) + (" …" if n > 6 else "") + f"; {fix}")
    ((sid, _),) = by_settings.items() if by_settings else ((None, None),)
    return (rec.get("settings_records") or {}).get(sid) or {}


__all__ = ["RENDER_KINDS", "StudyRenderError", "StaleRenderError", "file_sha256", "versions",
           "canonical_id", "read_record", "write_record", "up_to_date",
           "check_rendered"]
