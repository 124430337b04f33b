"""Process data: logged plant data onto the uniform grid DYNIA needs.

The models of :mod:`dynia.models` and the moving window of
:mod:`dynia.engine` need one input and one output value per step of a
uniform grid. :func:`load_csv` makes them from what an engineer exports: a
CSV file with one row per sample, two event logs in two files, or a
historian's long table of (time, tag, value) rows. It returns a
:class:`ProcessData` and says in its ``notes`` what it did to the data, and
it stops with a one-line :class:`DataError` naming the file, row and column
of anything it cannot read.

Plant historians log each tag on its own clock, and most log by exception:
a value is stored only when it has moved by more than a deadband since the
last stored value, or when a maximum interval has passed. The records are
dense while something happens and sparse while the plant is steady, and the
input and output of a loop have different timestamps.
:func:`resample_events` puts two such logs on one uniform grid, as the
thesis did (section 3.1.3), by linear interpolation. :func:`load_csv`
bridges stretches without records only up to ``max_gap`` grid steps: inside
a longer one the output is left missing (NaN), so that no window is fitted
to values the file never held, and a note names each such gap.

Examples
--------
>>> from dynia.io.csv import resample_events
>>> grid, u, y = resample_events([0, 2.5, 4], [1, 1, 3], [0.5, 4.5], [2, 6], dt=1)
>>> grid
array([0.5, 1.5, 2.5, 3.5])
>>> u
array([1.        , 1.        , 1.        , 2.33333333])
>>> y
array([2., 3., 4., 5.])
"""

import dataclasses
import datetime
import math
import numbers

import numpy as np

from .. import _checks
from ..errors import DataError, SettingsError
from ._csv_columns import (
    at_least_two_rows,
    averaged_repeats,
    column_log,
    common_origin,
    elapsed,
    filled_input,
    output_gaps,
    parse_times,
    parse_values,
    tag_logs,
)
from ._csv_table import counted, read_table

__all__ = ["DataError", "ProcessData", "load_csv", "resample_events"]

# Relative slack when deciding whether ``stop`` is itself a grid point: stop -
# start is rarely an exact float multiple of dt (0.3/0.1 = 2.9999999999999996),
# and a grid that loses its last point to rounding would surprise.
_GRID_SNAP = 1e-9

# Rows count as uniformly spaced when every spacing is this close to their
# mean, relative to it: times printed with a few decimals or summed in floats
# are never exactly uniform, and an error of 1e-6 in dt is far below anything
# a moving-window analysis can resolve.
_UNIFORM = 1e-6

# A grid longer than this comes from a dt in the wrong unit (or a log whose
# median spacing is a burst of near-coincident records); it would take
# gigabytes before the analysis even starts.
_MAX_GRID_STEPS = 10_000_000

# The notes name this many gaps one by one and only count the rest: a log
# with thousands of them should not bury the other notes.
_LISTED_GAPS = 5

# What load_csv does with rows of one log that share a time: stop, or average them.
_DUPLICATES = ("error", "mean")


@dataclasses.dataclass(frozen=True, eq=False)
class ProcessData:
    """One input and one output on a uniform time grid, ready for DYNIA.

    ``u`` and ``y`` go to :func:`dynia.run` as they are, with ``dt=data.dt``.

    Attributes
    ----------
    time : ndarray, shape (n_steps,)
        Seconds from the start of the record, ``time[0] + dt * arange(n_steps)``.
        ``time[0]`` is 0.0 unless the signals start at different times, when
        the grid starts where both have data.
    u : ndarray, shape (n_steps,)
        Input, finite everywhere.
    y : ndarray, shape (n_steps,)
        Output, NaN where the measurement is missing and inside the ``gaps``.
    dt : float
        Grid spacing in seconds.
    start : datetime.datetime or float
        The file's own time at ``time == 0``: a timestamp when the file had
        ISO 8601 timestamps (with its UTC offset if they had one), else the
        number in its time column. ``start + time`` is the file's time of a
        grid point.
    notes : tuple of str
        What was done to the data, one sentence each: resampling, filled
        inputs, missing outputs, gaps. Empty when the rows were used as they
        are.
    gaps : tuple of (int, int)
        Grid index ranges ``[start, stop)``, in time order, where ``y`` is
        NaN because the file has no rows there for longer than ``max_gap``
        grid steps (see :func:`load_csv`). Empty when there is no such gap.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.io.csv import ProcessData
    >>> data = ProcessData(time=np.array([0.0, 2.0, 4.0]), u=np.array([1.0, 1.0, 2.0]),
    ...                    y=np.array([0.0, np.nan, 0.8]), dt=2.0, start=0.0,
    ...                    notes=("1 output value missing, left as NaN in y",))
    >>> int(np.isnan(data.y).sum()), data.time.size * data.dt, data.gaps
    (1, 6.0, ())
    """

    time: np.ndarray
    u: np.ndarray
    y: np.ndarray
    dt: float
    start: datetime.datetime | float
    notes: tuple[str, ...]
    gaps: tuple[tuple[int, int], ...] = ()


def load_csv(
    path,
    *,
    time,
    input,
    output,
    output_path=None,
    long_format=False,
    tag_column="tag",
    value_column="value",
    dt=None,
    max_gap=5.0,
    duplicates="error",
    time_format=None,
):
    """Read logged process data from CSV into a uniform :class:`ProcessData`.

    Three layouts are read:

    * wide (default): ``path`` has a time, an input and an output column,
      one row per sample;
    * two files (``output_path`` given): ``path`` holds the time and input
      columns, ``output_path`` its own time column (also named ``time``) and
      the output column, each an event log with its own timestamps;
    * long (``long_format=True``): ``path`` has the columns ``time``,
      ``tag_column`` and ``value_column``, one row per stored value of any
      tag; ``input`` and ``output`` name tags, and each tag's rows form an
      event log.

    Parameters
    ----------
    path : str, os.PathLike or file-like
        The CSV file (the input file when ``output_path`` is given), or an
        open text or binary stream of it (anything with a ``read`` method,
        read to its end; the caller closes it). Messages name a stream by its
        ``name`` attribute when that is a str, else as ``<stream>``.
    time, input, output : str
        Column names, matched exactly after stripping whitespace; in the long
        layout ``input`` and ``output`` are tag names.
    output_path : str, os.PathLike or file-like, optional
        A second CSV file holding the output's event log.
    long_format : bool, default False
        Read ``path`` as a long (time, tag, value) table.
    tag_column, value_column : str
        The long layout's tag and value columns.
    dt : float, optional
        Grid spacing in seconds, > 0. By default the spacing of uniformly
        spaced rows, else the median spacing of the timestamps (see Notes).
    max_gap : float or None, default 5.0
        Longest stretch without rows that is interpolated across, in grid
        steps (``max_gap * dt`` seconds): a number > 1, or None (or
        ``math.inf``) to interpolate across stretches of any length. Inside a
        longer stretch ``y`` is NaN (see Notes).
    duplicates : {"error", "mean"}, default "error"
        Rows of one log that share a time: a DataError naming them, or
        "mean": one row per time holding the mean of their values, per
        signal, missing values ignored (missing when all are); a note counts
        the rows averaged. Only consecutive rows can share a time: times that
        go back are always an error.
    time_format : str, optional
        A :meth:`datetime.datetime.strptime` format of the time column, for
        timestamps that are not ISO 8601, e.g. ``"%d.%m.%Y %H:%M"`` for
        ``01.01.2012 00:15``; every time cell must match it (a ``%z`` makes
        timestamps with UTC offset). By default numbers of seconds or ISO
        8601 timestamps are read.

    Returns
    -------
    ProcessData

    Raises
    ------
    DataError
        One line naming the file, row and column: a file that is missing,
        empty or has no data rows, a missing column or tag, a cell that is
        not a number, a time that is missing, not finite, not a timestamp or
        of another kind than the rows before (seconds, timestamps with or
        without UTC offset), times that do not strictly increase (duplicates
        included, unless ``duplicates="mean"``), fewer than 2 rows or times, an input or output without any value,
        logs that do not overlap in time, or a ``dt`` that gives fewer than
        2 grid points or more than 10 000 000.
    SettingsError
        ``time``, ``input`` or ``output`` not a column name (a str), ``input``
        or ``output`` naming the time column, a ``time_format`` that is not a
        str, ``output_path`` given together with ``long_format``, a ``dt`` that is
        not a finite number > 0, a ``max_gap`` that is not a number > 1
        or None, or a ``duplicates`` other than "error" and "mean".

    Notes
    -----
    **Reading.** The first non-blank row is the header. Columns are
    separated by commas, unless the header (outside quotes) holds no comma
    and exactly one of semicolon and tab: then by that one. Blank rows are
    skipped; a row shorter than the header is missing its last cells, one
    longer than the header with anything in the extra cells is an error
    (often a decimal comma in a comma-separated file). Files are read as
    UTF-8, or as Windows-1252 (what Excel writes) when they are not UTF-8.
    Empty cells and ``NaN``, ``NA``, ``null`` (any case) are missing values.

    **Time.** A time column holds numbers of seconds or ISO 8601 timestamps
    (:meth:`datetime.datetime.fromisoformat`, with a trailing ``Z`` read as
    UTC); timestamps with a UTC offset are compared across offsets, so a
    daylight-saving change is no jump. Time zero is the first row, or for
    two logs the earlier of their first rows.

    **Grid.** Uniformly spaced rows (every spacing within 1e-6 of their mean,
    relative) are used as they are, with ``dt`` their mean spacing. Other
    rows, rows whose spacing differs from a given ``dt``, and every pair of
    event logs are interpolated linearly onto ``time[0] + k * dt`` by
    :func:`resample_events`, over the span where both signals have rows;
    the default ``dt`` is then the median spacing of all timestamps (of the
    rows, or of the union of both logs), as :func:`resample_events` infers
    it. See there for when to pass a ``dt`` instead.

    **Missing input values** are filled by linear interpolation between the
    nearest present values in time, held constant before the first and after
    the last.

    **Missing output values** are gaps. On rows used as they are, ``y`` is
    NaN there. On a resampled grid, a point is NaN when it falls on a missing
    value's row or between a missing value and the present values on either
    side of it: exactly the points whose interpolation between neighbouring
    rows would use a missing value. All other points interpolate between the
    present values around them, unless they lie in a gap. The timestamps of
    missing values still count for the span, for ``dt`` and as rows.

    **Gaps.** Where two consecutive rows (for two event logs: two
    consecutive records of either log) lie more than ``max_gap * dt`` apart,
    the grid points strictly between them are NaN in ``y``: the windows there
    report no IC instead of fitting values the file never held. ``u`` is
    filled there as everywhere, since a simulation needs an input at every
    step. ``gaps`` holds these grid ranges, and a note names each gap with
    its length and its two times as the file wrote them (the first five
    gaps; the rest are counted). Uniform rows used as they are have no gaps.
    The limit counts grid steps, so a given ``dt`` far below the spacing of
    the rows, or an input logged far more slowly than the output (the
    default ``dt`` follows the denser log), turns ordinary spacings into
    gaps. A historian that logs by exception with a deadband stores nothing
    while a signal stays within it, so its long stretches without records
    can be steady operation rather than lost data: when the notes show gaps
    where the plant was steady, raise ``max_gap`` above the longest steady
    interval (in grid steps), or pass ``max_gap=None`` to interpolate across
    stretches of any length.

    Examples
    --------
    Uniform rows are used as they are; a missing output stays NaN:

    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> from dynia.io.csv import load_csv
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     csv_path = pathlib.Path(folder, "loop.csv")
    ...     _ = csv_path.write_text("time,u,y\\n0,1,0.0\\n2,1,0.5\\n4,2,\\n6,2,1.4\\n")
    ...     data = load_csv(csv_path, time="time", input="u", output="y")
    >>> data.dt, data.time, data.y
    (2.0, array([0., 2., 4., 6.]), array([0. , 0.5, nan, 1.4]))
    >>> data.notes
    ('1 output value missing, left as NaN in y',)

    Irregular ISO timestamps are resampled; ``start`` keeps the first one:

    >>> with tempfile.TemporaryDirectory() as folder:
    ...     csv_path = pathlib.Path(folder, "loop.csv")
    ...     _ = csv_path.write_text("time;u;y\\n2024-05-01T12:00:00Z;0;10\\n"
    ...                             "2024-05-01T12:00:01Z;1;10\\n2024-05-01T12:00:04Z;4;13\\n")
    ...     data = load_csv(csv_path, time="time", input="u", output="y")
    >>> data.start.isoformat(), data.dt, data.u
    ('2024-05-01T12:00:00+00:00', 2.0, array([0., 2., 4.]))
    >>> print(*data.notes)
    resampled 3 irregular rows onto a 2 s grid by linear interpolation (dt inferred: the median spacing of the rows)

    A stretch without rows longer than ``max_gap`` grid steps is left missing in ``y``:

    >>> with tempfile.TemporaryDirectory() as folder:
    ...     csv_path = pathlib.Path(folder, "loop.csv")
    ...     _ = csv_path.write_text("time,u,y\\n0,1,5\\n1,1,5\\n2,1,5\\n10,2,6\\n11,2,6\\n")
    ...     data = load_csv(csv_path, time="time", input="u", output="y")
    >>> data.dt, data.gaps, int(np.isnan(data.y).sum()), bool(np.isfinite(data.u).all())
    (1.0, ((3, 10),), 7, True)
    >>> print(data.notes[-1])
    gap of 8 s with no rows from 2 to 10: 7 grid points left missing in y

    What cannot be read stops with one line naming the file (and the row and column):

    >>> from dynia.errors import DataError
    >>> try:
    ...     load_csv("no_such_file.csv", time="time", input="u", output="y")
    ... except DataError as error:
    ...     print(error)
    no_such_file.csv: no such file; expected a CSV file with a header row
    """
    _check_names(time, input, output, long_format, output_path)
    if time_format is not None and (not isinstance(time_format, str) or "%" not in time_format):
        raise SettingsError(
            f"time_format must be a strptime format such as '%d.%m.%Y %H:%M'; got {time_format!r}", "time_format"
        )
    if long_format and output_path is not None:
        raise SettingsError(
            "long_format reads both signals from one file; do not give output_path with it", "output_path"
        )
    if dt is not None:
        dt = _grid_spacing(dt)
    max_gap = _gap_limit(max_gap)
    if duplicates not in _DUPLICATES:
        raise SettingsError(
            f"duplicates must be one of {', '.join(map(repr, _DUPLICATES))}; got {duplicates!r}", "duplicates"
        )
    average = duplicates == "mean"
    if long_format:
        table = read_table(path, time_format)
        input_log, output_log = tag_logs(table, time, tag_column, value_column, input, output, average)
    elif output_path is not None:
        input_log = column_log(read_table(path, time_format), time, input, "input", average)
        output_log = column_log(read_table(output_path, time_format), time, output, "output", average)
    else:
        return _from_rows(read_table(path, time_format), time, input, output, dt, max_gap, average)
    return _from_logs(input_log, output_log, dt, max_gap)


def _check_names(time, input, output, long_format, output_path):
    """The column (or tag) names of load_csv: strings, the signals' apart from time and from each other."""
    for argument, name in (("time", time), ("input", input), ("output", output)):
        if not isinstance(name, str) or not name.strip():
            what = "tag" if long_format and argument != "time" else "column"
            raise SettingsError(f"{argument} must be the name of the {argument} {what} (a str); got {name!r}", argument)
    if not long_format:
        for argument, name in (("input", input), ("output", output)):
            if name.strip() == time.strip():
                raise SettingsError(
                    f"{argument} names the time column {time.strip()!r}; "
                    f"expected the column of the {argument}'s values",
                    argument,
                )
    if output_path is None and input.strip() == output.strip():
        what = "tag" if long_format else "column"
        raise SettingsError(
            f"input and output both name the {what} {input.strip()!r}; expected the {what} of each signal", "output"
        )


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
    DataError
        Naming the argument: a log whose times and values differ in length,
        timestamps that do not strictly increase (with the index), a
        non-finite time or value (with the index), or logs that do not
        overlap in time.
    SettingsError
        ``dt <= 0``, or ``start``/``stop`` outside the overlap or not in order.

    Notes
    -----
    The default ``dt`` is the median spacing of the union of both logs'
    timestamps: the typical interval between two consecutive records of the
    loop. It needs no unit and is robust: a few near-coincident timestamps
    of the two tags, or the long gaps of the steady stretches, do not move
    it, and neither does a burst of closely spaced records as long as it
    holds fewer spacings than the rest of the record (1000 records 1 ms
    apart inside an hour of records 1 s apart leave it at 1 s). A grid much
    coarser than that would throw away the detail the logs hold where they
    are dense; a much finer one adds points that carry nothing new. What
    it lands on depends on how the logs were compressed. Exception
    reporting that stores each exception with the reading before it (as
    plant historians do) makes half the spacings one scan, so the median is
    about the scan period: the finest resolution the data have, and
    possibly many more grid points than needed. A log dominated by its
    steady stretches gives the steady logging interval, which can be
    coarser than the dynamics. When the time constants of the process are
    roughly known, pass a ``dt`` below the fastest of them instead (the
    chapter-3 case study passes 1 minute for a 2-minute time constant).

    Linear interpolation between two stored values is what an exception
    logging historian implies: every value in between was within the
    deadband of the stored ones. A step in a value is stored as the last
    value before and the first value after it, and stays a step on a grid
    coarser than that interval. This function interpolates across stretches
    without records of any length; :func:`load_csv` leaves the output
    missing inside those longer than its ``max_gap``.

    Examples
    --------
    Two logs of one ramp, stored at different times, land on the ramp:

    >>> import numpy as np
    >>> from dynia.io.csv import resample_events
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
        raise DataError(
            f"the logs do not overlap in time: times_u spans [{times_u[0]}, {times_u[-1]}] and "
            f"times_y spans [{times_y[0]}, {times_y[-1]}]; a grid needs a stretch where both have data"
        )
    start = first if start is None else _inside(start, "start", first, last)
    stop = last if stop is None else _inside(stop, "stop", first, last)
    if not start < stop:
        raise SettingsError(f"start ({start}) must be before stop ({stop}): the grid would be empty")
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
        raise DataError(
            f"{times_name} has {times.size} timestamps but {values_name} has {values.size} values; "
            "a log needs one timestamp per value"
        )
    steps = np.diff(times)
    if (steps <= 0).any():
        index = int(np.argmax(steps <= 0)) + 1
        raise DataError(
            f"{times_name} must be strictly increasing: {times_name}[{index}] = {times[index]} "
            f"follows {times_name}[{index - 1}] = {times[index - 1]}"
        )
    return times, values


def _inside(value, name, first, last):
    """A finite number inside the span both logs cover, or raise naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise SettingsError(f"{name} must be a finite number; got {value!r}", name)
    if not first <= value <= last:
        raise SettingsError(
            f"{name} = {value} lies outside [{first}, {last}], the span in which both logs have data "
            "(values are interpolated, never extrapolated)",
            name,
        )
    return float(value)


def _median_spacing(times_u, times_y, start, stop):
    """Median spacing of the union of the timestamps inside [start, stop], start and stop included."""
    union = np.union1d(times_u, times_y)
    union = np.union1d(union[(union >= start) & (union <= stop)], [start, stop])
    return float(np.median(np.diff(union)))


def _from_rows(table, time, input, output, dt, max_gap, average=False):
    """A wide table: its rows as they are when uniformly spaced at ``dt``, else resampled.

    With ``average``, rows sharing a time are first merged into their mean.
    """
    rows = table.rows
    at_least_two_rows(table, "the file", rows)
    timeline = parse_times(table, time, rows, table.cells(time, "time"), average)
    u = parse_values(table, input, rows, table.cells(input, "input"))
    y = parse_values(table, output, rows, table.cells(output, "output"))
    notes = list(table.notes)
    if average:
        rows, timeline, (u, y), note = averaged_repeats(table, "the file", rows, timeline, (u, y))
        notes += [note] if note else []
    seconds = timeline.seconds
    u = filled_input(table, f"column {input.strip()!r}", rows, seconds, u, notes)
    missing = output_gaps(table, f"column {output.strip()!r}", rows, y)
    start = timeline.first
    spacing = seconds[-1] / (seconds.size - 1)
    uniform = np.abs(np.diff(seconds) - spacing).max() <= _UNIFORM * spacing
    if uniform and (dt is None or abs(dt - spacing) <= _UNIFORM * spacing):
        step = spacing if dt is None else dt
        if missing.any():
            notes.append(f"{counted(missing.sum(), 'output value')} missing, left as NaN in y")
        return ProcessData(step * np.arange(seconds.size), u, y, float(step), start, tuple(notes))
    grid, u_grid, y_grid, step = _resampled(table.path, seconds, u, seconds, y, dt)
    if uniform:
        notes.append(
            f"resampled {len(rows)} rows spaced {spacing:g} s onto the given {step:g} s grid by linear interpolation"
        )
    else:
        dt_source = "given" if dt is not None else "inferred: the median spacing of the rows"
        notes.append(
            f"resampled {len(rows)} irregular rows onto a {step:g} s grid by linear interpolation (dt {dt_source})"
        )
    _note_output_gaps(notes, missing, y_grid)
    gaps = _blank_gaps(grid, y_grid, step, max_gap, [(seconds, timeline.cells, "")], notes)
    return ProcessData(grid, u_grid, y_grid, step, start, tuple(notes), gaps)


def _from_logs(input_log, output_log, dt, max_gap):
    """Two event logs resampled onto a common grid over the span both cover."""
    origin = common_origin(input_log, output_log)
    times_u = input_log.timeline.seconds + elapsed(input_log.timeline.first, origin)
    times_y = output_log.timeline.seconds + elapsed(output_log.timeline.first, origin)
    if not max(times_u[0], times_y[0]) < min(times_u[-1], times_y[-1]):
        raise DataError(
            f"{output_log.table.path}: the output log ({_described(output_log)}) does not overlap the input log "
            f"({_described(input_log)}) of {input_log.table.path} in time; expected a stretch where both have data"
        )
    notes = list(dict.fromkeys(input_log.table.notes + output_log.table.notes)) + input_log.notes + output_log.notes
    u = filled_input(input_log.table, input_log.label, input_log.rows, times_u, input_log.values, notes)
    missing = output_gaps(output_log.table, output_log.label, output_log.rows, output_log.values)
    grid, u_grid, y_grid, step = _resampled(output_log.table.path, times_u, u, times_y, output_log.values, dt)
    dt_source = "given" if dt is not None else "inferred: the median spacing of both logs' timestamps"
    notes.append(
        f"resampled the input log ({input_log.label} of {input_log.table.path}, "
        f"{counted(len(input_log.rows), 'row')}) and the output log ({output_log.label} of "
        f"{output_log.table.path}, {counted(len(output_log.rows), 'row')}) onto a common {step:g} s grid "
        f"from {grid[0]:g} s to {grid[-1]:g} s by linear interpolation (dt {dt_source})"
    )
    _note_output_gaps(notes, missing, y_grid)
    logs = [
        (times, log.timeline.cells, f" in the {role} log ({log.label})")
        for times, log, role in ((times_u, input_log, "input"), (times_y, output_log, "output"))
    ]
    gaps = _blank_gaps(grid, y_grid, step, max_gap, logs, notes)
    return ProcessData(grid, u_grid, y_grid, step, origin, tuple(notes), gaps)


def _note_output_gaps(notes, missing, y_grid):
    if missing.any():
        notes.append(
            f"{counted(missing.sum(), 'output value')} missing, leaving "
            f"{counted(np.isnan(y_grid).sum(), 'grid point')} NaN in y"
        )


def _resampled(path, times_u, u, times_y, y, dt):
    """Complete ``u`` and gappy ``y`` on one grid by :func:`resample_events`; NaN in y inside its gaps.

    Returns grid, u on it, y on it and the grid spacing (``dt``, or inferred when None).
    """
    first, last = max(times_u[0], times_y[0]), min(times_u[-1], times_y[-1])
    step = _median_spacing(times_u, times_y, first, last) if dt is None else dt
    which = f"dt = {step:g} s" if dt is not None else f"the inferred dt ({step:g} s, the median spacing)"
    steps = (last - first) / step
    if steps >= _MAX_GRID_STEPS:
        inferred = "" if dt is not None else " (inferred: the median spacing of the timestamps)"
        raise DataError(
            f"{path}: the grid would have {_checks.spaced(math.floor(steps) + 1)} steps at dt = {step:g} s"
            f"{inferred} over the {last - first:g} s the data span (limit {_checks.spaced(_MAX_GRID_STEPS)}); "
            "pass a larger --dt / dt="
        )
    missing = np.isnan(y)
    bridged = np.interp(times_y, times_y[~missing], y[~missing])
    grid, u_grid, y_grid = resample_events(times_u, u, times_y, bridged, dt=step)
    if grid.size < 2:
        raise DataError(
            f"{path}: {which} is longer than the {last - first:g} s the data span; "
            "expected a dt that leaves at least 2 grid points"
        )
    y_grid[_in_gaps(grid, times_y, missing, step)] = np.nan
    return grid, u_grid, y_grid, float(step)


def _in_gaps(grid, times, missing, dt):
    """Grid points on the row of a missing value, or between such a row and a row next to it.

    A grid point within rounding (``_GRID_SNAP * dt``) of a row counts as on
    it, so 3 * 0.1 lands on a row logged at 0.3.
    """
    after = np.searchsorted(times, grid, side="right")
    before = after - 1
    after = np.minimum(after, times.size - 1)
    on_before = grid - times[before] <= _GRID_SNAP * dt
    on_after = times[after] - grid <= _GRID_SNAP * dt
    return np.where(on_before, missing[before], np.where(on_after, missing[after], missing[before] | missing[after]))


def _grid_spacing(dt):
    if isinstance(dt, bool) or not isinstance(dt, numbers.Real) or not (math.isfinite(dt) and dt > 0):
        raise SettingsError(f"dt must be a finite number of seconds > 0; got {dt!r}", "dt")
    return float(dt)


def _gap_limit(max_gap):
    """``max_gap`` as a float > 1, or None when stretches of any length are interpolated."""
    if max_gap is None:
        return None
    if isinstance(max_gap, bool) or not isinstance(max_gap, numbers.Real) or not max_gap > 1:
        raise SettingsError(
            f"max_gap must be a number of grid steps > 1, or None to interpolate across "
            f"stretches without rows of any length; got {max_gap!r}",
            "max_gap",
        )
    return None if math.isinf(max_gap) else float(max_gap)


def _blank_gaps(grid, y_grid, step, max_gap, logs, notes):
    """NaN in ``y_grid`` strictly inside every stretch of more than ``max_gap`` steps without rows.

    ``logs`` holds, per log whose rows count, its times (on the grid's
    clock), its time cells as the file wrote them and a phrase naming it
    for the notes ("" for a wide file). Each gap that leaves grid points
    missing gets a note (the first ``_LISTED_GAPS``; the rest are counted).
    Returns the merged grid ranges ``[start, stop)`` left missing, in time order.
    """
    if max_gap is None:
        return ()
    # A grid point within rounding of a row is on it, not inside the gap.
    snap = _GRID_SNAP * step
    found = []
    for times, cells, where in logs:
        for index in np.flatnonzero(np.diff(times) > max_gap * step).tolist():
            start = int(np.searchsorted(grid, times[index] + snap, side="right"))
            stop = int(np.searchsorted(grid, times[index + 1] - snap, side="left"))
            if stop > start:
                length = times[index + 1] - times[index]
                found.append(
                    (
                        start,
                        stop,
                        f"gap of {_duration(length)} s with no rows{where} from {cells[index]} "
                        f"to {cells[index + 1]}: {counted(stop - start, 'grid point')} left "
                        "missing in y",
                    )
                )
    found.sort(key=lambda gap: gap[:2])
    notes += [note for _, _, note in found[:_LISTED_GAPS]]
    rest = found[_LISTED_GAPS:]
    if rest:
        points = sum(stop - start for start, stop, _ in rest)
        notes.append(
            f"and {counted(len(rest), 'more gap')} longer than {max_gap:g} grid steps "
            f"({_duration(max_gap * step)} s): {counted(points, 'more grid point')} left missing in y"
        )
    merged = []
    for start, stop, _ in found:
        y_grid[start:stop] = np.nan
        if merged and start <= merged[-1][1]:
            merged[-1] = (merged[-1][0], max(merged[-1][1], stop))
        else:
            merged.append((start, stop))
    return tuple(merged)


def _described(log):
    return f"{log.label}, {log.timeline.first_cell} to {log.timeline.last_cell}"


def _duration(seconds):
    """Seconds as a short number, without the float noise of subtracted timestamps."""
    return f"{round(seconds, 6):.15g}"
