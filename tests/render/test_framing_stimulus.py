"""``render --framing stimulus`` (issue 33): one camera per stimulus, fitted to it
alone, so every video spans ≥ 75 % of the frame, centred within 10 % — measured on
the videos' pixels.  The cost, measured too: under ``--framing clip`` (the default,
one camera per base clip) the standing character is the same number of pixels tall
in every stimulus of a clip, so the picture's scale cannot give the condition away;
under ``stimulus`` it is not."""
from __future__ import annotations

import json

import numpy as np
import pytest

from _silhouettes import box, silhouette_union, span_and_offset, video_frames
from test_framing_family import DESIGN, NO_GROUND, SIZE
from flipstudy.render.style import Style, rgb8

BG = rgb8(Style.from_dict(NO_GROUND).background)


def _build(root, design: str):
    from flipstudy.stimuli.design import parse_design
    from flipstudy.stimuli.stimset import build_stimuli
    study = root / "study"
    return study, build_stimuli(parse_design(design), study, progress=False).rows


def _measure(study, rows) -> dict:
    """Per stimulus: (fill, dx, dy) of all frames, and the standing character's
    height in pixels (the first frame, before take-off)."""
    out = {}
    for r in rows:
        frames = video_frames(study / "render" / f"{r['stimulus']}.mp4")
        fill, dx, dy = span_and_offset(silhouette_union(frames, BG))
        x0, x1, y0, y1 = box(silhouette_union(frames[:1], BG))
        out[r["stimulus"]] = (fill, dx, dy, int(y1 - y0))
    return out


def _render(study, framing: str):
    from flipstudy.render.study import render_study
    return render_study(study, what="video", size=SIZE, fps=15, style=NO_GROUND, progress=False,
                        jobs=1, framing=framing)


def check_stimulus_framing(seen: dict):
    for name, (fill, dx, dy, _) in seen.items():
        assert fill >= 0.75, f"{name}: spans {fill:.0%} of the frame"
        assert abs(dx) <= 0.10 and abs(dy) <= 0.10, f"{name}: centre off by {dx:+.0%}, {dy:+.0%}"


def standing_heights(seen: dict, clip_of) -> dict:
    heights: dict = {}
    for name, (*_, h) in seen.items():
        heights.setdefault(clip_of(name), []).append(h)
    return heights


def test_stimulus_framing_fills_every_video_and_clip_framing_keeps_the_scale(tmp_path):
    study, rows = _build(tmp_path, DESIGN)
    clip_of = lambda n: n.split("_")[0]  # noqa: E731
    _render(study, "clip")
    by_clip = _measure(study, rows)
    # through the CLI: a changed framing makes every video again and is recorded
    from flipstudy.study.cli import main
    style = tmp_path / "plain.toml"
    style.write_text('ground = false\nanti_aliasing = "none"\n')
    assert main(["render", str(study), "--framing", "stimulus", "--size", f"{SIZE[0]}x{SIZE[1]}",
                 "--video-fps", "15", "--style", str(style), "--jobs", "1", "--quiet"]) == 0
    rec = json.loads((study / "render" / "render.json").read_text())
    assert rec["framing"] == "stimulus" and rec["made"] == len(rows)
    assert sorted(rec["cameras"]) == sorted(r["stimulus"] for r in rows)
    by_stim = _measure(study, rows)
    check_stimulus_framing(by_stim)
    # one camera per clip: the lowest flight spans less than 75 % (why the option exists)
    assert min(f for f, *_ in by_clip.values()) < 0.75
    for clip, hs in standing_heights(by_clip, clip_of).items():
        assert max(hs) - min(hs) <= 1, (clip, hs)                  # one scale per clip
    for clip, hs in standing_heights(by_stim, clip_of).items():
        assert max(hs) >= 1.1 * min(hs), (clip, hs)               # the scale tells the stimuli apart


def test_an_unknown_framing_is_refused(tmp_path):
    from flipstudy.errors import FlipstudyError
    study, _ = _build(tmp_path, DESIGN)
    with pytest.raises(FlipstudyError, match="framing 'video'"):
        _render(study, "video")


@pytest.mark.slow
def test_default_study_stimulus_framing_fills_every_video(tmp_path):
    from flipstudy.stimuli.design import PAPER_DESIGN
    study, rows = _build(tmp_path, PAPER_DESIGN)
    clip_of = lambda n: n.split("_")[0]  # noqa: E731
    _render(study, "clip")
    by_clip = _measure(study, rows)
    _render(study, "stimulus")
    by_stim = _measure(study, rows)
    assert len(by_stim) == 46
    check_stimulus_framing(by_stim)
    for clip, hs in standing_heights(by_clip, clip_of).items():
        assert max(hs) - min(hs) <= 1, (clip, hs)
    for clip, hs in standing_heights(by_stim, clip_of).items():
        assert max(hs) >= 1.1 * min(hs), (clip, hs)
    for name in sorted(by_stim):
        print(f"{name}: fill clip {by_clip[name][0]:.2f} stimulus {by_stim[name][0]:.2f}; "
              f"standing {by_clip[name][3]} px / {by_stim[name][3]} px")
