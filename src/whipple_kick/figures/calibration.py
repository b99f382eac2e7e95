"""Figures of the calibration: the posterior predictive of each feature beside the measurement.

They take the calibration's ``features`` table (:class:`whipple_kick.studies.calibration.Calibration`,
``features.csv`` read back draws the same figure) and return a
:class:`matplotlib.figure.Figure` on its own Agg canvas, or write it to ``path`` as PNG.
"""
import numpy as np

from .plotting import _written

#: The z of a central 90 % interval of a normal (the predictive intervals are 5-95 %).
Z90 = 1.6449
#: Where each source of the predictive sits beside the measurement, its colour and its words.
_SOURCES = (("predictive_5", "predictive_95", "predicted_mean", -0.18, "tab:blue", "emulator at posterior draws"),
            ("simulator_5", "simulator_95", "simulator_mean", 0.18, "tab:orange", "simulator runs at posterior draws"))


def predictive_figure(features, path=None, title=None, dpi=120):
    """Posterior predictive 5-95 % per feature and cell (emulator and simulator runs) beside the measured value.

    One panel per feature, the measured cells along x. The measured value is a black dot with a bar of
    +-1.645 sd of its measurement error (90 %); the predictive intervals hold the measurement's and the
    discrepancy's noise too (the spread of a new measurement), their means as dots. A source the table
    lacks (no posterior runs) is not drawn.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    names = list(dict.fromkeys(features["feature"]))
    cells = list(dict.fromkeys(features["cell"]))
    fig = Figure(figsize=(max(6.0, 0.9 * len(cells) + 1.5), 2.8 * len(names) + 0.6))
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(names), 1, squeeze=False)[:, 0]
    x = np.arange(len(cells))
    for ax, name in zip(axes, names, strict=True):
        rows = features[features["feature"] == name].set_index("cell").reindex(cells)
        for lo, hi, mean, dx, colour, label in _SOURCES:
            if lo not in rows or not np.isfinite(rows[lo].to_numpy(float)).any():
                continue
            ax.vlines(x + dx, rows[lo].to_numpy(float), rows[hi].to_numpy(float), colour, lw=5, alpha=0.6,
                      label=f"{label}, 5-95 %")
            ax.plot(x + dx, rows[mean].to_numpy(float), "o", color=colour, ms=4)
        z, sd = rows["measured"].to_numpy(float), rows["sd_measurement"].to_numpy(float)
        ax.errorbar(x, z, yerr=Z90 * sd, fmt="o", color="k", capsize=3, ms=5, label="measured, +-1.645 sd")
        unit = rows["unit"].dropna().iloc[0] if rows["unit"].notna().any() else ""
        ax.set_ylabel(f"{name} [{unit}]")
        ax.set_xticks(x, cells, fontsize=8)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle(title or "posterior predictive per feature and cell against thesis Tables 8.6-8.8", fontsize=10)
    fig.tight_layout()
    return _written(fig, path, dpi)
