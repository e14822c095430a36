"""The injectors the error-kind registry (:mod:`flipstudy.vocab.kinds`) names: each
builds the stimulus of one design group at one level, with one signature
``(analysis, group, level, design) -> Injected``, so that
:func:`flipstudy.stimuli.stimset.make_stimulus` picks none by name."""
from __future__ import annotations

from .analyse import Analysis
from .ballistic import inject_kind
from .injection import Injected, inject_angular_momentum, inject_takeoff_angle


def build_angular_momentum(a: Analysis, group, level: float, design) -> Injected:
    """A group's angular-momentum stimulus (its profile, the design's ``com_policy``)."""
    return inject_angular_momentum(a, group.sign * level / 100.0, group.profile, design.com_policy)


def build_takeoff_angle(a: Analysis, group, level: float, design) -> Injected:
    """A group's take-off angle stimulus."""
    return inject_takeoff_angle(a, group.sign * level / 100.0)


def build_ballistic(a: Analysis, group, level: float, design) -> Injected:
    """A group's stimulus of a kind of :mod:`flipstudy.stimuli.ballistic` (its option:
    policy, axis or span; a pose-rate level is the rate)."""
    return inject_kind(a, group.kind, group.sign * level / 100.0,
                       group.policy or group.axis or group.span, rate=level)
