"""How likely is a viewer to notice what is physically wrong in a motion?

:func:`score` measures a clip's physical inconsistencies
(:func:`flipstudy.stimuli.measure.measure`: per ballistic and ground phase, each
in the unit of the study kind that injects it) and turns each into the
probability of being noticed through a calibration
(:mod:`flipstudy.stimuli.calibration`; the shipped default unless given).

* An error whose kind, variant and sign the calibration has a function for gets
  ``p`` (posterior median) with its 95 % interval; an error of a kind the
  calibration does not cover is reported with its measured size and ``p = None``
  ("measured, not scored"): no number is guessed.
* **Combination rule**: the probability that *anything* is noticed is
  ``1 − Π (1 − p_i)`` over the scored errors: independent detectors, the
  high-threshold model the per-error ``p`` already assumes (each error is either
  noticed, with p_i, or not; a viewer calls the motion wrong when any one is).
  Independence is an assumption (the studies vary one error at a time, so
  nothing measures how errors interact); the interval is over posterior draws
  combined draw by draw.  Unscored errors do not enter it: it is a lower bound
  when some error is unscored, and the result says so.
* The worst moment: the instant (``worst_t``) of the error most likely noticed.

>>> from flipstudy.stimuli import builtin
>>> r = score(builtin("backflip"))
>>> c = r.clips[0]
>>> c.p_any < 0.2, c.name
(True, 'backflip')
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np

from .calibration import Calibration, get_calibration
from .measure import Inconsistency, measure

RULE = ("P(anything noticed) = 1 − Π(1 − p_i) over the scored errors (independent detectors: each "
        "error is noticed or not, as the high-threshold reading of each calibrated function assumes; "
        "the studies vary one error at a time, so independence is assumed, not measured)")


@dataclass(frozen=True)
class ErrorScore(Inconsistency):
    """One measured inconsistency (the fields of :class:`~flipstudy.stimuli.measure.Inconsistency`)
    and, when calibrated, its probability of being noticed."""
    p: float | None = None             # None: measured, not scored (no calibration for it)
    p_low: float | None = None
    p_high: float | None = None
    calibration: str = ""             # which calibrated function scored it
    note: str = ""

    @property
    def scored(self) -> bool:
        return self.p is not None

    def label(self) -> str:
        return self.kind + (f" {self.variant}" if self.variant else "")


@dataclass(frozen=True)
class ClipScore:
    """A clip's errors, the probability that any is noticed and the worst moment."""
    name: str
    fps: float
    frames: int
    phases: tuple                      # ((label, t0, t1), ...) in seconds
    errors: tuple                      # ErrorScore, ...
    p_any: float
    p_any_low: float
    p_any_high: float
    worst: ErrorScore | None
    note: str = ""
    warnings: tuple = ()               # the measurement's (e.g. a frame time gravity contradicts)

    @property
    def n_unscored(self) -> int:
        """Errors of non-zero size measured but not scored."""
        return sum(not e.scored and e.size != 0 for e in self.errors)

    @property
    def duration(self) -> float:
        return (self.frames - 1) / self.fps if self.fps else 0.0

    def summary(self, brief: bool = False) -> str:
        """One line per error (``brief``: the scored ones; the unscored of size ≥ 1 in
        their unit on one line)."""
        lines = [f"{self.name}: P(anything noticed) = {_pct(self.p_any)} "
                 f"[{_pct(self.p_any_low)}, {_pct(self.p_any_high)}]"
                 + (f"; worst moment {self.worst.worst_t:.3f} s ({self.worst.label()})"
                    if self.worst is not None else "")]
        for e in self.errors:
            if brief and not e.scored:
                continue
            p = (f"p = {_pct(e.p)} [{_pct(e.p_low)}, {_pct(e.p_high)}]" if e.scored
                 else "measured, not scored")
            lines.append(f"  {e.label():33s} {e.phase:10s} {e.size:+9.2f} {e.unit:9s} "
                         f"{e.t0:6.3f}–{e.t1:6.3f} s  {p}" + (f"  ({e.note})" if e.note else ""))
        if brief:
            big = [e for e in self.errors if not e.scored and abs(e.size) >= 1]
            if big:
                lines.append("  not scored (no calibration), |size| ≥ 1: " + ", ".join(
                    f"{e.label()} {e.phase} {e.size:+.1f} {e.unit}" for e in big))
            lines.append(f"  ({sum(not e.scored for e in self.errors)} errors measured, not scored: "
                         f"`flipstudy score` lists all)")
        elif self.note:
            lines.append(f"  note: {self.note}")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["phases"] = [list(p) for p in self.phases]
        d["duration_s"] = self.duration
        return _clean(d)


@dataclass(frozen=True)
class ScoreResult:
    """What :func:`score` found for each clip, and how (calibration, rule)."""
    clips: tuple
    calibration: str
    rule: str = RULE

    def summary(self) -> str:
        if len(self.clips) == 1:
            return self.clips[0].summary() + f"\n(calibration: {self.calibration})"
        rows = [f"{'clip':28s} {'P(any)':>7s} {'95 % interval':>15s} {'unscored':>8s}  worst moment"]
        for c in self.clips:
            w = f"{c.worst.worst_t:.3f} s {c.worst.label()} ({_pct(c.worst.p)})" if c.worst else "-"
            rows.append(f"{c.name[:28]:28s} {_pct(c.p_any):>7s} "
                        f"{'[' + _pct(c.p_any_low) + ', ' + _pct(c.p_any_high) + ']':>15s} "
                        f"{c.n_unscored:8d}  {w}")
        rows.append("unscored: errors of non-zero size the calibration has no function for "
                    "(`flipstudy score CLIP` lists them)")
        return "\n".join(rows) + f"\n(calibration: {self.calibration})"

    def to_dict(self) -> dict:
        return {"calibration": self.calibration, "rule": self.rule,
                "clips": [c.to_dict() for c in self.clips]}

    def to_json(self, **kw) -> str:
        return json.dumps(self.to_dict(), ensure_ascii=False, **kw)


def _pct(p) -> str:
    """A probability in percent to 0.1, never rounded to a certainty it is not
    (``> 99.9 %``, ``< 0.1 %``)."""
    if p is None or not np.isfinite(p):
        return "-"
    v = 100.0 * float(p)
    if 99.95 <= v < 100.0:
        return "> 99.9 %"
    if 0.0 < v < 0.05:
        return "< 0.1 %"
    return f"{v:.1f} %"


def _clean(v):
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    if isinstance(v, (float, np.floating)):
        return None if not np.isfinite(v) else float(v)
    if isinstance(v, np.integer):
        return int(v)
    return v


def _phases(m) -> tuple:
    """((name, t0, t1), ...) of a :class:`~flipstudy.stimuli.measure.Measurement`."""
    return tuple((str(p[0]), float(p[2]), float(p[3])) for p in m.phases)


def score_measurement(items, cal: Calibration, *, task="yes-no", style=None, rng_draws=None):
    """ErrorScores of measured inconsistencies, and (p_any, low, high)."""
    errors, draws = [], []
    for it in items:
        size, same = float(it.size), getattr(it, "same_as", "")
        f = cal.lookup(it.kind, it.variant, 1 if size >= 0 else -1, task, style)
        base = dict(kind=it.kind, variant=it.variant or "", phase=str(it.phase), size=size, unit=str(it.unit),
                    t0=float(it.t0), t1=float(it.t1), worst_t=float(it.worst_t), same_as=same)
        if f is None:
            errors.append(ErrorScore(**base))
            continue
        p, lo, hi = f.p_noticed(abs(size))
        notes = [f"beyond the calibrated range (largest tested {f.max_level:g} {f.unit})"
                 if abs(size) > f.max_level else "",
                 f"the same departure as {same}: counted once" if same else ""]
        errors.append(ErrorScore(**base, p=float(p), p_low=float(lo), p_high=float(hi),
                                 calibration=f.describe(), note="; ".join(filter(None, notes))))
        if not same:                      # an item repeating another kind's is counted once
            draws.append(f.p_noticed_samples(abs(size)))
    if draws:
        n = min(len(d) for d in draws)
        miss = 1.0 - np.stack([d[:n] for d in draws])
        p_any_s = 1.0 - np.prod(miss, axis=0)
        p_any, lo, hi = (float(v) for v in np.quantile(p_any_s, [0.5, 0.025, 0.975]))
    else:
        p_any = lo = hi = 0.0
    return tuple(errors), (p_any, lo, hi)


def score(clips, calibration=None, *, task: str = "yes-no", style: str | None = None) -> ScoreResult:
    """Score one clip or several (:class:`~flipstudy.stimuli.motion.clip.Clip`).

    ``calibration``: a :class:`~flipstudy.stimuli.calibration.Calibration`, a path to
    a calibration file, or None (the default, real human data only); ``task``:
    whose functions to use (``"yes-no"``: "is this motion correct?"); ``style``:
    the character style the viewer sees (None: any).  See the module doc."""
    cal = get_calibration(calibration)
    if not isinstance(clips, (list, tuple)):
        clips = [clips]
    out = []
    for clip in clips:
        m = measure(clip)
        errors, (p_any, lo, hi) = score_measurement(m.items, cal, task=task, style=style)
        scored = [e for e in errors if e.scored]
        worst = max(scored, key=lambda e: e.p) if scored else None
        unscored = sorted({e.label() for e in errors if not e.scored and abs(e.size) > 0})
        note = ("not scored (no calibration): " + ", ".join(unscored) + "; P(anything noticed) "
                "counts the scored errors only") if unscored else ""
        out.append(ClipScore(m.name, float(clip.fps), int(clip.num_frames), _phases(m), errors,
                             p_any, lo, hi, worst, note, tuple(m.warnings)))
    return ScoreResult(tuple(out), cal.path or cal.description)


def likelier_noticed(before: ClipScore, after: ClipScore, *, at=("takeoff", "landing"),
                     tol: float = 0.02) -> list[str]:
    """The errors at the contacts (phases starting with ``at``) that ``after`` (an
    edit's output) makes likelier noticed than ``before`` (its source) by more than
    ``tol``: matched by kind, variant and phase, scored in ``after`` (a source error
    the calibration does not score, e.g. of the other sign, counts as p = 0: the
    warning errs on the side of showing).  Empty: no regression the calibration can
    see (an error it scores in neither is compared by no one)."""
    was = {(e.kind, e.variant, e.phase): e for e in before.errors}
    out = []
    for e in after.errors:
        b = was.get((e.kind, e.variant, e.phase))
        bp = (b.p if b.scored else 0.0) if b is not None else None
        if e.scored and bp is not None and e.phase.startswith(at) and e.p > bp + tol:
            out.append(f"{e.label()} at {e.phase}: p = {_pct(e.p)} (source "
                       f"{_pct(b.p) if b.scored else 'not scored'}), {e.size:+.1f} {e.unit} "
                       f"(source {b.size:+.1f})")
    return out


def score_lines(clip, source=None, calibration=None) -> list[str]:
    """An editor's output scored (:func:`flipstudy.stimuli.score.score`), as report lines;
    with its ``source``: a warning for each contact error likelier noticed than the source's."""
    res = score([clip] + ([source] if source is not None else []), calibration).clips
    lines = ["score: " + ln for ln in res[0].summary(brief=True).splitlines()]
    if source is not None:
        lines += [f"warning: likelier noticed than in the source: {w}" for w in likelier_noticed(res[1], res[0])]
    return lines
