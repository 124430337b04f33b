"""dynia.io.writer and dynia.io.reader: DyniaResult to xarray and netCDF and back, exact to the bit; timestamps too."""

import dataclasses
import json

import h5py
import matplotlib
import numpy as np
import pytest
from conftest import stored_record

import dynia
from dynia.cli.report import write_analysis
from dynia.errors import DataError, OutputError, SettingsError
from dynia.io.csv import ProcessData
from dynia.io.frames import unpack
from dynia.io.layout import TIMESTAMP_UNITS
from dynia.models import FirstOrder
from dynia.settings import AnalysisSettings, RunRecord
from dynia.verdicts import high_ic_windows, reported_step

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import dates  # noqa: E402

ARRAYS = ("samples", "bounds", "time", "ic", "ci", "median", "gradient", "bin_centres")
BOUNDS = {"K": (0, 7), "T": (0, 7)}


@pytest.fixture(scope="module")
def thesis_result():
    u, y = stored_record()
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=6, n_samples=400, flavour="thesis", rng=1)


@pytest.fixture(scope="module")
def adaptive_result():
    u, y = stored_record()
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=6, n_samples=600, sampler="iis", percentage=5, rng=2)


@pytest.fixture(scope="module")
def nan_result():
    u, y = stored_record()
    y = y.copy()
    y[50:80] = np.nan
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=4, n_samples=300, min_points=5, rng=4)


def _stamps(time):
    """Dates of steps ``time`` seconds apart (dates must agree with the seconds), from an odd nanosecond: a writer
    that rounded to microseconds or seconds would lose it."""
    return np.datetime64("2024-03-31T00:59:58.123456789", "ns") + np.round(time * 1e9).astype("timedelta64[ns]")


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
    """The same settings and run record, each field of the same type (an int stays an int, a tuple a tuple)."""
    assert isinstance(back.settings, AnalysisSettings) and isinstance(back.run, RunRecord)
    assert back.settings == result.settings and back.run == result.run
    for before, after in ((result.settings, back.settings), (result.run, back.run)):
        for field in dataclasses.fields(before):
            assert type(getattr(after, field.name)) is type(getattr(before, field.name)), field.name


def test_a_thesis_run_comes_back_bit_for_bit(thesis_result, tmp_path):
    back = _round_trip(thesis_result, tmp_path)
    _assert_identical(back, thesis_result)
    _same_settings(back, thesis_result)
    assert back.settings.flavour == "thesis" and back.run.model == "FirstOrder" and back.run.n_sampled == 400
    assert back.timestamps is None
    assert back.summary() == thesis_result.summary()


def test_an_adaptive_run_keeps_its_weights_as_a_variable(adaptive_result, tmp_path):
    weights = adaptive_result.run.weights
    assert isinstance(weights, np.ndarray) and weights.size == adaptive_result.samples.shape[0]
    dataset = adaptive_result.to_xarray()
    assert dataset["weights"].dims == ("sample",)
    assert json.loads(dataset.attrs["settings"])["weights"] == {"__variable__": "weights"}
    back = _round_trip(adaptive_result, tmp_path)
    _assert_identical(back, adaptive_result)
    _same_settings(back, adaptive_result)
    assert back.run.weights.tobytes() == weights.tobytes()


def test_missing_ic_stays_nan(nan_result, tmp_path):
    missing = np.isnan(nan_result.ic)
    assert missing.any() and not missing.all()
    back = _round_trip(nan_result, tmp_path)
    _assert_identical(back, nan_result)
    assert np.array_equal(np.isnan(back.ic), missing)
    assert np.isnan(back.ci).sum() == np.isnan(nan_result.ci).sum() > 0


def test_timestamps_come_back_to_the_nanosecond(thesis_result, tmp_path):
    stamps = _stamps(thesis_result.time)
    stamped = dataclasses.replace(thesis_result, timestamps=stamps)
    back = _round_trip(stamped, tmp_path)
    _assert_identical(back, stamped)
    assert back.timestamps.dtype == np.dtype("datetime64[ns]")
    assert back.timestamps.view(np.int64).tolist() == stamps.view(np.int64).tolist()


def test_a_run_fed_from_pandas_keeps_its_timestamps(tmp_path):
    pd = pytest.importorskip("pandas")
    u, y = stored_record(80)
    index = pd.date_range("2024-10-27 00:30", periods=80, freq="1min", tz="Europe/Berlin")
    u, y, dt, stamps = unpack(pd.Series(u, index), pd.DataFrame({"y": y}, index))
    result = dynia.run(u, y, FirstOrder(), BOUNDS, n=4, n_samples=200, dt=dt, rng=5)
    result = dataclasses.replace(result, timestamps=stamps)
    back = _round_trip(result, tmp_path)
    assert back.settings.dt == 60.0
    assert str(back.timestamps[0]) == "2024-10-26T22:30:00.000000000"
    assert np.array_equal(back.timestamps, index.tz_convert("UTC").tz_localize(None).to_numpy())


def test_to_xarray_labels_every_axis(thesis_result):
    stamps = _stamps(thesis_result.time)
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
    # Dated: the dates index time, the seconds stay as a coordinate that is no index.
    assert np.array_equal(dataset["time"].values, stamps) and list(dataset.indexes["time"]) == list(stamps)
    assert dataset["elapsed"].dims == ("time",) and np.array_equal(dataset["elapsed"].values, thesis_result.time)
    assert dataset["elapsed"].attrs["units"] == "s" and "elapsed" not in dataset.indexes
    assert "timestamp" not in dataset.variables
    upper_t = dataset["ci"].sel(parameter="T", side="upper").values
    assert np.array_equal(upper_t, thesis_result.ci[1, :, 1], equal_nan=True)
    assert dataset["bounds"].sel(parameter="K").values.tolist() == [0.0, 7.0]
    settings = json.loads(dataset.attrs["settings"])
    assert settings["n"] == 6 and settings["model"] == "FirstOrder" and "bounds" not in settings
    assert json.loads(dataset.attrs["verdicts"]) == thesis_result.verdicts
    assert dataset.attrs["dynia_result"] == dynia.io.layout.FORMAT_VERSION == 2
    # Undated: seconds in time, as in format version 1, which the file says.
    undated = thesis_result.to_xarray()
    assert np.array_equal(undated["time"].values, thesis_result.time) and undated["time"].attrs["units"] == "s"
    assert "timestamp" not in undated.variables and "elapsed" not in undated.variables
    assert undated.attrs["dynia_result"] == 1


def test_the_run_record_keeps_its_types_through_a_file(thesis_result, tmp_path):
    run = RunRecord(
        model="FirstOrder",
        n_sampled=np.int64(7),
        noise_sigma=np.float64(0.25),
        noise_autocorrelation=float("nan"),
        target_se_met=np.bool_(False),
        target_se_rounds=[[400, 0.03], (800, float("nan"))],
        first_run_bounds={"K": (0, 7), "T": (1, 2.5)},
        narrowed=["K"],
    )
    assert run.n_sampled == 7 and type(run.n_sampled) is int and type(run.noise_sigma) is float
    assert run.target_se_met is False and run.target_se_rounds[0] == (400, 0.03) and run.narrowed == ("K",)
    assert dict(run.first_run_bounds) == {"K": (0.0, 7.0), "T": (1.0, 2.5)}
    result = dataclasses.replace(thesis_result, run=run, verdicts=None)
    back = _round_trip(result, tmp_path)
    assert back.verdicts is None
    _same_settings(back, result)
    assert type(back.run.target_se_rounds[1]) is tuple and np.isnan(back.run.target_se_rounds[1][1])


def test_settings_are_the_frozen_analysis_settings_and_the_record_is_frozen(thesis_result, adaptive_result):
    assert type(thesis_result.settings) is AnalysisSettings and type(thesis_result.run) is RunRecord
    assert thesis_result.settings.n_samples == 400 and thesis_result.settings.engine in ("numba", "numpy", "twin")
    with pytest.raises(dataclasses.FrozenInstanceError):
        thesis_result.settings.n = 3
    with pytest.raises(dataclasses.FrozenInstanceError):
        thesis_result.run.n_dropped = 3
    with pytest.raises(ValueError, match="read-only"):
        adaptive_result.run.weights[0] = 1.0
    with pytest.raises(TypeError, match="unhashable"):
        hash(adaptive_result.run)


def test_a_hand_built_result_takes_a_mapping_of_settings_and_of_thestored_record(thesis_result):
    built = dataclasses.replace(thesis_result, settings=dict(n=5, window="trailing"), run=dict(n_sampled=3))
    assert built.settings == AnalysisSettings(n=5, window="trailing") and built.run == RunRecord(n_sampled=3)
    assert dataclasses.replace(thesis_result, settings=None).settings is None
    assert dataclasses.replace(thesis_result, settings={}).settings is None
    with pytest.raises(SettingsError, match="unknown setting"):
        dataclasses.replace(thesis_result, settings={"noise_sigma": 0.5})
    with pytest.raises(SettingsError, match="settings must be a dynia.settings.AnalysisSettings"):
        dataclasses.replace(thesis_result, settings=[("n", 5)])
    with pytest.raises(SettingsError, match="n_sampled must be int or None; got '3'") as caught:
        RunRecord(n_sampled="3")
    assert caught.value.setting == "n_sampled"


def _rewrite_settings(path, change):
    """Replace the settings attribute of the file ``path`` by ``change`` of its decoded JSON."""
    with h5py.File(path, "r+") as file:
        file.attrs["settings"] = json.dumps(change(json.loads(file.attrs["settings"])))


def test_a_file_of_the_layout_before_the_run_record_loads(thesis_result, tmp_path):
    path = tmp_path / "result.nc"
    thesis_result.save(path)

    def old(settings):
        # As dynia wrote a run before the record: the bounds in the settings, every key in one flat object.
        return dict(settings, bounds={"K": {"__tuple__": [0.0, 7.0]}, "T": {"__tuple__": [0.0, 7.0]}})

    _rewrite_settings(path, old)
    back = dynia.load(path)
    _same_settings(back, thesis_result)
    _rewrite_settings(
        path, lambda settings: dict(settings, flavour="thesis-code", note="mine", target_se_rounds=[[1, 0.5]])
    )
    with pytest.warns(dynia.io.reader.StoredSettingsWarning, match="'note' are neither"):
        back = dynia.load(path)
    assert back.run.thesis_code and back.settings.flavour == "thesis" and back.run.target_se_rounds == ((1, 0.5),)
    _rewrite_settings(path, lambda settings: {"n": 1})  # a hand-built result's few settings
    assert dynia.load(path).settings == AnalysisSettings(n=1) and dynia.load(path).run == RunRecord()


@pytest.mark.parametrize(
    "settings, needle",
    [
        ({"n_sampled": "many"}, "n_sampled must be int or None"),
        ({"flavour": "best"}, "flavour must be one of"),
        ({"n": 1, "percentage": 0.01}, "percentage 0.01 of n_samples 2000 keeps 0"),
    ],
)
def test_settings_in_a_file_that_no_run_gives_are_a_data_error(thesis_result, tmp_path, settings, needle):
    path = tmp_path / "result.nc"
    thesis_result.save(path)
    _rewrite_settings(path, lambda _: settings)
    with pytest.raises(DataError, match="attribute 'settings'") as caught:
        dynia.load(path)
    assert needle in str(caught.value) and str(path) in str(caught.value)


def test_verdicts_that_cannot_be_saved_are_named(thesis_result, tmp_path):
    result = dataclasses.replace(thesis_result, verdicts={"K": {"when": object()}})
    with pytest.raises(SettingsError, match=r"result\.verdicts\['K'\]\['when'\] holds a value of type object"):
        result.save(tmp_path / "result.nc")


def test_load_names_what_it_cannot_read(thesis_result, tmp_path):
    with pytest.raises(DataError, match=r"missing\.nc: no such file; expected a netCDF file"):
        dynia.load(tmp_path / "missing.nc")
    # Issue 32: both were "no such file".
    with pytest.raises(DataError, match=r": is a directory; expected a netCDF file"):
        dynia.load(tmp_path)
    with pytest.raises(DataError, match=r"/dev/zero: is not a regular file \(a device"):
        dynia.load("/dev/zero")
    (tmp_path / "text.nc").write_text("time,u,y\n")
    with pytest.raises(DataError, match=r"text\.nc: cannot be read as netCDF-4"):
        dynia.load(tmp_path / "text.nc")
    foreign = thesis_result.to_xarray()
    del foreign.attrs["dynia_result"]
    foreign.to_netcdf(tmp_path / "foreign.nc", engine="h5netcdf")
    with pytest.raises(DataError, match=r"foreign\.nc: no dynia_result attribute; expected a result"):
        dynia.load(tmp_path / "foreign.nc")
    foreign.attrs["dynia_result"] = dynia.io.layout.FORMAT_VERSION + 1
    foreign.to_netcdf(tmp_path / "newer.nc", engine="h5netcdf")
    with pytest.raises(DataError, match=rf"newer\.nc: format version {dynia.io.layout.FORMAT_VERSION + 1}; expected"):
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
    stamps = _stamps(thesis_result.time)
    table = dataclasses.replace(thesis_result, timestamps=stamps).to_dataframe()
    assert list(table.columns) == ["time", "timestamp", "parameter", "ic", "lower", "upper", "median", "informative"]
    assert table["timestamp"].to_numpy().tolist() == np.tile(stamps, 2).tolist()
    assert "timestamp" not in thesis_result.to_dataframe().columns


@pytest.mark.parametrize("kind", ["plot_information_content", "plot_identifiability"])
def test_plots_draw_against_the_timestamps(thesis_result, kind):
    stamps = _stamps(thesis_result.time)
    stamped = dataclasses.replace(thesis_result, timestamps=stamps)
    fig, ax = plt.subplots()
    try:
        getattr(stamped, kind)("K", ax=ax)
        numbers = dates.date2num(stamps)
        assert ax.get_xlim() == (numbers[0], numbers[-1])
        assert np.array_equal(ax.lines[0].get_xdata(), numbers)
        assert isinstance(ax.xaxis.get_major_formatter(), dates.ConciseDateFormatter)
    finally:
        plt.close(fig)
    fig, ax = plt.subplots()
    try:
        getattr(thesis_result, kind)("K", ax=ax)
        assert ax.get_xlim() == (thesis_result.time[0], thesis_result.time[-1])
        assert not isinstance(ax.xaxis.get_major_formatter(), (dates.AutoDateFormatter, dates.ConciseDateFormatter))
    finally:
        plt.close(fig)


# --- dated results: dates in the summary, a date index in xarray and in the file ----------------------------------

# The dated record: thesis_result's record on a 1 s DatetimeIndex from 2015-01-31 23:59, February from step 60.
FEBRUARY = 60
TIME_KEYS = ("time_of_max_ic", "time_of_highest_ic", "high_ic_span")


def _dated_series(steps=120):
    pd = pytest.importorskip("pandas")
    u, y = stored_record(steps)
    index = pd.date_range("2015-01-31 23:59", periods=steps, freq="1s")
    return pd.Series(u, index), pd.Series(y, index)


@pytest.fixture(scope="module")
def dated_result():
    return dynia.run(*_dated_series(), FirstOrder(), BOUNDS, n=6, n_samples=400, flavour="thesis", rng=1)


def test_a_dated_runs_summary_gives_the_dates_of_its_steps(dated_result, thesis_result):
    assert np.array_equal(dated_result.ic, thesis_result.ic, equal_nan=True)  # the same analysis, dated
    stamps = dated_result.timestamps
    dated, undated = dated_result.summary(), thesis_result.summary()
    for p, name in enumerate(dated_result.names):
        entry = dated[name]
        step, highest = reported_step(dated_result, p), int(np.nanargmax(dated_result.ic[p]))
        evidence = np.flatnonzero(high_ic_windows(dated_result, p))
        assert type(entry["time_of_max_ic"]) is np.datetime64 and entry["time_of_max_ic"] == stamps[step]
        assert entry["time_of_max_ic"].dtype == np.dtype("datetime64[ns]")
        assert entry["time_of_highest_ic"] == stamps[highest]
        # Undated, the same steps in seconds, as before; the rest alike (the reasons' texts may name dates).
        plain = undated[name]
        assert type(plain["time_of_max_ic"]) is float and plain["time_of_max_ic"] == thesis_result.time[step]
        assert plain["time_of_highest_ic"] == thesis_result.time[highest]
        if evidence.size:
            assert entry["high_ic_span"] == [stamps[evidence[0]], stamps[evidence[-1]]]
            assert plain["high_ic_span"] == [thesis_result.time[evidence[0]], thesis_result.time[evidence[-1]]]
        else:
            assert entry["high_ic_span"] == plain["high_ic_span"] == [None, None]
        others = [key for key in entry if key not in (*TIME_KEYS, "reasons")]
        assert {key: entry[key] for key in others} == {key: plain[key] for key in others}
        assert [reason["code"] for reason in entry["reasons"]] == [reason["code"] for reason in plain["reasons"]]
    assert dated["K"]["high_ic_windows"] > 0  # the span's dates are checked


def test_to_xarray_of_a_dated_run_selects_by_date(dated_result):
    dataset = dated_result.to_xarray()
    assert dataset["time"].dtype == np.dtype("datetime64[ns]") and "time" in dataset.indexes
    february = dataset.sel(time="2015-02")
    assert february.sizes["time"] == dated_result.time.size - FEBRUARY
    assert np.array_equal(february["ic"].values, dated_result.ic[:, FEBRUARY:], equal_nan=True)
    assert np.array_equal(february["elapsed"].values, dated_result.time[FEBRUARY:])
    assert dataset.sel(time="2015-01").sizes["time"] == FEBRUARY
    around = dataset.sel(time=slice("2015-01-31T23:59:30", "2015-02-01T00:00:10"))
    assert np.array_equal(around["elapsed"].values, np.arange(30.0, 71.0))  # both ends included
    assert dataset.sel(time=slice("2015-02-01", "2015-02-02")).sizes == february.sizes


@pytest.mark.parametrize("dated", [False, True])
def test_a_dated_and_an_undated_run_come_back_with_their_dates_and_summary(
    dated_result, thesis_result, tmp_path, dated
):
    result = dated_result if dated else thesis_result
    back = _round_trip(result, tmp_path)
    _assert_identical(back, result)
    _same_settings(back, result)
    if dated:
        assert back.timestamps.dtype == np.dtype("datetime64[ns]")
        assert back.timestamps.tobytes() == result.timestamps.tobytes()
    else:
        assert back.timestamps is None
    assert back.summary() == result.summary()
    assert back.to_xarray().identical(result.to_xarray())
    with h5py.File(tmp_path / "result.nc", "r") as file:
        # An undated file is format version 1, as before: an older dynia reads it.
        assert file.attrs["dynia_result"] == (2 if dated else 1)
        assert file["time"].dtype == (np.int64 if dated else np.float64) and "timestamp" not in file
        assert ("elapsed" in file) == dated and all(file[key].fletcher32 for key in ("time", "elapsed") if key in file)


def test_a_dated_run_stored_block_by_block_loads_with_its_dates(dated_result, tmp_path):
    xr = pytest.importorskip("xarray")
    path = tmp_path / "stored.nc"
    stored = dynia.run(*_dated_series(), FirstOrder(), BOUNDS, n=6, n_samples=400, flavour="thesis", rng=1, store=path)
    assert type(stored.ic).__name__ == "DiskArray"
    assert stored.summary() == dated_result.summary()
    for lazy in (False, True):
        back = dynia.load(path, lazy=lazy)
        assert np.array_equal(back.ic, dated_result.ic, equal_nan=True) and np.array_equal(back.time, dated_result.time)
        assert back.timestamps.tobytes() == dated_result.timestamps.tobytes()
        assert back.summary() == dated_result.summary()
    assert stored.to_xarray().sel(time="2015-02").sizes["time"] == dated_result.time.size - FEBRUARY
    with xr.open_dataset(path, engine="h5netcdf") as opened:  # any CF reader decodes the dates
        assert np.array_equal(opened["time"].values, dated_result.timestamps)
        assert np.array_equal(opened.sel(time="2015-02")["elapsed"].values, dated_result.time[FEBRUARY:])


def _version_1(result, path):
    """``result`` written as dynia wrote format version 1: seconds in time, the dates beside them in ``timestamp``."""
    dataset = dataclasses.replace(result, timestamps=None).to_xarray()
    assert dataset.attrs["dynia_result"] == 1
    encoding = {
        name: {"_FillValue": None, "fletcher32": dataset[name].dtype.kind in "biuf"} for name in dataset.variables
    }
    if result.timestamps is not None:
        dataset = dataset.assign_coords(timestamp=("time", result.timestamps))
        encoding["timestamp"] = dict(
            _FillValue=None, units=TIMESTAMP_UNITS, calendar="proleptic_gregorian", dtype="int64"
        )
    dataset.to_netcdf(path, engine="h5netcdf", encoding=encoding)


@pytest.mark.parametrize("dated", [False, True])
def test_a_version_1_file_still_loads(dated_result, thesis_result, tmp_path, dated):
    result = dated_result if dated else thesis_result
    path = tmp_path / "version1.nc"
    _version_1(result, path)
    with h5py.File(path, "r") as file:
        assert ("timestamp" in file) == dated and file["time"].dtype == np.float64
    for lazy in (False, True):
        back = dynia.load(path, lazy=lazy)
        assert np.array_equal(back.ic, result.ic, equal_nan=True) and back.time.tobytes() == result.time.tobytes()
        assert (back.timestamps is None) if not dated else back.timestamps.tobytes() == result.timestamps.tobytes()
        assert back.summary() == result.summary()
    if dated:
        assert dynia.load(path).to_xarray().sel(time="2015-02").sizes["time"] == result.time.size - FEBRUARY


def test_a_dynia_reading_version_1_only_refuses_a_dated_file(dated_result, tmp_path, monkeypatch):
    path = tmp_path / "result.nc"
    dated_result.save(path)
    monkeypatch.setattr(dynia.io.reader, "FORMAT_VERSION", 1)
    with pytest.raises(DataError, match=r"result\.nc: format version 2; expected .*format version 1 or earlier"):
        dynia.load(path)


def test_a_dated_file_without_its_seconds_is_a_data_error(dated_result, tmp_path):
    dataset = dated_result.to_xarray()
    encoding = {"time": dict(units=TIMESTAMP_UNITS, calendar="proleptic_gregorian", dtype="int64")}
    dataset.drop_vars("elapsed").to_netcdf(tmp_path / "no_elapsed.nc", engine="h5netcdf", encoding=encoding)
    with pytest.raises(DataError, match=r"no_elapsed\.nc: time holds dates but the file has no 'elapsed'"):
        dynia.load(tmp_path / "no_elapsed.nc")
    stamped = dataset.assign_coords(timestamp=("time", dated_result.timestamps))
    stamped.to_netcdf(tmp_path / "twice.nc", engine="h5netcdf", encoding=encoding)
    with pytest.raises(DataError, match=r"twice\.nc: time holds dates and the file has a 'timestamp' too"):
        dynia.load(tmp_path / "twice.nc")
