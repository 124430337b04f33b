"""Tests of dynia.online: the semi-online mode equals the batch trailing-window analysis.

Bit for bit with ``engine="numpy"``: the online window sums are added up oldest
to newest, the numpy engine's order. The compiled engine's running sums agree
with those to rounding (the contract of tests/test_fast.py), not bit for bit.
"""

import math
import pickle
import warnings

import control
import numpy as np
import pytest
from numpy.testing import assert_array_equal

import dynia
from dynia.checkpoint import SharedArrays
from dynia.engine.noise import add_record_errors
from dynia.engine.windows import OverflowedWindowsWarning, moving_window
from dynia.errors import DataError
from dynia.models import FOPDT, FirstOrder, SecondOrderDelay, StateSpaceModel, TransferFunction
from dynia.online import OnlineDynia

FIRST_ORDER_BOUNDS = {"K": (0.0, 5.0), "T": (0.0, 8.0)}
# Bounds in another order than the model's columns, to check the reordering.
FOPDT_BOUNDS = {"theta": (0.0, 6.0), "K": (0.0, 5.0), "T": (0.0, 8.0)}


def record(model, truth, steps=240, seed=5):
    """Steps of both signs, noise, and missing measurements (one alone, two in a row, one early)."""
    u = np.zeros(steps)
    u[20:90], u[90:170] = 2.0, -1.0
    y = model.simulate([truth], u)[0] + np.random.default_rng(seed).normal(0, 0.2, steps)
    y[[index for index in (3, 40, 41, 150) if index < steps]] = np.nan
    return u, y


def trailing_oracle(y, sims, params, bounds, n, percentage, conf_level, bins):
    """The thesis flavour with a trailing window, written out step by step.

    Window sums are added oldest to newest like the engine, so costs (and hence
    the behavioural sets and the unweighted limits) are exact; the likelihood
    is normalised with a sequential sum, so the gradient agrees to rounding.
    """
    n_samples, n_params = params.shape
    count = math.floor(n_samples * percentage / 100)
    c_low = (1 - conf_level / 100) / 2
    positions = [math.floor(c_low * (count - 1)), math.floor((1 - c_low) * (count - 1))]
    ic = np.full((n_params, y.size), np.nan)
    ci = np.full((n_params, y.size, 2), np.nan)
    gradient = np.full((n_params, bins, y.size), np.nan)
    for t in range(y.size):
        total, points = np.zeros(n_samples), 0
        for s in range(max(0, t - 2 * n), t + 1):
            if not np.isnan(y[s]):
                total = total + np.abs(sims[:, s] - y[s])
                points += 1
        if points == 0:
            continue
        cost = (total / points) ** 2
        behavioural = np.argsort(cost, kind="stable")[:count]
        likelihood = 1 - cost[behavioural]
        if likelihood.min() < 0:
            likelihood = likelihood - likelihood.min()
        likelihood = likelihood / sum(likelihood.tolist())
        for p in range(n_params):
            low, high = bounds[p]
            values = params[behavioural, p]
            ci[p, t] = np.sort(values)[positions]
            ic[p, t] = 1 - (ci[p, t, 1] - ci[p, t, 0]) / (high - low)
            which = np.clip(((values - low) / (high - low) * bins).astype(int), 0, bins - 1)
            for b in range(bins):
                gradient[p, b, t] = sum(likelihood[which == b].tolist())
    return ic, ci, gradient


def model_columns(online, model):
    """The samples in the model's parameter order."""
    return online.samples[:, [online.names.index(name) for name in model.names]]


@pytest.mark.parametrize(
    "model, bounds, truth, n_samples, n",
    [
        (FirstOrder(), FIRST_ORDER_BOUNDS, [2.0, 3.0], 1000, 6),
        (FOPDT(), FOPDT_BOUNDS, [2.0, 3.0, 2.5], 600, 4),
    ],
)
def test_equals_a_plain_trailing_window_oracle(model, bounds, truth, n_samples, n):
    u, y = record(model, truth)
    online = OnlineDynia(model, bounds, n_samples=n_samples, n=n, bins=20, rng=3)
    result = online.replay(u, y)
    sims = model.simulate(model_columns(online, model), u)
    ic, ci, gradient = trailing_oracle(y, sims, online.samples, online.bounds, n, 10, 90, 20)
    assert_array_equal(result.ic, ic)
    assert_array_equal(result.ci, ci)
    np.testing.assert_allclose(result.gradient, gradient, rtol=0, atol=1e-12)
    # The record identifies the gain: the band closes around the truth at the end of the first step.
    k = online.names.index("K")
    assert result.ci[k, 85, 0] <= 2.0 <= result.ci[k, 85, 1]
    assert result.ic[k, 85] > 0.8


@pytest.mark.parametrize("flavour", ["thesis", "weighted", "mcat"])
@pytest.mark.parametrize(
    "model, bounds, truth",
    [
        (FirstOrder(), FIRST_ORDER_BOUNDS, [2.0, 3.0]),
        (FOPDT(), FOPDT_BOUNDS, [2.0, 3.0, 2.5]),
    ],
)
def test_equals_the_batch_trailing_engine_bit_for_bit(model, bounds, truth, flavour):
    u, y = record(model, truth)
    settings = dict(n_samples=800, n=5, percentage=10, bins=25, conf_level=80, flavour=flavour, rng=11)
    online = OnlineDynia(model, bounds, **settings).replay(u, y)
    batch = dynia.run(u, y, model, bounds, window="trailing", engine="numpy", **settings)
    assert batch.run.n_dropped == 0
    assert_array_equal(online.samples, batch.samples)
    assert_array_equal(online.ic, batch.ic)
    assert_array_equal(online.ci, batch.ci)
    assert_array_equal(online.median, batch.median)
    # Same flavour code on the same costs: the gradient is exact too.
    assert_array_equal(online.gradient, batch.gradient)
    assert_array_equal(online.time, batch.time)
    assert online.names == batch.names


def test_equals_moving_window_on_precomputed_simulations_with_few_points_required():
    model = FOPDT()
    u, y = record(model, [2.0, 3.0, 2.5], steps=120)
    online = OnlineDynia(model, FOPDT_BOUNDS, n_samples=500, n=3, min_points=4, dt=0.5, rng=2)
    result = online.replay(u, y)
    sims = model.simulate(model_columns(online, model), u, dt=0.5)
    batch = moving_window(y, sims, online.samples, online.bounds, n=3, min_points=4, window="trailing", engine="numpy")
    assert_array_equal(result.ic, batch.ic)
    assert_array_equal(result.ci, batch.ci)
    assert_array_equal(result.median, batch.median)
    assert_array_equal(result.gradient, batch.gradient)
    # Steps 0..4 hold 4 measured points only at step 4 (y[3] is missing): NaN until then.
    assert np.isnan(result.ic[:, :4]).all() and not np.isnan(result.ic[:, 4]).any()
    assert_array_equal(result.time, np.arange(120) * 0.5)


def test_update_returns_and_keeps_the_latest_step():
    model = FirstOrder()
    u, y = record(model, [2.0, 3.0], steps=60)
    online = OnlineDynia(model, FIRST_ORDER_BOUNDS, n_samples=400, n=4, bins=10, rng=4)
    assert online.steps == 0 and np.isnan(online.time)
    assert np.isnan(online.ic).all() and online.gradient.shape == (2, 10)
    for u_t, y_t in zip(u[:30], y[:30]):
        ic, ci, gradient = online.update(u_t, y_t)
    assert ic.shape == (2,) and ci.shape == (2, 2) and gradient.shape == (2, 10)
    assert online.ic is ic and online.ci is ci and online.gradient is gradient
    assert online.steps == 30 and online.time == 29.0
    rest = online.replay(u[30:], y[30:])  # continues where the updates stopped
    whole = OnlineDynia(model, FIRST_ORDER_BOUNDS, n_samples=400, n=4, bins=10, rng=4).replay(u, y)
    assert_array_equal(rest.ic, whole.ic[:, 30:])
    assert_array_equal(rest.time, whole.time[30:])
    assert_array_equal(ic, whole.ic[:, 29])


def test_reset_starts_over_and_mcat_state_is_renewed():
    model = FirstOrder()
    u, y = record(model, [2.0, 3.0], steps=80)
    online = OnlineDynia(model, FIRST_ORDER_BOUNDS, n_samples=400, n=4, flavour="mcat", rng=4)
    first = online.replay(u, y)
    online.reset()
    assert online.steps == 0 and np.isnan(online.ic).all()
    again = online.replay(u, y)
    assert_array_equal(first.ic, again.ic)
    assert_array_equal(first.gradient, again.gradient)


def test_same_seed_same_results_other_seed_other_samples():
    model = FirstOrder()
    u, y = record(model, [2.0, 3.0], steps=60)
    runs = [OnlineDynia(model, FIRST_ORDER_BOUNDS, n_samples=300, n=3, rng=seed).replay(u, y) for seed in (8, 8, 9)]
    assert_array_equal(runs[0].samples, runs[1].samples)
    assert_array_equal(runs[0].ic, runs[1].ic)
    assert_array_equal(runs[0].gradient, runs[1].gradient)
    assert not np.array_equal(runs[0].samples, runs[2].samples)
    generator = OnlineDynia(model, FIRST_ORDER_BOUNDS, n_samples=300, rng=np.random.default_rng(8))
    assert_array_equal(generator.samples, runs[0].samples)


def test_diverging_sets_rank_last():
    """An unstable pole overflows for a > ~2.4 within 300 steps; those sets must never be behavioural.

    The batch engine rejects non-finite simulations, so the oracle replaces
    them by 1e200: every window holding such a point then costs inf, which
    is what the online mode gives a set from the step it diverges on.
    """
    model = TransferFunction(lambda p: control.tf([1.0], [1.0, -p[0]]), names=("a",))
    u = np.r_[np.zeros(10), np.ones(290)]
    y = model.simulate([[-0.5]], u)[0] + np.random.default_rng(1).normal(0, 0.05, u.size)
    y[100] = np.nan
    for flavour in ("thesis", "weighted"):
        online = OnlineDynia(model, {"a": (-1.0, 3.0)}, n_samples=500, n=4, flavour=flavour, rng=6)
        result = online.replay(u, y)
        with np.errstate(over="ignore", invalid="ignore"):
            sims = model.simulate(online.samples, u)
        diverged = ~np.isfinite(sims).all(axis=1)
        assert 40 < online.n_diverged == diverged.sum()
        sims[~np.isfinite(sims)] = 1e200
        batch = moving_window(
            y, sims, online.samples, online.bounds, n=4, flavour=flavour, window="trailing", engine="numpy"
        )
        assert_array_equal(result.ic, batch.ic)
        assert_array_equal(result.ci, batch.ci)
        assert_array_equal(result.median, batch.median)
        assert_array_equal(result.gradient, batch.gradient)
        assert (result.ci[0, -1] < 0).all()  # the band ends around the true a = -0.5


def test_mcat_stays_finite_when_sets_diverge():
    model = TransferFunction(lambda p: control.tf([1.0], [1.0, -p[0]]), names=("a",))
    u = np.r_[np.zeros(10), np.ones(290)]
    y = model.simulate([[-0.5]], u)[0]
    online = OnlineDynia(model, {"a": (0.0, 3.0)}, n_samples=400, n=4, flavour="mcat", rng=6)
    result = online.replay(u, y)
    assert online.n_diverged > 0
    assert np.isfinite(result.ic).all() and np.isfinite(result.gradient).all()


def test_model_stepper_equals_simulate_bit_for_bit():
    """The per-step update the online mode uses is the batch simulation's own loop."""
    rng = np.random.default_rng(3)
    u = np.round(rng.uniform(-1, 1, 50), 2)
    lead_lag = TransferFunction(
        lambda p: control.tf([p[0] * p[1], p[0]], [p[2], 1.0]), names=("K", "a", "T", "theta"), delay="theta"
    )
    cases = [
        (FirstOrder(), rng.uniform(0, 5, (40, 2)), 1.0),
        (FOPDT(), np.c_[rng.uniform(0, 5, (40, 2)), rng.uniform(0, 7, 40)], 0.7),  # fractional delays
        (FOPDT(), np.c_[rng.uniform(0, 5, (40, 2)), np.full(40, 3.0)], 1.0),  # one common delay
        (SecondOrderDelay(), np.c_[rng.uniform(0, 5, (40, 3)), rng.uniform(0, 9, 40)], 1.3),
        (lead_lag, np.c_[rng.uniform(0.1, 5, (40, 3)), rng.uniform(0, 9, 40)], 0.5),  # feedthrough
    ]
    for model, params, dt in cases:
        for x0 in ("zero", "steady"):
            stepper = model.stepper(params, dt=dt, x0=x0)
            stepped = np.stack([stepper.step(u_k).copy() for u_k in u], axis=1)
            assert_array_equal(stepped, model.simulate(params, u, dt=dt, x0=x0))
            assert stepper.steps == u.size


def test_stepper_rejects_bad_input():
    stepper = FirstOrder().stepper([[1.0, 1.0]])
    with pytest.raises(ValueError, match="finite"):
        stepper.step(float("nan"))
    with pytest.raises(TypeError, match="real number"):
        stepper.step("1.0")
    with pytest.raises(ValueError, match="dead time"):
        FOPDT().stepper([[1.0, 1.0, 1e9]])
    assert not stepper.step(1.0).flags.writeable


@pytest.mark.parametrize(
    "u_t, y_t, error, match",
    [
        (float("nan"), 1.0, ValueError, "u_t must be finite"),
        (float("inf"), 1.0, ValueError, "u_t must be finite"),
        (1.0, float("inf"), ValueError, "y_t must be finite.*NaN marks a missing"),
        ("1", 1.0, TypeError, "u_t must be a real number"),
        (1.0, [1.0], TypeError, "y_t must be a real number"),
        (True, 1.0, TypeError, "u_t must be a real number"),
    ],
)
def test_update_rejects_bad_values_without_advancing(u_t, y_t, error, match):
    online = OnlineDynia(FirstOrder(), FIRST_ORDER_BOUNDS, n_samples=100, n=2, rng=0)
    online.update(0.0, 0.0)
    with pytest.raises(error, match=match):
        online.update(u_t, y_t)
    assert online.steps == 1
    online.update(np.float32(1.0), np.array(0.5))  # numpy scalars are fine


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(model="FirstOrder"), dynia.ModelError, "model must be a dynia.models.Model"),
        (dict(bounds={"K": (0, 5)}), ValueError, "missing: \\['T'\\]"),
        (dict(bounds=[(0, 5), (0, 8)]), ValueError, "bounds must map"),
        (dict(sampler="iis"), ValueError, "OnlineDynia does not support sampler='iis'"),
        (dict(flavour="glue"), ValueError, "flavour must be one of"),
        (dict(n=-1), ValueError, "n must be at least 0"),
        (dict(n_samples=2.5), ValueError, "n_samples must be a whole number"),
        (dict(percentage=0.1), ValueError, "at least 2 are needed"),
        (dict(conf_level=100), ValueError, r"conf_level is a percentage in \(50, 100\)"),
        (dict(min_points=0), ValueError, "min_points must be at least 1"),
        (dict(dt=0), ValueError, "dt must be a finite number > 0"),
        (dict(x0="initial"), ValueError, "x0 must be one of"),
    ],
)
def test_constructor_rejects_bad_settings(kwargs, error, match):
    arguments = dict(model=FirstOrder(), bounds=FIRST_ORDER_BOUNDS, n_samples=100)
    arguments.update(kwargs)
    with pytest.raises(error, match=match):
        OnlineDynia(arguments.pop("model"), arguments.pop("bounds"), **arguments)


def test_replay_checks_the_whole_record_before_feeding():
    online = OnlineDynia(FirstOrder(), FIRST_ORDER_BOUNDS, n_samples=100, n=2, rng=0)
    with pytest.raises(ValueError, match="u has 5 samples but y has 4"):
        online.replay(np.zeros(5), np.zeros(4))
    with pytest.raises(ValueError, match="u holds a non-finite value at index 3"):
        online.replay([0.0, 0.0, 0.0, np.nan], np.zeros(4))
    assert online.steps == 0


# ------------------------------------------------------------------ magnitudes (issue 20)

MAGNITUDE_U = np.r_[np.zeros(20), np.ones(80), np.zeros(100)]
# At rest before the step: the first measured values are exactly zero, so the scale is fixed at the step.
MAGNITUDE_Y = (
    FirstOrder().simulate([[2.0, 3.0]], MAGNITUDE_U)[0]
    + np.r_[np.zeros(20), np.random.default_rng(0).normal(0, 0.05, 180)]
)
MAGNITUDE_BOUNDS = {"K": (0.0, 7.0), "T": (0.5, 7.0)}


def scaled_lag(factor, beyond=None):
    """A first-order lag (Euler) whose output is ``factor`` times its state; ``beyond`` times more while u > 0.5.

    Parameters cannot reach 1e200 (the box refuses them), so the magnitude is in the output map.
    """

    def output(x, u_k, p):
        return factor * x[:, 0] * (beyond if beyond is not None and u_k > 0.5 else 1.0)

    return StateSpaceModel(
        lambda x, u_k, p, dt: x + dt / p[:, 1:2] * (p[:, 0:1] * u_k - x), output, [0.0], ["K", "T"], n_states=1
    )


@pytest.fixture(scope="module")
def unscaled_online():
    return OnlineDynia(scaled_lag(1.0), MAGNITUDE_BOUNDS, n_samples=300, n=5, rng=1).replay(MAGNITUDE_U, MAGNITUDE_Y)


@pytest.mark.parametrize("factor", [2.0**665, 1e200, 1e-200, 2.0**-665])
def test_online_equals_batch_at_huge_and_tiny_magnitudes(unscaled_online, factor):
    """Before: the costs overflowed (underflowed) and tied, IC 0.279/0.112 and noise sigma NaN (0) online."""
    model = scaled_lag(factor)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        online = OnlineDynia(model, MAGNITUDE_BOUNDS, n_samples=300, n=5, rng=1)
        result = online.replay(MAGNITUDE_U, MAGNITUDE_Y * factor)
        batch = dynia.run(MAGNITUDE_U, MAGNITUDE_Y * factor, model, MAGNITUDE_BOUNDS, n_samples=300, n=5, rng=1,
                          window="trailing", engine="numpy")  # fmt: skip
    assert online.error_scale != 1.0
    for field in ("ic", "ci", "median", "gradient", "informative"):
        assert_array_equal(getattr(result, field), getattr(batch, field), err_msg=field)
    assert result.run.noise_sigma == batch.run.noise_sigma
    # DYNIA on MAEs does not depend on the unit: a power of two changes no ranking at all.
    if math.log2(factor).is_integer():
        assert_array_equal(result.ic, unscaled_online.ic)
        assert_array_equal(result.ci, unscaled_online.ci)
        assert_array_equal(result.informative, unscaled_online.informative)
        assert result.run.noise_sigma == unscaled_online.run.noise_sigma * factor
    np.testing.assert_allclose(np.nanmax(result.ic, axis=1), np.nanmax(unscaled_online.ic, axis=1), atol=0.01)
    assert np.nanmax(result.ic, axis=1).min() > 0.9


def test_online_refuses_a_record_that_outgrows_its_first_value():
    """The scale is fixed at the first measured value (1.0 here); y at 1e200 later cannot be squared at it."""
    y = MAGNITUDE_Y.copy()
    y[120:] = 1e200
    online = OnlineDynia(scaled_lag(1.0), MAGNITUDE_BOUNDS, n_samples=300, n=5, rng=1)
    with pytest.raises(dynia.errors.DataError, match=r"y reaches 1e\+200 in magnitude by step 120.*first measured"):
        online.replay(MAGNITUDE_U, y)


def test_online_blanks_windows_whose_model_output_overflows_as_the_batch_run_does():
    """Model output 1e180 times the data while u = 1: those windows' costs tie at inf, so they have no results."""
    model = scaled_lag(1.0, beyond=1e180)
    online = OnlineDynia(model, MAGNITUDE_BOUNDS, n_samples=300, n=5, rng=1)
    with pytest.warns(OverflowedWindowsWarning, match="window ending at step [0-9]+, so its square"):
        result = online.replay(MAGNITUDE_U, MAGNITUDE_Y)
    with pytest.warns(OverflowedWindowsWarning):
        batch = dynia.run(MAGNITUDE_U, MAGNITUDE_Y, model, MAGNITUDE_BOUNDS, n_samples=300, n=5, rng=1,
                          window="trailing", engine="numpy")  # fmt: skip
    assert np.isnan(result.ic[:, 25:100]).all() and not np.isnan(result.ic[:, 150:]).any()
    assert_array_equal(result.ic, batch.ic)
    assert_array_equal(result.gradient, batch.gradient)


def test_a_built_in_model_below_the_resolution_is_not_said_to_ignore_its_parameters():
    """Issue 32: dt = 1e-300 made every FirstOrder set's output the same, refused as 'it must use params'."""
    online = OnlineDynia(FirstOrder(), MAGNITUDE_BOUNDS, n_samples=300, n=5, rng=1, dt=1e-300)
    with pytest.raises(dynia.errors.ModelError, match="the response is below what float64 resolves") as caught:
        online.replay(MAGNITUDE_U, MAGNITUDE_Y)
    assert "must use params" not in str(caught.value)


def test_replay_refuses_a_model_that_ignores_its_parameters():
    """Before: the linear model's windows all tied (IC from ties); the state-space model's refusal named 5 sets."""
    ignoring = StateSpaceModel(
        lambda x, u_k, p, dt: x + dt * (u_k - x), lambda x, u_k, p: x[:, 0], [0.0], ["K", "T"], n_states=1
    )
    online = OnlineDynia(ignoring, MAGNITUDE_BOUNDS, n_samples=300, n=5, rng=1)
    with pytest.raises(dynia.errors.ModelError, match="step and output returned the same output for all 300 "):
        online.replay(MAGNITUDE_U, MAGNITUDE_Y)
    online.reset()
    for u_t, y_t in zip(MAGNITUDE_U, MAGNITUDE_Y):  # an update cannot know that no later input excites it
        online.update(u_t, y_t)
    assert online.steps == MAGNITUDE_U.size
    # A transfer function's factory shows it at once: one system for every set, refused as the stepper is made.
    constant = TransferFunction(lambda p: control.tf([1.0], [1.0, 1.0]), names=("K", "T"))
    with pytest.raises(dynia.errors.ModelError, match=r"factory\(p\) returned the same system for all 300 "):
        OnlineDynia(constant, MAGNITUDE_BOUNDS, n_samples=300, n=5, rng=1)


# -- advance and checkpoints (dynia follow) -------------------------------------------------------------------------


def _logged_record(scale=1.0):
    """A FOPDT record opening with zeros (the error scale is fixed late) and with missing outputs."""
    model = dynia.models.FOPDT()
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0, 2, 40), 25)
    y = (model.simulate([[2.0, 3.0, 2.0]], u)[0] + rng.normal(0, 0.1, u.size)) * scale
    y[[5, 50, 51, 700]] = np.nan
    y[:30] = 0.0
    return model, {"K": (0, 7), "T": (0.1, 7), "theta": (0, 5)}, u, y


@pytest.mark.parametrize("scale", [1.0, 1e-200, 1e200])
@pytest.mark.parametrize(("cut", "block"), [(5, 512), (300, 7), (650, 100)])
def test_advance_leaves_the_state_that_updates_leave(scale, cut, block, monkeypatch):
    monkeypatch.setattr(dynia.online, "_ADVANCE_BLOCK", block)
    model, bounds, u, y = _logged_record(scale)
    advanced, updated = (OnlineDynia(model, bounds, n_samples=300, n=5, rng=1) for _ in range(2))
    advanced_totals, updated_totals = np.zeros(300), np.zeros(300)
    advanced.advance(u[:2], y[:2], advanced_totals)
    advanced.advance(u[2:cut], y[2:cut], advanced_totals)
    for u_t, y_t in zip(u[:cut], y[:cut]):
        scale_before = updated.error_scale
        updated.update(u_t, y_t)
        if updated.error_scale != scale_before:
            updated_totals *= updated.error_scale
        add_record_errors(updated_totals, updated.newest_errors[None])
    assert np.array_equal(advanced_totals, updated_totals)
    assert advanced.error_scale == updated.error_scale
    for u_t, y_t in zip(u[cut:], y[cut:]):
        for mine, theirs in zip(advanced.update(u_t, y_t), updated.update(u_t, y_t)):
            assert np.array_equal(mine, theirs, equal_nan=True)


@pytest.mark.parametrize("cut", [3, 8, 400])
def test_a_checkpoint_goes_on_bit_for_bit(cut):
    model, bounds, u, y = _logged_record()
    online = OnlineDynia(model, bounds, n_samples=300, n=5, rng=1, x0="steady")
    for u_t, y_t in zip(u[:cut], y[:cut]):
        online.update(u_t, y_t)
    shared = SharedArrays()
    first = online.to_bytes(shared)
    again = online.to_bytes(shared)
    assert len(again) < len(online.to_bytes()) / 3  # the samples and the models' coefficients are shared
    restored = [
        OnlineDynia.from_bytes(first, model, SharedArrays.from_bytes(shared.to_bytes())),
        OnlineDynia.from_bytes(again, model, SharedArrays.from_bytes(shared.to_bytes())),
    ]
    for u_t, y_t in zip(u[cut:], y[cut:]):
        expected = online.update(u_t, y_t)
        for other in restored:
            assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(expected, other.update(u_t, y_t)))


def test_a_checkpoint_runs_no_code_it_names():
    model = dynia.models.FirstOrder()
    with pytest.raises(DataError, match=r"names builtins.print"):
        OnlineDynia.from_bytes(pickle.dumps(print), model)
    with pytest.raises(DataError, match="cannot be read"):
        OnlineDynia.from_bytes(b"not a checkpoint", model)
    online = OnlineDynia(model, {"K": (0, 7), "T": (0, 7)}, n_samples=300, n=2, rng=1)
    shared = SharedArrays()
    data = online.to_bytes(shared)
    with pytest.raises(DataError, match="reference"):
        OnlineDynia.from_bytes(data, model)  # written with shared arrays, read without them
