"""The thesis's "second run", automated: narrow what is identified, re-analyse the rest.

In every example of the thesis (3.1.1, 3.1.2, 3.1.3) a first DYNIA run
identifies some parameters well; their ranges are then narrowed by hand and
a second run, with the same number of samples, sees the other parameters
far more sharply. :func:`narrowed_bounds` makes that choice from the first
result and :func:`second_run` does both runs.

The rule: a window counts for a parameter when it is informative about it
(:meth:`dynia.result.DyniaResult.informative_windows`: IC at least
``ic_threshold``, above the noise floor, behavioural set not tied within
noise), its band keeps clear of the range's bounds
(:func:`dynia.structure.clear_of_bounds`) and it belongs to a run of at
least ``min_windows`` such windows in a row. A parameter is identified when
it has informative windows and all their bands overlap, i.e. they agree on
where the parameter lies. Its new range is that common
part of the bands, widened by ``margin`` times its width on each side and
clipped to the old range. The tests matter: windows where the output is only
noise rank samples by sub-noise differences and can show a high IC with a
band anywhere, most often pressed against a bound (thesis example 1 after
the final step puts the time constant near 0 that way); a lone window, or a
few next to missing data, can be sharp by chance; and a parameter whose band
drifts between informative windows points to a model-structure problem
(thesis 4.4). None of them should narrow a range.
"""

import dataclasses
import math
import numbers

import numpy as np

from . import _checks
from .errors import SettingsError
from .pipeline import run
from .segments import mask_to_segments
from .settings import IC_THRESHOLD
from .structure import clear_of_bounds

__all__ = [
    "narrowed_bounds",
    "second_run",
]


def narrowed_bounds(result, bounds, *, ic_threshold=IC_THRESHOLD, margin=0.5, min_windows=3):
    """New ranges from a first run: the agreed band of each identified parameter.

    Parameters
    ----------
    result : DyniaResult
        The first run.
    bounds : mapping of str to (low, high)
        Its ranges.
    ic_threshold : float in [0, 1], default :data:`dynia.settings.IC_THRESHOLD` (0.5)
        IC from which a window is informative about a parameter
        (:meth:`~dynia.result.DyniaResult.informative_windows`: windows
        below the noise floor, or whose behavioural set ties within noise,
        never are: their band ranks noise).
    margin : float >= 0
        Share of the width of the bands' common part added on each side.
    min_windows : int >= 1
        Informative windows must come in runs of at least this many.

    Returns
    -------
    new_bounds : dict
        Every parameter's range, narrowed where identified, in ``bounds`` order.
    narrowed : list of str
        The parameters narrowed.

    Examples
    --------
    >>> import numpy as np, dynia
    >>> u = dynia.synthetic.example_firstorder_input()
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
    >>> first = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)}, rng=1)
    >>> new, narrowed = narrowed_bounds(first, {"K": (0, 7), "T": (0, 7)})
    >>> narrowed
    ['K', 'T']
    >>> bool(new["K"][0] < 2 < new["K"][1] and new["T"][0] < 3 < new["T"][1])
    True
    >>> narrowed_bounds(first, {"K": (0, 7), "T": (0, 7)}, ic_threshold=0.75)[1]  # T's windows at 0.75 disagree
    ['K']
    """
    min_windows = _checks.whole_number(min_windows, "min_windows", minimum=1)
    margin = check_margin(margin)
    if set(bounds) != set(result.names):
        raise SettingsError(f"bounds name {sorted(bounds)} but the result has {sorted(result.names)}")
    new_bounds, narrowed = {}, []
    for name, (low, high) in bounds.items():
        p = result.index(name)
        informative = _in_long_runs(
            result.informative_windows(ic_threshold, name)[0] & clear_of_bounds(result, p), min_windows
        )
        lowers, uppers = result.ci[p, informative, 0], result.ci[p, informative, 1]
        if not informative.any() or lowers.max() > uppers.min():
            new_bounds[name] = (float(low), float(high))
            continue
        lower, upper = lowers.max(), uppers.min()
        widen = margin * (upper - lower)
        new_low, new_high = max(lower - widen, float(low)), min(upper + widen, float(high))
        if not new_low < new_high:  # a band of one value: keep a sliver around it
            sliver = 0.01 * (float(high) - float(low))
            new_low, new_high = max(new_low - sliver, float(low)), min(new_high + sliver, float(high))
        new_bounds[name] = (new_low, new_high)
        if (new_low, new_high) != (float(low), float(high)):  # a band widened to the whole range narrows nothing
            narrowed.append(name)
    return new_bounds, narrowed


def check_margin(margin):
    """The narrowing's margin as a float, finite and >= 0, or a SettingsError naming ``margin``.

    Examples
    --------
    >>> check_margin(0.5)
    0.5
    """
    if isinstance(margin, bool) or not isinstance(margin, numbers.Real) or not 0 <= margin < math.inf:
        raise SettingsError(
            f"margin must be a finite number >= 0 (an infinite one would narrow nothing); got {margin!r}", "margin"
        )
    return float(margin)


def _in_long_runs(flags, min_length):
    """``flags`` without the runs of True shorter than ``min_length``."""
    kept = np.zeros_like(flags)
    for start, stop in mask_to_segments(flags):
        if stop - start >= min_length:
            kept[start:stop] = True
    return kept


def second_run(u, y, model, bounds, *, ic_threshold=IC_THRESHOLD, margin=0.5, **options):
    """Run DYNIA, narrow the well-identified parameters, run again.

    ``options`` go to both :func:`dynia.run` calls (``rng`` too: give a
    Generator to draw different samples for the second run, or a seed to
    draw the same uniform numbers scaled to the new ranges). ``u`` and ``y``
    go to both as given, so that pandas objects are unpacked by both alike
    (:func:`dynia.io.frames.unpack`): the two runs see the same aligned
    record, dt and ``timestamps``.

    Returns
    -------
    first, second : DyniaResult
    narrowed : list of str
        The parameters whose range the second run narrowed; empty when none
        had informative windows at ``ic_threshold`` that agree (the second
        run then repeats the first's ranges).
    """
    first = run(u, y, model, bounds, **options)
    new_bounds, narrowed = narrowed_bounds(first, bounds, ic_threshold=ic_threshold, margin=margin)
    second = run(u, y, model, new_bounds, **options)
    second = dataclasses.replace(
        second,
        run=dataclasses.replace(
            second.run,
            first_run_bounds={name: tuple(map(float, pair)) for name, pair in bounds.items()},
            narrowed=narrowed,
            narrowing_threshold=ic_threshold,
            narrowing_margin=margin,
        ),
    )
    return first, second, narrowed
