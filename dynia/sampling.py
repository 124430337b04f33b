"""Parameter sampling over a box of bounds: uniform Monte Carlo, Latin hypercube, Sobol.

Every sampler returns (n_samples, n_params) with the columns in the order of
``bounds`` rows (the package's shape convention, see :mod:`dynia.engine`),
and draws all its randomness from ``rng`` (a :class:`numpy.random.Generator`
or a seed; the same seed gives bit-identical samples).
"""

import numpy as np

from . import _checks
from .errors import SettingsError
from .settings import SAMPLERS, sample_count

__all__ = ["sample", "uniform", "latin_hypercube", "sobol", "SAMPLERS"]


def uniform(n_samples, bounds, rng=None):
    """Independent uniform draws, as the thesis's Monte Carlo (``rand*(ub-lb)+lb``).

    Examples
    --------
    >>> uniform(3, [[0, 7], [0, 7]], rng=1).shape
    (3, 2)
    """
    n_samples, bounds, rng = _prepare(n_samples, bounds, rng)
    unit = rng.random((n_samples, bounds.shape[0]))
    return unit * (bounds[:, 1] - bounds[:, 0]) + bounds[:, 0]


def latin_hypercube(n_samples, bounds, rng=None):
    """Latin hypercube: each parameter's range cut into n_samples equal strata, one draw per stratum.

    Examples
    --------
    >>> x = latin_hypercube(4, [[0, 4]], rng=1)
    >>> sorted(int(v) for v in x[:, 0])
    [0, 1, 2, 3]
    """
    n_samples, bounds, rng = _prepare(n_samples, bounds, rng)
    from scipy.stats import qmc  # here: scipy.stats takes a second to import, which uniform sampling does not need

    unit = qmc.LatinHypercube(d=bounds.shape[0], rng=rng).random(n_samples)
    return qmc.scale(unit, bounds[:, 0], bounds[:, 1])


def sobol(n_samples, bounds, rng=None):
    """Scrambled Sobol points (scipy.stats.qmc); balance is best for powers of two.

    Examples
    --------
    >>> sobol(8, [[0, 1], [10, 20]], rng=1).shape
    (8, 2)
    """
    n_samples, bounds, rng = _prepare(n_samples, bounds, rng)
    from scipy.stats import qmc

    engine = qmc.Sobol(d=bounds.shape[0], scramble=True, rng=rng)
    # Draw the next power of two and keep the first n_samples: a prefix of a
    # Sobol sequence is still low-discrepancy, and scipy warns on other sizes.
    unit = engine.random_base2(int(np.ceil(np.log2(max(n_samples, 1)))))[:n_samples]
    return qmc.scale(unit, bounds[:, 0], bounds[:, 1])


# The draw of each of the settings' SAMPLERS, by name.
_DRAWS = dict(zip(SAMPLERS, (uniform, latin_hypercube, sobol), strict=True))


def sample(method, n_samples, bounds, rng=None):
    """Draw with the sampler named ``method`` (one of :data:`dynia.settings.SAMPLERS`)."""
    if method not in SAMPLERS:
        raise SettingsError(f"sampler must be one of {SAMPLERS}; got {method!r}")
    return _DRAWS[method](n_samples, bounds, rng)


def _prepare(n_samples, bounds, rng):
    n_samples = sample_count(n_samples, "n_samples")
    bounds = _checks.as_2d_float(bounds, "bounds", columns=2)
    _checks.bounds_array(bounds, bounds.shape[0])
    return n_samples, bounds, _checks.generator(rng)
