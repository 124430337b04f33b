"""The noise floor: which windows tell parameter sets apart beyond what measurement noise alone does.

A window's information content is read off its behavioural set, the lowest
costs of the Monte Carlo population. When the window's data are noise only
(the sets' outputs there differ by much less than the noise), the ranking
that picks that set is a ranking of noise, and a narrow band is an accident
of it (of exact ties, too: sets whose outputs are equal tie, and the stable
sort keeps the first ones by index). The noise floor tests, per window,
whether the behavioural set's costs spread further than noise alone makes
them spread.

The statistic
-------------
Two numbers of every window come out of the engine's selection at no cost:
the best mean absolute error (MAE) ``best`` and the behavioural threshold
``threshold``, the largest MAE inside the behavioural set (the count-th
smallest). The statistic is their difference, the behavioural spread
``threshold - best``: 0 when the best sets tie, large when the window's
data rank the sets by their parameters.

The null hypothesis
-------------------
H0: within the window the residuals of the parameter sets are exchangeable
noise, so which set fits best is decided by the noise realisation, not by
the parameters. The MAE of m noise points of standard deviation sigma has
mean ``sigma sqrt(2/pi)`` and standard deviation
``s = sigma sqrt(1 - 2/pi) / sqrt(m)`` (normal noise), and by the central
limit theorem is close to normal. Under H0 with residuals correlated across
sets with correlation rho (they share the noise: rho near 1 when the outputs
nearly agree), MAE_i = mu + s (sqrt(rho) Z_0 + sqrt(1 - rho) Z_i), so the
spread is ``s sqrt(1 - rho)`` times the spread of independent normals:
largest for independent residuals (rho = 0). That case is the least
favourable, and a test sized for it holds for every rho.

For N independent normal MAEs, the threshold sits at the quantile
``z_q = Phi^-1(q)`` of the behavioural share q (its own spread, about
``s sqrt(q(1-q)/N) / phi(z_q)``, is a few hundredths of s and is left out)
and the minimum falls below ``mu + s z`` with probability
``1 - (1 - Phi(z))^N``. A window is informative, H0 rejected at level a,
when

    threshold - best > (z_q - z_a) s,    z_a = Phi^-1(1 - (1 - a)^(1/N)),

``multiple = z_q - z_a`` (:func:`critical_multiple`). A record of
``n_steps`` has ``W = ceil(n_steps / (2n+1))`` disjoint windows (the
overlapping ones share their data, so W is the number of independent tests);
Bonferroni over them, ``a = level / W`` with ``level`` = 5 %, keeps the chance
that any noise-only stretch of the record is called informative at 5 %. The
multiple grows slowly with N and W (see the examples of
:func:`critical_multiple`: thesis example 1 has N = 2000, q = 0.1 and W = 24,
a record of 10^5 steps W = 5000). The MAE of few
points is skewed to the right, so its left tail is lighter than the normal
one: the normal approximation makes the floor a little higher, not lower.

The noise level
---------------
sigma comes from the best fits' residuals: every window's best MAE divided
by ``sqrt(2/pi)`` (the MAE of normal noise), the median over the windows.
The minimum over many sets is biased low, but not as the minimum of N
independent MAEs is (sets share parameters, so their fits are one
p-parameter family, not N independent tries): the best of a dense sample is
close to the best fit of the p parameters to the window's m points, whose
residuals are smaller by ``sqrt((m - p)/m)`` (least squares: the expected
residual sum of squares is ``sigma^2 (m - p)``); that factor is divided out.
Windows with ``m <= p`` points say nothing about the noise and are left out.
The median is robust to the windows where the model cannot fit (their best
MAE holds the misfit too) while they are fewer than half; when they are
more, sigma is overestimated and the floor is higher: fewer windows are
informative, never more. On thesis examples 1 and 2 (sigma 0.5 and 0.2) the
estimate lands within 12 % of the truth.

Two limits of one sigma for the whole record. Errors that grow with the
output (relative gauging errors) are smaller than sigma where the output is
small, so windows there that do discriminate can fall below the floor.
And a population of unrelated outputs, not one model's family over its
parameters, puts the minimum MAE far below the best fit's (the minimum of N
independent MAEs): there the estimate is low and the floor too; give sigma
to :func:`noise_floor` when it is known.

Examples
--------
>>> import numpy as np
>>> floor = noise_floor(np.full(4, 0.4), np.array([0.4, 0.45, 0.9, np.nan]), np.full(4, 21.0),
...                     n_params=2, share=0.1, n_samples=2000, n_windows=1)
>>> floor.informative.tolist(), round(floor.multiple, 2)
([False, False, True, False], 2.77)
"""

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import norm

from ..errors import SettingsError

__all__ = [
    "NoiseFloor",
    "noise_floor",
    "record_noise_floor",
    "critical_multiple",
    "fitted_noise_sigma",
    "window_points",
    "FAMILY_LEVEL",
]

# The chance that any noise-only stretch of a record is called informative (Bonferroni over its windows).
FAMILY_LEVEL = 0.05


@dataclass(frozen=True, eq=False)
class NoiseFloor:
    """The noise floor of every window: what :func:`noise_floor` returns.

    Attributes
    ----------
    informative : ndarray (n_steps,) bool
        The behavioural spread exceeds the floor; False where a window had
        no result or too few points to judge.
    spread : ndarray (n_steps,)
        Behavioural threshold MAE minus best MAE; NaN where no result.
    floor : ndarray (n_steps,)
        ``multiple`` sampling standard deviations of the MAE of the window's
        points of noise ``sigma``; NaN where the window has at most
        ``n_params`` points.
    sigma : float
        The noise level estimated from the best fits (NaN when no window
        could give it).
    multiple : float
        The critical multiple of :func:`critical_multiple`.
    """

    informative: np.ndarray
    spread: np.ndarray
    floor: np.ndarray
    sigma: float
    multiple: float


def window_points(y, before, after):
    """Measured points (non-NaN ``y``) of the window at every step, which holds steps t-before .. t+after.

    Examples
    --------
    >>> window_points([1.0, np.nan, 2.0, 3.0], 1, 1).tolist()
    [1.0, 2.0, 2.0, 2.0]
    """
    measured = np.concatenate(([0], np.cumsum(~np.isnan(np.asarray(y, dtype=float)))))
    steps = np.arange(measured.size - 1)
    first = np.maximum(steps - before, 0)
    last = np.minimum(steps + after + 1, steps.size)
    return (measured[last] - measured[first]).astype(float)


def critical_multiple(share, n_samples, n_windows, level=FAMILY_LEVEL):
    """Sampling standard deviations of a noise-only MAE that the behavioural spread must exceed.

    ``z_q - z_a`` of the module documentation, with q = ``share`` and
    ``a = level / n_windows``.

    Examples
    --------
    >>> round(critical_multiple(0.1, 2000, 24), 2), round(critical_multiple(0.1, 20_000, 5000), 2)
    (3.46, 4.83)
    """
    if not 0 < share < 1:
        raise SettingsError(f"the behavioural share must lie in (0, 1); got {share!r}", "percentage")
    per_window = level / max(int(n_windows), 1)
    # 1 - (1 - a)^(1/N) without losing a to rounding when it is tiny.
    tail = -math.expm1(math.log1p(-per_window) / n_samples)
    return float(norm.ppf(share) - norm.ppf(tail))


def fitted_noise_sigma(best, points, n_params):
    """Noise standard deviation from the windows' best MAEs (see the module documentation); NaN if none can tell.

    Examples
    --------
    >>> round(fitted_noise_sigma(np.array([0.38, 0.4, 5.0]), np.full(3, 21.0), 2), 3)
    0.527
    """
    usable = np.isfinite(best) & (points > n_params)
    if not usable.any():
        return float("nan")
    m = points[usable]
    return float(np.median(best[usable] * np.sqrt(m / (m - n_params))) / math.sqrt(2 / math.pi))


def noise_floor(best, threshold, points, *, n_params, share, n_samples, n_windows, sigma=None, level=FAMILY_LEVEL):
    """Which windows are informative: their behavioural MAE spread exceeds what noise alone produces.

    Parameters
    ----------
    best, threshold : ndarray (n_steps,)
        Every window's best MAE and the largest MAE of its behavioural set;
        NaN where the window had no result.
    points : ndarray (n_steps,)
        Measured points of every window (:func:`window_points`).
    n_params : int
        Parameters analysed (the fit's degrees of freedom, see the module documentation).
    share : float
        The behavioural share of the population, ``percentage / 100``.
    n_samples : int
        Parameter sets ranked in every window.
    n_windows : int
        Independent windows tested, ``ceil(n_steps / (2n+1))``.
    sigma : float, optional
        The noise standard deviation, when known; default
        :func:`fitted_noise_sigma`.
    level : float, default 0.05
        The chance that any noise-only window of the record is called informative.

    Returns
    -------
    NoiseFloor
    """
    best, threshold = np.asarray(best, dtype=float), np.asarray(threshold, dtype=float)
    points = np.asarray(points, dtype=float)
    sigma = fitted_noise_sigma(best, points, n_params) if sigma is None else float(sigma)
    multiple = critical_multiple(share, n_samples, n_windows, level)
    with np.errstate(invalid="ignore", divide="ignore"):
        floor = np.where(points > n_params, multiple * sigma * math.sqrt(1 - 2 / math.pi) / np.sqrt(points), np.nan)
        spread = threshold - best
        informative = spread > floor  # NaN compares False
    return NoiseFloor(informative=informative, spread=spread, floor=floor, sigma=sigma, multiple=multiple)


def record_noise_floor(best, threshold, points, slots, n_params, percentage, n_samples):
    """:func:`noise_floor` of an analysis whose windows hold ``slots`` steps and ``points`` measured points each.

    The one place that turns an analysis's settings into the test's: the
    batch engine, the cluster and the online replay all call it.
    """
    return noise_floor(
        best,
        threshold,
        points,
        n_params=n_params,
        share=percentage / 100,
        n_samples=n_samples,
        n_windows=math.ceil(np.asarray(points).shape[0] / slots),
    )
