"""Plot decimation: extremes and gaps survive, sizes are bounded, short records are untouched."""

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)
from matplotlib.collections import QuadMesh  # noqa: E402

from dynia import DyniaResult  # noqa: E402
from dynia.cli.figures import plot_data
from dynia.decimation import decimated_columns, envelope  # noqa: E402
from dynia.errors import DataError, SettingsError  # noqa: E402

# An all-NaN bucket must not trip numpy's "All-NaN slice" warnings, nor a plot any other.
pytestmark = pytest.mark.filterwarnings("error")


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _walk(n_steps, seed=0):
    return np.cumsum(np.random.default_rng(seed).normal(size=n_steps))


def test_envelope_worked_example():
    values = np.array([0.0, 5.0, 1.0, 1.0, np.nan, np.nan, np.nan, np.nan, 2.0, -3.0])
    time, drawn = envelope(np.arange(10.0) * 2, values, max_points=6)
    np.testing.assert_array_equal(time, [0.0, 2.0, 8.0, 8.0, 16.0, 18.0])
    np.testing.assert_array_equal(drawn, [0.0, 5.0, np.nan, np.nan, 2.0, -3.0])


@pytest.mark.parametrize("n_steps, max_points", [(100_000, 4000), (100_003, 4000), (4001, 4000), (999, 7)])
def test_envelope_keeps_global_extremes_at_their_times_and_is_bounded(n_steps, max_points):
    time = 0.5 * np.arange(n_steps)
    values = _walk(n_steps)
    values[n_steps // 3] = 1e6  # a one-step spike
    values[-1] = -1e6  # in the last, possibly shorter, bucket
    drawn_time, drawn = envelope(time, values, max_points=max_points)
    assert drawn.size == drawn_time.size <= max_points
    assert drawn.max() == 1e6 and drawn_time[np.argmax(drawn)] == time[n_steps // 3]
    assert drawn.min() == -1e6 and drawn_time[np.argmin(drawn)] == time[-1]
    assert np.all(np.diff(drawn_time) >= 0)
    # Every point drawn is a real (time, value) pair of the series.
    steps = np.searchsorted(time, drawn_time)
    np.testing.assert_array_equal(values[steps], drawn)


def test_envelope_keeps_nan_gaps_and_skips_scattered_nan():
    n_steps = 100_000
    time = np.arange(n_steps, dtype=float)
    values = _walk(n_steps)
    values[40_000:41_000] = np.nan  # 1000 steps, several 50-step buckets
    values[::7] = np.nan  # scattered missing points must not blank whole buckets
    drawn_time, drawn = envelope(time, values)
    missing = np.isnan(drawn)
    assert missing.any()
    assert np.all((drawn_time[missing] >= 40_000) & (drawn_time[missing] < 41_000))
    # Buckets are 50 steps wide and the gap covers 20 of them exactly: two NaN points each.
    assert missing.sum() == 40
    assert np.nanmax(drawn) == np.nanmax(values) and np.nanmin(drawn) == np.nanmin(values)


@pytest.mark.parametrize("n_steps", [1, 2, 3999, 4000])
def test_envelope_leaves_short_series_unchanged(n_steps):
    time = np.linspace(0.0, 7.0, n_steps)
    values = _walk(n_steps)
    values[n_steps // 2] = np.nan
    drawn_time, drawn = envelope(time, values)
    assert drawn_time is time and drawn is values


def test_envelope_checks_its_arguments():
    with pytest.raises(DataError):
        envelope(np.arange(5.0), np.arange(4.0))
    with pytest.raises(DataError):
        envelope(np.arange(5.0), np.ones((5, 1)))
    with pytest.raises(SettingsError):
        envelope(np.arange(5.0), np.arange(5.0), max_points=1)


def test_decimated_columns_is_the_bucket_maximum_per_row():
    rng = np.random.default_rng(3)
    n_rows, n_steps, max_columns = 5, 10_007, 100
    time = 0.1 * np.arange(n_steps)
    image = rng.uniform(size=(n_rows, n_steps))
    image[:, 3000:3500] = np.nan  # whole buckets missing
    image[2, ::3] = np.nan  # scattered missing values
    image[1, :] = np.nan  # a row without any value
    centres, columns = decimated_columns(time, image, max_columns=max_columns)
    width = 101  # ceil(10007 / 100): 99 buckets of 101 and a last one of 8
    assert columns.shape == (n_rows, 100) and centres.shape == (100,)
    for bucket in range(100):
        part = slice(bucket * width, min((bucket + 1) * width, n_steps))
        for row in range(n_rows):
            cells = image[row, part]
            expected = np.nan if np.isnan(cells).all() else np.nanmax(cells)
            np.testing.assert_array_equal(columns[row, bucket], expected)
        assert centres[bucket] == (time[part][0] + time[part][-1]) / 2
    assert np.isnan(columns[1]).all()
    assert np.isnan(columns[0, 3030 // width]) and not np.isnan(columns[0]).all()
    assert np.nanmax(columns) == np.nanmax(image)


@pytest.mark.parametrize("n_steps", [1, 2000])
def test_decimated_columns_leaves_short_images_unchanged(n_steps):
    time = np.arange(n_steps, dtype=float)
    image = np.random.default_rng(4).uniform(size=(3, n_steps))
    centres, columns = decimated_columns(time, image)
    assert centres is time and columns is image


def test_decimated_columns_checks_its_arguments():
    with pytest.raises(DataError):
        decimated_columns(np.arange(5.0), np.ones((2, 4)))
    with pytest.raises(DataError):
        decimated_columns(np.arange(5.0), np.ones(5))
    with pytest.raises(SettingsError):
        decimated_columns(np.arange(5.0), np.ones((2, 5)), max_columns=0)


def _result(n_steps, n_bins=40, seed=5):
    rng = np.random.default_rng(seed)
    time = np.arange(n_steps, dtype=float)
    ic = rng.uniform(size=(2, n_steps))
    ic[:, n_steps // 2 : n_steps // 2 + n_steps // 50] = np.nan
    lower = rng.uniform(0, 1, size=(2, n_steps))
    ci = np.stack([lower, lower + 1], axis=2)
    gradient = rng.uniform(size=(2, n_bins, n_steps))
    bin_centres = np.tile(np.linspace(0.05, 1.95, n_bins), (2, 1))
    return DyniaResult(
        names=("K", "T"),
        samples=rng.uniform(0, 2, (10, 2)),
        bounds=np.array([[0, 2.0], [0, 2.0]]),
        time=time,
        ic=ic,
        ci=ci,
        gradient=gradient,
        bin_centres=bin_centres,
        settings=dict(n=5),
    )


def _mesh(ax):
    meshes = [artist for artist in ax.collections if isinstance(artist, QuadMesh)]
    assert len(meshes) == 1
    return meshes[0]


def test_result_plots_of_a_long_record_are_bounded():
    result = _result(100_000)
    ax = result.plot_information_content("T")
    assert ax.lines[0].get_xdata().size <= 4000
    assert np.nanmax(ax.lines[0].get_ydata()) == np.nanmax(result.ic[1])
    assert np.isnan(ax.lines[0].get_ydata()).any()  # the missing stretch stays a gap
    assert ax.get_xlim() == (0.0, 99_999.0)
    ax = result.plot_identifiability("T", true_value=1.0)
    for line, side in zip(ax.lines[:2], (0, 1), strict=True):
        assert line.get_xdata().size <= 4000
        assert np.min(line.get_ydata()) == result.ci[1, :, side].min()
        assert np.max(line.get_ydata()) == result.ci[1, :, side].max()
    mesh = _mesh(ax)
    assert mesh.get_array().size <= 40 * 2000
    assert mesh.get_array().max() == result.gradient[1].max()
    ax.figure.canvas.draw()


def test_result_plots_of_a_short_record_draw_every_step():
    result = _result(1500)
    ax = result.plot_information_content("K")
    np.testing.assert_array_equal(ax.lines[0].get_xdata(), result.time)
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), result.ic[0])
    ax = result.plot_identifiability("K")
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), result.ci[0, :, 0])
    np.testing.assert_array_equal(ax.lines[1].get_ydata(), result.ci[0, :, 1])
    np.testing.assert_array_equal(_mesh(ax).get_array().reshape(40, 1500), result.gradient[0])


def test_plot_data_is_bounded_and_labelled():
    n_steps = 100_000
    time = np.arange(n_steps, dtype=float)
    u = np.repeat(np.arange(100.0) % 3, 1000)
    y = _walk(n_steps)
    fig = plot_data(time, u, y, offset=2.5, xlabel="time (s)")
    top, bottom = fig.axes
    assert top.lines[0].get_xdata().size <= 4000 and bottom.lines[0].get_xdata().size <= 4000
    assert bottom.lines[0].get_ydata().max() == y.max() and bottom.lines[0].get_ydata().min() == y.min()
    assert bottom.get_ylabel() == "output\nas measured (offset 2.5)"
    assert bottom.get_xlabel() == "time (s)" and top.get_ylabel() == "input"
    short = plot_data(time[:50], u[:50], y[:50])
    np.testing.assert_array_equal(short.axes[1].lines[0].get_ydata(), y[:50])
    assert short.axes[1].get_ylabel() == "output"


def _reported_result():
    """A short result whose K has one clear highest-IC window at step 700, and its verdicts attached."""
    result = _result(1500)
    ic = np.array(result.ic)
    ic[0, 700] = 1.0
    return DyniaResult(**{**vars(result), "ic": ic})


def test_the_ic_plot_marks_the_threshold_and_the_reported_window_with_its_verdict():
    result = _reported_result()
    summary = result.summary()["K"]
    assert summary["time_of_max_ic"] == 700.0
    ax = result.plot_information_content("K")
    threshold = [line for line in ax.lines if line.get_linestyle() == ":"]
    assert len(threshold) == 1 and set(threshold[0].get_ydata()) == {0.5}
    (marker,) = [line for line in ax.lines if line.get_marker() == "o"]
    np.testing.assert_array_equal(marker.get_xdata(), [summary["time_of_max_ic"]])
    np.testing.assert_array_equal(marker.get_ydata(), [summary["max_ic"]])
    assert [text.get_text() for text in ax.texts] == [summary["verdict"]]


def test_the_identifiability_plot_has_a_colour_bar_the_estimate_and_a_labelled_reference():
    result = _reported_result()
    summary = result.summary()["K"]
    ax = result.plot_identifiability("K", true_value=0.3, true_label="calibrated")
    (colour_bar,) = [other for other in ax.figure.axes if other is not ax]
    assert colour_bar.get_ylabel() == "CLD gradient"
    (marker,) = [line for line in ax.lines if line.get_marker() == "D"]
    np.testing.assert_array_equal(marker.get_xdata(), [summary["time_of_max_ic"]])
    np.testing.assert_array_equal(marker.get_ydata(), [summary["estimate"]])
    (reference,) = [line for line in ax.lines if line.get_linestyle() == "--"]
    assert set(reference.get_ydata()) == {0.3} and reference.get_label() == "calibrated"
    default = result.plot_identifiability("K", true_value=0.3)
    assert [line.get_label() for line in default.lines if line.get_linestyle() == "--"] == ["true value"]
