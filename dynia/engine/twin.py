"""The compiled engine's window analysis in numpy: its numbers bit for bit, and nothing to compile.

A process's first run on the compiled engine (:mod:`dynia.engine.kernels`)
waits for numba to compile it, some 20 CPU-s, where a small run's analysis
takes well under a second. The numpy path of :mod:`dynia.engine.windows`
would spare that wait, but it sums each window left to right and so differs
from the compiled engine in the last bits of the costs, and then in the
behavioural set of a near-tied window: a user would see the results depend
on the record's size. This twin instead performs the compiled arithmetic
operation for operation, vectorised over the samples, with a Python loop
over the windows where the kernel carries something from one to the next:

- the window sums are the kernel's compensated running sums, per sample:
  TwoSum of the steps one by one, oldest first, at the first window of the
  block analysed (every chunk of the windows' pass starts afresh), then one
  step entering and one leaving, rounded once as high + low; a sum gone
  non-finite (an infinite error) is formed afresh from the window's steps,
  and plainly, left to right, when even that is not finite;
- the cost is ``mae * mae`` with ``mae = sum / points``;
- the behavioural set is the first ``count`` of a stable sort of the costs
  (ties by sample index), the threshold the count-th smallest cost and the
  noise floor's quantile the ``upper_position``-th: order statistics, whose
  values do not depend on how they are found;
- the likelihoods ``1 - cost`` are shifted, then divided by their total
  summed in index order: ``np.cumsum``, which adds one term after another,
  as the kernel does (``np.sum`` adds pairwise and would not match);
- the gradient adds each behavioural set's likelihood to its bin in index
  order (``np.bincount``, one term after another);
- the thesis limits and median are order statistics of the set's parameter
  values, read through the samples' ranks; the weighted ones are the first
  value of a stable sort whose cumulative likelihood (``np.cumsum``)
  reaches the level.

Elementwise numpy performs the same IEEE operations as the kernel, which
fuses none (no fast-math). The simulation is not here: a run on the twin
hands it the error rows of the models' numpy recursion
(:mod:`dynia.models.linear`), whose outputs are the compiled kernels' bit for
bit (the same products and sums in the same order, the same flush of tiny
states), as the error rows of any other model; the fused kernel's sums equal
those the rows give (tests/test_running_sums.py).

What the twin does not do, :func:`covers` says: the mcat flavour,
importance weights, the Monte Carlo batches of ``ic_error``, models that
simulate in compiled code (a StateSpaceModel of numba functions) and
parameter values holding a negative zero (where both zeros tie at an order
statistic, the kernel's selection may return either). ``engine="auto"``
takes it for a run it covers of at most :data:`AUTO_MOST_VALUES` samples x
steps and :data:`AUTO_MOST_STEPS` steps
(:func:`dynia.engine.flavours.chosen_engine`), ``engine="twin"`` for any
it covers. tests/test_twin.py checks it against the kernels bit for bit.
"""

import numpy as np

__all__ = ["AUTO_MOST_VALUES", "AUTO_MOST_STEPS", "AUTO_MOST_RUNS", "covers", "analyse_windows", "window_sums"]

# The largest run that engine "auto" analyses on the twin rather than on the compiled kernels: samples x steps, and
# steps, since much of a run on the twin is Python per step (the models' numpy recursion, the window sums, the
# record fit's simulations of a few sets). A whole dynia.run on the twin then costs at most about a CPU-second: on a
# first-order model 0.25 for the README's quick start (2000 x 300), 0.75 at 2000 x 1000, 0.5 at 20 000 x 100; on a
# two-state one (SecondOrderDelay) 1.2 at 2000 x 1000. The kernels take a fifth of that once compiled, but cost about
# 20 CPU-s to compile in a fresh process, or a second to load from numba's cache.
AUTO_MOST_VALUES = 2_000_000
AUTO_MOST_STEPS = 1_000
# How many analyses one process runs on the twin before "auto" takes the kernels even for small runs: ten cost about
# as much as loading the kernels from numba's cache, and a process that goes on analysing small records (a study,
# a notebook, a test suite) then runs each at a fifth of the twin's cost, for one compile at worst. "auto" also takes
# the kernels once a run of the process has loaded them. The numbers are the same either way; only the recorded
# engine differs.
AUTO_MOST_RUNS = 10

# How many analyses this process has run on the twin (dynia.engine.flavours.TwinFlavour counts them).
analyses_run = 0


def covers(flavour, params, weights=None, ic_error=False, model=None):
    """Whether the twin analyses this run as the compiled engine does, bit for bit (see the module documentation).

    Parameters
    ----------
    flavour : str
    params : ndarray (n_samples, n_params)
        The parameter sets analysed.
    weights : ndarray, optional
        Importance weights, which the twin does not take.
    ic_error : bool
        The Monte Carlo batches, which the twin does not read off.
    model : dynia.models.Model, optional
        The model simulated, when the twin's run simulates it.

    Examples
    --------
    >>> covers("thesis", np.array([[0.5, 2.0]])), covers("mcat", np.array([[0.5, 2.0]]))
    (True, False)
    >>> covers("thesis", np.array([[-0.0, 2.0]]))
    False
    """
    if flavour not in ("thesis", "weighted") or weights is not None or ic_error:
        return False
    # A StateSpaceModel of numba functions: the compiled engine simulates it with its own compiled loop.
    if getattr(model, "compiled", False):
        return False
    return not np.any(np.signbit(params) & (params == 0))


def window_sums(rows, measured, m, slots):
    """The error sums of m windows (m, n_samples) and their measured points (m,), as the compiled engine forms them.

    ``rows`` (m + slots - 1, n_samples) and ``measured`` (m + slots - 1,)
    as :func:`dynia.engine.kernels.readoff.analyse_windows` takes them: window t
    holds rows t .. t + slots - 1.

    Examples
    --------
    >>> rows = np.array([[1.0, 0.5], [2.0, 0.25], [4.0, 0.125]])
    >>> sums, present = window_sums(rows, np.ones(3), 2, 2)
    >>> sums.tolist(), present.tolist()
    ([[3.0, 0.75], [6.0, 0.375]], [2.0, 2.0])
    """
    n_samples = rows.shape[1]
    sums, present = np.empty((m, n_samples)), np.empty(m)
    high, low = np.zeros(n_samples), np.zeros(n_samples)
    points = 0.0
    # An infinite error makes the compensation NaN and, leaving, inf - inf: such sums are redone in _round.
    with np.errstate(invalid="ignore", over="ignore"):
        for j in range(slots):
            points += measured[j]
            high, carried = _two_sum(high, rows[j])
            low += carried
        for t in range(m):
            if t:
                high, first = _two_sum(high, rows[t + slots - 1])
                high, second = _two_sum(high, -rows[t - 1])
                low = low + (first + second)
                points = points + measured[t + slots - 1] - measured[t - 1]
            _round(rows[t : t + slots], high, low, sums[t])
            present[t] = points
    return sums, present


def _two_sum(a, b):
    """``a + b`` rounded and its rounding error, elementwise (Knuth's TwoSum, as the kernel's ``_two_sum``)."""
    total = a + b
    virtual = total - a
    return total, (a - (total - virtual)) + (b - virtual)


def _round(window, high, low, total):
    """``total`` = high + low; where not finite, the sum formed afresh from the ``window``'s rows (high, low updated).

    As the kernel's ``_round_sums`` and ``_window_sum``: the compensated sum
    of the rows, oldest first, or where even that is not finite their plain
    left-to-right sum, with a low part of 0.
    """
    np.add(high, low, out=total)
    bad = np.flatnonzero(~np.isfinite(total))
    if not bad.size:
        return
    rows = window[:, bad]
    afresh_high, afresh_low = np.zeros(bad.size), np.zeros(bad.size)
    for row in rows:
        afresh_high, carried = _two_sum(afresh_high, row)
        afresh_low += carried
    compensated = np.isfinite(afresh_high + afresh_low)
    plain = np.cumsum(rows, axis=0)[-1]  # left to right, one row after another
    high[bad] = np.where(compensated, afresh_high, plain)
    low[bad] = np.where(compensated, afresh_low, 0.0)
    total[bad] = high[bad] + low[bad]


def analyse_windows(rows, measured, m, slots, cost_ranks, samples, bounds, bins, limits, min_points, results, track):
    """:func:`dynia.engine.kernels.readoff.analyse_windows` in numpy: the same arguments, the same numbers written.

    ``rows`` and ``measured`` are the window inputs (``slots`` > 0) or the
    window sums and points (``slots`` = 0); every other argument and the
    outputs ``ic``, ``ci``, ``median``, ``gradient`` and ``extreme_costs``
    are as the kernel's, grouped as it groups them. ``track``, where the
    kernel's selections start, is left as it is: a sort needs no bracket.
    """
    count, upper_position = cost_ranks
    columns, ranks, ordered = samples
    lows, highs = bounds
    positions, levels, weighted = limits
    ic, ci, median, gradient, extreme_costs = results
    if slots:
        sums, present = window_sums(rows, measured, m, slots)
    else:
        sums, present = rows[:m], measured[:m]
    usable = present >= min_points
    for results in (ic, ci, median, extreme_costs):
        results[:, ~usable] = np.nan
    gradient[:, :, ~usable] = np.nan
    if not usable.any():
        return
    with np.errstate(over="ignore"):  # an MAE beyond 1e154 costs inf: the windows' pass blanks such windows
        mae = sums[usable] / present[usable, None]
        cost = mae * mae
    order = np.argsort(cost, axis=1, kind="stable")
    selected = np.sort(order[:, :count], axis=1)
    chosen = np.take_along_axis(cost, selected, axis=1)
    extreme_costs[0, usable] = chosen.min(axis=1)
    extreme_costs[1, usable] = np.take_along_axis(cost, order[:, count - 1 : count], axis=1)[:, 0]
    extreme_costs[2, usable] = np.take_along_axis(cost, order[:, upper_position : upper_position + 1], axis=1)[:, 0]
    weights = _likelihood_weights(chosen)
    bin_of = _bin_indices(columns, lows, highs, bins)
    for p in range(columns.shape[0]):
        gradient[p][:, usable] = _binned_mass(bin_of[p], selected, weights, bins)
        if weighted:
            lower, upper, middle = _weighted_read_off(columns[p][selected], weights, (*levels, 0.5))
        else:
            lower, upper, middle = _order_statistics(ranks[p], ordered[p], selected, (*positions, (count - 1) // 2))
        ci[p, usable, 0], ci[p, usable, 1], median[p, usable] = lower, upper, middle
        ic[p, usable] = 1 - (upper - lower) / (highs[p] - lows[p])


def _likelihood_weights(chosen):
    """Each row's normalised likelihoods ``1 - cost`` of the behavioural costs ``chosen`` (windows, count).

    As the kernel's ``_likelihood_weights``: shifted by the lowest when it is
    negative, divided by their total summed in index order, all equal where
    that total is 0.
    """
    weights = 1.0 - chosen
    lowest = weights.min(axis=1, keepdims=True)
    with np.errstate(invalid="ignore"):  # inf - inf where costs overflowed: those windows are blanked
        weights = np.where(lowest < 0, weights - lowest, weights)
        total = np.cumsum(weights, axis=1)[:, -1:]
        vanished = total[:, 0] == 0
        weights[vanished] = 1.0
        total[vanished] = chosen.shape[1]
        return weights / total


def _bin_indices(columns, lows, highs, bins):
    """Every sample's gradient bin per parameter (n_params, n_samples), as the kernel's ``_bin_indices``."""
    which = ((columns - lows[:, None]) / (highs - lows)[:, None] * bins).astype(np.int64)
    return np.clip(which, 0, bins - 1)


def _binned_mass(bin_of, selected, weights, bins):
    """Each window's likelihood mass per bin (bins, windows), added in index order as the kernel adds it."""
    windows = selected.shape[0]
    cells = bin_of[selected] + bins * np.arange(windows)[:, None]
    return np.bincount(cells.ravel(), weights=weights.ravel(), minlength=windows * bins).reshape(windows, bins).T


def _order_statistics(ranks, ordered, selected, positions):
    """The values at the sorted ``positions`` of each window's behavioural set, through the samples' ranks."""
    set_ranks = np.sort(ranks[selected], axis=1)
    return [ordered[set_ranks[:, position]] for position in positions]


def _weighted_read_off(values, weights, levels):
    """For each level, each window's first value, in a stable sort, whose cumulative likelihood reaches it.

    As the kernel's ``_cld_read_off``: the likelihoods added one after another in sorted order.
    """
    order = np.argsort(values, axis=1, kind="stable")
    ranked = np.take_along_axis(values, order, axis=1)
    cumulative = np.cumsum(np.take_along_axis(weights, order, axis=1), axis=1)
    last = values.shape[1] - 1
    windows = np.arange(values.shape[0])
    return [ranked[windows, np.minimum((cumulative < level).sum(axis=1), last)] for level in levels]
