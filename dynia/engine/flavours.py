"""The flavours of the moving window: how a window's behavioural set becomes limits, IC and gradient.

``"thesis"`` and ``"weighted"`` run on numpy (:class:`ThesisFlavour`,
:class:`WeightedFlavour`) or on the compiled kernels of
:mod:`dynia.engine.kernels` (:class:`CompiledFlavour`), alike to rounding (see there),
or on their numpy twin (:class:`TwinFlavour`, :mod:`dynia.engine.twin`), the kernels' numbers bit for bit;
importance-weighted samples take :class:`ImportanceFlavour`; ``"mcat"`` is
:class:`McatFlavour`. See :mod:`dynia.engine.windows` for what each computes.

With ``ic_error`` every analysis also reads IC and limits off each batch of
the samples (:func:`~dynia.settings.ic_batches`, :class:`BatchedFlavour`, and the compiled
kernel :func:`dynia.engine.kernels.batches.analyse_windows_batched`), from which
:func:`monte_carlo_errors` gives their standard errors.
"""

import math
import sys
from typing import NamedTuple

import numpy as np

from .. import _checks
from ..errors import SettingsError
from ..settings import ENGINES, FLAVOURS, ic_batches
from . import cld, kernels, twin
from .noise import quantile_position
from .selection import alike_in_size, lowest_stable, lowest_weighted_head, selected_columns, stable_rank_mask

__all__ = [
    "FLAVOURS",
    "ENGINES",
    "FLAVOUR_CLASSES",
    "compiled_engine",
    "chosen_engine",
    "takes_kernels",
    "parameter_ranks",
    "flavour_analysis",
    "bin_centres_of",
    "importance_weights",
    "monte_carlo_errors",
    "ThesisFlavour",
    "WeightedFlavour",
    "CompiledFlavour",
    "TwinFlavour",
    "ImportanceFlavour",
    "McatFlavour",
    "BatchedFlavour",
    "WindowResults",
]


class WindowResults(NamedTuple):
    """What a flavour reads off m windows.

    ``ic`` (n_params, m), ``ci`` (n_params, m, 2), ``median`` (n_params, m),
    the CLD median read off as the limits are (so it lies between them),
    ``gradient`` (n_params, n_bins, m); ``best``, ``threshold`` and ``upper`` (m,), the lowest MAE,
    the largest MAE of the behavioural set and the MAE at the population
    quantile of :func:`dynia.engine.noise.quantile_position`, what
    :mod:`dynia.engine.noise` tests (each the square root of a window cost
    for "thesis" and "weighted", taken as both engines take it; the
    population's, unweighted, with importance weights); with ``ic_error``
    ``batch_ic`` (batches, n_params, m) and ``batch_ci`` (batches, n_params,
    m, 2), else None. Every array is NaN where a window had too few
    measured points.
    """

    ic: np.ndarray
    ci: np.ndarray
    median: np.ndarray
    gradient: np.ndarray
    best: np.ndarray
    threshold: np.ndarray
    upper: np.ndarray
    batch_ic: np.ndarray | None = None
    batch_ci: np.ndarray | None = None


def compiled_engine(engine, flavour, weights=None):
    """Whether ``engine`` ("auto", "numba" or "numpy") runs the compiled kernels for this analysis."""
    if engine not in ENGINES:
        raise SettingsError(f"engine must be one of {ENGINES}; got {engine!r}")
    supported = flavour in ("thesis", "weighted") and weights is None
    if engine == "numba":
        if not kernels.AVAILABLE:
            raise SettingsError("engine='numba' needs numba, which is not installed (pip install numba)")
        if not supported:
            raise SettingsError(
                "engine='numba' covers the 'thesis' and 'weighted' flavours without "
                "importance weights; use engine='numpy' or 'auto' for this analysis"
            )
    return engine in ("auto", "numba") and supported and kernels.AVAILABLE


def chosen_engine(settings, params, n_steps, weights=None, model=None):
    """The engine that analyses a run, as its result records it: "twin", "numba" or "numpy".

    "auto" takes the compiled kernels where they can (:func:`compiled_engine`), else numpy; and, where it would take
    the kernels, their numpy twin (:mod:`dynia.engine.twin`), which gives their numbers and compiles nothing, for a
    small run that the twin covers (at most :data:`~dynia.engine.twin.AUTO_MOST_VALUES` samples x steps and
    :data:`~dynia.engine.twin.AUTO_MOST_STEPS` steps), while the process has not loaded the kernels and has run
    fewer than :data:`~dynia.engine.twin.AUTO_MOST_RUNS` analyses on the twin. "twin" refuses a run the twin does
    not cover. ``params`` (n_samples, n_params) are the sets analysed, ``model`` the model a run simulates (none for
    given simulations or errors).
    """
    engine = settings.engine
    compiled = compiled_engine(engine, settings.flavour, weights)
    small = n_steps <= twin.AUTO_MOST_STEPS and params.shape[0] * n_steps <= twin.AUTO_MOST_VALUES
    if engine == "twin" or (engine == "auto" and compiled and small and not _kernels_pay()):
        if twin.covers(settings.flavour, params, weights, settings.ic_error, model):
            return "twin"
        if engine == "twin":
            raise SettingsError(
                "engine 'twin' covers the 'thesis' and 'weighted' flavours without importance weights or ic_error, "
                "of models simulated in numpy and parameters without a negative zero; use engine 'auto', 'numba' or "
                "'numpy' for this analysis"
            )
    return "numba" if compiled else "numpy"


def _kernels_pay():
    """Whether this process is better served by the kernels than their twin, even for a small run.

    So once a run has loaded them, or after :data:`~dynia.engine.twin.AUTO_MOST_RUNS` analyses on the twin. The
    kernels' module is not imported to find out: no run loaded them while it is not.
    """
    if twin.analyses_run >= twin.AUTO_MOST_RUNS:
        return True
    return "dynia.engine.kernels.driver" in sys.modules and kernels.compiled()


def takes_kernels(settings, n_samples, n_steps, model=None):
    """Whether a run of ``n_samples`` sets over ``n_steps`` steps will analyse on the compiled kernels.

    What :func:`chosen_engine` decides, asked before the parameter sets are drawn (a negative zero among them, which
    sends a run the twin would take to the kernels, cannot be foreseen): a front-end says so before a run that may
    compile them.
    """
    return chosen_engine(settings, np.zeros((n_samples, 1)), n_steps, model=model) == "numba"


def flavour_analysis(
    flavour,
    compiled,
    params,
    bounds,
    percentage,
    bins,
    conf_level,
    min_points,
    weights=None,
    ic_error=False,
    on_twin=False,
):
    """The object that analyses windows for ``flavour``, on the compiled kernels or on numpy.

    Compiled, it has ``analyse_rows(window_errors, measured, m, slots)``
    (and, ``on_twin``, runs on the kernels' numpy twin, :class:`TwinFlavour`, which has no batches);
    otherwise ``analyse(mae, usable)``. Either returns the
    :class:`WindowResults` of the windows and has ``count``, ``n_bins`` and
    ``bin_centres``. With importance ``weights`` (n_samples,) it is an
    :class:`ImportanceFlavour`. With ``ic_error`` it also has ``batches``
    (see :func:`~dynia.settings.ic_batches`) and the results carry ``batch_ic`` and
    ``batch_ci``, the IC and limits of every batch; the mcat flavour has no
    batches yet (:class:`~dynia.errors.SettingsError`).
    """
    if ic_error:
        if flavour == "mcat":
            raise SettingsError(
                "ic_error is not available for the mcat flavour yet (its likelihood carries state from window "
                "to window); use flavour 'thesis' or 'weighted'",
                "ic_error",
            )
        batches = ic_batches(params.shape[0], percentage)
        if compiled:
            return CompiledFlavour(params, bounds, percentage, bins, conf_level, flavour, min_points, batches)
        parts = [
            flavour_analysis(
                flavour,
                False,
                params[batch::batches],
                bounds,
                percentage,
                bins,
                conf_level,
                min_points,
                weights=None if weights is None else np.asarray(weights)[batch::batches],
            )
            for batch in range(batches)
        ]
        whole = flavour_analysis(flavour, False, params, bounds, percentage, bins, conf_level, min_points, weights)
        return BatchedFlavour(whole, parts)
    if weights is not None:
        if flavour == "mcat":
            raise SettingsError(
                "weights are not supported by the mcat flavour, whose behavioural set "
                "is a block of the sorted population; use 'thesis' or 'weighted'"
            )
        return ImportanceFlavour(
            params, bounds, percentage, bins, conf_level, importance_weights(weights, params.shape[0]), flavour
        )
    if compiled:
        kind = TwinFlavour if on_twin else CompiledFlavour
        return kind(params, bounds, percentage, bins, conf_level, flavour, min_points)
    return FLAVOUR_CLASSES[flavour](params, bounds, percentage, bins, conf_level)


def monte_carlo_errors(batch_ic, batch_ci):
    """Standard errors of IC and limits from their batch estimates (batch means).

    The estimate from all n samples varies about as much as one from a
    batch of n/B samples does divided by B (the variance of these
    estimators falls as 1/n), so the standard error is the standard
    deviation of the B batch estimates (ddof 1) over sqrt(B). NaN where the
    IC is (a window with too few measured points); 0 where every batch
    agrees.

    Parameters
    ----------
    batch_ic : ndarray (B, n_params, m)
    batch_ci : ndarray (B, n_params, m, 2)

    Returns
    -------
    ic_se : ndarray (n_params, m)
    ci_se : ndarray (n_params, m, 2)

    Examples
    --------
    >>> import numpy as np
    >>> ic_se, ci_se = monte_carlo_errors(np.array([0.5, 0.7]).reshape(2, 1, 1), np.zeros((2, 1, 1, 2)))
    >>> round(float(ic_se[0, 0]), 6), ci_se.tolist()
    (0.1, [[[0.0, 0.0]]])
    """
    root = math.sqrt(batch_ic.shape[0])
    return np.std(batch_ic, axis=0, ddof=1) / root, np.std(batch_ci, axis=0, ddof=1) / root


def _chunk_arrays(n_params, n_bins, rows):
    """Uninitialised ic (n_params, rows), ci (n_params, rows, 2), median (n_params, rows) and gradient.

    The gradient is (n_params, n_bins, rows).
    """
    return (
        np.empty((n_params, rows)),
        np.empty((n_params, rows, 2)),
        np.empty((n_params, rows)),
        np.empty((n_params, n_bins, rows)),
    )


def _population_quantile(values):
    """Each row's value at :func:`~dynia.engine.noise.quantile_position` of its sorted order, (m,)."""
    position = quantile_position(values.shape[1])
    return np.partition(values, position, axis=1)[:, position]


def _blank_unusable(ic, ci, median, gradient, behavioural_mae, upper, usable):
    """The windows' results, NaN wherever a window had too few measured points.

    ``behavioural_mae`` (m, count) holds the behavioural set's MAEs (or
    costs, then ``behavioural_mae`` is their square root), any order;
    ``upper`` (m,) the MAE at the population quantile of the noise floor.
    """
    ic[:, ~usable] = np.nan
    ci[:, ~usable] = np.nan
    median[:, ~usable] = np.nan
    gradient[:, :, ~usable] = np.nan
    best = np.where(usable, behavioural_mae.min(axis=1), np.nan)
    threshold = np.where(usable, behavioural_mae.max(axis=1), np.nan)
    return WindowResults(ic, ci, median, gradient, best, threshold, np.where(usable, upper, np.nan))


def bin_centres_of(bounds, bins):
    """Centres of ``bins`` equal bins of each parameter's range, (n_params, bins)."""
    edges = np.linspace(bounds[:, 0], bounds[:, 1], bins + 1, axis=1)
    return (edges[:, :-1] + edges[:, 1:]) / 2


class ThesisFlavour:
    """Cost MAE^2, lowest-cost behavioural set, likelihood 1-cost, unweighted limits and median."""

    weighted = False

    def __init__(self, params, bounds, percentage, bins, conf_level):
        n_samples = params.shape[0]
        self.count = math.floor(n_samples * (percentage / 100))
        if self.count < 2:
            raise SettingsError(
                f"percentage={percentage} of {n_samples} samples leaves {self.count} behavioural "
                "sets per window; at least 2 are needed (raise percentage or the number of samples)"
            )
        self.columns = np.ascontiguousarray(params.T)
        self.bounds = bounds
        self.bins = bins
        self.n_bins = bins
        self.conf_level = conf_level
        self.bin_centres = bin_centres_of(bounds, bins)

    def analyse(self, mae, usable):
        return self._read_off(mae, usable, self.n_bins)

    def band(self, mae, usable):
        """``(ic, ci)`` of :meth:`analyse` without the gradient."""
        return self._read_off(mae, usable, 0)[:2]

    def _read_off(self, mae, usable, n_bins):
        with np.errstate(over="ignore"):  # an error beyond 1e154 costs inf: still the worst
            cost = mae**2
        cost[~usable] = 0.0  # any finite value: these windows are blanked below
        selected = lowest_stable(cost, self.count)
        behavioural_cost = np.take_along_axis(cost, selected, axis=1)
        with np.errstate(invalid="ignore"):  # costs overflowed to inf tie: the engine blanks such windows
            weights = cld.likelihood(behavioural_cost)
        rows = selected.shape[0]
        ic, ci, median, gradient = _chunk_arrays(self.columns.shape[0], n_bins, rows)
        for p, column in enumerate(self.columns):
            values = column[selected]
            low, high = self.bounds[p]
            ci[p], median[p] = cld.band_and_median(values, weights, self.conf_level, weighted=self.weighted)
            ic[p] = 1 - (ci[p, :, 1] - ci[p, :, 0]) / (high - low)
            if n_bins:
                gradient[p] = cld.binned_mass(values, weights, low, high, self.bins).T
        upper = np.sqrt(_population_quantile(cost))
        return _blank_unusable(ic, ci, median, gradient, np.sqrt(behavioural_cost), upper, usable)


class WeightedFlavour(ThesisFlavour):
    """As the thesis, but limits (and median) where the cumulative likelihood reaches the levels (and 0.5)."""

    weighted = True


def parameter_ranks(columns):
    """``(ranks, ordered)`` of ``columns`` (n_params, n_samples), as the window analysis takes them.

    ``ordered`` holds each row sorted, ``ranks`` every sample's position in
    its row's stable sort (ties in the order of the samples); see
    :func:`~dynia.engine.kernels.readoff.analyse_windows` and its twin.

    Examples
    --------
    >>> ranks, ordered = parameter_ranks(np.array([[0.3, 0.1, 0.3]]))
    >>> ranks.tolist(), ordered.tolist()
    ([[1, 0, 2]], [[0.1, 0.3, 0.3]])
    """
    order = np.argsort(columns, axis=1, kind="stable")
    ranks = np.empty(columns.shape, dtype=np.int64)
    np.put_along_axis(ranks, order, np.arange(columns.shape[1])[None, :], axis=1)
    return ranks, np.ascontiguousarray(np.take_along_axis(columns, order, axis=1))


class CompiledFlavour:
    """The thesis and weighted flavours on the compiled kernel :func:`~dynia.engine.kernels.readoff.analyse_windows`.

    With ``batches`` > 0 (see :func:`~dynia.settings.ic_batches`) on
    :func:`~dynia.engine.kernels.batches.analyse_windows_batched`, which also reads IC and
    limits off each batch of samples, from the same window costs.
    """

    @staticmethod
    def _window_kernel():
        """The kernel that analyses the windows, imported (with numba) when a flavour first analyses."""
        return kernels.analyse_windows

    def __init__(self, params, bounds, percentage, bins, conf_level, flavour, min_points, batches=0):
        reference = ThesisFlavour(params, bounds, percentage, bins, conf_level)
        self.count = reference.count
        self.columns = reference.columns
        self.ranks, self.ordered = parameter_ranks(self.columns)
        self.n_bins = bins
        self.bin_centres = reference.bin_centres
        self.lows = np.ascontiguousarray(bounds[:, 0])
        self.highs = np.ascontiguousarray(bounds[:, 1])
        self.conf_level = conf_level
        self.positions = self._positions(self.count)
        self.levels = np.array([(100 - conf_level) / 200, (100 + conf_level) / 200])
        self.weighted = flavour == "weighted"
        self.min_points = float(min_points)
        self.batches = batches
        n_samples = params.shape[0]
        self.upper_position = quantile_position(n_samples)
        # Batch b holds samples b, b + batches, ...: its size and count as ThesisFlavour would find them.
        self.batch_counts = np.array(
            [math.floor(len(range(b, n_samples, batches)) * (percentage / 100)) for b in range(batches)],
            dtype=np.int64,
        )
        self.batch_positions = np.array([self._positions(count) for count in self.batch_counts], dtype=np.int64)
        # Every sample's batch, and the batch of the sample at every rank of every parameter: fixed for the run.
        self.batch_of = np.arange(n_samples, dtype=np.int64) % max(batches, 1)
        self.batch_at_rank = np.empty_like(self.ranks)
        np.put_along_axis(self.batch_at_rank, self.ranks, np.broadcast_to(self.batch_of, self.ranks.shape), axis=1)
        # The brackets the kernels' selections carry from window to window (see analyse_windows's track and
        # analyse_windows_batched's tracks), NaN before the first block.
        self._tracks = (np.full(6, np.nan), np.full((batches, 2), np.nan), np.full(batches, np.nan))

    def _positions(self, count):
        lower_share = (1 - self.conf_level / 100) / 2
        return np.array(
            [math.floor(lower_share * (count - 1)), math.floor((1 - lower_share) * (count - 1))], dtype=np.int64
        )

    def analyse_rows(self, window_errors, measured, m, slots):
        """The :class:`WindowResults` of m windows from their error rows and measured flags (see the kernel)."""
        return self._analyse(window_errors, measured, m, slots)

    def analyse_sums(self, sums, present):
        """The :class:`WindowResults` of the windows whose error sums are ``sums`` (m, n_samples), time-major.

        ``present`` (m,) holds each window's measured points; the sums come
        from :meth:`dynia.engine.kernels.driver.CompiledErrors.window_sums` and are
        overwritten.
        """
        return self._analyse(sums, present, sums.shape[0], 0)

    def _analyse(self, window_errors, measured, m, slots):
        n_params = self.columns.shape[0]
        ic, ci, median, gradient = _chunk_arrays(n_params, self.n_bins, m)
        extreme_costs = np.empty((3, m))
        common = (
            window_errors,
            measured,
            m,
            slots,
            (self.count, self.upper_position),
            (self.columns, self.ranks, self.ordered),
            (self.lows, self.highs),
            self.n_bins,
            (self.positions, self.levels, self.weighted),
            self.min_points,
            (ic, ci, median, gradient, extreme_costs),
        )
        # Where the last block analysed left its brackets: this block's first window starts its selections there
        # rather than among every sample. Blocks analysed side by side each take whichever finished last; which one,
        # changes only how long a selection takes, never its result.
        tracks = tuple(np.copy(track) for track in self._tracks)
        # The square roots are taken here, as the numpy flavours take them.
        if not self.batches:
            self._window_kernel()(*common, tracks[0])
            self._tracks = tracks
            return WindowResults(ic, ci, median, gradient, *np.sqrt(extreme_costs))
        batch_ic, batch_ci = np.empty((self.batches, n_params, m)), np.empty((self.batches, n_params, m, 2))
        batches = (self.batch_counts, self.batch_positions, self.batch_of, self.batch_at_rank)
        kernels.analyse_windows_batched(*common, tracks, batches, (batch_ic, batch_ci))
        self._tracks = tracks
        return WindowResults(ic, ci, median, gradient, *np.sqrt(extreme_costs), batch_ic, batch_ci)


class TwinFlavour(CompiledFlavour):
    """:class:`CompiledFlavour` on the numpy twin of its kernel (:func:`dynia.engine.twin.analyse_windows`).

    The kernel's numbers bit for bit, and nothing to compile; no Monte Carlo batches.
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        twin.analyses_run += 1

    @staticmethod
    def _window_kernel():
        return twin.analyse_windows


def importance_weights(weights, n_samples):
    weights = _checks.as_1d_float(weights, "weights")
    if weights.size != n_samples:
        raise SettingsError(f"weights has {weights.size} values but there are {n_samples} samples")
    if (weights <= 0).any():
        raise SettingsError(f"weights must be positive; weights[{int(np.argmax(weights <= 0))}] is not")
    return weights / weights.sum()


class ImportanceFlavour:
    """The thesis and weighted flavours for samples drawn from another density than the prior.

    Each sample carries its importance weight (prior over proposal density),
    normalised to sum to 1. The behavioural set of a window is its lowest
    costs up to and including the first that brings their weight to
    ``percentage`` %: the estimate of the prior's lowest-cost fraction. Its
    values are weighted by importance for the limits ("thesis": weighted
    quantiles at (100 -/+ conf_level)/200) and by importance x likelihood for
    the gradient and, in "weighted", for the limits too. With equal weights
    this is the uniform analysis up to the quantile convention.
    """

    def __init__(self, params, bounds, percentage, bins, conf_level, prior_weights, flavour):
        self.prior_weights = prior_weights
        self.fraction = percentage / 100
        self.count = None  # the behavioural set's size varies from window to window
        self.columns = np.ascontiguousarray(params.T)
        self.bounds = bounds
        self.bins = bins
        self.n_bins = bins
        self.conf_level = conf_level
        self.likelihood_limits = flavour == "weighted"
        self.bin_centres = bin_centres_of(bounds, bins)
        self.largest = self.columns.max(axis=1)

    def analyse(self, mae, usable):
        return self._read_off(mae, usable, self.n_bins)

    def band(self, mae, usable):
        """``(ic, ci)`` of :meth:`analyse` without the gradient."""
        return self._read_off(mae, usable, 0)[:2]

    def _read_off(self, mae, usable, n_bins):
        with np.errstate(over="ignore"):
            cost = mae**2
        cost[~usable] = 0.0
        # Only the head of each window's cost order that holds a behavioural set is formed: the samples beyond
        # weigh nothing, so they change no cumulative weight, bin mass or first value reaching a level.
        order, behavioural = lowest_weighted_head(cost, self.prior_weights, self.fraction)
        ranked_cost = np.take_along_axis(cost, order, axis=1)
        sizes = behavioural.sum(axis=1)
        ic, ci, median, gradient = _chunk_arrays(self.columns.shape[0], n_bins, cost.shape[0])
        # Windows whose sets are alike in size are read off together, as wide as the largest of them.
        for group in alike_in_size(sizes):
            width = sizes[group].max()
            ci[:, group], median[:, group], gradient[:, :, group] = self._read_off_heads(
                ranked_cost[group, :width], order[group, :width], behavioural[group, :width], cost.shape[1], n_bins
            )
        for p, (low, high) in enumerate(self.bounds):
            ic[p] = 1 - (ci[p, :, 1] - ci[p, :, 0]) / (high - low)
        # The behavioural costs ascend in rank order: the first and the last are the lowest and the largest.
        ends = np.stack([ranked_cost[:, 0], np.take_along_axis(ranked_cost, sizes[:, None] - 1, axis=1)[:, 0]], axis=1)
        upper = np.sqrt(_population_quantile(cost))
        return _blank_unusable(ic, ci, median, gradient, np.sqrt(ends), upper, usable)

    def _read_off_heads(self, ranked_cost, order, behavioural, n_samples, n_bins):
        """Limits (n_params, rows, 2), median (n_params, rows) and gradient (n_params, n_bins, rows) of the heads.

        ``ranked_cost``, ``order`` and ``behavioural`` (rows, k) are the heads
        of the windows' cost orders (:func:`~dynia.engine.selection.lowest_weighted_head`)
        out of ``n_samples``.
        """
        prior = np.where(behavioural, self.prior_weights[order], 0.0)
        prior /= _row_sums_over(prior, n_samples)
        likelihood = 1 - ranked_cost
        lowest = np.where(behavioural, likelihood, np.inf).min(axis=1, keepdims=True)
        likelihood = np.where(behavioural, np.where(lowest < 0, likelihood - lowest, likelihood), 0.0)
        mass = likelihood * prior
        total = _row_sums_over(mass, n_samples)
        mass = np.where(total > 0, mass / np.where(total > 0, total, 1), prior)  # all-equal costs >= 1
        limit_weights = _with_weightless_column(mass if self.likelihood_limits else prior)
        rows = order.shape[0]
        _, ci, median, gradient = _chunk_arrays(self.columns.shape[0], n_bins, rows)
        for p, column in enumerate(self.columns):
            values = column[order]
            # Where rounding leaves the CLD short of a level, the whole population's largest value is read off:
            # a weightless last column holds it.
            ci[p], median[p] = cld.band_and_median(
                np.concatenate([values, np.broadcast_to(self.largest[p], (rows, 1))], axis=1),
                limit_weights,
                self.conf_level,
                weighted=True,
            )
            if n_bins:
                gradient[p] = cld.binned_mass(values, mass, *self.bounds[p], self.bins).T
        return ci, median, gradient


def _row_sums_over(values, n_columns):
    """Each row's sum as numpy forms it over ``n_columns`` columns, ``values`` first and zeros after, (rows, 1).

    numpy's pairwise summation groups a row by its length, so the zeros are
    summed too: the totals are those of the whole population's row, bit for bit.
    """
    padded = np.zeros((values.shape[0], n_columns))
    padded[:, : values.shape[1]] = values
    return padded.sum(axis=1, keepdims=True)


def _with_weightless_column(weights):
    """``weights`` (rows, k) with a column of zeros appended, (rows, k + 1)."""
    return np.concatenate([weights, np.zeros((weights.shape[0], 1))], axis=1)


class BatchedFlavour:
    """A numpy flavour that also reads IC and limits off every batch of the samples.

    ``whole`` analyses all samples; ``parts[b]`` the samples of batch b
    (b, b + B, ..., see :func:`~dynia.settings.ic_batches`), each a flavour of its own with
    its own behavioural count (importance weights renormalised within the
    batch). ``analyse(mae, usable)`` returns the :class:`WindowResults` of
    ``whole`` with ``batch_ic`` and ``batch_ci``; every batch's numbers are
    those of its samples analysed alone, bit for bit, as on the compiled
    kernel.
    """

    def __init__(self, whole, parts):
        self.whole = whole
        self.parts = parts
        self.batches = len(parts)
        self.count, self.n_bins, self.bin_centres = whole.count, whole.n_bins, whole.bin_centres

    def analyse(self, mae, usable):
        results = self.whole.analyse(mae, usable)
        bands = [part.band(mae[:, batch :: self.batches], usable) for batch, part in enumerate(self.parts)]
        return results._replace(batch_ic=np.stack([ic for ic, _ in bands]), batch_ci=np.stack([ci for _, ci in bands]))


class McatFlavour:
    """MCAT 5.1 ``id_time.m``; the plain reference is :func:`dynia.reference.mcat.id_time`."""

    def __init__(self, params, bounds, percentage, bins, conf_level):
        n_samples = params.shape[0]
        grouping = 100 / percentage
        if abs(grouping - round(grouping)) > 1e-9 * grouping:
            raise SettingsError(
                "the mcat flavour splits the population into 100/percentage blocks; "
                f"percentage={percentage} does not divide 100 into a whole number of blocks"
            )
        grouping = round(grouping)
        self.count = n_samples // grouping
        if self.count < 1:
            raise SettingsError(
                f"percentage={percentage} of {n_samples} samples leaves no behavioural set "
                "(raise percentage or the number of samples)"
            )
        self.block = (self.count * (grouping - 1), self.count * grouping)
        lowest, highest = params.min(axis=0), params.max(axis=0)
        if (lowest < 0).any():
            column = int(np.argmax(lowest < 0))
            raise SettingsError(
                f"the mcat flavour needs non-negative parameters (MCAT's CDF knot sits at "
                f"max(min - 0.001, 0)); parameter column {column} has samples down to {lowest[column]}"
            )
        self.columns = np.ascontiguousarray(params.T)
        self.n_bins = bins + 1
        self.bin_centres = np.linspace(lowest, highest, bins + 1, axis=1)
        self.outer_knots = np.stack([np.maximum(lowest - 0.001, 0), highest + 0.001], axis=1)
        self.span = highest - lowest
        ranks = np.arange(1, self.count + 1) / self.count
        low_level, high_level = (100 - conf_level) / 200, (100 + conf_level) / 200
        self.limit_index = [int(np.argmax(ranks > low_level)), int(np.argmax(ranks > high_level))]
        # The median read off as the limits are, at level 0.5: between them, since the ranks ascend.
        self.median_index = int(np.argmax(ranks > 0.5))
        self.cdf_levels = np.concatenate([[0.0], ranks, [1.0]])
        self.every_window_nonzero = True

    def analyse(self, mae, usable):
        likelihood = self._likelihood(mae, usable)
        selected = selected_columns(stable_rank_mask(likelihood, *self.block), self.count)
        rows = selected.shape[0]
        n_params = self.columns.shape[0]
        ic, ci, median, gradient = _chunk_arrays(n_params, self.n_bins, rows)
        for p, column in enumerate(self.columns):
            ordered = np.sort(column[selected], axis=1)
            ci[p] = ordered[:, self.limit_index]
            median[p] = ordered[:, self.median_index]
            ic[p] = 1 - (ci[p, :, 1] - ci[p, :, 0]) / self.span[p]
            gradient[p] = self._cdf_slope(_nudge_ties(ordered), p).T
        # MCAT ranks by MAE itself, so its behavioural set's MAEs are read off directly.
        upper = _population_quantile(mae)
        return _blank_unusable(ic, ci, median, gradient, np.take_along_axis(mae, selected, axis=1), upper, usable)

    def _likelihood(self, mae, usable):
        """``1 - mae/max(mae)`` (or ``1 - mae`` once a window had max 0), lifted above 0."""
        mae = np.where(usable[:, None], mae, 0.0)
        nonzero = (mae.max(axis=1) != 0) | ~usable
        # id_time.m divides only while every window so far had a non-zero maximum. A window without enough measured
        # points is blanked later and breaks no run of divisions, but is not divided (0 / 0 would rank NaNs).
        divide = np.logical_and.accumulate(nonzero) & self.every_window_nonzero
        self.every_window_nonzero = bool(divide[-1])
        with np.errstate(invalid="ignore", divide="ignore"):
            scaled = np.where((divide & usable)[:, None], mae / mae.max(axis=1, keepdims=True), mae)
        likelihood = 1 - scaled
        lowest = likelihood.min(axis=1, keepdims=True)
        return np.where(lowest <= 0, likelihood - lowest + 1000 * np.finfo(float).eps, likelihood)

    def _cdf_slope(self, nudged, p):
        """Unit-spaced gradient of the interpolated CDF at the grid points, NaN -> 0."""
        lower_knot, upper_knot = self.outer_knots[p]
        cdf = np.empty((nudged.shape[0], self.n_bins))
        for row, values in enumerate(nudged):
            knots = np.concatenate([[lower_knot], values, [upper_knot]])
            cdf[row] = np.interp(self.bin_centres[p], knots, self.cdf_levels)
        if self.n_bins < 2:
            return np.zeros_like(cdf)
        return np.nan_to_num(np.gradient(cdf, axis=1), nan=0.0)


FLAVOUR_CLASSES = {"thesis": ThesisFlavour, "weighted": WeightedFlavour, "mcat": McatFlavour}


def _nudge_ties(ordered):
    """MCAT's tie nudge on each row of sorted values, scanning left to right.

    For k = 0 .. count-3, a value equal to its predecessor is raised by
    (value after - predecessor)/1000. Only positions inside runs of equal
    values can change, so the scan visits just those (and the position after
    each change), in order, vectorised over rows.
    """
    nudged = ordered.copy()
    last = nudged.shape[1] - 3
    pending = sorted(set(np.nonzero((nudged[:, :-1] == nudged[:, 1:]).any(axis=0))[0]) & set(range(last + 1)))
    visited = set()
    while pending:
        k = pending.pop(0)
        if k in visited:
            continue
        visited.add(k)
        tie = nudged[:, k] == nudged[:, k + 1]
        nudged[:, k + 1] = np.where(tie, nudged[:, k + 1] + (nudged[:, k + 2] - nudged[:, k]) / 1000, nudged[:, k + 1])
        if tie.any() and k + 1 <= last and k + 1 not in visited:
            pending = sorted(set(pending) | {k + 1})
    return nudged
