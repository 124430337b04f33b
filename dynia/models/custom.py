"""Bring your own model: a simulation function, or a discrete-time state update.

:class:`FunctionModel` wraps any function that simulates many parameter sets
at once, ``fn(params, u, dt) -> sims``: a wrapper around an existing
simulator, a vectorised formula, a call into compiled code.
:class:`StateSpaceModel` takes a nonlinear state update and an output map,
both vectorised over the samples, and streams them through the record in
time chunks, so memory stays bounded as for the built-in models; it also
steps one logged sample at a time for :class:`dynia.online.OnlineDynia`.
When both functions are ``numba.njit`` functions the time loop runs compiled.

Shapes follow :mod:`dynia.models.base`: ``params`` (n_samples, n_params)
with columns in the order of ``names``, ``u`` (n_steps,) or (n_steps,
n_inputs), outputs (n_samples, n_steps).

A model that returns the wrong shape, raises, gives non-finite output for
every parameter set or ignores ``params`` is stopped with one
:class:`~dynia.errors.ModelError` line naming the model and what was wrong.

Examples
--------
A static gain as a function, and a first-order lag as a state update:

>>> import numpy as np
>>> from dynia.models import FunctionModel, StateSpaceModel
>>> gain = FunctionModel(lambda params, u, dt: params[:, :1] * u, ["K"])
>>> gain.simulate([[2.0], [3.0]], [1.0, 2.0])
array([[2., 4.],
       [3., 6.]])
>>> lag = StateSpaceModel(
...     step=lambda x, u_k, p, dt: x + dt / p[:, 1:2] * (p[:, 0:1] * u_k - x),
...     output=lambda x, u_k, p: x[:, 0],
...     x0=[0.0], names=["K", "T"], n_states=1)
>>> lag.simulate([[2.0, 4.0]], [1.0, 1.0, 1.0])
array([[0.   , 0.5  , 0.875]])
"""

from __future__ import annotations

import copy
import functools
import sys
from collections.abc import Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..errors import DyniaError, ModelError
from ..settings import check_dt, check_x0
from .base import FLUSH_BELOW, Model, SameOutput, SimulationState, flush_tiny, refuse_ignored_params, user_code_failed

__all__ = ["FunctionModel", "StateSpaceModel", "StateErrors"]


def _label(function):
    return getattr(function, "__qualname__", None) or getattr(function, "__name__", None) or repr(function)


class FunctionModel(Model):
    """A model given as a function that simulates many parameter sets at once.

    Parameters
    ----------
    fn : callable
        ``fn(params, u, dt) -> sims``: ``params`` (n_samples, n_params) with
        columns in the order of ``names``, ``u`` (n_steps,) or (n_steps,
        n_inputs), ``dt`` the sample time; returns (n_samples, n_steps).
        With ``state`` given, ``fn(params, u_chunk, dt, state) -> (sims_chunk,
        state)`` instead, called on consecutive chunks of the record.
    names : sequence of str
        Parameter names.
    n_inputs : int, default 1
        Number of input signals.
    state : callable, optional
        ``state(params) -> initial state`` (any object ``fn`` understands).
        Given, the model streams through the record chunk by chunk, carrying
        the state, so memory does not grow with the record and the model can
        step one sample at a time (online use). Without it ``fn`` sees the
        whole record at once.

    Notes
    -----
    The model has no notion of ``x0``: ``fn`` (or ``state``) sets the
    initial state, and ``x0="steady"`` is refused rather than ignored.

    Examples
    --------
    >>> import numpy as np, dynia
    >>> def tank_level(params, u, dt):
    ...     return params[:, :1] * np.cumsum(u) * dt        # a pure integrator, gain K
    >>> model = dynia.models.FunctionModel(tank_level, ["K"])
    >>> u = np.r_[np.zeros(10), np.ones(30)]
    >>> y = tank_level(np.array([[0.5]]), u, 1.0)[0]
    >>> res = dynia.run(u, y, model, {"K": (0, 2)}, n_samples=200, n=3, rng=1)
    >>> sims = tank_level(res.samples, u, 1.0)
    >>> same = dynia.moving_window(y, sims, res.samples, [[0, 2]], n=3)
    >>> bool(np.array_equal(res.ic, same.ic))
    True
    """

    def __init__(self, fn, names: Sequence[str], *, n_inputs: int = 1, state=None):
        if not callable(fn):
            raise ModelError(f"FunctionModel needs a callable fn(params, u, dt); got {type(fn).__name__}")
        if state is not None and not callable(state):
            raise ModelError(f"state must be a callable state(params) -> initial state; got {type(state).__name__}")
        super().__init__(names, n_inputs)
        self.fn = fn
        self.state = state

    @property
    def streams(self) -> bool:
        """Whether the model simulates chunk by chunk (``state`` given) or the whole record at once."""
        return self.state is not None

    def __repr__(self) -> str:
        return f"FunctionModel({_label(self.fn)})"

    def simulate(self, params, u, dt: float = 1.0, x0: str = "zero") -> np.ndarray:
        if self.streams:
            return super().simulate(params, u, dt=dt, x0=x0)
        # fn already answers for the whole record: no chunks to gather, no copy.
        return self._called(*self._arguments(params, u, dt, x0))

    simulate.__doc__ = Model.simulate.__doc__

    def simulate_chunks(
        self, params, u, dt: float = 1.0, x0: str = "zero", chunk_steps: int | None = None
    ) -> Iterator[np.ndarray]:
        params, u, dt = self._arguments(params, u, dt, x0)
        chunk_steps = self.chunk_steps(params.shape[0], chunk_steps)
        if not self.streams:
            sims = self._called(params, u, dt)
            return (sims[:, start : start + chunk_steps] for start in range(0, u.shape[0], chunk_steps))
        return self._streamed(params, u, dt, chunk_steps)

    simulate_chunks.__doc__ = Model.simulate_chunks.__doc__

    def stepper(self, params, dt: float = 1.0, x0: str = "zero"):
        if not self.streams:
            raise ModelError(
                f"{self!r} simulates the whole record at once, so it cannot step one sample at a time; "
                "give state=... (fn then simulates chunk by chunk) for online use"
            )
        params, _, dt = self._arguments(params, None, dt, x0)
        return _ChunkStepper(self, params, dt)

    stepper.__doc__ = Model.stepper.__doc__

    @property
    def resumable(self) -> bool:
        return self.streams

    resumable.__doc__ = Model.resumable.__doc__

    def start_simulation(self, params, u, dt: float = 1.0, x0: str = "zero") -> SimulationState:
        if not self.streams:
            raise ModelError(
                f"{self!r} simulates the whole record at once, so it cannot pause and resume; "
                "give state=... (fn then simulates chunk by chunk)"
            )
        params, u, dt = self._arguments(params, u, dt, x0)
        return SimulationState(0, u.shape[0], params.shape[0], (params, dt, self._initial_state(params)))

    start_simulation.__doc__ = Model.start_simulation.__doc__

    def simulate_span(self, state, u, stop, *, time_major=False):
        u = self.check_span(state, u, stop)
        params, dt, carried = state.carried
        # fn may update its state in place; the state given must stay as it was.
        sims, carried = self._called(params, u[state.step : stop], dt, copy.deepcopy(carried))
        resumed = SimulationState(stop, state.n_steps, state.n_samples, (params, dt, carried))
        return (np.ascontiguousarray(sims.T) if time_major else sims), resumed

    simulate_span.__doc__ = Model.simulate_span.__doc__

    def _arguments(self, params, u, dt, x0):
        params = self.check_params(params)
        if check_x0(x0) != "zero":
            raise ModelError(f"{self!r} sets its own initial state; x0={x0!r} is not available for it")
        return params, None if u is None else self.check_input(u), check_dt(dt)

    def _streamed(self, params, u, dt, chunk_steps):
        state = self._initial_state(params)
        same = SameOutput(self, params, "fn")
        for start in range(0, u.shape[0], chunk_steps):
            sims, state = self._called(params, u[start : start + chunk_steps], dt, state)
            same.check(sims, last=start + chunk_steps >= u.shape[0])
            yield sims

    def _initial_state(self, params):
        try:
            return self.state(params)
        except BaseException as error:
            raise user_code_failed(f"{self!r}: state(params)", error) from error

    def _called(self, params, u, dt, *state):
        """``fn`` on one piece of the record, its answer checked."""
        try:
            answer = self.fn(_read_only(params), _read_only(u), dt, *state)
        except BaseException as error:
            raise user_code_failed(f"{self!r}: fn", error) from error
        if state:
            if not (isinstance(answer, tuple) and len(answer) == 2):
                raise ModelError(
                    f"{self!r}: with state given, fn must return (sims, state); got {type(answer).__name__}"
                )
            sims, new_state = answer
            return _checked_output(self, sims, params, u, whole_record=False), new_state
        return _checked_output(self, answer, params, u, whole_record=True)


class StateSpaceModel(Model):
    """A discrete-time (nonlinear) state-space model, vectorised over the parameter sets.

    ``x[k+1] = step(x[k], u[k], params, dt)`` and ``y[k] = output(x[k],
    u[k], params)``, from ``x[0] = x0``: as for the built-in models, ``y[0]``
    is the output of the initial state.

    Parameters
    ----------
    step : callable
        ``step(x, u_k, params, dt) -> x_next``, ``x`` and ``x_next``
        (n_samples, n_states), ``u_k`` a float (one input) or (n_inputs,),
        ``params`` (n_samples, n_params).
    output : callable
        ``output(x, u_k, params) -> y_k`` (n_samples,).
    x0 : array_like (n_states,) or callable
        The initial state of every sample, or ``x0(params) -> (n_samples,
        n_states)``.
    names : sequence of str
        Parameter names.
    n_states : int
        Length of the state vector.
    n_inputs : int, default 1
        Number of input signals.

    Notes
    -----
    When ``step`` and ``output`` are both ``numba.njit`` functions, the time
    loop over each chunk runs in compiled code calling them; otherwise it is
    a Python loop with one vectorised call of each per step, which costs a
    few microseconds per step whatever the number of samples. The run's
    ``x0`` setting must stay "zero" (the model's own ``x0`` applies);
    "steady" is refused rather than ignored.

    Examples
    --------
    A tank with square-root outflow, level h, inflow u, area A, outflow
    coefficient c (explicit Euler):

    >>> import numpy as np
    >>> from dynia.models import StateSpaceModel
    >>> tank = StateSpaceModel(
    ...     step=lambda x, u_k, p, dt: np.maximum(x + dt * (u_k - p[:, 1:2] * np.sqrt(x)) / p[:, 0:1], 0.0),
    ...     output=lambda x, u_k, p: x[:, 0], x0=[1.0], names=["A", "c"], n_states=1)
    >>> tank.simulate([[2.0, 0.5]], np.full(3, 0.5)).round(3)
    array([[1., 1., 1.]])
    """

    def __init__(self, step, output, x0, names: Sequence[str], *, n_states: int, n_inputs: int = 1):
        for name, function in (("step", step), ("output", output)):
            if not callable(function):
                raise ModelError(f"StateSpaceModel needs a callable {name}; got {type(function).__name__}")
        super().__init__(names, n_inputs)
        if isinstance(n_states, bool) or not isinstance(n_states, (int, np.integer)) or n_states < 1:
            raise ModelError(f"n_states must be a whole number >= 1; got {n_states!r}")
        self.n_states = int(n_states)
        self.step_function = step
        self.output_function = output
        if callable(x0):
            self.x0 = x0
        else:
            state = np.asarray(x0, dtype=float)
            if state.shape != (self.n_states,) or not np.isfinite(state).all():
                raise ModelError(f"x0 must be {self.n_states} finite numbers (n_states) or a callable; got {x0!r}")
            self.x0 = state
        self.compiled = _is_numba_function(step) and _is_numba_function(output)

    def __repr__(self) -> str:
        return f"StateSpaceModel({_label(self.step_function)}, {_label(self.output_function)})"

    def simulate_chunks(
        self, params, u, dt: float = 1.0, x0: str = "zero", chunk_steps: int | None = None
    ) -> Iterator[np.ndarray]:
        params = _read_only(self.check_params(params))
        u = _read_only(self.check_input(u))
        dt = check_dt(dt)
        self._check_x0_setting(x0)
        chunk_steps = self.chunk_steps(params.shape[0], chunk_steps)
        state = self.initial_state(params)
        return self._chunks(params, u, dt, chunk_steps, state)

    simulate_chunks.__doc__ = Model.simulate_chunks.__doc__

    def stepper(self, params, dt: float = 1.0, x0: str = "zero"):
        params = _read_only(self.check_params(params))
        self._check_x0_setting(x0)
        return _ChunkStepper(self, params, check_dt(dt))

    stepper.__doc__ = Model.stepper.__doc__

    @property
    def resumable(self) -> bool:
        return True

    resumable.__doc__ = Model.resumable.__doc__

    def start_simulation(self, params, u, dt: float = 1.0, x0: str = "zero") -> SimulationState:
        params = _read_only(self.check_params(params))
        u = self.check_input(u)
        self._check_x0_setting(x0)
        return SimulationState(0, u.shape[0], params.shape[0], (params, check_dt(dt), self.initial_state(params)))

    start_simulation.__doc__ = Model.start_simulation.__doc__

    def simulate_span(self, state, u, stop, *, time_major=False):
        u = _read_only(self.check_span(state, u, stop))
        params, dt, values = state.carried
        params = _read_only(params)  # a state sent to another process arrives writable
        # step may update the state in place; the state given must stay as it was.
        sims, values = self._span(values.copy(), u[state.step : stop], params, dt, first=state.step == 0)
        resumed = SimulationState(stop, state.n_steps, state.n_samples, (params, dt, values))
        return (np.ascontiguousarray(sims.T) if time_major else sims), resumed

    simulate_span.__doc__ = Model.simulate_span.__doc__

    def initial_state(self, params):
        """The state at step 0 of every sample, (n_samples, n_states), checked."""
        n_samples = params.shape[0]
        if callable(self.x0):
            try:
                state = np.asarray(self.x0(params), dtype=float)
            except BaseException as error:
                raise user_code_failed(f"{self!r}: x0(params)", error) from error
            if state.shape != (n_samples, self.n_states):
                raise ModelError(
                    f"{self!r}: x0(params) returned shape {state.shape}; expected (n_samples, n_states) = "
                    f"({n_samples}, {self.n_states})"
                )
            return np.ascontiguousarray(state)
        return np.tile(self.x0, (n_samples, 1))

    def _check_x0_setting(self, x0):
        if check_x0(x0) != "zero":
            raise ModelError(f"{self!r} starts from its own x0; x0={x0!r} is not available for it")

    def _chunks(self, params, u, dt, chunk_steps, state):
        same = SameOutput(self, params, "step and output")
        for start in range(0, u.shape[0], chunk_steps):
            sims, state = self._span(state, u[start : start + chunk_steps], params, dt, first=start == 0)
            same.check(sims, last=start + chunk_steps >= u.shape[0])
            yield sims

    def _span(self, state, piece, params, dt, *, first):
        """The outputs over ``piece`` and the state after it; ``first``: the piece starts the record."""
        if not first:
            return self._loop(state, piece, params, dt)
        # The first step in Python: clear errors for wrong shapes before any compiled loop.
        self.check_compiled(state, piece[0], params, dt)
        sims = np.empty((params.shape[0], piece.shape[0]))
        sims[:, 0], state = self.advance(state, piece[0], params, dt)
        rest = piece[1:]
        if rest.shape[0]:
            sims[:, 1:], state = self._loop(state, rest, params, dt)
        return sims, state

    def _loop(self, state, piece, params, dt):
        if self.compiled:
            sims = np.empty((params.shape[0], piece.shape[0]))
            try:
                state = _compiled_loops()[0](self.step_function, self.output_function, state, piece, params, dt, sims)
            except Exception as error:
                raise ModelError(f"{self!r}: the compiled time loop failed: {type(error).__name__}: {error}") from error
            return sims, state
        sims = np.empty((params.shape[0], piece.shape[0]))
        for k in range(piece.shape[0]):
            sims[:, k], state = self.advance(state, piece[k], params, dt)
        return sims, state

    def check_compiled(self, state, u_k, params, dt):
        """Run one step of compiled ``step`` and ``output`` through their Python implementations (``py_func``).

        Compiled code does not check indexes: an index beyond an array's end
        reads or writes memory that is not the array's, and can crash the
        interpreter. numpy checks them, so the first step taken in Python
        turns such a mistake into a ModelError before any compiled loop runs.
        Nothing of the step is kept. A model that is not compiled is already
        checked by every step it takes.
        """
        if self.compiled:
            self.advance(state.copy(), u_k, params, dt, python=True)

    def advance(self, state, u_k, params, dt, *, python=False):
        """One step: ``(y_k, x_next)`` of every sample, both checked.

        ``python``: call compiled functions' Python implementations (see :meth:`check_compiled`).
        """
        step, output = self.step_function, self.output_function
        if python:
            step, output = step.py_func, output.py_func
        try:
            y_k = output(state, u_k, params)
            following = step(state, u_k, params, dt)
        except BaseException as error:
            where = " (in Python, checked before the compiled loop)" if python else ""
            raise user_code_failed(f"{self!r}: step or output{where}", error) from error
        y_k = np.asarray(y_k, dtype=float)
        following = np.asarray(following, dtype=float)
        n_samples = params.shape[0]
        if y_k.shape != (n_samples,):
            raise ModelError(f"{self!r}: output returned shape {y_k.shape}; expected (n_samples,) = ({n_samples},)")
        if following.shape != (n_samples, self.n_states):
            raise ModelError(
                f"{self!r}: step returned shape {following.shape}; expected (n_samples, n_states) = "
                f"({n_samples}, {self.n_states})"
            )
        if following is state:
            following = following.copy()  # flushed below: never the caller's array
        return y_k, flush_tiny(following)


def _is_numba_function(function):
    """Whether ``function`` is a ``numba.njit`` function, found without importing numba (a numba function has)."""
    numba = sys.modules.get("numba")
    return numba is not None and isinstance(function, numba.core.registry.CPUDispatcher)


@functools.cache
def _compiled_loops():
    """The time loops of a compiled StateSpaceModel, (outputs, errors): made, with numba imported, on first use."""
    import numba

    @numba.njit(cache=False)
    def _flushed(state):
        """The state with entries below FLUSH_BELOW in magnitude set to zero, as flush_tiny does."""
        flat = state.reshape(-1)
        for i in range(flat.shape[0]):
            if abs(flat[i]) < FLUSH_BELOW:
                flat[i] = 0.0
        return state

    @numba.njit(cache=False)
    def _compiled_loop(step, output, state, piece, params, dt, sims):
        for k in range(piece.shape[0]):
            sims[:, k] = output(state, piece[k], params)
            state = _flushed(np.ascontiguousarray(step(state, piece[k], params, dt)))
        return state

    @numba.njit(nogil=True, cache=False)
    def _compiled_errors(step, output, state, piece, params, dt, measured, errors, diverged):
        """Advance through ``piece``, writing |y_k - measured_k| time-major (0 where not measured)."""
        for k in range(piece.shape[0]):
            y_k = output(state, piece[k], params)
            missing = np.isnan(measured[k])
            for i in range(y_k.shape[0]):
                if np.isfinite(y_k[i]):
                    errors[k, i] = 0.0 if missing else abs(y_k[i] - measured[k])
                else:
                    # inf, never NaN: the selection kernels order costs and NaN has no order.
                    # The set is dropped and the analysis redone, so the value only has to be safe.
                    diverged[i] = True
                    errors[k, i] = np.inf
            state = _flushed(np.ascontiguousarray(step(state, piece[k], params, dt)))
        return state

    return _compiled_loop, _compiled_errors


class StateErrors:
    """Absolute errors of a compiled StateSpaceModel, time-major, one block of steps at a time.

    A source for the engine's compiled windows (like
    ``dynia.engine.kernels.CompiledErrors`` for the linear models):
    ``rows(start, stop)`` gives (stop - start, n_samples) errors, requests
    moving forward in time. The samples are split over ``workers`` threads,
    each advancing its own slice of the state. Instead of simulating once
    more to find unstable sets, it marks in ``diverged`` every set whose
    output was not finite, so the caller can drop them and start again.
    """

    def __init__(self, model, params, u, y, *, dt, workers):
        # step and output must not change the parameter sets or the caller's input (numba types them read-only).
        params = _read_only(model.check_params(params))
        u = _read_only(model.check_input(u))
        state = model.initial_state(params)
        # Clear errors for wrong shapes and indexes, before compiled code.
        model.check_compiled(state, u[0], params, dt)
        model.advance(state.copy(), u[0], params, dt)
        self.y = y
        self._model = model
        self._u = u
        self._dt = dt
        n_samples = params.shape[0]
        self.diverged = np.zeros(n_samples, dtype=np.bool_)
        edges = np.linspace(0, n_samples, max(1, min(workers, n_samples)) + 1).astype(int)
        self._ranges = list(zip(edges[:-1], edges[1:]))
        self._params = [_read_only(np.ascontiguousarray(params[lo:hi])) for lo, hi in self._ranges]
        self._states = [np.ascontiguousarray(state[lo:hi]) for lo, hi in self._ranges]
        self._pool = ThreadPoolExecutor(max_workers=len(self._ranges)) if len(self._ranges) > 1 else None
        self._start = 0
        self._buffer = np.zeros((0, n_samples))
        # The errors are |output - y|: equal for every set at every step when the output does not depend on params.
        self._same = SameOutput(model, params, "step and output")

    def rows(self, start, stop):
        """Errors for times [start, stop), shape (stop - start, n_samples)."""
        if start < self._start:
            raise ModelError(f"rows from step {start} were requested after rows from step {self._start}")
        self._buffer = self._buffer[start - self._start :]
        self._start = start
        computed = self._start + self._buffer.shape[0]
        if computed < stop:
            self._buffer = np.concatenate([self._buffer, self._simulate(computed, stop)])
        return self._buffer[: stop - start]

    def _simulate(self, first, stop):
        errors = np.empty((stop - first, self.diverged.shape[0]))
        piece = self._u[first:stop]
        measured = np.ascontiguousarray(self.y[first:stop])
        model = self._model

        def block(number):
            lo, hi = self._ranges[number]
            self._states[number] = _compiled_loops()[1](
                model.step_function,
                model.output_function,
                self._states[number],
                piece,
                self._params[number],
                self._dt,
                measured,
                errors[:, lo:hi],
                self.diverged[lo:hi],
            )

        try:
            if self._pool is None:
                block(0)
            else:
                list(self._pool.map(block, range(len(self._ranges))))
        except DyniaError:
            raise
        except Exception as error:
            raise ModelError(f"{model!r}: the compiled time loop failed: {type(error).__name__}: {error}") from error
        self._same.check(errors.T, last=stop >= self._u.shape[0])
        return errors

    def close(self):
        if self._pool is not None:
            self._pool.shutdown()


class _ChunkStepper:
    """One logged sample at a time through a streaming model: its chunks of one step."""

    def __init__(self, model, params, dt):
        self._model = model
        self._params = params
        self._dt = dt
        self._state = None
        self.steps = 0

    def step(self, u_k):
        """Take the input of step k (a float, or (n_inputs,)) and return every sample's output y[k]."""
        u_k = _read_only(self._model.check_input(np.reshape(np.asarray(u_k, dtype=float), (1, -1))))
        if isinstance(self._model, StateSpaceModel):
            if self._state is None:
                self._state = self._model.initial_state(self._params)
                self._model.check_compiled(self._state, u_k[0], self._params, self._dt)
            y_k, self._state = self._model.advance(self._state, u_k[0], self._params, self._dt)
        else:
            if self._state is None:
                self._state = self._model._initial_state(self._params)
            sims, self._state = self._model._called(self._params, u_k, self._dt, self._state)
            y_k = sims[:, 0]
        self.steps += 1
        return y_k


def _checked_output(model, sims, params, u, *, whole_record):
    """``sims`` as a float (n_samples, n_steps) array, or a one-line ModelError naming what is wrong.

    Only on a whole record is one output for every parameter set a mistake: a
    chunk before the first input change may well be the same for all.
    """
    expected = (params.shape[0], u.shape[0])
    returned = getattr(sims, "dtype", None)
    coarse = str(returned) if returned is not None and returned.kind == "f" and returned.itemsize < 8 else None
    try:
        sims = np.asarray(sims, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{model!r}: fn returned {type(sims).__name__}, not an array of numbers") from None
    if sims.shape != expected:
        raise ModelError(
            f"{model!r}: fn returned shape {sims.shape}; expected (n_samples, n_steps) = {expected}"
            + (" (transposed?)" if sims.shape == expected[::-1] else "")
        )
    # Two rows that differ settle it at once; only then is the whole array compared.
    if (
        whole_record
        and expected[0] > 1
        and np.array_equal(sims[1], sims[0])
        and np.array_equal(sims, np.broadcast_to(sims[:1], expected))
    ):
        refuse_ignored_params(model, params, "fn", output=sims[0], precision=coarse)
    return sims


def _read_only(array):
    """A read-only view of ``array``: user code given the caller's input or the samples must not change them."""
    view = array.view()
    view.flags.writeable = False
    return view
