"""figures/uncertainty.py (named apart from tests/studies/test_uncertainty.py: test basenames must differ): the
uncertainty study's figures draw from its tables (made up here: the figures, not the study, are tested)."""
import math

import pandas as pd

from whipple_kick.figures import uncertainty as figures


def _p_best():
    rows = []
    for fz, best in ((570.0, 300.0), (635.0, 400.0)):
        for criterion in ("settling", "last_peak"):
            for p, share in ((300.0, 0.2), (400.0, 0.3), (500.0, 0.5), (math.nan, 0.0)):
                rows.append({"fz_n": fz, "criterion": criterion, "pressure_kpa": p, "p": share,
                             "low": max(share - 0.1, 0.0), "high": share + 0.1, "rows": 16, "rows_failed": 0,
                             "measured_best": p == best})
    return pd.DataFrame(rows)


def test_p_best_figure_has_a_panel_per_load_and_marks_the_measured_best():
    fig = figures.p_best_figure(_p_best(), title="t")
    axes = fig.axes
    assert [ax.get_title() for ax in axes] == ["rear load 570 N", "rear load 635 N"]
    assert len(axes[0].patches) == 6   # 3 pressures x 2 criteria (the 'none' share is not a bar)
    stars = [line for line in axes[1].lines if line.get_marker() == "*"]
    assert len(stars) == 1 and stars[0].get_xdata()[0] == 1   # 400 kPa, the second pressure


def test_distribution_and_sobol_figures(tmp_path):
    outcomes = pd.DataFrame([{"sample": r, "block": "A" if r % 2 else "B", "fz_n": 635.0, "pressure_kpa": p,
                              "recovery.time_s": 2.0 + 0.1 * r + p / 1000 if r != 3 else math.nan,
                              "last_peak_time_s": 0.3, "fell": r == 3, "status": "ok"}
                             for r in range(6) for p in (300.0, 500.0)])
    fig = figures.distribution_figure(outcomes, "settling")
    assert "17 % not recovered" in [t.get_text() for t in fig.axes[0].texts]   # 1 of 6 rows fell
    sobol = pd.DataFrame([{"fz_n": 635.0, "criterion": "settling", "pressure_a_kpa": 300.0, "pressure_b_kpa": 500.0,
                           "input": name, "S1": 0.1, "S1_conf": 0.05, "ST": 0.2, "ST_conf": 0.05}
                          for name in ("speed", "rider")])
    path = tmp_path / "s.png"
    assert figures.sobol_figure(sobol, "settling", path=path) is None and path.stat().st_size > 0
