"""No simulator leaves a state in the subnormal floats, and flushing moves outputs by less than 1e-289.

A first-order state decays by exp(-dt/T) a step once the input rests at zero; with T = 3 it passes
2.2e-308 (the smallest normal float) after about 2100 steps and would stay subnormal for another ~150.
"""

import numpy as np
import pytest
from conftest import first_order_response

import dynia
from dynia.engine.kernels import CompiledErrors
from dynia.models import FirstOrder, SecondOrderDelay, StateSpaceModel
from dynia.models.base import FLUSH_BELOW

SUBNORMAL = np.finfo(float).smallest_normal

# Input on for 50 steps, then at rest for long enough that every state of T <= 5 would pass through subnormals.
U = np.r_[np.ones(50), np.zeros(4000)]
PARAMS = np.array([[2.0, 3.0], [1.0, 5.0], [0.5, 0.7]])


def _no_subnormal(values):
    values = np.abs(np.asarray(values))
    return not np.any((values > 0) & (values < SUBNORMAL))


def test_flush_threshold_is_far_above_the_subnormals():
    assert FLUSH_BELOW == 2.0**-960 and FLUSH_BELOW > 1e-290 and FLUSH_BELOW / SUBNORMAL > 1e18


def test_first_order_outputs_differ_from_the_unflushed_recursion_by_less_than_1e_289():
    flushed = FirstOrder().simulate(PARAMS, U)
    unflushed = first_order_response(PARAMS[:, 0], PARAMS[:, 1], U)  # the plain recursion of conftest
    assert _no_subnormal(flushed)
    assert not _no_subnormal(unflushed)  # the test record does reach the subnormals without the flush
    # The recursions are written differently (rounding: 1e-14 relative); beyond that only the flush differs.
    assert np.all(np.abs(flushed - unflushed) <= 1e-14 * np.abs(unflushed) + FLUSH_BELOW)
    assert np.all(np.abs(unflushed[flushed == 0]) < 2 * FLUSH_BELOW)  # only what was tiny became zero


@pytest.mark.parametrize("model, params", [(FirstOrder(), PARAMS), (SecondOrderDelay(), [[2.0, 3.0, 2.0, 1.0]])])
def test_states_carried_between_spans_are_never_subnormal(model, params):
    state = model.start_simulation(params, U)
    for stop in range(500, U.size + 1, 500):
        _, state = model.simulate_span(state, U, stop)
        assert _no_subnormal(state.carried[2])


def test_the_compiled_errors_equal_the_numpy_path_on_a_resting_record():
    y = FirstOrder().simulate([[2.0, 3.0]], U)[0]
    errors = CompiledErrors(FirstOrder(), PARAMS, U, y, dt=1.0, x0="zero", workers=1)
    compiled = errors.rows(0, U.size)
    errors.close()
    assert np.array_equal(compiled, np.abs(FirstOrder().simulate(PARAMS, U) - y).T)


def _decay(x, u_k, p, dt):
    return x * np.exp(-dt / p[:, 1:2]) + p[:, 0:1] * (1 - np.exp(-dt / p[:, 1:2])) * u_k


def _output(x, u_k, p):
    return x[:, 0]


def test_a_state_space_model_in_python_flushes_its_states():
    model = StateSpaceModel(_decay, _output, x0=[0.0], names=["K", "T"], n_states=1)
    sims = model.simulate(PARAMS, U)
    reference = first_order_response(PARAMS[:, 0], PARAMS[:, 1], U)
    assert _no_subnormal(sims)
    assert np.all(np.abs(sims - reference) <= 1e-14 * np.abs(reference) + FLUSH_BELOW)


def test_a_compiled_state_space_model_flushes_as_the_python_one():
    numba = pytest.importorskip("numba")
    python = StateSpaceModel(_decay, _output, x0=[0.0], names=["K", "T"], n_states=1)
    compiled = StateSpaceModel(numba.njit(_decay), numba.njit(_output), x0=[0.0], names=["K", "T"], n_states=1)
    assert compiled.compiled
    sims = compiled.simulate(PARAMS, U)
    assert _no_subnormal(sims)
    assert np.allclose(sims, python.simulate(PARAMS, U), rtol=1e-12, atol=1e-300)


def test_a_run_on_a_record_resting_at_zero_is_unchanged_in_its_results():
    y = FirstOrder().simulate([[2.0, 3.0]], U[:600])[0]
    res = dynia.run(U[:600], y, FirstOrder(), {"K": (0, 4), "T": (0.5, 6)}, n_samples=300, n=5, rng=0)
    assert np.isfinite(res.ic).all()
