"""Bring your own model: FunctionModel and StateSpaceModel through every front-end."""

import numpy as np
import pytest
from cli_cases import GOOD

import dynia
from dynia.cli import main
from dynia.errors import ModelError
from dynia.models import FirstOrder, FunctionModel, Model, StateSpaceModel
from dynia.online import OnlineDynia

numba = pytest.importorskip("numba")

U = dynia.synthetic.example_firstorder_input(300)
BOUNDS = {"K": (0, 7), "T": (0.5, 7)}


def euler_step(x, u_k, p, dt):
    return x + dt / p[:, 1:2] * (p[:, 0:1] * u_k - x)


def first_state(x, u_k, p):
    return x[:, 0]


@numba.njit
def compiled_step(x, u_k, p, dt):
    following = np.empty_like(x)
    for i in range(x.shape[0]):
        following[i, 0] = x[i, 0] + dt / p[i, 1] * (p[i, 0] * u_k - x[i, 0])
    return following


@numba.njit
def compiled_output(x, u_k, p):
    return x[:, 0].copy()


LAG = StateSpaceModel(euler_step, first_state, [0.0], ["K", "T"], n_states=1)
COMPILED_LAG = StateSpaceModel(compiled_step, compiled_output, [0.0], ["K", "T"], n_states=1)
Y = LAG.simulate([[2.0, 3.0]], U)[0] + np.random.default_rng(0).normal(0, 0.3, U.size)


def whole_record(params, u, dt):
    return LAG.simulate(params, u, dt)


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_a_function_model_run_equals_moving_window_on_its_output(engine):
    res = dynia.run(U, Y, FunctionModel(whole_record, ["K", "T"]), BOUNDS, n_samples=600, n=5, rng=1, engine=engine)
    by_hand = dynia.moving_window(
        Y, whole_record(res.samples, U, 1.0), res.samples, np.array(list(BOUNDS.values())), n=5, engine=engine
    )
    for name in ("ic", "ci", "gradient"):
        assert np.array_equal(getattr(res, name), getattr(by_hand, name), equal_nan=True), name


def test_a_streaming_function_model_equals_the_whole_record_one():
    def chunked(params, u, dt, state):
        sims = np.empty((params.shape[0], u.shape[0]))
        for k, u_k in enumerate(u):
            sims[:, k] = state[:, 0]
            state = euler_step(state, u_k, params, dt)
        return sims, state

    streaming = FunctionModel(chunked, ["K", "T"], state=lambda params: np.zeros((params.shape[0], 1)))
    params = np.array([[2.0, 3.0], [1.0, 0.7]])
    assert streaming.streams and not FunctionModel(whole_record, ["K", "T"]).streams
    pieces = list(streaming.simulate_chunks(params, U, chunk_steps=70))
    assert [piece.shape[1] for piece in pieces] == [70, 70, 70, 70, 20]
    np.testing.assert_array_equal(np.hstack(pieces), LAG.simulate(params, U))
    online = OnlineDynia(streaming, BOUNDS, n_samples=200, n=4, rng=3).replay(U, Y)
    batch = dynia.run(U, Y, streaming, BOUNDS, n_samples=200, n=4, rng=3, window="trailing")
    assert np.array_equal(online.ic, batch.ic, equal_nan=True)


def test_a_state_space_model_streams_and_its_compiled_loop_equals_the_python_one():
    params = dynia.sampling.uniform(300, [[0, 7], [0.5, 7]], rng=2)
    whole = LAG.simulate(params, U)
    pieces = list(LAG.simulate_chunks(params, U, chunk_steps=64))
    assert max(piece.shape[1] for piece in pieces) == 64
    np.testing.assert_array_equal(np.hstack(pieces), whole)
    assert COMPILED_LAG.compiled and not LAG.compiled
    # The same additions and products in the same order, compiled or not (no fast-math): equal to the bit.
    np.testing.assert_array_equal(COMPILED_LAG.simulate(params, U), whole)
    compiled = dynia.run(U, Y, COMPILED_LAG, BOUNDS, n_samples=500, n=5, rng=4)
    plain = dynia.run(U, Y, LAG, BOUNDS, n_samples=500, n=5, rng=4)
    assert np.array_equal(compiled.ic, plain.ic, equal_nan=True)


def test_a_state_space_model_online_equals_the_trailing_batch_run():
    online = OnlineDynia(COMPILED_LAG, BOUNDS, n_samples=300, n=4, rng=5).replay(U, Y)
    batch = dynia.run(U, Y, COMPILED_LAG, BOUNDS, n_samples=300, n=4, rng=5, window="trailing")
    assert np.array_equal(online.ic, batch.ic, equal_nan=True)
    assert np.array_equal(online.ci, batch.ci, equal_nan=True)


def test_a_state_space_model_identifies_its_parameters():
    res = dynia.run(U, Y, COMPILED_LAG, BOUNDS, n_samples=3000, n=10, rng=6)
    summary = res.summary()
    assert summary["K"]["verdict"] == "identified"
    low, high = summary["K"]["band"]
    assert low < 2.0 < high and summary["K"]["max_ic"] > 0.8


def test_several_inputs_reach_a_state_space_model():
    mixer = StateSpaceModel(
        step=lambda x, u_k, p, dt: x + dt / p[:, 2:3] * (p[:, 0:1] * u_k[0] + p[:, 1:2] * u_k[1] - x),
        output=first_state,
        x0=[0.0],
        names=["K1", "K2", "T"],
        n_states=1,
        n_inputs=2,
    )
    rng = np.random.default_rng(7)
    u = np.column_stack([np.repeat(rng.choice([0.0, 2.0], 10), 40), np.repeat(rng.choice([0.0, 1.0], 8), 50)])
    y = mixer.simulate([[2.0, 0.5, 4.0]], u)[0] + rng.normal(0, 0.02, 400)
    res = dynia.run(u, y, mixer, {"K1": (0, 5), "K2": (0, 5), "T": (0.5, 10)}, n_samples=3000, rng=8)
    for name, truth in (("K1", 2.0), ("K2", 0.5)):
        low, high = res.summary()[name]["band"]
        assert low <= truth <= high and res.summary()[name]["max_ic"] > 0.7, name
    with pytest.raises(
        dynia.DyniaError, match=r"u must have shape \(n_steps, 2\) for a model with 2 inputs; got \(400,\)"
    ):
        dynia.run(u[:, 0], y, mixer, {"K1": (0, 5), "K2": (0, 5), "T": (0.5, 10)}, n_samples=100, rng=8)


@pytest.mark.parametrize(
    "fn, message",
    [
        (
            lambda p, u, dt: (1000 + LAG.simulate(p, u, dt=dt) * 1e-3).astype(np.float16),
            "as float16 values: the parameters' effect is below what float16 resolves; return float64",
        ),
        (
            lambda p, u, dt: LAG.simulate(p, u * 1e-320, dt=dt),
            "0 everywhere: the response is below what float64 resolves",
        ),
    ],
)
def test_an_output_below_the_resolution_is_not_blamed_on_ignored_params(fn, message):
    """Issue 32: a float16 model and a response that underflows got 'it must use params'."""
    with pytest.raises(ModelError, match=message) as caught:
        dynia.run(U, Y, FunctionModel(fn, ["K", "T"]), BOUNDS, n_samples=100, rng=1)
    assert "must use params" not in str(caught.value)


@pytest.mark.parametrize(
    "fn, message",
    [
        (lambda p, u, dt: np.zeros((u.shape[0], p.shape[0])), r"fn returned shape \(300, 100\); expected .*transposed"),
        (lambda p, u, dt: np.zeros(p.shape[0]), r"fn returned shape \(100,\); expected \(n_samples, n_steps\)"),
        (lambda p, u, dt: np.full((p.shape[0], u.shape[0]), np.nan), "every one of the 100 parameter sets is not"),
        (lambda p, u, dt: 1 / 0, "fn raised ZeroDivisionError: division by zero"),
        (lambda p, u, dt: np.ones((p.shape[0], u.shape[0])), "the same output for all 100 parameter sets"),
        (lambda p, u, dt: "text", "fn returned str, not an array of numbers"),
    ],
)
def test_a_broken_function_model_is_one_line_naming_it(fn, message):
    with pytest.raises(ModelError, match=message) as caught:
        dynia.run(U, Y, FunctionModel(fn, ["K", "T"]), BOUNDS, n_samples=100, rng=1)
    assert "FunctionModel(" in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.parametrize(
    "model, message",
    [
        (
            StateSpaceModel(lambda x, u, p, dt: x[:, 0], first_state, [0.0], ["K", "T"], n_states=1),
            r"step returned shape \(100,\); expected \(n_samples, n_states\) = \(100, 1\)",
        ),
        (
            StateSpaceModel(euler_step, lambda x, u, p: x, [0.0], ["K", "T"], n_states=1),
            r"output returned shape \(100, 1\); expected \(n_samples,\) = \(100,\)",
        ),
        (
            StateSpaceModel(euler_step, first_state, lambda p: np.zeros(3), ["K", "T"], n_states=1),
            r"x0\(params\) returned shape \(3,\); expected \(n_samples, n_states\) = \(100, 1\)",
        ),
        (
            StateSpaceModel(lambda x, u, p, dt: x @ np.ones((2, 2)), first_state, [0.0], ["K", "T"], n_states=1),
            "step or output raised ValueError",
        ),
    ],
)
def test_a_broken_state_space_model_is_one_line_naming_it(model, message):
    with pytest.raises(ModelError, match=message) as caught:
        dynia.run(U, Y, model, BOUNDS, n_samples=100, rng=1)
    assert str(caught.value).startswith("StateSpaceModel(")


def test_what_a_custom_model_cannot_do_is_refused_not_ignored():
    with pytest.raises(ModelError, match="x0='steady' is not available"):
        dynia.run(U, Y, LAG, BOUNDS, n_samples=100, rng=1, x0="steady")
    with pytest.raises(ModelError, match="cannot step one sample at a time"):
        OnlineDynia(FunctionModel(whole_record, ["K", "T"]), BOUNDS, n_samples=100)
    with pytest.raises(ModelError, match=r"x0 must be 1 finite numbers"):
        StateSpaceModel(euler_step, first_state, [0.0, 1.0], ["K", "T"], n_states=1)

    class Bare(Model):
        pass

    with pytest.raises(NotImplementedError, match="Bare must implement simulate_chunks"):
        dynia.run(U, Y, Bare(["K"]), {"K": (0, 1)}, n_samples=100, rng=1)
    with pytest.raises(ModelError, match="model must be a dynia.models.Model"):
        dynia.run(U, Y, whole_record, BOUNDS, n_samples=100, rng=1)


def test_the_distributed_run_takes_a_state_space_model():
    pytest.importorskip("distributed")
    from distributed import Client, LocalCluster

    import dynia.distributed

    with LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster, Client(cluster) as client:
        remote = dynia.distributed.run(U, Y, LAG, BOUNDS, client=client, n_samples=300, n=4, rng=9, time_chunks=70)
    local = dynia.run(U, Y, LAG, BOUNDS, n_samples=300, n=4, rng=9)
    assert np.array_equal(remote.ic, local.ic, equal_nan=True)


MODULE = """
import numpy as np
from dynia.models import FunctionModel

def gain(params, u, dt):
    return params[:, :1] * np.asarray(u)[None, :]

instance = FunctionModel(gain, ["K"])

def factory():
    return FunctionModel(gain, ["K"])

not_a_model = 3
"""


@pytest.mark.parametrize("spec", ["usermodels.py:instance", "usermodels.py:factory", "usermodels:factory"])
def test_the_command_line_takes_a_model_from_a_file_or_module(tmp_path, capsys, monkeypatch, spec):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "usermodels.py").write_text(MODULE)
    (tmp_path / "data.csv").write_text(GOOD)
    arguments = ["analyse", "data.csv", "--time", "time", "--input", "u", "--output", "y", "--param", "K=0:5"]
    status = main([*arguments, "--model", spec, "--samples", "200", "--n", "3", "--seed", "1", "--out", "out"])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    assert "K " in captured.out and (tmp_path / "out" / "summary.json").exists()


@pytest.mark.parametrize(
    "spec, message",
    [
        ("usermodels.py:missing", "usermodels.py has no 'missing'"),
        ("usermodels.py:not_a_model", "not_a_model is a int, not a dynia.models.Model"),
        ("nowhere.py:model", "nowhere.py: no such file"),
        ("no_such_module:model", "cannot import no_such_module"),
        ("third-order", "--model must be one of first-order, fopdt, second-order-delay, or MODULE:NAME"),
    ],
)
def test_a_model_the_command_line_cannot_load_is_one_line(tmp_path, capsys, monkeypatch, spec, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "usermodels.py").write_text(MODULE)
    (tmp_path / "data.csv").write_text(GOOD)
    arguments = ["analyse", "data.csv", "--time", "time", "--input", "u", "--output", "y", "--param", "K=0:5"]
    assert main([*arguments, "--model", spec, "--out", "out"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "out").exists()


def test_first_order_still_runs_compiled_and_custom_models_do_not_claim_to():
    assert dynia.pipeline.compiled_simulation(FirstOrder())
    assert not dynia.pipeline.compiled_simulation(LAG)
    assert not dynia.pipeline.compiled_simulation(FunctionModel(whole_record, ["K", "T"]))


@numba.njit
def growing_step(x, u_k, p, dt):
    following = np.empty_like(x)
    for i in range(x.shape[0]):
        following[i, 0] = x[i, 0] * p[i, 1] + p[i, 0] * u_k
    return following


def test_unstable_sets_of_a_compiled_state_space_model_are_dropped_as_on_the_plain_path():
    # |a| > 1 grows without bound: sets with a large a overflow within the record and must be dropped.
    compiled = StateSpaceModel(growing_step, compiled_output, [0.0], ["K", "a"], n_states=1)
    plain = StateSpaceModel(
        lambda x, u_k, p, dt: x * p[:, 1:2] + p[:, 0:1] * u_k, first_state, [0.0], ["K", "a"], n_states=1
    )
    u = np.ones(600)
    y = plain.simulate([[1.0, 0.5]], u)[0]
    bounds = {"K": (0, 2), "a": (0, 5)}
    with pytest.warns(dynia.pipeline.DroppedSamplesWarning):
        fast = dynia.run(u, y, compiled, bounds, n_samples=400, n=3, rng=1)
    with pytest.warns(dynia.pipeline.DroppedSamplesWarning):
        slow = dynia.run(u, y, plain, bounds, n_samples=400, n=3, rng=1, engine="numpy")
    assert 0 < fast.run.n_dropped == slow.run.n_dropped < 400
    assert np.array_equal(fast.samples, slow.samples)
    assert np.array_equal(fast.ic, slow.ic, equal_nan=True)


TWO_INPUTS = """
import numpy as np
from dynia.models import FunctionModel

def gains(params, u, dt):
    u = np.asarray(u)
    return params[:, :1] * u[None, :, 0] + params[:, 1:2] * u[None, :, 1]

model = FunctionModel(gains, ["K1", "K2"], n_inputs=2)
"""


def test_identify_on_two_inputs_says_that_the_record_is_not_screened(tmp_path, capsys, monkeypatch):
    """identify's data-quality check takes one input; with two the DYNIA run is not screened, and it says so."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "twoinputs.py").write_text(TWO_INPUTS)
    rng = np.random.default_rng(5)
    u = np.repeat(rng.uniform(0, 2, (12, 2)), 25, axis=0)
    y = 2.0 * u[:, 0] + 0.5 * u[:, 1] + rng.normal(0, 0.05, u.shape[0])
    rows = "".join(
        f"{t},{a!r},{b!r},{c!r}\n" for t, (a, b, c) in enumerate(zip(u[:, 0].tolist(), u[:, 1].tolist(), y.tolist()))
    )
    (tmp_path / "data.csv").write_text("time,a,b,y\n" + rows)
    arguments = ["identify", "data.csv", "--time", "time", "--input", "a", "--input", "b", "--output", "y"]
    options = ["--model", "twoinputs.py:model", "--param", "K1=0:4", "--param", "K2=0:4", "--samples", "300"]
    status = main([*arguments, *options, "--n", "3", "--seed", "1", "--out", "out"])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    assert "the record is not screened for saturated, frozen or quantised readings" in captured.err
