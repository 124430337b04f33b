"""A window's behavioural set and order statistics, found by selection: no sort, which cannot change their value.

A window's costs are ``(sums / present)^2``. Its behavioural threshold,
the count-th smallest cost (and every Monte Carlo batch's), and the noise
floor's quantile are found by selection among the few costs within a
bracket around the previous window's value, which a counting pass finds
(:func:`select_near`, moved outward when it misses). A window's first pass
counts for both at once on the sums, with no cost formed (a cost grows with
its sum's magnitude, so each cost bound is carried to the sums exactly,
once a window: :func:`sum_limits`), and one more gathers the few costs each needs, forming
only those (:func:`gather_costs`); a miss of both forms every cost
(:func:`form_costs`);
the behavioural set is then the first ``count`` of a stable sort of the
costs, ties to the lowest indices (:func:`behavioural`). The limits and
median of a small set are order statistics of its values
(:func:`order_statistics`); a large set's are counted through the samples'
ranks instead (:mod:`dynia.engine.kernels.ranks`).
"""

import numpy as np

from .bits import ONE, lowest_set_bit, mark_at_most, mark_between
from .compile import inner, jit

__all__ = [
    "cost_of",
    "form_costs",
    "sum_bound",
    "sum_bracket",
    "sum_limits",
    "tied_cost",
    "first_candidates",
    "count_costs",
    "gather_costs",
    "threshold_ranks",
    "reserve_bound",
    "widened",
    "beside",
    "find_candidates",
    "open_bracket",
    "select_near",
    "select_within",
    "next_bracket",
    "behavioural",
    "order_statistics",
]

# A window's behavioural threshold and quantile are searched first within a bracket around the previous
# window's (select_near): its half-width thrice the last change, at least NARROWEST of the value, at most
# WIDEST, and holding at most about BRACKET_RANKS values either side at the last window's density of values
# there (a threshold's bracket fewer when its set is small: threshold_ranks).
# A miss moves the bracket and widens it fourfold, RETRIES times, each a counting pass; the bench's record and
# thesis example 1 need 0.1 to 1 such moves a window on average.
NARROWEST, WIDEST = 0.002, 0.5
BRACKET_RANKS = 128
RETRIES = 3
# More values than this within a bracket are first checked for being all the same, which no selection then needs.
CROWDED = 1024

# The smallest positive and the largest double, where a sum bound's search starts and stops.
_SMALLEST, _LARGEST = 5e-324, 1.7976931348623157e308

# Order statistics this close to either end (a batch's limits: the 3rd smallest and 4th largest of 50 at 90 %)
# are kept in a short sorted buffer in one pass, cheaper than a selection's unpredictable branches.
_FEW = 12


@inner
def cost_of(total, present):
    """A window's cost from one sample's error sum ``total`` over its ``present`` measured points: the squared MAE."""
    mae = total / present
    return mae * mae


@jit
def form_costs(sums, present, cost):
    """Every sample's cost, ``cost`` = (sums / present)^2: what a selection among every cost needs (a miss)."""
    for s in range(cost.shape[0]):
        cost[s] = cost_of(sums[s], present)


@inner
def sum_bound(bound, present):
    """The largest error sum whose cost is at most ``bound``: ``abs(sum) <= it`` exactly when ``cost_of(sum) <= bound``.

    A cost grows with the sum's magnitude (each rounding is monotone, and
    a sum and its negative give the same cost), so the sums at or below a
    cost ``bound`` are those up to one value. It is searched from the
    square root: by steps that double until a sum on the other side is met,
    then by halving the gap; a few steps, a hundred at most (where costs are
    subnormal, many sums share one). -inf where no sum qualifies (a
    negative bound), inf for an infinite bound, NaN for a NaN one (nothing
    qualifies). ``present`` is positive.
    """
    if bound != bound or bound == np.inf:
        return bound
    if bound < 0:
        return -np.inf
    # A zero bound starts where the smallest cost would: its answer lies below, among sums whose square underflows.
    guess = np.sqrt(max(bound, _SMALLEST)) * present
    if cost_of(guess, present) <= bound:
        low, high = guess, _first_beyond(guess, bound, present, True)
    else:
        low, high = _first_beyond(guess, bound, present, False), guess
    # low qualifies and high does not: halve the gap until they are neighbours.
    following = np.nextafter(low, np.inf)
    while following < high:
        middle = low + (high - low) * 0.5
        middle = middle if low < middle < high else following
        if cost_of(middle, present) <= bound:
            low = middle
        else:
            high = middle
        following = np.nextafter(low, np.inf)
    return low


@inner
def _first_beyond(start, bound, present, upward):
    """A sum past which the cost crosses ``bound``, from ``start``: the first of steps doubling from one unit in the
    last place, upward to a cost above ``bound`` (the largest double at most), or downward to one at most ``bound``
    (0 at least, whose cost is 0)."""
    step = abs(np.nextafter(start, np.inf if upward else -np.inf) - start)
    while True:
        if upward:
            trial = min(start + step, _LARGEST)
            if trial == _LARGEST or cost_of(trial, present) > bound:
                return trial
        else:
            trial = max(start - step, 0.0)
            if trial == 0.0 or cost_of(trial, present) <= bound:
                return trial
        step *= 2


@inner
def sum_bracket(bracket, present):
    """``bracket`` = (low, high) of costs carried to the sums: (s_low, s_high) with cost within it exactly when
    ``s_low < abs(sum) <= s_high``. A cost below ``low`` is one at most the double before it."""
    low, high = bracket
    return sum_bound(np.nextafter(low, -np.inf), present), sum_bound(high, present)


@inner
def tied_cost(sums, present):
    """The cost of every sample when all the window sums have one finite magnitude, else NaN: a window of ties.

    Such a window (every simulation settled to the same output, as when a
    record rests at zero) needs no selection: its threshold and quantile
    are that cost and its behavioural set the first samples. The first 64
    sums decide at once for the windows that differ, nearly all of them.
    Only sums of one magnitude count as ties; sums that differ but round to
    one cost are left to the selections, which find the same.
    """
    n = sums.shape[0]
    size = abs(sums[0])
    if not np.isfinite(size):
        return np.nan
    head = min(n, 64)
    alike = 0
    for s in range(head):
        alike += abs(sums[s]) == size
    if alike < head:
        return np.nan
    for s in range(head, n):
        alike += abs(sums[s]) == size
    return cost_of(size, present) if alike == n else np.nan


@inner
def first_candidates(cost, count, candidates):
    """The first ``count`` samples as the candidates, all of cost ``cost``, into ``candidates`` = (indices, costs).

    Where every sample ties they are the behavioural set, as a stable sort takes ties. Returns ``count``.
    """
    indices, costs = candidates
    for s in range(count):
        indices[s] = s
        costs[s] = cost
    return count


@jit
def sum_limits(bounds, brackets, present):
    """Two cost ``bounds`` and two cost ``brackets`` carried to the sums over ``present`` points, once a window.

    Returns ((bound, reserve), ((low, high), (wide_low, wide_high))) on the
    sums' magnitudes (:func:`sum_bound`, :func:`sum_bracket`): what
    :func:`count_costs` counts against and :func:`gather_costs` gathers
    within, so that neither pass searches a limit again.
    """
    at_most = (sum_bound(bounds[0], present), sum_bound(bounds[1], present))
    return at_most, (sum_bracket(brackets[0], present), sum_bracket(brackets[1], present))


@jit
def count_costs(sums, limits):
    """A window's costs, (sums / present)^2, counted against two bounds and two brackets, in one pass over the sums.

    ``limits`` are :func:`sum_limits`' of the bounds (bound, reserve),
    guesses at or above the behavioural threshold, and of the brackets
    ((low, high), (wide_low, wide_high)), where the noise floor's quantile
    is looked for (see :func:`open_bracket`). Returns (at or below bound, at
    or below reserve, below low, within (low, high), below wide_low, within
    the wide bracket): enough to know which gathering
    (:func:`gather_costs`) holds what each selection needs. The costs are
    not formed: the pass compares the sums' magnitudes with the limits, no
    division; no branch, so that the counts vectorise.
    """
    (bound, reserve), ((low, high), (wide_low, wide_high)) = limits
    under_bound, under_reserve, below, up_to_high, wide_below, up_to_wide_high = 0, 0, 0, 0, 0, 0
    for s in range(sums.shape[0]):
        size = abs(sums[s])
        under_bound += size <= bound
        under_reserve += size <= reserve
        below += size <= low
        up_to_high += size <= high
        wide_below += size <= wide_low
        up_to_wide_high += size <= wide_high
    # A bracket's low is at most its high (open_bracket, widened), so what lies within is what is at or below the
    # high less what is below the low (at or below the low's sum bound): a comparison a count fewer than both ends.
    return under_bound, under_reserve, below, up_to_high - below, wide_below, up_to_wide_high - wide_below


@jit
def gather_costs(window_sums, limits, candidates, within, kept):
    """Every cost at or below a bound into ``candidates`` = (indices, costs), and every one within a bracket.

    ``limits`` = (bound, (low, high)) carried to the sums' magnitudes
    (:func:`sum_bound`, :func:`sum_bracket`; NaN keeps nothing). The costs
    of ``window_sums`` = (sums, present), formed for these only
    (:func:`cost_of`); both in index order: the candidates as
    :func:`find_candidates` keeps them, the costs within the bracket into
    ``within`` as :func:`select_near` gathers them. Returns how many of
    each. ``kept``, about how many that will be (:func:`count_costs` tells),
    chooses the loop. When few, a word of bits marks each 64 sums' keepers
    (:mod:`~dynia.engine.kernels.bits`) and only those are written: a branch
    per sample mispredicts whenever about one in ten is kept (a tenth
    behavioural). When many (a window of near ties, as a record resting at
    zero makes), every cost is written and kept by counting it: visiting
    thousands of set bits one by one costs more.
    """
    if 4 * kept >= window_sums[0].shape[0]:
        return _write_every(window_sums, limits, candidates, within)
    return _write_marked(window_sums, limits, candidates, within)


@inner
def _write_every(window_sums, limits, candidates, within):
    """:func:`gather_costs` writing every cost, each kept by counting it: no branch.

    ``limits`` as there: on the sums' magnitudes.
    """
    sums, present = window_sums
    indices, costs = candidates
    bound, (low, high) = limits
    found, inside = 0, 0
    for s in range(sums.shape[0]):
        size = abs(sums[s])
        value = cost_of(size, present)
        indices[found] = s
        costs[found] = value
        found += size <= bound
        within[inside] = value
        inside += (size > low) & (size <= high)
    return found, inside


@inner
def _write_marked(window_sums, limits, candidates, within):
    """:func:`gather_costs` writing the costs each word of bits marks, 64 samples to a word; ``limits`` as there."""
    # The loops stay in this one function: a helper that numba calls, not inlines, counts references on every call.
    sums, present = window_sums
    indices, costs = candidates
    bound, bracket = limits
    n = sums.shape[0]
    whole = n - n % 64
    found, inside = 0, 0
    for base in range(0, whole, 64):
        word = mark_at_most(sums[base : base + 64], bound)
        while word:
            s = base + lowest_set_bit(word)
            indices[found] = s
            costs[found] = cost_of(sums[s], present)
            found += 1
            word &= word - ONE
        word = mark_between(sums[base : base + 64], bracket)
        while word:
            within[inside] = cost_of(sums[base + lowest_set_bit(word)], present)
            inside += 1
            word &= word - ONE
    low, high = bracket
    for s in range(whole, n):
        size = abs(sums[s])
        if size <= bound:
            indices[found] = s
            costs[found] = cost_of(size, present)
            found += 1
        if (size > low) & (size <= high):
            within[inside] = cost_of(size, present)
            inside += 1
    return found, inside


@inner
def threshold_ranks(count):
    """The ranks a behavioural threshold's bracket holds either side, at most: ``BRACKET_RANKS``, or four times
    ``count`` when that is fewer (a small set's candidates are then few too)."""
    return min(BRACKET_RANKS, 4 * count)


@inner
def reserve_bound(bound, bracket):
    """A second guess at or above the threshold, for when ``bound`` proves below it: the threshold's ``bracket``'s
    top moved up by four of its widths, from ``bound``; NaN when either is."""
    return bound + 4 * _search_width(bracket)


@inner
def widened(bracket):
    """``bracket`` = (low, high) with four times its width added either side (as a missed search moves)."""
    low, high = bracket
    width = _search_width(bracket)
    return low - 4 * width, high + 4 * width


@inner
def beside(bracket, lower):
    """Where a search that missed ``bracket`` = (low, high) looks next: four of its widths below it (``lower``), or
    above it, as :func:`select_near` moves."""
    low, high = bracket
    width = _search_width(bracket)
    return (low - 4 * width, low) if lower else (high, high + 4 * width)


@inner
def _search_width(bracket):
    """The width by which a search moves on from ``bracket`` = (low, high): its own, at least ``NARROWEST`` of it."""
    low, high = bracket
    return max(high - low, NARROWEST * max(abs(low), abs(high)))


@inner
def _select(values, length, k):
    """Rearrange ``values[:length]`` so that position k holds its k-th smallest; return it.

    Hoare partitioning around a median of three: equal values are spread
    over both sides, so long runs of ties (all samples simulating 0) stay
    O(length).
    """
    low, high = 0, length - 1
    while high > low:
        middle = (low + high) // 2
        a, b, d = values[low], values[middle], values[high]
        pivot = max(min(a, b), min(max(a, b), d))
        i, j = low, high
        while i <= j:
            while values[i] < pivot:
                i += 1
            while values[j] > pivot:
                j -= 1
            if i <= j:
                values[i], values[j] = values[j], values[i]
                i += 1
                j -= 1
        if k <= j:
            high = j
        elif k >= i:
            low = i
        else:
            break
    return values[k]


@jit
def find_candidates(cost, first, stride, count, bound, candidates):
    """Indices (ascending) of the samples first, first + stride, ... whose cost is at or below ``bound``.

    Written into ``candidates`` = (indices, their costs); returns how many. ``bound`` is a guess at
    or above the count-th smallest of these costs (a bracket's top): when
    at least ``count`` costs lie at or below it, the behavioural set is
    among them; otherwise (or when ``bound`` is NaN) every one of the
    samples is a candidate.
    """
    n = cost.shape[0]
    indices, costs = candidates
    found = 0
    if bound == bound:  # not NaN
        # Branch-free: every index is written, and kept (by counting it) when its cost is at or below the bound.
        for s in range(first, n, stride):
            indices[found] = s
            costs[found] = cost[s]
            found += cost[s] <= bound
    if found < count:
        found = 0
        for s in range(first, n, stride):
            indices[found] = s
            costs[found] = cost[s]
            found += 1
    return found


@inner
def open_bracket(bracket):
    """``bracket`` = (low, high) as the selections search it first: everything, (-inf, inf), when it is NaN."""
    low, high = bracket
    if not low <= high:
        return -np.inf, np.inf
    return low, high


@jit
def select_near(values, n, k, bracket, scratch):
    """The k-th smallest (0-based) of ``values[:n]``, searched first within ``bracket`` = (low, high).

    A pass counts the values below and within the bracket; when the answer
    lies within, the few values there are copied to ``scratch`` and
    selected. Otherwise the bracket moves to the side of the answer,
    fourfold wider, up to ``RETRIES - 1`` times, then reaches to that
    side's infinity, so the answer is always found (a NaN bracket starts
    there). Returns it and the values' density near it, the count within
    the last bracket over its width (0 when that is infinite or none), for
    :func:`next_bracket`.
    """
    low, high = open_bracket(bracket)
    for attempt in range(RETRIES + 1):
        below = 0
        inside = 0
        for i in range(n):
            below += values[i] < low
            inside += (values[i] >= low) & (values[i] <= high)
        if below <= k < below + inside:
            break
        width = _search_width((low, high))
        if k < below:
            low, high = (low - 4 * width if width > 0 and attempt < RETRIES - 1 else -np.inf), low
        else:
            low, high = high, (high + 4 * width if width > 0 and attempt < RETRIES - 1 else np.inf)
    return select_within(values, n, k, (low, high), (below, inside), scratch, False)


@inner
def select_within(values, n, k, bracket, counted, scratch, gathered):
    """The k-th smallest of ``values[:n]``, which lies within ``bracket``; and the values' density there.

    ``counted`` = (below, inside), how many values lie below the bracket
    and within it. The values within are in ``scratch[:inside]``, in index
    order, when ``gathered``; otherwise they are copied there first.
    Returns what :func:`select_near` returns.
    """
    low, high = bracket
    below, inside = counted
    density = inside / (high - low) if high > low else 0.0
    if inside > CROWDED:
        # Every value within may be the same (samples that simulate alike, as all do once a record rests at zero).
        smallest, largest = np.inf, -np.inf
        for i in range(inside if gathered else n):
            value = scratch[i] if gathered else values[i]
            within = (value >= low) & (value <= high)
            smallest = min(smallest, value if within else np.inf)
            largest = max(largest, value if within else -np.inf)
        if smallest == largest:
            return smallest, density
    if not gathered:
        taken = 0
        # Branch-free: every value is written, and kept (by counting it) when it is within the bracket.
        for i in range(n):
            scratch[taken] = values[i]
            taken += (values[i] >= low) & (values[i] <= high)
    return _select(scratch, inside, k - below), density


@jit
def next_bracket(value, previous, density, ranks):
    """(low, high) in which to look first for the next window's value, from ``value`` and the last two.

    ``density`` is :func:`select_near`'s, values per unit near ``value``;
    the bracket holds about ``ranks`` values either side at that density,
    at most.
    """
    change = abs(value - previous)
    width = max(3.0 * change, NARROWEST * value) if change == change else WIDEST * value
    if density > 0:
        width = min(width, ranks / density)
    width = min(width, WIDEST * value)
    return value - width, value + width


@jit
def behavioural(count, candidates, found, threshold, selected, chosen):
    """Indices (ascending) of the first ``count`` of a stable ascending sort of the costs, into ``selected``.

    ``candidates`` = (indices, costs): ``indices[:found]`` (ascending) hold
    every index of a cost at or below ``threshold``, the count-th smallest
    cost, and ``costs`` theirs, side by side so that they are read in order.
    Of the costs tied with the threshold, the lowest indices are taken.
    Their costs go to ``chosen``, in the same order.
    """
    indices, costs = candidates
    below = 0
    for i in range(found):
        below += costs[i] < threshold
    ties = count - below
    taken = 0
    for i in range(found):
        s = indices[i]
        value = costs[i]
        if value < threshold or (value == threshold and ties > 0):
            if value == threshold:
                ties -= 1
            selected[taken] = s
            chosen[taken] = value
            taken += 1
            if taken == count:  # the costs below the threshold are among them: no later one can be
                break


@inner
def _keep(buffer, size, seen, value, larger):
    """Insert ``value``, the ``seen``-th value met, into ``buffer[:size]``: the smallest met so far, ascending.

    With ``larger`` the largest met so far, descending. Returns nothing; the
    value is dropped when the buffer is full and it would come last.
    """
    if seen < size or (value > buffer[size - 1] if larger else value < buffer[size - 1]):
        j = min(seen, size - 1) - 1
        while j >= 0 and (buffer[j] < value if larger else buffer[j] > value):
            buffer[j + 1] = buffer[j]
            j -= 1
        buffer[j + 1] = value


@inner
def _extreme_order_statistics(values, count, first, last, scratch):
    """The ``first``-th smallest and ``last``-th smallest of ``values[:count]``, both within ``_FEW`` of an end.

    One pass keeps the first + 1 smallest values (ascending, in
    ``scratch[:first + 1]``) and the count - last largest (descending, after
    them); returns (lower, upper, NaN) as :func:`order_statistics` does.
    """
    small, large = first + 1, count - last
    low = scratch[:small]
    high = scratch[small : small + large]
    for i in range(count):
        _keep(low, small, i, values[i], False)
        _keep(high, large, i, values[i], True)
    return low[small - 1], high[large - 1], np.nan


@inner
def order_statistics(values, count, positions, with_median, scratch):
    """The ``positions[0]``-th and ``positions[1]``-th smallest of ``values[:count]``, and the median's if asked.

    The median's position is ``(count - 1) // 2``, between the two (NaN when
    not asked). Found in one copy, ``scratch``, so that ``values`` stays as
    it is: the selection leaves nothing larger before its answer and
    nothing smaller after, so the upper is searched after the lower only, and
    the median between the two.
    """
    first, last = positions[0], positions[1]
    if not with_median and first < _FEW and count - 1 - last < _FEW:
        return _extreme_order_statistics(values, count, first, last, scratch)
    for i in range(count):
        scratch[i] = values[i]
    lower = _select(scratch, count, first)
    upper = lower if last == first else _select(scratch[first + 1 :], count - first - 1, last - first - 1)
    middle = np.nan
    if with_median:
        k = (count - 1) // 2
        if k == first:
            middle = lower
        elif k == last:
            middle = upper
        else:
            middle = _select(scratch[first + 1 : last], last - first - 1, k - first - 1)
    return lower, upper, middle
