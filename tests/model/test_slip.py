"""The slip model at run time: limit to the classic model, invariants, tyre physics, steady motion, linearisation."""

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.model import benchmark, classic, slip
from whipple_kick.model.symbolic import slip_build
from whipple_kick.simulate import lsoda, steady


def _outputs(rhs, trajectory):
    return np.array([rhs.outputs(t, x)[1] for t, x in zip(trajectory.t, trajectory.x, strict=True)])


@pytest.mark.parametrize("speed", [3.0, 5.0, 7.0])
def test_stiff_tyres_approach_the_classic_model(speed):
    """Cornering stiffness -> inf, relaxation length -> 0, vertical stiffness -> inf: classic eigenvalues."""
    moore = benchmark.to_moore(benchmark.meijaard2007_parameters())
    ref = classic.eigenvalues(moore, [speed])[0]
    errors = []
    for kappa, sigma, kz in ((1e2, 1e-2, 1e7), (1e3, 1e-3, 1e8), (1e5, 1e-5, 1e10)):
        tyre = wk.tyres.linear_tyre(kappa, sigma, kz)
        ss = steady.steady_state(slip.model_parameters(moore, tyre, tyre), speed)
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
    ss = steady.steady_state(slip.model_parameters(rider_bike, t03, t03, gains=gains), 3.0)
    assert abs(ss.x[slip.X["u3"]]) > 0.05          # really a turn (measured 0.095 rad/s)
    rhs = slip.CompiledRHS(ss.params)
    A = slip.linearize(rhs, ss.x)
    x0 = ss.x.copy()
    x0[slip.X["u4"]] += 1e-3
    x0[slip.X["u7"]] += 1e-3
    tr = lsoda.integrate(rhs, x0, 2.0, rtol=1e-11, output_rate=100)
    z_ref = slip.heading_state(ss.x)
    dz0 = slip.heading_state(x0) - z_ref
    worst = 0.0
    for t, x in zip(tr.t[::10], tr.x[::10], strict=True):
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
    ss = steady.steady_state(slip.model_parameters(moore, tyre, tyre, gains=wk.control.gains_dict(K)), 4.0)
    A, B, Kfull = slip.linear_state_space(ss.params, ss.x)
    ref = np.linalg.eigvals(wk.control.closed_loop_matrix(moore, 4.0, K))
    for Amat, expected in ((A - B @ Kfull, ref), (A, classic.eigenvalues(moore, [4.0])[0])):
        ev = np.linalg.eigvals(Amat)
        matched = np.array([ev[np.argmin(np.abs(ev - r))] for r in expected])
        # Measured 9e-5 for both: the finite tyre stiffness, as in the stiff-tyre test above.
        assert np.max(np.abs(matched - expected) / np.abs(expected)) < 1e-3
    # The input is linear in T7: bumping another gain gives the same B.
    bumped = ss.params.replace(kq4=ss.params["kq4"] + 1.0)
    A_b = slip.linearize(slip.CompiledRHS(bumped), ss.x)
    j = slip.LINEAR_STATES.index("q4")
    np.testing.assert_allclose(A_b[:, j], (A - B @ Kfull)[:, j] - B[:, 0], atol=1e-6 * np.abs(B).max())


def test_linearisation_columns_are_the_whole_jacobians_bit_for_bit(rider_bike, gains, t03):
    """``linearize(..., columns=...)`` computes each asked column as the whole Jacobian does (tolerance 0: the
    same steps, the same evaluations), so :func:`slip.linear_state_space`'s B, from the bumped model's steer-rate
    column alone, is the B of the two whole Jacobians it came from before (tolerance 0)."""
    ss = steady.steady_state(slip.model_parameters(rider_bike, t03, t03, gains=gains), 3.0)
    rhs = slip.CompiledRHS(ss.params)
    whole = slip.linearize(rhs, ss.x)
    picked = [slip.LINEAR_STATES.index(n) for n in ("q4", "u7", "v_lat")]
    assert np.array_equal(slip.linearize(rhs, ss.x, columns=picked), whole[:, picked])
    A, B, K = slip.linear_state_space(ss.params, ss.x)
    j = slip.LINEAR_STATES.index("u7")
    bumped = slip.linearize(slip.CompiledRHS(ss.params.replace(ku7=ss.params["ku7"] + 1.0)), ss.x)
    B_before = (whole[:, j] - bumped[:, j]).reshape(-1, 1)
    assert np.array_equal(B, B_before) and np.array_equal(A, whole + B_before @ K)


def test_energy_never_increases_with_slip_and_damping(rider_bike, t03):
    par = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(symmetric_tyres=True))
    ss = steady.steady_state(par, 4.5)
    x0 = ss.x.copy()
    x0[slip.X["u4"]], x0[slip.X["u7"]], x0[slip.X["u10"]] = 0.3, 0.2, 0.05
    rhs = slip.CompiledRHS(ss.params)
    tr = lsoda.integrate(rhs, x0, 5.0, rtol=1e-11, output_rate=200)
    assert not tr.fell
    out = _outputs(rhs, tr)
    energy = out[:, slip.OUT["kinetic_energy"]] + out[:, slip.OUT["potential_energy"]] + out[:, slip.OUT["spring_energy"]]
    # "Never increases" to integration tolerance: 1e-9 of the total at rtol 1e-11.
    assert np.diff(energy).max() < 1e-9 * energy[0]
    assert energy[-1] < energy[0] - 1.0   # and it really dissipates (measured ~16 J)
    assert np.abs(out[:, slip.OUT["holonomic"]]).max() < 1e-9


def test_energy_conserved_without_damping_and_slip(rider_bike, t03):
    par = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(symmetric_tyres=True), lateral=False)
    par["czr"] = par["czf"] = 0.0
    ss = steady.steady_state(par, 4.5)
    x0 = ss.x.copy()
    x0[slip.X["u4"]], x0[slip.X["u7"]], x0[slip.X["u10"]] = 0.3, 0.2, 0.05
    rhs = slip.CompiledRHS(ss.params)
    tr = lsoda.integrate(rhs, x0, 5.0, rtol=1e-11, output_rate=200)
    out = _outputs(rhs, tr)
    energy = out[:, slip.OUT["kinetic_energy"]] + out[:, slip.OUT["potential_energy"]] + out[:, slip.OUT["spring_energy"]]
    # Without lateral forces the bicycle slides over and may fall; the run
    # ends at the event, and until then energy is constant (measured 1e-12).
    assert np.ptp(energy) / energy[0] < 1e-9
    assert np.abs(out[:, slip.OUT["holonomic"]]).max() < 1e-9


@pytest.mark.parametrize("symmetric", [True, False])
def test_steady_start_does_not_drift(rider_bike, gains, t03, symmetric):
    par = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(symmetric_tyres=symmetric), gains=gains)
    ss = steady.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    tr = lsoda.integrate(rhs, ss.x, 10.0, rtol=1e-10, output_rate=100)
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
    par = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(symmetric_tyres=True))
    ss = steady.steady_state(par, 3.0)
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


@pytest.mark.parametrize("wheel", ["r", "f"])
def test_a_lifted_wheel_closing_on_the_ground_carries_no_force(rider_bike, t03, wheel):
    """A tyre off the ground (compression q < 0) carries no normal force, however fast it closes on
    the ground: its damper acts only in contact. The case is the one seen with the controller off at
    500 kPa (a front wheel 3.8 cm up closing at 5 m/s), where kz q + cz dq/dt > 0 pushed it with kN.
    Its lateral force, moment and damper dissipation are zero too; C and the NumPy oracle agree."""
    par = slip.model_parameters(rider_bike, t03, t03)
    ss = steady.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    q, u = ("q9", "u9") if wheel == "r" else ("q10", "u10")
    x = ss.x.copy()
    x[slip.X[q]], x[slip.X[u]] = -0.038, 5.0
    x[slip.X["u2"]] = 0.3                       # sliding sideways as well
    x = slip.solve_pitch(rhs, x)
    # The spring-damper alone would push: kz q + cz dq/dt = 5 kN at 400 kPa.
    assert ss.params[f"kz{wheel}"] * x[slip.X[q]] + ss.params[f"cz{wheel}"] * x[slip.X[u]] > 4e3
    dx, out = rhs.outputs(0.0, x)
    for name in ("fz", "mz", "fy_ss", "mz_ss", "fy_limit"):
        assert out[slip.OUT[f"{name}_{wheel}"]] == 0.0, name
    # The carcass (default transient) still holds the deflection it had in contact; with no grip its patch
    # slides with the wheel and the force relaxes through the sliding viscosity alone, in ~1e-7 s.
    force = out[slip.OUT[f"fy_{wheel}"]]
    assert force == pytest.approx(ss.params[f"cc{wheel}"] * x[slip.X[f"carcass_y_{wheel}"]], rel=1e-15)
    assert ss.params[f"cc{wheel}"] * dx[slip.X[f"carcass_y_{wheel}"]] == pytest.approx(
        -ss.params[f"cc{wheel}"] * force / ss.params["carcass_viscosity"], rel=1e-9)
    assert np.all(np.isfinite(dx))
    assert dx[slip.X["D_damper"]] == pytest.approx(0.0, abs=1e-9)   # the other tyre is at rest vertically
    oracle, oracle_out = slip_build.numpy_rhs(0.0, x, slip.parameter_vector(ss.params), ss.params.model,
                                                 with_outputs=True)
    assert oracle_out[slip.OUT[f"fz_{wheel}"]] == 0.0
    np.testing.assert_allclose(dx, oracle, rtol=0, atol=1e-10 * np.abs(dx).max())
    # Touching the ground again (q > 0), the same rate pushes: the contact is back.
    x[slip.X[q]] = 1e-4
    x = slip.solve_pitch(rhs, x)
    assert rhs.outputs(0.0, x)[1][slip.OUT[f"fz_{wheel}"]] > 0.0


def test_mirror_symmetric_kicks(rider_bike, gains, t03):
    responses = []
    for sign in (1.0, -1.0):
        par = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(symmetric_tyres=True), gains=gains,
                                    kick=dict(t0=0.0, duration=0.15, displacement=0.15 * sign))
        ss = steady.steady_state(par, 3.0)
        rhs = slip.CompiledRHS(ss.params)
        tr = lsoda.integrate(rhs, ss.x, 3.0, t_start=-0.2, breakpoints=(0.0, 0.15), rtol=1e-11, output_rate=200)
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
    # As many names as the model's, one of them not its own: refused as missing (the gather's shortcut needs
    # every name found).
    par["kzx"] = 1.0
    with pytest.raises(wk.errors.InputError, match="missing: kzr"):
        slip.CompiledRHS(par)
    par = slip.model_parameters(rider_bike, t03, t03)
    par["kzx"] = 1.0
    with pytest.raises(wk.errors.InputError, match="unknown slip-model parameters: kzx"):
        slip.CompiledRHS(par)
    with pytest.raises(wk.errors.InputError, match="unknown slip-model parameters: kzx"):
        slip.CompiledRHS(slip.model_parameters(rider_bike, t03, t03)).replaced(kzx=1.0)


def test_a_replaced_model_is_the_model_of_the_replaced_parameters(rider_bike, gains, t03):
    """CompiledRHS.replaced changes the named values of the vector only: the same vector, right-hand side and
    outputs as the model built from ``params.replace``, bit for bit; the original is unchanged; and
    outputs_view reads what outputs copies."""
    par = slip.model_parameters(rider_bike, t03, t03, gains=gains)
    ss = steady.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    before = rhs.p.copy()
    bumped = rhs.replaced(ku7=ss.params["ku7"] + 1.0, T6c=0.5)
    built = slip.CompiledRHS(ss.params.replace(ku7=ss.params["ku7"] + 1.0, T6c=0.5))
    assert np.array_equal(bumped.p, built.p) and np.array_equal(rhs.p, before)
    assert np.array_equal(bumped(0.0, ss.x), built(0.0, ss.x))
    assert not np.array_equal(bumped(0.0, ss.x), rhs(0.0, ss.x))
    for a, b in zip(bumped.outputs(0.0, ss.x), built.outputs_view(0.0, ss.x), strict=True):
        assert np.array_equal(a, b)
    assert np.array_equal(slip.parameter_vector(ss.params), slip.parameter_vector(dict(ss.params), rhs.layout))


# ------------------------------------------------------- the tyre transient forms

def _eigenvalues(rider_bike, gains, rear, front, transient, symmetric):
    par = slip.model_parameters(rider_bike, rear, front,
                                slip.ModelOptions(symmetric_tyres=symmetric, tyre_transient=transient), gains=gains)
    ss = steady.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    return np.linalg.eigvals(slip.linearize(rhs, ss.x)), rhs, ss


def _matched_error(ev, ref):
    matched = np.array([ev[np.argmin(np.abs(ev - r))] for r in ref])
    return np.abs(matched - ref) / np.abs(ref)


@pytest.mark.parametrize("front_kpa", [400.0, 350.0])
@pytest.mark.parametrize("transient", ["contact_patch", "slip_lag"])
def test_small_slip_dynamics_equal_the_force_lag(rider_bike, gains, t03, front_kpa, transient):
    """Symmetric tyres (upright, zero slip): the linearised contact-patch forms equal the thesis' form.

    At a steady state with zero slip and camber, lagging the patch slip and
    camber gives d(dF)/dt = (V/sigma)(C_a da + C_g dg - dF), the force lag's
    equation, and the secant ratio is 1 there. Measured 2e-7 (400 kPa) and
    6e-8 (350 kPa front): the finite-difference Jacobians' own error.
    """
    front = wk.tyres.load("T03", pressure_kpa=front_kpa)
    ref, _, _ = _eigenvalues(rider_bike, gains, t03, front, "force_lag", True)
    ev, _, _ = _eigenvalues(rider_bike, gains, t03, front, transient, True)
    big = np.abs(ref) > 1e-6        # the forward-speed mode is 0 (measured ~1e-15 in both)
    assert np.max(_matched_error(ev, ref[big])) < 1e-6
    assert np.max(np.abs(ev[np.abs(ev) < 1e-6])) < 1e-9 and np.sum(~big) == 1


def test_measured_tyres_differ_from_the_force_lag_only_by_the_load_rate_term(rider_bike, gains, t03):
    """Measured T03 (a slow steady turn with offsets): the contact-patch force follows the load at once.

    Linearised, the contact-patch form is the force lag plus (dF_ss/dFz) dFz/dt
    in each tyre slot (the lagged force follows the load only through the lag).
    With the tyres' offsets dF_ss/dFz is not 0 at the steady point, which moves
    the fast tyre and vertical modes by up to 1.7 % (400 kPa); the slow modes
    (|lambda| < 5 1/s, which the rider acts on) by 3.2e-4. Adding that term
    to the force lag's Jacobian leaves 3.5e-4 (measured).
    """
    ref, rhs, ss = _eigenvalues(rider_bike, gains, t03, t03, "force_lag", False)
    ev, _, _ = _eigenvalues(rider_bike, gains, t03, t03, "contact_patch", False)
    slow = np.abs(ref) < 5.0
    assert np.sum(slow) == 4        # speed, weave pair, the real mode at -2.9 1/s
    assert np.max(_matched_error(ev, ref[slow])) < 1e-3
    assert np.max(_matched_error(ev, ref)) > 1e-2    # the fast modes really differ
    A = slip.linearize(rhs, ss.x)
    _, out = rhs.outputs(0.0, ss.x)
    names = list(slip.LINEAR_STATES)
    corrected = A.copy()
    for wheel, speed, (force_row, moment_row) in (("r", "u9", (11, 13)), ("f", "u10", (12, 14))):
        alpha, gamma, fz = (out[slip.OUT[f"{k}_{wheel}"]] for k in ("slip", "camber", "fz"))
        h = 1e-3
        dF = (t03.lateral_force(alpha, gamma, fz + h) - t03.lateral_force(alpha, gamma, fz - h)) / (2 * h)
        dM = (t03.aligning_moment(alpha, gamma, fz + h) - t03.aligning_moment(alpha, gamma, fz - h)) / (2 * h)
        # Fz = kz q + cz u, so dFz/dt = kz u + cz du/dt (the speed's row of the Jacobian).
        load_rate = (ss.params[f"kz{wheel}"] * np.eye(len(names))[names.index(speed)]
                     + ss.params[f"cz{wheel}"] * A[names.index(speed)])
        corrected[force_row] += dF * load_rate
        corrected[moment_row] += dM * load_rate
    assert np.max(_matched_error(ev, np.linalg.eigvals(corrected))) < 1e-3


def test_secant_ratio_of_t03():
    """T03 400 kPa, 635 N: 1 at zero slip, even, ~0.5 at the force peak, falling through the sliding range."""
    tyre = wk.tyres.load("T03", pressure_kpa=400)
    slips = np.radians(np.linspace(-90.0, 90.0, 3601))
    ratio = tyre.secant_ratio(slips, 635.0)
    force = -tyre.lateral_force(slips, 0.0, 635.0)
    np.testing.assert_allclose(ratio, ratio[::-1], rtol=1e-12)     # even
    assert tyre.secant_ratio(0.0, 635.0) == 1.0
    assert np.all(np.diff(ratio[1800:]) < 0.0)                     # falls monotonically with |slip|
    peak = slips[np.argmax(force)]
    # Measured: peak at 8.71 deg, ratio 0.481 there; 0.0865 at 36 deg; 0.0303 at 90 deg.
    assert np.degrees(peak) == pytest.approx(8.7, abs=0.1)
    assert tyre.secant_ratio(peak, 635.0) == pytest.approx(0.48, abs=0.01)
    assert tyre.secant_ratio(np.radians(36.0), 635.0) == pytest.approx(0.0865, abs=5e-4)
    assert tyre.secant_ratio(np.radians(90.0), 635.0) == pytest.approx(0.0303, abs=5e-4)
    assert ratio.min() > wk.transient.G_MIN       # the floor never acts for this fit


def test_secant_series_joins_the_quotient():
    """Across |B x| = SECANT_SERIES_LIMIT the series and the quotient agree to round-off."""
    tyre = wk.tyres.load("T03", pressure_kpa=400)
    factors = tyre.magic_formula_factors(635.0)
    edge = np.radians(wk.magic_formula.SECANT_SERIES_LIMIT / factors["B"])   # |B x| at the limit, x in deg
    below, above = tyre.secant_ratio(edge * (1 - 1e-9), 635.0), tyre.secant_ratio(edge * (1 + 1e-9), 635.0)
    # The dropped series term is O((B x)^4) = 1e-16; the quotient's cancellation error ~1e-16/(B x)^2 = 1e-8
    # at worst in principle, measured 1e-13.
    assert abs(below - above) < 1e-10
    assert 1.0 - below < 1e-7
    # The linear tyre (huge D, tiny B) never leaves the series: its relaxation length stays constant.
    linear = wk.tyres.linear_tyre(11.0, 0.175, 1e5)
    fy = linear.blend[0][1]
    slope, ratio = wk.magic_formula.lateral_secant_numpy(np.radians([0.0, 30.0, 80.0]), 600.0, fy)
    np.testing.assert_allclose(ratio, 1.0, atol=1e-12)


def test_patch_states_stay_finite_as_the_rolling_speed_vanishes(rider_bike, t03):
    """A wheel turned sideways (|vx| -> 0) while its contact slides: the patch slip turns toward
    +-90 deg at a finite rate, the camber lag stops, force and moment follow the steady curve; unloaded,
    they are exactly zero (the contact-patch form; the carcass' own case is in test_carcass.py)."""
    par = slip.model_parameters(rider_bike, t03, t03,
                                slip.ModelOptions(symmetric_tyres=True, tyre_transient="contact_patch"))
    ss = steady.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    x = ss.x.copy()
    x[slip.X["u1"]] = 0.0            # no forward speed: vx = 0 at both wheels (upright, no steer)
    x[slip.X["u2"]] = 0.8            # sliding to the right
    x[slip.X["slip_patch_r"]] = 0.3
    dx, out = rhs.outputs(0.0, x)
    assert np.all(np.isfinite(dx))
    assert abs(out[slip.OUT["vx_r"]]) < 1e-12
    sigma = out[slip.OUT["sigma_r"]]
    # sigma da'/dt = vsy cos(a')^2 when vx = 0; dg'/dt = 0.
    vsy = 0.8
    assert dx[slip.X["slip_patch_r"]] == pytest.approx(vsy * np.cos(0.3)**2 / sigma, rel=1e-9)
    assert dx[slip.X["camber_patch_r"]] == 0.0
    symmetric = t03.without_offsets()
    assert out[slip.OUT["fy_r"]] == pytest.approx(float(symmetric.lateral_force(0.3, x[slip.X["camber_patch_r"]],
                                                                              out[slip.OUT["fz_r"]])), rel=1e-12)
    x[slip.X["slip_patch_r"]] = np.radians(89.999)
    assert np.all(np.isfinite(rhs(0.0, x)))
    x[slip.X["q9"]] = -0.01          # lifted: unloaded
    x[slip.X["u9"]] = 0.0
    dx, out = rhs.outputs(0.0, x)
    assert out[slip.OUT["fz_r"]] == 0.0 and out[slip.OUT["fy_r"]] == 0.0 and out[slip.OUT["mz_r"]] == 0.0
    assert np.all(np.isfinite(dx))


def test_steady_motion_moved_in_time_is_a_solution(rider_bike, gains, t03):
    """advance_steady: integrating the steady turn for 2 s from the state 2 s earlier arrives at the state."""
    ss = steady.steady_state(slip.model_parameters(rider_bike, t03, t03, gains=gains), 3.0)
    rhs = slip.CompiledRHS(ss.params)
    start = steady.advance_steady(rhs, ss.x, -2.0)
    # Measured yaw -0.190 rad, rear contact 6 m back on a 32 m circle.
    assert start[slip.X["q3"]] == pytest.approx(-2.0 * ss.x[slip.X["u3"]], rel=1e-14)
    tr = lsoda.integrate(rhs, start, 0.0, t_start=-2.0, rtol=1e-12, output_rate=10)
    dyn = [slip.X[n] for n in slip.DYNAMIC_STATES]
    # Measured 3e-11 (positions in m, angles in rad, speeds): integration accuracy at rtol 1e-12.
    np.testing.assert_allclose(tr.end_state[dyn], ss.x[dyn], rtol=0, atol=1e-9)
    back = steady.advance_steady(rhs, start, 2.0)
    np.testing.assert_allclose(back, ss.x, rtol=0, atol=1e-12)


def test_plate_stop_impulse_is_the_limit_of_a_short_stop(rider_bike, gains, t03):
    """The plate stop's impulse against an independent computation: the plate decelerating linearly
    from 2 m/s to rest in delta seconds instead of instantly. As delta -> 0 the speeds tend to the
    impulse's (error O(delta): measured 1.4e-4 at 1e-5 s, 1.4e-5 at 1e-6 s) and so does the
    kinetic-energy change (measured -0.0279 and -0.0302 J against the impulse's -0.0305 J)."""
    T, D = 0.15, 0.15
    par = slip.model_parameters(rider_bike, t03, t03, gains=gains, kick=dict(t0=0.0, duration=T, displacement=D))
    ss = steady.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    x_stop = lsoda.integrate(rhs, ss.x, T, rtol=1e-12, output_rate=1000).end_state
    x_impulse, info = slip.velocity_jump(rhs, T, x_stop, impulse=True)
    # The impulse's work equals the kinetic-energy change computed from the energy expression.
    assert info["impulse_work_j"] == pytest.approx(info["kinetic_energy_change_j"], abs=1e-9)
    assert x_impulse[slip.X["W_plate"]] - x_stop[slip.X["W_plate"]] == pytest.approx(info["impulse_work_j"], abs=1e-12)
    # and the constraints hold after it (the plate at rest).
    M, A, a0 = rhs.impulse_terms(T, x_impulse)
    u_after = rhs.outputs(T, x_impulse)[1][:len(slip.SPEEDS)]
    assert np.max(np.abs(A @ u_after + a0)) < 1e-12
    ind = [slip.X[n] for n in slip.INDEPENDENT]
    ke = rhs.outputs(np.nextafter(T, 0.0), x_stop)[1][slip.OUT["kinetic_energy"]]
    errors, changes = [], []
    v = 2 * D / T
    for delta in (1e-5, 1e-6):
        short = slip.CompiledRHS(ss.params.replace(kick_profile=2.0, kick_t0=T, kick_c0=D, kick_c1=v,
                                      kick_c2=-v / (2 * delta), kick_c3=0.0))
        x = lsoda.integrate(short, x_stop, T + delta, t_start=T, rtol=1e-12, samples=np.array([T])).end_state
        errors.append(np.max(np.abs(x[ind] - x_impulse[ind])))
        changes.append(rhs.outputs(T + delta, x)[1][slip.OUT["kinetic_energy"]] - ke)
    assert errors[1] < 3e-5 and errors[0] / errors[1] > 8.0        # converges, linearly
    assert abs(changes[1] - info["kinetic_energy_change_j"]) < 1e-3
    # The re-solve of the dependent speeds alone loses about 30 times more (measured 0.98 J).
    _, resolve = slip.velocity_jump(rhs, T, x_stop, impulse=False)
    assert resolve["kinetic_energy_change_j"] < 20 * info["kinetic_energy_change_j"] < 0.0


@pytest.mark.parametrize("pressure", [300.0, 400.0, 500.0])
def test_t03_curve_opposes_the_slip_at_every_camber_and_load(pressure):
    """The sliding dissipation -(F - F0) V' >= 0 needs F_ss(a', g', Fz) - F_ss(0, g', Fz) to oppose a':
    T03 table7_9 over +-90 deg of slip, 50-1200 N, +-45 deg of camber (the chapter8 fit does not)."""
    tyre = wk.tyres.load("T03", pressure_kpa=pressure)
    slips = np.radians(np.linspace(-90.0, 90.0, 721))[None, None, :]
    loads = np.array([50.0, 100.0, 200.0, 343.0, 500.0, 635.0, 800.0, 1000.0, 1200.0])[:, None, None]
    cambers = np.radians(np.linspace(-45.0, 45.0, 37))[None, :, None]
    excess = tyre.lateral_force(slips, cambers, loads) - tyre.lateral_force(0.0 * slips, cambers, loads)
    assert np.all(excess * np.sign(slips) <= 0.0)
    chapter8 = wk.tyres.load("T03", pressure_kpa=pressure, coefficient_set="chapter8")
    excess = chapter8.lateral_force(slips, cambers, loads) - chapter8.lateral_force(0.0 * slips, cambers, loads)
    assert np.any(excess * np.sign(slips) > 0.0)


def test_upright_start_is_upright_and_balanced_vertically_but_not_steady(rider_bike, gains, t03):
    """The authors' start: roll, steer, yaw, lateral speeds and T6c zero; front contact on the ground and
    both tyres in vertical equilibrium (residual < 1e-8); the tyre states at their zero-slip values.
    With T03's offsets the lateral accelerations are not zero (measured 0.3-2.5 m/s^2 or rad/s^2); with
    symmetric tyres it is the steady motion (same pitch and compressions to 1e-12)."""
    par = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(tyre_transient="force_lag"), gains=gains)
    start = steady.upright_state(par, 3.0)
    x = start.x
    assert start.params["T6c"] == 0.0 and start.residual < 1e-8
    for name in ("q3", "q4", "q7", "u2", "u3", "u4", "u7", "u9", "u10"):
        assert x[slip.X[name]] == 0.0
    rhs = slip.CompiledRHS(start.params)
    dx, out = rhs.outputs(0.0, x)
    assert abs(out[slip.OUT["holonomic"]]) < 1e-10
    assert abs(dx[slip.X["u9"]]) < 1e-6 and abs(dx[slip.X["u10"]]) < 1e-6
    for slot, name in zip(slip.TYRE_STATES, ("fy_ss_r", "fy_ss_f", "mz_ss_r", "mz_ss_f"), strict=True):
        assert x[slip.X[slot]] == out[slip.OUT[name]] != 0.0
    assert start.unknowns["largest_rate"] > 0.05
    symmetric = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(symmetric_tyres=True), gains=gains)
    up, motion = steady.upright_state(symmetric, 3.0), steady.steady_state(symmetric, 3.0)
    for name in ("q5", "q9", "q10"):
        assert up.x[slip.X[name]] == pytest.approx(motion.x[slip.X[name]], abs=1e-12)
    assert up.unknowns["largest_rate"] < 1e-9


def test_kept_speeds_leave_the_rear_sliding_at_the_plate_velocity_times_sin_yaw(rider_bike, gains, t03):
    """The authors' plate stop: every speed continuous across it, and the rear constraint then imposes
    the slide vp sin(yaw) (vp = 2 m/s before the stop), constant while the motion goes on."""
    T, D = 0.15, 0.15
    par = slip.model_parameters(rider_bike, t03, t03, gains=gains, kick=dict(t0=0.0, duration=T, displacement=D))
    ss = steady.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    x_stop = lsoda.integrate(rhs, ss.x, T, rtol=1e-12, output_rate=1000).end_state
    slide = slip.kept_speeds_slide(rhs, T, x_stop)
    assert slide == pytest.approx(2 * D / T * np.sin(x_stop[slip.X["q3"]]), rel=1e-9)
    assert abs(slide) > 0.05
    after = slip.CompiledRHS(ss.params.replace(vsx_r=slide))
    before = rhs.outputs(np.nextafter(T, 0.0), x_stop)[1][:len(slip.SPEEDS)]
    np.testing.assert_allclose(after.outputs(T, x_stop)[1][:len(slip.SPEEDS)], before, rtol=0, atol=1e-12)
    tr = lsoda.integrate(after, x_stop, T + 1.0, t_start=T, rtol=1e-12, output_rate=100)
    for t, x in zip(tr.t, tr.x, strict=True):
        _, A, a0 = after.impulse_terms(t, x)
        u = after.outputs(t, x)[1][:len(slip.SPEEDS)]
        residual_without_slide = A @ u + a0 + np.array([slide, 0.0, 0.0])
        assert residual_without_slide[0] == pytest.approx(slide, abs=1e-9)
    assert slip.kept_speeds_slide(after, T + 1.0, tr.end_state) == pytest.approx(slide, abs=1e-12)


@pytest.mark.parametrize("fields", [
    {}, {"pressure_kpa": 350.0}, {"tyre_transient": "force_lag"}, {"tyre_transient": "contact_patch"},
    {"tyre_transient": "slip_lag"}, {"carcass_sliding": "curve", "carcass_damping": 75.0},
    {"rider_body": "leaning", "arms": "on", "reflex_delay": 0.1, "reflex_roll": 20.0, "plate_stop": "resolve"},
], ids=["default", "350kPa", "force_lag", "contact_patch", "slip_lag", "damped_curve", "body_arms_reflex"])
def test_outputs_without_the_dynamics_are_the_right_hand_side_outputs_bit_for_bit(fields):
    """The outputs function leaves Kane's mass matrix and solve out: at every sample of a run (kick, plate
    stop, recovery; every piece's own model) its outputs equal the whole right-hand side's exactly (tolerance
    0: the same C statements, pruned, so the sweep's tables do not move by one bit)."""
    from whipple_kick.library import inputs
    from whipple_kick.simulate import assembly, integration
    scenario = wk.Scenario(duration=1.0, **fields)
    kick = inputs.kick_of(scenario.validate())
    solution = integration.integrate_run(assembly.assemble(scenario, kick), scenario, kick)
    fast, reference = solution.outputs(), solution.outputs(via_rhs=True)
    assert np.array_equal(fast, reference), np.flatnonzero(np.any(fast != reference, axis=0))
    # Without the optional groups (a sweep row's outputs), and with each alone: the rest bit for bit the same,
    # the groups left out NaN (never read as values).
    names = solution.model.OUTPUT_NAMES
    for asked in ((), *slip.layout.OPTIONAL_OUTPUTS):
        some = solution.outputs(names=asked)
        left_out = [names.index(o) for group in slip.layout.OPTIONAL_OUTPUTS if group != asked for o in group]
        kept = [k for k in range(len(names)) if k not in left_out]
        assert np.array_equal(some[:, kept], reference[:, kept]), asked
        assert np.isnan(some[:, left_out]).all(), asked
