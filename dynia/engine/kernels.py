"""Compiled (numba) kernels of the engine: the numpy path's method, with running window sums, faster.

Three kernels cover the work of a :func:`dynia.run` with the ``"thesis"`` or
``"weighted"`` flavour:

- :func:`simulate_errors` advances every sample's discretised model (the
  recursion of the linear models, ``dynia.models.linear``) through a block of
  steps and writes the absolute errors against the measurement, time-major;
- :func:`simulate_window_sums` does the same fused with the window sums, a
  block of samples at a time through every step of a chunk, and writes only
  the sums: no error matrix goes through memory (the built-in linear models;
  other models hand their error rows to the next kernel);
- :func:`analyse_windows` forms each window's costs (from error rows by the
  same running sums, or from the sums given), selects its behavioural set
  and reads off limits, IC and gradient.

The window sums run: each window adds the step entering it and subtracts
the one leaving, so a window costs the same whatever its length. A plain
running sum would drift, and lose the small errors to cancellation when a
huge one leaves; this one is compensated (TwoSum, a double-double high/low
per sample, rounded once as high + low), summed afresh from its rows at
every chunk's first window, and summed afresh from the rows, for one
sample, while an infinite error is in its window. The pair holds the exact
sum unless its low part itself rounds, so high + low is in practice the
exact sum rounded once (every one checked on thesis example 1, and no bit
changes with the chunks: tests/test_running_sums.py), and it is always
within about one rounding of it, where the numpy path's left-to-right
sum (the readable reference, equal to the thesis port) is within 2n
roundings: the two agree to a relative ``2 (2n + 2) 2^-53`` on the costs,
not bit for bit, and give identical IC, limits and median wherever the
window's behavioural set is the same (tests/test_fast.py states and checks
that contract, and how often it holds). The fused kernel and the error-row
kernel perform the same operations in the same order, so they agree bit for
bit, and so do any worker counts (workers split samples, never a sum).

Everything else is the numpy path's arithmetic in the same order: products
and sums of the recursion term by term (LLVM does not fuse them into FMAs
without fast-math, which stays off), the behavioural set as the first
``count`` of a stable sort, the likelihood total summed in index order (as
:func:`dynia.engine.cld.likelihood` does with ``cumsum``) and the gradient
accumulated in index order (as ``bincount``). The order statistics are
found without sorting, which cannot change their value: a window's
behavioural threshold (and every Monte Carlo batch's) and the noise floor's
quantile by selection among the few costs within a bracket around the
previous window's, which a counting pass finds (moved outward when it
misses); the limits and median of the population's set, and the batches'
limits, by counting their members in a bitset of the samples' ranks,
sorted once per run (a small set's by selection).

The kernels release the GIL, so the engine's thread pool runs them on every
core. This module needs numba; :data:`AVAILABLE` says whether it imported.

A process compiles only what its runs use, since a newcomer's first run
waits for it: the lag models' kernels and the general ones are picked in
Python, not by a branch that would compile both; the Monte Carlo batches'
read-off compiles with ``ic_error`` only; helpers that only compiled code
calls have no Python wrappers; and no kernel assigns one array slice to
another, which would compile numba's shape check and its message. The
README's quick start compiles in about 20 CPU-s (``make bench``,
``cold-start``).
"""

import numpy as np

from ..errors import ModelError, SettingsError
from ..models.base import FLUSH_BELOW
from ..settings import check_dt, check_x0

try:
    import numba
except ImportError:  # the numpy path serves
    numba = None

AVAILABLE = numba is not None

__all__ = [
    "AVAILABLE",
    "compiled",
    "simulate_errors",
    "simulate_window_sums",
    "analyse_windows",
    "analyse_windows_batched",
    "parameter_ranks",
    "is_lag",
    "CompiledErrors",
]


def _jit(function, **options):
    if not AVAILABLE:
        return function
    try:
        # Compiled once, then loaded from numba's on-disk cache: next to this module, else the user's cache directory.
        return numba.njit(nogil=True, cache=True, **options)(function)
    except RuntimeError:  # neither is writable (a read-only install, no home): compile in every process instead
        return numba.njit(nogil=True, **options)(function)


def _inner(function):
    """:func:`_jit` for a helper that only compiled code calls: no wrappers for calls from Python.

    Each wrapper is compiled with the function; leaving them out takes about a seventh off a first run's compile.
    """
    return _jit(function, no_cpython_wrapper=True, no_cfunc_wrapper=True)


def is_lag(c, delays, state_terms, output_terms):
    """Whether a discretised linear model is a lag: one state that carries over, seen in the output, one dead time.

    Such models take the kernels' lag loops (``_simulate_lag``, ``_lag_window_sums``), the others the general ones.
    """
    return c.shape[0] == 1 and delays.shape[0] == 1 and bool(state_terms[0, 0]) and bool(output_terms[0])


@_inner
def _add_term(target, coefficient, source, first, start, stop):
    """target = coefficient*source (first term) or target += coefficient*source, over [start, stop)."""
    if first:
        for s in range(start, stop):
            target[s] = coefficient[s] * source[s]
    else:
        for s in range(start, stop):
            target[s] = target[s] + coefficient[s] * source[s]


@_inner
def _combine(target, coefficients, used, sources, start, stop):
    """target = sum of coefficients[term] * sources[term] over the used terms, in term order."""
    first = True
    for term in range(used.shape[0]):
        if used[term]:
            _add_term(target, coefficients[term], sources[term], first, start, stop)
            first = False
    if first:
        target[start:stop] = 0.0


def simulate_errors(
    phi,
    gamma_now,
    gamma_prev,
    c,
    feed_now,
    feed_prev,
    delays,
    state_terms,
    output_terms,
    padded_input,
    measured,
    first_step,
    last_step,
    state,
    errors,
    sample_start,
    sample_stop,
    outputs=False,
):
    """Advance samples [sample_start, sample_stop) through steps [first_step, first_step + m).

    ``state`` (n_states, n_samples) holds the state at ``first_step`` and is
    left at the state of the step after the block (not advanced past
    ``last_step``, the record's last step, where it could only overflow).
    ``errors`` (m, n_samples) receives ``|sim - measured|``, 0 where the
    measurement is NaN, or with ``outputs`` the outputs themselves.
    ``state_terms`` (n_states, n_states + 2) and ``output_terms`` (n_states + 2,) flag the terms the numpy path keeps
    (sources: the states, then u[k-d], then u[k-d-1]). The loop runs over
    time outside and samples inside, as the numpy path does, so each pass
    is a contiguous vector loop. Returns the first (step, sample) whose
    output is not finite, or (-1, -1). One state and one common dead time (the lag models) take
    ``_simulate_lag``, the others ``_general_errors``; chosen here, so that a run compiles
    only the one it uses.
    """
    # When every sample's pole underflows to 0 (a time constant far below dt) the general loop, which skips
    # unused terms as the numpy path does, gives the same numbers as the lag loop, which assumes the state
    # carries over.
    if is_lag(c, delays, state_terms, output_terms):
        return _simulate_lag(
            phi[0, 0],
            gamma_now[0],
            gamma_prev[0],
            c[0],
            feed_now,
            feed_prev,
            delays[0],
            state_terms[0],
            output_terms,
            padded_input,
            measured,
            first_step,
            last_step,
            state[0],
            errors,
            sample_start,
            sample_stop,
            outputs,
        )
    return _general_errors(
        phi,
        gamma_now,
        gamma_prev,
        c,
        feed_now,
        feed_prev,
        delays,
        state_terms,
        output_terms,
        padded_input,
        measured,
        first_step,
        last_step,
        state,
        errors,
        sample_start,
        sample_stop,
        outputs,
    )


@_jit
def _general_errors(
    phi,
    gamma_now,
    gamma_prev,
    c,
    feed_now,
    feed_prev,
    delays,
    state_terms,
    output_terms,
    padded_input,
    measured,
    first_step,
    last_step,
    state,
    errors,
    sample_start,
    sample_stop,
    outputs,
):
    """:func:`simulate_errors` of any linear model but the lag models: term by term, as the numpy path."""
    n_states, n_samples = c.shape
    lo, hi = sample_start, sample_stop
    output_coefficients, state_coefficients = _coefficient_tables(phi, gamma_now, gamma_prev, c, feed_now, feed_prev)
    sources = np.empty((n_states + 2, n_samples))
    upcoming = np.empty((n_states, n_samples))
    output = np.empty(n_samples)
    _copy_states(sources, state, n_states, lo, hi)
    bad_step, bad_sample = -1, -1
    for j in range(errors.shape[0]):
        k = first_step + j
        _delayed_inputs(sources[n_states], sources[n_states + 1], padded_input, delays, k, lo, hi)
        _combine(output, output_coefficients, output_terms, sources, lo, hi)
        _output_row(errors[j], output, measured[j], lo, hi, outputs)
        if bad_step < 0:
            for s in range(lo, hi):
                if not np.isfinite(output[s]):
                    bad_step, bad_sample = k, s
                    break
        if k == last_step:
            break
        for i in range(n_states):
            _combine(upcoming[i], state_coefficients[i], state_terms[i], sources, lo, hi)
        for i in range(n_states):
            for s in range(lo, hi):
                x = upcoming[i, s]
                sources[i, s] = x if abs(x) >= FLUSH_BELOW else 0.0
    _copy_states(state, sources, n_states, lo, hi)
    return bad_step, bad_sample


@_inner
def _copy_states(target, source, n_states, lo, hi):
    """target[:n_states, lo:hi] = source[:n_states, lo:hi], element by element: no shape check to compile."""
    for i in range(n_states):
        for s in range(lo, hi):
            target[i, s] = source[i, s]


# Samples a block of the fused kernel holds: its states, coefficients and sums (a dozen arrays of this length for one
# state, 96 kB) and its window's errors stay in the L2 cache while the block runs through every step of a chunk. Each
# step of a block has a fixed cost (views of the ring and the sums): on the bench's 20k samples, 1024 ran the
# first-order model 12 % and the second-order one 20 % faster than 256, whose arrays fit the L1 cache.
FUSED_BLOCK = 1024


def simulate_window_sums(
    phi,
    gamma_now,
    gamma_prev,
    c,
    feed_now,
    feed_prev,
    delays,
    state_terms,
    output_terms,
    padded_input,
    y,
    scale,
    steps,
    first_end,
    state,
    ring,
    sums,
    totals,
    sample_start,
    sample_stop,
):
    """Simulate, error and window-sum samples [sample_start, sample_stop) in blocks, fused: no error matrix.

    One state and one common dead time (the lag models) take ``_lag_window_sums``, the others
    ``_general_window_sums``; chosen here, so that a run compiles only the one it uses.

    Runs the window ends e in ``steps`` = (from, to): step e (while inside
    the record) is simulated as :func:`simulate_errors` does, term by term,
    and its absolute error (0 where ``y`` is NaN) times ``scale`` enters the
    sum of the window of ``slots = ring.shape[0]`` steps ending at e, while
    the error of step e - slots, kept in ``ring[(e - slots) % slots]``,
    leaves it; steps outside the record count 0. The sum of the window
    ending at e >= ``first_end`` goes to ``sums[e - first_end]``; the one
    ending at ``first_end`` is summed afresh from the ring, step by step, as
    ``_first_window`` sums a block's first window, and the next ones
    slide as ``_next_window`` slides, so the sums equal that kernel's on
    the same error rows bit for bit. ``state`` (n_states, n_samples) and
    ``ring`` (slots, n_samples) carry over between calls; ``totals``
    (n_samples,) adds every simulated step's error in time order, as
    :func:`dynia.engine.noise.add_record_errors` does. Returns the first
    (step, sample) whose output is not finite, or (-1, -1).
    """
    if is_lag(c, delays, state_terms, output_terms):
        return _lag_window_sums(
            (phi[0, 0], gamma_now[0], gamma_prev[0], c[0], feed_now, feed_prev),
            delays[0],
            state_terms[0],
            output_terms,
            padded_input,
            y,
            scale,
            steps,
            first_end,
            state[0],
            ring,
            sums,
            totals,
            sample_start,
            sample_stop,
        )
    return _general_window_sums(
        phi,
        gamma_now,
        gamma_prev,
        c,
        feed_now,
        feed_prev,
        delays,
        state_terms,
        output_terms,
        padded_input,
        y,
        scale,
        steps,
        first_end,
        state,
        ring,
        sums,
        totals,
        sample_start,
        sample_stop,
    )


@_jit
def _lag_window_sums(
    coefficients,
    delay,
    state_terms,
    output_terms,
    padded_input,
    y,
    scale,
    steps,
    first_end,
    state,
    ring,
    sums,
    totals,
    sample_start,
    sample_stop,
):
    """:func:`simulate_window_sums` of a lag model, block by block (:func:`_fused_lag_block`)."""
    bad_step, bad_sample = -1, -1
    for block_start in range(sample_start, sample_stop, FUSED_BLOCK):
        block_stop = min(block_start + FUSED_BLOCK, sample_stop)
        step, sample = _fused_lag_block(
            coefficients,
            delay,
            state_terms,
            output_terms,
            padded_input,
            y,
            scale,
            steps,
            first_end,
            state,
            ring,
            sums,
            totals,
            block_start,
            block_stop,
        )
        if step >= 0 and (bad_step < 0 or step < bad_step):
            bad_step, bad_sample = step, sample
    return bad_step, bad_sample


@_jit
def _general_window_sums(
    phi,
    gamma_now,
    gamma_prev,
    c,
    feed_now,
    feed_prev,
    delays,
    state_terms,
    output_terms,
    padded_input,
    y,
    scale,
    steps,
    first_end,
    state,
    ring,
    sums,
    totals,
    sample_start,
    sample_stop,
):
    """:func:`simulate_window_sums` of any other linear model, block by block (:func:`_fused_block`)."""
    n_states = c.shape[0]
    bad_step, bad_sample = -1, -1
    for block_start in range(sample_start, sample_stop, FUSED_BLOCK):
        block_stop = min(block_start + FUSED_BLOCK, sample_stop)
        step, sample = _fused_block(
            phi,
            gamma_now,
            gamma_prev,
            c,
            feed_now,
            feed_prev,
            delays,
            state_terms,
            output_terms,
            padded_input,
            y,
            scale,
            steps,
            first_end,
            state,
            ring,
            sums,
            totals,
            block_start,
            block_stop,
            n_states,
        )
        if step >= 0 and (bad_step < 0 or step < bad_step):
            bad_step, bad_sample = step, sample
    return bad_step, bad_sample


@_inner
def _fused_block(
    phi,
    gamma_now,
    gamma_prev,
    c,
    feed_now,
    feed_prev,
    delays,
    state_terms,
    output_terms,
    padded_input,
    y,
    scale,
    steps,
    first_end,
    state,
    ring,
    sums,
    totals,
    lo,
    hi,
    n_states,
):
    """:func:`simulate_window_sums` for one block of samples [lo, hi), held in block-local arrays."""
    width = hi - lo
    last_step = y.shape[0] - 1
    output_coefficients, state_coefficients = _coefficient_tables(
        phi[:, :, lo:hi], gamma_now[:, lo:hi], gamma_prev[:, lo:hi], c[:, lo:hi], feed_now[lo:hi], feed_prev[lo:hi]
    )
    block_delays = delays if delays.shape[0] == 1 else delays[lo:hi]
    sources = np.empty((n_states + 2, width))
    upcoming = np.empty((n_states, width))
    output = np.empty(width)
    error = np.empty(width)
    high, low = np.zeros(width), np.zeros(width)
    total = totals[lo:hi].copy()
    for i in range(n_states):
        for s in range(width):
            sources[i, s] = state[i, lo + s]
    bad_step, bad_sample = -1, -1
    for e in range(steps[0], steps[1]):
        if e <= last_step:
            tables = (output_coefficients, state_coefficients, output_terms, state_terms)
            bad = _fused_step(tables, sources, upcoming, output, error, padded_input, block_delays, y, e, scale, total)
            if bad >= 0 and bad_step < 0:
                bad_step, bad_sample = e, lo + bad
        else:
            error[:] = 0.0
        _fused_sums(ring, lo, hi, e, first_end, error, high, low, sums)
    for s in range(width):
        for i in range(n_states):
            state[i, lo + s] = sources[i, s]
        totals[lo + s] = total[s]
    return bad_step, bad_sample


@_inner
def _fused_lag_block(
    coefficients,
    delay,
    state_terms,
    output_terms,
    padded_input,
    y,
    scale,
    steps,
    first_end,
    state,
    ring,
    sums,
    totals,
    lo,
    hi,
):
    """:func:`_fused_block` for one state and one common dead time (the lag models): one loop per step.

    The recursion's arithmetic is :func:`_simulate_lag`'s, the sums'
    :func:`_fused_sums`'; each step's samples run through a few vector loops
    (:func:`_lag_samples`) that simulate, err, slide the window sum and
    write it, except at the block's first window and past the record, which
    take :func:`_fused_sums`.
    """
    flags = (output_terms[1], output_terms[2], state_terms[1], state_terms[2])
    width = hi - lo
    slots = ring.shape[0]
    last_step = y.shape[0] - 1
    x_block, total = state[lo:hi].copy(), totals[lo:hi].copy()
    error, high, low = np.zeros(width), np.zeros(width), np.zeros(width)
    bad_step, bad_sample = -1, -1
    for e in range(steps[0], steps[1]):
        if e > last_step:
            error[:] = 0.0
            _fused_sums(ring, lo, hi, e, first_end, error, high, low, sums)
            continue
        now = padded_input[max(e - delay, -1) + 1]
        previous = padded_input[max(e - delay - 1, -1) + 1]
        y_e = y[e]
        missing = np.isnan(y_e)
        advance = e != last_step
        sliding = e > first_end
        leaving = ring[e % slots, lo:hi]
        window = sums[e - first_end, lo:hi] if sliding else error
        inputs = (now, previous, y_e, missing, advance, sliding, scale)
        finite, bad = _lag_samples(coefficients, flags, inputs, lo, x_block, total, error, high, low, leaving, window)
        if not finite and bad_step < 0:
            bad_step = e
            for i in range(width):  # as in _simulate_lag: the sample is not known where y is missing
                if not np.isfinite(error[i]):
                    bad_sample = lo + i
                    break
        if not sliding:
            _fused_sums(ring, lo, hi, e, first_end, error, high, low, sums)
        elif bad:
            block_ring = ring[:, lo:hi]
            for i in range(width):
                if not np.isfinite(window[i]):
                    high[i], low[i] = _window_sum(block_ring, (e + 1) % slots, slots, slots, i)
                    window[i] = high[i] + low[i]
    # Element by element: a slice assignment would compile numba's shape check and its message, seconds of a first run.
    for i in range(width):
        state[lo + i] = x_block[i]
        totals[lo + i] = total[i]
    return bad_step, bad_sample


@_inner
def _lag_samples(coefficients, flags, inputs, lo, x_block, total, error, high, low, leaving, window):
    """One step of :func:`_fused_lag_block` for its samples: simulate, err, advance and, when sliding, slide.

    Returns whether every output was finite and how many window sums were not.
    """
    phi, gamma_now, gamma_prev, c, feed_now, feed_prev = coefficients
    now_out, prev_out, now_state, prev_state = flags
    now, previous, y_e, missing, advance, sliding, scale = inputs
    width = x_block.shape[0]
    hi = lo + width
    # Views from 0, so that every loop indexes with a counter LLVM knows to be non-negative: an index it cannot
    # (lo + i) gets numba's wraparound and the loop no longer vectorises.
    phi, gamma_now, gamma_prev = phi[lo:hi], gamma_now[lo:hi], gamma_prev[lo:hi]
    c, feed_now, feed_prev = c[lo:hi], feed_now[lo:hi], feed_prev[lo:hi]
    not_finite = 0
    for i in range(width):
        x = x_block[i]
        output = c[i] * x
        if now_out:
            output = output + feed_now[i] * now
        if prev_out:
            output = output + feed_prev[i] * previous
        not_finite += not np.isfinite(output)
        value = (0.0 if missing else abs(output - y_e)) * scale
        error[i] = value
        total[i] = total[i] + value
        if advance:
            x = phi[i] * x
            if now_state:
                x = x + gamma_now[i] * now
            if prev_state:
                x = x + gamma_prev[i] * previous
            x_block[i] = x if abs(x) >= FLUSH_BELOW else 0.0
    bad = 0
    if sliding:
        # Apart from the loop above, and the slide apart from the copies: LLVM vectorises a loop only while the arrays
        # it writes are few enough to check for overlap at run time (about four).
        for i in range(width):
            high[i], low[i] = _slide(high[i], low[i], error[i], leaving[i])
        for i in range(width):
            leaving[i] = error[i]
            window[i] = high[i] + low[i]
            bad += not np.isfinite(window[i])
    return not_finite == 0, bad


@_inner
def _fused_step(tables, sources, upcoming, output, error, padded_input, delays, y, e, scale, total):
    """Step e of a fused block: its scaled errors into ``error``, added to ``total``; the states advanced.

    The arithmetic of :func:`simulate_errors`, on block-local arrays.
    Returns the first sample (in the block) whose output is not finite, or -1.
    """
    output_coefficients, state_coefficients, output_terms, state_terms = tables
    n_states, width = upcoming.shape
    _delayed_inputs(sources[n_states], sources[n_states + 1], padded_input, delays, e, 0, width)
    _combine(output, output_coefficients, output_terms, sources, 0, width)
    _absolute_errors(error, output, y[e], 0, width)
    bad = -1
    for s in range(width):
        if not np.isfinite(output[s]):
            bad = s
            break
    if e != y.shape[0] - 1:  # not advanced past the record's last step, where it could only overflow
        for i in range(n_states):
            _combine(upcoming[i], state_coefficients[i], state_terms[i], sources, 0, width)
        for i in range(n_states):
            for s in range(width):
                x = upcoming[i, s]
                sources[i, s] = x if abs(x) >= FLUSH_BELOW else 0.0
    for s in range(width):
        error[s] = error[s] * scale
        total[s] = total[s] + error[s]
    return bad


@_inner
def _fused_sums(ring, lo, hi, e, first_end, error, high, low, sums):
    """Step e's ``error`` of samples [lo, hi) into the ring and the window sums ending at e (see the caller)."""
    width = hi - lo
    slots = ring.shape[0]
    leaving = ring[e % slots, lo:hi]
    if e == first_end:
        # The first window is summed afresh, step by step from the oldest, as _first_window sums it.
        high[:] = 0.0
        low[:] = 0.0
        for j in range(1, slots):
            row = ring[(e + j) % slots, lo:hi]
            for s in range(width):
                high[s], carried = _two_sum(high[s], row[s])
                low[s] += carried
        for s in range(width):
            high[s], carried = _two_sum(high[s], error[s])
            low[s] += carried
    elif e > first_end:
        for s in range(width):
            high[s], low[s] = _slide(high[s], low[s], error[s], leaving[s])
    for s in range(width):
        leaving[s] = error[s]  # the ring now holds the window ending at e
    if e >= first_end:
        _round_sums(ring[:, lo:hi], (e + 1) % slots, slots, slots, high, low, sums[e - first_end, lo:hi])


@_inner
def _coefficient_tables(phi, gamma_now, gamma_prev, c, feed_now, feed_prev):
    """The recursion's coefficients per source (the states, then u[k-d], then u[k-d-1]), every sample's.

    Returns the output's (n_states + 2, n_samples) and each next state's
    (n_states, n_states + 2, n_samples), the tables :func:`_combine` sums.
    """
    n_states, n_samples = c.shape
    output_coefficients = np.empty((n_states + 2, n_samples))
    state_coefficients = np.empty((n_states, n_states + 2, n_samples))
    # Element by element: row assignments would compile numba's shape check and its message, seconds of a first run.
    for s in range(n_samples):
        for i in range(n_states):
            output_coefficients[i, s] = c[i, s]
            for j in range(n_states):
                state_coefficients[i, j, s] = phi[i, j, s]
            state_coefficients[i, n_states, s] = gamma_now[i, s]
            state_coefficients[i, n_states + 1, s] = gamma_prev[i, s]
        output_coefficients[n_states, s] = feed_now[s]
        output_coefficients[n_states + 1, s] = feed_prev[s]
    return output_coefficients, state_coefficients


@_inner
def _delayed_inputs(now, previous, padded_input, delays, k, lo, hi):
    """u[k-d] into ``now`` and u[k-d-1] into ``previous`` for samples [lo, hi): one dead time, or one each."""
    if delays.shape[0] == 1:
        now[lo:hi] = padded_input[max(k - delays[0], -1) + 1]
        previous[lo:hi] = padded_input[max(k - delays[0] - 1, -1) + 1]
    else:
        for s in range(lo, hi):
            now[s] = padded_input[max(k - delays[s], -1) + 1]
            previous[s] = padded_input[max(k - delays[s] - 1, -1) + 1]


@_inner
def _output_row(row, output, y, lo, hi, outputs):
    """``row[lo:hi]`` = the ``output`` itself, or (without ``outputs``) its error (see :func:`_absolute_errors`)."""
    if outputs:
        for s in range(lo, hi):
            row[s] = output[s]
    else:
        _absolute_errors(row, output, y, lo, hi)


@_inner
def _absolute_errors(row, output, y, lo, hi):
    """``row[lo:hi]`` = |output - y|, or 0 where the measurement ``y`` is missing (NaN)."""
    if np.isnan(y):
        row[lo:hi] = 0.0
    else:
        for s in range(lo, hi):
            row[s] = abs(output[s] - y)


@_jit
def _simulate_lag(
    phi,
    gamma_now,
    gamma_prev,
    c,
    feed_now,
    feed_prev,
    delay,
    state_terms,
    output_terms,
    padded_input,
    measured,
    first_step,
    last_step,
    state,
    errors,
    lo,
    hi,
    outputs,
):
    """:func:`simulate_errors` for one state and one common dead time (the lag models), fused.

    The same products and sums in the same order, with each term present
    exactly when the general kernel uses it; one pass over the samples per
    step instead of one per term.
    """
    now_out, prev_out = output_terms[1], output_terms[2]
    now_state, prev_state = state_terms[1], state_terms[2]
    bad_step, bad_sample = -1, -1
    for j in range(errors.shape[0]):
        k = first_step + j
        now = padded_input[max(k - delay, -1) + 1]
        previous = padded_input[max(k - delay - 1, -1) + 1]
        y = measured[j]
        missing = np.isnan(y)
        row = errors[j]
        advance = k != last_step
        finite = True
        for s in range(lo, hi):
            x = state[s]
            output = c[s] * x
            if now_out:
                output = output + feed_now[s] * now
            if prev_out:
                output = output + feed_prev[s] * previous
            finite &= np.isfinite(output)
            row[s] = output if outputs else (0.0 if missing else abs(output - y))
            if advance:
                x = phi[s] * x
                if now_state:
                    x = x + gamma_now[s] * now
                if prev_state:
                    x = x + gamma_prev[s] * previous
                state[s] = x if abs(x) >= FLUSH_BELOW else 0.0
        if not finite and bad_step < 0:
            bad_step = k
            # The row holds the output or |output - y|, non-finite exactly where the
            # output is, unless y is missing; then the sample is not known (-1).
            for s in range(lo, hi):
                if not np.isfinite(row[s]):
                    bad_sample = s
                    break
        if not advance:
            break
    return bad_step, bad_sample


@_inner
def _select(values, length, k):
    """Rearrange ``values[:length]`` so that position k holds its k-th smallest; return it.

    Hoare partitioning around a median of three: equal values are spread
    over both sides, so long runs of ties (all samples simulating 0) stay
    O(length).
    """
    low, high = 0, length - 1
    while high > low:
        middle = (low + high) // 2
        a, b, d = values[low], values[middle], values[high]
        pivot = max(min(a, b), min(max(a, b), d))
        i, j = low, high
        while i <= j:
            while values[i] < pivot:
                i += 1
            while values[j] > pivot:
                j -= 1
            if i <= j:
                values[i], values[j] = values[j], values[i]
                i += 1
                j -= 1
        if k <= j:
            high = j
        elif k >= i:
            low = i
        else:
            break
    return values[k]


@_jit
def _candidates(cost, first, stride, count, bound, candidates):
    """Indices (ascending) of the samples first, first + stride, ... whose cost is at or below ``bound``.

    Written into ``candidates`` = (indices, their costs); returns how many. ``bound`` is a guess at
    or above the count-th smallest of these costs (a bracket's top): when
    at least ``count`` costs lie at or below it, the behavioural set is
    among them; otherwise (or when ``bound`` is NaN) every one of the
    samples is a candidate.
    """
    n = cost.shape[0]
    indices, costs = candidates
    found = 0
    if bound == bound:  # not NaN
        # Branch-free: every index is written, and kept (by counting it) when its cost is at or below the bound.
        for s in range(first, n, stride):
            indices[found] = s
            costs[found] = cost[s]
            found += cost[s] <= bound
    if found < count:
        found = 0
        for s in range(first, n, stride):
            indices[found] = s
            costs[found] = cost[s]
            found += 1
    return found


@_jit
def _select_near(values, n, k, bracket, scratch):
    """The k-th smallest (0-based) of ``values[:n]``, searched first within ``bracket`` = (low, high).

    A pass counts the values below and within the bracket; when the answer
    lies within, the few values there are copied to ``scratch`` and
    selected. Otherwise the bracket moves to the side of the answer,
    fourfold wider, up to ``_RETRIES - 1`` times, then reaches to that
    side's infinity, so the answer is always found (a NaN bracket starts
    there). Returns it and the values' density near it, the count within
    the last bracket over its width (0 when that is infinite or none), for
    :func:`_next_bracket`.
    """
    low, high = bracket
    if not low <= high:
        low, high = -np.inf, np.inf
    for attempt in range(_RETRIES + 1):
        below = 0
        inside = 0
        for i in range(n):
            below += values[i] < low
            inside += (values[i] >= low) & (values[i] <= high)
        if below <= k < below + inside:
            break
        width = max(high - low, _NARROWEST * max(abs(low), abs(high)))
        if k < below:
            low, high = (low - 4 * width if width > 0 and attempt < _RETRIES - 1 else -np.inf), low
        else:
            low, high = high, (high + 4 * width if width > 0 and attempt < _RETRIES - 1 else np.inf)
    density = inside / (high - low) if high > low else 0.0
    if inside > _CROWDED:
        # Every value within may be the same (samples that simulate alike, as all do once a record rests at zero).
        smallest, largest = np.inf, -np.inf
        for i in range(n):
            within = (values[i] >= low) & (values[i] <= high)
            smallest = min(smallest, values[i] if within else np.inf)
            largest = max(largest, values[i] if within else -np.inf)
        if smallest == largest:
            return smallest, density
    taken = 0
    # Branch-free: every value is written, and kept (by counting it) when it is within the bracket.
    for i in range(n):
        scratch[taken] = values[i]
        taken += (values[i] >= low) & (values[i] <= high)
    return _select(scratch, taken, k - below), density


@_jit
def _behavioural(count, candidates, found, threshold, selected, chosen):
    """Indices (ascending) of the first ``count`` of a stable ascending sort of the costs, into ``selected``.

    ``candidates`` = (indices, costs): ``indices[:found]`` (ascending) hold
    every index of a cost at or below ``threshold``, the count-th smallest
    cost, and ``costs`` theirs, side by side so that they are read in order.
    Of the costs tied with the threshold, the lowest indices are taken.
    Their costs go to ``chosen``, in the same order.
    """
    indices, costs = candidates
    below = 0
    for i in range(found):
        below += costs[i] < threshold
    ties = count - below
    taken = 0
    for i in range(found):
        s = indices[i]
        value = costs[i]
        if value < threshold or (value == threshold and ties > 0):
            if value == threshold:
                ties -= 1
            selected[taken] = s
            chosen[taken] = value
            taken += 1
            if taken == count:  # the costs below the threshold are among them: no later one can be
                break


@_jit
def _costs(sums, present, cost):
    """``cost`` = (sums / present)^2, a window's costs.

    A pass of its own, which vectorises: it streams the sums from memory,
    and the passes that pick candidates then read the costs from cache.
    """
    for s in range(cost.shape[0]):
        mae = sums[s] / present
        cost[s] = mae * mae


@_inner
def _stable_argsort(values, length, order, buffer):
    """``order[:length]`` = stable ascending argsort of ``values[:length]`` (bottom-up merge sort)."""
    for i in range(length):
        order[i] = i
    width = 1
    source, target = order, buffer
    while width < length:
        for start in range(0, length, 2 * width):
            middle = min(start + width, length)
            stop = min(start + 2 * width, length)
            i, j, out = start, middle, start
            while i < middle and j < stop:
                if values[source[j]] < values[source[i]]:
                    target[out] = source[j]
                    j += 1
                else:
                    target[out] = source[i]
                    i += 1
                out += 1
            while i < middle:
                target[out] = source[i]
                i += 1
                out += 1
            while j < stop:
                target[out] = source[j]
                j += 1
                out += 1
        source, target = target, source
        width *= 2
    if source is not order:
        for i in range(length):
            order[i] = source[i]


@_inner
def _two_sum(a, b):
    """``a + b`` rounded, and its rounding error exactly (Knuth's TwoSum): the two add up to a + b exactly."""
    total = a + b
    virtual = total - a
    return total, (a - (total - virtual)) + (b - virtual)


@_inner
def _slide(high, low, entering, leaving):
    """The compensated window sum (``high``, ``low``) with one step entering and one leaving."""
    high, first = _two_sum(high, entering)
    high, second = _two_sum(high, -leaving)
    return high, low + (first + second)


@_inner
def _window_sum(rows, first, period, slots, s):
    """Sample s's compensated sum of ``slots`` rows from ``first`` (row indices modulo ``period``), as (high, low).

    Left to right, each step as ``_first_window`` adds it. A window
    holding an infinite (or NaN) error has no compensated sum: its plain sum
    is returned, as (inf or NaN, 0), which is what a left-to-right sum gives.
    """
    high, low = 0.0, 0.0
    for j in range(slots):
        high, error = _two_sum(high, rows[(first + j) % period, s])
        low += error
    if np.isfinite(high + low):
        return high, low
    plain = 0.0
    for j in range(slots):
        plain += rows[(first + j) % period, s]
    return plain, 0.0


@_inner
def _window_sums(rows, measured, t, slots, present, running):
    """Window t's error sums and measured points: row t of given sums (``slots`` = 0), or the running sums.

    ``running`` = (high, low, total) carries the running sums from window
    t - 1 (``present`` its measured points); ``total`` receives window t's.
    """
    high, low, total = running
    if slots == 0:
        return rows[t], measured[t]
    if t == 0:
        return total, _first_window(rows, measured, slots, high, low, total)
    return total, _next_window(rows, measured, t, slots, present, high, low, total)


@_jit
def _first_window(errors, measured, slots, high, low, total):
    """Window 0's sums from its rows: ``total`` = high + low, each a compensated sum; returns its measured points."""
    n_samples = errors.shape[1]
    present = 0.0
    high[:] = 0.0
    low[:] = 0.0
    for j in range(slots):
        present += measured[j]
        row = errors[j]
        for s in range(n_samples):
            high[s], error = _two_sum(high[s], row[s])
            low[s] += error
    _round_sums(errors, 0, errors.shape[0], slots, high, low, total)
    return present


@_jit
def _next_window(errors, measured, t, slots, present, high, low, total):
    """Window t's sums from window t - 1's: its last row enters, row t - 1 leaves; returns its measured points."""
    n_samples = errors.shape[1]
    entering, leaving = errors[t + slots - 1], errors[t - 1]
    for s in range(n_samples):
        high[s], low[s] = _slide(high[s], low[s], entering[s], leaving[s])
    _round_sums(errors, t, errors.shape[0], slots, high, low, total)
    return present + measured[t + slots - 1] - measured[t - 1]


@_inner
def _round_sums(rows, first, period, slots, high, low, total):
    """``total`` = high + low, rounded once; a sum gone non-finite is redone from the window's rows.

    An infinite error entering makes the compensation NaN, and one leaving
    would leave inf - inf: such a sample's window (rows ``first`` ..
    ``first + slots - 1`` modulo ``period``) is summed afresh by
    :func:`_window_sum`, every window until the infinity has left.
    """
    n_samples = total.shape[0]
    bad = 0
    for s in range(n_samples):
        total[s] = high[s] + low[s]
        bad += not np.isfinite(total[s])
    if bad:
        for s in range(n_samples):
            if not np.isfinite(total[s]):
                high[s], low[s] = _window_sum(rows, first, period, slots, s)
                total[s] = high[s] + low[s]


@_inner
def _read_off(cost, count, candidates, found, threshold, rules, positions, t, ic, ci, median, gradient, whole, work):
    """Behavioural set of one window's ``cost`` and what it gives: ``ic``, ``ci``, ``median`` and ``gradient`` at t.

    The set is the candidates (see :func:`_behavioural`) at or below
    ``threshold``, the count-th smallest cost, = (indices, costs), indices
    of ``cost`` and of the columns of ``columns``: a batch of samples is
    read off through candidates that are its members only. Without ``whole``
    (a batch's read-off, whose IC and limits alone are used) the gradient,
    the median and, for the thesis limits, the likelihoods are left alone.
    The median is read off as the limits are: the first sorted value whose
    CLD reaches 0.5 (``weighted``), or the value at sorted position
    ``(count - 1) // 2``, which is ``floor(0.5 (count - 1))``.
    ``rules`` is ``(columns, lows, highs, levels, weighted, ranks, ordered,
    bin_of)``, how every window is read off (see :func:`analyse_windows`;
    ``bin_of`` from :func:`_bin_indices`),
    ``positions`` the thesis limits' sorted positions (the population's or a
    batch's) and ``work`` the scratch arrays of :func:`_workspace`. Returns
    the smallest cost of the set (NaN where its likelihoods are not needed).
    """
    columns, lows, highs, levels, weighted, ranks, ordered, bin_of = rules
    scratch, selected, chosen, weights, values, order, buffer, words = work
    n_params = columns.shape[0]
    _behavioural(count, candidates, found, threshold, selected, chosen)
    # A batch's thesis limits are order statistics alone: its likelihoods are never used.
    smallest = _likelihood_weights(chosen, count, weights) if whole or weighted else np.nan
    # The walk over every sample's rank pays once the set is a 32nd of the samples.
    by_rank = whole and not weighted and 32 * count >= columns.shape[1]
    for p in range(n_params):
        if whole:
            _gradient_column(bin_of[p], selected, weights, count, gradient[p, :, t])
        if by_rank:
            ci[p, t, 0], ci[p, t, 1], median[p, t] = _ranked_order_statistics(
                ranks[p], ordered[p], selected, count, positions, words
            )
        else:
            for i in range(count):
                values[i] = columns[p, selected[i]]
            if weighted:
                _stable_argsort(values, count, order, buffer)
                for side in range(2):
                    ci[p, t, side] = _cld_read_off(values, weights, order, count, levels[side])
                if whole:
                    median[p, t] = _cld_read_off(values, weights, order, count, 0.5)
            else:
                ci[p, t, 0], ci[p, t, 1], middle = _order_statistics(values, count, positions, whole, scratch)
                if whole:
                    median[p, t] = middle
        ic[p, t] = 1 - (ci[p, t, 1] - ci[p, t, 0]) / (highs[p] - lows[p])
    return smallest


_ONE = np.uint64(1)


@_inner
def _popcount(word):
    """How many bits of the uint64 ``word`` are set (the bit-parallel count: pairs, nibbles, bytes, then a sum)."""
    word = word - ((word >> _ONE) & np.uint64(0x5555555555555555))
    word = (word & np.uint64(0x3333333333333333)) + ((word >> np.uint64(2)) & np.uint64(0x3333333333333333))
    word = (word + (word >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return np.int64((word * np.uint64(0x0101010101010101)) >> np.uint64(56))


@_jit
def _ranked_order_statistics(ranks, ordered, selected, count, positions, words):
    """:func:`_order_statistics` with the median, through the samples' ranks: one parameter's, of a set.

    ``ranks`` (n_samples,) is every sample's position in the stable sort of
    the parameter's values, ``ordered`` those values sorted: the set's
    k-th smallest value is ``ordered`` at its k-th smallest rank, found by
    setting the set's ranks as bits of ``words`` (zeros, (n_samples + 63)
    // 64 of them, cleared again) and counting them in order, a word at a
    time. The values selection finds, in time linear in the samples / 64
    rather than in the set with a large constant.
    """
    for i in range(count):
        rank = ranks[selected[i]]
        words[rank >> 6] |= _ONE << np.uint64(rank & 63)
    # Ascending targets: each walk goes on from the word the last one stopped in.
    lower, w, seen = _set_bit_at(words, positions[0], np.int64(0), np.int64(0))  # not literals: one compile
    middle, w, seen = _set_bit_at(words, (count - 1) // 2, w, seen)
    upper, w, seen = _set_bit_at(words, positions[1], w, seen)
    words[:] = 0
    return ordered[lower], ordered[upper], ordered[middle]


@_inner
def _set_bit_at(words, target, w, seen):
    """Where the ``target``-th set bit (0-based) of ``words`` lies, counted on from word ``w`` after ``seen`` bits.

    Returns its position, the word it lies in and the set bits before that word, for the next, later target.
    """
    while seen + _popcount(words[w]) <= target:
        seen += _popcount(words[w])
        w += 1
    word = words[w]
    counted = seen
    bit = 0
    while True:
        if (word >> np.uint64(bit)) & _ONE:
            if counted == target:
                return 64 * w + bit, w, seen
            counted += 1
        bit += 1


@_inner
def _likelihood_weights(chosen, count, weights):
    """``weights[:count]`` = the normalised likelihoods 1 - cost of the set's costs ``chosen``; returns the smallest.

    As :func:`dynia.engine.cld.likelihood`: shifted to be non-negative when a
    cost exceeds 1, equal when they all vanish, then divided by their total
    summed in index order.
    """
    lowest = np.inf
    smallest = np.inf
    for i in range(count):
        smallest = min(smallest, chosen[i])
        weights[i] = 1.0 - chosen[i]
        lowest = min(lowest, weights[i])
    if lowest < 0:
        for i in range(count):
            weights[i] = weights[i] - lowest
    weight_total = 0.0
    for i in range(count):
        weight_total += weights[i]
    if weight_total == 0:
        for i in range(count):
            weights[i] = 1.0
        weight_total = float(count)
    for i in range(count):
        weights[i] = weights[i] / weight_total
    return smallest


@_inner
def _gradient_column(bin_of, selected, weights, count, column):
    """The likelihood mass of the set ``selected[:count]`` in each bin (``bin_of``, every sample's), into ``column``."""
    column[:] = 0.0
    for i in range(count):
        column[bin_of[selected[i]]] += weights[i]


@_inner
def _bin_indices(columns, lows, highs, bins):
    """Every sample's bin of the gradient map, per parameter: which of ``bins`` equal bins of [low, high] holds it."""
    n_params, n_samples = columns.shape
    bin_of = np.empty((n_params, n_samples), dtype=np.int64)
    for p in range(n_params):
        low, high = lows[p], highs[p]
        for s in range(n_samples):
            which = int((columns[p, s] - low) / (high - low) * bins)
            bin_of[p, s] = min(max(which, 0), bins - 1)
    return bin_of


@_inner
def _cld_read_off(values, weights, order, count, level):
    """The first of ``values[:count]``, sorted by ``order``, whose cumulative likelihood reaches ``level``."""
    cumulative = 0.0
    reached = 0
    for i in range(count):
        cumulative += weights[order[i]]
        if cumulative < level:
            reached += 1
    return values[order[min(reached, count - 1)]]


# Order statistics this close to either end (a batch's limits: the 3rd smallest and 4th largest of 50 at 90 %)
# are kept in a short sorted buffer in one pass, cheaper than a selection's unpredictable branches.
_FEW = 12


@_inner
def _keep(buffer, size, seen, value, larger):
    """Insert ``value``, the ``seen``-th value met, into ``buffer[:size]``: the smallest met so far, ascending.

    With ``larger`` the largest met so far, descending. Returns nothing; the
    value is dropped when the buffer is full and it would come last.
    """
    if seen < size or (value > buffer[size - 1] if larger else value < buffer[size - 1]):
        j = min(seen, size - 1) - 1
        while j >= 0 and (buffer[j] < value if larger else buffer[j] > value):
            buffer[j + 1] = buffer[j]
            j -= 1
        buffer[j + 1] = value


@_inner
def _extreme_order_statistics(values, count, first, last, scratch):
    """The ``first``-th smallest and ``last``-th smallest of ``values[:count]``, both within ``_FEW`` of an end.

    One pass keeps the first + 1 smallest values (ascending, in
    ``scratch[:first + 1]``) and the count - last largest (descending, after
    them); returns (lower, upper, NaN) as :func:`_order_statistics` does.
    """
    small, large = first + 1, count - last
    low = scratch[:small]
    high = scratch[small : small + large]
    for i in range(count):
        _keep(low, small, i, values[i], False)
        _keep(high, large, i, values[i], True)
    return low[small - 1], high[large - 1], np.nan


@_inner
def _order_statistics(values, count, positions, with_median, scratch):
    """The ``positions[0]``-th and ``positions[1]``-th smallest of ``values[:count]``, and the median's if asked.

    The median's position is ``(count - 1) // 2``, between the two (NaN when
    not asked). Found in one copy, ``scratch``, so that ``values`` stays as
    it is: :func:`_select` leaves nothing larger before its answer and
    nothing smaller after, so the upper is searched after the lower only, and
    the median between the two.
    """
    first, last = positions[0], positions[1]
    if not with_median and first < _FEW and count - 1 - last < _FEW:
        return _extreme_order_statistics(values, count, first, last, scratch)
    for i in range(count):
        scratch[i] = values[i]
    lower = _select(scratch, count, first)
    upper = lower if last == first else _select(scratch[first + 1 :], count - first - 1, last - first - 1)
    middle = np.nan
    if with_median:
        k = (count - 1) // 2
        if k == first:
            middle = lower
        elif k == last:
            middle = upper
        else:
            middle = _select(scratch[first + 1 : last], last - first - 1, k - first - 1)
    return lower, upper, middle


# A window's behavioural threshold and quantile are searched first within a bracket around the previous
# window's (_select_near): its half-width thrice the last change, at least _NARROWEST of the value, at most
# _WIDEST, and holding about _BRACKET_RANKS values either side at the last window's density of values there.
# A miss moves the bracket and widens it fourfold, _RETRIES times, each a counting pass; the bench's record and
# thesis example 1 need 0.1 to 1 such moves a window on average.
_NARROWEST, _WIDEST = 0.002, 0.5
_BRACKET_RANKS = 128
_RETRIES = 3
# More values than this within a bracket are first checked for being all the same, which no selection then needs.
_CROWDED = 1024


@_jit
def _next_bracket(value, previous, density):
    """(low, high) in which to look first for the next window's value, from ``value`` and the last two.

    ``density`` is :func:`_select_near`'s, values per unit near ``value``.
    """
    change = abs(value - previous)
    width = max(3.0 * change, _NARROWEST * value) if change == change else _WIDEST * value
    if density > 0:
        width = min(width, _BRACKET_RANKS / density)
    width = min(width, _WIDEST * value)
    return value - width, value + width


@_jit
def analyse_windows_batched(
    rows,
    measured,
    m,
    slots,
    count,
    upper_position,
    columns,
    ranks,
    ordered,
    lows,
    highs,
    bins,
    positions,
    levels,
    weighted,
    min_points,
    ic,
    ci,
    median,
    gradient,
    extreme_costs,
    batch_counts,
    batch_positions,
    batch_ic,
    batch_ci,
):
    """:func:`analyse_windows`, and the IC and limits of every batch of samples from the same costs.

    Batch b of the ``B = batch_counts.size`` batches holds samples b, b + B,
    b + 2B, ...; its behavioural set is its ``batch_counts[b]`` lowest costs
    and ``batch_positions[b]`` (2,) its thesis limits' positions. Writes
    ``batch_ic`` (B, n_params, m) and ``batch_ci`` (B, n_params, m, 2), each
    batch bit-identical to :func:`analyse_windows` on that batch's samples
    alone (a sample's window sums do not depend on the others'); the window
    sums are formed once for all, and one pass over each window's costs finds
    the candidates of the behavioural set (the batches' among them) and of
    the noise floor's quantile.
    """
    n_batches = batch_counts.shape[0]
    window = _window_state(rows.shape[1], count, columns, lows, highs, bins, levels, weighted, ranks, ordered)
    cost, candidates, work, track = window[1], window[2], window[4], window[5]
    results = (ic, ci, median, gradient, extreme_costs)
    batches = _batch_state(batch_counts, batch_positions, ranks)
    batch_brackets = batches[5]
    present = 0.0
    for t in range(m):
        sums, present = _window_sums(rows, measured, t, slots, present, window[0])
        if present < min_points:
            _blank_window(t, results, batch_ic, batch_ci)
            continue
        _costs(sums, present, cost)
        # The candidates reach the bracket's top, and every batch's, so that they hold the batches' sets too.
        bound = track[1]
        for b in range(n_batches):
            bound = max(bound, batch_brackets[b, 1]) if batch_brackets[b, 1] == batch_brackets[b, 1] else bound
        found = _analyse_window(t, bound, count, upper_position, positions, window, results)
        _read_off_batches(cost, candidates, found, batches, window[3], t, batch_ic, batch_ci, median, gradient, work)


@_inner
def _window_state(n_samples, count, columns, lows, highs, bins, levels, weighted, ranks, ordered):
    """What :func:`_analyse_window` works in and carries from window to window, made once a block.

    (running, cost, candidates, rules, work, track): the running sums
    (high, low, total) of :func:`_window_sums`; a window's costs; its
    candidates (indices, costs); the read-off's rules (see
    :func:`_read_off`); its workspace (:func:`_workspace`); and ``track``,
    the brackets of the threshold and of the quantile (see
    :func:`_next_bracket`) and their last values, NaN before the first window.
    """
    running = (np.empty(n_samples), np.empty(n_samples), np.empty(n_samples))
    candidates = (np.empty(n_samples, dtype=np.int64), np.empty(n_samples))
    rules = (columns, lows, highs, levels, weighted, ranks, ordered, _bin_indices(columns, lows, highs, bins))
    track = np.full(6, np.nan)
    return running, np.empty(n_samples), candidates, rules, _workspace(n_samples, count), track


@_inner
def _analyse_window(t, bound, count, upper_position, positions, window, results):
    """Window t from its costs (``window[1]``): its behavioural set, read-off and extreme costs, into ``results``.

    The candidates are every cost up to ``bound`` (at least the bracket's
    top, which the threshold is searched within); ``window`` is
    :func:`_window_state`'s, whose brackets move on. Returns how many
    candidates there were.
    """
    _, cost, candidates, rules, work, track = window
    ic, ci, median, gradient, extreme_costs = results
    scratch = work[0]
    found = _candidates(cost, 0, 1, count, bound, candidates)
    threshold, density = _select_near(candidates[1], found, count - 1, (track[0], track[1]), scratch)
    smallest = _read_off(
        cost, count, candidates, found, threshold, rules, positions, t, ic, ci, median, gradient, True, work
    )
    upper, quantile_density = _select_near(cost, cost.shape[0], upper_position, (track[2], track[3]), scratch)
    track[0], track[1] = _next_bracket(threshold, track[4], density)
    track[2], track[3] = _next_bracket(upper, track[5], quantile_density)
    track[4], track[5] = threshold, upper
    extreme_costs[0, t] = smallest
    extreme_costs[1, t] = threshold
    extreme_costs[2, t] = upper
    return found


@_inner
def _batch_state(counts, positions, ranks):
    """What :func:`_read_off_batches` carries from window to window, for batches of these ``counts``.

    (counts, positions, batch_of, member_candidates, member_found,
    brackets, last_thresholds, selected, at_rank): each sample's batch, the
    batches' candidates (indices, costs) and how many, each batch's bracket
    (see :func:`_next_bracket`, whose top bounds its candidates) and last
    threshold, its behavioural set, and the batch of the sample at every
    rank of every parameter (``ranks``, see :func:`parameter_ranks`).
    """
    n_batches = counts.shape[0]
    n_params, n_samples = ranks.shape
    batch_of = _batch_of(n_samples, n_batches)
    size = (n_samples + n_batches - 1) // max(n_batches, 1)
    at_rank = np.empty((n_params, n_samples if n_batches else 0), dtype=np.int64)
    for p in range(n_params):
        for s in range(at_rank.shape[1]):
            at_rank[p, ranks[p, s]] = batch_of[s]
    return (
        counts,
        positions,
        batch_of,
        (np.empty((n_batches, size), dtype=np.int64), np.empty((n_batches, size))),
        np.empty(n_batches, dtype=np.int64),
        np.full((n_batches, 2), np.nan),
        np.full(n_batches, np.nan),
        np.empty((n_batches, counts.max() if n_batches else 0), dtype=np.int64),
        at_rank,
    )


@_inner
def _read_off_batches(cost, candidates, found, batches, rules, t, batch_ic, batch_ci, median, gradient, work):
    """Every Monte Carlo batch's IC and limits at window t, from the population's ``candidates``.

    Each batch's threshold is searched as the population's is (within a
    bracket around its last, :func:`_select_near`); its thesis limits, order statistics of its
    set, are then found for all batches in one walk over each parameter's
    ranks from either end (:func:`_batch_limits`) when the sets are large,
    else by :func:`_read_off`, as are the weighted limits, read off each
    batch's CLD. ``batches`` is :func:`_batch_state`'s, updated here.
    """
    counts, positions, batch_of, batch_candidates, batch_found, brackets, last, selected, at_rank = batches
    lows, highs, weighted, ranks, ordered = rules[1], rules[2], rules[4], rules[5], rules[6]
    n_batches = counts.shape[0]
    # As for the population (see _read_off): the walk over the ranks pays once the sets are a 32nd of the samples.
    by_rank = not weighted and 32 * counts.sum() >= ranks.shape[1]
    _deal_candidates(candidates, found, batch_of, batch_candidates, batch_found)
    for b in range(n_batches):
        members = (batch_candidates[0][b], batch_candidates[1][b])
        bracket = (brackets[b, 0], brackets[b, 1])
        if batch_found[b] < counts[b]:
            batch_found[b] = _candidates(cost, b, n_batches, counts[b], bracket[1], members)
        threshold, density = _select_near(members[1], batch_found[b], counts[b] - 1, bracket, work[0])
        brackets[b, 0], brackets[b, 1] = _next_bracket(threshold, last[b], density)
        last[b] = threshold
        if not by_rank:
            _read_off(
                cost,
                counts[b],
                members,
                batch_found[b],
                threshold,
                rules,
                positions[b],
                t,
                batch_ic[b],
                batch_ci[b],
                median,
                gradient,
                False,
                work,
            )
        else:
            _behavioural(counts[b], members, batch_found[b], threshold, selected[b], work[2])
    if not by_rank:
        return
    limits = np.empty((n_batches, 2))
    for p in range(ranks.shape[0]):
        _batch_limits(selected, counts, positions, ranks[p], ordered[p], at_rank[p], work[7], limits)
        for b in range(n_batches):
            batch_ci[b, p, t, 0], batch_ci[b, p, t, 1] = limits[b, 0], limits[b, 1]
            batch_ic[b, p, t] = 1 - (limits[b, 1] - limits[b, 0]) / (highs[p] - lows[p])


@_inner
def _batch_limits(selected, counts, positions, ranks, ordered, at_rank, words, limits):
    """Every batch's thesis limits for one parameter, into ``limits`` (n_batches, 2): order statistics of its set.

    The sets' ranks are set as bits of ``words`` (zeros, cleared again),
    then walked from the lowest rank up until every batch has met its lower
    limit's position (``positions[b, 0]``), and from the highest down for the
    upper: near the ends for a confidence level of 90 %, a few hundred of
    the sets' members in all, where selecting in each set visits them all.
    ``at_rank`` holds the batch of the sample at every rank.
    """
    for b in range(counts.shape[0]):
        for i in range(counts[b]):
            rank = ranks[selected[b, i]]
            words[rank >> 6] |= _ONE << np.uint64(rank & 63)
    _walk_to_limits(words, at_rank, ordered, positions[:, 0], True, limits[:, 0])
    _walk_to_limits(words, at_rank, ordered, counts - 1 - positions[:, 1], False, limits[:, 1])
    words[:] = 0


@_inner
def _walk_to_limits(words, at_rank, ordered, targets, upward, limits):
    """``limits[b]`` = ``ordered`` at batch b's ``targets[b]``-th set rank (0-based) of ``words``, every batch.

    Counted from the lowest rank up (``upward``) or from the highest down,
    a word at a time, until every batch has met its target.
    """
    seen = np.zeros(targets.shape[0], dtype=np.int64)
    remaining = targets.shape[0]
    n_words = words.shape[0]
    for i in range(n_words):
        if remaining == 0:
            break
        w = i if upward else n_words - 1 - i
        word = words[w]
        for j in range(64 if word else 0):
            bit = j if upward else 63 - j
            if (word >> np.uint64(bit)) & _ONE:
                rank = 64 * w + bit
                b = at_rank[rank]
                if seen[b] == targets[b]:
                    limits[b] = ordered[rank]
                    remaining -= 1
                seen[b] += 1


@_inner
def _workspace(n_samples, count):
    """The scratch arrays of :func:`_read_off`, made once a block.

    (scratch, selected, chosen, weights, values, order, buffer, words):
    ``scratch`` (n_samples,) for the selections, then for ``count`` values:
    the behavioural set's indices, their costs, likelihood weights and one
    parameter's values, and the stable sort's order and its buffer; and
    ``words``, zero bits for every sample (:func:`_ranked_order_statistics`).
    """
    return (
        np.empty(n_samples),
        np.empty(count, dtype=np.int64),
        np.empty(count),
        np.empty(count),
        np.empty(count),
        np.empty(count, dtype=np.int64),
        np.empty(count, dtype=np.int64),
        np.zeros((n_samples + 63) // 64, dtype=np.uint64),
    )


@_inner
def _batch_of(n_samples, n_batches):
    """The batch of every sample: sample s belongs to batch s mod n_batches (none without batches)."""
    batch_of = np.empty(n_samples if n_batches else 0, dtype=np.int64)
    for first in range(0, batch_of.shape[0], max(n_batches, 1)):
        for b in range(min(n_batches, n_samples - first)):
            batch_of[first + b] = b
    return batch_of


@_inner
def _blank_window(t, results, batch_ic, batch_ci):
    """NaN for every result of window t, which has too few measured points."""
    ic, ci, median, gradient, extreme_costs = results
    ic[:, t] = np.nan
    ci[:, t, :] = np.nan
    median[:, t] = np.nan
    gradient[:, :, t] = np.nan
    extreme_costs[:, t] = np.nan
    for b in range(batch_ic.shape[0]):
        batch_ic[b, :, t] = np.nan
        batch_ci[b, :, t, :] = np.nan


@_inner
def _deal_candidates(candidates, found, batch_of, batch_candidates, batch_found):
    """Deal the population's ``candidates`` (indices, costs) to their batches: row b of ``batch_candidates``'s.

    The population's candidates are every cost at or below its bound: a batch
    with at least its count among them has its behavioural set and every tie
    there; one with fewer searches its members against its own bound, and all
    of them if that finds too few.
    """
    indices, costs = candidates
    batch_indices, batch_costs = batch_candidates
    batch_found[:] = 0
    for i in range(found):
        s = indices[i]
        b = batch_of[s]
        batch_indices[b, batch_found[b]] = s
        batch_costs[b, batch_found[b]] = costs[i]
        batch_found[b] += 1


@_jit
def analyse_windows(
    rows,
    measured,
    m,
    slots,
    count,
    upper_position,
    columns,
    ranks,
    ordered,
    lows,
    highs,
    bins,
    positions,
    levels,
    weighted,
    min_points,
    ic,
    ci,
    median,
    gradient,
    extreme_costs,
):
    """Analyse the m windows of a block; see :mod:`dynia.engine` for the method.

    ``rows`` (m + slots - 1, n_samples) and ``measured`` (m + slots - 1,)
    are the absolute errors and measured-point flags of the window inputs
    (row j + t belongs to slot j of window t), whose window sums are formed
    here by running sums (see the module documentation). With ``slots`` = 0
    they are the window sums themselves, ``rows`` (m, n_samples) (from
    :meth:`CompiledErrors.window_sums`), and each window's measured points
    ``measured`` (m,).
    ``columns`` (n_params, n_samples) are the samples' parameter values,
    ``ranks`` (n_params, n_samples) each sample's position in the stable
    sort of its row of ``columns`` and ``ordered`` (n_params, n_samples) the
    rows sorted (see :func:`parameter_ranks`).
    ``positions`` are the thesis limits' sorted positions, ``levels`` the
    weighted limits' CLD levels. Writes ``ic`` (n_params, m), ``ci``
    (n_params, m, 2), ``median`` (n_params, m), the CLD median read off as
    the limits are, ``gradient`` (n_params, bins, m) and
    ``extreme_costs`` (3, m), the smallest cost, the largest behavioural
    cost (the count-th smallest) and the ``upper_position``-th smallest
    (0-based, the noise floor's population quantile) of every window;
    windows with fewer than ``min_points`` measured points get NaN.
    """
    window = _window_state(rows.shape[1], count, columns, lows, highs, bins, levels, weighted, ranks, ordered)
    results = (ic, ci, median, gradient, extreme_costs)
    no_batches = (np.empty((0, 1, 1)), np.empty((0, 1, 1, 2)))
    present = 0.0
    for t in range(m):
        sums, present = _window_sums(rows, measured, t, slots, present, window[0])
        if present < min_points:
            _blank_window(t, results, *no_batches)
            continue
        _costs(sums, present, window[1])
        _analyse_window(t, window[5][1], count, upper_position, positions, window, results)


def parameter_ranks(columns):
    """``(ranks, ordered)`` of ``columns`` (n_params, n_samples), as :func:`analyse_windows` takes them.

    ``ordered`` holds each row sorted, ``ranks`` every sample's position in
    its row's stable sort (ties in the order of the samples).

    Examples
    --------
    >>> ranks, ordered = parameter_ranks(np.array([[0.3, 0.1, 0.3]]))
    >>> ranks.tolist(), ordered.tolist()
    ([[1, 0, 2]], [[0.1, 0.3, 0.3]])
    """
    order = np.argsort(columns, axis=1, kind="stable")
    ranks = np.empty(columns.shape, dtype=np.int64)
    np.put_along_axis(ranks, order, np.arange(columns.shape[1])[None, :], axis=1)
    return ranks, np.ascontiguousarray(np.take_along_axis(columns, order, axis=1))


# Samples the state pass of a lag model runs through every step at a time: their eight arrays (2 kB each) stay in
# the L1 cache.
_STATE_BLOCK = 256


@_jit
def _lag_states(coefficients, flags, delay, padded_input, y, scale, steps, state, totals, states):
    """One-state recursions with one dead time (the lags) through the record, without window sums: states and totals.

    Every sample runs from ``state`` (its state at step 0) to the end;
    ``states[j]`` receives its state at step ``steps[j]`` (ascending), and
    ``totals`` adds each step's absolute error (0 where ``y`` is missing)
    times ``scale``, in time order. The products and sums are those of the
    recursion of :mod:`dynia.engine.kernels`, term by term and in the same
    order, so the states and totals are bit for bit those of
    :func:`dynia.run`. A block of samples at a time runs through every step,
    in the L1 cache and vectorised: the least work of an analysis.
    """
    phi, gamma_now, gamma_prev, c, feed_now, feed_prev = coefficients
    now_out, prev_out, now_state, prev_state = flags
    n_samples = state.shape[0]
    for lo in range(0, n_samples, _STATE_BLOCK):
        hi = min(lo + _STATE_BLOCK, n_samples)
        x, total = state[lo:hi].copy(), totals[lo:hi].copy()
        # Views from the block's start: the loop over them vectorises.
        block_phi, block_now, block_previous = phi[lo:hi], gamma_now[lo:hi], gamma_prev[lo:hi]
        block_c, block_feed_now, block_feed_previous = c[lo:hi], feed_now[lo:hi], feed_prev[lo:hi]
        kept = 0
        for e in range(y.shape[0]):
            while kept < steps.shape[0] and steps[kept] == e:
                states[kept, lo:hi] = x
                kept += 1
            now = padded_input[max(e - delay, -1) + 1]
            previous = padded_input[max(e - delay - 1, -1) + 1]
            y_e = y[e]
            missing = np.isnan(y_e)
            for i in range(hi - lo):
                output = block_c[i] * x[i]
                if now_out:
                    output = output + block_feed_now[i] * now
                if prev_out:
                    output = output + block_feed_previous[i] * previous
                total[i] = total[i] + (0.0 if missing else abs(output - y_e)) * scale
                # Also past the record's last step, whose state is never kept.
                following = block_phi[i] * x[i]
                if now_state:
                    following = following + block_now[i] * now
                if prev_state:
                    following = following + block_previous[i] * previous
                x[i] = following if abs(following) >= FLUSH_BELOW else 0.0
        totals[lo:hi] = total


class CompiledErrors:
    """Absolute errors of a model's simulations, computed block by block by :func:`simulate_errors`.

    Or, fused, the window sums the errors make (:meth:`window_sums`, by
    :func:`simulate_window_sums`): what the engine's windows pass takes
    (``fused`` is True), so that no error matrix goes through memory.

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
        self._system = system
        n_states, n_samples = system.c.shape
        self._n_samples = n_samples
        coefficients = [
            [system.phi[i, j] for j in range(n_states)] + [system.gamma_now[i], system.gamma_prev[i]]
            for i in range(n_states)
        ]
        self._state_terms = np.array(
            [[bool(np.any(term != 0)) for term in row] for row in coefficients], dtype=np.bool_
        ).reshape(n_states, n_states + 2)
        self._output_terms = np.array(
            [bool(np.any(system.c[i] != 0)) for i in range(n_states)]
            + [bool(np.any(system.feed_now != 0)), bool(np.any(system.feed_prev != 0))],
            dtype=np.bool_,
        )
        self._padded_input = np.concatenate(([u[0] if x0 == "steady" else 0.0], u))
        self._state = system.steady_state * u[0] if x0 == "steady" else np.zeros((n_states, n_samples))
        self._state = np.ascontiguousarray(self._state, dtype=float)
        delays = system.delay_steps
        # One common dead time makes the delayed input one value per step, as in the numpy path.
        self._delays = np.ascontiguousarray(delays[:1] if np.all(delays == delays[0]) else delays, dtype=np.int64)
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
        system = self._system
        errors = np.empty((stop - first, self._n_samples))
        measured = np.ascontiguousarray(self.y[first:stop])

        def block(sample_range):
            return simulate_errors(
                system.phi,
                system.gamma_now,
                system.gamma_prev,
                system.c,
                system.feed_now,
                system.feed_prev,
                self._delays,
                self._state_terms,
                self._output_terms,
                self._padded_input,
                measured,
                first,
                self.y.shape[0] - 1,
                self._state,
                errors,
                *sample_range,
                outputs,
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
        what :func:`analyse_windows` forms from the error rows, and each
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
        system = self._system
        sums = np.empty((stop - start, self._n_samples))
        steps = np.array([start + after if start else 0, stop + after], dtype=np.int64)

        def block(sample_range):
            return simulate_window_sums(
                system.phi,
                system.gamma_now,
                system.gamma_prev,
                system.c,
                system.feed_now,
                system.feed_prev,
                self._delays,
                self._state_terms,
                self._output_terms,
                self._padded_input,
                self.y,
                scale,
                steps,
                start + after,
                self._state,
                self._ring,
                sums,
                totals,
                *sample_range,
            )

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
        system, n_samples = self._system, self._n_samples
        totals = np.zeros(n_samples)
        if is_lag(system.c, self._delays, self._state_terms, self._output_terms):
            states = np.empty((len(steps), 1, n_samples))
            _lag_states(
                (system.phi[0, 0], system.gamma_now[0], system.gamma_prev[0], system.c[0])
                + (system.feed_now, system.feed_prev),
                (bool(self._output_terms[1]), bool(self._output_terms[2]))
                + (bool(self._state_terms[0, 1]), bool(self._state_terms[0, 2])),
                int(self._delays[0]),
                self._padded_input,
                self.y,
                scale,
                np.asarray(steps, dtype=np.int64),
                self._state[0],
                totals,
                states[:, 0],
            )
            return list(states), totals
        # Imported here: the noise floor's module imports scipy, which a run on a lag model does not need here.
        from .noise import add_record_errors
        from .windows import record_cuts

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


def compiled():
    """Whether a kernel of the run has been compiled, or loaded from numba's cache, in this process already.

    False without numba. Before that, the first run either loads the kernels from the on-disk cache that an
    earlier process left (about a second) or compiles them (20-30 s of one core, once after dynia or numba
    changes); which of the two, only numba finds out.
    """
    return AVAILABLE and any(
        kernel.signatures
        for kernel in (
            _simulate_lag,
            _general_errors,
            _lag_window_sums,
            _general_window_sums,
            analyse_windows,
            analyse_windows_batched,
        )
    )
