"""The noise floor: which windows tell parameter sets apart beyond what measurement noise alone does.

A window's information content is read off its behavioural set, the lowest
costs of the Monte Carlo population. When the window's data are noise only
(the sets' outputs there differ by much less than the noise), the ranking
that picks that set is a ranking of noise, and a narrow band is an accident
of it (of exact ties, too: sets whose outputs are equal tie, and the stable
sort keeps the first ones by index). Two tests ask two questions of every
window, both against what noise alone does.

The two statistics
------------------
Three mean absolute errors (MAE) of every window come out of the engine's
selection: the best ``best``, the behavioural threshold ``threshold`` (the
largest MAE inside the behavioural set, the count-th smallest) and
``upper``, the MAE at the population quantile :data:`NOISE_FLOOR_QUANTILE`
(0.9): the ``floor(0.9 (N - 1))``-th smallest of the N samples' MAEs,
counted from 0 (:func:`quantile_position`; importance weights are not used
for it, it is a quantile of the samples drawn).

*Discrimination*, ``upper - best``, answers: does the window tell parameter
values apart at all? Does the worst-fitting tenth of the sampled box fit
clearly worse than the best, beyond noise? It decides the mask
``informative``. On thesis example 1 after the last input step (at 399) the
output decays as 70 exp(-(t-399)/3): until about step 430 slow, high-gain
sets still predict several units there and are clearly ruled out, though
every fast or small-gain set predicts about 0 and those tie. Such a window
does discriminate, and only the population statistic sees it.

*Behavioural spread*, ``threshold - best``, answers the narrower question
whether the *band* is a ranking of noise: when the behavioural set ties
within noise, which of its members are kept, and so the band, is decided by
the noise realisation. It gives the verdict reason ``noise_ranked``
(:mod:`dynia.verdicts`), which keeps a max IC from being called identified
even in an informative window: the windows of example 1 from about step 417
to 430 discriminate, yet their behavioural sets tie.

A quantile of the population rather than its maximum: the maximum is one
set, the most extreme corner of the box, whose misfit says as little about
the window as an outlier does; the tenth of the box that fits worst is a
share of the population, as the behavioural set is, and its MAE is as
stable. A lower quantile such as the median leaves the window as soon as
half of the box ties; on example 1 the median minus the best falls below
its floor by step 420 while the window still rules out a tenth of the box.

The null hypothesis
-------------------
H0: within the window the residuals of the parameter sets are exchangeable
noise, so which set fits best is decided by the noise realisation, not by
the parameters. The noise is assumed normal and stationary with standard
deviation sigma and autocorrelation rho_k at lag k, the same over the
record (white noise is rho_k = 0). The MAE of m consecutive noise points
then has mean ``sigma sqrt(2/pi)`` and standard deviation
``s = sigma sqrt(1 - 2/pi) sqrt(f / m)``, ``f = 1 + 2 sum_{k<m} (1 - k/m)
rho_k`` (:func:`size_factor`: the m points count as ``m / f`` independent
ones), and by the central limit theorem is close to normal. That f is the
one of the mean of the residuals themselves, which bounds those of their
absolute values and of their signs (for normal noise about rho_k^2 and
``(2/pi) arcsin rho_k``): a smooth stretch of noise is a level the sets
can fit, and a set's MAE moves with it as with the mean of the residuals,
not of independent points. Under H0 with residuals correlated across
sets with correlation rho (they share the noise: rho near 1 when the outputs
nearly agree), MAE_i = mu + s (sqrt(rho) Z_0 + sqrt(1 - rho) Z_i), so any
difference of two order statistics is ``s sqrt(1 - rho)`` times that of
independent normals: largest for independent residuals (rho = 0). That case
is the least favourable, and a test sized for it holds for every rho.

For N independent normal MAEs, the MAE at population quantile q sits at
``z_q = Phi^-1(q)`` (its own spread, about ``s sqrt(q(1-q)/N) / phi(z_q)``,
is a few hundredths of s and is left out) and the minimum falls below
``mu + s z`` with probability ``1 - (1 - Phi(z))^N``. The difference of the
quantile and the best exceeds noise, H0 rejected at level a, when

    quantile MAE - best > (z_q - z_a) s,    z_a = Phi^-1(1 - (1 - a)^(1/N)),

``multiple = z_q - z_a`` (:func:`critical_multiple`): q = 0.9 for the
discrimination, q = the behavioural share for the behavioural spread. A
record of ``n_steps`` has ``W = ceil(n_steps / (2n+1))`` disjoint windows
(the overlapping ones share their data, so W is the number of independent
tests); Bonferroni over them, ``a = level / W`` with ``level`` = 5 %, keeps
the chance that any noise-only stretch of the record is called informative
at 5 %. The multiple grows slowly with N and W (see the examples of
:func:`critical_multiple`: thesis example 1 has N = 2000 and W = 24, a
record of 10^5 steps W = 5000). The MAE of few points is skewed to the
right, so its left tail is lighter than the normal one: the normal
approximation makes the floor a little higher, not lower.

The noise level and its autocorrelation
---------------------------------------
Both come from the best fits' residuals.

*The windows' best fits.* Every window's best MAE divided by
``sqrt(2/pi)`` (the MAE of normal noise), the median over the windows.
The minimum over many sets is biased low, but not as the minimum of N
independent MAEs is (sets share parameters, so their fits are one
p-parameter family, not N independent tries): the best of a dense sample is
close to the best fit of the p parameters to the window's m points, whose
residuals are smaller by ``sqrt((m - p)/m)`` (least squares: the expected
residual sum of squares is ``sigma^2 (m - p)``); that factor is divided out.
Windows with ``m <= p`` points say nothing about the noise and are left out.
The median is robust to the windows where the model cannot fit (their best
MAE holds the misfit too) while they are fewer than half. On thesis
examples 1 and 2 (sigma 0.5 and 0.2) the estimate lands within 12 % of the
truth. Under coloured noise a window's fit also absorbs the slow part of
the noise (a level over the window is a gain to fit), so this estimate is
low: 0.85 of sigma at lag-1 autocorrelation 0.9 in 21-step windows, 0.6 at
0.98.

*The record's best fit.* As the errors stream by, every front-end adds
each set's absolute errors over the record, step by step in time order
(:func:`add_record_errors`: the batch engine, the cluster and the online
replay cut the record differently and find the same totals bit for bit).
The set with the lowest total is simulated once more with its ``2 p``
nearest sets (:func:`record_fit`), and its residuals ``y - sim`` are
projected off the differences of their outputs: a Gauss-Newton step
within the sample, which takes off the set's misfit of the parameters, a
smooth error of the response that is autocorrelated however white the
noise (on thesis example 1 it gives a lag-1 autocorrelation of up to 0.7
before the projection, within 0.15 of 0 after). Memory: one value a step.
From these residuals:

- the autocorrelations rho_1, rho_2, ... up to lag 2n (the lags a window
  holds), cut before the first one at most ``2 / sqrt(N_r)`` (N_r residuals
  present), the two-sigma limit of a white series' estimate
  (:func:`residual_autocorrelation`): white residuals keep no lag in about
  97.5 % of records, so their floor is the white one (f = 1), and a
  negative estimate never lowers it. f is computed for the full window of
  2n+1 steps; truncated windows and windows with missing points, whose f
  is smaller, get a floor a little too high;

The level sigma stays the windows' estimate above, not the record fit's
residual level: where the model cannot fit a stretch, the record fit's
residuals hold the misfit, and a floor raised by it would call the very
windows that show the misfit (bands that disagree from one stretch to
another, :mod:`dynia.verdicts`) noise. On the shipped heating record the
residual level is 2.44 against the windows' 0.443; with it 9 % of the
windows fell below the floor and the gain's disagreeing stretches were left
out as tied. The windows' estimate is low under coloured noise (above),
which the measured false-window shares below include.

So the floor holds for any stationary noise whose autocorrelation the
record-best fit's residuals show. What those residuals hold that is no
noise counts as noise: where the model cannot fit a stretch (a misfit
smooth in time), the autocorrelation rises and the floor with it; fewer
windows are informative, never more. The
estimate is one for the whole record: noise whose colour or level changes
along it gets the record's average; errors that grow with the output
(relative gauging errors) are smaller than sigma where the output is small,
so windows there that do discriminate can fall below the floor. A
population of unrelated outputs, not one model's family over its
parameters, puts the minimum MAE far below the best fit's (the minimum of N
independent MAEs): there the windows' estimate is low; give sigma to
:func:`noise_floor` when it is known.

Measured in ``notebooks/ch2_method.py`` (section "The noise floor under
coloured noise"; 20 records of 500 steps, first-order model, 2000 samples,
n = 10, AR(1) noise of SD 1 with lag-1 autocorrelation 0, 0.5, 0.9, 0.98):
how many pure-noise records (K in [0, 1] on input levels in [0, 1], every
set's output within one noise SD) still show an informative window, against
the white-noise floor, and which share of the windows of a response of up to
6 noise SDs is informative. The counts are printed by that report
(``reports/ch2_method.html``) from its run, so they stay those of the code.

Examples
--------
>>> import numpy as np
>>> best = np.full(4, 0.4)
>>> floor = noise_floor(best, np.array([0.4, 0.45, 1.5, np.nan]), np.array([0.4, 0.4, 0.41, np.nan]),
...                     np.full(4, 21.0), n_params=2, share=0.1, n_samples=2000, n_windows=1)
>>> floor.informative.tolist(), round(floor.multiple, 2)
([False, False, True, False], 5.33)
>>> (floor.behavioural_spread <= floor.behavioural_floor).tolist()
[True, True, True, False]
"""

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

# ndtri is the normal quantile (scipy.stats.norm.ppf calls it); scipy.stats itself takes a second to import.
from scipy.special import ndtri

from ..errors import SettingsError

__all__ = [
    "NoiseFloor",
    "noise_floor",
    "record_noise_floor",
    "critical_multiple",
    "quantile_position",
    "fitted_noise_sigma",
    "window_points",
    "add_record_errors",
    "RecordFit",
    "record_fit",
    "residual_autocorrelation",
    "size_factor",
    "steady_size_factor",
    "FAMILY_LEVEL",
    "NOISE_FLOOR_QUANTILE",
    "RESIDUAL_CHUNK",
    "floor_settings",
    "floor_fields",
]

# The chance that any noise-only stretch of a record is called informative (Bonferroni over its windows).
FAMILY_LEVEL = 0.05
# Steps per chunk of the record-best set's residuals (record_fit): its sums are cut there.
RESIDUAL_CHUNK = 65_536
# The population quantile whose MAE the discrimination compares with the best (see the module documentation).
NOISE_FLOOR_QUANTILE = 0.9


@dataclass(frozen=True, eq=False)
class NoiseFloor:
    """The noise floor of every window: what :func:`noise_floor` returns.

    Attributes
    ----------
    informative : ndarray (n_steps,) bool
        The discrimination exceeds its floor; False where a window had no
        result or too few points to judge.
    discrimination : ndarray (n_steps,)
        The MAE at population quantile :data:`NOISE_FLOOR_QUANTILE` minus
        the best MAE; NaN where no result.
    floor : ndarray (n_steps,)
        ``multiple`` sampling standard deviations of the MAE of the window's
        points of noise ``sigma``; NaN where the window has at most
        ``n_params`` points.
    behavioural_spread : ndarray (n_steps,)
        Behavioural threshold MAE minus best MAE; NaN where no result.
    behavioural_floor : ndarray (n_steps,)
        The same as ``floor`` with ``behavioural_multiple``: the behavioural
        set ties within noise where ``behavioural_spread`` is at most this.
    best : ndarray (n_steps,)
        Every window's best MAE, what ``sigma`` is estimated from; NaN where
        no result. With ``discrimination`` and ``behavioural_spread`` it
        gives back the three MAEs, so that a record that grows (``dynia
        follow``) can be judged again without analysing its windows again.
    sigma : float
        The noise level estimated from the best fits (NaN when no window
        could give it).
    multiple, behavioural_multiple : float
        The critical multiples of :func:`critical_multiple` for the
        quantile and for the behavioural share.
    autocorrelation : float
        The lag-1 autocorrelation estimated from the record-best set's
        residuals (NaN when none were given).
    size_factor : float
        A window of m points counts as ``m / size_factor`` independent ones
        (:func:`size_factor`; 1 for white residuals).
    record_fit : ndarray (n_params,) or None
        The record's fit within the sample (:class:`RecordFit` ``values``),
        where the front-ends' least squares of the whole record start
        (:func:`dynia.fit.record_least_squares`); None when the analysis had
        no record fit.
    """

    informative: np.ndarray
    discrimination: np.ndarray
    floor: np.ndarray
    behavioural_spread: np.ndarray
    behavioural_floor: np.ndarray
    best: np.ndarray
    sigma: float
    multiple: float
    behavioural_multiple: float
    autocorrelation: float = math.nan
    size_factor: float = 1.0
    record_fit: np.ndarray | None = None


def quantile_position(n_samples):
    """0-based sorted position of the MAE at population quantile :data:`NOISE_FLOOR_QUANTILE` among ``n_samples``.

    ``floor(0.9 (n_samples - 1))``: every engine reads the same order
    statistic of its costs, so their floors agree as the costs do (bit for
    bit between runs of one engine, to rounding between the numpy and the
    compiled engine, :mod:`dynia.engine.kernels`).

    Examples
    --------
    >>> quantile_position(2000), quantile_position(1)
    (1799, 0)
    """
    return math.floor(NOISE_FLOOR_QUANTILE * (n_samples - 1))


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


# A follower judges every new step with the multiple of its record's windows so far: the same few values, again.
@functools.lru_cache(maxsize=256)
def critical_multiple(quantile, n_samples, n_windows, level=FAMILY_LEVEL):
    """Sampling standard deviations of a noise-only MAE that the MAE at ``quantile`` minus the best must exceed.

    ``z_q - z_a`` of the module documentation, with q = ``quantile``, the
    population quantile compared with the best (:data:`NOISE_FLOOR_QUANTILE`
    for the discrimination, the behavioural share for the behavioural
    spread), and ``a = level / n_windows``.

    Examples
    --------
    >>> round(critical_multiple(0.9, 2000, 24), 2), round(critical_multiple(0.1, 2000, 24), 2)
    (6.03, 3.46)
    >>> round(critical_multiple(0.9, 20_000, 5000), 2)
    7.39
    """
    if not 0 < quantile < 1:
        raise SettingsError(
            f"the quantile compared with the best MAE must lie in (0, 1); got {quantile!r} "
            "(the behavioural one is percentage / 100)",
            "percentage",
        )
    per_window = level / max(int(n_windows), 1)
    # 1 - (1 - a)^(1/N) without losing a to rounding when it is tiny.
    tail = -math.expm1(math.log1p(-per_window) / n_samples)
    return float(ndtri(quantile) - ndtri(tail))


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


def add_record_errors(totals, rows):
    """Add time-major absolute errors ``rows`` (m, n_samples) to every sample's running record total, in place.

    Step by step in time order, whatever the chunks: every front-end
    (batch, cluster, online) cuts the record differently and must find the
    same totals bit for bit, hence the same record-best set.

    Examples
    --------
    >>> totals = np.zeros(2)
    >>> add_record_errors(totals, np.array([[1.0, 2.0], [0.5, 0.25]]))
    >>> totals.tolist()
    [1.5, 2.25]
    """
    # One C-ordered block, running total first: numpy reduces it row after row.
    block = np.empty((rows.shape[0] + 1, totals.size))
    block[0] = totals
    block[1:] = rows
    # A set whose simulation overflows gets an infinite total: it is never the best.
    with np.errstate(over="ignore", invalid="ignore"):
        np.add.reduce(block, axis=0, out=totals)


@dataclass(frozen=True, eq=False)
class RecordFit:
    """The record-best set with its Gauss-Newton step: what :func:`record_fit` returns.

    Attributes
    ----------
    residuals : ndarray (n_steps,)
        ``y`` minus the record-best set's output, projected off the output
        differences of its nearest sets, times a power of two (NaN where
        ``y`` is).
    values : ndarray (n_params,)
        The record's least-squares fit within the sample: the record-best
        set plus the Gauss-Newton step of the Jacobian estimated from its
        nearest sets (the set itself where the step leaves their
        neighbourhood, see :func:`record_fit`); a start for the least
        squares of :func:`dynia.fit.record_least_squares`.
    """

    residuals: np.ndarray
    values: np.ndarray


# The Gauss-Newton step is taken only within this many times the distance of the farthest neighbour used: beyond,
# the linearisation from that neighbourhood says nothing (a flat direction, or strong curvature).
_STEP_REACH = 4.0


def record_fit(y, params, bounds, totals, simulations, chunk_steps=RESIDUAL_CHUNK):
    """The record-best set, its Gauss-Newton step and its residuals: the noise estimate of the floor.

    The set with the lowest record total absolute error (``totals``) fits
    the record only as well as the sample allows: its misfit, output
    differences of a smooth response, is autocorrelated even when the noise
    is white. The linearised fit around it removes that: the residuals
    ``r = y - sim_best`` are projected off the output differences ``D`` of
    its ``2 p`` nearest sets (in the parameter box scaled to unit ranges), a
    Gauss-Newton step within the sample. ``simulations(indices)`` yields
    the simulated outputs of those sets, (len(indices), m) arrays in time
    order covering the record; it is called twice, so that memory holds
    one series (8 bytes a step) and chunks of ``chunk_steps``, never the
    sets' whole outputs. The residuals are multiplied by a power of two that
    brings the record's largest magnitude near 1 (what the floor reads of
    them, their autocorrelation, does not depend on it, and records near the
    floating-point limits neither overflow nor underflow).

    The same sums give the record's least-squares fit in the parameters
    (``values``), a start for the least squares of
    :func:`dynia.fit.record_least_squares`: the neighbours' parameter offsets ``P`` (2p x p) and
    ``D`` (2p x m) give the Jacobian by least squares, ``J^T = A D`` with
    ``A = (P^T P)^-1 P^T`` (central differences, where the neighbours lie on
    either side), so ``J^T J = A D D^T A^T`` and ``J^T r = A D r`` need only
    the sums already formed. Where the step would leave the neighbourhood by
    more than four times the farthest neighbour's distance, the
    linearisation is not trusted and ``values`` is the record-best set
    itself.

    Returns a :class:`RecordFit`, or None when the outputs overflow all the same.

    Examples
    --------
    >>> t = np.arange(200.0)
    >>> gains = np.array([[1.9], [2.1], [1.0], [3.0], [1.7]])
    >>> sims = gains * (1 - np.exp(-t / 10))
    >>> y = 2.05 * (1 - np.exp(-t / 10)) + 0.1 * np.cos(t)
    >>> fit = record_fit(y, gains, np.array([[0.0, 4.0]]), np.abs(y - sims).sum(axis=1), lambda rows: [sims[rows]])
    >>> bool(np.abs(4 * fit.residuals - 0.1 * np.cos(t)).max() < 0.01), round(float(fit.values[0]), 2)
    (True, 2.05)
    """
    y = np.asarray(y, dtype=float)
    best = int(np.argmin(np.fmin(totals, np.inf)))  # a NaN total (a diverged set) is never the best
    widths = np.where(bounds[:, 1] > bounds[:, 0], bounds[:, 1] - bounds[:, 0], 1.0)
    scaled = (params - bounds[:, 0]) / widths
    distance = np.sum((scaled - scaled[best]) ** 2, axis=1)
    distance[best] = np.inf
    count = min(2 * params.shape[1], params.shape[0] - 1)
    nearest = np.argsort(distance, kind="stable")[:count]
    rows = [best, *nearest.tolist()]
    largest = np.nanmax(np.abs(y)) if np.any(~np.isnan(y)) else 0.0
    scale = 2.0 ** -np.frexp(largest)[1] if 0 < largest < np.inf else 1.0  # exact: a power of two
    residuals = np.empty(y.size)
    gram, projection = np.zeros((count, count)), np.zeros(count)
    with np.errstate(over="ignore", invalid="ignore"):
        for start, chunk in _time_chunks(simulations(rows), chunk_steps):
            stop = start + chunk.shape[1]
            chunk = chunk * scale
            part = residuals[start:stop]
            np.subtract(y[start:stop] * scale, chunk[0], out=part)
            directions = chunk[1:] - chunk[0]
            measured = ~np.isnan(part)
            gram += directions[:, measured] @ directions[:, measured].T
            projection += directions[:, measured] @ part[measured]
    if np.isinf(residuals).any() or not (np.isfinite(gram).all() and np.isfinite(projection).all()):
        return None  # outputs beyond floating point: nothing to say about the noise
    if count:
        step = np.linalg.lstsq(gram, projection, rcond=1e-10)[0]
        for start, chunk in _time_chunks(simulations(rows), chunk_steps):
            residuals[start : start + chunk.shape[1]] -= step @ ((chunk[1:] - chunk[0]) * scale)
    return RecordFit(residuals, _parameter_step(params, best, nearest, widths, gram, projection))


def _parameter_step(params, best, nearest, widths, gram, projection):
    """:class:`RecordFit` ``values`` from the neighbours' sums (see :func:`record_fit`)."""
    if not nearest.size:
        return params[best].astype(float)
    # In unit ranges, so that the rank decisions do not depend on the parameters' units.
    offsets = (params[nearest] - params[best]) / widths
    spread = np.linalg.pinv(offsets, rcond=1e-10)  # A = (P^T P)^-1 P^T, (p, 2p)
    step = np.linalg.pinv(spread @ gram @ spread.T, rcond=1e-10, hermitian=True) @ (spread @ projection)
    reach = _STEP_REACH * math.sqrt(float(np.max(np.sum(offsets**2, axis=1))))
    if not (np.all(np.isfinite(step)) and math.sqrt(float(step @ step)) <= reach):
        return params[best].astype(float)
    return (params[best] + step * widths).astype(float)


def _time_chunks(chunks, size):
    """(first step, chunk) of a stream of (k, m) chunks, re-cut at the multiples of ``size`` steps.

    Fixed cuts make the sums over them, and so the residuals, the same
    whichever chunks a front-end's simulation comes in.
    """
    start, pending, held = 0, [], 0
    for chunk in chunks:
        pending.append(np.asarray(chunk, dtype=float))
        held += pending[-1].shape[1]
        if held >= size:
            joined = np.concatenate(pending, axis=1) if len(pending) > 1 else pending[0]
            whole = held - held % size
            for first in range(0, whole, size):
                yield start + first, joined[:, first : first + size]
            start += whole
            pending, held = [joined[:, whole:]], held - whole
    if held:
        yield start, np.concatenate(pending, axis=1) if len(pending) > 1 else pending[0]


def residual_autocorrelation(residuals, max_lag):
    """Autocorrelations of a residual series at lags 1 .. up to ``max_lag``, cut at the first not above noise.

    ``residuals`` (NaN where missing) is centred and overwritten. Lag k's
    estimate is the mean product of the pairs k steps apart, both present,
    over the variance. The sequence stops before the first lag whose
    estimate is at most ``2 / sqrt(n)`` (n present values), the two-sigma
    limit of a white series' estimate: white residuals give an empty
    sequence in about 97.5 % of records, and a negative lag-1 estimate never
    shrinks the floor. Returns the sequence kept and the lag-1 estimate
    (NaN when there are fewer than 3 values).

    Examples
    --------
    >>> rho, first = residual_autocorrelation(np.array([1.0, 1, 1, -1, -1, -1] * 20), 3)
    >>> np.round(rho, 2).tolist(), round(first, 2)
    ([0.34], 0.34)
    """
    present = ~np.isnan(residuals)
    count = int(present.sum())
    if count < 3:
        return np.empty(0), math.nan
    gaps = count < residuals.size
    residuals -= np.mean(residuals[present]) if gaps else np.mean(residuals)
    if gaps:
        residuals[~present] = 0.0  # a missing value adds nothing to any lag's products
    variance = float(np.dot(residuals, residuals)) / count
    if variance == 0:
        return np.empty(0), math.nan
    limit = 2 / math.sqrt(count)
    kept, first = [], math.nan
    for lag in range(1, min(max_lag, residuals.size - 1) + 1):
        pairs = np.count_nonzero(present[:-lag] & present[lag:]) if gaps else residuals.size - lag
        rho = float(np.dot(residuals[:-lag], residuals[lag:])) / max(pairs, 1) / variance
        if lag == 1:
            first = rho
        if not rho > limit:
            break
        kept.append(rho)
    return np.array(kept), first


def size_factor(rho, points):
    """How many times the variance of the mean of ``points`` correlated values exceeds that of independent ones.

    ``1 + 2 sum_k (1 - k/m) rho_k`` over the lags k < m = ``points``: a
    window of m points counts as ``m / size_factor`` independent ones.

    Examples
    --------
    >>> size_factor(np.empty(0), 21), round(size_factor(0.9 ** np.arange(1, 30), 21), 2)
    (1.0, 11.37)
    """
    lags = np.arange(1, min(len(rho), max(int(points) - 1, 0)) + 1)
    return float(1 + 2 * np.sum((1 - lags / points) * np.asarray(rho)[: lags.size]))


def steady_size_factor(y, fitted, sigma, slots):
    """The noise's own :func:`size_factor` for windows of ``slots`` steps, read where the process is steady.

    The record fit's residuals ``y - fitted`` hold the noise and the model's
    misfit, and both can be smooth in time: a slowly wandering disturbance
    (AR(1) noise of lag-1 autocorrelation 0.98) and a gain that fits one
    half of the record but not the other look alike in their
    autocorrelation. Where the fitted output is steady (it moves by less
    than ``sigma / slots`` a step, so less than one noise standard deviation
    over a window) a misfit of the dynamics is gone and one of the gain is a
    constant. Runs of at least ``slots`` such steps are kept where the
    measured output is steady too (its straight line over the run moves by
    at most ``2 sigma``: a process still settling where the model has, or
    moving with the operating point, is misfit); within them, each less its
    straight line, what remains is the noise. The autocorrelations of those
    runs (pairs within one run, cut as :func:`residual_autocorrelation` cuts
    them) give the factor. NaN where no run is kept: then the noise cannot
    be told from the misfit.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> flat = np.zeros(400)
    >>> round(steady_size_factor(rng.normal(0, 1, 400), flat, 1.0, 21), 2)
    1.0
    >>> slow = np.convolve(rng.normal(0, 1, 900), np.ones(30) / 30, mode="valid")[:400]
    >>> bool(steady_size_factor(slow, flat, 0.5, 21) > 3)
    True
    """
    y, fitted = np.asarray(y, dtype=float), np.asarray(fitted, dtype=float)
    with np.errstate(invalid="ignore"):
        steady = np.abs(np.diff(fitted, prepend=fitted[:1])) <= sigma / slots
    steady &= np.isfinite(y)
    edges = np.flatnonzero(np.diff(np.r_[0, steady.astype(np.int8), 0]))
    # The kept runs end to end, each less its straight line, with NaN between them so that no pair spans two.
    pieces = []
    for start, stop in zip(edges[::2], edges[1::2]):
        if stop - start < slots:
            continue
        steps = np.arange(stop - start, dtype=float)
        drift = np.polynomial.polynomial.polyfit(steps, y[start:stop], 1)[1] * (stop - start - 1)
        if abs(drift) > 2 * sigma:
            continue
        residuals = y[start:stop] - fitted[start:stop]
        line = np.polynomial.polynomial.polyfit(steps, residuals, 1)
        pieces += [residuals - np.polynomial.polynomial.polyval(steps, line), np.full(slots, np.nan)]
    if not pieces:
        return math.nan
    rho, _ = residual_autocorrelation(np.concatenate(pieces), slots - 1)
    return size_factor(rho, slots)


def noise_floor(
    best,
    upper,
    threshold,
    points,
    *,
    n_params,
    share,
    n_samples,
    n_windows,
    sigma=None,
    level=FAMILY_LEVEL,
    size_factor=1.0,
    autocorrelation=math.nan,
):
    """Which windows are informative, and where the behavioural set ties within noise.

    Parameters
    ----------
    best, upper, threshold : ndarray (n_steps,)
        Every window's best MAE, its MAE at population quantile
        :data:`NOISE_FLOOR_QUANTILE` (:func:`quantile_position`) and the
        largest MAE of its behavioural set; NaN where the window had no
        result.
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
        The chance that any noise-only window of the record is called
        informative (and the same for a behavioural set called untied).
    size_factor : float, default 1
        A window of m points counts as ``m / size_factor`` independent
        points of noise (:func:`size_factor`; 1: white noise).
    autocorrelation : float, optional
        The lag-1 autocorrelation behind ``size_factor``, recorded only.

    Returns
    -------
    NoiseFloor
    """
    best, upper = np.asarray(best, dtype=float), np.asarray(upper, dtype=float)
    threshold, points = np.asarray(threshold, dtype=float), np.asarray(points, dtype=float)
    sigma = fitted_noise_sigma(best, points, n_params) if sigma is None else float(sigma)
    multiple = critical_multiple(NOISE_FLOOR_QUANTILE, n_samples, n_windows, level)
    # With share 1 the behavioural set is the whole population: no quantile below the top compares it with the
    # best, so the spread test is undefined there (NaN: no window reads as tied).
    behavioural_multiple = critical_multiple(share, n_samples, n_windows, level) if share < 1 else math.nan
    # In place where it can be: on a long record every temporary is 8 bytes a step.
    with np.errstate(invalid="ignore", divide="ignore"):
        noise_sd = np.sqrt(points)
        np.divide(sigma * math.sqrt(1 - 2 / math.pi) * math.sqrt(size_factor), noise_sd, out=noise_sd)
        noise_sd[points <= n_params] = np.nan
        floor = noise_sd * multiple
        discrimination = upper - best
        informative = discrimination > floor  # NaN compares False
    return NoiseFloor(
        informative=informative,
        discrimination=discrimination,
        floor=floor,
        behavioural_spread=threshold - best,
        behavioural_floor=np.multiply(noise_sd, behavioural_multiple, out=noise_sd),
        best=best,
        sigma=sigma,
        multiple=multiple,
        behavioural_multiple=behavioural_multiple,
        autocorrelation=float(autocorrelation),
        size_factor=float(size_factor),
    )


def record_noise_floor(best, upper, threshold, points, slots, n_params, percentage, n_samples, fit=None):
    """:func:`noise_floor` of an analysis whose windows hold ``slots`` steps and ``points`` measured points each.

    The one place that turns an analysis's settings into the test's: the
    batch engine, the cluster and the online replay all call it. ``fit``,
    from :func:`record_fit`, gives the autocorrelation of the module
    documentation from its residuals (which are overwritten) and the
    start of the record's least squares (``record_fit``); without it the
    floor assumes white noise.
    """
    sigma, factor, first = fitted_noise_sigma(best, points, n_params), 1.0, math.nan
    if fit is not None:
        rho, first = residual_autocorrelation(fit.residuals, slots - 1)
        factor = size_factor(rho, slots)
    floor = noise_floor(
        best,
        upper,
        threshold,
        points,
        n_params=n_params,
        share=percentage / 100,
        n_samples=n_samples,
        n_windows=math.ceil(np.asarray(points).shape[0] / slots),
        sigma=sigma,
        size_factor=factor,
        autocorrelation=first,
    )
    return floor if fit is None else dataclasses.replace(floor, record_fit=fit.values)


def floor_settings(floor):
    """What an analysis records of its ``floor`` in ``result.run`` (:class:`~dynia.settings.RunRecord` fields)."""
    return dict(
        noise_sigma=floor.sigma,
        noise_multiple=floor.multiple,
        noise_floor_quantile=NOISE_FLOOR_QUANTILE,
        behavioural_multiple=floor.behavioural_multiple,
        noise_autocorrelation=floor.autocorrelation,
        noise_size_factor=floor.size_factor,
        record_fit=None if floor.record_fit is None else tuple(floor.record_fit),
    )


def floor_fields(floor):
    """The :class:`~dynia.result.DyniaResult` fields of ``floor``."""
    return dict(
        informative=floor.informative,
        discrimination=floor.discrimination,
        noise_floor=floor.floor,
        behavioural_spread=floor.behavioural_spread,
        behavioural_floor=floor.behavioural_floor,
        best_mae=floor.best,
    )
