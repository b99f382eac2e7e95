"""LQR steer controller: published gains, stability, sign, linear vs nonlinear.

The controller is ``T7 = -K x`` with ``x = [q4, q7, u4, u7]`` and
``K = [kq4, kq7, ku4, ku7]`` (python-control's ``lqr`` convention). These
tests pin the method against the gains the authors published, prove the sign
of the law on the linear and the nonlinear model, and check that the linear
closed loop the gains were designed on is what the nonlinear model does for
small motions.
"""
import numpy as np
import pytest
from scipy.linalg import expm, solve_continuous_are

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.model import classic
from whipple_kick.simulate import control

DESIGN_SPEED = 3.0  # m/s, the thesis' design speed
THESIS_LOADS = (570, 635, 701)  # N, Table 8.3 rear-tyre loads

# LQR gains published with the authors' kick-plate model (mechmotum/bicycle-kickplate-model
# on GitHub, October 2024): lqr(A, B, I, 1) for `browser_with_rider`, [kq4, kq7, ku4, ku7].
PUBLISHED_GAINS = {
    6.0: [-2.23409174, 4.90641021, -0.59393849, 0.43409879],
    3.0: [-23.18340061, 17.08640989, -7.99985294, 1.86343941],
}

# Indices of the state-feedback variables in the nonlinear model's full
# coordinate and speed vectors (q1..q8, u1..u8): q4 roll, q7 steer.
IQ4, IQ7, IU4, IU7 = 3, 6, 3, 6


def _feedback(K, sign=-1.0):
    """``steer_torque(t, q, u)`` for classic.simulate: ``T7 = sign * K x``."""
    K = np.asarray(K, dtype=float)

    def torque(t, q, u):
        return sign * (K @ np.array([q[IQ4], q[IQ7], u[IU4], u[IU7]]))

    return torque


def _thesis_K(load):
    gains = control.thesis_gains(load)
    return np.array([gains[name] for name in control.GAIN_ORDER])


@pytest.fixture(scope="module")
def bike():
    return wk.bicycles.load("balanceassist_v1")


@pytest.fixture(scope="module")
def combined(bike):
    """Bicycle + Yeadon rider for each thesis rear load."""
    return {fz: wk.riders.for_rear_load(bike, fz)[0] for fz in THESIS_LOADS}


def test_feedback_indices_match_model_ordering():
    # The literal indices used in the feedback law must be the model's q4, q7, u4, u7.
    assert (classic.Q["q4"], classic.Q["q7"]) == (IQ4, IQ7)
    assert (classic.U["u4"], classic.U["u7"]) == (IU4, IU7)


# --- (1) method check against the published gains --------------------------

@pytest.mark.parametrize("speed", sorted(PUBLISHED_GAINS))
def test_published_gains_browser_with_rider(speed):
    # Issue 5 asks for 0.5 % per gain. The published gains came from a slightly
    # different build of the authors' model, so a faithful linearisation lands
    # within a few tenths of a per cent; we measure at most 0.26 % (ku4 at 3 m/s).
    K, poles = control.lqr_gains(wk.bicycles.load("browser_with_rider"), speed)
    np.testing.assert_allclose(K, PUBLISHED_GAINS[speed], rtol=5e-3)
    assert np.all(poles.real < 0)


def test_lqr_solves_the_riccati_equation(combined):
    # Independent of python-control: K = R^-1 B^T P with P from scipy's CARE.
    # Both solve the same equation to round-off; 1e-8 relative leaves room for
    # the conditioning of the Riccati solve only.
    moore = combined[635]
    A, B = classic.linear_state_space(moore, DESIGN_SPEED)
    b = B[:, [1]]
    P = solve_continuous_are(A, b, np.eye(4), np.eye(1))
    K_care = (b.T @ P).ravel()
    K, poles = control.lqr_gains(moore, DESIGN_SPEED)
    np.testing.assert_allclose(K, K_care, rtol=1e-8)
    np.testing.assert_allclose(np.sort_complex(poles),
                               np.sort_complex(np.linalg.eigvals(A - b @ K[None, :])), rtol=1e-8)


# --- (2) closed loop stable, open loop unstable -----------------------------

@pytest.mark.parametrize("load", THESIS_LOADS)
def test_closed_loop_stable_open_loop_unstable(combined, load):
    moore = combined[load]
    A, _ = classic.linear_state_space(moore, DESIGN_SPEED)
    # Open loop at 3 m/s is below the weave speed: the weave pair is unstable
    # (Re ~ +1.1 to +1.2 1/s), so stabilising it is a real test of the gains.
    assert np.max(np.linalg.eigvals(A).real) > 0.5
    K, poles = control.lqr_gains(moore, DESIGN_SPEED)
    closed = np.linalg.eigvals(control.closed_loop_matrix(moore, DESIGN_SPEED, K))
    # Slowest closed-loop mode is about -1.6 1/s; require a clear margin,
    # not just Re < 0 up to round-off.
    assert np.max(closed.real) < -1.0
    np.testing.assert_allclose(np.sort_complex(closed), np.sort_complex(poles), rtol=1e-10)


# --- (3) sign of the law ----------------------------------------------------

@pytest.mark.parametrize("which", ["ours", "table_8_4"])
def test_minus_sign_stabilises_plus_sign_does_not(combined, which):
    # Thesis eq. 8.4 prints T7 = +K x; with the gains' signs (kq4 < 0,
    # kq7 > 0) only T7 = -K x stabilises, for our LQR gains and for Table 8.4's.
    moore = combined[635]
    K = control.lqr_gains(moore, DESIGN_SPEED)[0] if which == "ours" else _thesis_K(635)
    assert K[0] < 0 < K[1]
    minus = np.linalg.eigvals(control.closed_loop_matrix(moore, DESIGN_SPEED, K))
    plus = np.linalg.eigvals(control.closed_loop_matrix(moore, DESIGN_SPEED, -K))
    assert np.max(minus.real) < -0.5
    # With +K a real mode goes to about +8 (ours) or +11 (Table 8.4) 1/s.
    assert np.max(plus.real) > 5.0


def test_sign_on_the_nonlinear_model(combined):
    # The same sign proof through the nonlinear model's own steer-torque
    # input, with Table 8.4's gains, from 1e-4 rad of roll. With -K x the
    # slowest closed-loop mode is ~ -0.6 1/s (eigenvalues above), so after 3 s
    # roll and steer are back below half the initial roll (measured 4.5e-5
    # rad). With +K x the mode at ~ +11 1/s grows the steer angle ~100-fold in
    # 0.5 s (measured 1.0e-2 rad), still small enough to stay upright.
    moore = combined[635]
    K = _thesis_K(635)
    roll0 = 1e-4
    q0, u0 = classic.upright_state(moore, DESIGN_SPEED, roll=roll0)
    minus = classic.simulate(moore, q0, u0, 3.0, steer_torque=_feedback(K, -1.0))
    plus = classic.simulate(moore, q0, u0, 0.5, steer_torque=_feedback(K, +1.0))
    assert minus.status == 0 and plus.status == 0
    assert np.hypot(minus.y[IQ4, -1], minus.y[IQ7, -1]) < 0.5 * roll0
    assert np.hypot(plus.y[IQ4, -1], plus.y[IQ7, -1]) > 20 * roll0


# --- (4) linear vs nonlinear closed loop ------------------------------------

@pytest.mark.parametrize("load", THESIS_LOADS)
def test_linear_and_nonlinear_closed_loop_agree(combined, load):
    # From 0.01 rad of roll at 3 m/s, the first second of roll and steer of
    # the nonlinear classic model under T7 = -K x equals exp((A - B K) t) x0
    # to 1e-4 rad (issue 5). The difference is the model's quadratic terms,
    # O(roll0^2) = 1e-4 at most; we measure ~5e-6 rad roll and ~1.1e-5 rad
    # steer, against a peak steer of ~0.018 rad. The integrator's error
    # (rtol 1e-10) is far below either.
    moore = combined[load]
    K, _ = control.lqr_gains(moore, DESIGN_SPEED)
    roll0 = 0.01
    t = np.linspace(0.0, 1.0, 201)
    q0, u0 = classic.upright_state(moore, DESIGN_SPEED, roll=roll0)
    res = classic.simulate(moore, q0, u0, 1.0, steer_torque=_feedback(K), t_eval=t)
    assert res.status == 0, res.message
    Acl = control.closed_loop_matrix(moore, DESIGN_SPEED, K)
    x0 = np.array([roll0, 0.0, 0.0, 0.0])
    linear = np.array([expm(Acl * ti) @ x0 for ti in t])
    np.testing.assert_allclose(res.y[IQ4], linear[:, 0], rtol=0, atol=1e-4)
    np.testing.assert_allclose(res.y[IQ7], linear[:, 1], rtol=0, atol=1e-4)
    # The response is not trivially small: the steer moves by > 1e-2 rad, so
    # a wrong sign or index would show far above the tolerance.
    assert np.max(np.abs(linear[:, 1])) > 1e-2
    # Rows 8 and 10 of y are u4 and u7 (y = q1..q8, u4, u6, u7): the rates
    # agree too (same quadratic-term argument, rates are ~10x the angles).
    np.testing.assert_allclose(res.y[8], linear[:, 2], rtol=0, atol=1e-3)
    np.testing.assert_allclose(res.y[10], linear[:, 3], rtol=0, atol=1e-3)


# --- (5) presets, scaling, configurability, errors --------------------------

@pytest.mark.parametrize("load", THESIS_LOADS)
def test_thesis_gains_stabilise_the_bicycle_of_their_load(combined, load):
    """Table 8.4's gains for a load balance the bicycle with that load's rider at the 3 m/s design speed.

    Open loop the weave is unstable there (Re about +1.1 to +1.2 1/s); with T7 = -K x every
    closed-loop mode decays (slowest about -0.58, -0.60, -0.61 1/s for 570, 635, 701 N).
    """
    moore = combined[load]
    A, _ = classic.linear_state_space(moore, DESIGN_SPEED)
    assert np.max(np.linalg.eigvals(A).real) > 1.0
    closed = np.linalg.eigvals(control.closed_loop_matrix(moore, DESIGN_SPEED, _thesis_K(load)))
    assert np.max(closed.real) < -0.5
    # A float load selects the same row; the result is a copy the caller may change.
    g = control.thesis_gains(float(load))
    g["kq4"] = 0.0
    assert control.thesis_gains(load)["kq4"] == control.THESIS_GAINS[load]["kq4"] < 0


@pytest.mark.parametrize("load", [600, 635.5, 634.6, 0, -635])
def test_thesis_gains_unknown_load_is_input_error(load):
    with pytest.raises(InputError):
        control.thesis_gains(load)


def test_gains_dict_and_scale():
    K = np.array([-12.0, 9.0, -4.0, 1.2])
    assert list(control.gains_dict(K)) == ["kq4", "kq7", "ku4", "ku7"]
    assert control.gains_dict(K) == {"kq4": -12.0, "kq7": 9.0, "ku4": -4.0, "ku7": 1.2}
    # The thesis' 50 % run halves every gain; scale 0 is "control off".
    assert control.gains_dict(K, 0.5) == {"kq4": -6.0, "kq7": 4.5, "ku4": -2.0, "ku7": 0.6}
    assert all(v == 0.0 for v in control.gains_dict(K, 0.0).values())
    # Round trip with the Table 8.4 preset.
    assert control.gains_dict(_thesis_K(635)) == control.THESIS_GAINS[635]


def test_gains_dict_refuses_a_vector_of_another_length():
    """Five gains (a heading design) or three are not silently cut to the four names."""
    for K in ([-12.0, 9.0, -4.0, 1.2, 0.5], [-12.0, 9.0, -4.0]):
        with pytest.raises(InputError, match=f"exactly 4 gains \\(kq4, kq7, ku4, ku7\\), got {len(K)}"):
            control.gains_dict(K)


@pytest.mark.parametrize("weights", [{}, {"R": 10.0}, {"Q": np.diag([10.0, 1.0, 2.0, 0.5])}])
@pytest.mark.parametrize("load", THESIS_LOADS)
def test_scipy_riccati_design_equals_python_control(combined, load, weights):
    """The run-time design (SciPy's Riccati solver) against python-control's lqr, the oracle.

    Measured: identical to the last bit on this machine (python-control solves
    the same equation with SciPy when slycot is absent); asserted to 1e-8 of
    the largest gain, far below anything a run could see.
    """
    import control as ct

    moore = combined[load]
    K, poles = control.lqr_gains(moore, DESIGN_SPEED, **weights)
    A, B = classic.linear_state_space(moore, DESIGN_SPEED)
    Q = weights.get("Q", np.eye(4))
    K_ct, _, poles_ct = ct.lqr(A, B[:, [1]], Q, np.atleast_2d(weights.get("R", 1.0)))
    np.testing.assert_allclose(K, np.ravel(K_ct), rtol=0, atol=1e-8 * np.abs(K_ct).max())
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(poles_ct), rtol=0,
                               atol=1e-8 * np.abs(poles_ct).max())
    K5, _ = control.heading_lqr_gains(moore, DESIGN_SPEED)
    A5, b5 = control.heading_state_space(moore, DESIGN_SPEED)
    K5_ct, _, _ = ct.lqr(A5, b5, np.eye(5), np.eye(1))
    np.testing.assert_allclose(K5, np.ravel(K5_ct), rtol=0, atol=1e-8 * np.abs(K5_ct).max())


def test_weights_are_configurable(combined):
    moore = combined[635]
    K1, _ = control.lqr_gains(moore, DESIGN_SPEED)
    # Costlier torque (larger R) -> every gain smaller in magnitude.
    K10, poles10 = control.lqr_gains(moore, DESIGN_SPEED, R=10.0)
    assert np.all(np.abs(K10) < np.abs(K1))
    assert np.all(poles10.real < 0)
    # Weighting roll more -> a larger roll gain.
    Kq, _ = control.lqr_gains(moore, DESIGN_SPEED, Q=np.diag([10.0, 1.0, 1.0, 1.0]))
    assert abs(Kq[0]) > abs(K1[0])
    # Q = I passed explicitly is the default.
    np.testing.assert_allclose(control.lqr_gains(moore, DESIGN_SPEED, Q=np.eye(4))[0], K1, rtol=1e-12)


def test_lqr_input_errors(combined):
    moore = combined[635]
    with pytest.raises(InputError):
        control.lqr_gains(moore, DESIGN_SPEED, Q=np.eye(3))
    for speed in (0.0, -3.0):
        with pytest.raises(InputError):
            control.lqr_gains(moore, speed)
    with pytest.raises(InputError, match=r"R = 0.0 \(weight\) is outside the allowed range \(0, inf\]"):
        control.lqr_gains(moore, DESIGN_SPEED, R=0.0)


# --- (6) the heading-holding rider (yaw angle as a fifth state) --------------

def test_yaw_rate_map_is_the_benchmark_kinematics():
    # Meijaard et al. (2007) eq. (A.27) linearised: yaw rate = (v delta +
    # c delta') cos(lambda) / w, with no roll terms. Independent of our
    # constraint solution; both are exact, so 1e-12 relative is round-off.
    bench = wk.benchmark.meijaard2007_parameters()
    moore = wk.benchmark.to_moore(bench)
    scale = np.cos(bench["lam"]) / bench["w"]
    for speed in (1.0, 3.0, 6.0):
        expected = [0.0, speed * scale, 0.0, bench["c"] * scale]
        np.testing.assert_allclose(classic.yaw_rate_map(moore, speed), expected, rtol=1e-12, atol=1e-14)


def test_heading_lqr_solves_its_riccati_equation_and_is_stable(combined):
    moore = combined[635]
    A, b = control.heading_state_space(moore, DESIGN_SPEED)
    P = solve_continuous_are(A, b, np.eye(5), np.eye(1))
    K, poles = control.heading_lqr_gains(moore, DESIGN_SPEED)
    np.testing.assert_allclose(K, (b.T @ P).ravel(), rtol=1e-8)
    assert np.max(poles.real) < -0.5
    # Yaw is cyclic (column q3 of A is zero), so the (q3, q3) entry of the
    # Riccati equation reads (P b)_0^2 = Q_00 R: |kq3| = sqrt(Q_00 / R) exactly.
    for q00, r in ((1.0, 1.0), (4.0, 1.0), (1.0, 9.0)):
        Q = np.eye(5)
        Q[0, 0] = q00
        np.testing.assert_allclose(abs(control.heading_lqr_gains(moore, DESIGN_SPEED, Q=Q, R=r)[0][0]),
                                   np.sqrt(q00 / r), rtol=1e-8)


def test_heading_lqr_without_yaw_weight_is_the_balance_lqr(combined):
    # As the yaw weight goes to 0 the design forgets the heading: kq3 -> 0
    # (= 1e-5 by the identity above) and the other gains tend to lqr_gains'
    # (measured 2e-6 relative at a weight of 1e-10).
    moore = combined[635]
    Q = np.eye(5)
    Q[0, 0] = 1e-10
    K5, _ = control.heading_lqr_gains(moore, DESIGN_SPEED, Q=Q)
    K4, _ = control.lqr_gains(moore, DESIGN_SPEED)
    np.testing.assert_allclose(K5[1:], K4, rtol=1e-4)


def test_heading_rider_steers_back_to_the_heading_on_the_nonlinear_model(combined):
    # From 0.01 rad of roll the balance-only rider ends up in a new heading;
    # with the yaw-angle gain the nonlinear classic model returns to the old
    # one. Slowest pole -0.85 1/s: after 10 s the heading is back within
    # 1 % of its largest excursion (measured below 1e-3 of it), while the
    # balance-only rider keeps a heading change of half its excursion or more.
    moore = combined[635]
    K5, _ = control.heading_lqr_gains(moore, DESIGN_SPEED)
    K4, _ = control.lqr_gains(moore, DESIGN_SPEED)

    def heading_law(t, q, u):
        return -(K5 @ np.array([q[2], q[IQ4], q[IQ7], u[IU4], u[IU7]]))

    q0, u0 = classic.upright_state(moore, DESIGN_SPEED, roll=0.01)
    t = np.linspace(0.0, 10.0, 501)
    held = classic.simulate(moore, q0, u0, 10.0, steer_torque=heading_law, t_eval=t)
    free = classic.simulate(moore, q0, u0, 10.0, steer_torque=_feedback(K4), t_eval=t)
    assert held.status == 0 and free.status == 0
    held_yaw, free_yaw = held.y[2], free.y[2]
    assert np.max(np.abs(held_yaw)) > 1e-3
    assert abs(held_yaw[-1]) < 0.01 * np.max(np.abs(held_yaw))
    assert abs(free_yaw[-1]) > 0.5 * np.max(np.abs(free_yaw))


def test_heading_lqr_input_errors(combined):
    with pytest.raises(InputError, match="Q must be 5x5"):
        control.heading_lqr_gains(combined[635], DESIGN_SPEED, Q=np.eye(4))
    with pytest.raises(InputError, match="design speed"):
        control.heading_lqr_gains(combined[635], 0.0)


def test_closed_loop_poles_by_name_agree_with_the_matrix_forms(combined):
    """The rider's poles at any speed: the four-gain law is closed_loop_matrix; a yaw-rate gain folds
    into it through the rolling kinematics; a yaw-angle gain adds the heading as a fifth state whose
    pole, as that gain goes to 0, goes to 0 (the heading is then free) leaving the four-state poles."""
    moore = combined[635]
    gains = control.gains_dict(control.lqr_gains(moore, 3.0)[0])
    K = [gains[name] for name in control.GAIN_ORDER]
    for speed in (2.0, 3.0, 6.0):
        poles = control.closed_loop_poles(moore, speed, gains)
        expected = np.linalg.eigvals(control.closed_loop_matrix(moore, speed, K))
        np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(expected), rtol=1e-12)
        assert np.all(np.diff(poles.real) <= 0.0)
    yaw = classic.yaw_rate_map(moore, 3.0)
    with_ku3 = control.closed_loop_poles(moore, 3.0, {**gains, "ku3": 0.7})
    folded = np.linalg.eigvals(control.closed_loop_matrix(moore, 3.0, np.array(K) + 0.7 * yaw))
    np.testing.assert_allclose(np.sort_complex(with_ku3), np.sort_complex(folded), rtol=1e-12)
    tiny = control.closed_loop_poles(moore, 3.0, {**gains, "kq3": -1e-9})
    assert tiny.size == 5 and np.min(np.abs(tiny)) < 1e-8
    np.testing.assert_allclose(np.sort_complex(tiny[np.abs(tiny) > 1e-8]),
                               np.sort_complex(control.closed_loop_poles(moore, 3.0, gains)), rtol=1e-6)
    # The heading-holding LQR's own design poles are what closed_loop_poles gives for its gains.
    K5, design_poles = control.heading_lqr_gains(moore, 3.0)
    heading = control.closed_loop_poles(moore, 3.0, dict(zip(control.HEADING_GAIN_ORDER, K5, strict=True)))
    np.testing.assert_allclose(np.sort_complex(heading), np.sort_complex(design_poles), rtol=1e-9)
