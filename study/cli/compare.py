"""The comparison-study parts of ``flipstudy analyze`` and ``flipstudy simulate``
(a study whose design has ``[[sources]]``): short bodies over
:mod:`flipstudy.study.compare`; user errors reach :func:`flipstudy.study.cli.main`."""
from __future__ import annotations

import json
from pathlib import Path


def wants_comparison(args) -> bool:
    """Does ``flipstudy analyze`` get one study folder of a comparison study?
    (Answers given as a table are not: nothing of the comparison is imported.)"""
    if len(args.responses) != 1 or not Path(args.responses[0]).is_dir():
        return False
    from ..compare import is_comparison_study
    return is_comparison_study(args.responses[0])


def analyze_comparison_cmd(args) -> int:
    """``flipstudy analyze STUDY`` of a comparison study: ranking, win rates, agreement."""
    from ..compare import analyze_comparison
    from ..frozen import refuse_changed_design
    refuse_changed_design(Path(args.responses[0]), "analyze")
    res = analyze_comparison(args.responses[0], args.out, include_simulated=args.include_simulated,
                             n_boot=args.n_boot, ci=args.ci, seed=args.seed, figures=not args.no_figures)
    print(json.dumps(res.report.to_dict(), indent=2, ensure_ascii=False) if args.json else res.summary())
    return 0


def strengths_arg(text: str) -> dict:
    """The ``--strengths`` option's value (see :func:`flipstudy.study.compare.parse_strengths`)."""
    from ..compare import parse_strengths
    return parse_strengths(text)
