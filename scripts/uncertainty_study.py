"""The uncertainty study of thesis Chapter 8, and what a run of it costs.

Runs :func:`whipple_kick.studies.uncertainty.run_study` on the shipped
``kickplate_2025`` uncertainty file: 3 pressures (300/400/500 kPa) x 3 rear
loads (570/635/701 N) x the N (D + 2) rows of SALib's Saltelli-Sobol' design
(N base samples, D inputs), every row run at every pressure and load. It
prints the study (P(best) with intervals beside Table 8.9's measured best,
pooled and by option; rates; the Sobol indices of which pressure recovers
first; the verdict, with the measured ranking checked against its own error)
and the cost. Run again with the same ``--out`` it resumes the runs and
analyses them anew (the tables and verdict are the present analysis'). The cost:

* the study's wall time and its runs;
* per run: the wall time in its worker (``run.wall_s``) against the
  integration's (``numerics.integration_wall_s``), means and medians;
* the cost per run on this machine (wall time x workers / runs) and the
  extrapolated wall time of the N = 500 study.

Usage::

    python scripts/uncertainty_study.py --samples 8 --seed 0 [--workers 2] [--out DIR]
    python scripts/uncertainty_study.py --samples 8 --seed 0 --out DIR --analyse   # again, running nothing

(docs/uncertainty.md quotes a run of this; the full N = 500 study is
``recommend-pressure --fz 570 635 701 --uncertain --samples 500 --seed 0 --out DIR``.)
"""
import argparse
import json
import os
import sys
import tempfile
import time

import numpy as np

from whipple_kick import fileio
from whipple_kick.library import uncertain
from whipple_kick.studies import uncertainty


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, default=8, help="SALib base samples N (default 8)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    p.add_argument("--file", default=uncertain.DEFAULT, help="uncertainty file (default the shipped one)")
    p.add_argument("--out", help="folder for the runs and tables (default: a temporary one)")
    p.add_argument("--extrapolate", type=int, default=500, help="N to extrapolate the cost to (default 500)")
    p.add_argument("--analyse", action="store_true",
                   help="analyse the study already run in --out again with this code's statistics, running "
                        "nothing (its runs stay the code's that made them: see its runs/manifest.json)")
    p.add_argument("--loads", type=float, nargs="+", default=list(uncertainty.LOADS),
                   help="rear loads in N (default the thesis' three; with --analyse, the loads the study completed)")
    args = p.parse_args(argv)
    spec = uncertain.load(args.file)
    if args.analyse:
        if not args.out:
            p.error("--analyse needs --out, the folder of the study to analyse")
        study = uncertainty.analyse_folder(os.path.join(args.out, "runs"), spec, samples=args.samples,
                                           seed=args.seed, loads=args.loads)
        study.write(args.out)
        print(uncertainty.format_study(study))
        return
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or tmp
        # Resumed: the folder held finished runs before this session (a wall-time rule misread a quick study).
        resumed = os.path.exists(os.path.join(out, "runs", "cases.jsonl"))
        t0 = time.perf_counter()
        study = uncertainty.run_study(spec, samples=args.samples, seed=args.seed, workers=args.workers,
                                      folder=os.path.join(out, "runs"), progress=sys.stderr.isatty(),
                                      loads=args.loads)
        wall = time.perf_counter() - t0
        study.write(out)
    print(uncertainty.format_study(study))
    record = cost(study.outcomes, wall, args.workers, len(spec.inputs), args.extrapolate,
                  resumed=resumed)
    print_cost(record)
    if args.out:
        fileio.write_atomic(os.path.join(args.out, "cost.json"), json.dumps(record, indent=1) + "\n")


def cost(outcomes, wall, workers, n_inputs, extrapolate=500, resumed=False):
    """The study's cost from its outcomes table (``Study.outcomes`` or ``outcomes.csv``): a dict.

    ``wall`` is the study's wall time [s] on ``workers`` workers (a resumed study's is not the whole study's:
    ``resumed`` says so); per run, the wall and CPU time in its worker and its integration's wall time.
    """
    n = len(outcomes)
    runs = outcomes.drop_duplicates("case_id")   # a repeated design row is one case, run once
    distinct = len(runs)
    case_wall = runs["run.wall_s"].to_numpy(dtype=float)
    case_cpu = runs["run.cpu_s"].to_numpy(dtype=float)
    integ = runs["numerics.integration_wall_s"].to_numpy(dtype=float)
    ok = np.isfinite(case_wall) & np.isfinite(integ) & np.isfinite(case_cpu)
    rows = extrapolate * (n_inputs + 2)
    total = rows * len(uncertainty.PRESSURES) * len(uncertainty.LOADS)
    share = distinct / n
    return {"runs": n, "rows": n // (len(uncertainty.PRESSURES) * outcomes["fz_n"].nunique()), "distinct": distinct, "wall_s": wall, "workers": workers, "resumed": resumed,
            "run_wall_mean_s": float(case_wall[ok].mean()), "run_wall_median_s": float(np.median(case_wall[ok])),
            "run_cpu_mean_s": float(case_cpu[ok].mean()), "integration_wall_mean_s": float(integ[ok].mean()),
            "integration_wall_median_s": float(np.median(integ[ok])),
            "integration_share": float(integ[ok].sum() / case_wall[ok].sum()),
            "per_case_s": wall * workers / distinct, "extrapolate": extrapolate, "extrapolate_rows": rows,
            "extrapolate_runs": total, "extrapolate_distinct": total * share,
            "extrapolate_idle_h": total * share * float(case_cpu[ok].mean()) / workers / 3600,
            "extrapolate_contended_h": total * share * wall * workers / distinct / workers / 3600}


def print_cost(c):
    """Print :func:`cost`'s record."""
    print(f"\ncost: {c['runs']} runs ({c['rows']} rows x {len(uncertainty.PRESSURES)} pressures x "
          f"{len(uncertainty.LOADS)} loads; {c['distinct']} distinct cases, each run once) in {c['wall_s']:.1f} s wall on "
          f"{c['workers']} workers" + (" (resumed from --out: the wall time is not the study's)" if c["resumed"] else ""))
    print(f"  per run in its worker: wall mean {c['run_wall_mean_s']:.3f} s, median {c['run_wall_median_s']:.3f} s; "
          f"CPU mean {c['run_cpu_mean_s']:.3f} s; its integration: wall mean {c['integration_wall_mean_s']:.3f} s, "
          f"median {c['integration_wall_median_s']:.3f} s ({100 * c['integration_share']:.0f} % of the run's wall)")
    print(f"  cost per distinct case on this machine (study wall x workers / cases): {c['per_case_s']:.3f} s")
    print(f"  N = {c['extrapolate']}: {c['extrapolate_rows']} rows, {c['extrapolate_runs']} runs (about "
          f"{c['extrapolate_distinct']:.0f} distinct at this share): about {c['extrapolate_contended_h']:.1f} h wall "
          f"on {c['workers']} workers at this cost; {c['extrapolate_idle_h']:.1f} h at the measured CPU per run on "
          f"{c['workers']} otherwise idle cores")

if __name__ == "__main__":
    main()
