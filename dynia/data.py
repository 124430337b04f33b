"""Process data: event logs onto the uniform grid DYNIA needs.

Plant historians log each tag on its own clock, and most log by exception:
a value is stored only when it has moved by more than a deadband since the
last stored value, or when a maximum interval has passed. The records are
dense while something happens and sparse while the plant is steady, and the
input and output of a loop have different timestamps. The models of
:mod:`dynia.models` and the moving window of :mod:`dynia.analysis` need one
input and one output value per step of a uniform grid;
:func:`resample_events` makes them, as the thesis did (section 3.1.3), by
linear interpolation.

Examples
--------
>>> from dynia.data import resample_events
>>> grid, u, y = resample_events([0, 2.5, 4], [1, 1, 3], [0.5, 4.5], [2, 6], dt=1)
>>> grid
array([0.5, 1.5, 2.5, 3.5])
>>> u
array([1.        , 1.        , 1.        , 2.33333333])
>>> y
array([2., 3., 4., 5.])
"""
import math
import numbers

import numpy as np

from . import _checks

__all__ = ["resample_events"]

# Relative slack when deciding whether ``stop`` is itself a grid point: stop -
# start is rarely an exact float multiple of dt (0.3/0.1 = 2.9999999999999996),
# and a grid that loses its last point to rounding would surprise.
_GRID_SNAP = 1e-9


def resample_events(times_u, u, times_y, y, dt=None, start=None, stop=None):
    """Resample two event-based logs onto a common uniform grid.

    Each log is a sequence of (time, value) records with its own strictly
    increasing timestamps. Both are linearly interpolated
    (:func:`numpy.interp`) onto ``start, start + dt, ...`` up to ``stop``;
    nothing is extrapolated, so the grid must lie where both logs have data.

    Parameters
    ----------
    times_u, u : array_like, shape (m,)
        Timestamps and values of the input log.
    times_y, y : array_like, shape (p,)
        Timestamps and values of the output log. The timestamps are plain
        numbers in any unit (seconds, minutes, ...); ``dt``, ``start``,
        ``stop`` and the returned grid are in the same unit.
    dt : float, optional
        Grid spacing, > 0. By default the median spacing of the union of both
        logs' timestamps inside [start, stop] (start and stop included); see
        Notes.
    start, stop : float, optional
        First and last time of the grid. By default the span in which both
        logs have data: ``max(times_u[0], times_y[0])`` and
        ``min(times_u[-1], times_y[-1])``. Given values must lie inside that
        span, with ``start < stop``. The last grid point is the last
        ``start + k*dt`` not after ``stop``.

    Returns
    -------
    grid : ndarray, shape (n_steps,)
        ``start + dt * arange(n_steps)``.
    u_on_grid, y_on_grid : ndarray, shape (n_steps,)
        Input and output interpolated onto ``grid``.

    Raises
    ------
    ValueError
        Naming the argument: a log whose times and values differ in length,
        timestamps that do not strictly increase (with the index), a
        non-finite time or value (with the index), ``dt <= 0``, logs that do
        not overlap in time, or ``start``/``stop`` outside the overlap.

    Notes
    -----
    The default ``dt`` is the median spacing of the union of both logs'
    timestamps: the typical interval between two consecutive records of the
    loop. It needs no unit and is robust: a few near-coincident timestamps
    of the two tags, or the long gaps of the steady stretches, do not move
    it. A grid much coarser than that would throw away the detail the logs
    hold where they are dense; a much finer one adds points that carry
    nothing new. What it lands on depends on how the logs were compressed.
    Exception reporting that stores each exception with the reading before
    it (as plant historians do) makes half the spacings one scan, so the
    median is about the scan period: the finest resolution the data have,
    and possibly many more grid points than needed. A log dominated by its
    steady stretches gives the steady logging interval, which can be
    coarser than the dynamics. When the time constants of the process are
    roughly known, pass a ``dt`` below the fastest of them instead (the
    chapter-3 case study passes 1 minute for a 2-minute time constant).

    Linear interpolation between two stored values is what an exception
    logging historian implies: every value in between was within the
    deadband of the stored ones. A step in a value is stored as the last
    value before and the first value after it, and stays a step on a grid
    coarser than that interval.

    Examples
    --------
    Two logs of one ramp, stored at different times, land on the ramp:

    >>> import numpy as np
    >>> from dynia.data import resample_events
    >>> grid, u, y = resample_events([0, 3, 10], [0, 3, 10], [1, 4, 9, 12], [2, 8, 18, 24], dt=2)
    >>> grid
    array([1., 3., 5., 7., 9.])
    >>> u, y
    (array([1., 3., 5., 7., 9.]), array([ 2.,  6., 10., 14., 18.]))

    Without ``dt`` the grid follows the median spacing of all timestamps
    (here 1 of the union 0, 1, 2, 3, 4, 6):

    >>> grid, u, y = resample_events([0, 2, 4, 6], [0, 0, 1, 1], [0, 1, 3, 6], [5, 5, 7, 7])
    >>> grid
    array([0., 1., 2., 3., 4., 5., 6.])
    """
    times_u, u = _log(times_u, u, "times_u", "u")
    times_y, y = _log(times_y, y, "times_y", "y")
    first = max(times_u[0], times_y[0])
    last = min(times_u[-1], times_y[-1])
    if not first < last:
        raise ValueError(
            f"the logs do not overlap in time: times_u spans [{times_u[0]}, {times_u[-1]}] and "
            f"times_y spans [{times_y[0]}, {times_y[-1]}]; a grid needs a stretch where both have data")
    start = first if start is None else _inside(start, "start", first, last)
    stop = last if stop is None else _inside(stop, "stop", first, last)
    if not start < stop:
        raise ValueError(f"start ({start}) must be before stop ({stop}): the grid would be empty")
    if dt is None:
        dt = _median_spacing(times_u, times_y, start, stop)
    else:
        dt = _checks.open_interval(dt, "dt", 0, math.inf)
    steps = math.floor((stop - start) / dt * (1 + _GRID_SNAP)) + 1
    grid = start + dt * np.arange(steps)
    grid[-1] = min(grid[-1], stop)  # a last point snapped onto stop must not pass it
    return grid, np.interp(grid, times_u, u), np.interp(grid, times_y, y)


def _log(times, values, times_name, values_name):
    """One event log as two float arrays of equal length with strictly increasing times."""
    times = _checks.as_1d_float(times, times_name)
    values = _checks.as_1d_float(values, values_name)
    if times.size != values.size:
        raise ValueError(
            f"{times_name} has {times.size} timestamps but {values_name} has {values.size} values; "
            "a log needs one timestamp per value")
    steps = np.diff(times)
    if (steps <= 0).any():
        index = int(np.argmax(steps <= 0)) + 1
        raise ValueError(
            f"{times_name} must be strictly increasing: {times_name}[{index}] = {times[index]} "
            f"follows {times_name}[{index - 1}] = {times[index - 1]}")
    return times, values


def _inside(value, name, first, last):
    """A finite number inside the span both logs cover, or raise naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number; got {value!r}")
    if not first <= value <= last:
        raise ValueError(
            f"{name} = {value} lies outside [{first}, {last}], the span in which both logs have data "
            "(values are interpolated, never extrapolated)")
    return float(value)


def _median_spacing(times_u, times_y, start, stop):
    """Median spacing of the union of the timestamps inside [start, stop], start and stop included."""
    union = np.union1d(times_u, times_y)
    union = np.union1d(union[(union >= start) & (union <= stop)], [start, stop])
    return float(np.median(np.diff(union)))
