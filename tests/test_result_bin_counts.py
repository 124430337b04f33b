"""Samples per gradient bin, and the identifiability plot that divides the gradient by them."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import dynia  # noqa: E402
from dynia.result import DyniaResult  # noqa: E402


@pytest.fixture(scope="module")
def example_run():
    example = dynia.synthetic.thesis_example(1, np.random.default_rng(3))
    return dynia.run(example.u, example.y, example.model, example.bounds, n_samples=600, bins=12, rng=4)


def plotted_shading(result, name, **options):
    """The grey values drawn by ``plot_identifiability``, (n_bins, n_steps) for a short record."""
    fig, ax = plt.subplots()
    result.plot_identifiability(name, ax=ax, **options)
    shading = np.asarray(ax.collections[0].get_array()).reshape(result.gradient.shape[1:])
    plt.close(fig)
    return shading


def test_bin_counts_are_the_histogram_of_the_samples_over_the_gradient_bins(example_run):
    counts = example_run.bin_counts()
    assert counts.shape == (2, 12) and counts.dtype.kind == "i"
    for p, (low, high) in enumerate(example_run.bounds):
        by_hand, _ = np.histogram(example_run.samples[:, p], bins=np.linspace(low, high, 13))
        np.testing.assert_array_equal(counts[p], by_hand)
    assert (counts.sum(axis=1) == example_run.samples.shape[0]).all()


def test_bin_counts_of_the_mcat_flavour_go_to_the_nearest_gradient_point():
    example = dynia.synthetic.thesis_example(1, np.random.default_rng(3))
    result = dynia.run(
        example.u, example.y, example.model, example.bounds, n_samples=300, bins=5, flavour="mcat", rng=4
    )
    counts = result.bin_counts()
    assert counts.shape == result.bin_centres.shape
    for p in range(2):
        nearest = np.argmin(np.abs(result.samples[:, p, None] - result.bin_centres[p]), axis=1)
        np.testing.assert_array_equal(counts[p], np.bincount(nearest, minlength=6))


def test_per_sample_shading_is_the_gradient_over_the_share_of_samples(example_run):
    counts = example_run.bin_counts()[0]
    share = counts / counts.sum()
    expected = np.where(counts[:, None] > 0, example_run.gradient[0] / np.where(share > 0, share, 1)[:, None], 0)
    np.testing.assert_allclose(plotted_shading(example_run, "K", per_sample=True), expected)
    np.testing.assert_array_equal(plotted_shading(example_run, "K"), example_run.gradient[0])


def test_mass_that_follows_the_samples_alone_shades_every_bin_alike():
    # Three bins holding 1, 2 and 5 samples, each bin's mass its share of the samples: nothing but the sample.
    samples = np.array([[0.5], [1.5], [1.6], [2.1], [2.2], [2.5], [2.7], [2.9]])
    share = np.array([1, 2, 5]) / 8
    result = DyniaResult(
        names=("K",),
        samples=samples,
        bounds=np.array([[0.0, 3.0]]),
        time=np.arange(4.0),
        ic=np.zeros((1, 4)),
        ci=np.zeros((1, 4, 2)),
        gradient=np.tile(share[:, None], (1, 1, 4)),
        bin_centres=np.array([[0.5, 1.5, 2.5]]),
    )
    np.testing.assert_allclose(plotted_shading(result, "K", per_sample=True), 1.0)
    # The raw gradient makes the crowded bin five times as dark as the sparse one.
    assert plotted_shading(result, "K")[:, 0].tolist() == share.tolist()


def test_an_empty_bin_stays_white_per_sample():
    samples = np.array([[0.5], [2.5]])
    result = DyniaResult(
        names=("K",),
        samples=samples,
        bounds=np.array([[0.0, 3.0]]),
        time=np.arange(2.0),
        ic=np.zeros((1, 2)),
        ci=np.zeros((1, 2, 2)),
        gradient=np.full((1, 3, 2), 0.5),
        bin_centres=np.array([[0.5, 1.5, 2.5]]),
    )
    np.testing.assert_array_equal(result.bin_counts(), [[1, 0, 1]])
    np.testing.assert_array_equal(plotted_shading(result, "K", per_sample=True)[:, 0], [1.0, 0.0, 1.0])
