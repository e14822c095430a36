"""What a group's levels measure, and the error magnitude the fits use.

Most error kinds have a signed level in percent and the magnitude ``|level|`` %.
A ``pose-rate`` group (responses column ``kind``) has levels in poses per second,
``N``, with 0 the original motion: fewer poses per second is the larger error,
so its magnitude is the time each pose is held, ``1000 / N`` ms, and the
original (level 0) sits at 0 ms.

Why the hold ``1000/N`` and not the hold added to the clip's own
``1000/N − 1000/fps``: ``responses.csv`` does not carry the clip's frame rate
and a group may pool clips of different rates; every tested N is below the
frame rate (the stimuli refuse N ≥ fps), so ``1000/N`` orders the levels the
same way, and a threshold in ms maps back to poses per second by ``1000/x*``
with no frame rate needed.  (At 60 fps the original itself holds each pose
16.7 ms; it is drawn at 0.)

>>> magnitudes([0, 10, 20, -17], ["pose-rate", "pose-rate", "pose-rate", "gravity"])
array([  0., 100.,  50.,  17.])
>>> level_unit("pose-rate"), magnitude_unit("pose-rate"), magnitude_unit(None)
('poses/s', 'ms', '%')
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from flipstudy.vocab import kinds

#: the error kind whose levels are poses per second (declared in flipstudy.vocab.kinds)
POSE_RATE = kinds.POSE_RATE.name


def group_kinds(df: pd.DataFrame) -> dict:
    """``{group: kind}`` for the groups whose rows name one kind (column ``kind``;
    the originals' rows, level 0, may carry another and are not asked); empty
    without a ``kind`` column."""
    if "kind" not in df.columns:
        return {}
    out = {}
    for g, sub in df.groupby("group", sort=False):
        rows = sub[sub["level"] != 0]
        ks = set((rows if len(rows) else sub)["kind"].dropna().astype(str))
        if len(ks) == 1:
            out[g] = ks.pop()
    return out


def is_pose_rate(kind) -> bool:
    """Whether a group of this kind has levels in poses per second."""
    return kind == POSE_RATE


def magnitudes(levels, kinds=None) -> np.ndarray:
    """The error magnitude of each level: ``1000 / N`` ms for a pose-rate level N
    (0 for the original, N = 0), ``|level|`` otherwise.  ``kinds``: one kind, or one
    per level, or None (all percent)."""
    lv = np.asarray(levels, float)
    pr = np.broadcast_to(np.asarray([is_pose_rate(k) for k in np.atleast_1d(np.asarray(kinds, object))])
                         if kinds is not None else False, lv.shape)
    with np.errstate(divide="ignore"):
        hold = np.where(lv > 0, 1000.0 / np.where(lv > 0, lv, 1.0), 0.0)
    return np.where(pr, hold, np.abs(lv))


def pose_rate_of(hold_ms) -> np.ndarray:
    """Poses per second of a hold time in ms (the inverse of :func:`magnitudes`)."""
    return 1000.0 / np.asarray(hold_ms, float)


def level_unit(kind) -> str:
    """The unit the levels of a group of ``kind`` are written in (its registry entry's)."""
    entry = kinds.find(kind) if isinstance(kind, str) else None
    return entry.level_unit if entry is not None else "%"


def magnitude_unit(kind) -> str:
    """The unit of the error magnitude (fits, thresholds) of a group of ``kind``."""
    return "ms" if is_pose_rate(kind) else "%"


def magnitude_label(kind) -> str:
    """The x-axis label of a psychometric panel of a group of ``kind``."""
    if is_pose_rate(kind):
        return "time each pose is held, 1000/N (ms)"
    return "error magnitude |level| (%)"


def level_label(kind) -> str:
    """The x-axis label of a ratings or d′ panel of a group of ``kind``."""
    return "pose rate N (poses/s; 0: original)" if is_pose_rate(kind) else "error level (%)"
