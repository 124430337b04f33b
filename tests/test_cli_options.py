"""The command line's options of the analysis settings come from AnalysisSettings itself: one default, one help text,
one check, and errors naming the option through ``SettingsError.setting``."""

import ast
import dataclasses
import re

import pytest
from cli_cases import BASE, GOOD, cli_analyse, cli_one_error, write_text_file

from dynia.cli import COMMANDS, main
from dynia.cli.options import named_as_options, parser
from dynia.errors import SettingsError
from dynia.settings import AnalysisSettings

OPTIONS = {name: command.OPTIONS for name, command in COMMANDS.items()}
FIELDS = {field.name: field for field in dataclasses.fields(AnalysisSettings)}


def _attributes():
    """{name: (type and default line, description)} of AnalysisSettings' Attributes section."""
    section = AnalysisSettings.__doc__.split("Attributes\n    ----------\n")[1]
    entries, name = {}, None
    for line in section.splitlines():
        if re.match(r"^    \w+ : ", line):
            name, _, declared = line.strip().partition(" : ")
            entries[name] = [declared, ""]
        elif line.startswith("        ") and name:
            entries[name][1] += " " + line.strip()
    return {name: (declared, " ".join(text.split())) for name, (declared, text) in entries.items()}


def test_the_attributes_section_agrees_with_the_field_metadata():
    attributes = _attributes()
    assert list(attributes) == list(FIELDS)
    for name, field in FIELDS.items():
        declared, text = attributes[name]
        kind, _, default = declared.rpartition(", default ")
        assert ast.literal_eval(default) == field.default, name
        if "choices" in field.metadata:
            assert ast.literal_eval(kind) == set(field.metadata["choices"]), name
        # The help, with other settings named as the docstring names them, opens the description.
        help_text = field.metadata["help"].format(**{other: f"``{other}``" for other in FIELDS})
        assert text.startswith(help_text[0].upper() + help_text[1:]), (name, text)


def test_every_option_of_a_setting_has_the_fields_default_and_shows_it():
    for command, options in OPTIONS.items():
        for option in options.values():
            if option.is_setting:
                # A negated flag (--no-quality) is off by default, leaving its setting at its default.
                default = not option.default if option.negated else option.default
                assert default == FIELDS[option.setting].default, (command, option.key)
    text = parser(COMMANDS.values())._subparsers._group_actions[0].choices["analyse"].format_help()
    flat = " ".join(text.split())
    assert "--samples N Monte Carlo parameter sets (default 2000)" in flat
    assert "(50, 100) (default 90)" in flat and "(default uniform)" in flat
    assert "--max-samples N the budget of --target-se" in flat
    assert "--no-quality do not screen the record for saturated, frozen and coarsely quantised readings" in flat


def test_the_analysis_options_are_the_settings_with_their_option_names():
    analyse = {option.setting: key for key, option in OPTIONS["analyse"].items() if option.is_setting}
    assert analyse["n_samples"] == "samples" and analyse["conf_level"] == "conf_level"
    identify = {option.setting for option in OPTIONS["identify"].values() if option.is_setting}
    assert identify == {"x0", "n_samples", "n", "percentage", "quality"}
    # suggest's --max-samples is its own (the most samples of the proposal), not the budget of --target-se.
    assert not OPTIONS["suggest"]["max_samples"].is_setting


@pytest.mark.parametrize(
    "setting, message, expected",
    [
        ("conf_level", "conf_level is a percentage in (50, 100); got 0.9", "--conf-level is a percentage"),
        ("n_samples", "n_samples must be at least 1; got 0", "--samples must be at least 1; got 0"),
        ("n", "n must be at least 0; got -1", "--n must be at least 0"),
        (
            "n",
            "the record has 5 step(s), fewer than 2n+1 = 7 (n=3)",
            "the record has 5 step(s), fewer than 2n+1 = 7 (--n=3)",
        ),
        (
            "percentage",
            "splits into 100/percentage blocks; percentage 7 ...",
            "splits into 100/percentage blocks; --percentage 7",
        ),
        (
            "max_memory",
            "max_memory: 1 MB (max_memory); raise max_memory",
            "--max-memory: 1 MB (--max-memory); raise --max-memory",
        ),
        ("percentage", "the mcat flavour splits the samples", "--percentage: the mcat flavour splits the samples"),
    ],
)
def test_a_settings_error_names_the_option_of_its_setting(setting, message, expected):
    command = "suggest" if setting == "max_memory" else "analyse"
    with pytest.raises(SettingsError) as caught, named_as_options(OPTIONS[command]):
        raise SettingsError(message, setting)
    assert str(caught.value).startswith(expected), str(caught.value)


def test_a_settings_error_of_no_option_of_the_command_is_left_as_it_is():
    for setting in (None, "workers", "bins"):  # bins is no option of identify
        with pytest.raises(SettingsError, match="^as it was$"), named_as_options(OPTIONS["identify"]):
            raise SettingsError("as it was", setting)


@pytest.mark.parametrize(
    "options, needle",
    [
        (["--samples", "0"], "--samples must be at least 1; got 0"),
        (["--conf-level", "0.9"], "--conf-level is a percentage in (50, 100); got 0.9 (did you mean 90?)"),
        (["--flavour", "mcat", "--percentage", "7"], "100/percentage blocks; --percentage 7 does not divide 100"),
        (["--target-se", "0.1"], "--target-se and max_samples go together"),
    ],
)
def test_the_settings_own_checks_name_the_option(tmp_path, capsys, options, needle):
    good = write_text_file(tmp_path / "data.csv", GOOD)
    cli_one_error(*cli_analyse(capsys, good, *BASE, *options, "--out", tmp_path / "out"), needle)


@pytest.mark.parametrize(
    "line, needle",
    [
        ('sampler = "iis"', "sampler must be one of lhs, sobol, uniform; got 'iis'"),
        ('flavour = "glue"', "flavour must be one of thesis, mcat, weighted; got 'glue'"),
        ('x0 = "warm"', "x0 must be one of zero, steady; got 'warm'"),
    ],
)
def test_a_config_value_is_one_of_the_options_choices(tmp_path, capsys, line, needle):
    good = write_text_file(tmp_path / "data.csv", GOOD)
    config = write_text_file(tmp_path / "run.toml", line + "\n")
    cli_one_error(*cli_analyse(capsys, good, *BASE, "--config", config, "--out", tmp_path / "out"), needle)


@pytest.mark.parametrize(
    "command, options, typed",
    [
        ("analyse", ["--samp", "100"], "--samp"),  # would be --samples
        ("identify", ["--held", "0.2"], "--held"),  # would be --held-out
        ("suggest", ["--no-plot"], "--no-plot"),  # would be suggest's refused --no-plots, named as never typed
        ("suggest", ["--max-mem", "1GB"], "--max-mem"),  # would be --max-memory
    ],
)
def test_an_abbreviated_option_is_refused_naming_what_was_typed(tmp_path, capsys, command, options, typed):
    good = write_text_file(tmp_path / "data.csv", GOOD)
    status = main([command, str(good), *BASE[:10], *options])  # the data and the model: options of every command
    captured = capsys.readouterr()
    line = cli_one_error(status, captured.out, captured.err)
    assert line.endswith(f"unrecognized arguments: {' '.join(options)}") and line.count(typed) == 1


def test_every_parser_of_the_command_refuses_abbreviations():
    top = parser(COMMANDS.values())
    commands = top._subparsers._group_actions[0].choices
    assert not top.allow_abbrev and all(not sub.allow_abbrev for sub in commands.values())
