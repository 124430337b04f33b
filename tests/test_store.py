"""dynia.io.netcdf: DyniaResult to xarray and netCDF and back, exact to the bit; timestamps in tables and plots."""

import dataclasses
import json

import matplotlib
import numpy as np
import pytest

import dynia
from dynia.cli.report import write_analysis
from dynia.errors import DataError, OutputError, SettingsError
from dynia.io.csv import ProcessData
from dynia.io.frames import unpack
from dynia.models import FirstOrder

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import dates  # noqa: E402

ARRAYS = ("samples", "bounds", "time", "ic", "ci", "median", "gradient", "bin_centres")
BOUNDS = {"K": (0, 7), "T": (0, 7)}


def _record(steps=120, seed=3):
    rng = np.random.default_rng(seed)
    u = np.r_[np.zeros(20), np.full(40, 1.0), np.full(steps - 60, 0.3)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + rng.normal(0, 0.05, steps)
    return u, y


@pytest.fixture(scope="module")
def thesis_result():
    u, y = _record()
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=6, n_samples=400, flavour="thesis", rng=1)


@pytest.fixture(scope="module")
def adaptive_result():
    u, y = _record()
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=6, n_samples=600, sampler="iis", percentage=5, rng=2)


@pytest.fixture(scope="module")
def nan_result():
    u, y = _record()
    y = y.copy()
    y[50:80] = np.nan
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=4, n_samples=300, min_points=5, rng=4)


def _stamps(steps):
    # An odd nanosecond offset: a writer that rounded to microseconds or seconds would lose it.
    return np.datetime64("2024-03-31T00:59:58.123456789", "ns") + np.arange(steps) * np.timedelta64(15, "s")


def _round_trip(result, tmp_path):
    path = tmp_path / "result.nc"
    result.save(path)
    return dynia.load(path)


def _assert_identical(back, result):
    for name in ARRAYS:
        before, after = getattr(result, name), getattr(back, name)
        assert after.dtype == before.dtype and after.shape == before.shape, name
        assert after.tobytes() == before.tobytes(), name
    assert back.names == result.names and type(back.names) is tuple
    assert back.verdicts == result.verdicts


def _same_settings(back, result):
    """Equal, and every nested value of the same type (a tuple stays a tuple, an int an int)."""

    def walk(a, b, where):
        assert type(a) is type(b), where
        if isinstance(a, dict):
            assert list(a) == list(b), where
            for key in a:
                walk(a[key], b[key], f"{where}[{key!r}]")
        elif isinstance(a, (list, tuple)):
            assert len(a) == len(b), where
            for index, (x, y) in enumerate(zip(a, b)):
                walk(x, y, f"{where}[{index}]")
        elif isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), where
        else:
            assert a == b or (a != a and b != b), where

    walk(back.settings, result.settings, "settings")


def test_a_thesis_run_comes_back_bit_for_bit(thesis_result, tmp_path):
    back = _round_trip(thesis_result, tmp_path)
    _assert_identical(back, thesis_result)
    _same_settings(back, thesis_result)
    assert type(back.settings["bounds"]["K"]) is tuple and back.settings["flavour"] == "thesis"
    assert back.timestamps is None
    assert back.summary() == thesis_result.summary()


def test_an_adaptive_run_keeps_its_weights_as_a_variable(adaptive_result, tmp_path):
    weights = adaptive_result.settings["weights"]
    assert isinstance(weights, np.ndarray) and weights.size == adaptive_result.samples.shape[0]
    dataset = adaptive_result.to_xarray()
    assert dataset["weights"].dims == ("sample",)
    assert json.loads(dataset.attrs["settings"])["weights"] == {"__variable__": "weights"}
    back = _round_trip(adaptive_result, tmp_path)
    _assert_identical(back, adaptive_result)
    _same_settings(back, adaptive_result)
    assert back.settings["weights"].tobytes() == weights.tobytes()


def test_missing_ic_stays_nan(nan_result, tmp_path):
    missing = np.isnan(nan_result.ic)
    assert missing.any() and not missing.all()
    back = _round_trip(nan_result, tmp_path)
    _assert_identical(back, nan_result)
    assert np.array_equal(np.isnan(back.ic), missing)
    assert np.isnan(back.ci).sum() == np.isnan(nan_result.ci).sum() > 0


def test_timestamps_come_back_to_the_nanosecond(thesis_result, tmp_path):
    stamps = _stamps(thesis_result.time.size)
    stamped = dataclasses.replace(thesis_result, timestamps=stamps)
    back = _round_trip(stamped, tmp_path)
    _assert_identical(back, stamped)
    assert back.timestamps.dtype == np.dtype("datetime64[ns]")
    assert back.timestamps.view(np.int64).tolist() == stamps.view(np.int64).tolist()


def test_a_run_fed_from_pandas_keeps_its_timestamps(tmp_path):
    pd = pytest.importorskip("pandas")
    u, y = _record(80)
    index = pd.date_range("2024-10-27 00:30", periods=80, freq="1min", tz="Europe/Berlin")
    u, y, dt, stamps = unpack(pd.Series(u, index), pd.DataFrame({"y": y}, index))
    result = dynia.run(u, y, FirstOrder(), BOUNDS, n=4, n_samples=200, dt=dt, rng=5)
    result = dataclasses.replace(result, timestamps=stamps)
    back = _round_trip(result, tmp_path)
    assert back.settings["dt"] == 60.0
    assert str(back.timestamps[0]) == "2024-10-26T22:30:00.000000000"
    assert np.array_equal(back.timestamps, index.tz_convert("UTC").tz_localize(None).to_numpy())


def test_to_xarray_labels_every_axis(thesis_result):
    stamps = _stamps(thesis_result.time.size)
    dataset = dataclasses.replace(thesis_result, timestamps=stamps).to_xarray()
    n_params, n_bins, n_steps = thesis_result.gradient.shape
    assert dataset["ic"].dims == ("parameter", "time")
    assert dataset["ci"].dims == ("parameter", "time", "side")
    assert dataset["gradient"].dims == ("parameter", "bin", "time")
    assert dataset["bin_centres"].dims == ("parameter", "bin")
    assert dataset["samples"].dims == ("sample", "parameter")
    assert dataset["bounds"].dims == ("parameter", "side")
    assert dict(dataset.sizes) == {
        "parameter": n_params,
        "time": n_steps,
        "side": 2,
        "bin": n_bins,
        "sample": thesis_result.samples.shape[0],
    }
    assert dataset["parameter"].values.tolist() == ["K", "T"]
    assert dataset["side"].values.tolist() == ["lower", "upper"]
    assert np.array_equal(dataset["time"].values, thesis_result.time)
    assert dataset["timestamp"].dims == ("time",) and np.array_equal(dataset["timestamp"].values, stamps)
    upper_t = dataset["ci"].sel(parameter="T", side="upper").values
    assert np.array_equal(upper_t, thesis_result.ci[1, :, 1], equal_nan=True)
    assert dataset["bounds"].sel(parameter="K").values.tolist() == [0.0, 7.0]
    settings = json.loads(dataset.attrs["settings"])
    assert settings["bounds"]["K"] == {"__tuple__": [0.0, 7.0]} and settings["n"] == 6
    assert json.loads(dataset.attrs["verdicts"]) == thesis_result.verdicts
    assert dataset.attrs["dynia_result"] == dynia.io.netcdf.FORMAT_VERSION
    assert "timestamp" not in thesis_result.to_xarray().variables


def test_settings_keep_tuples_lists_and_scalar_types(thesis_result, tmp_path):
    settings = {
        "nested": {"pairs": [(1, 2.5), [3, None]], "flag": True, "empty": (), "nan": float("nan")},
        "count": np.int64(7),
        "share": np.float64(0.25),
        "grid": np.arange(6, dtype=np.int32).reshape(2, 3),
        "label": "Kühler",
    }
    result = dataclasses.replace(thesis_result, settings=settings, verdicts=None)
    back = _round_trip(result, tmp_path)
    assert back.verdicts is None
    nested = back.settings["nested"]
    assert nested["pairs"] == [(1, 2.5), [3, None]] and type(nested["pairs"][0]) is tuple
    assert type(nested["pairs"][1]) is list and nested["empty"] == () and nested["flag"] is True
    assert np.isnan(nested["nan"])
    assert back.settings["count"] == 7 and type(back.settings["count"]) is int
    assert back.settings["share"] == 0.25 and type(back.settings["share"]) is float
    assert back.settings["grid"].dtype == np.int32 and back.settings["grid"].tolist() == [[0, 1, 2], [3, 4, 5]]
    assert back.settings["label"] == "Kühler"
    assert result.to_xarray()["grid"].dims == ("grid_dim_0", "grid_dim_1")


@pytest.mark.parametrize(
    "settings, setting, message",
    [
        ({"when": object()}, "when", r"result\.settings\['when'\] holds a value of type object, which cannot be saved"),
        ({"deep": {"x": [1, {2}]}}, "deep", r"result\.settings\['deep'\]\['x'\]\[1\] holds a value of type set"),
        ({"map": {1: "a"}}, "map", r"result\.settings\['map'\] has the key 1; only str keys"),
        (
            {"ic": np.zeros(3)},
            "ic",
            r"result\.settings\['ic'\] is an array, .* but the result has a variable 'ic' of its own",
        ),
    ],
)
def test_settings_that_cannot_be_saved_are_named(thesis_result, tmp_path, settings, setting, message):
    result = dataclasses.replace(thesis_result, settings=settings)
    with pytest.raises(SettingsError, match=message) as caught:
        result.save(tmp_path / "result.nc")
    assert caught.value.setting == setting
    assert not (tmp_path / "result.nc").exists()


def test_load_names_what_it_cannot_read(thesis_result, tmp_path):
    with pytest.raises(DataError, match=r"missing\.nc: no such file; expected a netCDF file"):
        dynia.load(tmp_path / "missing.nc")
    (tmp_path / "text.nc").write_text("time,u,y\n")
    with pytest.raises(DataError, match=r"text\.nc: cannot be read as netCDF-4"):
        dynia.load(tmp_path / "text.nc")
    foreign = thesis_result.to_xarray()
    del foreign.attrs["dynia_result"]
    foreign.to_netcdf(tmp_path / "foreign.nc", engine="h5netcdf")
    with pytest.raises(DataError, match=r"foreign\.nc: no dynia_result attribute; expected a result"):
        dynia.load(tmp_path / "foreign.nc")
    foreign.attrs["dynia_result"] = dynia.io.netcdf.FORMAT_VERSION + 1
    foreign.to_netcdf(tmp_path / "newer.nc", engine="h5netcdf")
    with pytest.raises(DataError, match=r"newer\.nc: format version 2; expected"):
        dynia.load(tmp_path / "newer.nc")
    partial = thesis_result.to_xarray().drop_vars("gradient")
    partial.to_netcdf(tmp_path / "partial.nc", engine="h5netcdf")
    with pytest.raises(DataError, match=r"partial\.nc: has no 'gradient'; expected every part of a saved result$"):
        dynia.load(tmp_path / "partial.nc")


def test_save_into_a_missing_folder_is_an_output_error(thesis_result, tmp_path):
    with pytest.raises(OutputError, match=r"no_folder.result\.nc: cannot be written"):
        thesis_result.save(tmp_path / "no_folder" / "result.nc")


def test_write_analysis_writes_result_nc(thesis_result, tmp_path):
    steps = thesis_result.time.size
    data = ProcessData(time=thesis_result.time, u=np.zeros(steps), y=np.zeros(steps), dt=1.0, start=0.0, notes=())
    write_analysis(tmp_path, thesis_result, data, {"parameters": {}}, plots=False)
    back = dynia.load(tmp_path / "result.nc")
    _assert_identical(back, thesis_result)
    _same_settings(back, thesis_result)


def test_to_dataframe_carries_the_timestamps(thesis_result):
    pytest.importorskip("pandas")
    stamps = _stamps(thesis_result.time.size)
    table = dataclasses.replace(thesis_result, timestamps=stamps).to_dataframe()
    assert list(table.columns) == ["time", "timestamp", "parameter", "ic", "lower", "upper", "median", "informative"]
    assert table["timestamp"].to_numpy().tolist() == np.tile(stamps, 2).tolist()
    assert "timestamp" not in thesis_result.to_dataframe().columns


@pytest.mark.parametrize("kind", ["plot_information_content", "plot_identifiability"])
def test_plots_draw_against_the_timestamps(thesis_result, kind):
    stamps = _stamps(thesis_result.time.size)
    stamped = dataclasses.replace(thesis_result, timestamps=stamps)
    fig, ax = plt.subplots()
    try:
        getattr(stamped, kind)("K", ax=ax)
        numbers = dates.date2num(stamps)
        assert ax.get_xlim() == (numbers[0], numbers[-1])
        assert np.array_equal(ax.lines[0].get_xdata(), numbers)
        assert isinstance(ax.xaxis.get_major_formatter(), dates.AutoDateFormatter)
    finally:
        plt.close(fig)
    fig, ax = plt.subplots()
    try:
        getattr(thesis_result, kind)("K", ax=ax)
        assert ax.get_xlim() == (thesis_result.time[0], thesis_result.time[-1])
        assert not isinstance(ax.xaxis.get_major_formatter(), dates.AutoDateFormatter)
    finally:
        plt.close(fig)
