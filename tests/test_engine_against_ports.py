"""The fast engine against the plain ports, on hand-checkable cases, and on bad input."""

import math

import numpy as np
import pytest
from conftest import example_firstorder_input, first_order_response

from dynia import mcat, thesis
from dynia.engine.selection import lowest_stable, stable_rank_mask
from dynia.engine.windows import moving_window, window_costs
from dynia.errors import SettingsError


def _small_example(seed, steps=120, samples=300, zero_start=20):
    """Example-1-like data, short enough for the port; starts with zero input, so that
    every simulation is exactly 0 there and the first windows are exact cost ties."""
    rng = np.random.default_rng(seed)
    u = example_firstorder_input(500)[::4][:steps].copy()
    u[:zero_start] = 0
    y = first_order_response(2.0, 3.0, u)[0] + rng.normal(0, 0.5, steps)
    params = rng.uniform(0, 7, (samples, 2))
    sims = first_order_response(params[:, 0], params[:, 1], u)
    return y, sims, params


# The engine sums each window left to right, as the port does, and breaks
# cost ties by sample index, as the port's stable sort does, so the same
# parameter values are selected and the limits and IC agree exactly
# (tolerance 0), ties included.
@pytest.mark.parametrize(
    "seed, n, percentage, conf_level", [(0, 10, 10, 90), (1, 3, 20, 95), (2, 0, 10, 60), (3, 25, 5, 90), (4, 7, 12, 80)]
)
def test_thesis_flavour_equals_the_port_exactly(seed, n, percentage, conf_level):
    y, sims, params = _small_example(seed)
    res = moving_window(
        y, sims, params, [[0, 7], [0, 7]], n=n, percentage=percentage, conf_level=conf_level, chunk_steps=17
    )
    for p in range(2):
        IC, CI_t, _ = thesis.moving_window_calcs(
            y.size, params[:, p], 0, 7, len(params), sims, y, 40, percentage, n, conf_level=conf_level
        )
        np.testing.assert_array_equal(res.ic[p], IC)
        np.testing.assert_array_equal(res.ci[p], CI_t)


def test_thesis_flavour_equals_the_port_on_example1(example1):
    e = example1
    # The numpy engine is the port's arithmetic; the compiled one keeps the contract of tests/test_fast.py with it.
    res = moving_window(e["y"], e["sims"], e["params"], e["bounds"], n=10, engine="numpy")
    # The port's loop over every sample of every window takes ~14 CPU-s a parameter here. Its window costs do not
    # depend on the parameter, so the second parameter goes through moving_window_from_costs, the port's own rest of
    # the loop body on the same costs (equal to the port bit for bit: tests/test_reference_thesis.py).
    IC, CI_t, _ = thesis.moving_window_calcs(500, e["params"][:, 0], 0, 7, 2000, e["sims"], e["y"], 40, 10, 10)
    costs = window_costs(e["y"], e["sims"], 10, 0, 500)
    IC_T, CI_t_T, _ = thesis.moving_window_from_costs(costs, e["params"][:, 1], 0, 7, 2000, 40, 10)
    for p, (ic, ci) in enumerate([(IC, CI_t), (IC_T, CI_t_T)]):
        np.testing.assert_array_equal(res.ic[p], ic)
        np.testing.assert_array_equal(res.ci[p], ci)


@pytest.mark.parametrize("seed, n, bins, samples", [(0, 10, 20, 300), (1, 2, 40, 305), (2, 0, 7, 40)])
def test_mcat_flavour_equals_the_id_time_port_exactly(seed, n, bins, samples):
    y, sims, params = _small_example(seed, samples=samples)
    res = moving_window(y, sims, params, [[0, 7], [0, 7]], n=n, bins=bins, flavour="mcat", chunk_steps=13)
    for p in range(2):
        ic, lcl, ucl, colour, grid = mcat.id_time(sims.T, y, params, p, n, containers=bins)
        np.testing.assert_array_equal(res.ic[p], ic)
        np.testing.assert_array_equal(res.ci[p, :, 0], lcl)
        np.testing.assert_array_equal(res.ci[p, :, 1], ucl)
        np.testing.assert_array_equal(res.gradient[p], colour)
        np.testing.assert_array_equal(res.bin_centres[p], grid)


def _weighted_reference(y, sims, params, bounds, n, percentage, conf_level, window="centred"):
    """Plain loops: the likelihood-weighted limits of Wagener et al. (2003)."""
    steps, (samples, n_params) = y.size, params.shape
    count = math.floor(samples * percentage / 100)
    ic = np.zeros((n_params, steps))
    for t in range(steps):
        if window == "centred":
            lo, hi = max(t - n, 0), min(t + n + 1, steps)
        else:
            lo, hi = max(t - 2 * n, 0), t + 1
        cost = np.array([np.cumsum(np.abs(y[lo:hi] - sims[k, lo:hi]))[-1] / (hi - lo) for k in range(samples)]) ** 2
        best = np.argsort(cost, kind="stable")[:count]
        lhood = 1 - cost[best]
        if lhood.min() < 0:
            lhood = lhood - lhood.min()
        lhood = lhood / lhood.sum()
        for p in range(n_params):
            order = np.argsort(params[best, p], kind="stable")
            values, cumulative = params[best, p][order], np.cumsum(lhood[order])
            lower = values[np.nonzero(cumulative >= (100 - conf_level) / 200)[0][0]]
            upper = values[np.nonzero(cumulative >= (100 + conf_level) / 200)[0][0]]
            ic[p, t] = 1 - (upper - lower) / (bounds[p][1] - bounds[p][0])
    return ic


def test_weighted_flavour_equals_a_loop_reference():
    y, sims, params = _small_example(5, steps=60, samples=200, zero_start=0)
    res = moving_window(y, sims, params, [[0, 7], [0, 7]], n=4, flavour="weighted", conf_level=80)
    # Same order of every sum as the reference, so agreement is to the last bit.
    np.testing.assert_array_equal(res.ic, _weighted_reference(y, sims, params, [[0, 7], [0, 7]], 4, 10, 80))


def test_trailing_window_equals_a_loop_reference():
    y, sims, params = _small_example(6, steps=60, samples=200, zero_start=0)
    res = moving_window(
        y, sims, params, [[0, 7], [0, 7]], n=4, flavour="weighted", conf_level=80, window="trailing", chunk_steps=7
    )
    np.testing.assert_array_equal(
        res.ic, _weighted_reference(y, sims, params, [[0, 7], [0, 7]], 4, 10, 80, window="trailing")
    )
    assert res.settings.window == "trailing"


@pytest.mark.parametrize("flavour", ["thesis", "weighted", "mcat"])
def test_trailing_window_is_the_centred_one_shifted_by_n(flavour):
    y, sims, params = _small_example(7)
    n = 6
    centred = moving_window(y, sims, params, [[0, 7], [0, 7]], n=n, flavour=flavour)
    trailing = moving_window(y, sims, params, [[0, 7], [0, 7]], n=n, flavour=flavour, window="trailing", chunk_steps=11)
    np.testing.assert_array_equal(trailing.ic[:, n:], centred.ic[:, :-n])
    np.testing.assert_array_equal(trailing.ci[:, n:], centred.ci[:, :-n])
    np.testing.assert_array_equal(trailing.gradient[:, :, n:], centred.gradient[:, :, :-n])


def _hand_case():
    """Ten constant simulations p = 0..9 against y = 4.5: costs (4.5 - p)^2."""
    params = np.arange(10.0)[:, None]
    sims = np.repeat(params, 3, axis=1)
    return np.full(3, 4.5), sims, params


def test_thesis_flavour_by_hand():
    y, sims, params = _hand_case()
    res = moving_window(y, sims, params, [[0, 9]], n=1, percentage=40, bins=3)
    # behavioural: p = 4, 5 (cost 0.25), 3, 6 (cost 2.25); sorted [3, 4, 5, 6]
    # limits at floor(0.05*3) = 0 and floor(0.95*3) = 2 -> 3 and 5
    np.testing.assert_array_equal(res.ci[0], [[3, 5]] * 3)
    np.testing.assert_allclose(res.ic[0], 1 - 2 / 9)
    # likelihood 1 - cost = [.75, .75, -1.25, -1.25] -> +1.25 -> [2, 2, 0, 0] -> [.5, .5, 0, 0]
    # bins [0,3) [3,6) [6,9]: masses 0, 1, 0
    np.testing.assert_allclose(res.gradient[0][:, 0], [0, 1, 0])
    np.testing.assert_allclose(res.bin_centres[0], [1.5, 4.5, 7.5])


def test_weighted_flavour_by_hand():
    y, sims, params = _hand_case()
    res = moving_window(y, sims, params, [[0, 9]], n=1, percentage=40, bins=3, flavour="weighted")
    # sorted [3, 4, 5, 6] with weights [0, .5, .5, 0]: CLD [0, .5, 1, 1]
    # reaches 0.05 at 4 and 0.95 at 5
    np.testing.assert_array_equal(res.ci[0], [[4, 5]] * 3)
    np.testing.assert_allclose(res.ic[0], 1 - 1 / 9)


def test_mcat_flavour_by_hand():
    params = np.arange(20.0)[:, None]
    sims = np.repeat(params, 3, axis=1)
    res = moving_window(np.full(3, 9.7), sims, params, [[0, 19]], n=0, bins=19, flavour="mcat")
    # top block of floor(20/10) = 2: p = 10 and 9; ranks/count = [.5, 1]
    np.testing.assert_array_equal(res.ci[0], [[9, 10]] * 3)
    np.testing.assert_allclose(res.ic[0], 1 - 1 / 19)
    # CDF knots [0, 9, 10, 19.001] -> [0, .5, 1, 1] at x = 0..19; unit-spaced gradient
    x = np.arange(20.0)
    cdf = np.interp(x, [0, 9, 10, 19.001], [0, 0.5, 1, 1])
    np.testing.assert_allclose(res.gradient[0][:, 0], np.gradient(cdf))
    assert res.gradient.shape == (1, 20, 3)


def test_exact_ties_go_to_the_lowest_sample_index():
    values = np.array([[1.0, 0.0, 1.0, 1.0, 0.0, 1.0]])
    np.testing.assert_array_equal(lowest_stable(values, 3), [[0, 1, 4]])
    np.testing.assert_array_equal(stable_rank_mask(values, 2, 4)[0], [1, 0, 1, 0, 0, 0])
    np.testing.assert_array_equal(stable_rank_mask(values, 4, 6)[0], [0, 0, 0, 1, 0, 1])


def test_results_do_not_depend_on_chunking_or_threads(example1):
    e = example1
    reference = moving_window(e["y"], e["sims"], e["params"], e["bounds"], n=10, workers=1, chunk_steps=500)
    for chunk_steps, workers in [(1, 2), (7, 2), (64, 1), (None, None)]:
        res = moving_window(e["y"], e["sims"], e["params"], e["bounds"], n=10, workers=workers, chunk_steps=chunk_steps)
        np.testing.assert_array_equal(res.ic, reference.ic)
        np.testing.assert_array_equal(res.ci, reference.ci)
        np.testing.assert_array_equal(res.gradient, reference.gradient)


def test_one_worker_analyses_in_the_calling_thread(example1, monkeypatch):
    """workers=1 means one thread: no pool that would analyse one chunk while this thread prepares the next."""
    import dynia.engine.windows

    def no_pool(*args, **kwargs):
        raise AssertionError("a thread pool was started for workers=1")

    monkeypatch.setattr(dynia.engine.windows, "ThreadPoolExecutor", no_pool)
    e = example1
    res = moving_window(e["y"], e["sims"], e["params"], e["bounds"], n=10, workers=1, chunk_steps=64)
    assert np.isfinite(res.ic).any()


def test_gradient_is_the_likelihood_mass_per_bin(example1):
    e = example1
    res = moving_window(e["y"], e["sims"], e["params"], e["bounds"], n=10)
    np.testing.assert_allclose(res.gradient.sum(axis=1), 1.0, rtol=1e-12)
    assert (res.gradient >= 0).all()


def test_missing_measurements_use_the_points_present():
    y, sims, params = _hand_case()
    y = np.r_[y, y, y]
    sims = np.c_[sims, sims, sims]
    y[3:6] = np.nan
    res = moving_window(y, sims, params, [[0, 9]], n=1, percentage=40, bins=3, min_points=2)
    # windows centred on 3 and 5 have one measured point, 4 has none
    assert np.isnan(res.ic[0, 3:6]).all() and np.isnan(res.ci[0, 3:6]).all()
    assert np.isnan(res.gradient[0][:, 3:6]).all()
    np.testing.assert_allclose(res.ic[0, [0, 1, 2, 6, 7, 8]], 1 - 2 / 9)
    with_one = moving_window(y, sims, params, [[0, 9]], n=1, percentage=40, bins=3)
    assert np.isnan(with_one.ic[0, 4]) and np.isfinite(with_one.ic[0, [3, 5]]).all()


@pytest.mark.parametrize("flavour", ["thesis", "weighted", "mcat"])
def test_a_gap_longer_than_a_window_is_blank_and_leaves_the_other_windows_as_they_were(flavour, example1):
    e = example1
    y = e["y"].copy()
    y[60:90] = np.nan  # windows of 21 steps centred on 70-79 hold no measured point
    options = dict(n=10, percentage=10, bins=8, flavour=flavour, chunk_steps=17)
    gapped = moving_window(y, e["sims"], e["params"], e["bounds"], **options)
    whole = moving_window(e["y"], e["sims"], e["params"], e["bounds"], **options)
    assert np.isnan(gapped.ic[:, 70:80]).all() and np.isnan(gapped.ci[:, 70:80]).all()
    assert np.isfinite(gapped.ic[:, 69]).all() and np.isfinite(gapped.ic[:, 80]).all()  # points on one side suffice
    untouched = np.r_[: 60 - 10, 90 + 10 : y.size]  # windows that reach no missing point
    np.testing.assert_array_equal(gapped.ic[:, untouched], whole.ic[:, untouched])
    np.testing.assert_array_equal(gapped.ci[:, untouched], whole.ci[:, untouched])
    np.testing.assert_array_equal(gapped.gradient[..., untouched], whole.gradient[..., untouched])


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(y=np.zeros(4)), "sims has 3 steps"),
        (dict(sims=np.zeros(3)), "sims must be 2-D"),
        (dict(params=np.zeros((9, 1))), "params has 9 rows"),
        (dict(bounds=[[9, 0]]), "lower bound 9.0 must be below"),
        (dict(bounds=[[0, 5]]), "outside its bounds"),
        (dict(flavour="glue"), "flavour must be one of"),
        (dict(window="left"), "window must be one of"),
        (dict(percentage=10), "keeps 1 parameter sets per window"),
        (dict(percentage=0), r"percentage must lie in \(0, 100\]"),
        (dict(percentage=100.5), r"percentage must lie in \(0, 100\]"),
        (dict(conf_level=100), r"conf_level is a percentage in \(50, 100\)"),
        (dict(n=-1), "n must be at least 0"),
        (dict(n=1.5), "n must be a whole number"),
        (dict(y=[1, "a", 2]), "y must be a 1-D array of numbers"),
    ],
)
def test_bad_input_gets_a_clear_error(change, message):
    y, sims, params = _hand_case()
    args = dict(y=y, sims=sims, params=params, bounds=[[0, 9]])
    args.update(change)
    options = {key: args.pop(key) for key in list(args) if key not in ("y", "sims", "params", "bounds")}
    with pytest.raises(ValueError, match=message):
        moving_window(
            args["y"],
            args["sims"],
            args["params"],
            args["bounds"],
            n=options.pop("n", 1),
            percentage=options.pop("percentage", 40),
            **options,
        )


def test_non_finite_simulations_are_named():
    y, sims, params = _hand_case()
    sims[4, 2] = np.inf
    with pytest.raises(ValueError, match="sample 4 at step 2"):
        moving_window(y, sims, params, [[0, 9]], n=1, percentage=40)


def test_mcat_flavour_rejects_negative_parameters_and_odd_percentages():
    y, sims, params = _hand_case()
    with pytest.raises(ValueError, match="non-negative"):
        moving_window(y, sims - 1, params - 1, [[-1, 8]], n=1, flavour="mcat")
    with pytest.raises(ValueError, match="whole number of blocks"):
        moving_window(y, sims, params, [[0, 9]], n=1, percentage=30, flavour="mcat")


@pytest.mark.parametrize("change", [lambda t: t[::-1].copy(), lambda t: np.r_[t[:5], t[4], t[6:]]])
def test_a_time_that_does_not_rise_is_refused(example1, change):
    """Issue 32: moving_window accepted a falling time, and its plots and tables then ran backwards."""
    e = example1
    with pytest.raises(SettingsError, match="time must be finite and strictly rising") as refused:
        moving_window(
            e["y"], e["sims"], e["params"], e["bounds"], n=10, time=change(np.arange(e["y"].size, dtype=float))
        )
    assert refused.value.setting == "time"
