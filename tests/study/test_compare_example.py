"""The README's comparison example on the real CMU takes: docs/examples/compare_models.py
makes the ground truth as HumanML3D-layout joint positions with SOURCES.md's fixes
(60 Hz, no T-pose) and two degraded sources, and the design builds into a
comparison study through the loading rule's position reader."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from _shared import MOCAP, shared_file

from flipstudy import analyse, load_bvh
from flipstudy.stimuli.contract import StimulusSet
from flipstudy.stimuli.design import Design
from flipstudy.stimuli.stimset import build_stimuli

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "compare_models.py"
pytestmark = pytest.mark.shared


def _example():
    spec = importlib.util.spec_from_file_location("compare_models", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    for f in ("88_01.bvh", "87_03.bvh", "90_11.bvh"):
        shared_file(f)
    root = tmp_path_factory.mktemp("example")
    design = _example().make_sources(root, MOCAP)
    build_stimuli(Design.from_toml(design), root / "study", progress=False)
    return root


def test_the_ground_truth_is_the_take_at_its_true_rate_without_the_t_pose(example):
    """gt/88_01.npz: the take's joints at the SMPL body joints, 60 Hz, frame 1 (the
    T-pose) dropped once, by the loader (issue 42: the example dropped another); read back through the loading rule its flight's gravity is
    near 9.81 m/s² (SOURCES.md: 10.7-11.7 for a rough COM at 1/60 s, 43-47 at the
    header's 1/120 s)."""
    from flipstudy.stimuli.loading import load_clip
    raw = load_bvh(MOCAP / "88_01.bvh", fps=60.0)
    assert raw.meta["dropped_frames"] == [0]        # the loader already dropped the T-pose
    with np.load(example / "gt" / "88_01.npz") as z:
        X, fps = z["joints"], float(z["fps"])
    assert X.shape == (raw.num_frames, 22, 3) and fps == 60.0      # no second frame dropped
    hips = raw.joint_positions()[:, raw.skeleton.index("Hips")]
    np.testing.assert_allclose(X[:, 0], hips, atol=1e-5)                 # SMPL joint 0: the pelvis
    clip = load_clip(str(example / "gt" / "88_01.npz"))
    assert clip.fps == 60.0 and 8.5 < analyse(clip).apparent_gravity < 12.5


def test_the_models_are_degraded_copies_of_the_same_items(example):
    def joints(s):
        with np.load(example / s / "87_03.npz") as z:
            return z["joints"]
    gt, jit, flo = joints("gt"), joints("jitter"), joints("floaty")
    assert gt.shape == jit.shape == flo.shape
    # the floating copy's pelvis ends 6 cm higher; the jittered one is the take at times off by
    # a fraction of a frame: within two frames' travel of the take, never the same
    dy = flo[:, 0, 1] - gt[:, 0, 1]
    assert dy[-1] == pytest.approx(0.06, abs=0.01) and abs(dy[0]) < 0.01
    d = np.linalg.norm(jit - gt, axis=2)
    step = np.linalg.norm(np.diff(gt, axis=0), axis=2)
    assert d.max() > 0.005 and np.all(d[1:-1] <= 2 * np.maximum(step[1:], step[:-1]) + 1e-5)


def test_the_example_builds_a_comparison_study_of_three_sources(example):
    st = StimulusSet.read(example / "study")
    assert st.sources() == ["gt", "jitter", "floaty"] and len(st) == 9
    assert {s.clip for s in st} == {"88_01", "87_03", "90_11"} and {s.fps for s in st} == {60.0}
    assert all(s.landing > s.takeoff > 0 for s in st)             # every clip keeps its flight
