"""Kick-plate runs end to end (issue 6): scenario, outputs, thesis behaviour, numerics."""
import json
import math

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick import simulation
from whipple_kick.errors import InputError
from whipple_kick.simulation import Scenario, SimulationError, run


@pytest.fixture(scope="module")
def base():
    """The main job's run: 400 kPa, 635 N, thesis defaults."""
    return run(Scenario(pressure_kpa=400.0, fz_n=635.0))


def _recovery(result):
    return result.summary["recovery"]["time_s"]


# ------------------------------------------------------------------ outputs

def test_base_run_outputs(base):
    df, s = base.trajectory, base.summary
    assert not s["fell"] and s["fall_time_s"] is None
    for name in wk.analysis.COLUMNS:
        assert name in df.columns
    for name in ("plate_y", "plate_velocity", "plate_acceleration", "steer_torque", "fz_rear", "fz_front",
                 "mz_rear", "mz_front", "camber_rear", "camber_front", "slip_front", "pitch"):
        assert name in df.columns and name in simulation.UNITS
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
    """The 0.5 s before the kick is steady (the state from slip.steady_state does not drift)."""
    df = base.trajectory
    before = df[df["time"] <= 0.0]
    steady = base.summary["steady_state"]
    assert np.ptp(before["yaw_rate"]) < 1e-9
    assert np.ptp(before["roll"]) < 1e-9
    assert before["yaw_rate"].iloc[0] == pytest.approx(steady["yaw_rate_rad_s"], abs=1e-12)
    assert steady["residual"] < 1e-8


def test_kick_timing_variants():
    assert Scenario().kick_timing() == pytest.approx((0.15, 13.3333333, 0.15))
    dur, acc, d = Scenario(kick_accel=35.0).kick_timing()
    assert acc == 35.0 and dur == pytest.approx(math.sqrt(2 * 0.15 / 35.0)) and d == 0.15
    dur, acc, d = Scenario(kick_accel=35.0, kick_profile="smooth").kick_timing()
    assert dur == pytest.approx(math.sqrt(10 / math.sqrt(3) * 0.15 / 35.0))
    assert Scenario(kick_direction="left").kick_timing()[2] == -0.15
    with pytest.raises(InputError, match="not both"):
        Scenario(kick_accel=30.0, kick_duration=0.1).kick_timing()
    with pytest.raises(InputError, match="'table' is not supported"):
        Scenario(kick_profile="table").kick_timing()


def test_smooth_profile_peak_acceleration_matches_request():
    r = run(Scenario(kick_accel=20.0, kick_profile="smooth", duration=0.5))
    assert np.max(np.abs(r.trajectory["plate_acceleration"])) == pytest.approx(20.0, rel=2e-3)
    assert r.trajectory["plate_y"].iloc[-1] == pytest.approx(0.15)


def test_kick_to_the_left_mirrors_the_first_yaw_peak(base):
    left = run(Scenario(kick_direction="left", symmetric_tyres=True, duration=0.5))
    right = run(Scenario(kick_direction="right", symmetric_tyres=True, duration=0.5))
    np.testing.assert_allclose(left.trajectory["yaw_rate"], -right.trajectory["yaw_rate"], atol=1e-7)
    # A plate moving right pushes the rear wheel right: the bicycle first yaws left (u3 < 0).
    assert base.summary["metrics"]["peak_values"][0] < 0.0


def test_symmetric_tyres_run_upright():
    r = run(Scenario(symmetric_tyres=True, duration=0.2))
    st = r.summary["steady_state"]
    assert abs(st["roll_rad"]) < 1e-12 and abs(st["yaw_rate_rad_s"]) < 1e-12


def test_low_inertia_halves_rear_frame_inertia_and_height():
    sc = Scenario(fz_n=635.0)
    original, design, _ = simulation.build_bicycle(sc)
    low, design_low, _ = simulation.build_bicycle(Scenario(fz_n=635.0, low_inertia=True))
    b0, b1 = wk.benchmark.from_moore(original), wk.benchmark.from_moore(low)
    for key in simulation.LOW_INERTIA_KEYS:
        assert b1[key] == pytest.approx(0.5 * b0[key])
    for key in ("mB", "xB", "IHxx", "w"):
        assert b1[key] == pytest.approx(b0[key])
    assert design_low == design   # the controller is designed on the unmodified bicycle
    r = run(Scenario(fz_n=635.0, low_inertia=True, duration=1.0))
    assert np.all(np.isfinite(r.trajectory.to_numpy()))


def test_controller_variants_and_their_errors():
    gains, poles = simulation.controller_gains(Scenario(controller="thesis", fz_n=635.0, gain_scale=0.5), None)
    assert gains["kq4"] == pytest.approx(0.5 * -19.5679)
    gains, poles = simulation.controller_gains(Scenario(controller="off"), None)
    assert set(gains.values()) == {0.0} and poles is None
    with pytest.raises(InputError, match="570, 635 and 701 N"):
        simulation.controller_gains(Scenario(controller="thesis", fz_n=600.0), None)
    with pytest.raises(InputError, match="conflicts with controller off"):
        Scenario(controller="off", gain_scale=0.5).validate()
    with pytest.raises(InputError, match="already includes its rider"):
        simulation.preflight(Scenario(bicycle="balanceassist_635N", fz_n=635.0))
    with pytest.raises(InputError, match="300, 500"):
        simulation.preflight(Scenario(pressure_kpa=600.0))


def test_thesis_preset_runs():
    r = run(Scenario.thesis(pressure_kpa=400.0, duration=2.0))
    s = r.summary
    assert s["bicycle"]["bicycle"] == "balanceassist_635N" and s["bicycle"]["rider_mass_kg"] is None
    assert s["controller"]["gains"]["kq7"] == pytest.approx(15.4934)
    assert s["tyres"]["coefficient_set"] == "chapter8" and s["tyres"]["friction"] == "thesis"
    assert s["numerics"]["rtol"] == 1e-12 and not s["fell"]


def test_front_and_rear_pressures_may_differ():
    r = run(Scenario(pressure_front_kpa=300.0, pressure_rear_kpa=500.0, duration=0.3))
    assert (r.summary["tyres"]["pressure_rear_kpa"], r.summary["tyres"]["pressure_front_kpa"]) == (500.0, 300.0)


def test_tyre_without_moment_data_runs_with_zero_moment():
    r = run(Scenario(tyre="T01", duration=0.3))
    assert "M_z = 0" in r.summary["tyres"]["notes"][0]
    assert np.all(r.trajectory["mz_rear"] == 0.0)


def test_numerical_failure_is_an_exception(monkeypatch):
    def broken(*args, **kwargs):
        raise FloatingPointError("non-finite derivative in the slip model at t = 0.1 s")
    monkeypatch.setattr(wk.integrate, "integrate", broken)
    with pytest.raises(SimulationError, match="non-finite derivative"):
        run(Scenario(duration=0.3))


# ------------------------------------------------------- thesis behaviour (issue 6)

# Measured with the current slip model, our LQR gains and T03 table7_9 (rtol
# 1e-10): the yaw rate gets back within 5 % of its first peak (and stays)
# only 2.5-5.2 s after the kick: 570 N: 3.90/5.25/2.84 s, 635 N: 4.30/4.24/2.48 s,
# 701 N: 4.92/3.60/3.70 s at 300/400/500 kPa. Roll and steer settle in ~1.5 s;
# the yaw rate decays slowly because nothing controls the heading. The thesis
# reports recovery within 2 s. Reported to the lead; not tuned.
_RECOVERY_XFAIL = ("issue 6 acceptance not met by the current model: yaw rate back within 5 % of its "
                   "first peak only 2.5-5.2 s after the kick (400 kPa/635 N: 4.24 s), thesis: < 2 s")


@pytest.mark.xfail(strict=True, reason=_RECOVERY_XFAIL)
@pytest.mark.parametrize("fz", [570.0, 635.0, 701.0])
@pytest.mark.parametrize("pressure", [300.0, 400.0, 500.0])
def test_controller_recovers_within_2_s(pressure, fz):
    r = run(Scenario(pressure_kpa=pressure, fz_n=fz))
    assert not r.summary["fell"]
    assert _recovery(r) is not None and _recovery(r) <= 2.0


@pytest.mark.parametrize("fz", [570.0, 635.0, 701.0])
@pytest.mark.parametrize("pressure", [300.0, 400.0, 500.0])
def test_controller_keeps_the_bicycle_up(pressure, fz):
    """What does hold today: with the LQR no run falls and the yaw rate recovers within the 6 s."""
    r = run(Scenario(pressure_kpa=pressure, fz_n=fz))
    assert not r.summary["fell"]
    assert _recovery(r) is not None and _recovery(r) < 5.5


@pytest.mark.parametrize("pressure", [300.0, 400.0, 500.0])
def test_half_gains_recover_more_slowly(pressure):
    full = run(Scenario(pressure_kpa=pressure, fz_n=635.0))
    half = run(Scenario(pressure_kpa=pressure, fz_n=635.0, gain_scale=0.5))
    assert not half.summary["fell"]
    assert _recovery(half) is None or _recovery(half) > _recovery(full)


@pytest.mark.parametrize("pressure", [300.0, 400.0, 500.0])
def test_controller_off_falls_within_2_s(pressure):
    r = run(Scenario(pressure_kpa=pressure, fz_n=635.0, controller="off"))
    assert r.summary["fell"]
    assert 0.0 < r.summary["fall_time_s"] <= 2.0
    roll = r.trajectory["roll"].to_numpy()
    assert abs(roll[-1]) == pytest.approx(math.radians(45.0))   # the event ends the run exactly


# ------------------------------------------------ robustness: kicks and speeds

def _completes(result):
    df = result.trajectory
    assert np.all(np.isfinite(df.to_numpy()))
    s = result.summary
    json.dumps(s, allow_nan=False)
    if s["fell"]:
        assert df["time"].iloc[-1] == pytest.approx(s["fall_time_s"])
    else:
        assert df["time"].iloc[-1] == pytest.approx(result.scenario.duration)


@pytest.mark.parametrize("accel", [30.0, 35.0, 40.0])
def test_measured_plate_accelerations_complete(accel):
    """Where the thesis' model failed: a fall is a valid outcome, a crash or NaN is not."""
    _completes(run(Scenario(kick_accel=accel)))


@pytest.mark.parametrize("accel", [5.0, 200.0])
def test_kick_accelerations_5_to_200_complete(accel):
    _completes(run(Scenario(kick_accel=accel)))


@pytest.mark.parametrize("speed", [1.5, 8.0])
def test_speeds_complete(speed):
    _completes(run(Scenario(speed=speed)))


@pytest.mark.parametrize("accel", [5.0, 10.0, 20.0, 30.0, 32.5, 35.0, 37.5, 40.0, 60.0, 100.0, 150.0, 200.0])
@pytest.mark.parametrize("speed", [1.5, 3.0, 5.0, 8.0])
def test_grid_of_kicks_and_speeds_completes(accel, speed):
    _completes(run(Scenario(kick_accel=accel, speed=speed)))


# ------------------------------------------------------------------ numerics

_CONVERGENCE_KEYS = ("max_abs_yaw_rate", "max_abs_roll_rate", "max_abs_steer_rate", "max_abs_roll",
                     "max_abs_steer", "max_abs_slip_rear", "max_abs_fy_rear", "max_abs_fy_front")


def _headline(result):
    s = result.summary
    out = {k: s["peaks"][k] for k in _CONVERGENCE_KEYS}
    out["first_peak"] = s["metrics"]["peak_values"][0]
    out["first_peak_time"] = s["metrics"]["peak_times"][0]
    for key in ("fall_time_s",):
        if s[key] is not None:
            out[key] = s[key]
    if s["recovery"]["time_s"] is not None:
        out["recovery_5pct"] = s["recovery"]["time_s"]
    return out


@pytest.mark.parametrize("changes", [{}, {"controller": "off"}, {"kick_accel": 35.0}],
                         ids=["base", "controller-off", "35-m/s2"])
def test_metrics_converge_between_rtol_1e8_and_1e12(changes):
    """Issue 6: within 0.5 %; measured: within 1e-6 relative (the 5 % recovery time to the 1 ms sample)."""
    coarse = _headline(run(Scenario(rtol=1e-8, **changes)))
    fine = _headline(run(Scenario(rtol=1e-12, **changes)))
    assert coarse.keys() == fine.keys()
    for key in fine:
        assert coarse[key] == pytest.approx(fine[key], rel=5e-3), key
        assert coarse[key] == pytest.approx(fine[key], rel=1e-5, abs=1e-3), key


def test_piecewise_vs_single_integration_from_a_steady_turn(base):
    """Default run (tyre offsets give a steady turn): one LSODA piece across the kick agrees to ~rtol."""
    single = run(Scenario(pressure_kpa=400.0, fz_n=635.0, piecewise=False))
    d = np.max(np.abs(single.trajectory["yaw_rate"].to_numpy() - base.trajectory["yaw_rate"].to_numpy()))
    assert d < 1e-7   # measured 8e-10 rad/s at rtol 1e-10
    assert single.summary["metrics"]["peak_values"][0] == pytest.approx(
        base.summary["metrics"]["peak_values"][0], rel=1e-8)


@pytest.mark.parametrize("rtol", [1e-8, 1e-12])
def test_single_integration_steps_over_the_kick_from_exact_equilibrium(rtol):
    """Why the run restarts at the kick: from an exactly steady state (symmetric tyres) LSODA's step
    grows during a 2 s settle beyond the 0.15 s kick and one piece misses the kick altogether."""
    sc = Scenario(symmetric_tyres=True, settle=2.0, duration=1.0, rtol=rtol)
    piecewise = run(sc)
    single = run(simulation.with_changes(sc, piecewise=False))
    assert piecewise.summary["peaks"]["max_abs_yaw_rate"] > 1.5       # measured 1.78 rad/s
    assert single.summary["peaks"]["max_abs_yaw_rate"] < 1e-9          # measured ~1e-18 rad/s
    assert single.trajectory["plate_y"].iloc[-1] == pytest.approx(0.15)  # the plate did move
