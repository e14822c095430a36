"""Character styles and sided colours: what the pixels show."""
from pathlib import Path

import numpy as np
import pytest

from flipstudy import builtin, load_bvh
from flipstudy.render.characters import CHARACTER_STYLES, joint_side, joint_sides
from flipstudy.render.compose import read_image
from flipstudy.render.figures import ghost_image
from flipstudy.render.scene import scene_for
from flipstudy.render.staging import stage
from flipstudy.render.style import Style
from flipstudy.render.video import iter_frames, render_video

SHARED = Path(__file__).resolve().parents[3] / "shared"
CMU = SHARED / "mocap" / "88_01.bvh"
PLAIN = Style(ground=False, background="#ffffff", anti_aliasing="none")


def _lab(rgb8):
    """CIELAB (D65) of sRGB uint8 colours, written out here (not the library's)."""
    c = np.asarray(rgb8, float) / 255.0
    c = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    M = np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750],
                  [0.0193339, 0.1191920, 0.9503041]])
    xyz = c @ M.T / M.sum(axis=1)
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]),
                     200 * (f[..., 1] - f[..., 2])], axis=-1)


def _standing(style, clip):
    st = stage([clip], size=(240, 320), style=style)
    with scene_for(st) as sc:
        return next(iter_frames(st.clips[0], sc, fps=10.0)).copy()


@pytest.mark.parametrize("character", ["ellipsoids", "capsules", "mannequin"])
def test_left_and_right_limbs_differ_in_colour_and_in_grey(character):
    """A standing built-in frame, side view: the pixels that the sided tones make
    lighter than the one-colour body (left limbs) and darker (right limbs) differ
    by CIE ΔE ≥ 15, and their grey values (L*) by ≥ 15 too."""
    clip = builtin("backflip")
    st = PLAIN.replace(character=character)
    sided = _standing(st, clip)
    plain = _standing(st.replace(sided=False), clip)
    Ls, Lp = _lab(sided)[..., 0], _lab(plain)[..., 0]
    body = np.any(plain < 250, axis=-1)
    left = body & (Ls > Lp + 4)
    right = body & (Ls < Lp - 4)
    assert left.sum() > 50 and right.sum() > 50, (left.sum(), right.sum())
    a, b = _lab(np.median(sided[left], 0)), _lab(np.median(sided[right], 0))
    assert np.linalg.norm(a - b) >= 15
    grey = lambda im: (im.astype(float) @ [0.299, 0.587, 0.114])[..., None].repeat(3, -1)  # noqa: E731
    ga, gb = np.median(grey(sided)[left], 0), np.median(grey(sided)[right], 0)
    assert abs(_lab(ga)[0] - _lab(gb)[0]) >= 15
    # the sides are the joints' sides: left limbs light, and they lie on the body's left
    assert np.median(Ls[left]) > np.median(Ls[right])


def test_sides_from_joint_names_and_a_skeleton_without_sides():
    assert [joint_side(n) for n in ("LeftUpLeg", "RightHand", "LHipJoint", "RThumb", "lhip",
                                    "rknee", "hand_l", "foot_r", "Hips", "LowerBack")] == \
        [1, 2, 1, 2, 1, 2, 1, 2, 0, 0]
    clip = builtin("jump")
    s = joint_sides(clip.skeleton)
    assert (s == 1).sum() == (s == 2).sum() > 0
    from flipstudy.stimuli.motion import Skeleton
    sk = Skeleton(["a", "b", "c"], [-1, 0, 1], np.array([[0, 0, 0], [0, 1, 0], [0, 1, 0.]]))
    with pytest.warns(UserWarning, match="no left and right"):
        assert not joint_sides(sk).any()


def test_unknown_character_style_says_did_you_mean():
    from flipstudy.errors import FlipstudyError
    with pytest.raises(FlipstudyError, match="did you mean 'stick'"):
        Style(character="stik")


def test_point_light_is_white_dots_on_black():
    s = Style(character="point-light")
    assert (s.background, s.ground, s.body_color) == ("#000000", False, "#ffffff")
    img = _standing(s.replace(anti_aliasing="none"), builtin("backflip"))
    from scipy import ndimage
    lit = img.min(axis=-1) > 200
    assert img[~lit].max() < 140                    # black around the dots
    n = ndimage.label(lit)[1]
    assert 5 <= n <= 15                             # side view: near and far markers overlap


@pytest.mark.parametrize("character", CHARACTER_STYLES)
def test_every_style_renders_a_video_and_a_ghost(character, tmp_path):
    clips = [builtin("backflip")]
    if CMU.exists():
        clips.append(load_bvh(CMU, scale=None))
    style = Style(anti_aliasing="none").with_character(character)
    bg = np.array([int(style.background[i:i + 2], 16) for i in (1, 3, 5)])
    for k, clip in enumerate(clips):
        st = stage([clip.slice(0, min(clip.num_frames, 240))], size=(96, 64), style=style)
        render_video(st, tmp_path / f"{k}.mp4", fps=10.0)
        assert (tmp_path / f"{k}.mp4").stat().st_size > 1000
        img = ghost_image(st, tmp_path / f"{k}.png")
        assert read_image(tmp_path / f"{k}.png").shape[:2] == (64, 96)
        # something other than the background and the ground is drawn
        if not style.ground:
            assert (np.abs(img.astype(int) - bg).sum(-1) > 60).sum() > 20
        else:
            assert img.std() > 5


def test_mannequin_is_meshed_once_and_closed():
    from flipstudy import Body
    from flipstudy.render.characters import mannequin
    clip = builtin("jump")
    body = Body.from_clip(clip)
    m1, m2 = mannequin(body), mannequin(body)
    assert m1._X is m2._X or np.shares_memory(m1._X, m2._X) or np.array_equal(m1._X, m2._X)
    edges = m1.mesh.extract_feature_edges(boundary_edges=True, feature_edges=False,
                                          manifold_edges=False, non_manifold_edges=False)
    assert edges.n_cells == 0                       # closed: no boundary edges
    R, P = clip.joint_rotations(), clip.joint_positions()
    m1.pose(R[50], P[50])
    pts = m1.world_points()
    # posed points stay near the joints (skinned, not left in the meshing pose)
    d = np.linalg.norm(pts[:, None] - P[50][None], axis=-1).min(1)
    assert np.percentile(d, 99) < 0.35


DESIGN = '''
[study]
name = "styled"
seed = 3
{study_style}
[[clips]]
name = "backflip"
source = "backflip"
[[groups]]
name = "smooth-increase"
kind = "angular-momentum"
profile = "smooth"
levels = [0, 25]
original = "own"
{group_style}
'''


def test_design_style_is_validated_and_recorded_in_manifest_and_render_json(tmp_path):
    import csv
    import json
    from flipstudy.render.study import render_study
    from flipstudy.errors import DesignError
    from flipstudy.stimuli.design import parse_design
    from flipstudy.stimuli.stimset import MANIFEST_COLUMNS, build_stimuli
    with pytest.raises(DesignError, match="did you mean 'mannequin'"):
        parse_design(DESIGN.format(study_style='style = "manequin"', group_style=""))
    with pytest.raises(DesignError, match="did you mean 'point-light'"):
        parse_design(DESIGN.format(study_style="", group_style='style = "pointlight"'))
    plain = parse_design(DESIGN.format(study_style="", group_style=""))
    assert plain.style is None and not plain.styled
    d = parse_design(DESIGN.format(study_style='style = "capsules"', group_style='style = "stick"'))
    assert d.style == "capsules" and d.groups[0].style == "stick"
    rows = build_stimuli(plain, tmp_path / "plain", progress=False).rows
    header = (tmp_path / "plain" / "manifest.csv").read_text().splitlines()[0].split(",")
    assert header == MANIFEST_COLUMNS and "style" not in rows[0]       # unchanged without a style
    build_stimuli(d, tmp_path / "s", progress=False)
    with open(tmp_path / "s" / "manifest.csv") as f:
        man = list(csv.DictReader(f))
    assert [r["style"] for r in man] == ["stick", "stick"]
    rec = render_study(tmp_path / "s", what="ghost", size=(64, 48), jobs=1, progress=False)
    assert rec.record.style["character"] == "stick"
    assert {v.style for v in rec.record.stimuli.values()} == {"stick"}
    assert all(o.style == "stick" for o in rec.record.outputs.values())
    on_disk = json.loads((tmp_path / "s" / "render" / "render.json").read_text())
    assert on_disk["stimuli"]["backflip_smooth-increase_25"]["style"] == "stick"


def test_cli_style_takes_a_name_or_a_file(tmp_path):
    from flipstudy.errors import FlipstudyError
    from flipstudy.study.cli.render import _style
    assert _style(["stick"]).character == "stick"
    f = tmp_path / "s.toml"
    f.write_text('background = "#ffffff"\n')
    s = _style([str(f), "mannequin"])
    assert (s.background, s.character) == ("#ffffff", "mannequin")
    with pytest.raises(FlipstudyError, match="did you mean 'capsules'"):
        _style(["capsule"])


def test_analysis_splits_tables_by_style_when_there_are_several():
    import pandas as pd
    from flipstudy.analysis.pipeline import split_by_style
    df = pd.DataFrame({"group": ["a", "a", "b"], "style": ["stick", "stick", "mannequin"]})
    t, note = split_by_style(df, pd.DataFrame({"group": ["a", "b"], "n": [2, 1]}))
    assert list(t.columns[:2]) == ["group", "style"] and "stick: a" in note
    same = pd.DataFrame({"group": ["a", "b"], "style": ["stick", "stick"]})
    t2, note2 = split_by_style(same, pd.DataFrame({"group": ["a", "b"], "n": [2, 1]}))
    assert "style" not in t2.columns and note2 is None
