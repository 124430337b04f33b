"""How the kernels are compiled: numba's nopython mode, without the GIL, cached on disk.

Every kernel of the package is made by :func:`jit` (a kernel Python calls)
or :func:`inner` (a helper only compiled code calls). Without numba both
leave the function as it is, and :data:`AVAILABLE` says so: the engine then
runs the numpy path.

numba's cache notices a change of the file that holds the kernel it loads,
not of the files whose helpers that kernel calls: after editing a module of
this package, delete the cache (the ``__pycache__/*.nbi`` and ``*.nbc``
files next to it, or those under ``NUMBA_CACHE_DIR``) before running again.
"""

try:
    import numba
except ImportError:  # the numpy path serves
    numba = None

AVAILABLE = numba is not None

__all__ = ["AVAILABLE", "jit", "inner"]


def jit(function, **options):
    """``function`` compiled by numba, releasing the GIL (``options`` as ``numba.njit`` takes them), or as it is."""
    if not AVAILABLE:
        return function
    try:
        # Compiled once, then loaded from numba's on-disk cache: next to this module, else the user's cache directory.
        return numba.njit(nogil=True, cache=True, **options)(function)
    except RuntimeError:  # neither is writable (a read-only install, no home): compile in every process instead
        return numba.njit(nogil=True, **options)(function)


def inner(function):
    """:func:`jit` for a helper that only compiled code calls: no wrappers for calls from Python.

    Each wrapper is compiled with the function; leaving them out takes about a seventh off a first run's compile.
    """
    return jit(function, no_cpython_wrapper=True, no_cfunc_wrapper=True)
