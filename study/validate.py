"""Validation of everything that comes from outside: participant IDs and the
participant page's posts.

Every check raises :class:`RequestError` with an HTTP status (4xx) and a
message; the server turns it into a JSON error and stores nothing.  The same
functions run for simulated observers, so both paths accept exactly the same
answers.
"""
from __future__ import annotations

import json
import math
import re
from flipstudy.errors import RequestError
from flipstudy.vocab import answers

PARTICIPANT_RE = re.compile(r"[A-Za-z0-9_-]{1,32}")
RESPONSES = ("correct", "incorrect", "first", "second")
#: the responses each task accepts (yes/no: the motion judged correct or not; 2AFC:
#: which of the two motions was judged physically correct)
TASK_RESPONSES = {"yes-no": ("correct", "incorrect"), "2afc": ("first", "second")}
INPUTS = ("key", "click", "simulated")
MAX_BODY = 8192                 # bytes of one posted JSON object
MAX_RT_MS = 3_600_000.0         # one hour: anything longer is not a reaction time
MAX_SHOWN_MS = 600_000.0        # ten minutes of one stimulus
MAX_LATE_FRAMES = 100_000
MAX_REPLAYS = 1000

#: The demographics questions (what the paper reports: age, gender, experience
#: with computer animation and with gymnastics).  The page renders these and the
#: server validates against the same list.  ``null``/absent = prefer not to say.
PREFER_NOT = "prefer-not-to-say"
EXPERIENCE = [["none", "None"], ["some", "Some"], ["significant", "Significant"],
              [PREFER_NOT, "Prefer not to say"]]
DEMOGRAPHIC_FIELDS = [
    {"name": "age", "label": "Age (years)", "kind": "number", "min": 16, "max": 110,
     "prefer_not": True},
    {"name": "gender", "label": "Gender", "kind": "choice",
     "options": [["woman", "Woman"], ["man", "Man"], ["other", "Another gender"],
                 [PREFER_NOT, "Prefer not to say"]]},
    {"name": "animation_experience", "label": "Experience with computer animation",
     "kind": "choice", "options": EXPERIENCE},
    {"name": "gymnastics_experience", "label": "Experience with gymnastics or acrobatics",
     "kind": "choice", "options": EXPERIENCE},
]


def check_participant(pid) -> str:
    """A participant ID: 1–32 letters, digits, '_' or '-' (it names rows and files)."""
    if not isinstance(pid, str) or not PARTICIPANT_RE.fullmatch(pid):
        raise RequestError(400, f"participant ID {pid!r} is not valid: use 1-32 letters, "
                                f"digits, '_' or '-'")
    return pid


def _reject_constant(name):
    raise ValueError(f"{name} is not a number JSON allows")


def parse_json_object(body: bytes) -> dict:
    """A posted body: one JSON object, at most :data:`MAX_BODY` bytes, no NaN/Infinity."""
    if len(body) > MAX_BODY:
        raise RequestError(413, f"request body too large ({len(body)} bytes; at most {MAX_BODY})")
    try:
        obj = json.loads(body.decode("utf-8"), parse_constant=_reject_constant)
    except (UnicodeDecodeError, ValueError, RecursionError) as e:
        raise RequestError(400, f"body is not valid JSON: {e}") from None
    if not isinstance(obj, dict):
        raise RequestError(400, f"body must be a JSON object, got {type(obj).__name__}")
    return obj


def _fields(obj: dict, required: set, optional: set = frozenset()):
    missing = sorted(required - set(obj))
    if missing:
        raise RequestError(400, f"missing field(s): {', '.join(missing)}")
    unknown = sorted(set(obj) - required - set(optional))
    if unknown:
        raise RequestError(400, f"unknown field(s): {', '.join(unknown)}")


def _int(obj, key, lo, hi) -> int:
    v = obj[key]
    if isinstance(v, bool) or not isinstance(v, int):
        raise RequestError(400, f"{key}: expected an integer, got {v!r}"[:200])
    if not lo <= v <= hi:
        raise RequestError(400, f"{key}: must be between {lo} and {hi}, got {v}"[:200])
    return v


def _number(obj, key, lo, hi) -> float:
    v = obj[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise RequestError(400, f"{key}: expected a number, got {v!r}"[:200])
    v = float(v) if not isinstance(v, int) or abs(v) < 2 ** 63 else math.inf
    if not math.isfinite(v):
        raise RequestError(400, f"{key}: must be a finite number")
    if not lo <= v <= hi:
        raise RequestError(400, f"{key}: must be between {lo:g} and {hi:g}, got {v:g}")
    return v


def _choice(obj, key, options) -> str:
    v = obj[key]
    if not isinstance(v, str) or v not in options:
        raise RequestError(400, f"{key}: must be one of {', '.join(options)}, got {v!r}"[:200])
    return v


#: the fields of a posted answer, as the answer record declares them (flipstudy.vocab.answers)
ANSWER_FIELDS = set(answers.POSTED)
ANSWER_OPTIONAL = set(answers.POSTED_OPTIONAL)


def parse_answer(obj: dict, *, participant: str, session: int, n_trials: int,
                 replay_allowed: bool) -> dict:
    """Check one answer object against this participant's session; returns the
    cleaned fields.  Raises :class:`RequestError` (400 malformed, 403 another
    participant or session)."""
    _fields(obj, ANSWER_FIELDS, ANSWER_OPTIONAL)
    pid = obj["participant"]
    if not isinstance(pid, str) or not PARTICIPANT_RE.fullmatch(pid):
        raise RequestError(400, "participant: not a valid participant ID")
    if pid != participant:
        raise RequestError(403, f"this page runs participant {participant}, not {pid}")
    s = _int(obj, "session", 1, 10_000)
    if s != session:
        raise RequestError(403, f"this page runs session {session}, not {s}")
    trial = _int(obj, "trial", 1, n_trials)
    if not isinstance(obj["stimulus"], str) or len(obj["stimulus"]) > 200:
        raise RequestError(400, "stimulus: expected a stimulus name")
    out = {
        "trial": trial,
        "stimulus": obj["stimulus"],
        "response": _choice(obj, "response", RESPONSES),
        "rt_ms": _number(obj, "rt_ms", 0.0, MAX_RT_MS),
        "shown_ms": _number(obj, "shown_ms", 0.0, MAX_SHOWN_MS),
        "late_frames": _int(obj, "late_frames", 0, MAX_LATE_FRAMES),
        "replays": _int(obj, "replays", 0, MAX_REPLAYS) if "replays" in obj else 0,
        "input": _choice(obj, "input", INPUTS) if "input" in obj else "click",
    }
    if out["replays"] and not replay_allowed:
        raise RequestError(400, "replays: this study's design does not allow replaying a motion")
    return out


def check_task_response(task: str, response: str) -> str:
    """A response that fits the trial's task (400 otherwise).

    >>> check_task_response("2afc", "first")
    'first'
    >>> check_task_response("yes-no", "first")
    Traceback (most recent call last):
    ...
    flipstudy.errors.RequestError: response: a yes-no trial is answered correct or incorrect, not 'first'
    """
    ok = TASK_RESPONSES.get(task, TASK_RESPONSES["yes-no"])
    if response not in ok:
        raise RequestError(400, f"response: a {task} trial is answered {' or '.join(ok)}, not {response!r}")
    return response


def parse_demographics(obj: dict, *, participant: str, session: int) -> dict:
    """Check the demographics object; returns ``{name: value}`` with ``None`` for
    "prefer not to say" (age) and the option codes otherwise."""
    names = {f["name"] for f in DEMOGRAPHIC_FIELDS}
    _fields(obj, {"participant", "session"} | names)
    if obj["participant"] != participant:
        raise RequestError(403, f"this page runs participant {participant}")
    if _int(obj, "session", 1, 10_000) != session:
        raise RequestError(403, f"this page runs session {session}")
    out = {}
    for f in DEMOGRAPHIC_FIELDS:
        k = f["name"]
        if f["kind"] == "number":
            if obj[k] is None:
                out[k] = None
            else:
                out[k] = _int(obj, k, f["min"], f["max"])
        else:
            out[k] = _choice(obj, k, [o[0] for o in f["options"]])
    return out
