"""Results out: a :class:`~dynia.result.DyniaResult` as an xarray Dataset and a netCDF file, and back.

:func:`to_xarray` (also :meth:`DyniaResult.to_xarray`) labels every array of
a result with its dimensions; :func:`save` (:meth:`DyniaResult.save`) writes
that Dataset to netCDF-4 and :func:`load` (``dynia.load``) reads it back into
the result it came from, every array bit for bit.

The Dataset
-----------
Dimensions ``parameter``, ``time``, ``side``, ``bin`` and ``sample``;
variables ``ic`` (parameter, time), ``ci`` (parameter, time, side),
``gradient`` (parameter, bin, time), ``bin_centres`` (parameter, bin),
``samples`` (sample, parameter) and ``bounds`` (parameter, side); when the
result has its CLD median, ``median`` (parameter, time) (files written
before it existed load with ``median`` None); when the
result has its Monte Carlo errors, ``ic_se`` (parameter, time) and ``ci_se``
(parameter, time, side) too; when it has its noise floor, ``informative``,
``discrimination``, ``noise_floor``, ``behavioural_spread`` and
``behavioural_floor`` (time), the mask as int8 in the file (netCDF has no
booleans) and bool in the Dataset and when loaded; files without them, and
files of the older floor (``mae_spread``, whose mask tested the behavioural
spread), load with None there. Coordinates: ``parameter`` (the names),
``time`` (seconds), ``side`` ("lower", "upper": ``ci.sel(side="lower")``
is the lower limit, and for ``bounds`` the low end of the range) and, when
the result has timestamps, ``timestamp`` (datetime64[ns], along ``time``).

Settings and verdicts are the JSON attributes ``settings`` and ``verdicts``
(``"null"`` for a result without verdicts). The JSON is plain but for
one tag: a tuple is written as ``{"__tuple__": [...]}``, so that it comes
back a tuple while a list comes back a list. A setting that holds an
ndarray (the adaptive samplers' ``weights``) is written as a variable of its
own name instead, with ``{"__variable__": name}`` in its place in the JSON:
``weights`` lies along ``sample``, any other array along its own dimensions
``<name>_dim_0``, ... Attribute ``dynia_result`` holds the format version.

Why netCDF-4 through h5netcdf: netCDF-3 (scipy's writer, the one without
extra dependencies) has no 64-bit integers, so it could not hold the
timestamps to the nanosecond nor integer arrays exactly, and it limits a
variable to 2 GB, which the gradient of a long record passes.

Examples
--------
>>> import numpy as np, tempfile, pathlib, dynia
>>> res = dynia.DyniaResult(names=("K",), samples=np.zeros((3, 1)), bounds=np.array([[0.0, 1.0]]),
...                         time=np.arange(4.0), ic=np.array([[np.nan, 0.2, 0.5, 0.1]]),
...                         ci=np.zeros((1, 4, 2)), gradient=np.zeros((1, 2, 4)), bin_centres=np.zeros((1, 2)),
...                         settings={"n": 1, "bounds": {"K": (0.0, 1.0)}})
>>> res.to_xarray().ic.dims
('parameter', 'time')
>>> with tempfile.TemporaryDirectory() as folder:
...     res.save(pathlib.Path(folder, "result.nc"))
...     back = dynia.load(pathlib.Path(folder, "result.nc"))
>>> back.settings, back.ic
({'n': 1, 'bounds': {'K': (0.0, 1.0)}}, array([[nan, 0.2, 0.5, 0.1]]))
"""

import json
import numbers
import os

import numpy as np

from .errors import DataError, OutputError, SettingsError

__all__ = ["to_xarray", "save", "load", "metadata", "FORMAT_VERSION", "TIMESTAMP_ATTRIBUTES"]

# Written as the attribute "dynia_result"; a later layout raises it, and load refuses what it cannot read.
FORMAT_VERSION = 1

# Settings holding one value per parameter set: their variable lies along "sample".
_PER_SAMPLE = frozenset({"weights"})

_ARRAYS = {
    "ic": ("parameter", "time"),
    "ci": ("parameter", "time", "side"),
    "gradient": ("parameter", "bin", "time"),
    "bin_centres": ("parameter", "bin"),
    "samples": ("sample", "parameter"),
    "bounds": ("parameter", "side"),
}
# The noise floor along time (see dynia.engine.noise), written when the result has it. Part of the
# metadata, so that a result written block by block (dynia.storage) gets it too; the mask is int8 in a
# file, since netCDF has no booleans, and bool again when loaded.
_NOISE_FLOOR = ("informative", "discrimination", "noise_floor", "behavioural_spread", "behavioural_floor")
# Written when the result has them (not None), read back when the file has them.
_OPTIONAL_ARRAYS = {
    "median": ("parameter", "time"),
    "ic_se": ("parameter", "time"),
    "ci_se": ("parameter", "time", "side"),
}
_COORDINATES = ("parameter", "time", "side", "timestamp")
_SIDES = ("lower", "upper")

# The timestamps as integer nanoseconds from the epoch: exact, and what any CF reader decodes to datetimes.
_TIMESTAMP_UNITS = "nanoseconds since 1970-01-01"
# The attributes of the timestamp variable in a file (what xarray writes with that encoding).
TIMESTAMP_ATTRIBUTES = {"units": _TIMESTAMP_UNITS, "calendar": "proleptic_gregorian"}

_TUPLE = "__tuple__"
_VARIABLE = "__variable__"


def to_xarray(result):
    """``result`` as an :class:`xarray.Dataset` laid out as the module describes.

    Raises
    ------
    SettingsError
        A setting that JSON cannot hold (see :func:`save`).
    """
    import xarray as xr

    coords = {
        "parameter": ("parameter", np.array(result.names, dtype=str)),
        "time": ("time", result.time, {"units": "s", "long_name": "time from the start of the record"}),
        "side": ("side", np.array(_SIDES)),
    }
    if result.timestamps is not None:
        coords["timestamp"] = ("time", np.asarray(result.timestamps, dtype="datetime64[ns]"))
    variables = {name: _variable(getattr(result, name), dims) for name, dims in _ARRAYS.items()}
    variables.update(
        (name, _variable(getattr(result, name), dims))
        for name, dims in _OPTIONAL_ARRAYS.items()
        if getattr(result, name) is not None
    )
    attrs, array_settings = metadata(result, reserved=(*variables, *_COORDINATES))
    variables.update(array_settings)
    if result.informative is not None:
        variables["informative"] = (("time",), np.asarray(result.informative, dtype=bool))
    return xr.Dataset(variables, coords=coords, attrs=attrs)


def _variable(values, dims):
    """An array of a result as a Dataset variable: an array on disk stays there (read lazily by xarray)."""
    from .storage import DiskArray

    if not isinstance(values, DiskArray):
        return dims, values
    import xarray as xr

    opened = xr.open_dataset(values.filename, engine="h5netcdf", mask_and_scale=False, decode_times=False)
    return opened[values.name].variable.transpose(*dims)


def metadata(result, reserved):
    """The file attributes of ``result`` (format, settings and verdicts as JSON) and its array settings.

    Returns ``(attrs, variables)``: a setting that is an ndarray becomes a
    variable of its name, ``(dims, values)``, which must not be one of the
    names ``reserved`` for the result's own variables; so does the noise
    floor (``informative`` as int8, then ``discrimination``, ``noise_floor``,
    ``behavioural_spread``, ``behavioural_floor``), when the result has it.

    Raises
    ------
    SettingsError
        As :func:`save`.
    """
    variables = {
        name: (("time",), np.asarray(getattr(result, name), dtype=np.int8 if name == "informative" else float))
        for name in _NOISE_FLOOR
        if getattr(result, name) is not None
    }
    settings = {}
    for key, value in result.settings.items():
        if isinstance(value, np.ndarray):
            if key in reserved or key in _NOISE_FLOOR:
                raise SettingsError(
                    f"result.settings[{key!r}] is an array, saved as a variable of its name, but the result "
                    f"has a variable {key!r} of its own; rename the setting",
                    key,
                )
            dims = ("sample",) if key in _PER_SAMPLE else tuple(f"{key}_dim_{axis}" for axis in range(value.ndim))
            variables[key] = (dims, value)
            settings[key] = {_VARIABLE: key}
        else:
            settings[key] = _encoded(value, f"result.settings[{key!r}]", key)
    attrs = {
        "dynia_result": FORMAT_VERSION,
        "settings": json.dumps(settings),
        "verdicts": json.dumps(_encoded(result.verdicts, "result.verdicts", None)),
    }
    return attrs, variables


def save(result, path):
    """Write ``result`` to the netCDF-4 file ``path`` (replaced if it exists); :func:`load` reads it back.

    Every array is written as it is, without a fill value, so NaN stays NaN
    bit for bit; timestamps as int64 nanoseconds since 1970-01-01. A result
    whose arrays are on disk (``store``, see :mod:`dynia.storage`) is copied
    one time block at a time, never loaded whole.

    Raises
    ------
    SettingsError
        A setting, or a part of the verdicts, that is not a str, number, bool,
        None, list, tuple or dict with str keys (nested) or, at the top level
        of the settings, an ndarray; numpy scalars are written as Python
        numbers. The message names the setting.
    OutputError
        ``path`` cannot be written (a missing folder, no permission).
    """
    from .storage import DiskArray, write_result

    if isinstance(result.ic, DiskArray):
        write_result(result, path)
        return
    dataset = to_xarray(result)
    encoding = {name: {"_FillValue": None} for name in dataset.variables}
    if "timestamp" in dataset.variables:
        encoding["timestamp"].update(units=_TIMESTAMP_UNITS, calendar="proleptic_gregorian", dtype="int64")
    try:
        dataset.to_netcdf(path, engine="h5netcdf", encoding=encoding)
    except OSError as error:
        raise OutputError(f"{os.fspath(path)}: cannot be written ({error.strerror or error})") from None


def load(path, *, lazy=False):
    """The :class:`~dynia.result.DyniaResult` that :func:`save` wrote to ``path``.

    Every array comes back bit-identical (NaN where NaN), with the names, the
    timestamps, and the settings and verdicts equal to those saved: a tuple
    comes back a tuple and a list a list, an ndarray setting an ndarray of
    its dtype; a numpy scalar comes back as the Python number it was written
    as.

    With ``lazy=True`` the arrays along time (IC, limits, median, gradient
    and their errors) stay in the file as :class:`dynia.storage.DiskArray` objects,
    read where indexed: for results larger than memory (:mod:`dynia.storage`).

    Raises
    ------
    DataError
        ``path`` is missing, not netCDF-4, or not a result written by
        :func:`save` (of this format version or an earlier one).

    Examples
    --------
    See :mod:`dynia.store`.
    """
    import xarray as xr

    from .result import DyniaResult  # result imports this module for its methods

    name = os.fspath(path)
    if not os.path.isfile(name):
        raise DataError(f"{name}: no such file; expected a netCDF file written by DyniaResult.save")
    try:
        dataset = (xr.open_dataset if lazy else xr.load_dataset)(
            name, engine="h5netcdf", mask_and_scale=False, decode_times=False, decode_timedelta=False
        )
    except (OSError, ValueError) as error:
        raise DataError(
            f"{name}: cannot be read as netCDF-4 ({error}); expected a file written by DyniaResult.save"
        ) from None
    version = dataset.attrs.get("dynia_result")
    if not isinstance(version, numbers.Integral) or not 1 <= version <= FORMAT_VERSION:
        found = "no dynia_result attribute" if version is None else f"format version {version}"
        raise DataError(
            f"{name}: {found}; expected a result written by DyniaResult.save (format version {FORMAT_VERSION} "
            "or earlier)"
        )
    missing = [key for key in (*_ARRAYS, "parameter", "time") if key not in dataset.variables]
    missing += [key for key in ("settings", "verdicts") if key not in dataset.attrs]
    if missing:
        raise DataError(f"{name}: has no {', '.join(map(repr, missing))}; expected every part of a saved result")
    settings = {}
    for key, value in json.loads(dataset.attrs["settings"], object_hook=_decoded).items():
        is_variable = isinstance(value, dict) and value.keys() == {_VARIABLE}
        settings[key] = dataset[value[_VARIABLE]].values if is_variable else value
    arrays = {key: _loaded(dataset, key, dims, lazy) for key, dims in _ARRAYS.items()}
    arrays.update((key, _loaded(dataset, key, dims, lazy)) for key, dims in _OPTIONAL_ARRAYS.items() if key in dataset)
    # An older file's floor (mae_spread) tested another statistic: it loads as no floor, not as this one.
    if "discrimination" in dataset:
        arrays.update((key, dataset[key].values) for key in _NOISE_FLOOR if key in dataset)
    if "informative" in arrays:
        arrays["informative"] = arrays["informative"].astype(bool)
    timestamps = None
    if "timestamp" in dataset.variables:
        stamps = dataset["timestamp"]
        if stamps.attrs.get("units") != _TIMESTAMP_UNITS:
            raise DataError(f"{name}: timestamp has units {stamps.attrs.get('units')!r}; expected {_TIMESTAMP_UNITS!r}")
        timestamps = stamps.values.astype(np.int64).view("datetime64[ns]")
    return DyniaResult(
        names=tuple(str(label) for label in dataset["parameter"].values),
        time=dataset["time"].values,
        settings=settings,
        verdicts=json.loads(dataset.attrs["verdicts"], object_hook=_decoded),
        timestamps=timestamps,
        **arrays,
    )


def _loaded(dataset, key, dims, lazy):
    """Variable ``key`` in the order ``dims``: in memory, or with ``lazy`` a DiskArray when it lies along time."""
    from .storage import TIME_VARIABLES, disk_arrays

    variable = dataset[key]
    if not (lazy and key in TIME_VARIABLES):
        return variable.transpose(*dims).values
    if variable.dims != dims:
        raise DataError(
            f"{dataset.encoding['source']}: {key} has dimensions {variable.dims}; a lazy load needs {dims} "
            "(the order dynia writes), load it with lazy=False"
        )
    return disk_arrays(dataset.encoding["source"], [key])[key]


def _encoded(value, where, setting):
    """``value`` as what json.dumps writes, tuples tagged; a SettingsError naming ``where`` for anything else."""
    if value is None or isinstance(value, (str, bool, int, float)):
        return value
    if isinstance(value, np.generic) and isinstance(value.item(), (bool, int, float, str)):
        return value.item()
    if isinstance(value, (list, tuple)):
        items = [_encoded(item, f"{where}[{index}]", setting) for index, item in enumerate(value)]
        return {_TUPLE: items} if isinstance(value, tuple) else items
    if isinstance(value, dict):
        keys = [key for key in value if not isinstance(key, str)]
        if keys:
            raise SettingsError(f"{where} has the key {keys[0]!r}; only str keys can be saved", setting)
        return {key: _encoded(item, f"{where}[{key!r}]", setting) for key, item in value.items()}
    raise SettingsError(
        f"{where} holds a value of type {type(value).__name__}, which cannot be saved; expected str, number, "
        "bool, None, list, tuple or dict (an ndarray only as a setting of its own)",
        setting,
    )


def _decoded(mapping):
    return tuple(mapping[_TUPLE]) if mapping.keys() == {_TUPLE} else mapping
