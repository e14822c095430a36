"""Rendering a whole stimulus set: one style, one camera, one take-off spot.

:func:`render_study` reads ``STUDY_DIR/manifest.csv``, loads every stimulus
(``STUDY_DIR/<stimulus>.bvh``, metres, the header's frame rate), places all of
them with :func:`flipstudy.render.camera.stage` (take-off COM at the origin, one camera
fitted to every frame of every stimulus, one ground), and renders the chosen
outputs in parallel worker processes — each worker builds its offscreen
plotter once and reuses it for all its stimuli.  Outputs go to
``STUDY_DIR/render/`` and the settings (camera, style, size, fps, versions,
per-stimulus offsets and files) to ``STUDY_DIR/render/render.json``.

Interruptible and resumable: Ctrl-C terminates the workers at once (they
ignore SIGINT; the parent stops them and what they started), workers die with
their parent (``PR_SET_PDEATHSIG`` and a parent-pid watchdog), outputs are
written under ``render/.partial-<pid>/`` and renamed into place when complete,
and ``flipstudy.render.json`` records per output what it was made from, so a rerun makes
only what is missing or stale.  :func:`check_rendered` is what ``flipstudy
run`` asks before serving the videos.
"""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyValueError

from flipstudy.stimuli.exceptions import FlipstudyError
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

from flipstudy.stimuli._progress import Progress

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
        from flipstudy.stimuli.body import Body
        k = _skeleton_key(clip.skeleton)
        if k not in self._cache:
            self._cache[k] = Body.from_clip(clip)
        return self._cache[k]


def load_stimuli(study_dir) -> tuple[list[dict], list]:
    """Manifest rows and their clips (BVH in metres, the header's frame rate)."""
    from flipstudy.stimuli import load_bvh
    from flipstudy.stimuli.stimset import read_manifest
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
PARTIAL_PREFIX = ".partial-"          # STUDY/render/.partial-<pid>/: outputs being written


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


def _die_with_parent(parent_pid: int) -> None:
    """Make this process end when ``parent_pid`` does, even if it is SIGKILLed:
    Linux ``prctl(PR_SET_PDEATHSIG, SIGKILL)``, and a thread that watches the
    parent pid once a second (other systems, and a parent that died before the
    prctl)."""
    import signal
    import threading
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)          # 1 = PR_SET_PDEATHSIG
        except (OSError, AttributeError):                        # no libc prctl: the thread only
            pass
    if os.getppid() != parent_pid:
        os._exit(1)

    def watch():
        while True:
            time.sleep(1.0)
            if os.getppid() != parent_pid:
                os._exit(1)
    threading.Thread(target=watch, name="parent-watchdog", daemon=True).start()


def _init_pool_worker(settings: dict, parent_pid: int) -> None:
    """A pool worker: Ctrl-C is the parent's business (it terminates the workers),
    the worker dies with its parent, then builds its scene."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)      # already so from the parent's spawn
    _die_with_parent(parent_pid)
    _init_worker(settings)


def _close_worker() -> None:
    sc = _WORKER.pop("scene", None)
    if sc is not None:
        sc.close()


def _load_placed(path: str, offset, yaw: float = 0.0):
    from flipstudy.stimuli import load_bvh

    from .camera import place
    return place(load_bvh(path, scale=1.0), offset, yaw)


def file_sha256(path) -> str:
    import hashlib
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _render_task(task: dict) -> dict:
    """Render the requested outputs of one stimulus in this worker's scene.

    Each output is written under ``render/.partial-<pid>/`` and renamed into
    place only when complete, so an interrupted render never leaves a
    half-written file under an output's name."""
    from . import figures as fg
    t_start = time.perf_counter()
    st = _WORKER["settings"]
    scene = _WORKER["scene"]
    cam = _WORKER["camera"]
    gb = tuple(st["ground_bounds"])
    size = tuple(st["size"])
    clip = _load_placed(task["bvh"], task["offset"], task["yaw"])
    body = task["body"]            # measured once in the parent: the same in every worker
    part = Path(st["partial"])
    part.mkdir(parents=True, exist_ok=True)
    common = dict(camera=cam, body=body, takeoff=task["takeoff"], landing=task["landing"],
                  scene=scene, ground_bounds=gb)
    files = {}
    name = task["stimulus"]
    for kind in task["what"]:
        fname = RENDER_KINDS[kind].format(s=name)
        f = part / fname
        frames_tmp = None
        if kind == "video":
            frames_tmp = part / f"frames-{name}" if st.get("frames") else None
            fg.render_video(clip, f, fps=st["fps"], size=size, frames_dir=frames_tmp, **common)
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
        info = {"bytes": f.stat().st_size, "sha256": file_sha256(f)}
        # the parent moves the finished file into place and records it in one step
        # (:func:`_publish`), so no file stands in render/ that render.json does not record
        files[kind] = {"file": fname, **info, "partial": str(f),
                       "frames": None if frames_tmp is None else str(frames_tmp)}
    return {"stimulus": name, "files": files, "seconds": round(time.perf_counter() - t_start, 3)}


def _publish(res: dict, out: Path) -> None:
    """Move a finished task's files from the partial folder into ``out``."""
    import shutil
    for f in res["files"].values():
        if f.get("frames"):
            final = out / "frames" / res["stimulus"]
            final.parent.mkdir(parents=True, exist_ok=True)
            if final.exists():
                shutil.rmtree(final)
            os.replace(f["frames"], final)
        os.replace(f["partial"], out / f["file"])


def _run_local(settings: dict, tasks: list, done) -> None:
    _init_worker(settings)
    try:
        for t in tasks:
            done(_render_task(t))
    finally:
        _close_worker()


def _descendants(pids) -> set[int]:
    """Processes started by ``pids`` (Linux /proc; empty elsewhere), e.g. the
    workers' ffmpeg encoders, which run in their own process group."""
    ppid = {}
    try:
        entries = [e for e in os.listdir("/proc") if e.isdigit()]
    except OSError:
        return set()
    for e in entries:
        try:
            with open(f"/proc/{e}/stat", "rb") as f:
                ppid[int(e)] = int(f.read().rsplit(b")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
    found, front = set(), set(pids)
    while front:
        front = {c for c, pp in ppid.items() if pp in front} - found
        found |= front
    return found


def _stop_workers(ex, timeout: float = 5.0) -> None:
    """Terminate a ProcessPoolExecutor's workers now (SIGTERM, then SIGKILL)
    and what they started (SIGKILL) instead of letting them finish their tasks."""
    import signal
    procs = list((getattr(ex, "_processes", None) or {}).values())
    helpers = _descendants(p.pid for p in procs if p.pid)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for pid in helpers:
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
    t_end = time.monotonic() + timeout
    for p in procs:
        p.join(max(0.0, t_end - time.monotonic()))
        if p.is_alive():
            p.kill()
            p.join(1.0)
    ex.shutdown(wait=True, cancel_futures=True)


def _run_pool(settings: dict, tasks: list, jobs: int, done) -> None:
    import signal
    ctx = mp.get_context("spawn")     # no fork of a process that may hold a GL context
    # the workers start with SIGINT ignored (a disposition exec keeps), so a Ctrl-C
    # while they import cannot give them a KeyboardInterrupt and a traceback: the
    # parent alone takes it, and stops them (a Ctrl-C in the few milliseconds of
    # the spawn itself is lost)
    old = signal.signal(signal.SIGINT, signal.SIG_IGN) if _main_thread() else None
    try:
        ex = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_init_pool_worker,
                                 initargs=(settings, os.getpid()))
        # with 'spawn' each of the first `jobs` submits starts one worker
        futs = {ex.submit(_render_task, t): t["stimulus"] for t in tasks[:jobs]}
    finally:
        if old is not None:
            signal.signal(signal.SIGINT, old)
    try:
        futs.update({ex.submit(_render_task, t): t["stimulus"] for t in tasks[jobs:]})
        for fut in as_completed(futs):
            try:
                res = fut.result()
            except BrokenProcessPool as e:
                raise StudyRenderError(
                    f"a render worker died while rendering {futs[fut]!r} ({e}); workers are "
                    f"started with 'spawn', so a script calling render_study(jobs > 1) must "
                    f"guard its top level with `if __name__ == '__main__':` "
                    f"(or use jobs=1)") from e
            except Exception as e:
                raise StudyRenderError(f"rendering stimulus {futs[fut]!r} failed: {e}") from e
            done(res)
    except BaseException:
        # Ctrl-C or a failure: stop the workers at once; a second Ctrl-C while
        # they are stopped must not interrupt the clean-up
        prev = signal.signal(signal.SIGINT, signal.SIG_IGN) if _main_thread() else None
        try:
            _stop_workers(ex)
        finally:
            if prev is not None:
                signal.signal(signal.SIGINT, prev)
        raise
    ex.shutdown(wait=True)


def _main_thread() -> bool:
    import threading
    return threading.current_thread() is threading.main_thread()


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


def _canonical_id(obj) -> str:
    import hashlib
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()[:16]


def stimulus_hashes(study_dir, rows) -> list[str]:
    """The sha256 of each stimulus's BVH file, checked against the manifest's
    ``sha256`` column where it has one (a stimulus edited after ``flipstudy
    stimuli`` is an error: its manifest row no longer describes it)."""
    study_dir = Path(study_dir)
    out = []
    for i, r in enumerate(rows, start=2):
        p = study_dir / (r.get("bvh") or f"{r['stimulus']}.bvh")
        h = file_sha256(p)
        want = (r.get("sha256") or "").strip().lower()
        if want and want != h:
            raise StudyRenderError(
                f"{study_dir / 'manifest.csv'} line {i}: stimulus {r['stimulus']!r}: {p.name} has "
                f"sha256 {h[:12]}…, the manifest says {want[:12]}…; the file changed after "
                f"`flipstudy stimuli` wrote it (make the stimuli again)")
        out.append(h)
    return out


def read_record(out_dir) -> dict | None:
    """``flipstudy.render.json`` of a render folder (None if there is none)."""
    p = Path(out_dir) / "render.json"
    if not p.is_file():
        return None
    try:
        return json.loads(p.read_text())
    except (OSError, ValueError) as e:
        raise StudyRenderError(f"{p}: not readable as JSON ({e}); delete it to re-render "
                               f"everything") from None


def _up_to_date(out: Path, fname: str, have: dict | None, want: dict) -> bool:
    if not have or {k: v for k, v in have.items() if k not in ("bytes", "sha256")} != want:
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


def _clear_partials(out: Path) -> None:
    """Remove what interrupted renders left half-written (their process is gone)."""
    import shutil
    for d in out.glob(PARTIAL_PREFIX + "*"):
        try:
            pid = int(d.name[len(PARTIAL_PREFIX):])
            os.kill(pid, 0)
            if pid != os.getpid():
                continue                  # another render of this folder is running
        except ProcessLookupError:
            pass
        except (ValueError, PermissionError):
            continue
        shutil.rmtree(d, ignore_errors=True)


def render_study(study_dir, what=("video",), size=(640, 480), jobs: int | None = None,
                 fps: float = 60.0, style=None, out=None, frames: bool = False,
                 progress: bool = True, orient: bool = True, force: bool = False) -> dict:
    """Render the stimuli of a study with one style, one camera and one take-off
    spot; returns (and writes to ``render/render.json``) the settings.  With
    ``orient`` base clips that travel in other directions are turned about the
    vertical to travel like the first one (see :func:`flipstudy.render.camera.stage`).

    Resumable: ``flipstudy.render.json`` records for every output what it was made from
    (the stimulus's sha256, its placement, the settings that change pixels and
    the library versions) and the file's size and sha256; an output whose record
    matches and whose file is intact is kept, anything else is made again
    (``force``: everything).  ``flipstudy.render.json`` is rewritten atomically after every
    stimulus, so an interrupted render loses at most the outputs in flight, and
    those never appear under their final names.

    Example
    -------
    A study of two stimuli (``flipstudy stimuli`` of a two-level design), their
    ghost images at a small size, then the same call again:

    >>> import tempfile, pathlib
    >>> from flipstudy.stimuli.design import parse_design
    >>> from flipstudy.stimuli.stimset import build_stimuli
    >>> design = parse_design('''
    ... [study]
    ... name = "tiny"
    ... seed = 7
    ... [[clips]]
    ... name = "backflip"
    ... source = "backflip"
    ... [[groups]]
    ... name = "smooth-increase"
    ... kind = "angular-momentum"
    ... profile = "smooth"
    ... sign = 1
    ... levels = [0, 25]
    ... ''')
    >>> tmp = tempfile.TemporaryDirectory()
    >>> study = pathlib.Path(tmp.name) / "study"
    >>> [r["stimulus"] for r in build_stimuli(design, study, progress=False)]
    ['backflip_original', 'backflip_smooth-increase_25']
    >>> rec = render_study(study, what="ghost", size=(96, 64), jobs=1, progress=False)
    >>> rec["made"], sorted(p.name for p in (study / "render").glob("*.png"))
    (2, ['backflip_original_ghost.png', 'backflip_smooth-increase_25_ghost.png'])
    >>> render_study(study, what="ghost", size=(96, 64), jobs=1, progress=False)["made"]   # resumed
    0
    >>> tmp.cleanup()
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
    _clear_partials(out)
    rows, clips = load_stimuli(study_dir)
    shas = stimulus_hashes(study_dir, rows)
    bodies = _Bodies()
    body_list = [bodies(c) for c in clips]
    takeoffs = [_int_or_none(r.get("takeoff")) for r in rows]
    landings = [_int_or_none(r.get("landing")) for r in rows]
    st = stage(clips, takeoffs, landings, bodies=body_list, size=size,
               ground_margin=style.ground_margin, orient=orient)
    vers = versions()
    # what changes pixels, once for the whole study (the camera is fitted to all stimuli)
    pixel = {"size": list(size), "fps": float(fps), "style": style.to_dict(),
             "camera": st.camera.to_dict(), "ground_bounds": [float(v) for v in st.ground_bounds],
             "versions": vers}
    pixel = json.loads(json.dumps(pixel))             # the form it has when read back
    sid = _canonical_id(pixel)
    settings = {"style": style.to_dict(), "camera": st.camera.to_dict(), "size": list(size),
                "fps": float(fps), "ground_bounds": pixel["ground_bounds"],
                "out": str(out), "partial": str(out / f"{PARTIAL_PREFIX}{os.getpid()}"),
                "frames": bool(frames)}
    bvh = [str(study_dir / (r.get("bvh") or f"{r['stimulus']}.bvh")) for r in rows]
    sha_of = {r["stimulus"]: h for r, h in zip(rows, shas)}
    refs = {}                      # base clip -> its reference (level 0) stimulus, for overlays
    for r, o, p, y in zip(rows, st.offsets, bvh, st.yaws):
        try:
            level0 = float(r.get("level") or "nan") == 0.0
        except ValueError:
            level0 = False
        if r.get("kind") == "reference" or level0:
            refs.setdefault(r.get("clip", ""),
                            {"bvh": p, "offset": o.tolist(), "yaw": y, "stimulus": r["stimulus"]})
    old = read_record(out) or {}
    outputs = {k: v for k, v in (old.get("outputs") or {}).items()
               if isinstance(v, dict) and (out / k).is_file()}
    tasks, n_kept, expected = [], 0, {}
    for r, o, p, y, t0, t1, body in zip(rows, st.offsets, bvh, st.yaws, takeoffs, landings,
                                        body_list):
        name = r["stimulus"]
        ref = refs.get(r.get("clip", ""))
        if ref is not None and ref["stimulus"] == name:
            ref = None
        placement = json.loads(json.dumps({"offset": o.tolist(), "yaw_deg": float(y),
                                           "takeoff": t0, "landing": t1}))
        todo = []
        for kind in what:
            if kind == "overlay" and ref is None:
                continue
            want = {"stimulus": name, "kind": kind, "stimulus_sha256": sha_of[name],
                    "settings": sid, "placement": placement}
            if kind == "video":
                want["frames"] = bool(frames)
            if kind == "overlay":
                want["reference"] = json.loads(json.dumps(
                    {"stimulus": ref["stimulus"], "sha256": sha_of[ref["stimulus"]],
                     "offset": ref["offset"], "yaw_deg": float(ref["yaw"])}))
            fname = RENDER_KINDS[kind].format(s=name)
            expected[fname] = want
            if not force and _up_to_date(out, fname, outputs.get(fname), want):
                n_kept += 1
            else:
                todo.append(kind)
        if todo:
            tasks.append({"stimulus": name, "bvh": p, "offset": o.tolist(), "yaw": y,
                          "takeoff": t0, "landing": t1, "what": todo, "reference": ref,
                          "body": body})
    settings_records = {k: v for k, v in (old.get("settings_records") or {}).items()
                        if any(o_.get("settings") == k for o_ in outputs.values())}
    settings_records[sid] = pixel
    info = {r["stimulus"]: {"offset": [float(v) for v in o], "yaw_deg": float(y),
                            "takeoff": t0_, "landing": t1_}
            for r, o, y, t0_, t1_ in zip(rows, st.offsets, st.yaws, takeoffs, landings)}
    jobs = max(1, min(int(jobs or os.cpu_count() or 1), max(len(tasks), 1)))
    t_start = time.perf_counter()
    made = [0]

    def record() -> dict:
        files = {n: {} for n in info}
        for fname, o_ in outputs.items():
            if o_.get("stimulus") in files and o_ == {**expected.get(fname, {}),
                                                     "bytes": o_.get("bytes"),
                                                     "sha256": o_.get("sha256")}:
                files[o_["stimulus"]][o_["kind"]] = fname
        return {
            "study": str(study_dir.resolve()),
            "what": what, "size": list(size), "fps": float(fps), "jobs": jobs,
            "orient": bool(orient), "camera": st.camera.to_dict(), "style": style.to_dict(),
            "takeoff_spot": {"x": 0.0, "z": 0.0, "anchor": "COM in the last frame on the ground "
                                                              "(takeoff - 1); heights unchanged"},
            "direction": [float(v) for v in st.direction],
            "ground_bounds": settings["ground_bounds"],
            "versions": vers,
            "seconds": round(time.perf_counter() - t_start, 2),
            "made": made[0], "up_to_date": n_kept, "settings_id": sid,
            "stimuli": {n: {**v, "files": files[n]} for n, v in info.items()},
            "settings_records": settings_records,
            "outputs": dict(sorted(outputs.items())),
        }

    def write() -> dict:
        rec = record()
        tmp = out / ".render.json.tmp"
        tmp.write_text(json.dumps(rec, indent=2) + "\n")
        tmp.replace(out / "render.json")
        return rec

    bar = Progress(len(tasks), "render", progress)

    def done(res: dict) -> None:
        # moving the files into place and recording them is one step that Ctrl-C does not
        # cut (SIGINT waits until both are done): no output unrecorded, none recorded absent
        import signal
        old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            _publish(res, out)
            for kind, f in res["files"].items():
                outputs[f["file"]] = {**expected[f["file"]], "bytes": f["bytes"], "sha256": f["sha256"]}
                made[0] += 1
            write()
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)
        bar.step(res["stimulus"])

    write()                        # drops records of outputs whose files are gone
    try:
        if not tasks:
            pass
        elif jobs == 1:
            _run_local(settings, tasks, done)
        else:
            _run_pool(settings, tasks, jobs, done)
    finally:
        bar.close()
        import shutil
        shutil.rmtree(settings["partial"], ignore_errors=True)
        (out / ".render.json.tmp").unlink(missing_ok=True)     # a write cut short
    return write()


# --------------------------------------------------------------- checking
class StaleRenderError(StudyRenderError):
    """Rendered outputs that do not match the study (stale, missing, mixed settings)."""


def check_rendered(study_dir, kind: str = "video", rows=None, hash_files: bool = True) -> dict:
    """Check that every stimulus of the manifest has its ``kind`` output, made
    from the stimulus as it is now, intact, and all with one settings record.
    Returns that settings record; raises :class:`StaleRenderError` naming the
    offending files and the fix."""
    from flipstudy.stimuli.stimset import read_manifest
    study_dir = Path(study_dir)
    out = study_dir / "render"
    rows = read_manifest(study_dir) if rows is None else rows
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
        name = r["stimulus"]
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
        want = (r.get("sha256") or "").strip().lower()
        if not want:
            p = study_dir / (r.get("bvh") or f"{name}.bvh")
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
