"""A result written whole: as an xarray Dataset and as a netCDF-4 file.

:func:`to_xarray` and :func:`save` lay a :class:`~dynia.result.DyniaResult`
out as :mod:`dynia.io.layout` describes (the layout is
:mod:`dynia.io.layout`); :meth:`~dynia.result.DyniaResult.to_xarray` and
:meth:`~dynia.result.DyniaResult.save` call them, and :func:`dynia.io.reader.load` reads
the file back. A result whose arrays are on disk is copied block by block
(:func:`dynia.io.arrays.write_result`).
"""

import numpy as np

from ..errors import OutputError
from .arrays import DiskArray, write_netcdf, write_result
from .layout import ARRAYS, COORDINATES, OPTIONAL_ARRAYS, SECONDS_ATTRIBUTES, SIDES, TIMESTAMP_ATTRIBUTES, metadata

__all__ = [
    "to_xarray",
    "save",
]


def to_xarray(result):
    """``result`` as an :class:`xarray.Dataset` laid out as the module describes.

    Raises
    ------
    SettingsError
        A setting that JSON cannot hold (see :func:`save`).
    """
    import xarray as xr

    coords = {"parameter": ("parameter", np.array(result.names, dtype=str))}
    if result.timestamps is None:
        coords["time"] = ("time", result.time, SECONDS_ATTRIBUTES)
    else:
        # The dates index time, so that ds.sel(time="2015-01") selects by date; the seconds stay alongside.
        coords["time"] = ("time", np.asarray(result.timestamps, dtype="datetime64[ns]"))
        coords["elapsed"] = ("time", result.time, SECONDS_ATTRIBUTES)
    coords["side"] = ("side", np.array(SIDES))
    variables = {name: _variable(getattr(result, name), dims) for name, dims in ARRAYS.items()}
    variables.update(
        (name, _variable(getattr(result, name), dims))
        for name, dims in OPTIONAL_ARRAYS.items()
        if getattr(result, name) is not None
    )
    attrs, array_settings = metadata(result, reserved=(*variables, *COORDINATES))
    variables.update(array_settings)
    if result.informative is not None:
        variables["informative"] = (("time",), np.asarray(result.informative, dtype=bool))
    return xr.Dataset(variables, coords=coords, attrs=attrs)


def _variable(values, dims):
    """An array of a result as a Dataset variable: an array on disk stays there (read lazily by xarray)."""
    if not isinstance(values, DiskArray):
        return dims, values
    import xarray as xr

    opened = xr.open_dataset(values.filename, engine="h5netcdf", mask_and_scale=False, decode_times=False)
    return opened[values.name].variable.transpose(*dims)


def save(result, path):
    """Write ``result`` to the netCDF-4 file ``path`` (replaced if it exists); :func:`dynia.load` reads it back.

    Every array is written as it is, without a fill value, so NaN stays NaN
    bit for bit; the dates of a dated result (``time``) as int64 nanoseconds since 1970-01-01. A result
    whose arrays are on disk (``store``, see :mod:`dynia.io.arrays`) is copied
    one time block at a time, never loaded whole.

    Raises
    ------
    SettingsError
        A part of the verdicts that is not a str, number, bool, None, list,
        tuple or dict with str keys (nested); numpy scalars are written as
        Python numbers. The message names the part.
    OutputError
        ``path`` cannot be written (a missing folder, no permission, a full
        disk); the file is written under a temporary name beside ``path``
        and renamed when complete, so ``path`` is then left as it was.
    """
    if isinstance(result.ic, DiskArray):
        write_result(result, path)
        return
    dataset = to_xarray(result)
    # Fletcher-32 checksums on every numeric variable, so that load tells a damaged file from a result.
    encoding = {
        name: {"_FillValue": None, "fletcher32": dataset[name].dtype.kind in "biufM"} for name in dataset.variables
    }
    if result.timestamps is not None:
        encoding["time"].update(TIMESTAMP_ATTRIBUTES, dtype="int64")
    write_netcdf(lambda partial: dataset.to_netcdf(partial, engine="h5netcdf", encoding=encoding), path)


def add_attributes(path, attributes):
    """Add ``attributes`` (str name -> JSON-ready value) to the result file ``path`` as JSON text attributes.

    What the command line knows beyond the result, its units and reference values, travels with ``result.nc`` this
    way; :func:`dynia.load` ignores attributes it does not know, and ``xarray.open_dataset(path).attrs`` shows them.

    Raises
    ------
    OutputError
        ``path`` cannot be opened for writing.
    """
    import json

    import h5netcdf

    try:
        with h5netcdf.File(path, "a") as file:
            for name, value in attributes.items():
                file.attrs[name] = json.dumps(value)
    except OSError as error:
        raise OutputError(f"{path}: cannot be written ({error.strerror or error})") from None
