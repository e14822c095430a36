"""FXAA on the read-back frame (render.antialias): against the exact coverage of
a straight edge, against VTK's FXAA filter on real frames, and the frames
``Style.anti_aliasing = "fxaa"`` gives."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage
from _images import ssim
from hypothesis import given, settings, strategies as hs
from hypothesis.extra import numpy as hnp

from flipstudy.render.antialias import fxaa
from flipstudy.render.scene import scene_for
from flipstudy.render.staging import stage
from flipstudy.render.style import Style
from flipstudy.render.video import iter_frames
from flipstudy.stimuli import builtin


def _edge(slope: float, offset: float, n: int = 48, fg=(40, 70, 160), bg=(245, 245, 240)):
    """A straight edge y = offset + slope * x, drawn aliased (pixel centres) and
    exactly (each pixel's covered area, 32x32 samples), as uint8 RGB images."""
    yy, xx = np.mgrid[0:n, 0:n].astype(float)
    s = (np.arange(32) + 0.5) / 32 - 0.5
    cover = np.zeros((n, n))
    for dy in s:
        cover += ((yy + dy)[..., None] > offset + slope * (xx[..., None] + s)).mean(-1)
    cover /= len(s)
    fg, bg = np.asarray(fg, float), np.asarray(bg, float)
    exact = bg + (fg - bg) * cover[..., None]
    hard = np.where((yy > offset + slope * xx)[..., None], fg, bg).astype(np.uint8)
    return hard, exact


@settings(max_examples=25, deadline=None)
@given(slope=hs.floats(0.05, 0.45) | hs.floats(2.2, 12.0), offset=hs.floats(10.0, 14.0))
def test_fxaa_brings_a_straight_edge_towards_its_coverage(slope, offset):
    """Along a straight edge at a shallow or steep slope the anti-aliased pixels
    are closer to the exact area coverage than the aliased ones (RMS over the
    pixels the edge crosses, away from the frame's border); no pixel more than
    two away from the edge changes."""
    hard, exact = _edge(slope, offset if slope < 1 else -offset * slope)
    sm = fxaa(hard)
    crossed = np.abs(hard - exact).max(-1) > 1
    crossed[:, :4] = crossed[:, -4:] = crossed[:4] = crossed[-4:] = False
    if crossed.sum() < 10:
        return
    err = lambda img: np.sqrt(((img - exact)[crossed] ** 2).mean())  # noqa: E731
    assert err(sm) < 0.75 * err(hard), (err(sm), err(hard))
    near = ndimage.binary_dilation(np.abs(hard - exact).max(-1) > 1, np.ones((3, 3), bool), 2)
    assert np.array_equal(sm[~near], hard[~near])                # off the edge: as drawn


def test_fxaa_in_place_equals_a_copy_and_flat_frames_stay():
    hard, _ = _edge(0.3, 12.0)
    out = fxaa(hard)
    same = hard.copy()
    assert fxaa(same, same) is same and np.array_equal(same, out)
    flat = np.full((20, 30, 3), 128, np.uint8)
    assert np.array_equal(fxaa(flat), flat)


# images with edges at every slope and contrast, flat areas, borders and noise
_blocks = hnp.arrays(np.uint8, hs.tuples(hs.integers(3, 40), hs.integers(3, 40), hs.just(3)),
                     elements=hs.sampled_from([0, 17, 40, 128, 200, 255]))


@settings(max_examples=60, deadline=None)
@given(img=_blocks, scale=hs.integers(1, 4))
def test_fxaa_equals_the_plain_reference_byte_for_byte(img, scale):
    """The tuned FXAA (scratch buffers, bytes gathered where read, the endpoint search
    in two runs) gives the plain reference's bytes: on blocky images (long straight
    edges, stairs) at several sizes in turn (the scratch buffers change shape)."""
    from _fxaa_reference import fxaa as reference
    img = np.repeat(np.repeat(img, scale, 0), scale, 1)
    assert np.array_equal(fxaa(img), reference(img))
    same = img.copy()
    assert np.array_equal(fxaa(same, same), reference(img))


def test_fxaa_of_rendered_frames_equals_the_plain_reference():
    """On frames of the built-in backflip (character and checkerboard ground, 320x240,
    without anti-aliasing) the tuned FXAA's bytes are the reference's: the frames the
    videos get did not change."""
    from _fxaa_reference import fxaa as reference
    for f in _frames("none", ks=(10, 45, 80, 120)):
        assert np.array_equal(fxaa(f), reference(f))


def _frames(aa: str, size=(320, 240), ks=(30, 60, 90)):
    st = stage([builtin("backflip")], size=size, style=Style(anti_aliasing=aa))
    out = []
    with scene_for(st) as sc:
        for k, f in enumerate(iter_frames(st.clips[0], sc, 60.0, body=st.bodies[0])):
            if k in ks:
                out.append(f.copy())
            if k == max(ks):
                return out


def test_fxaa_frames_as_clean_as_vtks_filter():
    """The default anti-aliasing (FXAA on the read-back frame) against VTK's FXAA
    filter (the default before) on frames of the built-in backflip: SSIM >= 0.98
    and closer to VTK's than the frames without anti-aliasing are, on the whole
    frame and on the character's box; it changes the pixels VTK's changes."""
    vtk, ours, none = _frames("vtk-fxaa"), _frames("fxaa"), _frames("none")
    for v, o, n in zip(vtk, ours, none):
        touched = np.abs(v.astype(int) - n).max(-1) > 8           # where VTK's filter acted
        ys, xs = np.nonzero(touched)
        box = np.s_[ys.min():ys.max() + 1, xs.min():xs.max() + 1]
        assert ssim(o, v) >= 0.98 and ssim(o[box], v[box]) >= 0.98
        assert ssim(o[box], v[box]) > ssim(n[box], v[box])
        assert (np.abs(o.astype(int) - n).max(-1) > 8)[touched].mean() > 0.5


@pytest.mark.slow
def test_fxaa_edges_match_vtks_against_a_supersampled_reference():
    """At 160x120 against the same view rendered at 640x480 and averaged 4x4: the
    error on the character's edges with our FXAA is within 10 % of VTK's filter's
    (or below it), and well below none's."""
    ref = [f.astype(float).reshape(120, 4, 160, 4, 3).mean((1, 3)) for f in _frames("none", (640, 480))]
    none, vtk, ours = (_frames(a, (160, 120)) for a in ("none", "vtk-fxaa", "fxaa"))
    for r, n, v, o in zip(ref, none, vtk, ours):
        edge = np.abs(n - r).max(-1) > 8
        err = lambda img: np.sqrt(((img - r)[edge] ** 2).mean())  # noqa: E731
        assert err(o) < 1.1 * err(v) and err(o) < 0.85 * err(n), (err(o), err(v), err(n))


def test_fxaa_composites_as_clean_as_vtks_filter():
    """Ghost and trail composites (translucent ghosts, markers, lines) with the
    default anti-aliasing against VTK's FXAA filter: SSIM >= 0.98, and closer
    to VTK's than without anti-aliasing."""
    from flipstudy.render.figures import ghost_image, trail_image
    clip = builtin("backflip")
    for draw in (ghost_image, trail_image):
        imgs = {aa: draw(stage([clip], size=(240, 180), style=Style(anti_aliasing=aa)), None)
                for aa in ("vtk-fxaa", "fxaa", "none")}
        v = imgs["vtk-fxaa"]
        assert ssim(imgs["fxaa"], v) >= 0.98
        assert ssim(imgs["fxaa"], v) > ssim(imgs["none"], v), draw.__name__
