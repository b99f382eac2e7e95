"""The sweep folder: manifest, log, table and trajectories; resuming, truncated logs, another sweep's folder."""
import concurrent.futures as cf
import os

import numpy as np
import pandas as pd
import pytest

from conftest import SWEEP_BASE as BASE
import whipple_kick as wk
from whipple_kick.errors import InputError


def test_folder_holds_manifest_table_and_trajectories(default_run):
    folder, table = default_run
    manifest = wk.sweep_store.read_manifest(folder)
    assert manifest["status"] == "complete"
    assert (manifest["n_ok"], manifest["n_failed"]) == (3, 1)
    assert manifest["model_hash"] == wk.slip.model_hash()
    assert manifest["provenance"]["versions"]["numpy"] == np.__version__
    assert manifest["base_scenario"]["duration"] == 3.0
    assert [c["case_id"] for c in manifest["cases"]] == list(table["case_id"])
    assert manifest["cases"][0]["overrides"] == {"pressure_kpa": 300.0}
    on_disk = pd.read_csv(folder / wk.sweep_store.TABLE_FILE)
    assert list(on_disk["case_id"]) == list(table["case_id"])
    np.testing.assert_allclose(on_disk["last_peak_time_s"], table["last_peak_time_s"], rtol=1e-11)
    traj, summary = wk.sweep_store.load_trajectory(folder, table["case_id"].iloc[0])
    assert list(traj.columns) == list(wk.sweep_engine.DEFAULT_TRAJECTORY_COLUMNS)
    assert traj["yaw_rate"].dtype == np.float32
    assert len(traj) == 621   # -0.1 .. 3.0 s at 200 Hz
    assert summary["scenario"]["pressure_kpa"] == 300.0


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
    with pytest.raises(wk.sweep_engine.SweepInterrupted, match="3 of 5 cases were not run"):
        wk.sweep(grid, base=BASE, folder=folder, executor=killer, progress=False)
    killer.shutdown()
    first = wk.sweep_store.read_log(folder)
    assert len(first) == 2 and all(r["status"] == "ok" for r in first.values())
    assert wk.sweep_store.read_manifest(folder)["status"] == "incomplete"
    assert len(pd.read_csv(folder / wk.sweep_store.TABLE_FILE)) == 2
    assert len(list((folder / wk.sweep_store.TRAJECTORY_DIR).glob("*.npz"))) == 2

    table = wk.sweep(grid, base=BASE, folder=folder, progress=False)
    assert list(table["pressure_kpa"]) == [300.0, 350.0, 400.0, 450.0, 500.0]
    assert (table["status"] == "ok").all()
    lines = (folder / wk.sweep_store.LOG_FILE).read_text().splitlines()
    assert len(lines) == 5          # each case ran exactly once over both runs
    finished = dict(zip(table["case_id"], table["run.finished"], strict=True))
    for cid, rec in first.items():  # the first run's cases were kept, not redone
        assert finished[cid] == rec["run"]["finished"]
    assert wk.sweep_store.read_manifest(folder)["status"] == "complete"

    # A third run finds everything done and runs nothing.
    again = wk.sweep(grid, base=BASE, folder=folder, progress=False)
    assert len((folder / wk.sweep_store.LOG_FILE).read_text().splitlines()) == 5
    pd.testing.assert_frame_equal(again, table)


def test_truncated_log_line_is_ignored_and_the_case_rerun(tmp_path):
    folder = tmp_path / "crash"
    grid = {"pressure_kpa": [300, 400]}
    wk.sweep(grid, base=BASE, folder=folder, progress=False, trajectory_columns=None)
    log = folder / wk.sweep_store.LOG_FILE
    lines = log.read_text().splitlines()
    log.write_text(lines[0] + "\n" + lines[1][: len(lines[1]) // 2])   # a crash mid-write
    table = wk.sweep(grid, base=BASE, folder=folder, progress=False, trajectory_columns=None)
    assert (table["status"] == "ok").all()
    # The rerun case's record is on its own line, not glued to the cut one (before, that swallowed
    # it: the log then held one case, and every later run of the sweep ran the other again).
    assert set(wk.sweep_store.read_log(folder)) == set(table["case_id"])
    assert log.read_text().endswith("\n") and len(log.read_text().splitlines()) == 3


def test_folder_of_another_sweep_is_refused_unless_extended(default_run, tmp_path):
    folder, table = default_run
    with pytest.raises(InputError, match="holds a different sweep"):
        wk.sweep({"pressure_kpa": [300]}, base=BASE, folder=folder, progress=False)
    small = tmp_path / "small"
    wk.sweep({"pressure_kpa": [300]}, base=BASE, folder=small, progress=False)
    both = wk.sweep({"pressure_kpa": [500]}, base=BASE, folder=small, progress=False, extend=True)
    assert list(both["pressure_kpa"]) == [300.0, 500.0]


def _first_half(folder):
    """The first half of a sweep (one 1 s case) in ``folder``; returns its base scenario."""
    base = BASE.with_changes(duration=1.0)
    wk.sweep({"pressure_kpa": [300]}, base=base, folder=folder, progress=False)
    return base


def test_a_sweep_folder_refuses_to_resume_under_other_result_code(tmp_path, monkeypatch):
    """Issue 31 item 9 acceptance: the recovery rule changes from 5 % to 10 % between two halves of a sweep (the
    issue found both rules side by side in one table). The folder hashes the code and data that make results
    (provenance.code_hash), so the second half is refused in one line saying what to do, and the folder, its
    manifest included, is left as the first half wrote it."""
    from whipple_kick.simulate import analysis, provenance
    folder = tmp_path / "halves"
    base = _first_half(folder)
    manifest = (folder / wk.sweep_store.MANIFEST_FILE).read_bytes()
    source = analysis.__file__
    read = provenance._read_source
    rule = b"\nSETTLING_FRACTION = 0.05"
    assert rule in read(source)

    def ten_percent(path):
        text = read(path)
        return text.replace(rule, b"\nSETTLING_FRACTION = 0.10") if str(path) == source else text
    monkeypatch.setattr(provenance, "_read_source", ten_percent)
    provenance.code_hash.cache_clear()
    try:
        with pytest.raises(InputError) as info:
            wk.sweep({"pressure_kpa": [300, 400]}, base=base, folder=folder, extend=True, progress=False)
    finally:
        provenance.code_hash.cache_clear()
    message = str(info.value)
    assert "\n" not in message and "holds results of other code" in message and "use a new folder" in message
    assert (folder / wk.sweep_store.MANIFEST_FILE).read_bytes() == manifest
    assert len(wk.sweep_store.read_log(folder)) == 1


def test_a_resumed_sweep_keeps_its_first_provenance_and_adds_each_session(tmp_path):
    """Issue 31 item 9: the manifest's provenance was written over on every open of the folder."""
    folder = tmp_path / "halves"
    base = _first_half(folder)
    first = wk.sweep_store.read_manifest(folder)
    assert first["code_hash"] == wk.provenance.code_hash() and len(first["sessions"]) == 1
    assert first["sessions"][0] == first["provenance"]
    wk.sweep({"pressure_kpa": [300, 400]}, base=base, folder=folder, extend=True, progress=False)
    second = wk.sweep_store.read_manifest(folder)
    assert second["provenance"] == first["provenance"] and len(second["sessions"]) == 2
    assert second["sessions"][0] == first["sessions"][0]


def test_a_folder_of_an_earlier_format_is_refused(tmp_path):
    """A folder made before the code hash was recorded cannot be told to be this code's: refused in one line."""
    import json
    folder = tmp_path / "old"
    base = _first_half(folder)
    path = folder / wk.sweep_store.MANIFEST_FILE
    manifest = json.loads(path.read_text())
    del manifest["code_hash"]
    manifest["format"] = 1
    path.write_text(json.dumps(manifest))
    with pytest.raises(InputError, match=r"earlier version of whipple_kick \(folder format 1, no code hash\)"):
        wk.sweep({"pressure_kpa": [300]}, base=base, folder=folder, progress=False)
