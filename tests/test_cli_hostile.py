"""The command line under hostile but realistic use: it never destroys user files, never invents or drops data
silently, refuses settings that make results meaningless, and says what its results are worth.

Every case checks the exit status, that an error is exactly one ``dynia: error:`` line naming the option or
column at fault, that neither stream carries a traceback or a numpy/matplotlib warning, that the user's files
are byte-identical afterwards, and that no staging (``.partial``) or lock litter is left behind.
"""

import hashlib
import json
import os
import re
import signal
import stat
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from cli_cases import (
    BASE,
    GOOD,
    HEATING,
    assert_clean_streams,
    cli_analyse,
    cli_one_error,
    cli_run,
    cli_succeeded,
    tree_state,
    write_text_file,
)
from skips import skip_if_signal_ignored

import dynia
import dynia.cli
import dynia.cli.report
from dynia.io.outdir import MARKER, OutputDirectory
from dynia.models import FOPDT, TransferFunction
from dynia.pipeline import DroppedSamplesWarning
from dynia.verdicts import VERDICTS


def _csv(path, time, u, y):
    """A wide CSV of time, u, y; a NaN in y becomes an empty cell."""
    rows = [f"{float(t)!r},{float(a)!r},{'' if np.isnan(b) else repr(float(b))}" for t, a, b in zip(time, u, y)]
    return write_text_file(path, "time,u,y\n" + "\n".join(rows) + "\n")


def _litter(directory):
    """Staging, lock or retired-output names dynia left under ``directory``."""
    return sorted(
        str(item)
        for item in Path(directory).rglob("*")
        if ".partial" in item.name or item.name.endswith(".dynia-lock") or ".old-" in item.name
    )


def _summary(out):
    return json.loads((Path(out) / "summary.json").read_text())


def _ic_table(path):
    lines = Path(path).read_text().splitlines()
    header = lines[0].split(",")
    rows = [[float(cell) if cell else np.nan for cell in line.split(",")] for line in lines[1:]]
    return header, np.array(rows)


@pytest.fixture
def good(tmp_path):
    return write_text_file(tmp_path / "data.csv", GOOD)


@pytest.fixture
def never_analysed(monkeypatch):
    """Fail the test if the analysis or the data loading starts: errors must come before any work."""

    def refuse(*args, **kwargs):
        raise AssertionError("the analysis started although the command should have stopped before")

    # Reading the data is every command's first work: the analysis cannot start without it.
    monkeypatch.setattr("dynia.cli.common.load_csv", refuse)


# ------------------------------------------------------------------ output directory: never destroy anything


@pytest.mark.parametrize("overwrite", [[], ["--overwrite"]])
def test_out_equal_to_the_input_file_is_refused(tmp_path, capsys, good, never_analysed, overwrite):
    before = tree_state(tmp_path)
    line = cli_one_error(*cli_analyse(capsys, good, *BASE, "--out", good, *overwrite), "--out")
    assert tree_state(tmp_path) == before and good.read_text() == GOOD, line
    assert _litter(tmp_path) == []


def test_out_equal_to_the_inputs_directory_with_overwrite_is_refused(tmp_path, capsys, never_analysed):
    folder = tmp_path / "plant"
    folder.mkdir()
    data = write_text_file(folder / "data.csv", GOOD)
    write_text_file(folder / "notes.txt", "my notes")
    # Even a folder that looks like dynia's own results is refused when it holds the input.
    write_text_file(folder / MARKER, json.dumps({"created_by": "dynia"}))
    before = tree_state(tmp_path)
    cli_one_error(*cli_analyse(capsys, data, *BASE, "--out", folder, "--overwrite"), "--out")
    assert tree_state(tmp_path) == before
    assert _litter(tmp_path) == []


@pytest.mark.parametrize("out", [".", ".."])
def test_out_current_directory_or_its_parent_is_refused(tmp_path, capsys, monkeypatch, out):
    (tmp_path / "inputs").mkdir()
    data = write_text_file(tmp_path / "inputs" / "data.csv", GOOD)
    # The working directory is the results of an earlier run (marker and all), inside a user project.
    project = tmp_path / "project"
    project.mkdir()
    write_text_file(project / "analysis.py", "print('mine')\n")
    previous = project / "results"
    cli_succeeded(*cli_analyse(capsys, data, *BASE, "--out", previous))
    monkeypatch.chdir(previous)
    before = tree_state(tmp_path)

    def refuse(*args, **kwargs):
        raise AssertionError("the analysis started")

    monkeypatch.setattr("dynia.cli.common.load_csv", refuse)
    cli_one_error(*cli_analyse(capsys, data, *BASE, "--out", out, "--overwrite"), "--out")
    cli_one_error(*cli_analyse(capsys, data, *BASE, "--out", out), "--out")
    assert tree_state(tmp_path) == before
    assert _litter(tmp_path) == []


@pytest.mark.parametrize("marker", [None, "", "not json", json.dumps({"created_by": "someone else"})])
def test_overwrite_refuses_a_user_directory_without_dynias_marker(tmp_path, capsys, good, never_analysed, marker):
    mine = tmp_path / "mine"
    mine.mkdir()
    write_text_file(mine / "thesis.tex", "\\chapter{Results}\n")
    (mine / "figures").mkdir()
    write_text_file(mine / "figures" / "plot.txt", "1 2 3\n")
    if marker is not None:
        write_text_file(mine / MARKER, marker)
    before = tree_state(tmp_path)
    cli_one_error(*cli_analyse(capsys, good, *BASE, "--out", mine, "--overwrite"), "--out")
    assert tree_state(tmp_path) == before
    assert _litter(tmp_path) == []


def test_overwrite_replaces_an_earlier_dynia_run(tmp_path, capsys, good):
    out = tmp_path / "results"
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--out", out))
    # Files added since are not dynia's (issue 20): named, and the directory left alone, until they are moved away.
    write_text_file(out / "stale.txt", "from before")
    (out / "old-subdir").mkdir()
    assert _summary(out)["settings"]["seed"] == 2
    data_before = tree_state(good)
    kept = tree_state(out)
    cli_one_error(
        *cli_analyse(capsys, good, *BASE, "--seed", "7", "--out", out, "--overwrite"), "stale.txt", "old-subdir"
    )
    assert tree_state(out) == kept
    (out / "stale.txt").unlink()
    (out / "old-subdir").rmdir()
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--seed", "7", "--out", out, "--overwrite"))
    names = {item.name for item in out.iterdir()}
    assert {"summary.json", "ic.csv", MARKER} <= names
    assert _summary(out)["settings"]["seed"] == 7
    assert tree_state(good) == data_before
    assert _litter(tmp_path) == []
    assert sorted(item.name for item in tmp_path.iterdir()) == ["data.csv", "results"]


def test_unwritable_parent_is_an_error_before_analysis(tmp_path, capsys, good, never_analysed):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if os.geteuid() == 0:
            # Root ignores permission bits: if the write succeeds there is nothing to test here.
            probe = locked / "probe"
            probe.mkdir()
            probe.rmdir()
            pytest.skip("running as root: a 0o500 directory is writable, the refusal cannot be provoked")
        before = tree_state(tmp_path)
        started = time.monotonic()
        cli_one_error(*cli_analyse(capsys, good, *BASE, "--out", locked / "out"), "--out")
        assert time.monotonic() - started < 5
        assert tree_state(tmp_path) == before
        assert _litter(tmp_path) == []
    finally:
        locked.chmod(0o700)


def test_a_parent_that_is_a_file_is_an_error_before_analysis(tmp_path, capsys, good, never_analysed):
    # The same refusal as for an unwritable parent, provokable as root too: nobody can create a directory in a file.
    notes = write_text_file(tmp_path / "notes.txt", "mine\n")
    before = tree_state(tmp_path)
    cli_one_error(*cli_analyse(capsys, good, *BASE, "--out", notes / "out"), "--out")
    assert tree_state(tmp_path) == before
    assert _litter(tmp_path) == []


def test_a_second_run_on_the_same_out_fails_fast_with_a_lock_message(tmp_path, capsys, good, never_analysed):
    out = tmp_path / "results"
    first = OutputDirectory(out, inputs=[good], command="analyse")
    staging = first.__enter__()
    try:
        write_text_file(staging / "summary.json", '{"first": true}\n')
        started = time.monotonic()
        line = cli_one_error(*cli_analyse(capsys, good, *BASE, "--out", out), "--out")
        assert time.monotonic() - started < 5
        assert "another dynia run" in line or "lock" in line, line
        # The second run neither took nor removed the first one's staging directory or lock file, so a third
        # run is refused too.
        assert (staging / "summary.json").read_text() == '{"first": true}\n'
        assert (tmp_path / ".results.dynia-lock").exists()
        cli_one_error(*cli_analyse(capsys, good, *BASE, "--out", out, "--overwrite"), "--out")
        assert (staging / "summary.json").read_text() == '{"first": true}\n'
    except BaseException:
        first.__exit__(*sys.exc_info())
        raise
    first.__exit__(None, None, None)
    assert (out / "summary.json").read_text() == '{"first": true}\n'
    assert _litter(tmp_path) == []


def test_out_appearing_during_the_run_is_left_alone_and_the_results_kept_beside_it(tmp_path, capsys, good, monkeypatch):
    out = tmp_path / "results"
    original = dynia.cli.report.write_analysis

    def racing_writer(directory, *args, **kwargs):
        # Another program (or the user) creates --out while dynia is busy.
        out.mkdir()
        write_text_file(out / "theirs.txt", "written by someone else\n")
        return original(directory, *args, **kwargs)

    monkeypatch.setattr(dynia.cli.report, "write_analysis", racing_writer)
    status, stdout, err = cli_analyse(capsys, good, *BASE, "--out", out)
    line = cli_one_error(status, stdout, err, "--out")
    assert sorted(item.name for item in out.iterdir()) == ["theirs.txt"]
    assert (out / "theirs.txt").read_text() == "written by someone else\n"
    [kept] = [item for item in tmp_path.iterdir() if item.name.startswith("results.dynia-")]
    assert str(kept) in line, line
    assert (kept / "summary.json").exists() and (kept / "ic.csv").exists() and (kept / MARKER).exists()
    assert _litter(tmp_path) == []


def _slow_run_files(folder):
    """A record large enough that 20 000 samples take seconds."""
    rng = np.random.default_rng(0)
    u = np.repeat(rng.choice([0.0, 1.0, 2.0], 40), 50)
    y = 2 * u + rng.normal(0, 0.1, u.size)
    return _csv(folder / "big.csv", np.arange(u.size), u, y)


# Slow (about 3 s each): a subprocess imports dynia and starts a run of seconds before the signal arrives.
@pytest.mark.parametrize("name, status", [("SIGTERM", 143), ("SIGHUP", 129)])
def test_a_signal_during_the_run_leaves_nothing_behind(tmp_path, name, status):
    skip_if_signal_ignored(name)
    data = _slow_run_files(tmp_path)
    out = tmp_path / "results"
    before = tree_state(data)
    command = [
        sys.executable,
        "-m",
        "dynia.cli",
        "analyse",
        str(data),
        "--time",
        "time",
        "--input",
        "u",
        "--output",
        "y",
        "--model",
        "first-order",
        "--param",
        "K=0:5",
        "--param",
        "T=0:5",
        "--samples",
        "20000",
        "--seed",
        "1",
        "--out",
        str(out),
    ]
    process = subprocess.Popen(command, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 30
        # The staging directory exists once the run has started and its signal handlers are in place.
        while not list(tmp_path.glob(".results.partial-*")):
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "the run never started"
            time.sleep(0.05)
        time.sleep(0.5)
        assert process.poll() is None, "the run finished before the signal: make it larger"
        process.send_signal(getattr(signal, name))
        stdout, stderr = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == status, stderr
    assert_clean_streams(stdout, stderr)
    assert stderr.splitlines() == [f"dynia: interrupted by {name}; nothing was written"], stderr
    assert not os.path.lexists(out)
    assert _litter(tmp_path) == []
    assert tree_state(data) == before


@pytest.mark.parametrize("umask, file_mode, directory_mode", [(0o022, 0o644, 0o755), (0o027, 0o640, 0o750)])
def test_result_permissions_follow_the_umask(tmp_path, capsys, good, umask, file_mode, directory_mode):
    out = tmp_path / "results"
    previous = os.umask(umask)
    try:
        cli_succeeded(*cli_analyse(capsys, good, *BASE, "--out", out))
    finally:
        os.umask(previous)
    assert stat.S_IMODE(out.stat().st_mode) == directory_mode
    files = [item for item in out.rglob("*") if item.is_file()]
    assert {item.name for item in files} >= {"summary.json", "ic.csv", MARKER}
    assert {item.name: oct(stat.S_IMODE(item.stat().st_mode)) for item in files} == {
        item.name: oct(file_mode) for item in files
    }


# ------------------------------------------------------------------ data: no invented data, no silent drops


def test_a_gap_in_the_time_column_is_left_missing_and_reported(tmp_path, capsys):
    # 1 s rows from 0 to 59 without the rows of 20..29 s: 11 s (> 5 grid steps) without data.
    time = np.array([t for t in range(60) if not 20 <= t <= 29], dtype=float)
    u = (time >= 10).astype(float)
    y = 2 * (1 - np.exp(-np.clip(time - 10, 0, None) / 3))
    data = _csv(tmp_path / "gappy.csv", time, u, y)
    out = tmp_path / "results"
    status, stdout, err = cli_analyse(capsys, data, *BASE, "--out", out)
    cli_succeeded(status, stdout, err)
    warned = [line for line in err.splitlines() if line.startswith("dynia: warning:")]
    assert len(warned) == 1, err
    numbers = {float(value) for value in re.findall(r"-?\d+(?:\.\d+)?", warned[0].split(":", 2)[2])}
    assert {20.0, 29.0} <= numbers or {19.0, 30.0} <= numbers, warned
    header, ic = _ic_table(out / "ic.csv")
    assert header == ["time", "K", "T", "informative"]
    np.testing.assert_array_equal(ic[:, 0], np.arange(60.0))  # one row per grid step, the gap included
    # Windows (n = 3) lying wholly inside the gap hold no measurement: their IC is missing, not invented,
    # and they inform about nothing.
    inside = (ic[:, 0] >= 23) & (ic[:, 0] <= 26)
    assert np.isnan(ic[inside, 1:3]).all() and (ic[inside, 3] == 0).all()
    assert np.isfinite(ic[(ic[:, 0] <= 15) | (ic[:, 0] >= 34), 1:3]).all()
    summary = _summary(out)
    assert summary["data"]["gaps"], summary["data"]
    [(first, last)] = summary["data"]["gaps"]
    assert 19 <= first <= 20 and 29 <= last <= 30
    assert any("20" in text or "19" in text for text in summary["warnings"]), summary["warnings"]


def test_a_burst_of_close_rows_does_not_shrink_the_grid(tmp_path, capsys):
    regular = np.arange(100.0)
    burst = 40 + 0.001 * np.arange(1, 51)  # 50 rows 1 ms apart, between the rows of 40 s and 41 s
    time = np.sort(np.r_[regular, burst])
    u = (time >= 10).astype(float)
    y = 2 * (1 - np.exp(-np.clip(time - 10, 0, None) / 3))
    data = _csv(tmp_path / "burst.csv", time, u, y)
    out = tmp_path / "results"
    cli_succeeded(*cli_analyse(capsys, data, *BASE, "--out", out))
    summary = _summary(out)
    assert summary["data"]["dt"] == pytest.approx(1.0, rel=0.05)
    assert summary["data"]["n_steps"] <= 200
    assert sum(1 for _ in open(out / "ic.csv")) <= 201


@pytest.mark.parametrize("column", ["y", "u"])
def test_an_absurd_value_is_reported_never_a_traceback(tmp_path, capsys, column):
    text = GOOD.replace("20,1.0,2.0", "20,1e308,2.0" if column == "u" else "20,1.0,1e308")
    assert text != GOOD
    data = write_text_file(tmp_path / "data.csv", text)
    out = tmp_path / "results"
    status, stdout, err = cli_analyse(capsys, data, *BASE, "--out", out)
    assert_clean_streams(stdout, err)
    assert all(line.startswith("dynia:") for line in err.splitlines()), err
    warned = [line for line in err.splitlines() if line.startswith("dynia: warning:") and "1e+308" in line]
    assert status in (0, 2), err
    if status == 0:
        assert warned, err
        assert any("1e+308" in line for line in _summary(out)["warnings"])
    else:
        assert len(err.splitlines()) == 1 and "1e+308" in err, err
    assert tree_state(data) == {".": (hashlib.sha256(text.encode()).hexdigest(), stat.S_IMODE(data.stat().st_mode))}
    assert _litter(tmp_path) == []


@pytest.mark.parametrize("column", ["y", "u"])
def test_an_absurd_value_is_a_magnitude_finding_with_quality(tmp_path, capsys, column):
    text = GOOD.replace("20,1.0,2.0", "20,1e308,2.0" if column == "u" else "20,1.0,1e308")
    data = write_text_file(tmp_path / "data.csv", text)
    out = tmp_path / "results"
    status, stdout, err = cli_analyse(capsys, data, *BASE, "--out", out)
    cli_succeeded(status, stdout, err)
    findings = _summary(out)["data_quality"]
    magnitude = [entry for entry in findings if entry["kind"] == "magnitude"]
    assert len(magnitude) == 1, findings
    assert magnitude[0]["start_time"] == magnitude[0]["end_time"] == 20
    assert magnitude[0]["signal"] in ("input" if column == "u" else "output", column)


def _unstable_lag():
    """K/(s - a): stable for a < 0, overflowing over 100 steps for a above about 7.1."""
    import control

    return TransferFunction(lambda p: control.tf([p[0]], [1.0, -p[1]]), names=("K", "a"))


def test_dropping_more_than_one_percent_of_the_samples_warns_in_the_api():
    u = np.r_[np.zeros(10), np.ones(90)]
    model = _unstable_lag()
    y = model.simulate([[1.0, -0.5]], u)[0]
    with pytest.warns(DroppedSamplesWarning, match="dropped"):
        result = dynia.run(u, y, model, {"K": (0.5, 2.0), "a": (-1.0, 20.0)}, n_samples=200, n=3, rng=1)
    dropped = result.run.n_dropped
    assert dropped > 0.5 * 200 and result.samples.shape[0] == 200 - dropped
    # e^(a t) over the 90 steps after the input step overflows from a = 709.8 / 90 = 7.9 on.
    assert 7 < result.samples[:, 1].max() < 8.1 and np.isfinite(result.ic).any()
    assert np.isfinite(model.simulate(result.samples, u)).all()
    with warnings.catch_warnings():
        warnings.simplefilter("error", DroppedSamplesWarning)  # a stable box drops nothing and stays quiet
        stable = dynia.run(u, y, model, {"K": (0.5, 2.0), "a": (-1.0, -0.1)}, n_samples=200, n=3, rng=1)
    assert stable.run.n_dropped == 0


def test_a_parameter_range_where_the_arithmetic_overflows_is_refused(tmp_path, capsys, good, never_analysed):
    args = [arg if arg != "K=0:5" else "K=0:1e308" for arg in BASE]
    cli_one_error(*cli_analyse(capsys, good, *args, "--out", tmp_path / "out"), "--param K", "1e+150")


@pytest.mark.parametrize("plots", [["--no-plots"], []])
def test_dropping_more_than_one_percent_of_the_samples_is_in_the_summary(tmp_path, capsys, good, plots, monkeypatch):
    # No built-in model overflows inside the ranges the command line accepts, so the model is
    # made to report 5 % of its sets as not finite; what is checked is how the command reports it.
    def finite_but_every_twentieth(self, params, u, dt=1.0, x0="zero"):
        finite = np.ones(np.asarray(params).shape[0], dtype=bool)
        finite[::20] = False
        return finite

    monkeypatch.setattr(dynia.models.FirstOrder, "finite_samples", finite_but_every_twentieth)
    out = tmp_path / "results"
    status, stdout, err = cli_analyse(capsys, good, *BASE, *plots, "--out", out)
    cli_succeeded(status, stdout, err)
    summary = _summary(out)
    assert summary["run"]["n_dropped"] == 5 and summary["run"]["n_sampled"] == 100
    assert any("5 of 100 parameter sets (5.0 %) were dropped" in text for text in summary["warnings"])
    assert any(line.startswith("dynia: warning:") and "dropped" in line for line in err.splitlines()), err


# ------------------------------------------------------------------ settings that make results meaningless


@pytest.mark.parametrize(
    "value, needles",
    [("0.9", ["--conf-level", "90"]), ("40", ["--conf-level"]), ("100", ["--conf-level"]), ("nan", ["--conf-level"])],
)
def test_conf_level_out_of_range_is_an_error(tmp_path, capsys, good, never_analysed, value, needles):
    cli_one_error(*cli_analyse(capsys, good, *BASE, "--conf-level", value, "--out", tmp_path / "out"), *needles)
    assert not (tmp_path / "out").exists() and _litter(tmp_path) == []


def test_conf_level_90_is_fine(tmp_path, capsys, good):
    out = tmp_path / "out"
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--conf-level", "90", "--out", out))
    assert _summary(out)["settings"]["analysis"]["conf_level"] == 90


def test_min_points_above_the_window_is_an_error(tmp_path, capsys, good, never_analysed):
    # --n 3: a window holds 7 steps.
    cli_one_error(*cli_analyse(capsys, good, *BASE, "--min-points", "8", "--out", tmp_path / "out"), "--min-points")
    assert not (tmp_path / "out").exists()


def test_min_points_equal_to_the_window_is_fine(tmp_path, capsys, good):
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--min-points", "7", "--out", tmp_path / "out"))


def test_the_same_column_as_input_and_output_is_an_error(tmp_path, capsys, good, never_analysed):
    args = [arg if arg != "y" else "u" for arg in BASE]
    line = cli_one_error(*cli_analyse(capsys, good, *args, "--out", tmp_path / "out"), "--input", "--output")
    assert "'u'" in line
    assert not (tmp_path / "out").exists()


TWO_INPUTS = "time,u,u2,y\n" + "".join(
    f"{t},{1.0 if t > 5 else 0.0},{t % 3},{2.0 if t > 6 else 0.0}\n" for t in range(40)
)


def test_a_repeated_input_is_an_error(tmp_path, capsys, never_analysed):
    data = write_text_file(tmp_path / "two.csv", TWO_INPUTS)
    line = cli_one_error(*cli_analyse(capsys, data, *BASE, "--input", "u2", "--out", tmp_path / "out"), "--input")
    assert "one" in line
    assert not (tmp_path / "out").exists()


def test_two_inputs_in_a_config_file_are_an_error(tmp_path, capsys, never_analysed):
    data = write_text_file(tmp_path / "two.csv", TWO_INPUTS)
    config = write_text_file(tmp_path / "run.toml", 'input = ["u", "u2"]\n')
    args = [arg for arg in BASE if arg not in ("--input", "u")]
    line = cli_one_error(*cli_analyse(capsys, data, *args, "--config", config, "--out", tmp_path / "out"), "--input")
    assert "one" in line


@pytest.mark.parametrize("bins", ["1001", "0"])
def test_bins_out_of_range_is_an_error(tmp_path, capsys, good, never_analysed, bins):
    cli_one_error(*cli_analyse(capsys, good, *BASE, "--bins", bins, "--out", tmp_path / "out"), "--bins")


@pytest.mark.parametrize(
    "line, key",
    [
        ('overwrite = "false"', "overwrite"),
        ('percentage = "10"', "percentage"),
        ("samples = 2.5", "samples"),
        ('second-run = "no"', "second"),
        ("n = true", "n"),
    ],
)
def test_config_values_of_the_wrong_type_are_errors_never_truthy(tmp_path, capsys, good, never_analysed, line, key):
    out = tmp_path / "results"
    # An earlier dynia run: were "false" read as true, the run would replace it.
    out.mkdir()
    write_text_file(out / MARKER, json.dumps({"created_by": "dynia"}))
    write_text_file(out / "summary.json", '{"old": true}\n')
    config = write_text_file(tmp_path / "run.toml", line + "\n")
    before = tree_state(tmp_path)
    message = cli_one_error(*cli_analyse(capsys, good, *BASE, "--config", config, "--out", out), key)
    assert "--config" in message or str(config) in message
    assert tree_state(tmp_path) == before
    assert _litter(tmp_path) == []


def test_a_time_constant_range_below_the_grid_step_is_handled(tmp_path, capsys, good):
    # Every T in 0..0.001 s is a static gain at dt = 1 s: the run either works or says so naming --param T.
    args = [arg if arg != "T=0:5" else "T=0:0.001" for arg in BASE]
    out = tmp_path / "results"
    status, stdout, err = cli_analyse(capsys, good, *args, "--out", out)
    if status == 0:
        cli_succeeded(status, stdout, err)
        assert set(_summary(out)["parameters"]) == {"K", "T"}
    else:
        cli_one_error(status, stdout, err, "--param T")
        assert not out.exists()
    assert _litter(tmp_path) == []


# ------------------------------------------------------------------ results that say what they found


def test_success_prints_a_verdict_table(tmp_path, capsys, good):
    status, stdout, err = cli_analyse(capsys, good, *BASE, "--out", tmp_path / "out")
    cli_succeeded(status, stdout, err)
    # The table's rows start at the margin; the reasons under it are indented.
    lines = [line for line in stdout.splitlines() if line and not line[0].isspace()]
    assert lines[0].split()[0] == "parameter" and lines[0].split()[-1] == "verdict", stdout
    assert len(lines) == 4 and lines[3].startswith("noise floor: "), stdout
    summary = _summary(tmp_path / "out")
    share = summary["noise_floor"]["informative_share"]
    assert f"{100 * share:.0f} % of the windows informative" in lines[3]
    for name in ("K", "T"):
        [row] = [line for line in lines if line.split() and line.split()[0] == name]
        assert row.split()[-1] in VERDICTS and row.split()[-1] == summary["parameters"][name]["verdict"], row


# Slow (about 5 s): the README's full run, 2000 samples on 801 steps.
def test_heating_record_verdicts_as_in_the_readme(tmp_path, capsys):
    out = tmp_path / "heating"
    status, stdout, err = cli_analyse(
        capsys,
        HEATING,
        "--time",
        "time",
        "--input",
        "u",
        "--output",
        "y",
        "--model",
        "first-order",
        "--param",
        "K=0:40",
        "--param",
        "T=0:200",
        "--input-offset",
        "6",
        "--offset",
        "first",
        "--x0",
        "zero",
        "--seed",
        "1",
        "--out",
        out,
    )
    cli_succeeded(status, stdout, err)
    parameters = _summary(out)["parameters"]
    assert _summary(out)["settings"]["analysis"]["n_samples"] == 2000
    # T's highest IC (1580 s, band on the bound, tied within noise) is no evidence; the transient at 836 s is.
    assert parameters["T"]["verdict"] == "identified" and parameters["T"]["time_of_highest_ic"] == 1580.0
    assert "T: the record's highest IC, 0.917 at 1580.0, is in a window that is no evidence" in stdout
    # The gain's highest IC passes that window's rules, but the last plateau's windows rule out the 9 V ones.
    assert parameters["K"]["verdict"] == "suspect"
    assert [reason["code"] for reason in parameters["K"]["reasons"]] == ["windows_disagree"]
    assert parameters["K"]["high_ic_windows"] == 327 and parameters["K"]["high_ic_span"] == [122.0, 1420.0]
    assert (
        "K          0.884   398.0  [19.22, 23.88]  21.76     19.59 +- 0.49  327      122.0  1420.0  suspect" in stdout
    )
    assert (
        "T          0.846   836.0  [41.3, 72.14]   55.75     68.28 +- 4.5   181      6.0    1430.0  identified"
        in stdout
    )
    assert "is in a window that is no evidence (its behavioural set tied within noise)" in stdout


def test_a_dead_time_peaking_in_a_tied_window_at_the_record_start_is_reported_where_it_is_evidence(tmp_path, capsys):
    # A step at 2 s into K e^(-theta s)/(T s + 1) with theta = 3 s: theta's IC peaks at 3 s (for every seed
    # tried), in a whole window next to the record's start whose behavioural set ties within noise. The table
    # reports the highest IC among the windows that are evidence, and says where the record's highest lies.
    time = np.arange(60.0)
    u = (time >= 2).astype(float)
    y = FOPDT().simulate([[2.0, 10.0, 3.0]], u)[0] + np.random.default_rng(5).normal(0, 0.01, time.size)
    data = _csv(tmp_path / "step.csv", time, u, y)
    out = tmp_path / "results"
    status, stdout, err = cli_analyse(
        capsys,
        data,
        "--time",
        "time",
        "--input",
        "u",
        "--output",
        "y",
        "--model",
        "fopdt",
        "--param",
        "K=0:5",
        "--param",
        "T=0:20",
        "--param",
        "theta=0:5",
        "--samples",
        "400",
        "--n",
        "3",
        "--seed",
        "3",
        "--out",
        out,
    )
    cli_succeeded(status, stdout, err)
    theta = _summary(out)["parameters"]["theta"]
    assert theta["time_of_highest_ic"] == 3 and theta["time_of_max_ic"] == 5, theta
    assert theta["band"][0] <= 3.0 <= theta["band"][1] and theta["verdict"] == "identified", theta
    assert "theta: the record's highest IC, 0.775 at 3.0, is in a window that is no evidence" in stdout


def test_no_plots_writes_no_figures(tmp_path, capsys, good):
    out = tmp_path / "results"
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--no-plots", "--out", out))
    assert list(out.rglob("*.png")) == []
    assert (out / "summary.json").exists() and (out / "ic.csv").exists()


ANALYSE_ONLY = {
    "sampler",
    "bins",
    "conf_level",
    "flavour",
    "min_points",
    "second_run",
    "narrow_threshold",
    "narrow_margin",
}
IDENTIFY_ONLY = {"method", "ic_threshold", "mode", "held_out", "exclude_flagged", "starts"}


def test_each_summary_records_only_its_commands_options(tmp_path, capsys):
    time = np.arange(120.0)
    u = np.repeat([0.0, 1.0, 0.5, 2.0], 30)
    y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(1).normal(0, 0.01, u.size)
    data = _csv(tmp_path / "steps.csv", time, u, y)
    cli_succeeded(*cli_run(capsys, "identify", data, *BASE, "--out", tmp_path / "fit"))
    identified = json.loads((tmp_path / "fit" / "identified.json").read_text())
    assert IDENTIFY_ONLY <= set(identified["settings"]), sorted(identified["settings"])
    assert sorted(ANALYSE_ONLY & set(identified["settings"])) == []
    cli_succeeded(*cli_analyse(capsys, data, *BASE, "--out", tmp_path / "dynia"))
    analysed = _summary(tmp_path / "dynia")
    assert ANALYSE_ONLY <= set(analysed["settings"]), sorted(analysed["settings"])
    assert sorted(IDENTIFY_ONLY & set(analysed["settings"])) == []
