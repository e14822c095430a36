"""A stimulus against its original: |L| at the same clock time, over the span both are in
the air (``inspect --compare`` prints it, ``edit --plot`` and ``inspect --plot`` draw it)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LChange:
    """|L| of ``stim`` against ``original``, both clocks from the original's take-off frame."""
    t: np.ndarray               # s, the stimulus's frames inside both flights
    pct: np.ndarray             # 100 (|L_stim| / |L_orig| − 1) at those instants
    L_mean_stim: float          # flight mean |L|, kg·m²/s
    L_mean_orig: float
    flight_s_stim: float
    flight_s_orig: float

    def summary(self) -> str:
        d = 100 * (self.L_mean_stim / self.L_mean_orig - 1)
        s = (f"flight |L| mean {self.L_mean_stim:.2f} vs {self.L_mean_orig:.2f} kg·m²/s ({d:+.1f} %), "
             f"flight {self.flight_s_stim:.3f} vs {self.flight_s_orig:.3f} s")
        if self.pct.size:
            s += (f"; |L| change at the same clock time while both fly: median {np.median(self.pct):+.1f} %, "
                  f"range {self.pct.min():+.1f} to {self.pct.max():+.1f} %")
        return s


def l_change(stim, original) -> LChange | None:
    """:class:`LChange` of two analyses (``None`` unless both have a flight).

    >>> from flipstudy.stimuli import analyse, builtin
    >>> a = analyse(builtin("backflip"))
    >>> c = l_change(a, a)
    >>> float(abs(c.pct).max()), c.summary()[:40]
    (0.0, 'flight |L| mean 46.87 vs 46.87 kg·m²/s (')
    """
    if stim.flight is None or original.flight is None:
        return None
    t0 = original.takeoff
    to = (np.arange(original.clip.num_frames) - t0) / original.clip.fps
    ts = (np.arange(stim.clip.num_frames) - t0) / stim.clip.fps
    Lo, Ls = np.linalg.norm(original.L, axis=1), np.linalg.norm(stim.L, axis=1)
    fr = np.arange(stim.takeoff, stim.landing + 1)
    lo, hi = (original.takeoff - t0) / original.clip.fps, (original.landing - t0) / original.clip.fps
    fr = fr[(ts[fr] >= lo - 1e-9) & (ts[fr] <= hi + 1e-9)]       # both in the air
    pct = 100 * (Ls[fr] / np.maximum(np.interp(ts[fr], to, Lo), 1e-9) - 1)
    return LChange(ts[fr], pct, float(Ls[stim.flight_frames].mean()),
                   float(Lo[original.flight_frames].mean()), float(stim.flight_s), float(original.flight_s))
