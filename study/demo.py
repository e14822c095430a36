"""A tiny study folder for tests, demos and development: a design, a manifest in
the format of :mod:`flipstudy.stimuli.stimset` and small placeholder videos (a moving
square; H.264, yuv420p) — no motion data or renderer needed.

Examples
--------
>>> import tempfile, pathlib
>>> tmp = tempfile.TemporaryDirectory()
>>> study = make_demo_study(pathlib.Path(tmp.name) / "tiny")
>>> sorted(p.name for p in study.iterdir())
['design.toml', 'manifest.csv', 'render']
>>> len(list((study / "render").glob("*.mp4")))     # 2 groups × 2 levels and the reference
5
>>> tmp.cleanup()
"""
from __future__ import annotations

from pathlib import Path
from typing import Iterable

import numpy as np

from flipstudy.stimuli.contract import Stimulus, StimulusSet
from flipstudy.vocab import kinds

DEMO_GROUPS = (("smooth-increase", kinds.AM.name, "smooth", 1),
               ("abrupt-decrease", kinds.AM.name, "abrupt", -1))


def write_test_video(path, *, size=(64, 48), frames: int = 30, fps: float = 30.0,
                     color=(230, 180, 40)) -> Path:
    """A small valid MP4 (H.264, yuv420p): a square moving left to right."""
    from flipstudy.render.video import h264_writer
    w, h = size
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    gen = h264_writer(path, (w, h), fps, crf=30, preset="ultrafast")
    s = max(h // 4, 2)
    for i in range(frames):
        img = np.full((h, w, 3), 40, np.uint8)
        x = int((w - s) * i / max(frames - 1, 1))
        y = (h - s) // 2
        img[y:y + s, x:x + s] = color
        gen.send(img.tobytes())
    gen.close()
    return path


def demo_design_text(*, name="demo", seed=7, repetitions=2, replay=False, break_every=40,
                     clips=("backflip",), levels=(0, 25), groups=DEMO_GROUPS,
                     reference=True, original: str | None = "per-group",
                     max_dropped_pct: float | None = None, repeat_dropped: bool = False,
                     extra: str = "") -> str:
    """A demo design.  ``original``: written as ``[study] original`` — the demo keeps
    every group's own level 0 ("per-group") so its trial counts stay simple;
    "shared" (or None: the default) gives the paper's shared original.  ``extra``: TOML
    appended as it is (more ``[[groups]]``, an ``[online]`` or ``[exclusions]`` table)."""
    lines = ["[study]", f'name = "{name}"', f"seed = {seed}", f"repetitions = {repetitions}"]
    lines += ([f'original = "{original}"'] if original else []) + [""]
    lines += ["[session]", f"replay = {'true' if replay else 'false'}", f"break_every = {break_every}"]
    lines += ([f"max_dropped_pct = {max_dropped_pct:g}"] if max_dropped_pct is not None else [])
    lines += (["repeat_dropped = true"] if repeat_dropped else []) + [""]
    for c in clips:
        lines += ["[[clips]]", f'name = "{c}"', f'source = "{c}"', ""]
    if reference:
        lines += ["[reference]", "clips = [" + ", ".join(f'"{c}"' for c in clips) + "]", ""]
    for g, kind, profile, sign in groups:
        lines += ["[[groups]]", f'name = "{g}"', f'kind = "{kind}"']
        if kinds.get(kind).profiled:
            lines.append(f'profile = "{profile}"')
        lines += [f"sign = {sign}", "levels = [" + ", ".join(f"{v:g}" for v in levels) + "]", ""]
    return "\n".join(lines) + ("\n" + extra if extra else "")


def write_placeholder_study(out, text: str, *, frames: int, fps: float,
                            sha256=lambda i: "0" * 64) -> StimulusSet:
    """Write ``out/design.toml`` (``text``) and a ``manifest.csv`` naming every
    stimulus the design plans (placeholder numbers, no motion files: sessions read
    only the manifest); return the stimulus set.  ``sha256(i)`` gives row i's hash."""
    from flipstudy.stimuli.design import parse_design
    from flipstudy.stimuli.stimset import original_of, plan
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "design.toml").write_text(text)
    d = parse_design(text, out / "design.toml")
    rows = []
    for name, spec, group, level in plan(d):
        rows.append(Stimulus(
            name, spec.name, group.name if group else "reference", group.kind if group else "reference",
            (group.profile or "") if group else "", level,
            nominal_error_pct=(group.sign * level) if group else 0.0, takeoff_angle_deg=0.0,
            takeoff=10, landing=20, seed=0, sha256=sha256(len(rows)), L_ratio_window=0.0,
            flight_s=0.0, jump_height_m=0.0, jump_length_m=0.0, frames=frames, fps=fps,
            original=original_of(d, spec.name, group), takeoff_time=0.0, landing_time=0.0))
    stimuli = StimulusSet(out, rows, d)
    stimuli.write()
    return stimuli


def make_demo_study(out, *, video_frames: int = 30, video_fps: float = 30.0, size=(64, 48),
                    videos: bool = True, **design) -> Path:
    """Write ``design.toml``, ``manifest.csv`` and ``render/<stimulus>.mp4`` into ``out``
    (keyword arguments go to :func:`demo_design_text`)."""
    out = Path(out)
    rows = write_placeholder_study(out, demo_design_text(**design), frames=video_frames,
                                   fps=video_fps)
    if videos:
        palette = [(230, 180, 40), (80, 170, 230), (220, 90, 90), (120, 200, 120), (200, 120, 220)]
        for i, r in enumerate(rows):
            write_test_video(out / "render" / f"{r.stimulus}.mp4", size=size, frames=video_frames,
                             fps=video_fps, color=palette[i % len(palette)])
        write_demo_record(out, rows, size=size, fps=video_fps)
    return out


def write_demo_record(out, rows: Iterable[Stimulus], *, size=(64, 48), fps: float = 30.0) -> None:
    """``render/render.json`` for placeholder videos, in the form `flipstudy render`
    writes (one settings record, each video made from its manifest row's sha256),
    so ``flipstudy run`` serves them."""
    import json

    from flipstudy.render.record import file_sha256
    render = Path(out) / "render"
    settings = {"size": list(size), "fps": float(fps), "placeholder": "flipstudy.study.demo moving square"}
    outputs = {}
    for r in rows:
        f = render / f"{r.stimulus}.mp4"
        outputs[f.name] = {"stimulus": r.stimulus, "kind": "video",
                           "stimulus_sha256": r.sha256, "settings": "demo",
                           "bytes": f.stat().st_size, "sha256": file_sha256(f)}
    rec = {"what": ["video"], "size": list(size), "fps": float(fps), "settings_id": "demo",
           "settings_records": {"demo": settings}, "outputs": outputs}
    (render / "render.json").write_text(json.dumps(rec, indent=2) + "\n")
