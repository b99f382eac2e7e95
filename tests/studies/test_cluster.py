"""Sweeps on a Dask cluster of command-line processes (a scheduler and two workers over TCP on this machine):
the same table as the process pool's, and the compiled model built once per host from an empty cache."""
import os
import shutil

import pandas as pd
import pytest

import whipple_kick as wk
from whipple_kick.model.slip import compiled
from whipple_kick.simulate.scenario import Scenario
from whipple_kick.studies import cluster, sweep_engine

Client = pytest.importorskip("distributed", reason="Dask's distributed (the test extra) runs the cluster").Client

# Short cases: the executor, not the physics, is under test. 600 kPa is outside T03's measured 300-500 kPa: that
# case fails, and its row must come back the same way too.
SHORT = Scenario(duration=0.5, settle=0.1, output_rate=200.0, fz_n=635.0)
GRID = {"pressure_kpa": [300, 500, 600]}


def _comparable(table):
    return table.drop(columns=list(sweep_engine.VOLATILE_COLUMNS))


def test_a_sweep_on_a_command_line_cluster_is_the_pools_table():
    """The cases run in the cluster's worker processes and their table is the pool's exactly (tolerance 0: the
    same code on the same inputs; only where it runs differs), failed case included."""
    pool = wk.sweep(GRID, base=SHORT, workers=2, progress=False)
    with cluster.command_line_cluster(2, timeout=60) as address, Client(address, timeout=30) as client:
        reports = cluster.prepare_workers(client, GRID, base=SHORT)
        on_dask = wk.sweep(GRID, base=SHORT, executor=client.get_executor(), progress=False)
    assert len(reports) == 2 and all(r["built"] == [] for r in reports)   # the test's cache is warm
    # The pool's worker settings: freed memory kept (glibc, as here), no sampling profiler.
    assert all(r["memory_kept"] and r["profiler_stopped"] for r in reports)
    assert all(r["warmup_status"] == ["ok"] for r in reports)
    worker_pids = {str(r["pid"]) for r in reports}
    assert {w.rsplit(":", 1)[1] for w in on_dask["run.worker"]} <= worker_pids
    assert str(os.getpid()) not in worker_pids
    assert list(on_dask["status"]) == ["ok", "ok", "failed"]
    pd.testing.assert_frame_equal(_comparable(on_dask), _comparable(pool), check_exact=True)


def test_an_empty_cache_is_built_once_for_the_two_workers_of_a_host(tmp_path):
    """Two workers sharing one empty cache folder (one host): preparing them builds the model once, on the first
    worker; and when both ask for the missing model at the same moment, the cache's file lock still lets only one
    build it while the other waits.

    What is under test is who builds, so the build is made quick: each worker takes the generated C from the
    warm cache (a preload file) instead of repeating the SymPy derivation, and compiles it without
    optimisation (another cache key); the compiler, the lock and the cache entry are the real ones. The
    cache holds the warm one's other entries (the integrator's driver, the call extension): only the model
    is missing.
    """
    cache = tmp_path / "cache"
    cache.mkdir(mode=0o700)
    warm_c = compiled.library_path().with_suffix(".c")
    for entry in warm_c.parent.iterdir():
        if not entry.name.startswith("slip_") and not entry.name.endswith(".lock") and entry.is_file():
            shutil.copy2(entry, cache / entry.name)
    preload = tmp_path / "quick_model_build.py"
    preload.write_text("from whipple_kick.model import compiler\n"
                       "from whipple_kick.model.symbolic import slip_build\n"
                       f"slip_build.c_source = lambda *model: open({str(warm_c)!r}).read()\n"
                       "compiler.MODEL_FLAGS = ('-O0', *compiler.MODEL_FLAGS[1:])\n")
    env = dict(os.environ, WHIPPLE_KICK_CACHE=str(cache))
    with (cluster.command_line_cluster(2, env=env, preload=preload, timeout=60) as address,
          Client(address, timeout=30) as client):
        reports = cluster.prepare_workers(client, cases=[{}], base=SHORT)
        assert [len(r["built"]) for r in reports] == [1, 0], reports
        assert "building the slip model" in reports[0]["built"][0]
        libraries = [f.name for f in cache.iterdir() if f.name.startswith("slip_") and f.suffix == ".so"]
        assert len(libraries) == 1, libraries

        # Empty again, then both workers at once: the lock, not the order, keeps it to one build.
        for f in cache.iterdir():
            if f.name.startswith("slip_"):
                f.unlink()
        warmups = cluster.warmup_cases([SHORT])
        futures = [client.submit(cluster._ready_worker, r["worker"], warmups, workers=[r["worker"]], pure=False)
                   for r in reports]
        both = client.gather(futures)
    assert sum(len(r["built"]) for r in both) == 1, both
    # They did ask at once: the other began (and looked in the cache) before the builder had its model, so it
    # found none and waited on the lock (else one build would prove nothing).
    builder, other = sorted(both, key=lambda r: -len(r["built"]))
    assert other["started"] < builder["loaded"], both
    assert len([f for f in cache.iterdir() if f.name.startswith("slip_") and f.suffix == ".so"]) == 1
    assert not [f.name for f in cache.iterdir() if f.name.endswith(".tmp")]
