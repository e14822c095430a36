"""Trial order and timeline of a session (study.order, study.timeline)."""
import collections
import hashlib
import json
import os
import re
import subprocess
import sys

from flipstudy.stimuli.contract import Stimulus, StimulusSet
from flipstudy.stimuli.design import PAPER_DESIGN, parse_design
from flipstudy.stimuli.stimset import plan
from flipstudy.study.order import participant_seed, reference_stimuli, trial_order
from flipstudy.study.timeline import build_timeline


def paper_manifest():
    d = parse_design(PAPER_DESIGN)
    rows = []
    for name, spec, group, level in plan(d):
        rows.append(Stimulus(name, spec.name, group.name if group else "reference",
                             group.kind if group else "reference", level=level))
    return d, rows


def test_participant_seed_is_sha256_of_design_seed_and_id():
    expect = int.from_bytes(hashlib.sha256(b"20070803:P01").digest()[:8], "big")
    assert participant_seed(20070803, "P01") == expect
    assert participant_seed(20070803, "P01", 2) != expect
    assert participant_seed(20070803, "P02") != expect


def test_paper_design_order_blocks_groups_and_levels():
    """The paper's design: the four angular-momentum groups share one original per
    clip (group "original"), the take-off group has its own level 0; each motion
    file is shown `repetitions` (2) times — before, each original was shown 10 times."""
    d, rows = paper_manifest()
    trials = trial_order(d, rows, "P01")
    tests = [r for r in rows if r.group != "reference"]
    assert len(tests) == 2 * (4 * 4 + 1 + 5)
    assert len(trials) == d.repetitions * len(tests) == 88
    assert [t.trial for t in trials] == list(range(1, 89))
    assert set(collections.Counter(t.stimulus for t in trials).values()) == {d.repetitions}
    G = len(d.groups)
    for rep in (1, 2):
        block = [t for t in trials if t.repetition == rep]
        # every stimulus of every non-reference group exactly once per block
        assert collections.Counter(t.stimulus for t in block) == collections.Counter(
            r.stimulus for r in tests)
        # groups interleaved round by round: the take-off group (10 rows, the most) is in
        # every round, every other group at most once a round, so in every prefix of the
        # block no group is more than one ahead of it
        seen = collections.Counter()
        for t in block:
            seen[t.group] += 1
            assert seen[t.group] <= seen["takeoff-increase"] + 1, (rep, t)
        assert set(seen) == {g.name for g in d.groups} | {"original"} and len(d.groups) == G
    # level-0 trials: the shared original of each clip and the take-off group's own
    assert {(t.group, t.clip, t.level) for t in trials if t.level == 0} == {
        (g, c, 0.0) for g in ("original", "takeoff-increase") for c in ("backflip", "frontflip")}
    # the trials are rows of the manifest, with its condition
    by = {r.stimulus: r for r in rows}
    for t in trials:
        assert (t.group, t.clip, t.level) == (by[t.stimulus].group, by[t.stimulus].clip,
                                              by[t.stimulus].level)


def test_shared_originals_spread_over_the_block():
    """The two shared originals are not bunched at the start of every block: over
    many participants their positions cover the block."""
    d, rows = paper_manifest()
    pos = []
    for i in range(60):
        trials = trial_order(d, rows, f"P{i:02d}")
        pos += [t.trial - (t.repetition - 1) * 44 for t in trials if t.group == "original"]
    assert min(pos) <= 6 and max(pos) >= 38


def test_per_group_originals_as_before():
    """original = "per-group": every group has its own level 0 (100 trials)."""
    d = parse_design(PAPER_DESIGN.replace('original = "shared"', 'original = "per-group"'))
    names = [n for n, _, g, _ in plan(d) if g is not None]
    assert len(names) == 50 and not any(n.endswith("_original") for n in names)
    assert sum(n.endswith("_0") for n in names) == 10


def test_order_is_random_within_group_and_seeded_per_participant():
    d, rows = paper_manifest()
    a1, a2 = trial_order(d, rows, "P01"), trial_order(d, rows, "P01")
    b = trial_order(d, rows, "P02")
    assert a1 == a2
    assert [t.stimulus for t in a1] != [t.stimulus for t in b]
    # the two repetition blocks differ, and within a group the order is not the manifest's
    block1 = [t.stimulus for t in a1 if t.repetition == 1]
    block2 = [t.stimulus for t in a1 if t.repetition == 2]
    assert block1 != block2
    manifest_order = [r.stimulus for r in rows if r.group == "smooth-increase"]
    within = [s for s in block1 if "smooth-increase" in s]
    assert sorted(within) == sorted(manifest_order) and within != manifest_order
    # over many participants every group leads a block about equally often
    firsts = collections.Counter(trial_order(d, rows, f"P{i:03d}")[0].group for i in range(200))
    # (the shared originals, 2 rows in 10 rounds, lead about 1 block in 20)
    assert set(firsts) == {g.name for g in d.groups} | {"original"}
    assert min(firsts[g.name] for g in d.groups) > 20 and firsts["original"] < 25


def test_order_does_not_depend_on_python_hash_seed():
    code = ("import types; from study.order import trial_order;"
            "d = types.SimpleNamespace(seed=5, repetitions=2, groups=[]);"
            "from flipstudy.stimuli.contract import Stimulus;"
            "r = [Stimulus(f'c_{g}_{l}', 'c', g, '', level=l)"
            "     for g in 'abcde' for l in (0, 10, 20, 30)];"
            "print(','.join(t.stimulus for t in trial_order(d, r, 'P01')))")
    outs = set()
    for seed in ("1", "2"):
        env = dict(os.environ, PYTHONHASHSEED=seed)
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                             cwd=os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                             check=True)
        outs.add(out.stdout)
    assert len(outs) == 1


def test_uneven_groups_are_all_used():
    d, rows = paper_manifest()
    rows = [r for r in rows if not (r.group == "takeoff-increase" and r.level != 0)]
    trials = trial_order(d, rows, "X")
    assert len(trials) == 2 * (len(rows) - 2)
    assert collections.Counter(t.group for t in trials)["takeoff-increase"] == 2 * 2


class _FakeSession:
    def __init__(self, design, rows, n=None, participant="P01"):
        from flipstudy.study.session import Study
        self.study = Study(None, design, StimulusSet(".", rows, design, "x"))
        self.trials = trial_order(design, rows, participant)[:n]
        self.participant, self.session = participant, 1

    @property
    def n_trials(self):
        return len(self.trials)


def _state(answered=0, demographics=False):
    return {"answered": answered, "demographics": demographics}


def test_timeline_screens_and_breaks():
    d, rows = paper_manifest()
    s = _FakeSession(d, rows)
    tl = build_timeline(s, _state())
    json.dumps(tl)                           # plain data
    types = [x["type"] for x in tl["timeline"]]
    assert types[:3] == ["instructions", "demographics", "examples"]
    assert types[-1] == "end" and tl["start"] == 0
    trials = [x for x in tl["timeline"] if x["type"] == "trial"]
    assert [x["trial"] for x in trials] == list(range(1, 89))
    assert [x["stimulus"] for x in trials] == [t.stimulus for t in s.trials]
    assert all(x["video"] == f"/stimuli/{x['stimulus']}.mp4" and x["replay"] is False for x in trials)
    # a break after every 40 trials (not after the last)
    i_breaks = [i for i, x in enumerate(tl["timeline"]) if x["type"] == "break"]
    assert [tl["timeline"][i - 1]["trial"] for i in i_breaks] == [40, 80]
    ex = tl["timeline"][2]
    assert [e["video"] for e in ex["stimuli"]] == [f"/stimuli/{r.stimulus}.mp4"
                                                   for r in reference_stimuli(rows)]
    assert all("correct" in e["label"].lower() for e in ex["stimuli"])
    assert tl["keys"] == {"correct": "f", "incorrect": "j"}


def test_instructions_follow_the_paper_and_reveal_nothing():
    d, rows = paper_manifest()
    tl = build_timeline(_FakeSession(d, rows), _state())
    text = " ".join(tl["timeline"][0]["paragraphs"]).lower()
    assert "some of these motions are physically correct and some of them are not" in text
    assert "correct" in text and "incorrect" in text and "examples of physically correct" in text
    # not how many, not which kind
    assert not re.search(r"\d", text.replace("f = correct", "").replace("j = incorrect", ""))
    for word in ("momentum", "angle", "take-off", "takeoff", "half", "percent", "%", "speed",
                 "rotation", "how many", "error"):
        assert word not in text, word


def test_timeline_resume_points():
    d, rows = paper_manifest()
    s = _FakeSession(d, rows)
    tl = build_timeline(s, _state(demographics=True))
    assert tl["timeline"][tl["start"]]["type"] == "examples"
    tl = build_timeline(s, _state(answered=41, demographics=True))
    first = tl["timeline"][tl["start"]]
    assert first["id"] == "resume" and "41" in " ".join(first["paragraphs"])
    nxt = tl["timeline"][tl["start"] + 1]
    assert nxt["type"] == "trial" and nxt["trial"] == 42
    tl = build_timeline(s, _state(answered=100, demographics=True))
    assert tl["timeline"][tl["start"]]["type"] == "end"


def test_replay_flag_comes_from_the_design():
    text = PAPER_DESIGN.replace("replay = false", "replay = true")
    d = parse_design(text)
    _, rows = paper_manifest()
    tl = build_timeline(_FakeSession(d, rows, n=5), _state())
    assert all(x["replay"] is True for x in tl["timeline"] if x["type"] == "trial")


def test_no_motion_twice_in_a_row():
    d = parse_design(PAPER_DESIGN.replace("repetitions = 2", "repetitions = 4"))
    rows = [Stimulus(f"c_{g}_{lv}", "c", g, "", level=lv)
            for g in ("smooth-increase", "abrupt-decrease") for lv in (0, 25)]
    for i in range(300):
        t = trial_order(d, rows, f"P{i}")
        assert all(a.stimulus != b.stimulus for a, b in zip(t, t[1:]))
