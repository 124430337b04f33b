"""The whole record's least-squares fit and the verdicts that compare the evidence with it (issue 28).

Records that look real, each simulated here apart from dynia.models: a gain that moves half way under weak
excitation, a constant gain under weak excitation with white or slowly wandering (AR(1), 0.98) noise, and a
third-order heater fitted with a first-order-plus-dead-time model.
"""

import dataclasses
import math

import numpy as np
import pytest
import scipy.signal

import dynia
from dynia.fit import fit_segments, record_least_squares
from dynia.result import DyniaResult
from dynia.summary import verdict_table
from dynia.verdicts import assess, record_fit_conflict, record_fit_noise_error

STEPS = 1000


def lag_response(u, gains, time_constant):
    """First-order response (zero-order hold, zero start) whose gain at each step is ``gains``."""
    pole = math.exp(-1 / time_constant)
    y = np.zeros(u.size)
    for k in range(u.size - 1):
        y[k + 1] = pole * y[k] + gains[k] * (1 - pole) * u[k]
    return y


def ar1(rng, n_steps, phi, sd):
    """AR(1) noise of marginal standard deviation ``sd``, started in its stationary distribution."""
    noise = np.empty(n_steps)
    noise[0] = rng.normal(0, sd)
    shocks = rng.normal(0, sd * math.sqrt(1 - phi**2), n_steps)
    for k in range(1, n_steps):
        noise[k] = phi * noise[k - 1] + shocks[k]
    return noise


def weak_record(seed, gain_after=2.0, phi=None):
    """T = 5, gain 2 (``gain_after`` from half way), input levels in [0, 2] held 50 steps, noise SD 0.2."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0, 2, STEPS // 50), 50)
    gains = np.where(np.arange(STEPS) < STEPS // 2, 2.0, gain_after)
    noise = rng.normal(0, 0.2, STEPS) if phi is None else ar1(rng, STEPS, phi, 0.2)
    return u, lag_response(u, gains, 5.0) + noise


def weak_run(seed, **record):
    u, y = weak_record(seed, **record)
    bounds = {"K": (0.0, 5.0), "T": (0.5, 20.0)}
    return u, y, dynia.run(u, y, dynia.models.FirstOrder(), bounds, n=10, n_samples=2000, rng=seed)


def codes(verdict):
    return [reason["code"] for reason in verdict["reasons"]]


def holds_record_fit(summary):
    """Whether a parameter's reported band holds its record fit."""
    lower, upper = summary["band"]
    return lower <= summary["record_fit"] <= upper


def test_the_record_fit_is_the_whole_records_least_squares():
    u, y, result = weak_run(0)
    exact = fit_segments(
        u, y, dynia.models.FirstOrder(), [(0, STEPS)], bounds={"K": (0.0, 5.0), "T": (0.5, 20.0)}, x0="zero"
    )
    assert result.run.record_fit == pytest.approx([exact.parameters["K"], exact.parameters["T"]], rel=1e-6)
    assert result.run.record_fit_se == pytest.approx([exact.std_errors_hac["K"], exact.std_errors_hac["T"]], rel=1e-3)
    assert result.run.record_fit_rmse == pytest.approx(exact.rmse, rel=1e-6)
    summary = result.summary()["K"]
    assert (summary["record_fit"], summary["record_fit_se"]) == (result.run.record_fit[0], result.run.record_fit_se[0])


def test_the_online_replay_records_the_record_fit_of_dynia_run():
    u, y = weak_record(1)
    bounds = {"K": (0.0, 5.0), "T": (0.5, 20.0)}
    batch = dynia.run(u, y, dynia.models.FirstOrder(), bounds, n=10, n_samples=500, rng=1, engine="numpy")
    online = dynia.online.OnlineDynia(dynia.models.FirstOrder(), bounds, n=10, n_samples=500, rng=1).replay(u, y)
    assert online.run.record_fit == pytest.approx(batch.run.record_fit, rel=1e-9)
    assert online.run.record_fit_se == pytest.approx(batch.run.record_fit_se, rel=1e-6)


def test_a_saved_result_keeps_the_record_fit(tmp_path):
    _, _, result = weak_run(2)
    result.save(tmp_path / "result.nc")
    loaded = dynia.load(tmp_path / "result.nc")
    assert loaded.run.record_fit == result.run.record_fit
    assert loaded.run.record_fit_se == result.run.record_fit_se
    assert loaded.run.steady_size_factor == result.run.steady_size_factor
    assert loaded.summary()["K"]["verdict"] == result.summary()["K"]["verdict"]


def test_without_a_start_or_settings_nothing_is_fitted():
    result = band_result((2.0, 3.0), fit=None)
    assert record_least_squares(result, np.zeros(60), np.zeros(60), dynia.models.FirstOrder()) is result


def band_result(band, *, fit=2.5, se=0.01, sigma=None, rmse=None, steady=None):
    """A one-parameter result on [0, 10], n = 2, IC 0.9 with ``band`` at steps 10-39, the record fit given."""
    steps = 60
    ic = np.full(steps, 0.1)
    ic[10:40] = 0.9
    lower, upper = np.full(steps, 0.0), np.full(steps, 10.0)
    lower[10:40], upper[10:40] = band
    run = dict(n_behavioural=200, noise_sigma=sigma, record_fit_rmse=rmse, steady_size_factor=steady)
    if fit is not None:
        run.update(record_fit=(fit,), record_fit_se=(se,))
    return DyniaResult(
        names=("a",),
        samples=np.zeros((2000, 1)),
        bounds=np.array([[0.0, 10.0]]),
        time=np.arange(steps, dtype=float),
        ic=ic[None],
        ci=np.stack([lower, upper], axis=-1)[None],
        gradient=np.zeros((1, 40, steps)),
        bin_centres=np.zeros((1, 40)),
        settings=dict(n=2),
        run=run,
    )


def test_a_band_that_excludes_the_record_fit_is_suspect_and_names_both():
    found = assess(band_result((2.0, 3.0), fit=3.5, se=0.01))["a"]
    assert found["verdict"] == "suspect" and codes(found) == ["disagrees_with_record_fit"]
    text = found["reasons"][0]["text"]
    assert "the band [2, 3] at time" in text and "least-squares fit 3.5 +- 0.01 by 0.5" in text
    assert "thesis 4.4" in text and "slow disturbance" not in text  # no autocorrelated noise to blame


def test_a_band_that_holds_the_record_fit_within_the_tolerance_is_identified():
    assert assess(band_result((2.0, 3.0), fit=3.0))["a"] == {"verdict": "identified", "reasons": []}
    # Beyond the edge by less than two standard errors of the fit and of the band's limit.
    gap, tolerance = 0.02, 2 * math.hypot(0.02, math.sqrt(0.05 * 0.95 / 200) * 1.0 / 0.9)
    assert gap < tolerance
    assert assess(band_result((2.0, 3.0), fit=3.0 + gap, se=0.02))["a"]["verdict"] == "identified"
    assert record_fit_conflict(band_result((2.0, 3.0), fit=3.0 + 1.01 * tolerance, se=0.02), 0) is not None


@pytest.mark.parametrize("se", [math.inf, math.nan])
def test_a_record_fit_the_record_does_not_determine_is_not_compared(se):
    assert assess(band_result((2.0, 3.0), fit=8.0, se=se))["a"]["verdict"] == "identified"


def test_the_fits_misfit_is_not_counted_as_its_uncertainty():
    # Residuals of RMS 1 where the windows see noise of 0.25: three quarters of them are misfit.
    assert record_fit_noise_error(band_result((2.0, 3.0), se=0.2, sigma=0.25, rmse=1.0), 0) == pytest.approx(0.05)
    assert record_fit_noise_error(band_result((2.0, 3.0), se=0.2, sigma=1.5, rmse=1.0), 0) == pytest.approx(0.2)
    found = assess(band_result((2.0, 3.0), fit=3.2, se=0.2, sigma=0.25, rmse=1.0))["a"]
    assert codes(found) == ["disagrees_with_record_fit"]


def test_slow_noise_is_named_as_a_cause():
    text = assess(band_result((2.0, 3.0), fit=3.5, steady=9.0))["a"]["reasons"][0]["text"]
    assert "or a slow disturbance moves the window's estimate (a window of the noise counts 9 times fewer" in text


@pytest.mark.parametrize("seed", [0, 3, 4, 6, 9])
def test_a_gain_that_moves_half_way_under_weak_excitation_is_not_identified(seed):
    _, _, result = weak_run(seed, gain_after=3.0)
    summary = result.summary()["K"]
    assert summary["verdict"] == "suspect" and "disagrees_with_record_fit" in codes(summary)
    # The record fit is the compromise of the two halves; the band is one half's.
    assert 2.1 < summary["record_fit"] < 2.9 and not holds_record_fit(summary)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_constant_gain_under_weak_excitation_stays_identified(seed):
    _, _, result = weak_run(seed)
    summary = result.summary()["K"]
    assert summary["verdict"] == "identified" and summary["reasons"] == []
    assert holds_record_fit(summary) and summary["record_fit"] == pytest.approx(2.0, abs=0.02)


@pytest.mark.parametrize("seed", [0, 1, 3, 4, 6])
def test_slow_noise_raises_no_windows_disagree_and_leaves_no_identified_band_off_the_record_fit(seed):
    _, _, result = weak_run(seed, phi=0.98)
    assert result.run.steady_size_factor > 2  # the noise's own autocorrelation, seen where the output is steady
    for name, summary in result.summary().items():
        assert "windows_disagree" not in codes(summary), (name, summary["reasons"])
        if summary["verdict"] == "identified":
            assert holds_record_fit(summary), (name, summary)


def heater_record(seed):
    """Gain 0.62 and three lags (12, 8, 5 s) at 1 s: a heater whose "dead time" is the lags' apparent one."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(20, 80, 8), 225)
    y = 0.62 * u
    for time_constant in (12.0, 8.0, 5.0):
        pole = math.exp(-1 / time_constant)
        y = scipy.signal.lfilter([0, 1 - pole], [1, -pole], y)
    return u, y + rng.normal(0, 0.05, u.size)


def test_a_third_order_heater_fitted_with_fopdt_leaves_no_identified_band_off_the_record_fit():
    u, y = heater_record(0)
    bounds = {"K": (0.0, 2.0), "T": (1.0, 60.0), "theta": (0.0, 40.0)}
    result = dynia.run(u, y, dynia.models.FOPDT(), bounds, n=10, n_samples=2000, rng=0)
    summary = result.summary()
    identified = [name for name, entry in summary.items() if entry["verdict"] == "identified"]
    assert "K" in identified
    assert all(holds_record_fit(summary[name]) for name in identified)
    # The record's gain is pinned to 0.1 %: the model fits the steady states well, the transients not.
    assert summary["K"]["record_fit"] == pytest.approx(0.62, abs=0.002)


def test_the_table_shows_the_record_fit_and_says_why_the_highest_ic_is_no_evidence():
    result = band_result((2.0, 3.0), fit=2.5, se=0.01)
    ic = result.ic.copy()
    ic[0, 45] = 0.95  # the record's highest IC, in a window below the noise floor
    informative = np.ones(60, dtype=bool)
    informative[45] = False
    result = dataclasses.replace(result, ic=ic, informative=informative)
    summary = result.summary()
    assert summary["a"]["highest_ic_no_evidence"] == ["below_noise_floor"]
    table = verdict_table(summary)
    assert "record fit" in table.splitlines()[0] and "2.5 +- 0.01" in table.splitlines()[1]
    assert "is in a window that is no evidence (below the noise floor)" in table


@pytest.mark.parametrize("x0", ["zero", "steady"])
@pytest.mark.parametrize(
    "model, params",
    [
        (dynia.models.FirstOrder(), [[2.0, 5.0], [1.0, 3.0]]),
        (dynia.models.FOPDT(), [[1.0, 4.0, 2.5]]),
        (dynia.models.SecondOrderDelay(), [[2.0, 5.0, 2.0, 3.3]]),
    ],
)
def test_the_kernel_simulates_for_the_least_squares_as_the_model_does(model, params, x0):
    u = np.random.default_rng(0).normal(size=500)
    kernel = dynia.pipeline.KernelSimulated(model)
    assert kernel.names == model.names and repr(kernel) == repr(model)
    expected = model.simulate(np.array(params), u, dt=0.7, x0=x0)
    assert np.array_equal(kernel.simulate(np.array(params), u, dt=0.7, x0=x0), expected)  # bit for bit
