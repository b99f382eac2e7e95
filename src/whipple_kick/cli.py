"""Command-line entry points.

User mistakes (:class:`whipple_kick.errors.InputError`) print one line on
stderr and exit with status 2, without a traceback.
"""
import argparse
import sys

import numpy as np

from .errors import InputError


def _run(main, argv):
    try:
        return main(argv)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


def _benchmark(argv):
    parser = argparse.ArgumentParser(
        prog="whipple-benchmark",
        description="Linearise the classic Carvallo-Whipple model of the Meijaard et al. (2007) "
                    "benchmark bicycle and print its eigenvalues [1/s] against forward speed [m/s].")
    parser.add_argument("--speeds", type=float, nargs="+", default=list(range(11)),
                        metavar="M/S", help="forward speeds in m/s (default 0..10)")
    args = parser.parse_args(argv)
    from . import benchmark, classic
    moore = benchmark.to_moore(benchmark.meijaard2007_parameters())
    speeds = [float(v) for v in args.speeds]
    eigs = classic.eigenvalues(moore, speeds)
    print("Benchmark bicycle (Meijaard et al. 2007), classic no-slip model, eigenvalues [1/s]")
    print(f"{'v [m/s]':>8}  " + "  ".join(f"{'eigenvalue ' + str(i + 1):>26}" for i in range(4)))
    for v, row in zip(speeds, eigs):
        cells = [f"{e.real:+.10f}{e.imag:+.10f}j" for e in row]
        print(f"{v:8.3f}  " + "  ".join(f"{c:>26}" for c in cells))
    print(f"weave speed   {classic.weave_speed(moore):.10f} m/s (published {benchmark.WEAVE_SPEED:.10f})")
    print(f"capsize speed {classic.capsize_speed(moore):.10f} m/s (published {benchmark.CAPSIZE_SPEED:.10f})")
    return 0


def benchmark_main(argv=None):
    """Console script ``whipple-benchmark``."""
    np.set_printoptions(precision=10)
    sys.exit(_run(_benchmark, argv))
