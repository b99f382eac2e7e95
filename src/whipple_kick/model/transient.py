"""Transient tyre forms: how the lateral force and aligning moment build up.

Each form maps, per wheel, the wheel's kinematics (lateral sliding velocity
``vsy`` of its material contact point relative to the ground under it,
rolling speed ``vx``, camber, normal load ``fz``) and two tyre states to the
force and moment applied to the wheel, the states' rates, and the terms of
the energy accounting. The steady curves come from the Magic Formula
(:mod:`whipple_kick.model.magic_formula`), passed in as ``curves``, so the
compiled model can evaluate them as functions and the NumPy oracle inline.

``contact_patch``
    Single-contact-point model (Pacejka 2012, *Tyre and Vehicle Dynamics*,
    3rd ed., Ch. 7) with the contact patch's own slip angle a' and camber g'
    as states, a slip-dependent relaxation length, and the steady Magic
    Formula of (a', g', Fz) as the applied force and moment::

        sigma da'/dt = vsy cos(a')^2 - |vx| sin(a') cos(a')   (steady: tan a' = vsy/|vx|)
        sigma dg'/dt = |vx| (camber - g')
        sigma = sigma0 max(g_sec(a', Fz), G_MIN)
        F_y = F_ss(a', g', Fz),  M_z = M_ss(a', g', Fz)

    g_sec(a') = F_sym(a') / (C_a a') is the secant ratio of the pure-slip
    curve (zero camber, offsets removed) against the patch slip a' itself
    (not tan a'): 1 at zero slip, ~0.5 at the T03 peak, ~0.08 at 36 deg.
    It shortens the relaxation length as the patch saturates, so a sliding
    tyre relaxes quickly and can never hold more than the steady curve
    gives at the current load. The form is passive at constant load but
    not when the load changes at large slip (docs/validation.md).
``slip_lag``
    The same with a constant relaxation length (g_sec replaced by 1).
``force_lag``
    The thesis' form, ``(sigma/|vx|) dF/dt + F = F_ss(atan(vsy/|vx|), camber, Fz)``
    for the force and the moment, with the applied loads as states.
``carcass`` (default)
    A lateral carcass spring of constant stiffness ``C_Fa(F_z0)/sigma0`` in
    series with a contact patch sliding on the steady curve, its force held
    to the curve's extreme at the current load and camber: passive and
    friction-limited by construction, the force lag at small slip
    (:mod:`whipple_kick.model.carcass`, where the block is written; it needs a
    root finder, so it is C and Python code, not a SymPy expression).

Energy accounting (per wheel; F the applied force, V' the patch's sliding
velocity, ``|vx| tan a'`` in the contact forms and ``vsy`` in force_lag,
F0 = F_ss(0, patch camber, Fz) the zero-slip force): the power of the
tyre's lateral force on the bicycle (plate part excluded) splits as
``F vsy = F0 V' - D_slide - P_carcass`` with the sliding dissipation
``D_slide = -(F - F0) V'`` and the power into the carcass
``P_carcass = F (V' - vsy)``. docs/validation.md gives the argument and the
measured sizes.
"""
from . import symbols as S

#: Transient forms, by name; the compiled model's ``tyre_transient`` parameter is the index.
TRANSIENTS = ("contact_patch", "slip_lag", "force_lag", "carcass")
DEFAULT_TRANSIENT = "carcass"
#: Tyre states in their fixed slots (rear, front, rear, front), per form.
STATES = {
    "contact_patch": ("slip_patch_r", "slip_patch_f", "camber_patch_r", "camber_patch_f"),
    "slip_lag": ("slip_patch_r", "slip_patch_f", "camber_patch_r", "camber_patch_f"),
    "force_lag": ("fyr", "fyf", "mzr", "mzf"),
    "carcass": ("carcass_y_r", "carcass_y_f", "camber_patch_r", "camber_patch_f"),
}
#: Forms whose tyre block is a SymPy expression (:func:`tyre_block`); the carcass is written in C and Python.
SYMBOLIC = ("contact_patch", "slip_lag", "force_lag")
#: Floor of the secant ratio in the relaxation length [-]. A numerical floor
#: only: the ratio of a curve that keeps opposing the slip stays above it
#: (T03 table7_9, 400 kPa, 635 N: 0.03 at 90 deg); it acts where an
#: extrapolated fit turns back and changes sign at large slip (T03 chapter8
#: beyond ~50 deg), where sigma would otherwise reach zero or go negative.
#: Sensitivity of the default run: docs/validation.md.
G_MIN = 0.02
#: Normal load [N] below which the secant ratio (a SHAPE, independent of the
#: curve's peak factor) is evaluated at this load: the Magic-Formula factors
#: are 0/0 at zero load. Forces and moments still use the true load (zero
#: when unloaded).
FZ_SHAPE_FLOOR = 1.0


def check(name):
    """Index of the transient form ``name``; ``InputError`` naming the choices otherwise."""
    from whipple_kick.errors import InputError
    if name not in TRANSIENTS:
        raise InputError(f"tyre transient {name!r} is unknown; choose one of {', '.join(TRANSIENTS)}")
    return TRANSIENTS.index(name)


def tyre_block(name, curves, sigma0):
    """Symbolic tyre block of one transient form for both wheels.

    Parameters
    ----------
    name : str
        One of :data:`TRANSIENTS`.
    curves : mapping
        ``fy(wheel, slip, camber, fz)``, ``mz(wheel, slip, camber, fz)``
        (blended, scaled steady curves, zero when unloaded) and
        ``secant(wheel, slip, fz)`` (blended secant ratio, ``fz`` > 0),
        each returning a SymPy expression; ``wheel`` is ``"r"`` or ``"f"``.
    sigma0 : mapping
        ``{"r": symbol, "f": symbol}``: the relaxation lengths at small slip [m].

    Returns
    -------
    dict of sympy.Expr
        ``Fy_r Fy_f Mz_r Mz_f`` (applied), ``rates`` (list of 4, the state
        slots' time derivatives), ``W0`` (zero-slip-force power),
        ``D_slide`` (sliding dissipation rate), ``P_carcass_r``,
        ``P_carcass_f`` (power into each carcass), ``D_carcass`` (carcass
        damper dissipation rate: 0 in these forms), ``sigma_r``, ``sigma_f``
        (relaxation lengths in use [m]), ``patch_slip_r``, ``patch_slip_f``
        (the slip the steady curves are evaluated at [rad]).
    """
    import sympy as sm

    states = [sm.Symbol(n, real=True) for n in STATES[name]]
    out, rates = {}, [None] * 4
    w0 = slide = 0
    for k, wheel in enumerate("rf"):
        vsy, vx, camber, fz = S.syms([f"vsy_{wheel}", f"vx_{wheel}", f"camber_{wheel}", f"fz_{wheel}"])
        speed = sm.Abs(vx)
        first, second = states[k], states[k + 2]
        if name == "force_lag":
            slip = sm.atan2(vsy, speed)
            force, moment = first, second
            rates[k] = speed / sigma0[wheel] * (curves["fy"](wheel, slip, camber, fz) - first)
            rates[k + 2] = speed / sigma0[wheel] * (curves["mz"](wheel, slip, camber, fz) - second)
            force0 = curves["fy"](wheel, 0, camber, fz)
            patch_speed = vsy
            sigma = sigma0[wheel]
            out[f"P_carcass_{wheel}"] = sm.S.Zero
            out[f"patch_slip_{wheel}"] = slip
        else:
            slip, patch_camber = first, second
            force = curves["fy"](wheel, slip, patch_camber, fz)
            moment = curves["mz"](wheel, slip, patch_camber, fz)
            if name == "contact_patch":
                ratio = curves["secant"](wheel, slip, sm.Max(fz, FZ_SHAPE_FLOOR))
                sigma = sigma0[wheel] * sm.Max(ratio, G_MIN)
            else:
                sigma = sigma0[wheel]
            rates[k] = (vsy * sm.cos(slip)**2 - speed * sm.sin(slip) * sm.cos(slip)) / sigma
            rates[k + 2] = speed * (camber - patch_camber) / sigma
            force0 = curves["fy"](wheel, 0, patch_camber, fz)
            patch_speed = speed * sm.tan(slip)
            out[f"P_carcass_{wheel}"] = force * (patch_speed - vsy)
            out[f"patch_slip_{wheel}"] = slip
        out[f"Fy_{wheel}"], out[f"Mz_{wheel}"] = force, moment
        out[f"sigma_{wheel}"] = sigma
        w0 += force0 * patch_speed
        slide += -(force - force0) * patch_speed
    out["rates"] = rates
    out["W0"], out["D_slide"] = w0, slide
    out["D_carcass"] = sm.S.Zero
    return out
