"""Logged records onto the uniform grid as they arrive: :func:`dynia.io.csv.load_csv`'s grid, one batch at a time.

A follower of a database (``dynia follow``) sees a log grow row by row and
cannot wait for its end to grid it. :class:`StreamGrid` puts the records of
an output log and of one log per input onto ``origin + k dt`` as
:func:`~dynia.io.csv.load_csv` would, emitting a grid point as soon as every
log holds a record at or after it, since from then on nothing that arrives
in time order can change it:

* a record on a grid point (within 1e-6 of ``dt``) gives its value there, so
  uniformly spaced rows are used as they are, with the rows' own times;
* between records each signal is interpolated linearly; a missing output
  value (NaN) makes the points between it and its neighbours missing, a
  missing input value is left out of the input's log (filled by
  interpolation between the values around it);
* a grid point strictly inside a stretch of more than ``max_gap`` grid steps
  without a record of any log is a gap: its output is missing.

What differs from a whole file: ``dt``, when not given, is the median
spacing of the records of the first batch that holds two times (a file's
default is that of the whole file), and a point waits for the record after
it, so an input missing at the newest rows holds back the points after its
last value until its next value is logged (a file holds the last value).

Times are floats here, seconds from the first record; :mod:`dynia.io.database`
turns a source's timestamps into them and back.
"""

import dataclasses
import math

import numpy as np

from ..errors import DataError

__all__ = ["GridPoints", "StreamGrid"]

# A record this close to a grid point, relative to dt, is on it (load_csv's test of uniform rows).
_ON_GRID = 1e-6


@dataclasses.dataclass(frozen=True, eq=False)
class GridPoints:
    """Grid points that a batch completed: their indices, times, inputs and output.

    Attributes
    ----------
    index : ndarray (m,) of int
        Grid step ``k`` of each point.
    time : ndarray (m,)
        ``origin + k dt``, in seconds from the first record.
    record : ndarray (m,) of int
        The position, among all records fed so far, of the record each point
        lies on; -1 for a point between records.
    u : ndarray (m, n_inputs)
    y : ndarray (m,)
        NaN where missing or in a gap.
    """

    index: np.ndarray
    time: np.ndarray
    record: np.ndarray
    u: np.ndarray
    y: np.ndarray


class StreamGrid:
    """The uniform grid of logs that grow in time order (see the module documentation).

    Parameters
    ----------
    n_inputs : int
        Number of input logs.
    dt : float, optional
        Grid spacing in seconds; by default inferred from the first batch
        that holds two distinct times.
    max_gap : float, default 5
        Longest stretch without records that is interpolated across, in grid
        steps; ``math.inf`` interpolates across any.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.io.stream import StreamGrid
    >>> grid = StreamGrid(1)
    >>> points = grid.feed([0.0, 1.0, 2.0], [[0.0], [1.0], [2.0]], [5.0, np.nan, 7.0])
    >>> points.index.tolist(), points.u[:, 0].tolist(), points.y.tolist()
    ([0, 1, 2], [0.0, 1.0, 2.0], [5.0, nan, 7.0])
    >>> grid.feed([5.0], [[5.0]], [8.0]).y.tolist()  # 3 and 4 between records, no gap
    [7.333333333333333, 7.666666666666667, 8.0]
    """

    def __init__(self, n_inputs, dt=None, max_gap=5.0):
        self.n_inputs = n_inputs
        self.dt = dt
        self.max_gap = max_gap
        self.next_index = 0
        self.records = 0  # records fed so far, whatever happened to them
        # Each log as (times, values, record positions); only the records a later point can still need are kept.
        self._inputs = [_empty_log() for _ in range(n_inputs)]
        self._output = _empty_log()
        self._any = _empty_log()  # the times of every record of any log: the gaps are between them

    def feed(self, time, u, y):
        """Add rows (one record of every log per row) in time order; return the grid points they complete.

        Parameters
        ----------
        time : array_like (m,)
            Seconds from the first record, strictly increasing and after
            every time fed before.
        u : array_like (m, n_inputs)
            NaN where an input was not logged in that row.
        y : array_like (m,)
            NaN where the output is missing.

        Returns
        -------
        GridPoints
        """
        time = np.asarray(time, dtype=float)
        u = np.asarray(u, dtype=float).reshape(time.size, self.n_inputs)
        y = np.asarray(y, dtype=float)
        return self.feed_logs(time, [(time, u[:, j]) for j in range(self.n_inputs)], (time, y))

    def feed_logs(self, row_times, inputs, output):
        """Add the records of separate logs (a long table's tags); return the grid points they complete.

        ``row_times`` are the times of every record of any log (the rows of
        the source, sorted); ``inputs`` one (times, values) pair per input,
        ``output`` the output's (times, values), each sorted and after what
        was fed before.
        """
        positions = self.records + np.arange(len(row_times))
        self._any = _joined(self._any, np.asarray(row_times, dtype=float), np.zeros(len(row_times)), positions)
        for j, (times, values) in enumerate(inputs):
            times, values = np.asarray(times, dtype=float), np.asarray(values, dtype=float)
            present = ~np.isnan(values)  # a missing input value is interpolated across
            at = _at(row_times, times)[present] + self.records
            self._inputs[j] = _joined(self._inputs[j], times[present], values[present], at)
        times, values = np.asarray(output[0], dtype=float), np.asarray(output[1], dtype=float)
        self._output = _joined(self._output, times, values, _at(row_times, times) + self.records)
        self.records += len(row_times)
        if self.dt is None:
            self.dt = _first_spacing(self._any[0])
            if self.dt is None:
                return self._nothing()
        return self._complete()

    @property
    def first_record(self):
        """The position of the earliest record a later grid point can still lie on (``records`` if none)."""
        positions = self._any[2]
        return int(positions[0]) if positions.size else self.records

    def _complete(self):
        """The grid points every log has reached, from ``next_index`` on; drops the records no later point needs."""
        logs = [*self._inputs, self._output]
        if any(times.size == 0 for times, _, _ in logs):
            return self._nothing()
        tolerance = _ON_GRID * self.dt
        reached = min(times[-1] for times, _, _ in logs)
        last = math.floor(reached / self.dt + _ON_GRID)
        if last < self.next_index:
            return self._nothing()
        index = np.arange(self.next_index, last + 1)
        grid = index * self.dt
        u = np.column_stack([_interpolated(log, grid, tolerance, hold=True)[0] for log in self._inputs])
        y, _ = _interpolated(self._output, grid, tolerance, hold=False)
        _, record = _interpolated(self._any, grid, tolerance, hold=False)
        y[self._in_gap(grid, tolerance)] = np.nan
        self.next_index = last + 1
        following = self.next_index * self.dt - tolerance
        self._inputs = [_pruned(log, following) for log in self._inputs]
        self._output, self._any = _pruned(self._output, following), _pruned(self._any, following)
        return GridPoints(index=index, time=grid, record=record, u=u, y=y)

    def _in_gap(self, grid, tolerance):
        """Whether each point lies strictly between two records of any log more than ``max_gap`` steps apart."""
        times = self._any[0]
        after = np.searchsorted(times, grid - tolerance)
        on_record = np.abs(times[np.minimum(after, times.size - 1)] - grid) <= tolerance
        before = np.maximum(after - 1, 0)
        spacing = times[np.minimum(after, times.size - 1)] - times[before]
        return ~on_record & (after > 0) & (spacing > self.max_gap * self.dt + tolerance)

    def _nothing(self):
        empty = np.empty(0)
        return GridPoints(
            index=np.empty(0, dtype=np.int64),
            time=empty,
            record=np.empty(0, dtype=np.int64),
            u=np.empty((0, self.n_inputs)),
            y=empty,
        )

    def state(self):
        """What :meth:`restored` needs to go on: plain numbers and lists (JSON)."""

        def listed(log):
            return [array.tolist() for array in log]

        return dict(
            n_inputs=self.n_inputs,
            dt=self.dt,
            max_gap=None if math.isinf(self.max_gap) else self.max_gap,
            next_index=self.next_index,
            records=self.records,
            inputs=[listed(log) for log in self._inputs],
            output=listed(self._output),
            any=listed(self._any),
        )

    @classmethod
    def restored(cls, state):
        """The grid of :meth:`state`."""
        grid = cls(state["n_inputs"], state["dt"], math.inf if state["max_gap"] is None else state["max_gap"])
        grid.next_index, grid.records = state["next_index"], state["records"]

        def log(lists):
            times, values, positions = lists
            return np.array(times, dtype=float), np.array(values, dtype=float), np.array(positions, dtype=np.int64)

        grid._inputs = [log(lists) for lists in state["inputs"]]
        grid._output, grid._any = log(state["output"]), log(state["any"])
        return grid


def _empty_log():
    return np.empty(0), np.empty(0), np.empty(0, dtype=np.int64)


def _at(row_times, times):
    """The positions in ``row_times`` of ``times`` (each one of them)."""
    return np.searchsorted(np.asarray(row_times, dtype=float), np.asarray(times, dtype=float))


def _joined(log, times, values, positions):
    """``log`` with the records appended; their times must come after its last."""
    if times.size and log[0].size and not times[0] > log[0][-1]:
        raise DataError(f"a record at {times[0]:g} s does not come after the last one fed ({log[0][-1]:g} s)")
    if times.size > 1 and not np.all(np.diff(times) > 0):
        step = int(np.flatnonzero(np.diff(times) <= 0)[0])
        raise DataError(f"record times must increase; {times[step + 1]:g} s follows {times[step]:g} s")
    return (
        np.concatenate((log[0], times)),
        np.concatenate((log[1], values)),
        np.concatenate((log[2], np.asarray(positions, dtype=np.int64))),
    )


def _first_spacing(times):
    """The median spacing of ``times``, or None while they hold fewer than two."""
    if times.size < 2:
        return None
    return float(np.median(np.diff(times)))


def _interpolated(log, grid, tolerance, hold):
    """``log`` at the grid points: a record's value on it, else linear between the records around it.

    Returns the values and, per point, the position of the record it lies on
    (-1 if none). Before the first record the first value is held when
    ``hold`` (an input), else the value is NaN.
    """
    times, values, positions = log
    after = np.searchsorted(times, grid - tolerance)
    nearest = np.minimum(after, times.size - 1)
    on_record = np.abs(times[nearest] - grid) <= tolerance
    before = np.maximum(after - 1, 0)
    span = times[nearest] - times[before]
    with np.errstate(invalid="ignore", divide="ignore"):
        weight = np.where(span > 0, (grid - times[before]) / span, 0.0)
    result = values[before] + weight * (values[nearest] - values[before])
    result = np.where(on_record, values[nearest], result)
    if not hold:
        result = np.where(~on_record & (after == 0), np.nan, result)
    else:
        result = np.where(after == 0, values[nearest], result)
    return result, np.where(on_record, positions[nearest], -1)


def _pruned(log, following):
    """``log`` without the records before the last one at or before ``following`` (the next point's time)."""
    times = log[0]
    keep = max(int(np.searchsorted(times, following, side="right")) - 1, 0)
    return tuple(array[keep:] for array in log)
