"""``dynia.run``: sample, simulate and analyse in one call, streaming over time."""

import dataclasses
import itertools
import math
import warnings

import numpy as np

from . import _checks
from .adaptive import adaptive_run
from .bounds import parameter_box
from .engine import kernels
from .engine.error_sources import ArrayErrors, StreamedErrors
from .engine.flavours import chosen_engine
from .engine.noise import RESIDUAL_CHUNK
from .engine.windows import analyse_errors, default_chunk_steps
from .errors import DyniaError, ModelError, SettingsError
from .fit import record_least_squares
from .io.arrays import result_arrays
from .io.frames import unpack
from .models import LinearModel, Model, StateSpaceModel
from .models.base import check_model
from .models.custom import StateErrors
from .progress import shows_progress
from .quality import screening
from .sampling import sample
from .settings import ADAPTIVE_SAMPLERS, IC_THRESHOLD, MAX_PARAMETER, RunRecord, merged_settings
from .verdicts import assess

__all__ = [
    "run",
    "dated",
    "ic_se_that_matters",
    "DroppedSamplesWarning",
    "TargetNotReachedWarning",
    "UnreachedOutputWarning",
    "KernelSimulated",
    "RecursionSimulated",
]

# Above this share of dropped (non-finite) parameter sets the analysis no longer
# covers the box it claims to, so the run says so.
DROPPED_WARNING_SHARE = 0.01


# target_se: a round asks for the count predicted to reach the target (the error falls as 1/sqrt(N))
# times TARGET_MARGIN, since the prediction rests on an error estimate that is itself uncertain (about
# 24 % with 10 batches), and grows the sample at least TARGET_MIN_GROWTH-fold, so that an optimistic
# prediction costs few rounds.
TARGET_MARGIN = 1.2
TARGET_MIN_GROWTH = 1.5


class DroppedSamplesWarning(UserWarning):
    """More than 1 % of the parameter sets were dropped because their simulation was not finite."""


class UnreachedOutputWarning(UserWarning):
    """No parameter set in the box reaches the output's size (see ``warn_unreached_output``)."""


class TargetNotReachedWarning(UserWarning):
    """``target_se`` was not reached within ``max_samples``: the IC's Monte Carlo error is larger than asked."""


def run(
    u,
    y,
    model,
    bounds,
    *,
    settings=None,
    dt=None,
    n_samples=None,
    sampler=None,
    n=None,
    percentage=None,
    bins=None,
    conf_level=None,
    flavour=None,
    x0=None,
    min_points=None,
    window=None,
    engine=None,
    workers=None,
    ic_error=None,
    target_se=None,
    max_samples=None,
    dtype=None,
    store=None,
    quality=None,
    rng=None,
    progress="auto",
):
    """Dynamic identifiability analysis of a model against measured data.

    Draws ``n_samples`` parameter sets from the box ``bounds``, simulates the
    model for each and runs the moving-window analysis of
    :func:`dynia.engine.moving_window` on all parameters at once. The
    simulation is streamed into the analysis in time chunks, so memory does
    not grow with n_samples x n_steps.

    Every setting may come in a :class:`dynia.settings.AnalysisSettings`
    (``settings=``), as a keyword, or both: a keyword overrides the object, and
    the result's ``settings`` record what was used. Defaults are those of
    :class:`~dynia.settings.AnalysisSettings`.

    Parameters
    ----------
    u, y : array_like, shape (n_steps,), or pandas Series / DataFrame
        Input and measured output, one value per sample time ``k*dt``. NaN in
        ``y`` marks a missing measurement. ``u`` is (n_steps, n_inputs) for a
        model with several inputs (a DataFrame: its columns in order). Two
        pandas objects must share one index. With a time index (uniformly
        spaced dates, durations, or a numeric index of seconds) ``dt`` is its
        spacing, and dates become ``result.timestamps``
        (:func:`dynia.io.frames.unpack`).
    model : dynia.models.Model
        For example ``dynia.models.FirstOrder()``.
    bounds : mapping of str to (low, high)
        Sampling range of every model parameter; the result's parameter axis
        follows this order.
    dt : float, default 1.0
        Sample time.
    n_samples : int, default 2000
        Number of parameter sets (model evaluations).
    sampler : {"uniform", "lhs", "sobol", "iis", "de"}
        How the box is sampled: :mod:`dynia.sampling`, or the adaptive
        schemes of :mod:`dynia.adaptive`, which concentrate the
        ``n_samples`` evaluations in the windows' low-cost regions and
        weight them back to the uniform prior (they hold every simulation
        in memory, so keep n_samples x n_steps moderate).
    n, percentage, bins, conf_level, flavour
        As :func:`dynia.engine.moving_window`.
    x0 : {"zero", "steady"}
        Initial state of every simulation.
    rng : numpy.random.Generator or int, optional
        Source of every random draw; the same seed gives identical results.
    progress : bool or "auto", default "auto"
        Show a tqdm progress bar on stderr; "auto" shows one when stderr is
        a terminal or in a Jupyter notebook (:mod:`dynia.progress`).
    min_points : int, default 1
        Windows with fewer measured points get NaN results.
    window : {"centred", "trailing"}, default "centred"
        The window at step t holds t-n .. t+n, or t-2n .. t (ending at t,
        as :class:`dynia.online.OnlineDynia` sees it).
    engine : {"auto", "numba", "numpy"}, default "auto"
        As :func:`dynia.engine.moving_window`; the compiled engine also
        simulates the model in compiled code. The two agree to rounding in
        the costs, and exactly wherever a window's behavioural set is the
        same (:mod:`dynia.engine.kernels`).
    workers : int, optional
        Threads (default: every core). Results do not depend on it.
    ic_error : bool, default False
        Also estimate the Monte Carlo standard errors of IC and limits
        (``result.ic_se``, ``result.ci_se``): how much they would change
        with another sample of the same size. Batch means in the same pass,
        at little extra cost (see :mod:`dynia.engine.windows`); the adaptive
        samplers' errors use their importance weights.
    target_se : float, optional
        Add uniform samples until the largest IC standard error where it
        matters (:func:`ic_se_that_matters`) is at most this, or
        ``max_samples`` is reached. Every earlier sample is kept (the
        samples are those one run with the final count would draw); each
        round simulates them all again, so memory stays bounded and the
        cost is about twice that of one run at the final count.
        ``result.run`` records ``target_se_reached`` (the error
        reached), ``target_se_met`` and ``target_se_rounds`` (samples and
        error of each round); a :class:`TargetNotReachedWarning` says when
        the budget ran out first. Implies ``ic_error``.
    max_samples : int, optional
        The budget of ``target_se`` (required with it).
    dtype : {"float64", "float32"}, default "float64"
        Type of the result's IC, limits, median, gradient and their errors; float32
        values are the float64 results rounded, at half the memory.
    store : str or os.PathLike, optional
        A netCDF file that those arrays are written to as they are produced,
        for records whose gradient does not fit in memory: the file is
        complete (verdicts included) and renamed into place when ``run``
        returns, never left half-written, and the result reads it lazily
        (:mod:`dynia.io.arrays`; ``dynia.load`` reads it too).
    quality : bool, default True
        Screen the record first (:func:`dynia.quality.screen`): saturated
        and frozen readings of the input or the output, and a coarsely
        quantised output. ``result.run.screened`` records what was found,
        and the windows it dominates
        (:attr:`~dynia.result.DyniaResult.screened_windows`) are no
        evidence for any parameter. False: not screened
        (``run.screened`` None).
    settings : dynia.settings.AnalysisSettings, optional
        All of the above in one checked object.

    Returns
    -------
    DyniaResult
        Parameter sets whose simulation is not finite over the record
        (an unstable model overflowing) are left out of the analysis, never
        ranked; ``run.n_dropped`` counts them and ``.samples`` holds
        the sets analysed. When more than 1 % are dropped a
        :class:`DroppedSamplesWarning` says so: the analysis then covers less
        than the box it was given.

    Examples
    --------
    >>> import numpy as np, dynia
    >>> u = np.r_[np.zeros(20), np.full(60, 1.0)]
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
    >>> res = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n=5, rng=1)
    >>> res.ic.shape
    (2, 80)
    """
    # pandas in: a time index (dates, durations, seconds) gives dt; dates become the result's time axis.
    u, y, dt, timestamps = unpack(u, y, dt if dt is not None else getattr(settings, "dt", None))
    given = dict(
        dt=dt,
        n_samples=n_samples,
        sampler=sampler,
        n=n,
        percentage=percentage,
        bins=bins,
        conf_level=conf_level,
        flavour=flavour,
        x0=x0,
        min_points=min_points,
        window=window,
        engine=engine,
        workers=workers,
        ic_error=ic_error,
        target_se=target_se,
        max_samples=max_samples,
        dtype=dtype,
        store=store,
        quality=quality,
    )
    settings = merged_settings(settings, given, front_end=run)
    progress = shows_progress(progress)
    check_model(model)
    u, y = _checks.record(u, y, n_inputs=model.n_inputs)
    settings.check_record(y.size)  # before any simulation
    names, box = parameter_box(bounds, model.names, repr(model))
    model.check_ranges(dict(zip(names, box)))  # before any set is drawn, naming the parameter, not a sample
    if settings.sampler in ADAPTIVE_SAMPLERS:  # adaptive_run screens the record itself
        result = adaptive_run(
            u, y, model, dict(zip(names, map(tuple, box))), scheme=settings.sampler, settings=settings, rng=rng
        )
        # The verdicts name times: again with the dates, when there are dates.
        return result if timestamps is None else dated(result, timestamps)
    screened = screening(u, y, settings)  # before the analysis, which it does not change: the verdicts read it
    generator = _checks.generator(rng)
    samples = sample(settings.sampler, settings.n_samples, box, generator)
    # The arrays in memory, or in settings.store as they are produced, committed with the verdicts (dynia.io.arrays).
    with result_arrays(settings.store, settings.dtype) as output:
        if settings.target_se is None:
            result = _analyse_samples(u, y, model, names, box, samples, settings, progress, output)
        else:
            result = _analyse_to_target(u, y, model, names, box, samples, settings, generator, progress, output)
        result = dataclasses.replace(result, run=dataclasses.replace(result.run, screened=screened))
        # The box's corners and the least squares simulate a few sets at a time: through the kernel where the analysis
        # ran on it (the model's recursion loops over every step in Python: 4 s for the corners of 200 000 steps), by
        # the recursion where the twin did, which compiles nothing.
        simulated = {"numba": KernelSimulated, "twin": RecursionSimulated}.get(result.settings.engine)
        fitted = simulated(model) if simulated and compiled_simulation(model) else model
        warn_unreached_output(u, y, fitted, names, box, settings)
        result = record_least_squares(result, u, y, fitted)
        return output.commit(dated(result, timestamps))


def _analyse_samples(u, y, model, names, box, samples, settings, progress, output):
    """Simulate ``samples`` and analyse them into a result.

    Sets whose simulation is not finite are dropped (and warned about).
    """
    n_sampled = samples.shape[0]
    model_order = [names.index(name) for name in model.names]
    # Chosen for the sets drawn; the analysis runs the engine chosen here.
    settings = settings.replace(engine=chosen_engine(settings, samples, y.size, model=model))
    compiled = settings.engine == "numba"
    workers = settings.workers or _checks.default_workers()
    sims = None
    if not getattr(model, "streams", True):
        # A model that simulates the whole record at once is called once: its output is what is analysed.
        with np.errstate(over="ignore", invalid="ignore"):
            sims = model.simulate(samples[:, model_order], u, dt=settings.dt, x0=settings.x0)
        finite = np.isfinite(sims).all(axis=1)
    elif compiled and _compiled_state_space(model):
        # Unstable sets are found during the analysis (StateErrors.diverged), saving a simulation pass.
        finite = np.ones(n_sampled, dtype=bool)
    else:
        finite = model.finite_samples(samples[:, model_order], u, dt=settings.dt, x0=settings.x0)
    while True:
        if not finite.any():
            raise ModelError(
                f"{model!r}: the simulation of every one of the {n_sampled} parameter sets is not "
                "finite (NaN or overflow); check the model and the parameter ranges"
            )
        analysed = samples[finite]
        _check_enough_left(settings, analysed.shape[0], n_sampled, u)
        if sims is not None and not finite.all():
            sims = sims[finite]
        chunk_steps = default_chunk_steps(analysed.shape[0], 2 * settings.n)
        if sims is not None:
            errors = ArrayErrors(y, sims)
        elif compiled and compiled_simulation(model):
            errors = kernels.CompiledErrors(
                model, analysed[:, model_order], u, y, dt=settings.dt, x0=settings.x0, workers=workers
            )
        elif compiled and _compiled_state_space(model):
            errors = StateErrors(model, analysed[:, model_order], u, y, dt=settings.dt, workers=workers)
        else:
            chunks = model.simulate_chunks(
                analysed[:, model_order], u, dt=settings.dt, x0=settings.x0, chunk_steps=chunk_steps
            )
            errors = StreamedErrors(y, chunks, analysed.shape[0])
        n_dropped = int(n_sampled - analysed.shape[0])
        recorded = RunRecord.of(model, n_sampled=n_sampled, n_dropped=n_dropped)
        try:
            result = analyse_errors(
                y,
                errors,
                analysed,
                box,
                settings,
                names=names,
                time=_time_axis(y.size, settings.dt),
                chunk_steps=chunk_steps,
                progress=progress,
                run=recorded,
                output=output,
                simulations=_simulations(u, y, model, analysed[:, model_order], sims, settings, errors),
            )
        finally:
            # On the twin or numpy the kernels (and numba) are never imported: `compiled` comes first.
            if isinstance(errors, StateErrors) or (compiled and isinstance(errors, kernels.CompiledErrors)):
                errors.close()
        if not (isinstance(errors, StateErrors) and errors.diverged.any()):
            break
        # Some sets overflowed: their costs were not finite, so the analysis is redone without them.
        finite[np.flatnonzero(finite)[errors.diverged]] = False
    warn_dropped(n_dropped, n_sampled, u)
    return result


def _simulations(u, y, model, params, sims, settings, errors):
    """``simulations(indices)`` of :func:`dynia.engine.windows.analyse_stream`: those samples simulated once more.

    Where the analysis ran on the linear kernel (``errors``, its source), so do the few sets: the kernel gives
    the numpy recursion's outputs bit for bit without its Python loop over every step.
    """

    def simulations(rows):
        if sims is not None:
            return [sims[rows]]
        if settings.engine == "numba" and isinstance(errors, kernels.CompiledErrors):
            source = kernels.CompiledErrors(model, params[rows], u, y, dt=settings.dt, x0=settings.x0, workers=1)
            return source.output_chunks(RESIDUAL_CHUNK)
        return model.simulate_chunks(params[rows], u, dt=settings.dt, x0=settings.x0, chunk_steps=RESIDUAL_CHUNK)

    return simulations


class KernelSimulated(Model):
    """A single-input linear model whose :meth:`simulate` runs the compiled kernel.

    The kernel's outputs equal the model's numpy recursion bit for bit
    (:meth:`dynia.engine.kernels.driver.CompiledErrors.output_chunks`), without its
    Python loop over every step: the record's least squares
    (:func:`dynia.fit.record_least_squares`) simulates a few sets at a time,
    some ten times, where that loop costs about 0.5 s a call on 20 000 steps.
    """

    def __init__(self, model):
        super().__init__(model.names, model.n_inputs)
        self._model = model

    def __repr__(self):
        return repr(self._model)

    def simulate(self, params, u, dt=1.0, x0="zero"):
        u = np.asarray(u, dtype=float)
        source = kernels.CompiledErrors(self._model, params, u, np.zeros(u.shape[0]), dt=dt, x0=x0, workers=1)
        try:
            return np.concatenate(list(source.output_chunks(u.shape[0])), axis=1)
        finally:
            source.close()


class RecursionSimulated(Model):
    """A single-input linear model simulated by its own numpy recursion, which is the kernel's bit for bit.

    What the record's least squares simulates after a run on the twin engine: the fit would otherwise run the
    compiled kernel (:class:`KernelSimulated`), compiling it in a process that the twin spared that.
    """

    def __init__(self, model):
        super().__init__(model.names, model.n_inputs)
        self._model = model

    def __repr__(self):
        return repr(self._model)

    def simulate(self, params, u, dt=1.0, x0="zero"):
        return self._model.simulate(params, u, dt=dt, x0=x0)


def _analyse_to_target(u, y, model, names, box, samples, settings, generator, progress, output):
    """Add uniform samples to ``samples`` until the IC's Monte Carlo error meets ``settings.target_se``.

    Each round analyses every sample drawn so far (earlier ones are kept,
    new ones are drawn from the same ``generator``, so the samples are those
    a single run with the final count would draw). The error of IC falls as
    1/sqrt(N): the next count is the one that would reach the target, times
    :data:`TARGET_MARGIN`, at least :data:`TARGET_MIN_GROWTH` times the
    current one and at most ``max_samples``.
    """
    rounds = []
    while True:
        result = _analyse_samples(u, y, model, names, box, samples, settings, progress, output)
        reached = ic_se_that_matters(result)
        rounds.append([int(samples.shape[0]), reached])
        # NaN: no informative step has an IC, so no error can change a conclusion.
        if math.isnan(reached) or reached <= settings.target_se or samples.shape[0] >= settings.max_samples:
            break
        wanted = math.ceil(samples.shape[0] * TARGET_MARGIN * (reached / settings.target_se) ** 2)
        count = min(settings.max_samples, max(wanted, math.ceil(samples.shape[0] * TARGET_MIN_GROWTH)))
        samples = np.r_[samples, sample("uniform", count - samples.shape[0], box, generator)]
    met = math.isnan(reached) or reached <= settings.target_se
    run = dataclasses.replace(result.run, target_se_reached=reached, target_se_met=met, target_se_rounds=rounds)
    result = dataclasses.replace(result, run=run)
    if not met:
        warnings.warn(
            f"the largest Monte Carlo standard error of IC where it matters is {reached:.3g} with "
            f"max_samples={settings.max_samples} samples, above target_se={settings.target_se:g}; raise "
            "max_samples or accept the error (result.ic_se)",
            TargetNotReachedWarning,
            stacklevel=3,
        )
    return result


def ic_se_that_matters(result, threshold=IC_THRESHOLD):
    """The largest Monte Carlo standard error of IC over the steps where it can change a conclusion.

    Those are, for every parameter, the steps whose IC is within two
    standard errors of ``threshold`` or above it (``ic + 2 ic_se >=
    threshold``: where another Monte Carlo sample could make the IC reach
    the verdicts' threshold or fall below it), and always its highest IC
    (the verdict is read there). Steps without IC are left out, and so are
    windows below the noise floor (``result.informative`` False): their IC
    ranks noise, is never an estimate, and more samples do not make it one.

    Parameters
    ----------
    result : DyniaResult
        With ``ic_se`` (``ic_error=True``).
    threshold : float, default 0.5
        The IC from which a parameter counts as identified
        (:func:`dynia.verdicts.assess`'s ``ic_threshold``).

    Returns
    -------
    float
        NaN when no step has an IC.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.result import DyniaResult
    >>> res = DyniaResult(names=("K",), samples=np.zeros((1, 1)), bounds=np.array([[0.0, 1.0]]), time=np.arange(3.0),
    ...                   ic=np.array([[0.1, 0.45, 0.8]]), ci=np.zeros((1, 3, 2)), gradient=np.zeros((1, 2, 3)),
    ...                   bin_centres=np.zeros((1, 2)), ic_se=np.array([[0.1, 0.03, 0.01]]))
    >>> float(ic_se_that_matters(res))
    0.03
    """
    if result.ic_se is None:
        raise SettingsError("the result has no Monte Carlo errors: run with ic_error=True", "ic_error")
    ic, ic_se = np.asarray(result.ic), np.asarray(result.ic_se)
    if np.isnan(ic).all():
        return math.nan
    if result.informative is not None:
        ic = np.where(np.asarray(result.informative), ic, np.nan)
        if np.isnan(ic).all():
            return math.nan
    matters = np.nan_to_num(ic + 2 * ic_se, nan=-np.inf) >= threshold
    highest = np.nanargmax(np.where(np.isnan(ic), -np.inf, ic), axis=1)
    matters[np.arange(ic.shape[0]), highest] = ~np.isnan(ic[np.arange(ic.shape[0]), highest])
    return float(np.nanmax(np.where(matters, ic_se, np.nan)))


def _time_axis(n_steps, dt):
    """``k * dt`` for every step, scaled in place: one array of the record's length, not two."""
    time = np.arange(n_steps, dtype=float)
    time *= dt
    return time


def dated(result, timestamps):
    """``result`` with the record's dates (when it has them) and its verdicts, which then name the dates.

    The result carries the noise floor, so the verdicts need neither data nor simulation.
    """
    if timestamps is not None:
        result = dataclasses.replace(result, timestamps=timestamps)
    return dataclasses.replace(result, verdicts=assess(result))


def _compiled_state_space(model):
    return isinstance(model, StateSpaceModel) and model.compiled


def compiled_simulation(model):
    """Whether the compiled kernels can simulate ``model`` (the single-input linear models)."""
    return isinstance(model, LinearModel) and model.n_inputs == 1


# The share of the output's size that the largest output of the box's corners must reach: three decades. A record
# of noise on a weak response (the corners at a thirtieth of the output) is no mismatch of units; the corners of at
# most _MOST_CORNERS parameters are simulated (2^6 = 64 sets).
_REACHED_SHARE = 1e-3
_MOST_CORNERS = 6


def warn_unreached_output(u, y, model, names, box, settings):
    """Warn (:class:`UnreachedOutputWarning`) when no corner of the parameter box reaches a thousandth of the output.

    ``box`` holds the bounds of the parameters ``names``, in that order.
    The output's size is its 99th percentile of ``|y|`` (one spike does not
    set it); a corner's reach is the largest ``|value|`` of its simulation,
    which holds no spikes. (Where the input acts for less than a hundredth
    of the record, a step and then a long rest at zero, a corner's 99th
    percentile is its decay in the rest, decades below what it reaches while
    the input acts: that named a box that fits as out of reach.) The corners
    of the box hold each parameter's extremes, so for the usual models the
    largest output any set in the box can give;
    when even theirs stays three decades below the output's, no set can fit
    it and the verdicts would be ties or noise with no word why: data in
    other units than the model (1e100 apart), an offset that moved the data
    far away, bounds that leave out the gain by orders of magnitude. A
    mismatch of a factor 20 (l/s against mm/d) is not caught: a weak response
    under noise looks the same. A model of more than six parameters, or one
    that refuses a corner, is not checked.
    """
    n_params = box.shape[0]
    if n_params > _MOST_CORNERS:
        return
    corners = np.array(list(itertools.product(*box)))
    order = [names.index(name) for name in model.names]  # the box's rows follow names, the model's columns its own
    # Corners that overflow or give NaN (an unstable corner, a record of missing values) are no reach: no warnings.
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        sims = _corner_outputs(model, corners[:, order], u, settings)
        if sims is None:
            return
        sims[~np.isfinite(sims)] = np.nan
        simulated = ~np.isnan(sims).all(axis=1)
        corner_sizes = np.full(sims.shape[0], np.nan)
        corner_sizes[simulated] = np.nanmax(np.abs(sims[simulated]), axis=1)
        size = float(np.nanpercentile(np.abs(y), 99))
    known = np.isfinite(corner_sizes)
    if not known.any():  # every corner overflowed: what the box reaches is unknown
        return
    reach = float(corner_sizes[known].max())
    if np.isfinite(size) and size > 0 and reach < _REACHED_SHARE * size:
        warnings.warn(
            f"no parameter set in the box reaches the output's size: the largest output of the box's corners is "
            f"{reach:.3g} in magnitude, the output's size {size:.3g} (the 99th percentile of its magnitude), three "
            "decades and more apart; check the units and offsets of the data against the model's, and the bounds "
            "that set the gain",
            UnreachedOutputWarning,
            stacklevel=3,
        )


def _corner_outputs(model, corners, u, settings):
    """The corners' simulations, (corners, n_steps); None where the model refuses a corner.

    The compiled kernel (:class:`KernelSimulated`) stops at a corner whose simulation is not finite, where the
    model's own recursion gives it NaN and simulates the others: then the recursion simulates them.
    """
    for simulating in (model, model._model) if isinstance(model, KernelSimulated) else (model,):
        try:
            return np.asarray(simulating.simulate(corners, u, dt=settings.dt, x0=settings.x0), dtype=float)
        except DyniaError:
            continue
    return None


def _overflow_cause(u):
    """Why simulations overflowed: the input, when it holds values beyond 1e150, else an unstable model."""
    largest = 0.0 if u is None else float(np.max(np.abs(u)))
    if largest > MAX_PARAMETER:
        return f"the input reaches {largest:.3g} in magnitude, where the simulation overflows"
    return "an unstable model overflowing"


def _check_enough_left(settings, kept, n_sampled, u):
    """Refuse, saying why, when the sets left after dropping those that overflowed are too few to analyse.

    The settings' own message would name the count left as if it had been asked for ("n_samples 6").
    """
    if kept == n_sampled:
        return
    try:
        settings.replace(n_samples=kept)
    except SettingsError:
        raise ModelError(
            f"{n_sampled - kept} of the {n_sampled} parameter sets were dropped because their simulation is not "
            f"finite ({_overflow_cause(u)}); the {kept} left are too few to keep 2 behavioural sets a window at "
            f"percentage {settings.percentage:g}"
        ) from None


def warn_dropped(n_dropped, n_sampled, u=None):
    """Warn (:class:`DroppedSamplesWarning`) when more than 1 % of the sampled sets were dropped.

    ``u``, the input: when it holds values beyond 1e150 the overflow is
    blamed on them, not on an unstable model.
    """
    if n_dropped > DROPPED_WARNING_SHARE * n_sampled:
        warnings.warn(
            f"{n_dropped} of {n_sampled} parameter sets ({100 * n_dropped / n_sampled:.1f} %) were dropped "
            f"because their simulation is not finite ({_overflow_cause(u)}); the analysis covers only the rest of the "
            "box",
            DroppedSamplesWarning,
            stacklevel=3,
        )
