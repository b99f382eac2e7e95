"""The reflex delay's Pade filter against the algebra, the C code and the exact delayed system."""
import ctypes
import decimal
from fractions import Fraction
import math
import subprocess

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.signal import argrelextrema

from whipple_kick.model import reflex

TAU = 0.04  # s, a human reflex delay


# --- Pade coefficients -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("L, M, num, den", [
    (1, 1, [2, -1], [2, 1]),                               # (1 - x/2)/(1 + x/2)
    (2, 2, [12, -6, 1], [12, 6, 1]),                       # (1 - x/2 + x^2/12)/(1 + x/2 + x^2/12)
    (3, 4, [840, -360, 60, -4], [840, 480, 120, 16, 1]),
])
def test_pade_coefficients_hand_values(L, M, num, den):
    N, D = reflex.pade_coefficients(L, M)
    assert N.tolist() == num and D.tolist() == den  # exact: computed in rationals, rounded once
    assert D[-1] == 1.0
    assert N[0] / D[0] == 1.0  # DC gain exactly 1
    assert np.all(np.roots(D[::-1]).real < 0.0)


@pytest.mark.parametrize("L, M", [(1, 1), (2, 2), (3, 4), (0, 3), (2, 1)])
def test_pade_matches_exp_to_order_L_plus_M(L, M):
    # The error of (3, 4) at x = 0.01 is ~1e-22, below double precision, so evaluate in 60-digit decimals.
    # These coefficients are small integers and halves, exact in binary, so nothing is lost converting them.
    N, D = reflex.pade_coefficients(L, M)
    with decimal.localcontext() as ctx:
        ctx.prec = 60
        poly = lambda c, v: sum(decimal.Decimal(float(ci)) * v**i for i, ci in enumerate(c))
        err = lambda v: float(poly(N, v) / poly(D, v) - (-v).exp())
        x = decimal.Decimal("0.02")
        # Halving x divides an O(x^(L+M+1)) error by 2^(L+M+1) (measured 0.982-0.993 of it here,
        # the next order's O(x) correction).
        assert err(x) / err(x / 2) == pytest.approx(2.0 ** (L + M + 1), rel=0.02)
        # The leading term is the classical one for exp(x) (Baker & Graves-Morris, ch. 1) with x -> -x:
        # N/D - exp(-x) = (-1)^L L! M! / ((L+M)! (L+M+1)!) x^(L+M+1) + ...  ((1, 1): -x^3/12).
        f = math.factorial
        lead = (-1) ** L * f(L) * f(M) / (f(L + M) * f(L + M + 1)) * 0.01 ** (L + M + 1)
        assert err(x / 2) == pytest.approx(lead, rel=0.02)
    # In double precision, at x where the error is well above round-off, the same order shows (measured
    # 0.84-0.93 of 2^(L+M+1) at x = 0.2: the O(x) correction is larger there).
    err64 = lambda v: np.polynomial.polynomial.polyval(v, N) / np.polynomial.polynomial.polyval(v, D) - math.exp(-v)
    assert err64(0.2) / err64(0.1) == pytest.approx(2.0 ** (L + M + 1), rel=0.2)


@pytest.mark.parametrize("tau", [TAU, 0.137, 0.5, 1.0])
def test_pade_is_python_controls(tau):
    """The filter is python-control's ``control.pade(tau, 4, numdeg=3)`` (in s, descending powers, monic).

    Measured: equal to 2.5e-16 relative (1 ulp) at every tau; not bit for bit, because control.pade builds
    its coefficients by a floating-point recursion (840.0000000000001 at tau = 1) where ours are the exact
    rationals rounded once (840). So the project keeps its own derivation: the compiled C model's
    literals stay exact, and no run imports python-control (over a second). Bound 4 ulp.
    """
    control = pytest.importorskip("control", reason="python-control is the oracle")
    num, den = control.pade(tau, reflex.ORDER, numdeg=reflex.NUMERATOR_DEGREE)
    N, D = reflex.pade_coefficients(reflex.NUMERATOR_DEGREE, reflex.ORDER)
    # Ours are in x = s tau, ascending: the coefficient of s^j is N_j tau^j; divide by tau^4 to make D monic in s.
    ours_num = [N[j] * tau ** (j - reflex.ORDER) for j in range(reflex.NUMERATOR_DEGREE, -1, -1)]
    ours_den = [D[j] * tau ** (j - reflex.ORDER) for j in range(reflex.ORDER, -1, -1)]
    np.testing.assert_allclose(ours_num, num, rtol=4 * np.finfo(float).eps, atol=0)
    np.testing.assert_allclose(ours_den, den, rtol=4 * np.finfo(float).eps, atol=0)


def test_interface_constants():
    assert reflex.ORDER == 4 and reflex.NUMERATOR_DEGREE == 3
    assert reflex.STATE_NAMES == ("reflex_1", "reflex_2", "reflex_3", "reflex_4")
    with pytest.raises(ValueError, match="non-negative"):
        reflex.pade_coefficients(-1, 2)


# --- realisation -------------------------------------------------------------------------------------------------

def _transfer(theta):
    """C (i theta I - A)^-1 B of the realisation, theta = omega tau."""
    A, B, C = reflex.realisation()
    return np.array([C @ np.linalg.solve(1j * th * np.eye(reflex.ORDER) - A, B) for th in np.atleast_1d(theta)])


def test_realisation_is_the_3_4_approximant():
    A, B, C = reflex.realisation()
    assert A.shape == (4, 4) and B.shape == (4,) and C.shape == (4,)
    N, D = reflex.pade_coefficients(3, 4)
    theta = np.linspace(0.0, 5.0, 11)
    s = 1j * theta
    expected = np.polynomial.polynomial.polyval(s, N) / np.polynomial.polynomial.polyval(s, D)
    np.testing.assert_allclose(_transfer(theta), expected, rtol=1e-13, atol=1e-15)
    assert np.all(np.linalg.eigvals(A).real < 0.0)


def test_no_feedthrough_and_the_steady_state():
    # A step in r from rest: output 0 at once, then it first dips (the approximant's zeros are in the right half
    # plane, as a delay's must be), with slope C B / tau = -4/tau.
    z0 = reflex.steady_state(0.0, TAU)
    assert reflex.output(z0, 1.0, TAU) == 0.0
    _, B, C = reflex.realisation()
    assert C @ reflex.rates(z0, 1.0, TAU) == pytest.approx(C @ B / TAU) and C @ B == -4.0
    for r in (1.0, -2.5, 1e3):
        z = reflex.steady_state(r, TAU)
        np.testing.assert_array_equal(reflex.rates(z, r, TAU), 0.0)
        assert reflex.output(z, r, TAU) == r


def test_step_response_is_a_delayed_step():
    A, B, C = reflex.realisation()
    sol = solve_ivp(lambda t, z: reflex.rates(z, 1.0, TAU), (0.0, 4 * TAU), reflex.steady_state(0.0, TAU),
                    method="LSODA", rtol=1e-10, atol=1e-14, dense_output=True)
    t = np.linspace(0.0, 4 * TAU, 801)
    y = C @ sol.sol(t)
    # Measured: undershoot -0.169 at t = 0.56 tau (the torque first goes the wrong way), half-way at
    # t = 0.966 tau, overshoot 1.031 at t = 1.53 tau, 1 + 7e-6 at 4 tau.
    assert -0.18 < y.min() < -0.16
    half = t[np.argmax(y > 0.5)]
    assert half == pytest.approx(0.966 * TAU, rel=0.005)
    assert 1.02 < y.max() < 1.04
    assert y[-1] == pytest.approx(1.0, abs=1e-4)


# --- tau = 0: no delay -------------------------------------------------------------------------------------------

def test_zero_delay_passes_the_input_through():
    z = np.array([0.3, -1.0, 2.0, 7.0])
    assert reflex.output(z, 1.25, 0.0) == 1.25
    np.testing.assert_array_equal(reflex.rates(z, 1.25, 0.0), np.zeros(4))
    np.testing.assert_array_equal(reflex.steady_state(1.25, 0.0), np.zeros(4))
    t = np.linspace(-1.0, 1.0, 9)
    np.testing.assert_allclose(reflex.delayed_decay_reference(3.0, 0.0, t), np.where(t > 0, np.exp(-3.0 * t), 1.0))
    with pytest.raises(ValueError, match="tau"):
        reflex.rates(z, 1.0, -0.01)


# --- the C code --------------------------------------------------------------------------------------------------

_WRAPPER = """
void wk_test_rates(double tau, const double *z, double r, double *dz) { wk_reflex_rates(tau, z, r, dz); }
double wk_test_output(double tau, const double *z, double r) { return wk_reflex_output(tau, z, r); }
"""


def test_c_source_matches_numpy(tmp_path):
    src = tmp_path / "reflex_test.c"
    src.write_text(reflex.c_source() + _WRAPPER)
    lib_path = tmp_path / "reflex_test.so"
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-Wall", "-Werror", "-o", str(lib_path), str(src)],
                   check=True, capture_output=True)
    lib = ctypes.CDLL(str(lib_path))
    vec = ctypes.POINTER(ctypes.c_double)
    lib.wk_test_rates.argtypes = [ctypes.c_double, vec, ctypes.c_double, vec]
    lib.wk_test_rates.restype = None
    lib.wk_test_output.argtypes = [ctypes.c_double, vec, ctypes.c_double]
    lib.wk_test_output.restype = ctypes.c_double

    rng = np.random.default_rng(23)
    for i in range(200):
        tau = 0.0 if i % 10 == 0 else rng.uniform(0.005, 0.2)
        z = rng.normal(size=4) * 10.0 ** rng.uniform(-4, 2, size=4)
        r = rng.normal() * 10.0 ** rng.uniform(-2, 3)
        dz = np.zeros(4)
        lib.wk_test_rates(tau, z.ctypes.data_as(vec), r, dz.ctypes.data_as(vec))
        y = lib.wk_test_output(tau, z.ctypes.data_as(vec), r)
        # Relative to the size of the terms summed, so a cancelling sum is not held to more than round-off.
        A, B, C = reflex.realisation()
        scale_dz = (np.abs(A) @ np.abs(z) + np.abs(B * r)) / tau if tau else np.zeros(4)
        scale_y = np.abs(C) @ np.abs(z) if tau else abs(r)
        assert np.all(np.abs(dz - reflex.rates(z, r, tau)) <= 1e-14 * scale_dz)
        assert abs(y - reflex.output(z, r, tau)) <= 1e-14 * scale_y


def test_c_source_prints_full_precision_literals():
    text = reflex.c_source()
    assert "static void wk_reflex_rates(double tau, const double *z, double r, double *dz)" in text
    assert "static double wk_reflex_output(double tau, const double *z, double r)" in text
    for value in (840.0, 480.0, 120.0, 16.0, -360.0, 60.0, -4.0):
        assert f"({value!r})" in text


# --- the exact delayed system ------------------------------------------------------------------------------------

def _closed_form(k, tau, t):
    """sum_{j=0}^{floor(t/tau)+1} (-k)^j (t - (j-1) tau)^j / j!, in exact rationals."""
    if t <= 0:
        return Fraction(1)
    n = math.floor(t / tau)
    return sum((-k) ** j * (t - (j - 1) * tau) ** j / math.factorial(j) for j in range(n + 2))


@pytest.mark.parametrize("ktau", ["3/10", "6/5", "17/10"])
def test_reference_is_the_classical_closed_form(ktau):
    tau = Fraction(1, 25)
    k = Fraction(ktau) / tau
    times = [Fraction(i, 400) for i in range(-8, 161, 3)]  # -0.02 s to 0.4 s = 10 tau, knots included
    exact = np.array([float(_closed_form(k, tau, t)) for t in times])
    got = reflex.delayed_decay_reference(float(k), float(tau), np.array([float(t) for t in times]))
    np.testing.assert_allclose(got, exact, rtol=0, atol=1e-13 * max(1.0, np.abs(exact).max()))


def test_reference_solves_the_delay_equation():
    k, tau = 1.2 / TAU, TAU
    t = np.linspace(0.013, 40 * tau, 3001)  # off the knots, out to k t = 48 where the closed form has lost all digits
    h = 1e-6
    x = lambda v: reflex.delayed_decay_reference(k, tau, v)
    dxdt = (x(t + h) - x(t - h)) / (2 * h)
    np.testing.assert_allclose(dxdt, -k * x(t - tau), rtol=0, atol=1e-6 * k)
    knots = tau * np.arange(1, 40)
    np.testing.assert_allclose(x(knots - 1e-12), x(knots + 1e-12), atol=1e-9)  # continuous at the knots


def _pade_loop(ktau, n_tau):
    """dx/dt = -k y, y the filter's output with r = x, from x = 1 and the filter at rest for r = 1."""
    k = ktau / TAU

    def rhs(t, state):
        x, z = state[0], state[1:]
        return np.concatenate([[-k * reflex.output(z, x, TAU)], reflex.rates(z, x, TAU)])

    t = np.linspace(0.0, n_tau * TAU, 200 * n_tau + 1)
    y0 = np.concatenate([[1.0], reflex.steady_state(1.0, TAU)])
    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method="LSODA", rtol=1e-10, atol=1e-12, t_eval=t)
    assert sol.success
    return t, sol.y[0], reflex.delayed_decay_reference(k, TAU, t)


# The bound is the Pade approximation's error, not the integrator's: tightening LSODA to rtol 1e-12 moves the
# loop's solution by < 5e-8. The error peaks at t ~ 0.9 tau, where the exact solution's first kink (x' jumps from
# 0 to -k at t = 0) has been smoothed by the filter. Measured max |x_pade - x_exact| over 10 tau, x(0) = 1:
#   k tau = 0.3: 3.46e-4,   0.8: 2.47e-3,   1.2: 5.57e-3   (1.7: 1.12e-2);  the bounds are ~2x these.
@pytest.mark.parametrize("ktau, bound", [(0.3, 7e-4), (0.8, 5e-3), (1.2, 1.1e-2)])
def test_pade_loop_follows_the_delay_equation(ktau, bound):
    t, x, exact = _pade_loop(ktau, 10)
    err = np.abs(x - exact)
    assert err.max() < bound
    assert err.max() > bound / 4  # the bound is the approximation's, not slack: a sharper filter should lower it
    # Past the first few delays the smooth parts agree far better than the peak error.
    assert err[t > 5 * TAU].max() < bound / 5


def _peaks(v):
    return np.abs(v)[argrelextrema(np.abs(v), np.greater)[0]]


def test_decay_below_and_growth_above_pi_over_2():
    # k tau = 1.2 < pi/2: successive peaks of |x| shrink by ~0.66 each half period, in both systems.
    _, x, exact = _pade_loop(1.2, 30)
    for v in (x, exact):
        p = _peaks(v)
        assert len(p) >= 10 and np.all(np.diff(p) < 0) and p[-1] < 0.01
    # k tau = 1.7 > pi/2: they grow by ~1.12 each half period.
    _, x, exact = _pade_loop(1.7, 30)
    for v in (x, exact):
        p = _peaks(v)
        assert len(p) >= 10 and np.all(np.diff(p) > 0) and p[-1] > 5.0


def _closed_loop_growth(ktau):
    """Largest real part of the Pade loop's eigenvalues, times tau."""
    A, B, C = reflex.realisation()
    k = ktau / TAU
    M = np.zeros((5, 5))
    M[0, 1:] = -k * C
    M[1:, 0] = B / TAU
    M[1:, 1:] = A / TAU
    return np.linalg.eigvals(M).real.max() * TAU


def test_pade_loop_stability_boundary_is_pi_over_2():
    # The exact DDE x' = -k x(t - tau) is stable for k tau < pi/2. Measured Pade loop boundary:
    # k tau = 1.5708384 (relative error +2.68e-5: slightly more stable than the exact delay).
    assert _closed_loop_growth(1.2) < 0.0 < _closed_loop_growth(1.7)
    boundary = brentq(_closed_loop_growth, 1.2, 1.7, xtol=1e-13)
    assert abs(boundary - np.pi / 2) / (np.pi / 2) < 6e-5


# --- frequency response ------------------------------------------------------------------------------------------

def test_frequency_response_against_the_pure_delay():
    # A (3, 4) approximant is not all-pass: its gain falls below 1 and its phase lags slightly less than
    # omega tau. Measured at omega tau = 0.5 / 1 / pi/2 / 2:
    #   gain - 1:           -2.74e-9 / -6.80e-7 / -2.37e-5 / -1.54e-4
    #   phase + omega tau:  +1.74e-10 / +8.72e-8 / +4.84e-6 / +4.05e-5 rad
    # both growing monotonically with omega tau; the bounds are ~2x the values at omega tau = 2.
    theta = np.linspace(0.0, 2.0, 2001)
    H = _transfer(theta)
    gain_error = np.abs(H) - 1.0
    phase_error = np.unwrap(np.angle(H)) + theta
    assert np.all(gain_error <= 1e-15) and np.abs(gain_error).max() < 3.1e-4
    assert np.abs(gain_error).max() > 1e-4  # not all-pass, unlike the (4, 4) approximant
    assert np.all(phase_error >= -1e-15) and np.abs(phase_error).max() < 8.1e-5
    assert np.all(np.diff(np.abs(gain_error)) >= -1e-15) and np.all(np.diff(phase_error) >= -1e-15)
