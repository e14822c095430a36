"""flipstudy.stimuli.measure against closed forms that share none of its
assumptions (a frame time's effect on gravity, known added slides, dips and
velocity steps) and on the CMU captures' known traps."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from flipstudy import builtin, load_bvh
from flipstudy.stimuli.measure import Measurement, measure

MOCAP = Path(__file__).resolve().parents[1] / ".." / "shared" / "mocap"
need_mocap = pytest.mark.skipif(not (MOCAP / "88_01.bvh").exists(),
                                reason="needs the CMU clips in ../shared/mocap")


def size(m: Measurement, kind, phase, variant=""):
    got = m.get(kind, variant, phase)
    assert len(got) == 1, (kind, phase, m.warnings)
    return got[0].size


@need_mocap
@pytest.mark.parametrize("name", ["88_01", "87_03"])
def test_wrong_header_frame_time_is_a_gravity_error(name):
    """The una-dinosauria headers say 120 Hz for a 60 Hz capture (SOURCES.md): read
    with the header's frame time, the same frames fall (120/60)² = 4× as fast, so
    1 + gravity % / 100 is exactly 4× the one read at 60 fps; and the warning names
    the fix."""
    header = measure(load_bvh(MOCAP / f"{name}.bvh"))
    right = measure(load_bvh(MOCAP / f"{name}.bvh", fps=60))
    g120, g60 = size(header, "gravity", "flight 1"), size(right, "gravity", "flight 1")
    assert g120 > 200.0                                  # ≈ +330 … +385 %: the trap shows
    assert abs(g60) < 25.0                               # a real capture's own departure
    assert (1 + g120 / 100) / (1 + g60 / 100) == pytest.approx(4.0, rel=0.01)
    assert any("60 fps" in w for w in header.warnings)
    assert not any("60 fps instead" in w for w in right.warnings)


@need_mocap
def test_real_clips_measure_every_phase_without_nan():
    m = measure(load_bvh(MOCAP / "90_11.bvh"))
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
    """The body lowered (raised) by 20 mm for 0.08 s of the final stand (under 5 % of
    the feet's contact time, which sets their level): the feet go 20 mm into (above)
    the floor; the other ground phase stays ≈ 0."""
    c = builtin("backflip")
    t = np.arange(c.num_frames) / c.fps
    st = _stand(c)
    w = (t >= t[st][0] + 0.1) & (t < t[st][0] + 0.18)
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
