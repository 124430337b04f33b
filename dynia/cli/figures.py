"""The command line's figures: the data analysed, each parameter's IC and identifiability, and the fit.

The figures speak the user's terms (:class:`Labels`): each input and the output
under its column's name, with the units and reference lines given on the
command line, and a dated record on a date axis. The output is drawn as
measured in every figure; where the analysis removed an offset, the fitted
model is drawn with it added back.

Every line goes through :func:`dynia.decimation.envelope`, so a figure's memory
does not grow with the length of the record. matplotlib loads on the first
figure, with the Agg backend: the command line writes files and never opens a window.
"""

import dataclasses
import datetime
import textwrap

import numpy as np

from ..decimation import envelope
from ..result import date_axis

__all__ = ["Labels", "plot_data", "plot_inputs", "time_axis", "write_figures", "write_fit_figure"]

_NUMERIC_TIME = "time (s from the first grid point)"


@dataclasses.dataclass(frozen=True)
class Labels:
    """What the figures call the signals and parameters, and the reference lines they draw.

    Attributes
    ----------
    inputs : tuple of str
        The input columns' names, in the model's input order.
    output : str
        The output column's name.
    units : dict
        ``{name: unit}`` of parameters and columns, shown in the axis labels.
    references : dict
        ``{name: (value, label)}``: a horizontal line at ``value`` on the plots
        of the parameter or column ``name``.

    Examples
    --------
    >>> Labels(inputs=("rain", "PET"), output="q", units={"q": "mm/d"}).of("q")
    'q [mm/d]'
    """

    inputs: tuple = ("input",)
    output: str = "output"
    units: dict = dataclasses.field(default_factory=dict)
    references: dict = dataclasses.field(default_factory=dict)

    @classmethod
    def unnamed(cls, n_inputs):
        """Labels for data whose columns are not known by name: "input" (or "input 1", ...) and "output"."""
        return cls(inputs=("input",) if n_inputs == 1 else tuple(f"input {k + 1}" for k in range(n_inputs)))

    def of(self, name):
        """``name`` with its unit, as an axis label shows it."""
        unit = self.units.get(name)
        return name if unit is None else f"{name} [{unit}]"


def time_axis(data):
    """The x values of the record's steps, whether they are dates, and the axis label.

    A dated record (ISO timestamps in the file) gives matplotlib date numbers of
    the file's own clock (its UTC offset, if any, named in the label); a numeric
    one gives seconds from the first grid point, the result's own clock.
    """
    if not isinstance(data.start, datetime.datetime):
        return data.time - data.time[0], False, _NUMERIC_TIME
    from matplotlib import dates

    zone = data.start.utcoffset()
    # The wall clock of the file, as its tables write it, not UTC: a date number is days.
    x = dates.date2num(data.start.replace(tzinfo=None)) + np.asarray(data.time, dtype=float) / 86_400.0
    label = "time" if zone is None else f"time (UTC{_utc_offset(zone)})"
    return x, True, label


def _utc_offset(zone):
    minutes = round(zone.total_seconds() / 60)
    sign = "-" if minutes < 0 else "+"
    return f"{sign}{abs(minutes) // 60:02d}:{abs(minutes) % 60:02d}"


def plot_data(time, u, y, *, offset=0.0, input_offset=0.0, xlabel="time", labels=None, dated=False):
    """The record's inputs (one panel each, top) and output (bottom) over time, thinned by
    :func:`~dynia.decimation.envelope`.

    Parameters
    ----------
    time, u, y : array_like
        Time (n_steps,), input (n_steps,) or (n_steps, n_inputs) and output (n_steps,), as measured;
        NaN in ``y`` marks a missing measurement.
    offset : float, default 0.0
        The output offset the analysis removed; when not 0 the output's
        axis label says that it is drawn as measured.
    input_offset : float or array_like (n_inputs,), default 0.0
        The input offsets the analysis removed, said the same way on each
        input's axis: every signal is drawn as measured.
    xlabel : str, default "time"
        Label of the shared time axis.
    labels : Labels, optional
        The columns' names, units and reference lines; by default "input" and "output".
    dated : bool, default False
        Whether ``time`` holds matplotlib date numbers (see :func:`time_axis`).

    Returns
    -------
    matplotlib.figure.Figure
        A pyplot figure of one axis per input and one for the output, sharing
        the time axis; close it with ``matplotlib.pyplot.close(fig)`` when written.

    Examples
    --------
    >>> import numpy as np, matplotlib
    >>> matplotlib.use("Agg")
    >>> fig = plot_data(np.arange(10_000.0), np.ones(10_000), np.arange(10_000.0))
    >>> [ax.lines[0].get_xdata().size for ax in fig.axes]
    [4000, 4000]
    """
    import matplotlib.pyplot as plt

    u = np.asarray(u, dtype=float)
    labels = labels if labels is not None else Labels.unnamed(u.reshape(u.shape[0], -1).shape[1])
    n_inputs = len(labels.inputs)
    fig, axes = plt.subplots(n_inputs + 1, 1, sharex=True, figsize=(9, 2 + 1.6 * (n_inputs + 1)), squeeze=False)
    axes = axes[:, 0]
    plot_inputs(axes[:n_inputs], time, u, labels, input_offset)
    axes[-1].plot(*envelope(time, y), color="tab:orange")
    _label_output(axes[-1], labels, offset)
    _finish_time_axis(axes[-1], xlabel, dated)
    axes[0].set_title("Data analysed")
    return fig


def plot_inputs(axes, time, u, labels, input_offset=0.0):
    """Draw each input column, as measured, in its own axis of ``axes``, thinned, with its name, unit, the offset
    the analysis removed from it (``input_offset``, one or one per input) and its reference line."""
    u = np.asarray(u, dtype=float)
    columns = u.reshape(u.shape[0], -1).T
    offsets = np.broadcast_to(np.asarray(input_offset, dtype=float), (columns.shape[0],))
    for ax, name, column, offset in zip(axes, labels.inputs, columns, offsets):
        ax.plot(*envelope(time, column), color="tab:blue")
        ax.set_ylabel(_as_measured(labels.of(name), offset))
        _reference(ax, name, labels)


def _label_output(ax, labels, offset):
    """The output axis' label and reference line, once the caller has drawn the output as measured."""
    ax.set_ylabel(_as_measured(labels.of(labels.output), offset))
    _reference(ax, labels.output, labels)


def _as_measured(label, offset):
    # The analysis saw the signal minus its offset; the figures show what the file holds, and say so.
    return label + (f"\nas measured (offset {offset:g})" if offset else "")


def _reference(ax, name, labels):
    if name in labels.references:
        value, text = labels.references[name]
        ax.axhline(value, color="tab:purple", linestyle="--", linewidth=1, label=f"{text} {value:g}")
        ax.legend(loc="best", fontsize=8)


def _finish_time_axis(ax, xlabel, dated):
    ax.set_xlabel(xlabel)
    if dated:
        date_axis(ax)


def _figure_module():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def write_figures(directory, result, data, offset, labels=None, input_offset=0.0):
    """data.png, ic_NAME.png and identifiability_NAME.png of an analysis in ``directory``.

    ``labels`` (:class:`Labels`) names the columns and gives the units and
    references; a dated record (``data.start`` a datetime) is drawn on a date axis.
    """
    plt = _figure_module()
    labels = labels if labels is not None else Labels.unnamed(data.u.reshape(data.u.shape[0], -1).shape[1])
    x, dated, xlabel = time_axis(data)
    fig = plot_data(
        x, data.u, data.y, offset=offset, input_offset=input_offset, xlabel=xlabel, labels=labels, dated=dated
    )
    fig.savefig(directory / "data.png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    if dated:
        # The result of arrays knows no dates; the plots draw against its timestamps when it has them.
        start = np.datetime64(data.start.replace(tzinfo=None), "ns")
        result = dataclasses.replace(
            result, timestamps=start + np.round(np.asarray(data.time) * 1e9).astype("timedelta64[ns]")
        )
    for name in result.names:
        reference = labels.references.get(name)
        fig, ax = plt.subplots(figsize=(9, 3.5))
        result.plot_information_content(name, ax=ax)
        _finish_time_axis(ax, xlabel, dated)
        fig.savefig(directory / f"ic_{name}.png", dpi=110, bbox_inches="tight")
        plt.close(fig)
        fig, ax = plt.subplots(figsize=(9, 3.5))
        if reference is None:
            result.plot_identifiability(name, ax=ax)
        else:
            result.plot_identifiability(
                name, ax=ax, true_value=reference[0], true_label=f"{reference[1]} {reference[0]:g}"
            )
        ax.set_ylabel(labels.of(name))
        _finish_time_axis(ax, xlabel, dated)
        fig.savefig(directory / f"identifiability_{name}.png", dpi=110, bbox_inches="tight")
        plt.close(fig)


def write_fit_figure(path, found, data, u, y, offset, labels=None):
    """fit.png of ``dynia identify``: one panel per input, and the output as measured with the fitted model.

    ``u`` and ``y`` are the input and output as analysed (offsets removed):
    the model is simulated on ``u`` and drawn, like ``y``, with the output
    offset added back; the inputs are drawn as measured, their offsets
    (``data.u - u``) named on their axes.
    """
    plt = _figure_module()
    labels = labels if labels is not None else Labels.unnamed(data.u.reshape(data.u.shape[0], -1).shape[1])
    x, dated, xlabel = time_axis(data)
    n_inputs = len(labels.inputs)
    fig, axes = plt.subplots(n_inputs + 1, 1, sharex=True, figsize=(9, 2 + 1.6 * (n_inputs + 1)), squeeze=False)
    axes = axes[:, 0]
    bottom = axes[-1]
    plot_inputs(axes[:n_inputs], x, data.u, labels, (np.asarray(data.u) - u)[0])
    bottom.plot(*envelope(x, y + offset), color="tab:orange", label="measured")
    fitted = found.fit.simulate(u) + offset
    bottom.plot(*envelope(x, fitted), color="k", linewidth=1, label="fitted model" + (" + offset" if offset else ""))
    _label_output(bottom, labels, offset)
    for number, (start, stop) in enumerate(found.segments):
        for ax in axes:
            ax.axvspan(
                x[start],
                x[stop - 1],
                color="tab:green",
                alpha=0.15,
                label="fitted on" if number == 0 and ax is bottom else None,
            )
    start, _ = found.validation[0]
    bottom.axvspan(x[start], x[-1], color="0.5", alpha=0.15, label="held out")
    # The robust errors: residuals of process data are rarely independent.
    robust = getattr(found.fit, "std_errors_hac", None) or found.std_errors
    estimates = ", ".join(
        f"{name} = {value:.4g} \u00b1 {robust[name]:.2g}" + (f" {labels.units[name]}" if name in labels.units else "")
        for name, value in found.parameters.items()
    )
    title = f"{found.method}: {estimates}; validation RMSE {found.validation_error:.3g}"
    little_data = getattr(found, "little_data", None)
    if little_data:
        # Under the estimates it doubts, so that the figure never shows them without it.
        title += "\n" + textwrap.fill("warning: " + little_data.split(": the estimates")[0], 110)
    axes[0].set_title(title, color="k" if not little_data else "tab:red", fontsize=None if not little_data else 9)
    _finish_time_axis(bottom, xlabel, dated)
    bottom.legend(loc="best", fontsize=8)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
