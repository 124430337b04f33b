"""The ``dynia`` command line: DYNIA on an engineer's own logged data, without Python.

``dynia analyse DATA.csv --time COL --input COL --output COL --model MODEL
--param NAME=LOW:HIGH ... --out DIR`` loads the data (:mod:`dynia.io.csv`),
runs :func:`dynia.run` and writes tables, a JSON summary and figures to DIR.
``dynia analyse --config run.toml`` takes the same settings from a file.
``dynia identify DATA.csv`` with the same data and model options, and
``--method {dynia,baseline,whole}``, fits the model by least squares on the
data the method selects and validates it on the held-out end of the record
(:mod:`dynia.identification`), writing ``identified.json`` and ``fit.png``.
``dynia suggest DATA.csv`` with the same data and model options proposes a
window, a behavioural share and a number of samples for ``analyse`` and says
why (:mod:`dynia.suggestion`); ``--json`` prints it for machines. ``--window
60s`` (or ``2min``, ``1h``) gives the window in time units instead of ``--n``.
Bad input ends the command with one line on stderr and exit status 2.
"""

import contextlib
import dataclasses
import errno
import importlib.machinery
import importlib.metadata
import importlib.util
import json
import math
import os
import platform
import re
import shlex
import sys
import tomllib
from pathlib import Path

import numpy as np

from .. import __version__, models
from ..engine import kernels
from ..engine.flavours import compiled_engine
from ..engine.windows import OverflowedWindowsWarning
from ..errors import DyniaError, NothingSelected, OutputError, SettingsError
from ..identification import identify
from ..io.csv import load_csv
from ..io.outdir import OutputDirectory
from ..memory import parse_size
from ..models.base import user_code_failed
from ..pipeline import DroppedSamplesWarning, TargetNotReachedWarning, UnreachedOutputWarning, run
from ..progress import stderr_is_terminal
from ..quality import SCREENED_KINDS, check_quality
from ..refine import check_margin, narrowed_bounds
from ..settings import MAX_PARAMETER, AnalysisSettings, check_ic_threshold
from ..suggestion import suggest
from ..summary import verdict_table
from ..timescale import parse_duration, window_half_width
from ..verdicts import assess
from . import report
from .figures import Labels
from .follow import follow
from .parser import OPTIONS, RETIRED, WRITING_OPTIONS, UsageError, retired, setting_options, unwritten

__all__ = ["execute"]

# The most rows dynia follow reads into one transaction: some hundred bytes a row in memory.
_MOST_BATCH_ROWS = 10_000_000

MODELS = {"first-order": models.FirstOrder, "fopdt": models.FOPDT, "second-order-delay": models.SecondOrderDelay}


def execute(args, command_line, caught):
    """Run the parsed command ``args``; returns the exit status (see :func:`dynia.cli.main`).

    ``caught`` collects the warnings of the run, which the command reports itself.
    """
    run_command = {"analyse": _analyse, "identify": _identify, "suggest": _suggest, "follow": follow}[args.command]
    with _named_as_options(args.command):
        return run_command(_options(args), command_line, caught)


@contextlib.contextmanager
def _named_as_options(command):
    """A SettingsError naming a setting (``error.setting``) as one naming the option of ``command`` that gives it.

    Where the message names the setting as a word, the option takes its place (``conf_level is ...`` becomes
    ``--conf-level is ...``); a message that does not is led by the option.
    """
    try:
        yield
    except SettingsError as error:
        option = setting_options(command).get(error.setting) if isinstance(error.setting, str) else None
        if option is None:
            raise
        pieces = str(error).split(error.setting)
        message = pieces[0]
        for piece in pieces[1:]:
            alone = not (message and _joins(message[-1])) and not (piece and _joins(piece[0]))
            message += (option if alone else error.setting) + piece
        raise UsageError(message if message != str(error) else f"{option}: {message}") from None


def _joins(char):
    """Whether ``char`` next to a setting's name makes it part of a longer word (than, --n, 100/percentage)."""
    return char.isalnum() or char in "_-/"


def _options(args):
    """Command-line options over the config file over the defaults, every one checked.

    Every check that needs no model comes first, the output directory's included: a ``--model FILE.py`` is
    imported (running its code, side effects and all) only once the rest of the command is known to be valid.
    """
    command = args.command
    options, set_by_user = _merged_options(args, command)
    options["given"] = set_by_user
    if options.get("max_memory") is not None:
        options["max_memory"] = parse_size(options["max_memory"], "--max-memory")
    if options.get("window") is not None:
        if "n" in set_by_user:
            raise UsageError("--window and --n both set the window; give one of them")
        options["window_seconds"] = parse_duration(options["window"], "--window")
    _check_required(options, command)
    _ranges(options["param"])  # checked before the model runs; against the model below
    # suggest's are the settings of its pilot, and those given are kept in its proposal.
    options["analysis"] = _analysis_settings(options)
    _check_command_options(options)
    options["quality"] = not options["no_quality"]  # screening is on unless --no-quality
    options["offset"] = _offset(options["offset"], "--offset")
    options["input_offset"] = _offset(options["input_offset"], "--input-offset")
    if options.get("seed") is None:
        options["seed"] = int(np.random.SeedSequence().entropy % 2**63)
    # Every file the run reads is an input that --out must not replace: the model's source file too.
    sources = (options.get("data"), options.get("output_file"), options.get("config"), _model_file(options["model"]))
    options["inputs"] = [path for path in sources if path]
    if command in ("analyse", "identify"):
        # Checked now, before the data are read: an --out that could cost the user files is refused at once.
        options["destination"] = OutputDirectory(
            options["out"], overwrite=options["overwrite"], inputs=options["inputs"], command=command
        )
    model = options["model_object"] = _model(options["model"])
    options["input"] = _input_columns(options["input"], model)
    options["bounds"] = _bounds(options["param"], model)
    known = [*model.names, *options["input"], options["output"]]
    options["units"] = _units(options.get("unit") or (), known)
    options["references"] = _references(options.get("reference") or (), known)
    return options


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


def _merged_options(args, command):
    """The command's defaults, then its --config file, then the command line; and the keys the user set."""
    for option, message in RETIRED.items():
        if getattr(args, retired(option), False):
            raise UsageError(message)
    refused = [option for option in WRITING_OPTIONS if getattr(args, unwritten(option), None) is not None]
    if refused:
        raise UsageError(
            f"dynia suggest writes nothing (it prints its proposal), so it takes no {refused[0]}; "
            "give --out to the dynia analyse command it proposes"
        )
    given = {
        key: value
        for key, value in vars(args).items()
        if value is not None
        and key not in ("command", "config")
        and value is not False
        and not key.startswith(("unwritten_", "retired_"))
    }
    options = {key: option.default for key, option in OPTIONS[command].items()}
    options["command"] = command
    configured = {}
    if args.config:
        configured = _read_config(args.config, command)
        options.update(configured)
        options["config"] = args.config
    options.update(given)
    return options, set(given) | set(configured)


# What each command cannot run without (the model's ranges are checked apart).
_REQUIRED = {
    "analyse": ("data", "time", "input", "output", "model", "out"),
    "identify": ("data", "time", "input", "output", "model", "out"),
    "suggest": ("data", "time", "input", "output", "model"),
    "follow": ("url", "table", "time", "input", "output", "model"),
}


def _check_required(options, command):
    """Raise unless the data, its columns, the model, its ranges and (but for suggest) --out are given."""
    for key in _REQUIRED[command]:
        if not options.get(key):
            option = OPTIONS[command][key].flag
            raise UsageError(f"{option} is required (on the command line or in --config)")
    _check_columns(options)
    if not options.get("param"):
        raise UsageError("give a range for every model parameter with --param NAME=LOW:HIGH")


def _check_columns(options):
    """One --output, and --input, --output and --time naming different columns (unless they name tags)."""
    options["output"] = _one_column(options["output"], "--output")
    if isinstance(options["input"], str):
        options["input"] = [options["input"]]
    if options["output"] in options["input"] and not options["long"]:
        raise UsageError(
            f"--input and --output name the same column {options['output']!r}; "
            "the output must be logged apart from the input"
        )
    if not options["long"]:  # in the long layout --input and --output name tags, not columns
        for option, names in (("--input", options["input"]), ("--output", [options["output"]])):
            if options["time"].strip() in (name.strip() for name in names):
                raise UsageError(
                    f"{option} names the time column {options['time'].strip()!r} (--time); expected the column "
                    f"of the {option[2:]}'s values"
                )


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


def _one_column(names, option):
    if isinstance(names, str):
        names = [names]
    if len(names) != 1:
        raise UsageError(f"give one {option}; got {', '.join(map(repr, names))}")
    return names[0]


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


def _analysis_settings(options):
    """The AnalysisSettings of the command's options; the settings check them (and errors name the options)."""
    fields = {
        option.setting: not options[key] if option.negated else options[key]
        for key, option in OPTIONS[options["command"]].items()
        if option.is_setting
    }
    if options.get("window") is not None and "min_points" in fields:
        # With --window the window's length is known only on the data's grid; min_points is checked then (_load).
        fields["min_points"] = 1
    return AnalysisSettings(**fields)


def _check_command_options(options):
    """The options that only the command line has."""
    for key in ("narrow_threshold", "ic_threshold"):
        if key in options:
            check_ic_threshold(options[key])  # the library's own check, now rather than after the analysis
    if "held_out" in options and not 0 < options["held_out"] < 1:
        raise UsageError(f"--held-out must lie in (0, 1); got {options['held_out']:g}")
    _check_options_that_act_together(options)
    if options.get("second_run"):
        check_margin(options["narrow_margin"])  # now, not after the first run
    if options.get("seed") is not None and options["seed"] < 0:
        raise UsageError(f"--seed must be a whole number >= 0; got {options['seed']}")
    _check_follow_options(options)
    if options.get("min_length") is not None:
        if options["method"] != "dynia":
            raise UsageError(
                f"--min-length is the shortest segment DYNIA selects (--method dynia); --method {options['method']} "
                "selects its data otherwise"
            )
        _min_length(options["min_length"], None)  # its form now; in steps once the data's grid is known
    if not (options["max_gap"] > 1 or math.isinf(options["max_gap"])):
        raise UsageError(
            f"--max-gap is a multiple of the grid step above 1 (a gap longer than that many steps is "
            f"left missing); got {options['max_gap']:g}"
        )


# Options that do something only beside another: (option, the other, whether the other must be on, the refusal).
_ACT_TOGETHER = (
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
    ("reference", "no_plots", False, "--reference draws a line on the figures, and --no-plots draws none; drop one"),
)


def _check_options_that_act_together(options):
    """Refuse an option given where it would do nothing, rather than ignore it without a word."""
    for key, other, wanted, refusal in _ACT_TOGETHER:
        if key in options["given"] and other in options and bool(options[other]) != wanted:
            raise UsageError(refusal)


def _check_follow_options(options):
    """dynia follow's own: the poll and judgement intervals, the rows per transaction."""
    for key, low, high, unit in (("poll", 0, 86_400, "seconds"), ("judge_every", 0, 86_400 * 365, "seconds")):
        if key in options and not low < options[key] <= high:
            raise UsageError(f"--{key.replace('_', '-')} must lie in ({low}, {high}] {unit}; got {options[key]:g}")
    if "batch" in options and not 1 <= options["batch"] <= _MOST_BATCH_ROWS:
        raise UsageError(
            f"--batch must be a whole number of rows in [1, {_MOST_BATCH_ROWS}] (a transaction holds them all in "
            f"memory); got {options['batch']}"
        )


def _min_length(value, dt):
    """``--min-length`` in steps: a whole number is steps, a duration (60s, 2min) is rounded onto the grid ``dt``.

    With ``dt`` None only its form is checked (None is returned for a duration).
    """
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


def _in_options(text):
    """``text`` of the library with its names of identify's arguments replaced by the options that give them."""
    for name, option in _IDENTIFY_WORDS:
        text = re.sub(r"(?<![\w-])" + re.escape(name) + (r"(?!\w)" if name[-1].isalnum() else ""), option, text)
    return text


@contextlib.contextmanager
def _identify_errors():
    """An error of :func:`dynia.identify` as one naming the command line's options (:func:`_in_options`)."""
    try:
        yield
    except (NothingSelected, SettingsError) as error:
        kind = NothingSelected if isinstance(error, NothingSelected) else UsageError
        raise kind(_in_options(str(error))) from None


def _read_config(path, command):
    try:
        with open(path, "rb") as handle:
            config = tomllib.load(handle)
    except FileNotFoundError:
        raise UsageError(f"--config {path}: no such file") from None
    except OSError as error:
        raise UsageError(f"--config {path}: cannot be read ({error.strerror})") from None
    except tomllib.TOMLDecodeError as error:
        raise UsageError(f"--config {path}: not valid TOML: {error}") from None
    config = {key.replace("-", "_"): value for key, value in config.items()}
    if "quality" in config and "quality" not in OPTIONS[command]:
        raise UsageError(
            f"--config {path}: quality: the data-quality screening is on by default; write no_quality = true to "
            "turn it off"
        )
    allowed = sorted(OPTIONS[command])
    unknown = sorted(set(config) - set(allowed))
    if unknown:
        raise UsageError(
            f"--config {path}: unknown key(s) for dynia {command}: {', '.join(unknown)}; allowed: {', '.join(allowed)}"
        )
    return {key: _typed(value, OPTIONS[command][key], f"--config {path}: {key}") for key, value in config.items()}


def _typed(value, option, where):
    """A config value of the kind its option takes, one of its choices if it has them, or a one-line error (never
    truthy strings): checked as argparse checks the value on the command line."""
    if option.choices and value not in option.choices:
        raise UsageError(f"{where} must be one of {', '.join(option.choices)}; got {value!r}")
    kind = option.kind
    is_number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind == "flag" and isinstance(value, bool):
        return value
    if kind == "whole" and isinstance(value, int) and not isinstance(value, bool):
        return value
    if kind == "number" and is_number:
        return float(value)
    if kind == "text" and isinstance(value, str):
        return value
    if kind in ("offset", "size") and (isinstance(value, str) or is_number):
        return value
    if kind == "length" and (isinstance(value, str) or (isinstance(value, int) and not isinstance(value, bool))):
        return str(value)
    if kind == "names":
        if isinstance(value, str):
            return [value]
        if isinstance(value, list) and value and all(isinstance(item, str) for item in value):
            return value
    expected = {
        "flag": "true or false (unquoted)",
        "whole": "a whole number",
        "number": "a number",
        "text": "a string",
        "offset": "none, first or a number",
        "size": 'a size such as "4GB" or a number of bytes',
        "names": "a string or a list of strings",
        "length": 'a whole number of steps or a duration such as "60s"',
    }[kind]
    raise UsageError(f"{where} must be {expected}; got {value!r} ({type(value).__name__})")


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


def _bounds(specs, model):
    """``NAME=LOW:HIGH`` strings to an ordered {name: (low, high)}: every model parameter once, each range holding
    only values the model accepts."""
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


def _load(options):
    """The data (u (n_steps,) or (n_steps, n_inputs)), checked against the window, the offsets, and u and y minus them.

    A ``--window`` duration becomes the half window n on the data's grid
    here: ``options["n"]`` and ``options["analysis"]`` are updated.
    """
    loads = [
        load_csv(
            options["data"],
            time=options["time"],
            input=column,
            output=options["output"],
            output_path=options.get("output_file"),
            long_format=options["long"],
            tag_column=options["tag_column"],
            value_column=options["value_column"],
            dt=options.get("dt"),
            max_gap=None if math.isinf(options["max_gap"]) else options["max_gap"],
            duplicates=options["duplicates"],
            time_format=options.get("time_format"),
        )
        for column in options["input"]
    ]
    data = loads[0]
    if len(loads) > 1:
        # One load per input; every load grids the same output, so the grids agree unless the
        # inputs are logged over different spans or at different times.
        for column, other in zip(options["input"][1:], loads[1:]):
            if other.time.shape != data.time.shape or not np.array_equal(other.time, data.time):
                raise UsageError(
                    f"{options['data']}: the input {column!r} gives another time grid than {options['input'][0]!r} "
                    "(logged over another span or at other times); resample the inputs onto one grid first, or "
                    "give --dt"
                )
        data = dataclasses.replace(data, u=np.column_stack([load.u for load in loads]))
    if options.get("window_seconds") is not None:
        options["n"] = window_half_width(options["window_seconds"], data.dt, data.y.size, "--window")
        options["analysis"] = options["analysis"].replace(n=options["n"], min_points=options.get("min_points", 1))
    window = 2 * options.get("n", 0) + 1
    if data.y.size < window:
        raise UsageError(
            f"{options['data']}: {data.y.size} time steps, fewer than one window of "
            f"2n+1 = {window} (--n {options['n']})"
        )
    offset = _offset_value(options["offset"], data.y, options["data"], "--offset")
    input_offset = (
        _offset_value(options["input_offset"], data.u, options["data"], "--input-offset")
        if data.u.ndim == 1
        else np.array(
            [_offset_value(options["input_offset"], column, options["data"], "--input-offset") for column in data.u.T]
        )
    )
    return data, offset, input_offset, data.u - input_offset, data.y - offset


def _offset_value(offset, values, path, option):
    if offset == "none":
        return 0.0
    if offset == "first":
        measured = values[~np.isnan(values)]
        if measured.size == 0:
            raise UsageError(f"{path}: {option} first needs a measured value; every one is missing")
        return float(measured[0])
    return float(offset)


def _data_warnings(data, options, where="see data_quality in summary.json"):
    """Lines for stderr and summary.json: gaps, absurd magnitudes and (unless --no-quality) data-quality findings.

    ``where`` ends the line that counts the findings: where the command puts them. The findings are those of the
    data as the file holds them, before any offset is subtracted, so that their values are the ones measured; the
    run screens the same stretches (the tests do not depend on an offset).
    """
    lines = []
    for start, stop in data.gaps:
        first, last = report.file_times(data, [data.time[start], data.time[stop - 1]])
        lines.append(
            f"no rows in {options['data']} from {first} to {last}: {stop - start} grid points of the "
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
    if options["quality"]:
        for finding in _measured_quality(data).findings:
            start, end = report.file_times(data, [data.time[finding.start], data.time[finding.stop - 1]])
            entry = dict(
                signal=finding.signal,
                column=options["output"] if finding.signal == "y" else options["input"][0],
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


def _measured_quality(data):
    """:func:`~dynia.quality.check_quality` of the data as measured; with several inputs, of the output only."""
    u = data.u if data.u.ndim == 1 else np.zeros(data.y.size)
    return check_quality(data.time, u, data.y)


def _screening_summary(result, findings):
    """summary.json's ``data_quality`` (each finding, and the windows it takes from the evidence) and ``screening``.

    ``findings`` are :func:`_data_warnings`' (finding, entry) pairs; a screened kind's windows are those that use
    its readings (saturated, stuck) or the run's quantised windows of its signal.
    """
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


def _dynia_warnings(caught):
    """The messages of dynia's own warnings among those caught; the rest stay silent."""
    ours = (DroppedSamplesWarning, TargetNotReachedWarning, OverflowedWindowsWarning, UnreachedOutputWarning)
    messages = [str(item.message) for item in caught if issubclass(item.category, ours)]
    caught.clear()
    return messages


def _provenance(options, command_line):
    versions = {"dynia": __version__, "python": platform.python_version()}
    for package in ("numpy", "numba", "scipy", "control", "matplotlib"):
        try:
            versions[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            versions[package] = None
    return dict(
        command_line=command_line,
        versions=versions,
        inputs={str(path): {"sha256": report.sha256(path)} for path in options["inputs"]},
    )


def _recorded(options, analysis, offset, input_offset):
    """Exactly the options of this command as used, and the analysis settings."""
    command_keys = [key for key in OPTIONS[options["command"]] if key in options]
    recorded = {key: options[key] for key in command_keys if key not in ("param", "unit", "reference")}
    if len(recorded["input"]) == 1:
        recorded["input"] = recorded["input"][0]
    recorded.update(
        bounds={name: list(pair) for name, pair in options["bounds"].items()},
        offset_value=offset,
        input_offset_value=input_offset,
        analysis=analysis.to_dict(),
        units=options["units"],
        references={name: dict(value=value, label=label) for name, (value, label) in options["references"].items()},
    )
    return recorded


def _analyse(options, command_line, caught):
    model = options["model_object"]
    with options["destination"] as staging, _written_into(options["out"], staging):
        data, offset, input_offset, u, y = _load(options)
        analysis = options["analysis"].replace(dt=data.dt)
        notices, quality_findings = _data_warnings(data, options)
        for line in notices:
            print(f"dynia: warning: {line}", file=sys.stderr)

        def analyse(bounds, directory, narrowed=None):
            # --on-disk: the run writes result.nc itself, block by block, and the result reads it lazily.
            settings = analysis.replace(store=directory / "result.nc") if options["on_disk"] else analysis
            _announce_compilation(options, settings)
            result = run(u, y, model, bounds, settings=settings, rng=options["seed"], progress=_shows_progress(options))
            dropped = _dynia_warnings(caught)
            for line in dropped:
                print(f"dynia: warning: {line}", file=sys.stderr)
            # The reasons name times as the file wrote them, as the table does.
            result = dataclasses.replace(
                result, verdicts=assess(result, clock=lambda step: report.file_times(data, [data.time[step]])[0])
            )
            parameters = result.summary()
            for entry in parameters.values():
                # The result's clock starts at the first grid point, data.time[0] after time zero.
                for key in ("time_of_max_ic", "time_of_highest_ic"):
                    if entry.get(key) is not None:
                        entry[key] = report.file_times(data, [data.time[0] + entry[key]])[0]
                if entry["high_ic_span"][0] is not None:
                    entry["high_ic_span"] = report.file_times(data, data.time[0] + np.array(entry["high_ic_span"]))
            settings = dict(
                _recorded(options, analysis, offset, input_offset),
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
                warnings=notices + dropped,
                data=dict(
                    n_steps=int(data.time.size),
                    dt=data.dt,
                    start=report.file_times(data, [0.0])[0],
                    notes=list(data.notes),
                    gaps=[report.file_times(data, [data.time[a], data.time[b - 1]]) for a, b in data.gaps],
                ),
                **_provenance(options, command_line),
            )
            if options["quality"]:
                summary["data_quality"], summary["screening"] = _screening_summary(result, quality_findings)
            report.write_analysis(
                directory,
                result,
                data,
                summary,
                offset=offset,
                input_offset=input_offset,
                plots=not options["no_plots"],
                saved=options["on_disk"],
                labels=_labels(options),
            )
            table = verdict_table(parameters)
            table += "".join("\n" + line for line in report.screening_lines(summary))
            if summary["noise_floor"] is not None:
                table += "\n" + report.noise_floor_line(summary["noise_floor"])
            return result, parameters, table

        result, parameters, table = analyse(options["bounds"], staging)
        tables = [table]
        if options["second_run"]:
            bounds, narrowed = narrowed_bounds(
                result, options["bounds"], ic_threshold=options["narrow_threshold"], margin=options["narrow_margin"]
            )
            (staging / "second_run").mkdir()
            _, _, second = analyse(bounds, staging / "second_run", narrowed=narrowed)
            tables.append("second run (narrowed: " + (", ".join(narrowed) or "none") + ")\n" + second)
    print("\n\n".join(tables))
    return _done(options)


# Errors of a write that failed for want of room or of a working disk, when the error names no file.
_WRITE_ERRORS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO, errno.EROFS})


@contextlib.contextmanager
def _written_into(out, staging):
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


def _labels(options):
    """What the figures call the columns, with the units and references of the command line."""
    return Labels(
        inputs=tuple(options["input"]),
        output=options["output"],
        units=options["units"],
        references=options["references"],
    )


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


def _identify(options, command_line, caught):
    with options["destination"] as staging, _written_into(options["out"], staging):
        data, offset, input_offset, u, y = _load(options)
        analysis = options["analysis"].replace(dt=data.dt)
        notices, _ = _data_warnings(data, dict(options, quality=False))
        for line in notices:
            print(f"dynia: warning: {line}", file=sys.stderr)
        if options["method"] == "dynia":
            _announce_compilation(options, analysis)
        if options.get("min_length") is not None:
            options["min_length"] = _min_length(options["min_length"], data.dt)
        with _identify_errors():
            found = _identified(options, u, y, analysis)
        # Its warnings are the command line's: the terminal, identified.json and fit.png name options.
        found = dataclasses.replace(
            found,
            warnings=[_in_options(line) for line in found.warnings],
            little_data=found.little_data and _in_options(found.little_data),
        )
        dropped = _dynia_warnings(caught)
        for line in dropped + found.warnings:
            print(f"dynia: warning: {line}", file=sys.stderr)
        summary = found.to_dict(data.time)

        def file_time(index):
            return report.file_times(data, [data.time[index]])[0]

        for key, pairs in (("segments", found.segments), ("validation_segments", found.validation)):
            summary[key] = [[file_time(start), file_time(stop - 1)] for start, stop in pairs]
        # identify checked the record it fits, offsets subtracted: the values and reasons as measured instead.
        measured = {(f.signal, f.kind, f.start, f.stop): f for f in _measured_quality(data).findings}
        for finding, entry in zip(found.quality.findings if found.quality else (), summary.get("data_quality", [])):
            entry.update(start_time=file_time(finding.start), end_time=file_time(finding.stop - 1))
            same = measured.get((finding.signal, finding.kind, finding.start, finding.stop))
            if same is not None:
                entry.update(value=same.value, reason=same.reason)
        recorded = _recorded(options, analysis, offset, input_offset)
        # identify's own record adds what the command line does not set (held_out_steps, min_length, ...);
        # the analysis settings are already under "analysis".
        analysis_fields = set(analysis.to_dict())
        recorded.update(
            {
                key: value
                for key, value in summary.pop("settings").items()
                if key not in recorded and key not in analysis_fields
            }
        )
        summary.update(
            settings=recorded,
            version=__version__,
            warnings=notices + dropped + summary["warnings"],
            data=dict(
                n_steps=int(data.time.size), dt=data.dt, start=report.file_times(data, [0.0])[0], notes=list(data.notes)
            ),
            **_provenance(options, command_line),
        )
        report.write_identification(
            staging, found, data, u, y, summary, offset=offset, plots=not options["no_plots"], labels=_labels(options)
        )
    print(
        report.identification_table(
            summary,
            fitted_steps=sum(stop - start for start, stop in found.segments),
            held_out_steps=sum(stop - start for start, stop in found.validation),
        )
    )
    return _done(options)


def _identified(options, u, y, analysis):
    """:func:`dynia.identify` with the command's options."""
    return identify(
        u,
        y,
        options["model_object"],
        options["bounds"],
        method=options["method"],
        settings=analysis,
        held_out=options["held_out"],
        ic_threshold=options["ic_threshold"],
        mode=options["mode"],
        min_length=options.get("min_length"),
        # identify checks one input; with several, the run still screens the output.
        quality=options["quality"] and options["model_object"].n_inputs == 1,
        exclude_flagged=options["exclude_flagged"],
        n_starts=options["starts"],
        rng=options["seed"],
        progress=_shows_progress(options),
    )


def _suggest(options, command_line, caught):
    data, offset, input_offset, u, y = _load(options)
    # suggest writes no summary.json: the findings go with the proposal, as JSON or one warning line each.
    where = "see data_quality in the JSON output" if options["json"] else "listed in the warnings below"
    notices, pairs = _data_warnings(data, options, where)
    findings = [entry for _, entry in pairs]
    if not options["json"]:
        notices += [
            f"data quality: {entry['signal']} {entry['kind']} from {entry['start_time']} to {entry['end_time']}: "
            f"{entry['reason']}"
            for entry in findings
        ]
    _announce_compilation(options, options["analysis"])
    given = options["given"]
    found = suggest(
        u,
        y,
        options["model_object"],
        options["bounds"],
        dt=data.dt,
        x0=options["x0"],
        # Kept as given (a --window is n on the data's grid by now, _load); the rest is proposed around them.
        n=options["n"] if {"n", "window"} & given else None,
        percentage=options["percentage"] if "percentage" in given else None,
        n_samples=options["samples"] if "samples" in given else None,
        settings=options["analysis"],
        max_samples=options["max_samples"],
        max_memory=options["max_memory"],
        progress=_shows_progress(options),
        rng=options["seed"],
    )
    # Printed once there is a proposal: a record that gets none ends in its one error line, which says why.
    dropped = _dynia_warnings(caught)
    for line in notices + dropped:
        print(f"dynia: warning: {line}", file=sys.stderr)
    # The analyse command this proposal is for: every analyse option as the user gave it, and the settings proposed
    # (the proposal leaves out those given). suggest's own options (its seed is given anew) are not analyse's.
    own = ("--seed", "--max-samples", "--max-memory")
    kept, words = [], iter(command_line[2:])
    for word in words:
        if word in own:
            next(words, None)
        elif word != "--json" and not word.startswith(tuple(option + "=" for option in own)):
            kept.append(word)
    analyse = ["dynia", "analyse", *kept, *found.arguments(), "--seed", str(options["seed"]), "--out", "RESULTS"]
    if options["json"]:
        print(
            json.dumps(
                dict(
                    found.to_dict(),
                    seed=options["seed"],
                    command=analyse,
                    warnings=notices + dropped,
                    **({"data_quality": findings} if options["quality"] else {}),
                    version=__version__,
                    command_line=command_line,
                ),
                indent=2,
                allow_nan=False,
            )
        )
    else:
        print(found.text())
        print("run:\n  " + shlex.join(analyse))
    return 0


def _done(options):
    if _shows_progress(options):
        print(f"dynia: wrote {options['out']}", file=sys.stderr)
    return 0


def _shows_progress(options):
    """Whether the command shows its progress: bars, the compilation notice and the "wrote DIR" line, on stderr.

    Only on a terminal, so that the stderr of a script or a pipeline holds nothing but warnings and errors; --quiet
    silences it there too. Progress never goes to stdout, which holds the results (suggest --json's JSON).
    """
    return stderr_is_terminal() and not options["quiet"]


def _announce_compilation(options, settings):
    """Say so before a run that may compile the numba kernels: the first of a process, on the compiled engine.

    numba alone finds out whether its on-disk cache holds them (a second or so) or they compile (20-30 s of one core
    here, once after dynia or numba changes), hence "unless cached".
    """
    if _shows_progress(options) and not kernels.compiled() and compiled_engine(settings.engine, settings.flavour):
        print(
            "dynia: compiling the analysis kernels unless numba cached them "
            "(once after installing or upgrading dynia: 20-30 s)...",
            file=sys.stderr,
        )


# Values beyond this are no measurement of a process: a logger's overflow or
# fill value (1e308, 9.9e37). Reported on every run; the data-quality findings list them (unless --no-quality).
_ABSURD = 1e12
