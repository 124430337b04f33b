"""pandas records in dynia.distributed.run: aligned, refused and timed exactly as dynia.run does."""

import numpy as np
import pytest
from numpy.testing import assert_array_equal

import dynia
from dynia.errors import DataError, SettingsError
from dynia.models import FirstOrder

pd = pytest.importorskip("pandas")
pytest.importorskip("distributed")
from test_distributed import assert_same, client  # noqa: E402, F401  (the LocalCluster fixture of its tests)

from dynia.distributed import run  # noqa: E402  (after the skip: needs dask.distributed)

STEPS = 80
BOUNDS = {"K": (0.0, 7.0), "T": (0.0, 14.0)}
OPTIONS = dict(n_samples=300, n=4, rng=11)


@pytest.fixture(scope="module")
def record():
    """K = 2, T = 6 s sampled every 2 s, noisy; the arrays and the same on a 2 s DatetimeIndex."""
    u = dynia.synthetic.example_firstorder_input(STEPS)
    y = FirstOrder().simulate([[2.0, 6.0]], u, dt=2.0)[0] + np.random.default_rng(7).normal(0, 0.3, STEPS)
    index = pd.date_range("2024-05-01 12:00", periods=STEPS, freq="2s", tz="Europe/Berlin")
    return u, y, pd.Series(u, index), pd.Series(y, index)


@pytest.mark.slow
def test_a_2s_index_gives_dynia_runs_result_with_its_dates(client, record):  # noqa: F811
    u, y, u_frame, y_frame = record
    dated = run(u_frame, y_frame, FirstOrder(), BOUNDS, client=client, time_chunks=23, **OPTIONS)
    assert_same(dated, run(u, y, FirstOrder(), BOUNDS, client=client, dt=2.0, **OPTIONS))
    reference = dynia.run(u_frame, y_frame, FirstOrder(), BOUNDS, **OPTIONS)
    assert_same(dated, reference)
    assert dated.settings.dt == 2.0
    assert_array_equal(dated.timestamps, reference.timestamps)
    assert str(dated.timestamps[0]) == "2024-05-01T10:00:00.000000000"  # UTC
    assert dated.summary() == reference.summary()


@pytest.mark.slow
@pytest.mark.parametrize("case", ["shifted", "gap", "dt"])
def test_a_misaligned_or_gappy_record_is_refused_as_dynia_run_refuses_it(client, record, case):  # noqa: F811
    _, _, u, y = record
    dt = {}
    if case == "shifted":
        y = y.set_axis(y.index + pd.Timedelta(2, "s"))
    elif case == "gap":
        y = y.set_axis(y.index.where(np.arange(STEPS) < 30, y.index + pd.Timedelta(days=10)))
    else:
        dt = dict(dt=1.0)
    with pytest.raises((DataError, SettingsError)) as expected:
        dynia.run(u, y, FirstOrder(), BOUNDS, **dt, **OPTIONS)
    with pytest.raises(type(expected.value)) as caught:
        run(u, y, FirstOrder(), BOUNDS, client=client, **dt, **OPTIONS)
    assert str(caught.value) == str(expected.value)
