"""From information content to data segments.

The thesis (sections 4.3 and 4.4) proposes DYNIA as the first step of system
identification: select the data segments of high information content, then
estimate the parameters on those segments with least squares (its section
1.2.3.1) and check the model on other data. This module does the selection:
:func:`segments_from_ic` turns IC curves into segments: the informative
windows (:meth:`dynia.result.DyniaResult.informative_windows`, the package's
one rule) at the steps their IC is plotted at, the windows' centres
(:meth:`dynia.result.DyniaResult.window_centres`); :mod:`dynia.fit` fits the
model on them and scores it on held-out data. Shapes follow
:mod:`dynia.engine.windows`.

Segments
--------
A segment is a pair ``(start, stop)`` of step indices, ``stop`` exclusive, so
it holds steps ``start .. stop-1``. A list of segments is sorted by start,
non-overlapping (``stop`` of one <= ``start`` of the next; touching is
allowed) and inside the record, ``0 <= start < stop <= n_steps``;
:func:`check_segments` enforces this. :func:`segments_to_times` gives the
``[start_time, end_time]`` pairs to report, end_time being the time of the
segment's last step.

Validation data
---------------
:func:`holdout_split` holds out the last 30 % of the record by default. The
same block serves every selection method (DYNIA segments, a baseline's
intervals, the whole record, random segments), so their validation errors
compare; the complement of the fitted segments would differ per method and
be empty for the whole record. A block at the end predicts forward in time,
as the model will be used, and keeps correlated neighbouring noise out of
the fit. The held-out output must not inform the selection either: blank it
(NaN) in the data given to :func:`dynia.run` and to :func:`~dynia.fit.fit_segments`.

Workflow (what ``dynia identify`` does)
---------------------------------------
::

    fit_part, held_out = holdout_split(u.size, 0.3)
    y_fit = np.where(segments_to_mask(held_out, u.size), np.nan, y)
    result = dynia.run(u, y_fit, model, bounds, ...)              # --method dynia
    segments = intersect_segments(segments_from_ic(result), fit_part)
    # --method whole: segments = fit_part
    # random comparison: random_segments([b - a for a, b in segments], u.size, rng, exclude=held_out)
    fit = fit_segments(u, y_fit, model, segments, bounds=bounds, dt=dt)
    error = fit.validation_error(u, y, held_out)

Examples
--------
>>> holdout_split(100)
([(0, 70)], [(70, 100)])
"""

import math
import numbers
from collections.abc import Mapping

import numpy as np

from . import _checks
from .errors import DataError, NothingSelected, SettingsError
from .settings import IC_THRESHOLD

__all__ = [
    "check_segments",
    "segments_to_mask",
    "mask_to_segments",
    "intersect_segments",
    "segments_from_ic",
    "segments_to_times",
    "random_segments",
    "holdout_split",
]

MODES = ("any", "joint", "per_parameter")

# random_segments restarts the placement this often before giving up.
_PLACEMENT_ATTEMPTS = 1000

# ---------------------------------------------------------------- segments


def check_segments(segments, n_steps=None, name="segments"):
    """Validate a list of segments, against a record of ``n_steps`` steps if given.

    Parameters
    ----------
    segments : sequence of (start, stop) pairs of int, or array of shape (k, 2)
        Steps ``start .. stop-1`` each; sorted, non-overlapping (touching is
        fine), ``0 <= start < stop <= n_steps``. May be empty.
    n_steps : int, optional
        Length of the record; without it only ``0 <= start < stop`` is checked.
    name : str
        Argument name used in error messages.

    Returns
    -------
    list of tuple of int
        The segments as ``(start, stop)`` tuples of Python ints.

    Raises
    ------
    ValueError
        Naming the first offending segment and what is wrong with it.

    Examples
    --------
    >>> check_segments([[0, 5], (7, 9)], 10)
    [(0, 5), (7, 9)]
    >>> check_segments([(0, 5), (4, 9)], 10)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    dynia.errors.SettingsError: segments[1] = (4, 9) overlaps segments[0] = (0, 5); ...
    """
    if n_steps is not None:
        n_steps = _checks.whole_number(n_steps, "n_steps", minimum=1)
    if isinstance(segments, (str, bytes, Mapping)):
        raise TypeError(f"{name} must be a sequence of (start, stop) pairs; got {type(segments).__name__}")
    checked = []
    for position, pair in enumerate(segments):
        try:
            if isinstance(pair, (str, bytes)):
                raise TypeError
            start, stop = pair
        except (TypeError, ValueError):
            raise SettingsError(f"{name}[{position}] must be a (start, stop) pair; got {pair!r}") from None
        start, stop = (_index(value, f"{name}[{position}]") for value in (start, stop))
        if not 0 <= start < stop or (n_steps is not None and stop > n_steps):
            record = "" if n_steps is None else f" of a record of {n_steps} steps"
            limit = "" if n_steps is None else f" <= {n_steps}"
            raise SettingsError(
                f"{name}[{position}] = ({start}, {stop}) is not a segment{record}; "
                f"need 0 <= start < stop{limit} (stop is exclusive)"
            )
        if checked and start < checked[-1][1]:
            order = "overlaps" if start >= checked[-1][0] else "starts before"
            raise SettingsError(
                f"{name}[{position}] = ({start}, {stop}) {order} {name}[{position - 1}] = "
                f"{checked[-1]}; segments must be sorted and non-overlapping"
            )
        checked.append((start, stop))
    return checked


def _index(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        if isinstance(value, numbers.Real) and float(value).is_integer():
            return int(value)
        raise SettingsError(f"{name} must hold whole step indices; got {value!r}")
    return int(value)


def segments_to_mask(segments, n_steps):
    """Boolean mask of the steps inside ``segments``, shape (n_steps,).

    Examples
    --------
    >>> segments_to_mask([(1, 3)], 5).tolist()
    [False, True, True, False, False]
    """
    mask = np.zeros(_checks.whole_number(n_steps, "n_steps", minimum=1), dtype=bool)
    for start, stop in check_segments(segments, n_steps):
        mask[start:stop] = True
    return mask


def mask_to_segments(mask):
    """The runs of True in a boolean mask, as segments.

    Examples
    --------
    >>> mask_to_segments([True, True, False, True])
    [(0, 2), (3, 4)]
    """
    mask = np.asarray(mask)
    if mask.ndim != 1 or mask.dtype != bool:
        raise DataError(f"mask must be a 1-D boolean array; got dtype {mask.dtype}, shape {mask.shape}")
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return [(int(start), int(stop)) for start, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1))]


def intersect_segments(segments, allowed):
    """The parts of ``segments`` that lie inside ``allowed`` (both lists of segments).

    Use it to keep a selection inside the fitting part of the record.

    Examples
    --------
    >>> intersect_segments([(0, 10), (20, 40)], [(5, 30)])
    [(5, 10), (20, 30)]
    """
    segments = check_segments(segments)
    allowed = check_segments(allowed, name="allowed")
    common = []
    for start, stop in segments:
        for low, high in allowed:
            if max(start, low) < min(stop, high):
                common.append((max(start, low), min(stop, high)))
    return common


def segments_from_ic(
    result, *, ic_threshold=IC_THRESHOLD, min_length=None, merge_gap=None, parameters=None, mode="any"
):
    """Segments where the windows are informative: the data selection of ``dynia identify``.

    A step is selected where the window whose IC belongs to it is
    informative (:meth:`~dynia.result.DyniaResult.informative_windows`: IC
    at least ``ic_threshold``, above the noise floor, behavioural set not
    tied within noise). The IC of a window belongs to the step at its
    centre, where the plots draw it: for a run with ``window="trailing"``
    (read from ``result.settings``) the IC at ``t`` counts for step
    ``t - n``. Gaps shorter than ``merge_gap`` steps between informative
    runs are closed, then runs shorter than ``min_length`` steps are dropped.
    This is the package's one map from informative windows to data: the data
    quality checks locate their findings in these segments too.

    Parameters
    ----------
    result : DyniaResult
        A DYNIA run; its ``ic`` is (n_params, n_steps).
    ic_threshold : float or mapping of str to float, default :data:`dynia.settings.IC_THRESHOLD` (0.5)
        IC from which a window is informative, in [0, 1]; a mapping gives
        one per parameter (every chosen parameter needs one).
    min_length : int, optional
        Shortest run kept. Default: one window, ``2n+1`` steps, with ``n``
        from ``result.settings`` (1 when unknown). Neighbouring windows share
        all but one of their points, so a run shorter than a window is a
        handful of windows seeing the same few points.
    merge_gap : int, optional
        Gaps shorter than this are closed. Default: ``n`` steps from
        ``result.settings`` (0 when unknown): a dip shorter than half a
        window separates windows that still share most of their data.
    parameters : str or sequence of str, optional
        The parameters considered (default: all of ``result.names``).
    mode : {"any", "joint", "per_parameter"}, default "any"
        ``"any"``: a step is selected when at least one parameter's window
        is informative; the union of what each parameter needs, the data to
        fit all parameters together. ``"joint"``: every parameter's must be.
        ``"per_parameter"``: the segments of each parameter (a parameter
        may have none, as long as one has some).

    Returns
    -------
    list of (start, stop), or dict of str to such lists for ``"per_parameter"``

    Raises
    ------
    NothingSelected
        When no segment is left: lower ``ic_threshold`` or ``min_length``.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.result import DyniaResult
    >>> ic = np.array([[0.9, 0.9, 0.2, 0.9, 0.9, np.nan, 0.1],
    ...                [0.1, 0.8, 0.8, 0.8, 0.1, 0.1, 0.9]])
    >>> result = DyniaResult(names=("K", "T"), samples=np.zeros((2, 2)), bounds=np.array([[0.0, 1], [0, 1]]),
    ...                      time=np.arange(7.0), ic=ic, ci=np.zeros((2, 7, 2)), gradient=np.zeros((2, 1, 7)),
    ...                      bin_centres=np.zeros((2, 1)))  # no settings: each window is its own step
    >>> segments_from_ic(result, mode="joint")
    [(1, 2), (3, 4)]
    >>> segments_from_ic(result, mode="joint", merge_gap=2, min_length=2)
    [(1, 4)]
    >>> segments_from_ic(result, mode="per_parameter")
    {'K': [(0, 2), (3, 5)], 'T': [(1, 4), (6, 7)]}
    >>> import dataclasses
    >>> floored = dataclasses.replace(result, informative=np.array([True, True, True, True, False, False, False]))
    >>> segments_from_ic(floored, mode="per_parameter")
    {'K': [(0, 2), (3, 4)], 'T': [(1, 4)]}
    """
    _checks.analysis_result(result)
    if mode not in MODES:
        raise SettingsError(f"mode must be one of {MODES}; got {mode!r}")
    chosen = _chosen_parameters(parameters, result.names)
    limits = _thresholds(ic_threshold, chosen)
    half_window = None if result.settings is None else result.settings.n
    window_length = None if half_window is None else 2 * half_window + 1
    min_length = _default_length(min_length, "min_length", 1, 1 if window_length is None else window_length)
    merge_gap = _default_length(merge_gap, "merge_gap", 0, 0 if half_window is None else half_window)
    informative = np.array([result.informative_windows(limit, name)[0] for name, limit in zip(chosen, limits)])
    if half_window is not None:
        informative = np.array([result.window_centres(row) for row in informative])
    if mode == "per_parameter":
        found = {name: _clean_runs(row, merge_gap, min_length) for name, row in zip(chosen, informative)}
        selected = any(found.values())
    else:
        combined = informative.all(axis=0) if mode == "joint" else informative.any(axis=0)
        found = _clean_runs(combined, merge_gap, min_length)
        selected = bool(found)
    if not selected:
        raise NothingSelected(
            f"segments_from_ic selected nothing: no run of at least min_length={min_length} steps of windows "
            f"informative about {_which(chosen, mode)} (IC >= {_limits_text(chosen, limits)}, above the noise floor, "
            "behavioural set untied); lower ic_threshold or min_length"
            + ("" if mode != "joint" or len(chosen) == 1 else ", or use mode 'any'")
        )
    return found


def _which(chosen, mode):
    """The parameters a selection looked at, in words."""
    if len(chosen) == 1:
        return chosen[0]
    return ("all of " if mode == "joint" else "any of ") + ", ".join(chosen)


def _limits_text(chosen, limits):
    """The thresholds in words: one number, or one per parameter."""
    if len(set(limits.tolist())) == 1:
        return f"{limits[0]:g}"
    return ", ".join(f"{limit:g} for {name}" for name, limit in zip(chosen, limits))


def _chosen_parameters(parameters, names):
    if parameters is None:
        return names
    if isinstance(parameters, str):
        parameters = [parameters]
    chosen = tuple(parameters)
    unknown = [name for name in chosen if name not in names]
    if unknown or not chosen:
        raise SettingsError(
            f"parameters must name some of the result's parameters {list(names)}; "
            f"got {list(chosen)}" + (f" (unknown: {unknown})" if unknown else "")
        )
    if len(set(chosen)) != len(chosen):
        raise SettingsError(f"parameters names a parameter twice: {list(chosen)}")
    return chosen


def _thresholds(ic_threshold, chosen):
    if isinstance(ic_threshold, Mapping):
        missing = [name for name in chosen if name not in ic_threshold]
        unknown = [name for name in ic_threshold if name not in chosen]
        if missing or unknown:
            raise SettingsError(
                f"ic_threshold must give a value for each parameter {list(chosen)}"
                + (f"; missing: {missing}" if missing else "")
                + (f"; not among them: {unknown}" if unknown else "")
            )
        values = [ic_threshold[name] for name in chosen]
    else:
        values = [ic_threshold] * len(chosen)
    for name, value in zip(chosen, values):
        if (
            isinstance(value, bool)
            or not isinstance(value, numbers.Real)
            or not math.isfinite(value)
            or not 0 <= value <= 1
        ):
            raise SettingsError(f"ic_threshold of {name} must be a number in [0, 1] (IC lies there); got {value!r}")
    return np.array(values, dtype=float)


def _default_length(value, name, minimum, default):
    return default if value is None else _checks.whole_number(value, name, minimum=minimum)


def _clean_runs(mask, merge_gap, min_length):
    runs = []
    for start, stop in mask_to_segments(mask):
        if runs and start - runs[-1][1] < merge_gap:
            runs[-1] = (runs[-1][0], stop)
        else:
            runs.append((start, stop))
    return [(start, stop) for start, stop in runs if stop - start >= min_length]


def segments_to_times(segments, time):
    """``[start_time, end_time]`` of each segment; end_time is the time of its last step.

    Parameters
    ----------
    segments : list of (start, stop)
    time : array_like, shape (n_steps,)
        Time of each step, e.g. ``result.time``.

    Returns
    -------
    list of [float, float]

    Examples
    --------
    >>> segments_to_times([(0, 2), (5, 8)], [0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0])
    [[0.0, 2.0], [10.0, 14.0]]
    """
    time = _checks.as_1d_float(time, "time")
    return [[float(time[start]), float(time[stop - 1])] for start, stop in check_segments(segments, time.size)]


def random_segments(lengths, n_steps, rng=None, *, exclude=None):
    """Non-overlapping segments of the given lengths at random places.

    For comparing a selection with chance: pass the lengths of the selected
    segments, ``[stop - start for start, stop in segments]``, to draw random
    segments of the same number, lengths and total length.

    Parameters
    ----------
    lengths : sequence of int
        Length of each segment, >= 1.
    n_steps : int
        Length of the record.
    rng : numpy.random.Generator or int, optional
        Source of the draws; the same seed gives the same segments.
    exclude : list of (start, stop), optional
        Steps no segment may touch, e.g. the held-out validation data.

    Returns
    -------
    list of (start, stop)
        Sorted by start. Segments are placed one at a time in random order,
        each uniformly among the places still free; segments may touch.

    Raises
    ------
    ValueError
        When the lengths do not fit in the free steps.

    Examples
    --------
    >>> segments = random_segments([5, 3], 20, rng=1, exclude=[(10, 20)])
    >>> sorted(stop - start for start, stop in segments), max(stop for _, stop in segments) <= 10
    ([3, 5], True)
    """
    n_steps = _checks.whole_number(n_steps, "n_steps", minimum=1)
    if isinstance(lengths, (numbers.Number, str)):
        raise SettingsError(f"lengths must be a sequence of segment lengths; got {lengths!r}")
    lengths = [
        _checks.whole_number(length, f"lengths[{position}]", minimum=1) for position, length in enumerate(lengths)
    ]
    free = np.ones(n_steps, dtype=bool) if exclude is None else ~segments_to_mask(exclude, n_steps)
    if sum(lengths) > free.sum():
        raise SettingsError(
            f"the lengths total {sum(lengths)} steps but only {int(free.sum())} of the {n_steps} steps are free"
        )
    rng = _checks.generator(rng)
    for _ in range(_PLACEMENT_ATTEMPTS):
        placed = _place(lengths, free, rng)
        if placed is not None:
            return sorted(placed)
    raise SettingsError(
        f"could not place segments of lengths {lengths} in the free steps after "
        f"{_PLACEMENT_ATTEMPTS} attempts; the free part of the record is too fragmented"
    )


def _place(lengths, free, rng):
    """One random placement, or None when a segment found no room."""
    available = free.copy()
    placed = []
    for position in rng.permutation(len(lengths)):
        length = lengths[position]
        taken = np.concatenate(([0], np.cumsum(~available)))
        starts = np.flatnonzero(taken[length:] - taken[:-length] == 0)
        if starts.size == 0:
            return None
        start = int(starts[rng.integers(starts.size)])
        available[start : start + length] = False
        placed.append((start, start + length))
    return placed


def holdout_split(n_steps, held_out=0.3):
    """Split a record into a part for selection and fitting and a held-out part.

    Parameters
    ----------
    n_steps : int
        Length of the record.
    held_out : float in (0, 1) or list of (start, stop), default 0.3
        A fraction holds out that share of the record at its end (rounded
        to whole steps); a list of segments holds out exactly those. See the
        module documentation for why the end of the record is the default.

    Returns
    -------
    fit_part, validation : list of (start, stop)
        Complementary lists of segments, neither empty.

    Examples
    --------
    >>> holdout_split(100)
    ([(0, 70)], [(70, 100)])
    >>> holdout_split(100, [(20, 40)])
    ([(0, 20), (40, 100)], [(20, 40)])
    """
    n_steps = _checks.whole_number(n_steps, "n_steps", minimum=2)
    if isinstance(held_out, numbers.Real) and not isinstance(held_out, bool):
        fraction = _checks.open_interval(held_out, "held_out", 0, 1)
        n_validation = min(max(int(round(fraction * n_steps)), 1), n_steps - 1)
        validation = [(n_steps - n_validation, n_steps)]
    else:
        validation = check_segments(held_out, n_steps, name="held_out")
        if not validation:
            raise SettingsError("held_out is an empty list of segments; hold out at least one step")
    fit_part = mask_to_segments(~segments_to_mask(validation, n_steps))
    if not fit_part:
        raise SettingsError("held_out covers the whole record; nothing is left to fit")
    return fit_part, validation
