"""Parallel and distributed DYNIA on Dask: :func:`dynia.run` over the workers of a cluster.

:func:`run` takes the arguments of :func:`dynia.run` and returns the same
:class:`~dynia.result.DyniaResult`, bit for bit, but simulates and analyses on
the workers of a ``dask.distributed`` cluster: the cores of this machine by
default, or a cluster of many machines. Arrays follow the shape convention of
:mod:`dynia.engine`.

How the work is split
---------------------
The samples are drawn on the client exactly as :func:`dynia.run` draws them
(same ``rng``, same samples), then cut into chunks of ``sample_chunks``
consecutive samples, and time into chunks of ``time_chunks`` steps.

0. One task per sample chunk asks the model which of its samples simulate to
   finite output (:meth:`dynia.models.base.Model.finite_samples`); the others are
   dropped, as :func:`dynia.run` drops them.
1. The samples kept are simulated chunk by chunk of time as well: one task
   per (sample chunk, time chunk) resumes the simulation of its samples
   from the state the task of the previous time chunk left
   (:meth:`dynia.models.base.Model.simulate_span`, bit for bit one uninterrupted
   simulation), simulates the steps the time chunk's windows reach that no
   earlier task simulated, and cuts, with the engine's own code, the time
   chunk's window inputs: the absolute errors over the chunk and its halo
   for the compiled engine, the window means for the numpy engine (a
   sample's window mean depends on its own errors only, so those of a
   sample chunk are the single-process engine's). It hands on the model's
   state and the errors of the halo the next time chunk shares.
2. One task per time chunk joins these blocks of all sample chunks, in
   sample order, and runs the flavour's analysis: the behavioural set is
   selected among all samples of a window at once. MCAT's likelihood carries
   state from window to window, so for ``flavour="mcat"`` these tasks form a
   chain, each taking the state the previous one left.

Only the results, (n_params, n_steps) and (n_params, n_bins, n_steps), are
gathered on the client. Time chunks are submitted as the analysis goes,
at most two per worker thread submitted and not yet analysed, and each
chunk's blocks are released once analysed; so the cluster holds the blocks
of a few time chunks at a time, 8 x n_samples x time_chunks bytes each
(plus the halos), never a sample chunk's whole record. ``python -m
benchmarks.bench --case distributed`` runs 1e4 samples x 1e6 steps (a first-order
model, default chunks: 400 steps per time chunk) on a local cluster: a
worker's resident memory peaked at 565 MB with one worker and at 453 and
449 MB with two (limit 1 GB each). Two workers were not faster than one on
a 2-core machine shared with other jobs (load average 6): 459 s against
298 s. The workers got about 0.6 of a core in all either way (181 s of CPU
in 298 s; 157 + 91 s in 459 s), and two needed more CPU than one: each
time chunk's analysis receives the other sample chunk's block from the
other worker, and there are twice the stage-1 tasks.

A model that cannot pause and resume (``model.resumable`` false: a
:class:`~dynia.models.FunctionModel` without ``state=``, whose function
answers for the whole record at once) is still run, the old way: one task
per sample chunk simulates it over the whole record and keeps every time
chunk's block on its worker until analysed, 8 x n_samples x n_steps bytes
in all (dask spills to disk what does not fit in a worker's memory limit).

An existing cluster
-------------------
Start a scheduler on one machine and workers on every machine; the workers
need the same version of dynia and its dependencies installed (``pip install
'dynia[distributed]'``)::

    dask scheduler                                              # prints tcp://HOST:8786
    dask worker tcp://HOST:8786 --nworkers 4 --nthreads 1       # on each machine

then connect a client and pass it; :func:`run` uses it and leaves it open:

>>> from distributed import Client                          # doctest: +SKIP
>>> client = Client("tcp://HOST:8786")                      # doctest: +SKIP
>>> res = dynia.distributed.run(u, y, model, bounds, client=client,
...                             n_samples=100_000)           # doctest: +SKIP

The results equal :func:`dynia.run`'s bit for bit when every worker runs the
same numpy on the same kind of processor: numpy's vectorised ``exp``, which
discretises the models, may round differently in the last bit on processors
with other vector instructions. Without ``client``, :func:`run` starts a
local cluster of one single-threaded worker process per core and closes it
at the end; worker processes are started afresh, so a script calling it must
guard its entry point with ``if __name__ == "__main__":``.
"""

import copy
import dataclasses
import itertools
import math
import operator
import os
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from . import _checks
from .engine.flavours import compiled_engine, flavour_analysis, monte_carlo_errors
from .engine.noise import (
    RESIDUAL_CHUNK,
    add_record_errors,
    floor_fields,
    floor_settings,
    record_fit,
    record_noise_floor,
    window_points,
)
from .engine.windows import (
    ArrayErrors,
    ScaledErrors,
    StreamedErrors,
    blank_overflowed,
    error_scale,
    report_overflowed,
    window_halos,
    window_inputs,
    window_mean,
)
from .errors import DataError, DyniaError, ModelError, SettingsError
from .fit import record_least_squares
from .io.frames import unpack
from .pipeline import warn_dropped
from .progress import progress_bar, shows_progress
from .quality import screening
from .result import DyniaResult
from .sampling import sample
from .settings import SAMPLERS, RunRecord, merged_settings, parameter_box

__all__ = ["run"]


# Flavours whose analysis of a window depends on the windows before it.
_STATEFUL_FLAVOURS = ("mcat",)

# Default ceiling on the values of one time chunk's blocks: 4e6 float64 = 32 MB.
_BLOCK_VALUES = 4_000_000

# Time chunks submitted and not yet analysed, per worker thread: enough to
# keep every worker busy while the next chunk's stage 1 runs, few enough
# that the blocks waiting on the cluster stay a few time chunks' worth.
_CHUNKS_AHEAD_PER_THREAD = 2


def run(
    u,
    y,
    model,
    bounds,
    *,
    client=None,
    sample_chunks=None,
    time_chunks=None,
    settings=None,
    dt=None,
    n_samples=None,
    sampler=None,
    n=None,
    percentage=None,
    bins=None,
    conf_level=None,
    flavour=None,
    x0=None,
    rng=None,
    progress="auto",
    min_points=None,
    window=None,
    engine=None,
    ic_error=None,
    quality=None,
):
    """:func:`dynia.run` on a ``dask.distributed`` cluster, with the same result.

    Parameters
    ----------
    u, y : array_like, shape (n_steps,), or pandas Series / DataFrame
        Input and measured output; NaN in ``y`` marks a missing measurement.
        pandas objects as :func:`dynia.run` takes them
        (:func:`dynia.io.frames.unpack`): one index, whose time gives dt
        and whose dates become the result's ``timestamps``.
    model : dynia.models.Model
        The model simulated; it is sent to the workers (pickled).
    bounds : mapping of str to (low, high)
        Sampling range of every model parameter, as for :func:`dynia.run`.
    client : distributed.Client, optional
        The cluster to run on; left open. By default a local cluster of one
        single-threaded worker process per core is started and closed.
    sample_chunks : int, optional
        Samples per simulation task (default: the samples shared evenly
        among the worker threads).
    time_chunks : int, optional
        Time steps per simulation and analysis task (default: about four
        tasks per worker thread, and at most about 4e6 values per analysis
        task). Any size works, also one below the window's reach ``n``.
        Memory on the cluster grows with it (see the module docstring),
        not with the record.
    settings, dt, n_samples, n, percentage, bins, conf_level, flavour, x0, rng, progress, min_points, window
        As :func:`dynia.run`; ``settings.workers`` must be None (the
        cluster's workers do the work).
    engine : {"auto", "numba", "numpy"}, default "auto"
        As :func:`dynia.run`: the compiled kernels (simulation and windows)
        or plain numpy on the workers; "auto" takes the compiled ones where
        they cover the flavour. Results do not depend on it.
    sampler : {"uniform", "lhs", "sobol"}
        As :func:`dynia.run`; its adaptive schemes need every simulation at
        once and run on one machine only.
    ic_error : bool, default False
        As :func:`dynia.run`: the Monte Carlo standard errors ``ic_se`` and
        ``ci_se``, the batches read off in each time chunk's analysis.
        (``target_se``, ``dtype`` and ``store`` are :func:`dynia.run`'s
        only.)
    quality : bool, default True
        As :func:`dynia.run`: the record is screened on the client before
        the result is made, and ``run.screened`` records what was found.

    Returns
    -------
    DyniaResult
        Equal to ``dynia.run``'s with the same arguments, whatever the chunk
        sizes: ``ic``, ``ci``, ``median``, ``gradient``, ``samples`` and ``settings``.
        (``dynia.run``'s ``workers``, its threads, has no counterpart here:
        the cluster's workers do the work.)

    Raises
    ------
    ImportError
        If ``dask.distributed`` is not installed.
    TypeError
        If ``client`` is not a ``distributed.Client``.
    ValueError
        For a bad argument, as :func:`dynia.run`, or a chunk size that is
        not a whole number >= 1. Errors of a simulation on a worker name the
        sample chunk, since they count samples from its start.

    Examples
    --------
    >>> import numpy as np, dynia, dynia.distributed
    >>> from distributed import Client, LocalCluster
    >>> u = np.r_[np.zeros(20), np.full(60, 1.0)]
    >>> y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
    >>> bounds = {"K": (0, 7), "T": (0, 7)}
    >>> with LocalCluster(n_workers=2, processes=False, dashboard_address=None) as cluster, \\
    ...         Client(cluster) as client:
    ...     res = dynia.distributed.run(u, y, dynia.models.FirstOrder(), bounds, client=client,
    ...                                 sample_chunks=700, time_chunks=30, n=5, rng=1)
    >>> same = dynia.run(u, y, dynia.models.FirstOrder(), bounds, n=5, rng=1)
    >>> np.array_equal(res.ic, same.ic) and np.array_equal(res.gradient, same.gradient)
    True
    """
    distributed = _import_distributed()
    if client is not None and not isinstance(client, distributed.Client):
        raise TypeError(
            f"client must be a distributed.Client, or None for a local cluster; got {type(client).__name__}"
        )
    # pandas in, as dynia.run takes it: a time index gives dt (so before the settings), dates the result's time axis.
    u, y, dt, timestamps = unpack(u, y, dt if dt is not None else getattr(settings, "dt", None))
    u, y = _checks.record(u, y, n_inputs=model.n_inputs)
    settings = merged_settings(settings, locals())
    progress = shows_progress(progress)
    settings.require(
        "dynia.distributed.run",
        sampler=SAMPLERS,
        workers=(None,),
        target_se=(None,),
        dtype=("float64",),
        store=(None,),
        why="the adaptive schemes run on one machine, as do target_se and results stored as they are produced: "
        "use dynia.run; the cluster's workers are its threads",
    )
    names, box = parameter_box(bounds, model.names, type(model).__name__)
    settings.check_record(y.size)
    windows = _Windows(
        *window_halos(settings.n, settings.window),
        settings.min_points,
        compiled_engine(settings.engine, settings.flavour),
        error_scale(y),
    )
    if sample_chunks is not None:
        sample_chunks = _checks.whole_number(sample_chunks, "sample_chunks", minimum=1)
    if time_chunks is not None:
        time_chunks = _checks.whole_number(time_chunks, "time_chunks", minimum=1)
    samples = sample(settings.sampler, settings.n_samples, box, _checks.generator(rng))
    model_order = [names.index(name) for name in model.names]
    # simulate_chunks checks u, dt and x0 (and the model's constraints on the
    # first sample) when called, so mistakes surface here, before any cluster.
    model.simulate_chunks(samples[:1, model_order], u, dt=settings.dt, x0=settings.x0)

    with _connected(client, distributed) as client, _worker_loss_explained(client, distributed) as need:
        samples, flavour_impl, analysed, totals = _on_cluster(
            client,
            need,
            model,
            u,
            y,
            box,
            samples,
            model_order,
            settings,
            windows,
            (sample_chunks, time_chunks),
            progress,
        )
    result = _result(u, y, model, names, box, samples, settings, flavour_impl, windows, analysed, totals)
    result = record_least_squares(result, u, y, model)
    return result if timestamps is None else dataclasses.replace(result, timestamps=timestamps)


def _on_cluster(client, need, model, u, y, box, samples, model_order, settings, windows, chunk_sizes, progress):
    """Stages 0 to 2 on the cluster: the samples kept, the flavour, the analysed windows and the record totals.

    ``chunk_sizes`` are the sample and time chunks given (None: set here for
    the cluster's worker threads); ``need`` is filled with what one time
    chunk needs (:func:`_worker_loss_explained`).
    """
    sample_chunks, time_chunks = chunk_sizes
    threads = max(1, sum(client.nthreads().values()))
    sample_chunks = sample_chunks or math.ceil(settings.n_samples / threads)
    # What one time chunk needs, should a worker be lost before the chunks are set (as below, all sets kept).
    need.update(
        samples=settings.n_samples,
        steps=(time_chunks or _time_chunks(y.size, threads, settings.n_samples)) + windows.slots - 1,
    )
    u_data, y_data = client.scatter([u, y], broadcast=True, hash=False)
    samples = _finite_samples(client, model, samples, model_order, u_data, u, settings, sample_chunks)
    flavour_impl = flavour_analysis(
        settings.flavour,
        windows.compiled,
        samples,
        box,
        settings.percentage,
        settings.bins,
        settings.conf_level,
        settings.min_points,
        ic_error=settings.ic_error,
    )
    time_chunks = time_chunks or _time_chunks(y.size, threads, samples.shape[0])
    need.update(samples=samples.shape[0], steps=time_chunks + windows.slots - 1)
    row_chunks = list(_scatter_rows(client, samples[:, model_order], sample_chunks))
    if model.resumable:
        blocks = _ChainedBlocks(client, model, row_chunks, u_data, y_data, settings, windows)
    else:
        blocks = _WholeRecordBlocks(client, model, row_chunks, u_data, y_data, settings, windows, y.size, time_chunks)
    analysed = _analyse_on_cluster(
        client,
        blocks,
        flavour_impl,
        windows,
        [(start, min(start + time_chunks, y.size)) for start in range(0, y.size, time_chunks)],
        stateful=settings.flavour in _STATEFUL_FLAVOURS,
        progress=progress,
        ahead=_CHUNKS_AHEAD_PER_THREAD * threads,
    )
    # Every sample's record total absolute error, added step by step as dynia.run adds them.
    totals = np.concatenate(client.gather(blocks.totals()))
    return samples, flavour_impl, analysed, totals


def _result(u, y, model, names, box, samples, settings, flavour_impl, windows, analysed, totals):
    """The result of the analysed windows, with the noise floor and the same record as dynia.run's."""
    ic, ci, median, gradient, best, upper, threshold, ic_se, ci_se, overflowed = analysed
    n_steps, n_samples, dt = y.size, settings.n_samples, settings.dt
    report_overflowed(overflowed, best, np.arange(n_steps) * float(dt), y)
    for extreme in (best, upper, threshold):
        extreme /= windows.scale  # exact: a power of two
    # The record-best set and its neighbours are simulated once more here, as dynia.run does.
    model_order = [names.index(name) for name in model.names]
    fit = record_fit(
        y,
        samples,
        box,
        totals,
        lambda rows: model.simulate_chunks(
            samples[rows][:, model_order], u, dt=dt, x0=settings.x0, chunk_steps=RESIDUAL_CHUNK
        ),
    )
    floor = record_noise_floor(
        best,
        upper,
        threshold,
        window_points(y, windows.before, windows.after),
        windows.slots,
        len(names),
        settings.percentage,
        samples.shape[0],
        fit,
    )
    # The same record as dynia.run's: the settings asked for, then what the analysis did.
    recorded = dataclasses.replace(
        RunRecord.of(model, n_sampled=n_samples, n_dropped=n_samples - samples.shape[0]),
        n_behavioural=flavour_impl.count,
        ic_batches=flavour_impl.batches if settings.ic_error else None,
        screened=screening(u, y, settings),
        **floor_settings(floor),
    )
    return DyniaResult(
        names=tuple(names),
        samples=samples,
        bounds=box,
        time=np.arange(n_steps) * float(dt),
        ic=ic,
        ci=ci,
        median=median,
        gradient=gradient,
        bin_centres=flavour_impl.bin_centres,
        settings=settings.replace(n_samples=samples.shape[0], engine="numba" if windows.compiled else "numpy"),
        run=recorded,
        ic_se=ic_se,
        ci_se=ci_se,
        **floor_fields(floor),
    )


def _time_chunks(n_steps, threads, n_samples):
    """Steps per time chunk when none are given: about four per worker thread, at most ``_BLOCK_VALUES`` values."""
    return max(1, min(math.ceil(n_steps / (4 * threads)), _BLOCK_VALUES // n_samples))


def _finite_samples(client, model, samples, model_order, u_data, u, settings, sample_chunks):
    """Stage 0: the samples whose simulation is finite over the record; the others dropped (and warned about)."""
    finite = np.concatenate(
        client.gather(
            [
                client.submit(_finite_rows, model, rows, u_data, settings, first, pure=False)
                for first, rows in _scatter_rows(client, samples[:, model_order], sample_chunks)
            ]
        )
    )
    n_samples = settings.n_samples
    if not finite.any():
        raise ModelError(
            f"the simulation of every one of the {n_samples} parameter sets overflowed; "
            "check the model and the parameter ranges"
        )
    samples = samples[finite]
    warn_dropped(int(n_samples - samples.shape[0]), n_samples, u)
    return samples


def _analyse_on_cluster(client, blocks, flavour, windows, spans, *, stateful, progress, ahead):
    """Stage 2, fed by stage 1: one task per time chunk; its results (with best, upper, threshold MAE) to the client.

    ``blocks(start, stop)`` submits stage 1 of the time chunk [start, stop)
    and returns the futures of its outputs, (block, what it hands on) per
    sample chunk, in sample order; it is called in time order. At most
    ``ahead`` time chunks are submitted and not yet analysed, so the blocks
    on the cluster stay those of a few time chunks; a chunk's blocks are
    released once it is analysed. A stateful
    flavour's tasks form a chain in time order, each starting from the
    state the one before left.
    """
    from distributed import as_completed

    n_params = flavour.bin_centres.shape[0]
    n_steps = spans[-1][1]
    ic = np.empty((n_params, n_steps))
    ci = np.empty((n_params, n_steps, 2))
    median = np.empty((n_params, n_steps))
    gradient = np.empty((n_params, flavour.n_bins, n_steps))
    best, upper, threshold = np.empty(n_steps), np.empty(n_steps), np.empty(n_steps)
    overflowed = np.zeros(n_steps, dtype=bool)
    batched = getattr(flavour, "batches", 0) > 0
    ic_se = np.empty((n_params, n_steps)) if batched else None
    ci_se = np.empty((n_params, n_steps, 2)) if batched else None
    state = client.scatter(flavour, hash=False)
    chunk_spans = {}
    finished = as_completed(loop=client.loop)

    def submit(start, stop):
        nonlocal state
        analysed = client.submit(_analyse_stage_one, state, windows, blocks(start, stop), stop - start, pure=False)
        chunk = client.submit(operator.getitem, analysed, 0, pure=False)
        chunk_spans[chunk] = (start, stop)
        finished.add(chunk)
        if stateful:
            state = client.submit(operator.getitem, analysed, 1, pure=False)

    waiting = iter(spans)
    for start, stop in itertools.islice(waiting, ahead):
        submit(start, stop)
    bar = progress_bar(progress, total=len(spans), desc="DYNIA windows", unit="chunk")
    for future in finished:
        start, stop = chunk_spans.pop(future)
        results = future.result()
        overflowed[start:stop] = blank_overflowed(results)
        ic[:, start:stop], ci[:, start:stop], gradient[:, :, start:stop] = results.ic, results.ci, results.gradient
        median[:, start:stop] = results.median
        best[start:stop], upper[start:stop], threshold[start:stop] = results.best, results.upper, results.threshold
        if batched:
            ic_se[:, start:stop], ci_se[:, start:stop] = monte_carlo_errors(results.batch_ic, results.batch_ci)
        following = next(waiting, None)
        if following is not None:
            submit(*following)
        if bar is not None:
            bar.update()
    if bar is not None:
        bar.close()
    return ic, ci, median, gradient, best, upper, threshold, ic_se, ci_se, overflowed


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise ImportError("dynia.distributed needs dask.distributed: pip install 'dynia[distributed]'") from None
    return distributed


@contextmanager
def _connected(client, distributed):
    """The client given, left open, or a client of a new local cluster, closed on exit."""
    if client is not None:
        yield client
        return
    # Port 0: a free port for the scheduler's web server, which otherwise
    # wants 8787 and warns when another cluster holds it.
    with (
        distributed.LocalCluster(
            n_workers=os.cpu_count() or 1, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster, set_as_default=False) as own,
    ):
        yield own


@contextmanager
def _worker_loss_explained(client, distributed):
    """Turn a worker lost mid-run (killed at its memory limit, mostly) into a SettingsError saying what one chunk needs.

    Yields a dict the caller fills with ``samples`` and ``steps``, the size
    of one time chunk's errors and halo, which stage 2 joins on one worker.
    """
    limits = [info.get("memory_limit") or 0 for info in client.scheduler_info().get("workers", {}).values()]
    need = {}
    try:
        yield need
    except (
        distributed.KilledWorker,
        distributed.comm.CommClosedError,
        distributed.client.FutureCancelledError,
    ) as error:
        if limits and all(limits):
            limit = f"the smallest worker memory limit is {min(limits) / 2**20:.0f} MB"
        else:
            limit = "the workers have no memory limit, so the machine's memory ran out"
        chunk = ""
        if need:
            # The joined errors, their window sums and the flavour's working copies: about three arrays of it.
            size = 3 * 8 * need["samples"] * need["steps"] / 2**20
            chunk = (
                f"; one time chunk ({need['samples']} samples x {need['steps']} steps with its halo) needs about "
                f"{size:.0f} MB on one worker"
            )
        raise SettingsError(
            f"a worker of the cluster was lost ({type(error).__name__}), most likely killed at its memory limit: "
            f"{limit}{chunk}; give a smaller time_chunks or sample_chunks, or the workers more memory",
            "time_chunks",
        ) from None


def _scatter_rows(client, rows, size):
    """Send consecutive chunks of ``size`` rows to the workers: (first row, future) pairs."""
    firsts = range(0, rows.shape[0], size)
    return zip(firsts, client.scatter([rows[first : first + size] for first in firsts], hash=False))


@contextmanager
def _sample_chunk_context(first, count):
    """Name the sample chunk in a model's error, whose sample numbers count from its start."""
    try:
        yield
    except DyniaError as error:
        raise type(error)(
            f"in the sample chunk of samples {first} to {first + count - 1} "
            f"(sample numbers below count from {first}): {error}"
        ) from error


def _finite_rows(model, params, u, settings, first):
    """Stage 0: which samples of one chunk simulate to finite output, (rows,) bool."""
    with _sample_chunk_context(first, params.shape[0]):
        return model.finite_samples(params, u, dt=settings.dt, x0=settings.x0)


@dataclass(frozen=True)
class _Windows:
    """The windows' reach and the engine's path from simulated errors to a flavour's analysis.

    The compiled path hands the analysis the absolute errors of a time
    chunk and its halo, time-major (m + slots - 1, rows), and forms the
    window sums inside its kernel; the numpy path hands it the window means
    (m, rows). Either block has the samples on axis 1, so the blocks of
    consecutive sample chunks join along it.
    """

    before: int
    after: int
    min_points: int
    compiled: bool
    scale: float = 1.0  # the errors' factor, dynia.engine.windows.error_scale

    @property
    def slots(self):
        """Steps per window."""
        return self.before + self.after + 1

    def block(self, errors, start, stop, n_steps, totals):
        """One sample chunk's input to the windows at steps [start, stop), with its measured counts.

        The chunk's own steps' errors are added to ``totals``, its samples' record totals, as the engine adds them.
        """
        if self.scale != 1.0:
            errors = ScaledErrors(errors, self.scale)
        window_errors, measured = window_inputs(
            errors, start, stop, self.before, self.after, n_steps, time_major=self.compiled
        )
        m = stop - start
        add_record_errors(
            totals,
            window_errors[self.before : self.before + m]
            if self.compiled
            else window_errors[:, self.before : self.before + m].T,
        )
        if self.compiled:
            return window_errors, measured
        return window_mean(window_errors, measured, stop - start, self.slots)

    def analyse(self, flavour, blocks, m):
        """The flavour's :class:`~dynia.engine.flavours.WindowResults` of m windows from every sample chunk's block."""
        joined = np.concatenate([block for block, _ in blocks], axis=1)
        counts = blocks[0][1]
        if self.compiled:
            return flavour.analyse_rows(joined, counts, m, self.slots)
        return flavour.analyse(joined, counts >= self.min_points)


class _ChainedBlocks:
    """Stage 1 for a model that can pause and resume: per time chunk, one task per sample chunk.

    The task of a sample chunk's time chunk resumes from what the task of
    its previous time chunk handed on, so the tasks of a sample chunk form
    a chain in time and none simulates more than a time chunk and its halo.
    """

    def __init__(self, client, model, row_chunks, u, y, settings, windows):
        self._client = client
        self._arguments = (model, u, y, settings, windows)
        self._row_chunks = row_chunks
        self._previous = [None] * len(row_chunks)

    def __call__(self, start, stop):
        """Submit the time chunk [start, stop), the one after the last submitted; its outputs' futures."""
        # The tasks take the whole output of the one before and pick what they need on the worker:
        # splitting the outputs on the cluster would double the number of tasks.
        self._previous = [
            self._client.submit(
                _chained_window_inputs, rows, first, previous, start, stop, *self._arguments, pure=False
            )
            for (first, rows), previous in zip(self._row_chunks, self._previous)
        ]
        return self._previous

    def totals(self):
        """Futures of every sample chunk's record totals, once the last time chunk is submitted."""
        return [self._client.submit(_handed_totals, previous, pure=False) for previous in self._previous]


def _handed_totals(output):
    """The record totals a chained task hands on."""
    return output[1][2]


def _chained_window_inputs(params, first, previous, start, stop, model, u, y, settings, windows):
    """Stage 1, resumable: one sample chunk's window inputs at steps [start, stop), and what to hand on.

    ``previous`` is the output of the task of the previous time chunk (None
    for the first), whose second part it handed on: the simulation's state,
    the errors from where this chunk's windows reach back to up to that
    state's step and the samples' record totals of absolute error so far.
    The steps the windows reach beyond it are simulated here. Errors are
    kept time-major, the compiled windows' layout, which a linear model
    simulates in without transposing.
    """
    n_steps = y.size
    reach_back, reach_ahead = max(start - windows.before, 0), min(stop + windows.after, n_steps)
    with _sample_chunk_context(first, params.shape[0]):
        if previous is None:
            state = model.start_simulation(params, u, dt=settings.dt, x0=settings.x0)
            errors = np.empty((0, params.shape[0]))
            totals = np.zeros(params.shape[0])
        else:
            _, (state, errors, totals) = previous
            totals = totals.copy()  # the previous output may be shared with other tasks
        if reach_ahead > state.step:
            simulated_from = state.step
            sims, state = model.simulate_span(state, u, reach_ahead, time_major=True)
            try:
                # The transposed view makes the errors come out time-major (numpy keeps the input's layout).
                fresh = ArrayErrors(y[simulated_from:reach_ahead], sims.T).columns(0, sims.shape[0]).T
            except DataError as error:
                raise DataError(f"{error} (steps counted from step {simulated_from})") from error
            errors = np.concatenate([errors, fresh]) if errors.shape[0] else fresh
        block = windows.block(_ErrorSpan(y, reach_back, errors), start, stop, n_steps, totals)
        shared = max(stop - windows.before, 0)  # where the next time chunk's windows reach back to
        # A copy, so that the errors of this chunk are freed with its block.
        return block, (state, errors[shared - reach_back :].copy(), totals)


class _ErrorSpan:
    """Time-major absolute errors of consecutive steps from ``first`` on, an error source of ``window_inputs``."""

    def __init__(self, y, first, errors):
        self.y = y
        self._first = first
        self._errors = errors

    def rows(self, start, stop):
        """Errors for times [start, stop), time-major: shape (stop - start, n_samples)."""
        return self._errors[start - self._first : stop - self._first]

    def columns(self, start, stop):
        """Errors for times [start, stop), shape (n_samples, stop - start)."""
        return np.ascontiguousarray(self.rows(start, stop).T)


class _WholeRecordBlocks:
    """Stage 1 for a model that cannot pause: one task per sample chunk over the whole record.

    Every time chunk's blocks are split off at once, so that each is
    released after its analysis.
    """

    def __init__(self, client, model, row_chunks, u, y, settings, windows, n_steps, time_chunks):
        whole_record = [
            client.submit(
                _whole_record_window_inputs, model, rows, u, y, settings, windows, time_chunks, first, pure=False
            )
            for first, rows in row_chunks
        ]
        self._time_chunks = time_chunks
        n_chunks = math.ceil(n_steps / time_chunks)
        self._by_time = {
            k: [client.submit(operator.getitem, inputs, k, pure=False) for inputs in whole_record]
            for k in range(n_chunks)
        }
        self._totals = [client.submit(operator.getitem, inputs, n_chunks, pure=False) for inputs in whole_record]

    def __call__(self, start, stop):
        """The outputs' futures of the time chunk [start, stop), handed out once."""
        return self._by_time.pop(start // self._time_chunks)

    def totals(self):
        """Futures of every sample chunk's record totals of absolute error."""
        return self._totals


def _whole_record_window_inputs(model, params, u, y, settings, windows, time_chunks, first):
    """Stage 1, not resumable: simulate one sample chunk over the record; its window inputs per time chunk.

    Each time chunk's block comes with nothing to hand on, as a chained task's output does; the samples'
    record totals of absolute error follow the last.
    """
    n_steps = y.size
    totals = np.zeros(params.shape[0])
    with _sample_chunk_context(first, params.shape[0]):
        errors = StreamedErrors(
            y,
            model.simulate_chunks(params, u, dt=settings.dt, x0=settings.x0, chunk_steps=time_chunks),
            params.shape[0],
        )
        inputs = [
            (windows.block(errors, start, min(start + time_chunks, n_steps), n_steps, totals), None)
            for start in range(0, n_steps, time_chunks)
        ]
    return [*inputs, totals]


def _analyse_stage_one(flavour, windows, outputs, m):
    """Stage 2 on the outputs of stage 1, (block, what it hands on) per sample chunk: their blocks analysed."""
    return _analyse_time_chunk(flavour, windows, [block for block, _ in outputs], m)


def _analyse_time_chunk(flavour, windows, blocks, m):
    """Stage 2: the analysis of one time chunk's m windows, from the blocks of all sample chunks.

    Returns the chunk's :class:`~dynia.engine.flavours.WindowResults` and the flavour after it, whose
    state the next chunk of a stateful flavour starts from.
    """
    # A worker hands the same object to every task that needs it; analysing
    # must not change the state other tasks start from.
    flavour = copy.deepcopy(flavour)
    return windows.analyse(flavour, blocks, m), flavour
