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
    from flipstudy.stimuli.design import parse_design
    from flipstudy.stimuli.stimset import MANIFEST_COLUMNS, original_of, plan, write_manifest
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    text = text or design_text(**kw)
    (out / "design.toml").write_text(text)
    d = parse_design(text, out / "design.toml")
    rows = []
    for name, spec, group, level in plan(d):
        r = {c: 0.0 for c in MANIFEST_COLUMNS}
        r.update(stimulus=name, clip=spec.name, group=group.name if group else "reference",
                 kind=group.kind if group else "reference",
                 profile=(group.profile or "") if group else "", level=level,
                 nominal_error_pct=(group.sign * level) if group else 0.0, takeoff=10, landing=20,
                 seed=0, sha256="0" * 64, frames=60, fps=30.0, bvh=f"{name}.bvh", npz=f"{name}.npz",
                 original=original_of(d, spec.name, group), accept_unphysical="false")
        rows.append(r)
    write_manifest(out / "manifest.csv", rows)
    return out


def answer(session, trial, response, *, rt_ms=700.0, input="click") -> dict:
    """The payload the page posts for ``trial`` (a resolved :class:`Trial`)."""
    return {"participant": session.participant, "session": session.session, "trial": trial.trial,
            "stimulus": trial.stimulus, "response": response, "rt_ms": rt_ms, "shown_ms": 2000.0,
            "late_frames": 0, "input": input}
