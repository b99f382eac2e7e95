"""Side by side with the thesis authors' published code (docs/validation.md, "The authors' published code").

Usage:
    python scripts/authors_code_study.py             # all tables (about 1 min)
    python scripts/authors_code_study.py switches    # one table: agreement, held_out, switches, geometry,
                                                     # poles, energy, thesis

Tables (the stored run: tests/data/authors_model, T03 chapter8 at 500 kPa, Table 8.4 rider, 3 m/s;
two more runs held out from the mode's tuning in its subfolders, authors_code.STORED_RUNS):

* ``agreement``: ``Scenario.authors_code()`` against the stored run: each signal's largest
  difference as a fraction of the stored run's peak over 0-1, 0-2 and 0-3 s after the kick;
  the first yaw-rate peak; the fall time.
* ``held_out``: every stored run against the mode, each signal's largest difference over 0-1 s
  as a fraction of the run's peak, with the mode's slip speed and start pitch and with this
  model's (the mode before the slip speed and start pitch became switches); first yaw-rate peaks and falls.
* ``switches``: each of the mode's assumptions switched back to this model's alone (from the
  mode), and each switched on alone in the authors' preset with this model's assumptions
  (``Scenario.thesis(500)``): outcome, first yaw-rate peak, largest difference from the stored
  run over 0-1 s.
* ``geometry``: the authors' contact positions (2 r_t below the rim point) given to this model
  through its parameters alone (wheel radius + 2 r_t, crown radius 2 r_t): trail and outcome.
* ``poles``: slowest closed-loop poles of the Table 8.4 rider with either camber sign, about the
  steady motion and about upright running without the tyres' offsets.
* ``energy``: where the speed the falling run gains comes from: the energy columns of the mode's
  run, and the forward speed of the stored run.
* ``thesis``: the thesis' statements about its model against this model with the authors' preset
  (``Scenario.thesis``) at 300, 400 and 500 kPa.
"""
import argparse
import copy
import math
import pathlib
import sys
import tempfile

import numpy as np

import whipple_kick as wk
from whipple_kick.library import bicycles
from whipple_kick.model import slip
from whipple_kick.simulate import steady
from whipple_kick.simulate.simulation import Scenario, run
from whipple_kick.studies import authors_code

DATA = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "authors_model"


def _stored():
    return authors_code.load_run(DATA)


def _outcome(result):
    s = result.summary
    if s["fell"]:
        return (f"falls at {s['fall_time_s']:.3f} s" if s["fall_reason"] == "roll"
                else f"lost at {s['fall_time_s']:.3f} s (the fork turned over)")
    rec = s["recovery"]
    return (f"no fall in {s['end_time_s']:g} s, recovery {rec['time_s']:.2f} s" if rec["time_s"] is not None
            else f"no fall in {s['end_time_s']:g} s, not recovered within it")


def _largest(deviation):
    name = max(deviation, key=deviation.get)
    return f"{100 * deviation[name]:.1f} % ({name})"


def agreement():
    stored = _stored()
    result = run(Scenario.authors_code())
    print("| window after the kick | " + " | ".join(authors_code.SIGNALS) + " |")
    print("|---|" + "---|" * len(authors_code.SIGNALS))
    for end in (1.0, 2.0, 3.0):
        theirs = stored.samples if end == 1.0 else stored.whole
        d = authors_code.deviations(result.trajectory, theirs, window=(0.0, end))
        print(f"| 0-{end:g} s | " + " | ".join(f"{100 * d[n]:.1f} %" for n in authors_code.SIGNALS) + " |")
    t_ours, v_ours = authors_code.first_yaw_peak(result.trajectory)
    t_theirs, v_theirs = authors_code.first_yaw_peak(stored.samples)
    print(f"\nfirst yaw-rate peak: ours {v_ours:+.4f} rad/s at {t_ours:.4f} s, theirs {v_theirs:+.4f} rad/s at "
          f"{t_theirs:.4f} s ({100 * abs(v_ours / v_theirs - 1):.2f} %, {1e3 * abs(t_ours - t_theirs):.1f} ms)")
    print(f"fall: ours {result.summary['fall_time_s']:.3f} s, theirs {stored.fall_time_s:.3f} s")
    jump, = result.summary["energy"]["velocity_jumps"]
    print(f"rear slide after the plate stop: {jump['rear_slide_m_s']:+.4f} m/s")


#: The mode with this model's slip speed and start pitch (the mode before the slip speed and start pitch became switches).
OURS_SLIP_AND_PITCH = {"slip_speed": "wheel_centre", "start_pitch": "compressed"}


def held_out():
    print("| run | mode | " + " | ".join(authors_code.SIGNALS) + " | first yaw-rate peak [rad/s] | outcome |")
    print("|---|---|" + "---|" * (len(authors_code.SIGNALS) + 2))
    for name, (folder, changes) in authors_code.STORED_RUNS.items():
        stored = authors_code.load_run(DATA / folder)
        t, v = authors_code.first_yaw_peak(stored.samples)
        print(f"| {name} | their run | " + " | ".join("-" for _ in authors_code.SIGNALS)
              + f" | {v:+.4f} at {t:.4f} s | falls at {stored.fall_time_s:.3f} s |")
        for label, extra in (("with the wheel centre's slip speed and compressed pitch", OURS_SLIP_AND_PITCH),
                             ("`Scenario.authors_code`", {})):
            result = run(Scenario.authors_code(**changes, **extra))
            d = authors_code.deviations(result.trajectory, stored.samples)
            t, v = authors_code.first_yaw_peak(result.trajectory)
            print(f"| {name} | {label} | " + " | ".join(f"{100 * d[n]:.1f} %" for n in authors_code.SIGNALS)
                  + f" | {v:+.4f} at {t:.4f} s | {_outcome(result)} |")


def _switch_row(label, scenario, stored):
    result = run(scenario)
    t, v = authors_code.first_yaw_peak(result.trajectory)
    d = authors_code.deviations(result.trajectory, stored.samples)
    print(f"| {label} | {_outcome(result)} | {v:+.3f} at {t:.3f} s | {_largest(d)} |")


def switches():
    stored = _stored()
    print("| run | outcome (6 s after the kick) | first yaw-rate peak [rad/s] | largest difference from "
          "their run over 0-1 s (signal) |")
    print("|---|---|---|---|")
    print(f"| their stored run | falls at {stored.fall_time_s:.3f} s | "
          f"{authors_code.first_yaw_peak(stored.samples)[1]:+.3f} at "
          f"{authors_code.first_yaw_peak(stored.samples)[0]:.3f} s | - |")
    mode = Scenario.authors_code()
    _switch_row("`Scenario.authors_code()`", mode, stored)
    _switch_row("... with our camber sign (`camber_sign='physical'`)", Scenario.authors_code(camber_sign="physical"),
                stored)
    _switch_row("... with our start (`start='steady'`)", Scenario.authors_code(start="steady", settle=0.5), stored)
    _switch_row("... with our start pitch (`start_pitch='compressed'`)",
                Scenario.authors_code(start_pitch="compressed"), stored)
    _switch_row("... with our slip speed (`slip_speed='wheel_centre'`)",
                Scenario.authors_code(slip_speed="wheel_centre"), stored)
    _switch_row("... with our plate stop (`plate_stop='impulse'`)", Scenario.authors_code(plate_stop="impulse"),
                stored)
    _switch_row("... with the re-solve at the plate stop (`plate_stop='resolve'`)",
                Scenario.authors_code(plate_stop="resolve"), stored)
    _switch_row("... without the kick (`kick_displacement=0`)", Scenario.authors_code(kick_displacement=0.0),
                stored)
    ours = Scenario.thesis(500.0)
    _switch_row("`Scenario.thesis(500)` (this model's assumptions)", ours, stored)
    _switch_row("... with their camber sign", Scenario.thesis(500.0, camber_sign="reversed"), stored)
    _switch_row("... with their start", Scenario.thesis(500.0, start="upright", settle=0.0,
                                                        start_pitch="uncompressed"), stored)
    _switch_row("... with their slip speed", Scenario.thesis(500.0, slip_speed="contact_point"), stored)
    _switch_row("... with their plate stop", Scenario.thesis(500.0, plate_stop="keep_speeds"), stored)
    _switch_row("... with their start, plate stop and slip speed (our camber sign)",
                Scenario.thesis(500.0, start="upright", settle=0.0, start_pitch="uncompressed",
                                plate_stop="keep_speeds", slip_speed="contact_point"), stored)


def geometry():
    """Their contact positions in this model: wheel radius + 2 r_t and crown radius 2 r_t (parameters only)."""
    stored = _stored()
    sc = Scenario.authors_code()
    rear, front, _ = wk.assembly.build_tyres(sc.tyre_spec)
    bike = bicycles.load(sc.bicycle)
    r_t = {"rr": rear.crown_radius, "rf": front.crown_radius}
    text = (bicycles.BICYCLE_DIR / f"{sc.bicycle}.toml").read_text()
    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(folder) / "balanceassist_635N_authors_contact.toml"
        lines = []
        for line in text.splitlines():
            key = line.split("=")[0].strip()
            if key in r_t and line.lstrip().startswith(key):
                value = float(bike.moore[key]) + 2.0 * r_t[key]
                line = f'{key:<4} = {{ value = {value!r}, unit = "m", source = "kickplate_model" }}'
            elif line.startswith("name ="):
                line = f'name = "{path.stem}"'
            lines.append(line)
        path.write_text("\n".join(lines) + "\n")
        tyres = []
        for tyre in (rear, front):
            doubled = copy.copy(tyre)
            doubled.crown_radius = 2.0 * tyre.crown_radius
            tyres.append(doubled)
        moved = bicycles.load(str(path))
        for label, b in (("ours", bike), ("their contact positions", moved)):
            print(f"{label}: steer-axis tilt {b.benchmark['lam']:.6f} rad, trail {b.benchmark['c'] * 1e3:.1f} mm, "
                  f"wheel centres {b.moore['rr']:.4f} / {b.moore['rf']:.4f} m above the ground (less the tyre's "
                  "compression)")
        result = run(wk.assembly.without_tyre_fields(Scenario.authors_code(bicycle=str(path))), tyres=tuple(tyres))
        t, v = authors_code.first_yaw_peak(result.trajectory)
        d = authors_code.deviations(result.trajectory, stored.samples)
        print(f"mode with their contact positions: {_outcome(result)}, first yaw-rate peak {v:+.3f} at {t:.3f} s, "
              "differences over 0-1 s: " + ", ".join(f"{n} {100 * x:.1f} %" for n, x in d.items()))


def _parameters(scenario):
    moore, design, _ = wk.assembly.build_bicycle(scenario.bicycle_spec)
    rear, front, _ = wk.assembly.build_tyres(scenario.tyre_spec)
    gains, _ = wk.assembly.controller_gains(scenario.gains_spec, design)
    return slip.model_parameters(moore, rear, front, slip.ModelOptions(tyre_transient=scenario.tyre_transient,
                                                                   camber_sign=scenario.camber_sign,
                                                                   slip_speed=scenario.slip_speed), gains=gains)


def poles():
    print("| camber sign | about | slowest poles [1/s] |")
    print("|---|---|---|")
    for sign in ("reversed", "physical"):
        params = _parameters(Scenario.authors_code(camber_sign=sign))
        found = steady.find_steady_state(params, 3.0)
        lean = math.degrees(found.steady.x[slip.X["q4"]])
        upright = steady.steady_state(steady.offset_scaled(params, 0.0), 3.0)
        for about, state in ((f"the steady motion ({lean:+.2f} deg lean)", found.steady),
                             ("upright running without the offsets", upright)):
            p = steady.lateral_poles(state.params, state.x)[:3]
            text = ", ".join(f"{z.real:+.3f}" + (f" +- {abs(z.imag):.3f}j" if abs(z.imag) > 1e-9 else "")
                             for z in p if z.imag >= 0.0)
            print(f"| {sign} | {about} | {text} |")


def energy():
    stored = _stored()
    result = run(Scenario.authors_code())
    df = result.trajectory
    w = stored.whole
    theirs = (np.cos(w["q3"]) * w["u1"] + np.sin(w["q3"]) * w["u2"]).to_numpy()
    ours = df["forward_speed"].to_numpy()
    k, j = int(np.argmax(ours)), int(np.argmax(theirs))
    print(f"rear contact speed along the heading: ours 3.000 -> {ours[k]:.3f} m/s at {df['time'].iloc[k]:.2f} s "
          f"(roll {math.degrees(df['roll'].iloc[k]):.1f} deg), {ours[-1]:.3f} m/s at the fall; theirs 3.000 -> "
          f"{theirs[j]:.3f} m/s at {w['time'].iloc[j]:.2f} s (roll {math.degrees(w['roll'].iloc[j]):.1f} deg), "
          f"{theirs[-1]:.3f} m/s at the fall")
    columns = ("kinetic_energy", "potential_energy", "spring_energy", "plate_work", "steer_work",
               "rear_wheel_torque_work", "zero_slip_force_work", "aligning_moment_work", "sliding_dissipation",
               "damper_dissipation", wk.results.BALANCE_COLUMN)
    print("\n| from the kick to | " + " | ".join(f"{c} [J]" for c in columns) + " |")
    print("|---|" + "---|" * len(columns))
    for label, i in ((f"the largest speed ({df['time'].iloc[k]:.2f} s)", k), ("the fall", len(df) - 1)):
        print(f"| {label} | " + " | ".join(f"{df[c].iloc[i] - df[c].iloc[0]:+.2f}" if c != wk.results.BALANCE_COLUMN
                                          else f"{df[c].iloc[i]:.1e}" for c in columns) + " |")


def thesis():
    print("| pressure | first yaw-rate peak [rad/s] | recovery yaw / roll / steer rate [s] | 50 % gains: roll / "
          "steer rate [s] | controller off | `Scenario.authors_code` at this pressure |")
    print("|---|---|---|---|---|---|")
    for pressure in (300.0, 400.0, 500.0):
        full = run(Scenario.thesis(pressure))
        half = run(Scenario.thesis(pressure, gain_scale=0.5))
        off = run(Scenario.thesis(pressure, controller="off"))
        theirs = run(Scenario.authors_code(pressure))

        def times(signals, names):
            return " / ".join(f"{signals[n]['time_s']:.2f}" if signals[n]["time_s"] is not None else "not in 6 s"
                              for n in names)
        half_text = (_outcome(half) if half.summary["fell"]
                     else times(half.summary["recovery"]["signals"], ("roll_rate", "steer_rate")))
        peak = full.summary["metrics"]["yaw_rate_peaks_from_steady_rad_s"][0]
        print(f"| {pressure:g} kPa | {peak:+.3f} | "
              f"{times(full.summary['recovery']['signals'], ('yaw_rate', 'roll_rate', 'steer_rate'))} | "
              f"{half_text} | {_outcome(off)} | {_outcome(theirs)} |")


TABLES = {"agreement": agreement, "held_out": held_out, "switches": switches, "geometry": geometry, "poles": poles, "energy": energy,
          "thesis": thesis}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tables", nargs="*", choices=[*TABLES, []], help="tables to print (default all)")
    args = parser.parse_args(argv)
    for name in args.tables or TABLES:
        print(f"\n## {name}\n")
        TABLES[name]()
    return 0


if __name__ == "__main__":
    sys.exit(main())
