"""Tests of dynia.models.conceptual: HYMOD's water balance and hand-worked steps, the tank's levels, both code paths."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import dynia
from dynia.errors import ModelError, SettingsError
from dynia.models.conceptual import (
    HYMOD_NAMES,
    hymod,
    hymod_fluxes,
    hymod_record,
    tank,
    tank_record,
)
from dynia.pipeline import DroppedSamplesWarning

RNG = np.random.default_rng(20240612)
# Parameter sets across the whole feasible box, the extremes included.
HYMOD_SETS = np.vstack(
    [
        RNG.uniform([1.0, 0.0, 0.0, 0.0, 0.0], [600.0, 3.0, 1.0, 1.0, 1.0], (30, 5)),
        [[250.0, 0.8, 0.6, 0.5, 0.04], [5.0, 0.0, 1.0, 1.0, 1.0], [800.0, 3.0, 0.0, 0.0, 0.0]],
    ]
)


def harsh_forcing(n_steps, rng):
    """Rain with downpours far above any capacity, and evaporation up to 15 mm/day."""
    rain = np.where(rng.random(n_steps) < 0.3, rng.exponential(20.0, n_steps), 0.0)
    rain[rng.integers(0, n_steps, 5)] = 900.0
    return np.column_stack([rain, rng.uniform(0.0, 15.0, n_steps)])


@pytest.fixture(scope="module")
def catchment():
    return hymod_record(400, rng=np.random.default_rng(7))


def test_hymod_water_balance_closes_for_every_parameter_set(catchment):
    for forcing in (catchment.u, harsh_forcing(400, np.random.default_rng(1))):
        for params in HYMOD_SETS:
            flux = hymod_fluxes(params, forcing)
            change = flux["states"][-1].sum() - flux["states"][0].sum()
            balance = forcing[:, 0].sum() - flux["evaporation"].sum() - flux["discharge"].sum()
            assert abs(change - balance) < 1e-9
            # Each step too: rain is stored or becomes excess, nothing else.
            soil = flux["states"][:, 0]
            stored = np.diff(soil) + flux["evaporation"]
            np.testing.assert_allclose(stored + flux["excess"], forcing[:, 0], rtol=0, atol=1e-9)


def test_hymod_water_balance_from_a_wet_start(catchment):
    start = [80.0, 3.0, 2.0, 1.0, 40.0]
    flux = hymod_fluxes(dict(zip(HYMOD_NAMES, HYMOD_SETS[-3])), catchment.u, x0=start)
    assert flux["states"][0].tolist() == start
    change = flux["states"][-1].sum() - sum(start)
    assert abs(change - (catchment.u[:, 0].sum() - flux["evaporation"].sum() - flux["discharge"].sum())) < 1e-9


@pytest.mark.parametrize("compiled", [True, False])
def test_hymod_states_and_flows_never_negative(compiled):
    forcing = harsh_forcing(300, np.random.default_rng(2))
    model = hymod(compiled=compiled)
    state = np.zeros((HYMOD_SETS.shape[0], 5))
    for u_k in forcing:
        assert (model.output_function(state, u_k, HYMOD_SETS) >= 0).all()
        state = model.step_function(state, u_k, HYMOD_SETS, 1.0)
        assert (state >= 0).all()
    for params in HYMOD_SETS:
        flux = hymod_fluxes(params, forcing)
        for key in ("states", "discharge", "evaporation", "excess"):
            assert (flux[key] >= 0).all(), key
        # The soil never holds more than its capacity cmax/(b+1), nor evaporates more than E.
        assert (flux["states"][:, 0] <= params[0] / (params[1] + 1) * (1 + 1e-12)).all()
        assert (flux["evaporation"] <= forcing[:, 1]).all()


@pytest.mark.parametrize("compiled", [True, False])
def test_hymod_one_storm_by_hand(compiled):
    # cmax 100, b 1: Smax = 50. 50 mm on an empty soil fill capacities up to 50, storing
    # 50 * (1 - (1 - 50/100)**2) = 37.5 mm; 12.5 mm is excess, 6.25 mm to each path.
    # Day 1: the quick cascade passes on half of what each store holds, the slow store a tenth.
    u = np.zeros((4, 2))
    u[1, 0] = 50.0
    q = hymod(compiled=compiled).simulate([[100.0, 1.0, 0.5, 0.5, 0.1]], u)[0]
    quick_day1 = 6.25 * 0.5**3
    quick_day2 = (3.125 * 0.5 + 1.5625) * 0.5 * 0.5 + 0.78125 * 0.5  # stores after day 1: 3.125, 1.5625, 0.78125
    assert q[0] == 0.0
    assert q[1] == pytest.approx(quick_day1 + 0.625, abs=1e-12)
    assert q[2] == pytest.approx(quick_day2 + 5.625 * 0.1, abs=1e-12)
    flux = hymod_fluxes([100.0, 1.0, 0.5, 0.5, 0.1], u)
    assert flux["excess"][1] == pytest.approx(12.5, abs=1e-12)
    assert flux["states"][2, 0] == pytest.approx(37.5, abs=1e-12)


def test_hymod_full_soil_passes_all_rain_and_evaporation_follows_moisture():
    params = [100.0, 1.0, 0.5, 0.5, 0.1]
    full = hymod_fluxes(params, [[20.0, 4.0]], x0=[50.0, 0, 0, 0, 0])
    assert full["excess"][0] == pytest.approx(20.0, abs=1e-12)
    assert full["evaporation"][0] == pytest.approx(4.0, abs=1e-12)  # a full store evaporates at the potential rate
    half = hymod_fluxes(params, [[0.0, 4.0]], x0=[25.0, 0, 0, 0, 0])
    assert half["evaporation"][0] == pytest.approx(2.0, abs=1e-12)  # half full: half the potential rate
    assert half["excess"][0] == 0.0


def test_hymod_numba_and_numpy_paths_agree(catchment):
    params = HYMOD_SETS
    compiled = hymod(compiled=True).simulate(params, catchment.u)
    plain = hymod(compiled=False).simulate(params, catchment.u)
    np.testing.assert_allclose(compiled, plain, rtol=1e-12, atol=1e-12)
    assert hymod(compiled=True).compiled and not hymod(compiled=False).compiled
    for row in (0, -3):
        np.testing.assert_allclose(hymod_fluxes(params[row], catchment.u)["discharge"], plain[row], rtol=0, atol=0)


@pytest.mark.parametrize("compiled", [True, False])
def test_invalid_sets_and_inputs_simulate_to_nan(compiled):
    u = np.column_stack([np.full(5, 3.0), np.full(5, 1.0)])
    bad = [
        [0.0, 1.0, 0.5, 0.5, 0.1],
        [100.0, -0.1, 0.5, 0.5, 0.1],
        [100.0, 1.0, 1.5, 0.5, 0.1],
        [100.0, 1.0, 0.5, 1.01, 0.1],
        [100.0, 1.0, 0.5, 0.5, -0.1],
    ]
    good = [100.0, 1.0, 0.5, 0.5, 0.1]
    sims = hymod(compiled=compiled).simulate(bad + [good], u)
    assert np.isnan(sims[:-1, 1:]).all() and np.isfinite(sims[-1]).all()
    negative_rain = u.copy()
    negative_rain[2, 0] = -1.0
    assert np.isnan(hymod(compiled=compiled).simulate([good], negative_rain)[0, 3:]).all()
    levels = tank(compiled=compiled).simulate([[0.0, 0.3], [2.0, -0.1], [2.0, 0.3]], np.full(4, 0.2))
    assert np.isnan(levels[:2, 1:]).all() and np.isfinite(levels[2]).all()


# With the compiled engine the invalid sets are found while analysing (StateErrors.diverged) and the
# analysis is redone without them; both engines must drop the same sets and agree.
@pytest.mark.parametrize("engine", ["numpy", "numba"])
def test_dynia_drops_invalid_sets_with_a_warning(catchment, engine):
    bounds = {"cmax": (10, 500), "b": (0, 2), "alpha": (0, 1), "kq": (0.1, 1.5), "ks": (0, 0.2)}
    with pytest.warns(DroppedSamplesWarning):
        result = dynia.run(
            catchment.u[:100], catchment.y[:100], hymod(), bounds, n_samples=300, n=3, rng=1, engine=engine
        )
    assert result.run.n_dropped == int((result.run.n_sampled - result.samples.shape[0]))
    assert (result.samples[:, result.index("kq")] <= 1).all()
    with pytest.warns(DroppedSamplesWarning):
        other = dynia.run(
            catchment.u[:100],
            catchment.y[:100],
            hymod(),
            bounds,
            n_samples=300,
            n=3,
            rng=1,
            engine="numpy" if engine == "numba" else "numba",
        )
    assert np.array_equal(result.samples, other.samples) and np.array_equal(result.ic, other.ic, equal_nan=True)


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("area, c, inflow", [(2.0, 0.3, 0.45), (0.5, 0.8, 0.1), (5.0, 0.1, 0.3)])
def test_tank_settles_at_the_exact_steady_level(compiled, area, c, inflow):
    # The slowest case has a time constant 2*A*sqrt(h*)/c of 300 steps: 30 of them to settle.
    level = tank(compiled=compiled).simulate([[area, c]], np.full(9000, inflow))[0]
    assert level[-1] == pytest.approx((inflow / c) ** 2, rel=1e-9)
    assert (np.diff(level) >= 0).all()  # filling from empty never overshoots
    # Started at the steady level, it stays there.
    steady = tank(h0=(inflow / c) ** 2, compiled=compiled).simulate([[area, c]], np.full(50, inflow))[0]
    np.testing.assert_allclose(steady, (inflow / c) ** 2, rtol=1e-12)


def test_tank_drains_to_zero_and_stays_there():
    level = tank(h0=4.0).simulate([[1.0, 0.5]], np.zeros(400))[0]
    assert level[0] == 4.0 and level[-1] < 1e-6 and (level >= 0).all() and (np.diff(level) <= 0).all()
    assert tank().simulate([[1.0, 0.5]], np.zeros(5))[0].tolist() == [0.0] * 5


def test_tank_follows_the_ode_and_paths_agree():
    record = tank_record(500, rng=np.random.default_rng(3))
    area, c = record.truth["A"], record.truth["c"]

    def rate(t, h):
        return [(record.u[min(int(t), record.u.size - 1)] - c * np.sqrt(max(h[0], 0.0))) / area]

    accurate = solve_ivp(
        rate, (0, record.u.size - 1), [0.0], t_eval=np.arange(record.u.size), max_step=0.05, rtol=1e-10, atol=1e-12
    ).y[0]
    compiled = tank(compiled=True).simulate([[area, c]], record.u)[0]
    assert np.abs(compiled - accurate).max() < 0.002 * accurate.max()
    assert np.abs(tank(substeps=50).simulate([[area, c]], record.u)[0] - accurate).max() < 0.001 * accurate.max()
    np.testing.assert_allclose(compiled, record.clean, rtol=1e-12, atol=1e-14)
    params = RNG.uniform([0.5, 0.1], [5.0, 0.6], (20, 2))
    np.testing.assert_allclose(
        tank(compiled=True).simulate(params, record.u, dt=0.5),
        tank(compiled=False).simulate(params, record.u, dt=0.5),
        rtol=1e-12,
        atol=1e-14,
    )


def test_records_are_deterministic_and_carry_their_noise():
    first = hymod_record(200, rng=np.random.default_rng(5), noise=0.1)
    again = hymod_record(200, rng=np.random.default_rng(5), noise=0.1)
    assert np.array_equal(first.u, again.u) and np.array_equal(first.y, again.y)
    assert first.u.shape == (200, 2) and (first.u >= 0).all() and (first.u[:5, 0] == 0).all()
    clean = hymod_record(200, rng=np.random.default_rng(5), noise=0.0)
    assert np.array_equal(clean.y, clean.clean)
    flowing = first.clean > 0
    assert 0.07 < np.std(first.y[flowing] / first.clean[flowing] - 1) < 0.13
    # The record is simulated on numpy (compiled=False): that path gives it bit for bit; the compiled
    # one agrees to rounding (numba's and numpy's powers may differ in the last bit).
    truth = [[first.truth[k] for k in HYMOD_NAMES]]
    np.testing.assert_array_equal(first.clean, hymod(compiled=False).simulate(truth, first.u)[0])
    np.testing.assert_allclose(first.clean, hymod().simulate(truth, first.u)[0], rtol=1e-12, atol=1e-14)

    vessel = tank_record(600, rng=np.random.default_rng(5), noise=0.02)
    assert np.array_equal(vessel.y, tank_record(600, rng=np.random.default_rng(5), noise=0.02).y)
    assert (vessel.u[:10] == 0).all() and 0.1 <= vessel.u[10:].min() and vessel.u.max() <= 0.6
    holds = np.diff(np.flatnonzero(np.diff(vessel.u)))
    assert holds.min() >= 60 and holds.max() <= 150
    assert 0.015 < np.std(vessel.y - vessel.clean) < 0.025


@pytest.mark.parametrize(
    "call",
    [
        lambda: hymod_record(10, rng=np.random.default_rng(1)),
        lambda: hymod_record(100, rng=1),
        lambda: hymod_record(100, rng=np.random.default_rng(1), noise=-0.1),
        lambda: tank_record(100, rng=np.random.default_rng(1), dt=0.0),
        lambda: tank(substeps=0),
        lambda: hymod_fluxes({"cmax": 1.0}, np.zeros((3, 2))),
        lambda: hymod_fluxes([1.0, 1.0, 0.5, 0.5, 0.1], np.zeros(3)),
    ],
)
def test_bad_arguments_raise_settings_errors(call):
    with pytest.raises(SettingsError):
        call()


def test_bad_initial_state_raises_model_error():
    with pytest.raises(ModelError, match="x0 of hymod"):
        hymod(x0=[0.0, 0.0, -1.0, 0.0, 0.0])
    with pytest.raises(ModelError, match="x0 of tank"):
        tank(h0=float("nan"))


def test_dynia_finds_kq_in_a_storm():
    record = hymod_record(365, rng=np.random.default_rng(2009))
    bounds = {"cmax": (10.0, 500.0), "b": (0.0, 2.0), "alpha": (0.0, 1.0), "kq": (0.1, 1.0), "ks": (0.0, 0.2)}
    n = 5
    result = dynia.run(record.u, record.y, hymod(), bounds, n_samples=3000, n=n, rng=1)
    peak = int(np.nanargmax(result.ic[result.index("kq")]))
    truth = record.truth
    flux = hymod_fluxes(truth, record.u)
    slow_flow = truth["ks"] / (1 - truth["ks"]) * flux["states"][1:, 4]
    quick_share = 1 - slow_flow / flux["discharge"][peak]
    # A storm: rain fell in the window, and quick flow carries most of the discharge at the peak of the IC.
    assert record.u[peak - n : peak + n + 1, 0].max() > 5.0
    assert quick_share[peak] >= 0.5
    low, high = result.ci[result.index("kq"), peak]
    assert low <= truth["kq"] <= high
    assert result.summary()["kq"]["verdict"] == "identified"
