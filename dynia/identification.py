"""Re-identify a model from selected data: DYNIA segments, a baseline's intervals or the whole record.

The thesis's closing loop (sections 4.3-4.4): hold out the end of the
record for validation, choose the data to fit on, fit the model there by
least squares (:func:`dynia.fit.fit_segments`) and score it on the
held-out part. :func:`identify` does this for one selection method, so that
the methods can be compared on equal terms:

``"dynia"``
    :func:`dynia.run` on the fitting part (the held-out output blanked),
    then :func:`dynia.segments.segments_from_ic`: the stretches where the
    windows are informative about a parameter (``mode="any"``) or about all
    (``"joint"``) at ``ic_threshold``
    (:meth:`dynia.result.DyniaResult.informative_windows`: never a window
    that only ranks noise).
    Also reports the model-structure
    warnings of :func:`dynia.structure.structure_warnings` and the
    analysis's ``windows_disagree`` verdict reasons (:mod:`dynia.verdicts`).
``"baseline"``
    The accepted intervals of :func:`dynia.baseline.find_intervals`
    (Bittencourt et al., 2015) on the fitting part.
``"whole"``
    The whole fitting part.
``"given"``
    Segments the caller chooses (``segments=``), e.g. random segments of the
    same total length as another method's (:func:`dynia.segments.random_segments`).

``selected_share`` is the share of the fitting part's steps the selection
keeps. A DYNIA selection above :data:`SELECTED_ALL_SHARE` (95 %) of it is
all but the whole fitting part: every step had some IC at the threshold,
the fit is that of ``"whole"``, and ``warnings`` says so.

With ``quality=True`` the data are checked first (:func:`dynia.quality.check_quality`)
and, with ``exclude_flagged=True``, flagged output samples are treated as
missing and flagged input samples interpolated before anything else.

A held-out part can validate only what happens in it. When its input hardly
varies (standard deviation below 10 % of the input's in the fitted data)
and the fitted model's output there changes by no more than the noise
(its standard deviation over the held-out points below twice the fit's
residual standard deviation ``sigma``), ``validation_error`` measures noise
and a level, not the dynamics, and ``warnings`` says so. Both must hold: an
input that stopped changing just before the held-out part still tests the
model through the response that follows, and a model whose output is flat
everywhere is a bad fit, not a quiet held-out part.

A fit of p parameters on too little data fits the noise of its segments as
much as the process. ``warnings`` says so (and ``little_data`` holds the
warning) when the fitted segments hold fewer than
:data:`MIN_POINTS_PER_PARAMETER` (10) measured points per fitted parameter,
or when the validation error is more than :data:`OVERFIT_RATIO` (2) times
the fit's RMS error: ten points per parameter is the usual least-squares
rule of thumb below which the residuals no longer average the noise out of
each estimate, and a model that predicts the held-out part more than twice
as badly as it fits its segments has learnt something of the segments that
does not carry over (five parameters of a rainfall-runoff model fitted on 41
of 1 827 days, with a validation error three times the fit's, was the case
that asked for it). Either alone is reason to distrust the estimates.

Shapes follow :mod:`dynia.engine`: ``u`` and ``y`` are (n_steps,).

Examples
--------
>>> import numpy as np
>>> from dynia.identification import identify
>>> from dynia.models import FirstOrder
>>> u = np.repeat([0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0], 30)
>>> y = FirstOrder().simulate([[2.0, 5.0]], u)[0]
>>> found = identify(u, y, FirstOrder(), {"K": (0, 7), "T": (0, 20)}, method="whole", rng=1)
>>> {name: round(value, 4) for name, value in found.parameters.items()}
{'K': 2.0, 'T': 5.0}
>>> found.segments, found.validation
([(0, 210)], [(210, 300)])
"""

import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from . import _checks
from .baseline import find_intervals
from .bounds import parameter_box
from .errors import NothingSelected, SettingsError
from .fit import check_starts, fit_segments
from .io.frames import unpack
from .pipeline import dated, run
from .progress import shows_progress
from .quality import check_quality
from .segments import (
    check_segments,
    holdout_split,
    intersect_segments,
    segments_from_ic,
    segments_to_mask,
    segments_to_times,
)
from .serial import json_number
from .settings import IC_THRESHOLD, AnalysisSettings, merged_options, merged_settings, split_overrides
from .structure import structure_warnings

__all__ = [
    "Identification",
    "IdentifyOptions",
    "identify",
]

METHODS = ("dynia", "baseline", "whole", "given")

# A DYNIA selection above this share of the fitting part adds nothing over fitting all of it (module docs).
SELECTED_ALL_SHARE = 0.95
#: Fewer measured points than this per fitted parameter in the segments is too little data (module docs).
MIN_POINTS_PER_PARAMETER = 10
#: A validation error more than this many times the fit's RMS error is a fit that does not carry over (module docs).
OVERFIT_RATIO = 2.0


@dataclass(frozen=True, eq=False)
class Identification:
    """What :func:`identify` found.

    Attributes
    ----------
    method : str
    parameters, std_errors : dict of str to float
        Least-squares estimates and their classical standard errors (inf
        where the segments do not determine a parameter).
    std_errors_hac : dict of str to float
        Standard errors robust to autocorrelated residuals
        (:attr:`dynia.fit.FitResult.std_errors_hac`); judge the estimates by these.
    segments : list of (start, stop)
        The steps fitted on (stop exclusive).
    validation : list of (start, stop)
        The held-out steps the validation error is computed on.
    validation_error : float
        RMS of the simulation error on ``validation``.
    fit : dynia.fit.FitResult
    dynia_result : DyniaResult or None
        The DYNIA run ("dynia" only).
    baseline_result : dynia.baseline.BaselineResult or None
        The interval search ("baseline" only).
    quality : dynia.quality.QualityReport or None
    warnings : list of str
        Model-structure warnings, notes on the selection, and a held-out part
        too quiet to validate the model (see the module documentation).
    settings : dict
    selected_share : float
        Share of the fitting part's steps (the record before the held-out
        part) in ``segments``.
    little_data : str or None
        The warning (also in ``warnings``) that the parameters were fitted on
        too little data, see the module documentation; None when they were not.
    """

    method: str
    parameters: dict
    std_errors: dict
    segments: list
    validation: list
    validation_error: float
    fit: object = field(repr=False)
    dynia_result: object = field(default=None, repr=False)
    baseline_result: object = field(default=None, repr=False)
    quality: object = field(default=None, repr=False)
    warnings: list = field(default_factory=list)
    settings: dict = field(default_factory=dict)
    std_errors_hac: dict = field(default_factory=dict)
    selected_share: float = float("nan")
    little_data: str | None = None

    def to_dict(self, time):
        """JSON-ready summary; segments as [start_time, end_time] on ``time`` (n_steps,)."""
        fit = self.fit.to_dict()
        summary = dict(
            method=self.method,
            parameters=fit["parameters"],
            std_errors=fit["std_errors"],
            std_errors_hac=fit["std_errors_hac"],
            hac_lags=fit["hac_lags"],
            segments=segments_to_times(self.segments, time),
            selected_share=json_number(self.selected_share),
            validation_segments=segments_to_times(self.validation, time),
            validation_error=json_number(self.validation_error),
            fit_rmse=fit["rmse"],
            n_points=fit["n_points"],
            identifiable=fit["identifiable"],
            at_bound=fit["at_bound"],
            warnings=list(self.warnings),
            settings=self.settings,
        )
        if self.quality is not None:
            summary["data_quality"] = [
                dict(
                    signal=f.signal,
                    kind=f.kind,
                    start_time=json_number(time[f.start]),
                    end_time=json_number(time[f.stop - 1]),
                    value=json_number(f.value),
                    reason=f.reason,
                    inside_fitted_segments=any(f.start < stop and start < f.stop for start, stop in self.segments),
                )
                for f in self.quality.findings
            ]
        return summary


@dataclass(frozen=True)
class IdentifyOptions:
    """What :func:`identify` does besides the DYNIA run: from IC to segments, the data's quality, the fit.

    Attributes
    ----------
    ic_threshold : float or mapping of str to float, default :data:`~dynia.settings.IC_THRESHOLD` (0.5)
    mode : {"any", "joint"}, default "any"
    min_length, merge_gap : int, optional
        From IC to segments, as :func:`dynia.segments.segments_from_ic`.
    baseline_options : dict, optional
        Tuning of :func:`dynia.baseline.find_intervals`.
    quality : bool, default False
        Check the data with :func:`dynia.quality.check_quality` first. It
        is identify's one switch for the data's quality: the DYNIA run
        screens its record (:attr:`dynia.settings.AnalysisSettings.quality`,
        which it replaces) exactly when it is True.
    exclude_flagged : bool, default False
        Exclude what the check flags (implies the check).
    quality_options : dict, optional
        Tuning of :func:`dynia.quality.check_quality`.
    n_starts : int, default 1
        Starting points of the least-squares fit (the middle of the bounds,
        then random ones).
    """

    ic_threshold: float | Mapping = IC_THRESHOLD
    mode: str = "any"
    min_length: int | None = None
    merge_gap: int | None = None
    baseline_options: dict | None = None
    quality: bool = False
    exclude_flagged: bool = False
    quality_options: dict | None = None
    n_starts: int = 1


def identify(
    u,
    y,
    model,
    bounds,
    *,
    method="dynia",
    held_out=0.3,
    segments=None,
    settings=None,
    options=None,
    rng=None,
    progress="auto",
    **overrides,
):
    """Select data by ``method``, fit the model there and validate it on held-out data.

    Parameters
    ----------
    u, y : array_like, shape (n_steps,), or pandas Series / DataFrame
        Input and output, deviation variables around the operating point
        (as ``dynia analyse --offset/--input-offset`` prepares them). NaN in
        ``y`` marks a missing sample. pandas objects as :func:`dynia.run`
        takes them (:func:`dynia.io.frames.unpack`): one index, whose time
        gives dt and whose dates become ``dynia_result.timestamps``.
    model : dynia.models.Model
    bounds : mapping of str to (low, high)
        Every model parameter's range: DYNIA's prior and the fit's bounds.
    method : {"dynia", "baseline", "whole", "given"}
        How the fitting data are chosen (see the module documentation).
    held_out : float or list of (start, stop), default 0.3
        Validation data, never used to select or fit: that share of the
        record at its end, or explicit segments
        (:func:`dynia.segments.holdout_split`).
    segments : list of (start, stop), optional
        The segments to fit on, for ``method="given"``.
    settings : dynia.settings.AnalysisSettings, optional
        The DYNIA run's settings, as for :func:`dynia.run`; its ``dt``
        (default 1.0; with a time index its spacing, and a ``dt`` given
        must agree) and ``x0`` serve the fit too. ``min_points=2n+1`` keeps
        windows that reach into missing or excluded data from selecting
        segments.
    options : IdentifyOptions, optional
        The selection, the data-quality checks and the fit.
    rng : numpy.random.Generator or int, optional
        Every random draw (the DYNIA samples, the extra fit starts).
    progress : bool or "auto", default "auto"
        Show the DYNIA run's progress bar (tqdm, on stderr), as :func:`dynia.run`.
    **overrides
        Single settings over ``settings`` (any field of
        :class:`~dynia.settings.AnalysisSettings`, see :mod:`dynia.settings`
        for the list), e.g. ``n=200, n_samples=5000, dt=60``, and single
        options over ``options`` (any field of :class:`IdentifyOptions`),
        e.g. ``ic_threshold=0.6, n_starts=5``. ``quality`` names the
        option. Any other name is a :class:`~dynia.errors.SettingsError`.

    Returns
    -------
    Identification
    """
    option_overrides, setting_overrides = split_overrides(identify, overrides, IdentifyOptions, AnalysisSettings)
    options = merged_options(IdentifyOptions, options, option_overrides)
    # pandas in, as dynia.run takes it, before anything is cut out of the record by step.
    dt = setting_overrides.pop("dt", None)
    u, y, dt, timestamps = unpack(u, y, dt if dt is not None else getattr(settings, "dt", None))
    u, y = _checks.record(u, y, n_inputs=model.n_inputs)
    quality, exclude_flagged = options.quality, options.exclude_flagged
    _check_method(model, method, segments, quality or exclude_flagged)
    # The DYNIA run screens its record exactly when identify checks the data's quality (IdentifyOptions.quality).
    analysis = merged_settings(settings, {**setting_overrides, "dt": dt, "quality": quality}, front_end=identify)
    progress = shows_progress(progress)
    dt, x0 = analysis.dt, analysis.x0
    names, box = parameter_box(bounds, model.names, type(model).__name__)
    bounds = {name: tuple(map(float, row)) for name, row in zip(names, box)}
    rng = _checks.generator(rng)
    n_starts = check_starts(options.n_starts)  # before the analysis, which the fit waits for
    u, y, report = _quality_checked(u, y, dt, quality, exclude_flagged, options.quality_options)
    fit_part, validation = _split(y.size, held_out, method, analysis, len(names))
    y_fit = np.where(segments_to_mask(validation, y.size), np.nan, y)
    segmenting = dict(
        ic_threshold=options.ic_threshold, mode=options.mode, min_length=options.min_length, merge_gap=options.merge_gap
    )
    notes = []
    dynia_result = baseline_result = None
    if method == "dynia":
        dynia_result = run(u, y_fit, model, bounds, settings=analysis, rng=rng, progress=progress)
        if timestamps is not None:
            dynia_result = dated(dynia_result, timestamps)
        chosen = intersect_segments(segments_from_ic(dynia_result, **segmenting), fit_part)
        notes += [str(warning) for warning in structure_warnings(dynia_result)]
        # DYNIA's own model-structure warning (its verdicts): the windows that identify a parameter disagree.
        notes += [
            f"{name}: {reason['text']}"
            for name, verdict in dynia_result.verdicts.items()
            for reason in verdict["reasons"]
            if reason["code"] == "windows_disagree"
        ]
    elif method == "baseline":
        fitting = segments_to_mask(fit_part, y.size)
        baseline_result = find_intervals(np.where(fitting, u, np.nan), y_fit, dt=dt, **(options.baseline_options or {}))
        chosen = intersect_segments([tuple(map(int, pair)) for pair in baseline_result.accepted], fit_part)
    elif method == "whole":
        chosen = list(fit_part)
    else:
        chosen = intersect_segments(check_segments(segments, y.size), fit_part)
    if not chosen:
        raise NothingSelected(f"method {method!r} selected no data to fit on: {_NOTHING_SELECTED[method]}")
    fit = fit_segments(u, y_fit, model, chosen, bounds=bounds, dt=dt, x0=x0, n_starts=n_starts, rng=rng)
    asked = dict(method=method, n_starts=n_starts, quality=quality, exclude_flagged=exclude_flagged)
    recorded = _recorded(asked, analysis, bounds, validation, baseline_result, segmenting)
    found = dict(dynia_result=dynia_result, baseline_result=baseline_result, quality=report, settings=recorded)
    return _identification(asked, segmenting, fit, u, y, (chosen, fit_part, validation), notes, **found)


def _quality_checked(u, y, dt, quality, exclude_flagged, quality_options):
    """The record and its data-quality report (None unless asked for), flagged samples excluded when asked."""
    if not (quality or exclude_flagged):
        return u, y, None
    report = check_quality(np.arange(y.size) * dt, u, y, **(quality_options or {}))
    if exclude_flagged:
        u, y = report.exclude(u, signal="u"), report.exclude(y, signal="y")
    return u, y, report


def _recorded(asked, analysis, bounds, validation, baseline_result, segmenting):
    """``Identification.settings``: what was asked, and the DYNIA run's or the interval search's settings."""
    method, exclude_flagged = asked["method"], asked["exclude_flagged"]
    recorded = dict(
        method=method,
        dt=analysis.dt,
        x0=analysis.x0,
        held_out_steps=int(sum(b - a for a, b in validation)),
        bounds={name: list(pair) for name, pair in bounds.items()},
        n_starts=asked["n_starts"],
        quality=bool(asked["quality"] or exclude_flagged),
        exclude_flagged=bool(exclude_flagged),
    )
    if method == "dynia":
        recorded.update(analysis.to_dict(), **segmenting)
    if method == "baseline":
        recorded["baseline"] = {
            key: json_number(value) if isinstance(value, float) else value
            for key, value in baseline_result.settings.items()
            if isinstance(value, (int, float, str, bool))
        }
    return recorded


def _identification(asked, segmenting, fit, u, y, parts, notes, **found):
    """The :class:`Identification` of ``fit``, with the notes on the segments chosen and on the held-out part.

    ``parts`` are the segments chosen, the fitting part and the held-out
    part; ``found`` the other fields.
    """
    chosen, fit_part, validation = parts
    method, ic_threshold, report = asked["method"], segmenting["ic_threshold"], found["quality"]
    if report is not None:
        notes += _findings_inside(report, chosen, asked["exclude_flagged"])
    fitting_steps = sum(stop - start for start, stop in fit_part)
    selected_steps = sum(stop - start for start, stop in chosen)
    selected_share = selected_steps / fitting_steps
    if method == "dynia" and selected_share > SELECTED_ALL_SHARE:
        notes.append(
            f"DYNIA selected {100 * selected_share:.1f} % of the fitting part ({selected_steps} of {fitting_steps} "
            f"steps): nearly every step has an IC of at least {ic_threshold:g}, so the fit is that of the whole "
            "fitting part (method 'whole') and the selection added nothing; raise ic_threshold or use mode 'joint'"
        )
    notes += _quiet_held_out(u, y, fit, validation)
    validation_error = fit.validation_error(u, y, validation)
    little_data = _little_data(fit, validation_error)
    notes += [little_data] if little_data else []
    return Identification(
        method=method,
        parameters=dict(fit.parameters),
        std_errors=dict(fit.std_errors),
        std_errors_hac=dict(fit.std_errors_hac),
        segments=list(fit.segments),
        validation=list(validation),
        validation_error=validation_error,
        fit=fit,
        warnings=notes,
        selected_share=selected_share,
        little_data=little_data,
        **found,
    )


# Why a method selected nothing in the fitting part, and what to change (DYNIA's own rule raises before this).
_NOTHING_SELECTED = {
    "dynia": "its informative segments all lie in the held-out part; hold out another part (held_out)",
    "baseline": "the interval search accepted no interval in the fitting part; loosen baseline_options",
    "given": "no given segment reaches into the fitting part; give segments outside held_out",
}


def _check_method(model, method, segments, quality):
    """Raise unless ``method`` is known and can take ``model``, and ``segments`` come exactly with "given"."""
    if method not in METHODS:
        raise SettingsError(f"method must be one of {METHODS}; got {method!r}")
    if model.n_inputs > 1 and (method == "baseline" or quality):
        raise SettingsError(
            f"the baseline interval search and the data-quality checks take one input; {model!r} has {model.n_inputs}"
        )
    if (segments is None) != (method != "given"):
        raise SettingsError("segments are given exactly when method='given'")


def _split(n_steps, held_out, method, analysis, n_params):
    """The fitting part and the held-out validation part; an error when the fitting part is too short.

    A DYNIA selection needs one window in it, a fit one step more than the parameters.
    """
    fit_part, validation = holdout_split(n_steps, held_out)
    fit_steps = sum(stop - start for start, stop in fit_part)
    needed, why = (
        (analysis.window_length, f"one window, 2n+1 with n = {analysis.n}")
        if method == "dynia"
        else (n_params + 1, "one more than the parameters")
    )
    if fit_steps < needed:
        raise SettingsError(
            f"held_out {held_out if isinstance(held_out, numbers.Real) else 'as given'} leaves {fit_steps} of the "
            f"record's {n_steps} steps to select and fit on; expected at least {needed} ({why}): hold out less",
            "held_out",
        )
    return fit_part, validation


def _findings_inside(report, chosen, exclude_flagged):
    """A note (in a list) on the data-quality findings inside the segments ``chosen``, else []."""
    inside = sum(len(found) for found in report.findings_in(chosen).values())
    if not inside:
        return []
    return [
        f"{inside} data-quality finding(s) lie inside the fitted segments"
        + ("" if exclude_flagged else "; exclude them with exclude_flagged=True")
    ]


# A held-out part too quiet to validate anything (module docs): its input's
# standard deviation below this share of the fitted data's ...
_QUIET_INPUT_SHARE = 0.1
# ... and the fitted model's output there varying by less than this many residual standard deviations.
_QUIET_NOISE_MULTIPLE = 2.0


def _quiet_held_out(u, y, fit, validation):
    """A warning (in a list) when the held-out part has too little excitation to validate the model, else []."""
    held = segments_to_mask(validation, y.size) & ~np.isnan(y)
    fitted = segments_to_mask(fit.segments, y.size)
    if not held.any() or not np.isfinite(fit.sigma):
        return []
    columns = u.reshape(u.shape[0], -1)
    spread_fitted = columns[fitted].std(axis=0)
    if not (spread_fitted > 0).any():
        return []
    # With several inputs the most varied one counts: any input changing is excitation.
    share = float(np.max(columns[held].std(axis=0)[spread_fitted > 0] / spread_fitted[spread_fitted > 0]))
    response = float(np.std(fit.simulate(u, segments=validation)[held]))
    if share >= _QUIET_INPUT_SHARE or response >= _QUIET_NOISE_MULTIPLE * fit.sigma:
        return []
    return [
        f"the held-out part has too little excitation to validate the model: its input varies "
        f"{100 * share:.1f} % as much as in the fitted data (standard deviation), and the fitted model's output "
        f"there varies by {response:.3g}, within {_QUIET_NOISE_MULTIPLE:g} residual standard deviations "
        f"({fit.sigma:.3g}); validation_error there measures noise and level, not the dynamics; hold out a "
        "part of the record with input changes"
    ]


def _little_data(fit, validation_error):
    """The warning that the parameters were fitted on too little data (module docs), or None."""
    fitted = len(fit.parameters)
    per_parameter = fit.n_points / fitted if fitted else float("inf")
    ratio = validation_error / fit.rmse if fit.rmse > 0 else float("inf") if validation_error > 0 else 0.0
    findings = []
    if per_parameter < MIN_POINTS_PER_PARAMETER:
        findings.append(
            f"{fit.n_points} measured points in the fitted segments, {per_parameter:.1f} per parameter (fewer than "
            f"{MIN_POINTS_PER_PARAMETER})"
        )
    if np.isfinite(validation_error) and ratio > OVERFIT_RATIO:
        findings.append(
            f"the validation error {validation_error:.3g} is {ratio:.1f} times the fit's RMS error {fit.rmse:.3g} "
            f"(more than {OVERFIT_RATIO:g})"
        )
    if not findings:
        return None
    return (
        f"too little data for {fitted} fitted parameter(s): {' and '.join(findings)}; the estimates may follow the "
        "noise of the segments rather than the process: select more data (a lower ic_threshold) or fit fewer "
        "parameters"
    )
