"""Sources of absolute errors ``|y - sim|`` that the moving window reads, a range of time at a time.

A source has ``y`` (the record), ``rows(start, stop)`` (time-major errors,
(stop - start, n_samples)) and, where it has them, ``columns(start, stop)``
(n_samples, stop - start) or, for a source that forms the window sums
itself, ``window_sums`` (``fused`` is then True). :class:`ArrayErrors` reads
a whole array of simulations, :class:`StreamedErrors` pulls them chunk by
chunk, :class:`ScaledErrors` multiplies another source's errors by the
error scale (:func:`dynia.engine.windows.error_scale`); the compiled
engine's :class:`~dynia.engine.kernels.driver.CompiledErrors` simulates the
linear models itself.
"""

import numpy as np

from ..errors import DataError, SettingsError

__all__ = ["StreamedErrors", "ArrayErrors", "ScaledErrors"]


class StreamedErrors:
    """Absolute errors ``|y - sim|`` over a sliding range of time, pulled from simulation chunks.

    Missing measurements (NaN in y) give an error of 0. Requests must move
    forward in time; columns before a request are dropped.
    """

    def __init__(self, y, sim_chunks, n_samples):
        self.y = y
        self._chunks = iter(sim_chunks)
        self._n_samples = n_samples
        self._start = 0  # time of the first buffered column
        self._buffer = np.zeros((n_samples, 0))

    def columns(self, start, stop):
        """Errors for times [start, stop), shape (n_samples, stop - start)."""
        self._buffer = self._buffer[:, start - self._start :]
        self._start = start
        pieces = [self._buffer]
        buffered = self._buffer.shape[1]
        while self._start + buffered < stop:
            chunk = self._next_chunk(self._start + buffered)
            pieces.append(chunk)
            buffered += chunk.shape[1]
        if len(pieces) > 1:
            self._buffer = np.concatenate(pieces, axis=1)
        return self._buffer[:, : stop - start]

    def rows(self, start, stop):
        """Errors for times [start, stop), time-major: shape (stop - start, n_samples)."""
        return np.ascontiguousarray(self.columns(start, stop).T)

    def _next_chunk(self, at):
        try:
            sims = np.asarray(next(self._chunks), dtype=float)
        except StopIteration:
            raise SettingsError(f"the simulation ended at step {at}, before the {self.y.size} steps of y") from None
        if sims.ndim != 2 or sims.shape[0] != self._n_samples or sims.shape[1] == 0:
            raise SettingsError(
                f"a simulation chunk at step {at} has shape {sims.shape}; expected ({self._n_samples}, m>0)"
            )
        if at + sims.shape[1] > self.y.size:
            raise SettingsError(f"the simulation runs past the {self.y.size} steps of y")
        return _absolute_errors(self.y[at : at + sims.shape[1]], sims, at)


class ArrayErrors:
    """The same interface over a whole (n_samples, n_steps) array of simulations."""

    def __init__(self, y, sims):
        self.y = y
        self._sims = sims

    def columns(self, start, stop):
        return _absolute_errors(self.y[start:stop], self._sims[:, start:stop], start)

    def rows(self, start, stop):
        return np.ascontiguousarray(self.columns(start, stop).T)


class ScaledErrors:
    """An error source (``rows``; ``columns`` or ``window_sums`` where it has them), errors times ``scale``."""

    def __init__(self, errors, scale):
        self.y = errors.y
        self.scale = scale
        self._errors = errors
        self.fused = getattr(errors, "fused", False)

    def rows(self, start, stop):
        return self._errors.rows(start, stop) * self.scale

    def window_sums(self, start, stop, halos, totals, scale=1.0):
        """The fused source's window sums (see ``CompiledErrors.window_sums``), its errors scaled."""
        return self._errors.window_sums(start, stop, halos, totals, scale * self.scale)

    def columns(self, start, stop):
        return self._errors.columns(start, stop) * self.scale


def _absolute_errors(measured, sims, at):
    """|measured - sims| with missing measurements (NaN) giving 0; rejects non-finite sims."""
    bad = ~np.isfinite(sims)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise DataError(f"sims holds a non-finite value for sample {row} at step {at + col}")
    errors = np.subtract(sims, measured)  # |s - y| == |y - s| bit for bit
    np.abs(errors, out=errors)
    missing = np.isnan(measured)
    if missing.any():
        errors[:, missing] = 0.0
    return errors
