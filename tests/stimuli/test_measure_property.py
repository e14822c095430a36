"""Property tests of flipstudy.stimuli.measure: any error a construction of
known size puts into a built-in's flight comes back from the motion alone
(gravity and added horizontal acceleration exactly, |L| steps and take-off
velocity components within 1 point)."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings, strategies as st

from flipstudy import analyse, builtin
from flipstudy.stimuli.ballistic import inject_kind
from flipstudy.stimuli.injection import inject_angular_momentum
from flipstudy.stimuli.measure import measure, split_trend_step

A = analyse(builtin("backflip"))
E = st.floats(-0.3, 0.3).filter(lambda e: abs(e) > 0.02)


def one(m, kind, variant, phase):
    got = m.get(kind, variant, phase)
    assert len(got) == 1
    return got[0].size


@settings(max_examples=8, deadline=None)
@given(e=E)
def test_gravity_any_size(e):
    m = measure(inject_kind(A, "gravity", e, "flight-time").clip)
    want = 100 * ((1 + e) * A.apparent_gravity / 9.81 - 1)
    assert abs(one(m, "gravity", "", "flight 1") - want) < 0.05


@settings(max_examples=8, deadline=None)
@given(e=E)
def test_horizontal_acceleration_any_size(e):
    m = measure(inject_kind(A, "acceleration", e, "horizontal").clip)
    assert abs(one(m, "acceleration", "horizontal", "flight 1") - 100 * e) < 0.05
    assert abs(one(m, "takeoff-angle", "", "takeoff 1")) < 1.0


@settings(max_examples=8, deadline=None)
@given(e=E)
def test_abrupt_angular_momentum_any_size(e):
    m = measure(inject_angular_momentum(A, e, "abrupt").clip)
    assert abs(one(m, "angular-momentum", "abrupt", "flight 1") - 100 * e) < 1.0
    assert abs(one(m, "angular-momentum", "smooth", "flight 1")) < 1.5


@settings(max_examples=8, deadline=None)
@given(e=E)
def test_horizontal_velocity_any_size(e):
    m = measure(inject_kind(A, "horizontal-velocity", e).clip)
    assert abs(one(m, "takeoff-angle", "", "takeoff 1") - 100 * e) < 1.0


@settings(max_examples=30, deadline=None)
@given(L0=st.floats(5, 80), trend=st.floats(-0.5, 0.5), step=st.floats(-0.5, 0.5),
       where=st.floats(0.2, 0.8), n=st.integers(20, 120))
def test_split_trend_step_recovers_a_line_and_a_step(L0, trend, step, where, n):
    """The closed form it fits: |L| = L0·(1 + trend·τ/T) with a step of ``step`` × the
    line at its instant, halfway between two samples near ``where``·T: trend, step
    and instant come back exactly."""
    T = 0.6
    tau = np.linspace(0, T, n)
    k = int(np.searchsorted(tau, where * T))
    line = L0 * (1 + trend * tau / T)
    t_step = 0.5 * (tau[k - 1] + tau[k])
    before = L0 * (1 + trend * t_step / T)
    L = line + np.where(np.arange(n) >= k, step * before, 0.0)
    s, a, t_found, _ = split_trend_step(tau, L, T)
    if abs(step) > 0.01:
        assert abs(a - 100 * step) < 1e-6 and abs(s - 100 * trend) < 1e-6
        assert abs(t_found - t_step) < 1e-9
