"""resample_events: exact on piecewise-linear signals, the grid it promises, one clear error per mistake."""
import numpy as np
import pytest

from dynia.data import resample_events


def _event_times(rng, size, start=0.0):
    """Strictly increasing irregular timestamps: bursts of short gaps and long steady gaps."""
    gaps = np.where(rng.random(size - 1) < 0.5, rng.uniform(0.01, 0.2, size - 1), rng.uniform(1, 30, size - 1))
    return start + np.r_[0.0, np.cumsum(gaps)]


@pytest.mark.parametrize("seed", range(20))
def test_a_linear_signal_resamples_exactly(seed):
    rng = np.random.default_rng(seed)
    slope_u, offset_u, slope_y, offset_y = rng.normal(0, 5, 4)
    times_u = _event_times(rng, rng.integers(2, 60), start=rng.uniform(-10, 10))
    times_y = _event_times(rng, rng.integers(2, 60), start=rng.uniform(-10, 10))
    if max(times_u[0], times_y[0]) >= min(times_u[-1], times_y[-1]):
        times_y = times_y + (times_u[0] - times_y[0])  # make them overlap
    dt = rng.uniform(0.05, 3)
    grid, u, y = resample_events(times_u, slope_u * times_u + offset_u,
                                 times_y, slope_y * times_y + offset_y, dt=dt)
    np.testing.assert_allclose(u, slope_u * grid + offset_u, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(y, slope_y * grid + offset_y, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("seed", range(20))
def test_grid_is_uniform_and_spans_the_overlap(seed):
    rng = np.random.default_rng(100 + seed)
    times_u = _event_times(rng, 40, start=rng.uniform(0, 5))
    times_y = _event_times(rng, 40, start=rng.uniform(0, 5))
    dt = rng.uniform(0.1, 2)
    grid, u, y = resample_events(times_u, rng.normal(size=40), times_y, rng.normal(size=40), dt=dt)
    start, stop = max(times_u[0], times_y[0]), min(times_u[-1], times_y[-1])
    assert grid[0] == start
    np.testing.assert_allclose(np.diff(grid), dt, rtol=1e-9)
    assert grid[-1] <= stop < grid[-1] + dt
    assert grid.shape == u.shape == y.shape


@pytest.mark.parametrize("seed", range(10))
def test_values_stay_between_neighbouring_records_and_records_on_the_grid_are_kept(seed):
    rng = np.random.default_rng(200 + seed)
    times = np.arange(0, 50, 0.5) + rng.uniform(0, 0.4, 100) * (np.arange(100) % 3 > 0)
    values = rng.normal(size=100)
    grid, u, y = resample_events(times, values, times, -values, dt=0.5)
    right = np.searchsorted(times, grid, side="right")
    left = np.clip(right - 1, 0, 99)
    right = np.clip(right, 0, 99)
    low, high = np.minimum(values[left], values[right]), np.maximum(values[left], values[right])
    assert ((u >= low - 1e-12) & (u <= high + 1e-12)).all()
    np.testing.assert_array_equal(y, -u)  # the same log twice: one interpolation, sign aside
    on_grid = np.isin(times, grid)
    assert on_grid.sum() > 10
    np.testing.assert_array_equal(u[np.isin(grid, times)], values[on_grid])


def test_swapping_the_logs_swaps_the_results():
    rng = np.random.default_rng(7)
    times_u, times_y = _event_times(rng, 30), _event_times(rng, 25, start=0.3)
    u, y = rng.normal(size=30), rng.normal(size=25)
    grid, u_grid, y_grid = resample_events(times_u, u, times_y, y, dt=0.7)
    grid2, y_grid2, u_grid2 = resample_events(times_y, y, times_u, u, dt=0.7)
    np.testing.assert_array_equal(grid, grid2)
    np.testing.assert_array_equal(u_grid, u_grid2)
    np.testing.assert_array_equal(y_grid, y_grid2)


def test_start_stop_choose_a_stretch_and_stop_on_the_grid_is_kept():
    times = np.arange(0.0, 10.5, 0.5)
    grid, u, _ = resample_events(times, 3 * times, times, times, dt=0.1, start=2.0, stop=2.3)
    np.testing.assert_allclose(grid, [2.0, 2.1, 2.2, 2.3])  # 0.3/0.1 is 2.9999999999999996 in floats
    assert grid[-1] <= 2.3
    np.testing.assert_allclose(u, 3 * grid)


def test_default_dt_is_the_median_spacing_of_the_union_inside_the_span():
    times_u = np.array([0.0, 1.0, 1.5, 2.0, 10.0, 20.0])
    times_y = np.array([0.0, 1.2, 5.0, 20.0, 25.0])
    union = np.array([0.0, 1.0, 1.2, 1.5, 2.0, 5.0, 10.0, 20.0])
    grid, _, _ = resample_events(times_u, np.ones(6), times_y, np.ones(5))
    np.testing.assert_allclose(grid[1] - grid[0], np.median(np.diff(union)))
    # a stretch: only the timestamps inside it, with its ends, count
    grid, _, _ = resample_events(times_u, np.ones(6), times_y, np.ones(5), start=1.0, stop=4.0)
    np.testing.assert_allclose(grid[1] - grid[0], np.median(np.diff([1.0, 1.2, 1.5, 2.0, 4.0])))


def test_a_step_logged_as_last_value_before_and_first_after_stays_a_step():
    # exception logging stores 36 just before the step and 40 just after it
    times_u = np.array([0.0, 29.9, 30.0, 60.0])
    grid, u, _ = resample_events(times_u, [36, 36, 40, 40], [0.0, 60.0], [72, 72], dt=1.0)
    np.testing.assert_array_equal(u[:30], 36)
    np.testing.assert_array_equal(u[30:], 40)


@pytest.mark.parametrize("kwargs, message", [
    (dict(times_u=[0, 1, 2], u=[1, 2]), r"times_u has 3 timestamps but u has 2 values"),
    (dict(times_y=[0, 1], y=[1, 2, 3]), r"times_y has 2 timestamps but y has 3 values"),
    (dict(times_u=[0, 1, 1]), r"times_u must be strictly increasing: times_u\[2\] = 1.0 follows times_u\[1\]"),
    (dict(times_y=[0, 2, 1]), r"times_y must be strictly increasing: times_y\[2\] = 1.0"),
    (dict(times_u=[0, np.nan, 2]), r"times_u holds a non-finite value at index 1"),
    (dict(u=[1, 2, np.inf]), r"u holds a non-finite value at index 2"),
    (dict(y=[np.nan, 2, 3]), r"y holds a non-finite value at index 0"),
    (dict(times_y=[[0, 1, 2]]), r"times_y must be 1-D"),
    (dict(u=[]), r"u is empty"),
    (dict(dt=0), r"dt must lie strictly between 0 and inf; got 0"),
    (dict(dt=-1.0), r"dt must lie strictly between 0 and inf; got -1.0"),
    (dict(dt=np.nan), r"dt must be a finite number; got nan"),
    (dict(dt="1"), r"dt must be a finite number; got '1'"),
    (dict(times_y=[5, 6, 7]), r"the logs do not overlap in time: times_u spans \[0.0, 2.0\]"),
    (dict(times_y=[2, 3, 4]), r"the logs do not overlap in time"),
    (dict(start=-1), r"start = -1 lies outside \[0.0, 2.0\]"),
    (dict(stop=3), r"stop = 3 lies outside"),
    (dict(start=1.5, stop=1.0), r"start \(1.5\) must be before stop \(1.0\)"),
])
def test_mistakes_are_named(kwargs, message):
    arguments = dict(times_u=[0, 1, 2], u=[1, 2, 3], times_y=[0, 1, 2], y=[2, 4, 6])
    arguments.update(kwargs)
    with pytest.raises(ValueError, match=message):
        resample_events(**arguments)
