"""cooling_water_loop: determinism, the properties the case study relies on, exact dynamics, errors."""

import numpy as np
import pytest

from dynia.io.csv import resample_events
from dynia.synthetic import _exception_log, cooling_water_loop


@pytest.fixture(scope="module")
def month():
    """The default month with seed 11, and its 1-minute grid."""
    time_u, u, time_y, y, truth = cooling_water_loop(np.random.default_rng(11))
    grid, u_grid, y_grid = resample_events(time_u, u, time_y, y, dt=1.0)
    return dict(time_u=time_u, u=u, time_y=time_y, y=y, truth=truth, grid=grid, u_grid=u_grid, y_grid=y_grid)


def test_the_same_seed_gives_the_same_logs_and_another_seed_other_logs():
    first = cooling_water_loop(np.random.default_rng(4), days=5)
    again = cooling_water_loop(4, days=5)  # an int seed is the same stream
    other = cooling_water_loop(np.random.default_rng(5), days=5)
    for a, b in zip(first[:4], again[:4]):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(first[4].step_times, again[4].step_times)
    assert first[4].glitch_time == again[4].glitch_time and first[4].drift_start == again[4].drift_start
    assert first[1].size != other[1].size or not np.array_equal(first[1], other[1])
    assert not np.array_equal(first[4].step_times, other[4].step_times)


def test_logs_are_event_based_strictly_increasing_and_span_the_record(month):
    end = 30 * 1440.0
    assert month["truth"].end == end
    for times, values in [(month["time_u"], month["u"]), (month["time_y"], month["y"])]:
        assert times[0] == 0.0 and times[-1] == end
        assert (np.diff(times) > 0).all() and np.isfinite(values).all()
        gaps = np.diff(times)
        assert gaps.max() <= 60.0 + 2 * month["truth"].scan  # the heartbeat
        assert gaps.min() < month["truth"].scan < np.median(gaps) * 5 < gaps.max()  # irregular
        assert times.size < 0.1 * end / month["truth"].scan  # far fewer records than scans
    # the two tags have their own timestamps
    assert np.intersect1d(month["time_u"], month["time_y"]).size < 10


def test_logs_are_dense_at_a_step_and_sparse_when_steady(month):
    truth, time_y = month["truth"], month["time_y"]
    for step in truth.step_times:
        after_step = np.sum((time_y >= step) & (time_y < step + 5))
        steady_hour = np.sum((time_y >= step - 70) & (time_y < step - 10)) / 12  # per 5 minutes
        assert after_step > 4 * max(steady_hour, 1)


def test_levels_gains_and_the_change_of_mode(month):
    truth, grid, u, y = month["truth"], month["grid"], month["u_grid"], month["y_grid"]
    assert (truth.gain, truth.gain_after, truth.time_constant) == (2.0, 1.8, 2.0)
    assert truth.step_times.size == 6 and (np.diff(truth.step_times) > 0).all()
    assert truth.step_times[-1] < 0.6 * truth.end < truth.drift_start < truth.drift_end < truth.end
    assert truth.step_inputs[-1] == truth.input_level
    assert (np.abs(np.diff(np.r_[truth.input_level, truth.step_inputs])) >= 1.0).all()
    settled = np.ones(grid.size, bool)
    for step in truth.step_times:
        settled &= np.abs(grid - step) > 30
    settled &= np.abs(grid - truth.glitch_time) > 5
    before = settled & (grid < truth.drift_start)
    after = settled & (grid > truth.drift_end)
    assert abs(np.median(u[before]) - 36) < 1.0 and abs(np.median(y[before]) - 72) < 2.0
    assert abs(np.median(u[after]) - 40) < 0.5 and abs(np.median(y[after]) - 72) < 0.6
    # y = K u in steady state, no offset: K = 2 before the change of mode, 1.8 after it
    assert abs(np.median(y[before] / u[before]) - 2.0) < 0.01
    assert abs(np.median(y[after] / u[after]) - 1.8) < 0.01
    np.testing.assert_allclose(
        truth.gain_at([0.0, truth.drift_start, truth.drift_end, truth.end]), [2.0, 2.0, 1.8, 1.8]
    )
    middle = (truth.drift_start + truth.drift_end) / 2
    assert truth.gain_at(middle) * truth.base_input_at(middle) == pytest.approx(72.0)


def test_one_erroneous_zero_per_tag_one_grid_step_apart(month):
    truth = month["truth"]
    assert truth.glitch_time == round(truth.glitch_time)  # a whole minute
    assert truth.glitch_time_output == truth.glitch_time + 1.0
    np.testing.assert_array_equal(month["time_u"][month["u"] < 10], [truth.glitch_time])
    np.testing.assert_array_equal(month["time_y"][month["y"] < 10], [truth.glitch_time_output])
    # steady around it: more than 30 time constants from a step and from the drift
    assert np.abs(truth.step_times - truth.glitch_time).min() > 60
    assert not truth.drift_start - 60 < truth.glitch_time < truth.drift_end + 60
    grid = month["grid"]
    np.testing.assert_array_equal(grid[month["u_grid"] < 10], [truth.glitch_time])
    np.testing.assert_array_equal(grid[month["y_grid"] < 10], [truth.glitch_time + 1])
    k = int(truth.glitch_time)
    assert month["u_grid"][k] == 0 and month["y_grid"][k + 1] == 0
    # the neighbours are untouched: a scan is shorter than the grid step
    assert abs(month["u_grid"][k + 1] - month["u_grid"][k - 1]) < 1
    assert abs(month["y_grid"][k + 2] - month["y_grid"][k]) < 1.5


def test_glitch_lag_zero_puts_both_zeros_on_the_same_step():
    time_u, u, time_y, y, truth = cooling_water_loop(np.random.default_rng(3), days=4, glitch_lag=0)
    grid, u_grid, y_grid = resample_events(time_u, u, time_y, y, dt=1.0)
    assert truth.glitch_time_output == truth.glitch_time
    np.testing.assert_array_equal(grid[u_grid < 10], grid[y_grid < 10])


def test_without_noise_the_output_is_the_exact_first_order_step_response():
    quiet = dict(input_wander=0, output_disturbance=0, sensor_noise=0, input_deadband=0, output_deadband=0)
    time_u, u, time_y, y, truth = cooling_water_loop(np.random.default_rng(8), days=3, **quiet)
    steps_only = (u > 10) & (time_u < truth.drift_start)  # the drift is held on the scan raster
    np.testing.assert_array_equal(u[steps_only], truth.base_input_at(time_u[steps_only]))
    levels = np.r_[truth.input_level, truth.step_inputs]
    for step, before, after in zip(truth.step_times, levels[:-1], levels[1:]):
        near = (time_y > step) & (time_y < step + 20)
        expected = truth.gain * (before + (after - before) * -np.expm1(-(time_y[near] - step) / truth.time_constant))
        np.testing.assert_allclose(y[near], expected, rtol=1e-10)
        assert near.sum() > 100  # no deadband: every 10 s scan is stored
    drifted = time_y > truth.drift_end + 60
    np.testing.assert_allclose(y[drifted & (y > 10)], 72.0, rtol=1e-9)


def test_exception_log_stores_the_reading_before_an_exception_and_a_heartbeat():
    times = np.arange(12.0)
    values = np.array([0.0, 0.05, 0.1, 0.15, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.05, 1.0])
    # 4 passes the deadband (0.2) from 0: 3 is stored with it; 9 is the heartbeat (5 after 4)
    np.testing.assert_array_equal(_exception_log(times, values, 0.2, 5.0), [0, 3, 4, 9, 11])
    # consecutive exceptions are each stored once
    np.testing.assert_array_equal(_exception_log(times[:4], np.array([0.0, 1.0, 2.0, 2.0]), 0.5, 100.0), [0, 1, 2, 3])


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(days=0), "days must lie strictly between 0 and inf"),
        (dict(days=np.nan), "days must be a finite number"),
        (dict(n_steps=0), "n_steps must be at least 1"),
        (dict(scan=1.5), "scan must lie strictly between 0 and 1"),
        (dict(glitch_lag=-1.0), "glitch_lag must lie strictly between 0 and inf"),
        (dict(step_offset=(2.0, 1.0)), r"step_offset must satisfy 0 <= low <= high"),
        (dict(step_offset=3.0), r"step_offset must be a \(low, high\) pair"),
        (dict(sensor_noise=-0.1), "sensor_noise must lie strictly between 0 and inf"),
        (dict(days=0.05), "days = 0.05 is too short"),
    ],
)
def test_bad_arguments_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        cooling_water_loop(np.random.default_rng(0), **kwargs)
