"""The committed reports are clean: no warning printed to stderr and no path of the machine that rendered them."""

import json
import re
from pathlib import Path

import pytest

REPORTS = sorted((Path(__file__).parent.parent / "reports").glob("*.ipynb"))
# An absolute path of a machine: a home, a temporary or a work directory, or a site-packages file.
MACHINE_PATH = re.compile(r"(/(home|root|tmp|work|Users|private|var/folders)/|site-packages|[A-Z]:\\\\)")


def _outputs(notebook):
    for number, cell in enumerate(notebook["cells"]):
        for output in cell.get("outputs", []):
            yield number, output


@pytest.mark.parametrize("report", REPORTS, ids=[report.stem for report in REPORTS])
def test_report_has_no_warning_and_no_machine_path(report):
    notebook = json.loads(report.read_text())
    for number, output in _outputs(notebook):
        where = f"{report.name}, cell {number}"
        assert not (output["output_type"] == "stream" and output["name"] == "stderr"), f"{where}: {output['text']}"
        assert output["output_type"] != "error", where
        data = output.get("data", {})
        # Text only: base64 images are letters and slashes, where a path could appear by chance.
        text = (
            "".join(output["text"])
            if output["output_type"] == "stream"
            else json.dumps([data.get(kind, "") for kind in ("text/plain", "text/html", "text/markdown")])
        )
        found = MACHINE_PATH.search(text)
        assert found is None, f"{where}: {text[max(found.start() - 60, 0) : found.end() + 60]}"


def test_there_are_reports():
    assert len(REPORTS) >= 10
