"""Wall time of ``validate``'s model runs: the nine measured cases x two kick directions.

Usage:
    python scripts/bench_validate.py [--repeats 3] [--workers 2]

Times :func:`whipple_kick.studies.validation.validate` (the sweep with its process
pool started afresh, the trajectories loaded, the yaw rates processed as the
recordings were), then :func:`whipple_kick.studies.validation.write` (CSV files and
the figure) and the whole ``validate`` command in a fresh process (imports
included). "Warm": the compiled model is already in the on-disk cache (one
throw-away case builds it first). The issue's acceptance: at most 2 minutes
on 2 cores.
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    from whipple_kick.studies import sweep_engine, validation
    validation.validate(validation.base_scenario(duration=0.3), directions=("right",), workers=1)   # warm
    runs, writes = [], []
    for _ in range(args.repeats):
        sweep_engine._discard_default_pool(end_workers=True)   # every repeat starts its own pool, as a user's call
        t0 = time.perf_counter()
        result = validation.validate(workers=args.workers)
        runs.append(time.perf_counter() - t0)
        with tempfile.TemporaryDirectory() as out:
            t0 = time.perf_counter()
            validation.write(result, out)
            writes.append(time.perf_counter() - t0)
    exe = os.path.join(os.path.dirname(sys.executable), "validate")
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        subprocess.run([exe, "--out", os.path.join(out, "v"), "--workers", str(args.workers), "--quiet"], check=True)
        command = time.perf_counter() - t0
    print(f"validate: {len(result.runs)} runs (9 cases x 2 directions, 6 s after the kick), "
          f"{args.workers} workers, {os.cpu_count()} CPUs")
    print(f"  runs + processing: median {statistics.median(runs):.2f} s (min {min(runs):.2f}, max {max(runs):.2f}, "
          f"{args.repeats} repeats)")
    print(f"  writing the files: median {statistics.median(writes):.2f} s")
    print(f"  the whole command in a fresh process: {command:.2f} s")


if __name__ == "__main__":
    main()
