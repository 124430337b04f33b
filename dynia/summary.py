"""The summary of a result as a table: one row per parameter, as ``dynia analyse`` prints it, with the lines under it.

:meth:`dynia.result.DyniaResult.summary` returns a :class:`Summary`: the
dict it always was (``summary["K"]["verdict"]``), which shows itself as the
command's table (``print``, a notebook's HTML) and becomes a pandas frame
(:meth:`Summary.to_frame`). :func:`verdict_table` is what the command
prints, from the summary it writes to ``summary.json``.

Examples
--------
>>> import numpy as np, dynia
>>> u = np.r_[np.zeros(20), np.full(60, 1.0)]
>>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
>>> summary = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n=5, rng=1).summary()
>>> summary["K"]["verdict"], list(summary.to_frame().columns[:3])
('identified', ['max IC', 'at', 'band'])
>>> print(summary)  # doctest: +ELLIPSIS
parameter  max IC  at...verdict
K          0.910...identified
T...
"""

import html

import numpy as np

__all__ = [
    "Summary",
    "verdict_table",
    "aligned",
]


class Summary(dict):
    """A result's summary, ``{parameter: entry}`` (see :meth:`~dynia.result.DyniaResult.summary`), shown as a table."""

    def table(self):
        """The table and the lines under it, as ``dynia analyse`` prints them."""
        return verdict_table(self)

    def __repr__(self):
        return self.table()

    def _repr_html_(self):
        header, rows, notes = verdict_parts(self)
        cells = ["<table>", "<tr>" + "".join(f"<th>{html.escape(cell)}</th>" for cell in header) + "</tr>"]
        cells += ["<tr>" + "".join(f"<td>{html.escape(cell)}</td>" for cell in row) + "</tr>" for row in rows]
        cells.append("</table>")
        if notes:
            cells += ["<ul>", *(f"<li>{html.escape(line.strip())}</li>" for line in notes), "</ul>"]
        return "\n".join(cells)

    def to_frame(self):
        """The table as a pandas DataFrame, one row per parameter (indexed by name), its cells as printed."""
        import pandas as pd

        header, rows, _ = verdict_parts(self)
        return pd.DataFrame(
            [row[1:] for row in rows],
            index=pd.Index([row[0] for row in rows], name=header[0]),
            columns=list(header[1:]),
        )


NO_EVIDENCE = {
    "low_ic": "IC below the threshold",
    "record_edge": "truncated by the record's edge",
    "below_noise_floor": "below the noise floor",
    "noise_ranked": "its behavioural set tied within noise",
    "screened": "screened out for saturated, frozen or quantised readings",
}


def verdict_table(parameters):
    """The lines ``dynia analyse`` prints per parameter: max IC, where, band, estimate, record fit, evidence, verdict.

    The evidence is the number of windows with IC >= 0.5 above the noise
    floor and the times of the first and the last of them ("from", "to").
    ``parameters`` is ``summary["parameters"]`` of :func:`dynia.cli.report.write_analysis`, or a result's
    :meth:`~dynia.result.DyniaResult.summary`.
    """
    header, rows, notes = verdict_parts(parameters)
    return "\n".join(aligned(header, rows) + notes)


def verdict_parts(parameters):
    """The cells of :func:`verdict_table`: its header, its rows and the lines under it, as printed."""
    _time_text = _time_format(parameters)
    header = ("parameter", "max IC", "at", "band", "estimate", "record fit", "IC>=0.5", "from", "to", "verdict")
    rows = []
    for name, entry in parameters.items():
        first, last = entry["high_ic_span"]
        record = _record_fit_cell(entry)
        windows = (
            str(entry["high_ic_windows"]),
            _time_text(first),
            _time_text(last),
        )
        if entry["max_ic"] is None:
            rows.append((name, "-", "-", "-", "-", record, *windows, entry["verdict"]))
            continue
        low, high = entry["band"]
        se = entry.get("max_ic_se")
        rows.append(
            (
                name,
                f"{entry['max_ic']:.3f}" + ("" if se is None else f" +- {se:.3f}"),
                _time_text(entry["time_of_max_ic"]),
                f"[{low:.4g}, {high:.4g}]",
                f"{entry['estimate']:.4g}",
                record,
                *windows,
                entry["verdict"],
            )
        )
    notes = []
    for name, entry in parameters.items():
        if entry.get("highest_ic") is not None and entry["time_of_highest_ic"] != entry["time_of_max_ic"]:
            why = [NO_EVIDENCE.get(code, code) for code in entry.get("highest_ic_no_evidence", ())]
            when = _time_text(entry["time_of_highest_ic"])
            notes.append(
                f"  {name}: the record's highest IC, {entry['highest_ic']:.3f} at {when}, is "
                f"in a window that is no evidence ({' and '.join(why) or 'not evidence'}); shown: the highest IC among "
                "the windows that are"
            )
        for reason in entry["reasons"]:
            notes.append(f"  {name} {entry['verdict']}: {reason['text']}")
    return header, rows, notes


def _record_fit_cell(entry):
    """The table's "record fit": the whole record's least-squares value +- its standard error, "-" without one."""
    value, error = entry.get("record_fit"), entry.get("record_fit_se")
    if value is None or not np.isfinite(value):
        return "-"
    return f"{value:.4g} +- " + ("inf" if error is None or not np.isfinite(error) else f"{error:.2g}")


def aligned(header, rows):
    """The header and rows as lines of left-aligned columns two spaces apart."""
    widths = [max(len(row[column]) for row in [*rows, header]) for column in range(len(header))]
    return ["  ".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip() for row in [header, *rows]]


def _time_format(parameters):
    """How the table writes the summary's times: seconds as the command prints them (``1580.0``); dates as days when
    every date shown is a midnight (a daily record), else to the second; the command's own texts as they are."""
    dates = [
        value
        for entry in parameters.values()
        for value in (entry.get("time_of_max_ic"), entry.get("time_of_highest_ic"), *entry.get("high_ic_span", ()))
        if isinstance(value, np.datetime64)
    ]
    daily = bool(dates) and not any(np.datetime64(value, "ns").astype(np.int64) % (86_400 * 10**9) for value in dates)

    def text(value):
        if value is None:
            return "-"
        if isinstance(value, np.datetime64):
            return str(np.datetime_as_string(value, unit="D" if daily else "s"))
        return str(value)

    return text
