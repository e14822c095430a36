"""A comparison study's analysis: its answers, its clips' numbers, the ranking.

:func:`analyze_comparison` reads a comparison study (a design with ``[[sources]]``,
:mod:`flipstudy.stimuli.compare`) through its typed stimulus set, its exported
answers (``responses.csv``), measures every clip once (the score's P(anything
noticed), :func:`flipstudy.stimuli.score.score`, and the plain foot-skate,
floating and penetration sizes, :func:`flipstudy.stimuli.measure.measure`) and
hands them to :func:`flipstudy.analysis.compare.analyze_choices`.
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from flipstudy.errors import ComparisonError
from flipstudy.records import CompareReport
from flipstudy.results import CompareResult
from flipstudy.stimuli.contract import StimulusSet
from flipstudy.stimuli.design import GIVEN_KIND

#: the plain measured kinds compared with the choices (largest |size| in the clip, mm)
PLAIN_KINDS = ("foot-skate", "floating", "penetration")


def clip_metrics(stimuli: StimulusSet) -> pd.DataFrame:
    """Per stimulus (index): ``score_p_any`` and the largest size of each of
    :data:`PLAIN_KINDS` in the clip (0 when it has none)."""
    from flipstudy.stimuli.motion.bvh import load_bvh
    from flipstudy.stimuli.measure import measure
    from flipstudy.stimuli.score import score
    rows = {}
    for s in stimuli:
        clip = load_bvh(stimuli.path(s), scale=1.0)
        m = measure(clip)
        row = {"score_p_any": score(clip).clips[0].p_any}
        for k in PLAIN_KINDS:
            sizes = [abs(i.size) for i in m.items if i.kind == k]
            row[f"{k}_mm"] = max(sizes) if sizes else 0.0
        rows[s.stimulus] = row
    return pd.DataFrame.from_dict(rows, orient="index")


def analyze_comparison(study_dir, out_dir=None, *, responses=None, include_simulated: bool = False,
                       n_boot: int = 2000, ci: float = 0.95, seed=0, figures: bool = True):
    """Analyse the comparison study in ``study_dir`` from its ``responses.csv`` (or
    ``responses``, a path): ranking, win rates, agreement of the clips' numbers with
    the choices; tables and figure into ``out_dir`` (default ``STUDY/analysis``).
    Only the comparisons between sources count (trials of injected error groups are
    left to the error analysis).  Returns a
    :class:`flipstudy.analysis.compare.ComparisonAnalysis`."""
    from flipstudy.analysis.compare import analyze_choices, choices
    from flipstudy.analysis.io import load_responses, participants_label, select_participants
    d = Path(study_dir)
    stimuli = StimulusSet.read(d)
    if not stimuli.sourced:
        raise ComparisonError(f"{d / 'manifest.csv'}: not a comparison study (no source column; its "
                              f"design has no [[sources]])")
    df = load_responses(Path(responses) if responses is not None else d / "responses.csv")
    df, who = select_participants(df, include_simulated=include_simulated)
    given = [s for s in stimuli if s.kind == GIVEN_KIND]      # the error groups' trials are not comparisons
    df = df[df["stimulus"].isin({s.stimulus for s in given})]
    ch = choices(df, {s.stimulus: s.source for s in given}, {s.stimulus: s.clip for s in given})
    if not len(ch):
        raise ComparisonError(f"{d}: no 2AFC answers to analyse"
                              + (f" ({len(who['simulated_left_out'])} simulated participant(s) left "
                                 f"out: --include-simulated)" if who.get("simulated_left_out") else ""))
    used = set(ch["stimulus"]) | set(ch["original"])
    metrics = clip_metrics(StimulusSet(stimuli.folder, [s for s in stimuli if s.stimulus in used]))
    out = Path(out_dir) if out_dir is not None else d / "analysis"
    res = analyze_choices(ch, stimuli.sources(), metrics, out, n_boot=n_boot, ci=ci, seed=seed,
                          figures=figures, label=participants_label(who))
    return CompareResult(out=out, report=CompareReport.from_dict(res.to_dict()))


def is_comparison_study(path) -> bool:
    """Is ``path`` the folder of a 2AFC comparison study (a ``source`` column, task
    ``2afc``)?  A yes/no comparison study's answers are ratings per source (its
    groups), which the ordinary analysis tables."""
    p = Path(path)
    if not (p / "manifest.csv").is_file() or not (p / "design.toml").is_file():
        return False
    st = StimulusSet.read(p, files=False)
    return st.sourced and st.design is not None and st.design.task == "2afc"


def parse_strengths(text: str) -> dict:
    """``"gt=0,jitter=-1"`` → ``{"gt": 0.0, "jitter": -1.0}`` (the ``--strengths`` option).

    >>> parse_strengths("gt=0, a=-1.5")
    {'gt': 0.0, 'a': -1.5}
    """
    out = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        name, eq, val = part.partition("=")
        try:
            if not eq:
                raise ValueError
            out[name.strip()] = float(val)
        except ValueError:
            raise ComparisonError(f"--strengths: {part!r} is not SOURCE=LOGIT (e.g. gt=0,modelA=-1)") from None
    if not out:
        raise ComparisonError("--strengths: expected SOURCE=LOGIT,... (e.g. gt=0,modelA=-1)")
    return out


__all__ = ["analyze_comparison", "clip_metrics", "is_comparison_study", "parse_strengths", "PLAIN_KINDS"]
