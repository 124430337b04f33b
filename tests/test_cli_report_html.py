"""report.html: one valid, self-contained page per result directory, holding what the command printed."""

import base64
import contextlib
import io
import os
import re
from html.parser import HTMLParser

import pytest
from cli_cases import HEATING, ROOT, cli_run

from dynia.cli import main
from dynia.cli.html_report import without_directories

ARGS = (
    "--time time --input u --output y --model first-order --param K=0:40 --param T=0:200 "
    "--input-offset 6 --offset first --samples 100 --seed 1"
).split()

# Elements HTML never closes.
VOID = {"meta", "img", "br", "hr", "link", "input"}
PNG = b"\x89PNG\r\n\x1a\n"
DATA_URI = re.compile(r"data:image/png;base64,([A-Za-z0-9+/=]+)")
NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


class Page(HTMLParser):
    """The tags of a page, checked to nest, its text (entities resolved) and its images' sources."""

    def __init__(self, text):
        super().__init__()
        self.open, self.tags, self.images, self.text, self.doctype = [], [], [], [], None
        self.feed(text)
        self.close()

    def handle_decl(self, decl):
        self.doctype = decl

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        if tag == "img":
            self.images.append(dict(attrs))
        if tag not in VOID:
            self.open.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        if tag not in VOID:
            self.open.pop()

    def handle_endtag(self, tag):
        assert tag not in VOID, f"</{tag}> closes a void element"
        assert self.open and self.open[-1] == tag, f"</{tag}> closes <{self.open[-1] if self.open else None}>"
        self.open.pop()

    def handle_data(self, data):
        self.text.append(data)


def _run(command, out, *extra):
    """``dynia COMMAND HEATING ARGS EXTRA --out OUT`` in this process: (stdout, the page, its parse)."""
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(io.StringIO()):
        assert main([command, str(HEATING), *ARGS, *extra, "--out", str(out)]) == 0
    text = (out / "report.html").read_text(encoding="utf-8")
    return stdout.getvalue(), text, Page(text)


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "heating"
    return (out, *_run("analyse", out))


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "fit"
    return (out, *_run("identify", out))


def _well_formed(page):
    assert page.doctype == "DOCTYPE html"
    assert page.open == [], f"never closed: {page.open}"
    assert page.tags[:2] == ["html", "head"] and {"title", "body", "meta"} <= set(page.tags)
    assert "script" not in page.tags and "link" not in page.tags  # nothing to run, nothing to fetch


def _embeds_every_png(out, text, page):
    pngs = sorted(path.name for path in out.glob("*.png"))
    assert pngs and sorted(image["alt"] for image in page.images) == pngs
    for image in page.images:
        match = DATA_URI.fullmatch(image["src"])
        assert match, image["src"][:40]
        assert base64.b64decode(match.group(1), validate=True) == (out / image["alt"]).read_bytes()
        assert base64.b64decode(match.group(1))[:8] == PNG
    # Nothing outside the page: every src and href is a data URI.
    assert all(source.startswith("data:") for source in re.findall(r'(?:src|href)="([^"]*)"', text))


def _names_no_absolute_path(out, text, page):
    readable = DATA_URI.sub("", text)  # base64 holds "/" and letters: a "/tmp" there is no path
    for absolute in (str(out), str(out.parent), str(ROOT), "/tmp", os.path.expanduser("~"), str(HEATING)):
        assert absolute not in readable
    # No word of the page's text starts a path at the root or a home directory.
    words = [word.partition("=")[2] or word for word in " ".join(page.text).split()]
    assert [word for word in words if word.lstrip("'\"(").startswith(("/", "~"))] == []


def _holds_the_printed_numbers(stdout, page):
    shown = " ".join(page.text)
    numbers = NUMBER.findall(stdout)
    assert len(numbers) > 10
    missing = [number for number in numbers if number not in shown]
    assert missing == []
    return shown


def test_analyse_report_is_valid_html(analysed):
    _well_formed(analysed[3])


def test_analyse_report_embeds_every_figure(analysed):
    out, _, text, page = analysed
    assert len(page.images) == 5  # data.png, ic and identifiability of K and of T
    _embeds_every_png(out, text, page)


def test_analyse_report_names_no_absolute_path(analysed):
    out, _, text, page = analysed
    _names_no_absolute_path(out, text, page)
    shown = " ".join(page.text)
    assert "heating_system.csv" in shown  # the data file, by its name


def test_analyse_report_holds_the_printed_table_its_reasons_and_the_noise_floor(analysed):
    _, stdout, _, page = analysed
    shown = _holds_the_printed_numbers(stdout, page)
    table = stdout.splitlines()
    assert table[0].split()[:2] == ["parameter", "max"]
    for line in table:
        if line.startswith("  ") or line.startswith("noise floor:"):  # the reasons and the noise-floor line, whole
            assert line.strip() in shown
        else:  # a row: every cell in a cell of the page's table
            assert all(cell in page.text for cell in re.split(r"\s{2,}", line.strip()))


def test_analyse_report_holds_the_settings_versions_and_data_notes(analysed):
    _, _, _, page = analysed
    shown = " ".join(page.text)
    for needle in ("Settings", "analysis.n_samples", "bounds.K", "[0.0, 40.0]", "offset_value", "129.32"):
        assert needle in shown
    for package in ("dynia", "numpy", "numba", "python"):
        assert package in page.text
    assert "Data quality: 0 finding(s)" in shown and "Warnings and data notes" in shown


def test_identify_report_holds_the_printed_estimates_and_the_fit(identified):
    out, stdout, text, page = identified
    _well_formed(page)
    _embeds_every_png(out, text, page)
    assert [image["alt"] for image in page.images] == ["fit.png"]
    _names_no_absolute_path(out, text, page)
    shown = _holds_the_printed_numbers(stdout, page)
    header = next(line for line in stdout.splitlines() if line.startswith("parameter"))
    rows = stdout.splitlines()[stdout.splitlines().index(header) + 1 :][:2]
    for row in rows:  # K and T: name, estimate, std error, HAC std error, each a cell of the page
        cells = row.split()
        assert cells[0] in ("K", "T") and all(cell in page.text for cell in cells)
    assert "validation error: RMSE" in shown


def test_no_plots_gives_a_report_without_figures_that_says_so(tmp_path, capsys):
    data = tmp_path / "data.csv"
    # A step test with rows 20 to 24 missing: the gap is a warning the report must repeat, naming the file by name.
    rows = [f"{t},{1.0 if t > 5 else 0.0},{2.0 if t > 6 else 0.0}\n" for t in range(60) if not 20 <= t < 25]
    data.write_text("time,u,y\n" + "".join(rows))
    out = tmp_path / "out"
    args = "--time time --input u --output y --model first-order --param K=0:5 --param T=0:5 --samples 50 --n 3"
    status, stdout, stderr = cli_run(
        capsys, "analyse", data, *args.split(), "--max-gap", "2", "--no-plots", "--out", out
    )
    assert status == 0, stderr
    assert "no rows in" in stderr
    text = (out / "report.html").read_text(encoding="utf-8")
    page = Page(text)
    _well_formed(page)
    assert page.images == [] and "<img" not in text and not list(out.glob("*.png"))
    shown = " ".join(page.text)
    assert "No figures: the command ran with --no-plots." in shown
    assert "no rows in data.csv from 20.0 to 24.0" in shown or "no rows in data.csv from 20 to 24" in shown
    _names_no_absolute_path(out, text, page)
    _holds_the_printed_numbers(stdout, page)


@pytest.mark.parametrize(
    "text", ["--unit K='%/h'", "column dP [%/s]", "output (y)/2", "a rate in 1/s", "per /h and /2 and [/s]"]
)
def test_a_slash_of_a_unit_a_column_or_a_formula_is_kept(text):
    """Issue 32: the pattern took any slash after a non-word character for a path, '%/h' was shown as '%h'."""
    assert without_directories(text) == text


def test_without_directories_keeps_relative_paths_and_shows_absolute_ones_by_name():
    home = os.path.expanduser("~")
    assert without_directories("data/plant.csv ./a.csv ../b.csv 3 degC/V 1/2") == (
        "data/plant.csv ./a.csv ../b.csv 3 degC/V 1/2"
    )
    assert without_directories(f"'{home}/runs/x y/plant.csv' --out=/tmp/r/", [f"{home}/runs/x y/plant.csv"]) == (
        "'plant.csv' --out=r"
    )
    assert without_directories("~ana/data.csv and ~/m.py:tank") == "data.csv and m.py:tank"
