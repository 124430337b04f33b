"""Plain JSON values from numbers and containers: NaN and inf become null."""

import math
import numbers
from collections.abc import Mapping

__all__ = ["json_number", "json_ready"]


def json_number(value):
    """``value`` as a float, or None when it is not finite (JSON has no NaN).

    >>> json_number(2), json_number(float("nan"))
    (2.0, None)
    """
    value = float(value)
    return value if math.isfinite(value) else None


def json_ready(value):
    """Mappings, lists and tuples with every non-integer real made a :func:`json_number`."""
    if isinstance(value, Mapping):
        return {str(key): json_ready(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(item) for item in value]
    if isinstance(value, numbers.Real) and not isinstance(value, (bool, numbers.Integral)):
        return json_number(value)
    return value
