"""Issue 45, the cosmetic ones: ``inspect`` printed a fitted mass's momentum change
as ``(−-2.6 %)``, and a probability or level of 99.999999 % as ``100 %``."""
from __future__ import annotations


def test_the_momentum_change_of_a_mass_fit_has_one_sign():
    from flipstudy.study.motions import _signed
    assert _signed(-2.6) == "−2.6"          # a reduction of 2.6 %
    assert _signed(2.6) == "+2.6"           # an increase (a negative reduction): was "−-2.6"
    assert "−-" not in _signed(-(-2.6)) and "−-" not in _signed(-2.6)


def test_a_probability_short_of_certain_is_not_printed_as_100_percent():
    from flipstudy.stimuli.score import _pct
    assert _pct(0.99999999) == "> 99.9 %"
    assert _pct(1e-9) == "< 0.1 %"
    assert _pct(1.0) == "100.0 %" and _pct(0.0) == "0.0 %" and _pct(0.5) == "50.0 %"


def test_a_level_is_shown_as_written():
    from flipstudy.stimuli._designkeys import _pct
    assert _pct(99.999999) == "99.999999"
    assert _pct(17.5) == "17.5" and _pct(200.0) == "200" and _pct(float("inf")) == "inf"
