"""The linear models' recursion, compiled: every sample's outputs or absolute errors, a block of steps at a time.

A discretised linear model (``dynia.models.linear``) reaches the kernels as
a ``recursion`` = (coefficients, delays, terms): ``coefficients`` =
(phi, gamma_now, gamma_prev, c, feed_now, feed_prev), every sample's
(phi (n_states, n_states, n_samples), gamma_now, gamma_prev and c
(n_states, n_samples), feed_now and feed_prev (n_samples,)); ``delays`` one
dead time in steps, or one per sample; ``terms`` = (state_terms,
output_terms), (n_states, n_states + 2) and (n_states + 2,), flagging the
terms the numpy path keeps (sources: the states, then u[k-d], then
u[k-d-1]). A lag model (one state that carries over, seen in the output)
reaches them as a ``lag`` = (coefficients, delays, flags): its one state's
coefficients (phi, gamma_now, gamma_prev and c of (n_samples,)), its dead
time or one per sample, as a recursion's, and (now_out, prev_out,
now_state, prev_state), whether u[k-d] and u[k-d-1] enter the output and
the state; its delays are an integer where every sample shares the dead
time, so that a run compiles the kernels for the kind it has, and the
inputs of a step are then two values, or else two arrays, one value a
sample (:func:`lag_inputs`).
Which form a model takes, and so which kernels, is decided in one place:
:func:`dynia.engine.kernels.driver.recursion_kernels`.

Products and sums run term by term in the numpy path's order (LLVM does
not fuse them into FMAs without fast-math, which stays off), so the
outputs equal ``model.simulate``'s bit for bit. The loops run over time
outside and samples inside, as the numpy path does, so each pass is a
contiguous vector loop.
"""

import numpy as np

from ...models.base import FLUSH_BELOW
from .compile import inner, jit

__all__ = [
    "general_errors",
    "simulate_lag",
    "lag_states",
    "combine",
    "coefficient_tables",
    "delayed_inputs",
    "delayed_input",
    "absolute_errors",
    "lag_output",
    "lag_following",
    "block_delays",
    "lag_input_buffers",
    "lag_inputs",
    "input_at",
]


@inner
def _add_term(target, coefficient, source, first, start, stop):
    """target = coefficient*source (first term) or target += coefficient*source, over [start, stop)."""
    if first:
        for s in range(start, stop):
            target[s] = coefficient[s] * source[s]
    else:
        for s in range(start, stop):
            target[s] = target[s] + coefficient[s] * source[s]


@inner
def combine(target, coefficients, used, sources, start, stop):
    """target = sum of coefficients[term] * sources[term] over the used terms, in term order."""
    first = True
    for term in range(used.shape[0]):
        if used[term]:
            _add_term(target, coefficients[term], sources[term], first, start, stop)
            first = False
    if first:
        target[start:stop] = 0.0


@jit
def general_errors(recursion, padded_input, measured, first_step, last_step, state, errors, samples, outputs):
    """Advance samples [lo, hi) = ``samples`` of any linear ``recursion`` through steps [first_step, first_step + m).

    ``state`` (n_states, n_samples) holds the state at ``first_step`` and is
    left at the state of the step after the block (not advanced past
    ``last_step``, the record's last step, where it could only overflow).
    ``errors`` (m, n_samples) receives ``|sim - measured|``, 0 where the
    measurement is NaN, or with ``outputs`` the outputs themselves; term by
    term, as the numpy path. Returns the first (step, sample) whose output
    is not finite, or (-1, -1).
    """
    coefficients, delays, terms = recursion
    state_terms, output_terms = terms
    n_states, n_samples = coefficients[3].shape
    lo, hi = samples
    output_coefficients, state_coefficients = coefficient_tables(coefficients)
    sources = np.empty((n_states + 2, n_samples))
    upcoming = np.empty((n_states, n_samples))
    output = np.empty(n_samples)
    _copy_states(sources, state, n_states, lo, hi)
    bad_step, bad_sample = -1, -1
    for j in range(errors.shape[0]):
        k = first_step + j
        delayed_inputs((sources[n_states], sources[n_states + 1]), padded_input, delays, k, lo, hi)
        combine(output, output_coefficients, output_terms, sources, lo, hi)
        _output_row(errors[j], output, measured[j], lo, hi, outputs)
        if bad_step < 0:
            for s in range(lo, hi):
                if not np.isfinite(output[s]):
                    bad_step, bad_sample = k, s
                    break
        if k == last_step:
            break
        for i in range(n_states):
            combine(upcoming[i], state_coefficients[i], state_terms[i], sources, lo, hi)
        for i in range(n_states):
            for s in range(lo, hi):
                x = upcoming[i, s]
                sources[i, s] = x if abs(x) >= FLUSH_BELOW else 0.0
    _copy_states(state, sources, n_states, lo, hi)
    return bad_step, bad_sample


@inner
def _copy_states(target, source, n_states, lo, hi):
    """target[:n_states, lo:hi] = source[:n_states, lo:hi], element by element: no shape check to compile."""
    for i in range(n_states):
        for s in range(lo, hi):
            target[i, s] = source[i, s]


@inner
def coefficient_tables(coefficients):
    """The recursion's coefficients per source (the states, then u[k-d], then u[k-d-1]), every sample's.

    Returns the output's (n_states + 2, n_samples) and each next state's
    (n_states, n_states + 2, n_samples), the tables :func:`combine` sums.
    """
    phi, gamma_now, gamma_prev, c, feed_now, feed_prev = coefficients
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


@inner
def delayed_inputs(delayed, padded_input, delays, k, lo, hi):
    """u[k-d] and u[k-d-1] into ``delayed`` = (now, previous) for samples [lo, hi): one dead time, or one each."""
    now, previous = delayed
    if delays.shape[0] == 1:
        now[lo:hi] = padded_input[max(k - delays[0], -1) + 1]
        previous[lo:hi] = padded_input[max(k - delays[0] - 1, -1) + 1]
    else:
        delayed_input(now[lo:hi], padded_input, delays[lo:hi], k)
        delayed_input(previous[lo:hi], padded_input, delays[lo:hi], k - 1)


@inner
def delayed_input(values, padded_input, delays, k):
    """u[k-d] into ``values``, one a sample, each of its own dead time ``delays`` (u[k-d-1] is this at k - 1)."""
    for s in range(values.shape[0]):
        values[s] = padded_input[max(k - delays[s], -1) + 1]


@inner
def _output_row(row, output, y, lo, hi, outputs):
    """``row[lo:hi]`` = the ``output`` itself, or (without ``outputs``) its error (see :func:`absolute_errors`)."""
    if outputs:
        for s in range(lo, hi):
            row[s] = output[s]
    else:
        absolute_errors(row, output, y, lo, hi)


@inner
def absolute_errors(row, output, y, lo, hi):
    """``row[lo:hi]`` = ``|output - y|``, or 0 where the measurement ``y`` is missing (NaN)."""
    if np.isnan(y):
        row[lo:hi] = 0.0
    else:
        for s in range(lo, hi):
            row[s] = abs(output[s] - y)


@inner
def lag_output(c, feeds, x, inputs, flags):
    """A lag's output ``c x``, plus ``feed_now u[k-d]`` and ``feed_prev u[k-d-1]`` where it has them, term by term.

    ``feeds`` = (feed_now, feed_prev), ``inputs`` = (u[k-d], u[k-d-1]), ``flags`` = (now_out, prev_out). Every
    coefficient is read and a term the model lacks dropped by a select: read under the flag's branch, a vectorised
    loop's loads become masked loads, slow on AMD processors (the fused kernel's simulation ran a third slower).
    """
    now, previous = inputs
    output = c * x
    with_now = output + feeds[0] * now
    output = with_now if flags[0] else output
    with_previous = output + feeds[1] * previous
    return with_previous if flags[1] else output


@inner
def lag_following(phi, gammas, x, inputs, flags):
    """A lag's next state ``phi x``, plus ``gamma_now u[k-d]`` and ``gamma_prev u[k-d-1]`` where it has them.

    As :func:`lag_output`: ``gammas`` = (gamma_now, gamma_prev), ``flags`` = (now_state, prev_state); a state
    below ``FLUSH_BELOW`` in magnitude is 0.
    """
    now, previous = inputs
    following = phi * x
    with_now = following + gammas[0] * now
    following = with_now if flags[0] else following
    with_previous = following + gammas[1] * previous
    following = with_previous if flags[1] else following
    return following if abs(following) >= FLUSH_BELOW else 0.0


@jit
def simulate_lag(lag, padded_input, measured, first_step, last_step, state, errors, samples, outputs):
    """:func:`general_errors` for a ``lag`` (one state, its dead times), fused; ``state`` is (1, n_samples).

    The same products and sums in the same order, with each term present
    exactly when the general kernel uses it; one pass over the samples per
    step instead of one per term. When every sample's pole underflows to 0
    (a time constant far below dt) the general loop, which skips unused
    terms as the numpy path does, gives the same numbers as this one, which
    assumes the state carries over.
    """
    coefficients, _, flags = lag
    phi, gamma_now, gamma_prev, c, feed_now, feed_prev = coefficients
    now_out, prev_out, now_state, prev_state = flags
    lo, hi = samples
    current = state[0]
    delays = block_delays(lag[1], lo, hi)
    inputs = lag_input_buffers(delays, hi - lo)
    bad_step, bad_sample = -1, -1
    for j in range(errors.shape[0]):
        k = first_step + j
        inputs = lag_inputs(padded_input, delays, k, inputs, j == 0)
        now, previous = inputs
        y = measured[j]
        missing = np.isnan(y)
        row = errors[j]
        advance = k != last_step
        finite = True
        for s in range(lo, hi):
            x = current[s]
            sample_inputs = (input_at(now, s - lo), input_at(previous, s - lo))
            output = lag_output(c[s], (feed_now[s], feed_prev[s]), x, sample_inputs, (now_out, prev_out))
            finite &= np.isfinite(output)
            row[s] = output if outputs else (0.0 if missing else abs(output - y))
            if advance:
                current[s] = lag_following(
                    phi[s], (gamma_now[s], gamma_prev[s]), x, sample_inputs, (now_state, prev_state)
                )
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


@inner
def block_delays(delays, lo, hi):
    """A lag's dead times for samples [lo, hi): the one every sample shares (an integer), or theirs, from lo.

    A lag carries one dead time as an integer and one a sample as an
    array, so that each kernel is compiled for the kind a run has: a shared
    dead time's loops keep its inputs scalars (see :func:`lag_inputs`).
    """
    if isinstance(delays, int):
        return delays
    return delays[lo:hi]


@inner
def lag_input_buffers(delays, width):
    """What :func:`lag_inputs` fills for ``width`` samples: two arrays for a dead time each, none for a shared one."""
    if isinstance(delays, int):
        return 0.0, 0.0
    return np.empty(width), np.empty(width)


@inner
def lag_inputs(padded_input, delays, k, buffers, first):
    """A lag's inputs at step k, (u[k-d], u[k-d-1]): two values, or two arrays of one value a sample.

    ``delays`` is the dead time every sample shares (an integer: two
    values), or one per sample (an array, from the block's first sample,
    :func:`block_delays`):
    ``buffers`` (:func:`lag_input_buffers`, last step's) are then refilled,
    u[k-d] gathered and u[k-d-1] taken from the last step's u[k-d] (gathered
    too at the ``first`` step). A loop over the samples reads either with
    :func:`input_at`.
    """
    if isinstance(delays, int):
        return padded_input[max(k - delays, -1) + 1], padded_input[max(k - delays - 1, -1) + 1]
    now, previous = buffers
    if first:
        delayed_input(previous, padded_input, delays, k - 1)
    else:
        now, previous = previous, now
    delayed_input(now, padded_input, delays, k)
    return now, previous


@inner
def input_at(values, i):
    """Sample i's value of a step's input (see :func:`lag_inputs`): the value every sample shares, or ``values[i]``."""
    if isinstance(values, float):
        return values
    return values[i]


# Samples the state pass of a lag model runs through every step at a time: their eight arrays (2 kB each) stay in
# the L1 cache.
_STATE_BLOCK = 256


@jit
def lag_states(lag, record, scale, steps, state, totals, states):
    """A ``lag``'s recursions through the ``record`` = (padded_input, y), without window sums: states and totals.

    Every sample runs from ``state`` (n_samples,), its state at step 0, to
    the end; ``states[j]`` receives its state at step ``steps[j]``
    (ascending), and ``totals`` adds each step's absolute error (0 where
    ``y`` is missing) times ``scale``, in time order. The products and sums
    are those of :func:`simulate_lag`, term by term and in the same order, so
    the states and totals are bit for bit those of :func:`dynia.run`. A
    block of samples at a time runs through every step, in the L1 cache and
    vectorised: the least work of an analysis.
    """
    n_samples = state.shape[0]
    for lo in range(0, n_samples, _STATE_BLOCK):
        hi = min(lo + _STATE_BLOCK, n_samples)
        _lag_states_block(lag, block_delays(lag[1], lo, hi), record, scale, steps, (state, totals, states), lo, hi)


@inner
def _lag_states_block(lag, delays, record, scale, steps, outputs, lo, hi):
    """:func:`lag_states` for samples [lo, hi), ``delays`` the dead time they share or theirs (:func:`block_delays`)."""
    coefficients, _, flags = lag
    padded_input, y = record
    state, totals, states = outputs
    phi, gamma_now, gamma_prev, c, feed_now, feed_prev = coefficients
    out_flags, state_flags = (flags[0], flags[1]), (flags[2], flags[3])
    x, total = state[lo:hi].copy(), totals[lo:hi].copy()
    # Views from the block's start: the loop over them vectorises.
    block_phi, block_now, block_previous = phi[lo:hi], gamma_now[lo:hi], gamma_prev[lo:hi]
    block_c, block_feed_now, block_feed_previous = c[lo:hi], feed_now[lo:hi], feed_prev[lo:hi]
    inputs = lag_input_buffers(delays, hi - lo)
    kept = 0
    for e in range(y.shape[0]):
        while kept < steps.shape[0] and steps[kept] == e:
            states[kept, lo:hi] = x
            kept += 1
        inputs = lag_inputs(padded_input, delays, e, inputs, e == 0)
        now, previous = inputs
        y_e = y[e]
        missing = np.isnan(y_e)
        for i in range(hi - lo):
            sample_inputs = (input_at(now, i), input_at(previous, i))
            output = lag_output(block_c[i], (block_feed_now[i], block_feed_previous[i]), x[i], sample_inputs, out_flags)
            total[i] = total[i] + (0.0 if missing else abs(output - y_e)) * scale
            # Also past the record's last step, whose state is never kept.
            x[i] = lag_following(block_phi[i], (block_now[i], block_previous[i]), x[i], sample_inputs, state_flags)
    totals[lo:hi] = total
