"""The options of the ``dynia`` command, each defined once, and the argparse parser made of them.

An option of the command line is an :class:`Option`: its ``--config`` key, its kind of value, its help, its default
and, where it gives one, the setting of the library it gives (for error messages that name that setting). The
analysis settings (``--samples``, ``--conf-level``, ...) are not restated here: their options are made from the
metadata of :class:`~dynia.settings.AnalysisSettings`' fields (help, option name, metavar, choices), their type is
the field's annotation and their default the field's own, which the help shows. :data:`OPTIONS` maps each command to
its options, in the order ``--help`` lists them.
"""

import argparse
import dataclasses
import textwrap
import types

from .. import __version__
from ..errors import SettingsError
from ..settings import DEFAULT_MAX_SAMPLES, IC_THRESHOLD, SAMPLERS, AnalysisSettings

__all__ = [
    "OPTIONS",
    "Option",
    "RETIRED",
    "UsageError",
    "WRITING_OPTIONS",
    "attached",
    "parser",
    "retired",
    "setting_options",
    "unwritten",
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
        The argparse destination and the ``--config`` key; the option is ``--key`` with dashes.
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
    """

    key: str
    kind: str
    help: str
    default: object = None
    metavar: str | None = None
    choices: tuple | None = None
    setting: str | None = None
    negated: bool = False

    @property
    def flag(self):
        """The option as typed: ``--key`` with dashes, or ``DATA.csv`` for the data file."""
        return _POSITIONAL.get(self.key) or "--" + self.key.replace("_", "-")

    @property
    def is_setting(self):
        """Whether it gives a field of :class:`~dynia.settings.AnalysisSettings`."""
        return self.setting in _FIELDS

    def text(self):
        """The help as ``--help`` shows it, with its default."""
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
    """The option of the AnalysisSettings field ``name``, made from the field's metadata, annotation and default."""
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


_SEED = Option("seed", "whole", "seed of every random draw (default: drawn at random and recorded)", metavar="S")


_WINDOW_HELP = (
    "the window as a duration, e.g. 60s, 2min or 1h (a bare number is seconds), instead of --n: "
    "n = round(DURATION / (2 dt)) on the data's grid"
)

_DATA = (
    Option("data", "text", "CSV file with a header row: time, input and output columns", metavar="DATA.csv"),
    Option("time", "text", "name of the time column: seconds, or ISO 8601 timestamps"),
    Option(
        "time_format",
        "text",
        "strptime format of the time column for other timestamps, e.g. '%d.%m.%Y %H:%M' for 01.01.2012 00:15",
        metavar="FORMAT",
    ),
    Option("input", "names", "name of the input column (in long format: the input's tag); give one"),
    Option("output", "names", "name of the output column (in long format: the output's tag); give one"),
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

_MODEL = (
    Option(
        "model",
        "text",
        "first-order: K/(T s+1); fopdt: K e^(-theta s)/(T s+1); "
        "second-order-delay: K e^(-theta s)/((T1 s+1)(T2 s+1)); or your own, MODULE:NAME or FILE.py:NAME, "
        "a dynia.models.Model or a function returning one (e.g. mymodels.py:tank)",
        metavar="MODEL",
    ),
    Option("param", "names", "sampling range of a model parameter; give one per parameter", metavar="NAME=LOW:HIGH"),
    setting_option("x0"),
)

# Progress is shown only on a terminal, so scripts and pipelines need no option to silence it.
_QUIET = Option(
    "quiet",
    "flag",
    "show no progress on stderr (bars, the compilation notice, the 'wrote DIR' line); the results, warnings and "
    "errors still print",
)

_OUTPUT = (
    Option("out", "text", "directory for the results (must not exist; see --overwrite)", metavar="DIR"),
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
    _QUIET,
)

# Read before the other options, so not one of them (a config file does not name another).
_CONFIG = Option("config", "text", "read the settings from a TOML file", metavar="FILE.toml")

_ANALYSE_METHOD = (
    setting_option("n_samples"),
    setting_option("sampler"),
    setting_option("n"),
    Option("window", "text", _WINDOW_HELP, metavar="DURATION"),
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
    _SEED,
)

IDENTIFY_METHODS = ("dynia", "baseline", "whole")

_IDENTIFY_SELECTION = (
    Option(
        "method",
        "text",
        "{default} (default): segments where the IC reaches --ic-threshold; baseline: "
        "the accepted intervals of the Bittencourt et al. (2015) search; whole: "
        "the whole record before the held-out part",
        default="dynia",
        choices=IDENTIFY_METHODS,
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
    Option("window", "text", "dynia: " + _WINDOW_HELP, metavar="DURATION"),
    setting_option("percentage", "dynia: "),
    _SEED,
)

_SUGGEST_PILOT = (
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
    _QUIET,
)

# The analyse options suggest takes, to carry them into the analyse command it proposes: all of analyse's method
# but the seed and --max-samples, which are suggest's own (the pilot's seed, the most samples of the proposal), and
# --target-se, whose budget is analyse's --max-samples.
# What suggest proposes shows no default: left out, suggest proposes it.
_SUGGEST_ANALYSIS = tuple(
    dataclasses.replace(option, help=option.help + " (default: proposed)")
    if option.key in ("samples", "n", "window", "percentage")
    else option
    for option in _ANALYSE_METHOD
    if option.key not in ("seed", "max_samples", "target_se")
)

_SUGGEST_ANALYSIS_TEXT = (
    "the options of the dynia analyse command suggest proposes: each one given is carried into that command as "
    "given, and the pilot runs with it. --n or --window, --percentage and --samples fix what suggest would "
    "otherwise propose: it keeps the value given, proposes the rest around it and says what the record asks for"
)

# dynia follow reads a table of a database: the data options of analyse but the file's own.
_FOLLOW_SOURCE = (
    Option(
        "url",
        "text",
        "the database: sqlite:///plant.db (built in), or postgresql://user@host:5432/plant after "
        'pip install "dynia[postgres]"; any SQLAlchemy URL whose driver is installed',
        metavar="URL",
    ),
    Option(
        "table", "text", "the table of logged data: wide (time, input and output columns) or --long", metavar="NAME"
    ),
    *(option for option in _DATA if option.key not in ("data", "output_file")),
)

# A follower analyses one trailing window a step, with no Monte Carlo error and nothing written but its tables.
_FOLLOW_METHOD = tuple(
    option
    for option in _ANALYSE_METHOD
    if option.key
    in ("samples", "sampler", "n", "window", "percentage", "bins", "conf_level", "flavour", "min_points", "seed")
)

_FOLLOW_RUN = (
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

# Each command's option groups, in the order of its --help.
_GROUPS = {
    "analyse": (("data", _DATA), ("model", _MODEL), ("method", _ANALYSE_METHOD), ("output", _OUTPUT)),
    "identify": (
        ("data", _DATA),
        ("model", _MODEL),
        ("selection and fit", _IDENTIFY_SELECTION),
        ("output", _OUTPUT),
    ),
    "suggest": (
        ("data", _DATA),
        ("model", _MODEL),
        ("analysis (carried into the proposed command)", _SUGGEST_ANALYSIS),
        ("pilot and output", _SUGGEST_PILOT),
    ),
    "follow": (("source", _FOLLOW_SOURCE), ("model", _MODEL), ("method", _FOLLOW_METHOD), ("follower", _FOLLOW_RUN)),
}

# What --help says under a group's title, where the title does not say it all.
_GROUP_TEXTS = {"analysis (carried into the proposed command)": textwrap.fill(_SUGGEST_ANALYSIS_TEXT, 76)}

# Every command's options by key: their defaults, their kinds in a --config file, and exactly what its summary records.
OPTIONS = {
    command: {option.key: option for _, options in groups for option in options} for command, groups in _GROUPS.items()
}


def setting_options(command):
    """{library name: option as typed} of ``command``'s options, for naming a SettingsError's setting."""
    return {option.setting or option.key: option.flag for option in OPTIONS[command].values()}


# Not options of suggest, which writes nothing: known only to say so, instead of argparse's "ambiguous option"
# (--out abbreviates --output and --output-file).
WRITING_OPTIONS = ("--out", "--overwrite", "--no-plots", "--unit", "--reference")


# Options that are gone, and what replaced them: refused with this message rather than argparse's "unrecognized".
RETIRED = {
    "--quality": "--quality is gone: the data-quality screening is on by default (--no-quality turns it off)",
}


def retired(option):
    """The argparse destination of a retired option, known only to refuse it."""
    return f"retired_{option[2:].replace('-', '_')}"


def unwritten(option):
    """The argparse destination of an output option that suggest knows only to refuse."""
    return f"unwritten_{option[2:].replace('-', '_')}"


_COMMANDS = {
    "analyse": dict(
        help="run DYNIA on a CSV file and write the results to a directory",
        description="Sample the model's parameters, simulate every sample on the logged input and, "
        "at every time step, rank the samples over a moving window: the information "
        "content IC(t) of each parameter, its confidence band and the CLD gradient.",
        epilog="""\
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
""",
    ),
    "identify": dict(
        help="re-identify the model by least squares on selected data and validate it",
        description="Choose the data to fit on (DYNIA's high-IC segments, the intervals of the "
        "Bittencourt et al. 2015 search, or the whole record), estimate the parameters "
        "by least squares with standard errors, and score the model on the held-out end "
        "of the record. Writes DIR/identified.json and DIR/fit.png.",
        epilog="""\
example (the heating-system record; the last 30 % of it is held out for validation):
  dynia identify data/heating_system/heating_system.csv --time time --input u --output y \\
      --model first-order --param K=0:40 --param T=0:200 \\
      --input-offset 6 --offset first --x0 zero --method dynia --seed 1 --out results/heating-fit

  writes results/heating-fit/identified.json (parameters, std_errors, segments as
  [start_time, end_time] pairs, validation_error, settings) and fit.png.
""",
    ),
    "suggest": dict(
        help="propose a window, a behavioural share and a number of samples for analyse, and say why",
        description="Estimate the record's dominant time constant and its noise, choose a window of about one "
        "time constant or, on a noisy record, as long as it takes to beat the noise, a behavioural share that lets "
        "the IC reach high values, and the number of samples that brings a pilot run's IC standard error to 0.02; "
        "check the parameter ranges against a least-squares fit. A window (--n or --window), share (--percentage) "
        "or number of samples (--samples) given is kept, and the rest proposed around it; every analyse option "
        "given is carried into the proposed command. Writes nothing; prints the proposal (--json: as JSON).",
        epilog="""\
example (proposes --n, --percentage and --samples for dynia analyse, with the reasons):
  dynia suggest data/heating_system/heating_system.csv --time time --input u --output y \\
      --model first-order --param K=0:40 --param T=0:200 \\
      --input-offset 6 --offset first --x0 zero --seed 1

  with --window 2min (or --n 60) it keeps that window and proposes the share and the
  samples for it; --flavour mcat, --conf-level 95, ... go into the proposed command.
""",
    ),
    "follow": dict(
        help="keep a results table current as a database table of logged data grows (thesis 4.3)",
        description="Sample the parameters once, then analyse every new row of a database table as the logging "
        "system writes it: one trailing window per step (the batch engine for a first backlog), a row per step and "
        "parameter in the results table, verdict changes in the events table and as log lines. Killed at any moment "
        "and started again, it goes on where its last transaction ended; started with other settings, it refuses.",
        epilog="""\
example (the heating-system record loaded into SQLite as table heating, then followed):
  dynia follow sqlite:///plant.db --table heating --time time --input u --output y \\
      --model first-order --param K=0:40 --param T=0:200 \\
      --input-offset 6 --offset first --x0 zero --seed 1 --once

  writes table dynia_results (time, parameter, ic, lower, upper, estimate, informative),
  dynia_events (verdict changes) and the follower's own dynia_results_steps and
  dynia_results_state. Without --once it polls every --poll seconds until SIGINT or
  SIGTERM, which commit and exit 0.
""",
    ),
}


def parser():
    """The argparse parser of the ``dynia`` command and its commands."""
    top = _Parser(
        prog="dynia",
        description="Dynamic Identifiability Analysis (DYNIA) of process data: "
        "find the stretches of logged data that carry information about each model parameter.",
    )
    top.add_argument("--version", action="version", version=f"dynia {__version__}")
    commands = top.add_subparsers(dest="command", metavar="COMMAND")
    for command, text in _COMMANDS.items():
        sub = commands.add_parser(command, formatter_class=argparse.RawDescriptionHelpFormatter, **text)
        groups = _GROUPS[command]
        for title, options in groups:
            group = sub.add_argument_group(title, _GROUP_TEXTS.get(title))
            for option in options:
                option.add_to(group)
        group.add_argument(_CONFIG.flag, metavar=_CONFIG.metavar, help=_CONFIG.help)
        # Known only to be refused with a message that says what replaced it (see RETIRED).
        for option in RETIRED:
            group.add_argument(option, action="store_true", dest=retired(option), help=argparse.SUPPRESS)
        if command == "suggest":
            for option in WRITING_OPTIONS:
                group.add_argument(option, nargs="?", const=True, dest=unwritten(option), help=argparse.SUPPRESS)
    return top


def attached(parser, words):
    """``--window -60s`` as ``--window=-60s``.

    argparse reads a word starting with ``-`` after an option that takes a value as another option, and fails
    with "expected one argument"; attached, the value reaches the option's own check and its message.
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
