"""What every model offers DYNIA: batched simulation of many parameter sets, streamed in time.

A model simulates the same record for many parameter sets at once. It must
provide :meth:`Model.simulate_chunks` (the output a block of steps at a
time, so that memory does not grow with the record); :meth:`Model.stepper`
(one logged sample at a time, for :class:`dynia.online.OnlineDynia`) and
:meth:`Model.start_simulation` with :meth:`Model.simulate_span` (a
simulation paused and resumed from a :class:`SimulationState`, possibly in
another process, for :mod:`dynia.distributed`) are optional.
:meth:`Model.simulate`, :meth:`Model.finite_samples` and the argument checks
are shared.

Shape convention
----------------
``params``
    ``(n_samples, n_params)``; the columns follow ``model.names``. A 1-D
    array of length ``n_params`` is accepted as a single sample.
``u``
    ``(n_steps,)`` for a single-input model, ``(n_steps, n_inputs)`` for a
    model with ``n_inputs > 1``; the input sampled every ``dt``.
outputs
    ``(n_samples, n_steps)``; ``simulate_chunks`` yields consecutive
    ``(n_samples, m)`` pieces of it.

Subnormal states
----------------
A state that decays towards zero, as a first-order lag's does once the
input rests at zero, reaches the subnormal floats (below 2.2e-308) after a
few thousand time constants, and every multiplication with a subnormal
takes the processor's slow path, many times the cost of a normal one. Every
simulator of the package (the built-in linear models on both engines and
:class:`~dynia.models.StateSpaceModel`, in Python and compiled) therefore
sets each state of magnitude below :data:`FLUSH_BELOW` (2^-960, about
1.0e-289) to zero after every step. An output then differs from the
unflushed recursion's by less than the output coefficients times 1e-289:
nothing a measured record can show. A state-space model whose output
diverges as a state reaches zero (a logarithm of a state, say) reaches it
earlier.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import DataError, DyniaError, Interrupted, ModelError

__all__ = [
    "Model",
    "SimulationState",
    "FLUSH_BELOW",
]

# States of smaller magnitude are set to zero after every step (see "Subnormal states" above).
FLUSH_BELOW = 2.0**-960


def flush_tiny(states, scratch=None):
    """Set, in place, the entries of ``states`` of magnitude below :data:`FLUSH_BELOW` to zero.

    ``scratch``, a float array of the same shape, saves an allocation per call.

    Examples
    --------
    >>> x = np.array([1e-300, -1e-300, 1e-280, 0.5])
    >>> flush_tiny(x).tolist()
    [0.0, 0.0, 1e-280, 0.5]
    """
    magnitude = np.abs(states, out=scratch)
    np.copyto(states, 0.0, where=magnitude < FLUSH_BELOW)
    return states


# Default chunk size: 4e6 float64 values are 32 MB per output chunk, large
# enough that the per-chunk overhead is negligible and small enough that the
# chunk plus the gathered inputs stay far below typical memory limits.
VALUES_PER_CHUNK = 4_000_000


@dataclass(frozen=True)
class SimulationState:
    """Where a paused simulation stands: the next step and what the model needs to go on from it.

    Made by :meth:`Model.start_simulation` and :meth:`Model.simulate_span`;
    it can be pickled and sent to another process. :meth:`Model.simulate_span`
    never changes the state it is given, so one state can be resumed twice
    with the same result.

    Attributes
    ----------
    step : int
        The step the simulation goes on from (0 before the first step).
    n_steps : int
        Length of the record it simulates.
    n_samples : int
        Number of parameter sets simulated.
    carried : object
        The model's own: the parameter sets or their discretisation, and
        the state of every sample at ``step``.
    """

    step: int
    n_steps: int
    n_samples: int
    carried: Any


class Model:
    """Base class of every model DYNIA simulates.

    Subclasses implement :meth:`simulate_chunks` (and :meth:`stepper` for
    online use). Most users need none: :class:`dynia.models.FunctionModel`
    wraps a function and :class:`dynia.models.StateSpaceModel` a discrete
    state update.

    Parameters
    ----------
    names : sequence of str
        Parameter names, in the column order of ``params``.
    n_inputs : int, default 1
        Number of input signals (columns of ``u``).
    """

    def __init__(self, names: Sequence[str], n_inputs: int = 1):
        self._names = check_names(names)
        if isinstance(n_inputs, bool) or not isinstance(n_inputs, numbers.Integral) or n_inputs < 1:
            raise ModelError(f"n_inputs must be a whole number >= 1; got {n_inputs!r}")
        self._n_inputs = int(n_inputs)

    @property
    def names(self) -> tuple[str, ...]:
        """Parameter names, in the column order of ``params``."""
        return self._names

    @property
    def n_params(self) -> int:
        """Number of parameters (columns of ``params``)."""
        return len(self._names)

    @property
    def n_inputs(self) -> int:
        """Number of input signals (columns of ``u``; 1 means ``u`` is 1-D)."""
        return self._n_inputs

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"

    def simulate(self, params, u, dt: float = 1.0, x0: str = "zero") -> np.ndarray:
        """Simulate every parameter set on the input ``u``.

        Parameters
        ----------
        params : array_like, shape (n_samples, n_params)
            One parameter set per row, columns in the order of `names`.
        u : array_like, shape (n_steps,) or (n_steps, n_inputs)
            Input samples, held constant over each interval of length `dt`.
        dt : float, default 1.0
            Sampling interval, > 0.
        x0 : {"zero", "steady"}, default "zero"
            Initial state: zero, or the steady state at ``u[0]`` (where the
            model has one).

        Returns
        -------
        ndarray, shape (n_samples, n_steps)
            ``y[i, k]`` is the output of sample ``i`` at ``t = k*dt``.

        Raises
        ------
        DataError, ModelError
            If an argument has the wrong shape or value (the message names
            it), or the model cannot simulate as asked.

        Examples
        --------
        >>> from dynia.models import FirstOrder
        >>> FirstOrder().simulate([[2.0, 1.0], [1.0, 0.5]], [1.0, 1.0, 1.0]).round(4)
        array([[0.    , 1.2642, 1.7293],
               [0.    , 0.8647, 0.9817]])
        """
        u = self.check_input(u)
        output = None
        start = 0
        for chunk in self.simulate_chunks(params, u, dt=dt, x0=x0):
            if output is None:
                output = np.empty((chunk.shape[0], u.shape[0]))
            output[:, start : start + chunk.shape[1]] = chunk
            start += chunk.shape[1]
        return output

    def simulate_chunks(
        self, params, u, dt: float = 1.0, x0: str = "zero", chunk_steps: int | None = None
    ) -> Iterator[np.ndarray]:
        """Simulate like `simulate`, yielding the output a block of steps at a time.

        Only the state and one chunk are held in memory, so arbitrarily many
        samples times steps can be processed. Concatenating the chunks along
        axis 1 gives exactly (bit for bit) the result of `simulate`.
        Arguments are validated immediately, not on the first ``next()``.

        Parameters
        ----------
        params, u, dt, x0
            As for `simulate`.
        chunk_steps : int, optional
            Time steps per chunk (the last one may be shorter). By default
            about 4e6 values per chunk, i.e. ``4e6 // n_samples`` steps, at
            least 1.

        Yields
        ------
        ndarray, shape (n_samples, m)
            Consecutive blocks of the output.

        Examples
        --------
        >>> from dynia.models import FirstOrder
        >>> chunks = FirstOrder().simulate_chunks([1.0, 1.0], [1.0] * 5, chunk_steps=2)
        >>> [chunk.shape for chunk in chunks]
        [(1, 2), (1, 2), (1, 1)]
        """
        raise NotImplementedError(
            f"{type(self).__name__} must implement simulate_chunks(params, u, dt, x0, chunk_steps); "
            "dynia.models.FunctionModel and StateSpaceModel wrap a function or a state update without subclassing"
        )

    def stepper(self, params, dt: float = 1.0, x0: str = "zero"):
        """Simulate every parameter set one input sample at a time, as it is logged.

        Parameters
        ----------
        params, dt, x0
            As for `simulate`; ``x0="steady"`` starts in the steady state at
            the first input stepped.

        Returns
        -------
        object with ``step(u_k) -> ndarray (n_samples,)``
            ``stepper.step(u_k)`` returns the output of every sample at step
            k, bit for bit column k of `simulate` on the inputs stepped so far.

        Examples
        --------
        >>> from dynia.models import FOPDT
        >>> stepper = FOPDT().stepper([[1.0, 0.0, 2.0]])
        >>> [float(stepper.step(u_k)[0]) for u_k in [1.0, 2.0, 3.0, 4.0]]
        [0.0, 0.0, 0.0, 1.0]
        """
        raise ModelError(f"{type(self).__name__} cannot be simulated one sample at a time (it has no stepper)")

    @property
    def resumable(self) -> bool:
        """Whether the simulation can pause and resume (:meth:`start_simulation`, :meth:`simulate_span`)."""
        return False

    def start_simulation(self, params, u, dt: float = 1.0, x0: str = "zero") -> SimulationState:
        """The state before the first step of simulating every parameter set on ``u``.

        With :meth:`simulate_span` the record is then simulated in spans of
        steps, each resumed from the state the previous one left, in this or
        another process; the spans joined equal `simulate` bit for bit.

        Parameters
        ----------
        params, u, dt, x0
            As for `simulate`; ``u`` is the whole record.

        Returns
        -------
        SimulationState
            At step 0.

        Raises
        ------
        ModelError
            If the model cannot pause and resume (see `resumable`).

        Examples
        --------
        >>> from dynia.models import FirstOrder
        >>> model, u = FirstOrder(), [1.0] * 5
        >>> state = model.start_simulation([[2.0, 1.0]], u)
        >>> first, state = model.simulate_span(state, u, 2)
        >>> rest, state = model.simulate_span(state, u, 5)
        >>> (first.round(4), rest.round(4), state.step)
        (array([[0.    , 1.2642]]), array([[1.7293, 1.9004, 1.9634]]), 5)
        """
        raise ModelError(
            f"{self!r} cannot pause a simulation and resume it later (it has no start_simulation and "
            "simulate_span); it can only be simulated over the whole record"
        )

    def simulate_span(
        self, state: SimulationState, u, stop: int, *, time_major: bool = False
    ) -> tuple[np.ndarray, SimulationState]:
        """Simulate from ``state.step`` up to step ``stop``, resuming ``state``.

        Parameters
        ----------
        state : SimulationState
            From :meth:`start_simulation` or a previous span; not changed.
        u : array_like
            The whole record, as given to :meth:`start_simulation`.
        stop : int
            The step after the span, ``state.step < stop <= n_steps``.
        time_major : bool, default False
            Return the output transposed, (stop - state.step, n_samples)
            and C-contiguous, the layout of the compiled windows; a linear
            model computes it in that layout and saves two transpositions.

        Returns
        -------
        sims : ndarray, shape (n_samples, stop - state.step)
            The output over the span, bit for bit those columns of `simulate`.
        state : SimulationState
            At ``stop``.

        Examples
        --------
        >>> from dynia.models import FirstOrder
        >>> model, u = FirstOrder(), [1.0] * 4
        >>> state = model.start_simulation([[2.0, 1.0]], u)
        >>> model.simulate_span(state, u, 4)[0].round(4)
        array([[0.    , 1.2642, 1.7293, 1.9004]])
        """
        raise ModelError(
            f"{self!r} cannot pause a simulation and resume it later (it has no start_simulation and "
            "simulate_span); it can only be simulated over the whole record"
        )

    def check_span(self, state, u, stop) -> np.ndarray:
        """Check the arguments of :meth:`simulate_span`; return the whole ``u`` as floats.

        Only the span's own steps are checked for finite values: the steps
        before it were checked by the spans that simulated them, and a
        record of a million steps is not rescanned for every span.
        """
        if not isinstance(state, SimulationState):
            raise ModelError(
                f"state must be the SimulationState of start_simulation or simulate_span; got {type(state).__name__}"
            )
        if isinstance(stop, bool) or not isinstance(stop, numbers.Integral) or not state.step < stop <= state.n_steps:
            raise ModelError(
                f"stop must be a whole number after the state's step {state.step} and at most the record's "
                f"{state.n_steps} steps; got {stop!r}"
            )
        try:
            u = np.asarray(u, dtype=float)
        except (TypeError, ValueError):
            raise DataError("u must be the whole record given to start_simulation, an array of numbers") from None
        if u.ndim == 0 or u.shape[0] != state.n_steps:
            raise DataError(
                f"u has shape {u.shape} but the simulation was started on a record of {state.n_steps} steps; "
                "give the same whole record to every span"
            )
        try:
            span = self.check_input(u[state.step : stop])
        except DataError as error:
            raise DataError(
                f"in the span of steps {state.step} to {stop - 1} (counted from its start): {error}"
            ) from None
        return u.reshape(state.n_steps, *span.shape[1:])

    def finite_samples(self, params, u, dt: float = 1.0, x0: str = "zero") -> np.ndarray:
        """Which parameter sets simulate to finite output over the whole record.

        A model with unstable or huge coefficients can overflow; such sets
        must be left out of a DYNIA run rather than rank as anything. This
        default simulates once, streaming, and keeps only the verdict.

        Returns
        -------
        ndarray of bool, shape (n_samples,)

        Examples
        --------
        >>> import control
        >>> from dynia.models import TransferFunction
        >>> unstable = TransferFunction(lambda p: control.tf([1.0], [1.0, -p[0]]), names=("a",))
        >>> unstable.finite_samples([[0.5], [800.0]], [1.0] * 5).tolist()
        [True, False]
        """
        finite = np.ones(self.check_params(params).shape[0], dtype=bool)
        with np.errstate(over="ignore", invalid="ignore"):
            for chunk in self.simulate_chunks(params, u, dt=dt, x0=x0):
                finite &= np.isfinite(chunk).all(axis=1)
        return finite

    def check_ranges(self, ranges) -> None:
        """Refuse sampling ranges that reach values the model refuses, before any set is drawn.

        ``ranges`` maps every parameter name to its (low, high). Raises a
        :class:`~dynia.errors.SettingsError` whose ``setting`` is the
        parameter's name. The models of this package know their constraints
        and check (:class:`~dynia.models.linear.LinearModel`); a model of user
        code is left to the run, which reports its own errors (probing it
        would run the user's code twice).
        """

    def check_params(self, params) -> np.ndarray:
        """Return ``params`` as a finite float (n_samples, n_params) array."""
        expected = f"(n_samples, {self.n_params}) with columns {self.names}"
        try:
            params = np.asarray(params, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"params must be a numeric array of shape {expected}") from None
        if params.ndim == 1 and params.shape[0] == self.n_params:
            params = params.reshape(1, -1)
        if params.ndim != 2 or params.shape[1] != self.n_params:
            raise ModelError(f"params must have shape {expected}; got shape {params.shape}")
        if params.shape[0] == 0:
            raise ModelError("params must contain at least one sample (row)")
        bad = ~np.isfinite(params)
        if bad.any():
            sample, column = np.argwhere(bad)[0]
            raise DataError(
                f"params must be finite; sample {sample} has {self.names[column]} = {params[sample, column]}"
            )
        return params

    def check_input(self, u) -> np.ndarray:
        """Return ``u`` as finite floats, (n_steps,) for one input or (n_steps, n_inputs)."""
        expected = "(n_steps,)" if self.n_inputs == 1 else f"(n_steps, {self.n_inputs})"
        try:
            u = np.asarray(u, dtype=float)
        except (TypeError, ValueError):
            raise DataError(f"u must be an array of numbers of shape {expected}") from None
        if self.n_inputs == 1 and u.ndim == 2 and u.shape[1] == 1:
            u = u[:, 0]
        if (self.n_inputs == 1 and u.ndim != 1) or (self.n_inputs > 1 and (u.ndim != 2 or u.shape[1] != self.n_inputs)):
            raise DataError(f"u must have shape {expected} for {type(self).__name__}; got shape {u.shape}")
        if u.shape[0] == 0:
            raise DataError("u must contain at least one step; got an empty array")
        bad = np.argwhere(~np.isfinite(u))
        if bad.size:
            where = tuple(int(i) for i in bad[0])
            raise DataError(f"u must be finite; u[{', '.join(map(str, where))}] = {u[where]}")
        return u

    def chunk_steps(self, n_samples: int, chunk_steps: int | None) -> int:
        """Steps per chunk: ``chunk_steps`` checked, or about VALUES_PER_CHUNK values by default."""
        if chunk_steps is None:
            return max(1, VALUES_PER_CHUNK // n_samples)
        if isinstance(chunk_steps, bool) or not isinstance(chunk_steps, numbers.Integral) or chunk_steps < 1:
            raise ModelError(f"chunk_steps must be None or an integer >= 1; got {chunk_steps!r}")
        return int(chunk_steps)


def user_code_failed(what, error):
    """The ModelError for ``error``, raised by user code (``what`` names the call), or ``error`` re-raised.

    Anything user code raises becomes a :class:`~dynia.errors.ModelError`, ``SystemExit`` too: a
    model that exits would end the run without a word (or with status 0
    and nothing written). dynia's own errors, its signal interruptions,
    Ctrl-C and a generator's close pass unchanged. Use as ``except BaseException as error: raise
    user_code_failed("fn", error) from error``.

    Examples
    --------
    >>> str(user_code_failed("FunctionModel(f): fn", SystemExit(3)))
    'FunctionModel(f): fn raised SystemExit(3): model code must return or raise, not exit the process'
    """
    if isinstance(error, (DyniaError, Interrupted, KeyboardInterrupt, GeneratorExit)):
        raise error  # dynia's own, the user's Ctrl-C, and a stream closed by its consumer
    if isinstance(error, SystemExit):
        return ModelError(
            f"{what} raised SystemExit({error.code!r}): model code must return or raise, not exit the process"
        )
    return ModelError(f"{what} raised {type(error).__name__}: {error}")


def check_model(model) -> None:
    """Refuse anything but a :class:`Model` as a front-end's ``model``, with one :class:`~dynia.errors.ModelError`.

    Examples
    --------
    >>> check_model("FirstOrder")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    dynia.errors.ModelError: model must be a dynia.models.Model (e.g. FirstOrder(), ...); got str
    """
    if not isinstance(model, Model):
        raise ModelError(
            "model must be a dynia.models.Model (e.g. FirstOrder(), FunctionModel(fn, names) or "
            f"StateSpaceModel(...)); got {type(model).__name__}"
        )


def check_names(names) -> tuple[str, ...]:
    """Parameter names as a tuple of unique strings, or a :class:`~dynia.errors.ModelError`."""
    if isinstance(names, str) or not all(isinstance(name, str) for name in names):
        raise ModelError(f"names must be a sequence of strings; got {names!r}")
    names = tuple(names)
    if not names or len(set(names)) != len(names):
        raise ModelError(f"names must be non-empty and unique; got {names}")
    return names


def refuse_ignored_params(model, params, functions, output=None, precision=None):
    """The ModelError for a model whose output was the same for every parameter set, unless the sets are too.

    ``output`` is that one output (its last chunk will do) and ``precision``
    the float type user code returned it in, where it was coarser than
    float64. The message tells a model that ignores ``params`` from one whose
    response is below what the numbers can resolve: dynia's own models, an
    output that is 0 everywhere (a record or a dt so small that the response
    underflows), or an output of a coarse float type.
    """
    if np.unique(params, axis=0).shape[0] <= 1:
        return
    n_sets = params.shape[0]
    same = f"{model!r}: {functions} returned the same output for all {n_sets} parameter sets over the whole record"
    zero = output is not None and not np.any(output)
    if precision is not None and not zero:
        raise ModelError(
            f"{same}, as {precision} values: the parameters' effect is below what {precision} resolves; return float64"
        )
    if zero or functions == "the simulation":
        raise ModelError(
            f"{same}{', 0 everywhere' if zero else ''}: the response is below what float64 resolves (an input, "
            "a record or a dt so small, or so large beside the model's time scales, that the parameters change "
            "nothing); rescale the data or the time step, or check that the input excites the model"
        )
    raise ModelError(
        f"{same}; it must use params (one row per set, columns in the order of names), or the input never excites "
        "the model"
    )


class SameOutput:
    """Whether every parameter set's output has been the same so far, fed the record chunk by chunk.

    A chunk before the first input change may well be the same for all sets;
    only a whole record that is shows a model ignoring ``params``.
    """

    def __init__(self, model, params, functions):
        self._model, self._params, self._functions = model, params, functions
        self.same = params.shape[0] > 1
        self._zero = True  # and 0 everywhere so far

    def check(self, sims, *, last):
        """Take the next chunk (n_samples, m); at the ``last`` one, refuse a record the same for every set."""
        if self.same:
            self.same = bool(np.array_equal(sims, np.broadcast_to(sims[:1], sims.shape)))
            self._zero = self._zero and self.same and not np.any(sims)
            if self.same and last:
                refuse_ignored_params(
                    self._model, self._params, self._functions, output=np.zeros(1) if self._zero else sims[0]
                )
