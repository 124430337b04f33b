"""Results back in: :func:`load` (``dynia.load``) reads a result file into the
:class:`~dynia.result.DyniaResult` it came from, every array bit for bit, and checks it.

The file is laid out as :mod:`dynia.io.layout` describes and written by
:func:`dynia.io.writer.save` (:meth:`~dynia.result.DyniaResult.save`). A damaged or
altered file is a :class:`~dynia.errors.DataError` naming the file and what is wrong;
stored verdicts that the arrays no longer give, and settings no run records, are
warnings (:class:`StoredVerdictsWarning`, :class:`StoredSettingsWarning`).

Examples
--------
>>> import numpy as np, tempfile, pathlib, dynia
>>> limits = np.array([[[np.nan, np.nan], [0.1, 0.9], [0.25, 0.75], [0.05, 0.95]]])
>>> gradient = np.array([[[np.nan, 0.5, 0.5, 0.5], [np.nan, 0.5, 0.5, 0.5]]])
>>> res = dynia.DyniaResult(names=("K",), samples=np.zeros((3, 1)), bounds=np.array([[0.0, 1.0]]),
...                         time=np.arange(4.0), ic=1 - (limits[..., 1] - limits[..., 0]),
...                         ci=limits, gradient=gradient, bin_centres=np.array([[0.25, 0.75]]),
...                         settings=dict(n=1, n_samples=3, percentage=100))
>>> res.to_xarray().ic.dims
('parameter', 'time')
>>> with tempfile.TemporaryDirectory() as folder:
...     res.save(pathlib.Path(folder, "result.nc"))
...     back = dynia.load(pathlib.Path(folder, "result.nc"))
>>> back.settings == res.settings, back.settings.n, back.ic.round(2)
(True, 1, array([[nan, 0.2, 0.5, 0.1]]))
"""

import dataclasses
import functools
import json
import numbers
import os
import warnings
from collections.abc import Mapping

import numpy as np

from ..errors import DataError, SettingsError
from ..result import DyniaResult, timestamps_problem
from ..settings import AnalysisSettings, RunRecord
from ..verdicts import VERDICTS, assess
from .arrays import disk_arrays, read_block
from .layout import (
    ARRAYS,
    FORMAT_VERSION,
    NOISE_FLOOR,
    OPTIONAL_ARRAYS,
    TIME_VARIABLES,
    TIMESTAMP_UNITS,
    VARIABLE_TAG,
    MalformedAttribute,
    decoded,
)

__all__ = [
    "load",
    "StoredVerdictsWarning",
    "StoredSettingsWarning",
]


def load(path, *, lazy=False):
    """The :class:`~dynia.result.DyniaResult` that :func:`~dynia.io.writer.save` wrote to ``path``, checked.

    Every array comes back bit-identical (NaN where NaN), with the names, the
    timestamps, the settings (:class:`~dynia.settings.AnalysisSettings`), the
    run record (:class:`~dynia.settings.RunRecord`) and the verdicts equal
    to those saved: in the verdicts a tuple comes back a tuple and a list a
    list, a numpy scalar as the Python number it was written as. Files of
    the layout before the record, and of format version 1 (dates beside
    ``time``, not in it), load too (see :mod:`dynia.io.layout`).

    With ``lazy=True`` the arrays along time (IC, limits, median, gradient
    and their errors) stay in the file as :class:`dynia.io.arrays.DiskArray` objects,
    read where indexed: for results larger than memory (:mod:`dynia.io.arrays`).

    Nothing in the file is trusted. The arrays carry Fletcher-32 checksums
    (files written before them load unchecked); every array is checked
    against what an analysis can produce (``check_time_block`` and the
    rules for the fixed arrays); the verdicts are derived again from the
    arrays (:func:`dynia.verdicts.assess`): a stored verdict that agrees
    with its derived one, in verdict and reason codes, is kept (with its
    texts, which may write times as the data file did); one that does not
    (forged, or written by a dynia whose rules differed) is replaced by the
    derived one, with a :class:`StoredVerdictsWarning`. A lazy load checks the fixed arrays at once and the arrays
    along time one on-disk block at a time, when a read first touches the
    block, so it stays as fast as the reads it is asked for; its verdicts
    (``DeferredVerdicts``) are checked when first used, which reads IC
    (all of it) and some limits, once.

    Raises
    ------
    DataError
        ``path`` is missing, not netCDF-4, or not a result written by
        :func:`~dynia.io.writer.save` (of this format version or an earlier one); or any part
        of it is malformed, fails its checksum, or holds a value no analysis
        gives. The message names the
        file and the part. With ``lazy=True``, reads of a block that fails
        its checksum or its ranges raise it too.

    Examples
    --------
    See :mod:`dynia.io.reader`.
    """
    import xarray as xr

    name = os.fspath(path)
    if not os.path.isfile(name):
        kind = (
            "no such file"
            if not os.path.exists(name)
            else "is a directory"
            if os.path.isdir(name)
            else "is not a regular file (a device, a pipe or a socket)"
        )
        raise DataError(f"{name}: {kind}; expected a netCDF file written by DyniaResult.save")
    try:
        dataset = xr.open_dataset(
            name, engine="h5netcdf", mask_and_scale=False, decode_times=False, decode_timedelta=False
        )
    except (OSError, ValueError) as error:
        raise DataError(
            f"{name}: cannot be read as netCDF-4 ({error}); expected a file written by DyniaResult.save"
        ) from None
    with dataset:
        return _result(name, dataset, lazy)


def _result(name, dataset, lazy):
    """The checked result of the open ``dataset`` of file ``name`` (see :func:`load`)."""
    version = dataset.attrs.get("dynia_result")
    if not isinstance(version, numbers.Integral) or not 1 <= version <= FORMAT_VERSION:
        found = "no dynia_result attribute" if version is None else f"format version {version}"
        raise DataError(
            f"{name}: {found}; expected a result written by DyniaResult.save (format version {FORMAT_VERSION} "
            "or earlier)"
        )
    missing = [key for key in (*ARRAYS, "parameter", "time") if key not in dataset.variables]
    missing += [key for key in ("settings", "verdicts") if key not in dataset.attrs]
    if missing:
        raise DataError(f"{name}: has no {', '.join(map(repr, missing))}; expected every part of a saved result")
    if dataset.sizes.get("side") != 2:
        raise DataError(f"{name}: dimension 'side' has {dataset.sizes.get('side')} entries; expected lower, upper")
    names = tuple(str(label) for label in _values(name, dataset, "parameter", ("parameter",)))
    settings, run = _typed_settings(name, _settings(name, dataset))
    stored_verdicts = _attribute(name, dataset, "verdicts", (dict, type(None)), "an object or null")
    eager = {key: dims for key, dims in ARRAYS.items() if not (lazy and key in _TIME_ARRAYS)}
    eager.update(
        (key, dims) for key, dims in OPTIONAL_ARRAYS.items() if key in dataset and not (lazy and key in _TIME_ARRAYS)
    )
    arrays = {key: _values(name, dataset, key, dims) for key, dims in eager.items()}
    time, timestamps = _time(name, dataset)
    _check_fixed(name, names, time, arrays)
    # An older file's floor (mae_spread) tested another statistic: it loads as no floor, not as this one.
    if "discrimination" in dataset:
        arrays.update((key, _values(name, dataset, key, ("time",))) for key in NOISE_FLOOR if key in dataset)
        _check_floor(name, arrays)
        if "informative" in arrays:
            arrays["informative"] = arrays["informative"].astype(bool)
    spans = np.ptp(arrays["samples"], axis=0) if arrays["samples"].size else np.zeros(len(names))
    if lazy:
        arrays.update(_lazy(name, dataset, names, arrays["bounds"], spans))
    else:
        along_time = {key: arrays[key] for key in _TIME_ARRAYS if key in arrays}
        for key, values in along_time.items():
            check_time_block(name, names, arrays["bounds"], spans, key, values, along_time)
    result = DyniaResult(names=names, time=time, settings=settings, run=run, timestamps=timestamps, **arrays)
    if stored_verdicts is None:
        return result
    _check_verdict_form(name, result, stored_verdicts)
    if lazy:
        return dataclasses.replace(result, verdicts=DeferredVerdicts(name, result, stored_verdicts))
    return dataclasses.replace(result, verdicts=_checked_verdicts(name, result, stored_verdicts))


def _time(name, dataset):
    """The seconds of each step and the dates (datetime64[ns], None for an undated result) of the file.

    A version 2 file of a dated result holds the dates in ``time`` and the seconds in ``elapsed``; any other
    file the seconds in ``time`` and, a version 1 file of a dated result, the dates in ``timestamp``.
    """
    dated = dataset.attrs["dynia_result"] >= 2 and dataset["time"].attrs.get("units") == TIMESTAMP_UNITS
    if dated:
        if "elapsed" not in dataset.variables:
            raise DataError(f"{name}: time holds dates but the file has no 'elapsed'; expected the seconds there")
        if "timestamp" in dataset.variables:
            raise DataError(f"{name}: time holds dates and the file has a 'timestamp' too; expected the dates once")
        seconds, where = _values(name, dataset, "elapsed", ("time",)), "time"
    else:
        seconds, where = _values(name, dataset, "time", ("time",)), "timestamp"
    stamps = _timestamps(name, dataset, where) if dated or where in dataset.variables else None
    # Seconds that are not finite and rising are refused by the check of the fixed arrays.
    if stamps is not None and seconds.dtype.kind == "f" and np.isfinite(seconds).all():
        problem = timestamps_problem(seconds, stamps)
        if problem is not None:
            raise DataError(f"{name}: the dates in {where} {problem}; {_DAMAGED}")
    return seconds, stamps


def _timestamps(name, dataset, key):
    """Variable ``key`` of int64 nanoseconds since 1970-01-01 as datetime64[ns]; a DataError for anything else."""
    units = dataset[key].attrs.get("units")
    if units != TIMESTAMP_UNITS:
        raise DataError(f"{name}: {key} has units {units!r}; expected {TIMESTAMP_UNITS!r}")
    stamps = _values(name, dataset, key, ("time",))
    if stamps.dtype.kind not in "iu":
        raise DataError(f"{name}: {key} holds {stamps.dtype}; expected int64 nanoseconds")
    return stamps.astype(np.int64).view("datetime64[ns]")


# The arrays along time: checked block by block (check_time_block), read lazily with lazy=True.
_TIME_ARRAYS = tuple(TIME_VARIABLES)
_DAMAGED = "the file is damaged or was altered"


def _values(name, dataset, key, dims):
    """Variable ``key`` read whole in the order ``dims``; a DataError for other dimensions or a failed checksum."""
    variable = dataset[key]
    if set(variable.dims) != set(dims) or len(variable.dims) != len(dims):
        raise DataError(f"{name}: {key} has dimensions {variable.dims}; expected {dims}")
    try:
        values = variable.transpose(*dims).values
    except (OSError, RuntimeError) as error:
        raise DataError(f"{name}: {key} cannot be read ({_first_line(error)}); {_DAMAGED}") from None
    if values.dtype.kind not in "bfiuSUO":
        raise DataError(f"{name}: {key} holds {values.dtype}; expected numbers")
    return values


def _first_line(error):
    return str(error).splitlines()[0] if str(error) else type(error).__name__


def _attribute(name, dataset, key, kinds, expected):
    """JSON attribute ``key`` decoded; a DataError unless it is JSON text of a value of type ``kinds``."""
    text = dataset.attrs[key]
    if not isinstance(text, str):
        raise DataError(f"{name}: attribute {key!r} holds {type(text).__name__} {text!r}; expected JSON text")
    try:
        value = json.loads(text, object_hook=decoded)
    except MalformedAttribute as error:
        raise DataError(f"{name}: attribute {key!r}: {error}; expected JSON as DyniaResult.save writes it") from None
    except ValueError as error:
        raise DataError(f"{name}: attribute {key!r} is not JSON ({error}); expected JSON text") from None
    except RecursionError:
        raise DataError(
            f"{name}: attribute {key!r} nests its JSON deeper than Python can read; "
            "expected JSON as DyniaResult.save writes it (a few levels)"
        ) from None
    if not isinstance(value, kinds):
        raise DataError(f"{name}: attribute {key!r} holds a JSON {type(value).__name__}; expected {expected}")
    return value


def _settings(name, dataset):
    """The settings attribute, with array settings read from their variables."""
    settings = {}
    for key, value in _attribute(name, dataset, "settings", dict, "an object").items():
        if isinstance(value, dict) and VARIABLE_TAG in value:
            variable = value[VARIABLE_TAG]
            if value.keys() != {VARIABLE_TAG} or not isinstance(variable, str) or variable not in dataset.variables:
                raise DataError(
                    f"{name}: settings[{key!r}] is {value!r}; expected {{{VARIABLE_TAG!r}: the name of a variable of "
                    "the file}"
                )
            value = _values(name, dataset, variable, dataset[variable].dims)
        settings[key] = value
    return settings


def _typed_settings(name, stored):
    """The :class:`~dynia.settings.AnalysisSettings` (None when the file has none) and the record of ``stored``."""
    stored = dict(stored)
    stored.pop("bounds", None)  # written before the record: the same ranges as the bounds variable
    if stored.get("flavour") == "thesis-code":  # written before the record had thesis_code
        stored.update(flavour="thesis", thesis_code=True)
    setting_names = [field.name for field in dataclasses.fields(AnalysisSettings)]
    record_names = [field.name for field in dataclasses.fields(RunRecord)]
    unknown = [key for key in stored if key not in setting_names and key not in record_names]
    if unknown:
        warnings.warn(
            f"{name}: settings {', '.join(map(repr, unknown))} are neither analysis settings nor part of a run's "
            "record; loaded without them (a result saved by an older dynia with settings of its own)",
            StoredSettingsWarning,
            stacklevel=4,
        )
    try:
        given = {key: stored[key] for key in setting_names if key in stored}
        settings = AnalysisSettings(**given) if given else None
        run = RunRecord(**{key: stored[key] for key in record_names if key in stored})
    except SettingsError as error:
        raise DataError(f"{name}: attribute 'settings': {error}; {_DAMAGED}") from None
    return settings, run


def _check_fixed(name, names, time, arrays):
    """The arrays that do not lie along time: shapes, finite, samples and bin centres within bounds, time rising."""
    n_params = len(names)
    if len(set(names)) != n_params:
        raise DataError(f"{name}: parameter names {list(names)} repeat; {_DAMAGED}")
    bounds = arrays["bounds"]
    if bounds.dtype.kind != "f" or not np.isfinite(bounds).all() or not (bounds[:, 0] < bounds[:, 1]).all():
        raise DataError(f"{name}: bounds {bounds.tolist()} are not finite low < high pairs; {_DAMAGED}")
    if time.dtype.kind != "f" or not np.isfinite(time).all() or not (np.diff(time) > 0).all():
        raise DataError(f"{name}: time is not finite and rising; {_DAMAGED}")
    for key in ("samples", "bin_centres"):
        values = arrays[key]
        along = values.T if key == "samples" else values
        outside = ~((along >= bounds[:, :1]) & (along <= bounds[:, 1:]))
        if values.dtype.kind != "f" or outside.any():
            p = int(np.argwhere(outside)[0][0]) if outside.any() else 0
            raise DataError(
                f"{name}: {key} of {names[p]!r} lie outside its bounds {bounds[p].tolist()} or are not numbers; "
                f"{_DAMAGED}"
            )


def _check_floor(name, arrays):
    """The noise floor: the mask 0 or 1, the statistics non-negative (NaN where a window has none)."""
    informative = arrays.get("informative")
    if informative is not None and not np.isin(informative, (0, 1)).all():
        raise DataError(f"{name}: informative holds values other than 0 and 1; {_DAMAGED}")
    for key in NOISE_FLOOR[1:]:
        values = arrays.get(key)
        if values is not None and (values.dtype.kind != "f" or (values < 0).any() or np.isinf(values).any()):
            raise DataError(f"{name}: {key} holds negative or infinite values; expected >= 0 or NaN; {_DAMAGED}")


def check_time_block(name, names, bounds, spans, key, values, companions):
    """Refuse (:class:`~dynia.errors.DataError`) values of ``key`` that no analysis gives, for steps of one block.

    ``values`` holds array ``key`` (one of the arrays along time, in the
    module's dimension order) for every parameter over some steps;
    ``companions`` the other arrays for the same steps (``ci`` for ``ic``
    and ``median``, ``ic`` for ``gradient``). The rules, exact in the
    array's own dtype (a float32 array is the float64 result rounded to
    nearest, and that rounding keeps every order below):

    - ``ic`` in [0, 1], NaN exactly where the limits are, and equal to
      1 - (upper - lower) / range, the range that of the bounds or (MCAT)
      ``spans``, that of the samples (to the dtype's rounding);
    - ``ci``: each limit within the bounds (rounded to the dtype), lower at
      most upper, both NaN or neither;
    - ``median`` within the limits, NaN exactly where they are;
    - ``gradient`` (likelihood mass per bin) in [0, 1], NaN exactly where IC is;
    - ``ic_se`` and ``ci_se`` non-negative or NaN.

    ``name`` (the file) and ``names`` (the parameters) are for the message;
    ``bounds`` is (n_params, 2), ``spans`` the samples' max - min per parameter.
    """
    values = np.asarray(values)
    if values.dtype.kind != "f":
        raise DataError(f"{name}: {key} holds {values.dtype}; expected floating point numbers")
    if key in ("ic", "median") and "ci" in companions:
        # The limits first, so that a forged limit is named as such rather than as the IC or median it disowns.
        check_time_block(name, names, bounds, spans, "ci", companions["ci"], {})
    refuse = functools.partial(_refuse, name, names, key)
    with np.errstate(invalid="ignore", divide="ignore"):  # NaN compares False; a span of 0 never agrees
        if key == "ic":
            _check_ic(values, companions, bounds, spans, refuse)
        elif key == "ci":
            _check_limits(values, bounds, refuse)
        elif key == "median":
            limits = companions["ci"]
            bad = (values < limits[..., 0]) | (values > limits[..., 1]) | (np.isnan(values) != np.isnan(limits[..., 0]))
            if bad.any():
                refuse(bad, "lies outside the limits, or is NaN where they are not")
        elif key == "gradient":
            _check_gradient(values, companions, refuse)
        else:
            bad = (values < 0) | np.isinf(values)
            if bad.any():
                refuse(bad, "is negative or infinite")


def _refuse(name, names, key, bad, what):
    """The DataError for array ``key`` of file ``name`` where ``bad``, naming the first parameter (or step)."""
    where = np.argwhere(bad)[0]
    step = f"parameter {names[where[0]]!r}" if bad.ndim > 1 else "a step"
    raise DataError(f"{name}: {key} {what} (first at {step}); {_DAMAGED}")


def _check_ic(values, companions, bounds, spans, refuse):
    """IC in [0, 1], NaN exactly where the limits are, and 1 - (upper - lower) / range for its limits."""
    outside = (values < 0) | (values > 1)
    if outside.any():
        refuse(outside, "lies outside [0, 1]")
    if "ci" not in companions:
        return
    limits = companions["ci"]
    mismatch = np.isnan(values) != np.isnan(limits[..., 0])
    if mismatch.any():
        refuse(mismatch, "is NaN where the limits are not, or not NaN where they are")
    # Rounding to the dtype moves IC by half an ulp and each limit by half of its own.
    width, size = limits[..., 1] - limits[..., 0], np.abs(limits).sum(axis=-1, dtype=float)
    agrees = np.isnan(values)
    for extent in (bounds[:, 1] - bounds[:, 0], spans):
        extent = np.asarray(extent, dtype=float)[:, None]
        tolerance = 4 * np.finfo(values.dtype).eps * (1 + size / extent)
        agrees |= np.abs(values - (1 - width.astype(float) / extent)) <= tolerance
    if not agrees.all():
        refuse(~agrees, "is not 1 - (upper - lower) / range for its limits")


def _check_limits(values, bounds, refuse):
    """Each limit within the bounds (rounded to the dtype), lower at most upper, both NaN or neither."""
    low, high = (bounds[:, side].astype(values.dtype)[:, None] for side in (0, 1))
    lower, upper = values[..., 0], values[..., 1]
    bad = (lower < low) | (upper > high) | (lower > upper) | np.isinf(values).any(-1)
    if bad.any():
        refuse(bad, "has limits outside the bounds, or a lower limit above the upper")
    if (np.isnan(lower) != np.isnan(upper)).any():
        refuse(np.isnan(lower) != np.isnan(upper), "has one limit NaN and the other not")


def _check_gradient(values, companions, refuse):
    """The likelihood mass per bin in [0, 1], NaN exactly where IC is."""
    tolerance = 4 * np.finfo(values.dtype).eps  # a bin's mass is a sum of weights summing to 1
    bad = (values < 0) | (values > 1 + tolerance) | np.isinf(values)
    if "ic" in companions:
        bad |= np.isnan(values) != np.isnan(companions["ic"])[:, None, :]
    if bad.any():
        refuse(bad, "lies outside [0, 1], or is NaN where IC is not")


def _companions(key):
    return {"ic": ("ci",), "median": ("ci",), "gradient": ("ic",)}.get(key, ())


def _lazy(name, dataset, names, bounds, spans):
    """The arrays along time as DiskArrays that check each block on its first read."""
    keys = [key for key in _TIME_ARRAYS if key in dataset]
    for key in keys:
        if dataset[key].dims != TIME_VARIABLES[key]:
            raise DataError(
                f"{name}: {key} has dimensions {dataset[key].dims}; a lazy load needs {TIME_VARIABLES[key]} "
                "(the order dynia writes), load it with lazy=False"
            )
    check = functools.partial(_check_stored_block, name, names, np.asarray(bounds), spans)
    return disk_arrays(name, keys, check=check)


def _check_stored_block(name, names, bounds, spans, key, file, start, stop):
    """``check_time_block`` for steps [start, stop) of variable ``key`` of the open h5py ``file``."""
    companions = {other: read_block(file, other, start, stop) for other in _companions(key) if other in file}
    check_time_block(name, names, bounds, spans, key, read_block(file, key, start, stop), companions)


class DeferredVerdicts(Mapping):
    """The verdicts of a lazily loaded result: checked against its arrays (as :func:`load` says) on first use.

    Deriving them reads IC along the whole record, which for a result larger than memory is what ``lazy=True``
    is there to avoid until it is asked for; a :class:`StoredVerdictsWarning` comes then. It reads like the dict
    of verdicts an eager load gives, and compares equal to it.
    """

    def __init__(self, name, result, stored):
        self._name, self._result, self._stored = name, result, stored
        self._checked = None

    def _verdicts(self):
        if self._checked is None:
            self._checked = _checked_verdicts(self._name, self._result, self._stored, stacklevel=5)
        return self._checked

    def __getitem__(self, parameter):
        return self._verdicts()[parameter]

    def __iter__(self):
        return iter(self._stored)  # the parameters, known without deriving anything

    def __len__(self):
        return len(self._stored)

    def __repr__(self):
        return repr(self._verdicts())


def _check_verdict_form(name, result, stored):
    """A DataError naming the part when ``stored`` has not the form of verdicts of ``result``'s parameters."""
    if list(stored) != list(result.names):
        raise DataError(f"{name}: verdicts name {list(stored)}; expected the parameters {list(result.names)}")
    for parameter, entry in stored.items():
        well_formed = (
            isinstance(entry, dict)
            and entry.keys() == {"verdict", "reasons"}
            and entry["verdict"] in VERDICTS
            and isinstance(entry["reasons"], list)
            and all(
                isinstance(reason, dict)
                and reason.keys() == {"code", "text"}
                and all(isinstance(part, str) for part in reason.values())
                for reason in entry["reasons"]
            )
        )
        if not well_formed:
            raise DataError(
                f"{name}: verdicts[{parameter!r}] is {entry!r}; expected {{'verdict': one of {list(VERDICTS)}, "
                "'reasons': [{'code': ..., 'text': ...}, ...]}"
            )


def _checked_verdicts(name, result, stored, stacklevel=4):
    """The verdicts of ``stored`` (well formed) that agree with those the arrays give; the arrays' own for the others.

    Agreeing means the same verdict and reason codes (the texts may write times as the data file did); a stored
    ``noise_only`` of a result without the floor is taken on trust, as it came from the data and the model.
    """
    derived = assess(result)
    checked = {}
    for parameter, entry in stored.items():
        checked[parameter] = entry
        codes = [reason["code"] for reason in entry["reasons"]]
        verdict, expected = derived[parameter]["verdict"], [reason["code"] for reason in derived[parameter]["reasons"]]
        if result.informative is None and "noise_only" in codes:
            # A result without the floor gets noise_only from the data and the model, which the file does not hold.
            codes = [code for code in codes if code != "noise_only"]
            verdict = "suspect" if verdict == "identified" else verdict
        if (entry["verdict"], codes) != (verdict, expected):
            warnings.warn(
                f"{name}: the stored verdict of {parameter!r} is {entry['verdict']!r} "
                f"({', '.join(codes) or 'no reasons'}) but its arrays give {derived[parameter]['verdict']!r} "
                f"({', '.join(expected) or 'no reasons'}); loaded with the verdict the arrays give (the file was "
                "altered, or written by a dynia whose verdict rules differ, or with other settings of assess)",
                StoredVerdictsWarning,
                stacklevel=stacklevel,
            )
            checked[parameter] = derived[parameter]
    return checked


class StoredVerdictsWarning(UserWarning):
    """A file's stored verdict differs from the one its arrays give; :func:`load` returns the latter."""


class StoredSettingsWarning(UserWarning):
    """A file holds settings that are not fields of the settings or the run record; :func:`load` leaves them out."""
