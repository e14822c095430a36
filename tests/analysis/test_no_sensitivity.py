"""Issue 33: a participant who answers "incorrect" on every trial has no threshold.
Answers whose share does not grow with the error size show no sensitivity: the fit says
"not reached", and every interval bound it reports lies inside the tested levels."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flipstudy.analysis.stats import fit_psignifit, shows_sensitivity

LEVELS = np.array([0.0, 17, 25, 37, 50])


def inside(fit):
    for b in (fit.ci_low, fit.ci_high):
        assert np.isnan(b) or LEVELS.min() <= b <= LEVELS.max()


def test_all_incorrect_is_not_reached_with_bounds_in_the_level_range():
    n = np.full(5, 8.0)
    f = fit_psignifit("smooth-increase", LEVELS, n.copy(), n)
    assert not f.reached and np.isnan(f.threshold)
    assert "no sensitivity" in f.note
    inside(f)


@pytest.mark.slow
@pytest.mark.parametrize("k", [0, 4])
def test_the_same_share_at_every_level_is_never_a_threshold(k):
    n = np.full(5, 8.0)
    f = fit_psignifit("g", LEVELS, np.full(5, float(k)), n)
    assert not f.reached
    inside(f)


@pytest.mark.slow
def test_a_rising_share_still_has_its_threshold_inside_the_levels():
    n = np.full(5, 20.0)
    k = np.array([1.0, 4, 9, 16, 19])              # crosses (1 + γ)/2 between 17 and 37
    f = fit_psignifit("g", LEVELS, k, n)
    assert f.reached and 17 <= f.threshold <= 37
    inside(f)


@given(st.lists(st.integers(0, 10), min_size=2, max_size=6))
def test_sensitivity_is_the_sign_of_the_weighted_slope(ks):
    x = np.arange(len(ks), dtype=float)
    k = np.array(ks, float)
    n = np.full(len(ks), 10.0)
    assert shows_sensitivity(x, k, n) == (np.polyfit(x, k / n, 1)[0] > 1e-9)
