"""Sweep benchmarks: parallel speed-up on the nine thesis cases, and cases/s/core on a large sweep.

Usage:
    python scripts/bench_sweep.py nine            # 9 thesis cases, 1 vs 2 workers (median of --repeats)
    python scripts/bench_sweep.py many --n 1000   # an n-case sweep into a temporary folder
    python scripts/bench_sweep.py all

"Warm" means the compiled model is already in the on-disk cache and this
process has imported the package (one throw-away case runs first); the
default process pool is kept between the sweeps of a process (as in a user's
session), so the first sweep of each worker count includes its start-up (fork).
The per-case split comes from the table: ``run.wall_s`` (the case in its
worker) against ``numerics.integration_wall_s``; the parallel efficiency is
set against two pure-Python processes measured in the same run. The nine cases are the thesis grid
300/400/500 kPa x 570/635/701 N with the default scenario (LQR rider, 6 s
after the kick, rtol 1e-10, 1000 Hz output).
"""
import argparse
import os
import statistics
import sys
import tempfile
import time


def _thesis_grid():
    return {"pressure_kpa": [300.0, 400.0, 500.0], "fz_n": [570.0, 635.0, 701.0]}


def _burn(n):
    """Pure-Python CPU work; returns its wall time [s]."""
    t0 = time.perf_counter()
    total = 0
    for i in range(n):
        total += i * i
    return time.perf_counter() - t0


def parallel_ceiling(workers=2, n=10_000_000):
    """Speed-up ``workers`` independent CPU-bound processes get over one on this machine now.

    On shared or virtual cores this is often well below ``workers``; no sweep can beat it.
    """
    from concurrent.futures import ProcessPoolExecutor
    one = _burn(n)
    with ProcessPoolExecutor(workers) as pool:
        many = max(pool.map(_burn, [n] * workers))
    return workers * one / many


def _warm_up():
    from whipple_kick.simulate import simulation
    simulation.run(simulation.Scenario(duration=0.3))


def case_split(table):
    """Per-case medians [s] of a sweep table: the worker's wall time, the integration's, and the rest."""
    wall = table["run.wall_s"]
    integration = table["numerics.integration_wall_s"]
    return {"wall": wall.median(), "integration": integration.median(), "rest": (wall - integration).median(),
            "cpu": table["run.cpu_s"].median()}


def bench_nine(repeats, duration):
    import pandas as pd

    import whipple_kick as wk
    from whipple_kick.simulate import simulation
    base = simulation.Scenario(duration=duration)
    times = {}
    for workers in (1, 2):
        runs, tables = [], []
        for _ in range(repeats):
            t0 = time.perf_counter()
            table = wk.sweep(_thesis_grid(), base=base, workers=workers, progress=False)
            runs.append(time.perf_counter() - t0)
            assert (table["status"] == "ok").all(), table["error"].dropna().tolist()
            tables.append(table)
        times[workers] = runs
        split = case_split(pd.concat(tables))
        print(f"9 thesis cases, {workers} worker(s): wall median {statistics.median(runs):.2f} s "
              f"(runs: {', '.join(f'{t:.2f}' for t in runs)}); per case (median of {9 * repeats}): "
              f"run.wall_s {split['wall']:.4f} s = integration {split['integration']:.4f} s "
              f"+ the rest {split['rest']:.4f} s (CPU {split['cpu']:.4f} s); "
              f"run.wall_s / integration {split['wall'] / split['integration']:.2f} (target <= 1.3 with 1 worker)")
    speedup = statistics.median(times[1]) / statistics.median(times[2])
    best = min(times[1]) / min(times[2])
    ceiling = parallel_ceiling(2)
    print(f"speed-up 2 workers over 1: {speedup:.2f}x (medians), {best:.2f}x (best runs); "
          f"target >= 1.7x (nine equal cases on two workers cannot beat 9/5 = 1.8x)")
    print(f"this machine's ceiling right now (two pure-Python processes vs one): {ceiling:.2f}x; "
          f"parallel efficiency {speedup / 2:.2f} (sweep) against {ceiling / 2:.2f} (pure Python)")
    return speedup


def bench_many(n, duration, workers, folder):
    import numpy as np

    import whipple_kick as wk
    from whipple_kick.simulate import simulation
    # A pressure x load grid of about n cases (interpolated tyres between the measured pressures).
    n_p = max(1, int(round(np.sqrt(n / 1.6))))
    n_f = max(1, int(round(n / n_p)))
    grid = {"pressure_kpa": list(np.round(np.linspace(300.0, 500.0, n_p), 6)),
            "fz_n": list(np.round(np.linspace(550.0, 720.0, n_f), 6))}
    base = simulation.Scenario(duration=duration)
    workers = workers or os.cpu_count()
    with tempfile.TemporaryDirectory() as tmp:
        target = folder or os.path.join(tmp, "sweep")
        t0 = time.perf_counter()
        table = wk.sweep(grid, base=base, workers=workers, folder=target, progress=sys.stderr.isatty())
        wall = time.perf_counter() - t0
        size = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(target) for f in fs)
    n_cases = len(table)
    rate = n_cases / wall
    ok = int((table["status"] == "ok").sum())
    print(f"{n_cases} cases ({n_p} pressures x {n_f} loads, {duration:g} s each), {workers} workers: "
          f"{wall:.1f} s wall, {rate:.2f} cases/s, {rate / workers:.2f} cases/s/core; "
          f"{ok} ok, {n_cases - ok} failed, {int(table['fell'].fillna(False).astype(bool).sum())} fell; "
          f"per case median {table['run.wall_s'].median():.3f} s in the worker; "
          f"folder {size / 1e6:.0f} MB")
    split = case_split(table)
    print(f"per case (medians): integration {split['integration']:.4f} s + the rest {split['rest']:.4f} s; "
          f"{workers} pure-Python processes get {parallel_ceiling(workers):.2f}x one here now")
    return rate / workers


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("what", choices=("nine", "many", "all"))
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--n", type=int, default=1000, help="cases of the large sweep")
    p.add_argument("--duration", type=float, default=6.0, help="simulated time after the kick [s]")
    p.add_argument("--workers", type=int, default=None, help="workers of the large sweep (default: cores)")
    p.add_argument("--folder", default=None, help="keep the large sweep's folder here")
    args = p.parse_args(argv)
    print(f"{os.cpu_count()} cores; load average {os.getloadavg()[0]:.2f} before the run")
    _warm_up()
    if args.what in ("nine", "all"):
        bench_nine(args.repeats, args.duration)
    if args.what in ("many", "all"):
        bench_many(args.n, args.duration, args.workers, args.folder)
    return 0


if __name__ == "__main__":
    sys.exit(main())
