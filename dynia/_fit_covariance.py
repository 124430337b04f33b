"""The covariance of least-squares estimates: classical, and robust to autocorrelated residuals (HAC).

The formulas, and why both are reported, are the Standard errors of
:mod:`dynia.fit`'s module docs. A parameter the Jacobian does not determine
gets NaN rows and columns, the others the pseudo-inverse's variances.
"""

import math

import numpy as np

# Singular values of the Jacobian (columns scaled by the typical scales)
# below this fraction of the largest are taken as zero. The central
# differences are accurate to about 1e-10 relative, so this sits well above
# their noise; a direction this weak would have a standard error 1e7 times
# the best one, which is no estimate either.
_RANK_RTOL = 1e-7

# A parameter belongs to an unidentifiable direction when its component in
# the Jacobian's null space exceeds this (null vectors have unit norm).
_NULL_COMPONENT = 1e-6

# The HAC prewhitening's VAR(1) singular values and the bandwidth rule's
# autocorrelation are capped here: (I - A)^-1 and the lag count grow without
# bound as they approach 1 (Andrews and Monahan 1992 cap at 0.97).
_HAC_MAX_RHO = 0.97


def inverse_normal_matrix(jacobian, scale):
    """``(J^T J)^+``, which parameters it determines, and the rank of J.

    Columns are scaled by the parameters' typical scales first, so that the
    rank decision does not depend on their units. A parameter with a
    component in the null space of J is not determined; every other one is
    an estimable function, whose variance the pseudo-inverse gives (the
    rows and columns of the others are blanked by :func:`masked`).
    """
    scaled = jacobian * scale
    # Only the right singular vectors are used: the left ones of a long record (n_points x n_points) would take
    # seconds and gigabytes. Full matrices only where there are fewer points than parameters, so that the right
    # ones span the null space too.
    _, singular, right = np.linalg.svd(scaled, full_matrices=scaled.shape[0] < scaled.shape[1])
    # With fewer points than parameters J has fewer singular values than
    # columns; the missing ones are zeros.
    singular = np.concatenate((singular, np.zeros(right.shape[0] - singular.size)))
    largest = singular.max()
    kept = singular > _RANK_RTOL * largest if largest > 0 else np.zeros(singular.size, dtype=bool)
    identifiable = ~(np.abs(right[~kept].T) > _NULL_COMPONENT).any(axis=1)
    inverse = (right[kept].T / singular[kept] ** 2) @ right[kept] * np.outer(scale, scale)
    return inverse, identifiable, int(kept.sum())


def masked(covariance, identifiable):
    """``covariance`` with NaN in the rows and columns of the parameters the data do not determine."""
    covariance = covariance.copy()
    covariance[~identifiable, :] = np.nan
    covariance[:, ~identifiable] = np.nan
    return covariance


def hac_covariance(jacobian, residuals, steps, inverse, scale):
    """Prewhitened Newey-West sandwich ``A^+ S A^+`` (module docs) without the small-sample factor, and its L.

    ``inverse`` is ``A^+ = (J^T J)^+``. The scores ``g_t = J_t r_t`` are
    laid out on the record's time axis (zero where nothing was fitted), so
    that a lag is a distance in time steps, and scaled by the parameters'
    typical scales so that the VAR(1) fit does not depend on their units.
    """
    scores = np.zeros((steps[-1] - steps[0] + 1, jacobian.shape[1]))
    scores[steps - steps[0]] = jacobian * scale * residuals[:, None]
    previous, current = scores[:-1], scores[1:]
    transition = np.zeros((scores.shape[1], scores.shape[1]))
    if current.shape[0] > scores.shape[1]:
        transition = (current.T @ previous) @ np.linalg.pinv(previous.T @ previous)
        # Andrews and Monahan (1992): a nearly unit-root fit would blow (I - A)^-1 up; cap its singular values.
        left, singular, right = np.linalg.svd(transition)
        transition = (left * np.minimum(singular, _HAC_MAX_RHO)) @ right
    whitened = current - previous @ transition.T
    lags = _bartlett_lags(whitened)
    spread = whitened.T @ whitened
    for lag in range(1, lags + 1):
        product = whitened[lag:].T @ whitened[:-lag]
        spread += (1 - lag / (lags + 1)) * (product + product.T)
    recolour = np.linalg.pinv(np.eye(transition.shape[0]) - transition)
    spread = recolour @ spread @ recolour.T
    return inverse @ (spread * np.outer(1 / scale, 1 / scale)) @ inverse, lags


def _bartlett_lags(series):
    """Andrews' (1991) AR(1) plug-in bandwidth of the Bartlett kernel for ``series`` (n, k), as whole lags."""
    n_points = series.shape[0]
    total = float(np.sum(series * series))
    if n_points < 3 or total == 0:
        return 0
    # One autocorrelation pooled over the components, each weighted by its variance.
    rho = float(np.clip(np.sum(series[1:] * series[:-1]) / total, -_HAC_MAX_RHO, _HAC_MAX_RHO))
    alpha = 4 * rho**2 / ((1 - rho) ** 2 * (1 + rho) ** 2)
    return int(min(math.floor(1.1447 * (alpha * n_points) ** (1 / 3)), n_points - 1))
