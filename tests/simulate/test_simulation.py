"""Kick-plate runs end to end: the thesis behaviour, robustness across kicks and speeds, numerics, tables, energy."""
import json
import math

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.simulate.simulation import Scenario, run


def _recovery(result):
    return result.summary["recovery"]["time_s"]


# ------------------------------------------------------------------ outputs


def test_smooth_profile_peak_acceleration_matches_request():
    r = run(Scenario(kick_accel=20.0, kick_profile="smooth", duration=0.5))
    assert np.max(np.abs(r.trajectory["plate_acceleration"])) == pytest.approx(20.0, rel=2e-3)
    assert r.trajectory["plate_y"].iloc[-1] == pytest.approx(0.15)


def test_kick_to_the_left_mirrors_the_first_yaw_peak(base):
    left = run(Scenario(kick_direction="left", symmetric_tyres=True, duration=0.5))
    right = run(Scenario(kick_direction="right", symmetric_tyres=True, duration=0.5))
    np.testing.assert_allclose(left.trajectory["yaw_rate"], -right.trajectory["yaw_rate"], atol=1e-7)
    # A plate moving right pushes the rear wheel right: the bicycle first yaws left (u3 < 0).
    assert base.summary["metrics"]["yaw_rate_peaks_from_steady_rad_s"][0] < 0.0


def test_symmetric_tyres_run_upright():
    r = run(Scenario(symmetric_tyres=True, duration=0.2))
    st = r.summary["steady_state"]
    assert abs(st["roll_rad"]) < 1e-12 and abs(st["yaw_rate_rad_s"]) < 1e-12


def test_thesis_preset_runs_its_table_8_4_rider():
    """The thesis preset recovers at 400 kPa with the Table 8.4 rider for 635 N actually applied:
    the steer torque at every sample is -K x with those gains (to round-off)."""
    r = run(Scenario.thesis(pressure_kpa=400.0, duration=2.0))
    s = r.summary
    assert s["bicycle"]["bicycle"] == "balanceassist_635N" and not s["fell"]
    gains = wk.control.thesis_gains(635)
    x = r.trajectory[["roll", "steer", "roll_rate", "steer_rate"]].to_numpy()
    K = np.array([gains[name] for name in wk.control.GAIN_ORDER])
    torque = r.trajectory["steer_torque"].to_numpy()
    assert np.max(np.abs(torque)) > 1.0     # the kick makes the rider steer
    np.testing.assert_allclose(torque, -x @ K, rtol=0, atol=1e-12)


def test_front_and_rear_pressures_may_differ():
    """Each wheel gets the tyre of its own pressure: the assembled rear tyre is the 500 kPa one, the
    front the 300 kPa one, and the run differs from both runs at one pressure."""
    mixed = Scenario(pressure_front_kpa=300.0, pressure_rear_kpa=500.0, duration=0.3)
    rear, front, _ = wk.assembly.build_tyres(mixed.tyre_spec)
    force = lambda tyre: tyre.lateral_force(slip=0.02, camber=0.05, fz=600.0)
    assert force(rear) == force(wk.tyres.load("T03", 500.0)) != force(wk.tyres.load("T03", 300.0)) == force(front)
    r = run(mixed)
    for same in (300.0, 500.0):
        other = run(Scenario(pressure_kpa=same, duration=0.3))
        assert not np.allclose(r.trajectory["fy_front"], other.trajectory["fy_front"]) \
            or not np.allclose(r.trajectory["fy_rear"], other.trajectory["fy_rear"]), same


def test_tyre_without_moment_data_runs_with_zero_moment():
    r = run(Scenario(tyre="T01", duration=0.3))
    assert "M_z = 0" in r.summary["tyres"]["notes"][0]
    assert np.all(r.trajectory["mz_rear"] == 0.0)


def test_custom_gains_reproduce_the_named_controller(base):
    gains = base.summary["controller"]["gains"]
    again = run(Scenario(pressure_kpa=400.0, fz_n=635.0), gains=gains)
    assert again.summary["controller"]["type"] == "custom gains"
    assert again.summary["controller"]["gain_scale"] is None
    cols = ["yaw_rate", "roll", "steer", "fy_rear", "steer_torque"]
    assert np.array_equal(again.trajectory[cols].to_numpy(), base.trajectory[cols].to_numpy())


def test_heading_rider_gains_are_applied_and_reported():
    # The heading-holding LQR (control.heading_lqr_gains) on symmetric tyres:
    # the yaw gain is used (the summary names it, and the heading comes back
    # back to the old one: measured 4e-4 rad after 8 s, against 1.18 rad
    # kept by the balance-only rider; the bound 2 % leaves room for tuning).
    scenario = Scenario(pressure_kpa=400.0, fz_n=635.0, symmetric_tyres=True, duration=8.0)
    design = wk.assembly.build_bicycle(scenario.bicycle_spec)[1]
    K, _ = wk.control.heading_lqr_gains(design, 3.0)
    held = run(scenario, gains=dict(zip(wk.control.HEADING_GAIN_ORDER, K, strict=True)))
    free = run(scenario)
    ctl = held.summary["controller"]
    assert ctl["law"] == "T7 = -(kq4 q4 + kq7 q7 + ku4 u4 + ku7 u7 + kq3 q3)"
    assert ctl["gains"]["kq3"] == pytest.approx(K[0], rel=0, abs=0) and ctl["gain_units"]["kq3"] == "N m/rad"
    assert "kq3" not in free.summary["controller"]["gains"]
    assert not held.summary["fell"] and not free.summary["fell"]

    def heading_change(result):
        return abs(result.trajectory["yaw"].iloc[-1])   # the steady motion starts at yaw 0 and is straight

    assert heading_change(free) > 0.2     # measured 0.36 rad (1.18 rad with the thesis' force lag)
    assert heading_change(held) < 0.02 * heading_change(free)


def test_custom_tyres_are_used_and_named():
    rigid = wk.tyres.linear_tyre(100.0, 0.01, 1e7)
    # A small kick (the linear regime): a linear tyre has no friction limit, and after the full kick's
    # instant plate stop its contact-patch force follows the load spikes at once (tens of kN).
    r = run(Scenario(duration=0.5, symmetric_tyres=True, kick_displacement=0.005), tyres=(rigid, rigid))
    assert "LinearTyre(100/rad" in r.summary["tyres"]["name"]
    assert "custom tyre objects" in r.summary["tyres"]["notes"][0]
    assert r.summary["tyres"]["pressure_rear_kpa"] is None   # the scenario's pressure was not used
    # No camber force and 100/rad cornering: the rear force is -100 Fz slip (relaxed, 1e-2 m).
    df = r.trajectory
    late = df["time"].to_numpy() > 0.3
    np.testing.assert_allclose(df["fy_steady_rear"][late], -100.0 * df["fz_rear"][late] * df["slip_rear"][late],
                               rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("fields", [dict(pressure_kpa=300.0), dict(coefficient_set="chapter8"),
                                    dict(friction="plate"), dict(tyre="T01", pressure_kpa=400.0, friction="thesis")])
def test_custom_tyres_refuse_the_tyre_fields_they_replace(fields):
    """Issue 40 item 12: tyre objects with a non-default pressure, coefficient set or friction ran with only a
    note in the summary (lost in a sweep). Refused, in one line naming each field, before any long work."""
    rigid = wk.tyres.linear_tyre(100.0, 0.01, 1e7)
    with pytest.raises(wk.InputError) as info:
        run(Scenario(duration=0.5, symmetric_tyres=True, **fields), tyres=(rigid, rigid))
    text = str(info.value)
    assert "\n" not in text and "would be ignored" in text, text
    for name, value in fields.items():
        if value != wk.scenario.DEFAULTS[name]:
            assert f"{name} = {value!r}" in text, text


# ------------------------------------------------------- thesis behaviour: the nine cases

# The kick-plate acceptance behaviour, in the nine thesis cases (300/400/500 kPa x 570/635/701 N,
# 3 m/s, our LQR rider), measured on the default tyre transient (contact_patch) and, where a line
# holds only there, on the thesis' force lag: the rider recovers (no fall; yaw, roll and steer rates
# all settle within the 6 s run), a rider with 50 % gains settles roll and steer later or falls,
# and without control the bicycle is lost. Measured values per case: docs/validation.md ("The nine
# thesis cases"; scripts/recovery_study.py).
NINE_CASES = [(p, fz) for fz in (570.0, 635.0, 701.0) for p in (300.0, 400.0, 500.0)]
_NINE_RUNS = {}


def _nine_run(pressure, fz, **changes):
    """(summary, time the fork first turned past 90 deg after the kick or None) of a nine-case run,
    also when the integration failed (cached: the full-gain runs serve several tests)."""
    key = (pressure, fz, tuple(sorted(changes.items())))
    if key not in _NINE_RUNS:
        result = run(Scenario(pressure_kpa=pressure, fz_n=fz, **changes))   # a failed run too
        df = result.trajectory
        t = df["time"].to_numpy()
        over = np.flatnonzero((t >= 0.0) & (np.abs(df["steer"].to_numpy()) > np.pi / 2))
        _NINE_RUNS[key] = (result.summary, float(t[over[0]]) if over.size else None)
    return _NINE_RUNS[key]


def _nine(pressure, fz, **changes):
    """The summary of a nine-case run."""
    return _nine_run(pressure, fz, **changes)[0]


@pytest.mark.parametrize("pressure, fz", NINE_CASES)
def test_rider_recovers_in_the_nine_thesis_cases(pressure, fz):
    s = _nine(pressure, fz)
    assert s["outcome"] == "completed" and not s["fell"]
    assert s["linear_stability"]["stable"]
    for name, signal in s["recovery"]["signals"].items():
        assert signal["time_s"] is not None, (name, signal["reason"])
    assert 0.0 < s["recovery"]["time_s"] < s["scenario"]["duration"]


@pytest.mark.parametrize("pressure, fz", NINE_CASES)
def test_half_gains_settle_roll_and_steer_later_or_fall(pressure, fz):
    full, half = _nine(pressure, fz), _nine(pressure, fz, gain_scale=0.5)
    if half["fell"]:
        return
    for name in ("roll_rate", "steer_rate"):
        t_half, t_full = half["recovery"]["signals"][name]["time_s"], full["recovery"]["signals"][name]["time_s"]
        assert t_half is None or t_half > t_full, name


@pytest.mark.parametrize("pressure, fz", NINE_CASES)
def test_controller_off_falls_within_2_s_of_the_kick_with_the_thesis_force_lag(pressure, fz):
    """On the thesis' force lag too the run is lost 1.20-1.35 s after the kick (the fork turns over first)."""
    s = _nine(pressure, fz, controller="off", tyre_transient="force_lag")
    assert s["fell"] and s["outcome"] == "fell"
    assert 0.0 < s["fall_time_s"] <= 2.0
    assert s["recovery"]["time_s"] is None and s["metrics"]["last_peak_time_s"] is None


@pytest.mark.parametrize("pressure, fz", NINE_CASES)
def test_controller_off_loses_the_bicycle_within_2_s_of_the_kick(pressure, fz):
    """Issue acceptance on the default tyre: without control the bicycle is lost within 2 s of the
    kick. The fork turns over first (|steer| reaches the 90 deg steer limit, measured 1.54-1.97 s,
    roll then 14-30 deg below the 45 deg fall angle): past it the front wheel rolls backwards, which
    the tyre model does not describe, so the run ends there as lost (``fall_reason`` "steer")."""
    s, fork_over = _nine_run(pressure, fz, controller="off")
    assert s["outcome"] == "fell" and s["fall_reason"] == "steer"
    assert 0.0 < s["fall_time_s"] <= 2.0
    assert fork_over is None or fork_over >= s["fall_time_s"] - 1e-3   # the run ends at the limit itself
    assert s["recovery"]["time_s"] is None and s["metrics"]["last_peak_time_s"] is None


@pytest.mark.parametrize("transient, share", [("contact_patch", 0.2), ("force_lag", 0.4)])
def test_the_thesis_last_peak_time_is_not_a_recovery_time(transient, share):
    """Thesis Section 8.3's "recovery time" (the last yaw-rate peak above 8 % of the largest) is
    kept as metrics.last_peak_time_s. In the default run it is 1.12 s, when the yaw rate is still 0.27
    of its first peak away from steady (bound 0.2, four times the 5 % band; the recovery time is
    2.71 s); on the thesis' force lag 1.10 s and 0.50 of it (bound 0.4; recovery 4.17 s)."""
    changes = {} if transient == "contact_patch" else {"tyre_transient": transient}
    s = _nine(400.0, 635.0, **changes)
    last_peak = s["metrics"]["last_peak_time_s"]
    assert last_peak < s["recovery"]["time_s"]
    assert abs(s["metrics"]["yaw_rate_peaks_from_steady_rad_s"][-1]) > share * s["recovery"]["signals"]["yaw_rate"]["first_peak_from_steady_rad_s"]
    assert "recovery_time" not in s["metrics"]


def test_table_8_4_rider_in_the_no_slip_limit():
    """The thesis' rider on near-rigid tyres: roll and steer rates settle in about 1 s, yaw rate does not.

    Thesis Section 8.4: its controlled model returns to steady state "in about
    1 s, if we look at the steer angular rate and roll rate signals". With
    near-rigid tyres (the no-slip limit) the slip model reproduces that, and
    the yaw rate's slow tail is the classic closed loop's real pole at about
    -0.6 1/s (docs/riders.md), which the linearised slip model must find too.
    """
    rigid = wk.tyres.linear_tyre(100.0, 0.01, 1e7)
    # The thesis' force lag: a linear tyre has no friction limit, and at the instant plate stop the
    # contact-patch form's force follows the load spike at once (-27 kN at 1.9 kN load, the rear wheel
    # hops and the bicycle falls), which says nothing about the rider in the no-slip limit.
    scenario = Scenario(pressure_kpa=400.0, fz_n=635.0, controller="thesis", symmetric_tyres=True,
                        tyre_transient="force_lag")
    r = run(scenario, tyres=(rigid, rigid))
    signals = r.summary["recovery"]["signals"]
    # Measured 0.83 s and 0.64 s; the yaw rate 3.69 s.
    assert signals["roll_rate"]["time_s"] < 1.2 and signals["steer_rate"]["time_s"] < 1.2
    assert signals["yaw_rate"]["time_s"] > 3.0
    moore, design, _ = wk.assembly.build_bicycle(scenario.bicycle_spec)
    gains = wk.control.thesis_gains(635.0)
    K = [gains[k] for k in wk.control.GAIN_ORDER]
    classic_poles = np.linalg.eigvals(wk.control.closed_loop_matrix(moore, 3.0, K))
    slow_classic = classic_poles[np.argmax(classic_poles.real)]
    steady = wk.steady.steady_state(wk.slip.model_parameters(moore, rigid, rigid,
                                                             wk.slip.ModelOptions(symmetric_tyres=True),
                                                             gains=gains), 3.0)
    A, B, Kfull = wk.slip.linear_state_space(steady.params, steady.x)
    poles = np.linalg.eigvals(A - B @ Kfull)
    poles = poles[np.abs(poles) > 1e-2]          # leave out the forward-speed mode (0)
    slow = poles[np.argmax(poles.real)]
    assert slow_classic.imag == 0.0 and abs(slow.imag) < 1e-9
    # Measured -0.603 (classic) and -0.61 (tyre stiffness 100/rad, not infinite).
    assert slow.real == pytest.approx(slow_classic.real, rel=0.05)


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


@pytest.mark.parametrize("pressure", [300.0, 400.0])
def test_controller_off_falls_with_the_contact_patch_tyre(pressure):
    r = run(Scenario(pressure_kpa=pressure, fz_n=635.0, controller="off"))
    assert r.summary["fell"]
    assert 1.5 < r.summary["fall_time_s"] <= 2.5     # measured 2.25 s (300 kPa), 2.17 s (400 kPa)


@pytest.mark.parametrize("accel", [30.0, 35.0, 40.0])
def test_measured_plate_accelerations_complete(accel):
    """Where the thesis' model failed: a fall is a valid outcome, a crash or NaN is not."""
    _completes(run(Scenario(kick_accel=accel)))


@pytest.mark.parametrize("accel", [5.0, 200.0])
def test_kick_accelerations_5_to_200_complete(accel):
    _completes(run(Scenario(kick_accel=accel)))


@pytest.mark.parametrize("accel", [5.0, 10.0, 20.0, 30.0, 32.5, 35.0, 37.5, 40.0, 60.0, 100.0, 150.0, 200.0])
@pytest.mark.parametrize("speed, design_speed", [(1.5, None), (3.0, None), (5.0, 3.0), (8.0, 3.0)])
def test_grid_of_kicks_and_speeds_completes(accel, speed, design_speed):
    """Every kick size at each speed completes or falls. At 5 and 8 m/s the rider designed at the run's speed
    has no near-upright start at 400 kPa, 635 N (issue 40; before, it started from a steady turn at 12.5 deg
    of lean): the rider designed at 3 m/s rides there."""
    _completes(run(Scenario(kick_accel=accel, speed=speed, design_speed=design_speed)))


# ------------------------------------------------ the speed envelope (issue: rider at the run's speed)

ENVELOPE_SPEEDS = (1.5, 2.0, 2.2, 2.4, 2.5, 2.6, 2.7, 3.0, 4.0, 6.0, 8.0)
ENVELOPE_PRESSURES = (300.0, 400.0, 500.0)
ENVELOPE_LOADS = (500.0, 570.0, 701.0, 800.0)
# Twelve cases of the grid for the default run, every speed of the band where a rider fixed at 3 m/s
# fails (2.2-2.7 m/s) among them, each pressure and load more than once.
ENVELOPE_SUBSET = [(2.5, 300.0, 500.0), (2.5, 400.0, 701.0), (2.5, 500.0, 800.0), (2.6, 300.0, 570.0),
                   (2.6, 400.0, 800.0), (2.6, 500.0, 500.0), (2.2, 400.0, 570.0), (2.4, 500.0, 701.0),
                   (2.7, 300.0, 800.0), (1.5, 400.0, 500.0), (2.0, 500.0, 570.0), (8.0, 500.0, 701.0)]
#: Where the rider designed at the run's speed has no near-upright start (issue 40, measured over the grid:
#: 16 of 132 cases, all at 4-8 m/s and 300-400 kPa, where the search used to take steady turns of 6-21 deg of
#: lean): the steady search refuses them in one line.
NO_START_SPEEDS = (4.0, 6.0, 8.0)


def _envelope_case(speed, pressure, fz, **changes):
    """Run one envelope case: (result or None, the one-line reason if there is no steady motion)."""
    try:
        return run(Scenario(speed=speed, pressure_kpa=pressure, fz_n=fz, **changes)), None
    except wk.steady.NoSteadyMotion as exc:
        message = str(exc)
        assert "\n" not in message and f"{speed:g} m/s" in message and "scipy" not in message.lower()
        return None, message


def _check_envelope_run(result):
    _completes(result)
    s = result.summary
    assert s["outcome"] in ("completed", "fell")
    assert s["steady_state"]["residual"] < 1e-8
    assert s["controller"]["design_speed_m_s"] == result.scenario.speed
    stability = s["linear_stability"]
    assert stability["stable"] == (stability["message"] is None)


@pytest.mark.parametrize("speed, pressure, fz", ENVELOPE_SUBSET)
def test_adaptive_rider_runs_to_completion_across_the_envelope(speed, pressure, fz):
    """The default rider (LQR designed at the run's speed): a steady motion, and a run that completes or falls."""
    result, reason = _envelope_case(speed, pressure, fz)
    assert reason is None, reason
    _check_envelope_run(result)


@pytest.mark.slow
@pytest.mark.parametrize("fz", ENVELOPE_LOADS)
@pytest.mark.parametrize("pressure", ENVELOPE_PRESSURES)
@pytest.mark.parametrize("speed", ENVELOPE_SPEEDS)
def test_full_envelope(speed, pressure, fz):
    """The whole grid (132 cases, T03): the default rider runs to completion (a fall is a valid result), or at
    4-8 m/s has no near-upright start and says so in one line; the rider fixed at 3 m/s finds its steady
    motion or says in one line why there is none, and its run completes, falls, or ends as a reported
    numerical failure with the run up to it."""
    result, reason = _envelope_case(speed, pressure, fz)
    if reason is not None:
        assert speed in NO_START_SPEEDS and pressure < 500.0, reason
        assert reason.startswith(f"no near-upright steady motion at {speed:g} m/s"), reason
    else:
        _check_envelope_run(result)
    fixed, reason = _envelope_case(speed, pressure, fz, design_speed=3.0)
    if fixed is not None and not fixed.success:
        assert fixed.summary["outcome"] == "failed" and fixed.status == -1
        return
    if fixed is not None:
        _completes(fixed)


def test_rider_designed_at_the_run_speed_by_default():
    assert Scenario().lqr_design_speed == 3.0
    assert Scenario(speed=2.0).lqr_design_speed == 2.0
    assert Scenario(speed=2.0, design_speed=3.0).lqr_design_speed == 3.0
    sc = Scenario(speed=2.5, duration=0.5)
    s = run(sc).summary
    moore, design, _ = wk.assembly.build_bicycle(sc.bicycle_spec)
    K, design_poles = wk.control.lqr_gains(design, 2.5)
    assert s["controller"]["design_speed_m_s"] == 2.5
    assert [s["controller"]["gains"][k] for k in wk.control.GAIN_ORDER] == pytest.approx(K, rel=1e-12)
    # The poles reported are those of the rider in use at the run's speed (here the design's own).
    poles = np.array([complex(*p) for p in s["linear_stability"]["poles_no_slip_model_1_s"]])
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(design_poles), rtol=1e-9)
    assert s["linear_stability"]["stable"] and s["linear_stability"]["message"] is None


def test_the_3_m_s_rider_is_unstable_below_2_48_m_s_and_says_so():
    """Issue: on the no-slip model the 3 m/s rider's closed loop has a real pole crossing zero near
    2.48 m/s (measured 2.467 m/s), +1.03 1/s at 2 m/s. A run there reports the poles at the run's speed for that rider and
    says in one line that it is linearly unstable."""
    from scipy.optimize import brentq
    moore, design, _ = wk.assembly.build_bicycle(Scenario().bicycle_spec)
    gains = wk.control.gains_dict(wk.control.lqr_gains(design, 3.0)[0])

    def slowest(v):
        return wk.control.closed_loop_poles(moore, v, gains)[0]

    crossing = brentq(lambda v: slowest(v).real, 2.0, 2.9, xtol=1e-6)
    assert crossing == pytest.approx(2.48, abs=0.02) and slowest(crossing).imag == 0.0   # measured 2.467 m/s
    s = run(Scenario(speed=2.0, design_speed=3.0, duration=0.5)).summary
    assert s["controller"]["design_speed_m_s"] == 3.0
    no_slip = complex(*s["linear_stability"]["poles_no_slip_model_1_s"][0])
    assert no_slip.real == pytest.approx(1.03, abs=0.01) and no_slip.imag == 0.0
    stability = s["linear_stability"]
    assert not stability["stable"] and stability["slowest_pole_1_s"][0] > 0.5   # slip model: +1.13 1/s
    message = stability["message"]
    assert "\n" not in message and "designed at 3 m/s" in message and "unstable at 2 m/s" in message


def test_thesis_set_up_at_the_experiments_speed_returns():
    """The thesis' set-up at 2 m/s (its experiments ran at 1.92-2 m/s) used to hang: at 500 kPa the
    front wheel unloads in the fall, the steer passes 250 deg and LSODA's step collapses. Whatever the
    machine, the run now ends as a result, a fall or a reported failure within the evaluation budget
    (measured: stalled at t = 2.717 s after 47 272 evaluations, 1 039 Jacobians of 22 among them, 0.6 s)."""
    scenario = Scenario.thesis(pressure_kpa=500.0, speed=2.0)
    budget = wk.lsoda.DEFAULT_BUDGET
    result = run(scenario)
    if not result.success:
        assert result.summary["outcome"] == "failed" and "stalled" in result.message and "\n" not in result.message
    s = result.summary
    simulated = s["end_time_s"] + scenario.settle
    assert s["numerics"]["evaluations"] <= budget.limit(simulated) + budget.stall_window
    assert not s["linear_stability"]["stable"]     # Table 8.4's 3 m/s rider at 2 m/s
    _finite_partial(result)


def _finite_partial(result):
    df = result.trajectory
    assert np.all(np.isfinite(df.to_numpy())) and df["time"].iloc[-1] == pytest.approx(result.summary["end_time_s"])
    json.dumps(result.summary, allow_nan=False)


# ------------------------------------------------------------------ numerics

_CONVERGENCE_KEYS = ("max_abs_yaw_rate_absolute_rad_s", "max_abs_roll_rate_absolute_rad_s", "max_abs_steer_rate_absolute_rad_s", "max_abs_roll_absolute_rad",
                     "max_abs_steer_absolute_rad", "max_abs_slip_rear_absolute_rad", "max_abs_fy_rear_absolute_n", "max_abs_fy_front_absolute_n")


def _headline(result):
    s = result.summary
    out = {k: s["peaks"][k] for k in _CONVERGENCE_KEYS}
    out["first_peak"] = s["metrics"]["yaw_rate_peaks_from_steady_rad_s"][0]
    out["first_peak_time"] = s["metrics"]["yaw_rate_peak_times_s"][0]
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


# ------------------------------------------------------------- tabulated kick

# The thesis' kick (0.150 m in 0.150 s) sampled at 1 kHz from the two built-in profiles.
_D, _T = 0.150, 0.150
_TABLE_TIMES = np.arange(151) / 1000.0


def _constant_y(t):
    s = np.clip(t / _T, 0.0, 1.0)
    return _D * s**2


def _smooth_y(t):
    s = np.clip(t / _T, 0.0, 1.0)
    return _D * (10 * s**3 - 15 * s**4 + 6 * s**5)


def _write_table(path, t, y, header="time,y"):
    lines = ([header] if header else []) + [f"{float(a)!r},{float(b)!r}" for a, b in zip(t, y, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    folder = tmp_path_factory.mktemp("kick_tables")
    return {"constant": _write_table(folder / "constant.csv", _TABLE_TIMES, _constant_y(_TABLE_TIMES)),
            "smooth": _write_table(folder / "smooth.csv", _TABLE_TIMES, _smooth_y(_TABLE_TIMES)),
            "folder": folder}


@pytest.fixture(scope="module")
def smooth_pair(tables):
    """The built-in minimum-jerk kick and the same kick as a 1 kHz table (thesis defaults, 6 s)."""
    return (run(Scenario(kick_profile="smooth")),
            run(Scenario(kick_profile="table", kick_table=tables["smooth"])))


def test_smooth_table_reproduces_the_builtin_smooth_profile(smooth_pair):
    """A cubic spline through the 1 kHz minimum-jerk samples is that quintic to ~1e-9 m: the runs agree
    to integration accuracy. Measured (rtol 1e-10): max |yaw rate difference| 2.0e-8 rad/s over the 6 s
    (9e-9 of the peak), first yaw-rate peak to 2e-9 relative, roll 5e-9 rad."""
    ref, tab = smooth_pair
    a, b = ref.trajectory, tab.trajectory
    np.testing.assert_array_equal(a["time"].to_numpy(), b["time"].to_numpy())
    assert np.max(np.abs(a["yaw_rate"] - b["yaw_rate"])) < 2e-7
    assert np.max(np.abs(a["roll"] - b["roll"])) < 1e-7
    assert tab.summary["metrics"]["yaw_rate_peaks_from_steady_rad_s"][0] == pytest.approx(ref.summary["metrics"]["yaw_rate_peaks_from_steady_rad_s"][0],
                                                                     rel=1e-7)
    # The summary's kick comes from the spline: 10/sqrt(3) D/T^2 = 38.49 m/s^2 (spline: 38.492).
    k = tab.summary["kick"]
    assert k["profile"] == "table" and k["table"]["rows"] == 151
    assert (k["start_s"], k["duration_s"], k["displacement_m"]) == pytest.approx((0.0, 0.15, 0.15))
    assert k["peak_acceleration_m_s2"] == pytest.approx(ref.summary["kick"]["peak_acceleration_m_s2"], rel=1e-3)
    assert k["table"]["peak_velocity_m_s"] == pytest.approx(1.875 * _D / _T, rel=1e-4)
    assert tab.summary["numerics"]["breakpoints_s"] == pytest.approx(list(_TABLE_TIMES))
    json.dumps(tab.summary, allow_nan=False)


def test_constant_table_is_close_to_the_builtin_constant_profile(base, tables):
    """The thesis profile stops the plate instantly (2 m/s -> 0); the clamped spline must stop it within
    the table's last 1 ms interval instead (its velocity overshoots to 2.5 m/s there and its peak
    |acceleration| is 6.9e3 m/s^2), so the runs differ after t = 0.149 s. Measured against the 400 kPa/
    635 N base run: first yaw-rate peak 0.40 % apart, max |yaw rate difference| 0.030 rad/s (1.7 % of
    the peak, at 0.295 s where the yaw rate swings fastest), 0.0095 rad/s after 0.5 s, roll 0.0026 rad
    after 0.5 s; recovery time 4.187 s vs 4.239 s."""
    tab = run(Scenario(pressure_kpa=400.0, fz_n=635.0, kick_profile="table", kick_table=tables["constant"]))
    a, b = base.trajectory, tab.trajectory
    np.testing.assert_array_equal(a["time"].to_numpy(), b["time"].to_numpy())
    t = a["time"].to_numpy()
    during = t < 0.14
    # Before the last intervals the spline is the constant-acceleration parabola.
    assert np.max(np.abs(a["plate_velocity"] - b["plate_velocity"])[during]) < 1e-5   # measured 1.0e-6 m/s
    assert np.max(np.abs(a["yaw_rate"] - b["yaw_rate"])[during]) < 1e-5
    peak = abs(base.summary["metrics"]["yaw_rate_peaks_from_steady_rad_s"][0])
    assert tab.summary["metrics"]["yaw_rate_peaks_from_steady_rad_s"][0] == pytest.approx(base.summary["metrics"]["yaw_rate_peaks_from_steady_rad_s"][0],
                                                                     rel=0.01)
    dyaw = np.abs(a["yaw_rate"] - b["yaw_rate"]).to_numpy()
    assert np.max(dyaw) < 0.03 * peak
    late = t >= 0.5
    assert np.max(dyaw[late]) < 0.01 * peak
    assert np.max(np.abs(a["roll"] - b["roll"]).to_numpy()[late]) < 0.005
    assert tab.summary["recovery"]["time_s"] == pytest.approx(base.summary["recovery"]["time_s"], abs=0.1)
    assert tab.summary["kick"]["peak_acceleration_m_s2"] > 1e3    # the spline's stop, reported honestly


def test_plate_passes_through_the_table_points(smooth_pair, tables):
    df = smooth_pair[1].trajectory
    t = df["time"].to_numpy()
    # Table times are on the 1 kHz output grid (to a few ulps).
    idx = np.array([int(np.argmin(np.abs(t - tk))) for tk in _TABLE_TIMES])
    assert np.max(np.abs(t[idx] - _TABLE_TIMES)) < 1e-12
    np.testing.assert_allclose(df["plate_y"].to_numpy()[idx], _smooth_y(_TABLE_TIMES), rtol=0, atol=1e-12)
    # At rest at the first row's y before the table and at the last row's y after it.
    assert np.all(df["plate_y"][t < 0.0] == 0.0) and np.all(df["plate_velocity"][t < 0.0] == 0.0)
    assert np.all(df["plate_y"][t > 0.15 + 1e-9] == _D) and np.all(df["plate_velocity"][t > 0.15 + 1e-9] == 0.0)


def test_table_with_an_offset_start_and_off_grid_times(tables):
    """A table starting at y0 != 0 before the kick start, with rows between the output samples, mirrored
    to the left: every sample on the run's grid once, plate at y0 before and through every row on the grid."""
    t = np.r_[-0.2, 0.0003 + np.arange(150) / 1000.0, 0.1505]
    y = 0.02 + np.where(t < 0.0, 0.0, _smooth_y(t))
    # Units in the header, an extra column (ignored), a comment line.
    path = tables["folder"] / "offset.csv"
    path.write_text("# plate of the test rig\nTime [s],y (m),note\n"
                    + "".join(f"{float(a)!r},{float(b)!r},x\n" for a, b in zip(t, y, strict=True)))
    path = str(path)
    # Both runs below start the steady turn at heading 0 at -0.5 s (kick_heading="settled"): with the
    # heading fixed at each kick's start instead, they would differ by the 0.2 s of turning between the
    # table's first row and the built-in kick's start (0.019 rad, a yaw-rate difference of 0.013 rad/s).
    sc = Scenario(kick_profile="table", kick_table=path, kick_direction="left", duration=1.0, output_rate=300.0,
                  kick_heading="settled")
    r = run(sc)
    df = r.trajectory
    grid = np.arange(-150, 301) / 300.0   # the output grid on the kick's clock
    np.testing.assert_array_equal(df["time"].to_numpy(), grid)
    assert np.all(df["plate_y"][df["time"] < -0.2] == -0.02)
    assert df["plate_y"].iloc[-1] == -y[-1]
    assert r.summary["kick"]["start_s"] == -0.2 and r.summary["kick"]["displacement_m"] == pytest.approx(-_D)
    # Where the 300 Hz grid and a 1 kHz grid meet (every 10 ms) the two runs of this table agree to
    # integration accuracy (measured 4e-9 rad/s): splitting the pieces at the grid changes nothing.
    fine = run(sc.with_changes(output_rate=1000.0)).trajectory
    common = fine["time"].to_numpy()[::10]
    np.testing.assert_allclose(df["time"].to_numpy()[::3], common, rtol=0, atol=1e-12)
    assert np.max(np.abs(df["yaw_rate"].to_numpy()[::3] - fine["yaw_rate"].to_numpy()[::10])) < 1e-7
    # And it is close to the built-in minimum-jerk kick; not closer because the spline through these
    # uneven rows (a 0.2 s first interval, a 0.5 ms last one) departs from the quintic by up to 0.29 mm
    # and 0.09 m/s (measured yaw-rate difference 3.9e-4 rad/s, 0.05 % of the peak).
    ref = run(Scenario(kick_profile="smooth", kick_direction="left", duration=1.0, output_rate=300.0,
                       kick_heading="settled"))
    assert np.max(np.abs(df["yaw_rate"] - ref.trajectory["yaw_rate"])) < 1e-3


def test_tabulated_run_is_continuous_across_segment_boundaries(smooth_pair):
    """No sample duplicated or missing where the pieces meet, and no jump in the states there."""
    df = smooth_pair[1].trajectory
    t = df["time"].to_numpy()
    np.testing.assert_array_equal(t, np.arange(-500, 6001) / 1000.0)   # the output grid on the kick's clock
    assert np.unique(t).size == t.size
    # The yaw rate's second difference at the 1 ms table boundaries is no larger than between them:
    # a state restarted wrongly at a boundary would show as a spike.
    kick = (t > 0.0) & (t < 0.15)
    d2 = np.abs(np.diff(df["yaw_rate"].to_numpy(), 2))[kick[1:-1]]
    ref = np.abs(np.diff(smooth_pair[0].trajectory["yaw_rate"].to_numpy(), 2))[kick[1:-1]]
    assert np.max(np.abs(d2 - ref)) < 1e-8


def test_tabulated_fall_ends_at_the_event(tables):
    """Controller off: the tabulated kick falls at the built-in smooth kick's time (measured 2e-9 s apart)."""
    tab = run(Scenario(kick_profile="table", kick_table=tables["smooth"], controller="off", duration=3.0))
    ref = run(Scenario(kick_profile="smooth", controller="off", duration=3.0))
    assert tab.summary["fell"] and ref.summary["fell"]
    assert tab.summary["fall_time_s"] == pytest.approx(ref.summary["fall_time_s"], abs=1e-6)
    _completes(tab)
    # The run ends exactly at the limit that was reached (here the fork turning over).
    column, limit = {"roll": ("roll", 45.0), "steer": ("steer", 90.0)}[tab.summary["fall_reason"]]
    assert abs(tab.trajectory[column].iloc[-1]) == pytest.approx(math.radians(limit))
    assert len(tab.trajectory) == len(ref.trajectory)


# ------------------------------------------- tyre transient, energy accounting, plate stop, heading

@pytest.fixture(scope="module")
def kicks():
    """The controller-off run followed past the fork turning over (no steer limit, so the front wheel
    lifts off) and a 40 m/s^2 kick (default tyre transient)."""
    return {"controller off": run(Scenario(pressure_kpa=400.0, fz_n=635.0, controller="off",
                                           steer_limit_deg=None)),
            "40 m/s^2": run(Scenario(pressure_kpa=400.0, fz_n=635.0, kick_accel=40.0))}


# The bound the steady curve's peak sets on |F_y| and |M_z| at each sample (the acceptance's 1.001).
CURVE_BOUND = 1.001
# The scan over slip in [-90, 90] deg, 0.05 deg apart, and its every 20th point (1 deg apart).
_SLIPS = np.radians(np.linspace(-90.0, 90.0, 3601))
_SCREEN = _SLIPS[::20]


def _curve_ratios(curve, value, camber, fz):
    """|value| / the largest |curve| over slip in [-90, 90] deg at each sample's (camber, load), where
    that ratio could exceed CURVE_BOUND; elsewhere a ratio at most CURVE_BOUND.

    The 1 deg scan is a subset of the 0.05 deg one, so its peak is no larger and its ratio no smaller:
    a sample within the bound on it is within the bound on the fine scan too. Only the samples it does
    not clear are scanned at 0.05 deg, so the bound decides exactly as the full fine scan would, at a
    fraction of its cost (the fine scan of every sample took 45 s a run).
    """
    def peaks(slips, rows):
        out = np.empty(rows.size)
        for start in range(0, rows.size, 500):
            chunk = rows[start:start + 500]
            out[start:start + 500] = np.max(np.abs(curve(slips[None, :], camber[chunk, None], fz[chunk, None])),
                                            axis=1)
        return out

    ratio = np.abs(value) / peaks(_SCREEN, np.arange(value.size))
    again = np.flatnonzero(ratio > CURVE_BOUND)
    ratio[again] = np.abs(value[again]) / peaks(_SLIPS, again)
    return ratio


def _force_bound_ratios(result):
    """max over loaded samples of |F|/peak and |M|/peak per wheel (see _curve_ratios), and the unloaded
    samples' loads.

    The curves are taken at the camber each form evaluates them at: the patch's (lagged) camber in the
    contact-patch forms; in the carcass form the force's limit at the wheel's camber and the moment at
    the lagged one.
    """
    rear, front, _ = wk.assembly.build_tyres(result.scenario.tyre_spec)
    df = result.trajectory
    carcass = result.scenario.tyre_transient == "carcass"
    out = {}
    for wheel, tyre in (("rear", rear), ("front", front)):
        fz = df[f"fz_{wheel}"].to_numpy()
        force, moment = df[f"fy_{wheel}"].to_numpy(), df[f"mz_{wheel}"].to_numpy()
        patch = df[f"camber_patch_{wheel}"].to_numpy()
        loaded = fz > 0.0
        camber_f = (df[f"camber_{wheel}"].to_numpy() if carcass else patch)[loaded]
        ratio_f = _curve_ratios(tyre.lateral_force, force[loaded], camber_f, fz[loaded])
        ratio_m = _curve_ratios(tyre.aligning_moment, moment[loaded], patch[loaded], fz[loaded])
        out[wheel] = (np.max(ratio_f), np.max(ratio_m),
                      np.abs(force[~loaded]).tolist() + np.abs(moment[~loaded]).tolist())
    return out


@pytest.mark.parametrize("case", ["default", "controller off", "40 m/s^2"])
def test_tyre_loads_never_exceed_the_steady_curve(base, kicks, case):
    """Issue acceptance: at every sample |F_y| <= 1.001 x the largest |F_y| of the steady curve over slip at
    that sample's load and patch camber, |M_z| likewise, and an unloaded tyre carries nothing. The contact-
    patch form applies the steady curve of its own patch slip, so the measured ratio is <= 1 to round-off."""
    result = base if case == "default" else kicks[case]
    # The carcass form (default): a lifted tyre's carcass force relaxes through the sliding viscosity in
    # ~1e-7 s, so at the samples it is what the integration leaves of it: measured 1.1e-8 N (atol 1e-12 m
    # of the deflection at 4e4 N/m is 4e-8 N); its moment is exactly 0. The contact-patch form: exactly 0.
    zero = 1e-7 if result.scenario.tyre_transient == "carcass" else 0.0
    for wheel, (ratio_f, ratio_m, unloaded) in _force_bound_ratios(result).items():
        assert ratio_f <= CURVE_BOUND and ratio_m <= CURVE_BOUND, (wheel, ratio_f, ratio_m)
        assert all(v <= zero for v in unloaded), wheel
    if case == "controller off":
        # The front wheel really does lift off in this fall (so the zero-load check is not empty).
        assert np.any(result.trajectory["fz_front"] == 0.0)


def test_thesis_force_lag_keeps_force_on_an_unloaded_tyre():
    """Why the default changed (issue): in the thesis' form the lagged front force survives lift-off."""
    # No steer limit: the fall is followed past the fork turning over, where the front wheel lifts off.
    r = run(Scenario(pressure_kpa=400.0, fz_n=635.0, controller="off", tyre_transient="force_lag",
                     steer_limit_deg=None))
    df = r.trajectory
    unloaded = df["fz_front"].to_numpy() == 0.0
    assert unloaded.any()
    # Measured: up to ~700 N and ~20 N m while the front tyre carries no load.
    assert np.max(np.abs(df["fy_front"].to_numpy()[unloaded])) > 100.0


def test_steady_rear_wheel_torque_is_a_brake_fed_by_the_tyres():
    """T03's zero-slip offsets feed energy into the rolling bicycle, so the torque holding 3 m/s brakes
    (positive about C.y opposes forward rolling); the steady powers cancel. Measured: T6c = +0.0289 N m,
    -0.253 W; zero-slip forces +0.404 W, aligning moments +0.055 W, sliding -0.206 W."""
    r = run(Scenario(pressure_kpa=400.0, fz_n=635.0, duration=0.2))
    st = r.summary["steady_state"]
    assert st["rear_wheel_torque_n_m"] > 0.0 and st["rear_wheel_torque_role"] == "brake"
    power = st["steady_power_w"]
    assert power["rear_wheel_torque"] < 0.0 and power["zero_slip_forces"] > 0.0
    assert abs(sum(power.values())) < 1e-9
    assert "drive_torque_n_m" not in st
    # Without the brake the tyres speed the bicycle up.
    from whipple_kick.model import slip
    from whipple_kick.simulate import lsoda, steady
    sc = r.scenario
    moore, design, _ = wk.assembly.build_bicycle(sc.bicycle_spec)
    gains, _ = wk.assembly.controller_gains(sc.gains_spec, design)
    rear, front, _ = wk.assembly.build_tyres(sc.tyre_spec)
    ss = steady.steady_state(slip.model_parameters(moore, rear, front, gains=gains), 3.0)
    tr = lsoda.integrate(slip.CompiledRHS(ss.params.replace(T6c=0.0)), ss.x, 5.0, output_rate=10)
    assert np.hypot(tr.state("u1"), tr.state("u2"))[-1] > 3.001     # measured 3.004 m/s after 5 s


@pytest.mark.parametrize("transient", ["slip_lag", "force_lag"])
def test_transient_option_is_used_and_recorded(transient):
    r = run(Scenario(duration=0.3, tyre_transient=transient))
    assert r.summary["tyres"]["transient"] == transient
    assert ("slip_patch_rear" in r.trajectory.columns) == (transient != "force_lag")
    assert np.max(np.abs(r.trajectory[wk.results.BALANCE_COLUMN])) < 1e-3
    if transient == "slip_lag":
        np.testing.assert_allclose(r.trajectory["relaxation_length_rear"], 0.175, rtol=1e-12)


# --------------------------------------------- the authors' published code (docs/validation.md)


def test_upright_start_runs_from_upright_and_judges_stability_about_the_steady_motion():
    """Default tyres and rider, started upright: the run starts at the kick from roll 0 with no brake;
    the rider's stability and the recovery are still judged about the steady motion."""
    upright = run(Scenario(start="upright", settle=0.0, duration=0.3))
    steady = run(Scenario(duration=0.3))
    df, st = upright.trajectory, upright.summary["steady_state"]
    assert df["time"].iloc[0] == 0.0 and df["roll"].iloc[0] == 0.0 and df["yaw_rate"].iloc[0] == 0.0
    assert st["rear_wheel_torque_n_m"] == 0.0 and "upright start" in st["found_by"]
    assert upright.summary["linear_stability"]["poles_slip_model_1_s"] == \
        steady.summary["linear_stability"]["poles_slip_model_1_s"]
    # Yaw-rate peaks and recovery are measured from the steady motion, not from the upright start.
    assert st["yaw_rate_baseline_rad_s"] == steady.summary["steady_state"]["yaw_rate_rad_s"] != 0.0
    assert np.max(np.abs(df[wk.results.BALANCE_COLUMN])) < 1e-3




def test_the_whipple_designed_rider_with_arms_has_no_start_and_is_refused():
    """Issue 40: with the forearms' mass on the bar, the rider designed on the Whipple model cannot hold the
    near-upright steady turn the tyres' offsets ask for (the branch from symmetric tyres ends at 86 % of the
    offsets); the search used to take a steady turn at 83.5 deg of steer and 8.9 deg of roll held by -86 N m of
    rear-wheel drive, from which the run fell before the kick. Now: one line naming the fraction reached and
    the fix (the design on the model simulated)."""
    with pytest.raises(wk.steady.NoSteadyMotion) as info:
        run(Scenario(arms="on", duration=1.0))
    message = str(info.value)
    assert "\n" not in message and message.startswith("no near-upright steady motion at 3 m/s")
    reached = float(message.split(" deg at ")[1].split("% of the offsets", maxsplit=1)[0])
    assert 80.0 < reached < 90.0                 # measured 86 %
    assert "--lqr-model simulated" in message and "--symmetric-tyres" in message


def test_a_rider_that_falls_before_the_kick_is_warned_before_the_run_and_gives_a_clean_result(monkeypatch):
    """Issue 31 item 1: a start the rider cannot hold (the 83.5 deg steer turn of the Whipple-designed rider
    with arms, +10.06 1/s) fell before the kick, and the run died with a KeyError. The search no longer offers
    such a start (issue 40; the test above), so it is forced here (every turn accepted, the turn search
    started at 30 deg of lean only), to keep the result path of a fall before the kick covered: a warning
    naming the pole and the fix comes before the integration, and the result says what is missing."""
    import warnings

    from whipple_kick.errors import UnstableRiderWarning
    from whipple_kick.simulate import integration
    monkeypatch.setattr(wk.steady, "start_problem", lambda steady, hold=False: None)
    monkeypatch.setattr(wk.steady, "_continue", lambda *args: (None, None, 0.0, 0))
    monkeypatch.setattr(wk.steady, "TURN_LEANS_DEG", (30.0,))
    integrate = integration.integrate_run
    seen_before_integration = []

    def integrate_run(*args, **kwargs):
        seen_before_integration.append(len(caught))
        return integrate(*args, **kwargs)
    monkeypatch.setattr(integration, "integrate_run", integrate_run)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run(Scenario(arms="on", duration=1.0))
    unstable = [w for w in caught if issubclass(w.category, UnstableRiderWarning)]
    assert len(unstable) == 1 and seen_before_integration == [1]
    text = str(unstable[0].message)
    assert "+10.06" in text and "--lqr-model simulated" in text and "arms on the bar" in text, text
    s = result.summary
    assert s["outcome"] == "fell" and s["fall_time_s"] < 0.0 and s["linear_stability"]["message"] == text
    assert s["recovered"] is False and s["recovery"]["time_s"] is None
    assert "before the kick start" in s["recovery"]["reason"]
    # The same metric keys as a run with a response, each unavailable with the reason.
    assert set(run(Scenario(duration=0.5)).summary["metrics"]) == set(s["metrics"])
    assert s["metrics"]["yaw_rate_peaks_from_steady_rad_s"] == [] and s["metrics"]["last_peak_time_s"] is None
    assert all("before the kick start" in reason for reason in s["metrics_unavailable"].values())
    assert "last_peak_time_s" in s["metrics_unavailable"] and "period_s" in s["metrics_unavailable"]


def test_the_simulated_design_with_arms_is_stable_and_does_not_warn():
    """The fix the warning names: --lqr-model simulated stabilises the same rider (no warning, a kick response)."""
    import warnings

    from whipple_kick.errors import UnstableRiderWarning
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnstableRiderWarning)
        result = run(Scenario(arms="on", lqr_model="simulated", duration=1.0))
    assert result.summary["linear_stability"]["stable"] and result.summary["metrics"]["n_peaks"] > 0
