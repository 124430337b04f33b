"""dynia.distributed.run against dynia.run: the same result bit for bit, whatever the chunks."""

import operator
import pickle
import sys

import control
import numpy as np
import pytest
from conftest import example1_record
from numpy.testing import assert_array_equal

import dynia
from dynia.errors import DataError, ModelError
from dynia.models import FOPDT, FirstOrder, FunctionModel, SecondOrderDelay, StateSpaceModel, TransferFunction

distributed = pytest.importorskip("distributed")
from dynia.distributed import run  # noqa: E402  (after the skip: needs dask.distributed)
from dynia.pipeline import DroppedSamplesWarning  # noqa: E402

STEPS = 160
BOUNDS = {"K": (0.0, 7.0), "T": (0.0, 7.0)}


@pytest.fixture(scope="module")
def client():
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        yield client


@pytest.fixture(scope="module")
def record():
    """Thesis example 1 shortened: K=2, T=3, noise 0.5."""
    return example1_record(STEPS, seed=7)


def assert_same(result, reference):
    assert result.names == reference.names
    for attribute in ("samples", "bounds", "time", "ic", "ci", "median", "gradient", "bin_centres"):
        assert_array_equal(getattr(result, attribute), getattr(reference, attribute), err_msg=attribute)
    settings = result.settings
    # "auto" takes the kernels on the cluster and, for a small run on one machine, their numpy twin: the same numbers.
    if (settings.engine, reference.settings.engine) == ("numba", "twin"):
        settings = settings.replace(engine="twin")
    assert settings == reference.settings


@pytest.mark.parametrize("engine", ["numba", "numpy"])
@pytest.mark.parametrize(
    "sample_chunks, time_chunks",
    [
        (None, None),
        (300, STEPS),  # one task per stage
        (64, 37),  # neither divides evenly
        (101, 3),  # time chunks shorter than the halo n=5
        (1000, 1),  # a sample chunk larger than the population, one-step time chunks
    ],
)
def test_first_order_equals_dynia_run(client, record, sample_chunks, time_chunks, engine):
    u, y = record
    options = dict(n_samples=300, n=5, rng=11, engine=engine)
    result = run(
        u, y, FirstOrder(), BOUNDS, client=client, sample_chunks=sample_chunks, time_chunks=time_chunks, **options
    )
    assert_same(result, dynia.run(u, y, FirstOrder(), BOUNDS, **options))


@pytest.mark.parametrize("window", ["centred", "trailing"])
def test_fopdt_with_fractional_delays_equals_dynia_run(client, window):
    """Dead times off the sample grid, a steady start, dt != 1 and Latin hypercube samples."""
    u = np.r_[np.full(30, 1.0), np.full(50, 3.0), np.full(40, 0.5)]
    y = FOPDT().simulate([[1.5, 4.0, 2.3]], u, dt=0.5, x0="steady")[0]
    bounds = {"theta": (0.0, 5.0), "K": (0.5, 3.0), "T": (0.1, 8.0)}  # not the model's order
    options = dict(
        dt=0.5,
        x0="steady",
        sampler="lhs",
        n_samples=250,
        n=4,
        rng=5,
        window=window,
        engine="numba" if window == "centred" else "numpy",
    )
    result = run(u, y, FOPDT(), bounds, client=client, sample_chunks=90, time_chunks=17, **options)
    assert_same(result, dynia.run(u, y, FOPDT(), bounds, **options))


def test_missing_measurements_equal_dynia_run(client, record):
    u, y = record
    y = y.copy()
    y[40:52] = np.nan
    y[::9] = np.nan
    options = dict(n_samples=300, n=4, min_points=5, rng=3)  # engine "auto"
    result = run(u, y, FirstOrder(), BOUNDS, client=client, sample_chunks=77, time_chunks=10, **options)
    reference = dynia.run(u, y, FirstOrder(), BOUNDS, **options)
    assert np.isnan(reference.ic).any() and not np.isnan(reference.ic).all()  # the case is exercised
    assert_same(result, reference)


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_weighted_flavour_equals_dynia_run(client, record, capsys, engine):
    u, y = record
    options = dict(n_samples=300, n=5, flavour="weighted", percentage=20, conf_level=80, bins=15, rng=4, engine=engine)
    result = run(u, y, FirstOrder(), BOUNDS, client=client, sample_chunks=120, time_chunks=25, progress=True, **options)
    assert_same(result, dynia.run(u, y, FirstOrder(), BOUNDS, **options))
    err = capsys.readouterr().err
    assert "DYNIA windows" in err and f"{y.size}/{y.size}" in err  # it counts the windows, one a step


def test_mcat_flavour_chains_its_state_like_dynia_run(client, record):
    """MCAT's windows carry state forward, so its analysis tasks form a chain. Input and output
    start with 20 exact zeros: every window there fits all samples (max MAE 0), the case that
    switches MCAT's likelihood from 1 - MAE/max to 1 - MAE for the rest of the record."""
    u, y = (np.r_[np.zeros(20), signal[20:]] for signal in record)
    options = dict(n_samples=300, n=3, flavour="mcat", rng=8)
    result = run(u, y, FirstOrder(), BOUNDS, client=client, sample_chunks=100, time_chunks=11, **options)
    assert_same(result, dynia.run(u, y, FirstOrder(), BOUNDS, **options))


def unstable_model():
    """1/(s - a): for large a the simulation overflows and the sample must be dropped."""
    return TransferFunction(lambda p: control.tf([p[0]], [1.0, -p[1]]), names=("K", "a"))


def test_unstable_samples_are_dropped_as_dynia_run_drops_them(client):
    u = np.r_[np.zeros(10), np.ones(90)]
    y = np.r_[np.zeros(10), 1 - np.exp(-np.arange(90) / 2.0)]
    bounds = {"K": (0.1, 2.0), "a": (-2.0, 12.0)}
    options = dict(n_samples=150, n=3, rng=2)
    with pytest.warns(DroppedSamplesWarning, match="36 of 150 parameter sets"):
        result = run(u, y, unstable_model(), bounds, client=client, sample_chunks=45, time_chunks=30, **options)
    with pytest.warns(DroppedSamplesWarning, match="36 of 150 parameter sets"):
        reference = dynia.run(u, y, unstable_model(), bounds, **options)
    drawn = dynia.sampling.uniform(150, [[0.1, 2.0], [-2.0, 12.0]], rng=2)
    with np.errstate(over="ignore", invalid="ignore"):
        finite = np.isfinite(unstable_model().simulate(drawn, u)).all(axis=1)
    assert 0 < (~finite).sum() < 150  # some, not all, overflow
    assert_array_equal(result.samples, drawn[finite])
    assert result.run.n_dropped == (~finite).sum()
    assert_same(result, reference)


def test_every_sample_overflowing_is_a_clear_error(client):
    u = np.ones(100)
    with pytest.raises(ValueError, match="every one of the 20 parameter sets overflowed"):
        run(u, u, unstable_model(), {"K": (0.1, 2.0), "a": (900.0, 1000.0)}, client=client, n_samples=20, n=3, rng=1)


def _refuses_negative_time_constants(params, u, dt):
    """A user's model (not probed before the run, as dynia's own are) that refuses some sets on a worker."""
    if (params[:, 1] < 0).any():
        raise ValueError("T must be >= 0")
    return FirstOrder().simulate(params, u, dt=dt)


def test_a_model_error_on_a_worker_reaches_the_caller_with_its_sample_chunk(client, record):
    u, y = record
    bounds = {"K": (0.0, 7.0), "T": (-1.0, 7.0)}  # negative time constants: rejected by the model
    samples = dynia.sampling.uniform(300, [[0.0, 7.0], [-1.0, 7.0]], rng=6)
    assert samples[0, 1] >= 0 and (samples[100:, 1] < 0).any()  # the first chunk's samples pass the client check
    model = dynia.models.FunctionModel(_refuses_negative_time_constants, ["K", "T"])
    with pytest.raises(ValueError, match=r"sample chunk of samples \d+ to \d+.*T must be >= 0"):
        run(u, y, model, bounds, client=client, sample_chunks=100, n_samples=300, n=5, rng=6)


@pytest.mark.parametrize(
    "name, value, message",
    [
        ("sample_chunks", 0, "sample_chunks must be at least 1"),
        ("time_chunks", -3, "time_chunks must be at least 1"),
        ("time_chunks", 2.5, "time_chunks must be a whole number"),
        ("sample_chunks", "10", "sample_chunks must be a whole number"),
    ],
)
def test_bad_chunk_sizes_are_clear_errors(client, record, name, value, message):
    u, y = record
    with pytest.raises(ValueError, match=message):
        run(u, y, FirstOrder(), BOUNDS, client=client, n_samples=100, **{name: value})


def test_other_bad_arguments_are_clear_errors(client, record):
    u, y = record
    with pytest.raises(TypeError, match="client must be a distributed.Client"):
        run(u, y, FirstOrder(), BOUNDS, client="tcp://localhost:8786")
    with pytest.raises(ValueError, match="adaptive schemes .* use dynia.run"):
        run(u, y, FirstOrder(), BOUNDS, client=client, sampler="iis")
    with pytest.raises(ValueError, match="engine must be one of"):
        run(u, y, FirstOrder(), BOUNDS, client=client, engine="fast")
    with pytest.raises(ValueError, match="does not support engine='twin'.*the twin serves small runs of dynia.run"):
        run(u, y, FirstOrder(), BOUNDS, client=client, engine="twin")
    with pytest.raises(ValueError, match="dt must be a finite number > 0"):
        run(u, y, FirstOrder(), BOUNDS, client=client, dt=0)
    with pytest.raises(ValueError, match="percentage 1 of n_samples 100 keeps 1 parameter sets per window"):
        run(u, y, FirstOrder(), BOUNDS, client=client, n_samples=100, percentage=1)


def test_a_settings_object_and_keywords_go_together_and_the_keywords_win(client, record):
    u, y = record
    settings = dynia.AnalysisSettings(n_samples=300, n=8, conf_level=80)
    both = run(u, y, FirstOrder(), BOUNDS, client=client, settings=settings, n=5, rng=1)
    assert_same(both, dynia.run(u, y, FirstOrder(), BOUNDS, settings=settings.replace(n=5), rng=1))
    assert (both.settings.n, both.settings.conf_level) == (5, 80)


def test_a_client_passed_in_stays_open(client, record):
    u, y = record
    run(u, y, FirstOrder(), BOUNDS, client=client, n_samples=100, n=5, rng=1)
    assert client.status == "running"
    assert client.submit(operator.add, 1, 2).result() == 3


def test_without_a_client_a_local_cluster_runs_and_is_closed(record):
    psutil = pytest.importorskip("psutil")
    u, y = record
    before = {child.pid for child in psutil.Process().children(recursive=True)}
    result = run(u, y, FirstOrder(), BOUNDS, n_samples=200, n=5, rng=9)
    assert_same(result, dynia.run(u, y, FirstOrder(), BOUNDS, n_samples=200, n=5, rng=9))
    leftover = [
        child
        for child in psutil.Process().children(recursive=True)
        if child.pid not in before
        and child.is_running()
        and child.status() != psutil.STATUS_ZOMBIE
        and "resource_tracker" not in " ".join(child.cmdline())
    ]
    assert leftover == []


def test_without_dask_the_error_says_what_to_install(record, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # makes `import distributed` fail
    u, y = record
    with pytest.raises(ImportError, match=r"pip install 'dynia\[distributed\]'"):
        run(u, y, FirstOrder(), BOUNDS)


# Memory bounded in time: each time chunk's task resumes every sample chunk's simulation where its windows begin.

TANK_BOUNDS = {"A": (0.5, 5.0), "c": (0.1, 2.0)}


def tank_step(x, u_k, p, dt):
    return np.maximum(x + dt * (u_k - p[:, 1:2] * np.sqrt(x)) / p[:, 0:1], 0.0)


def tank_output(x, u_k, p):
    return x[:, 0]


def tank():
    """A nonlinear tank with square-root outflow, resumable from its level."""
    return StateSpaceModel(tank_step, tank_output, x0=[1.0], names=["A", "c"], n_states=1)


def tank_record():
    u = np.r_[np.full(40, 0.5), np.full(60, 1.5), np.full(50, 0.2)]
    y = tank().simulate([[2.0, 0.7]], u)[0] + np.random.default_rng(1).normal(0, 0.05, u.size)
    return u, y


# (first step, steps) of every call of lag_chunk: what each call of the model simulated.
LAG_CALLS = []


def lag_chunk(params, u, dt, state):
    """A first-order lag streamed chunk by chunk; the state is the step reached and the output."""
    step, level = state
    LAG_CALLS.append((step, u.shape[0]))
    gain, time_constant = params[:, 0], params[:, 1]
    sims = np.empty((params.shape[0], u.shape[0]))
    for k in range(u.shape[0]):
        sims[:, k] = level
        level = level + dt * (gain * u[k] - level) / time_constant
    return sims, (step + u.shape[0], level)


def lag_start(params):
    return 0, np.zeros(params.shape[0])


def whole_record_lag(params, u, dt):
    sims = np.empty((params.shape[0], u.shape[0]))
    sims[:, 0] = 0.0
    for k in range(1, u.shape[0]):
        sims[:, k] = sims[:, k - 1] + dt * (params[:, 0] * u[k - 1] - sims[:, k - 1]) / params[:, 1]
    return sims


LAG_BOUNDS = {"K": (0.0, 7.0), "T": (1.0, 7.0)}


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_second_order_dead_time_across_time_chunks_equals_dynia_run(client, engine):
    """Dead times of up to 14 steps, longer than a time chunk: the resumed simulation reads inputs
    from chunks simulated by earlier tasks; a steady start and per-sample delays."""
    u = np.r_[np.full(30, 1.0), np.full(50, 3.0), np.full(40, 0.5), np.full(40, 2.0)]
    y = SecondOrderDelay().simulate([[1.5, 4.0, 2.0, 6.5]], u, dt=0.5, x0="steady")[0]
    y = y + np.random.default_rng(2).normal(0, 0.05, u.size)
    bounds = {"K": (0.5, 3.0), "T1": (0.1, 8.0), "T2": (0.1, 8.0), "theta": (0.0, 7.0)}
    options = dict(dt=0.5, x0="steady", n_samples=240, n=4, rng=12, engine=engine)
    result = run(u, y, SecondOrderDelay(), bounds, client=client, sample_chunks=70, time_chunks=6, **options)
    assert result.samples[:, 3].max() / 0.5 > 6 * 2  # dead times of more than two time chunks
    assert_same(result, dynia.run(u, y, SecondOrderDelay(), bounds, **options))


@pytest.mark.parametrize("flavour", ["thesis", "mcat"])
def test_state_space_model_across_time_chunks_equals_dynia_run(client, flavour):
    u, y = tank_record()
    options = dict(n_samples=200, n=4, flavour=flavour, rng=3)
    result = run(u, y, tank(), TANK_BOUNDS, client=client, sample_chunks=70, time_chunks=9, **options)
    assert_same(result, dynia.run(u, y, tank(), TANK_BOUNDS, **options))


def test_streaming_function_model_is_simulated_in_time_chunks_from_the_states_of_one_pass(client, record):
    u, y = record
    model = FunctionModel(lag_chunk, ["K", "T"], state=lag_start)
    options = dict(n_samples=200, n=5, rng=4)
    LAG_CALLS.clear()
    result = run(u, y, model, LAG_BOUNDS, client=client, sample_chunks=100, time_chunks=20, **options)
    # Stage 0 checks each sample chunk over the whole record in one piece, the noise floor simulates the
    # record-best set and its neighbours twice on the client (engine.noise.record_fit) and the record's least
    # squares (dynia.fit.record_least_squares) one set at a time; the rest is simulated in pieces.
    pieces = sorted(call for call in LAG_CALLS if call[1] < STEPS)
    whole = [call for call in LAG_CALLS if call[1] == STEPS]
    assert len(whole) == len(LAG_CALLS) - len(pieces) and len(whole) > 4
    # One pass per sample chunk simulates the record once, paused where a time chunk's windows begin (n = 5
    # steps before it); each time chunk's task resumes there and simulates its windows: the chunk and n either side.
    state_pass = [(0, 15)] + [(start - 5, 20) for start in range(20, STEPS - 20, 20)] + [(STEPS - 25, 25)]
    time_chunks = [(0, 25)] + [(start - 5, 30) for start in range(20, STEPS - 20, 20)] + [(STEPS - 25, 25)]
    assert pieces == sorted((state_pass + time_chunks) * 2)  # twice: two sample chunks
    assert_same(result, dynia.run(u, y, model, LAG_BOUNDS, **options))


def test_a_model_that_cannot_resume_is_simulated_over_the_whole_record(client, record):
    """A FunctionModel without state= answers for the whole record: it takes the whole-record path."""
    u, y = record
    model = FunctionModel(whole_record_lag, ["K", "T"])
    assert not model.resumable
    with pytest.raises(ModelError, match="cannot pause and resume"):
        model.start_simulation([[1.0, 2.0]], u)
    options = dict(n_samples=200, n=5, rng=5)
    result = run(u, y, model, LAG_BOUNDS, client=client, sample_chunks=64, time_chunks=30, **options)
    assert_same(result, dynia.run(u, y, model, LAG_BOUNDS, **options))


@pytest.mark.parametrize(
    "model, params, x0",
    [
        (FirstOrder(), [[2.0, 3.0], [0.5, 0.0]], "zero"),
        (SecondOrderDelay(), [[1.0, 2.0, 3.0, 17.5], [2.0, 0.5, 0.5, 0.0]], "steady"),
        (TransferFunction(lambda p: control.tf([1.0, p[0]], [1.0, p[1], 2.0]), names=("a", "b")), [[1, 3]], "zero"),
        (tank(), [[2.0, 0.7], [4.0, 1.5]], "zero"),
        (FunctionModel(lag_chunk, ["K", "T"], state=lag_start), [[2.0, 3.0]], "zero"),
    ],
)
def test_a_simulation_resumed_from_pickled_states_equals_one_uninterrupted(model, params, x0):
    u = np.abs(np.random.default_rng(3).normal(1.0, 1.0, 90))
    whole = model.simulate(params, u, x0=x0)
    state = model.start_simulation(params, u, x0=x0)
    pieces = []
    for stop in (1, 2, 19, 20, 63, 90):
        time_major = stop % 2 == 0
        resumed = pickle.loads(pickle.dumps(state))
        sims, state = model.simulate_span(resumed, u, stop, time_major=time_major)
        again, _ = model.simulate_span(resumed, u, stop, time_major=time_major)  # the state given stays as it was
        assert_array_equal(again, sims)
        assert state.step == stop
        pieces.append(sims.T if time_major else sims)
    assert_array_equal(np.concatenate(pieces, axis=1), whole)


def test_resuming_with_the_wrong_record_or_step_is_a_clear_error():
    u = np.ones(50)
    state = FirstOrder().start_simulation([[1.0, 2.0]], u)
    with pytest.raises(ModelError, match="stop must be a whole number after the state's step 0"):
        FirstOrder().simulate_span(state, u, 0)
    with pytest.raises(DataError, match="started on a record of 50 steps"):
        FirstOrder().simulate_span(state, u[:40], 10)
    broken = u.copy()
    broken[12] = np.nan
    _, later = FirstOrder().simulate_span(state, u, 10)
    with pytest.raises(DataError, match=r"span of steps 10 to 19 .*u\[2\] = nan"):
        FirstOrder().simulate_span(later, broken, 20)
    with pytest.raises(ModelError, match="state must be the SimulationState"):
        FirstOrder().simulate_span((0, None), u, 10)
