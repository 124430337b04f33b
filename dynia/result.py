"""The result of a DYNIA run: arrays, tables and the thesis's two figure types.

Shapes follow the package convention (see :mod:`dynia.engine`):
``ic`` (n_params, n_steps), ``ci`` (n_params, n_steps, 2) as [lower, upper],
``median`` (n_params, n_steps),
``gradient`` (n_params, n_bins, n_steps), ``bin_centres`` (n_params, n_bins),
``samples`` (n_samples, n_params), ``bounds`` (n_params, 2); the optional
Monte Carlo errors ``ic_se`` (n_params, n_steps) and ``ci_se`` (n_params,
n_steps, 2).
"""

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .decimation import decimated_columns, envelope
from .engine.cld import binned_mass
from .errors import SettingsError
from .settings import IC_THRESHOLD, AnalysisSettings, RunRecord, check_ic_threshold
from .summary import Summary

__all__ = [
    "DyniaResult",
]


@dataclass(frozen=True, eq=False)
class DyniaResult:
    """Information content, confidence limits and CLD gradient over time.

    Attributes
    ----------
    names : tuple of str
        Parameter names, in the order of every parameter axis.
    samples : ndarray (n_samples, n_params)
        The parameter sets simulated.
    bounds : ndarray (n_params, 2)
        [low, high] of each parameter's sampling range.
    time : ndarray (n_steps,)
        Time of each step.
    ic : ndarray (n_params, n_steps)
        Information content, 1 - (upper - lower)/range; NaN where a window
        had too few measured points.
    ci : ndarray (n_params, n_steps, 2)
        Lower and upper confidence limit.
    gradient : ndarray (n_params, n_bins, n_steps)
        CLD gradient (likelihood mass per bin for "thesis" and "weighted").
    bin_centres : ndarray (n_params, n_bins)
        Parameter value of each gradient row.
    settings : dynia.settings.AnalysisSettings or None
        The settings of the run, frozen, as the analysis used them: ``n_samples``
        counts the parameter sets analysed (after any were dropped) and
        ``engine`` is the one that ran ("auto" resolved). The constructor
        also takes a mapping of :class:`~dynia.settings.AnalysisSettings`
        fields (the others at their defaults), e.g. ``dict(n=5,
        window="trailing")``, and converts it; an empty mapping is None.
        None for a result built without settings (then which samples a
        window used is unknown).
    run : dynia.settings.RunRecord
        What the run found out and did beside its settings: the model, the
        samples drawn and dropped, the noise floor's values, the Monte Carlo
        error's batches and rounds, the adaptive samplers' weights, ...
        (frozen; a mapping of its fields is converted). An empty record
        (every field None) by default.
    verdicts : dict or None
        Per parameter ``{"verdict", "reasons"}`` from
        :func:`dynia.verdicts.assess` with the data and the model, as
        :func:`dynia.run` attaches them; None for results built without
        them (then :meth:`summary` applies the rules that need the result
        only).
    timestamps : ndarray of datetime64[ns] or None
        The time axis as datetimes, one per step (``time`` stays seconds):
        :func:`dynia.run` sets it from a pandas DatetimeIndex (in UTC when
        the index had a time zone), see :func:`dynia.io.frames.unpack`. When
        present, :meth:`to_dataframe` and :meth:`to_xarray` carry it, the
        plots draw against it and :meth:`summary` reports its times as dates.
        None otherwise.
    ic_se : ndarray (n_params, n_steps) or None
        Monte Carlo standard error of ``ic``: how much the IC would change
        with another sample of the same size (``dynia.run(...,
        ic_error=True)``, batch means, see :mod:`dynia.engine.windows`).
        NaN where ``ic`` is. None when not estimated.
    ci_se : ndarray (n_params, n_steps, 2) or None
        The same for the lower and upper limit.
    informative : ndarray (n_steps,) of bool or None
        The noise floor (:mod:`dynia.engine.noise`): True where the window
        tells parameter values apart beyond what measurement noise alone
        does, its ``discrimination`` above ``noise_floor``. An uninformative
        window's IC and band are a ranking of noise: the plots grey it out,
        the verdicts never call it ``identified`` and ``dynia identify``
        never selects it. One mask for all parameters, since the population
        is one for all. None for results built without it (and for files
        saved before the discrimination was the statistic).
    discrimination : ndarray (n_steps,) or None
        The mask's statistic: the MAE at population quantile 0.9
        (``run.noise_floor_quantile``) minus the best MAE.
    noise_floor : ndarray (n_steps,) or None
        What noise alone keeps the discrimination below
        (``run.noise_multiple`` sampling standard deviations of the
        MAE of the window's points of noise ``run.noise_sigma``).
    behavioural_spread : ndarray (n_steps,) or None
        The behavioural set's largest MAE minus the best: whether the band
        itself is a ranking of noise (verdict reason ``noise_ranked``).
    behavioural_floor : ndarray (n_steps,) or None
        What noise alone keeps the behavioural spread below
        (``run.behavioural_multiple`` of the same standard deviations).
    best_mae : ndarray (n_steps,) or None
        Every window's lowest mean absolute error, from which the noise
        level ``run.noise_sigma`` is estimated; with ``discrimination`` and
        ``behavioural_spread`` the three MAEs the floor tests
        (:class:`dynia.engine.noise.NoiseFloor`). None where the floor is.
    median : ndarray (n_params, n_steps) or None
        CLD median of each window's behavioural values, read off as the
        limits are, so it lies in the band: the first sorted value whose
        likelihood-weighted CLD reaches 0.5 ("weighted"), the sorted value at
        position floor(0.5 (count - 1)) ("thesis", as its limits; with the
        adaptive samplers' importance weights, where their CLD reaches 0.5),
        MCAT's rank analogue ("mcat"). The estimate of :meth:`summary`. NaN where
        ``ic`` is; None for results built without it (files saved before it
        existed, :func:`dynia.reference.thesis.thesis_code_result`).
    """

    names: tuple
    samples: np.ndarray
    bounds: np.ndarray
    time: np.ndarray
    ic: np.ndarray
    ci: np.ndarray
    gradient: np.ndarray
    bin_centres: np.ndarray
    settings: AnalysisSettings | None = None
    run: RunRecord = field(default_factory=RunRecord)
    verdicts: dict | None = None
    timestamps: np.ndarray | None = None
    ic_se: np.ndarray | None = None
    ci_se: np.ndarray | None = None
    informative: np.ndarray | None = None
    discrimination: np.ndarray | None = None
    noise_floor: np.ndarray | None = None
    behavioural_spread: np.ndarray | None = None
    behavioural_floor: np.ndarray | None = None
    best_mae: np.ndarray | None = None
    median: np.ndarray | None = None

    def __post_init__(self):
        if isinstance(self.settings, Mapping):
            # An empty mapping is what results built by hand passed for "no settings known".
            object.__setattr__(self, "settings", AnalysisSettings().replace(**self.settings) if self.settings else None)
        elif self.settings is not None and not isinstance(self.settings, AnalysisSettings):
            raise SettingsError(
                f"settings must be a dynia.settings.AnalysisSettings, a mapping of its fields or None; "
                f"got {type(self.settings).__name__}",
                "settings",
            )
        if isinstance(self.run, Mapping):
            object.__setattr__(self, "run", RunRecord(**self.run))
        elif not isinstance(self.run, RunRecord):
            raise SettingsError(f"run must be a dynia.settings.RunRecord; got {type(self.run).__name__}", "run")
        if self.timestamps is not None:
            # Checked here, so that no result whose file dynia.load would refuse can be saved.
            problem = timestamps_problem(self.time, self.timestamps)
            if problem is not None:
                raise SettingsError(f"timestamps {problem}", "timestamps")

    def index(self, name):
        """Position of parameter ``name`` on the parameter axis."""
        try:
            return self.names.index(name)
        except ValueError:
            raise SettingsError(f"unknown parameter {name!r}; this result has {list(self.names)}") from None

    @property
    def window_halos(self):
        """Steps (before, after) the window at step t reaches: (n, n) centred, (2n, 0) trailing.

        Read from ``settings.n`` and ``settings.window``; a result built
        without settings has no known geometry.
        """
        if self.settings is None:
            raise SettingsError(
                "this result has no settings, so no half window 'n': which samples each window used is unknown"
            )
        n = self.settings.n
        return (n, n) if self.settings.window == "centred" else (2 * n, 0)

    def window_range(self, step):
        """Sample range ``[start, stop)`` the window at ``step`` used, clipped to the record.

        Examples
        --------
        >>> import numpy as np
        >>> res = DyniaResult(names=("K",), samples=np.zeros((2, 1)), bounds=np.array([[0.0, 1.0]]),
        ...                   time=np.arange(50.0), ic=np.zeros((1, 50)), ci=np.zeros((1, 50, 2)),
        ...                   gradient=np.zeros((1, 1, 50)), bin_centres=np.zeros((1, 1)),
        ...                   settings=dict(n=5, window="trailing"))
        >>> res.window_range(30), res.window_range(3)
        ((20, 31), (0, 4))
        """
        before, after = self.window_halos
        n_steps = self.time.size
        step = int(step)
        if not 0 <= step < n_steps:
            raise SettingsError(f"step {step} is outside the record's {n_steps} steps")
        return max(step - before, 0), min(step + after + 1, n_steps)

    def ic_at_least(self, threshold, parameters=None, mode="any"):
        """Steps whose IC is at least ``threshold`` (NaN never is), (n_steps,) bool.

        ``parameters`` (default all) are the parameters considered; ``mode``
        "any" needs one of them to reach the threshold, "joint" all. For one
        parameter's mask pass its name alone.
        """
        names = self.names if parameters is None else ((parameters,) if isinstance(parameters, str) else parameters)
        rows = self.ic[[self.index(name) for name in names]]
        if mode not in ("any", "joint"):
            raise SettingsError(f"mode must be 'any' or 'joint'; got {mode!r}")
        with np.errstate(invalid="ignore"):
            reached = rows >= threshold
        return reached.any(axis=0) if mode == "any" else reached.all(axis=0)

    def informative_windows(self, ic_threshold=IC_THRESHOLD, parameters=None):
        """Which windows are informative about each parameter, (n_params, n_steps) bool: the package's one rule.

        A window is informative about a parameter when its IC reaches
        ``ic_threshold`` and that IC is the data's, not the noise's: the
        window lies above the noise floor (:attr:`informative`: it tells
        parameter sets apart beyond what measurement noise alone does) and
        its behavioural set is not tied within noise (:attr:`behavioural_spread`
        above :attr:`behavioural_floor`; when it ties, which sets are kept,
        and so the band whose width the IC is, is decided by the noise
        realisation), and it is not screened (:attr:`screened_windows`: it
        uses no saturated or frozen reading and, on a coarsely quantised
        output, the output moves by at least a few grid steps in it; a window
        that ranks parameter sets by how well they reproduce a sensor's limit
        is evidence of the sensor, not of the process). A window with no IC
        (NaN: too few measured points) never is. Windows truncated by the record's ends count: the floor judges
        each window with its own measured points, so a truncated window above
        it is informative about the data it holds. With ``ic_threshold=0``
        the mask is every window whose IC says something about the data.

        Every rule that judges windows starts from this mask and may only
        narrow it: the segments of :func:`dynia.segments.segments_from_ic`
        (and so ``dynia identify``), the verdicts' evidence
        (:func:`dynia.verdicts.high_ic_windows`), the second run's narrowing
        (:func:`dynia.refine.narrowed_bounds`), the structure warnings
        (:func:`dynia.structure.structure_warnings`) and the grey veil of the
        plots. The verdicts and the structure warnings also need whole
        windows (``full_windows``), so that the windows they compare hold
        equally many points; the second run and the structure warnings need
        bands clear of the range's bounds and runs of several windows.

        A result without the noise floor (``informative`` None: the
        reference ports :mod:`dynia.reference`, results built by hand, files
        saved before the floor existed) has only the IC test; one with the
        floor but without the behavioural spread skips the tie test; one
        that was not screened (``run.screened`` None) skips the screening.

        Parameters
        ----------
        ic_threshold : float in [0, 1], default :data:`dynia.settings.IC_THRESHOLD` (0.5)
            IC from which a window can be informative.
        parameters : str or sequence of str, optional
            The parameters, one row each in this order (default: all of
            :attr:`names`); a single name gives one row.

        Returns
        -------
        ndarray of bool, shape (len(parameters), n_steps)

        Examples
        --------
        >>> import numpy as np
        >>> res = DyniaResult(names=("K",), samples=np.zeros((2, 1)), bounds=np.array([[0.0, 1.0]]),
        ...                   time=np.arange(4.0), ic=np.array([[0.9, 0.9, 0.9, np.nan]]), ci=np.zeros((1, 4, 2)),
        ...                   gradient=np.zeros((1, 1, 4)), bin_centres=np.zeros((1, 1)),
        ...                   informative=np.array([True, False, True, True]))
        >>> res.informative_windows().tolist()  # step 1 below the floor, step 3 without IC
        [[True, False, True, False]]
        """
        ic_threshold = check_ic_threshold(ic_threshold)
        names = self.names if parameters is None else ((parameters,) if isinstance(parameters, str) else parameters)
        rows = np.asarray(self.ic)[[self.index(name) for name in names]]
        with np.errstate(invalid="ignore"):  # NaN compares False
            informative = rows >= ic_threshold
            if self.informative is not None:
                informative &= np.asarray(self.informative, dtype=bool)
            if self.behavioural_spread is not None:
                informative &= ~(np.asarray(self.behavioural_spread) <= np.asarray(self.behavioural_floor))
        if self.run.screened:
            informative &= ~self.screened_windows
        return informative

    @property
    def screened_windows(self):
        """Windows the data-quality screening takes from the evidence for every parameter, (n_steps,) bool.

        Computed from ``run.screened`` (:func:`dynia.quality.screen`, which
        :func:`dynia.run` records when ``settings.quality`` is True, the
        default): every window that uses a saturated or stuck (frozen)
        reading of the input or the output (:meth:`windows_using`), and,
        when the output is coarsely quantised, every window whose output
        moves by fewer than :data:`dynia.quality.QUANTISED_MIN_STEPS` grid
        steps. :meth:`informative_windows` excludes them, so no verdict,
        segment, narrowing or structure warning rests on them. All False
        when nothing was screened or found (``run.screened`` None or empty).

        Examples
        --------
        >>> import numpy as np
        >>> res = DyniaResult(names=("K",), samples=np.zeros((2, 1)), bounds=np.array([[0.0, 1.0]]),
        ...                   time=np.arange(12.0), ic=np.full((1, 12), 0.9), ci=np.zeros((1, 12, 2)),
        ...                   gradient=np.zeros((1, 1, 12)), bin_centres=np.zeros((1, 1)), settings=dict(n=1),
        ...                   run=dict(screened=(("saturated", "y", 5, 7, 0.95),)))
        >>> np.flatnonzero(res.screened_windows).tolist()  # windows 4 to 7 use sample 5 or 6
        [4, 5, 6, 7]
        >>> res.informative_windows()[0].sum()
        np.int64(8)
        """
        # quality imports the settings only: imported here like verdicts, to keep the modules acyclic
        from .quality import screened_windows

        if not self.run.screened:
            return np.zeros(self.time.shape, dtype=bool)
        return screened_windows(self.run.screened, self.windows_using, self.time.size)

    def window_cover(self, steps):
        """Which samples the windows at the marked ``steps`` used, as a boolean mask (n_steps,).

        ``steps`` is a boolean mask over the steps (n_steps,); a sample is True when
        any marked window holds it. With :meth:`window_centres` and
        :meth:`windows_using` this is the one place that maps windows to the
        samples they analysed, for centred and trailing windows alike.
        """
        steps = self._step_mask(steps, "steps")
        before, after = self.window_halos
        n_steps = steps.size
        covered = np.zeros(n_steps + 1, dtype=np.int64)
        # +1 where a window starts, -1 after it ends: a running sum above 0 marks covered samples.
        centres = np.flatnonzero(steps)
        np.add.at(covered, np.maximum(centres - before, 0), 1)
        np.add.at(covered, np.minimum(centres + after + 1, n_steps), -1)
        return np.cumsum(covered[:-1]) > 0

    def window_centres(self, steps):
        """The sample at the centre of each marked window, as a mask (n_steps,).

        A centred window's centre is its own step; a trailing window's IC at t
        describes samples t-2n .. t, centred on t-n.
        """
        steps = self._step_mask(steps, "steps")
        before, after = self.window_halos
        shift = (before - after) // 2
        centres = np.zeros_like(steps)
        centres[: steps.size - shift] = steps[shift:]
        return centres

    def windows_using(self, samples):
        """Windows that use at least one of the marked ``samples``, as a mask over the steps (n_steps,)."""
        samples = self._step_mask(samples, "samples")
        before, after = self.window_halos
        # Window t holds samples t-before .. t+after: it uses a marked sample when
        # the count of marked samples in that range is above 0.
        counts = np.concatenate(([0], np.cumsum(samples)))
        steps = np.arange(samples.size)
        first = np.maximum(steps - before, 0)
        last = np.minimum(steps + after + 1, samples.size)
        return counts[last] - counts[first] > 0

    @property
    def full_windows(self):
        """Steps whose window holds all 2n+1 steps (not cut by the record's ends), (n_steps,) bool."""
        before, after = self.window_halos
        steps = np.arange(self.time.size)
        return (steps - before >= 0) & (steps + after < self.time.size)

    def _step_mask(self, mask, name):
        mask = np.asarray(mask)
        if mask.dtype != bool or mask.shape != self.time.shape:
            raise SettingsError(
                f"{name} must be a boolean mask of shape {self.time.shape}, one flag per step; "
                f"got dtype {mask.dtype}, shape {mask.shape}"
            )
        return mask

    def summary(self):
        """Per parameter: the reported window's IC, when it occurs, the band and the estimate there, and a verdict.

        The reported window (``max_ic``, ``time_of_max_ic``) is the one of
        highest IC among the windows that are evidence (informative,
        :meth:`informative_windows`, and whole) when there is one, else the
        one of highest IC of all (:func:`dynia.verdicts.reported_step`);
        ``highest_ic`` and ``time_of_highest_ic`` are the record's highest
        IC wherever it lies; where that is not the reported window,
        ``highest_ic_no_evidence`` lists why its window is no evidence
        (:func:`dynia.verdicts.no_evidence_reasons`: ``"record_edge"``,
        ``"below_noise_floor"``, ``"noise_ranked"``, ...). The estimate is the CLD median (:attr:`median`)
        at the reported window, so it always lies in the band there; a result without
        the median (a file saved before it existed) reports the band's
        midpoint instead. The verdict ("identified", "weak" or
        "suspect") and its reasons say what that estimate is worth (see
        :mod:`dynia.verdicts`). Parameters whose IC is missing everywhere get
        None for the numbers.

        ``high_ic_windows`` counts the windows informative about the
        parameter at the verdicts' threshold (:meth:`informative_windows`,
        :func:`dynia.verdicts.high_ic_windows`), the evidence whose agreement
        the verdict checks, and
        ``high_ic_span`` gives the time of the first and of the last of
        them ([None, None] when there is none).

        ``record_fit`` is the whole record's least-squares fit of the model
        and ``record_fit_se`` its standard error, robust to the residuals'
        autocorrelation (``run.record_fit``, inf where the record does not
        determine the parameter); None for a result without it. An
        identified band holds it (:mod:`dynia.verdicts`, reason
        ``disagrees_with_record_fit``).

        The times (``time_of_max_ic``, ``time_of_highest_ic``,
        ``high_ic_span``) are seconds from the start of the record (floats,
        as :attr:`time`), or for a dated result (:attr:`timestamps`) the
        dates of those steps, ``numpy.datetime64`` scalars in nanoseconds
        equal to ``timestamps[step]``.

        Returns
        -------
        dynia.summary.Summary
            A dict ``{name: {"max_ic", "time_of_max_ic", "band": [lower, upper], "estimate", "highest_ic",
            "time_of_highest_ic", "high_ic_windows", "high_ic_span": [first, last], "record_fit", "record_fit_se",
            "verdict", "reasons"}}``
            with plain Python values but the dates; with the Monte Carlo errors also
            ``"max_ic_se"``, the standard error of the max IC. It shows itself as the table ``dynia analyse``
            prints (``print(summary)``, HTML in a notebook) and ``summary.to_frame()`` gives it as a pandas frame.

        Examples
        --------
        >>> import dataclasses, numpy as np
        >>> res = DyniaResult(names=("K",), samples=np.zeros((2, 1)), bounds=np.array([[0.0, 1.0]]),
        ...                   time=np.array([0.0, 60.0, 120.0]), ic=np.array([[0.2, 0.9, 0.4]]), ci=np.zeros((1, 3, 2)),
        ...                   gradient=np.zeros((1, 1, 3)), bin_centres=np.zeros((1, 1)), settings=dict(n=1))
        >>> res.summary()["K"]["time_of_max_ic"]
        60.0
        >>> dates = np.array(["2015-01-31T23:59", "2015-02-01T00:00", "2015-02-01T00:01"], dtype="datetime64[ns]")
        >>> dataclasses.replace(res, timestamps=dates).summary()["K"]["time_of_max_ic"]
        np.datetime64('2015-02-01T00:00:00.000000000')
        """
        # verdicts reads results: imported here to keep the modules acyclic
        from .verdicts import assess, high_ic_windows, no_evidence_reasons, reported_step

        verdicts = self.verdicts if self.verdicts is not None else assess(self)
        summary = Summary()
        for p, name in enumerate(self.names):
            if np.isnan(self.ic[p]).all():
                summary[name] = dict(
                    max_ic=None,
                    time_of_max_ic=None,
                    band=[None, None],
                    estimate=None,
                    highest_ic=None,
                    time_of_highest_ic=None,
                )
            else:
                best = reported_step(self, p)
                highest = int(np.nanargmax(self.ic[p]))
                summary[name] = dict(
                    max_ic=float(self.ic[p, best]),
                    time_of_max_ic=self._when(best),
                    band=[float(self.ci[p, best, 0]), float(self.ci[p, best, 1])],
                    estimate=self._estimate(p, best),
                    highest_ic=float(self.ic[p, highest]),
                    time_of_highest_ic=self._when(highest),
                )
                if highest != best:
                    summary[name]["highest_ic_no_evidence"] = no_evidence_reasons(self, p, highest)
                if self.ic_se is not None:
                    summary[name]["max_ic_se"] = float(self.ic_se[p, best])
            steps = np.flatnonzero(high_ic_windows(self, p))
            summary[name].update(
                high_ic_windows=int(steps.size),
                high_ic_span=[self._when(steps[0]), self._when(steps[-1])] if steps.size else [None, None],
            )
            summary[name].update(self._record_fit(p))
            summary[name].update(verdict=verdicts[name]["verdict"], reasons=list(verdicts[name]["reasons"]))
        return summary

    def _record_fit(self, p):
        """``record_fit`` and ``record_fit_se`` of parameter ``p`` for :meth:`summary` (None where the run has none)."""
        fit, errors = self.run.record_fit, self.run.record_fit_se
        if fit is None or errors is None:
            return dict(record_fit=None, record_fit_se=None)
        return dict(record_fit=fit[p], record_fit_se=errors[p])

    def _when(self, step):
        """The time of ``step`` as :meth:`summary` reports it: its date (datetime64[ns]) when dated, else seconds."""
        if self.timestamps is None:
            return float(self.time[step])
        return np.datetime64(self.timestamps[step], "ns")

    def _estimate(self, p, step):
        """Parameter ``p``'s estimate at ``step``: its CLD median, or without one the band's midpoint."""
        if self.median is None:
            return float((self.ci[p, step, 0] + self.ci[p, step, 1]) / 2)
        return float(self.median[p, step])

    def to_dataframe(self):
        """Long table: one row per (time, parameter) with ic, lower and upper (and median, when the result has it).

        With :attr:`timestamps` a ``timestamp`` column follows ``time``; with
        the Monte Carlo errors, columns ``ic_se``, ``lower_se`` and
        ``upper_se`` follow; with the noise floor, ``informative`` (the
        window's mask, :attr:`informative`, the same for every parameter). Needs pandas (``pip install
        dynia[pandas]``).
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_dataframe needs pandas: pip install 'dynia[pandas]'") from None
        n_params, n_steps = self.ic.shape
        stamps = {} if self.timestamps is None else {"timestamp": np.tile(self.timestamps, n_params)}
        errors = {}
        if self.ic_se is not None:
            errors = dict(
                ic_se=self.ic_se.ravel(), lower_se=self.ci_se[:, :, 0].ravel(), upper_se=self.ci_se[:, :, 1].ravel()
            )
        return pd.DataFrame(
            {
                "time": np.tile(self.time, n_params),
                **stamps,
                "parameter": np.repeat(self.names, n_steps),
                "ic": self.ic.ravel(),
                "lower": self.ci[:, :, 0].ravel(),
                "upper": self.ci[:, :, 1].ravel(),
                **({} if self.median is None else {"median": np.asarray(self.median).ravel()}),
                **errors,
                **({} if self.informative is None else {"informative": np.tile(self.informative, n_params)}),
            }
        )

    def plot_information_content(self, name, ax=None):
        """Information content of ``name`` over time (thesis Figures 2.8, 3.3, ...).

        With :attr:`ic_se`, IC +- 2 standard errors is shaded blue (and a
        legend names it and the veil): where the shading crosses a
        threshold, more samples could change the verdict. Windows whose IC ranks noise (below the noise floor or
        with the behavioural set tied, never informative: :meth:`informative_windows`) are veiled in grey.
        A dotted line marks the threshold :data:`~dynia.settings.IC_THRESHOLD` the verdicts use, and a marker
        the reported window (:meth:`summary`'s ``time_of_max_ic``), labelled with the verdict.
        Returns the matplotlib Axes. A long record is
        drawn through :func:`dynia.decimation.envelope`, so its memory does not
        grow with it.
        """
        import matplotlib.pyplot as plt

        p = self.index(name)
        ax = ax if ax is not None else plt.figure().add_subplot()
        axis = self._plot_axis(ax)
        if self.ic_se is not None:
            # The envelope of each edge: the lower edge's minima and the upper edge's maxima stay in view.
            low_time, low = envelope(axis, self.ic[p] - 2 * self.ic_se[p])
            high_time, high = envelope(axis, self.ic[p] + 2 * self.ic_se[p])
            ax.fill_between(
                np.union1d(low_time, high_time),
                np.interp(np.union1d(low_time, high_time), low_time, low),
                np.interp(np.union1d(low_time, high_time), high_time, high),
                color="tab:blue",
                alpha=0.3,
                linewidth=0,
                label="IC +- 2 standard errors",
            )
        ax.plot(*envelope(axis, self.ic[p]), color="k", linewidth=1)
        self._veil_uninformative(ax, axis, p)
        ax.axhline(IC_THRESHOLD, color="0.3", linestyle=":", linewidth=1, label=f"threshold {IC_THRESHOLD:g}")
        reported = self._reported(p)
        if reported is not None:
            step, verdict = reported
            ax.plot(axis[step], self.ic[p, step], "o", color="tab:orange", markersize=6, label="reported window")
            ax.annotate(
                verdict,
                (axis[step], self.ic[p, step]),
                xytext=(0, 8),
                textcoords="offset points",
                ha="center",
                fontsize="small",
                fontweight="bold",
            )
        ax.legend(loc="best", fontsize="small")
        ax.set_ylim(0, 1)
        ax.set_xlim(axis[0], axis[-1])
        ax.set_xlabel("time")
        ax.set_ylabel("information content")
        ax.set_title(f"Information content of {name}")
        return ax

    def bin_counts(self):
        """Number of Monte Carlo samples in each gradient bin of each parameter.

        A bin's CLD gradient is the likelihood mass of the behavioural samples
        in it, so a bin that happens to hold more samples collects more mass
        and looks darker, whatever the data say. These counts tell how much of
        a dark bin is the sample: uniform samples put ``n_samples / n_bins``
        in each bin on average, give or take its square root. The bins are
        those of the gradient: for the ``"thesis"`` and ``"weighted"``
        flavours (and results without a flavour) ``n_bins`` equal bins of each
        parameter's ``bounds``, as the engine bins (a value on the upper bound
        counts in the last bin); for other rows (the ``"mcat"`` flavour's
        points of the sample range, the ``"thesis-code"`` rows of
        :func:`dynia.reference.thesis.thesis_code_result`) the nearest row.

        Returns
        -------
        ndarray of int, shape (n_params, n_bins)

        Examples
        --------
        >>> import numpy as np
        >>> res = DyniaResult(names=("K",), samples=np.array([[0.1], [0.2], [0.9], [1.0]]),
        ...                   bounds=np.array([[0.0, 1.0]]), time=np.arange(3.0), ic=np.zeros((1, 3)),
        ...                   ci=np.zeros((1, 3, 2)), gradient=np.zeros((1, 4, 3)),
        ...                   bin_centres=np.array([[0.125, 0.375, 0.625, 0.875]]))
        >>> res.bin_counts()
        array([[2, 0, 0, 2]])
        """
        n_bins = self.bin_centres.shape[1]
        columns = np.asarray(self.samples, dtype=float).T
        flavour = "thesis" if self.settings is None else self.settings.flavour
        if self.run.thesis_code or flavour not in ("thesis", "weighted"):
            between = (self.bin_centres[:, :-1] + self.bin_centres[:, 1:]) / 2
            which = [np.searchsorted(edges, values) for edges, values in zip(between, columns)]
            return np.array([np.bincount(rows, minlength=n_bins) for rows in which])
        counts = [binned_mass(values, 1.0, low, high, n_bins) for values, (low, high) in zip(columns, self.bounds)]
        return np.rint(counts).astype(int)

    def plot_identifiability(self, name, ax=None, true_value=None, per_sample=False, true_label="true value"):
        """Confidence band over time with the CLD gradient in grey (darker = larger), its scale in a colour bar.

        The thesis's parameter identifiability plot (Figures 2.9, 3.4, ...).
        ``true_value`` draws a dashed line, labelled ``true_label`` (say
        "calibrated" for a value that is no truth). A marker shows the
        estimate at the reported window (:meth:`summary`'s ``estimate`` at
        ``time_of_max_ic``). Windows whose IC ranks noise
        (below the noise floor or with the behavioural set tied, never
        informative: :meth:`informative_windows`) are veiled in grey: their
        band and gradient rank noise. Returns the matplotlib Axes. A long
        record is drawn through :mod:`dynia.decimation` (each time bucket's
        largest gradient and the envelope of the limits), so its memory does
        not grow with it.

        With ``per_sample=True`` each bin's gradient is divided by the share
        of the samples in that bin (:meth:`bin_counts`), so that a bin that
        holds more samples by chance does not look darker: the grey is then
        likelihood mass per sample, relative to an even spread (1 where a
        bin's share of the mass equals its share of the samples). Bins
        without samples stay white.

        Examples
        --------
        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import numpy as np
        >>> res = DyniaResult(names=("K",), samples=np.array([[0.1], [0.2], [0.9]]), bounds=np.array([[0.0, 1.0]]),
        ...                   time=np.arange(3.0), ic=np.zeros((1, 3)), ci=np.zeros((1, 3, 2)),
        ...                   gradient=np.ones((1, 2, 3)), bin_centres=np.array([[0.25, 0.75]]))
        >>> ax = res.plot_identifiability("K", per_sample=True)
        >>> ax.collections[0].get_array().reshape(2, 3)[:, 0].tolist()  # mass 1 in each bin, 2/3 and 1/3 of the samples
        [1.5, 3.0]
        """
        import matplotlib.pyplot as plt

        p = self.index(name)
        ax = ax if ax is not None else plt.figure().add_subplot()
        axis = self._plot_axis(ax)
        # Thinned first (a gradient on disk is read a block at a time): dividing a row by its positive share
        # commutes with a bucket's maximum, bit for bit, since rounding is monotonic.
        columns_time, columns = decimated_columns(axis, self.gradient[p])
        if per_sample:
            counts = self.bin_counts()[p]
            share = counts / counts.sum()
            with np.errstate(divide="ignore", invalid="ignore"):
                columns = np.where(counts[:, None] > 0, columns / share[:, None], 0.0)
        mesh = ax.pcolormesh(
            columns_time, self.bin_centres[p], columns, cmap="Greys", shading="nearest", vmin=0, rasterized=True
        )
        ax.plot(*envelope(axis, self.ci[p, :, 0]), color="tab:blue", linewidth=1, label="lower limit")
        ax.plot(*envelope(axis, self.ci[p, :, 1]), color="tab:red", linewidth=1, label="upper limit")
        if true_value is not None:
            ax.axhline(true_value, color="k", linestyle="--", linewidth=1, label=true_label)
        reported = self._reported(p)
        if reported is not None:
            step = reported[0]
            estimate = self._estimate(p, step)
            ax.plot(
                axis[step], estimate, "D", color="tab:orange", markeredgecolor="k", label=f"estimate {estimate:.4g}"
            )
        self._veil_uninformative(ax, axis, p)
        low, high = self.bounds[p]
        ax.set_ylim(min(low, self.bin_centres[p].min()), max(high, self.bin_centres[p].max()))
        ax.set_xlim(axis[0], axis[-1])
        ax.set_xlabel("time")
        ax.set_ylabel(name)
        shading = "CLD gradient per sample" if per_sample else "CLD gradient"
        ax.set_title(f"Uncertainty band and {shading} of {name}")
        ax.legend(loc="upper right", fontsize="small")
        ax.figure.colorbar(mesh, ax=ax, label=shading, pad=0.01)
        return ax

    def _reported(self, p):
        """The reported step of parameter ``p`` (:func:`dynia.verdicts.reported_step`) and its verdict; None
        without IC, or for a result built without settings (which windows are whole is then unknown)."""
        # verdicts reads results: imported here to keep the modules acyclic
        from .verdicts import assess, reported_step

        if self.settings is None:
            return None
        step = reported_step(self, p)
        if step is None:
            return None
        verdicts = self.verdicts if self.verdicts is not None else assess(self)
        return step, verdicts[self.names[p]]["verdict"]

    def _veil_uninformative(self, ax, axis, p):
        """A translucent grey band over each run of windows whose IC of parameter ``p`` ranks noise.

        Those are the windows with an IC that :meth:`informative_windows` never
        calls informative, whatever the threshold: below the noise floor, or
        with the behavioural set tied within noise. One collection however
        many runs, so a long record's plot stays small.
        """
        with np.errstate(invalid="ignore"):
            noise = ~self.informative_windows(0.0, self.names[p])[0] & ~np.isnan(self.ic[p])
        if not noise.any():
            return
        below = np.concatenate(([False], noise, [False]))
        starts = np.flatnonzero(below[1:] & ~below[:-1])
        stops = np.flatnonzero(~below[1:] & below[:-1])
        # A step reaches halfway to its neighbours; the record's first and last steps end at themselves.
        middles = np.concatenate(([axis[0]], (axis[:-1] + axis[1:]) / 2, [axis[-1]]))
        left, right = middles[starts], middles[stops]
        ax.broken_barh(
            list(zip(left, right - left)),
            (0, 1),
            transform=ax.get_xaxis_transform(),
            facecolor="0.75",
            alpha=0.5,
            linewidth=0,
            zorder=1.5,
            label="IC ranks noise (below the noise floor or tied)",
        )

    def _plot_axis(self, ax):
        """The x values of the plots: ``time``, or with timestamps matplotlib's date numbers on a date axis.

        Date numbers are floats, so the decimation of :mod:`dynia.decimation` works on them as on seconds.
        """
        if self.timestamps is None:
            return self.time
        from matplotlib import dates

        date_axis(ax)
        return dates.date2num(self.timestamps)

    def to_xarray(self):
        """The result as an :class:`xarray.Dataset`, laid out as :mod:`dynia.io.layout` describes.

        Examples
        --------
        >>> import numpy as np
        >>> res = DyniaResult(names=("K", "T"), samples=np.zeros((5, 2)), bounds=np.array([[0.0, 1.0], [0.0, 2.0]]),
        ...                   time=np.arange(3.0), ic=np.zeros((2, 3)), ci=np.zeros((2, 3, 2)),
        ...                   gradient=np.zeros((2, 4, 3)), bin_centres=np.zeros((2, 4)))
        >>> ds = res.to_xarray()
        >>> dict(ds.sizes), ds.ci.dims, ds.parameter.values.tolist()
        ({'parameter': 2, 'time': 3, 'side': 2, 'bin': 4, 'sample': 5}, ('parameter', 'time', 'side'), ['K', 'T'])
        """
        from .io.writer import to_xarray

        return to_xarray(self)

    def save(self, path):
        """Write the result to the netCDF-4 file ``path``; ``dynia.load(path)`` gives it back exactly.

        See :func:`dynia.io.writer.save` for what is written and what it raises.
        """
        from .io.writer import save

        save(self, path)


# Seconds and dates may disagree by this share of the record's span (plus a microsecond): a logged record's times
# count as uniform within 1e-6 of a step (dynia.io.csv), which adds up over the record.
_DATES_TOLERANCE = 1e-5


def timestamps_problem(time, timestamps):
    """What keeps ``timestamps`` from dating the steps at ``time`` seconds, or None when they can.

    The dates must be as many as the steps, known (no NaT), strictly rising
    and as far from the first as ``time`` says, within 1e-5 of the record's
    span and a microsecond.

    Examples
    --------
    >>> start = np.datetime64("2024-01-01T00:00", "ns")
    >>> timestamps_problem(np.array([0.0, 60.0, 120.0]), start + np.array([0, 60, 120]) * np.timedelta64(1, "s"))
    >>> timestamps_problem(np.array([0.0, 60.0, 120.0]), start + np.array([0, 60, 60]) * np.timedelta64(1, "s"))
    'do not rise at step 2 (2024-01-01T00:01:00.000000000 then 2024-01-01T00:01:00.000000000)'
    >>> timestamps_problem(np.array([0.0, 60.0, 120.0]), start + np.array([0, 1, 2]) * np.timedelta64(1, "s"))
    'put step 1 at 1 s from the first, where time says 60 s'
    """
    stamps = np.asarray(timestamps)
    time = np.asarray(time, dtype=float)
    if stamps.dtype != np.dtype("datetime64[ns]"):
        return f"must be datetime64[ns]; got {stamps.dtype}"
    if stamps.shape != time.shape:
        return f"hold {stamps.shape[0] if stamps.ndim else 0} dates for {time.size} steps"
    if np.isnat(stamps).any():
        return f"hold a missing date (NaT) at step {int(np.flatnonzero(np.isnat(stamps))[0])}"
    nanoseconds = stamps.view(np.int64)
    falling = np.flatnonzero(np.diff(nanoseconds) <= 0)
    if falling.size:
        step = int(falling[0]) + 1
        return f"do not rise at step {step} ({stamps[step - 1]} then {stamps[step]})"
    if not stamps.size:
        return None
    dated = (nanoseconds - nanoseconds[0]) / 1e9
    counted = time - time[0]
    tolerance = _DATES_TOLERANCE * max(abs(dated[-1]), abs(counted[-1])) + 1e-6
    off = np.flatnonzero(~(np.abs(dated - counted) <= tolerance))
    if off.size:
        step = int(off[0])
        return f"put step {step} at {dated[step]:g} s from the first, where time says {counted[step]:g} s"
    return None


def date_axis(ax):
    """Make ``ax``'s x axis a date axis with concise ticks: the date once at the axis' end, the times at the ticks.

    The x values are matplotlib's date numbers. Every dated plot of dynia, the result's and the command line's,
    has this axis.
    """
    from matplotlib import dates

    ax.xaxis_date()
    locator = dates.AutoDateLocator()
    ax.xaxis.set_major_locator(locator)
    ax.xaxis.set_major_formatter(dates.ConciseDateFormatter(locator))
