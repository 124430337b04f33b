"""``dynia.run``: sample, simulate and analyse in one call, streaming over time."""
import os
from collections.abc import Mapping

import numpy as np

from . import _checks
from .adaptive import SCHEMES, adaptive_run
from ._fast import CompiledErrors
from .analysis import analyse_stream, compiled_engine, default_chunk_steps
from .sampling import sample

__all__ = ["run"]


def run(u, y, model, bounds, *, dt=1.0, n_samples=2000, sampler="uniform", n=10, percentage=10,
        bins=40, conf_level=90, flavour="thesis", x0="zero", rng=None, progress=False,
        min_points=1, window="centred", engine="auto", workers=None):
    """Dynamic identifiability analysis of a model against measured data.

    Draws ``n_samples`` parameter sets from the box ``bounds``, simulates the
    model for each and runs the moving-window analysis of
    :func:`dynia.analysis.moving_window` on all parameters at once. The
    simulation is streamed into the analysis in time chunks, so memory does
    not grow with n_samples x n_steps.

    Parameters
    ----------
    u, y : array_like, shape (n_steps,)
        Input and measured output, one value per sample time ``k*dt``. NaN in
        ``y`` marks a missing measurement.
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

    Returns
    -------
    DyniaResult
        Parameter sets whose simulation is not finite over the record
        (an unstable model overflowing) are left out of the analysis, never
        ranked; ``settings["n_dropped"]`` counts them and ``.samples`` holds
        the sets analysed.

    Examples
    --------
    >>> import numpy as np, dynia
    >>> u = np.r_[np.zeros(20), np.full(60, 1.0)]
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
    >>> res = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n=5, rng=1)
    >>> res.ic.shape
    (2, 80)
    """
    u = _checks.as_1d_float(u, "u")
    y = _checks.as_1d_float(y, "y", allow_nan=True)
    if u.size != y.size:
        raise ValueError(f"u has {u.size} samples but y has {y.size}; they must be logged on the same steps")
    names, box = _ordered_bounds(bounds, model)
    if sampler in SCHEMES:
        return adaptive_run(u, y, model, dict(zip(names, map(tuple, box))), scheme=sampler, dt=dt,
                            n_samples=n_samples, n=n, percentage=percentage, bins=bins,
                            conf_level=conf_level, flavour=flavour, x0=x0, rng=rng, window=window)
    n_samples = _checks.whole_number(n_samples, "n_samples", minimum=1)
    n = _checks.whole_number(n, "n", minimum=0)
    samples = sample(sampler, n_samples, box, np.random.default_rng(rng))
    model_order = [names.index(name) for name in model.names]
    finite = model.finite_samples(samples[:, model_order], u, dt=dt, x0=x0)
    if not finite.any():
        raise ValueError(f"the simulation of every one of the {n_samples} parameter sets overflowed; "
                         "check the model and the parameter ranges")
    samples = samples[finite]
    chunk_steps = default_chunk_steps(samples.shape[0], 2 * n)
    if workers is None:
        workers = os.cpu_count() or 1
    workers = _checks.whole_number(workers, "workers", minimum=1)
    if compiled_engine(engine, flavour):
        errors = CompiledErrors(model, samples[:, model_order], u, y, dt=dt, x0=x0, workers=workers)
    else:
        errors = model.simulate_chunks(samples[:, model_order], u, dt=dt, x0=x0, chunk_steps=chunk_steps)
    settings = dict(dt=dt, sampler=sampler, x0=x0, model=type(model).__name__,
                    bounds={name: tuple(map(float, row)) for name, row in zip(names, box)},
                    n_sampled=n_samples, n_dropped=int(n_samples - samples.shape[0]))
    try:
        return analyse_stream(y, errors, samples, box, n=n, percentage=percentage, bins=bins,
                              conf_level=conf_level, flavour=flavour, names=names,
                              time=np.arange(y.size) * float(dt), chunk_steps=chunk_steps,
                              progress=progress, min_points=min_points, settings=settings,
                              window=window, engine=engine, workers=workers)
    finally:
        if isinstance(errors, CompiledErrors):
            errors.close()


def _ordered_bounds(bounds, model):
    """Names in the order given and an (n_params, 2) box; every model parameter exactly once."""
    if not isinstance(bounds, Mapping):
        raise ValueError(
            f"bounds must map each parameter name to (low, high), e.g. {{'K': (0, 7)}}; got {type(bounds).__name__}")
    names = [str(name) for name in bounds]
    unknown = [name for name in names if name not in model.names]
    missing = [name for name in model.names if name not in names]
    if unknown or missing:
        raise ValueError(
            f"bounds must name every parameter of {type(model).__name__} {list(model.names)} once"
            + (f"; unknown: {unknown}" if unknown else "") + (f"; missing: {missing}" if missing else ""))
    rows = []
    for name in names:
        pair = bounds[name]
        try:
            if isinstance(pair, (str, bytes)):
                raise TypeError
            low, high = (float(value) for value in pair)
        except (TypeError, ValueError):
            raise ValueError(f"bounds[{name!r}] must be a (low, high) pair of numbers; got {pair!r}") from None
        if not (np.isfinite(low) and np.isfinite(high) and low < high):
            raise ValueError(f"bounds[{name!r}]: need finite low < high; got ({low}, {high})")
        rows.append((low, high))
    return names, np.array(rows)
