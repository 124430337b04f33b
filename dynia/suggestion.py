"""Settings that let DYNIA see what a record holds, proposed from the record itself, with the reasons.

The defaults of :func:`dynia.run` (a window of 21 steps, the best 10 % of
2000 samples) suit the thesis's examples, whose time constants are a few
steps. On a heater step test sampled every second with a time constant of
three minutes they identify nothing, and nothing says why. :func:`suggest`
(``dynia suggest DATA.csv ...`` on the command line) proposes a window, a
behavioural share and a number of samples, and checks the parameter ranges,
by the reasoning below.

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
it would mislead: :func:`suggest` raises
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
its value (the resolution the behavioural share aims at, below) moves the
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

A window given (``n=``, ``dynia suggest --n`` or ``--window``) is kept as
given: the rest is proposed around it, and the reasons say what the record
would have asked for. So are a behavioural share (``percentage=``) and a
number of samples (``n_samples=``) given; the pilot runs with the share and
window given, and with the other settings of ``settings`` (flavour, bins,
confidence level, sampler, ...).

The behavioural share
---------------------
The information content is ``1 - (band width)/(range)``, and the band is
read from the behavioural set: the ``percentage`` % of the samples with the
lowest cost in the window, i.e. a fixed share of the volume of the
parameter box, however many samples are drawn. When a window pins each of
d parameters alike, that share spans about ``(percentage/100)^(1/d)`` of
every range, and much more along a ridge of correlated parameters (gain and
time constant in a transient), so the share caps the IC: the default 10 %
with two parameters lets the best window reach about 0.3 for a time
constant on a heater step test. The share proposed is ``100 * 0.1^d`` %
(capped at 10 %), a tenth of each range: 10 % for one parameter (the
thesis's choice), 1 % for two, 0.1 % for three, the s^d law of the thesis's
section 4.2. It is raised to at least ``100 * 50 / max_samples`` %, so that
the pilot's 50 behavioural sets fit in ``max_samples`` (:data:`~dynia.settings.DEFAULT_MAX_SAMPLES`,
200 000): with five parameters 0.001 % would need five million samples for
the pilot alone; 0.025 % spans about a fifth of each range instead of a
tenth, and the reasons say so.

The number of samples
---------------------
A pilot :func:`dynia.run` at the proposed window and share with few samples
(enough for 50 behavioural sets, at least 500: ten batches of five for the
batch means) gives the Monte Carlo standard error of each parameter's IC
near its highest value, ``result.ic_se`` of ``ic_error=True`` (its honesty
is checked in ``benchmarks/honesty.py``). The band's limits are
quantiles of a behavioural set whose size grows with the samples, so the
error shrinks as ``1/sqrt(N)``; the proposal is the N that brings the
largest of them to ``ic_se_target`` (0.02), rounded up to two significant
digits, and at least enough for 50 behavioural sets, at most
``max_samples`` (a note then gives the error reached there).

Memory
------
The pilot's memory is estimated before it starts (:func:`run_memory`: the
moving window holds about four arrays of n_samples x (chunk + 2n) values,
plus the samples, plus the whole simulation for a model that does not
stream; within 10 % of the growth of the peak memory measured with 50 000
samples on the heater record and 400 000 on HYMOD, to which compiling the
engine on first use adds about 150 MB), and a pilot above ``max_memory`` (default: half the memory
available when suggest starts, :data:`MEMORY_SHARE`) is refused with a
:class:`~dynia.errors.SettingsError` saying what it would need. The
proposed run's estimate is reported too, with a note when it is above the
limit. The pilot shows its progress bar as :func:`dynia.run` does (``progress``).

The parameter ranges
--------------------
The model itself is fitted by least squares to the whole record within the
ranges (:func:`dynia.fit.fit_segments`, from the middle of the ranges and
two random starts, in the initial state of the analysis). An estimate on a
bound means the range excludes the best fit: the band of every window would
lean on that bound; the proposal says which range to widen, unless the
model refuses values beyond that bound (a negative time constant or dead
time: it is tried there, the others at their estimates): then the range
stays and the note says the record asks for a value the model excludes. A
parameter the record does not determine is named too.

Gaps in the output
------------------
A stretch without output (a logger that was off for ten days) holds no
window to analyse, yet a simulation must run through it step by step: on a
record sampled every 2 s a 10-day gap is 432 000 steps, a hundred times the
measured ones. The pilot and the least-squares fit therefore keep only the
last :data:`GAP_MEMORY` dominant time constants (at least one window) of
every longer gap, the stretch over which a first-order response to the
input still remembers its state; across the rest the state has forgotten
where it started (less than e^-10 of it remains). The reasons say how
many steps were left out. The analysis the suggestion proposes runs through
the whole record.

Examples
--------
>>> import numpy as np
>>> from dynia.models import FirstOrder
>>> u = np.repeat([0.0, 50.0, 20.0, 70.0], 600)
>>> y = FirstOrder().simulate([[0.6, 60.0]], u)[0]
>>> round(dominant_time_constant(u, y).time_constant, 3)
60.0
>>> window_half_width(parse_duration("1min"), dt=1.0, n_steps=u.size)
30
"""

import math
import os
import re
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import lfilter

from . import _checks
from .bounds import parameter_box
from .engine.windows import default_chunk_steps
from .errors import DataError, ModelError, SettingsError, SuggestionError
from .fit import fit_segments
from .io.frames import unpack
from .pipeline import KernelSimulated, compiled_simulation, run
from .progress import shows_progress
from .segments import mask_to_segments
from .serial import json_number
from .settings import (
    DEFAULT_MAX_SAMPLES,
    IC_BATCHES,
    MIN_BATCH_BEHAVIOURAL,
    AnalysisSettings,
    check_dt,
    check_x0,
    sample_count,
)
from .verdicts import noise_sigma

__all__ = [
    "Suggestion",
    "TimeScale",
    "suggest",
    "dominant_time_constant",
    "parse_duration",
    "window_half_width",
    "parse_size",
    "run_memory",
    "available_memory",
    "IC_SE_TARGET",
    "MEMORY_SHARE",
    "MIN_EXPLAINED",
    "NOISE_MARGIN",
]

# The Monte Carlo standard error of the IC the proposed number of samples aims at.
IC_SE_TARGET = 0.02
# Without a max_memory, a pilot may take this share of the memory available when suggest starts.
MEMORY_SHARE = 0.5
# Below this share of the output's variance explained (R^2) the first-order fit sizes no window.
MIN_EXPLAINED = 0.5
#: A parameter a tenth off must move a window's mean by this many standard errors of the noise (The window).
NOISE_MARGIN = 2.0
#: The pilot and the fit keep this many dominant time constants of a gap without output (see Gaps in the output).
GAP_MEMORY = 10

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
_DURATION = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*([a-zA-Z]*)\s*$")
_BYTES = {"": 1, "b": 1, "k": 1e3, "kb": 1e3, "m": 1e6, "mb": 1e6, "g": 1e9, "gb": 1e9, "t": 1e12, "tb": 1e12}
_BYTES.update({"kib": 2**10, "mib": 2**20, "gib": 2**30, "tib": 2**40})
# run_memory: live arrays of n_samples x (chunk + 2n) float64 in the moving window (the errors pulled
# from the simulation, their padded and transposed copies, the chunks in flight), measured with 1 and 2
# workers on the heater (n = 85) and HYMOD (n = 3) pilots; and float64 values kept per sample besides
# its parameters (states, costs, ranks).
_WINDOW_ARRAYS = 4
_PER_SAMPLE_VALUES = 16

# Trial time constants of the first-order fit: this many, log-spaced from dt to the record's length.
_GRID_POINTS = 60
# A share 1/_RANGE_SHARE_INVERSE of each range is the aim of the proposed percentage (module docs);
# an integer, so that 100 / 10**d is the float nearest the intended 1 % or 0.1 %.
_RANGE_SHARE_INVERSE = 10
_MAX_PERCENTAGE = 10.0
# The pilot holds this many behavioural sets (and at least _PILOT_MIN samples): IC_BATCHES batches of
# MIN_BATCH_BEHAVIOURAL for its Monte Carlo error. The proposal keeps at least _MIN_BEHAVIOURAL.
_PILOT_BEHAVIOURAL = IC_BATCHES * MIN_BATCH_BEHAVIOURAL
_PILOT_MIN = 500
_MIN_BEHAVIOURAL = 50
# The IC standard error is pooled over the steps whose pilot IC lies within this of the parameter's highest.
_PEAK_MARGIN = 0.05
# An input change counts when it exceeds this share of the input's range; the input is step-like when
# fewer than _STEP_LIKE of its steps change.
_CHANGE_SHARE = 0.01
_STEP_LIKE = 0.1
# A bound is probed this share of its range beyond it (_refusal_beyond).
_BEYOND = 0.05
# No window is proposed when one value holds more than this share of the output's squared deviations.
_ONE_VALUE_SHARE = 0.5
# The other initial state is noted when its residual variance is below this share of the chosen one's.
_BETTER_RESIDUAL = 0.5


def parse_duration(text, name="window"):
    """Seconds in a duration such as ``"60s"``, ``"2min"``, ``"1.5h"``, ``"1d"`` or ``"90"`` (seconds).

    Raises :class:`~dynia.errors.SettingsError` naming ``name`` for anything
    else, or a duration that is not positive and finite.

    >>> parse_duration("2min"), parse_duration("1h"), parse_duration("90")
    (120.0, 3600.0, 90.0)
    """
    match = _DURATION.match(str(text))
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


def parse_size(text, name="max_memory"):
    """Bytes in a size such as ``"4GB"``, ``"512MiB"``, ``"2e9"`` or ``2e9`` (a bare number is bytes).

    kB, MB, GB, TB (and k, M, G, T) are powers of 1000; KiB, MiB, GiB, TiB
    powers of 1024. Raises :class:`~dynia.errors.SettingsError` naming
    ``name`` for anything else, or a size that is not positive and finite.

    >>> parse_size("4GB"), parse_size("1.5 MiB"), parse_size(1000)
    (4000000000.0, 1572864.0, 1000.0)
    """
    match = _DURATION.match(str(text))
    unit = match.group(2).lower() if match else None
    if match is None or unit not in _BYTES:
        raise SettingsError(
            f"{name} must be a size such as 4GB, 512MB or 2GiB (a bare number is bytes); got {text!r}", name
        )
    size = float(match.group(1)) * _BYTES[unit]
    if not (math.isfinite(size) and size > 0):
        raise SettingsError(f"{name} must be a positive, finite size; got {text!r}", name)
    return size


def run_memory(model, n_samples, n_steps, n, *, n_params=None, bins=40, ic_error=True):
    """Bytes a uniform :func:`dynia.run` of ``n_samples`` over ``n_steps`` adds, about (module docs).

    The moving window holds a few arrays of ``n_samples x (chunk + 2n)``
    float64 values, the chunk of :func:`dynia.engine.windows.default_chunk_steps`;
    each sample keeps its parameters and a few values more; a model that
    does not stream (``model.streams`` False) holds its whole simulation;
    the result holds IC, limits and gradient (and their errors) per step.

    >>> from dynia.models import FirstOrder
    >>> round(run_memory(FirstOrder(), 5000, 7200, 85) / 1e6)
    142
    """
    n_params = len(model.names) if n_params is None else n_params
    width = default_chunk_steps(n_samples, 2 * n) + 2 * n
    per_sample = _WINDOW_ARRAYS * width + n_params + _PER_SAMPLE_VALUES
    if not getattr(model, "streams", True):
        per_sample += n_steps
    per_step = n_params * (bins + 3 + (3 if ic_error else 0))
    return 8.0 * (n_samples * per_sample + n_steps * per_step)


def available_memory():
    """Bytes of memory available to a new allocation now (Linux's MemAvailable), or None where unknown."""
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, OSError, ValueError):
        return None


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


@dataclass(frozen=True)
class Suggestion:
    """Settings proposed by :func:`suggest`, and why.

    Attributes
    ----------
    n : int
        Half window; the window holds 2n+1 steps.
    window : float
        The window's duration, (2n+1) dt.
    percentage : float
        Behavioural share in percent.
    n_samples : int
        Monte Carlo samples.
    time_scale : TimeScale
        The first-order fit that set the window.
    pilot : dict
        ``n_samples``, ``seed`` and per parameter ``max_ic`` and ``ic_se``
        of the pilot run.
    fit : dict
        Per parameter the least-squares ``estimate``, its ``std_error``
        (robust, :attr:`dynia.fit.FitResult.std_errors_hac`), its ``range``,
        and ``at_bound`` / ``identifiable``.
    reasons : list of str
        Why each setting, one sentence each.
    notes : list of str
        What the user should look at: ranges that exclude the fit, input
        changes closer than a window, a time scale the record cannot resolve,
        a share or a sample count held by ``max_samples``.
    dt : float
    memory : dict
        Estimated bytes of the ``pilot`` and of the ``proposed`` run
        (:func:`run_memory`), and the ``limit`` the pilot was held to.
    given : tuple of str
        The settings given to :func:`suggest` and kept as given ("n",
        "percentage", "n_samples"): :meth:`arguments` leaves them out.
    """

    n: int
    window: float
    percentage: float
    n_samples: int
    time_scale: TimeScale
    pilot: dict
    fit: dict
    reasons: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    dt: float = 1.0
    memory: dict = field(default_factory=dict)
    given: tuple = ()

    def arguments(self):
        """The ``dynia analyse`` options of the settings this suggestion proposes (not those given), as strings."""
        options = (("n", "--n", str(self.n)), ("percentage", "--percentage", f"{self.percentage:g}"))
        options += (("n_samples", "--samples", str(self.n_samples)),)
        return [word for name, option, value in options if name not in self.given for word in (option, value)]

    def to_dict(self):
        """JSON-ready: the settings, the reasons and the evidence."""
        scale = self.time_scale
        return dict(
            settings=dict(n=self.n, window=self.window, percentage=self.percentage, n_samples=self.n_samples),
            arguments=self.arguments(),
            given=list(self.given),
            time_constant=json_number(scale.time_constant),
            first_order_fit=dict(
                time_constant=json_number(scale.time_constant),
                gains=[json_number(value) for value in scale.gains],
                level=json_number(scale.level),
                rmse=json_number(scale.rmse),
                explained=json_number(scale.explained),
                edge=scale.edge,
                x0=scale.x0,
            ),
            pilot=_json_tree(self.pilot),
            fit=_json_tree(self.fit),
            reasons=list(self.reasons),
            notes=list(self.notes),
            dt=self.dt,
            memory=_json_tree(self.memory),
        )

    def text(self):
        """Plain text for a terminal: the options, then why, then what to look at."""
        given = {"n": f"--n {self.n}", "percentage": f"--percentage {self.percentage:g}"}
        given["n_samples"] = f"--samples {self.n_samples}"
        kept = [given[name] for name in self.given]
        lines = [
            "suggested settings for dynia analyse: "
            + (" ".join(self.arguments()) or "none")
            + (f" (kept as given: {', '.join(kept)})" if kept else ""),
            f"  (window {self.window:g} s = 2n+1 = {2 * self.n + 1} steps of {self.dt:g} s)",
            "why:",
            *(f"  - {reason}" for reason in self.reasons),
        ]
        if self.notes:
            lines += ["check:", *(f"  - {note}" for note in self.notes)]
        return "\n".join(lines)


def suggest(
    u,
    y,
    model,
    bounds,
    *,
    dt=None,
    x0="zero",
    n=None,
    percentage=None,
    n_samples=None,
    settings=None,
    ic_se_target=IC_SE_TARGET,
    max_samples=DEFAULT_MAX_SAMPLES,
    max_memory=None,
    progress="auto",
    rng=None,
):
    """Propose a window, a behavioural share and a number of samples for this record and model.

    The reasoning is in the module documentation; every number it rests on
    is in the returned :class:`Suggestion`.

    Parameters
    ----------
    u, y : array_like, or pandas Series / DataFrame
        Input (n_steps,) or (n_steps, n_inputs) and output (n_steps,), as
        :func:`dynia.run` takes them (deviation variables when the analysis
        uses offsets). NaN in ``y`` marks a missing value. Two pandas
        objects must share one index; a time index must be uniformly spaced
        and gives dt, so that the window and the time constant are in
        seconds (:func:`dynia.io.frames.unpack`).
    model : dynia.models.Model
    bounds : mapping of str to (low, high)
        The ranges the analysis would sample.
    dt : float, optional
        Sample time in seconds; default the spacing of a time index, else
        1.0. Given with a time index, it must agree with its spacing.
    x0 : {"zero", "steady"}, default "zero"
        The analysis's initial state, used by the time-scale fit, the pilot
        and the least-squares fit.
    n, percentage, n_samples : optional
        The half window, the behavioural share or the number of samples of
        the analysis, fixed: kept as given, the rest proposed around them,
        and the reasons say what the record would have asked for. With
        ``n`` given, a record whose first-order fit sizes no window gets a
        proposal all the same.
    settings : dynia.settings.AnalysisSettings, optional
        The analysis's other settings (flavour, bins, conf_level, sampler,
        min_points, dtype, ...), which the pilot runs with; its ``n``,
        ``percentage``, ``n_samples``, ``x0`` and ``dt`` are not read.
    ic_se_target : float, default 0.02
        The Monte Carlo standard error of the IC the samples should reach.
    max_samples : int, default 200000
        The most samples of the pilot and of the proposal; the share is
        raised so that the pilot's behavioural sets fit in it.
    max_memory : float, optional
        Bytes the pilot may take (:func:`parse_size` reads "4GB");
        default: :data:`MEMORY_SHARE` of the memory available now.
    progress : bool or "auto", default "auto"
        Show the pilot's progress bar (tqdm, on stderr), as :func:`dynia.run`.
    rng : numpy.random.Generator or int, optional
        Seeds of the pilot runs and of the fit's extra starts.

    Returns
    -------
    Suggestion

    Raises
    ------
    dynia.errors.SuggestionError
        When a first-order fit explains less than :data:`MIN_EXPLAINED` of
        the output's variance: the record shows no time scale to size a
        window by.
    dynia.errors.SettingsError
        When the pilot would need more memory than ``max_memory``, or ``dt``
        disagrees with the spacing of a time index.
    dynia.errors.DataError
        pandas ``u`` and ``y`` on different indexes, or a time index that is
        not uniformly spaced (a gap of missing rows): their values are never
        paired by position.
    """
    # pandas in, as dynia.run takes it: aligned on one index, dt from its time.
    u, y, dt, _ = unpack(u, y, dt)
    dt, x0 = check_dt(1.0 if dt is None else dt), check_x0(x0)
    u, y = _checks.record(u, y, n_inputs=model.n_inputs)
    names, box = parameter_box(bounds, model.names, repr(model))
    bounds = {name: (float(low), float(high)) for name, (low, high) in zip(names, box)}
    target = _checks.open_interval(ic_se_target, "ic_se_target", 0.0, 1.0)
    max_samples = sample_count(max_samples, "max_samples", minimum=_PILOT_MIN)
    limit, limit_source = _memory_limit(max_memory)
    rng = _checks.generator(rng)
    progress = shows_progress(progress)

    given = {"n": n, "percentage": percentage, "n_samples": n_samples}
    given = {name: value for name, value in given.items() if value is not None}
    if "n" in given:
        n = AnalysisSettings(n=n).n  # checked as the analysis checks it
        if 2 * n + 1 > y.size:
            raise SettingsError(f"n {n}: the window 2n+1 = {2 * n + 1} is longer than the record ({y.size} steps)", "n")
    scale, n, reasons, notes = _window(u, y, dt, x0, n)
    percentage = _share(len(names), max_samples, reasons, notes, given.get("percentage"))
    base = AnalysisSettings() if settings is None else settings
    if base.flavour == "mcat":
        # The pilot needs the IC's Monte Carlo error, which MCAT's likelihood (carried from window to window) has not.
        base = base.replace(flavour="thesis")
        notes.append(
            "the pilot ran the thesis flavour, not mcat, which has no IC standard error yet: the samples proposed "
            "are those that bring the thesis flavour's to the target"
        )
    pilot_settings = base.replace(
        n_samples=min(max_samples, max(_PILOT_MIN, math.ceil(_PILOT_BEHAVIOURAL / (percentage / 100)))),
        n=n,
        percentage=percentage,
        x0=x0,
        dt=dt,
        ic_error=True,
        target_se=None,
        max_samples=None,
        store=None,
    )
    # A time scale the record does not show (a window given) is no memory of a gap: the window stands in for it.
    memory_steps = scale.time_constant / dt if scale.explained >= MIN_EXPLAINED else 2 * n + 1
    short_u, short_y = _shorten_gaps(u, y, max(math.ceil(GAP_MEMORY * memory_steps), 2 * n + 1), reasons)
    memory = _pilot_memory(model, pilot_settings, short_y.size, limit, limit_source)
    pilot = _pilot(short_u, short_y, model, bounds, pilot_settings, progress=progress, rng=rng)
    n_samples = _sample_count(pilot, target, max_samples, percentage, reasons, notes, given.get("n_samples"))
    memory["proposed"] = run_memory(model, n_samples, y.size, n)
    if limit is not None and memory["proposed"] > limit:
        notes.append(
            f"the proposed run would need about {_size(memory['proposed'])}, more than {_size(limit)} "
            f"({limit_source}): give fewer samples"
        )
    for name, entry in pilot["parameters"].items():
        if entry["max_ic"] is not None and entry["max_ic"] < 0.5:
            notes.append(
                f"{name}: the pilot's highest IC is {entry['max_ic']:.2f}; more samples sharpen the IC, they do not "
                "raise it: this record may hold little information on it"
            )
    fit = _ranges(short_u, short_y, model, bounds, dt, x0, rng, reasons, notes)
    return Suggestion(
        n=n,
        window=(2 * n + 1) * dt,
        percentage=percentage,
        n_samples=int(n_samples),
        time_scale=scale,
        pilot=pilot,
        fit=fit,
        reasons=reasons,
        notes=notes,
        dt=dt,
        memory=memory,
        given=tuple(given),
    )


def _window(u, y, dt, x0, given=None):
    """The half window n: the time scale, n, and their reasons and notes.

    n is the longer of one dominant time constant and what beats the noise (module docs), or ``given`` as given.
    Raises :class:`~dynia.errors.SuggestionError` when the record shows no time scale to size a window by and
    none is given.
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
    points = (NOISE_MARGIN * _RANGE_SHARE_INVERSE * sigma / size) ** 2 if size > 0 else math.inf
    by_noise = max(math.ceil((points - 1) / 2), 0) if math.isfinite(points) else y.size
    wanted = max(by_tau, by_noise)
    gains = ", ".join(f"{gain:.3g}" for gain in scale.gains)
    noise = (
        f"the noise (SD {sigma:.3g}, from the output's differences) against the response's size {size:.3g} (the "
        f"fitted response's SD) asks for m >= ({NOISE_MARGIN:g} x {_RANGE_SHARE_INVERSE} x {sigma:.3g} / "
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


def _shorten_gaps(u, y, keep, reasons):
    """``u`` and ``y`` with every run of missing output longer than ``keep`` steps cut to its last ``keep``.

    What the pilot and the fit need of a gap is the state it leaves; see Gaps in the output. A reason is appended
    when steps were left out.
    """
    missing = np.isnan(y)
    drop = np.zeros(y.size, dtype=bool)
    gaps = 0
    for start, stop in mask_to_segments(missing):
        if stop - start > keep:
            # A gap that ends the record leaves no state to carry on: its first steps stay instead of its last.
            if stop == y.size:
                drop[start + keep : stop] = True
            else:
                drop[start : stop - keep] = True
            gaps += 1
    if not gaps:
        return u, y
    reasons.append(
        f"gaps: {gaps} stretch(es) without output, {int(drop.sum())} steps in all, left out of the pilot and the "
        f"least-squares fit but {keep} steps each (at least {GAP_MEMORY} time constants, across which the state is "
        "carried); the analysis runs through the whole record"
    )
    return u[~drop], y[~drop]


def _share(d, max_samples, reasons, notes, given=None):
    """The behavioural percentage for ``d`` parameters within ``max_samples``, or ``given``; its reason and notes
    appended."""
    if given is not None:
        proposed = _share(d, max_samples, [], [])
        reasons.append(
            f"percentage {given:g}, as given"
            + ("" if given == proposed else f"; with {d} parameter(s) suggest would propose {proposed:g} (module docs)")
        )
        return float(given)
    wanted_percentage = min(_MAX_PERCENTAGE, 100.0 / _RANGE_SHARE_INVERSE**d)
    percentage = max(wanted_percentage, _round_up_share(100.0 * _PILOT_BEHAVIOURAL / max_samples))
    if percentage > wanted_percentage:
        reasons.append(
            f"percentage {percentage:g}: with {d} parameters {wanted_percentage:g} % would span about a tenth of each "
            f"range, but its pilot alone would need {math.ceil(_PILOT_BEHAVIOURAL / (wanted_percentage / 100))} "
            f"samples, more than max_samples {max_samples}; {percentage:g} % is the least share whose "
            f"{_PILOT_BEHAVIOURAL} behavioural sets fit in it, and spans about "
            f"{100 * (percentage / 100) ** (1 / d):.0f} % of each range where a window pins them all"
        )
        notes.append(
            f"the behavioural share is held at {percentage:g} % by max_samples {max_samples} (a tenth of each range "
            f"would need {wanted_percentage:g} %): the bands can be wider than the share aims at; a larger "
            "max_samples allows a smaller share"
        )
    else:
        reasons.append(
            f"percentage {percentage:g}: the behavioural set is that share of the parameter box whatever the number "
            f"of samples, and with {d} parameter(s) {percentage:g} % spans about a tenth of each range where a "
            f"window pins them all, so their IC can reach about 0.9 (the default 10 % spans "
            f"{100 * 0.1 ** (1 / d):.0f} % of each)"
        )
    return percentage


def _pilot_memory(model, settings, n_steps, limit, limit_source):
    """``memory`` of the Suggestion with the pilot's estimate; an error when it exceeds ``limit`` bytes."""
    memory = dict(pilot=run_memory(model, settings.n_samples, n_steps, settings.n), limit=limit)
    if limit is not None and memory["pilot"] > limit:
        raise SettingsError(
            f"max_memory: the pilot run ({settings.n_samples} samples, window {settings.window_length} steps, "
            f"{n_steps} steps) would need about {_size(memory['pilot'])}, more than the limit of {_size(limit)} "
            f"({limit_source}); lower max_samples or raise max_memory",
            "max_memory",
        )
    return memory


def _sample_count(pilot, target, max_samples, percentage, reasons, notes, given=None):
    """Samples whose IC standard error reaches ``target``, from the pilot's, or ``given``; its reason and notes
    appended."""
    worst = max(pilot["parameters"], key=lambda name: pilot["parameters"][name]["ic_se"])
    worst_se = pilot["parameters"][worst]["ic_se"]
    if given is not None:
        proposed = _sample_count(pilot, target, max_samples, percentage, [], [])
        reached = worst_se * math.sqrt(pilot["n_samples"] / given)
        reasons.append(
            f"samples {given}, as given: a pilot with {pilot['n_samples']} samples gave an IC standard error of "
            f"{worst_se:.3f} for {worst} near its highest IC (result.ic_se), so {given} reach about {reached:.3f}"
            + ("" if given == proposed else f"; suggest would propose {proposed} for {target:g}")
        )
        return int(given)
    needed = pilot["n_samples"] * (worst_se / target) ** 2
    floor = math.ceil(_MIN_BEHAVIOURAL / (percentage / 100))
    n_samples = min(max(_round_up(needed), floor), max_samples)
    reasons.append(
        f"samples {n_samples}: a pilot with {pilot['n_samples']} samples gave an IC standard error of "
        f"{worst_se:.3f} for {worst} near its highest IC (result.ic_se); "
        f"it falls as 1/sqrt(N), so {pilot['n_samples']} x ({worst_se:.3f}/{target:g})^2 = {needed:.0f} reach "
        f"{target:g}"
        + (f" (at least {floor}, for {_MIN_BEHAVIOURAL} behavioural sets)" if floor > needed else "")
        + (f" (at most max_samples {max_samples})" if needed > max_samples else "")
    )
    if needed > max_samples:
        notes.append(
            f"{max_samples} samples (max_samples) bring the IC standard error of {worst} to about "
            f"{worst_se * math.sqrt(pilot['n_samples'] / max_samples):.3f}, not {target:g}"
        )
    return n_samples


def _ranges(u, y, model, bounds, dt, x0, rng, reasons, notes):
    """Least squares on the whole record, per parameter; its reason and the notes on the ranges appended."""
    # Through the compiled kernel where it simulates the model (the same outputs, bit for bit): the pilot compiled it.
    simulated = KernelSimulated(model) if compiled_simulation(model) else model
    fitted = fit_segments(u, y, simulated, [(0, y.size)], bounds=bounds, dt=dt, x0=x0, n_starts=3, rng=rng)
    fit = {}
    for name, (low, high) in bounds.items():
        estimate = fitted.parameters[name]
        at_bound = name in fitted.at_bound
        fit[name] = dict(
            estimate=estimate,
            std_error=fitted.std_errors_hac[name],
            range=[low, high],
            at_bound=at_bound,
            identifiable=fitted.identifiable[name],
        )
        if at_bound:
            notes.append(_at_bound(model, fitted, name, low, high))
        elif not fitted.identifiable[name]:
            notes.append(f"least squares on the whole record does not determine {name}: no window will pin it")
    reasons.append(
        "ranges: least squares on the whole record gives "
        + ", ".join(f"{name} = {entry['estimate']:.4g} +- {entry['std_error']:.2g}" for name, entry in fit.items())
        + (" (inside every range)" if not fitted.at_bound else "")
    )
    return fit


def _at_bound(model, fitted, name, low, high):
    """The note on an estimate of ``name`` on a bound of its range [low, high]: widen it, or keep it (the model's)."""
    estimate = fitted.parameters[name]
    side = "lower" if estimate - low <= high - estimate else "upper"
    bound = low if side == "lower" else high
    refusal = _refusal_beyond(model, fitted.parameters, name, bound, high - low, side)
    if refusal is None:
        return (
            f"the range [{low:g}, {high:g}] of {name} excludes the least-squares fit: its estimate lies on "
            f"the {side} bound {bound:g}; widen the range beyond it"
        )
    return (
        f"the least-squares estimate of {name} lies on the {side} bound {bound:g} of its range, the "
        f"{'least' if side == 'lower' else 'greatest'} value {type(model).__name__} accepts ({refusal}): "
        "keep the range; the record would fit a value the model excludes, so check the model and the "
        "alignment of input and output"
    )


def _refusal_beyond(model, estimates, name, bound, width, side):
    """Why ``model`` refuses ``name`` just beyond ``bound`` (the others at their estimates), or None if it accepts it.

    Models declare their admissible values by refusing the others (a negative time constant or dead time: a
    :class:`~dynia.errors.ModelError`); a range is never to be widened into them.
    """
    beyond = bound - _BEYOND * width if side == "lower" else bound + _BEYOND * width
    point = np.array([[beyond if other == name else estimates[other] for other in model.names]])
    try:
        with np.errstate(all="ignore"):
            output = model.simulate(point, np.zeros(3 if model.n_inputs == 1 else (3, model.n_inputs)))
    except ModelError as error:
        return str(error).split(";")[0]
    if not np.isfinite(output).all():
        return f"{name} = {beyond:g} gives a non-finite output"
    return None


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


def _memory_limit(max_memory):
    """The pilot's memory limit in bytes and where it comes from; (None, None) where nothing is known."""
    if max_memory is not None:
        return parse_size(max_memory, "max_memory"), "max_memory"
    available = available_memory()
    if available is None:
        return None, None
    return MEMORY_SHARE * available, f"{100 * MEMORY_SHARE:.0f} % of the {_size(available)} available; max_memory"


def _size(size):
    """Bytes for a person: "3.2 GB", "450 MB"."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if size >= scale:
            return f"{size / scale:.2g} {unit}"
    return f"{size:.0f} B"


def _pilot(u, y, model, bounds, settings, *, progress, rng):
    """IC standard error near each parameter's highest IC, from the ``ic_se`` of a pilot run with ``settings``."""
    seed = int(rng.integers(2**63))
    result = run(u, y, model, bounds, settings=settings, rng=seed, progress=progress)
    ic, variance = result.ic, result.ic_se**2
    parameters = {}
    for p, name in enumerate(bounds):
        if np.isnan(ic[p]).all():
            parameters[name] = dict(max_ic=None, ic_se=0.0)
            continue
        highest = float(np.nanmax(ic[p]))
        near = ic[p] >= highest - _PEAK_MARGIN
        parameters[name] = dict(max_ic=highest, ic_se=float(math.sqrt(np.nanmean(variance[p][near]))))
    return dict(n_samples=settings.n_samples, seed=seed, parameters=parameters)


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


def _round_up_share(value):
    """A percentage rounded up to two significant digits, so that 100 * 50 / 123456 reads 0.041."""
    magnitude = 10.0 ** (math.floor(math.log10(value)) - 1)
    return round(math.ceil(round(value / magnitude, 9)) * magnitude, 12)


def _round_up(value):
    """``value`` rounded up to two significant digits (at least 1)."""
    if value <= 1:
        return 1
    magnitude = 10 ** max(math.floor(math.log10(value)) - 1, 0)
    return int(math.ceil(value / magnitude) * magnitude)


def _json_tree(value):
    if isinstance(value, dict):
        return {key: _json_tree(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_tree(item) for item in value]
    if isinstance(value, float):
        return json_number(value)
    return value
