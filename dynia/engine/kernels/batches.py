"""The Monte Carlo batches (``ic_error``): every batch's IC and limits read off the same window costs.

Batch b of B holds samples b, b + B, b + 2B, ...; a window's costs, formed
once for all samples, are read off each batch with its own behavioural
count, exactly as if the batch had been analysed alone (a sample's window
sums do not depend on the others'). One pass over each window's costs
finds the candidates of the population's behavioural set, the batches'
among them, and of the noise floor's quantile.
"""

import numpy as np

from .compile import inner, jit
from .ranks import batch_limits
from .readoff import analyse_window, blank_window, read_off, window_state
from .selection import behavioural, find_candidates, form_costs, next_bracket, select_near, threshold_ranks
from .sums import window_sums

__all__ = ["analyse_windows_batched"]


@jit
def analyse_windows_batched(
    rows,
    measured,
    m,
    slots,
    cost_ranks,
    samples,
    bounds,
    bins,
    limits,
    min_points,
    results,
    tracks,
    batches,
    batch_results,
):
    """:func:`~dynia.engine.kernels.readoff.analyse_windows`, and the IC and limits of every batch of samples.

    ``batches`` = (counts, positions, batch_of, at_rank): batch b of the
    ``B = counts.size`` batches holds samples b, b + B, b + 2B, ...
    (``batch_of``, every sample's batch); its behavioural set is its
    ``counts[b]`` lowest costs and ``positions[b]`` (2,) its thesis limits'
    positions; ``at_rank`` (n_params, n_samples) holds the batch of the
    sample at every rank of every parameter (see
    :func:`~dynia.engine.flavours.parameter_ranks`), fixed for a run like
    ``batch_of``. Writes ``batch_results`` = (batch_ic (B, n_params, m),
    batch_ci (B, n_params, m, 2)), each batch bit-identical to
    ``analyse_windows`` on that batch's samples alone; the window sums are
    formed once for all. ``tracks`` = (track, brackets (B, 2), last (B,)):
    ``analyse_windows``'s ``track`` and every batch's threshold bracket and
    last threshold (see ``_batch_state``), where the first window's
    selections start (NaN: nowhere) and the last window leaves them; they
    steer the work only.
    """
    # As analyse_windows's, with the batches' two after: positional, each group a tuple.
    positions, levels, weighted = limits
    counts = batches[0]
    n_batches = counts.shape[0]
    track, batch_brackets, batch_last = tracks
    window = window_state(rows.shape[1], cost_ranks[0], samples, bounds, bins, levels, weighted, track)
    cost, candidates, work = window[1], window[2], window[4]
    state = _batch_state(batches, samples[1].shape[1], batch_brackets, batch_last)
    present = 0.0
    for t in range(m):
        sums, present = window_sums(rows, measured, t, slots, present, window[0])
        if present < min_points:
            blank_window(t, results, batch_results)
            continue
        # The candidates reach the bracket's top, and every batch's, so that they hold the batches' sets too.
        bound = track[1]
        for b in range(n_batches):
            top = batch_brackets[b, 1]
            bound = max(bound, top) if top == top else bound
        found, formed, tie = analyse_window(t, (sums, present), bound, cost_ranks, positions, window, results)
        costs = (cost, (sums, present), formed, tie)
        _read_off_batches(costs, candidates, found, batches, state, window[3], t, results, batch_results, work)


@inner
def _batch_state(batches, n_samples, brackets, last):
    """What :func:`_read_off_batches` carries from window to window, for ``batches`` (see analyse_windows_batched).

    (member_candidates, member_found, brackets, last_thresholds, selected):
    the batches' candidates (indices, costs) and how many, each batch's
    bracket (see :func:`~dynia.engine.kernels.selection.next_bracket`, whose
    top bounds its candidates) and last threshold, and its behavioural set.
    The ``brackets`` and ``last`` thresholds are given, and updated in place.
    """
    counts = batches[0]
    n_batches = counts.shape[0]
    size = (n_samples + n_batches - 1) // max(n_batches, 1)
    return (
        (np.empty((n_batches, size), dtype=np.int64), np.empty((n_batches, size))),
        np.empty(n_batches, dtype=np.int64),
        brackets,
        last,
        np.empty((n_batches, counts.max() if n_batches else 0), dtype=np.int64),
    )


@inner
def _read_off_batches(costs, candidates, found, batches, state, rules, t, results, batch_results, work):
    """Every Monte Carlo batch's IC and limits at window t, from the population's ``candidates``.

    ``costs`` = (cost, window_sums, formed, tie): the window's cost array,
    its sums, whether the costs are formed in it yet, and the cost every
    sample ties at (NaN when they do not: see
    :func:`~dynia.engine.kernels.selection.tied_cost`); a batch whose
    members are not all among the candidates forms them (once a window).
    When every sample ties, each batch's set is its first members and
    nothing is dealt or selected.

    Each batch's threshold is searched as the population's is (within a
    bracket around its last,
    :func:`~dynia.engine.kernels.selection.select_near`); its thesis
    limits, order statistics of its set, are then found for all batches in
    one walk over each parameter's ranks from either end
    (:func:`~dynia.engine.kernels.ranks.batch_limits`) when the sets are
    large, else by :func:`~dynia.engine.kernels.readoff.read_off`, as are
    the weighted limits, read off each batch's CLD. ``state`` is
    :func:`_batch_state`'s, updated here; ``results`` the population's,
    whose median and gradient a batch leaves alone.
    """
    # Ten arguments: the population's candidates (three), the batches and their state, how and where to read off.
    counts, positions, batch_of, at_rank = batches
    batch_candidates, batch_found, brackets, last, selected = state
    (_, ranks, ordered), (lows, highs), weighted = rules[0], rules[1], rules[3]
    batch_ic, batch_ci = batch_results
    median, gradient = results[2], results[3]
    n_batches = counts.shape[0]
    # As for the population (see read_off): the walk over the ranks pays once the sets are a 32nd of the samples.
    by_rank = not weighted and 32 * counts.sum() >= ranks.shape[1]
    cost, window_sums, formed, tie = costs
    if tie == tie:
        _first_members(tie, counts, batch_candidates, batch_found)
    else:
        _deal_candidates(candidates, found, batch_of, batch_candidates, batch_found)
    for b in range(n_batches):
        members = (batch_candidates[0][b], batch_candidates[1][b])
        bracket = (brackets[b, 0], brackets[b, 1])
        if tie == tie:
            threshold, density = tie, 0.0
        else:
            if batch_found[b] < counts[b]:
                if not formed:
                    form_costs(*window_sums, cost)
                    formed = True
                batch_found[b] = find_candidates(cost, b, n_batches, counts[b], bracket[1], members)
            threshold, density = select_near(members[1], batch_found[b], counts[b] - 1, bracket, work[0])
        brackets[b, 0], brackets[b, 1] = next_bracket(threshold, last[b], density, threshold_ranks(counts[b]))
        last[b] = threshold
        if not by_rank:
            batch = (batch_ic[b], batch_ci[b], median, gradient)
            read_off(counts[b], members, batch_found[b], threshold, rules, positions[b], t, batch, False, work)
        else:
            behavioural(counts[b], members, batch_found[b], threshold, selected[b], work[2])
    if not by_rank:
        return
    limits = np.empty((n_batches, 2))
    for p in range(ranks.shape[0]):
        batch_limits(selected, counts, positions, ranks[p], ordered[p], at_rank[p], work[7], limits)
        for b in range(n_batches):
            batch_ci[b, p, t, 0], batch_ci[b, p, t, 1] = limits[b, 0], limits[b, 1]
            batch_ic[b, p, t] = 1 - (limits[b, 1] - limits[b, 0]) / (highs[p] - lows[p])


@inner
def _first_members(tie, counts, batch_candidates, batch_found):
    """Each batch's first ``counts[b]`` members, samples b, b + B, ..., as its candidates, all of cost ``tie``.

    Where every sample ties, they are the batch's behavioural set, as a stable sort of its costs takes ties.
    """
    batch_indices, batch_costs = batch_candidates
    n_batches = counts.shape[0]
    for b in range(n_batches):
        for i in range(counts[b]):
            batch_indices[b, i] = b + i * n_batches
            batch_costs[b, i] = tie
        batch_found[b] = counts[b]


@inner
def _deal_candidates(candidates, found, batch_of, batch_candidates, batch_found):
    """Deal the population's ``candidates`` (indices, costs) to their batches: row b of ``batch_candidates``'s.

    The population's candidates are every cost at or below its bound: a batch
    with at least its count among them has its behavioural set and every tie
    there; one with fewer searches its members against its own bound, and all
    of them if that finds too few.
    """
    indices, costs = candidates
    batch_indices, batch_costs = batch_candidates
    batch_found[:] = 0
    for i in range(found):
        s = indices[i]
        b = batch_of[s]
        batch_indices[b, batch_found[b]] = s
        batch_costs[b, batch_found[b]] = costs[i]
        batch_found[b] += 1
