"""dynia.io.frames.unpack: pandas Series and DataFrames in, arrays, dt and UTC timestamps out."""

import subprocess
import sys

import numpy as np
import pytest

from dynia.errors import DataError, SettingsError
from dynia.io.frames import unpack

pd = pytest.importorskip("pandas")


def _index(periods=6, freq="10s", **kwargs):
    return pd.date_range("2024-05-01 12:00", periods=periods, freq=freq, **kwargs)


def test_numpy_arrays_come_back_untouched():
    u, y = np.arange(5.0), np.ones(5)
    out_u, out_y, dt, stamps = unpack(u, y, dt=2.5)
    assert out_u is u and out_y is y and dt == 2.5 and stamps is None
    lists = [1, 2, 3]
    assert unpack(lists, lists) == (lists, lists, None, None)


@pytest.mark.parametrize("labels", [None, ["a", "b", "c"]])
def test_series_without_a_time_index_give_their_values_only(labels):
    # pandas' default RangeIndex, or text labels, shared by u and y: no time, the values in order.
    u = pd.Series([1, 2, 3], index=labels)
    y = pd.Series([0.5, np.nan, 0.7], index=labels)
    out_u, out_y, dt, stamps = unpack(u, y, dt=3.0)
    assert out_u.dtype == float and out_u.tolist() == [1.0, 2.0, 3.0]
    assert np.array_equal(out_y, [0.5, np.nan, 0.7], equal_nan=True)
    assert dt == 3.0 and stamps is None


def test_a_uniform_datetime_index_gives_dt_and_timestamps():
    index = _index()
    u, y, dt, stamps = unpack(pd.Series(np.arange(6.0), index), pd.DataFrame({"T_out": np.arange(6.0) / 2}, index))
    assert u.tolist() == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0] and y.tolist() == [0.0, 0.5, 1.0, 1.5, 2.0, 2.5]
    assert dt == 10.0 and type(dt) is float
    assert stamps.dtype == np.dtype("datetime64[ns]")
    assert np.array_equal(stamps, np.datetime64("2024-05-01T12:00:00", "ns") + np.arange(6) * np.timedelta64(10, "s"))


def test_a_coarser_index_unit_becomes_nanoseconds():
    index = _index(periods=3, freq="250ms").as_unit("ms")
    _, _, dt, stamps = unpack(pd.Series([1.0, 2, 3], index), pd.Series([1.0, 2, 3], index))
    assert dt == 0.25 and stamps.dtype == np.dtype("datetime64[ns]")
    assert str(stamps[1]) == "2024-05-01T12:00:00.250000000"


def test_a_given_dt_that_agrees_is_kept():
    index = _index()
    _, _, dt, _ = unpack(pd.Series(np.ones(6), index), pd.Series(np.ones(6), index), dt=10)
    assert dt == 10 and type(dt) is int


def test_a_dataframe_u_holds_one_input_per_column_in_order():
    index = _index(periods=4)
    frame = pd.DataFrame({"valve": [0.0, 1, 1, 1], "load": [5.0, 5, 6, 7]}, index)
    u, y, dt, stamps = unpack(frame, pd.Series([1.0, 1.1, 1.2, 1.3], index))
    assert u.shape == (4, 2)
    assert u[:, 0].tolist() == [0.0, 1.0, 1.0, 1.0] and u[:, 1].tolist() == [5.0, 5.0, 6.0, 7.0]
    one = pd.DataFrame({"valve": [0.0, 1, 1, 1]}, index)
    assert unpack(one, pd.Series(np.ones(4), index))[0].shape == (4,)


def test_a_numpy_u_with_a_dated_y_takes_y_index():
    index = _index(periods=3)
    u = np.array([1.0, 2.0, 3.0])
    out_u, y, dt, stamps = unpack(u, pd.Series([4.0, 5.0, 6.0], index))
    assert out_u is u and y.tolist() == [4.0, 5.0, 6.0] and dt == 10.0 and stamps.size == 3


def test_a_timezone_aware_index_becomes_utc():
    # Across the end of daylight saving time in Berlin: local clock times repeat, UTC ones do not.
    index = pd.date_range("2024-10-27 00:30", periods=6, freq="30min", tz="Europe/Berlin")
    _, _, dt, stamps = unpack(pd.Series(np.ones(6), index), pd.Series(np.ones(6), index))
    assert dt == 1800.0
    assert [str(stamp)[:16] for stamp in stamps] == [
        "2024-10-26T22:30",
        "2024-10-26T23:00",
        "2024-10-26T23:30",
        "2024-10-27T00:00",
        "2024-10-27T00:30",
        "2024-10-27T01:00",
    ]


def test_a_nanosecond_rounded_index_still_counts_as_uniform():
    for unit in ("ns", "us", "ms"):
        # Steps of 333333333 and 333333334 ns, of 333333 and 333334 us, of 333 and 334 ms.
        index = pd.date_range("2024-05-01", "2024-05-01 00:00:01", periods=4, unit=unit)
        _, _, dt, _ = unpack(pd.Series(np.ones(4), index), pd.Series(np.ones(4), index))
        assert dt == 1 / 3
    index = pd.DatetimeIndex(["2024-05-01 00:00:00", "2024-05-01 00:00:00.333", "2024-05-01 00:00:00.667"])
    with pytest.raises(DataError, match=r"from position 1 .* is 0\.334 s, but from 0 to 1 0\.333 s"):
        unpack(pd.Series(np.ones(3), index.as_unit("ns")), pd.Series(np.ones(3), index.as_unit("ns")))


def test_a_non_uniform_index_is_named_where():
    index = pd.DatetimeIndex(
        ["2024-05-01 12:00:00", "2024-05-01 12:00:10", "2024-05-01 12:00:20", "2024-05-01 12:00:35"]
    )
    with pytest.raises(DataError) as caught:
        unpack(pd.Series(np.ones(4), index), pd.Series(np.ones(4), index))
    assert str(caught.value) == (
        "the index of u and y is not uniformly spaced: from position 2 (2024-05-01T12:00:20.000000000) to 3 "
        "(2024-05-01T12:00:35.000000000) is 15 s, but from 0 to 1 10 s; "
        "dynia.io.csv.resample_events or dynia.io.csv.load_csv make a uniform grid"
    )


@pytest.mark.parametrize(
    "times, message",
    [
        (
            ["2024-05-01 12:00:00", "2024-05-01 12:00:10", "2024-05-01 12:00:10"],
            r"^the index of y must strictly increase: position 2 \(2024-05-01T12:00:10\.000000000\) repeats "
            r"position 1 .*average or drop repeated times$",
        ),
        (
            ["2024-05-01 12:00:00", "2024-05-01 12:00:10", "2024-05-01 12:00:05"],
            r"^the index of y must strictly increase: position 2 \(2024-05-01T12:00:05\.000000000\) is earlier "
            r"than position 1 \(2024-05-01T12:00:10\.000000000\); sort it",
        ),
        (["2024-05-01 12:00:00", None, "2024-05-01 12:00:05"], r"^the index of y has no time \(NaT\) at position 1;"),
    ],
)
def test_an_index_that_does_not_increase_is_a_data_error(times, message):
    with pytest.raises(DataError, match=message):
        unpack(np.ones(3), pd.Series(np.ones(3), pd.DatetimeIndex(times)))


def test_u_and_y_on_different_indexes_name_both():
    with pytest.raises(DataError) as caught:
        unpack(pd.Series(np.ones(6), _index()), pd.Series(np.ones(6), _index(freq="20s")))
    assert str(caught.value) == (
        "u and y must share one index, or their values would be paired by position: u's is DatetimeIndex of 6 "
        "from 2024-05-01 12:00:00 to 2024-05-01 12:00:50, y's DatetimeIndex of 6 from 2024-05-01 12:00:00 to "
        "2024-05-01 12:01:40; align them first (e.g. u.reindex(y.index)), pass both on one DataFrame's index, "
        "or pass numpy arrays (u.to_numpy()) with dt"
    )
    with pytest.raises(DataError, match=r"^u and y must share one index, .* u's is RangeIndex of 6 from 0 to 5"):
        unpack(pd.Series(np.ones(6)), pd.Series(np.ones(6), _index()))


def test_a_dt_that_disagrees_is_a_settings_error():
    index = _index()
    with pytest.raises(SettingsError) as caught:
        unpack(pd.Series(np.ones(6), index), pd.Series(np.ones(6), index), dt=1.0)
    assert caught.value.setting == "dt"
    assert str(caught.value) == (
        "dt = 1 s disagrees with the 10 s spacing of the index of u and y; leave dt out to use the index's"
    )
    with pytest.raises(SettingsError, match=r"^dt must be a finite number of seconds; got '10'$"):
        unpack(pd.Series(np.ones(6), index), pd.Series(np.ones(6), index), dt="10")


def test_a_y_of_several_columns_or_of_text_is_a_data_error():
    frame = pd.DataFrame({"a": [1.0, 2.0], "b": [3.0, 4.0]})
    with pytest.raises(DataError, match=r"^y must be a Series or a DataFrame of one column .* 2 columns \['a', 'b'\]$"):
        unpack(np.ones(2), frame)
    with pytest.raises(DataError, match=r"^u must hold numbers: "):
        unpack(pd.Series(["on", "off"]), np.ones(2))


def test_a_nullable_missing_value_becomes_nan():
    y = pd.Series([1.5, None, 2.5], dtype="Float64")
    assert np.array_equal(unpack(np.ones(3), y)[1], [1.5, np.nan, 2.5], equal_nan=True)


def test_the_result_feeds_dynia_run():
    import dynia

    index = _index(periods=60, freq="1min")
    u = np.r_[np.zeros(10), np.ones(50)]
    y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u, dt=60.0)[0]
    u, y, dt, stamps = unpack(pd.DataFrame({"u": u}, index), pd.Series(y, index))
    result = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 5), "T": (0, 500)}, dt=dt, n=4, n_samples=100, rng=1)
    assert result.settings.dt == 60.0 and result.time[-1] == 59 * 60.0 and stamps.size == result.time.size


def test_numpy_input_needs_no_pandas():
    # A child interpreter in which pandas cannot be imported, as when it is not installed.
    code = (
        "import sys\n"
        "class NoPandas:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] == 'pandas':\n"
        "            raise ImportError('pandas is not installed')\n"
        "sys.meta_path.insert(0, NoPandas())\n"
        "import numpy as np\n"
        "from dynia.io.frames import unpack\n"
        "out = unpack(np.ones(3), [1.0, 2.0, 3.0], 1.0)\n"
        "print('pandas' in sys.modules, out[1], out[2], out[3])\n"
    )
    found = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert found.stdout.split() == ["False", "[1.0,", "2.0,", "3.0]", "1.0", "None"]
