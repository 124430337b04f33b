"""dynia suggest and --window: settings from the record's own time scales, and the reasons for them."""

import json

import numpy as np
import pytest

import dynia
from dynia.cli import main
from dynia.errors import DataError, SettingsError, SuggestionError
from dynia.fit import fit_segments
from dynia.memory import parse_size, run_memory
from dynia.models import FirstOrder, FunctionModel
from dynia.models.conceptual import hymod, hymod_record
from dynia.suggestion import suggest
from dynia.timescale import dominant_time_constant, parse_duration, window_half_width

# A TCLab-like heater step test: 1 s sampling, about two hours, heater steps in %, a time constant of
# 170 s, a gain of 0.6 degC/%, ambient 21 degC, sensor noise of 0.15 degC.
TCLAB_GAIN, TCLAB_TAU = 0.6, 170.0
TCLAB_INPUT = np.r_[np.zeros(60), np.full(1800, 60.0), np.full(1500, 25.0), np.full(1800, 80.0), np.full(2040, 40.0)]
TCLAB_ARGS = ["--time", "time", "--input", "Q1", "--output", "T1", "--model", "first-order"]
TCLAB_ARGS += ["--param", "K=0:2", "--param", "T=0:500", "--offset", "first"]


def tclab_record(seed=3):
    noise = np.random.default_rng(seed).normal(0, 0.15, TCLAB_INPUT.size)
    return TCLAB_INPUT, 21.0 + FirstOrder().simulate([[TCLAB_GAIN, TCLAB_TAU]], TCLAB_INPUT)[0] + noise


def write_csv(path, u, y, dt=1.0):
    np.savetxt(path, np.column_stack([np.arange(u.size) * dt, u, y]), delimiter=",", header="time,Q1,T1", comments="")
    return path


@pytest.fixture(scope="module")
def tclab(tmp_path_factory):
    u, y = tclab_record()
    return write_csv(tmp_path_factory.mktemp("tclab") / "step_test.csv", u, y), u, y


def run_cli(capsys, *args):
    status = main([str(arg) for arg in args])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


# ------------------------------------------------------------ durations


@pytest.mark.parametrize(
    "text, seconds",
    [("60s", 60.0), ("60", 60.0), ("2min", 120.0), ("1h", 3600.0), ("1.5 h", 5400.0), ("1d", 86400.0), ("90 sec", 90)],
)
def test_durations_in_time_units(text, seconds):
    assert parse_duration(text) == seconds


@pytest.mark.parametrize("text", ["", "abc", "60 parsecs", "-5s", "0s", "1e999s", "s"])
def test_what_is_no_duration_is_one_line_naming_the_option(text):
    with pytest.raises(SettingsError, match="^--window ") as caught:
        parse_duration(text, "--window")
    assert "\n" not in str(caught.value)


def test_the_half_window_of_a_duration():
    assert window_half_width(60.0, 1.0, 1000) == 30
    assert window_half_width(61.0, 2.0, 1000) == 15  # 30.5 steps: 2n+1 = 31
    assert window_half_width(5.0, 1.0, 1000) == 3  # 2.5 rounds half up
    assert window_half_width(3.0, 1.0, 5) == 2  # 1.5 rounds half up: 5 steps
    with pytest.raises(SettingsError, match="at least 3 steps"):
        window_half_width(2.9, 1.0, 1000)
    with pytest.raises(SettingsError, match="longer than the record's 100 steps"):
        window_half_width(201.0, 1.0, 100)
    with pytest.raises(SettingsError, match="longer than the record's 100 steps"):
        window_half_width(100.0, 1.0, 100)  # n = 50: 101 steps
    # Issue 32: 1e308 s printed a 309-digit number of steps.
    with pytest.raises(SettingsError, match=r"^window 1e\+308 s is 1e\+308 steps of 1 s, longer than the record's 100"):
        window_half_width(1e308, 1.0, 100)


# ------------------------------------------------------- the time scale


def test_the_time_constant_of_a_clean_first_order_record_is_exact():
    u = np.repeat([0.0, 50.0, 20.0, 70.0], 600)
    scale = dominant_time_constant(u, 3.0 + FirstOrder().simulate([[0.6, 60.0]], u, dt=2.0)[0], dt=2.0)
    assert scale.time_constant == pytest.approx(60.0, rel=1e-4)
    assert scale.gains[0] == pytest.approx(0.6, rel=1e-4) and scale.level == pytest.approx(3.0, abs=1e-3)
    assert scale.explained == pytest.approx(1.0) and scale.edge is None


def test_the_time_constant_from_noisy_data_with_gaps_and_two_inputs():
    rng = np.random.default_rng(1)
    u = np.column_stack([np.repeat([0.0, 1.0, 0.0, 1.0, 1.0], 400), np.repeat([0.0, 0.0, 2.0, 2.0, 0.0], 400)])
    model = FirstOrder()
    y = model.simulate([[2.0, 40.0]], u[:, 0])[0] - model.simulate([[0.5, 40.0]], u[:, 1])[0]
    y = y + rng.normal(0, 0.05, y.size)
    y[500:700] = np.nan
    scale = dominant_time_constant(u, y)
    assert scale.time_constant == pytest.approx(40.0, rel=0.03)
    assert scale.gains == pytest.approx((2.0, -0.5), rel=0.03)


def test_an_output_that_follows_at_once_or_never_settles_is_at_the_edge():
    u = np.repeat([0.0, 1.0, 0.0, 1.0], 50)
    assert dominant_time_constant(u, 2 * u).edge == "fast"
    ramp = FirstOrder().simulate([[1.0, 1e6]], np.ones(200))[0]
    assert dominant_time_constant(np.ones(200) * np.r_[0, np.ones(199)], ramp).edge == "slow"
    with pytest.raises(DataError, match="measured values"):
        dominant_time_constant(u, np.full(u.size, np.nan))


# ----------------------------------------------------------- suggestions


def test_a_range_that_excludes_the_fit_is_named():
    u, y = tclab_record()
    found = suggest(u[:3400], y[:3400] - y[0], FirstOrder(), {"K": (0, 2), "T": (0, 100)}, rng=1)
    assert found.fit["T"]["at_bound"] and not found.fit["K"]["at_bound"]
    notes = [note for note in found.notes if "excludes the least-squares fit" in note]
    assert len(notes) == 1 and notes[0].startswith("the range [0, 100] of T") and "upper bound 100" in notes[0]


def test_input_changes_closer_than_a_window_are_noted():
    u = np.r_[np.zeros(100), np.ones(30), np.zeros(370), np.ones(500)]
    y = FirstOrder().simulate([[1.0, 60.0]], u)[0] + np.random.default_rng(2).normal(0, 0.01, u.size)
    found = suggest(u, y, FirstOrder(), {"K": (0, 3), "T": (0, 200)}, rng=1)
    assert found.n == 30
    close = [note for note in found.notes if "within a window" in note]
    assert len(close) == 1 and close[0].startswith("1 input change(s)") and "first at 130 s" in close[0]


def test_the_share_follows_the_number_of_parameters():
    from dynia.models import FOPDT

    u = np.repeat([0.0, 1.0, 0.0, 1.0], 60)
    y = FOPDT().simulate([[2.0, 8.0, 3.0]], u)[0] + np.random.default_rng(3).normal(0, 0.02, u.size)
    found = suggest(u, y, FOPDT(), {"K": (0, 5), "T": (0, 30), "theta": (0, 10)}, rng=1)
    assert found.percentage == 0.1
    assert found.n_samples >= 50 / 0.001  # at least 50 behavioural sets
    assert found.pilot["n_samples"] == 50_000  # ten batches of five behavioural sets for its ic_se


def test_suggested_settings_identify_the_time_constant_where_the_defaults_do_not(tclab, tmp_path, capsys):
    """The issue's TCLab case: the defaults leave T unidentified; the suggestion identifies it."""
    path, u, y = tclab
    status, out, err = run_cli(capsys, "suggest", path, *TCLAB_ARGS, "--seed", "1", "--json")
    assert status == 0 and err == ""
    proposal = json.loads(out)
    settings = proposal["settings"]
    assert proposal["time_constant"] == pytest.approx(TCLAB_TAU, rel=0.02)
    assert settings["n"] == 85 and settings["window"] == 171.0 and settings["percentage"] == 1.0
    assert 2500 <= settings["n_samples"] <= 30_000
    assert proposal["arguments"] == ["--n", "85", "--percentage", "1", "--samples", str(settings["n_samples"])]
    assert proposal["command"][:2] == ["dynia", "analyse"] and "--json" not in proposal["command"]

    least_squares = fit_segments(
        u, y - y[0], FirstOrder(), [(0, u.size)], bounds={"K": (0, 2), "T": (0, 500)}, x0="zero"
    ).parameters["T"]
    assert proposal["fit"]["T"]["estimate"] == pytest.approx(least_squares, rel=1e-3)

    def analysed(*options):
        out = tmp_path / f"run{len(list(tmp_path.iterdir()))}"
        status, _, _ = run_cli(
            capsys, "analyse", path, *TCLAB_ARGS, "--seed", "2", "--no-plots", *options, "--out", out
        )
        assert status == 0
        return json.loads((out / "summary.json").read_text())["parameters"]["T"]

    defaults = analysed()
    suggested = analysed(*proposal["arguments"])
    assert defaults["max_ic"] < 0.6
    assert suggested["max_ic"] > 0.6
    low, high = suggested["band"]
    assert low <= least_squares <= high
    assert suggested["verdict"] == "identified"


def test_suggest_prints_the_reasons_and_the_command_to_run(tclab, capsys):
    path, _, _ = tclab
    status, out, err = run_cli(capsys, "suggest", path, *TCLAB_ARGS, "--seed", "1")
    assert status == 0 and err == ""
    lines = out.splitlines()
    assert lines[0].startswith("suggested settings for dynia analyse: --n 85 --percentage 1 --samples ")
    assert "why:" in lines and "run:" in lines
    assert any(line.startswith("  - dominant time constant 17") for line in lines)
    command = lines[lines.index("run:") + 1].split()
    assert command[:3] == ["dynia", "analyse", str(path)] and command.count("--seed") == 1
    assert command[-2:] == ["--out", "RESULTS"]


def test_suggest_needs_no_out_and_refuses_what_only_writing_takes(tclab, capsys):
    path, _, _ = tclab
    for option in (["--out", "results"], ["--overwrite"], ["--no-plots"]):
        status, _, err = run_cli(capsys, "suggest", path, *TCLAB_ARGS, *option)
        assert status == 2 and err.count("\n") == 1
        assert f"dynia suggest writes nothing (it prints its proposal), so it takes no {option[0]}" in err
    status, _, err = run_cli(capsys, "suggest", path, "--time", "time", "--input", "Q1", "--output", "T1")
    assert status == 2 and "--model is required" in err


# --------------------------------------------------------------- --window


@pytest.fixture(scope="module")
def short_record(tmp_path_factory):
    u = np.repeat([0.0, 1.0, 0.0, 1.0, 0.0], 40)
    y = FirstOrder().simulate([[2.0, 10.0]], u, dt=2.0)[0] + np.random.default_rng(5).normal(0, 0.05, u.size)
    return write_csv(tmp_path_factory.mktemp("short") / "short.csv", u, y, dt=2.0)


SHORT_ARGS = ["--time", "time", "--input", "Q1", "--output", "T1", "--model", "first-order"]
SHORT_ARGS += ["--param", "K=0:5", "--param", "T=0:40", "--samples", "200", "--seed", "1", "--no-plots"]


@pytest.mark.parametrize("command, summary", [("analyse", "summary.json"), ("identify", "identified.json")])
def test_a_window_in_time_units_becomes_n_on_the_grid_and_is_recorded(short_record, tmp_path, capsys, command, summary):
    out = tmp_path / "out"
    status, _, err = run_cli(capsys, command, short_record, *SHORT_ARGS, "--window", "1min", "--out", out)
    assert status == 0, err
    settings = json.loads((out / summary).read_text())["settings"]
    assert settings["window"] == "1min" and settings["n"] == 15  # 60 s / (2 x 2 s)
    assert settings["analysis"]["n"] == 15


@pytest.mark.parametrize(
    "options, message",
    [
        (["--window", "5s"], "--window 5 s is 2.5 steps of 2 s; a window needs at least 3 steps"),
        (["--window", "1h"], "--window 3600 s is 1801 steps of 2 s (2n+1 with n = 900), longer than the record's"),
        (["--window", "60s", "--n", "5"], "--window and --n both set the window; give one of them"),
        (["--window", "fortnight"], "--window must be a duration such as 60s"),
        (["--window", "20s", "--min-points", "30"], "--min-points 30 is more than a window holds"),
    ],
)
def test_a_bad_window_is_one_line(short_record, tmp_path, capsys, options, message):
    out = tmp_path / "out"
    status, _, err = run_cli(capsys, "analyse", short_record, *SHORT_ARGS, *options, "--out", out)
    assert status == 2 and err.count("\n") == 1
    assert message in err
    assert not out.exists()


def test_window_and_n_are_exclusive_across_the_config_file(short_record, tmp_path, capsys):
    config = tmp_path / "run.toml"
    config.write_text("n = 5\n")
    status, _, err = run_cli(
        capsys, "analyse", short_record, *SHORT_ARGS, "--config", config, "--window", "20s", "--out", tmp_path / "o"
    )
    assert status == 2 and "--window and --n both set the window" in err
    config.write_text('window = "20s"\n')
    status, _, err = run_cli(capsys, "analyse", short_record, *SHORT_ARGS, "--config", config, "--out", tmp_path / "p")
    assert status == 0, err
    assert json.loads((tmp_path / "p" / "summary.json").read_text())["settings"]["n"] == 5


SUGGEST_SHORT = [*SHORT_ARGS[:12], "--seed", "1", "--max-samples", "5000"]  # the data and the model


def test_suggest_keeps_a_window_given_and_carries_the_analyse_options_into_its_command(short_record, tmp_path, capsys):
    carried = ["--window", "1min", "--flavour", "mcat", "--conf-level", "95", "--percentage", "10", "--bins", "20"]
    status, out, err = run_cli(capsys, "suggest", short_record, *SUGGEST_SHORT, *carried, "--json")
    assert status == 0, err
    proposal = json.loads(out)
    assert proposal["settings"]["n"] == 15 and proposal["settings"]["percentage"] == 10  # 60 s / (2 x 2 s)
    assert proposal["given"] == ["n", "percentage"] and proposal["arguments"][0] == "--samples"
    assert any(reason.startswith("window 2n+1 = 31 steps (62 s), as given (n = 15)") for reason in proposal["reasons"])
    command = proposal["command"]
    assert command[: 3 + len(SUGGEST_SHORT) - 4] == ["dynia", "analyse", str(short_record), *SUGGEST_SHORT[:-4]]
    for option, value in zip(carried[::2], carried[1::2]):
        assert command.count(option) == 1 and command[command.index(option) + 1] == value, option
    assert "--n" not in command and "--max-samples" not in command and command.count("--seed") == 1
    # The command runs as printed, with the window and the options given.
    out_dir = tmp_path / "analysed"
    status, _, err = run_cli(capsys, *command[1:-1], out_dir, "--no-plots")
    assert status == 0, err
    settings = json.loads((out_dir / "summary.json").read_text())["settings"]
    assert settings["n"] == 15 and settings["analysis"]["flavour"] == "mcat" and settings["analysis"]["bins"] == 20


@pytest.mark.parametrize(
    "options, message",
    [
        (["--window", "60s", "--n", "5"], "--window and --n both set the window; give one of them"),
        (["--window", "5s"], "--window 5 s is 2.5 steps of 2 s; a window needs at least 3 steps"),
        (["--n", "-1"], "--n must be at least 0; got -1"),
        (["--n", "200"], "200 time steps, fewer than one window of 2n+1 = 401 (--n 200)"),
        (["--percentage", "0"], "--percentage"),
        (["--samples", "0"], "--samples must be at least 1; got 0"),
        (["--conf-level", "0.9"], "--conf-level is a percentage in (50, 100)"),
        (["--target-se", "0.01"], "unrecognized arguments: --target-se 0.01"),
    ],
)
def test_suggest_checks_the_analyse_options_as_analyse_does(short_record, capsys, options, message):
    status, out, err = run_cli(capsys, "suggest", short_record, *SUGGEST_SHORT, *options)
    assert status == 2 and out == "" and err.count("\n") == 1 and err.startswith("dynia: error: ")
    assert message in err


def test_the_sample_count_brings_the_pilots_ic_standard_error_to_the_target():
    u, y = tclab_record()
    found = suggest(u[:3400], y[:3400] - y[0], FirstOrder(), {"K": (0, 2), "T": (0, 500)}, rng=1)
    # 1 % behavioural: 50 behavioural sets, ten batches of five, need 5000 pilot samples.
    assert found.percentage == 1 and found.pilot["n_samples"] == 5000
    worst = max(entry["ic_se"] for entry in found.pilot["parameters"].values())
    assert worst > 0
    needed = 5000 * (worst / 0.02) ** 2
    assert needed <= found.n_samples <= max(needed * 1.1, 5000)  # rounded up to two significant digits
    assert "(result.ic_se)" in found.reasons[3]


# ------------------------------------- the initial state, and no proposal from a poor fit (issue 18)


def heater_record(variant, seed):
    """One heater step at 50 %, two hours at 1 s, tau 170 s, noise 0.15, as ``--offset first`` leaves it.

    "inside": the heater goes on at 600 s; "before": it is on in the first row and the output is still
    rising from ambient (the record starts after the step, not at steady state).
    """
    u = np.full(7200, 50.0)
    if variant == "inside":
        u[:600] = 0.0
    noise = np.random.default_rng(seed).normal(0, 0.15, u.size)
    y = 21.0 + FirstOrder().simulate([[TCLAB_GAIN, TCLAB_TAU]], u)[0] + noise
    return u, y - y[0]


def test_the_time_constant_starts_where_the_analysis_starts():
    u, y = heater_record("before", 1)
    zero = dominant_time_constant(u, y, x0="zero")
    assert zero.time_constant == pytest.approx(TCLAB_TAU, rel=0.03) and zero.explained > 0.99 and zero.x0 == "zero"
    # From rest at its first value the input never moves the model: nothing is explained.
    steady = dominant_time_constant(u, y, x0="steady")
    assert steady.explained < 0.01 and steady.x0 == "steady"
    # An input that starts at zero: both initial states are the same model.
    u, y = heater_record("inside", 1)
    assert dominant_time_constant(u, y, x0="steady").time_constant == pytest.approx(
        dominant_time_constant(u, y, x0="zero").time_constant, rel=1e-9
    )


def test_a_fit_that_explains_little_proposes_no_window():
    u, y = heater_record("before", 1)
    with pytest.raises(SuggestionError, match="^cannot propose a window") as caught:
        suggest(u, y, FirstOrder(), {"K": (0, 2), "T": (0, 500)}, x0="steady", rng=1)
    message = str(caught.value)
    assert "x0 steady) explains 0 %" in message and "below 50 %" in message
    assert "stays at its first value" in message and "with x0 zero it explains 100 %" in message
    assert "\n" not in message
    noise = np.random.default_rng(2).normal(0, 1.0, 2000)
    with pytest.raises(SuggestionError, match="give the window yourself"):
        suggest(np.repeat([0.0, 1.0], 1000), noise, FirstOrder(), {"K": (0, 2), "T": (0, 500)}, rng=1)


# A first-order lag of 5 s sampled at 1 s under sensor noise of 0.4 degC: heater steps of a few %, a gain of
# 0.8 degC/%, so responses of about 1-3 degC, 1600 s. One time constant is a 5 s window (n = 2), in which the
# behavioural sets tie within the noise and neither parameter is identified; the default window (n = 10)
# identifies both.
NOISY_BOUNDS = {"K": (0, 2), "T": (0, 50)}


def noisy_fast_record():
    u = np.repeat([0.0, 3.0, 1.0, 4.0, 2.0, 5.0, 1.0, 3.0], 200)
    y = FirstOrder().simulate([[0.8, 5.0]], u)[0] + np.random.default_rng(1).normal(0, 0.4, u.size)
    return u, y


def test_the_window_of_a_noisy_record_with_a_short_time_constant_beats_the_noise():
    u, y = noisy_fast_record()
    found = suggest(u, y, FirstOrder(), NOISY_BOUNDS, rng=1, max_samples=20_000)
    assert found.time_scale.time_constant == pytest.approx(5.0, rel=0.1)
    assert found.n >= 10  # at least the default window, which identifies both
    assert "longer than one time constant (5 steps) to beat the noise" in found.reasons[1]

    def verdicts(n):
        result = dynia.run(
            u, y, FirstOrder(), NOISY_BOUNDS, n=n, percentage=found.percentage, n_samples=found.n_samples, rng=2
        )
        return {name: verdict["verdict"] for name, verdict in result.verdicts.items()}

    assert verdicts(found.n) == {"K": "identified", "T": "identified"}
    # The window of one time constant, which suggest proposed before it weighed the noise, identifies neither.
    assert "identified" not in verdicts(2).values()


def test_a_window_given_is_kept_and_the_rest_proposed_around_it():
    u, y = noisy_fast_record()
    found = suggest(u, y, FirstOrder(), NOISY_BOUNDS, n=12, percentage=2.0, rng=1, max_samples=20_000)
    assert found.n == 12 and found.window == 25.0 and found.percentage == 2.0 and found.given == ("n", "percentage")
    assert found.arguments() == ["--samples", str(found.n_samples)]
    assert found.pilot["n_samples"] == 2500  # 50 behavioural sets at the share given
    assert found.reasons[1].startswith("window 2n+1 = 25 steps (25 s), as given (n = 12); the record would ask for n =")
    assert found.reasons[2] == "percentage 2, as given; with 2 parameter(s) suggest would propose 1 (module docs)"
    assert "kept as given: --n 12, --percentage 2" in found.text().splitlines()[0]
    fixed = suggest(u, y, FirstOrder(), NOISY_BOUNDS, n_samples=3000, rng=1, max_samples=20_000)
    assert fixed.n_samples == 3000 and fixed.arguments()[:2] == ["--n", str(fixed.n)]
    assert fixed.reasons[3].startswith("samples 3000, as given: a pilot with 5000 samples")


def test_a_window_given_gets_a_proposal_where_the_record_sizes_none():
    noise = np.random.default_rng(2).normal(0, 1.0, 2000)
    found = suggest(np.repeat([0.0, 1.0], 1000), noise, FirstOrder(), {"K": (0, 2), "T": (0, 500)}, n=20, rng=1)
    assert found.n == 20 and found.reasons[0].startswith("no dominant time constant: a first-order model")
    with pytest.raises(SettingsError, match="^n 1000: the window 2n\\+1 = 2001 is longer than the record"):
        suggest(np.repeat([0.0, 1.0], 1000), noise, FirstOrder(), {"K": (0, 2), "T": (0, 500)}, n=1000, rng=1)


def test_the_cli_says_in_one_line_why_it_proposes_nothing(tmp_path, capsys):
    u, y = heater_record("before", 1)
    path = write_csv(tmp_path / "on_from_the_start.csv", u, y + 21.0)
    status, out, err = run_cli(capsys, "suggest", path, *TCLAB_ARGS, "--x0", "steady", "--seed", "1")
    assert status == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("dynia: error: cannot propose a window: ") and "--x0" in err


# The window proposed on a heater record with one step, inside it or before its first row, and what it
# finds. With one step the record's highest IC can be a window that sees only a sliver of the response's
# start, whose behavioural set is ranked by noise (seed 3, "inside": band 349-494 s); the verdict reports
# the highest IC among the windows that are evidence, in the transient itself.
@pytest.mark.parametrize("variant", ["inside", "before"])
@pytest.mark.parametrize("seed", [3, 4, 5])
def test_one_heater_step_inside_or_before_the_record_gets_a_window_that_finds_the_time_constant(variant, seed):
    u, y = heater_record(variant, seed)
    bounds = {"K": (0, 2), "T": (0, 500)}
    found = suggest(u, y, FirstOrder(), bounds, rng=1)
    assert 60 <= found.window <= 400
    assert found.time_scale.time_constant == pytest.approx(TCLAB_TAU, rel=0.05)
    assert found.percentage == 1 and 5000 <= found.n_samples <= 30_000 and found.notes == []
    assert 0 < found.memory["pilot"] <= found.memory["limit"]

    result = dynia.run(
        u, y, FirstOrder(), bounds, n=found.n, percentage=found.percentage, n_samples=found.n_samples, rng=2
    )
    least_squares = fit_segments(u, y, FirstOrder(), [(0, u.size)], bounds=bounds, x0="zero").parameters["T"]
    reported = result.summary()["T"]
    low, high = reported["band"]
    assert reported["verdict"] == "identified" and reported["max_ic"] >= 0.6, reported
    assert low <= least_squares <= high


# ----------------------------------------------------- samples and memory held in bounds (issue 18)

HYMOD_BOUNDS = {"cmax": (10.0, 500.0), "b": (0.0, 2.0), "alpha": (0.0, 1.0), "kq": (0.1, 1.0), "ks": (0.0, 0.2)}


@pytest.fixture(scope="module")
def catchment():
    return hymod_record(365, rng=np.random.default_rng(1))


def test_five_parameters_hold_the_share_and_the_samples_at_max_samples(catchment):
    found = suggest(catchment.u, catchment.y, hymod(), HYMOD_BOUNDS, max_samples=2000, rng=1)
    # 0.001 % would be a tenth of each of five ranges; 50 behavioural sets in 2000 samples need 2.5 %.
    assert found.percentage == 2.5 and found.pilot["n_samples"] == 2000 and found.n_samples <= 2000
    assert "more than max_samples 2000" in found.reasons[2]
    assert any(note.startswith("the behavioural share is held at 2.5 % by max_samples 2000") for note in found.notes)


def test_a_pilot_over_the_memory_limit_is_refused_before_it_starts(catchment):
    needed = run_memory(hymod(), 200_000, 365, 3)
    with pytest.raises(SettingsError, match=r"^max_memory: the pilot run \(200000 samples") as caught:
        # The default max_samples: five parameters take the share 0.025 %, the pilot 200000 samples.
        suggest(catchment.u, catchment.y, hymod(), HYMOD_BOUNDS, max_memory=needed / 2, rng=1)
    assert caught.value.setting == "max_memory" and "would need about" in str(caught.value)


def test_the_memory_estimate_grows_with_the_samples_and_a_whole_simulation():
    model = FirstOrder()
    # Four arrays of the samples x (a chunk of 4 x 2n steps + 2n) in the window, two parameters and 16 values more.
    per_sample = 8.0 * (4 * (680 + 170) + 2 + 16)
    assert run_memory(model, 20_000, 7200, 85) - run_memory(model, 5000, 7200, 85) == 15_000 * per_sample
    whole = FunctionModel(lambda params, u, dt: np.outer(params[:, 0], u), ["K", "T"])  # no state: not streamed
    extra = run_memory(whole, 5000, 7200, 85) - run_memory(model, 5000, 7200, 85)
    assert extra == 8.0 * 5000 * 7200  # the whole simulation


@pytest.mark.parametrize(
    "text, size", [("4GB", 4e9), ("512 MB", 512e6), ("2GiB", 2 * 2**30), ("1e9", 1e9), (1000, 1000.0)]
)
def test_sizes(text, size):
    assert parse_size(text) == size


def test_the_cli_limits_and_names_them_as_options(tclab, capsys):
    path, _, _ = tclab
    status, out, err = run_cli(capsys, "suggest", path, *TCLAB_ARGS, "--max-memory", "1MB", "--seed", "1")
    assert status == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("dynia: error: --max-memory: the pilot run (5000 samples") and "1 MB (--max-memory)" in err
    status, _, err = run_cli(capsys, "suggest", path, *TCLAB_ARGS, "--max-memory", "lots")
    assert status == 2 and err.count("\n") == 1 and "--max-memory must be a size" in err


def test_the_progress_bar_is_on_stderr_only_when_asked(capsys):
    u, y = heater_record("inside", 1)
    suggest(u[:2000], y[:2000], FirstOrder(), {"K": (0, 2), "T": (0, 500)}, progress=True, rng=1)
    captured = capsys.readouterr()
    assert "DYNIA windows" in captured.err and captured.out == ""
