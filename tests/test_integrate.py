"""Piecewise LSODA: the fall event against an exact answer and solve_ivp, and the budget against hangs."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from whipple_kick import integrate, slip

N = len(slip.STATE_NAMES)
ROLL, ROLL_RATE = slip.X["q4"], slip.X["u4"]


def capsize(t, x):
    """roll'' = roll (an inverted pendulum with unit rate); every other state decays."""
    dx = -x.copy()
    dx[ROLL], dx[ROLL_RATE] = x[ROLL_RATE], x[ROLL]
    return dx


def _start(roll=0.01):
    x = np.full(N, 1e-3)
    x[ROLL], x[ROLL_RATE] = roll, 0.0
    return x


def test_fall_event_against_the_exact_fall_time_and_solve_ivp():
    """roll = 0.01 cosh t reaches 45 deg at acosh(78.54...) = 5.0567 s. The careful path steps the
    same LSODA as solve_ivp and finds the same event time bit for bit."""
    fall_angle = math.radians(45.0)
    traj = integrate.integrate(capsize, _start(), 10.0, rtol=1e-10, output_rate=100.0, fall_angle=fall_angle)
    assert traj.fell and not traj.failed
    assert traj.fall_time == pytest.approx(math.acosh(fall_angle / 0.01), abs=1e-7)
    assert traj.t[-1] == traj.fall_time and abs(traj.x[-1, ROLL]) == pytest.approx(fall_angle, abs=1e-12)

    def fall(t, x):
        return fall_angle - abs(x[ROLL])
    fall.terminal, fall.direction = True, -1
    # The chunk the fall is in (5.0-5.5 s), from the trajectory's state at its start.
    start = int(np.flatnonzero(np.isclose(traj.t, 5.0))[0])
    times = traj.t[start:-1]
    times = np.r_[times, 5.5]
    ref = solve_ivp(capsize, (5.0, 5.5), traj.x[start], method="LSODA", t_eval=times, events=fall,
                    rtol=1e-10, atol=integrate.default_atol(1e-10))
    assert ref.t_events[0][0] == traj.fall_time
    # Every sample after the chunk's start (which solve_ivp gives from its interpolant, to round-off).
    np.testing.assert_array_equal(ref.y.T[1:], traj.x[start + 1:-1])
    np.testing.assert_allclose(ref.y.T[0], traj.x[start], rtol=1e-15, atol=0)


def chatter(t, x):
    """x' = -sign(x) + 0.5: sliding on x = 0, where no step size can follow the switching."""
    dx = np.zeros_like(x)
    dx[ROLL] = -np.sign(x[ROLL]) + 0.5
    return dx


def test_a_stalling_integration_ends_as_a_failure_with_its_samples():
    budget = integrate.Budget(allowance=5000, per_second=5000.0, stall_window=2000, stall_progress=1e-3)
    x0 = np.zeros(N)
    x0[ROLL] = 0.01
    traj = integrate.integrate(chatter, x0, 2.0, output_rate=1000.0, rtol=1e-10, budget=budget)
    assert traj.failed and not traj.fell and traj.message.startswith("integration stalled at t = ")
    # x reaches the switching line at t = 0.01 / 0.5 = 0.02 s, where the steps collapse.
    stall = float(traj.message.split("t = ")[1].split(" s")[0])
    assert stall == pytest.approx(0.02, abs=2e-3)
    assert traj.t[-1] <= stall and traj.t.size == int(round(traj.t[-1] * 1000)) + 1
    assert np.all(np.isfinite(traj.x)) and traj.end_state is not None
    assert traj.nfev <= budget.limit(stall) + 100


def test_a_run_slower_than_the_budget_rate_fails_and_a_normal_run_does_not():
    """An oscillation of 2000 rad/s needs tens of evaluations per millisecond: far more than a budget
    of 100 per simulated second allows, and far less than the default budget."""
    def fast(t, x):
        dx = np.zeros_like(x)
        dx[ROLL], dx[ROLL_RATE] = x[ROLL_RATE], -4e6 * x[ROLL]
        return dx
    tight = integrate.Budget(allowance=200, per_second=100.0)
    traj = integrate.integrate(fast, _start(1e-3), 1.0, output_rate=100.0, budget=tight)
    assert traj.failed and "more than the budget 200 + 100/s" in traj.message
    assert traj.nfev <= tight.limit(traj.t[-1]) + 100
    ok = integrate.integrate(fast, _start(1e-3), 0.05, output_rate=100.0)
    assert not ok.failed and ok.t[-1] == pytest.approx(0.05)
