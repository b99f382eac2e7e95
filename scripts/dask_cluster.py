"""A sweep on a Dask cluster, checked against the process pool: the same table, and the time per case of each.

Usage:
    python scripts/dask_cluster.py                                # a throw-away cluster on this machine
    python scripts/dask_cluster.py --scheduler tcp://HOST:8786    # an existing cluster, by its scheduler's address
    python scripts/dask_cluster.py --workers 2 --repeats 7 --duration 6 --empty-cache --memory-off

Without ``--scheduler`` the script starts a cluster the way one is started on real machines, from the command
line: ``dask scheduler`` and ``--workers`` ``dask worker`` processes of one thread each (under their nannies),
talking over TCP on 127.0.0.1 (:func:`whipple_kick.studies.cluster.command_line_cluster`); it ends them at the
end. With ``--scheduler`` it connects to a running cluster and leaves it running.

What it does:

1. ``prepare_workers``: one worker per host builds (or loads) the compiled model, then every worker loads it,
   keeps the memory it frees, stops Dask's sampling profiler and runs a short case; prints each worker's report, with the builds it did.
   ``--empty-cache`` (throw-away cluster only) gives the workers an empty cache folder of their own, shared by
   them as by the workers of one node: the report then counts the builds on this host (one expected).
2. The sweep (the nine thesis cases, 300/400/500 kPa x 570/635/701 N, ``--duration`` s after the kick) on the
   process pool of as many workers (kept between sweeps, as in a session) and on the cluster
   (``client.get_executor()``), once each untimed, then ``--repeats`` times each, in an order that alternates
   from repeat to repeat, so a neighbour's load falls on both alike.
3. Every table compared with the pool's first, exactly, less the columns that describe the run
   (``sweep_engine.VOLATILE_COLUMNS``); any difference is an error (exit 1).
4. Prints the median sweep wall time per case of each and the median of the per-repeat ratios (cluster over
   pool), the median ``run.wall_s`` (the case's own wall time in its worker, without the scheduling) and
   ``run.cpu_s`` (its worker process' CPU time over the case, every thread: the profiler's sampling and the
   page faults' system time included, and less sensitive than wall times to a neighbour's load). ``--memory-off`` (throw-away cluster only) runs a second cluster whose
   workers keep Dask's own memory setting (the nanny's ``MALLOC_TRIM_THRESHOLD_``, no ``mallopt``), as before
   the workers of any executor kept their freed memory, measured in the same repeats; ``--profiler-on`` one whose
   workers keep Dask's sampling profiler (``prepare_workers(profiler=True)``), which the others stop.
"""
import argparse
import contextlib
import functools
import os
import pathlib
import socket
import statistics
import sys
import tempfile
import time

#: Worker preload that keeps a Dask worker from setting the sweep's memory setting (``--memory-off``): marks it
#: as done, so ``_memory_kept_once`` never calls ``mallopt``.
_MEMORY_OFF = ("from whipple_kick.studies import sweep_engine\n"
               "sweep_engine._memory_kept = False\n")


def _thesis_cases(duration):
    from whipple_kick.simulate.scenario import Scenario
    return {"pressure_kpa": [300.0, 400.0, 500.0], "fz_n": [570.0, 635.0, 701.0]}, Scenario(duration=duration)


def _timed(run):
    start = time.perf_counter()
    table = run()
    return time.perf_counter() - start, table


def _print_reports(label, reports):
    print(f"{label}: prepare_workers, one worker per host first")
    for r in reports:
        print(f"  {r['worker']} (host {r['host']}, pid {r['pid']}): {len(r['built'])} build(s), "
              f"memory kept {r['memory_kept']}, profiler stopped {r['profiler_stopped']}, warm-up {r['warmup_status']}, {r['seconds']:.1f} s")
    print(f"  builds in all: {sum(len(r['built']) for r in reports)} on {len({r['host'] for r in reports})} host(s)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scheduler", help="address of a running cluster's scheduler (tcp://HOST:PORT); "
                                            "default: start a throw-away one here")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of the throw-away cluster, and "
                                                              "the pool's size (default 2)")
    parser.add_argument("--repeats", type=int, default=7, help="timed sweeps of each (default 7)")
    parser.add_argument("--duration", type=float, default=6.0, help="run length after the kick [s] (default 6)")
    parser.add_argument("--empty-cache", action="store_true", help="the throw-away cluster's workers start from "
                                                                   "an empty cache folder (a real build)")
    parser.add_argument("--memory-off", action="store_true", help="also a cluster whose workers keep Dask's "
                                                                  "memory setting")
    parser.add_argument("--profiler-on", action="store_true", help="also a cluster whose workers keep Dask's "
                                                                   "sampling profiler")
    args = parser.parse_args(argv)
    if args.scheduler and (args.empty_cache or args.memory_off or args.profiler_on):
        parser.error("--empty-cache, --memory-off and --profiler-on start their own workers: not with --scheduler")
    if args.workers < 1 or args.repeats < 1 or not args.duration > 0:
        parser.error("--workers and --repeats must be >= 1 and --duration > 0 s")

    from distributed import Client

    import whipple_kick as wk
    from whipple_kick.studies import cluster, sweep_engine

    grid, base = _thesis_cases(args.duration)
    n_cases = 9
    print(f"{socket.gethostname()}: {os.cpu_count()} cores; load average {os.getloadavg()[0]:.2f} before the run; "
          f"nine thesis cases, {args.duration} s after the kick")

    with contextlib.ExitStack() as stack:
        folder = pathlib.Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="wk-dask-run-")))
        clusters = {}
        if args.scheduler:
            clusters["cluster"] = args.scheduler
        else:
            env = dict(os.environ)
            if args.empty_cache:
                (folder / "cache").mkdir(mode=0o700)
                env["WHIPPLE_KICK_CACHE"] = str(folder / "cache")
            clusters["cluster"] = stack.enter_context(cluster.command_line_cluster(args.workers, env=env,
                                                                                   timeout=120))
            if args.memory_off:
                (folder / "memory_off.py").write_text(_MEMORY_OFF)
                clusters["cluster, memory setting off"] = stack.enter_context(cluster.command_line_cluster(
                    args.workers, env=env, preload=folder / "memory_off.py", timeout=120))
            if args.profiler_on:
                clusters["cluster, profiler on"] = stack.enter_context(cluster.command_line_cluster(
                    args.workers, env=env, timeout=120))
        clients = {label: stack.enter_context(Client(address, timeout=60)) for label, address in clusters.items()}
        for label, client in clients.items():
            print(f"{label}: {clusters[label]}, {len(cluster.scheduler_workers(client))} workers")
            start = time.perf_counter()
            reports = cluster.prepare_workers(client, grid, base=base, profiler=label.endswith("profiler on"))
            print(f"  ({time.perf_counter() - start:.1f} s)")
            _print_reports(label, reports)
        pool_size = args.workers if not args.scheduler else len(
            cluster.scheduler_workers(clients["cluster"]))

        runs = {"pool": functools.partial(wk.sweep, grid, base=base, workers=pool_size, progress=False)}
        for label, client in clients.items():
            runs[label] = functools.partial(wk.sweep, grid, base=base, executor=client.get_executor(), progress=False)
        labels = list(runs)
        reference = _comparable(runs["pool"]())   # untimed: the pool starts
        differs = []
        for label in labels[1:]:   # untimed: the workers' first sweep
            if not _comparable(runs[label]()).equals(reference):
                differs.append(f"{label}, first sweep")
        walls = {label: [] for label in labels}
        case_walls = {label: [] for label in labels}
        case_cpus = {label: [] for label in labels}
        for repeat in range(args.repeats):
            order = labels[repeat % len(labels):] + labels[:repeat % len(labels)]
            for label in order:
                wall, table = _timed(runs[label])
                walls[label].append(wall / n_cases)
                case_walls[label].append(float(table["run.wall_s"].median()))
                case_cpus[label].append(float(table["run.cpu_s"].median()))
                if not _comparable(table).equals(reference):
                    differs.append(f"{label}, repeat {repeat + 1}")
        # What the kept memory costs: each worker's resident memory after the sweeps (Dask pauses a worker at 80 %
        # of its memory limit).
        memory = {"pool": _pool_rss()}
        for label, client in clients.items():
            memory[label] = sorted(client.run(_rss).values())
    print(f"load average {os.getloadavg()[0]:.2f} after the run")
    for label, sizes in memory.items():
        print(f"  {label:30s} workers' resident memory after the sweeps: "
              f"{', '.join(f'{size / 2**20:.0f}' for size in sizes)} MiB")
    print(f"{args.repeats} repeats, medians; per case = sweep wall time / {n_cases} cases on {pool_size} workers")
    def ratio(values, label):
        return statistics.median(v / p for v, p in zip(values[label], values["pool"], strict=True))

    for label in labels:
        print(f"  {label:30s} {1e3 * statistics.median(walls[label]):6.1f} ms per case ({ratio(walls, label):.2f}x "
              f"the pool's); run.wall_s {1e3 * statistics.median(case_walls[label]):6.1f} ms "
              f"({ratio(case_walls, label):.2f}x); run.cpu_s {1e3 * statistics.median(case_cpus[label]):6.1f} ms "
              f"({ratio(case_cpus, label):.2f}x)")
    if differs:
        print(f"TABLES DIFFER from the pool's first: {', '.join(differs)}")
        return 1
    print(f"every table identical to the pool's first (less {', '.join(sweep_engine.VOLATILE_COLUMNS)})")
    return 0


def _rss():
    """This process' resident memory [bytes]."""
    import psutil
    return psutil.Process().memory_info().rss


def _pool_rss():
    """The default pool's workers' resident memory [bytes], sorted."""
    import psutil

    from whipple_kick.studies import sweep_engine
    processes = (getattr(sweep_engine._pool, "_processes", None) or {}).values()
    return sorted(psutil.Process(p.pid).memory_info().rss for p in processes)


def _comparable(table):
    """The table less the columns that describe the run (time stamps, wall times, worker)."""
    from whipple_kick.studies import sweep_engine
    return table.drop(columns=list(sweep_engine.VOLATILE_COLUMNS)).reset_index(drop=True)


if __name__ == "__main__":
    sys.exit(main())
