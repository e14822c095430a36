"""Rendering a whole stimulus set: one style, one camera, one take-off spot.

:func:`render_study` takes a study's :class:`~flipstudy.stimuli.contract.StimulusSet`
(or its folder, read and checked once), loads every stimulus
(:func:`load_stimuli`: ``STUDY_DIR/<stimulus>.bvh``, metres, the header's frame
rate), places all of them with :func:`flipstudy.render.staging.stage` (take-off COM
at the origin, one ground, one view direction), fits one camera per base clip to
every frame of all its stimuli (the paper's rule: every stimulus of a base clip
under one camera; each base clip's action centred and filling the frame),
and renders the chosen outputs in parallel worker processes
(:mod:`flipstudy.render.workers`: each builds its offscreen plotter once and
reuses it for all its stimuli).  Outputs go to ``STUDY_DIR/render/`` and the
settings (cameras, style, size, fps, versions, per-stimulus offsets, camera and files) to
``STUDY_DIR/render/render.json`` (:mod:`flipstudy.render.record`).

Interruptible and resumable: Ctrl-C stops the workers at once, outputs appear
under their names only when complete, and ``render.json`` records per output
what it was made from, so a rerun makes only what is missing or stale.
:func:`~flipstudy.render.record.check_rendered` is what ``flipstudy run`` asks
before serving the videos.
"""
from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path

import numpy as np

from flipstudy.stimuli._progress import Progress
from flipstudy.errors import FlipstudyValueError, StudyRenderError
from flipstudy.records import RenderRecord
from flipstudy.results import RenderResult

from flipstudy.stimuli.contract import Stimulus, StimulusSet, file_sha256

from .record import (RENDER_KINDS, canonical_id, read_record,
                     up_to_date, versions, write_record)
from .workers import PARTIAL_PREFIX, clear_partials, publish, run_tasks


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


def load_stimuli(stimuli) -> tuple[StimulusSet, list]:
    """A study's stimuli (a :class:`~flipstudy.stimuli.contract.StimulusSet`, or a
    folder, read and checked once: every file present, every hash as the manifest
    says) and their clips (BVH in metres, the header's frame rate)."""
    from flipstudy.stimuli import load_bvh
    if not isinstance(stimuli, StimulusSet):
        stimuli = StimulusSet.read(stimuli)
    if not len(stimuli):
        raise StudyRenderError(f"{stimuli.manifest_path}: no stimuli")
    clips = []
    for s in stimuli:
        clip = load_bvh(stimuli.path(s), scale=1.0)
        clip.meta["name"] = s.stimulus
        clips.append(clip)
    return stimuli, clips


def _character(row: Stimulus, style, study_dir) -> str:
    """The character style of a stimulus: its ``style`` column, else the
    render style's."""
    from .characters import CHARACTER_STYLES
    name = (row.style or "").strip() or style.character
    if name not in CHARACTER_STYLES:
        raise StudyRenderError(f"{Path(study_dir) / 'manifest.csv'}: stimulus {row.stimulus!r}: "
                               f"unknown style {name!r} (one of {', '.join(CHARACTER_STYLES)})")
    return name


def _methods(style) -> dict:
    """How the pixels and the videos were made, as ``render.json`` records it: the
    anti-aliasing actually run (not only the style's name for it) and the encoder."""
    from .style import ANTI_ALIASING_METHODS
    from .video import ENCODER
    return {"anti_aliasing": {"style": style.anti_aliasing,
                              "method": ANTI_ALIASING_METHODS[style.anti_aliasing]},
            "encoder": dict(ENCODER)}


#: how :func:`render_study` fits its cameras: ``"clip"``, one camera per base clip
#: fitted to all its stimuli (the paper's rule: the character's size on screen is the
#: same in every stimulus of a clip, so it cannot give the condition away; a lower
#: flight fills less of the frame); ``"stimulus"``, one camera per stimulus fitted to
#: it alone (every video centred and filling the frame; the character's size on
#: screen then differs between the stimuli of one clip)
FRAMINGS = ("clip", "stimulus")


def _refuse_unrecorded(out: Path, tasks: list, old: dict) -> None:
    """Render writes over only what it made: an output file already at ``out`` that
    ``render.json`` does not list (a file of the researcher's, a figure another command
    put there) is refused before anything is made, naming it."""
    listed = old.get("outputs") if isinstance(old.get("outputs"), dict) else {}
    for t in tasks:
        for kind in t["what"]:
            p = out / RENDER_KINDS[kind].format(s=t["stimulus"])
            if (p.exists() or p.is_symlink()) and p.name not in listed:
                raise StudyRenderError(
                    f"{p}: not made by `flipstudy render` ({out / 'render.json'} does not list it), "
                    f"so it is not written over: move it aside, then render again")


def render_study(study_dir, what=("video",), size=(640, 480), jobs: int | None = None,
                 fps: float = 60.0, style=None, out=None, frames: bool = False,
                 progress: bool = True, orient: bool = True, force: bool = False,
                 cluster=None, framing: str = "clip", replace_check=None) -> RenderResult:
    """Render the stimuli of a study with one style, one take-off spot and one camera
    per base clip (fitted to all its stimuli; ``cameras`` in the record, and each
    stimulus's ``camera``); writes the settings to ``render/render.json`` and returns a
    :class:`~flipstudy.results.RenderResult` (its ``record``).  Resumable (see the
    module's text): an output whose record matches and whose file is intact is kept,
    anything else is made again.

    Parameters
    ----------
    study_dir : str, pathlib.Path or StimulusSet
        The study's folder or its :class:`~flipstudy.stimuli.contract.StimulusSet`.
    what : sequence of str
        Outputs: ``video``, ``ghost``, ``trail``, ``strip``, ``composite``, ``overlay``.
    size : tuple of int
        (width, height) in pixels.
    jobs : int, optional
        Local worker processes.
    fps : float
        Display frames per second of the videos.
    style : Style, optional
    out : str or pathlib.Path, optional
    frames, progress : bool
    orient : bool
        Turn base clips that travel in other directions about the vertical to travel
        like the first one (see :func:`flipstudy.render.staging.stage`).
    force : bool
        Make every output again.
    cluster : Cluster, optional
        A :class:`flipstudy.study.cluster.Cluster`: render on its workers instead of
        ``jobs`` local processes; each output's record names the OpenGL renderer and
        versions that drew it (``renderer``).
    framing : str
        (:data:`FRAMINGS`) ``"clip"`` (default) one camera per base clip, ``"stimulus"``
        one camera per stimulus, fitted to it alone (same view direction, elevation and
        margins, centred), at the cost of the character's size on screen differing
        between the stimuli of one clip.
    replace_check : callable, optional
        Called with the names of the existing videos this call would make again
        (stale or ``force``), before anything is made; raises to refuse
        (:func:`flipstudy.study.pipeline.render` refuses for a study holding
        real participants' answers: they answered the videos as they are).

    Returns
    -------
    RenderResult

    Raises
    ------
    StudyRenderError

    Examples
    --------
    A study of two stimuli, their ghost images at a small size, then the same call again:

    >>> import tempfile, pathlib
    >>> from flipstudy.stimuli.design import Design
    >>> from flipstudy.stimuli.stimset import build_stimuli
    >>> from flipstudy.vocab.kinds import AM
    >>> design = Design.from_dict({"study": {"name": "tiny", "seed": 7},
    ...     "clips": [{"name": "backflip", "source": "backflip"}],
    ...     "groups": [{"name": "smooth-increase", "kind": AM.name, "profile": "smooth",
    ...                 "sign": 1, "levels": [0, 25]}]})
    >>> tmp = tempfile.TemporaryDirectory()
    >>> study = pathlib.Path(tmp.name) / "study"
    >>> [r["stimulus"] for r in build_stimuli(design, study, progress=False).rows]
    ['backflip_original', 'backflip_smooth-increase_25']
    >>> rec = render_study(study, what="ghost", size=(96, 64), jobs=1, progress=False)
    >>> rec.made, sorted(p.name for p in (study / "render").glob("*.png"))
    (2, ['backflip_original_ghost.png', 'backflip_smooth-increase_25_ghost.png'])
    >>> render_study(study, what="ghost", size=(96, 64), jobs=1, progress=False).made   # resumed
    0
    >>> tmp.cleanup()
    """
    from .style import Style
    stimuli = study_dir if isinstance(study_dir, StimulusSet) else None
    study_dir = stimuli.folder if stimuli is not None else Path(study_dir)
    what, size = _checked(what, size, fps, framing)
    style = style if isinstance(style, Style) else Style.from_dict(style)
    out = Path(out) if out is not None else study_dir / "render"
    out.mkdir(parents=True, exist_ok=True)
    clear_partials(out)
    rows, clips = load_stimuli(stimuli if stimuli is not None else study_dir)
    run, settings, tasks = _prepare(rows, clips, study_dir, out, what=what, size=size, fps=fps,
                                    style=style, frames=frames, orient=orient, force=force,
                                    framing=framing, progress=progress)
    if replace_check is not None:
        again = [RENDER_KINDS["video"].format(s=t["stimulus"]) for t in tasks if "video" in t["what"]]
        again = [f for f in again if (out / f).is_file()]
        if again:
            replace_check(again)
    rec = run.run(settings, tasks, jobs, cluster)
    return RenderResult(study=study_dir, what=tuple(rec["what"]), size=tuple(rec["size"]),
                        fps=rec["fps"], jobs=rec["jobs"], made=rec["made"], up_to_date=rec["up_to_date"],
                        seconds=rec["seconds"], n_stimuli=len(rec["stimuli"]),
                        record_path=out / "render.json", record=RenderRecord.from_dict(rec))


# the named steps of :func:`render_study`

def _prepare(rows, clips, study_dir: Path, out: Path, *, what, size, fps, style, frames, orient, force,
             framing, progress):
    """Everything before the workers start: the stage, the cameras, the settings that
    change pixels, what is up to date and what to make: (run, worker settings, tasks)."""
    from .staging import stage
    chosen = {(r.style or "").strip() for r in rows}
    if len(chosen) == 1 and "" not in chosen:        # the design chose one style for all
        style = style.with_character(_character(rows.stimuli[0], style, study_dir))
    shas = [r.sha256 or file_sha256(rows.path(r)) for r in rows]
    bodies = _Bodies()
    body_list = [bodies(c) for c in clips]
    takeoffs = [r.takeoff for r in rows]
    landings = [r.landing for r in rows]
    st = stage(clips, takeoffs, landings, bodies=body_list, size=size, style=style, orient=orient)
    cameras, camera_of = _cameras(st, rows, takeoffs, framing)
    vers = versions()
    # what changes pixels, once for the whole study (one camera per base clip)
    pixel = {"size": list(size), "fps": float(fps), "style": style.to_dict(),
             "framing": framing, "cameras": cameras, "ground_bounds": [float(v) for v in st.ground_bounds],
             "versions": vers, **_methods(style)}
    pixel = json.loads(json.dumps(pixel))             # the form it has when read back
    sid = canonical_id(pixel)
    settings = {"style": style.to_dict(), "camera": camera_of[0], "size": list(size),
                "fps": float(fps), "ground_bounds": pixel["ground_bounds"],
                "out": str(out), "partial": str(out / f"{PARTIAL_PREFIX}{os.getpid()}"),
                "frames": bool(frames)}
    old = read_record(out) or {}
    outputs = {k: v for k, v in (old.get("outputs") or {}).items()
               if isinstance(v, dict) and (out / k).is_file()}
    placed = list(zip(st.offsets, st.yaws, takeoffs, landings, body_list, camera_of))
    tasks, n_kept, expected = _plan(rows, placed, shas, outputs, what=what, style=style,
                                    study_dir=study_dir, sid=sid, frames=frames, force=force, out=out)
    _refuse_unrecorded(out, tasks, old)
    settings_records = {k: v for k, v in (old.get("settings_records") or {}).items()
                        if any(o_.get("settings") == k for o_ in outputs.values())}
    settings_records[sid] = pixel
    header = {"study": str(study_dir.resolve()),
              "what": what, "size": list(size), "fps": float(fps), "jobs": None,   # set when known
              "orient": bool(orient), "framing": framing, "camera": camera_of[0], "cameras": cameras,
              "style": style.to_dict(),
              "takeoff_spot": {"x": 0.0, "z": 0.0, "anchor": "COM in the last frame on the ground "
                                                             "(takeoff - 1); heights unchanged"},
              "direction": [float(v) for v in st.direction],
              "ground_bounds": settings["ground_bounds"],
              "versions": vers, **_methods(style)}
    info = {r.stimulus: {"offset": [float(v) for v in o], "yaw_deg": float(y),
                         "takeoff": t0_, "landing": t1_, "style": _character(r, style, study_dir),
                         "camera": cam}
            for r, (o, y, t0_, t1_, _, cam) in zip(rows, placed)}
    run = _Run(out, header, info, outputs, expected, n_kept, sid, settings_records, progress)
    return run, settings, tasks


def _checked(what, size, fps: float, framing: str) -> tuple[list, tuple[int, int]]:
    """The outputs and the size asked for, checked with the frame rate and the framing."""
    what = parse_what(what)
    size = (int(size[0]), int(size[1]))
    if "video" in what and (size[0] % 2 or size[1] % 2):
        raise StudyRenderError(f"size {size[0]}x{size[1]}: video needs an even width and height "
                               f"(H.264 yuv420p)")
    if not (math.isfinite(fps) and fps > 0):
        raise StudyRenderError(f"fps must be a positive number, got {fps!r}")
    if framing not in FRAMINGS:
        raise StudyRenderError(f"framing {framing!r}: choose {' or '.join(FRAMINGS)}")
    return what, size


def _cameras(st, rows, takeoffs, framing: str) -> tuple[dict, list]:
    """One camera per base clip, fitted to the union of its stimuli over every frame
    (framing "clip"), or per stimulus, fitted to it alone (framing "stimulus"):
    (cameras by base clip or stimulus, each stimulus's camera)."""
    from .staging import base_clip_groups
    if framing == "clip":
        groups = base_clip_groups(st.clips, takeoffs, [r.clip for r in rows])
    else:
        groups = {r.stimulus: [k] for k, r in enumerate(rows)}
    cameras, camera_of = {}, [None] * len(rows)
    for key, ks in groups.items():
        cam = st.refit(*ks).camera.to_dict()
        cameras[key if framing == "stimulus" else
                rows.stimuli[ks[0]].clip or rows.stimuli[ks[0]].stimulus] = cam
        for k in ks:
            camera_of[k] = cam
    return cameras, camera_of


def _plan(rows, placed, shas, outputs, *, what, style, study_dir, sid, frames, force,
          out) -> tuple[list, int, dict]:
    """What to make: (tasks for the workers, outputs kept as up to date, file name →
    what its record must say).  ``placed``: per stimulus (offset, yaw, take-off,
    landing, body, camera)."""
    bvh = [str(rows.path(r)) for r in rows]
    sha_of = {r.stimulus: h for r, h in zip(rows, shas)}
    refs = {}                      # base clip -> its reference (level 0) stimulus, for overlays
    for r, (o, y, *_), p in zip(rows, placed, bvh):
        if r.kind == "reference" or r.level == 0.0:
            refs.setdefault(r.clip, {"bvh": p, "offset": o.tolist(), "yaw": y, "stimulus": r.stimulus})
    tasks, n_kept, expected = [], 0, {}
    for r, (o, y, t0, t1, body, cam), p in zip(rows, placed, bvh):
        name = r.stimulus
        ref = refs.get(r.clip)
        if ref is not None and ref["stimulus"] == name:
            ref = None
        placement = json.loads(json.dumps({"offset": o.tolist(), "yaw_deg": float(y),
                                           "takeoff": t0, "landing": t1}))
        character = _character(r, style, study_dir)
        todo = []
        for kind in what:
            if kind == "overlay" and ref is None:
                continue
            want = {"stimulus": name, "kind": kind, "stimulus_sha256": sha_of[name],
                    "settings": sid, "placement": placement, "style": character}
            if kind == "video":
                want["frames"] = bool(frames)
            if kind == "overlay":
                want["reference"] = json.loads(json.dumps(
                    {"stimulus": ref["stimulus"], "sha256": sha_of[ref["stimulus"]],
                     "offset": ref["offset"], "yaw_deg": float(ref["yaw"])}))
            fname = RENDER_KINDS[kind].format(s=name)
            expected[fname] = want
            if not force and up_to_date(out, fname, outputs.get(fname), want):
                n_kept += 1
            else:
                todo.append(kind)
        if todo:
            tasks.append({"stimulus": name, "bvh": p, "offset": o.tolist(), "yaw": y,
                          "takeoff": t0, "landing": t1, "what": todo, "reference": ref,
                          "body": body, "style": character, "camera": cam})
    return tasks, n_kept, expected


class _Run:
    """The running render of :func:`render_study`: the outputs recorded so far, and
    ``render.json`` rewritten after every stimulus."""

    def __init__(self, out: Path, header: dict, info: dict, outputs: dict, expected: dict, n_kept: int,
                 sid: str, settings_records: dict, progress: bool):
        self.out, self.header, self.info, self.outputs = out, header, info, outputs
        self.expected, self.n_kept, self.sid = expected, n_kept, sid
        self.settings_records, self.progress = settings_records, progress
        self.made = 0
        self.t_start = time.perf_counter()                  # again when the run starts
        self.bar = None

    def record(self) -> dict:
        """``render.json`` as it stands."""
        files = {n: {} for n in self.info}
        for fname, o_ in self.outputs.items():
            if o_.get("stimulus") in files and "bytes" in o_ and "sha256" in o_ and \
                    {k: v for k, v in o_.items() if k not in ("bytes", "sha256", "renderer")} \
                    == self.expected.get(fname):
                files[o_["stimulus"]][o_["kind"]] = fname
        return {
            **self.header,
            "seconds": round(time.perf_counter() - self.t_start, 2),
            "made": self.made, "up_to_date": self.n_kept, "settings_id": self.sid,
            "stimuli": {n: {**v, "files": files[n]} for n, v in self.info.items()},
            "settings_records": self.settings_records,
            "outputs": dict(sorted(self.outputs.items())),
        }

    def write(self) -> dict:
        """Write ``render.json`` (atomically) and return it."""
        return write_record(self.out, self.record())

    def done(self, res: dict) -> None:
        """One stimulus's outputs from a worker: moved into place and recorded."""
        # moving the files into place and recording them is one step that Ctrl-C does not
        # cut (SIGINT waits until both are done): no output unrecorded, none recorded absent
        import signal
        old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        try:
            publish(res, self.out)
            for kind, f in res["files"].items():
                self.outputs[f["file"]] = {**self.expected[f["file"]], "bytes": f["bytes"],
                                           "sha256": f["sha256"], "renderer": res.get("renderer")}
                self.made += 1
            self.write()
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)
        self.bar.step(res["stimulus"])

    def run(self, settings: dict, tasks: list, jobs: int, cluster) -> dict:
        """Make ``tasks`` (in up to ``jobs`` local processes, or on ``cluster``'s workers);
        the final record."""
        jobs = max(1, min(int(jobs or os.cpu_count() or 1), max(len(tasks), 1))) if cluster is None \
            else cluster.n_workers
        self.header["jobs"] = jobs
        self.t_start = time.perf_counter()
        self.bar = Progress(len(tasks), "render", self.progress)
        self.write()                   # drops records of outputs whose files are gone
        try:
            if cluster is None:
                run_tasks(settings, tasks, jobs, self.done)
            else:                      # one task per stimulus on the cluster's workers
                cluster.map_render(settings, tasks, self.done)
        finally:
            self.bar.close()
            import shutil
            shutil.rmtree(settings["partial"], ignore_errors=True)
            (self.out / ".render.json.tmp").unlink(missing_ok=True)     # a write cut short
        return self.write()


__all__ = ["RENDER_KINDS", "FRAMINGS", "StudyRenderError", "parse_size", "parse_what", "load_stimuli",
           "render_study"]
