"""The compiled engine's error source: a linear model's simulation served as error rows or fused window sums.

:class:`CompiledErrors` runs the kernels of :mod:`dynia.engine.kernels.simulate`
and :mod:`dynia.engine.kernels.fused` on a thread pool, samples split
between the threads (the kernels release the GIL); :func:`recursion_kernels`
decides, once for a model, which of them run it; :func:`compiled` tells
whether a process has compiled them yet.
"""

from typing import NamedTuple

import numpy as np

from ...errors import ModelError, SettingsError
from ...settings import check_dt, check_x0
from .batches import analyse_windows_batched
from .compile import AVAILABLE
from .fused import general_window_sums, lag_window_sums
from .readoff import analyse_windows
from .simulate import general_errors, lag_states, simulate_lag

__all__ = ["CompiledErrors", "compiled", "recursion_kernels", "RecursionKernels"]


class RecursionKernels(NamedTuple):
    """The kernels that run one linear model's recursion, and the recursion in the form they take."""

    #: Error rows or outputs: :func:`~dynia.engine.kernels.simulate.general_errors` or ``simulate_lag``.
    errors: object
    #: Fused window sums: :func:`~dynia.engine.kernels.fused.general_window_sums` or ``lag_window_sums``.
    window_sums: object
    #: States and totals without window sums: :func:`~dynia.engine.kernels.simulate.lag_states`, or None.
    states: object
    #: The recursion (coefficients, delays, terms), or its lag (coefficients, delay, flags).
    form: tuple


def recursion_kernels(recursion):
    """The kernels of a discretised linear model's ``recursion`` (coefficients, delays, terms), and its form for them.

    A lag (one state that carries over, seen in the output; one dead time
    or one a sample, as a first order plus dead time with a sampled delay)
    takes the lag loops, a pass over the samples per step, and has a state
    pass of its own; any other model the general loops, term by term, and
    no state pass (the error rows serve). Decided here, and only here, so
    that a run compiles only the kernels it uses. The forms are described
    in :mod:`dynia.engine.kernels.simulate`.
    """
    coefficients, delays, (state_terms, output_terms) = recursion
    phi, gamma_now, gamma_prev, c, feed_now, feed_prev = coefficients
    if c.shape[0] == 1 and state_terms[0, 0] and output_terms[0]:
        flags = (bool(output_terms[1]), bool(output_terms[2]), bool(state_terms[0, 1]), bool(state_terms[0, 2]))
        # One dead time as an integer: the kernels are then compiled without the gathering of each sample's inputs.
        lag_delays = delays[0] if delays.shape[0] == 1 else delays
        lag = ((phi[0, 0], gamma_now[0], gamma_prev[0], c[0], feed_now, feed_prev), lag_delays, flags)
        return RecursionKernels(simulate_lag, lag_window_sums, lag_states, lag)
    return RecursionKernels(general_errors, general_window_sums, None, recursion)


class CompiledErrors:
    """Absolute errors of a model's simulations, computed block by block by the simulation kernels.

    Or, fused, the window sums the errors make (:meth:`window_sums`, by the
    fused kernels): what the engine's windows pass takes (``fused`` is
    True), so that no error matrix goes through memory. Which kernels, the
    lag models' or the general ones, :func:`recursion_kernels` decides.

    A source for :func:`dynia.engine.windows.analyse_stream`: ``rows(start,
    stop)`` returns the time-major errors (stop - start, n_samples);
    requests must move forward in time, and the rows before a request are
    dropped, so memory stays at one block. The simulation of each block is
    split over ``workers`` threads by sample. Its output equals
    ``model.simulate`` bit for bit (the same recursion, term by term).

    A cluster cuts the record in time: :meth:`states_at` tells every
    sample's state at the steps where the pieces begin, in one pass without
    window sums, and :meth:`resume` puts a fresh source where serving the
    window sums up to a piece would have left it.

    Parameters
    ----------
    model : dynia.models.Model
    params : ndarray (n_samples, n_params), columns in ``model.names`` order
    u, y : ndarray (n_steps,)
    dt : float
    x0 : {"zero", "steady"}
    workers : int
    """

    fused = True

    def __init__(self, model, params, u, y, *, dt, x0, workers):
        from concurrent.futures import ThreadPoolExecutor

        params = model.check_params(params)
        dt, x0 = check_dt(dt), check_x0(x0)
        system = model.discretise(params, dt, u.shape[0], steady=x0 == "steady")
        # A writable record always: numba types a read-only array (a pandas column under copy-on-write, pandas >= 3)
        # apart, and would compile the simulation kernels a second time for it.
        self.y = y if y.flags.writeable else y.copy()
        n_states, n_samples = system.c.shape
        self._n_samples = n_samples
        self._kernels = recursion_kernels(_recursion(system))
        self._padded_input = np.concatenate(([u[0] if x0 == "steady" else 0.0], u))
        self._state = system.steady_state * u[0] if x0 == "steady" else np.zeros((n_states, n_samples))
        self._state = np.ascontiguousarray(self._state, dtype=float)
        self._start = 0
        self._buffer = np.zeros((0, n_samples))
        self._ring = None  # the last window's errors, once window_sums runs
        self._serving = None  # what the source gives: "rows", "window sums" or "outputs", one kind only
        self._next = 0
        self._workers = max(1, min(workers, n_samples))
        self._pool = ThreadPoolExecutor(max_workers=self._workers) if self._workers > 1 else None
        edges = np.linspace(0, n_samples, self._workers + 1).astype(int)
        self._sample_ranges = list(zip(edges[:-1], edges[1:]))

    def rows(self, start, stop):
        """Errors for times [start, stop), shape (stop - start, n_samples)."""
        self._serve("rows")
        if start < self._start:
            raise SettingsError(
                f"rows from step {start} were requested after rows from step {self._start}; "
                "requests must move forward in time"
            )
        self._buffer = self._buffer[start - self._start :]
        self._start = start
        computed = self._start + self._buffer.shape[0]
        if computed < stop:
            self._buffer = np.concatenate([self._buffer, self._simulate(computed, stop)])
        return self._buffer[: stop - start]

    def output_chunks(self, chunk_steps):
        """The simulated outputs, (n_samples, m) chunks of ``chunk_steps`` steps in time order: ``model.simulate`` cut.

        Each set's output bit for bit as the model's numpy recursion gives it
        (the noise floor's residuals need the sign the errors drop). Once, on
        a fresh source, which then serves nothing else.
        """
        if self._serving is not None:
            raise SettingsError(f"outputs were requested after {self._serving}; a source gives one or the other")
        self._serving = "outputs"
        n_steps = self.y.shape[0]
        return (
            np.ascontiguousarray(self._simulate(first, min(first + chunk_steps, n_steps), True).T)
            for first in range(0, n_steps, chunk_steps)
        )

    def _simulate(self, first, stop, outputs=False):
        kernels = self._kernels
        errors = np.empty((stop - first, self._n_samples))
        measured = np.ascontiguousarray(self.y[first:stop])
        last_step = self.y.shape[0] - 1

        def block(sample_range):
            return kernels.errors(
                kernels.form, self._padded_input, measured, first, last_step, self._state, errors, sample_range, outputs
            )

        self._raise_on_overflow(self._run(block))
        return errors

    def window_sums(self, start, stop, halos, totals, scale=1.0):
        """The sums of the errors over the windows at steps [start, stop), fused with the simulation; no error rows.

        ``halos`` = (before, after), the steps a window reaches back and
        ahead (:func:`dynia.engine.windows.window_halos`); errors are
        multiplied by ``scale`` first and each simulated step's added to
        ``totals`` (n_samples,), in time order. Requests must come chunk
        after chunk from step 0, and not mixed with :meth:`rows`. Returns the
        sums (stop - start, n_samples), time-major, equal bit for bit to
        what :func:`~dynia.engine.kernels.readoff.analyse_windows` forms from the error rows, and each
        window's measured points (stop - start,). Memory: the sums and the
        last ``before + after + 1`` steps' errors.
        """
        before, after = halos
        n_steps = self.y.shape[0]
        self._serve("window sums")
        if self._ring is None:
            self._ring = np.zeros((before + after + 1, self._n_samples))
            self._next = 0
        if start != self._next:
            raise SettingsError(
                f"window sums from step {start} were requested after the windows up to step {self._next}; "
                "requests must come chunk after chunk"
            )
        kernels = self._kernels
        sums = np.empty((stop - start, self._n_samples))
        steps = np.array([start + after if start else 0, stop + after], dtype=np.int64)
        record, carried = (self._padded_input, self.y), (self._state, self._ring, totals)

        def block(sample_range):
            return kernels.window_sums(kernels.form, record, scale, steps, start + after, carried, sums, sample_range)

        self._raise_on_overflow(self._run(block))
        self._next = stop
        # A window's measured points: differences of the running count of measured steps.
        lo, hi = max(start - before, 0), min(stop + after, n_steps)
        counted = np.zeros(stop - start + before + after + 1)
        counted[lo - (start - before) + 1 : hi - (start - before) + 1] = ~np.isnan(self.y[lo:hi])
        counted = np.cumsum(counted)
        slots = before + after + 1
        return sums, counted[slots : slots + stop - start] - counted[: stop - start]

    def states_at(self, steps, scale, chunk_steps):
        """Every sample's state at each of ``steps`` (ascending) and the record totals (n_samples,): one pass.

        The states are (n_states, n_samples) arrays; the totals add every
        step's absolute error times ``scale``, as :meth:`window_sums` adds them.
        """
        kernels, n_samples = self._kernels, self._n_samples
        totals = np.zeros(n_samples)
        if kernels.states is not None:
            states = np.empty((len(steps), 1, n_samples))
            record = (self._padded_input, self.y)
            kept_steps = np.asarray(steps, dtype=np.int64)
            kernels.states(kernels.form, record, scale, kept_steps, self._state[0], totals, states[:, 0])
            return list(states), totals
        # Imported here: the noise floor's module imports scipy, which a run on a lag model does not need here.
        from ..noise import add_record_errors
        from ..windows import record_cuts

        # More states or dead times: the error rows of the engine's kernel, a chunk of time at a time.
        kept = {}
        for at, stop in record_cuts(steps, self.y.shape[0], chunk_steps):
            kept[at] = self._state.copy()
            errors = self.rows(at, stop)
            add_record_errors(totals, errors * scale if scale != 1.0 else errors)
        return [kept[at] for at in steps], totals

    def resume(self, state, start, halos, scale):
        """Stand where serving the window sums up to step ``start`` would have left the source.

        ``state`` holds every sample's state at step ``start - before``
        (``halos`` = (before, after)), where the window at ``start`` begins;
        from there the steps up to its end are simulated into the ring of
        the last window's errors (the sums of the windows before ``start`` are
        formed and dropped). Near the record's start it starts from step 0.
        """
        before, after = halos
        warm_from = start - before - after
        if warm_from > 0:
            self._state = np.array(state, dtype=float)
            self._ring = np.zeros((before + after + 1, self._n_samples))
            self._next = warm_from
        if start:
            self.window_sums(max(warm_from, 0), start, halos, np.zeros(self._n_samples), scale)

    def _serve(self, kind):
        """Refuse a request of another ``kind`` than the source has served: each keeps its own state."""
        if self._serving not in (None, kind):
            raise SettingsError(f"{kind} were requested after {self._serving}; a source gives one or the other")
        self._serving = kind

    def _run(self, block):
        """``block(sample_range)`` for every worker's range of samples, on the pool; their outcomes."""
        if self._pool is None:
            return [block(self._sample_ranges[0])]
        return list(self._pool.map(block, self._sample_ranges))

    @staticmethod
    def _raise_on_overflow(outcomes):
        for step, sample in outcomes:
            if step >= 0:
                which = f"sample {sample}" if sample >= 0 else "a sample"
                raise ModelError(f"the simulation of {which} is not finite at step {step}")

    def close(self):
        if self._pool is not None:
            self._pool.shutdown()


def _recursion(system):
    """The recursion (coefficients, delays, terms) of a discretised linear ``system``, as the kernels take it.

    The terms flag what the numpy path keeps: a coefficient that is not 0 for every sample.
    """
    n_states = system.c.shape[0]
    state_sources = [
        [system.phi[i, j] for j in range(n_states)] + [system.gamma_now[i], system.gamma_prev[i]]
        for i in range(n_states)
    ]
    state_terms = np.array(
        [[bool(np.any(term != 0)) for term in row] for row in state_sources], dtype=np.bool_
    ).reshape(n_states, n_states + 2)
    output_terms = np.array(
        [bool(np.any(system.c[i] != 0)) for i in range(n_states)]
        + [bool(np.any(system.feed_now != 0)), bool(np.any(system.feed_prev != 0))],
        dtype=np.bool_,
    )
    delays = system.delay_steps
    # One common dead time makes the delayed input one value per step, as in the numpy path.
    delays = np.ascontiguousarray(delays[:1] if np.all(delays == delays[0]) else delays, dtype=np.int64)
    coefficients = (system.phi, system.gamma_now, system.gamma_prev, system.c, system.feed_now, system.feed_prev)
    return coefficients, delays, (state_terms, output_terms)


def compiled():
    """Whether a kernel of the run has been compiled, or loaded from numba's cache, in this process already.

    False without numba. Before that, the first run either loads the kernels from the on-disk cache that an
    earlier process left (about a second) or compiles them (20-30 s of one core, once after dynia or numba
    changes); which of the two, only numba finds out.
    """
    return AVAILABLE and any(
        kernel.signatures
        for kernel in (
            simulate_lag,
            general_errors,
            lag_window_sums,
            general_window_sums,
            analyse_windows,
            analyse_windows_batched,
        )
    )
