"""Figures of kick responses: the four signals of the thesis' Figure 8.6.

Yaw rate, roll rate, steer rate [rad/s] and the rear tyre's lateral force
[N] (the relaxed force acting on the bicycle, model convention: + to the
right) against time from the kick start. Several runs overlay in one
figure (thesis Figures 8.6-8.9). Matplotlib's non-interactive Agg backend is
used, so plotting works without a display.
"""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

#: (column, axis label) of the four panels, top to bottom.
RESPONSE_PANELS = (
    ("yaw_rate", "yaw rate [rad/s]"),
    ("roll_rate", "roll rate [rad/s]"),
    ("steer_rate", "steer rate [rad/s]"),
    ("fy_rear", "rear lateral force $F_y$ [N]"),
)


def _frame_of(run):
    """The trajectory DataFrame of a Result or a DataFrame itself."""
    return getattr(run, "trajectory", run)


def response_figure(runs, path=None, title=None, kick=None, time_range=None, dpi=150):
    """Plot the response panels for one or more runs.

    Parameters
    ----------
    runs : sequence of (label, Result or DataFrame)
        Runs to overlay; DataFrames need the columns of :data:`RESPONSE_PANELS`
        and ``time`` [s].
    path : str or pathlib.Path, optional
        Write a PNG there (and close the figure).
    title : str, optional
        Figure title.
    kick : (float, float), optional
        Start and end of the kick [s], shaded in every panel.
    time_range : (float, float), optional
        Time axis limits [s]; default the runs' span.
    dpi : int
        Resolution of the PNG.

    Returns
    -------
    matplotlib.figure.Figure or None
        The figure, or None when it was written to ``path``.
    """
    fig, axes = plt.subplots(len(RESPONSE_PANELS), 1, sharex=True, figsize=(8.0, 9.0))
    for label, run in runs:
        df = _frame_of(run)
        fell = bool(getattr(run, "summary", {}).get("fell", False))
        text = f"{label} (fell)" if fell and label else label
        for ax, (column, _) in zip(axes, RESPONSE_PANELS):
            ax.plot(df["time"], df[column], lw=1.2, label=text)
    for ax, (_, ylabel) in zip(axes, RESPONSE_PANELS):
        ax.set_ylabel(ylabel)
        ax.grid(True, lw=0.4, alpha=0.5)
        ax.axvline(0.0, color="0.4", lw=0.6, ls=":")
        if kick is not None:
            ax.axvspan(kick[0], kick[1], color="0.85", zorder=0)
    axes[-1].set_xlabel("time from kick start [s]")
    if time_range is not None:
        axes[-1].set_xlim(*time_range)
    if any(label for label, _ in runs):
        axes[0].legend(loc="upper right", fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    if path is None:
        return fig
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return None


def result_title(result):
    """One-line description of a run for a figure title."""
    s = result.summary
    sc = s["scenario"]
    load = s["bicycle"]["static_load_rear_n"]
    return (f"{sc['tyre']} {s['tyres']['pressure_rear_kpa']:g}/{s['tyres']['pressure_front_kpa']:g} kPa "
            f"(rear/front), rear load {load:.0f} N, {sc['speed']:g} m/s, controller {sc['controller']}"
            f" x{sc['gain_scale']:g}; kick {abs(s['kick']['displacement_m']) * 1e3:.0f} mm "
            f"{s['kick']['direction']} in {s['kick']['duration_s']:.3f} s "
            f"({s['kick']['peak_acceleration_m_s2']:.1f} m/s$^2$)")
