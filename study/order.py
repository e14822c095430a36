"""Trial order of one participant's session, built from the design.

The paper (Majkowska & Faloutsos 2007, Section 7): "The test motions were
arranged randomly within each error group and then interleaved to reduce the
learning effect. Each motion was shown twice."

:func:`trial_order` makes ``design.repetitions`` blocks.  In each block every
stimulus of every non-reference group appears once: each group's stimuli (all
clips × levels, level 0 — the original — included) are shuffled, and the groups
are interleaved round by round, one stimulus of each group per round, the
groups' order shuffled again in every round.  The angular-momentum groups'
shared originals (group ``original``, one per clip) form a group of their own
whose few rows are placed in rounds drawn at random, so each original is shown
``repetitions`` times, not once per group.  A block never starts with the
motion the previous one ended with.  The random generator is seeded
from the design seed and the participant ID through SHA-256
(:func:`participant_seed`), never Python's ``hash()``, so the same participant
always gets the same order; the order is stored before the first trial anyway.

Example
-------
A tiny study's design and manifest (two groups of two levels, shown twice):

>>> import tempfile, pathlib
>>> from flipstudy.stimuli.design import load_design
>>> from flipstudy.stimuli.stimset import read_manifest
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = tempfile.TemporaryDirectory()
>>> study = make_demo_study(pathlib.Path(tmp.name) / "study", videos=False)
>>> trials = trial_order(load_design(study / "design.toml"), read_manifest(study), "P01")
>>> len(trials), trials[0].trial, trials[0].stimulus, trials[0].repetition
(8, 1, 'backflip_smooth-increase_0', 1)
>>> trials == trial_order(load_design(study / "design.toml"), read_manifest(study), "P01")
True
>>> tmp.cleanup()
"""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyValueError

import hashlib
import random
from dataclasses import asdict, dataclass

REFERENCE_GROUP = "reference"


@dataclass(frozen=True)
class Trial:
    """One test trial: its 1-based position, the stimulus and its condition."""
    trial: int
    stimulus: str
    clip: str
    group: str
    kind: str
    level: float
    repetition: int

    def to_dict(self) -> dict:
        return asdict(self)


def participant_seed(design_seed: int, participant: str, session: int = 1) -> int:
    """A 64-bit seed from the design seed and the participant ID (SHA-256).

    Session 1 uses ``"{design_seed}:{participant}"``; a later session (started
    with ``--new-session``) appends ``":{session}"`` so it gets a fresh order.

    >>> participant_seed(20070803, "P01") == participant_seed(20070803, "P01")
    True
    """
    key = f"{int(design_seed)}:{participant}" + (f":{int(session)}" if session != 1 else "")
    return int.from_bytes(hashlib.sha256(key.encode()).digest()[:8], "big")


def _level(row: dict) -> float:
    try:
        return float(row["level"])
    except (KeyError, ValueError) as e:
        raise FlipstudyValueError(f"manifest.csv: stimulus {row.get('stimulus')!r}: bad level "
                         f"{row.get('level')!r}") from e


def group_stimuli(manifest: list[dict], design=None) -> dict[str, list[dict]]:
    """Non-reference manifest rows grouped by error group, groups in the design's
    order (then any others in manifest order), rows in manifest order."""
    groups: dict[str, list[dict]] = {}
    if design is not None:
        for g in design.groups:
            groups[g.name] = []
    for row in manifest:
        g = row.get("group", "")
        if g == REFERENCE_GROUP:
            continue
        groups.setdefault(g, []).append(row)
    return {g: rows for g, rows in groups.items() if rows}


def reference_stimuli(manifest: list[dict]) -> list[dict]:
    """The manifest's reference rows (the correct example motions), in manifest order."""
    return [r for r in manifest if r.get("group") == REFERENCE_GROUP]


def trial_order(design, manifest: list[dict], participant: str, session: int = 1) -> list[Trial]:
    """The participant's trials: ``design.repetitions`` blocks, random within each
    group, groups interleaved (see the module docstring)."""
    groups = group_stimuli(manifest, design)
    if not groups:
        raise FlipstudyValueError("manifest.csv has no test stimuli (only reference rows)")
    rng = random.Random(participant_seed(design.seed, participant, session))
    n_stimuli = sum(len(rows) for rows in groups.values())
    trials: list[Trial] = []
    for rep in range(1, design.repetitions + 1):
        for _ in range(100):
            block = _block(groups, rng)
            # never the same motion twice in a row across a block boundary
            if not trials or n_stimuli == 1 or block[0][0]["stimulus"] != trials[-1].stimulus:
                break
        for row, g in block:
            trials.append(Trial(len(trials) + 1, row["stimulus"], row.get("clip", ""), g,
                                row.get("kind", ""), _level(row), rep))
    return trials


def _block(groups: dict[str, list[dict]], rng: random.Random) -> list[tuple[dict, str]]:
    """One repetition: each group's rows shuffled, then one row of each group per
    round, the groups' order shuffled in every round.  A group with fewer rows
    than the largest (the shared originals: one per clip) takes part in rounds
    drawn at random, so its rows are spread over the block, not bunched at its
    start."""
    queues = {}
    for g, rows in groups.items():
        rows = list(rows)
        rng.shuffle(rows)
        queues[g] = rows
    R = max(len(q) for q in queues.values())
    rounds = {g: (set(range(R)) if len(q) == R else set(rng.sample(range(R), len(q))))
              for g, q in queues.items()}
    block = []
    for r in range(R):
        names = [g for g in queues if r in rounds[g]]
        rng.shuffle(names)
        for g in names:
            block.append((queues[g].pop(), g))
    return block
