"""Issue 20, hostile cases on the engine and user model code: each failed (crash, silent wrong result or poor
message) before its fix. The CLI and data cases are in ``test_hostile_cases.py``."""

import sys
import warnings

import numpy as np
import pytest

import dynia
from dynia.cli import main
from dynia.engine.windows import OverflowedWindowsWarning, moving_window
from dynia.errors import DataError, ModelError, SettingsError
from dynia.models import FirstOrder, FunctionModel, StateSpaceModel
from dynia.online import OnlineDynia
from dynia.pipeline import DroppedSamplesWarning

numba = pytest.importorskip("numba")

U = np.r_[np.zeros(20), np.ones(80), np.zeros(100)]
Y = FirstOrder().simulate([[2.0, 3.0]], U)[0] + np.random.default_rng(0).normal(0, 0.05, U.size)
BOUNDS = {"K": (0.0, 7.0), "T": (0.1, 7.0)}
SETTINGS = dict(n_samples=300, n=5)


@pytest.fixture(scope="module")
def unscaled():
    return dynia.run(U, Y, FirstOrder(), BOUNDS, rng=1, **SETTINGS)


# ------------------------------------------------------------------ user code that exits


def _exits(code):
    def fn(params, u, dt):
        sys.exit(code)

    return fn


@pytest.mark.parametrize("code", [0, 3])
def test_a_model_function_that_exits_is_a_model_error(code):
    with pytest.raises(ModelError, match=rf"FunctionModel\(.*fn\): fn raised SystemExit\({code}\)"):
        dynia.run(U, Y, FunctionModel(_exits(code), ["K"]), {"K": (0, 1)}, rng=1, **SETTINGS)


def test_a_step_or_x0_that_exits_is_a_model_error():
    def step(x, u_k, p, dt):
        sys.exit(0)

    model = StateSpaceModel(step, lambda x, u_k, p: x[:, 0], [0.0], ["K"], n_states=1)
    with pytest.raises(ModelError, match=r"step or output raised SystemExit\(0\)"):
        model.simulate([[1.0]], U)
    exiting_x0 = StateSpaceModel(lambda x, *a: x, lambda x, u_k, p: x[:, 0], lambda p: sys.exit(4), ["K"], n_states=1)
    with pytest.raises(ModelError, match=r"x0\(params\) raised SystemExit\(4\)"):
        exiting_x0.simulate([[1.0]], U)


def test_keyboard_interrupt_in_user_code_stays_an_interrupt():
    def fn(params, u, dt):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        FunctionModel(fn, ["K"]).simulate([[1.0]], U)


@pytest.mark.parametrize("code", [0, 3])
def test_the_cli_reports_a_model_module_that_exits_at_import(tmp_path, capsys, code):
    data = tmp_path / "d.csv"
    data.write_text("time,u,y\n" + "".join(f"{t},{float(t > 5)},{2.0 * (t > 6)}\n" for t in range(40)))
    module = tmp_path / "exits.py"
    module.write_text(f"import sys\nsys.exit({code})\n")
    status = main(
        ["analyse", str(data), "--time", "time", "--input", "u", "--output", "y", "--model", f"{module}:model"]
        + ["--param", "K=0:5", "--samples", "100", "--n", "3", "--out", str(tmp_path / "out")]
    )
    err = capsys.readouterr().err
    assert status == 2 and err.count("dynia: error:") == 1 and f"SystemExit({code})" in err
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ compiled user code


def test_a_compiled_step_indexing_out_of_range_is_a_model_error_not_a_segfault():
    @numba.njit
    def step(x, u_k, p, dt):
        out = np.empty_like(x)
        for i in range(x.shape[0]):
            out[i, 0] = x[i, 0] + dt / p[i, 1] * (p[i, 0] * u_k - x[i, 0])
            out[i, 50_000_000] = 1.0  # beyond the state: compiled code writes anywhere
        return out

    @numba.njit
    def output(x, u_k, p):
        return x[:, 0].copy()

    model = StateSpaceModel(step, output, [0.0], ["K", "T"], n_states=1)
    assert model.compiled
    with pytest.raises(ModelError, match="in Python, checked before the compiled loop.*IndexError"):
        model.simulate([[2.0, 3.0]], U)
    for engine in ("numba", "numpy"):
        with pytest.raises(ModelError, match="IndexError"):
            dynia.run(U, Y, model, BOUNDS, rng=1, engine=engine, **SETTINGS)


# ------------------------------------------------------------------ magnitudes


@pytest.mark.parametrize("exponent", [-565, 665])  # 2^-565 ~ 1.1e-170, 2^665 ~ 1.2e200
def test_a_record_scaled_by_a_power_of_two_gives_the_unscaled_analysis(unscaled, exponent):
    """DYNIA on MAEs is scale-invariant; a power of two scales exactly, so nothing may change but the MAEs."""
    scale = 2.0**exponent
    sims = FirstOrder().simulate(unscaled.samples, U)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scaled = moving_window(Y * scale, sims * scale, unscaled.samples, unscaled.bounds, n=SETTINGS["n"])
    np.testing.assert_array_equal(scaled.ic, unscaled.ic)
    np.testing.assert_array_equal(scaled.ci, unscaled.ci)
    np.testing.assert_array_equal(scaled.informative, unscaled.informative)
    assert scaled.run.noise_sigma == unscaled.run.noise_sigma * scale


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_tiny_values_no_longer_underflow_into_ties(unscaled, engine):
    """Before: IC 0.279/0.074, 'weak', noise sigma 0 at 1e-170."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tiny = dynia.run(U, Y * 1e-170, FirstOrder(), {"K": (0, 7e-170), "T": (0.1, 7)}, rng=1, engine=engine,
                         **SETTINGS)  # fmt: skip
    np.testing.assert_allclose(np.nanmax(tiny.ic, axis=1), np.nanmax(unscaled.ic, axis=1), atol=0.02)
    assert {name: v["verdict"] for name, v in tiny.verdicts.items()} == {
        name: v["verdict"] for name, v in unscaled.verdicts.items()
    }
    assert tiny.run.noise_sigma == pytest.approx(unscaled.run.noise_sigma * 1e-170, rel=0.02)


def test_huge_data_against_unscaled_model_output_raises_no_numpy_warning():
    """Before: the MAEs overflowed, costs tied at inf, RuntimeWarning; now the exact ties are below the floor.

    The one warning is dynia's: data 1e200 above anything the model gives are named as such (issue 32).
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        huge = dynia.run(U, Y * 1e200, FirstOrder(), BOUNDS, rng=1, **SETTINGS)
    assert [item.category for item in caught] == [dynia.pipeline.UnreachedOutputWarning]
    assert not huge.informative.any() and np.isfinite(huge.run.noise_sigma)


def test_model_output_beyond_the_data_by_1e54_is_refused_with_the_reason():
    model = FunctionModel(lambda p, u, dt: 1e200 * (1 + FirstOrder().simulate(p, u, dt)), ["K", "T"])
    with pytest.raises(DataError, match="overflows and they tie.*y is at most"):
        dynia.run(U, Y, model, BOUNDS, rng=1, **SETTINGS)
    sims = 1e200 * FirstOrder().simulate(dynia.sampling.sample("uniform", 300, [[0, 7], [0.1, 7]], 1), U)
    with pytest.raises(DataError, match="overflows"):
        moving_window(Y, sims + 1e200, dynia.sampling.sample("uniform", 300, [[0, 7], [0.1, 7]], 1), [[0, 7], [0.1, 7]])


# ------------------------------------------------------------------ partial model checks


def _lag_ignoring_params(x, u_k, p, dt):
    return x + dt * (u_k - x)


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_a_state_space_model_ignoring_params_is_refused(engine):
    python = StateSpaceModel(_lag_ignoring_params, lambda x, u_k, p: x[:, 0], [0.0], ["K", "T"], n_states=1)
    compiled = StateSpaceModel(
        numba.njit(_lag_ignoring_params), numba.njit(lambda x, u_k, p: x[:, 0].copy()), [0.0], ["K", "T"], n_states=1
    )
    for model in (python, compiled):
        with pytest.raises(ModelError, match="same output for all 300 parameter sets over the whole record"):
            dynia.run(U, Y, model, BOUNDS, rng=1, engine=engine, **SETTINGS)


def test_a_streaming_function_model_ignoring_params_is_refused():
    model = FunctionModel(lambda p, u, dt, s: (np.tile(u, (p.shape[0], 1)), s), ["K", "T"], state=lambda p: None)
    with pytest.raises(ModelError, match="fn returned the same output for all 300"):
        dynia.run(U, Y, model, BOUNDS, rng=1, **SETTINGS)


def test_a_state_space_model_quiet_at_first_is_not_refused():
    """Only the whole record counts: the first 20 steps are the same for every set."""
    lag = StateSpaceModel(
        lambda x, u_k, p, dt: x + dt / p[:, 1:2] * (p[:, 0:1] * u_k - x), lambda x, u_k, p: x[:, 0], [0.0],
        ["K", "T"], n_states=1,
    )  # fmt: skip
    chunks = list(lag.simulate_chunks(np.array([[1.0, 2.0], [2.0, 3.0]]), U, chunk_steps=10))
    assert len(chunks) == 20


def test_a_function_model_cannot_change_the_callers_input():
    def writes(params, u, dt):
        u[:] = 0.0
        return params[:, :1] * np.ones_like(u)

    u = U.copy()
    with pytest.raises(ModelError, match="read-only"):
        dynia.run(u, Y, FunctionModel(writes, ["K", "T"]), BOUNDS, rng=1, **SETTINGS)
    np.testing.assert_array_equal(u, U)


def _lag_writing_params(x, u_k, p, dt):
    p[:, 0] = 1.0  # every set's K becomes 1 from the first step on
    return x + dt / p[:, 1:2] * (p[:, 0:1] * u_k - x)


@pytest.mark.parametrize("compiled", [False, True])
def test_a_state_space_model_cannot_change_the_parameter_sets(compiled):
    """Before: the compiled engine and the online stepper handed step a writable params, so every K became 1."""
    step, output = _lag_writing_params, lambda x, u_k, p: x[:, 0].copy()
    if compiled:
        step, output = numba.njit(step), numba.njit(output)
    model = StateSpaceModel(step, output, [0.0], ["K", "T"], n_states=1)
    for engine in ("numba", "numpy"):
        with pytest.raises(ModelError, match="read-only"):
            dynia.run(U, Y, model, BOUNDS, rng=1, engine=engine, **SETTINGS)
    online = OnlineDynia(model, BOUNDS, n_samples=100, n=2, rng=1)
    samples = online.samples.copy()
    with pytest.raises(ModelError, match="read-only"):
        online.update(1.0, 1.0)
    np.testing.assert_array_equal(online.samples, samples)
    params = np.array([[2.0, 3.0], [4.0, 5.0]])
    state = model.start_simulation(params, U)
    with pytest.raises(ModelError, match="read-only"):
        model.simulate_span(state, U, 50)
    np.testing.assert_array_equal(params, [[2.0, 3.0], [4.0, 5.0]])


# ------------------------------------------------------------------ online, short records, percentage 100


def test_online_refuses_a_model_whose_every_set_is_not_finite():
    model = FunctionModel(lambda p, u, dt, s: (np.full((p.shape[0], u.shape[0]), np.nan), s), ["K"], state=lambda p: 0)
    online = OnlineDynia(model, {"K": (0, 1)}, n_samples=100, n=2, rng=1)
    with pytest.raises(ModelError, match="every one of the 100 parameter sets is not finite"):
        online.update(1.0, 1.0)


@pytest.mark.parametrize("steps", [1, 10])
def test_a_record_shorter_than_one_window_is_refused(steps):
    with pytest.raises(SettingsError, match=f"the record has {steps} step.*2n\\+1 = 11"):
        dynia.run(U[:steps], Y[:steps], FirstOrder(), BOUNDS, rng=1, **SETTINGS)
    with pytest.raises(SettingsError, match="fewer than one window"):
        moving_window(Y[:steps], np.zeros((50, steps)), np.full((50, 1), 0.5), [[0, 1]], n=5)


def test_percentage_100_runs_and_has_no_behavioural_spread_test(tmp_path):
    result = dynia.run(U, Y, FirstOrder(), BOUNDS, rng=1, percentage=100, store=tmp_path / "r.nc", **SETTINGS)
    assert np.isnan(result.run.behavioural_multiple) and np.isnan(result.behavioural_floor).all()
    assert all(
        reason["code"] != "noise_ranked" for verdict in result.verdicts.values() for reason in verdict["reasons"]
    )
    assert np.isnan(dynia.load(tmp_path / "r.nc").run.behavioural_multiple)
    online = OnlineDynia(FirstOrder(), BOUNDS, n_samples=300, n=5, percentage=100, rng=1).replay(U, Y)
    assert np.isnan(online.run.behavioural_multiple)


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_windows_where_the_model_output_overflows_are_blanked_with_a_warning(engine):
    """An input of 1e300 at step 100 sends every set's output beyond 1e154 from then on: before, those windows
    ranked overflow ties; now they have no result, and the run says so."""
    u = U.copy()
    u[100] = 1e300
    with pytest.warns(OverflowedWindowsWarning, match=r"in \d+ window\(s\), the first at time 9\d"):
        result = dynia.run(u, Y, FirstOrder(), {"K": (0.5, 7), "T": (0.1, 7)}, rng=1, engine=engine, **SETTINGS)
    blank = np.isnan(result.ic[0])
    assert blank[96:].all() and not blank[:90].any()  # the lags take hundreds of steps to decay below 1e154


def test_sets_dropped_for_an_absurd_input_are_blamed_on_the_input():
    u = U.copy()
    u[100] = 1e308
    with pytest.warns(DroppedSamplesWarning, match=r"the input reaches 1e\+308 in magnitude"):
        with pytest.warns(OverflowedWindowsWarning):
            dynia.run(u, Y, FirstOrder(), BOUNDS, rng=1, **SETTINGS)


def _hog(params, u, dt):
    """A model that holds 1.6 GB while it simulates: beyond a 300 MB worker."""
    block = np.ones((400, 2**19))
    return params[:, :1] * u + 0.0 * block[0, 0]


@pytest.mark.slow
def test_a_worker_lost_at_its_memory_limit_is_named_with_the_limit():
    distributed = pytest.importorskip("distributed")
    from dynia.distributed import run

    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, memory_limit="300MB", dashboard_address=None
        ) as cluster,
        distributed.Client(cluster, set_as_default=False) as client,
    ):
        lost = r"worker memory limit is 286 MB; one time chunk \(300 samples x \d+ steps.*needs about \d+ MB"
        with pytest.raises(SettingsError, match=lost + ".*time_chunks") as raised:
            run(U, Y, FunctionModel(_hog, ["K", "T"]), BOUNDS, client=client, rng=1, **SETTINGS)
    assert raised.value.setting == "time_chunks"


def test_a_transfer_function_whose_factory_ignores_its_parameters_is_refused():
    # The case: dynia.run went ahead and read IC from ties of identical simulations. The check is on the systems the
    # factory builds, so a linear model on an input that never excites it (all zeros) still runs.
    import control

    from dynia.models import TransferFunction

    constant = TransferFunction(lambda p: control.tf([2.0], [3.0, 1.0]), names=("K", "T"))
    with pytest.raises(ModelError, match=r"factory\(p\) returned the same system for all 300 parameter sets"):
        dynia.run(U, Y, constant, BOUNDS, rng=1, **SETTINGS)
    # Sets that differ only in the dead time, which the model simulates itself, are one system by design.
    delayed = TransferFunction(lambda p: control.tf([2.0], [3.0, 1.0]), names=("theta",), delay="theta")
    assert np.isfinite(dynia.run(U, Y, delayed, {"theta": (0.0, 5.0)}, rng=1, **SETTINGS).ic).any()
    using = TransferFunction(lambda p: control.tf([p[0]], [p[1], 1.0]), names=("K", "T"))
    assert dynia.run(np.zeros_like(U), Y, using, BOUNDS, rng=1, **SETTINGS).ic.shape == (2, U.size)
