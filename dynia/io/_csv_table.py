"""A CSV file read into its header and data records, and how messages quote what it holds.

:func:`read_table` reads a file or an open stream the way :func:`dynia.io.csv.load_csv` documents (the
encoding, the delimiter, the header, blank and short rows) and stops with a one-line DataError naming the
file and row of anything it cannot read; :class:`Table` hands out the cells of a named column. The
helpers at the end put cells, names and counts into those messages and into load_csv's notes.
"""

import csv
import dataclasses
import io
import os
import re

from ..errors import DataError

# Longer cells are cut in messages, so that a garbled file still gives one readable line.
_SHOWN_CHARS = 40

# How many column or tag names a message lists before it only counts the rest.
_LISTED_NAMES = 20


@dataclasses.dataclass(frozen=True)
class Table:
    """A CSV file as read: its header and its data records, each with the row a spreadsheet shows."""

    path: str
    header_row: int
    header: tuple
    rows: list
    records: list
    notes: tuple
    time_format: str | None = None

    def cells(self, name, argument):
        """The cells of column ``name`` (the ``argument`` of load_csv that named it), '' past a short record's end."""
        index = self._index(name, argument)
        return [record[index] if index < len(record) else "" for record in self.records]

    def _index(self, name, argument):
        wanted = name.strip()
        found = [index for index, column in enumerate(self.header) if column == wanted]
        if len(found) == 1:
            return found[0]
        where = f"{self.path}: row {self.header_row} (the header)"
        if found:
            raise DataError(f"{where} names {len(found)} columns {wanted!r}; expected one, to read {argument} from")
        hint = (
            " (they are numbers: the file seems to lack a header row naming the columns)"
            if all(is_number(column) for column in self.header)
            else ""
        )
        raise DataError(
            f"{where} has no column {wanted!r} (given as {argument}); available columns: {listed(self.header)}{hint}"
        )


def read_table(path, time_format=None):
    """Header and data records of a CSV file or stream, or a DataError saying why there are none.

    ``time_format`` is kept with the table for reading its time column.
    """
    if hasattr(path, "read"):
        name, raw = _read_stream(path)
    else:
        name = os.fspath(path)
        try:
            with open(path, "rb") as file:
                raw = file.read()
        except FileNotFoundError:
            raise DataError(f"{name}: no such file; expected a CSV file with a header row") from None
        except OSError as error:
            raise DataError(f"{name}: cannot be read ({error.strerror or error}); expected a CSV file") from None
    text, notes = _decoded(name, raw)
    header_line = next((line for line in io.StringIO(text) if line.strip()), "")
    delimiter = _delimiter(header_line)
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    header_row = header = None
    rows, records = [], []
    row = 0  # a csv.Error is raised before its record is counted
    try:
        for row, record in enumerate(reader, start=1):
            if not any(cell.strip() for cell in record):
                continue
            if header is None:
                header_row, header = row, tuple(cell.strip() for cell in record)
                continue
            if any(cell.strip() for cell in record[len(header) :]):
                raise DataError(
                    f"{name}: row {row} has {len(record)} cells but the header (row {header_row}) names "
                    f"{len(header)} columns; expected one cell per column"
                    + (
                        " (a decimal comma in a comma-separated file splits a number in two: export the CSV with "
                        "'.' as the decimal separator)"
                        if delimiter == "," and _split_decimals(record)
                        else ""
                    )
                )
            rows.append(row)
            records.append(record)
    except csv.Error as error:
        raise DataError(f"{name}: row {row + 1} cannot be read as CSV ({error})") from None
    if header is None:
        raise DataError(f"{name}: the file is empty; expected a header row and at least 2 data rows")
    if not records:
        raise DataError(f"{name}: the file has a header (row {header_row}) but no data rows; expected at least 2")
    return Table(name, header_row, header, rows, records, notes, time_format)


def _decoded(name, raw):
    """The text of a file's bytes, and a note when it was not UTF-8; a DataError for what is no text."""
    notes = ()
    if isinstance(raw, str):  # a text stream is already decoded; only its byte order mark is left to drop
        text = raw.removeprefix("\ufeff")
    elif raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        # Excel's "Unicode text" and Windows' Notepad write UTF-16 with a byte order mark.
        try:
            text = raw.decode("utf-16")
        except UnicodeDecodeError as error:
            raise DataError(
                f"{name}: starts like UTF-16 text but byte {error.start} is not UTF-16; expected a text CSV file"
            ) from None
        notes = (f"read {name} as UTF-16 text (it starts with UTF-16's byte order mark)",)
    else:
        try:
            text = raw.decode("utf-8-sig")
        except UnicodeDecodeError:
            # Excel on Windows saves "CSV" in the ANSI code page; a degree sign in
            # a column name should not stop a load.
            text = raw.decode("cp1252", errors="replace")
            notes = (f"read {name} as Windows-1252 text, since it is not valid UTF-8",)
    text = text.removesuffix("\x1a")  # the end-of-file mark of DOS-era text files
    control = _CONTROL.search(text)
    if control is not None:
        offset = control.start()
        line = text.count("\n", 0, offset) + 1
        kind = (
            "NUL bytes (UTF-16 text without a byte order mark, or binary data)"
            if control.group() == "\x00"
            else f"the control character {control.group()!r}"
        )
        raise DataError(
            f"{name}: line {line} holds {kind}, which no CSV text holds; expected a CSV text file "
            "(UTF-8, UTF-16 with byte order mark, or Windows-1252); export the data as CSV"
        )
    return text, notes


# Characters no CSV text file holds: C0 controls but tab, line feed, vertical tab, form feed and carriage return.
_CONTROL = re.compile(r"[\x00-\x08\x0e-\x1f\x7f]")


def _read_stream(stream):
    """The name messages give an open stream, and all it holds from where it stands: str or bytes."""
    name = getattr(stream, "name", None)
    name = name if isinstance(name, str) else "<stream>"
    try:
        raw = stream.read()
    except (OSError, ValueError) as error:
        # ValueError: a closed stream.
        raise DataError(f"{name}: cannot be read ({error}); expected an open CSV stream") from None
    if not isinstance(raw, (str, bytes, bytearray)):
        raise DataError(f"{name}: read() gave a {type(raw).__name__}; expected a text or binary CSV stream")
    return name, raw


def _split_decimals(record):
    """Whether a record's cells look like numbers whose decimal comma split them: a digit-only cell after a number."""
    cells = [cell.strip() for cell in record]
    return any(is_number(a) and b.isdigit() for a, b in zip(cells, cells[1:]))


def _delimiter(header_line):
    """Comma, unless the header holds (outside quotes) no comma and exactly one of semicolon and tab."""
    bare = re.sub(r'"[^"]*"', "", header_line)
    if "," not in bare and (";" in bare) != ("\t" in bare):
        return ";" if ";" in bare else "\t"
    return ","


def is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def shown(cell):
    """A cell for a message: quoted, and cut when long."""
    return repr(cell if len(cell) <= _SHOWN_CHARS else cell[: _SHOWN_CHARS - 3] + "...")


def listed(names):
    shown = ", ".join(repr(name) for name in names[:_LISTED_NAMES])
    return shown if len(names) <= _LISTED_NAMES else f"{shown}, ... ({len(names)} in all)"


def counted(number, noun):
    return f"{number} {noun}" if number == 1 else f"{number} {noun}s"
