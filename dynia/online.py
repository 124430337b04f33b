"""Semi-online DYNIA (thesis section 4.3): analyse each sample as the logging system records it.

The thesis proposes to sample the parameters once and then, whenever the
logging system records a new input/output pair, simulate only that step and
run one window of the moving-window calculations. :class:`OnlineDynia` does
this with a window that ends at the newest step: the window at step ``t``
holds steps ``t-2n .. t`` (clipped to the start of the record), the
``window="trailing"`` of :func:`dynia.engine.moving_window`. Its result for
step ``t`` is therefore final as soon as step ``t`` is logged, and the whole
history equals the batch analysis ``dynia.run(..., window="trailing",
engine="numpy")`` on the same record and seed, bit for bit: both sum each
window left to right. The compiled engine's running sums agree with them to
rounding (the contract of :mod:`dynia.engine.kernels`).

Shapes follow the package convention (see :mod:`dynia.engine`); one update
gives one time step of it: ``ic`` (n_params,), ``ci`` (n_params, 2) as
[lower, upper], ``gradient`` (n_params, n_bins).

How an update works
-------------------
1. Every parameter set's model advances one step (:meth:`dynia.models.base.Model.stepper`,
   the same arithmetic as the batch simulation).
2. Their absolute errors against the new measurement go into a ring buffer
   of the window's 2n+1 steps (a missing measurement, NaN, is a row of
   zeros and does not count as a point).
3. Each sample's window sum is added up oldest to newest, exactly as the
   batch engine adds it (a running sum would drift by rounding and could
   reorder near-ties), divided by the number of measured points.
4. The engine's own flavour code ranks the samples, keeps the behavioural
   set and reads off the limits, the IC and the gradient.

The cost is O(n_samples x (2n+1)) per update and memory is fixed: nothing
grows with the number of steps.
"""

import copy
import dataclasses
import numbers
import warnings

import numpy as np

from . import _checks
from .bounds import parameter_box
from .checkpoint import restored_state, state_bytes
from .engine.flavours import FLAVOUR_CLASSES, McatFlavour
from .engine.noise import (
    RESIDUAL_CHUNK,
    add_record_errors,
    floor_fields,
    floor_settings,
    record_fit,
    record_noise_floor,
)
from .engine.windows import OverflowedWindowsWarning, blank_overflowed, error_scale
from .errors import DataError, ModelError, SettingsError
from .fit import record_least_squares
from .io.frames import unpack
from .models import FunctionModel, StateSpaceModel
from .models.base import SameOutput, check_model, refuse_ignored_params
from .quality import screen
from .result import DyniaResult
from .sampling import sample
from .settings import SAMPLERS, AnalysisSettings, RunRecord, merged_settings, split_overrides

__all__ = ["OnlineDynia"]


class OnlineDynia:
    """DYNIA updated one logged sample at a time, on a fixed Monte Carlo sample.

    Parameters
    ----------
    model : dynia.models.Model
        For example ``dynia.models.FirstOrder()``.
    bounds : mapping of str to (low, high)
        Sampling range of every model parameter; the parameter axis of every
        result follows this order (as in :func:`dynia.run`).
    settings : dynia.settings.AnalysisSettings, optional
        As for :func:`dynia.run`, with ``window="trailing"`` by default (and
        only): the window at step t holds the 2n+1 steps t-2n .. t. The
        ``n_samples`` parameter sets are drawn once; ``dt`` is the sample
        time of the log; ``x0="steady"`` is the steady state at the first
        input logged. ``sampler`` is "uniform", "lhs" or "sobol": the
        adaptive schemes need the whole record. A window with fewer
        measured points than ``min_points`` has NaN results, so the first
        results appear once ``min_points`` measurements are in. A stream
        cannot be screened before it is analysed: with ``quality``,
        :meth:`replay` screens the record it was given once it is replayed
        (``run.screened`` of its result) and :meth:`update` screens nothing.
        The engine is numpy, in the calling thread (``engine`` "auto" or
        "numpy", ``workers`` None), without ``ic_error``, ``target_se``,
        ``dtype`` or ``store``.
    rng : numpy.random.Generator or int, optional
        Source of the parameter draw; the same seed draws the same
        ``.samples`` as :func:`dynia.run`.
    **overrides
        Single settings over ``settings``: any field of
        :class:`~dynia.settings.AnalysisSettings` (see :mod:`dynia.settings`
        for the list), e.g. ``n_samples=500, n=5``; any other name is a
        :class:`~dynia.errors.SettingsError`.

    Attributes
    ----------
    names : tuple of str
        Parameter names, in the order of ``bounds``.
    samples : ndarray (n_samples, n_params)
        The parameter sets, fixed for the object's life.
    bounds : ndarray (n_params, 2)
    bin_centres : ndarray (n_params, n_bins)
    steps : int
        Number of samples fed so far.
    ic, ci, gradient : ndarray
        Results of the latest step, (n_params,), (n_params, 2) and
        (n_params, n_bins); NaN before the first usable window.
    median : ndarray (n_params,)
        The CLD median of the latest step (see :attr:`dynia.result.DyniaResult.median`).
    error_scale : float
        The power of two every absolute error is multiplied by: 1.0 until the
        first measured value that is not zero fixes it (see Notes).

    Notes
    -----
    Equality with ``dynia.run(u, y, model, bounds, window="trailing", ...)``
    (same seed, sampler, n_samples and settings) holds whenever that run drops
    no sample (``run.n_dropped == 0``), which is always the case for
    the lag models. The batch run leaves out every parameter set whose
    simulation overflows anywhere in the record; online, the future is
    unknown, so a set whose simulated output becomes non-finite is marked
    *diverged* from then on and ranks last in every window: its cost is
    infinite ("thesis", "weighted"), or its MAE is the window's largest
    finite MAE ("mcat", whose likelihood divides by that maximum). Windows
    with fewer finite sets than the behavioural set needs have NaN results.
    ``.n_diverged`` counts them. With ``x0="steady"``, a dead time longer
    than the whole record can differ from the batch run in the last bits
    (see :meth:`dynia.models.base.Model.stepper`).

    Magnitudes: the batch run multiplies every absolute error by the power
    of two that brings the record's largest ``|y|`` within 2^±332
    (:func:`dynia.engine.windows.error_scale`), so that the costs, MAEs
    squared, neither overflow nor underflow into ties. Online the largest
    ``|y|`` is not known in advance: the power of two is fixed from the first
    measured value that is not zero (the errors logged before it, against
    zeros, are rescaled alike), and ``.error_scale`` holds it. A power of two
    scales exactly, so the results equal the batch run's, whose power may
    differ, as long as the record stays within about 1e54 of that first
    value. A window whose behavioural MAE still overflows is left without
    results with an :class:`~dynia.engine.windows.OverflowedWindowsWarning`,
    as in the batch run, when the first value's power suits every measurement
    so far; when a later measurement lies beyond it, the update raises a
    :class:`~dynia.errors.DataError` naming both magnitudes, since one pass
    cannot rescale the windows already analysed.

    Examples
    --------
    >>> import numpy as np, dynia
    >>> from dynia.online import OnlineDynia
    >>> u = np.r_[np.zeros(20), np.ones(40)]
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
    >>> online = OnlineDynia(dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)},
    ...                      n_samples=500, n=5, rng=1)
    >>> for u_t, y_t in zip(u, y):
    ...     ic, ci, gradient = online.update(u_t, y_t)
    >>> ic.shape, ci.shape, gradient.shape
    ((2,), (2, 2), (2, 40))
    >>> batch = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)},
    ...                   n_samples=500, n=5, rng=1, window="trailing")
    >>> bool(np.array_equal(ic, batch.ic[:, -1]))
    True
    """

    def __init__(self, model, bounds, *, settings=None, rng=None, **overrides):
        (setting_overrides,) = split_overrides(OnlineDynia, overrides, AnalysisSettings)
        check_model(model)
        settings = merged_settings(
            settings, setting_overrides, front_end=OnlineDynia, default=AnalysisSettings(window="trailing")
        )
        settings.require(
            "OnlineDynia",
            window=("trailing",),
            sampler=SAMPLERS,
            engine=("auto", "numpy"),
            workers=(None,),
            ic_error=(False,),
            target_se=(None,),
            dtype=("float64",),
            store=(None,),
            why="the adaptive schemes need the whole record; an update is one "
            "trailing window, analysed on numpy in the calling thread, with no Monte Carlo error yet; "
            "for a stored or float32 result replay the record through dynia.run(window='trailing')",
        )
        names, box = parameter_box(bounds, model.names, type(model).__name__)
        n_samples = settings.n_samples
        # The settings of every result: an update is analysed by numpy.
        self._analysis = settings.replace(engine="numpy")
        self.names = tuple(names)
        self.bounds = box
        self.samples = sample(settings.sampler, n_samples, box, _checks.generator(rng))
        self.samples.flags.writeable = False
        model_order = [names.index(name) for name in model.names]
        self._model_params = self.samples[:, model_order]
        self._model = model
        self._flavour_args = (self.samples, box, settings.percentage, settings.bins, settings.conf_level)
        # Built once here so that bad settings fail now rather than at the first update.
        self._flavour = FLAVOUR_CLASSES[settings.flavour](*self._flavour_args)
        self._stepper = model.stepper(self._model_params, dt=settings.dt, x0=settings.x0)  # checks dt and x0
        self._lagged = self._copied(self._stepper)
        self.bin_centres = self._flavour.bin_centres
        self._run = dataclasses.replace(
            RunRecord.of(model, n_sampled=n_samples, n_dropped=0), n_behavioural=self._flavour.count
        )
        self._allocate_window(settings.window_length, n_samples)
        self._same = SameOutput(model, self._model_params, _functions(model))
        self.steps = 0
        self._blank_results()
        self._unscaled()

    def _allocate_window(self, width, n_samples):
        """The ring of the window's last ``width`` steps of errors, their inputs and outputs, and work arrays.

        The models are also stepped ``width`` steps behind (``_lagged``):
        from there and the ring's inputs and outputs the errors can be made
        again, so that a checkpoint (:meth:`to_bytes`) need not hold them.
        """
        self._errors = np.zeros((width, n_samples))  # ring: row t % width holds step t
        self._measured = np.zeros(width, dtype=bool)
        self._recent_u = np.zeros((width, self._model.n_inputs))
        self._recent_y = np.zeros(width)
        self._diverged = np.zeros(n_samples, dtype=bool)
        self._work_arrays(n_samples)

    def _work_arrays(self, n_samples):
        self._mae = np.empty((1, n_samples))
        self._finite = np.empty(n_samples, dtype=bool)

    # The per-sample arrays a checkpoint leaves out: the work arrays, the errors and the stepper they come from.
    _REMADE = ("_errors", "_stepper", "_mae", "_finite")

    def __getstate__(self):
        return {key: value for key, value in self.__dict__.items() if key not in self._REMADE}

    def __setstate__(self, state):
        self.__dict__.update(state)
        width, n_samples = self._measured.size, self.samples.shape[0]
        self._work_arrays(n_samples)
        self._errors = np.zeros((width, n_samples))
        self._stepper = self._copied(self._lagged)
        # The steps the lagged models have not taken, stepped again: their outputs, hence the errors, bit for bit.
        with np.errstate(over="ignore", invalid="ignore"):
            for step in range(max(self.steps - width, 0), self.steps):
                slot = step % width
                simulated = self._stepper.step(self._stepper_input(self._recent_u[slot]))
                if self._measured[slot]:
                    self._window_errors(simulated, self._recent_y[slot], self._errors[slot])

    def _mark_diverged(self, finite, step):
        """Mark the sets not ``finite`` (n_samples,) as diverged; refuse when none is left by ``step``."""
        if finite.all():
            return
        self._diverged |= ~finite
        if self._diverged.all():
            # As dynia.run: nothing is left to rank, and NaN results would pass for a quiet window.
            raise ModelError(
                f"{self._model!r}: the simulation of every one of the {self._diverged.size} parameter sets is not "
                f"finite (NaN or overflow) by step {step}; check the model and the parameter ranges"
            )

    def _window_errors(self, simulated, y_t, errors):
        """The scaled absolute errors of ``simulated`` against a measured ``y_t``, into ``errors``."""
        np.subtract(simulated, y_t, out=errors)  # |s - y| == |y - s| bit for bit
        np.abs(errors, out=errors)
        if self.error_scale != 1.0:
            errors *= self.error_scale  # as the batch engine's ScaledErrors

    def _copied(self, stepper):
        """A copy of ``stepper`` that shares the model (a stepper of a custom model holds it, and its functions)."""
        return copy.deepcopy(stepper, {id(self._model): self._model})

    def _stepper_input(self, row):
        return float(row[0]) if row.size == 1 else row

    @property
    def settings(self):
        """The :class:`~dynia.settings.AnalysisSettings` of every result (``window="trailing"``, numpy engine)."""
        return self._analysis

    @property
    def n_behavioural(self):
        """Parameter sets in every window's behavioural set."""
        return self._flavour.count

    @property
    def time(self):
        """Time of the latest step, ``(steps - 1) * dt``; NaN before the first update."""
        return (self.steps - 1) * self._analysis.dt if self.steps else float("nan")

    @property
    def n_diverged(self):
        """Parameter sets whose simulated output has become non-finite (see Notes)."""
        return int(self._diverged.sum())

    def reset(self):
        """Start again at step 0 with the same samples, as a new object would."""
        self._flavour = FLAVOUR_CLASSES[self._analysis.flavour](*self._flavour_args)
        self._stepper = self._model.stepper(self._model_params, dt=self._analysis.dt, x0=self._analysis.x0)
        self._lagged = self._copied(self._stepper)
        self._errors.fill(0.0)
        self._measured.fill(False)
        self._diverged.fill(False)
        self._same = SameOutput(self._model, self._model_params, _functions(self._model))
        self.steps = 0
        self._blank_results()
        self._unscaled()

    def _unscaled(self):
        """No error scale fixed yet (see Magnitudes in the class Notes)."""
        self.error_scale = 1.0
        self._scaled_by = None  # (step, y_t) of the measured value that fixed the scale
        self._largest = 0.0  # the largest |y| measured so far

    def _fix_scale(self, y_t, step):
        """Fix the error scale from ``y_t``, the first measured value not zero (at ``step``); rescale the window."""
        self.error_scale = error_scale([y_t])
        self._scaled_by = (step, y_t)
        if self.error_scale != 1.0:
            self._errors *= self.error_scale  # exact: a power of two; errors against zeros so far

    def update(self, u_t, y_t):
        """Feed the input and the measured output logged at the next step.

        Parameters
        ----------
        u_t : float
            Input at step ``steps`` (finite).
        y_t : float
            Measured output at that step; NaN marks a missing measurement.

        Returns
        -------
        ic : ndarray (n_params,)
        ci : ndarray (n_params, 2)
            Lower and upper confidence limit.
        gradient : ndarray (n_params, n_bins)
            The results of the window ending at this step, also kept as
            ``.ic``, ``.ci`` and ``.gradient`` (with the CLD median as
            ``.median``); new arrays at every update.
        """
        self._take(u_t, y_t)
        with np.errstate(over="ignore", invalid="ignore"):
            usable = self._window_mean()
        self._analyse(usable)
        return self.ic, self.ci, self.gradient

    def advance(self, u, y, totals=None):
        """Feed a stretch of the record without analysing its windows.

        For a caller that has those windows' results already, from the batch
        engine on the same record (``dynia follow`` catching up a backlog):
        the models, the window's errors and the error scale move on exactly
        as :meth:`update` moves them, so that the updates after it give what
        they would have given, while the costly part of an update, ranking the
        window, is skipped, and the errors are formed a block of steps at a
        time. The latest results (``.ic``, ...) are blanked.

        Parameters
        ----------
        u, y : ndarray (n_steps,)
            Input (n_steps, n_inputs for several inputs; finite) and measured
            output (NaN where missing, else finite).
        totals : ndarray (n_samples,), optional
            Every sample's running record total absolute error, in the
            window's scaled units (:attr:`newest_errors`), added to in place
            step by step (:func:`dynia.engine.noise.add_record_errors`).
        """
        u, y = _checks.record(u, y, n_inputs=self._model.n_inputs, whole=False)
        inputs = u.reshape(y.size, -1)
        width = self._errors.shape[0]
        for start in range(0, y.size, _ADVANCE_BLOCK):
            stop = min(start + _ADVANCE_BLOCK, y.size)
            self._advance_block(inputs[start:stop], y[start:stop], totals, width)
        self._blank_results()

    def _advance_block(self, inputs, y, totals, width):
        """:meth:`advance` over one block of steps: the models step by step, the errors as one array."""
        count = y.size
        outputs = np.empty((count, self.samples.shape[0]))
        # The lagged models take the steps that leave the ring: those whose inputs are in it, then the block's own.
        behind = [self._recent_u[(self.steps + k) % width] for k in range(min(count, width)) if self.steps + k >= width]
        behind += list(inputs[: max(count - width, 0)])
        with np.errstate(over="ignore", invalid="ignore"):
            for k in range(count):
                outputs[k] = self._stepper.step(self._stepper_input(inputs[k]))
            for row in behind:
                self._lagged.step(self._stepper_input(row))
            self._same.check(outputs.T, last=False)
            self._mark_diverged(np.isfinite(outputs).all(axis=0), self.steps + count - 1)
            measured = ~np.isnan(y)
            errors = np.abs(np.subtract(outputs, y[:, None], out=outputs), out=outputs)  # |s - y| == |y - s|
            errors[~measured] = 0.0
            fixed_at = self._scale_in_block(y, measured)
            self._largest = max(self._largest, float(np.abs(y[measured]).max(initial=0.0)))
            # Rows before the scale was fixed are added unscaled and the totals rescaled, as step by step.
            if totals is not None and fixed_at is not None:
                add_record_errors(totals, errors[:fixed_at])
                totals *= self.error_scale
            if self.error_scale != 1.0:
                errors[fixed_at or 0 :] *= self.error_scale
            if totals is not None:
                add_record_errors(totals, errors[fixed_at or 0 :])
        for k in range(max(count - width, 0), count):
            slot = (self.steps + k) % width
            self._errors[slot] = errors[k] if k >= (fixed_at or 0) else errors[k] * self.error_scale
            self._recent_u[slot], self._recent_y[slot], self._measured[slot] = inputs[k], y[k], measured[k]
        self.steps += count

    def _scale_in_block(self, y, measured):
        """Fix the error scale at the block's first measured value that is not zero, if none was before: its index."""
        if self._scaled_by is not None:
            return None
        nonzero = np.flatnonzero(measured & (y != 0.0))
        if not nonzero.size:
            return None
        first = int(nonzero[0])
        self._fix_scale(float(y[first]), self.steps + first)
        return first

    @property
    def newest_errors(self):
        """The absolute error of every sample at the newest step, times ``error_scale`` (read-only)."""
        view = self._errors[(self.steps - 1) % self._errors.shape[0]].view()
        view.flags.writeable = False
        return view

    @property
    def window_statistics(self):
        """(best, upper, threshold, points) of the newest window: what the noise floor reads of it.

        Its best MAE, its MAE at population quantile 0.9 and its behavioural
        threshold MAE, in the record's units, and its measured points
        (:mod:`dynia.engine.noise`); the MAEs are NaN where the window had no
        result.
        """
        return self._best, self._upper, self._threshold, self._present

    def to_bytes(self, shared=None):
        """The object's whole state (samples, models, window, error scale) as bytes, for :meth:`from_bytes`.

        The model itself is left out: whoever restores the state gives it
        again, so that no code travels with the bytes.

        Parameters
        ----------
        shared : dynia.checkpoint.SharedArrays, optional
            Arrays of a series of checkpoints that are written once: every
            array of the state that equals one of them is stored as a
            reference to it (the samples, the models' coefficients: two
            thirds of a checkpoint). An empty one takes every large array of
            this state.
        """
        return state_bytes(self, self._model, shared)

    @classmethod
    def from_bytes(cls, data, model, shared=None):
        """The object :meth:`to_bytes` gave ``data`` of, with ``model``, the model it was made with.

        Only the classes of numpy's arrays and of dynia's own models,
        settings, flavours and this class are rebuilt: bytes naming any
        other (a damaged or foreign checkpoint) raise a DataError instead of
        running code. ``shared`` are the :class:`~dynia.checkpoint.SharedArrays` it was
        written with.

        Raises
        ------
        DataError
            ``data`` is not a state written by :meth:`to_bytes`, or was
            written for another kind of model or other shared arrays.
        """
        state = restored_state(data, model, shared)
        if not isinstance(state, cls):
            raise DataError(f"the saved state is a {type(state).__name__}, not an OnlineDynia")
        return state

    def _take(self, u_t, y_t):
        """Step every model by ``u_t`` and put its absolute errors against ``y_t`` into the window's ring."""
        if self._model.n_inputs == 1:
            u_t = _scalar(u_t, "u_t", self.steps, allow_nan=False)
        else:
            u_t = _checks.as_1d_float(u_t, f"u_t at step {self.steps}")
            if u_t.size != self._model.n_inputs:
                raise DataError(f"u_t at step {self.steps} must hold {self._model.n_inputs} inputs; got {u_t.size}")
        y_t = _scalar(y_t, "y_t", self.steps, allow_nan=True)
        width = self._errors.shape[0]
        slot = self.steps % width
        errors = self._errors[slot]
        # An unstable set may overflow; it is caught below, so numpy need not warn.
        with np.errstate(over="ignore", invalid="ignore"):
            simulated = self._stepper.step(u_t)
            self._same.check(simulated[:, None], last=False)  # refused by replay, which sees the whole record
            np.isfinite(simulated, out=self._finite)
            self._mark_diverged(self._finite, self.steps)
            if self.steps >= width:  # the lagged models take the step leaving the ring
                self._lagged.step(self._stepper_input(self._recent_u[slot]))
            self._recent_u[slot], self._recent_y[slot] = u_t, y_t
            self._measured[slot] = y_t == y_t
            if self._measured[slot]:
                if self._scaled_by is None and y_t != 0.0:
                    self._fix_scale(y_t, self.steps)
                self._largest = max(self._largest, abs(y_t))
                self._window_errors(simulated, y_t, errors)
            else:
                errors.fill(0.0)
            self.steps += 1

    def replay(self, u, y):
        """Feed a whole record, step by step as if live, and collect every step's results.

        Continues from the current state (call :meth:`reset` first to start
        over). Both arrays are checked before anything is fed.

        Parameters
        ----------
        u, y : array_like, shape (n_steps,), or pandas Series / DataFrame
            Input and measured output (NaN marks a missing measurement).
            pandas objects as :func:`dynia.run` takes them
            (:func:`dynia.io.frames.unpack`): one index; a time index must be
            spaced by the ``dt`` this object steps by, and its dates become
            the result's ``timestamps``.

        Returns
        -------
        DyniaResult
            ``.ic`` (n_params, n_steps), ``.ci`` (n_params, n_steps, 2),
            ``.median`` (n_params, n_steps), ``.gradient`` (n_params, n_bins,
            n_steps), with ``.time`` continuing
            from the steps fed before; comparable with
            ``dynia.run(..., window="trailing")`` on the same record. Its
            noise floor (``.informative``, :mod:`dynia.engine.noise`) judges
            the replayed windows together, as the batch analysis does: the
            noise level is a median over them, and the noise's
            autocorrelation comes from the residuals of the set with the
            lowest total absolute error over the replayed steps, which is
            simulated once more; a single update cannot give them.

        Raises
        ------
        ModelError
            When every parameter set's output has been the same at every
            step fed since the start (or :meth:`reset`), as :func:`dynia.run`
            refuses such a model: every window's sets tie. A single update
            cannot tell, since a later input may still excite the model.
        """
        # The samples step by the dt they were made with: a time index is checked against it, never adopted.
        dt = self._analysis.dt
        try:
            u, y, _, timestamps = unpack(u, y, dt)
        except SettingsError:
            spacing = unpack(u, y)[2]
            raise SettingsError(
                f"the index of the record replayed is spaced {spacing:g} s, but this OnlineDynia steps by dt = {dt:g} "
                f"s; make it with dt={spacing:g}",
                "dt",
            ) from None
        u, y = _checks.record(u, y, n_inputs=self._model.n_inputs)
        n_params, n_bins = self.bin_centres.shape
        ic = np.empty((n_params, y.size))
        ci = np.empty((n_params, y.size, 2))
        median = np.empty((n_params, y.size))
        gradient = np.empty((n_params, n_bins, y.size))
        best, upper, threshold, points = np.empty(y.size), np.empty(y.size), np.empty(y.size), np.empty(y.size)
        first = self.steps
        # The simulation from here on, to simulate the record-best set again once it is known.
        start = self._copied(self._stepper) if first else None
        totals = np.zeros(self.samples.shape[0])
        width = self._errors.shape[0]
        for step, (u_t, y_t) in enumerate(zip(u.tolist(), y.tolist())):  # u_t a list for several inputs
            scale = self.error_scale
            ic[:, step], ci[:, step], gradient[:, :, step] = self.update(u_t, y_t)
            if self.error_scale != scale:  # fixed at this step: the errors added so far are rescaled alike
                totals *= self.error_scale
            median[:, step] = self.median
            best[step], upper[step], threshold[step] = self._best, self._upper, self._threshold
            points[step] = self._present
            add_record_errors(totals, self.newest_errors[None])  # as the batch engine adds them
        if self._same.same:  # every set tied in every window: no result is one
            refuse_ignored_params(self._model, self._model_params, _functions(self._model))
        totals[self._diverged] = np.inf
        floor = record_noise_floor(
            best,
            upper,
            threshold,
            points,
            width,
            n_params,
            self._analysis.percentage,
            self.samples.shape[0],
            fit=record_fit(y, self.samples, self.bounds, totals, self._simulations(u, start)),
        )
        run = dataclasses.replace(self._run, n_diverged=self.n_diverged, **floor_settings(floor))
        if self._analysis.quality:
            # Screened once replayed: a stream cannot be screened before it is seen. Windows reaching back before
            # this replay are judged on the samples replayed.
            run = dataclasses.replace(run, screened=screen(u, y, (2 * self._analysis.n, 0)))
        result = DyniaResult(
            names=self.names,
            samples=np.array(self.samples),
            bounds=self.bounds.copy(),
            time=(first + np.arange(y.size)) * self._analysis.dt,
            ic=ic,
            ci=ci,
            median=median,
            gradient=gradient,
            bin_centres=self.bin_centres,
            settings=self._analysis,
            run=run,
            timestamps=timestamps,
            **floor_fields(floor),
        )
        # The whole record's least squares simulates from the start state: only a replay from step 0 has it.
        return result if first else record_least_squares(result, u, y, self._model)

    def _simulations(self, u, start):
        """``simulations(rows)`` of :func:`dynia.engine.noise.record_fit` over the replayed record.

        ``start`` is the stepper as the replay began, None when it began at
        step 0: the sets are then simulated alone, which the stepper equals
        bit for bit; otherwise a copy of it is stepped through ``u`` again.
        """

        def simulations(rows):
            if start is None:
                model_params = self._model_params[rows]
                return self._model.simulate_chunks(
                    model_params, u, dt=self._analysis.dt, x0=self._analysis.x0, chunk_steps=RESIDUAL_CHUNK
                )
            return _stepped(self._copied(start), u, rows)

        return simulations

    def _window_mean(self):
        """Each sample's MAE over the window ending at the newest step, into ``_mae``.

        Returns whether the window has ``min_points`` measured points.
        """
        width = self._errors.shape[0]
        oldest = self.steps % width  # the slot after the newest is the oldest
        total = self._mae[0]
        # Oldest to newest, the batch engine's order; slots before the record
        # are zeros, which the engine's padding adds as well.
        np.copyto(total, self._errors[oldest])
        for age in range(1, width):
            total += self._errors[(oldest + age) % width]
        present = int(self._measured.sum())
        if present:
            total /= float(present)
        self._present = present
        return present >= self._analysis.min_points

    def _analyse(self, usable):
        """Rank, select and read off the window's results with the engine's flavour code."""
        if self._diverged.any():
            usable = self._rank_diverged_last() and usable
        results = self._flavour.analyse(self._mae, np.array([usable]))
        if blank_overflowed(results)[0]:
            self._report_overflowed()
        self.ic, self.ci, self.gradient = results.ic[:, 0], results.ci[:, 0], results.gradient[:, :, 0]
        self.median = results.median[:, 0]
        # In the record's units, as the batch engine reports them: the scale is a power of two.
        self._best, self._threshold, self._upper = (
            float(results.best[0]) / self.error_scale,
            float(results.threshold[0]) / self.error_scale,
            float(results.upper[0]) / self.error_scale,
        )

    def _report_overflowed(self):
        """The newest window's behavioural MAE overflowed when squared: refuse if the scale is to blame, else warn."""
        step = self.steps - 1
        if error_scale([self._largest]) != self.error_scale:
            first_step, first = self._scaled_by
            raise DataError(
                f"y reaches {self._largest:.3g} in magnitude by step {step}, beyond what the error scale fixed "
                f"online from the first measured value that is not zero ({first:.3g} at step {first_step}) can "
                "hold: the squared errors overflow and every set ties; OnlineDynia cannot rescale the windows "
                "it has analysed, so give y (and the model's output) in a unit that keeps them within about 1e54 "
                "of their first value, or analyse the record with dynia.run(..., window='trailing')"
            )
        warnings.warn(
            f"the behavioural parameter sets' mean absolute error is beyond 1.3e154 in the window ending at step "
            f"{step}, so its square, the cost, overflows and they tie, while y is at most {self._largest:.3g} in "
            "magnitude: the simulated output lies more than 1e54 times beyond the data there (check the input "
            "for absurd values and the model's output for its units); the window is left without results",
            OverflowedWindowsWarning,
            stacklevel=4,
        )

    def _rank_diverged_last(self):
        """Give diverged sets the worst MAE; False if too few finite sets remain to analyse."""
        finite_left = self._diverged.size - int(self._diverged.sum())
        if finite_left < max(self._flavour.count, 1):
            return False
        mae = self._mae[0]
        if isinstance(self._flavour, McatFlavour):
            mae[self._diverged] = mae[~self._diverged].max()
        else:
            mae[self._diverged] = np.inf
        return True

    def _blank_results(self):
        n_params, n_bins = self.bin_centres.shape
        self._best = self._threshold = self._upper = float("nan")
        self._present = 0
        self.ic = np.full(n_params, np.nan)
        self.ci = np.full((n_params, 2), np.nan)
        self.median = np.full(n_params, np.nan)
        self.gradient = np.full((n_params, n_bins), np.nan)


# Steps whose outputs advance() holds at once: 8 MB at 2 000 samples.
_ADVANCE_BLOCK = 512


def _functions(model):
    """What of ``model`` computes its output, as its 'ignores params' refusal names it."""
    if isinstance(model, FunctionModel):
        return "fn"
    if isinstance(model, StateSpaceModel):
        return "step and output"
    return "the simulation"


def _stepped(stepper, u, rows):
    """The outputs of samples ``rows`` as ``stepper`` steps through ``u``, in chunks of steps."""
    block = []
    with np.errstate(over="ignore", invalid="ignore"):
        for u_t in u.tolist():
            block.append(stepper.step(u_t)[rows])
            if len(block) == RESIDUAL_CHUNK:
                yield np.stack(block, axis=1)
                block = []
    if block:
        yield np.stack(block, axis=1)


def _scalar(value, name, step, *, allow_nan):
    """``value`` as a float, or a clear TypeError/ValueError naming it and the step."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number (one logged value); got {type(value).__name__} at step {step}")
    value = float(value)
    if np.isinf(value) or (np.isnan(value) and not allow_nan):
        raise DataError(
            f"{name} must be finite at step {step}; got {value}"
            + (" (NaN marks a missing measurement; inf is not allowed)" if allow_nan else "")
        )
    return value
