"""The sweep folder: a manifest, an append-only log of finished cases, the table and one trajectory file per case.

A sweep (:func:`whipple_kick.studies.sweep_engine.sweep`) with a ``folder`` saves
every finished case at once through :class:`Folder`, so an interrupted
sweep resumes where it stopped; docs/sweeps.md describes the folder and its
rules. A case is identified by a hash of its full scenario (:func:`case_id`),
whatever overrides produced it. Files are written atomically
(:mod:`whipple_kick.fileio`); the log is appended one line per case and a
truncated last line (a crash while writing) is ignored when read back, and
ended with a newline when the folder is opened again.

Example
-------
Skipped as a doctest: it needs the sweep folder of :mod:`whipple_kick.studies.sweep_engine`'s
example and one of its case ids.

>>> from whipple_kick import sweep_store
>>> frame, summary = sweep_store.load_trajectory("thesis_grid", case_id)   # doctest: +SKIP
"""
import dataclasses
import datetime
import hashlib
import io
import json
import os
import pathlib
import time

import numpy as np
import pandas as pd

from whipple_kick import fileio
from whipple_kick.errors import InputError
from whipple_kick.model import slip
from whipple_kick.simulate import provenance
from whipple_kick.simulate.scenario import Scenario

#: Files of a sweep folder.
MANIFEST_FILE = "manifest.json"
LOG_FILE = "cases.jsonl"
TABLE_FILE = "table.csv"
TRAJECTORY_DIR = "trajectories"
#: Held (flock) by the process running a sweep on the folder; holds its pid.
LOCK_FILE = "sweep.lock"
#: Version of the folder layout written into the manifest (2: the code hash and the provenance of every session).
FOLDER_FORMAT = 2

# Leading table columns, before the scenario fields.
_ID_COLUMNS = ("case_id", "status", "error")



# ------------------------------------------------------------------ case identity

def canonical(value):
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
    return {f.name: canonical(getattr(scenario, f.name)) for f in dataclasses.fields(scenario)}


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


# ----------------------------------------------------------------------- the folder

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
    with np.load(trajectory_path(folder, case_id)) as data:
        summary = json.loads(str(data["summary_json"]))
        columns = [str(c) for c in data["columns"]]
        frame = pd.DataFrame({c: data[c] for c in columns})
    return frame, summary


def pack_trajectory(trajectory, summary_json):
    """A case's trajectory file (what :func:`load_trajectory` reads) as bytes: compressed columns and the summary.

    A sweep's workers pack their own cases' files (:func:`whipple_kick.studies.sweep_engine.run_case`), so the
    compression, ~7 ms a case, is spread over the workers instead of capping the process that saves them
    (the parent capped at ~105 cases/s when it compressed them).

    Parameters
    ----------
    trajectory : dict
        ``{column: 1-D array}``, in the order :func:`load_trajectory` gives them back.
    summary_json : str
        The run's summary as JSON text.
    """
    buffer = io.BytesIO()
    np.savez_compressed(buffer, columns=np.array(list(trajectory)), summary_json=np.array(summary_json), **trajectory)
    return buffer.getvalue()


def _save_trajectory(folder, record):
    """Write a record's trajectory file: its packed bytes (:func:`pack_trajectory`), or its columns packed here."""
    traj = record["trajectory"]
    data = traj if isinstance(traj, bytes) else pack_trajectory(traj, record["summary"])
    # A file under its final name is always complete.
    fileio.write_atomic(trajectory_path(folder, record["case_id"]), data)


def table(case_list, records):
    """DataFrame of the finished cases, in the order of the case list."""
    scenario_fields = [f.name for f in dataclasses.fields(Scenario)]
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


def slim(record):
    """What the log keeps of a record (no trajectory, no full summary)."""
    line = {k: record[k] for k in ("case_id", "status", "error", "results", "run")}
    line["has_trajectory"] = record["trajectory"] is not None
    return line


def _lock(folder):
    """Take the folder's sweep lock (:func:`whipple_kick.fileio.take_lock` on :data:`LOCK_FILE`).

    Raises
    ------
    InputError
        Another process holds the lock (one line naming its pid).
    """
    return fileio.take_lock(pathlib.Path(folder) / LOCK_FILE,
                            f"sweep folder {str(folder)!r} is in use by another sweep (process {{pid}}, "
                            f"{LOCK_FILE}); wait for it to finish, then run again to resume")


class Folder:
    """Manifest, append-only log, table and trajectories of one sweep.

    Creating one takes the folder's lock (:func:`_lock`): a second sweep on
    the same folder is refused while the first runs. :meth:`close` releases it.
    """

    def __init__(self, path, case_list, base, extend, trajectory):
        self.path = pathlib.Path(path)
        self.case_list = case_list
        self.path.mkdir(parents=True, exist_ok=True)
        self._lock_fd = _lock(self.path)
        try:
            self._open(case_list, base, extend, trajectory)
        except BaseException:
            self.close()
            raise

    def close(self):
        """Release the folder's lock (idempotent)."""
        if self._lock_fd is not None:
            fileio.release_lock(self._lock_fd)
            self._lock_fd = None

    def _open(self, case_list, base, extend, trajectory):
        (self.path / TRAJECTORY_DIR).mkdir(exist_ok=True)
        self.model = slip.model_hash()
        self.code = provenance.code_hash()
        old = read_manifest(self.path)
        ids = [cid for _, _, cid in case_list]
        if old is not None:
            _check_same_code(self.path, old, self.model, self.code)
            old_ids = [c["case_id"] for c in old.get("cases", [])]
            if old_ids != ids:
                if not extend:
                    raise InputError(
                        f"sweep folder {str(self.path)!r} holds a different sweep ({len(old_ids)} cases, "
                        f"{len(set(old_ids) & set(ids))} shared with this one); use a new folder, "
                        "or extend=True (recommend-pressure --extend) to add this sweep's cases to it")
                # Keep the folder's cases first, then the new ones.
                by_id = {cid: (ov, sc, cid) for ov, sc, cid in case_list}
                old_cases = [(c["overrides"], Scenario(**c["scenario"]), c["case_id"])
                             for c in old["cases"] if c["case_id"] not in by_id]
                self.case_list = old_cases + case_list
        session = provenance.record(provenance.input_files(base))
        self.manifest = {
            "format": FOLDER_FORMAT,
            "created": (old or {}).get("created", _now()),
            "model_hash": self.model,
            "code_hash": self.code,
            # Where the folder's first cases came from; every later session (a resume, an extension) is added
            # to "sessions", never written over it (the code hash above is the same for all of them).
            "provenance": (old or {}).get("provenance", session),
            "sessions": [*(old or {}).get("sessions", []), session],
            "base_scenario": scenario_dict(base),
            "trajectory": None if trajectory is None else {
                **trajectory, "columns": trajectory["columns"] if trajectory["columns"] == "all"
                else list(trajectory["columns"])},
            "files": {"table": TABLE_FILE, "log": LOG_FILE, "trajectories": f"{TRAJECTORY_DIR}/<case_id>.npz"},
            "cases": [{"case_id": cid, "overrides": ov, "scenario": scenario_dict(sc)}
                      for ov, sc, cid in self.case_list],
        }
        _terminate_last_line(self.path / LOG_FILE)
        self.records = read_log(self.path)
        self._next_table = 0.0

    def write_manifest(self, status, **counts):
        self.manifest.update(status=status, updated=_now(), **counts)
        fileio.write_atomic(self.path / MANIFEST_FILE, json.dumps(self.manifest, indent=1, allow_nan=False) + "\n")

    def add(self, record):
        """Save one finished case: trajectory first, then its log line."""
        if record["trajectory"] is not None:
            _save_trajectory(self.path, record)
        line = slim(record)
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
        rows = table(self.case_list, self.records)
        fileio.write_csv(rows, self.path / TABLE_FILE, significant_digits=12)
        end = time.monotonic()
        self._next_table = end + max(interval, 20.0 * (end - start))


def _check_same_code(path, old, model, code):
    """Refuse to resume a folder whose results other code made (one line saying what to do).

    A resumed sweep's table would otherwise mix the results of two versions
    of the code (say two recovery rules) without a word.
    """
    where = f"sweep folder {str(path)!r}"
    if old.get("format") != FOLDER_FORMAT or "code_hash" not in old:
        raise InputError(f"{where} was made by an earlier version of whipple_kick (folder format "
                         f"{old.get('format')}, no code hash): its results cannot be told to be this code's; "
                         "use a new folder")
    if old["model_hash"] != model:
        raise InputError(f"{where} holds results of model {old['model_hash']}, but the model now is {model}; "
                         "use a new folder for the new model")
    if old["code_hash"] != code:
        raise InputError(f"{where} holds results of other code (code hash {old['code_hash']}, now {code}: the "
                         "Python or parameter files that make results changed since it was started); use a new "
                         "folder for this code, or finish the sweep with the code that started it")


def _terminate_last_line(path):
    """End a log cut short mid-line (a crash while appending) with a newline.

    The cut line stays unreadable (and is ignored); without the newline the
    next record appended would be glued to it and lost with it.
    """
    if not path.exists() or path.stat().st_size == 0:
        return
    with path.open("rb+") as fh:
        fh.seek(-1, os.SEEK_END)
        if fh.read(1) != b"\n":
            fh.write(b"\n")


def _now():
    return datetime.datetime.now(datetime.timezone.utc).isoformat()


