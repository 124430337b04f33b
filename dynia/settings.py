"""One settings object for every DYNIA front-end, validated once.

:class:`AnalysisSettings` holds what decides a DYNIA analysis: the Monte
Carlo sample, the window, the behavioural share, the band, the flavour and the
engine. :func:`dynia.run`, :func:`dynia.adaptive.adaptive_run`,
:func:`dynia.distributed.run`, :class:`dynia.online.OnlineDynia`,
:func:`dynia.identify` and the command line all build or take one (as
``settings=``, with single settings as keywords over it:
:func:`merged_settings`), so a setting is checked in one place, and a
front-end that cannot honour a setting says so instead of dropping it
(:meth:`AnalysisSettings.require`).

Types are checked strictly: ``percentage="10"`` or ``n=2.5`` is a
:class:`~dynia.errors.SettingsError`, never coerced, never truthy.

Examples
--------
>>> from dynia.settings import AnalysisSettings
>>> settings = AnalysisSettings(n_samples=5000, percentage=1)
>>> settings.n_behavioural
50
>>> settings.replace(n=5).window_length
11
>>> AnalysisSettings(conf_level=0.9)
Traceback (most recent call last):
    ...
dynia.errors.SettingsError: conf_level is a percentage in (50, 100); got 0.9 (did you mean 90?)
"""

import dataclasses
import difflib
import inspect
import math
import numbers
import os
from collections.abc import Mapping

import numpy as np

from . import _checks
from .errors import SettingsError

__all__ = [
    "AnalysisSettings",
    "RunRecord",
    "SAMPLERS",
    "MAX_BINS",
    "MAX_SAMPLES",
    "MAX_HALF_WINDOW",
    "MAX_WORKERS",
    "IC_THRESHOLD",
    "ic_batches",
    "merged_settings",
]

SAMPLERS = ("uniform", "lhs", "sobol")
ADAPTIVE_SAMPLERS = ("iis", "de")
FLAVOURS = ("thesis", "mcat", "weighted")
WINDOWS = ("centred", "trailing")
ENGINES = ("auto", "numba", "numpy", "twin")
X0 = ("zero", "steady")
DTYPES = ("float64", "float32")
# A finer CLD-gradient grid only spreads the behavioural set (a few hundred
# values) thinner: past this the rows are mostly empty and the array huge.
MAX_BINS = 1000
# Parameter ranges reaching beyond this are a typo or a unit slip; squares and
# sums of such values overflow float64 (1.8e308) in the engine and the plots.
MAX_PARAMETER = 1e150
# The upper ends of the whole-number settings. Far beyond any analysis (DYNIA needs 10^3 to 10^5 samples), yet low
# enough that the arrays they size can be allocated and their sizes computed without overflowing int64: a typo such
# as 9223372036854775807 samples is refused here instead of crashing numpy after the data are read.
MAX_SAMPLES = 100_000_000
MAX_HALF_WINDOW = 100_000_000
MAX_WORKERS = 1024
# The default max_samples of dynia.suggest: the most samples its pilot and its proposal use.
DEFAULT_MAX_SAMPLES = 200_000
# The median absolute deviation of Gaussian noise times this is its standard deviation (robust noise estimates).
MAD_TO_STD = 1.4826
# The information content from which a window is informative (DyniaResult.informative_windows): the one default of
# every rule that judges windows (verdicts, segments, second run, structure warnings). At 0.5 a window's band spans at
# most half of the parameter's sampling range.
IC_THRESHOLD = 0.5
# Batches of the Monte Carlo error (see ic_batches): ten give the error's own
# spread about 24 % (a standard deviation with 9 degrees of freedom), and a
# batch keeps at least five behavioural sets, or the limits of the thesis
# (sorted positions floor(c(count-1))) are the batch's extremes.
IC_BATCHES = 10
MIN_BATCH_BEHAVIOURAL = 5
_SAMPLES_WHY = " (DYNIA needs thousands; beyond this the samples alone fill the memory)"


def _whole(value, name, minimum, maximum=None, why=""):
    # A setting takes an int only (1.0 is refused, as a slip of type); the range as every count's.
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise SettingsError(f"{name} must be a whole number; got {value!r} ({type(value).__name__})", name)
    return _checks.whole_number(value, name, minimum=minimum, maximum=maximum, why=why)


def check_ic_threshold(value):
    """The IC from which a window counts as informative, a number in [0, 1], or a SettingsError naming ``ic_threshold``.

    Examples
    --------
    >>> check_ic_threshold(0.5)
    0.5
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 <= value <= 1:
        raise SettingsError(f"ic_threshold must be a number in [0, 1] (IC lies there); got {value!r}", "ic_threshold")
    return float(value)


def sample_count(value, name, minimum=1):
    """A number of Monte Carlo samples, from ``minimum`` to :data:`MAX_SAMPLES`, or a SettingsError naming ``name``.

    Examples
    --------
    >>> sample_count(2000, "n_samples")
    2000
    """
    return _checks.whole_number(value, name, minimum=minimum, maximum=MAX_SAMPLES, why=_SAMPLES_WHY)


def _real(value, name):
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise SettingsError(f"{name} must be a finite number; got {value!r} ({type(value).__name__})", name)
    return float(value)


def _choice(value, name, choices):
    if not isinstance(value, str) or value not in choices:
        raise SettingsError(f"{name} must be one of {', '.join(map(repr, choices))}; got {value!r}", name)
    return value


def check_dt(dt):
    """Return the sample time as a float > 0, or raise :class:`~dynia.errors.SettingsError` naming ``dt``."""
    if isinstance(dt, (bool, str)) or np.ndim(dt) != 0:
        raise SettingsError(f"dt must be a finite number > 0; got {dt!r}", "dt")
    try:
        value = float(dt)
    except (TypeError, ValueError):
        raise SettingsError(f"dt must be a finite number > 0; got {dt!r}", "dt") from None
    if not math.isfinite(value) or value <= 0:
        raise SettingsError(f"dt must be a finite number > 0; got {dt!r}", "dt")
    return value


def check_x0(x0):
    """Return the initial-state rule ("zero" or "steady"), or raise naming ``x0``."""
    return _choice(x0, "x0", X0)


def ic_batches(n_samples, percentage):
    """Batches B of the Monte Carlo error of IC for ``n_samples`` samples at ``percentage`` %.

    Sample i belongs to batch ``i mod B``: interleaved, so that every batch
    draws alike from samples drawn in stages (the adaptive samplers' uniform
    stage and boxes). B is :data:`IC_BATCHES` (10), or the largest number
    below it whose smallest batch (``n_samples // B`` samples) still keeps
    :data:`MIN_BATCH_BEHAVIOURAL` (5) behavioural sets,
    ``floor(n_samples//B * percentage/100)``. The engine reads IC off these
    batches (:mod:`dynia.engine.flavours`); the settings check with it that
    ``ic_error`` can be honoured.

    Raises
    ------
    SettingsError
        When not even 2 batches keep 5 behavioural sets each: the samples
        are too few for an error estimate (raise n_samples or percentage).

    Examples
    --------
    >>> ic_batches(2000, 10), ic_batches(50_000, 0.1), ic_batches(300, 10)
    (10, 10, 6)
    """
    for batches in range(IC_BATCHES, 1, -1):
        if math.floor(n_samples // batches * (percentage / 100)) >= MIN_BATCH_BEHAVIOURAL:
            return batches
    raise SettingsError(
        f"ic_error needs at least 2 batches of {MIN_BATCH_BEHAVIOURAL} behavioural sets; percentage={percentage:g} "
        f"of n_samples={n_samples} keeps {math.floor(n_samples * (percentage / 100))} in all (raise n_samples or "
        "percentage)",
        "ic_error",
    )


@dataclasses.dataclass(frozen=True)
class AnalysisSettings:
    """Every setting of a DYNIA analysis, checked when the object is made.

    Attributes
    ----------
    n_samples : int, default 2000
        Monte Carlo parameter sets (model evaluations), 1 to :data:`MAX_SAMPLES`.
    sampler : {"uniform", "lhs", "sobol", "iis", "de"}, default "uniform"
        How the parameter box is sampled; "iis" and "de" are the adaptive
        schemes of :mod:`dynia.adaptive`.
    n : int, default 10
        Half window: each window holds 2n+1 steps; 0 to :data:`MAX_HALF_WINDOW`,
        and below the record's length (:func:`dynia.run` checks that).
    percentage : float, default 10
        Behavioural share of the samples in percent, in (0, 100].
    bins : int, default 40
        CLD gradient bins, at most 1000 (:data:`MAX_BINS`).
    conf_level : float, default 90
        Confidence level of the band, percent in (50, 100): below 50 the
        "band" would hold less than half of the behavioural set.
    flavour : {"thesis", "mcat", "weighted"}, default "thesis"
        The variant of the method: the thesis's, MCAT's, or the thesis's with
        likelihood-weighted limits (the table of flavours in the user guide,
        docs/guide/package.rst).
    x0 : {"zero", "steady"}, default "zero"
        Initial state of every simulation: zero, or steady at the first input.
    min_points : int, default 1
        Windows with fewer measured output points report a missing IC (NaN);
        at most the window length 2n+1.
    window : {"centred", "trailing"}, default "centred"
        Where a window lies: centred on its step, or trailing it (the 2n+1
        steps up to the step, as an online analysis sees them).
    engine : {"auto", "numba", "numpy", "twin"}, default "auto"
        The compiled kernels (numba), plain numpy, their numpy twin, or the
        twin for a small run and numba where it can. The twin
        (:mod:`dynia.engine.twin`) gives the kernels' numbers bit for bit with
        nothing to compile; numba and numpy agree to rounding
        (:mod:`dynia.engine.kernels`).
    workers : int or None, default None
        Threads (None: every core), at most :data:`MAX_WORKERS`. Results do
        not depend on it.
    dt : float or None, default None
        Sample time of the record (None: a time index's spacing, else 1).
        Every front-end resolves None when it reads the record, so a
        result's settings hold the number the run used, and settings made
        without a dt agree with any pandas index.
    ic_error : bool, default False
        Also estimate the Monte Carlo standard error of IC and limits (batch
        means): ``result.ic_se``, ``result.ci_se`` (see
        :mod:`dynia.engine.windows`). Not for the mcat flavour.
    target_se : float or None, default None
        Add samples until the largest IC standard error where it can change a
        verdict is at most this (implies ``ic_error``; needs ``max_samples``):
        in (0, 1), with :func:`dynia.run` and the uniform sampler.
    max_samples : int or None, default None
        The budget of ``target_se``: at most this many samples, at least
        ``n_samples`` and at most :data:`MAX_SAMPLES`.
    dtype : {"float64", "float32"}, default "float64"
        Type of the result arrays: float32 halves their memory and their netCDF
        file.
        The arrays are the time-dependent ones (IC, limits, median, gradient
        and their errors); the engine computes in float64 either way, float32
        keeps each value rounded to the nearest float32 (see
        :mod:`dynia.io.arrays`).
    store : str or os.PathLike or None, default None
        A netCDF file that the time-dependent arrays are written to as they
        are produced, so that they never lie whole in memory; the result
        reads them from it (see :mod:`dynia.io.arrays`). Kept as a str.
    quality : bool, default True
        Screen the record for saturated, frozen and coarsely quantised
        readings before the analysis (:func:`dynia.quality.screen`):
        ``result.run.screened`` lists what was found, and the windows that
        use such readings are no evidence for any parameter
        (:attr:`dynia.result.DyniaResult.screened_windows`). The command
        line's ``--no-quality`` turns it off. :class:`dynia.online.OnlineDynia`
        streams and cannot screen a record before analysing it: it screens
        what :meth:`~dynia.online.OnlineDynia.replay` was given, once replayed;
        single updates are not screened.
    """

    # Each field's metadata says what a front-end needs to offer it, once: "help" (one line, lower case; the first
    # words of the Attributes entry above; {name} marks another setting, named as the front-end names it),
    # "option" (the command line's option, where it is not --name with dashes), "metavar" and "choices" (the
    # values the field accepts). The value type is the annotation, the default the field's own.
    n_samples: int = dataclasses.field(
        default=2000,
        metadata=dict(help="Monte Carlo parameter sets", option="--samples", metavar="N"),
    )
    sampler: str = dataclasses.field(
        default="uniform", metadata=dict(help="how the parameter box is sampled", choices=SAMPLERS + ADAPTIVE_SAMPLERS)
    )
    n: int = dataclasses.field(default=10, metadata=dict(help="half window: each window holds 2n+1 steps", metavar="N"))
    percentage: float = dataclasses.field(
        default=10.0, metadata=dict(help="behavioural share of the samples in percent", metavar="P")
    )
    bins: int = dataclasses.field(default=40, metadata=dict(help=f"CLD gradient bins, at most {MAX_BINS}", metavar="B"))
    conf_level: float = dataclasses.field(
        default=90.0, metadata=dict(help="confidence level of the band, percent in (50, 100)", metavar="C")
    )
    flavour: str = dataclasses.field(
        default="thesis",
        metadata=dict(
            help="the variant of the method: the thesis's, MCAT's, or the thesis's with likelihood-weighted limits",
            choices=FLAVOURS,
        ),
    )
    x0: str = dataclasses.field(
        default="zero",
        metadata=dict(help="initial state of every simulation: zero, or steady at the first input", choices=X0),
    )
    min_points: int = dataclasses.field(
        default=1, metadata=dict(help="windows with fewer measured output points report a missing IC", metavar="N")
    )
    window: str = dataclasses.field(
        default="centred",
        metadata=dict(help="where a window lies: centred on its step, or trailing it", choices=WINDOWS),
    )
    engine: str = dataclasses.field(
        default="auto",
        metadata=dict(
            help="the compiled kernels (numba), plain numpy, their numpy twin, or the twin for a small run and numba "
            "where it can",
            choices=ENGINES,
        ),
    )
    workers: int | None = dataclasses.field(default=None, metadata=dict(help="threads (None: every core)", metavar="N"))
    dt: float | None = dataclasses.field(
        default=None,
        metadata=dict(help="sample time of the record (None: a time index's spacing, else 1)", metavar="SECONDS"),
    )
    ic_error: bool = dataclasses.field(
        default=False,
        metadata=dict(help="also estimate the Monte Carlo standard error of IC and limits (batch means)"),
    )
    target_se: float | None = dataclasses.field(
        default=None,
        metadata=dict(
            help="add samples until the largest IC standard error where it can change a verdict is at most this "
            "(implies {ic_error}; needs {max_samples})",
            metavar="SE",
        ),
    )
    max_samples: int | None = dataclasses.field(
        default=None, metadata=dict(help="the budget of {target_se}", metavar="N")
    )
    dtype: str = dataclasses.field(
        default="float64",
        metadata=dict(
            help="type of the result arrays: float32 halves their memory and their netCDF file", choices=DTYPES
        ),
    )
    store: str | None = dataclasses.field(
        default=None,
        metadata=dict(
            help="a netCDF file that the time-dependent arrays are written to as they are produced", metavar="FILE"
        ),
    )
    # On by default, so its option is the negation: "negated" makes it --no-quality, which stores False.
    quality: bool = dataclasses.field(
        default=True,
        metadata=dict(
            help="screen the record for saturated, frozen and coarsely quantised readings before the analysis",
            option="--no-quality",
            negated=True,
        ),
    )

    def __post_init__(self):
        self._check_sampling()
        self._check_window()
        self._check_errors_and_storage()
        self._check_combinations()

    def _store(self, name, value):
        """Put the checked ``value`` in place of the one given (the object is frozen)."""
        object.__setattr__(self, name, value)

    def _check_sampling(self):
        """The Monte Carlo sample, the behavioural share and the band."""
        store = self._store
        store("n_samples", _whole(self.n_samples, "n_samples", 1, MAX_SAMPLES, _SAMPLES_WHY))
        store("sampler", _choice(self.sampler, "sampler", SAMPLERS + ADAPTIVE_SAMPLERS))
        store("n", _whole(self.n, "n", 0, MAX_HALF_WINDOW))
        percentage = _real(self.percentage, "percentage")
        if not 0 < percentage <= 100:
            raise SettingsError(f"percentage must lie in (0, 100]; got {percentage:g}", "percentage")
        store("percentage", percentage)
        bins = _whole(self.bins, "bins", 1)
        if bins > MAX_BINS:
            raise SettingsError(
                f"bins must be at most {MAX_BINS}; got {bins} (the behavioural set cannot fill a finer grid)", "bins"
            )
        store("bins", bins)
        conf_level = _real(self.conf_level, "conf_level")
        if not 50 < conf_level < 100:
            hint = f" (did you mean {conf_level * 100:g}?)" if 0.5 < conf_level < 1 else ""
            raise SettingsError(f"conf_level is a percentage in (50, 100); got {conf_level:g}{hint}", "conf_level")
        store("conf_level", conf_level)

    def _check_window(self):
        """The flavour, the initial state, the window and the engine."""
        store = self._store
        store("flavour", _choice(self.flavour, "flavour", FLAVOURS))
        store("x0", check_x0(self.x0))
        min_points = _whole(self.min_points, "min_points", 1)
        if min_points > self.window_length:
            raise SettingsError(
                f"min_points {min_points} is more than a window holds (2n+1 = {self.window_length} "
                f"with n = {self.n}): no window could ever report a result",
                "min_points",
            )
        store("min_points", min_points)
        store("window", _choice(self.window, "window", WINDOWS))
        store("engine", _choice(self.engine, "engine", ENGINES))
        if self.workers is not None:
            store("workers", _whole(self.workers, "workers", 1, MAX_WORKERS, " threads"))
        store("dt", None if self.dt is None else check_dt(self.dt))

    def _check_errors_and_storage(self):
        """The Monte Carlo error, its target, and where the result arrays go."""
        store = self._store
        for name in ("ic_error", "quality"):
            value = getattr(self, name)
            if not isinstance(value, bool):
                raise SettingsError(f"{name} must be True or False; got {value!r} ({type(value).__name__})", name)
        if self.target_se is not None:
            target_se = _real(self.target_se, "target_se")
            if not 0 < target_se < 1:
                raise SettingsError(f"target_se is an IC standard error in (0, 1); got {target_se:g}", "target_se")
            store("target_se", target_se)
            store("ic_error", True)  # the target is on the error, which must then be estimated
        if self.max_samples is not None:
            store("max_samples", _whole(self.max_samples, "max_samples", self.n_samples, MAX_SAMPLES, _SAMPLES_WHY))
        store("dtype", _choice(self.dtype, "dtype", DTYPES))
        if self.store is not None:
            if not isinstance(self.store, (str, os.PathLike)) or not os.fspath(self.store):
                raise SettingsError(
                    f"store must be the path of a file (str or os.PathLike); got {self.store!r}", "store"
                )
            store("store", os.fspath(self.store))

    def _check_combinations(self):
        """The settings that only work together, or not at all together."""
        self._check_error_target()
        if self.sampler in ADAPTIVE_SAMPLERS:
            self._check_adaptive()
        else:
            self._check_behavioural()

    def _check_error_target(self):
        if (self.target_se is None) != (self.max_samples is None):
            raise SettingsError(
                "target_se and max_samples go together: the target of the Monte Carlo error and the budget of "
                "samples that may be spent on it",
                "target_se" if self.max_samples is None else "max_samples",
            )
        if self.ic_error:
            ic_batches(self.n_samples, self.percentage)  # enough behavioural sets for two batches, or a clear error
        if self.ic_error and self.flavour == "mcat":
            raise SettingsError(
                "ic_error is not available for the mcat flavour yet (its likelihood carries state from window "
                "to window); use flavour 'thesis' or 'weighted'",
                "ic_error",
            )
        if self.target_se is not None and self.sampler != "uniform":
            raise SettingsError(
                f"target_se adds samples to the first ones, which only the uniform sampler can do (a Latin "
                f"hypercube or Sobol design does not extend, an adaptive one is redrawn); got sampler {self.sampler!r}",
                "target_se",
            )

    def _check_adaptive(self):
        if self.store is not None or self.dtype != "float64":
            raise SettingsError(
                f"sampler {self.sampler!r} holds every simulation in memory, so the storage settings for "
                "long records (store, dtype) do not help it; use the uniform, lhs or sobol sampler with them",
                "store" if self.store is not None else "dtype",
            )
        if self.flavour == "mcat":
            raise SettingsError(
                f"sampler {self.sampler!r} draws importance-weighted samples, which the mcat flavour cannot "
                "use; take flavour 'thesis' or 'weighted'"
            )
        if self.engine in ("numba", "twin"):
            which = "compiled engine" if self.engine == "numba" else "twin engine"
            raise SettingsError(
                f"sampler {self.sampler!r} draws importance-weighted samples, which the {which} does "
                "not take; use engine 'auto' or 'numpy'"
            )
        if self.n_samples < 10:
            raise SettingsError(f"sampler {self.sampler!r} needs n_samples >= 10; got {self.n_samples}", "n_samples")

    def _check_behavioural(self):
        if self.engine == "numba" and self.flavour == "mcat":
            raise SettingsError(
                "engine 'numba' covers the 'thesis' and 'weighted' flavours; use engine "
                "'auto' or 'numpy' with flavour 'mcat'"
            )
        if self.flavour == "mcat":
            blocks = 100 / self.percentage
            if abs(blocks - round(blocks)) > 1e-9 * blocks:
                raise SettingsError(
                    f"the mcat flavour splits the samples into 100/percentage blocks; percentage "
                    f"{self.percentage:g} does not divide 100 into a whole number of blocks",
                    "percentage",
                )
            if self.n_samples // round(blocks) < 1:
                raise SettingsError(
                    f"percentage {self.percentage:g} of n_samples {self.n_samples} leaves no behavioural set",
                    "percentage",
                )
        elif self.n_behavioural < 2:
            raise SettingsError(
                f"percentage {self.percentage:g} of n_samples {self.n_samples} keeps "
                f"{self.n_behavioural} parameter sets per window; at least 2 are needed "
                "(raise percentage or n_samples)",
                "percentage",
            )

    def check_record(self, n_steps):
        """Raise unless a record of ``n_steps`` holds one whole window of 2n+1 steps.

        With fewer, every window is truncated by both ends of the record, and
        the IC of such windows is not comparable with anything the method reports.
        """
        if n_steps < self.window_length:
            raise SettingsError(
                f"the record has {n_steps} step(s), fewer than one window of 2n+1 = {self.window_length} steps "
                f"(n={self.n}); give a longer record or a smaller n",
                "n",
            )
        return self

    @property
    def window_length(self):
        """Steps in a window, 2n+1."""
        return 2 * self.n + 1

    @property
    def n_behavioural(self):
        """Behavioural sets per window for the thesis and weighted flavours, ``floor(n_samples*percentage/100)``."""
        return math.floor(self.n_samples * (self.percentage / 100))

    @classmethod
    def build(cls, settings=None, **options):
        """``settings`` (or the defaults) with every option that is not None put in.

        The front-ends' keyword arguments default to None so that an explicit
        keyword overrides a settings object and nothing given is dropped.
        """
        if settings is None:
            settings = cls()
        elif not isinstance(settings, cls):
            raise SettingsError(f"settings must be a dynia.settings.AnalysisSettings; got {type(settings).__name__}")
        given = {key: value for key, value in options.items() if value is not None}
        return settings.replace(**given) if given else settings

    def replace(self, **changes):
        """A copy with ``changes``, checked again; an unknown name is an error naming the valid ones."""
        fields = {field.name for field in dataclasses.fields(self)}
        unknown = sorted(set(changes) - fields)
        if unknown:
            raise SettingsError(
                f"unknown setting(s) {', '.join(unknown)}; the settings are {', '.join(sorted(fields))}"
            )
        return dataclasses.replace(self, **changes)

    def require(self, front_end, why="", **allowed):
        """Raise unless every setting differs from its default only where ``front_end`` can honour it.

        ``allowed`` maps a setting to the values that front-end supports
        (a tuple), so that, e.g., an online analysis given ``workers=4``
        says it has no threads instead of ignoring them. ``why`` is added to
        the message.
        """
        for name, supported in allowed.items():
            value = getattr(self, name)
            if value not in supported:
                shown = ", ".join(repr(item) for item in supported)
                raise SettingsError(
                    f"{front_end} does not support {name}={value!r}; it takes {shown}" + (f" ({why})" if why else ""),
                    name,
                )
        return self

    def to_dict(self):
        """The settings as a plain dict, every field by name (for summary.json and the saved result)."""
        return dataclasses.asdict(self)


def _optional(kind, value, name):
    """``value`` as ``kind`` (int, float or bool), None kept; a SettingsError naming ``name`` for another type."""
    if value is None:
        return None
    if kind is bool:
        if isinstance(value, (bool, np.bool_)):
            return bool(value)
    elif kind is int:
        if isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_)):
            return int(value)
    elif isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)):
        return float(value)
    raise SettingsError(f"{name} must be {kind.__name__} or None; got {value!r} ({type(value).__name__})", name)


def _named_ranges(rows):
    """``first_run_bounds`` as ((name, (low, high)), ...), from pairs or a mapping; a SettingsError otherwise."""
    pairs = rows.items() if isinstance(rows, Mapping) else rows
    try:
        return tuple((str(name), (float(low), float(high))) for name, (low, high) in pairs)
    except (TypeError, ValueError):
        raise SettingsError(
            f"first_run_bounds must pair each name with (low, high); got {rows!r}", "first_run_bounds"
        ) from None


def _float_tuple(values, name):
    """``values`` as a tuple of floats (one per parameter), None kept; a SettingsError naming ``name`` otherwise."""
    if values is None:
        return None
    if isinstance(values, (str, bytes)) or not isinstance(values, (tuple, list, np.ndarray)):
        raise SettingsError(f"{name} must be a sequence of numbers, one per parameter; got {values!r}", name)
    return tuple(_optional(float, value, name) for value in values)


def _same(a, b):
    """Equal values, NaN equal to NaN and arrays compared element by element (for :meth:`RunRecord.__eq__`)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        if not (isinstance(a, np.ndarray) and isinstance(b, np.ndarray)):
            return False
        return a.dtype == b.dtype and np.array_equal(a, b, equal_nan=a.dtype.kind in "fc")
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


@dataclasses.dataclass(frozen=True, eq=False)
class RunRecord:
    """What a run of DYNIA found out and did beside its :class:`AnalysisSettings` (``result.run``).

    Every field is None (``thesis_code`` False) where the front-end that
    made the result does not know it or it does not apply. Values are
    converted to the types below when the record is made (numpy scalars to
    Python numbers, lists to tuples); another type is a
    :class:`~dynia.errors.SettingsError` naming the field. Two records are
    equal when every field is, NaN equal to NaN and arrays element by element.

    Attributes
    ----------
    thesis_code : bool, default False
        True for a result of the port of the thesis's MATLAB code
        (:func:`dynia.reference.thesis.thesis_code_result`), not of the engine.
    model : str or None
        Class name of the model simulated (e.g. "FirstOrder").
    n_sampled : int or None
        Parameter sets drawn (``settings.n_samples`` holds those analysed).
    n_dropped : int or None
        Sets dropped because their simulation was not finite.
    n_behavioural : int or None
        Behavioural sets per window, as the flavour counts them.
    n_diverged : int or None
        :class:`~dynia.online.OnlineDynia`: sets whose simulation became non-finite.
    ic_batches : int or None
        Batches of the Monte Carlo error (``settings.ic_error``).
    target_se_reached : float or None
        ``settings.target_se``: the largest IC standard error where it matters, at the end (NaN: nowhere).
    target_se_met : bool or None
        Whether that is at most ``settings.target_se``.
    target_se_rounds : tuple of (int, float) or None
        (samples, error reached) of every round.
    n_evaluations : int or None
        Adaptive samplers: model evaluations spent.
    n_blocks : int or None
        Adaptive samplers: blocks of windows the record was split into.
    weights : ndarray (n_samples,) or None
        Adaptive samplers: importance weight of each row of ``result.samples``; read-only.
    noise_sigma : float or None
        Noise floor (:mod:`dynia.engine.noise`): standard deviation of the measurement noise fitted.
    noise_multiple : float or None
        Sampling standard deviations of the MAE that the discrimination must pass.
    noise_floor_quantile : float or None
        Population quantile of the discrimination.
    behavioural_multiple : float or None
        The same multiple for the behavioural spread.
    noise_autocorrelation : float or None
        Lag-1 autocorrelation of the residuals (NaN: not estimated).
    noise_size_factor : float or None
        Factor on the noise's effective sample size that the autocorrelation gives (1: white noise).
    record_fit : tuple of float or None
        The whole record's least-squares fit of the model, one value per
        parameter in ``result.names`` order
        (:func:`dynia.fit.record_least_squares`); the fit within the sample
        (:func:`dynia.engine.noise.record_fit`) where the least squares did
        not run.
    record_fit_se : tuple of float or None
        Its standard errors, robust to the residuals' autocorrelation (HAC,
        :mod:`dynia.fit`; inf where the record does not determine the
        parameter); None where the least squares did not run.
    record_fit_rmse : float or None
        Root mean square of its residuals.
    steady_size_factor : float or None
        The noise's own size factor for a window, read off the record fit's
        residuals where its output is steady
        (:func:`dynia.engine.noise.steady_size_factor`; NaN where it never is).
    first_run_bounds : tuple of (str, (float, float)) or None
        :func:`dynia.refine.second_run`: the first run's ranges, ``dict(...)`` of it maps name to (low, high).
    narrowed : tuple of str or None
        The parameters whose range the second run narrowed.
    narrowing_threshold : float or None
    narrowing_margin : float or None
        The ``threshold`` and ``margin`` the ranges were narrowed with.
    screened : tuple of (str, str, int, int, float) or None
        ``settings.quality``: what the screening found, one
        ``(kind, signal, start, stop, value)`` per stretch
        (:func:`dynia.quality.screen`): for "saturated" and "stuck" the
        samples ``[start, stop)`` and the value read, in the units of the
        record the run was given (after any offset the caller subtracted);
        for "quantised" the windows (steps) ``[start, stop)`` whose output
        moves by fewer than a few grid steps, and the step. An empty tuple:
        screened, nothing found; None: not screened.
    """

    thesis_code: bool = False
    model: str | None = None
    n_sampled: int | None = None
    n_dropped: int | None = None
    n_behavioural: int | None = None
    n_diverged: int | None = None
    ic_batches: int | None = None
    target_se_reached: float | None = None
    target_se_met: bool | None = None
    target_se_rounds: tuple | None = None
    n_evaluations: int | None = None
    n_blocks: int | None = None
    weights: np.ndarray | None = None
    noise_sigma: float | None = None
    noise_multiple: float | None = None
    noise_floor_quantile: float | None = None
    behavioural_multiple: float | None = None
    noise_autocorrelation: float | None = None
    noise_size_factor: float | None = None
    record_fit: tuple | None = None
    record_fit_se: tuple | None = None
    record_fit_rmse: float | None = None
    steady_size_factor: float | None = None
    first_run_bounds: tuple | None = None
    narrowed: tuple | None = None
    narrowing_threshold: float | None = None
    narrowing_margin: float | None = None
    screened: tuple | None = None

    def __post_init__(self):
        for item in dataclasses.fields(self):
            kind = {bool | None: bool, int | None: int, float | None: float}.get(item.type)
            if kind is not None:
                object.__setattr__(self, item.name, _optional(kind, getattr(self, item.name), item.name))
        object.__setattr__(self, "thesis_code", _optional(bool, self.thesis_code, "thesis_code"))
        if self.model is not None and not isinstance(self.model, str):
            raise SettingsError(f"model must be the model's class name (str); got {self.model!r}", "model")
        if self.target_se_rounds is not None:
            try:
                rounds = tuple(
                    (_optional(int, count, "target_se_rounds"), _optional(float, reached, "target_se_rounds"))
                    for count, reached in self.target_se_rounds
                )
            except (TypeError, ValueError):
                raise SettingsError(
                    f"target_se_rounds must be (samples, error) pairs; got {self.target_se_rounds!r}",
                    "target_se_rounds",
                ) from None
            object.__setattr__(self, "target_se_rounds", rounds)
        for name in ("record_fit", "record_fit_se"):
            object.__setattr__(self, name, _float_tuple(getattr(self, name), name))
        if self.first_run_bounds is not None:
            object.__setattr__(self, "first_run_bounds", _named_ranges(self.first_run_bounds))
        self._check_collections()

    def _check_collections(self):
        """The fields that hold names, entries or an array."""
        if self.narrowed is not None:
            if isinstance(self.narrowed, str) or not all(isinstance(name, str) for name in self.narrowed):
                raise SettingsError(f"narrowed must be parameter names (str); got {self.narrowed!r}", "narrowed")
            object.__setattr__(self, "narrowed", tuple(self.narrowed))
        if self.screened is not None:
            object.__setattr__(self, "screened", _screened_entries(self.screened))
        if self.weights is not None:
            weights = np.array(self.weights, dtype=float)
            if weights.ndim != 1:
                raise SettingsError(f"weights must be one per sample (1-d); got shape {weights.shape}", "weights")
            weights.flags.writeable = False
            object.__setattr__(self, "weights", weights)

    def __eq__(self, other):
        if not isinstance(other, RunRecord):
            return NotImplemented
        return all(_same(getattr(self, item.name), getattr(other, item.name)) for item in dataclasses.fields(self))

    __hash__ = None  # the weights are an array

    @classmethod
    def of(cls, model, *, n_sampled, n_dropped):
        """The record a front-end starts from: the model's class name and the samples drawn and dropped."""
        return cls(model=type(model).__name__, n_sampled=int(n_sampled), n_dropped=int(n_dropped))

    def to_dict(self):
        """The fields that are set (not None, ``thesis_code`` only when True), by name; values as held."""
        return {
            item.name: getattr(self, item.name)
            for item in dataclasses.fields(self)
            if getattr(self, item.name) is not None and not (item.name == "thesis_code" and not self.thesis_code)
        }


def _screened_entries(entries):
    """``RunRecord.screened`` as a tuple of (kind, signal, start, stop, value), or a SettingsError naming it."""
    why = "screened must hold (kind, signal, start, stop, value) entries with 0 <= start < stop"
    try:
        checked = tuple(
            (kind, signal, _optional(int, start, "screened"), _optional(int, stop, "screened"), float(value))
            for kind, signal, start, stop, value in entries
        )
    except (TypeError, ValueError):
        raise SettingsError(f"{why}; got {entries!r}", "screened") from None
    for entry in checked:
        kind, signal, start, stop, _ = entry
        if not (isinstance(kind, str) and isinstance(signal, str) and 0 <= start < stop):
            raise SettingsError(f"{why}; got {entry!r}", "screened")
    return checked


def split_overrides(front_end, overrides, *kinds):
    """The keywords ``overrides`` of a call of ``front_end``, one dict per kind (a dataclass) whose fields they name.

    The front-ends take their settings as ``**overrides`` named after the
    fields of :class:`AnalysisSettings`, some also after those of an options
    object of their own (:class:`dynia.identification.IdentifyOptions`); a
    name two kinds share goes to the first. A name no kind has is a
    :class:`~dynia.errors.SettingsError` naming it, with the closest names
    ``front_end`` takes (``difflib.get_close_matches``) and the list.

    Examples
    --------
    >>> def analyse(u, *, settings=None, **overrides):
    ...     return split_overrides(analyse, overrides, AnalysisSettings)
    >>> analyse([1.0], n=3)
    [{'n': 3}]
    >>> analyse([1.0], windw="trailing")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    dynia.errors.SettingsError: dynia.settings.analyse takes no keyword 'windw' (did you mean 'window'?); besides ...
    """
    fields = [{field.name for field in dataclasses.fields(kind)} for kind in kinds]
    split, unknown = [{} for _ in kinds], []
    for name, value in overrides.items():
        owner = next((index for index, names in enumerate(fields) if name in names), None)
        if owner is None:
            unknown.append(name)
        else:
            split[owner][name] = value
    if not unknown:
        return split
    arguments = inspect.signature(front_end).parameters.values()
    own = [argument.name for argument in arguments if argument.kind != argument.VAR_KEYWORD]
    takes = list(dict.fromkeys(own + sorted(set().union(*fields))))
    hints = []
    for name in unknown:
        close = difflib.get_close_matches(name, takes, n=3)
        hints.append(f"{name!r}" + (f" (did you mean {' or '.join(map(repr, close))}?)" if close else ""))
    lists = [
        f"{kind.__module__}.{kind.__qualname__} ({', '.join(sorted(names))})" for kind, names in zip(kinds, fields)
    ]
    raise SettingsError(
        f"{front_end.__module__}.{front_end.__qualname__} takes no keyword {', '.join(hints)}; besides its own "
        f"arguments it takes the fields of {' and of '.join(lists)}",
        unknown[0],
    )


def merged_settings(settings, overrides, *, front_end, default=None):
    """The settings of a call of ``front_end``: ``settings`` (else ``default``, else the defaults) with ``overrides``.

    The one place the front-ends merge their settings: ``overrides`` names
    settings (``split_overrides`` refuses any other name), one given
    overrides the object, one given as None is not given. ``dt`` is 1.0
    where neither gives one.
    """
    (given,) = split_overrides(front_end, overrides, AnalysisSettings)
    merged = AnalysisSettings.build(default if settings is None else settings, **given)
    # A record without a time index, and no dt given anywhere: the unit step.
    return merged if merged.dt is not None else merged.replace(dt=1.0)


def merged_options(kind, options, given):
    """``options`` (a ``kind``; None: its defaults) with the keywords ``given`` in, None a value like any other."""
    if options is None:
        options = kind()
    elif not isinstance(options, kind):
        raise SettingsError(f"options must be a {kind.__module__}.{kind.__qualname__}; got {type(options).__name__}")
    return dataclasses.replace(options, **given)
