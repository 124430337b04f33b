"""The linear models' simulation fused with the window sums: every step's errors summed as they are made.

A block of samples at a time runs through every step of a chunk,
simulating as :mod:`dynia.engine.kernels.simulate` does, and writes only
the window sums (:mod:`dynia.engine.kernels.sums`): no error matrix goes
through memory. The kernel and the error-row kernel followed by the
running sums perform the same operations in the same order, so they agree
bit for bit, and so do any worker counts (workers split samples, never a
sum). ``recursion`` and ``lag`` are the model's two forms (see
:mod:`dynia.engine.kernels.simulate`); ``record`` = (padded_input, y), the
input with the value before step 0 in front and the measured output;
``carried`` = (state, ring, totals), what carries over from one call to
the next: the state (n_states, n_samples), the last window's errors (slots,
n_samples) and every sample's total error (n_samples,).
"""

import numpy as np

from ...models.base import FLUSH_BELOW
from .compile import inner, jit
from .simulate import (
    absolute_errors,
    block_delays,
    coefficient_tables,
    combine,
    delayed_inputs,
    input_at,
    lag_following,
    lag_input_buffers,
    lag_inputs,
    lag_output,
)
from .sums import ring_sums, slide, window_sum

__all__ = ["FUSED_BLOCK", "LAG_BLOCK", "lag_window_sums", "general_window_sums"]

# Samples a block of the fused kernel holds: its states, coefficients and sums (a dozen arrays of this length for one
# state, 96 kB) and its window's errors stay in the L2 cache while the block runs through every step of a chunk. Each
# step of a block has a fixed cost (views of the ring and the sums): on the bench's 20k samples, 1024 ran the
# first-order model 12 % and the second-order one 20 % faster than 256, whose arrays fit the L1 cache (AMD EPYC).
FUSED_BLOCK = 1024
# A lag's block: its one pass a step over a dozen arrays runs faster where they stay in a 48 kB L1 cache. On an Intel
# Xeon (AVX-512, 2 MB L2) 512 swept the bench's first-order record 15-20 % faster than 1024 at n = 10 and 10 % at
# n = 100, and dynia.run took 3-11 % less CPU time in every one of six alternated runs; FOPDT with a dead time a
# sample (a lag too) 2.34-2.50 ns a sample-step against 2.47-2.67. The general kernels (second order) ran 2-7 %
# slower at 512, so they keep FUSED_BLOCK.
LAG_BLOCK = 512


@jit
def general_window_sums(recursion, record, scale, steps, first_end, carried, sums, samples):
    """Simulate, error and window-sum samples [lo, hi) = ``samples`` of any linear ``recursion``, in blocks, fused.

    Runs the window ends e in ``steps`` = (from, to): step e (while inside
    the record) is simulated as :func:`~dynia.engine.kernels.simulate.general_errors`
    does, term by term, and its absolute error (0 where y is NaN) times
    ``scale`` enters the sum of the window of ``slots = ring.shape[0]``
    steps ending at e, while the error of step e - slots, kept in
    ``ring[(e - slots) % slots]``, leaves it; steps outside the record count
    0. The sum of the window ending at e >= ``first_end`` goes to
    ``sums[e - first_end]``; the one ending at ``first_end`` is summed
    afresh from the ring, step by step, as
    :func:`~dynia.engine.kernels.sums.first_window` sums a block's first
    window, and the next ones slide as
    :func:`~dynia.engine.kernels.sums.next_window` slides, so the sums equal
    that kernel's on the same error rows bit for bit. ``totals`` adds every
    simulated step's error in time order, as
    :func:`dynia.engine.noise.add_record_errors` does. Returns the first
    (step, sample) whose output is not finite, or (-1, -1).
    """
    bad_step, bad_sample = -1, -1
    for block_start in range(samples[0], samples[1], FUSED_BLOCK):
        block_stop = min(block_start + FUSED_BLOCK, samples[1])
        step, sample = _fused_block(recursion, record, scale, steps, first_end, carried, sums, block_start, block_stop)
        if step >= 0 and (bad_step < 0 or step < bad_step):
            bad_step, bad_sample = step, sample
    return bad_step, bad_sample


@jit
def lag_window_sums(lag, record, scale, steps, first_end, carried, sums, samples):
    """:func:`general_window_sums` of a ``lag``, block by block: one loop per step; its state is (1, n_samples)."""
    state, ring, totals = carried
    row = (state[0], ring, totals)
    bad_step, bad_sample = -1, -1
    for block_start in range(samples[0], samples[1], LAG_BLOCK):
        block_stop = min(block_start + LAG_BLOCK, samples[1])
        block = (block_start, block_stop)
        delays = block_delays(lag[1], block_start, block_stop)
        step, sample = _fused_lag_block(lag, delays, record, scale, steps, first_end, row, sums, block)
        if step >= 0 and (bad_step < 0 or step < bad_step):
            bad_step, bad_sample = step, sample
    return bad_step, bad_sample


@inner
def _fused_block(recursion, record, scale, steps, first_end, carried, sums, lo, hi):
    """:func:`general_window_sums` for one block of samples [lo, hi), held in block-local arrays."""
    coefficients, delays, terms = recursion
    state_terms, output_terms = terms
    phi, gamma_now, gamma_prev, c, feed_now, feed_prev = coefficients
    state, ring, totals = carried
    n_states = c.shape[0]
    width = hi - lo
    last_step = record[1].shape[0] - 1
    output_coefficients, state_coefficients = coefficient_tables(
        (phi[:, :, lo:hi], gamma_now[:, lo:hi], gamma_prev[:, lo:hi], c[:, lo:hi], feed_now[lo:hi], feed_prev[lo:hi])
    )
    block_delays = delays if delays.shape[0] == 1 else delays[lo:hi]
    work = (np.empty((n_states + 2, width)), np.empty((n_states, width)), np.empty(width))
    sources = work[0]
    error = np.empty(width)
    compensated = (np.zeros(width), np.zeros(width))
    total = totals[lo:hi].copy()
    for i in range(n_states):
        for s in range(width):
            sources[i, s] = state[i, lo + s]
    bad_step, bad_sample = -1, -1
    for e in range(steps[0], steps[1]):
        if e <= last_step:
            tables = (output_coefficients, state_coefficients, output_terms, state_terms)
            bad = _fused_step(tables, work, error, record, block_delays, e, scale, total)
            if bad >= 0 and bad_step < 0:
                bad_step, bad_sample = e, lo + bad
        else:
            error[:] = 0.0
        ring_sums(ring, lo, hi, e, first_end, error, compensated, sums)
    for s in range(width):
        for i in range(n_states):
            state[i, lo + s] = sources[i, s]
        totals[lo + s] = total[s]
    return bad_step, bad_sample


@inner
def _fused_lag_block(lag, delays, record, scale, steps, first_end, carried, sums, block):
    """:func:`_fused_block` for a ``lag``, samples [lo, hi) = ``block``: one loop per step; ``carried``'s state is its
    one row, ``delays`` the dead time they share or theirs (see :func:`~dynia.engine.kernels.simulate.lag_inputs`).

    The recursion's arithmetic is
    :func:`~dynia.engine.kernels.simulate.simulate_lag`'s, the sums'
    :func:`~dynia.engine.kernels.sums.ring_sums`'; each step's samples run
    through a few vector loops (``_lag_samples``) that simulate, err, slide
    the window sum and write it, except at the block's first window and
    past the record, which take ``ring_sums``.
    """
    coefficients, _, flags = lag
    padded_input, y = record
    state, ring, totals = carried
    lo, hi = block
    width = hi - lo
    slots = ring.shape[0]
    last_step = y.shape[0] - 1
    x_block, total = state[lo:hi].copy(), totals[lo:hi].copy()
    error = np.zeros(width)
    compensated = (np.zeros(width), np.zeros(width))
    samples = (x_block, total, error)
    inputs = lag_input_buffers(delays, width)
    bad_step, bad_sample = -1, -1
    for e in range(steps[0], steps[1]):
        if e > last_step:
            error[:] = 0.0
            ring_sums(ring, lo, hi, e, first_end, error, compensated, sums)
            continue
        inputs = lag_inputs(padded_input, delays, e, inputs, e == steps[0])
        y_e = y[e]
        sliding = e > first_end
        leaving = ring[e % slots, lo:hi]
        window = sums[e - first_end, lo:hi] if sliding else error
        step = (y_e, np.isnan(y_e), e != last_step, sliding, scale)
        finite, bad = _lag_samples(coefficients, flags, (inputs, step), lo, samples, compensated, leaving, window)
        if not finite and bad_step < 0:
            bad_step = e
            for i in range(width):  # as in simulate_lag: the sample is not known where y is missing
                if not np.isfinite(error[i]):
                    bad_sample = lo + i
                    break
        if not sliding:
            ring_sums(ring, lo, hi, e, first_end, error, compensated, sums)
        elif bad:
            _sum_afresh(ring[:, lo:hi], (e + 1) % slots, compensated, window)
    # Element by element: a slice assignment would compile numba's shape check and its message, seconds of a first run.
    for i in range(width):
        state[lo + i] = x_block[i]
        totals[lo + i] = total[i]
    return bad_step, bad_sample


@inner
def _sum_afresh(block_ring, first, compensated, window):
    """The window sums that slid to a non-finite value, summed afresh from ``block_ring``'s rows from ``first``."""
    high, low = compensated
    slots = block_ring.shape[0]
    for i in range(window.shape[0]):
        if not np.isfinite(window[i]):
            high[i], low[i] = window_sum(block_ring, first, slots, slots, i)
            window[i] = high[i] + low[i]


@inner
def _lag_samples(coefficients, flags, inputs, lo, block, compensated, leaving, window):
    """One step of :func:`_fused_lag_block` for its samples: simulate, err, advance and, when sliding, slide.

    ``block`` = (x_block, total, error), the block's states, totals and
    this step's errors; ``compensated`` = (high, low), its window sums;
    ``inputs`` = ((u[k-d], u[k-d-1]), shared or one a sample (see
    :func:`~dynia.engine.kernels.simulate.input_at`), (y, missing, advance,
    sliding, scale)). Returns whether every output was finite and how many
    window sums were not.
    """
    phi, gamma_now, gamma_prev, c, feed_now, feed_prev = coefficients
    now_out, prev_out, now_state, prev_state = flags
    (now, previous), (y_e, missing, advance, sliding, scale) = inputs
    x_block, total, error = block
    high, low = compensated
    width = x_block.shape[0]
    hi = lo + width
    # Views from 0, so that every loop indexes with a counter LLVM knows to be non-negative: an index it cannot
    # (lo + i) gets numba's wraparound and the loop no longer vectorises.
    phi, gamma_now, gamma_prev = phi[lo:hi], gamma_now[lo:hi], gamma_prev[lo:hi]
    c, feed_now, feed_prev = c[lo:hi], feed_now[lo:hi], feed_prev[lo:hi]
    not_finite = 0
    for i in range(width):
        x = x_block[i]
        sample_inputs = (input_at(now, i), input_at(previous, i))
        output = lag_output(c[i], (feed_now[i], feed_prev[i]), x, sample_inputs, (now_out, prev_out))
        not_finite += not np.isfinite(output)
        value = (0.0 if missing else abs(output - y_e)) * scale
        error[i] = value
        total[i] = total[i] + value
        following = lag_following(phi[i], (gamma_now[i], gamma_prev[i]), x, sample_inputs, (now_state, prev_state))
        x_block[i] = following if advance else x
    bad = 0
    if sliding:
        # Apart from the loop above: LLVM vectorises a loop only while the arrays it writes are few enough to check
        # for overlap at run time (about four).
        for i in range(width):
            entering = error[i]
            slid_high, slid_low = slide(high[i], low[i], entering, leaving[i])
            high[i] = slid_high
            low[i] = slid_low
            leaving[i] = entering
            rounded = slid_high + slid_low
            window[i] = rounded
            bad += not np.isfinite(rounded)
    return not_finite == 0, bad


@inner
def _fused_step(tables, work, error, record, delays, e, scale, total):
    """Step e of a fused block: its scaled errors into ``error``, added to ``total``; the states advanced.

    The arithmetic of :func:`~dynia.engine.kernels.simulate.general_errors`,
    on block-local arrays: ``work`` = (sources, upcoming, output).
    Returns the first sample (in the block) whose output is not finite, or -1.
    """
    output_coefficients, state_coefficients, output_terms, state_terms = tables
    sources, upcoming, output = work
    padded_input, y = record
    n_states, width = upcoming.shape
    delayed_inputs((sources[n_states], sources[n_states + 1]), padded_input, delays, e, 0, width)
    combine(output, output_coefficients, output_terms, sources, 0, width)
    absolute_errors(error, output, y[e], 0, width)
    bad = -1
    for s in range(width):
        if not np.isfinite(output[s]):
            bad = s
            break
    if e != y.shape[0] - 1:  # not advanced past the record's last step, where it could only overflow
        for i in range(n_states):
            combine(upcoming[i], state_coefficients[i], state_terms[i], sources, 0, width)
        for i in range(n_states):
            for s in range(width):
                x = upcoming[i, s]
                sources[i, s] = x if abs(x) >= FLUSH_BELOW else 0.0
    for s in range(width):
        error[s] = error[s] * scale
        total[s] = total[s] + error[s]
    return bad
