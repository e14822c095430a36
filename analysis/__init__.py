"""flipstudy analysis: ratings, d′, statistics, tables and figures from response tables.

Reads response tables (the long format of DESIGN.md) with pandas; imports
nothing of ``study``, ``render`` or ``stimuli``.

>>> from flipstudy import analysis
>>> round(float(analysis.dprime(59, 100, 28, 100)), 2)     # the paper's 41 % vs 72 % rated correct
0.81

Entry points:

* :func:`analyze` — the whole pipeline (tables, GEE, psychometric fits, figures);
* :func:`dprime`, :func:`criterion`, :func:`rates`, :func:`corrected_rate` —
  signal detection on counts (vectorised);
* :func:`load_responses` — read and check a response table;
* :func:`summarize`, :func:`gee_levels`, :func:`fit_psychometric` — the steps;
* :mod:`flipstudy.analysis.simulate` — simulated panels (the paper's, SDT observers);
* :mod:`flipstudy.analysis.adaptive` — the QUEST+ engine and simulated observers with
  known thresholds (:mod:`~flipstudy.analysis.adaptive_sim`: many at once);
  :func:`dprime_2afc` — 2AFC d′; :mod:`flipstudy.analysis.thresholds` — per-participant
  thresholds; :mod:`flipstudy.analysis.plan` — the power analysis of ``flipstudy plan``.
"""
from .core import count_cells, participant_dprimes, summarize
from flipstudy.errors import NeedsExport, NeedsExportError, ResponsesError  # noqa: F401  (the old name too)
from .io import load_responses
from .pipeline import Result, analyze
from .sdt import CORRECTIONS, corrected_rate, criterion, dprime, dprime_2afc, rates, z
from .stats import (PsychometricFit, detection_threshold, fit_psychometric, gee_levels,
                    psychometric_curve)
from .tables import fmt_cell, fmt_dprime, paper_layout, to_latex, to_markdown

__all__ = ["analyze", "Result", "dprime", "dprime_2afc", "criterion", "rates", "corrected_rate", "z", "CORRECTIONS",
           "load_responses", "ResponsesError", "NeedsExportError", "summarize", "count_cells",
           "participant_dprimes", "gee_levels", "fit_psychometric", "PsychometricFit",
           "detection_threshold", "psychometric_curve", "paper_layout", "to_markdown", "to_latex",
           "fmt_cell", "fmt_dprime"]
