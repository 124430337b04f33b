"""The Dask cluster of :func:`dynia.distributed.run`: taken or started, its chunks of work sized, its losses explained.

:func:`connected` takes the client given or starts a local cluster;
:func:`chunk_need` sizes the time chunks to the cluster's worker threads
and says what memory one chunk's task needs; :func:`worker_loss_explained`
turns a worker lost mid-run into a :class:`~dynia.errors.SettingsError`
saying so. How the work is cut into chunks is told in
:mod:`dynia.distributed`.
"""

import math
import os
from contextlib import contextmanager

from .engine.windows import default_chunk_steps
from .errors import SettingsError

__all__ = ["import_distributed", "connected", "worker_loss_explained", "chunk_need"]

# Time chunks per worker thread by default: enough for a worker that finishes early (another job on its core) to
# take over a share of the rest, few enough that a task's fixed costs (its halo simulated twice, the flavour and
# model sent, the results returned) stay a fraction of a percent of its work.
_CHUNKS_PER_THREAD = 4

# Ceiling on the result values of one time chunk (IC, limits, median, gradient...): 4e6 float64 = 32 MB, which the
# task holds and sends back.
_RESULT_VALUES = 4_000_000

# Without resuming, default ceiling on the values of one time chunk's blocks: 4e6 float64 = 32 MB.
_BLOCK_VALUES = 4_000_000


def import_distributed():
    """The ``distributed`` package, or an ImportError saying how to install it."""
    try:
        import distributed
    except ImportError:
        raise ImportError("dynia.distributed needs dask.distributed: pip install 'dynia[distributed]'") from None
    return distributed


@contextmanager
def connected(client, distributed):
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


def chunk_need(model, settings, windows, n_samples, time_chunks, threads, n_steps):
    """The steps of a time chunk (``time_chunks``, or the default) and the memory its task needs, in MB.

    ``windows`` holds the windows' reach (``slots``, steps per window);
    ``threads`` are the cluster's worker threads. Returns a dict of the
    ``steps``, ``what`` the task holds (in words) and the ``mb`` it needs.
    Resumed, a task holds its chunk's results and dynia.run's working arrays of one chunk of time; otherwise it
    joins every sample's errors over the time chunk and its halo, and holds the window sums and the flavour's
    working copies of them: about three such arrays.
    """
    n_bins = settings.bins + (settings.flavour == "mcat")
    # Per step: IC, two limits, median and the gradient of every parameter, three MAEs, and with ic_error the IC
    # and limits of each of at most ten batches.
    per_step = len(model.names) * (4 + n_bins + (30 if settings.ic_error else 0)) + 3
    if model.resumable:
        chunk_steps = default_chunk_steps(n_samples, 2 * settings.n)
        time_chunks = time_chunks or _resumed_time_chunks(n_steps, threads, chunk_steps, per_step)
        values = per_step * time_chunks + 3 * n_samples * (chunk_steps + windows.slots - 1)
        what = (
            f"{time_chunks} steps of results, dynia.run's working arrays of {chunk_steps} steps x {n_samples} samples"
        )
    else:
        time_chunks = time_chunks or _time_chunks(n_steps, threads, n_samples)
        values = 3 * n_samples * (time_chunks + windows.slots - 1)
        what = f"{n_samples} samples x {time_chunks + windows.slots - 1} steps with its halo"
    return dict(steps=time_chunks, what=what, mb=8 * values / 2**20)


@contextmanager
def worker_loss_explained(client, distributed):
    """Turn a worker lost mid-run (killed at its memory limit, mostly) into a SettingsError saying what one chunk needs.

    Yields a dict the caller fills with ``what`` one time chunk's task
    holds and the ``mb`` it needs (:func:`chunk_need`).
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
        chunk = f"; one time chunk ({need['what']}) needs about {need['mb']:.0f} MB on one worker" if need else ""
        raise SettingsError(
            f"a worker of the cluster was lost ({type(error).__name__}), most likely killed at its memory limit: "
            f"{limit}{chunk}; give a smaller time_chunks or sample_chunks, or the workers more memory",
            "time_chunks",
        ) from None


def _resumed_time_chunks(n_steps, threads, chunk_steps, per_step):
    """Steps per time chunk of a resumed run: about ``_CHUNKS_PER_THREAD`` per worker thread, in whole chunks of
    dynia.run's ``chunk_steps``, and at most ``_RESULT_VALUES`` values of results."""
    wanted = math.ceil(n_steps / (_CHUNKS_PER_THREAD * threads))
    ceiling = max(chunk_steps, _RESULT_VALUES // per_step // chunk_steps * chunk_steps)
    return min(math.ceil(wanted / chunk_steps) * chunk_steps, ceiling)


def _time_chunks(n_steps, threads, n_samples):
    """Steps per time chunk without resuming: about four per worker thread, at most ``_BLOCK_VALUES`` values."""
    return max(1, min(math.ceil(n_steps / (4 * threads)), _BLOCK_VALUES // n_samples))
