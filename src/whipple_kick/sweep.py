"""Parameter sweeps of the kick-plate simulation, and a pressure recommender.

:func:`sweep` runs a grid (or an explicit list) of :class:`~whipple_kick.simulation.Scenario`
overrides in parallel and returns one table row per case: every scenario
field, then the run's scalar results flattened from its summary. With a
``folder`` every finished case is saved at once, so an interrupted sweep
resumes where it stopped; docs/sweeps.md describes the folder and the rules.

:func:`recommend_pressure` sweeps a tyre's pressures for one rear load and
returns the pressure with the shortest recovery time (yaw, roll and steer
rates settled; or the thesis' last-peak rule, Section 8.3 and Table 8.9),
with the margin to the second best and whether that margin is clear of the
model's own spread.

Example
-------
>>> from whipple_kick import sweep
>>> table = sweep.sweep({"pressure_kpa": [300, 400, 500], "fz_n": [570, 635, 701]},
...                     folder="thesis_grid")                    # doctest: +SKIP
>>> table.pivot(index="fz_n", columns="pressure_kpa", values="recovery.time_s")  # doctest: +SKIP
"""
import atexit
import concurrent.futures as cf
import dataclasses
import datetime
import hashlib
import itertools
import json
import math
import os
import pathlib
import platform
import socket
import time

import numpy as np

from . import fileio, simulation
from .errors import InputError, check_range

#: Files of a sweep folder.
MANIFEST_FILE = "manifest.json"
LOG_FILE = "cases.jsonl"
TABLE_FILE = "table.csv"
TRAJECTORY_DIR = "trajectories"
#: Version of the folder layout written into the manifest.
FOLDER_FORMAT = 1

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

# Leading table columns, before the scenario fields.
_ID_COLUMNS = ("case_id", "status", "error")
# Summary sections that are not results of the run (the inputs are already
# columns; the units are documented in simulation.UNITS).
_SKIPPED_SECTIONS = ("scenario", "units")


class SweepInterrupted(RuntimeError):
    """Some cases were not run because the executor failed (e.g. its workers died).

    Every case that finished before is saved in the folder; running the same
    sweep on the folder again runs only the missing ones.
    """


# ------------------------------------------------------------------ case identity

def _canonical(value):
    """JSON-stable form of a scenario value: ints and NumPy numbers become floats."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, float, np.integer, np.floating)):
        # 400 and 400.0 (or np.float64(400)) are the same pressure, and must hash alike.
        return float(value)
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return value


def scenario_dict(scenario):
    """Fields of ``scenario`` in canonical JSON-ready form (see :func:`case_id`)."""
    return {f.name: _canonical(getattr(scenario, f.name)) for f in dataclasses.fields(scenario)}


def case_id(scenario):
    """Stable identifier of a case: a hash of its full scenario.

    Two scenarios get the same id exactly when every field is equal (numbers
    compared as floats), whichever overrides produced them. The id does not
    depend on the Python process, the platform or the order of the fields.

    Returns
    -------
    str
        16 hexadecimal digits (the first 64 bits of a SHA-256).
    """
    text = json.dumps(scenario_dict(scenario), sort_keys=True, separators=(",", ":"),
                      allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


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
    return [dict(zip(names, combo)) for combo in itertools.product(*choices)]


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
    base = simulation.Scenario() if base is None else base
    if not isinstance(base, simulation.Scenario):
        raise InputError(f"base must be a whipple_kick.simulation.Scenario, got {type(base).__name__}")
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
            changes = {k: _canonical(v) for k, v in changes.items()}
            scenario = simulation.with_changes(base, **changes)
            out.append((changes, scenario, case_id(scenario)))
    if not out:
        raise InputError("the sweep has no cases")
    return out


def _flat_value(value):
    """A summary value as a table cell, or the sentinel ``_SKIP`` for what is not a scalar."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return _SKIP


_SKIP = object()


def flatten_summary(summary):
    """Scalar results of a :func:`simulation.run` summary as one flat dict.

    The Section 8.3 metrics (``summary["metrics"]``) keep their own names
    (``last_peak_time``, ``damping_ratio_1_3``, ``max_abs_roll``, ...); the
    yaw-rate peak times and values are JSON lists in ``peak_times`` and
    ``peak_values``, the reasons for unavailable metrics a JSON object in
    ``metrics_unavailable``. Every other scalar is named by its path, e.g.
    ``recovery.time_s`` (the recovery time), ``recovery.signals.roll_rate.time_s``,
    ``linear_stability.stable``, ``steady_state.roll_rad``, ``controller.gains.kq4``,
    ``bicycle.rider_mass_kg``, ``numerics.nfev``. Lists elsewhere (the
    closed-loop poles, the tyre notes) are left out.
    """
    flat = {}
    for key, value in summary.get("metrics", {}).items():
        if isinstance(value, list):
            flat[key] = json.dumps(value)
        elif _flat_value(value) is not _SKIP:
            flat[key] = value
    flat["metrics_unavailable"] = json.dumps(summary.get("metrics_unavailable", {}), sort_keys=True)

    def walk(prefix, node):
        for key, value in node.items():
            name = f"{prefix}{key}"
            if isinstance(value, dict):
                walk(name + ".", value)
            elif _flat_value(value) is not _SKIP:
                flat[name] = value

    for key, value in summary.items():
        if key in _SKIPPED_SECTIONS or key in ("metrics", "metrics_unavailable"):
            continue
        if isinstance(value, dict):
            walk(key + ".", value)
        elif _flat_value(value) is not _SKIP:
            flat.setdefault(key, value)   # top-level "fell" equals metrics' "fell"
    return flat


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


def _sampled(df, spec):
    """The trajectory columns of ``spec`` at (about) its rate, the last sample always kept."""
    names = list(df.columns) if spec["columns"] == "all" else list(spec["columns"])
    missing = [n for n in names if n not in df.columns]
    if missing:
        raise InputError(f"trajectory column(s) {missing} do not exist; available: {', '.join(df.columns)}")
    t = df["time"].to_numpy()
    rows = np.arange(t.size)
    if spec["rate_hz"] is not None and t.size > 1:
        # Every k-th sample of the exact solution (no filtering needed: these
        # are values of the solution, not of a noisy signal); the last sample
        # is the end of the run or the fall.
        step = max(1, int(round(1.0 / (spec["rate_hz"] * (t[1] - t[0])))))
        rows = np.union1d(rows[::step], [t.size - 1])
    return {n: df[n].to_numpy()[rows].astype(spec["dtype"]) for n in names}


def run_case(scenario, case_id, trajectory=None):
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

    Returns
    -------
    dict
        ``case_id``, ``status`` ("ok" or "failed"), ``error`` (``"Type: message"``
        or None), ``results`` (flat, :func:`flatten_summary`), ``summary``
        (JSON text), ``trajectory`` ({column: array} or None) and ``run``
        (start/end time stamps, wall time, worker host:pid). A numerical
        failure (:class:`~whipple_kick.simulation.SimulationError`) keeps the
        results, summary and trajectory of the run up to the failure.
    """
    from threadpoolctl import threadpool_limits

    _preload()
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
        with threadpool_limits(limits=1):
            result = simulation.run(scenario)
        _keep(record, result, trajectory)
    except Exception as exc:  # noqa: BLE001 - a failing case must not stop the sweep
        record.update(status="failed", error=f"{type(exc).__name__}: {exc}", results={},
                      summary=None, trajectory=None)
        partial = getattr(exc, "partial", None)   # a numerical failure keeps what ran before it
        if partial is not None:
            _keep(record, partial, trajectory)
    record["run"] = {
        "started": datetime.datetime.fromtimestamp(started, datetime.timezone.utc).isoformat(),
        "finished": datetime.datetime.now(datetime.timezone.utc).isoformat(),
        "wall_s": time.perf_counter() - wall0,
        "cpu_s": time.process_time() - cpu0,   # all threads of the worker process
        "worker": f"{socket.gethostname()}:{os.getpid()}",
    }
    return record


def _keep(record, result, trajectory):
    """Put a run's flat results, summary and (thinned) trajectory into its record."""
    record["results"] = flatten_summary(result.summary)
    record["summary"] = json.dumps(result.summary, allow_nan=False)
    if trajectory is not None:
        record["trajectory"] = _sampled(result.trajectory, trajectory)


# ----------------------------------------------------------------------- the folder

def _versions():
    from importlib import metadata
    out = {"python": platform.python_version(), "platform": platform.platform()}
    for name in ("whipple_kick", "numpy", "scipy", "pandas", "sympy", "pydy", "control", "yeadon"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def read_log(folder):
    """Records of a sweep folder by case id (the last record of a case wins).

    A truncated last line (a crash while writing) is ignored.
    """
    path = pathlib.Path(folder) / LOG_FILE
    records = {}
    if not path.exists():
        return records
    with path.open() as fh:
        for line in fh:
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(rec, dict) and "case_id" in rec:
                records[rec["case_id"]] = rec
    return records


def read_manifest(folder):
    """The manifest of a sweep folder as a dict (None if there is none)."""
    path = pathlib.Path(folder) / MANIFEST_FILE
    return json.loads(path.read_text()) if path.exists() else None


def trajectory_path(folder, case_id):
    """Path of a case's trajectory file in a sweep folder."""
    return pathlib.Path(folder) / TRAJECTORY_DIR / f"{case_id}.npz"


def load_trajectory(folder, case_id):
    """A saved case: (trajectory DataFrame, summary dict)."""
    import pandas as pd
    with np.load(trajectory_path(folder, case_id)) as data:
        summary = json.loads(str(data["summary_json"]))
        columns = [str(c) for c in data["columns"]]
        frame = pd.DataFrame({c: data[c] for c in columns})
    return frame, summary


def _save_trajectory(folder, record):
    traj = record["trajectory"]
    # A file under its final name is always complete; savez wants a name ending in .npz.
    with fileio.atomic_path(trajectory_path(folder, record["case_id"])) as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, columns=np.array(list(traj)), summary_json=np.array(record["summary"]), **traj)


def _table(case_list, records):
    """DataFrame of the finished cases, in the order of the case list."""
    import pandas as pd
    scenario_fields = [f.name for f in dataclasses.fields(simulation.Scenario)]
    rows, seen, result_cols, run_cols = [], set(), {}, {}
    for _, scenario, cid in case_list:
        rec = records.get(cid)
        if rec is None or cid in seen:
            continue
        seen.add(cid)
        row = {"case_id": cid, "status": rec["status"], "error": rec["error"]}
        row.update(scenario_dict(scenario))
        row.update(rec.get("results", {}))
        result_cols.update(dict.fromkeys(rec.get("results", {})))
        for key, value in rec.get("run", {}).items():
            row[f"run.{key}"] = value
            run_cols[f"run.{key}"] = None
        rows.append(row)
    # Ids, the inputs, the results in first-seen order, then how the case ran.
    columns = list(_ID_COLUMNS) + scenario_fields + list(result_cols) + list(run_cols)
    return pd.DataFrame(rows, columns=columns)


def _slim(record):
    """What the log keeps of a record (no trajectory, no full summary)."""
    line = {k: record[k] for k in ("case_id", "status", "error", "results", "run")}
    line["has_trajectory"] = record["trajectory"] is not None
    return line


class _Folder:
    """Manifest, append-only log, table and trajectories of one sweep."""

    def __init__(self, path, case_list, base, extend, trajectory):
        self.path = pathlib.Path(path)
        self.case_list = case_list
        self.path.mkdir(parents=True, exist_ok=True)
        (self.path / TRAJECTORY_DIR).mkdir(exist_ok=True)
        self.model = simulation.model_hash()
        old = read_manifest(self.path)
        ids = [cid for _, _, cid in case_list]
        if old is not None:
            if old.get("model_hash") != self.model:
                raise InputError(
                    f"sweep folder {str(self.path)!r} holds results of model {old.get('model_hash')}, "
                    f"but the model now is {self.model}; use a new folder for the new model")
            old_ids = [c["case_id"] for c in old.get("cases", [])]
            if old_ids != ids:
                if not extend:
                    raise InputError(
                        f"sweep folder {str(self.path)!r} holds a different sweep ({len(old_ids)} cases, "
                        f"{len(set(old_ids) & set(ids))} shared with this one); use a new folder, "
                        "or extend=True (recommend-pressure --extend) to add this sweep's cases to it")
                # Keep the folder's cases first, then the new ones.
                by_id = {cid: (ov, sc, cid) for ov, sc, cid in case_list}
                old_cases = [(c["overrides"], simulation.Scenario(**c["scenario"]), c["case_id"])
                             for c in old["cases"] if c["case_id"] not in by_id]
                self.case_list = old_cases + case_list
        self.manifest = {
            "format": FOLDER_FORMAT,
            "created": (old or {}).get("created", _now()),
            "model_hash": self.model,
            "versions": _versions(),
            "base_scenario": scenario_dict(base),
            "trajectory": None if trajectory is None else {
                **trajectory, "columns": trajectory["columns"] if trajectory["columns"] == "all"
                else list(trajectory["columns"])},
            "files": {"table": TABLE_FILE, "log": LOG_FILE, "trajectories": f"{TRAJECTORY_DIR}/<case_id>.npz"},
            "cases": [{"case_id": cid, "overrides": ov, "scenario": scenario_dict(sc)}
                      for ov, sc, cid in self.case_list],
        }
        self.records = read_log(self.path)
        self._next_table = 0.0

    def write_manifest(self, status, **counts):
        self.manifest.update(status=status, updated=_now(), **counts)
        fileio.write_atomic(self.path / MANIFEST_FILE, json.dumps(self.manifest, indent=1, allow_nan=False) + "\n")

    def add(self, record):
        """Save one finished case: trajectory first, then its log line."""
        if record["trajectory"] is not None:
            _save_trajectory(self.path, record)
        line = _slim(record)
        with (self.path / LOG_FILE).open("a") as fh:
            fh.write(json.dumps(line, allow_nan=False) + "\n")
        self.records[record["case_id"]] = line

    def write_table(self, force=False, interval=1.0):
        # Rewriting the whole CSV is O(rows) (~1 s for 10,000 rows), and the
        # calling process shares the cores with the workers: wait at least
        # ``interval`` and 20x the last write's duration, so the table costs
        # <= 5 % of a core and lags the log by little.
        start = time.monotonic()
        if not force and start < self._next_table:
            return
        table = _table(self.case_list, self.records)
        with fileio.atomic_path(self.path / TABLE_FILE) as tmp:
            table.to_csv(tmp, index=False, float_format="%.12g")
        end = time.monotonic()
        self._next_table = end + max(interval, 20.0 * (end - start))


def _now():
    return datetime.datetime.now(datetime.timezone.utc).isoformat()


# ----------------------------------------------------------------------- the sweep

def sweep(grid=None, cases=None, *, base=None, folder=None, executor=None, workers=None,
          progress=True, trajectory_columns=DEFAULT_TRAJECTORY_COLUMNS, trajectory_dtype="float32",
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
        Where the cases run, e.g. ``dask.distributed.Client(...).get_executor()``;
        it is not shut down. Default: a local process pool of ``workers``,
        kept alive for later sweeps in this process.
    workers : int, optional
        Size of the default process pool (default: one per CPU core, at most
        one per case).
    progress : bool
        Show a tqdm progress bar (on stderr).
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
        results (:func:`flatten_summary`) and ``run.*`` (time stamps, wall time,
        worker). :data:`VOLATILE_COLUMNS` differ between runs of a case.

    Raises
    ------
    InputError
        Unknown field, or a folder holding another sweep or another model.
    SweepInterrupted
        The executor lost cases (e.g. its workers were killed). Finished cases
        are saved; run the sweep again on the folder to complete it.
    """
    case_list = make_cases(grid, cases, base)
    base = simulation.Scenario() if base is None else base
    spec = _trajectory_spec(trajectory_columns, trajectory_dtype, trajectory_rate)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, (int, np.integer))
                                or workers < 1):
        raise InputError(f"workers = {workers!r} must be a whole number >= 1")
    # Loads (or builds) the compiled model here, so forked workers inherit it.
    store = _Folder(folder, case_list, base, extend, spec) if folder is not None else None
    if store is not None:
        case_list = store.case_list
        records = store.records
    else:
        simulation.model_hash()
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
    if store is not None:
        store.write_manifest("running", n_cases=len(unique), n_done=len(unique) - len(todo))

    own = executor is None and todo
    if own:
        executor = _default_pool(workers or os.cpu_count() or 1)
    lost = []
    try:
        _collect(executor, todo, records, store, progress, len(unique), spec, table_interval, lost)
    finally:
        if own and lost:
            _discard_default_pool()
        if store is not None:
            n_ok = sum(1 for cid, _ in unique if records.get(cid, {}).get("status") == "ok")
            n_failed = sum(1 for cid, _ in unique if records.get(cid, {}).get("status") == "failed")
            status = "complete" if n_ok + n_failed == len(unique) else "incomplete"
            store.write_table(force=True)
            store.write_manifest(status, n_cases=len(unique), n_ok=n_ok, n_failed=n_failed,
                                 n_done=n_ok + n_failed)
    if lost:
        where = f"; run the sweep again on {str(store.path)!r} to finish" if store is not None else ""
        raise SweepInterrupted(f"{len(lost)} of {len(unique)} cases were not run: the executor failed "
                               f"({lost[0]}){where}")
    return _table(case_list, records)


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
        _pool = cf.ProcessPoolExecutor(max_workers=n)
        _pool_workers = n
    return _pool


def _discard_default_pool():
    global _pool, _pool_workers
    if _pool is not None:
        _pool.shutdown(wait=False, cancel_futures=True)
    _pool, _pool_workers = None, None


atexit.register(_discard_default_pool)


def _preload():
    """Import what every case needs (~1 s once per process; then free).

    Called before the default pool forks its workers and in every worker.

    With the ``fork`` start method (Linux up to Python 3.13) the workers
    inherit the modules and the loaded compiled model instead of importing
    them each; with other start methods this costs the main process ~1 s.
    """
    from . import analysis, control, integrate, riders, slip, tyres  # noqa: F401
    slip.library()


def _collect(executor, todo, records, store, progress, total, spec, table_interval, lost):
    """Submit ``todo`` to ``executor`` and save each case as it finishes."""
    from tqdm.auto import tqdm

    bar = tqdm(total=total, initial=total - len(todo), disable=not progress, desc="sweep",
               unit="case", dynamic_ncols=True)
    futures = {}
    try:
        for cid, scenario in todo:
            futures[executor.submit(run_case, scenario, cid, spec)] = cid
        n_failed = 0
        for fut in cf.as_completed(futures):
            try:
                record = fut.result()
            except Exception as exc:  # noqa: BLE001 - the executor, not the case, failed
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
                records[record["case_id"]] = _slim(record)
            bar.update(1)
    finally:
        for fut in futures:
            fut.cancel()
        bar.close()


# --------------------------------------------------------------- the pressure recommender

#: Recommender criteria: the table columns ranked, the first deciding, the
#: second breaking ties. ``settling`` (default) is the recovery time of
#: :func:`whipple_kick.analysis.recovery`: the time from which yaw, roll and
#: steer rates all stay within 5 % of their first peaks (``recovery.time_s``).
#: ``last_peak`` is the thesis' rule (time of the last yaw-rate peak above 8 %
#: of the largest, Section 8.3, Table 8.9; ``last_peak_time``).
CRITERIA = {"settling": ("recovery.time_s", "last_peak_time"),
            "last_peak": ("last_peak_time", "recovery.time_s")}
_CRITERION_TEXT = {"last_peak": "last-peak time (last yaw-rate peak above 8 % of the largest, thesis)",
                   "settling": "recovery time (yaw, roll and steer rates within 5 % of their first peaks)"}
#: Spread [s] of each criterion's value, below which a difference between pressures is not to be
#: trusted: the largest change of the value over the nine thesis cases (300/400/500 kPa x
#: 570/635/701 N) when the tyre coefficients change by 1 % (peak, stiffness, curvature, camber
#: and M_z terms one group at a time, all at once, and eight random draws of every coefficient in
#: [0.99, 1.01]) or rtol goes from 1e-10 to 1e-8 or 1e-12 (``scripts/recommender_spread.py``,
#: docs/sweeps.md). Settling: 0.218 s (a random draw at 400 kPa, 570 N); last peak: 0.005 s
#: (a random draw at 300 kPa, 701 N); rtol moves neither by 1 ms. A margin between the best and
#: the second-best pressure below the spread is "no clear optimum". Measured on the default
#: contact-patch tyre transient (model slip_dee09ad7; on the thesis' force lag they were 0.570 and
#: 0.011 s); re-measure when the model changes.
CRITERION_SPREAD_S = {"settling": 0.218, "last_peak": 0.005}


def criterion_key(criterion):
    """The :data:`CRITERIA` key of ``criterion`` (``"last-peak"`` as the CLI spells it is accepted)."""
    key = str(criterion).replace("-", "_")
    if key not in CRITERIA:
        raise InputError(f"criterion = {criterion!r} is unknown; choose one of "
                         f"{', '.join(k.replace('_', '-') for k in CRITERIA)}")
    return key


@dataclasses.dataclass
class Recommendation:
    """Result of :func:`recommend_pressure` for one rear load.

    Attributes
    ----------
    fz_n : float
        Static rear-tyre load [N].
    tyre : str
    best_pressure_kpa : float or None
        Pressure [kPa] ranked first (None if no case recovered or there is nothing to choose).
    best_measured_kpa : float or None
        The same among the measured pressures only.
    criterion : str
        Key of :data:`CRITERIA` the pressures were ranked by.
    margin_s : float or None
        Second-best minus best value of the criterion [s] (None with fewer
        than two pressures that recovered).
    spread_s : float
        :data:`CRITERION_SPREAD_S` of the criterion [s].
    verdict : str
        ``"clear"`` (margin >= spread, or the only pressure that recovered),
        ``"no clear optimum"`` (margin below the spread), ``"nothing to
        choose"`` (one pressure) or ``"none recovered"``.
    table : pandas.DataFrame
        One row per pressure: ``pressure_kpa``, ``measured``,
        ``recovery.time_s`` [s], ``last_peak_time`` [s], the yaw, roll and
        steer rates' settling times [s], ``n_peaks``, ``damping_ratio_1_3``,
        ``period`` [s], ``max_abs_roll`` [rad], ``fell``, ``status``,
        ``error``, ``rank``.
    """

    fz_n: float
    tyre: str
    best_pressure_kpa: float | None
    best_measured_kpa: float | None
    criterion: str
    margin_s: float | None
    spread_s: float
    verdict: str
    table: "object"


def tyre_pressures(tyre="T03", coefficient_set="table7_9"):
    """Measured pressures [kPa] of a tyre's coefficient set."""
    from . import tyres
    files = tyres._tyre_files()
    if tyre not in files:
        raise InputError(f"tyre = {tyre!r} is unknown; choose one of {', '.join(files)}")
    data = tyres.read_tyre_file(files[tyre])
    if coefficient_set not in data.sets:
        raise InputError(f"coefficient_set = {coefficient_set!r} does not exist for tyre {tyre}; "
                         f"choose one of {', '.join(data.sets)}")
    return sorted(float(p) for p in data.sets[coefficient_set])


def pressure_grid(tyre="T03", pressures=None, fine=False, step_kpa=10.0, coefficient_set="table7_9"):
    """Pressures [kPa] to try and which of them were measured.

    Returns
    -------
    pressures : list of float
        Sorted; the measured ones (or ``pressures``), plus with ``fine`` a
        grid of ``step_kpa`` between the smallest and largest measured
        pressure (interpolated tyres, :func:`whipple_kick.tyres.load`).
    measured : set of float
    """
    measured = tyre_pressures(tyre, coefficient_set)
    if pressures is None:
        chosen = measured
    else:
        # Checked here: inside the sweep a bad pressure would only fail its case.
        chosen = sorted({check_range(f"pressure of tyre {tyre}", p, measured[0], measured[-1], "kPa")
                         for p in pressures})
    if not chosen:
        raise InputError("give at least one pressure (kPa)")
    out = set(chosen)
    if fine:
        step = float(step_kpa)
        if not (math.isfinite(step) and step > 0):
            raise InputError(f"pressure step = {step_kpa!r} kPa must be > 0 kPa")
        n = int(math.floor((measured[-1] - measured[0]) / step + 1e-9))
        out.update(round(measured[0] + k * step, 9) for k in range(n + 1))
    return sorted(out), set(measured)


def _did_not_recover(table):
    """Rows that fell or failed (never ranked ahead of a run that did not)."""
    fell = table["fell"].map(lambda v: v is True or _num(v) == 1.0)
    return (fell | (table["status"] != "ok")).to_numpy()


def _rank(table, criterion):
    """Row order: runs that neither fell nor failed first, then by the criterion's columns (missing last)."""
    keys = [np.where(np.isfinite(v), v, np.inf)
            for v in (table[col].map(_num).to_numpy(dtype=float) for col in CRITERIA[criterion])]
    return np.lexsort(keys[::-1] + [_did_not_recover(table)])


def _ranked_values(rows, criterion):
    """(pressures, values) of the rows with a value of the criterion, best first."""
    order = _rank(rows, criterion)
    values = rows[CRITERIA[criterion][0]].map(_num).to_numpy(dtype=float)[order]
    ok = np.isfinite(values) & ~_did_not_recover(rows)[order]
    return rows["pressure_kpa"].to_numpy(dtype=float)[order][ok], values[ok]


def _verdict(rows, criterion):
    """(best pressure, margin, verdict) of one load's rows (see :class:`Recommendation`)."""
    if len(rows) == 1:
        return None, None, "nothing to choose"
    pressures, values = _ranked_values(rows, criterion)
    if not pressures.size:
        return None, None, "none recovered"
    if pressures.size == 1:
        return float(pressures[0]), None, "clear"   # the only pressure that recovered
    margin = float(values[1] - values[0])
    return float(pressures[0]), margin, ("clear" if margin >= CRITERION_SPREAD_S[criterion]
                                         else "no clear optimum")


#: Columns of :attr:`Recommendation.table`.
_RECOMMENDATION_COLUMNS = (
    "pressure_kpa", "measured", "recovery.time_s", "last_peak_time", "recovery.signals.yaw_rate.time_s",
    "recovery.signals.roll_rate.time_s", "recovery.signals.steer_rate.time_s", "n_peaks",
    "damping_ratio_1_3", "period", "max_abs_roll", "fell", "status", "error")


def recommend_pressures(loads, tyre="T03", pressures=None, fine=False, step_kpa=10.0, base=None,
                        criterion="settling", **sweep_options):
    """:func:`recommend_pressure` for several rear loads in one sweep.

    Returns
    -------
    list of Recommendation
        In the order of ``loads``.
    """
    base = simulation.Scenario() if base is None else base
    criterion = criterion_key(criterion)
    loads = [check_range("rear-tyre load fz", f, 0.0, None, "N", low_open=True) for f in loads]
    if not loads:
        raise InputError("give at least one rear load fz (N)")
    grid, measured = pressure_grid(tyre, pressures, fine, step_kpa, base.coefficient_set)
    sweep_options.setdefault("progress", False)
    table = sweep({"fz_n": loads, "pressure_kpa": grid}, base=dataclasses.replace(base, tyre=tyre),
                  **sweep_options)
    out = []
    for fz in loads:
        rows = table[table["fz_n"] == fz].copy()
        rows["measured"] = rows["pressure_kpa"].isin(measured)
        for col in _RECOMMENDATION_COLUMNS:
            if col not in rows:   # every case failed: no result columns at all
                rows[col] = np.nan
        rows = rows[list(_RECOMMENDATION_COLUMNS)].sort_values("pressure_kpa").reset_index(drop=True)
        rows["rank"] = np.argsort(_rank(rows, criterion)) + 1
        best, margin, verdict = _verdict(rows, criterion)
        best_measured = _verdict(rows[rows["measured"]].reset_index(drop=True), criterion)[0]
        out.append(Recommendation(fz, tyre, best, best_measured, criterion, margin,
                                  CRITERION_SPREAD_S[criterion], verdict, rows))
    return out


def recommend_pressure(fz_n, tyre="T03", pressures=None, fine=False, step_kpa=10.0, base=None,
                       criterion="settling", **sweep_options):
    """The inflation pressure with the fastest recovery after a kick, and how sure that is.

    Runs ``base`` (default: the thesis' kick on the default bicycle with a
    rider for ``fz_n`` and the LQR rider) at each pressure and ranks the
    cases by the recovery time (:func:`whipple_kick.analysis.recovery`: yaw,
    roll and steer rates all within 5 % of their first peaks), ties broken by
    the thesis' last-peak time; ``criterion="last_peak"`` ranks by the
    thesis' rule (last yaw-rate peak above 8 % of the largest, Table 8.9)
    instead. A run that fell or failed never ranks ahead of one that did not.
    The margin between the best and the second-best pressure is compared with
    the spread a 1 % change of the tyre coefficients or of the integration
    tolerance produces (:data:`CRITERION_SPREAD_S`): below it the verdict is
    "no clear optimum"; with one pressure there is "nothing to choose".
    docs/sweeps.md compares the result with thesis Table 8.9.

    Parameters
    ----------
    fz_n : float
        Static rear-tyre load [N].
    tyre : str
        Tyre on both wheels (default T03, the kick-plate bicycle's).
    pressures : sequence of float, optional
        Pressures [kPa] to try (default: the tyre's measured ones, T03:
        300, 400, 500). Both tyres get the same pressure, as in the experiment.
    fine : bool
        Add a grid every ``step_kpa`` between the smallest and largest
        measured pressure (tyres interpolated between the measured ones).
    step_kpa : float
        Step of the fine grid [kPa].
    base : Scenario, optional
        Everything else about the run (``fz_n``, ``tyre`` and the pressure
        are set here).
    criterion : {"settling", "last_peak"}
        What "fastest recovery" means (:data:`CRITERIA`; "last-peak" is accepted).
    **sweep_options
        Passed to :func:`sweep` (``folder``, ``extend``, ``executor``,
        ``workers``, ``progress``, ...).

    Returns
    -------
    Recommendation

    Example
    -------
    >>> from whipple_kick import sweep
    >>> rec = sweep.recommend_pressure(635)                  # doctest: +SKIP
    >>> rec.best_pressure_kpa, rec.margin_s, rec.verdict     # doctest: +SKIP
    """
    return recommend_pressures([fz_n], tyre, pressures, fine, step_kpa, base, criterion,
                               **sweep_options)[0]


def _num(value):
    """A table cell as a float (NaN for None, NaN or text)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def format_recommendation(rec):
    """Plain-text table and recommendation of one :class:`Recommendation`."""
    def cell(value, fmt, scale=1.0):
        v = _num(value) * scale
        return fmt.format(v) if math.isfinite(v) else "-"

    column = CRITERIA[rec.criterion][0]
    lines = [f"rear load {rec.fz_n:g} N, tyre {rec.tyre}: recovery after the kick, "
             f"ranked by the {_CRITERION_TEXT[rec.criterion]}",
             f"{'p [kPa]':>8} {'meas.':>5} {'recovery [s]':>12} {'yaw/roll/steer settle [s]':>25} "
             f"{'last peak [s]':>13} {'zeta 1-3':>8} {'max roll [deg]':>14} {'rank':>4}  note"]
    for _, r in rec.table.iterrows():
        if r["status"] != "ok":
            note = f"failed: {r['error']}"
        elif r["fell"] is True or _num(r["fell"]) == 1.0:
            note = "fell"
        elif not math.isfinite(_num(r[column])):
            note = "not recovered"
        else:
            note = "best" if r["pressure_kpa"] == rec.best_pressure_kpa else ""
        settle = "/".join(cell(r[f"recovery.signals.{name}.time_s"], "{:.2f}")
                          for name in ("yaw_rate", "roll_rate", "steer_rate"))
        lines.append(
            f"{r['pressure_kpa']:8g} {'yes' if r['measured'] else '':>5} "
            f"{cell(r['recovery.time_s'], '{:.3f}'):>12} {settle:>25} "
            f"{cell(r['last_peak_time'], '{:.3f}'):>13} {cell(r['damping_ratio_1_3'], '{:.4f}'):>8} "
            f"{cell(r['max_abs_roll'], '{:.2f}', 180.0 / math.pi):>14} {int(r['rank']):4d}  {note}")
    head = f"recommendation for {rec.fz_n:g} N: "
    if rec.verdict == "nothing to choose":
        only = float(rec.table["pressure_kpa"].iloc[0])
        lines.append(head + f"nothing to choose: only {only:g} kPa was run"
                     + (f" ({rec.tyre} was measured at one pressure)" if rec.table["measured"].all() else ""))
    elif rec.verdict == "none recovered":
        lines.append(head + "none (no pressure recovered within the run)")
    else:
        best = rec.table[rec.table["pressure_kpa"] == rec.best_pressure_kpa].iloc[0]
        text = f"{rec.best_pressure_kpa:g} kPa ({_num(best[column]):.3f} s)"
        if rec.margin_s is None:
            text += "; the only pressure that recovered"
        else:
            text += (f", {rec.margin_s:.3f} s ahead of the second best; "
                     f"spread from a 1 % change of the tyre coefficients or of rtol: {rec.spread_s:.3f} s")
            if rec.verdict == "no clear optimum":
                text = f"no clear optimum: {text} (margin below the spread)"
        if rec.best_measured_kpa is not None and rec.best_measured_kpa != rec.best_pressure_kpa:
            text += f"; best measured pressure {rec.best_measured_kpa:g} kPa"
        lines.append(head + text)
    return "\n".join(lines)
