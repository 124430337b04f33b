"""``dynia follow URL --table NAME ...``: the follower of :mod:`dynia.follow` as a command that runs until stopped.

It polls the table every ``--poll`` seconds, writing a transaction per
``--batch`` rows, and judges the whole record every ``--judge-every``
seconds (and before it exits). SIGINT and SIGTERM let the transaction in
progress commit, judge, and end the command with status 0; ``--once``
analyses the rows present, judges and exits. A database that cannot be
reached while following is retried at the next poll from the last commit;
at the start, or with ``--once``, it ends the command with one line.
"""

import contextlib
import logging
import signal
import sys
import threading
import time

from ..errors import SettingsError
from ..io.database import Source, connect, error_line

__all__ = ["follow"]

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


def follow(options, command_line, caught):
    """Run ``dynia follow`` with the checked ``options`` of :mod:`dynia.cli.commands`; the exit status."""
    import sqlalchemy

    from ..follow import Follower, FollowerSettings

    logger = _logger(options["quiet"])
    engine = connect(options["url"])
    source = Source(
        engine,
        options["table"],
        time=options["time"],
        inputs=options["input"],
        output=options["output"],
        long_format=options["long"],
        tag_column=options["tag_column"],
        value_column=options["value_column"],
        duplicates=options["duplicates"],
        time_format=options.get("time_format"),
    )
    analysis = options["analysis"].replace(window="trailing")
    if options.get("dt") is not None:
        analysis = analysis.replace(dt=options["dt"])
    recorded = {f"--{key.replace('_', '-')}": options.get(key) for key in _RECORDED}
    recorded["--seed"] = options["seed"] if "seed" in options["given"] else None
    settings = FollowerSettings(
        options=recorded,
        analysis=analysis,
        seed=options["seed"],
        window_seconds=options.get("window_seconds"),
        min_points=options["min_points"],
        offset=options["offset"],
        input_offset=options["input_offset"],
        quality=options["quality"],
        max_gap=options["max_gap"],
        dt_given=options.get("dt") is not None,
    )

    def started(restart):
        return Follower(
            engine,
            source,
            options["model_object"],
            options["bounds"],
            settings,
            options["results"],
            options["events"],
            restart=restart,
        )

    follower = started(options["restart"])
    logger.info(
        "following %s into %s (%d steps so far, seed %d)",
        options["table"],
        options["results"],
        follower.steps,
        follower.settings.seed,
    )
    stopping = threading.Event()
    with _stopped_by_signals(stopping):
        judged, unjudged = time.monotonic(), True
        while True:
            try:
                written = follower.poll(options["batch"], stop=stopping.is_set)
                unjudged = unjudged or written > 0
                if written:
                    logger.info("wrote %d step(s); %d in all", written, follower.steps)
                due = time.monotonic() - judged >= options["judge_every"]
                if unjudged and (options["once"] or stopping.is_set() or due):
                    follower.judge()
                    judged, unjudged = time.monotonic(), False
            except sqlalchemy.exc.IntegrityError:
                raise SettingsError(
                    f"{options['results']} was given a step it already holds: another follower writes to it; give "
                    "each follower its own --results",
                    "results",
                ) from None
            except sqlalchemy.exc.OperationalError as error:
                if options["once"]:
                    raise SettingsError(f"the database failed while following: {error_line(error)}", "url") from None
                logger.warning("the database failed (%s); going on from the last commit", error_line(error))
                stopping.wait(options["poll"])
                with contextlib.suppress(sqlalchemy.exc.OperationalError):
                    follower = started(False)
                continue
            if options["once"] or (stopping.wait(options["poll"]) and not unjudged):
                break
    if follower.late_rows:
        logger.warning("%d late row(s) skipped in all", follower.late_rows)
    return 0


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
