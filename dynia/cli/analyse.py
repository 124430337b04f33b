"""``dynia analyse DATA.csv ... --out DIR``: DYNIA on a CSV file, its results written to a directory.

It loads the data (:mod:`dynia.io.csv`), runs :func:`dynia.run` and writes
tables, a JSON summary and figures to DIR (:func:`dynia.cli.report.write_analysis`);
``--second-run`` narrows the ranges and analyses again into DIR/second_run.
``dynia analyse --config run.toml`` takes the same settings from a file.
"""

from __future__ import annotations

import dataclasses
import sys

import numpy as np

from .. import __version__
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
    SamplingOptions,
    WritingOptions,
    add_command,
    by_key,
    check_max_gap,
    check_seed,
    refuse_idle,
    setting_option,
)

__all__ = ["METHOD", "NARROWING", "OPTIONS", "Options", "check", "cli_action", "cli_parse"]

# The analysis: the settings of the library, and what the command line adds to them.
METHOD = (
    setting_option("n_samples"),
    setting_option("sampler"),
    setting_option("n"),
    Option("window", "text", WINDOW_HELP, metavar="DURATION"),
    setting_option("percentage"),
    setting_option("bins"),
    setting_option("conf_level"),
    setting_option("flavour"),
    setting_option("min_points"),
    setting_option("ic_error"),
    setting_option("target_se"),
    setting_option("max_samples"),
    setting_option("dtype"),
    Option(
        "on_disk",
        "flag",
        "write result.nc as the windows are analysed and read it back lazily: for records whose CLD "
        "gradient does not fit in memory (a year of 1 Hz data)",
    ),
    Option(
        "second_run",
        "flag",
        "narrow the range of every parameter whose highest IC reaches "
        "--narrow-threshold to its band there, and analyse again (thesis 3.1): "
        "results in DIR/second_run/",
    ),
    Option(
        "narrow_threshold",
        "number",
        "IC from which a window is informative, for the narrowing",
        default=IC_THRESHOLD,
        metavar="IC",
        setting="ic_threshold",
    ),
    Option(
        "narrow_margin",
        "number",
        "the band is widened by M times its width on each side",
        default=0.5,
        metavar="M",
        setting="margin",
    ),
    SEED,
)

GROUPS = (Group("data", DATA), Group("model", MODEL), Group("method", METHOD), Group("output", OUTPUT))

#: analyse's options by key, in the order of its ``--help``.
OPTIONS = by_key(GROUPS)

# The narrowing's options do something only with --second-run (see refuse_idle).
NARROWING = (
    (
        "narrow_threshold",
        "second_run",
        True,
        "--narrow-threshold sets the narrowing of --second-run; add that or leave it out",
    ),
    (
        "narrow_margin",
        "second_run",
        True,
        "--narrow-margin sets the narrowing of --second-run; add that or leave it out",
    ),
)

_EPILOG = """\
example (the DaISy heating-system record shipped in data/; it starts in steady state
at an input of 6 V, so the model works in deviations from that operating point):
  dynia analyse data/heating_system/heating_system.csv --time time --input u --output y \\
      --model first-order --param K=0:40 --param T=0:200 \\
      --input-offset 6 --offset first --x0 zero --seed 1 --out results/heating

  writes results/heating/: ic.csv, limits.csv, samples.csv, summary.json, result.nc and
  PNG figures (the data, and per parameter its information content and its
  identifiability plot). All settings can also come from a TOML file:
  dynia analyse --config run.toml (keys as the long options, e.g. samples = 5000,
  and param = ["K=0:30", "T=0:300"]); options given on the command line win.
"""


@dataclasses.dataclass(frozen=True, kw_only=True)
class Options(WritingOptions, SamplingOptions):
    """The options of ``dynia analyse``, checked: each field of an option's key holds its value."""

    ic_error: bool
    target_se: float | None
    max_samples: int | None
    dtype: str
    on_disk: bool
    second_run: bool
    narrow_threshold: float
    narrow_margin: float


def cli_parse(subparsers):
    """Add ``dynia analyse`` and its options to the ``subparsers`` of ``dynia``."""
    return add_command(
        subparsers,
        "analyse",
        GROUPS,
        help="run DYNIA on a CSV file and write the results to a directory",
        description="Sample the model's parameters, simulate every sample on the logged input and, "
        "at every time step, rank the samples over a moving window: the information "
        "content IC(t) of each parameter, its confidence band and the CLD gradient.",
        epilog=_EPILOG,
    )


def check(values):
    """analyse's own checks of its options (an ``argparse.Namespace`` of them), in the order they are made."""
    from ..refine import check_margin

    check_ic_threshold(values.narrow_threshold)  # the library's own check, now rather than after the analysis
    refuse_idle(values, (*NARROWING, REFERENCE_NEEDS_PLOTS))
    if values.second_run:
        check_margin(values.narrow_margin)  # now, not after the first run
    check_seed(values)
    check_max_gap(values)


def cli_action(options, caught):
    """Run ``dynia analyse`` with its checked ``options``: write the results into ``--out``, print the verdicts.

    ``caught`` collects the warnings of the run, which the command reports itself. Returns the exit status.
    """
    from ..refine import narrowed_bounds
    from .common import data_warnings, done, load, written_into

    with options.destination as staging, written_into(options.out, staging):
        options, record = load(options)
        analysis = options.analysis.replace(dt=record.data.dt)
        notices, findings = data_warnings(record.data, options, quality=options.quality)
        for line in notices:
            print(f"dynia: warning: {line}", file=sys.stderr)

        def analyse(bounds, directory, narrowed=None):
            result, dropped = _analysed(options, record, analysis, bounds, directory, caught)
            summary = _summary(options, record, analysis, result, bounds, notices + dropped, findings, narrowed)
            return result, _written(options, record, result, summary, directory)

        result, table = analyse(options.bounds, staging)
        tables = [table]
        if options.second_run:
            bounds, narrowed = narrowed_bounds(
                result, options.bounds, ic_threshold=options.narrow_threshold, margin=options.narrow_margin
            )
            (staging / "second_run").mkdir()
            _, second = analyse(bounds, staging / "second_run", narrowed=narrowed)
            tables.append("second run (narrowed: " + (", ".join(narrowed) or "none") + ")\n" + second)
    print("\n\n".join(tables))
    return done(options)


def _analysed(options, record, analysis, bounds, directory, caught):
    """The ``analysis`` of ``record`` within ``bounds``, its verdicts timed as the file times them; (result, the
    messages of its warnings, which are printed)."""
    from ..pipeline import run
    from ..verdicts import assess
    from . import report
    from .common import announce_compilation, dynia_warnings

    data = record.data
    # --on-disk: the run writes result.nc itself, block by block, and the result reads it lazily.
    settings = analysis.replace(store=directory / "result.nc") if options.on_disk else analysis
    announce_compilation(options, settings, settings.n_samples, record.y.shape[0])
    result = run(
        record.u,
        record.y,
        options.model_object,
        bounds,
        settings=settings,
        rng=options.seed,
        progress=options.shows_progress,
    )
    dropped = dynia_warnings(caught)
    for line in dropped:
        print(f"dynia: warning: {line}", file=sys.stderr)
    # The reasons name times as the file wrote them, as the table does.
    result = dataclasses.replace(
        result, verdicts=assess(result, clock=lambda step: report.file_times(data, [data.time[step]])[0])
    )
    return result, dropped


def _summary(options, record, analysis, result, bounds, warnings, findings, narrowed):
    """summary.json of a run: its parameters' verdicts, the settings, the run, the data and where it all comes from.

    ``warnings`` are the lines printed, ``findings`` the data-quality findings, ``narrowed`` the parameters a second
    run narrowed (None for a first run).
    """
    from . import report
    from .common import provenance, recorded

    data = record.data
    parameters = result.summary()
    for entry in parameters.values():
        # The result's clock starts at the first grid point, data.time[0] after time zero.
        for key in ("time_of_max_ic", "time_of_highest_ic"):
            if entry.get(key) is not None:
                entry[key] = report.file_times(data, [data.time[0] + entry[key]])[0]
        if entry["high_ic_span"][0] is not None:
            entry["high_ic_span"] = report.file_times(data, data.time[0] + np.array(entry["high_ic_span"]))
    settings = dict(
        recorded(options, OPTIONS, analysis, record),
        bounds={name: list(pair) for name, pair in bounds.items()},
        **({} if narrowed is None else {"narrowed": narrowed}),
    )
    summary = dict(
        parameters=parameters,
        settings=settings,
        version=__version__,
        run=dict(
            n_sampled=result.run.n_sampled,
            n_dropped=result.run.n_dropped,
            n_behavioural=result.run.n_behavioural,
            engine=result.settings.engine,
            **_monte_carlo_record(result),
        ),
        noise_floor=report.noise_floor_summary(result, data),
        warnings=warnings,
        data=dict(
            n_steps=int(data.time.size),
            dt=data.dt,
            start=report.file_times(data, [0.0])[0],
            notes=list(data.notes),
            gaps=[report.file_times(data, [data.time[a], data.time[b - 1]]) for a, b in data.gaps],
        ),
        **provenance(options),
    )
    if options.quality:
        summary["data_quality"], summary["screening"] = _screening_summary(result, findings)
    return summary


def _written(options, record, result, summary, directory):
    """Write the results of a run into ``directory``; the table of its verdicts that the command prints."""
    from ..summary import verdict_table
    from . import report
    from .common import labels

    report.write_analysis(
        directory,
        result,
        record.data,
        summary,
        offset=record.offset,
        input_offset=record.input_offset,
        plots=not options.no_plots,
        saved=options.on_disk,
        labels=labels(options),
    )
    table = verdict_table(summary["parameters"])
    table += "".join("\n" + line for line in report.screening_lines(summary))
    if summary["noise_floor"] is not None:
        table += "\n" + report.noise_floor_line(summary["noise_floor"])
    return table


def _monte_carlo_record(result):
    """What summary.json's ``run`` says of the Monte Carlo error: batches, and the target's rounds."""
    if not result.settings.ic_error:
        return {}
    record = dict(ic_batches=result.run.ic_batches)
    if result.settings.target_se is not None:
        record.update(
            target_se=result.settings.target_se,
            target_se_reached=result.run.target_se_reached,
            target_se_met=result.run.target_se_met,
            target_se_rounds=[list(pair) for pair in result.run.target_se_rounds],
        )
    return record


def _screening_summary(result, findings):
    """summary.json's ``data_quality`` (each finding, and the windows it takes from the evidence) and ``screening``.

    ``findings`` are :func:`~dynia.cli.common.data_warnings`' (finding, entry) pairs; a screened kind's windows are
    those that use its readings (saturated, stuck) or the run's quantised windows of its signal.
    """
    from ..quality import SCREENED_KINDS

    listed = []
    for finding, entry in findings:
        excluded = 0
        if finding.kind == "quantised":
            excluded = sum(
                stop - start
                for kind, signal, start, stop, _ in result.run.screened or ()
                if kind == "quantised" and signal == finding.signal
            )
        elif finding.kind in SCREENED_KINDS:
            samples = np.zeros(result.time.size, dtype=bool)
            samples[finding.start : finding.stop] = True
            excluded = int(result.windows_using(samples).sum())
        listed.append(dict(entry, screened=finding.kind in SCREENED_KINDS, windows_excluded=excluded))
    screening = dict(
        quality=result.settings.quality,
        excluded_windows=int(result.screened_windows.sum()),
        n_windows=int(result.time.size),
    )
    return listed, screening
