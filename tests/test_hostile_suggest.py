"""Issue 20's ``dynia suggest`` cases: records without information, bounds the model imposes, --quality's findings.

Each test failed on the code before the fix unless its comment says the change before it (suggest following x0
and refusing poor fits) had already fixed it. Errors are one ``dynia: error:`` line, exit status 2, and a
:class:`~dynia.errors.SuggestionError` in the API.
"""

import json

import numpy as np
import pytest
from cli_cases import cli_one_error, write_text_file

from dynia.cli import main
from dynia.errors import SuggestionError
from dynia.models import FOPDT, FirstOrder
from dynia.suggestion import suggest
from dynia.timescale import dominant_time_constant

DATA = "--time time --input u --output y --model first-order".split()
OPTIONS = [*DATA, *"--param K=0:5 --param T=0:5 --seed 1".split()]
BOUNDS = {"K": (0.0, 5.0), "T": (0.0, 5.0)}


def _record(u, y):
    return "time,u,y\n" + "".join(f"{t},{float(a)!r},{float(b)!r}\n" for t, (a, b) in enumerate(zip(u, y)))


# GOOD of cli_cases, the 40-row step test: the input steps at 6 s, the output at 7 s, with no lag between.
STEP_U = np.array([1.0 if t > 5 else 0.0 for t in range(40)])
STEP_Y = np.array([2.0 if t > 6 else 0.0 for t in range(40)])
HUGE_Y = np.where(np.arange(40) == 20, 1.797e308, STEP_Y)


def _suggest(capsys, path, *options):
    status = main(["suggest", str(path), *OPTIONS, *options])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.mark.parametrize(
    "u, y, options, needles",
    [
        # A constant output: explained 0 % before too, but the line now says what is missing.
        (STEP_U, np.full(40, 2.0), [], ["the output never changes", "every measured value is 2"]),
        # The 40-row record: proposed --n 1 because "the output follows the input within one sample".
        (STEP_U, STEP_Y, [], ["the output follows the input within one sample (1 s)", "resolves no time constant"]),
        # One 1.797e308 cell: the fit overflowed (nan % explained) and --n 1 was proposed.
        (STEP_U, HUGE_Y, [], ["one value, 1.797e+308 at step 20 (20 s from the start)", "check the data"]),
        # Constant inputs that never move the model: refused already by the change before (x0 followed).
        (np.zeros(40), STEP_Y, [], ["the input never moves the model", "zero throughout"]),
        (np.ones(40), STEP_Y, ["--x0", "steady"], ["the input never moves the model", "stays at its first value"]),
    ],
    ids=["constant-output", "40-rows", "huge-cell", "zero-input", "constant-input-steady"],
)
def test_a_record_without_information_gets_one_error_line_and_no_proposal(tmp_path, capsys, u, y, options, needles):
    path = write_text_file(tmp_path / "record.csv", _record(u, y))
    cli_one_error(*_suggest(capsys, path, *options), "cannot propose a window", *needles)
    x0 = options[1] if options else "zero"
    with pytest.raises(SuggestionError, match="^cannot propose a window") as caught:
        suggest(u, y, FirstOrder(), BOUNDS, x0=x0, rng=1)
    assert all(needle in str(caught.value) for needle in needles) and "\n" not in str(caught.value)


@pytest.mark.parametrize("factor", [1e200, 1e-170])
def test_the_time_scale_does_not_depend_on_the_output_scale(factor):
    u = np.repeat([0.0, 50.0, 20.0, 70.0], 300)
    y = 3.0 + FirstOrder().simulate([[0.6, 40.0]], u)[0] + np.random.default_rng(1).normal(0, 0.1, u.size)
    plain, scaled = dominant_time_constant(u, y), dominant_time_constant(u, y * factor)
    assert scaled.time_constant == pytest.approx(plain.time_constant, rel=1e-9)
    assert scaled.explained == pytest.approx(plain.explained, rel=1e-9)
    assert scaled.gains[0] == pytest.approx(plain.gains[0] * factor, rel=1e-9)
    assert scaled.rmse == pytest.approx(plain.rmse * factor, rel=1e-9)


def test_a_bound_the_model_imposes_is_never_to_be_widened():
    # The output leads the input by 5 steps (a misaligned log): the best dead time would be negative.
    u = np.repeat([0.0, 50.0, 20.0, 70.0, 30.0], 200)
    y = FirstOrder().simulate([[0.6, 20.0]], np.r_[u[5:], u[-5:]])[0] + np.random.default_rng(0).normal(0, 0.1, u.size)
    found = suggest(u, y, FOPDT(), {"K": (0, 2), "T": (0, 100), "theta": (0, 20)}, max_samples=5000, rng=1)
    assert found.fit["theta"]["at_bound"]
    theta = [note for note in found.notes if "theta" in note and "bound" in note]
    assert len(theta) == 1 and "widen" not in theta[0]
    assert "the least value FOPDT accepts (theta must be >= 0): keep the range" in theta[0]


def test_a_bound_the_model_does_not_impose_is_still_to_be_widened():
    # A negative gain is admissible: its range is to be widened below 0.
    u = np.repeat([0.0, 50.0, 20.0, 70.0, 30.0], 200)
    y = -FirstOrder().simulate([[0.6, 20.0]], u)[0] + np.random.default_rng(0).normal(0, 0.1, u.size)
    found = suggest(u, y, FirstOrder(), {"K": (0, 2), "T": (0, 100)}, rng=1)
    assert "the range [0, 2] of K excludes the least-squares fit: its estimate lies on the lower bound 0; widen " in (
        " ".join(found.notes)
    )


@pytest.fixture(scope="module")
def glitch(tmp_path_factory):
    u = np.repeat([0.0, 50.0, 20.0, 70.0, 30.0], 200)
    y = 21 + FirstOrder().simulate([[0.6, 20.0]], u)[0] + np.random.default_rng(0).normal(0, 0.1, u.size)
    y[300] += 40
    return write_text_file(tmp_path_factory.mktemp("glitch") / "glitch.csv", _record(u, y))


def test_quality_findings_come_with_the_proposal_not_in_a_summary_it_does_not_write(glitch, capsys):
    options = ["--param", "K=0:2", "--param", "T=0:100", "--max-samples", "1000"]
    status = main(["suggest", str(glitch), *DATA, *options, "--seed", "1"])
    err = capsys.readouterr().err
    assert status == 0 and "summary.json" not in err
    lines = err.splitlines()
    assert lines[0] == "dynia: warning: data quality: 1 finding(s) (glitch); listed in the warnings below"
    assert lines[1].startswith("dynia: warning: data quality: y glitch from 300.0 to 300.0: 1 sample at ")
    status = main(["suggest", str(glitch), *DATA, *options, "--seed", "1", "--json"])
    captured = capsys.readouterr()
    proposal = json.loads(captured.out)
    assert status == 0 and "summary.json" not in captured.out + captured.err
    assert proposal["warnings"] == ["data quality: 1 finding(s) (glitch); see data_quality in the JSON output"]
    assert [(entry["signal"], entry["kind"]) for entry in proposal["data_quality"]] == [("y", "glitch")]


def _gappy_record(gap_steps):
    rng = np.random.default_rng(5)
    u = np.repeat([0.0, 2.0, 1.0, 3.0, 1.5, 2.5], 120)
    y = FirstOrder().simulate([[2.0, 12.0]], u)[0] + rng.normal(0, 0.05, u.size)
    # A logger off for gap_steps steps after the third step of the input: the input is known (held), the output not.
    u = np.concatenate([u[:360], np.full(gap_steps, u[359]), u[360:]])
    y = np.concatenate([y[:360], np.full(gap_steps, np.nan), y[360:]])
    return u, y


def test_a_long_gap_in_the_output_is_left_out_of_the_pilot_and_the_fit():
    # The case: a 10-day gap at 2 s made suggest simulate 432 000 empty steps, once per sample of the pilot and
    # once per least-squares evaluation (147 s and 630 MB against 3.5 s). The memory of the pilot is what its record
    # holds, so a pilot that ran through the gap estimates hundreds of times the memory of one that did not.
    bounds = {"K": (0.0, 5.0), "T": (1.0, 40.0)}
    short = suggest(*_gappy_record(100), FirstOrder(), bounds, max_samples=600, rng=1)
    long = suggest(*_gappy_record(100_000), FirstOrder(), bounds, max_samples=600, rng=1)
    assert long.memory["pilot"] < 1.2 * short.memory["pilot"]
    assert any(reason.startswith("gaps: 1 stretch(es) without output") for reason in long.reasons)
    assert not any(reason.startswith("gaps:") for reason in short.reasons)  # 100 steps: under 10 time constants (120)
    # What the state remembers of the gap is kept: the fit equals the one on a gap the pilot runs through.
    for name in bounds:
        assert long.fit[name]["estimate"] == pytest.approx(short.fit[name]["estimate"], rel=1e-6)
    # The proposal is for the whole record: its memory estimate counts every step.
    assert long.memory["proposed"] > 5 * short.memory["proposed"]
