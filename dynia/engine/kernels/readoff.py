"""A window's analysis: its costs, behavioural set and what is read off it (limits, median, IC, CLD gradient).

:func:`analyse_windows` forms each window's costs, from error rows by the
running sums of :mod:`dynia.engine.kernels.sums` or from the sums given,
selects its behavioural set (:mod:`dynia.engine.kernels.selection`) and
reads off limits, IC and gradient. Everything is the numpy path's
arithmetic in the same order: the likelihood total summed in index order
(as :func:`dynia.engine.cld.likelihood` does with ``cumsum``) and the
gradient accumulated in index order (as ``bincount``). The limits and
median of a large behavioural set are counted through the samples' ranks
(:mod:`dynia.engine.kernels.ranks`), a small set's found by selection.

What every window is read off by, the ``rules``, is the tuple (samples,
bounds, levels, weighted, bin_of): ``samples`` = (columns, ranks,
ordered), the samples' parameter values (n_params, n_samples), every
sample's position in the stable sort of its row of ``columns`` and the
rows sorted (see :func:`~dynia.engine.flavours.parameter_ranks`);
``bounds`` = (lows, highs), the range of each parameter; the weighted
limits' CLD levels; whether the limits are weighted; and every sample's
gradient bin per parameter.
"""

import numpy as np

from .compile import inner, jit
from .ranks import ranked_order_statistics
from .selection import (
    BRACKET_RANKS,
    behavioural,
    beside,
    count_costs,
    find_candidates,
    first_candidates,
    form_costs,
    gather_costs,
    next_bracket,
    open_bracket,
    order_statistics,
    reserve_bound,
    select_near,
    select_within,
    sum_limits,
    threshold_ranks,
    tied_cost,
    widened,
)
from .sums import window_sums

__all__ = ["analyse_windows", "window_state", "analyse_window", "read_off", "blank_window"]


@jit
def analyse_windows(rows, measured, m, slots, cost_ranks, samples, bounds, bins, limits, min_points, results, track):
    """Analyse the m windows of a block; see :mod:`dynia.engine` for the method.

    ``rows`` (m + slots - 1, n_samples) and ``measured`` (m + slots - 1,)
    are the absolute errors and measured-point flags of the window inputs
    (row j + t belongs to slot j of window t), whose window sums are formed
    here by running sums. With ``slots`` = 0 they are the window sums
    themselves, ``rows`` (m, n_samples) (from
    :meth:`~dynia.engine.kernels.driver.CompiledErrors.window_sums`), and
    each window's measured points ``measured`` (m,).
    ``cost_ranks`` = (count, upper_position): the behavioural set's size and
    the noise floor's population quantile's position (0-based) among a
    window's costs. ``samples`` = (columns, ranks, ordered) and ``bounds`` =
    (lows, highs) as in the module documentation, ``bins`` the gradient's
    bins, ``limits`` = (positions, levels, weighted): the thesis limits'
    sorted positions, the weighted limits' CLD levels and whether the limits
    are weighted. Writes ``results`` = (ic (n_params, m), ci (n_params, m,
    2), median (n_params, m), the CLD median read off as the limits are,
    gradient (n_params, bins, m), extreme_costs (3, m)), the last the
    smallest cost, the largest behavioural cost (the count-th smallest) and
    the ``upper_position``-th smallest of every window; windows with fewer
    than ``min_points`` measured points get NaN. ``track`` (6,) holds the
    brackets the first window's selections start from (see
    :func:`window_state`; NaN: none) and is left holding the last window's:
    handed on to the next block, it spares that block's first window a
    selection among every sample. It steers the work only: any start
    gives the same results.
    """
    # Numba takes no keywords nor records: the arguments stay positional, grouped as tuples where they belong together.
    positions, levels, weighted = limits
    window = window_state(rows.shape[1], cost_ranks[0], samples, bounds, bins, levels, weighted, track)
    no_batches = (np.empty((0, 1, 1)), np.empty((0, 1, 1, 2)))
    present = 0.0
    for t in range(m):
        sums, present = window_sums(rows, measured, t, slots, present, window[0])
        if present < min_points:
            blank_window(t, results, no_batches)
            continue
        analyse_window(t, (sums, present), window[5][1], cost_ranks, positions, window, results)


@inner
def window_state(n_samples, count, samples, bounds, bins, levels, weighted, track):
    """What :func:`analyse_window` works in and carries from window to window, made once a block.

    (running, cost, candidates, rules, work, track, within): the running
    sums ((high, low), total) of
    :func:`~dynia.engine.kernels.sums.window_sums`; a window's costs; its
    candidates (indices, costs); the read-off's rules (see the module
    documentation); its workspace (``_workspace``); ``track`` (given,
    updated in place), the brackets of the threshold and of the quantile
    (see :func:`~dynia.engine.kernels.selection.next_bracket`) and their
    last values, NaN before the first window of a run; and the costs within
    the quantile's bracket.
    """
    running = ((np.empty(n_samples), np.empty(n_samples)), np.empty(n_samples))
    candidates = (np.empty(n_samples, dtype=np.int64), np.empty(n_samples))
    rules = (samples, bounds, levels, weighted, _bin_indices(samples[0], bounds, bins))
    return running, np.empty(n_samples), candidates, rules, _workspace(n_samples, count), track, np.empty(n_samples)


@inner
def analyse_window(t, window_sums, bound, cost_ranks, positions, window, results):
    """Window t from its ``window_sums`` = (sums, present): its set, read-off and extreme costs, into ``results``.

    The candidates of its set are every cost up to ``bound`` (at least the
    bracket's top, which the threshold is searched within) or more
    (``_gather_window``); ``window`` is :func:`window_state`'s, whose
    brackets move on. A window whose samples all tie
    (:func:`~dynia.engine.kernels.selection.tied_cost`) takes its first
    ``count`` samples as the candidates and selects nothing. Returns how many candidates there
    were, whether every cost was formed into ``window[1]`` (only a
    selection among every cost needs them) and the tied cost (NaN when the
    samples do not all tie).
    """
    count, upper_position = cost_ranks
    _, _, candidates, rules, work, track, _ = window
    ic, ci, median, gradient, extreme_costs = results
    tie = tied_cost(*window_sums)
    if tie == tie:
        found, formed = first_candidates(tie, count, candidates), False
        # No density: the next brackets are as wide as the last change asks, which finds the next window's values.
        threshold, density, upper, quantile_density = tie, 0.0, tie, 0.0
    else:
        found, quantile_bracket, quantile_counts, formed = _gather_window(window_sums, bound, cost_ranks, window)
        threshold, density = select_near(candidates[1], found, count - 1, (track[0], track[1]), work[0])
        quantile = (quantile_bracket, quantile_counts)
        upper, quantile_density, formed = _upper_quantile(window_sums, upper_position, quantile, formed, window)
    read_off_into = (ic, ci, median, gradient)
    smallest = read_off(count, candidates, found, threshold, rules, positions, t, read_off_into, True, work)
    track[0], track[1] = next_bracket(threshold, track[4], density, threshold_ranks(count))
    track[2], track[3] = next_bracket(upper, track[5], quantile_density, BRACKET_RANKS)
    track[4], track[5] = threshold, upper
    extreme_costs[0, t] = smallest
    extreme_costs[1, t] = threshold
    extreme_costs[2, t] = upper
    return found, formed, tie


@inner
def _upper_quantile(window_sums, upper_position, quantile, formed, window):
    """The noise floor's quantile, the ``upper_position``-th smallest cost, and the density of costs near it.

    ``quantile`` = (bracket, (below, within)), :func:`_gather_window`'s;
    when the bracket holds it, the costs within were gathered (``window[6]``),
    else it is searched on from the bracket's side among every cost, formed
    first unless ``formed``. Returns the quantile, the density and whether
    every cost is formed.
    """
    _, cost, _, _, work, _, within = window
    quantile_bracket, quantile_counts = quantile
    n_samples = cost.shape[0]
    if quantile_counts[1]:
        upper, density = select_within(cost, n_samples, upper_position, quantile_bracket, quantile_counts, within, True)
        return upper, density, formed
    # Beyond the wide bracket too: searched on from its side, among every cost.
    if not formed:
        form_costs(*window_sums, cost)
    side = beside(quantile_bracket, upper_position < quantile_counts[0])
    upper, density = select_near(cost, n_samples, upper_position, side, work[0])
    return upper, density, True


@inner
def _gather_window(window_sums, bound, cost_ranks, window):
    """The candidates of a window's behavioural set and the costs near its quantile, in two passes over its sums.

    The first counts the costs, unformed (:func:`~dynia.engine.kernels.selection.count_costs`),
    against two guesses at the threshold, ``bound`` and a reserve above it,
    and against the quantile's bracket and a wider one; the second gathers
    the candidates (``window[2]``), every cost up to the lower guess that
    holds the set, and the costs within the narrower bracket that holds the
    quantile (``window[6]``), forming those costs only. A window that
    neither guess serves (a block's first, or a jump) forms every cost
    (``window[1]``) and searches its threshold among them. Returns how many
    candidates, the quantile's bracket with the costs below and within it
    (when neither bracket holds the quantile, the wide one with none
    within), and whether every cost was formed.
    """
    count, upper_position = cost_ranks
    _, cost, candidates, _, work, track, within = window
    bounds = (bound, reserve_bound(bound, (track[0], track[1])))
    narrow = open_bracket((track[2], track[3]))
    wide = widened(narrow)
    at_most, brackets = sum_limits(bounds, (narrow, wide), window_sums[1])
    counted = count_costs(window_sums[0], (at_most, brackets))
    if counted[2] <= upper_position < counted[2] + counted[3]:
        quantile_bracket, quantile_counts, gathered = narrow, (counted[2], counted[3]), brackets[0]
    elif counted[4] <= upper_position < counted[4] + counted[5]:
        quantile_bracket, quantile_counts, gathered = wide, (counted[4], counted[5]), brackets[1]
    else:
        quantile_bracket, quantile_counts, gathered = wide, (counted[4], 0), (np.nan, np.nan)
    if counted[0] >= count:
        gather_bound, kept = at_most[0], counted[0]
    else:  # the reserve, else nothing (NaN): the costs are then searched among all, below
        gather_bound, kept = (at_most[1] if counted[1] >= count else np.nan), counted[1]
    limits = (gather_bound, gathered)
    found, _ = gather_costs(window_sums, limits, candidates, within, kept + quantile_counts[1])
    if found >= count:
        return found, quantile_bracket, quantile_counts, False
    # Neither guess holds the set: its threshold is searched among every cost from above the reserve, and the
    # candidates are the costs up to it.
    form_costs(*window_sums, cost)
    above = beside((track[0], bounds[1]), False)
    first_threshold, _ = select_near(cost, cost.shape[0], count - 1, above, work[0])
    found = find_candidates(cost, 0, 1, count, first_threshold, candidates)
    return found, quantile_bracket, quantile_counts, True


@inner
def read_off(count, candidates, found, threshold, rules, positions, t, results, whole, work):
    """Behavioural set of one window and what it gives: ``results`` = (ic, ci, median, gradient) at t.

    The set is the candidates (see
    :func:`~dynia.engine.kernels.selection.behavioural`) at or below
    ``threshold``, the count-th smallest cost, = (indices, costs), indices
    of the costs and of the columns of ``rules``' samples: a batch of
    samples is read off through candidates that are its members only.
    Without ``whole`` (a batch's read-off, whose IC and limits alone are
    used) the gradient, the median and, for the thesis limits, the
    likelihoods are left alone. The median is read off as the limits are:
    the first sorted value whose CLD reaches 0.5 (``weighted``), or the
    value at sorted position ``(count - 1) // 2``, which is ``floor(0.5
    (count - 1))``. ``positions`` are the thesis limits' sorted positions
    (the population's or a batch's) and ``work`` the scratch arrays of
    ``_workspace``. Returns the smallest cost of the set (NaN where its
    likelihoods are not needed).
    """
    # Ten arguments: the set (four), how it is read off and where to, and the scratch; each a different kind.
    (columns, ranks, ordered), (lows, highs), levels, weighted, bin_of = rules
    ic, ci, median, gradient = results
    scratch, selected, chosen, weights, values, order, buffer, words = work
    n_params = columns.shape[0]
    behavioural(count, candidates, found, threshold, selected, chosen)
    # A batch's thesis limits are order statistics alone: its likelihoods are never used.
    smallest = _likelihood_weights(chosen, count, weights) if whole or weighted else np.nan
    # The walk over every sample's rank pays once the set is a 32nd of the samples.
    by_rank = whole and not weighted and 32 * count >= columns.shape[1]
    for p in range(n_params):
        if whole:
            _gradient_column(bin_of[p], selected, weights, count, gradient[p, :, t])
        if by_rank:
            ci[p, t, 0], ci[p, t, 1], median[p, t] = ranked_order_statistics(
                ranks[p], ordered[p], selected, count, positions, words
            )
        else:
            for i in range(count):
                values[i] = columns[p, selected[i]]
            if weighted:
                _stable_argsort(values, count, order, buffer)
                for side in range(2):
                    ci[p, t, side] = _cld_read_off(values, weights, order, count, levels[side])
                if whole:
                    median[p, t] = _cld_read_off(values, weights, order, count, 0.5)
            else:
                ci[p, t, 0], ci[p, t, 1], middle = order_statistics(values, count, positions, whole, scratch)
                if whole:
                    median[p, t] = middle
        ic[p, t] = 1 - (ci[p, t, 1] - ci[p, t, 0]) / (highs[p] - lows[p])
    return smallest


@inner
def _likelihood_weights(chosen, count, weights):
    """``weights[:count]`` = the normalised likelihoods 1 - cost of the set's costs ``chosen``; returns the smallest.

    As :func:`dynia.engine.cld.likelihood`: shifted to be non-negative when a
    cost exceeds 1, equal when they all vanish, then divided by their total
    summed in index order.
    """
    lowest = np.inf
    smallest = np.inf
    for i in range(count):
        smallest = min(smallest, chosen[i])
        weights[i] = 1.0 - chosen[i]
        lowest = min(lowest, weights[i])
    if lowest < 0:
        for i in range(count):
            weights[i] = weights[i] - lowest
    weight_total = 0.0
    for i in range(count):
        weight_total += weights[i]
    if weight_total == 0:
        for i in range(count):
            weights[i] = 1.0
        weight_total = float(count)
    for i in range(count):
        weights[i] = weights[i] / weight_total
    return smallest


@inner
def _gradient_column(bin_of, selected, weights, count, column):
    """The likelihood mass of the set ``selected[:count]`` in each bin (``bin_of``, every sample's), into ``column``."""
    column[:] = 0.0
    for i in range(count):
        column[bin_of[selected[i]]] += weights[i]


@inner
def _bin_indices(columns, bounds, bins):
    """Every sample's bin of the gradient map, per parameter: which of ``bins`` equal bins of [low, high] holds it."""
    lows, highs = bounds
    n_params, n_samples = columns.shape
    bin_of = np.empty((n_params, n_samples), dtype=np.int64)
    for p in range(n_params):
        low, high = lows[p], highs[p]
        for s in range(n_samples):
            which = int((columns[p, s] - low) / (high - low) * bins)
            bin_of[p, s] = min(max(which, 0), bins - 1)
    return bin_of


@inner
def _stable_argsort(values, length, order, buffer):
    """``order[:length]`` = stable ascending argsort of ``values[:length]`` (bottom-up merge sort)."""
    for i in range(length):
        order[i] = i
    width = 1
    source, target = order, buffer
    while width < length:
        for start in range(0, length, 2 * width):
            middle = min(start + width, length)
            stop = min(start + 2 * width, length)
            i, j, out = start, middle, start
            while i < middle and j < stop:
                if values[source[j]] < values[source[i]]:
                    target[out] = source[j]
                    j += 1
                else:
                    target[out] = source[i]
                    i += 1
                out += 1
            while i < middle:
                target[out] = source[i]
                i += 1
                out += 1
            while j < stop:
                target[out] = source[j]
                j += 1
                out += 1
        source, target = target, source
        width *= 2
    if source is not order:
        for i in range(length):
            order[i] = source[i]


@inner
def _cld_read_off(values, weights, order, count, level):
    """The first of ``values[:count]``, sorted by ``order``, whose cumulative likelihood reaches ``level``."""
    cumulative = 0.0
    reached = 0
    for i in range(count):
        cumulative += weights[order[i]]
        if cumulative < level:
            reached += 1
    return values[order[min(reached, count - 1)]]


@inner
def _workspace(n_samples, count):
    """The scratch arrays of :func:`read_off`, made once a block.

    (scratch, selected, chosen, weights, values, order, buffer, words):
    ``scratch`` (n_samples,) for the selections, then for ``count`` values:
    the behavioural set's indices, their costs, likelihood weights and one
    parameter's values, and the stable sort's order and its buffer; and
    ``words``, zero bits for every sample
    (:func:`~dynia.engine.kernels.ranks.ranked_order_statistics`).
    """
    return (
        np.empty(n_samples),
        np.empty(count, dtype=np.int64),
        np.empty(count),
        np.empty(count),
        np.empty(count),
        np.empty(count, dtype=np.int64),
        np.empty(count, dtype=np.int64),
        np.zeros((n_samples + 63) // 64, dtype=np.uint64),
    )


@inner
def blank_window(t, results, batch_results):
    """NaN for every result of window t, which has too few measured points, and every batch's (``batch_results``)."""
    ic, ci, median, gradient, extreme_costs = results
    batch_ic, batch_ci = batch_results
    ic[:, t] = np.nan
    ci[:, t, :] = np.nan
    median[:, t] = np.nan
    gradient[:, :, t] = np.nan
    extreme_costs[:, t] = np.nan
    for b in range(batch_ic.shape[0]):
        batch_ic[b, :, t] = np.nan
        batch_ci[b, :, t, :] = np.nan
