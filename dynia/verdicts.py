"""Verdicts: what each parameter's highest information content is worth.

A DYNIA result reports, per parameter, one window: that of the highest
information content (IC) among the windows that can be evidence. A high IC
alone is not an estimate: :func:`assess` gives each parameter one of
:data:`VERDICTS` and the reasons for it.

Which window is reported
------------------------
A window is evidence for a parameter (:func:`evidence_windows`) when it is
informative about it (:meth:`dynia.result.DyniaResult.informative_windows`:
IC at least ``ic_threshold``, above the noise floor, behavioural set not tied
within noise) and holds all 2n+1 steps (not cut by the record's ends). The
reported window (:func:`reported_step`) is the one of highest IC among those;
when there is none, it is the one of highest IC of all, and the rules below
say why it is no estimate. A user who looked only at the
highest IC of the record would be shown the window of a noise ranking or of
the record's edge first, and on a record with one input step that is often
where the highest IC lies: the windows that see only the first seconds of
the response, or the truncated ones at the start.

``"identified"``
    The highest IC reaches ``ic_threshold`` and no rule below raises suspicion.
``"weak"``
    The highest IC stays below ``ic_threshold`` (reason ``"low_ic"``), or IC
    is missing everywhere (reason ``"no_ic"``). Any suspicion found is
    listed after it.
``"suspect"``
    The highest IC reaches ``ic_threshold`` but at least one rule applies:

    ``"band_at_bound"``
        The band at max IC lies within 1 % of the range of a sampling bound:
        the optimum may lie outside the range, or the model cannot fit there.
    ``"record_edge"``
        The window at max IC is truncated by the record's start or end (it
        holds fewer than 2n+1 steps): its IC is read off fewer points than
        any whole window's, and an artefact of the edge is likely. A whole
        window next to the edge is as good as any other (a record that
        starts just after an input step has its information there).
    ``"below_noise_floor"``
        The window at max IC lies below the noise floor of the analysis
        (``result.informative`` False, see :mod:`dynia.engine.noise`): the
        worst-fitting tenth of the sampled box fits no worse than the best
        beyond what measurement noise alone does, so the window does not
        tell parameter values apart at all. Results of :func:`dynia.run`
        and the other front-ends carry the floor; the engine computes it in
        the same pass.
    ``"noise_ranked"``
        The window at max IC tells parameter values apart, but its
        behavioural set ties within noise (``result.behavioural_spread`` at
        most ``result.behavioural_floor``): which sets are kept, and so the
        band, is decided by the noise realisation. Given only when the
        window is above the floor (below it, ``"below_noise_floor"`` says
        more).
    ``"noise_only"``
        The same question for a result without the floor (built by hand),
        when :func:`assess` is given the data and the model: the samples
        are simulated again and the window's median minus best MAE is
        compared with noise (see :func:`noise_only`).
    ``"screened"``
        The window at max IC is one the data-quality screening took from
        the evidence (:attr:`~dynia.result.DyniaResult.screened_windows`: a
        saturated or frozen reading in it, or a coarsely quantised output
        that hardly moves there); reported only because no window is
        evidence.
    ``"monte_carlo_error"``
        The result has the Monte Carlo standard error of IC (``ic_error``)
        and the max IC reaches ``ic_threshold`` by less than two of them:
        another sample of the same size could call the parameter weak.
    ``"isolated_evidence"``
        The reported window is evidence, but fewer windows than a quarter
        of a window's length (:func:`evidence_needed`) are: the high IC
        holds for one alignment of the window with the data and is gone
        when the window slides on, so nothing checks the band against
        anything. On a rainfall-runoff record a parameter was once called
        identified from one 11-day window whose band missed the truth.
    ``"windows_disagree"``
        The windows that identify the parameter do not agree with each
        other: DYNIA's model-structure warning (thesis 4.4), parameters
        whose identified values move from one period to another. The max-IC
        window is one of many; a band read there is an estimate only when
        the others would give a compatible one. See below.

Whether the windows agree
-------------------------
The windows compared are those informative about the parameter
(:func:`high_ic_windows`, the package's one rule; the summary counts them and
gives their span): windows below the noise floor or whose behavioural set
ties within noise (``noise_ranked``) have bands that rank noise, not
evidence. :func:`dynia.structure.band_disagreement`, the mechanism of the structure
warnings, groups them into stretches: runs joined across gaps shorter than
one window (2n+1 steps), whose windows share samples, and cut into
stretches of one window length, so that a record identifying the parameter
throughout still gives stretches of their own data. Each stretch's band is
the median of its windows' limits (one odd window does not move it). The
stretches disagree when the highest lower limit among them lies above the
lowest upper limit by more than the tolerance: one gradient bin (the CLD's
resolution), or two Monte Carlo standard errors of that difference
(``result.ci_se``) when larger. No single value then lies in both bands. The
reason names the two stretches, their times (dates for a dated record) and
bands. Correctly specified records with constant parameters (first-order
data with random level steps, white noise, thesis examples 1 and 2, in
several seeds and in wide and narrow ranges) leave overlaps of 20 to 70 %
of a band's width; a gain of 2 that turns 3 half way leaves a gap of five
bins. Noise that wanders slowly moves every window's band with it: before
they are compared, the bands are widened by
:func:`dynia.structure.noise_widening` half-widths (none for white noise).
A constant gain under weak excitation and AR(1) noise of lag-1
autocorrelation 0.98 drew this reason on 11 of 15 records without the
widening, on 1 of 20 with it.

The record's fit
----------------
The windows compare with each other only where two stretches of the record
are evidence; a model that approximates the process (a first order plus
dead time fitted to a higher-order lag, whose "dead time" is the apparent
one of the early response) or a parameter that moves under weak excitation
often leaves one such stretch, and nothing checks its band. The whole
record checks it: every front-end fits the model to the whole record by
least squares (:func:`dynia.fit.record_least_squares`, from the
record-best set of the noise floor), and where the model and a constant
parameter describe the record, that fit and every evidence band agree
within noise. A reported band (its window evidence) that excludes the fit
by more than the tolerance raises ``disagrees_with_record_fit``, naming
both. Only the reported band is compared: it is the estimate a user reads,
and under slowly wandering noise the other stretches' bands wander with it
(``windows_disagree`` widens them for that, see
:func:`dynia.structure.noise_widening`). The tolerance is two
standard errors of the difference: the fit's standard error from noise
alone (:func:`record_fit_noise_error`: its HAC standard error, scaled down
by the windows' noise level over the fit's RMSE where misfit inflates the
residuals, since another noise realisation would leave the misfit, and so
the compromise value, where it is), and the Monte Carlo error of the band's
limit (``result.ci_se``, or that of the behavioural set's order statistic
for values spread evenly over the band). A parameter the record does not
determine (infinite standard error) is not compared.

Measured on first-order records of 1 000 steps (T = 5, input levels held 50
steps, noise SD 0.2, 2 000 samples, n = 10; ``tests/test_record_fit.py``
builds the same records): a gain that moves from 2 to 3 half way under
weak excitation (levels in [0, 2]) is identified on 1 of 10 seeds (3
before the rule), its band then within the fit's standard error of it; a
constant gain stays identified on 10 of 10 (white noise) and on 15 of 20
under AR(1) noise of lag-1 autocorrelation 0.98, the other 5 suspect
because their bands miss the record's fit (as they miss the truth); a
constant gain of strong excitation (levels in [5, 30], AR(1) 0.98 noise of
SD 0.5) on 20 of 20. Every identified band of these records holds the
record's fit.

Each reason is ``{"code": ..., "text": ...}``; branch on the code, the text
is for people.
"""

import math

import numpy as np

from .errors import ModelError, SettingsError
from .settings import IC_THRESHOLD
from .structure import band_disagreement, noise_widening

__all__ = [
    "VERDICTS",
    "assess",
    "evidence_needed",
    "evidence_windows",
    "high_ic_windows",
    "noise_only",
    "noise_sigma",
    "record_fit_conflict",
    "record_fit_noise_error",
    "reported_step",
    "no_evidence_reasons",
]

VERDICTS = ("identified", "weak", "suspect")

# A band edge this close to a bound, as a fraction of the range, touches it.
BOUND_TOLERANCE = 0.01
# MAE spreads up to this many sampling standard deviations of a noise-only MAE count as noise.
NOISE_MULTIPLE = 3.0
# Simulated values per chunk when re-simulating for the noise rule (about 3x this many float64 in flight).
_MAX_VALUES = 2_000_000


def noise_sigma(y):
    """Robust standard deviation of the measurement noise of the record ``y``.

    The median absolute deviation of the first differences between measured
    neighbours, scaled by 1.4826 (normal consistency) and divided by sqrt(2)
    (a difference holds two noise draws). Steps and slow dynamics barely move
    a median, so the estimate follows the noise alone. NaN (missing) samples
    are skipped; with fewer than two measured neighbours the result is 0.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.r_[np.zeros(500), np.full(500, 70.0)] + np.random.default_rng(1).normal(0, 0.5, 1000)
    >>> round(noise_sigma(y), 1)
    0.5
    """
    diff = np.diff(np.asarray(y, dtype=float))
    diff = diff[np.isfinite(diff)]
    return float(1.4826 * np.median(np.abs(diff - np.median(diff))) / math.sqrt(2)) if diff.size else 0.0


def noise_only(y, sims, start, stop, *, sigma=None, multiple=NOISE_MULTIPLE):
    """Whether the window ``[start, stop)`` fits noise only, with the spread and threshold compared.

    Each parameter set's cost is its mean absolute error (MAE) over the
    window's m measured points (NaN in ``y`` are left out). Parameter sets
    whose outputs differ by less than the noise have MAEs that differ by
    about the sampling standard deviation of one MAE, ``sigma * sqrt(1 -
    2/pi) / sqrt(m)`` for normal noise. The window fits noise only when the
    population's spread, median MAE minus minimum MAE, is at most
    ``multiple`` times that: the better half of the parameter sets cannot be
    told apart from the best. Where every set gives the same output the
    spread is 0, so such a window always fits noise only.

    ``sims`` is (n_samples, >= stop); ``sigma`` defaults to
    :func:`noise_sigma` of ``y``. Returns ``(call, spread, threshold)``.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(1).normal(0, 0.5, 60)
    >>> noise_only(y, np.zeros((100, 60)), 20, 41)[0]
    True
    """
    y = np.asarray(y, dtype=float)
    sigma = noise_sigma(y) if sigma is None else float(sigma)
    measured = ~np.isnan(y[start:stop])
    if not measured.any():
        raise SettingsError(f"the window [{start}, {stop}) has no measured point; noise_only needs at least one")
    return _judge(_window_mae(y, np.asarray(sims, dtype=float), start, stop), int(measured.sum()), sigma, multiple)


def _window_mae(y, sims, start, stop):
    """MAE of every row of ``sims`` against ``y`` over the measured points of [start, stop)."""
    window = y[start:stop]
    measured = ~np.isnan(window)
    return np.abs(sims[:, start:stop][:, measured] - window[measured]).mean(axis=1)


def _judge(mae, m, sigma, multiple):
    spread = float(np.median(mae) - mae.min())
    threshold = multiple * sigma * math.sqrt(1 - 2 / math.pi) / math.sqrt(m)
    return spread <= threshold, spread, threshold


def assess(
    result, *, u=None, y=None, model=None, dt=None, x0=None, ic_threshold=IC_THRESHOLD, simulations=None, clock=None
):
    """Verdict and reasons for every parameter of a DYNIA result.

    Parameters
    ----------
    result : DyniaResult
        The analysis; its settings must hold the half window ``n``.
    u, y : array_like, shape (n_steps,), optional
        The input and output the analysis ran on (offsets already removed).
    model : dynia.models.Model, optional
        The model analysed. A result with its noise floor
        (``result.informative``) needs none of ``u``, ``y`` and ``model``:
        the ``"below_noise_floor"`` rule reads the floor, and nothing is
        simulated. For a result without it, ``u``, ``y`` and ``model``
        give the ``"noise_only"`` rule, which simulates the samples again;
        without them it is skipped.
    dt, x0 : optional
        Simulation settings; default ``result.settings.dt`` and
        ``result.settings.x0``, else 1 and "zero".
    ic_threshold : float in [0, 1], default :data:`dynia.settings.IC_THRESHOLD` (0.5)
        IC from which a window is informative
        (:meth:`~dynia.result.DyniaResult.informative_windows`); a highest
        IC below it makes a parameter ``"weak"``.
    simulations : ndarray (n_samples, n_steps), optional
        The model's output for ``result.samples``, when already at hand (a
        model that simulates the whole record at once); spares simulating
        again.
    clock : callable, optional
        ``clock(step)`` is the time of a step as the reasons' texts write
        it (a number, or a string such as an ISO timestamp); by default the
        result's ``timestamps`` when it has them, else ``result.time``.
        The command line passes the data file's own times.

    Returns
    -------
    dict
        ``{name: {"verdict": str, "reasons": [{"code": str, "text": str}, ...]}}``
        in ``result.names`` order.

    Examples
    --------
    >>> import numpy as np, dynia
    >>> u = np.r_[np.zeros(20), np.ones(100), np.zeros(80)]
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
    >>> res = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 5), "T": (0, 10)}, n=5, rng=1)
    >>> assess(res, u=u, y=y, model=dynia.models.FirstOrder())["K"]
    {'verdict': 'identified', 'reasons': []}
    """
    if (u is None, y is None, model is None).count(True) not in (0, 3):
        raise SettingsError("assess needs u, y and model together for the noise_only rule, or none of them")
    reported = {p: reported_step(result, p, ic_threshold) for p in range(len(result.names))}
    best = {p: step for p, step in reported.items() if step is not None}
    windows = {step: result.window_range(step) for step in set(best.values())}
    if model is not None:
        u, y = _checked_data(result, u, y, model)
    if result.informative is not None:
        noise = {step: _floor_reason(result, step) for step in windows}
    else:
        found = {} if model is None else _noise_windows(result, u, y, model, dt, x0, windows, simulations)
        noise = {step: ("noise_only", text) for step, text in found.items() if text}
    when = _clock(result, clock)
    verdicts = {}
    for p, name in enumerate(result.names):
        if p not in best:
            verdicts[name] = dict(verdict="weak", reasons=[_reason("no_ic", "no window had enough measured points")])
            continue
        step = best[p]
        reasons = _bound_reasons(result, p, step) + _edge_reasons(result, step, windows[step], when)
        reasons += _monte_carlo_reasons(result, p, step, ic_threshold)
        reasons += _screened_reasons(result, step, when)
        if noise.get(step):
            code, text = noise[step]
            reasons.append(_reason(code, f"the window at max IC (time {when(step)}) " + text))
        reasons += _isolation_reasons(result, p, step, ic_threshold)
        reasons += _agreement_reasons(result, p, ic_threshold, when)
        reasons += _record_fit_reasons(result, p, step, ic_threshold, when)
        ic = float(result.ic[p, step])
        if ic < ic_threshold:
            verdicts[name] = dict(
                verdict="weak", reasons=[_reason("low_ic", f"max IC {ic:.3g} is below {ic_threshold:g}")] + reasons
            )
        else:
            verdicts[name] = dict(verdict="suspect" if reasons else "identified", reasons=reasons)
    return verdicts


def _reason(code, text):
    return {"code": code, "text": text}


def evidence_windows(result, p, ic_threshold=IC_THRESHOLD):
    """Windows that are evidence for parameter ``p``, (n_steps,) bool: see "Which window is reported".

    The windows informative about it (:func:`high_ic_windows`) that are
    whole (:attr:`~dynia.result.DyniaResult.full_windows`): a truncated
    window may be informative, but its IC is read off fewer points than any
    whole window's and cannot be the estimate (reason ``record_edge``).
    """
    return high_ic_windows(result, p, ic_threshold) & result.full_windows


def evidence_needed(result):
    """Windows of evidence needed before a parameter can be called identified: a quarter of a window, at least 2.

    A band that holds while the window slides by a quarter of its length
    is a property of the data there, not of one alignment of the window
    with one event.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.result import DyniaResult
    >>> res = DyniaResult(names=("K",), samples=np.zeros((2, 1)), bounds=np.array([[0.0, 1.0]]),
    ...                   time=np.arange(50.0), ic=np.zeros((1, 50)), ci=np.zeros((1, 50, 2)),
    ...                   gradient=np.zeros((1, 1, 50)), bin_centres=np.zeros((1, 1)), settings=dict(n=10))
    >>> evidence_needed(res)
    6
    """
    before, after = result.window_halos
    return max(2, math.ceil((before + after + 1) / 4))


def _isolation_reasons(result, p, step, ic_threshold):
    """``isolated_evidence`` when the reported window is evidence but too few windows are."""
    evidence = evidence_windows(result, p, ic_threshold)
    if not evidence[step]:
        return []
    count = int(np.count_nonzero(evidence))
    needed = evidence_needed(result)
    if count >= needed:
        return []
    return [
        _reason(
            "isolated_evidence",
            f"only {count} window(s) can be evidence (IC >= {ic_threshold:g}, whole, above the noise floor, "
            f"behavioural set untied), fewer than {needed}, a quarter of a window: the band holds for one "
            "alignment of the window with the data, and nothing checks it",
        )
    ]


def reported_step(result, p, ic_threshold=IC_THRESHOLD):
    """The step whose window the verdict of parameter ``p`` judges and the summary reports; None without IC.

    The highest IC among the :func:`evidence_windows` when there are any,
    else the highest IC of all.

    Examples
    --------
    >>> import numpy as np, dynia
    >>> u = np.r_[np.zeros(20), np.ones(100), np.zeros(80)]
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
    >>> res = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 5), "T": (0, 10)}, n=5, rng=1)
    >>> step = reported_step(res, 0)
    >>> bool(evidence_windows(res, 0)[step]), bool(res.ic[0, step] >= 0.5)
    (True, True)
    """
    ic = np.asarray(result.ic[p], dtype=float)
    if np.isnan(ic).all():
        return None
    candidates = np.where(evidence_windows(result, p, ic_threshold), ic, np.nan)
    if not np.isnan(candidates).all():
        return int(np.nanargmax(candidates))
    return int(np.nanargmax(ic))


def no_evidence_reasons(result, p, step, ic_threshold=IC_THRESHOLD):
    """Why the window at ``step`` is no evidence for parameter ``p``: a list of codes, empty when it is evidence.

    ``"low_ic"`` (IC below ``ic_threshold`` or missing), ``"record_edge"``
    (truncated by the record's start or end), ``"below_noise_floor"``,
    ``"noise_ranked"`` (behavioural set tied within noise) and ``"screened"``
    (saturated, frozen or quantised readings, :attr:`~dynia.result.DyniaResult.screened_windows`):
    the codes of the verdict reasons that say the same of a reported window.

    Examples
    --------
    >>> import numpy as np
    >>> from dynia.result import DyniaResult
    >>> res = DyniaResult(names=("K",), samples=np.zeros((2, 1)), bounds=np.array([[0.0, 1.0]]),
    ...                   time=np.arange(9.0), ic=np.full((1, 9), 0.9), ci=np.zeros((1, 9, 2)),
    ...                   gradient=np.zeros((1, 1, 9)), bin_centres=np.zeros((1, 1)), settings=dict(n=2),
    ...                   informative=np.arange(9) != 4)
    >>> no_evidence_reasons(res, 0, 0), no_evidence_reasons(res, 0, 4), no_evidence_reasons(res, 0, 5)
    (['record_edge'], ['below_noise_floor'], [])
    """
    codes = []
    ic = float(result.ic[p, step])
    if not ic >= ic_threshold:
        codes.append("low_ic")
    if not result.full_windows[step]:
        codes.append("record_edge")
    if result.informative is not None and not result.informative[step]:
        codes.append("below_noise_floor")
    elif result.behavioural_spread is not None and result.behavioural_spread[step] <= result.behavioural_floor[step]:
        codes.append("noise_ranked")
    if result.screened_windows[step]:
        codes.append("screened")
    return codes


def high_ic_windows(result, p, ic_threshold=IC_THRESHOLD):
    """Windows informative about parameter ``p``, (n_steps,) bool: the windows that can identify it.

    :meth:`dynia.result.DyniaResult.informative_windows` of ``p`` (IC at
    least ``ic_threshold``, above the noise floor, behavioural set not tied
    within noise; the IC test alone for a result without the floor).
    """
    return result.informative_windows(ic_threshold, result.names[p])[0]


def _clock(result, clock):
    """``when(step)``: the time of a step as the reasons write it."""

    # A daily record (every date a midnight) names days, not midnights.
    daily = result.timestamps is not None and not (result.timestamps.view(np.int64) % (86_400 * 10**9)).any()

    def when(step):
        if clock is not None:
            value = clock(step)
        elif result.timestamps is not None:
            value = str(np.datetime_as_string(result.timestamps[step], unit="D" if daily else "s"))
        else:
            value = result.time[step]
        return value if isinstance(value, str) else f"{float(value):.6g}"

    return when


def _agreement_reasons(result, p, ic_threshold, when):
    """``windows_disagree`` when the stretches of windows that identify parameter ``p`` rule each other out."""
    found = band_disagreement(result, p, high_ic_windows(result, p, ic_threshold))
    if found is None:
        return []

    def stretch(position):
        steps = found.stretches[position]
        lower, upper = found.bands[position]
        return f"[{lower:.4g}, {upper:.4g}] from time {when(steps[0])} to {when(steps[-1])}"

    first, last = sorted((found.below, found.above))

    return [
        _reason(
            "windows_disagree",
            f"the windows with IC >= {ic_threshold:g} disagree: the median band {stretch(first)} and "
            f"{stretch(last)} are {found.gap:.3g} apart (tolerance {found.tolerance:.3g}), no value lies "
            f"in both ({len(found.stretches)} stretches compared); the parameter moves between periods or the "
            "model structure is wrong (thesis 4.4)",
        )
    ]


def record_fit_conflict(result, p, ic_threshold=IC_THRESHOLD):
    """How far the reported band of parameter ``p`` excludes the record's least-squares fit: see "The record's fit".

    Returns ``(gap, tolerance)`` when the band at the reported window
    (:func:`reported_step`), which is evidence, excludes
    ``result.run.record_fit`` by more than the tolerance; None when it holds
    it within the tolerance, when the window is no evidence (other reasons
    say so) or when the result has no record fit with standard errors or
    the record does not determine the parameter.
    """
    error = record_fit_noise_error(result, p)
    step = reported_step(result, p, ic_threshold)
    if error is None or step is None or not evidence_windows(result, p, ic_threshold)[step]:
        return None
    value = result.run.record_fit[p]
    lower, upper = (float(limit) for limit in result.ci[p, step])
    gap = max(lower - value, value - upper)
    tolerance = 2 * math.hypot(error, _limit_error(result, p, step, lower, upper))
    return (gap, tolerance) if gap > tolerance else None


def record_fit_noise_error(result, p):
    """The standard error of the record fit of parameter ``p`` that noise alone leaves; None without one.

    ``result.run.record_fit_se`` (HAC) times ``noise_sigma / record_fit_rmse``
    where the record fit's residuals exceed the noise the windows' best fits
    show: what they hold beyond it is the model's misfit, a property of the
    record that another noise realisation would leave as it is, so it does
    not make the fit's value uncertain (see "The record's fit").
    """
    run = result.run
    if run.record_fit is None or run.record_fit_se is None:
        return None
    value, error = run.record_fit[p], run.record_fit_se[p]
    if not (math.isfinite(value) and math.isfinite(error)):
        return None
    sigma, rmse = run.noise_sigma, run.record_fit_rmse
    if sigma is not None and rmse is not None and math.isfinite(sigma) and 0 < sigma < rmse:
        error *= sigma / rmse
    return error


def _limit_error(result, p, step, lower, upper):
    """Monte Carlo standard error of a limit of the band ``[lower, upper]`` of parameter ``p`` at ``step``.

    ``result.ci_se`` when the run estimated it (the larger of the two
    limits'); else that of an order statistic of the
    behavioural set, its ``(1 - conf_level)/2`` quantile, for values spread
    evenly over the band: ``sqrt(q (1 - q) / B) (upper - lower) / (1 - 2 q)``
    with B behavioural sets.
    """
    if result.ci_se is not None:
        return float(np.nanmax(result.ci_se[p, step]))
    settings = result.settings
    behavioural = result.run.n_behavioural or settings.n_behavioural
    tail = (1 - settings.conf_level / 100) / 2
    return math.sqrt(tail * (1 - tail) / max(behavioural, 1)) * (upper - lower) / (1 - 2 * tail)


def _record_fit_reasons(result, p, step, ic_threshold, when):
    """``disagrees_with_record_fit`` when the reported band of parameter ``p`` excludes the record's fit."""
    conflict = record_fit_conflict(result, p, ic_threshold)
    if conflict is None:
        return []
    gap, tolerance = conflict
    value, error = result.run.record_fit[p], result.run.record_fit_se[p]
    lower, upper = result.ci[p, step]
    return [
        _reason(
            "disagrees_with_record_fit",
            f"the band [{lower:.4g}, {upper:.4g}] at time {when(step)} excludes the whole record's least-squares fit "
            f"{value:.4g} +- {error:.2g} by {gap:.3g} (tolerance {tolerance:.3g}): the model only approximates the "
            "process, so that its parameters move with the part of the record it is fitted to, or the parameter "
            f"itself moves over the record (thesis 4.4){_slow_noise(result)}",
        )
    ]


def _slow_noise(result):
    """The third cause a ``disagrees_with_record_fit`` text names where the noise is slow, else ''."""
    widening = noise_widening(result)
    if not widening:
        return ""
    return (
        f", or a slow disturbance moves the window's estimate (a window of the noise counts {(widening + 1) ** 2:.3g} "
        "times fewer independent points: longer windows average it out)"
    )


def _screened_reasons(result, step, when):
    """``screened`` when the window at max IC is one the data-quality screening took from the evidence."""
    if not result.screened_windows[step]:
        return []
    kinds = sorted({kind for kind, *_ in result.run.screened})
    return [
        _reason(
            "screened",
            f"the window at max IC (time {when(step)}) is screened out of the evidence: it holds "
            f"{' or '.join(_SCREENED[kind] for kind in kinds)} readings (dynia.quality; the record has no other "
            "window that can be evidence)",
        )
    ]


# How a screened reason names what the screening found (the kinds of dynia.quality.screen).
_SCREENED = {"saturated": "saturated", "stuck": "frozen", "quantised": "too coarsely quantised"}


def _monte_carlo_reasons(result, p, step, ic_threshold):
    """``monte_carlo_error`` when the max IC reaches ``ic_threshold`` but not by two of its standard errors."""
    if result.ic_se is None:
        return []
    ic, se = float(result.ic[p, step]), float(result.ic_se[p, step])
    if not ic >= ic_threshold > ic - 2 * se:
        return []
    return [
        _reason(
            "monte_carlo_error",
            f"max IC {ic:.3g} +- {se:.2g} (one standard error) is within two standard errors of {ic_threshold:g}: "
            "another Monte Carlo sample of this size could call it weak; raise the samples (or target_se)",
        )
    ]


def _bound_reasons(result, p, step):
    (low, high), (lower, upper) = result.bounds[p], result.ci[p, step]
    tolerance = BOUND_TOLERANCE * (high - low)
    return [
        _reason("band_at_bound", f"the band [{lower:.4g}, {upper:.4g}] at max IC touches the {side} bound {bound:.4g}")
        for touches, side, bound in (
            (lower - low <= tolerance, "lower", low),
            (high - upper <= tolerance, "upper", high),
        )
        if touches
    ]


def _edge_reasons(result, step, window, when):
    before, after = result.window_halos
    length = before + after + 1
    if window[1] - window[0] >= length:
        return []
    edge = "start" if step < before else "end"
    return [
        _reason(
            "record_edge",
            f"max IC at time {when(step)} is in a window truncated by the record's {edge}: it holds "
            f"{window[1] - window[0]} of {length} steps",
        )
    ]


def _floor_reason(result, step):
    """``(code, text)`` of the noise floor's reason for the window at ``step``, or None when neither applies."""
    sigma = _or_nan(result.run.noise_sigma)
    if not result.informative[step]:
        discrimination, floor = float(result.discrimination[step]), float(result.noise_floor[step])
        if np.isnan(floor):
            return "below_noise_floor", (
                f"has too few measured points to tell parameter sets from noise (discrimination {discrimination:.3g})"
            )
        multiple = _or_nan(result.run.noise_multiple)
        quantile = _or_nan(result.run.noise_floor_quantile)
        return "below_noise_floor", (
            f"is below the noise floor: the MAE at population quantile {quantile:g} exceeds the best by "
            f"{discrimination:.3g}, at most {floor:.3g}, {multiple:.3g} standard deviations of the MAE of noise "
            f"sigma {sigma:.3g} (estimated from the best fits)"
        )
    if result.behavioural_spread is None:
        return None
    spread, floor = float(result.behavioural_spread[step]), float(result.behavioural_floor[step])
    if not spread <= floor:  # NaN: no floor to compare with
        return None
    multiple = _or_nan(result.run.behavioural_multiple)
    return "noise_ranked", (
        f"has its behavioural set tied within noise: its MAE spread {spread:.3g} is at most {floor:.3g}, "
        f"{multiple:.3g} standard deviations of the MAE of noise sigma {sigma:.3g}; the band is a ranking of noise"
    )


def _or_nan(value):
    """A value of ``result.run``, NaN where the record has none (a result built without the noise floor's values)."""
    return math.nan if value is None else value


def _checked_data(result, u, y, model):
    """``u`` and ``y`` as arrays, checked against the result's steps and ``model`` against its parameters."""
    u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
    if y.shape != result.time.shape or u.shape[:1] != result.time.shape:
        raise SettingsError(f"u and y must have the result's {result.time.size} steps; got {u.shape} and {y.shape}")
    if sorted(model.names) != sorted(result.names):
        raise ModelError(f"model parameters {list(model.names)} do not match the result's {list(result.names)}")
    return u, y


def _noise_windows(result, u, y, model, dt, x0, windows, simulations):
    """Text of the noise_only reason of each window that fits noise only, else None.

    The samples are simulated once, streamed in time chunks of about
    ``_MAX_VALUES`` values, up to the end of the latest window; only the
    windows' columns are kept.
    """
    params = result.samples[:, [result.names.index(name) for name in model.names]]
    options = dict(
        dt=(1.0 if result.settings is None else result.settings.dt) if dt is None else dt,
        x0=("zero" if result.settings is None else result.settings.x0) if x0 is None else x0,
    )
    points = {step: int((~np.isnan(y[start:stop])).sum()) for step, (start, stop) in windows.items()}
    windows = {step: window for step, window in windows.items() if points[step]}
    if not windows:
        return {}
    end = max(stop for _, stop in windows.values())
    # Only the windows' columns are kept: the simulation streams through the
    # record in chunks, so memory is samples x chunk, not samples x record.
    needed = np.zeros(end, dtype=bool)
    for start, stop in windows.values():
        needed[start:stop] = True
    position = np.cumsum(needed) - 1  # column of step k among the kept ones
    kept = np.empty((params.shape[0], int(needed.sum())))
    at = 0
    if simulations is not None:
        chunks = [np.asarray(simulations)[:, :end]]
    else:
        chunks = model.simulate_chunks(params, u[:end], chunk_steps=max(1, _MAX_VALUES // params.shape[0]), **options)
    for chunk in chunks:
        inside = needed[at : at + chunk.shape[1]]
        kept[:, position[at : at + chunk.shape[1]][inside]] = chunk[:, inside]
        at += chunk.shape[1]
    # A window's steps are all kept, so its columns are one contiguous block.
    mae = {
        step: [_window_mae(y[start:stop], kept[:, position[start] : position[stop - 1] + 1], 0, stop - start)]
        for step, (start, stop) in windows.items()
    }
    sigma = noise_sigma(y)
    texts = {}
    for step in windows:
        quiet, spread, threshold = _judge(np.concatenate(mae[step]), points[step], sigma, NOISE_MULTIPLE)
        texts[step] = (
            f"fits noise only: its MAE spread {spread:.3g} is at most {threshold:.3g}, {NOISE_MULTIPLE:g} "
            f"standard deviations of the MAE of {points[step]} points of noise sigma {sigma:.3g}"
            if quiet
            else None
        )
    return texts
