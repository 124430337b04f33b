"""The numpy twin of the compiled engine (dynia.engine.twin) against the kernels: every number, bit for bit.

Engine "auto" takes the twin for small runs and the compiled kernels for the others, so a user must never see a
result depend on the choice: each case runs both and compares everything the result carries (IC, limits, median,
gradient, the noise floor and its thresholds, the record's fit, the verdicts), the float arrays bit for bit. The
cases: the README's quick start, the thesis's two examples, a record resting at zero (every set simulating 0: exact
ties), lag models with dead times (the kernels' lag path) and without a common one (their general path), transfer
functions, error rows of models that simulate in Python, both flavours, half windows 3, 10 and 30, centred and
trailing windows, both initial states, missing measurements, scaled errors, several time chunks and workers, and many
sets tied exactly. Then what the twin refuses, how "auto" chooses, and that the quick start compiles nothing.
"""

import dataclasses
import importlib
import os
import subprocess
import sys
from pathlib import Path

import control
import numpy as np
import pytest
from conftest import example_firstorder_input

import dynia
from dynia.engine import kernels, twin
from dynia.engine.flavours import CompiledFlavour, TwinFlavour, chosen_engine
from dynia.engine.windows import OverflowedWindowsWarning, moving_window
from dynia.errors import SettingsError
from dynia.models import FOPDT, FirstOrder, FunctionModel, SecondOrderDelay, StateSpaceModel, TransferFunction
from dynia.settings import AnalysisSettings
from dynia.synthetic import thesis_example

needs_numba = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")

QUICK_START = """
import numpy as np
import dynia

u = np.r_[np.zeros(50), np.full(150, 35.0), np.zeros(100)]
y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
y = y + np.random.default_rng(0).normal(0, 0.5, y.size)
res = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=2000, n=10, percentage=10, rng=1)
"""


def assert_identical(ours, theirs, where="result"):
    """Equal values, and float values with equal bits (the sign of a zero, a NaN's payload), field by field."""
    if dataclasses.is_dataclass(ours):
        assert type(ours) is type(theirs), where
        for field in dataclasses.fields(ours):
            assert_identical(getattr(ours, field.name), getattr(theirs, field.name), f"{where}.{field.name}")
    elif isinstance(ours, dict):
        assert ours.keys() == theirs.keys(), where
        for key in ours:
            assert_identical(ours[key], theirs[key], f"{where}[{key!r}]")
    elif isinstance(ours, (list, tuple)):
        assert type(ours) is type(theirs) and len(ours) == len(theirs), where
        for index, (mine, other) in enumerate(zip(ours, theirs)):
            assert_identical(mine, other, f"{where}[{index}]")
    elif isinstance(ours, (np.ndarray, float, np.floating)):
        ours, theirs = np.asarray(ours), np.asarray(theirs)
        np.testing.assert_array_equal(ours, theirs, err_msg=where, strict=True)
        if ours.dtype.kind == "f":
            assert ours.tobytes() == theirs.tobytes(), f"{where}: equal values, different bits"
    else:
        assert ours == theirs, where


def assert_same_result(on_twin, compiled):
    """Everything of the two results identical but the engine each records."""
    assert on_twin.settings.engine == "twin" and compiled.settings.engine == "numba"
    assert_identical(dataclasses.replace(on_twin, settings=compiled.settings), compiled)


def run_both(u, y, model, bounds, **options):
    """``dynia.run`` on the twin and on the kernels, asserted identical; the twin's result."""
    on_twin = dynia.run(u, y, model, bounds, engine="twin", **options)
    compiled = dynia.run(u, y, model, bounds, engine="numba", **options)
    assert_same_result(on_twin, compiled)
    return on_twin


def window_both(y, sims, params, bounds, twin_options=(), **options):
    """``moving_window`` on the twin (with ``twin_options`` too) and on the kernels, asserted identical."""
    on_twin = moving_window(y, sims, params, bounds, engine="twin", **{**options, **dict(twin_options)})
    compiled = moving_window(y, sims, params, bounds, engine="numba", **options)
    assert_same_result(on_twin, compiled)
    return on_twin


def quick_start_record():
    u = np.r_[np.zeros(50), np.full(150, 35.0), np.zeros(100)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(0).normal(0, 0.5, u.size)
    return u, y


def record(steps=240, seed=0, gaps=True):
    """The thesis's first-order input and noisy response, with missing measurements."""
    u = example_firstorder_input(steps)
    u[:20] = 0.0
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(seed).normal(0, 0.3, steps)
    if gaps:
        y[90:97] = np.nan
        y[150] = np.nan
    return u, y


@needs_numba
def test_the_quick_start_runs_on_the_twin_with_the_kernels_numbers(fresh_process):
    u, y = quick_start_record()
    options = dict(n_samples=2000, n=10, percentage=10, rng=1)
    auto = dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, **options)
    assert auto.settings.engine == "twin"
    assert_same_result(auto, dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, engine="numba", **options))


@needs_numba
@pytest.mark.parametrize("flavour", ["thesis", "weighted"])
@pytest.mark.parametrize("number", [1, 2])
def test_the_thesis_examples(number, flavour):
    found = thesis_example(number, np.random.default_rng(number))
    run_both(found.u, found.y, found.model, found.bounds, n_samples=2000, n=10, percentage=10, flavour=flavour, rng=3)


@needs_numba
def test_a_record_resting_at_zero_from_half_way():
    u = np.r_[np.zeros(10), np.ones(40), np.zeros(100), np.full(50, 2.0), np.zeros(400)]
    y = FirstOrder().simulate([[2.0, 0.2]], u)[0]
    y[:300] += np.random.default_rng(2).normal(0, 0.1, 300)
    result = run_both(u, y, FirstOrder(), {"K": (0, 4), "T": (0.05, 0.4)}, n_samples=2000, n=10, rng=4)
    # Every set's simulation has flushed to exactly 0 long before the end: every cost ties there.
    assert not FirstOrder().simulate(result.samples, u)[:, -100:].any()


@needs_numba
@pytest.mark.parametrize("x0", ["zero", "steady"])
@pytest.mark.parametrize("theta", [(2.1, 2.45), (0.0, 6.3)])
def test_lag_models_with_a_dead_time(theta, x0):
    # Dead times within one step of dt are one common delay (the kernels' lag path), wider ranges one per sample.
    u = np.r_[np.full(20, 1.0), example_firstorder_input(180) + 1.0]
    y = FOPDT().simulate([[2.0, 3.0, 2.2]], u, dt=0.5, x0=x0)[0] + np.random.default_rng(5).normal(0, 0.2, u.size)
    bounds = {"K": (0, 4), "T": (0.5, 8), "theta": theta}
    run_both(u, y, FOPDT(), bounds, n_samples=1200, n=6, dt=0.5, x0=x0, rng=6, flavour="weighted")


@needs_numba
def test_transfer_functions_and_two_lags():
    u, y = record(160)
    lead_lag = TransferFunction(lambda p: control.tf([p[0] * p[1], p[0]], [p[2], 1.0]), names=("K", "a", "T"))
    run_both(u, y, lead_lag, {"K": (0.5, 4), "a": (0.1, 2), "T": (0.5, 6)}, n_samples=300, n=4, x0="steady", rng=7)
    bounds = {"K": (0, 4), "T1": (0, 6), "T2": (0, 3), "theta": (0, 3)}
    run_both(u, y, SecondOrderDelay(), bounds, n_samples=800, n=5, rng=8, window="trailing")


@needs_numba
def test_error_rows_of_models_that_simulate_in_python():
    u, y = record(200)

    def first_order(params, u, dt):
        return FirstOrder().simulate(params, u, dt=dt)

    def decay(x, u_k, p, dt):
        return x * np.exp(-dt / p[:, 1:2]) + p[:, 0:1] * (1 - np.exp(-dt / p[:, 1:2])) * u_k

    def output(x, u_k, p):
        return x[:, 0]

    bounds = {"K": (0, 7), "T": (0.2, 7)}
    run_both(u, y, FunctionModel(first_order, ["K", "T"]), bounds, n_samples=600, n=5, rng=9)
    state_space = StateSpaceModel(decay, output, x0=[0.0], names=["K", "T"], n_states=1)
    run_both(u, y, state_space, bounds, n_samples=600, n=5, rng=9, flavour="weighted")


@needs_numba
@pytest.mark.parametrize("flavour", ["thesis", "weighted"])
@pytest.mark.parametrize("window", ["centred", "trailing"])
@pytest.mark.parametrize(
    "n, percentage, conf_level, min_points",
    # 1 % of 800 leaves 8 sets, a set the kernel reads off by selection, not through the samples' ranks.
    [(3, 1, 95, 4), (10, 10, 90, 1), (30, 25, 80, 40)],
)
def test_half_windows_flavours_and_windows(flavour, window, n, percentage, conf_level, min_points):
    u, y = record()
    options = dict(n=n, percentage=percentage, conf_level=conf_level, min_points=min_points, bins=17)
    run_both(
        u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=800, rng=10, flavour=flavour, window=window, **options
    )


@needs_numba
def test_several_time_chunks_and_workers(monkeypatch):
    u, y = record(300)
    # Every chunk's first window is summed afresh: the twin must start afresh at the same steps.
    monkeypatch.setattr(dynia.pipeline, "default_chunk_steps", lambda *_: 23)
    on_twin = dynia.run(
        u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=700, n=8, rng=11, engine="twin", workers=2
    )
    compiled = dynia.run(
        u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=700, n=8, rng=11, engine="numba", workers=1
    )
    assert_same_result(on_twin, compiled)
    params = np.random.default_rng(12).uniform(0, 7, (500, 2))
    sims = FirstOrder().simulate(params, u)
    window_both(y, sims, params, [[0, 7], [0, 7]], {"workers": 2}, n=5, chunk_steps=37, workers=1, window="trailing")


@needs_numba
@pytest.mark.parametrize("flavour", ["thesis", "weighted"])
def test_many_sets_tied_exactly(flavour):
    u, y = record(200, gaps=False)
    rng = np.random.default_rng(13)
    params = rng.uniform(0, 7, (25, 2))[rng.integers(0, 25, 1000)]  # each set about 40 times: its costs tie
    sims = FirstOrder().simulate(params, u)
    window_both(y, sims, params, [[0, 7], [0, 7]], n=4, percentage=7, flavour=flavour)


@needs_numba
# The noise floor's fit meets the overflowing outputs too, on either engine.
@pytest.mark.filterwarnings("ignore:overflow encountered in dot", "ignore:invalid value encountered in scalar divide")
def test_one_step_windows_every_set_behavioural_and_costs_that_overflow():
    u, y = record(200)
    params = np.random.default_rng(17).uniform(0, 7, (400, 2))
    sims = FirstOrder().simulate(params, u)
    window_both(y, sims, params, [[0, 7], [0, 7]], n=0)
    window_both(y, sims, params, [[0, 7], [0, 7]], n=2, percentage=100, flavour="weighted", dtype="float32")
    sims[:150, 60:70] = 1e170  # these sets' costs overflow to inf, the behavioural set's stay finite
    window_both(y, sims, params, [[0, 7], [0, 7]], n=3)
    sims[:, 60:70] = 1e170  # every set's: the windows are left without results
    with pytest.warns(OverflowedWindowsWarning):
        window_both(y, sims, params, [[0, 7], [0, 7]], n=3)


@needs_numba
def test_errors_scaled_for_a_huge_record():
    u, y = record(200)
    scale = 2.0**400  # beyond 2^332: every error is scaled by a power of two before the costs are formed
    run_both(u, y * scale, FirstOrder(), {"K": (0, 7 * scale), "T": (0, 7)}, n_samples=600, n=5, rng=14)


@needs_numba
@pytest.mark.parametrize("weighted", [False, True])
def test_infinite_errors_and_given_window_sums(weighted):
    # Error rows straight into the flavours: a sample whose error overflowed to inf has its windows summed afresh
    # until the step has left; then the fused sources' path, the window sums given.
    rng = np.random.default_rng(15)
    slots, m, n_samples = 9, 60, 300
    rows = rng.uniform(0, 1, (m + slots - 1, n_samples))
    rows[20, 2] = rows[40, 7] = rows[41, 7] = np.inf
    rows[30:33, 11] = 1e308  # a finite sum that overflows on the way
    measured = np.ones(m + slots - 1)
    measured[50:55] = 0.0
    params = rng.uniform(0, 1, (n_samples, 2))
    flavours = [
        kind(params, np.array([[0.0, 1.0], [0.0, 1.0]]), 10, 12, 90, "weighted" if weighted else "thesis", 6)
        for kind in (TwinFlavour, CompiledFlavour)
    ]
    on_twin, compiled = (flavour.analyse_rows(rows, measured, m, slots) for flavour in flavours)
    assert_identical(on_twin, compiled)
    assert np.isinf(twin.window_sums(rows, measured, m, slots)[0][:, 2]).sum() == slots
    sums, present = twin.window_sums(rows, measured, m, slots)
    on_twin, compiled = (flavour.analyse_sums(sums.copy(), present) for flavour in flavours)
    assert_identical(on_twin, compiled)


def test_what_the_twin_does_not_cover_it_refuses():
    u, y = record(60, gaps=False)
    bounds = {"K": (0, 7), "T": (0, 7)}
    for options in (dict(flavour="mcat"), dict(ic_error=True)):
        with pytest.raises(SettingsError, match="engine 'twin' covers"):
            dynia.run(u, y, FirstOrder(), bounds, n_samples=200, n=3, rng=1, engine="twin", **options)
    params = np.random.default_rng(16).uniform(0, 1, (100, 1))
    sims = params * u
    # Importance weights, of the adaptive samplers or given: refused with the settings.
    with pytest.raises(SettingsError, match="which the twin engine does not take"):
        dynia.run(u, y, FirstOrder(), bounds, n_samples=200, n=3, rng=1, engine="twin", sampler="iis")
    with pytest.raises(SettingsError, match="which the twin engine does not take"):
        moving_window(y, sims, params, [[0, 1]], n=3, engine="twin", weights=np.ones(100))
    params[3] = -0.0  # where zeros tie, the kernel's selection may return either
    with pytest.raises(SettingsError, match="negative zero"):
        moving_window(y, sims, params, [[-1, 1]], n=3, engine="twin")
    compiled = StateSpaceModel(lambda x, *_: x, lambda x, *_: x[:, 0], x0=[0.0], names=["a"], n_states=1)
    compiled.compiled = True  # as numba functions make it: the compiled engine simulates it in compiled code
    assert not twin.covers("thesis", params[:3], model=compiled)


@needs_numba
@pytest.mark.parametrize("engine", ["auto", "twin"])
def test_auto_takes_the_twin_for_small_runs_it_covers(engine, fresh_process, monkeypatch):
    settings = AnalysisSettings(n_samples=100, engine=engine)

    def chosen(n_samples, steps, **changes):
        return chosen_engine(settings.replace(**changes), np.ones((n_samples, 2)), steps)

    most_values, most_steps = twin.AUTO_MOST_VALUES, twin.AUTO_MOST_STEPS
    assert chosen(most_values // most_steps, most_steps) == chosen(100, 50) == "twin"
    larger = "twin" if engine == "twin" else "numba"
    assert chosen(most_values // most_steps, most_steps + 1) == chosen(most_values, 2) == larger
    if engine == "auto":
        assert chosen(100, 50, flavour="mcat", percentage=10) == "numpy"
        assert chosen(100, 50, ic_error=True, percentage=50) == "numba"
        # Without numba "auto" runs numpy, as every front-end then does: the twin gives the kernels' numbers.
        monkeypatch.setattr(kernels, "AVAILABLE", False)
        assert chosen(100, 50) == "numpy"


@needs_numba
def test_the_quick_start_compiles_nothing(tmp_path):
    """In a fresh process with an empty numba cache: numba not even imported, no kernel compiled, nothing cached."""
    cache = tmp_path / "numba"
    cache.mkdir()
    script = QUICK_START + (
        "import sys\nassert 'numba' not in sys.modules, 'numba imported'\n"
        "import gc\nfrom numba.core.dispatcher import Dispatcher\n"
        "assert res.settings.engine == 'twin'\n"
        "compiled = [d for d in gc.get_objects() if isinstance(d, Dispatcher) and d.signatures]\n"
        "print(sorted(kernel.py_func.__qualname__ for kernel in compiled))\n"
    )
    root = Path(__file__).resolve().parent.parent
    path = os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")])
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONPATH": path}
    done = subprocess.run([sys.executable, "-c", script], env=env, cwd=root, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
    assert not [path for path in cache.rglob("*") if path.is_file()]  # numba makes a module's folder, and no more


@needs_numba
def test_a_process_that_loaded_the_kernels_or_ran_the_twin_often_takes_the_kernels(fresh_process, monkeypatch):
    """The numbers are the same either way: "auto" takes whichever costs this process less."""
    settings, params = AnalysisSettings(n_samples=100), np.ones((100, 2))
    assert chosen_engine(settings, params, 50) == "twin"
    monkeypatch.setattr(twin, "analyses_run", twin.AUTO_MOST_RUNS - 1)
    u, y = quick_start_record()
    dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=200, n=3, rng=1)  # the tenth on the twin
    assert twin.analyses_run == twin.AUTO_MOST_RUNS
    assert chosen_engine(settings, params, 50) == "numba"
    monkeypatch.setattr(twin, "analyses_run", 0)
    importlib.import_module("dynia.engine.kernels.driver")
    monkeypatch.setattr(kernels, "compiled", lambda: True)  # a run of the process loaded them
    assert chosen_engine(settings, params, 50) == "numba"
    assert chosen_engine(settings.replace(engine="twin"), params, 50) == "twin"  # asked for, it is taken


@needs_numba
@pytest.mark.parametrize("percentage", [0.5, 3, 12])
@pytest.mark.parametrize("weighted", [False, True])
def test_window_costs_that_jump_stall_and_tie(percentage, weighted):
    # The kernel searches each window's threshold and quantile near the last window's: within a bracket, a wider
    # one, a reserve above it, then among every cost. Costs that stand still, drift, jump a thousandfold either way
    # and tie exactly take every one of these paths; every number must be the twin's all the same, and every Monte
    # Carlo batch's those of its samples analysed alone.
    rng = np.random.default_rng(int(percentage * 10) + weighted)
    m, n_samples, batches = 90, 3000, 4
    steps = np.resize([1.0, 1.0, 1.0001, 1.03, 1.5, 4.0, 1e3, 1e-3, 1e-3, 0.7, 50.0, 0.02], m)
    sums = rng.gamma(2.0, 1.0, (m, n_samples)) * np.cumprod(steps)[:, None]
    sums[20:24] = sums[19]  # windows that stand still
    sums[40:50] = np.round(sums[40:50], 0)  # ties everywhere, zeros among them
    sums[60:62] = 0.0  # every sample alike
    present = np.full(m, 11.0)
    params, bounds = rng.uniform(0, 1, (n_samples, 2)), np.array([[0.0, 1.0], [0.0, 1.0]])
    flavour = "weighted" if weighted else "thesis"
    on_twin = TwinFlavour(params, bounds, percentage, 12, 90, flavour, 6).analyse_sums(sums.copy(), present)
    compiled = CompiledFlavour(params, bounds, percentage, 12, 90, flavour, 6).analyse_sums(sums.copy(), present)
    assert_identical(on_twin, compiled)
    if weighted:
        return
    with_batches = CompiledFlavour(params, bounds, percentage, 12, 90, flavour, 6, batches)
    batched = with_batches.analyse_sums(sums.copy(), present)
    assert_identical(batched._replace(batch_ic=None, batch_ci=None), compiled)
    for b in range(batches):
        alone = TwinFlavour(params[b::batches], bounds, percentage, 12, 90, flavour, 6)
        own = alone.analyse_sums(np.ascontiguousarray(sums[:, b::batches]), present)
        assert_identical((batched.batch_ic[b], batched.batch_ci[b]), (own.ic, own.ci))


@needs_numba
@pytest.mark.parametrize("batches", [0, 4])
def test_brackets_handed_from_block_to_block_steer_the_work_never_the_numbers(batches):
    # A flavour hands each block of windows the brackets the last block left, so that its first window's selections
    # start near their answer (blocks analysed side by side take whichever finished last). Whatever those brackets
    # hold, left by another record a thousandfold off, by one window or by many, the numbers are a fresh start's.
    rng = np.random.default_rng(batches)
    m, n_samples = 60, 3000
    steps = np.resize([1.0, 1.03, 4.0, 1e3, 1e-3, 0.7, 1.0], m)
    sums = rng.gamma(2.0, 1.0, (m, n_samples)) * np.cumprod(steps)[:, None]
    sums[30:33] = 0.0
    present = np.full(m, 11.0)
    params, bounds = rng.uniform(0, 1, (n_samples, 2)), np.array([[0.0, 1.0], [0.0, 1.0]])
    fresh = CompiledFlavour(params, bounds, 3, 12, 90, "thesis", 6, batches).analyse_sums(sums.copy(), present)
    carried = CompiledFlavour(params, bounds, 3, 12, 90, "thesis", 6, batches)
    carried.analyse_sums(sums[::-1] * 1e3, present)
    cuts = [0, 7, 8, 31, 32, 60]
    blocks = [carried.analyse_sums(sums[a:b].copy(), present[a:b]) for a, b in zip(cuts[:-1], cuts[1:])]
    # Each field's window axis: the last, but for the limits' pairs (ci, batch_ci), which come after it.
    joined = type(fresh)(
        *(
            None if field is None else np.concatenate([block[i] for block in blocks], axis=-1 - name.endswith("ci"))
            for i, (name, field) in enumerate(zip(fresh._fields, fresh))
        )
    )
    assert_identical(joined, fresh)
