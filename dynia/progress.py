"""Progress bars: when a front-end shows one, and which kind.

Every front-end (:func:`dynia.run`, :func:`dynia.suggest`,
:func:`dynia.identify`, :func:`dynia.second_run`,
:func:`dynia.adaptive.adaptive_run`, :func:`dynia.distributed.run`) takes
``progress``: ``True`` shows a tqdm bar on stderr, ``False`` none, and
``"auto"`` (their default) one where a person is likely to be watching:
when stderr is a terminal, or in a Jupyter notebook. Nothing of it reaches
the result, its files or stdout.

A notebook run headless (papermill, nbval) runs in a Jupyter kernel as
well; there ``"auto"`` would write the bar into the executed notebook's
stderr. tqdm's own switch, the environment variable ``TQDM_DISABLE=1``,
turns ``"auto"`` off: the Makefile sets it where it renders the reports,
and the test suite for the notebooks it executes.

In a notebook the bar is a widget when ipywidgets is installed, else text.
"""

import importlib.util
import os
import sys

import numpy as np

from .errors import SettingsError

__all__ = [
    "shows_progress",
    "progress_bar",
]

#: The values ``progress`` takes.
PROGRESS_CHOICES = (True, False, "auto")


def shows_progress(progress):
    """Whether a front-end given ``progress`` shows a bar here and now.

    Examples
    --------
    >>> shows_progress(False), shows_progress(True)
    (False, True)
    >>> shows_progress("auto")  # pytest's stderr is no terminal, and this is no notebook
    False
    """
    if isinstance(progress, (bool, np.bool_)):
        return bool(progress)
    if isinstance(progress, str) and progress == "auto":
        if os.environ.get("TQDM_DISABLE", "") not in ("", "0"):
            return False
        return stderr_is_terminal() or _in_notebook()
    raise SettingsError(f"progress must be True, False or 'auto'; got {progress!r}", "progress")


def progress_bar(progress, iterable=None, **options):
    """A tqdm bar over ``iterable`` (tqdm's ``options``, e.g. ``total``, ``desc``), or None without one."""
    if not shows_progress(progress):
        return None
    if _in_notebook() and importlib.util.find_spec("ipywidgets") is not None:
        from tqdm.notebook import tqdm
    else:
        # tqdm.auto would warn in a notebook without ipywidgets before falling back to this one.
        from tqdm.std import tqdm
    return tqdm(iterable, **options)


def stderr_is_terminal():
    """Whether stderr is a terminal (False for a replaced stream without ``isatty`` or a closed one)."""
    stream = sys.stderr
    try:
        return stream is not None and stream.isatty()
    except (AttributeError, ValueError):  # a replaced or closed stream
        return False


def _in_notebook():
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    # The shell of a Jupyter kernel; a terminal IPython's is TerminalInteractiveShell.
    return type(shell).__name__ == "ZMQInteractiveShell"
