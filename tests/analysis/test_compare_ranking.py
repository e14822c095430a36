"""The Bradley–Terry ranking of a comparison study's sources: recovery of known
strengths, interval coverage over repeated panels, an independent fit (choix),
win rates and the agreement of per-clip numbers with the choices."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from flipstudy.analysis.compare import (agreement, analyze_choices, bradley_terry, simulate_choices,
                                        win_rates)
from flipstudy.errors import ComparisonError

TRUE = {"gt": 0.0, "jitter": -0.7, "floaty": -1.5}
SOURCES = ["gt", "jitter", "floaty"]


def test_ranking_recovers_the_order_of_known_strengths():
    ch = simulate_choices(TRUE, ["jitter", "floaty"], "gt", 8, 40, np.random.default_rng(5))
    r = bradley_terry(ch, SOURCES)
    assert r.order() == ["gt", "jitter", "floaty"]
    t = r.table.set_index("source")
    assert t.loc["gt", "strength"] == 0 and t.loc["gt", "low"] == t.loc["gt", "high"] == 0
    for s in ("jitter", "floaty"):
        assert abs(t.loc[s, "strength"] - TRUE[s]) < 4 * t.loc[s, "se"]
    assert t["n"].sum() == 2 * len(ch)


def test_intervals_cover_the_true_strengths_at_about_the_nominal_rate():
    """200 panels of 12 participants × 6 items: the 95 % Wald intervals of each
    challenger's θ contain the truth in 90–99 % of them."""
    R, hits = 200, np.zeros(2)
    for k in range(R):
        ch = simulate_choices(TRUE, ["jitter", "floaty"], "gt", 6, 12, np.random.default_rng(1000 + k))
        t = bradley_terry(ch, SOURCES).table.set_index("source")
        hits += [(t.loc[s, "low"] <= TRUE[s] <= t.loc[s, "high"]) for s in ("jitter", "floaty")]
    cover = hits / R
    assert np.all((cover >= 0.90) & (cover <= 0.99)), cover


def test_maximum_likelihood_agrees_with_an_independent_fit():
    choix = pytest.importorskip("choix", reason="choix (the test extra) cross-checks the statsmodels fit")
    ch = simulate_choices(TRUE, ["jitter", "floaty"], "gt", 5, 10, np.random.default_rng(2))
    idx = {s: i for i, s in enumerate(SOURCES)}
    data = [(idx[a], idx[b]) if w else (idx[b], idx[a]) for a, b, w in zip(ch.a, ch.b, ch.a_wins)]
    p = choix.opt_pairwise(3, data, alpha=0.0)
    ours = bradley_terry(ch, SOURCES).table.strength.to_numpy()
    np.testing.assert_allclose(ours, p - p[0], atol=1e-5)


def test_a_closed_form_two_source_case():
    """Two sources: the MLE is the log odds of the wins, its SE √(1/w + 1/l)."""
    ch = pd.DataFrame({"participant": ["p"] * 10, "item": ["i"] * 10, "stimulus": ["i_a"] * 10,
                       "original": ["i_gt"] * 10, "a": ["a"] * 10, "b": ["gt"] * 10,
                       "a_wins": [1] * 3 + [0] * 7})
    t = bradley_terry(ch, ["gt", "a"]).table.set_index("source")
    assert t.loc["a", "strength"] == pytest.approx(np.log(3 / 7), abs=1e-6)
    assert t.loc["a", "se"] == pytest.approx(np.sqrt(1 / 3 + 1 / 7), rel=1e-4)
    assert (t.loc["gt", "wins"], t.loc["a", "wins"]) == (7, 3)


def test_a_source_that_wins_every_time_or_is_never_compared_is_a_clear_error():
    ch = simulate_choices({"gt": 0.0, "a": 0.0}, ["a"], "gt", 3, 3, np.random.default_rng(0))
    with pytest.raises(ComparisonError, match="'b' was never compared"):
        bradley_terry(ch, ["gt", "a", "b"])
    with pytest.raises(ComparisonError, match="'gt' won all its 9 comparisons: its Bradley–Terry strength is infinite"):
        bradley_terry(ch.assign(a_wins=0), ["gt", "a"])


def test_win_rates_count_each_trial_for_both_sources():
    ch = pd.DataFrame({"participant": ["p", "p", "q"], "item": ["x", "x", "y"],
                       "stimulus": ["x_a", "x_a", "y_a"], "original": ["x_gt", "x_gt", "y_gt"],
                       "a": ["a"] * 3, "b": ["gt"] * 3, "a_wins": [1, 0, 0]})
    w = win_rates(ch).set_index(["item", "source"])
    assert w.loc[("x", "a"), "wins"] == 1 and w.loc[("x", "gt"), "wins"] == 1
    assert w.loc[("y", "gt"), "win_rate"] == 1.0 and w.loc[("y", "a"), "n"] == 1


def test_agreement_of_a_perfect_and_a_reversed_predictor():
    ch = simulate_choices({"gt": 0.0, "a": -0.5}, ["a"], "gt", 6, 30, np.random.default_rng(3))
    # a metric that separates exactly the chosen from the not chosen: each trial its own pair
    ch = ch.assign(stimulus=[f"s{k}" for k in range(len(ch))], original=[f"o{k}" for k in range(len(ch))])
    m = {}
    for k, w in enumerate(ch.a_wins):
        m[f"s{k}"], m[f"o{k}"] = (0.0, 1.0) if w else (1.0, 0.0)
    metrics = pd.DataFrame({"perfect": m, "reversed": {k: -v for k, v in m.items()}})
    a = agreement(ch, metrics, n_boot=200).set_index("metric")
    assert a.loc["perfect", "accuracy"] == 1 and a.loc["perfect", "auc"] == 1
    assert a.loc["reversed", "accuracy"] == 0 and a.loc["reversed", "auc"] == 0
    assert a.loc["perfect", "n"] == len(ch)


def test_agreement_of_an_unrelated_number_is_near_chance_with_an_interval_around_it():
    rng = np.random.default_rng(4)
    ch = simulate_choices({"gt": 0.0, "a": 0.0}, ["a"], "gt", 10, 40, rng)
    ch = ch.assign(stimulus=[f"s{k}" for k in range(len(ch))], original=[f"o{k}" for k in range(len(ch))])
    names = list(ch.stimulus) + list(ch.original)
    metrics = pd.DataFrame({"noise": dict(zip(names, rng.random(len(names))))})
    r = agreement(metrics=metrics, ch=ch, n_boot=300).iloc[0]
    # 400 trials: the AUC's standard error is about 0.03
    assert abs(r.auc - 0.5) < 0.12 and abs(r.accuracy - 0.5) < 0.12
    assert r.auc_low < r.auc < r.auc_high and 0.03 < r.auc_high - r.auc_low < 0.3


def test_analyze_choices_writes_tables_figure_and_notes(tmp_path, monkeypatch):
    """The tables, the figure (saying which participants it shows, as every figure
    does) and notes.md beside them (issue 42)."""
    import matplotlib.figure

    texts, save = [], matplotlib.figure.Figure.savefig

    def savefig(fig, path, **kw):                   # the figure's own texts (supxlabel, ...)
        texts.extend(t.get_text() for t in fig.texts)
        return save(fig, path, **kw)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", savefig)
    ch = simulate_choices(TRUE, ["jitter", "floaty"], "gt", 3, 4, np.random.default_rng(6))
    label = "N = 4 participants (0 real, 4 simulated)"
    res = analyze_choices(ch, SOURCES, None, tmp_path, n_boot=50, label=label)
    assert pd.read_csv(tmp_path / "ranking.csv").source.tolist() == SOURCES
    assert (tmp_path / "comparison.png").stat().st_size > 1000 and (tmp_path / "comparison.pdf").is_file()
    assert "Bradley–Terry" in res.summary()
    assert label in texts
    notes = (tmp_path / "notes.md").read_text()
    assert notes.startswith("# Comparison notes") and label in notes and "over 3 item(s)" in notes
    assert "not meaningful below 5" in notes and res.to_dict()["participants_label"] == label
