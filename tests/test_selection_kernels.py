"""The compiled engine's per-window order statistics against plain sorting.

A window's behavioural threshold and the noise floor's quantile are searched
first within a bracket around the previous window's; the limits and median of
the population's behavioural set are read through a bitset of the samples'
ranks. Each must give exactly what a stable sort gives, whether the bracket
holds the answer, misses it on either side, is NaN (the first window) or has
no width (every cost zero), and with ties among the costs and among the
parameter values. Exact equality is the contract: these are order statistics,
so no rounding enters.
"""

import numpy as np
import pytest

from dynia.engine import kernels

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


PRESENT = 4.0  # measured points of the window


def _tied_costs(rng, n_samples):
    """Window sums with many exact ties (a coarse grid), as samples simulating alike give, and their costs."""
    sums = np.round(rng.gamma(2.0, 1.0, n_samples), 1) * PRESENT
    return sums, (sums / PRESENT) ** 2


def _picked(sums, count, bracket, quantile_band):
    """The kernels' costs, threshold, behavioural set and the band's candidates for one window's ``sums``."""
    n_samples = sums.size
    cost = np.empty(n_samples)
    below, below_band = kernels._costs(sums, PRESENT, cost, (bracket[0], quantile_band[0]))
    candidates = (np.empty(n_samples, dtype=np.int64), np.empty(n_samples))
    band_values = np.empty(n_samples)
    found, inside = kernels._gather(cost, bracket[1], quantile_band, candidates, band_values)
    if found < count:
        found = kernels._candidates(cost, 0, 1, count, np.nan, candidates)
    threshold = kernels._bracketed_threshold(count, candidates, found, below, bracket, np.empty(n_samples))
    selected, chosen = np.empty(count, dtype=np.int64), np.empty(count)
    kernels._behavioural(count, candidates, found, threshold, selected, chosen)
    return cost, threshold, selected, chosen, (band_values, inside, below_band)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("where", ["holds", "too low", "too high", "nan", "point"])
def test_the_bracketed_threshold_and_set_are_the_stable_sorts(seed, where):
    rng = np.random.default_rng(seed)
    n_samples = int(rng.integers(50, 3000))
    count = int(rng.integers(1, n_samples))
    sums, costs = _tied_costs(rng, n_samples)
    order = np.argsort(costs, kind="stable")
    expected = costs[order[count - 1]]
    bracket = {
        "holds": (expected * 0.9, expected * 1.1),
        "too low": (expected * 0.2, expected * 0.5),
        "too high": (expected * 1.5, expected * 2.0),
        "nan": (np.nan, np.nan),
        "point": (expected, expected),
    }[where]
    cost, threshold, selected, chosen, _ = _picked(sums, count, bracket, (np.nan, np.nan))
    np.testing.assert_array_equal(cost, costs)
    assert threshold == expected
    np.testing.assert_array_equal(selected, np.sort(order[:count]))
    np.testing.assert_array_equal(chosen, costs[np.sort(order[:count])])


def test_every_cost_zero_gives_the_first_samples():
    _, threshold, selected, _, _ = _picked(np.zeros(500), 50, (0.0, 0.0), (0.0, 0.0))
    assert threshold == 0
    np.testing.assert_array_equal(selected, np.arange(50))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("where", ["holds", "too low", "too high", "nan"])
def test_the_banded_quantile_is_the_sorted_value(seed, where):
    rng = np.random.default_rng(seed)
    n_samples = int(rng.integers(50, 3000))
    sums, costs = _tied_costs(rng, n_samples)
    position = int(0.9 * n_samples)
    expected = np.sort(costs)[position]
    band = {
        "holds": (expected * 0.95, expected * 1.05),
        "too low": (expected * 0.3, expected * 0.6),
        "too high": (expected * 1.2, expected * 1.4),
        "nan": (np.nan, np.nan),
    }[where]
    cost, _, _, _, (band_values, inside, below) = _picked(sums, 1, (np.nan, np.nan), band)
    assert kernels._quantile_cost(cost, position, band_values, inside, below) == expected


def test_the_next_bracket_follows_the_last_change_within_its_limits():
    assert kernels._next_bracket(1.0, np.nan) == (0.5, 1.5)  # the first window: widest
    low, high = kernels._next_bracket(1.0, 0.98)  # changed by 2 %: thrice that either side
    assert low == pytest.approx(0.94) and high == pytest.approx(1.06)
    low, high = kernels._next_bracket(1.0, 1.0)  # unchanged: the narrowest
    assert low == pytest.approx(1 - kernels._NARROWEST) and high == pytest.approx(1 + kernels._NARROWEST)
    assert kernels._next_bracket(0.0, 1.0) == (0.0, 0.0)


@pytest.mark.parametrize("seed", range(10))
def test_rank_bitset_order_statistics_are_the_sorted_values(seed):
    rng = np.random.default_rng(seed)
    n_samples = int(rng.integers(2, 5000))
    # Parameter values with ties (a coarse grid), and sets of every size from one sample to all.
    column = np.round(rng.uniform(0, 3, n_samples), 1)
    ranks, ordered = kernels.parameter_ranks(column[None, :])
    words = np.zeros((n_samples + 63) // 64, dtype=np.uint64)
    for count in {1, 2, n_samples, int(rng.integers(1, n_samples + 1))}:
        selected = np.sort(rng.choice(n_samples, count, replace=False))
        values = np.sort(column[selected])
        for lower_share in (0.0, 0.05, 0.25, 0.5):
            positions = np.array(
                [int(np.floor(lower_share * (count - 1))), int(np.floor((1 - lower_share) * (count - 1)))]
            )
            lower, upper, middle = kernels._ranked_order_statistics(
                ranks[0], ordered[0], selected, count, positions, words
            )
            assert (lower, upper, middle) == (values[positions[0]], values[positions[1]], values[(count - 1) // 2])
            assert not words.any()  # cleared for the next window


def test_parameter_ranks_are_the_stable_sort():
    columns = np.array([[0.2, 0.1, 0.2, 0.0], [1.0, 1.0, 1.0, 1.0]])
    ranks, ordered = kernels.parameter_ranks(columns)
    np.testing.assert_array_equal(ranks, [[2, 1, 3, 0], [0, 1, 2, 3]])
    np.testing.assert_array_equal(ordered, np.sort(columns, axis=1))
