"""Issue 33: ``inspect --compare`` prints numbers.  Known value: the same flight played
k times faster has k times the angular momentum (L ∝ dθ/dt), and in flight |L| is
conserved, so at every instant both are in the air the change is 100 (k − 1) %."""
import json

import numpy as np
import pytest

from flipstudy.stimuli import analyse, builtin, save_bvh
from flipstudy.stimuli.lchange import l_change
from flipstudy.study.cli import main


@pytest.mark.parametrize("k", [0.8, 1.25])
def test_a_faster_flight_has_k_times_the_angular_momentum(k):
    clip = builtin("backflip")
    orig = analyse(clip)
    fast = analyse(clip.with_fps(clip.fps * k), body=orig.body, estimate=False)
    ch = l_change(fast, orig)
    assert ch.L_mean_stim / ch.L_mean_orig == pytest.approx(k, rel=0.01)
    assert ch.flight_s_stim == pytest.approx(ch.flight_s_orig / k, rel=0.02)
    assert np.median(ch.pct) == pytest.approx(100 * (k - 1), abs=1.0)
    lo, hi = orig.takeoff / clip.fps, orig.landing / clip.fps
    assert ch.t.min() >= -1e-9 and ch.t.max() <= hi - lo + 1e-9       # only while both fly


def test_inspect_compare_prints_the_numbers_without_a_plot(tmp_path, capsys):
    clip = builtin("backflip")
    save_bvh(clip.with_fps(clip.fps * 1.25), tmp_path / "fast.bvh")
    assert main(["inspect", str(tmp_path / "fast.bvh"), "--compare", "backflip", "--json"]) == 0
    c = json.loads(capsys.readouterr().out)["compare"]
    assert c["L_mean"] / c["L_mean_original"] == pytest.approx(1.25, rel=0.01)
    assert c["L_change_pct_median"] == pytest.approx(25, abs=1.0)
    assert main(["inspect", str(tmp_path / "fast.bvh"), "--compare", "backflip"]) == 0
    out = capsys.readouterr().out
    assert "against backflip: flight |L| mean" in out and "median +25" in out
