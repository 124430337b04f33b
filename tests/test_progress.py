"""progress="auto": a bar on a terminal's stderr and in a notebook, none elsewhere (dynia.progress)."""

import sys
import types
import warnings

import numpy as np
import pytest

import dynia
from dynia.errors import SettingsError
from dynia.models import FirstOrder
from dynia.progress import progress_bar, shows_progress

U = np.r_[np.zeros(20), np.ones(100)]
Y = FirstOrder().simulate([[2.0, 3.0]], U)[0]
BOUNDS = {"K": (0.0, 5.0), "T": (0.5, 6.0)}


def _notebook(monkeypatch):
    """This process seen as a Jupyter kernel: IPython's shell is a ZMQInteractiveShell."""
    shell = type("ZMQInteractiveShell", (), {})()
    monkeypatch.setitem(sys.modules, "IPython", types.SimpleNamespace(get_ipython=lambda: shell))


def test_true_and_false_are_taken_as_given_and_anything_else_is_named():
    assert shows_progress(True) is True and shows_progress(False) is False
    assert shows_progress(np.True_) is True  # a flag taken from an array
    for wrong in (1, 0, None, "yes", "Auto"):
        with pytest.raises(SettingsError, match=r"progress must be True, False or 'auto'"):
            shows_progress(wrong)


def test_auto_shows_a_bar_on_a_terminal_or_in_a_notebook_unless_tqdm_is_disabled(monkeypatch):
    monkeypatch.delenv("TQDM_DISABLE", raising=False)
    assert shows_progress("auto") is False  # pytest's captured stderr, no kernel
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert shows_progress("auto") is True
    monkeypatch.setenv("TQDM_DISABLE", "1")
    assert shows_progress("auto") is False
    monkeypatch.setenv("TQDM_DISABLE", "0")
    assert shows_progress("auto") is True


def test_auto_in_a_notebook_without_ipywidgets_is_a_text_bar_without_a_warning(monkeypatch):
    monkeypatch.delenv("TQDM_DISABLE", raising=False)
    _notebook(monkeypatch)
    assert shows_progress("auto") is True
    monkeypatch.setattr("importlib.util.find_spec", lambda name: None)  # no ipywidgets
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # tqdm.auto would warn "IProgress not found"
        bar = progress_bar("auto", range(3), desc="x")
    from tqdm.std import tqdm

    assert type(bar) is tqdm
    bar.close()


def test_dynia_run_shows_its_bar_by_default_on_a_terminal_only(monkeypatch, capsys):
    monkeypatch.delenv("TQDM_DISABLE", raising=False)
    dynia.run(U, Y, FirstOrder(), BOUNDS, n=5, n_samples=200, rng=1)
    assert "DYNIA windows" not in capsys.readouterr().err
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    dynia.run(U, Y, FirstOrder(), BOUNDS, n=5, n_samples=200, rng=1)
    err = capsys.readouterr().err
    assert "DYNIA windows" in err
    assert f"{U.size}/{U.size}" in err and ("window/s" in err or "s/window" in err)  # it counts the windows
    dynia.run(U, Y, FirstOrder(), BOUNDS, n=5, n_samples=200, rng=1, progress=False)
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("front_end", ["run", "suggest", "identify"])
def test_a_wrong_progress_is_refused_before_any_work(front_end):
    call = getattr(dynia, front_end)
    with pytest.raises(SettingsError, match="progress must be True, False or 'auto'; got 'yes'"):
        if front_end == "suggest":
            call(U, Y, FirstOrder(), BOUNDS, progress="yes")
        else:
            call(U, Y, FirstOrder(), BOUNDS, n=5, n_samples=200, progress="yes")
