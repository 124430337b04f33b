"""What a user gets from `import dynia`: the package's version, and no heavy optional library loaded."""

import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

import dynia

# Loaded on first use only: plots, result files, the cluster and pandas input.
LAZY = ("matplotlib", "xarray", "h5py", "h5netcdf", "dask", "distributed", "pandas")


def test_import_loads_no_optional_heavy_library():
    code = f"import sys, dynia; print(','.join(m for m in {LAZY!r} if m in sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert loaded.strip() == ""


def test_a_first_order_run_loads_no_statistics_library():
    """scipy.stats takes about 0.7 CPU-s to import, a third of a warm quick start; a plain run needs none of it."""
    code = (
        "import sys, numpy as np, dynia\n"
        "u = np.r_[np.zeros(10), np.ones(40)]\n"
        "y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]\n"
        "dynia.run(u, y, dynia.models.FirstOrder(), {'K': (0, 7), 'T': (0, 7)}, n_samples=100, n=5, rng=1)\n"
        "print(','.join(m for m in ('scipy.stats', 'pandas', 'matplotlib') if m in sys.modules))"
    )
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert loaded.strip() == ""


def test_a_transfer_function_model_still_simulates_after_the_lean_import():
    code = (
        "import control, dynia\n"
        "model = dynia.models.TransferFunction(lambda p: control.tf([p[0]], [p[1], 1.0]), names=('K', 'T'))\n"
        "print(model.simulate([[2.0, 1.0]], [1.0, 1.0, 1.0]).round(4).tolist())"
    )
    printed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert printed.strip() == "[[0.0, 1.2642, 1.7293]]"


def test_version_is_the_distributions():
    from importlib.metadata import version

    assert dynia.__version__ == version("dynia")


def test_import_loads_only_the_root_and_the_error_types():
    code = "import sys, dynia; print(sorted(m for m in sys.modules if m.startswith('dynia')))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert loaded.strip() == "['dynia', 'dynia.errors']"


def test_the_verbs_are_callables_at_the_top_level():
    import types

    for verb in ("run", "identify", "suggest", "second_run", "load", "load_csv", "moving_window"):
        value = getattr(dynia, verb)
        assert callable(value) and not isinstance(value, types.ModuleType), verb
    # Importing the modules that hold them does not shadow them.
    importlib.import_module("dynia.identification")
    importlib.import_module("dynia.suggestion")
    assert callable(dynia.identify) and callable(dynia.suggest)


def test_all_lists_the_public_api_and_no_module():
    import types

    assert "run" in dynia.__all__ and "DyniaResult" in dynia.__all__
    for name in dynia.__all__:
        assert not isinstance(getattr(dynia, name), types.ModuleType), name


def test_an_unknown_attribute_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        dynia.nonsense  # noqa: B018


def test_the_short_names_of_the_ports_are_the_reference_modules_themselves():
    import dynia.mcat
    import dynia.reference.mcat
    import dynia.reference.thesis
    import dynia.thesis

    assert dynia.thesis is dynia.reference.thesis and dynia.mcat is dynia.reference.mcat
    from dynia import thesis

    assert thesis is dynia.reference.thesis


@pytest.mark.parametrize(("old", "new"), [("dynia.analysis", "dynia.engine"), ("dynia.cld", "dynia.engine.cld")])
def test_the_old_homes_warn_with_the_new_home_and_the_version_that_removes_them(old, new):
    code = (
        "import warnings\n"
        "with warnings.catch_warnings(record=True) as caught:\n"
        "    warnings.simplefilter('always')\n"
        f"    import {old}\n"
        "print([str(w.message) for w in caught if w.category is DeprecationWarning])"
    )
    printed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert f"{old} is deprecated" in printed and new in printed and "0.3.0" in printed


def test_nothing_in_the_package_tests_notebooks_or_benchmarks_uses_the_old_homes():
    root = Path(__file__).resolve().parents[1]
    old_home = re.compile(
        r"dynia\.(analysis|cld)\b|from dynia import [^\n]*\b(analysis|cld)\b|from \.+(analysis|cld) import"
    )
    offenders = [
        f"{path.relative_to(root)}: {line.strip()}"
        for folder in ("dynia", "tests", "notebooks", "benchmarks")
        for path in (root / folder).rglob("*.py")
        if path.name not in ("analysis.py", "cld.py", "test_packaging.py") and "__pycache__" not in path.parts
        for line in path.read_text().splitlines()
        if old_home.search(line)
    ]
    assert offenders == []


def test_the_commands_version_and_help_load_neither_the_engine_nor_numba():
    code = (
        "import sys\n"
        "from dynia.cli import main\n"
        "for words in (['--version'], ['analyse', '--help']):\n"
        "    try:\n"
        "        main(words)\n"
        "    except SystemExit:\n"
        "        pass\n"
        "print(sorted(m for m in ('numba', 'scipy', 'dynia.engine', 'dynia.pipeline') if m in sys.modules))"
    )
    printed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert printed.strip().endswith("[]")
