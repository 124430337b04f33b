"""The reported estimate: the CLD median at the max-IC step, which lies in its band by construction.

The median is read off each window's behavioural set as the limits are (see
:attr:`dynia.result.DyniaResult.median`); these tests check it against known
answers, check that it and the estimate lie in the band on records that fit,
that misfit the model and that carry coloured noise, for every flavour and
several seeds, and that a result without it (an older file) falls back to the
band's midpoint.
"""

import numpy as np
import pytest

import dynia
from dynia.engine import cld
from dynia.engine.windows import moving_window
from dynia.models import FirstOrder, SecondOrderDelay

BOUNDS = {"K": (0, 7), "T": (0, 7)}


def test_cld_median_known_answers():
    values = np.array([5.0, 1.0, 4.0, 2.0, 3.0, 0.0])
    # Six sorted values 0 .. 5: position floor(0.5 * 5) = 2 holds 2.
    assert cld.median(values) == 2.0
    # Weights in sorted order 0.1, 0.1, 0.2, 0.05, 0.5, 0.05: the CLD is 0.1, 0.2, 0.4, 0.45, 0.95, 1.
    weights = np.array([0.05, 0.1, 0.5, 0.2, 0.05, 0.1])
    assert cld.weighted_median(values, weights) == 4.0
    band, median = cld.band_and_median(values, weights, 95, weighted=True)
    assert band.tolist() == [0.0, 5.0] and median == 4.0
    # Unweighted at 80 %: positions floor(0.1 * 5) = 0, floor(0.5 * 5) = 2 and floor(0.9 * 5) = 4.
    band, median = cld.band_and_median(values, None, 80, weighted=False)
    assert band.tolist() == [0.0, 4.0] and median == 2.0
    # Along the last axis, one median per row.
    rows = np.array([[3.0, 1.0, 2.0], [9.0, 7.0, 8.0]])
    assert cld.median(rows).tolist() == [2.0, 8.0]
    # Sorted, the weights are 0.3, 0.1, 0.6: the CLD reaches 0.5 at the largest value.
    assert cld.weighted_median(rows, np.array([0.6, 0.3, 0.1])).tolist() == [3.0, 9.0]


@pytest.mark.parametrize("engine", ["numpy", "numba"])
@pytest.mark.parametrize("flavour", ["thesis", "weighted"])
def test_tied_costs_give_the_median_of_the_lowest_indices(engine, flavour):
    if engine == "numba":
        pytest.importorskip("numba")
    params = np.linspace(0, 1, 50)[:, None]
    result = moving_window(
        np.zeros(12), np.zeros((50, 12)), params, [[0, 1]], n=2, percentage=10, flavour=flavour, engine=engine
    )
    # Behavioural: the five lowest indices, values 0 .. 4/49, equally weighted; the median is the third.
    np.testing.assert_array_equal(result.median[0], params[2, 0])


def test_the_median_is_that_of_the_window_behavioural_set():
    rng = np.random.default_rng(3)
    u = np.r_[np.zeros(10), np.ones(50)]
    params = rng.uniform(0, 7, (400, 2))
    sims = FirstOrder().simulate(params, u)
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + rng.normal(0, 0.05, u.size)
    costs = dynia.engine.windows.window_costs(y, sims, 4, 30, 31)[0]
    kept = np.argsort(costs, kind="stable")[:40]
    weights = cld.likelihood(costs[kept])
    for flavour, expected in (
        ("thesis", [cld.median(params[kept, p]) for p in range(2)]),
        ("weighted", [cld.weighted_median(params[kept, p], weights) for p in range(2)]),
    ):
        result = moving_window(y, sims, params, [[0, 7], [0, 7]], n=4, flavour=flavour, engine="numpy")
        assert result.median[:, 30].tolist() == expected


def _records():
    """(name, u, y): a record the model fits, one it misfits (a second-order plant with dead time), coloured noise."""
    steps = 300
    u = dynia.synthetic.example_firstorder_input(steps)
    for seed in (0, 1, 2):
        rng = np.random.default_rng(seed)
        fits = FirstOrder().simulate([[2.0, 3.0]], u)[0] + rng.normal(0, 0.2, steps)
        misfit = SecondOrderDelay().simulate([[2.0, 3.0, 2.0, 2.0]], u)[0] + 0.5 + rng.normal(0, 0.1, steps)
        # AR(1) noise with coefficient 0.95: neighbouring windows share their errors.
        shocks = rng.normal(0, 0.1, steps)
        coloured = np.empty(steps)
        coloured[0] = shocks[0]
        for k in range(1, steps):
            coloured[k] = 0.95 * coloured[k - 1] + shocks[k]
        brown = FirstOrder().simulate([[2.0, 3.0]], u)[0] + coloured
        yield from (
            (f"fits-{seed}", u, fits, seed),
            (f"misfit-{seed}", u, misfit, seed),
            (f"coloured-{seed}", u, brown, seed),
        )


@pytest.mark.parametrize("flavour", ["thesis", "weighted", "mcat"])
def test_the_estimate_and_every_median_lie_in_their_band(flavour):
    for label, u, y, seed in _records():
        result = dynia.run(u, y, FirstOrder(), BOUNDS, n=5, n_samples=600, flavour=flavour, rng=seed)
        lower, upper = result.ci[..., 0], result.ci[..., 1]
        usable = ~np.isnan(result.ic)
        assert np.array_equal(np.isnan(result.median), ~usable), label
        assert ((lower <= result.median) & (result.median <= upper))[usable].all(), label
        for p, (name, entry) in enumerate(result.summary().items()):
            best = int(np.nanargmax(result.ic[p]))
            assert entry["estimate"] == result.median[p, best], (label, name)
            assert entry["band"][0] <= entry["estimate"] <= entry["band"][1], (label, name)


def test_the_estimate_keeps_its_band_in_float32_and_on_disk(tmp_path):
    u, y, seed = next((u, y, seed) for label, u, y, seed in _records() if label == "misfit-1")
    stored = dynia.run(
        u, y, FirstOrder(), BOUNDS, n=5, n_samples=600, rng=seed, dtype="float32", store=tmp_path / "r.nc"
    )
    assert stored.median.dtype == np.float32
    for entry in stored.summary().values():
        assert entry["band"][0] <= entry["estimate"] <= entry["band"][1]


def test_a_result_without_median_reports_the_band_midpoint(tmp_path):
    u, y, seed = next((u, y, seed) for label, u, y, seed in _records() if label == "fits-0")
    result = dynia.run(u, y, FirstOrder(), BOUNDS, n=5, n_samples=400, rng=seed)
    # A file written before the median existed: the same layout without the variable.
    result.to_xarray().drop_vars("median").to_netcdf(tmp_path / "old.nc", engine="h5netcdf")
    for lazy in (False, True):
        old = dynia.load(tmp_path / "old.nc", lazy=lazy)
        assert old.median is None
        np.testing.assert_array_equal(np.asarray(old.ci), result.ci)
        for p, entry in enumerate(old.summary().values()):
            best = int(np.nanargmax(result.ic[p]))
            assert entry["estimate"] == (result.ci[p, best, 0] + result.ci[p, best, 1]) / 2
        assert "median" not in old.to_dataframe().columns


@pytest.mark.parametrize("flavour", ["thesis", "weighted"])
def test_a_band_narrower_than_a_gradient_bin_holds_its_estimate(flavour):
    # K = 2 sits on the edge between the bins [1, 2) and [2, 3) of 7 bins over 0 .. 7, and the band of a
    # clean record is far narrower than a bin: a bin centre (1.5 or 2.5, the former estimate) lies outside it.
    u = dynia.synthetic.example_firstorder_input(300)
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(5).normal(0, 0.05, 300)
    result = dynia.run(u, y, FirstOrder(), BOUNDS, n=10, n_samples=2000, percentage=1, bins=7, flavour=flavour, rng=5)
    entry = result.summary()["K"]
    lower, upper = entry["band"]
    assert upper - lower < 0.2 and 1.95 < entry["estimate"] < 2.05
    assert lower <= entry["estimate"] <= upper
    best = int(np.nanargmax(result.ic[0]))
    assert not lower <= result.bin_centres[0, np.argmax(result.gradient[0, :, best])] <= upper
