"""Pacejka 1989 Magic Formula for bicycle tyres, written once in SymPy.

Everything tyre-related in the project comes from the expressions built here:
the compiled model prints them to C, :mod:`whipple_kick.library.tyres` evaluates them
with NumPy through :func:`sympy.lambdify`. Nothing else re-implements the
formula. SymPy is imported by the functions that build expressions, not by
the module: the runtime needs only the coefficient layout (counts, offset
and camber-odd indices, :func:`camber_reversed`).

Two conventions meet in this module:

* the *formula* convention (``*_formula`` builders, ``*_factors``): slip angle
  ``alpha`` and camber ``gamma`` in degrees, normal load in kN, force in N,
  moment in N m, Pacejka's "adapted SAE" signs as used by the coefficient
  fits of Dell'Orto's thesis (Chapter 7, Table 7.9; Chapter 8 T03 sets);
* the *model* convention (``*_model`` builders): Moore's bicycle axes, x
  forward along the wheel heading in the ground plane, y to the right, z
  down; SI units and radians.

The one and only mapping between them is in :func:`_formula_inputs` and the
leading minus signs of :func:`lateral_force_model` /
:func:`aligning_moment_model`::

    F_y,model(slip, camber, F_z) = -F_y,formula(alpha = +slip [deg], gamma = -camber [deg], F_z [kN])
    M_z,model(slip, camber, F_z) = -M_z,formula(alpha = +slip [deg], gamma = -camber [deg], F_z [kN])

Why (derived from physics and the fitted data, proved by
``tests/model/test_magic_formula.py``):

* ``slip = atan(v_y / |v_x|)`` > 0 means the contact slides to the right.
  Friction then pushes it to the LEFT, so ``F_y,model < 0``. All fitted sets
  have ``a3 > 0`` (BCD > 0: the formula's force rises with alpha), so the
  formula's force is positive for positive alpha; hence alpha = +slip and a
  minus sign on the force (the formula's y axis points left).
* A wheel with its top leaning right (camber > 0) is pushed right
  (``F_y,model > 0`` at zero slip). The fitted camber terms ``a11 > 0``
  (Sv) and ``a8 > 0`` (Sh) make the formula's force positive for positive
  gamma; with the minus sign on the force this needs gamma = -camber:
  the formula's positive camber is a lean to the left.
* At small slip the moment must turn the wheel toward its velocity: for
  slip > 0 the velocity points right of the heading, so ``M_z,model`` about
  the downward normal must be > 0. The fitted M_z sets have BCD < 0 (the
  formula's moment is negative for small positive alpha), and the formula's
  z axis points up, so ``M_z,model = -M_z,formula`` with the same alpha and
  gamma mapping as the force.

Friction scaling (``friction_scale = k``): the peak factor D becomes ``k*D``
and the stiffness factor B becomes ``B/k``, so the slope ``B*C*D`` at the
curve centre (cornering / aligning stiffness) is unchanged and only the
friction limit moves. The shifts Sh and Sv are NOT scaled: they hold the
small-slip properties (camber thrust, ply-steer/conicity offsets) that come
from carcass and tread deformation, not from the friction limit, and scaling
them would change the camber stiffness. Note that at ``alpha = 0`` the curve is
evaluated at ``x = Sh`` rather than at its centre, so the slope there changes
by a term of second order in Sh (well below 1 % for the thesis data).
"""
import functools

import numpy as np

__all__ = [
    "FY_CAMBER_ODD_INDICES",
    "FY_OFFSET_INDICES",
    "MZ_CAMBER_ODD_INDICES",
    "MZ_OFFSET_INDICES",
    "N_FY_COEFFICIENTS",
    "N_MZ_COEFFICIENTS",
    "OFFSET_FADE_LOAD",
    "SECANT_SERIES_LIMIT",
    "aligning_moment_factors",
    "aligning_moment_formula",
    "aligning_moment_model",
    "aligning_moment_numpy",
    "camber_reversed",
    "cornering_stiffness_model",
    "cornering_stiffness_numpy",
    "inner_function",
    "lateral_force_factors",
    "lateral_force_factors_numpy",
    "lateral_force_formula",
    "lateral_force_model",
    "lateral_force_model_factors",
    "lateral_force_numpy",
    "lateral_secant_model",
    "lateral_secant_numpy",
    "offset_fade",
]

#: Number of Pacejka 1989 lateral-force coefficients a0..a13.
N_FY_COEFFICIENTS = 14
#: Number of Pacejka 1989 aligning-moment coefficients c0..c17.
N_MZ_COEFFICIENTS = 18

#: Coefficients that shift the curves at zero slip and camber (the Sh and Sv
#: terms not multiplied by camber): zeroing them gives a tyre with no
#: zero-slip force or moment ("symmetric tyres").
FY_OFFSET_INDICES = (9, 10, 12, 13)
MZ_OFFSET_INDICES = (12, 13, 16, 17)
#: Coefficients of the terms odd in camber: a8 (Sh) and a11 (Sv) of F_y, c11
#: (Sh) and c14, c15 (Sv) of M_z. Every other camber term is in ``|gamma|``, so
#: negating these five equals evaluating the curves at the opposite camber
#: (:func:`camber_reversed`).
FY_CAMBER_ODD_INDICES = (8, 11)
MZ_CAMBER_ODD_INDICES = (11, 14, 15)

#: Degrees per radian and newtons per kilonewton, exact (SymPy: 180/pi and 1000).
_DEG_PER_RAD_TEXT, _N_PER_KN = "180/pi", 1000


def _coefficients(values, count, name):
    """Return ``values`` as a list of sympified coefficients, checking the count."""
    import sympy as sm

    values = list(values)
    if len(values) != count:
        raise ValueError(f"{name} needs {count} coefficients, got {len(values)}")
    return [sm.sympify(v) for v in values]


def lateral_force_factors(gamma_deg, fz_kn, a):
    """Magic Formula factors of the lateral force, formula convention.

    Parameters
    ----------
    gamma_deg : sympy.Expr or float
        Camber angle in degrees (formula's sign).
    fz_kn : sympy.Expr or float
        Normal load in kN.
    a : sequence of 14
        Coefficients a0..a13 (Pacejka 1989).

    Returns
    -------
    dict
        ``B`` (1/deg), ``C``, ``D`` (N), ``E``, ``Sh`` (deg), ``Sv`` (N).
    """
    import sympy as sm

    a = _coefficients(a, N_FY_COEFFICIENTS, "lateral force")
    g, fz = sm.sympify(gamma_deg), sm.sympify(fz_kn)
    c_factor = a[0]
    d_factor = a[1] * fz**2 + a[2] * fz
    bcd = a[3] * sm.sin(2 * sm.atan(fz / a[4])) * (1 - a[5] * sm.Abs(g))
    return {
        "B": bcd / (c_factor * d_factor),
        "C": c_factor,
        "D": d_factor,
        "E": a[6] * fz + a[7],
        "Sh": a[8] * g + a[9] * fz + a[10],
        "Sv": a[11] * fz * g + a[12] * fz + a[13],
    }


def aligning_moment_factors(gamma_deg, fz_kn, c):
    """Magic Formula factors of the aligning moment, formula convention.

    Same units as :func:`lateral_force_factors` with D and Sv in N m;
    ``c`` holds the 18 coefficients c0..c17.
    """
    import sympy as sm

    c = _coefficients(c, N_MZ_COEFFICIENTS, "aligning moment")
    g, fz = sm.sympify(gamma_deg), sm.sympify(fz_kn)
    c_factor = c[0]
    d_factor = c[1] * fz**2 + c[2] * fz
    bcd = (c[3] * fz**2 + c[4] * fz) * (1 - c[6] * sm.Abs(g)) * sm.exp(-c[5] * fz)
    return {
        "B": bcd / (c_factor * d_factor),
        "C": c_factor,
        "D": d_factor,
        "E": (c[7] * fz**2 + c[8] * fz + c[9]) * (1 - c[10] * sm.Abs(g)),
        "Sh": c[11] * g + c[12] * fz + c[13],
        "Sv": (c[14] * fz**2 + c[15] * fz) * g + c[16] * fz + c[17],
    }


def camber_reversed(coefficients, kind):
    """Coefficients whose curve is the given one at the opposite camber.

    ``F(slip, camber, Fz)`` with the returned coefficients equals
    ``F(slip, -camber, Fz)`` with ``coefficients``, exactly: the terms odd in
    camber change sign (:data:`FY_CAMBER_ODD_INDICES`,
    :data:`MZ_CAMBER_ODD_INDICES`), the even ones (in ``|gamma|``) do not. With
    it the thesis authors' published code is reproduced, which feeds the
    camber to the formula with the opposite sign to this module's mapping,
    so that a leaning wheel's camber thrust pushes away from the lean.

    Parameters
    ----------
    coefficients : sequence of 14 (``kind="fy"``) or 18 (``kind="mz"``)
    kind : {"fy", "mz"}

    Returns
    -------
    numpy.ndarray

    Example
    -------
    >>> import numpy as np
    >>> a = np.arange(14.0)
    >>> camber_reversed(a, "fy")[[7, 8, 11]].tolist()
    [7.0, -8.0, -11.0]
    """
    indices, count = {"fy": (FY_CAMBER_ODD_INDICES, N_FY_COEFFICIENTS),
                      "mz": (MZ_CAMBER_ODD_INDICES, N_MZ_COEFFICIENTS)}[kind]
    out = np.array(coefficients, dtype=float)
    if out.shape != (count,):
        raise ValueError(f"{kind} needs {count} coefficients, got shape {out.shape}")
    out[list(indices)] *= -1.0
    return out


def _scale_friction(factors, friction_scale):
    """Return factors with D -> k*D and B -> B/k (stiffness B*C*D kept)."""
    import sympy as sm

    k = sm.sympify(friction_scale)
    scaled = dict(factors)
    scaled["D"] = k * factors["D"]
    scaled["B"] = factors["B"] / k
    return scaled


def _curve(alpha_deg, factors):
    """The Magic Formula curve itself, y(alpha) for given factors."""
    import sympy as sm

    b, c, d, e = factors["B"], factors["C"], factors["D"], factors["E"]
    bx = b * (sm.sympify(alpha_deg) + factors["Sh"])
    return d * sm.sin(c * sm.atan(inner_function(bx, e))) + factors["Sv"]


def lateral_force_formula(alpha_deg, gamma_deg, fz_kn, a):
    """Lateral force in N, Pacejka 1989, the formula's own convention."""
    return _curve(alpha_deg, lateral_force_factors(gamma_deg, fz_kn, a))


def aligning_moment_formula(alpha_deg, gamma_deg, fz_kn, c):
    """Aligning moment in N m, Pacejka 1989, the formula's own convention."""
    return _curve(alpha_deg, aligning_moment_factors(gamma_deg, fz_kn, c))


def _formula_inputs(slip_rad, camber_rad, fz_n):
    """Map model inputs (rad, rad, N) to formula inputs (deg, deg, kN).

    This is the single place where the camber sign flips (see module notes).
    """
    import sympy as sm

    deg_per_rad = sm.sympify(_DEG_PER_RAD_TEXT)
    alpha_deg = sm.sympify(slip_rad) * deg_per_rad
    gamma_deg = -sm.sympify(camber_rad) * deg_per_rad
    fz_kn = sm.sympify(fz_n) / sm.Integer(_N_PER_KN)
    return alpha_deg, gamma_deg, fz_kn


def _loaded_only(expr, fz_n):
    """``expr`` where the tyre is loaded (fz_n > 0), exactly 0 otherwise."""
    import sympy as sm

    fz_n = sm.sympify(fz_n)
    if fz_n.is_number:
        # A number needs no Piecewise; and building the formula at Fz = 0
        # would divide by D = 0, so decide before ``expr`` is evaluated.
        return expr() if fz_n > 0 else sm.S.Zero
    return sm.Piecewise((expr(), fz_n > 0), (0, True))


#: Normal load [N] below which the fits' load-independent vertical shifts
#: (a13 of F_y, c17 of M_z) fade to zero with the load. Every other term of
#: the curves vanishes with the load (D, and Sv's other terms, are
#: proportional to it); these two do not, so the curve of a tyre whose load
#: tends to zero would keep their force (T03 at 500 kPa: a13 = -38.9 N) and
#: drop it at once when the wheel lifts off. That jump makes a lift-off a
#: point where no integrator can step (the load chatters about zero). The
#: fits hold from 343 N up (thesis Chapter 7, the loads measured); the kick
#: runs with a rider keep both loads above 280 N, so they do not see the
#: fade. Its sensitivity: docs/validation.md.
OFFSET_FADE_LOAD = 100.0
#: Index of the load-independent vertical shift (Sv's constant) per factor builder.
_CONSTANT_SHIFT = {"lateral_force_factors": 13, "aligning_moment_factors": 17}


def offset_fade(fz_n):
    """Weight of the fits' load-independent vertical shifts at normal load ``fz_n``.

    A C1 smoothstep: ``3 s^2 - 2 s^3`` with ``s = fz_n / OFFSET_FADE_LOAD``
    below :data:`OFFSET_FADE_LOAD`, exactly 1 from it up.

    Parameters
    ----------
    fz_n : sympy.Expr or float
        Normal load [N] (>= 0 where it is used: the curves are 0 unloaded).

    Returns
    -------
    sympy.Expr
        The weight [-], between 0 and 1.

    Example
    -------
    >>> float(offset_fade(0.0)), float(offset_fade(50.0)), float(offset_fade(635.0))
    (0.0, 0.5, 1.0)
    """
    import sympy as sm

    fz_n = sm.sympify(fz_n)
    s = fz_n / sm.Float(OFFSET_FADE_LOAD)
    smooth = s**2 * (3 - 2 * s)
    if fz_n.is_number:
        return sm.S.One if fz_n >= OFFSET_FADE_LOAD else smooth
    return sm.Piecewise((1, fz_n >= OFFSET_FADE_LOAD), (smooth, True))


def _model_factors(factor_builder, count, camber_rad, fz_n, coefficients, friction_scale):
    """Factors at model inputs (rad, N): the constant shift faded with the load, friction scaled; formula units."""
    coefficients = _coefficients(coefficients, count, factor_builder.__name__)
    k = _CONSTANT_SHIFT[factor_builder.__name__]
    coefficients[k] = coefficients[k] * offset_fade(fz_n)
    _, gamma, fz_kn = _formula_inputs(0, camber_rad, fz_n)
    return _scale_friction(factor_builder(gamma, fz_kn, coefficients), friction_scale)


def _model_curve(factor_builder, count, slip_rad, camber_rad, fz_n, coefficients, friction_scale):
    """Shared body of the ``*_model`` builders: map inputs, fade the constant shift, scale, flip sign, gate on load."""
    alpha, _, _ = _formula_inputs(slip_rad, 0, fz_n)
    _coefficients(coefficients, count, factor_builder.__name__)   # a wrong count raises at every load

    def value():
        factors = _model_factors(factor_builder, count, camber_rad, fz_n, coefficients, friction_scale)
        # Minus: the formula's y axis points left and its z axis up (module notes).
        return -_curve(alpha, factors)

    return _loaded_only(value, fz_n)


def lateral_force_model_factors(camber_rad, fz_n, a, friction_scale=1):
    """The factors :func:`lateral_force_model` evaluates its curve with, at model inputs.

    ``F_y,model(slip) = -(D sin(C atan(B x - E (B x - atan(B x)))) + Sv)`` with
    ``x = slip [deg] + Sh``: the formula's units (B 1/deg, D and Sv N, Sh
    deg), the constant shift faded with the load (:func:`offset_fade`) and
    the friction scale applied. The carcass tyre's compiled inverse and
    friction limit (:mod:`whipple_kick.model.transient`) start from these.

    Parameters
    ----------
    camber_rad, fz_n : sympy.Expr or float
        Camber [rad, model sign] and normal load [N, > 0].
    a : sequence of 14
        Coefficients a0..a13.
    friction_scale : sympy.Expr or float

    Returns
    -------
    dict
        ``B C D E Sh Sv``.
    """
    return _model_factors(lateral_force_factors, N_FY_COEFFICIENTS, camber_rad, fz_n, a, friction_scale)


def inner_function(u, e):
    """The Magic Formula's inner function ``(1 - E) u + E atan(u)`` of ``u = B x``.

    The curve is ``D sin(C atan(inner(B x))) + Sv``; the carcass tyre inverts
    the curve through it (closed form for the sine and arctangent, Newton
    for this function, which rises monotonically for E <= 1).
    """
    import sympy as sm

    return (1 - e) * u + e * sm.atan(u)


def lateral_force_model(slip_rad, camber_rad, fz_n, a, friction_scale=1):
    """Lateral force in N, model convention (y right), zero when unloaded.

    Parameters
    ----------
    slip_rad : sympy.Expr or float
        ``atan(v_y/|v_x|)`` of the contact velocity relative to the ground,
        rad, positive when the contact slides to the right.
    camber_rad : sympy.Expr or float
        Lean of the wheel plane about the heading, rad, positive = top right.
    fz_n : sympy.Expr or float
        Normal force in N (the force is exactly 0 for ``fz_n <= 0``).
    a : sequence of 14
        Coefficients a0..a13 in the formula's units.
    friction_scale : sympy.Expr or float
        ``k``: D -> k*D, B -> B/k (see module notes).
    """
    return _model_curve(lateral_force_factors, N_FY_COEFFICIENTS, slip_rad, camber_rad, fz_n, a,
                        friction_scale)


def aligning_moment_model(slip_rad, camber_rad, fz_n, c, friction_scale=1):
    """Aligning moment in N m about the downward normal, model convention.

    Same arguments as :func:`lateral_force_model` with ``c`` the 18
    coefficients c0..c17; exactly 0 for ``fz_n <= 0``.
    """
    return _model_curve(aligning_moment_factors, N_MZ_COEFFICIENTS, slip_rad, camber_rad, fz_n, c,
                        friction_scale)


def cornering_stiffness_model(fz_n, a, friction_scale=1):
    """Cornering stiffness ``-dF_y,model/dslip`` at zero slip and camber, N/rad.

    Returned as a positive magnitude, as the thesis tabulates it (Tables
    7.2-7.7, there in N/deg): in the model convention the force opposes the
    slip, ``F_y ~ -C_alpha * slip``. Exactly 0 for ``fz_n <= 0``.
    """
    import sympy as sm

    slip = sm.Dummy("slip")
    # Differentiate the model expression itself, so the sign mapping is not
    # restated here: C_alpha = -dF_y,model/dslip.
    force = lateral_force_model(slip, 0, fz_n, a, friction_scale)
    return -sm.diff(force, slip).subs(slip, 0)


#: ``|B x|`` (x = slip in deg) below which :func:`lateral_secant_model` uses its
#: series: the next term is O((B x)^4), below 1e-16 there, while the direct
#: quotient loses digits to cancellation (sin and atan of a tiny argument).
SECANT_SERIES_LIMIT = 1e-4


def lateral_secant_model(slip_rad, fz_n, a, friction_scale=1):
    """Secant ratio of one coefficient set's pure-slip lateral-force curve, and its slope at zero slip.

    With the curve taken at zero camber and without its zero-slip offsets
    (Sh = Sv = 0), ``F_sym(slip) = D sin(C atan(B x - E (B x - atan(B x))))``
    (x = slip in deg), the secant ratio is ``g = F_sym / (C0 x)`` with
    ``C0 = B C D`` the slope at zero: 1 at zero slip, falling as the force
    saturates, even in slip. It is independent of the peak factor D (so of
    the load through D), and the friction scale k enters as B -> B/k. For
    ``|B x| < SECANT_SERIES_LIMIT`` the series
    ``1 - ((1 + E)/3 + C^2/6) (B x)^2`` replaces the 0/0 quotient.

    Parameters
    ----------
    slip_rad : sympy.Expr or float
        Slip angle [rad] (model convention; the ratio is even in it).
    fz_n : sympy.Expr or float
        Normal load [N], > 0 (callers floor it: the ratio is a shape only).
    a : sequence of 14
        Lateral-force coefficients a0..a13.
    friction_scale : sympy.Expr or float
        ``k`` as in :func:`lateral_force_model`.

    Returns
    -------
    (slope, ratio) : tuple of sympy.Expr
        ``slope`` = B C D [N/deg] (the weight of this set when sets are
        blended: the blended ratio is sum(w slope g) / sum(w slope));
        ``ratio`` = g [-].
    """
    import sympy as sm

    a = _coefficients(a, N_FY_COEFFICIENTS, "lateral force")
    alpha, _, fz_kn = _formula_inputs(slip_rad, 0, fz_n)
    factors = _scale_friction(lateral_force_factors(0, fz_kn, a), friction_scale)
    b, c, e = factors["B"], factors["C"], factors["E"]
    y = b * alpha
    direct = sm.sin(c * sm.atan(y - e * (y - sm.atan(y)))) / (c * y)
    series = 1 - ((1 + e) / 3 + c**2 / 6) * y**2
    ratio = sm.Piecewise((series, sm.Abs(y) < SECANT_SERIES_LIMIT), (direct, True))
    return b * c * factors["D"], ratio


# ---------------------------------------------------------------------------
# NumPy evaluation, generated from the expressions above (built once, cached).

_FACTOR_NAMES = ("B", "C", "D", "E", "Sh", "Sv")


@functools.cache
def _numpy_function(which):
    """Lambdify one of the model expressions (cached: built on first use)."""
    import sympy as sm

    slip, camber, fz, scale = sm.symbols("slip camber fz friction_scale", real=True)
    a = sm.symbols(f"a0:{N_FY_COEFFICIENTS}", real=True)
    c = sm.symbols(f"c0:{N_MZ_COEFFICIENTS}", real=True)
    if which == "fy":
        expr = lateral_force_model(slip, camber, fz, a, scale)
        args = (slip, camber, fz, scale, *a)
    elif which == "mz":
        expr = aligning_moment_model(slip, camber, fz, c, scale)
        args = (slip, camber, fz, scale, *c)
    elif which == "stiffness":
        expr = cornering_stiffness_model(fz, a, scale)
        args = (fz, scale, *a)
    elif which == "secant":
        expr = list(lateral_secant_model(slip, fz, a, scale))
        args = (slip, fz, scale, *a)
    elif which == "fy_factors":
        _, gamma_deg, fz_kn = _formula_inputs(0, camber, fz)
        factors = _scale_friction(lateral_force_factors(gamma_deg, fz_kn, a), scale)
        expr = [factors[key] for key in _FACTOR_NAMES]
        args = (camber, fz, scale, *a)
    else:  # pragma: no cover - internal misuse
        raise KeyError(which)
    return sm.lambdify(args, expr, modules="numpy")


def _coefficient_array(coefficients, count):
    coefficients = np.asarray(coefficients, dtype=float).ravel()
    if coefficients.size != count:
        raise ValueError(f"expected {count} coefficients, got {coefficients.size}")
    return coefficients


def _evaluate(which, arrays, friction_scale, coefficients, count):
    """Broadcast the inputs, evaluate quietly, return a float array."""
    coefficients = _coefficient_array(coefficients, count)
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in arrays))
    # np.select evaluates both Piecewise branches; the unloaded branch's
    # 0/0 is computed and then discarded, so silence its warnings.
    with np.errstate(all="ignore"):
        out = _numpy_function(which)(*arrays, float(friction_scale), *coefficients)
    return np.broadcast_to(np.asarray(out, dtype=float), arrays[0].shape).copy()


def lateral_force_numpy(slip, camber, fz, a, friction_scale=1.0):
    """Vectorised :func:`lateral_force_model`: rad, rad, N -> N (never NaN for fz <= 0)."""
    return _evaluate("fy", (slip, camber, fz), friction_scale, a, N_FY_COEFFICIENTS)


def aligning_moment_numpy(slip, camber, fz, c, friction_scale=1.0):
    """Vectorised :func:`aligning_moment_model`: rad, rad, N -> N m."""
    return _evaluate("mz", (slip, camber, fz), friction_scale, c, N_MZ_COEFFICIENTS)


def cornering_stiffness_numpy(fz, a, friction_scale=1.0):
    """Vectorised :func:`cornering_stiffness_model`: N -> N/rad (positive)."""
    return _evaluate("stiffness", (fz,), friction_scale, a, N_FY_COEFFICIENTS)


def lateral_secant_numpy(slip, fz, a, friction_scale=1.0):
    """Vectorised :func:`lateral_secant_model`: (slope B C D [N/deg], secant ratio [-]) for rad, N (fz > 0)."""
    coefficients = _coefficient_array(a, N_FY_COEFFICIENTS)
    slip, fz = np.broadcast_arrays(np.asarray(slip, dtype=float), np.asarray(fz, dtype=float))
    # numpy.select evaluates the quotient at zero slip too (0/0), then takes the series there.
    with np.errstate(all="ignore"):
        slope, ratio = _numpy_function("secant")(slip, fz, float(friction_scale), *coefficients)
    return (np.broadcast_to(np.asarray(slope, dtype=float), fz.shape).copy(),
            np.broadcast_to(np.asarray(ratio, dtype=float), fz.shape).copy())


def lateral_force_factors_numpy(camber, fz, a, friction_scale=1.0):
    """Magic Formula factors of F_y for MODEL inputs (camber in rad, fz in N).

    The inputs go through the same convention mapping as the force; the
    factors are returned in the formula's units and signs: ``B`` 1/deg,
    ``C``, ``D`` N, ``E``, ``Sh`` deg, ``Sv`` N (dict of arrays). Meaningless
    (0/0) for ``fz <= 0``: callers must check the load.
    """
    coefficients = _coefficient_array(a, N_FY_COEFFICIENTS)
    camber, fz = np.broadcast_arrays(np.asarray(camber, dtype=float), np.asarray(fz, dtype=float))
    with np.errstate(all="ignore"):
        values = _numpy_function("fy_factors")(camber, fz, float(friction_scale), *coefficients)
    return {key: np.broadcast_to(np.asarray(v, dtype=float), fz.shape).copy()
            for key, v in zip(_FACTOR_NAMES, values, strict=True)}
