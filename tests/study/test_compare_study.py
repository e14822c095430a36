"""Comparison studies ([[sources]]): the design, the build (items matched across
source folders), the trials the local and web orders make of it, simulated
observers with known source preferences, and `flipstudy analyze` of it."""
from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from flipstudy import builtin, save_bvh
from flipstudy.errors import SourceMismatchError
from flipstudy.stimuli.contract import StimulusSet
from flipstudy.stimuli.design import Design, DesignError
from flipstudy.stimuli.motion.clip import Clip
from flipstudy.stimuli.stimset import build_stimuli

ITEMS = ("backflip", "jump")


def _write_sources(root: Path, items=ITEMS) -> None:
    """gt: the built-ins as they are; jitter: 1.5 cm of noise on the root every frame;
    floaty: the root rising 0 → 8 cm over the clip."""
    rng = np.random.default_rng(0)
    for s in ("gt", "jitter", "floaty"):
        (root / s).mkdir(parents=True, exist_ok=True)
    for n in items:
        c = builtin(n)
        save_bvh(c, root / "gt" / f"{n}.bvh")
        rp = c.root_pos + rng.normal(0, 0.015, c.root_pos.shape)
        save_bvh(Clip(c.skeleton, c.fps, rp, c.rotations), root / "jitter" / f"{n}.bvh")
        rp = c.root_pos.copy()
        rp[:, 1] += np.linspace(0, 0.08, c.num_frames)
        save_bvh(Clip(c.skeleton, c.fps, rp, c.rotations), root / "floaty" / f"{n}.bvh")


def _design(root: Path, task="2afc", repetitions=1, extra="") -> Path:
    p = root / "design.toml"
    p.write_text(f"""[study]
name = "compare-test"
seed = 7
task = "{task}"
repetitions = {repetitions}
style = "capsules"

[[sources]]
name = "gt"
folder = "gt"

[[sources]]
name = "jitter"
folder = "jitter"

[[sources]]
name = "floaty"
folder = "floaty"
{extra}""")
    return p


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    root = tmp_path_factory.mktemp("cmp")
    _write_sources(root)
    design = Design.from_toml(_design(root, repetitions=2))
    build_stimuli(design, root / "study", progress=False)
    return root / "study"


def test_a_comparison_design_round_trips_and_its_groups_are_its_sources(tmp_path):
    d = Design.from_toml(_design(tmp_path))
    assert [s.name for s in d.sources] == ["gt", "jitter", "floaty"] and d.compares
    assert [(g.name, g.task, g.kind) for g in d.groups] == [(s, "2afc", "given") for s in ("gt", "jitter", "floaty")]
    assert Design.from_toml_text(d.to_toml()) == d and Design.from_dict(d.to_dict()) == d
    assert "[[groups]]" not in d.to_toml() and "[[clips]]" not in d.to_toml()


@pytest.mark.parametrize("extra, message", [
    ('\n[[clips]]\nname = "x"\nsource = "backflip"\n', r"\[\[clips\]\] and \[\[sources\]\]"),
    ('\n[[groups]]\nname = "g"\nkind = "takeoff-angle"\nlevels = [0, 10]\nstyle = "stick"\n',
     r"groups\[0\] \(g\).style: one style for the whole comparison study"),
    ('\n[[sources]]\nname = "gt"\nfolder = "other"\n', r"duplicate source names \['gt'\]"),
    ('\n[[sources]]\nname = "x"\nfoldr = "x"\n', r"sources\[3\] \(x\).*foldr.*did you mean 'folder'"),
])
def test_bad_comparison_designs_name_the_section(tmp_path, extra, message):
    with pytest.raises(DesignError, match=message):
        Design.from_toml(_design(tmp_path, extra=extra))


def test_an_item_missing_in_one_source_names_the_folder_and_the_item(tmp_path):
    _write_sources(tmp_path)
    (tmp_path / "floaty" / "jump.bvh").unlink()
    design = Design.from_toml(_design(tmp_path))
    with pytest.raises(SourceMismatchError) as e:
        build_stimuli(design, tmp_path / "study", progress=False)
    msg = str(e.value)
    assert str(tmp_path / "floaty") in msg and "'jump'" in msg and str(tmp_path / "gt" / "jump.bvh") in msg
    assert not (tmp_path / "study").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".study")]   # nothing half-written


def test_a_missing_or_empty_source_folder_is_a_clear_error(tmp_path):
    _write_sources(tmp_path)
    for f in (tmp_path / "jitter").iterdir():
        f.unlink()
    with pytest.raises(SourceMismatchError, match=rf"sources 'jitter': folder {tmp_path / 'jitter'} holds no clip"):
        build_stimuli(Design.from_toml(_design(tmp_path)), tmp_path / "study", progress=False)


def test_the_manifest_holds_one_row_per_item_and_source_through_the_contract(built):
    st = StimulusSet.read(built)
    assert st.sourced and st.sources() == ["gt", "jitter", "floaty"]
    assert st.names == [f"{i}_{s}" for i in ITEMS for s in ("gt", "jitter", "floaty")]
    for s in st:
        assert (s.group, s.kind, s.level, s.style) == (s.source, "given", 0.0, "capsules")
        assert s.original == ("" if s.source == "gt" else f"{s.clip}_gt")
    assert (built / "manifest.csv").read_text() == st.manifest_text()       # written byte for byte
    # the given clips are what the sources hold: the gt copy has the built-in's flight
    assert st["backflip_gt"].landing > st["backflip_gt"].takeoff > 0
    assert st["backflip_gt"].sha256 != st["backflip_floaty"].sha256


def test_local_and_web_orders_make_balanced_2afc_trials_against_the_first_source(built):
    from flipstudy.study.order import trial_order
    from flipstudy.study.web.order import order_groups, web_trial_order
    st = StimulusSet.read(built)
    for trials in (trial_order(st.design, st, "P01"),
                   web_trial_order(order_groups(st.design, st), st.design.repetitions, st.design.seed, "P01")):
        assert len(trials) == len(ITEMS) * 2 * 2                # items × challengers × repetitions
        assert all(t.task == "2afc" for t in trials)
        pairs = Counter((t.stimulus, t.original) for t in trials)
        assert pairs == Counter({(f"{i}_{s}", f"{i}_gt"): 2 for i in ITEMS for s in ("jitter", "floaty")})
        for g in ("jitter", "floaty"):                           # left/right balanced per source
            firsts = Counter(t.first for t in trials if t.group == g)
            assert firsts["original"] == firsts["modified"] == 2


def test_a_yes_no_comparison_asks_about_every_clip(tmp_path):
    from flipstudy.study.order import trial_order
    _write_sources(tmp_path, items=("jump",))
    build_stimuli(Design.from_toml(_design(tmp_path, task="yes-no")), tmp_path / "study", progress=False)
    st = StimulusSet.read(tmp_path / "study")
    trials = trial_order(st.design, st, "P01")
    assert sorted(t.stimulus for t in trials) == sorted(["jump_gt", "jump_jitter", "jump_floaty"])
    assert {t.task for t in trials} == {"yes-no"} and all(s.original == "" for s in st)
    # its answers are ratings per source: `analyze STUDY` tables them as groups at level 0
    from flipstudy.study.cli import main
    from flipstudy.study.simulate import simulate
    simulate(tmp_path / "study", 10, seed=2, strengths={"gt": 3.0, "jitter": 0.0, "floaty": -3.0})
    assert main(["export", str(tmp_path / "study"), "--include-simulated"]) == 0
    assert main(["analyze", str(tmp_path / "study"), "--include-simulated", "--psychometric", "none",
                 "--no-gee", "--no-figures", "--n-boot", "50"]) == 0
    t = pd.read_csv(tmp_path / "study" / "analysis" / "table.csv").set_index("group")
    assert set(t.index) >= {"gt", "jitter", "floaty"} and (t.loc[["gt", "jitter", "floaty"], "n"] == 10).all()
    assert t.loc["gt", "rating_pct"] > t.loc["floaty", "rating_pct"]     # P(correct) 95 % against 5 %


def test_a_small_simulated_panel_is_stored_exported_and_analysed(built, tmp_path):
    """The fast twin of the slow test below: 4 participants' answers go through the
    store and export (with the left/right order), `flipstudy analyze STUDY` writes
    the comparison's tables with every choice counted."""
    import shutil

    from flipstudy.study.cli import main
    from flipstudy.study.simulate import simulate
    study = tmp_path / "study"
    shutil.copytree(built, study)
    simulate(study, 4, seed=1, strengths={"gt": 0.0, "jitter": -1.0, "floaty": -2.0})
    assert main(["export", str(study), "--include-simulated"]) == 0
    df = pd.read_csv(study / "responses.csv")
    assert len(df) == 4 * 8 and set(df["first"]) <= {"original", "modified"} and df.simulated.all()
    assert main(["analyze", str(study), "--include-simulated", "--n-boot", "20", "--no-figures"]) == 0
    r = pd.read_csv(study / "analysis" / "ranking.csv")
    assert r.source.tolist() == ["gt", "jitter", "floaty"] and r.n.sum() == 2 * 32
    assert main(["analyze", str(study), "--n-boot", "20"]) == 1      # simulated only: left out, said so
    from flipstudy.results import CompareResult
    from flipstudy.study.compare import analyze_comparison
    res = analyze_comparison(study, tmp_path / "again", include_simulated=True, n_boot=20, figures=False)
    assert CompareResult.load_json(res.save_json(tmp_path / "compare.json")) == res
    pd.testing.assert_frame_equal(pd.DataFrame([x.to_dict() for x in res.report.ranking]), r, atol=1e-6)   # the CSV's six decimals
    assert "Bradley–Terry ranking (32 choices" in res.summary()


@pytest.mark.slow
def test_simulated_observers_answer_with_their_known_preferences_and_analyze_ranks_them(built, tmp_path):
    """30 simulated participants (gt = 0, jitter = −1, floaty = −2.5 logits): the
    exported answers record which clip came first; `flipstudy analyze STUDY` ranks
    the sources in the known order with intervals that hold the truth."""
    import shutil

    from flipstudy.study.cli import main
    from flipstudy.study.simulate import simulate
    study = tmp_path / "study"
    shutil.copytree(built, study)
    truth = {"gt": 0.0, "jitter": -1.0, "floaty": -2.5}
    simulate(study, 30, seed=3, strengths=truth)
    assert main(["export", str(study), "--include-simulated"]) == 0
    df = pd.read_csv(study / "responses.csv")
    assert len(df) == 30 * 8 and set(df["first"]) == {"original", "modified"}
    assert set(df.original_stimulus) == {f"{i}_gt" for i in ITEMS}
    # P(the challenger chosen) = logistic(θ − 0), by source
    chosen = (df.response == "first") == (df["first"] == "modified")
    rate = chosen.groupby(df.group).mean()
    assert rate["jitter"] == pytest.approx(1 / (1 + np.e), abs=0.1)
    assert rate["floaty"] == pytest.approx(1 / (1 + np.exp(2.5)), abs=0.07)
    assert main(["analyze", str(study), "--include-simulated", "--n-boot", "100"]) == 0
    r = pd.read_csv(study / "analysis" / "ranking.csv").set_index("source")
    assert list(r.strength.sort_values(ascending=False).index) == ["gt", "jitter", "floaty"]
    for s, th in truth.items():
        assert r.loc[s, "low"] - 1e-9 <= th <= r.loc[s, "high"] + 1e-9
    a = pd.read_csv(study / "analysis" / "agreement.csv").set_index("metric")
    assert set(a.index) == {"score_p_any", "foot-skate_mm", "floating_mm", "penetration_mm"}
    assert (a.n == 240).all() and a.auc.between(0, 1).all()
    w = pd.read_csv(study / "analysis" / "win_rates.csv")
    assert set(w.item) == set(ITEMS) and (w.groupby("item").n.sum() == 2 * 120).all()


def test_strengths_must_name_the_study_sources(built):
    from flipstudy.errors import ComparisonError
    from flipstudy.study.simulate import simulate
    with pytest.raises(ComparisonError, match="missing floaty"):
        simulate(built, 1, strengths={"gt": 0, "jitter": -1})
    with pytest.raises(ComparisonError, match="unknown model"):
        simulate(built, 1, strengths={"gt": 0, "jitter": -1, "floaty": 0, "model": 1})


@pytest.mark.skipif(__import__("shutil").which("node") is None, reason="needs node to run the site's JavaScript")
def test_the_sites_javascript_serves_the_comparisons_as_its_python_twin(built):
    """export-web's order (flipstudy-order.js under node) gives each participant the
    same comparison trials, comparisons and left/right order as its Python twin."""
    from test_web_order import _node

    from flipstudy.study.session import load_study
    from flipstudy.study.web.order import order_groups, web_trial_order
    st = load_study(built)
    groups = order_groups(st.design, st.manifest)
    ids = ["P01", "sim002", "5f3c9a1b2d4e6f7081920a1b"]
    got = _node(groups, st.design.repetitions, st.design.seed, ids,
                fields="t.stimulus, t.group, t.task || 'yes-no', t.first || '', t.original || ''")
    for pid, js in zip(ids, got):
        py = web_trial_order(groups, st.design.repetitions, st.design.seed, pid)
        assert js == [[t.stimulus, t.group, t.task, t.first, t.original] for t in py], pid
        assert {(s, o) for s, _, _, _, o in js} == {(f"{i}_{g}", f"{i}_gt") for i in ITEMS
                                                     for g in ("jitter", "floaty")}


GROUPS = """
[[groups]]
name = "takeoff"
kind = "takeoff-angle"
levels = [0, 20]
"""


def test_error_groups_on_top_of_every_source_round_trip_and_are_checked(tmp_path):
    d = Design.from_toml(_design(tmp_path, extra=GROUPS))
    assert [g.name for g in d.groups] == ["gt", "jitter", "floaty", "takeoff"]
    assert [g.name for g in d.error_groups] == ["takeoff"]
    assert Design.from_toml_text(d.to_toml()) == d
    with pytest.raises(DesignError, match=r"groups\[0\] \(takeoff\).task: 'yes-no', the study's is '2afc'"):
        Design.from_toml(_design(tmp_path, extra=GROUPS + 'task = "yes-no"\n'))
    with pytest.raises(DesignError, match="'gt' is a source's"):
        Design.from_toml(_design(tmp_path, extra=GROUPS.replace('"takeoff"', '"gt"', 1)))


def test_errors_are_injected_into_each_sources_clip_and_shown_beside_it(tmp_path):
    """A take-off angle +20 % group on top of the sources: per item and source one
    modified clip whose 2AFC comparison is that source's clip as given; its flight's
    horizontal COM speed (a line fitted to the written BVH's COM) is 1.2× the given's."""
    from flipstudy import analyse, load_bvh
    from flipstudy.study.order import trial_order
    _write_sources(tmp_path, items=("backflip",))
    build_stimuli(Design.from_toml(_design(tmp_path, extra=GROUPS)), tmp_path / "study", progress=False)
    st = StimulusSet.read(tmp_path / "study")
    for src in ("gt", "jitter", "floaty"):
        s = st[f"backflip_{src}_takeoff_20"]
        assert (s.group, s.kind, s.level, s.source, s.original) == ("takeoff", "takeoff-angle", 20.0, src,
                                                                    f"backflip_{src}")
        speeds = []
        for name in (s.original, s.stimulus):
            a = analyse(load_bvh(st.path(name), scale=1.0))
            f = np.arange(a.takeoff, a.landing + 1)
            vx = np.polyfit(f / a.clip.fps, a.com[f][:, [0, 2]], 1)[0]
            speeds.append(np.hypot(*vx))
        assert speeds[1] / speeds[0] == pytest.approx(1.2, abs=0.02), src
    trials = trial_order(st.design, st, "P01")
    assert Counter((t.stimulus, t.original) for t in trials if t.group == "takeoff") == \
        Counter({(f"backflip_{s}_takeoff_20", f"backflip_{s}"): 1 for s in ("gt", "jitter", "floaty")})


def test_an_item_twice_in_one_folder_and_a_bad_strengths_option_are_clear_errors(tmp_path, built, capsys):
    from flipstudy.study.cli import main
    _write_sources(tmp_path, items=("jump",))
    (tmp_path / "jitter" / "jump.npy").write_bytes(b"")
    with pytest.raises(SourceMismatchError, match=r"sources 'jitter': folder .*jitter holds item 'jump' twice "
                                                  r"\(jump.bvh and jump.npy\)"):
        build_stimuli(Design.from_toml(_design(tmp_path)), tmp_path / "study", progress=False)
    assert main(["simulate", str(built), "--participants", "1", "--strengths", "gt:0"]) == 1
    assert "--strengths: 'gt:0' is not SOURCE=LOGIT" in capsys.readouterr().err


def test_compare_all_adds_the_pairs_without_the_first_source(tmp_path):
    """compare = "all": per item the first source's pairs as before, and the pair of
    the others (floaty-vs-jitter: floaty's clip again, beside jitter's); each pair
    balanced left/right; the ranking counts every pair's choices."""
    from flipstudy.study.cli import main
    from flipstudy.study.order import trial_order
    from flipstudy.study.simulate import simulate
    with pytest.raises(DesignError, match="compare: 'all' pairs the sources in 2AFC trials"):
        Design.from_toml_text(_design(tmp_path, task="yes-no").read_text()
                              .replace('task = "yes-no"', 'task = "yes-no"\ncompare = "all"'))
    with pytest.raises(DesignError, match=r"\[study\].compare: 'all' chooses the pairs of a \[\[sources\]\] design"):
        Design.from_toml_text('[study]\nname = "x"\nseed = 1\ncompare = "all"\n[[clips]]\nname = "b"\n'
                              'source = "backflip"\n[[groups]]\nname = "g"\nkind = "takeoff-angle"\nlevels = [0, 10]\n')
    _write_sources(tmp_path, items=("jump",))
    p = _design(tmp_path, repetitions=2)
    p.write_text(p.read_text().replace('task = "2afc"', 'task = "2afc"\ncompare = "all"'))
    design = Design.from_toml(p)
    assert Design.from_toml_text(design.to_toml()) == design and 'compare = "all"' in design.to_toml()
    build_stimuli(design, tmp_path / "study", progress=False)
    st = StimulusSet.read(tmp_path / "study")
    s = st["jump_floaty-vs-jitter"]
    assert (s.group, s.source, s.original, s.sha256) == ("floaty-vs-jitter", "floaty", "jump_jitter",
                                                         st["jump_floaty"].sha256)   # the same clip again
    trials = trial_order(st.design, st, "P01")
    pairs = Counter((t.stimulus, t.original, t.first) for t in trials)
    for shown, comp in (("jump_jitter", "jump_gt"), ("jump_floaty", "jump_gt"), ("jump_floaty-vs-jitter", "jump_jitter")):
        assert pairs[(shown, comp, "original")] == pairs[(shown, comp, "modified")] == 1
    simulate(tmp_path / "study", 5, seed=4, strengths={"gt": 0.0, "jitter": -1.0, "floaty": -2.0})
    assert main(["export", str(tmp_path / "study"), "--include-simulated"]) == 0
    assert main(["analyze", str(tmp_path / "study"), "--include-simulated", "--n-boot", "20", "--no-figures"]) == 0
    r = pd.read_csv(tmp_path / "study" / "analysis" / "ranking.csv").set_index("source")
    assert (r.n == 2 * 5 * 2).all() and r.n.sum() == 2 * 30      # each source in 2 of the 3 pairs


@pytest.mark.slow                                   # measures the clips (about 8 s)
def test_the_comparison_figure_says_who_and_the_analysis_writes_notes(built, tmp_path, monkeypatch):
    """Every figure says which participants it shows (N = … (… real, … simulated)),
    and the comparison analysis writes notes.md like the other analyses (issue 42)."""
    import shutil

    import matplotlib.figure

    from flipstudy.study.compare import analyze_comparison
    from flipstudy.study.simulate import simulate
    study = tmp_path / "study"
    shutil.copytree(built, study)
    simulate(study, 3, seed=2, strengths={"gt": 0.0, "jitter": -1.0, "floaty": -2.0})
    from flipstudy.study.export import export_responses
    export_responses(study, include_simulated=True)
    texts, save = [], matplotlib.figure.Figure.savefig

    def savefig(fig, path, **kw):                   # the figure's own texts (supxlabel, ...)
        texts.extend(t.get_text() for t in fig.texts)
        return save(fig, path, **kw)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", savefig)
    res = analyze_comparison(study, tmp_path / "out", include_simulated=True, n_boot=20)
    label = "N = 3 participants (0 real, 3 simulated)"
    assert label in texts
    notes = (tmp_path / "out" / "notes.md").read_text()
    assert notes.startswith("# Comparison notes") and label in notes
    assert "| gt |" in notes and "not meaningful below 5" in notes
    assert res.report.participants_label == label
    assert res.report.files["notes"] == str(tmp_path / "out" / "notes.md")
