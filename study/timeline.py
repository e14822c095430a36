"""The participant's screens as data (a jsPsych-style timeline).

:func:`build_timeline` returns one JSON-able object::

    {"participant": "P01", "session": 1, "n_trials": 100, "start": 0,
     "keys": {"correct": "f", "incorrect": "j"},
     "timeline": [screen, screen, ...]}

Each screen is an object with a ``type`` and an ``id``; the page
(``study/static/session.js``) has one renderer ("plugin") per type and runs the
screens in order from ``start``.  Types:

``instructions``  ``title``, ``paragraphs`` (list of str), ``button``
``demographics``  ``title``, ``text``, ``fields`` (see
                  :data:`flipstudy.study.validate.DEMOGRAPHIC_FIELDS`), ``submit`` (URL)
``examples``      ``title``, ``text``, ``stimuli`` (list of ``{"video", "label"}``),
                  ``button``: each example is loaded fully, played, may be
                  watched again; the button is enabled once all were shown
``trial``         ``trial`` (1-based), ``of`` (total), ``stimulus``, ``video``,
                  ``replay`` (bool), ``iti_ms``, ``prompt``, ``submit`` (URL)
``break``         ``title``, ``text``, ``button``
``end``           ``title``, ``paragraphs``

A resumed session starts at a "welcome back" instructions screen placed just
before the first unanswered trial (demographics and examples are not repeated
once any trial is answered); a finished one starts at the end screen.  The
server only builds this list; it has no per-screen logic.
"""
from __future__ import annotations

from .validate import DEMOGRAPHIC_FIELDS

KEYS = {"correct": "f", "incorrect": "j"}

INSTRUCTIONS = [
    "You are about to see a sequence of short animations of a person jumping and "
    "turning in the air.",
    "Some of these motions are physically correct and some of them are not.",
    "After each motion, mark it either as correct (it could happen like this in the real "
    "world) or as incorrect (it could not).",
    "First you will see examples of physically correct motions, to give you a reference point.",
]


def _keys_sentence(keys: dict) -> str:
    return (f"Answer with the keyboard — {keys['correct'].upper()} = correct, "
            f"{keys['incorrect'].upper()} = incorrect — or with the buttons on the screen. "
            f"The buttons work once the motion has been shown.")


def build_timeline(session, state: dict | None = None, *, iti_ms: int = 500,
                   video_url: str = "/stimuli/{name}.mp4") -> dict:
    """The screens of ``session`` (:class:`flipstudy.study.session.Session`) and where to
    start, given its ``state`` (:meth:`Session.state`)."""
    state = state or session.state()
    settings = session.study.design.session          # the design's [session] table
    keys = dict(KEYS)
    replay = bool(settings.replay)
    paragraphs = INSTRUCTIONS + [
        _keys_sentence(keys)
        + (" You may replay a motion before answering." if replay else
           " Each motion plays once, then you answer."),
    ] + (["There will be short breaks along the way."] if session.n_trials > settings.break_every else [])
    screens = [{"type": "instructions", "id": "instructions", "title": "Judging motions",
                "paragraphs": paragraphs, "button": "Continue"}]
    screens.append({"type": "demographics", "id": "demographics", "title": "About you",
                    "text": "A few questions about you. Every question has a “prefer not to say” "
                            "option.",
                    "fields": DEMOGRAPHIC_FIELDS, "submit": "/api/demographics",
                    "button": "Continue"})
    refs = session.study.references
    if refs:
        screens.append({
            "type": "examples", "id": "examples", "title": "Examples of correct motions",
            "text": "These motions are physically correct. Watch each one; you can watch "
                    "them again before you start.",
            "stimuli": [{"video": video_url.format(name=r["stimulus"]),
                         "label": f"Correct motion {i + 1} of {len(refs)}"}
                        for i, r in enumerate(refs)],
            "button": "Start the test"})
    first_trial = len(screens)
    n = session.n_trials
    every = max(int(settings.break_every), 1)
    for t in session.trials:
        screens.append({"type": "trial", "id": f"trial-{t.trial}", "trial": t.trial, "of": n,
                        "stimulus": t.stimulus, "video": video_url.format(name=t.stimulus),
                        "replay": replay, "iti_ms": int(iti_ms),
                        "prompt": "Was this motion physically correct?",
                        "submit": "/api/answer"})
        if t.trial % every == 0 and t.trial < n:
            screens.append({"type": "break", "id": f"break-{t.trial}", "title": "Break",
                            "text": f"Take a short rest. {t.trial} of {n} motions done. "
                                    f"Continue when you are ready.",
                            "button": "Continue"})
    screens.append({"type": "end", "id": "end", "title": "Thank you!",
                    "paragraphs": ["All your answers are saved. The study is complete.",
                                   "You may close this window."]})

    answered, start = state["answered"], 0
    if answered >= n:
        start = len(screens) - 1
    elif answered > 0:
        idx = next(i for i, s in enumerate(screens) if s.get("trial") == answered + 1)
        screens.insert(idx, {
            "type": "instructions", "id": "resume", "title": "Welcome back",
            "paragraphs": [f"Your first {answered} answers are saved. The study continues "
                           f"with motion {answered + 1} of {n}.",
                           "Remember: some motions are physically correct and some are not.",
                           _keys_sentence(keys)],
            "button": "Continue"})
        start = idx
    elif state["demographics"]:
        start = first_trial - 1 if refs else first_trial     # the examples (again)
    return {"participant": session.participant, "session": session.session, "n_trials": n,
            "start": start, "keys": keys, "timeline": screens}
