"""Time the classic model's derivation, code generation and cached start.

Usage: python scripts/bench_derivation.py [--repeats N]

Cold = derive + generate NumPy code into an empty cache, in a fresh process.
Warm = a fresh process that imports the cached module and linearises once.
Reports the median of N runs of each.
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

WARM = ("import whipple_kick as wk; m = wk.benchmark.to_moore(wk.benchmark.meijaard2007_parameters()); "
        "wk.classic.linear_state_space(m, 5.0)")


def run(cache, code):
    env = dict(os.environ, WHIPPLE_KICK_CACHE=cache)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
    return time.perf_counter() - t0


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    cold, warm = [], []
    for _ in range(args.repeats):
        with tempfile.TemporaryDirectory() as tmp:
            cache = os.path.join(tmp, "cache")
            cold.append(run(cache, WARM))
            warm.append(run(cache, WARM))
    baseline = statistics.median(run(tempfile.gettempdir(), "import numpy, scipy.integrate") for _ in range(args.repeats))
    print(f"cold derive+generate+linearise: median {statistics.median(cold):.2f} s  runs {[round(x, 2) for x in cold]}")
    print(f"warm start (cached) + linearise: median {statistics.median(warm):.2f} s  runs {[round(x, 2) for x in warm]}")
    print(f"baseline python+numpy+scipy import: median {baseline:.2f} s; warm/baseline = {statistics.median(warm) / baseline:.1f}x")


if __name__ == "__main__":
    main()
