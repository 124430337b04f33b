"""The tests of :func:`dynia.quality.check_quality` on one signal, one per kind of fault it finds.

Each test takes the signal's present samples (absurd magnitudes left out of
all but their own test) and the tuning of check_quality, and returns the
runs it flags as (start, stop, value, reason), start and stop indexing those
samples; :func:`fault_runs` runs them all. What each test looks for, and why
its tuning defaults to what it does, is the module documentation of
:mod:`dynia.quality`.
"""

import math

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from .segments import mask_to_segments
from .settings import MAD_TO_STD

# Changes of a quantised signal are whole multiples of its step to within this share of the step.
_GRID_TOLERANCE = 1e-3

# Scales never fall below this fraction of a signal's size (see dynia.quality's module docstring).
_RESOLUTION = 1e-6
# Readings this fraction of a signal's size apart are one value read at a limit, rounded (saturated runs).
_ROUNDING = 1e-9
# The usual run length of a signal is this quantile of its run lengths.
_USUAL_RUN_QUANTILE = 0.95
# A run entered by _SETTLING_STEPS steps all below _SETTLED_FRACTION of the median step is
# a steady state reached smoothly, not a tag that froze.
_SETTLING_STEPS = 3
_SETTLED_FRACTION = 1e-3
# A value larger than this squares to more than 1e300, and a sum of such squares
# overflows: it is a magnitude finding whatever max_magnitude says.
SQUARABLE = 1e150


def fault_runs(values, settings, *, output, screened_steps):
    """Every run one signal's tests flag: magnitudes among its present samples, the other tests on the rest.

    Parameters
    ----------
    values : ndarray, shape (n_steps,)
        The signal, NaN where a sample is missing.
    settings : dict
        The tuning of :func:`dynia.quality.check_quality`, checked.
    output : bool
        Whether the signal is the output, the only one tested for quantisation.
    screened_steps : int
        The grid steps below which :func:`dynia.quality.screen` screens a window of a quantised output, which
        the quantised finding's reason names.

    Returns
    -------
    list of (samples, kind, start, stop, value, reason)
        In the order check_quality reports them: per kind, by start. ``samples`` are the indices of ``values``
        the test ran on, and ``[start, stop)`` the run among them.
    """
    present = np.flatnonzero(~np.isnan(values))
    absurd = np.abs(values[present]) > min(settings["max_magnitude"], SQUARABLE)
    found = [(present, "magnitude", *run) for run in _magnitudes(values[present], absurd, settings)]
    where = present[~absurd]
    if where.size == 0:
        return found
    x = values[where]
    # Rounded inwards, the quantiles leave out at least the most extreme value at
    # each end even in a record shorter than 1/outlier_quantile samples.
    low = np.quantile(x, settings["outlier_quantile"], method="higher")
    high = np.quantile(x, 1 - settings["outlier_quantile"], method="lower")
    floor = _RESOLUTION * max(high - low, abs(float(np.median(x))))

    found += [(where, "glitch", *run) for run in _glitches(x, high - low, floor, settings)]
    found += [(where, "outlier", *run) for run in _outliers(x, low, high, floor, settings)]
    saturated = _saturated_runs(x, floor, settings)
    found += [(where, "saturated", *run) for run in saturated]
    # A run at the record's extreme is a sensor at its limit: reported as saturated, never also as frozen.
    stuck = [run for run in _stuck_runs(x, settings) if not any(_overlap(run, other) for other in saturated)]
    found += [(where, "stuck", *run) for run in stuck]
    if output:
        found += [(where, "quantised", *run) for run in _quantisation(x, floor, settings, screened_steps)]
    return found


def _overlap(run, other):
    return run[0] < other[1] and other[0] < run[1]


def _magnitudes(x, absurd, settings):
    """(start, stop, value, reason) of every run of values too large in size to be a measurement."""
    limit = settings["max_magnitude"]
    found = []
    for start, stop in mask_to_segments(absurd):
        run = x[start:stop]
        worst = run[np.argmax(np.abs(run))]
        why = (
            f"its size exceeds max_magnitude = {limit:g}: a sentinel, a unit or parsing error or a corrupted reading"
            if limit <= SQUARABLE
            else f"its size exceeds {SQUARABLE:g}, beyond which squaring it in a cost overflows"
        )
        found.append((start, stop, worst, f"{worst:.6g} is no plausible reading, {why}; left out of the other tests"))
    return found


def _glitches(x, bulk_width, floor, settings):
    """(start, stop, value, reason) of every glitch, in present-sample indices."""
    longest = settings["max_glitch_length"]
    if longest == 0 or x.size < 3:
        return []
    half, threshold = settings["half_window"], settings["glitch_threshold"]
    windows = sliding_window_view(np.pad(x, half, constant_values=np.nan), 2 * half + 1)
    local = np.nanmedian(windows, axis=1)
    local_mad = np.nanmedian(np.abs(windows - local[:, None]), axis=1)
    # The record's own noise level (from sample-to-sample steps) is a floor for the
    # local scale: in a short window that happens to be smooth the MAD is near 0.
    noise = MAD_TO_STD * float(np.median(np.abs(np.diff(x)))) / math.sqrt(2)
    scale = np.maximum(np.maximum(MAD_TO_STD * local_mad, noise), floor)
    departure = np.abs(x - local)
    far = (departure > threshold * scale) & (departure >= settings["glitch_min_size"] * bulk_width)
    found = []
    for start, stop in mask_to_segments(far):
        if stop - start > longest:
            continue
        run, run_scale = x[start:stop], scale[start:stop]
        neighbours = [x[i] for i in (start - 1, stop) if 0 <= i < x.size]
        if not all((np.abs(run - neighbour) > threshold * run_scale).all() for neighbour in neighbours):
            continue
        worst = start + int(np.argmax(departure[start:stop] / run_scale))
        size = float(departure[worst] / scale[worst])
        found.append(
            (
                start,
                stop,
                x[worst],
                (
                    f"{stop - start} sample{'s' if stop - start > 1 else ''} at {x[worst]:.6g} "
                    f"{size:.3g} robust standard deviations from the local median {local[worst]:.6g} "
                    "and far from both neighbours: an isolated erroneous reading"
                ),
            )
        )
    return found


def _outliers(x, low, high, floor, settings):
    """(start, stop, value, reason) of every run of values outside the fenced bulk."""
    margin = max(settings["outlier_fence"] * (high - low), floor)
    below, above = low - margin, high + margin
    found = []
    for start, stop in mask_to_segments((x < below) | (x > above)):
        run = x[start:stop]
        worst = run[np.argmax(np.maximum(below - run, run - above))]
        found.append(
            (
                start,
                stop,
                worst,
                (
                    f"{worst:.6g} lies outside [{below:.6g}, {above:.6g}], the record's bulk "
                    f"[{low:.6g}, {high:.6g}] widened by {settings['outlier_fence']:g} times its width"
                ),
            )
        )
    return found


def _usual_run(steps, tolerance):
    """The usual length of a signal's runs of equal readings (:data:`_USUAL_RUN_QUANTILE` of them) and their bounds."""
    changes = np.flatnonzero(steps > tolerance) + 1
    starts = np.r_[0, changes]
    stops = np.r_[changes, steps.size + 1]
    return float(np.quantile(stops - starts, _USUAL_RUN_QUANTILE)), starts, stops


def _settled_into(steps, start, settled):
    """Whether the steps before ``start`` all shrank below ``settled``: a steady state reached smoothly."""
    approach = steps[max(start - _SETTLING_STEPS, 0) : start]
    return bool(approach.size) and bool((approach <= settled).all())


def _saturated_runs(x, floor, settings):
    """(start, stop, value, reason) of every long run of readings at the record's maximum or minimum."""
    high, low = float(x.max()), float(x.min())
    if x.size < 2 or high - low <= floor:
        return []
    floor *= _ROUNDING / _RESOLUTION  # readings at the limit are one value but for rounding
    steps = np.abs(np.diff(x))
    top, bottom = x >= high - floor, x <= low + floor
    off = ~(top | bottom)
    inner = steps[off[:-1] & off[1:]]  # the steps between readings off the extremes
    tolerance = settings["stuck_tolerance"]
    if inner.size < settings["min_saturated"] or (inner <= tolerance).mean() >= 0.5:
        return []  # the signal does not move off its extremes: a held or switching input, not a clipped sensor
    usual, _, _ = _usual_run(steps, tolerance)
    shortest = max(settings["min_saturated"], settings["stuck_factor"] * usual)
    settled = _SETTLED_FRACTION * float(np.median(steps))
    found = []
    for at_extreme, value, which in ((top, high, "maximum"), (bottom, low, "minimum")):
        for start, stop in mask_to_segments(at_extreme):
            # A run that opens the record may have been entered any way: a noise-free output at rest before the
            # first input step sits at its minimum exactly like a clipped sensor.
            if start == 0 or stop - start < shortest or _settled_into(steps, start, settled):
                continue
            exact = bool((x[start:stop] == value).all())
            found.append(
                (
                    start,
                    stop,
                    value,
                    (
                        f"saturated at {value:.6g} (its record {which}) for {stop - start} consecutive readings"
                        + ("" if exact else f", each within {floor:.3g}")
                        + ": a sensor at the end of its range reads its limit, not the process"
                    ),
                )
            )
    return sorted(found)


def _quantisation(x, floor, settings, screened_steps):
    """[(0, n, q, reason)] when the output lies on a grid of step q coarser than its noise, else [].

    The reason says that a window where the output moves by fewer than ``screened_steps`` grid steps holds rounding.
    """
    if x.size < 2:
        return []
    steps = np.abs(np.diff(x))
    changes = steps[steps > floor]
    if changes.size < settings["quantised_min_changes"]:
        return []
    step = float(changes.min())
    multiples = changes / step
    if np.abs(multiples - np.rint(multiples)).max() > _GRID_TOLERANCE:
        return []
    levels = (float(x.max()) - float(x.min())) / step
    noise = MAD_TO_STD * float(np.median(np.where(steps > floor, steps, 0.0))) / math.sqrt(2)
    if levels < settings["quantised_min_levels"] or not step > 2 * noise:
        return []
    equal = float(np.mean(steps <= floor))
    reason = (
        f"takes values on a grid of step {step:.6g} over {levels:.0f} steps, and {100 * equal:.0f} % of its "
        f"consecutive readings are equal: the noise (robust standard deviation {noise:.3g}) hides under the grid, "
        f"so a window where it moves by fewer than {screened_steps} steps holds rounding, not dynamics"
    )
    return [(0, x.size, step, reason)]


def _stuck_runs(x, settings):
    """(start, stop, value, reason) of every run of equal readings much longer than usual."""
    if x.size < 2:
        return []
    steps = np.abs(np.diff(x))
    equal = steps <= settings["stuck_tolerance"]
    if equal.mean() >= 0.5:
        return []  # the signal is flat more often than not: a repeat is its normal behaviour
    tolerance = settings["stuck_tolerance"]
    usual, starts, stops = _usual_run(steps, tolerance)
    shortest = max(settings["min_stuck"], settings["stuck_factor"] * usual)
    settled = _SETTLED_FRACTION * float(np.median(steps))
    found = []
    for start, stop in zip(starts.tolist(), stops.tolist(), strict=True):
        # As for saturated runs: how a run that opens the record was entered is unknown (an output at rest).
        if start == 0 or stop - start < shortest or _settled_into(steps, start, settled):
            continue
        found.append(
            (
                start,
                stop,
                x[start],
                (
                    f"{stop - start} consecutive readings equal to {x[start]:.6g}"
                    + (f" within {tolerance:g}" if tolerance else "")
                    + f", where this signal's runs of equal readings are usually at most {usual:g} long: "
                    "a frozen sensor or tag"
                ),
            )
        )
    return found
