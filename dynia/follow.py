"""DYNIA inside the logging system (thesis section 4.3): a results table kept current on the plant's database.

The thesis proposes to sample the parameters once and to run the
moving-window calculations "semi-online" as the logging system records new
data, so that a database of the time-varying information content is at hand
whenever someone decides to re-identify the model. :class:`Follower` does
that on a SQL database (:mod:`dynia.io.database`): it reads the rows a
source table gained since it last looked, puts them on the grid
(:class:`dynia.io.stream.StreamGrid`), analyses one trailing window per new
step (:class:`dynia.online.OnlineDynia`) and writes one row per step and
parameter to its results table. ``dynia follow`` is its command.

What it guarantees
------------------
*Equal to the batch analysis.* The rows of the results table equal
``dynia.run(u, y, model, bounds, n_samples=S, n=n, rng=seed,
window="trailing")`` on the same grid (after the same offsets): ``ic``,
``lower``, ``upper`` and ``estimate`` (the CLD median) to rounding, however
the rows arrived and however often the follower was stopped. A backlog (the
rows present when a follower starts for the first time) goes through the
compiled batch engine, and the per-step updates take over from there.

*Exactly once.* Every transaction writes the steps it analysed together
with the checkpoint that covers them: the Monte Carlo sample, the models'
states, the window's errors, the noise floor's running totals, the grid, the
settings and the last source time read. A follower killed at any moment
restarts from its last commit: no step is lost and none is written twice
(the results table's key, time and parameter, would refuse it).

*Late rows are not woven in.* A row whose time is not after the last one
read (it arrived late) cannot enter the windows already analysed: each poll
counts the source's rows up to that time, and the ones it did not read are
logged, counted (``late_rows`` of the progress) and skipped.

*The record's judgement.* The noise floor and the verdicts judge the whole
record (:mod:`dynia.engine.noise`, :mod:`dynia.verdicts`): a new step can
change the noise level, and so whether an earlier window is informative.
:meth:`Follower.judge` judges the record so far as the batch analysis judges
it: it rewrites the ``informative`` of every step whose judgement changed,
and a verdict that changed becomes a row of the events table and a log line.
Between judgements a new step's ``informative`` is judged with the noise
level of the last one (NULL before the first).
"""

import copy
import dataclasses
import datetime
import io
import json
import logging
import math
import tempfile
from pathlib import Path

import numpy as np
import sqlalchemy

from .checkpoint import SharedArrays
from .engine.noise import (
    add_record_errors,
    floor_fields,
    floor_settings,
    noise_floor,
    record_fit,
    record_noise_floor,
    window_points,
)
from .errors import DataError, ModelError, SettingsError
from .fit import record_least_squares
from .io.database import Clock, FollowerTables
from .io.stream import StreamGrid
from .online import OnlineDynia
from .pipeline import KernelSimulated, compiled_simulation, run
from .quality import screen
from .result import DyniaResult
from .settings import RunRecord
from .timescale import window_half_width
from .verdicts import assess

__all__ = ["Follower", "FollowerSettings"]

log = logging.getLogger("dynia.follow")

# The level of a verdict change in the log: above the progress lines (INFO), which --quiet leaves out, below warnings.
VERDICT_CHANGE = 25
logging.addLevelName(VERDICT_CHANGE, "VERDICT")

# A first backlog of at least this many windows goes through the batch engine; a shorter one is updated step by step.
BACKLOG_WINDOWS = 10

# A backlog whose CLD gradient would take more memory than this writes it to a temporary file (a year of 1 s data
# at two parameters and 40 bins: 20 GB).
BACKLOG_GRADIENT_BYTES = 1 << 30


@dataclasses.dataclass(frozen=True)
class FollowerSettings:
    """What a follower is, fixed at its first start and checked at every start after.

    Attributes
    ----------
    options : dict
        Every option that decides the results, as the command line names it
        (``{"--samples": 2000, ...}``): a restart with another value of any
        of them is refused, naming it.
    analysis : dynia.settings.AnalysisSettings
        The analysis (``window="trailing"``); its ``dt`` is the grid's when
        given, else set from the first rows.
    seed : int
    window_seconds : float or None
        A window given as a duration, made a half window once ``dt`` is known.
    min_points : int
        As the analysis's, for a window given as a duration (checked once
        the window is known).
    offset, input_offset : "none", "first" or float
    quality : bool
        Screen the record when judging it (:mod:`dynia.quality`).
    max_gap : float
        Grid steps without records interpolated across (``math.inf``: any).
    dt_given : bool
        Whether the grid's ``dt`` was given (else the first rows' spacing).
    """

    options: dict
    analysis: object
    seed: int
    window_seconds: float | None = None
    min_points: int = 1
    offset: object = "none"
    input_offset: object = "none"
    quality: bool = True
    max_gap: float = 5.0
    dt_given: bool = False


class Follower:
    """A source table followed into a results table (see the module documentation).

    Parameters
    ----------
    engine : sqlalchemy.engine.Engine
        From :func:`dynia.io.database.connect`.
    source : dynia.io.database.Source
    model : dynia.models.Model
    bounds : mapping of str to (low, high)
    settings : FollowerSettings
    results, events : str
        The results table and the events table.
    restart : bool, default False
        Drop the follower's tables and rows first and start over.

    Raises
    ------
    SettingsError
        The results table belongs to a follower started with other
        settings: one line naming the first option that differs.
    """

    def __init__(
        self, engine, source, model, bounds, settings, results="dynia_results", events="dynia_events", *, restart=False
    ):
        self.engine, self.source, self.model = engine, source, model
        self.bounds, self.settings = dict(bounds), settings
        self.tables = FollowerTables(engine, results, events, source.time_type, len(source.inputs))
        with engine.connect() as connection:
            self.tables.check_owned(connection, source)
        if restart:
            with engine.begin() as connection:
                self.tables.drop(connection)
        self.tables.create()
        with engine.begin() as connection:
            saved = self.tables.load_state(connection)
            self._history = _History(len(bounds), len(source.inputs))
            if saved is None:
                self.progress = _fresh_progress(settings, len(source.inputs))
                self.online, self.totals, self._shared = None, None, SharedArrays()
            else:
                self._resume(connection, *saved)
        self._grid = StreamGrid.restored(self.progress["grid"])
        self._through = None

    # -- starting --------------------------------------------------------------------------------------------------

    def _resume(self, connection, options, progress, analysis, totals, shared):
        """Go on from the checkpoint; refuse other settings, naming the first that differs."""
        for option, value in self.settings.options.items():
            if option == "--seed" and value is None:
                continue  # not given: the recorded seed goes on
            if options.get(option) != value:
                raise SettingsError(
                    f"the follower {self.tables.name!r} was started with {option} {_shown(options.get(option))}; "
                    f"this command gives {_shown(value)}: give its settings again, or --restart to start over "
                    "(its results are dropped)"
                )
        self.settings = dataclasses.replace(self.settings, seed=options["--seed"])
        self.progress = progress
        self._shared = SharedArrays() if shared is None else SharedArrays.from_bytes(shared)
        self.online = None if analysis is None else OnlineDynia.from_bytes(analysis, self.model, self._shared)
        self.totals = None if totals is None else np.load(io.BytesIO(totals), allow_pickle=False)
        if progress["clock"] is not None:
            self._history.load(*self.tables.history(connection), self.online)

    @property
    def _clock(self):
        clock = self.progress["clock"]
        return None if clock is None else Clock(**clock)

    @property
    def steps(self):
        """Steps analysed and written so far."""
        return self._history.size

    @property
    def late_rows(self):
        """Rows that arrived with a time before the last one read, and were skipped."""
        return self.progress["late"]

    # -- reading and analysing -------------------------------------------------------------------------------------

    def poll(self, batch_rows=10_000, stop=lambda: False):
        """Analyse the rows the source holds as the poll begins, a transaction per batch of rows; the steps written.

        ``stop()`` is asked between transactions; when it is true the
        follower returns with what it committed. After an exception the
        object no longer matches the database (its transaction rolled back):
        make a new one, which goes on from the last commit.
        """
        written = 0
        self._through = None  # the source's newest time as the poll began: read with its first rows
        if self.online is None:
            written += self._catch_up(batch_rows, stop)
        while not stop():
            with self.engine.begin() as connection:
                rows = self._read(connection, batch_rows)
                if rows is not None:
                    written += self._commit(connection, rows)
            if rows is None or rows.count < batch_rows:  # caught up: the next rows are for the next poll
                break
        return written

    def _read(self, connection, batch_rows):
        """The next rows after the last time read (None when there are none); fixes the clock at the first."""
        progress = self.progress
        clock = self._clock
        last = None if clock is None else clock.from_json(progress["last_time"])
        if self._through is None:
            self._through = self.source.last_time(connection)
            if self._through is None:
                return None
        rows = self.source.rows_after(connection, last, batch_rows, self._through)
        if rows.count == 0:
            return None
        if clock is None:
            progress["clock"] = dataclasses.asdict(Clock.of(self.source.kind, rows.times[0], self.source.time_format))
        return rows

    def _catch_up(self, batch_rows, stop):
        """The first start: the rows present now, analysed by the batch engine when they are many."""
        chunks = []
        with self.engine.begin() as connection:
            while True:
                rows = self._read_ahead(connection, chunks, batch_rows)
                if rows is None:
                    break
                chunks.append(rows)
        if not chunks:
            return 0
        grid = copy.deepcopy(self._grid)  # a look ahead: the follower's own grid takes the rows as they commit
        points = [self._gridded(grid, rows, record=False) for rows in chunks]
        u, y = np.concatenate([p.u for p in points]), np.concatenate([p.y for p in points])
        if y.size == 0:
            return self._commit_chunks(chunks, None, stop)
        self._start(grid.dt, u, y)
        u, y = self._offset(u, y)
        backlog = None
        if y.size >= BACKLOG_WINDOWS * self.online.settings.window_length:
            backlog = self._batch(u, y)
        return self._commit_chunks(chunks, backlog, stop)

    def _read_ahead(self, connection, chunks, batch_rows):
        """The rows after those in ``chunks`` (reading a backlog before analysing any of it)."""
        if not chunks:
            return self._read(connection, batch_rows)
        last = chunks[-1].times[-1]
        rows = self.source.rows_after(connection, last, batch_rows, self._through)
        return None if rows.count == 0 else rows

    def _commit_chunks(self, chunks, backlog, stop):
        written = 0
        for rows in chunks:
            with self.engine.begin() as connection:
                written += self._commit(connection, rows, backlog)
            if stop():
                break
        return written

    def _gridded(self, grid, rows, record=True):
        """The grid points ``rows`` complete on ``grid``; with ``record``, also their times as the source writes them.

        A point on a row keeps that row's own time (a number, a date-time or
        the text as stored); a point between rows gets the grid's time. Rows a
        later point may still lie on are remembered in the progress.
        """
        clock = self._clock or Clock.of(self.source.kind, rows.times[0], self.source.time_format)
        first = grid.records
        seconds = clock.seconds(rows.times)
        inputs = [(clock.seconds(times), values) for times, values in rows.inputs]
        points = grid.feed_logs(seconds, inputs, (clock.seconds(rows.output[0]), rows.output[1]))
        if not record:
            return points
        known = self.progress["record_times"]
        known.update({str(first + k): clock.to_json(time) for k, time in enumerate(rows.times)})
        times = [
            clock.from_json(known[str(int(at))]) if at >= 0 else clock.value(float(moment))
            for moment, at in zip(points.time, points.record)
        ]
        kept = grid.first_record
        self.progress["record_times"] = {key: value for key, value in known.items() if int(key) >= kept}
        return points, times

    def _start(self, dt, u, y):
        """Fix the window, the offsets and the sample from the first grid points (the first start only)."""
        settings, progress = self.settings, self.progress
        analysis = settings.analysis.replace(dt=dt)
        if settings.window_seconds is not None:
            # The record grows: no length of it bounds the window.
            n = window_half_width(settings.window_seconds, dt, math.inf, "--window")
            analysis = analysis.replace(n=n, min_points=settings.min_points)
        progress["offset"] = _first_value(settings.offset, y, "--offset", "output")
        progress["input_offset"] = [
            _first_value(settings.input_offset, column, "--input-offset", "input") for column in u.T
        ]
        self.online = OnlineDynia(self.model, self.bounds, settings=analysis, rng=settings.seed)
        self.totals = np.zeros(self.online.samples.shape[0])

    def _offset(self, u, y):
        return u - np.asarray(self.progress["input_offset"]), y - self.progress["offset"]

    def _batch(self, u, y):
        """The backlog's windows from the batch engine: per-step arrays, or None where the updates must do them.

        The batch run equals the updates only where it drops no parameter set
        (OnlineDynia's Notes); and it refuses a record on which every set's
        output is the same (a plant at rest), which the updates go on with.
        """
        analysis = self.online.settings
        n_params, n_bins = self.online.bin_centres.shape
        try:
            with tempfile.TemporaryDirectory(prefix="dynia-follow-") as folder:
                # The CLD gradient, which the follower does not keep, goes to a file when it would not fit in memory.
                large = y.size * n_params * n_bins * 8 > BACKLOG_GRADIENT_BYTES
                store = Path(folder, "backlog.nc") if large else None
                result = run(
                    _inputs(u),
                    y,
                    self.model,
                    self.bounds,
                    settings=analysis.replace(engine="auto", quality=False, store=store),
                    rng=self.settings.seed,
                    progress=False,
                )
                ic, ci, median = (np.asarray(values) for values in (result.ic, result.ci, result.median))
        except ModelError:
            return None
        if result.run.n_dropped or not np.array_equal(result.samples, self.online.samples):
            return None
        before = 2 * analysis.n
        # Judged as the batch run judges the backlog: the judgement after it then changes nothing.
        self.progress["judged"] = dict(sigma=result.run.noise_sigma, size_factor=result.run.noise_size_factor)
        return _Steps(
            informative=result.informative,
            ic=ic,
            ci=ci,
            median=median,
            best=result.best_mae,
            discrimination=result.discrimination,
            spread=result.behavioural_spread,
            points=window_points(y, before, 0).astype(np.int64),
        )

    def _commit(self, connection, rows, backlog=None):
        """Grid ``rows``, analyse the steps they complete, write them with the checkpoint; the steps written."""
        points, times = self._gridded(self._grid, rows)
        self.progress["last_time"] = self._clock.to_json(rows.times[-1])
        self.progress["consumed"] += rows.count
        if points.index.size:
            if self.online is None:
                self._start(self._grid.dt, points.u, points.y)
            u, y = self._offset(points.u, points.y)
            first = self.steps
            if backlog is not None:
                steps = backlog.part(first, first + y.size)
                self.online.advance(_inputs(u), y, self.totals)
            else:
                steps = self._updated(u, y)
            informative = self._informative(steps) if steps.informative is None else steps.informative.tolist()
            self._write(connection, first, times, u, y, steps, informative)
            self._history.append(times, u, y, steps, informative)
        self._save(connection)
        return points.index.size

    def _updated(self, u, y):
        """Update the analysis step by step through ``u``, ``y``: per-step arrays."""
        online, totals = self.online, self.totals
        n_params = len(online.names)
        steps = _Steps.empty(n_params, y.size)
        for k, (u_t, y_t) in enumerate(zip(_inputs(u).tolist(), y.tolist())):
            scale = online.error_scale
            ic, ci, _ = online.update(u_t, y_t)
            if online.error_scale != scale:
                totals *= online.error_scale
            add_record_errors(totals, online.newest_errors[None])
            steps.ic[:, k], steps.ci[:, k], steps.median[:, k] = ic, ci, online.median
            best, upper, threshold, points = online.window_statistics
            steps.best[k], steps.discrimination[k], steps.spread[k] = best, upper - best, threshold - best
            steps.points[k] = points
        return steps

    def _informative(self, steps):
        """The new steps' noise-floor verdict with the last judgement's noise level; None before the first."""
        judged = self.progress["judged"]
        if judged is None:
            return [None] * steps.best.size
        analysis = self.online.settings
        slots = 2 * analysis.n + 1
        total = self.steps + steps.best.size
        floor = noise_floor(
            steps.best,
            steps.best + steps.discrimination,
            steps.best + steps.spread,
            steps.points,
            n_params=len(self.online.names),
            share=analysis.percentage / 100,
            n_samples=self.online.samples.shape[0],
            n_windows=math.ceil(total / slots),
            sigma=judged["sigma"],
            size_factor=judged["size_factor"],
        )
        return floor.informative.tolist()

    def _write(self, connection, first, times, u, y, steps, informative):
        names = self.online.names
        results = [
            dict(
                time=time,
                parameter=name,
                ic=_sql(steps.ic[p, k]),
                lower=_sql(steps.ci[p, k, 0]),
                upper=_sql(steps.ci[p, k, 1]),
                estimate=_sql(steps.median[p, k]),
                informative=informative[k],
            )
            for k, time in enumerate(times)
            for p, name in enumerate(names)
        ]
        self.tables.insert(connection, self.tables.results, results)
        rows = [
            dict(
                step=first + k,
                time=time,
                y=_sql(y[k]),
                best=_sql(steps.best[k]),
                discrimination=_sql(steps.discrimination[k]),
                spread=_sql(steps.spread[k]),
                points=int(steps.points[k]),
                **{f"u{j}": float(u[k, j]) for j in range(u.shape[1])},
            )
            for k, time in enumerate(times)
        ]
        self.tables.insert(connection, self.tables.steps, rows)

    def _save(self, connection):
        self.progress["grid"] = self._grid.state()
        first = self._shared.accepting
        analysis = None if self.online is None else self.online.to_bytes(self._shared)
        shared = self._shared.to_bytes() if first and analysis is not None else None
        if shared is not None:
            self._restorable(analysis, shared)
        totals = None
        if self.totals is not None:
            buffer = io.BytesIO()
            np.save(buffer, self.totals, allow_pickle=False)
            totals = buffer.getvalue()
        options = dict(self.settings.options, **{"--seed": self.settings.seed})
        self.tables.save_state(connection, options, self.progress, analysis, totals, shared)

    def _restorable(self, analysis, shared):
        """Refuse now, not at a restart, a model whose simulation state a checkpoint cannot rebuild."""
        try:
            OnlineDynia.from_bytes(analysis, self.model, SharedArrays.from_bytes(shared))
        except DataError as error:
            raise ModelError(
                f"{self.model!r}: its simulation state cannot be checkpointed ({error}); dynia follow restores only "
                "numpy arrays, plain values and dynia's own classes"
            ) from None

    # -- judging ---------------------------------------------------------------------------------------------------

    def _count_late(self, connection):
        """Count (and log) the rows that arrived with a time at or before the last one read: they are skipped.

        The source's rows up to that time, less the rows read: a scan of the
        time column's index, so it runs with the judgement, not every poll.
        """
        progress, clock = self.progress, self._clock
        if clock is None or progress["last_time"] is None:
            return
        last = clock.from_json(progress["last_time"])
        through = self.source.count_through(connection, last)
        if through > progress["consumed"]:
            late = through - progress["consumed"]
            progress["late"] += late
            progress["consumed"] = through
            log.warning(
                "%d row(s) of %s arrived with a time at or before %s, the last time analysed: skipped (%d late in all)",
                late,
                self.source.name,
                clock.shown(last),
                progress["late"],
            )

    def judge(self):
        """Judge the record so far as the batch analysis would; return the verdicts (see the module documentation).

        Rewrites the ``informative`` of the steps whose judgement changed,
        and writes a row to the events table (and a log line) for every
        parameter whose verdict changed, in one transaction.
        """
        if self.online is None or self.steps == 0:
            with self.engine.begin() as connection:
                self._count_late(connection)
                self._save(connection)
            return {}
        history = self._history
        result = self.result()
        changed = np.flatnonzero(history.informative != result.informative.astype(np.int8))
        verdicts = {
            name: dict(verdict=v["verdict"], reasons=[r["code"] for r in v["reasons"]], details=v["reasons"])
            for name, v in result.verdicts.items()
        }
        with self.engine.begin() as connection:
            self._count_late(connection)
            if changed.size:
                table = self.tables.results
                statement = (
                    table.update()
                    .where(table.c.time == sqlalchemy.bindparam("step_time"))
                    .values(informative=sqlalchemy.bindparam("flag"))
                )
                connection.execute(
                    statement,
                    [dict(step_time=history.times[k], flag=bool(result.informative[k])) for k in changed.tolist()],
                )
                history.set_informative(changed, result.informative[changed])
            self._events(connection, verdicts, history.times[-1])
            self.progress["judged"] = dict(sigma=result.run.noise_sigma, size_factor=result.run.noise_size_factor)
            self.progress["verdicts"] = {
                name: dict(verdict=v["verdict"], reasons=v["reasons"]) for name, v in verdicts.items()
            }
            self._save(connection)
        return result.verdicts

    def result(self):
        """The record so far as a :class:`~dynia.result.DyniaResult` with its noise floor, record fit and verdicts.

        What ``dynia.run(..., window="trailing")`` gives on the same steps
        (but ``gradient``, which the follower does not keep: NaN).
        """
        history, online = self._history, self.online
        analysis = online.settings
        u, y = history.u[:, 0] if history.u.shape[1] == 1 else history.u, history.y
        slots = 2 * analysis.n + 1
        order = [online.names.index(name) for name in self.model.names]
        simulating = KernelSimulated(self.model) if compiled_simulation(self.model) else self.model

        def simulations(rows):
            params = online.samples[rows][:, order]
            return [simulating.simulate(params, u, dt=analysis.dt, x0=analysis.x0)]

        n_samples = online.samples.shape[0]
        fit = record_fit(y, online.samples, online.bounds, self.totals, simulations)
        floor = record_noise_floor(
            history.best,
            history.best + history.discrimination,
            history.best + history.spread,
            history.points.astype(float),
            slots,
            len(online.names),
            analysis.percentage,
            n_samples,
            fit=fit,
        )
        run = dataclasses.replace(
            RunRecord.of(self.model, n_sampled=n_samples, n_dropped=0),
            n_behavioural=online.n_behavioural,
            n_diverged=online.n_diverged,
            **floor_settings(floor),
        )
        if self.settings.quality:
            run = dataclasses.replace(run, screened=screen(u, y, (2 * analysis.n, 0)))
        n_params, n_bins = online.bin_centres.shape
        result = DyniaResult(
            names=online.names,
            samples=np.array(online.samples),
            bounds=online.bounds.copy(),
            time=np.arange(y.size) * analysis.dt,
            ic=history.ic,
            ci=history.ci,
            median=history.median,
            gradient=np.broadcast_to(np.float64(np.nan), (n_params, n_bins, y.size)),
            bin_centres=online.bin_centres,
            settings=analysis,
            run=run,
            **floor_fields(floor),
        )
        result = record_least_squares(result, u, y, simulating)
        clock = self._clock
        verdicts = assess(result, clock=lambda step: clock.shown(history.times[step]))
        return dataclasses.replace(result, verdicts=verdicts)

    def _events(self, connection, verdicts, time):
        before = self.progress["verdicts"]
        rows = []
        for name, now in verdicts.items():
            then = before.get(name)
            if then is not None and then["verdict"] == now["verdict"] and then["reasons"] == now["reasons"]:
                continue
            previous = None if then is None else then["verdict"]
            codes = ", ".join(now["reasons"])
            rows.append(
                dict(
                    follower=self.tables.name,
                    time=time,
                    parameter=name,
                    verdict=now["verdict"],
                    previous=previous,
                    reasons=codes,
                    details=json.dumps(now["details"]),
                    logged_at=datetime.datetime.now(datetime.timezone.utc),
                )
            )
            log.log(
                VERDICT_CHANGE,
                "%s: %s%s%s (at %s)",
                name,
                "" if previous is None else f"{previous} -> ",
                now["verdict"],
                f": {codes}" if codes else "",
                self._clock.shown(time),
            )
        if rows:
            connection.execute(self.tables.events.insert(), rows)


def _inputs(u):
    """(n_steps, n_inputs) inputs as the models take them: 1-D for one input."""
    return u[:, 0] if u.shape[1] == 1 else u


def _fresh_progress(settings, n_inputs):
    grid = StreamGrid(n_inputs, settings.analysis.dt if settings.dt_given else None, settings.max_gap)
    return dict(
        clock=None,
        last_time=None,
        consumed=0,
        late=0,
        grid=grid.state(),
        record_times={},
        offset=None,
        input_offset=None,
        judged=None,
        verdicts={},
    )


def _first_value(offset, values, option, signal):
    """The offset to subtract: 0, the given number, or the first measured value of ``values``."""
    if offset == "none":
        return 0.0
    if offset != "first":
        return float(offset)
    measured = np.asarray(values)[~np.isnan(values)]
    if measured.size == 0:
        raise DataError(f"{option} first takes the first measured {signal}, but the first rows have none; give a value")
    return float(measured[0])


def _shown(value):
    return "(not given)" if value is None else str(value)


def _sql(value):
    """A float for the database; NaN as NULL (SQL has no NaN that every database keeps)."""
    value = float(value)
    return None if math.isnan(value) else value


@dataclasses.dataclass
class _Steps:
    """What the windows of a run of steps gave: the results table's columns and the floor's statistics."""

    ic: np.ndarray
    ci: np.ndarray
    median: np.ndarray
    best: np.ndarray
    discrimination: np.ndarray
    spread: np.ndarray
    points: np.ndarray
    informative: np.ndarray | None = None  # the noise floor's verdict, where the batch engine judged the steps

    @classmethod
    def empty(cls, n_params, n_steps):
        return cls(
            ic=np.full((n_params, n_steps), np.nan),
            ci=np.full((n_params, n_steps, 2), np.nan),
            median=np.full((n_params, n_steps), np.nan),
            best=np.full(n_steps, np.nan),
            discrimination=np.full(n_steps, np.nan),
            spread=np.full(n_steps, np.nan),
            points=np.zeros(n_steps, dtype=np.int64),
        )

    def part(self, start, stop):
        return _Steps(
            ic=self.ic[:, start:stop],
            ci=self.ci[:, start:stop],
            median=self.median[:, start:stop],
            best=self.best[start:stop],
            discrimination=self.discrimination[start:stop],
            spread=self.spread[start:stop],
            points=self.points[start:stop],
            informative=None if self.informative is None else self.informative[start:stop],
        )


class _History:
    """Every step written, in memory: what :meth:`Follower.result` judges. Arrays grow by doubling."""

    _FIELDS = ("ic", "lower", "upper", "median", "best", "discrimination", "spread", "points", "informative")

    def __init__(self, n_params, n_inputs):
        self.times = []
        self._arrays = dict(
            u=np.empty((0, n_inputs)),
            y=np.empty(0),
            ic=np.empty((n_params, 0)),
            lower=np.empty((n_params, 0)),
            upper=np.empty((n_params, 0)),
            median=np.empty((n_params, 0)),
            best=np.empty(0),
            discrimination=np.empty(0),
            spread=np.empty(0),
            points=np.empty(0, dtype=np.int64),
            informative=np.empty(0, dtype=np.int8),  # 1, 0, or -1 where not judged yet
        )

    @property
    def size(self):
        return len(self.times)

    def __getattr__(self, name):
        arrays = self.__dict__.get("_arrays", {})
        if name in arrays:
            size = len(self.__dict__["times"])
            return arrays[name][:size] if name in ("u", "y") else arrays[name][..., :size]
        raise AttributeError(name)

    @property
    def ci(self):
        return np.stack((self.lower, self.upper), axis=-1)

    def append(self, times, u, y, steps, informative):
        size, count = self.size, len(times)
        new = dict(
            u=u,
            y=y,
            ic=steps.ic,
            lower=steps.ci[..., 0],
            upper=steps.ci[..., 1],
            median=steps.median,
            best=steps.best,
            discrimination=steps.discrimination,
            spread=steps.spread,
            points=steps.points,
            informative=np.array([-1 if flag is None else int(flag) for flag in informative], dtype=np.int8),
        )
        for name, values in new.items():
            held = self._arrays[name]
            axis = 1 if held.ndim == 2 and name != "u" else 0  # time is the last axis of the (n_params, n_steps) ones
            if held.shape[axis] < size + count:
                shape = list(held.shape)
                shape[axis] = max(2 * held.shape[axis], size + count, 64)
                grown = np.empty(shape, dtype=held.dtype)
                grown[(slice(None),) * axis + (slice(0, size),)] = held[(slice(None),) * axis + (slice(0, size),)]
                self._arrays[name] = held = grown
            held[(slice(None),) * axis + (slice(size, size + count),)] = values
        self.times.extend(times)

    def set_informative(self, steps, flags):
        self._arrays["informative"][steps] = flags

    def load(self, steps, results, online):
        """The history from the follower's tables (rows of its steps table, and of its results table)."""
        if not steps:
            return
        names = online.names
        n_steps = len(steps)
        loaded = _Steps.empty(len(names), n_steps)
        times = [row.time for row in steps]
        position = {time: k for k, time in enumerate(times)}
        n_inputs = self._arrays["u"].shape[1]
        u = np.array([[getattr(row, f"u{j}") for j in range(n_inputs)] for row in steps], dtype=float)
        y = np.array([_nan(row.y) for row in steps])
        for k, row in enumerate(steps):
            loaded.best[k], loaded.discrimination[k] = _nan(row.best), _nan(row.discrimination)
            loaded.spread[k], loaded.points[k] = _nan(row.spread), row.points
        informative = [None] * n_steps
        for row in results:
            k, p = position[row.time], names.index(row.parameter)
            loaded.ic[p, k], loaded.median[p, k] = _nan(row.ic), _nan(row.estimate)
            loaded.ci[p, k] = _nan(row.lower), _nan(row.upper)
            informative[k] = row.informative
        self.append(times, u, y, loaded, informative)


def _nan(value):
    return math.nan if value is None else float(value)
