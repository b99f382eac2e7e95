"""Speed benchmarks of the slip model (medians; ratios against a baseline in the same process).

Usage:
    python scripts/bench.py rhs        # one RHS evaluation: compiled C vs NumPy (lambdify-style) oracle
    python scripts/bench.py build      # cold build (derive + generate + compile) and warm start, fresh processes
    python scripts/bench.py run        # the 6 s kick-plate base case at rtol 1e-12 and 1e-8, C vs NumPy RHS
    python scripts/bench.py cli        # end to end: `simulate --pressure 400 --fz 635 --out NEW --quiet`, warm cache
    python scripts/bench.py all
"""
import argparse
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np


def _base_case(rtol=1e-10):
    import whipple_kick as wk
    from whipple_kick import slip
    bike = wk.bicycles.load("balanceassist_v1")
    combined, _ = wk.riders.for_rear_load(bike, fz_n=635.0)
    K, _ = wk.control.lqr_gains(combined, 3.0)
    tyre = wk.tyres.load("T03", pressure_kpa=400)
    par = slip.model_parameters(combined, tyre, tyre, gains=wk.control.gains_dict(K),
                                kick=dict(t0=0.0, duration=0.15, displacement=0.15))
    return slip.steady_state(par, 3.0)


def bench_rhs(repeats):
    from whipple_kick import slip
    ss = _base_case()
    rhs = slip.CompiledRHS(ss.params)
    p = slip.parameter_vector(ss.params)
    x = ss.x.copy()
    x[slip.X["u4"]] = 0.1
    n_c, n_np = 20000, 200
    c_times, np_times = [], []
    slip.numpy_rhs(0.05, x, p)  # import and warm up
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n_c):
            rhs(0.05, x)
        c_times.append((time.perf_counter() - t0) / n_c)
        t0 = time.perf_counter()
        for _ in range(n_np):
            slip.numpy_rhs(0.05, x, p)
        np_times.append((time.perf_counter() - t0) / n_np)
    c, n = statistics.median(c_times), statistics.median(np_times)
    print(f"RHS call, compiled C (incl. ctypes + copy): median {c * 1e6:.2f} us  ({repeats} runs x {n_c} calls)")
    print(f"RHS call, NumPy oracle (same expressions):  median {n * 1e6:.1f} us  ({repeats} runs x {n_np} calls)")
    print(f"speed-up C / NumPy: {n / c:.0f}x")


def _fresh(cache, code):
    env = dict(os.environ, WHIPPLE_KICK_CACHE=cache)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
    return time.perf_counter() - t0


def bench_build(repeats):
    code = "from whipple_kick import slip; slip.library()"
    cold, warm = [], []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as tmp:
            cache = os.path.join(tmp, "cache")
            cold.append(_fresh(cache, code))
            warm.append(_fresh(cache, code))
    base = statistics.median(_fresh(tempfile.gettempdir(), "import numpy, scipy.integrate, sympy") for _ in range(repeats))
    print(f"cold build (derive + generate C + compile): median {statistics.median(cold):.2f} s  runs {[round(v, 2) for v in cold]}")
    print(f"warm start (load cached library):           median {statistics.median(warm):.2f} s  runs {[round(v, 2) for v in warm]}")
    print(f"baseline (python + numpy + scipy + sympy import): median {base:.2f} s")


def bench_run(repeats):
    from whipple_kick import integrate, slip
    ss = _base_case()
    p = slip.parameter_vector(ss.params)
    for rtol in (1e-12, 1e-8):
        times = []
        for _ in range(repeats):
            rhs = slip.CompiledRHS(ss.params)
            t0 = time.perf_counter()
            traj = integrate.integrate(rhs, ss.x, 6.0, t_start=0.0, breakpoints=(0.15,), rtol=rtol)
            times.append(time.perf_counter() - t0)
        print(f"6 s base case, C RHS, rtol {rtol:g}: median {statistics.median(times):.3f} s  "
              f"({traj.nfev} RHS calls)  runs {[round(v, 3) for v in times]}")
        c_med = statistics.median(times)
        t0 = time.perf_counter()
        integrate.integrate(lambda t, x: slip.numpy_rhs(t, x, p), ss.x, 6.0, t_start=0.0,
                            breakpoints=(0.15,), rtol=rtol)
        n = time.perf_counter() - t0
        print(f"6 s base case, NumPy RHS, rtol {rtol:g}: {n:.2f} s (one run); C is {n / c_med:.0f}x faster")


def _simulate_command():
    """The ``simulate`` console script of this interpreter's environment (or an equivalent -c call)."""
    script = shutil.which("simulate", path=str(pathlib.Path(sys.executable).parent))
    if script:
        return [script]
    return [sys.executable, "-c", "from whipple_kick.cli import simulate_main; simulate_main()"]


def bench_cli(repeats):
    """Wall time of the whole command, each run in a fresh process writing into a new folder.

    Uses the normal per-user cache (or $WHIPPLE_KICK_CACHE); one untimed run
    first makes sure it is warm, so this measures what a user sees on every
    run after the first.
    """
    command = _simulate_command() + ["--pressure", "400", "--fz", "635", "--quiet"]
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(repeats + 1):
            out = os.path.join(tmp, f"run{k}")
            t0 = time.perf_counter()
            subprocess.run(command + ["--out", out], check=True)
            if k:   # the first run only warms the cache
                times.append(time.perf_counter() - t0)
    print(f"simulate --pressure 400 --fz 635 --quiet (warm cache, fresh process): "
          f"median {statistics.median(times):.2f} s  runs {[round(v, 2) for v in times]}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", choices=("rhs", "build", "run", "cli", "all"))
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    np.set_printoptions(precision=4)
    for name, fn in (("rhs", bench_rhs), ("build", bench_build), ("run", bench_run), ("cli", bench_cli)):
        if args.what in (name, "all"):
            fn(args.repeats)


if __name__ == "__main__":
    main()
