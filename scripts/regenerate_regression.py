"""Regenerate the stored regression trajectories (deliberately, with a reason).

Usage:
    python scripts/regenerate_regression.py --reason "why the reference runs changed"

Writes ``tests/data/regression/<name>.npz`` for the cases in :data:`CASES`
and appends a line (date, model hash, reason) to
``tests/data/regression/CHANGELOG.md``. ``tests/test_regression.py`` reruns
each stored scenario and compares.

Each file holds float32 arrays at 200 Hz of the columns in :data:`COLUMNS`
(time from the kick start, SI units), plus ``scenario_json`` (every Scenario
field, so the test needs nothing else to rerun the case), ``model_hash`` and
``generated`` (UTC time stamp). float32 keeps ~7 significant digits: its
rounding (~6e-8 of a signal's peak) is far below the test's tolerance.
"""
import argparse
import dataclasses
import datetime
import json
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = ROOT / "tests" / "data" / "regression"
CHANGELOG = OUT / "CHANGELOG.md"
#: Stored columns (analysis.COLUMNS names): yaw, roll and steer rates, roll, steer, rear F_y.
COLUMNS = ("time", "yaw_rate", "roll_rate", "steer_rate", "roll", "steer", "fy_rear")
RATE_HZ = 200.0


def cases():
    """{name: Scenario}: the nine thesis cases, the controller-off case and a 40 m/s^2 kick."""
    from whipple_kick.simulation import Scenario
    base = Scenario(output_rate=RATE_HZ)    # defaults: LQR rider, T03, 3 m/s, 150 mm in 0.150 s, 6 s
    out = {}
    for fz in (570, 635, 701):
        for p in (300, 400, 500):
            out[f"lqr_{p}kPa_{fz}N"] = dataclasses.replace(base, pressure_kpa=float(p), fz_n=float(fz))
    out["off_400kPa_635N"] = dataclasses.replace(base, pressure_kpa=400.0, fz_n=635.0, controller="off")
    out["kick40_400kPa_635N"] = dataclasses.replace(base, pressure_kpa=400.0, fz_n=635.0, kick_accel=40.0)
    return out


def write_case(name, scenario, path):
    """Run ``scenario`` and store its trajectory in ``path`` (NPZ)."""
    from whipple_kick import simulation
    result = simulation.run(scenario)
    df = result.trajectory
    arrays = {c: df[c].to_numpy(dtype=np.float32) for c in COLUMNS}
    np.savez_compressed(path, **arrays, name=np.array(name),
                        scenario_json=np.array(json.dumps(scenario.to_dict(), sort_keys=True)),
                        model_hash=np.array(simulation.model_hash()),
                        generated=np.array(_now()))
    return result


def _now():
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--reason", required=True,
                        help="why the references change (written to the changelog)")
    args = parser.parse_args(argv)
    reason = " ".join(args.reason.split())
    if not reason:
        parser.error("--reason must not be empty")
    from whipple_kick import simulation
    OUT.mkdir(parents=True, exist_ok=True)
    for name, scenario in cases().items():
        result = write_case(name, scenario, OUT / f"{name}.npz")
        s = result.summary
        end = f"fell at {s['fall_time_s']:.3f} s" if s["fell"] else f"{s['end_time_s']:g} s"
        print(f"{name:22s} {end:18s} -> {name}.npz")
    if not CHANGELOG.exists():
        CHANGELOG.write_text(
            "# Regression trajectories: changelog\n\n"
            "One line per regeneration (`scripts/regenerate_regression.py --reason ...`): "
            "date (UTC), compiled model hash, reason.\n\n")
    with CHANGELOG.open("a") as fh:
        fh.write(f"- {_now()} | {simulation.model_hash()} | {reason}\n")
    print(f"appended to {CHANGELOG.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
