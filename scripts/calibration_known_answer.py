"""Known-answer check of the calibration (issue 39): synthetic measurements at known inputs are recovered.

    python scripts/calibration_known_answer.py toy   [--cases 10]
    python scripts/calibration_known_answer.py model [--cases 10] [--first 24] [--per-wave 12] [--workers 2]

Each case draws a true input (uniform within the middle 70 % of every prior:
an input on the prior's edge leaves a central interval no room on one side),
runs the simulator there, adds Gaussian noise of the stated measurement
standard deviation (the calibration file's, per feature and cell), and
calibrates on the result: history matching in two waves, then the emcee
posterior. A case counts as recovered when every input's 90 % central credible
interval covers its true value. Acceptance (issue 39): at least 8 of 10.

``toy`` uses :class:`whipple_kick.studies.calibration.ToySimulator` (every
measured cell, three inputs; about 20 s a case); ``model`` the kick model
itself (:class:`~whipple_kick.studies.calibration.ModelSimulator`) at three
cells (570 N 300 kPa, 635 N 400 kPa, 701 N 500 kPa), the rigid rider kicked to
the right, on gain scale, carcass stiffness scale and carcass damping:
``--first`` + ``--per-wave`` runs of three cells per case.
"""
import argparse
import time

import numpy as np

from whipple_kick.library import priors
from whipple_kick.studies import calibration as cal

INPUTS = ["gain_scale", "carcass_stiffness_scale", "carcass_damping"]
TOY_INPUTS = ["gain_scale", "carcass_stiffness_scale", "kick_accel"]
CELLS = [(570.0, 300.0), (635.0, 400.0), (701.0, 500.0)]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("mode", choices=("toy", "model"))
    p.add_argument("--cases", type=int, default=10)
    p.add_argument("--first", type=int, default=None, help="runs of wave 1 (default 10 per input)")
    p.add_argument("--per-wave", type=int, default=None, help="runs of wave 2 (default 5 per input)")
    p.add_argument("--steps", type=int, default=2000)
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    spec = priors.load()
    if args.mode == "toy":
        pl = cal.choose_priors(spec, TOY_INPUTS)
        factory, options = cal.ToySimulator, {}
    else:
        pl = cal.choose_priors(spec, INPUTS)

        def factory(prior_list, cells, features):
            return cal.ModelSimulator([q.field for q in prior_list], cells, features, workers=args.workers)
        options = {"cells": CELLS}
    rng = np.random.default_rng(args.seed)
    recovered, rows = 0, []
    started = time.perf_counter()
    for k in range(args.cases):
        truth = rng.uniform(0.15, 0.85, len(pl))
        t0 = time.perf_counter()
        result, x, covered = cal.known_answer(factory, pl, truth, seed=args.seed + k, first=args.first,
                                              per_wave=args.per_wave, steps=args.steps, **options)
        ok = bool(covered) and all(covered.values())
        recovered += ok
        held = result.checks.query("check == 'emulator_held_out'")["value"].to_list()
        rhat = result.checks.query("check == 'mcmc_rhat'")["value"].max() if covered else float("nan")
        line = [f"case {k}: {'recovered' if ok else 'MISSED'} ({time.perf_counter() - t0:.0f} s); held-out within "
                f"+-3: {', '.join(f'{h:.2f}' for h in held)}; max split R-hat {rhat:.3f}"]
        for q, value in zip(pl, x, strict=True):
            if covered:
                lo, hi = result.interval(q.name)
                line.append(f"    {q.name}: true {value:.4g}, 90 % {lo:.4g}-{hi:.4g} {q.unit} "
                            f"({'in' if covered[q.name] else 'OUT'}; prior {q.low:g}-{q.high:g})")
            else:
                line.append(f"    {q.name}: true {value:.4g}: {result.verdict[-1]}")
        print("\n".join(line), flush=True)
        rows.append(ok)
    print(f"{args.mode}: {recovered} of {args.cases} cases recovered (90 % intervals cover every true input); "
          f"acceptance: at least 8 of 10; {time.perf_counter() - started:.0f} s")
    return 0 if recovered >= 0.8 * args.cases else 1


if __name__ == "__main__":
    raise SystemExit(main())
