"""The moving window: every parameter of every window in one pass, in time chunks.

Shape convention (used by every function of the package)
--------------------------------------------------------
- ``y``: measured output, (n_steps,); NaN marks a missing sample.
- ``sims``: simulated outputs, (n_samples, n_steps), one row per parameter set.
- ``params``: sampled parameter sets, (n_samples, n_params).
- ``bounds``: sampling range of each parameter, (n_params, 2) as [low, high].
- results: ``ic`` (n_params, n_steps); ``ci`` (n_params, n_steps, 2) as
  [lower, upper]; ``median`` (n_params, n_steps), the CLD median read off
  as the limits are; ``gradient`` (n_params, n_bins, n_steps).

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

On numpy (:func:`window_mean`) window sums are accumulated left to right
over the window's points, so two parameter sets whose errors agree inside a
window get bit-identical costs (ties stay ties, whatever came before the
window), and ties are ranked by sample index, exactly as the thesis's
stable sort does. The compiled engine keeps compensated running sums
instead, which cost the same for any n and are within rounding of these;
see :mod:`dynia.engine.kernels` for how close, and the contract between
the two engines.

Flavours
--------
``"thesis"``
    The thesis implementation (Appendix B): cost = MAE squared; behavioural
    set = the ``floor(n_samples*percentage/100)`` lowest costs (stable);
    likelihood ``1 - cost``, shifted by its minimum when negative,
    normalised; unweighted limits at sorted positions
    ``floor(c*(count-1))`` with ``c = (1-conf_level/100)/2`` and ``1-c``;
    ``IC = 1 - (upper-lower)/(high-low)``. IC and limits equal
    :func:`dynia.reference.thesis.moving_window_calcs`. The gradient is what the
    thesis's ``cld_gradient`` sets out to compute, without its quirks: the
    likelihood mass of the behavioural values in each of ``bins`` equal bins
    of [low, high] (the CLD increase across the bin). Where every behavioural
    cost is equal and at least 1 the thesis's likelihood is 0/0; the engine
    then weights the behavioural sets equally.
``"mcat"``
    The DYNIA of Wagener's MCAT toolbox 5.1 (``id_time.m``, centred window):
    see :mod:`dynia.reference.mcat` for the plain reference and every detail. The
    gradient has ``bins + 1`` rows, at equally spaced points from the sample
    minimum to the sample maximum, and IC is normalised by the sample range.
``"weighted"``
    The likelihood-weighted CLD of Wagener et al. (2003): as ``"thesis"``,
    but the limits are the first sorted behavioural values at which the
    cumulative likelihood reaches ``(100-conf_level)/200`` and
    ``(100+conf_level)/200``.

Magnitudes
----------
The cost is the MAE squared, which overflows for MAEs beyond about 1.3e154
and underflows below about 1.5e-154 (to 0 near 1e-162): then every set
ties and the behavioural set is the first ones by index. DYNIA on MAEs does
not depend on the unit of the output (scaling data and model output by one
factor keeps every ranking), so the engine analyses a record whose largest
``|y|`` lies beyond 2^332 (about 8.7e99) or below 2^-332 (about 1.1e-100)
with every absolute error multiplied by the power of two
(:func:`error_scale`) that brings that largest value to the edge: exact in
floating point, so the ranking is that of the exact MAEs, and the MAEs the
noise floor reads are divided back. Where even then the behavioural set's
MAE overflows (a model output more than about 1e54 times the data's
magnitude), the window is left without results rather than rank ties,
with an :class:`OverflowedWindowsWarning`; when no window is left, the
analysis stops with a :class:`~dynia.errors.DataError` saying so.

The Monte Carlo error (``ic_error=True``)
-----------------------------------------
IC and limits are estimates from a finite Monte Carlo sample. With
``ic_error`` the samples are split into B interleaved batches (sample i in
batch ``i mod B``; B = 10, fewer so that every batch keeps at least 5
behavioural sets, an error when not even 2 can: see
:func:`dynia.settings.ic_batches`). In the same pass, every window's
costs, already formed for all samples, are read off each batch with the
batch's own behavioural count and the flavour's own arithmetic, exactly as
if the batch had been analysed alone. The result's ``ic_se`` (n_params,
n_steps) and ``ci_se`` (n_params, n_steps, 2) are the standard deviations
of the B batch estimates over sqrt(B) (batch means: these estimators'
variance falls as 1/n). Importance-weighted samples renormalise their
weights within each batch. Not for ``"mcat"`` yet.

How honest that is (``benchmarks/honesty.py``, ``python -m benchmarks.bench --case
ic-error-honesty``, checked in ``tests/test_ic_error.py``): over 20 seeds
on thesis examples 1 and 2, at 10 % of 2000 samples and at 0.1 % of
50 000, the median over the steps of the predicted error lies within 0.75
and 1.40 times the median seed-to-seed standard deviation for every
parameter. A batch reads its limits off a behavioural set a tenth the size
of the whole one, at sorted positions whose spread does not shrink exactly
as 1/n; no correction factor is applied.
"""

import dataclasses
import math
import warnings
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

from .. import _checks
from ..errors import DataError, SettingsError
from ..io.arrays import ResultArrays, result_arrays
from ..progress import progress_bar
from ..result import DyniaResult
from ..settings import FLAVOURS, WINDOWS, AnalysisSettings, RunRecord
from .error_sources import ArrayErrors, ScaledErrors, StreamedErrors
from .flavours import chosen_engine, flavour_analysis, monte_carlo_errors
from .noise import add_record_errors, floor_fields, floor_settings, record_fit, record_noise_floor, window_points

__all__ = [
    "moving_window",
    "analyse_stream",
    "analyse_errors",
    "window_costs",
    "window_halos",
    "default_chunk_steps",
    "window_inputs",
    "window_mean",
    "plain_window_mean",
    "error_scale",
    "blank_overflowed",
    "report_overflowed",
    "OverflowedWindowsWarning",
    "FLAVOURS",
    "WINDOWS",
]

# Records whose largest |y| lies beyond 2^SAFE_EXPONENT or below 2^-SAFE_EXPONENT have their errors scaled
# (see "Magnitudes" in the module documentation): at that edge MAE^2 keeps 54 decades of room either side.
SAFE_EXPONENT = 332

# Values per working array of one time chunk: 2.5e5 float64 = 2 MB, which keeps
# the dozen passes over a chunk in cache for a few thousand samples; for many
# samples the four-halo floor of default_chunk_steps sets the size instead.
_CHUNK_VALUES = 250_000

# Samples per block of window_mean: its time-major errors and sums of a block stay in cache for windows of
# a hundred steps.
_MEAN_BLOCK = 4096


def moving_window(
    y,
    sims,
    params,
    bounds,
    *,
    n=10,
    percentage=10,
    bins=40,
    conf_level=90,
    flavour="thesis",
    names=None,
    time=None,
    min_points=1,
    chunk_steps=None,
    workers=None,
    progress=False,
    weights=None,
    window="centred",
    engine="auto",
    ic_error=False,
    dtype="float64",
    store=None,
):
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
    progress : bool or "auto", default False
        Show a tqdm progress bar (:mod:`dynia.progress`).
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
    engine : {"auto", "numba", "numpy", "twin"}, default "auto"
        The compiled kernels of :mod:`dynia.engine.kernels` or plain numpy; their
        costs agree to rounding and their IC, limits and median are identical
        wherever a window's behavioural set is (see that module). "twin" is
        the kernels' numpy twin (:mod:`dynia.engine.twin`), their numbers bit
        for bit with nothing to compile. "auto" takes the twin for a small run
        it covers, else numba when it is installed and
        the flavour is "thesis" or "weighted" without ``weights`` (the
        other cases always run on numpy): :func:`~dynia.engine.flavours.chosen_engine`.
    ic_error : bool, default False
        Also estimate the Monte Carlo standard errors of IC and limits, by
        batch means in the same pass (see the module documentation). Not
        for ``"mcat"``.
    dtype : {"float64", "float32"}, default "float64"
        Type of the time-dependent result arrays; float32 values are the
        float64 results rounded (see :mod:`dynia.io.arrays`).
    store : str or os.PathLike, optional
        Write those arrays to this netCDF file as they are produced (complete
        and renamed into place when the analysis ends) and return a result
        that reads them from it; memory then does not grow with them (see
        :mod:`dynia.io.arrays`). A :class:`dynia.io.arrays.ResultArrays` or
        :class:`~dynia.io.arrays.ResultFile` may be given instead, whose owner
        commits it.

    Returns
    -------
    DyniaResult
        ``.ic`` (n_params, n_steps), ``.ci`` (n_params, n_steps, 2),
        ``.median`` (n_params, n_steps), ``.gradient`` (n_params, n_bins,
        n_steps), ``.bin_centres``
        (n_params, n_bins) and the settings; with ``ic_error`` also
        ``.ic_se`` (n_params, n_steps) and ``.ci_se`` (n_params, n_steps,
        2), and ``run.ic_batches``, the number of batches.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.engine import moving_window
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
        raise DataError(f"sims must be 2-D (n_samples, n_steps); got shape {sims.shape}")
    y = _checks.as_1d_float(y, "y", allow_nan=True)
    if sims.shape[1] != y.size:
        raise SettingsError(f"sims has {sims.shape[1]} steps (columns) but y has {y.size}; they must match")
    params = _checks.as_2d_float(params, "params")
    if params.shape[0] != sims.shape[0]:
        raise SettingsError(
            f"params has {params.shape[0]} rows but sims has {sims.shape[0]}; one row per parameter set"
        )
    return analyse_stream(
        y,
        ArrayErrors(y, sims),
        params,
        bounds,
        n=n,
        percentage=percentage,
        bins=bins,
        conf_level=conf_level,
        flavour=flavour,
        names=names,
        time=time,
        min_points=min_points,
        chunk_steps=chunk_steps,
        workers=workers,
        progress=progress,
        weights=weights,
        window=window,
        engine=engine,
        ic_error=ic_error,
        dtype=dtype,
        store=store,
        simulations=lambda rows: [sims[rows]],
    )


def default_chunk_steps(n_samples, halo):
    """Time steps per chunk: about ``_CHUNK_VALUES`` values per (n_samples, chunk + halo) array.

    Small enough to stay in cache for a few thousand samples, and at least
    four halos long so that re-reading the halo never dominates.
    """
    return max(1, 4 * halo, _CHUNK_VALUES // max(n_samples, 1) - halo)


def analyse_stream(
    y,
    sim_chunks,
    params,
    bounds,
    *,
    n,
    percentage,
    bins,
    conf_level,
    flavour,
    names=None,
    time=None,
    min_points=1,
    chunk_steps=None,
    workers=None,
    progress=False,
    settings=None,
    run=None,
    weights=None,
    window="centred",
    engine="auto",
    ic_error=False,
    dtype="float64",
    store=None,
    simulations=None,
):
    """Moving-window DYNIA fed by simulated output in consecutive time chunks.

    ``sim_chunks`` yields (n_samples, m) arrays in time order that together
    cover ``y``; otherwise as :func:`moving_window`, which wraps this.
    ``sim_chunks`` may instead be a source of absolute errors with a
    ``rows(start, stop)`` method, such as :class:`dynia.engine.kernels.CompiledErrors`.
    ``simulations(indices)`` yields the simulated output of the samples
    ``indices`` again, (len(indices), m) arrays in time order covering
    ``y``: the noise floor estimates the noise's autocorrelation from the
    residuals of the record-best sample and its neighbours
    (:func:`dynia.engine.noise.record_fit`); without it the floor
    assumes white noise. ``settings`` (an
    :class:`~dynia.settings.AnalysisSettings`) and ``run`` (a
    :class:`~dynia.settings.RunRecord`) are what the caller knows of the run;
    the result's are these with what the analysis did put in.
    """
    y = _checks.as_1d_float(y, "y", allow_nan=True)
    params = _checks.as_2d_float(params, "params")
    errors = sim_chunks if hasattr(sim_chunks, "rows") else StreamedErrors(y, sim_chunks, params.shape[0])
    bounds = _bounds_holding(params, bounds)
    # A store given as arrays already made is the caller's output, not a setting.
    given = isinstance(store, ResultArrays)
    # One place checks every setting; weighted samples are what the adaptive samplers produce.
    keywords = dict(
        n=n,
        percentage=percentage,
        bins=bins,
        conf_level=conf_level,
        flavour=flavour,
        min_points=min_points,
        window=window,
        engine=engine,
        workers=workers,
        ic_error=ic_error,
        dtype=dtype,
        store=None if given else store,
    )
    # The keywords win over the caller's settings, which keep what the keywords do not say (dt, x0, ...).
    checked = (
        AnalysisSettings(n_samples=params.shape[0], sampler="uniform" if weights is None else "iis", **keywords)
        if settings is None
        else settings.replace(n_samples=params.shape[0], **keywords)
    )
    return analyse_errors(
        y,
        errors,
        params,
        bounds,
        checked,
        names=names,
        time=time,
        chunk_steps=chunk_steps,
        progress=progress,
        run=run,
        weights=weights,
        output=store if given else None,
        simulations=simulations,
    )


def window_halos(n, window):
    """Steps (before, after) the window at t reaches: (n, n) centred, (2n, 0) trailing."""
    if window not in WINDOWS:
        raise SettingsError(f"window must be one of {WINDOWS}; got {window!r}")
    return (n, n) if window == "centred" else (2 * n, 0)


def analyse_errors(
    y,
    errors,
    params,
    bounds,
    settings,
    *,
    names=None,
    time=None,
    chunk_steps=None,
    progress=False,
    run=None,
    weights=None,
    output=None,
    simulations=None,
):
    """The moving window over a source of absolute errors, every setting taken from ``settings``.

    What :func:`analyse_stream` and :func:`moving_window` run once their
    keywords are checked, and what :func:`dynia.run` and
    :func:`dynia.adaptive.adaptive_run` run with their own settings.

    Parameters
    ----------
    y : ndarray (n_steps,)
        The record, checked (NaN marks a missing sample).
    errors : source of absolute errors
        ``rows(start, stop)`` and ``columns(start, stop)``, e.g.
        :class:`~dynia.engine.error_sources.ArrayErrors`,
        :class:`~dynia.engine.error_sources.StreamedErrors` or
        :class:`dynia.engine.kernels.CompiledErrors`, in time order.
    params : ndarray (n_samples, n_params)
        The parameter sets analysed, inside ``bounds``.
    bounds : ndarray (n_params, 2)
        [low, high] of each parameter, checked.
    settings : dynia.settings.AnalysisSettings
        The analysis; its ``n_samples`` is taken as the rows of ``params``
        (the sets analysed, after any were dropped), and its ``store`` and
        ``dtype`` make the output unless ``output`` is given.
    names, time, chunk_steps, progress, weights, simulations
        As :func:`analyse_stream`.
    run : dynia.settings.RunRecord, optional
        What the caller knows of the run (the model, the samples drawn and
        dropped, ...); the result's record adds what the engine did.
    output : dynia.io.arrays.ResultArrays, optional
        Where the arrays go, made and committed by the caller.

    Returns
    -------
    DyniaResult
    """
    n_samples, n_params = params.shape
    if settings.n_samples != n_samples:  # sets were dropped after sampling: the checks hold for those analysed
        settings = settings.replace(n_samples=n_samples)
    before, after = window_halos(settings.n, settings.window)
    settings.check_record(y.size)
    names, time = _parameter_names(names, n_params), _time_of_steps(time, y.size)
    if chunk_steps is None:
        chunk_steps = default_chunk_steps(n_samples, 2 * settings.n)
    chunk_steps = _checks.whole_number(chunk_steps, "chunk_steps", minimum=1)
    engine, flavour_impl = _flavour(settings, params, bounds, weights, y.size)
    scale = error_scale(y)
    if scale != 1.0:
        errors = ScaledErrors(errors, scale)
    # In memory or, with a store, in a file written as the chunks come (dynia.io.arrays).
    own_output = output is None
    output = result_arrays(settings.store, settings.dtype) if own_output else output
    _allocate(output, flavour_impl, settings.ic_error, y.size, names=names, samples=params, bounds=bounds, time=time)
    passed = _windows_pass(
        errors, flavour_impl, engine != "numpy", output, settings, (before, after), chunk_steps, progress
    )
    floor = _noise_floor(y, params, bounds, time, settings, passed, scale, simulations)
    # What the engine did wins over what the caller asked: the samples analysed
    # (after any were dropped) and the engine that ran ("auto" resolved).
    recorded = settings.replace(n_samples=n_samples, engine=engine)
    run = dataclasses.replace(
        run or RunRecord(),
        n_behavioural=flavour_impl.count,
        ic_batches=flavour_impl.batches if settings.ic_error else None,
        **floor_settings(floor),
    )
    arrays = output.arrays()
    result = DyniaResult(
        names=names,
        samples=params,
        bounds=bounds,
        time=time,
        ic=arrays["ic"],
        ci=arrays["ci"],
        median=arrays["median"],
        gradient=arrays["gradient"],
        bin_centres=flavour_impl.bin_centres,
        settings=recorded,
        run=run,
        ic_se=arrays.get("ic_se"),
        ci_se=arrays.get("ci_se"),
        **floor_fields(floor),
    )
    # An output given by the caller is committed by the caller, once it has added the verdicts.
    return output.commit(result) if own_output else result


def _noise_floor(y, params, bounds, time, settings, passed, scale, simulations):
    """The record's noise floor (:func:`dynia.engine.noise.record_noise_floor`) from what the windows' pass left.

    Windows whose MAE overflowed are reported first; the MAEs are divided by
    the error ``scale`` back to the record's units.
    """
    best, threshold, upper, totals, overflowed = passed
    report_overflowed(overflowed, best, time, y)
    for extreme in (best, threshold, upper):
        extreme /= scale  # exact: a power of two
    before, after = window_halos(settings.n, settings.window)
    points = window_points(y, before, after)
    fit = None if simulations is None else record_fit(y, params, bounds, totals, simulations)
    n_samples, n_params = params.shape
    slots = before + after + 1
    return record_noise_floor(best, upper, threshold, points, slots, n_params, settings.percentage, n_samples, fit)


def _flavour(settings, params, bounds, weights, n_steps):
    """The engine that runs (:func:`~dynia.engine.flavours.chosen_engine`), and the flavour's analysis of a window."""
    engine = chosen_engine(settings, params, n_steps, weights)
    flavour_impl = flavour_analysis(
        settings.flavour,
        engine != "numpy",
        params,
        bounds,
        settings.percentage,
        settings.bins,
        settings.conf_level,
        settings.min_points,
        weights=weights,
        ic_error=settings.ic_error,
        on_twin=engine == "twin",
    )
    return engine, flavour_impl


def _time_of_steps(time, n_steps):
    """``time`` checked as one value per step, or 0, 1, ... when None."""
    time = np.arange(n_steps, dtype=float) if time is None else _checks.as_1d_float(time, "time")
    if time.size != n_steps:
        raise SettingsError(f"time has {time.size} values but y has {n_steps}; they must match", "time")
    falling = np.flatnonzero(~(np.diff(time) > 0))
    if not np.isfinite(time).all() or falling.size:
        where = f"at step {int(falling[0]) + 1}" if falling.size else "somewhere"
        raise SettingsError(f"time must be finite and strictly rising, one value per step; it is not {where}", "time")
    return time


def _bounds_holding(params, bounds):
    """``bounds`` checked as (n_params, 2), and every sample inside them."""
    bounds = _checks.bounds_array(bounds, params.shape[1])
    outside = (params < bounds[:, 0]) | (params > bounds[:, 1])
    if outside.any():
        row, col = np.argwhere(outside)[0]
        raise SettingsError(
            f"params row {row}, column {col} = {params[row, col]} lies outside its bounds "
            f"[{bounds[col, 0]}, {bounds[col, 1]}]; samples must come from the ranges analysed"
        )
    return bounds


def _allocate(output, flavour_impl, ic_error, n_steps, **coordinates):
    """Room in ``output`` for every time-dependent result array (and the Monte Carlo errors with ``ic_error``)."""
    n_params = flavour_impl.bin_centres.shape[0]
    shapes = dict(
        ic=(n_params, n_steps),
        ci=(n_params, n_steps, 2),
        median=(n_params, n_steps),
        gradient=(n_params, flavour_impl.n_bins, n_steps),
    )
    if ic_error:
        shapes.update(ic_se=(n_params, n_steps), ci_se=(n_params, n_steps, 2))
    output.allocate(shapes, bin_centres=flavour_impl.bin_centres, **coordinates)


def _windows_pass(errors, flavour_impl, compiled, output, settings, halos, chunk_steps, progress):
    """Analyse every window, chunk by chunk of time, into ``output``.

    Returns what the noise floor needs, which needs every window's before it
    can judge any: each window's best, threshold and upper behavioural MAE
    (n_steps,), every sample's record total absolute error (n_samples,),
    whose lowest gives the residuals the floor's noise model comes from, and
    the windows left without results because their MAE overflowed (n_steps,).
    """
    before, after = halos
    n_steps, slots, min_points = errors.y.size, before + after + 1, settings.min_points
    best, threshold, upper = np.full(n_steps, np.nan), np.full(n_steps, np.nan), np.full(n_steps, np.nan)
    totals = np.zeros(settings.n_samples)
    overflowed = np.zeros(n_steps, dtype=bool)
    workers = 1 if settings.flavour == "mcat" else settings.workers or _checks.default_workers()

    # A source that forms the window sums itself (the built-in linear models, compiled) hands over no error rows.
    fused = compiled and getattr(errors, "fused", False)
    # The bar counts the windows analysed, as each chunk's results are written.
    bar = progress_bar(progress, total=n_steps, desc="DYNIA windows", unit="window")

    def analyse_chunk(start, stop, window_errors, measured):
        if fused:
            return start, stop, flavour_impl.analyse_sums(window_errors, measured)
        if compiled:
            return start, stop, flavour_impl.analyse_rows(window_errors, measured, stop - start, slots)
        mae, present = window_mean(window_errors, measured, stop - start, slots)
        return start, stop, flavour_impl.analyse(mae, present >= min_points)

    def write(finished):
        start, stop, results = finished.result()
        overflowed[start:stop] = blank_overflowed(results)
        chunks = dict(ic=results.ic, ci=results.ci, median=results.median, gradient=results.gradient)
        if settings.ic_error:
            chunks["ic_se"], chunks["ci_se"] = monte_carlo_errors(results.batch_ic, results.batch_ci)
        output.write(start, stop, chunks)
        best[start:stop], threshold[start:stop], upper[start:stop] = results.best, results.threshold, results.upper
        if bar is not None:
            bar.update(stop - start)

    # Errors are pulled in time order (a simulation stream is sequential); the
    # windows of each chunk are then analysed on a worker, while this thread
    # pulls the next chunk. One worker means one thread: the chunk is analysed
    # here. MCAT's likelihood carries state from window to window, so it stays
    # on one worker. An error or an interruption discards the output (a
    # store's partial file).
    with _InlineExecutor() if workers == 1 else ThreadPoolExecutor(max_workers=workers) as pool, output:
        pending = deque()
        for start in range(0, n_steps, chunk_steps):
            stop = min(start + chunk_steps, n_steps)
            if fused:
                inputs = errors.window_sums(start, stop, (before, after), totals)
            else:
                inputs = window_inputs(errors, start, stop, before, after, n_steps, time_major=compiled)
                own = (
                    inputs[0][before : before + stop - start]
                    if compiled
                    else inputs[0][:, before : before + stop - start].T
                )
                add_record_errors(totals, own)
            pending.append(pool.submit(analyse_chunk, start, stop, *inputs))
            while len(pending) > workers:  # bounds the chunks held in memory
                write(pending.popleft())
        while pending:
            write(pending.popleft())
    if bar is not None:
        bar.close()
    return best, threshold, upper, totals, overflowed


def _parameter_names(names, n_params):
    if names is None:
        return tuple(f"p{i}" for i in range(n_params))
    names = tuple(str(name) for name in names)
    if len(names) != n_params:
        raise SettingsError(f"names has {len(names)} entries but there are {n_params} parameters")
    if len(set(names)) != len(names):
        raise SettingsError(f"names must be unique; got {names}")
    return names


def record_cuts(steps, n_steps, chunk_steps):
    """The record in pieces of at most ``chunk_steps``, cut at every one of ``steps`` too: (from, to) pairs.

    Examples
    --------
    >>> list(record_cuts([5], 12, 4))
    [(0, 4), (4, 5), (5, 8), (8, 12)]
    """
    cuts = sorted({*steps, *range(0, n_steps, chunk_steps), n_steps})
    return zip(cuts[:-1], cuts[1:])


class _InlineExecutor:
    """An executor that runs each task as it is submitted, in the calling thread."""

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        return False

    def submit(self, function, *args):
        done = Future()
        done.set_result(function(*args))  # an error stops the loop at once, as it would in the pool's reader
        return done


def error_scale(y):
    """The power of two every absolute error is multiplied by before costs are formed; 1.0 for most records.

    See "Magnitudes" in the module documentation.

    Examples
    --------
    >>> error_scale([0.5, np.nan, -3.0]), error_scale([1e200]) == 2.0**-333, error_scale([1e-170]) == 2.0**232
    (1.0, True, True)
    """
    magnitude = np.abs(np.asarray(y, dtype=float))
    largest = float(np.max(magnitude, initial=0.0, where=~np.isnan(magnitude)))
    if largest == 0.0 or not math.isfinite(largest):
        return 1.0
    exponent = math.frexp(largest)[1]  # largest < 2^exponent
    if exponent > SAFE_EXPONENT:
        return 2.0 ** (SAFE_EXPONENT - exponent)
    if exponent < -SAFE_EXPONENT:
        return 2.0 ** (-SAFE_EXPONENT - exponent)
    return 1.0


class OverflowedWindowsWarning(UserWarning):
    """Windows were left without results: their behavioural sets' MAE overflows when squared, so they tie."""


def blank_overflowed(results):
    """Set to NaN, in place, the windows of ``results`` (WindowResults) whose behavioural MAE is infinite; their mask.

    Such a window's behavioural costs overflowed and tie, so its band would
    be the first sets by index: no result is better than that one.
    """
    overflowed = np.isinf(results.threshold)
    if overflowed.any():
        results.ic[:, overflowed] = np.nan
        results.ci[:, overflowed] = np.nan
        results.median[:, overflowed] = np.nan
        results.gradient[:, :, overflowed] = np.nan
        for batched in (results.batch_ic, results.batch_ci):
            if batched is not None:
                batched[:, :, overflowed] = np.nan
        for extreme in (results.best, results.threshold, results.upper):
            extreme[overflowed] = np.nan
    return overflowed


def report_overflowed(overflowed, best, time, y):
    """Warn about the windows :func:`blank_overflowed` blanked (mask ``overflowed``); refuse if no other is left.

    ``best`` holds every window's best MAE (NaN without result), ``time`` the
    windows' times, ``y`` the record (its magnitude is named).
    """
    if not overflowed.any():
        return
    largest = float(np.nanmax(np.abs(y))) if not np.isnan(y).all() else math.nan
    what = (
        f"the behavioural parameter sets' mean absolute error is beyond 1.3e154 in {int(overflowed.sum())} "
        f"window(s), the first at time {time[np.argmax(overflowed)]:g}, so its square, the cost, overflows and they "
        f"tie, while y is at most {largest:.3g} in magnitude: the simulated output lies more than 1e54 times beyond "
        "the data there (check the input for absurd values and the model's output for its units)"
    )
    if np.isnan(best).all():
        raise DataError(what)
    warnings.warn(f"{what}; those windows are left without results", OverflowedWindowsWarning, stacklevel=4)


def window_inputs(errors, start, stop, before, after, n_steps, time_major=False):
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
        padded[:, offset : offset + (hi - lo)] = window_errors
        counts = np.zeros(width)
        counts[offset : offset + (hi - lo)] = measured
        window_errors, measured = padded, counts
    return (np.ascontiguousarray(window_errors.T) if time_major else window_errors), measured


def window_mean(window_errors, measured, m, slots):
    """Mean absolute error of every sample over each of the m windows of ``slots`` steps.

    Returns ``mae`` (m, n_samples) and the number of measured points per
    window (m,). Sums run left to right over each window, the order of
    :func:`dynia.reference.thesis.moving_window_calcs`, so the result depends on the
    window's own errors only and equals the port's bit for bit
    (:func:`plain_window_mean` is the plain form).
    """
    present = measured[0:m].copy()
    for shift in range(1, slots):
        present += measured[shift : shift + m]
    mae = np.empty((m, window_errors.shape[0]))
    # A block of samples at a time, time-major, so that each window sum adds whole rows held in cache.
    for first in range(0, window_errors.shape[0], _MEAN_BLOCK):
        errors = np.ascontiguousarray(window_errors[first : first + _MEAN_BLOCK].T)
        total = mae[:, first : first + _MEAN_BLOCK]
        total[...] = errors[0:m]
        # A diverged simulation (the thesis's Euler scheme for small T) sums to inf and ranks last, as in
        # MATLAB: an expected result, not a warning for the user.
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for shift in range(1, slots):
                total += errors[shift : shift + m]
            total /= present[:, None]
    return mae, present


def plain_window_mean(window_errors, measured, m, slots):
    """:func:`window_mean` in one plain pass over every sample, sample-major: the reference it is tested against."""
    total = window_errors[:, 0:m].copy()
    present = measured[0:m].copy()
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for shift in range(1, slots):
            total += window_errors[:, shift : shift + m]
            present += measured[shift : shift + m]
        total /= present
    return np.ascontiguousarray(total.T), present


def window_costs(y, sims, n, start, stop, window="centred"):
    """Thesis costs (window MAE squared) of every sample for the windows at steps [start, stop).

    Returns (stop - start, n_samples); windows without a measured point are NaN.
    """
    errors = ArrayErrors(_checks.as_1d_float(y, "y", allow_nan=True), np.asarray(sims, dtype=float))
    before, after = window_halos(n, window)
    mae, _ = window_mean(
        *window_inputs(errors, start, stop, before, after, errors.y.size), stop - start, before + after + 1
    )
    with np.errstate(over="ignore"):
        return mae**2
