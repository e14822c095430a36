"""Framing (issue 17): every stimulus video of the default study shows its
character centred and filling the frame, measured on the video's own frames;
composites of a CMU clip do not crop the body."""
from __future__ import annotations

import numpy as np
import pytest

from _silhouettes import box, silhouette_union, video_frames as _frames
from flipstudy.render.compose import read_image
from flipstudy.render.style import Style, rgb8

SIZE = (128, 96)
NO_GROUND = {"ground": False, "anti_aliasing": "none"}


def _character_box(frames: np.ndarray, background) -> tuple:
    """(x0, x1, y0, y1) pixels of everything that differs from the background
    in any frame (the ground is off: only the character is drawn)."""
    return box(silhouette_union(frames, background))


@pytest.fixture(scope="module")
def default_study_videos(tmp_path_factory):
    from flipstudy.render.study import render_study
    from flipstudy.stimuli.design import PAPER_DESIGN, parse_design
    from flipstudy.stimuli.stimset import build_stimuli
    study = tmp_path_factory.mktemp("framing") / "study"
    rows = build_stimuli(parse_design(PAPER_DESIGN), study, progress=False).rows
    render_study(study, what="video", size=SIZE, fps=15, style=NO_GROUND, progress=False)
    return study, rows


@pytest.mark.slow
def test_default_study_videos_centre_and_fill_the_frame(default_study_videos):
    study, rows = default_study_videos
    W, H = SIZE
    bg = rgb8(Style.from_dict(NO_GROUND).background)
    seen = []
    for r in rows:
        x0, x1, y0, y1 = _character_box(_frames(study / "render" / f"{r['stimulus']}.mp4"), bg)
        fill = max((x1 - x0) / W, (y1 - y0) / H)
        off = abs(0.5 * (x0 + x1) - W / 2) / W
        seen.append((r["stimulus"], round(fill, 2), round(off, 3)))
        assert fill >= 0.60, f"{r['stimulus']}: the action spans {fill:.0%} of the frame"
        assert off <= 0.10, f"{r['stimulus']}: the action is {off:.0%} of the width off centre"
        assert x0 > 0 and y0 > 0 and x1 < W and y1 < H, f"{r['stimulus']}: the body touches the edge"
    assert len(seen) == 46


@pytest.mark.shared("mocap/88_01.bvh")
def test_cmu_composites_do_not_crop_the_body(shared_path, tmp_path):
    from flipstudy.render import figures as fg
    from flipstudy.render.staging import stage
    from flipstudy.stimuli import load_bvh
    clip = load_bvh(shared_path("mocap/88_01.bvh"))
    sty = Style.from_dict(NO_GROUND)
    st = stage([clip], size=(160, 120), style=sty)
    bg = np.asarray(rgb8(sty.background), int)
    for name, img in (("ghost", fg.ghost_image(st)), ("trail", fg.trail_image(st, legend=False)),
                      ("composite", fg.composite_image(st))):
        diff = np.abs(img.astype(int) - bg).max(-1) > 40
        border = np.r_[diff[0], diff[-1], diff[:, 0], diff[:, -1]]
        assert not border.any(), f"{name}: the body is cut by the image's edge"
        assert diff.mean() > 0.01, name
    strip = fg.strip_image(st, None, dt=0.1, panel_size=(80, 120))
    ph, pw = 120, 80
    for k in range(strip.shape[1] // (pw + 4) + 1):
        for row in range((strip.shape[0] + 4) // (ph + 4)):
            p = strip[row * (ph + 4):row * (ph + 4) + ph, k * (pw + 4):k * (pw + 4) + pw]
            if p.shape[:2] != (ph, pw):
                continue
            body = np.abs(p.astype(int) - bg).max(-1) > 40
            rows_ = np.nonzero(body.any(1))[0]
            if rows_.size == 0:
                continue
            # the label band is at the top: the body must not touch the bottom or the sides
            assert not (body[-1].any() or body[:, 0].any() or body[:, -1].any()), \
                f"strip panel {row},{k} crops the body"
