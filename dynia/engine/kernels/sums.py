"""Compensated running window sums: each window's error sums from the last window's, a step in and a step out.

A window costs the same whatever its length: the step entering it is
added and the one leaving subtracted. A plain running sum would drift, and
lose the small errors to cancellation when a huge one leaves; these are
compensated (TwoSum, a double-double ``compensated`` = (high, low) per
sample, rounded once as high + low), summed afresh from the rows at every
chunk's first window (:func:`first_window`), slid on from there
(:func:`next_window`), and summed afresh from the rows, for one sample,
while an infinite error is in its window. The fused kernels
(:mod:`dynia.engine.kernels.fused`) keep the last window's errors in a ring
instead of rows and slide their sums by :func:`ring_sums`, with the same
operations in the same order, so both give the same sums bit for bit.
"""

import numpy as np

from .compile import inner, jit

__all__ = ["slide", "window_sum", "window_sums", "first_window", "next_window", "ring_sums"]


@inner
def _two_sum(a, b):
    """``a + b`` rounded, and its rounding error exactly (Knuth's TwoSum): the two add up to a + b exactly."""
    total = a + b
    virtual = total - a
    return total, (a - (total - virtual)) + (b - virtual)


@inner
def slide(high, low, entering, leaving):
    """The compensated window sum (``high``, ``low``) with one step entering and one leaving."""
    high, first = _two_sum(high, entering)
    high, second = _two_sum(high, -leaving)
    return high, low + (first + second)


@inner
def window_sum(rows, first, period, slots, s):
    """Sample s's compensated sum of ``slots`` rows from ``first`` (row indices modulo ``period``), as (high, low).

    Left to right, each step as :func:`first_window` adds it. A window
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


@inner
def window_sums(rows, measured, t, slots, present, running):
    """Window t's error sums and measured points: row t of given sums (``slots`` = 0), or the running sums.

    ``running`` = (compensated, total) carries the running sums from window
    t - 1 (``present`` its measured points), ``compensated`` = (high, low);
    ``total`` receives window t's.
    """
    compensated, total = running
    if slots == 0:
        return rows[t], measured[t]
    if t == 0:
        return total, first_window(rows, measured, slots, compensated, total)
    return total, next_window(rows, measured, t, slots, present, compensated, total)


@jit
def first_window(errors, measured, slots, compensated, total):
    """Window 0's sums from its rows: ``total`` = high + low, each a compensated sum; returns its measured points.

    ``compensated`` = (high, low), every sample's, is overwritten with window 0's.
    """
    high, low = compensated
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
    _round_sums(errors, 0, errors.shape[0], slots, compensated, total)
    return present


@jit
def next_window(errors, measured, t, slots, present, compensated, total):
    """Window t's sums from window t - 1's: its last row enters, row t - 1 leaves; returns its measured points."""
    high, low = compensated
    n_samples = errors.shape[1]
    entering, leaving = errors[t + slots - 1], errors[t - 1]
    for s in range(n_samples):
        high[s], low[s] = slide(high[s], low[s], entering[s], leaving[s])
    _round_sums(errors, t, errors.shape[0], slots, compensated, total)
    return present + measured[t + slots - 1] - measured[t - 1]


@inner
def _round_sums(rows, first, period, slots, compensated, total):
    """``total`` = high + low, rounded once; a sum gone non-finite is redone from the window's rows.

    An infinite error entering makes the compensation NaN, and one leaving
    would leave inf - inf: such a sample's window (rows ``first`` ..
    ``first + slots - 1`` modulo ``period``) is summed afresh by
    :func:`window_sum`, every window until the infinity has left.
    """
    high, low = compensated
    n_samples = total.shape[0]
    bad = 0
    for s in range(n_samples):
        total[s] = high[s] + low[s]
        bad += not np.isfinite(total[s])
    if bad:
        for s in range(n_samples):
            if not np.isfinite(total[s]):
                high[s], low[s] = window_sum(rows, first, period, slots, s)
                total[s] = high[s] + low[s]


@inner
def ring_sums(ring, lo, hi, e, first_end, error, compensated, sums):
    """Step e's ``error`` of samples [lo, hi) into the ``ring`` and the window sums ending at e.

    The ring (slots, n_samples) holds the errors of the last ``slots``
    steps, step e - slots's in row e % slots, which leaves as e enters.
    ``compensated`` = (high, low), the block's, carries the window sum
    ending at e - 1; the one ending at ``first_end`` is summed afresh from
    the ring, and the sum ending at e >= ``first_end`` goes, rounded, to
    ``sums[e - first_end, lo:hi]``.
    """
    high, low = compensated
    width = hi - lo
    slots = ring.shape[0]
    leaving = ring[e % slots, lo:hi]
    if e == first_end:
        # The first window is summed afresh, step by step from the oldest, as first_window sums it.
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
            high[s], low[s] = slide(high[s], low[s], error[s], leaving[s])
    for s in range(width):
        leaving[s] = error[s]  # the ring now holds the window ending at e
    if e >= first_end:
        _round_sums(ring[:, lo:hi], (e + 1) % slots, slots, slots, compensated, sums[e - first_end, lo:hi])
