"""Reproduce the kick-plate figures of the thesis' Chapter 8 as PNGs.

Each figure is one command; the runs use the thesis' presets
(:meth:`whipple_kick.simulate.simulation.Scenario.thesis`: the authors' bicycle+rider
set ``balanceassist_635N``, Table 8.4 gains for 635 N, T03 with the
``chapter8`` coefficients and the ``thesis`` friction mode, LSODA rtol 1e-12)
unless ``--project`` asks for the project's defaults (balanceassist_v1 +
Yeadon rider for 635 N, our LQR, Table 7.9 tyre fit, measured friction).

    python scripts/thesis_figures.py fig8.4          # tyre curves (scripts/plot_tyres.py)
    python scripts/thesis_figures.py fig8.6          # 300/400/500 kPa, controller on
    python scripts/thesis_figures.py fig8.7          # 400 kPa: controller on / 50 % / off
    python scripts/thesis_figures.py fig8.8          # controller off, 300/400/500 kPa
    python scripts/thesis_figures.py fig8.9          # 400 kPa: original vs low inertia
    python scripts/thesis_figures.py all --out-dir figures
"""
import argparse
import pathlib
import sys
import time

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.library import thesis
from whipple_kick.simulate.simulation import Scenario, run

HERE = pathlib.Path(__file__).resolve().parent
PRESSURES = thesis.PRESSURES_KPA


def _scenario(args, **changes):
    if args.project:
        base = dict(fz_n=635.0, rtol=args.rtol)
        if changes.get("controller") == "thesis":
            changes["thesis_load_n"] = 635.0
        base.update(changes)
        return Scenario(**base)
    return Scenario.thesis(**{"rtol": args.rtol, **changes})


def run_line(s):
    """How a run ended and when it recovered, from its summary ``s``, for the progress lines."""
    outcome = f"fell at {s['fall_time_s']:.3f} s ({s['fall_reason']})" if s["fell"] else "no fall"
    time_s = s["recovery"]["time_s"]
    recovery = "not recovered within the run" if time_s is None else f"{time_s:.3f} s"
    return f"{outcome}; recovery (yaw, roll, steer rates within 5 %) {recovery}"


def _figure(args, name, runs, title):
    path = pathlib.Path(args.out_dir) / f"{name}.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    results = []
    for label, scenario in runs:
        t = time.perf_counter()
        result = run(scenario)
        print(f"  {name}: {label}: {run_line(result.summary)}; {time.perf_counter() - t:.2f} s", file=sys.stderr)
        results.append((label, result))
    wk.plotting.response_figure(results, path, title=title, time_range=tuple(args.time_range),
                                kick=wk.plotting.kick_band(results[0][1]))
    print(path)


def fig8_4(args):
    sys.path.insert(0, str(HERE))
    import plot_tyres
    path = pathlib.Path(args.out_dir) / "fig8.4.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    plot_tyres.main([str(path)])   # prints the path itself


def fig8_6(args):
    runs = [(f"{p:g} kPa", _scenario(args, pressure_kpa=p)) for p in PRESSURES]
    _figure(args, "fig8.6", runs, "Figure 8.6: controller on, 635 N, three pressures")


def fig8_7(args):
    runs = [("controller on", _scenario(args, pressure_kpa=400.0)),
            ("gains scaled by 0.5", _scenario(args, pressure_kpa=400.0, gain_scale=0.5)),
            ("controller off", _scenario(args, pressure_kpa=400.0, controller="off", thesis_load_n=None))]
    _figure(args, "fig8.7", runs, "Figure 8.7: 400 kPa, 635 N; rider gains as designed, scaled by 0.5, and off")


def fig8_8(args):
    runs = [(f"{p:g} kPa", _scenario(args, pressure_kpa=p, controller="off", thesis_load_n=None))
            for p in PRESSURES]
    _figure(args, "fig8.8", runs, "Figure 8.8: controller off, 635 N, three pressures")


def fig8_9(args):
    runs = [("original", _scenario(args, pressure_kpa=400.0)),
            ("low inertia", _scenario(args, pressure_kpa=400.0, low_inertia=True))]
    _figure(args, "fig8.9", runs, "Figure 8.9: 400 kPa, 635 N, controller on; rear frame -50 % inertia and CoM height")


FIGURES = {"fig8.4": fig8_4, "fig8.6": fig8_6, "fig8.7": fig8_7, "fig8.8": fig8_8, "fig8.9": fig8_9}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    p.add_argument("figure", choices=[*FIGURES, "all"], help="figure to draw")
    p.add_argument("--out-dir", default="figures", help="folder for the PNGs (default ./figures)")
    p.add_argument("--rtol", type=float, default=1e-12, help="LSODA relative tolerance (default 1e-12, as the thesis)")
    p.add_argument("--time-range", type=float, nargs=2, default=(-0.5, 4.0), metavar=("S", "S"),
                   help="time axis limits in s from the kick start (default -0.5 4)")
    p.add_argument("--project", action="store_true",
                   help="use the project's defaults instead of the thesis' presets")
    args = p.parse_args(argv)
    try:
        for name in (FIGURES if args.figure == "all" else [args.figure]):
            FIGURES[name](args)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
