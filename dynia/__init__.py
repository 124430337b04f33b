"""Dynamic Identifiability Analysis (DYNIA) of process data.

The verbs are at the top level, each loading its module on first use, so
``import dynia`` stays quick and loads no plotting, file or cluster library:

* :func:`dynia.run` samples parameter sets, simulates them and runs the
  moving-window analysis, returning a :class:`~dynia.result.DyniaResult`;
* :func:`dynia.suggest` proposes a window, a behavioural share and a number of
  samples for a record, with the reasons;
* :func:`dynia.second_run` narrows what is identified and re-analyses the rest;
* :func:`dynia.identify` fits a model by least squares on the data DYNIA (or a
  baseline) selects and validates it on held-out data;
* :func:`dynia.load` reads a saved result back; :func:`dynia.load_csv` reads
  logged plant data onto a uniform grid.

Every front-end takes one :class:`~dynia.settings.AnalysisSettings`; every
mistake raises a subclass of :class:`~dynia.errors.DyniaError`.

The stages have one module each: :mod:`dynia.sampling` draws parameter sets,
:mod:`dynia.models` simulates them (:mod:`dynia.models.conceptual` holds the
nonlinear case-study models), :mod:`dynia.engine` runs the moving window,
:mod:`dynia.result` and :mod:`dynia.verdicts` hold what comes out, and
:mod:`dynia.io` reads records and writes results. After the analysis,
:mod:`dynia.segments`, :mod:`dynia.fit`, :mod:`dynia.baseline`,
:mod:`dynia.quality` and :mod:`dynia.structure` turn IC curves into fitted
models and warnings. :mod:`dynia.online` (:class:`~dynia.online.OnlineDynia`),
:mod:`dynia.adaptive` and :mod:`dynia.distributed` are the other front-ends
over the same engine; :mod:`dynia.cli` is the ``dynia`` command.
:mod:`dynia.reference` holds plain ports of the thesis's MATLAB
(``dynia.thesis`` is the same module) and of MCAT's ``id_time.m``, the
oracles the fast engine is tested against.

Examples
--------
>>> import dynia
>>> callable(dynia.identify), callable(dynia.suggest)
(True, True)
"""

import importlib

# The error types are part of the top-level API: catch dynia.DyniaError, dynia.SettingsError, ...
from .errors import *  # noqa: F403
from .errors import __all__ as _ERRORS

__version__ = "0.1.0"

# Public name -> (module, attribute), imported on first use.
_VERBS = {
    "run": ("pipeline", "run"),
    "identify": ("identification", "identify"),
    "suggest": ("suggestion", "suggest"),
    "second_run": ("refine", "second_run"),
    "load": ("io.reader", "load"),
    "load_csv": ("io.csv", "load_csv"),
    "moving_window": ("engine.windows", "moving_window"),
    "AnalysisSettings": ("settings", "AnalysisSettings"),
    "DyniaResult": ("result", "DyniaResult"),
    "Identification": ("identification", "Identification"),
    "Suggestion": ("suggestion", "Suggestion"),
    "OnlineDynia": ("online", "OnlineDynia"),
    "ProcessData": ("io.csv", "ProcessData"),
}

_SUBMODULES = frozenset(
    {
        "adaptive",
        "analysis",
        "baseline",
        "cld",
        "claims",
        "cli",
        "decimation",
        "distributed",
        "engine",
        "errors",
        "fit",
        "identification",
        "io",
        "mcat",
        "memory",
        "models",
        "online",
        "pipeline",
        "quality",
        "reference",
        "refine",
        "result",
        "sampling",
        "segments",
        "settings",
        "structure",
        "suggestion",
        "summary",
        "synthetic",
        "thesis",
        "timescale",
        "verdicts",
    }
)

__all__ = [*_VERBS, *_ERRORS, "__version__"]


def __getattr__(name):
    if name in _VERBS:
        module, attribute = _VERBS[name]
        value = getattr(importlib.import_module(f"{__name__}.{module}"), attribute)
        globals()[name] = value
        return value
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__) | _SUBMODULES)
