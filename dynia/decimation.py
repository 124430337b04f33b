"""Decimation for plots: figures whose memory does not grow with the length of the record.

A figure is about a thousand pixels wide, so a record of 500 000 steps gains
nothing from drawing every step, yet matplotlib holds every vertex of a line
and every cell of a pcolormesh (several times over) while it renders: a
40 x 500 000 gradient image alone took 2 GB. Every plot of the package goes
through these helpers:

* :func:`envelope` thins a line to the minimum and maximum of each time
  bucket, so peaks, dips and the global extremes stay visible;
* :func:`decimated_columns` thins an image over time to the maximum of each
  bucket, so a short stretch of dark (concentrated) CLD gradient stays dark;

Below their thresholds the helpers return their input unchanged, so short
records look exactly as when drawn in full. Buckets are runs of consecutive
steps, all of one width except a shorter last one; the work is one reshape of
the whole buckets plus the last bucket on its own, without copying the data.
Time is finite and increasing; NaN in the values marks missing data.
"""

import numpy as np

from ._checks import whole_number
from .errors import DataError

__all__ = ["envelope", "decimated_columns"]

# Values of an image read per block by decimated_columns (32 MB of float64).
_BLOCK_VALUES = 2**22


def envelope(time, values, max_points=4000):
    """A line thinned to the minimum and maximum of each time bucket.

    Parameters
    ----------
    time : array_like, shape (n_steps,)
        Time of each value, increasing.
    values : array_like, shape (n_steps,)
        The series; NaN marks a missing value.
    max_points : int, default 4000
        Most points returned, at least 2.

    Returns
    -------
    time, values : ndarray, shape (m,)
        What to draw. When ``n_steps <= max_points`` these are the arguments
        themselves (as float arrays), so a short series is drawn exactly as
        before. Otherwise the steps are cut into at most ``max_points // 2``
        buckets and each gives two points, its minimum and its maximum, at the
        times they occur and in time order: ``m <= max_points`` and the
        series' global minimum and maximum are among the points. NaN are
        skipped within a bucket; a bucket without any value gives two NaN, so
        a gap that covers a whole bucket stays a gap in the line.

    Examples
    --------
    Ten steps, at most 6 points: three buckets of width 4, 4 and 2; the
    second bucket holds no value.

    >>> import numpy as np
    >>> values = np.array([0.0, 5.0, 1.0, 1.0, np.nan, np.nan, np.nan, np.nan, 2.0, -3.0])
    >>> time, drawn = envelope(np.arange(10.0), values, max_points=6)
    >>> time
    array([0., 1., 4., 4., 8., 9.])
    >>> drawn
    array([ 0.,  5., nan, nan,  2., -3.])
    """
    time = _series(time, "time")
    values = _series(values, "values")
    if time.size != values.size:
        raise DataError(f"time has {time.size} steps but values has {values.size}; they must match")
    max_points = whole_number(max_points, "max_points", minimum=2)
    if values.size <= max_points:
        return time, values
    width = _bucket_width(values.size, max_points // 2)
    low, low_at = _bucket_extreme(values, width, np.fmin)
    high, high_at = _bucket_extreme(values, width, np.fmax)
    low_first = low_at <= high_at
    steps = np.column_stack([np.where(low_first, low_at, high_at), np.where(low_first, high_at, low_at)])
    drawn = np.column_stack([np.where(low_first, low, high), np.where(low_first, high, low)])
    return time[steps.ravel()], drawn.ravel()


def decimated_columns(time, image, max_columns=2000):
    """An image over time thinned to the maximum of each time bucket, per row.

    The maximum, not the mean: in the CLD gradient image dark means a
    concentrated likelihood, and an informative stretch is often short. A
    bucket's mean would dilute a few dark steps among hundreds of pale ones
    until they vanish, and would lower the colour scale's top; the maximum
    keeps each row's darkest value, so the image's largest value (the top of
    the colour scale) is unchanged and short dark stretches stay visible,
    as the minimum and maximum of :func:`envelope` keep a line's peaks.

    Parameters
    ----------
    time : array_like, shape (n_steps,)
        Time of each column, increasing.
    image : array_like, shape (n_rows, n_steps)
        One column per time step; NaN marks a missing value. Anything with
        ``shape`` and numpy slicing, such as a :class:`dynia.io.arrays.DiskArray`,
        is read a block of columns at a time.
    max_columns : int, default 2000
        Most columns returned, at least 1.

    Returns
    -------
    time : ndarray, shape (m,)
        The centre of each bucket, midway between its first and last time
        (for ``shading="nearest"``).
    image : ndarray, shape (n_rows, m)
        The largest value of each row in each bucket, NaN skipped; NaN where
        a row has no value in the bucket. When ``n_steps <= max_columns`` the
        arguments themselves (as float arrays) are returned.

    Examples
    --------
    >>> import numpy as np
    >>> image = np.array([[0.0, 0.0, 0.0, 9.0, 0.0, 1.0, 2.0],
    ...                   [1.0, np.nan, 2.0, np.nan, np.nan, np.nan, 5.0]])
    >>> time, columns = decimated_columns(np.arange(7.0), image, max_columns=3)
    >>> time
    array([1., 4., 6.])
    >>> columns
    array([[ 0.,  9.,  2.],
           [ 2., nan,  5.]])
    """
    time = _series(time, "time")
    if not hasattr(image, "shape"):
        image = np.asarray(image, dtype=float)
    if len(image.shape) != 2 or image.shape[1] != time.size:
        raise DataError(f"image must be 2-D (n_rows, {time.size}), one column per time; got shape {image.shape}")
    max_columns = whole_number(max_columns, "max_columns", minimum=1)
    n_steps = time.size
    if n_steps <= max_columns:
        return time, np.asarray(image, dtype=float)
    width = _bucket_width(n_steps, max_columns)
    whole = n_steps // width * width
    # Whole buckets a block at a time, so that an image on disk (dynia.io.arrays) is never read whole; splitting
    # the last axis of a row-major block is a view, so an image in memory is not copied either.
    block = width * max(1, _BLOCK_VALUES // (width * max(image.shape[0], 1)))
    columns = np.concatenate(
        [
            np.fmax.reduce(
                np.asarray(image[:, start : min(start + block, whole)], dtype=float).reshape(image.shape[0], -1, width),
                axis=2,
            )
            for start in range(0, whole, block)
        ],
        axis=1,
    )
    starts = np.arange(0, n_steps, width)
    ends = np.minimum(starts + width, n_steps) - 1
    if whole < n_steps:
        columns = np.column_stack([columns, np.fmax.reduce(np.asarray(image[:, whole:], dtype=float), axis=1)])
    return (time[starts] + time[ends]) / 2, columns


def _series(values, name):
    array = np.asarray(values, dtype=float)
    if array.ndim != 1:
        raise DataError(f"{name} must be 1-D (n_steps,); got shape {array.shape}")
    return array


def _bucket_width(n_steps, max_buckets):
    """Smallest width that cuts ``n_steps`` into at most ``max_buckets`` buckets, the last one included."""
    return -(-n_steps // max_buckets)


def _bucket_extreme(values, width, extreme):
    """Per bucket, the ``extreme`` (np.fmin or np.fmax, which skip NaN) and the first step holding it."""
    whole = values.size // width * width
    buckets = [values[:whole].reshape(-1, width)]
    if whole < values.size:
        buckets.append(values[whole:][np.newaxis, :])
    found, steps = [], []
    start = 0
    for block in buckets:
        best = extreme.reduce(block, axis=1)
        # An all-NaN bucket matches nowhere and points at its first step; its value stays NaN.
        steps.append(start + np.arange(block.shape[0]) * width + (block == best[:, np.newaxis]).argmax(axis=1))
        found.append(best)
        start += block.size
    return np.concatenate(found), np.concatenate(steps)
