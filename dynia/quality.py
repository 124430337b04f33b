"""Data quality of an input/output record: absurd magnitudes, glitches, outliers, saturated, stuck and quantised values.

A DYNIA window is only as good as the samples in it. In the thesis's case
study (section 3.1.3) the highest information content of the time constant
came from one erroneous reading, where input and output read 0 for one
sample and then returned to their steady values; the thesis concludes that
high-IC segments must be checked for erroneous data. :func:`check_quality`
does that check on the record, :meth:`QualityReport.findings_in` says which
findings fall inside the informative segments of a result
(:func:`dynia.segments.segments_from_ic`), and :meth:`QualityReport.exclude` removes the
flagged samples before a new run.

Shapes follow the package convention (see :mod:`dynia.engine`): ``time``,
``u`` and ``y`` are (n_steps,). NaN marks a missing sample: it is never
flagged, and every test runs on the samples present, so the neighbours of a
sample are the nearest samples present.

What is detected, per signal (``"u"`` and ``"y"``)
--------------------------------------------------
magnitude
    A value larger in size than ``max_magnitude``, or than 1e150, beyond
    which squaring it in a cost overflows to inf (the mean absolute error of
    the simulated output is far from its bulk then too): a sentinel of the
    logging system, a unit or parsing error, a corrupted reading.
    Consecutive such samples form one finding. They are left out of the
    other tests, like missing samples, so that one 1e308 cell does not turn
    the bulk and the noise level of its signal into inf.
glitch
    A run of at most ``max_glitch_length`` samples that departs from the
    local robust trend (a Hampel filter: median and MAD over
    ``2*half_window + 1`` samples) by more than ``glitch_threshold`` robust
    standard deviations and from both neighbours of the run by as much, then
    returns, and whose departure is at least ``glitch_min_size`` times the
    width of the signal's bulk (see outlier): the thesis's zero reading.
outlier
    A value outside the bulk of the whole record: more than
    ``outlier_fence`` bulk widths below the ``outlier_quantile`` quantile or
    above the ``1 - outlier_quantile`` quantile (both rounded inwards to a
    sample, so that even a short record leaves its most extreme value out of
    the bulk). Consecutive outlying samples form one finding.
saturated
    A run of consecutive readings at the signal's record maximum or minimum
    (exactly, or within ``1e-9`` of the signal's size: the rounding of a
    unit conversion or an offset subtracted; a smooth output settling
    within the floor below of its maximum is no sensor at its limit), at least
    ``min_saturated`` long and at least ``stuck_factor`` times as long as the
    signal's usual runs, in a signal that moves from most samples to the
    next off its extremes, entered with a step rather than settled into: a
    sensor or transmitter at the end of its range (a tank level at its top)
    reads its limit, not the process. Reported at the value measured, and
    never also as stuck.
stuck
    A frozen sensor or tag: a run of consecutive readings that differ by at
    most ``stuck_tolerance``, at least ``min_stuck`` long and at least
    ``stuck_factor`` times as long as the signal's usual runs (the 95th
    percentile of its run lengths), in a signal that moves from most samples
    to the next, entered with a step rather than settled into (a run that
    opens the record is not judged), and not at the signal's record maximum
    or minimum (that is saturated).
quantised (the output only)
    The output takes values on a grid coarser than its noise: every change
    between consecutive readings is a whole multiple of the smallest change
    q (within ``1e-3 q``), the output changes at least
    ``quantised_min_changes`` times and spans at least ``quantised_min_levels``
    grid steps, and the robust noise standard deviation of its changes
    (``1.4826 median|dy| / sqrt(2)`` over every consecutive pair) is below
    q / 2. Every non-zero change is at least q, so that estimate is either 0
    or above 1.05 q: the test is "at least half of the consecutive readings
    are equal in an output that moves", the noise hidden under the grid. One
    finding spans the whole signal, its value the step q. A window whose
    output moves by fewer than a few steps carries no information the model
    can rank (:func:`screen`). Not tested on the input: an input that
    holds a few levels (steps, a PRBS) is an experiment's design, not a
    coarse sensor, and the windows' information is read off the output.

The other kinds are tested independently; one sample can be in several
findings (a zero reading in a signal near 72 is a glitch and an outlier).

Screening
---------
:func:`dynia.run` (and :func:`dynia.distributed.run`) screen the record with
these tests before the analysis when ``settings.quality`` is True, the
default: the saturated, stuck and quantised findings (:data:`SCREENED_KINDS`)
go into ``result.run.screened`` (:func:`screen`), and the windows they
dominate are no evidence for any parameter
(:attr:`dynia.result.DyniaResult.screened_windows`). A saturated or frozen
reading holds no information about the process, and a window that uses one
ranks parameter sets by how well they reproduce a sensor's limit. Glitches,
outliers and absurd magnitudes are reported but not screened: one erroneous
reading is the user's to remove (:meth:`QualityReport.exclude`), and an
outlier may be the record's largest, most informative event.

Tuning parameters
-----------------
=========================  ========  ==============================================================
parameter                  default   reasoning
=========================  ========  ==============================================================
``half_window``            3         Hampel window of 7 samples: short, so the median follows
                                     steps and transients, and long enough that a run of up to
                                     ``max_glitch_length`` bad samples cannot move the median.
``glitch_threshold``       6.0       Robust standard deviations. The textbook Hampel 3 flags
                                     0.3 % of Gaussian noise, tens of false glitches in a
                                     record of thousands; a Gaussian sample departs 6 of them
                                     with probability 2e-9, and both neighbours must be as far.
                                     Heavy-tailed noise does reach it now and then.
``glitch_min_size``        0.1       Gross errors only. A record resampled from an exception
                                     log is straight between stored readings, so its robust
                                     scales are tiny and one ordinary stored reading stands
                                     out by many of them; it moves by a few % of the signal's
                                     range, the thesis's zero reading by several ranges.
``max_glitch_length``      2         One erroneous reading (thesis 3.1.3) lands on one grid
                                     point, or on two at partial depth when resampling falls
                                     between readings. Longer excursions are real events (the
                                     3-sample input dip of the thesis's example 1) or outliers.
``outlier_quantile``       0.01      The bulk of the record is its 1 %-99 % range: a handful
                                     of bad values cannot move it.
``outlier_fence``          1.0       A value one bulk width beyond the bulk: about 7 standard
                                     deviations for Gaussian noise, so only gross errors count.
``min_stuck``              10        Fewer identical readings happen by chance on a quantised
                                     sensor.
``min_saturated``          10        As ``min_stuck``: fewer readings at the extreme happen on a
                                     quantised sensor at a steady high level; a clipped noisy
                                     signal sits there for as long as the process lies beyond.
``stuck_factor``           4.0       A run counts as stuck only when it is much longer than the
                                     signal's own usual runs.
``stuck_tolerance``        0.0       A frozen tag repeats its value exactly.
``max_magnitude``          1e12      No reading of a process variable in the units its historian
                                     logs comes near it; sentinels (1e30, 3.4e38, 1e308) and
                                     corrupted floats lie far beyond. Totalisers in small units
                                     can be large: raise it for them.
``quantised_min_changes``  20        Changes of the output; fewer do not show a grid, and a
                                     signal switching a few times is a record of steps.
``quantised_min_levels``   4         Grid steps the output must span: an output between two or
                                     three values is a noise-free simulation of a switching
                                     input, not a coarse sensor.
=========================  ========  ==============================================================

Every scale has a floor of ``1e-6`` times the signal's size (the larger of
its bulk width and its median magnitude), so that noise-free signals, whose
robust scales are 0, are not flagged for rounding dust, while a single
different value in an otherwise constant signal still is.

Stuck values and legitimate repeats. A constant input during steady
operation is no fault, and a historian logging by exception, resampled by
linear interpolation, repeats a value exactly whenever two stored values are
equal. So a signal is only checked for stuck runs when most of its samples
differ from the previous one (a noisy or moving signal; a piecewise-constant
input is not), and a run is only flagged when it is much longer than the
signal's usual runs. A noise-free output settles into its steady state, the
steps before the run shrinking to nothing, and reaches exactly repeated
values; a frozen tag stops at once. So a run is not flagged when the three
steps before it are all below a thousandth of the signal's median step.
The same guards hold for saturated runs, with one difference: whether the
signal moves is judged on its steps off the extremes, so that a sensor
clipped for much of the record is still checked, and an input that only
switches between two levels (every reading at an extreme) is not; and a
run that opens the record is not judged, since how it was entered is
unknown (a noise-free output at rest before the first input step sits at
its minimum as exactly as a clipped sensor).

Examples
--------
>>> import numpy as np
>>> from dynia.quality import check_quality
>>> rng = np.random.default_rng(0)
>>> u = np.repeat([36.0, 38.0, 36.0], 100)
>>> y = 2 * u + rng.normal(0, 0.3, u.size)
>>> u[150], y[151] = 0.0, 0.0                     # one erroneous reading of each
>>> report = check_quality(np.arange(300.0), u, y)
>>> [(f.signal, f.kind, f.start) for f in report.findings]
[('u', 'glitch', 150), ('u', 'outlier', 150), ('y', 'glitch', 151), ('y', 'outlier', 151)]
>>> clean_y = report.exclude(y, signal="y")     # NaN: missing for dynia.run
>>> clean_u = report.exclude(u, signal="u")     # interpolated: the model needs an input
>>> bool(np.isnan(clean_y[151])), float(clean_u[150])
(True, 38.0)
"""

import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from . import _checks
from ._signal_faults import SQUARABLE, fault_runs
from .errors import DataError, SettingsError
from .io.frames import unpack
from .segments import mask_to_segments

__all__ = [
    "Finding",
    "QualityReport",
    "check_quality",
    "screen",
    "screening",
    "screened_windows",
    "KINDS",
    "QUANTISED_MIN_STEPS",
]

KINDS = ("magnitude", "glitch", "outlier", "saturated", "stuck", "quantised")
# The kinds dynia.run screens: their windows are no evidence (see "Screening" above).
SCREENED_KINDS = ("saturated", "stuck", "quantised")
SIGNALS = ("u", "y")
# A window whose output spans fewer than this many grid steps of a quantised output is screened: with at most three
# levels in it, the rounding (uniform, 0.29 steps standard deviation) is as large as what the output does there.
QUANTISED_MIN_STEPS = 3


@dataclass(frozen=True)
class Finding:
    """One suspicious stretch of one signal.

    Attributes
    ----------
    signal : {"u", "y"}
    kind : {"magnitude", "glitch", "outlier", "saturated", "stuck", "quantised"}
    start, stop : int
        Sample indices ``[start, stop)`` of the stretch (missing samples
        inside it are not flagged); a quantised finding spans the signal.
    start_time, end_time : float
        Time of the first and of the last sample of the stretch.
    value : float
        The most deviant value of the stretch (for magnitude findings: the
        largest in size; for saturated and stuck runs: the value read, in
        the units of the signal checked; for quantised: the grid step).
    reason : str
        One sentence on why it was flagged.
    """

    signal: str
    kind: str
    start: int
    stop: int
    start_time: float
    end_time: float
    value: float
    reason: str


@dataclass(frozen=True, eq=False)
class QualityReport:
    """What :func:`check_quality` found, and how to use it.

    Attributes
    ----------
    findings : tuple of Finding
        Ordered by signal, kind and start.
    time : ndarray, shape (n_steps,)
        Time of each sample.
    missing : dict of str to ndarray of bool
        Per signal, the samples that were missing (NaN); never flagged.
    settings : dict
        The tuning parameters used.
    """

    findings: tuple
    time: np.ndarray
    missing: dict
    settings: dict = field(default_factory=dict)

    def mask(self, signal, kinds=None):
        """Boolean array, shape (n_steps,): the flagged samples of ``signal``.

        Parameters
        ----------
        signal : {"u", "y"}
        kinds : sequence of kinds, optional
            Only these kinds (default: all but "quantised", whose finding
            spans the signal: its readings are right, only rounded).

        Examples
        --------
        >>> import numpy as np
        >>> from dynia.quality import check_quality
        >>> y = np.sin(np.arange(50) / 5.0)
        >>> y[20] = 9.0
        >>> np.flatnonzero(check_quality(None, np.zeros(50), y).mask("y", ["glitch"])).tolist()
        [20]
        """
        signal = _signal_name(signal)
        kinds = _kind_names(kinds)
        flagged = np.zeros(self.time.size, dtype=bool)
        for finding in self.findings:
            if finding.signal == signal and finding.kind in kinds:
                flagged[finding.start : finding.stop] = True
        return flagged & ~self.missing[signal]

    def exclude(self, values, signal="y", kinds=None):
        """A copy of ``values`` without the flagged samples of ``signal``.

        For the output, flagged samples become NaN, which :func:`dynia.run`
        treats as missing: windows use the samples present. The input cannot
        be missing (the simulation needs an input at every step), so for
        ``signal="u"`` flagged samples are replaced by linear interpolation
        in time between the nearest samples that are present and not flagged
        (the nearest such value before the first or after the last one).
        Samples missing in ``values`` already are left as they are.

        Parameters
        ----------
        values : array_like, shape (n_steps,)
            The signal checked (``u`` or ``y``).
        signal : {"u", "y"}, default "y"
            Which of the two it is.
        kinds : sequence of kinds, optional
            Exclude only these kinds (default: all but "quantised", as
            :meth:`mask`).

        Returns
        -------
        ndarray, shape (n_steps,)

        Examples
        --------
        >>> import numpy as np
        >>> from dynia.quality import check_quality
        >>> u, y = np.linspace(1.0, 3.0, 21), np.full(21, 8.0)
        >>> u[10], y[11] = 0.0, 0.0
        >>> report = check_quality(None, u, y)
        >>> float(report.exclude(u, signal="u")[10]), float(report.exclude(y)[11])
        (2.0, nan)
        """
        flagged = self.mask(signal, kinds)
        values = _checks.as_1d_float(values, "values", allow_nan=True)
        if values.size != self.time.size:
            raise DataError(
                f"values has {values.size} samples but the report covers {self.time.size}; "
                "pass the signal that was checked"
            )
        cleaned = values.copy()
        if not flagged.any():
            return cleaned
        if _signal_name(signal) == "y":
            cleaned[flagged] = np.nan
            return cleaned
        usable = ~flagged & ~np.isnan(values)
        if not usable.any():
            raise DataError(
                f"every sample of {signal} that is present is flagged; there is nothing to interpolate from"
            )
        cleaned[flagged] = np.interp(self.time[flagged], self.time[usable], values[usable])
        return cleaned

    def findings_in(self, segments):
        """The findings that overlap each segment, e.g. the high-IC segments of a result.

        Parameters
        ----------
        segments : sequence of (start, stop)
            Sample index ranges ``[start, stop)``, for example from
            :func:`dynia.segments.segments_from_ic`.

        Returns
        -------
        dict
            ``{(start, stop): [Finding, ...]}`` for every segment, in the order
            given; an empty list means the segment is clean.

        Examples
        --------
        >>> import numpy as np
        >>> from dynia.quality import check_quality
        >>> y = np.cos(np.arange(60) / 4.0)
        >>> y[30] = 0.0 if y[30] > 0.5 else 5.0
        >>> found = check_quality(None, np.zeros(60), y).findings_in([(0, 20), (25, 40)])
        >>> {segment: [(f.kind, f.start) for f in hits] for segment, hits in found.items()}
        {(0, 20): [], (25, 40): [('glitch', 30), ('outlier', 30)]}
        """
        checked = {}
        for pair in _segment_pairs(segments, self.time.size):
            checked[pair] = [f for f in self.findings if f.start < pair[1] and pair[0] < f.stop]
        return checked

    def to_dataframe(self):
        """One row per finding: signal, kind, start, stop, start_time, end_time, value, reason.

        Needs pandas (``pip install dynia[pandas]``).
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_dataframe needs pandas: pip install 'dynia[pandas]'") from None
        columns = ["signal", "kind", "start", "stop", "start_time", "end_time", "value", "reason"]
        return pd.DataFrame([[getattr(f, name) for name in columns] for f in self.findings], columns=columns)

    def summary(self):
        """A short text: counts per signal and kind, then one line per finding.

        Examples
        --------
        >>> import numpy as np
        >>> from dynia.quality import check_quality
        >>> print(check_quality(None, np.ones(30), np.linspace(0, 1, 30)).summary())
        Data quality of 30 samples: no absurd magnitude, glitch, outlier, saturated, stuck or quantised value.
        """
        if not self.findings:
            return (
                f"Data quality of {self.time.size} samples: no absurd magnitude, glitch, outlier, saturated, "
                "stuck or quantised value."
            )
        count = len(self.findings)
        lines = [f"Data quality of {self.time.size} samples: {count} finding{'' if count == 1 else 's'}."]
        for signal in SIGNALS:
            counts = [f"{sum(f.signal == signal and f.kind == kind for f in self.findings)} {kind}" for kind in KINDS]
            flagged = int(self.mask(signal).sum())
            lines.append(
                f"  {signal}: " + ", ".join(counts) + f"; {flagged} flagged sample{'' if flagged == 1 else 's'}"
            )
        for f in self.findings:
            when = f"t={f.start_time:g}" if f.stop - f.start == 1 else f"t={f.start_time:g}..{f.end_time:g}"
            lines.append(f"  {f.signal} {f.kind:<9} {when} (samples {f.start}-{f.stop - 1}): {f.reason}")
        return "\n".join(lines)


def check_quality(
    time,
    u,
    y,
    *,
    half_window=3,
    glitch_threshold=6.0,
    glitch_min_size=0.1,
    max_glitch_length=2,
    outlier_quantile=0.01,
    outlier_fence=1.0,
    min_stuck=10,
    min_saturated=10,
    stuck_factor=4.0,
    stuck_tolerance=0.0,
    max_magnitude=1e12,
    quantised_min_changes=20,
    quantised_min_levels=4,
):
    """Find absurd magnitudes, glitches, outliers, saturated, stuck and quantised values in an input/output record.

    The tests and the reasoning behind every default are in the module
    documentation.

    Parameters
    ----------
    time : array_like, shape (n_steps,), or None
        Time of each sample, strictly increasing (default: seconds from a
        time index of pandas ``u`` and ``y``, else 0, 1, ...).
    u, y : array_like, shape (n_steps,), or pandas Series
        Input and output. NaN marks a missing sample. Two pandas objects
        must share one index (:func:`dynia.io.frames.unpack`).
    half_window : int, default 3
        Half width of the Hampel window, at least ``max_glitch_length``.
    glitch_threshold : float, default 6.0
        Robust standard deviations a glitch departs from its local median
        and from both neighbours.
    glitch_min_size : float >= 0, default 0.1
        Smallest departure of a glitch, in widths of the signal's bulk.
    max_glitch_length : int, default 2
        Longest run of samples that counts as a glitch (0: no glitch test).
    outlier_quantile : float in (0, 0.5), default 0.01
        The bulk of a signal lies between this quantile and its complement.
    outlier_fence : float > 0, default 1.0
        Bulk widths beyond the bulk from which a value is an outlier.
    min_stuck : int, default 10
        Shortest run of equal readings that can be stuck.
    min_saturated : int, default 10
        Shortest run of readings at the record's maximum or minimum that can
        be saturated.
    stuck_factor : float > 0, default 4.0
        A stuck or saturated run is at least this many times the signal's
        usual run length.
    stuck_tolerance : float >= 0, default 0.0
        Consecutive readings differing by at most this are equal.
    max_magnitude : float > 0, default 1e12
        Values larger in size are magnitude findings, as are those above
        1e150 whatever it says (``math.inf``: only those).
    quantised_min_changes : int, default 20
        Fewest changes between consecutive output readings that can show
        a grid.
    quantised_min_levels : int, default 4
        Fewest grid steps the output must span to be called quantised.

    Returns
    -------
    QualityReport

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.quality import check_quality
    >>> y = 72 + np.random.default_rng(1).normal(0, 0.5, 200)
    >>> y[80:120] = y[80]                                  # a frozen tag
    >>> [(f.kind, f.start, f.stop) for f in check_quality(None, np.full(200, 36.0), y).findings]
    [('stuck', 80, 120)]

    A sentinel is a magnitude finding, and the other tests do not see it:

    >>> y[150] = 1e308
    >>> report = check_quality(None, np.full(200, 36.0), y)
    >>> [(f.kind, f.start, f.stop) for f in report.findings], report.findings[0].value
    ([('magnitude', 150, 151), ('stuck', 80, 120)], 1e+308)
    """
    u, y, spacing, _ = unpack(u, y)
    u = _checks.as_1d_float(u, "u", allow_nan=True)
    y = _checks.as_1d_float(y, "y", allow_nan=True)
    if u.size != y.size:
        raise DataError(f"u has {u.size} samples but y has {y.size}; they must be logged on the same steps")
    if time is None and spacing is not None:
        time = np.arange(y.size) * spacing  # seconds from the first row, from the time index
    time = _time_axis(time, y.size)
    max_glitch_length = _checks.whole_number(max_glitch_length, "max_glitch_length", minimum=0)
    half_window = _checks.whole_number(half_window, "half_window", minimum=1)
    if half_window < max_glitch_length:
        raise SettingsError(
            f"half_window ({half_window}) must be at least max_glitch_length ({max_glitch_length}), "
            "or a glitch as long as allowed could move the window's median",
            "half_window",
        )
    settings = dict(
        half_window=half_window,
        glitch_threshold=_checks.open_interval(glitch_threshold, "glitch_threshold", 0, math.inf),
        glitch_min_size=_nonnegative(glitch_min_size, "glitch_min_size"),
        max_glitch_length=max_glitch_length,
        outlier_quantile=_checks.open_interval(outlier_quantile, "outlier_quantile", 0, 0.5),
        outlier_fence=_checks.open_interval(outlier_fence, "outlier_fence", 0, math.inf),
        min_stuck=_checks.whole_number(min_stuck, "min_stuck", minimum=2),
        min_saturated=_checks.whole_number(min_saturated, "min_saturated", minimum=2),
        stuck_factor=_checks.open_interval(stuck_factor, "stuck_factor", 0, math.inf),
        stuck_tolerance=_nonnegative(stuck_tolerance, "stuck_tolerance"),
        max_magnitude=_magnitude_limit(max_magnitude),
        quantised_min_changes=_checks.whole_number(quantised_min_changes, "quantised_min_changes", minimum=2),
        quantised_min_levels=_checks.whole_number(quantised_min_levels, "quantised_min_levels", minimum=2),
    )
    findings = []
    for signal, values in (("u", u), ("y", y)):
        runs = fault_runs(values, settings, output=signal == "y", screened_steps=QUANTISED_MIN_STEPS)
        findings += [_finding(signal, time, *run) for run in runs]
    return QualityReport(
        findings=tuple(findings), time=time, missing={"u": np.isnan(u), "y": np.isnan(y)}, settings=settings
    )


def screen(u, y, window_halos, *, time=None, min_steps=QUANTISED_MIN_STEPS, **options):
    """What :func:`dynia.run` screens: a record's saturated, stuck and quantised stretches, as its run records them.

    Parameters
    ----------
    u : array_like, shape (n_steps,) or (n_steps, n_inputs)
        The input; only a single input is checked (several: the output only).
    y : array_like, shape (n_steps,)
        The output, NaN where missing.
    window_halos : (int, int)
        Steps (before, after) the window at a step reaches:
        :attr:`dynia.result.DyniaResult.window_halos`.
    time : array_like, shape (n_steps,), optional
        As :func:`check_quality`.
    min_steps : int, default :data:`QUANTISED_MIN_STEPS` (3)
        A window of a quantised output is screened when its output spans
        fewer than this many grid steps.
    **options
        Tuning of :func:`check_quality`.

    Returns
    -------
    tuple of (kind, signal, start, stop, value)
        ``result.run.screened``. For "saturated" and "stuck" the samples
        ``[start, stop)`` of the run and the value read (in the units of the
        ``u`` and ``y`` given); for "quantised" the steps ``[start, stop)`` of
        a run of windows whose output moves by fewer than ``min_steps`` grid
        steps, and the step. Empty when nothing is screened.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> y = np.sin(np.arange(300) / 20.0) + rng.normal(0, 0.05, 300)
    >>> y[100:140] = y.max() + 0.2                    # the sensor at the top of its range
    >>> screen(np.zeros(300), y, (5, 5))[0][:4]
    ('saturated', 'y', 100, 140)
    """
    y = _checks.as_1d_float(y, "y", allow_nan=True)
    u = np.asarray(u, dtype=float)
    min_steps = _checks.whole_number(min_steps, "min_steps", minimum=1)
    report = check_quality(time, u if u.ndim == 1 else np.zeros(y.size), y, **options)
    screened = []
    for finding in report.findings:
        if finding.kind in ("saturated", "stuck"):
            screened.append((finding.kind, finding.signal, finding.start, finding.stop, finding.value))
        elif finding.kind == "quantised":
            flat = _flat_windows(y, finding.value, window_halos, min_steps)
            screened += [(finding.kind, finding.signal, a, b, finding.value) for a, b in mask_to_segments(flat)]
    return tuple(screened)


def screening(u, y, settings):
    """``result.run.screened`` of a front-end's run: :func:`screen` with the window of ``settings``, or None.

    None when ``settings.quality`` is False (not screened); the window's
    reach follows ``settings.n`` and ``settings.window``.
    """
    if not settings.quality:
        return None
    n = settings.n
    return screen(u, y, (n, n) if settings.window == "centred" else (2 * n, 0))


def screened_windows(screened, windows_using, n_steps):
    """The windows that the entries of :func:`screen` take from the evidence, (n_steps,) bool.

    ``windows_using(samples)`` maps a sample mask to the windows using one
    (:meth:`dynia.result.DyniaResult.windows_using`): every window that uses
    a saturated or stuck reading, and the quantised entries' windows.
    """
    windows = np.zeros(n_steps, dtype=bool)
    samples = np.zeros(n_steps, dtype=bool)
    for kind, _, start, stop, _ in screened or ():
        (windows if kind == "quantised" else samples)[start:stop] = True
    return windows | windows_using(samples) if samples.any() else windows


def _flat_windows(y, step, window_halos, min_steps):
    """The windows whose present output spans fewer than ``min_steps`` grid steps of size ``step``, (n_steps,) bool."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    before, after = window_halos
    length = before + after + 1
    present = ~np.isnan(y)

    def padded(values, fill):
        return np.concatenate((np.full(before, fill), np.where(present, values, fill), np.full(after, fill)))

    # origin -(length // 2) makes entry t the extreme of padded[t : t + length], the window of step t.
    top = maximum_filter1d(padded(y, -np.inf), length, origin=-(length // 2))[: y.size]
    bottom = minimum_filter1d(padded(y, np.inf), length, origin=-(length // 2))[: y.size]
    with np.errstate(invalid="ignore"):  # a window without a measured point spans inf - inf: NaN, never flat
        # Spans are whole steps up to rounding: half a step apart is a safe threshold.
        return (top - bottom) < (min_steps - 0.5) * step


def _finding(signal, time, where, kind, start, stop, value, reason):
    """A Finding from a run [start, stop) of the samples ``where`` a test ran on."""
    first, last = where[start], where[stop - 1]
    return Finding(
        signal=signal,
        kind=kind,
        start=int(first),
        stop=int(last) + 1,
        start_time=float(time[first]),
        end_time=float(time[last]),
        value=float(value),
        reason=reason,
    )


def _time_axis(time, n_steps):
    if time is None:
        return np.arange(n_steps, dtype=float)
    time = _checks.as_1d_float(time, "time")
    if time.size != n_steps:
        raise DataError(f"time has {time.size} values but u and y have {n_steps}; they must match")
    steps = np.diff(time)
    if (steps <= 0).any():
        at = int(np.argmax(steps <= 0)) + 1
        raise DataError(f"time must increase strictly; time[{at}] = {time[at]} follows {time[at - 1]}")
    return time


def _magnitude_limit(value):
    """``max_magnitude`` as a float > 0; inf leaves only the overflow limit."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not value > 0:
        raise SettingsError(
            f"max_magnitude must be a number > 0 (math.inf: flag only values above {SQUARABLE:g}); got {value!r}",
            "max_magnitude",
        )
    return float(value)


def _nonnegative(value, name):
    return 0.0 if value == 0 else _checks.open_interval(value, name, 0, math.inf)


def _signal_name(signal):
    if signal not in SIGNALS:
        raise SettingsError(f"signal must be one of {SIGNALS}; got {signal!r}", "signal")
    return signal


def _kind_names(kinds):
    if kinds is None:
        return tuple(kind for kind in KINDS if kind != "quantised")
    if isinstance(kinds, str):
        raise SettingsError(f"kinds must be a sequence of kinds, e.g. ['glitch']; got the string {kinds!r}", "kinds")
    unknown = [kind for kind in kinds if kind not in KINDS]
    if unknown:
        raise SettingsError(f"unknown kinds {unknown}; choose from {KINDS}", "kinds")
    return tuple(kinds)


def _segment_pairs(segments, n_steps):
    """Check ``segments`` as [start, stop) index pairs inside the record."""
    try:
        pairs = [tuple(pair) for pair in segments]
    except TypeError:
        raise SettingsError(
            f"segments must be a sequence of (start, stop) pairs; got {segments!r}", "segments"
        ) from None
    checked = []
    for position, pair in enumerate(pairs):
        if len(pair) != 2:
            raise SettingsError(f"segments[{position}] must be a (start, stop) pair; got {pair!r}", "segments")
        start = _checks.whole_number(pair[0], f"segments[{position}] start", minimum=0)
        stop = _checks.whole_number(pair[1], f"segments[{position}] stop", minimum=0)
        if not start < stop <= n_steps:
            raise SettingsError(
                f"segments[{position}] = {pair!r} must satisfy 0 <= start < stop <= {n_steps} (n_steps)", "segments"
            )
        checked.append((start, stop))
    return checked
