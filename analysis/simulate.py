"""Simulated response tables: the paper's panel and ideal signal-detection observers.

Used by the tests, the benchmark and the documentation figures; both return
the long format of DESIGN.md (one row per trial) with an extra ``clip`` column.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.special import expit, logit, ndtr

from flipstudy.vocab import kinds

#: Majkowska & Faloutsos 2007, Table 2: mean rating (% judged correct) and d′ per
#: group and level.  Minus signs lost in the text extraction are restored (each
#: checked against the ratings: z(1 − r) − z(1 − r₀)).  The smooth-increase 37 %
#: cell is empty in the paper; :data:`PAPER_FILL` gives the value used to simulate it.
PAPER_TABLE2 = {
    "smooth-increase": {"levels": (0, 17, 25, 37, 50),
                        "rating": (72, 71, 72, None, 41),
                        "dprime": (0.00, 0.05, 0.00, None, 0.81)},
    "smooth-decrease": {"levels": (0, 17, 25, 37, 50),
                        "rating": (72, 79, 78, 78, 62),
                        "dprime": (0.00, -0.22, -0.18, -0.18, 0.27)},
    "abrupt-increase": {"levels": (0, 17, 25, 37, 50),
                        "rating": (72, 76, 78, 48, 44),
                        "dprime": (0.00, -0.13, -0.18, 0.63, 0.75)},
    "abrupt-decrease": {"levels": (0, 17, 25, 37, 50),
                        "rating": (72, 83, 68, 33, 22),
                        "dprime": (0.00, -0.38, 0.11, 1.0, 1.4)},
    "takeoff-increase": {"levels": (0, 10, 20, 30, 40),
                         "rating": (63, 81, 50, 63, 18),
                         "dprime": (0.00, -0.53, 0.34, 0.00, 1.3)},
}
#: the missing smooth-increase 37 % rating, interpolated linearly between 25 % (72) and 50 % (41)
PAPER_FILL = {("smooth-increase", 37): 57}

_BASE_TIME = np.datetime64("2026-01-05T10:00:00")


def paper_ratings() -> pd.DataFrame:
    """Table 2 as a long table: group, level, rating_pct, dprime (NaN for the missing cell),
    and ``rating_sim`` (the rating used to simulate, the missing cell filled)."""
    rows = []
    for g, t in PAPER_TABLE2.items():
        for lv, r, d in zip(t["levels"], t["rating"], t["dprime"]):
            rows.append((g, float(lv), np.nan if r is None else float(r),
                         np.nan if d is None else float(d),
                         float(PAPER_FILL.get((g, lv), r))))
    return pd.DataFrame(rows, columns=["group", "level", "rating_pct", "dprime", "rating_sim"])


def _assemble(participant, group, level, clip, rep, incorrect, rng, n_part, per_part) -> pd.DataFrame:
    """Shuffle each participant's trials, number them, add timings."""
    N = len(participant)
    order = np.lexsort((rng.random(N), participant))        # random order within participant
    participant, group, level, clip, rep, incorrect = (a[order] for a in
                                                       (participant, group, level, clip, rep, incorrect))
    trial = np.tile(np.arange(1, per_part + 1), n_part)
    rt = np.round(np.exp(rng.normal(np.log(1400), 0.35, N))).astype(int)
    shown = np.round(rng.normal(2400, 15, N)).astype(int)
    t = _BASE_TIME + (participant.astype(np.int64) * 3600 * 1000).astype("timedelta64[ms]") \
        + np.cumsum(rt + shown + 800).astype("timedelta64[ms]")
    width = max(2, len(str(n_part)))
    pid = np.char.add("P", np.char.zfill(participant.astype(str), width))
    lv_txt = np.where(level == np.round(level), level.astype(int).astype(str), level.astype(str))
    return pd.DataFrame({
        "participant": pid,
        "session": np.char.add(pid, "-S1"),
        "trial": trial,
        "stimulus": np.where(group == "original", np.char.add(clip, "_original"),  # as in the manifest
                             np.char.add(np.char.add(np.char.add(np.char.add(clip, "_"), group), "_"),
                                         lv_txt)),
        "group": group,
        "level": level,
        "repetition": rep,
        "response": np.where(incorrect, "incorrect", "correct"),
        "rt_ms": rt,
        "shown_ms": shown,
        "timestamp": np.datetime_as_string(t, unit="ms"),
        "clip": clip,
    })


def _design(groups_levels, n_participants, clips, repetitions):
    cells = [(g, float(lv)) for g, lvs in groups_levels for lv in lvs]
    per_part = len(cells) * len(clips) * repetitions
    base_g = np.array([g for g, _ in cells for _c in clips for _r in range(repetitions)])
    base_l = np.array([lv for _, lv in cells for _c in clips for _r in range(repetitions)])
    base_c = np.array([c for _ in cells for c in clips for _r in range(repetitions)])
    base_r = np.array([r + 1 for _ in cells for _c in clips for r in range(repetitions)])
    P = n_participants
    participant = np.repeat(np.arange(1, P + 1), per_part)
    return (cells, per_part, participant, np.tile(base_g, P), np.tile(base_l, P), np.tile(base_c, P),
            np.tile(base_r, P))


def _kind(group: str) -> str:
    return kinds.TAKEOFF_ANGLE.name if "takeoff" in group else kinds.AM.name


def paper_panel(n_participants: int = 19, *, clips=("backflip", "frontflip"), repetitions: int = 2,
                participant_sd: float = 0.5, seed=0, ratings: pd.DataFrame | None = None,
                original: str = "shared") -> pd.DataFrame:
    """A simulated panel of the paper's study (Section 7), each motion (2 clips)
    shown twice.  ``original="shared"`` (the paper's design and the default
    design's): the four angular-momentum groups share one original per clip
    (group ``original``, answered with their level-0 rating, 72) and the take-off
    group has its own (63): 22 motions per clip, 88 trials per participant.
    ``"per-group"``: every group its own level 0, 100 trials.  The table has a
    ``kind`` column (groups named ``takeoff…`` are take-off groups).

    Each answer is "correct" with the probability of the paper's Table 2 rating
    for its cell (the missing smooth-increase 37 % cell filled with
    :data:`PAPER_FILL`), shifted per participant by a normal bias of standard
    deviation ``participant_sd`` on the logit scale (0 = every participant
    answers with the table's probabilities).  ``ratings`` may replace the table
    (columns group, level, rating_sim or rating_pct).
    """
    rng = np.random.default_rng(seed)
    tab = paper_ratings() if ratings is None else ratings
    col = "rating_sim" if "rating_sim" in tab.columns else "rating_pct"
    if original not in ("shared", "per-group"):
        raise ValueError(f"original: expected 'shared' or 'per-group', got {original!r}")
    groups_levels = [(g, list(sub["level"])) for g, sub in tab.groupby("group", sort=False)]
    prob = {(g, float(lv)): r / 100.0 for g, lv, r in zip(tab["group"], tab["level"], tab[col])}
    if original == "shared":
        am0 = [prob[(g, 0.0)] for g, lvs in groups_levels
               if _kind(g) == kinds.AM.name and 0.0 in map(float, lvs)]
        if am0:
            groups_levels = [(g, [lv for lv in lvs if not (float(lv) == 0 and _kind(g) == kinds.AM.name)])
                             for g, lvs in groups_levels] + [("original", [0.0])]
            prob[("original", 0.0)] = float(np.mean(am0))
    cells, per_part, participant, group, level, clip, rep = _design(
        groups_levels, n_participants, tuple(clips), repetitions)
    p_cell = np.array([prob[c] for c in cells])
    cell_idx = np.tile(np.repeat(np.arange(len(cells)), len(clips) * repetitions), n_participants)
    bias = rng.normal(0.0, participant_sd, n_participants) if participant_sd > 0 else np.zeros(n_participants)
    p_correct = expit(logit(np.clip(p_cell[cell_idx], 1e-6, 1 - 1e-6)) + bias[participant - 1])
    incorrect = rng.random(len(participant)) >= p_correct
    df = _assemble(participant, group, level, clip, rep, incorrect, rng, n_participants, per_part)
    df["kind"] = [_kind(g) for g in df["group"]]
    return df


def sdt_observers(dprimes: dict, *, n_participants: int = 40, trials_per_level: int = 40,
                  criterion_location: float = 0.6, group: str = "simulated", seed=0) -> pd.DataFrame:
    """Equal-variance Gaussian yes/no observers with a known d′ per level.

    On each trial an internal value is drawn, ``N(d′(level), 1)`` (``d′(0) = 0``
    for the original) and the answer is "incorrect" when it exceeds the fixed
    location ``criterion_location`` (so ``F = Φ(−k)`` and ``H = Φ(d′ − k)``).
    ``dprimes`` maps level → d′ (level 0 is added with d′ = 0) or group →
    {level: d′}.  Every participant sees ``trials_per_level`` trials per level.
    """
    if dprimes and all(isinstance(v, dict) for v in dprimes.values()):
        spec = {g: {0.0: 0.0, **{float(k): float(v) for k, v in d.items()}} for g, d in dprimes.items()}
    else:
        spec = {group: {0.0: 0.0, **{float(k): float(v) for k, v in dprimes.items()}}}
    rng = np.random.default_rng(seed)
    groups_levels = [(g, sorted(d)) for g, d in spec.items()]
    cells, per_part, participant, grp, level, clip, rep = _design(
        groups_levels, n_participants, ("clip",), trials_per_level)
    mu = np.array([spec[g][lv] for g, lv in zip(grp, level)])
    incorrect = rng.normal(mu, 1.0) > criterion_location
    return _assemble(participant, grp, level, clip, rep, incorrect, rng, n_participants, per_part)


def expected_rates(dprime: float, criterion_location: float = 0.6) -> tuple[float, float]:
    """(H, F) of :func:`sdt_observers` for one d′."""
    return float(ndtr(dprime - criterion_location)), float(ndtr(-criterion_location))
