"""flipstudy.stimuli.measure against closed forms that share none of its
assumptions (a frame time's effect on gravity, known added slides, dips and
velocity steps) and on the CMU captures' known traps."""
from __future__ import annotations

import json
import numpy as np
import pytest

from flipstudy import builtin, load_bvh
from flipstudy.stimuli.measure import Measurement, measure



def size(m: Measurement, kind, phase, variant=""):
    got = m.get(kind, variant, phase)
    assert len(got) == 1, (kind, phase, m.warnings)
    return got[0].size


@pytest.mark.parametrize("name", ["88_01", "87_03"])
def test_wrong_header_frame_time_is_a_gravity_error(name, shared_path):
    """The una-dinosauria headers say 120 Hz for a 60 Hz capture (SOURCES.md): read
    with the header's frame time, the same frames fall (120/60)² = 4× as fast, so
    1 + gravity % / 100 is exactly 4× the one read at 60 fps; and the warning names
    the fix."""
    path = shared_path(f"mocap/{name}.bvh")
    header = measure(load_bvh(path))
    right = measure(load_bvh(path, fps=60))
    g120, g60 = size(header, "gravity", "flight 1"), size(right, "gravity", "flight 1")
    assert g120 > 200.0                                  # ≈ +330 … +385 %: the trap shows
    assert abs(g60) < 25.0                               # a real capture's own departure
    assert (1 + g120 / 100) / (1 + g60 / 100) == pytest.approx(4.0, rel=0.01)
    assert any("60 fps" in w for w in header.warnings)
    assert any("T-pose" in w for w in header.warnings)      # the raw CMU frame 1, dropped
    assert not any("60 fps instead" in w for w in right.warnings)


def test_retargeted_lengths_are_a_gravity_error(shared_path):
    """MASS's retarget of 88_01 scales the trajectories to a bigger rig but not time
    (SOURCES.md: g ≈ 14.5–15.4 m/s² at its true 60 Hz): +48 … +57 % of 9.81, and the
    analyser's warning in the measurement says the lengths are scaled."""
    path = shared_path("mocap/88_01_mass-retarget.bvh")
    with pytest.warns(UserWarning, match="implausible for a hand"):
        m = measure(load_bvh(path, fps=60))
    assert 48.0 <= size(m, "gravity", "flight 1") <= 57.0
    assert any("lengths are probably scaled" in w for w in m.warnings)


def test_real_clips_measure_every_phase_without_nan(shared_path):
    m = measure(load_bvh(shared_path("mocap/90_11.bvh")))
    assert [p[1] for p in m.phases].count("flight") == 3          # its three flights
    assert all(np.isfinite(i.size) for i in m.items)
    json.dumps(m.to_dict())
    assert len(m.table()) == len(m.items)


def _stand(clip):
    """Frames of the built-in's final stand (the last 0.6 s)."""
    return np.arange(clip.num_frames) / clip.fps >= (clip.num_frames - 1) / clip.fps - 0.6


@pytest.mark.parametrize("mm", [10.0, 30.0])
def test_a_known_slide_is_the_foot_skate(mm):
    """The whole body slid sideways by ``mm`` over the final stand: both feet slide that far."""
    c = builtin("backflip")
    t = np.arange(c.num_frames) / c.fps
    st = _stand(c)
    s = np.clip((t - t[st][0]) / 0.4, 0.0, 1.0) * mm / 1000
    root = c.root_pos.copy()
    root[:, 0] += s
    m = measure(c.replace(root_pos=root))
    assert size(m, "foot-skate", "ground 1") == pytest.approx(mm, abs=0.5)
    assert size(m, "foot-skate", "ground 0") < 0.5


@pytest.mark.parametrize("dy,kind", [(-0.02, "penetration"), (0.02, "floating")])
def test_a_known_dip_or_lift_on_the_ground(dy, kind):
    """The body lowered (raised) by 20 mm for 0.1 s of the final stand (under 5 % of
    the feet's contact time, which sets their level): the feet go 20 mm into (above)
    the floor; the other ground phase stays ≈ 0."""
    c = builtin("backflip")
    t = np.arange(c.num_frames) / c.fps
    st = _stand(c)
    w = (t >= t[st][0] + 0.1) & (t < t[st][0] + 0.2)
    root = c.root_pos.copy()
    root[w, 1] += dy
    m = measure(c.replace(root_pos=root))
    assert size(m, kind, "ground 1") == pytest.approx(20.0, abs=0.5)
    assert size(m, kind, "ground 0") < 0.5


@pytest.mark.parametrize("dv", [0.2, 0.5])
def test_a_known_velocity_step_in_the_air_is_the_jolt(dv):
    """The root pushed sideways by ``dv`` m/s from mid-flight (and held after touchdown):
    the air jolt is ``dv``, gravity stays."""
    c = builtin("backflip")
    t = np.arange(c.num_frames) / c.fps
    t_to, t_ld = c.meta["takeoff"] / c.fps, c.meta["takeoff"] / c.fps + c.meta["flight_s"]
    tk = 0.5 * (t_to + t_ld) + 0.25 / c.fps
    root = c.root_pos.copy()
    root[:, 0] += dv * np.clip(t - tk, 0.0, t_ld - tk)
    m = measure(c.replace(root_pos=root))
    assert size(m, "air-jolt", "flight 1") == pytest.approx(dv, rel=0.03)
    assert abs(size(m, "gravity", "flight 1")) < 0.1
    assert m.get("air-jolt", phase="flight 1")[0].worst_t == pytest.approx(tk, abs=1.5 / c.fps)


def test_the_two_flip_backflips_take_off_jump_is_measured():
    """Issue 30's example: ``edit backflip --flips 2`` (0.7·k*) writes a take-off whose
    COM goes from about 3 to 6 m/s upward in one frame.  The measured |Δv| agrees with
    an independent finite difference of the COM across the contact (the frame
    intervals either side; they sit half a frame from the instant, so within 0.2 m/s)."""
    from flipstudy import analyse
    from flipstudy.stimuli.edit.multiflip import multiflip
    r = multiflip(builtin("backflip"), 2, k_ratio=0.7)        # the paper's k (k* is the default)
    clip = getattr(r, "clip", r)
    m = measure(clip)
    jump = size(m, "takeoff-velocity-jump", "takeoff 1")
    a = analyse(clip, estimate=False)
    v = np.diff(a.com, axis=0) * clip.fps               # velocity over each frame interval
    k = int(np.floor(m.get("takeoff-velocity-jump", phase="takeoff 1")[0].worst_t * clip.fps + 1e-6))
    fd = float(np.linalg.norm(v[k] - v[k - 1]))
    assert fd > 2.5
    assert jump == pytest.approx(fd, abs=0.2)
    assert size(m, "vertical-velocity", "takeoff 1") > 80.0     # 3 → 6 m/s upward
    assert abs(size(m, "gravity", "flight 1")) < 0.5             # the flight itself falls freely


def test_measurement_json_round_trip(tmp_path):
    """A measurement written as JSON and read back is the same measurement."""
    c = builtin("frontflip")
    m = measure(c)
    p = tmp_path / "m.json"
    p.write_text(json.dumps(m.to_dict(), allow_nan=False))
    back = Measurement.from_dict(json.loads(p.read_text()))
    assert back == m
    assert back.table().equals(m.table())
