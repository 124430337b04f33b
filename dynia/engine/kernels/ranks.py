"""Order statistics of large sets counted through the samples' ranks: a bitset per set, no selection.

Each parameter's values are sorted once per run
(:func:`dynia.engine.flavours.parameter_ranks`).
A set's k-th smallest value is then the sorted value at its k-th smallest
rank: its members' ranks are set as bits of a word array and counted in
order, a word at a time, in time linear in the samples / 64 rather than in
the set with a large constant. The population's limits and median
(:func:`ranked_order_statistics`), and every Monte Carlo batch's limits at
once (:func:`batch_limits`), are found so when the sets are large.
"""

import numpy as np

from .bits import ONE, popcount
from .compile import inner, jit

__all__ = ["ranked_order_statistics", "batch_limits"]


@jit
def ranked_order_statistics(ranks, ordered, selected, count, positions, words):
    """The ``positions``-th smallest values of a set and its median, through the samples' ranks: one parameter's.

    ``ranks`` (n_samples,) is every sample's position in the stable sort of
    the parameter's values, ``ordered`` those values sorted: the set's
    (``selected[:count]``) k-th smallest value is ``ordered`` at its k-th
    smallest rank, found by setting the set's ranks as bits of ``words``
    (zeros, (n_samples + 63) // 64 of them, cleared again) and counting
    them in order, a word at a time. Returns (lower, upper, median), the
    values :func:`~dynia.engine.kernels.selection.order_statistics` finds.
    """
    for i in range(count):
        rank = ranks[selected[i]]
        words[rank >> 6] |= ONE << np.uint64(rank & 63)
    # Ascending targets: each walk goes on from the word the last one stopped in.
    lower, w, seen = _set_bit_at(words, positions[0], np.int64(0), np.int64(0))  # not literals: one compile
    middle, w, seen = _set_bit_at(words, (count - 1) // 2, w, seen)
    upper, w, seen = _set_bit_at(words, positions[1], w, seen)
    words[:] = 0
    return ordered[lower], ordered[upper], ordered[middle]


@inner
def _set_bit_at(words, target, w, seen):
    """Where the ``target``-th set bit (0-based) of ``words`` lies, counted on from word ``w`` after ``seen`` bits.

    Returns its position, the word it lies in and the set bits before that word, for the next, later target.
    """
    while seen + popcount(words[w]) <= target:
        seen += popcount(words[w])
        w += 1
    word = words[w]
    counted = seen
    bit = 0
    while True:
        if (word >> np.uint64(bit)) & ONE:
            if counted == target:
                return 64 * w + bit, w, seen
            counted += 1
        bit += 1


@inner
def batch_limits(selected, counts, positions, ranks, ordered, at_rank, words, limits):
    """Every batch's thesis limits for one parameter, into ``limits`` (n_batches, 2): order statistics of its set.

    Batch b's set is ``selected[b, :counts[b]]``. The sets' ranks are set
    as bits of ``words`` (zeros, cleared again), then walked from the lowest
    rank up until every batch has met its lower limit's position
    (``positions[b, 0]``), and from the highest down for the upper: near
    the ends for a confidence level of 90 %, a few hundred of the sets'
    members in all, where selecting in each set visits them all.
    ``at_rank`` holds the batch of the sample at every rank.
    """
    for b in range(counts.shape[0]):
        for i in range(counts[b]):
            rank = ranks[selected[b, i]]
            words[rank >> 6] |= ONE << np.uint64(rank & 63)
    _walk_to_limits(words, at_rank, ordered, positions[:, 0], True, limits[:, 0])
    _walk_to_limits(words, at_rank, ordered, counts - 1 - positions[:, 1], False, limits[:, 1])
    words[:] = 0


@inner
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
            if (word >> np.uint64(bit)) & ONE:
                rank = 64 * w + bit
                b = at_rank[rank]
                if seen[b] == targets[b]:
                    limits[b] = ordered[rank]
                    remaining -= 1
                seen[b] += 1
