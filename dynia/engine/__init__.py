"""The DYNIA engine: moving windows, behavioural selection, flavours, CLD and compiled kernels.

:mod:`~dynia.engine.windows` runs the moving window over time chunks,
reading the absolute errors from a source (:mod:`~dynia.engine.error_sources`),
:mod:`~dynia.engine.selection` picks each window's behavioural set,
:mod:`~dynia.engine.flavours` turns it into limits, IC and CLD gradient,
:mod:`~dynia.engine.cld` holds the likelihood and CLD arithmetic,
:mod:`~dynia.engine.kernels` the compiled (numba) versions of the hot loops,
:mod:`~dynia.engine.twin` their numpy twin for small runs (their numbers bit
for bit, nothing to compile) and :mod:`~dynia.engine.noise` the noise floor:
which windows tell parameter sets apart beyond what measurement noise alone does.
"""

import importlib

# Loaded on first use, so that importing one engine module (the CLD arithmetic,
# say) does not import the whole engine.
_NAMES = {
    "moving_window": "windows",
    "WINDOWS": "windows",
    "FLAVOURS": "flavours",
    "ENGINES": "flavours",
}
_SUBMODULES = frozenset({"cld", "error_sources", "flavours", "kernels", "noise", "selection", "twin", "windows"})

__all__ = ["moving_window", "FLAVOURS", "WINDOWS", "ENGINES"]


def __getattr__(name):
    if name in _NAMES:
        return getattr(importlib.import_module(f"{__name__}.{_NAMES[name]}"), name)
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__) | _SUBMODULES)
