"""What the dynia command says while it works (progress on a terminal's stderr only) and what identify prints."""

import json
import re
import sys

import numpy as np
import pytest
from cli_cases import HEATING, cli_run, cli_succeeded

import dynia
from dynia.engine import kernels, twin
from dynia.models import FirstOrder

HEATING_ARGS = (
    "--time time --input u --output y --model first-order --param K=0:40 --param T=0:200 "
    "--input-offset 6 --offset first --x0 zero --samples 400 --seed 1"
).split()

# What the progress of a run puts on stderr: tqdm's bar, the compilation notice, the "wrote DIR" line.
BAR = "DYNIA windows"
NOTICE = "dynia: compiling the analysis kernels"
WROTE = "dynia: wrote"


def on_terminal(monkeypatch):
    """stderr seen as a terminal (pytest's captured stderr is not one).

    Called in the test itself: capsys puts its own stderr in place only when the test runs, after the fixtures.
    """
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)


def _identify(capsys, tmp_path, *extra):
    out = tmp_path / "fit"
    status, stdout, stderr = cli_run(capsys, "identify", HEATING, *HEATING_ARGS, "--no-plots", *extra, "--out", out)
    assert status == 0, stderr
    return stdout, stderr, json.loads((out / "identified.json").read_text())


def _table(stdout):
    """{parameter: (estimate, std error, HAC std error)} parsed from identify's printed table."""
    lines = stdout.splitlines()
    header = next(index for index, line in enumerate(lines) if line.split()[:2] == ["parameter", "estimate"])
    rows = {}
    for line in lines[header + 1 :]:
        if line.startswith(" "):
            break
        name, *numbers = line.split()
        rows[name] = tuple(float(number) for number in numbers[:3])
    return rows


def test_identify_prints_the_estimates_errors_and_validation_error_of_identified_json(tmp_path, capsys):
    stdout, stderr, found = _identify(capsys, tmp_path)
    table = _table(stdout)
    assert set(table) == {"K", "T"}
    for name, (estimate, classical, hac) in table.items():
        # Six significant digits of the file's numbers.
        assert estimate == pytest.approx(found["parameters"][name], rel=1e-5)
        assert classical == pytest.approx(found["std_errors"][name], rel=1e-5)
        assert hac == pytest.approx(found["std_errors_hac"][name], rel=1e-5)
    [validation] = re.findall(r"validation error: RMSE (\S+) on the held-out part \((\d+) steps", stdout)
    assert float(validation[0]) == pytest.approx(found["validation_error"], rel=1e-5)
    assert int(validation[1]) == 240  # the last 30 % of 801 steps
    [share] = re.findall(r"--method dynia selected (\S+) % of the fitting part \((\d+) steps in (\d+) segment", stdout)
    assert float(share[0]) == pytest.approx(100 * found["selected_share"], abs=0.05)
    assert int(share[2]) == len(found["segments"])
    # Not a terminal: stderr holds warnings at most, no progress.
    cli_succeeded(0, stdout, stderr)
    assert all(line.startswith("dynia: warning:") for line in stderr.splitlines()), stderr


def on_kernels(monkeypatch):
    """Every run of "auto" on the compiled kernels, as a run too large for their numpy twin goes."""
    monkeypatch.setattr(twin, "AUTO_MOST_VALUES", 0)


def test_a_terminal_shows_progress_on_stderr_and_never_on_stdout(tmp_path, capsys, fresh_process, monkeypatch):
    on_terminal(monkeypatch)
    on_kernels(monkeypatch)
    stdout, stderr, _ = _identify(capsys, tmp_path)
    assert BAR in stderr and NOTICE in stderr and f"{WROTE} {tmp_path / 'fit'}" in stderr
    assert BAR not in stdout and NOTICE not in stdout and "\r" not in stdout
    assert set(_table(stdout)) == {"K", "T"}


def test_quiet_silences_the_progress_but_not_the_result(tmp_path, capsys, fresh_process, monkeypatch):
    on_terminal(monkeypatch)
    stdout, stderr, found = _identify(capsys, tmp_path, "--quiet")
    assert BAR not in stderr and NOTICE not in stderr and WROTE not in stderr
    assert all(line.startswith("dynia: warning:") for line in stderr.splitlines()), stderr
    assert _table(stdout)["K"][0] == pytest.approx(found["parameters"]["K"], rel=1e-5)


def test_the_compilation_notice_only_before_the_kernels_are_compiled(tmp_path, capsys, monkeypatch):
    on_terminal(monkeypatch)
    monkeypatch.setattr(kernels, "compiled", lambda: True)
    _, stderr, _ = _identify(capsys, tmp_path)
    assert BAR in stderr and NOTICE not in stderr
    # The baseline and whole methods run no DYNIA: no bar, no notice, even before any compilation.
    monkeypatch.setattr(kernels, "compiled", lambda: False)
    for method in ("baseline", "whole"):
        _, stderr, _ = _identify(capsys, tmp_path / method, "--method", method)
        assert BAR not in stderr and NOTICE not in stderr and WROTE in stderr


def test_a_run_on_the_twin_compiles_nothing_and_says_nothing_of_compiling(tmp_path, capsys, fresh_process, monkeypatch):
    on_terminal(monkeypatch)
    _, stderr, _ = _identify(capsys, tmp_path)  # 801 steps x 2000 sets: "auto" takes the twin
    assert BAR in stderr and NOTICE not in stderr


def test_a_second_run_shows_the_progress_of_both_analyses(tmp_path, capsys, monkeypatch):
    on_terminal(monkeypatch)
    on_kernels(monkeypatch)
    # Uncompiled until the first analysis has run, as in a fresh process.
    answers = iter([False])
    monkeypatch.setattr(kernels, "compiled", lambda: next(answers, True))
    out = tmp_path / "runs"
    status, stdout, stderr = cli_run(
        capsys, "analyse", HEATING, *HEATING_ARGS, "--no-plots", "--second-run", "--out", out
    )
    assert status == 0, stderr
    # Each bar starts once at 0 %; the notice is said once, before the first.
    assert stderr.count(f"{BAR}:   0%") == 2 and stderr.count(NOTICE) == 1
    assert BAR not in stdout and "second run" in stdout


def test_analyse_outside_a_terminal_writes_nothing_but_warnings_to_stderr(tmp_path, capsys, fresh_process):
    status, stdout, stderr = cli_run(capsys, "analyse", HEATING, *HEATING_ARGS, "--no-plots", "--out", tmp_path / "a")
    cli_succeeded(status, stdout, stderr)
    assert all(line.startswith("dynia: warning:") for line in stderr.splitlines()), stderr


@pytest.mark.parametrize("quiet", [False, True])
def test_suggest_json_stays_json_on_a_terminal(capsys, fresh_process, monkeypatch, quiet):
    on_terminal(monkeypatch)
    on_kernels(monkeypatch)
    args = ["--seed", "1", "--max-samples", "2000", "--json"] + (["--quiet"] if quiet else [])
    status, stdout, stderr = cli_run(capsys, "suggest", HEATING, *HEATING_ARGS[:-4], *args)
    assert status == 0, stderr
    proposal = json.loads(stdout)
    assert proposal["settings"]["n_samples"] <= 2000
    assert (BAR in stderr, NOTICE in stderr) == (not quiet, not quiet)
    assert BAR not in stdout and NOTICE not in stdout


def test_the_kernels_say_they_are_compiled_once_a_run_has_compiled_them():
    model = FirstOrder()
    u = np.r_[np.zeros(5), np.ones(45)]
    y = model.simulate([[2.0, 5.0]], u)[0]
    # On the kernels: "auto" would take their numpy twin for so small a run, which compiles nothing.
    dynia.run(u, y, model, {"K": (0, 5), "T": (1, 9)}, n_samples=60, n=3, rng=1, engine="numba")
    assert kernels.compiled() is kernels.AVAILABLE
