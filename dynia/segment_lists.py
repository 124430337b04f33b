"""Segment lists: the step ranges a fit uses, checked, and to and from boolean masks.

A segment is a pair ``(start, stop)`` of step indices, ``stop`` exclusive; a
list of them is sorted, non-overlapping and inside the record
(:func:`check_segments`). :mod:`dynia.segments` selects segments from IC
curves and :mod:`dynia.fit` fits on them; both take them from here.
"""

import numbers
from collections.abc import Mapping

import numpy as np

from . import _checks
from .errors import DataError, SettingsError

__all__ = ["check_segments", "segments_to_mask", "mask_to_segments"]


def check_segments(segments, n_steps=None, name="segments"):
    """Validate a list of segments, against a record of ``n_steps`` steps if given.

    Parameters
    ----------
    segments : sequence of (start, stop) pairs of int, or array of shape (k, 2)
        Steps ``start .. stop-1`` each; sorted, non-overlapping (touching is
        fine), ``0 <= start < stop <= n_steps``. May be empty.
    n_steps : int, optional
        Length of the record; without it only ``0 <= start < stop`` is checked.
    name : str
        Argument name used in error messages.

    Returns
    -------
    list of tuple of int
        The segments as ``(start, stop)`` tuples of Python ints.

    Raises
    ------
    ValueError
        Naming the first offending segment and what is wrong with it.

    Examples
    --------
    >>> check_segments([[0, 5], (7, 9)], 10)
    [(0, 5), (7, 9)]
    >>> check_segments([(0, 5), (4, 9)], 10)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    dynia.errors.SettingsError: segments[1] = (4, 9) overlaps segments[0] = (0, 5); ...
    """
    if n_steps is not None:
        n_steps = _checks.whole_number(n_steps, "n_steps", minimum=1)
    if isinstance(segments, (str, bytes, Mapping)):
        raise TypeError(f"{name} must be a sequence of (start, stop) pairs; got {type(segments).__name__}")
    checked = []
    for position, pair in enumerate(segments):
        try:
            if isinstance(pair, (str, bytes)):
                raise TypeError
            start, stop = pair
        except (TypeError, ValueError):
            raise SettingsError(f"{name}[{position}] must be a (start, stop) pair; got {pair!r}") from None
        start, stop = (_index(value, f"{name}[{position}]") for value in (start, stop))
        if not 0 <= start < stop or (n_steps is not None and stop > n_steps):
            record = "" if n_steps is None else f" of a record of {n_steps} steps"
            limit = "" if n_steps is None else f" <= {n_steps}"
            raise SettingsError(
                f"{name}[{position}] = ({start}, {stop}) is not a segment{record}; "
                f"need 0 <= start < stop{limit} (stop is exclusive)"
            )
        if checked and start < checked[-1][1]:
            order = "overlaps" if start >= checked[-1][0] else "starts before"
            raise SettingsError(
                f"{name}[{position}] = ({start}, {stop}) {order} {name}[{position - 1}] = "
                f"{checked[-1]}; segments must be sorted and non-overlapping"
            )
        checked.append((start, stop))
    return checked


def _index(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        if isinstance(value, numbers.Real) and float(value).is_integer():
            return int(value)
        raise SettingsError(f"{name} must hold whole step indices; got {value!r}")
    return int(value)


def segments_to_mask(segments, n_steps):
    """Boolean mask of the steps inside ``segments``, shape (n_steps,).

    Examples
    --------
    >>> segments_to_mask([(1, 3)], 5).tolist()
    [False, True, True, False, False]
    """
    mask = np.zeros(_checks.whole_number(n_steps, "n_steps", minimum=1), dtype=bool)
    for start, stop in check_segments(segments, n_steps):
        mask[start:stop] = True
    return mask


def mask_to_segments(mask):
    """The runs of True in a boolean mask, as segments.

    Examples
    --------
    >>> mask_to_segments([True, True, False, True])
    [(0, 2), (3, 4)]
    """
    mask = np.asarray(mask)
    if mask.ndim != 1 or mask.dtype != bool:
        raise DataError(f"mask must be a 1-D boolean array; got dtype {mask.dtype}, shape {mask.shape}")
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return [(int(start), int(stop)) for start, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1))]
