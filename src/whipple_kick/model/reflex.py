"""Time delay of the rider's reflex feedback: a Pade filter for exp(-s tau).

The undelayed reflex signal r(t) (a steer torque) passes through a linear
filter that approximates the pure delay exp(-s tau); the filter's output
y(t) ~ r(t - tau) is the torque applied to the bicycle. The filter is the
strictly proper Pade approximant of degree (3, 4) of exp(-x), x = s tau::

    exp(-x) ~ N(x)/D(x) = (840 - 360 x + 60 x^2 - 4 x^3) / (840 + 480 x + 120 x^2 + 16 x^3 + x^4)

Strictly proper means no instantaneous feedthrough: a step in r gives an
output that starts at 0 (the diagonal (4, 4) approximant passes a step
through at once, which defeats a reflex delay). The price is that its gain
is not exactly 1 at all frequencies; see the tests for the measured gain
and phase errors and the error of a delayed loop against the exact delay
differential equation.

The coefficients come from the explicit Pade formula for exp(-x) with
numerator degree L and denominator degree M (G. A. Baker and
P. Graves-Morris, *Pade Approximants*, 2nd ed., Cambridge University Press
1996, ch. 1; G. H. Golub and C. F. Van Loan, *Matrix Computations*,
4th ed., 2013, on the matrix exponential)::

    N(x) = sum_j (L+M-j)! L! / ((L+M)! j! (L-j)!) (-x)^j,   j = 0..L
    D(x) = sum_j (L+M-j)! M! / ((L+M)! j! (M-j)!)   x^j,   j = 0..M

N/D agrees with exp(-x) to order x^(L+M). :func:`pade_coefficients`
returns them with D made monic. They are python-control's
``control.pade(tau, 4, numdeg=3)`` to 1 ulp (``tests/model/test_reflex.py``);
the exact rationals are kept here because control's recursion rounds them
(840.0000000000001 for 840), and so that no run imports python-control.

The filter's states (:data:`STATE_NAMES`) are those of the controllable
canonical form of :func:`realisation` in scaled time t' = t/tau; in real
time dz/dt = (A z + B r)/tau (:func:`rates`) and y = C z
(:func:`output`). With tau = 0 the delay is off: y = r and the states are
frozen. :func:`c_source` gives the same two functions in C for the
compiled model, and :func:`delayed_decay_reference` the exact solution of
dx/dt = -k x(t - tau), against which the tests check the filter in a loop.
"""
from fractions import Fraction
import math

import numpy as np

#: Number of filter states (denominator degree M of the Pade approximant).
ORDER = 4
#: Numerator degree L: one less than :data:`ORDER`, so there is no feedthrough.
NUMERATOR_DEGREE = 3
#: Names of the filter states, in the order of :func:`realisation`'s z.
STATE_NAMES = ("reflex_1", "reflex_2", "reflex_3", "reflex_4")


def pade_coefficients(L, M):
    """Pade approximant of degree (L, M) of exp(-x).

    Parameters
    ----------
    L, M : int
        Numerator and denominator degrees (non-negative).

    Returns
    -------
    numerator, denominator : numpy.ndarray
        Coefficients in ascending powers of x (lengths L+1 and M+1), scaled
        so that the denominator is monic (its x^M coefficient is 1). The
        constant terms are equal, so N(0)/D(0) = 1.
    """
    L, M = int(L), int(M)
    if L < 0 or M < 0:
        raise ValueError(f"Pade degrees must be non-negative, got L={L}, M={M}")
    f = math.factorial
    total = f(L + M)
    # Exact rationals, rounded once: the (3, 4) coefficients are then the integers 840, -360, ... exactly.
    num = [Fraction(f(L + M - j) * f(L), total * f(j) * f(L - j)) * (-1) ** j for j in range(L + 1)]
    den = [Fraction(f(L + M - j) * f(M), total * f(j) * f(M - j)) for j in range(M + 1)]
    lead = den[-1]
    return np.array([float(c / lead) for c in num]), np.array([float(c / lead) for c in den])


_NUM, _DEN = pade_coefficients(NUMERATOR_DEGREE, ORDER)


def realisation():
    """State-space form of the (3, 4) approximant in scaled time t' = t/tau.

    Controllable canonical form of N(x)/D(x) with D(x) = x^4 + a3 x^3 +
    a2 x^2 + a1 x + a0 and N(x) = b3 x^3 + b2 x^2 + b1 x + b0::

        dz/dt' = A z + B r,   y = C z
        A = [[0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [-a0, -a1, -a2, -a3]]
        B = [0, 0, 0, 1],     C = [b0, b1, b2, b3]

    so z_1 is r filtered by 1/D and z_(i+1) its i-th derivative in t'.
    There is no D term. In real time dz/dt = (A z + B r)/tau.

    Returns
    -------
    A : numpy.ndarray, shape (4, 4)
    B : numpy.ndarray, shape (4,)
    C : numpy.ndarray, shape (4,)
    """
    A = np.zeros((ORDER, ORDER))
    A[np.arange(ORDER - 1), np.arange(1, ORDER)] = 1.0
    A[-1] = -_DEN[:-1]
    B = np.zeros(ORDER)
    B[-1] = 1.0
    C = np.zeros(ORDER)
    C[: NUMERATOR_DEGREE + 1] = _NUM
    return A, B, C


def _check_tau(tau):
    if not tau >= 0.0:
        raise ValueError(f"reflex delay tau must be >= 0 s, got {tau}")


def rates(z, r, tau):
    """Time derivatives of the filter states, dz/dt = (A z + B r)/tau.

    Parameters
    ----------
    z : array_like, shape (4,)
        Filter states.
    r : float
        Undelayed reflex signal.
    tau : float
        Delay [s]; 0 turns the delay off (the states are frozen).

    Returns
    -------
    numpy.ndarray, shape (4,)
    """
    _check_tau(tau)
    z = np.asarray(z, dtype=float)
    dz = np.zeros(ORDER)
    if tau == 0.0:
        return dz
    # Written out in the order of the C code (c_source) so both round alike.
    dz[:-1] = z[1:] / tau
    acc = r
    for i in range(ORDER):
        acc = acc - _DEN[i] * z[i]
    dz[-1] = acc / tau
    return dz


def output(z, r, tau):
    """Filter output y ~ r(t - tau): C z, or r itself when tau = 0.

    Parameters
    ----------
    z : array_like, shape (4,)
        Filter states.
    r : float
        Undelayed reflex signal.
    tau : float
        Delay [s].

    Returns
    -------
    float
    """
    _check_tau(tau)
    if tau == 0.0:
        return float(r)
    z = np.asarray(z, dtype=float)
    acc = 0.0
    for i in range(NUMERATOR_DEGREE + 1):
        acc = acc + _NUM[i] * z[i]
    return float(acc)


def steady_state(r, tau):
    """Filter states in equilibrium with a constant input r (then the output is r).

    Parameters
    ----------
    r : float
        Constant input.
    tau : float
        Delay [s]; for 0 the states are unused and returned as zeros.

    Returns
    -------
    numpy.ndarray, shape (4,)
        ``[r/a0, 0, 0, 0]``: A z + B r = 0, and C z = b0 r/a0 = r since b0 = a0.
    """
    _check_tau(tau)
    z = np.zeros(ORDER)
    if tau > 0.0:
        z[0] = r / _DEN[0]
    return z


def c_source():
    """C code of :func:`rates` and :func:`output` for the compiled model.

    Returns
    -------
    str
        Two static functions, ``wk_reflex_rates(tau, z, r, dz)`` and
        ``wk_reflex_output(tau, z, r)``, with the coefficients as full-precision
        double literals and the same order of operations as the NumPy code.
    """
    den = "".join(f"    acc = acc - ({float(_DEN[i])!r}) * z[{i}];\n" for i in range(ORDER))
    num = "".join(f"    acc = acc + ({float(_NUM[i])!r}) * z[{i}];\n" for i in range(NUMERATOR_DEGREE + 1))
    shifts = "".join(f"    dz[{i}] = z[{i + 1}] / tau;\n" for i in range(ORDER - 1))
    return (
        f"/* Reflex delay: Pade ({NUMERATOR_DEGREE}, {ORDER}) approximant of exp(-s tau),\n"
        "   controllable canonical form (whipple_kick.model.reflex). tau == 0: no delay. */\n"
        "static void wk_reflex_rates(double tau, const double *z, double r, double *dz)\n"
        "{\n"
        "    double acc;\n"
        "    if (tau == 0.0) {\n"
        + "".join(f"        dz[{i}] = 0.0;\n" for i in range(ORDER))
        + "        return;\n"
        "    }\n"
        + shifts
        + "    acc = r;\n"
        + den
        + f"    dz[{ORDER - 1}] = acc / tau;\n"
        "}\n"
        "\n"
        "static double wk_reflex_output(double tau, const double *z, double r)\n"
        "{\n"
        "    double acc = 0.0;\n"
        "    if (tau == 0.0) return r;\n"
        + num
        + "    return acc;\n"
        "}\n"
    )


def delayed_decay_reference(k, tau, t):
    """Exact solution of dx/dt = -k x(t - tau) with history x = 1 for t <= 0.

    The classical closed form (method of steps) is, on [n tau, (n+1) tau]::

        x(t) = sum_{j=0}^{n+1} (-k)^j (t - (j-1) tau)^j / j!

    (each term's derivative is -k times the previous term at t - tau, and
    the term j = n+2 that joins at t = (n+1) tau starts at zero, so x is
    continuous). Its terms grow like (k t)^j/j! and cancel, losing all
    digits by k t ~ 40, so the same polynomials are built step by step in
    the local variable u = t/tau - n in [0, 1] instead: with x = sum_i
    c_n[i] u^i on step n, c_n[i+1] = -k tau c_(n-1)[i]/(i+1) and
    c_n[0] = sum_i c_(n-1)[i] (continuity), starting from c_(-1) = [1].
    All coefficients are then at most (k tau)^i/i! in size.
    For tau = 0 the solution is exp(-k t).

    Parameters
    ----------
    k : float
        Feedback gain [1/s].
    tau : float
        Delay [s].
    t : array_like
        Times [s].

    Returns
    -------
    numpy.ndarray
        x(t), the shape of ``t``.
    """
    _check_tau(tau)
    t = np.asarray(t, dtype=float)
    x = np.ones_like(t)
    pos = t > 0.0
    if tau == 0.0:
        x[pos] = np.exp(-k * t[pos])
        return x
    if not pos.any():
        return x
    scaled = t / tau
    step = np.floor(scaled).astype(int)
    coef = np.array([1.0])
    for n in range(int(step[pos].max()) + 1):
        new = np.empty(n + 2)
        new[0] = coef.sum()
        new[1:] = -k * tau * coef / np.arange(1, n + 2)
        coef = new
        on = pos & (step == n)
        x[on] = np.polynomial.polynomial.polyval(scaled[on] - n, coef)
    return x
