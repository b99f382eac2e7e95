"""Sweeps: the table, the folder, executors (process pool, Dask), resume, failures, recommender."""
import concurrent.futures as cf
import json
import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from whipple_kick import simulation, sweep
from whipple_kick.errors import InputError

# Short runs: the sweep machinery, not the physics, is under test here.
BASE = simulation.Scenario(duration=3.0, settle=0.1, output_rate=200.0, fz_n=635.0)
# 600 kPa is outside T03's measured 300-500 kPa: that case fails with an InputError.
GRID = {"pressure_kpa": [300, 400, 500, 600]}


@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep") / "grid"
    table = sweep.sweep(GRID, base=BASE, folder=folder, progress=False)
    return folder, table


def test_table_has_one_row_per_case_with_inputs_and_metrics(default_run):
    folder, table = default_run
    assert list(table["pressure_kpa"]) == [300.0, 400.0, 500.0, 600.0]
    assert list(table["status"]) == ["ok", "ok", "ok", "failed"]
    assert table["error"].iloc[:3].isna().all()
    # Every scenario field is a column, then the flattened results.
    for column in ("fz_n", "tyre", "duration", "last_peak_time", "damping_ratio_1_3", "recovery.time_s",
                   "recovery.signals.roll_rate.time_s", "linear_stability.stable", "steady_state.found_by",
                   "steady_state.roll_rad", "controller.gains.kq4", "numerics.model_hash", "run.worker"):
        assert column in table.columns, column
    assert table["case_id"].is_unique
    assert table["case_id"].iloc[1] == sweep.case_id(simulation.with_changes(BASE, pressure_kpa=400.0))


def test_failing_case_is_recorded_with_its_error(default_run):
    folder, table = default_run
    row = table.iloc[3]
    assert row["error"].startswith("InputError: ") and "600" in row["error"] and "kPa" in row["error"]
    assert np.isnan(row["last_peak_time"])
    log = sweep.read_log(folder)
    assert log[row["case_id"]]["status"] == "failed"
    assert not sweep.trajectory_path(folder, row["case_id"]).exists()


def test_sweep_results_equal_a_direct_run(default_run):
    # The per-process cache of rider and LQR must not change any number.
    _, table = default_run
    direct = simulation.run(simulation.with_changes(BASE, pressure_kpa=400.0)).summary
    flat = sweep.flatten_summary(direct)
    row = table.iloc[1]
    assert flat["last_peak_time"] is not None
    for key, value in flat.items():
        if key in sweep.VOLATILE_COLUMNS:
            continue
        if value is None:
            assert pd.isna(row[key]), key
        else:
            assert row[key] == value, key


def test_folder_holds_manifest_table_and_trajectories(default_run):
    folder, table = default_run
    manifest = sweep.read_manifest(folder)
    assert manifest["status"] == "complete"
    assert (manifest["n_ok"], manifest["n_failed"]) == (3, 1)
    assert manifest["model_hash"] == simulation.model_hash()
    assert manifest["versions"]["numpy"] == np.__version__
    assert manifest["base_scenario"]["duration"] == 3.0
    assert [c["case_id"] for c in manifest["cases"]] == list(table["case_id"])
    assert manifest["cases"][0]["overrides"] == {"pressure_kpa": 300.0}
    on_disk = pd.read_csv(folder / sweep.TABLE_FILE)
    assert list(on_disk["case_id"]) == list(table["case_id"])
    np.testing.assert_allclose(on_disk["last_peak_time"], table["last_peak_time"], rtol=1e-11)
    traj, summary = sweep.load_trajectory(folder, table["case_id"].iloc[0])
    assert list(traj.columns) == list(sweep.DEFAULT_TRAJECTORY_COLUMNS)
    assert traj["yaw_rate"].dtype == np.float32
    assert len(traj) == 621   # -0.1 .. 3.0 s at 200 Hz
    assert summary["scenario"]["pressure_kpa"] == 300.0


def test_dask_executor_gives_the_same_table(default_run):
    distributed = pytest.importorskip("distributed")
    _, table = default_run
    with distributed.LocalCluster(processes=True, n_workers=2, threads_per_worker=1,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        dask_table = sweep.sweep(GRID, base=BASE, executor=client.get_executor(), progress=False)
        workers = set(dask_table["run.worker"])
    assert len(workers) == 2   # both Dask workers ran cases
    keep = [c for c in table.columns if c not in sweep.VOLATILE_COLUMNS]
    pd.testing.assert_frame_equal(dask_table[keep], table[keep])


# -------------------------------------------------------------------------- resume

class KillAfter(cf.Executor):
    """A one-process pool whose worker is killed instead of running case ``n + 1``.

    Cases 1..n run normally; the worker then exits in the middle of the sweep
    (``os._exit``), which breaks the pool, so every later case is lost.
    """

    def __init__(self, n):
        self.pool = cf.ProcessPoolExecutor(max_workers=1)
        self.n, self.submitted = n, 0

    def submit(self, fn, *args, **kwargs):
        self.submitted += 1
        if self.submitted == self.n + 1:
            return self.pool.submit(os._exit, 1)
        return self.pool.submit(fn, *args, **kwargs)

    def shutdown(self, wait=True, *, cancel_futures=False):
        self.pool.shutdown(wait=wait, cancel_futures=cancel_futures)


def test_interrupted_sweep_resumes_without_redoing_or_losing_cases(tmp_path):
    folder = tmp_path / "resume"
    grid = {"pressure_kpa": [300, 350, 400, 450, 500]}
    killer = KillAfter(2)
    with pytest.raises(sweep.SweepInterrupted, match="3 of 5 cases were not run"):
        sweep.sweep(grid, base=BASE, folder=folder, executor=killer, progress=False)
    killer.shutdown()
    first = sweep.read_log(folder)
    assert len(first) == 2 and all(r["status"] == "ok" for r in first.values())
    assert sweep.read_manifest(folder)["status"] == "incomplete"
    assert len(pd.read_csv(folder / sweep.TABLE_FILE)) == 2
    assert len(list((folder / sweep.TRAJECTORY_DIR).glob("*.npz"))) == 2

    table = sweep.sweep(grid, base=BASE, folder=folder, progress=False)
    assert list(table["pressure_kpa"]) == [300.0, 350.0, 400.0, 450.0, 500.0]
    assert (table["status"] == "ok").all()
    lines = (folder / sweep.LOG_FILE).read_text().splitlines()
    assert len(lines) == 5          # each case ran exactly once over both runs
    finished = dict(zip(table["case_id"], table["run.finished"]))
    for cid, rec in first.items():  # the first run's cases were kept, not redone
        assert finished[cid] == rec["run"]["finished"]
    assert sweep.read_manifest(folder)["status"] == "complete"

    # A third run finds everything done and runs nothing.
    again = sweep.sweep(grid, base=BASE, folder=folder, progress=False)
    assert len((folder / sweep.LOG_FILE).read_text().splitlines()) == 5
    pd.testing.assert_frame_equal(again, table)


def test_truncated_log_line_is_ignored_and_the_case_rerun(tmp_path):
    folder = tmp_path / "crash"
    grid = {"pressure_kpa": [300, 400]}
    sweep.sweep(grid, base=BASE, folder=folder, progress=False, trajectory_columns=None)
    log = folder / sweep.LOG_FILE
    lines = log.read_text().splitlines()
    log.write_text(lines[0] + "\n" + lines[1][: len(lines[1]) // 2])   # a crash mid-write
    table = sweep.sweep(grid, base=BASE, folder=folder, progress=False, trajectory_columns=None)
    assert (table["status"] == "ok").all()


def test_folder_of_another_sweep_is_refused_unless_extended(default_run, tmp_path):
    folder, table = default_run
    with pytest.raises(InputError, match="holds a different sweep"):
        sweep.sweep({"pressure_kpa": [300]}, base=BASE, folder=folder, progress=False)
    small = tmp_path / "small"
    sweep.sweep({"pressure_kpa": [300]}, base=BASE, folder=small, progress=False)
    both = sweep.sweep({"pressure_kpa": [500]}, base=BASE, folder=small, progress=False, extend=True)
    assert list(both["pressure_kpa"]) == [300.0, 500.0]


def test_case_ids_and_input_errors():
    a = simulation.with_changes(BASE, pressure_kpa=400)
    b = simulation.with_changes(BASE, pressure_kpa=np.float64(400.0))
    assert sweep.case_id(a) == sweep.case_id(b) == sweep.case_id(BASE.__class__(**BASE.to_dict()))
    assert sweep.case_id(a) != sweep.case_id(simulation.with_changes(BASE, pressure_kpa=400.001))
    cases = sweep.make_cases({"speed": [2, 3], "tyre": "T04"}, cases=[{"fz_n": 570}, {"fz_n": 701}])
    assert [c[0] for c in cases] == [
        {"fz_n": 570.0, "speed": 2.0, "tyre": "T04"}, {"fz_n": 570.0, "speed": 3.0, "tyre": "T04"},
        {"fz_n": 701.0, "speed": 2.0, "tyre": "T04"}, {"fz_n": 701.0, "speed": 3.0, "tyre": "T04"}]
    with pytest.raises(InputError, match="unknown scenario field.*'presure_kpa'"):
        sweep.make_cases({"presure_kpa": [300]})
    with pytest.raises(InputError, match="no values"):
        sweep.make_cases({"pressure_kpa": []})
    with pytest.raises(InputError, match="workers"):
        sweep.sweep({"pressure_kpa": [300]}, base=BASE, workers=0)


# --------------------------------------------------------------------- recommender

def _cli(*args):
    exe = os.path.join(os.path.dirname(sys.executable), "recommend-pressure")
    return subprocess.run([exe, *args], capture_output=True, text=True, timeout=600)


def test_recommend_pressure_prints_table_and_recommendation_for_thesis_loads():
    proc = _cli("--fz", "570", "635", "701")
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    for fz in (570, 635, 701):
        assert f"rear load {fz} N, tyre T03" in out
        assert f"recommendation for {fz} N: " in out
    # Three pressures per load, each a table row with the recovery time, and the margin to the second best.
    rows = [line.split() for line in out.splitlines() if line.strip().startswith(("300 ", "400 ", "500 "))]
    assert len(rows) == 9 and all(float(r[2]) > 0 for r in rows)
    assert out.count("ahead of the second best") == 3 and "ranked by the recovery time" in out


@pytest.mark.parametrize("args, message", [
    (("--fz", "-3"), "rear-tyre load fz = -3.0 N is outside"),
    (("--fz", "635", "--pressures", "700"), "700.0 kPa is outside the allowed range [300, 500] kPa"),
    (("--fz", "635", "--tyre", "T99"), "tyre = 'T99' is unknown"),
    (("--fz", "x"), "'x' is not a number (N)"),
])
def test_recommend_pressure_bad_input_is_one_line_exit_2(args, message):
    proc = _cli(*args)
    assert proc.returncode == 2
    assert message in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert proc.stdout == ""


def test_recommend_pressure_function_fine_grid():
    # 3 s runs: too short for the rates to settle, so rank by the thesis' last-peak time here.
    base = simulation.Scenario(duration=3.0, output_rate=200.0)
    rec = sweep.recommend_pressure(701, pressures=[300, 500], fine=True, step_kpa=50, base=base,
                                   criterion="last-peak")
    assert rec.criterion == "last_peak"
    assert list(rec.table["pressure_kpa"]) == [300.0, 350.0, 400.0, 450.0, 500.0]
    assert list(rec.table["measured"]) == [True, False, True, False, True]
    best = rec.table.loc[rec.table["rank"] == 1]
    assert float(best["pressure_kpa"].iloc[0]) == rec.best_pressure_kpa
    assert float(best["last_peak_time"].iloc[0]) == rec.table["last_peak_time"].min()
    assert rec.best_measured_kpa in (300.0, 400.0, 500.0)
    assert "recommendation for 701 N:" in sweep.format_recommendation(rec)


def test_saved_trajectory_is_thinned_and_keeps_the_fall():
    scenario = simulation.Scenario(duration=3.0, settle=0.1, controller="off", fz_n=635.0,
                                   fall_angle_deg=20.0)   # the roll reaches 20 deg before the fork turns over
    spec = {"columns": ("time", "roll"), "dtype": "float64", "rate_hz": 100.0}
    record = sweep.run_case(scenario, "x", spec)
    t = record["trajectory"]["time"]
    summary = json.loads(record["summary"])
    assert summary["fell"]
    np.testing.assert_allclose(np.diff(t[:-1]), 0.01, rtol=1e-9)   # 1000 Hz output, every 10th
    assert t[-1] == summary["end_time_s"] == pytest.approx(summary["fall_time_s"])
    assert summary["fall_reason"] == "roll"
    assert abs(record["trajectory"]["roll"][-1]) == pytest.approx(np.radians(20.0))
    with pytest.raises(InputError, match="trajectory_rate"):
        sweep.sweep({"pressure_kpa": [300]}, base=BASE, trajectory_rate=0)


# ---------------------------------------------------------- the recommender's rules on the nine cases

@pytest.fixture(scope="module")
def nine_case_recommendations(tmp_path_factory):
    """The nine thesis cases (default scenario, 6 s) ranked by both criteria (one sweep: the second
    call resumes the folder of the first and runs nothing)."""
    folder = tmp_path_factory.mktemp("nine") / "sweep"
    return {criterion: sweep.recommend_pressures([570, 635, 701], criterion=criterion, folder=folder)
            for criterion in ("settling", "last-peak")}


@pytest.mark.parametrize("criterion", ["settling", "last-peak"])
def test_recommendation_margin_and_no_clear_optimum_rule_on_the_nine_cases(nine_case_recommendations,
                                                                        criterion):
    key = sweep.criterion_key(criterion)
    column = sweep.CRITERIA[key][0]
    for rec, fz in zip(nine_case_recommendations[criterion], (570.0, 635.0, 701.0)):
        assert rec.fz_n == fz and rec.criterion == key and rec.spread_s == sweep.CRITERION_SPREAD_S[key] > 0
        table = rec.table
        assert list(table["pressure_kpa"]) == [300.0, 400.0, 500.0] and table["measured"].all()
        ok = table[(table["status"] == "ok") & ~table["fell"].astype(bool) & table[column].notna()]
        values = np.sort(ok[column].to_numpy(dtype=float))
        assert rec.best_pressure_kpa == float(ok.loc[ok[column].idxmin(), "pressure_kpa"])
        assert rec.margin_s == pytest.approx(values[1] - values[0], abs=1e-12)
        assert rec.verdict == ("no clear optimum" if rec.margin_s < rec.spread_s else "clear")
        assert int(table.loc[table["pressure_kpa"] == rec.best_pressure_kpa, "rank"].iloc[0]) == 1
        text = sweep.format_recommendation(rec)
        assert f"{rec.margin_s:.3f} s ahead of the second best" in text
        assert f"{rec.spread_s:.3f} s" in text
        assert ("no clear optimum" in text) == (rec.verdict == "no clear optimum")
        for p in (300, 400, 500):   # every pressure's value is printed
            cell = table.loc[table["pressure_kpa"] == p, column].iloc[0]
            assert f"{cell:.3f}" in text


@pytest.mark.parametrize("fz, base", [
    # The issue's case, which needs the thesis' force lag: 2 m/s, 35 m/s^2; 400 kPa falls, 300 and
    # 500 kPa do not (measured). On the default tyre nothing falls there, nor at 2-3 m/s for any
    # load and pressure of the nine cases with kicks of 30-100 m/s^2 over 150 mm.
    (701, simulation.Scenario(speed=2.0, design_speed=2.0, kick_accel=35.0, duration=4.0,
                              tyre_transient="force_lag")),
    # On the default tyre a longer plate travel does it: 350 mm in 150 ms (31 m/s^2, within the
    # plate peaks the thesis measured) at 701 N: 300 and 400 kPa fall (1.38 and 1.84 s), 500 kPa
    # recovers (3.27 s, roll at most 16.6 deg).
    (701, simulation.Scenario(kick_displacement=0.35, kick_duration=0.15)),
], ids=["force_lag_issue_case", "default_350mm_kick"])
def test_a_run_that_fell_is_never_ranked_ahead(fz, base):
    """By either criterion a run that fell ranks after the runs that did not fall, and is never the
    recommendation."""
    for criterion in ("last-peak", "settling"):
        rec = sweep.recommend_pressure(fz, base=base, criterion=criterion)
        fell = rec.table["fell"].astype(bool).to_numpy()
        assert fell.any() and not fell.all()
        assert rec.table["rank"].to_numpy()[fell].min() > rec.table["rank"].to_numpy()[~fell].max()
        assert rec.best_pressure_kpa is not None and rec.best_pressure_kpa not in set(rec.table["pressure_kpa"][fell])


def _rows(**columns):
    n = len(columns["pressure_kpa"])
    defaults = {"measured": [True] * n, "recovery.time_s": [np.nan] * n, "last_peak_time": [np.nan] * n,
                "fell": [False] * n, "status": ["ok"] * n}
    return pd.DataFrame({**defaults, **columns})


def test_ranking_rules_on_a_synthetic_table():
    # A fall with the shortest last-peak time still ranks last; ties broken by the other criterion.
    rows = _rows(pressure_kpa=[300.0, 400.0, 500.0], last_peak_time=[1.0, 0.2, 1.0],
                 **{"recovery.time_s": [4.0, np.nan, 3.0]}, fell=[False, True, False])
    assert list(np.argsort(sweep._rank(rows, "last_peak")) + 1) == [2, 3, 1]
    assert sweep._verdict(rows, "last_peak") == (500.0, 0.0, "no clear optimum")
    assert sweep._verdict(rows, "settling") == (500.0, 1.0, "clear")
    # Only one pressure recovered: it is the recommendation, with no margin.
    one = _rows(pressure_kpa=[300.0, 400.0], **{"recovery.time_s": [np.nan, 3.0]})
    assert sweep._verdict(one, "settling") == (400.0, None, "clear")
    assert sweep._verdict(_rows(pressure_kpa=[300.0, 400.0]), "settling") == (None, None, "none recovered")
    failed = _rows(pressure_kpa=[300.0, 400.0], status=["failed", "ok"], **{"recovery.time_s": [1.0, 3.0]})
    assert sweep._verdict(failed, "settling") == (400.0, None, "clear")
    assert sweep._verdict(_rows(pressure_kpa=[400.0], **{"recovery.time_s": [3.0]}), "settling") == (
        None, None, "nothing to choose")
    assert sweep.criterion_key("last-peak") == "last_peak"
    with pytest.raises(InputError, match="settling, last-peak"):
        sweep.criterion_key("fastest")


def test_one_measured_pressure_leaves_nothing_to_choose():
    """T01 was measured at 400 kPa only (thesis Table 7.9): there is nothing to choose."""
    rec = sweep.recommend_pressure(635, tyre="T01", base=simulation.Scenario(duration=1.0, output_rate=200.0))
    assert rec.verdict == "nothing to choose" and rec.best_pressure_kpa is None and rec.margin_s is None
    assert list(rec.table["pressure_kpa"]) == [400.0]
    assert "nothing to choose: only 400 kPa was run (T01 was measured at one pressure)" in (
        sweep.format_recommendation(rec))


def test_recommend_pressure_cli_criterion_and_extend(tmp_path):
    folder = tmp_path / "runs"
    first = _cli("--fz", "635", "--pressures", "300", "500", "--duration", "3", "--criterion", "last-peak",
                 "--out", str(folder), "--no-progress")
    assert first.returncode == 0, first.stderr
    assert "ranked by the last-peak time" in first.stdout
    # Another sweep into the same folder needs --extend.
    refused = _cli("--fz", "701", "--pressures", "300", "--duration", "3", "--out", str(folder), "--no-progress")
    assert refused.returncode == 2 and "extend" in refused.stderr
    extended = _cli("--fz", "701", "--pressures", "300", "--duration", "3", "--out", str(folder), "--extend",
                    "--no-progress")
    assert extended.returncode == 0, extended.stderr
    assert len(sweep.read_log(folder)) == 3
