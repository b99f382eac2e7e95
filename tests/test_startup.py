"""Start-up cost of ``simulate``: the on-disk LQR design cache and the exact, fast trajectory CSV.

python-control's import costs over a second, so a design is solved once and
kept in the per-user cache (``control.cached_lqr_gains``); a warm ``simulate``
must not import python-control at all. ``trajectory.csv`` is written with each
float's ``repr`` so that reading it back gives the identical float64 table.
No timings here (see ``scripts/bench.py cli``).
"""
import io
import json
import os
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import whipple_kick as wk
from whipple_kick import cache, control, simulation
from whipple_kick.cli import simulate_main, write_trajectory_csv


@pytest.fixture(scope="module")
def design():
    """The LQR design parameters of the main job (balanceassist_v1 + Yeadon rider for 635 N)."""
    _, design, _ = simulation.build_bicycle(simulation.Scenario(fz_n=635.0))
    return design


@pytest.fixture
def private_cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("WHIPPLE_KICK_CACHE", str(folder))
    return folder


def _no_solver(monkeypatch):
    """Make any python-control solve fail, so a result can only come from the disk cache."""
    def refuse(*args, **kwargs):
        raise AssertionError("solved again although the design is cached")
    monkeypatch.setattr(control, "lqr_gains", refuse)


def _entries(folder):
    return sorted(folder.glob("lqr_*.json"))


# ------------------------------------------------------------- LQR design cache

def test_cached_gains_equal_a_fresh_python_control_solve(design, private_cache, monkeypatch):
    K0, poles0 = control.lqr_gains(design, 3.0)
    K1, poles1 = control.cached_lqr_gains(design, 3.0)      # miss: solved and stored
    assert len(_entries(private_cache)) == 1
    _no_solver(monkeypatch)
    K2, poles2 = control.cached_lqr_gains(design, 3.0)      # hit: read from disk
    for K in (K1, K2):
        np.testing.assert_allclose(K, K0, rtol=1e-12, atol=0)
    for poles in (poles1, poles2):
        np.testing.assert_allclose(poles, poles0, rtol=1e-12, atol=0)
    # JSON floats are written with repr: the stored design is the solve, bit for bit.
    assert np.array_equal(K2, K0) and np.array_equal(poles2, np.asarray(poles0, dtype=complex))


def test_cache_key_is_what_the_design_depends_on(design, private_cache, monkeypatch, tmp_path):
    name = control.lqr_cache_key(design, 3.0)[0]
    assert name == control.lqr_cache_key(dict(reversed(list(design.items()))), 3.0)[0]
    assert name == control.lqr_cache_key({**design, "not_read_by_the_design": 1.0}, 3.0)[0]
    assert name == control.lqr_cache_key(design, 3.0, Q=np.eye(4), R=1.0)[0]
    changed = [
        control.lqr_cache_key(design, np.nextafter(3.0, 4.0))[0],
        control.lqr_cache_key({**design, "mc": np.nextafter(design["mc"], 0.0)}, 3.0)[0],  # last bit
        control.lqr_cache_key(design, 3.0, R=10.0)[0],
        control.lqr_cache_key(design, 3.0, Q=np.diag([10.0, 1.0, 1.0, 1.0]))[0],
    ]
    # A change to the package source (control.py here) or the solver libraries misses too.
    copy = tmp_path / "pkg"
    shutil.copytree(cache._PACKAGE_DIR, copy, ignore=shutil.ignore_patterns("__pycache__"))
    with open(copy / "control.py", "a") as fh:
        fh.write("\n# edited\n")
    with monkeypatch.context() as patch:
        patch.setattr(cache, "_PACKAGE_DIR", copy)
        changed.append(control.lqr_cache_key(design, 3.0)[0])
    with monkeypatch.context() as patch:
        patch.setattr(control, "_solver_versions", lambda: "control 99.0")
        changed.append(control.lqr_cache_key(design, 3.0)[0])
    assert len({name, *changed}) == 1 + len(changed)
    assert {"control", "classic"} <= set(control._LQR_SOURCES)


CORRUPTIONS = {
    "garbage": lambda p: p.write_bytes(b"\x00\xff not json"),
    "truncated": lambda p: p.write_text(p.read_text()[: len(p.read_text()) // 2]),
    "empty": lambda p: p.write_text(""),
    "wrong shape": lambda p: p.write_text('{"key": {}, "gains": 1}'),
    "other design": lambda p: p.write_text(p.read_text().replace('"speed": "3.0"', '"speed": "4.0"')),
    "non-finite gain": lambda p: _edit_gains(p, lambda g: [float("nan")] + g[1:]),
    "three gains": lambda p: _edit_gains(p, lambda g: g[:3]),
    "writable by others": lambda p: p.chmod(0o666),
    "a folder": lambda p: (p.unlink(), p.mkdir()),
}


def _edit_gains(path, edit):
    data = json.loads(path.read_text())
    data["gains"] = edit(data["gains"])
    path.write_text(json.dumps(data))


@pytest.mark.parametrize("how", list(CORRUPTIONS))
def test_corrupt_entry_is_solved_again_and_replaced(how, design, private_cache, monkeypatch):
    K0, poles0 = control.cached_lqr_gains(design, 3.0)
    (path,) = _entries(private_cache)
    CORRUPTIONS[how](path)
    if how == "a folder":
        # Not replaceable by a rename: still no crash, the design is solved in memory.
        K, poles = control.cached_lqr_gains(design, 3.0)
        np.testing.assert_allclose(K, K0, rtol=1e-12, atol=0)
        return
    K, poles = control.cached_lqr_gains(design, 3.0)
    np.testing.assert_allclose(K, K0, rtol=1e-12, atol=0)
    np.testing.assert_allclose(poles, poles0, rtol=1e-12, atol=0)
    assert path.stat().st_mode & 0o777 == 0o600
    _no_solver(monkeypatch)                                  # the entry was rewritten whole
    K, poles = control.cached_lqr_gains(design, 3.0)
    assert np.array_equal(K, K0) and np.array_equal(poles, poles0)


def test_unreadable_entry_is_solved_again(design, private_cache, monkeypatch):
    K0, _ = control.cached_lqr_gains(design, 3.0)
    (path,) = _entries(private_cache)
    path.chmod(0)                     # unreadable, except for root: make reading fail for root too
    real_read = pathlib.Path.read_text

    def read_text(self, *args, **kwargs):
        if self.name.startswith("lqr_"):
            raise PermissionError(13, "Permission denied", str(self))
        return real_read(self, *args, **kwargs)

    with monkeypatch.context() as patch:
        patch.setattr(pathlib.Path, "read_text", read_text)
        K, _ = control.cached_lqr_gains(design, 3.0)
    np.testing.assert_allclose(K, K0, rtol=1e-12, atol=0)
    assert path.stat().st_mode & 0o777 == 0o600       # replaced by a readable entry


def test_bad_design_input_is_still_an_input_error(design, private_cache):
    with pytest.raises(wk.errors.InputError, match="speed"):
        control.cached_lqr_gains(design, 0.0)
    with pytest.raises(wk.errors.InputError, match="4x4"):
        control.cached_lqr_gains(design, 3.0, Q=np.eye(3))
    with pytest.raises(wk.errors.InputError, match="missing"):
        control.cached_lqr_gains({k: v for k, v in design.items() if k != "mc"}, 3.0)
    assert not _entries(private_cache)


_PROBE = """
import sys
from whipple_kick.cli import simulate_main
try:
    simulate_main(["--duration", "0.2", "--no-plot", "--quiet", "--out", sys.argv[1]])
except SystemExit as exc:
    assert exc.code == 0, exc.code
print("control" in sys.modules)
"""


def test_warm_simulate_does_not_import_python_control(tmp_path):
    """The first run solves the design (imports python-control); the next one reads it from the cache."""
    from whipple_kick import slip
    slip.library()                                            # the compiled model, built if needed
    folder = tmp_path / "cache"
    folder.mkdir(mode=0o700)
    for entry in cache.cache_dir().iterdir():                 # generated code, but no LQR designs
        if entry.is_file() and not entry.name.startswith(("lqr_", ".")) and not entry.name.endswith(".lock"):
            shutil.copy2(entry, folder / entry.name)
    env = dict(os.environ, WHIPPLE_KICK_CACHE=str(folder))

    def imported_control(out):
        done = subprocess.run([sys.executable, "-c", _PROBE, str(tmp_path / out)], env=env,
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr
        return done.stdout.split()[-1] == "True"

    assert imported_control("cold")                           # the test can see the import
    assert len(_entries(folder)) == 1
    assert not imported_control("warm")


# ------------------------------------------------------------------ trajectory.csv

def _bits(frame):
    return frame.to_numpy(dtype=np.float64).view(np.int64)


def test_trajectory_csv_reads_back_bit_for_bit(tmp_path, capsys, monkeypatch):
    """The CLI's trajectory.csv is the run's DataFrame exactly: columns, order, every bit."""
    runs = []
    real_run = simulation.run
    monkeypatch.setattr(simulation, "run", lambda scenario: runs.append(real_run(scenario)) or runs[-1])
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as status:
        simulate_main(["--duration", "0.5", "--no-plot", "--quiet", "--out", str(out)])
    assert status.value.code == 0, capsys.readouterr().err
    frame = runs[0].trajectory
    text = (out / "trajectory.csv").read_text()
    assert text.splitlines()[0] == ",".join(frame.columns)   # the header pandas writes
    back = pd.read_csv(out / "trajectory.csv")
    assert list(back.columns) == list(frame.columns)
    assert (back.dtypes == np.float64).all()
    assert np.array_equal(_bits(back), _bits(frame))


def test_csv_writer_is_exact_for_awkward_floats(tmp_path):
    rng = np.random.default_rng(0)
    raw = rng.integers(0, 2**63 - 1, size=2000, dtype=np.int64).view(np.float64)
    raw = raw[np.isfinite(raw)]
    special = np.array([0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 1.7976931348623157e308,
                        -1.7976931348623157e308, 0.1 + 0.2, np.nextafter(1.0, 2.0), 1e16, 123456789012345678.0,
                        1 / 3, -2.5, 1.0])
    n = len(special)
    frame = pd.DataFrame({
        "time": np.arange(n) * 1e-3,
        "random": raw[:n],
        "special": special,
        "zeros": np.zeros(n),                                  # must stay a float column
        "negative zeros": np.full(n, -0.0),
        "whole": np.arange(n, dtype=float),
    })
    path = tmp_path / "t.csv"
    write_trajectory_csv(frame, path)
    back = pd.read_csv(path)
    assert list(back.columns) == list(frame.columns) and (back.dtypes == np.float64).all()
    assert np.array_equal(_bits(back), _bits(frame))
    reference = io.StringIO()
    frame.to_csv(reference, index=False, lineterminator="\n")
    assert path.read_text().splitlines()[0] == reference.getvalue().splitlines()[0]
    # Longer than one write chunk, every random bit pattern.
    many = pd.DataFrame({"a": raw[: len(raw) // 2 * 2].reshape(-1, 2)[:, 0],
                         "b": raw[: len(raw) // 2 * 2].reshape(-1, 2)[:, 1]})
    many = pd.concat([many] * 3, ignore_index=True)
    write_trajectory_csv(many, path)
    assert np.array_equal(_bits(pd.read_csv(path)), _bits(many))


def test_csv_writer_falls_back_to_pandas_for_other_tables(tmp_path):
    frame = pd.DataFrame({"time": [0.0, 0.1], "x": [np.nan, 1.5], "n": [1, 2]})
    path = tmp_path / "t.csv"
    write_trajectory_csv(frame, path)
    assert path.read_text() == frame.to_csv(index=False, lineterminator="\n")
