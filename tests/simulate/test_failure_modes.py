"""Failure modes a user meets: one line on stderr, the right exit status, nothing half-written left.

Exit statuses: 2 the user's input, 1 the machine's set-up (a C compiler that
fails, an unusable cache folder) or the numerics, 130 Ctrl-C, 143 SIGTERM.
Subprocess tests run the installed console script as a user would.
"""
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from whipple_kick import cli, fileio
from whipple_kick.cli import simulate_main
from whipple_kick.errors import BuildError, InputError
from whipple_kick.library import inputs
from whipple_kick.model import cache, slip
from whipple_kick.model.symbolic import slip_build


def _simulate(argv, capsys):
    """Run ``simulate`` in-process; return (status, stdout, stderr)."""
    with pytest.raises(SystemExit) as info:
        simulate_main(argv)
    out, err = capsys.readouterr()
    return info.value.code, out, err


def _console_script(name):
    exe = pathlib.Path(sys.executable).with_name(name)
    assert exe.exists(), f"console script {name} not installed (pip install -e .)"
    return str(exe)


#: Python code that resets SIGINT and SIGTERM to their default actions, then runs ``argv[1:]`` in its place
#: (same pid). A test runner started with SIGINT ignored (``nohup``, ``&`` in a non-interactive shell)
#: passes that on to its children, and Python then installs no KeyboardInterrupt handler.
_DEFAULT_SIGNALS = ("import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
                    "signal.signal(signal.SIGTERM, signal.SIG_DFL); os.execv(sys.argv[1], sys.argv[1:])")


def _with_default_signals(argv):
    """``argv`` run with SIGINT and SIGTERM at their default actions, whatever this process ignores."""
    return [sys.executable, "-c", _DEFAULT_SIGNALS, *argv]


def _start_long_run(out, *extra):
    """``simulate`` of 120 s at rtol 1e-12 (far longer than a test waits) on ``out``, once ``out`` exists."""
    proc = subprocess.Popen(_with_default_signals([_console_script("simulate"), "--duration", "120", "--rtol",
                                                   "1e-12", "--no-plot", "--out", str(out), *extra]),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not out.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert proc.poll() is None, proc.communicate()
    return proc


# ------------------------------------------------------------ C compiler

def test_failing_compiler_is_one_line_naming_compiler_and_log(tmp_path, monkeypatch):
    """A compiler that exits non-zero: BuildError, one line, full output saved beside the source."""
    monkeypatch.setenv("WHIPPLE_KICK_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(slip_build, "c_source", lambda *model: "int main(void) { return 0; }\n")
    failing = shutil.which("false")
    with pytest.raises(BuildError) as info:
        slip_build.build_library(tmp_path / "cache" / "x.so", "k", failing, ("-O2",))
    message = str(info.value)
    assert "\n" not in message and failing in message and "exit status 1" in message
    assert (tmp_path / "cache" / "slip_k.build.log").exists()


def test_failing_compiler_from_simulate_is_status_1_and_leaves_no_folder(tmp_path, capsys, monkeypatch):
    def fail(*layout):
        raise BuildError("the C compiler /bin/false failed (exit status 1: no output)")
    monkeypatch.setattr(slip.compiled, "library_path", fail)
    slip.compiled._library.cache_clear()
    try:
        out = tmp_path / "run"
        status, stdout, err = _simulate(["--duration", "0.6", "--no-plot", "--out", str(out)], capsys)
    finally:
        slip.compiled._library.cache_clear()
    assert status == 1 and stdout == ""
    assert err.count("\n") == 1 and err.startswith("simulate: cannot build the compiled model: the C compiler")
    assert not out.exists()                      # the folder it made is removed


def test_missing_compiler_from_simulate_is_status_2_one_line(tmp_path, capsys, monkeypatch):
    """No C compiler: the user's to install, as an input error is (status 2, one line, no traceback), but named as
    what it is."""
    from whipple_kick.errors import CompilerNotFoundError

    def missing(*layout):
        raise CompilerNotFoundError("no C compiler found (looked for cc, gcc, clang on PATH): install a C compiler "
                                    "(e.g. gcc) or set CC to one")
    monkeypatch.setattr(slip.compiled, "library_path", missing)
    slip.compiled._library.cache_clear()
    try:
        status, stdout, err = _simulate(["--duration", "0.6", "--no-plot", "--out", str(tmp_path / "run")], capsys)
    finally:
        slip.compiled._library.cache_clear()
    assert status == 2 and stdout == "" and "Traceback" not in err
    assert err.count("\n") == 1 and err.startswith("simulate: cannot build the compiled model: no C compiler found")
    assert "install a C compiler" in err


def test_the_build_announces_itself_as_a_warning_not_a_print(tmp_path, monkeypatch, capsys):
    """The build's one line is a PerformanceWarning (a library caller filters it; the commands print it once), not
    text written to stderr behind the caller's back."""
    from whipple_kick.errors import PerformanceWarning
    monkeypatch.setenv("WHIPPLE_KICK_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(slip_build, "c_source", lambda *model: "int main(void) { return 0; }\n")
    with pytest.warns(PerformanceWarning, match="building the slip model"), pytest.raises(BuildError):
        slip_build.build_library(tmp_path / "cache" / "x.so", "k", shutil.which("false"), ("-O2",))
    assert capsys.readouterr().err == ""


@pytest.mark.slow
def test_failing_compiler_end_to_end(tmp_path):
    """CC=false on a fresh cache: the build line, then one error line; status 1; no folder (about 30 s)."""
    env = dict(os.environ, WHIPPLE_KICK_CACHE=str(tmp_path / "cache"), CC=shutil.which("false"))
    proc = subprocess.run([_console_script("simulate"), "--out", str(tmp_path / "run")], env=env,
                          capture_output=True, text=True, timeout=600)
    lines = proc.stderr.splitlines()
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert len(lines) == 2 and lines[0].startswith("simulate: warning: building the slip model") and "C compiler" in lines[1]
    assert not (tmp_path / "run").exists()


# ------------------------------------------------------------ damaged cache entry

def test_truncated_cache_entry_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("WHIPPLE_KICK_CACHE", str(tmp_path / "cache"))
    builds = []

    def build(tmp):
        builds.append(tmp)
        tmp.write_bytes(b"\x7fELF" + bytes(range(256)) * 40)

    path = cache.build_once("lib.so", build)
    good = path.read_bytes()
    assert cache.intact(path) and len(builds) == 1
    assert cache.build_once("lib.so", build) == path and len(builds) == 1      # warm: not rebuilt
    path.write_bytes(good[:1000])                                              # cut short, e.g. a full disk
    assert not cache.intact(path)
    assert cache.build_once("lib.so", build) == path and len(builds) == 2
    assert path.read_bytes() == good
    path.with_name("lib.so.sha256").unlink()                                   # never finished
    cache.build_once("lib.so", build)
    assert len(builds) == 3 and cache.intact(path)


def test_the_compiled_model_in_use_is_checked_against_its_manifest():
    path = slip.library_path()
    assert cache.intact(path)
    size, digest = path.with_name(path.name + ".sha256").read_text().split()
    assert int(size) == path.stat().st_size and len(digest) == 64


# ------------------------------------------------------------ Ctrl-C

def _signal_ends_the_run(tmp_path, signum, status, what):
    """Send ``signum`` to a long run once its folder exists: one line, ``status`` (128 + signal), no folder."""
    out = tmp_path / "run"
    proc = _start_long_run(out)
    proc.send_signal(signum)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == status == 128 + signum
    assert stdout == "" and stderr == f"simulate: {what}; no results were kept\n"
    assert not out.exists()


def test_ctrl_c_during_a_run_is_status_130_and_leaves_no_folder(tmp_path):
    """SIGINT once the output folder exists: one line, status 130, the folder removed.

    The run (120 s simulated at rtol 1e-12, several seconds of work) is far
    longer than the time the signal takes to arrive; the test waits for the
    folder, not for a fixed time. The child gets the default SIGINT handling
    whatever the test runner was started with (nohup, &).
    """
    _signal_ends_the_run(tmp_path, signal.SIGINT, cli.EXIT_INTERRUPTED, "interrupted")


# ------------------------------------------------------------ SIGTERM

def test_sigterm_during_a_run_is_status_143_and_leaves_no_folder(tmp_path):
    """SIGTERM (schedulers, ``timeout``) as Ctrl-C: one line, status 143, the folder removed (before: silent death)."""
    _signal_ends_the_run(tmp_path, signal.SIGTERM, cli.EXIT_TERMINATED, "terminated (SIGTERM)")


def test_sigterm_while_writing_the_trajectory_leaves_no_temporary(tmp_path):
    """SIGTERM in the middle of writing trajectory.csv: the hidden temporary is removed with the run's files."""
    out = tmp_path / "run"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    code = f"""
import os, signal
from whipple_kick import cli, fileio
rows = fileio.csv_text_rows
def killed_midway(*args, **kwargs):
    for k, text in enumerate(rows(*args, **kwargs)):
        if k == 0:
            os.kill(os.getpid(), signal.SIGTERM)
        yield text
fileio.csv_text_rows = killed_midway
cli.simulate_main(["--duration", "0.6", "--no-plot", "--force", "--out", {str(out)!r}])
"""
    proc = subprocess.run(_with_default_signals([sys.executable, "-c", code]), capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 143 and proc.stderr == "simulate: terminated (SIGTERM); no results were kept\n"
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]


def test_stale_hidden_temporaries_do_not_make_the_folder_busy_and_are_removed(tmp_path, capsys):
    """A killed writer's ``.trajectory.csv.<pid>.tmp`` is invisible to ``ls``: it neither blocks nor stays."""
    out = tmp_path / "run"
    out.mkdir()
    (out / ".trajectory.csv.99999999.tmp").write_text("half a trajectory")
    status, _, err = _simulate(["--duration", "0.6", "--no-plot", "--quiet", "--out", str(out)], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["scenario.toml", "summary.json", "trajectory.csv"]
    (out / ".summary.json.99999999.tmp").write_text("{")
    (out / ".notes.txt.99999999.tmp").write_text("not ours: kept")
    status, _, err = _simulate(["--duration", "0.6", "--no-plot", "--quiet", "--force", "--out", str(out)], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == [".notes.txt.99999999.tmp", "scenario.toml", "summary.json",
                                                     "trajectory.csv"]


# ------------------------------------------------------------ one run per output folder

def test_second_run_on_the_same_out_is_refused_in_one_line(tmp_path):
    """Two runs on one --out: the second gets one line and status 2, the first finishes (before: both wrote)."""
    out = tmp_path / "run"
    first = _start_long_run(out)
    try:
        second = subprocess.run([_console_script("simulate"), "--duration", "0.6", "--no-plot", "--force",
                                 "--out", str(out)], capture_output=True, text=True, timeout=300)
    finally:
        first.send_signal(signal.SIGINT)
        first.communicate(timeout=120)
    assert second.returncode == 2 and second.stderr.count("\n") == 1, second.stderr
    assert f"output folder {str(out)!r} is in use by another run (process {first.pid})" in second.stderr
    assert not out.exists()           # the first run, interrupted, removed the folder it made


def test_lock_of_a_killed_run_is_taken_over_and_not_left_behind(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / cli.OUT_LOCK_FILE).write_text("99999999\n")      # a run killed by SIGKILL
    status, _, err = _simulate(["--duration", "0.6", "--no-plot", "--quiet", "--out", str(out)], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["scenario.toml", "summary.json", "trajectory.csv"]


# ------------------------------------------------------------ cache folder

def test_cache_folder_others_can_write_is_a_cache_error(tmp_path):
    """Named as the cache's problem, with the folder and the fix (before: "cannot write the results", status 2)."""
    shared = tmp_path / "cache"
    shared.mkdir()
    shared.chmod(0o777)
    proc = subprocess.run([_console_script("simulate"), "--duration", "0.6", "--no-plot", "--out",
                           str(tmp_path / "run")], env=dict(os.environ, WHIPPLE_KICK_CACHE=str(shared)),
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1 and proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.startswith(f"simulate: cache error: cache folder {shared} is not private")
    assert "mode 0o777" in proc.stderr and "WHIPPLE_KICK_CACHE" in proc.stderr
    assert not (tmp_path / "run").exists()


def test_cache_folder_that_cannot_be_created_is_a_cache_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    proc = subprocess.run([_console_script("stability"), "--speeds", "3", "--no-plot", "--out", str(tmp_path / "run")],
                          env=dict(os.environ, WHIPPLE_KICK_CACHE=str(blocker / "cache")),
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1 and proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.startswith(f"stability: cache error: cache folder {blocker / 'cache'} cannot be created")


def test_read_only_cache_folder_is_a_cache_error(tmp_path, monkeypatch):
    """A cache folder the build cannot write into (read-only, full): CacheError naming the folder and the fix."""
    import errno

    from whipple_kick.errors import CacheError
    monkeypatch.setenv("WHIPPLE_KICK_CACHE", str(tmp_path / "cache"))

    def read_only(path):
        raise PermissionError(errno.EROFS, "Read-only file system", str(path) + ".lock")
    monkeypatch.setattr(cache, "locked", read_only)
    with pytest.raises(CacheError) as info:
        cache.build_once("x.py", lambda tmp: tmp.write_text(""))
    message = str(info.value)
    assert message.startswith(f"cache folder {tmp_path / 'cache'} cannot be written (Read-only file system)")
    assert "WHIPPLE_KICK_CACHE" in message and "\n" not in message


def test_interrupted_run_in_an_existing_folder_removes_only_its_own_files(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    from whipple_kick.figures import plotting

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr(plotting, "response_figure", interrupt)
    status, stdout, err = _simulate(["--duration", "0.6", "--force", "--out", str(out)], capsys)
    assert status == 130 and err == "simulate: interrupted; no results were kept\n"
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]


# ------------------------------------------------------------ --force

def _earlier_run(out, capsys):
    """A finished run in ``out`` (with a user's own file beside it); returns {name: bytes} of the folder."""
    status, _, err = _simulate(["--duration", "0.3", "--quiet", "--out", str(out)], capsys)
    assert status == 0, err
    (out / "notes.txt").write_text("mine\n")
    return {p.name: p.read_bytes() for p in out.iterdir()}


def _folder_bytes(out):
    return {p.name: p.read_bytes() for p in out.iterdir()}


def test_force_replaces_the_earlier_run_only_when_the_new_one_succeeds(tmp_path, capsys, monkeypatch):
    """Issue 31 item 2: ``--force --out OLD`` removed OLD's results at the start, so a run that then stopped on a
    user's mistake (exit 2) left OLD empty. Now the new run is written into a hidden staging folder and replaces
    OLD's files at the end; a run that stops leaves OLD as it was, and no staging folder."""
    from whipple_kick.simulate import simulation
    out = tmp_path / "run"
    before = _earlier_run(out, capsys)
    assert sorted(before) == ["notes.txt", "response.png", "scenario.toml", "summary.json", "trajectory.csv"]

    def no_steady_motion(*args, **kwargs):   # a user's mistake found during the run (after the folder is claimed)
        raise InputError("no steady motion at 3 m/s (a stand-in)")
    monkeypatch.setattr(simulation, "run", no_steady_motion)
    status, _, err = _simulate(["--duration", "0.4", "--force", "--no-plot", "--out", str(out)], capsys)
    assert status == 2 and "stand-in" in err
    assert _folder_bytes(out) == before

    def interrupt(*args, **kwargs):          # Ctrl-C while the figure is drawn: the new run's files half there
        raise KeyboardInterrupt
    monkeypatch.undo()
    from whipple_kick.figures import plotting
    monkeypatch.setattr(plotting, "response_figure", interrupt)
    status, _, err = _simulate(["--duration", "0.4", "--force", "--out", str(out)], capsys)
    assert status == 130
    assert _folder_bytes(out) == before
    monkeypatch.undo()

    # Success: the new run's files replace the earlier ones; the earlier response.png goes (--no-plot), the
    # user's file stays.
    status, _, err = _simulate(["--duration", "0.4", "--force", "--no-plot", "--quiet", "--out", str(out)], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "scenario.toml", "summary.json", "trajectory.csv"]
    assert json.loads((out / "summary.json").read_text())["scenario"]["duration"] == 0.4
    assert (out / "notes.txt").read_text() == "mine\n"


def test_sigterm_during_a_forced_rerun_leaves_the_earlier_run_whole(tmp_path, capsys):
    """Issue 31 item 2 with SIGTERM (a scheduler's time limit) in the middle of the new run."""
    out = tmp_path / "run"
    before = _earlier_run(out, capsys)
    proc = subprocess.Popen(_with_default_signals([_console_script("simulate"), "--duration", "120", "--rtol",
                                                   "1e-12", "--no-plot", "--force", "--out", str(out)]),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list(out.glob(cli.STAGING_PREFIX + ".*")) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == cli.EXIT_TERMINATED, stderr
    assert _folder_bytes(out) == before


def test_a_killed_forced_rerun_leaves_a_staging_folder_the_next_run_removes(tmp_path, capsys):
    """SIGKILL cannot be caught: the staging folder stays, hidden, until the next run on the folder removes it."""
    out = tmp_path / "run"
    _earlier_run(out, capsys)
    (out / f"{cli.STAGING_PREFIX}.99999999").mkdir()
    (out / f"{cli.STAGING_PREFIX}.99999999" / "trajectory.csv").write_text("half")
    status, _, err = _simulate(["--duration", "0.3", "--force", "--no-plot", "--quiet", "--out", str(out)], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "scenario.toml", "summary.json", "trajectory.csv"]


def test_force_removes_the_previous_runs_files(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    for name in ("response.png", "animation.mp4", "summary.json"):
        (out / name).write_text("from an earlier run")
    (out / "notes.txt").write_text("mine\n")
    status, _, err = _simulate(["--duration", "0.6", "--force", "--no-plot", "--quiet", "--out", str(out)], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "scenario.toml", "summary.json", "trajectory.csv"]


# ------------------------------------------------------------ kick table units

def _write(path, text):
    path.write_text(text)
    return path


def test_kick_table_units_from_the_header(tmp_path):
    t = np.linspace(0.0, 0.15, 16)
    y = (0.15 * (t / 0.15) ** 2).tolist()
    t = t.tolist()
    si = _write(tmp_path / "si.csv", "time [s],y [m]\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(t, y, strict=True)))
    milli = _write(tmp_path / "milli.csv",
                   "Time (ms),Y (mm)\n" + "".join(f"{a * 1e3!r},{b * 1e3!r}\n" for a, b in zip(t, y, strict=True)))
    plain = _write(tmp_path / "plain.csv", "time,y\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(t, y, strict=True)))
    ts, ys = inputs.load_kick_table(si)
    for other in (milli, plain):
        to, yo = inputs.load_kick_table(other)
        # ms -> s and mm -> m are one multiplication by 1e-3 of a printed decimal: equal to round-off.
        np.testing.assert_allclose(to, ts, rtol=1e-15, atol=1e-18)
        np.testing.assert_allclose(yo, ys, rtol=1e-15, atol=1e-18)
    assert ts[-1] == 0.15 and ys[-1] == 0.15


def test_kick_table_with_an_unknown_unit_names_the_column_and_the_allowed_units(tmp_path):
    table = _write(tmp_path / "cm.csv", "time [s],y [cm]\n0,0\n0.15,15\n")
    with pytest.raises(InputError, match=r"column 'y \[cm\]' has unit 'cm'; allowed: m, mm"):
        inputs.load_kick_table(table)


def test_kick_table_in_mm_read_as_metres_is_implausible(tmp_path, capsys, monkeypatch):
    """The issue's case: 150 'm' in 0.15 s would be a 40,000 m/s^2 kick; refused like a built-in one."""
    table = _write(tmp_path / "plate.csv", "time,y\n0,0\n0.075,75\n0.15,150\n")
    monkeypatch.chdir(tmp_path)
    status, stdout, err = _simulate(["--kick-table", str(table), "--quiet"], capsys)
    assert status == 2 and stdout == "" and err.count("\n") == 1
    assert "plate travel from the first row = 150 m is implausible; allowed [0, 1] m" in err
    assert "y [mm]" in err


def test_kick_table_held_to_the_built_in_velocity_cap(tmp_path):
    from whipple_kick.simulate.scenario import Scenario
    table = _write(tmp_path / "plate.csv", "time,y\n0,0\n0.001,0.5\n0.002,0\n")     # 0.5 m in 1 ms and back
    with pytest.raises(InputError, match=r"peak plate velocity = \d+(\.\d+)? m/s is implausible; allowed \[0, 31.62\] m/s"):
        inputs.kick_of(Scenario(kick_profile="table", kick_table=str(table)))
    # A sharp but plausible stop (10 mm in 2 ms, about 1.5e4 m/s^2 at the rows) is accepted:
    # the built-in constant profile stops the plate instantly.
    sharp = _write(tmp_path / "sharp.csv", "time,y\n0,0\n0.002,0.01\n0.004,0.01\n")
    assert inputs.kick_of(Scenario(kick_profile="table", kick_table=str(sharp))).peak_acceleration > inputs.MAX_ACCELERATION


# ------------------------------------------------------------ data-quality warnings

def test_data_warning_is_one_line_silenced_by_quiet_and_kept_in_the_summary(tmp_path, capsys):
    out = tmp_path / "loud"
    status, _, err = _simulate(["--tyre", "T02", "--duration", "0.6", "--no-plot", "--out", str(out)], capsys)
    assert status == 0
    warning_lines = [line for line in err.splitlines() if "T02" in line]
    assert len(warning_lines) == 1 and warning_lines[0].startswith("simulate: warning: tyre T02:")
    assert "UserWarning" not in err and "warnings.warn" not in err
    quiet = tmp_path / "quiet"
    status, stdout, err = _simulate(["--tyre", "T02", "--duration", "0.6", "--no-plot", "--quiet",
                                     "--out", str(quiet)], capsys)
    assert status == 0 and stdout == "" and err == ""
    summary = json.loads((quiet / "summary.json").read_text())
    assert len(summary["tyres"]["data_warnings"]) == 1 and "T02" in summary["tyres"]["data_warnings"][0]
    base = json.loads((out / "summary.json").read_text())
    assert base["tyres"]["data_warnings"] == summary["tyres"]["data_warnings"]


def test_the_cli_does_not_drop_data_warnings_for_the_rest_of_the_process(tmp_path, capsys):
    """Issue 31 item 16: simulate called ``warnings.filterwarnings("ignore", DataQualityWarning)`` for the whole
    process, so a library caller running the CLI in-process never saw the warning again."""
    import warnings

    from whipple_kick.library import tyres
    filters = list(warnings.filters)
    status, _, err = _simulate(["--tyre", "T02", "--duration", "0.3", "--no-plot", "--quiet",
                                "--out", str(tmp_path / "q")], capsys)
    assert status == 0 and err == ""
    assert warnings.filters == filters
    with pytest.warns(tyres.DataQualityWarning, match="T02"):
        tyres.load("T02", 300)


# ------------------------------------------------------------ sweeps

def _children(pid):
    """Pids of the live (not zombie) child processes of ``pid``, from /proc."""
    found = []
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


def _alive(pid):
    try:
        state = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _start_long_sweep(folder, workers=2):
    """recommend-pressure on 201 cases (300-500 kPa every 1 kPa, 6 s each: minutes of work) into ``folder``."""
    return subprocess.Popen([_console_script("recommend-pressure"), "--fz", "635", "--pressures", "300", "500",
                             "--fine", "--step", "1", "--workers", str(workers), "--out", str(folder)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_until_running(proc, folder, workers=0):
    """Wait (up to 2 min) until the manifest says running and ``workers`` pool processes exist."""
    deadline = time.monotonic() + 120
    while proc.poll() is None and time.monotonic() < deadline:
        manifest = folder / "manifest.json"
        if (manifest.exists() and json.loads(manifest.read_text()).get("status") == "running"
                and len(_children(proc.pid)) >= workers):
            return
        time.sleep(0.02)
    raise AssertionError(f"the sweep did not start: {proc.poll()} {proc.communicate() if proc.poll() else ''}")


def test_sigterm_ends_the_sweeps_workers_and_records_interrupted(tmp_path):
    folder = tmp_path / "sweep"
    proc = _start_long_sweep(folder)
    try:
        _wait_until_running(proc, folder, workers=2)
        workers = _children(proc.pid)
        proc.send_signal(signal.SIGTERM)
        _, stderr = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == cli.EXIT_TERMINATED == 143
    assert stderr.startswith("recommend-pressure: terminated (SIGTERM); the finished cases are kept in ") \
        and stderr.count("\n") == 1, stderr
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["status"] == "interrupted" and manifest["n_done"] < manifest["n_cases"] == 201
    assert workers and not any(_alive(pid) for pid in workers)


def test_second_sweep_on_the_same_folder_is_refused_in_one_line(tmp_path):
    folder = tmp_path / "sweep"
    first = _start_long_sweep(folder, workers=1)   # one: the second process starts on the other core
    try:
        _wait_until_running(first, folder)
        second = subprocess.run([_console_script("recommend-pressure"), "--fz", "635", "--pressures", "300", "500",
                                 "--fine", "--step", "1", "--out", str(folder)],
                                capture_output=True, text=True, timeout=120)
    finally:
        first.send_signal(signal.SIGTERM)
        first.communicate(timeout=120)
    assert second.returncode == 2 and second.stderr.count("\n") == 1
    assert f"is in use by another sweep (process {first.pid}, sweep.lock)" in second.stderr


def test_lock_of_a_dead_process_is_taken_over(tmp_path):
    """The lock is the operating system's (flock): it goes with its holder, whatever the file says."""
    from whipple_kick.studies import sweep_store
    folder = tmp_path / "sweep"
    folder.mkdir()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    (folder / sweep_store.LOCK_FILE).write_text(dead.stdout)
    fd = sweep_store._lock(folder)
    try:
        assert (folder / sweep_store.LOCK_FILE).read_text() == f"{os.getpid()}\n"
        # While this live process holds it, another process is refused, the message naming us.
        held = subprocess.run([sys.executable, "-c", f"from whipple_kick import sweep_store; sweep_store._lock({str(folder)!r})"],
                              capture_output=True, text=True, timeout=120)
        assert held.returncode == 1 and f"in use by another sweep (process {os.getpid()}," in held.stderr
    finally:
        fileio.release_lock(fd)


def test_progress_bar_only_on_a_terminal_unless_asked(tmp_path):
    args = ["--fz", "635", "--pressures", "400", "--duration", "0.6"]
    quiet = subprocess.run([_console_script("recommend-pressure"), *args], capture_output=True, text=True,
                           timeout=300)
    assert quiet.returncode == 0 and "sweep" not in quiet.stderr and "case/s" not in quiet.stderr
    asked = subprocess.run([_console_script("recommend-pressure"), *args, "--progress"], capture_output=True,
                           text=True, timeout=300)
    assert asked.returncode == 0 and "sweep: 100%" in asked.stderr
