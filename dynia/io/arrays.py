"""Where the result arrays live: in memory, or in a netCDF file written as the windows are analysed.

A year of 1 Hz data is 3e7 steps; its CLD gradient alone, (n_params, bins,
n_steps) in float64, needs 19 GB for two parameters and 40 bins. Two
settings of :class:`dynia.settings.AnalysisSettings` bound that:

``dtype="float32"``
    The time-dependent arrays (``ic``, ``ci``, ``median``, ``gradient``,
    ``ic_se``, ``ci_se``) are kept in float32: the engine still computes in float64,
    and every value is the float64 result rounded to the nearest float32
    (relative error at most 6e-8, far below any Monte Carlo error), at half
    the memory and disk.
``store=PATH``
    Those arrays go to the netCDF-4 file ``PATH`` as they are produced, in
    time blocks (:class:`ResultFile`), never whole in memory. The file has
    the layout :func:`dynia.io.writer.save` writes, chunked over time, so
    :func:`dynia.load` reads it, and the returned result reads it lazily:
    its time-dependent arrays are :class:`DiskArray` objects, which index
    like numpy arrays (``res.ic[p]`` reads one parameter's row) and turn into
    ndarrays wherever numpy needs one. The file is written under a temporary
    name beside ``PATH`` and renamed to ``PATH`` only when complete (for
    :func:`dynia.run`, with its verdicts), so an error or an interruption
    never leaves a half-written file under ``PATH``.

What still grows with the record, with a store: the time axis (8 bytes a
step), the caller's input and output, and one parameter's row of IC or of a
limit while the summary and the verdicts look for its maximum; the gradient
is read one time block at a time for plots and one column for estimates.

Examples
--------
>>> import numpy as np, tempfile, pathlib, dynia
>>> from dynia.engine import moving_window
>>> gain = np.random.default_rng(1).uniform(0, 4, (500, 1))
>>> u = np.r_[np.zeros(20), np.ones(40)]
>>> with tempfile.TemporaryDirectory() as folder:
...     path = pathlib.Path(folder, "result.nc")
...     res = moving_window(2 * u, gain * u, gain, [[0, 4]], n=3, dtype="float32", store=path)
...     kept = type(res.gradient).__name__, str(res.ic.dtype), res.ic[0].shape
...     same = np.array_equal(dynia.load(path).ic, res.ic, equal_nan=True)
>>> kept, same
(('DiskArray', 'float32', (60,)), True)
"""

import contextlib
import dataclasses
import os
import re
import secrets
import sys
import tempfile

import numpy as np
from numpy.lib.mixins import NDArrayOperatorsMixin

from ..errors import DataError, OutputError
from .layout import COORDINATES, SECONDS_ATTRIBUTES, TIME_VARIABLES, TIMESTAMP_ATTRIBUTES, metadata

__all__ = [
    "TIME_VARIABLES",
    "DiskArray",
    "ResultArrays",
    "ResultFile",
    "result_arrays",
    "write_result",
    "write_netcdf",
    "disk_arrays",
    "read_block",
    "PartialFile",
]


# Bytes of one on-disk chunk of the widest variable (the gradient of one parameter): large enough that
# a row of IC is read in few requests, small enough for HDF5's chunk cache and for the write buffer.
_CHUNK_BYTES = 4 * 2**20


def result_arrays(store, dtype):
    """Where an analysis keeps its arrays: :class:`ResultArrays` in memory, or a :class:`ResultFile` at ``store``.

    ``store`` may also be a :class:`ResultArrays` or :class:`ResultFile` already made, whose owner commits it.

    Examples
    --------
    >>> [type(result_arrays(store, "float32")).__name__ for store in (None, "result.nc")]
    ['ResultArrays', 'ResultFile']
    """
    if isinstance(store, ResultArrays):
        return store
    return ResultArrays(dtype) if store is None else ResultFile(store, dtype)


def _time_index(name, start, stop):
    """Index of the steps [start, stop) of variable ``name``."""
    axis = TIME_VARIABLES[name].index("time")
    return (slice(None),) * axis + (slice(start, stop),)


class ResultArrays:
    """The time-dependent result arrays in memory, NaN until written, in ``dtype``.

    Assigning float64 chunks into float32 arrays rounds each value to the nearest float32.
    """

    def __init__(self, dtype="float64"):
        self.dtype = np.dtype(dtype)
        self._arrays = {}

    def __enter__(self):
        return self

    def __exit__(self, kind, error, trace):
        if kind is not None:
            self.discard()

    def allocate(self, shapes, **fixed):
        """Make an array per ``shapes`` entry (a TIME_VARIABLES name to its shape); ``fixed`` is unused here.

        ``fixed`` holds the parts a file writes first (names, samples, bounds, time, bin_centres).
        """
        self._arrays = {name: np.full(shape, np.nan, dtype=self.dtype) for name, shape in shapes.items()}

    def write(self, start, stop, chunks):
        """Put each chunk of ``chunks`` (name to the values of steps [start, stop)) in place."""
        for name, chunk in chunks.items():
            self._arrays[name][_time_index(name, start, stop)] = chunk

    def arrays(self):
        """The arrays, by name."""
        return dict(self._arrays)

    def discard(self):
        """Drop the arrays (nothing is kept outside memory)."""
        self._arrays = {}

    def commit(self, result):
        """The finished ``result`` (in memory there is nothing more to write)."""
        return result


class ResultFile(ResultArrays):
    """Result arrays written to a netCDF-4 file as they are produced, then renamed into place.

    :meth:`allocate` creates ``.PATH.XXXX.partial`` beside ``PATH`` with
    every variable laid out as :func:`dynia.io.writer.save` writes it, the
    time-dependent ones chunked over time; :meth:`write` fills them block by
    block (a time block is buffered until its on-disk chunks are complete, so
    each chunk is written once); :meth:`commit` adds the time coordinate (the
    dates of a dated result), the settings and the verdicts of the finished result, renames the file to ``PATH`` and
    returns the result reading from it. :meth:`discard` (also on an error in
    ``with``) deletes the partial file.

    Every numeric variable carries a Fletcher-32 checksum, which
    :func:`dynia.load` verifies. Each block is flushed to disk as it is
    written, so that a write error (a full disk, a file size limit) is
    raised there, as an :class:`~dynia.errors.OutputError` naming ``path``,
    and not later from HDF5's caches where it cannot be reported; the
    partial file is then closed without a word from HDF5 and deleted.

    Parameters
    ----------
    path : str or os.PathLike
        The final file; replaced if it exists, when the commit succeeds.
    dtype : {"float64", "float32"}
        Type of the time-dependent arrays in the file.

    Examples
    --------
    Made by hand, the file waits for its owner's commit, here after the verdicts:

    >>> import dataclasses, tempfile, pathlib, numpy as np, dynia
    >>> from dynia.engine import moving_window
    >>> gain = np.random.default_rng(1).uniform(0, 4, (500, 1))
    >>> u = np.r_[np.zeros(20), np.ones(40)]
    >>> with tempfile.TemporaryDirectory() as folder, ResultFile(pathlib.Path(folder, "r.nc")) as output:
    ...     res = moving_window(2 * u, gain * u, gain, [[0, 4]], n=3, store=output)
    ...     waiting = sorted(path.suffix for path in pathlib.Path(folder).iterdir())
    ...     res = output.commit(dataclasses.replace(res, verdicts=dynia.verdicts.assess(res)))
    ...     done = sorted(path.name for path in pathlib.Path(folder).iterdir())
    ...     verdict = dynia.load(output.path).verdicts["p0"]["verdict"]
    >>> waiting, done, verdict
    (['.partial'], ['r.nc'], 'identified')
    """

    def __init__(self, path, dtype="float64"):
        super().__init__(dtype)
        self.path = os.path.abspath(os.fspath(path))
        self._partial = None
        self._h5 = None
        self._sink = None
        self._datasets = {}
        self._variables = {}
        self._buffers = {}
        self._block = 0
        self._block_start = 0
        self._n_steps = 0

    def allocate(self, shapes, *, names, samples, bounds, time, bin_centres):
        """Create the partial file with its fixed parts and the empty time-dependent variables of ``shapes``.

        Called again (a retried analysis), it starts a new file.
        """
        import h5py

        self.discard()
        folder, base = os.path.split(self.path)
        if os.path.isdir(self.path):
            raise OutputError(f"{self.path}: is a folder; store must name a file")
        try:
            handle, self._partial = tempfile.mkstemp(prefix=f".{base}.", suffix=".partial", dir=folder)
            os.close(handle)
        except OSError as error:
            self._partial = None
            raise OutputError(f"{self.path}: cannot be written ({error.strerror or error})") from None
        with self._writing():
            # The h5py file is ours, h5netcdf only lays out the variables (_netcdf): after a write error it is
            # closed without h5netcdf's final writes, and HDF5 writes through a PartialFile, which can be abandoned.
            self._sink = PartialFile(self._partial)
            self._h5 = h5py.File(self._sink, "w", track_order=True)
            with _netcdf(self._h5, "w") as file:
                self._create(file, shapes, names, samples, bounds, time, bin_centres)
            self._h5.flush()

    def _create(self, file, shapes, names, samples, bounds, time, bin_centres):
        import h5py

        samples, bounds, time = np.asarray(samples), np.asarray(bounds), np.asarray(time)
        n_bins = shapes["gradient"][1]
        self._n_steps = time.size
        self._block = int(min(max(_CHUNK_BYTES // (n_bins * self.dtype.itemsize), 1), max(self._n_steps, 1)))
        file.dimensions = dict(parameter=len(names), time=self._n_steps, side=2, bin=n_bins, sample=samples.shape[0])
        file.create_variable("parameter", ("parameter",), dtype=h5py.string_dtype(), data=np.array(names, dtype=object))
        file.create_variable(
            "side", ("side",), dtype=h5py.string_dtype(), data=np.array(["lower", "upper"], dtype=object)
        )
        # The time variable waits for the commit (_describe): whether it holds seconds or dates is known then.
        for name, data, dims in (
            ("samples", samples, ("sample", "parameter")),
            ("bounds", bounds, ("parameter", "side")),
            ("bin_centres", bin_centres, ("parameter", "bin")),
        ):
            file.create_variable(name, dims, dtype="f8", data=data, fletcher32=True)
        self._buffers = {}
        for name, shape in shapes.items():
            chunks = tuple(
                self._block if dim == "time" else (1 if dim == "parameter" else size)
                for dim, size in zip(TIME_VARIABLES[name], shape)
            )
            file.create_variable(name, TIME_VARIABLES[name], dtype=self.dtype, chunks=chunks, fletcher32=True)
            buffer_shape = tuple(
                self._block if dim == "time" else size for dim, size in zip(TIME_VARIABLES[name], shape)
            )
            self._buffers[name] = np.full(buffer_shape, np.nan, dtype=self.dtype)
        # Held open, so that no dataset closes (writing its cached chunks) when a temporary handle dies.
        self._datasets = {name: self._h5[name] for name in self._buffers}
        self._block_start = 0

    @contextlib.contextmanager
    def _writing(self):
        """Turn a write error into an OutputError naming ``path``, the partial file discarded."""
        try:
            yield
            if self._sink is not None:
                self._sink.check()
        except (OSError, RuntimeError) as error:
            reason = write_error(self._sink.error if self._sink is not None and self._sink.error else error)
            self.discard()
            raise OutputError(f"{self.path}: cannot be written ({reason})") from None

    def write(self, start, stop, chunks):
        """Write ``chunks`` (name to the values of steps [start, stop)); steps must come in order.

        Values are buffered until a time block is complete, then written to
        the file in one piece.
        """
        at = start
        while at < stop:
            block_stop = min(self._block_start + self._block, self._n_steps)
            end = min(stop, block_stop)
            for name, chunk in chunks.items():
                self._buffers[name][_time_index(name, at - self._block_start, end - self._block_start)] = chunk[
                    _time_index(name, at - start, end - start)
                ]
            if end == block_stop:
                self._flush(block_stop)
            at = end

    def _flush(self, block_stop):
        width = block_stop - self._block_start
        with self._writing():
            for name, buffer in self._buffers.items():
                self._datasets[name][_time_index(name, self._block_start, block_stop)] = buffer[
                    _time_index(name, 0, width)
                ]
                buffer.fill(np.nan)
            self._h5.flush()
        self._block_start = block_stop

    def arrays(self):
        """The variables written, as :class:`DiskArray` objects on the partial file."""
        with self._writing():
            self._h5.flush()
        self._variables = {name: _Variable(self._datasets[name], self._partial, name) for name in self._buffers}
        return {name: DiskArray(variable) for name, variable in self._variables.items()}

    def commit(self, result):
        """Add ``result``'s time coordinate, settings and verdicts, rename the file to ``path``, return it read lazily.

        ``result`` is the finished result whose arrays this file holds.
        """
        attrs, variables = metadata(
            result, reserved=(*TIME_VARIABLES, *COORDINATES, "samples", "bounds", "bin_centres")
        )
        with self._writing():
            with _netcdf(self._h5, "a") as file:
                self._describe(file, result, attrs, variables)
            self._datasets = {}
            self._h5.close()
            self._sink.check()  # HDF5's last writes, at its close
            self._sink.close()
            self._h5 = self._sink = None
            os.replace(self._partial, self.path)
        self._partial = None
        # The arrays handed out before move with the file; the rest stays as the result holds it.
        reopened = disk_arrays(self.path, self._variables)
        for name, variable in self._variables.items():
            variable.dataset, variable.filename = reopened[name]._variable.dataset, self.path
        committed = {name: DiskArray(variable) for name, variable in self._variables.items()}
        self._variables = {}  # a later discard (a reuse of this object) leaves the committed file alone
        return dataclasses.replace(result, **committed)

    def _describe(self, file, result, attrs, variables):
        """Write the time coordinate, the settings' array variables and the attributes through the h5netcdf ``file``.

        ``time`` holds the seconds, or for a result with timestamps the dates, with the seconds as ``elapsed``
        (the layout of :mod:`dynia.io.layout`).
        """
        seconds = {"dtype": "f8", "data": np.asarray(result.time, dtype=float)}
        if result.timestamps is None:
            times = {"time": (seconds, SECONDS_ATTRIBUTES)}
        else:
            dates = np.asarray(result.timestamps, dtype="datetime64[ns]").view(np.int64)
            times = {
                "time": ({"dtype": "i8", "data": dates}, TIMESTAMP_ATTRIBUTES),
                "elapsed": (seconds, SECONDS_ATTRIBUTES),
            }
        for name, (values, attributes) in times.items():
            variable = file.create_variable(name, ("time",), chunks=(self._block,), fletcher32=True, **values)
            variable.attrs.update(attributes)
        for name, (dims, values) in variables.items():
            for axis, dim in enumerate(dims):
                if dim not in file.dimensions:
                    file.dimensions[dim] = values.shape[axis]
            file.create_variable(name, dims, data=values, fletcher32=values.dtype.kind in "biuf")
        file.attrs.update(attrs)

    def discard(self):
        """Close and delete the partial file, if any; arrays read from it raise :class:`~dynia.errors.DataError`."""
        # After a write error HDF5 fails again on every close, and h5py prints each failure: silenced, as the
        # file is deleted next and the error that matters is the one being raised.
        if self._sink is not None:
            self._sink.abandon()
        with _quiet():
            for variable in self._variables.values():
                variable.dataset = None
            self._variables = {}
            self._datasets = {}
            if self._h5 is not None:
                try:
                    self._h5.close()
                except Exception:
                    pass
                self._h5 = None
        if self._sink is not None:
            self._sink.close()
            self._sink = None
        if self._partial is not None:
            try:
                os.remove(self._partial)
            except FileNotFoundError:
                pass
            self._partial = None


class PartialFile:
    """A file being written, as h5py's ``fileobj`` driver writes it: the first write error abandons it.

    HDF5 writes from its caches whenever it closes an object, and after a
    write error (a full disk) every such write fails again: h5py prints each
    failure, and the library can crash at exit while it still holds the
    file. Here the first failing write is kept in ``error`` and the file
    abandoned: that write and every later one succeed for HDF5 without
    touching the disk, so HDF5 goes on and lets go of the file quietly, and
    the writer raises ``error`` at its next check (:meth:`check`). A
    file about to be deleted is abandoned too (:meth:`abandon`).
    """

    def __init__(self, path):
        # 0o666: the permissions the umask gives, as a file written in place would get.
        self._descriptor = os.open(path, os.O_RDWR | os.O_CREAT | os.O_TRUNC, 0o666)
        self._position = 0
        self.error = None
        self.abandoned = False

    def seek(self, offset, whence=os.SEEK_SET):
        self._position = os.lseek(self._descriptor, offset, whence)
        return self._position

    def tell(self):
        return self._position

    def readinto(self, buffer):
        data = os.pread(self._descriptor, len(memoryview(buffer).cast("B")), self._position)
        memoryview(buffer).cast("B")[: len(data)] = data
        self._position += len(data)
        return len(data)

    def read(self, size=-1):
        size = os.fstat(self._descriptor).st_size - self._position if size is None or size < 0 else size
        data = os.pread(self._descriptor, size, self._position)
        self._position += len(data)
        return data

    def write(self, data):
        data = memoryview(data).cast("B")
        if not self.abandoned:
            try:
                written = 0
                while written < len(data):
                    written += _pwrite(self._descriptor, data[written:], self._position + written)
            except OSError as error:
                self._failed(error)
        self._position += len(data)
        return len(data)

    def truncate(self, size=None):
        if not self.abandoned:
            try:
                os.ftruncate(self._descriptor, self._position if size is None else size)
            except OSError as error:
                self._failed(error)
        return size

    def _failed(self, error):
        # Raised here, the error would reach HDF5 as a failed write, and the storm described above would follow.
        self.error = error
        self.abandoned = True

    def check(self):
        """Raise the write error, if a write failed."""
        if self.error is not None:
            raise self.error

    def flush(self):
        pass  # every write went to the system at once

    def abandon(self):
        """Write nothing from now on: the file is going to be deleted."""
        self.abandoned = True

    def close(self):
        if self._descriptor is not None:
            os.close(self._descriptor)
            self._descriptor = None


def _pwrite(descriptor, data, offset):
    """``os.pwrite``: where the tests make the disk fill up."""
    return os.pwrite(descriptor, data, offset)


@contextlib.contextmanager
def _netcdf(h5file, mode):
    """An h5netcdf view of the open h5py ``h5file``, to create variables with their netCDF dimensions.

    Closed on leaving (its attributes go into HDF5's cache; the owner's flush reports any write error). On an
    error it is marked closed instead: its close, and its ``__del__``, would write again into a file that failed.
    """
    import h5netcdf

    file = h5netcdf.File(h5file, mode)
    try:
        yield file
        file.close()
    except BaseException:
        file._closed = True
        raise


@contextlib.contextmanager
def _quiet():
    """Nothing printed to stderr, nor as an unraisable exception (h5py's objects failing to close)."""
    import gc

    stderr, hook = sys.stderr, sys.unraisablehook
    sys.stderr, sys.unraisablehook = open(os.devnull, "w"), lambda unraisable: None
    try:
        yield
        gc.collect()  # objects of the closed file that die now die quietly
    finally:
        sys.stderr.close()
        sys.stderr, sys.unraisablehook = stderr, hook


def write_error(error):
    """The reason of a write ``error`` in a few words: the system's message (HDF5 puts it in its text)."""
    if isinstance(error, OSError) and error.errno is not None:
        return error.strerror or os.strerror(error.errno)
    found = re.search(r"error message = '([^']*)'", str(error))
    if found:
        return found.group(1)
    return str(error).splitlines()[0] if str(error) else type(error).__name__


def write_netcdf(write, path):
    """Call ``write(file)`` to write a file beside ``path`` (``file`` a :class:`PartialFile`), then rename it.

    On a write error the partial file is deleted, HDF5 kept quiet (see
    :class:`PartialFile`), and an :class:`~dynia.errors.OutputError` names
    ``path``, which is left as it was.
    """
    path = os.path.abspath(os.fspath(path))
    folder, base = os.path.split(path)
    partial = os.path.join(folder, f".{base}.{os.getpid()}-{secrets.token_hex(4)}.partial")
    try:
        sink = PartialFile(partial)
    except OSError as error:
        raise OutputError(f"{path}: cannot be written ({error.strerror or error})") from None
    try:
        try:
            write(sink)
            sink.check()
        except BaseException:
            sink.abandon()
            with _quiet():  # what the failed write leaves open is closed, quietly
                pass
            raise
        finally:
            sink.close()
        os.replace(partial, path)
    except (OSError, RuntimeError) as error:
        _remove(partial)
        raise OutputError(f"{path}: cannot be written ({write_error(sink.error or error)})") from None
    except BaseException:
        _remove(partial)
        raise


def _remove(path):
    try:
        os.remove(path)
    except FileNotFoundError:
        pass


def write_result(result, path, dtype=None):
    """Write ``result`` to ``path`` through a :class:`ResultFile`, one time block at a time.

    How :func:`dynia.io.writer.save` writes a result whose arrays are on disk
    (:class:`DiskArray`), so that saving it elsewhere never loads them whole.
    ``dtype`` defaults to that of ``result.ic``.
    """
    present = {name: getattr(result, name) for name in TIME_VARIABLES if getattr(result, name) is not None}
    with ResultFile(path, dtype or present["ic"].dtype) as file:
        file.allocate(
            {name: array.shape for name, array in present.items()},
            names=result.names,
            samples=result.samples,
            bounds=result.bounds,
            time=result.time,
            bin_centres=result.bin_centres,
        )
        for start in range(0, result.time.size, file._block):
            stop = min(start + file._block, result.time.size)
            file.write(start, stop, {name: array[_time_index(name, start, stop)] for name, array in present.items()})
        return file.commit(result)


def disk_arrays(path, names, check=None):
    """The variables ``names`` of the netCDF file ``path`` as :class:`DiskArray` objects, by name.

    ``check``, when given, is called as ``check(name, file, start, stop)``
    (``file`` the open h5py file) for each on-disk block of steps
    [start, stop) the first time a read touches it, and raises to refuse
    the block (:func:`dynia.load` checks its ranges so).
    """
    import h5py

    file = h5py.File(path, "r")
    return {name: DiskArray(_Variable(file[name], path, name, check)) for name in names}


# Steps checked at once along time in a variable stored without chunks (files of other writers).
_CHECK_BLOCK = 2**16


def read_block(file, name, start, stop):
    """Steps [start, stop) of variable ``name`` (one of TIME_VARIABLES) of the open h5py ``file``, all parameters."""
    return _read(file[name], _time_index(name, start, stop), file.filename, name)


def _read(dataset, index, filename, name):
    """``dataset[index]``; a DataError naming the file when HDF5 cannot read it (a checksum that fails)."""
    try:
        return np.asarray(dataset[index])
    except OSError as error:
        raise DataError(
            f"{filename}: {name} cannot be read ({str(error).splitlines()[0]}); the file is damaged or was altered"
        ) from None


class _Variable:
    """What DiskArrays read: a variable of a file, moved with the file when it is renamed, gone when deleted.

    With ``check`` (see :func:`disk_arrays`) each block along time is checked on the first read that touches it.
    """

    def __init__(self, dataset, filename, name, check=None):
        self.dataset = dataset
        self.filename = os.fspath(filename)
        self.name = name
        self.check = check
        self._checked = None
        self._layout = None
        self._all_checked = False

    def opened(self):
        if self.dataset is None:
            raise DataError(
                f"{self.name!r} of {self.filename}: the file was deleted, as its analysis did not finish (an error, "
                "an interruption, or a retry with other samples); use the result the analysis returned"
            )
        return self.dataset

    def read(self, index):
        """``index`` of the variable (a tuple over all its axes or fewer), its blocks checked first."""
        dataset = self.opened()
        if self.check is not None and not self._all_checked:
            if self._checked is None:  # the layout, read once: HDF5 answers each question at a cost
                axis = TIME_VARIABLES[self.name].index("time")
                block = dataset.chunks[axis] if dataset.chunks else _CHECK_BLOCK
                self._layout = (dataset.ndim, axis, dataset.shape[axis], block)
                self._checked = np.zeros(-(-dataset.shape[axis] // block), dtype=bool)
            ndim, axis, n_steps, block = self._layout
            span = _time_span(index, ndim, axis, n_steps)
            if span is not None:
                for number in range(span[0] // block, (span[1] - 1) // block + 1):
                    if not self._checked[number]:
                        self.check(self.name, dataset.file, number * block, min((number + 1) * block, n_steps))
                        self._checked[number] = True
                self._all_checked = bool(self._checked.all())
        return _read(dataset, index, self.filename, self.name)


def _time_span(index, ndim, axis, n_steps):
    """Steps [first, last + 1) that ``index`` reads along ``axis``; None when it reads none."""
    if any(item is None for item in index) or sum(item is Ellipsis for item in index) > 1:
        return (0, n_steps) if n_steps else None  # unusual indices: check every block, h5py judges the index
    ellipsis = [at for at, item in enumerate(index) if item is Ellipsis]  # not `in`: arrays compare elementwise
    if ellipsis:
        at = ellipsis[0]
        index = index[:at] + (slice(None),) * (ndim - len(index) + 1) + index[at + 1 :]
    item = index[axis] if axis < len(index) else slice(None)
    if isinstance(item, slice):
        steps = range(*item.indices(n_steps))
        return (min(steps[0], steps[-1]), max(steps[0], steps[-1]) + 1) if len(steps) else None
    steps = np.asarray(item)
    steps = np.flatnonzero(steps) if steps.dtype == bool else steps.astype(np.int64, copy=False) % max(n_steps, 1)
    return (int(steps.min()), int(steps.max()) + 1) if steps.size else None


class DiskArray(NDArrayOperatorsMixin):
    """A numpy-like view of an array in an HDF5 file, read only where indexed.

    Indexing with whole numbers on leading axes alone (``gradient[p]``) gives
    another DiskArray; any other index reads those values into an ndarray.
    ``np.asarray`` reads the whole view; numpy functions and arithmetic read
    their operands first. A DiskArray pickles as its file name and variable,
    so it can be sent to another process on the same file system.
    """

    def __init__(self, variable, leading=()):
        self._variable = variable
        self._leading = tuple(leading)

    @property
    def filename(self):
        """The file read."""
        return self._variable.filename

    @property
    def name(self):
        """The variable read."""
        return self._variable.name

    @property
    def shape(self):
        return self._variable.opened().shape[len(self._leading) :]

    @property
    def dtype(self):
        return self._variable.opened().dtype

    @property
    def ndim(self):
        return len(self.shape)

    @property
    def size(self):
        return int(np.prod(self.shape))

    def __len__(self):
        return self.shape[0]

    def __getitem__(self, key):
        key = key if isinstance(key, tuple) else (key,)
        if (
            all(isinstance(item, (int, np.integer)) and not isinstance(item, bool) for item in key)
            and len(key) < self.ndim
        ):
            leading = []
            for axis, item in enumerate(key):
                size = self.shape[axis]
                if not -size <= item < size:
                    raise IndexError(f"index {item} is out of bounds for axis {axis} with size {size}")
                leading.append(int(item) % size)
            return DiskArray(self._variable, self._leading + tuple(leading))
        try:
            return self._variable.read(self._leading + key)
        except DataError:
            raise
        except (TypeError, ValueError):
            # Selections HDF5 cannot make (fancy indices out of order, repeated): read the view, index in memory.
            return np.asarray(self)[key]

    def ravel(self):
        """The whole view read, flattened (as ``ndarray.ravel``)."""
        return np.asarray(self).ravel()

    def astype(self, dtype):
        """The whole view read, as ``dtype``."""
        return np.asarray(self).astype(dtype)

    def __array__(self, dtype=None, copy=None):
        values = self._variable.read(self._leading + (Ellipsis,))
        return values if dtype is None else values.astype(dtype, copy=False)

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        inputs = tuple(np.asarray(item) if isinstance(item, DiskArray) else item for item in inputs)
        return getattr(ufunc, method)(*inputs, **kwargs)

    def __reduce__(self):
        return _reopened, (self.filename, self.name, self._leading, self._variable.check)

    def __repr__(self):
        return f"DiskArray({self.name!r} in {self.filename!r}, shape={self.shape}, dtype={self.dtype})"


def _reopened(filename, name, leading, check=None):
    import h5py

    return DiskArray(_Variable(h5py.File(filename, "r")[name], filename, name, check), leading)
