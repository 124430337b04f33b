"""The committed reference runs in tests/notebooks/ must match notebooks/ and their CI parameters.

nbval re-executes the reference notebooks and compares the cells marked
NBVAL_CHECK_OUTPUT; that only tests the current notebooks if the references
hold their code. `make references` regenerates them.
"""

from pathlib import Path

import jupytext
import nbformat
import pytest
import yaml

ROOT = Path(__file__).resolve().parent.parent
SOURCES = sorted((ROOT / "notebooks").glob("*.py"))


def _code_cells(notebook):
    return [
        cell.source.strip()
        for cell in notebook.cells
        if cell.cell_type == "code" and "injected-parameters" not in cell.metadata.get("tags", [])
    ]


@pytest.mark.parametrize("source", SOURCES, ids=[path.stem for path in SOURCES])
def test_reference_run_is_up_to_date(source):
    reference_path = ROOT / "tests" / "notebooks" / f"{source.stem}.ipynb"
    params_path = ROOT / "tests" / "notebook_params" / f"{source.stem}.yaml"
    assert params_path.exists(), f"{params_path.relative_to(ROOT)} is missing: every notebook needs CI parameters"
    assert reference_path.exists(), f"no reference run for {source.name}: run `make references`"
    reference = nbformat.read(reference_path, as_version=4)
    stale = f"{reference_path.relative_to(ROOT)} is out of date with {source.relative_to(ROOT)}: run `make references`"
    assert _code_cells(reference) == _code_cells(jupytext.read(source)), stale
    injected = reference.metadata.get("papermill", {}).get("parameters", {})
    assert injected == (yaml.safe_load(params_path.read_text()) or {}), stale
