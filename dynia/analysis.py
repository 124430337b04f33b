"""Old home of the moving-window engine, kept so existing imports work: see :mod:`dynia.engine`."""

from .engine.flavours import FLAVOURS, compiled_engine, flavour_analysis
from .engine.selection import lowest_stable, lowest_weighted, stable_rank_mask
from .engine.windows import WINDOWS, analyse_stream, default_chunk_steps, moving_window, window_costs, window_halos

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
