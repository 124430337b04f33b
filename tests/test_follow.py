"""dynia follow: a results table kept equal to the batch trailing analysis, whatever the batches and the kills.

Every test runs on SQLite and on a real PostgreSQL server (the ``database_url`` fixture of conftest.py); the
command-line tests run ``dynia follow`` as a user does, in a process of its own.
"""

import datetime
import io
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
import sqlalchemy as sa

import dynia
import dynia.follow
from dynia.errors import DataError, SettingsError
from dynia.follow import Follower, FollowerSettings
from dynia.io.csv import load_csv
from dynia.io.database import Source, connect
from dynia.settings import AnalysisSettings

MODEL = dynia.models.FirstOrder()
BOUNDS = {"K": (0.0, 7.0), "T": (0.1, 9.0)}
SAMPLES, N, SEED = 300, 5, 11
ARGS = ["--model", "first-order", "--param", "K=0:7", "--param", "T=0.1:9", "--samples", str(SAMPLES), "--n", str(N)]


def record(steps=700, seed=4, noise=0.1):
    """A first-order loop with held levels, the gain changing a third of the way in."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0, 2, steps // 25 + 1), 25)[:steps]
    y = np.empty(steps)
    third = steps // 3
    y[:third] = MODEL.simulate([[2.0, 3.0]], u[:third])[0]
    y[third:] = MODEL.simulate([[3.0, 3.0]], u, x0="zero")[0][third:]
    return u, y + rng.normal(0, noise, steps)


def wide_table(engine, name="plant", kind=sa.Float):
    table = sa.Table(name, sa.MetaData(), sa.Column("time", kind), sa.Column("u", sa.Float), sa.Column("y", sa.Float))
    table.create(engine)
    return table


def insert(engine, table, times, u, y):
    rows = [dict(time=t, u=float(a), y=None if np.isnan(b) else float(b)) for t, a, b in zip(times, u, y)]
    with engine.begin() as connection:
        connection.execute(table.insert(), rows)


def settings(**options):
    analysis = AnalysisSettings(window="trailing", n_samples=SAMPLES, n=N)
    recorded = {"--table": "plant", "--samples": SAMPLES, "--n": N, "--seed": SEED, **options}
    return FollowerSettings(options=recorded, analysis=analysis, seed=SEED)


def follower(engine, results="dynia_results", **options):
    source = Source(engine, "plant", time="time", inputs=["u"], output="y", **options)
    return Follower(engine, source, MODEL, BOUNDS, settings(), results)


def stored(engine, results="dynia_results"):
    """The results table as (n_params, n_steps) arrays in BOUNDS order, its times, and the informative flags."""
    table = sa.Table(results, sa.MetaData(), autoload_with=engine)  # typed: SQLite's date-times come back as such
    with engine.connect() as connection:
        rows = connection.execute(table.select().order_by(table.c.time, table.c.parameter)).mappings().all()
    names = sorted(BOUNDS)
    order = [names.index(name) for name in BOUNDS]

    def column(key):
        values = np.array([np.nan if row[key] is None else row[key] for row in rows], dtype=float)
        return values.reshape(-1, len(names)).T[order]

    flags = np.array([row["informative"] for row in rows]).reshape(-1, len(names))
    assert (flags == flags[:, :1]).all(), "one informative flag per step, for every parameter"
    times = [row["time"] for row in rows][:: len(names)]
    return (
        dict(ic=column("ic"), lower=column("lower"), upper=column("upper"), estimate=column("estimate")),
        times,
        flags[:, 0],
    )


def batch(u, y):
    return dynia.run(u, y, MODEL, BOUNDS, n_samples=SAMPLES, n=N, rng=SEED, window="trailing")


def assert_equal_to_batch(engine, u, y, results="dynia_results"):
    """The checked contract: every row equals the batch trailing analysis to rounding, informative included."""
    expected = batch(u, y)
    arrays, times, informative = stored(engine, results)
    assert arrays["ic"].shape == expected.ic.shape
    # Rounding: the batch engine's compiled sums against the per-step updates' numpy sums.
    for key, values in (("ic", expected.ic), ("lower", expected.ci[..., 0]), ("upper", expected.ci[..., 1])):
        np.testing.assert_allclose(arrays[key], values, rtol=1e-9, atol=1e-12, equal_nan=True, err_msg=key)
    np.testing.assert_allclose(arrays["estimate"], expected.median, rtol=1e-9, atol=1e-12, equal_nan=True)
    assert informative.tolist() == expected.informative.tolist()
    return times


def test_equal_to_the_batch_analysis_whatever_the_batches(database_url):
    engine = connect(database_url)
    u, y = record()
    table = wide_table(engine)
    insert(engine, table, np.arange(400.0), u[:400], y[:400])
    first = follower(engine)
    assert first.poll(batch_rows=90) == 400  # a backlog: the batch engine, committed 90 rows at a time
    first.judge()
    for start, stop in ((400, 401), (401, 450), (450, 700)):
        insert(engine, table, np.arange(start, stop, dtype=float), u[start:stop], y[start:stop])
        again = follower(engine)  # a new process: from the checkpoint
        assert again.poll(batch_rows=37) == stop - start
    again.judge()
    times = assert_equal_to_batch(engine, u, y)
    assert times == list(np.arange(700.0))


def test_a_failed_transaction_loses_no_step_and_doubles_none(database_url, monkeypatch):
    engine = connect(database_url)
    u, y = record(500)
    table = wide_table(engine)
    insert(engine, table, np.arange(60.0), u[:60], y[:60])
    follower(engine).poll()
    insert(engine, table, np.arange(60.0, 500.0), u[60:], y[60:])
    broken = follower(engine)
    writes = []
    original = type(broken)._write

    def dies_on_the_fourth(self, *args):
        writes.append(1)
        if len(writes) == 4:
            raise RuntimeError("killed")
        return original(self, *args)

    monkeypatch.setattr(type(broken), "_write", dies_on_the_fourth)
    with pytest.raises(RuntimeError, match="killed"):
        broken.poll(batch_rows=50)
    monkeypatch.undo()
    assert follower(engine).steps == 60 + 3 * 50  # three commits survived, the fourth rolled back
    resumed = follower(engine)
    resumed.poll(batch_rows=50)
    resumed.judge()
    assert_equal_to_batch(engine, u, y)


def test_late_rows_are_counted_and_skipped(database_url, caplog):
    engine = connect(database_url)
    u, y = record(300)
    table = wide_table(engine)
    insert(engine, table, np.arange(0.0, 300.0, 2.0), u[::2], y[::2])  # every other second
    first = follower(engine)
    first.poll()
    insert(engine, table, [11.0, 13.0], u[[11, 13]], y[[11, 13]])  # the rows between, too late
    again = follower(engine)
    assert again.poll() == 0
    with caplog.at_level("WARNING", logger="dynia.follow"):
        again.judge()  # counted with the judgement, which scans the time column
    assert again.late_rows == 2 and follower(engine).late_rows == 2
    assert "2 row(s) of plant arrived with a time at or before 298" in caplog.text


def test_a_poll_reads_what_the_table_held_as_it_began(database_url):
    """A logger faster than the follower cannot keep a poll (a cron job's --once) from ending."""
    engine = connect(database_url)
    u, y = record(400)
    table = wide_table(engine)
    insert(engine, table, np.arange(200.0), u[:200], y[:200])
    logging_on, poll_done, logged = threading.Event(), threading.Event(), [200]

    def logger():  # a row a millisecond or so, until the poll has ended (or 20 000 rows)
        while not poll_done.is_set() and logged[0] < 20_000:
            k = logged[0]
            insert(engine, table, [float(k)], u[k % 400 : k % 400 + 1], y[k % 400 : k % 400 + 1])
            logged[0] += 1
            logging_on.set()

    thread = threading.Thread(target=logger)
    thread.start()
    logging_on.wait(60)
    following = follower(engine)
    following.poll()  # the rows present: the batch engine
    following.poll(batch_rows=1)  # then a transaction a row, slower than the logger
    poll_done.set()
    thread.join()
    assert logged[0] < 20_000, "the poll went on with the rows that kept coming"
    assert 200 <= following.steps < logged[0]


def test_a_gap_is_a_gap_as_in_the_csv_reader(database_url, tmp_path):
    engine = connect(database_url)
    u, y = record(400)
    kept = np.r_[0:150, 170:400]  # 20 rows lost: more than --max-gap 5 steps
    y[[30, 31]] = np.nan  # and two missing values
    table = wide_table(engine)
    insert(engine, table, kept.astype(float)[:200], u[kept][:200], y[kept][:200])
    follower(engine).poll()
    insert(engine, table, kept.astype(float)[200:], u[kept][200:], y[kept][200:])
    last = follower(engine)
    last.poll()
    last.judge()
    lines = [f"{t:g},{float(a)!r},{'' if np.isnan(b) else repr(float(b))}" for t, a, b in zip(kept, u[kept], y[kept])]
    csv = "time,u,y\n" + "\n".join(lines) + "\n"
    data = load_csv(io.StringIO(csv), time="time", input="u", output="y", dt=1.0)
    assert data.gaps == ((150, 170),)
    assert_equal_to_batch(engine, data.u, data.y)


def test_a_long_table_gives_what_the_wide_one_gives(database_url):
    engine = connect(database_url)
    u, y = record(300)
    long = sa.Table(
        "plant",
        sa.MetaData(),
        sa.Column("time", sa.Float),
        sa.Column("tag", sa.String(16)),
        sa.Column("value", sa.Float),
    )
    long.create(engine)
    rows = [
        dict(time=float(k), tag=tag, value=float(v)) for k in range(300) for tag, v in (("FIC1", u[k]), ("TI1", y[k]))
    ]
    rows += [dict(time=float(k), tag="OTHER", value=0.0) for k in range(0, 300, 7)]  # another tag of the historian
    with engine.begin() as connection:
        connection.execute(long.insert(), rows)
    source = Source(engine, "plant", time="time", inputs=["FIC1"], output="TI1", long_format=True)
    following = Follower(engine, source, MODEL, BOUNDS, settings(), "dynia_results")
    assert following.poll(batch_rows=101) == 300
    following.judge()
    assert_equal_to_batch(engine, u, y)


def test_timestamps_stay_timestamps(database_url):
    engine = connect(database_url)
    u, y = record(250)
    start = datetime.datetime(2024, 3, 1, 6, 0, 0)
    times = [start + datetime.timedelta(seconds=2 * k) for k in range(250)]
    table = wide_table(engine, kind=sa.DateTime)
    insert(engine, table, times[:120], u[:120], y[:120])
    follower(engine).poll()
    insert(engine, table, times[120:], u[120:], y[120:])
    last = follower(engine)
    last.poll()
    last.judge()
    expected = dynia.run(u, y, MODEL, BOUNDS, n_samples=SAMPLES, n=N, rng=SEED, window="trailing", dt=2.0)
    arrays, stored_times, _ = stored(engine)
    assert stored_times == times
    np.testing.assert_allclose(arrays["ic"], expected.ic, rtol=1e-9, atol=1e-12, equal_nan=True)


def test_other_settings_are_refused_naming_the_option(database_url):
    engine = connect(database_url)
    u, y = record(100)
    insert(engine, wide_table(engine), np.arange(100.0), u, y)
    follower(engine).poll()
    source = Source(engine, "plant", time="time", inputs=["u"], output="y")
    with pytest.raises(SettingsError, match=r"started with --n 5; this command gives 7"):
        Follower(engine, source, MODEL, BOUNDS, settings(**{"--n": 7}))
    over = Follower(engine, source, MODEL, BOUNDS, settings(**{"--n": 7}), restart=True)
    assert over.steps == 0


def test_what_the_database_lacks_is_named(database_url):
    engine = connect(database_url)
    with pytest.raises(DataError, match="has no table 'plant'"):
        Source(engine, "plant", time="time", inputs=["u"], output="y")
    wide_table(engine)
    with pytest.raises(DataError, match=r"no column 'flow' \(--input\); its columns: time, u, y"):
        Source(engine, "plant", time="time", inputs=["flow"], output="y")


def test_a_url_that_is_not_one_is_one_line():
    with pytest.raises(SettingsError, match="is not a database URL"):
        connect("plant.db")
    with pytest.raises(SettingsError, match="cannot connect"):
        connect("sqlite:////no/such/folder/plant.db")


# -- the command, in processes of its own ---------------------------------------------------------------------------


def command(url, *extra):
    return [
        sys.executable,
        "-m",
        "dynia.cli",
        "follow",
        url,
        "--table",
        "plant",
        "--time",
        "time",
        "--input",
        "u",
        "--output",
        "y",
        *ARGS,
        "--seed",
        str(SEED),
        *extra,
    ]


def steps_written(engine):
    with engine.connect() as connection:
        if not sa.inspect(connection).has_table("dynia_results_steps"):
            return 0
        return connection.execute(sa.text("select count(*) from dynia_results_steps")).scalar_one()


def test_sigkill_half_way_then_again_equals_the_batch_analysis(database_url):
    engine = connect(database_url)
    u, y = record(3000)  # a transaction of 7 rows at a time
    table = wide_table(engine)
    insert(engine, table, np.arange(40.0), u[:40], y[:40])
    assert subprocess.run(command(database_url, "--once"), capture_output=True).returncode == 0
    # Half the record is there when the follower starts, and it polls for more instead of finishing: killed once it
    # has written 300 steps, it is killed half-way whatever the machine's load. (A count can wait a second or more on
    # SQLite while the follower commits; with the whole record there and --once, the follower could write all of it
    # meanwhile, and a loaded machine saw it finished before the kill.)
    insert(engine, table, np.arange(40.0, 1500.0), u[40:1500], y[40:1500])
    running = subprocess.Popen(command(database_url, "--poll", "0.2", "--batch", "7"), stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while steps_written(engine) < 300 and running.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    running.send_signal(signal.SIGKILL)
    running.wait()
    assert running.returncode == -signal.SIGKILL, "killed half-way, not finished"
    assert 300 <= steps_written(engine) <= 1500
    insert(engine, table, np.arange(1500.0, 3000.0), u[1500:], y[1500:])
    done = subprocess.run(command(database_url, "--once"), capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert_equal_to_batch(engine, u, y)


def test_sigterm_commits_and_exits_0(database_url):
    engine = connect(database_url)
    u, y = record(200)
    insert(engine, wide_table(engine), np.arange(200.0), u, y)
    running = subprocess.Popen(command(database_url, "--poll", "0.2"), stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while steps_written(engine) < 200 and time.monotonic() < deadline:
        time.sleep(0.05)
    running.send_signal(signal.SIGTERM)
    _, stderr = running.communicate(timeout=120)
    assert running.returncode == 0, stderr
    assert "K: identified" in stderr or "K: suspect" in stderr or "K: weak" in stderr  # judged before it exits
    with engine.connect() as connection:
        events = connection.execute(sa.text("select parameter, verdict from dynia_events")).all()
    assert sorted(parameter for parameter, _ in events) == ["K", "T"]


def test_started_again_with_other_settings_the_command_refuses_in_one_line(database_url):
    engine = connect(database_url)
    u, y = record(100)
    insert(engine, wide_table(engine), np.arange(100.0), u, y)
    assert subprocess.run(command(database_url, "--once"), capture_output=True).returncode == 0
    other = command(database_url, "--once", "--percentage", "20")
    refused = subprocess.run(other, capture_output=True, text=True)
    assert refused.returncode == 2
    assert refused.stderr.count("\n") == 1
    assert "started with --percentage 10.0; this command gives 20.0" in refused.stderr
    assert subprocess.run([*other, "--restart"], capture_output=True).returncode == 0


def test_a_window_given_as_a_duration(database_url):
    engine = connect(database_url)
    u, y = record(200)
    insert(engine, wide_table(engine), np.arange(200.0), u, y)
    by_duration = [word if word != "--n" else "--window" for word in command(database_url, "--once")]
    by_duration[by_duration.index("--window") + 1] = "10s"  # n = 10 s / (2 x 1 s) = 5, as --n 5
    done = subprocess.run(by_duration, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert_equal_to_batch(engine, u, y)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--poll", "0"], "--poll must lie in (0, 86400]"),
        (["--batch", "0"], "--batch must be a whole number of rows in [1, 10000000]"),
        (["--judge-every", "-1"], "--judge-every must lie in"),
    ],
)
def test_follow_options_are_checked(extra, message, tmp_path):
    refused = subprocess.run(command(f"sqlite:///{tmp_path}/plant.db", *extra), capture_output=True, text=True)
    assert refused.returncode == 2 and message in refused.stderr


TANK = dynia.models.StateSpaceModel(
    step=lambda x, u_k, p, dt: np.maximum(x + dt * (u_k - p[:, 1:2] * np.sqrt(x)) / p[:, 0:1], 0.0),
    output=lambda x, u_k, p: x[:, 0],
    x0=[1.0],
    names=["A", "c"],
    n_states=1,
)


def test_a_model_of_your_own_is_followed_and_checkpointed(database_url):
    """A state-space model of Python functions: its stepper holds the model, which no checkpoint copies."""
    engine = connect(database_url)
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(0, 2, 20), 20)
    y = TANK.simulate([[2.0, 0.5]], u)[0] + rng.normal(0, 0.01, u.size)
    table = wide_table(engine)
    bounds = {"A": (0.5, 4.0), "c": (0.1, 1.0)}
    for start, stop in ((0, 300), (300, 400)):
        insert(engine, table, np.arange(start, stop, dtype=float), u[start:stop], y[start:stop])
        source = Source(engine, "plant", time="time", inputs=["u"], output="y")
        following = Follower(engine, source, TANK, bounds, settings())
        following.poll()
    expected = dynia.run(u, y, TANK, bounds, n_samples=SAMPLES, n=N, rng=SEED, window="trailing")
    np.testing.assert_allclose(following.result().ic, expected.ic, rtol=1e-9, atol=1e-12, equal_nan=True)


def test_a_model_that_cannot_step_is_refused_in_one_line(tmp_path):
    engine = connect(f"sqlite:///{tmp_path}/plant.db")
    u, y = record(50)
    insert(engine, wide_table(engine), np.arange(50.0), u, y)
    whole = dynia.models.FunctionModel(lambda params, u, dt: params[:, :1] * u[None, :], ["K"])
    source = Source(engine, "plant", time="time", inputs=["u"], output="y")
    with pytest.raises(dynia.errors.ModelError, match="cannot step one sample at a time"):
        Follower(engine, source, whole, {"K": (0, 5)}, settings()).poll()


def test_a_backlog_too_large_for_memory_keeps_its_gradient_on_disk(tmp_path, monkeypatch):
    """The batch engine writes the gradient, which the follower does not keep, to a temporary file: same rows."""
    monkeypatch.setattr(dynia.follow, "BACKLOG_GRADIENT_BYTES", 0)
    engine = connect(f"sqlite:///{tmp_path}/plant.db")
    u, y = record(400)
    insert(engine, wide_table(engine), np.arange(400.0), u, y)
    following = follower(engine)
    following.poll()
    following.judge()
    assert_equal_to_batch(engine, u, y)


def test_iso_text_times_and_repeated_rows_averaged(database_url):
    """Times stored as ISO 8601 text, and rows repeated at a time averaged (--duplicates mean), as load_csv does."""
    engine = connect(database_url)
    u, y = record(150)
    start = datetime.datetime(2024, 3, 1, 6, 0, 0, tzinfo=datetime.timezone.utc)
    times = [(start + datetime.timedelta(seconds=k)).isoformat().replace("+00:00", "Z") for k in range(150)]
    table = wide_table(engine, kind=sa.String(32))
    insert(engine, table, times, u, y)
    insert(engine, table, times[40:41], u[40:41], y[40:41] + 1.0)  # logged twice: the mean is y + 0.5
    source = Source(engine, "plant", time="time", inputs=["u"], output="y", duplicates="mean")
    following = Follower(engine, source, MODEL, BOUNDS, settings())
    following.poll()
    following.judge()
    averaged = y.copy()
    averaged[40] += 0.5
    arrays, stored_times, _ = stored(engine)
    assert stored_times == times
    np.testing.assert_allclose(arrays["ic"], batch(u, averaged).ic, rtol=1e-9, atol=1e-12, equal_nan=True)
    with pytest.raises(DataError, match="several rows at time"):
        Follower(
            engine, Source(engine, "plant", time="time", inputs=["u"], output="y"), MODEL, BOUNDS, settings(), "other"
        ).poll()


def test_tables_that_are_not_the_followers_are_neither_filled_nor_dropped(tmp_path):
    """--results naming the source, or a table of the user's own, is refused, --restart or not: nothing is lost."""
    engine = connect(f"sqlite:///{tmp_path}/plant.db")
    u, y = record(100)
    insert(engine, wide_table(engine), np.arange(100.0), u, y)
    own = sa.Table("orders", sa.MetaData(), sa.Column("a", sa.Integer))
    own.create(engine)
    with engine.begin() as connection:
        connection.execute(own.insert(), [dict(a=1)])
    source = Source(engine, "plant", time="time", inputs=["u"], output="y")
    for results, message in (("plant", "names the source table"), ("orders", "is not a dynia follow table")):
        for restart in (False, True):
            with pytest.raises(SettingsError, match=message):
                Follower(engine, source, MODEL, BOUNDS, settings(), results, restart=restart)
    with engine.connect() as connection:
        assert connection.execute(sa.text("select count(*) from plant")).scalar_one() == 100
        assert connection.execute(sa.text("select count(*) from orders")).scalar_one() == 1
