"""Memory: what a run of :func:`dynia.run` takes, what the machine has, and sizes in words.

:func:`run_memory` estimates the bytes a uniform run adds: the moving
window holds about four arrays of n_samples x (chunk + 2n) values, plus the
samples, plus the whole simulation for a model that does not stream; within
10 % of the growth of the peak memory measured with 50 000 samples on the
heater record and 400 000 on HYMOD, to which compiling the engine on first
use adds about 150 MB. :func:`available_memory` says what the machine has
free, :func:`parse_size` reads a size given in words ("4GB") and
:func:`size_text` writes one for a person. :func:`dynia.suggestion.suggest`
holds its pilot run to a limit with them.
"""

import math
import os

from . import _checks
from .engine.windows import default_chunk_steps
from .errors import SettingsError

__all__ = ["run_memory", "available_memory", "parse_size", "size_text"]

_BYTES = {"": 1, "b": 1, "k": 1e3, "kb": 1e3, "m": 1e6, "mb": 1e6, "g": 1e9, "gb": 1e9, "t": 1e12, "tb": 1e12}
_BYTES.update({"kib": 2**10, "mib": 2**20, "gib": 2**30, "tib": 2**40})
# run_memory: live arrays of n_samples x (chunk + 2n) float64 in the moving window (the errors pulled
# from the simulation, their padded and transposed copies, the chunks in flight), measured with 1 and 2
# workers on the heater (n = 85) and HYMOD (n = 3) pilots; and float64 values kept per sample besides
# its parameters (states, costs, ranks).
_WINDOW_ARRAYS = 4
_PER_SAMPLE_VALUES = 16


def parse_size(text, name="max_memory"):
    """Bytes in a size such as ``"4GB"``, ``"512MiB"``, ``"2e9"`` or ``2e9`` (a bare number is bytes).

    kB, MB, GB, TB (and k, M, G, T) are powers of 1000; KiB, MiB, GiB, TiB
    powers of 1024. Raises :class:`~dynia.errors.SettingsError` naming
    ``name`` for anything else, or a size that is not positive and finite.

    >>> parse_size("4GB"), parse_size("1.5 MiB"), parse_size(1000)
    (4000000000.0, 1572864.0, 1000.0)
    """
    match = _checks.QUANTITY.match(str(text))
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


def size_text(size):
    """Bytes for a person, to two significant digits.

    >>> size_text(3.2e9), size_text(1500), size_text(12)
    ('3.2 GB', '1.5 kB', '12 B')
    """
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if size >= scale:
            return f"{size / scale:.2g} {unit}"
    return f"{size:.0f} B"
