"""Figures of kick responses: the four signals of the thesis' Figure 8.6, sweeps, comparisons and validation.

Yaw rate, roll rate, steer rate [rad/s] and the rear tyre's lateral force
[N] (the relaxed force acting on the bicycle, model convention: + to the
right) against time from the kick start. Several runs overlay in one
figure (thesis Figures 8.6-8.9). The figure says what happened: the kick
band is labelled, a fall is marked by a vertical line and "fell at t s",
the axis limits come from the motion before the fall (a falling bicycle's
last few tenths of a second would otherwise stretch them 50-fold), and the
yaw-rate baseline (the steady turn before the kick) is drawn and named.
Figures are :class:`matplotlib.figure.Figure` objects drawn on their own Agg
canvas, without pyplot: plotting works without a display and leaves the
global backend (and a user's interactive session) alone.
"""
import math
import textwrap

import numpy as np
import pandas as pd

from whipple_kick.errors import InputError
from whipple_kick.library import experiments, thesis
from whipple_kick.simulate import analysis
from whipple_kick.simulate.results import checked_labels

#: (column, axis label) of the four panels, top to bottom.
RESPONSE_PANELS = (
    ("yaw_rate", "yaw rate [rad/s]"),
    ("roll_rate", "roll rate [rad/s]"),
    ("steer_rate", "steer rate [rad/s]"),
    ("fy_rear", "rear lateral force $F_y$ [N]"),
)
#: Fall angle [deg] assumed for a bare DataFrame (the Scenario default).
DEFAULT_FALL_ANGLE_DEG = 45.0
#: Fraction of the fall angle up to which the motion sets the axis limits.
LIMIT_ROLL_FRACTION = 0.5
#: Margin added on both sides of the data range, as a fraction of it.
LIMIT_PADDING = 0.08
#: Subplot margins of the response figure (fractions of its 8 x 9 in): what ``tight_layout`` gave for
#: the default run, the left one widened to fit six-character tick labels such as "-0.075". Fixed,
#: because ``tight_layout`` lays out every tick label once more before the drawing does (about a
#: quarter of the figure's time).
RESPONSE_MARGINS = {"left": 0.11, "right": 0.98, "bottom": 0.065, "hspace": 0.12}
#: Top margin without a title, and what each line of the title takes off it (fractions of the height).
RESPONSE_TOP = 0.985
RESPONSE_TITLE_LINE = 0.0185
#: Characters per title line: a run's title (tyre, load, speed, rider, kick) is ~150 characters, wider
#: than the 8 in figure at 10 pt, so it is wrapped instead of clipped.
RESPONSE_TITLE_WIDTH = 100
#: zlib level of the PNG: 1 writes about twice as fast as the default 6, for a file ~10 % larger.
PNG_COMPRESS_LEVEL = 1


def _frame_of(run):
    """The trajectory DataFrame of a Result or a DataFrame itself."""
    return getattr(run, "trajectory", run)


def motion_limits(time, values, roll, fall_roll, time_range=None, steer=None, steer_limit=None):
    """Axis limits of a signal from the motion before the fall.

    Only the samples before the bicycle first leans past
    :data:`LIMIT_ROLL_FRACTION` of the fall angle (or, given ``steer`` and
    ``steer_limit``, first steers past that fraction of the steer limit)
    count (all of them if it never does), within ``time_range`` if given;
    the range is padded by :data:`LIMIT_PADDING` on both sides.

    Parameters
    ----------
    time, values, roll : array_like
        Time [s], the signal, roll angle [rad] at the same samples.
    fall_roll : float
        ``|roll|`` [rad] that counts as a fall.
    time_range : (float, float), optional
        Only samples within it count [s].
    steer : array_like, optional
        Steer angle [rad] at the same samples.
    steer_limit : float, optional
        ``|steer|`` [rad] that ends a run (None: no limit).

    Returns
    -------
    (float, float)

    Example
    -------
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> roll = np.where(t < 0.8, 0.0, 1.0)          # leans over at 0.8 s
    >>> low, high = motion_limits(t, np.where(t < 0.8, np.sin(t), 50.0), roll, math.radians(45))
    >>> round(low, 4), round(high, 4)               # sin(0.7) = 0.6442, padded by 8 %
    (-0.0515, 0.6958)
    """
    t = np.asarray(time, dtype=float)
    y = np.asarray(values, dtype=float)
    past = np.abs(np.asarray(roll, dtype=float)) >= LIMIT_ROLL_FRACTION * fall_roll
    if steer is not None and steer_limit is not None:
        # A fork turning over ends a run too; its last spin would stretch the axes just the same.
        past |= np.abs(np.asarray(steer, dtype=float)) >= LIMIT_ROLL_FRACTION * steer_limit
    over = np.flatnonzero(past)
    keep = np.arange(t.size) < (over[0] if over.size else t.size)
    if time_range is not None:
        keep &= (t >= time_range[0]) & (t <= time_range[1])
    if not keep.any():
        keep = np.ones(t.size, dtype=bool)
    lo, hi = float(np.min(y[keep])), float(np.max(y[keep]))
    span = hi - lo if hi > lo else max(abs(hi), 1e-3)
    return lo - LIMIT_PADDING * span, hi + LIMIT_PADDING * span


def _outcome(run):
    """(fell, fall time or None, steady yaw rate or None, fall angle [rad], steer limit [rad] or None) of a
    Result; DataFrames: unknown."""
    summary = getattr(run, "summary", None) or {}
    scenario = getattr(run, "scenario", None)
    fall_angle = math.radians(getattr(scenario, "fall_angle_deg", DEFAULT_FALL_ANGLE_DEG))
    steer_deg = getattr(scenario, "steer_limit_deg", None)
    steer_limit = None if steer_deg is None else math.radians(steer_deg)
    fell = bool(summary.get("fell", False))
    steady = summary.get("steady_state", {})
    # The yaw-rate metrics' baseline: the steady turn, also after an upright start (which is not one).
    baseline = steady.get("yaw_rate_baseline_rad_s", steady.get("yaw_rate_rad_s"))
    return fell, summary.get("fall_time_s") if fell else None, baseline, fall_angle, steer_limit


def recovery_marks(run):
    """(recovery time [s] or None, {column: (steady value, half band)}) of a Result; a DataFrame has none.

    The bands are each rate's steady value +/- 5 % of its first peak from
    steady (``summary["recovery"]["signals"]``): recovered from the time all
    three rates stay inside theirs.
    """
    summary = getattr(run, "summary", None) or {}
    recovery = summary.get("recovery", {})
    bands = {name: (entry["steady_rad_s"], entry["band_rad_s"]) for name, entry in recovery.get("signals", {}).items()
             if entry.get("band_rad_s") is not None}
    return (recovery.get("time_s") if summary.get("recovered") else None), bands


def response_figure(runs, path=None, title=None, kick=None, time_range=None, dpi=150):
    """Plot the response panels for one or more runs.

    Parameters
    ----------
    runs : sequence of (label, Result or DataFrame)
        Runs to overlay; DataFrames need the columns of :data:`RESPONSE_PANELS`,
        ``time`` [s] and ``roll`` [rad]. A Result's fall, steady turn, recovery
        time and 5 % bands (:func:`recovery_marks`) are marked.
    path : str or pathlib.Path, optional
        Write a PNG there.
    title : str, optional
        Figure title.
    kick : (float, float), optional
        Start and end of the kick [s], shaded and labelled in every panel.
    time_range : (float, float), optional
        Time axis limits [s]; default the runs' span.
    dpi : int
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure or None
        The figure, or None when it was written to ``path``.

    Example
    -------
    >>> import whipple_kick as wk
    >>> result = wk.run(wk.Scenario(controller="off", duration=2.0))
    >>> fig = response_figure([("", result)], kick=(0.0, 0.15))
    >>> [t.get_text() for t in fig.axes[0].texts if t.get_text().startswith("fell")]
    ['fell at 1.536 s']
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    import matplotlib.transforms as mtransforms

    fig = Figure(figsize=(8.0, 9.0))
    FigureCanvasAgg(fig)   # its own canvas: no pyplot, no global backend
    axes = fig.subplots(len(RESPONSE_PANELS), 1, sharex=True)
    limits = {column: [] for column, _ in RESPONSE_PANELS}
    baselines = []
    marked = False
    for k, (label, run) in enumerate(runs):
        df = _frame_of(run)
        fell, fall_time, baseline, fall_angle, steer_limit = _outcome(run)
        recovered_at, bands = recovery_marks(run)
        color = f"C{k}"
        text = (f"{label} (fell at {fall_time:.3f} s)" if fell and label else
                f"{label} (recovered at {recovered_at:.2f} s)" if recovered_at is not None and label else label)
        t = df["time"].to_numpy()
        for ax, (column, _) in zip(axes, RESPONSE_PANELS, strict=True):
            ax.plot(t, df[column], lw=1.2, label=text, color=color)
            limits[column].append(motion_limits(t, df[column], df["roll"], fall_angle, time_range,
                                                df["steer"] if "steer" in df else None, steer_limit))
            if fell:
                ax.axvline(fall_time, color=color, lw=1.0, ls="--", gid="fall")
            if column in bands:
                steady, band = bands[column]
                for level in (steady - band, steady + band):
                    ax.axhline(level, color=color, lw=0.6, ls=(0, (4, 3)), alpha=0.7, gid="band")
            if recovered_at is not None:
                ax.axvline(recovered_at, color=color, lw=1.0, ls="-.", gid="recovery")
        if recovered_at is not None:
            axes[0].text(recovered_at, 0.97 - 0.09 * k, f"recovered at {recovered_at:.2f} s", color=color, fontsize=8,
                         ha="left", va="top", gid="recovery", transform=mtransforms.blended_transform_factory(
                             axes[0].transData, axes[0].transAxes))
        marked |= bool(bands)
        if fell:
            # Stacked below the top panel's upper edge when several runs fall.
            axes[0].text(fall_time, 0.97 - 0.09 * k, f"fell at {fall_time:.3f} s", color=color, fontsize=8,
                         ha="right", va="top", transform=mtransforms.blended_transform_factory(
                             axes[0].transData, axes[0].transAxes), gid="fall")
        if baseline is not None:
            axes[0].axhline(baseline, color=color, lw=0.8, ls=":", gid="baseline")
            baselines.append(baseline)
    for ax, (column, ylabel) in zip(axes, RESPONSE_PANELS, strict=True):
        ax.set_ylabel(ylabel)
        ax.grid(True, lw=0.4, alpha=0.5)
        ax.axvline(0.0, color="0.4", lw=0.6, ls=":")
        if kick is not None:
            ax.axvspan(kick[0], kick[1], color="0.85", zorder=0)
        if limits[column]:
            ax.set_ylim(min(lo for lo, _ in limits[column]), max(hi for _, hi in limits[column]))
    if kick is not None:
        # Upright in the band, from its top: clear of the baseline note and the fall marks.
        axes[0].text(0.5 * (kick[0] + kick[1]), 0.97, f"kick ({(kick[1] - kick[0]) * 1e3:.0f} ms)", fontsize=7.5,
                     color="0.3", rotation=90, ha="center", va="top", gid="kick",
                     transform=mtransforms.blended_transform_factory(axes[0].transData, axes[0].transAxes))
    if baselines:
        value = (f"{baselines[0]:.3f} rad/s" if np.ptp(baselines) < 5e-4 else
                 f"{min(baselines):.3f} to {max(baselines):.3f} rad/s")
        upright = any(getattr(getattr(run, "scenario", None), "start", "steady") == "upright" for _, run in runs)
        what = "steady motion (the run starts upright)" if upright else "steady turn before the kick"
        axes[0].text(0.01, 0.03, f"dotted: {what}, {value} (the yaw-rate baseline)",
                     fontsize=7.5, color="0.25", transform=axes[0].transAxes, ha="left", va="bottom", gid="baseline")
    if marked:
        axes[1].text(0.01, 0.03, "dashed: steady value +/- 5 % of the first peak; dash-dot: recovered (all three "
                     "rates inside their bands from then on)", fontsize=7.5, color="0.25", transform=axes[1].transAxes,
                     ha="left", va="bottom", gid="band")
    axes[-1].set_xlabel("time from kick start [s]")
    if time_range is not None:
        axes[-1].set_xlim(*time_range)
    if any(label for label, _ in runs):
        axes[0].legend(loc="upper right", fontsize=8)
    lines = textwrap.wrap(title, RESPONSE_TITLE_WIDTH, break_on_hyphens=False) if title else []
    if lines:
        fig.suptitle("\n".join(lines), fontsize=10)
    top = RESPONSE_TOP - (RESPONSE_TITLE_LINE * (len(lines) + 1) if lines else 0.0)
    fig.subplots_adjust(top=top, **RESPONSE_MARGINS)
    return _written(fig, path, dpi)


def _written(fig, path, dpi):
    """``fig``, or None once it is written to ``path`` as PNG (when a path is given)."""
    if path is None:
        return fig
    fig.savefig(path, dpi=dpi, pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
    return None


def kick_band(result):
    """(start, end) [s] of a Result's kick, from its summary."""
    k = result.summary["kick"]
    return k["start_s"], k["start_s"] + k["duration_s"]


def compare(results, path=None, labels=None, title=None, time_range=None, dpi=150):
    """One figure overlaying runs, each with its kick, fall, recovery time and 5 % bands marked.

    The response panels of :func:`response_figure`, one colour per run; the
    legend names each run and its fall or recovery time. Runs with different
    kicks get a band each, in their colour. The table of their metrics side
    by side is :func:`whipple_kick.simulate.results.compare_table`.

    Parameters
    ----------
    results : sequence of Result
        Runs (from :func:`whipple_kick.run` or :meth:`whipple_kick.Result.load`).
    path : str or pathlib.Path, optional
        Write a PNG there.
    labels : sequence of str, optional
        Legend entries (default :func:`whipple_kick.simulate.results.run_labels`: the
        scenario fields in which the runs differ).
    title, time_range, dpi
        As :func:`response_figure`.

    Returns
    -------
    matplotlib.figure.Figure or None
        The figure, or None when it was written to ``path``.

    Example
    -------
    >>> import whipple_kick as wk
    >>> runs = [wk.run(wk.Scenario(pressure_kpa=p, duration=4.0)) for p in (300.0, 500.0)]
    >>> runs.append(wk.run(wk.Scenario(controller="off", duration=3.0)))
    >>> fig = wk.plotting.compare(runs)
    >>> [t.get_text() for t in fig.axes[0].get_legend().get_texts()][2]
    'pressure_kpa=400, controller=off, duration=3 (fell at 1.536 s)'
    """
    results = list(results)
    if not results:
        raise InputError("nothing to compare: give at least one run")
    labels = checked_labels(results, labels)
    kicks = [kick_band(r) for r in results]
    same = len(set(kicks)) == 1
    fig = response_figure(list(zip(labels, results, strict=True)), title=title, time_range=time_range,
                          kick=kicks[0] if same else None)
    if not same:
        for k, (start, end) in enumerate(kicks):
            for ax in fig.axes:
                ax.axvspan(start, end, color=f"C{k}", alpha=0.15, zorder=0, gid="kick")
    return _written(fig, path, dpi)


#: Kinds of :func:`sweep_figure`.
SWEEP_KINDS = ("lines", "heatmap")


def _sweep_cells(table, x, metric, y):
    """Per case: (x, y or None, metric value or NaN, fell, failed), duplicates of (x, y) refused."""
    for name in (x, metric) + (() if y is None else (y,)):
        if name not in table.columns:
            raise InputError(f"column {name!r} is not in the sweep table ({len(table.columns)} columns, e.g. "
                             "pressure_kpa, fz_n, recovery.time_s, last_peak_time_s; see table.columns)")
    keys = [x] if y is None else [x, y]
    if table.duplicated(subset=keys).any():
        raise InputError(f"several cases share the same {' and '.join(keys)} (the sweep varies other fields too); "
                         "select the rows of one figure first, e.g. table[table['speed'] == 3.0]")
    values = pd.to_numeric(table[metric], errors="coerce").to_numpy(dtype=float)
    fell = (table["fell"] == True).to_numpy() if "fell" in table else np.zeros(len(table), bool)   # noqa: E712
    failed = (table["status"] != "ok").to_numpy() if "status" in table else np.zeros(len(table), bool)
    return table[x].to_numpy(dtype=float), None if y is None else table[y].to_numpy(), values, fell, failed


def sweep_figure(table, x, metric, y=None, kind="lines", path=None, title=None, dpi=150):
    """A sweep's ``metric`` against ``x`` (a line per ``y`` value, or a heat map of x by y), fallen cases marked.

    Parameters
    ----------
    table : pandas.DataFrame
        A sweep table (:func:`whipple_kick.sweep`, table.csv of a sweep
        folder, :attr:`whipple_kick.studies.recommend.Recommendation.table`): one row
        per case, ``fell`` and ``status`` used when present.
    x : str
        Column along the horizontal axis (e.g. ``"pressure_kpa"``).
    metric : str
        Column plotted (e.g. ``"recovery.time_s"``, ``"last_peak_time_s"``).
    y : str, optional
        Column that tells the lines apart (or, in a heat map, the vertical axis),
        e.g. ``"fz_n"``.
    kind : {"lines", "heatmap"}
        Lines: a case that fell is an x at the top of the axes (it has no
        recovery time), a failed case a hollow square. Heat map (needs ``y``):
        each cell says its value, "fell" or "failed".
    path, title, dpi
        As :func:`response_figure`.

    Returns
    -------
    matplotlib.figure.Figure or None
        The figure, or None when it was written to ``path``.

    Raises
    ------
    InputError
        A column is missing, ``kind`` is unknown, or several cases share one
        point (x, y).

    Example
    -------
    >>> import whipple_kick as wk
    >>> table = wk.sweep({"pressure_kpa": [300, 400, 500], "fz_n": [570, 701]}, progress=False)
    >>> fig = wk.plotting.sweep_figure(table, x="pressure_kpa", y="fz_n", metric="recovery.time_s")
    >>> [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    ['fz_n = 570', 'fz_n = 701']
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    import matplotlib.transforms as mtransforms

    if kind not in SWEEP_KINDS:
        raise InputError(f"sweep figure kind {kind!r} is unknown; choose one of {', '.join(SWEEP_KINDS)}")
    if kind == "heatmap" and y is None:
        raise InputError("a heat map needs y, the column of its vertical axis (e.g. y='fz_n')")
    xs, ys, values, fell, failed = _sweep_cells(table, x, metric, y)
    fig = Figure(figsize=(7.0, 4.5))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    if kind == "lines":
        groups = [(None, np.ones(xs.size, bool))] if y is None else [(v, ys == v) for v in sorted(set(ys))]
        top = mtransforms.blended_transform_factory(ax.transData, ax.transAxes)
        for k, (value, rows) in enumerate(groups):
            order = np.flatnonzero(rows)[np.argsort(xs[rows], kind="stable")]
            color = f"C{k}"
            label = None if y is None else (f"{y} = {value:g}" if isinstance(value, (int, float, np.number))
                                            else f"{y} = {value}")
            ax.plot(xs[order], values[order], marker="o", ms=4, color=color, label=label, gid="metric")
            down = order[fell[order]]
            ax.plot(xs[down], np.full(down.size, 0.96), ls="none", marker="x", ms=8, mew=2, color=color,
                    transform=top, gid="fell")
            broken = order[failed[order] & ~fell[order]]
            ax.plot(xs[broken], np.full(broken.size, 0.96), ls="none", marker="s", mfc="none", color=color,
                    transform=top, gid="failed")
        ax.set_xlabel(x)
        ax.set_ylabel(metric)
        ax.grid(True, lw=0.4, alpha=0.5)
        if y is not None:
            ax.legend(fontsize=8, loc="best")
        if fell.any() or failed.any():
            ax.text(0.01, 0.02, "x at the top: the case fell (no value); hollow square: it failed", fontsize=7.5,
                    color="0.25", transform=ax.transAxes, gid="fell")
    else:
        columns, rows = sorted(set(xs)), sorted(set(ys))
        grid = np.full((len(rows), len(columns)), np.nan)
        for xv, yv, v in zip(xs, ys, values, strict=True):
            grid[rows.index(yv), columns.index(xv)] = v
        mesh = ax.pcolormesh(np.arange(len(columns) + 1) - 0.5, np.arange(len(rows) + 1) - 0.5,
                             np.ma.masked_invalid(grid), cmap="viridis", gid="metric")
        fig.colorbar(mesh, ax=ax, label=metric)
        for xv, yv, v, down, broken in zip(xs, ys, values, fell, failed, strict=True):
            text, gid = (("fell", "fell") if down else ("failed", "failed") if broken else
                         ("-" if not np.isfinite(v) else f"{v:.3g}", "value"))
            ax.text(columns.index(xv), rows.index(yv), text, ha="center", va="center", fontsize=8, gid=gid,
                    color="k" if gid != "value" else "w")
        ax.set_xticks(range(len(columns)), [f"{v:g}" for v in columns])
        ax.set_yticks(range(len(rows)), [f"{v:g}" if isinstance(v, (int, float, np.number)) else str(v)
                                         for v in rows])
        ax.set_xlabel(x)
        ax.set_ylabel(y)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return _written(fig, path, dpi)


def controller_text(summary):
    """The rider model of a run in words, gain scale spelled out (e.g. "LQR rider (designed at 3 m/s), gains x 1")."""
    sc = summary["scenario"]
    if summary.get("controller", {}).get("type") == "custom gains":
        return "rider with custom steer-torque gains"
    if sc["controller"] == "off":
        return "no rider control (steer torque off)"
    # The design speed actually used (the scenario's is None when the rider adapts to the run's speed).
    design = summary.get("controller", {}).get("design_speed_m_s")
    if design is None:
        design = sc.get("design_speed") or sc["speed"]
    what = (f"LQR rider (designed at {design:g} m/s)" if sc["controller"] == "lqr"
            else "thesis Table 8.4 rider gains")
    return f"{what}, gains scaled by {sc['gain_scale']:g}"


def result_title(result):
    """One-line description of a run for a figure title."""
    s = result.summary
    sc = s["scenario"]
    load = s["bicycle"]["static_load_rear_n"]
    rear, front = s["tyres"]["pressure_rear_kpa"], s["tyres"]["pressure_front_kpa"]
    tyres = "custom tyres" if rear is None else f"{sc['tyre']} {rear:g}/{front:g} kPa (rear/front)"
    return (f"{tyres}, rear load {load:.0f} N, {sc['speed']:g} m/s, {controller_text(s)}; "
            f"kick {abs(s['kick']['displacement_m']) * 1e3:.0f} mm "
            f"{s['kick']['direction']} in {s['kick']['duration_s']:.3f} s "
            f"({s['kick']['peak_acceleration_m_s2']:.1f} m/s$^2$)")


#: (validation.csv column, axis label) of the validation figure's metric panels.
VALIDATION_METRICS = (
    ("last_peak_time_s", "last-peak time [s]"),
    ("n_peaks", "peaks above 8 %"),
    ("period_s", "period, peaks #1-#3 [s]"),
    ("log_dec_13", "log decrement #1-#3"),
    ("log_dec_24", "log decrement #2-#4"),
    ("dominant_frequency_hz", "dominant frequency [Hz]"),
)


def validation_figure(result, path=None, dpi=120):
    """Model against the thesis' measurements (:func:`whipple_kick.studies.validation.validate`).

    Six metric panels (each case: measured, model with kicks to the right
    and to the left), the model's processed yaw-rate histories (steady turn
    removed) and their amplitude spectra over the 1 s after the kick, with
    the measured 5-6 Hz band shaded; the spectra's 1 s window starts as
    the wheel leaves the plate (0.2 s), as the dominant frequency's does.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    exp = experiments.load()
    band = (exp.processing["yaw_band_low"], exp.processing["yaw_band_high"])
    start = exp.conditions["wheel_on_plate_min"]   # the spectra's window starts as the wheel leaves the plate
    table = result.table
    cases = list(dict.fromkeys(table["case"]))
    x = np.arange(len(cases))
    fig = Figure(figsize=(13, 11))
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(4, 3, height_ratios=(1, 1, 1.3, 1.3))
    styles = {("measured", ""): dict(marker="s", color="k", label="measured (thesis Tables 8.6-8.8)"),
              ("model", "right"): dict(marker="o", color="tab:red", label="model, kick to the right"),
              ("model", "left"): dict(marker="^", color="tab:blue", label="model, kick to the left")}
    for k, (column, label) in enumerate(VALIDATION_METRICS):
        ax = fig.add_subplot(grid[k // 3, k % 3])
        for (source, direction), style in styles.items():
            rows = table[(table["source"] == source) & (table["direction"] == direction)].set_index("case")
            if rows.empty:
                continue
            values = [float(rows.loc[c, column]) if c in rows.index and rows.loc[c, column] is not None
                      and np.isfinite(float(rows.loc[c, column])) else np.nan for c in cases]
            ax.plot(x, values, linestyle="none", markersize=6, **style)
        if column == "dominant_frequency_hz":
            ax.axhspan(*band, color="0.85", zorder=0, label="measured 5-6 Hz band (Section 8.6)")
        ax.set_ylabel(label, fontsize=8)
        ax.set_xticks(x)
        ax.set_xticklabels([c.replace("_", "\n") for c in cases], fontsize=6.5)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        if k == 0:   # one legend for the six metric panels, above them
            fig.legend(*ax.get_legend_handles_labels(), loc="upper center", ncol=3, fontsize=8,
                       bbox_to_anchor=(0.5, 0.965), frameon=False)
        if column == "dominant_frequency_hz":
            ax.legend(handles=ax.get_legend_handles_labels()[0][-1:], fontsize=7, loc="best")
    colors = dict(zip(thesis.PRESSURES_KPA, ("tab:blue", "tab:red", "tab:olive"), strict=True))
    dashes = dict(zip(thesis.LOADS_N, (":", "-", "--"), strict=True))
    legend_drawn = False
    for row, direction in enumerate(("right", "left")):
        ax_t = fig.add_subplot(grid[2 + row, 0:2])
        ax_f = fig.add_subplot(grid[2 + row, 2])
        if not any(name.endswith(f"_{direction}") for name in result.runs):
            ax_t.text(0.5, 0.5, f"kicks to the {direction} not run", transform=ax_t.transAxes, ha="center")
            ax_t.set_axis_off()
            ax_f.set_axis_off()
            continue
        for name, run in result.runs.items():
            if not name.endswith(f"_{direction}"):
                continue
            summary = run["summary"]["scenario"]
            t, y = run["recording"]
            style = dict(color=colors.get(summary["pressure_kpa"], "0.4"), linestyle=dashes.get(summary["fz_n"], "-"),
                         linewidth=1.0)
            ax_t.plot(t, y - run["steady"], label=name.rsplit("_", 1)[0], **style)
            after = (t >= start - 1e-9) & (t < start + exp.processing["record_length"] - 1e-9)
            f, a = analysis.amplitude_spectrum(t[after], y[after] - run["steady"], exp.processing["spectrum_max"])
            ax_f.plot(f, a, **style)
        ax_t.axvspan(0.0, 0.5, color="0.93", zorder=0)
        ax_t.text(0.25, 0.02, "measured peaks end here (< 0.5 s)", transform=ax_t.get_xaxis_transform(),
                  ha="center", fontsize=7, color="0.3")
        ax_t.axvline(0.0, color="tab:green", linestyle=":", linewidth=1)
        ax_t.set_xlim(-0.2, 3.0)   # the slow swing's first half-period; the runs go on to 6 s
        ax_t.set_ylabel(f"yaw rate - steady [rad/s]\nkick to the {direction}", fontsize=8)
        ax_t.grid(alpha=0.3)
        ax_f.axvspan(*band, color="0.85", zorder=0)
        ax_f.set_xlim(0, exp.processing["spectrum_max"])
        ax_f.set_ylabel(f"amplitude [rad/s], {start:g}-{start + exp.processing['record_length']:g} s", fontsize=8)
        ax_f.grid(alpha=0.3)
        if not legend_drawn:
            ax_t.legend(fontsize=6, ncol=3, loc="upper right")
            legend_drawn = True
        if row == 1:
            ax_t.set_xlabel("time from kick start [s] (model: 100 Hz, 20 Hz low-pass, as recorded)")
            ax_f.set_xlabel("frequency [Hz] (grey: measured 5-6 Hz band)")
    fig.suptitle("Model against the kick-plate measurements (thesis Section 8.5, Tables 8.6-8.8): "
                 "2 m/s, 150 mm smooth kick at 35 m/s^2", fontsize=10)
    fig.subplots_adjust(left=0.06, right=0.99, top=0.93, bottom=0.05, hspace=0.45, wspace=0.25)
    return _written(fig, path, dpi)
