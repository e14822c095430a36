"""The participant's screens as data (a jsPsych-style timeline).

:func:`build_timeline` returns one JSON-able object::

    {"participant": "P01", "session": 1, "n_trials": 100, "start": 0,
     "keys": {"correct": "f", "incorrect": "j"},
     "timeline": [screen, screen, ...]}

Each screen is an object with a ``type`` and an ``id``; the page (the jsPsych site of
``export-web`` in its ``local`` host mode, ``study/web/static/flipstudy-web.js``) builds
jsPsych trials for each type and runs the screens in order from ``start``.  Types:

``instructions``  ``title``, ``paragraphs`` (list of str), ``button``
``demographics``  ``title``, ``text``, ``fields`` (see
                  :data:`flipstudy.study.validate.DEMOGRAPHIC_FIELDS`), ``submit`` (URL)
``examples``      ``title``, ``text``, ``stimuli`` (list of ``{"video", "label"}``),
                  ``button``: each example is loaded fully, played, may be
                  watched again; the button is enabled once all were shown
``trial``         ``trial`` (1-based), ``of`` (total), ``stimulus``, ``video``,
                  ``replay`` (bool), ``iti_ms``, ``prompt``, ``submit`` (URL); a
                  yes/no trial of a study that also has 2AFC or adaptive groups
                  carries ``"task": "yes-no"``
``trial-2afc``    two-alternative forced choice: ``trial``, ``of``, ``stimuli`` (the
                  page's names of the two videos, in the order shown; the answer
                  names them so; which is the original is not said), ``videos``
                  (their two URLs, in that order), ``labels`` (``["1", "2"]``,
                  shown over each motion), ``gap_ms`` (the blank stage between
                  the two), ``keys`` (``{"first": "f",
                  "second": "j"}``), ``prompt``, ``replay`` (both motions again),
                  ``iti_ms``, ``submit``; the answer's ``response`` is ``"first"``
                  or ``"second"`` (the interval judged physically correct)
``break``         ``title``, ``text``, ``button``
``end``           ``title``, ``paragraphs``

A trial of an adaptive (QUEST+) group is ``{"type": "trial" | "trial-2afc",
"adaptive": true, "trial", "of", "task"}`` without stimulus or video: its level
is chosen when it is served, so the page fetches the filled screen from
``GET /api/trial/{n}`` (:func:`trial_screen` of ``session.resolve(n)``) just
before showing it.

A resumed session starts at a "welcome back" instructions screen placed just
before the first unanswered trial (demographics and examples are not repeated
once any trial is answered); a finished one starts at the end screen.  The
server only builds this list; it has no per-screen logic.
"""
from __future__ import annotations

from .validate import DEMOGRAPHIC_FIELDS

KEYS = {"correct": "f", "incorrect": "j"}
#: the 2AFC trial's keys: the first or the second motion was physically correct
KEYS_2AFC = {"first": "f", "second": "j"}
PROMPT = "Was this motion physically correct?"
PROMPT_2AFC = "Which motion was physically correct?"
GAP_MS = 600

INSTRUCTIONS = [
    "You are about to see a sequence of short animations of a person jumping and "
    "turning in the air.",
    "Some of these motions are physically correct and some of them are not.",
    "After each motion, mark it either as correct (it could happen like this in the real "
    "world) or as incorrect (it could not).",
    "First you will see examples of physically correct motions, to give you a reference point.",
]


INSTRUCTIONS_2AFC = [
    "You are about to see short animations of a person jumping and turning in the air, "
    "two at a time.",
    "In each trial you see two motions, one after the other, marked 1 and 2. One of them is "
    "physically correct (it could happen like this in the real world) and the other is not.",
    "After the second motion, choose which one was physically correct: the first or the second. "
    "If you are not sure, make your best guess.",
    "First you will see examples of physically correct motions, to give you a reference point.",
]

INSTRUCTIONS_MIXED = [
    "You are about to see a sequence of short animations of a person jumping and "
    "turning in the air.",
    "Some of these motions are physically correct and some of them are not.",
    "There are two kinds of trials. In some you see one motion: mark it either as correct "
    "(it could happen like this in the real world) or as incorrect (it could not).",
    "In others you see two motions, one after the other, marked 1 and 2; one of them is "
    "physically correct. Choose which one: the first or the second. The question on the "
    "screen tells you which kind of trial it is.",
    "First you will see examples of physically correct motions, to give you a reference point.",
]


ONE_REPLAY = " You may replay a motion before answering."


def _keys_sentence(keys: dict) -> str:
    return (f"Answer with the keyboard — {keys['correct'].upper()} = correct, "
            f"{keys['incorrect'].upper()} = incorrect — or with the buttons on the screen. "
            f"The buttons work once the motion has been shown.")


def _keys_sentence_2afc(keys: dict) -> str:
    return (f"Answer with the keyboard — {keys['first'].upper()} = the first motion, "
            f"{keys['second'].upper()} = the second — or with the buttons on the screen. "
            f"The buttons work once both motions have been shown.")


def _keys_sentence_mixed(keys: dict, keys2: dict) -> str:
    return (f"Answer with the keyboard or with the buttons on the screen: for one motion "
            f"{keys['correct'].upper()} = correct, {keys['incorrect'].upper()} = incorrect; for "
            f"two motions {keys2['first'].upper()} = the first, {keys2['second'].upper()} = the "
            f"second. The buttons work once the motion has been shown.")


def study_tasks(design) -> list[str]:
    """The tasks of the design's groups, in the order ``("yes-no", "2afc")``
    (a design without the ``task`` key is yes/no)."""
    tasks = {getattr(g, "task", "yes-no") or "yes-no" for g in design.groups}
    return [t for t in ("yes-no", "2afc") if t in tasks]


def is_default(design) -> bool:
    """True for a design of yes/no, constant-stimuli groups only: its screens are
    the ones flipstudy showed before 2AFC and adaptive groups existed."""
    return all((getattr(g, "task", "yes-no") or "yes-no") == "yes-no"
               and (getattr(g, "method", "constant") or "constant") == "constant"
               for g in design.groups)


def texts(design) -> dict:
    """The task-dependent wording: ``instructions`` (paragraphs), ``keys_sentence``,
    ``remember`` (the welcome-back reminder), ``noun`` (what a trial is called in
    the breaks' and the resume's counts: "motion", or "trial" when two are shown),
    ``replay`` and ``once`` (how often a motion plays, with and without replay).

    >>> from types import SimpleNamespace as NS
    >>> texts(NS(groups=[NS(task="2afc", method="constant")]))["keys_sentence"][:48]
    'Answer with the keyboard — F = the first motion,'
    >>> texts(NS(groups=[NS(task="yes-no", method="quest+")]))["instructions"] == INSTRUCTIONS
    True
    """
    tasks = study_tasks(design)
    if tasks == ["2afc"]:
        return {"instructions": list(INSTRUCTIONS_2AFC), "keys_sentence": _keys_sentence_2afc(KEYS_2AFC),
                "noun": "trial", "replay": " You may replay the two motions before answering.",
                "once": " The two motions play once, then you answer.",
                "remember": "Remember: in each trial one of the two motions is physically correct."}
    if tasks == ["yes-no", "2afc"]:
        return {"instructions": list(INSTRUCTIONS_MIXED), "noun": "trial", "replay": ONE_REPLAY,
                "once": " Each motion plays once, then you answer.",
                "keys_sentence": _keys_sentence_mixed(KEYS, KEYS_2AFC),
                "remember": "Remember: some motions are physically correct and some are not; "
                            "when you see two, one of them is."}
    return {"instructions": list(INSTRUCTIONS), "keys_sentence": _keys_sentence(KEYS), "noun": "motion",
            "replay": ONE_REPLAY, "once": " Each motion plays once, then you answer.",
            "remember": "Remember: some motions are physically correct and some are not."}


def trial_screen(t, n: int, *, replay: bool, iti_ms: int, video_url: str = "/stimuli/{name}.mp4",
                 tagged: bool = False, name=None) -> dict:
    """The screen of trial ``t`` (:class:`flipstudy.study.order.Trial`) of ``n``.
    An adaptive trial whose level is not chosen yet (no stimulus) gives the
    placeholder ``{"adaptive": true}``; once resolved, the filled screen (it keeps
    ``"adaptive": true``).  ``tagged``: yes/no screens carry ``"task"`` (studies
    that are not all yes/no, constant stimuli).  ``name(stimulus)``: what the screen
    calls a stimulus, in ``stimulus`` and in the video URLs (the local runner: its
    opaque name, :class:`flipstudy.study.web.opaque.PageNames`; None: the stimulus's own)."""
    name = name or str
    task = getattr(t, "task", "yes-no") or "yes-no"
    adaptive = (getattr(t, "method", "constant") or "constant") != "constant"
    common = {"type": "trial-2afc" if task == "2afc" else "trial", "id": f"trial-{t.trial}",
              "trial": t.trial, "of": n}
    if adaptive and not t.stimulus:
        return dict(common, adaptive=True, task=task)
    if task == "2afc":
        shown = [name(t.original), name(t.stimulus)]       # the order shown (the page never
        if t.first != "original":                          # learns which is the original)
            shown.reverse()
        screen = dict(common, stimuli=shown, videos=[video_url.format(name=x) for x in shown],
                      labels=["1", "2"], gap_ms=GAP_MS, keys=dict(KEYS_2AFC),
                      replay=replay, iti_ms=int(iti_ms), prompt=PROMPT_2AFC, submit="/api/answer",
                      task=task)
    else:
        screen = dict(common, stimulus=name(t.stimulus), video=video_url.format(name=name(t.stimulus)),
                      replay=replay, iti_ms=int(iti_ms), prompt=PROMPT, submit="/api/answer")
        if tagged:
            screen["task"] = task
    if adaptive:
        screen["adaptive"] = True
    return screen


def build_timeline(session, state: dict | None = None, *, iti_ms: int = 500,
                   video_url: str = "/stimuli/{name}.mp4", name=None) -> dict:
    """The screens of ``session`` (:class:`flipstudy.study.session.Session`) and where to
    start, given its ``state`` (:meth:`Session.state`).  ``name(stimulus)``: what the
    screens call a stimulus (:func:`trial_screen`; None: the stimulus's own name)."""
    name = name or str
    state = state or session.state()
    settings = session.study.design.session          # the design's [session] table
    keys = dict(KEYS)
    replay = bool(settings.replay)
    words = texts(session.study.design)
    tagged = not is_default(session.study.design)
    paragraphs = words["instructions"] + [
        words["keys_sentence"]
        + (words["replay"] if replay else words["once"]),
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
            "stimuli": [{"video": video_url.format(name=name(r.stimulus)),
                         "label": f"Correct motion {i + 1} of {len(refs)}"}
                        for i, r in enumerate(refs)],
            "button": "Start the test"})
    first_trial = len(screens)
    n = session.n_trials
    every = max(int(settings.break_every), 1)
    for t in session.trials:
        screens.append(trial_screen(t, n, replay=replay, iti_ms=iti_ms, video_url=video_url,
                                    tagged=tagged, name=name))
        if t.trial % every == 0 and t.trial < n:
            screens.append({"type": "break", "id": f"break-{t.trial}", "title": "Break",
                            "text": f"Take a short rest. {t.trial} of {n} {words['noun']}s done. "
                                    f"Continue when you are ready.",
                            "button": "Continue"})
    screens.append({"type": "end", "id": "end", "title": "Thank you!",
                    "paragraphs": ["All your answers are saved. The study is complete.",
                                   "You may close this window."]})

    answered, start = state["answered"], 0
    # the next open trial: quest+ slots skipped once their group stopped early are passed over
    nxt = state.get("next_trial", answered + 1)
    if state.get("finished", answered >= n):
        start = len(screens) - 1
    elif answered > 0:
        idx = next(i for i, s in enumerate(screens) if s.get("trial") == nxt)
        screens.insert(idx, {
            "type": "instructions", "id": "resume", "title": "Welcome back",
            "paragraphs": [f"Your first {answered} answers are saved. The study continues "
                           f"with {words['noun']} {nxt} of {n}.",
                           words["remember"], words["keys_sentence"]],
            "button": "Continue"})
        start = idx
    elif state["demographics"]:
        start = first_trial - 1 if refs else first_trial     # the examples (again)
    return {"participant": session.participant, "session": session.session, "n_trials": n,
            "start": start, "keys": keys, "timeline": screens}
