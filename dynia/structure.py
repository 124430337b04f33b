"""Model-structure warnings: a constant parameter whose estimate moves over time.

The thesis (section 4.4) names an asset of DYNIA in system identification:
if the CLD gradient of a parameter, the measure of where the parameter lies,
varies with time, the model structure may not represent the system, unless
the parameter really describes something time-varying. Its case study
(3.1.3) shows the kind of finding: the gain's CLD gradient is darkest at
1.7-1.9 rather than at the 2 its band points to, which the thesis traces to
a change of operating mode late in the record. :func:`structure_warnings`
makes that check for every parameter of a :class:`~dynia.result.DyniaResult`.

Shapes follow the package convention (see :mod:`dynia.engine`): ``ic``
(n_params, n_steps), ``ci`` (n_params, n_steps, 2), ``gradient`` (n_params,
n_bins, n_steps), ``bin_centres`` (n_params, n_bins).

The rule
--------
1. Informative windows (:meth:`~dynia.result.DyniaResult.informative_windows`:
   IC at least ``ic_threshold``, above the noise floor, behavioural set not
   tied within noise), leaving out

   - the first and last ``n`` windows, which are truncated (thesis 4.1), so
     that every block compared is read off windows of equal length;
   - windows that use a sample marked in ``ignore`` (for instance the
     glitches found by :func:`dynia.quality.check_quality`: the thesis's
     highest IC of the time constant sat on one erroneous reading);
   - windows whose band leans on a bound of the range: it comes closer to
     the bound than a quarter of its own width, or than one gradient bin.
     Such a band bounds the parameter from one side only, and it is what
     windows whose output carries only noise produce: the parameter sets
     whose simulations come closest to a flat line there (a time constant
     near 0, long settled, or near its maximum, hardly moving) fit the
     noise best, with a narrow band at the bound and a high IC (thesis
     example 1 after its last step does exactly this).

2. Consecutive informative windows form runs; runs shorter than
   ``min_windows`` are dropped and longer ones are cut into blocks of
   ``2n + 1`` windows or a little more (at least ``min_windows``), so that
   each block stands for its own stretch of about ``4n + 1`` samples.
3. Each block's location is the bin centre of the largest summed CLD
   gradient of its windows (the aggregated identifiability of thesis
   2.2.3.2); its band is the median of its windows' limits.
4. With k = max(2, a fifth of the blocks rounded up), compare the k-th
   lowest and the k-th highest location: k blocks must agree on each, since
   one stretch of data can always rank oddly, and the outermost of many
   blocks would move apart with their number even where the parameter does
   not (at a tenth, the Monte Carlo jitter of a well-identified gain in a
   narrow second-run range reached past the tolerance; a fifth still sees a
   change that holds for the last quarter of a record). Warn when the two
   are more than ``drift_tolerance`` times the parameter's range apart and
   each lies outside the median band of the blocks on the other side: two
   groups of stretches of data that each pin the parameter down, at values
   the other group rules out.

What it cannot tell apart. DYNIA keeps a fixed share of the parameter sets in
every window, however little their costs differ. Where the output carries
only noise (a long stretch at zero input, or long after the last step) but
the simulations still differ a little, noise can pick a narrow band away
from the bounds, and a correct model can draw a warning. Pass those
stretches in ``ignore`` when you know them.

Examples
--------
>>> import numpy as np
>>> from dynia.result import DyniaResult
>>> from dynia.structure import structure_warnings
>>> steps, centres = 60, np.linspace(0.05, 0.95, 10)
>>> peak = np.where(np.arange(steps) < 30, 2, 7)          # bin 2, then bin 7
>>> gradient = (np.arange(10)[:, None] == peak).astype(float)[None]
>>> band = np.stack([centres[peak] - 0.1, centres[peak] + 0.1], axis=-1)[None]
>>> result = DyniaResult(names=("T",), samples=np.zeros((1, 1)), bounds=np.array([[0.0, 1.0]]),
...                      time=np.arange(steps, dtype=float), ic=np.full((1, steps), 0.8), ci=band,
...                      gradient=gradient, bin_centres=centres[None], settings={"n": 2})
>>> print(structure_warnings(result)[0])  # doctest: +NORMALIZE_WHITESPACE
the location of the CLD-gradient maximum of T moves from 0.25 (t=13-17) to 0.75 (t=43-47),
50 % of its range [0, 1], rising over time (11 informative segments); a constant
parameter should not move: the model structure may be wrong (thesis 4.4), unless T really
varies over time
"""

import math
from dataclasses import dataclass

import numpy as np

from . import _checks
from .errors import SettingsError
from .segments import mask_to_segments
from .settings import IC_THRESHOLD

__all__ = [
    "StructureWarning",
    "structure_warnings",
    "clear_of_bounds",
    "Disagreement",
    "widened",
    "band_disagreement",
    "noise_widening",
]

# A band closer to a bound than this fraction of its width (or one gradient bin)
# leans on the bound. Behavioural values spread evenly from some value up to
# the bound put the upper limit of a 90 % band 1/18 of the band's width below it.
_CLEARANCE = 0.25

# The k of rule 4: at least _CONFIRMING_BLOCKS, and _CONFIRMING_SHARE of the blocks.
_CONFIRMING_BLOCKS = 2
_CONFIRMING_SHARE = 0.2

# A rank correlation of the block locations with time beyond this says
# "rising" or "falling" instead of "back and forth".
_TREND = 0.5


@dataclass(frozen=True, eq=False)
class StructureWarning:
    """A parameter whose CLD-gradient maximum moves between informative segments.

    Attributes
    ----------
    parameter : str
    segments : tuple of (int, int)
        Step index ranges ``[start, stop)`` of the informative blocks of
        windows, in time order.
    times : ndarray, shape (n_blocks, 2)
        Time of the first and of the last window of each block.
    locations : ndarray, shape (n_blocks,)
        Location of the gradient maximum in each block.
    bands : ndarray, shape (n_blocks, 2)
        Median lower and upper limit of each block.
    compared : (int, int)
        Positions in ``segments`` of the block with the k-th lowest and the
        block with the k-th highest location (rule 4 of :mod:`dynia.structure`).
    spread : float
        Distance between those two locations, as a fraction of the
        parameter's range.
    trend : float
        Spearman rank correlation of the locations with time: near +1 or -1
        a drift in one direction, near 0 a parameter that goes back and
        forth (for instance with the operating point).
    message : str
        The warning in one sentence; also ``str(warning)``.
    """

    parameter: str
    segments: tuple
    times: np.ndarray
    locations: np.ndarray
    bands: np.ndarray
    compared: tuple
    spread: float
    trend: float
    message: str

    def __str__(self):
        return self.message


def structure_warnings(result, *, ic_threshold=IC_THRESHOLD, min_windows=3, drift_tolerance=0.1, ignore=None):
    """Warn about every parameter whose CLD-gradient maximum drifts over time.

    See the module documentation for the rule and what it cannot tell apart.

    Parameters
    ----------
    result : DyniaResult
        With the half window ``n`` in ``result.settings`` (as every run of
        :func:`dynia.run` and :func:`dynia.moving_window` records it).
    ic_threshold : float in [0, 1], default :data:`dynia.settings.IC_THRESHOLD` (0.5)
        IC from which a window is informative
        (:meth:`~dynia.result.DyniaResult.informative_windows`).
    min_windows : int, default 3
        Fewest consecutive informative windows that make a block; shorter
        runs are single windows that happened to rank well and are ignored.
    drift_tolerance : float in (0, 1), default 0.1
        Smallest distance between the compared locations that counts, as a
        fraction of the parameter's range: more than four bins of the
        default 40, beyond the jitter of the gradient maximum that the
        Monte Carlo sampling alone causes (about two bins). Smaller moves
        (the thesis's case study: 0.2 in a gain range of 6, 3 %) need a
        narrower range, as in the thesis's second run, before they stand
        out of that jitter.
    ignore : array_like of bool, shape (n_steps,), optional
        Samples not to trust; every window that uses one is left out. For
        example ``report.mask("u") | report.mask("y")`` of a
        :class:`dynia.quality.QualityReport`.

    Returns
    -------
    list of StructureWarning
        One per parameter that drifts, in parameter order; empty when none does.

    Examples
    --------
    A first-order model of first-order data:

    >>> import numpy as np, dynia
    >>> u = np.repeat(np.random.default_rng(0).choice([5.0, 15.0, 25.0], 10), 40)
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 4.0]], u)[0]
    >>> y = y + np.random.default_rng(1).normal(0, 0.2, y.size)
    >>> res = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 5), "T": (0, 10)}, n=5, rng=2)
    >>> structure_warnings(res)
    []
    """
    _checks.analysis_result(result)
    min_windows = _checks.whole_number(min_windows, "min_windows", minimum=1)
    drift_tolerance = _checks.open_interval(drift_tolerance, "drift_tolerance", 0, 1)
    usable = result.full_windows & ~_ignored_windows(result, ignore)  # raises if the geometry is unknown
    n = result.settings.n
    block = max(2 * n + 1, min_windows)
    warnings = []
    for p in range(len(result.names)):
        blocks = _informative_blocks(result, p, ic_threshold, usable, min_windows, block)
        warning = _drift(result, p, blocks, drift_tolerance)
        if warning is not None:
            warnings.append(warning)
    return warnings


def _ignored_windows(result, ignore):
    """Windows that use an ignored sample, shape (n_steps,)."""
    n_steps = result.time.size
    if ignore is None:
        return np.zeros(n_steps, dtype=bool)
    ignore = np.asarray(ignore)
    if ignore.dtype != bool or ignore.shape != (n_steps,):
        raise SettingsError(
            f"ignore must be a boolean array of shape ({n_steps},), one flag per step; "
            f"got dtype {ignore.dtype} and shape {ignore.shape}"
        )
    return result.windows_using(ignore)


def clear_of_bounds(result, p):
    """Windows whose band of parameter ``p`` keeps clear of both bounds of its range, (n_steps,) bool.

    A band closer to a bound than a quarter of its own width, or than one
    gradient bin, leans on the bound: it limits the parameter from one side
    only, and it is what windows holding only noise produce. NaN bands are
    not clear.
    """
    low, high = result.bounds[p]
    lower, upper = result.ci[p, :, 0], result.ci[p, :, 1]
    clearance = np.maximum(_CLEARANCE * (upper - lower), (high - low) / result.gradient.shape[1])
    with np.errstate(invalid="ignore"):
        return (lower - low > clearance) & (high - upper > clearance)


def _informative_blocks(result, p, ic_threshold, usable, min_windows, block):
    """Blocks of informative windows of parameter ``p``: a list of step index arrays."""
    informative = usable & result.informative_windows(ic_threshold, result.names[p])[0] & clear_of_bounds(result, p)
    return window_stretches(informative, block, min_windows=min_windows)


def window_stretches(windows, length, *, min_windows=1, bridge=0):
    """The marked windows grouped into stretches of data: a list of step index arrays, in time order.

    Runs of marked windows (joined across fewer than ``bridge`` unmarked
    steps) with fewer than ``min_windows`` steps are dropped; the others are
    cut into stretches of ``length`` steps or a little more (the whole run
    when shorter), so that each stands for its own stretch of data. A
    stretch holds only marked steps.

    Examples
    --------
    >>> marked = np.array([1, 1, 1, 0, 1, 1, 0, 0, 0, 1], dtype=bool)
    >>> [list(map(int, steps)) for steps in window_stretches(marked, 2, bridge=2)]
    [[0, 1, 2], [4, 5], [9]]
    """
    windows = np.asarray(windows, dtype=bool)
    runs = []
    for start, stop in mask_to_segments(windows):
        if runs and start - runs[-1][1] < bridge:
            runs[-1] = (runs[-1][0], stop)
        else:
            runs.append((start, stop))
    stretches = []
    for start, stop in runs:
        if stop - start >= min_windows:
            steps = start + np.flatnonzero(windows[start:stop])
            stretches += np.array_split(steps, max(1, steps.size // length))
    return stretches


def stretch_bands(result, p, stretches):
    """Band of parameter ``p`` over each stretch: the median of its windows' limits, (n_stretches, 2).

    Each column's median as ``np.median`` gives it (NaN when a window's limit
    is), for every stretch at once: one sort of all the stretches' limits,
    not a median per stretch, of which a long record has hundreds.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> ci = np.array([[[1.0, 4.0], [3.0, 6.0], [2.0, 5.0], [7.0, 9.0], [8.0, np.nan]]])
    >>> stretch_bands(SimpleNamespace(ci=ci), 0, [np.array([0, 1, 2]), np.array([3, 4])]).tolist()
    [[2.0, 5.0], [7.5, nan]]
    """
    if not stretches:
        return np.empty((0, 2))
    lengths = np.array([steps.size for steps in stretches])
    limits = result.ci[p, np.concatenate(stretches)]
    owner = np.repeat(np.arange(lengths.size), lengths)
    first = np.cumsum(lengths) - lengths
    bands = np.empty((lengths.size, 2))
    for side in range(2):
        # Within each stretch ascending, NaN last, as np.median partitions them.
        ordered = limits[np.lexsort((limits[:, side], owner)), side]
        lower, upper = ordered[first + (lengths - 1) // 2], ordered[first + lengths // 2]
        # np.median's mean of the middle one or two: summed from 0.0 (so -0.0 gives 0.0), then divided by their number.
        with np.errstate(invalid="ignore", over="ignore"):  # evaluated for the odd stretches too, and dropped
            bands[:, side] = np.where(lengths % 2 == 1, 0.0 + lower, ((0.0 + lower) + upper) / 2)
        bands[np.isnan(ordered[first + lengths - 1]), side] = np.nan
    return bands


def noise_widening(result):
    """Half-widths by which every band is widened on either side before bands are compared with each other.

    ``sqrt(f) - 1``, f the noise's own size factor
    (``result.run.steady_size_factor``, :func:`dynia.engine.noise.steady_size_factor`):
    0 for white noise, for which the comparisons' tolerances were measured
    (a band holds what noise does to its window's estimate). Noise whose
    window counts f times fewer independent points moves a window's
    estimate about sqrt(f) times as far, a slowly wandering disturbance
    taken for a change of the parameter. Where the noise cannot be told
    from the misfit (NaN: the record is never steady) and for a result
    without a record fit (None), the bands are compared as they are.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> noise_widening(SimpleNamespace(run=SimpleNamespace(steady_size_factor=16.0)))
    3.0
    """
    factor = result.run.steady_size_factor
    if factor is None or not math.isfinite(factor):
        return 0.0
    return max(math.sqrt(factor) - 1, 0.0)


def widened(bands, widening):
    """``bands`` (n, 2) widened by ``widening`` half-widths on either side."""
    bands = np.asarray(bands, dtype=float).reshape(-1, 2)
    half = (bands[:, 1] - bands[:, 0]) / 2
    return np.stack([bands[:, 0] - widening * half, bands[:, 1] + widening * half], axis=1)


@dataclass(frozen=True, eq=False)
class Disagreement:
    """Two stretches of windows whose bands of one parameter are disjoint (see :func:`band_disagreement`).

    Attributes
    ----------
    stretches : list of ndarray
        Steps of every stretch compared, in time order.
    bands : ndarray, shape (n_stretches, 2)
        Median lower and upper limit over each stretch.
    below, above : int
        Positions in ``stretches`` of the stretch with the lowest upper
        limit and of the one with the highest lower limit.
    gap : float
        The lower limit of ``above`` minus the upper limit of ``below``.
    tolerance : float
        The gap that still counts as agreement.
    """

    stretches: list
    bands: np.ndarray
    below: int
    above: int
    gap: float
    tolerance: float


def band_disagreement(result, p, windows):
    """Whether the bands of parameter ``p`` in the marked windows rule each other out.

    The windows are grouped into stretches by ``window_stretches``
    (joined across gaps shorter than one window, cut into stretches of one
    window length, 2n+1 steps), and each stretch's band is the median of
    its windows' limits (``stretch_bands``), as for the structure
    warnings. Each band is widened by :func:`noise_widening` half-widths on
    either side (none under white noise), and the stretches disagree when
    the highest lower limit exceeds the lowest upper limit by more than the
    tolerance: one gradient bin
    (the resolution of the CLD), or, with the Monte Carlo errors
    (``result.ci_se``), two standard errors of that difference when larger.
    A constant parameter lies in both bands; no value does.

    Parameters
    ----------
    result : DyniaResult
        With the half window in its settings.
    p : int
        The parameter's position.
    windows : ndarray of bool, shape (n_steps,)
        The windows whose evidence is compared.

    Returns
    -------
    Disagreement or None
        None when fewer than two stretches or their bands overlap within the tolerance.
    """
    before, after = result.window_halos
    length = before + after + 1
    stretches = window_stretches(windows, length, bridge=length)
    if len(stretches) < 2:
        return None
    bands = stretch_bands(result, p, stretches)
    compared = widened(bands, noise_widening(result))
    below, above = int(np.argmin(compared[:, 1])), int(np.argmax(compared[:, 0]))
    gap = float(compared[above, 0] - compared[below, 1])
    low, high = result.bounds[p]
    tolerance = float(high - low) / result.gradient.shape[1]
    if result.ci_se is not None:
        se_upper = np.median(result.ci_se[p, stretches[below], 1])
        se_lower = np.median(result.ci_se[p, stretches[above], 0])
        tolerance = max(tolerance, 2 * math.hypot(se_upper, se_lower))
    if not gap > tolerance:  # NaN: no comparison
        return None
    return Disagreement(stretches=stretches, bands=bands, below=below, above=above, gap=gap, tolerance=tolerance)


def _drift(result, p, blocks, drift_tolerance):
    """A StructureWarning if the blocks of parameter ``p`` locate it apart, else None."""
    if len(blocks) < 2 * _CONFIRMING_BLOCKS:
        return None
    name = result.names[p]
    low, high = result.bounds[p]
    centres = result.bin_centres[p]
    locations = np.array([centres[np.argmax(result.gradient[p][:, steps].sum(axis=1))] for steps in blocks])
    bands = stretch_bands(result, p, blocks)
    k = max(_CONFIRMING_BLOCKS, math.ceil(_CONFIRMING_SHARE * len(blocks)))
    order = np.argsort(locations, kind="stable")
    lowest, highest = int(order[k - 1]), int(order[-k])
    spread = float((locations[highest] - locations[lowest]) / (high - low))
    low_band = np.median(bands[locations <= locations[lowest]], axis=0)
    high_band = np.median(bands[locations >= locations[highest]], axis=0)
    separated = locations[highest] > low_band[1] and locations[lowest] < high_band[0]
    # Locations are bin centres, so the spread is a whole number of bins; the
    # relative margin keeps a spread of exactly the tolerance from passing by rounding.
    if spread <= drift_tolerance * (1 + 1e-9) or not separated:
        return None
    times = np.array([[result.time[steps[0]], result.time[steps[-1]]] for steps in blocks])
    import scipy.stats  # here: it takes a second to import, and only a drifting parameter needs it

    trend = float(scipy.stats.spearmanr(np.arange(len(blocks)), locations)[0])

    def at(block):
        return f"{locations[block]:.3g} (t={times[block, 0]:g}-{times[block, 1]:g})"

    if abs(trend) >= _TREND:
        first, last = sorted((lowest, highest))
        course = (
            f"moves from {at(first)} to {at(last)}, {100 * spread:.0f} % of its range "
            f"[{low:g}, {high:g}], {'rising' if trend > 0 else 'falling'} over time"
        )
    else:
        course = (
            f"goes back and forth between {at(lowest)} and {at(highest)}, "
            f"{100 * spread:.0f} % of its range [{low:g}, {high:g}]"
        )
    message = (
        f"the location of the CLD-gradient maximum of {name} {course} ({len(blocks)} "
        f"informative segments); a constant parameter should not move: the model structure "
        f"may be wrong (thesis 4.4), unless {name} really varies over time"
    )
    return StructureWarning(
        parameter=name,
        segments=tuple((int(s[0]), int(s[-1]) + 1) for s in blocks),
        times=times,
        locations=locations,
        bands=bands,
        compared=(lowest, highest),
        spread=spread,
        trend=trend,
        message=message,
    )
