"""The steady motion before the kick: found robustly, an equilibrium, or a one-line physical reason."""
import math

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.model import slip
from whipple_kick.simulate import control, steady
from whipple_kick.simulate.simulation import Scenario


def _params(pressure=400.0, fz=635.0, design_speed=3.0, symmetric=False):
    sc = Scenario(pressure_kpa=pressure, fz_n=fz)
    moore, design, _ = wk.assembly.build_bicycle(sc.bicycle_spec)
    rear, front, _ = wk.assembly.build_tyres(sc.tyre_spec)
    gains = control.gains_dict(control.lqr_gains(design, design_speed)[0])
    return slip.model_parameters(moore, rear, front, slip.ModelOptions(symmetric_tyres=symmetric), gains=gains)


def _heading_rates(found, speed):
    """Accelerations of the steady motion in the heading frame (all zero at an equilibrium)."""
    x = found.steady.x
    rhs = slip.CompiledRHS(found.steady.params)
    dx = rhs(0.0, x)
    u1, u2, u3 = x[slip.X["u1"]], x[slip.X["u2"]], x[slip.X["u3"]]
    rates = [dx[slip.X["u1"]] + u3 * u2, dx[slip.X["u2"]] - u3 * u1] + [dx[slip.X[n]] for n in
                                                                       ("u3", "u4", "u7", "u9", "u10")]
    return np.array(rates), x[slip.X["u1"]] - speed


def test_the_common_case_is_the_direct_solve_unchanged():
    params = _params()
    found = steady.find_steady_state(params, 3.0)
    direct = steady.steady_state(params, 3.0)
    assert found.route == "direct" and found.solves == 1
    np.testing.assert_array_equal(found.steady.x, direct.x)


@pytest.mark.parametrize("pressure, fz, speed, route", [(300.0, 570.0, 2.2, "offset continuation"),
                                                        (500.0, 635.0, 2.5, "steady turn")])
def test_a_rider_fixed_at_3_m_s_has_a_steady_motion_in_the_band_that_failed(pressure, fz, speed, route):
    """The band (2.2-2.7 m/s) with the rider designed at 3 m/s, where the direct solve from upright running
    gives up (scipy: "not making good progress"): where a start exists (these two cases, measured), it is
    found by the route named, it is an equilibrium of the model (every heading-frame acceleration zero to the
    solver's tolerance) and a start (near-upright, inside the measured slip)."""
    params = _params(pressure=pressure, fz=fz)
    found = steady.find_steady_state(params, speed)
    assert found.route.startswith(route)
    assert found.steady.residual < 1e-8
    rates, speed_error = _heading_rates(found, speed)
    assert np.max(np.abs(rates)) < 1e-7 and speed_error == 0.0
    assert steady.start_problem(found.steady, hold=found.route.startswith("steady turn")) is None


@pytest.mark.parametrize("pressure, fz, speed", [(300.0, 570.0, 2.6), (400.0, 635.0, 2.6), (400.0, 635.0, 2.7)])
def test_where_the_band_has_no_start_the_search_says_so(pressure, fz, speed):
    """Issue 40: in these cases (which the search before issue 40 answered with a steady turn at 85 deg of steer,
    or at 21 deg of lean) no near-upright steady motion exists: the branch from symmetric tyres ends before the
    offsets reach their measured size, and every turn the search reaches is no start. Refused in one line."""
    with pytest.raises(steady.NoSteadyMotion) as info:
        steady.find_steady_state(_params(pressure=pressure, fz=fz), speed)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"no near-upright steady motion at {speed:g} m/s")
    assert "are no start" in message or "is no start" in message


def test_the_steady_turn_closest_to_upright_among_the_starts_is_chosen():
    """Where the direct solve and the offset continuation fail and the turn search finds a start (3 m/s rider
    at 2.5 m/s, 635 N, 500 kPa), the route says how many starts were found, and of the turns that are starts
    (near-upright, inside the measured slip, held by the rider) the one closest to upright is taken."""
    params = _params(pressure=500.0, fz=635.0)
    found = steady.find_steady_state(params, 2.5)
    assert found.route.startswith("steady turn started at") and "found)" in found.route
    assert steady.start_problem(found.steady, hold=True) is None
    chosen = math.hypot(found.steady.unknowns["q4"], found.steady.unknowns["q7"])
    others = [t for t in _turns(params, 2.5) if steady.start_problem(t, hold=True) is None]
    assert others and all(chosen <= math.hypot(t.unknowns["q4"], t.unknowns["q7"]) + 1e-9 for t in others)


def _turns(params, speed):
    """Every steady turn the turn search's starts reach at ``speed`` (duplicates included)."""
    found = []
    for lean in steady.TURN_LEANS_DEG:
        try:
            found.append(steady.steady_state(params, speed, guess=steady.turn_guess(params, speed,
                                                                                   math.radians(lean))))
        except FloatingPointError:
            pass
    return found


def test_a_far_turn_is_no_start_and_says_why():
    """Issue 40: the turn search also reaches turns far from upright running (the 3 m/s rider at 2.6 m/s,
    400 kPa, 635 N: +-21 deg of lean at +-40 deg of steer, and +7.2 deg of lean at 84.9 deg of steer with
    the front tyre sliding at -78 deg and the rear wheel driving at -85 N m), every one of them unstable
    under the rider (slowest poles +0.8 to +11 1/s). None is a start: each is refused with its reason."""
    params = _params()
    turns = _turns(params, 2.6)
    steers = [abs(math.degrees(t.unknowns["q7"])) for t in turns]
    assert max(steers) > 80.0 and len(turns) >= 5        # the issue's 85 deg turn is among them
    for turn in turns:
        problem = steady.start_problem(turn, hold=True)
        assert problem is not None and "\n" not in problem
        lean, steer = (abs(math.degrees(turn.unknowns[n])) for n in ("q4", "q7"))
        if max(lean, steer) > steady.NEAR_UPRIGHT_DEG:
            assert "not near-upright" in problem
        else:
            assert "unstable" in problem or "slip" in problem
    far = max(turns, key=lambda t: abs(t.unknowns["q7"]))
    assert abs(math.degrees(far.angles["slip_f"])) > 70.0     # the front tyre slides sideways in that "turn"


def test_start_problem_checks_each_bound_on_its_own():
    """The bounds one at a time on a start that passes them all (the default's direct solve, lean +1.6 deg):
    a lean or a steer beyond NEAR_UPRIGHT_DEG, a slip beyond START_SLIP_DEG, an unstable closed loop."""
    params = _params()
    good = steady.steady_state(params, 3.0)
    assert steady.start_problem(good, hold=True) is None

    def changed(unknowns=None, angles=None, params_=None):
        return steady.SteadyState(good.x, params_ or good.params, good.residual, {**good.unknowns, **(unknowns or {})},
                                  {**good.angles, **(angles or {})})
    limit = math.radians(steady.NEAR_UPRIGHT_DEG)
    assert "not near-upright" in steady.start_problem(changed({"q4": 1.01 * limit}))
    assert "not near-upright" in steady.start_problem(changed({"q7": -1.01 * limit}))
    assert steady.start_problem(changed({"q7": 0.99 * limit})) is None
    slip_limit = math.radians(steady.START_SLIP_DEG)
    assert "front tyre's slip" in steady.start_problem(changed(angles={"slip_f": 1.01 * slip_limit}))
    assert "rear tyre's slip" in steady.start_problem(changed(angles={"slip_r": -1.01 * slip_limit}))
    # The rider's gains reversed in roll: the same motion, no longer held (only asked for with hold=True).
    reversed_roll = good.params.replace(kq4=-good.params["kq4"], ku4=-good.params["ku4"])
    assert steady.start_problem(changed(params_=reversed_roll)) is None
    assert "unstable" in steady.start_problem(changed(params_=reversed_roll), hold=True)


def test_the_issue_case_has_no_start_and_says_where_the_branch_ends():
    """Issue 40: at 2.6 m/s the 3 m/s rider has no near-upright steady motion; before, the 84.9 deg steer turn
    was taken as the start. Now one line: how far the continuation from symmetric tyres got (42 % of the
    offsets, measured), why the turns found are no start, and what to try."""
    with pytest.raises(steady.NoSteadyMotion) as info:
        steady.find_steady_state(_params(), 2.6, advice="choose another speed")
    message = str(info.value)
    assert "\n" not in message and message.startswith("no near-upright steady motion at 2.6 m/s")
    fraction = float(message.split("steady lean grows to ")[1].split(" deg at ")[1].split("%", maxsplit=1)[0])
    assert 30.0 < fraction < 60.0
    assert "steady turns found from 1-30 deg of lean are no start" in message
    assert message.endswith("; choose another speed")


def test_offset_scaling_spans_symmetric_to_measured_tyres():
    params = _params()
    assert steady.offset_scaled(params, 1.0) == params
    assert steady.offset_scaled(params, 0.0) == _params(symmetric=True)
    half = steady.offset_scaled(params, 0.5)
    changed = [k for k in params if half[k] != params[k]]
    assert changed and all(half[k] == 0.5 * params[k] for k in changed)
    assert all(k[0] in "ac" and int(k.split("_")[1]) in (slip.FY_OFFSET_INDICES if k[0] == "a"
                                                         else slip.MZ_OFFSET_INDICES) for k in changed)


def test_turn_guess_is_a_balanced_turn():
    params = _params()
    guess = steady.turn_guess(params, 3.0, math.radians(5.0))
    # Lateral acceleration v u3 balances gravity's pull at the lean: v u3 = g tan(lean).
    assert 3.0 * guess["u3"] == pytest.approx(params["g"] * math.tan(math.radians(5.0)), rel=1e-12)
    assert guess["q7"] > 0.0 and guess["q4"] == math.radians(5.0)


def test_lateral_poles_leave_out_only_the_forward_speed():
    params = _params(symmetric=True)
    st = steady.steady_state(params, 3.0)
    poles = steady.lateral_poles(st.params, st.x)
    A, B, K = slip.linear_state_space(st.params, st.x)
    full = np.linalg.eigvals(A - B @ K)
    assert poles.size == len(slip.LINEAR_STATES) - 1
    assert np.all(np.diff(poles.real) <= 0.0)
    # With symmetric tyres upright, the forward speed decouples exactly (its eigenvalue is the one
    # left out, about 0): the other poles are the full model's.
    dropped = [p for p in full if np.min(np.abs(poles - p)) > 1e-6 * max(1.0, abs(p))]
    assert len(dropped) == 1 and abs(dropped[0]) < 1e-6


def test_no_steady_motion_says_why_in_one_line(monkeypatch):
    """Only the direct solve and the offset continuation (turn starts and speed continuation
    switched off): at the issue's case the branch from symmetric tyres folds; the message gives the
    lean and the real closed-loop pole at the fold (near zero: that is what a fold is) and what to do."""
    monkeypatch.setattr(steady, "TURN_LEANS_DEG", ())
    monkeypatch.setattr(steady, "NEIGHBOUR_STEPS", ())
    with pytest.raises(steady.NoSteadyMotion) as info:
        steady.find_steady_state(_params(), 2.6, advice="choose another speed")
    message = str(info.value)
    assert isinstance(info.value, wk.errors.InputError) and "\n" not in message
    assert message.startswith("no near-upright steady motion at 2.6 m/s: the closed loop cannot hold the steady turn")
    assert message.endswith("; choose another speed")
    pole = float(message.split("a real closed-loop pole has reached ")[1].split(" 1/s", maxsplit=1)[0])
    assert abs(pole) < 0.1    # measured -0.059 1/s at 42 % of the offsets, +3.2 deg of lean
    assert "with symmetric tyres the rider's closed loop is stable at 2.6 m/s" in message


def test_the_search_is_bounded(monkeypatch):
    monkeypatch.setattr(steady, "MAX_SOLVES", 3)
    with pytest.raises(steady.NoSteadyMotion, match="the search stopped after 3 solves"):
        steady.find_steady_state(_params(pressure=300.0, fz=570.0), 2.6)
