"""The chapter-3 notebooks' second rendering, code_path "thesis", which CI's reference runs do not execute."""

from pathlib import Path

import jupytext
import papermill
import pytest

NOTEBOOKS = Path(__file__).resolve().parent.parent / "notebooks"


def test_example1_draws_its_figures_from_the_thesis_code(tmp_path):
    notebook = jupytext.read(NOTEBOOKS / "ch3_example1.py")
    jupytext.write(notebook, tmp_path / "ch3_example1.ipynb")
    executed = papermill.execute_notebook(
        str(tmp_path / "ch3_example1.ipynb"),
        str(tmp_path / "out.ipynb"),
        parameters={"code_path": "thesis", "n_samples": 400, "compare_with_port": False, "figure_dir": "figures"},
        cwd=str(tmp_path),
        kernel_name="python3",
        progress_bar=False,
    )
    printed = "".join(
        "".join(output.get("text", ""))
        for cell in executed["cells"]
        if cell["cell_type"] == "code"
        for output in cell.get("outputs", [])
    )
    assert "code path: thesis" in printed
    drawn = {path.name for path in (tmp_path / "figures").glob("*.png")}
    assert {f"fig3_{number:02d}.png" for number in range(2, 9)} | {"fig3_04_08_thesis_code.png"} <= drawn


def test_a_code_path_other_than_thesis_or_corrected_stops_the_notebook(tmp_path):
    notebook = jupytext.read(NOTEBOOKS / "ch3_case_study.py")
    jupytext.write(notebook, tmp_path / "ch3_case_study.ipynb")
    with pytest.raises(papermill.PapermillExecutionError, match="code_path must be one of"):
        papermill.execute_notebook(
            str(tmp_path / "ch3_case_study.ipynb"),
            str(tmp_path / "out.ipynb"),
            parameters={"code_path": "matlab", "days": 1},
            cwd=str(tmp_path),
            kernel_name="python3",
            progress_bar=False,
        )
