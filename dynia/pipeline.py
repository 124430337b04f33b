"""``dynia.run``: sample, simulate and analyse in one call, streaming over time."""

import dataclasses
import warnings

import numpy as np

from . import _checks
from .adaptive import adaptive_run
from .engine.flavours import compiled_engine
from .engine.kernels import CompiledErrors
from .engine.windows import ArrayErrors, analyse_stream, default_chunk_steps
from .errors import ModelError
from .frames import unpack
from .models import LinearModel, Model, StateSpaceModel
from .models.custom import StateErrors
from .sampling import sample
from .settings import ADAPTIVE_SAMPLERS, AnalysisSettings, parameter_box
from .verdicts import assess

__all__ = ["run", "DROPPED_WARNING_SHARE", "DroppedSamplesWarning"]

# Above this share of dropped (non-finite) parameter sets the analysis no longer
# covers the box it claims to, so the run says so.
DROPPED_WARNING_SHARE = 0.01


class DroppedSamplesWarning(UserWarning):
    """More than 1 % of the parameter sets were dropped because their simulation was not finite."""


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
    rng=None,
    progress=False,
):
    """Dynamic identifiability analysis of a model against measured data.

    Draws ``n_samples`` parameter sets from the box ``bounds``, simulates the
    model for each and runs the moving-window analysis of
    :func:`dynia.analysis.moving_window` on all parameters at once. The
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
        model with several inputs (a DataFrame: its columns in order). With a
        DatetimeIndex (shared by both, uniformly spaced) ``dt`` is its
        spacing and the index becomes ``result.timestamps``
        (:func:`dynia.frames.unpack`).
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
        As :func:`dynia.analysis.moving_window`.
    x0 : {"zero", "steady"}
        Initial state of every simulation.
    rng : numpy.random.Generator or int, optional
        Source of every random draw; the same seed gives identical results.
    progress : bool, default False
        Show a tqdm progress bar.
    min_points : int, default 1
        Windows with fewer measured points get NaN results.
    window : {"centred", "trailing"}, default "centred"
        The window at step t holds t-n .. t+n, or t-2n .. t (ending at t,
        as :class:`dynia.online.OnlineDynia` sees it).
    engine : {"auto", "numba", "numpy"}, default "auto"
        As :func:`dynia.analysis.moving_window`; the compiled engine also
        simulates the model in compiled code. Results are bit-identical.
    workers : int, optional
        Threads (default: every core). Results do not depend on it.
    settings : dynia.settings.AnalysisSettings, optional
        All of the above in one checked object.

    Returns
    -------
    DyniaResult
        Parameter sets whose simulation is not finite over the record
        (an unstable model overflowing) are left out of the analysis, never
        ranked; ``settings["n_dropped"]`` counts them and ``.samples`` holds
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
    # pandas in: a DatetimeIndex gives dt and becomes the result's time axis.
    u, y, dt_of_index, timestamps = unpack(u, y, dt if dt is not None else getattr(settings, "dt", None))
    dt = dt if dt is not None else (dt_of_index if timestamps is not None else None)
    settings = AnalysisSettings.build(
        settings,
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
    )
    if not isinstance(model, Model):
        raise ModelError(
            f"model must be a dynia.models.Model (e.g. FirstOrder(), FunctionModel(fn, names) or "
            f"StateSpaceModel(...)); got {type(model).__name__}"
        )
    u, y = _checks.record(u, y, n_inputs=model.n_inputs)
    names, box = parameter_box(bounds, model.names, repr(model))
    if settings.sampler in ADAPTIVE_SAMPLERS:
        return _dated(
            adaptive_run(
                u, y, model, dict(zip(names, map(tuple, box))), scheme=settings.sampler, settings=settings, rng=rng
            ),
            timestamps,
        )
    samples = sample(settings.sampler, settings.n_samples, box, np.random.default_rng(rng))
    model_order = [names.index(name) for name in model.names]
    compiled = compiled_engine(settings.engine, settings.flavour)
    workers = settings.workers or _checks.default_workers()
    sims = None
    if not getattr(model, "streams", True):
        # A model that simulates the whole record at once is called once: its output is what is analysed.
        with np.errstate(over="ignore", invalid="ignore"):
            sims = model.simulate(samples[:, model_order], u, dt=settings.dt, x0=settings.x0)
        finite = np.isfinite(sims).all(axis=1)
    elif compiled and _compiled_state_space(model):
        # Unstable sets are found during the analysis (StateErrors.diverged), saving a simulation pass.
        finite = np.ones(samples.shape[0], dtype=bool)
    else:
        finite = model.finite_samples(samples[:, model_order], u, dt=settings.dt, x0=settings.x0)
    while True:
        if not finite.any():
            raise ModelError(
                f"{model!r}: the simulation of every one of the {settings.n_samples} parameter sets is not "
                "finite (NaN or overflow); check the model and the parameter ranges"
            )
        analysed = samples[finite]
        if sims is not None and not finite.all():
            sims = sims[finite]
        chunk_steps = default_chunk_steps(analysed.shape[0], 2 * settings.n)
        if sims is not None:
            errors = ArrayErrors(y, sims)
        elif compiled and compiled_simulation(model):
            errors = CompiledErrors(
                model, analysed[:, model_order], u, y, dt=settings.dt, x0=settings.x0, workers=workers
            )
        elif compiled and _compiled_state_space(model):
            errors = StateErrors(model, analysed[:, model_order], u, y, dt=settings.dt, workers=workers)
        else:
            errors = model.simulate_chunks(
                analysed[:, model_order], u, dt=settings.dt, x0=settings.x0, chunk_steps=chunk_steps
            )
        n_dropped = int(settings.n_samples - analysed.shape[0])
        recorded = settings.record(model, names, box, n_sampled=settings.n_samples, n_dropped=n_dropped)
        try:
            result = analyse_stream(
                y,
                errors,
                analysed,
                box,
                n=settings.n,
                percentage=settings.percentage,
                bins=settings.bins,
                conf_level=settings.conf_level,
                flavour=settings.flavour,
                names=names,
                time=np.arange(y.size) * settings.dt,
                chunk_steps=chunk_steps,
                progress=progress,
                min_points=settings.min_points,
                settings=recorded,
                window=settings.window,
                engine=settings.engine,
                workers=workers,
            )
        finally:
            if isinstance(errors, (CompiledErrors, StateErrors)):
                errors.close()
        if not (isinstance(errors, StateErrors) and errors.diverged.any()):
            break
        # Some sets overflowed: their costs were not finite, so the analysis is redone without them.
        finite[np.flatnonzero(finite)[errors.diverged]] = False
    warn_dropped(n_dropped, settings.n_samples)
    with np.errstate(over="ignore", invalid="ignore"):
        verdicts = assess(result, u=u, y=y, model=model, simulations=sims)
    return _dated(dataclasses.replace(result, verdicts=verdicts), timestamps)


def _dated(result, timestamps):
    return result if timestamps is None else dataclasses.replace(result, timestamps=timestamps)


def _compiled_state_space(model):
    return isinstance(model, StateSpaceModel) and model.compiled


def compiled_simulation(model):
    """Whether the compiled kernels can simulate ``model`` (the single-input linear models)."""
    return isinstance(model, LinearModel) and model.n_inputs == 1


def warn_dropped(n_dropped, n_sampled):
    """Warn (:class:`DroppedSamplesWarning`) when more than 1 % of the sampled sets were dropped."""
    if n_dropped > DROPPED_WARNING_SHARE * n_sampled:
        warnings.warn(
            f"{n_dropped} of {n_sampled} parameter sets ({100 * n_dropped / n_sampled:.1f} %) were dropped "
            "because their simulation is not finite (an unstable model overflowing); the analysis covers "
            "only the rest of the box",
            DroppedSamplesWarning,
            stacklevel=3,
        )
