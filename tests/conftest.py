"""Shared test data: the thesis's example 1, simulated independently of dynia.models; the notebooks' environment;
the databases (SQLite, and a real PostgreSQL server) that dynia follow writes to."""

import os
import shutil
import subprocess
import tempfile
import uuid
from pathlib import Path

import numpy as np
import pytest

import dynia


def pytest_sessionstart(session):
    """A pytest-xdist worker first compiles its share of the engine's kernels into numba's cache: warm_kernels.py.

    Its folder of markers is in the run's base temporary directory, the parent of every worker's own.
    """
    workerinput = getattr(session.config, "workerinput", None)
    if workerinput is not None:
        import warm_kernels

        worker = int(workerinput["workerid"].removeprefix("gw"))
        folder = Path(session.config.option.basetemp).parent / "warm-kernels"
        warm_kernels.warm(worker, int(workerinput["workercount"]), folder)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    """Notebook kernels start in the environment of tests/notebook.env, as make's notebooks do.

    nbval starts a notebook's kernel as its first cell is set up, with the environment of that moment; the variables
    are put back as they were at teardown, so that nothing else in the suite sees them.
    """
    if type(item).__module__.startswith("nbval"):
        item.stash[_BEFORE] = {name: os.environ.get(name) for name in NOTEBOOK_ENV}
        os.environ.update(NOTEBOOK_ENV)


def pytest_runtest_teardown(item):
    for name, value in item.stash.get(_BEFORE, {}).items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


def _notebook_env():
    lines = (Path(__file__).with_name("notebook.env")).read_text().splitlines()
    return dict(line.split("=", 1) for line in lines if line.strip() and not line.startswith("#"))


NOTEBOOK_ENV = _notebook_env()
_BEFORE = pytest.StashKey()


def first_order_response(gain, time_constant, u):
    """Exact zero-order-hold response of K/(T s + 1), one row per (gain, time constant) pair.

    Deliberately separate from dynia.models so the engine tests do not rest on it.
    """
    gain = np.atleast_1d(np.asarray(gain, dtype=float))
    pole = np.exp(-1.0 / np.maximum(np.atleast_1d(time_constant), 1e-12))
    out = np.zeros((gain.size, len(u)))
    for k in range(len(u) - 1):
        out[:, k + 1] = pole * out[:, k] + gain * (1 - pole) * u[k]
    return out


def stored_record(steps=120, seed=3):
    """The small first-order record the result-file tests save and load: a step up, a step down, noise 0.05."""
    rng = np.random.default_rng(seed)
    u = np.r_[np.zeros(20), np.full(40, 1.0), np.full(steps - 60, 0.3)]
    y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0] + rng.normal(0, 0.05, steps)
    return u, y


def example1_record(steps=500, seed=0, noise=0.5):
    """Thesis example 1 simulated by dynia.models: K=2, T=3 on the thesis's input, white noise of SD ``noise``."""
    u = dynia.synthetic.example_firstorder_input(steps)
    y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(seed).normal(0, noise, steps)
    return u, y


def example_firstorder_input(steps=500):
    """The input of example_firstorder.m, 0-based: 35, with two dips to 10 and a final 0."""
    return dynia.synthetic.example_firstorder_input(steps)


@pytest.fixture
def fresh_process(monkeypatch):
    """The engine's choice as in a fresh process: no kernel loaded, no analysis run on the twin yet.

    Whatever the tests before ran in this worker (and tests/warm_kernels.py loads the kernels first).
    """
    from dynia.engine import kernels, twin

    monkeypatch.setattr(kernels, "compiled", lambda: False)
    monkeypatch.setattr(twin, "analyses_run", 0)


@pytest.fixture(scope="session")
def example1():
    """Thesis example 1 on 500 steps: k=2, T=3, noise 0.5, 2000 samples of [0, 7]^2."""
    rng = np.random.default_rng(2009)
    u = example_firstorder_input()
    y = first_order_response(2.0, 3.0, u)[0] + rng.normal(0, 0.5, u.size)
    params = rng.uniform(0, 7, (2000, 2))  # columns: gain, time constant
    sims = first_order_response(params[:, 0], params[:, 1], u)
    return dict(u=u, y=y, params=params, sims=sims, bounds=np.array([[0.0, 7.0], [0.0, 7.0]]))


def compiled_window_costs(y, sims, n, window="centred", chunk_steps=None):
    """The window costs the compiled engine ranks (m, n_samples): its running sums over the same chunks, squared MAE.

    Formed with the compiled kernel's own helpers, chunk by chunk as the windows pass cuts the record, so that they
    are the bits the engine used (the fused linear-model path gives the same, tests/test_running_sums.py).
    """
    from dynia.engine.error_sources import ArrayErrors
    from dynia.engine.kernels.sums import first_window, next_window
    from dynia.engine.windows import default_chunk_steps, window_halos, window_inputs

    y, sims = np.asarray(y, dtype=float), np.asarray(sims, dtype=float)
    errors = ArrayErrors(y, sims)
    before, after = window_halos(n, window)
    slots = before + after + 1
    chunk_steps = chunk_steps or default_chunk_steps(sims.shape[0], 2 * n)
    high, low, total = (np.empty(sims.shape[0]) for _ in range(3))
    costs = []
    for start in range(0, y.size, chunk_steps):
        stop = min(start + chunk_steps, y.size)
        rows, measured = window_inputs(errors, start, stop, before, after, y.size, time_major=True)
        present = first_window(rows, measured, slots, (high, low), total)
        for t in range(stop - start):
            if t:
                present = next_window(rows, measured, t, slots, present, (high, low), total)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                costs.append((total / present) ** 2)
    return np.array(costs)


# A throwaway PostgreSQL server: see .ci/postgres. Its exit status when the server binaries are not installed.
POSTGRES_SCRIPT = Path(__file__).resolve().parent.parent / ".ci" / "postgres"
NO_POSTGRES_SERVER = 3


@pytest.fixture(scope="session")
def postgres_url():
    """The SQLAlchemy URL of a real PostgreSQL server for this test session.

    The one in DYNIA_TEST_POSTGRES_URL when set (make test starts one through .ci/with-postgres); otherwise a
    throwaway cluster of this session's own (.ci/postgres start, stopped at the session's end), so that a plain
    `pytest` gets a real server too. Skips when no PostgreSQL server is installed. Under pytest-xdist every worker
    without DYNIA_TEST_POSTGRES_URL starts a server of its own, each on its own port.
    """
    url = os.environ.get("DYNIA_TEST_POSTGRES_URL")
    if url:
        yield url
        return
    # Under /tmp, not pytest's tmp_path: as root the cluster belongs to the postgres user, who must reach it.
    directory = tempfile.mkdtemp(prefix="dynia-postgres.", dir="/tmp")
    started = subprocess.run([POSTGRES_SCRIPT, "start", directory], capture_output=True, text=True)
    if started.returncode != 0:
        shutil.rmtree(directory, ignore_errors=True)
        if started.returncode == NO_POSTGRES_SERVER:
            # The script's one line says which binaries are missing and how to install them.
            pytest.skip(f"no PostgreSQL server to test against: {started.stderr.strip()}")
        pytest.fail(f".ci/postgres start failed (exit {started.returncode}):\n{started.stderr}", pytrace=False)
    try:
        yield started.stdout.strip()
    finally:
        subprocess.run([POSTGRES_SCRIPT, "stop", directory], check=True)


@pytest.fixture(params=["sqlite", "postgresql"])
def database_url(request, tmp_path):
    """A fresh, empty database for one test, as a SQLAlchemy URL: an SQLite file, and a database on the session's
    PostgreSQL server (postgres_url).

    The PostgreSQL one is made for the test under a unique name, so that tests (and pytest-xdist workers) sharing a
    server never meet, and dropped after it, connections still open or not.
    """
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path}/plant.db"
        return
    import sqlalchemy as sa
    from sqlalchemy.pool import NullPool

    server = sa.make_url(request.getfixturevalue("postgres_url"))
    name = f"dynia_test_{uuid.uuid4().hex}"
    # CREATE and DROP DATABASE cannot run inside a transaction; from the maintenance database, not template1, which
    # CREATE DATABASE copies and so wants nobody connected to.
    admin = sa.create_engine(server.set(database="postgres"), isolation_level="AUTOCOMMIT", poolclass=NullPool)
    try:
        with admin.connect() as connection:
            connection.execute(sa.text(f'CREATE DATABASE "{name}"'))
        try:
            yield server.set(database=name).render_as_string(hide_password=False)
        finally:
            with admin.connect() as connection:
                connection.execute(sa.text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
    finally:
        admin.dispose()
