"""Piecewise LSODA: the fall event against an exact answer and solve_ivp, and the budget against hangs."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from whipple_kick.library import inputs
from whipple_kick.model import slip
from whipple_kick.simulate import assembly, lsoda
from whipple_kick.simulate.scenario import Scenario

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
    traj = lsoda.integrate(capsize, _start(), 10.0, rtol=1e-10, output_rate=100.0, fall_angle=fall_angle)
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
                    rtol=1e-10, atol=lsoda.default_atol(1e-10))
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
    budget = lsoda.Budget(allowance=5000, per_second=5000.0, stall_window=2000, stall_progress=1e-3)
    x0 = np.zeros(N)
    x0[ROLL] = 0.01
    traj = lsoda.integrate(chatter, x0, 2.0, output_rate=1000.0, rtol=1e-10, budget=budget)
    assert traj.failed and not traj.fell and traj.message.startswith("integration stalled at t = ")
    # x reaches the switching line at t = 0.01 / 0.5 = 0.02 s, where the steps collapse.
    stall = float(traj.message.split("t = ")[1].split(" s")[0])
    assert stall == pytest.approx(0.02, abs=2e-3)
    assert traj.t[-1] <= stall and traj.t.size == int(round(traj.t[-1] * 1000)) + 1
    assert np.all(np.isfinite(traj.x)) and traj.end_state is not None
    assert traj.evaluations == traj.nfev <= budget.limit(stall) + 100   # no Jacobian: LSODA differences itself


def test_a_run_slower_than_the_budget_rate_fails_and_a_normal_run_does_not():
    """An oscillation of 2000 rad/s needs tens of evaluations per millisecond: far more than a budget
    of 100 per simulated second allows, and far less than the default budget."""
    def fast(t, x):
        dx = np.zeros_like(x)
        dx[ROLL], dx[ROLL_RATE] = x[ROLL_RATE], -4e6 * x[ROLL]
        return dx
    tight = lsoda.Budget(allowance=200, per_second=100.0)
    traj = lsoda.integrate(fast, _start(1e-3), 1.0, output_rate=100.0, budget=tight)
    assert traj.failed and "more than the budget 200 + 100/s" in traj.message
    assert traj.evaluations <= tight.limit(traj.t[-1]) + 100
    ok = lsoda.integrate(fast, _start(1e-3), 0.05, output_rate=100.0)
    assert not ok.failed and ok.t[-1] == pytest.approx(0.05)


# ------------------------------------------- the careful path across a jump map, and the Jacobian's cost

def _every_chunk_careful():
    """A budget whose fast path gives up after 2 steps between samples (mxstep = stall_window // 4), so
    every chunk is integrated by the careful path; it never runs out and never judges a stall."""
    return lsoda.Budget(allowance=10**9, per_second=0.0, stall_window=8, stall_progress=0.0)


@pytest.mark.parametrize("budget", [None, "careful"])
def test_a_fall_right_after_a_jump_map_is_exact(budget):
    """roll'' = roll; at t = 1 s a jump map sets the roll rate to 0.5 rad/s. From there roll =
    r1 cosh(tau) + 0.5 sinh(tau) with r1 = 0.01 cosh(1), which reaches 45 deg at a closed-form time:
    the fall is found exactly in the piece right after the jump (fast or careful path before it), the
    sample at the jump holds the mapped state and the samples before it the unmapped one."""
    budget = _every_chunk_careful() if budget == "careful" else None
    fall_angle = math.radians(45.0)

    def kick(t, x):
        x = x.copy()
        x[ROLL_RATE] = 0.5
        return x
    traj = lsoda.integrate(capsize, _start(), 4.0, breakpoints=(1.0,), rtol=1e-11, output_rate=100.0,
                               fall_angle=fall_angle, jumps={1.0: kick}, budget=budget)
    assert traj.fell and not traj.failed
    r1, w1 = 0.01 * math.cosh(1.0), 0.5
    # r1 cosh(tau) + w1 sinh(tau) = R sinh(tau + phi) with R = sqrt(w1^2 - r1^2), tanh(phi) = r1 / w1.
    tau = math.asinh(fall_angle / math.sqrt(w1**2 - r1**2)) - math.atanh(r1 / w1)
    assert traj.fall_time == pytest.approx(1.0 + tau, abs=1e-8)
    at = int(np.flatnonzero(traj.t == 1.0)[0])
    assert traj.x[at, ROLL_RATE] == 0.5                                       # mapped
    assert traj.x[at - 1, ROLL_RATE] == pytest.approx(0.01 * math.sinh(0.99), rel=1e-8)   # not mapped
    assert traj.x[at, ROLL] == pytest.approx(r1, rel=1e-8)
    if budget is not None:                  # every chunk on the careful path: it counted its work
        assert traj.evaluations == traj.nfev > 0


def test_a_stall_right_after_a_jump_map_keeps_the_samples_up_to_it():
    """The piece after the jump slides on a switching line (x' = -sign(x) + 0.5) from 2 ms after it:
    the careful path reports the stall there, with the mapped sample at the jump and every sample up
    to the stall, within the budget."""
    def after_one_second(t, x):
        return chatter(t, x) if t >= 1.0 else np.zeros_like(x)

    def move(t, x):
        x = x.copy()
        x[ROLL] = 0.001
        return x
    budget = lsoda.Budget(allowance=5000, per_second=5000.0, stall_window=2000, stall_progress=1e-3)
    traj = lsoda.integrate(after_one_second, np.zeros(N), 2.0, breakpoints=(1.0,), output_rate=1000.0,
                               rtol=1e-10, jumps={1.0: move}, budget=budget)
    assert traj.failed and not traj.fell and traj.message.startswith("integration stalled at t = ")
    stall = float(traj.message.split("t = ")[1].split(" s")[0])
    assert stall == pytest.approx(1.002, abs=2e-3)
    at = int(np.flatnonzero(traj.t == 1.0)[0])
    assert traj.x[at, ROLL] == 0.001 and traj.x[at - 1, ROLL] == 0.0
    assert traj.t[-1] <= stall and traj.t.size == int(round(traj.t[-1] * 1000)) + 1
    assert traj.evaluations <= budget.limit(stall) + 100


def test_the_budget_counts_the_evaluations_inside_the_jacobian():
    """A stiff decay (rates 1e4 /s) makes LSODA take Jacobians. With a Jacobian that says it costs
    1000 evaluations (as the compiled model's says it costs 22), the budget counts them: the same
    run fits a budget when the Jacobian is free and fails it when it is not."""
    def stiff(t, x):
        return -1e4 * (x - 1e-3)

    def make_jac(cost):
        def jac(t, x):
            return -1e4 * np.eye(N)
        jac.evaluations = cost
        return jac

    class Model:
        """An f(t, x) with a Jacobian, as slip.CompiledRHS offers one."""
        def __init__(self, cost):
            self.cost = cost

        def __call__(self, t, x):
            return stiff(t, x)

        def jacobian_function(self, scale):
            return make_jac(self.cost)
    budget = lsoda.Budget(allowance=2000, per_second=2000.0)
    free = lsoda.integrate(Model(0), _start(), 1.0, output_rate=100.0, budget=budget)
    assert not free.failed and free.njev > 0 and free.evaluations == free.nfev
    costly = lsoda.integrate(Model(1000), _start(), 1.0, output_rate=100.0, budget=budget)
    assert costly.failed and "more than the budget 2000 + 2000/s" in costly.message
    assert costly.evaluations == costly.nfev + 1000 * costly.njev


@pytest.mark.parametrize("limit", ["roll", "steer"])
def test_a_fast_chunk_ending_past_a_limit_is_a_fall(limit, monkeypatch):
    """The fast path's guard sees only the states LSODA evaluates; a chunk whose samples (its end
    above all) lie past a limit although no evaluation did must still end the run as a fall.

    Modelled by a guard that never fires: roll (or steer) = 0.01 cosh t passes 0.3 rad at
    acosh(30) = 4.0941 s, inside the chunk 4.0-4.5 s. Before, the run went on to 10 s "no fall".
    """
    monkeypatch.setattr(lsoda, "_guarded", lambda rhs, *limits: rhs)
    index = ROLL if limit == "roll" else slip.X["q7"]
    rate = ROLL_RATE if limit == "roll" else slip.X["u7"]

    def grow(t, x):
        dx = -x.copy()
        dx[index], dx[rate] = x[rate], x[index]
        return dx
    x0 = np.full(N, 1e-3)
    x0[index], x0[rate] = 0.01, 0.0
    limits = dict(fall_angle=0.3 if limit == "roll" else 1.0, steer_limit=0.3 if limit == "steer" else None)
    traj = lsoda.integrate(grow, x0, 10.0, rtol=1e-10, output_rate=100.0, **limits)
    assert traj.fell and traj.fall_reason == limit
    assert traj.fall_time == pytest.approx(math.acosh(30.0), abs=1e-7)


def test_a_chunk_starting_past_the_limit_falls_at_its_start():
    x0 = _start(roll=0.5)
    traj = lsoda.integrate(capsize, x0, 1.0, rtol=1e-10, output_rate=100.0, fall_angle=0.3)
    assert traj.fell and traj.fall_time == 0.0 and traj.t.tolist() == [0.0]


def _piece_samples_by_masks(samples, a, b, eps):
    """The per-piece sample sets as the tests on every sample give them (what lsoda._piece_samples must match)."""
    return (samples[np.abs(samples - a) <= eps], samples[(np.abs(samples - b) <= eps) & (samples > a + eps)],
            samples[(samples > a + eps) & (samples < b - eps)])


@pytest.mark.parametrize("a, b", [(-0.5, 0.0), (0.0, 0.15), (0.15, 6.0), (0.1234, 0.5678), (-1.0, 7.0), (0.3, 0.3)])
def test_piece_samples_are_those_the_tests_on_every_sample_give(a, b):
    """Found by binary search on the candidates only, the same samples in the same order, also with samples just
    inside, on and just outside ``eps`` of the piece's ends (where rounding decides) and with ``eps`` 0."""
    eps = 1e-9 * 1e-3 + 1e-14 * 6.0
    grid = np.arange(-500, 6001) / 1000.0
    near = [t + d for t in (a, b) for d in (-4 * eps, -eps, -eps / 2, 0.0, eps / 2, eps, np.nextafter(eps, 1.0),
                                           1.5 * eps, 4 * eps)]
    samples = np.unique(np.concatenate([grid, near]))
    for e in (eps, 0.0):
        for got, want in zip(lsoda._piece_samples(samples, a, b, e), _piece_samples_by_masks(samples, a, b, e),
                             strict=True):
            np.testing.assert_array_equal(got, want)
            assert got.tobytes() == want.tobytes()
    empty = np.empty(0)
    assert all(s.size == 0 for s in lsoda._piece_samples(empty, a, b, eps))


def test_the_cached_tolerances_are_default_atol_and_read_only():
    """Shared by every run of a process: the same values as a fresh default_atol, and nobody may change them."""
    atol, scale = lsoda._tolerances(1e-10, "force_lag", N, lsoda._exact_key(1e-10))
    np.testing.assert_array_equal(atol, lsoda.default_atol(1e-10, "force_lag"))
    np.testing.assert_array_equal(scale, lsoda.default_atol(1e-10, "force_lag") / 1e-10)
    assert not atol.flags.writeable and not scale.flags.writeable
    assert lsoda._tolerances(1e-10, "force_lag", N, lsoda._exact_key(1e-10))[0] is atol
    assert lsoda._exact_key(0.0) != lsoda._exact_key(-0.0) and lsoda._exact_key(1) != lsoda._exact_key(1.0)


@pytest.mark.parametrize("compiled", [True, False], ids=["c_chunk_loop", "odeint"])
def test_a_non_finite_state_in_the_result_is_an_error(compiled):
    """The rows the C chunk loop checked are not checked again; every other row is: here the state a jump map
    gives at the run's end (a sample), which no chunk produced."""
    scenario = Scenario(duration=0.3)
    model = assembly.assemble(scenario, inputs.kick_of(scenario.validate()))
    rhs = slip.CompiledRHS(model.start.params)

    def nan_map(t, x):
        return np.full_like(x, np.nan)

    def plain(t, x):   # the model without its C Jacobian: odeint's path
        return rhs(t, x)
    f = rhs if compiled else plain
    lsoda.integrate(f, model.start.x, 0.2, output_rate=100.0)   # finite without the map
    with pytest.raises(FloatingPointError, match="non-finite state in the integration result"):
        lsoda.integrate(f, model.start.x, 0.2, output_rate=100.0, jumps={0.2: nan_map})
