"""``dynia suggest DATA.csv ...``: a window, a behavioural share and a number of samples for ``analyse``, and why.

With the data and model options of ``analyse``, it proposes what
:func:`dynia.suggest` finds and prints the ``dynia analyse`` command that
runs it; ``--json`` prints it for machines. Every option of ``analyse``
given is carried into that command, and the window, share or number of
samples given is kept. It writes nothing.
"""

from __future__ import annotations

import dataclasses
import json
import shlex
import sys
import textwrap

from .. import __version__
from ..settings import DEFAULT_MAX_SAMPLES, check_ic_threshold
from .analyse import METHOD, NARROWING
from .options import (
    DATA,
    MODEL,
    QUIET,
    FileOptions,
    Group,
    Option,
    SamplingOptions,
    add_command,
    by_key,
    check_max_gap,
    check_seed,
    refuse_idle,
)

__all__ = ["OPTIONS", "Options", "check", "cli_action", "cli_parse"]

PILOT = (
    Option("seed", "whole", "seed of the pilot runs (default: drawn at random and printed)", metavar="S"),
    Option(
        "max_samples",
        "whole",
        "the most samples of the pilot and of the proposal (default {default}); the behavioural share is "
        "raised so that the pilot's 50 behavioural sets fit in N",
        default=DEFAULT_MAX_SAMPLES,
        metavar="N",
    ),
    Option(
        "max_memory",
        "size",
        "the most memory the pilot may take, e.g. 4GB or 512MB (default: half the memory available); "
        "a pilot estimated above it is refused",
        metavar="SIZE",
    ),
    Option("json", "flag", "print the proposal as JSON"),
    QUIET,
)

# The analyse options suggest takes, to carry them into the analyse command it proposes: all of analyse's method
# but the seed and --max-samples, which are suggest's own (the pilot's seed, the most samples of the proposal), and
# --target-se, whose budget is analyse's --max-samples.
# What suggest proposes shows no default: left out, suggest proposes it.
ANALYSIS = tuple(
    dataclasses.replace(option, help=option.help + " (default: proposed)")
    if option.key in ("samples", "n", "window", "percentage")
    else option
    for option in METHOD
    if option.key not in ("seed", "max_samples", "target_se")
)

_ANALYSIS_TEXT = (
    "the options of the dynia analyse command suggest proposes: each one given is carried into that command as "
    "given, and the pilot runs with it. --n or --window, --percentage and --samples fix what suggest would "
    "otherwise propose: it keeps the value given, proposes the rest around it and says what the record asks for"
)

GROUPS = (
    Group("data", DATA),
    Group("model", MODEL),
    Group("analysis (carried into the proposed command)", ANALYSIS, textwrap.fill(_ANALYSIS_TEXT, 76)),
    Group("pilot and output", PILOT),
)

#: suggest's options by key, in the order of its ``--help``.
OPTIONS = by_key(GROUPS)

# The options of the commands that write, which suggest knows only to refuse with this: argparse would call --out an
# ambiguous abbreviation of --output and --output-file.
_REFUSED = {
    option: f"dynia suggest writes nothing (it prints its proposal), so it takes no {option}; "
    "give --out to the dynia analyse command it proposes"
    for option in ("--out", "--overwrite", "--no-plots", "--unit", "--reference")
}

# suggest's own options, which the analyse command it proposes does not take (its seed is given anew).
_OWN = ("--seed", "--max-samples", "--max-memory")

_EPILOG = """\
example (proposes --n, --percentage and --samples for dynia analyse, with the reasons):
  dynia suggest data/heating_system/heating_system.csv --time time --input u --output y \\
      --model first-order --param K=0:40 --param T=0:200 \\
      --input-offset 6 --offset first --x0 zero --seed 1

  with --window 2min (or --n 60) it keeps that window and proposes the share and the
  samples for it; --flavour mcat, --conf-level 95, ... go into the proposed command.
"""


@dataclasses.dataclass(frozen=True, kw_only=True)
class Options(FileOptions, SamplingOptions):
    """The options of ``dynia suggest``, checked: each field of an option's key holds its value.

    ``analysis`` holds the settings of the pilot runs; ``max_memory`` is in bytes.
    """

    ic_error: bool
    dtype: str
    on_disk: bool
    second_run: bool
    narrow_threshold: float
    narrow_margin: float
    max_samples: int
    max_memory: float | None
    json: bool


def cli_parse(subparsers):
    """Add ``dynia suggest`` and its options to the ``subparsers`` of ``dynia``."""
    return add_command(
        subparsers,
        "suggest",
        GROUPS,
        refused=_REFUSED,
        help="propose a window, a behavioural share and a number of samples for analyse, and say why",
        description="Estimate the record's dominant time constant and its noise, choose a window of about one "
        "time constant or, on a noisy record, as long as it takes to beat the noise, a behavioural share that lets "
        "the IC reach high values, and the number of samples that brings a pilot run's IC standard error to 0.02; "
        "check the parameter ranges against a least-squares fit. A window (--n or --window), share (--percentage) "
        "or number of samples (--samples) given is kept, and the rest proposed around it; every analyse option "
        "given is carried into the proposed command. Writes nothing; prints the proposal (--json: as JSON).",
        epilog=_EPILOG,
    )


def check(values):
    """suggest's own checks of its options (an ``argparse.Namespace`` of them), in the order they are made."""
    from ..refine import check_margin

    check_ic_threshold(values.narrow_threshold)  # as analyse will check it, now
    refuse_idle(values, NARROWING)
    if values.second_run:
        check_margin(values.narrow_margin)
    check_seed(values)
    check_max_gap(values)


def cli_action(options, caught):
    """Run ``dynia suggest`` with its checked ``options``: print the proposal and the analyse command that runs it.

    ``caught`` collects the warnings of the run, which the command reports itself. Returns the exit status.
    """
    from ..suggestion import suggest
    from .common import announce_compilation, data_warnings, dynia_warnings, load

    options, record = load(options)
    # suggest writes no summary.json: the findings go with the proposal, as JSON or one warning line each.
    where = "see data_quality in the JSON output" if options.json else "listed in the warnings below"
    notices, pairs = data_warnings(record.data, options, quality=options.quality, where=where)
    findings = [entry for _, entry in pairs]
    if not options.json:
        notices += [
            f"data quality: {entry['signal']} {entry['kind']} from {entry['start_time']} to {entry['end_time']}: "
            f"{entry['reason']}"
            for entry in findings
        ]
    # The pilot runs and the check of the proposal take at most --max-samples sets.
    announce_compilation(options, options.analysis, options.max_samples, record.y.shape[0])
    given = options.given
    found = suggest(
        record.u,
        record.y,
        options.model_object,
        options.bounds,
        dt=record.data.dt,
        x0=options.x0,
        # Kept as given (a --window is n on the data's grid by now, load); the rest is proposed around them.
        n=options.n if {"n", "window"} & given else None,
        percentage=options.percentage if "percentage" in given else None,
        n_samples=options.samples if "samples" in given else None,
        settings=options.analysis,
        max_samples=options.max_samples,
        max_memory=options.max_memory,
        progress=options.shows_progress,
        rng=options.seed,
    )
    # Printed once there is a proposal: a record that gets none ends in its one error line, which says why.
    dropped = dynia_warnings(caught)
    for line in notices + dropped:
        print(f"dynia: warning: {line}", file=sys.stderr)
    analyse = _analyse_command(options, found)
    if options.json:
        print(
            json.dumps(
                dict(
                    found.to_dict(),
                    seed=options.seed,
                    command=analyse,
                    warnings=notices + dropped,
                    **({"data_quality": findings} if options.quality else {}),
                    version=__version__,
                    command_line=options.command_line,
                ),
                indent=2,
                allow_nan=False,
            )
        )
    else:
        print(found.text())
        print("run:\n  " + shlex.join(analyse))
    return 0


def _analyse_command(options, found):
    """The analyse command of the proposal ``found``: every analyse option as the user gave it, and the settings
    proposed (the proposal leaves out those given), with the seed of the pilot."""
    kept, words = [], iter(options.command_line[2:])
    for word in words:
        if word in _OWN:
            next(words, None)
        elif word != "--json" and not word.startswith(tuple(option + "=" for option in _OWN)):
            kept.append(word)
    return ["dynia", "analyse", *kept, *found.arguments(), "--seed", str(options.seed), "--out", "RESULTS"]
