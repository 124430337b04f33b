"""The dynia command line: end to end on the DaISy heating system, settings files, bad input."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from cli_cases import BASE, GOOD, HEATING
from hypothesis import given
from hypothesis import strategies as st

from dynia import __version__, load
from dynia.cli import main
from dynia.cli.common import bounds
from dynia.cli.options import UsageError
from dynia.models import FirstOrder

HEATING_ARGS = (
    "--time time --input u --output y --model first-order --param K=0:40 --param T=0:200 "
    "--input-offset 6 --offset first --samples 400 --seed 1"
).split()


def _analyse(capsys, *args):
    status = main(["analyse", *map(str, args)])
    return status, capsys.readouterr().err


def _read_csv(path):
    lines = Path(path).read_text().splitlines()
    header = lines[0].split(",")
    rows = [[float(cell) if cell else np.nan for cell in line.split(",")] for line in lines[1:]]
    return header, np.array(rows)


@pytest.fixture(scope="module")
def heating_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs") / "heating"
    assert main(["analyse", str(HEATING), *HEATING_ARGS, "--out", str(out)]) == 0
    return out


def test_heating_system_end_to_end(heating_run):
    out = heating_run
    expected = {
        "ic.csv",
        "limits.csv",
        "samples.csv",
        "summary.json",
        "data.png",
        "ic_K.png",
        "ic_T.png",
        "identifiability_K.png",
        "identifiability_T.png",
    }
    assert expected <= {path.name for path in out.iterdir()}
    header, ic = _read_csv(out / "ic.csv")
    assert header == ["time", "K", "T", "informative"] and ic.shape == (801, 4)
    assert set(np.unique(ic[:, 3])) <= {0.0, 1.0}  # the noise floor's flag of every window
    np.testing.assert_allclose(ic[:3, 0], [0, 2, 4])
    header, limits = _read_csv(out / "limits.csv")
    assert header == ["time", "K_lower", "K_upper", "T_lower", "T_upper"]
    assert (limits[:, 1] <= limits[:, 2]).all()
    header, samples = _read_csv(out / "samples.csv")
    assert header == ["K", "T"] and samples.shape == (400, 2)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["version"] == __version__
    for name in ("K", "T"):
        entry = summary["parameters"][name]
        # Why the record's highest IC is no evidence, where it is not the window reported.
        assert set(entry) - {"highest_ic_no_evidence"} == {
            "max_ic",
            "time_of_max_ic",
            "band",
            "estimate",
            "highest_ic",
            "time_of_highest_ic",
            "high_ic_windows",
            "high_ic_span",
            "record_fit",
            "record_fit_se",
            "verdict",
            "reasons",
        }
        assert ("highest_ic_no_evidence" in entry) == (entry["time_of_highest_ic"] != entry["time_of_max_ic"])
        assert entry["record_fit_se"] > 0
        assert entry["verdict"] in ("identified", "weak", "suspect")
        assert entry["band"][0] <= entry["estimate"] <= entry["band"][1]
        column = header.index(name)
        assert entry["highest_ic"] == pytest.approx(np.nanmax(ic[:, 1 + column]))
        assert entry["max_ic"] == pytest.approx(ic[ic[:, 0] == entry["time_of_max_ic"], 1 + column][0])
    settings = summary["settings"]
    assert settings["seed"] == 1 and settings["samples"] == 400 and settings["n"] == 10
    assert settings["bounds"] == {"K": [0.0, 40.0], "T": [0.0, 200.0]}
    assert settings["offset_value"] == pytest.approx(129.32) and settings["input_offset_value"] == 6
    assert summary["run"]["n_dropped"] == 0 and summary["warnings"] == []
    assert settings["analysis"]["n_samples"] == 400 and "method" not in settings  # no identify options
    assert summary["command_line"][:2] == ["dynia", "analyse"]
    assert set(summary["versions"]) >= {"dynia", "numpy", "numba"}
    [(path, digest)] = summary["inputs"].items()
    assert path.endswith("heating_system.csv") and len(digest["sha256"]) == 64


def test_heating_system_gain_is_found_among_the_static_gains(heating_run):
    # The settled levels give 17-21 C per volt around the 6 V operating point
    # (9 V -> 192, 4 V -> 86.4, 8 V -> 163.5, 3 V -> 76.9, from 129.3 at 6 V);
    # the plant is not linear, so a first-order model's gain varies with the window.
    summary = json.loads((heating_run / "summary.json").read_text())
    assert 10 < summary["parameters"]["K"]["estimate"] < 25
    assert summary["parameters"]["K"]["max_ic"] > 0.7
    _, ic = _read_csv(heating_run / "ic.csv")
    assert np.nanmedian(ic[:, 1]) > np.nanmedian(ic[:, 2])  # settled levels inform K most of the time


def test_config_file_gives_the_same_run(tmp_path, capsys, heating_run):
    config = tmp_path / "run.toml"
    config.write_text(
        f'data = "{HEATING}"\ntime = "time"\ninput = "u"\noutput = "y"\nmodel = "first-order"\n'
        'param = ["K=0:40", "T=0:200"]\ninput-offset = "6"\noffset = "first"\nsamples = 400\nseed = 1\n'
        f'out = "{tmp_path / "from-config"}"\n'
    )
    status, err = _analyse(capsys, "--config", config)
    assert status == 0, err
    assert (tmp_path / "from-config" / "ic.csv").read_text() == (heating_run / "ic.csv").read_text()


def test_the_command_is_installed_and_answers_version_and_help():
    # The console script sits beside the interpreter of the environment dynia is installed in.
    script = Path(sys.executable).parent / "dynia"
    done = subprocess.run([str(script), "--version"], capture_output=True, text=True)
    assert done.returncode == 0 and done.stdout.strip() == f"dynia {__version__}"
    done = subprocess.run([sys.executable, "-m", "dynia.cli", "analyse", "--help"], capture_output=True, text=True)
    assert done.returncode == 0
    assert "--param NAME=LOW:HIGH" in done.stdout and "heating_system.csv" in done.stdout


def _write(path, text):
    path.write_text(text)
    return path


def _with(extra):
    """BASE with the model and the K range replaced where ``extra`` gives its own."""
    args = list(BASE)
    if "--model" in extra:
        del args[args.index("--model") : args.index("--model") + 2]
    if any(value.startswith("K=") for value in extra):
        del args[args.index("K=0:5") - 1 : args.index("K=0:5") + 1]
    return args + extra


@pytest.mark.parametrize(
    "content, extra, message",
    [
        (None, [], "no such file"),
        ("", [], "empty"),
        ("time,u,y\n", [], ""),
        (GOOD.replace("time,u,y", "time,u,z"), [], "'y'"),
        (GOOD.replace("7,1.0,2.0", "7,1.0,abc"), [], "abc"),
        (GOOD.replace("8,1.0", "6.5,1.0"), [], "increasing"),
        ("time,u,y\n" + "".join(f"{t},1,2\n" for t in range(5)), [], "fewer than one window"),
        (GOOD, ["--param", "K=5:0"], "lower bound"),
        (GOOD, ["--param", "tau=0:1"], "tau"),
        (GOOD, ["--model", "third-order"], "--model"),
        (GOOD, ["--flavour", "glue"], "--flavour"),
        (GOOD, ["--percentage", "1"], "at least 2"),
        (GOOD, ["--conf-level", "100"], "--conf-level"),
        (GOOD, ["--param", "K=0-5"], "NAME=LOW:HIGH"),
        (GOOD, ["--offset", "warm"], "--offset"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_no_output(tmp_path, capsys, content, extra, message):
    data = tmp_path / "data.csv"
    if content is not None:
        _write(data, content)
    out = tmp_path / "out"
    status, err = _analyse(capsys, data, *_with(extra), "--out", out)
    assert status == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("dynia: error:"), err
    assert message in lines[0]
    assert "Traceback" not in err
    assert not out.exists()
    assert not list(tmp_path.glob(".out.*"))


def test_an_existing_output_directory_is_kept_and_overwrite_replaces_only_dynias_own(tmp_path, capsys):
    data = _write(tmp_path / "data.csv", GOOD)
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    status, err = _analyse(capsys, data, *BASE, "--out", out)
    assert status == 2 and "exists" in err and (out / "keep.txt").read_text() == "mine"
    status, err = _analyse(capsys, data, *BASE, "--out", out, "--overwrite")
    assert status == 2 and "dynia did not create it" in err and (out / "keep.txt").read_text() == "mine"
    mine = tmp_path / "results"
    assert _analyse(capsys, data, *BASE, "--out", mine)[0] == 0
    # A file added to dynia's results is not dynia's (issue 20): named and kept until it is moved away.
    (mine / "note.txt").write_text("added later")
    status, err = _analyse(capsys, data, *BASE, "--out", mine, "--overwrite")
    assert status == 2 and "note.txt" in err and (mine / "note.txt").read_text() == "added later"
    (mine / "note.txt").unlink()
    status, err = _analyse(capsys, data, *BASE, "--out", mine, "--overwrite")
    assert status == 0, err
    assert (mine / "summary.json").exists()


def test_an_interrupted_run_leaves_nothing_behind(tmp_path, capsys, monkeypatch):
    import dynia.cli.report

    def interrupted(*args, **kwargs):
        (args[0] / "ic.csv").write_text("half")
        raise KeyboardInterrupt

    monkeypatch.setattr(dynia.cli.report, "write_figures", interrupted)
    data = _write(tmp_path / "data.csv", GOOD)
    status, err = _analyse(capsys, data, *BASE, "--out", tmp_path / "out")
    assert status == 130 and "nothing was written" in err
    assert sorted(path.name for path in tmp_path.iterdir()) == ["data.csv"]


def test_missing_output_values_give_missing_ic(tmp_path, capsys):
    lines = GOOD.splitlines()
    for row in range(20, 30):  # rows of times 19..28: output missing
        time, u, _ = lines[row].split(",")
        lines[row] = f"{time},{u},"
    data = _write(tmp_path / "data.csv", "\n".join(lines) + "\n")
    status, err = _analyse(capsys, data, *BASE, "--n", "1", "--min-points", "2", "--out", tmp_path / "out")
    assert status == 0, err
    _, ic = _read_csv(tmp_path / "out" / "ic.csv")
    assert np.isnan(ic[20:28, 1]).all() and np.isfinite(ic[:18, 1]).all()


finite = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e12, max_value=1e12)


@given(low=finite, width=st.floats(min_value=1e-6, max_value=1e12))
def test_param_ranges_round_trip(low, width):
    high = low + width
    # T is a time constant, which FirstOrder refuses below 0 (issue 20: refused with the --param it comes from).
    t_low, t_high = abs(low), abs(low) + width
    if not (low < high and t_low < t_high):  # width lost to rounding at this magnitude
        return
    ranges = bounds([f"T={t_low!r}:{t_high!r}", f"K={low!r}:{high!r}"], FirstOrder())
    assert ranges == {"T": (t_low, t_high), "K": (low, high)}
    assert list(ranges) == ["T", "K"]  # the order given is the order of the results


@given(text=st.text(max_size=12))
def test_malformed_param_ranges_are_usage_errors(text):
    try:
        ranges = bounds([f"K={text}", "T=0:1"], FirstOrder())
    except UsageError as error:
        assert "\n" not in str(error)
    else:  # only well-formed increasing ranges get through
        low, high = ranges["K"]
        assert low < high


def test_second_run_writes_its_own_results(tmp_path, capsys):
    import dynia

    u = dynia.synthetic.example_firstorder_input()
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(4).normal(0, 0.5, u.size)
    data = _write(
        tmp_path / "example1.csv",
        "time,u,y\n" + "".join(f"{k},{float(a)!r},{float(b)!r}\n" for k, (a, b) in enumerate(zip(u, y))),
    )
    out = tmp_path / "twice"
    status, err = _analyse(
        capsys,
        data,
        "--time",
        "time",
        "--input",
        "u",
        "--output",
        "y",
        "--model",
        "first-order",
        "--param",
        "K=0:7",
        "--param",
        "T=0:7",
        "--seed",
        "1",
        "--second-run",
        "--out",
        out,
    )
    assert status == 0, err
    first = json.loads((out / "summary.json").read_text())
    second = json.loads((out / "second_run" / "summary.json").read_text())
    assert second["settings"]["narrowed"] == ["K", "T"]  # at IC_THRESHOLD 0.5 T's informative windows agree too
    low, high = second["settings"]["bounds"]["K"]
    low_t, high_t = second["settings"]["bounds"]["T"]
    assert 0 < low < 2 < high < 7 and 0 < low_t < 3 < high_t < 7
    assert first["settings"]["bounds"] == {"K": [0.0, 7.0], "T": [0.0, 7.0]}
    assert (out / "second_run" / "ic.csv").exists() and (out / "second_run" / "identifiability_T.png").exists()


# ------------------------------------------------------------------ dynia identify


@pytest.fixture(scope="module")
def heating_identified(tmp_path_factory):
    runs = tmp_path_factory.mktemp("identify")
    for method in ("dynia", "baseline", "whole"):
        assert main(["identify", str(HEATING), *HEATING_ARGS, "--method", method, "--out", str(runs / method)]) == 0
    return {
        method: json.loads((runs / method / "identified.json").read_text()) for method in ("dynia", "baseline", "whole")
    } | {"dir": runs}


def test_identify_writes_the_checked_schema(heating_identified):
    for method in ("dynia", "baseline", "whole"):
        found = heating_identified[method]
        assert set(found["parameters"]) == set(found["std_errors"]) == {"K", "T"}
        assert found["settings"]["method"] == method
        assert np.isfinite(found["validation_error"]) and found["validation_error"] > 0
        segments = np.array(found["segments"], dtype=float)
        assert segments.ndim == 2 and segments.shape[1] == 2 and (segments[:, 1] >= segments[:, 0]).all()
        # The last 30 % of the 801 steps (0 to 1600 s, dt 2 s) is held out, untouched by the fit.
        [(held_start, held_end)] = found["validation_segments"]
        assert held_end == 1600.0 and abs(held_start - 0.7 * 1600) <= 2 and segments.max() < held_start
        assert (heating_identified["dir"] / method / "fit.png").stat().st_size > 10_000
    assert heating_identified["whole"]["segments"] == [[0.0, 1120.0]]


def test_every_selection_finds_the_heating_gain_near_the_static_gains(heating_identified):
    # The record's steady levels give static gains of about 19-21 degC/V (see the analyse test).
    for method in ("dynia", "baseline", "whole"):
        assert 17 < heating_identified[method]["parameters"]["K"] < 23
        assert 40 < heating_identified[method]["parameters"]["T"] < 100


def test_identify_recovers_a_known_model_with_a_glitch_excluded(tmp_path, capsys):
    rng = np.random.default_rng(3)
    u = np.repeat(rng.choice([0.0, 1.0, 2.0], 12), 50)
    y = FirstOrder().simulate([[1.5, 8.0]], u)[0] + rng.normal(0, 0.02, u.size)
    y[130] = 40.0  # one erroneous reading
    _write(
        tmp_path / "data.csv",
        "time,u,y\n" + "".join(f"{k},{float(a)!r},{float(b)!r}\n" for k, (a, b) in enumerate(zip(u, y))),
    )
    common = (
        "--time time --input u --output y --model first-order --param K=0:5 --param T=0:30 --method whole --seed 2"
    ).split()
    assert main(["identify", str(tmp_path / "data.csv"), *common, "--out", str(tmp_path / "raw")]) == 0
    assert (
        main(["identify", str(tmp_path / "data.csv"), *common, "--exclude-flagged", "--out", str(tmp_path / "clean")])
        == 0
    )
    raw, clean = (json.loads((tmp_path / name / "identified.json").read_text()) for name in ("raw", "clean"))
    # The reading is both a glitch (off its neighbours) and an outlier (off the record's range).
    assert {(entry["start_time"], entry["end_time"]) for entry in clean["data_quality"]} == {(130.0, 130.0)}
    assert all(entry["inside_fitted_segments"] for entry in clean["data_quality"])
    for name, truth in (("K", 1.5), ("T", 8.0)):
        assert abs(clean["parameters"][name] - truth) < 3 * clean["std_errors"][name]
    assert clean["fit_rmse"] < raw["fit_rmse"] / 5


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--narrow-margin", "inf", "--second-run"], "--narrow-margin must be a finite number >= 0"),
        (["--narrow-threshold", "0.6"], "--narrow-threshold sets the narrowing of --second-run"),
        (["--narrow-margin", "0.2"], "--narrow-margin sets the narrowing of --second-run"),
        (["--reference", "K=1", "--no-plots"], "--reference draws a line on the figures, and --no-plots draws none"),
    ],
)
def test_an_option_that_would_do_nothing_is_refused(tmp_path, capsys, extra, message):
    """Issue 32: these were accepted and silently ignored (or, --narrow-margin inf, reported T as narrowed)."""
    status = main(["analyse", str(HEATING), *HEATING_ARGS, *extra, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and message in err[0], err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--method", "random"], "--method"),
        (["--ic-threshold", "1.5"], "--ic-threshold must be a number in [0, 1] (IC lies there); got 1.5"),
        (["--held-out", "1"], "--held-out"),
        (["--starts", "0"], "--starts"),
        # Issue 32: numpy's out-of-memory traceback, and --starts 1000000 ran for minutes without a word.
        (["--starts", "10000000000"], "--starts must be at most 10 000 (each start is a least-squares fit"),
        (["--starts", "1000000"], "got 1 000 000"),
    ],
)
def test_identify_bad_options_are_one_line_errors(tmp_path, capsys, extra, message):
    status = main(["identify", str(HEATING), *HEATING_ARGS, *extra, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and message in err[0]
    assert not (tmp_path / "out").exists()


def test_ic_error_reaches_the_table_the_summary_and_ic_csv(tmp_path, capsys):
    out = tmp_path / "with-error"
    assert main(["analyse", str(HEATING), *HEATING_ARGS, "--ic-error", "--no-plots", "--out", str(out)]) == 0
    table = capsys.readouterr().out
    header, ic = _read_csv(out / "ic.csv")
    assert header == ["time", "K", "K_se", "T", "T_se", "informative"]
    summary = json.loads((out / "summary.json").read_text())
    # 400 samples at 10 %: 8 batches of 50 keep 5 behavioural sets each, 10 of 40 would keep 4.
    assert summary["run"]["ic_batches"] == 8 and summary["settings"]["analysis"]["ic_error"] is True
    for column, name in ((1, "K"), (3, "T")):
        best = int(np.flatnonzero(ic[:, 0] == summary["parameters"][name]["time_of_max_ic"])[0])
        assert summary["parameters"][name]["max_ic_se"] == pytest.approx(ic[best, column + 1], rel=1e-12)
        assert f"{summary['parameters'][name]['max_ic']:.3f} +- " in table


def test_target_se_records_its_rounds_and_warns_when_the_budget_runs_out(tmp_path, capsys):
    out = tmp_path / "target"
    args = ["--target-se", "0.001", "--max-samples", "800", "--no-plots", "--out", str(out)]
    assert main(["analyse", str(HEATING), *HEATING_ARGS, *args]) == 0
    assert "dynia: warning: the largest Monte Carlo standard error" in capsys.readouterr().err
    run = json.loads((out / "summary.json").read_text())["run"]
    assert run["n_sampled"] == 800 and run["target_se_met"] is False
    assert [count for count, _ in run["target_se_rounds"]] == [400, 800]


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--target-se", "0.02"], "--target-se and max_samples go together"),
        (["--ic-error", "--samples", "30"], "--ic-error needs at least 2 batches of 5 behavioural sets"),
        (["--target-se", "2", "--max-samples", "900"], "--target-se is an IC standard error in (0, 1)"),
        (["--ic-error", "--flavour", "mcat"], "mcat"),
    ],
)
def test_monte_carlo_error_options_are_checked(tmp_path, capsys, extra, message):
    status, err = _analyse(capsys, HEATING, *HEATING_ARGS, *extra, "--out", tmp_path / "x")
    assert status == 2 and message in err and not (tmp_path / "x").exists()


def test_on_disk_float32_writes_what_the_in_memory_float32_run_writes(tmp_path, capsys):
    common = [*HEATING_ARGS, "--dtype", "float32", "--no-plots"]
    assert main(["analyse", str(HEATING), *common, "--on-disk", "--out", str(tmp_path / "disk")]) == 0
    assert main(["analyse", str(HEATING), *common, "--out", str(tmp_path / "memory")]) == 0
    for name in ("ic.csv", "limits.csv", "samples.csv"):
        assert (tmp_path / "disk" / name).read_bytes() == (tmp_path / "memory" / name).read_bytes(), name
    disk, memory = load(tmp_path / "disk" / "result.nc"), load(tmp_path / "memory" / "result.nc")
    assert disk.gradient.dtype == np.float32
    np.testing.assert_array_equal(disk.gradient, memory.gradient)
    header, _ = _read_csv(tmp_path / "disk" / "ic.csv")
    assert header == ["time", "K", "T", "informative"]
    assert json.loads((tmp_path / "disk" / "summary.json").read_text())["settings"]["analysis"]["dtype"] == "float32"


def test_a_dated_record_gives_every_time_of_the_summary_as_a_date(tmp_path, capsys):
    # Every time of a parameter's entry is in the file's terms: the highest IC's too, so that the table
    # does not take the same window, once as a date and once as seconds, for two.
    lines = HEATING.read_text().splitlines()
    start = np.datetime64("2012-01-01T00:00:00")
    dated = [lines[0]] + [
        f"{start + np.timedelta64(int(float(line.split(',')[0])), 's')},{line.split(',', 1)[1]}" for line in lines[1:]
    ]
    path = tmp_path / "dated.csv"
    path.write_text("\n".join(dated) + "\n")
    out = tmp_path / "out"
    assert main(["analyse", str(path), *HEATING_ARGS, "--no-plots", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    parameters = json.loads((out / "summary.json").read_text())["parameters"]
    for name, entry in parameters.items():
        for key in ("time_of_max_ic", "time_of_highest_ic"):
            assert isinstance(entry[key], str) and entry[key].startswith("2012-01-01"), (name, key, entry[key])
        if entry["time_of_highest_ic"] == entry["time_of_max_ic"]:
            assert f"{name}: the record's highest IC" not in printed
