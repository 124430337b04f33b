"""A baseline beside DYNIA: the identification-interval search of Bittencourt et al. (2015).

Bittencourt, Isaksson, Peretzki and Forsman, "An algorithm for finding
process identification intervals from normal operating data", *Processes*
3(2), 357-383, 2015 (extending Peretzki et al., "Data mining of historic
data for process identification", AIChE Annual Meeting 2011), scan logged
loop data for stretches informative enough to identify a SISO process
model from. :func:`find_intervals` implements their scheme:

1. **Excitation.** An exponentially weighted moving average (EWMA) of each
   signal and an EWMA of its squared innovation flag the samples where the
   input (the setpoint when the loop is closed, the manipulated variable
   when it is in manual) or the output moves more than its noise. A
   candidate interval is a run of excited samples of either signal, so it
   ends once the output has settled; it must hold input excitation.
2. **Laguerre model.** On each candidate the output is regressed on
   ``laguerre_order`` Laguerre-filtered versions of the input (pole
   ``laguerre_pole``), which describe a monotone response with dead time
   without estimating the delay.
3. **Condition number.** The candidate is informative only if the
   information matrix of the regressors, built from the excitation signal,
   is well conditioned (at most ``max_condition``).
4. **Causality.** A chi-square test of the hypothesis that every Laguerre
   coefficient is zero: the output must depend on the input, at
   significance ``significance``.

Shapes follow the package convention (see :mod:`dynia.engine`): ``u``,
``y`` and ``setpoint`` are (n_steps,), one value per sample time ``k*dt``.
Intervals are index pairs ``[start, stop)``, sorted, non-overlapping and
inside the record, so ``y[start:stop]`` is the data of one interval.

Missing values
--------------
NaN in ``u``, ``y`` or ``setpoint`` breaks the record: the search runs on
each stretch of finite samples separately (the filters restart) and no
interval contains a NaN. ``inf`` is rejected with a ``ValueError``.

What comes from the paper, and what is ours
-------------------------------------------
The stored copy of the paper we could read holds its abstract, problem
statement and assumptions: the four steps above, the use of the setpoint in
closed loop and of the input in manual mode, Laguerre models for dead time,
SISO linear processes with monotone step responses, and a numeric quality
for every interval. Its later sections (the filter equations and the
values of its thresholds) were not reachable, so the following are our
choices, made to stay close to the scheme and to standard least squares
(Ljung, *System Identification*, 1999). An open-source implementation
citing the paper (HDSIdent, Santo 2020) likewise takes the condition number
and the chi-square statistic from a QR factorisation of [Phi y], and in
closed loop the first from the setpoint and the second from the input:

- *Excitation statistic.* ``m(k) = lam m(k-1) + (1-lam) x(k)``, innovation
  ``e(k) = x(k) - m(k-1)``, ``v(k) = lam_v v(k-1) + (1-lam_v) e(k)**2``.
  For white noise of standard deviation ``s`` at rest, ``v`` averages
  ``2 s**2 / (1 + lam)``; a sample is excited when ``v`` exceeds
  ``excitation_threshold`` times that. The filters start at rest, the mean
  at the median of the first 1/(1-lam) samples of each finite stretch.
- *Noise level.* ``s`` is estimated from the first differences, robustly
  (1.4826 x median absolute deviation / sqrt 2), so the few steps of a
  record do not inflate it. It is floored at 1 % of the signal's range
  between its 1 % and 99 % quantiles (so that a glitch does not raise it),
  so a noise-free setpoint or input is excited at each change larger than
  about 2 % of that range and settles again within about 4/(1-lam) samples.
  ``noise_std`` overrides the estimate.
- *Interval bounds.* Excited runs (input or output) at most
  ``max(merge_gap, margin)`` samples apart are joined; each joined run
  begins ``margin`` samples early, so the interval holds the level before
  the first change and never overlaps the previous one.
  Runs without input excitation are kept as candidates and rejected ("no
  input excitation"): the output moved by itself, a disturbance.
- *Regression.* Deviation variables from the interval's first sample for
  the input (the Laguerre filters start at rest there) and an intercept for
  the output's operating point. The information matrix is that of the
  centred regressors, ``Phi_c' Phi_c / N``; with a setpoint it is built from
  the setpoint and the chi-square test from the manipulated variable.
- *Chi-square statistic.* In terms of the QR factorisation
  ``[Phi_c y_c] = Q [[R1, R2], [0, R3]]`` (computed by least squares):
  ``theta = R1^-1 R2`` and ``zeta = (N - n - 1) |R2|**2 / R3**2``, which is
  ``theta' (Phi_c' Phi_c) theta / sigma**2`` with the unbiased residual
  variance. Under "no causal relation" with white output noise ``zeta`` is
  asymptotically chi-square with n degrees of freedom; the interval passes
  if ``zeta`` exceeds the ``1 - significance`` quantile.

Limitations
-----------
- The EWMA memory sets how long an interval runs on: a process much slower
  than 1/(1-lam) samples gets intervals that end before it settles (and a
  biased ``static_gain``).
- In closed loop without ``setpoint`` a disturbance moves input and output
  together, and its interval can pass both tests; pass the setpoint.
- The chi-square test assumes white output noise; strongly coloured noise
  makes it pass inputs with no effect more often than ``significance``.
- The noise estimate assumes mostly flat data; a record that moves all the
  time (a long PRBS, say) gets an inflated noise level and fewer intervals.

Tuning parameters
-----------------
Sample counts are in samples, not time units. "Paper" says what the
readable part of the paper fixes; "-" means it was not in that part.

+--------------------------+---------+------------------------+-----------------+----------------------------+
| parameter                | default | meaning                | paper           | how to choose              |
+==========================+=========+========================+=================+============================+
| ``setpoint``             | None    | the loop's setpoint:   | closed loop:    | pass it for loops in       |
|                          |         | when given, the input  | setpoint        | automatic mode             |
|                          |         | excitation and the     | changes;        |                            |
|                          |         | condition number use   | manual: input   |                            |
|                          |         | it                     | variations      |                            |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``mean_forgetting``      | 0.95    | lam of the EWMA mean;  | EWMA filter     | 1/(1-lam) about the        |
|                          |         | memory about 1/(1-lam) | (value -)       | output's settling time in  |
|                          |         | samples                |                 | samples; smaller ends      |
|                          |         |                        |                 | intervals before slow      |
|                          |         |                        |                 | responses settle           |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``variance_forgetting``  | 0.9     | lam_v of the EWMA of   | EWMA filter     | below lam, so it reacts    |
|                          |         | the squared innovation | (value -)       | within 1/(1-lam_v)         |
|                          |         |                        |                 | samples; nearer 1 gives    |
|                          |         |                        |                 | fewer false alarms         |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``excitation_threshold`` | 4.0     | excited where the      | threshold from  | > 1; raise it if flat      |
|                          |         | variance EWMA exceeds  | the noise level | noisy stretches make many  |
|                          |         | this multiple of its   | (value -)       | short candidates           |
|                          |         | rest value             |                 |                            |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``noise_std``            | None    | (input, output) noise  | -               | give it for noise-free or  |
|                          |         | standard deviations    |                 | strongly coloured signals  |
|                          |         | instead of the         |                 |                            |
|                          |         | estimate               |                 |                            |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``merge_gap``            | 20      | excited runs at most   | -               | at least the longest dead  |
|                          |         | this many samples      |                 | time less the input's      |
|                          |         | apart are one interval |                 | excitation time, so a      |
|                          |         |                        |                 | change and its delayed     |
|                          |         |                        |                 | response stay together     |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``margin``               | 10      | samples kept before    | -               | a few samples of the level |
|                          |         | the first excited      |                 | before the change; more if |
|                          |         | sample                 |                 | the input starts slowly    |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``min_length``           | 20      | shorter candidates are | -               | several times              |
|                          |         | rejected               |                 | ``laguerre_order``: the    |
|                          |         |                        |                 | fit needs more samples     |
|                          |         |                        |                 | than parameters            |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``laguerre_order``       | 3       | number n of Laguerre   | Laguerre model  | 2-4 for monotone           |
|                          |         | regressors (chi-square | (order -)       | responses; a single step   |
|                          |         | degrees of freedom)    |                 | excites few, so higher     |
|                          |         |                        |                 | orders raise the condition |
|                          |         |                        |                 | number                     |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``laguerre_pole``        | 0.9     | pole a of the Laguerre | Laguerre model  | exp(-dt/T), T a rough      |
|                          |         | filters                | (pole -)        | dominant time constant     |
|                          |         |                        |                 | (plus dead time)           |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``max_condition``        | 1000    | largest accepted       | condition-      | single steps give 10-100   |
|                          |         | condition number of    | number test     | at the defaults, slow      |
|                          |         | the information matrix | (value -)       | ramps and drifts 1e3-1e5   |
+--------------------------+---------+------------------------+-----------------+----------------------------+
| ``significance``         | 0.01    | level of the chi-      | chi-square test | the rate at which an input |
|                          |         | square test            | of a causal     | with no effect on the      |
|                          |         |                        | relation (level | output still passes        |
|                          |         |                        | -)              |                            |
+--------------------------+---------+------------------------+-----------------+----------------------------+

Examples
--------
>>> import numpy as np
>>> from dynia.baseline import find_intervals
>>> rng = np.random.default_rng(0)
>>> u = np.r_[np.zeros(200), np.ones(200), np.zeros(200)]
>>> y = np.zeros(u.size)
>>> for k in range(u.size - 1):                   # gain 2, time constant 10 samples
...     y[k + 1] = 0.9 * y[k] + 0.2 * u[k]
>>> result = find_intervals(u, y + rng.normal(0, 0.1, u.size))
>>> result.accepted
array([[190, 297],
       [390, 497]])
>>> [c.reason for c in result.candidates]
['accepted', 'accepted']
>>> round(result.candidates[0].static_gain, 1)
2.0
"""

import math
import numbers
from dataclasses import dataclass, field

import numpy as np
import scipy.signal
import scipy.stats

from . import _checks
from .errors import DataError, SettingsError
from .io.frames import unpack
from .segments import mask_to_segments
from .settings import MAD_TO_STD, check_dt

__all__ = ["find_intervals", "BaselineResult", "CandidateInterval", "REASONS"]

# Why a candidate interval was kept or dropped, in the order the checks run.
REASONS = ("accepted", "no input excitation", "too short", "ill-conditioned", "no causal relation")


# Noise floor as a fraction of a signal's range: without it a noise-free signal
# would count as excited until its EWMA mean had converged to machine precision.
_NOISE_FLOOR = 1e-2


@dataclass(frozen=True)
class CandidateInterval:
    """One stretch of excitation and what the tests said about it.

    Attributes
    ----------
    start, stop : int
        The samples ``start .. stop-1``.
    input_excited : bool
        Whether the input (or setpoint) was excited anywhere in it.
    condition_number : float
        Of the information matrix of the Laguerre regressors of the
        excitation signal; inf when they are linearly dependent, NaN when
        the candidate is too short to compute it.
    chi2_statistic, chi2_threshold : float
        The test statistic of "no causal relation" and the quantile it must
        exceed.
    static_gain : float
        Steady-state gain of the fitted Laguerre model (output units per
        input unit); a rough estimate, meaningful for accepted intervals.
    reason : str
        "accepted" or the first failed check (one of :data:`REASONS`).
    """

    start: int
    stop: int
    input_excited: bool
    condition_number: float
    chi2_statistic: float
    chi2_threshold: float
    static_gain: float
    reason: str

    @property
    def accepted(self):
        """Whether every check passed."""
        return self.reason == "accepted"


@dataclass(frozen=True, eq=False)
class BaselineResult:
    """The intervals found by :func:`find_intervals`, and the evidence.

    Attributes
    ----------
    accepted : ndarray (n_accepted, 2) of int
        ``[start, stop)`` of every accepted interval, sorted and
        non-overlapping: ``y[start:stop]`` is an interval's data.
    candidates : tuple of CandidateInterval
        Every candidate, accepted or not, in time order.
    input_excited, output_excited : ndarray (n_steps,) of bool
        Where the input (or setpoint) and the output were excited.
    dt : float
        Sample time.
    settings : dict
        Every tuning parameter used, with the noise levels.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.baseline import find_intervals
    >>> u = np.r_[np.zeros(50), np.ones(150)]
    >>> y = np.zeros(200)
    >>> for k in range(199):                      # gain 1, time constant 4.5 samples
    ...     y[k + 1] = 0.8 * y[k] + 0.2 * u[k]
    >>> result = find_intervals(u, y + np.random.default_rng(1).normal(0, 0.05, 200), dt=0.5)
    >>> result.accepted, result.intervals()
    (array([[ 40, 147]]), array([[20., 73.]]))
    >>> result.to_dataframe()[["start_time", "end_time", "reason"]]
       start_time  end_time    reason
    0        20.0      73.0  accepted
    """

    accepted: np.ndarray
    candidates: tuple
    input_excited: np.ndarray
    output_excited: np.ndarray
    dt: float
    settings: dict = field(default_factory=dict)

    def intervals(self, time=None):
        """Accepted intervals as [start_time, end_time], end_time the time of the last sample.

        Parameters
        ----------
        time : array_like, shape (n_steps,), optional
            Time of each sample (default ``k*dt``).

        Returns
        -------
        ndarray (n_accepted, 2)
        """
        time = self._time(time)
        return np.column_stack([time[self.accepted[:, 0]], time[self.accepted[:, 1] - 1]])

    def to_dataframe(self, time=None):
        """One row per candidate: bounds, times, test values, accepted and why.

        Needs pandas (``pip install dynia[pandas]``). ``time`` as in
        :meth:`intervals`.
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_dataframe needs pandas: pip install 'dynia[pandas]'") from None
        time = self._time(time)
        rows = [
            dict(
                start=c.start,
                stop=c.stop,
                start_time=time[c.start],
                end_time=time[c.stop - 1],
                length=c.stop - c.start,
                input_excited=c.input_excited,
                condition_number=c.condition_number,
                chi2_statistic=c.chi2_statistic,
                chi2_threshold=c.chi2_threshold,
                static_gain=c.static_gain,
                accepted=c.accepted,
                reason=c.reason,
            )
            for c in self.candidates
        ]
        return pd.DataFrame(
            rows,
            columns=[
                "start",
                "stop",
                "start_time",
                "end_time",
                "length",
                "input_excited",
                "condition_number",
                "chi2_statistic",
                "chi2_threshold",
                "static_gain",
                "accepted",
                "reason",
            ],
        )

    def _time(self, time):
        n_steps = self.input_excited.size
        if time is None:
            return np.arange(n_steps) * self.dt
        time = _checks.as_1d_float(time, "time")
        if time.size != n_steps:
            raise SettingsError(f"time has {time.size} values but the record has {n_steps} samples")
        return time


def find_intervals(
    u,
    y,
    *,
    dt=None,
    setpoint=None,
    mean_forgetting=0.95,
    variance_forgetting=0.9,
    excitation_threshold=4.0,
    noise_std=None,
    merge_gap=20,
    margin=10,
    min_length=20,
    laguerre_order=3,
    laguerre_pole=0.9,
    max_condition=1000.0,
    significance=0.01,
):
    """Find the intervals of a record that are informative enough for identification.

    The scheme of Bittencourt et al. (2015): EWMA excitation detection on
    the input (or setpoint) and the output, a Laguerre regression on each
    candidate, a condition-number test of its information matrix and a
    chi-square test of a causal input-output relation. The module
    documentation has every step, the choices made where the paper's text
    was not available, and a table of the tuning parameters.

    Parameters
    ----------
    u : array_like, shape (n_steps,), or pandas Series
        Input (manipulated variable). NaN breaks the record.
    y : array_like, shape (n_steps,), or pandas Series
        Measured output. NaN breaks the record. Two pandas objects must
        share one index, and a time index gives ``dt``
        (:func:`dynia.io.frames.unpack`); intervals count steps by position.
    dt : float, optional
        Sample time, only used to give intervals in time units; default the
        spacing of a time index, else 1.0.
    setpoint : array_like, shape (n_steps,), or pandas Series, optional
        Setpoint of a closed loop: then it is the excitation signal (for
        the excitation detection and the condition number) and ``u`` enters
        the chi-square test only.
    mean_forgetting, variance_forgetting : float, default 0.95, 0.9
        Forgetting factors in (0, 1) of the EWMA mean and of the EWMA of
        the squared innovation.
    excitation_threshold : float, default 4.0
        A sample is excited where the variance EWMA exceeds this multiple
        (> 1) of its value at rest.
    noise_std : (float, float), optional
        Noise standard deviations of the excitation signal and of the
        output; estimated from the data when omitted.
    merge_gap : int, default 20
        Excited runs separated by at most this many samples are joined.
    margin : int, default 10
        Samples kept before the first excited sample of an interval.
    min_length : int, default 20
        Candidates shorter than this are rejected; at least
        ``laguerre_order + 2``.
    laguerre_order : int, default 3
        Number of Laguerre regressors.
    laguerre_pole : float, default 0.9
        Pole of the Laguerre filters, in [0, 1).
    max_condition : float, default 1000
        Largest accepted condition number (> 1).
    significance : float, default 0.01
        Level of the chi-square test, in (0, 1).

    Returns
    -------
    BaselineResult
        ``.accepted`` holds the accepted ``[start, stop)`` pairs,
        ``.candidates`` the diagnostics of every candidate.

    Examples
    --------
    An input step with no effect on the output is found and rejected:

    >>> import numpy as np
    >>> from dynia.baseline import find_intervals
    >>> u = np.r_[np.zeros(100), np.ones(100)]
    >>> y = np.random.default_rng(3).normal(0, 1, 200)
    >>> result = find_intervals(u, y)
    >>> result.accepted.shape, result.candidates[0].reason
    ((0, 2), 'no causal relation')
    """
    if setpoint is not None:
        setpoint = unpack(setpoint, y)[0]  # a pandas setpoint on the output's index
    u, y, dt, _ = unpack(u, y, dt)
    u, y, setpoint = _checked_record(u, y, setpoint)
    dt = check_dt(1.0 if dt is None else dt)
    mean_forgetting = _checks.open_interval(mean_forgetting, "mean_forgetting", 0, 1)
    variance_forgetting = _checks.open_interval(variance_forgetting, "variance_forgetting", 0, 1)
    excitation_threshold = _positive(excitation_threshold, "excitation_threshold", above=1.0)
    merge_gap = _checks.whole_number(merge_gap, "merge_gap", minimum=0)
    margin = _checks.whole_number(margin, "margin", minimum=0)
    laguerre_order = _checks.whole_number(laguerre_order, "laguerre_order", minimum=1)
    min_length = _checks.whole_number(min_length, "min_length", minimum=laguerre_order + 2)
    laguerre_pole = _pole(laguerre_pole)
    max_condition = _positive(max_condition, "max_condition", above=1.0)
    significance = _checks.open_interval(significance, "significance", 0, 1)

    excitation = u if setpoint is None else setpoint
    if noise_std is None:
        noise_std = (_noise_std(excitation), _noise_std(y))
    else:
        noise_std = _noise_pair(noise_std)

    finite = np.isfinite(u) & np.isfinite(y)
    if setpoint is not None:
        finite &= np.isfinite(setpoint)
    forgetting = (mean_forgetting, variance_forgetting, excitation_threshold)
    input_excited, output_excited, bounds = _excited_stretches(
        excitation, y, finite, noise_std, forgetting, max(merge_gap, margin), margin
    )
    chi2_threshold = float(scipy.stats.chi2.ppf(1 - significance, laguerre_order))
    candidates = [
        _tested_candidate(
            u,
            y,
            setpoint,
            start,
            stop,
            bool(input_excited[start:stop].any()),
            (laguerre_order, laguerre_pole),
            min_length,
            max_condition,
            chi2_threshold,
        )
        for start, stop in bounds
    ]
    accepted = np.array([(c.start, c.stop) for c in candidates if c.accepted], dtype=np.int64).reshape(-1, 2)
    settings = dict(
        dt=dt,
        closed_loop=setpoint is not None,
        mean_forgetting=mean_forgetting,
        variance_forgetting=variance_forgetting,
        excitation_threshold=excitation_threshold,
        noise_std=noise_std,
        merge_gap=merge_gap,
        margin=margin,
        min_length=min_length,
        laguerre_order=laguerre_order,
        laguerre_pole=laguerre_pole,
        max_condition=max_condition,
        significance=significance,
    )
    return BaselineResult(accepted, tuple(candidates), input_excited, output_excited, dt, settings)


def _checked_record(u, y, setpoint):
    """``u``, ``y`` and ``setpoint`` (or None) as float arrays of one length; NaN allowed (it breaks the record)."""
    u = _checks.as_1d_float(u, "u", allow_nan=True)
    y = _checks.as_1d_float(y, "y", allow_nan=True)
    if u.size != y.size:
        raise DataError(f"u has {u.size} samples but y has {y.size}; they must be logged on the same steps")
    if setpoint is not None:
        setpoint = _checks.as_1d_float(setpoint, "setpoint", allow_nan=True)
        if setpoint.size != u.size:
            raise SettingsError(f"setpoint has {setpoint.size} samples but u has {u.size}; they must match")
    return u, y, setpoint


def _excited_stretches(excitation, y, finite, noise_std, forgetting, gap, margin):
    """Where the excitation signal and the output are excited, and the candidate intervals that gives.

    Each stretch of ``finite`` steps is detected on its own (NaN breaks the
    record). ``forgetting`` is (mean_forgetting, variance_forgetting,
    excitation_threshold). Returns the two (n_steps,) masks and the
    candidates' ``(start, stop)`` bounds.
    """
    input_excited = np.zeros(y.size, dtype=bool)
    output_excited = np.zeros(y.size, dtype=bool)
    bounds = []
    for first, end in mask_to_segments(finite):
        stretch = slice(first, end)
        input_excited[stretch] = _excited(excitation[stretch], noise_std[0], *forgetting)
        output_excited[stretch] = _excited(y[stretch], noise_std[1], *forgetting)
        bounds += _candidate_bounds(input_excited[stretch] | output_excited[stretch], first, gap, margin)
    return input_excited, output_excited, bounds


def _tested_candidate(u, y, setpoint, start, stop, has_input, laguerre, min_length, max_condition, chi2_threshold):
    """The candidate [start, stop) with its Laguerre tests and the first check it fails (or "accepted").

    ``laguerre`` is (order, pole); the checks run in the order of :data:`REASONS`.
    """
    condition_number, chi2_statistic, static_gain = _laguerre_tests(
        u[start:stop], y[start:stop], *laguerre, None if setpoint is None else setpoint[start:stop]
    )
    if not has_input:
        reason = "no input excitation"
    elif stop - start < min_length:
        reason = "too short"
    elif not condition_number <= max_condition:
        reason = "ill-conditioned"
    elif not chi2_statistic > chi2_threshold:
        reason = "no causal relation"
    else:
        reason = "accepted"
    return CandidateInterval(
        start, stop, has_input, condition_number, chi2_statistic, chi2_threshold, static_gain, reason
    )


def _excited(x, noise_std, forgetting, variance_forgetting, threshold):
    """Samples where the EWMA of the squared innovation exceeds ``threshold`` times its rest value."""
    rest = 2 * noise_std**2 / (1 + forgetting)
    # Starting the mean at x[0] alone would bias the first innovations by that sample's noise.
    start = float(np.median(x[: math.ceil(1 / (1 - forgetting))]))
    mean = scipy.signal.lfilter([1 - forgetting], [1, -forgetting], x, zi=[forgetting * start])[0]
    innovation = x - np.r_[start, mean[:-1]]
    variance = scipy.signal.lfilter(
        [1 - variance_forgetting], [1, -variance_forgetting], innovation**2, zi=[variance_forgetting * rest]
    )[0]
    return variance > threshold * rest


def _candidate_bounds(excited, offset, join_gap, margin):
    """[start, stop) of the excited runs: runs at most ``join_gap`` apart joined, each begun ``margin`` early.

    ``join_gap >= margin``, so moving a start back never reaches the previous stop.
    """
    bounds = []
    for start, stop in mask_to_segments(excited):
        if bounds and start - bounds[-1][1] <= join_gap:
            bounds[-1][1] = stop
        else:
            bounds.append([start, stop])
    return [(offset + max(0, start - margin), offset + stop) for start, stop in bounds]


def _laguerre_regressors(x, order, pole):
    """(len(x), order) outputs of the Laguerre filters, started at rest, for the deviation of x from x[0]."""
    deviation = x - x[0]
    columns = [scipy.signal.lfilter([0, math.sqrt(1 - pole * pole)], [1, -pole], deviation)]
    for _ in range(order - 1):
        columns.append(scipy.signal.lfilter([-pole, 1], [1, -pole], columns[-1]))
    return np.column_stack(columns)


def _laguerre_tests(u, y, order, pole, setpoint=None):
    """Condition number (from ``setpoint`` if given, else ``u``), chi-square statistic and static gain.

    NaN throughout when the interval has too few samples for an intercept
    and ``order`` coefficients with a residual left.
    """
    n_samples = y.size
    if n_samples < order + 2:
        return math.nan, math.nan, math.nan
    regressors = _laguerre_regressors(u, order, pole)
    centred = regressors - regressors.mean(axis=0)
    if setpoint is None:
        singular = np.linalg.svd(centred, compute_uv=False)
    else:
        excitation = _laguerre_regressors(setpoint, order, pole)
        singular = np.linalg.svd(excitation - excitation.mean(axis=0), compute_uv=False)
    condition_number = float(singular[0] / singular[-1]) ** 2 if singular[-1] > 0 else math.inf

    output = y - y.mean()
    theta = np.linalg.lstsq(centred, output, rcond=None)[0]
    fitted = centred @ theta
    explained = float(fitted @ fitted)
    residual = float((output - fitted) @ (output - fitted))
    if residual > 0:
        chi2_statistic = (n_samples - order - 1) * explained / residual
    else:
        chi2_statistic = math.inf if explained > 0 else 0.0
    # Each Laguerre filter after the first is all-pass with unit gain at q = 1.
    static_gain = float(theta.sum()) * math.sqrt(1 - pole * pole) / (1 - pole)
    return condition_number, chi2_statistic, static_gain


def _noise_std(x):
    """Robust noise level from the first differences, floored at a small fraction of the range."""
    finite = x[np.isfinite(x)]
    # The range between the 1 % and 99 % quantiles, so that one glitch does not
    # raise the floor (the full range where the signal rarely leaves one level).
    spread = float(np.subtract(*np.quantile(finite, [0.99, 0.01]))) if finite.size else 0.0
    if spread == 0 and finite.size:
        spread = float(np.ptp(finite))
    floor = _NOISE_FLOOR * spread if spread > 0 else 1.0
    steps = np.diff(x)
    steps = steps[np.isfinite(steps)]
    if steps.size == 0:
        return floor
    deviation = np.median(np.abs(steps - np.median(steps)))
    return max(MAD_TO_STD * float(deviation) / math.sqrt(2), floor)


def _noise_pair(noise_std):
    """Return ``noise_std`` as a pair of positive floats, or raise."""
    expected = "noise_std must be a pair (input, output) of positive numbers"
    try:
        pair = tuple(noise_std)
    except TypeError:
        raise SettingsError(f"{expected}; got {noise_std!r}") from None
    if len(pair) != 2:
        raise SettingsError(f"{expected}; got {len(pair)} values")
    return (_positive(pair[0], "noise_std[0]"), _positive(pair[1], "noise_std[1]"))


def _positive(value, name, *, above=0.0):
    """Return ``value`` as a finite float greater than ``above``, or raise naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise SettingsError(f"{name} must be a finite number; got {value!r}")
    if not value > above:
        raise SettingsError(f"{name} must be greater than {above}; got {value}")
    return float(value)


def _pole(value):
    """Return the Laguerre pole as a float in [0, 1), or raise."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise SettingsError(f"laguerre_pole must be a finite number; got {value!r}")
    if not 0 <= value < 1:
        raise SettingsError(f"laguerre_pole must lie in [0, 1) (a stable, non-oscillating filter); got {value}")
    return float(value)
