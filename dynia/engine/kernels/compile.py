"""How the kernels are compiled: numba's nopython mode, without the GIL, cached on disk.

Every kernel of the package is made by :func:`jit` (a kernel Python calls)
or :func:`inner` (a helper only compiled code calls). Without numba both
leave the function as it is, and :data:`AVAILABLE` says so: the engine then
runs the numpy path.

numba's cache notices a change of the file that holds the kernel it loads,
not of the files whose helpers that kernel calls: a kernel of ``readoff.py``
cached before ``sums.py`` was edited would go on running the old sums. So on
import :func:`drop_stale_cache` deletes every cached kernel of the package
older than its newest source file, and they compile afresh.
"""

import hashlib
import importlib.util
import os
from pathlib import Path

# Whether numba is installed, found without importing it: it is imported when the first kernel is made.
AVAILABLE = importlib.util.find_spec("numba") is not None

__all__ = ["AVAILABLE", "jit", "inner", "drop_stale_cache"]


def drop_stale_cache(package=Path(__file__).parent):
    """Delete the cached kernels of ``package`` written before its newest source file changed.

    numba caches next to the sources (``__pycache__``), or under ``NUMBA_CACHE_DIR`` when that is set, in a folder
    named after the sources' directory and a hash of its path. An installed package's sources do not change after
    the install, so this finds nothing to do. Returns the number of files deleted.
    """
    newest = max(source.stat().st_mtime for source in package.glob("*.py"))
    folders = [package / "__pycache__"]
    if os.environ.get("NUMBA_CACHE_DIR"):
        elsewhere = Path(os.environ["NUMBA_CACHE_DIR"])
        # Recent numba keys the folder by the directory's name and a SHA-1 of its absolute path (a path too long
        # for Windows otherwise); older releases mirrored the absolute path. Both are looked in.
        directory = Path(os.path.abspath(package))
        hashed = hashlib.sha1(str(directory).encode()).hexdigest()
        folders += [elsewhere / f"{directory.name}_{hashed}", elsewhere / directory.relative_to(directory.anchor)]
    deleted = 0
    for folder in folders:
        for cached in [*folder.glob("*.nbi"), *folder.glob("*.nbc")]:
            try:
                if cached.stat().st_mtime < newest:
                    cached.unlink()
                    deleted += 1
            except OSError:  # gone already (another process dropped it), or not ours to delete: numba copes
                pass
    return deleted


def jit(function, **options):
    """``function`` compiled by numba, releasing the GIL (``options`` as ``numba.njit`` takes them), or as it is."""
    if not AVAILABLE:
        return function
    import numba

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


if AVAILABLE:
    drop_stale_cache()
