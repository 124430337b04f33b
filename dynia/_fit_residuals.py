"""What a least-squares fit on data segments minimises: the simulated output, the residuals, their Jacobians.

:class:`SegmentSimulator` simulates a model from a consistent initial state
up to every measured step of the segments (the scheme of :mod:`dynia.fit`'s
module docs), for many parameter sets at once; :class:`Residuals` turns it
into the residuals ``y - sim`` of the free parameters, with the segments'
offsets projected out, and their finite-difference Jacobians.
"""

import numpy as np

from .errors import ModelError, SettingsError

# Relative finite-difference steps, times max(|value|, typical scale): about
# sqrt(eps) for the forward differences that steer the search and eps^(1/3)
# for the central differences of the reported covariance, the steps that
# balance truncation against rounding error for each formula.
_FORWARD_STEP = 1.5e-8
_CENTRAL_STEP = 6e-6


class SegmentSimulator:
    """Simulated output at the measured steps of every segment, for many parameter sets.

    Segments whose simulation starts at the same step share one simulation
    (with ``warmup=None`` all of them do).
    """

    def __init__(self, u, y, model, segments, *, dt, x0, warmup):
        self._u, self._model, self._dt, self._x0 = u, model, dt, x0
        self._kernel = _kernel_simulated(model)
        measured = [start + np.flatnonzero(~np.isnan(y[start:stop])) for start, stop in segments]
        self.steps = np.concatenate(measured)
        self.observed = y[self.steps]
        bounds = np.cumsum([0] + [steps.size for steps in measured])
        self.parts = [slice(low, high) for low, high in zip(bounds[:-1], bounds[1:])]
        groups = {}
        for (start, stop), steps, part in zip(segments, measured, self.parts):
            origin = 0 if warmup is None else max(0, start - warmup)
            groups.setdefault(origin, []).append((stop, steps - origin, part))
        self._groups = [
            (origin, max(stop for stop, _, _ in members), [(local, part) for _, local, part in members])
            for origin, members in groups.items()
        ]

    def outputs(self, params):
        """Simulated output, (n_sets, n_points), of the parameter sets ``params`` (n_sets, n_params)."""
        out = np.empty((params.shape[0], self.steps.size))
        for origin, stop, members in self._groups:
            try:
                with np.errstate(over="ignore", invalid="ignore"):
                    simulated = self._simulate(params, self._u[origin:stop])
            except ValueError as error:
                raise SettingsError(
                    f"{type(self._model).__name__} cannot simulate the parameters "
                    f"{dict(zip(self._model.names, params[0].tolist()))} (or a finite-difference "
                    f"step from them): {error}; choose bounds that keep the parameters admissible"
                ) from None
            for local, part in members:
                out[:, part] = simulated[:, local]
        return out

    def _simulate(self, params, u):
        if self._kernel is not None:
            try:
                return self._kernel.simulate(params, u, dt=self._dt, x0=self._x0)
            except ModelError:  # not finite somewhere (or not simulable): the recursion's own answer, as before
                pass
        return self._model.simulate(params, u, dt=self._dt, x0=self._x0)


def _kernel_simulated(model):
    """The model simulated by the compiled kernel where it can be (its outputs bit for bit), else None.

    A fit simulates a few parameter sets at a time, some ten times per start: the numpy recursion's Python loop over
    the steps is most of a fit's time (about 0.5 s a fit of 2000 steps), the kernel's a few milliseconds.
    """
    from .engine import kernels
    from .pipeline import KernelSimulated, compiled_simulation

    return KernelSimulated(model) if kernels.AVAILABLE and compiled_simulation(model) else None


class Residuals:
    """Residuals y - sim (offsets projected out) and their Jacobians in the free parameters."""

    def __init__(self, simulator, base, free, lower, upper, typical, offset):
        self._simulator, self._base, self._free = simulator, base, free
        self._lower, self._upper, self._typical = lower, upper, typical
        self._offset = offset == "segment"

    def full(self, free_rows):
        params = np.tile(self._base, (free_rows.shape[0], 1))
        params[:, self._free] = free_rows
        return params

    def rows(self, free_rows):
        residuals = self._simulator.observed - self._simulator.outputs(self.full(free_rows))
        if self._offset:
            # The best offset of a segment is its mean residual; removing it
            # is the exact elimination of these linear nuisance parameters.
            for part in self._simulator.parts:
                residuals[:, part] -= residuals[:, part].mean(axis=1, keepdims=True)
        return residuals

    def __call__(self, theta):
        return self.rows(theta[None, :])[0]

    def forward_jacobian(self, theta):
        step = _FORWARD_STEP * np.maximum(np.abs(theta), self._typical)
        step = np.where(theta + step > self._upper, -step, step)
        residuals = self.rows(np.vstack([theta, theta + np.diag(step)]))
        return (residuals[1:] - residuals[0]).T / step

    def central_jacobian(self, theta):
        step = _CENTRAL_STEP * np.maximum(np.abs(theta), self._typical)
        # At a bound the difference turns one-sided instead of leaving the box.
        up, down = np.minimum(theta + step, self._upper), np.maximum(theta - step, self._lower)
        k = theta.size
        trial = np.tile(theta, (2 * k, 1))
        trial[np.arange(k), np.arange(k)] = up
        trial[k + np.arange(k), np.arange(k)] = down
        residuals = self.rows(trial)
        return (residuals[:k] - residuals[k:]).T / (up - down)
