"""Words of bits: counting the set bits of a uint64, finding the lowest, and marking values in one.

A pass that keeps a few values of many (a window's candidates, the costs
near a quantile) marks them as bits, 64 values to a word, in a loop that
vectorises (:func:`mark_at_most`, :func:`mark_between`), then visits only the
set bits (:func:`lowest_set_bit`): no branch per value to mispredict, and
no write per value that is not kept. The limits of a large set count its
members' ranks a word at a time (:func:`popcount`,
:mod:`~dynia.engine.kernels.ranks`).
"""

import numpy as np

from .compile import inner

__all__ = ["ONE", "popcount", "lowest_set_bit", "mark_at_most", "mark_between"]

#: The uint64 1: shifts and masks of words stay unsigned, as numba types a literal 1 signed.
ONE = np.uint64(1)


@inner
def popcount(word):
    """How many bits of the uint64 ``word`` are set (the bit-parallel count: pairs, nibbles, bytes, then a sum).

    LLVM recognises the idiom and emits the processor's own count.
    """
    word = word - ((word >> ONE) & np.uint64(0x5555555555555555))
    word = (word & np.uint64(0x3333333333333333)) + ((word >> np.uint64(2)) & np.uint64(0x3333333333333333))
    word = (word + (word >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return np.int64((word * np.uint64(0x0101010101010101)) >> np.uint64(56))


@inner
def lowest_set_bit(word):
    """The position (0-63) of the lowest set bit of a ``word`` that is not 0: the bits below it counted.

    LLVM recognises the idiom and emits the processor's trailing-zero count.
    """
    return popcount((word & (~word + ONE)) - ONE)


@inner
def mark_at_most(values, bound):
    """A word whose bit j is set when ``|values[j]| <= bound``, for the 64 ``values`` (none for a NaN value or bound).

    ``values`` is a view of 64, indexed from 0: an index LLVM cannot prove non-negative (base + j) takes numba's
    wraparound, and the loop no longer vectorises (a third of the speed).
    """
    word = np.uint64(0)
    for j in range(64):
        word |= np.uint64(abs(values[j]) <= bound) << np.uint64(j)
    return word


@inner
def mark_between(values, bracket):
    """A word whose bit j is set when ``low < |values[j]| <= high``, ``bracket`` = (low, high).

    As :func:`mark_at_most`, for 64 ``values``.
    """
    low, high = bracket
    word = np.uint64(0)
    for j in range(64):
        size = abs(values[j])
        word |= np.uint64((size > low) & (size <= high)) << np.uint64(j)
    return word
