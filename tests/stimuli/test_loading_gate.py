"""Issue 33, "one loading rule": every CLIP passes one physics gate
(:func:`flipstudy.stimuli.loading.checked_clip`), measured against what a wrong header does:
at the header's 120 fps a 60 Hz capture's gravity is 4× too large; a body scaled ×2 falls at
2 g and stands 3.4 m tall."""
import numpy as np
import pytest

from flipstudy.errors import FlipstudyError, UnphysicalClipError
from flipstudy.stimuli import analyse, builtin
from flipstudy.stimuli.loading import checked_clip, load_clip

from _shared import shared_file


def test_a_60hz_capture_read_at_its_header_120fps_is_refused_with_the_fix():
    p = str(shared_file("88_01.bvh"))
    with pytest.raises(UnphysicalClipError) as e:
        load_clip(p)
    msg = str(e.value)
    assert msg.startswith(p) and "--fps 60" in msg and "--accept-unphysical" in msg
    assert isinstance(e.value, FlipstudyError)
    clip = load_clip(p, fps=60)                       # the fix it names passes the gate
    g = analyse(clip, estimate=False).apparent_gravity
    assert abs(g / 9.81 - 1) < 0.25                   # and gravity is then an Earth's
    assert load_clip(p, accept_unphysical=True).fps == 120.0      # the way past it


@pytest.mark.parametrize("name", ["87_03.bvh", "88_05.bvh", "90_11.bvh", "02_04_iclone-retarget.bvh"])
def test_real_clips_at_their_true_rate_pass(name):
    fps = 60 if name[:2] in ("87", "88") else None
    assert load_clip(str(shared_file(name)), fps=fps).num_frames > 100


def test_a_scaled_builtin_is_refused_naming_the_scale_and_exact_ones_pass():
    with pytest.raises(UnphysicalClipError, match=r"--scale"):
        load_clip("backflip", scale=2.0)
    for name in ("backflip", "frontflip", "jump"):
        assert checked_clip(builtin(name), name) is not None
    # the gate's verdict agrees with the closed form g_app = 9.81 · scale
    g = analyse(builtin("backflip").scaled(2.0), estimate=False).apparent_gravity
    assert g == pytest.approx(2 * 9.81, rel=0.02)


def test_inspect_is_not_gated_it_warns(capsys):
    from flipstudy.study.cli import main
    assert main(["inspect", str(shared_file("88_01.bvh"))]) == 0
    assert "Rerun with --fps 60" in capsys.readouterr().out
