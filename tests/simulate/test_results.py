"""Results of a run: the trajectory table and its units, the summary, the recovery and the energy balance."""
import json
import math
import pathlib
import re

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.errors import SimulationError
from whipple_kick.model import slip
from whipple_kick.simulate import results
from whipple_kick.simulate.scenario import Scenario
from whipple_kick.simulate.simulation import run


def test_every_column_has_one_unit_from_one_source():
    """Units come from the compiled model's output table and the energy columns: no second list to drift."""
    mapped = {**results.APPLIED_COLUMNS, **results.OUTPUT_COLUMNS, **results.PATCH_OUTPUT_COLUMNS}
    for output, column in mapped.items():
        assert results.UNITS[column] == slip.OUTPUTS[output][0], column
    assert set(mapped) == set(slip.OUTPUTS)
    for column, unit in results.UNITS.items():
        assert unit and isinstance(unit, str), column


def test_clean_refuses_what_json_cannot_hold():
    assert results.clean({"a": np.float64(1.5), "b": [np.int64(2), True], "c": complex(1, -2)}) == \
        {"a": 1.5, "b": [2, True], "c": [1.0, -2.0]}
    with pytest.raises(SimulationError, match="non-finite value nan in the summary"):
        results.clean({"a": [0.0, math.nan]})


def test_clean_keeps_every_leaf_of_a_plain_dict_and_list():
    """The plain dicts' and lists' leaves are kept as clean gives them (floats, strings, None, bools, ints); the
    others still go through clean (a numpy scalar, a tuple, a non-string key, a non-finite float)."""
    value = {"f": 1.5, "s": "x", "n": None, "b": False, "i": 3, 7: (np.float64(2.5), [0.5, np.int64(4)]),
             "nested": {"list": [1.0, -0.0, True]}}
    cleaned = results.clean(value)
    assert cleaned == {"f": 1.5, "s": "x", "n": None, "b": False, "i": 3, "7": [2.5, [0.5, 4]],
                       "nested": {"list": [1.0, -0.0, True]}}
    assert [type(v) for v in cleaned["7"][1]] == [float, int] and math.copysign(1.0, cleaned["nested"]["list"][1]) < 0
    for bad in ({"a": math.inf}, {"a": [1.0, -math.inf]}, [{"a": math.nan}]):
        with pytest.raises(SimulationError, match="non-finite value"):
            results.clean(bad)


def test_the_samples_after_the_kick_are_a_slice_where_they_are_the_last_ones():
    """A run's time increases: the samples at or after the kick are a slice (views, not copies); any other time
    column keeps its mask, so the same samples are selected either way."""
    for time in (np.array([-0.2, -0.1, 0.0, 0.1]), np.array([0.0, 0.1]), np.array([-0.2, -0.1]), np.array([]),
                 np.array([0.1, -0.1, 0.2]), np.array([-0.1, 0.1, -0.2])):
        rows = results._after_kick(time)
        assert np.array_equal(time[rows], time[time >= 0.0])
        assert isinstance(rows, slice) == bool(np.all(np.diff((time >= 0.0).astype(int)) >= 0))


def test_the_peaks_are_kick_metrics_largest_values(base):
    """The summary's peaks take kick_metrics' largest absolute values after the kick where it has them: the same
    numbers as the section finds by itself."""
    from whipple_kick.simulate import analysis
    metrics = analysis.kick_metrics(base.trajectory, include_spectra=False)
    known = {n: metrics[f"max_abs_{n}"] for n in results.PEAK_COLUMNS if metrics.get(f"max_abs_{n}") is not None}
    assert len(known) == len(results.PEAK_COLUMNS) - 1   # all but the steer torque
    assert results._peaks(base.trajectory, known) == results._peaks(base.trajectory, {}) == base.summary["peaks"]


def test_base_run_outputs(base):
    df, s = base.trajectory, base.summary
    assert not s["fell"] and s["fall_time_s"] is None
    for name in wk.analysis.COLUMNS:
        assert name in df.columns
    for name in ("plate_y", "plate_velocity", "plate_acceleration", "steer_torque", "fz_rear", "fz_front",
                 "mz_rear", "mz_front", "camber_rear", "camber_front", "slip_front", "frame_pitch"):
        assert name in df.columns and name in wk.results.UNITS
    assert np.all(np.isfinite(df.to_numpy()))
    t = df["time"].to_numpy()
    assert t[0] == pytest.approx(-0.5) and t[-1] == pytest.approx(6.0)
    np.testing.assert_allclose(np.diff(t), 1e-3, rtol=1e-6)
    # Thesis kick: 0.150 m in 0.150 s at 13.3 m/s^2, held afterwards.
    kick = (t > 0.0) & (t < 0.15)
    np.testing.assert_allclose(df["plate_acceleration"][kick], 2 * 0.15 / 0.15**2)
    assert df["plate_y"].iloc[-1] == pytest.approx(0.15)
    assert np.all(df["plate_y"][t <= 0.0] == 0.0)
    assert s["kick"]["peak_acceleration_m_s2"] == pytest.approx(13.333333)
    # The rider mass was chosen for 635 N and the loads are reported.
    assert s["bicycle"]["static_load_rear_n"] == pytest.approx(635.0)
    assert 40.0 < s["bicycle"]["rider_mass_kg"] < 100.0
    json.dumps(s, allow_nan=False)   # JSON-ready, no NaN anywhere


def test_steady_running_before_the_kick(base):
    """The 0.5 s before the kick is steady (the state from steady.steady_state does not drift)."""
    df = base.trajectory
    before = df[df["time"] <= 0.0]
    steady = base.summary["steady_state"]
    assert np.ptp(before["yaw_rate"]) < 1e-9
    assert np.ptp(before["roll"]) < 1e-9
    assert before["yaw_rate"].iloc[0] == pytest.approx(steady["yaw_rate_rad_s"], abs=1e-12)
    assert steady["residual"] < 1e-8


def test_recovery_is_reported_for_yaw_roll_and_steer_rates(base):
    rec = base.summary["recovery"]
    signals = rec["signals"]
    assert set(signals) == {"yaw_rate", "roll_rate", "steer_rate"}
    # The recovery time is when the last of the three has settled.
    assert rec["time_s"] == max(v["time_s"] for v in signals.values()) == signals[rec["last_to_settle"]]["time_s"]
    df = base.trajectory
    after = df["time"].to_numpy() >= 0.0
    for name, entry in signals.items():
        t_rec, peak = entry["time_s"], entry["first_peak_from_steady_rad_s"]
        assert 0.0 < t_rec < 6.0 and peak > 0.0 and entry["reason"] is None
        steady = df[name].iloc[0]
        dev = np.abs(df[name].to_numpy() - steady)
        # Within 5 % of the first peak from t_rec on, and outside it just before.
        assert np.all(dev[df["time"].to_numpy() >= t_rec] <= 0.05 * peak)
        assert dev[np.flatnonzero(after & (df["time"].to_numpy() < t_rec))[-1]] > 0.05 * peak
        # The yaw-rate peak is refined between samples, so it may exceed them slightly: the first one
        # comes 2.3 ms after the plate stop's impulse and is sharp (measured 2.2e-4 above the 1 kHz
        # samples, 7e-6 above those of a 20 kHz run).
        assert peak <= dev[after].max() * (1 + 5e-4)


def test_energy_balance_closes_over_the_default_run(base):
    """Issue acceptance: kinetic + gravity + tyre springs + carcasses against the cumulative works and
    dissipations closes to 1e-3 J over the whole run, across the kick start and the plate stop (measured
    8.7e-9 J at rtol 1e-10); the plate stop's impulse is in the plate's work."""
    df, energy = base.trajectory, base.summary["energy"]
    residual = df[wk.results.BALANCE_COLUMN].to_numpy()
    assert np.max(np.abs(residual)) < 1e-3
    assert energy["balance_residual_max_abs_j"] == pytest.approx(np.max(np.abs(residual)))
    # The terms are not trivially small (measured plate 16.3 J, sliding 29.0 J).
    assert energy["plate_work_j"] > 10.0 and energy["sliding_dissipation_j"] > 10.0
    jump, = energy["velocity_jumps"]
    assert jump["time_s"] == pytest.approx(0.15)
    assert jump["impulse_work_j"] == pytest.approx(jump["kinetic_energy_change_j"], abs=1e-9)
    # Works and dissipations are cumulative from the kick start; the carcass energies are what the
    # carcasses hold, c y^2 / 2 (the steady force there: 19.1 N rear -> 4.4 mJ), from the state itself.
    t = df["time"].to_numpy()
    for name in wk.energy.CUMULATIVE:
        column = wk.energy.COLUMNS[name][0]
        assert df[column].to_numpy()[t == 0.0][0] == 0.0, column
    carcass = base.summary["tyres"]["carcass"]
    for wheel in ("rear", "front"):
        stored = 0.5 * carcass[f"stiffness_{wheel}_n_per_m"] * df[f"carcass_deflection_{wheel}"].to_numpy() ** 2
        np.testing.assert_allclose(df[f"carcass_energy_{wheel}"], stored, rtol=0, atol=1e-6)
    for name in ("plate_work", "carcass_energy_rear", "slip_patch_rear", wk.results.BALANCE_COLUMN):
        assert name in wk.results.UNITS


def test_dissipation_never_decreases_with_symmetric_tyres():
    """Issue acceptance: sliding + damper dissipation never decreases (tyres without zero-slip offsets,
    whose curves oppose the slip everywhere). Measured: no decrease between samples larger than 1e-12 J."""
    r = run(Scenario(pressure_kpa=400.0, fz_n=635.0, symmetric_tyres=True))
    df = r.trajectory
    dissipation = df["sliding_dissipation"].to_numpy() + df["damper_dissipation"].to_numpy()
    assert np.min(np.diff(dissipation)) > -1e-9
    assert dissipation[-1] > 10.0
    assert np.max(np.abs(df[wk.results.BALANCE_COLUMN])) < 1e-3


def test_heading_speeds_are_the_steady_motion_before_the_kick(base):
    """forward_speed and lateral_speed rotate the fixed-frame velocity by the yaw: during the settle (steady
    turn) they stay the run's speed and the steady drift, while the fixed-frame components turn with the
    heading. Tolerance 1e-6 m/s: the steady turn is held to ~1e-6 of its states over the settle."""
    df, st = base.trajectory, base.summary["steady_state"]
    settle = df[df["time"] < 0.0]
    np.testing.assert_allclose(settle["forward_speed"], st["speed_m_s"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(settle["lateral_speed"], st["lateral_drift_m_s"], rtol=0, atol=1e-6)
    speed = np.hypot(df["velocity_x_fixed"], df["velocity_y_fixed"])
    np.testing.assert_allclose(np.hypot(df["forward_speed"], df["lateral_speed"]), speed, rtol=1e-12)
    assert np.ptp(df["velocity_x_fixed"]) > 0.5     # the fixed-frame components are not the forward speed


def test_trajectory_csv_names_carry_units_and_read_back(base, tmp_path):
    """The file's header is '<name> [<unit>]' for every column; read_trajectory gives the plain names back,
    with values within the file's 13 significant digits (5e-13 relative)."""
    path = tmp_path / "trajectory.csv"
    wk.fileio.write_csv(wk.results.with_units(base.trajectory), path,
                        significant_digits=wk.results.TRAJECTORY_CSV_DIGITS)
    header = path.read_text().splitlines()[0].split(",")
    assert header == [f"{c} [{wk.results.UNITS[c]}]" for c in base.trajectory.columns]
    assert "roll [rad]" in header and "time [s]" in header and "fy_rear [N]" in header
    back = wk.results.read_trajectory(path)
    assert list(back.columns) == list(base.trajectory.columns)
    np.testing.assert_allclose(back.to_numpy(), base.trajectory.to_numpy(), rtol=6e-13, atol=1e-300)


def test_save_and_load_round_trip(base, tmp_path):
    """Result.save writes the three files; Result.load gives the summary back exactly and the trajectory to
    trajectory.csv's 13 significant digits (relative 5e-13); a loaded result saves the same files again."""
    assert base.save(tmp_path / "run") == ["trajectory.csv", "summary.json", "scenario.toml"]
    loaded = wk.Result.load(tmp_path / "run")
    assert loaded.summary == base.summary and loaded.scenario == base.scenario
    a, b = loaded.trajectory.to_numpy(), base.trajectory.to_numpy()
    assert np.all(np.abs(a - b) <= 5e-13 * np.abs(b))
    loaded.save(tmp_path / "again")
    for name in ("trajectory.csv", "summary.json", "scenario.toml"):
        assert (tmp_path / "again" / name).read_bytes() == (tmp_path / "run" / name).read_bytes()


def test_load_of_a_folder_that_is_not_a_run_is_one_line(tmp_path):
    with pytest.raises(wk.InputError, match="does not exist"):
        wk.Result.load(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(wk.InputError, match=r"is not a run folder: it has no summary\.json"):
        wk.Result.load(tmp_path / "empty")
    (tmp_path / "empty" / "summary.json").write_text("{not json")
    (tmp_path / "empty" / "trajectory.csv").write_text("time [s]\n0\n")
    with pytest.raises(wk.InputError, match="is not a run summary"):
        wk.Result.load(tmp_path / "empty")


#: Unit suffixes of summary keys (results.unit_suffix of the units used): s, rad, rad/s, m, N, N m, J, W, kg, kPa,
#: m/s, m/s^2, 1/s.
_UNIT_SUFFIX = re.compile(r"_(s|rad|rad_s|deg|m|n|n_m|n_per_m|n_s_per_m|j|w|kg|kpa|m_s|m_s2|1_s)$")
#: Numbers without a unit: counts, ratios and tolerances; the gains' units are in controller.gain_units, the steady
#: powers' unit in the name of their section (steady_power_w).
_DIMENSIONLESS = re.compile(r"^(controller\.gain_scale|bicycle\.(steady_)?rear_load_share|controller\.gains\..*|steady_state\.steady_power_w\..*|"
                            r"steady_state\.residual|metrics\.n_peaks|metrics\.(log_decrement|damping_ratio)_\d_\d|"
                            r"numerics\.(rtol|nfev|njev|evaluations|budget\..*))$")


def _numeric_keys(node, prefix=""):
    for key, value in node.items():
        if isinstance(value, dict):
            yield from _numeric_keys(value, f"{prefix}{key}.")
        elif (isinstance(value, (int, float)) and not isinstance(value, bool)) or (
                isinstance(value, list) and value and isinstance(value[0], (int, float, list))):
            yield f"{prefix}{key}"


def test_every_number_in_the_summary_has_a_unit_in_its_key(base):
    """Issue 25: a unit suffix on every key holding a number (dimensionless ones listed above), and the peaks
    named 'absolute' or 'from steady'."""
    keys = list(_numeric_keys({k: v for k, v in base.summary.items() if k not in ("scenario", "units")}))
    assert len(keys) > 80
    assert [k for k in keys if not (_UNIT_SUFFIX.search(k) or _DIMENSIONLESS.match(k))] == []
    peaks = [k for k in keys if k.startswith(("peaks.", "metrics.", "recovery.")) and "peak" in k
             and "time" not in k and not k.startswith("metrics.n_")]   # the response's (not the plate's) peaks
    assert peaks and all("absolute" in k or "from_steady" in k for k in peaks), peaks


def test_the_summary_gives_the_static_and_the_steady_loads_each_named(base):
    """Issue 40 item 15: the summary gave only the no-compression statics (635 N) as the run's load. Both are given,
    named for which they are: the static ones are what the rider is sized for, the steady ones the tyres' normal
    forces in the state the run starts from (the trajectory's first sample, exactly) and sum to the weight's
    support to the steady motion's accuracy. Measured in the default run: 635.000 N / 0.63675 static, 636.004 N /
    0.63775 steady; bound: the steady load 0.1-5 N above the static (the frame pitches forward-up as the tyres
    compress) and the sum within 1e-6 of the static sum."""
    b = base.summary["bicycle"]
    assert b["static_load_rear_n"] == pytest.approx(635.0, abs=1e-9)
    first = base.trajectory.iloc[0]
    assert b["steady_load_rear_n"] == first["fz_rear"] and b["steady_load_front_n"] == first["fz_front"]
    assert 0.1 < b["steady_load_rear_n"] - b["static_load_rear_n"] < 5.0
    total = b["static_load_rear_n"] + b["static_load_front_n"]
    assert b["steady_load_rear_n"] + b["steady_load_front_n"] == pytest.approx(total, rel=1e-6)
    assert b["steady_rear_load_share"] == pytest.approx(b["steady_load_rear_n"] / total, rel=1e-6)
    assert b["rear_load_share"] == pytest.approx(635.0 / total, rel=1e-12)
    assert "static_load_* and rear_load_share: rigid-contact statics" in b["loads_are"]


def test_recovered_says_whether_all_three_rates_settled(base):
    s = base.summary
    assert s["recovered"] is True and s["outcome"] == "completed" and s["recovery"]["time_s"] is not None
    short = run(Scenario(duration=1.0))          # too short to settle (the default run recovers at 2.7 s)
    assert short.summary["outcome"] == "completed" and short.summary["recovered"] is False
    assert short.summary["recovery"]["time_s"] is None
    fell = run(Scenario(controller="off", duration=3.0))
    assert fell.summary["fell"] and fell.summary["recovered"] is False


def test_extrapolation_gives_the_true_load_extremes(base):
    """Issue 31 item 12: min_load_n was ``load.min(initial=0.0)``, always 0 N. Each wheel's extremes are those of
    the trajectory's own fz column after the kick start (an independent reading of the same samples: exact)."""
    after = base.trajectory["time"] >= 0.0
    for wheel in ("rear", "front"):
        e = base.summary["tyres"]["extrapolation"][wheel]
        load = base.trajectory.loc[after, f"fz_{wheel}"]
        assert e["min_load_n"] == float(load.min()) and e["max_load_n"] == float(load.max())
        assert 0.0 < e["min_load_n"] < e["max_load_n"]
    # The default run's rear minimum: 525.3 N here; the issue read 523.5 N on its commit. 2.5 N holds both: the
    # point is a true minimum, 110 N below the static 635 N, not 0 (a model change moves it a little).
    assert base.summary["tyres"]["extrapolation"]["rear"]["min_load_n"] == pytest.approx(525.3, abs=2.5)


@pytest.mark.parametrize("slip_deg, load_min, load_max", [(2.0, 400.0, 700.0), (50.0, 100.0, 2000.0),
                                                         (5.5, 560.0, 2000.0), (50.0, 100.0, 640.0)])
def test_extrapolation_times_are_the_samples_beyond_the_measured_ranges(slip_deg, load_min, load_max):
    """Each time outside a measured range sums the sample intervals of the samples outside it (0.0 where none is),
    whether the largest value reaches past the range or not."""
    import types
    t = np.linspace(-0.5, 1.0, 151)
    wave = np.sin(7.0 * t)
    frame = {"time": t, "slip_rear": np.radians(6.0) * wave, "slip_front": np.radians(3.0) * wave,
             "slip_patch_rear": np.radians(5.0) * wave, "fz_rear": 600.0 + 50.0 * wave, "fz_front": 400.0 - 30.0 * wave}
    tyre = types.SimpleNamespace(measured={"slip_deg": slip_deg, "load_min": load_min, "load_max": load_max})
    out = results.extrapolation(frame, tyre, tyre)
    after = t >= 0.0
    dt = np.diff(t[after], append=t[-1])
    for wheel, patch in (("rear", "slip_patch_rear"), ("front", "slip_front")):
        kinematic = np.degrees(np.abs(frame[f"slip_{wheel}"][after]))
        load = frame[f"fz_{wheel}"][after]
        e = out[wheel]
        assert e["kinematic_slip_beyond_s"] == float(np.sum(dt[kinematic > slip_deg]))
        assert e["patch_slip_beyond_s"] == float(np.sum(dt[np.degrees(np.abs(frame[patch][after])) > slip_deg]))
        assert e["load_outside_s"] == float(np.sum(dt[(load < load_min) | (load > load_max)]))


def _saved_run(folder, rows=600):
    """A short run saved in ``folder`` (0.1 s settle + 0.5 s at 1000 Hz: 601 rows)."""
    result = run(Scenario(duration=0.5, settle=0.1))
    result.save(folder)
    return result


def test_load_refuses_a_truncated_trajectory(tmp_path):
    """Issue 31 item 3: a trajectory.csv cut short (a copy interrupted, a full disk) is refused in one line naming
    the rows and the end time summary.json promises (before: loaded and plotted as a normal run)."""
    folder = tmp_path / "run"
    _saved_run(folder)
    wk.Result.load(folder)                                   # the whole file loads
    lines = (folder / "trajectory.csv").read_text().splitlines(keepends=True)
    (folder / "trajectory.csv").write_text("".join(lines[:300]))   # cut at a row boundary
    with pytest.raises(wk.InputError) as info:
        wk.Result.load(folder)
    message = str(info.value)
    assert "\n" not in message and "truncated" in message and "0.5" in message, message
    # Cut in the middle of a row: the last row is short (pandas would fill it with NaN).
    (folder / "trajectory.csv").write_text("".join(lines)[:-40])
    with pytest.raises(wk.InputError, match=r"trajectory\.csv"):
        wk.Result.load(folder)


@pytest.mark.parametrize("edit, fragment", [
    (lambda text: text.replace("time [s]", "t [s]", 1), "no time column"),
    (lambda text: text.replace("\n0.1", "\nabc", 1), "not a number"),
    (lambda text: "\n".join(line for k, line in enumerate(text.split("\n")) if k != 200), "time"),
    (lambda text: text.split("\n", 1)[0] + "\n", "is empty: it has the header but no rows"),
], ids=["time column renamed", "text in a row", "a row missing in the middle", "the header alone"])
def test_load_refuses_a_malformed_trajectory(edit, fragment, tmp_path):
    folder = tmp_path / "run"
    _saved_run(folder)
    path = folder / "trajectory.csv"
    path.write_text(edit(path.read_text()))
    with pytest.raises(wk.InputError) as info:
        wk.Result.load(folder)
    assert "\n" not in str(info.value) and fragment in str(info.value), str(info.value)


def test_a_fall_is_status_1_and_a_success():
    """Issue 32 item 5: the Result says how the run ended as SciPy's OdeResult does: a fall is a terminal
    event (status 1) and a success (the model did what it should); -1 is kept for numerical failure
    (tests/simulate/test_integration.py) and 0 for a run that reached its end (the Result.status doctest)."""
    result = wk.run(wk.Scenario(controller="off", duration=2.5, output_rate=200.0))
    assert result.summary["fell"]
    assert (result.status, result.success) == (1, True)
    assert result.message == result.summary["message"] and "\n" not in result.message


@pytest.mark.parametrize("changes", [
    {},                                                                   # carcass tyre, completed
    {"tyre_transient": "force_lag"},                                      # no patch columns
    {"rider_body": "leaning", "duration": 0.8},                           # a part's states and outputs
    {"controller": "off", "duration": 3.0, "fall_angle_deg": 20.0},       # ends in a fall
    {"kick_profile": "table",                                             # a model per table piece
     "kick_table": str(pathlib.Path(__file__).parents[1] / "data" / "regression" / "kick_table_smooth_10ms.csv")},
])
def test_the_lean_path_gives_the_tables_values_and_the_same_summary(changes):
    # run(columns=...) builds no table: its columns must be the table's, bit for bit (the same sources and
    # arithmetic), and its summary the table's summary exactly, but for the run's wall times and the date.
    scenario = Scenario(duration=1.2, settle=0.1).with_changes(**changes)
    full = run(scenario)
    lean = run(scenario, columns="all")
    assert list(lean.trajectory) == list(full.trajectory.columns)
    for column in full.trajectory.columns:
        assert np.array_equal(lean.trajectory[column], full.trajectory[column].to_numpy()), column

    def comparable(summary):
        numerics = {k: v for k, v in summary["numerics"].items() if k not in ("wall_s", "integration_wall_s")}
        return {**summary, "numerics": numerics, "provenance": None}

    assert comparable(lean.summary) == comparable(full.summary)
    assert json.dumps(comparable(lean.summary)) == json.dumps(comparable(full.summary))   # -0.0 is not 0.0 here
    only = run(scenario, columns=("plate_y",))
    assert "plate_y" in only.trajectory and "camber_front" not in only.trajectory
    assert comparable(only.summary) == comparable(full.summary)
    # A table-only case (a sweep's row): no optional output group evaluated (slip.layout.OPTIONAL_OUTPUTS),
    # the same summary, JSON text included, and the same values of the columns it keeps.
    row = run(scenario, columns=())
    assert json.dumps(comparable(row.summary)) == json.dumps(comparable(full.summary))
    assert row.trajectory and all(np.array_equal(values, full.trajectory[column].to_numpy())
                                  for column, values in row.trajectory.items())
    with pytest.raises(wk.errors.InputError, match=r"trajectory column\(s\) \['rol'\] do not exist"):
        run(scenario, columns=("rol",))


def test_the_lean_path_refuses_a_non_finite_value_where_the_table_does():
    """trajectory_columns checks the table's columns as trajectory_frame does (whole arrays first, then the
    table's columns): a NaN in an output of the table fails both, one in an output the table leaves out
    neither."""
    from whipple_kick.library import inputs
    from whipple_kick.simulate import assembly, integration

    scenario = Scenario(duration=0.3, settle=0.05, tyre_transient="force_lag")   # its table has no patch slip
    kick = inputs.kick_of(scenario.validate())
    solution = integration.integrate_run(assembly.assemble(scenario, kick), scenario, kick)
    outputs = solution.outputs()
    layout = results.frame_layout(scenario.tyre_transient, solution.model)
    used = sorted({index for _, source, index in layout if source == "output"})
    unused = [k for k in range(outputs.shape[1]) if k not in used]
    assert unused   # the patch slips the force-lag form's table does not show
    for column, fails in ((used[3], True), (unused[0], False)):
        bad = outputs.copy()
        bad[5, column] = np.nan
        solution.outputs = lambda bad=bad, **_: bad
        if fails:
            for build in (results.trajectory_frame, results.trajectory_columns):
                with pytest.raises(SimulationError, match="non-finite"):
                    build(solution, scenario.tyre_transient)
        else:
            frame = results.trajectory_frame(solution, scenario.tyre_transient)
            columns = results.trajectory_columns(solution, scenario.tyre_transient, "all")
            assert all(np.array_equal(frame[c].to_numpy(), columns[c]) for c in frame.columns)


@pytest.mark.parametrize("columns", [[0, 1, 2, 4, 7, 8], [3], [], [8, 0, 5, 6]])
def test_the_finite_check_looks_at_exactly_its_columns(columns):
    # The columns are summed at once: a NaN or an infinity anywhere in a listed column fails, elsewhere not.
    values = np.ones((4, 9))
    assert results._all_finite(values, columns)
    for k in range(9):
        for bad in (np.nan, np.inf):
            changed = values.copy()
            changed[2, k] = bad
            assert results._all_finite(changed, columns) == (k not in columns), (k, bad)
    # Finite values whose sum overflows are finite: the check looks at them value by value, not at the sum.
    huge = np.full((4, 9), np.finfo(float).max)
    assert results._all_finite(huge, columns)
    huge[1, 8] = -np.inf
    assert results._all_finite(huge, columns) == (8 not in columns)
    # Infinities of both signs in one column (their sum is NaN) fail it as a NaN does, where the column is listed.
    both = np.ones((4, 9))
    both[0, 3], both[2, 3], both[1, 5] = np.inf, -np.inf, np.nan
    assert results._all_finite(both, columns) == (3 not in columns and 5 not in columns)
