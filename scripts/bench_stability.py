"""Speed of the stability analysis (medians; ratios against baselines in the same process or session).

Usage:
    python scripts/bench_stability.py linearisation   # one heading-frame linearisation, in RHS evaluations
    python scripts/bench_stability.py sweep           # the default 191-speed sweep (both loops), in process
    python scripts/bench_stability.py cli             # `stability --pressure 400 --fz 635`, fresh processes
    python scripts/bench_stability.py all

Bounds: one linearisation at most 50 right-hand-side
evaluations' worth of time; the default sweep of the command at most 5 s
warm. Absolute times depend on the load of the machine (other jobs share
its two cores): the ratios, measured interleaved in the same process, are
the stable numbers.
"""
import argparse
import pathlib
import shutil
import statistics
import sys
import time

from bench import time_against_baseline  # scripts/ is on sys.path when a script in it runs
import numpy as np


def _steady(symmetric, speed=4.0):
    import whipple_kick as wk
    from whipple_kick.model import slip
    from whipple_kick.simulate import simulation, steady
    sc = simulation.Scenario(symmetric_tyres=symmetric, speed=speed)
    moore, design, _ = wk.assembly.build_bicycle(sc.bicycle_spec)
    rear, front, _ = wk.assembly.build_tyres(sc.tyre_spec)
    gains, _ = wk.assembly.controller_gains(sc.gains_spec, design)
    params = slip.model_parameters(moore, rear, front, slip.ModelOptions(symmetric_tyres=symmetric), gains=gains)
    return steady.find_steady_state(params, speed).steady


def _per_call(fun, calls):
    t0 = time.perf_counter()
    for _ in range(calls):
        fun()
    return (time.perf_counter() - t0) / calls


def bench_linearisation(repeats):
    """One call of slip.heading_linearisation, slip.linearize and CompiledRHS, interleaved rounds."""
    from whipple_kick.model import slip
    for label, symmetric in (("symmetric T03, 4 m/s (upright)", True), ("measured T03, 4 m/s (steady turn)", False)):
        st = _steady(symmetric)
        rhs = slip.CompiledRHS(st.params)
        rounds = {"rhs": [], "fast": [], "old": []}
        for _ in range(repeats):
            rounds["rhs"].append(_per_call(lambda: rhs(0.0, st.x), 5000))
            rounds["fast"].append(_per_call(lambda: slip.heading_linearisation(rhs, st.x), 300))
            rounds["old"].append(_per_call(lambda: slip.linearize(rhs, st.x), 30))
        med = {k: statistics.median(v) for k, v in rounds.items()}
        ratios_fast = [f / r for f, r in zip(rounds["fast"], rounds["rhs"], strict=True)]
        ratios_old = [o / r for o, r in zip(rounds["old"], rounds["rhs"], strict=True)]
        print(f"{label}: RHS call {med['rhs'] * 1e6:.1f} us; heading_linearisation {med['fast'] * 1e6:.0f} us "
              f"= {statistics.median(ratios_fast):.1f} RHS evaluations (rounds {[round(v, 1) for v in ratios_fast]}); "
              f"slip.linearize {med['old'] * 1e6:.0f} us = {statistics.median(ratios_old):.0f} RHS evaluations "
              f"({repeats} interleaved rounds)")


def bench_sweep(repeats):
    """analyse() over 0.5:10:0.05 in one process (warm), against one RHS call and the old linearisation."""
    from whipple_kick.model import slip
    from whipple_kick.simulate.simulation import Scenario
    from whipple_kick.studies import stability
    speeds = stability.parse_speeds("0.5:10:0.05")
    scenario = Scenario(symmetric_tyres=True)
    stability.analyse(scenario, speeds)   # warm: caches, LQR designs, imports
    st = _steady(True)
    rhs = slip.CompiledRHS(st.params)
    fast, old, rhs_times = [], [], []
    original = slip.heading_linearisation

    def central_difference_route(rhs_, x, t=0.0):
        """The same (A, B) from slip.linearize (two of them for B, as slip.linear_state_space)."""
        params = {n: float(v) for n, v in zip(slip.PARAMETER_NAMES, rhs_.p, strict=True)}
        A, B, K = slip.linear_state_space(params, x)
        return A - B @ K, B

    for _ in range(repeats):
        rhs_times.append(_per_call(lambda: rhs(0.0, st.x), 5000))
        t0 = time.perf_counter()
        stability.analyse(scenario, speeds)
        fast.append(time.perf_counter() - t0)
        slip.heading_linearisation = central_difference_route
        try:
            t0 = time.perf_counter()
            stability.analyse(scenario, speeds)
            old.append(time.perf_counter() - t0)
        finally:
            slip.heading_linearisation = original
    med = statistics.median(fast)
    print(f"analyse, {speeds.size} speeds x 2 loops (+ no-slip model, refinements), warm process: median "
          f"{med:.2f} s (runs {[round(v, 2) for v in fast]}) = {med / statistics.median(rhs_times):.0f} RHS "
          f"evaluations; with slip.linearize instead: median {statistics.median(old):.2f} s "
          f"(ratio {statistics.median([f / o for f, o in zip(fast, old, strict=True)]):.2f}, {repeats} interleaved rounds)")


def _command(name):
    script = shutil.which(name, path=str(pathlib.Path(sys.executable).parent))
    if script:
        return [script]
    return [sys.executable, "-c", f"from whipple_kick.cli import {name}_main; {name}_main()"]


def bench_cli(repeats):
    """The whole `stability` command in fresh processes (warm cache), beside a bare import of its libraries."""
    command = _command("stability") + ["--pressure", "400", "--fz", "635", "--quiet"]
    # The command no longer imports pyplot (a bare Figure with the Agg canvas), so neither does the baseline.
    baseline = [sys.executable, "-c", "import numpy, scipy.optimize, pandas, matplotlib"]
    times, base = time_against_baseline(command, baseline, repeats)
    print(f"stability --pressure 400 --fz 635 --quiet (191 speeds, warm cache, fresh process): median "
          f"{statistics.median(times):.2f} s runs {[round(v, 2) for v in times]}; importing numpy, scipy, pandas "
          f"and matplotlib alone: median {statistics.median(base):.2f} s (ratio "
          f"{statistics.median(times) / statistics.median(base):.1f})")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("linearisation", "sweep", "cli", "all"))
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    np.set_printoptions(precision=4)
    for name, fun in (("linearisation", bench_linearisation), ("sweep", bench_sweep), ("cli", bench_cli)):
        if args.what in (name, "all"):
            fun(args.repeats)


if __name__ == "__main__":
    main()
