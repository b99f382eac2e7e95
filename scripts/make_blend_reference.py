"""Store the blended-pressure right-hand side at every sample of a 350 kPa run (a test's reference).

Usage:
    python scripts/make_blend_reference.py [--out tests/data/blend/rhs_350kPa_635N.npz]

The 350 kPa tyre blends T03's 300 and 400 kPa fits (outputs weighted 1:1).
The file holds, at the 500 Hz samples of a 0.8 s run through the kick and
the plate stop (default scenario: carcass tyre, LQR rider), the sample times
``t``, the states ``x``, the parameter vector ``p``, and the compiled model's
derivatives ``dx`` and named outputs ``out`` there, with the layouts' names. It was written with the
compiled model before the blend's patch-slip solve stopped bisecting away
from exact roots (tests/model/test_carcass.py compares the current model
with it: the change must stay at round-off). Written by this script run on
the package before that change (commit 4911fbd); a later change of the state
or parameter layout retires the file and its test.
"""
import argparse
import pathlib
import sys

import numpy as np


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", default=str(pathlib.Path(__file__).resolve().parents[1]
                                        / "tests" / "data" / "blend" / "rhs_350kPa_635N.npz"))
    args = p.parse_args(argv)
    from whipple_kick.library import inputs
    from whipple_kick.model import slip
    from whipple_kick.simulate import assembly, integration
    from whipple_kick.simulate.scenario import Scenario
    scenario = Scenario(pressure_kpa=350.0, fz_n=635.0, duration=0.7, settle=0.1, output_rate=500.0)
    kick = inputs.kick_of(scenario.validate())
    solution = integration.integrate_run(assembly.assemble(scenario, kick), scenario, kick)
    if solution.owner is not None:
        raise SystemExit("expected one compiled model for the whole run")
    rhs, traj = solution.rhs, solution.states
    pairs = [rhs.outputs(t, x) for t, x in zip(traj.t, traj.x, strict=True)]
    np.savez_compressed(args.out, t=traj.t, x=traj.x, p=rhs.p, dx=np.array([d for d, _ in pairs]),
                        out=np.array([o for _, o in pairs]), output_names=np.array(slip.OUTPUT_NAMES),
                        state_names=np.array(slip.STATE_NAMES), parameter_names=np.array(slip.PARAMETER_NAMES))
    print(f"wrote {args.out}: {traj.t.size} samples")
    return 0


if __name__ == "__main__":
    sys.exit(main())
