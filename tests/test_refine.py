"""The automatic second run of the thesis (3.1.1-3.1.3)."""

import dataclasses

import numpy as np
import pytest

import dynia
from dynia.models import FirstOrder
from dynia.refine import narrowed_bounds, second_run


@pytest.fixture(scope="module")
def example1_twice():
    u = dynia.synthetic.example_firstorder_input()
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(4).normal(0, 0.5, u.size)
    return second_run(u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=2000, n=10, rng=1)


def test_the_gain_is_narrowed_around_its_band_and_the_time_constant_sharpens(example1_twice):
    first, second, narrowed = example1_twice
    # At the default IC_THRESHOLD 0.5 the windows informative about T agree on a band around its true 3.
    assert narrowed == ["K", "T"]
    assert tuple(second.bounds[second.index("K")]) == pytest.approx((1.416, 2.576), abs=1e-3)
    assert tuple(second.bounds[second.index("T")]) == pytest.approx((0.818, 5.657), abs=1e-3)
    # At 0.75, T's highest IC (0.92 at step 424, band near 0) comes from windows that fit only noise; the
    # informative ones disagree, so T keeps its range.
    assert first.ic[1].max() > 0.75
    assert narrowed_bounds(first, {"K": (0, 7), "T": (0, 7)}, ic_threshold=0.75)[1] == ["K"]
    dips = np.r_[139:175, 329:345]  # the thesis's spikes of T (Figures 3.5 and 3.7)
    assert second.ic[1, dips].mean() > first.ic[1, dips].mean() + 0.2
    assert second.run.narrowed == ("K", "T")


def test_nothing_identified_nothing_narrowed(example1_twice):
    first = example1_twice[0]
    new, narrowed = narrowed_bounds(first, {"K": (0, 7), "T": (0, 7)}, ic_threshold=0.99)
    assert narrowed == [] and new == {"K": (0.0, 7.0), "T": (0.0, 7.0)}


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(ic_threshold=1.5), r"ic_threshold must be a number in \[0, 1\]"),
        (dict(margin=-1), "margin must be a finite number >= 0"),
        (dict(margin=float("inf")), "an infinite one would narrow nothing"),
    ],
)
def test_bad_narrowing_options(example1_twice, kwargs, message):
    with pytest.raises(ValueError, match=message):
        narrowed_bounds(example1_twice[0], {"K": (0, 7), "T": (0, 7)}, **kwargs)


def test_a_band_widened_to_the_whole_range_is_not_reported_as_narrowed(example1_twice):
    """Issue 32: with a margin that widens the band past the bounds, the range stays whole and nothing is narrowed."""
    new, narrowed = narrowed_bounds(example1_twice[0], {"K": (0, 7), "T": (0, 7)}, margin=1e6)
    assert new == {"K": (0.0, 7.0), "T": (0.0, 7.0)} and narrowed == []


def _hand_result(bands, bounds=(0.0, 7.0)):
    """One parameter; ``bands`` lists (count, lower, upper, ic): that many windows with that band and IC."""
    ci = np.concatenate([np.tile([lower, upper], (count, 1)) for count, lower, upper, _ in bands])
    ic = np.concatenate([np.full(count, value) for count, _, _, value in bands])
    steps = ci.shape[0]
    return dynia.DyniaResult(
        names=("T",),
        samples=np.zeros((1, 1)),
        bounds=np.array([bounds]),
        time=np.arange(steps, dtype=float),
        ic=ic[None],
        ci=ci[None],
        gradient=np.zeros((1, 40, steps)),
        bin_centres=np.zeros((1, 40)),
        settings={},
    )


def test_a_lone_sharp_window_does_not_block_the_narrowing():
    result = _hand_result(
        [(20, 2.9, 3.1, 0.9), (5, 1, 6, 0.3), (1, 5.0, 5.2, 0.9), (5, 1, 6, 0.3), (20, 2.8, 3.2, 0.9)]
    )
    new, narrowed = narrowed_bounds(result, {"T": (0, 7)})
    assert narrowed == ["T"] and new["T"] == pytest.approx((2.8, 3.2))
    # Counted as informative, the lone window disagrees with the rest: nothing is narrowed.
    assert narrowed_bounds(result, {"T": (0, 7)}, min_windows=1)[1] == []


def test_windows_below_the_noise_floor_never_narrow():
    # A disagreeing stretch below the floor is no evidence: the others narrow the range.
    result = _hand_result([(20, 2.9, 3.1, 0.9), (15, 5.0, 5.5, 0.9), (20, 2.8, 3.2, 0.9)])
    assert narrowed_bounds(result, {"T": (0, 7)})[1] == []
    informative = np.r_[np.ones(20, dtype=bool), np.zeros(15, dtype=bool), np.ones(20, dtype=bool)]
    new, narrowed = narrowed_bounds(dataclasses.replace(result, informative=informative), {"T": (0, 7)})
    assert narrowed == ["T"] and new["T"] == pytest.approx((2.8, 3.2))


def test_bands_pressed_against_a_bound_are_left_out():
    # Noise-only windows put a narrow band at T = 0 (thesis example 1's tail).
    result = _hand_result([(20, 2.9, 3.1, 0.9), (15, 0.0, 0.2, 0.97), (20, 2.85, 3.05, 0.9)])
    new, narrowed = narrowed_bounds(result, {"T": (0, 7)})
    assert narrowed == ["T"] and new["T"] == pytest.approx((2.825, 3.125))
