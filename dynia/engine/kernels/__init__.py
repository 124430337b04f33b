"""Compiled (numba) kernels of the engine: the numpy path's method, with running window sums, faster.

Three kinds of kernel cover the work of a :func:`dynia.run` with the
``"thesis"`` or ``"weighted"`` flavour:

- :mod:`~dynia.engine.kernels.simulate` advances every sample's discretised
  model (the recursion of the linear models, ``dynia.models.linear``)
  through a block of steps and writes the absolute errors against the
  measurement, time-major;
- :mod:`~dynia.engine.kernels.fused` does the same fused with the window
  sums, a block of samples at a time through every step of a chunk, and
  writes only the sums: no error matrix goes through memory (the built-in
  linear models; other models hand their error rows to the next kernel);
- :func:`~dynia.engine.kernels.readoff.analyse_windows` forms each
  window's costs (from error rows by the same running sums, or from the
  sums given), selects its behavioural set and reads off limits, IC and
  gradient; :func:`~dynia.engine.kernels.batches.analyse_windows_batched`
  also reads IC and limits off each
  Monte Carlo batch of samples.

:class:`CompiledErrors` (:mod:`~dynia.engine.kernels.driver`) serves the
simulation to the moving window, as error rows or fused window sums, on a
thread pool: the kernels release the GIL, so they run on every core.

The window sums run (:mod:`~dynia.engine.kernels.sums`): each window adds
the step entering it and subtracts the one leaving, so a window costs the
same whatever its length. They are compensated (TwoSum, a double-double
high/low per sample, rounded once as high + low), summed afresh from the
rows at every chunk's first window, and summed afresh from the rows, for
one sample, while an infinite error is in its window. The pair holds the
exact sum unless its low part itself rounds, so high + low is in practice
the exact sum rounded once (every one checked on thesis example 1, and no
bit changes with the chunks: tests/test_running_sums.py), and it is always
within about one rounding of it, where the numpy path's left-to-right sum
(the readable reference, equal to the thesis port) is within 2n roundings:
the two agree to a relative ``2 (2n + 2) 2^-53`` on the costs, not bit for
bit, and give identical IC, limits and median wherever the window's
behavioural set is the same (tests/test_fast.py states and checks that
contract, and how often it holds). The fused kernel and the error-row
kernel perform the same operations in the same order, so they agree bit
for bit, and so do any worker counts (workers split samples, never a sum).

Everything else is the numpy path's arithmetic in the same order: products
and sums of the recursion term by term (LLVM does not fuse them into FMAs
without fast-math, which stays off), the behavioural set as the first
``count`` of a stable sort, the likelihood total summed in index order (as
:func:`dynia.engine.cld.likelihood` does with ``cumsum``) and the gradient
accumulated in index order (as ``bincount``). The order statistics are
found without sorting, which cannot change their value: a window's
behavioural threshold (and every Monte Carlo batch's) and the noise floor's
quantile by selection among the few costs within a bracket around the
previous window's (:mod:`~dynia.engine.kernels.selection`); the limits and
median of the population's set, and the batches' limits, by counting their
members in a bitset of the samples' ranks, sorted once per run
(:mod:`~dynia.engine.kernels.ranks`; a small set's by selection). The two
passes over a window's samples form no cost they need not: the first counts
the sums against the selections' bounds carried to the sums (a cost grows
with its sum's magnitude), the second marks the few to keep in words of
bits and forms only their costs (:mod:`~dynia.engine.kernels.bits`).

This package needs numba; :data:`~dynia.engine.kernels.compile.AVAILABLE`
says whether it imported (:mod:`~dynia.engine.kernels.compile`).

A process compiles only what its runs use, since a newcomer's first run
waits for it: the lag models' kernels and the general ones are picked in
Python (:func:`~dynia.engine.kernels.driver.recursion_kernels`), not by a
branch that would compile both; the Monte Carlo batches' read-off compiles
with ``ic_error`` only; helpers that only compiled code calls have no
Python wrappers; and no kernel assigns one array slice to another, which
would compile numba's shape check and its message. All of them compile in
some 20 CPU-s, which is why a small run takes their numpy twin
(:mod:`dynia.engine.twin`) and compiles nothing.
"""

import importlib

# Each name loads its module on first use: importing the package loads neither numba nor a kernel, so a run that
# the numpy twin analyses (dynia.engine.twin) never imports numba (a third of a second).
_HOMES = {
    "AVAILABLE": "compile",
    "compiled": "driver",
    "CompiledErrors": "driver",
    "analyse_windows": "readoff",
    "analyse_windows_batched": "batches",
}

__all__ = list(_HOMES)


_MODULES = frozenset({"batches", "compile", "driver", "fused", "ranks", "readoff", "selection", "simulate", "sums"})


def __getattr__(name):
    if name in _HOMES:
        return getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
    if name in _MODULES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__) | _MODULES)
