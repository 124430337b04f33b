"""Argument checks shared by the public functions: one clear message per mistake."""

import math
import numbers
import os
import re

import numpy as np

from .errors import DataError, SettingsError

# A quantity written as a number and a unit, "2min", "1.5 GB" or "90": groups (number, unit), the unit maybe empty.
QUANTITY = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*([a-zA-Z]*)\s*$")


def as_1d_float(value, name, *, allow_nan=False):
    """Return ``value`` as a 1-D float64 array, or raise naming ``name``."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise DataError(f"{name} must be a 1-D array of numbers: {error}") from None
    if array.ndim != 1:
        raise DataError(f"{name} must be 1-D (n_steps,); got shape {array.shape}")
    if array.size == 0:
        raise DataError(f"{name} is empty; expected at least one value")
    bad = np.isinf(array) if allow_nan else ~np.isfinite(array)
    if bad.any():
        raise DataError(
            f"{name} holds a non-finite value at index {int(np.argmax(bad))}"
            + (" (NaN marks a missing value; inf is not allowed)" if allow_nan else "")
        )
    return array


def as_2d_float(value, name, *, columns=None):
    """Return ``value`` as a 2-D float64 array of finite numbers, or raise naming ``name``."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise DataError(f"{name} must be a 2-D array of numbers: {error}") from None
    if array.ndim != 2:
        raise DataError(f"{name} must be 2-D; got shape {array.shape}")
    if columns is not None and array.shape[1] != columns:
        raise DataError(f"{name} must have {columns} columns; got shape {array.shape}")
    bad = ~np.isfinite(array)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise DataError(f"{name} holds a non-finite value at row {row}, column {col}")
    return array


def whole_number(value, name, *, minimum, maximum=None, why=""):
    """Return ``value`` as an int in [``minimum``, ``maximum``], or raise naming ``name`` (and ``why`` the maximum).

    A count a user types can be any size: every count that sizes an
    allocation or a loop has a ``maximum``, so that a slip (1e10 for 1e4)
    is one clear line, not numpy's out-of-memory traceback or hours of work.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        if isinstance(value, numbers.Real) and math.isfinite(value) and float(value).is_integer():
            value = int(value)
        else:
            raise SettingsError(f"{name} must be a whole number; got {value!r}", name)
    if value < minimum:
        raise SettingsError(f"{name} must be at least {minimum}; got {value}", name)
    if maximum is not None and value > maximum:
        raise SettingsError(f"{name} must be at most {spaced(maximum)}{why}; got {spaced(value)}", name)
    return int(value)


def spaced(number):
    """A whole number with its thousands set apart by spaces, as the messages write them: 100 000 000."""
    return f"{number:,}".replace(",", " ")


def open_interval(value, name, low, high):
    """Return ``value`` as a float strictly inside (low, high), or raise naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise SettingsError(f"{name} must be a finite number; got {value!r}")
    if not low < value < high:
        raise SettingsError(f"{name} must lie strictly between {low} and {high}; got {value}")
    return float(value)


def percentage_value(value):
    """Return the behavioural percentage as a float in (0, 100], or raise."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise SettingsError(f"percentage must be a finite number; got {value!r}")
    if not 0 < value <= 100:
        raise SettingsError(f"percentage must lie in (0, 100]; got {value}")
    return float(value)


def bounds_array(bounds, n_params):
    """Check an (n_params, 2) array of [low, high] rows with low < high."""
    array = as_2d_float(bounds, "bounds", columns=2)
    if array.shape[0] != n_params:
        raise SettingsError(f"bounds must have one [low, high] row per parameter ({n_params}); got {array.shape[0]}")
    for row, (low, high) in enumerate(array):
        if not low < high:
            raise SettingsError(f"bounds row {row}: the lower bound {low} must be below the upper bound {high}")
    return array


def default_workers():
    """Threads to use when none are asked for: every core."""
    return os.cpu_count() or 1


# A record whose values are all smaller than this cannot be simulated faithfully: the simulators set states below
# dynia.models.base.FLUSH_BELOW (2^-960) to zero, and 2^60 above it leaves room for a model's gains and slow poles.
SMALLEST_RESOLVED = 2.0**-900


def record(u, y, n_inputs=1, *, whole=True):
    """Input and output of one record: ``u`` (n_steps,) or (n_steps, n_inputs), ``y`` (n_steps,).

    NaN in ``y`` marks a missing sample; ``u`` must be finite. A ``whole``
    record (not a block of one fed in pieces) must hold a value of at least
    :data:`SMALLEST_RESOLVED` in each signal that is not all zero.
    """
    if n_inputs == 1:
        u = as_1d_float(u, "u")
    else:
        shape = np.shape(u)
        if len(shape) != 2 or shape[1] != n_inputs:
            raise DataError(f"u must have shape (n_steps, {n_inputs}) for a model with {n_inputs} inputs; got {shape}")
        u = as_2d_float(u, "u", columns=n_inputs)
    y = as_1d_float(y, "y", allow_nan=True)
    if u.shape[0] != y.size:
        raise DataError(f"u has {u.shape[0]} samples but y has {y.size}; they must be logged on the same steps")
    for name, values in (("u", u), ("y", y)) if whole else ():
        largest = float(np.nanmax(np.abs(values), initial=0.0))
        if 0 < largest < SMALLEST_RESOLVED:
            raise DataError(
                f"{name}'s largest magnitude is {largest:.3g}, below {SMALLEST_RESOLVED:.2g}: the simulation sets "
                "states below 1e-289 to 0 every step, so no model's response can be told from another's; "
                "express the record in a smaller unit (multiply it by a power of ten)"
            )
    return u, y


def generator(rng, name="rng"):
    """``numpy.random.default_rng(rng)``, or a SettingsError naming ``name`` when ``rng`` cannot seed one.

    Accepted as numpy accepts them (SPEC 7): None, a whole number >= 0, a sequence of them, a
    SeedSequence, a BitGenerator or a Generator.

    Examples
    --------
    >>> generator(1).integers(10) == np.random.default_rng(1).integers(10)
    np.True_
    >>> generator(-5)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    dynia.errors.SettingsError: rng must be None, a whole number >= 0 (a seed), ...; got -5
    """
    if isinstance(rng, bool):
        rng = object()  # True is an int to numpy; as a seed it is a mistake
    try:
        return np.random.default_rng(rng)
    except (TypeError, ValueError):
        raise SettingsError(
            f"{name} must be None, a whole number >= 0 (a seed), a sequence of them, a SeedSequence, a BitGenerator "
            f"or a numpy Generator; got {rng!r}",
            name,
        ) from None


# What the readers of a result use of it: its arrays, its settings and its window geometry.
_RESULT_ATTRIBUTES = ("names", "time", "ic", "ci", "settings", "informative", "window_cover")


def analysis_result(value, name="result"):
    """``value``, or a TypeError unless it is a :class:`~dynia.result.DyniaResult` (or has everything one has).

    Checked by what a result offers rather than by its class, so that the
    modules that read results (:mod:`dynia.segments`, :mod:`dynia.structure`)
    need not import :mod:`dynia.result`, whose methods use them.
    """
    if not all(hasattr(value, attribute) for attribute in _RESULT_ATTRIBUTES):
        raise TypeError(f"{name} must be a DyniaResult; got {type(value).__name__}")
    return value
