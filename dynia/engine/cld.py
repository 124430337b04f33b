"""Likelihoods, cumulative likelihood distributions (CLD) and what is read off them.

The GLUE and RSA building blocks of DYNIA, usable on one analysis (the whole
record, as in the thesis's chapter 2) or on many windows at once: every
function works along the last axis, so ``values`` of shape (k,) is one
behavioural set and (n_windows, k) is one per window. Weights are likelihoods
normalised to sum to 1 along the last axis.

Examples
--------
>>> import numpy as np
>>> from dynia.engine import cld
>>> cost = np.array([0.2, 0.6, 0.4])
>>> w = cld.likelihood(cost)
>>> w.round(3)
array([0.444, 0.222, 0.333])
>>> cld.weighted_limits(np.array([1.0, 3.0, 2.0]), w, 50).tolist()
[1.0, 2.0]
"""

import math

import numpy as np

__all__ = [
    "likelihood",
    "limits",
    "weighted_limits",
    "median",
    "weighted_median",
    "band_and_median",
    "binned_mass",
    "cumulative",
    "weighted_quantiles",
]


def likelihood(cost):
    """GLUE/MCAT likelihood: ``1 - cost``, shifted by its minimum where negative, normalised.

    Where every cost of a set is equal and at least 1 the measure is 0/0;
    such a set is weighted equally instead.

    Parameters
    ----------
    cost : array_like (..., k)

    Returns
    -------
    ndarray (..., k), non-negative, summing to 1 along the last axis.
    """
    value = 1 - np.asarray(cost, dtype=float)
    lowest = value.min(axis=-1, keepdims=True)
    value = np.where(lowest < 0, value - lowest, value)
    # Summed in index order (not numpy's pairwise order), the order the
    # compiled engine (dynia.engine.kernels) uses, so both give the same bits.
    total = np.cumsum(value, axis=-1)[..., -1:]
    degenerate = total[..., 0] == 0
    value[degenerate] = 1.0
    total[degenerate] = value.shape[-1]
    return value / total


def limits(values, conf_level):
    """Unweighted confidence limits, as the thesis's ``confLimits``.

    The sorted values at 0-based positions ``floor(c*(k-1))`` for
    ``c = (1 - conf_level/100)/2`` and ``1 - c``.

    Returns
    -------
    ndarray (..., 2): lower, upper.
    """
    return band_and_median(values, None, conf_level, weighted=False)[0]


def median(values):
    """The unweighted CLD median: the sorted value at 0-based position ``floor((k-1)/2)``, shape (...).

    The analogue of :func:`limits` at level 0.5, so it lies between them.
    """
    return band_and_median(values, None, 50, weighted=False)[1]


def weighted_limits(values, weights, conf_level):
    """Likelihood-weighted limits (Wagener et al., 2003).

    The first sorted values at which the CLD reaches ``(100 - conf_level)/200``
    and ``(100 + conf_level)/200``.

    Returns
    -------
    ndarray (..., 2): lower, upper.
    """
    return band_and_median(values, weights, conf_level, weighted=True)[0]


def weighted_median(values, weights):
    """The likelihood-weighted CLD median: the first sorted value at which the CLD reaches 0.5, shape (...)."""
    return band_and_median(values, weights, 50, weighted=True)[1]


def band_and_median(values, weights, conf_level, *, weighted):
    """Confidence limits and CLD median from one sort of ``values``.

    ``weighted`` reads them off the CLD of ``weights`` as
    :func:`weighted_limits` does, at the levels ``(100 -/+ conf_level)/200``
    and 0.5; otherwise (``weights`` unused) as :func:`limits` does, at the
    sorted positions ``floor(c*(k-1))``, ``floor(0.5*(k-1))`` and
    ``floor((1-c)*(k-1))``. Either way the median lies between the limits:
    the levels, and the positions, are in that order.

    Returns
    -------
    band : ndarray (..., 2)
        Lower and upper limit.
    median : ndarray (...)
    """
    if weighted:
        ordered, cumulative_likelihood = cumulative(values, weights)
        lower, middle, upper = (
            _first_reaching(ordered, cumulative_likelihood, level)
            for level in ((100 - conf_level) / 200, 0.5, (100 + conf_level) / 200)
        )
        return np.concatenate([lower, upper], axis=-1), middle[..., 0]
    ordered = np.sort(values, axis=-1)
    count = ordered.shape[-1]
    c1 = (1 - conf_level / 100) / 2
    c2 = 1 - c1
    positions = [math.floor(c1 * (count - 1)), math.floor(c2 * (count - 1))]
    return ordered[..., positions], ordered[..., math.floor(0.5 * (count - 1))]


def _first_reaching(ordered, cumulative_likelihood, level):
    """The first ordered value whose cumulative likelihood reaches ``level``, shape (..., 1)."""
    # The CLD never decreases, so the count of points below the level is the
    # first index reaching it; rounding can leave the total a hair under a
    # level close to 1, hence the clip to the last value.
    first = np.minimum((cumulative_likelihood < level).sum(axis=-1, keepdims=True), ordered.shape[-1] - 1)
    return np.take_along_axis(ordered, first, axis=-1)


def cumulative(values, weights):
    """Values in ascending order (stable) and the cumulative likelihood at each.

    Returns
    -------
    ordered, cld : ndarray (..., k) each.
    """
    values = np.asarray(values, dtype=float)
    order = np.argsort(values, axis=-1, kind="stable")
    ordered = np.take_along_axis(values, order, axis=-1)
    weights = np.broadcast_to(weights, values.shape)
    return ordered, np.cumsum(np.take_along_axis(weights, order, axis=-1), axis=-1)


def binned_mass(values, weights, low, high, bins):
    """Likelihood mass of the values in each of ``bins`` equal bins of [low, high].

    The CLD's increase across each bin: the thesis's CLD gradient, without the
    quirks of its ``cld_gradient`` (see :mod:`dynia.reference.thesis`). A value equal to
    ``high`` counts in the last bin.

    Returns
    -------
    ndarray (..., bins)
    """
    values = np.asarray(values, dtype=float)
    weights = np.broadcast_to(weights, values.shape)
    rows = values.reshape(-1, values.shape[-1])
    which = np.clip(((rows - low) / (high - low) * bins).astype(np.intp), 0, bins - 1)
    flat = which + bins * np.arange(rows.shape[0])[:, None]
    mass = np.bincount(flat.ravel(), weights=weights.reshape(rows.shape).ravel(), minlength=rows.shape[0] * bins)
    return mass.reshape(values.shape[:-1] + (bins,))


def weighted_quantiles(outputs, weights, levels):
    """Likelihood-weighted quantiles of simulated outputs at every time step (GLUE).

    Parameters
    ----------
    outputs : array_like (k, n_steps)
        Outputs of the behavioural parameter sets.
    weights : array_like (k,)
        Their likelihoods, summing to 1.
    levels : sequence of float
        Quantile levels in (0, 1), e.g. (0.05, 0.95).

    Returns
    -------
    ndarray (len(levels), n_steps): the first sorted output at which the
    cumulative likelihood reaches each level.
    """
    ordered, cumulative_likelihood = cumulative(np.asarray(outputs, dtype=float).T, weights)
    return np.array([_first_reaching(ordered, cumulative_likelihood, level)[:, 0] for level in levels])
