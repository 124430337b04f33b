"""CLD building blocks on hand-worked cases, one set and many sets at once."""

import numpy as np

from dynia.engine import cld


def test_likelihood_is_shifted_only_when_negative_and_sums_to_one():
    np.testing.assert_allclose(cld.likelihood([0.2, 0.6]), [0.8 / 1.2, 0.4 / 1.2])
    np.testing.assert_allclose(cld.likelihood([0.5, 3.0, 1.0]), [2.5 / 4.5, 0, 2 / 4.5])
    np.testing.assert_allclose(cld.likelihood([[2.0, 2.0], [0.0, 1.0]]), [[0.5, 0.5], [1.0, 0.0]])


def test_unweighted_limits_match_the_thesis_positions():
    values = np.arange(200.0)[::-1]
    np.testing.assert_array_equal(cld.limits(values, 90), [9.0, 189.0])


def test_weighted_limits_are_where_the_cld_first_reaches_each_level():
    values = np.array([3.0, 1.0, 2.0, 4.0])
    weights = np.array([0.1, 0.02, 0.5, 0.38])
    # sorted 1, 2, 3, 4 with CLD 0.02, 0.52, 0.62, 1.0
    np.testing.assert_array_equal(cld.weighted_limits(values, weights, 90), [2.0, 4.0])
    np.testing.assert_array_equal(cld.weighted_limits(values, weights, 20), [2.0, 3.0])


def test_binned_mass_counts_the_upper_edge_in_the_last_bin():
    mass = cld.binned_mass(np.array([[0.0, 1.0, 2.5, 4.0]]), np.array([[0.1, 0.2, 0.3, 0.4]]), 0, 4, 4)
    np.testing.assert_allclose(mass, [[0.1, 0.2, 0.3, 0.4]])
    mass = cld.binned_mass(np.array([0.5, 0.6, 3.9]), np.array([0.2, 0.3, 0.5]), 0, 4, 2)
    np.testing.assert_allclose(mass, [0.5, 0.5])


def test_weighted_quantiles_of_outputs_per_time_step():
    outputs = np.array([[1.0, 10.0], [2.0, 30.0], [3.0, 20.0]])
    band = cld.weighted_quantiles(outputs, np.array([0.2, 0.5, 0.3]), (0.1, 0.5, 0.9))
    # step 0: sorted 1, 2, 3 with CLD .2, .7, 1; step 1: sorted 10, 20, 30 with CLD .2, .5, 1
    np.testing.assert_array_equal(band, [[1.0, 10.0], [2.0, 20.0], [3.0, 30.0]])


def test_cumulative_sorts_stably():
    ordered, cumulative = cld.cumulative(np.array([2.0, 1.0, 2.0]), np.array([0.5, 0.25, 0.25]))
    np.testing.assert_array_equal(ordered, [1.0, 2.0, 2.0])
    np.testing.assert_allclose(cumulative, [0.25, 0.75, 1.0])
