"""Importance-weighted DYNIA and the adaptive samplers."""

import numpy as np
import pytest
from conftest import example1_record

import dynia
from dynia.adaptive import BoxMixture
from dynia.models import FirstOrder


def test_box_mixture_density_is_a_density_and_weights_undo_it():
    mixture = BoxMixture([[0, 4], [0, 2]])
    mixture.counts[0] = 100
    mixture.add([[1, 2], [0, 1]], 300)
    mixture.add([[3, 5], [1, 3]], 100)  # clipped to the prior: [3, 4] x [1, 2]
    np.testing.assert_array_equal(mixture.boxes[-1], [[3, 4], [1, 2]])
    rng = np.random.default_rng(0)
    grid = rng.uniform([0, 0], [4, 2], (400_000, 2))
    # the density integrates to 1 over the prior box (volume 8)
    assert mixture.density(grid).mean() * 8 == pytest.approx(1, rel=0.01)
    # at a point in the first inner box: 100/500 / 8 + 300/500 / 1
    assert mixture.density([[1.5, 0.5]])[0] == pytest.approx(0.2 / 8 + 0.6)
    assert mixture.importance_weights([[1.5, 0.5]])[0] == pytest.approx((1 / 8) / (0.2 / 8 + 0.6))


@pytest.fixture(scope="module")
def record():
    return example1_record(seed=0)


def test_equal_weights_select_the_same_set_and_limits_one_position_apart_at_most(record):
    u, y = record
    params = np.random.default_rng(1).uniform(0, 7, (4000, 2))
    sims = FirstOrder().simulate(params, u)
    # Importance weights run on numpy: the plain run on numpy too, whose costs window_costs gives bit for bit.
    plain = dynia.moving_window(y, sims, params, [[0, 7], [0, 7]], n=10, engine="numpy")
    weighted = dynia.moving_window(y, sims, params, [[0, 7], [0, 7]], n=10, weights=np.ones(4000))
    # Equal weights 1/N: the lowest 400 costs hold 10 % and the weighted
    # quantile positions equal the thesis's floor(c (k-1)) = 19 and 379, up to
    # the rounding of a cumulative sum of 1/400s, which can move a limit by
    # one position in the sorted behavioural values.
    costs = dynia.engine.windows.window_costs(y, sims, 10, 0, 500)
    selected = dynia.engine.selection.lowest_stable(costs, 400)
    for p in range(2):
        ordered = np.sort(params[:, p][selected], axis=1)
        for side, position in ((0, 19), (1, 379)):
            near = ordered[:, position - 1 : position + 2]
            assert (weighted.ci[p, :, side, None] == near).any(axis=1).all()
            np.testing.assert_array_equal(plain.ci[p, :, side], ordered[:, position])


def test_importance_weights_recover_the_uniform_result_from_another_proposal(record):
    u, y = record
    rng = np.random.default_rng(2)
    uniform = rng.uniform(0, 7, (20_000, 2))
    reference = dynia.moving_window(y, FirstOrder().simulate(uniform, u), uniform, [[0, 7], [0, 7]], n=10)
    # half the samples uniform, half with K squeezed into [1.5, 2.5]
    proposal = np.r_[rng.uniform(0, 7, (10_000, 2)), np.c_[rng.uniform(1.5, 2.5, 10_000), rng.uniform(0, 7, 10_000)]]
    mixture = BoxMixture([[0, 7], [0, 7]])
    mixture.counts[0] = 10_000
    mixture.add([[1.5, 2.5], [0, 7]], 10_000)
    weighted = dynia.moving_window(
        y,
        FirstOrder().simulate(proposal, u),
        proposal,
        [[0, 7], [0, 7]],
        n=10,
        weights=mixture.importance_weights(proposal),
    )
    # Both converge to the same curves; 2000 behavioural uniform samples leave
    # Monte Carlo noise of about 0.01 in IC.
    assert np.abs(weighted.ic - reference.ic).mean() < 0.01


@pytest.mark.parametrize("scheme", ["iis", "de"])
def test_adaptive_runs_spend_exactly_their_budget_and_repeat_with_the_seed(record, scheme):
    u, y = record
    runs = [
        dynia.run(
            u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, sampler=scheme, n_samples=3000, n=10, percentage=1, rng=5
        )
        for _ in range(2)
    ]
    assert runs[0].run.n_evaluations == 3000
    np.testing.assert_array_equal(runs[0].ic, runs[1].ic)
    assert runs[0].samples.shape[0] == runs[0].run.weights.size <= 3000


def test_iterated_importance_sampling_beats_uniform_at_the_same_budget(record):
    u, y = record
    bounds = {"K": (0, 7), "T": (0, 7)}
    reference = dynia.run(u, y, FirstOrder(), bounds, n_samples=100_000, n=10, percentage=0.5, rng=1)
    uniform = dynia.run(u, y, FirstOrder(), bounds, n_samples=5000, n=10, percentage=0.5, rng=2)
    adaptive = dynia.run(u, y, FirstOrder(), bounds, sampler="iis", n_samples=5000, n=10, percentage=0.5, rng=2)
    # over the steps before the final settling (see the note in dynia.adaptive)
    error = {
        name: np.sqrt(np.nanmean((res.ic[:, :400] - reference.ic[:, :400]) ** 2))
        for name, res in (("uniform", uniform), ("iis", adaptive))
    }
    assert error["iis"] < error["uniform"]


def test_weights_are_checked():
    y = np.zeros(5)
    params = np.linspace(0, 1, 10)[:, None]
    sims = np.zeros((10, 5))
    with pytest.raises(ValueError, match="weights has 3 values"):
        dynia.moving_window(y, sims, params, [[0, 1]], n=1, weights=np.ones(3))
    with pytest.raises(ValueError, match="weights must be positive"):
        dynia.moving_window(y, sims, params, [[0, 1]], n=1, weights=np.r_[np.ones(9), 0])
    with pytest.raises(ValueError, match="which the mcat flavour cannot use"):
        dynia.moving_window(y, sims, params, [[0, 1]], n=1, weights=np.ones(10), flavour="mcat")


def test_de_says_how_many_evaluations_it_needs(record):
    u, y = record
    with pytest.raises(ValueError, match=r"needs at least \d+ evaluations for 23 blocks"):
        dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, sampler="de", n_samples=500, n=10, percentage=1)
