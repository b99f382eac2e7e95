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
from collections.abc import Callable
from dataclasses import dataclass, field
import functools
import hashlib
import inspect

from whipple_kick.errors import InputError

from . import symbols as S


@dataclass(frozen=True)
class Form:
    """One transient form, declared once (:func:`declare`): what the rest of the package reads of it.

    Attributes
    ----------
    name : str
        The ``tyre_transient`` value; the compiled model's parameter is its index in :func:`transients`.
    description : str
        What it is, in a phrase (the scenario's help and documentation).
    states : tuple of str
        Names of its four tyre states in the fixed slots (rear, front, rear, front).
    wheel : callable or None
        Its tyre block for one wheel as SymPy expressions (:func:`tyre_block` calls it; see
        :func:`_force_lag` for the arguments and results); None for a form written in C and Python
        (the carcass, :mod:`whipple_kick.model.carcass`).
    scales : tuple of float
        Typical size of each state (1 for an angle [rad]; 100 for a force [N]; 1e-2 for a carcass deflection
        [m]): the compiled Jacobian's difference steps follow it, and the integrator's tolerances and the
        linearisation's steps follow it where it is above an angle's.
    steady_outputs : tuple of str or None
        The model outputs each state equals in a steady motion (its relaxed value); None: the form sets its
        own (the carcass, whose stiffness comes from the steady loads:
        :func:`whipple_kick.simulate.steady.start_state`).
    columns : tuple
        Its trajectory columns ``(column, "state" or "output", name in the model, unit)``.
    """

    name: str
    description: str
    states: tuple
    wheel: Callable | None = None
    scales: tuple = (1.0, 1.0, 1.0, 1.0)
    steady_outputs: tuple | None = None
    columns: tuple = field(default=())


#: Every declared form by name, in declaration order (:func:`declare`).
FORMS: dict = {}


def declare(form):
    """Add ``form`` to :data:`FORMS` (its index is its place there) and return it.

    A form may be declared anywhere (a test, a script): the scenario's choices, the trajectory's columns, the
    layouts' state names and the generated code's cache key read :data:`FORMS` when they are used.
    """
    if len(form.states) != 4 or len(form.scales) != 4:
        raise ValueError(f"transient form {form.name!r}: four states and four scales (rear, front, rear, front)")
    if form.wheel is None and any(f.wheel is None for f in FORMS.values() if f.name != form.name):
        # The generated C dispatches the SymPy forms by index and leaves the rest to the carcass' C block.
        raise ValueError(f"transient form {form.name!r} has no SymPy block: there is one form written in C (the "
                         "carcass), the rest need their wheel function")
    for other in FORMS.values():
        moved = [n for k, n in enumerate(form.states) if other.name != form.name and n in other.states
                 and other.states.index(n) != k]
        if moved:   # a state's name is an alias of one slot (whipple_kick.model.slip.layout.StateIndex)
            raise ValueError(f"transient form {form.name!r}: states {moved} are in other slots in form {other.name!r}")
    FORMS[form.name] = form
    return form


def transients():
    """Names of the declared forms, in the compiled model's order (its ``tyre_transient`` index), read when called:
    a form declared after the package was imported (a test's, a script's) is among them."""
    return tuple(FORMS)


def symbolic():
    """Names of the declared forms whose tyre block is a SymPy expression (:func:`tyre_block`), in
    :func:`transients` order; the carcass is written in C and Python."""
    return tuple(name for name, form in FORMS.items() if form.wheel is not None)


def slot(state):
    """The slot (0-3: rear, front, rear, front) of the tyre state ``state`` of any declared form, or None."""
    for form in FORMS.values():
        if state in form.states:
            return form.states.index(state)
    return None


def fingerprint():
    """The declared forms and their functions' source, hashed (part of the generated code's cache key).

    This module's own source is hashed with the others the model is generated from; this adds a form
    declared elsewhere (its declaration and its own function's source, not of helpers it calls). Read when
    called: a form declared later changes it, so the model with that form is another cache entry.
    """
    return _fingerprint(tuple(FORMS.values()))


@functools.cache
def _fingerprint(forms):
    """:func:`fingerprint` of the declared ``forms`` (once per set of declarations: a run asks for it often)."""
    text = repr([(f.name, f.states, f.scales, f.steady_outputs, f.columns) for f in forms])
    text += "".join(inspect.getsource(f.wheel) for f in forms if f.wheel is not None)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


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
    if name not in FORMS:
        raise InputError(f"tyre transient {name!r} is unknown; choose one of {', '.join(FORMS)}")
    return transients().index(name)


def tyre_block(name, curves, sigma0):
    """Symbolic tyre block of one transient form for both wheels.

    Parameters
    ----------
    name : str
        One of :func:`transients`.
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

    states = [sm.Symbol(n, real=True) for n in FORMS[name].states]
    out, rates = {}, [None] * 4
    w0 = slide = 0
    for k, wheel in enumerate("rf"):
        vsy, vx, camber, fz = S.syms([f"vsy_{wheel}", f"vx_{wheel}", f"camber_{wheel}", f"fz_{wheel}"])
        b = FORMS[name].wheel(wheel, states[k], states[k + 2], vsy, sm.Abs(vx), camber, fz, curves, sigma0[wheel])
        rates[k], rates[k + 2] = b["rates"]
        out[f"P_carcass_{wheel}"] = b["P_carcass"]
        out[f"patch_slip_{wheel}"] = b["patch_slip"]
        out[f"Fy_{wheel}"], out[f"Mz_{wheel}"] = b["force"], b["moment"]
        out[f"sigma_{wheel}"] = b["sigma"]
        w0 += b["force0"] * b["patch_speed"]
        slide += -(b["force"] - b["force0"]) * b["patch_speed"]
    out["rates"] = rates
    out["W0"], out["D_slide"] = w0, slide
    out["D_carcass"] = sm.S.Zero
    return out


# ------------------------------------------------------------------ the forms

def _force_lag(wheel, first, second, vsy, speed, camber, fz, curves, sigma0):
    """The thesis' lagged force and moment of one wheel (its states are the applied loads).

    Parameters
    ----------
    wheel : {"r", "f"}
    first, second : sympy.Symbol
        The wheel's two states (slots k and k + 2).
    vsy, speed, camber, fz : sympy.Expr
        Lateral sliding velocity [m/s], rolling speed ``|vx|`` [m/s], camber [rad], normal load [N].
    curves : mapping
        As :func:`tyre_block`'s.
    sigma0 : sympy.Symbol
        Relaxation length at small slip [m].

    Returns
    -------
    dict
        ``force``, ``moment`` (applied), ``rates`` (of ``first`` and ``second``), ``force0`` (zero-slip force),
        ``patch_speed`` (the patch's sliding velocity), ``sigma`` (relaxation length in use), ``patch_slip``
        (the slip the steady curves are evaluated at), ``P_carcass`` (power into the carcass).
    """
    import sympy as sm

    slip = sm.atan2(vsy, speed)
    return {"force": first, "moment": second,
            "rates": (speed / sigma0 * (curves["fy"](wheel, slip, camber, fz) - first),
                      speed / sigma0 * (curves["mz"](wheel, slip, camber, fz) - second)),
            "force0": curves["fy"](wheel, 0, camber, fz), "patch_speed": vsy, "sigma": sigma0,
            "patch_slip": slip, "P_carcass": sm.S.Zero}


def _patch(wheel, first, second, vsy, speed, camber, fz, curves, sigma, slip_dependent):
    """The contact patch's lagged slip and camber (the contact forms), with the relaxation length ``sigma``."""
    import sympy as sm

    slip, patch_camber = first, second
    force = curves["fy"](wheel, slip, patch_camber, fz)
    if slip_dependent:
        ratio = curves["secant"](wheel, slip, sm.Max(fz, FZ_SHAPE_FLOOR))
        sigma = sigma * sm.Max(ratio, G_MIN)
    patch_speed = speed * sm.tan(slip)
    return {"force": force, "moment": curves["mz"](wheel, slip, patch_camber, fz),
            "rates": ((vsy * sm.cos(slip)**2 - speed * sm.sin(slip) * sm.cos(slip)) / sigma,
                      speed * (camber - patch_camber) / sigma),
            "force0": curves["fy"](wheel, 0, patch_camber, fz), "patch_speed": patch_speed, "sigma": sigma,
            "patch_slip": slip, "P_carcass": force * (patch_speed - vsy)}


def _contact_patch(wheel, first, second, vsy, speed, camber, fz, curves, sigma0):
    """Lagged patch slip and camber, the relaxation length shortened by the secant ratio (as :func:`_force_lag`)."""
    return _patch(wheel, first, second, vsy, speed, camber, fz, curves, sigma0, slip_dependent=True)


def _slip_lag(wheel, first, second, vsy, speed, camber, fz, curves, sigma0):
    """Lagged patch slip and camber with a constant relaxation length (as :func:`_force_lag`)."""
    return _patch(wheel, first, second, vsy, speed, camber, fz, curves, sigma0, slip_dependent=False)


#: Trajectory columns of a form with a contact patch: its slip (an output: the state itself) and camber.
_PATCH_COLUMNS = (("slip_patch_rear", "output", "patch_slip_r", "rad"),
                  ("slip_patch_front", "output", "patch_slip_f", "rad"),
                  ("camber_patch_rear", "state", "camber_patch_r", "rad"),
                  ("camber_patch_front", "state", "camber_patch_f", "rad"))
_PATCH_STATES = ("slip_patch_r", "slip_patch_f", "camber_patch_r", "camber_patch_f")
_KINEMATIC = ("slip_r", "slip_f", "camber_r", "camber_f")

declare(Form("contact_patch", "lagged patch slip and camber with a slip-dependent relaxation length "
                              "(friction-limited, not passive under load changes)",
             _PATCH_STATES, _contact_patch, steady_outputs=_KINEMATIC, columns=_PATCH_COLUMNS))
declare(Form("slip_lag", "the same with a constant relaxation length", _PATCH_STATES, _slip_lag,
             steady_outputs=_KINEMATIC, columns=_PATCH_COLUMNS))
declare(Form("force_lag", "the thesis' lagged force and moment", ("fyr", "fyf", "mzr", "mzf"), _force_lag,
             scales=(1e2, 1e2, 1e2, 1e2), steady_outputs=("fy_ss_r", "fy_ss_f", "mz_ss_r", "mz_ss_f")))
declare(Form("carcass", "a lateral carcass spring in series with a sliding contact patch (passive and "
                        "friction-limited whatever the load does; the force lag at small slip)",
             ("carcass_y_r", "carcass_y_f", "camber_patch_r", "camber_patch_f"), scales=(1e-2, 1e-2, 1.0, 1.0),
             columns=(*_PATCH_COLUMNS, ("carcass_deflection_rear", "state", "carcass_y_r", "m"),
                      ("carcass_deflection_front", "state", "carcass_y_f", "m"))))

#: The form a scenario uses unless it names another.
DEFAULT_TRANSIENT = "carcass"
