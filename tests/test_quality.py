"""Data quality: absurd magnitudes, glitches, outliers and stuck values, and the high-IC segments they fall in."""

import math
import statistics
import warnings

import numpy as np
import pytest

import dynia
from dynia.errors import SettingsError
from dynia.io.csv import resample_events
from dynia.models import FirstOrder
from dynia.quality import Finding, QualityReport, check_quality
from dynia.segments import segments_from_ic


def noisy_steps(rng, steps=2000, noise=0.3):
    """Input: levels held 100 steps; output: a first-order response to it plus white noise."""
    u = np.repeat(rng.uniform(30, 40, steps // 100), 100)
    y = FirstOrder().simulate([[2.0, 3.0]], u, x0="steady")[0] + rng.normal(0, noise, steps)
    return u, y


def kinds(report, signal=None):
    return [(f.signal, f.kind, f.start, f.stop) for f in report.findings if signal in (None, f.signal)]


# --- the thesis's case: one erroneous zero reading (section 3.1.3) -----------------------------


@pytest.fixture(scope="module", params=[0, 1])
def case_study(request):
    """Two days of the synthetic cooling-water loop on a 1-minute grid, and a second DYNIA run."""
    time_u, u_log, time_y, y_log, truth = dynia.synthetic.cooling_water_loop(request.param, days=2)
    grid, u, y = resample_events(time_u, u_log, time_y, y_log, dt=1.0)
    bounds = {"K": (1.8, 2.2), "T": (0.0, 8.0)}
    result = dynia.run(u, y, FirstOrder(), bounds, n_samples=2000, n=2, x0="steady", rng=request.param)
    return dict(grid=grid, u=u, y=y, truth=truth, bounds=bounds, result=result, seed=request.param)


def test_the_zero_readings_are_the_only_findings(case_study):
    report = check_quality(case_study["grid"], case_study["u"], case_study["y"])
    glitch_u = int(np.flatnonzero(case_study["grid"] == case_study["truth"].glitch_time)[0])
    glitch_y = glitch_u + 1  # the output's zero is stamped one minute later
    assert kinds(report) == [
        ("u", "glitch", glitch_u, glitch_u + 1),
        ("u", "outlier", glitch_u, glitch_u + 1),
        ("y", "glitch", glitch_y, glitch_y + 1),
        ("y", "outlier", glitch_y, glitch_y + 1),
    ]
    assert all(f.value == 0.0 for f in report.findings)
    assert report.findings[0].start_time == report.findings[0].end_time == case_study["truth"].glitch_time


def test_the_highest_ic_of_the_time_constant_sits_on_the_glitch_until_it_is_excluded(case_study):
    # The thesis's finding: after narrowing the gain, T's highest IC lands on the erroneous reading.
    grid, u, y, result = case_study["grid"], case_study["u"], case_study["y"], case_study["result"]
    report = check_quality(grid, u, y)
    best = float(np.nanmax(result.ic[1]))
    segments = segments_from_ic(result, parameters="T", ic_threshold=0.95 * best, min_length=1)
    hits = {segment: found for segment, found in report.findings_in(segments).items() if found}
    assert len(hits) == 1
    assert {(f.signal, f.kind) for f in next(iter(hits.values()))} == {
        ("u", "glitch"),
        ("u", "outlier"),
        ("y", "glitch"),
        ("y", "outlier"),
    }

    cleaned = dynia.run(
        report.exclude(u, signal="u"),
        report.exclude(y, signal="y"),
        FirstOrder(),
        case_study["bounds"],
        n_samples=2000,
        n=2,
        x0="steady",
        rng=case_study["seed"],
    )
    near_glitch = np.abs(grid - case_study["truth"].glitch_time) <= 5
    assert np.nanmax(cleaned.ic[1, near_glitch]) < 0.3 < 0.8 < best
    assert np.nanmax(cleaned.ic[1]) < 0.6 * best


# --- glitches ---------------------------------------------------------------------------------


def test_glitches_of_one_and_two_samples_are_found_exactly_and_real_events_are_not():
    rng = np.random.default_rng(5)
    u, y = noisy_steps(rng)
    y[[150, 777]] = [0.0, y[777] + 20]
    y[1234:1236] = y[1234:1236] - 15  # two samples, both far from both neighbours
    u[640] = 0.0
    report = check_quality(None, u, y)
    assert kinds(report, "u") == [("u", "glitch", 640, 641), ("u", "outlier", 640, 641)]
    assert [(f.start, f.stop) for f in report.findings if f.kind == "glitch" and f.signal == "y"] == [
        (150, 151),
        (777, 778),
        (1234, 1236),
    ]
    # steps of the input and of the output are not glitches; nor is a three-sample excursion
    y[1500:1503] += 15
    glitches = [(f.start, f.stop) for f in check_quality(None, u, y).findings if f.kind == "glitch"]
    assert (1500, 1503) not in glitches and (150, 151) in glitches


def glitch_reference(x, half=3, threshold=6.0, min_size=0.1, longest=2, quantile=0.01):
    """The glitch rule of dynia.quality, written out sample by sample (x without NaN)."""
    ordered = sorted(x)
    low = ordered[math.ceil(quantile * (len(x) - 1))]  # quantiles rounded inwards to a sample
    high = ordered[math.floor((1 - quantile) * (len(x) - 1))]
    floor = 1e-6 * max(high - low, abs(statistics.median(x)))
    noise = 1.4826 * statistics.median(abs(b - a) for a, b in zip(x, x[1:], strict=False)) / 2**0.5
    medians, scales = [], []
    for i in range(len(x)):
        window = list(x[max(i - half, 0) : i + half + 1])
        medians.append(statistics.median(window))
        mad = statistics.median(abs(v - medians[i]) for v in window)
        scales.append(max(1.4826 * mad, noise, floor))
    far = [
        abs(x[i] - medians[i]) > threshold * scales[i] and abs(x[i] - medians[i]) >= min_size * (high - low)
        for i in range(len(x))
    ]
    found, i = [], 0
    while i < len(x):
        if not far[i]:
            i += 1
            continue
        j = i
        while j < len(x) and far[j]:
            j += 1
        neighbours = [x[k] for k in (i - 1, j) if 0 <= k < len(x)]
        isolated = all(abs(x[k] - v) > threshold * scales[k] for k in range(i, j) for v in neighbours)
        if j - i <= longest and isolated:
            found.append((i, j))
        i = j
    return found


@pytest.mark.parametrize("seed", range(4))
def test_glitches_match_a_sample_by_sample_reference(seed):
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.normal(0, 0.2, 600)) + rng.standard_t(3, 600)  # wandering, heavy-tailed
    spikes = rng.choice(600, 12, replace=False)
    x[spikes] += rng.choice([-1, 1], 12) * rng.uniform(2, 30, 12)
    found = [
        (f.start, f.stop)
        for f in check_quality(None, np.zeros(600), x).findings
        if f.kind == "glitch" and f.signal == "y"
    ]
    assert found == glitch_reference(x)
    assert len(found) >= 6  # the comparison is not empty


def test_an_ordinary_stored_reading_of_an_interpolated_log_is_not_a_glitch():
    # An exception log, resampled linearly onto a grid: straight lines between stored readings,
    # so tiny robust scales. Around step 255, where the tag held still, it was logged scan by
    # scan, and the scan the grid hits read 0.4 high, within the deadband: ordinary, not gross.
    rng = np.random.default_rng(9)
    stored_at = np.arange(0, 1001, 10.0)
    stored = 72 + np.cumsum(rng.normal(0, 0.5, stored_at.size))
    stored[26] = stored[25]
    scans = np.array([254.9, 255.0, 255.1])
    readings = stored[25] + np.array([0.0, 0.4, 0.0])
    order = np.argsort(np.r_[stored_at, scans])
    y = np.interp(np.arange(1001), np.r_[stored_at, scans][order], np.r_[stored, readings][order])
    u = np.full(1001, 36.0)
    low, high = np.quantile(y, [0.01, 0.99])
    assert 0.4 < 0.1 * (high - low)
    assert check_quality(None, u, y).findings == ()
    assert kinds(check_quality(None, u, y, glitch_min_size=0)) == [("y", "glitch", 255, 256)]


def test_white_noise_with_steps_raises_nothing():
    rng = np.random.default_rng(11)
    u, y = noisy_steps(rng, steps=20_000)
    assert check_quality(None, u + rng.normal(0, 0.05, u.size), y).findings == ()


def test_a_single_wrong_value_in_a_constant_signal_is_found_but_rounding_dust_is_not():
    y = np.full(50, 72.0)
    y[20] += 1e-12
    assert check_quality(None, np.full(50, 36.0), y).findings == ()
    y[20] = 71.0
    found = kinds(check_quality(None, np.full(50, 36.0), y))
    assert found == [("y", "glitch", 20, 21), ("y", "outlier", 20, 21)]


def test_max_glitch_length_zero_turns_the_glitch_test_off():
    y = np.full(50, 72.0)
    y[20] = 0.0
    assert [f.kind for f in check_quality(None, np.ones(50), y, max_glitch_length=0).findings] == ["outlier"]


# --- outliers ---------------------------------------------------------------------------------


def test_a_run_of_outlying_values_is_one_outlier_finding():
    rng = np.random.default_rng(2)
    u, y = noisy_steps(rng)
    y[900:906] = 200.0  # too long for a glitch
    report = check_quality(None, u, y)
    assert kinds(report) == [("y", "outlier", 900, 906)]
    assert report.findings[0].value == 200.0
    low, high = np.quantile(np.delete(y, range(900, 906)), [0.01, 0.99])
    assert y[900] > high + (high - low)


def test_the_outlier_fence_is_where_the_docstring_puts_it():
    x = np.linspace(0.0, 100.0, 1001)  # steps of 0.1
    # Two values moved above the top: the sorted record's 1 % and 99 % positions (10 and 990)
    # then hold 1.0 and 99.2, a bulk 98.2 wide.
    low, high = 1.0, 99.2
    x[500] = high + 1.01 * (high - low)
    x[600] = high + 0.99 * (high - low)
    assert [f.start for f in check_quality(None, np.ones(1001), x).findings if f.kind == "outlier"] == [500]


# --- stuck values -----------------------------------------------------------------------------


def test_a_frozen_output_is_stuck_and_a_piecewise_constant_input_is_not():
    rng = np.random.default_rng(3)
    u, y = noisy_steps(rng)
    y[1200:1260] = y[1200]
    report = check_quality(None, u, y)
    assert kinds(report) == [("y", "stuck", 1200, 1260)]
    assert report.findings[0].value == y[1200]


def test_short_repeats_and_the_usual_runs_of_a_quantised_sensor_are_not_stuck():
    rng = np.random.default_rng(4)
    u, y = noisy_steps(rng)
    y[300:309] = y[300]  # 9 < min_stuck
    quantised = np.round(y, 1)  # runs of a few equal readings are usual here
    assert kinds(check_quality(None, u, y)) == []
    assert kinds(check_quality(None, u, quantised)) == []
    usual = np.quantile(np.diff(np.flatnonzero(np.r_[True, np.diff(quantised) != 0, True])), 0.95)
    quantised[1000 : 1000 + int(4 * usual) + 10] = quantised[1000]
    assert [f.kind for f in check_quality(None, u, quantised).findings] == ["stuck"]


def test_a_noise_free_output_settling_to_repeated_values_is_not_stuck():
    u = np.r_[np.full(5, 30.0), np.repeat(np.resize([38.0, 33.0, 40.0, 30.0], 20), 60)]
    u[600:800] = 35.0  # long enough to settle to the last bit
    y = FirstOrder().simulate([[2.0, 3.0]], u, x0="steady")[0]
    assert (np.diff(y[600:800]) == 0).sum() > 50 and (np.diff(y) != 0).mean() > 0.5
    assert check_quality(None, u, y).findings == ()
    y[300:360] = y[300]  # the same output frozen in the middle of a transient
    assert kinds(check_quality(None, u, y)) == [("y", "stuck", 300, 360)]


def test_stuck_tolerance_joins_readings_that_differ_by_less():
    rng = np.random.default_rng(6)
    u, y = noisy_steps(rng)
    y[500:540] = y[500] + rng.uniform(-1e-3, 1e-3, 40)
    assert check_quality(None, u, y).findings == ()
    assert kinds(check_quality(None, u, y, stuck_tolerance=0.01)) == [("y", "stuck", 500, 540)]


# --- absurd magnitudes ------------------------------------------------------------------------


@pytest.mark.parametrize("signal", ["u", "y"])
@pytest.mark.parametrize("value", [1e308, -1e308])
def test_a_1e308_cell_is_a_magnitude_finding_and_leaves_the_other_tests_as_without_it(signal, value):
    rng = np.random.default_rng(12)
    u, y = noisy_steps(rng)
    u[640], y[150] = 0.0, 0.0  # a glitch in each signal, to be found as before
    record = {"u": u, "y": y}
    record[signal] = record[signal].copy()
    without = dict(record)
    without[signal] = record[signal].copy()
    without[signal][1000] = np.nan
    record[signal][1000] = value
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow on the way
        report = check_quality(None, record["u"], record["y"])
    magnitude = [f for f in report.findings if f.kind == "magnitude"]
    assert [(f.signal, f.start, f.stop, f.value) for f in magnitude] == [(signal, 1000, 1001, value)]
    assert magnitude[0].start_time == magnitude[0].end_time == 1000.0
    assert magnitude[0].reason == (
        f"{value:.6g} is no plausible reading, its size exceeds max_magnitude = 1e+12: a "
        "sentinel, a unit or parsing error or a corrupted reading; left out of the other "
        "tests"
    )
    others = [f for f in report.findings if f.kind != "magnitude"]
    assert others == list(check_quality(None, without["u"], without["y"]).findings)
    assert kinds(report) == sorted(kinds(report), key=lambda f: (f[0], dynia.quality.KINDS.index(f[1]), f[2]))
    assert ("u", "glitch", 640, 641) in kinds(report) and ("y", "glitch", 150, 151) in kinds(report)
    assert report.mask(signal, ["magnitude"]).sum() == 1 and report.mask(signal, ["magnitude"])[1000]
    assert (
        "1 magnitude" in report.summary() and f"  {signal} magnitude t=1000 (samples 1000-1000): " in report.summary()
    )


def test_magnitudes_are_removed_by_exclude():
    u, y = np.linspace(1.0, 3.0, 21), np.full(21, 8.0)
    u[10], y[11] = 1e300, -1e308
    report = check_quality(None, u, y)
    assert kinds(report) == [("u", "magnitude", 10, 11), ("y", "magnitude", 11, 12)]
    assert report.exclude(u, signal="u")[10] == pytest.approx(2.0)
    assert np.isnan(report.exclude(y)[11]) and np.isnan(report.exclude(y)).sum() == 1


def test_the_magnitude_limit_and_the_overflow_limit():
    y = np.sin(np.arange(100) / 7.0)
    y[[20, 21, 23, 60]] = [2e12, 5e12, 3e12, 1e11]
    y[22] = np.nan  # a missing sample does not split a run
    report = check_quality(None, np.ones(100), y)
    assert [(f.start, f.stop, f.value) for f in report.findings if f.kind == "magnitude"] == [(20, 24, 5e12)]
    assert ("y", "magnitude", 60, 61) not in kinds(report)  # 1e11: an outlier, no magnitude finding
    assert ("y", "outlier", 60, 61) in kinds(report)
    assert [
        f.start for f in check_quality(None, np.ones(100), y, max_magnitude=1e10).findings if f.kind == "magnitude"
    ] == [20, 60]
    assert not any(f.kind == "magnitude" for f in check_quality(None, np.ones(100), y, max_magnitude=1e13).findings)
    y[[20, 21, 23, 60]] = [1e140, 1e151, np.sin(23 / 7.0), np.sin(60 / 7.0)]
    found = [f for f in check_quality(None, np.ones(100), y, max_magnitude=math.inf).findings if f.kind == "magnitude"]
    assert [(f.start, f.stop, f.value) for f in found] == [(21, 22, 1e151)]
    assert found[0].reason.endswith(
        "its size exceeds 1e+150, beyond which squaring it in a cost overflows; left out of the other tests"
    )


def test_a_signal_of_nothing_but_absurd_values_has_only_magnitude_findings():
    report = check_quality(None, np.ones(20), np.full(20, 1e200))
    assert kinds(report) == [("y", "magnitude", 0, 20)]
    assert report.summary().splitlines()[0] == "Data quality of 20 samples: 1 finding."


@pytest.mark.parametrize("limit", [0, -1.0, math.nan, "1e12", True, None])
def test_max_magnitude_must_be_a_number_above_zero(limit):
    with pytest.raises(
        SettingsError,
        match=r"^max_magnitude must be a number > 0 \(math\.inf: flag only values "
        r"above 1e\+150\); got ",
    ) as caught:
        check_quality(None, np.ones(5), np.ones(5), max_magnitude=limit)
    assert caught.value.setting == "max_magnitude"


# --- missing samples --------------------------------------------------------------------------


def test_missing_samples_are_never_flagged_and_tests_skip_them():
    rng = np.random.default_rng(7)
    u, y = noisy_steps(rng)
    y[400:405] = np.nan
    y[405] = 0.0  # a glitch right after a gap: its neighbours are 399 and 406
    y[1000:1030] = y[1000]
    y[1010:1013] = np.nan  # a gap inside a frozen stretch does not end it
    report = check_quality(None, u, y)
    assert kinds(report) == [("y", "glitch", 405, 406), ("y", "outlier", 405, 406), ("y", "stuck", 1000, 1030)]
    mask = report.mask("y")
    assert np.array_equal(report.missing["y"], np.isnan(y)) and not report.missing["u"].any()
    assert not mask[np.isnan(y)].any()
    assert mask.sum() == 1 + 27


def test_an_all_missing_signal_has_no_findings():
    assert check_quality(None, np.ones(20), np.full(20, np.nan)).findings == ()


# --- the report -------------------------------------------------------------------------------


@pytest.fixture()
def glitchy():
    rng = np.random.default_rng(8)
    u, y = noisy_steps(rng, steps=400)
    u[150] = 0.0
    y[151] = 0.0
    y[250:290] = y[250]
    time = 10.0 * np.arange(400) + 0.5 * (np.arange(400) % 3)  # not uniform
    return time, u, y, check_quality(time, u, y)


def test_mask_per_signal_and_kind(glitchy):
    _, _, _, report = glitchy
    assert np.flatnonzero(report.mask("u")).tolist() == [150]
    assert np.flatnonzero(report.mask("y", ["glitch"])).tolist() == [151]
    assert report.mask("y").sum() == 41
    assert np.flatnonzero(report.mask("y", ["stuck"])).tolist() == list(range(250, 290))


def test_exclude_makes_output_samples_missing_and_interpolates_the_input_in_time(glitchy):
    time, u, y, report = glitchy
    clean_y = report.exclude(y)
    assert np.isnan(clean_y[report.mask("y")]).all()
    assert np.array_equal(clean_y[~report.mask("y")], y[~report.mask("y")])
    only_glitches = report.exclude(y, kinds=["glitch"])
    assert np.isnan(only_glitches).sum() == 1
    u[149], u[151] = 30.0, 40.0  # a slope to interpolate along
    clean_u = report.exclude(u, signal="u")
    weight = (time[150] - time[149]) / (time[151] - time[149])
    assert weight != 0.5 and clean_u[150] == pytest.approx(30.0 + weight * 10.0)
    assert np.array_equal(np.delete(clean_u, 150), np.delete(u, 150))
    assert u[150] == 0.0  # the caller's arrays are not changed


def test_exclude_holds_the_nearest_value_at_the_ends_and_refuses_a_wholly_flagged_input():
    u = np.r_[0.0, np.full(20, 5.0)]
    report = check_quality(None, u, np.zeros(21))
    assert report.exclude(u, signal="u")[0] == 5.0
    with pytest.raises(ValueError, match="values has 20 samples but the report covers 21"):
        report.exclude(u[:20], signal="u")
    everything = QualityReport(
        findings=(Finding("u", "stuck", 0, 21, 0.0, 20.0, 5.0, "test"),),
        time=np.arange(21.0),
        missing={"u": np.zeros(21, bool), "y": np.zeros(21, bool)},
    )
    with pytest.raises(ValueError, match="every sample of u that is present is flagged"):
        everything.exclude(u, signal="u")


def test_findings_in_segments_uses_half_open_ranges(glitchy):
    _, _, _, report = glitchy
    found = report.findings_in([(0, 150), (150, 151), (151, 250), (289, 290), (290, 400)])
    assert {segment: sorted((f.signal, f.kind) for f in hits) for segment, hits in found.items()} == {
        (0, 150): [],
        (150, 151): [("u", "glitch"), ("u", "outlier")],
        (151, 250): [("y", "glitch"), ("y", "outlier")],
        (289, 290): [("y", "stuck")],
        (290, 400): [],
    }


def test_to_dataframe_and_summary(glitchy):
    time, _, _, report = glitchy
    table = report.to_dataframe()
    assert list(table.columns) == ["signal", "kind", "start", "stop", "start_time", "end_time", "value", "reason"]
    assert len(table) == len(report.findings) == 5
    stuck = table[table.kind == "stuck"].iloc[0]
    assert (stuck.start_time, stuck.end_time) == (time[250], time[289])
    text = report.summary()
    assert (
        "5 findings" in text
        and "u: 0 magnitude, 1 glitch, 1 outlier, 0 saturated, 0 stuck, 0 quantised; 1 flagged sample\n" in text
    )
    assert "y: 0 magnitude, 1 glitch, 1 outlier, 0 saturated, 1 stuck, 0 quantised; 41 flagged samples" in text
    assert "40 consecutive readings" in text


# --- bad input --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args, kwargs, message",
    [
        ((None, np.ones(5), np.ones(6)), {}, "u has 5 samples but y has 6"),
        ((np.arange(4.0), np.ones(5), np.ones(5)), {}, "time has 4 values but u and y have 5"),
        ((np.array([0, 1, 1, 2, 3.0]), np.ones(5), np.ones(5)), {}, r"time must increase strictly; time\[2\] = 1.0"),
        ((None, np.ones(5), np.r_[1, 1, np.inf, 1, 1]), {}, "y holds a non-finite value at index 2"),
        ((None, np.ones((5, 2)), np.ones(5)), {}, "u must be 1-D"),
        (
            (None, np.ones(5), np.ones(5)),
            dict(half_window=1, max_glitch_length=2),
            "half_window \\(1\\) must be at least",
        ),
        (
            (None, np.ones(5), np.ones(5)),
            dict(outlier_quantile=0.5),
            "outlier_quantile must lie strictly between 0 and 0.5",
        ),
        ((None, np.ones(5), np.ones(5)), dict(glitch_threshold=-1), "glitch_threshold must lie strictly between"),
        ((None, np.ones(5), np.ones(5)), dict(min_stuck=1), "min_stuck must be at least 2"),
        ((None, np.ones(5), np.ones(5)), dict(stuck_tolerance=-0.1), "stuck_tolerance must lie strictly between"),
    ],
)
def test_bad_input_is_named(args, kwargs, message):
    with pytest.raises(ValueError, match=message):
        check_quality(*args, **kwargs)


def test_bad_report_arguments_are_named(glitchy):
    _, _, y, report = glitchy
    with pytest.raises(ValueError, match="signal must be one of \\('u', 'y'\\); got 'z'"):
        report.mask("z")
    with pytest.raises(ValueError, match="unknown kinds \\['spike'\\]"):
        report.exclude(y, kinds=["spike"])
    with pytest.raises(ValueError, match="kinds must be a sequence of kinds"):
        report.mask("y", "glitch")
    with pytest.raises(ValueError, match="must satisfy 0 <= start < stop <= 400"):
        report.findings_in([(10, 5)])
    with pytest.raises(ValueError, match="segments\\[0\\] must be a \\(start, stop\\) pair"):
        report.findings_in([(1, 2, 3)])
