"""Dynamic Identifiability Analysis (DYNIA) of process data.

The pipeline has one module per stage: :mod:`dynia.sampling` draws parameter
sets, :mod:`dynia.models` simulates them, :mod:`dynia.analysis` runs the
moving-window analysis and :mod:`dynia.result` holds what comes out.
:func:`dynia.run` chains them. :mod:`dynia.thesis` and :mod:`dynia.mcat` are
plain ports of the thesis's MATLAB and of MCAT's ``id_time.m``, kept as the
oracles the fast engine is tested against.
"""
from . import (adaptive, analysis, baseline, cld, data, mcat, models, online, refine, sampling, segments,
               synthetic, thesis)
from .analysis import moving_window
from .pipeline import run
from .refine import second_run
from .result import DyniaResult

__version__ = "0.1.0"

__all__ = ["run", "second_run", "moving_window", "DyniaResult", "adaptive", "analysis", "cld", "data",
           "models", "online", "refine", "baseline", "segments", "sampling", "synthetic", "thesis", "mcat"]
