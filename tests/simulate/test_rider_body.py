"""The rider's body: the locked body is the lumped rider, the split conserves the rider, the hip and
arm single-degree-of-freedom systems, the reflex delay through the full model, energy, the output-feedback LQR,
the steady lean and the scenario's checks.

Each bound is a few times the value measured when the test was written (given in the docstring).
"""
import math

import numpy as np
import pytest
from scipy.linalg import solve_continuous_lyapunov

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.library import inputs, riders
from whipple_kick.model import benchmark, classic, parts, slip
from whipple_kick.model.benchmark import steer_axis_tilt
from whipple_kick.model.symbolic import slip_build
from whipple_kick.simulate import assembly, control, lsoda, steady


@pytest.fixture(scope="module")
def bike():
    return wk.bicycles.load("balanceassist_v1")


@pytest.fixture(scope="module")
def rider():
    return riders.yeadon_rider("jason", mass_kg=70)


@pytest.fixture(scope="module")
def t03():
    return wk.tyres.load("T03", pressure_kpa=400)


def _totals(bench, extra=()):
    """Total mass [kg] and mass centre (x, z) [m] of a benchmark set's four bodies and ``extra`` (m, x, z)."""
    parts = [(bench["mR"], 0.0, -bench["rR"]), (bench["mB"], bench["xB"], bench["zB"]),
             (bench["mH"], bench["xH"], bench["zH"]), (bench["mF"], bench["w"], -bench["rF"]), *extra]
    m = sum(p[0] for p in parts)
    return m, sum(p[0] * p[1] for p in parts) / m, sum(p[0] * p[2] for p in parts) / m


def _upper_body_com(seat, body):
    """The upper body's mass centre in the benchmark frame: the seat point plus (lt1, 0, lt3) (G = benchmark axes)."""
    return seat + np.array([body["lt1"], 0.0, body["lt3"]])


# ----------------------------------------------------------------- 1. locked body = lumped rider

@pytest.mark.parametrize("shift_m", [0.0, -0.1], ids=["seated", "shifted-0.1m"])
def test_upper_body_merged_into_the_rear_frame_is_the_lumped_rider(bike, rider, t03, shift_m):
    """The split rider with its upper body merged back into the rear frame
    (:func:`whipple_kick.model.parts.merge_into_rear_frame`: what the rigid rider with arms on the bar runs,
    the model without the trunk part) is the rider lumped into the rear frame by :func:`riders.seat`, an
    independent computation (Yeadon's combined inertia): the same Moore parameters, the same steady turn, the
    same rates at random states and the same roll and steer after a push. Also with the whole rider shifted
    0.1 m rearward (a rear load share's shift, :func:`riders.shifted`): the hinge moves with it.

    Measured: Moore parameters 2e-16 relative; steady unknowns ~1e-15 relative; rates ~1e-14 relative to
    max(|rate|, 1) over 20 states; histories over 3 s (rtol 1e-11) ~1e-13 rad. Bounds 1e-12 (parameters),
    1e-10 (rates) and 1e-11 rad (histories).
    """
    lumped = riders.seat(bike, rider, shift_m=shift_m)
    split, body = riders.seat_with_body(bike, rider, arms_on_bar=False, shift_m=shift_m)
    assert body["mt"] > 30.0   # the upper body really carries most of the rider (measured 40.1 kg of 70)
    merged = parts.merge_into_rear_frame(dict(split.moore), body)
    for name in ("mc", "l1", "l2", "ic11", "ic22", "ic33", "ic31"):
        assert merged[name] == pytest.approx(lumped.moore[name], rel=1e-12, abs=1e-12), name
    gains = control.gains_dict(control.lqr_gains(lumped, 3.0)[0])
    pa = slip.model_parameters(dict(lumped.moore), t03, t03, gains=gains)
    pb = slip.model_parameters(merged, t03, t03, gains=gains)
    assert pb.model.layout is slip.layout.BASE   # no trunk part, nothing locked
    sa, sb = steady.steady_state(pa, 3.0), steady.steady_state(pb, 3.0)
    assert "q11" not in sb.unknowns
    for name, value in sa.unknowns.items():
        assert sb.unknowns[name] == pytest.approx(value, rel=1e-10, abs=1e-14), name
    assert sb.params["ccr"] == pytest.approx(sa.params["ccr"], rel=1e-12)
    ra, rb = slip.CompiledRHS(sa.params), slip.CompiledRHS(sb.params)
    keep = list(range(len(slip.STATE_NAMES)))
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(20):
        x = sa.x.copy()
        for name, size in (("q3", 0.5), ("q4", 0.2), ("q7", 0.3), ("u2", 0.3), ("u3", 0.5), ("u4", 1.0),
                           ("u7", 2.0), ("u9", 0.05), ("u10", 0.05)):
            x[slip.X[name]] += rng.uniform(-size, size)
        x[slip.X["u1"]] = rng.uniform(2.0, 6.0)
        x[slip.X["q9"]] *= rng.uniform(0.5, 1.5)
        x[slip.X["q10"]] *= rng.uniform(0.5, 1.5)
        for name in slip.PATCH_STATES:
            x[slip.X[name]] *= rng.uniform(-2.0, 2.0)
        x = slip.solve_pitch(ra, x)
        da, db = ra(0.0, x), rb(0.0, x)
        worst = max(worst, float(np.max(np.abs(da - db)[keep] / np.maximum(np.abs(da[keep]), 1.0))))
    assert worst < 1e-10
    histories = []
    for s, rhs in ((sa, ra), (sb, rb)):
        x0 = s.x.copy()
        x0[slip.X["u4"]] += 0.3
        x0[slip.X["u7"]] += 0.2
        tr = lsoda.integrate(rhs, x0, 3.0, rtol=1e-11, output_rate=200)
        assert not tr.fell
        histories.append(tr)
    a, b = histories
    assert np.abs(a.state("q4")).max() > 0.1   # a real response (measured 0.14 rad)
    for name in ("q4", "q7"):
        assert np.abs(a.state(name) - b.state(name)).max() < 1e-11, name


# ----------------------------------------------------------------- 2. the split conserves the rider

@pytest.mark.parametrize("shift_m", [0.0, 0.05])
@pytest.mark.parametrize("arms_on_bar", [False, True])
def test_split_conserves_the_riders_mass_and_mass_centre(bike, rider, arms_on_bar, shift_m):
    """Legs (rear frame) + forearms (front frame, on the bar) + upper body = the seated rider: mass and mass
    centre as :func:`riders.place` and the lumped bicycle's; the hip is at the seat point.

    Measured: mass 1.4e-14 kg, mass centre 1.1e-16 m (the rider alone: 0 kg, 2.2e-16 m), hip 2.8e-17 m.
    Bound 1e-12 (kg, m).
    """
    seated = riders.shifted(riders.place(bike, rider), shift_m)
    lumped = riders.seat(bike, rider, shift_m=shift_m)
    split, body = riders.seat_with_body(bike, rider, arms_on_bar=arms_on_bar, shift_m=shift_m)
    com = _upper_body_com(seated.seat, body)
    whole = _totals(split.benchmark, [(body["mt"], com[0], com[2])])
    np.testing.assert_allclose(whole, _totals(lumped.benchmark), rtol=0, atol=1e-12)
    m_bike, x_bike, z_bike = _totals(bike.benchmark)
    m_rider = whole[0] - m_bike
    assert m_rider == pytest.approx(seated.mass, abs=1e-12)
    assert (whole[0] * whole[1] - m_bike * x_bike) / m_rider == pytest.approx(seated.com[0], abs=1e-12)
    assert (whole[0] * whole[2] - m_bike * z_bike) / m_rider == pytest.approx(seated.com[2], abs=1e-12)
    # The hip point (lh1, lh3 along Moore's C.x, C.z from the rear wheel centre) is the seat point.
    lam = bike.benchmark["lam"]
    c_x, c_z = np.array([math.cos(lam), 0.0, -math.sin(lam)]), np.array([math.sin(lam), 0.0, math.cos(lam)])
    hip = np.array([0.0, 0.0, -bike.benchmark["rR"]]) + body["lh1"] * c_x + body["lh3"] * c_z
    np.testing.assert_allclose(hip, seated.seat, rtol=0, atol=1e-12)
    assert body["hip_tilt"] == -lam and body["lt3"] < 0.0   # H.x horizontal; the upper body above the hip


def test_a_leaning_rider_reports_the_static_loads_of_the_whole_rider():
    """The summary's static loads of a split rider include the upper body's weight (they were the bicycle's,
    the legs' and the forearms' alone: 344 N instead of 635 N at the rear). Computed here by hand from the
    split bicycle plus the upper body; measured equal to ~1e-13 N. Bound 1e-9 N."""
    rigid = assembly.build_bicycle(wk.Scenario().bicycle_spec)[2]
    for changes in ({"rider_body": "leaning"}, {"arms": "on"}, {"rider_body": "leaning", "arms": "on"}):
        sc = wk.Scenario(**changes)
        split, _, info = assembly.build_bicycle(sc.bicycle_spec)
        bench = benchmark.from_moore(split)
        body = info["body"]
        bike = wk.bicycles.load(sc.bicycle)
        seat = riders.place(bike, riders.yeadon_rider(sc.rider, mass_kg=info["rider_mass_kg"])).seat
        com = _upper_body_com(seat, body)
        # The rigid rider with arms on the bar has its upper body in the rear frame already.
        apart = [(body["mt"], com[0], com[2])] if sc.rider_body == "leaning" else []
        m, x, _ = _totals(bench, apart)
        weight = m * bench["g"]
        assert info["static_load_rear_n"] == pytest.approx(weight * (bench["w"] - x) / bench["w"], abs=1e-9)
        assert info["static_load_front_n"] == pytest.approx(weight * x / bench["w"], abs=1e-9)
        assert info["static_load_rear_n"] == pytest.approx(635.0, abs=1e-6)
        assert info["static_load_rear_n"] == pytest.approx(rigid["static_load_rear_n"], abs=1e-9)
        assert info["total_mass_kg"] == pytest.approx(rigid["total_mass_kg"], abs=1e-9)


# ----------------------------------------------------------------- 3, 4. single-degree-of-freedom checks

def _stage2(params, q, u):
    """Full mass matrix (n x n, n speeds of the model) and forcing without tyre loads (n,) from the NumPy oracle."""
    layout = params.model.layout
    p = slip.parameter_vector(params, layout)
    with np.errstate(invalid="ignore", divide="ignore"):
        M, f0, *_ = slip_build.numpy_module(layout.part_names).stage2([0.0], q, u, [0.0], p)
    return np.asarray(M, dtype=float), np.asarray(f0, dtype=float).ravel()


def _frame_fixed_sdof(params, speed_name, h=1e-6):
    """(inertia, stiffness, damping) of one speed's row with every other coordinate and speed held at the
    upright, uncompressed configuration (q5 the steer-axis tilt, all else 0): M[i, i], -df_i/dq_i and
    -df_i/du_i by central differences."""
    speeds = params.model.layout.SPEEDS
    i = speeds.index(speed_name)
    q, u = np.zeros(len(speeds)), np.zeros(len(speeds))
    q[speeds.index("u5")] = steer_axis_tilt(params)
    M, f = _stage2(params, q, u)
    assert f[i] == 0.0   # an equilibrium of this degree of freedom
    step = np.zeros_like(q)
    step[i] = h
    k = -(_stage2(params, q + step, u)[1][i] - _stage2(params, q - step, u)[1][i]) / (2 * h)
    c = -(_stage2(params, q, u + step)[1][i] - _stage2(params, q, u - step)[1][i]) / (2 * h)
    return M[i, i], k, c


def test_hip_is_the_upper_body_on_a_spring_damper_with_the_frame_held(bike, rider, t03):
    """The u11 row with the frame held: an inverted pendulum about the horizontal hip axis H.x (G's axes are the
    benchmark axes at q11 = 0): I = it11 + mt lt3^2, k = kh + mt g lt3 (lt3 < 0: gravity destabilises the upper
    body above the hip), c = ch; the eigenvalues of [[0, 1], [-k/I, -c/I]] agree.

    Measured: I exact, c exact, k 1.4e-11 relative (central differences of the gravity torque), eigenvalues
    5.5e-14 relative. Bound 1e-9 (the brief's).

    Physics: with Moore's 128 N m/rad the hip spring does NOT hold this rider's 40 kg upper body (its mass
    centre 0.32 m above the saddle) up by itself: mt g |lt3| = 126.9 N m/rad + the inertia give k = -1.54
    N m/rad and a slow divergence, +0.031 1/s, with the frame held.
    """
    split, body = riders.seat_with_body(bike, rider, arms_on_bar=False)
    body = dict(body, kh=128.0, ch=50.0)
    params = slip.model_parameters(dict(split.moore), t03, t03, model=slip.Model(("trunk",)), body=body)
    inertia, k, c = _frame_fixed_sdof(params, "u11")
    i_ref = body["it11"] + body["mt"] * body["lt3"] ** 2
    k_ref = body["kh"] + body["mt"] * params["g"] * body["lt3"]
    c_ref = body["ch"]
    assert inertia == pytest.approx(i_ref, rel=1e-12)
    assert k == pytest.approx(k_ref, rel=1e-9)
    assert c == pytest.approx(c_ref, rel=1e-12)
    ev = np.sort_complex(np.linalg.eigvals([[0.0, 1.0], [-k / inertia, -c / inertia]]))
    ev_ref = np.sort_complex(np.linalg.eigvals([[0.0, 1.0], [-k_ref / i_ref, -c_ref / i_ref]]))
    assert np.abs(ev - ev_ref).max() < 1e-9 * np.abs(ev_ref).max()
    assert k_ref < 0.0 and ev_ref.real.max() > 0.0   # the finding above (measured -1.54 N m/rad, +0.031 1/s)


def test_arms_are_a_spring_damper_on_the_bar_with_the_frame_held(bike, rider, t03):
    """The u7 row with the frame held, no gravity and uncompressed tyres (no normal force): the front frame
    (with the forearms and hands) and the front wheel about the steer axis on the arms' spring-damper.
    The inertia is computed independently from the combined bicycle's benchmark parameters: the steer axis
    through the ground point at trail c ahead of the front contact, tilted back by lam, and the parallel-axis
    theorem for the front frame H and the front wheel F.

    Measured: inertia 2.2e-16 relative (0.554 kg m^2, of which the forearms and hands 0.395), stiffness and
    damping exact, frequency and damping ratio 2.2e-16 relative. Bound 1e-9 (the brief's).
    """
    split, body = riders.seat_with_body(bike, rider, arms_on_bar=True)
    ka, ca = 10.0, 1.5
    params = slip.model_parameters(dict(split.moore), t03, t03, model=slip.Model(("trunk", "arms")),
                                    body=dict(body, ka=ka, ca=ca, kh=0.0, ch=0.0))
    params["g"] = 0.0
    inertia, k, c = _frame_fixed_sdof(params, "u7")
    bench = split.benchmark
    lam = bench["lam"]
    axis, point = np.array([math.sin(lam), 0.0, math.cos(lam)]), np.array([bench["w"] + bench["c"], 0.0, 0.0])

    def about_axis(m, com, tensor):
        r = com - point
        r = r - (r @ axis) * axis
        return axis @ tensor @ axis + m * (r @ r)

    front_frame = np.array([[bench["IHxx"], 0.0, bench["IHxz"]], [0.0, bench["IHyy"], 0.0],
                            [bench["IHxz"], 0.0, bench["IHzz"]]])
    i_ref = (about_axis(bench["mH"], np.array([bench["xH"], 0.0, bench["zH"]]), front_frame)
             + about_axis(bench["mF"], np.array([bench["w"], 0.0, -bench["rF"]]),
                          np.diag([bench["IFxx"], bench["IFyy"], bench["IFxx"]])))
    assert inertia == pytest.approx(i_ref, rel=1e-9)
    assert (k, c) == (pytest.approx(ka, rel=1e-9), pytest.approx(ca, rel=1e-9))
    assert math.sqrt(k / inertia) == pytest.approx(math.sqrt(ka / i_ref), rel=1e-9)
    assert c / (2 * math.sqrt(k * inertia)) == pytest.approx(ca / (2 * math.sqrt(ka * i_ref)), rel=1e-9)
    # The forearms on the bar more than triple the steer inertia (measured 0.159 -> 0.554 kg m^2).
    without, body_without = riders.seat_with_body(bike, rider, arms_on_bar=False)
    bare = slip.model_parameters(dict(without.moore), t03, t03, model=slip.Model(("trunk", "arms")),
                                  body=dict(body_without, ka=ka, ca=ca, kh=0.0, ch=0.0))
    bare["g"] = 0.0
    assert _frame_fixed_sdof(bare, "u7")[0] < inertia / 3


# ----------------------------------------------------------------- 5, 6. reflex delay and energy in full runs

REFLEX = wk.Scenario(duration=2.0, rider_body="leaning", arms="on", arm_stiffness=10.0, arm_damping=1.0,
                     lqr_model="simulated", reflex_delay=0.03, reflex_steer=2.0, reflex_steer_rate=0.2)


@pytest.fixture(scope="module")
def reflex_runs():
    """The reflex run and its twin without the delay (~1 s each)."""
    return wk.run(REFLEX), wk.run(REFLEX.with_changes(reflex_delay=0.0))


def _delay_error(frame, tau):
    t = frame["time"].to_numpy()
    delayed, undelayed = frame["reflex_steer_torque"].to_numpy(), frame["reflex_undelayed_torque"].to_numpy()
    after = t >= t[0] + tau
    return np.abs(delayed[after] - np.interp(t[after] - tau, t, undelayed)).max()


def test_reflex_torque_is_the_undelayed_one_delayed_through_the_full_model(reflex_runs):
    """The trajectory's reflex_steer_torque(t) is reflex_undelayed_torque(t - tau) (interpolated at 1 kHz),
    to the (3,4) Pade filter's error on the kick's fast response; with no delay they are the same numbers.

    Measured (tau 30 ms): 3.1e-4 N m (5.1e-4 of the 0.61 N m peak, largest at t = 0.18 s, the same from the
    start or after 0.5 s); the same comparison with tau/2 or 2 tau is ~10x larger. Bound 2e-3 of the peak.
    """
    delayed, undelayed = reflex_runs
    frame = delayed.trajectory
    peak = np.abs(frame["reflex_undelayed_torque"]).max()
    assert peak > 0.3   # the reflex really acts (measured 0.61 N m)
    error = _delay_error(frame, REFLEX.reflex_delay)
    assert error < 2e-3 * peak
    for wrong in (0.5 * REFLEX.reflex_delay, 2.0 * REFLEX.reflex_delay, 0.0):
        assert _delay_error(frame, wrong) > 3.0 * error, wrong
    other = undelayed.trajectory
    assert np.array_equal(other["reflex_steer_torque"].to_numpy(), other["reflex_undelayed_torque"].to_numpy())


@pytest.fixture(scope="module")
def leaning_run():
    """The default run with the leaning rider and the LQR designed on the model simulated (~1 s)."""
    return wk.run(wk.Scenario(rider_body="leaning", lqr_model="simulated", duration=2.0))


def test_energy_balances_with_the_body_arms_and_reflex(reflex_runs, leaning_run):
    """The energy balance closes with a leaning body, arms and a (delayed) reflex: the hip's and arms'
    springs are in the stored energy, their dampers in the dissipation, the reflex and rider torques in the
    steer work.

    Measured max |energy_balance_residual|: 2.3e-8 J (reflex), 7.2e-9 J (no delay), 6.6e-9 J (leaning only;
    its upper body leans up to 0.053 rad).
    Bound 2e-7 J.
    """
    for result in (*reflex_runs, leaning_run):
        frame = result.trajectory
        assert not result.summary["fell"]
        assert np.abs(frame["energy_balance_residual"]).max() < 2e-7
        assert np.abs(frame["upper_body_lean"]).max() > 1e-3   # the body really moves


def test_hip_and_arm_springs_and_dampers_are_in_the_energy(bike, rider, t03):
    """At a state with the tyres at rest vertically (u9 = u10 = 0): the stored energy less the tyres' springs
    is kh q11^2/2 + ka (q7 - sin(lam) q11)^2/2, the damper rate is ch u11^2 + ca (u7 - sin(lam) u11)^2, and
    the hip and arm torques are those spring-dampers' (H.x . C.z = sin(lam) with H.x horizontal).
    Measured ~1e-16 relative. Bound 1e-12."""
    split, body = riders.seat_with_body(bike, rider, arms_on_bar=True)
    body = dict(body, kh=128.0, ch=50.0, ka=10.0, ca=1.5)
    ss = steady.steady_state(slip.model_parameters(dict(split.moore), t03, t03, model=slip.Model(("trunk", "arms")),
                                                   body=body), 3.0)
    rhs = slip.CompiledRHS(ss.params)
    X = rhs.layout.X
    x = ss.x.copy()
    x[X["q11"]], x[X["u11"]], x[X["q7"]], x[X["u7"]] = 0.05, -0.3, 0.1, 0.7
    x[slip.X["u9"]] = x[slip.X["u10"]] = 0.0
    x = slip.solve_pitch(rhs, x)
    dx, out = rhs.outputs(0.0, x)
    s = math.sin(-body["hip_tilt"])
    q9, q10 = x[slip.X["q9"]], x[slip.X["q10"]]
    tyres = 0.5 * (ss.params["kzr"] * max(q9, 0.0) ** 2 + ss.params["kzf"] * max(q10, 0.0) ** 2)
    arm_angle, arm_rate = 0.1 - s * 0.05, 0.7 - s * (-0.3)
    springs = 0.5 * 128.0 * 0.05 ** 2 + 0.5 * 10.0 * arm_angle ** 2
    assert out[slip.OUT["spring_energy"]] - tyres == pytest.approx(springs, rel=1e-12)
    assert dx[slip.X["D_damper"]] == pytest.approx(50.0 * 0.3 ** 2 + 1.5 * arm_rate ** 2, rel=1e-12)
    assert out[rhs.layout.OUT["hip_torque"]] == pytest.approx(-(128.0 * 0.05 + 50.0 * -0.3), rel=1e-12)
    assert out[rhs.layout.OUT["arm_steer_torque"]] == pytest.approx(-(10.0 * arm_angle + 1.5 * arm_rate), rel=1e-12)


# ----------------------------------------------------------------- 7. output-feedback LQR

@pytest.fixture(scope="module")
def whipple_moore():
    combined, _ = riders.for_rear_load(wk.bicycles.load("balanceassist_v1"), fz_n=635.0)
    return dict(combined.moore)


def _cost(A, b, C, k, X0):
    """The LQR cost trace(P X0) of u = -k C x, identity weights, R = 1 (inf if not stabilising)."""
    closed = A - b @ k[None, :] @ C
    if np.linalg.eigvals(closed).real.max() >= 0.0:
        return np.inf
    P = solve_continuous_lyapunov(closed.T, -(C.T @ (np.eye(len(k)) + np.outer(k, k)) @ C))
    return float(np.trace(P @ X0))


@pytest.mark.parametrize("speed", [3.0, 5.0])
def test_output_feedback_lqr_with_every_state_is_the_riccati_lqr(whipple_moore, speed):
    """With C the identity the Levine-Athans optimum is the full-state LQR, whatever the start and the
    (positive definite) initial-state covariance X0. Measured: 1.4e-11 to 4.5e-9 relative (BFGS, gtol 1e-8).
    Bound 3e-8."""
    A, B = classic.linear_state_space(whipple_moore, speed)
    b = B[:, [1]]
    K, _ = control.lqr_gains(whipple_moore, speed)
    for start in (0.5 * K, 2.0 * K):
        for X0 in (np.eye(4), np.diag([1.0, 2.0, 3.0, 4.0])):
            found, poles = control.output_feedback_lqr(A, b, np.eye(4), K0=start, X0=X0)
            assert np.abs(found - K).max() < 3e-8 * np.abs(K).max()
            assert poles.real.max() < 0.0


@pytest.mark.parametrize("speed, felt", [(3.0, [0, 1, 2]), (5.0, [0, 2, 3]), (5.0, [0, 2])])
def test_output_feedback_lqr_on_a_subset_improves_the_start_and_is_a_local_optimum(whipple_moore, speed, felt):
    """Feeding back only some states (of q4 q7 u4 u7), from the full-state LQR's gains on them: the result
    stabilises, costs less than the start (default X0 = C^T C + 1e-3 I; measured 76.3 -> 54.1, 13.7 -> 6.6,
    9.4 -> 4.7) and no small change of the gains lowers the cost (random relative 1e-3 steps: measured +2e-8 to +1.2e-4
    relative)."""
    A, B = classic.linear_state_space(whipple_moore, speed)
    b = B[:, [1]]
    C = np.eye(4)[felt]
    start = control.lqr_gains(whipple_moore, speed)[0][felt]
    X0 = C.T @ C + 1e-3 * np.eye(4)
    found, poles = control.output_feedback_lqr(A, b, C, K0=start)
    assert poles.real.max() < 0.0
    best = _cost(A, b, C, found, X0)
    assert best < 0.9 * _cost(A, b, C, start, X0)
    rng = np.random.default_rng(3)
    for _ in range(10):
        nudged = found * (1.0 + 1e-3 * rng.standard_normal(len(found)))
        assert _cost(A, b, C, nudged, X0) >= best * (1.0 - 1e-12)


def test_output_feedback_lqr_checks_the_gradient_not_bfgs_status(whipple_moore, monkeypatch):
    """Issue 31 item 11: the optimiser's result was used whatever it said. Now the relative gradient at the gains
    returned (|g| max(|K|, 1) / J) decides: a design that stops short (here BFGS held to 2 iterations) warns with
    ConvergenceWarning naming the gradient and the tolerance; one that converges does not warn, even where BFGS
    reports "precision loss" (scripts/output_feedback_convergence.py: 12 of 14 designs, largest 2.5e-6)."""
    import warnings

    import scipy.optimize

    from whipple_kick.errors import ConvergenceWarning
    A, B = classic.linear_state_space(whipple_moore, 5.0)
    b, C = B[:, [1]], np.eye(4)[[0, 2]]
    start = control.lqr_gains(whipple_moore, 5.0)[0][[0, 2]]
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        found, _ = control.output_feedback_lqr(A, b, C, K0=start)   # converged: no warning
    minimize = scipy.optimize.minimize

    def two_steps(*args, **kwargs):
        return minimize(*args, **{**kwargs, "options": {**kwargs["options"], "maxiter": 2}})
    monkeypatch.setattr(control, "minimize", two_steps)   # the name control.py calls
    with pytest.warns(ConvergenceWarning) as caught:
        stopped, poles = control.output_feedback_lqr(A, b, C, K0=start)
    text = str(caught[0].message)
    assert "did not converge: relative gradient" in text and f"> {control.GRADIENT_TOLERANCE:g}" in text
    assert poles.real.max() < 0.0 and not np.allclose(stopped, found)


# ----------------------------------------------------------------- 8. steady lean

@pytest.mark.parametrize("lqr_model", ["whipple", "simulated"])
def test_steady_turn_with_a_leaning_body_and_the_measured_tyres(lqr_model):
    """The default scenario's steady turn (measured tyres' offsets) with the leaning upper body: the start's
    accelerations in the heading frame are ~0, q11 is the steady lean (small, nonzero) and the run holds it
    until the kick; the summary reports it.

    Measured: residual 3.4e-14 (whipple design) and 2.0e-14 (simulated); lean -6.6e-4 and -2.9e-4 rad (the
    upper body leans slightly against the 1.5 and 2.3 deg roll), drift before the kick 1.5e-11 and 2.5e-12 rad
    (roll 6.6e-11, 1.0e-11). Bounds 2e-13 and 5e-10 rad.
    """
    sc = wk.Scenario(rider_body="leaning", lqr_model=lqr_model, duration=0.3)
    model = assembly.assemble(sc, inputs.kick_of(sc.validate()))
    x = model.start.x
    rhs = slip.CompiledRHS(model.params)
    assert rhs.layout.part_names == ("trunk",) and model.params["mt"] > 30.0
    dx = rhs(0.0, x)
    X = rhs.layout.X
    u1, u2, u3 = (x[X[n]] for n in ("u1", "u2", "u3"))
    residual = [dx[X["u1"]] + u3 * u2, dx[X["u2"]] - u3 * u1,
                *(dx[X[n]] for n in ("u3", "u4", "u7", "u9", "u10", "u11"))]
    assert np.abs(residual).max() < 2e-13
    lean = x[X["q11"]]
    assert 1e-5 < abs(lean) < 1e-2
    assert model.start.unknowns["q11"] == lean
    result = wk.run(sc)
    frame = result.trajectory
    before = frame["time"] < 0.0
    assert np.abs(frame["upper_body_lean"][before] - lean).max() < 5e-10
    assert np.abs(frame["roll"][before] - x[slip.X["q4"]]).max() < 5e-10
    assert result.summary["steady_state"]["upper_body_lean_rad"] == lean
    assert result.summary["linear_stability"]["stable"]


# ----------------------------------------------------------------- 9. scenario checks

BAD_BODIES = {
    "negative-hip-stiffness": ({"hip_stiffness": -1.0}, ["hip stiffness = -1.0 N m/rad", "[0, 1e+06] N m/rad"]),
    "negative-hip-damping": ({"hip_damping": -5.0}, ["hip damping = -5.0 N m s/rad", "N m s/rad"]),
    "negative-arm-stiffness": ({"arm_stiffness": -1.0}, ["arm stiffness = -1.0 N m/rad", "N m/rad"]),
    "negative-arm-damping": ({"arm_damping": -1.0}, ["arm damping = -1.0 N m s/rad", "N m s/rad"]),
    "long-delay": ({"reflex_delay": 0.6}, ["reflex delay = 0.6 s", "[0, 0.5] s"]),
    "negative-delay": ({"reflex_delay": -0.01}, ["reflex delay = -0.01 s", "[0, 0.5] s"]),
    "huge-reflex-gain": ({"reflex_steer_rate": 2e4}, ["reflex steer-rate gain = 20000.0 N m s/rad", "N m s/rad"]),
    "carcass-scale": ({"carcass_stiffness_scale": 0.0}, ["carcass stiffness scale = 0.0", "[0.05, 20]"]),
    "unknown-body": ({"rider_body": "floppy"}, ["rider body 'floppy'", "rigid, leaning"]),
    "unknown-arms": ({"arms": "both"}, ["arms 'both'", "off, on"]),
    "unknown-lqr-model": ({"lqr_model": "full"}, ["LQR design model 'full'", "whipple, simulated"]),
    "leaning-without-hip-spring": ({"rider_body": "leaning", "hip_stiffness": 0.0},
                                   ["hip stiffness = 0 N m/rad", "nothing to hold it up", "(0, 1e+06] N m/rad"]),
    "leaning-on-a-preset-with-rider": ({"rider_body": "leaning", "bicycle": "balanceassist_635N"},
                                       ["'balanceassist_635N'", "lumped in already", "balanceassist_v1"]),
    "arms-on-a-preset-with-rider": ({"arms": "on", "bicycle": "balanceassist_635N"}, ["lumped in already"]),
}


@pytest.mark.parametrize("changes, fragments", BAD_BODIES.values(), ids=BAD_BODIES.keys())
def test_bad_body_fields_are_one_line_input_errors(changes, fragments):
    """Each bad value is refused before any long work (:func:`assembly.preflight`) in one line naming it."""
    with pytest.raises(InputError) as info:
        assembly.preflight(wk.Scenario(**changes))
    message = str(info.value)
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def test_the_simulated_design_can_hold_the_heading():
    """``lqr_heading``: the design on the model simulated adds the yaw angle to what the rider feels (kq3 != 0),
    the run recovers, and asking for it with the Whipple design is a one-line InputError."""
    sc = wk.Scenario(duration=2.0, symmetric_tyres=True, lqr_model="simulated", lqr_heading=True)
    result = wk.run(sc)
    gains = result.summary["controller"]["gains"]
    assert gains["kq3"] != 0.0 and not result.summary["fell"]
    with pytest.raises(wk.errors.InputError, match="lqr_heading needs the LQR rider designed on the model simulated"):
        wk.Scenario(lqr_heading=True).validate()


def test_lateral_poles_carry_the_leaning_body():
    """steady.lateral_poles (the failure diagnoses' poles) include the leaning body's two states, and agree
    with the rigid rider's count otherwise."""
    sc = wk.Scenario(rider_body="leaning", lqr_model="simulated")
    model = assembly.assemble(sc, inputs.kick_of(sc))
    poles = steady.lateral_poles(model.params, model.start.x)
    assert poles.size == len(slip.LINEAR_STATES) - 1 + 2
    assert np.all(np.isfinite(poles)) and poles[0].real < 0.0


def test_the_whipple_design_sees_the_whole_rider():
    """With a body, the Whipple model the LQR is designed on (``build_bicycle``'s ``design``) is the whole rider
    lumped into the rear frame, as for the rigid rider: not the bicycle with legs and forearms only, which
    would leave the upper body's mass out of the rider's gains."""
    rigid = assembly.build_bicycle(wk.Scenario().bicycle_spec)[1]
    for changes in ({"rider_body": "leaning"}, {"arms": "on"}, {"rider_body": "leaning", "arms": "on"}):
        moore, design, _ = assembly.build_bicycle(wk.Scenario(**changes).bicycle_spec)
        assert design == rigid and moore != rigid


# ----------------------------------------------------------------- the field's leaning-rider model as oracle

@pytest.mark.parametrize(("k9", "c9"), [(128.0, 50.0), (400.0, 5.0)])
def test_leaning_body_is_moore_rider_lean_2012_with_stiff_tyres(bike, rider, k9, c9):
    """The leaning body (arms off the bar, hip spring-damper k9, c9) against BicycleParameters'
    MooreRiderLean2012Model (Moore 2012, "Leaning rider extension"): the upper body G on a horizontal hinge
    ``d4`` below the rear wheel centre, its mass centre ``l5`` ahead of the rear wheel centre and ``l6``
    below the hinge, its inertia in the benchmark axes, the rest of the bicycle and legs in Moore's
    parameters. Their model rolls without slip; ours has tyres, so the two coincide as the tyres stiffen.

    The six eigenvalues of theirs (roll, steer, lean and their rates) against the nearest of ours at 2, 4 and
    6 m/s, with linear tyres of cornering stiffness kappa = 1e3 and 1e5 per unit load (relaxation 1/kappa m,
    vertical stiffness 1e5 kappa N/m). Measured, largest relative error over the six: 3.8e-4 to 1.4e-2 at
    kappa = 1e3 and 3.8e-6 to 1.4e-4 at 1e5 (the larger with the stiffer hip at 6 m/s); the error falls as
    1/kappa (ratios 96-100), and the Richardson limit (100 ev(1e5) - ev(1e3)) / 99 agrees with theirs to
    3e-8 to 1.3e-6: the two models coincide in the no-slip limit. Bounds: 1e-3 at 1e5, ratio 30-300, limit
    5e-6 (the residue of the limit is the central differences' and 1/kappa^2 terms').
    """
    bpk = pytest.importorskip("bicycleparameters", reason="bicycleparameters (the test extra) is the oracle")
    from bicycleparameters.models import MooreRiderLean2012Model
    from bicycleparameters.parameter_sets import MooreRiderLean2012ParameterSet
    assert bpk
    split, body = riders.seat_with_body(bike, rider, arms_on_bar=False)
    c_x, c_z = benchmark._pitch_matrix(split.benchmark["lam"])
    hip = body["lh1"] * c_x + body["lh3"] * c_z           # (x, z) from the rear wheel centre, benchmark axes
    assert body["hip_tilt"] == -split.benchmark["lam"]    # our hinge is horizontal, as Moore's
    theirs = {name: split.moore[name] for name in benchmark.MOORE_NAMES}
    theirs.update(c9=c9, k9=k9, d4=float(hip[1]), l5=float(hip[0] + body["lt1"]), l6=body["lt3"], mg=body["mt"],
                  ig11=body["it11"], ig22=body["it22"], ig33=body["it33"], ig31=body["it31"], v=1.0)
    model = MooreRiderLean2012Model(MooreRiderLean2012ParameterSet(theirs))
    keep = [3, 5, 7, 8, 10, 11]                             # q4, q7, q9, u4, u7, u9 of their 12 states
    for speed in (2.0, 4.0, 6.0):
        A, _ = model.form_state_space_matrices(v=speed)
        ref = np.linalg.eigvals(A[np.ix_(keep, keep)])
        ours = []
        for kappa in (1e3, 1e5):
            tyre = wk.tyres.linear_tyre(kappa, 1.0 / kappa, 1e5 * kappa)
            params = slip.model_parameters(dict(split.moore), tyre, tyre, model=slip.Model(("trunk",)),
                                           body=dict(body, kh=k9, ch=c9))
            ss = steady.steady_state(params, speed)
            A_ours, _ = slip.linear.heading_linearisation(slip.CompiledRHS(ss.params), ss.x)
            ev = np.linalg.eigvals(A_ours)
            ours.append(np.array([ev[np.argmin(np.abs(ev - r))] for r in ref]))
        errors = [float(np.max(np.abs(o - ref) / np.abs(ref))) for o in ours]
        # Richardson: with an error first order in 1/kappa, (100 ev(1e5) - ev(1e3)) / 99 removes it.
        limit = (100.0 * ours[1] - ours[0]) / 99.0
        limit_error = float(np.max(np.abs(limit - ref) / np.abs(ref)))
        assert errors[1] < 1e-3, (speed, errors)
        assert 30.0 < errors[0] / errors[1] < 300.0, (speed, errors)   # first order in 1/kappa
        assert limit_error < 5e-6, (speed, limit_error)
