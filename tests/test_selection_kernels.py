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

import functools

import numpy as np
import pytest

from dynia.engine import kernels
from dynia.engine.flavours import parameter_ranks
from dynia.engine.kernels import bits, selection
from dynia.engine.kernels.ranks import ranked_order_statistics

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


PRESENT = 4.0  # measured points of the window


def _tied_costs(rng, n_samples):
    """Window sums with many exact ties (a coarse grid), as samples simulating alike give, and their costs."""
    sums = np.round(rng.gamma(2.0, 1.0, n_samples), 1) * PRESENT
    return sums, (sums / PRESENT) ** 2


def _picked(sums, count, bracket):
    """The kernels' costs, threshold and behavioural set for one window's ``sums``, searched first in ``bracket``."""
    n_samples = sums.size
    cost = np.empty(n_samples)
    selection.form_costs(sums, PRESENT, cost)
    candidates = (np.empty(n_samples, dtype=np.int64), np.empty(n_samples))
    found = selection.find_candidates(cost, 0, 1, count, bracket[1], candidates)
    threshold, _ = selection.select_near(candidates[1], found, count - 1, bracket, np.empty(n_samples))
    selected, chosen = np.empty(count, dtype=np.int64), np.empty(count)
    selection.behavioural(count, candidates, found, threshold, selected, chosen)
    return cost, threshold, selected, chosen


@functools.cache
def _callable(helper):
    """A kernels' helper, which has no wrapper for calls from Python, through a compiled one: made once a process."""
    import numba

    return numba.njit(lambda *arguments: helper(*arguments))


BRACKETS = {  # around the answer x: (low, high) as multiples of it
    "holds": (0.9, 1.1),
    "too low": (0.2, 0.5),  # one move up
    "far too low": (1e-9, 2e-9),  # every move up, then to infinity
    "too high": (1.5, 2.0),
    "far too high": (1e6, 1.1e6),
    "point": (1.0, 1.0),
}


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("where", [*BRACKETS, "nan"])
def test_the_bracketed_threshold_and_set_are_the_stable_sorts(seed, where):
    rng = np.random.default_rng(seed)
    n_samples = int(rng.integers(50, 3000))
    count = int(rng.integers(1, n_samples))
    sums, costs = _tied_costs(rng, n_samples)
    order = np.argsort(costs, kind="stable")
    expected = costs[order[count - 1]]
    bracket = tuple(expected * np.array(BRACKETS.get(where, (np.nan, np.nan))))
    cost, threshold, selected, chosen = _picked(sums, count, bracket)
    np.testing.assert_array_equal(cost, costs)
    assert threshold == expected
    np.testing.assert_array_equal(selected, np.sort(order[:count]))
    np.testing.assert_array_equal(chosen, costs[np.sort(order[:count])])


def test_every_cost_zero_gives_the_first_samples():
    for bracket in ((0.0, 0.0), (np.nan, np.nan), (1.0, 2.0)):
        _, threshold, selected, _ = _picked(np.zeros(500), 50, bracket)
        assert threshold == 0
        np.testing.assert_array_equal(selected, np.arange(50))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("where", [*BRACKETS, "nan"])
def test_the_quantile_near_a_bracket_is_the_sorted_value(seed, where):
    rng = np.random.default_rng(seed)
    n_samples = int(rng.integers(50, 3000))
    _, costs = _tied_costs(rng, n_samples)
    position = int(0.9 * n_samples)
    expected = np.sort(costs)[position]
    bracket = tuple(expected * np.array(BRACKETS.get(where, (np.nan, np.nan))))
    value, density = selection.select_near(costs, n_samples, position, bracket, np.empty(n_samples))
    assert value == expected
    assert density >= 0


def test_the_next_bracket_follows_the_last_change_within_its_limits():
    ranks = selection.BRACKET_RANKS
    assert selection.next_bracket(1.0, np.nan, 0.0, ranks) == (0.5, 1.5)  # the first window: widest
    low, high = selection.next_bracket(1.0, 0.98, 0.0, ranks)  # changed by 2 %: thrice that either side
    assert low == pytest.approx(0.94) and high == pytest.approx(1.06)
    low, high = selection.next_bracket(1.0, 1.0, 0.0, ranks)  # unchanged: the narrowest
    assert low == pytest.approx(1 - selection.NARROWEST) and high == pytest.approx(1 + selection.NARROWEST)
    low, high = selection.next_bracket(1.0, 0.9, 1000.0, ranks)  # 1000 values a unit there: 128 either side, not 0.3
    assert low == pytest.approx(1 - 0.128) and high == pytest.approx(1 + 0.128)
    low, high = selection.next_bracket(1.0, 0.9, 1000.0, 20)  # a set of 5: 20 either side
    assert low == pytest.approx(1 - 0.02) and high == pytest.approx(1 + 0.02)
    assert selection.next_bracket(0.0, 1.0, 0.0, ranks) == (0.0, 0.0)


@pytest.mark.parametrize("seed", range(4))
def test_one_pass_counts_the_costs_against_every_guess(seed):
    rng = np.random.default_rng(seed)
    sums, costs = _tied_costs(rng, int(rng.integers(50, 3000)))
    sums[::97] = np.inf  # an overflowed window sum: an infinite cost, counted as numpy counts it
    sums[5::101] = np.nan  # a sum the simulation could not form: counted nowhere
    costs = (sums / PRESENT) ** 2
    finite = costs[np.isfinite(costs)]
    # Bounds at costs that occur (ties on them), and between costs.
    bound, reserve = np.quantile(finite, 0.02, method="lower"), np.quantile(finite, 0.1)
    low, high = np.quantile(finite, [0.85, 0.95], method="nearest")
    narrow, wide = (low, high), (low / 2, np.inf)
    counted = selection.count_costs(sums, selection.sum_limits((bound, reserve), (narrow, wide), PRESENT))
    assert counted == (
        np.sum(costs <= bound),
        np.sum(costs <= reserve),
        np.sum(costs < low),
        np.sum((costs >= low) & (costs <= high)),
        np.sum(costs < wide[0]),
        np.sum(costs >= wide[0]),
    )


@pytest.mark.parametrize("present", [1.0, 3.0, 7.0, 21.0, 201.0])
def test_a_cost_bound_carried_to_the_sums_keeps_exactly_the_same_sums(present):
    sum_bound = _callable(selection.sum_bound)
    rng = np.random.default_rng(int(present))
    for total in np.concatenate([rng.gamma(2.0, 1.0, 300) * present, [0.0, 5e-324, 1e-300, 1e150, 1e300]]):
        cost = (total / present) ** 2
        # The cost of a sum that occurs, the doubles beside it, and some between costs.
        for bound in (cost, np.nextafter(cost, 0), np.nextafter(cost, np.inf), cost * (1 + 1e-9), cost * 0.97):
            limit = sum_bound(bound, present)
            near = total + np.arange(-8, 9) * np.spacing(total)
            near = np.concatenate([near, -near, [limit, np.nextafter(limit, np.inf)]])
            near = near[np.isfinite(near)]
            np.testing.assert_array_equal(np.abs(near) <= limit, (near / present) ** 2 <= bound)
    assert sum_bound(np.inf, present) == np.inf
    assert sum_bound(-1.0, present) == -np.inf
    assert np.isnan(sum_bound(np.nan, present))


@pytest.mark.parametrize("share", [0.01, 0.3])
@pytest.mark.parametrize("n_samples", [2000, 128, 64, 63, 1])  # whole words of 64, and a part word after them
@pytest.mark.parametrize("loop", ["marked", "every"])  # a word of bits per 64 sums (few kept), or every cost written
def test_the_gathered_costs_are_in_index_order(share, n_samples, loop):
    rng = np.random.default_rng(7)
    sums, _ = _tied_costs(rng, n_samples)
    sums[3::29] = np.nan  # a window the simulation could not score: never kept, as numpy's comparisons keep none
    sums[::31] *= -1  # a sum's sign does not change its cost
    sums[7::37] = np.inf
    cost = (sums / PRESENT) ** 2
    bound = np.nanquantile(cost, share, method="nearest")  # a cost that occurs: ties on the bound are kept
    bracket = tuple(np.nanquantile(cost, [0.9 - share, 0.9], method="nearest"))
    kept = 0 if loop == "marked" else n_samples  # the estimate that chooses the loop
    candidates, within = (np.empty(cost.size, dtype=np.int64), np.empty(cost.size)), np.empty(cost.size)
    limits = selection.sum_limits((bound, bound), (bracket, bracket), PRESENT)
    carried = (limits[0][0], limits[1][0])
    found, inside = selection.gather_costs((sums, PRESENT), carried, candidates, within, kept)
    expected = np.flatnonzero(cost <= bound)
    np.testing.assert_array_equal(candidates[0][:found], expected)
    np.testing.assert_array_equal(candidates[1][:found], cost[expected])
    np.testing.assert_array_equal(within[:inside], cost[(cost >= bracket[0]) & (cost <= bracket[1])])


def test_words_of_bits_count_find_and_mark_as_numpy_does():
    lowest_set_bit, popcount = _callable(bits.lowest_set_bit), _callable(bits.popcount)
    mark_at_most, mark_between = _callable(bits.mark_at_most), _callable(bits.mark_between)
    rng = np.random.default_rng(3)
    for position in range(64):
        word = np.uint64(1) << np.uint64(position)
        above = np.uint64(rng.integers(0, 2**63)) << np.uint64(position + 1) if position < 63 else np.uint64(0)
        assert lowest_set_bit(word) == lowest_set_bit(word | above) == position
        assert popcount(word | above) == bin(int(word | above)).count("1")
    values = rng.uniform(-1, 1, 64)  # marked by magnitude
    values[5] = np.nan
    at_most = sum(1 << j for j in np.flatnonzero(np.abs(values) <= 0.5).tolist())
    between = sum(1 << j for j in np.flatnonzero((np.abs(values) > 0.25) & (np.abs(values) <= 0.75)).tolist())
    assert int(mark_at_most(values, 0.5)) == at_most
    assert int(mark_between(values, (0.25, 0.75))) == between
    assert int(mark_at_most(values, np.inf)) == 2**64 - 1 - (1 << 5)  # every value but the NaN


@pytest.mark.parametrize("seed", range(10))
def test_rank_bitset_order_statistics_are_the_sorted_values(seed):
    rng = np.random.default_rng(seed)
    n_samples = int(rng.integers(2, 5000))
    # Parameter values with ties (a coarse grid), and sets of every size from one sample to all.
    column = np.round(rng.uniform(0, 3, n_samples), 1)
    ranks, ordered = parameter_ranks(column[None, :])
    words = np.zeros((n_samples + 63) // 64, dtype=np.uint64)
    for count in {1, 2, n_samples, int(rng.integers(1, n_samples + 1))}:
        selected = np.sort(rng.choice(n_samples, count, replace=False))
        values = np.sort(column[selected])
        for lower_share in (0.0, 0.05, 0.25, 0.5):
            positions = np.array(
                [int(np.floor(lower_share * (count - 1))), int(np.floor((1 - lower_share) * (count - 1)))]
            )
            lower, upper, middle = ranked_order_statistics(ranks[0], ordered[0], selected, count, positions, words)
            assert (lower, upper, middle) == (values[positions[0]], values[positions[1]], values[(count - 1) // 2])
            assert not words.any()  # cleared for the next window


def test_parameter_ranks_are_the_stable_sort():
    columns = np.array([[0.2, 0.1, 0.2, 0.0], [1.0, 1.0, 1.0, 1.0]])
    ranks, ordered = parameter_ranks(columns)
    np.testing.assert_array_equal(ranks, [[2, 1, 3, 0], [0, 1, 2, 3]])
    np.testing.assert_array_equal(ordered, np.sort(columns, axis=1))


def test_a_crowd_of_equal_values_is_answered_without_selection():
    # Every sample simulating alike (a record resting at zero): the bracket holds them all, one value.
    values = np.full(3 * selection.CROWDED, 0.25)
    values[:5] = 0.1
    scratch = np.full(values.size, np.nan)
    value, _ = selection.select_near(values, values.size, 100, (0.2, 0.3), scratch)
    assert value == 0.25
    assert np.isnan(scratch).all()  # answered by the check, nothing copied
    value, _ = selection.select_near(values, values.size, 3, (0.05, 0.3), scratch)
    assert value == 0.1  # a crowd of two values still selects


@pytest.mark.parametrize("seed", range(4))
def test_an_answer_just_outside_the_bracket_is_found_on_its_side(seed):
    rng = np.random.default_rng(seed)
    values = rng.uniform(0, 1, 500)  # distinct: the ranks at the bracket's edges are exact
    ordered = np.sort(values)
    k = int(rng.integers(10, 490))
    for bracket in ((ordered[k - 6], ordered[k - 1]), (ordered[k + 1], ordered[k + 6])):
        value, _ = selection.select_near(values, values.size, k, bracket, np.empty(values.size))
        assert value == ordered[k]


@pytest.mark.parametrize("n_samples", [1, 63, 64, 65, 2000])
def test_a_window_ties_only_when_every_sum_has_one_finite_magnitude(n_samples):
    tied_cost = _callable(selection.tied_cost)
    sums = np.full(n_samples, 2.5)
    sums[::3] = -2.5  # a sum's sign does not change its cost
    assert tied_cost(sums, PRESENT) == (2.5 / PRESENT) ** 2
    assert tied_cost(np.zeros(n_samples), PRESENT) == 0.0
    for where in {0, n_samples // 2, n_samples - 1}:  # in the first 64 or after them
        # One sum alone is a tie of one, whatever its value; not when it is NaN or infinite.
        for odd in (np.nextafter(2.5, 3.0), np.nan, np.inf) if n_samples > 1 else (np.nan, np.inf):
            other = sums.copy()
            other[where] = odd
            assert np.isnan(tied_cost(other, PRESENT))
    assert np.isnan(tied_cost(np.full(n_samples, np.inf), PRESENT))  # an overflowed window is no tie
