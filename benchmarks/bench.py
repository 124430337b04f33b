"""Benchmark: the one-to-one port against the engine, then the engine at scale.

Run with ``make bench`` or ``python -m benchmarks.bench``. Each case runs in its own
process so that its peak resident memory (``ru_maxrss``) is its own.

1. Thesis example 1 (500 steps, 2000 samples, both parameters): the port
   (:mod:`dynia.thesis`, once per parameter) against :func:`dynia.moving_window`
   (all parameters in one pass) on the same simulations; ratio target >= 300.
2. The engine on 20 000 samples x 2 000 steps (simulations held in memory).
3. :func:`dynia.run` (simulate and analyse, streamed) on 20 000 x 2 000 and on
   10^5 samples x 10^4 steps, which never holds the 8 GB simulation matrix.
4. Throughput of the complete analysis (simulate and analyse both
   parameters, flavour "thesis") at 20 000 samples x 20 000 steps, compiled
   engine and numpy engine, with the ratio to the port's sample-steps per
   second measured in the same case; target >= 10^8 sample-steps/s.
5. Memory: :func:`dynia.run` on 10^5 samples x 10^5 steps; target peak
   resident memory <= 2 GB.
6. Semi-online mode: time per :meth:`dynia.online.OnlineDynia.update` at
   10 000 samples (first order, n=10); target <= 1 ms.
7. Samplers at percentage 0.1 on example 1: IC error against a uniform
   400 000-sample reference for uniform (10^4, 10^5) and the adaptive
   schemes of :mod:`dynia.adaptive` (10^4).
8. The command line on a long record: ``dynia analyse`` of a 500 000-row
   CSV (first-order response to random steps, with noise) with plots on,
   500 samples; target peak resident memory <= 1.5 GB.
9. Your own model: a :class:`dynia.models.StateSpaceModel` with numba-compiled
   step and output (the same first-order lag) against the built-in
   :class:`dynia.models.FirstOrder`, complete runs at 20 000 samples x 20 000
   steps; target >= 1/3 of the built-in sample-steps/s. And the overhead of
   :func:`dynia.run` on a pure-numpy :class:`dynia.models.FunctionModel` over
   calling the function and :func:`dynia.moving_window` by hand (5 000
   samples x 5 000 steps); target < 10 %.
10. :func:`dynia.distributed.run` on a local Dask cluster of one and of two
    single-threaded worker processes (1 GB memory limit each) against
    :func:`dynia.run` in one thread, 4 000 samples x 200 000 steps, first
    order (``--distributed-samples``, ``--distributed-steps``): wall and CPU
    time (the client's and the workers' added), each worker's peak resident
    memory, sampled every 0.1 s, and the results compared bit for bit; goals:
    one worker within 1.3x of :func:`dynia.run`, two workers at least 1.6x
    faster than one, at most 1 GB per worker.

11. The yardstick: :func:`dynia.run` (first order, K and T, thesis flavour,
    20 000 samples x 20 000 steps, n = 10 and 100) against the least work an
    analysis has to do, one fused compiled pass that simulates every sample
    and accumulates ``|y - sim|`` (``_bare_pass``), timed in the same run, on
    an input that never rests and on one that rests at zero from half-way,
    in CPU time (``time.process_time``) beside the wall clock; goal: within
    10x of the bare pass in CPU time. Then the scaling exponents of
    :func:`dynia.run` in samples, steps and half window n (log-log slopes
    over a factor of 4; goal about 1, 1 and 0).

12. ``dynia follow`` (:mod:`dynia.follow`) on an SQLite file: a backlog of
    10^5 rows (2 000 samples, n = 10, ``--once``) against ``dynia analyse``
    of the same rows as CSV, CPU time in one process after both compiled on
    a short record (goal: at most 2x); then one new row at a time, each
    followed by a poll (the per-step update, the database's round trip and
    the checkpoint), CPU and wall time per row (goal: at most 5 ms).

13. The first run: the README's quick start in a fresh process with numba's
    cache in an empty folder, then again with it filled, CPU time of the
    child processes beside the wall clock; goal <= 10 and <= 2 CPU-s. And
    ``dynia --help`` / ``dynia analyse --help`` there, which compile nothing.

``long-record``: a year of 1 Hz data in bounded memory, :func:`dynia.run`
with ``dtype="float32"`` and ``store`` (a netCDF file in a temporary folder)
on 10^4 samples x 3x10^7 steps (``--long-samples``, ``--long-steps``; about
an hour on two cores), then its summary and plots; target peak resident
memory <= 4 GB.
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from dynia.synthetic import example_firstorder_input

__all__ = ["main", "best_of"]


def _example1(n_samples, n_steps, seed=2009):
    from dynia.models import FirstOrder

    rng = np.random.default_rng(seed)
    u = example_firstorder_input(n_steps)
    model = FirstOrder()
    y = model.simulate([[2.0, 3.0]], u)[0] + rng.normal(0, 0.5, n_steps)
    params = rng.uniform(0, 7, (n_samples, 2))
    return u, y, params, model


def best_of(function, repeats, clock=time.perf_counter):
    """Smallest time of ``repeats`` calls of ``function``, in seconds: wall clock, or ``clock``."""
    times = []
    for _ in range(repeats):
        start = clock()
        function()
        times.append(clock() - start)
    return min(times)


def _case_port_vs_engine():
    from dynia import thesis
    from dynia.engine.windows import moving_window

    u, y, params, model = _example1(2000, 500)
    sims = model.simulate(params, u)
    start = time.perf_counter()
    for p in range(2):
        thesis.moving_window_calcs(500, params[:, p], 0, 7, 2000, sims, y, 40, 10, 10)
    port = time.perf_counter() - start
    engine = best_of(lambda: moving_window(y, sims, params, [[0, 7], [0, 7]], n=10), 7)
    single = best_of(lambda: moving_window(y, sims, params, [[0, 7], [0, 7]], n=10, workers=1), 7)
    return dict(
        port_s=port, engine_s=engine, engine_one_thread_s=single, ratio=port / engine, ratio_one_thread=port / single
    )


def _case_engine(n_samples, n_steps):
    from dynia.engine.windows import moving_window

    u, y, params, model = _example1(n_samples, n_steps)
    sims = model.simulate(params, u)
    seconds = best_of(lambda: moving_window(y, sims, params, [[0, 7], [0, 7]], n=10), 2)
    return dict(seconds=seconds, sample_steps_per_s=n_samples * n_steps / seconds)


def _case_run(n_samples, n_steps, engine="auto"):
    from dynia.pipeline import run

    u, y, _, model = _example1(1, n_steps)
    start = time.perf_counter()
    result = run(u, y, model, {"K": (0, 7), "T": (0, 7)}, n_samples=n_samples, n=10, rng=1, engine=engine)
    seconds = time.perf_counter() - start
    return dict(seconds=seconds, sample_steps_per_s=n_samples * n_steps / seconds, engine=result.settings["engine"])


def _case_throughput():
    from dynia import thesis
    from dynia.pipeline import run

    u, y, params, model = _example1(2000, 500)
    sims = model.simulate(params, u)
    start = time.perf_counter()
    for p in range(2):
        thesis.moving_window_calcs(500, params[:, p], 0, 7, 2000, sims, y, 40, 10, 10)
    port_rate = 2000 * 500 / (time.perf_counter() - start)
    u, y, _, model = _example1(1, 20_000)
    run(u, y, model, {"K": (0, 7), "T": (0, 7)}, n_samples=200, n=10, rng=1, engine="numba")  # compile
    result = dict(port_sample_steps_per_s=port_rate)
    for engine, repeats in (("numba", 3), ("numpy", 1)):
        seconds = best_of(
            lambda engine=engine: run(
                u, y, model, {"K": (0, 7), "T": (0, 7)}, n_samples=20_000, n=10, rng=1, engine=engine
            ),
            repeats,
        )
        result[engine] = dict(
            seconds=seconds,
            sample_steps_per_s=20_000 * 20_000 / seconds,
            ratio_to_port=20_000 * 20_000 / seconds / port_rate,
        )
    return result


def _case_online():
    from dynia.online import OnlineDynia

    u, y, _, model = _example1(1, 2_000)
    online = OnlineDynia(model, {"K": (0, 7), "T": (0, 7)}, n_samples=10_000, n=10, rng=1)
    times = []
    for u_t, y_t in zip(u, y):
        start = time.perf_counter()
        online.update(u_t, y_t)
        times.append(time.perf_counter() - start)
    times = np.array(times[50:]) * 1e3  # the first updates warm the caches
    return dict(
        mean_ms=float(times.mean()),
        median_ms=float(np.median(times)),
        p99_ms=float(np.percentile(times, 99)),
        updates=int(times.size),
    )


def _case_sampling():
    from dynia.pipeline import run

    u, y, _, model = _example1(1, 500)
    bounds = {"K": (0, 7), "T": (0, 7)}
    reference = run(u, y, model, bounds, n_samples=400_000, n=10, percentage=0.1, rng=1)
    result = {}
    for sampler, budget in (("uniform", 10_000), ("uniform", 100_000), ("iis", 10_000), ("de", 10_000)):
        start = time.perf_counter()
        estimate = run(u, y, model, bounds, sampler=sampler, n_samples=budget, n=10, percentage=0.1, rng=2)
        seconds = time.perf_counter() - start
        error = float(np.sqrt(np.nanmean((estimate.ic - reference.ic) ** 2)))
        result[f"{sampler} {budget}"] = dict(rmse=error, seconds=seconds)
    return result


def _case_cli_long_record(n_rows=500_000):
    import tempfile
    from pathlib import Path

    from dynia.cli import main as cli_main
    from dynia.models import FirstOrder

    rng = np.random.default_rng(1)
    u = np.repeat(rng.choice([0.0, 10.0, 20.0, 30.0], n_rows // 200 + 1), 200)[:n_rows]
    y = FirstOrder().simulate([[2.0, 25.0]], u)[0] + rng.normal(0, 0.5, n_rows)
    with tempfile.TemporaryDirectory() as folder:
        data = Path(folder, "long.csv")
        with open(data, "w") as handle:
            handle.write("time,u,y\n")
            for first in range(0, n_rows, 100_000):
                block = np.column_stack(
                    [
                        np.arange(first, min(first + 100_000, n_rows)),
                        u[first : first + 100_000],
                        y[first : first + 100_000],
                    ]
                )
                np.savetxt(handle, block, delimiter=",", fmt=["%d", "%.6g", "%.6g"])
        start = time.perf_counter()
        arguments = [
            "analyse",
            str(data),
            "--time",
            "time",
            "--input",
            "u",
            "--output",
            "y",
            "--model",
            "first-order",
            "--param",
            "K=0:5",
            "--param",
            "T=0:50",
            "--samples",
            "500",
            "--seed",
            "1",
            "--out",
            str(Path(folder, "out")),
        ]
        status = cli_main(arguments)
        seconds = time.perf_counter() - start
        figures = len(list(Path(folder, "out").glob("*.png")))
    return dict(rows=n_rows, seconds=seconds, status=status, figures=figures)


def _lag_functions():
    """A first-order lag (ZOH-exact, as FirstOrder) as numba step/output functions and as a numpy simulator."""
    import numba

    @numba.njit
    def step(x, u_k, p, dt):
        following = np.empty_like(x)
        for i in range(x.shape[0]):
            decay = np.exp(-dt / p[i, 1])
            following[i, 0] = decay * x[i, 0] + (1.0 - decay) * p[i, 0] * u_k
        return following

    @numba.njit
    def output(x, u_k, p):
        return x[:, 0].copy()

    def simulate(params, u, dt):
        decay = np.exp(-dt / params[:, 1])
        gain = (1.0 - decay) * params[:, 0]
        sims = np.empty((params.shape[0], u.shape[0]))
        state = np.zeros(params.shape[0])
        for k, u_k in enumerate(u):
            sims[:, k] = state
            state = decay * state + gain * u_k
        return sims

    return step, output, simulate


def _case_custom_models():
    from dynia.engine.windows import moving_window
    from dynia.models import FunctionModel, StateSpaceModel
    from dynia.pipeline import run

    step, output, simulate = _lag_functions()
    lag = StateSpaceModel(step, output, [0.0], ["K", "T"], n_states=1)
    bounds = {"K": (0, 7), "T": (0.5, 7)}
    u, y, _, model = _example1(1, 20_000)
    run(u[:200], y[:200], lag, bounds, n_samples=100, rng=1)  # compile outside the timing
    result = {}
    for name, candidate in (("built-in FirstOrder", model), ("StateSpaceModel (numba)", lag)):
        seconds = best_of(lambda candidate=candidate: run(u, y, candidate, bounds, n_samples=20_000, rng=1), 2)
        result[name] = dict(seconds=seconds, sample_steps_per_s=20_000 * 20_000 / seconds)
    result["ratio"] = (
        result["StateSpaceModel (numba)"]["sample_steps_per_s"] / result["built-in FirstOrder"]["sample_steps_per_s"]
    )
    u, y, _, _ = _example1(1, 5_000)
    function_model = FunctionModel(simulate, ["K", "T"])
    by_run = best_of(lambda: run(u, y, function_model, bounds, n_samples=5_000, rng=1), 3)
    samples = run(u, y, function_model, bounds, n_samples=5_000, rng=1).samples
    box = np.array(list(bounds.values()))
    by_hand = best_of(lambda: moving_window(y, simulate(samples, u, 1.0), samples, box), 3)
    result["function_model"] = dict(run_s=by_run, by_hand_s=by_hand, overhead=by_run / by_hand - 1)
    return result


def _case_distributed(n_samples=4_000, n_steps=200_000, time_chunks=None):
    """dynia.distributed.run on local clusters of one and of two workers, against dynia.run, all in one thread each.

    Every process computes in one thread (numba's and BLAS's too, workers=1 for dynia.run), so CPU seconds count
    the work: this process's (the client and the scheduler, or dynia.run) plus the workers'. Each run is made twice
    and the faster kept, since other jobs on the machine slow runs down; the results must equal dynia.run's bit for
    bit.
    """
    import threading

    import numba
    import psutil
    from distributed import Client, LocalCluster

    from dynia.distributed import run as distributed_run
    from dynia.pipeline import run

    numba.set_num_threads(1)
    u, y, _, model = _example1(1, n_steps)
    bounds = {"K": (0, 7), "T": (0, 7)}
    options = dict(n_samples=n_samples, rng=1)
    run(u[:200], y[:200], model, bounds, n_samples=200, workers=1, rng=1)  # load the compiled kernels
    reference, timing = _timed_twice(lambda: run(u, y, model, bounds, workers=1, **options), [])
    result = dict(n_samples=n_samples, n_steps=n_steps, machine=_machine(), dynia_run=timing)
    one_thread = {
        name: "1" for name in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
    }
    for n_workers in (1, 2):
        with (
            LocalCluster(
                n_workers=n_workers,
                threads_per_worker=1,
                processes=True,
                memory_limit="1GiB",
                dashboard_address=":0",
                env=one_thread,
            ) as cluster,
            Client(cluster) as client,
        ):
            distributed_run(u[:200], y[:200], model, bounds, client=client, n_samples=200, rng=1)  # load the kernels
            workers = [psutil.Process(pid) for pid in client.run(os.getpid).values()]
            peaks = [worker.memory_info().rss for worker in workers]
            done = threading.Event()

            def watch(workers=workers, peaks=peaks, done=done):
                while not done.wait(0.1):
                    for number, worker in enumerate(workers):
                        peaks[number] = max(peaks[number], worker.memory_info().rss)

            watcher = threading.Thread(target=watch)
            watcher.start()
            try:
                analysed, timing = _timed_twice(
                    lambda: distributed_run(u, y, model, bounds, client=client, time_chunks=time_chunks, **options),
                    workers,
                )
            finally:
                done.set()
                watcher.join()
        result[f"{n_workers} workers"] = dict(
            timing,
            equal=all(
                np.array_equal(getattr(analysed, name), getattr(reference, name), equal_nan=True)
                for name in ("samples", "ic", "ci", "median", "gradient", "noise_floor", "best_mae")
            ),
            worker_peak_rss_mb=[peak / 2**20 for peak in peaks],
        )
    one, two, single = result["1 workers"], result["2 workers"], result["dynia_run"]
    result["one_worker_over_run"] = dict(wall=one["seconds"] / single["seconds"], cpu=one["cpu_s"] / single["cpu_s"])
    result["speed_up"] = one["seconds"] / two["seconds"]
    result["cpu_two_over_one"] = two["cpu_s"] / one["cpu_s"]
    return result


def _timed_twice(function, workers):
    """``function``'s result and its faster run of two: wall seconds, CPU seconds of this process and ``workers``
    (psutil processes), and the one-minute load average as it started."""
    best = None
    for _ in range(2):
        load = os.getloadavg()[0]
        before = time.process_time(), [sum(worker.cpu_times()[:2]) for worker in workers]
        start = time.perf_counter()
        value = function()
        seconds = time.perf_counter() - start
        worker_cpu = [sum(worker.cpu_times()[:2]) - used for worker, used in zip(workers, before[1])]
        own_cpu = time.process_time() - before[0]
        if best is None or seconds < best["seconds"]:
            best = dict(
                seconds=seconds,
                cpu_s=own_cpu + sum(worker_cpu),
                client_cpu_s=own_cpu,
                worker_cpu_s=worker_cpu,
                load_average=load,
            )
    return value, best


def _case_ic_error_cost(n_samples=20_000, n_steps=20_000):
    """A complete run with and without the Monte Carlo error, one thread, at percentage 10, 1 and 0.1.

    Timed in CPU seconds of this process (one thread), so that other jobs on the machine change the
    ratio little.

    The record repeats example 1's 500 steps, so that its windows keep changing (a record that rests
    would let every window reuse the last one's behavioural bound). Then, at 10 %, the yardstick's record that
    rests at zero from half-way, whose windows come to tie (``resting``): the goal of at most 1.15x holds for both.
    """
    from dynia.models import FirstOrder
    from dynia.pipeline import run

    model = FirstOrder()
    u = np.resize(example_firstorder_input(), n_steps)
    y = model.simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(2009).normal(0, 0.5, n_steps)
    bounds = {"K": (0, 7), "T": (0, 7)}
    result = dict(n_samples=n_samples, n_steps=n_steps)
    for ic_error in (False, True):  # compile the kernels
        run(u[:500], y[:500], model, bounds, n_samples=2000, ic_error=ic_error, workers=1, rng=1)
    for percentage in (10, 1, 0.1):
        seconds = {}
        for ic_error in (False, True):
            options = dict(n_samples=n_samples, percentage=percentage, ic_error=ic_error, workers=1, rng=1)
            seconds[ic_error] = best_of(
                lambda options=options: run(u, y, model, bounds, **options), 2, time.process_time
            )
        result[f"{percentage:g} %"] = dict(plain_s=seconds[False], ic_error_s=seconds[True])
    u = _yardstick_inputs(n_steps)["rests at zero from half-way"]
    y = model.simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(2).normal(0, 0.1, n_steps)
    seconds = {}
    for ic_error in (False, True):
        options = dict(n_samples=n_samples, ic_error=ic_error, workers=1, rng=1)
        seconds[ic_error] = best_of(
            lambda options=options: run(u, y, model, {"K": (0, 4), "T": (1.5, 6)}, **options), 2, time.process_time
        )
    result["resting"] = dict(plain_s=seconds[False], ic_error_s=seconds[True])
    return result


def _case_ic_error_honesty():
    """Predicted IC standard error against the spread over 20 seeds (dynia.honesty), examples 1 and 2."""
    from .honesty import ic_error_honesty

    rows = []
    for number in (1, 2):
        for percentage, n_samples in ((10, 2000), (0.1, 50_000)):
            check = ic_error_honesty(number, percentage, n_samples, seeds=20)
            for p, name in enumerate(check.names):
                rows.append(
                    dict(
                        example=number,
                        percentage=percentage,
                        n_samples=n_samples,
                        parameter=name,
                        empirical_median=float(np.nanmedian(check.empirical[p])),
                        predicted_median=float(np.nanmedian(check.predicted[p])),
                        ratio=float(check.ratio[p]),
                        stepwise_ratio=float(check.stepwise_ratio[p]),
                    )
                )
    return dict(rows=rows)


def _case_long_record(n_samples=10_000, n_steps=30_000_000):
    import tempfile
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from dynia.pipeline import run

    u, y, _, model = _example1(1, n_steps)
    data_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder, "long.nc")
        start = time.perf_counter()
        result = run(
            u,
            y,
            model,
            {"K": (0, 7), "T": (0, 7)},
            n_samples=n_samples,
            n=10,
            bins=40,
            rng=1,
            dtype="float32",
            store=path,
        )
        seconds = time.perf_counter() - start
        run_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        start = time.perf_counter()
        summary = result.summary()
        for name in result.names:
            plt.close(result.plot_identifiability(name).figure)
            plt.close(result.plot_information_content(name).figure)
        after_seconds = time.perf_counter() - start
        file_mb = path.stat().st_size / 2**20
    return dict(
        n_samples=n_samples,
        n_steps=n_steps,
        seconds=seconds,
        sample_steps_per_s=n_samples * n_steps / seconds,
        data_peak_rss_mb=data_rss,
        run_peak_rss_mb=run_rss,
        summary_and_plots_s=after_seconds,
        file_mb=file_mb,
        max_ic={name: entry["max_ic"] for name, entry in summary.items()},
    )


def _yardstick_inputs(n_steps, seed=0):
    """Two inputs of the yardstick: random levels that never rest, and the same resting at zero from half-way."""
    rng = np.random.default_rng(seed)
    never = np.repeat(rng.uniform(0.5, 1.5, n_steps // 100 + 1), 100)[:n_steps]
    rests = never.copy()
    rests[n_steps // 2 :] = 0.0
    return {"never rests": never, "rests at zero from half-way": rests}


def _bare_pass():
    """The least work an analysis must do: simulate every sample and accumulate |y - sim|, fused, compiled.

    Samples in blocks of 64 so that the inner loop over a block vectorises; states below the simulators'
    flush level set to zero as they do, so no subnormal arithmetic; blocks spread over numba's threads.
    """
    import numba

    from dynia.models.base import FLUSH_BELOW

    @numba.njit(parallel=True)
    def bare(pole, gain, u, y, total):
        width = 64
        for block in numba.prange((pole.size + width - 1) // width):
            lo = block * width
            hi = min(lo + width, pole.size)
            a, b = pole[lo:hi].copy(), gain[lo:hi].copy()
            x, acc = np.zeros(hi - lo), np.zeros(hi - lo)
            for k in range(u.size):
                for i in range(hi - lo):
                    acc[i] += abs(x[i] - y[k])
                    following = a[i] * x[i] + b[i] * u[k]
                    x[i] = following if abs(following) >= FLUSH_BELOW else 0.0
            total[lo:hi] = acc

    return bare


def _case_yardstick(n_samples=20_000, n_steps=20_000):
    """dynia.run against the bare fused pass, both inputs, n = 10 and 100; scaling exponents in S, N and n."""
    from dynia.models import FirstOrder
    from dynia.pipeline import run

    bare = _bare_pass()
    bounds = {"K": (0, 4), "T": (1.5, 6)}
    params = np.random.default_rng(1).uniform([0, 1.5], [4, 6], (n_samples, 2))
    pole = np.exp(-1.0 / params[:, 1])
    gain = params[:, 0] * (1 - pole)
    rows = []
    for label, u_input in _yardstick_inputs(n_steps).items():
        rows += _yardstick_rows(bare, label, u_input, pole, gain, bounds, n_samples)
    u_full = _yardstick_inputs(n_steps)["never rests"]
    y_full = FirstOrder().simulate([[2.0, 3.0]], u_full)[0]

    def timed(samples, steps, n):
        return best_of(
            lambda: run(u_full[:steps], y_full[:steps], FirstOrder(), bounds, n_samples=samples, n=n, rng=1), 2
        )

    sizes = (n_samples // 4, n_samples // 2, n_samples)
    lengths = (n_steps // 4, n_steps // 2, n_steps)
    halves = (10, 30, 100)
    small_s, small_n = n_samples // 4, n_steps // 4
    exponents = dict(
        samples=_loglog_slope(sizes, [timed(size, small_n, 10) for size in sizes]),
        steps=_loglog_slope(lengths, [timed(small_s, length, 10) for length in lengths]),
        half_window=_loglog_slope(halves, [timed(small_s, small_n, half) for half in halves]),
    )
    return dict(n_samples=n_samples, n_steps=n_steps, rows=rows, exponents=exponents, machine=_machine())


def _yardstick_rows(bare, label, u, pole, gain, bounds, n_samples):
    """The bare pass and dynia.run (n = 10 and 100) on one input, best of 3 each."""
    from dynia.models import FirstOrder
    from dynia.pipeline import run

    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(2).normal(0, 0.1, u.size)
    bare(pole[:64], gain[:64], u[:100], y[:100], np.empty(64))  # compile
    run(u[:500], y[:500], FirstOrder(), bounds, n_samples=200, n=10, rng=1, flavour="thesis")  # compile
    rows = []
    for n in (10, 100):
        row = dict(input=label, n=n)
        for clock, name in ((time.perf_counter, "wall"), (time.process_time, "cpu")):
            row[f"bare_{name}_s"] = best_of(lambda: bare(pole, gain, u, y, np.empty(pole.size)), 3, clock)
            row[f"run_{name}_s"] = best_of(
                lambda n=n: run(u, y, FirstOrder(), bounds, n_samples=n_samples, n=n, rng=1, flavour="thesis"),
                3,
                clock,
            )
            row[f"{name}_ratio"] = row[f"run_{name}_s"] / row[f"bare_{name}_s"]
        rows.append(row)
    return rows


def _loglog_slope(x, seconds):
    return float(np.polyfit(np.log(x), np.log(seconds), 1)[0])


def _follow_plant(n_rows, seed=1):
    """A first-order loop logged at 1 s: random levels held 200 s, noise 0.5."""
    from dynia.models import FirstOrder

    rng = np.random.default_rng(seed)
    u = np.repeat(rng.choice([0.0, 10.0, 20.0, 30.0], n_rows // 200 + 1), 200)[:n_rows]
    return u, FirstOrder().simulate([[2.0, 25.0]], u)[0] + rng.normal(0, 0.5, n_rows)


def _case_follow(n_rows=100_000, steady_rows=300, n_samples=2_000):
    """dynia follow: a backlog against dynia analyse on the same rows, then the cost of one new row (CPU, wall)."""
    import tempfile

    import sqlalchemy as sa

    from dynia.cli import main as cli_main
    from dynia.io.database import connect

    u, y = _follow_plant(n_rows + steady_rows)
    common = ["--time", "time", "--input", "u", "--output", "y", "--model", "first-order", "--param", "K=0:5"]
    common += ["--param", "T=0:50", "--samples", str(n_samples), "--n", "10", "--seed", "1", "--quiet"]
    with tempfile.TemporaryDirectory() as folder:
        data = Path(folder, "plant.csv")
        np.savetxt(
            data,
            np.column_stack([np.arange(n_rows), u[:n_rows], y[:n_rows]]),
            delimiter=",",
            fmt=["%d", "%.17g", "%.17g"],
            header="time,u,y",
            comments="",
        )
        url = f"sqlite:///{folder}/plant.db"
        engine = connect(url)
        table = sa.Table(
            "plant",
            sa.MetaData(),
            sa.Column("time", sa.Float, index=True),
            sa.Column("u", sa.Float),
            sa.Column("y", sa.Float),
        )
        table.create(engine)

        def log(first, stop):
            with engine.begin() as connection:
                connection.execute(
                    table.insert(), [dict(time=float(k), u=float(u[k]), y=float(y[k])) for k in range(first, stop)]
                )

        log(0, n_rows)
        # Both compile first on a short record, so that the comparison is of the work, not of the compilation.
        warm = Path(folder, "warm.csv")
        np.savetxt(
            warm,
            np.column_stack([np.arange(2000), u[:2000], y[:2000]]),
            delimiter=",",
            fmt="%.17g",
            header="time,u,y",
            comments="",
        )
        cli_main(["analyse", str(warm), *common, "--no-plots", "--out", str(Path(folder, "warm"))])
        cpu, wall = time.process_time(), time.perf_counter()
        analyse_status = cli_main(["analyse", str(data), *common, "--out", str(Path(folder, "out"))])
        analyse_cpu, analyse_wall = time.process_time() - cpu, time.perf_counter() - wall
        cpu, wall = time.process_time(), time.perf_counter()
        follow_status = cli_main(["follow", url, "--table", "plant", *common, "--once"])
        follow_cpu, follow_wall = time.process_time() - cpu, time.perf_counter() - wall
        steady = _follow_steady(url, engine, log, n_rows, steady_rows, n_samples)
    return dict(
        rows=n_rows,
        n_samples=n_samples,
        analyse_status=analyse_status,
        follow_status=follow_status,
        analyse_cpu_s=analyse_cpu,
        analyse_wall_s=analyse_wall,
        follow_cpu_s=follow_cpu,
        follow_wall_s=follow_wall,
        ratio_cpu=follow_cpu / analyse_cpu,
        machine=_machine(),
        **steady,
    )


def _follow_steady(url, engine, log, first, rows, n_samples):
    """One new row at a time, each followed by a poll of the follower: CPU and wall time per row."""
    from dynia.follow import Follower, FollowerSettings
    from dynia.io.database import Source
    from dynia.models import FirstOrder
    from dynia.settings import AnalysisSettings

    source = Source(engine, "plant", time="time", inputs=["u"], output="y")
    settings = FollowerSettings(
        options={}, analysis=AnalysisSettings(window="trailing", n_samples=n_samples, n=10), seed=1
    )
    follower = Follower(engine, source, FirstOrder(), {"K": (0, 5), "T": (0, 50)}, settings, "steady")
    follower.poll()
    cpu, wall = [], []
    for k in range(first, first + rows):
        log(k, k + 1)
        started_cpu, started_wall = time.process_time(), time.perf_counter()
        follower.poll()
        cpu.append(time.process_time() - started_cpu)
        wall.append(time.perf_counter() - started_wall)
    cpu, wall = np.array(cpu[20:]) * 1e3, np.array(wall[20:]) * 1e3  # the first polls warm the caches
    return dict(
        row_cpu_ms=float(cpu.mean()),
        row_wall_ms=float(wall.mean()),
        row_wall_p99_ms=float(np.percentile(wall, 99)),
        steady_rows=int(cpu.size),
    )


# The README's quick start, as a newcomer runs it in a fresh process.
QUICK_START = """
import numpy as np
import dynia

u = np.r_[np.zeros(50), np.full(150, 35.0), np.zeros(100)]
y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
y = y + np.random.default_rng(0).normal(0, 0.5, y.size)
res = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=2000, n=10, percentage=10, rng=1)
assert res.ic.shape == (2, 300)
"""


def _child_seconds(command, cache):
    """CPU (user + system) and wall seconds of ``command`` in a fresh process, numba's cache in ``cache``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True, env={**os.environ, "NUMBA_CACHE_DIR": str(cache)})
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime, wall


def _case_cold_start():
    """The quick start in a fresh process with an empty numba cache, then with it filled; the help compiles nothing."""
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        cache = Path(folder) / "numba"
        cache.mkdir()
        script = Path(folder) / "quick_start.py"
        script.write_text(QUICK_START)
        helps = [
            _child_seconds([sys.executable, "-m", "dynia.cli", *words, "--help"], cache) for words in ([], ["analyse"])
        ]
        help_files = sum(1 for _ in cache.rglob("*"))
        cold = _child_seconds([sys.executable, str(script)], cache)
        warm = _child_seconds([sys.executable, str(script)], cache)
    return dict(
        cold_cpu_s=cold[0],
        cold_wall_s=cold[1],
        warm_cpu_s=warm[0],
        warm_wall_s=warm[1],
        help_cpu_s=[cpu for cpu, _ in helps],
        files_cached_by_help=help_files,
        machine=_machine(),
    )


def _machine():
    """What the ratios were measured on: processor, cores, load."""
    model = "unknown processor"
    try:
        with open("/proc/cpuinfo") as info:
            model = next((line.split(":", 1)[1].strip() for line in info if line.startswith("model name")), model)
    except OSError:
        pass
    return dict(processor=model, cores=os.cpu_count(), load_average=os.getloadavg()[0])


CASES = {
    "port-vs-engine": _case_port_vs_engine,
    "engine-20000x2000": lambda: _case_engine(20_000, 2_000),
    "run-20000x2000": lambda: _case_run(20_000, 2_000),
    "run-100000x10000": lambda: _case_run(100_000, 10_000),
    "throughput-20000x20000": _case_throughput,
    "memory-100000x100000": lambda: _case_run(100_000, 100_000),
    "online-10000": _case_online,
    "sampling-example1": _case_sampling,
    "cli-500000-rows": _case_cli_long_record,
    "custom-models": _case_custom_models,
    "distributed": _case_distributed,
    "ic-error-cost": _case_ic_error_cost,
    "ic-error-honesty": _case_ic_error_honesty,
    "long-record": _case_long_record,
    "yardstick": _case_yardstick,
    "follow": _case_follow,
    "cold-start": _case_cold_start,
}


def _run_case(name, **options):
    result = CASES[name](**options)
    result["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(result))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0], allow_abbrev=False)
    parser.add_argument("--case", choices=sorted(CASES), help="run one case in this process")
    parser.add_argument("--skip", nargs="*", default=[], choices=sorted(CASES), help="cases to leave out")
    parser.add_argument("--distributed-samples", type=int, default=4_000, help="samples of the distributed case")
    parser.add_argument("--distributed-steps", type=int, default=200_000, help="steps of the distributed case")
    parser.add_argument("--distributed-time-chunks", type=int, help="time_chunks of the distributed case")
    parser.add_argument("--long-samples", type=int, default=10_000, help="samples of the long-record case")
    parser.add_argument("--long-steps", type=int, default=30_000_000, help="steps of the long-record case")
    parser.add_argument("--yardstick-samples", type=int, default=20_000, help="samples of the yardstick case")
    parser.add_argument("--yardstick-steps", type=int, default=20_000, help="steps of the yardstick case")
    parser.add_argument("--ic-error-samples", type=int, default=20_000, help="samples of the ic-error-cost case")
    parser.add_argument("--ic-error-steps", type=int, default=20_000, help="steps of the ic-error-cost case")
    args = parser.parse_args(argv)
    if args.case:
        sizes = dict(
            n_samples=args.distributed_samples, n_steps=args.distributed_steps, time_chunks=args.distributed_time_chunks
        )
        options = {
            "distributed": sizes,
            "long-record": dict(n_samples=args.long_samples, n_steps=args.long_steps),
            "yardstick": dict(n_samples=args.yardstick_samples, n_steps=args.yardstick_steps),
            "ic-error-cost": dict(n_samples=args.ic_error_samples, n_steps=args.ic_error_steps),
        }
        _run_case(args.case, **options.get(args.case, {}))
        return
    for name in CASES:
        if name in args.skip:
            continue
        output = subprocess.run(
            [sys.executable, "-m", "benchmarks.bench", "--case", name],
            check=True,
            capture_output=True,
            text=True,
            cwd=Path(__file__).resolve().parent.parent,
        ).stdout
        result = json.loads(output.strip().splitlines()[-1])
        print(_describe(name, result), flush=True)


def _describe_yardstick(r):
    lines = [
        f"dynia.run against the bare fused pass (simulate + accumulate |y - sim|, compiled), "
        f"{r['n_samples']} samples x {r['n_steps']} steps, thesis flavour, best of 3, CPU time and wall clock "
        f"in one process ({r['machine']['processor']}, {r['machine']['cores']} cores, "
        f"load {r['machine']['load_average']:.1f}):"
    ]
    lines += [
        f"  {row['input']}, n = {row['n']}: bare {row['bare_cpu_s']:.2f} CPU-s ({row['bare_wall_s']:.2f} s wall), "
        f"dynia.run {row['run_cpu_s']:.2f} CPU-s ({row['run_wall_s']:.2f} s wall) -> {row['cpu_ratio']:.1f}x the "
        f"bare pass in CPU time (goal <= 10x), {row['wall_ratio']:.1f}x in wall clock"
        for row in r["rows"]
    ]
    e = r["exponents"]
    lines.append(
        f"  scaling exponents of dynia.run: samples {e['samples']:.2f}, steps {e['steps']:.2f}, "
        f"half window n {e['half_window']:.2f} (goal: about 1, 1 and 0)"
    )
    return "\n".join(lines)


def _describe_ic_error_honesty(r):
    lines = ["IC standard error, predicted (mean ic_se) vs empirical (SD over 20 seeds), medians over the steps:"]
    lines += [
        f"  example {row['example']} at {row['percentage']:g} % ({row['n_samples']} samples), {row['parameter']}: "
        f"empirical {row['empirical_median']:.4f}, predicted {row['predicted_median']:.4f}, ratio "
        f"{row['ratio']:.2f} (step by step {row['stepwise_ratio']:.2f}; target within 1/1.5 .. 1.5)"
        for row in r["rows"]
    ]
    return "\n".join(lines)


def _describe_ic_error_cost(r):
    costs = "; ".join(
        f"{level}: {r[level]['plain_s']:.2f} s plain, {r[level]['ic_error_s']:.2f} s with ic_error "
        f"({r[level]['ic_error_s'] / r[level]['plain_s']:.2f}x)"
        for level in ("10 %", "1 %", "0.1 %", "resting")
        if level in r
    )
    return (
        f"Monte Carlo error of IC, complete runs of {r['n_samples']} samples x {r['n_steps']} steps, one thread, "
        "CPU seconds: "
        f"{costs} (resting: 10 % on the yardstick's record that rests at zero; goal at most 1.15x)"
    )


def _describe_port_vs_engine(r):
    return (
        f"thesis example 1 (500 steps, 2000 samples, K and T): port {r['port_s']:.2f} s, "
        f"engine {r['engine_s'] * 1e3:.1f} ms -> {r['ratio']:.0f}x (target >= 300x); "
        f"one thread {r['engine_one_thread_s'] * 1e3:.1f} ms -> {r['ratio_one_thread']:.0f}x; "
        f"peak RSS {r['peak_rss_mb']:.0f} MB"
    )


def _describe_throughput_20000x20000(r):
    engines = "; ".join(
        f"{engine} engine {r[engine]['seconds']:.2f} s = {r[engine]['sample_steps_per_s']:.3g} "
        f"sample-steps/s, {r[engine]['ratio_to_port']:.0f}x the port"
        for engine in ("numba", "numpy")
    )
    return (
        f"complete analysis (simulate + K and T, thesis flavour), 20 000 samples x 20 000 steps: "
        f"{engines} (port {r['port_sample_steps_per_s']:.3g} sample-steps/s on example 1; "
        f"target >= 1e8); peak RSS {r['peak_rss_mb']:.0f} MB"
    )


def _describe_memory_100000x100000(r):
    return (
        f"dynia.run, 10^5 samples x 10^5 steps ({r['engine']} engine): {r['seconds']:.0f} s, "
        f"{r['sample_steps_per_s']:.3g} sample-steps/s, peak RSS {r['peak_rss_mb']:.0f} MB "
        "(target <= 2048 MB)"
    )


def _describe_online_10000(r):
    return (
        f"OnlineDynia.update, 10 000 samples, first order, n=10 ({r['updates']} updates): mean "
        f"{r['mean_ms']:.3f} ms, median {r['median_ms']:.3f} ms, 99th percentile {r['p99_ms']:.3f} ms "
        f"(target <= 1 ms); peak RSS {r['peak_rss_mb']:.0f} MB"
    )


def _describe_custom_models(r):
    built_in, custom = r["built-in FirstOrder"], r["StateSpaceModel (numba)"]
    function = r["function_model"]
    return (
        f"20 000 samples x 20 000 steps, complete runs: built-in FirstOrder {built_in['seconds']:.2f} s = "
        f"{built_in['sample_steps_per_s']:.3g} sample-steps/s, StateSpaceModel with numba step/output "
        f"{custom['seconds']:.2f} s = {custom['sample_steps_per_s']:.3g} -> {r['ratio']:.2f} of the built-in "
        f"(target >= 0.33); pure-numpy FunctionModel at 5 000 x 5 000: dynia.run {function['run_s']:.2f} s, fn + "
        f"moving_window by hand {function['by_hand_s']:.2f} s -> overhead {100 * function['overhead']:.1f} % "
        f"(target < 10 %); peak RSS {r['peak_rss_mb']:.0f} MB"
    )


def _describe_distributed(r):
    m, single = r["machine"], r["dynia_run"]
    lines = [
        f"dynia.distributed.run, {r['n_samples']:,} samples x {r['n_steps']:,} steps, first order, local clusters of "
        f"single-threaded workers, against dynia.run in one thread ({m['processor']}, {m['cores']} cores), faster of "
        f"two runs:",
        f"  dynia.run: {single['seconds']:.1f} s wall, {single['cpu_s']:.1f} s CPU (load {single['load_average']:.1f})",
    ]
    for count in ("1 workers", "2 workers"):
        c = r[count]
        lines.append(
            f"  {count[0]} worker{'s' if count[0] != '1' else ''}: {c['seconds']:.1f} s wall, {c['cpu_s']:.1f} s CPU "
            f"(client {c['client_cpu_s']:.1f} + workers {' + '.join(f'{cpu:.1f}' for cpu in c['worker_cpu_s'])}), "
            f"worker peak RSS {', '.join(f'{peak:.0f}' for peak in c['worker_peak_rss_mb'])} MB, "
            f"{'equal to' if c['equal'] else 'DIFFERENT from'} dynia.run's bit for bit (load {c['load_average']:.1f})"
        )
    ratio = r["one_worker_over_run"]
    lines.append(
        f"  one worker / dynia.run: {ratio['wall']:.2f} wall, {ratio['cpu']:.2f} CPU (goal <= 1.3); two workers "
        f"{r['speed_up']:.2f}x faster than one (goal >= 1.6), {r['cpu_two_over_one']:.2f}x its CPU"
    )
    return "\n".join(lines)


def _describe_long_record(r):
    return (
        f"dynia.run, {r['n_samples']:,} samples x {r['n_steps']:,} steps, float32 + store: {r['seconds']:.0f} s "
        f"= {r['sample_steps_per_s']:.3g} sample-steps/s, peak RSS {r['run_peak_rss_mb']:.0f} MB "
        f"(the data alone {r['data_peak_rss_mb']:.0f} MB; target <= 4096 MB), after summary and plots "
        f"{r['peak_rss_mb']:.0f} MB ({r['summary_and_plots_s']:.0f} s); file {r['file_mb']:.0f} MB"
    )


def _describe_cli_500000_rows(r):
    return (
        f"dynia analyse on a {r['rows']:,}-row CSV, 500 samples, plots on ({r['figures']} figures, exit "
        f"{r['status']}): {r['seconds']:.0f} s, peak RSS {r['peak_rss_mb']:.0f} MB (target <= 1536 MB)"
    )


def _describe_sampling_example1(r):
    runs = ", ".join(
        f"{key}: RMSE {value['rmse']:.3f} in {value['seconds']:.1f} s"
        for key, value in r.items()
        if key != "peak_rss_mb"
    )
    return (
        f"example 1 at percentage 0.1, IC error against uniform 400 000 by sampler and "
        f"evaluations: {runs} (goal: an adaptive sampler at 10 000 matching uniform at 100 000)"
    )


def _describe_follow(r):
    m = r["machine"]
    return (
        f"dynia follow on SQLite ({m['processor']}, {m['cores']} cores, load {m['load_average']:.1f}): a backlog of "
        f"{r['rows']} rows at {r['n_samples']} samples, n = 10, --once: {r['follow_cpu_s']:.1f} CPU-s "
        f"({r['follow_wall_s']:.1f} s wall) against dynia analyse on the same rows {r['analyse_cpu_s']:.1f} CPU-s "
        f"({r['analyse_wall_s']:.1f} s wall) -> {r['ratio_cpu']:.2f}x (goal <= 2x); then one new row per poll: "
        f"{r['row_cpu_ms']:.2f} CPU-ms, {r['row_wall_ms']:.2f} ms wall (p99 {r['row_wall_p99_ms']:.1f} ms) a row, "
        f"database included, over {r['steady_rows']} rows (goal <= 5 ms)"
    )


def _describe_cold_start(r):
    m = r["machine"]
    return (
        f"first run, the README's quick start (2 000 samples x 300 steps) in a fresh process "
        f"({m['processor']}, load {m['load_average']:.1f}): empty numba cache {r['cold_cpu_s']:.1f} CPU-s "
        f"({r['cold_wall_s']:.1f} s wall; goal <= 10 CPU-s), cache filled {r['warm_cpu_s']:.1f} CPU-s "
        f"({r['warm_wall_s']:.1f} s wall; goal <= 2); `dynia --help` and `dynia analyse --help` "
        f"{r['help_cpu_s'][0]:.1f} and {r['help_cpu_s'][1]:.1f} CPU-s, {r['files_cached_by_help']} files compiled"
    )


_DESCRIPTIONS = {
    "follow": _describe_follow,
    "yardstick": _describe_yardstick,
    "ic-error-cost": _describe_ic_error_cost,
    "ic-error-honesty": _describe_ic_error_honesty,
    "port-vs-engine": _describe_port_vs_engine,
    "throughput-20000x20000": _describe_throughput_20000x20000,
    "memory-100000x100000": _describe_memory_100000x100000,
    "online-10000": _describe_online_10000,
    "custom-models": _describe_custom_models,
    "distributed": _describe_distributed,
    "long-record": _describe_long_record,
    "cli-500000-rows": _describe_cli_500000_rows,
    "sampling-example1": _describe_sampling_example1,
    "cold-start": _describe_cold_start,
}


def _describe(name, r):
    if name in _DESCRIPTIONS:
        return _DESCRIPTIONS[name](r)
    return (
        f"{name}: {r['seconds']:.2f} s, {r['sample_steps_per_s']:.3g} sample-steps/s, "
        f"peak RSS {r['peak_rss_mb']:.0f} MB"
    )


if __name__ == "__main__":
    main()
