"""pandas in: a record held as Series or DataFrames, with its time axis, taken apart for :func:`dynia.run`.

:func:`unpack` turns ``u`` and ``y`` given as pandas objects into the arrays
the analysis takes, a time index (dates, durations or seconds) into the grid
spacing ``dt``, and a DatetimeIndex into the timestamps of every step, which
:class:`dynia.result.DyniaResult` keeps as its ``timestamps``. pandas stays optional: nothing here imports it unless the
caller has already done so, since a pandas object cannot exist before.

Examples
--------
>>> import pandas as pd
>>> from dynia.io.frames import unpack
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

from ..errors import DataError, SettingsError

__all__ = ["unpack"]

# Index spacings count as uniform within this share of their mean, as in
# dynia.io.csv.load_csv: a DatetimeIndex built with pd.date_range(start, end,
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
        Sample time in seconds. With a time index (see Notes) it may be left
        out: it is the index's spacing; given, it must agree with that spacing.

    Returns
    -------
    u, y : ndarray
        The values. Anything that is not a pandas object comes back as it
        was given (and the checks of :func:`dynia.run` apply to it).
    dt : float or None
        The ``dt`` given, else the spacing of the time index in seconds, else
        None.
    timestamps : ndarray of datetime64[ns] or None
        The DatetimeIndex as numpy datetimes; None without one. A
        timezone-aware index is converted to UTC and returned without its
        zone, so that these are UTC times.

    Raises
    ------
    DataError
        A DataFrame ``y`` with more than one column; values that are not
        numbers; ``u`` and ``y`` both pandas objects on different indexes
        (of any kind: their values would be paired by position); a time
        index with a missing time (NaT, NaN), that does not strictly
        increase, or is not uniformly spaced (each named by its position and
        times).
    SettingsError
        A ``dt`` that is not a number, or differs from the index's spacing
        (``setting == "dt"``).

    Notes
    -----
    Three kinds of index carry time: a DatetimeIndex (dates; they become
    ``timestamps``), a TimedeltaIndex (time since some start), and a
    numeric index other than pandas' RangeIndex, read as seconds (a float
    index of seconds, as a resampled log has). A RangeIndex (pandas'
    default) and labels carry none: the values are used in order and
    ``dt`` is what was given. When both ``u`` and ``y`` are pandas objects
    their indexes must be equal, whatever their kind, so that no value of
    ``u`` is paired with the ``y`` of another label; a numeric index of
    sample numbers is better dropped (``reset_index(drop=True)``), with
    ``dt`` given. A DatetimeIndex or TimedeltaIndex counts as uniform when
    every spacing is within 1e-6 of the first, relative to it, or within one
    tick of the index's unit (``pd.date_range(start, end, periods=3)``
    rounds each step to it), a numeric one when every spacing is within
    1e-6 of their mean, relative; ``dt`` is then the mean spacing, and
    ``dt`` given agrees when it is within 1e-6 of that, relative.
    Irregular logs go through :func:`dynia.io.csv.resample_events` or
    :func:`dynia.io.csv.load_csv` first, which make a uniform grid.

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
    if u_index is not None and y_index is not None and not u_index.equals(y_index):
        # Paired by position, two indexes that differ would match a label of u with another label of y.
        raise DataError(
            f"u and y must share one index, or their values would be paired by position: u's is {_span(u_index)}, "
            f"y's {_span(y_index)}; align them first (e.g. u.reindex(y.index)), pass both on one DataFrame's index, "
            "or pass numpy arrays (u.to_numpy()) with dt"
        )
    both = u_index is not None and y_index is not None
    index = y_index if y_index is not None else u_index
    if index is None:
        return u_values, y_values, dt, None
    name = "the index of u and y" if both else ("the index of y" if index is y_index else "the index of u")
    if isinstance(index, pandas.DatetimeIndex):
        timestamps, quantum = _timestamps(index)
        spacing = _spacing(timestamps, quantum, name)
    elif isinstance(index, pandas.TimedeltaIndex):
        timestamps = None
        spacing = _spacing(*_elapsed(index), name)
    elif _numeric(pandas, index):
        timestamps = None
        spacing = _numeric_spacing(index.to_numpy(dtype=float), name)
    else:
        # A RangeIndex (pandas' default) or labels (text) carry no time: the values in order, dt as given.
        return u_values, y_values, dt, None
    if spacing is not None and dt is not None:
        _agreeing(dt, spacing, name, numeric=timestamps is None)
    return u_values, y_values, (spacing if dt is None else dt), timestamps


def _numeric(pandas, index):
    """Whether ``index`` holds numbers that are times in seconds: numeric, not boolean, not pandas' RangeIndex."""
    kind = index.dtype
    return (
        not isinstance(index, pandas.RangeIndex)
        and pandas.api.types.is_numeric_dtype(kind)
        and not pandas.api.types.is_bool_dtype(kind)
        and not pandas.api.types.is_complex_dtype(kind)
    )


def _elapsed(index):
    """A TimedeltaIndex as timedelta64[ns], and the nanoseconds of one tick of the index's own unit."""
    times = index.to_numpy()
    unit, count = np.datetime_data(times.dtype)
    return times.astype("timedelta64[ns]"), int(np.timedelta64(count, unit) // np.timedelta64(1, "ns"))


def _numeric_spacing(seconds, name):
    """Mean spacing of a numeric time index in seconds, after checking it is finite, increasing and uniform."""
    how = "read as time in seconds"
    bad = ~np.isfinite(seconds)
    if bad.any():
        raise DataError(
            f"{name} ({how}) holds {seconds[bad][0]} at position {int(np.argmax(bad))}; expected a finite time per "
            "step, or drop the index (reset_index(drop=True)) and give dt"
        )
    if seconds.size < 2:
        return None
    steps = np.diff(seconds)
    if (steps <= 0).any():
        at = int(np.argmax(steps <= 0)) + 1
        relation = "repeats" if steps[at - 1] == 0 else "is below"
        raise DataError(
            f"{name} ({how}) must strictly increase: position {at} ({seconds[at]:g}) {relation} position {at - 1} "
            f"({seconds[at - 1]:g}); sort it, or drop the index (reset_index(drop=True)) and give dt"
        )
    spacing = (seconds[-1] - seconds[0]) / (seconds.size - 1)
    off = np.abs(steps - spacing) > _UNIFORM * spacing
    if off.any():
        at = int(np.argmax(off))
        raise DataError(
            f"{name} ({how}) is not uniformly spaced: from position {at} ({seconds[at]:g}) to {at + 1} "
            f"({seconds[at + 1]:g}) is {steps[at]:g} s, against {spacing:g} s on average; "
            "dynia.io.csv.resample_events makes a uniform grid"
        )
    return float(spacing)


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
            "dynia.io.csv.resample_events or dynia.io.csv.load_csv make a uniform grid"
        )
    return int(timestamps[-1].astype(np.int64) - timestamps[0].astype(np.int64)) / (timestamps.size - 1) / 1e9


def _agreeing(dt, spacing, name, numeric=False):
    if isinstance(dt, bool) or not isinstance(dt, numbers.Real) or not math.isfinite(dt):
        raise SettingsError(f"dt must be a finite number of seconds; got {dt!r}", "dt")
    if abs(dt - spacing) > _UNIFORM * spacing:
        hint = (
            " (a numeric index is read as time in seconds: if it holds sample numbers, drop it with "
            "reset_index(drop=True))"
            if numeric
            else ""
        )
        raise SettingsError(
            f"dt = {dt:g} s disagrees with the {spacing:g} s spacing of {name}; leave dt out to use the index's{hint}",
            "dt",
        )
