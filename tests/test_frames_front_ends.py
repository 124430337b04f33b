"""pandas records in every front-end that takes (u, y): aligned, refused and timed exactly as dynia.run does.

Each front-end goes through dynia.io.frames.unpack: u and y on different indexes, or a time index with a gap,
are refused with run's own error (never paired by position), a time index gives dt, and its dates become the
result's timestamps. A record on a 2 s DatetimeIndex gives, bit for bit, what the same arrays give with dt=2.
"""

import numpy as np
import pytest
from numpy.testing import assert_array_equal

import dynia
from dynia.adaptive import adaptive_run
from dynia.errors import DataError, SettingsError
from dynia.models import FirstOrder
from dynia.online import OnlineDynia
from dynia.refine import second_run
from dynia.suggestion import suggest
from dynia.timescale import dominant_time_constant

pd = pytest.importorskip("pandas")

STEPS = 120
DT = 2.0
BOUNDS = {"K": (0.0, 5.0), "T": (0.0, 40.0)}
# A fixed memory limit: the default is a share of the memory free at the call, which differs between two calls.
MEMORY = "4GB"


@pytest.fixture(scope="module")
def record():
    """K = 2, T = 10 s sampled every 2 s (5 steps), small noise; the arrays and the same on a 2 s DatetimeIndex."""
    u = np.repeat([0.0, 1.0, 0.3, 1.2, 0.5, 0.0], STEPS // 6)
    y = FirstOrder().simulate([[2.0, 10.0]], u, dt=DT)[0] + np.random.default_rng(3).normal(0, 0.05, STEPS)
    index = pd.date_range("2024-05-01 12:00", periods=STEPS, freq="2s")
    return u, y, pd.Series(u, index, name="valve"), pd.DataFrame({"T_out": y}, index)


def _run(u, y, **dt):
    return dynia.run(u, y, FirstOrder(), BOUNDS, n=3, n_samples=300, rng=1, **dt)


def _suggest(u, y, **dt):
    return suggest(u, y, FirstOrder(), BOUNDS, max_samples=2000, max_memory=MEMORY, rng=1, **dt)


def _identify(u, y, **dt):
    return dynia.identify(u, y, FirstOrder(), BOUNDS, n=3, n_samples=300, rng=1, **dt)


def _adaptive(u, y, **dt):
    return adaptive_run(u, y, FirstOrder(), BOUNDS, n=3, n_samples=400, percentage=5, rng=1, **dt)


def _second_run(u, y, **dt):
    return second_run(u, y, FirstOrder(), BOUNDS, n=3, n_samples=300, rng=1, **dt)


def _replay(u, y, dt=DT):
    return OnlineDynia(FirstOrder(), BOUNDS, n_samples=300, n=3, dt=dt, rng=1).replay(u, y)


def _time_constant(u, y, **dt):
    return dominant_time_constant(u, y, **dt)


FRONT_ENDS = {
    "suggest": _suggest,
    "dominant_time_constant": _time_constant,
    "identify": _identify,
    "adaptive_run": _adaptive,
    "second_run": _second_run,
    "replay": _replay,
}


def _refusal(call, u, y, **dt):
    """The error ``call`` raises, as (type, message, setting)."""
    with pytest.raises((DataError, SettingsError)) as caught:
        call(u, y, **dt)
    return type(caught.value), str(caught.value), getattr(caught.value, "setting", None)


def _misaligned(record):
    """y one step later than u: by position each u would meet the y of the next label."""
    _, _, u, y = record
    return u, y.set_axis(y.index + pd.Timedelta(DT, "s"))


def _gap_in_y(record):
    """y without the rows of 10 days (its index jumps), u complete."""
    _, _, u, y = record
    later = y.copy()
    later.index = later.index.where(np.arange(STEPS) < 40, later.index + pd.Timedelta(days=10))
    return u, later.iloc[np.r_[0:40, 60:STEPS]]


def _gap_in_both(record):
    """u and y on one index that jumps by 10 days after row 40."""
    u, y = _gap_in_y(record)
    return u.iloc[np.r_[0:40, 60:STEPS]].set_axis(y.index), y


@pytest.mark.parametrize("name", FRONT_ENDS)
@pytest.mark.parametrize("case", [_misaligned, _gap_in_y, _gap_in_both], ids=["shifted", "gap_in_y", "gap_in_both"])
def test_misaligned_or_gappy_records_are_refused_as_dynia_run_refuses_them(record, name, case):
    u, y = case(record)
    expected = _refusal(_run, u, y)
    assert expected[0] is DataError  # never paired by position
    assert _refusal(FRONT_ENDS[name], u, y) == expected


@pytest.mark.parametrize("name", [name for name in FRONT_ENDS if name != "replay"])
def test_a_dt_that_disagrees_with_the_index_is_refused_as_dynia_run_refuses_it(record, name):
    _, _, u, y = record
    expected = _refusal(_run, u, y, dt=1.0)
    assert expected[0] is SettingsError and expected[2] == "dt"
    assert _refusal(FRONT_ENDS[name], u, y, dt=1.0) == expected


def test_replay_refuses_an_index_spaced_otherwise_than_its_dt(record):
    _, _, u, y = record
    kind, message, setting = _refusal(_replay, u, y, dt=1.0)
    assert kind is SettingsError and setting == "dt"
    assert message == (
        "the index of the record replayed is spaced 2 s, but this OnlineDynia steps by dt = 1 s; make it with dt=2"
    )


def test_a_record_on_one_index_is_aligned_whatever_its_pandas_types(record):
    # A Series u with a one-column DataFrame y on the same index: values as given, nothing refused.
    u, y, u_frame, y_frame = record
    dated = _time_constant(u_frame, y_frame)
    assert dated == _time_constant(u, y, dt=DT)
    assert dated == _time_constant(u_frame.to_frame(), y_frame["T_out"], dt=DT)


def test_suggest_on_a_2s_index_equals_suggest_on_arrays_with_dt_2(record):
    u, y, u_frame, y_frame = record
    dated = _suggest(u_frame, y_frame)
    assert dated.to_dict() == _suggest(u, y, dt=DT).to_dict()
    # The time constant and the window in seconds: 10 s, not the 5 steps the arrays without dt would give.
    assert dated.dt == DT
    assert dated.time_scale.time_constant == pytest.approx(10.0, rel=0.05)
    assert dated.window == (2 * dated.n + 1) * DT
    assert _suggest(u, y).time_scale.time_constant == pytest.approx(5.0, rel=0.05)


def test_identify_on_a_2s_index_equals_identify_on_arrays_with_dt_2(record):
    u, y, u_frame, y_frame = record
    dated, plain = _identify(u_frame, y_frame), _identify(u, y, dt=DT)
    assert dated.parameters == plain.parameters and dated.segments == plain.segments
    assert dated.validation_error == plain.validation_error and dated.settings == plain.settings
    assert_array_equal(dated.dynia_result.ic, plain.dynia_result.ic)
    assert_array_equal(dated.dynia_result.time, np.arange(STEPS) * DT)
    assert plain.dynia_result.timestamps is None
    assert_array_equal(dated.dynia_result.timestamps, y_frame.index.to_numpy())
    # Its verdicts name the dates, as dynia.run's do.
    assert dated.dynia_result.verdicts == _run(u_frame, y_frame.iloc[:, 0].where(np.arange(STEPS) < 84)).verdicts


def test_adaptive_run_on_a_2s_index_equals_adaptive_run_on_arrays_with_dt_2(record):
    u, y, u_frame, y_frame = record
    dated, plain = _adaptive(u_frame, y_frame), _adaptive(u, y, dt=DT)
    for attribute in ("samples", "time", "ic", "ci", "median", "gradient"):
        assert_array_equal(getattr(dated, attribute), getattr(plain, attribute), err_msg=attribute)
    assert dated.settings == plain.settings and dated.settings.dt == DT
    assert_array_equal(dated.timestamps, y_frame.index.to_numpy())
    # dynia.run with an adaptive sampler hands the same record on: the same result, dates included.
    through_run = dynia.run(
        u_frame, y_frame, FirstOrder(), BOUNDS, n=3, n_samples=400, percentage=5, sampler="iis", rng=1
    )
    assert_array_equal(through_run.ic, dated.ic)
    assert_array_equal(through_run.timestamps, dated.timestamps)
    assert through_run.verdicts == dated.verdicts


def test_second_run_on_a_2s_index_equals_second_run_on_arrays_with_dt_2(record):
    u, y, u_frame, y_frame = record
    (first, second, narrowed), (plain_first, plain_second, plain_narrowed) = (
        _second_run(u_frame, y_frame),
        _second_run(u, y, dt=DT),
    )
    assert narrowed == plain_narrowed
    assert second.run.first_run_bounds == plain_second.run.first_run_bounds
    for dated, plain in ((first, plain_first), (second, plain_second)):
        assert_array_equal(dated.ic, plain.ic)
        assert_array_equal(dated.time, np.arange(STEPS) * DT)
        assert_array_equal(dated.timestamps, y_frame.index.to_numpy())


def test_replay_on_a_2s_index_equals_replay_of_arrays(record):
    u, y, u_frame, y_frame = record
    dated, plain = _replay(u_frame, y_frame), _replay(u, y)
    for attribute in ("time", "ic", "ci", "median", "gradient"):
        assert_array_equal(getattr(dated, attribute), getattr(plain, attribute), err_msg=attribute)
    assert plain.timestamps is None
    assert_array_equal(dated.timestamps, y_frame.index.to_numpy())
    # As the batch analysis with a trailing window on the same pandas record.
    batch = dynia.run(u_frame, y_frame, FirstOrder(), BOUNDS, n=3, n_samples=300, rng=1, window="trailing")
    assert_array_equal(dated.ic, batch.ic)
    assert_array_equal(dated.timestamps, batch.timestamps)


def test_settings_without_a_dt_take_the_index_spacing_and_keep_the_unit_step_without_one():
    # The case: AnalysisSettings.dt defaulted to 1.0, so settings=AnalysisSettings(n=5) with a 2 s index was refused
    # as a disagreeing dt. None now means "not given", resolved by the front-end as it reads the record.
    from dynia.settings import AnalysisSettings

    index = pd.date_range("2020-01-01", periods=120, freq="2s")
    u = pd.Series(np.r_[np.zeros(20), np.ones(100)], index)
    y = pd.Series(FirstOrder().simulate([[2.0, 6.0]], u.to_numpy(), dt=2.0)[0], index)
    bounds = {"K": (0.0, 5.0), "T": (1.0, 10.0)}
    settings = AnalysisSettings(n=5, n_samples=200)
    assert AnalysisSettings().dt is None
    assert dynia.run(u, y, FirstOrder(), bounds, settings=settings, rng=1).settings.dt == 2.0
    assert dynia.run(u.to_numpy(), y.to_numpy(), FirstOrder(), bounds, settings=settings, rng=1).settings.dt == 1.0
    with pytest.raises(SettingsError, match="dt = 1 s disagrees with the 2 s spacing"):
        dynia.run(u, y, FirstOrder(), bounds, settings=settings.replace(dt=1.0), rng=1)


def test_fit_baseline_and_quality_align_pandas_records_and_take_dt_from_the_index():
    # The case: fit_segments, validation_error, find_intervals and check_quality took arrays only, so pandas objects
    # were paired by position and a 2 s index gave T in steps (5 instead of 10).
    from dynia.baseline import find_intervals
    from dynia.fit import fit_segments, validation_error
    from dynia.quality import check_quality

    index = pd.date_range("2020-01-01", periods=300, freq="2s")
    u = pd.Series(np.repeat([0.0, 1.0, 0.5], 100), index)
    y = pd.Series(FirstOrder().simulate([[2.0, 10.0]], u.to_numpy(), dt=2.0)[0], index)
    bounds = {"K": (0.0, 5.0), "T": (1.0, 30.0)}
    fitted = fit_segments(u, y, FirstOrder(), [(0, 300)], bounds=bounds)
    assert fitted.parameters["T"] == pytest.approx(10.0, rel=1e-6)
    assert validation_error(u, y, FirstOrder(), fitted.parameters, [(200, 300)]) == pytest.approx(0.0, abs=1e-9)
    assert find_intervals(u, y).dt == 2.0
    frozen = y.copy()
    frozen.iloc[110:140] = frozen.iloc[
        110
    ]  # the tag freezes during the rise (its rest before the step opens the record)
    stuck = check_quality(None, u, frozen).findings[0]
    assert (stuck.kind, stuck.end_time) == ("stuck", 278.0)  # seconds from the first row, not steps
    shifted = y.shift(1, freq="2s")
    for call in (
        lambda: fit_segments(u, shifted, FirstOrder(), [(0, 300)], bounds=bounds),
        lambda: validation_error(u, shifted, FirstOrder(), fitted.parameters, [(200, 300)]),
        lambda: find_intervals(u, shifted),
        lambda: check_quality(None, u, shifted),
    ):
        with pytest.raises(DataError, match="u and y must share one index"):
            call()
