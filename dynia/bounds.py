"""The parameter box: the sampling range of every model parameter, checked against the model once.

Every front-end (:func:`dynia.run`, :func:`dynia.adaptive.adaptive_run`,
:func:`dynia.distributed.run`, :class:`dynia.online.OnlineDynia`,
:func:`dynia.identify`, :func:`dynia.suggest`) takes the bounds as a mapping
of parameter name to (low, high); :func:`parameter_box` turns it into the
names in the order given and an (n_params, 2) array, or one
:class:`~dynia.errors.SettingsError` saying what is wrong with it.

Examples
--------
>>> from dynia.bounds import parameter_box
>>> names, box = parameter_box({"T": (0, 7), "K": (0, 2)}, ["K", "T"])
>>> names, box.tolist()
(['T', 'K'], [[0.0, 7.0], [0.0, 2.0]])
"""

import math
from collections.abc import Mapping

import numpy as np

from .errors import SettingsError
from .settings import MAX_PARAMETER

__all__ = ["parameter_box"]


def parameter_box(bounds, model_names, model_label="the model"):
    """Names in the order given and an (n_params, 2) box; every model parameter exactly once.

    Parameters
    ----------
    bounds : mapping of str to (low, high)
    model_names : sequence of str
        The model's parameter names.
    model_label : str
        How messages name the model.

    Returns
    -------
    names : list of str
    box : ndarray (n_params, 2)
    """
    if not isinstance(bounds, Mapping):
        raise SettingsError(
            f"bounds must map each parameter name to (low, high), e.g. {{'K': (0, 7)}}; got {type(bounds).__name__}"
        )
    names = [str(name) for name in bounds]
    unknown = [name for name in names if name not in model_names]
    missing = [name for name in model_names if name not in names]
    if unknown or missing:
        raise SettingsError(
            f"bounds must name every parameter of {model_label} {list(model_names)} once"
            + (f"; unknown: {unknown}" if unknown else "")
            + (f"; missing: {missing}" if missing else "")
        )
    rows = []
    for name in names:
        pair = bounds[name]
        try:
            if isinstance(pair, (str, bytes)):
                raise TypeError
            low, high = (float(value) for value in pair)
        except (TypeError, ValueError):
            raise SettingsError(f"bounds[{name!r}] must be a (low, high) pair of numbers; got {pair!r}") from None
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise SettingsError(f"bounds[{name!r}]: need finite low < high; got ({low}, {high})")
        if max(abs(low), abs(high)) > MAX_PARAMETER:
            raise SettingsError(
                f"bounds[{name!r}] = ({low:g}, {high:g}) reaches beyond {MAX_PARAMETER:g}; no "
                "parameter of a process model is that large, and the arithmetic on such values "
                "overflows"
            )
        rows.append((low, high))
    return names, np.array(rows)
