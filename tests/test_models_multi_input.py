"""TransferFunction with several inputs: y = G1 u1 + G2 u2 + ..., one common dead time."""

import control
import numpy as np
import pytest

import dynia
from dynia.errors import DataError, ModelError
from dynia.models import TransferFunction

NAMES = ("K1", "K2", "T1", "T2", "theta")
RNG = np.random.default_rng(12)
# Piecewise-constant inputs that change at different times, so neither is a multiple of the other.
U = np.column_stack([np.repeat(RNG.normal(size=30), 10), np.repeat(RNG.normal(size=20), 15)])
PARAMS = np.column_stack([RNG.uniform(-2, 3, (40, 2)), RNG.uniform(0, 8, (40, 2)), RNG.uniform(0, 4, 40)])
# Superposition and the python-control reference are computed differently from the multi-input
# model (one matrix exponential of the joint block system, whose scaling and squaring depends on
# the whole matrix, and the terms summed in another order), so they agree to rounding, not bit
# for bit: about 4e-15 here on outputs of order 5.
TOLERANCE = 1e-12


def lag(gain, time_constant):
    return control.tf([gain], [time_constant, 1.0])


def lead_lag(gain, time_constant):
    """A proper column: direct feedthrough 0.5*K/T, exercised with fractional dead times."""
    return control.tf([0.5 * gain, gain], [time_constant, 1.0])


def static(gain, time_constant):
    """No states at all: its block of the realisation is empty."""
    return control.tf([gain], [1.0])


def two_input(first, second):
    def factory(p):
        columns = (first(p[0], p[2]), second(p[1], p[3]))
        return control.tf([[column.num[0][0] for column in columns]], [[column.den[0][0] for column in columns]])

    return TransferFunction(factory, NAMES, delay="theta", n_inputs=2)


def one_input(column, index):
    return TransferFunction(lambda p: column(p[index], p[2 + index]), NAMES, delay="theta")


@pytest.mark.parametrize("second", [lag, lead_lag, static])
@pytest.mark.parametrize("x0", ["zero", "steady"])
def test_two_inputs_are_the_sum_of_two_single_input_simulations(second, x0):
    model = two_input(lag, second)
    assert model.n_inputs == 2
    both = model.simulate(PARAMS, U, dt=0.7, x0=x0)
    apart = one_input(lag, 0).simulate(PARAMS, U[:, 0], dt=0.7, x0=x0) + one_input(second, 1).simulate(
        PARAMS, U[:, 1], dt=0.7, x0=x0
    )
    assert both.shape == (PARAMS.shape[0], U.shape[0])
    np.testing.assert_allclose(both, apart, rtol=0, atol=TOLERANCE)
    # The second input really reaches the output: without it the sum is far off.
    assert np.abs(both - one_input(lag, 0).simulate(PARAMS, U[:, 0], dt=0.7, x0=x0)).max() > 0.1


A = np.array([[-0.5, 0.4], [0.0, -2.0]])
B = np.array([[1.0, 0.0], [0.3, -1.5]])
C = np.array([[1.0, 0.5]])
D = np.array([[0.1, 0.2]])


def shared_states(p):
    """Both inputs drive the same two states, with feedthrough; p = (speed, theta)."""
    return control.ss(A * p[0], B, C, D)


@pytest.mark.parametrize("delay_steps", [0, 3])
def test_two_inputs_equal_forced_response_of_the_zoh_discretisation(delay_steps):
    dt = 0.5
    model = TransferFunction(shared_states, ("speed", "theta"), delay="theta", n_inputs=2)
    got = model.simulate([[1.0, delay_steps * dt]], U, dt=dt)[0]
    reference = control.forced_response(
        control.c2d(shared_states([1.0, 0.0]), dt, "zoh"), np.arange(U.shape[0]) * dt, U.T
    ).outputs[0]  # one output, two inputs: not squeezed to 1-D
    # A whole-step dead time shifts the response; before it the inputs are 0 (x0="zero").
    expected = np.concatenate((np.zeros(delay_steps), reference[: U.shape[0] - delay_steps]))
    np.testing.assert_allclose(got, expected, rtol=0, atol=TOLERANCE)


def test_a_steady_start_is_the_steady_state_of_the_first_input_vector():
    model = two_input(lag, lead_lag)
    params = [[2.0, -3.0, 4.0, 0.5, 1.3]]
    constant = np.tile([1.5, 0.25], (50, 1))
    expected = 2.0 * 1.5 - 3.0 * 0.25
    np.testing.assert_allclose(model.simulate(params, constant, x0="steady")[0], expected, rtol=0, atol=TOLERANCE)
    assert model.simulate(params, constant, x0="zero")[0, 0] == 0.0


@pytest.mark.parametrize("x0", ["zero", "steady"])
@pytest.mark.parametrize("theta", ["common", "per sample"])
def test_the_stepper_equals_simulate_bit_for_bit(x0, theta):
    model = two_input(lag, lead_lag)
    params = PARAMS.copy()
    if theta == "common":
        params[:, 4] = 2.0  # a whole number of steps of dt=0.5: the delayed inputs are scalars
    expected = model.simulate(params, U, dt=0.5, x0=x0)
    stepper = model.stepper(params, dt=0.5, x0=x0)
    assert stepper.n_inputs == 2
    stepped = np.stack([stepper.step(list(u_k)).copy() for u_k in U], axis=1)
    assert np.array_equal(stepped, expected)
    assert stepper.steps == U.shape[0]


def test_run_identifies_both_gains_of_a_two_input_record():
    model = TransferFunction(
        lambda p: control.tf([[[p[0]], [p[1]]]], [[[p[2], 1.0], [p[3], 1.0]]]),
        ("K1", "K2", "T1", "T2"),
        n_inputs=2,
    )
    rng = np.random.default_rng(7)
    u = np.column_stack([np.repeat(rng.choice([0.0, 2.0], 10), 40), np.repeat(rng.choice([0.0, 1.0], 8), 50)])
    truth = {"K1": 2.0, "K2": -1.0, "T1": 3.0, "T2": 6.0}
    y = model.simulate(list(truth.values()), u)[0] + rng.normal(0, 0.02, u.shape[0])
    bounds = {"K1": (0, 5), "K2": (-3, 2), "T1": (0.5, 10), "T2": (0.5, 10)}
    res = dynia.run(u, y, model, bounds, n_samples=1500, rng=8)
    for index, name in enumerate(("K1", "K2")):
        informative = res.ic[index] > 0.7
        assert informative.any(), name
        low, high = res.ci[index, informative].T
        assert np.all((low <= truth[name]) & (truth[name] <= high)), name


def one_line(error):
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(
    "factory, n_inputs, message",
    [
        (
            lambda p: lag(p[0], 1.0),
            2,
            r"^factory must return a 2-input single-output system \(n_inputs=2\); sample 0 has 1 inputs and "
            r"1 outputs \(set n_inputs=1 for such a system\)$",
        ),
        (
            lambda p: control.ss(A, B, C, D),
            1,
            r"^factory must return a single-input single-output system \(n_inputs=1\); sample 0 has 2 inputs "
            r"and 1 outputs \(set n_inputs=2 for such a system\)$",
        ),
        (
            lambda p: control.ss(A, B, np.eye(2), 0),
            2,
            r"^factory must return a 2-input single-output system \(n_inputs=2\); sample 0 has 2 inputs and "
            r"2 outputs$",
        ),
        (
            lambda p: control.ss(A, B, C, D) if p[0] < 2 else control.ss(A, B[:, :1], C, D[:, :1]),
            2,
            r"sample 2 has 1 inputs and 1 outputs",
        ),
    ],
)
def test_a_factory_with_other_inputs_than_n_inputs_is_one_line(factory, n_inputs, message):
    model = TransferFunction(factory, ("K",), n_inputs=n_inputs)
    u = U if n_inputs == 2 else U[:, 0]
    with pytest.raises(ModelError, match=message) as error:
        model.simulate([[0.0], [1.0], [2.0]], u)
    one_line(error)


@pytest.mark.parametrize("n_inputs", [0, 1.5, True, "2"])
def test_n_inputs_must_be_a_whole_number_of_at_least_one(n_inputs):
    with pytest.raises(ModelError, match=r"^n_inputs must be a whole number >= 1; got") as error:
        TransferFunction(shared_states, ("speed", "theta"), n_inputs=n_inputs)
    one_line(error)


@pytest.mark.parametrize(
    "u, message, run_message",
    [
        (
            U[:, 0],
            r"^u must have shape \(n_steps, 2\) for TransferFunction; got shape \(300,\)$",
            r"^u must have shape \(n_steps, 2\) for a model with 2 inputs; got \(300,\)$",
        ),
        (
            np.column_stack([U, U[:, :1]]),
            r"^u must have shape \(n_steps, 2\) for TransferFunction; got shape \(300, 3\)$",
            r"^u must have shape \(n_steps, 2\) for a model with 2 inputs; got \(300, 3\)$",
        ),
        (
            U.T,
            r"^u must have shape \(n_steps, 2\) for TransferFunction; got shape \(2, 300\)$",
            r"^u must have shape \(n_steps, 2\) for a model with 2 inputs; got \(2, 300\)$",
        ),
        (
            np.where(np.arange(600).reshape(300, 2) == 7, np.nan, U),
            r"^u must be finite; u\[3, 1\] = nan$",
            r"^u holds a non-finite value at row 3, column 1",
        ),
    ],
)
def test_a_wrong_input_array_is_one_line(u, message, run_message):
    model = TransferFunction(shared_states, ("speed", "theta"), delay="theta", n_inputs=2)
    with pytest.raises(DataError, match=message) as error:
        model.simulate([[1.0, 0.0]], u)
    one_line(error)
    with pytest.raises(DataError, match=run_message) as error:
        dynia.run(u, np.zeros(u.shape[0]), model, {"speed": (0.5, 2), "theta": (0, 1)}, n_samples=50, rng=1)
    one_line(error)


def test_a_wrong_stepper_input_is_one_line():
    stepper = TransferFunction(shared_states, ("speed", "theta"), delay="theta", n_inputs=2).stepper([[1.0, 0.0]])
    with pytest.raises(DataError, match=r"^u_k must hold one value per input, shape \(2,\); got shape \(\) at step 0$"):
        stepper.step(1.0)
    with pytest.raises(
        DataError, match=r"^u_k must hold one value per input, shape \(2,\); got shape \(3,\) at step 0"
    ):
        stepper.step([1.0, 2.0, 3.0])
    with pytest.raises(DataError, match=r"^u_k must be finite; got \[1.0, inf\] at step 0$"):
        stepper.step([1.0, np.inf])
    with pytest.raises(TypeError, match=r"^u_k must be a sequence of 2 real numbers"):
        stepper.step(["1.0", "2.0"])
    assert stepper.steps == 0
    assert float(stepper.step(np.array([1.0, 2.0]))[0]) == pytest.approx(0.1 * 1.0 + 0.2 * 2.0, abs=1e-15)


def test_repr_names_n_inputs_only_when_there_are_several():
    def factory(p):
        return shared_states(p)

    assert repr(TransferFunction(factory, ("speed",), n_inputs=2)).endswith("delay=None, n_inputs=2)")
    assert repr(TransferFunction(factory, ("speed",))) == "TransferFunction(factory, names=('speed',), delay=None)"
