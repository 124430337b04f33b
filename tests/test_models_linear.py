"""Tests of dynia.models against python-control and an independent ODE solution."""

import math
import warnings

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from dynia.models import FOPDT, FirstOrder, Model, SecondOrderDelay, TransferFunction

RNG = np.random.default_rng(20240601)
# A staircase with steps of both signs and a few repeated values.
U = np.round(RNG.uniform(-1.0, 1.0, 30), 2)
U[5:9] = U[5]


def first_order_tf(p):
    return control.tf([p[0]], [p[1], 1.0])


def second_order_tf(p):
    return control.tf([p[0]], np.polymul([p[1], 1.0], [p[2], 1.0]))


def lead_lag_tf(p):
    # (K (a s + 1)) / (T s + 1): proper, with direct feedthrough K a / T.
    return control.tf([p[0] * p[1], p[0]], [p[2], 1.0])


def third_order_ss(p):
    return control.ss(control.tf([p[0], 1.0], [1.0, 3.0, 3.5, 1.5]))


def lead_lag_model():
    return TransferFunction(lead_lag_tf, names=("K", "a", "T", "theta"), delay="theta")


def steady_state(system, u0):
    return -np.linalg.solve(system.A, system.B[:, 0]) * u0


def control_references(transfer_function, u, dt, x0, substeps=1000):
    """Discrete ZOH response, and continuous response to a finely sampled staircase."""
    system = control.ss(transfer_function)
    initial = steady_state(system, u[0]) if x0 == "steady" else np.zeros(system.nstates)
    times = np.arange(u.size) * dt
    discrete = control.forced_response(control.c2d(system, dt, "zoh"), times, u, initial)
    fine_times = np.arange((u.size - 1) * substeps + 1) * (dt / substeps)
    fine_input = np.repeat(u, substeps)[: fine_times.size]
    continuous = control.forced_response(system, fine_times, fine_input, initial)
    return discrete.outputs, continuous.outputs[::substeps]


DELAY_FREE_CASES = [
    (FirstOrder(), first_order_tf, [[1.5, 2.0], [-0.7, 0.8], [1.0, 5.0]]),
    (
        SecondOrderDelay(),
        second_order_tf,
        [
            [2.0, 1.5, 0.7, 0.0],
            [1.0, 1.2, 1.2, 0.0],
            [-1.0, 0.6, 3.0, 0.0],
            [0.5, 2.0, 2.0 * (1 + 1e-9), 0.0],
        ],
    ),
    (
        TransferFunction(second_order_tf, names=("K", "T1", "T2")),
        second_order_tf,
        [[2.0, 1.5, 0.7], [1.0, 1.2, 1.2]],
    ),
    (lead_lag_model(), lead_lag_tf, [[1.5, 2.0, 0.8, 0.0], [-1.0, 0.3, 1.7, 0.0]]),
    (TransferFunction(third_order_ss, names=("b",)), third_order_ss, [[0.5], [-2.0]]),
]


@pytest.mark.parametrize("model, build, params", DELAY_FREE_CASES)
@pytest.mark.parametrize("x0", ["zero", "steady"])
@pytest.mark.parametrize("dt", [1.0, 0.3])
def test_matches_python_control_without_dead_time(model, build, params, x0, dt):
    y = model.simulate(params, U, dt=dt, x0=x0)
    for row, p in zip(y, np.asarray(params)):
        discrete, continuous = control_references(build(p), U, dt, x0)
        # Both sides are exact ZOH discretisations; they differ only by
        # rounding in expm/closed forms and in the recursion (~1e-14).
        np.testing.assert_allclose(row, discrete, rtol=1e-9, atol=1e-11)
        # python-control interpolates the fine input linearly, turning each
        # jump into a ramp over dt/1000. Each ramp misplaces an input area of
        # |jump| * dt/2000, which moves the response by a similar fraction of
        # its size, i.e. well below 2e-3 of its peak here.
        tolerance = 2e-3 * np.max(np.abs(row))
        np.testing.assert_allclose(row, continuous, atol=tolerance)
        # ...while a convention off by one step would be far outside it.
        assert np.max(np.abs(row[1:] - continuous[:-1])) > 5 * tolerance


def delayed_ode_reference(system, theta, u, dt, x0):
    """Output of a delayed state-space system at t = k*dt by piecewise ODE integration.

    The delayed staircase is constant between the grid points and the
    shifted switching times theta + j*dt, so each such piece is integrated
    on its own with a tight tolerance.
    """
    a, b, c, d = system.A, system.B[:, 0], system.C[0], system.D[0, 0]
    u_before = u[0] if x0 == "steady" else 0.0
    state = -np.linalg.solve(a, b) * u_before if x0 == "steady" else np.zeros(a.shape[0])

    def delayed_input(t):
        index = math.floor((t - theta) / dt)
        return u_before if index < 0 else u[min(index, u.size - 1)]

    grid = np.arange(u.size) * dt
    switches = theta + np.arange(u.size) * dt
    breaks = np.unique(np.round(np.concatenate((grid, switches, [u.size * dt])), 12))
    outputs = []
    for start, stop in zip(breaks[:-1], breaks[1:]):
        level = delayed_input(0.5 * (start + stop))  # value inside the piece
        if np.isclose(start, grid, rtol=0, atol=1e-9).any() and len(outputs) < u.size:
            outputs.append(c @ state + d * level)  # right-continuous input at k*dt
        if start >= grid[-1]:
            break
        if a.shape[0]:
            piece = solve_ivp(
                lambda t, x, level=level: a @ x + b * level,
                (start, stop),
                state,
                method="DOP853",
                rtol=1e-12,
                atol=1e-14,
            )
            state = piece.y[:, -1]
    return np.array(outputs)


DELAY_CASES = [
    (
        FOPDT(),
        first_order_tf,
        [[1.5, 2.0, 3.0], [-0.7, 0.8, 2.4], [1.0, 1.3, 0.35], [2.0, 0.5, 7.0 / 3.0]],
    ),
    (
        SecondOrderDelay(),
        second_order_tf,
        [[2.0, 1.5, 0.7, 2.3], [1.0, 1.2, 1.2, 1.6], [1.0, 3.0, 0.4, 4.0], [-1.0, 0.9, 0.0, 0.5]],
    ),
    (
        TransferFunction(second_order_tf, names=("K", "T1", "T2", "theta"), delay="theta"),
        second_order_tf,
        [[2.0, 1.5, 0.7, 2.3], [1.0, 1.2, 1.2, 3.0]],
    ),
    (
        lead_lag_model(),
        lead_lag_tf,
        [[1.5, 2.0, 0.8, 1.4], [-1.0, 0.3, 1.7, 2.0], [1.0, 1.0, 0.5, 0.7]],
    ),
]


@pytest.mark.parametrize("model, build, params", DELAY_CASES)
@pytest.mark.parametrize("x0", ["zero", "steady"])
@pytest.mark.parametrize("dt", [1.0, 0.7])
def test_dead_time_matches_ode_integration(model, build, params, x0, dt):
    u = U[:20]
    # All rows in one batch also exercises the per-sample delay gather.
    y = model.simulate(params, u, dt=dt, x0=x0)
    for row, p in zip(y, np.asarray(params)):
        reference = delayed_ode_reference(control.ss(build(p)), p[-1], u, dt, x0)
        # The ODE solution is accurate to ~1e-11 (rtol 1e-12 per piece).
        np.testing.assert_allclose(row, reference, rtol=1e-8, atol=1e-9)


def test_whole_step_dead_time_is_an_exact_shift():
    u = RNG.standard_normal(300)
    shifted = FOPDT().simulate([[1.3, 4.0, 100.0]], u)
    undelayed = FirstOrder().simulate([[1.3, 4.0]], u)
    np.testing.assert_array_equal(shifted[:, :100], 0.0)
    np.testing.assert_array_equal(shifted[:, 100:], undelayed[:, :-100])
    # 0.3 / 0.1 is 2.9999999999999996 in floating point; still three steps.
    shifted = FOPDT().simulate([[1.3, 4.0, 0.3]], u, dt=0.1)
    undelayed = FirstOrder().simulate([[1.3, 4.0]], u, dt=0.1)
    np.testing.assert_array_equal(shifted[:, 3:], undelayed[:, :-3])


def test_dead_time_longer_than_record():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        y = FOPDT().simulate([[1.0, 1.0, 1e300], [1.0, 1.0, 50.0]], U, dt=1e-3, x0="steady")
    np.testing.assert_array_equal(y, U[0])


@pytest.mark.parametrize("tiny", [0.0, 1e-300, 1e-14])
def test_vanishing_time_constants_give_static_gain(tiny):
    u = U[:12]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        first = FirstOrder().simulate([[2.0, tiny]], u)
        delayed = FOPDT().simulate([[2.0, tiny, 1.6]], u)
        both = SecondOrderDelay().simulate([[2.0, tiny, tiny, 1.6]], u)
        one = SecondOrderDelay().simulate([[2.0, tiny, 3.0, 1.6], [2.0, 3.0, tiny, 1.6]], u)
        steady = SecondOrderDelay().simulate([[2.0, tiny, tiny, 1.6]], u, x0="steady")
    # The limit T -> 0 of the sampled lag: y[k] = K * (delayed input just before k*dt).
    np.testing.assert_array_equal(first[0], 2.0 * np.concatenate(([0.0], u[:-1])))
    np.testing.assert_array_equal(delayed[0], 2.0 * np.concatenate(([0.0, 0.0], u[:-2])))
    np.testing.assert_array_equal(both, delayed)
    np.testing.assert_array_equal(steady[0], 2.0 * np.concatenate(([u[0]] * 2, u[:-2])))
    # With one lag vanishing only the other remains (up to T_tiny/3 relative).
    remaining = FOPDT().simulate([[2.0, 3.0, 1.6]], u)
    np.testing.assert_allclose(one, np.vstack((remaining, remaining)), rtol=1e-13, atol=1e-15)


def test_close_time_constants_are_continuous():
    relative_gaps = (1e-15, 1e-10, 1e-6)
    params = [[1.0, 2.0, 2.0, 0.4]] + [[1.0, 2.0, 2.0 * (1 + gap), 0.4] for gap in relative_gaps]
    y = SecondOrderDelay().simulate(params, U)
    np.testing.assert_allclose(y[1:], np.broadcast_to(y[0], y[1:].shape), rtol=0, atol=3e-6)
    np.testing.assert_allclose(y[1:3], y[[0, 0]], rtol=0, atol=1e-9)


CHUNK_CASES = [
    (FirstOrder(), [[1.0, 2.0], [2.0, 0.0], [-1.0, 7.0]]),
    (FOPDT(), [[1.0, 2.0, 0.0], [2.0, 0.5, 1.5], [-1.0, 7.0, 12.0]]),
    (FOPDT(), [[1.0, 2.0, 2.5], [2.0, 0.5, 2.5]]),
    (SecondOrderDelay(), [[1.0, 2.0, 2.0, 0.3], [2.0, 0.5, 3.0, 4.0], [1.0, 0.0, 1.0, 0.0]]),
    (lead_lag_model(), [[1.5, 2.0, 0.8, 1.4], [-1.0, 0.3, 1.7, 2.0]]),
]


@pytest.mark.parametrize("model, params", CHUNK_CASES)
@pytest.mark.parametrize("x0", ["zero", "steady"])
def test_chunks_concatenate_to_simulate_exactly(model, params, x0):
    whole = model.simulate(params, U, x0=x0)
    assert whole.shape == (len(params), U.size)
    for chunk_steps in (1, 7, U.size, U.size + 5, None):
        chunks = list(model.simulate_chunks(params, U, x0=x0, chunk_steps=chunk_steps))
        if chunk_steps is not None:
            assert all(chunk.shape[1] == chunk_steps for chunk in chunks[:-1])
        np.testing.assert_array_equal(np.concatenate(chunks, axis=1), whole)


def test_input_and_params_forms_are_accepted():
    model = FOPDT()
    as_array = model.simulate(np.array([[1.0, 2.0, 1.0]]), np.array([0.0, 1.0, 1.0, 2.0]))
    np.testing.assert_array_equal(model.simulate([1, 2, 1], [0, 1, 1, 2]), as_array)
    assert model.simulate([[1, 2, 1]], [3]).shape == (1, 1)
    assert model.names == ("K", "T", "theta") and model.n_params == 3
    assert FirstOrder().names == ("K", "T") and SecondOrderDelay().n_params == 4


def test_transfer_function_factory_agrees_with_second_order_delay():
    params = np.array([[2.0, 1.5, 0.7, 2.3], [1.0, 1.2, 1.2, 1.0], [-1.0, 0.6, 3.0, 0.45], [1.0, 2.0, 0.5, 0.0]])
    model = TransferFunction(second_order_tf, names=SecondOrderDelay().names, delay="theta")
    for x0 in ("zero", "steady"):
        np.testing.assert_allclose(
            model.simulate(params, U, dt=0.8, x0=x0),
            SecondOrderDelay().simulate(params, U, dt=0.8, x0=x0),
            rtol=1e-10,
            atol=1e-12,
        )


def test_static_transfer_function_uses_delayed_input_at_grid_points():
    model = TransferFunction(lambda p: control.tf([p[0]], [1.0]), names=("K", "theta"), delay="theta")
    y = model.simulate([[2.0, 1.0], [2.0, 1.5]], U)
    np.testing.assert_array_equal(y[0], 2.0 * np.concatenate(([0.0], U[:-1])))
    np.testing.assert_array_equal(y[1], 2.0 * np.concatenate(([0.0, 0.0], U[:-2])))


def test_integrator_simulates_from_zero_but_has_no_steady_state():
    model = TransferFunction(lambda p: control.tf([p[0]], [1.0, 0.0]), names=("K",))
    running_sum = np.concatenate(([0.0], np.cumsum(U[:-1])))
    np.testing.assert_allclose(model.simulate([[0.5]], U)[0], 0.5 * running_sum, atol=1e-12)
    with pytest.raises(ValueError, match=r'x0="steady".*sample 0.*singular'):
        model.simulate([[0.5]], U, x0="steady")


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"params": [[1.0, 2.0]]}, r"params must have shape \(n_samples, 3\)"),
        ({"params": [1.0, 2.0]}, r"params must have shape .* got shape \(2,\)"),
        ({"params": np.ones((2, 3, 1))}, r"params must have shape"),
        ({"params": np.ones((0, 3))}, r"params must contain at least one sample"),
        ({"params": [["a", "b", "c"]]}, r"params must be a numeric array"),
        (
            {"params": [[1.0, 1.0, 0.0], [1.0, np.nan, 0.0]]},
            r"params must be finite; sample 1 has T = nan",
        ),
        (
            {"params": [[1.0, 1.0, 0.0], [1.0, -1.0, 0.0], [1.0, -2.0, 0.0]]},
            r"T must be >= 0; sample 1",
        ),
        ({"params": [[1.0, 1.0, 0.0], [1.0, 1.0, -0.5]]}, r"theta must be >= 0; sample 1"),
        ({"u": [[1.0, 2.0]]}, r"u must have shape \(n_steps,\) for FOPDT; got shape \(1, 2\)"),
        ({"u": []}, r"u must contain at least one step"),
        ({"u": [1.0, np.inf]}, r"u must be finite; u\[1\] = inf"),
        ({"u": ["x"]}, r"u must be an array of numbers of shape \(n_steps,\)"),
        ({"dt": 0.0}, r"dt must be a finite number > 0"),
        ({"dt": -1.0}, r"dt must be a finite number > 0"),
        ({"dt": np.nan}, r"dt must be a finite number > 0"),
        ({"dt": [1.0]}, r"dt must be a finite number > 0"),
        ({"x0": "initial"}, r"x0 must be one of 'zero', 'steady'; got 'initial'"),
        ({"x0": np.zeros(1)}, r"x0 must be one of 'zero', 'steady'"),
        ({"chunk_steps": 0}, r"chunk_steps must be None or an integer >= 1"),
        ({"chunk_steps": 2.5}, r"chunk_steps must be None or an integer >= 1"),
    ],
)
def test_invalid_arguments_are_named(kwargs, match):
    arguments = {"params": [[1.0, 1.0, 0.5]], "u": U, "dt": 1.0, "x0": "zero", "chunk_steps": None}
    arguments.update(kwargs)
    with pytest.raises(ValueError, match=match):
        FOPDT().simulate_chunks(**arguments)  # raises before the first chunk
    if "chunk_steps" not in kwargs:
        arguments.pop("chunk_steps")
        with pytest.raises(ValueError, match=match):
            FOPDT().simulate(**arguments)


def test_negative_time_constants_of_second_order_are_named():
    with pytest.raises(ValueError, match=r"T2 must be >= 0; sample 0"):
        SecondOrderDelay().simulate([[1.0, 1.0, -1.0, 0.0]], U)


def test_transfer_function_rejects_inconsistent_systems():
    def changing_order(p):
        return control.tf([1.0], [p[0], 1.0]) if p[0] > 0 else control.tf([1.0], [1.0])

    model = TransferFunction(changing_order, names=("T",))
    with pytest.raises(ValueError, match=r"same state dimension; sample 2 has 0 states, sample 0"):
        model.simulate([[1.0], [2.0], [0.0]], U)

    def simulate_one(factory):
        return TransferFunction(factory, names=("K",)).simulate([[1.0]], U)

    with pytest.raises(ValueError, match=r"continuous-time.*sample 0"):
        simulate_one(lambda p: control.tf([1.0], [1.0, 0.5], 0.1))
    with pytest.raises(ValueError, match=r"single-input single-output.*sample 0"):
        simulate_one(lambda p: control.ss(-np.eye(2), np.eye(2), np.eye(2), 0))
    with pytest.raises(ValueError, match=r"sample 0 cannot be converted to state space"):
        simulate_one(lambda p: control.tf([1.0, 1.0], [1.0]))
    with pytest.raises(TypeError, match=r"factory must return a control.TransferFunction"):
        simulate_one(lambda p: 1.0)
    with pytest.raises(ValueError, match=r"delay must be None or one of names"):
        TransferFunction(first_order_tf, names=("K", "T"), delay="theta")
    with pytest.raises(ValueError, match=r"names must be non-empty and unique"):
        TransferFunction(first_order_tf, names=("K", "K"))
    with pytest.raises(ValueError, match=r"names must be a sequence of strings"):
        TransferFunction(first_order_tf, names="KT")
    with pytest.raises(TypeError, match=r"factory must be callable"):
        TransferFunction(None, names=("K",))


def test_models_share_the_base_class():
    for model in (FirstOrder(), FOPDT(), SecondOrderDelay(), lead_lag_model()):
        assert isinstance(model, Model)


@pytest.mark.parametrize("time_constant", [0.5, 1.0, 2.0])
def test_the_time_convention_is_zero_order_hold_as_the_docstring_says(time_constant):
    # Equal to control's response of the ZOH-discretised system; not to its response of the
    # continuous system, which interpolates the input linearly between samples.
    u = np.zeros(20)
    u[2] = 1.0
    time = np.arange(20.0)
    system = control.tf([1.0], [time_constant, 1.0])
    ours = FirstOrder().simulate([[1.0, time_constant]], u)[0]
    held = control.forced_response(control.c2d(system, 1.0, "zoh"), time, u).outputs
    interpolated = control.forced_response(system, time, u).outputs
    np.testing.assert_allclose(ours, held, atol=1e-12)
    assert np.abs(ours - interpolated).max() > 0.2
