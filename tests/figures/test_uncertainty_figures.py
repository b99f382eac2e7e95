"""figures/uncertainty.py (named apart from tests/studies/test_uncertainty.py: test basenames must differ): the
uncertainty study's figures draw from its tables (made up here: the figures, not the study, are tested)."""
import math

import pandas as pd
import pytest

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
    """Issue 39 item 4: the legend hid the measured-best star, and the `none` share was not drawn."""
    table = _p_best()
    table.loc[table["pressure_kpa"].isna(), ["p", "high"]] = [0.1, 0.2]
    fig = figures.p_best_figure(table, title="t")
    axes = fig.axes
    assert [ax.get_title() for ax in axes] == ["rear load 570 N", "rear load 635 N"]
    assert len(axes[0].patches) == 8   # (3 pressures + none) x 2 criteria
    assert [t.get_text() for t in axes[0].get_xticklabels()] == ["300", "400", "500", "none"]
    assert axes[0].patches[3].get_height() == 0.1   # the none share, drawn
    stars = [line for line in axes[1].lines if line.get_marker() == "*"]
    assert len(stars) == 1 and stars[0].get_xdata()[0] == 1   # 400 kPa, the second pressure
    assert stars[0].get_ydata()[0] > 0.4   # above its bars' intervals (0.3 + 0.1)
    fig.canvas.draw()
    box = fig.legends[0].get_window_extent()
    for ax in axes:
        for star in (line for line in ax.lines if line.get_marker() == "*"):
            x, y = ax.transData.transform((star.get_xdata()[0], star.get_ydata()[0]))
            assert not box.contains(x, y)
            assert y < box.y0 or y > box.y1   # not even beside it: the legend is below the panels
        assert ax.get_window_extent().y0 > box.y1 - 1


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
    # Every pair per load by default, or each load's own pair; the rows without a time in the title.
    sobol = pd.concat([sobol.assign(fz_n=fz, pressure_a_kpa=a, pressure_b_kpa=b, rows=20, rows_one_not_recovered=2,
                                    rows_neither_recovered=1)
                       for fz in (570.0, 635.0) for a, b in ((300.0, 400.0), (300.0, 500.0))])
    fig = figures.sobol_figure(sobol, "settling")
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert len(titles) == 4 and "635 N: 300 vs 500 kPa\none not recovered 10 %, neither 5 %" in titles
    fig = figures.sobol_figure(sobol, "settling", pair={570.0: (400.0, 300.0), 635.0: (300.0, 500.0)})
    assert [ax.get_title().split("\n")[0] for ax in fig.axes if ax.get_title()] == ["570 N: 300 vs 400 kPa",
                                                                                   "635 N: 300 vs 500 kPa"]


def test_paired_figure_draws_each_row_at_two_pressures():
    """Paired differences shown as paired: one point per row, a run not recovered on the band beyond the times."""
    outcomes = pd.DataFrame([{"sample": r, "block": "A" if r % 2 else "B", "fz_n": 635.0, "pressure_kpa": p,
                              "recovery.time_s": (2.0 + 0.1 * r + p / 1000) if (r, p) != (3, 500.0) else math.nan,
                              "last_peak_time_s": 0.3, "fell": False, "status": "ok"}
                             for r in range(6) for p in (300.0, 500.0)])
    fig = figures.paired_figure(outcomes, "settling")
    ax = fig.axes[0]
    both, lost = ax.collections[0].get_offsets(), ax.collections[1].get_offsets()
    assert len(both) == 5 and len(lost) == 1
    assert lost[0][0] == pytest.approx(2.3 + 0.3) and lost[0][1] > both[:, 1].max()   # row 3 at 500 kPa: the band
    text = [t.get_text() for t in ax.texts]
    assert "300 first 1.00\n500 first 0.00\nneither 0.00" in text and "not recovered" in text
