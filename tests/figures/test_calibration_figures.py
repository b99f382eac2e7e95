"""figures/calibration.py: the predictive figure draws from the features table (made up here)."""
import math

import pandas as pd

from whipple_kick.figures import calibration as figures


def _features(runs=True):
    rows = []
    for cell in ("570N_300kPa", "635N_400kPa"):
        for f, unit, z in (("frequency_hz", "Hz", 5.0), ("log_decrement", "-", 1.0)):
            row = {"key": f"{cell}:{f}", "cell": cell, "feature": f, "unit": unit, "measured": z,
                   "sd_measurement": 0.1 * z, "predicted_mean": z, "predictive_5": 0.8 * z, "predictive_95": 1.2 * z}
            if runs:
                row.update(simulator_mean=1.1 * z, simulator_5=0.9 * z, simulator_95=1.3 * z)
            rows.append(row)
    return pd.DataFrame(rows)


def test_predictive_figure_has_a_panel_per_feature_and_both_sources(tmp_path):
    fig = figures.predictive_figure(_features())
    assert [ax.get_ylabel() for ax in fig.axes] == ["frequency_hz [Hz]", "log_decrement [-]"]
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert labels == ["emulator at posterior draws, 5-95 %", "simulator runs at posterior draws, 5-95 %",
                      "measured, +-1.645 sd"]
    bars = fig.axes[0].collections[0].get_segments()
    assert [tuple(s[:, 1]) for s in bars] == [(4.0, 6.0), (4.0, 6.0)]
    path = tmp_path / "p.png"
    assert figures.predictive_figure(_features(), path) is None and path.stat().st_size > 1000


def test_predictive_figure_without_simulator_runs_draws_the_emulator_only():
    frame = _features(runs=False)
    frame["simulator_5"] = math.nan
    labels = figures.predictive_figure(frame).axes[0].get_legend_handles_labels()[1]
    assert labels == ["emulator at posterior draws, 5-95 %", "measured, +-1.645 sd"]
