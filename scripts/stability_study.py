"""What the measured tyres change in the bicycle's linear stability, and why (docs/stability.md).

Usage: ``python scripts/stability_study.py WHAT [--out DIR]``, WHAT one of

* ``table``: weave and capsize speeds, self-stable range, closed-loop weave and
  wobble at 3 m/s over 300/400/500 kPa x 570/635/701 N
  (``stability.pressure_load_table``), with the figure
  ``stability_pressure_load.png`` in ``--out`` (about 20 s);
* ``coefficients``: the tyres' small-slip coefficients at the static loads
  per pressure (cornering and camber stiffness per unit load, pneumatic
  trail, twisting torque);
* ``properties``: 400 kPa, 635 N, no rider: one tyre property changed at a
  time (camber thrust, aligning moment and its camber part, relaxation
  length, crown radius, linear and near-rigid tyres): which one makes the
  capsize mode unstable (about 15 s);
* ``sensitivity``: the relaxation length (an estimate, 0.175 m, not measured
  for T03), the tyre transient form and the zero-slip offsets;
* ``consistency``: growth rates and frequencies of the nonlinear model's
  free responses against the eigenvalues;
* ``recoveries``: the nine kick-plate runs (the default model, our LQR rider
  at 3 m/s) against the linear closed loop at 3 m/s, ranked by pressure;
* ``figure``: the default case's stability.png into ``--out``;
* ``hands``: the wobble (or the arms' steer mode) with hands off and on the
  bar, 2-8 m/s, open loop and with the LQR rider designed on the model
  simulated, and the leaning rider's lean mode; ``hands.csv`` and
  ``hands.png`` in ``--out`` (about 30 s; ``--arm-stiffness``,
  ``--arm-damping``: not published values);
* ``all``.

Every table is printed as Markdown. Symmetric tyres (zero-slip offsets
removed) unless a row says otherwise: the linear analysis is of straight
running.
"""
import argparse
import math
import pathlib

import numpy as np

import whipple_kick as wk
from whipple_kick.library import tyres
from whipple_kick.simulate import simulation
from whipple_kick.simulate.simulation import Scenario
from whipple_kick.studies import stability
from whipple_kick.studies.stability import modes as stability_modes
from whipple_kick.studies.stability import pressure_load

BASE = Scenario(symmetric_tyres=True)
STUDY_SPEEDS = stability.parse_speeds("2:8:0.05")
#: Magic-Formula coefficients that carry the camber: F_y a5 (|camber| in BCD), a8 (Sh), a11 (Sv);
#: M_z c6 (BCD), c10 (E), c11 (Sh), c14 and c15 (Sv) (docs/tyres.md, Pacejka 1989 form).
FY_CAMBER_SHIFTS = (8, 11)
MZ_CAMBER_TERMS = (6, 10, 11, 14, 15)


def _speed(value):
    return "none" if value is None else f"{value:.2f}"


class ModifiedTyre:
    """A loaded tyre with some properties changed; study only (the slip model reads these attributes).

    Parameters
    ----------
    tyre : whipple_kick.library.tyres.Tyre
    camber_scale : float
        Multiplies the camber shifts of F_y (a8, a11): the camber stiffness scales with it.
    moment : {"on", "off", "no_camber"}
        M_z as fitted, zero, or without its camber terms (the twisting torque).
    relaxation_scale : float
        Multiplies the relaxation length.
    crown_radius : float, optional
        Replaces the toroidal crown radius [m].
    """

    def __init__(self, tyre, camber_scale=1.0, moment="on", relaxation_scale=1.0, crown_radius=None):
        self._tyre, self._camber, self._moment = tyre, camber_scale, moment
        self._relaxation, self._crown = relaxation_scale, crown_radius

    def __getattr__(self, name):
        return getattr(self._tyre, name)

    @property
    def relaxation_length(self):
        return self._tyre.relaxation_length * self._relaxation

    @property
    def crown_radius(self):
        return self._tyre.crown_radius if self._crown is None else self._crown

    @property
    def blend(self):
        out = []
        for weight, fy, mz in self._tyre.blend:
            fy, mz = np.array(fy, dtype=float), np.array(mz, dtype=float)
            fy[list(FY_CAMBER_SHIFTS)] *= self._camber
            if self._moment == "off":
                mz = tyres.ZERO_MOMENT_COEFFICIENTS.copy()
            elif self._moment == "no_camber":
                mz[list(MZ_CAMBER_TERMS)] = 0.0
            out.append((weight, fy, mz))
        return out


def _loads(scenario):
    _, _, info = wk.assembly.build_bicycle(scenario.bicycle_spec)
    return info["static_load_rear_n"], info["static_load_front_n"]


def small_slip_coefficients(tyre, fz):
    """(C_alpha/Fz [1/rad], C_gamma/Fz [1/rad], pneumatic trail [m], dMz/dgamma [N m/rad]) at zero slip.

    Model convention (docs/tyres.md): F_y = -C_alpha slip + C_gamma camber, and
    M_z = C_alpha t slip (aligning: it turns the wheel toward its velocity), so
    the pneumatic trail t is positive when the force acts behind the contact.
    dMz/dgamma > 0 turns the heading toward the lean (camber to the right turns it right).
    """
    t, h = tyre.without_offsets(), 1e-5
    c_alpha = (t.lateral_force(-h, 0.0, fz) - t.lateral_force(h, 0.0, fz)) / (2 * h)
    c_gamma = (t.lateral_force(0.0, h, fz) - t.lateral_force(0.0, -h, fz)) / (2 * h)
    m_alpha = (t.aligning_moment(h, 0.0, fz) - t.aligning_moment(-h, 0.0, fz)) / (2 * h)
    m_gamma = (t.aligning_moment(0.0, h, fz) - t.aligning_moment(0.0, -h, fz)) / (2 * h)
    return float(c_alpha / fz), float(c_gamma / fz), float(m_alpha / c_alpha), float(m_gamma)


# ----------------------------------------------------------------------------- table

def table(out):
    rows = stability.pressure_load_table()
    print("Pressure and load (T03, zero-slip offsets removed, our LQR rider designed at each speed)\n")
    print("| load [N] | pressure [kPa] | weave speed [m/s] | capsize speed [m/s] | self-stable [m/s] | "
          "no-slip: weave / capsize [m/s] | with rider: stable [m/s] | closed-loop weave at 3 m/s: "
          "real [1/s], f [Hz], damping | wobble at 3 m/s: f [Hz], damping | wobble's least damping (speed) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows.itertuples():
        stable = ("none" if r.self_stable_from_m_s is None or np.isnan(r.self_stable_from_m_s)
                  else f"{r.self_stable_from_m_s:.2f}-{r.self_stable_to_m_s:.2f}")
        print(f"| {r.fz_n:g} | {r.pressure_kpa:g} | {_speed(r.weave_speed_m_s)} | {_speed(r.capsize_speed_m_s)} | "
              f"{stable} | {r.noslip_weave_speed_m_s:.2f} / {r.noslip_capsize_speed_m_s:.2f} | "
              f"{r.closed_stable_ranges} | {r.closed_weave_real_1_s:+.2f}, {r.closed_weave_frequency_hz:.2f}, "
              f"{r.closed_weave_damping_ratio:.2f} | {r.closed_wobble_frequency_hz:.2f}, "
              f"{r.closed_wobble_damping_ratio:.3f} | {r.wobble_least_damping_ratio:+.3f} "
              f"({r.wobble_least_damped_at_m_s:g} m/s) |")
    print()
    if out is not None:
        path = stability.pressure_load_figure(rows, pathlib.Path(out) / "stability_pressure_load.png")
        print(f"wrote {path}\n")
    return rows


def coefficients():
    print("Small-slip coefficients of T03 (offsets removed) at the static loads of the 635 N rider\n")
    print("| pressure [kPa] | wheel | load [N] | C_alpha/Fz [1/rad] | C_gamma/Fz [1/rad] | pneumatic trail [mm] | "
          "dMz/dgamma [N m/rad] |")
    print("|---|---|---|---|---|---|---|")
    loads = _loads(BASE)
    for p in stability.THESIS_PRESSURES_KPA:
        rear, front, _ = wk.assembly.build_tyres(BASE.with_changes(pressure_kpa=p).tyre_spec)
        for wheel, t, fz in (("rear", rear, loads[0]), ("front", front, loads[1])):
            ca, cg, trail, mg = small_slip_coefficients(t, fz)
            print(f"| {p:g} | {wheel} | {fz:.0f} | {ca:.2f} | {cg:.3f} | {trail * 1e3:.1f} | {mg:+.2f} |")
    print()


# ------------------------------------------------------------------------ properties

def _open_loop_row(label, pair, scenario=BASE, speeds=STUDY_SPEEDS):
    res = stability.analyse(scenario, speeds, loops=("open",), tyres=pair)
    s = res.summary["slip"]["open"]
    t = res.eigenvalues[(res.eigenvalues["model"] == "slip")]
    capsize = lambda v: t[np.isclose(t["speed_m_s"], v) & (t["mode"] == "capsize")]["real_1_s"].max()
    wob = pressure_load._at(t, 3.0, "wobble")
    stable = ", ".join(stability.range_text(r) for r in s["stable_speed_ranges"]) or "none"
    wobble = "none" if wob is None else f"{abs(wob.imag) / (2 * math.pi):.2f} Hz, {-wob.real / abs(wob):.3f}"
    print(f"| {label} | {_speed(s['weave_speed_m_s'])} | {_speed(s['capsize_speed_m_s'])} | {stable} | "
          f"{capsize(5.0):+.3f} | {capsize(8.0):+.3f} | {wobble} |")


def properties(pressure=400.0):
    scenario = BASE.with_changes(pressure_kpa=pressure)
    rear, front, _ = wk.assembly.build_tyres(scenario.tyre_spec)
    loads = _loads(scenario)
    unit_camber = [1.0 / small_slip_coefficients(t, fz)[1] for t, fz in ((rear, loads[0]), (front, loads[1]))]
    both = lambda **kw: (ModifiedTyre(rear, **kw), ModifiedTyre(front, **kw))
    coeff = [t.cornering_stiffness(fz) / fz for t, fz in ((rear, loads[0]), (front, loads[1]))]
    linear = lambda c, sigma, kz: tuple(tyres.linear_tyre(ci, sigma, kz) for ci in c)
    cases = [
        ("T03 as measured", (rear, front)),
        (f"camber thrust x{unit_camber[0]:.2f} / x{unit_camber[1]:.2f}: C_gamma = Fz per rad on both wheels",
         (ModifiedTyre(rear, camber_scale=unit_camber[0]), ModifiedTyre(front, camber_scale=unit_camber[1]))),
        ("camber thrust off", both(camber_scale=0.0)),
        ("M_z off", both(moment="off")),
        ("M_z off, front only", (rear, ModifiedTyre(front, moment="off"))),
        ("M_z off, rear only", (ModifiedTyre(rear, moment="off"), front)),
        ("M_z without its camber terms (no twisting torque)", both(moment="no_camber")),
        ("M_z without its camber terms, front only", (rear, ModifiedTyre(front, moment="no_camber"))),
        ("C_gamma = Fz per rad and M_z off",
         (ModifiedTyre(rear, camber_scale=unit_camber[0], moment="off"),
          ModifiedTyre(front, camber_scale=unit_camber[1], moment="off"))),
        ("crown radius 0 and M_z off", both(crown_radius=0.0, moment="off")),
        ("crown radius 0, C_gamma = Fz per rad and M_z off",
         (ModifiedTyre(rear, camber_scale=unit_camber[0], moment="off", crown_radius=0.0),
          ModifiedTyre(front, camber_scale=unit_camber[1], moment="off", crown_radius=0.0))),
        ("crown radius 0, camber thrust off and M_z off", both(crown_radius=0.0, moment="off", camber_scale=0.0)),
        ("relaxation length x0.5 (0.0875 m)", both(relaxation_scale=0.5)),
        ("relaxation length x2 (0.35 m)", both(relaxation_scale=2.0)),
        ("crown radius 0 (knife-edge contact geometry)", both(crown_radius=0.0)),
        (f"linear tyre, T03's cornering ({coeff[0]:.1f}, {coeff[1]:.1f} /rad), relaxation and vertical stiffness; "
         "no camber thrust, no M_z", linear(coeff, rear.relaxation_length, rear.vertical_stiffness)),
        ("near-rigid linear tyre (1e5 /rad, 1e-5 m, 1e10 N/m): the no-slip limit", linear([1e5, 1e5], 1e-5, 1e10)),
    ]
    print(f"Which tyre property: T03, {pressure:g} kPa, 635 N, no rider control (open loop), offsets removed\n")
    print("| tyres | weave speed [m/s] | capsize speed [m/s] | self-stable [m/s] | capsize eigenvalue at 5 m/s "
          "[1/s] | at 8 m/s [1/s] | wobble at 3 m/s: f, damping ratio |")
    print("|---|---|---|---|---|---|---|")
    for label, pair in cases:
        _open_loop_row(label, pair, scenario)
    print()


def sensitivity():
    """The relaxation length (not measured for T03), the transient form and the offsets, at 400 kPa, 635 N."""
    rear, front, _ = wk.assembly.build_tyres(BASE.tyre_spec)
    print("Sensitivity of the default case (400 kPa, 635 N) to modelling choices nothing validated\n")
    print("| choice | weave speed [m/s] | capsize speed [m/s] | self-stable [m/s] | with rider: stable [m/s] | "
          "closed-loop weave at 3 m/s (real, f, damping) | wobble at 3 m/s (f, damping) |")
    print("|---|---|---|---|---|---|---|")
    cases = [("default: relaxation length 0.175 m, contact_patch, offsets removed", BASE, None),
             ("relaxation length x0.5 (0.0875 m)", BASE,
              (ModifiedTyre(rear, relaxation_scale=0.5), ModifiedTyre(front, relaxation_scale=0.5))),
             ("relaxation length x2 (0.35 m)", BASE,
              (ModifiedTyre(rear, relaxation_scale=2.0), ModifiedTyre(front, relaxation_scale=2.0))),
             ("crown radius x0.5 (5 mm)", BASE,
              (ModifiedTyre(rear, crown_radius=0.5 * rear.crown_radius),
               ModifiedTyre(front, crown_radius=0.5 * front.crown_radius))),
             ("crown radius x2 (20 mm)", BASE,
              (ModifiedTyre(rear, crown_radius=2 * rear.crown_radius),
               ModifiedTyre(front, crown_radius=2 * front.crown_radius))),
             ("force_lag (the thesis' transient)", BASE.with_changes(tyre_transient="force_lag"), None),
             ("measured zero-slip offsets (about the steady turn)", Scenario(), None)]
    for label, sc, pair in cases:
        res = stability.analyse(sc, stability.parse_speeds("0.5:10:0.05"), tyres=pair)
        row = stability.case_row(res)
        s = res.summary["slip"]["open"]
        stable = ", ".join(stability.range_text(r) for r in s["stable_speed_ranges"]) or "none"
        lean = res.summary["steady_motion"]["open"]["largest_lean_rad"]
        note = f" (open-loop steady lean up to {math.degrees(lean):.0f} deg)" if lean > 0.05 else ""
        print(f"| {label}{note} | {_speed(row['weave_speed_m_s'])} | {_speed(row['capsize_speed_m_s'])} | {stable} | "
              f"{row['closed_stable_ranges']} | {row['closed_weave_real_1_s']:+.2f}, "
              f"{row['closed_weave_frequency_hz']:.2f}, {row['closed_weave_damping_ratio']:.2f} | "
              f"{row['closed_wobble_frequency_hz']:.2f}, {row['closed_wobble_damping_ratio']:.3f} |")
    print()


# ------------------------------------------------------------------------ consistency

def consistency():
    """Free responses of the nonlinear model (1e-4 rad along the eigenvector) against the eigenvalues."""
    print("Nonlinear free responses against the eigenvalues (modal amplitude fitted; LSODA rtol 1e-11)\n")
    print("| case | mode | eigenvalue [1/s] | fitted [1/s] | rate error | frequency error |")
    print("|---|---|---|---|---|---|")
    cases = [(BASE, 3.6, "open", "weave", 4.0), (BASE, 6.0, "open", "capsize", 3.0),
             (BASE, 3.0, "closed", "weave", 4.0)]
    cases += [(BASE.with_changes(pressure_kpa=p), 3.0, "closed", "wobble", 1.0)
              for p in stability.THESIS_PRESSURES_KPA]
    cases += [(BASE, 1.0, "open", "wobble", 1.0), (BASE, 3.0, "open", "lateral_rear", 1.0)]
    for sc, v, loop, mode, duration in cases:
        model = stability.linear_model(sc, v, loop)
        lam, vec = np.linalg.eig(model.matrix)
        k = _named_index(model, lam, vec, mode)
        rate = 2000.0 if abs(lam[k].imag) > 20 else 500.0
        t, dev = stability.free_response(model, vec[:, k], 1e-4, duration=duration, rate=rate)
        eta = stability.modal_coordinate(model, k, dev)
        osc = lam[k].imag != 0
        fit = stability.fit_eigenvalue(t, np.column_stack([eta.real, eta.imag]) if osc else eta.real[:, None],
                                       oscillatory=osc)
        f_err = abs(fit.imag - abs(lam[k].imag)) / abs(lam[k].imag) if osc else 0.0
        print(f"| {sc.pressure_kpa:g} kPa, {v:g} m/s, {loop} loop | {mode} | {lam[k].real:+.4f} "
              f"{'+- ' + format(abs(lam[k].imag), '.4f') + 'j' if osc else ''} | {fit.real:+.4f} "
              f"{'+- ' + format(fit.imag, '.4f') + 'j' if osc else ''} | "
              f"{abs(fit.real - lam[k].real) / abs(lam[k].real):.1e} | {f_err:.1e} |")
    print()


def _named_index(model, lam, vec, mode):
    """Index of the eigenvalue (Im >= 0) named ``mode`` with the largest real part."""
    wheelbase = stability_modes._wheelbase(wk.assembly.build_bicycle(BASE.bicycle_spec)[0])
    best = None
    for k in range(lam.size):
        if lam[k].imag < 0:
            continue
        shares, _ = stability.mode_content(model, lam[k], vec[:, k], wheelbase)
        if stability.name_mode(shares, lam[k].imag == 0, abs(lam[k].imag) / (2 * math.pi)) == mode:
            if best is None or lam[k].real > lam[best].real:
                best = k
    if best is None:
        raise LookupError(f"no {mode} mode")
    return best


# ------------------------------------------------------------------------ recoveries

def recoveries(linear_rows=None):
    """The nine kick runs (default model) against the linear closed loop at 3 m/s."""
    linear_rows = stability.pressure_load_table() if linear_rows is None else linear_rows
    print("Kick-plate recoveries (default model: contact_patch, measured offsets, our LQR rider at 3 m/s, "
          "6 s) against the linear closed loop at 3 m/s (offsets removed)\n")
    print("| load [N] | pressure [kPa] | recovery [s] (yaw / roll / steer) | recovery, offsets removed [s] | "
          "slowest linear pole [1/s] | weave damping ratio |")
    print("|---|---|---|---|---|---|")
    ranks = {}
    for r in linear_rows.itertuples():
        times = []
        for symmetric in (False, True):
            res = simulation.run(Scenario(pressure_kpa=r.pressure_kpa, fz_n=r.fz_n, symmetric_tyres=symmetric))
            rec = res.summary["recovery"]
            sig = rec["signals"]
            cell = lambda v: "> run" if v is None else f"{v:.2f}"
            times.append((rec["time_s"], " / ".join(cell(sig[n]["time_s"]) for n in ("yaw_rate", "roll_rate",
                                                                                      "steer_rate"))))
        ranks.setdefault(r.fz_n, []).append((r.pressure_kpa, times[0][0], times[1][0], r.closed_slowest_real_1_s))
        print(f"| {r.fz_n:g} | {r.pressure_kpa:g} | {_speed(times[0][0])} ({times[0][1]}) | {_speed(times[1][0])} | "
              f"{r.closed_slowest_real_1_s:+.3f} | {r.closed_weave_damping_ratio:.2f} |")
    print("\nBest pressure per load: recovery (measured offsets), recovery (offsets removed), fastest linear decay\n")
    print("| load [N] | kick recovery | kick recovery, offsets removed | linear closed loop | thesis experiment "
          "(Table 8.9, last-peak time) |")
    print("|---|---|---|---|---|")
    thesis = {570.0: 300, 635.0: 400, 701.0: 500}
    for load, cases in ranks.items():
        order = lambda key: " < ".join(f"{c[0]:g}" for c in sorted(cases, key=key))
        print(f"| {load:g} | {order(lambda c: math.inf if c[1] is None else c[1])} | "
              f"{order(lambda c: math.inf if c[2] is None else c[2])} | {order(lambda c: c[3])} | "
              f"{thesis.get(load, '-')} kPa |")
    print("\n(' < ' orders from the fastest recovery or decay.)\n")


def figure(out):
    res = stability.analyse(BASE, stability.parse_speeds("0.5:10:0.05"))
    path = stability.figure(res, pathlib.Path(out) / "stability.png", title=res.summary["title"])
    print(f"wrote {path}\n")


# ------------------------------------------------------------------------ hands on and off

HANDS_SPEEDS = stability.parse_speeds("2:8:0.25")


def _mode_at(table, speed, modes):
    """(mode, eigenvalue) of the least damped oscillation (Im > 0) named one of ``modes`` at ``speed``, or None."""
    sel = table[np.isclose(table["speed_m_s"], speed) & table["mode"].isin(modes) & (table["imag_1_s"] > 0)]
    if sel.empty:
        return None
    row = sel.loc[sel["damping_ratio"].idxmin()]
    return row["mode"], complex(row["real_1_s"], row["imag_1_s"])


def hands(out, arm_stiffness=10.0, arm_damping=1.0, speeds=HANDS_SPEEDS):
    """The wobble's frequency and damping with hands off and on, open and closed loop; the lean mode."""
    import pandas as pd
    cases = [("hands off", dict(arms="off")),
             ("hands on", dict(arms="on", arm_stiffness=arm_stiffness, arm_damping=arm_damping)),
             ("leaning, hands off", dict(rider_body="leaning")),
             ("leaning, hands on", dict(rider_body="leaning", arms="on", arm_stiffness=arm_stiffness,
                                        arm_damping=arm_damping))]
    rows = []
    for label, fields in cases:
        for loop in ("open", "closed"):
            sc = BASE.with_changes(controller="off" if loop == "open" else "lqr", lqr_model="simulated", **fields)
            res = stability.analyse(sc, speeds, loops=(loop,))
            t = res.eigenvalues[res.eigenvalues["model"] == "slip"]
            for v in speeds:
                row = {"case": label, "loop": loop, "speed_m_s": float(v)}
                for key, modes in (("wobble", ("wobble", "arm_steer")), ("lean", ("lean",))):
                    hit = _mode_at(t, v, modes)
                    row[f"{key}_mode"] = None if hit is None else hit[0]
                    row[f"{key}_frequency_hz"] = np.nan if hit is None else abs(hit[1].imag) / (2 * math.pi)
                    row[f"{key}_damping_ratio"] = np.nan if hit is None else -hit[1].real / abs(hit[1])
                lean_real = t[np.isclose(t["speed_m_s"], v) & (t["mode"] == "lean")]["real_1_s"]
                row["lean_slowest_real_1_s"] = float(lean_real.max()) if len(lean_real) else np.nan
                row["no_model"] = not np.isclose(t["speed_m_s"], v).any()
                rows.append(row)
    df = pd.DataFrame(rows)
    print(f"Wobble with hands off and on the bar (arms {arm_stiffness:g} N m/rad, {arm_damping:g} N m s/rad: "
          "not published values), T03 400 kPa, offsets removed; closed loop: LQR designed on the model "
          "simulated at each speed ('-': no design stabilises the start)\n")
    print("| speed [m/s] | " + " | ".join(f"{c}, {l}: f [Hz], damping" for c, _ in cases[:2]
                                           for l in ("open", "closed")) + " |")
    print("|---" * 5 + "|")
    cell = lambda r: "-" if r.no_model or np.isnan(r.wobble_frequency_hz) else \
        f"{r.wobble_frequency_hz:.2f}, {r.wobble_damping_ratio:.3f}" + (" (arm steer)" if r.wobble_mode == "arm_steer"
                                                                        else "")
    for v in speeds[::4]:
        sel = df[np.isclose(df["speed_m_s"], v)]
        cells = [cell(next(sel[(sel["case"] == c) & (sel["loop"] == l)].itertuples()))
                 for c, _ in cases[:2] for l in ("open", "closed")]
        print(f"| {v:g} | " + " | ".join(cells) + " |")
    print("\nLean mode of the leaning rider (hip 128 N m/rad, 50 N m s/rad): oscillation if any, else the "
          "slowest real root\n")
    print("| speed [m/s] | " + " | ".join(f"{c}, {l}" for c, _ in cases[2:] for l in ("open", "closed")) + " |")
    print("|---" * 5 + "|")
    lean = lambda r: "-" if r.no_model else (f"{r.lean_frequency_hz:.2f} Hz, {r.lean_damping_ratio:.3f}"
                                             if not np.isnan(r.lean_frequency_hz) else
                                             f"{r.lean_slowest_real_1_s:+.3f} 1/s" if not np.isnan(r.lean_slowest_real_1_s)
                                             else "not named")
    for v in speeds[::4]:
        sel = df[np.isclose(df["speed_m_s"], v)]
        cells = [lean(next(sel[(sel["case"] == c) & (sel["loop"] == l)].itertuples()))
                 for c, _ in cases[2:] for l in ("open", "closed")]
        print(f"| {v:g} | " + " | ".join(cells) + " |")
    print()
    if out is not None:
        out = pathlib.Path(out)
        out.mkdir(parents=True, exist_ok=True)
        wk.fileio.write_csv(df, out / "hands.csv")
        _hands_figure(df, cases, out / "hands.png", arm_stiffness, arm_damping)
        print(f"wrote {out / 'hands.csv'}, {out / 'hands.png'}\n")
    return df


def _hands_figure(df, cases, path, arm_stiffness, arm_damping):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(12, 4.2))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2)
    for (label, _), colour in zip(cases, ("tab:blue", "tab:red", "tab:green", "tab:purple"), strict=True):
        for loop, ls in (("open", "-"), ("closed", "--")):
            g = df[(df["case"] == label) & (df["loop"] == loop)]
            axes[0].plot(g["speed_m_s"], g["wobble_frequency_hz"], color=colour, ls=ls, label=f"{label}, {loop}")
            axes[1].plot(g["speed_m_s"], g["wobble_damping_ratio"], color=colour, ls=ls)
    axes[0].set_ylabel("wobble (or arm steer) frequency [Hz]")
    axes[1].set_ylabel("damping ratio")
    for ax in axes:
        ax.set_xlabel("speed [m/s]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"Wobble, hands off and on (arms {arm_stiffness:g} N m/rad, {arm_damping:g} N m s/rad; "
                 "not published values)", fontsize=10)
    fig.savefig(path, dpi=110)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("table", "coefficients", "properties", "sensitivity", "consistency",
                                         "recoveries", "figure", "hands", "all"))
    parser.add_argument("--out", help="folder for the figures (table, figure)")
    parser.add_argument("--pressure", type=float, nargs="+", default=[400.0],
                        help="pressures [kPa] of the properties table (default 400)")
    parser.add_argument("--arm-stiffness", type=float, default=10.0,
                        help="hands: the arms' stiffness about the steer axis [N m/rad] (default 10; an "
                             "assumption, not a published value)")
    parser.add_argument("--arm-damping", type=float, default=1.0,
                        help="hands: the arms' damping about the steer axis [N m s/rad] (default 1; an "
                             "assumption, not a published value)")
    args = parser.parse_args(argv)
    rows = None
    if args.what in ("coefficients", "all"):
        coefficients()
    if args.what in ("table", "all"):
        rows = table(args.out)
    if args.what in ("properties", "all"):
        for pressure in args.pressure:
            properties(pressure)
    if args.what in ("sensitivity", "all"):
        sensitivity()
    if args.what in ("consistency", "all"):
        consistency()
    if args.what in ("recoveries", "all"):
        recoveries(rows)
    if args.what in ("figure", "all") and args.out:
        figure(args.out)
    if args.what in ("hands", "all"):
        hands(args.out, args.arm_stiffness, args.arm_damping)


if __name__ == "__main__":
    main()
