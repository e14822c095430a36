"""The answer record, declared once: every column of the tables a study's answers are
exported to, with its type, the step that writes it and what it means.

As a jsPsych plugin declares the data of its trial, this module declares the rows
of ``responses.csv`` (:data:`RESPONSES`; a study with a quest+ or 2AFC group adds
:data:`ADAPTIVE`), ``participants.csv`` (:data:`PARTICIPANTS`) and
``simulated_truth.csv`` (:data:`TRUTH`).  The export
(:mod:`flipstudy.study.export`), the web import, the Psych-DS description
(:mod:`flipstudy.study.psychds`), the local runner's answer check
(:data:`POSTED`) and the analysis (:mod:`flipstudy.analysis.io`) read
the column names from here; the first :data:`DESIGN_COLUMNS` are DESIGN.md's long
format.

The steps: ``run`` (the session stores the answer: local runner or browser),
``build`` (from the stimulus' manifest row), ``simulate`` (a simulated
participant's), ``export`` (computed when the table is written).

>>> RESPONSE_COLUMNS[:4], DESIGN_COLUMNS[-3:]
(['participant', 'session', 'trial', 'stimulus'], ('rt_ms', 'shown_ms', 'timestamp'))
>>> column("rt_ms").type, column("rt_ms").written_by
(<class 'float'>, 'run')
"""
from __future__ import annotations

from dataclasses import dataclass

from .kinds import study_kind_names

STEPS = ("run", "build", "simulate", "export")


@dataclass(frozen=True)
class Column:
    """One column of an answer table: name, type, the step that writes it, meaning."""
    name: str
    type: type
    written_by: str
    meaning: str


def _cols(*rows) -> tuple:
    return tuple(Column(*r) for r in rows)


#: ``responses.csv``, one row per answered trial
RESPONSES = _cols(
    ("participant", str, "run", "participant ID"),
    ("session", int, "run", "session number of the participant (1-based)"),
    ("trial", int, "run", "trial number within the session (1-based)"),
    ("stimulus", str, "run", "stimulus name (manifest.csv)"),
    ("group", str, "build", "error group of the stimulus"),
    ("level", float, "build", "nominal error in percent (0 = the original motion); of kind pose-rate, "
                              "poses per second (0 = the original motion)"),
    ("repetition", int, "run", "which showing of the stimulus (1-based)"),
    ("response", str, "run", "the answer: correct or incorrect (physically plausible or not)"),
    ("rt_ms", float, "run", "reaction time in milliseconds, from the end of the motion to the answer"),
    ("shown_ms", float, "run", "how long the motion was shown, milliseconds ('playing' to 'ended')"),
    ("timestamp", str, "run", "when the answer was stored (ISO 8601, UTC)"),
    ("clip", str, "build", "base clip of the stimulus"),
    ("kind", str, "build", "kind of error (" + ", ".join(study_kind_names()) + ")"),
    ("late_frames", int, "run", "frames shown late or dropped during the motion"),
    ("replays", int, "run", "times the participant replayed the motion"),
    ("input", str, "run", "how the answer was given: key, click or simulated"),
    ("simulated", bool, "simulate", "true for a simulated participant"),
    ("complete", bool, "export", "false when the session did not answer every trial"))
#: the columns a study with a quest+ or 2AFC group adds at the end of ``responses.csv``
ADAPTIVE = _cols(
    ("method", str, "build", "how the trial's level was chosen: constant (stimuli fixed in advance) or "
                             "quest+ (adaptive: QUEST+ picked the level from the participant's earlier "
                             "answers)"),
    ("task", str, "build", "yes-no (one motion: correct or incorrect?) or 2afc (an original and a "
                           "modified motion: which was physically correct? response first or second)"),
    ("first", str, "run", "2afc: which motion was shown first (original or modified)"),
    ("original_stimulus", str, "run", "2afc: the original motion the modified one was shown with"),
    ("quest_threshold", float, "run", "quest+: posterior mean of the group's detection threshold x* "
                                      "after this answer (percent; P(x*) = (1 + guess rate)/2)"),
    ("quest_ci_low", float, "run", "quest+: lower end of the 95 % posterior interval of x* after this "
                                   "answer"),
    ("quest_ci_high", float, "run", "quest+: upper end of the 95 % posterior interval of x* after this "
                                    "answer"))
#: ``participants.csv``, one row per session
PARTICIPANTS = _cols(
    ("participant", str, "run", "participant ID"),
    ("session", int, "run", "session number of the participant (1-based)"),
    ("source", str, "run", "where the answer came from (web-jatos, web-pavlovia, web-static)"),
    ("age", str, "run", "age in years (empty: prefer not to say)"),
    ("gender", str, "run", "gender (option code)"),
    ("animation_experience", str, "run", "experience with computer animation"),
    ("gymnastics_experience", str, "run", "experience with gymnastics or acrobatics"),
    ("started", str, "run", "when the session started (ISO 8601, UTC)"),
    ("finished", str, "run", "when the session's last answer was stored"),
    ("answered", int, "export", "answers given in the session"),
    ("n_trials", int, "run", "trials of the session"),
    ("simulated", bool, "simulate", "true for a simulated participant"),
    ("complete", bool, "export", "false when the session did not answer every trial"))
#: ``simulated_truth.csv``: each simulated session's observer per group
TRUTH = _cols(
    ("participant", str, "simulate", "participant ID"),
    ("session", int, "simulate", "session number of the participant (1-based)"),
    ("group", str, "simulate", "error group of the stimulus"),
    ("task", str, "simulate", "yes-no or 2afc"),
    ("threshold", float, "simulate", "the simulated observer's psychometric threshold"),
    ("width", float, "simulate", "its width"),
    ("gamma", float, "simulate", "its guess rate"),
    ("lapse", float, "simulate", "its lapse rate"))

#: what a browser records of one answer besides the columns of :data:`RESPONSES` (the
#: web site's answer record, checked by ``import-web``)
WEB = _cols(
    ("frames_expected", int, "run", "frames of the video"),
    ("frames_presented", int, "run", "video frames presented (requestVideoFrameCallback presentedFrames)"),
    ("frames_dropped", int, "run", "video frames never presented (frames_expected - frames_presented)"),
    ("dropped_pct", float, "run", "frames_dropped in percent of frames_expected"),
    ("playback_ms", float, "run", "milliseconds from the first presented frame to the end of playback"),
    ("video_ms", float, "run", "duration of the video in milliseconds"),
    ("timing", str, "run", "how frames were counted: rvfc (requestVideoFrameCallback) or raf (fallback)"),
    ("playback_flagged", bool, "run", "true when dropped_pct exceeds max_dropped_pct"),
    ("max_dropped_pct", float, "run", "the site's dropped-frame threshold, percent"))


def _names(cols, *names) -> tuple:
    """The names of ``cols`` (all, or these, in this order, each one declared)."""
    declared = [c.name for c in cols]
    missing = [n for n in names if n not in declared]
    if missing:
        raise KeyError(missing)
    return tuple(names) if names else tuple(declared)


#: the fields the local runner's page posts for one answer (required), and may post
POSTED = _names(RESPONSES, "participant", "session", "trial", "stimulus", "response", "rt_ms",
                "shown_ms", "late_frames")
POSTED_OPTIONAL = _names(RESPONSES, "replays", "input")
#: the fields of a web answer record, in the order ``import-web`` checks them
WEB_ANSWER = _names(RESPONSES, "trial", "stimulus", "group", "level", "repetition", "response", "rt_ms",
                    "shown_ms", "input", "replays") + _names(WEB)

RESPONSE_COLUMNS = [c.name for c in RESPONSES]
ADAPTIVE_COLUMNS = [c.name for c in ADAPTIVE]
PARTICIPANT_COLUMNS = [c.name for c in PARTICIPANTS]
TRUTH_COLUMNS = [c.name for c in TRUTH]
#: DESIGN.md's long format: the first columns of ``responses.csv``
DESIGN_COLUMNS = tuple(RESPONSE_COLUMNS[:RESPONSE_COLUMNS.index("timestamp") + 1])


def column(name: str) -> Column:
    """The declaration of a column of ``responses.csv`` (or its adaptive or participants'
    columns), by name."""
    for c in RESPONSES + ADAPTIVE + PARTICIPANTS + WEB:
        if c.name == name:
            return c
    raise KeyError(name)


def meanings() -> dict:
    """Column name → meaning, of every declared column (the first declaration wins)."""
    out: dict = {}
    for c in RESPONSES + ADAPTIVE + PARTICIPANTS + WEB:
        out.setdefault(c.name, c.meaning)
    return out


__all__ = ["ADAPTIVE", "ADAPTIVE_COLUMNS", "Column", "DESIGN_COLUMNS", "PARTICIPANTS", "PARTICIPANT_COLUMNS",
           "POSTED", "POSTED_OPTIONAL", "RESPONSES", "RESPONSE_COLUMNS", "STEPS", "TRUTH", "TRUTH_COLUMNS",
           "WEB", "WEB_ANSWER", "column", "meanings"]
