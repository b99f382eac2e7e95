"""Parameter sweeps of the kick-plate simulation: many runs in parallel, one table row per case.

:func:`sweep` runs a grid (or an explicit list) of
:class:`~whipple_kick.simulate.scenario.Scenario` overrides in parallel and returns
one table row per case: every scenario field, then the run's scalar results
flattened from its summary (:func:`whipple_kick.simulate.results.flatten_summary`). With a ``folder``
every finished case is saved at once (:mod:`whipple_kick.studies.sweep_store`), so
an interrupted sweep resumes where it stopped; docs/sweeps.md describes the
folder and the rules. The pressure recommender on top of it is
:mod:`whipple_kick.studies.recommend`.

Example
-------
Skipped as a doctest: nine 6 s kick runs, and the folder ``thesis_grid`` written
into the current folder.

>>> import whipple_kick as wk
>>> table = wk.sweep({"pressure_kpa": [300, 400, 500], "fz_n": [570, 635, 701]},
...                  folder="thesis_grid")                    # doctest: +SKIP
>>> table.pivot(index="fz_n", columns="pressure_kpa", values="recovery.time_s")  # doctest: +SKIP
"""
import atexit
import concurrent.futures as cf
import ctypes
import ctypes.util
import dataclasses
import datetime
import itertools
import json
import os
import signal
import socket
import sys
import time
import warnings

import numpy as np
from threadpoolctl import ThreadpoolController
from tqdm.auto import tqdm

from whipple_kick.errors import DefaultValueWarning, InputError, Terminated, UnstableRiderWarning, terminate_raises
from whipple_kick.library import bicycleparameters
from whipple_kick.model import slip
from whipple_kick.simulate import simulation
from whipple_kick.simulate.results import flatten_summary
from whipple_kick.simulate.scenario import Scenario

from .sweep_store import Folder, canonical, case_id, pack_trajectory, slim, table, trajectory_path

# Summary sections that are not results of the run (the inputs are already
# columns; the units are documented in whipple_kick.simulate.results.UNITS).
#: Trajectory columns saved per case by default: what the thesis' figures and
#: metrics use plus the plate motion and the rear tyre's load, so a case can
#: be re-analysed or plotted without re-running it.
DEFAULT_TRAJECTORY_COLUMNS = (
    "time", "yaw_rate", "roll_rate", "steer_rate", "roll", "steer", "yaw", "y_rear",
    "slip_rear", "slip_front", "fy_rear", "fy_front", "fz_rear", "steer_torque", "plate_y",
)

#: Table columns that describe the run rather than its result (time stamps,
#: wall times, worker): they differ between two runs of the same case.
VOLATILE_COLUMNS = ("run.started", "run.finished", "run.wall_s", "run.cpu_s", "run.worker",
                    "numerics.wall_s", "numerics.integration_wall_s")


#: SIGTERM reached the process running a sweep (the package's :class:`~whipple_kick.errors.Terminated`).
SweepTerminated = Terminated


class SweepFailed(RuntimeError):
    """Every case of a sweep failed: no result to rank or tabulate, so a bug or a broken set-up, not a verdict.

    The message names how many cases failed and the first one's error; a
    sweep folder keeps every case's error in its table and log.
    """


def check_some_ok(table):
    """Raise :class:`SweepFailed` if every case of a sweep's ``table`` failed (one line, the first error)."""
    failed = table["status"] == "failed"
    if len(table) and bool(failed.all()):
        first = table.loc[failed.idxmax()]
        raise SweepFailed(f"all {len(table)} cases failed (a bug or a broken set-up, not a result); the first, "
                          f"case {first['case_id']}, with {first['error']}")


class SweepInterrupted(RuntimeError):
    """Some cases were not run because the executor failed (e.g. its workers died).

    Every case that finished before is saved in the folder; running the same
    sweep on the folder again runs only the missing ones.
    """


def expand_grid(grid):
    """Cartesian product of ``{field: values}`` as a list of override dicts.

    The last field varies fastest. A scalar value counts as a single value
    (a string is one value, not a list of characters).
    """
    if not isinstance(grid, dict):
        raise InputError(f"grid must be a dict {{field: list of values}}, got {type(grid).__name__}")
    names, choices = [], []
    for name, values in grid.items():
        if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
            values = [values]
        values = list(values)
        if not values:
            raise InputError(f"grid field {name!r} has no values")
        names.append(name)
        choices.append(values)
    return [dict(zip(names, combo, strict=True)) for combo in itertools.product(*choices)]


def make_cases(grid=None, cases=None, base=None):
    """The sweep's scenarios: ``[(overrides, scenario, case_id), ...]``.

    Parameters
    ----------
    grid : dict, optional
        ``{field: values}``; every combination is a case.
    cases : list of dict, optional
        Explicit overrides, one dict per case. With ``grid`` as well, every
        case is combined with every grid point.
    base : Scenario, optional
        What the overrides change (default ``Scenario()``).

    Raises
    ------
    InputError
        An override names no Scenario field, or there is no case. (Values are
        not checked here: an invalid value fails only its own case.)
    """
    base = Scenario() if base is None else base
    if not isinstance(base, Scenario):
        raise InputError(f"base must be a whipple_kick.Scenario, got {type(base).__name__}")
    if cases is None:
        overrides = [{}]
    elif isinstance(cases, dict) or isinstance(cases, (str, bytes)):
        raise InputError("cases must be a list of dicts of scenario fields (one dict per case)")
    else:
        overrides = list(cases)
    grid_points = expand_grid(grid) if grid is not None else [{}]
    fields = {f.name for f in dataclasses.fields(base)}
    out = []
    for case in overrides:
        if not isinstance(case, dict):
            raise InputError(f"each case must be a dict of scenario fields, got {case!r}")
        for point in grid_points:
            changes = {**case, **point}
            unknown = sorted(set(changes) - fields)
            if unknown:
                raise InputError(f"unknown scenario field(s) {', '.join(map(repr, unknown))}; "
                                 f"choose from {', '.join(sorted(fields))}")
            changes = {k: canonical(v) for k, v in changes.items()}
            scenario = base.with_changes(**changes)
            out.append((changes, scenario, case_id(scenario)))
    if not out:
        raise InputError("the sweep has no cases")
    return out


def _trajectory_spec(columns, dtype, rate_hz):
    """What :func:`run_case` returns of the trajectory (None: nothing)."""
    if columns is None:
        return None
    if isinstance(columns, str) and columns != "all":
        columns = (columns,)   # one column, not its letters
    if rate_hz is not None and not (isinstance(rate_hz, (int, float)) and rate_hz > 0):
        raise InputError(f"trajectory_rate = {rate_hz!r} Hz must be > 0 Hz (or None for every sample)")
    np.dtype(dtype)   # a bad dtype fails here, not in every case
    return {"columns": columns if columns == "all" else tuple(columns), "dtype": str(np.dtype(dtype)),
            "rate_hz": None if rate_hz is None else float(rate_hz)}


def _sampled(columns, spec):
    """The trajectory columns of ``spec`` at (about) its rate, the last sample always kept.

    ``columns``: the run's columns (:func:`whipple_kick.simulate.results.trajectory_columns`, which refuses
    an unknown name), in the table's order.
    """
    names = list(columns) if spec["columns"] == "all" else list(spec["columns"])
    t = columns["time"]
    rows = slice(None)
    if spec["rate_hz"] is not None and t.size > 1:
        # Every k-th sample of the exact solution (no filtering needed: these
        # are values of the solution, not of a noisy signal); the last sample
        # is the end of the run or the fall (added where the steps miss it: ascending, no repeat).
        step = max(1, int(round(1.0 / (spec["rate_hz"] * (t[1] - t[0])))))
        rows = np.arange(0, t.size, step)
        if rows[-1] != t.size - 1:
            rows = np.append(rows, t.size - 1)
    return {n: columns[n][rows].astype(spec["dtype"]) for n in names}


def run_case(scenario, case_id, trajectory=None, *, packed=False, summary=True):
    """Run one case; never raises for a failing case (the worker function of :func:`sweep`).

    Parameters
    ----------
    scenario : Scenario
    case_id : str
        Passed through into the record.
    trajectory : dict or None
        ``{"columns": names or "all", "dtype": str, "rate_hz": float or None}``:
        the trajectory columns to return, their dtype, and the sampling rate
        they are thinned to (None: every sample). None returns no trajectory.
    packed : bool
        Return the trajectory as the bytes of its sweep-folder file
        (:func:`whipple_kick.studies.sweep_store.pack_trajectory`, compressed here in the worker) instead
        of a dict of arrays.
    summary : bool
        Put the summary's JSON text into the record. A sweep leaves it out of a case that keeps no trajectory:
        what it keeps of such a case is the flat results (:func:`whipple_kick.studies.sweep_store.slim`),
        and the text is only written into a trajectory's file.

    Returns
    -------
    dict
        ``case_id``, ``status`` ("ok" or "failed"), ``error`` (``"Type: message"``
        or None), ``results`` (flat, :func:`flatten_summary`), ``summary``
        (JSON text, or None without ``summary``), ``trajectory`` ({column: array}, its file's bytes, or None) and ``run``
        (start/end time stamps, wall time, worker host:pid). A numerical
        failure (a :class:`~whipple_kick.simulate.results.Result` whose ``success`` is
        False; error ``"SimulationError: <its message>"``, as before) keeps the
        results, summary and trajectory of the run up to the failure.
    """
    _preload()
    _memory_kept_once()
    started = time.time()
    wall0, cpu0 = time.perf_counter(), time.process_time()
    record = {"case_id": case_id, "status": "ok", "error": None, "results": {},
              "summary": None, "trajectory": None}
    try:
        # One BLAS thread: the model's matrices are tiny, and OpenBLAS' helper
        # thread only spins. Measured on a 6 s case: 0.243 s of process CPU
        # for 0.190 s of work without the limit, 0.184 s with it (and the wall
        # time drops alike); with two workers on two cores the spinning also
        # steals the other worker's core. Scoped to the case, so a caller's
        # own process keeps its settings.
        # The table records linear stability (linear_stability.stable, .message): no warning per case. Nor of a
        # BicycleParameters bicycle's defaults: the summary lists them, and the sweep warns once (_warn_defaults).
        with _blas_controller().limit(limits=1), warnings.catch_warnings():
            warnings.simplefilter("ignore", UnstableRiderWarning)
            warnings.simplefilter("ignore", DefaultValueWarning)
            # The lean path: the summary's columns and the kept ones, no trajectory table (the same table row).
            result = simulation.run(scenario, columns=() if trajectory is None else trajectory["columns"])
        _keep(record, result, trajectory, packed, summary)   # a numerical failure keeps what ran before it
        if not result.success:
            record.update(status="failed", error=f"SimulationError: {result.message}")
    except Exception as exc:
        record.update(status="failed", error=f"{type(exc).__name__}: {exc}", results={},
                      summary=None, trajectory=None)
    record["run"] = {
        "started": datetime.datetime.fromtimestamp(started, datetime.timezone.utc).isoformat(),
        "finished": datetime.datetime.now(datetime.timezone.utc).isoformat(),
        "wall_s": time.perf_counter() - wall0,
        "cpu_s": time.process_time() - cpu0,   # all threads of the worker process
        "worker": f"{socket.gethostname()}:{os.getpid()}",
    }
    return record


def _warn_defaults(scenarios):
    """The defaults warning (DefaultValueWarning) of each BicycleParameters bicycle the cases name, here, once per
    bicycle (identical texts once): each case ignores it (:func:`run_case`), where it came once per case and
    worker (the uncertainty study's hundreds of sampled bicycles, all with the same ~600-character text)."""
    for name in dict.fromkeys(str(sc.bicycle) for sc in scenarios):
        if bicycleparameters.is_bicycleparameters_path(name):
            try:
                bicycleparameters.load_bicycle(name)
            except InputError:
                pass   # each of its cases fails, and its record says why


_blas = (None, -1)   # (threadpoolctl controller, len(sys.modules) when it looked)


def _blas_controller():
    """The process' threadpoolctl controller, looked for again only after new imports.

    Finding the BLAS libraries a process has loaded takes ~1.2 ms, setting
    their thread count ~10 us; libraries come with imports, so a count of
    ``sys.modules`` that has not changed means the same libraries.
    """
    global _blas

    controller, seen = _blas
    if seen != len(sys.modules):
        controller = ThreadpoolController()
        _blas = (controller, len(sys.modules))
    return controller


def _keep(record, result, trajectory, packed=False, summary=True):
    """Put a run's flat results, summary (``summary``, or a trajectory's file, needing it) and (thinned, or packed
    into its file) trajectory into its record."""
    record["results"] = flatten_summary(result.summary)
    if summary or trajectory is not None:
        record["summary"] = json.dumps(result.summary, allow_nan=False)
    if trajectory is not None:
        record["trajectory"] = _sampled(result.trajectory, trajectory)
        if packed:
            record["trajectory"] = pack_trajectory(record["trajectory"], record["summary"])


# ----------------------------------------------------------------------- the sweep

def sweep(grid=None, cases=None, *, base=None, folder=None, executor=None, workers=None,
          progress=None, trajectory_columns=DEFAULT_TRAJECTORY_COLUMNS, trajectory_dtype="float32",
          trajectory_rate=200.0, retry_failed=False, extend=False, table_interval=1.0):
    """Run many kick-plate cases in parallel and tabulate them.

    Parameters
    ----------
    grid : dict, optional
        ``{scenario field: values}``; every combination is a case, e.g.
        ``{"pressure_kpa": [300, 400, 500], "fz_n": [570, 635, 701]}``.
    cases : list of dict, optional
        Explicit overrides, one dict per case (combined with ``grid`` if both).
    base : Scenario, optional
        The scenario the overrides change (default ``Scenario()``).
    folder : path-like, optional
        Sweep folder: finished cases are saved as they come (manifest, log,
        ``table.csv``, one trajectory file per case) and an existing folder of
        the same sweep is resumed. Without it nothing is written.
    executor : concurrent.futures.Executor, optional
        Where the cases run, e.g. ``dask.distributed.Client(...).get_executor()``
        (readied first by :func:`whipple_kick.studies.cluster.prepare_workers`);
        it is not shut down. Default: a local process pool of ``workers``,
        kept alive for later sweeps in this process.
    workers : int, optional
        Size of the default process pool (default: one per CPU core, at most
        one per case).
    progress : bool or None
        Show a tqdm progress bar on stderr; None (default): only when stderr
        is a terminal.
    trajectory_columns : sequence of str, "all" or None
        Trajectory columns saved per case (with ``folder``); None saves none.
    trajectory_dtype : str
        dtype of the saved trajectories (default float32: about 7 significant
        digits, half the size).
    trajectory_rate : float or None
        Rate [Hz] the saved trajectories are thinned to (default 200 Hz, like
        the regression references: ~60 kB per 6 s case instead of ~300 kB at
        the scenario's 1000 Hz; the table's metrics always come from the full
        output). None keeps every sample.
    retry_failed : bool
        Run again the cases that failed in an earlier run on the folder.
    extend : bool
        Allow a folder holding a different sweep: add this sweep's cases to it.
    table_interval : float
        Least time [s] between two rewrites of ``table.csv`` during the sweep
        (also at least 20x the last rewrite's duration; always written at the end).

    Returns
    -------
    pandas.DataFrame
        One row per case, in case order (duplicates once): ``case_id``,
        ``status`` ("ok"/"failed"), ``error``, every Scenario field, the flat
        results (:func:`whipple_kick.simulate.results.flatten_summary`) and ``run.*`` (time stamps, wall time,
        worker). :data:`VOLATILE_COLUMNS` differ between runs of a case.

    Raises
    ------
    InputError
        Unknown field, or a folder holding another sweep or another model.
    SweepInterrupted
        The executor lost cases (e.g. its workers were killed). Finished cases
        are saved; run the sweep again on the folder to complete it.
    KeyboardInterrupt, SweepTerminated
        Ctrl-C or SIGTERM: the default pool's workers are ended, finished
        cases are saved and the manifest's status is ``interrupted``.
    """
    case_list = make_cases(grid, cases, base)
    base = Scenario() if base is None else base
    if progress is None:
        progress = sys.stderr.isatty()
    spec = _trajectory_spec(trajectory_columns, trajectory_dtype, trajectory_rate)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, (int, np.integer))
                                or workers < 1):
        raise InputError(f"workers = {workers!r} must be a whole number >= 1")
    # Loads (or builds) the compiled model here, so forked workers inherit it.
    store = Folder(folder, case_list, base, extend, spec) if folder is not None else None
    if store is not None:
        case_list = store.case_list
        records = store.records
    else:
        slip.model_hash()   # loads (or builds) the compiled model here, so forked workers inherit it
        records = {}

    def finished(cid):
        rec = records.get(cid)
        if rec is None or (rec["status"] == "failed" and retry_failed):
            return False
        if (rec["status"] == "ok" and spec is not None and store is not None
                and not trajectory_path(store.path, cid).exists()):
            return False
        return True

    unique = list({cid: sc for _, sc, cid in case_list}.items())
    todo = [(cid, sc) for cid, sc in unique if not finished(cid)]
    _warn_defaults(sc for _, sc in todo)
    lost, interrupted, own = [], False, False
    try:
        with terminate_raises():
            if store is not None:
                store.write_manifest("running", n_cases=len(unique), n_done=len(unique) - len(todo))
            own = executor is None and todo
            if own:
                executor = _default_pool(workers or os.cpu_count() or 1)
            try:
                # Without a folder no trajectory is kept: the workers make none.
                _collect(executor, todo, records, store, progress, len(unique), spec if store is not None else None,
                         table_interval, lost)
            except (KeyboardInterrupt, SweepTerminated):
                interrupted = True
                if own:
                    _discard_default_pool(end_workers=True)   # no worker outlives the sweep
                raise
            finally:
                if own and lost:
                    _discard_default_pool()
    finally:
        if store is not None:
            n_ok = sum(1 for cid, _ in unique if records.get(cid, {}).get("status") == "ok")
            n_failed = sum(1 for cid, _ in unique if records.get(cid, {}).get("status") == "failed")
            status = ("complete" if n_ok + n_failed == len(unique)
                      else "interrupted" if interrupted else "incomplete")
            try:
                store.write_table(force=True)
                store.write_manifest(status, n_cases=len(unique), n_ok=n_ok, n_failed=n_failed,
                                     n_done=n_ok + n_failed)
            finally:
                store.close()
    if lost:
        where = f"; run the sweep again on {str(store.path)!r} to finish" if store is not None else ""
        raise SweepInterrupted(f"{len(lost)} of {len(unique)} cases were not run: the executor failed "
                               f"({lost[0]}){where}")
    return table(case_list, records)


_pool = None          # the default executor, kept between sweeps in this process
_pool_workers = None


def _default_pool(n):
    """The process pool sweeps use when no executor is given, kept alive between sweeps.

    Starting a pool and warming each worker (imports, compiled model, rider
    and LQR caches) costs about as much as a case; a researcher running
    sweep after sweep in one session pays it once. A broken pool (a worker
    died) or a different worker count gets a fresh one.
    """
    global _pool, _pool_workers
    if _pool is not None and (_pool_workers != n or getattr(_pool, "_broken", False)):
        _discard_default_pool()
    if _pool is None:
        _preload()
        _pool = cf.ProcessPoolExecutor(max_workers=n, initializer=_worker_start)
        _pool_workers = n
    return _pool


def _worker_start():
    """In each pool worker: SIGTERM ends it (a worker forked during a sweep inherits the sweep's handler),
    and its freed memory stays with it (:func:`_keep_freed_memory`)."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _memory_kept_once()


_memory_kept = None   # this process' _keep_freed_memory() result, once it ran (None: not yet)


def _memory_kept_once():
    """:func:`_keep_freed_memory` once per process, from the first case it runs.

    The default pool's workers set it when they start (:func:`_worker_start`); a worker of another executor
    (a Dask cluster's, whose nanny sets glibc's opposite, ``MALLOC_TRIM_THRESHOLD_=65536``) gets it from its
    first case, or before it from :func:`whipple_kick.studies.cluster.prepare_workers`. Results are unchanged.
    """
    global _memory_kept
    if _memory_kept is None:
        _memory_kept = _keep_freed_memory()
    return _memory_kept


#: glibc's mallopt parameters (malloc.h) and the values a worker sets.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
_KEEP_TRIM_BYTES, _KEEP_MMAP_BYTES = 1 << 30, 1 << 26


def _keep_freed_memory():
    """Let this process reuse the memory it frees instead of handing it back to the system (glibc only).

    A case allocates and frees tens of MB in arrays of a few MB (the samples, the outputs, the table);
    by default glibc maps each such array afresh and unmaps it when freed, so every case pays a page fault
    per 4 kB touched: about 2400 faults and 10 ms of system time per 6 s case measured here (the
    integration itself is about 100 ms). Arrays up to 64 MB now come from the heap and a freed heap is
    kept up to 1 GB, so the next case writes into pages already mapped. Results are unchanged (only
    where the bytes live changes). Elsewhere (no glibc) nothing is done. Returns whether it was set.
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):   # not glibc (musl has no mallopt)
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return bool(mallopt(_M_MMAP_THRESHOLD, _KEEP_MMAP_BYTES)) and bool(mallopt(_M_TRIM_THRESHOLD, _KEEP_TRIM_BYTES))


def _discard_default_pool(end_workers=False):
    """Drop the default pool; ``end_workers`` also ends its worker processes (SIGTERM) instead of
    letting them finish the cases they run."""
    global _pool, _pool_workers
    if _pool is not None:
        workers = list((getattr(_pool, "_processes", None) or {}).values()) if end_workers else []
        _pool.shutdown(wait=False, cancel_futures=True)
        for process in workers:
            process.terminate()
        for process in workers:
            process.join(timeout=10)
    _pool, _pool_workers = None, None


atexit.register(_discard_default_pool)


def _preload():
    """Import what every case needs (~1 s once per process; then free).

    Called before the default pool forks its workers and in every worker.

    With the ``fork`` start method (Linux up to Python 3.13) the workers
    inherit the modules and the loaded compiled model instead of importing
    them each; with other start methods this costs the main process ~1 s.
    """
    slip.library()


def _collect(executor, todo, records, store, progress, total, spec, table_interval, lost):
    """Submit ``todo`` to ``executor`` and save each case as it finishes."""
    bar = tqdm(total=total, initial=total - len(todo), disable=not progress, desc="sweep",
               unit="case", dynamic_ncols=True)
    futures = {}
    try:
        for cid, scenario in todo:
            # A case without trajectory: the parent keeps its flat results alone (slim), no summary text (a kept
            # trajectory's file holds its summary all the same: _keep).
            futures[executor.submit(run_case, scenario, cid, spec, packed=True, summary=False)] = cid
        n_failed = 0
        for fut in cf.as_completed(futures):
            try:
                record = fut.result()
            except Exception as exc:
                # Not recorded: a resumed sweep runs this case again.
                lost.append(f"{type(exc).__name__}: {exc}")
                continue
            if record["status"] == "failed":
                n_failed += 1
                bar.set_postfix(failed=n_failed)
            if store is not None:
                store.add(record)   # also enters the slim record into ``records``
                store.write_table(interval=table_interval)
            else:
                records[record["case_id"]] = slim(record)
            bar.update(1)
    finally:
        for fut in futures:
            fut.cancel()
        bar.close()


