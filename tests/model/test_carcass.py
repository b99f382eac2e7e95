"""The carcass tyre (the default transient): passive, friction-limited, the force lag at small slip.

The acceptance of the carcass tyre: passivity and the energy balance on four runs, the friction limit
against an independent scan of the steady curve, the steady characteristic of the block held at a
constant slip, the small-slip eigenvalues against the thesis' force lag, the sliding viscosity's
convergence, the damper option, and the summary's record of the stiffness and of the extrapolation.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import whipple_kick as wk
from whipple_kick.library import inputs
from whipple_kick.model import carcass, slip
from whipple_kick.model.symbolic import slip_build
from whipple_kick.simulate import steady
from whipple_kick.simulate.scenario import Scenario
from whipple_kick.simulate.simulation import run

RUNS = {"default": {}, "left kick": {"kick_direction": "left"}, "40 m/s^2": {"kick_accel": 40.0},
        "controller off": {"controller": "off"}}


@pytest.fixture(scope="module")
def runs(base):
    out = {"default": base}
    for name, changes in RUNS.items():
        if name != "default":
            out[name] = run(Scenario(pressure_kpa=400.0, fz_n=635.0, **changes))
    return out


def _curve_extremes(tyre, camber, fz, cap_deg=carcass.PATCH_SLIP_CAP_DEG):
    """Largest and smallest F_y of the steady curve over |slip| <= cap at each (camber, load).

    A 0.5 deg scan of every sample at once, then each extreme refined by zooming in: 33 slips a step
    around the best one, the bracket 16 times narrower each step, to 1e-11 rad (vectorised over the
    samples; an extreme at the cap stays there). Independent of the C code's branch search.
    """
    cap = np.radians(cap_deg)
    coarse = np.linspace(-cap, cap, 321)
    steps = np.linspace(0.0, 1.0, 33)
    camber, fz = camber[:, None], fz[:, None]
    force = tyre.lateral_force(coarse[None, :], camber, fz)
    rows = np.arange(force.shape[0])
    extremes = []
    for sign in (1.0, -1.0):
        k = np.argmax(sign * force, axis=1)
        a0, a1 = coarse[np.clip(k - 1, 0, None)], coarse[np.clip(k + 1, None, coarse.size - 1)]
        while np.max(a1 - a0) > 1e-11:
            fine = a0[:, None] + (a1 - a0)[:, None] * steps
            j = np.argmax(sign * tyre.lateral_force(fine, camber, fz), axis=1)
            a0, a1 = fine[rows, np.clip(j - 1, 0, None)], fine[rows, np.clip(j + 1, None, steps.size - 1)]
        extremes.append(tyre.lateral_force(0.5 * (a0 + a1), camber[:, 0], fz[:, 0]))
    return tuple(extremes)


@pytest.mark.parametrize("case", list(RUNS))
def test_force_stays_within_the_friction_limit(runs, case):
    """|F_y| <= 1.0001 x the steady curve's extreme on its side at the sample's load and camber (an
    independent scan, refined to 1e-11 rad). The regularised plateau carries viscosity x the extra sliding
    speed above it: measured 1.3e-5 (default) to 5.5e-5 (40 m/s^2); the compiled limit output agrees with
    the scan to 1e-9 relative (two searches of a flat extreme: each value within ~eps of the peak)."""
    result = runs[case]
    rear, front, _ = wk.assembly.build_tyres(result.scenario.tyre_spec)
    df = result.trajectory
    for wheel, tyre in (("rear", rear), ("front", front)):
        fz = df[f"fz_{wheel}"].to_numpy()
        force = df[f"fy_{wheel}"].to_numpy()
        loaded = fz > 0.0
        hi, lo = _curve_extremes(tyre, df[f"camber_{wheel}"].to_numpy()[loaded], fz[loaded])
        limit = np.where(force[loaded] >= 0.0, hi, -lo)
        assert np.max(np.abs(force[loaded]) / limit) <= 1.0001, wheel
        np.testing.assert_allclose(df[f"fy_limit_{wheel}"].to_numpy()[loaded], limit, rtol=1e-9)


@pytest.mark.parametrize("case", list(RUNS))
def test_friction_limit_of_an_interior_peak_is_the_search_bit_for_bit(runs, case):
    """The limit output takes one set's peak value Sv +- D where the peak lies inside the cap, without the
    branch search: at every sample of the run (the wheel's own camber, load and force side) it equals the
    search's value exactly (tolerance 0: the sine at the peak the search finds is exactly +-1), so the
    trajectory's ``fy_limit_*`` columns do not move by one bit."""
    df = runs[case].trajectory
    scenario = runs[case].scenario
    rhs = slip.CompiledRHS(wk.assembly.assemble(scenario, inputs.kick_of(scenario.validate())).params)
    for wheel, name in (("r", "rear"), ("f", "front")):
        args = [df[f"{column}_{name}"].to_numpy() for column in ("camber", "fz", "fy")]
        fast, search = rhs.friction_limits(wheel, *args), rhs.friction_limits(wheel, *args, search=True)
        assert np.array_equal(fast, search), wheel
        assert np.array_equal(fast, df[f"fy_limit_{name}"].to_numpy()), wheel


@pytest.mark.parametrize("pressure", [300.0, 350.0, 400.0, 500.0])
def test_friction_limit_shortcut_is_the_search_over_cambers_loads_and_sides(pressure):
    """The same, away from any run: 60 cambers (+-40 deg) x 60 loads (1 N - 3 kN, past the fits' grip) x
    both force sides, at each measured pressure and a blend (which always searches): identical values."""
    scenario = Scenario(pressure_kpa=pressure)
    rear, front, _ = wk.assembly.build_tyres(scenario.tyre_spec)
    rhs = slip.CompiledRHS(slip.model_parameters(wk.assembly.build_bicycle(scenario.bicycle_spec)[0], rear, front))
    camber, fz, side = np.meshgrid(np.radians(np.linspace(-40.0, 40.0, 60)), np.geomspace(1.0, 3000.0, 60),
                                   [-1.0, 1.0])
    for wheel in "rf":
        fast = rhs.friction_limits(wheel, camber.ravel(), fz.ravel(), side.ravel())
        search = rhs.friction_limits(wheel, camber.ravel(), fz.ravel(), side.ravel(), search=True)
        assert np.array_equal(fast, search), wheel
        assert np.count_nonzero(fast) > fast.size // 2   # most points have grip


@pytest.mark.parametrize("fields", [{"pressure_kpa": 350.0}, {"pressure_rear_kpa": 450.0, "pressure_front_kpa": 400.0},
                                    {"pressure_kpa": 330.0, "kick_accel": 40.0}, {"kick_accel": 40.0}],
                         ids=["350kPa", "450kPa_rear", "330kPa_40m_s2", "400kPa_40m_s2"])
def test_patch_slip_shortcuts_are_the_search_bit_for_bit(fields):
    """Two shortcuts of the patch slip, each against its reference at every sample of a run (three blended,
    one measured pressure; the 40 m/s^2 kicks saturate the rear tyre), at the camber and at the lagged
    camber: a pressure blend tests whether each set's root lies on the other set's rising branch by one
    evaluation of the inner function, not by a Newton solve for each set's peak; a saturated force finds
    only the branch end on its own side. The slips equal the search's exactly (tolerance 0: the same
    decisions, then the same solves), and the force's equals the run's patch-slip column."""
    scenario = Scenario(duration=2.0, **fields)
    result = run(scenario)
    rhs = slip.CompiledRHS(wk.assembly.assemble(scenario, inputs.kick_of(scenario.validate())).params)
    df = result.trajectory
    for wheel, name in (("r", "rear"), ("f", "front")):
        args = [df[column].to_numpy() for column in (f"camber_{name}", f"camber_patch_{name}", f"fz_{name}",
                                                     f"fy_{name}")]
        fast, search = rhs.carcass_slips(wheel, *args), rhs.carcass_slips(wheel, *args, search=True)
        assert np.array_equal(fast, search), wheel
        loaded = args[2] > 0.0
        assert np.array_equal(fast[loaded, 0], df[f"slip_patch_{name}"].to_numpy()[loaded]), wheel


# ------------------------------------------------------------- the block at a constant slip

def _frozen_block(params, slip_deg, fz_target=635.0):
    """A state with the rear wheel sliding at ``slip_deg`` (upright, 3 m/s) and an ODE for its deflection alone."""
    rhs = slip.CompiledRHS(params)
    ss = steady.steady_state(params, 3.0)
    x = ss.x.copy()
    x[slip.X["u2"]] = 3.0 * np.tan(np.radians(slip_deg))
    x = slip.solve_pitch(rhs, x)
    j = slip.X["carcass_y_r"]

    def f(_, y):
        xs = x.copy()
        xs[j] = y[0]
        return [rhs(0.0, xs)[j]]

    return rhs, x, j, f


@pytest.mark.parametrize("law", carcass.SLIDING_LAWS)
def test_steady_characteristic_of_the_block(rider_bike, t03, law):
    """The block held at a constant kinematic slip (-40 to 40 deg) and load converges to the steady curve
    below the peak slip and, past it, to the peak ("peak") or to the curve itself ("curve", the fit's
    falling branch). Tolerance 1e-4 of the force: the plateau carries viscosity x (sliding speed - the
    peak's), at most 0.005 N s/m x 2 m/s = 0.01 N here."""
    params = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(symmetric_tyres=True, carcass_sliding=law))
    ss = steady.steady_state(params, 3.0)
    for slip_deg in (-40.0, -20.0, -8.0, -3.0, 0.5, 5.0, 12.0, 40.0):
        rhs, x, j, f = _frozen_block(ss.params, slip_deg)
        sol = solve_ivp(f, (0.0, 1.0), [0.0], method="Radau", rtol=1e-10, atol=1e-13)
        xs = x.copy()
        xs[j] = sol.y[0, -1]
        _, out = rhs.outputs(0.0, xs)
        alpha, camber, fz = (out[slip.OUT[n]] for n in ("slip_r", "camber_r", "fz_r"))
        assert np.degrees(alpha) == pytest.approx(slip_deg, abs=0.05)
        symmetric = t03.without_offsets()
        on_curve = float(symmetric.lateral_force(alpha, camber, fz))
        scan = np.radians(np.linspace(-80.0, 80.0, 16001))
        curve = symmetric.lateral_force(scan, camber, fz)
        rising = scan[np.argmax(curve)] <= alpha <= scan[np.argmin(curve)]   # the peak: 8.7 deg at 635 N
        expected = on_curve if rising or law == "curve" else (curve.max() if alpha < 0 else curve.min())
        assert out[slip.OUT["fy_r"]] == pytest.approx(expected, rel=1e-4, abs=1e-3), (slip_deg, law)


def test_patch_slip_inverts_the_steady_curve(rider_bike, t03):
    """Set the carcass force to the steady curve at a chosen slip: the block's patch slip is that slip (on
    the rising branch), to 1e-9 rad (the closed form's conditioning near the peak), with the measured
    offsets and a lean."""
    params = slip.model_parameters(rider_bike, t03, t03)
    ss = steady.steady_state(params, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    x = ss.x.copy()
    x[slip.X["q4"]] = 0.1
    x = slip.solve_pitch(rhs, x)
    _, out = rhs.outputs(0.0, x)
    camber, fz = out[slip.OUT["camber_r"]], out[slip.OUT["fz_r"]]
    for slip_deg in (-8.0, -4.0, -1.0, 0.0, 0.3, 2.0, 6.0, 8.0):
        a = np.radians(slip_deg)
        xs = x.copy()
        xs[slip.X["carcass_y_r"]] = float(t03.lateral_force(a, camber, fz)) / ss.params["ccr"]
        assert rhs.outputs(0.0, xs)[1][slip.OUT["patch_slip_r"]] == pytest.approx(a, abs=1e-9), slip_deg


def test_stiffness_is_the_cornering_stiffness_over_the_relaxation_length(base, t03):
    """c = C_Fa(F_z0)/sigma0 at each wheel's load in the steady motion the run starts from (summary.json),
    against the tyre library's own cornering stiffness (NumPy, independent of the C), to 1e-9."""
    info = base.summary["tyres"]["carcass"]
    for wheel in ("rear", "front"):
        load = info[f"reference_load_{wheel}_n"]
        expected = float(t03.cornering_stiffness(load)) / t03.relaxation_length
        assert info[f"stiffness_{wheel}_n_per_m"] == pytest.approx(expected, rel=1e-9)
    # The static loads of the 635 N rider: about 635 and 360 N (the steady turn shifts them slightly).
    assert info["reference_load_rear_n"] == pytest.approx(635.0, abs=2.0)


def test_extrapolation_is_recorded(base):
    """Time beyond the measured slip (6 deg) and loads (343-488 N) after the kick, per tyre."""
    e = base.summary["tyres"]["extrapolation"]["rear"]
    assert e["measured"] == {"slip_deg": 6.0, "load_n": [343.0, 488.0]}
    # The rear tyre carries 635 N, above every measured load, throughout; its patch slides past 6 deg briefly.
    assert e["load_outside_s"] == pytest.approx(e["duration_s"], abs=0.01)
    assert 0.0 < e["patch_slip_beyond_s"] < 0.5 and e["max_abs_kinematic_slip_deg"] > 25.0
    assert e["max_abs_patch_slip_deg"] < 12.0     # the peak's slip (8.7 deg) and the plateau above it
    assert wk.results.extrapolation_line(base.summary).startswith("tyre fits extrapolated: rear: patch slip")


# ------------------------------------------------------------- small slip, numerics, options

def test_small_slip_eigenvalues_equal_the_force_lag(rider_bike, gains, t03):
    """Symmetric tyres, upright: linearised, the carcass force and moment are the thesis' force lag
    (F = c y with c = C_a/sigma0; the moment's slip found at the lagged camber), so every eigenvalue
    agrees to 1e-6 relative. Measured 3e-8 (the finite-difference Jacobians' own error)."""
    def eigenvalues(form):
        par = slip.model_parameters(rider_bike, t03, t03,
                                    slip.ModelOptions(symmetric_tyres=True, tyre_transient=form), gains=gains)
        ss = steady.steady_state(par, 3.0)
        return np.linalg.eigvals(slip.linearize(slip.CompiledRHS(ss.params), ss.x))

    ref, ev = eigenvalues("force_lag"), eigenvalues("carcass")
    big = np.abs(ref) > 1e-6
    matched = np.array([ev[np.argmin(np.abs(ev - r))] for r in ref[big]])
    assert np.max(np.abs(matched - ref[big]) / np.abs(ref[big])) < 1e-6


def test_sliding_viscosity_is_converged():
    """The 40 m/s^2 kick (the fastest sliding) with the default viscosity and a fifth of it (the smallest
    the scenario allows: stiffer still, LSODA stalls at the plate stop): every response peak and whole
    histories agree to 1e-3 (measured 1.6e-5)."""
    a = run(Scenario(pressure_kpa=400.0, fz_n=635.0, kick_accel=40.0))
    b = run(Scenario(pressure_kpa=400.0, fz_n=635.0, kick_accel=40.0, carcass_viscosity=0.001))
    for key, value in a.summary["peaks"].items():
        assert b.summary["peaks"][key] == pytest.approx(value, rel=1e-3), key
    for name in ("yaw_rate", "roll_rate", "steer_rate", "fy_rear"):
        x, y = a.trajectory[name].to_numpy(), b.trajectory[name].to_numpy()
        assert np.max(np.abs(x - y)) < 1e-3 * np.max(np.abs(x)), name


def test_carcass_damper_dissipates_and_the_balance_closes():
    """With a parallel damper the stored energy is still c y^2/2, the damper's dissipation d (dy/dt)^2 is
    an output (measured 2.9 J at 75 N s/m) and the balance closes (measured 2.4e-6 J)."""
    r = run(Scenario(pressure_kpa=400.0, fz_n=635.0, carcass_damping=75.0))
    df, info = r.trajectory, r.summary["tyres"]["carcass"]
    assert info["damping_n_s_per_m"] == 75.0
    damper = df["carcass_damper_dissipation"].to_numpy()
    assert damper[-1] > 1.0 and np.min(np.diff(damper)) >= -1e-12
    stored = 0.5 * info["stiffness_rear_n_per_m"] * df["carcass_deflection_rear"].to_numpy() ** 2
    np.testing.assert_allclose(df["carcass_energy_rear"], stored, rtol=0, atol=1e-5)
    assert np.max(np.abs(df[wk.results.BALANCE_COLUMN])) < 1e-5


@pytest.mark.parametrize(("law", "damping"), [("curve", 0.0), ("peak", 75.0), ("curve", 75.0)])
def test_options_agree_with_the_python_block(rider_bike, gains, t03, law, damping):
    """C against the independent Python block (:func:`whipple_kick.model.carcass.reference_block`) for the
    sliding laws and the damper, at 60 random states on and past the limit. Tolerance 1e-8 relative: two
    exact inversions of the curve near its peak agree to ~eps F / (dF/da)."""
    par = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(carcass_sliding=law, carcass_damping=damping),
                                gains=gains, kick=dict(t0=0.0, duration=0.15, displacement=0.15))
    ss = steady.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    p = slip.parameter_vector(ss.params)
    rng = np.random.default_rng(7)
    for _ in range(60):
        x = ss.x.copy()
        for name, spread in (("q4", 0.2), ("q7", 0.2), ("u2", 2.0), ("u3", 0.5), ("u4", 0.5), ("u7", 0.5),
                             ("carcass_y_r", 0.015), ("carcass_y_f", 0.015), ("camber_patch_r", 0.2),
                             ("camber_patch_f", 0.2)):
            x[slip.X[name]] += rng.uniform(-spread, spread)
        t = rng.uniform(-0.05, 0.2)
        dx_c, out_c = rhs.outputs(t, x)
        dx_n, out_n = slip_build.numpy_rhs(t, x, p, ss.params.model, with_outputs=True)
        np.testing.assert_allclose(dx_c, dx_n, rtol=1e-8, atol=1e-8 * np.abs(dx_n).max())
        np.testing.assert_allclose(out_c, out_n, rtol=1e-8, atol=1e-8 * np.abs(out_n).max())


def test_block_stays_finite_as_the_rolling_speed_vanishes(rider_bike, t03):
    """A wheel turned sideways (|vx| = 0) while sliding: finite rates, the camber lag stops, the force
    relaxes toward the limit on its side."""
    par = slip.model_parameters(rider_bike, t03, t03, slip.ModelOptions(symmetric_tyres=True))
    ss = steady.steady_state(par, 3.0)
    rhs = slip.CompiledRHS(ss.params)
    x = ss.x.copy()
    x[slip.X["u1"]], x[slip.X["u2"]] = 0.0, 0.8
    x[slip.X["carcass_y_r"]] = 0.005
    dx, out = rhs.outputs(0.0, x)
    assert np.all(np.isfinite(dx)) and abs(out[slip.OUT["vx_r"]]) < 1e-12
    assert dx[slip.X["camber_patch_r"]] == 0.0
    # Sliding right at 0.8 m/s with no rolling: the patch slides too, the deflection falls (force to the left).
    assert dx[slip.X["carcass_y_r"]] < 0.0


def test_ignorable_columns_of_the_jacobian_are_exactly_zero(runs):
    """The compiled Jacobian skips the ignorable coordinates' columns (q1, q2, q6, q8): a forward difference of
    the right-hand side in each of them, at states along the default run (kick, plate stop, recovery) and with
    the coordinates moved far, changes no derivative at all (exactly 0.0, not merely small)."""
    result = runs["default"]
    a = wk.assembly.assemble(result.scenario, wk.inputs.kick_of(result.scenario))
    rhs = slip.CompiledRHS(a.params)
    x0 = a.start.x
    for t, shift in ((0.05, 3.0), (0.151, -7.0), (0.3, 50.0)):
        x = x0.copy()
        x[slip.X["u4"]] += 0.3
        x[slip.X["carcass_y_r"]] += 0.004
        base = rhs(t, x)
        for name in slip.IGNORABLE:
            moved = x.copy()
            moved[slip.X[name]] += shift
            assert np.array_equal(rhs(t, moved), base), name
        jac = rhs.jacobian_function(np.ones(len(slip.STATE_NAMES)))(t, x)
        assert not np.any(jac[:, [slip.X[n] for n in slip.IGNORABLE]])
    # The default rider's model has no trunk and no delay filter: 21 dynamic states, 18 evaluations per Jacobian.
    assert rhs.layout is slip.layout.BASE and rhs.layout.key == "rigid"
    assert len(slip.DYNAMIC_STATES) + 1 - 4 == slip.JACOBIAN_EVALUATIONS == 18


def test_blended_pressure_rhs_is_unchanged_at_every_sample():
    """The blend's patch-slip solve returns at a converged Newton step instead of bisecting away from a root on
    its bracket's end: derivatives and outputs at every sample of a 350 kPa run (tests/data/blend, written by
    scripts/make_blend_reference.py before the change) agree to 1e-11 of each column's largest value (the
    solve's own tolerance is 1e-13 deg; measured 2.3e-13 at worst, at 250 of the 401 samples; the rest are
    bit for bit)."""
    import pathlib
    ref = np.load(pathlib.Path(__file__).resolve().parents[1] / "data" / "blend" / "rhs_350kPa_635N.npz")
    # Stored with the locked-hip model (its hip and delay filter's states frozen at 0): the rigid rider's model
    # has neither, so its states, outputs and parameters are read by name, and what it lacks must have been
    # frozen (locked hip, no upper-body mass, no delay, zero rates of the dropped states).
    p_old = dict(zip(ref["parameter_names"], ref["p"], strict=True))
    assert p_old["hip_locked"] == 1.0 and p_old["mt"] == 0.0 and p_old["reflex_delay"] == 0.0
    state = [list(ref["state_names"]).index(n) for n in slip.STATE_NAMES]
    dropped = [i for i, n in enumerate(ref["state_names"]) if n not in slip.X]
    assert sorted(ref["state_names"][dropped]) == sorted(("q11", "u11", *slip.REFLEX_STATES))
    assert not np.any(ref["x"][:, dropped]) and not np.any(ref["dx"][:, dropped])
    output = [list(ref["output_names"]).index(n) for n in slip.OUTPUT_NAMES]
    model = slip.Model(transient=wk.transient.transients()[int(p_old["tyre_transient"])])
    rhs = slip.CompiledRHS(slip.Parameters(model, {n: p_old[n] for n in slip.PARAMETER_NAMES}))
    assert rhs.p[slip.P["wr"]] == 0.5 and rhs.p[slip.P["wf"]] == 0.5   # the blend: 300 and 400 kPa, 1:1
    pairs = [rhs.outputs(t, x) for t, x in zip(ref["t"], ref["x"][:, state], strict=True)]
    for got, want in ((np.array([d for d, _ in pairs]), ref["dx"][:, state]),
                      (np.array([o for _, o in pairs]), ref["out"][:, output])):
        scale = np.maximum(np.abs(want).max(axis=0), 1e-300)
        assert np.max(np.abs(got - want) / scale) <= 1e-11
