"""The linear models: exact batched simulation of many parameter sets at once.

A DYNIA run simulates the same single-output model for tens of thousands of
parameter sets on the same input record. The models here
discretise every parameter set exactly (zero-order hold, fractional dead
times included) and then advance all samples together, one vectorised update
per time step.

Shape convention
----------------
``params``
    ``(n_samples, n_params)``; the columns follow ``model.names``. A 1-D
    array of length ``n_params`` is accepted as a single sample.
``u``
    ``(n_steps,)``, the input sampled every ``dt``; ``(n_steps, n_inputs)``
    for a :class:`~dynia.models.transfer.TransferFunction` with ``n_inputs > 1``.
outputs
    ``(n_samples, n_steps)``; ``simulate_chunks`` yields consecutive
    ``(n_samples, m)`` pieces of it.

Time convention
---------------
Zero-order hold: ``y[k]`` is the output at ``t = k*dt`` and the input is
held from one sample to the next, ``u(t) = u[k]`` for ``k*dt <= t <
(k+1)*dt``, as a logging system holds a controller output. Hence ``y[0]`` is
the initial output. Before ``t = 0`` the input is 0 for ``x0="zero"`` and
``u[0]`` for ``x0="steady"``, which starts every sample in the steady state
at ``u[0]``. This equals ``control.forced_response`` of the discretised
system ``control.c2d(sys, dt, "zoh")`` (to rounding). It is *not*
``control.forced_response`` of the continuous-time ``sys``, which
interpolates the input linearly between the samples (a first-order hold):
for a unit pulse into ``1/(T s + 1)`` at ``dt = 1`` the two differ by up to
0.37 (T = 1) or 0.57 (T = 0.5). (MATLAB's ``lsim`` likewise holds the input
with ``'zoh'`` and interpolates it with ``'foh'``.)

Examples
--------
>>> import numpy as np
>>> from dynia.models import FOPDT
>>> model = FOPDT()
>>> model.names
('K', 'T', 'theta')
>>> params = np.array([[2.0, 1.0, 0.0], [2.0, 1.0, 1.5]])
>>> model.simulate(params, np.ones(4)).round(3)
array([[0.   , 1.264, 1.729, 1.9  ],
       [0.   , 0.   , 0.787, 1.554]])
"""

from __future__ import annotations

import numbers
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import DataError, ModelError, SettingsError
from ..settings import check_dt, check_x0
from .base import Model, SimulationState, flush_tiny

__all__ = ["LinearModel", "FirstOrder", "FOPDT", "SecondOrderDelay"]


# Time constants are clamped to this fraction of dt. Below it every factor
# exp(-tau/T) used by the discretisation is exactly 0.0 in float64: tau is dt
# or a part of dt that split_delay keeps at least ~1e-9*dt long, so
# tau/T >= 1000, far past exp's underflow at about 745. A clamped lag
# therefore reproduces the static-gain limit T -> 0 to machine precision,
# while the clamp avoids dividing by a zero time constant.
_TIME_CONSTANT_FLOOR = 1e-12

# theta/dt within this relative distance of an integer is taken as that
# integer, so that e.g. theta=0.3, dt=0.1 (0.3/0.1 = 2.9999999999999996) is
# a whole number of steps instead of a fractional delay of almost a step.
_DELAY_SNAP = 1e-9

# Samples per block when turning a (time, sample) chunk into (sample, time):
# a blocked copy keeps source and destination in cache and measured about
# four times faster than a plain transposed copy for 20 000 samples.
_TRANSPOSE_BLOCK = 256

# Longest dead time, in steps, a Stepper accepts: it keeps that much input
# history, 80 MB of float64 at this limit.
_STEPPER_MAX_DELAY_STEPS = 10_000_000


@dataclass(frozen=True)
class _DiscreteSystem:
    """Exact discretisation of every sample, sample axis last.

    With ``d`` the whole-step part of the dead time, the recursion is::

        x[k+1] = phi x[k] + gamma_now u[k-d] + gamma_prev u[k-d-1]
        y[k]   = c x[k]   + feed_now  u[k-d] + feed_prev  u[k-d-1]

    Keeping samples on the last axis makes each coefficient row used in the
    time loop one contiguous vector over samples.

    With several inputs (one dead time common to all), the input-dependent
    fields gain a leading input axis: ``gamma_now[j]`` is input j's
    ``(n_states, n_samples)`` column, ``feed_now[j]`` its ``(n_samples,)``
    feedthrough, ``steady_state[j]`` the state per unit of input j. One
    input keeps the layout without that axis, which the compiled kernels
    read.
    """

    phi: np.ndarray  # (n_states, n_states, n_samples)
    gamma_now: np.ndarray  # (n_states, n_samples) or (n_inputs, n_states, n_samples)
    gamma_prev: np.ndarray  # as gamma_now
    c: np.ndarray  # (n_states, n_samples)
    feed_now: np.ndarray  # (n_samples,) or (n_inputs, n_samples)
    feed_prev: np.ndarray  # as feed_now
    delay_steps: np.ndarray  # (n_samples,) int64
    steady_state: np.ndarray | None  # as gamma_now, per unit input

    @property
    def n_inputs(self) -> int:
        return 1 if self.feed_now.ndim == 1 else self.feed_now.shape[0]

    def input_columns(self) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """``(gamma_now, gamma_prev, feed_now, feed_prev)`` of each input, in input order."""
        fields = (self.gamma_now, self.gamma_prev, self.feed_now, self.feed_prev)
        if self.n_inputs == 1:
            return [fields]
        return list(zip(*fields))


class LinearModel(Model):
    """Base class of the linear models: exact zero-order-hold discretisation of every sample.

    Subclasses set the parameter names and implement ``discretise``; the
    chunking and the time loop live here, shared by all. The compiled engine
    (:mod:`dynia.engine.kernels`) simulates these models in compiled code.
    """

    def check_ranges(self, ranges) -> None:
        """Refuse a range that reaches a value the model refuses (a negative time constant), naming the parameter.

        Each end of each range is tried with the other parameters in the middle of theirs, on three steps of input.

        Examples
        --------
        >>> FirstOrder().check_ranges({"K": (0, 7), "T": (-1, 7)})  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        dynia.errors.SettingsError: T ranges over (-1, 7), which reaches T = -1, where FirstOrder refuses it ...
        """
        middle = [sum(map(float, ranges[name])) / 2 for name in self.names]
        trials = [(None, None, middle)] + [
            (name, float(end), middle[:column] + [float(end)] + middle[column + 1 :])
            for column, name in enumerate(self.names)
            for end in ranges[name]
        ]
        for name, value, point in trials:
            reason = self._refusal(point)
            if reason is None:
                continue
            if name is None:  # refused in the middle of every range: blame the parameter the model names
                named = [other for other in self.names if reason.startswith(f"{other} ")]
                if not named:
                    return  # not a matter of one range: the run says what is wrong
                name, value = named[0], middle[self.names.index(named[0])]
            low, high = map(float, ranges[name])
            raise SettingsError(
                f"{name} ranges over ({low:g}, {high:g}), which reaches {name} = {value:g}, where "
                f"{type(self).__name__} refuses it ({reason}); give a range of values the model accepts",
                name,
            )

    def _refusal(self, point):
        """Why the model refuses the parameter set ``point`` (its error's first clause), or None."""
        probe = np.zeros(3 if self.n_inputs == 1 else (3, self.n_inputs))
        try:
            self.simulate(np.array([point]), probe)
        except ModelError as error:
            return str(error).split(";")[0]
        return None

    def simulate_chunks(
        self, params, u, dt: float = 1.0, x0: str = "zero", chunk_steps: int | None = None
    ) -> Iterator[np.ndarray]:
        params = self.check_params(params)
        u = self.check_input(u)
        dt = check_dt(dt)
        x0 = check_x0(x0)
        chunk_steps = self.chunk_steps(params.shape[0], chunk_steps)
        system = self.discretise(params, dt, u.shape[0], steady=x0 == "steady")
        return _run(system, u, x0, chunk_steps)

    simulate_chunks.__doc__ = Model.simulate_chunks.__doc__

    @property
    def resumable(self) -> bool:
        return True

    resumable.__doc__ = Model.resumable.__doc__

    def start_simulation(self, params, u, dt: float = 1.0, x0: str = "zero") -> SimulationState:
        params = self.check_params(params)
        u = self.check_input(u)
        x0 = check_x0(x0)
        system = self.discretise(params, check_dt(dt), u.shape[0], steady=x0 == "steady")
        state = _initial_state(system, x0, u[0])
        # The discretisation travels with the state: resuming must not redo it (per sample for a TransferFunction).
        return SimulationState(0, u.shape[0], params.shape[0], (system, x0, state))

    start_simulation.__doc__ = Model.start_simulation.__doc__

    def simulate_span(self, state, u, stop, *, time_major=False):
        u = self.check_span(state, u, stop)
        system, x0, values = state.carried
        # The recursion overwrites the rows it starts from; the state given stays as it was.
        recursion = _Recursion(system, values.copy())
        output = np.empty((stop - state.step, state.n_samples))
        _advance(system, recursion, u, x0, state.step, stop, output)
        resumed = SimulationState(stop, state.n_steps, state.n_samples, (system, x0, recursion.state()))
        return (output if time_major else _to_sample_major(output)), resumed

    simulate_span.__doc__ = Model.simulate_span.__doc__

    def stepper(self, params, dt: float = 1.0, x0: str = "zero") -> Stepper:
        params = self.check_params(params)
        dt = check_dt(dt)
        x0 = check_x0(x0)
        system = self.discretise(params, dt, _STEPPER_MAX_DELAY_STEPS, steady=x0 == "steady")
        longest = int(system.delay_steps.max())
        if longest > _STEPPER_MAX_DELAY_STEPS:
            raise ModelError(
                f"a dead time of more than {_STEPPER_MAX_DELAY_STEPS} steps of dt={dt} is too long "
                "for a stepper, which keeps the input history of the longest dead time"
            )
        return Stepper(system, x0)

    stepper.__doc__ = Model.stepper.__doc__

    def _require_nonnegative(self, params: np.ndarray, names: Sequence[str]) -> None:
        """Raise for the first sample with a negative value of one of ``names``."""
        for name in names:
            column = params[:, self.names.index(name)]
            negative = np.flatnonzero(column < 0)
            if negative.size:
                sample = negative[0]
                raise ModelError(f"{name} must be >= 0; sample {sample} has {name} = {column[sample]}")

    def discretise(self, params: np.ndarray, dt: float, n_steps: int, steady: bool) -> _DiscreteSystem:
        """The exact discretisation of every sample (see ``_DiscreteSystem``)."""
        raise NotImplementedError(f"{type(self).__name__} must implement discretise(params, dt, n_steps, steady)")


class Stepper:
    """Every parameter set of a model advanced one input sample at a time.

    Made by `Model.stepper`. The arithmetic is the time loop of `simulate`
    (both call the same per-step update), so the outputs agree bit for bit.
    Only the input history of the longest dead time is kept: memory does
    not grow with the number of steps.

    Attributes
    ----------
    steps : int
        Number of input samples stepped so far (the next one is step
        ``steps``, at ``t = steps*dt``).
    n_inputs : int
        Number of inputs: ``step`` takes a number for one, a sequence of
        ``n_inputs`` numbers otherwise.
    """

    def __init__(self, system: _DiscreteSystem, x0: str):
        self._system = system
        self._x0 = x0
        self.n_inputs = system.n_inputs
        delays = system.delay_steps
        # With one common delay the delayed input is a scalar, as in _run.
        self._delays = delays[:1] if np.all(delays == delays[0]) else delays
        # One row of input history per input; the delay is common to all inputs.
        self._history = np.empty((self.n_inputs, int(delays.max()) + 2))
        self._index = np.empty(self._delays.shape, dtype=np.int64)
        self._delayed = [np.empty((self.n_inputs, *self._delays.shape)) for _ in range(2)]
        self._output = np.empty(system.c.shape[1])
        self._view = self._output.view()
        self._view.flags.writeable = False
        self._recursion = None
        self.steps = 0

    def __getstate__(self):
        # The output buffer holds the last step's output only: a copy (or a checkpoint) gets a fresh one.
        return {key: value for key, value in self.__dict__.items() if key not in ("_output", "_view")}

    def __setstate__(self, state):
        # A copy (or an unpickled stepper) gets its own arrays; its view must look at its own output.
        self.__dict__.update(state)
        self._output = np.empty(self._system.c.shape[1])
        self._view = self._output.view()
        self._view.flags.writeable = False

    def step(self, u_k) -> np.ndarray:
        """Take the input ``u_k`` of step k and return every sample's output y[k].

        Parameters
        ----------
        u_k : float, or sequence of `n_inputs` floats
            The input at step k (every input's value, in input order, for
            a multi-input model).

        Returns
        -------
        ndarray, shape (n_samples,)
            A read-only view that the next call overwrites; copy it to keep it.
        """
        u_k = self._checked(u_k)
        if self._recursion is None:
            self._recursion = _Recursion(self._system, _initial_state(self._system, self._x0, u_k))
            # Slots not yet written stand for the input before t=0.
            self._history[:] = np.reshape(u_k, (-1, 1)) if self._x0 == "steady" else 0.0
        self._history[:, self.steps % self._history.shape[1]] = u_k
        inputs = self._delayed_inputs(0)
        if self._recursion.needs_prev:
            inputs += self._delayed_inputs(1)
        self._recursion.step(self._output, inputs)
        self.steps += 1
        return self._view

    def _checked(self, u_k):
        """``u_k`` as a finite float (one input) or a finite (n_inputs,) array."""
        if self.n_inputs == 1:
            if isinstance(u_k, bool) or not isinstance(u_k, numbers.Real):
                raise TypeError(f"u_k must be a real number; got {type(u_k).__name__}")
            u_k = float(u_k)
            if not np.isfinite(u_k):
                raise DataError(f"u_k must be finite; got {u_k} at step {self.steps}")
            return u_k
        values = np.asarray(u_k)
        if values.dtype.kind not in "iuf":
            raise TypeError(f"u_k must be a sequence of {self.n_inputs} real numbers; got {values.dtype} values")
        if values.shape != (self.n_inputs,):
            raise DataError(
                f"u_k must hold one value per input, shape ({self.n_inputs},); got shape {values.shape} "
                f"at step {self.steps}"
            )
        values = values.astype(float)
        if not np.isfinite(values).all():
            raise DataError(f"u_k must be finite; got {values.tolist()} at step {self.steps}")
        return values

    def _delayed_inputs(self, extra: int) -> list:
        """u_j[k - d - extra] of every input j, per sample (a scalar each for one common delay)."""
        length = self._history.shape[1]
        if self._delays.shape[0] == 1:
            slot = (self.steps - int(self._delays[0]) - extra) % length
            return [row[slot] for row in self._history]
        np.subtract(self.steps - extra, self._delays, out=self._index)
        np.remainder(self._index, length, out=self._index)
        return [np.take(row, self._index, out=out) for row, out in zip(self._history, self._delayed[extra])]


class _Lag(LinearModel):
    """Models whose output never exceeds |K| times the largest input in magnitude.

    Lags with non-negative time constants and a dead time have no overshoot,
    from a zero or a steady start alike, so that bound decides finiteness.
    """

    def finite_samples(self, params, u, dt: float = 1.0, x0: str = "zero") -> np.ndarray:
        params = self.check_params(params)
        peak = np.abs(self.check_input(u)).max()
        with np.errstate(over="ignore"):
            return np.isfinite(np.abs(params[:, self.names.index("K")]) * peak * 2.0)


class FirstOrder(_Lag):
    """First-order lag ``K / (T s + 1)``.

    Parameters (columns of ``params``): ``K`` gain, ``T`` time constant
    (>= 0; ``T = 0`` is the static gain).

    Examples
    --------
    >>> from dynia.models import FirstOrder
    >>> FirstOrder().simulate([[2.0, 1.0]], [1.0, 1.0, 1.0], x0="steady")
    array([[2., 2., 2.]])
    """

    def __init__(self):
        super().__init__(("K", "T"))

    def discretise(self, params, dt, n_steps, steady):
        self._require_nonnegative(params, ("T",))
        gain, time_constant = params.T
        return _first_order_system(gain, time_constant, np.zeros_like(gain), dt, n_steps)


class FOPDT(_Lag):
    """First-order lag plus dead time ``K exp(-theta s) / (T s + 1)``.

    Parameters (columns of ``params``): ``K`` gain, ``T`` time constant
    (>= 0), ``theta`` dead time (>= 0, any real value, not only multiples of
    ``dt``).

    Examples
    --------
    >>> from dynia.models import FOPDT
    >>> FOPDT().simulate([[1.0, 0.0, 2.0]], [1.0, 2.0, 3.0, 4.0])
    array([[0., 0., 0., 1.]])
    """

    def __init__(self):
        super().__init__(("K", "T", "theta"))

    def discretise(self, params, dt, n_steps, steady):
        self._require_nonnegative(params, ("T", "theta"))
        gain, time_constant, delay = params.T
        return _first_order_system(gain, time_constant, delay, dt, n_steps)


class SecondOrderDelay(_Lag):
    """Two lags plus dead time ``K exp(-theta s) / ((T1 s + 1)(T2 s + 1))``.

    Parameters (columns of ``params``): ``K`` gain, ``T1`` and ``T2`` time
    constants (>= 0, equal values allowed), ``theta`` dead time (>= 0).

    The model is discretised in closed form, with the lags realised as a
    cascade, which stays exact and free of cancellation for ``T1 == T2`` and
    for vanishing time constants.

    Examples
    --------
    >>> from dynia.models import SecondOrderDelay
    >>> SecondOrderDelay().simulate([[1.0, 1.0, 1.0, 0.0]], [1.0] * 4).round(4)
    array([[0.    , 0.2642, 0.594 , 0.8009]])
    """

    def __init__(self):
        super().__init__(("K", "T1", "T2", "theta"))

    def discretise(self, params, dt, n_steps, steady):
        self._require_nonnegative(params, ("T1", "T2", "theta"))
        gain, lag1, lag2, delay = params.T
        delay_steps, fraction = split_delay(delay, dt, n_steps)
        lag1_clamped = np.maximum(lag1, _TIME_CONSTANT_FLOOR * dt)
        lag2_clamped = np.maximum(lag2, _TIME_CONSTANT_FLOOR * dt)

        # State x1 is the first lag's output (unit gain), x2 = y is the
        # second lag's output driven by K*x1.
        def over(duration):
            """Free-response factors and the state after a unit input step."""
            decay1 = np.exp(-duration / lag1_clamped)
            decay2 = np.exp(-duration / lag2_clamped)
            coupling = _cascade_coupling(duration, lag1, lag2, lag1_clamped, lag2_clamped, decay1, decay2)
            step_x1 = -np.expm1(-duration / lag1_clamped)
            # By superposition the step response of x2 is K (1 - e^{-t/T2} - coupling).
            step_x2 = gain * (-np.expm1(-duration / lag2_clamped) - coupling)
            return decay1, decay2, coupling, step_x1, step_x2

        n_samples = gain.shape[0]
        decay1, decay2, coupling, _, _ = over(np.full(n_samples, dt))
        phi = np.zeros((2, 2, n_samples))
        phi[0, 0] = decay1
        phi[1, 0] = gain * coupling
        phi[1, 1] = decay2

        late_decay1, late_decay2, late_coupling, late_x1, late_x2 = over((1.0 - fraction) * dt)
        _, _, _, early_x1, early_x2 = over(fraction * dt)
        gamma_now = np.stack((late_x1, late_x2))
        gamma_prev = np.stack((late_decay1 * early_x1, gain * late_coupling * early_x1 + late_decay2 * early_x2))
        zeros = np.zeros(n_samples)
        return _DiscreteSystem(
            phi=phi,
            gamma_now=gamma_now,
            gamma_prev=gamma_prev,
            c=np.stack((zeros, np.ones(n_samples))),
            feed_now=zeros,
            feed_prev=zeros,
            delay_steps=delay_steps,
            steady_state=np.stack((np.ones(n_samples), gain)),
        )


def _first_order_system(gain, time_constant, delay, dt, n_steps) -> _DiscreteSystem:
    """Closed-form discretisation of K e^{-theta s}/(T s + 1), state x = y."""
    delay_steps, fraction = split_delay(delay, dt, n_steps)
    time_constant = np.maximum(time_constant, _TIME_CONSTANT_FLOOR * dt)
    late = (1.0 - fraction) * dt
    # -expm1(-x) is 1 - exp(-x) without cancellation when T >> dt.
    gamma_now = gain * -np.expm1(-late / time_constant)
    gamma_prev = np.exp(-late / time_constant) * gain * -np.expm1(-fraction * dt / time_constant)
    zeros = np.zeros_like(gain)
    return _DiscreteSystem(
        phi=np.exp(-dt / time_constant)[None, None, :],
        gamma_now=gamma_now[None, :],
        gamma_prev=gamma_prev[None, :],
        c=np.ones((1, gain.shape[0])),
        feed_now=zeros,
        feed_prev=zeros,
        delay_steps=delay_steps,
        steady_state=gain[None, :].copy(),
    )


def _cascade_coupling(duration, lag1, lag2, lag1_clamped, lag2_clamped, decay1, decay2):
    """x2(t) of 1/(T1 s+1) -> 1/(T2 s+1) from x1(0) = 1, x2(0) = 0, no input.

    This is ``T1 (e^{-t/T1} - e^{-t/T2}) / (T1 - T2)``. For close time
    constants the difference cancels, so it is rewritten with
    ``z = t/T2 - t/T1`` as ``e^{-t/T2} (t/T2) expm1(z)/z``, whose limit for
    ``T1 == T2`` is ``(t/T) e^{-t/T}``.
    """
    z = duration / lag2_clamped - duration / lag1_clamped
    close = np.abs(z) <= 0.5
    safe_z = np.where(close & (z != 0), z, 1.0)
    relative_growth = np.where(z == 0, 1.0, np.expm1(safe_z) / safe_z)
    close_value = decay2 * (duration / lag2_clamped) * relative_growth
    # Away from the close branch the clamped constants differ, so at least one
    # raw constant exceeds the floor and T1 - T2 != 0. Using the raw T1 keeps
    # T1 = 0 an exact zero coupling (the first lag then follows u at once).
    gap = np.where(close, 1.0, lag1 - lag2)
    far_value = lag1 * (decay1 - decay2) / gap
    return np.where(close, close_value, far_value)


def split_delay(delay, dt, n_steps):
    """Write each dead time as (d + f)*dt, d integer >= 0, 0 <= f < 1."""
    # A dead time beyond the record only ever sees the input before t=0, so
    # capping it changes nothing and keeps theta/dt and the int cast finite.
    steps = np.minimum(delay, (n_steps + 1) * dt) / dt
    nearest = np.rint(steps)
    snap = np.abs(steps - nearest) <= _DELAY_SNAP * np.maximum(1.0, steps)
    steps = np.where(snap, nearest, steps)
    whole = np.floor(steps)
    return whole.astype(np.int64), steps - whole


def _run(system: _DiscreteSystem, u: np.ndarray, x0: str, chunk_steps: int) -> Iterator[np.ndarray]:
    """Advance all samples through ``u`` and yield (n_samples, m) output chunks."""
    n_steps = u.shape[0]
    recursion = _Recursion(system, _initial_state(system, x0, u[0]))
    time_major = np.empty((min(chunk_steps, n_steps), system.c.shape[1]))
    for start in range(0, n_steps, chunk_steps):
        stop = min(start + chunk_steps, n_steps)
        _advance(system, recursion, u, x0, start, stop, time_major[: stop - start])
        yield _to_sample_major(time_major[: stop - start])


def _advance(system: _DiscreteSystem, recursion: _Recursion, u: np.ndarray, x0: str, start: int, stop: int, out):
    """Write the outputs of steps [start, stop) into ``out`` (stop - start, n_samples); the recursion moves on."""
    n_steps = u.shape[0]
    by_input = u.reshape(n_steps, -1).T
    delays = system.delay_steps
    # With one common delay the delayed input is a scalar per step, so no
    # (steps, samples) gather is needed.
    offsets = delays[:1] if np.all(delays == delays[0]) else delays
    # Only the inputs the span reaches back to are gathered, after one slot
    # standing for every time before t=0: indices clipped at reach - 1 land
    # on it, so the pre-history needs no padding by the delay.
    reach = max(start - int(offsets.max()) - 1, 0)
    before = by_input[:, :1] if x0 == "steady" else np.zeros((by_input.shape[0], 1))
    padded_input = np.concatenate((before, by_input[:, reach:stop]), axis=1)
    source_index = np.arange(start, stop)[:, None] - offsets[None, :]
    # Each gathered block is (n_inputs, steps, offsets): u_j[k-d], then u_j[k-d-1].
    gathered = [padded_input[:, np.maximum(source_index, reach - 1) - reach + 1]]
    if recursion.needs_prev:
        gathered.append(padded_input[:, np.maximum(source_index - 1, reach - 1) - reach + 1])
    if offsets.shape[0] == 1:
        gathered = [block[:, :, 0] for block in gathered]
    inputs = [rows for block in gathered for rows in block]
    for step in range(stop - start):
        # The state after the record is never output; advancing to it could only overflow.
        recursion.step(out[step], [rows[step] for rows in inputs], advance=start + step + 1 < n_steps)


def _initial_state(system: _DiscreteSystem, x0: str, first_input) -> np.ndarray:
    """State at t=0, (n_states, n_samples): zero, or the steady state at the first input (vector)."""
    if x0 != "steady":
        return np.zeros(system.c.shape)
    if system.n_inputs == 1:
        return system.steady_state * first_input
    state = system.steady_state[0] * first_input[0]
    for per_unit, value in zip(system.steady_state[1:], first_input[1:]):
        state += per_unit * value
    return state


class _Recursion:
    """One time step of a discretised system for every sample at once.

    The single place where outputs and states are computed: the batch loop of
    `_run` and `Stepper` both call `step`, so they agree bit for bit.
    """

    def __init__(self, system: _DiscreteSystem, state: np.ndarray):
        n_states, n_samples = system.c.shape
        n_inputs = system.n_inputs
        # Sources of the linear combinations: the states, then u_j[k-d] of
        # every input j, then u_j[k-d-1]. The input terms are summed input by
        # input, now before prev, which for one input is the order the
        # compiled kernels follow.
        columns = system.input_columns()
        first_prev = n_states + n_inputs
        self._state_terms = [
            _nonzero_terms(
                [(system.phi[i, j], j) for j in range(n_states)]
                + [
                    term
                    for j, (gamma_now, gamma_prev, _, _) in enumerate(columns)
                    for term in ((gamma_now[i], n_states + j), (gamma_prev[i], first_prev + j))
                ]
            )
            for i in range(n_states)
        ]
        self._output_terms = _nonzero_terms(
            [(system.c[i], i) for i in range(n_states)]
            + [
                term
                for j, (_, _, feed_now, feed_prev) in enumerate(columns)
                for term in ((feed_now, n_states + j), (feed_prev, first_prev + j))
            ]
        )
        self.needs_prev = any(
            source >= first_prev for terms in [*self._state_terms, self._output_terms] for _, source in terms
        )
        self._current, self._upcoming = list(state), list(np.empty_like(state))
        self._n_samples = n_samples
        self._scratch = np.empty(n_samples)

    def __getstate__(self):
        # The next state and the scratch row are written in full before they are read: a copy needs neither.
        return {key: value for key, value in self.__dict__.items() if key not in ("_upcoming", "_scratch")}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._upcoming = [np.empty_like(row) for row in self._current]
        self._scratch = np.empty(self._n_samples)

    def state(self) -> np.ndarray:
        """A copy of the current state, (n_states, n_samples)."""
        return np.array(self._current).reshape(len(self._current), self._n_samples)

    def step(self, out: np.ndarray, inputs: list, advance: bool = True) -> None:
        """Write y[k] into ``out`` and, if ``advance``, move the state to x[k+1].

        ``inputs`` is ``[u_0[k-d], ..., u_m[k-d]]`` for the inputs 0..m,
        followed by ``[u_0[k-d-1], ..., u_m[k-d-1]]`` when `needs_prev`;
        each a scalar (one common delay) or (n_samples,).
        """
        sources = self._current + inputs
        _combine(out, self._output_terms, sources, self._scratch)
        if advance:
            for row, terms in zip(self._upcoming, self._state_terms):
                _combine(row, terms, sources, self._scratch)
                flush_tiny(row, self._scratch)
            self._current, self._upcoming = self._upcoming, self._current


def _nonzero_terms(terms):
    """Drop terms whose coefficient is zero for every sample (structural zeros)."""
    return [(coefficient, source) for coefficient, source in terms if np.any(coefficient != 0)]


def _combine(out, terms, sources, scratch):
    """out = sum(coefficient * sources[source]) without allocating."""
    if not terms:
        out.fill(0.0)
        return
    coefficient, source = terms[0]
    np.multiply(coefficient, sources[source], out=out)
    for coefficient, source in terms[1:]:
        np.multiply(coefficient, sources[source], out=scratch)
        out += scratch


def _to_sample_major(time_major: np.ndarray) -> np.ndarray:
    n_steps, n_samples = time_major.shape
    sample_major = np.empty((n_samples, n_steps))
    for start in range(0, n_samples, _TRANSPOSE_BLOCK):
        block = slice(start, start + _TRANSPOSE_BLOCK)
        sample_major[block] = time_major[:, block].T
    return sample_major
