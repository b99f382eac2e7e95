"""Measure what the tyre transient form and the kick's model options change (docs/validation.md).

Usage:
    python scripts/tyre_transient_study.py            # all tables (about 1 min)
    python scripts/tyre_transient_study.py forms      # one table: forms, gmin, plate_stop, carcass, steady, secant

Tables (400 kPa, 635 N, T03 table7_9, our LQR rider, 3 m/s, thesis kick):

* ``forms``: the default kick under each transient form (and the earlier
  model: force_lag with the dependent-speed re-solve and the settled heading):
  peak rates, roll change, rear force, recovery times, slips, energy terms.
* ``gmin``: the default run's sensitivity to the secant floor G_MIN.
* ``plate_stop``: kinetic-energy change at the plate stop, re-solve vs impulse,
  measured and symmetric tyres, and the impulse's work (the independent check).
* ``carcass``: passivity of the carcass: integrated carcass power against the
  constant-load-and-camber storage function at the samples, split into the
  zero-slip force's part and the rest; and the sign of the sliding dissipation.
* ``bounds``: |F_y| and |M_z| against the steady curve's largest value over
  slip at each sample's load, with the patch camber and with the wheel's.
* ``steady``: the steady motion's rear-wheel torque and what feeds it, and the
  speed reached with T6c = 0.
* ``secant``: the secant ratio of T03 at 400 kPa, 635 N at a few slips.
* ``six_runs``: the four transient forms on six runs (default, left kick,
  40 m/s^2, 300 and 500 kPa, controller off): peaks, recoveries, created energy.
* ``sliding_laws``: the carcass tyre's "peak" and "curve" sliding laws and a
  carcass damper on the same six runs.
* ``peak_slips``: T03's peak slip and force per pressure and load, and what
  the carcass tyre's 80 deg cap changes.
"""
import argparse
import contextlib
import dataclasses
import math
import sys

import numpy as np

import whipple_kick as wk
from whipple_kick.model import transient
from whipple_kick.simulate.assembly import build_tyres
from whipple_kick.simulate.simulation import Scenario, run

BASE = Scenario(pressure_kpa=400.0, fz_n=635.0)


def _peak_change(df, column):
    after = df["time"].to_numpy() >= 0.0
    values = df[column].to_numpy()
    return float(np.max(np.abs(values[after] - values[0])))


def _row(label, result):
    s, df = result.summary, result.trajectory
    e = s["energy"]
    rec = s["recovery"]["signals"]
    patch = (f"{math.degrees(np.max(np.abs(df['slip_patch_rear']))):.1f}" if "slip_patch_rear" in df else "-")
    times = " / ".join("fell" if v["time_s"] is None else f"{v['time_s']:.2f}" for v in rec.values())
    return (f"| {label} | {s['peaks']['max_abs_yaw_rate_absolute_rad_s']:.3f} | {s['peaks']['max_abs_roll_rate_absolute_rad_s']:.3f} | "
            f"{s['peaks']['max_abs_steer_rate_absolute_rad_s']:.3f} | {math.degrees(_peak_change(df, 'roll')):.1f} | "
            f"{s['peaks']['max_abs_fy_rear_absolute_n']:.0f} | {times} | {math.degrees(s['peaks']['max_abs_slip_rear_absolute_rad']):.1f} | "
            f"{patch} | {e['plate_work_j']:.2f} | {e['sliding_dissipation_j']:.2f} | "
            f"{e['carcass_energy_rear_j']:.2f} | {e['zero_slip_force_work_j']:.2f} | {e['aligning_moment_work_j']:.2f} | "
            f"{e['balance_residual_max_abs_j']:.1e} |")


def forms():
    print("| form | peak yaw rate [rad/s] | peak roll rate [rad/s] | peak steer rate [rad/s] | peak roll change [deg] "
          "| peak rear F_y [N] | 5 % recovery yaw / roll / steer rate [s] | max kinematic rear slip [deg] "
          "| max rear patch slip [deg] | plate work [J] | sliding dissipation [J] | rear carcass at 6 s [J] "
          "| zero-slip-force work [J] | moment work [J] | max balance residual [J] |")
    print("|" + "---|" * 15)
    for name in transient.transients():
        print(_row(name + (" (default)" if name == transient.DEFAULT_TRANSIENT else ""),
                   run(dataclasses.replace(BASE, tyre_transient=name))))
    earlier = dataclasses.replace(BASE, tyre_transient="force_lag", plate_stop="resolve", kick_heading="settled")
    print(_row("force_lag, re-solve, settled heading (earlier model)", run(earlier)))
    print()
    for name in transient.transients():
        r = run(dataclasses.replace(BASE, tyre_transient=name, controller="off"))
        print(f"controller off, {name}: fell {r.summary['fell']} ({r.summary['fall_reason']}) at "
              f"{r.summary['fall_time_s']}")


def gmin():
    print("| G_MIN | peak yaw rate [rad/s] | peak roll change [deg] | peak rear F_y [N] | yaw recovery [s] "
          "| smallest rear relaxation length [m] |")
    print("|---|---|---|---|---|---|")
    for value in (0.01, 0.02, 0.05):
        with _secant_floor(value):
            r = run(BASE)
        df = r.trajectory
        print(f"| {value:g} | {r.summary['peaks']['max_abs_yaw_rate_absolute_rad_s']:.6f} | "
              f"{math.degrees(_peak_change(df, 'roll')):.4f} | {r.summary['peaks']['max_abs_fy_rear_absolute_n']:.2f} | "
              f"{r.summary['recovery']['time_s']} | {df['relaxation_length_rear'].min():.4f} |")


@contextlib.contextmanager
def _secant_floor(value):
    """Compile and use the model with ``transient.G_MIN = value`` (its own cache entry)."""
    from whipple_kick.model import cache, slip
    from whipple_kick.model.symbolic import slip_build
    original, hash_function = transient.G_MIN, cache.source_hash

    def keyed(sources, extra=""):
        return hash_function(sources, extra=f"{extra} G_MIN={value!r}")
    transient.G_MIN = value
    cache.source_hash = keyed
    slip_build._expressions_of.cache_clear()
    slip.compiled._library.cache_clear()
    try:
        yield
    finally:
        transient.G_MIN, cache.source_hash = original, hash_function
        slip_build._expressions_of.cache_clear()
        slip.compiled._library.cache_clear()


def plate_stop():
    print("| tyres | transient | plate stop | KE change at the stop [J] | impulse work [J] |")
    print("|---|---|---|---|---|")
    for symmetric in (False, True):
        for name in ("force_lag", "contact_patch"):
            for stop in ("resolve", "impulse"):
                r = run(dataclasses.replace(BASE, tyre_transient=name, plate_stop=stop, symmetric_tyres=symmetric,
                                            duration=0.3))
                jump = r.summary["energy"]["velocity_jumps"][0]
                work = jump["impulse_work_j"]
                print(f"| {'symmetric' if symmetric else 'measured'} | {name} | {stop} | "
                      f"{jump['kinetic_energy_change_j']:+.4f} | {'-' if work is None else f'{work:+.4f}'} |")


def _storage(tyre, a, g, fz):
    """Constant-load-and-camber carcass storage -int_0^a (F - F0) sigma sec^2 da at each sample [J]."""
    out = np.empty(a.size)
    for i in range(a.size):
        al = np.linspace(0.0, a[i], 401)
        if fz[i] <= 0.0:
            out[i] = 0.0
            continue
        force = tyre.lateral_force(al, g[i], fz[i]) - tyre.lateral_force(0.0 * al, g[i], fz[i])
        sigma = tyre.relaxation_length * np.maximum(tyre.secant_ratio(al, max(fz[i], transient.FZ_SHAPE_FLOOR)),
                                                    transient.G_MIN)
        out[i] = -np.trapezoid(force * sigma / np.cos(al)**2, al)
    return out


def carcass():
    for label, scenario in (("default", BASE), ("symmetric", dataclasses.replace(BASE, symmetric_tyres=True))):
        r = run(scenario)
        df = r.trajectory
        rear, front, _ = build_tyres(scenario.tyre_spec)
        if scenario.symmetric_tyres:
            rear, front = rear.without_offsets(), front.without_offsets()
        t = df["time"].to_numpy()
        every = slice(None, None, 5)
        for wheel, tyre in (("rear", rear), ("front", front)):
            a = df[f"slip_patch_{wheel}"].to_numpy()
            g = df[f"camber_patch_{wheel}"].to_numpy()
            fz = df[f"fz_{wheel}"].to_numpy()
            vx = np.abs(df[f"rolling_speed_{wheel}"].to_numpy())
            vsy = vx * np.tan(df[f"slip_{wheel}"].to_numpy())
            force = df[f"fy_{wheel}"].to_numpy()
            force0 = tyre.lateral_force(0.0 * a, g, fz)
            patch_speed = vx * np.tan(a)
            after = t >= 0.0
            part0 = np.trapezoid((force0 * (patch_speed - vsy))[after], t[after])
            rest = np.trapezoid(((force - force0) * (patch_speed - vsy))[after], t[after])
            stored = _storage(tyre, a[every], g[every], fz[every])
            column = df[f"carcass_energy_{wheel}"].to_numpy()
            print(f"{label} {wheel}: carcass energy min {column.min():+.3f} J, at 6 s {column[-1]:+.3f} J; "
                  f"of which (trapezoid) zero-slip force {part0:+.3f} J, the rest {rest:+.3f} J; "
                  f"constant-load storage max {stored.max():.3f} J, at 6 s {stored[-1]:.4f} J")
        slide = np.diff(df["sliding_dissipation"].to_numpy())
        print(f"{label}: sliding dissipation total {df['sliding_dissipation'].iloc[-1]:.3f} J, "
              f"largest decrease between samples {max(0.0, -slide.min()):.2e} J")
    # The thesis' form in the same accounting: energy created where its force pushes along the sliding.
    df = run(dataclasses.replace(BASE, tyre_transient="force_lag")).trajectory
    slide = np.diff(df["sliding_dissipation"].to_numpy())
    t = df["time"].to_numpy()[1:]
    stop = (t > 0.15) & (t < 0.2)
    print(f"force_lag: sliding dissipation decreases by {-slide[slide < 0].sum():.2f} J in all, "
          f"{-slide[stop & (slide < 0)].sum():.2f} J of it in the 50 ms after the plate stop")


def steady():
    r = run(dataclasses.replace(BASE, duration=0.2))
    st = r.summary["steady_state"]
    print(f"T6c = {st['rear_wheel_torque_n_m']:+.5f} N m ({st['rear_wheel_torque_role']}); steady powers [W]: "
          + ", ".join(f"{k} {v:+.4f}" for k, v in st["steady_power_w"].items()))
    # What positive T6c does: integrate the steady state with T6c = 0 for 20 s (no kick).
    from whipple_kick.model import slip
    from whipple_kick.simulate import lsoda
    moore, design, _ = wk.assembly.build_bicycle(BASE.bicycle_spec)
    gains, _ = wk.assembly.controller_gains(BASE.gains_spec, design)
    rear, front, _ = build_tyres(BASE.tyre_spec)
    ss = steady.steady_state(slip.model_parameters(moore, rear, front, gains=gains), 3.0)
    for torque in (0.0, 2 * ss.params["T6c"]):
        params = ss.params.replace(T6c=torque)
        tr = lsoda.integrate(slip.CompiledRHS(params), ss.x, 20.0, output_rate=10)
        speed = np.hypot(tr.state("u1"), tr.state("u2"))
        print(f"T6c = {torque:+.4f} N m from the steady state: speed after 20 s {speed[-1]:.4f} m/s")


def secant():
    tyre = wk.tyres.load("T03", 400.0)
    slips = np.radians([0.0, 2.0, 5.0, 8.5, 20.0, 36.0, 60.0, 90.0])
    ratio = tyre.secant_ratio(slips, 635.0)
    force = -tyre.lateral_force(np.radians(np.linspace(0, 90, 9001)), 0.0, 635.0)
    peak = math.degrees(np.radians(np.linspace(0, 90, 9001))[np.argmax(force)])
    print(f"T03 400 kPa 635 N: peak of F_y at {peak:.2f} deg, secant ratio there "
          f"{float(tyre.secant_ratio(math.radians(peak), 635.0)):.3f}")
    print(", ".join(f"{math.degrees(s):g} deg: {g:.4f}" for s, g in zip(slips, ratio, strict=True)))


def _curve_peak(tyre, camber, fz, kind):
    """Largest |F_y| (or |M_z|) of the steady curve over slip in [-90, 90] deg at each (camber, load)."""
    slips = np.radians(np.linspace(-90.0, 90.0, 3601))[None, :]
    curve = tyre.lateral_force if kind == "fy" else tyre.aligning_moment
    out = np.empty(camber.size)
    for start in range(0, camber.size, 500):
        rows = slice(start, start + 500)
        out[rows] = np.max(np.abs(curve(slips, camber[rows, None], fz[rows, None])), axis=1)
    return out


def bounds():
    """|F_y| and |M_z| against the steady curve's largest value at the sample's load and camber."""
    print("| run | form | wheel | max |F_y|/peak, patch camber | same, wheel camber | max |M_z|/peak, patch camber "
          "| same, wheel camber | largest |F_y| while unloaded [N] |")
    print("|---|---|---|---|---|---|---|---|")
    # Controller off is followed past the fork turning over to the widest steer limit (180 deg), as the tests do:
    # the front wheel lifts off about 10 ms after the steer passes 90 deg, and the unloaded tyre is the point.
    for label, changes in (("default", {}), ("controller off", {"controller": "off", "steer_limit_deg": 180.0}),
                           ("40 m/s^2 kick", {"kick_accel": 40.0})):
        for name in ("contact_patch", "force_lag"):
            scenario = dataclasses.replace(BASE, tyre_transient=name, **changes)
            r = run(scenario)
            df = r.trajectory
            rear, front, _ = build_tyres(scenario.tyre_spec)
            for wheel, tyre in (("rear", rear), ("front", front)):
                fz = df[f"fz_{wheel}"].to_numpy()
                loaded = fz > 0.0
                cells = []
                for kind, column in (("fy", f"fy_{wheel}"), ("mz", f"mz_{wheel}")):
                    value = np.abs(df[column].to_numpy())
                    for camber_column in (f"camber_patch_{wheel}", f"camber_{wheel}"):
                        if camber_column not in df:
                            cells.append("-")
                            continue
                        peak = _curve_peak(tyre, df[camber_column].to_numpy()[loaded], fz[loaded], kind)
                        cells.append(f"{np.max(value[loaded] / peak):.4f}")
                unloaded = np.abs(df[f"fy_{wheel}"].to_numpy()[~loaded])
                print(f"| {label} | {name} | {wheel} | " + " | ".join(cells)
                      + f" | {unloaded.max() if unloaded.size else 0.0:.1f} |")


#: The six runs the transient forms are compared on (400 kPa and 635 N unless changed).
SIX_RUNS = {"default": {}, "left kick": {"kick_direction": "left"}, "40 m/s^2 kick": {"kick_accel": 40.0},
            "300 kPa": {"pressure_kpa": 300.0}, "500 kPa": {"pressure_kpa": 500.0},
            "controller off": {"controller": "off"}}


def six_runs():
    """The four forms on the six runs: peaks, recoveries and the carcass energy's minimum (created energy)."""
    print("| run | form | outcome | peak roll change [deg] | peak yaw rate [rad/s] | peak steer rate [rad/s] "
          "| peak rear F_y [N] | 5 % recovery yaw / roll / steer rate [s] | created energy [J] |")
    print("|" + "---|" * 9)
    for label, changes in SIX_RUNS.items():
        for name in (transient.DEFAULT_TRANSIENT, *(f for f in transient.transients() if f != transient.DEFAULT_TRANSIENT)):
            r = run(dataclasses.replace(BASE, tyre_transient=name, **changes))
            s, df = r.summary, r.trajectory
            rec = s["recovery"]["signals"]
            times = " / ".join("-" if v["time_s"] is None else f"{v['time_s']:.2f}" for v in rec.values())
            outcome = (f"lost at {s['fall_time_s']:.2f} s ({s['fall_reason']})" if s["fell"] else "completed")
            # Energy the tyre model creates: the carcass energies' lowest value below what the carcass held
            # at the kick start (the force lag stores nothing: 0 by construction, its spurious work shows
            # in the zero-slip and sliding terms instead).
            created = max(0.0, -min(float((df[c] - df[c].iloc[df.index[df["time"] >= 0.0][0]]).min())
                                    for c in ("carcass_energy_rear", "carcass_energy_front")))
            if name == "carcass":
                created = max(0.0, -min(float(df[c].min()) for c in ("carcass_energy_rear", "carcass_energy_front")))
            print(f"| {label} | {name} | {outcome} | {math.degrees(_peak_change(df, 'roll')):.2f} | "
                  f"{s['peaks']['max_abs_yaw_rate_absolute_rad_s']:.3f} | {s['peaks']['max_abs_steer_rate_absolute_rad_s']:.3f} | "
                  f"{s['peaks']['max_abs_fy_rear_absolute_n']:.0f} | {times} | {created:.3g} |")


def sliding_laws():
    """The carcass tyre's sliding law past the peak and its damper: what they change on the six runs."""
    print("| run | variant | peak roll change [deg] | peak yaw rate [rad/s] | peak rear F_y [N] "
          "| 5 % recovery yaw rate [s] | carcass damper dissipation [J] |")
    print("|" + "---|" * 7)
    for label, changes in SIX_RUNS.items():
        for variant, extra in (("peak (default)", {}), ("curve", {"carcass_sliding": "curve"}),
                               ("peak, damper 75 N s/m", {"carcass_damping": 75.0})):
            r = run(dataclasses.replace(BASE, **changes, **extra))
            s, df = r.summary, r.trajectory
            yaw = s["recovery"]["signals"]["yaw_rate"]["time_s"]
            print(f"| {label} | {variant} | {math.degrees(_peak_change(df, 'roll')):.2f} | "
                  f"{s['peaks']['max_abs_yaw_rate_absolute_rad_s']:.3f} | {s['peaks']['max_abs_fy_rear_absolute_n']:.0f} | "
                  f"{'-' if yaw is None else f'{yaw:.2f}'} | {df['carcass_damper_dissipation'].iloc[-1]:.2f} |")


def peak_slips():
    """T03 table7_9's peak slip and peak force per pressure and load (the carcass tyre's friction limit)."""
    from whipple_kick.model import carcass as carcass_module
    print(r"| pressure [kPa] | C | load [N] | peak slip [deg] | peak \|F_y\| [N] | \|F_y\| at 33 deg / peak "
          r"| \|F_y\| at 80 deg (cap) / at 89.9 deg |")
    print("|" + "---|" * 7)
    for p in (300, 400, 500):
        tyre = wk.tyres.load("T03", p)
        c_factor = tyre.blend[0][1][0]
        for fz in (343.0, 488.0, 635.0, 1100.0):
            slips = np.radians(np.linspace(0.0, 89.9, 8991))
            f = -tyre.lateral_force(slips, 0.0, fz)
            k = int(np.argmax(f))
            cap = float(-tyre.lateral_force(np.radians(carcass_module.PATCH_SLIP_CAP_DEG), 0.0, fz))
            peak_text = f"{math.degrees(slips[k]):.1f}" if k < slips.size - 1 else "none below 90"
            print(f"| {p} | {c_factor:.4g} | {fz:.0f} | {peak_text} | {f[k]:.0f} | "
                  f"{float(-tyre.lateral_force(np.radians(33.0), 0.0, fz)) / f[k]:.3f} | {cap / f[-1]:.4f} |")


TABLES = {"six_runs": six_runs, "sliding_laws": sliding_laws, "peak_slips": peak_slips, "forms": forms, "bounds": bounds, "gmin": gmin, "plate_stop": plate_stop, "carcass": carcass, "steady": steady,
          "secant": secant}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("tables", nargs="*", choices=[*TABLES, []], default=[])
    args = parser.parse_args(argv)
    for name in args.tables or TABLES:
        print(f"## {name}")
        TABLES[name]()
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
