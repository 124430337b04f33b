"""Records in, results out.

:mod:`~dynia.io.csv` reads logged plant data from CSV onto the uniform grid
DYNIA needs (:func:`~dynia.io.csv.load_csv`); :mod:`~dynia.io.frames` takes a
record held as pandas Series or DataFrames apart; a result file is laid out as :mod:`~dynia.io.layout` says,
written by :mod:`~dynia.io.writer` (:meth:`DyniaResult.save <dynia.result.DyniaResult.save>`)
and read back by :mod:`~dynia.io.reader` (:func:`dynia.load`);
:mod:`~dynia.io.arrays` holds a run's result arrays, in memory or in a netCDF
file written while the windows are analysed, and reads them back lazily;
:mod:`~dynia.io.outdir` is the command line's output directory and the rules
that keep a user's own files safe.
"""

import importlib

# Loaded on first use (dynia.io.csv.load_csv, say), so that reading a CSV file does not load xarray.
_SUBMODULES = frozenset({"arrays", "csv", "frames", "layout", "outdir", "reader", "writer"})

__all__ = []


def __getattr__(name):
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | _SUBMODULES)
