"""Response figures that say what happened, tested through the figure objects (artists, texts), not pixels."""
import math

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.figures import plotting
from whipple_kick.simulate import simulation


@pytest.fixture(scope="module")
def fall():
    """Controller off, thesis force-lag tyre, no steer limit: falls by roll at 1.35 s, its steer rate reaching
    -67 rad/s at the end."""
    result = simulation.run(simulation.Scenario(controller="off", duration=2.0, tyre_transient="force_lag",
                                                 steer_limit_deg=None))
    assert result.summary["fell"]
    return result


@pytest.fixture(scope="module")
def recovers():
    return simulation.run(simulation.Scenario(duration=1.0))


def _texts(fig):
    return [t.get_text() for ax in fig.axes for t in ax.texts] + [t.get_text() for t in fig.texts]


def test_plotting_leaves_the_backend_and_pyplot_alone(tmp_path):
    """A Figure on its own Agg canvas: no pyplot, no switch of the global backend (in a fresh process)."""
    import subprocess
    import sys
    probe = ("import sys, matplotlib\n"
             "matplotlib.use('pdf')\n"     # the user's choice, which plotting must keep
             "from whipple_kick import plotting, simulation\n"
             "r = simulation.run(simulation.Scenario(duration=0.3))\n"
             "plotting.response_figure([('', r)], sys.argv[1], kick=(0.0, 0.15))\n"
             "print(matplotlib.get_backend(), 'matplotlib.pyplot' in sys.modules)\n")
    done = subprocess.run([sys.executable, "-c", probe, str(tmp_path / "r.png")], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["pdf", "False"]
    assert (tmp_path / "r.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_fall_is_marked(fall):
    """Acceptance: a vertical line at the fall time in every panel and "fell at 1.345 s"."""
    fall_time = fall.summary["fall_time_s"]
    fig = plotting.response_figure([("", fall)], kick=(0.0, 0.15))
    for ax in fig.axes:
        marks = [line for line in ax.lines if line.get_gid() == "fall"]
        assert len(marks) == 1
        assert tuple(marks[0].get_xdata()) == (fall_time, fall_time)
    assert f"fell at {fall_time:.3f} s" in _texts(fig)


def test_axis_limits_come_from_the_motion_before_the_fall(fall):
    """The fall's last tenths (steer rate -67 rad/s) do not set the limits; the kick response does.

    Limits: the samples before |roll| first reaches half the fall angle
    (22.5 deg, at 0.98 s here), padded by 8 %: steer rate within about
    +-1.65 rad/s, so the kick response fills the panel.
    """
    fig = plotting.response_figure([("", fall)], kick=(0.0, 0.15))
    panels = dict(zip((c for c, _ in plotting.RESPONSE_PANELS), fig.axes, strict=True))
    df = fall.trajectory
    low, high = panels["steer_rate"].get_ylim()
    assert df["steer_rate"].min() < -60.0           # the fall itself ...
    assert -2.0 < low < -1.0 and 1.0 < high < 2.0   # ... is off the scale
    before = np.abs(df["roll"].to_numpy()) < 0.5 * math.radians(45.0)
    peak = np.max(np.abs(df["steer_rate"].to_numpy()[before]))
    assert max(-low, high) == pytest.approx(peak * 1.16, rel=0.1)


def test_kick_baseline_and_gain_scale_are_said(recovers):
    """The kick band is labelled, the steady-turn baseline drawn and named, the gain scale spelled out."""
    baseline = recovers.summary["steady_state"]["yaw_rate_rad_s"]
    title = plotting.result_title(recovers)
    fig = plotting.response_figure([("", recovers)], kick=(0.0, 0.15), title=title)
    texts = _texts(fig)
    assert any(t.strip() == "kick (150 ms)" for t in texts)
    assert any("steady turn before the kick" in t and f"{baseline:.3f} rad/s" in t for t in texts)
    lines = [line for line in fig.axes[0].lines if line.get_gid() == "baseline"]
    assert len(lines) == 1 and tuple(lines[0].get_ydata()) == (baseline, baseline)
    assert not any(line.get_gid() == "fall" for ax in fig.axes for line in ax.lines)
    title = fig._suptitle.get_text().replace("\n", " ")   # wrapped to the figure's width
    assert "gains scaled by 1" in title
    assert " x1" not in title
    # The whole title is inside the figure (it was once one 150-character line, clipped at both ends),
    # and above the first panel.
    renderer = fig.canvas.get_renderer()
    box, panel = fig._suptitle.get_window_extent(renderer), fig.axes[0].get_window_extent(renderer)
    assert box.x0 >= 0.0 and box.x1 <= fig.bbox.width and box.y1 <= fig.bbox.height
    assert box.y0 >= panel.y1


def test_several_runs_name_their_fall_in_the_legend(fall, recovers):
    fig = plotting.response_figure([("off", fall), ("lqr", recovers)], kick=(0.0, 0.15))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == [f"off (fell at {fall.summary['fall_time_s']:.3f} s)", "lqr"]


def test_motion_limits_ignore_samples_after_half_the_fall_angle():
    t = np.linspace(0.0, 1.0, 11)
    roll = np.where(t < 0.75, 0.1, 0.5)         # passes 22.5 deg (0.39 rad) at 0.8 s
    y = np.where(t < 0.75, t, 100.0)
    low, high = plotting.motion_limits(t, y, roll, math.radians(45.0))
    assert (low, high) == pytest.approx((-0.056, 0.756))
    assert plotting.motion_limits(t, y, roll, math.radians(45.0), time_range=(0.0, 0.5)) == pytest.approx(
        (-0.04, 0.54))


def test_upright_start_draws_the_steady_motion_as_the_baseline():
    """After an upright start (not a steady motion) the yaw-rate baseline is still the steady turn's."""
    result = simulation.run(simulation.Scenario(start="upright", settle=0.0, duration=0.3))
    st = result.summary["steady_state"]
    assert st["yaw_rate_rad_s"] == 0.0 and abs(st["yaw_rate_baseline_rad_s"]) > 0.01
    fig = plotting.response_figure([("", result)], kick=(0.0, 0.15))
    assert any("steady motion (the run starts upright)" in t and f"{st['yaw_rate_baseline_rad_s']:.3f}" in t
               for t in _texts(fig))
    line, = [line for line in fig.axes[0].lines if line.get_gid() == "baseline"]
    assert line.get_ydata()[0] == st["yaw_rate_baseline_rad_s"]

def test_axis_limits_stop_where_the_fork_turns_over():
    """A run lost at the steer limit whose roll never reaches half the fall angle (500 kPa, 570 N, controller
    off: |roll| stays below 22.5 deg): only the steer cut (half the steer limit, 45 deg) can keep the fork's
    last spin off the steer-rate axis."""
    result = simulation.run(simulation.Scenario(controller="off", duration=2.0, pressure_kpa=500.0, fz_n=570.0))
    assert result.summary["fall_reason"] == "steer"
    df = result.trajectory
    fig = plotting.response_figure([("", result)], kick=(0.0, 0.15))
    panels = dict(zip((c for c, _ in plotting.RESPONSE_PANELS), fig.axes, strict=True))
    low, high = panels["steer_rate"].get_ylim()
    assert np.max(np.abs(df["roll"].to_numpy())) < 0.5 * math.radians(45.0)
    before = np.arange(len(df)) < np.flatnonzero(np.abs(df["steer"].to_numpy()) >= 0.5 * math.radians(90.0))[0]
    peak = np.max(np.abs(df["steer_rate"].to_numpy()[before]))
    assert max(-low, high) == pytest.approx(peak * 1.16, rel=0.1)
    assert np.max(np.abs(df["steer_rate"].to_numpy())) > 2.0 * max(-low, high)   # the spin is off the scale


def test_recovery_time_and_bands_are_drawn(base, fall):
    """Issue 25: the recovery time is a vertical line in every panel, labelled "recovered at 2.71 s"; each rate
    panel has its 5 % band (steady +/- 5 % of the first peak from steady, from the summary) as two lines. A run
    that falls has its bands but no recovery."""
    rec = base.summary["recovery"]
    fig = plotting.response_figure([("", base)], kick=(0.0, 0.15))
    for ax, (column, _) in zip(fig.axes, plotting.RESPONSE_PANELS, strict=True):
        marks = [line for line in ax.lines if line.get_gid() == "recovery"]
        assert len(marks) == 1 and tuple(marks[0].get_xdata()) == (rec["time_s"], rec["time_s"])
        levels = sorted(line.get_ydata()[0] for line in ax.lines if line.get_gid() == "band")
        if column in rec["signals"]:
            entry = rec["signals"][column]
            assert entry["band_rad_s"] == pytest.approx(0.05 * entry["first_peak_from_steady_rad_s"], rel=1e-15)
            assert levels == [entry["steady_rad_s"] - entry["band_rad_s"], entry["steady_rad_s"] + entry["band_rad_s"]]
        else:
            assert levels == []
    assert f"recovered at {rec['time_s']:.2f} s" in _texts(fig)
    fig = plotting.response_figure([("", fall)], kick=(0.0, 0.15))
    assert not [line for ax in fig.axes for line in ax.lines if line.get_gid() == "recovery"]
    assert len([line for line in fig.axes[0].lines if line.get_gid() == "band"]) == 2


@pytest.fixture(scope="module")
def three(base):
    """Three runs to compare: the default run, 300 kPa (both recover), and no control (falls)."""
    return [base, simulation.run(simulation.Scenario(pressure_kpa=300.0, fz_n=635.0)),
            simulation.run(simulation.Scenario(controller="off", fz_n=635.0, duration=3.0))]


def test_compare_marks_each_runs_fall_recovery_and_bands(three):
    """Issue 25 acceptance: one figure overlaying the runs; per run its fall or recovery time as a vertical line in
    every panel, its 5 % bands in each rate panel (the falling run has no steer-rate band: its steer rate has no
    first peak before the fall), the legend naming the runs by what differs and how each ended."""
    fig = plotting.compare(three)
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    recovered = [r.summary["recovery"]["time_s"] for r in three[:2]]
    fall_time = three[2].summary["fall_time_s"]
    assert legend == [f"pressure_kpa=400, controller=lqr, duration=6 (recovered at {recovered[0]:.2f} s)",
                      f"pressure_kpa=300, controller=lqr, duration=6 (recovered at {recovered[1]:.2f} s)",
                      f"pressure_kpa=400, controller=off, duration=3 (fell at {fall_time:.3f} s)"]
    for ax in fig.axes:
        assert sorted(line.get_xdata()[0] for line in ax.lines if line.get_gid() == "recovery") == sorted(recovered)
        assert [line.get_xdata()[0] for line in ax.lines if line.get_gid() == "fall"] == [fall_time]
    bands = [len([line for line in ax.lines if line.get_gid() == "band"]) for ax in fig.axes]
    assert bands == [6, 6, 4, 0]
    assert [p.get_gid() for p in fig.axes[0].patches] == [None]   # one shared kick band (the same kick)


def test_compare_table_puts_the_runs_side_by_side(three):
    table = wk.results.compare_table(three, labels=["400 kPa", "300 kPa", "off"])
    assert list(table.columns) == ["400 kPa", "300 kPa", "off"]
    assert table.loc["outcome"].tolist() == ["completed", "completed", "fell"]
    assert table.loc["recovered"].tolist() == [True, True, False]
    assert table.loc["recovery.time_s"].tolist() == [r.summary["recovery"]["time_s"] for r in three[:2]] + [None]
    assert table.loc["fall_time_s"].tolist() == [None, None, three[2].summary["fall_time_s"]]
    assert table.loc["tyres.pressure_rear_kpa"].tolist() == [400.0, 300.0, 400.0]
    assert table.loc["peaks.max_abs_yaw_rate_absolute_rad_s", "400 kPa"] == \
        three[0].summary["peaks"]["max_abs_yaw_rate_absolute_rad_s"]
    with pytest.raises(wk.InputError, match="2 labels for 3 runs"):
        wk.results.compare_table(three, labels=["a", "b"])


def _sweep_table():
    """Pressure x load, as a sweep table: at 570 N 300 kPa fell, at 701 N 500 kPa failed."""
    import pandas as pd
    return pd.DataFrame({
        "pressure_kpa": [300.0, 400.0, 500.0] * 2, "fz_n": [570.0] * 3 + [701.0] * 3,
        "recovery.time_s": [np.nan, 2.5, 2.7, 3.1, 2.9, np.nan], "fell": [True, False, False, False, False, np.nan],
        "status": ["ok"] * 5 + ["failed"]})


def test_sweep_figure_lines_mark_fallen_and_failed_cases():
    """Issue 25: recovery time against pressure, one line per load; the case that fell is an x at the top of the
    axes at its pressure, the failed one a hollow square; both have no value on their line (NaN)."""
    fig = plotting.sweep_figure(_sweep_table(), x="pressure_kpa", y="fz_n", metric="recovery.time_s")
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["fz_n = 570", "fz_n = 701"]
    lines = [line for line in ax.lines if line.get_gid() == "metric"]
    np.testing.assert_array_equal(lines[0].get_ydata(), [np.nan, 2.5, 2.7])
    np.testing.assert_array_equal(lines[1].get_ydata(), [3.1, 2.9, np.nan])
    fell = [tuple(line.get_xdata()) for line in ax.lines if line.get_gid() == "fell"]
    failed = [tuple(line.get_xdata()) for line in ax.lines if line.get_gid() == "failed"]
    assert fell == [(300.0,), ()] and failed == [(), (500.0,)]
    assert ax.get_xlabel() == "pressure_kpa" and ax.get_ylabel() == "recovery.time_s"


def test_sweep_figure_heatmap_says_each_cells_value():
    fig = plotting.sweep_figure(_sweep_table(), x="pressure_kpa", y="fz_n", metric="recovery.time_s", kind="heatmap")
    cells = {(t.get_position(), t.get_text()) for t in fig.axes[0].texts}
    assert cells == {((0, 0), "fell"), ((1, 0), "2.5"), ((2, 0), "2.7"), ((0, 1), "3.1"), ((1, 1), "2.9"),
                     ((2, 1), "failed")}
    assert fig.axes[1].get_ylabel() == "recovery.time_s"           # the colour bar


@pytest.mark.parametrize("options, message", [
    (dict(x="pressure", metric="recovery.time_s"), "column 'pressure' is not in the sweep table"),
    (dict(x="pressure_kpa", metric="recovery.time_s"), "several cases share the same pressure_kpa"),
    (dict(x="pressure_kpa", metric="recovery.time_s", kind="heatmap"), "a heat map needs y"),
    (dict(x="pressure_kpa", y="fz_n", metric="recovery.time_s", kind="bars"), "kind 'bars' is unknown"),
])
def test_sweep_figure_mistakes_are_one_line(options, message):
    with pytest.raises(wk.InputError, match=message):
        plotting.sweep_figure(_sweep_table(), **options)
