"""The closed-form rotation log used by the angular velocities, against scipy."""
import numpy as np
from hypothesis import given, settings, strategies as st
from scipy.spatial.transform import Rotation

from flipstudy.stimuli.motion.clip import angular_velocity, rotation_log


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3),
       st.floats(0.0, np.pi - 1e-6), st.floats(1e-12, 1.0))
def test_rotation_log_is_scipys_rotvec(axis, angle, tiny):
    a = np.array(axis)
    if np.linalg.norm(a) < 1e-3:
        a = np.array([0.0, 0.0, 1.0])
    a = a / np.linalg.norm(a)
    for th in (angle, angle * tiny):                 # moderate and very small turns
        v = a * th
        R = Rotation.from_rotvec(v).as_matrix()
        assert np.allclose(rotation_log(R), Rotation.from_matrix(R).as_rotvec(), atol=1e-12)


def test_angular_velocity_of_a_constant_spin_is_exact():
    w = np.array([1.5, -7.0, 3.0])                   # rad/s
    fps = 60.0
    t = np.arange(40) / fps
    R = Rotation.from_rotvec(t[:, None] * w).as_matrix()
    assert np.allclose(angular_velocity(R, fps), w, atol=1e-10)
