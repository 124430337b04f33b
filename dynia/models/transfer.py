"""Any linear model python-control builds from the parameters, simulated exactly like the built-in ones.

:class:`TransferFunction` asks a factory for each parameter set's
continuous-time transfer function or state-space system, discretises every
one exactly (zero-order hold by the matrix exponential, a fractional dead
time included) and advances them all together in the time loop of
:class:`~dynia.models.linear.LinearModel`. Shapes and times follow the
conventions of :mod:`dynia.models.linear`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from ..errors import ModelError
from .base import user_code_failed

# _DiscreteSystem keeps its private name: a checkpoint (dynia.online.OnlineDynia.to_bytes) names its class.
from .linear import LinearModel, _DiscreteSystem, split_delay

if TYPE_CHECKING:
    import control

__all__ = ["TransferFunction"]


class TransferFunction(LinearModel):
    """Any single-output continuous-time LTI model built by python-control from the parameters.

    Parameters
    ----------
    factory : callable
        ``factory(p)`` receives one sample's parameters as a 1-D float array
        (in `names` order) and returns a continuous-time, single-output
        ``control.TransferFunction`` or ``control.StateSpace`` with
        `n_inputs` inputs (a 1 x n_inputs transfer function, or B with
        n_inputs columns). Every sample must give the same number of
        states. Direct feedthrough (proper, not strictly proper models) is
        supported. A transfer function with several inputs is realised
        with one block of states per input (return a ``control.ss`` for a
        realisation with shared states).
    names : sequence of str
        Parameter names, in the column order of ``params``.
    delay : str, optional
        Name of the parameter (one of `names`) that is an input dead time in
        time units. python-control has no exact delay element; this one is
        simulated exactly, including fractions of ``dt``. The factory still
        receives it but should not model it. With several inputs the one
        dead time delays every input alike; separate dead times per input
        are not available.
    n_inputs : int, default 1
        Number of inputs, i.e. columns of ``u``, which is then
        ``(n_steps, n_inputs)``. Every system the factory returns must have
        this many inputs (a :class:`~dynia.errors.ModelError` says so otherwise).

    Notes
    -----
    Each sample is discretised with the matrix exponential of
    ``[[A, B], [0, 0]] * h``, batched over samples. The factory is called
    once per sample in a Python loop, so building the model costs what
    python-control needs per system (~0.15 ms, about 3 s for 20 000
    samples); the time loop itself is vectorised like the other models.
    With several inputs the output is the sum of each input's response,
    added in input order; ``x0="steady"`` starts in the steady state at the
    first input vector ``u[0]``. Only single-input models are simulated by
    the compiled engine of :func:`dynia.run`; multi-input ones use this
    numpy time loop.

    Examples
    --------
    >>> import control
    >>> from dynia.models import TransferFunction
    >>> model = TransferFunction(
    ...     lambda p: control.tf([p[0]], [p[1], 1.0]), names=("K", "T", "theta"), delay="theta"
    ... )
    >>> model.simulate([[1.0, 1.0, 1.0]], [1.0, 1.0, 1.0, 1.0]).round(4)
    array([[0.    , 0.    , 0.6321, 0.8647]])

    Two inputs, ``y = K1/(s + 1) u1 + K2/(2 s + 1) u2``:

    >>> two = TransferFunction(
    ...     lambda p: control.tf([[[p[0]], [p[1]]]], [[[1.0, 1.0], [2.0, 1.0]]]), names=("K1", "K2"), n_inputs=2
    ... )
    >>> two.simulate([[1.0, 3.0]], [[1.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).round(4)
    array([[0.    , 0.6321, 0.8647]])
    """

    def __init__(
        self,
        factory: Callable[[np.ndarray], control.TransferFunction | control.StateSpace],
        names: Sequence[str],
        delay: str | None = None,
        *,
        n_inputs: int = 1,
    ):
        super().__init__(names, n_inputs=n_inputs)
        if not callable(factory):
            raise TypeError(f"factory must be callable; got {type(factory).__name__}")
        if delay is not None and delay not in self.names:
            raise ModelError(f"delay must be None or one of names {self.names}; got {delay!r}")
        self._factory = factory
        self._delay = delay

    @property
    def delay(self) -> str | None:
        """Name of the dead-time parameter, or None."""
        return self._delay

    def __repr__(self) -> str:
        factory = getattr(self._factory, "__name__", repr(self._factory))
        inputs = f", n_inputs={self.n_inputs}" if self.n_inputs > 1 else ""
        return f"TransferFunction({factory}, names={self.names}, delay={self._delay!r}{inputs})"

    def discretise(self, params, dt, n_steps, steady):
        if self._delay is None:
            delay = np.zeros(params.shape[0])
        else:
            self._require_nonnegative(params, (self._delay,))
            delay = params[:, self.names.index(self._delay)]
        a, b, c, d = self._state_space(params)
        n_samples, n_states, n_inputs = b.shape
        delay_steps, fraction = split_delay(delay, dt, n_steps)

        augmented = np.zeros((n_samples, n_states + n_inputs, n_states + n_inputs))
        augmented[:, :n_states, :n_states] = a
        augmented[:, :n_states, n_states:] = b
        # expm([[A, B], [0, 0]] tau) = [[e^{A tau}, int_0^tau e^{As} B ds], [0, I]]
        # Overflow is detected below, per sample, so numpy need not warn of it.
        with np.errstate(over="ignore", invalid="ignore"):
            late = scipy.linalg.expm(augmented * ((1.0 - fraction) * dt)[:, None, None])
            early = scipy.linalg.expm(augmented * (fraction * dt)[:, None, None])
            late_transition = late[:, :n_states, :n_states]
            # For fraction == 0 `early` is the identity, so phi equals e^{A dt} exactly.
            phi = late_transition @ early[:, :n_states, :n_states]
            gamma_now = late[:, :n_states, n_states:]
            gamma_prev = late_transition @ early[:, :n_states, n_states:]
        discretised = np.concatenate(
            (phi.reshape(n_samples, -1), gamma_now.reshape(n_samples, -1), gamma_prev.reshape(n_samples, -1)), axis=1
        )
        # A pole far in the right half-plane overflows e^{A dt}. Such a sample
        # cannot be simulated; NaN coefficients make its output NaN (quietly:
        # NaN arithmetic raises no floating-point warning), which
        # finite_samples reports and dynia.run drops.
        overflowed = ~np.isfinite(discretised).all(axis=1)
        phi[overflowed] = np.nan
        gamma_now[overflowed] = np.nan
        gamma_prev[overflowed] = np.nan

        feed_now, feed_prev = _split_feedthrough(d, fraction[:, None])
        return _DiscreteSystem(
            phi=np.moveaxis(phi, 0, -1).copy(),
            gamma_now=_input_major(gamma_now),
            gamma_prev=_input_major(gamma_prev),
            c=c.T.copy(),
            feed_now=_input_major(feed_now),
            feed_prev=_input_major(feed_prev),
            delay_steps=delay_steps,
            steady_state=_input_major(_steady_state(a, b)) if steady else None,
        )

    def _state_space(self, params: np.ndarray):
        """Stack A (n, s, s), B (n, s, n_inputs), C (n, s), D (n, n_inputs) of every sample's system."""
        # python-control imports matplotlib.pyplot: loaded by the first TransferFunction, not by import dynia.
        import control

        matrices = []
        for sample, values in enumerate(params):
            try:
                system = self._factory(values.copy())
            except BaseException as error:
                raise user_code_failed(f"{self!r}: factory(p) for sample {sample}", error) from error
            if not isinstance(system, (control.TransferFunction, control.StateSpace)):
                raise TypeError(
                    f"factory must return a control.TransferFunction or control.StateSpace; "
                    f"got {type(system).__name__} for sample {sample}"
                )
            if not system.isctime():
                raise ModelError(f"factory must return a continuous-time system; sample {sample} gave dt={system.dt}")
            if system.ninputs != self.n_inputs or system.noutputs != 1:
                expected = "single-input" if self.n_inputs == 1 else f"{self.n_inputs}-input"
                hint = f" (set n_inputs={system.ninputs} for such a system)" if system.noutputs == 1 else ""
                raise ModelError(
                    f"factory must return a {expected} single-output system (n_inputs={self.n_inputs}); sample "
                    f"{sample} has {system.ninputs} inputs and {system.noutputs} outputs{hint}"
                )
            realised = _realisation(system, sample)
            if matrices and realised[0].shape[0] != matrices[0][0].shape[0]:
                raise ModelError(
                    f"all samples must have the same state dimension; sample {sample} has "
                    f"{realised[0].shape[0]} states, sample 0 has {matrices[0][0].shape[0]}"
                )
            matrices.append(realised)
        a, b, c, d = (np.array(stack, dtype=float) for stack in zip(*matrices))
        self._refuse_one_system(params, (a, b, c, d))
        return a, b, c, d

    def _refuse_one_system(self, params, matrices):
        """A ModelError when the factory built one system for parameter sets that differ in what it receives.

        Such a factory ignores ``p``: every set would simulate alike and rank by ties. The dead time is
        simulated here, not by the factory, so sets that differ only in it may well give one system.
        """
        built = [name != self._delay for name in self.names]
        if np.unique(params[:, built], axis=0).shape[0] < 2:
            return
        if all(np.array_equal(stack, np.broadcast_to(stack[:1], stack.shape)) for stack in matrices):
            raise ModelError(
                f"{self!r}: factory(p) returned the same system for all {params.shape[0]} parameter sets; it must "
                "build the system from p (one sample's parameters as a 1-D array, in the order of names)"
            )


def _realisation(system, sample):
    """A (s, s), B (s, n_inputs), C (s,), D (n_inputs,) of one single-output system.

    python-control realises a transfer function with several inputs only
    with the optional slycot; without it such a one is realised input by
    input, one block of states per input column, stacked. That realisation
    is exact, though not minimal when columns share poles, and does not
    depend on whether slycot is installed.
    """
    import control

    if isinstance(system, control.TransferFunction) and system.ninputs > 1:
        columns = [_realisation(system[0, j], sample) for j in range(system.ninputs)]
        return (
            scipy.linalg.block_diag(*(a for a, _, _, _ in columns)),
            scipy.linalg.block_diag(*(b for _, b, _, _ in columns)),
            np.concatenate([c for _, _, c, _ in columns]),
            np.concatenate([d for _, _, _, d in columns]),
        )
    try:
        system = control.ss(system)
    except ValueError as error:
        raise ModelError(f"the system of sample {sample} cannot be converted to state space: {error}") from error
    return system.A, system.B, system.C[0], system.D[0]


def _split_feedthrough(feedthrough, fraction):
    """Direct feedthrough sees the delayed input at t = k*dt: u[k-d-1] if f > 0 else u[k-d].

    ``fraction`` broadcasts against ``feedthrough``.
    """
    fractional = fraction > 0
    return np.where(fractional, 0.0, feedthrough), np.where(fractional, feedthrough, 0.0)


def _steady_state(a, b):
    """Per-sample state -A^{-1} B for a unit constant input, (n_samples, n_states, n_inputs)."""
    n_samples, n_states, n_inputs = b.shape
    if n_states == 0:
        return np.zeros((n_samples, 0, n_inputs))
    singular = np.linalg.matrix_rank(a) < n_states
    if singular.any():
        raise ModelError(
            f'x0="steady" needs a steady state, but A of sample {np.flatnonzero(singular)[0]} '
            f"is singular (the model has an integrator or a pole at 0)"
        )
    return -np.linalg.solve(a, b)


def _input_major(per_sample: np.ndarray) -> np.ndarray:
    """(n_samples, ..., n_inputs) to the _DiscreteSystem layout: (n_inputs, ..., n_samples), no input axis for one."""
    moved = np.moveaxis(per_sample, (0, -1), (-1, 0))
    return np.ascontiguousarray(moved[0] if moved.shape[0] == 1 else moved)
