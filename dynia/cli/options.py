"""The options every command of ``dynia`` shares, and how a command's options become one typed object.

An option of the command line is an :class:`Option`: its ``--config`` key, its kind of value, its help, its default
and, where it gives one, the setting of the library it gives (for error messages that name that setting). The
analysis settings (``--samples``, ``--conf-level``, ...) are not restated here: :func:`setting_option` makes their
options from the metadata of :class:`~dynia.settings.AnalysisSettings`' fields (help, option name, metavar,
choices), their type is the field's annotation and their default the field's own, which the help shows.

A command (:mod:`~dynia.cli.analyse`, :mod:`~dynia.cli.identify`, :mod:`~dynia.cli.suggest`,
:mod:`~dynia.cli.follow`) lists its options in :class:`Group` s, in the order of its ``--help``, and adds itself to
the parser with :func:`add_command`. :func:`merged` puts argparse's Namespace, the ``--config`` file and the defaults
together; once checked (:func:`dynia.cli.common.checked_options`), they are one frozen dataclass of the command,
made from :class:`CommandOptions` and its kin, whose fields the command's run reads. This module loads nothing of
the analysis, so ``dynia --help`` answers at once.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import math
import tomllib
import types
import typing

from .. import __version__
from ..errors import SettingsError
from ..progress import stderr_is_terminal
from ..settings import SAMPLERS, AnalysisSettings

if typing.TYPE_CHECKING:
    from ..io.outdir import OutputDirectory
    from ..models import Model

__all__ = [
    "CONFIG",
    "CommandOptions",
    "DATA",
    "FileOptions",
    "Group",
    "MODEL",
    "OUTPUT",
    "Option",
    "QUIET",
    "REFERENCE_NEEDS_PLOTS",
    "RETIRED",
    "SEED",
    "SamplingOptions",
    "UsageError",
    "WINDOW_HELP",
    "WritingOptions",
    "add_command",
    "attached",
    "by_key",
    "check_max_gap",
    "check_seed",
    "merged",
    "named_as_options",
    "parser",
    "read_config",
    "refuse_idle",
    "setting_option",
]


class UsageError(SettingsError):
    """A mistake in the command's options, reported as one line with exit status 2."""


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage mistake is one line on stderr (no usage dump), exit status 2, and no abbreviations.

    argparse would read ``--n 15`` given to a command without ``--n`` as an abbreviation of whichever option it
    begins (``--no-plots``), and its error would then name an option the user never typed; every parser of the
    command, the commands' own included (argparse makes them of this class), takes options only as spelled.
    """

    def __init__(self, *args, **kwargs):
        kwargs["allow_abbrev"] = False
        super().__init__(*args, **kwargs)

    def error(self, message):
        raise UsageError(message)


@dataclasses.dataclass(frozen=True)
class Option:
    """One option of the command line.

    Attributes
    ----------
    key : str
        The argparse destination, the ``--config`` key and the field of the command's options object; the option is
        ``--key`` with dashes.
    kind : {"flag", "whole", "number", "text", "names", "offset", "size", "length"}
        The value it takes, on the command line and in a ``--config`` file.
    help : str
        Its help; ``{default}`` in it is the default, else a default that is not None or False is added at the end
        (unless the help says which value is the default).
    default : object
        Its value when given neither on the command line nor in ``--config``.
    metavar, choices
        As argparse takes them.
    setting : str or None
        The library's name of what it gives (an :class:`~dynia.settings.AnalysisSettings` field, or an argument of
        the command's function): a :class:`~dynia.errors.SettingsError` naming it is reported naming the option.
    negated : bool
        A flag that turns off a setting on by default (``--no-quality``): the setting is ``not`` the flag.
    required : bool
        The command cannot run without it: refused when given neither on the command line nor in ``--config``.
    """

    key: str
    kind: str
    help: str
    default: object = None
    metavar: str | None = None
    choices: tuple | None = None
    setting: str | None = None
    negated: bool = False
    required: bool = False

    @property
    def flag(self):
        """The option as typed: ``--key`` with dashes, or ``DATA.csv`` for the data file."""
        return _POSITIONAL.get(self.key) or "--" + self.key.replace("_", "-")

    @property
    def is_setting(self):
        """Whether it gives a field of :class:`~dynia.settings.AnalysisSettings`."""
        return self.setting in _FIELDS

    def text(self):
        """The help as ``--help`` shows it, with its default.

        >>> Option("poll", "number", "seconds between looks at the table", default=10.0).text()
        'seconds between looks at the table (default 10)'
        """
        if "{default" in self.help:
            return self.help.format(default=self.default)
        if self.default is None or self.default is False or "(default" in self.help:
            return self.help
        shown = f"{self.default:g}" if isinstance(self.default, float) else self.default
        return f"{self.help} (default {shown})"

    def add_to(self, group):
        """Add the option to an argparse group (defaults stay None: a given value is one that is not None)."""
        if self.key in _POSITIONAL:
            group.add_argument(self.key, nargs="?", metavar=self.metavar, help=self.text())
            return
        how = dict(help=self.text().replace("%", "%%"))
        if self.kind == "flag":
            how.update(action="store_true")
        elif self.kind == "names":
            how.update(action="append")
        elif self.kind in ("whole", "number"):
            how.update(type=int if self.kind == "whole" else float)
        how.update({name: value for name, value in (("metavar", self.metavar), ("choices", self.choices)) if value})
        group.add_argument(self.flag, **how)


class Group(typing.NamedTuple):
    """Options that ``--help`` lists together under ``title``, with ``text`` under the title where it needs one."""

    title: str
    options: tuple
    text: str | None = None


def by_key(groups):
    """{key: option} of every option of ``groups``, in the order of ``--help``."""
    return {option.key: option for group in groups for option in group.options}


# The options given without a name, as their place in the command line is shown.
_POSITIONAL = {"data": "DATA.csv", "url": "URL"}

_FIELDS = {field.name: field for field in dataclasses.fields(AnalysisSettings)}

# The command line's name of every field, as the fields' help texts name each other.
_SETTING_FLAGS = {name: field.metadata.get("option", "--" + name.replace("_", "-")) for name, field in _FIELDS.items()}

# The kind of value of each field's annotation (int | None takes a whole number, or is left out).
_KINDS = {int: "whole", float: "number", bool: "flag", str: "text"}

# What the command line offers of a setting that is not all the library takes: the adaptive samplers are the
# library's (dynia.adaptive); the command line's reports assume a plain Monte Carlo sample.
_OFFERED = {"sampler": tuple(sorted(SAMPLERS))}

# What the command line adds to a setting's help: where it writes what the setting adds.
_WRITES = {
    "ic_error": ": NAME_se columns in ic.csv, max_ic_se in summary.json, IC +- 2 SE shaded in the plots",
    "quality": ": their windows are no evidence for any parameter, and data_quality in summary.json says which",
}


def setting_option(name, prefix=""):
    """The option of the AnalysisSettings field ``name``, made from the field's metadata, annotation and default.

    >>> option = setting_option("conf_level")
    >>> option.flag, option.kind, option.text()
    ('--conf-level', 'number', 'confidence level of the band, percent in (50, 100) (default 90)')
    """
    field = _FIELDS[name]
    meta = field.metadata
    annotation = field.type
    if isinstance(annotation, types.UnionType):  # int | None: the option takes an int, or is left out
        annotation = next(member for member in annotation.__args__ if member is not type(None))
    flag = _SETTING_FLAGS[name]
    negated = meta.get("negated", False)
    help_text = meta["help"].format(**_SETTING_FLAGS) + _WRITES.get(name, "")
    if negated:
        help_text = f"do not {help_text} (on by default)"
    return Option(
        key=flag[2:].replace("-", "_"),
        kind=_KINDS[annotation],
        help=prefix + help_text,
        # A negated flag is not given by default, which leaves its setting at its default (True).
        default=not field.default if negated else field.default,
        metavar=meta.get("metavar"),
        choices=_OFFERED.get(name, meta.get("choices")),
        setting=name,
        negated=negated,
    )


SEED = Option("seed", "whole", "seed of every random draw (default: drawn at random and recorded)", metavar="S")

WINDOW_HELP = (
    "the window as a duration, e.g. 60s, 2min or 1h (a bare number is seconds), instead of --n: "
    "n = round(DURATION / (2 dt)) on the data's grid"
)

DATA = (
    Option(
        "data", "text", "CSV file with a header row: time, input and output columns", metavar="DATA.csv", required=True
    ),
    Option("time", "text", "name of the time column: seconds, or ISO 8601 timestamps", required=True),
    Option(
        "time_format",
        "text",
        "strptime format of the time column for other timestamps, e.g. '%d.%m.%Y %H:%M' for 01.01.2012 00:15",
        metavar="FORMAT",
    ),
    Option("input", "names", "name of the input column (in long format: the input's tag); give one", required=True),
    Option("output", "names", "name of the output column (in long format: the output's tag); give one", required=True),
    Option(
        "output_file",
        "text",
        "the output is logged in this second file, with its own time column of the "
        "same name: both logs are resampled onto a common grid",
        metavar="FILE",
        setting="output_path",
    ),
    Option("long", "flag", "DATA.csv is a long-format event log: columns time, tag, value"),
    Option("tag_column", "text", "long format: the tag column (default: {default})", default="tag"),
    Option("value_column", "text", "long format: the value column (default: {default})", default="value"),
    Option(
        "dt",
        "number",
        "grid spacing for irregular or event-based data (default: the median spacing of the rows)",
        metavar="SECONDS",
    ),
    Option(
        "max_gap",
        "number",
        "a stretch without rows longer than this many grid steps is a gap: the output there is "
        "left missing, not interpolated (default {default:g}; inf interpolates across everything)",
        default=5.0,
        metavar="STEPS",
    ),
    Option(
        "duplicates",
        "text",
        "rows that repeat a timestamp: an error (default), or mean: average their values",
        default="error",
        choices=("error", "mean"),
    ),
    setting_option("quality"),
    Option(
        "offset",
        "offset",
        "subtract an output offset before fitting: {default} (default), first (the first measured output) or a number",
        default="none",
        metavar="{none,first,VALUE}",
    ),
    Option(
        "input_offset",
        "offset",
        "subtract an input offset before simulating: {default} (default), first or a "
        "number; with --offset and --x0 zero this makes a deviation model around "
        "an operating point",
        default="none",
        metavar="{none,first,VALUE}",
    ),
)

MODEL = (
    Option(
        "model",
        "text",
        "first-order: K/(T s+1); fopdt: K e^(-theta s)/(T s+1); "
        "second-order-delay: K e^(-theta s)/((T1 s+1)(T2 s+1)); or your own, MODULE:NAME or FILE.py:NAME, "
        "a dynia.models.Model or a function returning one (e.g. mymodels.py:tank)",
        metavar="MODEL",
        required=True,
    ),
    Option("param", "names", "sampling range of a model parameter; give one per parameter", metavar="NAME=LOW:HIGH"),
    setting_option("x0"),
)

# Progress is shown only on a terminal, so scripts and pipelines need no option to silence it.
QUIET = Option(
    "quiet",
    "flag",
    "show no progress on stderr (bars, the compilation notice, the 'wrote DIR' line); the results, warnings and "
    "errors still print",
)

OUTPUT = (
    Option("out", "text", "directory for the results (must not exist; see --overwrite)", metavar="DIR", required=True),
    Option("overwrite", "flag", "replace DIR if it holds the results of an earlier dynia run (never anything else)"),
    Option("no_plots", "flag", "write the tables and the summary, no figures"),
    Option(
        "unit",
        "names",
        "the unit of a parameter or a column (--input, --output), e.g. K=degC/V or q=mm/d: shown in the figures' "
        "axis labels and recorded in the summary; give one per name",
        metavar="NAME=UNIT",
    ),
    Option(
        "reference",
        "names",
        "a horizontal line at VALUE on the figures of the parameter or column NAME (a parameter's identifiability "
        "plot, a column's panel), labelled 'reference' or LABEL, e.g. K=18.5:calibrated; give one per name",
        metavar="NAME=VALUE[:LABEL]",
    ),
    QUIET,
)

# Read before the other options, so not one of them (a config file does not name another).
CONFIG = Option("config", "text", "read the settings from a TOML file", metavar="FILE.toml")

# Options that are gone, and what replaced them: refused with this message rather than argparse's "unrecognized".
RETIRED = {
    "--quality": "--quality is gone: the data-quality screening is on by default (--no-quality turns it off)",
}


def parser(commands):
    """The argparse parser of the ``dynia`` command: its ``--version``, and ``commands``, the modules of its commands,
    each adding itself with its ``cli_parse``."""
    top = _Parser(
        prog="dynia",
        description="Dynamic Identifiability Analysis (DYNIA) of process data: "
        "find the stretches of logged data that carry information about each model parameter.",
    )
    top.add_argument("--version", action="version", version=f"dynia {__version__}")
    subparsers = top.add_subparsers(dest="command", metavar="COMMAND")
    for command in commands:
        command.cli_parse(subparsers)
    return top


def add_command(subparsers, name, groups, *, refused=None, **texts):
    """Add the command ``name`` to the ``subparsers`` of ``dynia``: its option ``groups``, ``--config``, and the
    options it knows only to refuse (:data:`RETIRED`, and ``refused``: {option: the refusal}); returns its parser.

    ``texts`` are argparse's ``help``, ``description`` and ``epilog`` of the command. The refusals go into the
    Namespace as ``refusals`` ({argparse destination: the refusal}) for :func:`merged` to make.
    """
    command = subparsers.add_parser(name, formatter_class=argparse.RawDescriptionHelpFormatter, **texts)
    for title, options, text in groups:
        group = command.add_argument_group(title, text)
        for option in options:
            option.add_to(group)
    group.add_argument(CONFIG.flag, metavar=CONFIG.metavar, help=CONFIG.help)
    refusals = {}
    for option, refusal in RETIRED.items():
        action = group.add_argument(
            option, action="store_true", dest=_hidden("retired", option), help=argparse.SUPPRESS
        )
        refusals[action.dest] = refusal
    for option, refusal in (refused or {}).items():
        action = group.add_argument(
            option, nargs="?", const=True, dest=_hidden("refused", option), help=argparse.SUPPRESS
        )
        refusals[action.dest] = refusal
    command.set_defaults(refusals=refusals)
    return command


def _hidden(why, option):
    """The argparse destination of an option known only to be refused."""
    return f"{why}_{option[2:].replace('-', '_')}"


def attached(parser, words):
    """``--window -60s`` as ``--window=-60s``.

    argparse reads a word starting with ``-`` after an option that takes a value as another option, and fails
    with "expected one argument"; attached, the value reaches the option's own check and its message.

    >>> from dynia.cli import COMMANDS
    >>> attached(parser(COMMANDS.values()), ["analyse", "--window", "-60s", "--n", "3"])
    ['analyse', '--window=-60s', '--n', '3']
    """
    takes_value, known = set(), set()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for command in action.choices.values():
                for option in command._actions:
                    known.update(option.option_strings)
                    if option.option_strings and option.nargs is None:
                        takes_value.update(option.option_strings)
    attached, index = [], 0
    while index < len(words):
        word = words[index]
        if word == "--":
            attached += words[index:]
            break
        following = words[index + 1] if index + 1 < len(words) else None
        if (
            word in takes_value
            and following is not None
            and following.startswith("-")
            and not following.startswith("--")
            and following not in known
        ):
            attached.append(f"{word}={following}")
            index += 2
            continue
        attached.append(word)
        index += 1
    return attached


def merged(args, options):
    """The defaults of ``options`` ({key: Option} of the command), then its --config file, then the command line.

    Returns an ``argparse.Namespace`` of every option's value, with ``command``, ``config`` and ``given`` (the
    keys the user set, on the command line or in the file) besides, for the command's checks to complete. An option
    the command knows only to refuse (see :func:`add_command`) is refused first.
    """
    for dest, refusal in args.refusals.items():
        if getattr(args, dest) not in (None, False):
            raise UsageError(refusal)
    given = {
        key: value
        for key, value in vars(args).items()
        if value is not None
        and key not in ("command", "config", "refusals")
        and value is not False
        and key not in args.refusals
    }
    values = {key: option.default for key, option in options.items()}
    configured = {}
    if args.config:
        configured = read_config(args.config, args.command, options)
        values.update(configured)
    values.update(given)
    return argparse.Namespace(
        command=args.command, config=args.config, given=frozenset(given) | frozenset(configured), **values
    )


def read_config(path, command, options):
    """The settings of the TOML file ``path`` for ``command``, each of the kind its option takes."""
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
    if "quality" in config and "quality" not in options:
        raise UsageError(
            f"--config {path}: quality: the data-quality screening is on by default; write no_quality = true to "
            "turn it off"
        )
    allowed = sorted(options)
    unknown = sorted(set(config) - set(allowed))
    if unknown:
        raise UsageError(
            f"--config {path}: unknown key(s) for dynia {command}: {', '.join(unknown)}; allowed: {', '.join(allowed)}"
        )
    return {key: _typed(value, options[key], f"--config {path}: {key}") for key, value in config.items()}


# What a --config value of each kind of option must be, as its refusal says.
_EXPECTED = {
    "flag": "true or false (unquoted)",
    "whole": "a whole number",
    "number": "a number",
    "text": "a string",
    "offset": "none, first or a number",
    "size": 'a size such as "4GB" or a number of bytes',
    "names": "a string or a list of strings",
    "length": 'a whole number of steps or a duration such as "60s"',
}


def _typed(value, option, where):
    """A config value of the kind its option takes, one of its choices if it has them, or a one-line error (never
    truthy strings): checked as argparse checks the value on the command line."""
    if option.choices and value not in option.choices:
        raise UsageError(f"{where} must be one of {', '.join(option.choices)}; got {value!r}")
    kind = option.kind
    is_whole = isinstance(value, int) and not isinstance(value, bool)
    is_number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind == "flag" and isinstance(value, bool):
        return value
    if kind == "whole" and is_whole:
        return value
    if kind == "number" and is_number:
        return float(value)
    if kind == "text" and isinstance(value, str):
        return value
    if kind in ("offset", "size") and (isinstance(value, str) or is_number):
        return value
    if kind == "length" and (isinstance(value, str) or is_whole):
        return str(value)
    if kind == "names":
        if isinstance(value, str):
            return [value]
        if isinstance(value, list) and value and all(isinstance(item, str) for item in value):
            return value
    raise UsageError(f"{where} must be {_EXPECTED[kind]}; got {value!r} ({type(value).__name__})")


@contextlib.contextmanager
def named_as_options(options):
    """A SettingsError naming a setting (``error.setting``) as one naming the option of ``options`` that gives it.

    ``options`` are the command's, {key: Option}. Where the message names the setting as a word, the option takes
    its place (``conf_level is ...`` becomes ``--conf-level is ...``); a message that does not is led by the option.
    """
    try:
        yield
    except SettingsError as error:
        flags = {option.setting or option.key: option.flag for option in options.values()}
        option = flags.get(error.setting) if isinstance(error.setting, str) else None
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


# Refused where --no-plots is given: a line on figures that are not drawn (see refuse_idle).
REFERENCE_NEEDS_PLOTS = (
    "reference",
    "no_plots",
    False,
    "--reference draws a line on the figures, and --no-plots draws none; drop one",
)


def refuse_idle(values, rules):
    """Refuse an option given where it would do nothing, rather than ignore it without a word.

    ``rules`` are (option, the other, whether the other must be on, the refusal), the option's key and the other's.
    """
    for key, other, wanted, refusal in rules:
        if key in values.given and bool(getattr(values, other)) != wanted:
            raise UsageError(refusal)


def check_seed(values):
    """Refuse a negative ``--seed`` (numpy's generators take none)."""
    if values.seed is not None and values.seed < 0:
        raise UsageError(f"--seed must be a whole number >= 0; got {values.seed}")


def check_max_gap(values):
    """Refuse a ``--max-gap`` of one grid step or less."""
    if not (values.max_gap > 1 or math.isinf(values.max_gap)):
        raise UsageError(
            f"--max-gap is a multiple of the grid step above 1 (a gap longer than that many steps is "
            f"left missing); got {values.max_gap:g}"
        )


@dataclasses.dataclass(frozen=True, kw_only=True)
class CommandOptions:
    """What every command is given, checked: the record's columns, the model, the window and the seed.

    Made once by :func:`dynia.cli.common.checked_options` from argparse's Namespace; each command's own options
    object derives from it. A field named as an option holds that option's value as the command uses it (its
    default if not given); the others are made from them.

    Attributes
    ----------
    command : str
        The command: ``"analyse"``, ``"identify"``, ``"suggest"`` or ``"follow"``.
    command_line : list of str
        The command as typed, ``dynia`` first.
    given : frozenset of str
        The keys of the options the user set, on the command line or in ``--config``.
    config : str or None
        The ``--config`` file.
    inputs : list of str
        The files the command reads (data, output file, config, a model's source): ``--out`` must spare them.
    time, time_format, input, output, long, tag_column, value_column, dt, max_gap, duplicates, no_quality
        The record's options: ``input`` the input columns in the model's input order, ``output`` the one column.
    quality : bool
        Whether the record is screened (not ``--no-quality``).
    offset, input_offset : {"none", "first"} or float
        The offsets to subtract, as given (:func:`dynia.cli.common.load` finds their values).
    model, param, x0 : str, list of str, str
        The model's options as given.
    model_object : dynia.models.Model
        The model ``--model`` names.
    bounds : dict
        {parameter: (low, high)} of ``--param``, in the order given.
    n, window, window_seconds
        The half window (``--n``), the ``--window`` duration as given and in seconds; with ``--window``, ``n`` is
        the default until :meth:`on_grid` finds it on the data's grid.
    min_points : int
        The least measured output points of a window that reports an IC.
    analysis : dynia.settings.AnalysisSettings
        The analysis settings of the options.
    seed : int
        The seed, drawn if not given.
    quiet : bool
        ``--quiet``: no progress on stderr.
    """

    command: str
    command_line: list[str]
    given: frozenset[str]
    config: str | None
    inputs: list[str]
    time: str
    time_format: str | None
    input: list[str]
    output: str
    long: bool
    tag_column: str
    value_column: str
    dt: float | None
    max_gap: float
    duplicates: str
    no_quality: bool
    quality: bool
    offset: str | float
    input_offset: str | float
    model: str
    param: list[str]
    x0: str
    model_object: Model
    bounds: dict[str, tuple[float, float]]
    n: int
    window: str | None
    window_seconds: float | None
    min_points: int
    analysis: AnalysisSettings
    seed: int
    quiet: bool

    @property
    def shows_progress(self):
        """Whether the command shows its progress: bars, the compilation notice and the "wrote DIR" line, on stderr.

        Only on a terminal, so that the stderr of a script or a pipeline holds nothing but warnings and errors;
        --quiet silences it there too. Progress never goes to stdout, which holds the results (suggest --json's).
        """
        return stderr_is_terminal() and not self.quiet

    def on_grid(self, n):
        """The options with ``n``, the half window of ``--window`` on the data's grid, in the analysis settings."""
        return dataclasses.replace(self, n=n, analysis=self.analysis.replace(n=n, min_points=self.min_points))


@dataclasses.dataclass(frozen=True, kw_only=True)
class FileOptions(CommandOptions):
    """What a command that reads a CSV file is given: the file, and the output's own file if the output has one."""

    data: str
    output_file: str | None


@dataclasses.dataclass(frozen=True, kw_only=True)
class WritingOptions(FileOptions):
    """What a command that writes a result directory is given.

    Attributes
    ----------
    out, overwrite, no_plots, unit, reference
        The output options as given.
    destination : dynia.io.outdir.OutputDirectory
        Where the results go: ``--out`` checked before any work.
    units : dict
        {name: unit} of ``--unit``.
    references : dict
        {name: (value, label)} of ``--reference``.
    """

    out: str
    overwrite: bool
    no_plots: bool
    unit: list[str] | None
    reference: list[str] | None
    destination: OutputDirectory
    units: dict[str, str]
    references: dict[str, tuple[float, str]]


@dataclasses.dataclass(frozen=True, kw_only=True)
class SamplingOptions(CommandOptions):
    """What a command that runs DYNIA's Monte Carlo analysis on the command line's settings is given.

    Its fields are the analysis settings' options of the same names (``samples`` is ``n_samples``).
    """

    samples: int
    sampler: str
    percentage: float
    bins: int
    conf_level: float
    flavour: str
