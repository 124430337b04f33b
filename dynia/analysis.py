"""Deprecated: the old home of the moving-window engine; import from :mod:`dynia.engine`.

Importing this module raises a :class:`DeprecationWarning`; it will be removed
in dynia 0.3.0.
"""

import warnings

from .engine.flavours import FLAVOURS, compiled_engine, flavour_analysis
from .engine.selection import lowest_stable, lowest_weighted, stable_rank_mask
from .engine.windows import WINDOWS, analyse_stream, default_chunk_steps, moving_window, window_costs, window_halos

warnings.warn(
    "dynia.analysis is deprecated and will be removed in dynia 0.3.0: import from dynia.engine "
    "(moving_window, analyse_stream and window_costs from dynia.engine.windows, lowest_stable from "
    "dynia.engine.selection, flavour_analysis from dynia.engine.flavours)",
    DeprecationWarning,
    stacklevel=2,
)

__all__ = [
    "moving_window",
    "analyse_stream",
    "window_costs",
    "window_halos",
    "default_chunk_steps",
    "compiled_engine",
    "flavour_analysis",
    "lowest_stable",
    "lowest_weighted",
    "stable_rank_mask",
    "FLAVOURS",
    "WINDOWS",
]
