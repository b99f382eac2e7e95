"""The ``simulate`` command: files written, output folder rules, and one-line errors with status 2."""
import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from conftest import run_console
import whipple_kick as wk
from whipple_kick.cli import simulate_main
from whipple_kick.errors import InputError


def _simulate(argv, capsys):
    """Run ``simulate`` in-process; return (status, stdout, stderr)."""
    return run_console(simulate_main, argv, capsys)


def test_main_job_writes_the_three_files(tmp_path, capsys):
    """Issue 6 acceptance: ``simulate --pressure 400 --fz 635``."""
    out = tmp_path / "run"
    status, stdout, stderr = _simulate(["--pressure", "400", "--fz", "635", "--out", str(out)], capsys)
    assert status == 0, stderr
    assert sorted(p.name for p in out.iterdir()) == ["response.png", "scenario.toml", "summary.json", "trajectory.csv"]
    assert (out / "response.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "response.png").stat().st_size > 20_000
    summary = json.loads((out / "summary.json").read_text())
    assert summary["fell"] is False
    assert summary["scenario"]["pressure_kpa"] == 400.0 and summary["scenario"]["fz_n"] == 635.0
    header = (out / "trajectory.csv").read_text().splitlines()[0].split(",")
    for column in ("time [s]", "yaw_rate [rad/s]", "roll_rate [rad/s]", "steer_rate [rad/s]", "fy_rear [N]",
                   "plate_y [m]", "steer_torque [N m]", "forward_speed [m/s]", "velocity_x_fixed [m/s]"):
        assert column in header
    assert "no fall" in stdout and "trajectory.csv" in stdout
    roll = summary["recovery"]["signals"]["roll_rate"]["time_s"]
    assert f"roll rate {roll:.2f} s" in stdout
    assert stderr == ""
    # One line says where the tyre fits are extrapolated (T03 was measured to 6 deg and 488 N).
    assert sum(line.strip().startswith("tyre fits extrapolated: rear: patch slip") for line in stdout.splitlines()) == 1


_WARM_PROBE = """
import sys
from whipple_kick.cli import simulate_main
try:
    simulate_main(["--pressure", "400", "--fz", "635", "--quiet", "--out", sys.argv[1]])
except SystemExit as exc:
    assert exc.code == 0, exc.code
print(sorted(name for name in ("sympy", "control", "matplotlib.pyplot", "SALib", "sklearn", "emcee", "scipy.signal",
                               "tornado", "whipple_kick.studies.sweep_engine") if name in sys.modules))
"""


def test_warm_simulate_imports_neither_sympy_nor_python_control(tmp_path):
    """The main job in a fresh process with the compiled model cached: no SymPy, no python-control, no pyplot,
    no SALib, scikit-learn or emcee, no SciPy signal package, no Tornado, no sweep engine.

    SymPy belongs to the build (a cache miss), python-control to the
    control-analysis API, SALib to the uncertainty study, scikit-learn and emcee to the calibration, SciPy's
    signal package to the measurements' spectra, Tornado to the explorer, the sweep engine to the studies
    (the command-line module imports a command's own studies when it runs); the LQR design comes from
    SciPy's Riccati solver and the figure is drawn without pyplot.
    """
    wk.slip.library_path()                                     # the compiled model, built if needed
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-c", _WARM_PROBE, str(out)], capture_output=True, text=True,
                          timeout=600, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout
    assert done.stderr == ""                                   # a warm run builds nothing: not even its one line
    assert sorted(p.name for p in out.iterdir()) == ["response.png", "scenario.toml", "summary.json", "trajectory.csv"]


def test_default_output_folder_is_new(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = ["--duration", "0.3", "--no-plot", "--quiet"]
    assert _simulate(argv, capsys)[0] == 0
    assert _simulate(argv, capsys)[0] == 0
    folders = sorted(p for p in tmp_path.iterdir() if p.is_dir())
    assert len(folders) == 2      # the second run did not reuse the first one's folder
    for folder in folders:
        assert sorted(p.name for p in folder.iterdir()) == ["scenario.toml", "summary.json", "trajectory.csv"]


def test_existing_folder_needs_force(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    argv = ["--duration", "0.3", "--no-plot", "--quiet", "--out", str(out)]
    status, _, err = _simulate(argv, capsys)
    assert status == 2 and "not empty" in err and "--force" in err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]
    assert _simulate(argv + ["--force"], capsys)[0] == 0
    assert (out / "notes.txt").read_text() == "keep me"
    assert (out / "summary.json").exists()


def test_variants_reach_the_scenario(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["--pressure-front", "300", "--pressure-rear", "500", "--rider-mass", "61", "--speed", "4",
            "--kick-accel", "30", "--kick-profile", "smooth", "--kick-direction", "left",
            "--controller", "lqr", "--gain-scale", "0.8", "--low-inertia", "--symmetric-tyres",
            "--friction", "plate", "--rtol", "1e-8", "--duration", "0.5", "--no-plot", "--quiet",
            "--out", str(out)]
    status, stdout, err = _simulate(argv, capsys)
    assert status == 0, err
    assert stdout == ""
    s = json.loads((out / "summary.json").read_text())
    sc = s["scenario"]
    assert (sc["pressure_front_kpa"], sc["pressure_rear_kpa"], sc["rider_mass_kg"]) == (300.0, 500.0, 61.0)
    assert sc["low_inertia"] and sc["symmetric_tyres"] and sc["friction"] == "plate"
    assert s["kick"]["displacement_m"] == -0.15 and s["kick"]["peak_acceleration_m_s2"] == 30.0
    assert s["controller"]["gain_scale"] == 0.8 and s["numerics"]["rtol"] == 1e-8


def test_thesis_tyre_transient_and_earlier_options_reach_the_summary(tmp_path, capsys):
    """--tyre-transient force_lag (the thesis' form), --plate-stop resolve, --kick-heading settled."""
    out = tmp_path / "run"
    argv = ["--tyre-transient", "force_lag", "--plate-stop", "resolve", "--kick-heading", "settled",
            "--duration", "0.5", "--no-plot", "--out", str(out)]
    status, stdout, err = _simulate(argv, capsys)
    assert status == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["tyres"]["transient"] == "force_lag" and s["scenario"]["tyre_transient"] == "force_lag"
    assert s["numerics"]["plate_stop"] == "resolve" and s["numerics"]["kick_heading"] == "settled"
    jump, = s["energy"]["velocity_jumps"]
    assert jump["impulse_work_j"] is None and jump["kinetic_energy_change_j"] < -0.1
    assert "transient force_lag" in stdout and "plate stop (resolve)" in stdout
    header = [c.split(" [")[0] for c in (out / "trajectory.csv").read_text().splitlines()[0].split(",")]
    assert "fy_rear" in header and "plate_work" in header and "slip_patch_rear" not in header
    assert s["steady_state"]["rear_wheel_torque_role"] == "brake" and "brake" in stdout


def test_compat_authors_code_and_flags_that_override_it(tmp_path, capsys):
    """``--compat authors-code`` is ``Scenario.authors_code``; flags given with it change its fields."""
    out = tmp_path / "compat"
    status, stdout, err = _simulate(["--compat", "authors-code", "--duration", "0.3", "--no-plot",
                                     "--out", str(out)], capsys)
    assert status == 0, err
    sc = json.loads((out / "summary.json").read_text())["scenario"]
    preset = wk.simulation.Scenario.authors_code(duration=0.3).to_dict()
    assert sc == preset
    assert "camber sign reversed" in stdout and "start: upright" in stdout and "keep_speeds" in stdout
    assert "front contact is 3.2 mm below the ground" in stdout and "contact points' forward speeds" in stdout
    # The rider of their code is linearly unstable with their camber sign (docs/validation.md).
    assert "linearly unstable" in err
    out2 = tmp_path / "ours"
    status, stdout, err = _simulate(["--compat", "authors-code", "--camber-sign", "physical", "--pressure", "400",
                                     "--plate-stop", "impulse", "--duration", "0.3", "--no-plot", "--quiet",
                                     "--out", str(out2)], capsys)
    assert status == 0, err
    sc = json.loads((out2 / "summary.json").read_text())["scenario"]
    assert sc == wk.simulation.Scenario.authors_code(400.0, camber_sign="physical", plate_stop="impulse",
                                                     duration=0.3).to_dict()
    assert stdout == "" and err == ""


def test_compat_with_the_701N_preset_uses_its_gains_and_warns_when_told_otherwise(tmp_path, capsys):
    """Issue 24: ``--compat authors-code --bicycle balanceassist_701N`` kept the 635 N gains. Now it takes Table
    8.4's 701 N column; other gains are still possible (--thesis-load) but warned about, in summary.json and on
    stderr (not with --quiet). The compat preset's own switches have flags that switch them back alone."""
    gains_701 = wk.control.thesis_gains(701.0)
    out = tmp_path / "701"
    status, _, err = _simulate(["--compat", "authors-code", "--bicycle", "balanceassist_701N", "--duration", "0.3",
                                "--no-plot", "--out", str(out)], capsys)
    assert status == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller"]["gains"] == gains_701 and summary["controller"]["warning"] is None
    assert "warning: the Table 8.4 gains" not in err
    for quiet in ([], ["--quiet"]):
        out = tmp_path / f"635{len(quiet)}"
        status, _, err = _simulate(["--compat", "authors-code", "--bicycle", "balanceassist_701N", "--thesis-load",
                                    "635", "--duration", "0.3", "--no-plot", "--out", str(out), *quiet], capsys)
        assert status == 0, err
        warning = json.loads((out / "summary.json").read_text())["controller"]["warning"]
        assert warning.startswith("the Table 8.4 gains in use are those for 635 N, but bicycle "
                                  "'balanceassist_701N' is labelled a rear load of 701 N")
        assert (f"simulate: warning: {warning}\n" in err) == (not quiet)
    out = tmp_path / "switches"
    status, stdout, err = _simulate(["--compat", "authors-code", "--slip-speed", "wheel_centre", "--start-pitch",
                                     "compressed", "--duration", "0.3", "--no-plot", "--out", str(out)], capsys)
    assert status == 0, err
    sc = json.loads((out / "summary.json").read_text())["scenario"]
    assert sc == wk.simulation.Scenario.authors_code(slip_speed="wheel_centre", start_pitch="compressed",
                                                     duration=0.3).to_dict()
    assert "front contact is" not in stdout and "contact points' forward speeds" not in stdout


# Every bad input: (argv, fragments the one-line message must contain).
BAD_INPUTS = {
    "pressure-above-range": (["--pressure", "900"], ["900", "[300, 500]", "kPa"]),
    "pressure-negative": (["--pressure", "-5"], ["-5", "kPa"]),
    "front-pressure-out-of-range": (["--pressure-front", "250", "--pressure-rear", "400"], ["250", "kPa"]),
    "negative-load": (["--fz", "-100"], ["-100", "N", "range"]),
    # 0 N and 10 N state the same, real range: the loads a rider can put on this bicycle
    # (before: "(0, inf] N" for 0 N, "(165.09, 1535.65] N" for 10 N).
    "zero-load": (["--fz", "0"], ["fz = 0.0 N", "allowed range [322.71, 1535.65] N for 'balanceassist_v1'"]),
    "load-below-the-bicycle's-own": (["--fz", "10"], ["fz = 10.0 N",
                                                      "allowed range [322.71, 1535.65] N for 'balanceassist_v1'"]),
    # Issue 40 item 7: the loads of a rider of a human mass (23-200 kg), not of a rider of no mass.
    "load-of-a-rider-too-light": (["--fz", "200"], ["fz = 200.0 N", "[322.71, 1535.65] N", "a 23 kg rider"]),
    "load-too-large": (["--fz", "5000"], ["5000", "N", "range"]),
    "negative-rider-mass": (["--rider-mass", "-3"], ["-3", "kg", "[23, 200]"]),
    "unknown-tyre": (["--tyre", "T99"], ["T99", "T01", "T05"]),
    "unknown-coefficient-set": (["--tyre", "T01", "--coefficient-set", "chapter8"], ["chapter8", "T01"]),
    "unknown-bicycle": (["--bicycle", "nope"], ["nope", "balanceassist_v1"]),
    "zero-speed": (["--speed", "0"], ["speed", "0", "m/s", "(0, 15]"]),
    "negative-speed": (["--speed", "-2"], ["speed", "-2", "m/s"]),
    "malformed-pressure": (["--pressure", "abc"], ["--pressure", "'abc'", "kPa"]),
    "malformed-load": (["--fz", "6x5"], ["--fz", "'6x5'", "N"]),
    "malformed-speed": (["--speed", "nan"], ["--speed", "m/s"]),
    "malformed-kick": (["--kick-accel", "fast"], ["--kick-accel", "m/s^2"]),
    "zero-kick-accel": (["--kick-accel", "0"], ["kick peak acceleration", "m/s^2"]),
    "negative-kick-duration": (["--kick-duration", "-0.1"], ["kick duration", "s"]),
    "negative-displacement": (["--kick-displacement", "-0.1"], ["kick displacement", "m", "[0, 1]"]),
    "zero-duration": (["--duration", "0"], ["duration", "s"]),
    "rtol-out-of-range": (["--rtol", "0.1"], ["rtol", "0.1"]),
    "unwritable-output": (["--out", "/dev/null/run"], ["/dev/null/run", "not writable"]),
    "load-and-rider-mass": (["--fz", "635", "--rider-mass", "60"], ["--rider-mass", "--fz"]),
    "accel-and-duration": (["--kick-accel", "30", "--kick-duration", "0.1"], ["--kick-duration", "--kick-accel"]),
    "pressure-and-front": (["--pressure", "400", "--pressure-front", "300"], ["--pressure", "--pressure-front"]),
    "front-without-rear": (["--pressure-front", "300"], ["--pressure-rear"]),
    "gain-scale-with-controller-off": (["--controller", "off", "--gain-scale", "0.5"], ["0.5", "off"]),
    "thesis-gains-unknown-load": (["--controller", "thesis", "--fz", "600"], ["600", "570, 635 and 701 N"]),
    "thesis-load-unknown": (["--controller", "thesis", "--thesis-load", "600"], ["600", "570, 635 and 701 N"]),
    "thesis-gains-preset-without-label": (["--bicycle", "browser_with_rider", "--controller", "thesis"],
                                          ["570, 635 or 701 N", "--thesis-load"]),
    "malformed-design-speed": (["--design-speed", "x"], ["--design-speed", "m/s"]),
    "zero-design-speed": (["--design-speed", "0"], ["design speed = 0.0 m/s", "(0, 15] m/s"]),
    "preset-with-rider-and-load": (["--bicycle", "balanceassist_635N", "--fz", "635"], ["already includes"]),
    "no-rider-on-a-bicycle-alone": (["--rider", "none"], ["rider 'none'", "'balanceassist_v1'", "includes_rider = false"]),
    "no-rider-and-a-load": (["--bicycle", "balanceassist_635N", "--rider", "none", "--fz", "635"], ["already includes"]),
    "unknown-rider": (["--rider", "nobody"], ["unknown rider 'nobody'", "jason"]),
    "unknown-profile": (["--kick-profile", "fast"], ["--kick-profile", "'fast'", "constant", "smooth", "table"]),
    "table-profile-without-file": (["--kick-profile", "table"], ["--kick-profile table", "--kick-table FILE"]),
    "missing-table": (["--kick-table", "nope.csv"], ["kick table 'nope.csv'", "does not exist"]),
    "table-and-accel": (["--kick-table", "k.csv", "--kick-accel", "30"], ["--kick-table", "--kick-accel"]),
    "table-and-duration": (["--kick-table", "k.csv", "--kick-duration", "0.1"], ["--kick-table", "--kick-duration"]),
    "table-and-displacement": (["--kick-table", "k.csv", "--kick-displacement", "0.15"],
                               ["--kick-table", "--kick-displacement"]),
    "table-and-smooth": (["--kick-table", "k.csv", "--kick-profile", "smooth"],
                         ["--kick-table", "--kick-profile smooth"]),
    "unknown-controller": (["--controller", "pid"], ["--controller", "'pid'"]),
    "animation-option-alone": (["--fps", "10"], ["--fps", "--animate"]),
    "animation-fps-zero": (["--animate", "--fps", "0"], ["frame rate", "[1, 120]", "frames/s"]),
    "animation-slow-motion": (["--animate", "--slow-motion", "5"], ["slow-motion factor", "(0, 1]"]),
    "unknown-tyre-transient": (["--tyre-transient", "lag"], ["--tyre-transient", "'lag'", "contact_patch",
                                                              "force_lag"]),
    "unknown-plate-stop": (["--plate-stop", "hold"], ["--plate-stop", "'hold'", "impulse", "resolve"]),
    "unknown-flag": (["--pressur", "400"], ["unrecognized", "--pressur"]),
    "unknown-compat": (["--compat", "thesis"], ["--compat", "'thesis'", "authors-code"]),
    "unknown-camber-sign": (["--camber-sign", "minus"], ["--camber-sign", "'minus'", "physical", "reversed"]),
    "upright-start-with-settle": (["--start", "upright"], ["settle time = 0.5 s", "start 'upright'", "0 s"]),
    "compat-with-settle": (["--compat", "authors-code", "--settle", "1"], ["settle time = 1 s", "0 s"]),
    "missing-scenario-file": (["--scenario", "nope.toml"], ["scenario file 'nope.toml' does not exist"]),
    "scenario-and-compat": (["--scenario", "nope.toml", "--compat", "authors-code"],
                            ["--scenario FILE", "--compat"]),
    "malformed-output-rate": (["--output-rate", "fast"], ["--output-rate", "'fast'", "Hz"]),
    # The rider's body: each names the value, the allowed range and the unit.
    "reflex-delay-too-long": (["--reflex-delay", "2"], ["reflex delay = 2.0 s", "[0, 0.5] s"]),
    "negative-hip-stiffness": (["--hip-stiffness", "-1"], ["hip stiffness = -1.0 N m/rad", "[0, 1e+06] N m/rad"]),
    "negative-arm-damping": (["--arm-damping", "-2"], ["arm damping = -2.0 N m s/rad", "N m s/rad"]),
    "malformed-arm-stiffness": (["--arm-stiffness", "stiff"], ["--arm-stiffness", "'stiff'", "N m/rad"]),
    "reflex-gain-too-large": (["--reflex-roll", "1e5"], ["reflex roll gain", "N m/rad"]),
    "carcass-stiffness-scale-too-large": (["--carcass-stiffness-scale", "100"],
                                          ["carcass stiffness scale = 100.0", "[0.05, 20]"]),
    "unknown-rider-body": (["--rider-body", "floppy"], ["--rider-body", "'floppy'", "rigid", "leaning"]),
    "unknown-arms": (["--arms", "both"], ["--arms", "'both'", "off", "on"]),
    "unknown-lqr-model": (["--lqr-model", "lin"], ["--lqr-model", "'lin'", "whipple", "simulated"]),
    "leaning-without-hip-spring": (["--rider-body", "leaning", "--hip-stiffness", "0"],
                                   ["hip stiffness = 0 N m/rad", "nothing to hold it up", "(0, 1e+06] N m/rad"]),
    "leaning-on-a-preset-with-rider": (["--rider-body", "leaning", "--bicycle", "balanceassist_635N"],
                                       ["balanceassist_635N", "lumped in already", "balanceassist_v1"]),
    # The rear load share: outside (0, 1), not reachable by a shift within 0.15 m, and on a preset whose rider's
    # place is fixed (the share would be ignored).
    "rear-share-above-1": (["--rear-share", "1.5"], ["rear load share = 1.5", "(0, 1)"]),
    "rear-share-unreachable": (["--fz", "570", "--rear-share", "0.75"],
                               ["rear load share = 0.75", "[0.5467, 0.7032]", "0.15 m", "unit 1"]),
    "rear-share-on-a-preset": (["--rear-share", "0.68", "--bicycle", "balanceassist_635N"],
                               ["rear load share = 0.68", "would be ignored", "balanceassist_635N"]),
    # A flag its mechanism does not read: named as given, the flag with its unit, and the flag that would
    # switch the mechanism on (issue 40 item 11: it named the Python fields and gave no unit).
    "hip-stiffness-without-the-leaning-body": (
        ["--hip-stiffness", "500"],
        ["--hip-stiffness 500 N m/rad is read only by the leaning upper body (--rider-body leaning)",
         "leave it at its default (--hip-stiffness 128 N m/rad); it would be ignored"]),
    "carcass-damping-without-the-carcass": (
        ["--tyre-transient", "force_lag", "--carcass-damping", "5"],
        ["--carcass-damping 5 N s/m is read only by the carcass tyre (--tyre-transient carcass)"]),
    "design-speed-without-the-lqr-rider": (["--controller", "off", "--design-speed", "3"],
                                           ["--design-speed 3 m/s is read only by the LQR rider (--controller lqr)",
                                            "leave it out"]),
    "leaning-with-a-negative-hip-stiffness": (["--rider-body", "leaning", "--hip-stiffness", "-1"],
                                              ["hip stiffness = -1.0 N m/rad", "(0, 1e+06] N m/rad"]),
}


@pytest.mark.parametrize("argv, fragments", BAD_INPUTS.values(), ids=BAD_INPUTS.keys())
def test_bad_input_is_one_line_and_status_2(argv, fragments, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, stdout, err = _simulate(argv + ["--quiet"], capsys)
    assert status == 2
    assert stdout == ""
    assert "Traceback" not in err
    assert err.endswith("\n") and err.count("\n") == 1, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    # Nothing left behind in the working directory.
    assert list(tmp_path.iterdir()) == []


def test_console_script_reports_without_traceback(tmp_path):
    """The installed console script: status 2 and one stderr line from a fresh process."""
    exe = os.path.join(os.path.dirname(sys.executable), "simulate")
    if not os.path.exists(exe):
        pytest.skip("console script not installed (pip install -e .)")
    proc = subprocess.run([exe, "--pressure", "900", "--fz", "635"], capture_output=True, text=True,
                          cwd=tmp_path, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "kPa" in proc.stderr and "Traceback" not in proc.stderr
    help_text = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=120).stdout
    for unit in ("KPA", "M/S", "M/S2", "kg", "m/s^2", "in s"):
        assert unit in help_text


# ------------------------------------------------------------- tabulated kick

def _smooth_table(path, rate=1000.0):
    """The thesis' 150 mm in 0.150 s as a minimum-jerk table sampled at ``rate``."""
    lines = ["time,y"]
    for k in range(int(round(0.15 * rate)) + 1):
        t = k / rate
        s = t / 0.15
        lines.append(f"{t!r},{0.15 * (10 * s**3 - 15 * s**4 + 6 * s**5)!r}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_kick_table_runs_end_to_end(tmp_path, capsys):
    table = _smooth_table(tmp_path / "plate.csv")
    out = tmp_path / "run"
    status, stdout, err = _simulate(["--kick-table", str(table), "--duration", "0.6", "--no-plot",
                                     "--out", str(out)], capsys)
    assert status == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["scenario"]["kick_profile"] == "table" and s["scenario"]["kick_table"] == str(table)
    assert s["kick"]["table"]["rows"] == 151 and s["kick"]["duration_s"] == 0.15
    assert abs(s["kick"]["peak_acceleration_m_s2"] - 38.49) < 0.05
    assert "table" in stdout and "151 rows" in stdout and err == ""
    rows = (out / "trajectory.csv").read_text().splitlines()
    assert len(rows) == 1 + 1101                 # header + -0.5..0.6 s at 1 kHz, each sample once
    # Same as spelling the profile out, and the same as the built-in smooth kick to ~1e-8.
    out2 = tmp_path / "run2"
    assert _simulate(["--kick-profile", "table", "--kick-table", str(table), "--duration", "0.6", "--no-plot",
                      "--quiet", "--out", str(out2)], capsys)[0] == 0
    assert (out2 / "trajectory.csv").read_text() == (out / "trajectory.csv").read_text()
    out3 = tmp_path / "run3"
    assert _simulate(["--kick-profile", "smooth", "--duration", "0.6", "--no-plot", "--quiet",
                      "--out", str(out3)], capsys)[0] == 0
    s3 = json.loads((out3 / "summary.json").read_text())
    assert abs(s3["peaks"]["max_abs_yaw_rate_absolute_rad_s"] - s["peaks"]["max_abs_yaw_rate_absolute_rad_s"]) < 1e-6


BAD_TABLES = {
    "missing-column": ("time,x\n0,0\n0.1,0.1\n", ["no column 'y'"]),
    "non-numeric": ("time,y\n0,0\n0.1,fast\n", ["line 3", "'fast'", "not a number"]),
    "non-increasing": ("time,y\n0,0\n0.1,0.1\n0.05,0.15\n", ["line 4", "increase strictly"]),
    "non-finite": ("time,y\n0,0\n0.1,nan\n", ["line 3", "not finite"]),
    "one-row": ("time,y\n0,0\n", ["1 data row", "at least 2"]),
    "longer-than-the-run": ("time,y\n0,0\n9,0.1\n", ["[0, 9] s", "duration"]),
}


@pytest.mark.parametrize("content, fragments", BAD_TABLES.values(), ids=BAD_TABLES.keys())
def test_bad_kick_table_is_one_line_and_status_2(content, fragments, tmp_path, capsys, monkeypatch):
    table = tmp_path / "plate.csv"
    table.write_text(content)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    status, stdout, err = _simulate(["--kick-table", str(table), "--quiet"], capsys)
    assert status == 2 and stdout == ""
    assert "Traceback" not in err
    assert err.endswith("\n") and err.count("\n") == 1, err
    for fragment in ["plate.csv"] + fragments:
        assert fragment in err, (fragment, err)
    assert list(work.iterdir()) == []            # checked before any output folder is made


# ------------------------------------------------------------------ animation

def test_animate_writes_a_playable_mp4(tmp_path, capsys):
    """Acceptance: ``simulate --animate`` writes an mp4 with the expected frames, read back by imageio-ffmpeg.

    1.5 s of run (0.5 s before the kick, 1 s after) at 10 frames/s with the
    default 0.2x slow motion from the kick start to 1 s after its end
    (clipped to the run's end): 0.5 s + 1 s / 0.2 = 5.5 video s, 56 frames.
    """
    import imageio_ffmpeg

    out = tmp_path / "run"
    status, stdout, err = _simulate(["--duration", "1.0", "--animate", "--fps", "10", "--out", str(out)], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["animation.mp4", "response.png", "scenario.toml",
                                                     "summary.json", "trajectory.csv"]
    path = str(out / "animation.mp4")
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(path)
    reader = imageio_ffmpeg.read_frames(path)
    meta = next(reader)
    assert frames == sum(1 for _ in reader) == 56
    assert tuple(meta["size"]) == (1280, 720) and meta["fps"] == 10.0
    assert "animation.mp4 (56 frames, 5.6 s)" in stdout


def test_animate_without_an_encoder_writes_a_gif(tmp_path, capsys, monkeypatch):
    """No ffmpeg: the same animation as a GIF (Pillow), with a note saying how to get mp4."""
    from PIL import Image

    from whipple_kick.figures import animation

    monkeypatch.setattr(animation, "video_encoder", lambda: None)
    out = tmp_path / "run"
    status, stdout, err = _simulate(["--duration", "1.0", "--animate", "--fps", "10", "--slow-motion", "1",
                                     "--no-plot", "--out", str(out)], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["animation.gif", "scenario.toml", "summary.json", "trajectory.csv"]
    with Image.open(out / "animation.gif") as image:
        assert image.n_frames == 16 and image.size == (640, 360)
    assert "whipple_kick[video]" in stdout


def test_rider_is_designed_at_the_run_speed_unless_told(tmp_path, capsys):
    out = tmp_path / "adaptive"
    status, stdout, err = _simulate(["--speed", "2.5", "--duration", "0.5", "--no-plot", "--out", str(out)], capsys)
    assert status == 0 and err == ""
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller"]["design_speed_m_s"] == 2.5 and summary["linear_stability"]["stable"]
    assert "designed at 2.5 m/s" in stdout


def test_unstable_rider_is_one_printed_line(tmp_path, capsys):
    """The thesis' 3 m/s design at 2 m/s: the run goes on, one warning line says the rider is
    linearly unstable there, and summary.json says so too."""
    out = tmp_path / "fixed"
    status, stdout, err = _simulate(["--speed", "2", "--design-speed", "3", "--duration", "0.5", "--no-plot",
                                     "--quiet", "--out", str(out)], capsys)
    assert status == 0 and stdout == ""
    assert err.count("\n") == 1 and err.startswith("simulate: warning: ")
    assert "designed at 3 m/s is linearly unstable at 2 m/s" in err
    summary = json.loads((out / "summary.json").read_text())
    assert not summary["linear_stability"]["stable"]
    assert summary["linear_stability"]["message"] in err


@pytest.mark.parametrize("argv, row", [
    (["--bicycle", "balanceassist_701N"], 701),                            # the preset's label
    (["--bicycle", "balanceassist_701N", "--thesis-load", "635"], 635),    # the flag decides
])
def test_thesis_rider_from_the_command_line(argv, row, tmp_path, capsys):
    out = tmp_path / "thesis"
    status, _, err = _simulate(argv + ["--controller", "thesis", "--duration", "0.3", "--no-plot", "--quiet",
                                       "--out", str(out)], capsys)
    assert status == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller"]["gains"] == wk.control.thesis_gains(row)
    assert summary["controller"]["design_speed_m_s"] == 3.0


def test_no_steady_motion_is_one_physical_line_and_status_2(tmp_path, capsys, monkeypatch):
    """The issue's case (2.6 m/s with the rider designed at 3 m/s) when only the direct solve and the
    continuation in the tyre offsets are tried: that branch folds, and the message says so in
    physical terms, never with scipy's words."""
    monkeypatch.setattr(wk.steady, "TURN_LEANS_DEG", ())
    monkeypatch.setattr(wk.steady, "NEIGHBOUR_STEPS", ())
    monkeypatch.chdir(tmp_path)
    status, stdout, err = _simulate(["--speed", "2.6", "--design-speed", "3", "--quiet"], capsys)
    assert status == 2 and stdout == ""
    assert err.count("\n") == 1 and "Traceback" not in err
    for fragment in ("no near-upright steady motion at 2.6 m/s", "zero-slip offsets", "real closed-loop pole",
                     "designed at 3 m/s", "--design-speed"):
        assert fragment in err, (fragment, err)
    assert "progress" not in err and "iteration" not in err     # scipy's "not making good progress"
    assert list(tmp_path.iterdir()) == []


def test_numerical_failure_keeps_the_partial_run(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(wk.lsoda, "DEFAULT_BUDGET", wk.lsoda.Budget(allowance=1000, per_second=1000.0))
    out = tmp_path / "stalled"
    status, stdout, err = _simulate(["--duration", "2", "--no-plot", "--out", str(out)], capsys)
    assert status == 1 and stdout == ""
    assert err.count("\n") == 1 and err.startswith("simulate: numerical failure: ") and str(out) in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["outcome"] == "failed" and summary["end_time_s"] < 2.0
    rows = (out / "trajectory.csv").read_text().splitlines()
    assert len(rows) > 2


# ------------------------------------------------------------ run folders: load, rerun, output rate

#: Timing entries of a summary: the only ones two runs of one scenario may differ in.
_WALL_TIMES = ("wall_s", "integration_wall_s")


def _without_wall_times(summary):
    return {**summary, "numerics": {k: v for k, v in summary["numerics"].items() if k not in _WALL_TIMES},
            "provenance": None}


def test_a_loaded_cli_run_is_the_run_in_memory(base, tmp_path, capsys):
    """Issue 25 acceptance: Result.load of a ``simulate`` folder equals wk.run's Result of the same scenario:
    the summary exactly (JSON keeps every float's bits) but for the wall times and the provenance, the trajectory
    to trajectory.csv's 13 significant digits (relative 5e-13)."""
    out = tmp_path / "run"
    assert _simulate(["--pressure", "400", "--fz", "635", "--no-plot", "--quiet", "--out", str(out)], capsys)[0] == 0
    loaded = wk.Result.load(out)
    assert loaded.scenario == base.scenario
    assert _without_wall_times(loaded.summary) == _without_wall_times(base.summary)
    assert list(loaded.trajectory.columns) == list(base.trajectory.columns)
    a, b = loaded.trajectory.to_numpy(), base.trajectory.to_numpy()
    assert np.all(np.abs(a - b) <= 5e-13 * np.abs(b))
    assert wk.plotting.response_figure([("", loaded)]) is not None   # figures work on a loaded run


def test_scenario_file_reruns_the_run_from_another_folder(tmp_path, capsys, monkeypatch):
    """Issue 25 acceptance: ``simulate --scenario folder/scenario.toml`` reproduces the run to 1e-12 (here
    exactly: the same scenario, the same compiled model), also with a kick table given by a relative path and
    the rerun made from another folder; flags given override the file's values."""
    monkeypatch.chdir(tmp_path)
    _smooth_table(tmp_path / "plate.csv")
    first = tmp_path / "first"
    assert _simulate(["--kick-table", "plate.csv", "--pressure", "350", "--duration", "0.6", "--no-plot", "--quiet",
                      "--out", str(first)], capsys)[0] == 0
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    again = tmp_path / "again"
    assert _simulate(["--scenario", str(first / "scenario.toml"), "--no-plot", "--quiet", "--out", str(again)],
                     capsys)[0] == 0
    a, b = wk.Result.load(first), wk.Result.load(again)
    assert np.max(np.abs(a.trajectory.to_numpy() - b.trajectory.to_numpy())) <= 1e-12
    assert b.summary["scenario"]["pressure_kpa"] == 350.0 and b.summary["kick"]["table"]["rows"] == 151
    changed = tmp_path / "changed"
    assert _simulate(["--scenario", str(first / "scenario.toml"), "--pressure", "450", "--rider-mass", "70",
                      "--no-plot", "--quiet", "--out", str(changed)], capsys)[0] == 0
    sc = wk.Result.load(changed).summary["scenario"]
    assert (sc["pressure_kpa"], sc["fz_n"], sc["rider_mass_kg"], sc["duration"]) == (450.0, None, 70.0, 0.6)


@pytest.mark.parametrize("content, fragments", [
    ('speed = "fast"\n', ["scenario file", "speed = 'fast'", "not a finite number"]),
    ("sped = 3.0\n", ["unknown key 'sped'", "speed"]),
    ("speed = 30.0\n", ["scenario file", "speed", "(0, 15] m/s"]),
    ("speed = \n", ["not valid TOML"]),
    ("low_inertia = 1\n", ["low_inertia = 1", "true or false"]),
])
def test_bad_scenario_file_is_one_line_and_status_2(content, fragments, tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(content)
    status, stdout, err = _simulate(["--scenario", str(path), "--out", str(tmp_path / "run")], capsys)
    assert status == 2 and stdout == "" and err.count("\n") == 1, err
    for fragment in fragments:
        assert fragment in err
    assert not (tmp_path / "run").exists()


def test_output_rate_sets_the_rows_of_trajectory_csv(tmp_path, capsys):
    out = tmp_path / "run"
    assert _simulate(["--duration", "0.6", "--output-rate", "100", "--no-plot", "--quiet", "--out", str(out)],
                     capsys)[0] == 0
    rows = (out / "trajectory.csv").read_text().splitlines()
    assert len(rows) == 1 + 111                  # header + -0.5..0.6 s at 100 Hz
    assert json.loads((out / "summary.json").read_text())["scenario"]["output_rate"] == 100.0
    status, _, err = _simulate(["--output-rate", "0.5", "--out", str(tmp_path / "slow")], capsys)
    assert status == 2 and "output rate = 0.5 Hz" in err and "[1, 100000] Hz" in err


def test_compare_writes_the_figure_and_the_table(tmp_path, capsys):
    """Issue 25: ``compare RUN_DIR... --out`` on three run folders (one falls) writes compare.png and compare.csv
    (one row per quantity, one column per run, named by the folders) and prints the table."""
    from whipple_kick.cli import compare_main

    folders = []
    for name, argv in (("p400", []), ("p300", ["--pressure", "300"]), ("off", ["--controller", "off"])):
        folders.append(str(tmp_path / name))
        assert _simulate([*argv, "--duration", "3", "--no-plot", "--quiet", "--out", folders[-1]], capsys)[0] == 0
    out = tmp_path / "cmp"
    with pytest.raises(SystemExit) as info:
        compare_main([*folders, "--out", str(out)])
    stdout, err = capsys.readouterr()
    assert info.value.code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["compare.csv", "compare.png"]
    assert (out / "compare.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import pandas as pd
    table = pd.read_csv(out / "compare.csv", index_col="quantity")
    assert list(table.columns) == ["p400", "p300", "off"]
    assert table.loc["outcome"].tolist() == ["completed", "completed", "fell"]
    assert table.loc["tyres.pressure_rear_kpa"].astype(float).tolist() == [400.0, 300.0, 400.0]
    assert "fell" in stdout and "compare.png" in stdout
    with pytest.raises(SystemExit) as info:
        compare_main([folders[0], str(tmp_path), "--out", str(tmp_path / "cmp2")])
    stdout, err = capsys.readouterr()
    assert info.value.code == 2 and err.count("\n") == 1 and "is not a run folder" in err
    assert not (tmp_path / "cmp2").exists()


def test_gitignore_covers_the_folders_the_commands_write():
    """The quick start run from the repository root leaves git status clean: simulate's, stability's and compare's
    default folders and thesis_figures.py's figures/ are ignored (names as _default_out/_new_folder make them)."""
    import pathlib

    from whipple_kick.cli import _default_out, _new_folder
    root = pathlib.Path(__file__).resolve().parent.parent
    names = [_default_out(wk.Scenario(fz_n=635.0)).name, _default_out(wk.Scenario(), "stability").name,
             _new_folder("compare").name, "figures"]
    done = subprocess.run(["git", "-C", str(root), "check-ignore", "--no-index", *(f"{n}/x.csv" for n in names)],
                          capture_output=True, text=True, check=False)
    assert done.stdout.split() == [f"{n}/x.csv" for n in names], (names, done.stderr)


def test_rider_body_flags_reach_the_run_and_a_scenario_file(tmp_path, capsys):
    """``--rider-body leaning --lqr-model simulated``: the leaning upper body is simulated (its lean is in
    trajectory.csv, the LQR rider feeds it back) and the summary is printed; a rerun of its scenario.toml
    with body flags given keeps the file's other body fields and changes those given."""
    out = tmp_path / "lean"
    status, stdout, err = _simulate(["--rider-body", "leaning", "--lqr-model", "simulated", "--hip-damping", "40",
                                     "--duration", "1", "--no-plot", "--out", str(out)], capsys)
    assert status == 0, err
    assert "no fall in 1 s" in stdout and "summary.json" in stdout
    s = json.loads((out / "summary.json").read_text())
    sc = s["scenario"]
    assert (sc["rider_body"], sc["lqr_model"], sc["hip_damping"], sc["arms"]) == ("leaning", "simulated", 40.0, "off")
    assert s["controller"]["gains"]["kq11"] != 0.0 and "model simulated" in s["controller"]["rider"]
    header = [c.split(" [")[0] for c in (out / "trajectory.csv").read_text().splitlines()[0].split(",")]
    lean = header.index("upper_body_lean")
    rows = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1)
    assert np.abs(rows[:, lean]).max() > 1e-3   # the upper body really leans (steady lean and the kick)
    again = tmp_path / "again"
    # A reflex delay needs a reflex gain (a delay alone would be ignored: refused).
    status, _, err = _simulate(["--scenario", str(out / "scenario.toml"), "--reflex-delay", "0.05",
                                "--reflex-steer-rate", "0.5", "--duration", "0.2", "--no-plot", "--quiet",
                                "--out", str(again)], capsys)
    assert status == 0, err
    sc = wk.Result.load(again).summary["scenario"]
    assert (sc["rider_body"], sc["lqr_model"], sc["hip_damping"], sc["reflex_delay"], sc["duration"]) == (
        "leaning", "simulated", 40.0, 0.05, 0.2)
    status, _, err = _simulate(["--scenario", str(out / "scenario.toml"), "--reflex-delay", "0.05",
                                "--out", str(tmp_path / "refused")], capsys)
    # Named as it was given: the flag, with its unit (issue 40 item 11).
    assert status == 2 and "--reflex-delay 0.05 s is read only by the reflex (a reflex gain other than 0)" in err


def test_stability_takes_the_rider_body_flags(tmp_path, capsys):
    """``stability --rider-body leaning``: the linear model has the upper body (its lean mode is named in the
    table) -- the flags reach the sweep's parameters rather than being dropped."""
    from whipple_kick.cli import stability_main
    out = tmp_path / "stab"
    status, stdout, err = run_console(stability_main, ["--rider-body", "leaning", "--hip-stiffness", "400",
                                                       "--hip-damping", "5", "--controller", "off", "--speeds",
                                                       "2,3", "--out", str(out), "--no-plot", "--quiet"], capsys)
    assert status == 0, err
    summary = json.loads((out / "summary.json").read_text())
    # The upper body's lean mode at both speeds, with the hip the flags gave (not only the flags echoed back).
    assert summary["slip"]["open"]["modes"]["lean"]["speeds_m_s"] == [2.0, 3.0]
    assert "the leaning upper body (hip stiffness 400 N m/rad, hip damping 5 N m s/rad)" in summary["title"]


# ------------------------------------------------------------ issue 31: nothing silent

@pytest.mark.parametrize("command, extra", [("stability", ["--speeds", "3"]), ("simulate", ["--duration", "0.3"])])
def test_an_unreadable_bicycle_is_an_input_error_not_an_output_failure(command, extra, tmp_path, capsys):
    """Issue 31 item 21: ``--bicycle <a folder>`` said "cannot write the results: [Errno 21] Is a directory"."""
    from whipple_kick import cli
    folder = tmp_path / "bike.toml"
    folder.mkdir()
    main = {"stability": cli.stability_main, "simulate": cli.simulate_main}[command]
    status, stdout, err = run_console(main, ["--bicycle", str(folder), *extra, "--no-plot", "--quiet",
                                             "--out", str(tmp_path / "out")], capsys)
    assert status == 2 and err.count("\n") == 1, err
    assert "cannot be read" in err and str(folder) in err and "cannot write" not in err
    assert not (tmp_path / "out").exists()


def test_compare_help_prints_one_percent_sign(capsys):
    """Issue 31 item 20: argparse does not %-format a description: "5 %%" was printed as it stands."""
    from whipple_kick.cli import compare_main
    status, stdout, _ = run_console(compare_main, ["--help"], capsys)
    assert status == 0 and "5 %" in stdout and "%%" not in stdout


def test_compare_reports_a_truncated_run(tmp_path, capsys):
    """Issue 31 item 3: a run folder whose trajectory.csv was cut short is refused in one line (exit 2), also when
    it is the only run given (before: plotted as a normal run, or a traceback)."""
    from whipple_kick.cli import compare_main
    run_dir = tmp_path / "run"
    assert _simulate(["--duration", "0.5", "--settle", "0.1", "--no-plot", "--quiet", "--out", str(run_dir)],
                     capsys)[0] == 0
    lines = (run_dir / "trajectory.csv").read_text().splitlines(keepends=True)
    (run_dir / "trajectory.csv").write_text("".join(lines[:250]))
    status, stdout, err = run_console(compare_main, [str(run_dir), "--out", str(tmp_path / "cmp")], capsys)
    assert status == 2 and err.count("\n") == 1 and "truncated" in err, err
    assert not (tmp_path / "cmp").exists()


def test_a_closed_stdout_pipe_is_not_a_write_failure(tmp_path):
    """Issue 31 item 4: ``simulate ... | head`` wrote its results, then exited 2 with "cannot write the
    results" when head closed the pipe. It now exits as Unix tools do on SIGPIPE (status 141 = 128 + 13: the
    printing was cut, the results are whole), without a message, and the folder is complete."""
    out = tmp_path / "run"
    script = os.path.join(os.path.dirname(sys.executable), "simulate")
    # The reader closes the pipe before simulate prints anything, whatever the timing.
    proc = subprocess.Popen([script, "--duration", "0.5", "--no-plot", "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    proc.stdout.close()
    stderr = proc.stderr.read()
    assert proc.wait(timeout=300) == 141, stderr
    assert stderr == ""
    assert sorted(p.name for p in out.iterdir()) == ["scenario.toml", "summary.json", "trajectory.csv"]
    wk.Result.load(out)


def test_arms_on_without_a_start_is_refused_in_one_line(tmp_path, capsys):
    """Issue 40: ``simulate --arms on`` (the rider designed on the Whipple model) started from a steady turn at
    83.5 deg of steer, fell 0.434 s before the kick and exited 0 with post-kick maxima of 0.000. Now exit 2,
    one line saying how far the near-upright branch got and what to try, no folder; and the fix it names runs
    (a start within 10 deg of steer, no fall before the kick)."""
    # The arms model built first: where this test is the first to use it (an empty cache), its one-time build
    # notice would be a second line of stderr that is not the refusal's.
    from whipple_kick.model import slip
    from whipple_kick.simulate import assembly
    slip.library(assembly.model_of(wk.Scenario(arms="on").body_spec, wk.Scenario().tyre_transient).layout)
    out = tmp_path / "arms"
    status, stdout, err = _simulate(["--arms", "on", "--duration", "1", "--no-plot", "--out", str(out)], capsys)
    assert status == 2 and "Traceback" not in err
    assert err.count("\n") == 1 and "no near-upright steady motion at 3 m/s" in err
    assert "% of the offsets" in err and "--lqr-model simulated" in err
    assert not out.exists()
    status, stdout, err = _simulate(["--arms", "on", "--lqr-model", "simulated", "--duration", "1", "--no-plot",
                                     "--out", str(out)], capsys)
    assert status == 0, err
    result = wk.Result.load(out)
    summary = result.summary
    assert summary["outcome"] != "fell" or summary["fall_time_s"] > 0.0
    assert abs(np.degrees(result.trajectory["steer"].iloc[0])) < 10.0      # measured 6.5 deg


def test_item15_help_gives_the_reflex_gains_sign(capsys):
    """Issue 31 item 15: a positive --reflex-roll steers against the roll (and the bicycle falls); --help said
    nothing of the sign."""
    with pytest.raises(SystemExit):
        simulate_main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "T = -(gain x state)" in text and "a positive --reflex-roll steers out of the lean, against the roll" in text
    assert "T = -gain x roll (a positive gain steers against the roll)" in text


@pytest.mark.parametrize("command", ["simulate", "recommend", "validate"])
def test_help_gives_the_duration_cap_and_every_file_written(command, capsys):
    """Issue 40 item 16: --help did not say --duration is at most 120 s, nor that simulate writes scenario.toml."""
    from whipple_kick.simulate.scenario import MAX_DURATION
    with pytest.raises(SystemExit):
        getattr(wk.cli, f"{command}_main")(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert re.search(rf"--duration S [^-]*at most {MAX_DURATION:g}\)", text), text
    with pytest.raises(InputError, match=rf"\(0, {MAX_DURATION:g}\] s"):
        wk.Scenario(duration=MAX_DURATION + 1).validate()
    if command == "simulate":
        for name in wk.cli._OUTPUT_FILES:
            assert name.split(".")[0] in text, name   # animation.mp4 or .gif
        assert "scenario.toml" in text


@pytest.mark.parametrize("given", [False, True])
def test_an_ended_recommendation_says_what_it_kept(given, tmp_path, capsys, monkeypatch):
    """Issue 40 item 16: SIGTERM's (and Ctrl-C's) line said "kept in the --out folder (if given)"; it says where,
    or that nothing was kept."""
    from whipple_kick.errors import Terminated

    def ended(argv):
        raise Terminated("terminated (SIGTERM)")
    monkeypatch.setattr(wk.cli, "_recommend", ended)
    out = tmp_path / "sweep"
    code, _, err = run_console(wk.cli.recommend_main, ["--fz", "635", *(["--out", str(out)] if given else [])],
                               capsys)
    assert code == wk.cli.EXIT_TERMINATED and err.count("\n") == 1 and "if given" not in err
    if given:
        assert f"the finished cases are kept in {out}: run again with --out {out} to resume" in err
    else:
        assert "no results were kept (--out DIR keeps the finished cases" in err
    assert wk.cli._out_given(["--fz", "635", f"--ou={out}"]) == str(out)
