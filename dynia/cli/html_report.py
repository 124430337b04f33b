"""``report.html``: one result directory as one self-contained page, the file a user forwards to a colleague.

:func:`write_report` writes what the command printed (its tables and the
lines under them), the warnings and data notes, every PNG figure of the
directory inline as a base64 data URI, the settings, the run and the versions:
no script, no stylesheet or image to fetch, nothing that needs the directory.
A page that travels must not give away where the results were made, so every
absolute path in it is shown by its last part (:func:`without_directories`):
the paths the summary names, and any other that starts in a directory of this
machine or a home directory; relative paths and the slashes of units and
formulas stay as the user gave them. Every text is escaped.
"""

import base64
import html
import json
import os
import re
import shlex
from pathlib import Path

from ..serial import json_ready

__all__ = ["write_report", "without_directories"]

# What may be a path inside a text: a word (or what follows "=", a quote or an opening bracket) that starts at the
# root or a home directory (~, ~user) and runs to whitespace or a delimiter. Only a candidate: user text is full of
# slashes (units %/h, columns dP [%/s], formulas (y)/2), so it is a path only if it starts in a directory of this
# machine (see _is_machine_path).
_CANDIDATE = re.compile(r"(?<![^\s'\"=(\[{<])(?:~[\w.-]*)?/[^\s'\"<>,;()\[\]{}]+")

_STYLE = """
body { font-family: sans-serif; max-width: 70em; margin: 1em auto; padding: 0 1em; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.6em; text-align: left; vertical-align: top; }
th { background: #eee; }
td.number { font-variant-numeric: tabular-nums; }
pre { white-space: pre-wrap; background: #f6f6f6; padding: 0.5em; }
figure { margin: 1em 0; }
img { max-width: 100%; }
.verdict-identified { color: #1a7f37; } .verdict-weak { color: #9a6700; } .verdict-suspect { color: #cf222e; }
"""


def without_directories(text, paths=()):
    """``text`` with every absolute path shown by its last part: ``/home/ana/runs/plant.csv`` as ``plant.csv``.

    ``paths`` are paths known to occur in ``text`` (the data file, ``--out``...);
    an absolute one among them is replaced whole, so that one holding a space
    leaves no part of its directories behind.

    Examples
    --------
    >>> without_directories("no rows in /home/ana/plant data.csv from 2", ["/home/ana/plant data.csv"])
    'no rows in plant data.csv from 2'
    >>> without_directories("--out=/tmp/run/ --model ~/m.py:tank data/plant.csv 5 degC/V")
    '--out=run --model m.py:tank data/plant.csv 5 degC/V'

    A slash in a unit, a column name or a formula is no path:

    >>> without_directories("K in %/h, column dP [%/s], output (y)/2, rate /s")
    'K in %/h, column dP [%/s], output (y)/2, rate /s'
    """
    text = str(text)
    for path in sorted({str(path) for path in paths if _is_absolute(str(path))}, key=len, reverse=True):
        text = text.replace(path, _last_part(path))
    return _CANDIDATE.sub(
        lambda match: _last_part(match.group()) if _is_machine_path(match.group()) else match.group(), text
    )


def _is_machine_path(candidate):
    """Whether ``candidate`` (``/...`` or ``~...``) names a place on this machine: a home directory's, or one whose
    first directory exists (``/home/ana/x.csv``, ``/tmp/run``), not a slash of a unit or a formula (``/h``, ``/2``)."""
    if candidate.startswith("~"):
        return True
    first = candidate.split("/", 2)[1]
    return bool(first) and os.path.isdir("/" + first)


def write_report(directory, summary, *, command, tables, lines=(), plots=True):
    """Write ``report.html`` into ``directory`` (the one holding ``summary``'s file and the figures).

    Parameters
    ----------
    directory : path-like
        The result directory; every ``*.png`` in it is embedded.
    summary : dict
        The content of ``summary.json`` or ``identified.json``: its
        ``settings``, ``warnings``, ``data``, ``versions``, ``inputs`` and
        ``command_line`` are shown, and ``run``, ``noise_floor``, ``segments``
        and ``data_quality`` where it has them.
    command : str
        The command that wrote the directory, ``"analyse"`` or ``"identify"``.
    tables : sequence of (lead, header, rows, notes)
        What the command printed: lines above a table, its header and rows of
        cells, and the lines below it.
    lines : sequence of str
        Further printed lines, after the tables (the noise-floor line).
    plots : bool
        Whether the command drew figures; without, the page says so.
    """
    directory = Path(directory)
    known = _known_paths(summary)

    def text(value):
        return html.escape(without_directories(value, known))

    settings = summary.get("settings", {})
    data_name = settings.get("data")
    title = f"dynia {command}" + ("" if data_name is None else f": {data_name}")
    page = [
        "<!DOCTYPE html>",
        '<html lang="en">',
        "<head>",
        '<meta charset="utf-8">',
        f"<title>{text(title)}</title>",
        f"<style>{_STYLE}</style>",
        "</head>",
        "<body>",
        f"<h1>{text(title)}</h1>",
        f"<p>Written by dynia {text(summary.get('version', ''))}; the tables, figures and numbers below are those "
        "of this directory's files.</p>",
        "<h2>Result</h2>",
    ]
    for lead, header, rows, notes in tables:
        page += [f"<p>{text(line.strip())}</p>" for line in lead]
        page += _table(header, rows, text)
        if notes:
            page += ["<ul>", *(f"<li>{text(line.strip())}</li>" for line in notes), "</ul>"]
    page += [f"<p>{text(line)}</p>" for line in lines]
    page += _selection(summary, text)
    if settings.get("second_run") and "narrowed" not in settings:
        page.append("<p>The second run, on the narrowed ranges, has its own report: second_run/report.html.</p>")
    page += _notes(summary, text)
    page += _figures(directory, plots, text)
    page += _record(summary, text)
    page += ["</body>", "</html>", ""]
    (directory / "report.html").write_text("\n".join(page), encoding="utf-8")


def _is_absolute(path):
    return os.path.isabs(path) or path.startswith("~")


def _last_part(path):
    return path.rstrip("/").rsplit("/", 1)[-1]


def _known_paths(summary):
    """The paths the summary names: the inputs, the settings' files and --out, the words of the command line."""
    settings = summary.get("settings", {})
    paths = list(summary.get("inputs", {}))
    paths += [settings[key] for key in ("data", "out", "config", "output_file") if isinstance(settings.get(key), str)]
    model = settings.get("model")
    if isinstance(model, str) and ":" in model:
        paths.append(model.rpartition(":")[0])
    paths += [word.partition("=")[2] or word for word in summary.get("command_line", ()) if isinstance(word, str)]
    return paths


def _table(header, rows, text):
    cells = ["<table>", "<tr>" + "".join(f"<th>{text(cell)}</th>" for cell in header) + "</tr>"]
    for row in rows:
        cells.append(
            "<tr>"
            + "".join(
                f'<td class="verdict-{text(cell)}">{text(cell)}</td>'
                if column == "verdict"
                else f"<td>{text(cell)}</td>"
                for column, cell in zip(header, row)
            )
            + "</tr>"
        )
    cells.append("</table>")
    return cells


def _pairs(pairs, text):
    """A two-column table of names and values; a value that is no string shown as JSON."""
    rows = ["<table>"]
    for name, value in pairs:
        shown = value if isinstance(value, str) else json.dumps(json_ready(value), default=str)
        rows.append(f"<tr><th>{text(name)}</th><td>{text(shown)}</td></tr>")
    rows.append("</table>")
    return rows


def _flat(mapping, prefix=""):
    """(dotted name, value) of a nested mapping, its leaves in order."""
    for name, value in mapping.items():
        if isinstance(value, dict) and value:
            yield from _flat(value, f"{prefix}{name}.")
        else:
            yield f"{prefix}{name}", value


def _stretches(pairs):
    return ", ".join(f"{first} to {last}" for first, last in pairs) or "none"


def _selection(summary, text):
    """Where the result comes from in time: the noise floor's informative stretches, identify's segments."""
    found = []
    floor = summary.get("noise_floor")
    if floor:
        found.append(f"<p>Windows above the noise floor: {text(_stretches(floor['informative']))}.</p>")
    if "segments" in summary:
        found.append(f"<p>Fitted on: {text(_stretches(summary['segments']))}.</p>")
    return found


def _notes(summary, text):
    """The warnings the command printed, what loading did to the data, its gaps and the data-quality findings."""
    data = summary.get("data", {})
    notes = list(summary.get("warnings", ())) + list(data.get("notes", ()))
    notes += [f"no measurements from {first} to {last}" for first, last in data.get("gaps", ())]
    dropped = summary.get("run", {}).get("n_dropped")
    if dropped:
        notes.append(f"{dropped} parameter set(s) dropped: their simulation was not finite")
    page = ["<h2>Warnings and data notes</h2>"]
    if notes:
        page += ["<ul>", *(f"<li>{text(note)}</li>" for note in notes), "</ul>"]
    else:
        page.append("<p>None: the command printed no warning and loading changed nothing in the data.</p>")
    findings = summary.get("data_quality")
    if findings is not None:
        page.append(f"<h3>Data quality: {len(findings)} finding(s)</h3>")
        screening = summary.get("screening")
        if screening:
            page.append(
                f"<p>{text(str(screening['excluded_windows']))} of {text(str(screening['n_windows']))} windows are "
                "screened out of the evidence: they use saturated or frozen readings, or their output moves by "
                "fewer than a few steps of a coarse quantisation (--no-quality keeps them).</p>"
            )
        if findings:
            # analyse says how many windows each finding took from the evidence; identify selects segments instead.
            counted = ("windows_excluded",) if any("windows_excluded" in entry for entry in findings) else ()
            header = ("signal", "kind", "start_time", "end_time", "value", *counted, "reason")
            page += _table(header, [[_cell(entry.get(key)) for key in header] for entry in findings], text)
    return page


def _cell(value):
    return value if isinstance(value, str) else json.dumps(json_ready(value))


def _figures(directory, plots, text):
    page = ["<h2>Figures</h2>"]
    if not plots:
        return page + ["<p>No figures: the command ran with --no-plots.</p>"]
    # The data (or the fit) first, then the others by name.
    for path in sorted(directory.glob("*.png"), key=lambda path: (path.name not in ("data.png", "fit.png"), path.name)):
        encoded = base64.b64encode(path.read_bytes()).decode("ascii")
        page += [
            "<figure>",
            f'<img src="data:image/png;base64,{encoded}" alt="{text(path.name)}">',
            f"<figcaption>{text(path.name)}</figcaption>",
            "</figure>",
        ]
    return page


def _record(summary, text):
    """The data's grid, the run, the settings, the versions, the inputs' digests and the command line."""
    page = []
    data = summary.get("data", {})
    if data:
        page += ["<h2>Data</h2>"]
        page += _pairs([(key, value) for key, value in data.items() if key in ("n_steps", "dt", "start")], text)
    if "run" in summary:
        page += ["<h2>Run</h2>", *_pairs(summary["run"].items(), text)]
    page += ["<h2>Settings</h2>", *_pairs(_flat(summary.get("settings", {})), text)]
    page += ["<h2>Versions</h2>", *_pairs(summary.get("versions", {}).items(), text)]
    inputs = summary.get("inputs", {})
    if inputs:
        digests = [(path, entry["sha256"]) for path, entry in inputs.items()]
        page += ["<h2>Inputs (SHA-256)</h2>", *_pairs(digests, text)]
    words = summary.get("command_line")
    if words:
        page += ["<h2>Command</h2>", f"<pre>{text(shlex.join(map(str, words)))}</pre>"]
    return page
