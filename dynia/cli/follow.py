"""``dynia follow URL --table NAME ...``: the follower of :mod:`dynia.follow` as a command that runs until stopped.

It polls the table every ``--poll`` seconds, writing a transaction per
``--batch`` rows, and judges the whole record every ``--judge-every``
seconds (and before it exits). SIGINT and SIGTERM let the transaction in
progress commit, judge, and end the command with status 0; ``--once``
analyses the rows present, judges and exits. A database that cannot be
reached while following is retried at the next poll from the last commit;
at the start, or with ``--once``, it ends the command with one line.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import signal
import sys
import threading
import time

from ..errors import SettingsError
from ..io.database import Source, connect, error_line
from .analyse import METHOD
from .options import (
    DATA,
    MODEL,
    Group,
    Option,
    SamplingOptions,
    UsageError,
    add_command,
    by_key,
    check_max_gap,
    check_seed,
)

__all__ = ["OPTIONS", "Options", "check", "cli_action", "cli_parse"]

# dynia follow reads a table of a database: the data options of analyse but the file's own.
SOURCE = (
    Option(
        "url",
        "text",
        "the database: sqlite:///plant.db (built in), or postgresql://user@host:5432/plant after "
        'pip install "dynia[postgres]"; any SQLAlchemy URL whose driver is installed',
        metavar="URL",
        required=True,
    ),
    Option(
        "table",
        "text",
        "the table of logged data: wide (time, input and output columns) or --long",
        metavar="NAME",
        required=True,
    ),
    *(option for option in DATA if option.key not in ("data", "output_file")),
)

# A follower analyses one trailing window a step, with no Monte Carlo error and nothing written but its tables.
ANALYSIS = tuple(
    option
    for option in METHOD
    if option.key
    in ("samples", "sampler", "n", "window", "percentage", "bins", "conf_level", "flavour", "min_points", "seed")
)

FOLLOWER = (
    Option(
        "results", "text", "the results table: a row per step and parameter", default="dynia_results", metavar="NAME"
    ),
    Option(
        "events", "text", "the table of verdict changes, shared by followers", default="dynia_events", metavar="NAME"
    ),
    Option("poll", "number", "seconds between looks at the table for new rows", default=10.0, metavar="SECONDS"),
    Option("once", "flag", "analyse every row present, judge the record, commit and exit (for cron and tests)"),
    Option(
        "batch",
        "whole",
        "rows read and committed per transaction: the most a kill can make the follower redo",
        default=10_000,
        metavar="ROWS",
    ),
    Option(
        "judge_every",
        "number",
        "seconds between judgements of the whole record (noise floor, informative windows, verdicts); also on "
        "--once and on exit",
        default=60.0,
        metavar="SECONDS",
    ),
    Option("restart", "flag", "drop this follower's results, steps and state, and start over from the first row"),
    Option(
        "quiet",
        "flag",
        "no progress lines on stderr (steps written per poll); verdict changes, late rows, warnings and errors "
        "still print",
    ),
)

GROUPS = (Group("source", SOURCE), Group("model", MODEL), Group("method", ANALYSIS), Group("follower", FOLLOWER))

#: follow's options by key, in the order of its ``--help``.
OPTIONS = by_key(GROUPS)

# The most rows dynia follow reads into one transaction: some hundred bytes a row in memory.
_MOST_BATCH_ROWS = 10_000_000

# The options that decide what the results are: a follower started again must be given the same.
_RECORDED = (
    "table",
    "time",
    "time_format",
    "input",
    "output",
    "long",
    "tag_column",
    "value_column",
    "dt",
    "max_gap",
    "duplicates",
    "no_quality",
    "offset",
    "input_offset",
    "model",
    "param",
    "x0",
    "samples",
    "sampler",
    "n",
    "window",
    "percentage",
    "bins",
    "conf_level",
    "flavour",
    "min_points",
    "seed",
)

_EPILOG = """\
example (the heating-system record loaded into SQLite as table heating, then followed):
  dynia follow sqlite:///plant.db --table heating --time time --input u --output y \\
      --model first-order --param K=0:40 --param T=0:200 \\
      --input-offset 6 --offset first --x0 zero --seed 1 --once

  writes table dynia_results (time, parameter, ic, lower, upper, estimate, informative),
  dynia_events (verdict changes) and the follower's own dynia_results_steps and
  dynia_results_state. Without --once it polls every --poll seconds until SIGINT or
  SIGTERM, which commit and exit 0.
"""


@dataclasses.dataclass(frozen=True, kw_only=True)
class Options(SamplingOptions):
    """The options of ``dynia follow``, checked: each field of an option's key holds its value."""

    url: str
    table: str
    results: str
    events: str
    poll: float
    once: bool
    batch: int
    judge_every: float
    restart: bool


def cli_parse(subparsers):
    """Add ``dynia follow`` and its options to the ``subparsers`` of ``dynia``."""
    return add_command(
        subparsers,
        "follow",
        GROUPS,
        help="keep a results table current as a database table of logged data grows (thesis 4.3)",
        description="Sample the parameters once, then analyse every new row of a database table as the logging "
        "system writes it: one trailing window per step (the batch engine for a first backlog), a row per step and "
        "parameter in the results table, verdict changes in the events table and as log lines. Killed at any moment "
        "and started again, it goes on where its last transaction ended; started with other settings, it refuses.",
        epilog=_EPILOG,
    )


def check(values):
    """follow's own checks of its options (an ``argparse.Namespace`` of them), in the order they are made:
    the poll and judgement intervals, the rows per transaction."""
    check_seed(values)
    for option, value, low, high in (
        ("--poll", values.poll, 0, 86_400),
        ("--judge-every", values.judge_every, 0, 86_400 * 365),
    ):
        if not low < value <= high:
            raise UsageError(f"{option} must lie in ({low}, {high}] seconds; got {value:g}")
    if not 1 <= values.batch <= _MOST_BATCH_ROWS:
        raise UsageError(
            f"--batch must be a whole number of rows in [1, {_MOST_BATCH_ROWS}] (a transaction holds them all in "
            f"memory); got {values.batch}"
        )
    check_max_gap(values)


def cli_action(options, caught):
    """Run ``dynia follow`` with its checked ``options`` until stopped (or, with ``--once``, the rows present are
    analysed and judged); the exit status.

    ``caught`` is not read: the follower logs its warnings itself.
    """
    logger = _logger(options.quiet)
    engine = connect(options.url)
    source = Source(
        engine,
        options.table,
        time=options.time,
        inputs=options.input,
        output=options.output,
        long_format=options.long,
        tag_column=options.tag_column,
        value_column=options.value_column,
        duplicates=options.duplicates,
        time_format=options.time_format,
    )
    settings = _follower_settings(options)

    def started(restart):
        from ..follow import Follower

        return Follower(
            engine,
            source,
            options.model_object,
            options.bounds,
            settings,
            options.results,
            options.events,
            restart=restart,
        )

    follower = started(options.restart)
    logger.info(
        "following %s into %s (%d steps so far, seed %d)",
        options.table,
        options.results,
        follower.steps,
        follower.settings.seed,
    )
    stopping = threading.Event()
    with _stopped_by_signals(stopping):
        follower = _followed(options, follower, started, logger, stopping)
    if follower.late_rows:
        logger.warning("%d late row(s) skipped in all", follower.late_rows)
    return 0


def _followed(options, follower, started, logger, stopping):
    """Poll and judge until the rows present are (``--once``) or ``stopping`` is set; the follower then (``started``
    anew after the database failed)."""
    import sqlalchemy

    judged, unjudged = time.monotonic(), True
    while True:
        try:
            written = follower.poll(options.batch, stop=stopping.is_set)
            unjudged = unjudged or written > 0
            if written:
                logger.info("wrote %d step(s); %d in all", written, follower.steps)
            due = time.monotonic() - judged >= options.judge_every
            if unjudged and (options.once or stopping.is_set() or due):
                follower.judge()
                judged, unjudged = time.monotonic(), False
        except sqlalchemy.exc.IntegrityError:
            raise SettingsError(
                f"{options.results} was given a step it already holds: another follower writes to it; give "
                "each follower its own --results",
                "results",
            ) from None
        except sqlalchemy.exc.OperationalError as error:
            if options.once:
                raise SettingsError(f"the database failed while following: {error_line(error)}", "url") from None
            logger.warning("the database failed (%s); going on from the last commit", error_line(error))
            stopping.wait(options.poll)
            with contextlib.suppress(sqlalchemy.exc.OperationalError):
                follower = started(False)
            continue
        if options.once or (stopping.wait(options.poll) and not unjudged):
            return follower


def _follower_settings(options):
    """The :class:`~dynia.follow.FollowerSettings` of the options: the analysis of a trailing window, and the options
    that decide the results as given, which a follower started again must be given alike."""
    from ..follow import FollowerSettings

    analysis = options.analysis.replace(window="trailing")
    if options.dt is not None:
        analysis = analysis.replace(dt=options.dt)
    recorded = {f"--{key.replace('_', '-')}": getattr(options, key) for key in _RECORDED}
    recorded["--seed"] = options.seed if "seed" in options.given else None
    return FollowerSettings(
        options=recorded,
        analysis=analysis,
        seed=options.seed,
        window_seconds=options.window_seconds,
        min_points=options.min_points,
        offset=options.offset,
        input_offset=options.input_offset,
        quality=options.quality,
        max_gap=options.max_gap,
        dt_given=options.dt is not None,
    )


@contextlib.contextmanager
def _stopped_by_signals(stopping):
    """SIGINT and SIGTERM set ``stopping`` instead of interrupting a transaction; the handlers are put back after."""
    previous = {}
    for number in (signal.SIGINT, signal.SIGTERM):
        previous[number] = signal.signal(number, lambda *_: stopping.set())
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


def _logger(quiet):
    """The follower's log on stderr: one line per event, with the UTC time it happened."""
    from ..follow import VERDICT_CHANGE

    logger = logging.getLogger("dynia.follow")
    logger.handlers.clear()
    handler = logging.StreamHandler(sys.stderr)
    formatter = logging.Formatter("%(asctime)s dynia follow: %(message)s", "%Y-%m-%dT%H:%M:%SZ")
    formatter.converter = time.gmtime
    handler.setFormatter(formatter)
    logger.addHandler(handler)
    logger.setLevel(VERDICT_CHANGE if quiet else logging.INFO)
    logger.propagate = False
    return logger
