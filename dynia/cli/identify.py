"""``dynia identify DATA.csv ... --out DIR``: the model fitted by least squares on selected data, and validated.

With the data and model options of ``analyse`` and ``--method
{dynia,baseline,whole}``, it fits the model on the data the method selects
and validates it on the held-out end of the record
(:func:`dynia.identify`), writing ``identified.json`` and ``fit.png``.
What the library says names its arguments; the command says it naming the
options that give them (:func:`in_options`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import re
import sys

from .. import __version__
from ..errors import NothingSelected, SettingsError
from ..settings import IC_THRESHOLD, check_ic_threshold
from .options import (
    DATA,
    MODEL,
    OUTPUT,
    REFERENCE_NEEDS_PLOTS,
    SEED,
    WINDOW_HELP,
    Group,
    Option,
    UsageError,
    WritingOptions,
    add_command,
    by_key,
    check_max_gap,
    check_seed,
    refuse_idle,
    setting_option,
)

__all__ = ["METHODS", "OPTIONS", "Options", "check", "cli_action", "cli_parse", "in_options", "min_length_steps"]

#: How identify selects the data it fits on.
METHODS = ("dynia", "baseline", "whole")

SELECTION = (
    Option(
        "method",
        "text",
        "{default} (default): segments where the IC reaches --ic-threshold; baseline: "
        "the accepted intervals of the Bittencourt et al. (2015) search; whole: "
        "the whole record before the held-out part",
        default="dynia",
        choices=METHODS,
    ),
    Option(
        "ic_threshold", "number", "dynia: IC from which a window is informative", default=IC_THRESHOLD, metavar="IC"
    ),
    Option(
        "mode",
        "text",
        "dynia: a step is informative when any parameter's IC reaches the threshold (default) or when all do",
        default="any",
        choices=("any", "joint"),
    ),
    Option(
        "min_length",
        "length",
        "dynia: the shortest segment kept, in steps (a whole number) or as a duration such as 60s, 2min or 1h "
        "(default: one window, 2n+1 steps): shorter runs of informative windows see the same few points",
        metavar="STEPS|DURATION",
    ),
    Option(
        "held_out",
        "number",
        "share of the record, at its end, kept for validation",
        default=0.3,
        metavar="FRACTION",
    ),
    Option(
        "exclude_flagged",
        "flag",
        "check the data and leave out what is flagged (output as missing, input interpolated)",
    ),
    Option(
        "starts",
        "whole",
        "least-squares starting points: the middle of the ranges, then random",
        default=1,
        metavar="N",
        setting="n_starts",
    ),
    setting_option("n_samples", "dynia: "),
    setting_option("n", "dynia: "),
    Option("window", "text", "dynia: " + WINDOW_HELP, metavar="DURATION"),
    setting_option("percentage", "dynia: "),
    SEED,
)

GROUPS = (Group("data", DATA), Group("model", MODEL), Group("selection and fit", SELECTION), Group("output", OUTPUT))

#: identify's options by key, in the order of its ``--help``.
OPTIONS = by_key(GROUPS)

_EPILOG = """\
example (the heating-system record; the last 30 % of it is held out for validation):
  dynia identify data/heating_system/heating_system.csv --time time --input u --output y \\
      --model first-order --param K=0:40 --param T=0:200 \\
      --input-offset 6 --offset first --x0 zero --method dynia --seed 1 --out results/heating-fit

  writes results/heating-fit/identified.json (parameters, std_errors, segments as
  [start_time, end_time] pairs, validation_error, settings) and fit.png.
"""


@dataclasses.dataclass(frozen=True, kw_only=True)
class Options(WritingOptions):
    """The options of ``dynia identify``, checked: each field of an option's key holds its value.

    ``min_length`` is in steps once :func:`cli_action` knows the data's grid. identify has no ``--min-points``:
    its DYNIA windows report an IC from one measured point, the analysis settings' default.
    """

    samples: int
    percentage: float
    method: str
    ic_threshold: float
    mode: str
    min_length: str | int | None
    held_out: float
    exclude_flagged: bool
    starts: int
    min_points: int = 1


def cli_parse(subparsers):
    """Add ``dynia identify`` and its options to the ``subparsers`` of ``dynia``."""
    return add_command(
        subparsers,
        "identify",
        GROUPS,
        help="re-identify the model by least squares on selected data and validate it",
        description="Choose the data to fit on (DYNIA's high-IC segments, the intervals of the "
        "Bittencourt et al. 2015 search, or the whole record), estimate the parameters "
        "by least squares with standard errors, and score the model on the held-out end "
        "of the record. Writes DIR/identified.json and DIR/fit.png.",
        epilog=_EPILOG,
    )


def check(values):
    """identify's own checks of its options (an ``argparse.Namespace`` of them), in the order they are made."""
    check_ic_threshold(values.ic_threshold)  # the library's own check, now rather than after the data are read
    if not 0 < values.held_out < 1:
        raise UsageError(f"--held-out must lie in (0, 1); got {values.held_out:g}")
    refuse_idle(values, (REFERENCE_NEEDS_PLOTS,))
    check_seed(values)
    if values.min_length is not None:
        if values.method != "dynia":
            raise UsageError(
                f"--min-length is the shortest segment DYNIA selects (--method dynia); --method {values.method} "
                "selects its data otherwise"
            )
        min_length_steps(values.min_length, None)  # its form now; in steps once the data's grid is known
    check_max_gap(values)


def min_length_steps(value, dt):
    """``--min-length`` in steps: a whole number is steps, a duration (60s, 2min) is rounded onto the grid ``dt``.

    With ``dt`` None only its form is checked (None is returned for a duration).
    """
    from ..timescale import parse_duration

    text = str(value).strip()
    if text.isdigit():
        steps = int(text)
    else:
        try:
            seconds = parse_duration(text, "--min-length")
        except SettingsError:
            raise UsageError(
                f"--min-length must be a whole number of steps or a duration such as 60s, 2min or 1h; got {value!r}"
            ) from None
        if dt is None:
            return None
        steps = math.floor(seconds / dt + 0.5)
    if steps < 1:
        where = "" if text.isdigit() else f" ({steps} steps of {dt:g} s)"
        raise UsageError(f"--min-length {text}{where}: the shortest segment kept must hold at least 1 step")
    return steps


def cli_action(options, caught):
    """Run ``dynia identify`` with its checked ``options``: write ``identified.json`` and ``fit.png`` into ``--out``,
    print the fit.

    ``caught`` collects the warnings of the run, which the command reports itself. Returns the exit status.
    """
    from . import report
    from .common import announce_compilation, data_warnings, done, dynia_warnings, labels, load, written_into

    with options.destination as staging, written_into(options.out, staging):
        options, record = load(options)
        data = record.data
        analysis = options.analysis.replace(dt=data.dt)
        notices, _ = data_warnings(data, options, quality=False)
        if options.quality and options.model_object.n_inputs > 1:
            notices.append(
                "the record is not screened for saturated, frozen or quantised readings: identify checks a "
                "one-input record only, so its DYNIA run takes every reading as evidence"
            )
        for line in notices:
            print(f"dynia: warning: {line}", file=sys.stderr)
        if options.method == "dynia":
            announce_compilation(options, analysis, analysis.n_samples, record.y.shape[0])
        if options.min_length is not None:
            options = dataclasses.replace(options, min_length=min_length_steps(options.min_length, data.dt))
        with _identify_errors():
            found = _identified(options, record, analysis)
        # Its warnings are the command line's: the terminal, identified.json and fit.png name options.
        found = dataclasses.replace(
            found,
            warnings=[in_options(line) for line in found.warnings],
            little_data=found.little_data and in_options(found.little_data),
        )
        dropped = dynia_warnings(caught)
        for line in dropped + found.warnings:
            print(f"dynia: warning: {line}", file=sys.stderr)
        summary = _summary(options, record, analysis, found, notices + dropped)
        report.write_identification(
            staging,
            found,
            data,
            record.u,
            record.y,
            summary,
            offset=record.offset,
            plots=not options.no_plots,
            labels=labels(options),
        )
    print(
        report.identification_table(
            summary,
            fitted_steps=sum(stop - start for start, stop in found.segments),
            held_out_steps=sum(stop - start for start, stop in found.validation),
        )
    )
    return done(options)


def _identified(options, record, analysis):
    """:func:`dynia.identify` with the command's options."""
    from ..identification import identify

    return identify(
        record.u,
        record.y,
        options.model_object,
        options.bounds,
        method=options.method,
        settings=analysis,
        held_out=options.held_out,
        ic_threshold=options.ic_threshold,
        mode=options.mode,
        min_length=options.min_length,
        # identify checks one input; with several, neither the check nor the run's screening is done (a notice says so).
        quality=options.quality and options.model_object.n_inputs == 1,
        exclude_flagged=options.exclude_flagged,
        n_starts=options.starts,
        rng=options.seed,
        progress=options.shows_progress,
    )


def _summary(options, record, analysis, found, warnings):
    """identified.json: the fit, its segments and findings timed as the file times them, the settings, the data and
    where it all comes from. ``warnings`` are the lines printed before the fit's own."""
    from . import report
    from .common import measured_quality, provenance, recorded

    data = record.data
    summary = found.to_dict(data.time)

    def file_time(index):
        return report.file_times(data, [data.time[index]])[0]

    for key, pairs in (("segments", found.segments), ("validation_segments", found.validation)):
        summary[key] = [[file_time(start), file_time(stop - 1)] for start, stop in pairs]
    # identify checked the record it fits, offsets subtracted: the values and reasons as measured instead.
    measured = {(f.signal, f.kind, f.start, f.stop): f for f in measured_quality(data).findings}
    for finding, entry in zip(found.quality.findings if found.quality else (), summary.get("data_quality", [])):
        entry.update(start_time=file_time(finding.start), end_time=file_time(finding.stop - 1))
        same = measured.get((finding.signal, finding.kind, finding.start, finding.stop))
        if same is not None:
            entry.update(value=same.value, reason=same.reason)
    settings = recorded(options, OPTIONS, analysis, record)
    # identify's own record adds what the command line does not set (held_out_steps, min_length, ...);
    # the analysis settings are already under "analysis".
    analysis_fields = set(analysis.to_dict())
    settings.update(
        {
            key: value
            for key, value in summary.pop("settings").items()
            if key not in settings and key not in analysis_fields
        }
    )
    summary.update(
        settings=settings,
        version=__version__,
        warnings=warnings + summary["warnings"],
        data=dict(
            n_steps=int(data.time.size), dt=data.dt, start=report.file_times(data, [0.0])[0], notes=list(data.notes)
        ),
        **provenance(options),
    )
    return summary


# The library's names in what identify says, as the command line spells them: an error or a warning never names a
# Python argument the user cannot give. Longest first, so that min_length= is read before min_length.
_IDENTIFY_WORDS = (
    ("segments_from_ic selected nothing", "DYNIA selected nothing"),
    ("exclude_flagged=True", "--exclude-flagged"),
    ("loosen baseline_options", "the command line does not tune it: try --method dynia or --method whole"),
    ("choose bounds", "choose --param ranges"),
    ("min_length=", "--min-length "),
    ("min_length", "--min-length"),
    ("ic_threshold", "--ic-threshold"),
    ("held_out", "--held-out"),
    ("n_starts", "--starts"),
    ("mode 'any'", "--mode any"),
    ("mode 'joint'", "--mode joint"),
    ("method 'dynia'", "--method dynia"),
    ("method 'baseline'", "--method baseline"),
    ("method 'whole'", "--method whole"),
)


def in_options(text):
    """``text`` of the library with its names of identify's arguments replaced by the options that give them.

    >>> in_options("raise held_out or lower min_length=")
    'raise --held-out or lower --min-length '
    """
    for name, option in _IDENTIFY_WORDS:
        text = re.sub(r"(?<![\w-])" + re.escape(name) + (r"(?!\w)" if name[-1].isalnum() else ""), option, text)
    return text


@contextlib.contextmanager
def _identify_errors():
    """An error of :func:`dynia.identify` as one naming the command line's options (:func:`in_options`)."""
    try:
        yield
    except (NothingSelected, SettingsError) as error:
        kind = NothingSelected if isinstance(error, NothingSelected) else UsageError
        raise kind(in_options(str(error))) from None
