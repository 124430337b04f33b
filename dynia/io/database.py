"""Process data in a SQL database, and the tables ``dynia follow`` keeps there.

Everything goes through SQLAlchemy Core, so that one code serves SQLite (the
embedded default: ``sqlite:///plant.db``, nothing else to install),
PostgreSQL (``postgresql://user@host:port/db`` after ``pip install
"dynia[postgres]"``, which brings the psycopg driver) and any database
SQLAlchemy has a dialect for. Names of tables and columns are quoted by
SQLAlchemy, never pasted into SQL.

The source (:class:`Source`) is a table as :func:`dynia.io.csv.load_csv`
reads a file: wide (one row per time, a column per signal) or long (time,
tag, value rows, as historians store them). Its time column holds numbers
of seconds, timestamps (a date-time column) or ISO 8601 text; ``Clock``
turns them into seconds from the first one and back.

The follower's tables (``FollowerTables``), named after ``results``:

``results``
    One row per step and parameter: ``time`` (as the source writes it),
    ``parameter``, ``ic``, ``lower``, ``upper``, ``estimate`` (the CLD
    median), ``informative`` (the noise floor's verdict on the window;
    revised as the record grows, see :mod:`dynia.follow`). Primary key
    (time, parameter): a step is never written twice.
``events`` (``dynia_events`` by default, shared by followers)
    One row per change of a parameter's verdict: ``follower`` (its results
    table), ``time``, ``parameter``, ``verdict``, ``previous``, ``reasons``
    (the codes, comma-separated), ``details`` (the reasons' texts, JSON),
    ``logged_at`` (UTC).
``<results>_steps``
    One row per step of what the windows left (``best``, ``discrimination``,
    ``spread``, ``points``) and the step's ``u0`` .. and ``y`` after the
    offsets: the history the record's verdicts are judged on.
``<results>_state``
    One row: the settings, the progress (JSON) and the checkpoint of the
    analysis (bytes, its large constant arrays apart in ``shared``, written
    once), written in the same transaction as the rows they cover.
"""

import dataclasses
import datetime
import json
import math
import numbers
import warnings

import numpy as np

from ..errors import DataError, SettingsError

__all__ = [
    "Source",
    "connect",
]

# The longest name PostgreSQL keeps (it cuts longer ones, so that two names could become one).
_MAX_NAME = 63
_STATE_SUFFIX, _STEPS_SUFFIX = "_state", "_steps"


def _sqlalchemy():
    """SQLAlchemy, imported when a database is used, so that the rest of dynia starts without it."""
    import sqlalchemy

    return sqlalchemy


def connect(url):
    """An SQLAlchemy engine for the database ``url``, checked by connecting once.

    ``postgresql://`` without a driver means psycopg 3 (``dynia[postgres]``).

    Raises
    ------
    SettingsError
        ``url`` is not a database URL, names a driver that is not installed,
        or the database cannot be reached (one line naming the URL without
        its password).
    """
    sqlalchemy = _sqlalchemy()
    try:
        parsed = sqlalchemy.engine.make_url(url)
    except Exception:  # SQLAlchemy's ArgumentError and ValueError both say it cannot parse
        raise SettingsError(
            f"{url!r} is not a database URL; expected e.g. sqlite:///plant.db or postgresql://user@host:5432/plant",
            "url",
        ) from None
    if parsed.drivername == "postgresql":
        parsed = parsed.set(drivername="postgresql+psycopg")
    shown = parsed.render_as_string(hide_password=True)
    sqlite = parsed.get_backend_name() == "sqlite"
    try:
        engine = sqlalchemy.create_engine(parsed, **({"connect_args": {"timeout": 30}} if sqlite else {}))
    except ModuleNotFoundError as error:
        extra = ' (pip install "dynia[postgres]")' if parsed.get_backend_name() == "postgresql" else ""
        raise SettingsError(f"{shown}: its database driver {error.name!r} is not installed{extra}", "url") from None
    except Exception as error:
        raise SettingsError(f"{shown}: {error_line(error)}", "url") from None
    if sqlite:
        sqlalchemy.event.listen(engine, "connect", _write_ahead)
        sqlalchemy.event.listen(engine, "begin", _begin)
    try:
        with engine.connect():
            pass
    except Exception as error:
        raise SettingsError(f"{shown}: cannot connect: {error_line(error)}", "url") from None
    return engine


def _write_ahead(connection, _):
    """SQLite in write-ahead-log mode: the logger's writes and the follower's reads do not block each other.

    A commit then waits for no flush to disk (synchronous NORMAL): a killed
    process loses no committed transaction; a power cut may lose the last
    ones, whole, never half of one. The mode stays with the database file.
    The driver's own transaction handling is turned off, so that a
    transaction begins where SQLAlchemy begins it (:func:`_begin`), reads
    included, not at the first write.
    """
    connection.isolation_level = None
    cursor = connection.cursor()
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.close()


def _begin(connection):
    # IMMEDIATE: the write lock at once. A transaction that read first and wrote after a logger's commit would fail
    # (its snapshot is stale); the logger waits the few milliseconds of a follower's transaction instead.
    connection.exec_driver_sql("BEGIN IMMEDIATE")


def error_line(error):
    return (
        str(getattr(error, "orig", None) or error).strip().splitlines()[0]
        if str(error).strip()
        else type(error).__name__
    )


@dataclasses.dataclass(frozen=True)
class Clock:
    """The source's times as seconds from its first record, and back.

    Attributes
    ----------
    kind : {"number", "datetime", "text"}
        What the time column holds: numbers of seconds, date-times, or
        ISO 8601 text (or text in ``time_format``).
    origin : float or str
        The first record's time: the number, or the ISO form of the date-time.
    time_format : str or None
        A strptime format of text times; None reads ISO 8601.
    """

    kind: str
    origin: object
    time_format: str | None = None

    def _moment(self, value):
        """A date-time (or text) time as a datetime; a DataError naming it when it is not one."""
        if isinstance(value, datetime.datetime):
            return value
        if isinstance(value, datetime.date):
            return datetime.datetime.combine(value, datetime.time())
        text = str(value).strip()
        try:
            if self.time_format is not None:
                return datetime.datetime.strptime(text, self.time_format)
            return datetime.datetime.fromisoformat(text[:-1] + "+00:00" if text.endswith("Z") else text)
        except ValueError:
            expected = f"a time in the format {self.time_format!r}" if self.time_format else "an ISO 8601 timestamp"
            raise DataError(f"time {text!r} is not {expected}") from None

    def seconds(self, values):
        """Seconds from the origin of every time in ``values`` (ndarray)."""
        if self.kind == "number":
            return np.asarray([float(value) for value in values], dtype=float) - float(self.origin)
        origin = self._moment(self.origin)
        try:
            return np.asarray([(self._moment(value) - origin).total_seconds() for value in values], dtype=float)
        except TypeError:
            raise DataError(
                "the time column mixes timestamps with and without a UTC offset; expected one kind throughout"
            ) from None

    def value(self, seconds):
        """The time ``seconds`` after the origin, written as the source writes its times."""
        if self.kind == "number":
            return float(self.origin) + seconds
        moment = self._moment(self.origin) + datetime.timedelta(microseconds=round(seconds * 1e6))
        if self.kind == "datetime":
            return moment
        return moment.strftime(self.time_format) if self.time_format else moment.isoformat()

    def shown(self, value):
        """A time of the source as the log lines write it."""
        if isinstance(value, (datetime.date, datetime.datetime)):
            return value.isoformat()
        return f"{value:g}" if isinstance(value, float) else str(value)

    def to_json(self, value):
        """A time of the source as JSON: numbers as they are, date-times as ISO text."""
        return value.isoformat() if isinstance(value, (datetime.date, datetime.datetime)) else value

    def from_json(self, value):
        if value is None or self.kind != "datetime":
            return value
        return self._moment(value)

    @classmethod
    def of(cls, kind, first, time_format=None):
        """The clock of a source whose first time is ``first``."""
        if kind == "number":
            if isinstance(first, bool) or not isinstance(first, numbers.Real) or not math.isfinite(first):
                raise DataError(f"the first time {first!r} is not a finite number of seconds")
            return cls(kind, float(first), time_format)
        clock = cls(kind, None, time_format)
        moment = clock._moment(first)
        return cls(kind, moment.isoformat(), time_format)


def _time_kind(column):
    """``Clock.kind`` of a reflected time column, or a DataError naming it."""
    sqlalchemy = _sqlalchemy()
    kind = column.type
    if isinstance(kind, (sqlalchemy.DateTime, sqlalchemy.Date)):
        return "datetime"
    if isinstance(kind, (sqlalchemy.Integer, sqlalchemy.Numeric, sqlalchemy.Float)):
        return "number"
    if isinstance(kind, (sqlalchemy.String, sqlalchemy.Text)):
        return "text"
    raise DataError(
        f"the time column {column.name!r} is of type {kind}; expected numbers of seconds, date-times or ISO 8601 text"
    )


@dataclasses.dataclass(frozen=True, eq=False)
class SourceRows:
    """Rows read from a source, in time order.

    Attributes
    ----------
    times : list
        Every row's time as the source holds it (the rows of a long table:
        each distinct time once).
    inputs : list of (list, ndarray)
        Per input, its records' times (as in ``times``) and values, NaN for
        a missing value.
    output : (list, ndarray)
        The output's records.
    count : int
        Rows of the source these came from.
    """

    times: list
    inputs: list
    output: tuple
    count: int


class Source:
    """A table of logged process data, wide or long, read in time order.

    Parameters
    ----------
    engine : sqlalchemy.engine.Engine
    table : str
    time : str
        The time column.
    inputs : sequence of str
        Input columns (long layout: the input tags).
    output : str
        Output column (long layout: the output tag).
    long_format : bool
        Read the table as (time, tag, value) rows.
    tag_column, value_column : str
        The long layout's columns.
    duplicates : {"error", "mean"}
        Rows of one signal that share a time, within what one read returns:
        a DataError naming the time, or the mean of their values.
    time_format : str, optional
        A strptime format of text times.
    """

    def __init__(
        self,
        engine,
        table,
        *,
        time,
        inputs,
        output,
        long_format=False,
        tag_column="tag",
        value_column="value",
        duplicates="error",
        time_format=None,
    ):
        sqlalchemy = _sqlalchemy()
        self.name = table
        try:
            self.table = sqlalchemy.Table(table, sqlalchemy.MetaData(), autoload_with=engine)
        except sqlalchemy.exc.NoSuchTableError:
            known = sorted(sqlalchemy.inspect(engine).get_table_names())
            raise DataError(f"the database has no table {table!r}; its tables: {', '.join(known) or 'none'}") from None
        self.long_format, self.inputs, self.output = long_format, list(inputs), output
        self.duplicates = duplicates
        needed = [("--time", time)]
        needed += [("--tag-column", tag_column), ("--value-column", value_column)] if long_format else []
        needed += [] if long_format else [("--input", name) for name in inputs] + [("--output", output)]
        for option, name in needed:
            if name not in self.table.c:
                raise DataError(
                    f"table {table!r} has no column {name!r} ({option}); its columns: {', '.join(self.table.c.keys())}"
                )
        self.time = self.table.c[time]
        self.kind = _time_kind(self.time)
        self.time_format = time_format
        if long_format:
            self.tag, self.value = self.table.c[tag_column], self.table.c[value_column]

    @property
    def time_type(self):
        """The SQL type the follower's tables give ``time``: the source's own kind."""
        sqlalchemy = _sqlalchemy()
        if self.kind == "datetime":
            return sqlalchemy.DateTime(timezone=bool(getattr(self.time.type, "timezone", False)))
        return sqlalchemy.Double() if self.kind == "number" else sqlalchemy.String(64)

    def _selected(self):
        """The rows of this source's signals (in a long table, of its tags)."""
        return self.tag.in_([*self.inputs, self.output]) if self.long_format else self.time.is_not(None)

    def count_through(self, connection, last):
        """Rows of the source at or before the time ``last`` (the source's own value)."""
        sqlalchemy = _sqlalchemy()
        query = sqlalchemy.select(sqlalchemy.func.count()).select_from(self.table).where(self._selected())
        return int(connection.execute(query.where(self.time <= last)).scalar_one())

    def last_time(self, connection):
        """The source's newest time (None when it has no rows)."""
        sqlalchemy = _sqlalchemy()
        # Read backwards along the time column's index: max() under a WHERE clause scans the whole table in SQLite.
        query = sqlalchemy.select(self.time).where(self._selected()).order_by(self.time.desc()).limit(1)
        return connection.execute(query).scalar()

    def rows_after(self, connection, last, limit, through=None):
        """Up to about ``limit`` rows after the time ``last`` (None: from the first), whole times only.

        With ``through``, only rows at or before that time: what a poll
        reads is what the table held when it began, however fast rows arrive.

        A read that stops at ``limit`` leaves out the rows of its last time,
        unless they are all it holds, so that rows sharing a time are read
        together.
        """
        sqlalchemy = _sqlalchemy()
        columns = [self.time, self.tag, self.value] if self.long_format else [self.time, *self._signal_columns()]
        query = sqlalchemy.select(*columns).where(self._selected()).order_by(self.time).limit(limit + 1)
        if last is not None:
            query = query.where(self.time > last)
        if through is not None:
            query = query.where(self.time <= through)
        rows = connection.execute(query).all()
        if any(row[0] is None for row in rows):
            raise DataError(f"table {self.name!r} has rows without a time in {self.time.name!r}")
        if len(rows) > limit:
            whole = [row for row in rows if row[0] != rows[-1][0]]
            rows = whole if whole else rows[:-1] if len({row[0] for row in rows}) > 1 else rows
        return self._long_rows(rows) if self.long_format else self._wide_rows(rows)

    def _signal_columns(self):
        return [self.table.c[name] for name in [*self.inputs, self.output]]

    def _wide_rows(self, rows):
        values = np.array(
            [[_number(cell, row[0], name) for cell, name in zip(row[1:], [*self.inputs, self.output])] for row in rows],
            dtype=float,
        ).reshape(len(rows), len(self.inputs) + 1)
        times, values = self._merged([row[0] for row in rows], values)
        inputs = [(times, values[:, j]) for j in range(len(self.inputs))]
        return SourceRows(times=times, inputs=inputs, output=(times, values[:, -1]), count=len(rows))

    def _long_rows(self, rows):
        signals = [*self.inputs, self.output]
        logs = {name: ([], []) for name in signals}
        for time, tag, value in rows:
            logs[tag][0].append(time)
            logs[tag][1].append(_number(value, time, tag))
        merged = [self._merged(times, np.array(values, dtype=float).reshape(-1, 1)) for times, values in logs.values()]
        times = sorted({time for time, _, _ in rows})
        records = [(times_, values[:, 0]) for times_, values in merged]
        return SourceRows(times=times, inputs=records[:-1], output=records[-1], count=len(rows))

    def _merged(self, times, values):
        """Rows that share a time as one: refused, or their mean (missing values ignored)."""
        if len(times) < 2 or all(a != b for a, b in zip(times, times[1:])):
            return times, values
        if self.duplicates == "error":
            repeated = next(a for a, b in zip(times, times[1:]) if a == b)
            raise DataError(
                f"table {self.name!r} has several rows at time {repeated}; expected one per time "
                "(--duplicates mean averages them)"
            )
        unique, first = [], []
        for position, time in enumerate(times):
            if not unique or time != unique[-1]:
                unique.append(time)
                first.append(position)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # the mean of none: NaN, a missing value
            averaged = np.array([np.nanmean(part, axis=0) for part in np.split(values, first[1:])])
        return unique, averaged


def _number(cell, time, name):
    """A value cell as a float (NULL: NaN), or a DataError naming its time and signal."""
    if cell is None:
        return math.nan
    if isinstance(cell, bool) or not isinstance(cell, numbers.Real):
        try:
            return float(str(cell))
        except ValueError:
            raise DataError(f"the value of {name!r} at time {time} is {cell!r}, not a number") from None
    return float(cell)


class FollowerTables:
    """The tables of one follower (see the module documentation), made when missing.

    Parameters
    ----------
    engine : sqlalchemy.engine.Engine
    results, events : str
        Table names.
    time_type : sqlalchemy type
        The type of every ``time`` column (:attr:`Source.time_type`).
    n_inputs : int
    """

    def __init__(self, engine, results, events, time_type, n_inputs):
        sqlalchemy = _sqlalchemy()
        for option, name in (("--results", results), ("--events", events)):
            if not isinstance(name, str) or not name.strip() or len(name) + len(_STATE_SUFFIX) > _MAX_NAME:
                raise SettingsError(
                    f"{option} must be a table name of 1 to {_MAX_NAME - len(_STATE_SUFFIX)} characters; got {name!r}",
                    option[2:],
                )
        self.engine, self.name = engine, results
        column, types = sqlalchemy.Column, sqlalchemy
        metadata = sqlalchemy.MetaData()
        self.results = sqlalchemy.Table(
            results,
            metadata,
            column("time", time_type, primary_key=True),
            column("parameter", types.String(64), primary_key=True),
            column("ic", types.Double()),
            column("lower", types.Double()),
            column("upper", types.Double()),
            column("estimate", types.Double()),
            column("informative", types.Boolean()),
        )
        self.events = sqlalchemy.Table(
            events,
            metadata,
            column("id", types.Integer(), primary_key=True, autoincrement=True),
            column("follower", types.String(_MAX_NAME), nullable=False),
            column("time", time_type),
            column("parameter", types.String(64), nullable=False),
            column("verdict", types.String(16), nullable=False),
            column("previous", types.String(16)),
            column("reasons", types.Text()),
            column("details", types.Text()),
            column("logged_at", types.DateTime(timezone=True)),
        )
        self.steps = sqlalchemy.Table(
            results + _STEPS_SUFFIX,
            metadata,
            column("step", types.BigInteger(), primary_key=True, autoincrement=False),
            column("time", time_type, nullable=False),
            *(column(f"u{j}", types.Double()) for j in range(n_inputs)),
            column("y", types.Double()),
            column("best", types.Double()),
            column("discrimination", types.Double()),
            column("spread", types.Double()),
            column("points", types.Integer()),
        )
        self.state = sqlalchemy.Table(
            results + _STATE_SUFFIX,
            metadata,
            column("follower", types.String(_MAX_NAME), primary_key=True),
            column("settings", types.Text(), nullable=False),
            column("progress", types.Text(), nullable=False),
            column("analysis", types.LargeBinary()),
            column("totals", types.LargeBinary()),
            column("shared", types.LargeBinary()),
        )
        self._metadata = metadata
        self.n_inputs = n_inputs
        self._inserts, self._updates = {}, {}

    def insert(self, connection, table, rows):
        """Insert ``rows`` (dicts by column name) into ``table``, many at a time.

        The statement is SQLAlchemy's, compiled for the database's dialect, and
        each value goes through its column type's own conversion, as
        ``connection.execute(table.insert(), rows)`` would; only SQLAlchemy's
        per-row bookkeeping is skipped, which costs more than the database
        itself on a backlog of 10^5 steps.
        """
        if not rows:
            return
        dialect = connection.dialect
        compiled, names, convert = self._insert_statement(table, tuple(rows[0]), dialect)
        converted = [
            [
                value if convert[name] is None or value is None else convert[name](value)
                for name, value in ((name, row[name]) for name in names)
            ]
            for row in rows
        ]
        params = (
            [tuple(row) for row in converted] if compiled.positional else [dict(zip(names, row)) for row in converted]
        )
        connection.exec_driver_sql(str(compiled), params)

    def _insert_statement(self, table, keys, dialect):
        """The compiled insert of ``keys`` into ``table``, its parameters' order and their conversions (cached)."""
        cached = self._inserts.get((table.name, keys, dialect.name))
        if cached is None:
            compiled = table.insert().compile(dialect=dialect, column_keys=list(keys))
            names = list(compiled.positiontup) if compiled.positional else list(compiled.params)
            convert = {name: table.c[name].type.bind_processor(dialect) for name in names}
            cached = self._inserts[(table.name, keys, dialect.name)] = (compiled, names, convert)
        return cached

    def create(self):
        """Make the tables that do not exist yet (one transaction)."""
        self._metadata.create_all(self.engine)

    def check_owned(self, connection, source):
        """Refuse tables this follower would write into that are not a follower's: the source, or a user's own.

        A follower's results and steps tables come with its state table; a
        results or steps table without one is somebody else's, which the
        follower must neither fill nor drop (``--restart``).
        """
        for option, table in (("--results", self.results), ("--events", self.events)):
            if table.name == source.name:
                raise SettingsError(f"{option} names the source table {source.name!r}; give the follower its own")
        inspector = _sqlalchemy().inspect(connection)
        if inspector.has_table(self.state.name):
            return
        for table in (self.results, self.steps):
            if inspector.has_table(table.name):
                raise SettingsError(
                    f"table {table.name!r} exists but is not a dynia follow table (there is no {self.state.name!r}); "
                    "give --results another name",
                    "results",
                )

    def drop(self, connection):
        """Remove this follower: its results, steps and state tables and its rows of the events table."""
        for table in (self.results, self.steps, self.state):
            table.drop(connection, checkfirst=True)
        if _sqlalchemy().inspect(connection).has_table(self.events.name):
            connection.execute(self.events.delete().where(self.events.c.follower == self.name))

    def load_state(self, connection):
        """(settings, progress, analysis, totals, shared) of the checkpoint, or None before the first.

        ``analysis``, ``totals`` and ``shared`` are bytes (None until the analysis has started).
        """
        row = connection.execute(self.state.select().where(self.state.c.follower == self.name)).first()
        if row is None:
            return None
        return json.loads(row.settings), json.loads(row.progress), row.analysis, row.totals, row.shared

    def save_state(self, connection, settings, progress, analysis, totals, shared=None):
        """Write the checkpoint (in the caller's transaction, with the rows it covers); ``shared`` when given."""
        values = dict(settings=json.dumps(settings), progress=json.dumps(progress), analysis=analysis, totals=totals)
        if shared is not None:
            values["shared"] = shared
        done = connection.execute(self._update(tuple(values)), dict(values, key=self.name))
        if done.rowcount == 0:
            connection.execute(self.state.insert().values(follower=self.name, **values))

    def _update(self, columns):
        """The statement that writes ``columns`` of this follower's state row, built once."""
        statement = self._updates.get(columns)
        if statement is None:
            sqlalchemy = _sqlalchemy()
            statement = self.state.update().where(self.state.c.follower == sqlalchemy.bindparam("key"))
            statement = self._updates[columns] = statement.values(
                {name: sqlalchemy.bindparam(name) for name in columns}
            )
        return statement

    def history(self, connection):
        """Every step written so far, in order: the steps table's columns and the results per parameter."""
        steps = connection.execute(self.steps.select().order_by(self.steps.c.step)).all()
        results = connection.execute(self.results.select().order_by(self.results.c.time)).all()
        return steps, results
