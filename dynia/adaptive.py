"""Adaptive sampling for DYNIA: spend model evaluations where windows have low cost.

Uniform Monte Carlo wastes most evaluations when the behavioural set is a
small fraction of the prior (thesis 4.2, 5.2). The samplers here concentrate
evaluations in the low-cost regions of the windows and correct for it, so
that the target stays the thesis's uniform-prior definition: the behavioural
set of a window is the lowest-cost ``percentage`` % of the prior.

The correction
--------------
Every sample used for estimation is drawn from a known mixture: a uniform
stage over the whole prior box, then uniform draws inside boxes placed around
the low-cost regions found so far. The mixture density is

    g(theta) = sum_c (n_c / N) * 1[theta in box_c] / volume(box_c),

with the prior box among the components, so g > 0 wherever the prior is.
Each sample gets the importance weight prior(theta) / g(theta) ("deterministic
mixture" weights), and :func:`dynia.engine.moving_window` with these
weights estimates, per window, the prior's lowest-cost fraction and the
weighted quantiles of each parameter inside it: the uniform analysis, with
far more samples where it matters. Every estimation sample serves every
window.

Two schemes place the boxes:

``"iis"`` (iterated importance sampling, global)
    After the uniform stage, each block of consecutive windows gets a box
    around the union of its current behavioural sets (enlarged by a margin);
    the next stage draws uniformly inside the boxes; repeat.
``"de"`` (differential evolution)
    Each block of windows runs a short scipy differential evolution on the
    block's mean cost, started from the previous block's final population;
    the box is set around the population's best members. Its evaluations
    only locate the regions (their density is unknown, so they cannot be
    weighted); they count towards the budget. The estimation stage then
    draws inside the boxes.

``n_samples`` counts model evaluations for every sampler, so budgets compare.

Status (measured on thesis example 1 at percentage 0.1, against uniform
Monte Carlo with 400 000 samples; RMSE of IC over time and both
parameters): uniform 10 000 gives 0.116, uniform 100 000 0.022, "iis"
10 000 0.055-0.06 and "de" 10 000 0.17-0.19. "iis" matches or beats uniform
100 000 before the final settling (steps 0-400) but not after it, where the
behavioural region is L-shaped (small T with any K, or small K with any T)
and one bounding box per block covers the whole prior. Boxes that follow
the shape of a region (several per block, or one around each behavioural
sample) are the next step; the "de" boxes are built from too few points.
notebooks/ch5_sampling_benchmark.py measures every sampler on examples 1
and 2 against 10^6-sample references.
"""

import dataclasses
import math

import numpy as np
from scipy.optimize import differential_evolution

from . import _checks
from .bounds import parameter_box
from .engine.error_sources import ArrayErrors
from .engine.selection import lowest_weighted_head
from .engine.windows import analyse_errors, window_costs
from .errors import SettingsError
from .fit import record_least_squares
from .io.frames import unpack
from .progress import shows_progress
from .quality import screening
from .settings import ADAPTIVE_SAMPLERS as SCHEMES
from .settings import AnalysisSettings, RunRecord, merged_options, merged_settings, split_overrides
from .verdicts import assess

__all__ = [
    "AdaptiveOptions",
    "BoxMixture",
    "adaptive_run",
]


class BoxMixture:
    """A mixture of uniform distributions on boxes, with an exact density.

    Parameters
    ----------
    prior : array_like (n_params, 2)
        The prior box, [low, high] per parameter: the first component.

    Examples
    --------
    >>> mixture = BoxMixture([[0, 4], [0, 1]])
    >>> mixture.add([[1, 2], [0, 1]], count=3)
    >>> mixture.counts
    [0, 3]
    >>> float(mixture.density([[1.5, 0.5]])[0] * 1)  # all weight on the inner box, volume 1
    1.0
    """

    def __init__(self, prior):
        self.prior = _checks.bounds_array(prior, np.asarray(prior).shape[0])
        self.boxes = [self.prior]
        self.counts = [0]

    def add(self, box, count):
        """Add a box (clipped to the prior) that ``count`` samples will be drawn from."""
        box = np.asarray(box, dtype=float).copy()
        box[:, 0] = np.maximum(box[:, 0], self.prior[:, 0])
        box[:, 1] = np.minimum(box[:, 1], self.prior[:, 1])
        self.boxes.append(box)
        self.counts.append(int(count))

    def density(self, points):
        """Mixture density at ``points`` (n, n_params), weighting each box by its count."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        total = sum(self.counts)
        density = np.zeros(points.shape[0])
        for box, count in zip(self.boxes, self.counts):
            if count == 0:
                continue
            inside = ((points >= box[:, 0]) & (points <= box[:, 1])).all(axis=1)
            density += inside * (count / total) / np.prod(box[:, 1] - box[:, 0])
        return density

    def importance_weights(self, points):
        """Prior density over mixture density: uniform prior, so 1/volume(prior) / g."""
        return (1 / np.prod(self.prior[:, 1] - self.prior[:, 0])) / self.density(points)


@dataclasses.dataclass(frozen=True)
class AdaptiveOptions:
    """How :func:`adaptive_run` places its boxes and shares its evaluations (see the module documentation).

    Attributes
    ----------
    blocks : int or None, default None
        Number of blocks of consecutive windows that get their own box
        (None: one per 2n+1 steps, at most 50).
    initial_share : float, default 0.25
        Share of the evaluations drawn uniformly over the prior first.
    stages : int, default 3
        "iis": number of box stages after the uniform one.
    margin : float, default 0.25
        Boxes are enlarged by this share of their width on each side, so
        that the edges of a region are not cut off (and are at least 2 % of
        the prior's width).
    de_share : float, default 0.3
        "de": share of the evaluations given to the differential evolution.
    """

    blocks: int | None = None
    initial_share: float = 0.25
    stages: int = 3
    margin: float = 0.25
    de_share: float = 0.3


def adaptive_run(
    u, y, model, bounds, *, scheme=None, settings=None, options=None, rng=None, progress="auto", **overrides
):
    """DYNIA with evaluations concentrated in the windows' low-cost regions.

    Parameters
    ----------
    u, y, model, bounds, rng, progress
        As :func:`dynia.run`; ``bounds`` is a mapping name -> (low, high).
        pandas ``u`` and ``y`` too, as :func:`dynia.run` takes them
        (:func:`dynia.io.frames.unpack`): one index, whose time gives dt and
        whose dates become the result's ``timestamps``.
    scheme : {"iis", "de"}, optional
        How the boxes are placed (see the module documentation): the
        settings' ``sampler``, which it overrides. Default "iis".
    settings : dynia.settings.AnalysisSettings, optional
        Every analysis setting at once, as for :func:`dynia.run`; its
        ``sampler`` must be "iis" or "de". Without it the defaults are those
        of :class:`~dynia.settings.AnalysisSettings` except
        ``n_samples=10_000`` and ``percentage=1``, where the adaptive
        schemes pay off. ``n_samples`` counts model evaluations in all, for
        every scheme; ``engine`` "numba" is an error (the weighted analysis
        runs on numpy); with ``ic_error`` the Monte Carlo standard errors of
        IC and limits come from the importance-weighted samples: each batch
        (every B-th sample, so every stage of the sampling is in every
        batch) is analysed with its own weights, renormalised.
    options : AdaptiveOptions, optional
        The boxes and the share of the evaluations of each stage.
    **overrides
        Single settings over ``settings``: any field of
        :class:`~dynia.settings.AnalysisSettings` (see :mod:`dynia.settings`
        for the list), e.g. ``n=10, percentage=1``, or of
        :class:`AdaptiveOptions` over ``options``, e.g. ``stages=2``; any
        other name is a :class:`~dynia.errors.SettingsError`.

    Returns
    -------
    DyniaResult
        With ``run.weights`` holding the importance weights of
        ``.samples``, ``run.n_evaluations`` the evaluations spent and
        ``run.n_blocks`` the blocks of windows.

    Examples
    --------
    >>> import numpy as np, dynia
    >>> from dynia.adaptive import adaptive_run
    >>> u = np.r_[np.zeros(20), np.full(60, 1.0)]
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
    >>> res = adaptive_run(u, y, dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)},
    ...                    n_samples=600, n=5, percentage=5, stages=2, rng=1)
    >>> res.run.n_evaluations, res.settings.sampler
    (600, 'iis')
    """
    option_overrides, setting_overrides = split_overrides(adaptive_run, overrides, AdaptiveOptions, AnalysisSettings)
    options = merged_options(AdaptiveOptions, options, option_overrides)
    # pandas in, as dynia.run takes it: a time index gives dt (so before the settings), dates the result's time axis.
    dt = setting_overrides.pop("dt", None)
    u, y, dt, timestamps = unpack(u, y, dt if dt is not None else getattr(settings, "dt", None))
    sampler = {} if scheme is None else {"sampler": scheme}
    settings = merged_settings(
        settings,
        {**setting_overrides, **sampler, "dt": dt},
        front_end=adaptive_run,
        default=AnalysisSettings(n_samples=10_000, percentage=1, sampler="iis"),
    )
    if settings.sampler not in SCHEMES:
        raise SettingsError(f"adaptive_run takes sampler (scheme) 'iis' or 'de'; got {settings.sampler!r}")
    progress = shows_progress(progress)
    u, y = _checks.record(u, y, n_inputs=model.n_inputs)
    names, prior = parameter_box(bounds, model.names, type(model).__name__)
    order = [names.index(name) for name in model.names]
    n_blocks = options.blocks or max(1, min(50, y.size // settings.window_length))

    def simulate(points):
        return model.simulate(points[:, order], u, dt=settings.dt, x0=settings.x0)

    samples, sims, mixture, spent = _staged_samples(
        y,
        simulate,
        prior,
        settings,
        np.linspace(0, y.size, n_blocks + 1).astype(int),
        _checks.generator(rng),
        options,
    )
    weights = mixture.importance_weights(samples)
    run = dataclasses.replace(
        RunRecord.of(model, n_sampled=spent, n_dropped=0),
        n_evaluations=spent,
        weights=weights,
        n_blocks=n_blocks,
        screened=screening(u, y, settings),
    )
    result = analyse_errors(
        y,
        ArrayErrors(y, sims),
        samples,
        prior,
        settings,
        names=names,
        time=np.arange(y.size) * settings.dt,
        progress=progress,
        run=run,
        weights=weights,
        simulations=lambda rows: [sims[rows]],
    )
    result = dataclasses.replace(record_least_squares(result, u, y, model), timestamps=timestamps)
    # The engine gives the noise floor, so the verdicts need neither data nor simulation.
    return dataclasses.replace(result, verdicts=assess(result))


def _staged_samples(y, simulate, prior, settings, edges, rng, options):
    """Every stage's samples and simulations, the mixture they were drawn from and the evaluations spent.

    A uniform stage over the prior first, then the scheme's boxes around
    the low-cost regions of each block of windows (``edges``).
    """
    n_samples, fraction, n, window = settings.n_samples, settings.percentage / 100, settings.n, settings.window
    initial_share, stages, margin, de_share = options.initial_share, options.stages, options.margin, options.de_share
    mixture = BoxMixture(prior)
    initial = max(10, int(n_samples * initial_share))
    samples = _uniform_in(prior, initial, rng)
    sims = simulate(samples)
    mixture.counts[0] = initial
    spent = initial
    if settings.sampler == "iis":
        per_stage = (n_samples - spent) // max(stages, 1)
        for _ in range(stages):
            weights = mixture.importance_weights(samples)
            regions = _behavioural_boxes(
                y, sims, samples, weights / weights.sum(), fraction, n, edges, prior, margin, window
            )
            new_samples = _draw_in_boxes(mixture, regions, per_stage, rng)
            samples = np.r_[samples, new_samples]
            sims = np.r_[sims, simulate(new_samples)]
            spent += new_samples.shape[0]
        return samples, sims, mixture, spent
    n_blocks = edges.size - 1
    budget = int(n_samples * de_share)
    population_size = _population_size(prior.shape[0])
    needed = spent + n_blocks * (2 * population_size + 1)
    if n_samples < needed:
        raise SettingsError(
            f"the 'de' scheme needs at least {needed} evaluations for {n_blocks} blocks of windows "
            f"(a population of {population_size} evolved twice per block); got n_samples={n_samples}: "
            "raise n_samples or lower blocks"
        )
    regions, used = _evolved_boxes(y, simulate, prior, fraction, n, edges, budget, margin, rng, window)
    spent += used
    new_samples = _draw_in_boxes(mixture, regions, n_samples - spent, rng)
    samples = np.r_[samples, new_samples]
    sims = np.r_[sims, simulate(new_samples)]
    spent += new_samples.shape[0]
    return samples, sims, mixture, spent


def _uniform_in(box, count, rng):
    return rng.random((count, box.shape[0])) * (box[:, 1] - box[:, 0]) + box[:, 0]


def _draw_in_boxes(mixture, regions, count, rng):
    """``count`` draws shared equally among ``regions``, each registered with the mixture."""
    shares = np.full(len(regions), count // len(regions))
    shares[: count - shares.sum()] += 1
    drawn = []
    for region, share in zip(regions, shares):
        mixture.add(region, share)
        drawn.append(_uniform_in(mixture.boxes[-1], share, rng))
    return np.concatenate(drawn)


def _enlarged(low, high, prior, margin):
    # A region seen through one or two samples has no width yet: give it a little of the prior's.
    width = np.maximum(high - low, 0.02 * (prior[:, 1] - prior[:, 0]))
    centre = (low + high) / 2
    return np.stack(
        [
            np.maximum(centre - width / 2 - margin * width, prior[:, 0]),
            np.minimum(centre + width / 2 + margin * width, prior[:, 1]),
        ],
        axis=1,
    )


def _behavioural_boxes(y, sims, samples, prior_weights, fraction, n, edges, prior, margin, window):
    """One box per block of windows, around the union of the block's behavioural samples."""
    boxes = []
    for start, stop in zip(edges[:-1], edges[1:]):
        cost = window_costs(y, sims, n, start, stop, window)
        order, behavioural = lowest_weighted_head(np.nan_to_num(cost, copy=False, nan=np.inf), prior_weights, fraction)
        chosen = np.unique(order[behavioural])
        boxes.append(_enlarged(samples[chosen].min(axis=0), samples[chosen].max(axis=0), prior, margin))
    return boxes


def _population_size(n_params):
    return max(5 * n_params, 10)


def _evolved_boxes(y, simulate, prior, fraction, n, edges, budget, margin, rng, window):
    """Differential evolution per block, each started from the last block's population."""
    n_params = prior.shape[0]
    population_size = _population_size(n_params)
    per_block = max(budget // len(edges[:-1]), 2 * population_size)
    generations = max(1, per_block // population_size - 1)
    population = _uniform_in(prior, population_size, rng)
    boxes, used = [], 0
    for start, stop in zip(edges[:-1], edges[1:]):
        evaluated = []

        def block_cost(points, start=start, stop=stop, evaluated=evaluated):  # bound now: called in this pass
            sims = simulate(points.T)
            cost = np.nanmean(window_costs(y, sims, n, start, stop, window), axis=0)
            evaluated.append((points.T.copy(), cost))
            return cost

        found = differential_evolution(
            block_cost,
            prior,
            init=population,
            maxiter=generations,
            popsize=1,
            polish=False,
            vectorized=True,
            updating="deferred",
            tol=0,
            rng=rng,
        )
        points = np.concatenate([points for points, _ in evaluated])
        costs = np.concatenate([cost for _, cost in evaluated])
        used += points.shape[0]
        # The best few evaluated points outline the block's low-cost region.
        best = points[np.argsort(costs)[: max(n_params + 1, math.ceil(0.2 * population_size))]]
        boxes.append(_enlarged(best.min(axis=0), best.max(axis=0), prior, margin))
        population = found.population
    return boxes, used
