"""The Magic Formula expressions and their sign mapping to the model.

The coefficient sets used here are read from the shipped tyre files (by
name), so the physics is checked on the data the simulation uses.
"""
import numpy as np
import pytest
import sympy as sm

from whipple_kick.library import tyres
from whipple_kick.model import magic_formula as mf

DEG = np.pi / 180.0
# Offsets (Sh: a9, a10; Sv: a12, a13) are the fit's zero-slip force at zero
# camber (conicity/ply-steer or rig misalignment); removing them isolates the
# slip and camber physics.
FY_OFFSET_INDICES = (9, 10, 12, 13)
MZ_OFFSET_INDICES = (12, 13, 16, 17)


def _all_sets():
    """(label, fy, mz) for every physically consistent shipped set (T02 excluded)."""
    out = []
    for name, _, sets in tyres.available():
        if name == "T02":  # its Table 7.9 columns are known to be inconsistent
            continue
        data = tyres.read_tyre_file(tyres.TYRE_DIR / f"{name}.toml")
        for set_name in sets:
            for pressure, (fy, mz) in data.sets[set_name].items():
                out.append((f"{name}-{set_name}-{pressure:g}", fy, mz))
    return out


SETS = _all_sets()
MZ_SETS = [s for s in SETS if s[2] is not None]


def _without(coefficients, indices):
    out = np.array(coefficients, dtype=float)
    out[list(indices)] = 0.0
    return out


# Loads: the thesis' measured range (343-526 N) and the Chapter 8 loads up to
# 700 N. Slip up to 30 deg covers the kick (the thesis plots +-10 deg). Below
# ~300 N some Table 7.9 sets extrapolate E = a6*Fz + a7 far above 1 and the
# force reverses; docs/tyres.md lists those limits.
LOADS = np.array([343.0, 404.0, 488.0, 526.0, 600.0, 700.0])
SLIPS = np.linspace(0.25, 30.0, 120) * DEG


@pytest.mark.parametrize("label, fy, mz", SETS, ids=[s[0] for s in SETS])
def test_force_opposes_sliding(label, fy, mz):
    """A sliding tyre's force opposes its lateral sliding: F_y * slip < 0."""
    a = _without(fy, FY_OFFSET_INDICES)
    slip = np.concatenate([-SLIPS, SLIPS])[:, None]
    force = mf.lateral_force_numpy(slip, 0.0, LOADS[None, :], a)
    assert np.all(force * slip < 0)


@pytest.mark.parametrize("label, fy, mz", SETS, ids=[s[0] for s in SETS])
def test_camber_thrust_toward_the_lean(label, fy, mz):
    """Zero slip, wheel top leaning right (camber > 0): pushed right (F_y > 0).

    With the offsets kept, the camber part F(+c) - F(-c) must still point
    toward the lean.
    """
    camber = np.array([1.0, 2.0, 5.0])[:, None] * DEG
    clean = _without(fy, FY_OFFSET_INDICES)
    assert np.all(mf.lateral_force_numpy(0.0, camber, LOADS, clean) > 0)
    assert np.all(mf.lateral_force_numpy(0.0, -camber, LOADS, clean) < 0)
    both = mf.lateral_force_numpy(0.0, camber, LOADS, fy) - mf.lateral_force_numpy(0.0, -camber, LOADS, fy)
    assert np.all(both > 0)


@pytest.mark.parametrize("label, fy, mz", MZ_SETS, ids=[s[0] for s in MZ_SETS])
def test_moment_aligns_wheel_with_velocity(label, fy, mz):
    """At small slip M_z (about z down) has the sign of slip: it turns the
    heading toward the contact's velocity. Checked at the loads the M_z fits
    cover (Chapter 8: 500-700 N, the rig: 343-526 N).
    """
    c = _without(mz, MZ_OFFSET_INDICES)
    slip = np.array([-1.0, -0.5, -0.1, 0.1, 0.5, 1.0])[:, None] * DEG
    moment = mf.aligning_moment_numpy(slip, 0.0, LOADS[None, :], c)
    assert np.all(moment * slip > 0)


@pytest.mark.parametrize("label, fy, mz", SETS, ids=[s[0] for s in SETS])
def test_odd_symmetry_without_offsets(label, fy, mz):
    """With Sh and Sv offsets removed, F_y(-s, -c) = -F_y(s, c), same for M_z.

    Tolerance 1e-9 relative: both sides are the same double-precision
    expression evaluated at mirrored inputs.
    """
    slip = np.linspace(-20, 20, 41)[:, None] * DEG
    camber = np.array([-5.0, 0.0, 5.0])[None, :] * DEG
    a = _without(fy, FY_OFFSET_INDICES)
    f = mf.lateral_force_numpy(slip, camber, 600.0, a)
    np.testing.assert_allclose(mf.lateral_force_numpy(-slip, -camber, 600.0, a), -f, rtol=1e-9, atol=1e-9)
    if mz is not None:
        c = _without(mz, MZ_OFFSET_INDICES)
        m = mf.aligning_moment_numpy(slip, camber, 600.0, c)
        np.testing.assert_allclose(mf.aligning_moment_numpy(-slip, -camber, 600.0, c), -m,
                                   rtol=1e-9, atol=1e-9)


def test_model_is_the_formula_with_the_documented_mapping():
    """F_y,model(s, c) = -F_y,formula(+s deg, -c deg, Fz kN), M_z likewise."""
    _, fy, mz = next(s for s in MZ_SETS if s[0] == "T03-chapter8-400")
    s, c, f = 0.05, 0.03, 620.0
    deg = 180.0 / np.pi
    assert float(mf.lateral_force_model(s, c, f, fy)) == pytest.approx(
        -float(mf.lateral_force_formula(s * deg, -c * deg, f / 1000, fy)), rel=1e-12)
    assert float(mf.aligning_moment_model(s, c, f, mz)) == pytest.approx(
        -float(mf.aligning_moment_formula(s * deg, -c * deg, f / 1000, mz)), rel=1e-12)


def test_unloaded_tyre_is_exactly_zero_and_prints_a_ternary():
    _, fy, mz = next(s for s in MZ_SETS if s[0] == "T03-table7_9-400")
    slip, camber, fz = sm.symbols("slip camber fz")
    expr = mf.lateral_force_model(slip, camber, fz, fy)
    assert isinstance(expr, sm.Piecewise)
    assert "((fz > 0) ?" in sm.ccode(expr)
    assert mf.lateral_force_model(0.1, 0.05, 0, fy) == 0
    assert mf.aligning_moment_model(0.1, 0.05, -5.0, mz) == 0
    with np.errstate(all="raise"):  # the NumPy path must silence its own 0/0
        force = mf.lateral_force_numpy([0.1, 0.1, 0.1], 0.05, [-10.0, 0.0, 500.0], fy)
        moment = mf.aligning_moment_numpy([0.1, 0.1, 0.1], 0.05, [-10.0, 0.0, 500.0], mz)
    assert force[0] == 0.0 and force[1] == 0.0 and force[2] != 0.0
    assert moment[0] == 0.0 and moment[1] == 0.0 and np.isfinite(moment[2])


@pytest.mark.parametrize("label, fy, mz", SETS, ids=[s[0] for s in SETS])
def test_force_and_moment_vanish_with_the_load(label, fy, mz):
    """A tyre whose load tends to zero carries a force and moment that tend to zero (no jump at
    lift-off): below OFFSET_FADE_LOAD the fits' load-independent shifts a13 and c17 fade out, so
    |F_y| and |M_z| are bounded by a constant times the load. Measured over +-90 deg of slip,
    +-45 deg of camber and 1e-6..99 N: |F_y| <= 2.33 Fz, |M_z| <= 0.019 m x Fz; without the fade the
    sets' a13 (up to 46 N) would stay as Fz -> 0."""
    fz = np.geomspace(1e-6, 0.99 * mf.OFFSET_FADE_LOAD, 40)[None, None, :]
    slip = np.radians(np.linspace(-90.0, 90.0, 91))[:, None, None]
    camber = np.radians(np.linspace(-45.0, 45.0, 19))[None, :, None]
    assert np.all(np.abs(mf.lateral_force_numpy(slip, camber, fz, fy)) <= 2.5 * fz)
    if mz is not None:
        assert np.all(np.abs(mf.aligning_moment_numpy(slip, camber, fz, mz)) <= 0.025 * fz)


@pytest.mark.parametrize("label, fy, mz", MZ_SETS, ids=[s[0] for s in MZ_SETS])
def test_the_fade_leaves_the_fitted_range_untouched(label, fy, mz):
    """From OFFSET_FADE_LOAD up the model curves are the fitted formula exactly (the fits hold from
    343 N, thesis Chapter 7); below it only the constant shifts a13 and c17 are weighted."""
    deg = 180.0 / np.pi
    for f in (mf.OFFSET_FADE_LOAD, 343.0, 635.0):
        for s, c in ((0.05, 0.03), (-0.4, -0.2)):
            # The same expression up to SymPy's order of evaluation (round-off).
            assert float(mf.lateral_force_model(s, c, f, fy)) == pytest.approx(-float(
                mf.lateral_force_formula(s * deg, -c * deg, f / 1000, fy)), rel=1e-12)
            assert float(mf.aligning_moment_model(s, c, f, mz)) == pytest.approx(-float(
                mf.aligning_moment_formula(s * deg, -c * deg, f / 1000, mz)), rel=1e-12)
    half = 0.5 * mf.OFFSET_FADE_LOAD          # smoothstep weight 1/2
    moved = np.array(fy, dtype=float)
    moved[13] *= 0.5
    assert float(mf.lateral_force_model(0.05, 0.03, half, fy)) == pytest.approx(
        -float(mf.lateral_force_formula(0.05 * deg, -0.03 * deg, half / 1000, moved)), rel=1e-12)


def test_numpy_matches_sympy():
    """The lambdified functions evaluate the same expression (rel 1e-12)."""
    _, fy, mz = next(s for s in MZ_SETS if s[0] == "T03-chapter8-500")
    for s, c, f in [(0.02, 0.0, 500.0), (-0.15, 0.08, 700.0), (0.3, -0.05, 350.0)]:
        assert mf.lateral_force_numpy(s, c, f, fy, 1.3) == pytest.approx(
            float(mf.lateral_force_model(s, c, f, fy, 1.3)), rel=1e-12)
        assert mf.aligning_moment_numpy(s, c, f, mz, 1.3) == pytest.approx(
            float(mf.aligning_moment_model(s, c, f, mz, 1.3)), rel=1e-12)


def test_cornering_stiffness_is_minus_the_slope():
    """Symbolic C_alpha equals a central finite difference of -F_y (rel 1e-6:
    the difference step 1e-6 rad has O(h^2) error far below that)."""
    _, fy, _ = next(s for s in SETS if s[0] == "T05-table7_9-300")
    h = 1e-6
    for fz in (343.0, 600.0):
        slope = (mf.lateral_force_numpy(h, 0.0, fz, fy) - mf.lateral_force_numpy(-h, 0.0, fz, fy)) / (2 * h)
        assert mf.cornering_stiffness_numpy(fz, fy) == pytest.approx(-slope, rel=1e-6)
    assert mf.cornering_stiffness_numpy(0.0, fy) == 0.0


def test_friction_scale_keeps_stiffness_and_moves_the_limit():
    """k scales the peak by k and keeps the small-slip stiffness.

    The slope at alpha = 0 is taken at x = Sh, not at the curve centre, so it
    changes by O(Sh^2): the tolerance 0.5 % covers that for the thesis data
    (|Sh| < 0.15 deg); with the offsets removed it is exact (rel 1e-12).
    """
    k = 1.03 / 0.79
    for _, fy, _ in SETS:
        fz = np.array([343.0, 600.0])
        np.testing.assert_allclose(mf.cornering_stiffness_numpy(fz, fy, k),
                                   mf.cornering_stiffness_numpy(fz, fy), rtol=5e-3)
        clean = _without(fy, FY_OFFSET_INDICES)
        np.testing.assert_allclose(mf.cornering_stiffness_numpy(fz, clean, k),
                                   mf.cornering_stiffness_numpy(fz, clean), rtol=1e-12)
        factors = mf.lateral_force_factors_numpy(0.0, fz, fy, k)
        plain = mf.lateral_force_factors_numpy(0.0, fz, fy)
        np.testing.assert_allclose(factors["D"], k * plain["D"], rtol=1e-12)
        np.testing.assert_allclose(factors["B"], plain["B"] / k, rtol=1e-12)
        np.testing.assert_allclose(factors["Sv"], plain["Sv"], rtol=1e-12)


def test_wrong_coefficient_count_is_refused():
    with pytest.raises(ValueError, match="14"):
        mf.lateral_force_formula(1.0, 0.0, 0.5, [1.0] * 13)
    with pytest.raises(ValueError, match="18"):
        mf.aligning_moment_model(0.1, 0.0, 500.0, [1.0] * 14)


@pytest.mark.parametrize("label, fy, mz", MZ_SETS, ids=[s[0] for s in MZ_SETS])
def test_reversed_camber_coefficients_are_the_curve_at_the_opposite_camber(label, fy, mz):
    """Negating the five odd camber coefficients (a8, a11; c11, c14, c15) equals evaluating at -camber,
    for every slip, camber and load (measured: bit for bit equal, -gamma enters only through these terms
    and |gamma|; asserted to 1e-12 relative); and with them
    a leaning wheel's camber thrust points away from the lean (the authors' published code)."""
    rng = np.random.default_rng(7)
    slip, camber = rng.uniform(-0.6, 0.6, 200), rng.uniform(-0.5, 0.5, 200)
    fz = rng.uniform(100.0, 1000.0, 200)
    fy_rev, mz_rev = mf.camber_reversed(fy, "fy"), mf.camber_reversed(mz, "mz")
    assert np.count_nonzero(fy_rev != fy) + np.count_nonzero(mz_rev != mz) == 5
    np.testing.assert_allclose(mf.lateral_force_numpy(slip, camber, fz, fy_rev),
                               mf.lateral_force_numpy(slip, -camber, fz, fy), rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(mf.aligning_moment_numpy(slip, camber, fz, mz_rev),
                               mf.aligning_moment_numpy(slip, -camber, fz, mz), rtol=1e-12, atol=1e-11)
    clean = mf.camber_reversed(_without(fy, FY_OFFSET_INDICES), "fy")
    assert np.all(mf.lateral_force_numpy(0.0, np.array([1.0, 5.0])[:, None] * DEG, LOADS, clean) < 0)
    np.testing.assert_array_equal(mf.camber_reversed(fy_rev, "fy"), fy)
    with pytest.raises(ValueError, match="14"):
        mf.camber_reversed(fy[:13], "fy")
