"""The uncertainty study of thesis Chapter 8, and what a run of it costs.

Runs :func:`whipple_kick.studies.uncertainty.run_study` on the shipped
``kickplate_2025`` uncertainty file: 3 pressures (300/400/500 kPa) x 3 rear
loads (570/635/701 N) x the N (D + 2) rows of SALib's Saltelli-Sobol' design
(N base samples, D inputs), every row run at every pressure and load. It
prints the study (P(best) with intervals beside Table 8.9's measured best,
rates, verdict) and the cost:

* the study's wall time and its runs;
* per run: the wall time in its worker (``run.wall_s``) against the
  integration's (``numerics.integration_wall_s``), means and medians;
* the cost per run on this machine (wall time x workers / runs) and the
  extrapolated wall time of the N = 500 study.

Usage::

    python scripts/uncertainty_study.py --samples 8 --seed 0 [--workers 2] [--out DIR]

(docs/uncertainty.md quotes a run of this; the full N = 500 study is
``recommend-pressure --fz 570 635 701 --uncertain --samples 500 --seed 0 --out DIR``.)
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np

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
    args = p.parse_args(argv)
    spec = uncertain.load(args.file)
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or tmp
        t0 = time.perf_counter()
        study = uncertainty.run_study(spec, samples=args.samples, seed=args.seed, workers=args.workers,
                                      folder=os.path.join(out, "runs"), progress=sys.stderr.isatty())
        wall = time.perf_counter() - t0
        study.write(out)
    print(uncertainty.format_study(study))
    n = len(study.outcomes)
    runs = study.outcomes.drop_duplicates("case_id")   # a repeated design row is one case, run once
    distinct = len(runs)
    case_wall = runs["run.wall_s"].to_numpy(dtype=float)
    case_cpu = runs["run.cpu_s"].to_numpy(dtype=float)
    integ = runs["numerics.integration_wall_s"].to_numpy(dtype=float)
    ok = np.isfinite(case_wall) & np.isfinite(integ) & np.isfinite(case_cpu)
    per_run = wall * args.workers / distinct
    rows = args.extrapolate * (len(spec.inputs) + 2)
    total = rows * len(uncertainty.PRESSURES) * len(uncertainty.LOADS)
    print(f"\ncost: {n} runs ({len(study.inputs)} rows x {len(uncertainty.PRESSURES)} pressures x "
          f"{len(uncertainty.LOADS)} loads; {distinct} distinct cases, each run once) in {wall:.1f} s wall on "
          f"{args.workers} workers"
          + (" (resumed from --out: the wall time is not the study's)" if args.out and wall < 0.05 * n else ""))
    print(f"  per run in its worker: wall mean {case_wall[ok].mean():.3f} s, median {np.median(case_wall[ok]):.3f} s; "
          f"CPU mean {case_cpu[ok].mean():.3f} s; its integration: wall mean {integ[ok].mean():.3f} s, median "
          f"{np.median(integ[ok]):.3f} s ({100 * integ[ok].sum() / case_wall[ok].sum():.0f} % of the run's wall)")
    print(f"  cost per distinct case on this machine (study wall x workers / cases): {per_run:.3f} s")
    share = distinct / n
    print(f"  N = {args.extrapolate}: {rows} rows, {total} runs (about {total * share:.0f} distinct at this share): "
          f"about {total * share * per_run / args.workers / 3600:.1f} h wall on {args.workers} workers at this cost; "
          f"{total * share * case_cpu[ok].mean() / args.workers / 3600:.1f} h at the measured CPU per run on "
          f"{args.workers} otherwise idle cores")


if __name__ == "__main__":
    main()
