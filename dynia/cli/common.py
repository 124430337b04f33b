"""What the commands of ``dynia`` do alike once they run: check their options, load the record, report.

:func:`checked_options` turns argparse's Namespace into a command's typed options object, every check that needs no
model first, the output directory's included: a ``--model FILE.py`` is imported (running its code, side effects and
all) only once the rest of the command is known to be valid. :func:`load` reads the record onto its grid;
:func:`data_warnings`, :func:`provenance` and :func:`recorded` make what the commands print and write about it;
:func:`written_into` names ``--out`` in a failed write. This module loads the library, so the ``dynia`` command
imports it only once a command is to run.
"""

import contextlib
import dataclasses
import errno
import importlib.machinery
import importlib.metadata
import importlib.util
import math
import os
import platform
import sys
from pathlib import Path

import numpy as np

from .. import __version__, models
from ..engine import kernels
from ..engine.flavours import takes_kernels
from ..engine.windows import OverflowedWindowsWarning
from ..errors import DyniaError, OutputError, SettingsError
from ..io.csv import ProcessData, load_csv
from ..io.outdir import OutputDirectory
from ..memory import parse_size
from ..models.base import user_code_failed
from ..pipeline import DroppedSamplesWarning, TargetNotReachedWarning, UnreachedOutputWarning
from ..quality import check_quality
from ..settings import MAX_PARAMETER, AnalysisSettings
from ..timescale import parse_duration, window_half_width
from . import report
from .figures import Labels
from .options import UsageError, merged

__all__ = [
    "MODELS",
    "Record",
    "announce_compilation",
    "bounds",
    "checked_options",
    "data_warnings",
    "done",
    "dynia_warnings",
    "labels",
    "load",
    "measured_quality",
    "provenance",
    "recorded",
    "written_into",
]

MODELS = {"first-order": models.FirstOrder, "fopdt": models.FOPDT, "second-order-delay": models.SecondOrderDelay}


def checked_options(command, args, command_line):
    """The options of ``command`` in ``args`` (argparse's Namespace) over its --config file over the defaults, every
    one checked: the command's options object.

    ``command`` is the module of the command (:mod:`dynia.cli.analyse`, ...): its ``OPTIONS`` ({key:
    :class:`~dynia.cli.options.Option`}), its own ``check`` of them and its ``Options`` class.
    """
    values = merged(args, command.OPTIONS)
    values.command_line = command_line
    for key, option in command.OPTIONS.items():
        if option.kind == "size" and getattr(values, key) is not None:
            setattr(values, key, parse_size(getattr(values, key), option.flag))
    values.window_seconds = None
    if values.window is not None:
        if "n" in values.given:
            raise UsageError("--window and --n both set the window; give one of them")
        values.window_seconds = parse_duration(values.window, "--window")
    _check_required(values, command.OPTIONS)
    _ranges(values.param)  # checked before the model runs; against the model below
    # suggest's are the settings of its pilot, and those given are kept in its proposal.
    values.analysis = _analysis_settings(values, command.OPTIONS)
    command.check(values)
    values.quality = not values.no_quality  # screening is on unless --no-quality
    values.offset = _offset(values.offset, "--offset")
    values.input_offset = _offset(values.input_offset, "--input-offset")
    if values.seed is None:
        values.seed = int(np.random.SeedSequence().entropy % 2**63)
    # Every file the run reads is an input that --out must not replace: the model's source file too.
    files = [getattr(values, key) for key in ("data", "output_file") if key in command.OPTIONS]
    values.inputs = [path for path in (*files, values.config, _model_file(values.model)) if path]
    writes = "out" in command.OPTIONS
    if writes:
        # Checked now, before the data are read: an --out that could cost the user files is refused at once.
        values.destination = OutputDirectory(
            values.out, overwrite=values.overwrite, inputs=values.inputs, command=values.command
        )
    model = values.model_object = _model(values.model)
    values.input = _input_columns(values.input, model)
    values.bounds = bounds(values.param, model)
    if writes:
        known = [*model.names, *values.input, values.output]
        values.units = _units(values.unit or (), known)
        values.references = _references(values.reference or (), known)
    return command.Options(**vars(values))


def _check_required(values, options):
    """Raise unless every required option (the data, its columns, the model, --out) and the ranges are given."""
    for key, option in options.items():
        if option.required and not getattr(values, key):
            raise UsageError(f"{option.flag} is required (on the command line or in --config)")
    _check_columns(values)
    if not values.param:
        raise UsageError("give a range for every model parameter with --param NAME=LOW:HIGH")


def _check_columns(values):
    """One --output, and --input, --output and --time naming different columns (unless they name tags)."""
    values.output = _one_column(values.output, "--output")
    if isinstance(values.input, str):
        values.input = [values.input]
    if values.output in values.input and not values.long:
        raise UsageError(
            f"--input and --output name the same column {values.output!r}; "
            "the output must be logged apart from the input"
        )
    if not values.long:  # in the long layout --input and --output name tags, not columns
        for option, names in (("--input", values.input), ("--output", [values.output])):
            if values.time.strip() in (name.strip() for name in names):
                raise UsageError(
                    f"{option} names the time column {values.time.strip()!r} (--time); expected the column "
                    f"of the {option[2:]}'s values"
                )


def _one_column(names, option):
    if isinstance(names, str):
        names = [names]
    if len(names) != 1:
        raise UsageError(f"give one {option}; got {', '.join(map(repr, names))}")
    return names[0]


def _analysis_settings(values, options):
    """The AnalysisSettings of the command's options; the settings check them (and errors name the options)."""
    fields = {
        option.setting: not getattr(values, key) if option.negated else getattr(values, key)
        for key, option in options.items()
        if option.is_setting
    }
    if values.window is not None and "min_points" in fields:
        # With --window the window's length is known only on the data's grid; min_points is checked then (load).
        fields["min_points"] = 1
    return AnalysisSettings(**fields)


def _model_file(spec):
    """The source file of a ``--model`` of the user's, found without running it; None for a built-in."""
    where, colon, _ = str(spec).rpartition(":")
    if spec in MODELS or not colon or not where:
        return None
    if where.endswith(".py") or os.sep in where:
        return where if os.path.isfile(where) else None
    # As _import_model_module finds it (the working directory first), but without importing any package on the way.
    locations = [os.getcwd(), *sys.path]
    found = None
    for part in where.split("."):
        try:
            found = importlib.machinery.PathFinder.find_spec(part, locations)
        except (ImportError, ValueError):
            return None
        if found is None:
            return None
        locations = list(found.submodule_search_locations or [])
    return found.origin if found.has_location else None


def _input_columns(names, model):
    """The input columns in the model's input order: as many as the model has inputs, each once."""
    if isinstance(names, str):
        names = [names]
    if len(names) != model.n_inputs:
        raise UsageError(
            f"--input is given {len(names)} time(s) ({', '.join(map(repr, names))}) but the model {model!r} takes "
            f"{model.n_inputs} input(s); give one --input per model input, in the model's order"
        )
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise UsageError(f"--input names {', '.join(map(repr, repeated))} more than once")
    return list(names)


def _model(spec):
    """A built-in model by name, or MODULE:NAME / FILE.py:NAME naming a Model or a function returning one."""
    if spec in MODELS:
        return MODELS[spec]()
    where, colon, attribute = str(spec).rpartition(":")
    if not colon or not where or not attribute:
        raise UsageError(
            f"--model must be one of {', '.join(sorted(MODELS))}, or MODULE:NAME or FILE.py:NAME for your own; "
            f"got {spec!r}"
        )
    module = _import_model_module(where, spec)
    try:
        found = getattr(module, attribute)
    except AttributeError:
        raise UsageError(f"--model {spec}: {where} has no {attribute!r}") from None
    if not isinstance(found, models.Model):
        if not callable(found):
            raise UsageError(f"--model {spec}: {attribute} is a {type(found).__name__}, not a dynia.models.Model")
        try:
            found = found()
        except BaseException as error:
            raise UsageError(f"--model {spec}: {user_code_failed(f'calling {attribute}()', error)}") from None
        if not isinstance(found, models.Model):
            raise UsageError(
                f"--model {spec}: {attribute}() returned a {type(found).__name__}, not a dynia.models.Model"
            )
    return found


def _import_model_module(where, spec):
    """Import a module by dotted name (from the working directory too) or a .py file by path."""
    try:
        if where.endswith(".py") or os.sep in where:
            path = Path(where)
            if not path.is_file():
                raise UsageError(f"--model {spec}: {where}: no such file")
            module_spec = importlib.util.spec_from_file_location(f"dynia_user_model_{path.stem}", path)
            module = importlib.util.module_from_spec(module_spec)
            module_spec.loader.exec_module(module)
            return module
        # The dynia script does not put the working directory on the path; a user's module usually lives there.
        sys.path.insert(0, os.getcwd())
        try:
            return importlib.import_module(where)
        finally:
            sys.path.remove(os.getcwd())
    except DyniaError:
        raise
    except ImportError as error:
        raise UsageError(f"--model {spec}: cannot import {where}: {error}") from None
    except BaseException as error:
        raise UsageError(f"--model {spec}: {user_code_failed(f'importing {where}', error)}") from None


def _ranges(specs):
    """``NAME=LOW:HIGH`` strings to an ordered {name: (low, high)} of finite ranges, before the model is known."""
    ranges = {}
    for spec in specs:
        name, _, interval = str(spec).partition("=")
        low, _, high = interval.partition(":")
        try:
            low, high = float(low), float(high)
        except ValueError:
            raise UsageError(f"--param {spec!r}: expected NAME=LOW:HIGH with numbers, e.g. K=0:7") from None
        name = name.strip()
        if name in ranges:
            raise UsageError(f"--param {name} is given twice")
        if not (math.isfinite(low) and math.isfinite(high)):
            raise UsageError(f"--param {spec}: expected finite bounds, a range to sample from; got {low:g} to {high:g}")
        if not low < high:
            raise UsageError(f"--param {name}: the lower bound {low:g} must be below the upper bound {high:g}")
        if max(abs(low), abs(high)) > MAX_PARAMETER:
            raise UsageError(
                f"--param {name}: the range reaches beyond {MAX_PARAMETER:g}, where the arithmetic "
                "overflows; give the range in the units of the data"
            )
        ranges[name] = (low, high)
    return ranges


def bounds(specs, model):
    """``NAME=LOW:HIGH`` strings to an ordered {name: (low, high)}: every model parameter once, each range holding
    only values the model accepts.

    >>> bounds(["T=0:200", "K=0:40"], models.FirstOrder())
    {'T': (0.0, 200.0), 'K': (0.0, 40.0)}
    """
    ranges = _ranges(specs)
    for name in ranges:
        if name not in model.names:
            raise UsageError(f"--param {name}: {type(model).__name__} has parameters {', '.join(model.names)}")
    missing = [name for name in model.names if name not in ranges]
    if missing:
        raise UsageError(
            f"no --param for {', '.join(missing)} ({type(model).__name__} has parameters {', '.join(model.names)})"
        )
    _admissible(model, ranges)
    return ranges


def _admissible(model, ranges):
    """The model's own check of the ranges (:meth:`~dynia.models.Model.check_ranges`), naming the --param."""
    try:
        model.check_ranges(ranges)
    except SettingsError as error:
        low, high = ranges[error.setting]
        raise UsageError(f"--param {error.setting}={low:g}:{high:g}: {error}") from None


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


def _named(option, spec, known):
    """``NAME=REST`` of a repeatable option, NAME a parameter or column of this run; (name, rest)."""
    name, equals, rest = str(spec).partition("=")
    name, rest = name.strip(), rest.strip()
    if not equals or not name or not rest:
        expected = "UNIT" if option == "--unit" else "VALUE[:LABEL]"
        raise UsageError(f"{option} {spec!r}: expected NAME={expected}")
    if name not in known:
        raise UsageError(f"{option} {name}: not a parameter or column of this run; expected one of {', '.join(known)}")
    return name, rest


def _units(specs, known):
    """``NAME=UNIT`` strings to {name: unit}, each name a parameter or column of the run, once."""
    units = {}
    for spec in specs:
        name, unit = _named("--unit", spec, known)
        if name in units:
            raise UsageError(f"--unit {name} is given twice")
        units[name] = unit
    return units


def _references(specs, known):
    """``NAME=VALUE[:LABEL]`` strings to {name: (value, label)}; the label is "reference" unless given."""
    references = {}
    for spec in specs:
        name, rest = _named("--reference", spec, known)
        number, _, label = rest.partition(":")
        try:
            value = float(number)
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise UsageError(f"--reference {spec!r}: expected NAME=VALUE[:LABEL] with a finite number, e.g. K=18.5")
        if name in references:
            raise UsageError(f"--reference {name} is given twice")
        references[name] = (value, label.strip() or "reference")
    return references


@dataclasses.dataclass(frozen=True)
class Record:
    """The logged data as a command analyses it.

    Attributes
    ----------
    data : dynia.io.csv.ProcessData
        The record as read, on its grid.
    offset : float
        The output offset subtracted (``--offset``).
    input_offset : float or numpy.ndarray
        The input offset subtracted (``--input-offset``), one per input.
    u, y : numpy.ndarray
        The input(s) and the output, their offsets subtracted.
    """

    data: ProcessData
    offset: float
    input_offset: float | np.ndarray
    u: np.ndarray
    y: np.ndarray


def load(options):
    """The record of the options' file(s), checked against the window and the offsets; (options, :class:`Record`).

    A ``--window`` duration becomes the half window n on the data's grid here: the options returned hold it
    (:meth:`~dynia.cli.options.CommandOptions.on_grid`).
    """
    loads = [
        load_csv(
            options.data,
            time=options.time,
            input=column,
            output=options.output,
            output_path=options.output_file,
            long_format=options.long,
            tag_column=options.tag_column,
            value_column=options.value_column,
            dt=options.dt,
            max_gap=None if math.isinf(options.max_gap) else options.max_gap,
            duplicates=options.duplicates,
            time_format=options.time_format,
        )
        for column in options.input
    ]
    data = loads[0]
    if len(loads) > 1:
        # One load per input; every load grids the same output, so the grids agree unless the
        # inputs are logged over different spans or at different times.
        for column, other in zip(options.input[1:], loads[1:]):
            if other.time.shape != data.time.shape or not np.array_equal(other.time, data.time):
                raise UsageError(
                    f"{options.data}: the input {column!r} gives another time grid than {options.input[0]!r} "
                    "(logged over another span or at other times); resample the inputs onto one grid first, or "
                    "give --dt"
                )
        data = dataclasses.replace(data, u=np.column_stack([load.u for load in loads]))
    if options.window_seconds is not None:
        options = options.on_grid(window_half_width(options.window_seconds, data.dt, data.y.size, "--window"))
    window = 2 * options.n + 1
    if data.y.size < window:
        raise UsageError(
            f"{options.data}: {data.y.size} time steps, fewer than one window of 2n+1 = {window} (--n {options.n})"
        )
    offset = _offset_value(options.offset, data.y, options.data, "--offset")
    input_offset = (
        _offset_value(options.input_offset, data.u, options.data, "--input-offset")
        if data.u.ndim == 1
        else np.array(
            [_offset_value(options.input_offset, column, options.data, "--input-offset") for column in data.u.T]
        )
    )
    return options, Record(data, offset, input_offset, data.u - input_offset, data.y - offset)


def _offset_value(offset, values, path, option):
    if offset == "none":
        return 0.0
    if offset == "first":
        measured = values[~np.isnan(values)]
        if measured.size == 0:
            raise UsageError(f"{path}: {option} first needs a measured value; every one is missing")
        return float(measured[0])
    return float(offset)


# Values beyond this are no measurement of a process: a logger's overflow or
# fill value (1e308, 9.9e37). Reported on every run; the data-quality findings list them (unless --no-quality).
_ABSURD = 1e12


def data_warnings(data, options, *, quality, where="see data_quality in summary.json"):
    """Lines for stderr and summary.json: gaps, absurd magnitudes and (with ``quality``) data-quality findings;
    (lines, [(finding, its entry)]).

    ``where`` ends the line that counts the findings: where the command puts them. The findings are those of the
    data as the file holds them, before any offset is subtracted, so that their values are the ones measured; the
    run screens the same stretches (the tests do not depend on an offset).
    """
    lines = []
    for start, stop in data.gaps:
        first, last = report.file_times(data, [data.time[start], data.time[stop - 1]])
        lines.append(
            f"no rows in {options.data} from {first} to {last}: {stop - start} grid points of the "
            "output left missing (raise --max-gap to interpolate across)"
        )
    for name, values in (("input", data.u), ("output", data.y)):
        with np.errstate(invalid="ignore"):
            huge = np.flatnonzero(np.abs(values) > _ABSURD)
        if huge.size:
            lines.append(
                f"the {name} holds {huge.size} value(s) beyond {_ABSURD:g} in magnitude, the first "
                f"{values[huge[0]]:g} at time {report.file_times(data, [data.time[huge[0]]])[0]}; "
                "check the data (the data-quality findings list them)"
            )
    findings = []
    if quality:
        for finding in measured_quality(data).findings:
            start, end = report.file_times(data, [data.time[finding.start], data.time[finding.stop - 1]])
            entry = dict(
                signal=finding.signal,
                column=options.output if finding.signal == "y" else options.input[0],
                kind=finding.kind,
                start_time=start,
                end_time=end,
                value=finding.value,
                reason=finding.reason,
            )
            if finding.kind == "saturated":
                values = data.y if finding.signal == "y" else data.u
                entry["limit"] = "maximum" if finding.value >= np.nanmax(values) else "minimum"
            findings.append((finding, entry))
        if findings:
            kinds = sorted({entry["kind"] for _, entry in findings})
            lines.append(f"data quality: {len(findings)} finding(s) ({', '.join(kinds)}); {where}")
    return lines, findings


def measured_quality(data):
    """:func:`~dynia.quality.check_quality` of the data as measured; with several inputs, of the output only."""
    u = data.u if data.u.ndim == 1 else np.zeros(data.y.size)
    return check_quality(data.time, u, data.y)


def dynia_warnings(caught):
    """The messages of dynia's own warnings among those ``caught``; the rest stay silent."""
    ours = (DroppedSamplesWarning, TargetNotReachedWarning, OverflowedWindowsWarning, UnreachedOutputWarning)
    messages = [str(item.message) for item in caught if issubclass(item.category, ours)]
    caught.clear()
    return messages


def provenance(options):
    """What summary.json says of where its results come from: the command line, the versions, the inputs' hashes."""
    versions = {"dynia": __version__, "python": platform.python_version()}
    for package in ("numpy", "numba", "scipy", "control", "matplotlib"):
        try:
            versions[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            versions[package] = None
    return dict(
        command_line=options.command_line,
        versions=versions,
        inputs={str(path): {"sha256": report.sha256(path)} for path in options.inputs},
    )


def recorded(options, command_options, analysis, record):
    """Exactly the options of this command as used (``command_options``, {key: Option}), and the analysis
    settings."""
    recorded = {key: getattr(options, key) for key in command_options if key not in ("param", "unit", "reference")}
    if len(recorded["input"]) == 1:
        recorded["input"] = recorded["input"][0]
    recorded.update(
        bounds={name: list(pair) for name, pair in options.bounds.items()},
        offset_value=record.offset,
        input_offset_value=record.input_offset,
        analysis=analysis.to_dict(),
        units=options.units,
        references={name: dict(value=value, label=label) for name, (value, label) in options.references.items()},
    )
    return recorded


def labels(options):
    """What the figures call the columns, with the units and references of the command line."""
    return Labels(
        inputs=tuple(options.input),
        output=options.output,
        units=options.units,
        references=options.references,
    )


# Errors of a write that failed for want of room or of a working disk, when the error names no file.
_WRITE_ERRORS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO, errno.EROFS})


@contextlib.contextmanager
def written_into(out, staging):
    """A failed write into ``staging`` as one error naming --out; the caller's OutputDirectory then removes it.

    The result file's own error (:class:`~dynia.errors.OutputError` naming its path in ``staging``) and an
    :class:`OSError` of a table or figure written there (naming its file, or a full disk naming none).
    """
    folder = str(staging) + os.sep
    try:
        yield
    except OutputError as error:
        if folder not in str(error):
            raise
        raise OutputError(f"--out {out}: cannot write the results: {str(error).replace(folder, '')}") from None
    except OSError as error:
        name = None if error.filename is None else os.path.abspath(os.fspath(error.filename))
        if not (name.startswith(folder) if name is not None else error.errno in _WRITE_ERRORS):
            raise
        where = "" if name is None else f"{name[len(folder) :]}: "
        raise OutputError(f"--out {out}: cannot write the results: {where}{error.strerror or error}") from None


def done(options):
    """The exit status of a command that wrote ``--out``, said on a terminal."""
    if options.shows_progress:
        print(f"dynia: wrote {options.out}", file=sys.stderr)
    return 0


def announce_compilation(options, settings, n_samples, n_steps):
    """Say so before a run that may compile the numba kernels: the first of a process, on the compiled engine.

    A run of at most ``n_samples`` sets over ``n_steps`` steps that "auto" gives to the kernels' numpy twin compiles
    nothing, and nothing is said (:func:`dynia.engine.flavours.takes_kernels`).

    numba alone finds out whether its on-disk cache holds them (a second or so) or they compile (15 s of one core on
    an Intel Xeon, 20-30 s on an AMD EPYC, once after dynia or numba changes), hence "unless cached".
    """
    if (
        options.shows_progress
        and takes_kernels(settings, n_samples, n_steps, options.model_object)
        and not kernels.compiled()
    ):
        print(
            "dynia: compiling the analysis kernels unless numba cached them "
            "(once after installing or upgrading dynia: 15-30 s)...",
            file=sys.stderr,
        )
