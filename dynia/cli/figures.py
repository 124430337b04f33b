"""The command line's figures: the data analysed, each parameter's IC and identifiability, and the fit.

Every line goes through :func:`dynia.decimation.envelope`, so a figure's memory
does not grow with the length of the record. matplotlib loads on the first
figure, with the Agg backend: the command line writes files and never opens a window.
"""

import numpy as np

from ..decimation import envelope

__all__ = ["plot_data", "plot_inputs", "write_figures", "write_fit_figure"]


def plot_data(time, u, y, *, offset=0.0, xlabel="time"):
    """The record's input (top) and output (bottom) over time, thinned by :func:`~dynia.decimation.envelope`.

    Parameters
    ----------
    time, u, y : array_like, shape (n_steps,)
        Time, input and output; NaN in ``y`` marks a missing measurement.
    offset : float, default 0.0
        The output offset the analysis removed; when not 0 the output's
        axis label says so.
    xlabel : str, default "time"
        Label of the shared time axis.

    Returns
    -------
    matplotlib.figure.Figure
        A pyplot figure of two axes sharing the time axis; close it with
        ``matplotlib.pyplot.close(fig)`` when written.

    Examples
    --------
    >>> import numpy as np, matplotlib
    >>> matplotlib.use("Agg")
    >>> fig = plot_data(np.arange(10_000.0), np.ones(10_000), np.arange(10_000.0))
    >>> [ax.lines[0].get_xdata().size for ax in fig.axes]
    [4000, 4000]
    """
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(9, 5))
    plot_inputs(top, time, u)
    bottom.plot(*envelope(time, y), color="tab:orange")
    bottom.set_ylabel("output" + (f" (offset {offset:g} removed in the analysis)" if offset else ""))
    bottom.set_xlabel(xlabel)
    top.set_title("Data analysed")
    return fig


def plot_inputs(ax, time, u):
    """Draw the input, (n_steps,) or one line per column of (n_steps, n_inputs), thinned.

    Each line is thinned by :func:`~dynia.decimation.envelope`.
    """
    u = np.asarray(u, dtype=float)
    columns = u.reshape(u.shape[0], -1).T
    for number, column in enumerate(columns):
        label = f"input {number + 1}" if len(columns) > 1 else None
        ax.plot(*envelope(time, column), color=None if len(columns) > 1 else "tab:blue", label=label)
    ax.set_ylabel("input" if len(columns) == 1 else "inputs")
    if len(columns) > 1:
        ax.legend(loc="best", fontsize=8)


def _figure_module():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def write_figures(directory, result, data, offset):
    plt = _figure_module()
    grid_time = data.time - data.time[0]  # the clock of the result's plots
    fig = plot_data(grid_time, data.u, data.y, offset=offset, xlabel="time (s from the first grid point)")
    fig.savefig(directory / "data.png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    for name in result.names:
        for kind, plot in (("ic", result.plot_information_content), ("identifiability", result.plot_identifiability)):
            fig, ax = plt.subplots(figsize=(9, 3.5))
            plot(name, ax=ax)
            ax.set_xlabel("time (s from the first grid point)")
            fig.savefig(directory / f"{kind}_{name}.png", dpi=110, bbox_inches="tight")
            plt.close(fig)


def write_fit_figure(path, found, data, u, y, offset):
    plt = _figure_module()
    grid_time = data.time - data.time[0]
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(9, 5))
    plot_inputs(top, grid_time, data.u)
    bottom.plot(*envelope(grid_time, y), color="tab:orange", label="measured")
    bottom.plot(*envelope(grid_time, found.fit.simulate(u)), color="k", linewidth=1, label="fitted model")
    for number, (start, stop) in enumerate(found.segments):
        for ax in (top, bottom):
            ax.axvspan(
                grid_time[start],
                grid_time[stop - 1],
                color="tab:green",
                alpha=0.15,
                label="fitted on" if number == 0 and ax is bottom else None,
            )
    start, _ = found.validation[0]
    bottom.axvspan(grid_time[start], grid_time[-1], color="0.5", alpha=0.15, label="held out")
    # The robust errors: residuals of process data are rarely independent.
    robust = getattr(found.fit, "std_errors_hac", None) or found.std_errors
    estimates = ", ".join(f"{name} = {value:.4g} \u00b1 {robust[name]:.2g}" for name, value in found.parameters.items())
    top.set_title(f"{found.method}: {estimates}; validation RMSE {found.validation_error:.3g}")
    bottom.set_ylabel("output" + (f" (minus {offset:g})" if offset else ""))
    bottom.set_xlabel("time (s from the first grid point)")
    bottom.legend(loc="best", fontsize=8)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
