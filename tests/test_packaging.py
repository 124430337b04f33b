"""What a user gets from `import dynia`: the package's version, and no heavy optional library loaded."""

import subprocess
import sys

import dynia

# Loaded on first use only: plots, result files, the cluster and pandas input.
LAZY = ("matplotlib", "xarray", "h5py", "h5netcdf", "dask", "distributed", "pandas")


def test_import_loads_no_optional_heavy_library():
    code = f"import sys, dynia; print(','.join(m for m in {LAZY!r} if m in sys.modules))"
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
