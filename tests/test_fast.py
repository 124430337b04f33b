"""The compiled engine (dynia._fast) against the numpy path: bit for bit, tolerance 0.

Both paths perform the same floating-point operations in the same order (see
the module docstring of dynia._fast), so every comparison here is exact.
"""

import control
import numpy as np
import pytest
from conftest import example_firstorder_input

import dynia
from dynia.engine import kernels
from dynia.engine.windows import moving_window
from dynia.models import FOPDT, FirstOrder, SecondOrderDelay, TransferFunction

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


def _lead_lag(p):
    return control.tf([p[0] * p[1], p[0]], [p[2], 1.0])


def _data(steps=300, seed=0, zero_start=30):
    rng = np.random.default_rng(seed)
    u = example_firstorder_input(steps)
    u[:zero_start] = 0  # every simulation is exactly 0 there: exact cost ties
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + rng.normal(0, 0.3, steps)
    y[100:104] = np.nan
    return u, y


def _assert_same(a, b):
    np.testing.assert_array_equal(a.ic, b.ic)
    np.testing.assert_array_equal(a.ci, b.ci)
    np.testing.assert_array_equal(a.median, b.median)
    np.testing.assert_array_equal(a.gradient, b.gradient)


@pytest.mark.parametrize("flavour", ["thesis", "weighted"])
@pytest.mark.parametrize("window", ["centred", "trailing"])
@pytest.mark.parametrize(
    "n, percentage, conf_level, min_points", [(10, 10, 90, 1), (3, 0.5, 95, 4), (0, 20, 60, 1), (25, 5, 80, 30)]
)
def test_windows_equal_the_numpy_path(flavour, window, n, percentage, conf_level, min_points):
    u, y = _data()
    rng = np.random.default_rng(1)
    params = rng.uniform(0, 7, (1200, 2))
    sims = FirstOrder().simulate(params, u)
    options = dict(
        n=n,
        percentage=percentage,
        conf_level=conf_level,
        flavour=flavour,
        window=window,
        min_points=min_points,
        bins=17,
    )
    numpy_result = moving_window(y, sims, params, [[0, 7], [0, 7]], engine="numpy", **options)
    compiled = moving_window(y, sims, params, [[0, 7], [0, 7]], engine="numba", chunk_steps=37, **options)
    _assert_same(numpy_result, compiled)
    assert compiled.settings.engine == "numba" and numpy_result.settings.engine == "numpy"


def test_every_cost_tied_selects_the_lowest_indices():
    params = np.linspace(0, 1, 50)[:, None]
    sims = np.zeros((50, 12))
    compiled = moving_window(np.zeros(12), sims, params, [[0, 1]], n=2, percentage=10, engine="numba")
    # The five lowest indices hold the values 0 .. 4/49: the band of a stable sort.
    np.testing.assert_array_equal(compiled.ci[0, :, 0], 0.0)
    np.testing.assert_array_equal(compiled.ci[0, :, 1], params[3, 0])
    _assert_same(compiled, moving_window(np.zeros(12), sims, params, [[0, 1]], n=2, percentage=10, engine="numpy"))


MODELS = [
    (FirstOrder(), {"K": (0, 7), "T": (0, 7)}),
    (FOPDT(), {"K": (0, 7), "T": (0, 7), "theta": (0, 3.5)}),
    (SecondOrderDelay(), {"K": (0, 7), "T1": (0, 7), "T2": (0, 3), "theta": (0, 3)}),
    (
        TransferFunction(_lead_lag, names=("K", "a", "T", "theta"), delay="theta"),
        {"K": (0.5, 3), "a": (0, 2), "T": (0.5, 5), "theta": (0, 2.5)},
    ),
]


@pytest.mark.parametrize("model, bounds", MODELS, ids=lambda value: type(value).__name__)
@pytest.mark.parametrize("x0", ["zero", "steady"])
def test_run_equals_the_numpy_path(model, bounds, x0):
    u, y = _data(steps=200)
    options = dict(n_samples=800, n=5, rng=4, x0=x0, dt=0.7)
    numpy_result = dynia.run(u, y, model, bounds, engine="numpy", **options)
    for workers in (1, 3):
        _assert_same(numpy_result, dynia.run(u, y, model, bounds, engine="numba", workers=workers, **options))


@pytest.mark.parametrize("model, bounds", MODELS, ids=lambda value: type(value).__name__)
def test_compiled_simulation_equals_the_model(model, bounds):
    u, y = _data(steps=120)
    rng = np.random.default_rng(5)
    box = np.array(list(bounds.values()))
    params = rng.uniform(box[:, 0], box[:, 1], (300, box.shape[0]))
    source = kernels.CompiledErrors(model, params, u, y, dt=0.4, x0="steady", workers=2)
    errors = np.concatenate([source.rows(0, 50), source.rows(40, 60)[10:], source.rows(55, 120)[5:]])
    with pytest.raises(ValueError, match="must move forward"):
        source.rows(10, 20)
    source.close()
    expected = np.abs(model.simulate(params, u, dt=0.4, x0="steady") - y).T
    expected[np.isnan(y)] = 0
    np.testing.assert_array_equal(errors, expected)


def test_an_overflowing_simulation_is_named():
    unstable = TransferFunction(lambda p: control.tf([1.0], [1.0, -p[0]]), names=("a",))
    u = np.ones(400)
    y = np.zeros(400)
    source = kernels.CompiledErrors(unstable, np.array([[0.5], [3.0]]), u, y, dt=1.0, x0="zero", workers=1)
    with pytest.raises(ValueError, match="simulation of sample 1 is not finite at step"):
        source.rows(0, 400)


def test_engine_choice_is_checked():
    u, y = _data(steps=40)
    bounds = {"K": (0, 7), "T": (0, 7)}
    with pytest.raises(ValueError, match="engine must be one of"):
        dynia.run(u, y, FirstOrder(), bounds, n_samples=100, engine="cuda")
    with pytest.raises(ValueError, match="engine 'numba' covers the 'thesis' and 'weighted'"):
        dynia.run(u, y, FirstOrder(), bounds, n_samples=100, percentage=10, flavour="mcat", engine="numba")
    auto = dynia.run(u, y, FirstOrder(), bounds, n_samples=100, percentage=10, flavour="mcat")
    assert auto.settings.engine == "numpy"
