"""pandas in: a record held as Series or DataFrames, with its time axis, taken apart for :func:`dynia.run`.

:func:`unpack` turns ``u`` and ``y`` given as pandas objects into the arrays
the analysis takes, and a DatetimeIndex into the grid spacing ``dt`` and the
timestamps of every step, which :class:`dynia.result.DyniaResult` keeps as its
``timestamps``. pandas stays optional: nothing here imports it unless the
caller has already done so, since a pandas object cannot exist before.

Examples
--------
>>> import pandas as pd
>>> from dynia.frames import unpack
>>> index = pd.date_range("2024-05-01 12:00", periods=4, freq="30s")
>>> u, y, dt, stamps = unpack(pd.Series([0.0, 1, 1, 1], index), pd.Series([0.0, 0.2, 0.5, 0.7], index))
>>> u, dt
(array([0., 1., 1., 1.]), 30.0)
>>> stamps[-1]
np.datetime64('2024-05-01T12:01:30.000000000')
"""

import math
import numbers
import sys

import numpy as np

from .errors import DataError, SettingsError

__all__ = ["unpack"]

# Index spacings count as uniform within this share of their mean, as in
# dynia.data.load_csv: a DatetimeIndex built with pd.date_range(start, end,
# periods=...) rounds each step to the nanosecond.
_UNIFORM = 1e-6


def unpack(u, y, dt=None):
    """Arrays, grid spacing and timestamps of a record given as numpy arrays or pandas objects.

    Parameters
    ----------
    u : array_like, pandas.Series or pandas.DataFrame
        The input. A DataFrame holds one input per column, in column order:
        shape (n_steps, n_inputs); one of a single column gives (n_steps,),
        like a Series.
    y : array_like, pandas.Series or single-column pandas.DataFrame
        The measured output; NaN (or a missing value of a nullable dtype)
        marks a missing measurement.
    dt : float, optional
        Sample time in seconds. With a DatetimeIndex it may be left out: it is
        the index's spacing; given, it must agree with that spacing.

    Returns
    -------
    u, y : ndarray
        The values. Anything that is not a pandas object comes back as it
        was given (and the checks of :func:`dynia.run` apply to it).
    dt : float or None
        The ``dt`` given, else the spacing of the DatetimeIndex in seconds,
        else None.
    timestamps : ndarray of datetime64[ns] or None
        The DatetimeIndex as numpy datetimes; None without one. A
        timezone-aware index is converted to UTC and returned without its
        zone, so that these are UTC times.

    Raises
    ------
    DataError
        A DataFrame ``y`` with more than one column; values that are not
        numbers; ``u`` and ``y`` on different indexes when either has a
        DatetimeIndex; a DatetimeIndex with a missing time (NaT), that does
        not strictly increase, or is not uniformly spaced (each named by its
        position and times).
    SettingsError
        A ``dt`` that is not a number, or differs from the index's spacing
        (``setting == "dt"``).

    Notes
    -----
    Other indexes (a RangeIndex, numbers) carry no time: their values are
    used in order and ``dt`` is what was given. A DatetimeIndex counts as
    uniform when every spacing is within 1e-6 of the first, relative to it,
    or within one tick of the index's unit (``pd.date_range(start, end,
    periods=3)`` rounds each step to it); ``dt`` is then the mean spacing,
    and ``dt`` given agrees when it is within 1e-6 of that, relative.
    Irregular logs go through :func:`dynia.data.resample_events` or
    :func:`dynia.data.load_csv` first, which make a uniform grid.

    Examples
    --------
    Two inputs in a DataFrame, the output in a Series on the same index:

    >>> import pandas as pd
    >>> index = pd.date_range("2024-05-01", periods=3, freq="2s", tz="Europe/Berlin")
    >>> frame = pd.DataFrame({"valve": [0.0, 1, 1], "load": [5.0, 5, 6]}, index)
    >>> u, y, dt, stamps = unpack(frame, pd.Series([1.0, 1.1, 1.3], index))
    >>> u.shape, dt, str(stamps[0])
    ((3, 2), 2.0, '2024-04-30T22:00:00.000000000')
    """
    pandas = sys.modules.get("pandas")
    if pandas is None:
        # Without pandas imported no pandas object exists: plain arrays, as given.
        return u, y, dt, None
    frame_types = (pandas.Series, pandas.DataFrame)
    u_index = u.index if isinstance(u, frame_types) else None
    y_index = y.index if isinstance(y, frame_types) else None
    u_values = _values(pandas, u, "u", many_columns=True) if u_index is not None else u
    y_values = _values(pandas, y, "y", many_columns=False) if y_index is not None else y
    dated = [index for index in (u_index, y_index) if isinstance(index, pandas.DatetimeIndex)]
    if not dated:
        return u_values, y_values, dt, None
    if u_index is not None and y_index is not None and not u_index.equals(y_index):
        raise DataError(
            f"u and y must share one time index: u's runs {_span(u_index)}, y's {_span(y_index)}; "
            "align them first (e.g. u.reindex(y.index)) or pass both on one DataFrame's index"
        )
    index = dated[0]
    name = "the index of u and y" if len(dated) == 2 else ("the index of u" if u_index is index else "the index of y")
    timestamps, quantum = _timestamps(index)
    spacing = _spacing(timestamps, quantum, name)
    if spacing is not None and dt is not None:
        _agreeing(dt, spacing, name)
    return u_values, y_values, (spacing if dt is None else dt), timestamps


def _values(pandas, value, name, many_columns):
    """A Series or DataFrame as a float array; a missing value of a nullable dtype becomes NaN."""
    if isinstance(value, pandas.DataFrame):
        columns = list(value.columns)
        if len(columns) == 1:
            value = value.iloc[:, 0]
        elif not many_columns:
            raise DataError(
                f"{name} must be a Series or a DataFrame of one column (the measured output); "
                f"got a DataFrame of {len(columns)} columns {columns}"
            )
    try:
        return value.to_numpy(dtype=float, na_value=np.nan)
    except (TypeError, ValueError) as error:
        raise DataError(f"{name} must hold numbers: {error}") from None


def _span(index):
    if len(index) == 0:
        return "an empty index"
    return f"{type(index).__name__} of {len(index)} from {index[0]} to {index[-1]}"


def _timestamps(index):
    """The index as naive UTC datetime64[ns], and the nanoseconds of one tick of the index's own unit."""
    if index.tz is not None:
        index = index.tz_convert("UTC").tz_localize(None)
    stamps = index.to_numpy()
    unit, count = np.datetime_data(stamps.dtype)
    return stamps.astype("datetime64[ns]"), int(np.timedelta64(count, unit) // np.timedelta64(1, "ns"))


def _spacing(timestamps, quantum, name):
    """Seconds between the steps of a strictly increasing, uniform index; None for fewer than 2 steps.

    Steps count as equal within ``_UNIFORM`` of the first, or one tick
    (``quantum`` ns) of the index's unit, by which a split interval rounds.
    """
    missing = np.isnat(timestamps)
    if missing.any():
        raise DataError(f"{name} has no time (NaT) at position {int(np.argmax(missing))}; expected a time per step")
    if timestamps.size < 2:
        return None
    steps = np.diff(timestamps.view(np.int64))
    if (steps <= 0).any():
        at = int(np.argmax(steps <= 0)) + 1
        how = "repeats" if steps[at - 1] == 0 else "is earlier than"
        raise DataError(
            f"{name} must strictly increase: position {at} ({timestamps[at]}) {how} position {at - 1} "
            f"({timestamps[at - 1]}); sort it and average or drop repeated times"
        )
    off = np.abs(steps - steps[0]) > max(_UNIFORM * steps[0], quantum)
    if off.any():
        at = int(np.argmax(off))
        raise DataError(
            f"{name} is not uniformly spaced: from position {at} ({timestamps[at]}) to {at + 1} "
            f"({timestamps[at + 1]}) is {steps[at] / 1e9:g} s, but from 0 to 1 {steps[0] / 1e9:g} s; "
            "dynia.data.resample_events or dynia.data.load_csv make a uniform grid"
        )
    return int(timestamps[-1].astype(np.int64) - timestamps[0].astype(np.int64)) / (timestamps.size - 1) / 1e9


def _agreeing(dt, spacing, name):
    if isinstance(dt, bool) or not isinstance(dt, numbers.Real) or not math.isfinite(dt):
        raise SettingsError(f"dt must be a finite number of seconds; got {dt!r}", "dt")
    if abs(dt - spacing) > _UNIFORM * spacing:
        raise SettingsError(
            f"dt = {dt:g} s disagrees with the {spacing:g} s spacing of {name}; leave dt out to use the index's",
            "dt",
        )
