"""The result of a DYNIA run: arrays, tables and the thesis's two figure types.

Shapes follow the package convention (see :mod:`dynia.engine`):
``ic`` (n_params, n_steps), ``ci`` (n_params, n_steps, 2) as [lower, upper],
``median`` (n_params, n_steps),
``gradient`` (n_params, n_bins, n_steps), ``bin_centres`` (n_params, n_bins),
``samples`` (n_samples, n_params), ``bounds`` (n_params, 2); the optional
Monte Carlo errors ``ic_se`` (n_params, n_steps) and ``ci_se`` (n_params,
n_steps, 2).
"""

from dataclasses import dataclass, field

import numpy as np

from .decimation import decimated_columns, envelope
from .engine.cld import binned_mass
from .errors import SettingsError

__all__ = ["DyniaResult"]


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
    settings : dict
        Every option of the run.
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
        present, :meth:`to_dataframe` and :meth:`to_xarray` carry it and the
        plots draw against it. None otherwise.
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
        (``settings["noise_floor_quantile"]``) minus the best MAE.
    noise_floor : ndarray (n_steps,) or None
        What noise alone keeps the discrimination below
        (``settings["noise_multiple"]`` sampling standard deviations of the
        MAE of the window's points of noise ``settings["noise_sigma"]``).
    behavioural_spread : ndarray (n_steps,) or None
        The behavioural set's largest MAE minus the best: whether the band
        itself is a ranking of noise (verdict reason ``noise_ranked``).
    behavioural_floor : ndarray (n_steps,) or None
        What noise alone keeps the behavioural spread below
        (``settings["behavioural_multiple"]`` of the same standard deviations).
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
    settings: dict = field(default_factory=dict)
    verdicts: dict | None = None
    timestamps: np.ndarray | None = None
    ic_se: np.ndarray | None = None
    ci_se: np.ndarray | None = None
    informative: np.ndarray | None = None
    discrimination: np.ndarray | None = None
    noise_floor: np.ndarray | None = None
    behavioural_spread: np.ndarray | None = None
    behavioural_floor: np.ndarray | None = None
    median: np.ndarray | None = None

    def index(self, name):
        """Position of parameter ``name`` on the parameter axis."""
        try:
            return self.names.index(name)
        except ValueError:
            raise SettingsError(f"unknown parameter {name!r}; this result has {list(self.names)}") from None

    @property
    def window_halos(self):
        """Steps (before, after) the window at step t reaches: (n, n) centred, (2n, 0) trailing.

        Read from ``settings["n"]`` and ``settings["window"]`` (default
        "centred"); a result built without them has no known geometry.
        """
        if "n" not in self.settings:
            raise SettingsError(
                "this result's settings have no half window 'n', so which samples each window used is unknown"
            )
        n = int(self.settings["n"])
        window = self.settings.get("window", "centred")
        if window not in ("centred", "trailing"):
            raise SettingsError(f"result.settings['window'] must be 'centred' or 'trailing'; got {window!r}")
        return (n, n) if window == "centred" else (2 * n, 0)

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
        highest IC among the windows that can be evidence (whole, above the
        noise floor, behavioural set untied) when one reaches 0.5, else the
        one of highest IC of all (:func:`dynia.verdicts.reported_step`);
        ``highest_ic`` and ``time_of_highest_ic`` are the record's highest
        IC wherever it lies. The estimate is the CLD median (:attr:`median`)
        at the reported window, so it always lies in the band there; a result without
        the median (a file saved before it existed) reports the band's
        midpoint instead. The verdict ("identified", "weak" or
        "suspect") and its reasons say what that estimate is worth (see
        :mod:`dynia.verdicts`). Parameters whose IC is missing everywhere get
        None for the numbers.

        ``high_ic_windows`` counts the windows whose IC reaches the verdicts'
        0.5 above the noise floor (:func:`dynia.verdicts.high_ic_windows`),
        the evidence whose agreement the verdict checks, and
        ``high_ic_span`` gives the time of the first and of the last of
        them ([None, None] when there is none).

        Returns
        -------
        dict
            ``{name: {"max_ic", "time_of_max_ic", "band": [lower, upper], "estimate", "highest_ic",
            "time_of_highest_ic", "high_ic_windows", "high_ic_span": [first, last], "verdict", "reasons"}}``
            with plain Python values; with the Monte Carlo errors also
            ``"max_ic_se"``, the standard error of the max IC.
        """
        # verdicts reads results: imported here to keep the modules acyclic
        from .verdicts import assess, high_ic_windows, reported_step

        verdicts = self.verdicts if self.verdicts is not None else assess(self)
        summary = {}
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
                    time_of_max_ic=float(self.time[best]),
                    band=[float(self.ci[p, best, 0]), float(self.ci[p, best, 1])],
                    estimate=self._estimate(p, best),
                    highest_ic=float(self.ic[p, highest]),
                    time_of_highest_ic=float(self.time[highest]),
                )
                if self.ic_se is not None:
                    summary[name]["max_ic_se"] = float(self.ic_se[p, best])
            steps = np.flatnonzero(high_ic_windows(self, p))
            summary[name].update(
                high_ic_windows=int(steps.size),
                high_ic_span=[float(self.time[steps[0]]), float(self.time[steps[-1]])] if steps.size else [None, None],
            )
            summary[name].update(verdict=verdicts[name]["verdict"], reasons=list(verdicts[name]["reasons"]))
        return summary

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
        threshold, more samples could change the verdict. Windows below the noise floor (:attr:`informative` False)
        are veiled in grey. Returns the matplotlib Axes. A long record is
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
        self._veil_uninformative(ax, axis)
        if self.ic_se is not None:
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
        if self.settings.get("flavour", "thesis") not in ("thesis", "weighted"):
            between = (self.bin_centres[:, :-1] + self.bin_centres[:, 1:]) / 2
            which = [np.searchsorted(edges, values) for edges, values in zip(between, columns)]
            return np.array([np.bincount(rows, minlength=n_bins) for rows in which])
        counts = [binned_mass(values, 1.0, low, high, n_bins) for values, (low, high) in zip(columns, self.bounds)]
        return np.rint(counts).astype(int)

    def plot_identifiability(self, name, ax=None, true_value=None, per_sample=False):
        """Confidence band over time with the CLD gradient in grey (darker = larger).

        The thesis's parameter identifiability plot (Figures 2.9, 3.4, ...).
        ``true_value`` draws a dashed line. Windows below the noise floor
        (:attr:`informative` False) are veiled in grey: their band and
        gradient rank noise. Returns the matplotlib Axes. A long
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
        ax.pcolormesh(
            columns_time, self.bin_centres[p], columns, cmap="Greys", shading="nearest", vmin=0, rasterized=True
        )
        ax.plot(*envelope(axis, self.ci[p, :, 0]), color="tab:blue", linewidth=1, label="lower limit")
        ax.plot(*envelope(axis, self.ci[p, :, 1]), color="tab:red", linewidth=1, label="upper limit")
        if true_value is not None:
            ax.axhline(true_value, color="k", linestyle="--", linewidth=1, label="true value")
        self._veil_uninformative(ax, axis)
        low, high = self.bounds[p]
        ax.set_ylim(min(low, self.bin_centres[p].min()), max(high, self.bin_centres[p].max()))
        ax.set_xlim(axis[0], axis[-1])
        ax.set_xlabel("time")
        ax.set_ylabel(name)
        shading = "CLD gradient per sample" if per_sample else "CLD gradient"
        ax.set_title(f"Uncertainty band and {shading} of {name}")
        ax.legend(loc="upper right", fontsize="small")
        return ax

    def _veil_uninformative(self, ax, axis):
        """A translucent grey band over each run of windows below the noise floor, from edge to edge of its steps.

        One collection however many runs, so a long record's plot stays small.
        """
        if self.informative is None or np.all(self.informative):
            return
        below = np.concatenate(([False], ~np.asarray(self.informative, dtype=bool), [False]))
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
            label="below the noise floor",
        )

    def _plot_axis(self, ax):
        """The x values of the plots: ``time``, or with timestamps matplotlib's date numbers on a date axis.

        Date numbers are floats, so the decimation of :mod:`dynia.decimation` works on them as on seconds.
        """
        if self.timestamps is None:
            return self.time
        from matplotlib import dates

        ax.xaxis_date()
        return dates.date2num(self.timestamps)

    def to_xarray(self):
        """The result as an :class:`xarray.Dataset`, laid out as :mod:`dynia.io.netcdf` describes.

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

        See :func:`dynia.io.netcdf.save` for what is written and what it raises.
        """
        from .io.writer import save

        save(self, path)
