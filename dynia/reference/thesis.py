"""One-to-one port of the thesis's MATLAB DYNIA (Appendix B): the reference oracle.

This module ports ``movingWindowCalcs.m``, ``runDynia.m``, ``calcLikelihood.m``,
``cumulLikelihood.m``, ``cld_gradient.m`` and ``confLimits.m`` from Appendix B of
the 2009 thesis, plus ``selectBestParameters.m``, which the thesis uses but does
not print. The functions take the same arguments in the same order and run the
same loops, so that a reader can hold the MATLAB beside the Python line by line.
It is deliberately slow and plain: the fast engine (:mod:`dynia.engine`) is
tested against it.

Time and sample indices are 0-based here where the MATLAB is 1-based; every
index computed by the MATLAB (``cli``, ``end_index``, ...) is shifted by one
and nothing else changes.

Shape convention (as in the MATLAB): ``mct`` is (ns, TIME), one simulated
output per row; ``par`` is (ns,), the samples of the one parameter analysed;
``y`` is (TIME,).

Quirks kept and deviations made
-------------------------------
::

    =====================================  =============================================
    MATLAB behaviour                       What this port does
    =====================================  =============================================
    ``movingWindowCalcs`` reads ``yn``,    Uses the argument ``y`` (the only sensible
    which it never receives (it only       reading; the example script passes the
    exists in the example script).         noise-free ``y``, this port uses whatever is
                                           passed).
    The waitbar (and its ``partitle``,     Dropped: no progress display.
    also never received).
    MATLAB's ``sum`` adds in an order of    Sums run left to right (``numpy.cumsum``),
    its own choosing.                      the order of a plain loop, so the costs
                                           can be reproduced exactly.
    Some long lines are cut off in the     Read as the mean over the points present
    printed code: the MAE of the full      (divided by ``2n+1`` and ``TIME-tStep+n+1``),
    and final windows, and the argument    and as the arguments the callee bodies use:
    lists of ``movingWindowCalcs``,        ``runDynia(ns, par, best_mat, lb, ub,
    ``runDynia`` and ``cumulLikelihood``.  bins)``, ``cumulLikelihood(ns,
                                           all_par_sorted, par_sorted,
                                           par_sorted_indices, lhood)``.
    ``best = zeros(TIME, ns*(percentage    Not stored (nothing reads it), but the port
    /100), 2)`` fails when                 raises ``ValueError`` in the same cases.
    ``ns*percentage/100`` is not an
    integer.
    Windows ``1:tStep+n`` and              Same windows, so the series must hold at
    ``tStep-n:TIME`` index outside the     least ``2n`` steps; shorter series raise
    data when ``TIME < 2n``.               ``ValueError`` instead of an index error.
    ``calcLikelihood`` uses                Kept: with ``count_max == 1`` the MATLAB
    ``length(best_mat)``, the larger       reads a second row that does not exist; the
    dimension of the (count_max, 2)        port raises ``ValueError`` (fewer than two
    matrix.                                behavioural sets).
    Likelihood ``1 - cost``, shifted by    Kept, including the 0/0 = NaN weights when
    ``-min`` only when negative, then      every behavioural cost is equal and >= 1.
    normalised.
    ``cumulLikelihood``'s second           Read as ``all_par_sorted(it) <
    ``while`` condition is cut off in      par_sorted(size)``. ``lhood_c_all`` is
    the printed code.                      computed (grown with zero fill as MATLAB
                                           does) and returned, though nothing uses it.
    ``cld_gradient`` bin width             Kept: the width is added repeatedly, so the
    ``(ub-lb)/(bins-1)``, built by         last edges drift by rounding and ``bins``
    repeated addition from ``lb + w``.     bins of that width overrun ``ub``.
    A bin's value is the CLD at its last   Kept: the first sample's weight in each bin
    sample minus the CLD at its first.     is dropped; an empty bin gets minus the next
                                           sample's weight.
    The bin holding the largest            Kept (they come out 0).
    behavioural value and the last bin.
    ``end_index = 0`` when the first       MATLAB stops with an index error; the port
    behavioural value lies exactly on an   raises ``ValueError``.
    edge (``lhood_cumulated(0)``).
    ``confLimits``: unweighted limits at   Kept, with the same floating-point
    1-based index ``floor(c*(count_max-     arithmetic (``c1 = (1-conf_level/100)/2``,
    1))+1``.                               ``c2 = 1-c1``).
    ``runDynia`` hard-codes                Kept as the default; ``conf_level`` is also
    ``conf_level = 90``.                   a keyword-only extra argument of
                                           ``run_dynia`` and ``moving_window_calcs`` so
                                           that other levels can be checked.
    ``ub == lb`` gives Inf/NaN IC and      Raises ``ValueError`` (``lb < ub`` needed).
    ``bins == 1`` an infinite width.       Raises ``ValueError`` (``bins >= 2``).
    =====================================  =============================================

The text and its code disagree
------------------------------
::

    =====================================  =============================================
    The thesis's text says                 Its code does (and this port with it)
    =====================================  =============================================
    The cost of a window is the summed     ``wCost = wMAE.^2``: the squared *mean
    squared error, SSE (sections 2.2.2,    absolute* error over the window (commented
    3 and 4.2).                            "SSE value for the window"). It ranks the
                                           samples by the L1 norm of their errors, and
                                           the likelihood ``1 - cost`` weights them by
                                           it. Kept.
    Eq. 2.3 normalises the band by "the    ``IC = 1 - (CI(2) - CI(1))/(ub - lb)``: by
    maximum and minimum acceptable values  the *sampling* range. Kept. Over the
    of the parameters in the behavioural   behavioural set's own range the IC would
    set".                                  measure the shape of the behavioural values,
                                           not their width: on example 1 a set a tenth
                                           of the range wide and one spanning all of it
                                           read about the same low IC (0.15 and 0.07;
                                           notebooks/ch2_method.py draws both).
    The uncertainty limits are read off    ``confLimits`` takes unweighted sorted
    the cumulative likelihood distribution positions ``floor(c (count-1))`` of the
    (sections 2.2.2, 2.2.3.1).             behavioural values: the likelihood never
                                           enters the limits, so neither the band nor
                                           the IC depends on it. Kept (the engine's
                                           ``"weighted"`` flavour reads the CLD).
    The simulations use ``lsim`` (section  ``example_firstorder.m`` simulates the Monte
    3).                                    Carlo sets with forward Euler, time step 1,
                                           from a state of 70 (``lsim`` is commented out
                                           as the "alternative simulation method"):
                                           ported as :func:`euler_simulation`. Its
                                           measured output comes from ``lsim`` from
                                           ``y0 = 0``: data and sets come from two
                                           different simulators.
    =====================================  =============================================

The example script, beyond the DYNIA files: :func:`euler_simulation` is its
Monte Carlo simulation loop, :func:`plot_parameter_estimation` its
identifiability plot (``pcolor`` with ``shading flat``), and
:func:`moving_window_from_costs` is ``movingWindowCalcs`` for windows whose
costs are already known, fast enough for records of tens of thousands of
steps; :func:`thesis_code_result` runs it on given simulations and packs the
result as a :class:`dynia.DyniaResult`, so that a notebook can draw what the
thesis's code draws beside what the engine computes.
"""

import math

import numpy as np

from ..errors import SettingsError

__all__ = [
    "moving_window_calcs",
    "moving_window_from_costs",
    "euler_simulation",
    "plot_parameter_estimation",
    "thesis_code_result",
    "plot_thesis_code_result",
    "check_code_path",
    "run_dynia",
    "select_best_parameters",
    "calc_likelihood",
    "cumul_likelihood",
    "cld_gradient",
    "conf_limits",
]


def moving_window_calcs(TIME, par, lb, ub, ns, mct, y, bins, percentage, n, *, conf_level=90):
    """Moving-window DYNIA for one parameter (``movingWindowCalcs.m``).

    Parameters
    ----------
    TIME : int
        Number of time steps.
    par : array_like, shape (ns,)
        Monte Carlo samples of the parameter analysed.
    lb, ub : float
        Range the parameter was sampled from.
    ns : int
        Number of Monte Carlo samples.
    mct : array_like, shape (ns, TIME)
        Simulated output of every sample.
    y : array_like, shape (TIME,)
        Measured output.
    bins : int
        Number of bins of the CLD gradient.
    percentage : float
        Percentage of the samples kept as the behavioural set of each window.
    n : int
        Half window: the window at step t holds steps t-n .. t+n.
    conf_level : float, optional
        Confidence level of the limits in percent (the MATLAB hard-codes 90).

    Returns
    -------
    IC : ndarray, shape (TIME,)
        Information content.
    CI_t : ndarray, shape (TIME, 2)
        Lower and upper confidence limit.
    gradient_data : ndarray, shape (bins, TIME)
        CLD gradient per bin, with the MATLAB's quirks.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> par = rng.uniform(0, 1, 50)
    >>> mct = par[:, None] * np.ones((50, 30))
    >>> IC, CI_t, grad = moving_window_calcs(30, par, 0, 1, 50, mct, 0.5 * np.ones(30), 5, 10, 2)
    >>> bool(np.all(IC > 0.8))
    True
    """
    par = np.asarray(par, dtype=float)
    mct = np.asarray(mct, dtype=float)
    y = np.asarray(y, dtype=float)
    _check_port_arguments(TIME, par, lb, ub, ns, mct, y, bins, percentage, n)

    IC = np.zeros(TIME)
    CI_t = np.zeros((TIME, 2))
    gradient_data = np.zeros((bins, TIME))

    for t in range(TIME):
        wPar = par
        wMAE = np.zeros(ns)
        # The three windows of the MATLAB: truncated at the start, full, truncated at the end.
        if t + 1 <= n:
            for k in range(ns):
                wMAE[k] = _sum_left_to_right(np.abs(y[0 : t + 1 + n] - mct[k, 0 : t + 1 + n])) / (t + 1 + n)
        if t + 1 > n and t + 1 <= TIME - n:
            for k in range(ns):
                wMAE[k] = _sum_left_to_right(np.abs(y[t - n : t + n + 1] - mct[k, t - n : t + n + 1])) / (2 * n + 1)
        if t + 1 > TIME - n:
            for k in range(ns):
                wMAE[k] = _sum_left_to_right(np.abs(y[t - n : TIME] - mct[k, t - n : TIME])) / (TIME - t + n)
        wCost = wMAE**2

        count_max = math.floor(len(wCost) * (percentage / 100))
        best_mat, best_indices = select_best_parameters(wCost, wPar, count_max)

        lhood_cumulated, CI, lhood, gradient_vec = run_dynia(ns, par, best_mat, lb, ub, bins, conf_level=conf_level)

        CI_t[t, 0] = CI[0]
        CI_t[t, 1] = CI[1]
        IC[t] = 1 - (CI[1] - CI[0]) / (ub - lb)
        gradient_data[:, t] = gradient_vec[:, 0]
    return IC, CI_t, gradient_data


def _sum_left_to_right(values):
    """Sum in index order, as a plain loop does (numpy.sum adds pairwise).

    A fixed, simple order makes the oracle's costs reproducible by any
    implementation, so ranks agree bit for bit rather than up to rounding.
    """
    return np.cumsum(values)[-1]


def _check_port_arguments(TIME, par, lb, ub, ns, mct, y, bins, percentage, n):
    """Raise a clear ``ValueError`` where the MATLAB would fail or misbehave."""
    if mct.shape != (ns, TIME):
        raise SettingsError(f"mct must have shape (ns, TIME) = ({ns}, {TIME}); got {mct.shape}")
    if par.shape != (ns,):
        raise SettingsError(f"par must have shape (ns,) = ({ns},); got {par.shape}")
    if y.shape != (TIME,):
        raise SettingsError(f"y must have shape (TIME,) = ({TIME},); got {y.shape}")
    if n < 0 or TIME < 2 * n or TIME < 1:
        raise SettingsError(f"the MATLAB windows need 0 <= n and TIME >= 2n (and TIME >= 1); got TIME={TIME}, n={n}")
    _check_window_settings(lb, ub, ns, bins, percentage)


def _check_window_settings(lb, ub, ns, bins, percentage):
    """Raise a clear ``ValueError`` for a range, bin count or percentage the MATLAB cannot use."""
    if not lb < ub:
        raise SettingsError(f"lb must be below ub; got lb={lb}, ub={ub}")
    if bins < 2:
        raise SettingsError(f"bins must be at least 2 (the bin width is (ub-lb)/(bins-1)); got {bins}")
    rows = ns * (percentage / 100)
    if rows != math.floor(rows):
        raise SettingsError(
            f"ns*percentage/100 = {rows!r} is not a whole number; the MATLAB's "
            "best = zeros(TIME, ns*(percentage/100), 2) fails for it"
        )
    if math.floor(rows) < 2:
        raise SettingsError(
            f"percentage={percentage} of ns={ns} leaves {math.floor(rows)} behavioural sets; "
            "calcLikelihood needs at least 2"
        )


def select_best_parameters(wCost, wPar, count_max):
    """Rank by cost, ascending and stable, and keep the first ``count_max``.

    Returns ``best_mat`` (count_max, 2) with columns [cost, parameter] and the
    indices of the kept samples. Equal costs keep their sample order.
    """
    order = np.argsort(wCost, kind="stable")
    best_indices = order[:count_max]
    best_mat = np.zeros((count_max, 2))
    for it in range(count_max):
        best_mat[it, 0] = wCost[best_indices[it]]
        best_mat[it, 1] = wPar[best_indices[it]]
    return best_mat, best_indices


def run_dynia(ns, par, best_mat, lb, ub, bins, *, conf_level=90):
    """Likelihood, CLD, gradient and limits of one window (``runDynia.m``).

    Returns ``lhood_cumulated``, ``CI`` (lower, upper), ``lhood`` and
    ``gradient_vec`` (bins, 4): [gradient, bin start, bin centre, bin end].
    """
    size = len(best_mat[:, 0])
    lhood = calc_likelihood(best_mat)
    par_sorted_indices = np.argsort(best_mat[:, 1], kind="stable")
    par_sorted = best_mat[par_sorted_indices, 1]
    all_par_sorted = np.sort(par, kind="stable")
    lhood_cumulated, lhood_c_all = cumul_likelihood(ns, all_par_sorted, par_sorted, par_sorted_indices, lhood)
    gradient_vec = cld_gradient(bins, ub, lb, par_sorted, lhood_cumulated, size)
    CI = conf_limits(par_sorted, size, conf_level)
    return lhood_cumulated, CI, lhood, gradient_vec


def calc_likelihood(best_mat):
    """Likelihood ``1 - cost``, shifted when negative, normalised (``calcLikelihood.m``)."""
    best_mat = np.asarray(best_mat, dtype=float)
    size = max(best_mat.shape)  # MATLAB's length(): the larger dimension
    if size > best_mat.shape[0]:
        raise SettingsError(
            f"calcLikelihood reads {size} rows of a {best_mat.shape[0]}-row best_mat "
            "(MATLAB length() of a matrix with fewer than 2 rows); need at least 2 behavioural sets"
        )
    lhood = np.zeros(size)
    for it in range(size):
        lhood[it] = 1 - best_mat[it, 0]
    if np.min(lhood) < 0:
        lhood[:] = lhood[:] - np.min(lhood)
    with np.errstate(invalid="ignore", divide="ignore"):
        lhood[:] = lhood[:] / np.sum(lhood)  # 0/0 = NaN, as in MATLAB
    return lhood


def cumul_likelihood(ns, all_par_sorted, par_sorted, par_sorted_indices, lhood):
    """Cumulative likelihood of the behavioural values in ascending order (``cumulLikelihood.m``).

    Returns ``lhood_cumulated`` (count_max,) and ``lhood_c_all``, the MATLAB's
    attempt at the CLD over all samples, which nothing downstream reads.
    """
    size = len(par_sorted_indices)
    lhood_cumulated = np.zeros(size)
    lhood_cumulated[0] = lhood[par_sorted_indices[0]]
    for it in range(1, size):
        lhood_cumulated[it] = lhood_cumulated[it - 1] + lhood[par_sorted_indices[it]]

    it = 0
    while all_par_sorted[it] < par_sorted[0]:
        it = it + 1
    assigned = {}  # MATLAB grows lhood_c_all on assignment and fills gaps with 0
    for j in range(it):
        assigned[j] = 0.0
    count = 0
    while all_par_sorted[it] >= par_sorted[0] and all_par_sorted[it] < par_sorted[size - 1]:
        count = count + 1
        it = it + 1
    for j in range(size):
        assigned[it + j] = lhood_cumulated[j]
    for j in range(it + size, ns - count):
        assigned[j] = 1.0
    lhood_c_all = np.zeros(max(assigned) + 1 if assigned else 0)
    for j, value in assigned.items():
        lhood_c_all[j] = value
    return lhood_cumulated, lhood_c_all


def cld_gradient(bins, ub, lb, par_sorted, lhood_cumulated, size):
    """CLD increase per bin, with the MATLAB's quirks (``cld_gradient.m``).

    Returns ``gradient_vec`` (bins, 4): [gradient, bin start, bin centre, bin end].
    """
    gradient_vec = np.zeros((bins, 4))
    next_limit = lb + (ub - lb) / (bins - 1)
    prev_limit = next_limit
    b = 0
    # Bins below the smallest behavioural value: the CLD is flat there.
    while next_limit < par_sorted[0] and next_limit <= ub and b < bins:
        next_limit = next_limit + (ub - lb) / (bins - 1)
        gradient_vec[b, :] = [0, prev_limit, (prev_limit + next_limit) / 2, next_limit]
        b = b + 1
        prev_limit = next_limit
    start_index = 0
    while next_limit <= par_sorted[size - 1] and next_limit <= ub and b < bins:
        index = start_index
        while par_sorted[index] < next_limit and index <= size - 2:
            index = index + 1
        end_index = index - 1
        if end_index < 0:
            raise SettingsError(
                f"cld_gradient: the smallest behavioural value {par_sorted[0]!r} lies exactly on a "
                "bin edge, where the MATLAB reads lhood_cumulated(0) and stops"
            )
        next_limit = next_limit + (ub - lb) / (bins - 1)
        gradient_vec[b, 0] = lhood_cumulated[end_index] - lhood_cumulated[start_index]
        gradient_vec[b, 1:] = [prev_limit, (prev_limit + next_limit) / 2, next_limit]
        b = b + 1
        prev_limit = next_limit
        start_index = end_index + 1
    # Bins above the largest behavioural value: the CLD is flat there too.
    while next_limit > par_sorted[size - 1] and next_limit <= ub and b < bins:
        next_limit = next_limit + (ub - lb) / (bins - 1)
        gradient_vec[b, :] = [0, prev_limit, (prev_limit + next_limit) / 2, next_limit]
        prev_limit = next_limit
        b = b + 1
    return gradient_vec


def conf_limits(par_sorted, count_max, conf_level):
    """Unweighted confidence limits of the sorted behavioural values (``confLimits.m``)."""
    c1 = (1 - conf_level / 100) / 2
    c2 = 1 - c1
    cli = [math.floor(c1 * (count_max - 1)), math.floor(c2 * (count_max - 1))]
    return np.array([par_sorted[cli[0]], par_sorted[cli[1]]])


# Costs per chunk of windows in moving_window_from_costs (16 MB): its temporaries stay a few times that.
_CHUNK_ELEMENTS = 2**21


def moving_window_from_costs(wCost, par, lb, ub, ns, bins, percentage, *, conf_level=90):
    """``movingWindowCalcs`` for windows whose costs are given: the rest of its loop body, many windows at once.

    The cost loop of :func:`moving_window_calcs` runs in Python over every sample of every window, which
    is slow for long records. Given each window's costs ``wMAE.^2`` (for instance from
    :func:`dynia.engine.windows.window_costs`, which computes them as the MATLAB does, bit for bit), this runs
    the rest of the loop body: ``selectBestParameters``, ``runDynia`` and the information content. It
    skips only ``cumulLikelihood``'s ``lhood_c_all``, which nothing reads. It works on arrays of windows
    rather than window by window, every step with the per-window functions' arithmetic in their order, so
    for the same costs it returns what :func:`moving_window_calcs` returns, bit for bit, and stops with
    the same error where ``cld_gradient`` stops.

    Parameters
    ----------
    wCost : array_like, shape (n_windows, ns)
        Cost of every sample in every window; inf and then NaN rank last, as MATLAB's ``sort`` puts them.
    par, lb, ub, ns, bins, percentage, conf_level
        As :func:`moving_window_calcs`.

    Returns
    -------
    IC : ndarray, shape (n_windows,)
    CI_t : ndarray, shape (n_windows, 2)
    gradient_data : ndarray, shape (bins, n_windows)

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.engine.windows import window_costs
    >>> rng = np.random.default_rng(0)
    >>> par = rng.uniform(0, 1, 50)
    >>> mct = par[:, None] * np.ones((50, 30))
    >>> y = 0.5 * np.ones(30)
    >>> fast = moving_window_from_costs(window_costs(y, mct, 2, 0, 30), par, 0, 1, 50, 5, 10)
    >>> slow = moving_window_calcs(30, par, 0, 1, 50, mct, y, 5, 10, 2)
    >>> all(np.array_equal(a, b) for a, b in zip(fast, slow))
    True
    """
    wCost = np.asarray(wCost, dtype=float)
    par = np.asarray(par, dtype=float)
    if wCost.ndim != 2 or wCost.shape[1] != ns:
        raise SettingsError(f"wCost must have shape (n_windows, ns) = (..., {ns}); got {wCost.shape}")
    if par.shape != (ns,):
        raise SettingsError(f"par must have shape (ns,) = ({ns},); got {par.shape}")
    _check_window_settings(lb, ub, ns, bins, percentage)

    n_windows = wCost.shape[0]
    IC = np.zeros(n_windows)
    CI_t = np.zeros((n_windows, 2))
    gradient_data = np.zeros((bins, n_windows))
    count_max = math.floor(ns * (percentage / 100))
    # Many windows at a time, each step in the arithmetic and order of the per-window functions, in chunks
    # so that the temporaries do not grow with the number of windows.
    chunk = max(1, _CHUNK_ELEMENTS // ns)
    for start in range(0, n_windows, chunk):
        windows = slice(start, min(start + chunk, n_windows))
        best_indices = _first_of_stable_argsort(wCost[windows], count_max)
        lhood = _likelihoods(np.take_along_axis(wCost[windows], best_indices, axis=1))
        best_par = par[best_indices]
        par_sorted_indices = np.argsort(best_par, axis=1, kind="stable")
        par_sorted = np.take_along_axis(best_par, par_sorted_indices, axis=1)
        # cumulLikelihood's running sum, in the same order (numpy's cumsum adds left to right).
        lhood_cumulated = np.cumsum(np.take_along_axis(lhood, par_sorted_indices, axis=1), axis=1)
        gradient_data[:, windows] = _cld_gradients(bins, ub, lb, par_sorted, lhood_cumulated).T
        # conf_limits indexes the first axis: given the windows as columns it reads all their limits at once.
        CI = conf_limits(par_sorted.T, count_max, conf_level)
        CI_t[windows] = CI.T
        IC[windows] = 1 - (CI[1] - CI[0]) / (ub - lb)
    return IC, CI_t, gradient_data


def _first_of_stable_argsort(costs, count_max):
    """Per row, the first ``count_max`` of ``np.argsort(row, kind="stable")``, without sorting the whole row.

    Every sample the stable sort puts among the first ``count_max`` costs at most the ``count_max``-th
    smallest cost (partition and sort agree on it, NaN last), so a stable sort of just the samples costing
    that much or less, kept in sample order, ranks them as the sort of the whole row does, ties included.
    """
    partitioned = np.argpartition(costs, count_max - 1, axis=1)
    kth_cost = np.take_along_axis(costs, partitioned[:, count_max - 1 : count_max], axis=1)
    # A NaN there means fewer than count_max costs are numbers: then every sample is a candidate.
    candidate = (costs <= kth_cost) | np.isnan(kth_cost)
    candidates = candidate.sum(axis=1)
    best = np.empty((costs.shape[0], count_max), dtype=np.intp)
    # Where no other cost ties the count_max-th, the partition's first count_max are the candidates.
    exact = np.flatnonzero(candidates == count_max)
    samples = np.sort(partitioned[exact, :count_max], axis=1)
    best[exact] = _sorted_by_cost(costs[exact[:, None], samples], samples, count_max)
    tied = np.flatnonzero(candidates != count_max)
    if tied.size:
        rows, samples = np.nonzero(candidate[tied])
        counts = candidates[tied]
        position = np.arange(rows.size) - np.repeat(np.cumsum(counts) - counts, counts)
        # Rows shorter than the longest are padded with NaN costs, which the stable sort puts after theirs.
        padded = np.zeros((tied.size, counts.max()), dtype=np.intp)
        padded[rows, position] = samples
        padded_costs = np.full(padded.shape, np.nan)
        padded_costs[rows, position] = costs[tied[rows], samples]
        best[tied] = _sorted_by_cost(padded_costs, padded, count_max)
    return best


def _sorted_by_cost(candidate_costs, candidates, count_max):
    """The first ``count_max`` of each row of ``candidates`` (in sample order) in a stable sort by cost."""
    order = np.argsort(candidate_costs, axis=1, kind="stable")[:, :count_max]
    return np.take_along_axis(candidates, order, axis=1)


def _likelihoods(best_costs):
    """:func:`calc_likelihood` of every row of ``best_costs``, with its arithmetic.

    The row sums are numpy's pairwise sums along the contiguous last axis, the order in which ``np.sum``
    adds a single row.
    """
    lhood = 1 - np.ascontiguousarray(best_costs)
    lowest = lhood.min(axis=1)
    shifted = lowest < 0
    with np.errstate(invalid="ignore", divide="ignore"):  # inf costs make -inf - -inf and 0/0: NaN, as in MATLAB
        lhood[shifted] = lhood[shifted] - lowest[shifted, None]
        return lhood / lhood.sum(axis=1)[:, None]


def _cld_gradients(bins, ub, lb, par_sorted, lhood_cumulated):
    """The gradient column of :func:`cld_gradient` for every row of ``par_sorted`` at once.

    ``cld_gradient`` meets bin b with ``next_limit`` at the b-th sum of its repeated addition. Its first
    loop passes the bins whose limit lies below the smallest value and its last loop those above the
    largest, both leaving 0. Its middle loop takes the bins from there on while the limit is at most the
    largest value. The values below a limit come first (NaN last), and their count p never decreases
    from one bin to the next, so the scan starting where the bin before stopped (at 0 for the first) stops
    at ``min(p, size - 1)``: the bin reads the CLD one before that stop minus the CLD where it started.
    """
    size = par_sorted.shape[1]
    limits = [lb + (ub - lb) / (bins - 1)]
    while len(limits) < bins:
        limits.append(limits[-1] + (ub - lb) / (bins - 1))
    within_range = np.array([limit <= ub for limit in limits])
    limits = np.array(limits, dtype=float)
    # Each loop runs until its condition first fails: a running "and" over the bins marks the bins it takes.
    first_loop = np.logical_and.accumulate((limits < par_sorted[:, :1]) & within_range, axis=1)
    middle_condition = (limits <= par_sorted[:, -1:]) & within_range
    middle_loop = np.logical_and.accumulate(middle_condition | first_loop, axis=1) & ~first_loop
    # A value lies below every limit from the first limit above it on.
    first_limit_above = np.searchsorted(limits, par_sorted, side="right")
    rows = np.arange(par_sorted.shape[0])[:, None]
    values_first_below = np.bincount((rows * (bins + 1) + first_limit_above).ravel(), minlength=rows.size * (bins + 1))
    values_below = np.cumsum(values_first_below.reshape(-1, bins + 1), axis=1)[:, :bins]
    scan_stop = np.minimum(values_below, size - 1)
    on_edge = middle_loop & (scan_stop == 0)
    if on_edge.any():
        window = np.argmax(on_edge.any(axis=1))
        cld_gradient(bins, ub, lb, par_sorted[window], lhood_cumulated[window], size)  # raises the MATLAB's stop
    scan_start = np.concatenate([np.zeros_like(scan_stop[:, :1]), scan_stop[:, :-1]], axis=1)
    end_cld = np.take_along_axis(lhood_cumulated, np.maximum(scan_stop - 1, 0), axis=1)
    start_cld = np.take_along_axis(lhood_cumulated, scan_start, axis=1)
    with np.errstate(invalid="ignore"):  # inf - inf where the likelihood is NaN
        return np.where(middle_loop, end_cld - start_cld, 0.0)


def euler_simulation(params, u, *, x=70.0, return_state=False):
    """The Monte Carlo simulator of ``example_firstorder.m``: forward Euler, time step 1, from ``x = 70``.

    For every sample the script builds ``sys = ss(tf(b1_mc(k), [a1_mc(k) 1]))``, takes
    ``[a, b, c, d] = ssdata(sys)`` and runs::

        x = 70;
        for i = 1:size
            x_d = a * x + b * u(i);
            x = x + x_d;            % time step = 1
            mct(k,i) = c*x;
        end

    This port runs the same three lines for all samples at once, with the controllable canonical
    realisation of ``K/(T s + 1)``: ``a = -1/T``, ``b = 1``, ``c = K/T``. MATLAB's ``ss`` balances the
    realisation it builds, which may rescale the state and with it what a start at 70 means; the
    dynamics and the steady state do not depend on the realisation.

    Compared with the exact, zero-order-hold simulation of :class:`dynia.models.FirstOrder`:

    * the output at step i already answers ``u(i)``, a lead of one step (the exact output at step i
      answers the inputs up to step i-1);
    * the pole is ``1 - 1/T`` instead of ``exp(-1/T)``: the response is too fast, oscillates for
      T < 1 and grows without bound for T < 0.5 (to inf, then NaN, as in MATLAB);
    * every simulation starts from the state ``x``, whatever the data did;
    * the steady state, ``K*u``, is exact.

    Parameters
    ----------
    params : array_like, shape (ns, 2)
        Gain K (the script's ``b1_mc``) and time constant T (``a1_mc``) of each sample, the column
        order of :class:`dynia.models.FirstOrder`.
    u : array_like, shape (TIME,)
        Input, one value per step.
    x : float or array_like of shape (ns,), default 70.0
        State before the first step.
    return_state : bool, default False
        Also return the state after the last step, to continue on the next piece of a long record.

    Returns
    -------
    mct : ndarray, shape (ns, TIME)
        Simulated output of every sample.
    x : ndarray, shape (ns,)
        The final state (only with ``return_state=True``).

    Examples
    --------
    >>> euler_simulation([[2.0, 1.0], [2.0, 3.0]], [35.0, 35.0, 35.0]).round(2)
    array([[70.  , 70.  , 70.  ],
           [54.44, 59.63, 63.09]])
    >>> bool(np.isnan(euler_simulation([[2.0, 0.1]], np.full(500, 35.0))[0, -1]))
    True
    """
    params = np.asarray(params, dtype=float)
    u = np.asarray(u, dtype=float)
    if params.ndim != 2 or params.shape[1] != 2:
        raise SettingsError(f"params must have shape (ns, 2), columns K and T; got {params.shape}")
    if u.ndim != 1:
        raise SettingsError(f"u must be 1-D (TIME,); got shape {u.shape}")
    ns = params.shape[0]
    x = np.array(np.broadcast_to(np.asarray(x, dtype=float), (ns,)))
    mct = np.zeros((ns, u.size))
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # T = 0 and T < 0.5 overflow, as in MATLAB
        a = -1.0 / params[:, 1]
        b = 1.0
        c = params[:, 0] / params[:, 1]
        for i in range(u.size):
            x_d = a * x + b * u[i]
            x = x + x_d
            mct[:, i] = c * x
    return (mct, x) if return_state else mct


def plot_parameter_estimation(time, CI_t, gradient_data, lb, ub, bins, *, ax=None):
    """The example script's identifiability plot ("Parameter estimation plot"), drawn as MATLAB draws it.

    The script runs::

        plot(time, CI(:, 1), time, CI(:, 2)); hold on
        colormap(flipud(gray))
        y_step = (ub-lb)/(bins-1); y_range = lb:y_step:ub;
        pcolor(time, y_range, gradient_data); shading flat
        axis([time(1), time(size), lb, ub])

    ``pcolor`` with flat shading colours the cell between rows i and i+1 and columns j and j+1 with
    ``gradient_data(i, j)``: row i is drawn from ``lb + (i-1)*y_step`` to ``lb + i*y_step``, and the
    last row (bin) and the last column (step) are not drawn. The colour limits are the data's minimum
    and maximum (MATLAB's automatic ``CLim``), so where ``cld_gradient`` left negative entries (empty
    bins) zero is light grey, not white. The limits are drawn over the shading here; in MATLAB the
    surface may hide them.

    Parameters
    ----------
    time : array_like, shape (TIME,)
        The x values of the steps.
    CI_t : array_like, shape (TIME, 2)
        Lower and upper limit of every step.
    gradient_data : array_like, shape (bins, TIME)
        As :func:`moving_window_calcs` returns it.
    lb, ub : float
        Sampling range of the parameter.
    bins : int
        Number of gradient bins.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure's axes by default.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt

    time = np.asarray(time, dtype=float)
    CI_t = np.asarray(CI_t, dtype=float)
    gradient_data = np.asarray(gradient_data, dtype=float)
    if gradient_data.shape != (bins, time.size) or CI_t.shape != (time.size, 2):
        raise SettingsError(
            f"gradient_data must be (bins, TIME) = ({bins}, {time.size}) and CI_t (TIME, 2); "
            f"got {gradient_data.shape} and {CI_t.shape}"
        )
    ax = ax if ax is not None else plt.figure().add_subplot()
    y_range = lb + (ub - lb) / (bins - 1) * np.arange(bins)
    ax.pcolormesh(
        time,
        y_range,
        gradient_data[:-1, :-1],
        shading="flat",
        cmap="Greys",
        vmin=np.nanmin(gradient_data),
        vmax=np.nanmax(gradient_data),
        rasterized=True,
    )
    # The colours of DyniaResult.plot_identifiability, so that both code paths read alike.
    ax.plot(time, CI_t[:, 0], color="tab:blue", linewidth=1, label="lower limit")
    ax.plot(time, CI_t[:, 1], color="tab:red", linewidth=1, label="upper limit")
    ax.axis([time[0], time[-1], lb, ub])
    ax.set_xlabel("Time Step")
    ax.set_ylabel("Parameter Value")
    return ax


def thesis_code_result(y, sims, samples, bounds, names, *, n, percentage, bins, time=None, conf_level=90):
    """DYNIA as the thesis's code computes it, on given simulations, as a :class:`dynia.DyniaResult`.

    The costs of every window are those of ``movingWindowCalcs`` (:func:`dynia.engine.windows.window_costs`,
    bit for bit), and each parameter goes through :func:`moving_window_from_costs`: the information
    content and limits are the engine's ``"thesis"`` flavour's, the gradient is ``cld_gradient``'s, with
    its quirks. Row b of the gradient holds the behavioural values in ``[lb + b w, lb + (b+1) w)`` with
    ``w = (ub-lb)/(bins-1)``, the row ``pcolor`` draws there (:func:`plot_parameter_estimation`), so
    ``bin_centres`` are ``lb + (b + 1/2) w``; the last row lies beyond ``ub`` and is always 0.

    Parameters
    ----------
    y : array_like, shape (TIME,)
        Measured output.
    sims : array_like, shape (ns, TIME)
        Simulated output of every sample (for instance :func:`euler_simulation`, or a model's exact
        simulation where the thesis gives no script).
    samples : array_like, shape (ns, n_params)
        The parameter values analysed, one column per name.
    bounds : array_like, shape (n_params, 2)
        Sampling range [lb, ub] of each.
    names : sequence of str
        The parameters' names.
    n, percentage, bins, conf_level
        As :func:`moving_window_calcs`.
    time : array_like, shape (TIME,), optional
        Time of each step; the step number by default.

    Returns
    -------
    dynia.DyniaResult
        With ``run.thesis_code`` True (it is the port's, not the engine's) and
        settings of the ``"thesis"`` flavour with ``n_samples`` ns, ``n``,
        ``percentage``, ``bins`` and ``conf_level`` as given (checked by
        :class:`dynia.settings.AnalysisSettings`).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> samples = rng.uniform(0, 1, (50, 1))
    >>> sims = samples * np.ones((50, 30))
    >>> res = thesis_code_result(0.5 * np.ones(30), sims, samples, [[0.0, 1.0]], ["a"], n=2, percentage=10, bins=5)
    >>> IC, CI_t, grad = moving_window_calcs(30, samples[:, 0], 0, 1, 50, sims, 0.5 * np.ones(30), 5, 10, 2)
    >>> np.array_equal(res.ic[0], IC), np.array_equal(res.gradient[0], grad), res.bin_centres[0].tolist()
    (True, True, [0.125, 0.375, 0.625, 0.875, 1.125])
    """
    from ..result import DyniaResult
    from ..settings import AnalysisSettings, RunRecord

    y = np.asarray(y, dtype=float)
    sims = np.asarray(sims, dtype=float)
    samples = np.asarray(samples, dtype=float)
    bounds = np.asarray(bounds, dtype=float)
    names = tuple(names)
    ns = sims.shape[0]
    if samples.shape != (ns, len(names)) or bounds.shape != (len(names), 2):
        raise SettingsError(
            f"samples must be (ns, n_params) = ({ns}, {len(names)}) and bounds ({len(names)}, 2) for names "
            f"{names}; got {samples.shape} and {bounds.shape}"
        )
    if sims.shape != (ns, y.size) or y.ndim != 1:
        raise SettingsError(f"sims must be (ns, TIME) for y of shape (TIME,); got {sims.shape} and {y.shape}")
    settings = AnalysisSettings(n_samples=ns, n=n, percentage=percentage, bins=bins, conf_level=conf_level)
    steps = y.size
    ic = np.empty((len(names), steps))
    ci = np.empty((len(names), steps, 2))
    gradient = np.empty((len(names), bins, steps))
    # Costs in blocks of windows: for a month of minutes the whole (TIME, ns) table would rival the simulations.
    block = max(1, 2**24 // max(ns, 1))
    for start in range(0, steps, block):
        stop = min(start + block, steps)
        costs = _matlab_window_costs(y, sims, n, start, stop)
        for p, (low, high) in enumerate(bounds):
            IC, CI_t, grad = moving_window_from_costs(
                costs, samples[:, p], low, high, ns, bins, percentage, conf_level=conf_level
            )
            ic[p, start:stop], ci[p, start:stop], gradient[p, :, start:stop] = IC, CI_t, grad
    width = (bounds[:, 1] - bounds[:, 0]) / (bins - 1)
    bin_centres = bounds[:, :1] + (np.arange(bins) + 0.5) * width[:, None]
    return DyniaResult(
        names=names,
        samples=samples,
        bounds=bounds,
        time=np.arange(float(steps)) if time is None else np.asarray(time, dtype=float),
        ic=ic,
        ci=ci,
        gradient=gradient,
        bin_centres=bin_centres,
        settings=settings,
        run=RunRecord(thesis_code=True),
    )


def _matlab_window_costs(y, sims, n, start, stop):
    """``wMAE.^2`` of the windows at steps [start, stop), with MATLAB's inf and NaN where a simulation diverged.

    :func:`dynia.engine.windows.window_costs` refuses non-finite simulations; the thesis's Euler loop makes them
    (T < 0.5). In MATLAB a window holding an inf costs inf and one holding a NaN costs NaN, and its sort
    puts both after every finite cost, inf before NaN, as numpy's does.
    """
    from ..engine.windows import window_costs

    finite = np.isfinite(sims)
    if finite.all():
        return window_costs(y, sims, n, start, stop)
    costs = window_costs(y, np.where(finite, sims, 0.0), n, start, stop)
    steps = y.size
    lows = np.clip(np.arange(start, stop) - n, 0, steps)
    highs = np.clip(np.arange(start, stop) + n + 1, 0, steps)
    for marker, value in ((np.isinf(sims), np.inf), (np.isnan(sims), np.nan)):
        seen = np.concatenate([np.zeros((sims.shape[0], 1), dtype=np.int64), np.cumsum(marker, axis=1)], axis=1)
        in_window = (seen[:, highs] - seen[:, lows]).T > 0
        costs[in_window] = value
    return costs


CODE_PATHS = ("thesis", "corrected")


def check_code_path(code_path):
    """The chapter-3 notebooks' ``code_path``, checked: ``"thesis"`` or ``"corrected"``.

    ``"thesis"`` draws each identifiability figure as the thesis's code draws it (its Euler simulator
    where its script uses one, :func:`thesis_code_result`'s gradient, :func:`plot_parameter_estimation`);
    ``"corrected"`` draws the engine's exact simulation and likelihood mass per bin.

    Examples
    --------
    >>> check_code_path("thesis")
    'thesis'
    >>> check_code_path("matlab")
    Traceback (most recent call last):
    ...
    dynia.errors.SettingsError: code_path must be one of 'thesis', 'corrected'; got 'matlab'
    """
    if code_path not in CODE_PATHS:
        raise SettingsError(
            f"code_path must be one of {', '.join(map(repr, CODE_PATHS))}; got {code_path!r}", "code_path"
        )
    return code_path


def plot_thesis_code_result(result, name, *, ax=None, true_value=None):
    """A :func:`thesis_code_result`'s identifiability plot, as the script draws it, with the true value.

    :func:`plot_parameter_estimation` on the result's limits and gradient of ``name``, a dashed line at
    ``true_value`` when given, the parameter's name on the y axis and a legend.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> samples = rng.uniform(0, 1, (50, 1))
    >>> res = thesis_code_result(0.5 * np.ones(30), samples * np.ones((50, 30)), samples, [[0.0, 1.0]], ["a"],
    ...                          n=2, percentage=10, bins=5)
    >>> plot_thesis_code_result(res, "a", true_value=0.5).get_ylabel()
    'a'
    """
    if not result.run.thesis_code:
        raise SettingsError("plot_thesis_code_result draws results of thesis_code_result only", "result")
    p = result.index(name)
    low, high = result.bounds[p]
    ax = plot_parameter_estimation(
        result.time, result.ci[p], result.gradient[p], low, high, result.settings.bins, ax=ax
    )
    if true_value is not None:
        ax.axhline(true_value, color="k", linestyle="--", linewidth=1, label="true value")
    ax.set_ylabel(name)
    ax.legend(loc="upper right", fontsize="small")
    return ax
