"""Print the controller tables of docs/riders.md (markdown).

For each of the thesis' rear-tyre loads (570, 635, 701 N) the Yeadon rider is
sized with ``riders.for_rear_load`` on ``balanceassist_v1`` and the LQR gains
are designed on the linearised classic model (default 3 m/s, Q = I, R = 1).
Two tables are printed:

1. rider mass, front load, our gains next to thesis Table 8.3/8.4;
2. closed-loop eigenvalues of our model with our gains and with Table 8.4's
   gains (both applied as T7 = -K x), and the open-loop eigenvalues.

Example::

    python scripts/controller_table.py
    python scripts/controller_table.py --speed 4 --R 10
"""
import argparse
import sys

import numpy as np

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.model import classic
from whipple_kick.simulate import control

#: Thesis Table 8.3: rider label, mass [kg] and the front load [N] implied by
#: its 25/75 estimate (33 kg bicycle with 19 kg on the rear wheel, g = 9.81).
THESIS_RIDERS = {570: ("A", 52), 635: ("B", 61), 701: ("C", 70)}
G_THESIS = 9.81


def _thesis_front(rider_kg):
    return ((33.0 - 19.0) + 0.25 * rider_kg) * G_THESIS


def _gains(K, fmt="{:.3f}"):
    return ", ".join(fmt.format(k) for k in K)


def _eigs(ev):
    """Eigenvalues as ``a +- bj`` pairs and reals, sorted by real part."""
    ev = np.asarray(ev)
    ev = ev[np.lexsort((-ev.imag, ev.real))]
    parts = []
    for e in ev:
        if abs(e.imag) < 1e-9:
            parts.append(f"{e.real:.3f}")
        elif e.imag > 0:
            parts.append(f"{e.real:.3f} ± {e.imag:.3f}j")
    return ", ".join(parts)


def rows(bike_name="balanceassist_v1", speed=3.0, R=1.0):
    """Controller data per thesis load.

    Returns
    -------
    list of dict
        Keys ``fz, mass, front, K, poles, thesis_K, thesis_poles, open``.
    """
    bike = wk.bicycles.load(bike_name)
    out = []
    for fz in sorted(control.THESIS_GAINS):
        sol = wk.riders.for_rear_load(bike, fz)
        K, poles = control.lqr_gains(sol.combined, speed=speed, R=R)
        tk = control.thesis_gains(fz)
        thesis_K = np.array([tk[name] for name in control.GAIN_ORDER])
        A, _ = classic.linear_state_space(sol.combined, speed)
        out.append({
            "fz": fz, "mass": sol.rider_mass_kg,
            "front": sol.front_n, "K": K, "poles": poles, "thesis_K": thesis_K,
            "thesis_poles": np.linalg.eigvals(control.closed_loop_matrix(sol.combined, speed, thesis_K)),
            "open": np.linalg.eigvals(A),
        })
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bike", default="balanceassist_v1", help="bicycle set (default balanceassist_v1)")
    p.add_argument("--speed", type=float, default=3.0, help="design speed [m/s] (default 3)")
    p.add_argument("--R", type=float, default=1.0, help="steer-torque weight (default 1; Q = I)")
    args = p.parse_args(argv)
    try:
        data = rows(args.bike, args.speed, args.R)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2

    print(f"LQR at {args.speed:g} m/s, Q = I, R = {args.R:g}; gains [kq4, kq7, ku4, ku7] "
          "in N m/rad and N m s/rad, T7 = -K x.\n")
    print("| rear load F_z [N] | rider mass, ours [kg] | front load, ours [N] | thesis rider [kg] "
          "| thesis front [N] | LQR gains ours [kq4, kq7, ku4, ku7] "
          "| LQR gains thesis Table 8.4 [kq4, kq7, ku4, ku7] |")
    print("|---|---|---|---|---|---|---|")
    for r in data:
        label, kg = THESIS_RIDERS[r["fz"]]
        print(f"| {r['fz']} | {r['mass']:.2f} | {r['front']:.1f} | {kg} ({label}) "
              f"| {_thesis_front(kg):.0f} | {_gains(r['K'])} | {_gains(r['thesis_K'], '{:g}')} |")
    print()
    print("| rear load F_z [N] | open loop [1/s] | closed loop, our gains [1/s] "
          "| closed loop, Table 8.4 gains [1/s] |")
    print("|---|---|---|---|")
    for r in data:
        print(f"| {r['fz']} | {_eigs(r['open'])} | {_eigs(r['poles'])} | {_eigs(r['thesis_poles'])} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
