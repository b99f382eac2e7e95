"""The ``validate`` command and recommend-pressure's direction/transient verdicts: files, help, one-line errors."""
import json
import os
import subprocess
import sys

import pytest

from conftest import run_console
import whipple_kick as wk
from whipple_kick.cli import validate_main
from whipple_kick.simulate.scenario import Scenario


def _validate(argv, capsys):
    return run_console(validate_main, argv, capsys)


def test_validate_writes_the_comparison(tmp_path, capsys):
    out = tmp_path / "v"
    status, stdout, stderr = _validate(["--out", str(out), "--workers", "2", "--directions", "left"], capsys)
    assert status == 0, stderr
    assert sorted(p.name for p in out.iterdir()) == ["cases", "summary.json", "validation.csv", "validation.png"]
    assert sorted(p.name for p in (out / "cases").iterdir())[:2] == ["570N_300kPa_left", "570N_400kPa_left"]
    assert len(list((out / "cases").iterdir())) == 9
    summary = json.loads((out / "summary.json").read_text())
    assert summary["setup"]["directions"] == ["left"]
    assert "Table 8.9 300/400/500" in stdout and "mean |model - measured|" in stdout
    lines = (out / "validation.csv").read_text().splitlines()
    assert lines[0].startswith("case,fz_n,pressure_kpa,direction,source,last_peak_time_s,n_peaks,period_s,"
                               "log_dec_13,log_dec_24,log_dec_35,dominant_frequency_hz,slow_swing_ratio")
    assert len(lines) == 1 + 9 + 9
    assert not any(cell.lower() in ("nan", "inf", "-inf") for line in lines for cell in line.split(","))
    # Issue 31 item 20: the summary has the provenance every result has, and each case is a run folder that
    # Result.load and compare read (it held a bare trajectory.csv).
    assert summary["provenance"]["versions"]["whipple_kick"] == wk.__version__
    assert set(summary["provenance"]["input_files"]) >= {"bicycle", "rider", "tyre", "experiment"}
    assert summary["provenance"]["code_hash"] == wk.provenance.code_hash()
    cases = sorted((out / "cases").iterdir())
    run = wk.Result.load(cases[0])
    assert run.summary["scenario"]["fz_n"] == 570.0 and run.summary["scenario"]["kick_direction"] == "left"
    assert sorted(p.name for p in cases[0].iterdir()) == ["scenario.toml", "summary.json", "trajectory.csv"]
    from whipple_kick.cli import compare_main
    status, stdout, stderr = run_console(compare_main, [str(cases[0]), str(cases[1]), "--no-plot",
                                                        "--out", str(tmp_path / "cmp")], capsys)
    assert status == 0, stderr
    assert "570N_300kPa_left" in stdout and "570N_400kPa_left" in stdout
    # The folder is not overwritten without --force.
    status, _, stderr = _validate(["--out", str(out), "--directions", "left"], capsys)
    assert status == 2 and "exists and is not empty" in stderr


@pytest.mark.parametrize("args, message", [
    (["--speed", "-1"], "speed = -1.0 m/s is outside the allowed range (0, 15] m/s"),
    (["--kick-accel", "0"], "m/s^2"),
    (["--pressure", "400"], "unrecognized arguments: --pressure 400"),
    (["--fz", "635"], "unrecognized arguments: --fz 635"),
    (["--directions", "up"], "argument --directions: invalid choice: 'up'"),
    (["--workers", "0"], "--workers = 0 must be a whole number >= 1"),
    (["--speed", "fast"], "'fast' is not a number (m/s)"),
    (["--tyre-transient", "x"], "argument --tyre-transient: invalid choice"),
    (["--bicycle", "balanceassist_635N"], "already includes its rider"),
    (["--tyre", "T01"], "kPa"),
])
def test_validate_bad_input_is_one_line_exit_2(args, message, tmp_path, capsys):
    status, stdout, stderr = _validate([*args, "--out", str(tmp_path / "v")], capsys)
    assert status == 2
    assert message in stderr and len(stderr.strip().splitlines()) == 1 and "Traceback" not in stderr
    assert stdout == "" and not (tmp_path / "v").exists()


def test_validate_help_lists_the_scenario_flags():
    exe = os.path.join(os.path.dirname(sys.executable), "validate")
    proc = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0
    for flag in ("--tyre-transient", "--controller", "--gain-scale", "--kick-accel", "--kick-profile", "--directions",
                 "--time-origin", "--compare-transients", "--out", "--speed", "Tables 8.6-8.9", "--rider-body",
                 "--reflex-delay", "--lqr-model", "--carcass-stiffness-scale"):
        assert flag in proc.stdout
    assert "--pressure " not in proc.stdout and "--fz " not in proc.stdout   # set by validate itself


def test_recommend_pressure_says_whether_the_direction_matters():
    exe = os.path.join(os.path.dirname(sys.executable), "recommend-pressure")
    proc = subprocess.run([exe, "--fz", "635", "--pressures", "300", "500", "--duration", "3", "--criterion",
                           "last-peak", "--kick-direction", "both", "--workers", "2"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    form = Scenario().tyre_transient          # the default form, whichever it is
    assert f"kicks to the right, {form} tyre transient:" in proc.stdout
    assert f"kicks to the left, {form} tyre transient:" in proc.stdout
    verdict = proc.stdout.split("what the best pressure depends on:")[1].strip()
    assert verdict.startswith(f"635 N, {form} transient: ")
    assert "whatever the direction" in verdict or "the answer depends on the direction" in verdict
