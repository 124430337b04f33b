"""The compiled engine's window sums: compensated running sums, and the fused kernel of the linear models.

The numpy path's left-to-right sums are the reference; the contract between
the two is stated and checked in tests/test_fast.py. Here: the running sum
survives what breaks a plain one (a huge error leaving a window of small
ones, an infinite error), and compiled against compiled stays bit for bit:
the fused kernel (:meth:`dynia.engine.kernels.driver.CompiledErrors.window_sums`)
gives the sums the error rows give (:func:`dynia.engine.kernels.readoff.analyse_windows`),
hence the same results, for every built-in linear model, dead time, missing
measurement, error scale, half window and worker count.
"""

import os
from fractions import Fraction

import control
import numpy as np
import pytest
from conftest import compiled_window_costs, example_firstorder_input

import dynia
from dynia.engine import kernels
from dynia.engine.kernels.fused import FUSED_BLOCK, LAG_BLOCK
from dynia.engine.kernels.sums import first_window, next_window
from dynia.engine.noise import window_points
from dynia.engine.windows import default_chunk_steps, moving_window, window_costs, window_halos
from dynia.errors import ModelError, SettingsError
from dynia.models import FOPDT, FirstOrder, SecondOrderDelay, TransferFunction

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


def test_a_huge_error_leaving_does_not_cancel_the_small_ones():
    rng = np.random.default_rng(3)
    y = rng.normal(0, 1, 200)
    y[60] = 1e12  # every sample's error there is about 1e12; a plain running sum keeps ~1e-4 of it afterwards
    sims = rng.normal(0, 1, (50, 200))
    n = 4
    costs = compiled_window_costs(y, sims, n, chunk_steps=200)
    reference = window_costs(y, sims, n, 0, 200)
    np.testing.assert_allclose(costs, reference, rtol=2 * (2 * n + 2) * 2.0**-53, atol=0)
    plain = np.cumsum(np.abs(sims - y), axis=1)  # what an uncompensated running sum would have left
    drifted = (plain[:, 100] - plain[:, 100 - 2 * n - 1]) / (2 * n + 1)
    assert np.abs(drifted**2 - reference[100 - n]).max() > 1e-6  # the case is one that needs the compensation


def _running_sums(rows, slots):
    """Every window's sums (m, n_samples) by the compiled kernel's running sums, over one chunk of error rows."""
    high, low, total = (np.empty(rows.shape[1]) for _ in range(3))
    measured = np.ones(rows.shape[0])
    sums = []
    for t in range(rows.shape[0] - slots + 1):
        if t:
            next_window(rows, measured, t, slots, 0.0, (high, low), total)
        else:
            first_window(rows, measured, slots, (high, low), total)
        sums.append(total.copy())
    return np.array(sums)


def test_an_infinite_error_is_summed_afresh_until_it_has_left():
    slots = 7
    rows = np.random.default_rng(4).uniform(0, 1, (60, 5))
    rows[20, 2] = np.inf  # an error that overflowed
    sums = _running_sums(rows, slots)
    reference = np.array([rows[t : t + slots].sum(axis=0) for t in range(sums.shape[0])])
    infinite = np.isinf(reference)
    assert infinite.sum() == slots and infinite[:, 2].sum() == slots
    np.testing.assert_array_equal(np.isinf(sums), infinite)
    # Every other sum, sample 2's once the step has left too, is within rounding of the plain one.
    np.testing.assert_allclose(sums[~infinite], reference[~infinite], rtol=2 * slots * 2.0**-53, atol=0)


def _record(steps=260, seed=0, gaps=True):
    rng = np.random.default_rng(seed)
    u = example_firstorder_input(steps)
    u[:25] = 0
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + rng.normal(0, 0.3, steps)
    if gaps:
        y[90:97] = np.nan
        y[200] = np.nan
    return u, y


def _lead_lag(p):
    return control.tf([p[0] * p[1], p[0]], [p[2], 1.0])


MODELS = [
    (FirstOrder(), {"K": (0, 7), "T": (0, 7)}),
    (FOPDT(), {"K": (0, 7), "T": (0, 7), "theta": (0, 3.5)}),  # a dead time per sample
    (SecondOrderDelay(), {"K": (0, 7), "T1": (0, 7), "T2": (0, 3), "theta": (0, 3)}),
    (
        TransferFunction(_lead_lag, names=("K", "a", "T", "theta"), delay="theta"),
        {"K": (0.5, 3), "a": (0, 2), "T": (0.5, 5), "theta": (0, 2.5)},
    ),
]


@pytest.mark.parametrize("model, bounds", MODELS, ids=lambda value: type(value).__name__)
@pytest.mark.parametrize(
    "n, window, x0", [(0, "centred", "zero"), (4, "trailing", "steady"), (30, "centred", "steady")]
)
def test_the_fused_kernel_equals_the_error_rows_bit_for_bit(model, bounds, n, window, x0):
    u, y = _record()
    options = dict(n=n, window=window, percentage=10, min_points=min(3, 2 * n + 1))
    # Two workers of 1 050 samples each: each worker's range spans a block boundary of the lag and general kernels.
    n_samples = 2 * (max(LAG_BLOCK, FUSED_BLOCK) + 26)
    fused = dynia.run(
        u, y, model, bounds, n_samples=n_samples, rng=5, x0=x0, dt=0.7, engine="numba", workers=2, **options
    )
    order = [fused.names.index(name) for name in model.names]
    sims = model.simulate(fused.samples[:, order], u, dt=0.7, x0=x0)
    rows = moving_window(
        y,
        sims,
        fused.samples,
        fused.bounds,
        names=fused.names,
        engine="numba",
        chunk_steps=default_chunk_steps(n_samples, 2 * n),
        **options,
    )
    for name in ("ic", "ci", "median", "gradient"):
        np.testing.assert_array_equal(getattr(fused, name), getattr(rows, name))


def test_the_fused_kernel_keeps_the_error_scale_and_the_monte_carlo_batches():
    u, y = _record(gaps=False)
    bounds = {"K": (0, 7e120), "T": (0, 7)}  # y near 1e121: errors are scaled by a power of two (error_scale)
    y = y * 1e120
    options = dict(n=6, percentage=10, ic_error=True)
    fused = dynia.run(u, y, FirstOrder(), bounds, n_samples=900, rng=2, engine="numba", **options)
    sims = FirstOrder().simulate(fused.samples, u)
    rows = moving_window(y, sims, fused.samples, fused.bounds, names=fused.names, engine="numba", **options)
    for name in ("ic", "ci", "median", "gradient", "ic_se", "ci_se"):
        np.testing.assert_array_equal(getattr(fused, name), getattr(rows, name))
    assert np.nanmax(fused.ic) > 0.5


def test_window_sums_count_the_measured_points_and_come_in_order():
    u, y = _record()
    n_steps = y.size
    params = np.random.default_rng(1).uniform(0, 7, (40, 2))
    source = kernels.CompiledErrors(FirstOrder(), params, u, y, dt=1.0, x0="zero", workers=1)
    halos = window_halos(5, "centred")
    totals = np.zeros(40)
    present = [source.window_sums(start, min(start + 33, n_steps), halos, totals)[1] for start in range(0, n_steps, 33)]
    np.testing.assert_array_equal(np.concatenate(present), window_points(y, *halos))
    expected = np.abs(FirstOrder().simulate(params, u) - y)
    expected[:, np.isnan(y)] = 0
    record = np.zeros(40)
    for step in expected.T:  # step by step in time order, as add_record_errors adds them
        record += step
    np.testing.assert_array_equal(totals, record)
    with pytest.raises(ValueError, match="chunk after chunk"):
        source.window_sums(0, 33, halos, totals)
    with pytest.raises(ValueError, match="after window sums"):
        source.rows(0, 10)


def test_an_overflowing_simulation_is_named_by_the_fused_kernel():
    unstable = TransferFunction(lambda p: control.tf([1.0], [1.0, -p[0]]), names=("a",))
    u, y = np.ones(400), np.zeros(400)
    source = kernels.CompiledErrors(unstable, np.array([[0.5], [3.0]]), u, y, dt=1.0, x0="zero", workers=1)
    with pytest.raises(ModelError, match="simulation of sample 1 is not finite at step"):
        source.window_sums(0, 400, (2, 2), np.zeros(2))


def test_the_cost_of_a_window_does_not_depend_on_its_length():
    """The running sum touches two rows a window whatever n: counted on the kernel's own helpers, not timed."""
    rows = np.random.default_rng(0).uniform(0, 1, (500, 3))
    measured = np.ones(500)
    for slots in (3, 201):
        high, low, total = np.empty(3), np.empty(3), np.empty(3)
        first_window(rows, measured, slots, (high, low), total)
        # Window 1 reads row 0 (leaving) and row ``slots`` (entering) only: every other row is poisoned.
        rows_copy = np.full_like(rows, np.nan)
        rows_copy[[0, slots]] = rows[[0, slots]]
        present = next_window(rows_copy, measured, 1, slots, float(slots), (high, low), total)
        assert present == slots
        np.testing.assert_allclose(total, rows[1 : slots + 1].sum(axis=0), rtol=4 * slots * 2.0**-53)


def test_the_sums_are_the_exact_sums_rounded_once_whatever_the_chunks(example1):
    """Known answers on thesis example 1: the compensation leaves no trace of the window's history.

    The high/low pair holds the exact sum unless its low part itself rounds,
    which these errors never make it do: each cost is the one of the exact
    window sum rounded once, the same bits whatever the chunk it starts
    afresh in, so the compiled engine's results do not depend on its chunks
    (nor on the distributed engine's time chunks).
    """
    y, sims = example1["y"], example1["sims"]
    for n in (100, 10):
        costs = compiled_window_costs(y, sims, n, chunk_steps=37)
        np.testing.assert_array_equal(costs, compiled_window_costs(y, sims, n, chunk_steps=500))
    errors = np.abs(sims - y)
    for t in range(0, 500, 7):
        first, stop = max(t - n, 0), min(t + n + 1, 500)
        for s in range(0, 2000, 97):
            exact = sum(Fraction(float(value)) for value in errors[s, first:stop])
            mae = float(exact) / (stop - first)  # float() of a Fraction rounds once, to nearest
            assert mae * mae == costs[t, s], (t, s)


@pytest.mark.parametrize("model, bounds", MODELS, ids=lambda value: type(value).__name__)
@pytest.mark.parametrize("x0", ["zero", "steady"])
def test_the_kernels_outputs_are_the_models_own_bit_for_bit(model, bounds, x0):
    # The noise floor's re-simulation of its few sets takes these on the compiled engine.
    u, y = _record()
    low, high = np.array(list(bounds.values())).T
    params = np.random.default_rng(8).uniform(low, high, (6, low.size))
    source = kernels.CompiledErrors(model, params, u, y, dt=0.7, x0=x0, workers=1)
    chunks = list(source.output_chunks(37))
    assert {chunk.shape[1] for chunk in chunks[:-1]} == {37}
    np.testing.assert_array_equal(np.concatenate(chunks, axis=1), model.simulate(params, u, dt=0.7, x0=x0))
    with pytest.raises(SettingsError, match="rows were requested after outputs"):
        source.rows(0, 5)
    with pytest.raises(SettingsError, match="outputs were requested after outputs"):
        source.output_chunks(37)
    used = kernels.CompiledErrors(model, params, u, y, dt=0.7, x0=x0, workers=1)
    used.rows(0, 5)
    with pytest.raises(SettingsError, match="outputs were requested after rows"):
        used.output_chunks(37)


def test_a_cached_kernel_older_than_any_source_of_the_package_is_dropped(tmp_path, monkeypatch):
    """numba checks only the kernel's own file: an edit of a helper's module must still recompile the kernel."""
    from dynia.engine.kernels.compile import drop_stale_cache

    package, elsewhere = tmp_path / "kernels", tmp_path / "numba-cache"
    (package / "__pycache__").mkdir(parents=True)
    for name in ("readoff.py", "sums.py"):
        (package / name).write_text("")
    # Where numba puts the package's kernels under NUMBA_CACHE_DIR: asked of numba itself, so that a release that
    # moves them fails here rather than leaving stale kernels to run (a helper's old code, once a loop that hung).
    from numba.core.caching import _CacheLocator

    mapped = elsewhere / _CacheLocator.get_suitable_cache_subpath(str(package / "readoff.py"))
    mapped.mkdir(parents=True)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(elsewhere))
    stale = [package / "__pycache__" / "readoff.analyse-1.nbi", mapped / "readoff.analyse-1.py311.1.nbc"]
    fresh = [package / "__pycache__" / "readoff.analyse-2.nbi", mapped / "readoff.analyse-2.py311.1.nbc"]
    for path in stale + fresh:
        path.write_text("")
    os.utime(package / "readoff.py", (1000, 1000))
    os.utime(package / "sums.py", (3000, 3000))  # the helper's module edited after the kernel was cached
    for path in stale:
        os.utime(path, (2000, 2000))
    for path in fresh:
        os.utime(path, (4000, 4000))
    assert drop_stale_cache(package) == 2
    assert not any(path.exists() for path in stale) and all(path.exists() for path in fresh)
