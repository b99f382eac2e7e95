"""Plot tyre lateral force and aligning moment against slip angle.

Top row: like the thesis' Figure 8.4 (T03 at 500 kPa, Chapter 8 coefficients,
Fz 500/600/700 N, camber 0 and +-5 deg), extended to +-40 deg of slip, where
the kick takes the rear tyre. Middle row: the same tyre at one load for
several pressures (measured ones solid, interpolated dashed). Bottom row:
the contact-patch transient's relaxation length, sigma0 * max(g_sec, G_MIN),
with g_sec the secant ratio of the pure-slip curve (whipple_kick.model.transient).

The shaded band is the slip range the fits were measured over: up to 6 deg
("> |6| degrees, the maximum value tested in this study", thesis Section
7.4.1.1); beyond it the curves are the fits' extrapolation.

Everything is drawn in the MODEL convention (y right, z down): a positive slip
(contact sliding right) gives a negative force. The thesis' Figure 8.4 uses
the formula's convention, so its curves are these mirrored (F -> -F, M -> -M,
camber -> -camber).

Example::

    python scripts/plot_tyres.py tyres.png
    python scripts/plot_tyres.py t04.png --tyre T04 --coefficient-set table7_9 \\
        --pressure 400 --missing-moment zero
"""
import argparse
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import whipple_kick as wk
from whipple_kick.errors import InputError


def _parser():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Angles in degrees, loads in N, pressures in kPa; "
                                       "forces and moments in the model convention.")
    p.add_argument("output", help="PNG file to write")
    p.add_argument("--tyre", default="T03", help="tyre name (default T03)")
    p.add_argument("--coefficient-set", default="chapter8",
                   help="coefficient set (default chapter8, as the thesis' Figure 8.4)")
    p.add_argument("--pressure", type=float, default=500.0,
                   help="pressure of the top row in kPa (default 500)")
    p.add_argument("--loads", type=float, nargs="+", default=[500.0, 600.0, 700.0],
                   help="normal loads of the top row in N (default 500 600 700)")
    p.add_argument("--cambers", type=float, nargs="+", default=[-5.0, 0.0, 5.0],
                   help="camber angles of the top row in deg (default -5 0 5)")
    p.add_argument("--pressures", type=float, nargs="+", default=[300, 350, 400, 450, 500],
                   help="pressures of the bottom row in kPa (default 300 350 400 450 500)")
    p.add_argument("--compare-load", type=float, default=600.0,
                   help="normal load of the bottom row in N (default 600)")
    p.add_argument("--max-slip", type=float, default=40.0, help="slip range +- in deg (default 40)")
    p.add_argument("--friction", choices=wk.tyres.FRICTION_MODES, default="none",
                   help="friction mode (default none)")
    p.add_argument("--missing-moment", choices=wk.tyres.MISSING_MOMENT_MODES, default="error",
                   help="what to draw for a tyre without M_z data (default error)")
    return p


def _load(args, pressure):
    return wk.tyres.load(args.tyre, pressure, coefficient_set=args.coefficient_set,
                         friction=args.friction, missing_moment=args.missing_moment)


#: Largest slip angle of the VeTyT measurements the fits come from [deg] (thesis Section 7.4.1.1).
MEASURED_SLIP_DEG = 6.0


def plot(args):
    """Draw the figure described by the parsed ``args`` and save it."""
    slip_deg = np.linspace(-args.max_slip, args.max_slip, 801)
    slip = np.radians(slip_deg)
    fig, axes = plt.subplots(3, 2, figsize=(11, 12), sharex=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    styles = ["--", "-", ":", "-.", (0, (5, 1, 1, 1))]

    tyre = _load(args, args.pressure)
    for i, fz in enumerate(args.loads):
        for j, camber in enumerate(args.cambers):
            kw = dict(color=colours[i % len(colours)], ls=styles[j % len(styles)],
                      label=f"Fz {fz:g} N, camber {camber:+g} deg")
            axes[0, 0].plot(slip_deg, tyre.lateral_force(slip, np.radians(camber), fz), **kw)
            axes[0, 1].plot(slip_deg, tyre.aligning_moment(slip, np.radians(camber), fz), **kw)
    top = f"{args.tyre}, {args.pressure:g} kPa, set {args.coefficient_set}, friction {args.friction}"
    axes[0, 0].set_title(f"Lateral force: {top}", fontsize=9)
    axes[0, 1].set_title(f"Aligning moment: {top}", fontsize=9)

    for i, pressure in enumerate(args.pressures):
        t = _load(args, pressure)
        measured = pressure in t.measured_pressures
        kw = dict(color=colours[i % len(colours)], ls="-" if measured else "--",
                  label=f"{pressure:g} kPa" + ("" if measured else " (interpolated)"))
        axes[1, 0].plot(slip_deg, t.lateral_force(slip, 0.0, args.compare_load), **kw)
        axes[1, 1].plot(slip_deg, t.aligning_moment(slip, 0.0, args.compare_load), **kw)
    bottom = f"{args.tyre}, Fz {args.compare_load:g} N, camber 0, set {args.coefficient_set}"
    axes[1, 0].set_title(f"Lateral force by pressure: {bottom}", fontsize=9)
    axes[1, 1].set_title(f"Aligning moment by pressure: {bottom}", fontsize=9)

    for i, fz in enumerate(args.loads):
        sigma = tyre.relaxation_length * np.maximum(tyre.secant_ratio(slip, fz), wk.transient.G_MIN)
        axes[2, 0].plot(slip_deg, sigma, color=colours[i % len(colours)], label=f"Fz {fz:g} N")
    axes[2, 0].set_title(f"Contact-patch relaxation length: {top}", fontsize=9)
    for i, pressure in enumerate(args.pressures):
        t = _load(args, pressure)
        measured = pressure in t.measured_pressures
        axes[2, 1].plot(slip_deg, t.secant_ratio(slip, args.compare_load), color=colours[i % len(colours)],
                        ls="-" if measured else "--", label=f"{pressure:g} kPa" + ("" if measured else " (interpolated)"))
    axes[2, 1].axhline(wk.transient.G_MIN, color="k", lw=0.8, ls=":", label=f"floor G_MIN = {wk.transient.G_MIN:g}")
    axes[2, 1].set_title(f"Secant ratio F/(C0 slip): {args.tyre}, Fz {args.compare_load:g} N, set {args.coefficient_set}",
                         fontsize=9)

    for ax in axes.flat:
        ax.axvspan(-MEASURED_SLIP_DEG, MEASURED_SLIP_DEG, color="0.9", zorder=0,
                   label=f"measured slip range (+-{MEASURED_SLIP_DEG:g} deg)")
        ax.axhline(0, color="0.6", lw=0.6)
        ax.axvline(0, color="0.6", lw=0.6)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes[:2, 0]:
        ax.set_ylabel("F_y [N] (+ = right)")
    for ax in axes[:2, 1]:
        ax.set_ylabel("M_z [N m] (+ = about z down)")
    axes[2, 0].set_ylabel("sigma [m]")
    axes[2, 1].set_ylabel("g_sec [-]")
    for ax in axes[2]:
        ax.set_xlabel("slip angle [deg] (+ = contact sliding right)")
    fig.suptitle("Magic Formula tyre model, model convention (Moore axes: x forward, y right, z down)",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(args.output, dpi=120)
    plt.close(fig)


def main(argv=None):
    args = _parser().parse_args(argv)
    try:
        plot(args)
    except InputError as exc:
        print(f"plot_tyres: {exc}", file=sys.stderr)
        return 2
    print(args.output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
