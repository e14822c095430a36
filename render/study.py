"""Rendering a whole stimulus set: one style, one camera, one take-off spot.

:func:`render_study` reads ``STUDY_DIR/manifest.csv``, loads every stimulus
(``STUDY_DIR/<stimulus>.bvh``, metres, the header's frame rate), places all of
them with :func:`render.camera.stage` (take-off COM at the origin, one camera
fitted to every frame of every stimulus, one ground), and renders the chosen
outputs in parallel worker processes — each worker builds its offscreen
plotter once and reuses it for all its stimuli.  Outputs go to
``STUDY_DIR/render/`` and the settings (camera, style, size, fps, versions,
per-stimulus offsets and files) to ``STUDY_DIR/render/render.json``.
"""
from __future__ import annotations

from stimuli.exceptions import FlipstudyValueError

from stimuli.exceptions import FlipstudyError
import json
import math
import multiprocessing as mp
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

import numpy as np

#: What ``--what`` can ask for, and the file each writes (``{s}`` = stimulus).
RENDER_KINDS = {
    "video": "{s}.mp4",
    "ghost": "{s}_ghost.png",
    "trail": "{s}_trail.png",
    "strip": "{s}_strip.png",
    "composite": "{s}_composite.png",
    "overlay": "{s}_overlay.png",     # the stimulus over its clip's reference (level 0)
}


class StudyRenderError(FlipstudyError, ValueError):
    pass


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` → (640, 480)."""
    try:
        w, h = (int(v) for v in str(text).lower().split("x"))
    except ValueError:
        raise FlipstudyValueError(f"size {text!r}: expected WIDTHxHEIGHT, e.g. 640x480") from None
    if w < 16 or h < 16:
        raise FlipstudyValueError(f"size {text!r}: width and height must be at least 16 pixels")
    return w, h


def parse_what(text) -> list[str]:
    items = [w.strip() for w in (text.split(",") if isinstance(text, str) else text) if w.strip()]
    bad = [w for w in items if w not in RENDER_KINDS]
    if bad or not items:
        raise FlipstudyValueError(f"--what {text!r}: choose from {', '.join(RENDER_KINDS)} (comma-separated)")
    return items


def _int_or_none(v):
    if v is None:
        return None
    v = str(v).strip()
    if v in ("", "nan", "None", "none"):
        return None
    return int(float(v))


def _skeleton_key(sk) -> tuple:
    return (tuple(sk.joint_names), np.round(sk.offsets, 9).tobytes(),
            tuple((p, np.round(o, 9).tobytes()) for p, o in sk.end_sites))


class _Bodies:
    """One table Body per distinct skeleton (stimuli of one base clip share it)."""

    def __init__(self):
        self._cache: dict = {}

    def __call__(self, clip):
        """The body of ``clip``'s skeleton, measured on the first clip seen with it."""
        from stimuli.body import Body
        k = _skeleton_key(clip.skeleton)
        if k not in self._cache:
            self._cache[k] = Body.from_clip(clip)
        return self._cache[k]


def load_stimuli(study_dir) -> tuple[list[dict], list]:
    """Manifest rows and their clips (BVH in metres, the header's frame rate)."""
    from stimuli import load_bvh
    from stimuli.stimset import read_manifest
    study_dir = Path(study_dir)
    rows = read_manifest(study_dir)
    if not rows:
        raise StudyRenderError(f"{study_dir / 'manifest.csv'}: no stimuli")
    for col in ("stimulus", "takeoff", "landing"):
        if col not in rows[0]:
            raise StudyRenderError(f"{study_dir / 'manifest.csv'}: no column {col!r} "
                                   f"(columns: {', '.join(rows[0])})")
    clips = []
    for i, r in enumerate(rows, start=2):
        name = r["stimulus"]
        p = study_dir / (r.get("bvh") or f"{name}.bvh")
        if not p.exists():
            raise StudyRenderError(f"{study_dir / 'manifest.csv'} line {i}: stimulus {name!r}: "
                                   f"no file {p}")
        clip = load_bvh(p, scale=1.0)
        clip.meta["name"] = name
        clips.append(clip)
    return rows, clips


# ---------------------------------------------------------------- worker side
_WORKER: dict = {}


def _init_worker(settings: dict) -> None:
    """Build the worker's one scene (plotter) from plain data."""
    from .camera import Camera
    from .scene import Scene
    from .style import Style
    style = Style.from_dict(settings["style"])
    _WORKER.clear()
    _WORKER["settings"] = settings
    _WORKER["style"] = style
    _WORKER["camera"] = Camera.from_dict(settings["camera"])
    _WORKER["scene"] = Scene(None, style, tuple(settings["size"]), _WORKER["camera"],
                             tuple(settings["ground_bounds"]))


def _close_worker() -> None:
    sc = _WORKER.pop("scene", None)
    if sc is not None:
        sc.close()


def _load_placed(path: str, offset, yaw: float = 0.0):
    from stimuli import load_bvh

    from .camera import place
    return place(load_bvh(path, scale=1.0), offset, yaw)


def _render_task(task: dict) -> dict:
    """Render every requested output of one stimulus in this worker's scene."""
    from . import figures as fg
    t_start = time.perf_counter()
    st = _WORKER["settings"]
    scene = _WORKER["scene"]
    cam = _WORKER["camera"]
    gb = tuple(st["ground_bounds"])
    size = tuple(st["size"])
    clip = _load_placed(task["bvh"], task["offset"], task["yaw"])
    body = task["body"]            # measured once in the parent: the same in every worker
    out = Path(st["out"])
    common = dict(camera=cam, body=body, takeoff=task["takeoff"], landing=task["landing"],
                  scene=scene, ground_bounds=gb)
    files = {}
    name = task["stimulus"]
    for kind in task["what"]:
        f = out / RENDER_KINDS[kind].format(s=name)
        if kind == "video":
            fd = out / "frames" / name if st.get("frames") else None
            fg.render_video(clip, f, fps=st["fps"], size=size, frames_dir=fd, **common)
        elif kind == "ghost":
            fg.ghost_image(clip, f, size=size, **common)
        elif kind == "trail":
            fg.trail_image(clip, f, size=size, **common)
        elif kind == "strip":
            ph = max(120, 2 * (size[1] // 4))             # panels half the image height
            fg.strip_image(clip, f, panel_size=(2 * int(round(ph * 0.35)), ph), **common)
        elif kind == "composite":
            fg.composite_image(clip, f, size=size, **common)
        elif kind == "overlay":
            if not task.get("reference"):
                continue
            ref = _load_placed(task["reference"]["bvh"], task["reference"]["offset"],
                               task["reference"]["yaw"])
            fg.overlay_image(ref, clip, f, size=size, labels=("original", name), **common)
        files[kind] = f.name
    return {"stimulus": name, "files": files, "seconds": round(time.perf_counter() - t_start, 3)}


def _run_local(settings: dict, tasks: list, bar) -> list:
    _init_worker(settings)
    try:
        out = []
        for t in tasks:
            out.append(_render_task(t))
            bar.step(t["stimulus"])
        return out
    finally:
        _close_worker()


# ------------------------------------------------------------------ progress
class Progress:
    """A plain stderr progress bar (no dependency)."""

    def __init__(self, total: int, label: str = "render", enabled: bool = True, stream=None):
        self.total, self.label, self.enabled = int(total), label, enabled
        self.n = 0
        self.t0 = time.perf_counter()
        self.stream = stream or sys.stderr

    def step(self, what: str = "") -> None:
        self.n += 1
        if not self.enabled:
            return
        tty = self.stream.isatty()
        done = self.n >= self.total
        if not tty and not (done or self.n % max(1, self.total // 10) == 0):
            return
        el = time.perf_counter() - self.t0
        eta = el / self.n * (self.total - self.n)
        w = 28
        k = int(w * self.n / max(self.total, 1))
        line = (f"{self.label} [{'#' * k}{'.' * (w - k)}] {self.n}/{self.total} "
                f"{el:6.1f} s, eta {eta:5.1f} s {what[:32]}")
        self.stream.write(f"\r{line:<90}" + ("\n" if done else "") if tty else line + "\n")
        self.stream.flush()


def versions() -> dict:
    """Versions of what renders (recorded in render.json)."""
    import imageio_ffmpeg
    import OpenImageIO as oiio
    import vtk

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
            "pyvista": pv.__version__, "vtk": vtk.vtkVersion.GetVTKVersion(),
            "openimageio": oiio.__version__, "imageio_ffmpeg": imageio_ffmpeg.__version__,
            "ffmpeg": ff}


def render_study(study_dir, what=("video",), size=(640, 480), jobs: int | None = None,
                 fps: float = 60.0, style=None, out=None, frames: bool = False,
                 progress: bool = True, orient: bool = True) -> dict:
    """Render the stimuli of a study with one style, one camera and one take-off
    spot; returns (and writes to ``render/render.json``) the settings.  With
    ``orient`` base clips that travel in other directions are turned about the
    vertical to travel like the first one (see :func:`render.camera.stage`).

    Example
    -------
    >>> render_study("study/", what=("video", "ghost"), size=(640, 480), jobs=2)   # doctest: +SKIP
    """
    from .camera import stage
    from .style import Style
    study_dir = Path(study_dir)
    what = parse_what(what)
    size = (int(size[0]), int(size[1]))
    if "video" in what and (size[0] % 2 or size[1] % 2):
        raise StudyRenderError(f"size {size[0]}x{size[1]}: video needs an even width and height "
                               f"(H.264 yuv420p)")
    if not (math.isfinite(fps) and fps > 0):
        raise StudyRenderError(f"fps must be a positive number, got {fps!r}")
    style = style if isinstance(style, Style) else Style.from_dict(style)
    out = Path(out) if out is not None else study_dir / "render"
    out.mkdir(parents=True, exist_ok=True)
    rows, clips = load_stimuli(study_dir)
    bodies = _Bodies()
    body_list = [bodies(c) for c in clips]
    takeoffs = [_int_or_none(r.get("takeoff")) for r in rows]
    landings = [_int_or_none(r.get("landing")) for r in rows]
    st = stage(clips, takeoffs, landings, bodies=body_list, size=size,
               ground_margin=style.ground_margin, orient=orient)
    settings = {"style": style.to_dict(), "camera": st.camera.to_dict(), "size": list(size),
                "fps": float(fps), "ground_bounds": [float(v) for v in st.ground_bounds],
                "out": str(out), "frames": bool(frames)}
    bvh = [str(study_dir / (r.get("bvh") or f"{r['stimulus']}.bvh")) for r in rows]
    refs = {}                      # base clip -> its reference (level 0) stimulus, for overlays
    for r, o, p, y in zip(rows, st.offsets, bvh, st.yaws):
        try:
            level0 = float(r.get("level") or "nan") == 0.0
        except ValueError:
            level0 = False
        if r.get("kind") == "reference" or level0:
            refs.setdefault(r.get("clip", ""),
                            {"bvh": p, "offset": o.tolist(), "yaw": y, "stimulus": r["stimulus"]})
    tasks = []
    for r, o, p, y, t0, t1, body in zip(rows, st.offsets, bvh, st.yaws, takeoffs, landings,
                                        body_list):
        ref = refs.get(r.get("clip", ""))
        if ref is not None and ref["stimulus"] == r["stimulus"]:
            ref = None
        tasks.append({"stimulus": r["stimulus"], "bvh": p, "offset": o.tolist(), "yaw": y,
                      "takeoff": t0, "landing": t1, "what": what, "reference": ref,
                      "body": body})
    jobs = max(1, min(int(jobs or os.cpu_count() or 1), len(tasks)))
    bar = Progress(len(tasks), "render", progress)
    t0 = time.perf_counter()
    if jobs == 1:
        results = _run_local(settings, tasks, bar)
    else:
        results = []
        ctx = mp.get_context("spawn")     # no fork of a process that may hold a GL context
        with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_init_worker,
                                 initargs=(settings,)) as ex:
            futs = {ex.submit(_render_task, t): t["stimulus"] for t in tasks}
            for fut in as_completed(futs):
                try:
                    results.append(fut.result())
                except BrokenProcessPool as e:
                    raise StudyRenderError(
                        f"a render worker died while rendering {futs[fut]!r} ({e}); workers are "
                        f"started with 'spawn', so a script calling render_study(jobs > 1) must "
                        f"guard its top level with `if __name__ == '__main__':` "
                        f"(or use jobs=1)") from e
                except Exception as e:
                    for f in futs:
                        f.cancel()
                    raise StudyRenderError(f"rendering stimulus {futs[fut]!r} failed: {e}") from e
                bar.step(futs[fut])
    elapsed = time.perf_counter() - t0
    by_name = {r["stimulus"]: r for r in results}
    record = {
        "study": str(study_dir.resolve()),
        "what": what, "size": list(size), "fps": float(fps), "jobs": jobs, "orient": bool(orient),
        "camera": st.camera.to_dict(), "style": style.to_dict(),
        "takeoff_spot": {"x": 0.0, "z": 0.0, "anchor": "COM in the last frame on the ground "
                                                          "(takeoff - 1); heights unchanged"},
        "direction": [float(v) for v in st.direction],
        "ground_bounds": settings["ground_bounds"],
        "versions": versions(),
        "seconds": round(elapsed, 2),
        "stimuli": {r["stimulus"]: {"offset": [float(v) for v in o], "yaw_deg": float(y),
                                    "takeoff": t0_, "landing": t1_,
                                    "files": by_name.get(r["stimulus"], {}).get("files", {})}
                    for r, o, y, t0_, t1_ in zip(rows, st.offsets, st.yaws, takeoffs, landings)},
    }
    tmp = out / ".render.json.tmp"
    tmp.write_text(json.dumps(record, indent=2) + "\n")
    tmp.replace(out / "render.json")
    return record
