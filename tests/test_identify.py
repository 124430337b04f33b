"""dynia.identify: select, fit and validate, on data with a known model."""

import json

import numpy as np
import pytest

from dynia.errors import NothingSelected, SettingsError
from dynia.identification import IdentifyOptions, identify
from dynia.models import FirstOrder, SecondOrderDelay
from dynia.segments import random_segments
from dynia.settings import AnalysisSettings

BOUNDS = {"K": (0, 7), "T": (0, 20)}


def _record(seed=0, steps=600, glitch=None):
    """Long steady stretches with a few setpoint changes, noise 0.05, K=2, T=5."""
    rng = np.random.default_rng(seed)
    u = np.zeros(steps)
    for start, level in ((60, 1.0), (200, 3.0), (330, 2.0), (470, 0.5)):
        u[start:] = level
    y = FirstOrder().simulate([[2.0, 5.0]], u)[0] + rng.normal(0, 0.05, steps)
    if glitch is not None:
        y[glitch] = 0.0
    return u, y


@pytest.mark.parametrize("method", ["dynia", "baseline", "whole"])
def test_every_method_recovers_the_model_within_its_standard_errors(method):
    u, y = _record()
    found = identify(u, y, FirstOrder(), BOUNDS, method=method, n_samples=2000, rng=1)
    for name, truth in (("K", 2.0), ("T", 5.0)):
        assert abs(found.parameters[name] - truth) < 4 * found.std_errors[name]
    # The validation error of a correct model is the noise level.
    assert 0.04 < found.validation_error < 0.07
    held_start = found.validation[0][0]
    assert held_start == 420 and all(stop <= held_start for _, stop in found.segments)


def test_dynia_fits_on_fewer_points_than_the_whole_record():
    u, y = _record()
    dynia_fit = identify(u, y, FirstOrder(), BOUNDS, method="dynia", rng=1)
    whole = identify(u, y, FirstOrder(), BOUNDS, method="whole", rng=1)
    assert dynia_fit.fit.n_points < whole.fit.n_points
    assert dynia_fit.dynia_result is not None and whole.dynia_result is None


def test_given_segments_are_fitted_as_given():
    u, y = _record()
    chosen = random_segments([40, 40], 420, rng=3)
    found = identify(u, y, FirstOrder(), BOUNDS, method="given", segments=chosen)
    assert found.segments == chosen


def test_a_glitch_is_reported_and_excluded_on_request():
    u, y = _record(glitch=300)
    kept = identify(u, y, FirstOrder(), BOUNDS, method="whole", quality=True)
    excluded = identify(u, y, FirstOrder(), BOUNDS, method="whole", exclude_flagged=True)
    assert {finding.start for finding in kept.quality.findings} == {300}
    assert any("inside the fitted segments" in note for note in kept.warnings)
    assert excluded.fit.rmse < kept.fit.rmse / 2
    assert abs(excluded.parameters["K"] - 2.0) < abs(kept.parameters["K"] - 2.0) + 1e-3


def test_settings_options_and_their_keywords_go_together_and_the_keywords_win():
    u, y = _record()
    settings = AnalysisSettings(n_samples=400, n=8, percentage=10, conf_level=80)
    options = IdentifyOptions(ic_threshold=0.6, n_starts=3)
    both = identify(u, y, FirstOrder(), BOUNDS, settings=settings, options=options, n=5, n_starts=2, rng=1)
    merged = identify(
        u,
        y,
        FirstOrder(),
        BOUNDS,
        settings=settings.replace(n=5),
        options=IdentifyOptions(ic_threshold=0.6, n_starts=2),
        rng=1,
    )
    analysis = dict(n_samples=400, n=5, percentage=10, conf_level=80)
    keywords = identify(u, y, FirstOrder(), BOUNDS, **analysis, ic_threshold=0.6, n_starts=2, rng=1)
    for found in (merged, keywords):
        assert found.parameters == both.parameters and found.segments == both.segments
        assert found.settings == both.settings and found.dynia_result.settings == both.dynia_result.settings
    assert (both.dynia_result.settings.n, both.dynia_result.settings.conf_level) == (5, 80)
    assert (both.settings["ic_threshold"], both.settings["n_starts"]) == (0.6, 2)
    with pytest.raises(SettingsError, match="options must be a dynia.identification.IdentifyOptions; got dict"):
        identify(u, y, FirstOrder(), BOUNDS, options={"n_starts": 2})


@pytest.mark.parametrize("quality", [False, True])
def test_identifys_quality_is_the_dynia_runs_screening_whatever_the_settings_say(quality):
    u, y = _record(steps=300)
    settings = AnalysisSettings(n_samples=300, quality=not quality)
    found = identify(u, y, FirstOrder(), BOUNDS, settings=settings, quality=quality, rng=1)
    assert found.dynia_result.settings.quality is quality and (found.quality is not None) is quality


def test_to_dict_has_the_checked_keys():
    u, y = _record()
    summary = identify(u, y, FirstOrder(), BOUNDS, method="whole").to_dict(np.arange(u.size) * 2.0)
    assert {"parameters", "std_errors", "segments", "validation_error", "settings"} <= set(summary)
    assert summary["segments"] == [[0.0, 838.0]]


@pytest.mark.parametrize(
    "options, message",
    [
        (dict(method="random"), "method must be one of"),
        (dict(method="given"), "segments are given exactly when"),
        (dict(segments=[(0, 10)]), "segments are given exactly when"),
        (dict(bounds={"K": (0, 7)}), r"missing: \['T'\]"),
        (dict(model=SecondOrderDelay()), "unknown"),
    ],
)
def test_bad_requests_get_clear_errors(options, message):
    u, y = _record(steps=200)
    arguments = dict(model=FirstOrder(), bounds=BOUNDS)
    arguments.update({key: options.pop(key) for key in ("model", "bounds") if key in options})
    with pytest.raises(ValueError, match=message):
        identify(u, y, arguments["model"], arguments["bounds"], **options)


def test_a_selection_of_nothing_raises_nothing_selected():
    u, y = _record(steps=200)
    with pytest.raises(NothingSelected, match="segments_from_ic selected nothing"):
        identify(u, y, FirstOrder(), BOUNDS, ic_threshold=1.0, n_samples=200)
    with pytest.raises(NothingSelected, match="no given segment reaches into the fitting part"):
        identify(u, y, FirstOrder(), BOUNDS, method="given", segments=[(150, 200)], held_out=0.3)


def _busy_record(seed=0):
    """A new input level every 8 steps, noise 0.05, K=2, T=5: no stretch without a response."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.choice([0.0, 1.0, 3.0], 75), 8)
    return u, FirstOrder().simulate([[2.0, 5.0]], u)[0] + rng.normal(0, 0.05, u.size)


def test_the_share_selected_is_reported_and_a_selection_of_nearly_everything_is_warned_about():
    u, y = _record()
    found = identify(u, y, FirstOrder(), BOUNDS, method="dynia", n_samples=2000, rng=1)
    selected = sum(stop - start for start, stop in found.segments)
    assert found.selected_share == pytest.approx(selected / 420) and found.selected_share < 0.95
    assert not any("selected" in note for note in found.warnings)
    assert found.to_dict(np.arange(u.size))["selected_share"] == found.selected_share
    # An input that changes every 8 steps: every window informs, the selection is the fitting part (seed 0 has a few
    # windows whose behavioural set ties within noise, which are not informative: 94.5 % selected).
    u, y = _busy_record(1)
    everything = identify(u, y, FirstOrder(), BOUNDS, method="dynia", n_samples=2000, rng=1)
    assert everything.selected_share > 0.95
    [note] = [note for note in everything.warnings if note.startswith("DYNIA selected")]
    assert "of the fitting part" in note and "added nothing" in note
    whole = identify(u, y, FirstOrder(), BOUNDS, method="whole")
    assert whole.selected_share == 1.0 and not any("DYNIA selected" in note for note in whole.warnings)


def test_the_cli_prints_and_records_the_share_selected(tmp_path, capsys):
    from dynia.cli import main

    u, y = _busy_record(1)
    path = tmp_path / "record.csv"
    np.savetxt(path, np.column_stack([np.arange(u.size), u, y]), delimiter=",", header="time,u,y", comments="")
    common = [str(path), "--time", "time", "--input", "u", "--output", "y", "--model", "first-order"]
    common += ["--param", "K=0:7", "--param", "T=0:20", "--samples", "2000", "--seed", "1", "--no-plots"]
    assert main(["identify", *common, "--out", str(tmp_path / "all")]) == 0
    captured = capsys.readouterr()
    found = json.loads((tmp_path / "all" / "identified.json").read_text())
    assert found["selected_share"] > 0.95
    assert captured.out.startswith(f"--method dynia selected {100 * found['selected_share']:.1f} % of the fitting part")
    assert "dynia: warning: DYNIA selected" in captured.err
    assert any(note.startswith("DYNIA selected") for note in found["warnings"])


def _gain_change_record(seed=0, steps=1200):
    """First order, T = 3, gain 2 switching to 3 half-way; random levels held 40 steps, noise 0.2."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(5, 30, steps // 40), 40)
    gain = np.where(np.arange(steps) < steps // 2, 2.0, 3.0)
    pole = np.exp(-1 / 3)
    y = np.zeros(steps)
    for k in range(steps - 1):
        y[k + 1] = pole * y[k] + gain[k] * (1 - pole) * u[k]
    return u, y + rng.normal(0, 0.2, steps)


def test_dynias_model_structure_warning_reaches_the_identification():
    u, y = _gain_change_record()
    found = identify(
        u, y, FirstOrder(), {"K": (0.0, 5.0), "T": (0.0, 20.0)}, method="dynia", n=10, n_samples=2000, rng=0
    )
    disagree = [note for note in found.warnings if "the windows with IC >= 0.5 disagree" in note]
    assert len(disagree) == 1 and disagree[0].startswith("K: ")


# ------------------------------------------------- errors in options, too little data


def _cli_record(tmp_path, drift=0.0):
    u, y = _record()
    y[420:] += drift  # the held-out part drifts away from what the fitted part shows
    path = tmp_path / "record.csv"
    np.savetxt(path, np.column_stack([np.arange(u.size), u, y]), delimiter=",", header="time,u,y", comments="")
    common = [str(path), "--time", "time", "--input", "u", "--output", "y", "--model", "first-order"]
    return common + ["--param", "K=0:7", "--param", "T=0:20", "--samples", "500", "--seed", "1", "--no-plots"]


@pytest.mark.parametrize(
    "options, needles",
    [
        # DYNIA's selection, too strict: segments_from_ic's rule, in the options that set it.
        (["--min-length", "400"], ["DYNIA selected nothing", "--min-length 400 steps", "lower --ic-threshold"]),
        (["--min-length", "7min"], ["at least --min-length 420 steps"]),
        (["--held-out", "0.999"], ["--held-out 0.999 leaves 1 of the record's 600 steps"]),
        (["--min-length", "ten"], ["--min-length must be a whole number of steps or a duration such as 60s"]),
        (["--min-length", "0"], ["--min-length 0: the shortest segment kept must hold at least 1 step"]),
        (["--min-length", "0.2s"], ["--min-length 0.2s (0 steps of 1 s): the shortest segment kept"]),
        (["--min-length", "5", "--method", "whole"], ["--min-length is the shortest segment DYNIA selects"]),
    ],
)
def test_identifys_errors_name_the_options_typed(tmp_path, capsys, options, needles):
    from cli_cases import cli_one_error

    from dynia.cli import main

    status = main(["identify", *_cli_record(tmp_path), *options, "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    line = cli_one_error(status, captured.out, captured.err, *needles)
    for python_name in ("segments_from_ic", "min_length", "ic_threshold", "held_out", "n_starts", "exclude_flagged"):
        assert python_name not in line


def test_min_length_selects_longer_segments_and_is_recorded_in_steps(tmp_path, capsys):
    from dynia.cli import main

    assert main(["identify", *_cli_record(tmp_path), "--min-length", "30s", "--out", str(tmp_path / "out")]) == 0
    capsys.readouterr()
    found = json.loads((tmp_path / "out" / "identified.json").read_text())
    assert found["settings"]["min_length"] == 30
    assert all(end - start + 1 >= 30 for start, end in found["segments"])


def test_the_library_names_become_options():
    from dynia.cli.identify import in_options

    text = (
        "segments_from_ic selected nothing: no run of at least min_length=21 steps; lower ic_threshold or min_length, "
        "or use mode 'any'; hold out another part (held_out); exclude them with exclude_flagged=True"
    )
    assert in_options(text) == (
        "DYNIA selected nothing: no run of at least --min-length 21 steps; lower --ic-threshold or --min-length, "
        "or use --mode any; hold out another part (--held-out); exclude them with --exclude-flagged"
    )


def test_a_fit_on_too_little_data_is_warned_about():
    u, y = _record()
    # Five points per parameter, on the first step's response: fewer than ten.
    few = identify(u, y, FirstOrder(), BOUNDS, method="given", segments=[(58, 68)], rng=1)
    assert few.little_data is not None and few.little_data in few.warnings
    assert few.little_data.startswith("too little data for 2 fitted parameter(s): 10 measured points")
    assert "5.0 per parameter (fewer than 10)" in few.little_data
    # The same model on the whole fitting part: hundreds of points, a validation error at the noise level.
    whole = identify(u, y, FirstOrder(), BOUNDS, method="whole", rng=1)
    assert whole.little_data is None and not any("too little data" in note for note in whole.warnings)


def test_a_validation_error_far_above_the_fit_error_is_warned_about():
    u, y = _record()
    y = y.copy()
    y[420:] += 0.5  # the held-out part drifts away from what the fitted part shows
    found = identify(u, y, FirstOrder(), BOUNDS, method="whole", rng=1)
    assert found.validation_error > 2 * found.fit.rmse
    assert "times the fit's RMS error" in found.little_data and "(more than 2)" in found.little_data
    assert "per parameter" not in found.little_data  # 420 points are enough


def test_the_cli_puts_the_little_data_warning_on_stderr_in_the_json_and_in_the_figure(tmp_path, capsys, monkeypatch):
    from dynia.cli import main, report

    titles = []
    original = report.write_fit_figure

    def recording(path, found, *args, **kwargs):
        titles.append(found.little_data)
        return original(path, found, *args, **kwargs)

    monkeypatch.setattr(report, "write_fit_figure", recording)
    common = [word for word in _cli_record(tmp_path, drift=0.5) if word != "--no-plots"]
    status = main(["identify", *common, "--method", "whole", "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    found = json.loads((tmp_path / "out" / "identified.json").read_text())
    warned = [line for line in found["warnings"] if line.startswith("too little data")]
    assert status == 0 and len(warned) == 1 and "ic_threshold" not in warned[0] and "--ic-threshold" in warned[0]
    assert "times the fit's RMS error" in warned[0] and (tmp_path / "out" / "fit.png").exists()
    assert f"dynia: warning: {warned[0]}" in captured.err.splitlines()
    assert titles == [warned[0]]
