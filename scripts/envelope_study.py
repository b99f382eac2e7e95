"""The rider across the speed envelope, and the integration budget that keeps runs from hanging.

Two measurements, each printed as Markdown:

``envelope``
    Speeds 1.5, 1.92, 2, 2.2, 2.4, 2.5, 2.6, 2.7, 3, 4, 6, 8 m/s x pressures
    300/400/500 kPa x rear loads 500/570/701/800 N (T03, default kick, 6 s),
    for the default rider (LQR designed at the run's speed), the rider fixed
    at the thesis' 3 m/s design speed, and (1.92, 2 and 3 m/s, the authors'
    635 N and 701 N presets) the thesis' own set-up (``Scenario.thesis``). Per rider: how many steady
    motions were found and how (directly, as a steady turn, by
    continuation), how many riders are linearly unstable, how many runs fell,
    failed or recovered, and the slowest cases.

``budget``
    Right-hand-side evaluations (those inside the C Jacobians included) of
    completed and falling runs across kicks
    (5-200 m/s^2), speeds (1.5-8 m/s), tolerances (rtol 1e-8..1e-12), riders,
    a 151-row kick table and the thesis preset, measured on every evaluation:
    the largest fraction of the default budget (``lsoda.DEFAULT_BUDGET``)
    any part of an integrate() call (the settle, the run after the kick, a
    table's pieces: each has its own budget) from its start spent, and the least time any window
    of its ``stall_window`` consecutive evaluations advanced it, so the
    budget is set with a stated margin.

Usage: ``python scripts/envelope_study.py [envelope|budget|all]``. The
envelope takes about 4 min on one core, the budget about 2 min.
"""
import argparse
import collections
import math
import sys
import time

import numpy as np

import whipple_kick as wk
from whipple_kick.model import slip
from whipple_kick.simulate import lsoda, simulation, steady
from whipple_kick.simulate.simulation import Scenario

SPEEDS = (1.5, 1.92, 2.0, 2.2, 2.4, 2.5, 2.6, 2.7, 3.0, 4.0, 6.0, 8.0)
PRESSURES = (300.0, 400.0, 500.0)
LOADS = (500.0, 570.0, 701.0, 800.0)


def outcome(scenario):
    """(status, summary or None, error text, wall time [s]) of one run; never raises."""
    t0 = time.perf_counter()
    try:
        result = simulation.run(scenario)
    except steady.NoSteadyMotion as exc:
        return "no steady motion", None, str(exc), time.perf_counter() - t0
    except simulation.SimulationError as exc:   # nothing computed to return
        return "failed", None, str(exc), time.perf_counter() - t0
    error = None if result.success else result.message
    return result.summary["outcome"], result.summary, error, time.perf_counter() - t0


def envelope_cases():
    riders = {
        "adaptive LQR (default)": lambda v, p, fz: Scenario(speed=v, pressure_kpa=p, fz_n=fz),
        "LQR fixed at 3 m/s": lambda v, p, fz: Scenario(speed=v, pressure_kpa=p, fz_n=fz, design_speed=3.0),
    }
    for name, make in riders.items():
        yield name, [((v, p, fz), make(v, p, fz)) for v in SPEEDS for p in PRESSURES for fz in LOADS]
    # The authors' presets with rider (635 and 701 N; their label selects the Table 8.4 row).
    yield "thesis set-up (Table 8.4 rider, presets with rider)", [
        ((v, p, fz), Scenario.thesis(pressure_kpa=p, speed=v, thesis_load_n=None, bicycle=f"balanceassist_{fz:.0f}N"))
        for v in (1.92, 2.0, 3.0) for p in PRESSURES for fz in (635.0, 701.0)]


def envelope():
    print(f"slip model {wk.slip.model_hash()}\n")
    for rider, cases in envelope_cases():
        per_speed = collections.defaultdict(collections.Counter)
        slow, notes = [], []
        for (v, p, fz), scenario in cases:
            status, summary, error, wall = outcome(scenario)
            row = per_speed[v]
            row[status] += 1
            if summary is not None:
                row["unstable"] += not summary["linear_stability"]["stable"]
                row["turn"] += summary["steady_state"]["found_by"] != "direct"
                row["recovered"] += summary["recovery"]["time_s"] is not None
                row["steer"] += summary.get("fall_reason") == "steer"
            if status in ("failed", "no steady motion"):
                notes.append(f"{v:g} m/s, {p:g} kPa, {fz:g} N: {error}")
            elif status == "fell" and rider.startswith("adaptive"):
                notes.append(f"{v:g} m/s, {p:g} kPa, {fz:g} N: {summary['message']}")
            slow.append((wall, f"{v:g} m/s, {p:g} kPa, {fz:g} N ({status})"))
        slow.sort(reverse=True)
        total = sum(per_speed.values(), collections.Counter())
        print(f"### {rider}: {len(cases)} cases\n")
        print("| speed [m/s] | cases | completed (recovered in 6 s) | fell (of which the fork turned over) | failed "
              "| no steady motion | "
              "steady motion not the direct solve | rider linearly unstable |\n|---|---|---|---|---|---|---|---|")
        for v, row in sorted(per_speed.items()) + [("all", total)]:
            n = sum(row[k] for k in ("completed", "fell", "failed", "no steady motion"))
            label = v if v == "all" else f"{v:g}"
            print(f"| {label} | {n} | {row['completed']} ({row['recovered']}) | {row['fell']} ({row['steer']}) | {row['failed']} | "
                  f"{row['no steady motion']} | {row['turn']} | {row['unstable']} |")
        print("\nslowest runs: " + "; ".join(f"{w:.2f} s {label}" for w, label in slow[:3]))
        for note in notes:
            print(f"* {note}")
        print()


class CallLog:
    """Records the time of every right-hand-side evaluation of the compiled model.

    A C Jacobian counts as the evaluations it makes (``jac.evaluations``), as
    the budget counts it.
    """

    def __init__(self):
        self.times = []
        self.calls = []   # (first index into times, last index + 1, t_start) of each integrate() call

    def install(self):
        original_call, original_guarded = slip.CompiledRHS.__call__, slip.CompiledRHS.guarded
        original_jacobian = slip.CompiledRHS.jacobian_function
        log = self.times

        def call(rhs, t, x):
            log.append(t)
            return original_call(rhs, t, x)

        def guarded(rhs, *limits):
            fast = original_guarded(rhs, *limits)

            def f(t, x):
                log.append(t)
                return fast(t, x)
            return f

        def jacobian_function(rhs, scale):
            jac = original_jacobian(rhs, scale)

            def logged(t, x):
                log.extend([t] * jac.evaluations)
                return jac(t, x)
            logged.evaluations = jac.evaluations
            return logged

        original_integrate = lsoda.integrate
        calls = self.calls

        def integrate_logged(rhs, x0, t_end, t_start=0.0, *args, **kwargs):
            first = len(log)
            try:
                return original_integrate(rhs, x0, t_end, t_start, *args, **kwargs)
            finally:
                calls.append((first, len(log), t_start))

        slip.CompiledRHS.__call__, slip.CompiledRHS.guarded = call, guarded
        slip.CompiledRHS.jacobian_function = jacobian_function
        lsoda.integrate = integrate_logged


def budget_used(times, t_start, budget):
    """(largest fraction of ``budget``'s limit any prefix of a run spent, least time any
    ``budget.stall_window`` consecutive evaluations advanced it [s], or inf for shorter runs)."""
    t = np.asarray(times, dtype=float)
    reached = np.maximum.accumulate(t) - t_start
    n = np.arange(1, t.size + 1)
    used = float(np.max(n / (budget.allowance + budget.per_second * reached)))
    w = budget.stall_window
    progress = float(np.min(reached[w:] - reached[:-w])) if t.size > w else math.inf
    return used, progress


def budget_cases(table_path):
    for accel in (5.0, 13.3333, 30.0, 40.0, 100.0, 200.0):
        for speed in (1.5, 3.0, 5.0, 8.0):
            yield f"kick {accel:g} m/s^2, {speed:g} m/s, rider at 3 m/s", Scenario(
                kick_accel=accel, speed=speed, design_speed=3.0)
    for speed in SPEEDS:
        yield f"adaptive rider, {speed:g} m/s", Scenario(speed=speed)
    for rtol in (1e-8, 1e-12):
        for changes in ({}, {"controller": "off"}, {"kick_accel": 35.0}):
            yield f"rtol {rtol:g} {changes}", Scenario(rtol=rtol, **changes)
    yield "151-row kick table", Scenario(kick_profile="table", kick_table=table_path)
    for p in PRESSURES:
        yield f"thesis preset {p:g} kPa, 3 m/s, rtol 1e-12", Scenario.thesis(pressure_kpa=p)
        yield f"thesis preset {p:g} kPa, 1.92 m/s", Scenario.thesis(pressure_kpa=p, speed=1.92)
    yield "low inertia", Scenario(low_inertia=True)


def budget():
    import pathlib
    import tempfile
    budget_ = lsoda.DEFAULT_BUDGET
    with tempfile.TemporaryDirectory() as folder:
        table = pathlib.Path(folder) / "smooth.csv"
        t = np.arange(151) / 1000.0
        s = t / 0.15
        table.write_text("time,y\n" + "".join(f"{float(a)!r},{float(0.15 * (10 * b**3 - 15 * b**4 + 6 * b**5))!r}\n"
                                              for a, b in zip(t, s, strict=True)))
        log = CallLog()
        log.install()
        rows = []
        for label, scenario in budget_cases(str(table)):
            log.times.clear()
            log.calls.clear()
            status, summary, error, wall = outcome(scenario)
            if status not in ("completed", "fell"):
                rows.append((math.inf, 0.0, label, status, 0, 0.0, error))
                continue
            # The steady-state solve and the linearisation evaluate the model too: only the
            # integration's evaluations count, per integrate() call (each has its own budget).
            per_call = [budget_used(log.times[a:b], t0, budget_) for a, b, t0 in log.calls if b > a]
            span = summary["end_time_s"] + scenario.settle
            if status == "fell":
                status = f"fell ({summary['fall_reason']})"
            rows.append((max(u for u, _ in per_call), min(p for _, p in per_call), label, status,
                         summary["numerics"]["evaluations"], span, None))
    rows.sort(key=lambda r: -r[0])
    print(f"Default budget: {budget_.allowance} evaluations + {budget_.per_second:g} per simulated second, "
          f"and at least {budget_.stall_progress:g} s per {budget_.stall_window} evaluations. Per run: the largest "
          f"fraction of the first any part of it (from its start) spent, and the least time any "
          f"{budget_.stall_window} consecutive evaluations advanced it; largest fraction first\n")
    print("| run | outcome | evaluations | simulated [s] | per simulated s | budget used | least advance [s] |"
          "\n|---|---|---|---|---|---|---|")
    for used, progress, label, status, nfev, span, error in rows:
        if error is not None:
            print(f"| {label} | {status}: {error} | | | | | |")
        else:
            print(f"| {label} | {status} | {nfev} | {span:.3f} | {nfev / span:.0f} | {used:.1%} | {progress:.3g} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", nargs="?", default="all", choices=("envelope", "budget", "all"))
    args = parser.parse_args(argv)
    if args.what in ("envelope", "all"):
        envelope()
    if args.what in ("budget", "all"):
        budget()
    return 0


if __name__ == "__main__":
    sys.exit(main())
