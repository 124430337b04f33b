"""Settings that let DYNIA see what a record holds, proposed from the record itself, with the reasons.

The defaults of :func:`dynia.run` (a window of 21 steps, the best 10 % of
2000 samples) suit the thesis's examples, whose time constants are a few
steps. On a heater step test sampled every second with a time constant of
three minutes they identify nothing, and nothing says why. :func:`suggest`
(``dynia suggest DATA.csv ...`` on the command line) proposes a window, a
behavioural share and a number of samples, and checks the parameter ranges,
by the reasoning below.

The window
----------
About one dominant time constant of the record (the time constant of a
first-order fit to the whole record), and long enough that a parameter a
tenth off moves a window's mean by more than the measurement noise hides:
:mod:`dynia.timescale` gives the reasoning, and why no window is proposed
(a :class:`~dynia.errors.SuggestionError`) for a record that shows no time
scale to size one by. Input changes closer together than one window are
reported.

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
The pilot's memory is estimated before it starts (:func:`~dynia.memory.run_memory`: the
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
"""

import math
from dataclasses import dataclass, field

import numpy as np

from . import _checks
from .bounds import parameter_box
from .errors import ModelError, SettingsError
from .fit import fit_segments
from .io.frames import unpack
from .memory import available_memory, parse_size, run_memory, size_text
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
from .timescale import MIN_EXPLAINED, RANGE_SHARE_INVERSE, TimeScale, proposed_window

__all__ = [
    "Suggestion",
    "suggest",
]

# The Monte Carlo standard error of the IC the proposed number of samples aims at.
IC_SE_TARGET = 0.02
# Without a max_memory, a pilot may take this share of the memory available when suggest starts.
MEMORY_SHARE = 0.5
#: The pilot and the fit keep this many dominant time constants of a gap without output (see Gaps in the output).
GAP_MEMORY = 10

# The proposed percentage never exceeds the default's.
_MAX_PERCENTAGE = 10.0
# The pilot holds this many behavioural sets (and at least _PILOT_MIN samples): IC_BATCHES batches of
# MIN_BATCH_BEHAVIOURAL for its Monte Carlo error. The proposal keeps at least _MIN_BEHAVIOURAL.
_PILOT_BEHAVIOURAL = IC_BATCHES * MIN_BATCH_BEHAVIOURAL
_PILOT_MIN = 500
_MIN_BEHAVIOURAL = 50
# The IC standard error is pooled over the steps whose pilot IC lies within this of the parameter's highest.
_PEAK_MARGIN = 0.05
# A bound is probed this share of its range beyond it (_refusal_beyond).
_BEYOND = 0.05


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
    time_scale : dynia.timescale.TimeScale
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
        (:func:`~dynia.memory.run_memory`), and the ``limit`` the pilot was held to.
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
        Bytes the pilot may take (:func:`~dynia.memory.parse_size` reads "4GB");
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
        When a first-order fit explains less than :data:`~dynia.timescale.MIN_EXPLAINED` of
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
    scale, n, reasons, notes = proposed_window(u, y, dt, x0, n)
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
            f"the proposed run would need about {size_text(memory['proposed'])}, more than {size_text(limit)} "
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
    wanted_percentage = min(_MAX_PERCENTAGE, 100.0 / RANGE_SHARE_INVERSE**d)
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
            f"{n_steps} steps) would need about {size_text(memory['pilot'])}, more than the limit of "
            f"{size_text(limit)} ({limit_source}); lower max_samples or raise max_memory",
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


def _memory_limit(max_memory):
    """The pilot's memory limit in bytes and where it comes from; (None, None) where nothing is known."""
    if max_memory is not None:
        return parse_size(max_memory, "max_memory"), "max_memory"
    available = available_memory()
    if available is None:
        return None, None
    return MEMORY_SHARE * available, f"{100 * MEMORY_SHARE:.0f} % of the {size_text(available)} available; max_memory"


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
