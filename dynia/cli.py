"""The ``dynia`` command line: DYNIA on an engineer's own logged data, without Python.

``dynia analyse DATA.csv --time COL --input COL --output COL --model MODEL
--param NAME=LOW:HIGH ... --out DIR`` loads the data (:mod:`dynia.data`),
runs :func:`dynia.run` and writes tables, a JSON summary and figures to DIR.
``dynia analyse --config run.toml`` takes the same settings from a file.
``dynia identify DATA.csv`` with the same data and model options, and
``--method {dynia,baseline,whole}``, fits the model by least squares on the
data the method selects and validates it on the held-out end of the record
(:mod:`dynia.identify`), writing ``identified.json`` and ``fit.png``.
Bad input ends the command with one line on stderr and exit status 2.
"""
import argparse
import csv
import datetime
import json
import math
import os
import shutil
import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np

from . import __version__, models
from .analysis import FLAVOURS
from .data import DataError, load_csv
from .identify import identify
from .pipeline import run
from .refine import narrowed_bounds
from .sampling import SAMPLERS

__all__ = ["main"]

IDENTIFY_METHODS = ("dynia", "baseline", "whole")

MODELS = {"first-order": models.FirstOrder, "fopdt": models.FOPDT,
          "second-order-delay": models.SecondOrderDelay}

EXAMPLE = """\
example (the DaISy heating-system record shipped in data/; it starts in steady state
at an input of 6 V, so the model works in deviations from that operating point):
  dynia analyse data/heating_system/heating_system.csv --time time --input u --output y \\
      --model first-order --param K=0:40 --param T=0:200 \\
      --input-offset 6 --offset first --x0 zero --seed 1 --out results/heating

  writes results/heating/: ic.csv, limits.csv, samples.csv, summary.json and
  PNG figures (the data, and per parameter its information content and its
  identifiability plot). All settings can also come from a TOML file:
  dynia analyse --config run.toml (keys as the long options, e.g. samples = 5000,
  and param = ["K=0:30", "T=0:300"]); options given on the command line win.
"""


IDENTIFY_EXAMPLE = """\
example (the heating-system record; the last 30 % of it is held out for validation):
  dynia identify data/heating_system/heating_system.csv --time time --input u --output y \\
      --model first-order --param K=0:40 --param T=0:200 \\
      --input-offset 6 --offset first --x0 zero --method dynia --seed 1 --out results/heating-fit

  writes results/heating-fit/identified.json (parameters, std_errors, segments as
  [start_time, end_time] pairs, validation_error, settings) and fit.png.
"""


class UsageError(Exception):
    """A mistake in the command's options, reported as one line with exit status 2."""


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage mistake is one line on stderr (no usage dump), exit status 2."""

    def error(self, message):
        raise UsageError(message)


def _parser():
    parser = _Parser(prog="dynia", description="Dynamic Identifiability Analysis (DYNIA) of process data: "
                     "find the stretches of logged data that carry information about each model parameter.")
    parser.add_argument("--version", action="version", version=f"dynia {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    analyse = commands.add_parser(
        "analyse", help="run DYNIA on a CSV file and write the results to a directory",
        description="Sample the model's parameters, simulate every sample on the logged input and, "
                    "at every time step, rank the samples over a moving window: the information "
                    "content IC(t) of each parameter, its confidence band and the CLD gradient.",
        epilog=EXAMPLE, formatter_class=argparse.RawDescriptionHelpFormatter)
    _add_data_and_model_options(analyse)
    method = analyse.add_argument_group("method")
    method.add_argument("--samples", type=int, metavar="N", help="Monte Carlo parameter sets (default 2000)")
    method.add_argument("--sampler", choices=sorted(SAMPLERS), help="uniform (default), lhs or sobol")
    method.add_argument("--n", type=int, help="half window: each window holds 2n+1 steps (default 10)")
    method.add_argument("--percentage", type=float, metavar="P",
                        help="behavioural share of the samples in percent (default 10)")
    method.add_argument("--bins", type=int, metavar="B", help="CLD gradient bins (default 40)")
    method.add_argument("--conf-level", type=float, metavar="C",
                        help="confidence level of the band, percent in (0, 100) (default 90)")
    method.add_argument("--flavour", choices=FLAVOURS, help="thesis (default), mcat or weighted")
    method.add_argument("--min-points", type=int, metavar="N",
                        help="windows with fewer measured output points report a missing IC (default 1)")
    method.add_argument("--second-run", action="store_true",
                        help="narrow the range of every parameter whose highest IC reaches "
                             "--narrow-threshold to its band there, and analyse again (thesis 3.1): "
                             "results in DIR/second_run/")
    method.add_argument("--narrow-threshold", type=float, metavar="IC",
                        help="highest IC from which a parameter counts as identified (default 0.75)")
    method.add_argument("--narrow-margin", type=float, metavar="M",
                        help="the band is widened by M times its width on each side (default 0.5)")
    method.add_argument("--seed", type=int, metavar="S",
                        help="seed of every random draw (default: drawn at random and recorded)")
    _add_output_options(analyse)

    identify = commands.add_parser(
        "identify", help="re-identify the model by least squares on selected data and validate it",
        description="Choose the data to fit on (DYNIA's high-IC segments, the intervals of the "
                    "Bittencourt et al. 2015 search, or the whole record), estimate the parameters "
                    "by least squares with standard errors, and score the model on the held-out end "
                    "of the record. Writes DIR/identified.json and DIR/fit.png.",
        epilog=IDENTIFY_EXAMPLE, formatter_class=argparse.RawDescriptionHelpFormatter)
    _add_data_and_model_options(identify)
    selection = identify.add_argument_group("selection and fit")
    selection.add_argument("--method", choices=IDENTIFY_METHODS,
                           help="dynia (default): segments where the IC reaches --ic-threshold; baseline: "
                                "the accepted intervals of the Bittencourt et al. (2015) search; whole: "
                                "the whole record before the held-out part")
    selection.add_argument("--ic-threshold", type=float, metavar="IC",
                           help="dynia: IC from which a step is informative (default 0.5)")
    selection.add_argument("--mode", choices=("any", "joint"),
                           help="dynia: a step is informative when any parameter's IC reaches the "
                                "threshold (default) or when all do")
    selection.add_argument("--held-out", type=float, metavar="FRACTION",
                           help="share of the record, at its end, kept for validation (default 0.3)")
    selection.add_argument("--quality", action="store_true",
                           help="check the data for glitches, outliers and stuck values and report them")
    selection.add_argument("--exclude-flagged", action="store_true",
                           help="check the data and leave out what is flagged (output as missing, "
                                "input interpolated)")
    selection.add_argument("--starts", type=int, metavar="N",
                           help="least-squares starting points: the middle of the ranges, then random (default 1)")
    selection.add_argument("--samples", type=int, metavar="N", help="dynia: Monte Carlo parameter sets (default 2000)")
    selection.add_argument("--n", type=int, help="dynia: half window, each window holds 2n+1 steps (default 10)")
    selection.add_argument("--percentage", type=float, metavar="P",
                           help="dynia: behavioural share of the samples in percent (default 10)")
    selection.add_argument("--seed", type=int, metavar="S",
                           help="seed of every random draw (default: drawn at random and recorded)")
    _add_output_options(identify)
    return parser


def _add_output_options(command):
    output = command.add_argument_group("output")
    output.add_argument("--out", metavar="DIR", help="directory for the results (must not exist)")
    output.add_argument("--overwrite", action="store_true", help="replace DIR if it exists")
    output.add_argument("--config", metavar="FILE.toml", help="read the settings from a TOML file")


def _add_data_and_model_options(command):
    data = command.add_argument_group("data")
    data.add_argument("data", nargs="?", metavar="DATA.csv",
                      help="CSV file with a header row: time, input and output columns")
    data.add_argument("--time", help="name of the time column: seconds, or ISO 8601 timestamps")
    data.add_argument("--input", help="name of the input column (in long format: the input's tag)")
    data.add_argument("--output", help="name of the output column (in long format: the output's tag)")
    data.add_argument("--output-file", metavar="FILE",
                      help="the output is logged in this second file, with its own time column of the "
                           "same name: both logs are resampled onto a common grid")
    data.add_argument("--long", action="store_true",
                      help="DATA.csv is a long-format event log: columns time, tag, value")
    data.add_argument("--tag-column", help="long format: the tag column (default: tag)")
    data.add_argument("--value-column", help="long format: the value column (default: value)")
    data.add_argument("--dt", type=float, metavar="SECONDS",
                      help="grid spacing for irregular or event-based data (default: inferred)")
    data.add_argument("--offset", metavar="{none,first,VALUE}",
                      help="subtract an output offset before fitting: none (default), first (the first "
                           "measured output) or a number")
    data.add_argument("--input-offset", metavar="{none,first,VALUE}",
                      help="subtract an input offset before simulating: none (default), first or a "
                           "number; with --offset and --x0 zero this makes a deviation model around "
                           "an operating point")
    model = command.add_argument_group("model")
    model.add_argument("--model", choices=sorted(MODELS),
                       help="first-order: K/(T s+1); fopdt: K e^(-theta s)/(T s+1); "
                            "second-order-delay: K e^(-theta s)/((T1 s+1)(T2 s+1))")
    model.add_argument("--param", action="append", metavar="NAME=LOW:HIGH",
                       help="sampling range of a model parameter; give one per parameter")
    model.add_argument("--x0", choices=["zero", "steady"],
                       help="initial state of every simulation: zero (default) or steady at the first input")


DEFAULTS = dict(samples=2000, sampler="uniform", n=10, percentage=10.0, bins=40, conf_level=90.0,
                flavour="thesis", x0="zero", offset="none", input_offset="none", min_points=1, tag_column="tag",
                value_column="value", overwrite=False, long=False, second_run=False,
                narrow_threshold=0.75, narrow_margin=0.5, method="dynia", ic_threshold=0.5, mode="any",
                held_out=0.3, quality=False, exclude_flagged=False, starts=1)


def main(argv=None):
    """Entry point of the ``dynia`` command; returns the exit status."""
    parser = _parser()
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return 2
        settings = _settings(args)
        return _identify(settings) if args.command == "identify" else _analyse(settings)
    except (UsageError, DataError, ValueError, OSError) as error:
        print(f"dynia: error: {_one_line(error)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("dynia: interrupted; nothing was written", file=sys.stderr)
        return 130


def _one_line(error):
    if isinstance(error, FileNotFoundError) and error.filename:
        return f"{error.filename}: no such file"
    return " ".join(str(error).split())


def _settings(args):
    """Command-line options over the config file over the defaults, checked."""
    given = {key: value for key, value in vars(args).items()
             if value is not None and key not in ("command", "config") and value is not False}
    settings = dict(DEFAULTS)
    if args.config:
        settings.update(_read_config(args.config))
    settings.update(given)
    for key in ("data", "time", "input", "output", "model", "out"):
        if not settings.get(key):
            option = "DATA.csv" if key == "data" else f"--{key}"
            raise UsageError(f"{option} is required (on the command line or in --config)")
    if not settings.get("param"):
        raise UsageError("give a range for every model parameter with --param NAME=LOW:HIGH")
    if settings["model"] not in MODELS:
        raise UsageError(f"--model must be one of {', '.join(sorted(MODELS))}; got {settings['model']!r}")
    settings["bounds"] = _bounds(settings["param"], MODELS[settings["model"]]())
    for key, minimum in (("samples", 1), ("n", 0), ("bins", 1), ("min_points", 1), ("starts", 1)):
        if not isinstance(settings[key], int) or isinstance(settings[key], bool) or settings[key] < minimum:
            raise UsageError(f"--{key.replace('_', '-')} must be a whole number >= {minimum}; got {settings[key]!r}")
    if not 0 < settings["conf_level"] < 100:
        raise UsageError(f"--conf-level must lie strictly between 0 and 100; got {settings['conf_level']}")
    if not 0 < settings["narrow_threshold"] < 1:
        raise UsageError(f"--narrow-threshold must lie strictly between 0 and 1; got {settings['narrow_threshold']}")
    if not settings["narrow_margin"] >= 0:
        raise UsageError(f"--narrow-margin must be >= 0; got {settings['narrow_margin']}")
    if not 0 < settings["percentage"] <= 100:
        raise UsageError(f"--percentage must lie in (0, 100]; got {settings['percentage']}")
    behavioural = math.floor(settings["samples"] * settings["percentage"] / 100)
    if behavioural < 2:
        raise UsageError(f"--percentage {settings['percentage']:g} of --samples {settings['samples']} keeps "
                         f"{behavioural} parameter sets per window; at least 2 are needed")
    if not 0 < settings["ic_threshold"] <= 1:
        raise UsageError(f"--ic-threshold must lie in (0, 1]; got {settings['ic_threshold']}")
    if not 0 < settings["held_out"] < 1:
        raise UsageError(f"--held-out must lie strictly between 0 and 1; got {settings['held_out']}")
    for key, choices in (("sampler", SAMPLERS), ("flavour", FLAVOURS), ("x0", ("zero", "steady")),
                         ("method", IDENTIFY_METHODS), ("mode", ("any", "joint"))):
        if settings[key] not in choices:
            raise UsageError(f"--{key} must be one of {', '.join(choices)}; got {settings[key]!r}")
    settings["offset"] = _offset(settings["offset"], "--offset")
    settings["input_offset"] = _offset(settings["input_offset"], "--input-offset")
    if settings.get("seed") is None:
        settings["seed"] = int(np.random.SeedSequence().entropy % 2**63)
    out = Path(settings["out"])
    if out.exists() and not settings["overwrite"]:
        raise UsageError(f"--out {out} exists; choose another directory or add --overwrite")
    return settings


def _read_config(path):
    try:
        with open(path, "rb") as handle:
            config = tomllib.load(handle)
    except tomllib.TOMLDecodeError as error:
        raise UsageError(f"--config {path}: not valid TOML: {error}") from None
    config = {key.replace("-", "_"): value for key, value in config.items()}
    allowed = set(DEFAULTS) | {"data", "time", "input", "output", "output_file", "dt", "model", "param",
                               "seed", "out"}
    unknown = sorted(set(config) - allowed)
    if unknown:
        raise UsageError(f"--config {path}: unknown key(s) {', '.join(unknown)}; "
                         f"allowed: {', '.join(sorted(allowed))}")
    if isinstance(config.get("param"), str):
        config["param"] = [config["param"]]
    return config


def _bounds(specs, model):
    """``NAME=LOW:HIGH`` strings to an ordered {name: (low, high)} covering every model parameter."""
    bounds = {}
    for spec in specs:
        name, _, interval = str(spec).partition("=")
        low, _, high = interval.partition(":")
        try:
            low, high = float(low), float(high)
        except ValueError:
            raise UsageError(f"--param {spec!r}: expected NAME=LOW:HIGH with numbers, e.g. K=0:7") from None
        name = name.strip()
        if name not in model.names:
            raise UsageError(f"--param {name}: {type(model).__name__} has parameters {', '.join(model.names)}")
        if name in bounds:
            raise UsageError(f"--param {name} is given twice")
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise UsageError(f"--param {name}: the lower bound {low:g} must be below the upper bound {high:g}")
        bounds[name] = (low, high)
    missing = [name for name in model.names if name not in bounds]
    if missing:
        raise UsageError(f"no --param for {', '.join(missing)} ({type(model).__name__} has parameters "
                         f"{', '.join(model.names)})")
    return bounds


def _offset(value, option):
    if value in ("none", "first"):
        return value
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise UsageError(f"{option} must be none, first or a number; got {value!r}") from None
    if not math.isfinite(number):
        raise UsageError(f"{option} must be finite; got {value!r}")
    return number


def _load(settings):
    """The data, checked against the window, and the output and input offsets."""
    data = load_csv(settings["data"], time=settings["time"], input=settings["input"],
                    output=settings["output"], output_path=settings.get("output_file"),
                    long_format=settings["long"], tag_column=settings["tag_column"],
                    value_column=settings["value_column"], dt=settings.get("dt"))
    window = 2 * settings["n"] + 1
    if data.y.size < window:
        raise UsageError(f"{settings['data']}: {data.y.size} time steps, fewer than one window of "
                         f"2n+1 = {window} (--n {settings['n']})")
    offset = _offset_value(settings["offset"], data.y, settings["data"], "--offset")
    input_offset = _offset_value(settings["input_offset"], data.u, settings["data"], "--input-offset")
    return data, offset, input_offset


def _write_atomically(out, write):
    """Call ``write(staging_dir)``, then move the finished directory to ``out``."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    try:
        write(staging)
        _move_into_place(staging, out)
    finally:
        if staging.exists():
            shutil.rmtree(staging)
    if sys.stderr.isatty():  # quiet in scripts and pipelines
        print(f"dynia: wrote {out}", file=sys.stderr)
    return 0


def _analyse(settings):
    data, offset, input_offset = _load(settings)
    model = MODELS[settings["model"]]()

    def analyse(bounds):
        return run(data.u - input_offset, data.y - offset, model, bounds, dt=data.dt,
                   n_samples=settings["samples"], sampler=settings["sampler"], n=settings["n"],
                   percentage=settings["percentage"], bins=settings["bins"],
                   conf_level=settings["conf_level"], flavour=settings["flavour"], x0=settings["x0"],
                   rng=settings["seed"], progress=sys.stderr.isatty(), min_points=settings["min_points"])

    result = analyse(settings["bounds"])

    def write(staging):
        _write_results(staging, result, data, settings, offset, input_offset)
        if settings["second_run"]:
            bounds, narrowed = narrowed_bounds(result, settings["bounds"], threshold=settings["narrow_threshold"],
                                               margin=settings["narrow_margin"])
            (staging / "second_run").mkdir()
            _write_results(staging / "second_run", analyse(bounds), data, dict(settings, bounds=bounds),
                           offset, input_offset, narrowed=narrowed)

    return _write_atomically(settings["out"], write)


def _identify(settings):
    data, offset, input_offset = _load(settings)
    model = MODELS[settings["model"]]()
    u, y = data.u - input_offset, data.y - offset
    found = identify(u, y, model, settings["bounds"], method=settings["method"], dt=data.dt,
                     x0=settings["x0"], held_out=settings["held_out"], n_samples=settings["samples"],
                     sampler=settings["sampler"], n=settings["n"], percentage=settings["percentage"],
                     flavour=settings["flavour"], ic_threshold=settings["ic_threshold"], mode=settings["mode"],
                     quality=settings["quality"], exclude_flagged=settings["exclude_flagged"],
                     n_starts=settings["starts"], rng=settings["seed"])
    summary = found.to_dict(data.time)

    def file_time(index):
        return _file_times(data, [data.time[index]])[0]

    for key, pairs in (("segments", found.segments), ("validation_segments", found.validation)):
        summary[key] = [[file_time(start), file_time(stop - 1)] for start, stop in pairs]
    for finding, entry in zip(found.quality.findings if found.quality else (), summary.get("data_quality", [])):
        entry.update(start_time=file_time(finding.start), end_time=file_time(finding.stop - 1))
    recorded = {key: settings[key] for key in sorted(settings)
                if key not in ("param", "bounds", "second_run", "narrow_threshold", "narrow_margin")}
    recorded.update(summary.pop("settings"))
    recorded["offset_value"] = offset
    recorded["input_offset_value"] = input_offset
    summary.update(settings=recorded, version=__version__,
                   data=dict(n_steps=int(data.time.size), dt=data.dt, start=_file_times(data, [0.0])[0],
                             notes=list(data.notes)))

    def write(staging):
        (staging / "identified.json").write_text(json.dumps(summary, indent=2, default=_plain) + "\n")
        _write_fit_figure(staging / "fit.png", found, data, u, y, offset)

    return _write_atomically(settings["out"], write)


def _offset_value(offset, values, path, option):
    if offset == "none":
        return 0.0
    if offset == "first":
        measured = values[~np.isnan(values)]
        if measured.size == 0:
            raise UsageError(f"{path}: {option} first needs a measured value; every one is missing")
        return float(measured[0])
    return float(offset)


def _move_into_place(staging, out):
    """Rename the finished results to ``out``; an old ``out`` is replaced only at the very end."""
    if out.exists():
        retired = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
        os.replace(out, retired / out.name)
        os.replace(staging, out)
        shutil.rmtree(retired)
    else:
        os.replace(staging, out)


def _file_times(data, seconds):
    """Times as the data file wrote them: ISO timestamps, or numbers on the file's own origin."""
    if isinstance(data.start, datetime.datetime):
        return [(data.start + datetime.timedelta(seconds=float(value))).isoformat() for value in seconds]
    return [data.start + float(value) for value in seconds]


def _write_results(directory, result, data, settings, offset, input_offset, narrowed=None):
    names = list(result.names)
    times = _file_times(data, data.time)
    _write_csv(directory / "ic.csv", ["time"] + names, result.ic.T, times)
    limit_columns = [f"{name}_{side}" for name in names for side in ("lower", "upper")]
    _write_csv(directory / "limits.csv", ["time"] + limit_columns,
               result.ci.transpose(1, 0, 2).reshape(data.time.size, -1), times)
    _write_csv(directory / "samples.csv", names, result.samples)
    parameters = result.summary()
    for entry in parameters.values():
        if entry["time_of_max_ic"] is not None:
            # The result's clock starts at the first grid point, data.time[0] after time zero.
            entry["time_of_max_ic"] = _file_times(data, [data.time[0] + entry["time_of_max_ic"]])[0]
    recorded = {key: settings[key] for key in sorted(settings) if key not in ("param", "bounds")}
    recorded["bounds"] = {name: list(pair) for name, pair in settings["bounds"].items()}
    recorded["offset_value"] = offset
    recorded["input_offset_value"] = input_offset
    recorded["n_dropped"] = result.settings["n_dropped"]
    recorded["n_behavioural"] = result.settings["n_behavioural"]
    if narrowed is not None:
        recorded["narrowed"] = narrowed
    summary = dict(parameters=parameters, settings=recorded, version=__version__,
                   data=dict(n_steps=int(data.time.size), dt=data.dt, start=_file_times(data, [0.0])[0],
                             notes=list(data.notes)))
    (directory / "summary.json").write_text(json.dumps(summary, indent=2, default=_plain) + "\n")
    _write_figures(directory, result, data, offset)


def _plain(value):
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")


def _write_csv(path, header, rows, times=None):
    """Numbers in full precision, missing values as empty cells, an optional leading time column."""
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for index, row in enumerate(rows):
            cells = ["" if np.isnan(value) else repr(float(value)) for value in row]
            writer.writerow(cells if times is None else [times[index], *cells])


def _write_figures(directory, result, data, offset):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(9, 5))
    grid_time = data.time - data.time[0]  # the clock of the result's plots
    top.plot(grid_time, data.u, color="tab:blue")
    top.set_ylabel("input")
    bottom.plot(grid_time, data.y, color="tab:orange")
    bottom.set_ylabel("output" + (f" (offset {offset:g} removed in the analysis)" if offset else ""))
    bottom.set_xlabel("time (s from the first grid point)")
    top.set_title("Data analysed")
    fig.savefig(directory / "data.png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    for name in result.names:
        for kind, plot in (("ic", result.plot_information_content), ("identifiability", result.plot_identifiability)):
            fig, ax = plt.subplots(figsize=(9, 3.5))
            plot(name, ax=ax)
            ax.set_xlabel("time (s from the first grid point)")
            fig.savefig(directory / f"{kind}_{name}.png", dpi=110, bbox_inches="tight")
            plt.close(fig)


def _write_fit_figure(path, found, data, u, y, offset):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    grid_time = data.time - data.time[0]
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(9, 5))
    top.plot(grid_time, data.u, color="tab:blue")
    top.set_ylabel("input")
    bottom.plot(grid_time, y, color="tab:orange", label="measured")
    bottom.plot(grid_time, found.fit.simulate(u), color="k", linewidth=1, label="fitted model")
    for number, (start, stop) in enumerate(found.segments):
        for ax in (top, bottom):
            ax.axvspan(grid_time[start], grid_time[stop - 1], color="tab:green", alpha=0.15,
                       label="fitted on" if number == 0 and ax is bottom else None)
    start, stop = found.validation[0]
    bottom.axvspan(grid_time[start], grid_time[-1], color="0.5", alpha=0.15, label="held out")
    estimates = ", ".join(f"{name} = {value:.4g} \u00b1 {found.std_errors[name]:.2g}"
                          for name, value in found.parameters.items())
    top.set_title(f"{found.method}: {estimates}; validation RMSE {found.validation_error:.3g}")
    bottom.set_ylabel("output" + (f" (minus {offset:g})" if offset else ""))
    bottom.set_xlabel("time (s from the first grid point)")
    bottom.legend(loc="best", fontsize=8)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
