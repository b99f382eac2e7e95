"""The slip model: compiled C vs NumPy oracle, limit to the classic model, invariants, tyre physics."""

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick import benchmark, classic, integrate, slip


@pytest.fixture(scope="module")
def rider_bike():
    bike = wk.bicycles.load("balanceassist_v1")
    combined, _ = wk.riders.for_rear_load(bike, fz_n=635.0)
    return combined


@pytest.fixture(scope="module")
def gains(rider_bike):
    K, _ = wk.control.lqr_gains(rider_bike, 3.0)
    return wk.control.gains_dict(K)


@pytest.fixture(scope="module")
def t03():
    return wk.tyres.load("T03", pressure_kpa=400)


def _outputs(rhs, trajectory):
    return np.array([rhs.outputs(t, x)[1] for t, x in zip(trajectory.t, trajectory.x)])


def test_c_agrees_with_numpy_oracle(rider_bike, gains, t03):
    """100 random states, plate moving or not: C and the NumPy printing of the same expressions."""
    par = slip.model_parameters(rider_bike, t03, wk.tyres.load("T03", pressure_kpa=350), gains=gains,
                                kick=dict(t0=0.0, duration=0.15, displacement=0.15))
    ss = slip.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    p = slip.parameter_vector(ss.params)
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(100):
        x = ss.x.copy()
        for name, spread in (("q3", 0.5), ("q4", 0.3), ("q7", 0.3), ("q5", 0.01), ("u1", 1.0), ("u2", 0.5),
                             ("u3", 1.0), ("u4", 1.0), ("u7", 1.0), ("u9", 0.05), ("u10", 0.05),
                             ("fyr", 200.0), ("fyf", 200.0), ("mzr", 5.0), ("mzf", 5.0)):
            x[slip.X[name]] += rng.uniform(-spread, spread)
        x[slip.X["q9"]] = rng.uniform(0.0, 0.01)
        x[slip.X["q10"]] = rng.uniform(0.0, 0.01)
        t = rng.uniform(-0.05, 0.2)
        dx_c, out_c = rhs.outputs(t, x)
        dx_n, out_n = slip.numpy_rhs(t, x, p, with_outputs=True)
        # Same expressions, different evaluation order: agreement is limited
        # by the conditioning of the two small linear solves, ~1e-13 here.
        np.testing.assert_allclose(dx_c, dx_n, rtol=1e-10, atol=1e-10 * np.abs(dx_n).max())
        np.testing.assert_allclose(out_c, out_n, rtol=1e-10, atol=1e-10 * np.abs(out_n).max())
        worst = max(worst, np.abs(dx_c - dx_n).max() / np.abs(dx_n).max())
    assert worst < 1e-10


@pytest.mark.parametrize("speed", [3.0, 5.0, 7.0])
def test_stiff_tyres_approach_the_classic_model(speed):
    """Cornering stiffness -> inf, relaxation length -> 0, vertical stiffness -> inf: classic eigenvalues."""
    moore = benchmark.to_moore(benchmark.meijaard2007_parameters())
    ref = classic.eigenvalues(moore, [speed])[0]
    errors = []
    for kappa, sigma, kz in ((1e2, 1e-2, 1e7), (1e3, 1e-3, 1e8), (1e5, 1e-5, 1e10)):
        tyre = wk.tyres.linear_tyre(kappa, sigma, kz)
        ss = slip.steady_state(slip.model_parameters(moore, tyre, tyre), speed)
        ev = np.linalg.eigvals(slip.linearize(slip.CompiledRHS(ss.params), ss.x))
        matched = np.array([ev[np.argmin(np.abs(ev - r))] for r in ref])
        errors.append(np.max(np.abs(matched - ref) / np.abs(ref)))
    # Measured: ~1e-2, ~2e-4, ~2e-5. The last is limited by the finite
    # stiffnesses and the central differences, so 1e-4 is the bound.
    assert errors[0] > errors[1] > errors[2]
    assert errors[-1] < 1e-4


def test_linearisation_predicts_the_response_about_a_steady_turn(rider_bike, gains, t03):
    """Heading-frame Jacobian against the nonlinear model, about the offset-balancing turn.

    A small perturbation (1e-3 in roll rate and steer rate) is integrated
    with the nonlinear model and with exp(A t); the difference is second
    order in the perturbation, so it must be a small fraction of it.
    """
    from scipy.linalg import expm
    ss = slip.steady_state(slip.model_parameters(rider_bike, t03, t03, gains=gains), 3.0)
    assert abs(ss.x[slip.X["u3"]]) > 0.05          # really a turn (measured 0.095 rad/s)
    rhs = slip.CompiledRHS(ss.params)
    A = slip.linearize(rhs, ss.x)
    x0 = ss.x.copy()
    x0[slip.X["u4"]] += 1e-3
    x0[slip.X["u7"]] += 1e-3
    tr = integrate.integrate(rhs, x0, 2.0, rtol=1e-11, output_rate=100)
    z_ref = slip.heading_state(ss.x)
    dz0 = slip.heading_state(x0) - z_ref
    worst = 0.0
    for t, x in zip(tr.t[::10], tr.x[::10]):
        dz_nonlinear = slip.heading_state(x) - z_ref
        dz_linear = expm(A * t) @ dz0
        worst = max(worst, np.abs(dz_nonlinear - dz_linear)[:11].max())
    # Measured 8e-7 (second order: (1e-3)^2 times the model's curvature);
    # an error in A of 1 % would give ~1e-5 over the 2 s.
    assert worst < 5e-6


def test_steer_torque_input_matrix_matches_the_classic_model():
    """Stiff tyres: eigenvalues of A - B K equal the classic closed loop, so B is right."""
    moore = benchmark.to_moore(benchmark.meijaard2007_parameters())
    K, _ = wk.control.lqr_gains(moore, 4.0)
    tyre = wk.tyres.linear_tyre(1e4, 1e-4, 1e9)
    ss = slip.steady_state(slip.model_parameters(moore, tyre, tyre, gains=wk.control.gains_dict(K)), 4.0)
    A, B, Kfull = slip.linear_state_space(ss.params, ss.x)
    ref = np.linalg.eigvals(wk.control.closed_loop_matrix(moore, 4.0, K))
    for Amat, expected in ((A - B @ Kfull, ref), (A, classic.eigenvalues(moore, [4.0])[0])):
        ev = np.linalg.eigvals(Amat)
        matched = np.array([ev[np.argmin(np.abs(ev - r))] for r in expected])
        # Measured 9e-5 for both: the finite tyre stiffness, as in the stiff-tyre test above.
        assert np.max(np.abs(matched - expected) / np.abs(expected)) < 1e-3
    # The input is linear in T7: bumping another gain gives the same B.
    bumped = dict(ss.params, kq4=ss.params["kq4"] + 1.0)
    A_b = slip.linearize(slip.CompiledRHS(bumped), ss.x)
    j = slip.LINEAR_STATES.index("q4")
    np.testing.assert_allclose(A_b[:, j], (A - B @ Kfull)[:, j] - B[:, 0], atol=1e-6 * np.abs(B).max())


def test_energy_never_increases_with_slip_and_damping(rider_bike, t03):
    par = slip.model_parameters(rider_bike, t03, t03, symmetric=True)
    ss = slip.steady_state(par, 4.5)
    x0 = ss.x.copy()
    x0[slip.X["u4"]], x0[slip.X["u7"]], x0[slip.X["u10"]] = 0.3, 0.2, 0.05
    rhs = slip.CompiledRHS(ss.params)
    tr = integrate.integrate(rhs, x0, 5.0, rtol=1e-11, output_rate=200)
    assert not tr.fell
    out = _outputs(rhs, tr)
    energy = out[:, slip.OUT["kinetic_energy"]] + out[:, slip.OUT["potential_energy"]] + out[:, slip.OUT["spring_energy"]]
    # "Never increases" to integration tolerance: 1e-9 of the total at rtol 1e-11.
    assert np.diff(energy).max() < 1e-9 * energy[0]
    assert energy[-1] < energy[0] - 1.0   # and it really dissipates (measured ~16 J)
    assert np.abs(out[:, slip.OUT["holonomic"]]).max() < 1e-9


def test_energy_conserved_without_damping_and_slip(rider_bike, t03):
    par = slip.model_parameters(rider_bike, t03, t03, symmetric=True, lateral=False)
    par["czr"] = par["czf"] = 0.0
    ss = slip.steady_state(par, 4.5)
    x0 = ss.x.copy()
    x0[slip.X["u4"]], x0[slip.X["u7"]], x0[slip.X["u10"]] = 0.3, 0.2, 0.05
    rhs = slip.CompiledRHS(ss.params)
    tr = integrate.integrate(rhs, x0, 5.0, rtol=1e-11, output_rate=200)
    out = _outputs(rhs, tr)
    energy = out[:, slip.OUT["kinetic_energy"]] + out[:, slip.OUT["potential_energy"]] + out[:, slip.OUT["spring_energy"]]
    # Without lateral forces the bicycle slides over and may fall; the run
    # ends at the event, and until then energy is constant (measured 1e-12).
    assert np.ptp(energy) / energy[0] < 1e-9
    assert np.abs(out[:, slip.OUT["holonomic"]]).max() < 1e-9


@pytest.mark.parametrize("symmetric", [True, False])
def test_steady_start_does_not_drift(rider_bike, gains, t03, symmetric):
    par = slip.model_parameters(rider_bike, t03, t03, gains=gains, symmetric=symmetric)
    ss = slip.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    tr = integrate.integrate(rhs, ss.x, 10.0, rtol=1e-10, output_rate=100)
    assert not tr.fell
    roll, steer = tr.state("q4"), tr.state("q7")
    speed = np.hypot(tr.state("u1"), tr.state("u2"))
    if symmetric:
        assert np.abs(roll).max() < 1e-9 and np.abs(steer).max() < 1e-9
    else:
        # The offsets are balanced by a slow steady turn (measured lean 1.6 deg).
        assert abs(ss.unknowns["q4"]) > 1e-3
        assert np.abs(roll - ss.unknowns["q4"]).max() < 1e-6
        assert np.abs(steer - ss.unknowns["q7"]).max() < 1e-6
    assert np.abs(speed / speed[0] - 1).max() < 1e-3
    out = _outputs(rhs, tr)
    assert np.abs(out[:, slip.OUT["holonomic"]]).max() < 1e-9


def test_tyre_physics_in_the_model(rider_bike, t03):
    par = slip.model_parameters(rider_bike, t03, t03, symmetric=True)
    ss = slip.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    rng = np.random.default_rng(7)
    for _ in range(50):
        x = ss.x.copy()
        x[slip.X["u2"]] = rng.uniform(-0.5, 0.5)   # sideways sliding
        x[slip.X["q4"]] = 0.0
        _, out = rhs.outputs(0.0, x)
        slip_r = out[slip.OUT["slip_r"]]
        # The steady force opposes the sliding (no energy from sliding).
        assert out[slip.OUT["fy_ss_r"]] * slip_r < 0
        if abs(np.rad2deg(slip_r)) < 1.0:
            # Small slip: the moment turns the wheel toward its velocity.
            assert out[slip.OUT["mz_ss_r"]] * slip_r > 0
    # Leaning right with no sliding: pushed to the right (toward the lean).
    x = ss.x.copy()
    x[slip.X["q4"]] = 0.1
    x = slip.solve_pitch(rhs, x)
    _, out = rhs.outputs(0.0, x)
    assert abs(out[slip.OUT["slip_r"]]) < 1e-12
    assert out[slip.OUT["camber_r"]] == pytest.approx(0.1, abs=1e-12)
    assert out[slip.OUT["fy_ss_r"]] > 0
    # Unloaded tyre (wheel lifted): zero force and moment, finite derivatives.
    x = ss.x.copy()
    x[slip.X["q9"]] = -0.01
    x[slip.X["u2"]] = 0.3
    dx, out = rhs.outputs(0.0, x)
    assert out[slip.OUT["fz_r"]] == 0.0
    assert out[slip.OUT["fy_ss_r"]] == 0.0 and out[slip.OUT["mz_ss_r"]] == 0.0
    assert np.all(np.isfinite(dx))


def test_mirror_symmetric_kicks(rider_bike, gains, t03):
    responses = []
    for sign in (1.0, -1.0):
        par = slip.model_parameters(rider_bike, t03, t03, gains=gains, symmetric=True,
                                    kick=dict(t0=0.0, duration=0.15, displacement=0.15 * sign))
        ss = slip.steady_state(par, 3.0)
        rhs = slip.CompiledRHS(ss.params)
        tr = integrate.integrate(rhs, ss.x, 3.0, t_start=-0.2, breakpoints=(0.0, 0.15), rtol=1e-11, output_rate=200)
        responses.append(tr)
    a, b = responses
    for name in ("u3", "u4", "u7", "q4", "q7", "fyr"):
        scale = np.abs(a.state(name)).max()
        assert scale > 0
        # Mirror images to integration accuracy (rtol 1e-11 over ~1e4 steps).
        np.testing.assert_allclose(a.state(name), -b.state(name), rtol=0, atol=1e-9 * max(scale, 1.0))
    np.testing.assert_allclose(a.state("u1"), b.state("u1"), rtol=0, atol=1e-9)


def test_bad_parameters_are_reported(rider_bike, t03):
    par = slip.model_parameters(rider_bike, t03, t03)
    del par["kzr"]
    with pytest.raises(wk.errors.InputError, match="kzr"):
        slip.CompiledRHS(par)
    with pytest.raises(wk.errors.InputError, match="unknown controller gains"):
        slip.model_parameters(rider_bike, t03, t03, gains={"kq5": 1.0})
