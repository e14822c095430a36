"""The batched twin of QUEST+ (analysis/adaptive_sim.py) against questplus, and
parameter recovery over 200 simulated observers (the issue's Done-when)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from flipstudy.analysis.adaptive import Observer, Quest, QuestSettings, population, quest_model
from flipstudy.analysis.adaptive_sim import QuestBatch, constant_sequence, simulate

GRID = np.arange(0, 61, 1.0)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(task=st.sampled_from(["yes-no", "2afc"]),
       answers=st.lists(st.lists(st.booleans(), min_size=3, max_size=3), min_size=1, max_size=14))
def test_twin_gives_questplus_next_levels_and_posteriors(task, answers):
    """Three runs fed arbitrary answers: questplus (Quest) one by one, the twin in one batch."""
    model = quest_model(GRID, task)
    quests = [Quest.new(model) for _ in range(3)]
    batch = QuestBatch(model, 3)
    for row in answers:
        idx = batch.next_index()
        assert [float(model.levels[i]) for i in idx] == [q.next_level() for q in quests]
        for q, i, a in zip(quests, idx, row):
            q.update(float(model.levels[i]), a)
        batch.update(idx, np.array(row))
        for j, q in enumerate(quests):
            np.testing.assert_allclose(batch.post[j], q.posterior, rtol=1e-10, atol=1e-300)
    summ = batch.summary()
    for j, q in enumerate(quests):
        t = q.threshold()
        for k in ("threshold", "ci_low", "ci_high", "sd"):
            assert summ[k][j] == pytest.approx(t[k], rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("task", ["yes-no", pytest.param("2afc", marks=pytest.mark.slow)])
def test_parameter_recovery_coverage_of_95_intervals(task):
    """200 observers drawn from a population, 40 QUEST+ trials each: the 95 % posterior
    intervals of x* cover the true x* in 85–99 % of the observers, and the
    estimates follow the truth."""
    model = quest_model(GRID, task, QuestSettings(trials=40))
    obs = population(200, np.random.default_rng(19), task)
    sim = simulate(model, obs, 40, np.random.default_rng(1900), every_trial=False)
    cover = sim.covered.mean()
    assert 0.85 <= cover <= 0.99, cover
    est = sim.threshold[-1]
    assert np.corrcoef(est, sim.truth)[0, 1] > 0.8
    assert np.median(sim.width[-1]) < np.median(sim.width[0]) / 2     # 40 trials narrowed it


def test_recovery_with_a_misspecified_lapse_still_covers():
    """Observers lapse at 4 % while the model assumes 2 %: the intervals still cover
    most truths (2AFC)."""
    model = quest_model(GRID, "2afc")
    obs = population(200, np.random.default_rng(7), "2afc", lapse=0.04)
    sim = simulate(model, obs, 40, np.random.default_rng(70), every_trial=False)
    assert 0.85 <= sim.covered.mean() <= 0.99


@settings(max_examples=25, deadline=None)
@given(levels=st.lists(st.sampled_from([0.0, 10.0, 17.0, 25.0, 37.0, 50.0]), min_size=1, max_size=6,
                       unique=True),
       n_trials=st.integers(1, 40), n_obs=st.integers(1, 5), seed=st.integers(0, 2**32 - 1))
def test_constant_sequence_is_balanced_blocks(levels, n_trials, n_obs, seed):
    seq = constant_sequence(levels, n_trials, n_obs, np.random.default_rng(seed))
    assert seq.shape == (n_trials, n_obs)
    k = len(levels)
    for j in range(n_obs):
        for b in range(0, n_trials - k + 1, k):
            assert sorted(seq[b:b + k, j]) == sorted(levels)


def test_trials_to_width_is_the_first_crossing():
    model = quest_model(GRID, "2afc")
    obs = [Observer(20.0, 10.0, 0.5, 0.02, "2afc")] * 4
    sim = simulate(model, obs, 30, np.random.default_rng(3))
    n = sim.trials_to_width(15.0)
    for j in range(4):
        if np.isfinite(n[j]):
            k = int(n[j])
            assert sim.width[k, j] < 15.0 and np.all(sim.width[:k, j] >= 15.0)
        else:
            assert np.all(sim.width[:, j] >= 15.0)
    assert np.all(sim.trials_to_width(1e-9) == np.inf)


def test_posterior_from_counts_equals_trial_by_trial_updates():
    model = quest_model(GRID, "yes-no")
    obs = population(6, np.random.default_rng(4), "yes-no")
    sim = simulate(model, obs, 60, np.random.default_rng(5), method="constant",
                   constant_levels=[0.0, 17.0, 25.0, 37.0, 50.0], every_trial=False)
    idx = np.searchsorted(model.levels, sim.levels.T)
    nl = len(model.levels)
    k = np.stack([np.bincount(i, d, nl) for i, d in zip(idx, sim.detected.T)])
    n = np.stack([np.bincount(i, None, nl) for i in idx])
    b = QuestBatch.from_counts(model, k, n)
    np.testing.assert_allclose(b.post, sim.posterior, rtol=1e-8, atol=1e-300)
