"""QUEST+ engine (analysis/adaptive.py): round trip, determinism, agreement with
questplus's own entropy search and likelihood, and that answers move the posterior
towards the observer's truth."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.special import xlogy

from flipstudy.analysis.adaptive import (Observer, Quest, QuestSettings, population,
                                         quest_model)
from flipstudy.analysis.stats import detection_threshold, psychometric_curve
from flipstudy.errors import FlipstudyError

LEVELS = np.arange(0, 61, 2.0)


def run(model, observer, n, seed=0, quest=None):
    q = quest or Quest.new(model)
    rng = np.random.default_rng(seed)
    for _ in range(n):
        lv = q.next_level()
        q.update(lv, observer.answer(lv, rng))
    return q


@pytest.mark.parametrize("task", ["yes-no", "2afc"])
def test_round_trip_same_posterior_bytes_and_next_level(task):
    model = quest_model(LEVELS, task, QuestSettings(trials=30))
    obs = Observer(25.0, 15.0, 0.3 if task == "yes-no" else 0.5, 0.02, task)
    q = run(model, obs, 17)
    q2 = Quest.from_json(model, q.to_json())
    assert q2.posterior.tobytes() == q.posterior.tobytes()
    assert q2.history == q.history and q2.n_trials == 17
    assert q2.next_level() == q.next_level()
    assert q2.threshold() == q.threshold()
    # and they go on alike: the same answers give the same levels and posteriors
    run(model, obs, 5, seed=9, quest=q)
    run(model, obs, 5, seed=9, quest=q2)
    assert q2.posterior.tobytes() == q.posterior.tobytes() and q2.history == q.history
    assert Quest.from_json(model, q2.to_json()).to_json() == q2.to_json()


def test_next_level_is_deterministic_and_a_grid_level():
    model = quest_model(LEVELS, "yes-no")
    obs = Observer(30.0, 20.0, 0.2, 0.02)
    a, b = run(model, obs, 25, seed=4), run(model, obs, 25, seed=4)
    assert a.history == b.history
    assert all(lv in set(model.levels.tolist()) for lv, _ in a.history)
    assert len({lv for lv, _ in a.history}) > 2        # it explores, not one level


@pytest.mark.parametrize("task", ["yes-no", "2afc"])
def test_next_level_and_entropies_equal_questplus(task):
    """Our closed-form expected entropy is questplus's next_stim computation."""
    model = quest_model(LEVELS, task)
    obs = Observer(20.0, 10.0, 0.25 if task == "yes-no" else 0.5, 0.02, task)
    q = Quest.new(model)
    rng = np.random.default_rng(2)
    for i in range(24):
        lv = q.next_level()
        if i % 4 == 0:
            assert q.qp.next_stim["intensity"] == lv
            qp = q.qp
            new = qp.posterior * qp.likelihoods
            pk = new.sum(dim=list(qp.param_domain))
            new = new / pk
            H = -(xlogy(new, new)).sum(dim=list(qp.param_domain))
            eh_qp = (pk * H).sum(dim="response").values
            np.testing.assert_allclose(model.expected_entropy(q.posterior), eh_qp, rtol=1e-9, atol=1e-12)
        q.update(lv, obs.answer(lv, rng))


def test_likelihood_is_the_analysis_curve_and_questplus_norm_cdf():
    from questplus.psychometric_function import norm_cdf
    model = quest_model(LEVELS, "yes-no")
    M, W, G = np.meshgrid(model.m, model.width, model.gamma, indexing="ij")
    ours = psychometric_curve(model.levels[:, None, None, None], M, W, G, model.lapse)
    np.testing.assert_array_equal(model.p_detect, ours.reshape(len(model.levels), -1))
    theirs = norm_cdf(intensity=model.levels, mean=model.m, sd=model.width / 3.289707253902945,
                      lower_asymptote=model.gamma, lapse_rate=[model.lapse], scale="linear")
    theirs = theirs.transpose("intensity", "mean", "sd", "lower_asymptote", "lapse_rate").values
    np.testing.assert_allclose(model.p_detect, theirs.reshape(len(model.levels), -1), atol=1e-12)
    np.testing.assert_array_equal(model.xstar, detection_threshold(M, W, G, model.lapse).ravel())


@pytest.mark.parametrize("task", ["yes-no", "2afc"])
def test_answers_move_the_posterior_towards_the_truth(task):
    model = quest_model(LEVELS, task, QuestSettings(trials=40))
    prior_mass = {}
    for truth in (12.0, 42.0):
        obs = Observer(truth, 12.0, 0.2 if task == "yes-no" else 0.5, 0.02, task)
        q = run(model, obs, 40, seed=int(truth))
        near = np.abs(model.xstar - truth) < 6
        prior_mass[truth] = model.prior[near].sum()
        assert q.posterior[near].sum() > 3 * prior_mass[truth]
        t = q.threshold()
        assert abs(t["threshold"] - truth) < 2.5 * t["sd"] + 2
        assert t["ci_low"] <= t["threshold"] <= t["ci_high"] and t["sd"] > 0


def test_stop_width_finishes_early_and_trials_cap():
    model = quest_model(LEVELS, "2afc", QuestSettings(trials=200, stop_width=12.0))
    q = run(model, Observer(25.0, 8.0, 0.5, 0.02, "2afc"), 0)
    while not q.finished():
        lv = q.next_level()
        q.update(lv, Observer(25.0, 8.0, 0.5, 0.02, "2afc").answer(lv, np.random.default_rng(q.n_trials)))
    t = q.threshold()
    assert q.n_trials < 200 and t["ci_high"] - t["ci_low"] < 12.0
    capped = quest_model(LEVELS, "2afc", QuestSettings(trials=3))
    assert run(capped, Observer(25.0, 8.0, 0.5, 0.02, "2afc"), 3).finished()


def test_bad_states_and_levels_are_refused():
    a = quest_model(LEVELS, "yes-no")
    b = quest_model(LEVELS, "yes-no", QuestSettings(lapse=0.05))
    q = run(a, Observer(20.0, 10.0, 0.2, 0.02), 3)
    with pytest.raises(FlipstudyError, match="another model"):
        Quest.from_json(b, q.to_json())
    with pytest.raises(FlipstudyError, match="not a QUEST"):
        Quest.from_json(a, "{}")
    with pytest.raises(FlipstudyError, match="not one of the group's levels"):
        q.update(3.0, True)
    with pytest.raises(FlipstudyError, match="trials"):
        QuestSettings(trials=0)
    with pytest.raises(FlipstudyError, match="width_prior"):
        QuestSettings(width_prior=(10, 5))
    with pytest.raises(FlipstudyError, match="task"):
        quest_model(LEVELS, "3afc")


def test_observer_threshold_is_its_x_star_and_population_bounds():
    obs = population(50, np.random.default_rng(1), "yes-no")
    for o in obs[:10]:
        np.testing.assert_allclose(o.p_detect(o.threshold), (1 + o.gamma) / 2, atol=1e-12)
        np.testing.assert_allclose(detection_threshold(o.m, o.width, o.gamma, o.lapse), o.threshold)
    assert all(3 <= o.threshold <= 57 and 8 <= o.width <= 40 for o in obs)
    two = population(5, np.random.default_rng(1), "2afc")
    assert all(o.gamma == 0.5 and abs(o.p_detect(o.threshold) - 0.75) < 1e-12 for o in two)
