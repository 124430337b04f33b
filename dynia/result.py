"""The result of a DYNIA run: arrays, tables and the thesis's two figure types.

Shapes follow the package convention (see :mod:`dynia.analysis`):
``ic`` (n_params, n_steps), ``ci`` (n_params, n_steps, 2) as [lower, upper],
``gradient`` (n_params, n_bins, n_steps), ``bin_centres`` (n_params, n_bins),
``samples`` (n_samples, n_params), ``bounds`` (n_params, 2).
"""
from dataclasses import dataclass, field

import numpy as np

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

    def index(self, name):
        """Position of parameter ``name`` on the parameter axis."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(f"unknown parameter {name!r}; this result has {list(self.names)}") from None

    def summary(self):
        """Per parameter: the highest IC, when it occurs, the band and the estimate there.

        The estimate is the centre of the bin with the largest CLD gradient
        at the time of the highest IC. Parameters whose IC is missing
        everywhere get None throughout.

        Returns
        -------
        dict
            ``{name: {"max_ic", "time_of_max_ic", "band": [lower, upper], "estimate"}}``
            with plain Python floats.
        """
        summary = {}
        for p, name in enumerate(self.names):
            if np.isnan(self.ic[p]).all():
                summary[name] = dict(max_ic=None, time_of_max_ic=None, band=[None, None], estimate=None)
                continue
            best = int(np.nanargmax(self.ic[p]))
            summary[name] = dict(
                max_ic=float(self.ic[p, best]),
                time_of_max_ic=float(self.time[best]),
                band=[float(self.ci[p, best, 0]), float(self.ci[p, best, 1])],
                estimate=float(self.bin_centres[p, int(np.argmax(self.gradient[p, :, best]))]),
            )
        return summary

    def to_dataframe(self):
        """Long table: one row per (time, parameter) with ic, lower and upper.

        Needs pandas (``pip install dynia[pandas]``).
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_dataframe needs pandas: pip install 'dynia[pandas]'") from None
        n_params, n_steps = self.ic.shape
        return pd.DataFrame({
            "time": np.tile(self.time, n_params),
            "parameter": np.repeat(self.names, n_steps),
            "ic": self.ic.ravel(),
            "lower": self.ci[:, :, 0].ravel(),
            "upper": self.ci[:, :, 1].ravel(),
        })

    def plot_information_content(self, name, ax=None):
        """Information content of ``name`` over time (thesis Figures 2.8, 3.3, ...).

        Returns the matplotlib Axes.
        """
        import matplotlib.pyplot as plt
        p = self.index(name)
        ax = ax if ax is not None else plt.figure().add_subplot()
        ax.plot(self.time, self.ic[p], color="k", linewidth=1)
        ax.set_ylim(0, 1)
        ax.set_xlim(self.time[0], self.time[-1])
        ax.set_xlabel("time")
        ax.set_ylabel("information content")
        ax.set_title(f"Information content of {name}")
        return ax

    def plot_identifiability(self, name, ax=None, true_value=None):
        """Confidence band over time with the CLD gradient in grey (darker = larger).

        The thesis's parameter identifiability plot (Figures 2.9, 3.4, ...).
        ``true_value`` draws a dashed line. Returns the matplotlib Axes.
        """
        import matplotlib.pyplot as plt
        p = self.index(name)
        ax = ax if ax is not None else plt.figure().add_subplot()
        ax.pcolormesh(self.time, self.bin_centres[p], self.gradient[p], cmap="Greys",
                      shading="nearest", vmin=0, rasterized=True)
        ax.plot(self.time, self.ci[p, :, 0], color="tab:blue", linewidth=1, label="lower limit")
        ax.plot(self.time, self.ci[p, :, 1], color="tab:red", linewidth=1, label="upper limit")
        if true_value is not None:
            ax.axhline(true_value, color="k", linestyle="--", linewidth=1, label="true value")
        low, high = self.bounds[p]
        ax.set_ylim(min(low, self.bin_centres[p].min()), max(high, self.bin_centres[p].max()))
        ax.set_xlim(self.time[0], self.time[-1])
        ax.set_xlabel("time")
        ax.set_ylabel(name)
        ax.set_title(f"Uncertainty band and CLD gradient of {name}")
        ax.legend(loc="upper right", fontsize="small")
        return ax
