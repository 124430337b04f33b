"""How a result lies in a netCDF file: the dimensions of its variables, its attributes and their JSON.

The one home of what every side of a result file shares: :mod:`dynia.io.arrays`
writes a file block by block while the windows are analysed and
:mod:`dynia.io.writer` writes a result whole, both with the attributes of
:func:`metadata`; :mod:`dynia.io.reader` reads either back.

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
``discrimination``, ``noise_floor``, ``behavioural_spread``,
``behavioural_floor`` and ``best_mae`` (time), the mask as int8 in the file (netCDF has no
booleans) and bool in the Dataset and when loaded; files without them, and
files of the older floor (``mae_spread``, whose mask tested the behavioural
spread), load with None there. Coordinates: ``parameter`` (the names),
``time``, ``side`` ("lower", "upper": ``ci.sel(side="lower")`` is the lower
limit, and for ``bounds`` the low end of the range). ``time`` is the time
of each step in seconds from the start of the record, or, when the result
has timestamps (a dated record), its dates (datetime64[ns]), so that
``ds.sel(time="2015-01")`` and ``ds.sel(time=slice("2015-01-01",
"2015-02-01"))`` select by date; a dated result keeps the seconds as the
coordinate ``elapsed`` along ``time`` (units "s"), not an index. In the
file, dates are int64 nanoseconds since 1970-01-01 (attributes ``units``
:data:`TIMESTAMP_UNITS` and ``calendar`` "proleptic_gregorian", which any
CF reader decodes to datetimes).

Settings and verdicts are the JSON attributes ``settings`` and ``verdicts``
(``"null"`` for a result without verdicts). ``settings`` is one object:
every field of the result's :class:`~dynia.settings.AnalysisSettings` (none
for a result without settings) and the fields of its
:class:`~dynia.settings.RunRecord` that are set (not None; ``thesis_code``
only when True), each by its name; :func:`~dynia.io.reader.load` rebuilds both from it. The
JSON is plain but for one tag: a tuple is written as ``{"__tuple__":
[...]}``, so that it comes back a tuple while a list comes back a list. The
adaptive samplers' ``weights`` (an ndarray) is written as a variable of its
own name along ``sample`` instead, with ``{"__variable__": "weights"}`` in
its place in the JSON.

Attribute ``dynia_result`` holds the format version: the lowest version
whose reader reads the file right (:func:`format_version`), so that a file
an older dynia can read says so.

- Version 1: ``time`` in seconds always; the dates of a dated result in a
  non-index coordinate ``timestamp`` along ``time``.
- Version 2 (a dated result): ``time`` holds the dates, ``elapsed`` the
  seconds, and there is no ``timestamp``. A result without timestamps is
  still written as version 1, its file unchanged. A dynia that reads only
  version 1 refuses a version 2 file by its version, rather than misread
  its dates as seconds.

:func:`~dynia.io.reader.load` reads both.

Files written before the record existed hold the same object with a few
more keys: ``bounds`` (the ``bounds`` variable holds them, and it is not
read), flavour ``"thesis-code"`` (read as flavour "thesis" with
``thesis_code``), and whatever a user had put into the settings dict (left
out, with a :class:`~dynia.io.reader.StoredSettingsWarning` naming it).

Why netCDF-4 through h5netcdf: netCDF-3 (scipy's writer, the one without
extra dependencies) has no 64-bit integers, so it could not hold the
timestamps to the nanosecond nor integer arrays exactly, and it limits a
variable to 2 GB, which the gradient of a long record passes.
"""

import json
from collections.abc import Mapping

import numpy as np

from ..errors import SettingsError

__all__ = [
    "FORMAT_VERSION",
    "format_version",
    "TIME_VARIABLES",
    "ARRAYS",
    "OPTIONAL_ARRAYS",
    "NOISE_FLOOR",
    "COORDINATES",
    "SIDES",
    "TIMESTAMP_UNITS",
    "TIMESTAMP_ATTRIBUTES",
    "SECONDS_ATTRIBUTES",
    "VARIABLE_TAG",
    "metadata",
    "encoded",
    "decoded",
    "MalformedAttribute",
]

# The latest layout, written as the attribute "dynia_result" (see format_version); a later layout raises it,
# and load refuses what it cannot read.
FORMAT_VERSION = 2

# Settings holding one value per parameter set: their variable lies along "sample".
_PER_SAMPLE = frozenset({"weights"})

# The result arrays that lie along time, with the file's dimensions.
TIME_VARIABLES = {
    "ic": ("parameter", "time"),
    "ci": ("parameter", "time", "side"),
    "median": ("parameter", "time"),
    "gradient": ("parameter", "bin", "time"),
    "ic_se": ("parameter", "time"),
    "ci_se": ("parameter", "time", "side"),
}
# The arrays every result has.
ARRAYS = {
    "ic": TIME_VARIABLES["ic"],
    "ci": TIME_VARIABLES["ci"],
    "gradient": TIME_VARIABLES["gradient"],
    "bin_centres": ("parameter", "bin"),
    "samples": ("sample", "parameter"),
    "bounds": ("parameter", "side"),
}
# Written when the result has them (not None), read back when the file has them.
OPTIONAL_ARRAYS = {name: TIME_VARIABLES[name] for name in ("median", "ic_se", "ci_se")}
# The noise floor along time (see dynia.engine.noise), written when the result has it. Part of the
# metadata, so that a result written block by block (dynia.io.arrays) gets it too; the mask is int8 in a
# file, since netCDF has no booleans, and bool again when loaded.
NOISE_FLOOR = ("informative", "discrimination", "noise_floor", "behavioural_spread", "behavioural_floor", "best_mae")
COORDINATES = ("parameter", "time", "side", "timestamp", "elapsed")
SIDES = ("lower", "upper")

# The timestamps as integer nanoseconds from the epoch: exact, and what any CF reader decodes to datetimes.
TIMESTAMP_UNITS = "nanoseconds since 1970-01-01"
# The attributes of the timestamp variable in a file (what xarray writes with that encoding).
TIMESTAMP_ATTRIBUTES = {"units": TIMESTAMP_UNITS, "calendar": "proleptic_gregorian"}
# The attributes of the seconds from the start: ``time`` of a result without timestamps, ``elapsed`` of one with.
SECONDS_ATTRIBUTES = {"units": "s", "long_name": "time from the start of the record"}

_TUPLE = "__tuple__"
# In the settings' JSON, the place of a setting written as a variable of its own: {VARIABLE_TAG: name}.
VARIABLE_TAG = "__variable__"


def format_version(result):
    """The format version of ``result``'s file: 2 when it has timestamps (dated ``time``), else 1 (see the module)."""
    return FORMAT_VERSION if result.timestamps is not None else 1


def metadata(result, reserved):
    """The file attributes of ``result`` (format, settings and verdicts as JSON) and its array settings.

    Returns ``(attrs, variables)``: a field of the run record that is an
    ndarray (``weights``) becomes a variable of its name, ``(dims, values)``, which must not be one of the
    names ``reserved`` for the result's own variables; so does the noise
    floor (``informative`` as int8, then ``discrimination``, ``noise_floor``,
    ``behavioural_spread``, ``behavioural_floor``, ``best_mae``), when the result has it.

    Raises
    ------
    SettingsError
        As :func:`~dynia.io.writer.save`.
    """
    variables = {
        name: (("time",), np.asarray(getattr(result, name), dtype=np.int8 if name == "informative" else float))
        for name in NOISE_FLOOR
        if getattr(result, name) is not None
    }
    settings = {}
    recorded = dict({} if result.settings is None else result.settings.to_dict(), **result.run.to_dict())
    for key, value in recorded.items():
        if isinstance(value, np.ndarray):
            if key in reserved or key in NOISE_FLOOR:
                raise SettingsError(
                    f"result.run.{key} is an array, saved as a variable of its name, but the result "
                    f"has a variable {key!r} of its own",
                    key,
                )
            dims = ("sample",) if key in _PER_SAMPLE else tuple(f"{key}_dim_{axis}" for axis in range(value.ndim))
            variables[key] = (dims, value)
            settings[key] = {VARIABLE_TAG: key}
        else:
            settings[key] = encoded(value, f"result.run.{key}", key)
    attrs = {
        "dynia_result": format_version(result),
        "settings": json.dumps(settings),
        "verdicts": json.dumps(encoded(result.verdicts, "result.verdicts", None)),
    }
    return attrs, variables


def encoded(value, where, setting):
    """``value`` as what json.dumps writes, tuples tagged; a SettingsError naming ``where`` for anything else."""
    if value is None or isinstance(value, (str, bool, int, float)):
        return value
    if isinstance(value, np.generic) and isinstance(value.item(), (bool, int, float, str)):
        return value.item()
    if isinstance(value, (list, tuple)):
        items = [encoded(item, f"{where}[{index}]", setting) for index, item in enumerate(value)]
        return {_TUPLE: items} if isinstance(value, tuple) else items
    if isinstance(value, Mapping):  # a dict, or a lazily loaded result's DeferredVerdicts
        keys = [key for key in value if not isinstance(key, str)]
        if keys:
            raise SettingsError(f"{where} has the key {keys[0]!r}; only str keys can be saved", setting)
        return {key: encoded(item, f"{where}[{key!r}]", setting) for key, item in value.items()}
    raise SettingsError(
        f"{where} holds a value of type {type(value).__name__}, which cannot be saved; expected str, number, "
        "bool, None, list, tuple or dict (an ndarray only as a setting of its own)",
        setting,
    )


class MalformedAttribute(ValueError):
    """A JSON attribute that is JSON but not as :func:`metadata` writes it."""


def decoded(mapping):
    """The ``object_hook`` of ``json.loads`` for the attributes: a tagged tuple back as a tuple."""
    if mapping.keys() != {_TUPLE}:
        return mapping
    if not isinstance(mapping[_TUPLE], list):
        raise MalformedAttribute(f"{mapping!r} tags a tuple but holds no list")
    return tuple(mapping[_TUPLE])
