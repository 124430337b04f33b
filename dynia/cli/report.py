"""What the command line writes: result tables, ``summary.json``, figures, ``report.html`` and the verdict table.

:func:`write_analysis` fills a result directory of ``dynia analyse``,
:func:`write_identification` one of ``dynia identify``; :func:`dynia.summary.verdict_table`
is the short table ``dynia analyse`` prints on success, :func:`identification_table`
the one ``dynia identify`` prints. Times are written as
the data file wrote them (:func:`file_times`). Figures are decimated
(:mod:`dynia.decimation`) so that their memory does not grow with the record.
Both directories get a ``report.html`` of what they hold (:mod:`dynia.cli.html_report`).
"""

import csv
import datetime
import hashlib
import json
from pathlib import Path

import numpy as np

from .. import segments
from ..io.writer import add_attributes
from ..serial import json_ready
from ..summary import aligned, verdict_parts
from .figures import write_figures, write_fit_figure
from .html_report import write_report

__all__ = [
    "write_analysis",
    "write_identification",
    "identification_table",
    "identification_parts",
    "noise_floor_summary",
    "noise_floor_line",
    "file_times",
    "sha256",
    "write_json",
]

# Rows written to a CSV per call of writerows: bounds the strings held at once.
_CSV_BLOCK = 10_000


def file_times(data, seconds):
    """Times as the data file wrote them: ISO timestamps, or numbers on the file's own origin."""
    if isinstance(data.start, datetime.datetime):
        return [(data.start + datetime.timedelta(seconds=float(value))).isoformat() for value in seconds]
    return [data.start + float(value) for value in seconds]


def sha256(path):
    """SHA-256 of a file's bytes, hex."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def write_json(path, content):
    """``content`` as indented JSON with NaN and inf as null."""
    Path(path).write_text(json.dumps(json_ready(content), indent=2, default=_plain) + "\n")


def write_analysis(
    directory, result, data, summary, *, offset=0.0, input_offset=0.0, plots=True, saved=False, labels=None
):
    """Write one analysis into ``directory``: ic.csv, limits.csv, samples.csv, summary.json, result.nc, figures, report.

    ``report.html`` holds the verdict table, the noise-floor line, the figures and the record of ``summary``.

    ``summary`` is the finished content of ``summary.json``; the per-parameter
    times in it are already the file's. ``result.nc`` is the whole result
    (:meth:`dynia.result.DyniaResult.save`), which ``dynia.load`` reads back;
    with ``saved`` the run already wrote it there (``store=``), and it is
    not written again. ``labels`` (:class:`~dynia.cli.figures.Labels`) names
    the columns in the figures and gives their units and reference lines.
    """
    directory = Path(directory)
    names = list(result.names)
    times = file_times(data, data.time)
    # np.asarray: a result stored on disk (store=) is read here, one array at a time.
    ic_columns, ic_values = ["time"], []
    for p, name in enumerate(names):
        ic_columns.append(name)
        ic_values.append(np.asarray(result.ic[p]))
        if result.ic_se is not None:
            ic_columns.append(f"{name}_se")
            ic_values.append(np.asarray(result.ic_se[p]))
    if result.informative is not None:  # the window's noise floor, the same for every parameter
        ic_columns.append("informative")
        ic_values.append(np.asarray(result.informative, dtype=int))
    _write_csv(directory / "ic.csv", ic_columns, np.column_stack(ic_values), times)
    limit_columns = [f"{name}_{side}" for name in names for side in ("lower", "upper")]
    _write_csv(
        directory / "limits.csv",
        ["time"] + limit_columns,
        np.asarray(result.ci).transpose(1, 0, 2).reshape(data.time.size, -1),
        times,
    )
    _write_csv(directory / "samples.csv", names, result.samples)
    write_json(directory / "summary.json", summary)
    if not saved:
        result.save(directory / "result.nc")
    # The units and references as summary.json records them, so that the two files cannot say different things.
    settings = summary.get("settings", {})
    recorded = {key: settings[key] for key in ("units", "references") if settings.get(key)}
    if recorded:
        add_attributes(directory / "result.nc", dict(dict(units={}, references={}), **recorded))
    if plots:
        write_figures(directory, result, data, offset, labels, input_offset)
    floor = summary.get("noise_floor")
    write_report(
        directory,
        summary,
        command="analyse",
        tables=[([], *verdict_parts(summary["parameters"]))],
        lines=[line.strip() for line in screening_lines(summary)]
        + ([] if floor is None else [noise_floor_line(floor)]),
        plots=plots,
    )


def write_identification(directory, found, data, u, y, summary, *, offset=0.0, plots=True, labels=None):
    """Write ``identified.json``, with ``plots`` ``fit.png``, and ``report.html`` into ``directory``."""
    directory = Path(directory)
    write_json(directory / "identified.json", summary)
    if plots:
        write_fit_figure(directory / "fit.png", found, data, u, y, offset, labels)
    parts = identification_parts(
        summary,
        fitted_steps=sum(stop - start for start, stop in found.segments),
        held_out_steps=sum(stop - start for start, stop in found.validation),
    )
    write_report(directory, summary, command="identify", tables=[parts], plots=plots)


def noise_floor_summary(result, data):
    """``summary.json``'s ``noise_floor``: the noise level, the multiples and where the windows are informative.

    None for a result without the floor. ``informative`` lists the runs of
    informative windows as ``[first_time, last_time]`` pairs in the file's
    times (the window centred, or ending, at each). ``autocorrelation`` is
    the lag-1 autocorrelation of the record-best fit's residuals and
    ``size_factor`` how many times fewer independent points a window's
    count as (:mod:`dynia.engine.noise`); a result saved before they were
    estimated gives None and 1.
    """
    if result.informative is None:
        return None
    mask = np.asarray(result.informative, dtype=bool)
    run = result.run
    autocorrelation = run.noise_autocorrelation
    return dict(
        sigma=run.noise_sigma,
        autocorrelation=None if autocorrelation is None or np.isnan(autocorrelation) else autocorrelation,
        size_factor=1.0 if run.noise_size_factor is None else run.noise_size_factor,
        quantile=run.noise_floor_quantile,
        multiple=run.noise_multiple,
        behavioural_multiple=run.behavioural_multiple,
        informative_share=float(mask.mean()),
        informative=[
            file_times(data, [data.time[start], data.time[stop - 1]]) for start, stop in segments.mask_to_segments(mask)
        ],
    )


def noise_floor_line(floor):
    """The line ``dynia analyse`` prints under the verdict table about the noise floor (``floor``: the summary's)."""
    autocorrelation, factor = floor.get("autocorrelation"), floor.get("size_factor", 1.0)
    if autocorrelation is None:
        noise = "white noise assumed"
    elif factor > 1:
        noise = f"lag-1 autocorrelation {autocorrelation:.2f}: a window's points count {factor:.3g} times fewer"
    else:
        noise = f"white: lag-1 autocorrelation {autocorrelation:.2f}"
    return (
        f"noise floor: {100 * floor['informative_share']:.0f} % of the windows informative (their "
        f"{floor['quantile']:g}-quantile MAE above the best by more than {floor['multiple']:.2f} standard "
        f"deviations of the MAE of noise sigma {floor['sigma']:.3g}, {noise}; estimated from the best fits)"
    )


def screening_lines(summary):
    """The lines ``dynia analyse`` prints under the verdict table about the data-quality screening.

    One per screened finding of ``summary["data_quality"]``, in the units measured, with the windows it takes
    from the evidence, and one for the total (``summary["screening"]``); none when the run was not screened.
    """
    screening = summary.get("screening")
    if not screening:
        return []
    lines = []
    for entry in summary.get("data_quality", ()):
        if not entry.get("screened"):
            continue
        value, column, kind = entry["value"], entry["column"], entry["kind"]
        if kind == "saturated":
            what = f"{column} saturated at {value:.6g} (its record {entry['limit']})"
        elif kind == "stuck":
            what = f"{column} frozen at {value:.6g}"
        else:
            what = f"{column} quantised in steps of {value:.6g} (coarser than its noise)"
        where = "" if kind == "quantised" else f" from {entry['start_time']} to {entry['end_time']}"
        lines.append(f"  data quality: {what}{where}: {entry['windows_excluded']} window(s) are no evidence")
    if lines or screening["excluded_windows"]:
        lines.append(
            f"data quality: {screening['excluded_windows']} of {screening['n_windows']} windows screened out of the "
            "evidence for every parameter (saturated, frozen or quantised readings; --no-quality keeps them)"
        )
    return lines


# How the table's notes say why a window is no evidence (the codes of dynia.verdicts.no_evidence_reasons).
def identification_table(summary, *, fitted_steps, held_out_steps):
    """What ``dynia identify`` prints: the selection, the estimates with their standard errors, the validation error.

    ``summary`` is the content of ``identified.json`` (its numbers, None for
    a non-finite one, are the ones printed); ``fitted_steps`` and
    ``held_out_steps`` count the steps of its ``segments`` and
    ``validation_segments``. One row per parameter: the estimate, its
    classical standard error and the one robust to autocorrelated residuals
    (HAC), and a note where the selected data do not determine it or it
    lies on a bound of its range.
    """
    lead, header, rows, notes = identification_parts(summary, fitted_steps=fitted_steps, held_out_steps=held_out_steps)
    return "\n".join(lead + aligned(header, rows) + notes)


def identification_parts(summary, *, fitted_steps, held_out_steps):
    """The pieces of :func:`identification_table`: the lines above the table, its header and rows, the lines below."""
    segments = summary["segments"]
    lead = [
        f"--method {summary['method']} selected {100 * summary['selected_share']:.1f} % of the fitting part "
        f"({fitted_steps} steps in {len(segments)} segment(s), the held-out part aside)"
    ]
    header = ("parameter", "estimate", "std error", "HAC std error", "note")
    rows = []
    for name, value in summary["parameters"].items():
        if not summary["identifiable"].get(name, True):
            note = "not determined by the selected data: the value is no estimate"
        elif name in summary["at_bound"]:
            note = "on a bound of its range: the errors do not hold"
        else:
            note = ""
        rows.append(
            (
                name,
                _number(value),
                _number(summary["std_errors"][name]),
                _number(summary["std_errors_hac"][name]),
                note,
            )
        )
    if not any(row[-1] for row in rows):
        header, rows = header[:-1], [row[:-1] for row in rows]
    held_out = ", ".join(f"{first} to {last}" for first, last in summary["validation_segments"])
    notes = [
        f"  standard errors: classical, and HAC (Newey-West, {summary['hac_lags']} lag(s)) robust to autocorrelated "
        "residuals; judge the estimates by the HAC ones",
        f"validation error: RMSE {_number(summary['validation_error'])} on the held-out part ({held_out_steps} steps, "
        f"{held_out}); fit RMSE {_number(summary['fit_rmse'])} on the selected data",
    ]
    return lead, header, rows, notes


def _number(value):
    """A number of identified.json as the table shows it: 6 significant digits, "inf" where JSON holds null."""
    return "inf" if value is None else f"{value:.6g}"


def _plain(value):
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")


def _write_csv(path, header, rows, times=None):
    """Numbers in full precision, missing values as empty cells, an optional leading time column."""
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for first in range(0, len(rows), _CSV_BLOCK):
            block = rows[first : first + _CSV_BLOCK]
            cells = [["" if np.isnan(value) else repr(value) for value in row] for row in block.tolist()]
            if times is not None:
                cells = [[time, *row] for time, row in zip(times[first : first + _CSV_BLOCK], cells)]
            writer.writerows(cells)
