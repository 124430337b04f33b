"""Parallel and distributed DYNIA on Dask: :func:`dynia.run` over the workers of a cluster.

:func:`run` takes the arguments of :func:`dynia.run` and returns the same
:class:`~dynia.result.DyniaResult`, bit for bit, but simulates and analyses on
the workers of a ``dask.distributed`` cluster: the cores of this machine by
default, or a cluster of many machines. Arrays follow the shape convention of
:mod:`dynia.engine`.

How the work is split
---------------------
The samples are drawn on the client exactly as :func:`dynia.run` draws them
(same ``rng``, same samples) and cut into chunks of ``sample_chunks``
consecutive samples; time is cut into chunks of ``time_chunks`` steps.
A window's behavioural set is selected among all samples at once, so the
analysis of a window needs every sample in one place, but the simulation
of a sample needs only its own state. Hence:

0. One task per sample chunk asks the model which of its samples simulate to
   finite output (:meth:`dynia.models.base.Model.finite_samples`); the others are
   dropped, as :func:`dynia.run` drops them.
1. The state pass: one task per sample chunk simulates the record once
   (:meth:`dynia.models.base.Model.simulate_span`, bit for bit one
   uninterrupted simulation) and keeps only every sample's state at the
   step where each time chunk's windows begin, ``n`` steps before the
   chunk (``2n`` for trailing windows), and its record total of absolute
   error, added step by step as :func:`dynia.run` adds it (the noise floor
   picks the record-best set by it). For the single-input linear models on
   the compiled engine the pass is the engine's recursion in compiled code
   without the window sums, the least work an analysis does.
2. One task per time chunk resumes every sample from those states and
   analyses its chunk whole, with :func:`dynia.run`'s own code, cut where
   :func:`dynia.run` cuts the record: the fused kernel's window sums
   (:class:`~dynia.engine.kernels.CompiledErrors`) for those linear models,
   the errors of the resumed simulations otherwise; each re-simulates only
   the ``2n`` steps of the halo. Its per-window results, (n_params, chunk
   steps) and (n_params, n_bins, chunk steps), are all that travels back.
   MCAT's likelihood carries state from window to window, so for
   ``flavour="mcat"`` these tasks form a chain, each taking the state the
   previous one left.

By default there is one sample chunk per worker thread and about four time
chunks (at most 4e6 result values each), whole multiples of
:func:`dynia.run`'s chunks of time. A task holds its chunk's results and
:func:`dynia.run`'s working arrays of one of its chunks of time, never a
sample's record: memory does not grow with the record.

``python -m benchmarks.bench --case distributed`` runs 4 000 samples x 200
000 steps (a first-order model) with :func:`dynia.run` in one thread and on
local clusters of one and of two single-threaded workers, every process
computing in one thread. On a quiet 2-core AMD EPYC (load average 1.0 to
1.3), :func:`dynia.run` took 13.1 s (13.5 s of CPU), one worker 15.1 s
(17.7 s of CPU, the client's 2.6 s included: the screening, the noise floor
and Dask's scheduler), two workers 9.2 s, 1.63 times faster than one. A
worker's resident memory peaked at 370 MB with one worker and at 333 MB with
two. The results equalled :func:`dynia.run`'s bit for bit.

A model that cannot pause and resume (``model.resumable`` false: a
:class:`~dynia.models.FunctionModel` without ``state=``, whose function
answers for the whole record at once) is still run, the old way: one task
per sample chunk simulates it over the whole record and keeps every time
chunk's block of errors on its worker until one task per time chunk has
joined the blocks of all sample chunks and analysed them, 8 x n_samples x
n_steps bytes in all (dask spills to disk what does not fit in a worker's
memory limit).

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
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from . import _checks
from .bounds import parameter_box
from .cluster import chunk_need, connected, import_distributed, worker_loss_explained
from .engine.error_sources import ArrayErrors, ScaledErrors, StreamedErrors
from .engine.flavours import WindowResults, compiled_engine, flavour_analysis, monte_carlo_errors
from .engine.kernels import CompiledErrors
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
    blank_overflowed,
    default_chunk_steps,
    error_scale,
    record_cuts,
    report_overflowed,
    window_halos,
    window_inputs,
    window_mean,
)
from .errors import DataError, DyniaError, ModelError
from .fit import record_least_squares
from .io.frames import unpack
from .pipeline import KernelSimulated, compiled_simulation, warn_dropped, warn_unreached_output
from .progress import progress_bar, shows_progress
from .quality import screening
from .result import DyniaResult
from .sampling import sample
from .settings import SAMPLERS, AnalysisSettings, RunRecord, merged_settings, split_overrides

__all__ = ["run"]


# Flavours whose analysis of a window depends on the windows before it.
_STATEFUL_FLAVOURS = ("mcat",)

# Without resuming, time chunks submitted and not yet analysed, per worker thread: enough to keep every worker
# busy while the next chunk's blocks are cut, few enough that the blocks waiting on the cluster stay a few time
# chunks' worth.
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
    rng=None,
    progress="auto",
    **overrides,
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
        Samples per task of the state pass (default: the samples shared
        evenly among the worker threads).
    time_chunks : int, optional
        Time steps per analysis task (default: about four tasks per worker
        thread, whole multiples of :func:`dynia.run`'s chunks of time, at
        most about 4e6 result values per task). Any size works, also one
        below the window's reach ``n``. Memory on the cluster grows with it
        (see the module docstring), not with the record.
    settings : dynia.settings.AnalysisSettings, optional
        As :func:`dynia.run`. ``engine`` picks the compiled kernels
        (simulation and windows) or plain numpy on the workers; results do
        not depend on it. ``sampler`` is "uniform", "lhs" or "sobol": the
        adaptive schemes need every simulation at once and run on one
        machine only. With ``ic_error`` the batches of the Monte Carlo
        errors are read off in each time chunk's analysis. With ``quality``
        the record is screened on the client before the result is made.
        ``workers`` must be None (the cluster's workers do the work);
        ``target_se``, ``dtype`` and ``store`` are :func:`dynia.run`'s only.
    rng, progress
        As :func:`dynia.run`.
    **overrides
        Single settings over ``settings``: any field of
        :class:`~dynia.settings.AnalysisSettings` (see :mod:`dynia.settings`
        for the list), e.g. ``n_samples=100_000, n=10``; any other name is a
        :class:`~dynia.errors.SettingsError`.

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
    (setting_overrides,) = split_overrides(run, overrides, AnalysisSettings)
    distributed = import_distributed()
    if client is not None and not isinstance(client, distributed.Client):
        raise TypeError(
            f"client must be a distributed.Client, or None for a local cluster; got {type(client).__name__}"
        )
    # pandas in, as dynia.run takes it: a time index gives dt (so before the settings), dates the result's time axis.
    dt = setting_overrides.pop("dt", None)
    u, y, dt, timestamps = unpack(u, y, dt if dt is not None else getattr(settings, "dt", None))
    u, y = _checks.record(u, y, n_inputs=model.n_inputs)
    settings = merged_settings(settings, {**setting_overrides, "dt": dt}, front_end=run)
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
    settings.require(
        "dynia.distributed.run",
        engine=("auto", "numba", "numpy"),
        why="its workers analyse on the compiled kernels, or on numpy; the twin serves small runs of dynia.run",
    )
    names, box = parameter_box(bounds, model.names, type(model).__name__)
    model.check_ranges(dict(zip(names, box)))
    settings.check_record(y.size)
    compiled = compiled_engine(settings.engine, settings.flavour)
    windows = _Windows(
        *window_halos(settings.n, settings.window),
        settings.min_points,
        compiled,
        error_scale(y),
        # The single-input linear models run dynia.run's fused kernel, simulation and window sums in one.
        compiled and compiled_simulation(model),
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

    with (
        ThreadPoolExecutor(max_workers=1) as aside,
        connected(client, distributed) as client,
        worker_loss_explained(client, distributed) as need,
    ):
        # The record's screening needs nothing of the analysis: the client does it while the cluster works.
        screened = aside.submit(screening, u, y, settings)
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
        screened = screened.result()
    result = _result(u, y, model, names, box, samples, settings, flavour_impl, windows, analysed, totals, screened)
    # The box's corners and the least squares (some ten times) simulate a few sets at a time: through the kernel where
    # dynia.run does, not the model's recursion, which loops over every step in Python.
    simulating = KernelSimulated(model) if windows.fused else model
    warn_unreached_output(u, y, simulating, names, box, settings)
    result = record_least_squares(result, u, y, simulating)
    return result if timestamps is None else dataclasses.replace(result, timestamps=timestamps)


def _on_cluster(client, need, model, u, y, box, samples, model_order, settings, windows, chunk_sizes, progress):
    """Everything on the cluster: the samples kept, the flavour, the analysed windows and the record totals.

    ``chunk_sizes`` are the sample and time chunks given (None: set here for
    the cluster's worker threads); ``need`` is filled with what one time
    chunk needs (:func:`dynia.cluster.worker_loss_explained`).
    """
    sample_chunks, time_chunks = chunk_sizes
    threads = max(1, sum(client.nthreads().values()))
    sample_chunks = sample_chunks or math.ceil(settings.n_samples / threads)
    n_steps = y.size
    # Should a worker be lost before the chunks are set: what a chunk of every sample needs, as below.
    need.update(chunk_need(model, settings, windows, settings.n_samples, time_chunks, threads, n_steps))
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
    need.update(chunk_need(model, settings, windows, samples.shape[0], time_chunks, threads, n_steps))
    time_chunks = need["steps"]
    spans = [(start, min(start + time_chunks, n_steps)) for start in range(0, n_steps, time_chunks)]
    row_chunks = list(_scatter_rows(client, samples[:, model_order], sample_chunks))
    stateful = settings.flavour in _STATEFUL_FLAVOURS
    if model.resumable:
        # dynia.run's chunks of time: each task cuts its own where dynia.run cuts, so its window sums are dynia.run's.
        chunk_steps = default_chunk_steps(samples.shape[0], 2 * settings.n)
        resumed_at = [max(start - windows.before, 0) for start, _ in spans]
        states = [
            client.submit(
                _state_pass, model, rows, first, u_data, y_data, settings, windows, resumed_at, chunk_steps, pure=False
            )
            for first, rows in row_chunks
        ]

        def submit(flavour, k, start, stop):
            return client.submit(
                _analyse_resumed,
                flavour,
                windows,
                model,
                row_chunks,
                states,
                k,
                (start, stop),
                chunk_steps,
                u_data,
                y_data,
                settings,
                pure=False,
            )

        # Every chunk at once: a task holds no more than its chunk's results, so the scheduler may see them all.
        ahead = len(spans)
        totals = [client.submit(operator.getitem, output, 1, pure=False) for output in states]
    else:
        blocks = _WholeRecordBlocks(client, model, row_chunks, u_data, y_data, settings, windows, n_steps, time_chunks)

        def submit(flavour, k, start, stop):
            return client.submit(_analyse_blocks, flavour, windows, blocks(k), stop - start, pure=False)

        ahead = _CHUNKS_AHEAD_PER_THREAD * threads
        totals = blocks.totals()
    analysed = _analyse_on_cluster(
        client, submit, flavour_impl, spans, stateful=stateful, progress=progress, ahead=ahead
    )
    # Every sample's record total absolute error, added step by step as dynia.run adds them.
    return samples, flavour_impl, analysed, np.concatenate(client.gather(totals))


def _result(u, y, model, names, box, samples, settings, flavour_impl, windows, analysed, totals, screened):
    """The result of the analysed windows, with the noise floor and the same record as dynia.run's.

    ``screened`` is the record's screening (:func:`dynia.quality.screening`).
    """
    ic, ci, median, gradient, best, upper, threshold, ic_se, ci_se, overflowed = analysed
    n_steps, n_samples, dt = y.size, settings.n_samples, settings.dt
    report_overflowed(overflowed, best, np.arange(n_steps) * float(dt), y)
    for extreme in (best, upper, threshold):
        extreme /= windows.scale  # exact: a power of two
    # The record-best set and its neighbours are simulated once more here, as dynia.run does: through the kernel
    # where its analysis ran on it, which gives the model's outputs bit for bit without a Python loop over the steps.
    model_order = [names.index(name) for name in model.names]

    def simulations(rows):
        params = samples[rows][:, model_order]
        if windows.fused:
            return CompiledErrors(model, params, u, y, dt=dt, x0=settings.x0, workers=1).output_chunks(RESIDUAL_CHUNK)
        return model.simulate_chunks(params, u, dt=dt, x0=settings.x0, chunk_steps=RESIDUAL_CHUNK)

    fit = record_fit(y, samples, box, totals, simulations)
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
        screened=screened,
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


def _finite_samples(client, model, samples, model_order, u_data, u, settings, sample_chunks):
    """The samples whose simulation is finite over the record; the others dropped (and warned about)."""
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


def _analyse_on_cluster(client, submit, flavour, spans, *, stateful, progress, ahead):
    """One task per time chunk; its results (with best, upper, threshold MAE) to the client.

    ``submit(flavour, k, start, stop)`` submits the task of the k-th time
    chunk [start, stop), which starts from ``flavour`` (or the future of
    one), and returns the future of its WindowResults and the flavour after
    it; it is called in time order. At most ``ahead`` time chunks are
    submitted and not yet analysed. A stateful flavour's tasks form a chain
    in time order, each starting from the state the one before left.
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

    def submit_chunk(k, start, stop):
        nonlocal state
        analysed = submit(state, k, start, stop)
        chunk = client.submit(operator.getitem, analysed, 0, pure=False)
        chunk_spans[chunk] = (start, stop)
        finished.add(chunk)
        if stateful:
            state = client.submit(operator.getitem, analysed, 1, pure=False)

    waiting = iter(enumerate(spans))
    for k, (start, stop) in itertools.islice(waiting, ahead):
        submit_chunk(k, start, stop)
    bar = progress_bar(progress, total=n_steps, desc="DYNIA windows", unit="window")
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
            submit_chunk(following[0], *following[1])
        if bar is not None:
            bar.update(stop - start)
    if bar is not None:
        bar.close()
    return ic, ci, median, gradient, best, upper, threshold, ic_se, ci_se, overflowed


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
    """Which samples of one chunk simulate to finite output, (rows,) bool."""
    with _sample_chunk_context(first, params.shape[0]):
        return model.finite_samples(params, u, dt=settings.dt, x0=settings.x0)


@dataclass(frozen=True)
class _Windows:
    """The windows' reach and the engine's path from simulated errors to a flavour's analysis.

    The compiled path hands the analysis the absolute errors of a chunk of
    time and its halo, time-major (m + slots - 1, rows), and forms the
    window sums inside its kernel; the numpy path hands it the window means
    (m, rows). Either block has the samples on axis 1, so the blocks of
    consecutive sample chunks join along it. The fused path (``fused``, the
    single-input linear models on the compiled engine) simulates and sums
    in one kernel, as :func:`dynia.run` does, and hands on the window sums.
    """

    before: int
    after: int
    min_points: int
    compiled: bool
    scale: float = 1.0  # the errors' factor, dynia.engine.windows.error_scale
    fused: bool = False

    @property
    def slots(self):
        """Steps per window."""
        return self.before + self.after + 1

    def inputs(self, errors, start, stop, n_steps):
        """The windows' input at steps [start, stop) from the error source ``errors``: errors and measured counts."""
        if self.scale != 1.0:
            errors = ScaledErrors(errors, self.scale)
        return window_inputs(errors, start, stop, self.before, self.after, n_steps, time_major=self.compiled)

    def own_errors(self, window_errors, m):
        """The errors of the m steps [start, stop) themselves, time-major, among the window errors of ``inputs``."""
        if self.compiled:
            return window_errors[self.before : self.before + m]
        return window_errors[:, self.before : self.before + m].T

    def block(self, window_errors, measured, m):
        """What the analysis of m windows takes of one sample chunk: the error rows (compiled) or the window means."""
        if self.compiled:
            return window_errors, measured
        return window_mean(window_errors, measured, m, self.slots)

    def analyse(self, flavour, block, counts, m):
        """The flavour's :class:`~dynia.engine.flavours.WindowResults` of m windows from a block of every sample."""
        if self.compiled:
            return flavour.analyse_rows(block, counts, m, self.slots)
        return flavour.analyse(block, counts >= self.min_points)


def _state_pass(model, params, first, u, y, settings, windows, resumed_at, chunk_steps):
    """One sample chunk simulated over the record: its state at each step of ``resumed_at`` and its record totals.

    ``resumed_at`` holds, in time order, the steps the time chunks' tasks
    resume from. The totals add every step's absolute error (times the
    errors' scale) in time order, as :func:`dynia.run` adds them, which only
    a pass over the whole record can. Returns the states, one per step of
    ``resumed_at`` (the model's :class:`~dynia.models.base.SimulationState`,
    or the fused kernel's (n_states, rows) array), and the totals (rows,).
    """
    with _sample_chunk_context(first, params.shape[0]):
        if windows.fused:
            source = CompiledErrors(model, params, u, y, dt=settings.dt, x0=settings.x0, workers=1)
            return source.states_at(resumed_at, windows.scale, chunk_steps)
        state = model.start_simulation(params, u, dt=settings.dt, x0=settings.x0)
        totals = np.zeros(params.shape[0])
        kept = {}
        for at, stop in record_cuts(resumed_at, y.size, chunk_steps):
            kept[at] = state
            sims, state = model.simulate_span(state, u, stop, time_major=True)
            errors = _time_major_errors(y, at, sims)
            add_record_errors(totals, errors * windows.scale if windows.scale != 1.0 else errors)
        return [kept[at] for at in resumed_at], totals


def _time_major_errors(y, at, sims):
    """|y - sims| of time-major simulations (m, rows) of the steps from ``at`` on, time-major; 0 where y is missing."""
    try:
        # The transposed view makes the errors come out time-major (numpy keeps the input's layout).
        return ArrayErrors(y[at : at + sims.shape[0]], sims.T).columns(0, sims.shape[0]).T
    except DataError as error:
        raise DataError(f"{error} (steps counted from step {at})") from error


def _analyse_resumed(flavour, windows, model, row_chunks, states, k, span, chunk_steps, u, y, settings):
    """The k-th time chunk, ``span`` = [start, stop), analysed whole from every sample's state where its windows begin.

    ``row_chunks`` are the sample chunks, (first sample, rows) pairs, and
    ``states`` the state pass's outputs for them. The chunk is cut where :func:`dynia.run`
    cuts the record (:func:`_pieces`) and each piece analysed with its code:
    the fused kernel's window sums, or the errors of the resumed
    simulations. Returns the chunk's
    :class:`~dynia.engine.flavours.WindowResults` and the flavour after it,
    whose state the next chunk of a stateful flavour starts from.
    """
    start, stop = span
    n_steps = y.size
    # A worker hands the same object to every task that needs it; analysing
    # must not change the state other tasks start from.
    flavour = copy.deepcopy(flavour)
    pieces = _pieces(start, stop, chunk_steps)
    if windows.fused:
        params = np.concatenate([rows for _, rows in row_chunks])
        source = CompiledErrors(model, params, u, y, dt=settings.dt, x0=settings.x0, workers=1)
        state = np.concatenate([output[0][k] for output in states], axis=1)
        halos = (windows.before, windows.after)
        source.resume(state, start, halos, windows.scale)
        # The record totals are the state pass's: the ones this source adds up are dropped.
        ignored = np.zeros(params.shape[0])
        parts = [
            flavour.analyse_sums(*source.window_sums(first, last, halos, ignored, windows.scale))
            for first, last in pieces
        ]
    else:
        resumed = [output[0][k] for output in states]
        errors = _ResumedErrors(model, resumed, [first for first, _ in row_chunks], u, y)
        parts = []
        for first, last in pieces:
            window_errors, measured = windows.inputs(errors, first, last, n_steps)
            parts.append(windows.analyse(flavour, *windows.block(window_errors, measured, last - first), last - first))
    return _joined(parts), flavour


def _pieces(start, stop, chunk_steps):
    """[start, stop) cut where dynia.run cuts the record, at the multiples of ``chunk_steps``: (from, to) pairs."""
    cuts = [start, *range((start // chunk_steps + 1) * chunk_steps, stop, chunk_steps), stop]
    return list(zip(cuts[:-1], cuts[1:]))


# The axis of time of each WindowResults field.
_TIME_AXES = WindowResults(ic=1, ci=1, median=1, gradient=2, best=0, threshold=0, upper=0, batch_ic=2, batch_ci=2)


def _joined(parts):
    """The WindowResults of consecutive pieces of time joined into one."""
    if len(parts) == 1:
        return parts[0]
    return WindowResults(
        *(
            None if pieces[0] is None else np.concatenate(pieces, axis=axis)
            for pieces, axis in zip(zip(*parts), _TIME_AXES)
        )
    )


class _ResumedErrors:
    """Absolute errors, time-major, of every sample chunk's paused simulation, simulated as they are asked for.

    An error source of :func:`~dynia.engine.windows.window_inputs`: requests
    move forward in time, and the first starts at the states' step.
    """

    def __init__(self, model, states, firsts, u, y):
        self.y = y
        self._model = model
        self._u = u
        self._states = list(states)
        self._firsts = firsts
        self._first = states[0].step  # the step of the first error row kept
        self._errors = np.empty((0, sum(state.n_samples for state in states)))

    def rows(self, start, stop):
        """Errors for times [start, stop), time-major: shape (stop - start, n_samples)."""
        self._errors = self._errors[start - self._first :]
        self._first = start
        reached = self._states[0].step
        if stop > reached:
            sims = []
            for i, (first, state) in enumerate(zip(self._firsts, self._states)):
                with _sample_chunk_context(first, state.n_samples):
                    span, self._states[i] = self._model.simulate_span(state, self._u, stop, time_major=True)
                sims.append(span)
            fresh = _time_major_errors(self.y, reached, np.concatenate(sims, axis=1))
            self._errors = np.concatenate([self._errors, fresh]) if self._errors.shape[0] else fresh
        return self._errors[: stop - start]

    def columns(self, start, stop):
        """Errors for times [start, stop), shape (n_samples, stop - start)."""
        return np.ascontiguousarray(self.rows(start, stop).T)


class _WholeRecordBlocks:
    """For a model that cannot pause: one task per sample chunk over the whole record, cut into time chunks' blocks.

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
        n_chunks = math.ceil(n_steps / time_chunks)
        self._by_time = [
            [client.submit(operator.getitem, inputs, k, pure=False) for inputs in whole_record] for k in range(n_chunks)
        ]
        self._totals = [client.submit(operator.getitem, inputs, n_chunks, pure=False) for inputs in whole_record]

    def __call__(self, k):
        """The futures of the k-th time chunk's blocks, handed out once."""
        blocks, self._by_time[k] = self._by_time[k], None
        return blocks

    def totals(self):
        """Futures of every sample chunk's record totals of absolute error."""
        return self._totals


def _whole_record_window_inputs(model, params, u, y, settings, windows, time_chunks, first):
    """Simulate one sample chunk over the record: its block of every time chunk, then its samples' record totals."""
    n_steps = y.size
    totals = np.zeros(params.shape[0])
    with _sample_chunk_context(first, params.shape[0]):
        errors = StreamedErrors(
            y,
            model.simulate_chunks(params, u, dt=settings.dt, x0=settings.x0, chunk_steps=time_chunks),
            params.shape[0],
        )
        blocks = []
        for start in range(0, n_steps, time_chunks):
            m = min(start + time_chunks, n_steps) - start
            window_errors, measured = windows.inputs(errors, start, start + m, n_steps)
            add_record_errors(totals, windows.own_errors(window_errors, m))
            blocks.append(windows.block(window_errors, measured, m))
    return [*blocks, totals]


def _analyse_blocks(flavour, windows, blocks, m):
    """The analysis of one time chunk's m windows from the blocks of all sample chunks, in sample order.

    Returns the chunk's :class:`~dynia.engine.flavours.WindowResults` and the flavour after it.
    """
    flavour = copy.deepcopy(flavour)  # as in _analyse_resumed
    joined = np.concatenate([block for block, _ in blocks], axis=1)
    return windows.analyse(flavour, joined, blocks[0][1], m), flavour
