"""The pressure x load table of stability (the thesis' nine cases) and its figure."""
import math
import pathlib

import numpy as np
import pandas as pd

from whipple_kick.library import thesis
from whipple_kick.simulate.scenario import Scenario

from ._constants import DEFAULT_SPEEDS
from .report import range_text
from .sweep import analyse, check_speeds, parse_speeds

# ------------------------------------------------------------------ pressure and load

#: The thesis' kick-plate grid: pressures [kPa] and static rear loads [N] (:mod:`whipple_kick.library.thesis`).
THESIS_PRESSURES_KPA = thesis.PRESSURES_KPA
THESIS_LOADS_N = thesis.LOADS_N


def _at(table, speed, mode):
    """(eigenvalue with Im >= 0 named ``mode`` at ``speed`` with the largest real part, or None)."""
    sel = table[np.isclose(table["speed_m_s"], speed) & (table["mode"] == mode) & (table["imag_1_s"] >= 0)]
    if sel.empty:
        return None
    r = sel.loc[sel["real_1_s"].idxmax()]
    return complex(r["real_1_s"], r["imag_1_s"])


def _mode_columns(prefix, lam):
    if lam is None:
        return {f"{prefix}_real_1_s": None, f"{prefix}_frequency_hz": None, f"{prefix}_damping_ratio": None}
    return {f"{prefix}_real_1_s": lam.real, f"{prefix}_frequency_hz": abs(lam.imag) / (2 * math.pi),
            f"{prefix}_damping_ratio": -lam.real / abs(lam)}


def case_row(result, at_speed=3.0):
    """One row of :func:`pressure_load_table`: speeds, ranges and modes at ``at_speed`` of one analysis.

    Columns: pressure and load; the slip and no-slip weave and capsize
    speeds and the self-stable range (open loop); the stable speed range
    with the rider (closed loop); at ``at_speed`` the weave (open and closed
    loop) and the wobble (closed loop) as real part, frequency and damping
    ratio, and the closed loop's slowest eigenvalue (what a disturbance
    decays with); the wobble's least damping over the sweep.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import analyse, case_row, parse_speeds
    >>> round(case_row(analyse(Scenario(symmetric_tyres=True), parse_speeds("2:6:0.1")))["weave_speed_m_s"], 2)
    3.82
    """
    sc, s, table = result.scenario, result.summary, result.eigenvalues
    speed = float(result.speeds[np.argmin(np.abs(result.speeds - at_speed))])
    rear, _ = sc.pressures
    row = {"pressure_kpa": rear, "fz_n": sc.fz_n, "at_speed_m_s": speed}
    first = lambda ranges: (ranges[0]["from_m_s"], ranges[0]["to_m_s"]) if ranges else (None, None)
    for model, tag in (("slip", ""), ("no-slip", "noslip_")):
        info = s[model]["open"]
        row[f"{tag}weave_speed_m_s"] = info["weave_speed_m_s"]
        row[f"{tag}capsize_speed_m_s"] = info["capsize_speed_m_s"]
        row[f"{tag}self_stable_from_m_s"], row[f"{tag}self_stable_to_m_s"] = first(info["stable_speed_ranges"])
    slip_table = table[table["model"] == "slip"]
    open_t, closed_t = slip_table[slip_table["loop"] == "open"], slip_table[slip_table["loop"] == "closed"]
    row.update(_mode_columns("open_weave", _at(open_t, speed, "weave")))
    if "closed" in s["slip"]:
        ranges = s["slip"]["closed"]["stable_speed_ranges"]
        row["closed_stable_ranges"] = "; ".join(range_text(r) for r in ranges) or "none"
        row.update(_mode_columns("closed_weave", _at(closed_t, speed, "weave")))
        row.update(_mode_columns("closed_wobble", _at(closed_t, speed, "wobble")))
        here = closed_t[np.isclose(closed_t["speed_m_s"], speed)]
        slowest = here.loc[here["real_1_s"].idxmax()]
        row["closed_slowest_real_1_s"] = float(slowest["real_1_s"])
        row["closed_slowest_mode"] = slowest["mode"]
    loop = "closed" if "closed" in s["slip"] else "open"
    wob = s["slip"][loop]["wobble"]
    row["wobble_least_damping_ratio"] = wob["least_damped"]["damping_ratio"] if wob["exists"] else None
    row["wobble_least_damped_at_m_s"] = wob["least_damped"]["speed_m_s"] if wob["exists"] else None
    return row


def pressure_load_table(pressures=THESIS_PRESSURES_KPA, loads=THESIS_LOADS_N, *, base=None, speeds=None,
                        at_speed=3.0):
    """Weave, wobble and stable speed ranges over pressures x rear loads (:func:`case_row` per case).

    Parameters
    ----------
    pressures : sequence of float
        Inflation pressures of both tyres [kPa] (default the thesis' 300, 400, 500).
    loads : sequence of float
        Static rear-tyre loads [N] the rider is sized for (default 570, 635, 701).
    base : whipple_kick.simulate.scenario.Scenario, optional
        Everything else (default: offsets removed, the default rider designed at each speed).
    speeds : array_like, optional
        Sweep speeds [m/s] (default :data:`DEFAULT_SPEEDS`).
    at_speed : float
        Speed [m/s] of the weave and wobble columns (default 3, the kick-plate runs').

    Returns
    -------
    pandas.DataFrame
        One row per case, loads outer, pressures inner.

    Example
    -------
    Skipped as a doctest: one full speed sweep (0.5-10 m/s every 0.05 m/s) per case,
    several seconds each (``scripts/stability_study.py`` runs the whole table).

    >>> table = pressure_load_table(pressures=(400.0,), loads=(635.0,))   # doctest: +SKIP
    >>> table[["pressure_kpa", "weave_speed_m_s", "capsize_speed_m_s"]]   # doctest: +SKIP
    """
    base = Scenario(symmetric_tyres=True) if base is None else base
    speeds = parse_speeds("{}:{}:{}".format(*DEFAULT_SPEEDS)) if speeds is None else check_speeds(speeds)
    rows = []
    for load in loads:
        for pressure in pressures:
            sc = base.with_changes(pressure_kpa=float(pressure), fz_n=float(load),
                                         pressure_front_kpa=None, pressure_rear_kpa=None)
            rows.append(case_row(analyse(sc, speeds), at_speed))
    return pd.DataFrame(rows)



def pressure_load_figure(table, path):
    """Figure of :func:`pressure_load_table`: against pressure, one line per rear load.

    Panels: the open-loop weave and capsize speeds (the no-slip model's as
    faint horizontal lines); the closed loop's weave damping ratio and
    decay rate at the table's speed; the wobble's frequency and damping
    ratio there.

    Returns
    -------
    pathlib.Path

    Example
    -------
    Skipped as a doctest: the whole pressure-load table (a minute or more) and a PNG
    written into the current folder.

    >>> pressure_load_figure(pressure_load_table(), "stability_pressure_load.png")   # doctest: +SKIP
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(14, 4.4))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 3)
    rate_axis, wobble_damping_axis = axes[1].twinx(), axes[2].twinx()
    # One colour per load, in order (the palette's cycle: any number of loads).
    palette = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")
    colours = {fz: palette[k % len(palette)] for k, fz in enumerate(sorted(set(table["fz_n"])))}
    at = float(table["at_speed_m_s"].iloc[0])
    for load, g in table.groupby("fz_n"):
        c, p = colours[load], g["pressure_kpa"]
        axes[0].plot(p, g["weave_speed_m_s"], "o-", color=c, label=f"{load:g} N: weave")
        axes[0].plot(p, g["capsize_speed_m_s"], "s--", color=c, label=f"{load:g} N: capsize")
        axes[0].axhline(g["noslip_weave_speed_m_s"].iloc[0], color=c, lw=0.8, alpha=0.4)
        axes[0].axhline(g["noslip_capsize_speed_m_s"].iloc[0], color=c, lw=0.8, ls="--", alpha=0.4)
        axes[1].plot(p, g["closed_weave_damping_ratio"], "o-", color=c)
        rate_axis.plot(p, -g["closed_slowest_real_1_s"], "s:", color=c)
        axes[2].plot(p, g["closed_wobble_frequency_hz"], "o-", color=c)
        wobble_damping_axis.plot(p, g["closed_wobble_damping_ratio"], "s:", color=c)
    axes[0].set_ylabel("speed [m/s]")
    axes[0].set_title("open loop: weave (o-) and capsize (s--) speeds;\nfaint: no-slip model", fontsize=10)
    axes[1].set_ylabel("weave damping ratio (o-)")
    rate_axis.set_ylabel("slowest decay rate [1/s] (s:)")
    axes[1].set_title(f"closed loop at {at:g} m/s: weave", fontsize=10)
    axes[2].set_ylabel("wobble frequency [Hz] (o-)")
    wobble_damping_axis.set_ylabel("wobble damping ratio (s:)")
    axes[2].set_title(f"closed loop at {at:g} m/s: wobble", fontsize=10)
    for ax in axes:
        ax.set_xlabel("tyre pressure [kPa]")
        ax.grid(alpha=0.3)
        ax.set_xticks(sorted(set(table["pressure_kpa"])))
    axes[0].legend(fontsize=7, ncol=1, loc="best")
    fig.subplots_adjust(left=0.05, right=0.93, bottom=0.13, top=0.86, wspace=0.6)
    path = pathlib.Path(path)
    fig.savefig(path, dpi=110)
    return path
