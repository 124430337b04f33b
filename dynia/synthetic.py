"""Synthetic process data with a known truth.

:func:`example_firstorder_input` is the input of the thesis's examples
(``example_firstorder.m``, Appendix B), and :func:`thesis_example` the one
definition of examples 1 and 2 (section 3.1) that every notebook, test and
benchmark uses. :func:`cooling_water_loop` makes a stand-in for the thesis's case study
(section 3.1.3): a month of event-logged input and output of the control of
the cooling water return of an offshore cooling water system. The thesis's
data are not public; this generator reproduces what the thesis reports about
them (first order, k ~ 2, T1 ~ 2, output ~ 72, input ~ 36, a handful of input
steps, a late drift of the input to ~ 40 with the output unchanged, one sample
where both read 0) and returns the truth it used, so every DYNIA finding on it
can be checked.

Examples
--------
>>> import numpy as np
>>> from dynia.synthetic import cooling_water_loop
>>> time_u, u, time_y, y, truth = cooling_water_loop(np.random.default_rng(1), days=3)
>>> truth.gain, truth.gain_after, truth.time_constant
(2.0, 1.8, 2.0)
>>> bool(time_u[0] == time_y[0] == 0), bool(time_u[-1] == time_y[-1] == 3 * 1440)
(True, True)
"""

import math
from dataclasses import dataclass

import numpy as np

from . import _checks
from .errors import SettingsError
from .models import FirstOrder, SecondOrderDelay

__all__ = ["CoolingWaterTruth", "ThesisExample", "cooling_water_loop", "example_firstorder_input", "thesis_example"]

MINUTES_PER_DAY = 1440.0


def example_firstorder_input(n_steps=500):
    """The input of the thesis's ``example_firstorder.m``, with 0-based steps.

    35 everywhere, except 10 at MATLAB steps 140-160 and 330-332 (0-based
    139-159 and 329-331) and 0 from MATLAB step 400 (0-based 399) on. The
    thesis uses 500 steps; a longer record stays at 0, a shorter one is cut.

    Examples
    --------
    >>> u = example_firstorder_input()
    >>> float(u[0]), float(u[139]), float(u[331]), float(u[398]), float(u[399])
    (35.0, 10.0, 10.0, 35.0, 0.0)
    """
    n_steps = _checks.whole_number(n_steps, "n_steps", minimum=1)
    u = 35.0 * np.ones(n_steps)
    u[139:160] = 10
    u[329:332] = 10
    u[399:] = 0
    return u


@dataclass(frozen=True, eq=False)
class ThesisExample:
    """One of the thesis's examples, with its truth: what :func:`thesis_example` returns.

    Attributes
    ----------
    u : ndarray (n_steps,)
        Input.
    y : ndarray (n_steps,)
        Measured output: ``y_true`` plus Gaussian noise of standard deviation ``noise``.
    y_true : ndarray (n_steps,)
        Noise-free output of the model at the true parameters.
    model : dynia.models.Model
    truth : dict
        True value of every parameter, in the model's order.
    bounds : dict
        Sampling range of every parameter.
    noise : float
        Standard deviation of the output noise.
    """

    u: np.ndarray
    y: np.ndarray
    y_true: np.ndarray
    model: object
    truth: dict
    bounds: dict
    noise: float


def thesis_example(number, rng):
    """Thesis example 1 or 2 (section 3.1), as every notebook and test of this package defines it.

    **Example 1** (thesis 3.1.1, ``example_firstorder.m``): ``K/(T s + 1)``
    with K = 2, T = 3; the script's 500-step input
    (:func:`example_firstorder_input`); noise 0.5 (the script's); K and T
    sampled on [0, 7] (the script's).

    **Example 2** (thesis 3.1.2): ``K exp(-theta s)/((T1 s + 1)(T2 s + 1))``
    with K = 2, T1 = 2, T2 = 2/3, theta = 100. The thesis gives neither input,
    noise nor ranges; these are the choices of ``notebooks/ch3_example2``
    (where they are argued): 600 steps of 0 with unit pulses of 10 steps
    from steps 100 and 350, noise 0.2, K in [0, 5], T1 and T2 in [0, 8],
    theta in [50, 150]. Simulations start from zero, as the record does.

    Parameters
    ----------
    number : {1, 2}
    rng : numpy.random.Generator
        The noise is drawn from it (SPEC 7); nothing else is random.

    Returns
    -------
    ThesisExample

    Examples
    --------
    >>> import numpy as np
    >>> first = thesis_example(1, np.random.default_rng(0))
    >>> first.y.shape, first.truth, first.noise
    ((500,), {'K': 2.0, 'T': 3.0}, 0.5)
    >>> second = thesis_example(2, np.random.default_rng(0))
    >>> second.model.names, second.bounds["theta"], round(float(second.y_true.max()), 2)
    (('K', 'T1', 'T2', 'theta'), (50.0, 150.0), 1.98)
    """
    if number == 1:
        u = example_firstorder_input()
        model = FirstOrder()
        truth = {"K": 2.0, "T": 3.0}
        bounds = {"K": (0.0, 7.0), "T": (0.0, 7.0)}
        noise = 0.5
    elif number == 2:
        u = np.zeros(600)
        for start in (100, 350):
            u[start : start + 10] = 1.0
        model = SecondOrderDelay()
        truth = {"K": 2.0, "T1": 2.0, "T2": 2.0 / 3.0, "theta": 100.0}
        bounds = {"K": (0.0, 5.0), "T1": (0.0, 8.0), "T2": (0.0, 8.0), "theta": (50.0, 150.0)}
        noise = 0.2
    else:
        raise SettingsError(f"number must be 1 or 2 (the thesis's two examples); got {number!r}", "number")
    rng = _checks.generator(rng)
    y_true = model.simulate([list(truth.values())], u, x0="zero")[0]
    y = y_true + rng.normal(0, noise, u.size)
    return ThesisExample(u=u, y=y, y_true=y_true, model=model, truth=truth, bounds=bounds, noise=noise)


@dataclass(frozen=True, eq=False)
class CoolingWaterTruth:
    """What :func:`cooling_water_loop` built into its data. Times in minutes from the start.

    Attributes
    ----------
    gain : float
        Gain K of the loop before the change of operating mode.
    gain_after : float
        Gain after it: ``gain * input_level / drifted_input``, so that the
        output stays where it was while the input drifts.
    time_constant : float
        Time constant T1 of the first-order lag, in minutes (constant).
    input_level, drifted_input : float
        The input's base level before and after the drift.
    step_times : ndarray
        Times of the input's step changes.
    step_inputs : ndarray
        The input's base level after each step (the last step returns to
        ``input_level``).
    drift_start, drift_end : float
        The change of operating mode: the input's base level ramps linearly
        from ``input_level`` to ``drifted_input`` and the gain falls from
        ``gain`` to ``gain_after`` between these times.
    glitch_time : float
        Timestamp of the input's erroneous zero reading (a whole minute).
    glitch_time_output : float
        Timestamp of the output's erroneous zero reading:
        ``glitch_time + glitch_lag``.
    scan : float
        Scan period of both tags.
    end : float
        Length of the record; both logs run from 0 to ``end``.
    """

    gain: float
    gain_after: float
    time_constant: float
    input_level: float
    drifted_input: float
    step_times: np.ndarray
    step_inputs: np.ndarray
    drift_start: float
    drift_end: float
    glitch_time: float
    glitch_time_output: float
    scan: float
    end: float

    def base_input_at(self, t):
        """The input's base level at times ``t``: steps and drift, without the wander."""
        t = np.asarray(t, dtype=float)
        levels = np.r_[self.input_level, self.step_inputs]
        base = levels[np.searchsorted(self.step_times, t, side="right")]
        return base + (self.drifted_input - self.input_level) * self._drift_fraction(t)

    def gain_at(self, t):
        """The true gain K at times ``t``: ``gain`` before the drift, ``gain_after`` after it.

        During the drift ``K(t) * level(t)`` stays ``gain * input_level``,
        where level(t) is the drifting base level.
        """
        drifting = self.input_level + (self.drifted_input - self.input_level) * self._drift_fraction(t)
        return self.gain * self.input_level / drifting

    def _drift_fraction(self, t):
        t = np.asarray(t, dtype=float)
        return np.clip((t - self.drift_start) / (self.drift_end - self.drift_start), 0.0, 1.0)


def cooling_water_loop(
    rng,
    *,
    days=30,
    gain=2.0,
    time_constant=2.0,
    input_level=36.0,
    drifted_input=40.0,
    n_steps=6,
    step_offset=(1.0, 2.0),
    scan=1 / 6,
    glitch_lag=1.0,
    input_wander=0.25,
    output_disturbance=0.3,
    sensor_noise=0.05,
    input_deadband=0.1,
    output_deadband=0.3,
    max_interval=60.0,
):
    """Event logs of a synthetic cooling-water return loop, and the truth behind them.

    Time is in minutes from the start of the record. The process is the
    first-order lag ``y/u = K/(T1 s + 1)`` with T1 = ``time_constant`` and a
    gain K(t) that is ``gain`` until a change of operating mode late in the
    record, simulated exactly (zero-order hold on the input's scan raster,
    the output evaluated at its own scan instants).

    The input (the controller output to the loop, known exactly) is its base
    level plus a slow wander: an Ornstein-Uhlenbeck process with standard
    deviation ``input_wander`` and correlation time 2 h. The base level is
    ``input_level`` with ``n_steps`` step changes in the first 60 % of the
    record: excursions of alternating sign and magnitude uniform in
    ``step_offset`` around ``input_level``, the last step back to
    ``input_level``. At about 70 % of the record the base level ramps, over
    about a tenth of the record, to ``drifted_input``, while the gain falls
    in proportion (``K(t) * level(t)`` constant): a change of operating mode
    in which the input rises from ~36 to ~40 and the output stays near 72.

    The measured output is the process output plus an unmeasured disturbance
    (Ornstein-Uhlenbeck, standard deviation ``output_disturbance``,
    correlation time 1 h) plus white sensor noise (``sensor_noise``).

    Logging. Each tag is scanned every ``scan`` minutes on its own clock (a
    random phase, and timestamps up to a fifth of a scan late) and stored by
    exception, as plant historians do: a reading is stored when it differs
    from the last stored value by more than the tag's deadband
    (``input_deadband``, ``output_deadband``), together with the reading
    before it if that was not stored (so that linear interpolation between
    stored values follows the signal within the deadband), or when
    ``max_interval`` minutes have passed since the last stored value (a
    heartbeat). Steps are therefore logged scan by scan and steady stretches
    every several minutes. Both logs start with the reading at 0 and end
    with the reading at the record's end, as an export of a time range does.

    The glitch. One reading of each tag is 0 instead of its value: the
    input's is stamped at a whole minute ``t_g`` in a steady stretch, at
    least 30 time constants from any step and from the drift; the output's
    is stamped at ``t_g + glitch_lag``. Both are surrounded by good readings
    one scan before and after. This is a deliberate choice, made so that the
    glitch looks on a 1-minute grid starting at 0 the way the thesis
    describes it: because ``t_g`` is a whole minute and a scan is shorter
    than a minute, :func:`dynia.io.csv.resample_events` with ``dt=1`` gives
    exactly one zero input sample, at ``t_g``, and exactly one zero output
    sample, at ``t_g + 1`` for the default lag of 1 minute. Independently
    logged tags do see one fault at slightly different times; a lag of one
    grid step is the case in which a first-order model with T1 -> 0
    reproduces the glitch exactly (its output at step k+1 is K times the
    input at step k), so the window around the glitch favours T1 near 0, the
    thesis's finding. With ``glitch_lag=0`` the two zeros are simultaneous,
    which no causal model reproduces; other grids smear the zeros over
    neighbouring grid points at partial depth.

    Parameters
    ----------
    rng : numpy.random.Generator or int
        Source of every random draw; the same seed gives identical logs.
    days : float, default 30
        Length of the record in days (about a month, as in the thesis).
    gain, time_constant : float, default 2.0, 2.0
        K before the change of mode and T1 (minutes).
    input_level, drifted_input : float, default 36.0, 40.0
        The input's base level before and after the drift.
    n_steps : int, default 6
        Number of input step changes.
    step_offset : (float, float), default (1.0, 2.0)
        Range of the magnitude of each excursion from ``input_level``.
    scan : float, default 1/6
        Scan period of both tags in minutes (10 s); below 1 minute.
    glitch_lag : float, default 1.0
        Time from the input's zero reading to the output's, minutes, >= 0.
    input_wander, output_disturbance, sensor_noise : float
        Standard deviations of the input's wander, of the output's
        disturbance and of the output's sensor noise.
    input_deadband, output_deadband : float, default 0.1, 0.3
        Exception deadbands of the two tags.
    max_interval : float, default 60.0
        Longest time between two stored values of a tag, minutes.

    Returns
    -------
    time_u, u : ndarray
        The input's event log: timestamps (minutes, strictly increasing)
        and values.
    time_y, y : ndarray
        The output's event log.
    truth : CoolingWaterTruth
        The gains, time constant, step times, the change of mode and the
        glitch times used.

    Raises
    ------
    ValueError
        For an argument out of range (the message names it), or a record too
        short to hold the steps, the drift and a glitch in a steady stretch.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.synthetic import cooling_water_loop
    >>> time_u, u, time_y, y, truth = cooling_water_loop(np.random.default_rng(3))
    >>> len(truth.step_times), truth.drift_start < truth.drift_end < truth.end
    (6, True)
    >>> float(np.median(u[time_u < truth.drift_start]).round()), float(np.median(y).round())
    (36.0, 72.0)
    >>> float(u[time_u == truth.glitch_time][0]), float(y[time_y == truth.glitch_time_output][0])
    (0.0, 0.0)
    """
    rng = _checks.generator(rng)
    days = _checks.open_interval(days, "days", 0, math.inf)
    gain = _checks.open_interval(gain, "gain", 0, math.inf)
    time_constant = _checks.open_interval(time_constant, "time_constant", 0, math.inf)
    input_level = _checks.open_interval(input_level, "input_level", 0, math.inf)
    drifted_input = _checks.open_interval(drifted_input, "drifted_input", 0, math.inf)
    n_steps = _checks.whole_number(n_steps, "n_steps", minimum=1)
    scan = _checks.open_interval(scan, "scan", 0, 1)
    glitch_lag = _nonnegative(glitch_lag, "glitch_lag")
    low_offset, high_offset = _range(step_offset, "step_offset")
    input_wander = _nonnegative(input_wander, "input_wander")
    output_disturbance = _nonnegative(output_disturbance, "output_disturbance")
    sensor_noise = _nonnegative(sensor_noise, "sensor_noise")
    input_deadband = _nonnegative(input_deadband, "input_deadband")
    output_deadband = _nonnegative(output_deadband, "output_deadband")
    max_interval = _checks.open_interval(max_interval, "max_interval", 0, math.inf)

    end = days * MINUTES_PER_DAY
    raster = scan * np.arange(math.floor(end / scan * (1 + 1e-12)) + 1)  # the input's scans, <= end

    step_times, step_inputs, drift_start, drift_end = _plan(
        rng, end, raster, n_steps, input_level, low_offset, high_offset
    )
    glitch_time = _glitch_time(rng, days, end, step_times, drift_start, drift_end, 30 * time_constant, glitch_lag)
    truth = CoolingWaterTruth(
        gain=gain,
        gain_after=gain * input_level / drifted_input,
        time_constant=time_constant,
        input_level=input_level,
        drifted_input=drifted_input,
        step_times=step_times,
        step_inputs=step_inputs,
        drift_start=drift_start,
        drift_end=drift_end,
        glitch_time=glitch_time,
        glitch_time_output=glitch_time + glitch_lag,
        scan=scan,
        end=end,
    )
    time_u, u, time_y, y = _tag_readings(rng, truth, raster, input_wander, output_disturbance, sensor_noise)
    _zero_reading(time_u, u, glitch_time)
    _zero_reading(time_y, y, glitch_time + glitch_lag)
    stored_u = _exception_log(time_u, u, input_deadband, max_interval)
    stored_y = _exception_log(time_y, y, output_deadband, max_interval)
    return time_u[stored_u], u[stored_u], time_y[stored_y], y[stored_y], truth


def _plan(rng, end, raster, n_steps, input_level, low_offset, high_offset):
    """The input steps (times and levels) and the drift's start and end, drawn from ``rng``.

    One step in the middle 60 % of each of n_steps equal slots of [5 %, 60 %]
    of the record, on the input's scan raster; alternating excursions, the
    last back to input_level. The drift starts at about 70 % and lasts about 10 %.
    """
    slot = 0.55 * end / n_steps
    step_times = 0.05 * end + slot * (np.arange(n_steps) + rng.uniform(0.2, 0.8, n_steps))
    step_times = raster[np.searchsorted(raster, step_times)]
    sign = rng.choice([-1.0, 1.0]) * (-1.0) ** np.arange(n_steps - 1)
    step_inputs = np.r_[input_level + sign * rng.uniform(low_offset, high_offset, n_steps - 1), input_level]
    drift_start = end * rng.uniform(0.68, 0.72)
    drift_end = drift_start + end * rng.uniform(0.08, 0.12)
    return step_times, step_inputs, drift_start, drift_end


def _glitch_time(rng, days, end, step_times, drift_start, drift_end, margin, glitch_lag):
    """The glitch: a whole minute in a steady stretch, ``margin`` minutes from the steps and the drift."""
    minutes = np.arange(math.ceil(0.03 * end), math.floor(0.97 * end - glitch_lag))
    steady = (np.abs(minutes[:, None] - step_times[None, :]) > margin).all(axis=1)
    steady &= (minutes < drift_start - margin) | (minutes > drift_end + margin)
    if not steady.any():
        raise SettingsError(
            f"days = {days} is too short: no steady minute at least {margin} minutes from the steps "
            "and the drift is left for the glitch"
        )
    return float(rng.choice(minutes[steady]))


def _tag_readings(rng, truth, raster, input_wander, output_disturbance, sensor_noise):
    """The process simulated on the input's raster, and what the two tags read of it: time_u, u, time_y, y.

    u[k] is held on [raster[k], raster[k+1]). The input tag reads the input
    at its scans (raster plus a late stamp); the output tag scans on its own
    phase and reads the exact response between raster points.
    """
    from scipy.signal import lfilter  # here: scipy.signal takes 1.5 s to import, and most records do not filter

    scan, end, time_constant = truth.scan, truth.end, truth.time_constant
    u_true = truth.base_input_at(raster) + _ornstein_uhlenbeck(rng, raster.size, scan, 120.0, input_wander)
    drive = truth.gain_at(raster) * u_true
    pole = math.exp(-scan / time_constant)
    states, _ = lfilter([1 - pole], [1, -pole], drive, zi=[pole * drive[0]])
    states = np.r_[drive[0], states[:-1]]  # the output at each raster time, steady at the start
    disturbance = _ornstein_uhlenbeck(rng, raster.size, scan, 60.0, output_disturbance)

    time_u = raster + rng.uniform(0, 0.2 * scan, raster.size)
    time_u[0] = 0.0
    keep = time_u < end
    time_u, u = np.r_[time_u[keep], end], np.r_[u_true[keep], u_true[-1]]
    scans_y = rng.uniform(0, 0.8 * scan) + raster + rng.uniform(0, 0.2 * scan, raster.size)
    time_y = np.r_[0.0, scans_y[(scans_y > 0) & (scans_y < end)], end]
    index = np.searchsorted(raster, time_y, side="right") - 1
    y = (
        drive[index]
        + (states[index] - drive[index]) * np.exp(-(time_y - raster[index]) / time_constant)
        + disturbance[index]
        + rng.normal(0, sensor_noise, time_y.size)
    )
    return time_u, u, time_y, y


def _range(pair, name):
    """A (low, high) pair with 0 <= low <= high, or raise naming ``name``."""
    try:
        low, high = (float(value) for value in pair)
    except (TypeError, ValueError):
        raise SettingsError(f"{name} must be a (low, high) pair of numbers; got {pair!r}") from None
    if not (math.isfinite(low) and math.isfinite(high) and 0 <= low <= high):
        raise SettingsError(f"{name} must satisfy 0 <= low <= high; got {pair!r}")
    return low, high


def _nonnegative(value, name):
    """0, or a finite number > 0; raise naming ``name`` otherwise."""
    return 0.0 if value == 0 else _checks.open_interval(value, name, 0, math.inf)


def _ornstein_uhlenbeck(rng, size, step, correlation_time, std):
    """A stationary Ornstein-Uhlenbeck process sampled every ``step``: exact AR(1)."""
    from scipy.signal import lfilter  # here: scipy.signal takes 1.5 s to import, and most records do not filter

    decay = math.exp(-step / correlation_time)
    shocks = rng.normal(0, std, size)
    shocks[1:] *= math.sqrt(1 - decay**2)
    return lfilter([1.0], [1.0, -decay], shocks)


def _zero_reading(times, values, at):
    """Turn the reading nearest ``at`` into an erroneous 0 stamped exactly ``at`` (in place)."""
    nearest = int(np.argmin(np.abs(times - at)))
    times[nearest] = at
    values[nearest] = 0.0


def _exception_log(times, values, deadband, max_interval):
    """Indices a historian stores under exception reporting with a heartbeat.

    A reading is stored when it differs from the last stored value by more
    than ``deadband`` (with the reading before it, if that was not stored),
    or when ``max_interval`` has passed since the last stored reading. The
    first and last readings are always stored.
    """
    times_list, values_list = times.tolist(), values.tolist()
    stored = [0]
    last_value, last_time = values_list[0], times_list[0]
    for index in range(1, len(values_list) - 1):
        value, time = values_list[index], times_list[index]
        if abs(value - last_value) > deadband:
            if stored[-1] != index - 1:
                stored.append(index - 1)
            stored.append(index)
        elif time - last_time >= max_interval:
            stored.append(index)
        else:
            continue
        last_value, last_time = value, time
    stored.append(len(values_list) - 1)
    return np.array(stored)
