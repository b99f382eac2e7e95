"""Sweeps: cases, parallel runs, the table of results, executors, saved trajectories."""
import json
import sys

import numpy as np
import pandas as pd
import pytest

from conftest import SWEEP_BASE as BASE
from conftest import SWEEP_GRID as GRID
import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.simulate.scenario import Scenario
from whipple_kick.studies import sweep_engine


def test_table_has_one_row_per_case_with_inputs_and_metrics(default_run):
    folder, table = default_run
    assert list(table["pressure_kpa"]) == [300.0, 400.0, 500.0, 600.0]
    assert list(table["status"]) == ["ok", "ok", "ok", "failed"]
    assert table["error"].iloc[:3].isna().all()
    # Every scenario field is a column, then the flattened results.
    for column in ("fz_n", "tyre", "duration", "last_peak_time_s", "damping_ratio_1_3", "recovery.time_s",
                   "recovery.signals.roll_rate.time_s", "linear_stability.stable", "steady_state.found_by",
                   "steady_state.roll_rad", "controller.gains.kq4", "numerics.model_hash", "run.worker"):
        assert column in table.columns, column
    assert table["case_id"].is_unique
    assert table["case_id"].iloc[1] == wk.sweep_store.case_id(BASE.with_changes(pressure_kpa=400.0))


def test_failing_case_is_recorded_with_its_error(default_run):
    folder, table = default_run
    row = table.iloc[3]
    assert row["error"].startswith("InputError: ") and "600" in row["error"] and "kPa" in row["error"]
    assert np.isnan(row["last_peak_time_s"])
    log = wk.sweep_store.read_log(folder)
    assert log[row["case_id"]]["status"] == "failed"
    assert not wk.sweep_store.trajectory_path(folder, row["case_id"]).exists()


def test_sweep_results_equal_a_direct_run(default_run):
    # The per-process cache of rider and LQR must not change any number.
    _, table = default_run
    direct = wk.run(BASE.with_changes(pressure_kpa=400.0)).summary
    flat = wk.results.flatten_summary(direct)
    row = table.iloc[1]
    assert flat["last_peak_time_s"] is not None
    for key, value in flat.items():
        if key in wk.sweep_engine.VOLATILE_COLUMNS:
            continue
        if value is None:
            assert pd.isna(row[key]), key
        else:
            assert row[key] == value, key


def test_a_case_thinned_to_200_hz_keeps_the_summary_of_every_sample():
    # The sweep fixture runs at 200 Hz, where a 200 Hz trajectory is every sample; at the default 1000 Hz a
    # table row must still be the run's summary of every sample (peaks, energy balance, extrapolation).
    scenario = Scenario(duration=1.5, settle=0.1, fz_n=635.0)
    assert scenario.output_rate == 1000.0
    spec = wk.sweep_engine._trajectory_spec(wk.sweep_engine.DEFAULT_TRAJECTORY_COLUMNS, "float32", 200.0)
    record = wk.sweep_engine.run_case(scenario, "x", spec)
    assert record["trajectory"]["time"].size == 1 + int(round((1.5 + 0.1) * 200))
    direct = wk.results.flatten_summary(wk.run(scenario).summary)
    volatile = set(wk.sweep_engine.VOLATILE_COLUMNS)
    assert {k: v for k, v in record["results"].items() if k not in volatile} == \
        {k: v for k, v in direct.items() if k not in volatile}


def test_dask_executor_gives_the_same_table(default_run, dask_client):
    _, table = default_run
    dask_table = wk.sweep(GRID, base=BASE, executor=dask_client.get_executor(), progress=False)
    workers = set(dask_table["run.worker"])
    assert len(workers) == 2   # both Dask workers ran cases
    keep = [c for c in table.columns if c not in wk.sweep_engine.VOLATILE_COLUMNS]
    pd.testing.assert_frame_equal(dask_table[keep], table[keep])


def test_case_ids_and_input_errors():
    a = BASE.with_changes(pressure_kpa=400)
    b = BASE.with_changes(pressure_kpa=np.float64(400.0))
    assert wk.sweep_store.case_id(a) == wk.sweep_store.case_id(b) == wk.sweep_store.case_id(BASE.__class__(**BASE.to_dict()))
    assert wk.sweep_store.case_id(a) != wk.sweep_store.case_id(BASE.with_changes(pressure_kpa=400.001))
    cases = wk.sweep_engine.make_cases({"speed": [2, 3], "tyre": "T04"}, cases=[{"fz_n": 570}, {"fz_n": 701}])
    assert [c[0] for c in cases] == [
        {"fz_n": 570.0, "speed": 2.0, "tyre": "T04"}, {"fz_n": 570.0, "speed": 3.0, "tyre": "T04"},
        {"fz_n": 701.0, "speed": 2.0, "tyre": "T04"}, {"fz_n": 701.0, "speed": 3.0, "tyre": "T04"}]
    with pytest.raises(InputError, match=r"unknown scenario field.*'presure_kpa'"):
        wk.sweep_engine.make_cases({"presure_kpa": [300]})
    with pytest.raises(InputError, match="no values"):
        wk.sweep_engine.make_cases({"pressure_kpa": []})
    with pytest.raises(InputError, match="workers"):
        wk.sweep({"pressure_kpa": [300]}, base=BASE, workers=0)


def test_saved_trajectory_is_thinned_and_keeps_the_fall():
    scenario = Scenario(duration=3.0, settle=0.1, controller="off", fz_n=635.0,
                                   fall_angle_deg=20.0)   # the roll reaches 20 deg before the fork turns over
    spec = {"columns": ("time", "roll"), "dtype": "float64", "rate_hz": 100.0}
    record = wk.sweep_engine.run_case(scenario, "x", spec)
    t = record["trajectory"]["time"]
    summary = json.loads(record["summary"])
    assert summary["fell"]
    np.testing.assert_allclose(np.diff(t[:-1]), 0.01, rtol=1e-9)   # 1000 Hz output, every 10th
    assert t[-1] == summary["end_time_s"] == pytest.approx(summary["fall_time_s"])
    assert summary["fall_reason"] == "roll"
    assert abs(record["trajectory"]["roll"][-1]) == pytest.approx(np.radians(20.0))
    with pytest.raises(InputError, match="trajectory_rate"):
        wk.sweep({"pressure_kpa": [300]}, base=BASE, trajectory_rate=0)


_FAULTS_SNIPPET = """
import resource, sys
import numpy as np
from whipple_kick.studies import sweep_engine

np._core.multiarray._set_madvise_hugepage(False)   # 4 kB pages: one fault each (numpy asks for 2 MB ones)

def faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt

def case():   # a 48 MB array written and freed: above glibc's largest automatic mmap threshold (32 MB)
    np.ones(6_000_000)

case()
before = faults(); case(); plain = faults() - before
kept = sweep_engine._keep_freed_memory()
case()
before = faults(); case(); after = faults() - before
print(kept, plain, after)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc only")
def test_pool_workers_reuse_the_memory_they_free():
    """A sweep worker (:func:`sweep_engine._worker_start`) keeps the memory it frees, so a case's arrays do not
    page-fault afresh each case (about 10 ms of system time per case otherwise). In a fresh process a 48 MB
    array written and freed costs a page fault per 4 kB page each time (11 719 pages; measured ~11 700
    faults), and after the setting about none (measured 0): at most a twentieth of them is asked (a kernel
    that maps huge pages by itself faults ~50 times less in both)."""
    import subprocess
    out = subprocess.run([sys.executable, "-c", _FAULTS_SNIPPET], capture_output=True, text=True, check=True)
    kept, plain, after = out.stdout.split()
    if kept != "True":
        pytest.skip("not glibc: mallopt is not available")
    assert int(plain) >= 20 and int(after) * 20 <= int(plain), out.stdout


def test_a_case_run_by_any_executor_sets_the_memory_setting_once(monkeypatch):
    """Issue 41 item 5: a Dask worker (any executor's, not the default pool's) ran without the pool's memory
    setting. :func:`sweep_engine.run_case` sets it from the first case a process runs, and only then."""
    calls = []
    monkeypatch.setattr(sweep_engine, "_memory_kept", None)
    monkeypatch.setattr(sweep_engine, "_keep_freed_memory", lambda: calls.append(1) or True)
    scenario = wk.Scenario(duration=0.2, symmetric_tyres=True)
    for k in range(2):
        assert sweep_engine.run_case(scenario, f"c{k}")["status"] == "ok"
    assert calls == [1] and sweep_engine._memory_kept is True


def test_a_sweep_over_the_rear_load_share_gives_different_rows():
    """Each share is another rider (mass and place): the rows differ in the static loads, the rider's mass
    and shift, and the response (a field that changed nothing would give identical rows)."""
    table = wk.sweep({"rear_load_share": [0.63, 0.69]}, base=wk.Scenario(fz_n=635.0, duration=0.4), workers=1,
                     progress=False)
    assert list(table["status"]) == ["ok", "ok"]
    front = table["bicycle.static_load_front_n"].to_numpy()
    assert front == pytest.approx(635.0 / np.array([0.63, 0.69]) - 635.0, abs=1e-9)
    assert table["bicycle.rider_shift_m"].iloc[1] < table["bicycle.rider_shift_m"].iloc[0]
    assert table["bicycle.rider_mass_kg"].nunique() == 2
    assert table["yaw_rate_peaks_from_steady_rad_s"].nunique() == 2


def test_a_packed_case_is_its_trajectory_file_and_its_row_the_full_paths(tmp_path):
    # A sweep's worker packs the trajectory file itself (the parent only writes the bytes) and computes its
    # row without the trajectory table: the row must equal the full path's (wk.run) exactly, and the file
    # must hold what the unpacked record holds.
    scenario = Scenario(duration=1.0, settle=0.1, fz_n=635.0)
    spec = wk.sweep_engine._trajectory_spec(("time", "roll", "fy_rear"), "float32", 200.0)
    packed = wk.sweep_engine.run_case(scenario, "c1", spec, packed=True)
    plain = wk.sweep_engine.run_case(scenario, "c1", spec)
    assert isinstance(packed["trajectory"], bytes)
    volatile = set(wk.sweep_engine.VOLATILE_COLUMNS)
    direct = wk.results.flatten_summary(wk.run(scenario).summary)
    assert {k: v for k, v in packed["results"].items() if k not in volatile} == \
        {k: v for k, v in direct.items() if k not in volatile}
    (tmp_path / wk.sweep_store.TRAJECTORY_DIR).mkdir()
    wk.sweep_store._save_trajectory(tmp_path, packed)
    frame, summary = wk.sweep_store.load_trajectory(tmp_path, "c1")
    assert list(frame.columns) == ["time", "roll", "fy_rear"]
    for column in frame.columns:
        assert np.array_equal(frame[column].to_numpy(), plain["trajectory"][column])
    assert summary == json.loads(packed["summary"])
    table_only = wk.sweep_engine.run_case(scenario, "c1")
    assert table_only["trajectory"] is None
    assert {k: v for k, v in table_only["results"].items() if k not in volatile} == \
        {k: v for k, v in direct.items() if k not in volatile}


def test_a_table_only_case_returns_no_summary_text_as_a_sweep_asks(tmp_path):
    """A sweep keeps of a case without trajectory its flat results alone (sweep_store.slim), so it asks for no summary
    text: the same results and log line; a case with a trajectory, or run_case by default, still has the text."""
    scenario = Scenario(duration=1.0, settle=0.1)
    volatile = set(wk.sweep_engine.VOLATILE_COLUMNS)
    with_text = wk.sweep_engine.run_case(scenario, "c1")
    without = wk.sweep_engine.run_case(scenario, "c1", summary=False)
    assert without["summary"] is None and json.loads(with_text["summary"])["outcome"] == "completed"
    assert {k: v for k, v in without["results"].items() if k not in volatile} == \
        {k: v for k, v in with_text["results"].items() if k not in volatile}
    assert wk.sweep_store.slim(without).keys() == wk.sweep_store.slim(with_text).keys()
    spec = wk.sweep_engine._trajectory_spec(("time", "roll"), "float32", 200.0)
    kept = wk.sweep_engine.run_case(scenario, "c1", spec, packed=True, summary=False)
    stable = lambda text: {k: v for k, v in json.loads(text).items() if k not in ("numerics", "provenance")}
    assert stable(kept["summary"]) == stable(with_text["summary"])   # the file holds it (wall time, date aside)
    table = wk.sweep({"pressure_kpa": [400.0]}, base=scenario, workers=1, progress=False, folder=tmp_path / "s")
    assert (table["status"] == "ok").all()
