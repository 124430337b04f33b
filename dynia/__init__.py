"""Dynamic Identifiability Analysis (DYNIA) of process data.

The pipeline has one module per stage: :mod:`dynia.sampling` draws parameter
sets, :mod:`dynia.models` simulates them, :mod:`dynia.engine` runs the
moving-window analysis and :mod:`dynia.result` holds what comes out.
:func:`dynia.run` chains them. :mod:`dynia.settings` holds the one
:class:`~dynia.settings.AnalysisSettings` every front-end takes and
:mod:`dynia.errors` the error types. :mod:`dynia.reference` holds plain
ports of the thesis's MATLAB and of MCAT's ``id_time.m``, kept as the
oracles the fast engine is tested against.

After the analysis: :mod:`dynia.segments` turns IC curves into data segments,
:mod:`dynia.fit` fits the model on them by least squares, :mod:`dynia.baseline` is the
interval search of Bittencourt et al. (2015) to compare with,
:mod:`dynia.quality` flags glitches, outliers and stuck values,
:mod:`dynia.structure` warns when a constant parameter's estimate drifts, and
:mod:`dynia.identify` chains them (``dynia identify`` on the command line).
:mod:`dynia.online` updates the analysis one logged sample at a time, and
:mod:`dynia.distributed` runs it on a Dask cluster.
"""

from . import (
    adaptive,
    analysis,
    baseline,
    cld,
    conceptual,
    data,
    engine,
    errors,
    fit,
    identify,
    mcat,
    models,
    online,
    quality,
    reference,
    refine,
    sampling,
    segments,
    settings,
    structure,
    synthetic,
    thesis,
)
from .engine.windows import moving_window
from .errors import DyniaError
from .pipeline import run
from .refine import second_run
from .result import DyniaResult
from .settings import AnalysisSettings
from .store import load

__version__ = "0.1.0"

__all__ = [
    "run",
    "second_run",
    "load",
    "moving_window",
    "DyniaResult",
    "AnalysisSettings",
    "DyniaError",
    "adaptive",
    "analysis",
    "baseline",
    "cld",
    "conceptual",
    "data",
    "engine",
    "errors",
    "fit",
    "identify",
    "mcat",
    "models",
    "online",
    "quality",
    "reference",
    "refine",
    "sampling",
    "segments",
    "settings",
    "structure",
    "synthetic",
    "thesis",
]
