"""A result's summary shows itself as the table dynia analyse prints: text, HTML and a pandas frame."""

import numpy as np
import pytest
from conftest import stored_record

import dynia
from dynia.models import FirstOrder
from dynia.summary import Summary, verdict_table

BOUNDS = {"K": (0, 7), "T": (0, 7)}


@pytest.fixture(scope="module")
def result():
    return dynia.run(*stored_record(), FirstOrder(), BOUNDS, n=6, n_samples=400, rng=1)


def test_the_summary_is_the_dict_it_was_and_prints_as_the_commands_table(result):
    summary = result.summary()
    assert isinstance(summary, Summary) and isinstance(summary, dict)
    assert summary["K"]["verdict"] in ("identified", "weak", "suspect")
    shown = repr(summary)
    assert shown == verdict_table(summary) == str(summary)
    lines = shown.splitlines()
    assert lines[0].split()[:3] == ["parameter", "max", "IC"]
    assert [line.split()[0] for line in lines[1:3]] == ["K", "T"]
    assert lines[1].split()[-1] == summary["K"]["verdict"]


def test_the_html_view_escapes_and_the_frame_has_a_row_per_parameter(result):
    summary = result.summary()
    page = summary._repr_html_()
    assert page.startswith("<table>") and "<th>IC&gt;=0.5</th>" in page
    frame = summary.to_frame()
    assert list(frame.index) == ["K", "T"] and frame.index.name == "parameter"
    assert frame.loc["K", "verdict"] == summary["K"]["verdict"]
    assert frame.loc["K", "max IC"] == f"{summary['K']['max_ic']:.3f}"


def test_a_daily_records_dates_print_as_days():
    """Issue 33: dates of daily records printed with T00:00:00."""
    pd = pytest.importorskip("pandas")
    u, y = stored_record()
    index = pd.date_range("2024-01-01", periods=u.size, freq="D")
    summary = dynia.run(pd.Series(u, index), pd.Series(y, index), FirstOrder(), BOUNDS, n=6, n_samples=400,
                        rng=1).summary()  # fmt: skip
    assert "T00:00:00" not in repr(summary)
    at = summary["K"]["time_of_max_ic"]
    assert np.datetime_as_string(at, unit="D") in repr(summary)
