"""Nonlinear conceptual models: the HYMOD rainfall-runoff model and a draining tank.

DYNIA was born on conceptual hydrological models (Wagener et al. 2003): a
handful of stores whose parameters each matter in a different part of the
record. :func:`hymod` builds the five-parameter HYMOD model and :func:`tank`
a tank with square-root outflow, both as
:class:`~dynia.models.StateSpaceModel`, compiled with numba when it is
installed (a plain numpy update otherwise, same equations, same results to
rounding). :func:`hymod_record` and :func:`tank_record` make synthetic
records from known parameters, so that every DYNIA finding on them can be
checked against the truth; :func:`hymod_fluxes` returns every flux of one
HYMOD simulation, for water balances.

Examples
--------
>>> import numpy as np
>>> from dynia.models.conceptual import tank
>>> model = tank()
>>> model.names
('A', 'c')
>>> level = model.simulate([[2.0, 0.5]], np.full(400, 0.5))[0]
>>> round(float(level[-1]), 6)    # the steady level (q/c)**2
1.0
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError, SettingsError
from . import StateSpaceModel

try:
    import numba
except ImportError:  # the numpy update serves
    numba = None

__all__ = [
    "HYMOD_NAMES",
    "SyntheticRecord",
    "hymod",
    "hymod_fluxes",
    "hymod_record",
    "tank",
    "tank_record",
]

HYMOD_NAMES = ("cmax", "b", "alpha", "kq", "ks")
# The order of the state vector of hymod(), and of hymod_fluxes()["states"] columns.
HYMOD_STATES = ("soil", "quick1", "quick2", "quick3", "slow")
TANK_NAMES = ("A", "c")

# The parameters of the synthetic records.
HYMOD_TRUTH = {"cmax": 250.0, "b": 0.8, "alpha": 0.6, "kq": 0.5, "ks": 0.04}
TANK_TRUTH = {"A": 2.0, "c": 0.3}


def _hymod_valid(rain, pet, cmax, b, alpha, kq, ks):
    """Whether a parameter set and the step's inputs are in range (scalars or arrays)."""
    shares = (alpha >= 0) & (alpha <= 1) & (kq >= 0) & (kq <= 1) & (ks >= 0) & (ks <= 1)
    return shares & (cmax > 0) & (b >= 0) & (rain >= 0) & (pet >= 0)


def _hymod_update(soil, quick1, quick2, quick3, slow, rain, pet, cmax, b, alpha, kq, ks):
    """One step of HYMOD: new stores, discharge, actual evaporation and excess rainfall.

    Written with arithmetic and numpy ufuncs only, so that numba compiles for
    scalars the very source numpy runs on arrays. Inputs must be valid
    (:func:`_hymod_valid`); the callers make invalid ones NaN.
    """
    exponent = b + 1.0
    smax = cmax / exponent
    # The critical capacity (the largest point capacity already full) of the present storage, then after the rain.
    fill = np.minimum(np.maximum(soil / smax, 0.0), 1.0)
    critical = cmax * (1.0 - (1.0 - fill) ** (1.0 / exponent))
    reached = np.minimum(critical + rain, cmax)
    # Clipped, the rounding of the round trip storage -> capacity -> storage can neither create nor lose water:
    # rain = stored + excess exactly.
    stored = np.minimum(np.maximum(smax * (1.0 - (1.0 - reached / cmax) ** exponent) - soil, 0.0), rain)
    excess = rain - stored
    wetted = soil + stored
    evaporation = np.minimum(pet * np.minimum(wetted / smax, 1.0), wetted)
    soil = wetted - evaporation
    # Linear reservoirs: the step's inflow joins the store, a share k of it leaves.
    store = quick1 + alpha * excess
    out1 = kq * store
    quick1 = store - out1
    store = quick2 + out1
    out2 = kq * store
    quick2 = store - out2
    store = quick3 + out2
    out3 = kq * store
    quick3 = store - out3
    store = slow + (excess - alpha * excess)
    out_slow = ks * store
    slow = store - out_slow
    return soil, quick1, quick2, quick3, slow, out3 + out_slow, evaporation, excess


def _hymod_numpy(x, rain, pet, params):
    """:func:`_hymod_update` on (n_samples,) columns, NaN for invalid sets."""
    columns = params.T
    rain = np.where(_hymod_valid(rain, pet, *columns), rain, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):  # an invalid set's 0/0: NaN, as intended
        return _hymod_update(*x.T, rain, pet, *columns)


def _hymod_step_numpy(x, u_k, params, dt):
    return np.stack(_hymod_numpy(x, u_k[0], u_k[1], params)[:5], axis=1)


def _hymod_output_numpy(x, u_k, params):
    return _hymod_numpy(x, u_k[0], u_k[1], params)[5]


def _tank_valid(inflow, area, c):
    return (area > 0) & (c >= 0) & (inflow >= 0)


def _tank_level(level, inflow, area, c, dt, substeps):
    """The level after one sample step: ``substeps`` backward-Euler steps, each solved exactly.

    Backward Euler in ``h`` is a quadratic in ``s = sqrt(h)``: ``s**2 + beta*s
    - gamma = 0`` with ``beta = tau*c/A`` and ``gamma = h + tau*q/A``. Its
    root is taken in the form without cancellation. Scalars or arrays alike;
    inputs must be valid (:func:`_tank_valid`).
    """
    tau = dt / substeps
    beta = tau * c / area
    for _ in range(substeps):
        gamma = level + tau * inflow / area
        # The floor keeps an empty tank without inflow or outflow (0/0) at level 0.
        root = 2.0 * gamma / np.maximum(beta + np.sqrt(beta * beta + 4.0 * gamma), 1e-300)
        level = root * root
    return level


def _tank_step_numpy(x, u_k, params, dt, substeps):
    area, c = params[:, 0], params[:, 1]
    level = np.where(_tank_valid(u_k, area, c), x[:, 0], np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):  # an invalid set's 0/0: NaN, as intended
        return _tank_level(level, u_k, area, c, dt, substeps)[:, None]


def _tank_output(x, u_k, params):
    return x[:, 0].copy()


if numba is not None:
    # numpy's error model: an invalid set's 0/0 is NaN, as on the numpy path, instead of a ZeroDivisionError.
    _compile = numba.njit(error_model="numpy")
    _hymod_valid_compiled = _compile(_hymod_valid)
    _hymod_update_compiled = _compile(_hymod_update)
    _tank_valid_compiled = _compile(_tank_valid)
    _tank_level_compiled = _compile(_tank_level)

    @_compile
    def _hymod_sample(x, u_k, params, i):
        """:func:`_hymod_update` for sample ``i``, NaN for an invalid set."""
        rain, pet = u_k[0], u_k[1]
        cmax, b, alpha, kq, ks = params[i, 0], params[i, 1], params[i, 2], params[i, 3], params[i, 4]
        if not _hymod_valid_compiled(rain, pet, cmax, b, alpha, kq, ks):
            rain = np.nan
        return _hymod_update_compiled(x[i, 0], x[i, 1], x[i, 2], x[i, 3], x[i, 4], rain, pet, cmax, b, alpha, kq, ks)

    @_compile
    def _hymod_step_compiled(x, u_k, params, dt):
        following = np.empty_like(x)
        for i in range(x.shape[0]):
            result = _hymod_sample(x, u_k, params, i)
            following[i, 0] = result[0]
            following[i, 1] = result[1]
            following[i, 2] = result[2]
            following[i, 3] = result[3]
            following[i, 4] = result[4]
        return following

    @_compile
    def _hymod_output_compiled(x, u_k, params):
        discharge = np.empty(x.shape[0])
        for i in range(x.shape[0]):
            discharge[i] = _hymod_sample(x, u_k, params, i)[5]
        return discharge

    @_compile
    def _tank_output_compiled(x, u_k, params):
        return x[:, 0].copy()

    @functools.cache
    def _tank_step_factory(substeps):
        """The compiled step for ``substeps`` (a constant of the compiled code), compiled once per value."""

        @_compile
        def step(x, u_k, params, dt):
            following = np.empty_like(x)
            for i in range(x.shape[0]):
                area, c = params[i, 0], params[i, 1]
                level = x[i, 0] if _tank_valid_compiled(u_k, area, c) else np.nan
                following[i, 0] = _tank_level_compiled(level, u_k, area, c, dt, substeps)
            return following

        return step

else:  # pragma: no cover - hymod() and tank() fall back to numpy without numba
    _hymod_step_compiled = _hymod_output_compiled = _tank_output_compiled = _tank_step_factory = None


def _use_numba(compiled):
    if compiled is None:
        return numba is not None
    if compiled and numba is None:
        raise SettingsError("compiled=True needs numba, which is not installed; pass compiled=None or False")
    return bool(compiled)


def _initial_state(x0, n_states, what):
    state = np.zeros(n_states) if x0 is None else np.asarray(x0, dtype=float)
    if state.shape != (n_states,) or not np.isfinite(state).all() or (state < 0).any():
        raise ModelError(f"x0 of {what} must be {n_states} finite numbers >= 0; got {x0!r}")
    return state


def hymod(*, x0=None, compiled=None) -> StateSpaceModel:
    """The five-parameter HYMOD rainfall-runoff model (Boyle 2001; Wagener et al. 2001).

    A soil store with a Pareto distribution of point storage capacities
    turns rain into excess rainfall; a share ``alpha`` of it runs through
    three identical linear reservoirs (quick flow), the rest through one
    linear reservoir (slow flow). Per step ``k``, with rain ``P`` and
    potential evaporation ``E`` (depths per step, e.g. mm/day):

    1. *Storage capacities.* Point capacities ``c`` in ``[0, cmax]`` have
       the distribution ``F(c) = 1 - (1 - c/cmax)**b``. When every point of
       capacity below ``C`` is full, the soil holds ``S(C) = Smax * (1 - (1 -
       C/cmax)**(b+1))`` with ``Smax = cmax/(b+1)``; inversely, storage
       ``S`` fills the capacities up to ``C(S) = cmax * (1 - (1 -
       S/Smax)**(1/(b+1)))``.
    2. *Excess rainfall.* Rain raises the critical capacity from ``C(S)``
       to ``C' = min(C(S) + P, cmax)``; the soil stores ``S(C') - S(C(S))``
       and the rest of ``P`` (rain on full points, and all rain once every
       point is full) is the excess ``ER``.
    3. *Evaporation* from the wetted soil store ``S'``: ``Ea = min(E * S'/Smax,
       S')``, so it falls with soil moisture and never empties the store below zero.
    4. *Routing.* ``alpha * ER`` enters the first quick reservoir and
       ``(1 - alpha) * ER`` the slow one. Each reservoir adds its inflow to
       its store ``Si`` and releases ``k * Si`` in the same step (``kq``
       for the three quick ones in series, ``ks`` for the slow one), so
       ``1/k`` is its residence time in steps.
    5. The discharge ``Q = kq*S3 + ks*Ss`` of step k is the output ``y[k]``.

    Every step conserves water: ``P = (S' - S) + ER``, each reservoir's
    change is its inflow minus its outflow, and over a record the change of
    total storage is ``sum(P) - sum(Ea) - sum(Q)`` (see :func:`hymod_fluxes`).

    Parameters
    ----------
    x0 : array_like (5,), optional
        Initial stores (soil, quick1, quick2, quick3, slow), default all
        empty: a record that starts dry.
    compiled : bool, optional
        Use numba-compiled update functions (default: when numba is
        installed) or the numpy ones.

    Returns
    -------
    StateSpaceModel
        Parameters ``("cmax", "b", "alpha", "kq", "ks")``: ``cmax > 0`` the
        largest point capacity (mm), ``b >= 0`` the Pareto shape, ``alpha``
        in [0, 1] the quick-flow share, ``kq`` and ``ks`` in [0, 1] the
        outflow shares per step. Two inputs, ``u`` (n_steps, 2) with
        columns P and E. ``dt`` is not used: the fluxes are depths per step.
        A parameter set outside these ranges, or a negative input, simulates
        to NaN, and :func:`dynia.run` leaves it out with a warning.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.models.conceptual import hymod
    >>> u = np.zeros((6, 2))
    >>> u[1, 0] = 50.0      # one storm of 50 mm on a dry soil: 37.5 mm stored, 12.5 mm excess
    >>> hymod().simulate([[100.0, 1.0, 0.5, 0.5, 0.1]], u).round(3)
    array([[0.   , 1.406, 1.734, 1.678, 1.432, 1.142]])
    """
    state = _initial_state(x0, 5, "hymod")
    if _use_numba(compiled):
        step, output = _hymod_step_compiled, _hymod_output_compiled
    else:
        step, output = _hymod_step_numpy, _hymod_output_numpy
    return StateSpaceModel(step, output, state, HYMOD_NAMES, n_states=5, n_inputs=2)


def hymod_fluxes(params, u, *, x0=None) -> dict:
    """Every flux and store of one HYMOD simulation, for water balances and plots.

    Parameters
    ----------
    params : mapping or array_like (5,)
        ``{"cmax": ..., "b": ..., "alpha": ..., "kq": ..., "ks": ...}`` or the
        five values in that order.
    u : array_like (n_steps, 2)
        Rain and potential evaporation per step.
    x0 : array_like (5,), optional
        Initial stores, as :func:`hymod`.

    Returns
    -------
    dict
        ``states`` (n_steps + 1, 5): the stores before every step and after
        the last; ``discharge``, ``evaporation`` (actual) and ``excess``
        (effective rainfall), each (n_steps,). ``discharge`` is what
        :func:`hymod` outputs.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.models.conceptual import hymod_fluxes
    >>> u = np.column_stack([np.r_[0.0, 50.0, np.zeros(8)], np.full(10, 2.0)])
    >>> flux = hymod_fluxes([100.0, 1.0, 0.5, 0.5, 0.1], u)
    >>> change = flux["states"][-1].sum() - flux["states"][0].sum()
    >>> bool(abs(change - (u[:, 0].sum() - flux["evaporation"].sum() - flux["discharge"].sum())) < 1e-12)
    True
    """
    if isinstance(params, dict):
        missing = [name for name in HYMOD_NAMES if name not in params]
        if missing:
            raise SettingsError(f"params lacks {missing}; expected the keys {list(HYMOD_NAMES)}")
        params = [params[name] for name in HYMOD_NAMES]
    values = np.asarray(params, dtype=float)
    if values.shape != (5,):
        raise SettingsError(f"params must be the five values {list(HYMOD_NAMES)}; got shape {values.shape}")
    forcing = np.asarray(u, dtype=float)
    if forcing.ndim != 2 or forcing.shape[1] != 2:
        raise SettingsError(f"u must be (n_steps, 2), columns rain and potential evaporation; got {forcing.shape}")
    n_steps = forcing.shape[0]
    states = np.empty((n_steps + 1, 5))
    states[0] = _initial_state(x0, 5, "hymod")
    discharge, evaporation, excess = np.empty(n_steps), np.empty(n_steps), np.empty(n_steps)
    for k in range(n_steps):
        result = _hymod_numpy(states[k : k + 1], forcing[k, :1], forcing[k, 1:], values[None, :])
        states[k + 1] = np.concatenate(result[:5])
        discharge[k], evaporation[k], excess[k] = result[5][0], result[6][0], result[7][0]
    return dict(states=states, discharge=discharge, evaporation=evaporation, excess=excess)


def tank(*, h0=0.0, substeps=10, compiled=None) -> StateSpaceModel:
    """A tank with square-root outflow: ``A dh/dt = q_in - c*sqrt(h)``, output the level ``h``.

    The outflow through an orifice grows with the square root of the level,
    so the tank's time constant grows with the level (linearised at the
    steady level ``h* = (q/c)**2`` it is ``2*A*sqrt(h*)/c``) and the
    steady level does not depend on the area ``A``.

    Each sample step is integrated with ``substeps`` backward (implicit)
    Euler steps of ``dt/substeps``, each solved exactly (a quadratic in
    ``sqrt(h)``). The scheme is stable for any step, never drives the level
    below zero, and its fixed point is the exact steady level ``(q/c)**2``;
    its error in a transient is first order in the substep. On
    :func:`tank_record` (time constants of 7 samples and more) ten substeps
    keep the level within 0.2 % of its range of an accurate ODE solution.

    Parameters
    ----------
    h0 : float, default 0.0
        Initial level (an empty tank).
    substeps : int, default 10
        Implicit Euler steps per sample step.
    compiled : bool, optional
        Use numba-compiled update functions (default: when numba is
        installed) or the numpy ones.

    Returns
    -------
    StateSpaceModel
        Parameters ``("A", "c")``, ``A > 0`` and ``c >= 0``; one input, the
        inflow ``q_in >= 0`` held over each step; ``dt`` the sample time.
        Values out of range simulate to NaN.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.models.conceptual import tank
    >>> level = tank().simulate([[1.0, 0.5], [4.0, 0.5]], np.full(5, 0.5))
    >>> level.round(3)          # the larger tank fills more slowly towards h* = 1
    array([[0.   , 0.296, 0.479, 0.608, 0.701],
           [0.   , 0.097, 0.175, 0.242, 0.302]])
    """
    substeps = _substeps(substeps)
    state = _initial_state([h0], 1, "tank")
    if _use_numba(compiled):
        step, output = _tank_step_factory(substeps), _tank_output_compiled
    else:

        def step(x, u_k, params, dt):
            return _tank_step_numpy(x, u_k, params, dt, substeps)

        output = _tank_output
    return StateSpaceModel(step, output, state, TANK_NAMES, n_states=1, n_inputs=1)


def _substeps(value):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise SettingsError(f"substeps must be a whole number >= 1; got {value!r}")
    return int(value)


@dataclass(frozen=True)
class SyntheticRecord:
    """A synthetic record from known parameters.

    Attributes
    ----------
    u : ndarray
        The input: (n_steps, 2) rain and potential evaporation for HYMOD,
        (n_steps,) inflow for the tank.
    y : ndarray (n_steps,)
        The measured output: ``clean`` plus noise.
    clean : ndarray (n_steps,)
        The model's output for the true parameters.
    truth : dict
        The true parameters, by name.
    noise : float
        The noise level the record was made with (see the generator).
    dt : float
        The sample time.
    """

    u: np.ndarray
    y: np.ndarray
    clean: np.ndarray
    truth: dict
    noise: float
    dt: float


def _generator(rng):
    if not isinstance(rng, np.random.Generator):
        raise SettingsError(f"rng must be a numpy.random.Generator; got {type(rng).__name__}")
    return rng


def _length(n_steps, minimum):
    if isinstance(n_steps, bool) or not isinstance(n_steps, (int, np.integer)) or n_steps < minimum:
        raise SettingsError(f"n_steps must be a whole number >= {minimum}; got {n_steps!r}")
    return int(n_steps)


def _noise_level(noise):
    if isinstance(noise, bool) or not isinstance(noise, (int, float)) or not 0 <= noise < np.inf:
        raise SettingsError(f"noise must be a finite number >= 0; got {noise!r}")
    return float(noise)


def hymod_record(n_steps=1095, *, rng, noise=0.1) -> SyntheticRecord:
    """Daily rain, potential evaporation and noisy discharge of HYMOD with :data:`HYMOD_TRUTH`.

    The year starts in late summer on a dry catchment (all stores empty).
    Rain falls in storms: a wet day follows a wet day with probability 0.6
    and a dry day with a seasonal probability (0.35 in winter, 0.1 in
    summer), its depth exponential with mean 9 mm; every year has a dry
    spell of 40 days in early summer, so the soil dries out and later wets
    up again. Potential evaporation is a seasonal sine between 0.5 and 5
    mm/day. The discharge carries relative Gaussian noise: ``y = Q * (1 +
    noise * e)``, as gauging errors grow with the flow.

    Parameters
    ----------
    n_steps : int, default 1095
        Days (at least 30).
    rng : numpy.random.Generator
        Source of every random draw: the same seed gives the same record.
    noise : float, default 0.1
        Relative standard deviation of the discharge errors.

    Examples
    --------
    >>> import numpy as np
    >>> record = hymod_record(365, rng=np.random.default_rng(1))
    >>> record.u.shape, record.truth["kq"]
    ((365, 2), 0.5)
    """
    rng = _generator(rng)
    n_steps = _length(n_steps, 30)
    noise = _noise_level(noise)
    day = np.arange(n_steps)
    # Day 0 is late summer: the season's phase puts the evaporation peak 30 days before the start.
    season = np.cos(2 * np.pi * (day + 30) / 365.0)  # 1 at midsummer, -1 at midwinter
    pet = 2.75 + 2.25 * season
    wet_after_dry = 0.225 - 0.125 * season
    wet = np.zeros(n_steps, dtype=bool)
    draws = rng.random(n_steps)
    for k in range(1, n_steps):
        wet[k] = draws[k] < (0.6 if wet[k - 1] else wet_after_dry[k])
    wet[((day + 30) % 365 >= 320) & ((day + 30) % 365 < 360)] = False  # the early-summer dry spell
    wet[:5] = False  # a dry start, before the first storm
    rain = np.where(wet, rng.exponential(9.0, n_steps), 0.0)
    u = np.column_stack([rain, pet])
    clean = hymod(compiled=False).simulate([[HYMOD_TRUTH[name] for name in HYMOD_NAMES]], u)[0]
    y = clean * (1.0 + noise * rng.standard_normal(n_steps))
    return SyntheticRecord(u=u, y=y, clean=clean, truth=dict(HYMOD_TRUTH), noise=noise, dt=1.0)


def tank_record(n_steps=800, *, rng, noise=0.02, dt=1.0) -> SyntheticRecord:
    """An inflow schedule of steps and the noisy level of :func:`tank` with :data:`TANK_TRUTH`.

    The tank starts empty with the valve closed for 10 steps; then the
    inflow steps to a new level, drawn uniformly from [0.1, 0.6], every 60
    to 150 steps (long enough, at ``dt = 1``, to settle: the time constant
    is 7 to 23 steps over that range). The level carries additive Gaussian
    noise of standard deviation ``noise``.

    Parameters
    ----------
    n_steps : int, default 800
        Samples (at least 20).
    rng : numpy.random.Generator
        Source of every random draw.
    noise : float, default 0.02
        Standard deviation of the level errors.
    dt : float, default 1.0
        Sample time.

    Examples
    --------
    >>> import numpy as np
    >>> record = tank_record(300, rng=np.random.default_rng(1))
    >>> bool(record.clean[:10].max() == 0.0), record.truth
    (True, {'A': 2.0, 'c': 0.3})
    """
    rng = _generator(rng)
    n_steps = _length(n_steps, 20)
    noise = _noise_level(noise)
    if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not 0 < dt < np.inf:
        raise SettingsError(f"dt must be a finite number > 0; got {dt!r}")
    inflow = np.zeros(n_steps)
    start = 10
    while start < n_steps:
        hold = int(rng.integers(60, 151))
        inflow[start : start + hold] = rng.uniform(0.1, 0.6)
        start += hold
    clean = tank(compiled=False).simulate([[TANK_TRUTH[name] for name in TANK_NAMES]], inflow, dt=float(dt))[0]
    y = clean + noise * rng.standard_normal(n_steps)
    return SyntheticRecord(u=inflow, y=y, clean=clean, truth=dict(TANK_TRUTH), noise=noise, dt=float(dt))
