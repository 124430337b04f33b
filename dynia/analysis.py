"""The fast moving-window engine: all parameters of all windows in one pass.

Shape convention (used by every function of the package)
--------------------------------------------------------
- ``y``: measured output, (n_steps,); NaN marks a missing sample.
- ``sims``: simulated outputs, (n_samples, n_steps), one row per parameter set.
- ``params``: sampled parameter sets, (n_samples, n_params).
- ``bounds``: sampling range of each parameter, (n_params, 2) as [low, high].
- results: ``ic`` (n_params, n_steps); ``ci`` (n_params, n_steps, 2) as
  [lower, upper]; ``gradient`` (n_params, n_bins, n_steps).

How it works
------------
The window at step ``t`` holds steps ``t-n .. t+n`` clipped to the record (so
the first and last ``n`` windows are truncated, as in the thesis); with
``window="trailing"`` it holds ``t-2n .. t`` instead, the same 2n+1 steps
ending at ``t`` (MCAT's "right boundary" option), so that a window's result
is known as soon as step ``t`` is logged (see :mod:`dynia.online`). The
cost of a parameter set is computed from the mean absolute error over the
points present. A window's behavioural set depends on the costs only, not on
the parameter analysed, so it is selected once per window and every
parameter's limits, information content and CLD gradient are read off it.
Time is processed in chunks, so memory grows with n_samples x chunk, never
with n_samples x n_steps; :func:`dynia.run` streams the simulation into the
same chunks, so the (n_samples, n_steps) matrix is never built.

Window sums are accumulated left to right over the window's points, so two
parameter sets whose errors agree inside a window get bit-identical costs
(ties stay ties, whatever came before the window), and ties are ranked by
sample index, exactly as the thesis's stable sort does.

Flavours
--------
``"thesis"``
    The thesis implementation (Appendix B): cost = MAE squared; behavioural
    set = the ``floor(n_samples*percentage/100)`` lowest costs (stable);
    likelihood ``1 - cost``, shifted by its minimum when negative,
    normalised; unweighted limits at sorted positions
    ``floor(c*(count-1))`` with ``c = (1-conf_level/100)/2`` and ``1-c``;
    ``IC = 1 - (upper-lower)/(high-low)``. IC and limits equal
    :func:`dynia.thesis.moving_window_calcs`. The gradient is what the
    thesis's ``cld_gradient`` sets out to compute, without its quirks: the
    likelihood mass of the behavioural values in each of ``bins`` equal bins
    of [low, high] (the CLD increase across the bin). Where every behavioural
    cost is equal and at least 1 the thesis's likelihood is 0/0; the engine
    then weights the behavioural sets equally.
``"mcat"``
    The DYNIA of Wagener's MCAT toolbox 5.1 (``id_time.m``, centred window):
    see :mod:`dynia.mcat` for the plain reference and every detail. The
    gradient has ``bins + 1`` rows, at equally spaced points from the sample
    minimum to the sample maximum, and IC is normalised by the sample range.
``"weighted"``
    The likelihood-weighted CLD of Wagener et al. (2003): as ``"thesis"``,
    but the limits are the first sorted behavioural values at which the
    cumulative likelihood reaches ``(100-conf_level)/200`` and
    ``(100+conf_level)/200``.
"""
import math
import os
from collections import deque
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from . import _checks, _fast, cld
from .result import DyniaResult

__all__ = ["moving_window", "FLAVOURS", "WINDOWS"]

FLAVOURS = ("thesis", "mcat", "weighted")
WINDOWS = ("centred", "trailing")
ENGINES = ("auto", "numba", "numpy")

# Values per working array of one time chunk: 2.5e5 float64 = 2 MB, which keeps
# the dozen passes over a chunk in cache for a few thousand samples; for many
# samples the four-halo floor of default_chunk_steps sets the size instead.
_CHUNK_VALUES = 250_000


def moving_window(y, sims, params, bounds, *, n=10, percentage=10, bins=40, conf_level=90,
                  flavour="thesis", names=None, time=None, min_points=1, chunk_steps=None,
                  workers=None, progress=False, weights=None, window="centred", engine="auto"):
    """Moving-window DYNIA of every parameter at once.

    Parameters
    ----------
    y : array_like, shape (n_steps,)
        Measured output. NaN marks a missing sample: windows use the points
        present.
    sims : array_like, shape (n_samples, n_steps)
        Simulated output of every parameter set.
    params : array_like, shape (n_samples, n_params)
        The parameter sets simulated.
    bounds : array_like, shape (n_params, 2)
        [low, high] of the range each parameter was sampled from.
    n : int, default 10
        Half window: the window at step t holds steps t-n .. t+n.
    percentage : float, default 10
        Percentage of the parameter sets kept as each window's behavioural
        set (fractions such as 0.1 are fine).
    bins : int, default 40
        Number of gradient bins (``"mcat"`` returns ``bins + 1`` points).
    conf_level : float, default 90
        Confidence level of the limits, in percent, in (0, 100).
    flavour : {"thesis", "mcat", "weighted"}
        See the module documentation.
    names : sequence of str, optional
        Parameter names (default ``p0``, ``p1``, ...).
    time : array_like, shape (n_steps,), optional
        Time of each step (default 0, 1, ...), used by plots and tables.
    min_points : int, default 1
        Windows with fewer measured points than this get NaN results.
    chunk_steps : int, optional
        Time steps per chunk (default: see :func:`default_chunk_steps`).
    workers : int, optional
        Threads analysing chunks in parallel (default: every core). Results
        do not depend on it.
    progress : bool, default False
        Show a tqdm progress bar.
    weights : array_like, shape (n_samples,), optional
        Importance weights against the uniform prior (prior density over the
        density the samples were drawn from), for samples not drawn
        uniformly; see :mod:`dynia.adaptive`. The behavioural set of a window
        is then the lowest costs holding ``percentage`` % of the weight, and
        the limits are weighted quantiles ("thesis") or quantiles of
        likelihood x weight ("weighted"). Not for ``"mcat"``.
    window : {"centred", "trailing"}, default "centred"
        Where the 2n+1 steps of the window at step t lie: ``t-n .. t+n``
        (the thesis) or ``t-2n .. t`` (ending at t, for online use). The
        trailing result at t equals the centred one at t-n wherever the
        centred window is not truncated by the end of the record.
    engine : {"auto", "numba", "numpy"}, default "auto"
        The compiled kernels of :mod:`dynia._fast` or plain numpy; both give
        bit-identical results. "auto" takes numba when it is installed and
        the flavour is "thesis" or "weighted" without ``weights`` (the
        other cases always run on numpy).

    Returns
    -------
    DyniaResult
        ``.ic`` (n_params, n_steps), ``.ci`` (n_params, n_steps, 2),
        ``.gradient`` (n_params, n_bins, n_steps), ``.bin_centres``
        (n_params, n_bins) and the settings.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.analysis import moving_window
    >>> rng = np.random.default_rng(1)
    >>> gain = rng.uniform(0, 4, 500)
    >>> u = np.r_[np.zeros(20), np.ones(40)]
    >>> sims = gain[:, None] * u
    >>> res = moving_window(2 * u, sims, gain[:, None], [[0, 4]], n=3)
    >>> float(res.ic[0, :15].max()) < 0.2 < float(res.ic[0, 30:].min())
    True
    """
    sims = np.asarray(sims, dtype=float)
    if sims.ndim != 2:
        raise ValueError(f"sims must be 2-D (n_samples, n_steps); got shape {sims.shape}")
    y = _checks.as_1d_float(y, "y", allow_nan=True)
    if sims.shape[1] != y.size:
        raise ValueError(
            f"sims has {sims.shape[1]} steps (columns) but y has {y.size}; they must match")
    params = _checks.as_2d_float(params, "params")
    if params.shape[0] != sims.shape[0]:
        raise ValueError(
            f"params has {params.shape[0]} rows but sims has {sims.shape[0]}; one row per parameter set")
    return _analyse(y, _ArrayErrors(y, sims), params, bounds, n=n, percentage=percentage, bins=bins,
                    conf_level=conf_level, flavour=flavour, names=names, time=time,
                    min_points=min_points, chunk_steps=chunk_steps, workers=workers,
                    progress=progress, weights=weights, window=window, engine=engine)


def default_chunk_steps(n_samples, halo):
    """Time steps per chunk: about ``_CHUNK_VALUES`` values per (n_samples, chunk + halo) array.

    Small enough to stay in cache for a few thousand samples, and at least
    four halos long so that re-reading the halo never dominates.
    """
    return max(1, 4 * halo, _CHUNK_VALUES // max(n_samples, 1) - halo)


def analyse_stream(y, sim_chunks, params, bounds, *, n, percentage, bins, conf_level, flavour,
                   names=None, time=None, min_points=1, chunk_steps=None, workers=None,
                   progress=False, settings=None, weights=None, window="centred", engine="auto"):
    """Moving-window DYNIA fed by simulated output in consecutive time chunks.

    ``sim_chunks`` yields (n_samples, m) arrays in time order that together
    cover ``y``; otherwise as :func:`moving_window`, which wraps this.
    ``sim_chunks`` may instead be a source of absolute errors with a
    ``rows(start, stop)`` method, such as :class:`dynia._fast.CompiledErrors`.
    """
    y = _checks.as_1d_float(y, "y", allow_nan=True)
    params = _checks.as_2d_float(params, "params")
    errors = sim_chunks if hasattr(sim_chunks, "rows") else _StreamedErrors(y, sim_chunks, params.shape[0])
    return _analyse(y, errors, params, bounds, n=n,
                    percentage=percentage, bins=bins, conf_level=conf_level, flavour=flavour,
                    names=names, time=time, min_points=min_points, chunk_steps=chunk_steps,
                    workers=workers, progress=progress, settings=settings, weights=weights,
                    window=window, engine=engine)


def compiled_engine(engine, flavour, weights=None):
    """Whether ``engine`` ("auto", "numba" or "numpy") runs the compiled kernels for this analysis."""
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {ENGINES}; got {engine!r}")
    supported = flavour in ("thesis", "weighted") and weights is None
    if engine == "numba":
        if not _fast.AVAILABLE:
            raise ValueError("engine='numba' needs numba, which is not installed (pip install numba)")
        if not supported:
            raise ValueError("engine='numba' covers the 'thesis' and 'weighted' flavours without "
                             "importance weights; use engine='numpy' or 'auto' for this analysis")
    return engine != "numpy" and supported and _fast.AVAILABLE


def flavour_analysis(flavour, compiled, params, bounds, percentage, bins, conf_level, min_points):
    """The object that analyses windows for ``flavour``, on the compiled kernels or on numpy.

    Compiled, it has ``analyse_rows(window_errors, measured, m, slots)``;
    otherwise ``analyse(mae, usable)``. Either has ``count``, ``n_bins`` and
    ``bin_centres``.
    """
    if compiled:
        return _CompiledFlavour(params, bounds, percentage, bins, conf_level, flavour, min_points)
    return _FLAVOUR_CLASSES[flavour](params, bounds, percentage, bins, conf_level)


def window_halos(n, window):
    """Steps (before, after) the window at t reaches: (n, n) centred, (2n, 0) trailing."""
    if window not in WINDOWS:
        raise ValueError(f"window must be one of {WINDOWS}; got {window!r}")
    return (n, n) if window == "centred" else (2 * n, 0)


def _analyse(y, errors, params, bounds, *, n, percentage, bins, conf_level, flavour, names,
             time, min_points, chunk_steps, progress, workers=None, settings=None, weights=None,
             window="centred", engine="auto"):
    n_samples, n_params = params.shape
    bounds = _checks.bounds_array(bounds, n_params)
    outside = (params < bounds[:, 0]) | (params > bounds[:, 1])
    if outside.any():
        row, col = np.argwhere(outside)[0]
        raise ValueError(
            f"params row {row}, column {col} = {params[row, col]} lies outside its bounds "
            f"[{bounds[col, 0]}, {bounds[col, 1]}]; samples must come from the ranges analysed")
    n = _checks.whole_number(n, "n", minimum=0)
    before, after = window_halos(n, window)
    bins = _checks.whole_number(bins, "bins", minimum=1)
    min_points = _checks.whole_number(min_points, "min_points", minimum=1)
    conf_level = _checks.open_interval(conf_level, "conf_level", 0, 100)
    percentage = _checks.percentage_value(percentage)
    if flavour not in FLAVOURS:
        raise ValueError(f"flavour must be one of {FLAVOURS}; got {flavour!r}")
    names = _parameter_names(names, n_params)
    time = np.arange(y.size, dtype=float) if time is None else _checks.as_1d_float(time, "time")
    if time.size != y.size:
        raise ValueError(f"time has {time.size} values but y has {y.size}; they must match")
    if chunk_steps is None:
        chunk_steps = default_chunk_steps(n_samples, 2 * n)
    chunk_steps = _checks.whole_number(chunk_steps, "chunk_steps", minimum=1)
    if workers is None:
        workers = os.cpu_count() or 1
    workers = 1 if flavour == "mcat" else _checks.whole_number(workers, "workers", minimum=1)

    compiled = compiled_engine(engine, flavour, weights)
    if weights is None:
        flavour_impl = flavour_analysis(flavour, compiled, params, bounds, percentage, bins, conf_level,
                                        min_points)
    else:
        if flavour == "mcat":
            raise ValueError("weights are not supported by the mcat flavour, whose behavioural set "
                             "is a block of the sorted population; use 'thesis' or 'weighted'")
        flavour_impl = _ImportanceFlavour(params, bounds, percentage, bins, conf_level,
                                          _importance_weights(weights, n_samples), flavour)
    n_steps = y.size
    ic = np.full((n_params, n_steps), np.nan)
    ci = np.full((n_params, n_steps, 2), np.nan)
    gradient = np.full((n_params, flavour_impl.n_bins, n_steps), np.nan)

    slots = before + after + 1

    def analyse_chunk(start, stop, window_errors, measured):
        if compiled:
            return start, stop, flavour_impl.analyse_rows(window_errors, measured, stop - start, slots)
        mae, present = _window_mean(window_errors, measured, stop - start, slots)
        return start, stop, flavour_impl.analyse(mae, present >= min_points)

    def store(finished):
        start, stop, (chunk_ic, chunk_ci, chunk_gradient) = finished.result()
        ic[:, start:stop] = chunk_ic
        ci[:, start:stop] = chunk_ci
        gradient[:, :, start:stop] = chunk_gradient

    starts = range(0, n_steps, chunk_steps)
    if progress:
        from tqdm.auto import tqdm
        starts = tqdm(starts, desc="DYNIA windows", unit="chunk")
    # Errors are pulled in time order (a simulation stream is sequential); the
    # windows of each chunk are then analysed on a worker. MCAT's likelihood
    # carries state from window to window, so it stays on one worker.
    with ThreadPoolExecutor(max_workers=workers) as pool:
        pending = deque()
        for start in starts:
            stop = min(start + chunk_steps, n_steps)
            pending.append(pool.submit(analyse_chunk, start, stop,
                                       *_window_inputs(errors, start, stop, before, after, n_steps,
                                                       time_major=compiled)))
            while len(pending) > workers:  # bounds the chunks held in memory
                store(pending.popleft())
        while pending:
            store(pending.popleft())

    recorded = dict(n=n, window=window, percentage=percentage, bins=bins, conf_level=conf_level,
                    flavour=flavour, min_points=min_points, n_samples=n_samples,
                    n_behavioural=flavour_impl.count, engine="numba" if compiled else "numpy")
    recorded.update(settings or {})
    return DyniaResult(names=names, samples=params, bounds=bounds, time=time, ic=ic, ci=ci,
                       gradient=gradient, bin_centres=flavour_impl.bin_centres, settings=recorded)


def _parameter_names(names, n_params):
    if names is None:
        return tuple(f"p{i}" for i in range(n_params))
    names = tuple(str(name) for name in names)
    if len(names) != n_params:
        raise ValueError(f"names has {len(names)} entries but there are {n_params} parameters")
    if len(set(names)) != len(names):
        raise ValueError(f"names must be unique; got {names}")
    return names


class _StreamedErrors:
    """Absolute errors |y - sim| over a sliding range of time, pulled from simulation chunks.

    Missing measurements (NaN in y) give an error of 0. Requests must move
    forward in time; columns before a request are dropped.
    """

    def __init__(self, y, sim_chunks, n_samples):
        self.y = y
        self._chunks = iter(sim_chunks)
        self._n_samples = n_samples
        self._start = 0  # time of the first buffered column
        self._buffer = np.zeros((n_samples, 0))

    def columns(self, start, stop):
        """Errors for times [start, stop), shape (n_samples, stop - start)."""
        self._buffer = self._buffer[:, start - self._start:]
        self._start = start
        pieces = [self._buffer]
        buffered = self._buffer.shape[1]
        while self._start + buffered < stop:
            chunk = self._next_chunk(self._start + buffered)
            pieces.append(chunk)
            buffered += chunk.shape[1]
        if len(pieces) > 1:
            self._buffer = np.concatenate(pieces, axis=1)
        return self._buffer[:, :stop - start]

    def rows(self, start, stop):
        """Errors for times [start, stop), time-major: shape (stop - start, n_samples)."""
        return np.ascontiguousarray(self.columns(start, stop).T)

    def _next_chunk(self, at):
        try:
            sims = np.asarray(next(self._chunks), dtype=float)
        except StopIteration:
            raise ValueError(f"the simulation ended at step {at}, before the {self.y.size} steps of y") from None
        if sims.ndim != 2 or sims.shape[0] != self._n_samples or sims.shape[1] == 0:
            raise ValueError(
                f"a simulation chunk at step {at} has shape {sims.shape}; expected ({self._n_samples}, m>0)")
        if at + sims.shape[1] > self.y.size:
            raise ValueError(f"the simulation runs past the {self.y.size} steps of y")
        return _absolute_errors(self.y[at:at + sims.shape[1]], sims, at)


class _ArrayErrors:
    """The same interface over a whole (n_samples, n_steps) array of simulations."""

    def __init__(self, y, sims):
        self.y = y
        self._sims = sims

    def columns(self, start, stop):
        return _absolute_errors(self.y[start:stop], self._sims[:, start:stop], start)

    def rows(self, start, stop):
        return np.ascontiguousarray(self.columns(start, stop).T)


def _absolute_errors(measured, sims, at):
    """|measured - sims| with missing measurements (NaN) giving 0; rejects non-finite sims."""
    bad = ~np.isfinite(sims)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise ValueError(f"sims holds a non-finite value for sample {row} at step {at + col}")
    errors = np.subtract(sims, measured)  # |s - y| == |y - s| bit for bit
    np.abs(errors, out=errors)
    missing = np.isnan(measured)
    if missing.any():
        errors[:, missing] = 0.0
    return errors


def _window_inputs(errors, start, stop, before, after, n_steps, time_major=False):
    """Errors and measured-point flags for the windows at steps [start, stop).

    The window at t reaches ``before`` steps back and ``after`` ahead (see
    :func:`window_halos`). Returns (n_samples, m + before + after) errors
    (transposed if ``time_major``) and (m + before + after,) flags,
    m = stop - start, where column j belongs to time start - before + j;
    times outside the record are zero columns, so every window has
    before+after+1 slots (adding 0.0 changes no sum).
    """
    lo, hi = max(start - before, 0), min(stop + after, n_steps)
    window_errors = errors.rows(lo, hi).T if time_major else errors.columns(lo, hi)
    measured = (~np.isnan(errors.y[lo:hi])).astype(float)
    width = stop - start + before + after
    offset = lo - (start - before)
    if offset or hi - lo < width:
        padded = np.zeros((window_errors.shape[0], width))
        padded[:, offset:offset + (hi - lo)] = window_errors
        counts = np.zeros(width)
        counts[offset:offset + (hi - lo)] = measured
        window_errors, measured = padded, counts
    return (np.ascontiguousarray(window_errors.T) if time_major else window_errors), measured


def _window_mean(window_errors, measured, m, slots):
    """Mean absolute error of every sample over each of the m windows of ``slots`` steps.

    Returns ``mae`` (m, n_samples) and the number of measured points per
    window (m,). Sums run left to right over each window, the order of
    :func:`dynia.thesis.moving_window_calcs`, so the result depends on the
    window's own errors only and equals the port's bit for bit.
    """
    total = window_errors[:, 0:m].copy()
    present = measured[0:m].copy()
    for shift in range(1, slots):
        total += window_errors[:, shift:shift + m]
        present += measured[shift:shift + m]
    with np.errstate(invalid="ignore", divide="ignore"):
        total /= present
    return np.ascontiguousarray(total.T), present


def lowest_stable(values, count):
    """Columns of the ``count`` smallest entries of each row, ties broken by column.

    Returns (rows, count) column indices, ascending within each row: the
    first ``count`` of a stable ascending sort, as a set.
    """
    chosen = np.argpartition(values, count - 1, axis=1)[:, :count]
    threshold = np.take_along_axis(values, chosen, axis=1).max(axis=1, keepdims=True)
    tied = (values <= threshold).sum(axis=1) > count
    if tied.any():
        chosen[tied] = _selected_columns(stable_rank_mask(values[tied], 0, count), count)
    return np.sort(chosen, axis=1)


def stable_rank_mask(values, start, stop):
    """Mark, in each row, the entries whose stable ascending rank lies in [start, stop).

    The stable rank orders equal values by their column index, as a stable
    sort does. ``values`` is (rows, n); the mask has ``stop - start`` True per row.
    """
    part = np.partition(values, (start, stop - 1), axis=1)
    low = part[:, start, None]
    high = part[:, stop - 1, None]
    mask = (values > low) & (values < high)
    equal_low = values == low
    rank_low = (values < low).sum(axis=1, keepdims=True) + np.cumsum(equal_low, axis=1) - 1
    mask |= equal_low & (rank_low >= start) & (rank_low < stop)
    equal_high = (values == high) & (high != low)
    rank_high = (values < high).sum(axis=1, keepdims=True) + np.cumsum(equal_high, axis=1) - 1
    mask |= equal_high & (rank_high < stop)
    return mask


def _selected_columns(mask, count):
    """Column indices of the True entries, (rows, count), ascending within each row."""
    return np.nonzero(mask)[1].reshape(mask.shape[0], count)


def _chunk_arrays(n_params, n_bins, rows):
    """Uninitialised ic (n_params, rows), ci (n_params, rows, 2), gradient (n_params, n_bins, rows)."""
    return np.empty((n_params, rows)), np.empty((n_params, rows, 2)), np.empty((n_params, n_bins, rows))


def _blank_unusable(ic, ci, gradient, usable):
    """NaN wherever a window had too few measured points."""
    ic[:, ~usable] = np.nan
    ci[:, ~usable] = np.nan
    gradient[:, :, ~usable] = np.nan
    return ic, ci, gradient


def _bin_centres(bounds, bins):
    """Centres of ``bins`` equal bins of each parameter's range, (n_params, bins)."""
    edges = np.linspace(bounds[:, 0], bounds[:, 1], bins + 1, axis=1)
    return (edges[:, :-1] + edges[:, 1:]) / 2


class _ThesisFlavour:
    """Cost MAE^2, lowest-cost behavioural set, likelihood 1-cost, unweighted limits."""

    def __init__(self, params, bounds, percentage, bins, conf_level):
        n_samples = params.shape[0]
        self.count = math.floor(n_samples * (percentage / 100))
        if self.count < 2:
            raise ValueError(
                f"percentage={percentage} of {n_samples} samples leaves {self.count} behavioural "
                "sets per window; at least 2 are needed (raise percentage or the number of samples)")
        self.columns = np.ascontiguousarray(params.T)
        self.bounds = bounds
        self.bins = bins
        self.n_bins = bins
        self.conf_level = conf_level
        self.bin_centres = _bin_centres(bounds, bins)

    def analyse(self, mae, usable):
        with np.errstate(over="ignore"):  # an error beyond 1e154 costs inf: still the worst
            cost = mae ** 2
        cost[~usable] = 0.0  # any finite value: these windows are blanked below
        selected = lowest_stable(cost, self.count)
        weights = cld.likelihood(np.take_along_axis(cost, selected, axis=1))
        rows = selected.shape[0]
        ic, ci, gradient = _chunk_arrays(self.columns.shape[0], self.n_bins, rows)
        for p, column in enumerate(self.columns):
            values = column[selected]
            low, high = self.bounds[p]
            ci[p] = self._limits(values, weights)
            ic[p] = 1 - (ci[p, :, 1] - ci[p, :, 0]) / (high - low)
            gradient[p] = cld.binned_mass(values, weights, low, high, self.bins).T
        return _blank_unusable(ic, ci, gradient, usable)

    def _limits(self, values, weights):
        return cld.limits(values, self.conf_level)


class _WeightedFlavour(_ThesisFlavour):
    """As the thesis, but limits where the cumulative likelihood reaches the levels."""

    def _limits(self, values, weights):
        return cld.weighted_limits(values, weights, self.conf_level)


class _CompiledFlavour:
    """The thesis and weighted flavours on the compiled kernel :func:`dynia._fast.analyse_windows`."""

    def __init__(self, params, bounds, percentage, bins, conf_level, flavour, min_points):
        reference = _ThesisFlavour(params, bounds, percentage, bins, conf_level)
        self.count = reference.count
        self.columns = reference.columns
        self.n_bins = bins
        self.bin_centres = reference.bin_centres
        self.lows = np.ascontiguousarray(bounds[:, 0])
        self.highs = np.ascontiguousarray(bounds[:, 1])
        lower_share = (1 - conf_level / 100) / 2
        self.positions = np.array([math.floor(lower_share * (self.count - 1)),
                                   math.floor((1 - lower_share) * (self.count - 1))], dtype=np.int64)
        self.levels = np.array([(100 - conf_level) / 200, (100 + conf_level) / 200])
        self.weighted = flavour == "weighted"
        self.min_points = float(min_points)

    def analyse_rows(self, window_errors, measured, m, slots):
        ic, ci, gradient = _chunk_arrays(self.columns.shape[0], self.n_bins, m)
        _fast.analyse_windows(window_errors, measured, m, slots, self.count, self.columns, self.lows,
                              self.highs, self.n_bins, self.positions, self.levels, self.weighted,
                              self.min_points, ic, ci, gradient)
        return ic, ci, gradient


def lowest_weighted(cost, prior_weights, fraction):
    """Each row's lowest costs up to the first that brings their prior weight to ``fraction``.

    Parameters
    ----------
    cost : ndarray (rows, n_samples)
    prior_weights : ndarray (n_samples,), summing to 1
    fraction : float in (0, 1]

    Returns
    -------
    order : ndarray (rows, n_samples)
        Each row's samples by ascending cost (stable).
    behavioural : ndarray of bool (rows, n_samples)
        In ``order``'s positions: True for the behavioural samples.
    """
    order = np.argsort(cost, axis=1, kind="stable")
    reached = (np.cumsum(prior_weights[order], axis=1) < fraction).sum(axis=1, keepdims=True)
    return order, np.arange(order.shape[1]) <= np.minimum(reached, order.shape[1] - 1)


def window_costs(y, sims, n, start, stop, window="centred"):
    """Thesis costs (window MAE squared) of every sample for the windows at steps [start, stop).

    Returns (stop - start, n_samples); windows without a measured point are NaN.
    """
    errors = _ArrayErrors(_checks.as_1d_float(y, "y", allow_nan=True), np.asarray(sims, dtype=float))
    before, after = window_halos(n, window)
    mae, _ = _window_mean(*_window_inputs(errors, start, stop, before, after, errors.y.size),
                          stop - start, before + after + 1)
    with np.errstate(over="ignore"):
        return mae ** 2


def _importance_weights(weights, n_samples):
    weights = _checks.as_1d_float(weights, "weights")
    if weights.size != n_samples:
        raise ValueError(f"weights has {weights.size} values but there are {n_samples} samples")
    if (weights <= 0).any():
        raise ValueError(f"weights must be positive; weights[{int(np.argmax(weights <= 0))}] is not")
    return weights / weights.sum()


class _ImportanceFlavour:
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
        self.bin_centres = _bin_centres(bounds, bins)

    def analyse(self, mae, usable):
        with np.errstate(over="ignore"):
            cost = mae ** 2
        cost[~usable] = 0.0
        order, behavioural = lowest_weighted(cost, self.prior_weights, self.fraction)
        prior = np.where(behavioural, self.prior_weights[order], 0.0)
        prior /= prior.sum(axis=1, keepdims=True)
        likelihood = 1 - np.take_along_axis(cost, order, axis=1)
        lowest = np.where(behavioural, likelihood, np.inf).min(axis=1, keepdims=True)
        likelihood = np.where(behavioural, np.where(lowest < 0, likelihood - lowest, likelihood), 0.0)
        mass = likelihood * prior
        total = mass.sum(axis=1, keepdims=True)
        mass = np.where(total > 0, mass / np.where(total > 0, total, 1), prior)  # all-equal costs >= 1
        rows = order.shape[0]
        ic, ci, gradient = _chunk_arrays(self.columns.shape[0], self.n_bins, rows)
        for p, column in enumerate(self.columns):
            values = column[order]
            low, high = self.bounds[p]
            ci[p] = cld.weighted_limits(values, mass if self.likelihood_limits else prior, self.conf_level)
            ic[p] = 1 - (ci[p, :, 1] - ci[p, :, 0]) / (high - low)
            gradient[p] = cld.binned_mass(values, mass, low, high, self.bins).T
        return _blank_unusable(ic, ci, gradient, usable)


class _McatFlavour:
    """MCAT 5.1 ``id_time.m``; the plain reference is :func:`dynia.mcat.id_time`."""

    def __init__(self, params, bounds, percentage, bins, conf_level):
        n_samples = params.shape[0]
        grouping = 100 / percentage
        if abs(grouping - round(grouping)) > 1e-9 * grouping:
            raise ValueError(
                "the mcat flavour splits the population into 100/percentage blocks; "
                f"percentage={percentage} does not divide 100 into a whole number of blocks")
        grouping = round(grouping)
        self.count = n_samples // grouping
        if self.count < 1:
            raise ValueError(
                f"percentage={percentage} of {n_samples} samples leaves no behavioural set "
                "(raise percentage or the number of samples)")
        self.block = (self.count * (grouping - 1), self.count * grouping)
        lowest, highest = params.min(axis=0), params.max(axis=0)
        if (lowest < 0).any():
            column = int(np.argmax(lowest < 0))
            raise ValueError(
                f"the mcat flavour needs non-negative parameters (MCAT's CDF knot sits at "
                f"max(min - 0.001, 0)); parameter column {column} has samples down to {lowest[column]}")
        self.columns = np.ascontiguousarray(params.T)
        self.n_bins = bins + 1
        self.bin_centres = np.linspace(lowest, highest, bins + 1, axis=1)
        self.outer_knots = np.stack([np.maximum(lowest - 0.001, 0), highest + 0.001], axis=1)
        self.span = highest - lowest
        ranks = np.arange(1, self.count + 1) / self.count
        low_level, high_level = (100 - conf_level) / 200, (100 + conf_level) / 200
        self.limit_index = [int(np.argmax(ranks > low_level)), int(np.argmax(ranks > high_level))]
        self.cdf_levels = np.concatenate([[0.0], ranks, [1.0]])
        self.every_window_nonzero = True

    def analyse(self, mae, usable):
        likelihood = self._likelihood(mae, usable)
        selected = _selected_columns(stable_rank_mask(likelihood, *self.block), self.count)
        rows = selected.shape[0]
        n_params = self.columns.shape[0]
        ic, ci, gradient = _chunk_arrays(n_params, self.n_bins, rows)
        for p, column in enumerate(self.columns):
            ordered = np.sort(column[selected], axis=1)
            ci[p] = ordered[:, self.limit_index]
            ic[p] = 1 - (ci[p, :, 1] - ci[p, :, 0]) / self.span[p]
            gradient[p] = self._cdf_slope(_nudge_ties(ordered), p).T
        return _blank_unusable(ic, ci, gradient, usable)

    def _likelihood(self, mae, usable):
        """``1 - mae/max(mae)`` (or ``1 - mae`` once a window had max 0), lifted above 0."""
        mae = np.where(usable[:, None], mae, 0.0)
        nonzero = (mae.max(axis=1) != 0) | ~usable
        # id_time.m divides only while every window so far had a non-zero maximum.
        divide = np.logical_and.accumulate(nonzero) & self.every_window_nonzero
        self.every_window_nonzero = bool(divide[-1])
        with np.errstate(invalid="ignore", divide="ignore"):
            scaled = np.where(divide[:, None], mae / mae.max(axis=1, keepdims=True), mae)
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


_FLAVOUR_CLASSES = {"thesis": _ThesisFlavour, "weighted": _WeightedFlavour, "mcat": _McatFlavour}


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
        nudged[:, k + 1] = np.where(tie, nudged[:, k + 1] + (nudged[:, k + 2] - nudged[:, k]) / 1000,
                                    nudged[:, k + 1])
        if tie.any() and k + 1 <= last and k + 1 not in visited:
            pending = sorted(set(pending) | {k + 1})
    return nudged
