"""The importance-weighted analysis reads only the head of each window's cost order: the same bits as sorting all.

The fast forms (:func:`~dynia.engine.selection.lowest_weighted_head`, the
importance flavour, and the blocked :func:`~dynia.engine.windows.window_mean`
they are fed by) against their plain references, tolerance zero: costs with
ties, with infinities, weights equal, zero or far apart.
"""

import numpy as np
import pytest

from dynia.engine import cld
from dynia.engine.flavours import ImportanceFlavour
from dynia.engine.noise import quantile_position
from dynia.engine.selection import lowest_weighted, lowest_weighted_head
from dynia.engine.windows import plain_window_mean, window_mean


def _costs(kind, rows, n, rng):
    if kind == "mixed":  # rows of every kind, so behavioural sets of very different sizes side by side
        kinds = ["distinct", "few values", "all equal", "infinite", "one big tie", "rising"]
        return np.concatenate([_costs(kinds[row % len(kinds)], 1, n, rng) for row in range(rows)])
    if kind == "rising":  # the order of the samples: the heaviest weights come last
        return np.linspace(0, 1, n)[None, :].repeat(rows, axis=0)
    if kind == "distinct":
        return rng.random((rows, n))
    if kind == "few values":  # ties everywhere, the threshold among them
        return rng.integers(0, 4, (rows, n)).astype(float)
    if kind == "all equal":
        return np.zeros((rows, n))
    if kind == "infinite":
        return np.where(rng.random((rows, n)) < 0.4, np.inf, rng.integers(0, 3, (rows, n)).astype(float))
    if kind == "missing":
        return np.where(rng.random((rows, n)) < 0.2, np.nan, rng.random((rows, n)))
    return np.where(rng.random((rows, n)) < 0.9, 1.0, rng.random((rows, n)))  # one tie holding most samples


def _weights(kind, n, rng):
    weights = {
        "equal": np.ones(n),
        "random": rng.random(n),
        "zero": np.where(rng.random(n) < 0.5, 0.0, rng.random(n)) + np.eye(1, n)[0],
        "far apart": rng.random(n) ** 12 + 1e-300,
        "heavy last": np.sort(rng.random(n)) ** 4 + 1e-300,
    }[kind]
    return weights / weights.sum()


COST_KINDS = ["distinct", "few values", "all equal", "infinite", "missing", "one big tie", "rising", "mixed"]
WEIGHT_KINDS = ["equal", "random", "zero", "far apart", "heavy last"]


@pytest.mark.parametrize("cost_kind", COST_KINDS)
@pytest.mark.parametrize("weight_kind", WEIGHT_KINDS)
def test_lowest_weighted_head_is_the_head_of_the_full_sort(cost_kind, weight_kind):
    rng = np.random.default_rng(len(cost_kind) * 31 + len(weight_kind))
    for n in (1, 7, 300, 2500):
        cost = _costs(cost_kind, 5, n, rng)
        weights = _weights(weight_kind, n, rng)
        for fraction in (1e-3, 0.01, 0.1, 0.5, 1.0):
            order, behavioural = lowest_weighted(cost, weights, fraction)
            head, head_behavioural = lowest_weighted_head(cost, weights, fraction)
            width = head.shape[1]
            np.testing.assert_array_equal(head_behavioural, behavioural[:, :width])
            assert not behavioural[:, width:].any()
            np.testing.assert_array_equal(head[head_behavioural], order[:, :width][head_behavioural])
            np.testing.assert_array_equal(head[~head_behavioural], 0)


def _plain_importance_analysis(flavour, mae, usable, conf_level, likelihood_limits):
    """The importance flavour's numbers from every sample of every window, each one sorted in full."""
    with np.errstate(over="ignore"):
        cost = mae**2
    cost[~usable] = 0.0
    order, behavioural = lowest_weighted(cost, flavour.prior_weights, flavour.fraction)
    ranked_cost = np.take_along_axis(cost, order, axis=1)
    behavioural_cost = np.where(behavioural, ranked_cost, ranked_cost[:, :1])
    prior = np.where(behavioural, flavour.prior_weights[order], 0.0)
    prior /= prior.sum(axis=1, keepdims=True)
    likelihood = 1 - ranked_cost
    lowest = np.where(behavioural, likelihood, np.inf).min(axis=1, keepdims=True)
    likelihood = np.where(behavioural, np.where(lowest < 0, likelihood - lowest, likelihood), 0.0)
    mass = likelihood * prior
    total = mass.sum(axis=1, keepdims=True)
    mass = np.where(total > 0, mass / np.where(total > 0, total, 1), prior)
    ci, median, gradient = [], [], []
    for p, column in enumerate(flavour.columns):
        values = column[order]
        band, middle = cld.band_and_median(values, mass if likelihood_limits else prior, conf_level, weighted=True)
        ci.append(band)
        median.append(middle)
        gradient.append(cld.binned_mass(values, mass, *flavour.bounds[p], flavour.bins).T)
    position = quantile_position(cost.shape[1])
    upper = np.sqrt(np.partition(cost, position, axis=1)[:, position])
    keep = lambda values: np.where(usable, values, np.nan)  # noqa: E731
    ci, median, gradient = np.array(ci), np.array(median), np.array(gradient)
    ci[:, ~usable], median[:, ~usable], gradient[:, :, ~usable] = np.nan, np.nan, np.nan
    extremes = [keep(np.sqrt(behavioural_cost).min(axis=1)), keep(np.sqrt(behavioural_cost).max(axis=1)), keep(upper)]
    return ci, median, gradient, extremes


@pytest.mark.parametrize("flavour_name", ["thesis", "weighted"])
@pytest.mark.parametrize("cost_kind", ["distinct", "few values", "all equal", "infinite", "one big tie", "mixed"])
@pytest.mark.parametrize("weight_kind", ["equal", "random", "far apart", "heavy last"])
def test_importance_flavour_reads_the_head_as_the_whole_population(flavour_name, cost_kind, weight_kind):
    rng = np.random.default_rng(len(flavour_name) + 7 * len(cost_kind) + 13 * len(weight_kind))
    n = 3000
    params = np.c_[rng.random(n) * 4, rng.integers(0, 5, n) * 0.5]  # the second parameter's values tie
    bounds = np.array([[0.0, 4.0], [0.0, 2.0]])
    mae = np.sqrt(_costs(cost_kind, 12, n, rng)) * 1.5  # costs above 1 too: the likelihood is shifted
    usable = np.ones(12, dtype=bool)
    usable[3] = False
    weights = _weights(weight_kind, n, rng)
    # A confidence level whose upper CLD level lies within rounding of 1, which the CLD may fall short of.
    for conf_level in (90, 100 - 2e-14):
        for percentage in (0.5, 10):
            flavour = ImportanceFlavour(params, bounds, percentage, 8, conf_level, weights, flavour_name)
            results = flavour.analyse(mae.copy(), usable)
            ci, median, gradient, extremes = _plain_importance_analysis(
                flavour, mae.copy(), usable, conf_level, flavour_name == "weighted"
            )
            np.testing.assert_array_equal(results.ci, ci)
            np.testing.assert_array_equal(results.median, median)
            np.testing.assert_array_equal(results.gradient, gradient)
            np.testing.assert_array_equal(results.ic, 1 - (ci[:, :, 1] - ci[:, :, 0]) / np.array([[4.0], [2.0]]))
            for fast, plain in zip((results.best, results.threshold, results.upper), extremes):
                np.testing.assert_array_equal(fast, plain)


def test_a_cld_short_of_its_level_reads_the_population_largest_value():
    # Ten equal weights sum to a hair under 1 in the CLD, which never reaches the upper level 1 of a confidence
    # level within rounding of 100: the limit is then the whole population's largest value, as when every sample
    # is sorted, not the behavioural set's.
    n = 1000
    params = np.linspace(0, 1, n)[:, None]
    mae = np.r_[np.zeros(10), np.ones(n - 10)][None, :]
    usable = np.ones(1, dtype=bool)
    conf_level = 100 - 2e-14
    assert (100 + conf_level) / 200 == 1.0 and np.cumsum(np.full(10, 0.1))[-1] < 1.0
    flavour = ImportanceFlavour(params, np.array([[0.0, 1.0]]), 0.95, 4, conf_level, np.full(n, 1 / n), "thesis")
    results = flavour.analyse(mae.copy(), usable)
    ci, _, _, _ = _plain_importance_analysis(flavour, mae.copy(), usable, conf_level, False)
    np.testing.assert_array_equal(results.ci, ci)
    assert results.ci[0, 0, 1] == 1.0


@pytest.mark.parametrize("n_samples", [0, 1, 4095, 4096, 4097, 9000])
def test_window_mean_in_blocks_equals_the_plain_pass(n_samples):
    rng = np.random.default_rng(n_samples)
    m, slots = 37, 21
    errors = rng.random((n_samples, m + slots - 1)) * 10.0 ** rng.integers(-5, 5, (n_samples, m + slots - 1))
    errors[: n_samples // 3, 5] = 1e308  # sums that overflow to inf
    measured = (rng.random(m + slots - 1) < 0.6).astype(float)
    measured[:slots] = 0.0  # a window without a measured point: 0/0
    mae, present = window_mean(errors, measured, m, slots)
    plain_mae, plain_present = plain_window_mean(errors, measured, m, slots)
    np.testing.assert_array_equal(mae, plain_mae)
    np.testing.assert_array_equal(present, plain_present)
    assert mae.flags.c_contiguous and mae.shape == (m, n_samples)
