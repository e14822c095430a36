"""The web session's trial order: the rule of :mod:`flipstudy.study.order` over a
small generator that JavaScript runs too.

``flipstudy run`` orders trials with Python's Mersenne Twister
(:func:`flipstudy.study.order.trial_order`); a browser cannot replay that
cheaply, so the exported site (``study/web/static/flipstudy-order.js``) runs the
same rule — ``repetitions`` blocks, each group's stimuli shuffled, the groups
interleaved round by round (the groups' order shuffled in every round, a smaller
group such as the shared originals in rounds drawn at random), a block never
starting with the motion the previous one ended with — over **sfc32**
(Doty-Humphrey's Small Fast Chaotic generator, 128-bit state, 32-bit outputs).
This module is its Python twin, written line for line; the tests run the
JavaScript file under node and in Chromium and compare.

* Seed: the key ``"flipstudy-web:{design seed}:{participant}"`` (UTF-8) hashed
  by 32-bit FNV-1a four times, with the prefixes ``"0:"`` … ``"3:"``, gives
  sfc32's state ``a, b, c, d``; the first 12 outputs are discarded.
* ``below(n)``: ``floor(u * n / 2**32)`` for the next output ``u`` (exact in
  JavaScript's doubles for n < 2**21).
* Shuffle: Fisher–Yates from the last element down (``j = below(i + 1)``).
* Sample k of ``0..R-1``: the first k places of a partial Fisher–Yates
  (``j = i + below(R - i)``).
* ``random()``: ``u / 2**32`` for the next output ``u``.
* 2AFC groups: after the last block, :func:`flipstudy.study.order.balance_first`
  (the local rule) sets which motion each 2AFC trial shows first, half each way
  within each group, drawn with this generator's ``shuffle`` and ``random``.

The local page's order is untouched (the same participant gets a different,
equally random order online than locally); the site stores nothing about the
order but the seed rule, and ``import-web`` recomputes each participant's order
with :func:`web_trial_order` and refuses a row whose stimulus does not match.

>>> fnv1a32(b""), fnv1a32(b"a")
(2166136261, 3826002220)
>>> g = Sfc32.from_key(order_key(7, "P01"))
>>> [g.below(10) for _ in range(8)]
[8, 5, 8, 9, 6, 8, 5, 8]
"""
from __future__ import annotations

import math
from typing import Iterable

from flipstudy.errors import FlipstudyValueError
from flipstudy.stimuli.contract import Stimulus

from ..order import Trial, balance_first, group_stimuli

RULE = "flipstudy-web-order/1 (sfc32 seeded by FNV-1a; the rule of flipstudy.study.order)"
M32 = 0xFFFFFFFF


def fnv1a32(data: bytes) -> int:
    """32-bit FNV-1a of ``data``."""
    h = 0x811C9DC5
    for b in data:
        h = ((h ^ b) * 0x01000193) & M32
    return h


def order_key(design_seed: int, participant: str) -> str:
    """The string the participant's generator is seeded from."""
    return f"flipstudy-web:{int(design_seed)}:{participant}"


class Sfc32:
    """sfc32 with 32-bit outputs (the JavaScript file's ``sfc32``)."""

    def __init__(self, a: int, b: int, c: int, d: int):
        self.a, self.b, self.c, self.d = a & M32, b & M32, c & M32, d & M32

    @classmethod
    def from_key(cls, key: str) -> "Sfc32":
        data = key.encode("utf-8")
        g = cls(*(fnv1a32(f"{i}:".encode() + data) for i in range(4)))
        for _ in range(12):
            g.next()
        return g

    def next(self) -> int:
        a, b, c, d = self.a, self.b, self.c, self.d
        t = (a + b) & M32
        a = b ^ (b >> 9)
        b = (c + (c << 3)) & M32
        c = ((c << 21) | (c >> 11)) & M32
        d = (d + 1) & M32
        t = (t + d) & M32
        c = (c + t) & M32
        self.a, self.b, self.c, self.d = a, b, c, d
        return t

    def below(self, n: int) -> int:
        """An integer in ``[0, n)``."""
        return (self.next() * n) >> 32

    def random(self) -> float:
        """A number in ``[0, 1)``."""
        return self.next() / 4294967296

    def shuffle(self, x: list) -> None:
        for i in range(len(x) - 1, 0, -1):
            j = self.below(i + 1)
            x[i], x[j] = x[j], x[i]

    def sample(self, n: int, k: int) -> list[int]:
        pool = list(range(n))
        for i in range(k):
            j = i + self.below(n - i)
            pool[i], pool[j] = pool[j], pool[i]
        return pool[:k]


def order_groups(design, manifest: Iterable[Stimulus]) -> list[list]:
    """The groups as the site's config holds them: ``[[group, [{stimulus, clip,
    kind, level}, ...]], ...]`` in the design's order, rows in manifest order (the
    constant trials' rows of :func:`flipstudy.study.order.group_stimuli`); a 2AFC
    group's rows also carry ``task`` ("2afc") and ``original`` (the comparison)."""
    groups = group_stimuli(manifest, design)
    if not groups:
        raise FlipstudyValueError("manifest.csv has no test stimuli (only reference rows)")
    tasks = {g.name: getattr(g, "task", "yes-no") for g in design.groups}

    def row(r, g):
        out = {"stimulus": r.stimulus, "clip": r.clip, "kind": r.kind, "level": r.level}
        if tasks.get(g) == "2afc":
            out.update(task="2afc", original=r.original)
        return out
    return [[g, [row(r, g) for r in rows]] for g, rows in groups.items()]


def balanced_latin_square(k: int) -> list[list[int]]:
    """Williams' balanced Latin square of ``k`` blocks: every block once in every position
    and, over the rows, every block right after every other the same number of times
    (k rows for an even k; 2k for an odd k: each row and its mirror).

    >>> balanced_latin_square(4)
    [[0, 1, 3, 2], [1, 2, 0, 3], [2, 3, 1, 0], [3, 0, 2, 1]]
    """
    k = int(k)
    step = [0] + [((j + 1) // 2 if j % 2 else k - j // 2) for j in range(1, k)]
    rows = [[(r + s_) % k for s_ in step] for r in range(k)]
    return rows + [row[::-1] for row in rows] if k % 2 else rows


def latin_row(participant: str, k: int) -> int:
    """The Latin-square row of a participant: FNV-1a of ``"flipstudy-latin:ID"`` modulo the
    number of rows (a static host cannot count participants; the rows are equally likely)."""
    return fnv1a32(f"flipstudy-latin:{participant}".encode()) % len(balanced_latin_square(k))


def condition_groups(groups: list[list], between, condition: str | None) -> list[list]:
    """The groups a participant in ``condition`` sees: every group not in ``between``,
    and of those in it, only ``condition``."""
    return [[g, rows] for g, rows in groups if g not in between or g == condition]


def condition_by_hash(participant: str, between) -> str:
    """A between-subject condition from the participant ID alone (a host that cannot count):
    FNV-1a of ``"flipstudy-condition:ID"`` modulo the number of conditions."""
    return list(between)[fnv1a32(f"flipstudy-condition:{participant}".encode()) % len(between)]


def web_trial_order(groups: list[list], repetitions: int, design_seed: int,
                    participant: str, block_order: str = "interleaved", row: int | None = None) -> list[Trial]:
    """The participant's trials online (``groups`` from :func:`order_groups`, or the
    site's config, whose rows name their video only: then clip and kind are empty and
    the level NaN).
    ``block_order`` "latin-square": one block per group in the order of Latin-square row
    ``row`` (None: :func:`latin_row` of the participant ID).

    >>> groups = [["a", [{"stimulus": f"a{i}", "clip": "c", "kind": "k", "level": i} for i in range(3)]],
    ...           ["b", [{"stimulus": f"b{i}", "clip": "c", "kind": "k", "level": i} for i in range(3)]]]
    >>> t = web_trial_order(groups, 2, 7, "P01")
    >>> len(t), sorted(x.stimulus for x in t if x.repetition == 1)
    (12, ['a0', 'a1', 'a2', 'b0', 'b1', 'b2'])
    >>> t == web_trial_order(groups, 2, 7, "P01"), t == web_trial_order(groups, 2, 7, "P02")
    (True, False)
    """
    rng = Sfc32.from_key(order_key(design_seed, participant))
    n_stimuli = sum(len(rows) for _, rows in groups)
    trials: list[Trial] = []
    if block_order == "latin-square":
        # one block per group in the order of the participant's Latin-square row; within a
        # block every repetition of the group's stimuli, shuffled, never one twice in a row
        square = balanced_latin_square(len(groups))
        row = square[latin_row(participant, len(groups)) if row is None else int(row)]
        for gi in row:
            g, rows = groups[gi]
            for _ in range(100):
                items = [(r, rep) for rep in range(1, int(repetitions) + 1) for r in rows]
                rng.shuffle(items)
                names = [r["stimulus"] for r, _ in items]
                prev = [trials[-1].stimulus] if trials else []
                seq = prev + names
                if len(rows) == 1 or all(a != b for a, b in zip(seq, seq[1:])):
                    break
            for r, rep in items:
                trials.append(Trial(len(trials) + 1, r["stimulus"], r.get("clip", ""), g, r.get("kind", ""),
                                    float(r.get("level", math.nan)), rep, task=r.get("task", "yes-no"),
                                    original=r.get("original", "")))
        return balance_first(trials, rng.shuffle, rng.random) if any(t.task == "2afc" for t in trials) else trials
    for rep in range(1, int(repetitions) + 1):
        for _ in range(100):
            block = _block(groups, rng)
            if not trials or n_stimuli == 1 or block[0][0]["stimulus"] != trials[-1].stimulus:
                break
        for row, g in block:
            trials.append(Trial(len(trials) + 1, row["stimulus"], row.get("clip", ""), g, row.get("kind", ""),
                                float(row.get("level", math.nan)), rep, task=row.get("task", "yes-no"),
                                original=row.get("original", "")))
    if any(t.task == "2afc" for t in trials):
        trials = balance_first(trials, rng.shuffle, rng.random)
    return trials


def _block(groups: list[list], rng: Sfc32) -> list[tuple[dict, str]]:
    queues = []
    for g, rows in groups:
        rows = list(rows)
        rng.shuffle(rows)
        queues.append((g, rows))
    R = max(len(q) for _, q in queues)
    rounds = {g: (set(range(R)) if len(q) == R else set(rng.sample(R, len(q)))) for g, q in queues}
    block = []
    for r in range(R):
        names = [g for g, _ in queues if r in rounds[g]]
        rng.shuffle(names)
        q = dict(queues)
        for g in names:
            block.append((q[g].pop(), g))
    return block
