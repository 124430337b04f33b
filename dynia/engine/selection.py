"""Choosing each window's behavioural set: the lowest costs, ties broken as a stable sort does."""

import numpy as np

__all__ = ["lowest_stable", "stable_rank_mask", "selected_columns", "lowest_weighted"]


def lowest_stable(values, count):
    """Columns of the ``count`` smallest entries of each row, ties broken by column.

    Returns (rows, count) column indices, ascending within each row: the
    first ``count`` of a stable ascending sort, as a set.
    """
    chosen = np.argpartition(values, count - 1, axis=1)[:, :count]
    threshold = np.take_along_axis(values, chosen, axis=1).max(axis=1, keepdims=True)
    tied = (values <= threshold).sum(axis=1) > count
    if tied.any():
        chosen[tied] = selected_columns(stable_rank_mask(values[tied], 0, count), count)
    return np.sort(chosen, axis=1)


def stable_rank_mask(values, start, stop):
    """Mark, in each row, the entries whose stable ascending rank lies in [start, stop).

    The stable rank orders equal values by their column index, as a stable
    sort does. ``values`` is (rows, n); the mask has ``stop - start`` True per row.
    """
    part = np.partition(values, (start, stop - 1), axis=1)
    low = part[:, start, None]
    high = part[:, stop - 1, None]
    mask = (values > low) & (values < high)
    equal_low = values == low
    rank_low = (values < low).sum(axis=1, keepdims=True) + np.cumsum(equal_low, axis=1) - 1
    mask |= equal_low & (rank_low >= start) & (rank_low < stop)
    equal_high = (values == high) & (high != low)
    rank_high = (values < high).sum(axis=1, keepdims=True) + np.cumsum(equal_high, axis=1) - 1
    mask |= equal_high & (rank_high < stop)
    return mask


def selected_columns(mask, count):
    """Column indices of the True entries, (rows, count), ascending within each row."""
    return np.nonzero(mask)[1].reshape(mask.shape[0], count)


def lowest_weighted(cost, prior_weights, fraction):
    """Each row's lowest costs up to the first that brings their prior weight to ``fraction``.

    Parameters
    ----------
    cost : ndarray (rows, n_samples)
    prior_weights : ndarray (n_samples,), summing to 1
    fraction : float in (0, 1]

    Returns
    -------
    order : ndarray (rows, n_samples)
        Each row's samples by ascending cost (stable).
    behavioural : ndarray of bool (rows, n_samples)
        In ``order``'s positions: True for the behavioural samples.
    """
    order = np.argsort(cost, axis=1, kind="stable")
    reached = (np.cumsum(prior_weights[order], axis=1) < fraction).sum(axis=1, keepdims=True)
    return order, np.arange(order.shape[1]) <= np.minimum(reached, order.shape[1] - 1)
