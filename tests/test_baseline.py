"""The Bittencourt et al. (2015) interval search on records with known steps."""

import numpy as np
import pytest
import scipy.stats

from dynia.baseline import (
    REASONS,
    _laguerre_regressors,  # the orthonormality check needs the raw filters
    find_intervals,
)

STEPS = (300, 700, 1100)
N_STEPS = 1500


def lag_response(u, gain, time_constant, delay=0):
    """Zero-order-hold response of gain e^(-delay s) / (time_constant s + 1), delay in whole samples."""
    pole = np.exp(-1.0 / time_constant)
    delayed = np.r_[np.full(delay, u[0]), u[: u.size - delay]]
    y = np.zeros(u.size)
    for k in range(u.size - 1):
        y[k + 1] = pole * y[k] + gain * (1 - pole) * delayed[k]
    return y


def step_input():
    """Flat for 300 samples, then steps to 1, 0.4 and 1.2, each held 400 samples."""
    u = np.zeros(N_STEPS)
    for step, level in zip(STEPS, (1.0, 0.4, 1.2)):
        u[step:] = level
    return u


def covered(result, n_steps):
    """Mask of the samples inside an accepted interval."""
    mask = np.zeros(n_steps, dtype=bool)
    for start, stop in result.accepted:
        mask[start:stop] = True
    return mask


def assert_usable(result, n_steps):
    """Accepted intervals are sorted, non-overlapping, non-empty index pairs inside the record."""
    accepted = result.accepted
    assert accepted.dtype.kind == "i" and accepted.ndim == 2 and accepted.shape[1] == 2
    assert np.all(accepted[:, 0] >= 0) and np.all(accepted[:, 1] <= n_steps)
    assert np.all(accepted[:, 0] < accepted[:, 1])
    assert np.all(accepted[1:, 0] >= accepted[:-1, 1])


@pytest.mark.parametrize("delay", [0, 12])
def test_each_step_is_covered_from_before_it_until_the_response_has_settled(delay):
    time_constant = 6.0
    u = step_input()
    y = lag_response(u, 2.0, time_constant, delay) + np.random.default_rng(7).normal(0, 0.1, N_STEPS)
    result = find_intervals(u, y)
    assert_usable(result, N_STEPS)
    # 98 % of the change is reached delay + 4 time constants after the step.
    settled = delay + int(4 * time_constant)
    for step in STEPS:
        around = [(start, stop) for start, stop in result.accepted if start < step < stop]
        assert len(around) == 1, f"step at {step}: {result.accepted.tolist()}"
        start, stop = around[0]
        assert step - 20 <= start < step
        assert step + settled < stop <= step + 150
    assert len(result.accepted) == len(STEPS)
    for candidate in result.candidates:
        if candidate.accepted:
            assert candidate.static_gain == pytest.approx(2.0, abs=0.2)


def test_flat_stretches_between_the_steps_are_left_out():
    u = step_input() + np.random.default_rng(8).normal(0, 0.01, N_STEPS)
    y = lag_response(u, 2.0, 6.0) + np.random.default_rng(9).normal(0, 0.1, N_STEPS)
    inside = covered(find_intervals(u, y), N_STEPS)
    for flat in (slice(0, 280), slice(450, 680), slice(850, 1080), slice(1250, N_STEPS)):
        assert not inside[flat].any()
    assert inside[[step - 1 for step in STEPS]].all() and inside[[step + 30 for step in STEPS]].all()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_record_of_noise_alone_has_no_interval(seed):
    rng = np.random.default_rng(seed)
    result = find_intervals(5 + rng.normal(0, 0.2, 4000), 50 + rng.normal(0, 1.0, 4000))
    assert result.accepted.shape == (0, 2)
    assert result.settings["noise_std"] == pytest.approx((0.2, 1.0), rel=0.1)


def test_an_input_without_effect_on_the_output_fails_the_chi_square_test():
    # Each such candidate passes with probability `significance` (1 %), as the next test checks;
    # with this seed none does (with seed 11 the second one would).
    y = np.random.default_rng(12).normal(0, 0.1, N_STEPS)
    result = find_intervals(step_input(), y)
    excited = [c for c in result.candidates if c.input_excited]
    assert len(excited) == len(STEPS)
    for candidate in excited:
        assert candidate.reason == "no causal relation"
        assert candidate.condition_number < 100  # well excited: only causality is missing
        assert candidate.chi2_statistic < candidate.chi2_threshold
    assert result.accepted.shape == (0, 2)


def test_the_chi_square_statistic_has_its_null_distribution_when_the_output_ignores_the_input():
    u = np.r_[np.zeros(150), np.ones(150)]
    order, significance = 3, 0.1
    statistics, passed = [], 0
    for seed in range(300):
        y = np.random.default_rng(seed).normal(0, 1, u.size)
        result = find_intervals(u, y, laguerre_order=order, significance=significance)
        [candidate] = [c for c in result.candidates if c.start < 150 < c.stop]
        statistics.append(candidate.chi2_statistic)
        passed += candidate.accepted
    # Under "no causal relation" the statistic is chi-square with `order` degrees of freedom:
    # mean 3 (standard error 0.14 over 300 records), and 10 % pass (standard error 1.7 %).
    assert np.mean(statistics) == pytest.approx(order, abs=0.45)
    assert passed / 300 == pytest.approx(significance, abs=0.055)
    assert scipy.stats.kstest(statistics, scipy.stats.chi2(order).cdf).pvalue > 0.001


def test_a_slow_ramp_excites_too_little_and_fails_the_condition_number_test():
    u = np.zeros(1000)
    u[300:700] = np.linspace(0, 1, 400)
    u[700:] = 1
    y = lag_response(u, 2.0, 6.0) + np.random.default_rng(12).normal(0, 0.1, u.size)
    result = find_intervals(u, y)
    [ramp] = [c for c in result.candidates if c.start < 500 < c.stop]
    assert ramp.reason == "ill-conditioned"
    assert ramp.condition_number > 1e4
    assert ramp.chi2_statistic > ramp.chi2_threshold  # causal, but not informative
    assert result.accepted.shape == (0, 2)
    relaxed = find_intervals(u, y, max_condition=1e6)
    assert [c.reason for c in relaxed.candidates if c.start < 500 < c.stop] == ["accepted"]


def test_a_response_delayed_past_the_input_excitation_is_joined_to_its_cause():
    rng = np.random.default_rng(16)
    u = np.r_[np.zeros(300), np.ones(700)] + rng.normal(0, 0.05, 1000)
    y = lag_response(u, 2.0, 6.0, delay=80) + rng.normal(0, 0.1, 1000)
    joined = find_intervals(u, y)
    assert [(c.start, c.reason) for c in joined.candidates] == [(290, "accepted")]
    assert joined.candidates[0].stop > 300 + 80 + 24
    # The input's excitation dies out before the output moves: apart, neither half passes.
    split = find_intervals(u, y, merge_gap=0)
    assert [c.reason for c in split.candidates] == ["no causal relation", "no input excitation"]


def pi_loop(setpoint, disturbance, rng):
    """First-order process (gain 2, time constant 8) under PI control, output noise 0.05."""
    pole, gain, kp, ti = np.exp(-1 / 8), 2.0, 0.4, 8.0
    state = integral = 0.0
    u, y = np.zeros(setpoint.size), np.zeros(setpoint.size)
    for k in range(setpoint.size):
        y[k] = state + disturbance[k] + rng.normal(0, 0.05)
        error = setpoint[k] - y[k]
        integral += error / ti
        u[k] = kp * (error + integral)
        state = pole * state + gain * (1 - pole) * u[k]
    return u, y


def test_closed_loop_intervals_follow_the_setpoint_changes_not_the_disturbances():
    setpoint, disturbance = np.zeros(N_STEPS), np.zeros(N_STEPS)
    setpoint[300:], setpoint[1100:] = 1.0, 0.3
    disturbance[700:] = 0.5
    u, y = pi_loop(setpoint, disturbance, np.random.default_rng(13))
    result = find_intervals(u, y, setpoint=setpoint)
    assert_usable(result, N_STEPS)
    assert [(start < 300 < stop, start < 1100 < stop) for start, stop in result.accepted] == [
        (True, False),
        (False, True),
    ]
    [upset] = [c for c in result.candidates if c.start < 710 < c.stop]
    assert upset.reason == "no input excitation"
    for candidate in result.candidates:
        if candidate.accepted:
            assert candidate.static_gain == pytest.approx(2.0, abs=0.2)


def test_nan_breaks_the_record_and_no_interval_holds_one():
    u = step_input()
    y = lag_response(u, 2.0, 6.0) + np.random.default_rng(14).normal(0, 0.1, N_STEPS)
    missing = [100, 305, 1000]
    y[missing] = np.nan
    result = find_intervals(u, y)
    assert_usable(result, N_STEPS)
    assert not covered(result, N_STEPS)[missing].any()
    assert [start < 700 < stop for start, stop in result.accepted].count(True) == 1
    assert [start < 1100 < stop for start, stop in result.accepted].count(True) == 1

    assert find_intervals(u, np.full(N_STEPS, np.nan)).candidates == ()


def test_laguerre_impulse_responses_are_orthonormal():
    impulse = np.zeros(2000)
    impulse[1] = 1.0  # the filters see the deviation from the first sample, 0 here
    basis = _laguerre_regressors(impulse, 5, 0.9)
    np.testing.assert_allclose(basis.T @ basis, np.eye(5), atol=1e-10)


def test_intervals_in_time_units_and_the_table():
    pytest.importorskip("pandas")
    u = step_input()
    y = lag_response(u, 2.0, 6.0) + np.random.default_rng(15).normal(0, 0.1, N_STEPS)
    result = find_intervals(u, y, dt=2.0)
    np.testing.assert_array_equal(result.intervals(), 2.0 * (result.accepted - [0, 1]))
    time = 100 + 0.5 * np.arange(N_STEPS)
    np.testing.assert_array_equal(result.intervals(time)[:, 0], time[result.accepted[:, 0]])
    table = result.to_dataframe()
    assert len(table) == len(result.candidates)
    assert set(table["reason"]) <= set(REASONS)
    np.testing.assert_array_equal(table.loc[table["accepted"], ["start", "stop"]].to_numpy(), result.accepted)
    with pytest.raises(ValueError, match="time has 3 values but the record has 1500"):
        result.intervals([0, 1, 2])


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(u=np.zeros((2, 50))), r"u must be 1-D \(n_steps,\); got shape \(2, 50\)"),
        (dict(y=np.zeros(49)), "u has 50 samples but y has 49"),
        (dict(y=np.r_[np.zeros(49), np.inf]), "y holds a non-finite value at index 49"),
        (dict(setpoint=np.zeros(10)), "setpoint has 10 samples but u has 50"),
        (dict(dt=0), "dt must be a finite number > 0; got 0"),
        (dict(mean_forgetting=1.0), "mean_forgetting must lie strictly between 0 and 1"),
        (dict(variance_forgetting="0.9"), "variance_forgetting must be a finite number"),
        (dict(excitation_threshold=1.0), "excitation_threshold must be greater than 1.0"),
        (dict(noise_std=0.1), r"noise_std must be a pair \(input, output\)"),
        (dict(noise_std=(0.1, -1)), r"noise_std\[1\] must be greater than 0.0"),
        (dict(margin=-1), "margin must be at least 0"),
        (dict(merge_gap=2.5), "merge_gap must be a whole number"),
        (dict(laguerre_order=0), "laguerre_order must be at least 1"),
        (dict(min_length=4), "min_length must be at least 5"),
        (dict(laguerre_pole=1.0), r"laguerre_pole must lie in \[0, 1\)"),
        (dict(max_condition=1), "max_condition must be greater than 1.0"),
        (dict(significance=0), "significance must lie strictly between 0 and 1"),
    ],
)
def test_bad_arguments_are_named(kwargs, message):
    arguments = dict(u=np.zeros(50), y=np.zeros(50)) | kwargs
    with pytest.raises(ValueError, match=message):
        find_intervals(arguments.pop("u"), arguments.pop("y"), **arguments)
