"""A record's time scale, and the window it asks for: a first-order fit to the whole record, and the noise.

DYNIA's moving window must span the dynamics a parameter shows in: about one dominant time constant of the
record, and enough points to tell a parameter a little off from the noise. :func:`dominant_time_constant`
finds the time constant, :func:`proposed_window` sizes the window by it and by the noise (the window
:func:`dynia.suggestion.suggest` proposes), and :func:`window_half_width` turns a window given as a
duration (:func:`parse_duration` reads "3min") into the half window n of :func:`dynia.run`.

The dominant time constant
--------------------------
A first-order model ``y = c + sum_j K_j r_j(T)`` is fitted to the whole
record, ``r_j(T)`` being the unit-gain first-order response (zero-order
hold) of input j in the analysis's initial state: with ``x0="zero"`` from
rest at zero input, so that a record whose input is already on in its first
row (a heater switched on before logging began) shows the response still
rising toward it; with ``x0="steady"`` from rest at the input's first value,
so that only its changes drive the response. ``u`` and ``y`` are those the
analysis sees, the offsets (``--input-offset``, ``--offset``) already taken
off; the level c is fitted all the same, so that a level the offsets leave
does not pass for dynamics. For a given T the output is
linear in the gains and the level c, which ordinary least squares gives
exactly (variable projection), so only T is searched: on a logarithmic grid
from dt to the record's length, then refined between the neighbours of the
best grid point. This needs no starting value and finds the best T on the
grid, not a local minimum; it uses every measured point, so the noise
averages out over the record; it takes any input (steps that never settle,
several inputs) and missing output values. A dead time or a second, faster
lag adds roughly its length to the fitted T, which is what a window must
span anyway. Rejected: reading the time to 63 % after each step (needs
clean steps that settle, and reads one noisy crossing per step) and the
decay of the autocorrelation of the output's increments (at fast sampling
they are mostly measurement noise).

When the fit explains less than :data:`MIN_EXPLAINED` (50 %) of the
output's variance (``R^2 = 1 - RSS/TSS``), the time constant it finds is no
property of the record (an input that never changes as the analysis sees
it gives the shortest one, whatever the output does), and a window sized by
it would mislead: :func:`proposed_window` (and so :func:`dynia.suggestion.suggest`) raises
:class:`~dynia.errors.SuggestionError` saying so, and which initial state
would explain the output instead, rather than proposing one. It raises the
same, saying what is missing, for an output that never changes, for one
value (a logger's 1.797e308) that holds most of the output's variance, and
for a fit whose best time constant is the shortest tried, dt (an output that
follows the input within one sample resolves no time constant). The fit
runs on values scaled to unit size, so that neither 1e200 overflows nor
1e-170 underflows; T does not depend on the scale.

The window
----------
A window of about one time constant, ``2n+1 = T/dt``, so ``n = round(T /
(2 dt))`` (at least 1). The window centred on a step then holds the settled
level before it and the first half time constant of the response, where the
response bends most: there gain and time constant act differently on the
output. A much shorter window sees a straight line, along which gain and
time constant trade off (only their ratio, the initial slope, shows); a
much longer one averages the transient with settled stretches, which
inform the gain only, or with the response to the next input change
(several regimes in one window). Input changes closer together than one
window are reported.

The window must also beat the measurement noise. A parameter a tenth off
its value (the resolution the behavioural share of :mod:`dynia.suggestion` aims at) moves the
response by about a tenth of its size A, the standard deviation of the
first-order fit's response (the part of the output the input explains,
``sqrt(R^2) * SD(y)``); noise of standard deviation sigma hides a shift of
the mean over a window of m measured points below ``sigma / sqrt(m)``. The
window tells the two apart when that tenth is at least :data:`NOISE_MARGIN`
(2) such standard errors, ``A / 10 >= 2 sigma / sqrt(m)``, so it holds at
least ``m = (2 * 10 * sigma / A)^2`` steps, and the window is the longer of
the two. sigma is :func:`dynia.verdicts.noise_sigma` of the output (the
median absolute difference of neighbours, which steps and slow dynamics
barely move). On a first-order record with T = 5 s at 1 s, responses of
about 1 degC and noise of 0.4 degC, one time constant is a 5 s window in
which neither gain nor time constant is identified (every window's
behavioural set ties within the noise); the noise asks for about 45 s, which
identifies both. On a clean record (the TCLab-like step test: responses of
20 degC under 0.15 degC of noise) the time constant sets the window alone.

Examples
--------
>>> import numpy as np
>>> from dynia.models import FirstOrder
>>> u = np.repeat([0.0, 50.0, 20.0, 70.0], 600)
>>> y = FirstOrder().simulate([[0.6, 60.0]], u)[0]
>>> round(dominant_time_constant(u, y).time_constant, 3)
60.0
>>> window_half_width(60.0, dt=1.0, n_steps=u.size)
30
"""

import math
from dataclasses import dataclass

import numpy as np

from . import _checks
from .errors import DataError, SettingsError, SuggestionError
from .io.frames import unpack
from .settings import check_dt, check_x0
from .verdicts import noise_sigma

__all__ = [
    "TimeScale",
    "dominant_time_constant",
    "proposed_window",
    "window_half_width",
    "parse_duration",
    "MIN_EXPLAINED",
    "NOISE_MARGIN",
    "RANGE_SHARE_INVERSE",
]

# Below this share of the output's variance explained (R^2) the first-order fit sizes no window.
MIN_EXPLAINED = 0.5
#: A parameter a tenth off must move a window's mean by this many standard errors of the noise (The window).
NOISE_MARGIN = 2.0
# The resolution the analysis aims at: a share 1/RANGE_SHARE_INVERSE of each range, which the window's noise test
# and the percentage dynia.suggestion proposes both use; an integer, so that 100 / 10**d is the float nearest the
# intended 1 % or 0.1 %.
RANGE_SHARE_INVERSE = 10

# Trial time constants of the first-order fit: this many, log-spaced from dt to the record's length.
_GRID_POINTS = 60
# An input change counts when it exceeds this share of the input's range; the input is step-like when
# fewer than _STEP_LIKE of its steps change.
_CHANGE_SHARE = 0.01
_STEP_LIKE = 0.1
# No window is proposed when one value holds more than this share of the output's squared deviations.
_ONE_VALUE_SHARE = 0.5
# The other initial state is noted when its residual variance is below this share of the chosen one's.
_BETTER_RESIDUAL = 0.5
# The units parse_duration reads, in seconds.
_UNITS = {
    "s": 1.0,
    "sec": 1.0,
    "second": 1.0,
    "seconds": 1.0,
    "min": 60.0,
    "minute": 60.0,
    "minutes": 60.0,
    "h": 3600.0,
    "hour": 3600.0,
    "hours": 3600.0,
    "d": 86400.0,
    "day": 86400.0,
    "days": 86400.0,
}


def parse_duration(text, name="window"):
    """Seconds in a duration such as ``"60s"``, ``"2min"``, ``"1.5h"``, ``"1d"`` or ``"90"`` (seconds).

    Raises :class:`~dynia.errors.SettingsError` naming ``name`` for anything
    else, or a duration that is not positive and finite.

    >>> parse_duration("2min"), parse_duration("1h"), parse_duration("90")
    (120.0, 3600.0, 90.0)
    """
    match = _checks.QUANTITY.match(str(text))
    unit = match.group(2).lower() if match else None
    if match is None or (unit and unit not in _UNITS):
        raise SettingsError(
            f"{name} must be a duration such as 60s, 2min or 1h (units s, min, h, d; a bare number is seconds); "
            f"got {text!r}",
            name,
        )
    seconds = float(match.group(1)) * _UNITS.get(unit, 1.0)
    if not (math.isfinite(seconds) and seconds > 0):
        raise SettingsError(f"{name} must be a positive, finite duration; got {text!r}", name)
    return seconds


def window_half_width(seconds, dt, n_steps, name="window"):
    """Half window n of a window lasting ``seconds``: ``round(seconds / (2 dt))``, rounded half up.

    Raises :class:`~dynia.errors.SettingsError` naming ``name`` when the
    window is shorter than 3 steps or when its 2n+1 steps exceed the
    record's ``n_steps``.

    >>> window_half_width(171.0, dt=1.0, n_steps=7200), window_half_width(60.0, dt=2.0, n_steps=100)
    (86, 15)
    """
    dt = check_dt(dt)
    steps = seconds / dt
    if steps < 3:
        raise SettingsError(
            f"{name} {seconds:g} s is {steps:.3g} steps of {dt:g} s; a window needs at least 3 steps ({3 * dt:g} s)",
            name,
        )
    if steps > max(n_steps, 10**12):  # not as a whole number: 1e308 s would print 309 digits
        raise SettingsError(
            f"{name} {seconds:g} s is {steps:.6g} steps of {dt:g} s, longer than the record's "
            f"{n_steps} steps ({n_steps * dt:g} s)",
            name,
        )
    n = math.floor(steps / 2 + 0.5)
    if 2 * n + 1 > n_steps:
        raise SettingsError(
            f"{name} {seconds:g} s is {2 * n + 1} steps of {dt:g} s (2n+1 with n = {n}), longer than the record's "
            f"{n_steps} steps ({n_steps * dt:g} s)",
            name,
        )
    return n


@dataclass(frozen=True)
class TimeScale:
    """The first-order fit of :func:`dominant_time_constant`.

    Attributes
    ----------
    time_constant : float
        T, in the units of dt.
    gains : tuple of float
        K of each input.
    level : float
        The output's level c where the response starts: at rest, at zero
        input (``x0="zero"``) or at the inputs' first values (``"steady"``).
    rmse : float
        Root mean square of the residuals.
    explained : float
        Share of the output's variance the fit explains (1 - RSS/TSS).
    edge : str or None
        "fast" when T came out at the grid's lower end (the output follows
        the input within a sample), "slow" at its upper end (slower than the
        record); None otherwise.
    x0 : str
        The initial state the responses start from ("zero" or "steady").
    """

    time_constant: float
    gains: tuple
    level: float
    rmse: float
    explained: float
    edge: str | None = None
    x0: str = "zero"


def dominant_time_constant(u, y, dt=None, x0="zero"):
    """The time constant of a first-order fit to the whole record (module docs).

    Parameters
    ----------
    u : array_like, shape (n_steps,) or (n_steps, n_inputs), or pandas Series / DataFrame
    y : array_like, shape (n_steps,), or pandas Series
        NaN marks a missing value. pandas objects as :func:`dynia.run` takes
        them (:func:`dynia.io.frames.unpack`): one index, whose time gives dt.
    dt : float, optional
        Sample time; default the spacing of a time index, else 1.0.
    x0 : {"zero", "steady"}, default "zero"
        The analysis's initial state: the responses start at rest at zero
        input, or at rest at the inputs' first values.

    Returns
    -------
    TimeScale
    """
    # Here, not at the top: scipy.signal (with the scipy.stats it loads) takes 1.5 s to import, and every command
    # of the command line imports this module for its window's duration, which needs neither.
    from scipy.optimize import minimize_scalar
    from scipy.signal import lfilter

    u, y, dt, _ = unpack(u, y, dt)
    dt, x0 = check_dt(1.0 if dt is None else dt), check_x0(x0)
    columns = np.asarray(u, dtype=float)
    n_inputs = 1 if columns.ndim == 1 else columns.shape[1]
    u, y = _checks.record(u, y, n_inputs=n_inputs)
    columns = u.reshape(u.shape[0], -1)
    if x0 == "steady":
        # At rest at the first input only the changes from it move the output; its level is in c.
        columns = columns - columns[0]
    measured = ~np.isnan(y)
    if measured.sum() < n_inputs + 2:
        raise DataError(f"y has {int(measured.sum())} measured values; a first-order fit needs {n_inputs + 2}")
    # The fit on unit-scaled values, so that neither the squares of 1e200 overflow nor those of 1e-170 underflow:
    # T and the share explained do not depend on the scale; gains, level and RMS residual are scaled back.
    centre = float(np.median(y[measured]))
    spread_y = _unit(y[measured] - centre)
    observed = (y[measured] - centre) / spread_y
    spread_u = np.array([_unit(column) for column in columns.T])
    columns = columns / spread_u

    def solve(log_tau):
        pole = math.exp(-dt / math.exp(log_tau))
        responses = lfilter([0.0, 1.0 - pole], [1.0, -pole], columns, axis=0)[measured]
        design = np.column_stack([np.ones(observed.size), responses])
        coefficients, *_ = np.linalg.lstsq(design, observed, rcond=None)
        residual = observed - design @ coefficients
        return float(residual @ residual), coefficients

    grid = np.linspace(math.log(dt), math.log(max(u.shape[0] * dt, 2 * dt)), _GRID_POINTS)
    costs = [solve(point)[0] for point in grid]
    best = int(np.argmin(costs))
    low, high = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
    refined = minimize_scalar(lambda point: solve(point)[0], bounds=(low, high), method="bounded")
    log_tau = refined.x if refined.fun < costs[best] else grid[best]
    rss, coefficients = solve(log_tau)
    spread = float(np.sum((observed - observed.mean()) ** 2))
    edge = "fast" if best == 0 else "slow" if best == grid.size - 1 else None
    return TimeScale(
        time_constant=float(math.exp(log_tau)),
        gains=tuple(float(value) * spread_y / scale for value, scale in zip(coefficients[1:], spread_u)),
        level=float(coefficients[0]) * spread_y + centre,
        rmse=math.sqrt(rss / observed.size) * spread_y,
        explained=1.0 - rss / spread if spread > 0 else 0.0,
        edge=edge,
        x0=x0,
    )


def _unit(values):
    """The largest magnitude among ``values``, or 1 where all are 0: a divisor that leaves them within [-1, 1]."""
    largest = float(np.max(np.abs(values))) if values.size else 0.0
    return largest if largest > 0 else 1.0


def proposed_window(u, y, dt, x0, given=None):
    """The half window n a record asks for, the time scale that sets it, and why (module docs).

    n is the longer of one dominant time constant and what beats the noise, or ``given`` as given.

    Parameters
    ----------
    u : ndarray, shape (n_steps,) or (n_steps, n_inputs)
    y : ndarray, shape (n_steps,)
        Input and output as :func:`dynia.suggestion.suggest` has checked
        them: a finite input, NaN where the output is missing.
    dt : float
        Sample time.
    x0 : {"zero", "steady"}
        The analysis's initial state.
    given : int, optional
        A half window given: kept, and the reasons say what the record
        would have asked for.

    Returns
    -------
    scale : TimeScale
        The first-order fit in the initial state ``x0``.
    n : int
        The half window.
    reasons, notes : list of str
        Why this window, one sentence each; and what to check: input
        changes closer together than a window, a record the other initial
        state explains better, a record too short or too slow to settle.

    Raises
    ------
    dynia.errors.SuggestionError
        When the record shows no time scale to size a window by and none
        is given.
    """
    n_steps = y.size
    measured = y[~np.isnan(y)]
    if measured.size and (measured == measured[0]).all():
        raise SuggestionError(
            f"cannot propose a window: the output never changes (every measured value is {measured[0]:g}), so the "
            "record holds no response to size a window by, nor any information on the parameters"
        )
    scale = dominant_time_constant(u, y, dt, x0)
    other = dominant_time_constant(u, y, dt, "steady" if x0 == "zero" else "zero")
    unusable = None
    if not scale.explained >= MIN_EXPLAINED:  # NaN too
        unusable = _no_time_scale(u, y, scale, other, dt)
    elif scale.edge == "fast":
        # The shortest trial time constant fits best: a step in the output one sample after the input's, or a pure
        # delay, looks the same; a 3-step window sized by it would rest on no time scale of the record.
        unusable = (
            f"cannot propose a window: the output follows the input within one sample ({dt:g} s), so the record "
            "resolves no time constant at this sampling to size a window by (a first-order fit finds the shortest "
            "it tries, dt); sample faster, or give the window yourself (--window or --n)"
        )
    if unusable is not None:
        if given is None:
            raise SuggestionError(unusable)
        why = unusable.removeprefix("cannot propose a window: ").split("; ")[0]
        reasons = [
            f"no dominant time constant: {why}",
            f"window 2n+1 = {2 * given + 1} steps ({(2 * given + 1) * dt:g} s), as given (n = {given})",
        ]
        return scale, given, reasons, _close_changes(u, given, dt)
    wanted, reasons = _window_reasons(scale, y, dt, x0, given)
    n = min(wanted, (n_steps - 1) // 2) if given is None else given
    notes = []
    if scale.edge == "slow":
        notes.append("the first-order fit finds a time constant as long as the record: the record may not settle")
    if (1 - other.explained) < _BETTER_RESIDUAL * (1 - scale.explained):
        notes.append(
            f"with x0 {other.x0} a first-order model explains {100 * other.explained:.0f} % of the output's variance, "
            f"against {100 * scale.explained:.0f} % with x0 {x0}: check the initial state and the offsets"
        )
    if n < wanted and given is None:
        notes.append(f"the window is capped at the record's length ({n_steps} steps); a longer record would help")
    notes += _close_changes(u, n, dt)
    return scale, n, reasons, notes


def _window_reasons(scale, y, dt, x0, given):
    """The half window the record asks for (one time constant, or what beats the noise), and the two reasons."""
    tau = scale.time_constant
    by_tau = max(math.floor(tau / (2 * dt) + 0.5), 1)
    sigma = noise_sigma(y)
    # The response's size: the standard deviation of the fitted first-order response, sqrt(R^2) SD(y).
    size = math.sqrt(max(scale.explained, 0.0)) * float(np.nanstd(y))
    points = (NOISE_MARGIN * RANGE_SHARE_INVERSE * sigma / size) ** 2 if size > 0 else math.inf
    by_noise = max(math.ceil((points - 1) / 2), 0) if math.isfinite(points) else y.size
    wanted = max(by_tau, by_noise)
    gains = ", ".join(f"{gain:.3g}" for gain in scale.gains)
    noise = (
        f"the noise (SD {sigma:.3g}, from the output's differences) against the response's size {size:.3g} (the "
        f"fitted response's SD) asks for m >= ({NOISE_MARGIN:g} x {RANGE_SHARE_INVERSE} x {sigma:.3g} / "
        f"{size:.3g})^2 = {points:.3g} points, for a parameter a tenth off to move a window's mean by "
        f"{NOISE_MARGIN:g} standard errors of the noise"
    )
    if by_noise > by_tau:
        window = (
            f"window 2n+1 = {2 * wanted + 1} steps ({(2 * wanted + 1) * dt:g} s), longer than one time constant "
            f"({2 * by_tau + 1} steps) to beat the noise: {noise}"
        )
    else:
        window = (
            f"window 2n+1 = {2 * wanted + 1} steps ({(2 * wanted + 1) * dt:g} s), about one time constant: centred on "
            "an input change it holds the level before and the bend of the response, where gain and time constant "
            f"act differently; shorter windows see a line (only their ratio), longer ones mix in settled stretches; "
            + noise.replace("asks for", "asks for no more than one time constant:", 1)
        )
    if given is not None:
        window = f"window 2n+1 = {2 * given + 1} steps ({(2 * given + 1) * dt:g} s), as given (n = {given}); " + (
            f"the record would ask for n = {wanted}: " + window.split(": ", 1)[1] if wanted != given else "as proposed"
        )
    reasons = [
        f"dominant time constant {tau:.4g} s: a first-order fit to the whole record from the analysis's initial "
        f"state (x0 {x0}; gain {gains}, RMS residual {scale.rmse:.3g}, {100 * scale.explained:.0f} % of the "
        "output's variance explained)",
        window,
    ]
    return wanted, reasons


def _no_time_scale(u, y, scale, other, dt):
    """Why no window can be proposed from ``scale``, the fit in the analysis's initial state, in one line."""
    columns = u.reshape(u.shape[0], -1)
    if scale.x0 == "steady":
        columns = columns - columns[0]
    explained = max(scale.explained, 0.0) if math.isfinite(scale.explained) else 0.0
    message = (
        f"cannot propose a window: a first-order model from the analysis's initial state (x0 {scale.x0}) explains "
        f"{100 * explained:.0f} % of the output's variance, below {100 * MIN_EXPLAINED:.0f} %, so "
        "the record shows no time constant to size a window by"
    )
    # One value far from the rest (a logger's overflow or fill value) is the variance no model explains.
    deviation = np.abs(y - np.nanmedian(y))
    deviation = np.nan_to_num(deviation / _unit(deviation[~np.isnan(deviation)]), nan=0.0)
    largest = int(np.argmax(deviation))
    if deviation[largest] ** 2 > _ONE_VALUE_SHARE * np.sum(deviation**2):
        message += (
            f" (one value, {y[largest]:g} at step {largest} ({largest * dt:g} s from the start), holds "
            f"{100 * deviation[largest] ** 2 / np.sum(deviation**2):.0f} % of the output's variance: check the data)"
        )
    if not columns.any():
        message += (
            " (the input never moves the model: "
            + ("it stays at its first value" if scale.x0 == "steady" else "it is zero throughout")
            + ")"
        )
    if other.explained >= MIN_EXPLAINED:
        message += (
            f"; with x0 {other.x0} it explains {100 * other.explained:.0f} % (time constant "
            f"{other.time_constant:.4g} s): check --x0 and the offsets"
        )
    else:
        message += "; check the offsets and the model, or give the window yourself (--window or --n)"
    return message


def _close_changes(u, n, dt):
    """A note when a step-like input changes again within one window of an earlier change."""
    notes = []
    columns = u.reshape(u.shape[0], -1)
    for column in columns.T:
        span = float(column.max() - column.min())
        if span == 0:
            continue
        changed = np.abs(np.diff(column)) > _CHANGE_SHARE * span
        if changed.mean() >= _STEP_LIKE:
            continue
        changes = np.flatnonzero(changed) + 1
        # A ramp is one change: only a change after a quiet step starts a new one.
        starts = changes[np.r_[True, np.diff(changes) > 1]] if changes.size else changes
        close = np.flatnonzero(np.diff(starts) < 2 * n + 1)
        if close.size:
            notes.append(
                f"{close.size} input change(s) follow the previous one within a window ({(2 * n + 1) * dt:g} s), "
                f"the first at {starts[close[0] + 1] * dt:g} s: windows there see two responses at once"
            )
    return notes
