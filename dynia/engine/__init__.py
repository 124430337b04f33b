"""The DYNIA engine: moving windows, behavioural selection, flavours, CLD and compiled kernels.

:mod:`~dynia.engine.windows` runs the moving window over time chunks,
:mod:`~dynia.engine.selection` picks each window's behavioural set,
:mod:`~dynia.engine.flavours` turns it into limits, IC and CLD gradient,
:mod:`~dynia.engine.cld` holds the likelihood and CLD arithmetic,
:mod:`~dynia.engine.kernels` the compiled (numba) versions of the hot loops
and :mod:`~dynia.engine.noise` the noise floor: which windows tell parameter
sets apart beyond what measurement noise alone does.
"""

from . import cld, flavours, kernels, noise, selection, windows
from .flavours import ENGINES, FLAVOURS
from .windows import WINDOWS, moving_window

__all__ = [
    "moving_window",
    "FLAVOURS",
    "WINDOWS",
    "ENGINES",
    "cld",
    "flavours",
    "kernels",
    "noise",
    "selection",
    "windows",
]
