"""Fill numba's on-disk cache of the engine's kernels once per run of the suite, its compile shared by the workers.

On a fresh clone the cache is empty, and the first use of the kernels compiles them: some 50 s of one core. Under
pytest-xdist every worker, and every notebook kernel and command-line subprocess started before the cache is written,
would compile the same kernels at once. Instead each worker, before its first test (tests/conftest.py), compiles its
share of them, and loads the others' from the cache once they are written: the compile takes half the time on two
cores, and everything after it loads the cache in a second or two.

The shares are the three kernels that take long to compile, each called on a small record with the argument types of
a run (a share compiled with other types would only cost its own compile: the runs compile theirs as they need them).
Nothing here is a test: any failure is left for the tests to meet, and the suite runs as it would without it.
"""

import time
from pathlib import Path

import numpy as np

# How long a worker waits for another's share before it compiles that share itself (a worker that died, say).
PATIENCE = 600


def _records():
    """A short record of each kind of linear model the kernels take apart: a lag model and a two-state one."""
    from dynia.models import FirstOrder, SecondOrderDelay

    u = np.r_[np.zeros(5), np.ones(25)]
    generator = np.random.default_rng(0)
    lag = FirstOrder(), generator.uniform([0.5, 0.5], [4.0, 6.0], (200, 2)), [2.0, 3.0]
    two_states = SecondOrderDelay(), generator.uniform([0.5, 0.5, 0.5, 0.0], [4.0, 6.0, 6.0, 2.0], (200, 4)), None
    for model, params, truth in (lag, two_states):
        yield model, u, model.simulate([truth if truth else params[0]], u)[0], params


def _windows():
    """kernels.analyse_windows and analyse_windows_batched (with ic_error): the windows of every run."""
    from dynia.engine.windows import moving_window

    model, u, y, params = next(_records())
    bounds = [[0.5, 4.0], [0.5, 6.0]]
    for ic_error in (False, True):
        moving_window(y, model.simulate(params, u), params, bounds, n=3, engine="numba", workers=1, ic_error=ic_error)


def _fused_simulation():
    """kernels.fused: a linear model's simulation fused with the window sums, as dynia.run does it."""
    from dynia.engine.kernels import CompiledErrors

    for model, u, y, params in _records():
        source = CompiledErrors(model, params, u, y, dt=1.0, x0="zero", workers=1)
        try:
            source.window_sums(0, u.size, (3, 3), np.zeros(params.shape[0]))
        finally:
            source.close()


def _simulation():
    """kernels.simulate: a linear model's outputs or error rows, for the fits and the other error sources."""
    from dynia.engine.kernels import CompiledErrors

    for model, u, y, params in _records():
        source = CompiledErrors(model, params, u, y, dt=1.0, x0="zero", workers=1)
        try:
            list(source.output_chunks(u.size))
        finally:
            source.close()


# Worker i compiles shares i, i + n, ...: the windows (about 30 s) on one worker, the two simulations (about 20 s)
# on the other, when there
# are two. Each kernel compiles a lag model's path and the general one apart (a run compiles only the one it uses).
SHARES = (_windows, _fused_simulation, _simulation)


def warm(worker, workers, folder):
    """Compile worker ``worker``'s shares of :data:`SHARES` (of ``workers``), then load the others' from the cache.

    ``folder``, a directory every worker of the run sees: a share's ``.done`` file there says that it is in the cache.
    """
    from dynia.engine import kernels

    if not kernels.AVAILABLE:
        return
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    mine = [share for index, share in enumerate(SHARES) if index % workers == worker]
    others = [share for share in SHARES if share not in mine]
    for share in mine:
        _run(share, folder)
    for share in others:
        deadline = time.monotonic() + PATIENCE
        while not (folder / f"{share.__name__}.done").exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        _run(share, folder)


def _run(share, folder):
    try:
        share()
    except Exception:  # left for the tests that use the kernel to report
        pass
    finally:
        (folder / f"{share.__name__}.done").touch()
