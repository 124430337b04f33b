"""Choosing each window's behavioural set: the lowest costs, ties broken as a stable sort does."""

import math

import numpy as np

__all__ = [
    "lowest_stable",
    "stable_rank_mask",
    "selected_columns",
    "lowest_weighted",
    "lowest_weighted_head",
    "alike_in_size",
]


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


def lowest_weighted_head(cost, prior_weights, fraction):
    """:func:`lowest_weighted`'s behavioural sets, in the same order, without sorting every cost.

    Each row's behavioural set is a head of its stable ascending order, and
    the cumulative weight of a head depends on the head alone; so a row is
    sorted only as far as its behavioural set reaches, and the rest of it is
    only partitioned off. ``prior_weights`` must be non-negative (so the
    cumulative weight never falls).

    Parameters
    ----------
    cost : ndarray (rows, n_samples)
    prior_weights : ndarray (n_samples,), summing to 1
    fraction : float in (0, 1]

    Returns
    -------
    order : ndarray (rows, k)
        k is the size of the largest behavioural set. Where ``behavioural``
        is True, :func:`lowest_weighted`'s ``order``; past a row's set,
        sample 0 as padding.
    behavioural : ndarray of bool (rows, k)
        The first k columns of :func:`lowest_weighted`'s ``behavioural``
        (every later one is False).

    Examples
    --------
    >>> cost = np.array([[0.5, 0.1, 0.1, 0.9], [0.3, 0.2, 0.1, 0.0]])
    >>> order, behavioural = lowest_weighted_head(cost, np.array([0.1, 0.2, 0.3, 0.4]), 0.35)
    >>> order.tolist(), behavioural.tolist()
    ([[1, 2], [3, 0]], [[True, True], [True, False]])
    """
    rows, n_samples = cost.shape
    # Every behavioural set holds at least fraction / (largest weight) samples, and about fraction * n_samples
    # when the weights are equal: a head twice the larger holds most sets at once.
    largest = prior_weights.max(initial=0.0)
    fewest = n_samples if largest <= 0 else math.ceil(min(fraction / largest, n_samples))
    count = min(n_samples, max(16, fewest + 1, 2 * math.ceil(fraction * n_samples)))
    if np.isnan(cost).any():  # a partition places NaNs in no stable order: sort them all
        count = n_samples
    heads, lengths = [None] * rows, np.zeros(rows, dtype=np.intp)
    # Every row at once first; the rows whose heads fall short of the fraction then grow two to eight times, as
    # their weight so far suggests, together with the rows whose heads grow to about the same size.
    pending = [(np.arange(rows), count)]
    while pending:
        group, count = pending.pop()
        head = _stable_head(cost if group.size == rows else cost[group], count)
        cumulative = np.cumsum(prior_weights[head], axis=1)
        reached = (cumulative < fraction).sum(axis=1)
        done = (reached < count) | (count == n_samples)
        for row, row_head, row_reached in zip(group[done], head[done], reached[done]):
            lengths[row] = min(row_reached, n_samples - 1) + 1
            heads[row] = row_head[: lengths[row]]
        weight_so_far = cumulative[~done, -1]
        with np.errstate(divide="ignore"):
            growth = np.clip(1.25 * fraction / weight_so_far, 2.0, 8.0)
        counts = np.minimum(np.ceil(count * growth), n_samples).astype(np.intp)
        pending += [(group[~done][rows], int(counts[rows].max())) for rows in alike_in_size(counts)]
    width = int(lengths.max(initial=0))
    order = np.zeros((rows, width), dtype=np.intp)
    behavioural = np.arange(width) < lengths[:, None]
    order[behavioural] = np.concatenate(heads) if rows else []
    return order, behavioural


def alike_in_size(sizes):
    """The indices of ``sizes`` (rows,) in groups whose sizes lie within a factor of two (one power of two).

    Rows of alike sizes go through one array as wide as the largest of them, wasting at most half of it.

    Examples
    --------
    >>> [group.tolist() for group in alike_in_size(np.array([3, 9, 2, 12, 5]))]
    [[0, 2], [4], [1, 3]]
    """
    scales = np.frexp(sizes)[1]
    return [np.flatnonzero(scales == scale) for scale in np.unique(scales)]


def _stable_head(cost, count):
    """The first ``count`` columns of each row's stable ascending argsort, (rows, count); no NaN in ``cost``."""
    if count == cost.shape[1]:
        return np.argsort(cost, axis=1, kind="stable")
    chosen = np.argpartition(cost, count - 1, axis=1)[:, :count]
    threshold = np.take_along_axis(cost, chosen[:, -1:], axis=1)
    tied = (cost <= threshold).sum(axis=1) > count
    # Where more than count samples reach the threshold, the ones equal to it come in by index, as a stable sort has it.
    for row in np.flatnonzero(tied):
        below = np.flatnonzero(cost[row] < threshold[row])
        equal = np.flatnonzero(cost[row] == threshold[row])[: count - below.size]
        chosen[row] = np.concatenate([below, equal])
    chosen.sort(axis=1)  # by index, so that the stable sort by cost keeps ties in index order
    return np.take_along_axis(
        chosen, np.argsort(np.take_along_axis(cost, chosen, axis=1), axis=1, kind="stable"), axis=1
    )
