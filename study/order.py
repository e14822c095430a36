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
motion the previous one ended with.

Adaptive and two-alternative groups (issue 19):

* A quest+ group has no fixed stimuli: it gets ``trials`` adaptive slots
  (``method = "quest+"``, ``stimulus = ""``, ``level`` NaN; the session picks
  the level when the trial is served, :meth:`flipstudy.study.session.Session.resolve`),
  each with a clip (the group's clips in equal shares, shuffled).  The slots are
  spread over the session among the constant trials: the constant trials keep
  their order, and every sequence (the constant trials, each quest+ group's
  slots) is placed at stratified random positions ``(k + u) / n`` and merged.
* A 2AFC trial shows the modified motion and its original (``original``, the
  comparison stimulus; level 0 is not a trial level of a 2AFC group).  Which comes
  first (``first`` = ``"original"`` or ``"modified"``) is balanced within each
  group: half of its trials each way (an odd one drawn), shuffled.
* The shared originals are trials of their own only while a constant yes/no
  group shares them (:attr:`flipstudy.stimuli.design.Design.shows_shared_original`).

A design with only constant yes/no groups draws exactly the random numbers it
drew before these were added, so its orders are unchanged.  The random generator is seeded
from the design seed and the participant ID through SHA-256
(:func:`participant_seed`), never Python's ``hash()``, so the same participant
always gets the same order; the order is stored before the first trial anyway.

Examples
--------
A tiny study's design and manifest (two groups of two levels, shown twice):

>>> import tempfile, pathlib
>>> from flipstudy.stimuli.contract import StimulusSet
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = tempfile.TemporaryDirectory()
>>> study = StimulusSet.read(make_demo_study(pathlib.Path(tmp.name) / "study", videos=False), files=False)
>>> trials = trial_order(study.design, study, "P01")
>>> len(trials), trials[0].trial, trials[0].stimulus, trials[0].repetition
(8, 1, 'backflip_smooth-increase_0', 1)
>>> trials == trial_order(study.design, study, "P01")
True
>>> tmp.cleanup()
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

import hashlib
import math
import random
from dataclasses import asdict, dataclass, replace
from typing import Iterable

from flipstudy.stimuli.contract import REFERENCE_GROUP, Stimulus


METHODS = ("constant", "quest+")
TASKS = ("yes-no", "2afc")
FIRSTS = ("original", "modified")


@dataclass(frozen=True)
class Trial:
    """One test trial: its 1-based position, the stimulus and its condition.

    ``method``: "constant" or "quest+" (an adaptive slot: ``stimulus`` "" and
    ``level`` NaN until :meth:`~flipstudy.study.session.Session.resolve` fills
    them); ``task``: "yes-no" or "2afc"; ``first``: what a 2AFC trial shows first
    ("original" or "modified"; "" for yes/no); ``original``: a 2AFC trial's
    comparison stimulus ("" for yes/no)."""
    trial: int
    stimulus: str
    clip: str
    group: str
    kind: str
    level: float
    repetition: int
    method: str = "constant"
    task: str = "yes-no"
    first: str = ""
    original: str = ""

    @property
    def adaptive(self) -> bool:
        """Is this a quest+ slot?"""
        return self.method == "quest+"

    @property
    def resolved(self) -> bool:
        """Is its stimulus known (a constant trial, or a slot :meth:`Session.resolve` filled)?"""
        return bool(self.stimulus)

    def to_dict(self) -> dict:
        """The trial as JSON-able data (an unresolved slot's NaN level is None).

        >>> Trial(3, "", "backflip", "g", "takeoff-angle", math.nan, 1, "quest+").to_dict()["level"] is None
        True
        """
        d = asdict(self)
        if not math.isfinite(d["level"]):
            d["level"] = None
        return d


def participant_seed(design_seed: int, participant: str, session: int = 1) -> int:
    """A 64-bit seed from the design seed and the participant ID (SHA-256).

    Session 1 uses ``"{design_seed}:{participant}"``; a later session (started
    with ``--new-session``) appends ``":{session}"`` so it gets a fresh order.

    >>> participant_seed(20070803, "P01") == participant_seed(20070803, "P01")
    True
    """
    key = f"{int(design_seed)}:{participant}" + (f":{int(session)}" if session != 1 else "")
    return int.from_bytes(hashlib.sha256(key.encode()).digest()[:8], "big")


def group_stimuli(manifest: Iterable[Stimulus], design=None) -> dict[str, list[Stimulus]]:
    """Non-reference stimuli grouped by error group, groups in the design's
    order (then any others in manifest order), rows in manifest order.

    With a ``design``, only the rows that are constant trials: no quest+ group
    (the session picks its stimuli), no level 0 of a 2AFC group (its comparison: a
    2AFC row is a trial when its ``original`` names another row),
    and the shared originals only while a constant yes/no group shares them."""
    groups: dict[str, list[Stimulus]] = {}
    keep = None
    if design is not None:
        for g in design.groups:
            groups[g.name] = []
        keep = _constant_row_rule(design)
    for row in manifest:
        g = row.group
        if g == REFERENCE_GROUP or (keep is not None and not keep(row)):
            continue
        groups.setdefault(g, []).append(row)
    return {g: rows for g, rows in groups.items() if rows}


def _constant_row_rule(design):
    from flipstudy.stimuli.design import SHARED_ORIGINAL_GROUP
    by = {g.name: g for g in design.groups}
    shared = getattr(design, "shows_shared_original", True)

    def keep(row: Stimulus) -> bool:
        g = by.get(row.group)
        if g is None:
            return shared or row.group != SHARED_ORIGINAL_GROUP
        # a 2AFC trial is a row with a comparison other than itself (a group's own level 0
        # names itself; a comparison study's first source names none)
        return (not getattr(g, "adaptive", False)
                and (getattr(g, "task", "yes-no") == "yes-no" or row.original not in ("", row.stimulus)))
    return keep


def reference_stimuli(manifest: Iterable[Stimulus]) -> list[Stimulus]:
    """The reference stimuli (the correct example motions), in manifest order."""
    return [r for r in manifest if r.is_reference]


def trial_order(design, manifest: Iterable[Stimulus], participant: str, session: int = 1) -> list[Trial]:
    """The participant's trials: ``design.repetitions`` blocks, random within each
    group, groups interleaved, quest+ slots spread among them, 2AFC order balanced
    (see the module docstring).  ``manifest``: a
    :class:`~flipstudy.stimuli.contract.StimulusSet` or its stimuli."""
    manifest = list(manifest)
    groups = group_stimuli(manifest, design)
    adaptive = [g for g in design.groups if getattr(g, "adaptive", False)]
    if not groups and not adaptive:
        raise FlipstudyValueError("manifest.csv has no test stimuli (only reference rows)")
    by = {g.name: g for g in design.groups}
    rng = random.Random(participant_seed(design.seed, participant, session))
    n_stimuli = sum(len(rows) for rows in groups.values())
    trials: list[Trial] = []
    for rep in range(1, design.repetitions + 1 if groups else 1):
        for _ in range(100):
            block = _block(groups, rng)
            # never the same motion twice in a row across a block boundary
            if not trials or n_stimuli == 1 or block[0][0].stimulus != trials[-1].stimulus:
                break
        for row, g in block:
            task = getattr(by.get(g), "task", "yes-no")
            trials.append(Trial(len(trials) + 1, row.stimulus, row.clip, g, row.kind, row.level, rep,
                                "constant", task, "", row.original if task == "2afc" else ""))
    if adaptive:
        trials = _interleave(trials, [_slots(design, g, manifest, rng) for g in adaptive], rng)
    if any(t.task == "2afc" for t in trials):
        trials = balance_first(trials, rng.shuffle, rng.random)
    return [replace(t, trial=i) for i, t in enumerate(trials, start=1)]


def _slots(design, group, manifest: list[Stimulus], rng: random.Random) -> list[Trial]:
    """A quest+ group's ``trials`` slots: its clips in equal shares (the remainder
    drawn), shuffled."""
    clips = [c.name for c in design.clips]
    T = group.quest.trials
    order = clips * (T // len(clips)) + rng.sample(clips, T % len(clips))
    rng.shuffle(order)
    originals = {}
    if group.task == "2afc":
        for r in manifest:
            if r.group == group.name and r.original:
                originals.setdefault(r.clip, r.original)
        missing = sorted(set(clips) - set(originals))
        if missing:
            raise FlipstudyValueError(f"manifest.csv: the 2afc group {group.name!r} has no original "
                                      f"for clip(s) {missing}; rebuild the stimuli")
    return [Trial(0, "", c, group.name, group.kind, math.nan, 1, "quest+", group.task, "",
                  originals.get(c, "")) for c in order]


def _interleave(constant: list[Trial], slots: list[list[Trial]], rng: random.Random) -> list[Trial]:
    """Merge the sequences, each keeping its order, at stratified random positions."""
    keyed = []
    for s, seq in enumerate([constant] + slots):
        n = len(seq)
        keyed += [((k + rng.random()) / n, s, k, t) for k, t in enumerate(seq)]
    keyed.sort(key=lambda x: x[:3])
    return [t for *_, t in keyed]


def balance_first(trials: list[Trial], shuffle, random01) -> list[Trial]:
    """``trials`` with ``first`` set on every 2AFC trial: within each group half
    "original", half "modified" (an odd one drawn with ``random01() < 0.5``), in
    the order ``shuffle`` leaves them.  ``shuffle``/``random01`` come from the
    order's generator (the web order passes its own).

    >>> ts = [Trial(i, f"s{i}", "c", "g", "k", 10.0, 1, task="2afc") for i in range(1, 6)]
    >>> out = balance_first(ts, random.Random(1).shuffle, random.Random(2).random)
    >>> sorted(t.first for t in out).count("original") in (2, 3)
    True
    """
    out = list(trials)
    by_group: dict[str, list[int]] = {}
    for i, t in enumerate(out):
        if t.task == "2afc":
            by_group.setdefault(t.group, []).append(i)
    for idx in by_group.values():
        n = len(idx)
        firsts = ["original", "modified"] * (n // 2)
        if n % 2:
            firsts.append("original" if random01() < 0.5 else "modified")
        shuffle(firsts)
        for i, f in zip(idx, firsts):
            out[i] = replace(out[i], first=f)
    return out


def _block(groups: dict[str, list[Stimulus]], rng: random.Random) -> list[tuple[Stimulus, str]]:
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
