"""The columns of a CSV table as signals: times in seconds, values as numbers, rows as event logs.

A time column holds one kind of time (seconds, or timestamps with or without UTC offset) and strictly
increasing times, unless rows sharing a time are averaged; a value column holds numbers, or a missing
value. Every cell that breaks this stops :func:`dynia.io.csv.load_csv` with a DataError naming its file,
row and column.
"""

import dataclasses
import datetime
import math
import re

import numpy as np

from ..errors import DataError
from ._csv_table import Table, counted, listed, shown

# What spreadsheets, pandas, R and databases write into a cell without a value.
_MISSING = frozenset({"", "nan", "na", "null"})

# The three kinds of time a time column may hold; one column holds one kind.
_SECONDS = "a number of seconds"
_NAIVE = "a timestamp without UTC offset"
_AWARE = "a timestamp with UTC offset"


@dataclasses.dataclass(frozen=True)
class Timeline:
    """The time column of one log: its first time, its kind, every cell as written and in seconds from the first."""

    column: str
    first: object
    kind: str
    first_row: int
    cells: tuple
    seconds: np.ndarray

    @property
    def first_cell(self):
        return self.cells[0]

    @property
    def last_cell(self):
        return self.cells[-1]


@dataclasses.dataclass(frozen=True)
class Log:
    """One signal as an event log: the table it came from, its times and its values (NaN where missing)."""

    table: Table
    label: str
    rows: list
    timeline: Timeline
    values: np.ndarray
    notes: list


def column_log(table, time, column, argument, average=False):
    """The log of one column of a two-file layout: every data row of ``table``."""
    label = f"column {column.strip()!r}"
    return _event_log(table, label, time, column, argument, range(len(table.rows)), average)


def tag_logs(table, time, tag_column, value_column, input, output, average=False):
    """The input and output logs of a long table: the rows of each tag."""
    tags = [cell.strip() for cell in table.cells(tag_column, "tag_column")]
    logs = []
    for argument, tag in (("input", input), ("output", output)):
        wanted = tag.strip()
        picks = [index for index, cell in enumerate(tags) if cell == wanted]
        if not picks:
            present = [cell for cell in dict.fromkeys(tags) if cell]
            raise DataError(
                f"{table.path}: column {tag_column.strip()!r} holds no tag {wanted!r} "
                f"(given as {argument}) in rows {table.rows[0]} to {table.rows[-1]}; "
                f"tags present: {listed(present)}"
            )
        logs.append(_event_log(table, f"tag {wanted!r}", time, value_column, "value_column", picks, average))
    return logs


def _event_log(table, label, time, column, argument, picks, average=False):
    """The log of the records ``picks`` of ``table``: their times and the values of ``column``.

    With ``average``, records sharing a time are merged into their mean.
    """
    rows = [table.rows[index] for index in picks]
    at_least_two_rows(table, label, rows)
    time_cells, value_cells = table.cells(time, "time"), table.cells(column, argument)
    timeline = parse_times(table, time, rows, [time_cells[index] for index in picks], average)
    values = parse_values(table, column, rows, [value_cells[index] for index in picks])
    notes = []
    if average:
        rows, timeline, (values,), note = averaged_repeats(table, label, rows, timeline, (values,))
        notes += [f"{note} ({label} of {table.path})"] if note else []
    return Log(table, label, rows, timeline, values, notes)


def averaged_repeats(table, label, rows, timeline, columns):
    """Rows sharing a time as one row: its first row number and cell, each column's mean with NaN ignored.

    The mean is NaN where all the rows' values are. Returns the rows, the
    timeline and the columns left, and a note (None when no time repeats).
    """
    first = np.r_[True, np.diff(timeline.seconds) > 0]
    if first.all():
        return rows, timeline, columns, None
    kept = np.flatnonzero(first)
    if kept.size < 2:
        raise DataError(
            f"{table.path}: {label} has {len(rows)} rows (rows {rows[0]} to {rows[-1]}) but all at one time "
            f"{shown(timeline.first_cell)}; expected at least 2 times"
        )
    group = np.cumsum(first) - 1
    averaged = []
    for values in columns:
        present = ~np.isnan(values)
        totals = np.bincount(group, weights=np.where(present, values, 0.0))
        counts = np.bincount(group, weights=present)
        with np.errstate(invalid="ignore"):  # 0 / 0 where every value of the time is missing: NaN
            averaged.append(totals / counts)
    sizes = np.bincount(group)
    note = (
        f"{int(sizes[sizes > 1].sum())} rows with repeated timestamps averaged into "
        f"{counted(int((sizes > 1).sum()), 'row')}"
    )
    merged = dataclasses.replace(
        timeline, cells=tuple(timeline.cells[index] for index in kept), seconds=timeline.seconds[kept]
    )
    return [rows[index] for index in kept], merged, tuple(averaged), note


def at_least_two_rows(table, label, rows):
    if len(rows) < 2:
        raise DataError(
            f"{table.path}: {label} has only one data row (row {rows[0]}); expected at least 2 to span a time"
        )


def parse_times(table, column, rows, cells, repeats=False):
    """Parse a time column: one kind of time throughout, strictly increasing; seconds from its first row.

    With ``repeats`` consecutive rows may share a time (non-decreasing).
    """
    column = column.strip()
    stamps = [
        _time_stamp(table.path, column, row, cell, table.time_format) for row, cell in zip(rows, cells, strict=True)
    ]
    kind = _kind(stamps[0])
    for row, cell, stamp in zip(rows, cells, stamps, strict=True):
        if _kind(stamp) != kind:
            raise DataError(
                f"{table.path}: row {row}, column {column!r}: {shown(cell)} is {_kind(stamp)}, "
                f"but row {rows[0]} holds {kind} ({shown(cells[0])}); expected one kind of time "
                "throughout"
            )
    first = stamps[0]
    if kind == _SECONDS:
        with np.errstate(over="ignore"):  # an overflow is reported below, with its row
            seconds = np.array(stamps) - first
    else:
        seconds = np.array([(stamp - first).total_seconds() for stamp in stamps])
    if not np.isfinite(seconds).all():
        far = int(np.argmin(np.isfinite(seconds)))
        raise DataError(
            f"{table.path}: row {rows[far]}, column {column!r}: {shown(cells[far])} is so far from "
            f"{shown(cells[0])} on row {rows[0]} that the seconds between them overflow; "
            "expected times of one record"
        )
    steps = np.diff(seconds)
    backwards = steps < 0 if repeats else steps <= 0
    if backwards.any():
        later = int(np.argmax(backwards)) + 1
        where = f"{table.path}: row {rows[later]}, column {column!r}"
        if steps[later - 1] == 0:
            raise DataError(
                f"{where}: duplicate timestamp {shown(cells[later])}, already on row {rows[later - 1]}; "
                "expected strictly increasing times, or pass --duplicates mean (duplicates='mean') to average "
                "the rows that share a time"
            )
        raise DataError(
            f"{where}: {shown(cells[later])} is earlier than {shown(cells[later - 1])} on row "
            f"{rows[later - 1]}; expected strictly increasing times"
        )
    return Timeline(column, first, kind, rows[0], tuple(cell.strip() for cell in cells), seconds)


def _time_stamp(path, column, row, cell, time_format=None):
    """A time cell as float seconds or a datetime, or a DataError naming the row.

    With ``time_format`` the cell is read by :meth:`datetime.datetime.strptime` only.
    """
    text = cell.strip()
    where = f"{path}: row {row}, column {column!r}"
    if text.lower() in _MISSING:
        expected = (
            f"a time in the format {time_format!r}" if time_format else "a number of seconds or an ISO 8601 timestamp"
        )
        raise DataError(f"{where}: the time is missing ({shown(cell)}); expected {expected}")
    if time_format is not None:
        try:
            return datetime.datetime.strptime(text, time_format)
        except ValueError:
            raise DataError(
                f"{where}: {shown(cell)} does not match the time format {time_format!r} (--time-format)"
            ) from None
    try:
        seconds = float(text)
    except ValueError:
        # fromisoformat reads a trailing Z only from Python 3.11 on.
        iso = text[:-1] + "+00:00" if text.endswith(("Z", "z")) else text
        try:
            return datetime.datetime.fromisoformat(iso)
        except ValueError:
            hint = (
                " (decimals need a point, not a comma)"
                if _DECIMAL_COMMA.fullmatch(text)
                else "; give the format of other timestamps with --time-format (time_format=), "
                "e.g. '%d.%m.%Y %H:%M' for 01.01.2012 00:15"
            )
            raise DataError(
                f"{where}: {shown(cell)} is neither a number of seconds nor an ISO 8601 timestamp "
                f"such as 2024-05-01T12:00:00{hint}"
            ) from None
    if not math.isfinite(seconds):
        raise DataError(f"{where}: {shown(cell)} is not a finite time; expected a number of seconds")
    return seconds


# A number written with a decimal comma: 0,5 or -1,25e3.
_DECIMAL_COMMA = re.compile(r"[+-]?\d*,\d+([eE][+-]?\d+)?")


def _kind(stamp):
    if isinstance(stamp, float):
        return _SECONDS
    return _NAIVE if stamp.utcoffset() is None else _AWARE


def common_origin(input_log, output_log):
    """Time zero of two logs: the earlier first time, once both hold the same kind of time."""
    first_u, first_y = input_log.timeline, output_log.timeline
    if first_u.kind != first_y.kind:
        raise DataError(
            f"{output_log.table.path}: row {first_y.first_row}, column {first_y.column!r}: "
            f"{shown(first_y.first_cell)} is {first_y.kind}, but row {first_u.first_row} of "
            f"{input_log.table.path} ({input_log.label}) holds {first_u.kind} ({shown(first_u.first_cell)}); "
            "expected one kind of time for both signals"
        )
    return min(first_u.first, first_y.first)


def elapsed(stamp, origin):
    """Seconds from ``origin`` to ``stamp``, both numbers of seconds or both datetimes."""
    difference = stamp - origin
    return difference if isinstance(difference, float) else difference.total_seconds()


def parse_values(table, column, rows, cells):
    """Parse a value column: float per cell, NaN for a missing one."""
    values = np.empty(len(cells))
    for index, (row, cell) in enumerate(zip(rows, cells, strict=True)):
        text = cell.strip()
        if text.lower() in _MISSING:
            values[index] = np.nan
            continue
        where = f"{table.path}: row {row}, column {column.strip()!r}"
        expected = "expected a number, or an empty cell, NaN, NA or null where the value is missing"
        try:
            value = float(text)
        except ValueError:
            if _DECIMAL_COMMA.fullmatch(text):
                raise DataError(
                    f"{where}: {shown(cell)} is not a number (decimals need a point, not a comma: "
                    f"{text.replace(',', '.')}); export the CSV with '.' as the decimal separator"
                ) from None
            raise DataError(f"{where}: {shown(cell)} is not a number; {expected}") from None
        if not math.isfinite(value):
            raise DataError(f"{where}: {shown(cell)} is not a finite number; {expected}")
        values[index] = value
    return values


def filled_input(table, label, rows, times, values, notes):
    """The input with its missing values interpolated in time, ends held; a note says how many."""
    missing = np.isnan(values)
    if missing.all():
        raise DataError(
            f"{table.path}: {label} has no value in rows {rows[0]} to {rows[-1]}; "
            "expected at least one number for the input"
        )
    if not missing.any():
        return values
    notes.append(
        f"filled {counted(missing.sum(), 'missing input value')} by linear interpolation "
        "between the nearest present values"
    )
    return np.interp(times, times[~missing], values[~missing])


def output_gaps(table, label, rows, values):
    """Where the output is missing; a DataError when it is missing everywhere."""
    missing = np.isnan(values)
    if missing.all():
        raise DataError(
            f"{table.path}: {label} has no value in rows {rows[0]} to {rows[-1]}; "
            "expected at least one number for the output"
        )
    return missing
