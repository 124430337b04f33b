"""Issue 28: data-quality screening on by default: saturated, frozen and quantised readings are no evidence."""

import json

import numpy as np
import pandas as pd
import pytest
from cli_cases import HEATING, cli_analyse, cli_one_error, cli_succeeded, write_text_file

import dynia
from dynia.errors import SettingsError
from dynia.models import FirstOrder
from dynia.quality import QUANTISED_MIN_STEPS, check_quality, screen
from dynia.verdicts import evidence_windows

TRUE_K, TRUE_T, LEVEL = 2.0, 5.0, 2.5
BOUNDS = {"K": (0.0, 10.0), "T": (0.0, 30.0)}


def clipped_record(seed=0, third_pulse=0.0):
    """A first-order response (K 2, T 5) to two input pulses that drive it beyond a sensor's top, 2.5, plus noise.

    The sensor reads exactly 2.5 for about 107 steps twice; ``third_pulse`` adds a later pulse that stays in range.
    """
    rng = np.random.default_rng(seed)
    u = np.zeros(1000)
    u[200:310] = u[600:710] = 2.0
    u[850:950] = third_pulse
    y = FirstOrder().simulate([[TRUE_K, TRUE_T]], u)[0] + rng.normal(0, 0.1, u.size)
    return u, np.minimum(y, LEVEL)


def analysed(u, y, **options):
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=15, n_samples=3000, rng=1, **options)


@pytest.fixture(scope="module")
def clipped_runs():
    """The clipped record with a clean third pulse, analysed with and without screening."""
    u, y = clipped_record(third_pulse=1.0)
    return u, y, analysed(u, y), analysed(u, y, quality=False)


def clipped_samples(y):
    return y == LEVEL


# --- detection ---------------------------------------------------------------------------------


def test_a_clipped_sensor_is_saturated_at_its_measured_value_and_not_frozen():
    u, y = clipped_record()
    report = check_quality(None, u, y + 10.0)  # in the units measured: the level never had an offset taken off
    found = [(f.kind, f.start, f.stop, f.value) for f in report.findings]
    runs = [(a, b) for a, b in zip(*np.flatnonzero(np.diff(np.r_[0, clipped_samples(y), 0])).reshape(-1, 2).T)]
    assert found == [("saturated", a, b, LEVEL + 10.0) for a, b in runs]
    assert all(b - a > 100 for a, b in runs)
    assert all("saturated at 12.5 (its record maximum)" in f.reason for f in report.findings)


def test_a_sensor_clipped_at_its_minimum_is_saturated_there():
    u, y = clipped_record()
    report = check_quality(None, u, -y)
    assert {(f.kind, f.value) for f in report.findings} == {("saturated", -LEVEL)}
    assert all("its record minimum" in f.reason for f in report.findings)


def test_a_frozen_sensor_away_from_its_extremes_is_stuck_not_saturated():
    rng = np.random.default_rng(0)
    u = np.repeat([0.0, 1.0, 0.5, 1.5, 0.0], 200)
    y = FirstOrder().simulate([[TRUE_K, TRUE_T]], u)[0] + rng.normal(0, 0.1, u.size)
    y[400:470] = y[400]  # the tag freezes mid-range
    assert [(f.kind, f.start, f.stop) for f in check_quality(None, u, y).findings] == [("stuck", 400, 470)]
    assert screen(u, y, (15, 15)) == (("stuck", "y", 400, 470, y[400]),)


def quantised_record(seed=0, step=0.25):
    """Slow steps of a first-order output, read by a sensor whose grid (``step``) is coarser than its noise (0.03)."""
    rng = np.random.default_rng(seed)
    u = np.repeat([0.0, 2.0, 0.5, 1.5, 0.0], 200)
    y = FirstOrder().simulate([[TRUE_K, 20.0]], u)[0] + rng.normal(0, 0.03, u.size)
    return u, np.round(y / step) * step


def test_a_coarsely_quantised_output_is_found_with_its_step():
    u, y = quantised_record()
    (finding,) = check_quality(None, u, y).findings
    assert (finding.kind, finding.signal, finding.value, finding.start, finding.stop) == (
        "quantised",
        "y",
        0.25,
        0,
        1000,
    )
    # A quantised reading is right, only rounded: excluding flagged samples leaves it alone unless asked.
    assert not check_quality(None, u, y).mask("y").any()


def test_a_fine_grid_under_the_noise_is_no_finding():
    u, y = quantised_record(step=0.01)  # a third of the noise: the noise shows through the grid
    assert check_quality(None, u, y).findings == ()


def test_windows_where_a_quantised_output_moves_by_fewer_than_a_few_steps_are_screened():
    u, y = quantised_record()
    halos = (10, 10)
    flat = np.zeros(y.size, dtype=bool)
    for kind, signal, start, stop, step in screen(u, y, halos):
        assert (kind, signal, step) == ("quantised", "y", 0.25)
        flat[start:stop] = True
    spans = np.array([np.ptp(y[max(t - 10, 0) : t + 11]) for t in range(y.size)])
    np.testing.assert_array_equal(flat, spans < (QUANTISED_MIN_STEPS - 0.5) * 0.25)
    assert flat[150] and not flat[205]  # the steady state before the step, and the step's rise


# --- the run and the result --------------------------------------------------------------------


def test_screened_windows_are_those_using_a_clipped_reading_and_none_is_informative(clipped_runs):
    u, y, screened, _ = clipped_runs
    assert [entry[:2] for entry in screened.run.screened] == [("saturated", "y")] * 2
    np.testing.assert_array_equal(screened.screened_windows, screened.windows_using(clipped_samples(y)))
    assert not (screened.informative_windows(0.0) & screened.screened_windows).any()


def test_the_gain_is_no_longer_identified_from_the_clipped_stretches(clipped_runs):
    # Without screening the gain is called identified in a clipped window, its band [0.84, 1.68] missing the true 2;
    # with it, the reported window is the clean third pulse's and its band holds 2.
    u, y, screened, unscreened = clipped_runs
    clipped = unscreened.windows_using(clipped_samples(y))
    before, after = unscreened.summary()["K"], screened.summary()["K"]
    step_before = int(np.flatnonzero(unscreened.time == before["time_of_max_ic"])[0])
    assert before["verdict"] == "identified" and clipped[step_before]
    assert not before["band"][0] <= TRUE_K <= before["band"][1]
    step_after = int(np.flatnonzero(screened.time == after["time_of_max_ic"])[0])
    assert not clipped[step_after] and step_after > 850
    assert after["band"][0] <= TRUE_K <= after["band"][1]
    assert after["high_ic_windows"] < before["high_ic_windows"]


def test_without_other_information_the_gain_has_no_evidence_left():
    u, y = clipped_record()
    screened, unscreened = analysed(u, y), analysed(u, y, quality=False)
    assert evidence_windows(unscreened, 0).sum() > 200
    assert not evidence_windows(screened, 0).any()


def test_without_other_information_the_gain_is_not_identified():
    u, y = clipped_record()
    found = analysed(u, y).summary()["K"]
    assert found["verdict"] == "suspect" and "screened" in [reason["code"] for reason in found["reasons"]]
    assert "holds saturated readings" in found["reasons"][0]["text"] or any(
        "holds saturated readings" in reason["text"] for reason in found["reasons"]
    )


def test_quality_false_records_nothing_and_screens_nothing(clipped_runs):
    _, _, _, unscreened = clipped_runs
    assert unscreened.run.screened is None and not unscreened.screened_windows.any()
    assert unscreened.settings.quality is False


def test_a_saved_result_keeps_what_was_screened(clipped_runs, tmp_path):
    _, _, screened, _ = clipped_runs
    screened.save(tmp_path / "result.nc")
    loaded = dynia.load(tmp_path / "result.nc")
    assert loaded.run == screened.run and loaded.run.screened == screened.run.screened
    np.testing.assert_array_equal(loaded.screened_windows, screened.screened_windows)
    assert loaded.settings.quality is True


def test_the_online_replay_screens_what_it_was_given():
    u, y = clipped_record()
    online = dynia.OnlineDynia(FirstOrder(), BOUNDS, n=15, n_samples=300, rng=1)
    result = online.replay(u, y)
    assert result.run.screened == screen(u, y, (30, 0))
    assert result.screened_windows.any()


@pytest.mark.parametrize("quality", ["yes", 1, None])
def test_quality_must_be_a_bool(quality):
    with pytest.raises(SettingsError, match="quality must be True or False"):
        dynia.settings.AnalysisSettings(quality=quality if quality is not None else np.float64(1.0))


def test_a_damaged_screened_record_is_refused():
    with pytest.raises(SettingsError, match="screened must hold"):
        dynia.settings.RunRecord(screened=(("saturated", "y", 5, 2, 1.0),))


# --- no false screening ------------------------------------------------------------------------


def test_a_clean_noisy_step_record_is_not_screened():
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(30, 40, 20), 100)
    y = FirstOrder().simulate([[2.0, 3.0]], u, x0="steady")[0] + rng.normal(0, 0.3, u.size)
    result = dynia.run(u, y, FirstOrder(), {"K": (0, 5), "T": (0, 10)}, n=10, n_samples=500, x0="steady", rng=1)
    assert result.run.screened == () and not result.screened_windows.any()


def test_the_heating_system_record_is_not_screened():
    data = pd.read_csv(HEATING)
    u, y = data["u"].to_numpy() - 6.0, data["y"].to_numpy() - data["y"].iloc[0]
    assert screen(u, y, (10, 10)) == ()
    assert check_quality(data["time"].to_numpy(), data["u"], data["y"]).findings == ()


# --- the command line --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def clipped_csv(tmp_path_factory):
    u, y = clipped_record(third_pulse=1.0)
    rows = "\n".join(f"{t:.1f},{float(a)!r},{float(b) + 10.0!r}" for t, a, b in zip(range(u.size), u, y))
    return write_text_file(tmp_path_factory.mktemp("clipped") / "tank.csv", "time,u,level\n" + rows + "\n")


CLIPPED = "--time time --input u --output level --model first-order --param K=0:10 --param T=0:30".split() + [
    *"--offset first --n 15 --samples 1000 --seed 1 --no-plots".split()
]


def test_analyse_screens_by_default_and_says_so_in_the_measured_units(clipped_csv, tmp_path, capsys):
    out = tmp_path / "screened"
    status, stdout, err = cli_analyse(capsys, clipped_csv, *CLIPPED, "--out", out)
    cli_succeeded(status, stdout, err)
    summary = json.loads((out / "summary.json").read_text())
    findings = summary["data_quality"]
    assert [(entry["kind"], entry["column"], entry["value"], entry["limit"]) for entry in findings] == [
        ("saturated", "level", LEVEL + 10.0, "maximum")
    ] * 2
    assert all(entry["screened"] and entry["windows_excluded"] > 100 for entry in findings)
    assert summary["screening"]["excluded_windows"] == sum(entry["windows_excluded"] for entry in findings)
    assert "data quality: level saturated at 12.5 (its record maximum) from 2" in stdout
    assert f"{summary['screening']['excluded_windows']} of 1000 windows screened out of the evidence" in stdout
    page = (out / "report.html").read_text()
    assert "windows_excluded" in page and "screened out of the evidence" in page
    assert summary["settings"]["analysis"]["quality"] is True


def test_no_quality_turns_the_screening_off(clipped_csv, tmp_path, capsys):
    out = tmp_path / "unscreened"
    status, stdout, err = cli_analyse(capsys, clipped_csv, *CLIPPED, "--no-quality", "--out", out)
    cli_succeeded(status, stdout, err)
    summary = json.loads((out / "summary.json").read_text())
    assert "data_quality" not in summary and "screening" not in summary and "data quality" not in stdout
    assert summary["settings"]["analysis"]["quality"] is False
    assert dynia.load(out / "result.nc").run.screened is None


def test_the_old_quality_option_is_refused_naming_its_replacement(clipped_csv, tmp_path, capsys):
    status, stdout, err = cli_analyse(capsys, clipped_csv, *CLIPPED, "--quality", "--out", tmp_path / "never")
    cli_one_error(status, stdout, err, "--quality is gone", "--no-quality")
    assert not (tmp_path / "never").exists()


def test_quality_in_a_config_file_is_refused_naming_no_quality(clipped_csv, tmp_path, capsys):
    config = write_text_file(tmp_path / "run.toml", "quality = true\n")
    status, stdout, err = cli_analyse(capsys, clipped_csv, *CLIPPED, "--config", config, "--out", tmp_path / "x")
    cli_one_error(status, stdout, err, "quality", "no_quality = true")
