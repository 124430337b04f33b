"""The parameters of a least-squares fit: which are fitted, within which box, from which starts.

``initial``, ``fixed`` and ``bounds`` of :func:`dynia.fit.fit_segments` map
parameter names to numbers; each is checked here with one clear message per
mistake, and the parameters left free get their box and their starts.
"""

import math
import numbers
from collections.abc import Mapping

import numpy as np

from . import _checks
from .errors import SettingsError


def named_values(values, name, names):
    """``values``, a mapping of parameter names among ``names`` to finite numbers, as a dict of floats in ``names``
    order; {} for None. ``name`` is the argument that gave it."""
    if values is None:
        return {}
    if not isinstance(values, Mapping):
        raise TypeError(f"{name} must map parameter names to values, e.g. {{'K': 2.0}}; got {type(values).__name__}")
    unknown = [key for key in values if key not in names]
    if unknown:
        raise SettingsError(f"{name} names unknown parameters {unknown}; the model has {list(names)}")
    checked = {}
    for key in names:
        if key in values:
            value = values[key]
            if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
                raise SettingsError(f"{name}[{key!r}] must be a finite number; got {value!r}")
            checked[key] = float(value)
    return checked


def named_bounds(bounds, names):
    """``bounds``, a mapping of parameter names among ``names`` to (low, high) with low < high, as a dict of float
    pairs in ``names`` order; {} for None."""
    if bounds is None:
        return {}
    if not isinstance(bounds, Mapping):
        raise TypeError(
            f"bounds must map parameter names to (low, high), e.g. {{'K': (0, 7)}}; got {type(bounds).__name__}"
        )
    unknown = [key for key in bounds if key not in names]
    if unknown:
        raise SettingsError(f"bounds names unknown parameters {unknown}; the model has {list(names)}")
    checked = {}
    for key in names:
        if key not in bounds:
            continue
        pair = bounds[key]
        try:
            if isinstance(pair, (str, bytes)):
                raise TypeError
            low, high = (float(value) for value in pair)
        except (TypeError, ValueError):
            raise SettingsError(f"bounds[{key!r}] must be a (low, high) pair of numbers; got {pair!r}") from None
        if math.isnan(low) or math.isnan(high) or not low < high:
            raise SettingsError(f"bounds[{key!r}]: need low < high; got ({low}, {high})")
        checked[key] = (low, high)
    return checked


def free_parameters(model, fixed, initial, bounds):
    """The names of the parameters to fit, their box (lower, upper) and the first start, all checked."""
    free_names = [name for name in model.names if name not in fixed]
    if not free_names:
        raise SettingsError(f"fixed holds every parameter of {type(model).__name__}; nothing is left to fit")
    clash = [name for name in initial if name in fixed]
    if clash:
        raise SettingsError(f"initial and fixed both name {clash}; a parameter is either fitted or fixed")
    lower, upper, start = _box_and_start(free_names, bounds, initial)
    _check_fixed_in_bounds(fixed, bounds)
    return free_names, lower, upper, start


def _box_and_start(free_names, bounds, initial):
    lower, upper, start = [], [], []
    for name in free_names:
        low, high = bounds.get(name, (-math.inf, math.inf))
        if name in initial:
            value = initial[name]
            if not low <= value <= high:
                raise SettingsError(f"initial[{name!r}] = {value} lies outside its bounds [{low}, {high}]")
        elif math.isfinite(low) and math.isfinite(high):
            value = 0.5 * (low + high)
        else:
            raise SettingsError(
                f"parameter {name!r} needs finite bounds (its start is their middle) or an "
                f"initial value; give bounds={{{name!r}: (low, high)}} or "
                f"initial={{{name!r}: value}}"
            )
        lower.append(low)
        upper.append(high)
        start.append(value)
    return np.array(lower), np.array(upper), np.array(start)


def _check_fixed_in_bounds(fixed, bounds):
    for name, value in fixed.items():
        if name in bounds and not bounds[name][0] <= value <= bounds[name][1]:
            raise SettingsError(f"fixed[{name!r}] = {value} lies outside its bounds {list(bounds[name])}")


def search_starts(start, lower, upper, n_starts, rng):
    """``start``, then ``n_starts - 1`` starts drawn uniformly in the (finite) box from ``rng``."""
    starts = [start]
    if n_starts > 1:
        if not (np.isfinite(lower).all() and np.isfinite(upper).all()):
            raise SettingsError(
                "n_starts > 1 draws starts uniformly in the bounds, which must then be finite "
                "for every fitted parameter"
            )
        starts += list(_checks.generator(rng).uniform(lower, upper, (n_starts - 1, start.size)))
    return starts
