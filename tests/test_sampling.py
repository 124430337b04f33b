"""Samplers: shapes, ranges, stratification, determinism through rng."""

import numpy as np
import pytest

from dynia import sampling

BOUNDS = [[0.0, 7.0], [-1.0, 1.0], [100.0, 120.0]]


@pytest.mark.parametrize("method", sorted(sampling.SAMPLERS))
def test_samples_fill_the_box_and_repeat_with_the_seed(method):
    first = sampling.sample(method, 64, BOUNDS, rng=np.random.default_rng(5))
    again = sampling.sample(method, 64, BOUNDS, rng=np.random.default_rng(5))
    other = sampling.sample(method, 64, BOUNDS, rng=np.random.default_rng(6))
    assert first.shape == (64, 3)
    np.testing.assert_array_equal(first, again)
    assert not np.array_equal(first, other)
    low, high = np.array(BOUNDS).T
    assert ((first >= low) & (first <= high)).all()


def test_uniform_is_the_thesis_formula_on_the_generator_stream():
    expected = np.random.default_rng(3).random((5, 2)) * [7, 2] + [0, -1]
    np.testing.assert_array_equal(sampling.uniform(5, [[0, 7], [-1, 1]], rng=3), expected)


def test_latin_hypercube_puts_one_sample_in_each_stratum():
    x = sampling.latin_hypercube(50, BOUNDS, rng=1)
    for column, (low, high) in zip(x.T, BOUNDS):
        strata = np.floor((column - low) / (high - low) * 50).astype(int)
        np.testing.assert_array_equal(np.sort(strata), np.arange(50))


def test_sobol_of_a_power_of_two_is_balanced():
    x = sampling.sobol(256, [[0, 1]], rng=1)
    counts = np.histogram(x[:, 0], bins=16, range=(0, 1))[0]
    np.testing.assert_array_equal(counts, 16)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: sampling.sample("grid", 5, BOUNDS), "sampler must be one of"),
        (lambda: sampling.uniform(0, BOUNDS), "n_samples must be at least 1"),
        (lambda: sampling.uniform(5, [[1, 0]]), "lower bound 1.0 must be below"),
        (lambda: sampling.uniform(5, [[0, 1, 2]]), "bounds must have 2 columns"),
    ],
)
def test_bad_arguments_are_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()
