"""The site's trial order (study/web/static/flipstudy-order.js) equals its Python twin
(flipstudy.study.web.order) for many participant IDs and design shapes, and has the
structure of flipstudy.study.order: every stimulus once per repetition, groups
interleaved, no motion twice in a row across a block boundary.  The JavaScript runs
under node (skipped without it); in Chromium, tests/study/web/test_web_browser.py compares
the order of the session it runs."""
import json
import shutil
import subprocess
from collections import Counter
from pathlib import Path

import pytest

from flipstudy.study.demo import make_demo_study
from flipstudy.study.order import trial_order
from flipstudy.study.session import load_study
from flipstudy.study.web.order import Sfc32, fnv1a32, order_groups, order_key, web_trial_order

JS = Path(__file__).resolve().parents[3] / "study" / "web" / "static" / "flipstudy-order.js"
IDS = ["P01", "P02", "K01", "sim001", "5f3c9a1b2d4e6f7081920a1b", "W-x_9", "a", "Z" * 32]


def _study(tmp_path, **kw):
    return load_study(make_demo_study(tmp_path / "s", videos=False, **kw))


SHAPES = {
    "per-group": dict(levels=(0, 25), repetitions=2),
    "shared-original": dict(levels=(0, 17, 50), repetitions=3, clips=("backflip", "frontflip"),
                            original="shared"),
    "one-rep": dict(levels=(0, 10, 20, 30, 40), repetitions=1),
}


def _node(groups, reps, seed, ids, fields="t.trial, t.stimulus, t.group, t.repetition"):
    script = (f"const o = require({json.dumps(str(JS))});"
              f"const g = {json.dumps(groups)};"
              f"console.log(JSON.stringify({json.dumps(ids)}.map((p) => o.webTrialOrder(g, {reps}, {seed}, p)"
              f".map((t) => [{fields}]))));")
    r = subprocess.run(["node", "-e", script], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.mark.skipif(shutil.which("node") is None, reason="needs node to run the site's JavaScript")
@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_javascript_order_equals_python_twin(tmp_path, shape):
    st = _study(tmp_path, **SHAPES[shape])
    groups = order_groups(st.design, st.manifest)
    got = _node(groups, st.design.repetitions, st.design.seed, IDS)
    for pid, js in zip(IDS, got):
        py = web_trial_order(groups, st.design.repetitions, st.design.seed, pid)
        assert js == [[t.trial, t.stimulus, t.group, t.repetition] for t in py], pid


@pytest.mark.skipif(shutil.which("node") is None, reason="needs node to run the site's JavaScript")
def test_javascript_generator_equals_python_twin():
    script = (f"const o = require({json.dumps(str(JS))});"
              "const g = o.Sfc32.fromKey(o.orderKey(20070803, 'P01'));"
              "const out = []; for (let i = 0; i < 2000; i++) out.push(g.next());"
              "out.push(o.fnv1a32(new TextEncoder().encode('flipstudy')));"
              "console.log(JSON.stringify(out));")
    js = json.loads(subprocess.run(["node", "-e", script], capture_output=True, text=True, check=True).stdout)
    g = Sfc32.from_key(order_key(20070803, "P01"))
    assert js == [g.next() for _ in range(2000)] + [fnv1a32(b"flipstudy")]


@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_web_order_has_the_local_rules_structure(tmp_path, shape):
    st = _study(tmp_path, **SHAPES[shape])
    groups = order_groups(st.design, st.manifest)
    names = [r["stimulus"] for _, rows in groups for r in rows]
    orders = set()
    for pid in IDS:
        web = web_trial_order(groups, st.design.repetitions, st.design.seed, pid)
        local = trial_order(st.design, st.manifest, pid)
        # the same trials as the local rule gives, in another random order
        assert sorted((t.stimulus, t.repetition) for t in web) == sorted((t.stimulus, t.repetition) for t in local)
        for rep in range(1, st.design.repetitions + 1):
            assert Counter(t.stimulus for t in web if t.repetition == rep) == Counter(names)
        assert all(a.stimulus != b.stimulus for a, b in zip(web, web[1:]))
        assert [t.trial for t in web] == list(range(1, len(web) + 1))
        orders.add(tuple(t.stimulus for t in web))
        # interleaved: the first round of each block has one stimulus of each full group
        full = [g for g, rows in groups if len(rows) == max(len(r) for _, r in groups)]
        first = web[:len(full)] if shape != "shared-original" else None
        if first is not None:
            assert sorted(t.group for t in first) == sorted(full)
    assert len(orders) == len(IDS)                      # participants get different orders


def test_local_order_is_unchanged(tmp_path):
    """The local page keeps its Mersenne-Twister order (reproduce's bytes)."""
    st = _study(tmp_path, **SHAPES["per-group"])
    assert trial_order(st.design, st.manifest, "P01")[0].stimulus == "backflip_smooth-increase_0"


# --- 2AFC groups: which motion comes first, from the same generator --------------------------

TWO_AFC_SHAPES = {
    "2afc": ([{"name": "up", "sign": 1, "levels": [0, 25, 50], "task": "2afc"},
              {"name": "down", "sign": -1, "levels": [0, 10, 20, 40], "task": "2afc"}], 2, "per-group"),
    "mixed-shared": ([{"name": "up", "sign": 1, "levels": [0, 17, 50]},
                      {"name": "down", "sign": -1, "levels": [0, 30], "task": "2afc"}], 3, "shared"),
}


def _2afc_study(tmp_path, shape):
    from _kinds import design_text, make_study
    groups, reps, original = TWO_AFC_SHAPES[shape]
    return load_study(make_study(tmp_path / "s", design_text(groups, repetitions=reps, original=original),
                                 videos=False))


@pytest.mark.skipif(shutil.which("node") is None, reason="needs node to run the site's JavaScript")
@pytest.mark.parametrize("shape", sorted(TWO_AFC_SHAPES))
def test_javascript_2afc_order_and_first_equal_python_twin(tmp_path, shape):
    st = _2afc_study(tmp_path, shape)
    groups = order_groups(st.design, st.manifest)
    got = _node(groups, st.design.repetitions, st.design.seed, IDS,
                fields="t.trial, t.stimulus, t.group, t.repetition, t.task || 'yes-no', t.first || '', "
                       "t.original || ''")
    for pid, js in zip(IDS, got):
        py = web_trial_order(groups, st.design.repetitions, st.design.seed, pid)
        assert js == [[t.trial, t.stimulus, t.group, t.repetition, t.task, t.first, t.original] for t in py], pid


@pytest.mark.parametrize("shape", sorted(TWO_AFC_SHAPES))
def test_web_2afc_order_is_balanced_like_the_local_one(tmp_path, shape):
    st = _2afc_study(tmp_path, shape)
    groups = order_groups(st.design, st.manifest)
    two = {g.name for g in st.design.groups if g.task == "2afc"}
    firsts = Counter()
    for pid in IDS:
        web = web_trial_order(groups, st.design.repetitions, st.design.seed, pid)
        local = trial_order(st.design, st.manifest, pid)
        # the same trials (stimulus, comparison, task) as the local session's, no level 0 in 2AFC
        key = lambda t: (t.stimulus, t.repetition, t.task, t.original)  # noqa: E731
        assert sorted(map(key, web)) == sorted(map(key, local))
        assert all(t.level > 0 and t.original.endswith("_0") or t.original.endswith("_original")
                   for t in web if t.task == "2afc")
        for g in two:
            f = Counter(t.first for t in web if t.group == g)
            assert set(f) <= {"original", "modified"} and abs(f["original"] - f["modified"]) <= 1, (pid, g, f)
            firsts.update(t.first for t in web if t.group == g)
        assert all(t.first == "" and t.original == "" for t in web if t.task == "yes-no")
    assert firsts["original"] and firsts["modified"]
