"""Tiny study folders with quest+ and 2AFC groups (design.toml and manifest.csv,
no videos), for the session, storage, order, simulation and export tests."""
from __future__ import annotations

from pathlib import Path

HEAD = """[study]
name = "adaptive-demo"
seed = 11
repetitions = {repetitions}
original = "per-group"

[[clips]]
name = "backflip"
source = "backflip"
"""
FRONT = """
[[clips]]
name = "frontflip"
source = "frontflip"
"""
GROUPS = {
    "yn": """
[[groups]]
name = "yn"
kind = "angular-momentum"
profile = "smooth"
levels = [0, 25]
""",
    "quest": """
[[groups]]
name = "quest"
kind = "angular-momentum"
profile = "smooth"
levels = {{from = 0, to = 60, step = 5}}
method = "quest+"
trials = {trials}
""",
    "quest2afc": """
[[groups]]
name = "quest2afc"
kind = "takeoff-angle"
levels = {{from = 0, to = 60, step = 5}}
method = "quest+"
task = "2afc"
trials = {trials}
""",
    "twoafc": """
[[groups]]
name = "twoafc"
kind = "takeoff-angle"
task = "2afc"
levels = [0, 20, 40]
""",
}


def design_text(groups=("yn", "quest"), *, trials: int = 12, repetitions: int = 2,
                two_clips: bool = False, extra: str = "") -> str:
    """A design with these groups (keys of :data:`GROUPS`); ``extra`` is appended
    to the last group's table."""
    text = HEAD.format(repetitions=repetitions) + (FRONT if two_clips else "")
    text += "".join(GROUPS[g].format(trials=trials) for g in groups)
    return text + extra


def make_study(out, text: str | None = None, **kw) -> Path:
    """``out/design.toml`` and a manifest of every stimulus the design plans (no
    motion files: sessions read only the manifest)."""
    from flipstudy.study.demo import write_placeholder_study
    write_placeholder_study(out, text or design_text(**kw), frames=60, fps=30.0)
    return Path(out)


def answer(session, trial, response, *, rt_ms=700.0, input="click") -> dict:
    """The payload the page posts for ``trial`` (a resolved :class:`Trial`)."""
    return {"participant": session.participant, "session": session.session, "trial": trial.trial,
            "stimulus": trial.stimulus, "response": response, "rt_ms": rt_ms, "shown_ms": 2000.0,
            "late_frames": 0, "input": input}
