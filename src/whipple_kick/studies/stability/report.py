"""The figure, the printed lines and the files of a stability analysis."""
import json
import math
import pathlib

import numpy as np

from whipple_kick import fileio
from whipple_kick.model import parts
from whipple_kick.simulate import results

from ._constants import LOOPS, MODES, TURN_NOTE_DEG

# ------------------------------------------------------------------ the figure

#: Colour of each mode in stability.png.
MODE_COLOURS = {"weave": "tab:blue", "capsize": "tab:red", "caster": "tab:green", "wobble": "tab:purple",
                "lateral_rear": "tab:orange", "lateral_front": "tab:brown", "relaxation_rear": "tab:olive",
                "relaxation_front": "tab:cyan", "vertical": "tab:gray", "arm_steer": "tab:pink",
                "lean": "gold", "reflex_delay": "black"}
#: Real-part range [1/s] of the left ("slow modes") panels, as Meijaard et al. (2007) Fig. 3.
SLOW_RANGE = (-10.0, 10.0)


def _branch_lines(table):
    """Per mode: (speeds, real parts, |imag| parts), its branches joined with NaN gaps (Im >= 0 only).

    One line per mode and part keeps the figure to a few dozen artists
    (drawing some 600 separate lines cost 0.3 s of the command's 5 s).
    """
    speeds_all = np.unique(np.round(table["speed_m_s"].to_numpy(), 9))
    lines = {}
    for (_track, mode), g in table.groupby(["track", "mode"], sort=False):
        g = g.sort_values("speed_m_s")
        if (g["imag_1_s"] < 0).all():
            continue   # the conjugate of a drawn pair
        order = np.searchsorted(speeds_all, np.round(g["speed_m_s"].to_numpy(), 9))
        breaks = np.nonzero(np.diff(order) > 1)[0] + 1   # gaps in speed end a branch too
        parts = lines.setdefault(mode, ([], [], []))
        for piece in np.split(np.arange(len(g)), breaks):
            sub = g.iloc[piece]
            for store, values in zip(parts, (sub["speed_m_s"], sub["real_1_s"], np.abs(sub["imag_1_s"])), strict=True):
                store += [*np.asarray(values, dtype=float), np.nan]
    return {mode: tuple(np.array(v) for v in parts) for mode, parts in lines.items()}


def _speed(value):
    return "none" if value is None else f"{value:.2f} m/s"


def range_text(interval):
    """``"a-b"`` [m/s] of a stable speed range, saying where it is cut by the sweep's ends.

    Example
    -------
    >>> range_text({"from_m_s": 0.5, "to_m_s": 4.33, "lower_open": True, "upper_open": False})
    '0.50 (sweep start)-4.33'
    """
    lo = f"{interval['from_m_s']:.2f}" + (" (sweep start)" if interval["lower_open"] else "")
    hi = f"{interval['to_m_s']:.2f}" + (" (sweep end)" if interval["upper_open"] else "")
    return f"{lo}-{hi}" + (" (an end not located: at a sweep speed)" if "note" in interval else "")


def speeds_text(summary, loop):
    """Weave and capsize speeds and stable ranges of one loop, slip and no-slip model, one line each.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import analyse
    >>> result = analyse(Scenario(symmetric_tyres=True), [3.0, 3.5, 4.0, 4.5, 5.0], loops=("open",))
    >>> print(speeds_text(result.summary, "open"))
    slip: weave 3.82 m/s, capsize 3.88 m/s; stable none
    no-slip: weave 3.97 m/s, capsize none; stable 3.97-5.00 (sweep end) m/s
    """
    lines = []
    for model in ("slip", "no-slip"):
        info = summary.get(model, {}).get(loop)
        if info is None:
            continue
        ranges = ", ".join(range_text(r) for r in info["stable_speed_ranges"]) or "none"
        lines.append(f"{model}: weave {_speed(info['weave_speed_m_s'])}, capsize "
                     f"{_speed(info['capsize_speed_m_s'])}; stable {ranges}" + (" m/s" if ranges != "none" else ""))
    return "\n".join(lines)


def figure(result, path, title=None):
    """stability.png: real (solid) and imaginary (dashed) parts against speed, coloured by mode.

    One row per loop; the left panel shows the slow modes (as Meijaard et
    al. 2007, Fig. 3), the right all of them. The no-slip (knife-edge)
    model of the same bicycle and rider is drawn faintly in grey; the slip
    model's weave and capsize speeds are marked and its stable speed ranges
    shaded.

    Parameters
    ----------
    result : Stability
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional

    Returns
    -------
    pathlib.Path

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import analyse
    >>> _ = figure(analyse(Scenario(symmetric_tyres=True), [3.0, 3.5, 4.0, 4.5, 5.0]), "stability.png")
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    df = result.eigenvalues
    loops = [loop for loop in LOOPS if loop in set(df["loop"])]
    # A bare Figure (no pyplot): pyplot's redraw hooks on every artist cost 0.1 s here.
    fig = Figure(figsize=(13, 4.6 * len(loops)))
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(loops), 2, squeeze=False)
    used = set()
    for row, loop in enumerate(loops):
        slip_lines = _branch_lines(df[(df["model"] == "slip") & (df["loop"] == loop)])
        classic_lines = _branch_lines(df[(df["model"] == "no-slip") & (df["loop"] == loop)])
        used |= set(slip_lines)
        for col, ax in enumerate(axes[row]):
            _draw_panel(ax, slip_lines, classic_lines, result, loop, slow=col == 0)
    handles = [Line2D([], [], color=MODE_COLOURS[m], lw=2, label=m.replace("_", " ")) for m in MODES if m in used]
    handles += [Line2D([], [], color="k", lw=1.5, label="real part"),
                Line2D([], [], color="k", lw=1.2, ls="--", label="imaginary part"),
                Line2D([], [], color="0.55", lw=1.0, alpha=0.6, label="no-slip (knife-edge) model")]
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 7), fontsize=9, frameon=False)
    if title:
        fig.suptitle(title, fontsize=11)
    # Fixed margins: tight_layout costs 0.4 s of the command's 5 s budget.
    fig.subplots_adjust(left=0.06, right=0.985, bottom=0.06 + 0.14 / len(loops), top=0.93 if title else 0.96,
                        hspace=0.3, wspace=0.15)
    path = pathlib.Path(path)
    fig.savefig(path, dpi=110)
    return path


def _draw_panel(ax, slip_lines, classic_lines, result, loop, slow):
    """One panel of :func:`figure`: the no-slip model faint, the slip model by mode, speeds and ranges marked."""
    info = result.summary.get("slip", {}).get(loop, {})
    for v, re, im in classic_lines.values():
        ax.plot(v, re, color="0.55", lw=1.0, alpha=0.45, zorder=1)
        ax.plot(v, np.where(im > 0, im, np.nan), color="0.55", lw=1.0, ls="--", alpha=0.45, zorder=1)
    for mode, (v, re, im) in slip_lines.items():
        ax.plot(v, re, color=MODE_COLOURS[mode], lw=1.6, zorder=3)
        ax.plot(v, np.where(im > 0, im, np.nan), color=MODE_COLOURS[mode], lw=1.3, ls="--", zorder=3)
    for rng in info.get("stable_speed_ranges", []):
        ax.axvspan(rng["from_m_s"], rng["to_m_s"], color="tab:green", alpha=0.08, zorder=0)
    for key in ("weave_speed_m_s", "capsize_speed_m_s"):
        if info.get(key) is not None:
            ax.axvline(info[key], color="k", lw=0.8, ls=":", zorder=2)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlim(result.speeds[0], result.speeds[-1])
    ax.set_xlabel("speed [m/s]")
    ax.grid(alpha=0.3)
    if slow:
        ax.text(0.99, 0.98, speeds_text(result.summary, loop), transform=ax.transAxes, fontsize=8,
                va="top", ha="right", bbox={"facecolor": "white", "alpha": 0.85, "edgecolor": "0.8"})
        ax.set_ylim(*SLOW_RANGE)
        ax.set_ylabel("eigenvalue [1/s]")
        ax.set_title(f"{loop} loop: slow modes" + (" (no rider control)" if loop == "open" else " (with the rider)"),
                     fontsize=10)
    else:
        ax.set_title(f"{loop} loop: all modes", fontsize=10)



# ------------------------------------------------------------------ outputs

def describe(scenario, info=None):
    """One line naming the bicycle, rider, tyres, offsets and rider control of a stability analysis.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import analyse
    >>> describe(Scenario(symmetric_tyres=True, controller="off"))
    'T03 400 kPa (zero-slip offsets removed, carcass), balanceassist_v1; no rider control'
    """
    rear, front = scenario.pressures
    p = f"{rear:g}" if rear == front else f"{rear:g}/{front:g} (rear/front)"
    load = f", rear load {info['static_load_rear_n']:.0f} N" if info else ""
    offsets = "zero-slip offsets removed" if scenario.symmetric_tyres else "measured zero-slip offsets"
    if scenario.controller == "lqr":
        rider = ("LQR rider designed at each speed" if scenario.design_speed is None
                 else f"LQR rider designed at {scenario.design_speed:g} m/s")
    elif scenario.controller == "thesis":
        rider = "Table 8.4 rider"
    else:
        rider = "no rider control"
    if scenario.controller == "lqr" and scenario.lqr_model == "simulated":
        rider += " on the model simulated"
    scale = f" x{scenario.gain_scale:g}" if scenario.controller != "off" and scenario.gain_scale != 1 else ""
    body = []   # the rider's body, named only when it is not the rigid rider's
    for part in parts.selected(scenario):   # the declared parts in the run's model, with their fields' values
        values = ", ".join(f"{f.label} {getattr(scenario, f.name):g} {f.unit}" for f in part.fields)
        body.append((part.title or part.name) + (f" ({values})" if values else ""))
    if scenario.reflex_delay:
        body.append(f"reflex delayed {scenario.reflex_delay * 1e3:g} ms")
    return (f"{scenario.tyre} {p} kPa ({offsets}, {scenario.tyre_transient}), {scenario.bicycle}{load}; "
            f"{rider}{scale}" + "".join(f"; {b}" for b in body))


def write(result, out, plot=True):
    """Write eigenvalues.csv, summary.json and (``plot``) stability.png into the folder ``out``.

    Returns
    -------
    list of str
        The file names written.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import analyse
    >>> import os
    >>> os.mkdir("out")
    >>> write(analyse(Scenario(symmetric_tyres=True), [3.0, 4.0]), "out")
    ['eigenvalues.csv', 'summary.json', 'stability.png']
    """
    out = pathlib.Path(out)
    fileio.write_csv(result.eigenvalues, out / "eigenvalues.csv")
    summary = results.clean(result.summary)
    fileio.write_atomic(out / "summary.json", json.dumps(summary, indent=2, allow_nan=False) + "\n")
    files = ["eigenvalues.csv", "summary.json"]
    if plot:
        figure(result, out / "stability.png", title=result.summary.get("title"))
        files.append("stability.png")
    return files


def report_lines(summary):
    """The few lines the ``stability`` command prints: speeds and modes per loop.

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import analyse
    >>> result = analyse(Scenario(symmetric_tyres=True), [3.0, 3.5, 4.0, 4.5, 5.0], loops=("open",))
    >>> print("\\n".join(report_lines(result.summary)))
      open loop (no rider control):
        slip: weave 3.82 m/s, capsize 3.88 m/s; stable none
        no-slip: weave 3.97 m/s, capsize none; stable 3.97-5.00 (sweep end) m/s
        wobble 9.2-9.4 Hz, damping ratio 0.063-0.102 (least damped at 3.00 m/s), stable
        modes: weave, capsize, caster, wobble, lateral rear, relaxation rear, relaxation front, vertical
    """
    lines = []
    for loop in LOOPS:
        info = summary.get("slip", {}).get(loop)
        if info is None:
            continue
        lines.append(f"  {loop} loop ({'no rider control' if loop == 'open' else 'with the rider'}):")
        lines += ["    " + text for text in speeds_text(summary, loop).split("\n")]
        wob = info.get("wobble")
        if wob and wob["exists"]:
            least = wob["least_damped"]
            lines.append(f"    wobble {wob['frequency_hz'][0]:.1f}-{wob['frequency_hz'][1]:.1f} Hz, damping ratio "
                         f"{wob['damping_ratio'][0]:.3f}-{wob['damping_ratio'][1]:.3f} (least damped at "
                         f"{least['speed_m_s']:.2f} m/s), {'UNSTABLE somewhere' if wob['unstable'] else 'stable'}")
        elif wob is not None:
            lines.append("    no wobble (no steer-dominated oscillation with the front tyre lagging)")
        for mode in ("arm_steer", "lean"):   # the rider body's modes
            if mode in info["modes"]:
                m = info["modes"][mode]
                lines.append(f"    {mode.replace('_', ' ')} {m['frequency_hz'][0]:.2f}-{m['frequency_hz'][1]:.2f} Hz at "
                             f"{m['speeds_m_s'][0]:g}-{m['speeds_m_s'][1]:g} m/s, largest real part "
                             f"{m['largest_real_part_1_s']:+.3f} 1/s (at {m['at_speed_m_s']:g} m/s)")
        lines.append("    modes: " + ", ".join(m.replace("_", " ") for m in info["modes"]))
        lean = summary.get("steady_motion", {}).get(loop, {}).get("largest_lean_rad")
        if lean is not None and abs(lean) > math.radians(TURN_NOTE_DEG):
            lines.append(f"    note: the steady motion is a turn with up to {math.degrees(lean):.1f} deg of lean "
                         "(the tyres' zero-slip offsets); these are the eigenvalues of that turn")
    return lines
