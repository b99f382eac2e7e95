"""How the steer limit that ends a run as lost changes the outcomes (docs/validation.md, "The steer limit").

A run ends as lost when |roll| reaches ``fall_angle_deg`` (45 deg) or |steer| reaches
``steer_limit_deg`` (90 deg by default; ``summary["fall_reason"]`` says which). This script runs
the same cases with the steer limit at 60, 75, 90 and 180 deg and with none at all, and prints
Markdown tables of where each run ends and why:

* ``off``: the nine thesis cases (T03, 300/400/500 kPa x 570/635/701 N, 3 m/s, thesis kick)
  without control, on the default tyre transient and on the thesis' force lag; beside them the
  roll when the 90 deg limit ends the run and how long the fork takes from 90 to 180 deg of steer;
* ``presets``: the thesis' set-up (``Scenario.thesis``) without control and the authors'-code
  mode (``Scenario.authors_code``, its controller on) at 300, 400 and 500 kPa;
* ``lqr``: the default run (400 kPa, 635 N, our LQR rider) under every limit, and the largest
  |steer| of the nine cases with our rider, full and half gains.

"none" is ``steer_limit_deg=None`` (a fork spinning past 90 deg also reaches 180 deg, so 180 is
not the same as no limit).

Usage: ``python scripts/steer_limit_study.py [off presets lqr]`` (all by default; about 1 min).
"""
import argparse
import math
import sys

import numpy as np

from whipple_kick.model import slip
from whipple_kick.simulate import simulation
from whipple_kick.simulate.simulation import Scenario

LIMITS = (60.0, 75.0, 90.0, 180.0, None)   # [deg]; None: no steer limit
NINE_CASES = [(p, fz) for fz in (570.0, 635.0, 701.0) for p in (300.0, 400.0, 500.0)]


def run(scenario, limit):
    """The result of ``scenario`` with the steer limit ``limit`` [deg] (None: none), also when it failed."""
    return simulation.run(scenario.with_changes(steer_limit_deg=limit))   # a failed run is a Result too


def ending(result):
    """Where and why a run ended: "1.59 steer", "2.17 roll", "2.68 stalled" or "completed"."""
    s = result.summary
    if s["outcome"] == "fell":
        return f"{s['fall_time_s']:.2f} {s['fall_reason']}"
    if s["outcome"] == "failed":
        return f"{s['end_time_s']:.2f} " + ("stalled" if "stalled" in s["message"] else "failed")
    return "completed"


def first_time_past(result, column, angle_deg):
    """First sample time after the kick at which |column| reaches ``angle_deg`` [deg], or None."""
    df = result.trajectory
    t = df["time"].to_numpy()
    past = np.flatnonzero((t >= 0.0) & (np.abs(df[column].to_numpy()) >= math.radians(angle_deg) * (1 - 1e-12)))
    return float(t[past[0]]) if past.size else None


def limit_header(first, extra):
    names = ["none" if v is None else f"{v:g} deg" + (" (default)" if v == 90.0 else "") for v in LIMITS]
    head = f"| {first} | " + " | ".join(names) + "".join(f" | {e}" for e in extra) + " |"
    return head + "\n|" + "---|" * (1 + len(LIMITS) + len(extra))


def off(transients=("contact_patch", "force_lag")):
    for transient in transients:
        print(f"\nController off, tyre transient {transient}: end of the run after the kick [s] and why, "
              "for each steer limit\n")
        print(limit_header("case", ["roll when the 90 deg limit ends the run [deg]",
                                    "fork from 90 to 180 deg of steer [ms]"]))
        for pressure, fz in NINE_CASES:
            scenario = Scenario(pressure_kpa=pressure, fz_n=fz, controller="off", tyre_transient=transient)
            results = {limit: run(scenario, limit) for limit in LIMITS}
            at90 = results[90.0]
            roll90 = (f"{math.degrees(abs(at90.trajectory['roll'].iloc[-1])):.1f}"
                      if at90.summary["fall_reason"] == "steer" else "-")
            free = results[None]
            t90, t180 = first_time_past(free, "steer", 90.0), first_time_past(free, "steer", 180.0)
            spin = f"{1e3 * (t180 - t90):.0f}" if t90 is not None and t180 is not None else "-"
            print(f"| {pressure:.0f} kPa, {fz:.0f} N | " + " | ".join(ending(results[v]) for v in LIMITS)
                  + f" | {roll90} | {spin} |")


def presets():
    print("\nThe thesis' set-up without control and the authors'-code mode: end of the run after the kick [s] "
          "and why, for each steer limit; and the largest |steer| before the end without a limit\n")
    print(limit_header("run", ["largest \\|steer\\| without a limit [deg]"]))
    for label, make in (("`Scenario.thesis`, controller off", lambda p: Scenario.thesis(p, controller="off")),
                        ("`Scenario.authors_code`", Scenario.authors_code)):
        for pressure in (300.0, 400.0, 500.0):
            results = {limit: run(make(pressure), limit) for limit in LIMITS}
            largest = math.degrees(np.max(np.abs(results[None].trajectory["steer"].to_numpy())))
            print(f"| {label}, {pressure:.0f} kPa | " + " | ".join(ending(results[v]) for v in LIMITS)
                  + f" | {largest:.1f} |")


def lqr():
    base = Scenario(pressure_kpa=400.0, fz_n=635.0)
    results = {limit: run(base, limit) for limit in LIMITS}
    reference = results[None].trajectory.drop(columns="time")
    differences = [float(np.max(np.abs((results[v].trajectory.drop(columns="time") - reference).to_numpy())))
                   for v in LIMITS]
    print("\nThe default run (400 kPa, 635 N, our LQR rider, 6 s) under each steer limit\n")
    print(limit_header("", []))
    print("| outcome | " + " | ".join(ending(results[v]) for v in LIMITS) + " |")
    print("| largest difference from the run without a limit (any column) | "
          + " | ".join(f"{d:.1e}" for d in differences) + " |")
    steer = math.degrees(np.max(np.abs(results[None].trajectory["steer"].to_numpy())))
    print(f"\nlargest |steer| of the default run: {steer:.1f} deg\n")
    print("| case | largest \\|steer\\|, full gains [deg] | largest \\|steer\\|, 50 % gains [deg] |\n|---|---|---|")
    for pressure, fz in NINE_CASES:
        cells = []
        for scale in (1.0, 0.5):
            r = run(Scenario(pressure_kpa=pressure, fz_n=fz, gain_scale=scale), None)
            cells.append(f"{math.degrees(np.max(np.abs(r.trajectory['steer'].to_numpy()))):.1f}"
                         + ("" if r.summary["outcome"] == "completed" else f" ({ending(r)})"))
        print(f"| {pressure:.0f} kPa, {fz:.0f} N | " + " | ".join(cells) + " |")


TABLES = {"off": off, "presets": presets, "lqr": lqr}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tables", nargs="*", choices=[*TABLES, []], help="tables to print (default all)")
    args = parser.parse_args(argv)
    print(f"slip model {slip.model_hash()}")
    for name in args.tables or TABLES:
        TABLES[name]()
    return 0


if __name__ == "__main__":
    sys.exit(main())
