"""The errors dynia raises on purpose: one type per kind of mistake.

Every one is a :class:`DyniaError`, itself a ``ValueError`` so that code
written against earlier versions (``except ValueError``) keeps working. The
command line catches :class:`DyniaError` only and reports it as one line with
exit status 2; any other exception is a bug in dynia and shows its traceback.
Callers branch on the type, never on the message text.

Examples
--------
>>> import dynia
>>> from dynia.errors import DyniaError, SettingsError
>>> try:
...     dynia.sampling.sample("uniform", 0, [[0.0, 1.0]], 1)
... except SettingsError as error:
...     print(type(error).__name__, isinstance(error, DyniaError))
SettingsError True
"""

__all__ = [
    "DyniaError",
    "DataError",
    "SettingsError",
    "ModelError",
    "OutputError",
    "SuggestionError",
    "NothingSelected",
    "Interrupted",
]


class DyniaError(ValueError):
    """A mistake in what dynia was given; the message is one line saying what and where."""


class DataError(DyniaError):
    """Bad input data: the message names the file or array, the column and row, and what was expected."""


class SettingsError(DyniaError):
    """An option or argument out of range, of the wrong type, or in conflict with another.

    ``setting`` names the setting at fault where one does (the name used in
    the message), so that a front-end can name it its own way, e.g. the
    command line's ``--conf-level`` for ``conf_level``.
    """

    def __init__(self, message, setting=None):
        super().__init__(message)
        self.setting = setting


class ModelError(DyniaError):
    """A model that cannot be simulated as asked: wrong parameters, shapes, or a simulation that fails."""


class OutputError(DyniaError):
    """An output location dynia refuses to write to, so that nothing the user owns is lost."""


class Interrupted(Exception):
    """The run was stopped by a signal (SIGINT, SIGTERM, SIGHUP); partial results were removed.

    Not a :class:`DyniaError`: nothing was wrong with the input.
    """

    def __init__(self, signal_name):
        super().__init__(f"interrupted by {signal_name}")
        self.signal_name = signal_name


class SuggestionError(DyniaError):
    """No settings can be proposed from this record (:func:`dynia.suggest`): the message says why."""


class NothingSelected(DyniaError):
    """A selection of data came out empty: no informative window, segment or interval to fit on.

    Raised by the functions that select data (:func:`dynia.segments.segments_from_ic`,
    :func:`dynia.identify`, ...) instead of returning nothing; the message says which
    rule selected nothing and what to change.
    """
