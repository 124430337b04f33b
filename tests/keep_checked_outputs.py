"""Drop every output of a reference notebook except those nbval compares.

Reference runs (tests/notebooks/*.ipynb) are committed only for the cells
marked NBVAL_CHECK_OUTPUT; figures and other outputs would only bloat the
repository. Usage: python tests/keep_checked_outputs.py NOTEBOOK.ipynb
"""

import sys

import nbformat


def main(path):
    notebook = nbformat.read(path, as_version=4)
    for cell in notebook.cells:
        if cell.cell_type == "code" and not cell.source.lstrip().startswith("# NBVAL_CHECK_OUTPUT"):
            cell.outputs = []
    nbformat.write(notebook, path)


if __name__ == "__main__":
    main(sys.argv[1])
