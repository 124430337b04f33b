"""Least squares on data segments, and the validation of the fitted model.

:func:`fit_segments` fits a model to the measured output inside chosen
segments (see :mod:`dynia.segments` for what a segment is and how DYNIA
selects them) and :func:`validation_error` scores a fitted model on held-out
data.

Initial state of a segment
--------------------------
The output in a segment depends on the state at its start, which is not
measured. Every segment is simulated from an earlier step ``s`` where the
state is taken as known, on the measured input (the input is known
everywhere), and only the residuals inside the segment are fitted:

- ``warmup=None`` (default): ``s = 0``, the start of the record, in state
  ``x0``. The state entering each segment is then exactly the model's
  response to the whole input history, the model DYNIA analysed, with no
  truncation error; all segments share one simulation.
- ``warmup=w``: ``s = max(0, start - w)``. For a record too long to simulate
  whole, or whose early part is not trusted; the error of assuming state
  ``x0`` at ``s`` decays like ``exp(-w dt / T)`` for the slowest time
  constant T, so w should be several of them (in steps).

``x0="steady"`` (default) starts in the steady state for the input at ``s``;
``x0="zero"`` in the zero state. Both treat ``u`` and ``y`` as deviation
variables around an operating point where the output is 0 at input 0 (as
``dynia analyse --offset/--input-offset`` prepares them). When the output
level drifts between segments (unmeasured disturbances), ``offset="segment"``
adds one constant output offset per segment as a nuisance parameter; a
segment then informs about the gain only through the changes of its output
(responses to input changes in it or shortly before), never through its
level. ``x0`` should be the one the DYNIA run used (:func:`dynia.run`
defaults to ``"zero"``), so that the fit sees the model that was analysed.

Standard errors
---------------
Two are reported. ``std_errors`` are the classical ones,
``s^2 (J^T J)^-1``: right when the residuals are independent. Residuals of
process data rarely are (slow disturbances, a model a little too simple,
sensors filtering their signal), and with positively correlated residuals
the classical errors are too small by about ``sqrt((1 + phi)/(1 - phi))``
for lag-one correlation phi: 4.4 times at phi = 0.9. ``std_errors_hac`` are
robust to that: the Newey-West (1987) heteroscedasticity and
autocorrelation consistent (HAC) sandwich

    ``(J^T J)^-1 [G_0 + sum_l w_l (G_l + G_l^T)] (J^T J)^-1 * n/dof``,
    ``G_l = sum_t g_t g_{t-l}^T``, ``g_t = J_t r_t``,

with Bartlett weights ``w_l = 1 - l/(L+1)`` for lags ``l = 1..L`` counted in
time steps of the record (pairs across a gap or between segments further
apart than L steps contribute nothing) and ``n/dof`` the same small-sample
correction as ``s^2``. The bandwidth L follows Andrews' (1991) plug-in rule
for the Bartlett kernel under an AR(1) approximation of the residuals,
``L = floor(1.1447 (alpha n)^(1/3))``, ``alpha = 4 rho^2 / ((1-rho)^2 (1+rho)^2)``,
with rho the lag-one autocorrelation of the residuals (clipped to +-0.99)
and n the points fitted: no lags for white residuals, about 50 for
rho = 0.9 and n = 2000. Use ``std_errors_hac`` to judge an estimate; the
classical ones stay for comparison (their ratio shows how correlated the
residuals are).

Examples
--------
>>> import numpy as np
>>> from dynia.models import FirstOrder
>>> u = np.r_[np.zeros(20), np.ones(40), np.zeros(40)]
>>> y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
>>> fit = fit_segments(u, y, FirstOrder(), [(15, 40), (55, 70)], bounds={"K": (0, 7), "T": (0, 7)})
>>> {name: round(value, 6) for name, value in fit.parameters.items()}
{'K': 2.0, 'T': 3.0}
"""

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares

from . import _checks
from ._fit_covariance import hac_covariance, inverse_normal_matrix, masked
from ._fit_parameters import free_parameters, named_bounds, named_values, search_starts
from ._fit_residuals import Residuals, SegmentSimulator
from .engine.noise import steady_size_factor
from .errors import DataError, ModelError, SettingsError
from .io.frames import unpack
from .models import Model
from .models.base import check_model
from .segments import check_segments, mask_to_segments
from .serial import json_number, json_ready
from .settings import check_dt

__all__ = [
    "FitResult",
    "fit_segments",
    "record_least_squares",
    "validation_error",
]

OFFSETS = ("none", "segment")
X0_CHOICES = ("steady", "zero")

# Each start is a least-squares fit of every segment, a fraction of a second to seconds: more than this would run
# for hours, and 10 000 random starts already cover a box of a few parameters densely.
MAX_STARTS = 10_000


def check_starts(n_starts):
    """The number of least-squares starts, 1 to :data:`MAX_STARTS`, or a SettingsError naming ``n_starts``.

    Examples
    --------
    >>> check_starts(5)
    5
    """
    why = " (each start is a least-squares fit of every segment; more would run for hours)"
    return _checks.whole_number(n_starts, "n_starts", minimum=1, maximum=MAX_STARTS, why=why)


# A fitted parameter's typical scale is the width of its bounds, or
# max(|start|, 1) when they are infinite; it scales the search (least_squares
# x_scale), the finite-difference steps and the rank decision, so that none
# depends on the parameter's units.

# An estimate closer than this fraction of its typical scale to a bound is
# reported as lying on it (trf keeps iterates strictly inside the bounds).
_AT_BOUND_RTOL = 1e-6

# ftol, xtol and gtol of least_squares. Far below scipy's 1e-8: the extra
# Gauss-Newton iterations are few (convergence is fast near the minimum) and
# buy estimates whose error is the data's, not the solver's.
_LSQ_TOLERANCE = 1e-12

# --------------------------------------------------------------- the fit


@dataclass(frozen=True, eq=False)
class FitResult:
    """A model fitted by least squares on data segments.

    Attributes
    ----------
    parameters : dict of str to float
        Every model parameter, in ``model.names`` order, fixed ones included.
    std_errors : dict of str to float
        Classical standard error of each fitted parameter, from the
        linearisation at the solution: the square roots of the diagonal of
        ``covariance``. Right for independent residuals only (see the module
        documentation). ``inf`` for a parameter not identifiable from these
        segments (see ``identifiable``); ``nan`` when there are no more
        measured points than fitted quantities.
    covariance : ndarray (n_fitted, n_fitted)
        ``s^2 (J^T J)^-1`` over ``fitted_names``, ``s^2 = RSS/dof``; NaN in
        the rows and columns of unidentifiable parameters (the others are
        estimable and use the pseudo-inverse).
    std_errors_hac : dict of str to float
        Standard errors robust to autocorrelated residuals: the square roots
        of the diagonal of ``covariance_hac``; inf and nan as ``std_errors``.
    covariance_hac : ndarray (n_fitted, n_fitted)
        The Newey-West (HAC) covariance of the module documentation.
    hac_lags : int
        Its bandwidth L: residual lags (in time steps) it includes.
    fitted_names : tuple of str
        The parameters fitted, the order of ``covariance``.
    identifiable : dict of str to bool
        False where the Jacobian is singular along a direction that involves
        the parameter: these segments do not determine it, and its value in
        ``parameters`` is wherever the search left it, not an estimate.
    at_bound : tuple of str
        Fitted parameters whose estimate lies on a bound; their standard
        errors describe an unconstrained minimum that is not there.
    offsets : tuple of float
        The output offset of each segment (zeros unless ``offset="segment"``).
    segments : tuple of (start, stop)
        The segments fitted.
    rmse : float
        Root mean square of the fitted residuals.
    sigma : float
        Residual standard deviation ``s = sqrt(RSS/dof)`` used for the errors.
    n_points : int
        Measured points fitted (NaN outputs skipped).
    dof : int
        ``n_points`` minus the rank of the Jacobian (the parameter directions
        the data determine) minus the fitted offsets.
    success : bool
        Whether scipy's least_squares reports convergence.
    message : str
        Its message.
    nfev : int
        Residual evaluations over all starts.
    fitted : ndarray (n_steps,)
        Simulated output with offsets inside the segments, NaN elsewhere.
    model : dynia.models.Model
    settings : dict
        dt, x0, warmup, offset, bounds, initial, fixed, n_starts, model.
    """

    parameters: dict
    std_errors: dict
    covariance: np.ndarray
    std_errors_hac: dict
    covariance_hac: np.ndarray
    hac_lags: int
    fitted_names: tuple
    identifiable: dict
    at_bound: tuple
    offsets: tuple
    segments: tuple
    rmse: float
    sigma: float
    n_points: int
    dof: int
    success: bool
    message: str
    nfev: int
    fitted: np.ndarray = field(repr=False)
    model: Model
    settings: dict = field(default_factory=dict)

    def simulate(self, u, segments=None):
        """Output of the fitted model on the input ``u``, without offsets.

        Without ``segments``, the whole input from its first step in state
        ``x0``; with them, each segment by the fit's initial-state scheme
        (``warmup``, ``x0``), NaN outside. Returns shape (n_steps,).
        """
        u = self.model.check_input(u)
        settings = self.settings
        if segments is None:
            segments = [(0, u.shape[0])]
        simulator = SegmentSimulator(
            u,
            np.zeros(u.shape[0]),
            self.model,
            check_segments(segments, u.shape[0]),
            dt=settings["dt"],
            x0=settings["x0"],
            warmup=settings["warmup"],
        )
        output = np.full(u.shape[0], np.nan)
        output[simulator.steps] = simulator.outputs(self._vector()[None, :])[0]
        return output

    def validation_error(self, u, y, segments):
        """:func:`validation_error` of this fit, with its settings, on ``segments`` (or a mask)."""
        settings = self.settings
        return validation_error(
            u,
            y,
            self.model,
            self.parameters,
            segments,
            dt=settings["dt"],
            x0=settings["x0"],
            warmup=settings["warmup"],
            offset=settings["offset"],
        )

    def to_dict(self):
        """Everything but the arrays ``fitted`` and the model, as JSON-ready Python values.

        Non-finite numbers (infinite standard errors, unbounded ranges)
        become None, so ``json.dumps(..., allow_nan=False)`` accepts it.
        """
        return dict(
            parameters={name: json_number(value) for name, value in self.parameters.items()},
            std_errors={name: json_number(value) for name, value in self.std_errors.items()},
            covariance=[[json_number(value) for value in row] for row in self.covariance],
            std_errors_hac={name: json_number(value) for name, value in self.std_errors_hac.items()},
            covariance_hac=[[json_number(value) for value in row] for row in self.covariance_hac],
            hac_lags=self.hac_lags,
            fitted_names=list(self.fitted_names),
            identifiable=dict(self.identifiable),
            at_bound=list(self.at_bound),
            offsets=[json_number(value) for value in self.offsets],
            segments=[[start, stop] for start, stop in self.segments],
            rmse=json_number(self.rmse),
            sigma=json_number(self.sigma),
            n_points=self.n_points,
            dof=self.dof,
            success=self.success,
            message=self.message,
            nfev=self.nfev,
            settings=json_ready(self.settings),
        )

    def _vector(self):
        return np.array([self.parameters[name] for name in self.model.names])


def fit_segments(
    u,
    y,
    model,
    segments,
    *,
    bounds=None,
    dt=None,
    initial=None,
    fixed=None,
    x0="steady",
    warmup=None,
    offset="none",
    n_starts=1,
    rng=None,
):
    """Least-squares estimate of the model parameters from data segments.

    Minimises the sum of squared residuals ``y - sim`` over the measured
    steps of all segments (NaN outputs are skipped) with
    ``scipy.optimize.least_squares`` (trust-region reflective, inside
    ``bounds``). Each segment is simulated from a consistent initial state,
    see the module documentation; steps before a segment are simulated but
    not fitted. Jacobians are forward differences during the search and
    central differences (one-sided at a bound) for the covariance, with
    steps relative to ``max(|value|, range)``: a dead time is only piecewise
    smooth in its value (kinks at multiples of dt), so no analytic Jacobian
    would be exact either.

    Parameters
    ----------
    u, y : array_like, shape (n_steps,), or pandas Series
        Input and measured output. NaN in ``y`` marks a missing point; blank
        the held-out part this way. Two pandas objects must share one
        index, and a time index gives ``dt`` (:func:`dynia.io.frames.unpack`);
        segments count steps, by position, either way.
    model : dynia.models.Model
        For example ``dynia.models.FOPDT()``.
    segments : list of (start, stop)
        The data to fit (see :func:`~dynia.segments.check_segments`); at least one measured
        point each.
    bounds : mapping of str to (low, high), optional
        Range of each fitted parameter (infinite ends allowed). Required for
        every fitted parameter without an ``initial`` value; parameters
        without bounds are unbounded.
    dt : float, optional
        Sample time; default the spacing of a time index, else 1.0.
    initial : mapping of str to float, optional
        Start values; by default the middle of the bounds.
    fixed : mapping of str to float, optional
        Parameters held at these values, not fitted.
    x0 : {"steady", "zero"}, default "steady"
        State at the start of each simulation.
    warmup : int, optional
        Steps simulated before each segment; None (default) simulates from
        the start of the record.
    offset : {"none", "segment"}, default "none"
        ``"segment"`` fits one output offset per segment.
    n_starts : int, default 1
        Number of starts: the first from ``initial``, the rest uniform in
        the bounds (which must then be finite); the lowest cost wins.
    rng : numpy.random.Generator or int, optional
        Source of the extra starts.

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        For bad segments, unknown parameter names, a parameter without
        bounds or start value, a start outside its bounds, no measured
        point in a segment, or parameters the model cannot simulate.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.models import FOPDT
    >>> u = np.r_[np.zeros(10), np.ones(30), -np.ones(30)]
    >>> y = FOPDT().simulate([[1.5, 4.0, 2.5]], u)[0]
    >>> fit = fit_segments(u, y, FOPDT(), [(5, 70)], bounds={"K": (0, 5), "T": (0, 10), "theta": (0, 6)})
    >>> [round(fit.parameters[name], 6) for name in ("K", "T", "theta")]
    [1.5, 4.0, 2.5]
    >>> fit.identifiable
    {'K': True, 'T': True, 'theta': True}
    """
    check_model(model)
    u, y, dt, _ = unpack(u, y, dt)
    u, y = _checks.record(u, y, n_inputs=model.n_inputs)
    segments = check_segments(segments, u.shape[0])
    if not segments:
        raise SettingsError("segments is empty; give at least one (start, stop) segment to fit")
    dt, x0, warmup, offset = _scheme(dt, x0, warmup, offset)
    n_starts = check_starts(n_starts)
    fixed = named_values(fixed, "fixed", model.names)
    initial = named_values(initial, "initial", model.names)
    bounds = named_bounds(bounds, model.names)
    free_names, lower, upper, start = free_parameters(model, fixed, initial, bounds)
    _check_measured(y, segments)

    simulator = SegmentSimulator(u, y, model, segments, dt=dt, x0=x0, warmup=warmup)
    free = np.array([model.names.index(name) for name in free_names])
    base = np.array([fixed.get(name, 0.0) for name in model.names], dtype=float)
    typical = np.where(np.isfinite(upper - lower), upper - lower, np.maximum(np.abs(start), 1.0))
    residuals = Residuals(simulator, base, free, lower, upper, typical, offset)
    starts = search_starts(start, lower, upper, n_starts, rng)
    best, nfev = _best_solution(residuals, starts, lower, upper, typical, free_names)
    return _summarise(
        best,
        nfev,
        residuals,
        simulator,
        u,
        model,
        free_names,
        lower,
        upper,
        typical,
        segments,
        settings=dict(
            model=type(model).__name__,
            dt=dt,
            x0=x0,
            warmup=warmup,
            offset=offset,
            bounds={name: [float(low), float(high)] for name, low, high in zip(free_names, lower, upper)},
            initial=dict(zip(free_names, start.tolist())),
            fixed=fixed,
            n_starts=n_starts,
        ),
    )


def record_least_squares(result, u, y, model):
    """``result`` with the whole record's least-squares fit of ``model`` in its run record.

    The front-ends' analyses leave the record's fit within the sample in
    ``result.run.record_fit`` (:func:`dynia.engine.noise.record_fit`: the
    record-best set and a Gauss-Newton step from its neighbours, as fine
    as the sample). From there :func:`fit_segments` fits the whole record
    inside the sampling box, with the run's ``dt`` and ``x0``, leaving out
    the output's saturated and frozen readings that the run screened
    (``run.screened``, :mod:`dynia.quality`); the
    estimates, their HAC standard errors (robust to the residuals'
    autocorrelation) and the residuals' RMSE replace it
    (``record_fit``, ``record_fit_se``, ``record_fit_rmse``), and the
    noise's own size factor read off its residuals where its output is
    steady (``steady_size_factor``,
    :func:`dynia.engine.noise.steady_size_factor`). The verdicts
    compare the evidence bands with it (:mod:`dynia.verdicts`, reason
    ``disagrees_with_record_fit``). Where the least squares cannot run (the model cannot
    simulate a point it reaches), the fit within the sample stays, without
    standard errors, and no verdict compares with it; so does a record whose
    squared residuals overflow or underflow (magnitudes near the
    floating-point limits).

    Examples
    --------
    >>> import numpy as np, dynia
    >>> u = np.r_[np.zeros(20), np.ones(100), np.zeros(80)]
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(0).normal(0, 0.05, 200)
    >>> res = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 5), "T": (0, 10)}, n=5, rng=1)
    >>> [round(value, 2) for value in res.run.record_fit], [round(se, 3) for se in res.run.record_fit_se]
    ([2.01, 2.95], [0.005, 0.05])
    """
    start = result.run.record_fit
    if start is None or result.settings is None:
        return result
    names = list(result.names)
    bounds = {name: (float(low), float(high)) for name, (low, high) in zip(names, result.bounds)}
    y = np.array(y, dtype=float)
    for kind, signal, first, stop, _ in result.run.screened or ():
        if signal == "y" and kind != "quantised":  # a clipped or frozen reading is no measurement of the output
            y[first:stop] = np.nan
    initial = {name: float(np.clip(value, *bounds[name])) for name, value in zip(names, start)}
    try:
        # Records near the floating-point limits square into overflow or underflow: such a fit is dropped below.
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            fit = fit_segments(
                u,
                y,
                model,
                [(0, y.shape[0])],
                bounds=bounds,
                initial=initial,
                dt=result.settings.dt,
                x0=result.settings.x0,
            )
    except ValueError:  # ours (DyniaError), or scipy's for residuals that overflowed on the way
        return result
    if not (math.isfinite(fit.rmse) and fit.rmse > 0):
        return result
    sigma = result.run.noise_sigma
    steady = math.nan
    if sigma is not None and math.isfinite(sigma):
        before, after = result.window_halos
        with np.errstate(all="ignore"):
            steady = steady_size_factor(y, fit.fitted, sigma, before + after + 1)
    fields = dict(
        record_fit=tuple(fit.parameters[name] for name in names),
        record_fit_se=tuple(fit.std_errors_hac[name] for name in names),
        record_fit_rmse=fit.rmse,
        steady_size_factor=steady,
    )
    return replace(result, run=replace(result.run, **fields))


def _check_measured(y, segments):
    """Raise a DataError naming the first segment without a measured output."""
    for position, ((low, high), part) in enumerate(zip(segments, _measured_counts(y, segments))):
        if part == 0:
            raise DataError(f"segments[{position}] = ({low}, {high}) has no measured output (all NaN)")


def _best_solution(residuals, starts, lower, upper, typical, free_names):
    """The least-squares solution of lowest cost over ``starts``, and the evaluations all of them took."""
    best, nfev = None, 0
    for point in starts:
        if not np.isfinite(residuals(point)).all():
            raise ModelError(
                f"the simulation overflows at the start "
                f"{dict(zip(free_names, point.tolist()))}; choose bounds or initial values "
                "where the model is stable"
            )
        solution = least_squares(
            residuals,
            point,
            jac=residuals.forward_jacobian,
            bounds=(lower, upper),
            method="trf",
            x_scale=typical,
            ftol=_LSQ_TOLERANCE,
            xtol=_LSQ_TOLERANCE,
            gtol=_LSQ_TOLERANCE,
        )
        nfev += solution.nfev
        if best is None or solution.cost < best.cost:
            best = solution
    return best, nfev


def _scheme(dt, x0, warmup, offset):
    dt = check_dt(1.0 if dt is None else dt)
    if x0 not in X0_CHOICES:
        raise SettingsError(f"x0 must be one of {X0_CHOICES}; got {x0!r}")
    if warmup is not None:
        warmup = _checks.whole_number(warmup, "warmup", minimum=0)
    if offset not in OFFSETS:
        raise SettingsError(f"offset must be one of {OFFSETS}; got {offset!r}")
    return float(dt), x0, warmup, offset


def _measured_counts(y, segments):
    return [int(np.count_nonzero(~np.isnan(y[start:stop]))) for start, stop in segments]


def _summarise(solution, nfev, residuals, simulator, u, model, free_names, lower, upper, typical, segments, settings):
    theta = solution.x
    with_offsets = settings["offset"] == "segment"
    final = residuals(theta)
    n_points = final.size
    rss = float(final @ final)
    jacobian = residuals.central_jacobian(theta)
    inverse, identifiable, rank = inverse_normal_matrix(jacobian, typical)
    # Degrees of freedom count what the data determine: the rank of J (an
    # unidentifiable direction fits nothing) plus one offset per segment.
    dof = n_points - rank - (len(segments) if with_offsets else 0)
    variance = rss / dof if dof > 0 else math.nan
    covariance = masked(variance * inverse, identifiable)
    sandwich, hac_lags = hac_covariance(jacobian, final, simulator.steps, inverse, typical)
    covariance_hac = masked(sandwich * (n_points / dof if dof > 0 else math.nan), identifiable)
    std_errors, std_errors_hac = (
        np.where(identifiable, np.sqrt(np.abs(np.diag(matrix))), np.inf) for matrix in (covariance, covariance_hac)
    )
    if dof <= 0:
        std_errors[:] = std_errors_hac[:] = np.nan

    params = residuals.full(theta[None, :])
    every_step = SegmentSimulator(
        u, np.zeros(u.shape[0]), model, segments, dt=settings["dt"], x0=settings["x0"], warmup=settings["warmup"]
    )
    fitted = np.full(u.shape[0], np.nan)
    fitted[every_step.steps] = every_step.outputs(params)[0]
    offsets = tuple(
        float(np.mean(simulator.observed[part] - fitted[simulator.steps[part]])) if with_offsets else 0.0
        for part in simulator.parts
    )
    for (start, stop), level in zip(segments, offsets):
        fitted[start:stop] += level
    near = _AT_BOUND_RTOL * typical
    return FitResult(
        parameters=dict(zip(model.names, params[0].tolist())),
        std_errors=dict(zip(free_names, std_errors.tolist())),
        covariance=covariance,
        std_errors_hac=dict(zip(free_names, std_errors_hac.tolist())),
        covariance_hac=covariance_hac,
        hac_lags=hac_lags,
        fitted_names=tuple(free_names),
        identifiable=dict(zip(free_names, identifiable.tolist())),
        at_bound=tuple(
            name
            for name, value, low, high, tol in zip(free_names, theta, lower, upper, near)
            if value - low <= tol or high - value <= tol
        ),
        offsets=offsets,
        segments=tuple(segments),
        rmse=math.sqrt(rss / n_points),
        sigma=math.sqrt(variance) if dof > 0 else math.nan,
        n_points=n_points,
        dof=dof,
        success=bool(solution.success),
        message=str(solution.message),
        nfev=nfev,
        fitted=fitted,
        model=model,
        settings=settings,
    )


# -------------------------------------------------------------- validation


def validation_error(u, y, model, parameters, segments, *, dt=None, x0="steady", warmup=None, offset="none"):
    """Root mean square error of a model on held-out data.

    The model is simulated on ``segments`` by the same initial-state scheme
    as :func:`fit_segments` (give it the same ``dt``, ``x0``, ``warmup``
    and ``offset``; :meth:`FitResult.validation_error` does) and compared
    with the measured points there. With ``offset="segment"`` each segment's
    offset is its mean residual (a level, not a prediction), which lowers
    the error by a factor ``sqrt(1 - 1/m)`` on a segment of m points.

    Parameters
    ----------
    u, y : array_like, shape (n_steps,), or pandas Series
        The full record, held-out output included (pandas as in
        :func:`fit_segments`).
    model : dynia.models.Model
    parameters : mapping of str to float
        A value for every model parameter, e.g. ``fit.parameters``.
    segments : list of (start, stop), or boolean mask of shape (n_steps,)
        The held-out data, e.g. from :func:`~dynia.segments.holdout_split`.
    dt, x0, warmup, offset
        As :func:`fit_segments`.

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.models import FirstOrder
    >>> u = np.r_[np.zeros(10), np.ones(20), np.zeros(20)]
    >>> y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + 0.1
    >>> round(validation_error(u, y, FirstOrder(), {"K": 2.0, "T": 3.0}, [(30, 50)]), 12)
    0.1
    """
    check_model(model)
    u, y, dt, _ = unpack(u, y, dt)
    u, y = _checks.record(u, y, n_inputs=model.n_inputs)
    mask = np.asarray(segments) if isinstance(segments, np.ndarray) else None
    if mask is not None and mask.dtype == bool:
        if mask.shape != u.shape[:1]:
            raise SettingsError(f"the validation mask must have shape {u.shape[:1]}; got {mask.shape}")
        segments = mask_to_segments(mask)
    segments = check_segments(segments, u.shape[0])
    dt, x0, warmup, offset = _scheme(dt, x0, warmup, offset)
    values = named_values(parameters, "parameters", model.names)
    missing = [name for name in model.names if name not in values]
    if missing:
        raise SettingsError(f"parameters lacks {missing}; give a value for every parameter of {list(model.names)}")
    if sum(_measured_counts(y, segments)) == 0:
        raise DataError("the validation segments hold no measured output (empty, or all NaN)")
    kept = [segment for segment, count in zip(segments, _measured_counts(y, segments)) if count]
    simulator = SegmentSimulator(u, y, model, kept, dt=dt, x0=x0, warmup=warmup)
    vector = np.array([values[name] for name in model.names])
    residuals = Residuals(simulator, vector, np.array([], dtype=int), np.array([]), np.array([]), np.array([]), offset)
    error = residuals(np.array([]))
    return math.sqrt(float(error @ error) / error.size)
