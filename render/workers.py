"""The render workers: one offscreen scene per process, reused for all its stimuli.

:func:`run_tasks` renders the tasks :func:`flipstudy.render.study.render_study`
planned, in this process (one job) or in a pool of worker processes (started
with 'spawn': no fork of a process that may hold a GL context).  Each worker
builds its plotter once from plain settings (:func:`_init_worker`) and draws
every task's stimulus on a :class:`~flipstudy.render.staging.Stage` under the
study's camera.

Interruptible: Ctrl-C terminates the workers at once (they ignore SIGINT; the
parent stops them and what they started, e.g. their ffmpeg encoders), workers
die with their parent (``PR_SET_PDEATHSIG`` and a parent-pid watchdog), and
outputs are written under ``render/.partial-<pid>/``; the parent moves each
finished one into place (:func:`publish`).
"""
from __future__ import annotations

import multiprocessing as mp
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from flipstudy.errors import StudyRenderError
from .record import RENDER_KINDS, file_sha256

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
    for sc, _ in _WORKER.pop("scenes", {}).values():
        sc.close()


def _load_placed(path: str, offset, yaw: float = 0.0):
    from flipstudy.stimuli import load_bvh

    from .staging import place
    return place(load_bvh(path, scale=1.0), offset, yaw)


def _scene_for_style(name):
    """The worker's scene and style for a stimulus's character style (the
    study's scene, or one more scene per other style, kept for later stimuli)."""
    style = _WORKER["style"]
    if not name or name == style.character:
        return _WORKER["scene"], style
    scenes = _WORKER.setdefault("scenes", {})
    if name not in scenes:
        from .scene import Scene
        st = _WORKER["settings"]
        s2 = style.with_character(name)
        scenes[name] = (Scene(None, s2, tuple(st["size"]), _WORKER["camera"],
                              tuple(st["ground_bounds"])), s2)
    return scenes[name]


def _render_task(task: dict) -> dict:
    """Render the requested outputs of one stimulus in this worker's scene.

    Each output is written under ``render/.partial-<pid>/``; the parent renames
    it into place when the task is done, so an interrupted render never leaves a
    half-written file under an output's name."""
    from . import figures as fg
    from .camera import Camera
    from .staging import Stage
    from .video import render_video
    t_start = time.perf_counter()
    st = _WORKER["settings"]
    scene, style = _scene_for_style(task.get("style"))
    clip = _load_placed(task["bvh"], task["offset"], task["yaw"])
    body = task["body"]            # measured once in the parent: the same in every worker
    # the study's camera, ground and style (render_study fitted them to every stimulus)
    camera = Camera.from_dict(task["camera"]) if task.get("camera") else _WORKER["camera"]
    common = dict(camera=camera, size=tuple(st["size"]), style=style,
                  ground=tuple(st["ground_bounds"]))
    t0, t1 = task["takeoff"], task["landing"]
    one = Stage([clip], [body], [t0], [t1], **common)
    part = Path(st["partial"])
    part.mkdir(parents=True, exist_ok=True)
    files = {}
    name = task["stimulus"]
    for kind in task["what"]:
        fname = RENDER_KINDS[kind].format(s=name)
        f = part / fname
        frames_tmp = None
        if kind == "video":
            frames_tmp = part / f"frames-{name}" if st.get("frames") else None
            render_video(one, f, fps=st["fps"], frames_dir=frames_tmp, scene=scene)
        elif kind == "ghost":
            fg.ghost_image(one, f, scene=scene)
        elif kind == "trail":
            fg.trail_image(one, f, scene=scene)
        elif kind == "strip":
            ph = max(120, 2 * (one.size[1] // 4))         # panels half the image height
            fg.strip_image(one, f, panel_size=(2 * int(round(ph * 0.35)), ph), scene=scene)
        elif kind == "composite":
            fg.composite_image(one, f, scene=scene)
        elif kind == "overlay":
            if not task.get("reference"):
                continue
            ref = _load_placed(task["reference"]["bvh"], task["reference"]["offset"],
                               task["reference"]["yaw"])
            both = Stage([ref, clip], [body, body], [t0, t0], [t1, t1], **common)
            fg.overlay_image(both, f, labels=("original", name), scene=scene)
        info = {"bytes": f.stat().st_size, "sha256": file_sha256(f)}
        # the parent moves the finished file into place and records it in one step
        # (:func:`publish`), so no file stands in render/ that render.json does not record
        files[kind] = {"file": fname, **info, "partial": str(f),
                       "frames": None if frames_tmp is None else str(frames_tmp)}
    return {"stimulus": name, "files": files, "seconds": round(time.perf_counter() - t_start, 3),
            "renderer": _renderer(scene)}


def _renderer(scene) -> dict:
    """What drew this worker's pixels: the OpenGL vendor, renderer and version
    strings of its render window, the window class, and the library versions
    (once per worker process); recorded per output in ``render.json``."""
    if "renderer" not in _WORKER:
        from .record import versions
        info = {}
        try:
            text = scene.plotter.render_window.ReportCapabilities() or ""
        except Exception:  # noqa: BLE001 — a window that cannot report: recorded as unknown
            text = ""
        names = {"OpenGL vendor string": "gl_vendor", "OpenGL renderer string": "gl_renderer",
                 "OpenGL version string": "gl_version"}
        for line in text.splitlines():
            k, _, v = line.partition(":")
            if k.strip() in names:
                info[names[k.strip()]] = v.strip()
        info["window"] = scene.plotter.render_window.GetClassName()
        _WORKER["renderer"] = {**info, "versions": versions()}
    return _WORKER["renderer"]


_WORKER_LOCK = None


def render_on_worker(settings: dict, task: dict) -> dict:
    """One task of :func:`run_tasks`, in a long-lived process that renders for
    any study (a Dask worker, :mod:`flipstudy.study.cluster`): the scene is built
    on first use and rebuilt only when ``settings`` change; one task at a time
    per process (a lock: the GL context is not shared between threads)."""
    global _WORKER_LOCK
    import threading
    if _WORKER_LOCK is None:
        _WORKER_LOCK = threading.Lock()
    # each worker process writes in its own subfolder: a task rerun after its worker
    # was killed never shares a file with the dead worker's last (orphaned) encoder
    settings = {**settings, "partial": str(Path(settings["partial"]) / f"w{os.getpid()}")}
    with _WORKER_LOCK:
        if _WORKER.get("settings") != settings:
            _close_worker()
            _WORKER.pop("renderer", None)
            _init_worker(settings)
        return _render_task(task)


def publish(res: dict, out: Path) -> None:
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


def clear_partials(out: Path) -> None:
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


def run_tasks(settings: dict, tasks: list, jobs: int, done) -> None:
    """Render ``tasks`` with the study's ``settings`` (plain data: style, camera,
    size, fps, ground bounds, the partial folder), in this process when
    ``jobs == 1``, else in ``jobs`` worker processes; ``done(result)`` is called
    in this process for each finished task."""
    if not tasks:
        return
    if jobs == 1:
        _run_local(settings, tasks, done)
    else:
        _run_pool(settings, tasks, jobs, done)


__all__ = ["PARTIAL_PREFIX", "run_tasks", "publish", "clear_partials", "render_on_worker"]
