"""Issue 20's hostile cases on result files: tampered attributes, damaged or forged arrays, and a full disk.

Each test is one case of the review and failed before the fix. ``dynia.load`` must refuse, with one DataError
naming the file and the part at fault, whatever no analysis writes; a write that fails (a full disk, a file size
limit) must end in one OutputError (one ``dynia: error:`` line naming --out on the command line), with the partial
file, the staging directory and the lock removed and nothing printed by h5py. The disk is never filled: the
failure is injected where the result file is written (``dynia.io.arrays._pwrite``) or comes from a file size
limit (RLIMIT_FSIZE) in a subprocess.
"""

import dataclasses
import errno
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest
from cli_cases import (
    BASE,
    GOOD,
    cli_analyse,
    cli_one_error,
    write_text_file,
)
from conftest import stored_record

import dynia
import dynia.cli.report
import dynia.io.arrays
from dynia.errors import DataError, OutputError
from dynia.io.reader import StoredVerdictsWarning
from dynia.models import FirstOrder

ROOT = Path(__file__).resolve().parent.parent
BOUNDS = {"K": (0, 7), "T": (0, 7)}
ARRAYS = ("samples", "bounds", "time", "ic", "ci", "median", "gradient", "bin_centres")


@pytest.fixture(scope="module")
def result():
    u, y = stored_record()
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=6, n_samples=400, rng=1)


@pytest.fixture
def saved(result, tmp_path):
    path = tmp_path / "result.nc"
    result.save(path)
    return path


def _identical(back, result):
    for name in ARRAYS:
        before, after = np.asarray(getattr(result, name)), np.asarray(getattr(back, name))
        assert after.dtype == before.dtype and after.tobytes() == before.tobytes(), name
    assert back.verdicts == result.verdicts
    assert back.settings.replace(store=None) == result.settings.replace(store=None) and back.run == result.run


def _set_attribute(path, name, value):
    with h5py.File(path, "r+") as file:
        file.attrs[name] = value


def _refused(path, *needles, lazy=False):
    with pytest.raises(DataError) as caught:
        back = dynia.load(path, lazy=lazy)
        for name in ARRAYS:  # a lazy load may refuse a block only when it is read
            np.asarray(getattr(back, name))
    message = str(caught.value)
    assert str(path) in message and "\n" not in message, message
    for needle in needles:
        assert needle in message, message
    return message


# --- tampered attributes: a DataError, never TypeError, AttributeError, JSONDecodeError or KeyError ---------


@pytest.mark.parametrize(
    "attribute, value, needle",
    [
        ("settings", 5, "attribute 'settings' holds int64"),
        ("settings", "{not json", "attribute 'settings' is not JSON"),
        ("settings", "[1, 2]", "attribute 'settings' holds a JSON list; expected an object"),
        ("settings", '{"weights": {"__variable__": "weights"}}', "settings['weights']"),
        ("settings", '{"weights": {"__variable__": 3}}', "settings['weights']"),
        ("settings", '{"bounds": {"__tuple__": 5}}', "tags a tuple but holds no list"),
        ("settings", '{"a": ' * 100_000 + "1" + "}" * 100_000, "attribute 'settings' nests its JSON deeper"),
        ("verdicts", "[" * 100_000 + "]" * 100_000, "attribute 'verdicts' nests its JSON deeper"),
        ("verdicts", 3, "attribute 'verdicts' holds int64"),
        ("verdicts", "[1, 2]", "attribute 'verdicts' holds a JSON list"),
        ("verdicts", '{"K": 1, "T": 2}', "verdicts['K'] is 1"),
        ("verdicts", '{"K": {"verdict": "sure", "reasons": []}, "T": {"verdict": "weak", "reasons": []}}', "'sure'"),
        ("verdicts", '{"T": {"verdict": "weak", "reasons": []}}', "expected the parameters ['K', 'T']"),
    ],
)
def test_a_tampered_attribute_is_a_data_error(saved, attribute, value, needle):
    _set_attribute(saved, attribute, value)
    _refused(saved, needle)


def test_a_missing_settings_attribute_is_a_data_error(saved):
    with h5py.File(saved, "r+") as file:
        del file.attrs["settings"]
    _refused(saved, "has no 'settings'")


# --- damaged files: checksums ---------------------------------------------------------------------------


def _flip_bytes(path, variable, count, seed=0):
    """Flip ``count`` bytes at random in the stored data of ``variable`` (its chunks, or its contiguous block)."""
    with h5py.File(path, "r") as file:
        dataset = file[variable]
        if dataset.chunks is None:
            spans = [(dataset.id.get_offset(), dataset.id.get_storage_size())]
        else:
            spans = []
            for index in range(dataset.id.get_num_chunks()):
                info = dataset.id.get_chunk_info(index)
                spans.append((info.byte_offset, info.size - (4 if dataset.fletcher32 else 0)))
    offsets = np.concatenate([np.arange(start, start + size) for start, size in spans])
    chosen = np.random.default_rng(seed).choice(offsets, size=count, replace=False)
    with open(path, "r+b") as file:
        for offset in chosen:
            file.seek(int(offset))
            byte = file.read(1)[0]
            file.seek(int(offset))
            file.write(bytes([byte ^ 0xFF]))


def test_a_file_is_written_with_checksums(saved, result, tmp_path):
    with h5py.File(saved, "r") as file:
        assert _unchecked(file) == []
    stored = dynia.run(*stored_record(), FirstOrder(), BOUNDS, n=6, n_samples=400, rng=1, store=tmp_path / "disk.nc")
    with h5py.File(stored.ic.filename, "r") as file:
        assert _unchecked(file) == []


def _unchecked(file):
    """The numeric variables of an open file without a checksum (netCDF's bare dimensions hold no data)."""
    bare = b"This is a netCDF dimension but not a netCDF variable"
    return [
        name
        for name in file
        if file[name].dtype.kind in "biuf"
        and not np.asarray(file[name].attrs.get("NAME", b"")).tobytes().startswith(bare)
        and not file[name].fletcher32
    ]


@pytest.mark.parametrize("lazy", [False, True])
def test_flipped_bytes_fail_their_checksum(saved, lazy):
    _flip_bytes(saved, "gradient", 4000)
    _refused(saved, "gradient cannot be read", "damaged", lazy=lazy)


def test_flipped_bytes_in_the_on_disk_store_fail_their_checksum(tmp_path):
    path = tmp_path / "disk.nc"
    dynia.run(*stored_record(), FirstOrder(), BOUNDS, n=6, n_samples=400, rng=1, dtype="float32", store=path)
    _flip_bytes(path, "ic", 40)
    _refused(path, "ic cannot be read")
    _refused(path, "ic cannot be read", lazy=True)


def _without_checksums(result, path):
    """The file as dynia wrote it before checksums: every variable unfiltered."""
    dataset = result.to_xarray()
    dataset.to_netcdf(path, engine="h5netcdf", encoding={name: {"_FillValue": None} for name in dataset.variables})


def test_an_older_file_without_checksums_loads_bit_for_bit(result, tmp_path):
    path = tmp_path / "old.nc"
    _without_checksums(result, path)
    _identical(dynia.load(path), result)
    _identical(dynia.load(path, lazy=True), result)


def test_flipped_bytes_in_an_older_file_fail_the_range_checks(result, tmp_path):
    path = tmp_path / "old.nc"
    _without_checksums(result, path)
    _flip_bytes(path, "gradient", 4000)
    _refused(path, "gradient")


# --- forged values: the checksums recomputed, the ranges refuse them ------------------------------------------


def _forge(path, variable, index, value):
    with h5py.File(path, "r+") as file:
        file[variable][index] = value


@pytest.mark.parametrize(
    "variable, index, value, needle",
    [
        ("ic", (0, 60), 5.0, "ic lies outside [0, 1]"),
        ("ic", (0, 60), -1.0, "ic lies outside [0, 1]"),
        ("ic", (0, 60), np.nan, "ic is NaN where the limits are not"),
        ("ic", (1, slice(None)), np.nan, "ic is NaN where the limits are not"),
        ("ci", (0, 60, 1), 8.0, "limits outside the bounds"),
        ("ci", (0, 60, 0), 6.9, "a lower limit above the upper"),
        ("median", (0, 60), 6.99, "median lies outside the limits"),
        ("gradient", (0, 3, 60), -0.25, "gradient lies outside [0, 1]"),
        ("gradient", (0, 3, 60), 3870.0, "gradient lies outside [0, 1]"),
        ("samples", (5, 0), 9.0, "samples of 'K' lie outside its bounds"),
        ("bounds", (1, 0), 8.0, "bounds"),
        ("time", (3,), 0.0, "time is not finite and rising"),
        ("noise_floor", (10,), -1.0, "noise_floor holds negative"),
    ],
)
@pytest.mark.parametrize("lazy", [False, True])
def test_a_forged_value_is_refused(saved, variable, index, value, needle, lazy):
    _forge(saved, variable, index, value)
    _refused(saved, needle, lazy=lazy)


@pytest.fixture
def saved_dated(result, tmp_path):
    """A dated result's file (format 2: the dates in time, the seconds in elapsed), one step a second."""
    start = np.datetime64("2024-03-31T00:59:58", "ns")
    dated = dataclasses.replace(result, timestamps=start + np.round(result.time * 1e9).astype("timedelta64[ns]"))
    path = tmp_path / "dated.nc"
    dated.save(path)
    return path


def _dates_forged(path, change):
    with h5py.File(path, "r+") as file:
        file["time"][:] = change(file["time"][:])


@pytest.mark.parametrize(
    "change, needle",
    [
        (lambda dates: dates[::-1], "the dates in time do not rise at step 1"),
        (lambda dates: np.r_[dates[:5], dates[4], dates[6:]], "the dates in time do not rise at step 5"),
        (lambda dates: np.r_[dates[:5], np.iinfo(np.int64).min, dates[6:]], "missing date (NaT) at step 5"),
        (
            lambda dates: dates[0] + (dates - dates[0]) * 1000,
            "put step 1 at 1000 s from the first, where time says 1 s",
        ),
    ],
)
@pytest.mark.parametrize("lazy", [False, True])
def test_damaged_dates_of_a_dated_file_are_refused(saved_dated, change, needle, lazy):
    """Issue 32: reversed, repeated or missing dates, or dates that disagree with elapsed, loaded without a word."""
    dynia.load(saved_dated)
    _dates_forged(saved_dated, change)
    _refused(saved_dated, needle, lazy=lazy)


def test_elapsed_that_disagrees_with_the_dates_is_refused(saved_dated):
    with h5py.File(saved_dated, "r+") as file:
        file["elapsed"][:] = file["elapsed"][:] * 1000
    _refused(saved_dated, "put step 1 at 1 s from the first, where time says 1000 s")


def test_a_result_whose_dates_disagree_with_its_seconds_cannot_be_made(result):
    """Refused when made, so that no file that dynia.load refuses can be saved."""
    start = np.datetime64("2024-03-31", "ns")
    with pytest.raises(dynia.SettingsError, match="timestamps put step 1 at 15 s from the first, where time says 1 s"):
        dataclasses.replace(result, timestamps=start + np.arange(result.time.size) * np.timedelta64(15, "s"))


def test_a_forged_ic_with_forged_verdicts_is_refused(saved):
    """IC of 5 where the limits say otherwise, and the verdicts rewritten to match: refused by the ranges."""
    _forge(saved, "ic", (1, slice(None)), 0.9)
    _set_attribute(saved, "verdicts", json.dumps({name: {"verdict": "identified", "reasons": []} for name in "KT"}))
    _refused(saved, "ic is not 1 - (upper - lower) / range for its limits (first at parameter 'T')")


@pytest.mark.parametrize("lazy", [False, True])
def test_forged_verdicts_load_as_the_arrays_give_them(saved, result, lazy):
    assert result.verdicts["T"]["verdict"] == "weak"  # the case: a weak parameter forged identified
    forged = dict(result.verdicts, T={"verdict": "identified", "reasons": []})
    _set_attribute(saved, "verdicts", json.dumps(forged))
    with pytest.warns(StoredVerdictsWarning) as caught:
        back = dynia.load(saved, lazy=lazy)
        assert back.verdicts == result.verdicts  # a lazy load checks them here, when first used
    (message,) = [str(warning.message) for warning in caught]
    assert message.startswith(f"{saved}: the stored verdict of 'T' is 'identified' (no reasons) but its arrays give")


def test_a_lazy_load_derives_the_verdicts_when_they_are_first_used_not_at_load(saved, result, monkeypatch):
    # The case: a lazy load re-derived the verdicts at once, reading IC over the whole record (1.8 s for 2 x 200 000
    # steps, proportional to the record) before a single array was asked for.
    calls = []
    monkeypatch.setattr(dynia.io.reader, "assess", lambda loaded: calls.append(1) or dynia.verdicts.assess(loaded))
    back = dynia.load(saved, lazy=True)
    assert calls == [] and list(back.verdicts) == list(result.names) and len(back.verdicts) == len(result.names)
    assert calls == []
    assert back.verdicts["T"] == result.verdicts["T"] and dict(back.verdicts) == result.verdicts
    assert calls == [1]  # once
    copy = saved.with_name("copy.nc")
    back.save(copy)  # a deferred mapping saves as the dict it stands for
    assert dynia.load(copy).verdicts == result.verdicts and len(calls) == 2  # an eager load checks at once


def test_the_verdicts_of_a_file_load_without_a_warning(saved, result):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert dynia.load(saved).verdicts == result.verdicts


def test_verdicts_whose_texts_name_times_otherwise_still_load(result, tmp_path):
    """The command line writes the reasons' times as the data file does: codes and verdicts are what is checked."""
    verdicts = dynia.verdicts.assess(result, clock=lambda step: f"day {step}")
    path = tmp_path / "result.nc"
    dataclasses.replace(result, verdicts=verdicts).save(path)
    assert dynia.load(path).verdicts == verdicts


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_a_file_written_today_loads_bit_for_bit_eager_and_lazy(tmp_path, dtype):
    u, y = stored_record()
    dynia.run(u, y, FirstOrder(), BOUNDS, n=6, n_samples=400, rng=1, dtype=dtype, store=tmp_path / "d.nc")
    memory = dynia.run(u, y, FirstOrder(), BOUNDS, n=6, n_samples=400, rng=1, dtype=dtype)
    memory.save(tmp_path / "m.nc")
    for path in (tmp_path / "d.nc", tmp_path / "m.nc"):
        for lazy in (False, True):
            _identical(dynia.load(path, lazy=lazy), memory)


def test_a_lazy_load_checks_only_the_blocks_it_reads(tmp_path, monkeypatch):
    """A forged gradient in a late block: loading and reading early steps pass, reading the block refuses it."""
    monkeypatch.setattr(dynia.io.arrays, "_CHUNK_BYTES", 40 * 4 * 16)  # blocks of 16 steps
    path = tmp_path / "disk.nc"
    dynia.run(*stored_record(), FirstOrder(), BOUNDS, n=6, n_samples=400, rng=1, dtype="float32", store=path)
    _forge(path, "gradient", (0, 3, 100), -1.0)
    back = dynia.load(path, lazy=True)
    assert np.isfinite(back.gradient[0][:, 20:40]).all()
    with pytest.raises(DataError, match=r"gradient lies outside \[0, 1\]"):
        back.gradient[1][:, 90:110]


# --- a full disk ------------------------------------------------------------------------------------------


def _full_disk(monkeypatch, at):
    """Let the result file's writes fail with ENOSPC from the ``at``-th on; returns the list of attempts."""
    attempts = []
    write = dynia.io.arrays._pwrite

    def pwrite(descriptor, data, offset):
        attempts.append(len(data))
        if len(attempts) >= at:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return write(descriptor, data, offset)

    monkeypatch.setattr(dynia.io.arrays, "_pwrite", pwrite)
    return attempts


def _count_writes(monkeypatch, run):
    attempts = _full_disk(monkeypatch, at=np.inf)
    run()
    monkeypatch.undo()
    return len(attempts)


@pytest.mark.parametrize("where", ["first", "middle", "last"])
def test_a_full_disk_in_the_store_is_one_output_error_and_no_file(tmp_path, monkeypatch, capfd, where):
    path = tmp_path / "out" / "result.nc"
    path.parent.mkdir()

    def run():
        monkeypatch.setattr(dynia.io.arrays, "_CHUNK_BYTES", 40 * 4 * 16)  # several blocks, as a long record has
        return dynia.run(*stored_record(), FirstOrder(), BOUNDS, n=6, n_samples=400, rng=1, dtype="float32", store=path)

    total = _count_writes(monkeypatch, run)
    shutil.rmtree(path.parent)
    path.parent.mkdir()
    capfd.readouterr()
    _full_disk(monkeypatch, at={"first": 1, "middle": total // 2, "last": total}[where])
    with pytest.raises(OutputError) as caught:
        run()
    assert str(caught.value) == f"{path}: cannot be written (No space left on device)"
    assert os.listdir(path.parent) == []
    out, err = capfd.readouterr()
    assert out == err == ""


def test_a_full_disk_in_save_keeps_the_old_file(result, tmp_path, monkeypatch, capfd):
    path = tmp_path / "result.nc"
    path.write_bytes(b"the previous results")
    capfd.readouterr()
    _full_disk(monkeypatch, at=5)
    with pytest.raises(OutputError, match=r"result\.nc: cannot be written \(No space left on device\)$"):
        result.save(path)
    assert os.listdir(tmp_path) == ["result.nc"] and path.read_bytes() == b"the previous results"
    assert capfd.readouterr() == ("", "")


def test_a_full_disk_writing_a_table_is_one_error_naming_out(tmp_path, monkeypatch, capsys):
    data = write_text_file(tmp_path / "data.csv", GOOD)
    write_analysis = dynia.cli.report.write_analysis

    def full(directory, *args, **kwargs):
        write_analysis(directory, *args, **kwargs)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(dynia.cli.report, "write_analysis", full)
    out = tmp_path / "out"
    line = cli_one_error(*cli_analyse(capsys, data, *BASE, "--out", out), f"--out {out}", "No space left on device")
    assert "Traceback" not in line and sorted(os.listdir(tmp_path)) == ["data.csv"]


SITE = """
import errno, os
import dynia.io.arrays

_calls = []
_original_pwrite = dynia.io.arrays._pwrite


def _pwrite(descriptor, data, offset):
    _calls.append(1)
    if len(_calls) >= int(os.environ["DYNIA_TEST_FULL_AFTER"]):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    return _original_pwrite(descriptor, data, offset)


dynia.io.arrays._pwrite = _pwrite
"""


def _command(tmp_path, *, site=None, limit=None, after=None):
    data = write_text_file(tmp_path / "data.csv", GOOD)
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [site and str(site), str(ROOT)])))
    if after is not None:
        env["DYNIA_TEST_FULL_AFTER"] = str(after)

    def limited():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit then fails with EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    command = [sys.executable, "-m", "dynia.cli", "analyse", str(data), *BASE, "--dtype", "float32", "--on-disk"]
    finished = subprocess.run(
        [*command, "--out", str(out)],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        preexec_fn=limited if limit else None,
        timeout=600,
    )
    return finished, out


@pytest.mark.slow
@pytest.mark.parametrize("after", [1, 4])
def test_a_full_disk_on_the_command_line_is_one_error_line(tmp_path, after):
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text(textwrap.dedent(SITE))
    finished, out = _command(tmp_path, site=site, after=after)
    assert finished.returncode == 2, finished.stderr
    assert finished.stderr.splitlines() == [
        f"dynia: error: --out {out}: cannot write the results: result.nc: cannot be written (No space left on device)"
    ]
    assert sorted(os.listdir(tmp_path)) == ["data.csv", "site"]  # no out, no staging directory, no lock


@pytest.mark.slow
def test_a_file_size_limit_on_the_command_line_is_one_error_line(tmp_path):
    """A real write error from the system (EFBIG past RLIMIT_FSIZE): before, tracebacks and a segfault."""
    finished, out = _command(tmp_path, limit=20000)
    assert finished.returncode == 2, finished.stderr
    assert finished.stderr.splitlines() == [
        f"dynia: error: --out {out}: cannot write the results: result.nc: cannot be written (File too large)"
    ]
    assert sorted(os.listdir(tmp_path)) == ["data.csv"]
