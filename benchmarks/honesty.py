"""How honest the Monte Carlo error of IC is: predicted against seed-to-seed spread.

``dynia.run(..., ic_error=True)`` predicts, from one Monte Carlo sample,
how much the information content would change with another (``ic_se``,
batch means, see :mod:`dynia.engine.windows`). :func:`ic_error_honesty`
checks the prediction the direct way: it analyses the same record with
independent samples from ``seeds`` seeds and compares, step by step, the
standard deviation of IC across the seeds (what really happens) with the
mean predicted standard error (what the runs said would happen).

Used by ``tests/test_ic_error.py`` (the agreement must stay within a
factor 1.5 on the thesis's examples at percentage 10 and 0.1) and by
``python -m benchmarks.bench --case ic-error-honesty``, which prints the table.
"""

from dataclasses import dataclass

import numpy as np

from dynia.pipeline import run
from dynia.synthetic import thesis_example

__all__ = ["Honesty", "ic_error_honesty"]


@dataclass(frozen=True)
class Honesty:
    """Predicted and empirical Monte Carlo errors of IC over independent seeds.

    Attributes
    ----------
    names : tuple of str
    empirical : ndarray (n_params, n_steps)
        Standard deviation of IC across the seeds (ddof 1), per step.
    predicted : ndarray (n_params, n_steps)
        Mean over the seeds of the predicted standard error ``ic_se``.
    ratio : ndarray (n_params,)
        Median over the steps of ``predicted`` divided by the median over
        the steps of ``empirical``, per parameter: above 1 the prediction is
        cautious, below 1 it promises more precision than the sample has.
    stepwise_ratio : ndarray (n_params,)
        Median over the steps of ``predicted / empirical`` (steps where
        both are 0, an IC every seed agrees on, left out).
    """

    names: tuple
    empirical: np.ndarray
    predicted: np.ndarray
    ratio: np.ndarray
    stepwise_ratio: np.ndarray


def ic_error_honesty(number, percentage, n_samples, *, seeds=20, data_rng=2009, n=10):
    """Compare ``ic_se`` with the spread of IC over ``seeds`` independent Monte Carlo samples.

    Parameters
    ----------
    number : {1, 2}
        Thesis example (:func:`dynia.synthetic.thesis_example`); its record
        is drawn once from ``data_rng`` and kept for every seed.
    percentage : float
        Behavioural share, in percent.
    n_samples : int
        Monte Carlo samples of every run.
    seeds : int, default 20
        Independent runs (sampling seeds 0, 1, ..., seeds - 1).
    data_rng : numpy.random.Generator or int, default 2009
        Source of the record's noise.
    n : int, default 10
        Half window (the thesis's).

    Returns
    -------
    Honesty

    Examples
    --------
    >>> check = ic_error_honesty(1, 10, 300, seeds=4)
    >>> check.empirical.shape, check.ratio.shape
    ((2, 500), (2,))
    """
    example = thesis_example(number, data_rng)
    runs = [
        run(
            example.u,
            example.y,
            example.model,
            example.bounds,
            n_samples=n_samples,
            percentage=percentage,
            n=n,
            ic_error=True,
            rng=seed,
        )
        for seed in range(seeds)
    ]
    ic = np.stack([result.ic for result in runs])
    empirical = np.std(ic, axis=0, ddof=1)
    predicted = np.mean([result.ic_se for result in runs], axis=0)
    ratio = np.nanmedian(predicted, axis=1) / np.nanmedian(empirical, axis=1)
    both_zero = (empirical == 0) & (predicted == 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        stepwise = np.where(both_zero, np.nan, predicted / empirical)
    return Honesty(
        names=runs[0].names,
        empirical=empirical,
        predicted=predicted,
        ratio=ratio,
        stepwise_ratio=np.nanmedian(stepwise, axis=1),
    )
