"""dynia.io.csv: resample_events on event logs, load_csv on the files engineers export.

resample_events: exact on piecewise-linear signals, the grid it promises, one
clear error per mistake. load_csv: every layout and kind of time, missing
values, and one DataError line naming file, row and column per bad input.
"""

import datetime
import io
import math
import pathlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from dynia.errors import SettingsError
from dynia.io.csv import DataError, ProcessData, load_csv, resample_events

HEATING_SYSTEM = pathlib.Path("/work/shared/data/heating_system/heating_system.dat")


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
    grid, u, y = resample_events(times_u, slope_u * times_u + offset_u, times_y, slope_y * times_y + offset_y, dt=dt)
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


@pytest.mark.parametrize(
    "kwargs, message",
    [
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
    ],
)
def test_mistakes_are_named(kwargs, message):
    arguments = dict(times_u=[0, 1, 2], u=[1, 2, 3], times_y=[0, 1, 2], y=[2, 4, 6])
    arguments.update(kwargs)
    with pytest.raises(ValueError, match=message):
        resample_events(**arguments)


# --- load_csv -----------------------------------------------------------------


def _write(folder, text, name="data.csv", encoding="utf-8"):
    """Write ``text`` as the file ``name`` in ``folder``, byte for byte (no newline translation)."""
    path = folder / name
    path.write_bytes(text.encode(encoding))
    return path


def _load(path, **kwargs):
    kwargs = {"time": "time", "input": "u", "output": "y", **kwargs}
    return load_csv(path, **kwargs)


def test_uniform_rows_are_used_as_they_are(tmp_path):
    path = _write(tmp_path, "time,u,y\n100,1.5,2\n102,1.5,2.25\n104,3,2.5\n106,3,3.125\n")
    data = _load(path)
    assert isinstance(data, ProcessData)
    np.testing.assert_array_equal(data.time, [0, 2, 4, 6])
    np.testing.assert_array_equal(data.u, [1.5, 1.5, 3, 3])
    np.testing.assert_array_equal(data.y, [2, 2.25, 2.5, 3.125])
    assert data.dt == 2.0 and isinstance(data.dt, float)
    assert data.start == 100.0 and data.notes == ()  # the file's time of grid time 0
    assert data.gaps == ()


def test_columns_are_chosen_by_name_in_any_order_with_whitespace_stripped(tmp_path):
    path = _write(tmp_path, " flow , T out ,stamp,other\n1,20,0,x\n2,21,1,y\n")
    data = load_csv(path, time="stamp", input="flow ", output="T out")
    np.testing.assert_array_equal(data.u, [1, 2])
    np.testing.assert_array_equal(data.y, [20, 21])


def test_a_given_dt_equal_to_the_spacing_keeps_the_rows(tmp_path):
    path = _write(tmp_path, "time,u,y\n0,1,2\n0.1,2,3\n0.2,3,4\n0.30000000000000004,4,5\n")
    data = _load(path, dt=0.1)
    assert data.dt == 0.1 and data.notes == ()
    np.testing.assert_array_equal(data.u, [1, 2, 3, 4])


def test_a_given_dt_that_differs_resamples_uniform_rows(tmp_path):
    path = _write(tmp_path, "time,u,y\n0,0,10\n2,2,8\n4,4,6\n6,6,4\n")
    data = _load(path, dt=1.5)
    np.testing.assert_allclose(data.time, [0, 1.5, 3, 4.5, 6])
    np.testing.assert_allclose(data.u, data.time)
    np.testing.assert_allclose(data.y, 10 - data.time)
    assert data.notes == ("resampled 4 rows spaced 2 s onto the given 1.5 s grid by linear interpolation",)


def test_irregular_rows_are_resampled_at_the_median_spacing(tmp_path):
    path = _write(tmp_path, "time,u,y\n0,0,1\n1,1,3\n2,2,5\n5,5,11\n6,6,13\n")
    data = _load(path)
    assert data.dt == 1.0  # spacings 1, 1, 3, 1
    np.testing.assert_allclose(data.time, np.arange(7.0))
    np.testing.assert_allclose(data.u, data.time)
    np.testing.assert_allclose(data.y, 1 + 2 * data.time)
    assert data.notes == (
        "resampled 5 irregular rows onto a 1 s grid by linear interpolation "
        "(dt inferred: the median spacing of the rows)",
    )
    assert _load(path, dt=2).notes == ("resampled 5 irregular rows onto a 2 s grid by linear interpolation (dt given)",)


def test_iso_timestamps_with_z_are_utc_and_start_keeps_the_first(tmp_path):
    path = _write(tmp_path, "time,u,y\n2024-05-01T12:00:00Z,1,2\n2024-05-01T12:00:30Z,1,2\n2024-05-01T12:01:00Z,1,2\n")
    data = _load(path)
    assert data.dt == 30.0
    np.testing.assert_array_equal(data.time, [0, 30, 60])
    assert data.start == datetime.datetime(2024, 5, 1, 12, tzinfo=datetime.timezone.utc)


def test_timestamps_with_offsets_are_compared_across_a_daylight_saving_change(tmp_path):
    path = _write(
        tmp_path,
        "time,u,y\n2024-03-31T01:59:00+01:00,1,2\n2024-03-31T03:00:00+02:00,1,2\n2024-03-31T03:01:00+02:00,1,2\n",
    )
    data = _load(path)
    assert data.dt == 60.0 and data.notes == ()
    assert data.start.utcoffset() == datetime.timedelta(hours=1)


def test_naive_timestamps_with_a_space_and_fractions_of_a_second(tmp_path):
    path = _write(
        tmp_path, "time,u,y\n2024-01-01 23:59:59.500,1,2\n2024-01-02 00:00:00.000,1,2\n2024-01-02 00:00:00.500,1,2\n"
    )
    data = _load(path)
    assert data.dt == 0.5
    assert data.start == datetime.datetime(2024, 1, 1, 23, 59, 59, 500000)


@pytest.mark.parametrize(
    "text",
    [
        "time;u;y\n0;1;2\n1;3;4\n",
        "time\tu\ty\n0\t1\t2\n1\t3\t4\n",
        '"time";"u";"y"\r\n"0";"1";"2"\r\n"1";"3";"4"\r\n',
        "\ufefftime,u,y\n0,1,2\n1,3,4\n",  # Excel's "CSV UTF-8" starts with a byte order mark
        "\n\ntime,u,y\n\n0,1,2\n1,3,4\n\n\n,,\n",
    ],
)
def test_separators_quotes_byte_order_mark_and_blank_rows(tmp_path, text):
    data = _load(_write(tmp_path, text))
    np.testing.assert_array_equal(data.u, [1, 3])
    np.testing.assert_array_equal(data.y, [2, 4])


def test_a_comma_header_wins_over_semicolons_and_quoted_commas_do_not_count(tmp_path):
    data = load_csv(_write(tmp_path, "time,flow;m3/h,y\n0,1,2\n1,3,4\n"), time="time", input="flow;m3/h", output="y")
    np.testing.assert_array_equal(data.u, [1, 3])
    path = _write(tmp_path, 'time;"flow, m3/h";y\n0;1;2\n1;3;4\n')
    np.testing.assert_array_equal(load_csv(path, time="time", input="flow, m3/h", output="y").u, [1, 3])


def test_a_windows_1252_file_is_read_and_noted(tmp_path):
    path = _write(tmp_path, "time,u,T [°C]\n0,1,20.5\n1,1,21\n", encoding="cp1252")
    data = load_csv(path, time="time", input="u", output="T [°C]")
    np.testing.assert_array_equal(data.y, [20.5, 21])
    assert data.notes == (f"read {path} as Windows-1252 text, since it is not valid UTF-8",)


@pytest.mark.parametrize("token", ["", " ", "NaN", "nan", "NA", "na", "null", "NULL", "Null"])
def test_missing_values_fill_the_input_and_stay_nan_in_the_output(tmp_path, token):
    path = _write(tmp_path, f"time,u,y\n0,{token},{token}\n1,1,1\n2,{token},{token}\n3,3,3\n4,{token},4\n")
    data = _load(path)
    np.testing.assert_array_equal(data.u, [1, 1, 2, 3, 3])  # ends held, the middle interpolated
    np.testing.assert_array_equal(data.y, [np.nan, 1, np.nan, 3, 4])
    assert data.notes == (
        "filled 3 missing input values by linear interpolation between the nearest present values",
        "2 output values missing, left as NaN in y",
    )


def test_a_row_shorter_than_the_header_misses_its_last_cells(tmp_path):
    data = _load(_write(tmp_path, "time,u,y\n0,1,2\n1,2\n2,3,4\n"))
    np.testing.assert_array_equal(data.y, [2, np.nan, 4])


def test_input_missing_between_irregular_rows_is_interpolated_in_time(tmp_path):
    data = _load(_write(tmp_path, "time,u,y\n0,0,0\n1,,0\n4,4,0\n5,5,0\n"), dt=1)
    np.testing.assert_allclose(data.u, np.arange(6.0))


def test_output_gaps_on_a_resampled_grid(tmp_path):
    # rows at 0..10 s, the output missing at 4 s: with dt 0.5 the grid points
    # from 3.5 to 4.5 would interpolate with it; 3 and 5 are present rows
    rows = "".join(f"{t},{t},{'' if t == 4 else 2 * t}\n" for t in range(11))
    data = _load(_write(tmp_path, "time,u,y\n" + rows), dt=0.5)
    nan = np.isnan(data.y)
    np.testing.assert_array_equal(data.time[nan], [3.5, 4.0, 4.5])
    np.testing.assert_allclose(data.y[~nan], 2 * data.time[~nan])
    assert data.notes[-1] == "1 output value missing, leaving 3 grid points NaN in y"
    # a grid too coarse to land in the gap keeps every point
    data = _load(_write(tmp_path, "time,u,y\n" + rows), dt=3)
    assert not np.isnan(data.y).any()
    assert data.notes[-1] == "1 output value missing, leaving 0 grid points NaN in y"


def test_missing_output_at_the_ends_of_irregular_rows(tmp_path):
    data = _load(_write(tmp_path, "time,u,y\n0,0,\n1,1,1\n3,3,3\n4,4,\n"), dt=0.5)
    expected_nan = (data.time < 1) | (data.time > 3)
    np.testing.assert_array_equal(np.isnan(data.y), expected_nan)
    np.testing.assert_allclose(data.y[~expected_nan], data.time[~expected_nan])


def test_a_long_stretch_without_records_is_a_gap_unless_max_gap_is_none(tmp_path):
    path = _write(tmp_path, "time,u,y\n0,1,5\n1,1,5\n101,1,5\n102,2,6\n")
    data = _load(path, dt=1)
    assert data.time.size == 103
    np.testing.assert_array_equal(np.flatnonzero(np.isnan(data.y)), np.arange(2, 101))  # strictly inside 1..101
    assert data.gaps == ((2, 101),)
    assert data.notes[-1] == "gap of 100 s with no rows from 1 to 101: 99 grid points left missing in y"
    # exception logging that stored nothing for 100 s while the output was steady: bridge it
    bridged = _load(path, dt=1, max_gap=None)
    assert not np.isnan(bridged.y).any() and bridged.gaps == ()
    np.testing.assert_array_equal(bridged.y[:101], 5)
    assert not any(note.startswith("gap") for note in bridged.notes)
    np.testing.assert_array_equal(_load(path, dt=1, max_gap=math.inf).y, bridged.y)
    # a limit above the stretch bridges it too; one just below does not
    assert _load(path, dt=1, max_gap=100).gaps == ()
    assert _load(path, dt=1, max_gap=99.5).gaps == ((2, 101),)


def test_a_missing_stretch_in_the_middle_of_a_wide_file_is_left_missing_in_y_only(tmp_path):
    times = np.r_[np.arange(0, 100), np.arange(200, 300)]  # rows 100 to 199 lost
    path = _write(tmp_path, "time,u,y\n" + "".join(f"{t},{t},{2 * t}\n" for t in times))
    data = _load(path)
    assert data.dt == 1.0 and data.time.size == 300
    missing = np.isnan(data.y)
    np.testing.assert_array_equal(np.flatnonzero(missing), np.arange(100, 200))  # strictly inside 99..200
    np.testing.assert_array_equal(data.y[~missing], 2 * data.time[~missing])
    np.testing.assert_array_equal(data.u, data.time)  # the input is still filled, finite
    assert data.gaps == ((100, 200),)
    assert data.notes == (
        "resampled 200 irregular rows onto a 1 s grid by linear interpolation (dt inferred: the "
        "median spacing of the rows)",
        "gap of 101 s with no rows from 99 to 200: 100 grid points left missing in y",
    )
    bridged = _load(path, max_gap=None)  # the old behaviour: interpolate across
    np.testing.assert_array_equal(bridged.y, 2 * bridged.time)
    assert bridged.gaps == () and len(bridged.notes) == 1


def test_a_gap_note_names_iso_timestamps_as_the_file_wrote_them(tmp_path):
    stamps = [f"2024-05-01T11:59:{second:02d}" for second in range(50, 60)] + ["2024-05-01T12:00:00"]
    stamps += [f"2024-05-01T13:00:{second:02d}" for second in range(11)]
    data = _load(_write(tmp_path, "time,u,y\n" + "".join(f"{stamp},1,2\n" for stamp in stamps)))
    assert data.dt == 1.0
    assert data.notes[-1] == (
        "gap of 3600 s with no rows from 2024-05-01T12:00:00 to 2024-05-01T13:00:00: 3599 grid points left missing in y"
    )
    assert data.gaps == ((11, 3610),) and int(np.isnan(data.y).sum()) == 3599
    zoned = _load(_write(tmp_path, "time,u,y\n" + "".join(f"{stamp}Z,1,2\n" for stamp in stamps)))
    assert "from 2024-05-01T12:00:00Z to 2024-05-01T13:00:00Z:" in zoned.notes[-1]


def test_more_than_five_gaps_are_listed_up_to_five_and_counted(tmp_path):
    # rows every second, with 7 stretches of 10 s (9 grid points each) without rows
    times = [t for t in range(150) if t % 20 <= 10]
    data = _load(_write(tmp_path, "time,u,y\n" + "".join(f"{t},1,2\n" for t in times)))
    assert data.dt == 1.0
    assert data.gaps == tuple((20 * k + 11, 20 * k + 20) for k in range(7))
    gap_notes = [note for note in data.notes if note.startswith("gap of")]
    assert gap_notes == [
        f"gap of 10 s with no rows from {20 * k + 10} to {20 * k + 20}: 9 grid points left missing in y"
        for k in range(5)
    ]
    assert data.notes[-1] == "and 2 more gaps longer than 5 grid steps (5 s): 18 more grid points left missing in y"


def test_a_given_dt_far_below_the_spacing_of_the_rows_makes_every_interval_a_gap(tmp_path):
    data = _load(_write(tmp_path, "time,u,y\n0,0,0\n2,2,4\n4,4,8\n"), dt=0.25)
    assert data.gaps == ((1, 8), (9, 16))
    np.testing.assert_array_equal(data.y[[0, 8, 16]], [0, 4, 8])  # the rows themselves are kept
    np.testing.assert_allclose(data.u, data.time)
    assert _load(_write(tmp_path, "time,u,y\n0,0,0\n2,2,4\n4,4,8\n"), dt=0.25, max_gap=9).gaps == ()


def test_gaps_in_either_event_log_leave_the_output_missing(tmp_path):
    u_times = [t for t in range(61) if not 45 < t < 55]
    y_times = [t for t in range(61) if not 20 < t < 40]
    inputs = _write(tmp_path, "time,u\n" + "".join(f"{t},{t}\n" for t in u_times), name="u.csv")
    outputs = _write(tmp_path, "time,y\n" + "".join(f"{t},{-t}\n" for t in y_times), name="y.csv")
    data = _load(inputs, output_path=outputs)
    assert data.dt == 1.0 and data.time.size == 61
    assert data.gaps == ((21, 40), (46, 55))
    missing = np.isnan(data.y)
    np.testing.assert_array_equal(np.flatnonzero(missing), np.r_[21:40, 46:55])
    np.testing.assert_array_equal(data.y[~missing], -data.time[~missing])
    np.testing.assert_array_equal(data.u, data.time)
    assert data.notes[-2:] == (
        "gap of 20 s with no rows in the output log (column 'y') from 20 to 40: 19 grid points left missing in y",
        "gap of 10 s with no rows in the input log (column 'u') from 45 to 55: 9 grid points left missing in y",
    )
    bridged = _load(inputs, output_path=outputs, max_gap=None)
    np.testing.assert_array_equal(bridged.y, -bridged.time)


def test_overlapping_gaps_of_two_tags_merge_into_one_range(tmp_path):
    records = [(t, "in", t) for t in range(61) if not 20 < t < 35] + [
        (t, "out", 1) for t in range(61) if not 30 < t < 45
    ]
    records.sort(key=lambda record: record[0])
    path = _write(tmp_path, "time,tag,value\n" + "".join("{},{},{}\n".format(*record) for record in records))
    data = load_csv(path, time="time", input="in", output="out", long_format=True)
    assert data.dt == 1.0
    assert data.gaps == ((21, 45),)
    np.testing.assert_array_equal(np.flatnonzero(np.isnan(data.y)), np.arange(21, 45))
    assert [note.split(":")[0] for note in data.notes if note.startswith("gap")] == [
        "gap of 15 s with no rows in the input log (tag 'in') from 20 to 35",
        "gap of 15 s with no rows in the output log (tag 'out') from 30 to 45",
    ]


def test_a_burst_of_closely_spaced_rows_does_not_shrink_the_inferred_dt(tmp_path):
    # an hour of rows 1 s apart, and inside it 1000 rows 1 ms apart
    burst = 1800.0005 + 0.001 * np.arange(1000)
    times = np.sort(np.r_[np.arange(3601.0), burst]).tolist()
    path = _write(tmp_path, "time,u,y\n" + "".join(f"{t!r},{t!r},{3 * t!r}\n" for t in times))
    data = _load(path)
    assert data.dt == 1.0
    assert data.time.size == 3601 and data.gaps == ()
    np.testing.assert_allclose(data.u, data.time, rtol=1e-12)
    np.testing.assert_allclose(data.y, 3 * data.time, rtol=1e-12)


def test_a_grid_of_too_many_steps_is_refused_naming_dt(tmp_path):
    # most spacings are a microsecond: the inferred dt would need 1e8 steps over the 100 s span
    path = _write(tmp_path, "time,u,y\n0,1,2\n1e-06,1,2\n2e-06,1,2\n3e-06,1,2\n100,1,2\n")
    with pytest.raises(
        DataError,
        match=r"data\.csv: the grid would have 10\d \d{3} \d{3} steps at dt = 1e-06 s "
        r"\(inferred: the median spacing of the timestamps\) over the 100 s the data "
        r"span \(limit 10 000 000\); pass a larger --dt / dt=$",
    ):
        _load(path)
    assert _load(path, dt=1, max_gap=None).time.size == 101


def test_two_files_are_two_event_logs_on_their_common_span(tmp_path):
    inputs = _write(tmp_path, "time,valve\n0,0\n4,4\n9,9\n20,20\n", name="valve.csv")
    outputs = _write(tmp_path, "time,level\n2,4\n3,6\n6,12\n12,24\n", name="level.csv")
    data = load_csv(inputs, time="time", input="valve", output="level", output_path=outputs, max_gap=None)
    # time zero is the first record of either log; the grid starts where both have data
    np.testing.assert_allclose(data.time, np.arange(2.0, 13.0, 2.0))
    np.testing.assert_allclose(data.u, data.time)
    np.testing.assert_allclose(data.y, 2 * data.time)
    assert data.dt == 2.0  # median spacing of the union 2, 3, 4, 6, 9, 12 inside [2, 12]
    assert data.start == 0.0
    assert data.notes == (
        f"resampled the input log (column 'valve' of {inputs}, 4 rows) and the output log (column 'level' of "
        f"{outputs}, 4 rows) onto a common 2 s grid from 2 s to 12 s by linear interpolation "
        "(dt inferred: the median spacing of both logs' timestamps)",
    )


def test_two_files_with_timestamps_count_from_the_earlier_first_record(tmp_path):
    inputs = _write(tmp_path, "time,u\n2024-05-01T00:00:10,1\n2024-05-01T00:01:10,1\n", name="u.csv")
    outputs = _write(
        tmp_path,
        "time,y\n2024-05-01T00:00:00,2\n2024-05-01T00:00:20,4\n2024-05-01T00:00:40,\n2024-05-01T00:01:00,8\n",
        name="y.csv",
    )
    data = load_csv(inputs, time="time", input="u", output="y", output_path=outputs, dt=10, max_gap=None)
    assert data.start == datetime.datetime(2024, 5, 1)
    np.testing.assert_allclose(data.time, [10, 20, 30, 40, 50, 60])
    # the gap runs from the last present value before the missing one to the first after it
    np.testing.assert_array_equal(data.y, [3, 4, np.nan, np.nan, np.nan, 8])
    assert data.notes[-1] == "1 output value missing, leaving 3 grid points NaN in y"
    assert "(dt given)" in data.notes[0]


def test_long_format_reads_each_tag_as_a_log(tmp_path):
    path = _write(
        tmp_path,
        "time,tag,value,unit\n"
        "2024-05-01T00:00:00Z,FIC101,1,%\n"
        "2024-05-01T00:00:00Z,TI204,20,degC\n"
        "2024-05-01T00:00:05Z,PI300,abc,bar\n"  # another tag: never parsed
        "2024-05-01T00:00:10Z,FIC101,3,%\n"
        "2024-05-01T00:00:20Z,TI204,22,degC\n"
        "2024-05-01T00:00:30Z,TI204,NA,degC\n"
        "2024-05-01T00:00:40Z,FIC101,,%\n"
        "2024-05-01T00:00:40Z,TI204,24,degC\n",
    )
    data = load_csv(path, time="time", input="FIC101", output="TI204", long_format=True)
    assert data.dt == 10.0
    np.testing.assert_allclose(data.time, [0, 10, 20, 30, 40])
    np.testing.assert_allclose(data.u, [1, 3, 3, 3, 3])  # the missing last value is held
    np.testing.assert_allclose(data.y, [20, 21, 22, np.nan, 24])
    assert data.start == datetime.datetime(2024, 5, 1, tzinfo=datetime.timezone.utc)
    assert data.notes[0] == "filled 1 missing input value by linear interpolation between the nearest present values"
    assert data.notes[1].startswith(
        f"resampled the input log (tag 'FIC101' of {path}, 3 rows) and the output log "
        f"(tag 'TI204' of {path}, 4 rows) onto a common 10 s grid"
    )


def test_long_format_with_other_column_names(tmp_path):
    path = _write(tmp_path, "t;name;v\n0;a;1\n0;b;2\n1;a;3\n2;b;6\n")
    data = load_csv(path, time="t", input="a", output="b", long_format=True, tag_column="name", value_column="v", dt=1)
    np.testing.assert_allclose(data.u, [1, 3])
    np.testing.assert_allclose(data.y, [2, 4])


def test_long_format_and_output_path_exclude_each_other(tmp_path):
    path = _write(tmp_path, "time,tag,value\n0,a,1\n1,a,2\n")
    with pytest.raises(SettingsError, match="do not give output_path"):
        load_csv(path, time="time", input="a", output="a", long_format=True, output_path=path)


@pytest.mark.skipif(not HEATING_SYSTEM.exists(), reason="the DaISy heating-system record is not available")
def test_the_daisy_heating_system_record(tmp_path):
    rows = [line.split() for line in HEATING_SYSTEM.read_text().splitlines() if line.strip()]
    path = _write(tmp_path, "time,voltage,temperature\n" + "".join(",".join(row) + "\n" for row in rows))
    data = load_csv(path, time="time", input="voltage", output="temperature")
    assert data.time.size == 801
    assert data.dt == 2.0
    assert data.u[0] == 9.0
    assert data.notes == () and not np.isnan(data.y).any()


_ROWS = "time,u,y\n0,1,2\n1,1,2\n"
_SIXTEEN_ROWS = "time,u,y\n" + "".join(f"{t},1,2\n" for t in range(15))
_LONG = {"long_format": True, "input": "a", "output": "b"}


@pytest.mark.parametrize(
    "text, kwargs, message",
    [
        ("", {}, r"data\.csv: the file is empty; expected a header row and at least 2 data rows$"),
        ("  \n\n \n", {}, r"data\.csv: the file is empty"),
        ("time,u,y\n", {}, r"data\.csv: the file has a header \(row 1\) but no data rows; expected at least 2$"),
        ("time,u,y\n\n,,\n", {}, r"the file has a header \(row 1\) but no data rows"),
        ("time,u,y\n0,1,2\n", {}, r"data\.csv: the file has only one data row \(row 2\); expected at least 2"),
        (
            _ROWS,
            {"output": "T"},
            r"data\.csv: row 1 \(the header\) has no column 'T' \(given as output\); "
            r"available columns: 'time', 'u', 'y'$",
        ),
        (_ROWS, {"time": "t"}, r"no column 't' \(given as time\); available columns: 'time', 'u', 'y'$"),
        (
            "0,1,2\n1,1,2\n2,1,2\n",
            {},
            r"row 1 \(the header\) has no column 'time' .* available columns: '0', '1', '2' "
            r"\(they are numbers: the file seems to lack a header row naming the columns\)$",
        ),
        ("time,u,y,y\n0,1,2,3\n1,1,2,3\n", {}, r"row 1 \(the header\) names 2 columns 'y'; expected one"),
        (
            _SIXTEEN_ROWS + "15,1,abc\n",
            {},
            r"data\.csv: row 17, column 'y': 'abc' is not a number; expected a number, "
            r"or an empty cell, NaN, NA or null where the value is missing$",
        ),
        ("time;u;y\n0;1,5;2\n1;1;2\n", {}, r"row 2, column 'u': '1,5' is not a number \(decimals need a point"),
        ("time,u,y\n0,1,2\n1,inf,2\n", {}, r"row 3, column 'u': 'inf' is not a finite number"),
        (
            "time,u,y\n0,1,2\n1,1,2\n1.0,1,2\n",
            {},
            r"row 4, column 'time': duplicate timestamp '1\.0', already on row 3; "
            r"expected strictly increasing times, or pass --duplicates mean \(duplicates='mean'\) to average",
        ),
        (
            "time,u,y\n2024-01-01T00:00:01,1,2\n2024-01-01T00:00:01.000,1,2\n",
            {},
            r"row 3, column 'time': duplicate timestamp",
        ),
        (
            "time,u,y\n0,1,2\n\n5,1,2\n3,1,2\n",
            {},
            r"row 5, column 'time': '3' is earlier than '5' on row 4; "
            r"expected strictly increasing times$",
        ),
        ("time,u,y\n0,1,2\ninf,1,2\n", {}, r"row 3, column 'time': 'inf' is not a finite time"),
        (
            "time,u,y\n-1e308,1,2\n1e308,1,2\n",
            {},
            r"row 3, column 'time': '1e308' is so far from '-1e308' on row 2 "
            r"that the seconds between them overflow",
        ),
        ("time,u,y\n0,1,2\n1,1," + "9" * 200_000 + "\n", {}, r"data\.csv: row 3 cannot be read as CSV \(field larger"),
        (
            "time,u,y\n0,1,2\n,1,2\n",
            {},
            r"row 3, column 'time': the time is missing \(''\); expected a number of seconds "
            r"or an ISO 8601 timestamp$",
        ),
        ("time,u,y\n0,1,2\nNaN,1,2\n", {}, r"row 3, column 'time': the time is missing \('NaN'\)"),
        (
            "time,u,y\n0,1,2\n01.02.2024 10:00,1,2\n",
            {},
            r"row 3, column 'time': '01\.02\.2024 10:00' is neither a "
            r"number of seconds nor an ISO 8601 timestamp",
        ),
        (
            "time,u,y\n0,1,2\n2024-01-01T00:00:00,1,2\n",
            {},
            r"row 3, column 'time': '2024-01-01T00:00:00' is a timestamp without UTC offset, but row 2 holds a number "
            r"of seconds \('0'\); expected one kind of time throughout$",
        ),
        (
            "time,u,y\n2024-01-01T00:00:00,1,2\n2024-01-01T00:00:01Z,1,2\n",
            {},
            r"row 3, column 'time': '2024-01-01T00:00:01Z' is a timestamp with UTC offset, but row 2 holds a "
            r"timestamp without UTC offset",
        ),
        (
            "time,u,y\n0,,2\n1,NA,2\n",
            {},
            r"data\.csv: column 'u' has no value in rows 2 to 3; expected at least one "
            r"number for the input$",
        ),
        (
            "time,u,y\n0,1,\n1,1,null\n",
            {},
            r"column 'y' has no value in rows 2 to 3; expected at least one number "
            r"for the output$",
        ),
        (
            "time,u,y\n0,1,2\n1,1,2,5\n",
            {},
            r"data\.csv: row 3 has 4 cells but the header \(row 1\) names 3 columns; "
            r"expected one cell per column",
        ),
        (
            _ROWS,
            {"dt": 5},
            r"data\.csv: dt = 5 s is longer than the 1 s the data span; expected a dt that leaves at least "
            r"2 grid points$",
        ),
        (
            _ROWS,
            {"dt": 1e-8},
            r"data\.csv: the grid would have 100 000 001 steps at dt = 1e-08 s over the 1 s the data "
            r"span \(limit 10 000 000\); pass a larger --dt / dt=$",
        ),
        (
            "time,tag,value\n0,a,1\n1,b,2\n2,a,3\n3,b,4\n",
            {**_LONG, "output": "c"},
            r"data\.csv: column 'tag' holds no tag 'c' \(given as output\) in rows 2 to 5; tags present: 'a', 'b'$",
        ),
        ("time,tag,value\n0,a,1\n1,b,2\n2,a,3\n", _LONG, r"data\.csv: tag 'b' has only one data row \(row 3\)"),
        (
            "time,tag,value\n0,a,1\n1,b,2\n2,a,3\n1,b,x\n",
            _LONG,
            r"row 5, column 'time': duplicate timestamp '1', "
            r"already on row 3",
        ),
        (
            "time,tag,value\n0,a,1\n1,b,2\n3,a,3\n2,a,4\n",
            _LONG,
            r"row 5, column 'time': '2' is earlier than '3' on row 4",
        ),
        ("time,tag,value\n0,a,1\n1,b,2\n2,a,3\n3,b,x\n", _LONG, r"row 5, column 'value': 'x' is not a number"),
        (
            "time,tag,value\n0,a,1\n1,a,2\n5,b,2\n6,b,4\n",
            _LONG,
            r"the output log \(tag 'b', 5 to 6\) does not overlap the input log \(tag 'a', 0 to 1\) of .*data\.csv in "
            r"time; expected a stretch where both have data$",
        ),
        (
            "time,tag,value\n0,a,1\n1,a,2\n2024-01-01T00:00:00,b,2\n2024-01-01T00:00:01,b,4\n",
            _LONG,
            r"row 4, column 'time': '2024-01-01T00:00:00' is a timestamp without UTC offset, but row 2 of .*data\.csv "
            r"\(tag 'a'\) holds a number of seconds \('0'\); expected one kind of time for both signals$",
        ),
    ],
)
def test_bad_input_is_one_line_naming_file_row_and_column(tmp_path, text, kwargs, message):
    path = _write(tmp_path, text)
    with pytest.raises(DataError, match=message) as caught:
        _load(path, **kwargs)
    assert str(caught.value).startswith(f"{path}: ")
    assert "\n" not in str(caught.value)


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(DataError, match=r"nowhere\.csv: no such file; expected a CSV file with a header row$"):
        _load(tmp_path / "nowhere.csv")
    with pytest.raises(DataError, match=r"nowhere\.csv: no such file"):
        _load(_write(tmp_path, _ROWS), output_path=tmp_path / "nowhere.csv")


def test_a_folder_is_not_a_file(tmp_path):
    with pytest.raises(DataError, match=r": cannot be read \(.*\); expected a CSV file$"):
        _load(tmp_path)


def test_one_column_for_both_signals_is_refused(tmp_path):
    """Issue 32: load_csv(input="y", output="y") was accepted, a record whose output is its own input."""
    with pytest.raises(SettingsError, match=r"^input and output both name the column 'y'; expected") as caught:
        load_csv(_write(tmp_path, _ROWS), time="time", input="y", output="y")
    assert caught.value.setting == "output"


@pytest.mark.parametrize("dt", [0, -1.0, math.nan, math.inf, "2", True])
def test_dt_must_be_a_finite_number_above_zero(tmp_path, dt):
    with pytest.raises(SettingsError, match=r"^dt must be a finite number of seconds > 0; got "):
        _load(_write(tmp_path, _ROWS), dt=dt)


@pytest.mark.parametrize("max_gap", [1, 0.5, 0, -3, math.nan, -math.inf, "5", True])
def test_max_gap_must_be_a_number_above_one_or_none(tmp_path, max_gap):
    with pytest.raises(
        SettingsError,
        match=r"^max_gap must be a number of grid steps > 1, or None to interpolate "
        r"across stretches without rows of any length; got ",
    ) as caught:
        _load(_write(tmp_path, _ROWS), max_gap=max_gap)
    assert caught.value.setting == "max_gap"


def test_errors_in_the_output_file_name_that_file(tmp_path):
    inputs = _write(tmp_path, "time,u\n0,1\n1,2\n", name="u.csv")
    outputs = _write(tmp_path, "stamp,y\n0,1\n1,2\n", name="y.csv")
    with pytest.raises(
        DataError,
        match=r"y\.csv: row 1 \(the header\) has no column 'time' \(given as time\); "
        r"available columns: 'stamp', 'y'$",
    ):
        _load(inputs, output_path=outputs)
    outputs = _write(tmp_path, "time,y\n2024-01-01T00:00:00Z,1\n2024-01-01T00:00:01Z,2\n", name="y.csv")
    with pytest.raises(
        DataError,
        match=r"y\.csv: row 2, column 'time': '2024-01-01T00:00:00Z' is a timestamp with "
        r"UTC offset, but row 2 of .*u\.csv \(column 'u'\) holds a number of seconds",
    ):
        _load(inputs, output_path=outputs)
    outputs = _write(tmp_path, "time,y\n0,1\n", name="y.csv")
    with pytest.raises(DataError, match=r"y\.csv: column 'y' has only one data row \(row 2\)"):
        _load(inputs, output_path=outputs)


# --- load_csv, properties -----------------------------------------------------

_FINITE = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    start=st.floats(-1e4, 1e4),
    spacing=st.floats(1e-3, 1e3),
    values=st.lists(st.tuples(_FINITE, st.none() | _FINITE), min_size=2, max_size=40).filter(
        lambda rows: any(output is not None for _, output in rows)
    ),
)
def test_a_uniform_numeric_csv_round_trips_exactly(tmp_path, start, spacing, values):
    u = np.array([value for value, _ in values])
    y = np.array([np.nan if value is None else value for _, value in values])
    times = start + spacing * np.arange(u.size)
    rows = "".join(
        f"{float(t)!r},{a!r},{'' if b is None else repr(b)}\n" for t, (a, b) in zip(times, values, strict=True)
    )
    data = _load(_write(tmp_path, "time,u,y\n" + rows))
    np.testing.assert_array_equal(data.u, u)
    np.testing.assert_array_equal(data.y, y)
    np.testing.assert_allclose(data.dt, spacing, rtol=1e-6)
    np.testing.assert_array_equal(data.time, data.dt * np.arange(u.size))
    missing = int(np.isnan(y).sum())
    assert data.notes == (
        (f"{missing} output value{'s' * (missing != 1)} missing, left as NaN in y",) if missing else ()
    )


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    gaps=st.lists(st.integers(1, 5_000_000), min_size=1, max_size=30),  # microseconds, up to 5 s
    slopes=st.tuples(st.floats(-10, 10), st.floats(-10, 10)),
    offsets=st.tuples(_FINITE, _FINITE),
    dt=st.floats(0.01, 2.0),
    zone=st.sampled_from(["", "Z", "+05:30", "-08:00"]),
)
def test_irregular_timestamps_of_a_linear_signal_resample_exactly(tmp_path, gaps, slopes, offsets, dt, zone):
    first = datetime.datetime(2024, 5, 1, 12, 0, 0)
    seconds = np.r_[0, np.cumsum(gaps)] / 1e6
    stamps = [
        (first + datetime.timedelta(microseconds=int(micro))).isoformat(timespec="microseconds") + zone
        for micro in np.r_[0, np.cumsum(gaps)]
    ]
    (slope_u, slope_y), (offset_u, offset_y) = slopes, offsets
    rows = "".join(
        f"{stamp},{float(offset_u + slope_u * t)!r},{float(offset_y + slope_y * t)!r}\n"
        for stamp, t in zip(stamps, seconds, strict=True)
    )
    if seconds[-1] < dt:
        dt = seconds[-1]  # the grid needs two points
    data = _load(_write(tmp_path, "time,u,y\n" + rows), dt=dt, max_gap=None)
    assert data.time[0] == 0 and data.time[-1] <= seconds[-1]
    np.testing.assert_allclose(np.diff(data.time), dt, rtol=1e-9)
    scale = 1 + abs(offset_u) + abs(offset_y)
    np.testing.assert_allclose(data.u, offset_u + slope_u * data.time, rtol=1e-12, atol=1e-9 * scale)
    np.testing.assert_allclose(data.y, offset_y + slope_y * data.time, rtol=1e-12, atol=1e-9 * scale)
    assert data.start.replace(tzinfo=None) == first
    assert (data.start.utcoffset() is None) == (zone == "")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(missing=st.lists(st.booleans(), min_size=2, max_size=30).filter(lambda flags: not all(flags)))
def test_halving_the_spacing_puts_nan_next_to_every_missing_output(tmp_path, missing):
    missing = np.array(missing)
    rows = "".join(f"{2 * k},{k},{'' if gone else k}\n" for k, gone in enumerate(missing))
    data = _load(_write(tmp_path, "time,u,y\n" + rows), dt=1)
    on_rows, between = np.isnan(data.y[0::2]), np.isnan(data.y[1::2])
    np.testing.assert_array_equal(on_rows, missing)
    np.testing.assert_array_equal(between, missing[:-1] | missing[1:])
    present = ~np.isnan(data.y)
    np.testing.assert_allclose(data.y[present], data.time[present] / 2)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_long_table_reads_as_the_same_two_logs_in_two_files(tmp_path, data):
    times_u = np.cumsum(data.draw(st.lists(st.integers(1, 9), min_size=2, max_size=15)))
    times_y = np.cumsum(data.draw(st.lists(st.integers(1, 9), min_size=2, max_size=15)))
    if max(times_u[0], times_y[0]) >= min(times_u[-1], times_y[-1]):
        times_y = times_y - times_y[0] + times_u[0]
    records = [(t, "in", float(k)) for k, t in enumerate(times_u)] + [
        (t, "out", -3.0 * k) for k, t in enumerate(times_y)
    ]
    order = data.draw(st.permutations(range(len(records))))
    by_time = sorted(order, key=lambda index: records[index][0])  # sorted by time, ties in random tag order
    long = _write(tmp_path, "time,tag,value\n" + "".join("{},{},{}\n".format(*records[i]) for i in by_time), "long.csv")
    inputs = _write(tmp_path, "time,u\n" + "".join(f"{t},{k}\n" for k, t in enumerate(times_u)), "u.csv")
    outputs = _write(tmp_path, "time,y\n" + "".join(f"{t},{-3.0 * k}\n" for k, t in enumerate(times_y)), "y.csv")
    from_long = load_csv(long, time="time", input="in", output="out", long_format=True)
    from_files = _load(inputs, output_path=outputs)
    for name in ("time", "u", "y"):
        np.testing.assert_array_equal(getattr(from_long, name), getattr(from_files, name))
    assert from_long.dt == from_files.dt


# Streams and repeated timestamps (issue 12).


def test_a_text_or_binary_stream_reads_like_the_file(tmp_path):
    text = "time;u;y\n0;1;0.5\n2;1;0.75\n4;2;\n6;2;1.25\n"
    from_file = _load(_write(tmp_path, text))
    for stream in (io.StringIO(text), io.BytesIO(text.encode()), io.BytesIO(b"\xef\xbb\xbf" + text.encode())):
        data = _load(stream)
        assert data.dt == from_file.dt == 2.0 and data.notes == from_file.notes
        for name in ("time", "u", "y"):
            np.testing.assert_array_equal(getattr(data, name), getattr(from_file, name))


def test_a_binary_stream_that_is_not_utf8_is_read_as_windows_1252():
    data = load_csv(
        io.BytesIO("time,u,T \u00b0C\n0,1,20\n1,1,21\n".encode("cp1252")), time="time", input="u", output="T \u00b0C"
    )
    assert data.y.tolist() == [20.0, 21.0]
    assert data.notes == ("read <stream> as Windows-1252 text, since it is not valid UTF-8",)


def test_errors_in_a_stream_name_it(tmp_path):
    with pytest.raises(DataError, match=r"^<stream>: row 3, column 'y': 'abc' is not a number; "):
        _load(io.StringIO("time,u,y\n0,1,2\n1,1,abc\n"))
    named = io.StringIO("time,u\n0,1\n1,1\n")
    named.name = "plant/loop7.csv"
    with pytest.raises(DataError, match=r"^plant/loop7\.csv: row 1 \(the header\) has no column 'y'"):
        _load(named)
    with open(_write(tmp_path, "time,u,y\n0,1,2\n0,1,2\n"), encoding="utf-8") as handle:
        with pytest.raises(DataError, match=r"data\.csv: row 3, column 'time': duplicate timestamp '0'"):
            _load(handle)
    closed = io.StringIO(_ROWS)
    closed.close()
    with pytest.raises(DataError, match=r"^<stream>: cannot be read \(I/O operation on closed file\.?\); "):
        _load(closed)


def test_two_event_logs_from_streams():
    inputs = io.StringIO("time,u\n0,0\n4,4\n")
    outputs = io.BytesIO(b"time,y\n0,10\n2,12\n4,14\n")
    data = _load(inputs, output_path=outputs)
    assert data.time.tolist() == [0.0, 2.0, 4.0] and data.u.tolist() == [0.0, 2.0, 4.0]
    assert data.y.tolist() == [10.0, 12.0, 14.0]
    assert data.notes[0].startswith(
        "resampled the input log (column 'u' of <stream>, 2 rows) and the output log (column 'y' of <stream>, 3 rows)"
    )


def test_repeated_timestamps_average_per_signal_ignoring_missing_values(tmp_path):
    text = "time,u,y\n0,1,10\n1,2,\n1,4,11\n1,,13\n2,5,\n2,7,\n3,1,1\n"
    with pytest.raises(DataError, match=r"row 4, column 'time': duplicate timestamp '1', already on row 3"):
        _load(_write(tmp_path, text))
    data = _load(_write(tmp_path, text), duplicates="mean")
    assert data.time.tolist() == [0.0, 1.0, 2.0, 3.0] and data.dt == 1.0
    assert data.u.tolist() == [1.0, 3.0, 6.0, 1.0]  # (2 + 4) / 2 with the empty cell left out; (5 + 7) / 2
    assert np.array_equal(data.y, [10.0, 12.0, np.nan, 1.0], equal_nan=True)  # no value at time 2: missing
    assert data.notes == (
        "5 rows with repeated timestamps averaged into 2 rows",
        "1 output value missing, left as NaN in y",
    )


def test_repeated_timestamps_average_exactly():
    values = [0.1, 0.2, 0.7, 1e-17]
    text = "time,u,y\n" + "".join(f"5,1,{value!r}\n" for value in values) + "6,1,0\n7,1,0\n"
    data = _load(io.StringIO(text), duplicates="mean")
    assert data.y[0] == np.nanmean(values) == (0.1 + 0.2 + 0.7 + 1e-17) / 4
    assert data.time.tolist() == [0.0, 1.0, 2.0]


def test_repeated_timestamps_average_in_each_tag_of_a_long_table():
    text = "time,tag,value\n0,a,1\n0,b,10\n2,a,2\n2,a,5\n2,b,20\n4,a,6\n4,b,30\n4,b,31\n"
    data = load_csv(io.StringIO(text), time="time", input="a", output="b", long_format=True, duplicates="mean")
    assert data.time.tolist() == [0.0, 2.0, 4.0]
    assert data.u.tolist() == [1.0, 3.5, 6.0] and data.y.tolist() == [10.0, 20.0, 30.5]
    assert data.notes[:2] == (
        "2 rows with repeated timestamps averaged into 1 row (tag 'a' of <stream>)",
        "2 rows with repeated timestamps averaged into 1 row (tag 'b' of <stream>)",
    )


def test_repeated_timestamps_still_need_increasing_times_and_two_of_them(tmp_path):
    with pytest.raises(DataError, match=r"row 5, column 'time': '0' is earlier than '1' on row 4"):
        _load(_write(tmp_path, "time,u,y\n0,1,2\n1,1,2\n1,1,2\n0,1,2\n"), duplicates="mean")
    with pytest.raises(
        DataError, match=r"data\.csv: the file has 3 rows \(rows 2 to 4\) but all at one time '7'; expected at least 2"
    ):
        _load(_write(tmp_path, "time,u,y\n7,1,2\n7,1,2\n7.0,1,2\n"), duplicates="mean")


@pytest.mark.parametrize("duplicates", ["first", "Mean", None, True])
def test_duplicates_must_be_error_or_mean(duplicates):
    with pytest.raises(SettingsError, match=r"^duplicates must be one of 'error', 'mean'; got ") as caught:
        _load(io.StringIO(_ROWS), duplicates=duplicates)
    assert caught.value.setting == "duplicates"
