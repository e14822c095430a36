"""Issue 32, item 5: block orders by a balanced Latin square ([online] block_order =
"latin-square"): the square is balanced (counted here, not by its construction), the
JavaScript twin gives the same orders as Python, each participant's blocks follow their
row, and import-web checks the recorded row."""
import collections
import json
import shutil
import subprocess
from pathlib import Path

import pandas as pd
import pytest

import flipstudy.study.web as web_pkg
from flipstudy.errors import WebImportError
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.order import balanced_latin_square, latin_row, order_groups, web_trial_order
from flipstudy.study.web.site import FORMAT
from _site_names import as_site_writes

JS = Path(web_pkg.__file__).parent / "static" / "flipstudy-order.js"
GROUPS4 = (("smooth-increase", "angular-momentum", "smooth", 1), ("abrupt-decrease", "angular-momentum", "abrupt", -1),
           ("smooth-decrease", "angular-momentum", "smooth", -1), ("takeoff-increase", "takeoff-angle", None, 1))
IDS = [f"P{i:02d}" for i in range(40)] + ["5f1a2b3c4d5e6f7a8b9c0d1e", "x_y-z"]


@pytest.mark.parametrize("k", range(1, 10))
def test_the_square_is_balanced(k):
    rows = balanced_latin_square(k)
    assert all(sorted(r) == list(range(k)) for r in rows)
    position = collections.Counter((r[j], j) for r in rows for j in range(k))
    assert set(position.values()) == {len(rows) // k} and len(position) == k * k     # each block, each place
    follows = collections.Counter((r[j], r[j + 1]) for r in rows for j in range(k - 1))
    if k > 1:                                          # each ordered pair adjacent equally often
        assert len(follows) == k * (k - 1) and len(set(follows.values())) == 1


@pytest.fixture
def study(tmp_path):
    return make_demo_study(tmp_path / "study", videos=False, levels=(0, 25), repetitions=2, groups=GROUPS4,
                           extra='[online]\nblock_order = "latin-square"\n')


def test_each_participant_sees_one_block_per_group_in_their_row(study):
    st = load_study(study)
    groups = order_groups(st.design, st.manifest)
    names = [g for g, _ in groups]
    rows_used = collections.Counter()
    for pid in IDS:
        t = web_trial_order(groups, 2, st.design.seed, pid, "latin-square")
        blocks = [g for g, _ in __import__("itertools").groupby(x.group for x in t)]
        row = balanced_latin_square(4)[latin_row(pid, 4)]
        assert blocks == [names[i] for i in row], pid                      # contiguous, in the row's order
        assert collections.Counter(x.stimulus for x in t) == {r["stimulus"]: 2 for _, rs in groups for r in rs}
        assert all(a.stimulus != b.stimulus for a, b in zip(t, t[1:]))
        rows_used[latin_row(pid, 4)] += 1
    assert set(rows_used) == {0, 1, 2, 3}             # every row in use (by the ID's hash)


@pytest.mark.skipif(shutil.which("node") is None, reason="needs node to run the site's JavaScript")
def test_javascript_twin_gives_the_same_latin_square_orders(study):
    st = load_study(study)
    groups = order_groups(st.design, st.manifest)
    script = (f"const o = require({json.dumps(str(JS))}); const g = {json.dumps(groups)};"
              f"console.log(JSON.stringify({{sq: [1,2,3,4,5,6,7].map((k) => o.balancedLatinSquare(k)),"
              f"orders: {json.dumps(IDS)}.map((p) => o.webTrialOrder(g, 2, {st.design.seed}, p, 'latin-square')"
              f".map((t) => [t.trial, t.stimulus, t.group, t.repetition]))}}));")
    r = subprocess.run(["node", "-e", script], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    assert got["sq"] == [balanced_latin_square(k) for k in range(1, 8)]
    for pid, js in zip(IDS, got["orders"]):
        py = web_trial_order(groups, 2, st.design.seed, pid, "latin-square")
        assert js == [[t.trial, t.stimulus, t.group, t.repetition] for t in py], pid


def test_import_records_and_checks_the_row(study, tmp_path):
    st = load_study(study)
    groups = order_groups(st.design, st.manifest)
    trials = web_trial_order(groups, 2, st.design.seed, "P01", "latin-square")
    blocks = " ".join(dict.fromkeys(t.group for t in trials))
    base = {"format": FORMAT, "site_id": "s", "study": st.design.name, "manifest_sha256": st.manifest_sha256,
            "host": "jatos", "participant": "P01", "run_id": "r1", "run_started": "2026-01-05T10:00:00.000Z",
            "timestamp": "2026-01-05T10:00:01.000Z"}
    start, = as_site_writes(study, [dict(base, record="start", n_trials=len(trials), block_order=blocks,
                                         order=" ".join(t.stimulus for t in trials))])
    f = tmp_path / "a.jsonl"
    f.write_text(json.dumps(start) + "\n")
    import_web(study, [f])
    assert pd.read_csv(study / "web" / "participants.csv").loc[0, "block_order"] == blocks
    bad = tmp_path / "b.jsonl"
    bad.write_text(json.dumps(dict(start, run_id="r2", block_order=" ".join(reversed(start["block_order"].split()))))
                   + "\n")
    with pytest.raises(WebImportError, match="is not P01's Latin-square row"):
        import_web(study, [bad])
