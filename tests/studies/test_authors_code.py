"""The compatibility mode against the thesis authors' stored run (tests/data/authors_model/README.md).

Tolerances: the mode reproduces the published code's camber sign, start (with its pitch that leaves
the front contact 3.2-4.0 mm below the ground), slip speed and plate stop, but not its wheel-contact
geometry (contact 2 r_t below the rim point, rolling on the rim, lateral slip at geometric points):
that remains as the differences measured here (docs/validation.md, "The authors' published code").
The mode was tuned on the standard run; the 400 kPa run and the kick to the left were held out.
"""
import json
import pathlib

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.model import slip
from whipple_kick.simulate.simulation import Scenario, run
from whipple_kick.studies import authors_code

DATA = pathlib.Path(__file__).resolve().parents[1] / "data" / "authors_model"


@pytest.fixture(scope="module")
def stored():
    return authors_code.load_run(DATA)


@pytest.fixture(scope="module")
def compat():
    return run(Scenario.authors_code())


def test_each_signal_within_10_percent_of_its_peak_over_the_first_second(compat, stored):
    """Acceptance: yaw, roll and steer rate, roll, steer, rear and front lateral force within 10 % of each
    signal's peak over 0-1 s after the kick. Measured: 1.8 / 1.0 / 2.7 / 1.8 / 4.2 / 1.1 / 2.5 % (with the
    wheel centre's slip speed and the compressed start pitch: 2.9 / 3.7 / 5.1 / 1.9 / 2.8 / 6.5 / 4.9 %)."""
    deviation = authors_code.deviations(compat.trajectory, stored.samples, window=(0.0, 1.0))
    assert set(deviation) == set(authors_code.SIGNALS)
    assert max(deviation.values()) < 0.10, deviation


#: The runs held out from the mode's tuning: name -> measured deviations [%] over 0-1 s (yaw, roll and steer
#: rate, roll, steer, rear and front F_y) of the mode, and of it with the wheel centre's slip speed and the
#: compressed start pitch (before issue 24).
HELD_OUT = {"T03_400kPa_635N": ("1.9 / 2.4 / 3.9 / 0.8 / 2.5 / 7.7 / 4.5",
                                "7.4 / 9.5 / 14.7 / 3.5 / 2.5 / 34.5 / 17.0"),
            "T03_500kPa_635N_kickleft": ("1.8 / 1.0 / 3.1 / 1.2 / 3.2 / 2.0 / 3.1",
                                         "3.7 / 4.9 / 7.8 / 1.9 / 1.9 / 10.6 / 6.8")}


@pytest.fixture(scope="module", params=sorted(HELD_OUT))
def held_out(request):
    folder, changes = authors_code.STORED_RUNS[request.param]
    return request.param, authors_code.load_run(DATA / folder), run(Scenario.authors_code(duration=1.2, **changes))


def test_held_out_runs_each_signal_within_10_percent_of_its_peak_over_the_first_second(held_out):
    """Acceptance on the runs the mode was not tuned on (HELD_OUT gives the measured values)."""
    name, theirs, ours = held_out
    deviation = authors_code.deviations(ours.trajectory, theirs.samples, window=(0.0, 1.0))
    assert max(deviation.values()) < 0.10, (name, deviation)


def test_held_out_runs_first_yaw_rate_peak_within_2_percent_and_5_ms(held_out):
    """Measured: 400 kPa -1.8852 rad/s at 0.1769 s against their -1.8768 at 0.1765 s (0.45 %, 0.4 ms); kick
    to the left +1.8395 at 0.1787 s against +1.8359 at 0.1786 s (0.20 %, 0.1 ms)."""
    name, theirs, ours = held_out
    t_ours, v_ours = authors_code.first_yaw_peak(ours.trajectory)
    t_theirs, v_theirs = authors_code.first_yaw_peak(theirs.samples)
    assert (v_theirs > 0) == name.endswith("kickleft")   # the kick to the left yaws right first
    assert abs(v_ours - v_theirs) <= 0.02 * abs(v_theirs)
    assert abs(t_ours - t_theirs) <= 0.005


def test_first_yaw_rate_peak_within_2_percent_and_5_ms(compat, stored):
    """Acceptance. Measured (parabola-refined): -1.7220 rad/s at 0.1806 s against their -1.7217 at 0.1807 s
    (0.02 %, 0.1 ms; with the wheel centre's slip speed and the compressed pitch -1.7234 at 0.1812 s)."""
    t_ours, v_ours = authors_code.first_yaw_peak(compat.trajectory)
    t_theirs, v_theirs = authors_code.first_yaw_peak(stored.samples)
    assert v_theirs < -1.7   # the kick to the right yaws the bicycle left first, in both codes
    assert abs(v_ours - v_theirs) <= 0.02 * abs(v_theirs)
    assert abs(t_ours - t_theirs) <= 0.005


def test_falls_between_3_5_and_4_1_s_like_the_published_run(compat, stored):
    """Acceptance: their run falls at 3.832 s; the mode at 3.601 s (measured; 3.733 s with the wheel centre's
    slip speed and the compressed start pitch)."""
    assert stored.fall_time_s == pytest.approx(3.832, abs=1e-3)
    assert compat.summary["fell"]
    assert 3.5 <= compat.summary["fall_time_s"] <= 4.1


def test_with_our_camber_sign_it_does_not_fall_within_6_s():
    """Acceptance: everything else the published code's, camber thrust toward the lean: no fall."""
    r = run(Scenario.authors_code(camber_sign="physical"))
    assert r.summary["outcome"] == "completed" and r.summary["end_time_s"] == pytest.approx(6.0)


def test_the_plate_stop_leaves_the_published_rear_slide(compat):
    """Their plate stop leaves the rear no-slip condition violated by 0.204 m/s: the plate's 2 m/s before
    the stop times sin(yaw) there. Measured: -0.2045 m/s (theirs 0.204 in size: their yaw -0.1021 rad at 0.15 s)."""
    jump, = compat.summary["energy"]["velocity_jumps"]
    assert jump["rear_slide_m_s"] == pytest.approx(-0.204, abs=1e-3)
    df = compat.trajectory
    yaw = np.interp(0.15, df["time"], df["yaw"])
    assert jump["rear_slide_m_s"] == pytest.approx(2.0 * np.sin(yaw), rel=1e-6)


@pytest.mark.parametrize("name", sorted(authors_code.STORED_RUNS))
def test_parameters_equal_the_authors_number_for_number(name):
    """Every value of their parameter array that their runs use, their tyre's coefficients and its friction
    factor equal ours (exactly), for each stored run (the 400 kPa one: their 400 kPa fit and k_z 106000 N/m)."""
    folder, changes = authors_code.STORED_RUNS[name]
    stored = authors_code.load_run(DATA / folder)
    assert len(stored.samples) == 1001 and list(stored.samples.columns) == ["time", *authors_code.SIGNALS]
    sc = Scenario.authors_code(**changes)
    moore, _, _ = wk.assembly.build_bicycle(sc.bicycle_spec)
    rear, front, _ = wk.assembly.build_tyres(sc.tyre_spec)
    params = slip.model_parameters(moore, rear, front)
    for theirs, ours in authors_code.PARAMETER_NAMES.items():
        assert params[ours] == stored.parameters[theirs], (theirs, ours)
    assert rear.curve_scale == front.curve_scale == stored.tyre["Friction_coeff"]
    for tyre in (rear, front):
        (weight, fy, mz), = tyre.blend    # one measured pressure: their 500 kPa set
        assert weight == 1.0 and fy.tolist() == stored.tyre["Fy_coef"] and mz.tolist() == stored.tyre["Mz_coef"]
    assert wk.assembly.controller_gains(sc.gains_spec, moore)[0] == {"kq4": -19.5679, "kq7": 15.4934,
                                                          "ku4": -6.7665, "ku7": 1.5876}


def _start(scenario):
    sc = scenario.validate()
    return wk.assembly.assemble(sc, wk.inputs.kick_of(sc)).start


@pytest.mark.parametrize("name", sorted(authors_code.STORED_RUNS))
def test_upright_start_with_the_uncompressed_pitch_is_theirs(name):
    """Their start solves the pitch with the tyres uncompressed, then splits the weight as on rigid tyres:
    ours (start_pitch "uncompressed": the compressions in vertical equilibrium at that pitch) gives their
    pitch and compressions (measured equal to 2e-15) and their front contact below the ground (3.206 mm
    at 500 kPa, 4.022 mm at 400 kPa, as their records say)."""
    folder, changes = authors_code.STORED_RUNS[name]
    theirs = authors_code.load_run(DATA / folder)
    start = _start(Scenario.authors_code(**changes))
    for ours_name, theirs_name in (("q5", "q5"), ("q9", "q11"), ("q10", "q12")):
        assert start.x[slip.X[ours_name]] == pytest.approx(theirs.initial_state[theirs_name], abs=1e-12)
    offset = start.unknowns["front_contact_offset_m"]
    assert offset == pytest.approx(start.x[slip.X["q9"]] - start.x[slip.X["q10"]], rel=1e-3)
    if folder != ".":
        record = json.loads((DATA / folder / "run.json").read_text())
        assert offset == pytest.approx(record["front_contact_offset_at_start_m"], abs=1e-12)


def test_upright_start_with_the_compressed_pitch_has_the_front_contact_on_the_ground(stored):
    """start_pitch "compressed" solves pitch and compressions together: the front contact on the ground, the
    weight split as our statics say: their loads 682.8 and 256.5 N, ours 684.4 and 254.9 N (0.23 %, 0.61 %;
    the same total, the weight: measured 2e-16 apart, asserted 1e-6)."""
    start = _start(Scenario.authors_code(start_pitch="compressed"))
    assert abs(start.unknowns["front_contact_offset_m"]) < 1e-12
    _, out = slip.CompiledRHS(start.params).outputs(0.0, start.x)
    loads = {}
    for ours, theirs, k in (("fz_r", "q11", "k_r"), ("fz_f", "q12", "k_f")):
        loads[ours] = stored.initial_state[theirs] * stored.parameters[k]
        assert out[slip.OUT[ours]] == pytest.approx(loads[ours], rel=1e-2)
    assert out[slip.OUT["fz_r"]] + out[slip.OUT["fz_f"]] == pytest.approx(sum(loads.values()), rel=1e-6)


def test_slip_speed_is_the_contact_points_forward_speed(compat):
    """slip_speed "contact_point": the rolling speeds the slip angle and relaxation use are the forward
    speeds of the geometric contact points (the rear one relative to the plate), here checked against
    central differences of the contact positions at 1 kHz (measured agreement 5e-5 m/s, at the plate stop);
    with slip_speed "wheel_centre" the same check is off by up to 0.07 m/s (rear) and 0.17 m/s (front)."""
    df = compat.trajectory[compat.trajectory["time"] <= 1.0]   # the first second (near the fall, 1 kHz is coarse)
    sc = Scenario.authors_code()
    moore, _, _ = wk.assembly.build_bicycle(sc.bicycle_spec)
    rear, front, _ = wk.assembly.build_tyres(sc.tyre_spec)
    params = {**dict(moore), "rtr": rear.crown_radius, "rtf": front.crown_radius}
    columns = ("x_rear", "y_rear", "yaw", "roll", "frame_pitch", "rear_wheel_angle", "steer", "front_wheel_angle",
               "compression_rear", "compression_front")
    pose = wk.geometry.evaluate({f"q{i + 1}": df[c].to_numpy() for i, c in enumerate(columns)}, params)
    t = df["time"].to_numpy()
    yaw = df["yaw"].to_numpy()
    plate = np.column_stack([np.zeros_like(t), df["plate_velocity"].to_numpy()])
    heading = {"rear": np.column_stack([np.cos(yaw), np.sin(yaw)]), "front": pose.directions["front_heading"][:, :2]}
    worst = {}
    for wheel, point, moving in (("rear", "rear_contact", plate), ("front", "front_contact", 0.0)):
        velocity = np.gradient(pose.points[point][:, :2], t, axis=0) - moving
        forward = np.sum(velocity * heading[wheel], axis=1)[1:-1]
        worst[wheel] = np.max(np.abs(forward - df[f"rolling_speed_{wheel}"].to_numpy()[1:-1]))
    assert max(worst.values()) < 1e-4, worst


def test_stored_run_is_read_with_our_names_and_checked(stored, tmp_path):
    assert list(stored.samples.columns) == ["time", *authors_code.SIGNALS]
    assert len(stored.samples) == 1001 and stored.samples["time"].iloc[-1] == pytest.approx(1.0)
    assert stored.whole["time"].iloc[-1] == pytest.approx(stored.fall_time_s, abs=1e-3)
    with pytest.raises(InputError, match=r"run_0-1s_1kHz\.csv\.gz"):
        authors_code.load_run(tmp_path)
    short = stored.samples[stored.samples["time"] <= 0.5]
    with pytest.raises(InputError, match="window"):
        authors_code.deviations(short, stored.samples)


def test_the_701N_preset_takes_its_own_table_8_4_gains():
    """Issue 24: Scenario.authors_code(bicycle="balanceassist_701N") kept the 635 N gains silently. The preset's
    label now selects the row; gains of another load are possible (thesis_load_n) and warned about."""
    sc = Scenario.authors_code(bicycle="balanceassist_701N")
    moore, _, _ = wk.assembly.build_bicycle(sc.bicycle_spec)
    assert wk.assembly.controller_gains(sc.gains_spec, moore)[0] == wk.control.thesis_gains(701.0)
    assert wk.assembly.thesis_gains_warning(sc.gains_spec) is None
    assert wk.assembly.thesis_gains_warning(Scenario.authors_code().gains_spec) is None
    warning = wk.assembly.thesis_gains_warning(sc.with_changes(thesis_load_n=635.0).gains_spec)
    assert "those for 635 N, but bicycle 'balanceassist_701N' is labelled a rear load of 701 N" in warning
    # A bicycle without rider: the load its rider is seated for.
    seated = Scenario(controller="thesis", fz_n=701.0, thesis_load_n=570.0)
    warning = wk.assembly.thesis_gains_warning(seated.gains_spec)
    assert "those for 570 N, but the rider is seated for a rear load of 701 N" in warning
    assert wk.assembly.thesis_gains_warning(seated.with_changes(controller="lqr").gains_spec) is None
