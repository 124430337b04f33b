"""Long records in bounded memory: float32 result arrays and a netCDF store written as the windows are analysed."""

import dataclasses
import os
import pickle

import h5py
import matplotlib
import numpy as np
import pytest

import dynia
from dynia import decimation
from dynia.engine.windows import analyse_stream, moving_window
from dynia.errors import DataError, OutputError, SettingsError
from dynia.io.arrays import TIME_VARIABLES, DiskArray, ResultFile
from dynia.models import FirstOrder
from dynia.settings import AnalysisSettings
from dynia.verdicts import assess

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

BOUNDS = {"K": (0, 7), "T": (0, 7)}
STORED = ("ic", "ci", "median", "gradient", "ic_se", "ci_se")


def _record(steps=400, seed=3):
    rng = np.random.default_rng(seed)
    u = np.r_[np.zeros(20), np.full(60, 1.0), np.full(steps - 80, 0.3)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + rng.normal(0, 0.05, steps)
    return u, y


def _run(**options):
    u, y = _record()
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=6, n_samples=400, ic_error=True, rng=1, **options)


@pytest.fixture(scope="module")
def in_memory():
    return _run()


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("long_records")


@pytest.fixture(scope="module")
def stored(folder):
    return _run(store=folder / "float64.nc")


@pytest.fixture(scope="module")
def stored_float32(folder):
    return _run(dtype="float32", store=folder / "float32.nc")


def _same(first, second):
    return np.array_equal(np.asarray(first), np.asarray(second), equal_nan=True)


def test_a_stored_run_equals_the_run_in_memory_bit_for_bit(stored, in_memory):
    for name in STORED:
        assert isinstance(getattr(stored, name), DiskArray)
        assert getattr(stored, name).dtype == np.float64
        assert _same(getattr(stored, name), getattr(in_memory, name)), name
    for name in ("samples", "bounds", "time", "bin_centres"):
        assert _same(getattr(stored, name), getattr(in_memory, name)), name
    assert stored.names == in_memory.names
    assert stored.verdicts == in_memory.verdicts
    assert stored.summary() == in_memory.summary()
    assert stored.settings.replace(store=None) == in_memory.settings.replace(store=None)
    assert stored.run == in_memory.run
    assert stored.settings.store.endswith("float64.nc")


def test_float32_results_are_the_float64_results_rounded(stored_float32, in_memory):
    u, y = _record()
    in_memory_float32 = dynia.run(u, y, FirstOrder(), BOUNDS, n=6, n_samples=400, ic_error=True, rng=1, dtype="float32")
    for name in STORED:
        rounded = getattr(in_memory, name).astype(np.float32)
        assert getattr(in_memory_float32, name).dtype == np.float32
        assert _same(getattr(in_memory_float32, name), rounded), name
        assert getattr(stored_float32, name).dtype == np.float32
        assert _same(getattr(stored_float32, name), rounded), name
    # float64 where float32 would change nothing: the samples and the time axis are not rounded.
    assert stored_float32.samples.dtype == np.float64 and stored_float32.time.dtype == np.float64


def test_the_store_is_complete_and_loads_back_exactly(stored, folder):
    for lazy in (False, True):
        back = dynia.load(folder / "float64.nc", lazy=lazy)
        for name in STORED:
            assert isinstance(getattr(back, name), DiskArray if lazy else np.ndarray)
            assert _same(getattr(back, name), getattr(stored, name)), name
        assert back.verdicts == stored.verdicts
        assert back.settings == stored.settings and back.run == stored.run
    assert [name for name in os.listdir(folder) if name.endswith(".partial")] == []


def test_the_store_is_chunked_over_time(folder):
    u, y = _record(steps=1500)
    path = folder / "blocks.nc"
    # 1000 bins make a time block of 4 MB / 8 kB = 524 steps, so 1500 steps in chunks of 7 cross block edges.
    stored = moving_window(y, _simulations(u), _samples(), [[0, 7], [0, 7]], n=4, bins=1000, chunk_steps=7, store=path)
    in_memory = moving_window(y, _simulations(u), _samples(), [[0, 7], [0, 7]], n=4, bins=1000, chunk_steps=7)
    with h5py.File(path, "r") as file:
        for name in ("ic", "ci", "median", "gradient"):
            dims = TIME_VARIABLES[name]
            chunks = file[name].chunks
            assert chunks[dims.index("time")] < 1500 and chunks[dims.index("parameter")] == 1
    for name in ("ic", "ci", "median", "gradient"):
        assert _same(getattr(stored, name), getattr(in_memory, name)), name


def _samples():
    return np.random.default_rng(5).uniform(0, 7, (200, 2))


def _simulations(u):
    return FirstOrder().simulate(_samples(), u)


def test_an_error_or_an_interruption_leaves_no_file(tmp_path):
    u, y = _record()
    sims = _simulations(u)
    path = tmp_path / "result.nc"

    def chunks(error):
        yield sims[:, :100]
        raise error

    for error in (RuntimeError("the historian went away"), KeyboardInterrupt()):
        with pytest.raises(type(error)):
            analyse_stream(
                y, chunks(error), _samples(), [[0, 7], [0, 7]], n=3, percentage=10, bins=40, conf_level=90,
                flavour="thesis", chunk_steps=20, store=path,
            )  # fmt: skip
        assert os.listdir(tmp_path) == []


def test_an_existing_file_is_replaced_only_when_the_new_one_is_complete(tmp_path):
    u, y = _record()
    path = tmp_path / "result.nc"
    path.write_bytes(b"an earlier result")

    def failing():
        yield _simulations(u)[:, :100]
        raise RuntimeError("stopped")

    with pytest.raises(RuntimeError):
        analyse_stream(
            y, failing(), _samples(), [[0, 7], [0, 7]], n=3, percentage=10, bins=40, conf_level=90, flavour="thesis",
            chunk_steps=20, store=path,
        )  # fmt: skip
    assert path.read_bytes() == b"an earlier result" and os.listdir(tmp_path) == ["result.nc"]
    moving_window(y, _simulations(u), _samples(), [[0, 7], [0, 7]], n=3, store=path)
    assert dynia.load(path).ic.shape == (2, y.size)


def test_a_run_that_fails_in_its_verdicts_leaves_no_file(tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("verdicts failed")

    monkeypatch.setattr(dynia.pipeline, "assess", broken)
    with pytest.raises(RuntimeError, match="verdicts failed"):
        _run(store=tmp_path / "result.nc")
    assert os.listdir(tmp_path) == []


def test_an_unwritable_store_is_an_output_error(tmp_path):
    u, y = _record()
    with pytest.raises(OutputError, match="cannot be written"):
        moving_window(y, _simulations(u), _samples(), [[0, 7], [0, 7]], n=3, store=tmp_path / "missing" / "r.nc")
    with pytest.raises(OutputError, match="is a folder"):
        moving_window(y, _simulations(u), _samples(), [[0, 7], [0, 7]], n=3, store=tmp_path)


@pytest.mark.parametrize(
    "options, setting",
    [
        (dict(dtype="float16"), "dtype"),
        (dict(dtype=np.float32), "dtype"),
        (dict(store=""), "store"),
        (dict(store=3), "store"),
        (dict(store="r.nc", sampler="iis"), "store"),
        (dict(dtype="float32", sampler="de"), "dtype"),
    ],
)
def test_storage_settings_are_checked_once(options, setting):
    with pytest.raises(SettingsError) as raised:
        AnalysisSettings(**options)
    assert raised.value.setting == setting


def test_a_disk_array_indexes_like_numpy_and_reads_only_what_is_indexed(stored, in_memory):
    gradient = stored.gradient
    assert isinstance(gradient[1], DiskArray) and gradient[1].shape == in_memory.gradient[1].shape
    assert isinstance(gradient[-1, 3], DiskArray)
    for key in ((1, slice(None), 50), (0, 5, slice(10, 20)), (slice(None), 2), (1, Ellipsis, 7)):
        assert _same(gradient[key], in_memory.gradient[key])
    assert _same(stored.ic[[1, 0]], in_memory.ic[[1, 0]])  # an order HDF5 cannot select is read and reordered
    assert _same(stored.ic[1] - 2 * stored.ic_se[1], in_memory.ic[1] - 2 * in_memory.ic_se[1])
    assert np.nanargmax(stored.ic[0]) == np.nanargmax(in_memory.ic[0])
    assert _same(stored.ci.ravel(), in_memory.ci.ravel())
    assert _same(pickle.loads(pickle.dumps(stored.ci[1])), in_memory.ci[1])
    with pytest.raises(IndexError):
        gradient[2]


def test_xarray_and_save_of_a_stored_result_stream_from_its_file(stored, in_memory, folder):
    lazy, eager = stored.to_xarray(), in_memory.to_xarray()
    assert lazy.gradient.dims == eager.gradient.dims and lazy.attrs["verdicts"] == eager.attrs["verdicts"]
    for name in STORED:
        assert _same(lazy[name].values, eager[name].values), name
    stored.save(folder / "copy.nc")
    copy = dynia.load(folder / "copy.nc")
    for name in STORED:
        assert _same(getattr(copy, name), getattr(in_memory, name)), name
    assert copy.verdicts == stored.verdicts


def test_a_lazy_load_refuses_dimensions_in_another_order(stored, folder):
    dataset = stored.to_xarray().load()
    dataset["gradient"] = dataset.gradient.transpose("time", "bin", "parameter")
    dataset.to_netcdf(folder / "transposed.nc", engine="h5netcdf")
    assert _same(dynia.load(folder / "transposed.nc").gradient, stored.gradient)
    with pytest.raises(DataError, match="lazy=False"):
        dynia.load(folder / "transposed.nc", lazy=True)


def test_plots_of_a_stored_result_read_its_gradient_by_blocks(stored, in_memory, monkeypatch):
    # Blocks of a few buckets, so that the thinning of a short record goes through several reads.
    monkeypatch.setattr(decimation, "_BLOCK_VALUES", 50)
    axis = stored.time
    by_blocks = decimation.decimated_columns(axis, stored.gradient[1], max_columns=60)
    whole = decimation.decimated_columns(axis, in_memory.gradient[1], max_columns=60)
    assert _same(by_blocks[0], whole[0]) and _same(by_blocks[1], whole[1])
    for per_sample in (False, True):
        drawn = [
            result.plot_identifiability("T", per_sample=per_sample).collections[0].get_array()
            for result in (stored, in_memory)
        ]
        assert _same(*drawn)
    plt.close("all")


def test_a_result_file_made_by_hand_is_committed_by_its_owner(tmp_path):
    u, y = _record()
    path = tmp_path / "result.nc"
    with ResultFile(path, "float32") as output:
        result = moving_window(y, _simulations(u), _samples(), [[0, 7], [0, 7]], n=3, store=output)
        assert not path.exists() and isinstance(result.ic, DiskArray)
        committed = output.commit(dataclasses.replace(result, verdicts=assess(result)))
    assert committed.verdicts == assess(result) and dynia.load(path).verdicts == committed.verdicts


def test_arrays_of_a_discarded_file_say_so(tmp_path):
    u, y = _record()
    output = ResultFile(tmp_path / "result.nc")
    result = moving_window(y, _simulations(u), _samples(), [[0, 7], [0, 7]], n=3, store=output)
    output.discard()
    assert os.listdir(tmp_path) == []
    with pytest.raises(DataError, match="the file was deleted"):
        result.ic[0, 5]
