"""Sweeps on a Dask cluster: the compiled models built once per host before the cases, and a throw-away cluster.

:func:`whipple_kick.studies.sweep_engine.sweep` runs on any ``concurrent.futures`` executor, a Dask client's
``get_executor()`` among them. On a cluster, :func:`prepare_workers` readies the workers first: one worker of each
host builds (or loads) every compiled model the sweep's cases ask for, then every worker loads them, keeps the
memory it frees as the default pool's workers do, stops Dask's sampling profiler (the pool's workers have none)
and runs one short case per model, so the first real cases do not pay for imports and builds. The cache's own
file lock (:func:`whipple_kick.model.cache.build_once`) keeps two workers of one host that ask for the same
missing model at once from building it twice; preparing one worker per host first makes the build happen before
any case is waiting on it, and a build that fails fails once, here.

:func:`command_line_cluster` starts a cluster the way a real one is started, from the command line
(``dask scheduler`` and ``dask worker`` processes talking over TCP), on this machine: for
``scripts/dask_cluster.py`` and the tests. docs/sweeps.md says how to run a sweep on a real cluster.
"""
import contextlib
import json
import os
import pathlib
import signal
import socket
import subprocess
import sys
import tempfile
import time
import uuid
import warnings

from whipple_kick.errors import InputError, PerformanceWarning
from whipple_kick.model.slip import compiled
from whipple_kick.simulate.assembly import model_of

from .sweep_engine import _memory_kept_once, _preload, make_cases, run_case

#: Length [s] of each worker's warm-up case (one per compiled model): past the kick's start, so the run goes
#: through every step a case takes (steady state, rider, integration, summary), at about a tenth of a 6 s case.
WARMUP_DURATION = 0.5


def warmup_cases(scenarios):
    """One short scenario per compiled model the ``scenarios`` ask for: ``[(layout key, scenario), ...]``.

    The first scenario of each model, cut to :data:`WARMUP_DURATION`. A scenario whose settings name no model
    (an invalid value) is left out: its case fails on its own and says why.
    """
    chosen = {}
    for scenario in scenarios:
        try:
            key = model_of(scenario.body_spec, scenario.tyre_transient).layout.key
            short = scenario.with_changes(duration=min(scenario.duration, WARMUP_DURATION))
        except (InputError, ValueError):
            continue
        chosen.setdefault(key, short)
    return list(chosen.items())


def _stop_profiler(dask_worker):
    """Stop a Dask worker's sampling profiler (run by ``client.run``, in the worker's event loop); whether it ran.

    Dask's default takes the running task's stack every 10 ms (``distributed.worker.profile.interval``), the GIL
    with it, for the dashboard's profile page; the pool's workers have no such sampling (docs/sweeps.md measures
    what it costs a case).
    """
    stopped = False
    for name in ("profile", "profile-cycle"):
        callback = dask_worker.periodic_callbacks.get(name)
        if callback is not None and callback.is_running():
            callback.stop()
            stopped = True
    return stopped


def _ready_worker(address, warmups):
    """In one worker: keep freed memory, load (building on a miss) each model, run each warm-up case.

    Returns ``{"worker", "host", "pid", "built", "memory_kept", "warmup_status", "started", "loaded", "seconds"}``;
    ``built`` lists the builds this process did (each build announces itself with a
    :class:`~whipple_kick.errors.PerformanceWarning`, once per build), so the builds across a cluster add up;
    ``started`` and ``loaded`` are the Unix times [s] it began and had every model loaded, ``seconds`` how long
    it took in all.
    """
    started, start = time.time(), time.perf_counter()
    memory_kept = _memory_kept_once()
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always", PerformanceWarning)
        _preload()   # the rigid rider's model, which every sweep process loads first
        statuses = []
        for _, scenario in warmups:
            layout = model_of(scenario.body_spec, scenario.tyre_transient).layout
            # The cache entry checked (built on a miss) even where this process has loaded the model before.
            compiled.library_path(layout)
            compiled.library(layout)
        loaded = time.time()
        for _, scenario in warmups:
            statuses.append(run_case(scenario, "warm-up")["status"])
    built = [str(w.message) for w in said
             if issubclass(w.category, PerformanceWarning) and str(w.message).startswith("building the slip model")]
    return {"worker": address, "host": socket.gethostname(), "pid": os.getpid(), "built": built,
            "memory_kept": memory_kept, "warmup_status": statuses, "started": started, "loaded": loaded,
            "seconds": time.perf_counter() - start}


def scheduler_workers(client):
    """The scheduler's ``{address: info}`` of every worker (newer Dask lists 5 unless asked for all)."""
    try:
        return client.scheduler_info(n_workers=-1)["workers"]
    except TypeError:   # an older distributed has no n_workers, and lists them all
        return client.scheduler_info()["workers"]


def prepare_workers(client, grid=None, cases=None, *, base=None, profiler=False):
    """Ready a Dask cluster's workers for a sweep: the compiled models built once per host, then loaded by all.

    Parameters
    ----------
    client : dask.distributed.Client
        Connected to the cluster; its workers must have joined (``client.wait_for_workers(n)``).
    grid, cases, base
        The sweep's cases, as :func:`~whipple_kick.studies.sweep_engine.sweep` takes them: they name the
        compiled models to build (the rigid rider's always).
    profiler : bool
        Keep Dask's sampling profiler running in the workers (its dashboard page); by default it is stopped,
        as it slows a case (:func:`_stop_profiler`).

    Returns
    -------
    list of dict
        One per worker (:func:`_ready_worker`'s report, and ``profiler_stopped``), the first worker of each
        host first.

    Each model is built on one worker per host (the scheduler's ``host`` of the worker) before the other
    workers of that host load it from the cache folder they share. Workers that join later (an adaptive
    cluster) load or build on their first case, under the cache's lock, and keep the profiler unless the
    workers' Dask configuration turns it off (``distributed.worker.profile.enabled: false``).
    """
    warmups = warmup_cases(sc for _, sc, _ in make_cases(grid, cases, base))
    workers = scheduler_workers(client)
    if not workers:
        raise InputError("the Dask cluster has no workers yet; wait for them first (client.wait_for_workers(n))")
    by_host = {}
    for address, info in sorted(workers.items()):
        by_host.setdefault(info["host"], []).append(address)
    first = [addresses[0] for addresses in by_host.values()]
    rest = [address for addresses in by_host.values() for address in addresses[1:]]
    tag = uuid.uuid4().hex[:8]
    reports = []
    for group in (first, rest):
        # A task, not client.run: a build of 20-60 s would block the worker's event loop (and its heartbeats).
        futures = [client.submit(_ready_worker, address, warmups, key=f"whipple-kick-ready-{tag}-{address}",
                                 workers=[address], allow_other_workers=False, pure=False) for address in group]
        reports += client.gather(futures)
    stopped = {} if profiler else client.run(_stop_profiler, workers=[r["worker"] for r in reports])
    for report in reports:
        report["profiler_stopped"] = stopped.get(report["worker"], False)
    return reports


# ----------------------------------------------------------------------- a throw-away cluster of processes

def _dask_command(program):
    """The ``dask scheduler`` / ``dask worker`` command of this Python (its own module: no PATH needed)."""
    return [sys.executable, "-m", f"distributed.cli.dask_{program}"]


def _log_tail(path, n=20):
    try:
        return "\n".join(pathlib.Path(path).read_text(errors="replace").splitlines()[-n:])
    except OSError:
        return "(no log)"


@contextlib.contextmanager
def command_line_cluster(n_workers=2, *, env=None, preload=None, timeout=60.0, nanny=True):
    """A Dask cluster of separate processes on this machine, started as on a real one; yields its address.

    ``dask scheduler`` on 127.0.0.1 (a free port) and ``n_workers`` ``dask worker`` processes of one thread
    each, connected over TCP through the scheduler file. The processes are this context's: on exit each is
    sent SIGTERM (SIGKILL 10 s later if still there).

    Parameters
    ----------
    n_workers : int
        Worker processes, one thread each (a case is single-threaded).
    env : dict, optional
        The processes' environment (default: this one's), e.g. their ``WHIPPLE_KICK_CACHE``.
    preload : path-like, optional
        A Python file each worker runs at start (``dask worker --preload``).
    timeout : float
        Seconds [s] to wait for the scheduler and for every worker to join.
    nanny : bool
        Start each worker under a nanny process (the ``dask worker`` default, which also sets the worker's
        environment: ``MALLOC_TRIM_THRESHOLD_``, one BLAS thread).

    Raises
    ------
    RuntimeError
        The cluster did not come up within ``timeout`` (the end of its log in the message).
    """
    if isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1:
        raise InputError(f"n_workers = {n_workers!r} must be a whole number >= 1")
    from distributed import Client

    processes = []
    with tempfile.TemporaryDirectory(prefix="wk-dask-") as folder:
        folder = pathlib.Path(folder)
        scheduler_file = folder / "scheduler.json"

        def start(args, name):
            log = open(folder / f"{name}.log", "wb")
            try:
                processes.append(subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT, env=env, cwd=folder,
                                                  stdin=subprocess.DEVNULL))
            finally:
                log.close()

        try:
            start([*_dask_command("scheduler"), "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                   "--scheduler-file", str(scheduler_file)], "scheduler")
            deadline = time.monotonic() + timeout
            address = None
            while address is None:
                try:
                    address = json.loads(scheduler_file.read_text())["address"]
                except (OSError, ValueError, KeyError):
                    if time.monotonic() > deadline or processes[0].poll() is not None:
                        raise RuntimeError(f"the Dask scheduler did not start within {timeout} s:\n"
                                           f"{_log_tail(folder / 'scheduler.log')}") from None
                    time.sleep(0.1)
            worker_args = [*_dask_command("worker"), address, "--nthreads", "1", "--nworkers", "1",
                           "--host", "127.0.0.1", "--no-dashboard", "--nanny" if nanny else "--no-nanny"]
            if preload is not None:
                worker_args += ["--preload", str(preload)]
            for i in range(n_workers):
                start([*worker_args, "--name", f"worker-{i}"], f"worker-{i}")
            with Client(address, timeout=timeout) as client:
                try:
                    client.wait_for_workers(n_workers, timeout=max(1.0, deadline - time.monotonic()))
                except TimeoutError:
                    raise RuntimeError(f"{n_workers} Dask workers did not join within {timeout} s:\n"
                                       f"{_log_tail(folder / 'worker-0.log')}") from None
            yield address
        finally:
            for process in reversed(processes):   # the workers first, then the scheduler
                if process.poll() is None:
                    process.send_signal(signal.SIGTERM)
            for process in reversed(processes):
                try:
                    process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()
