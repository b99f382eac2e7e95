"""Registry of every symbol in the model: name, one-line description, unit.

Everything symbolic in whipple_kick (constants, generalised coordinates and
speeds, inputs, tyre states) is declared here exactly once, and created
through :func:`sym` / :func:`dyn`, which refuse names that are not
registered. Numeric values are always passed and looked up by these names.

The registry is plain data: importing this module does not import SymPy, so
the runtime (which only needs names, units and descriptions) never pays for
it; :func:`sym` and :func:`dyn` import SymPy when the build side first
creates a symbol.

Frames and points follow Moore (2012): N ground (x, y horizontal, z down),
A yaw frame, B roll frame, C rear frame (pitched so C.z is the steer axis),
D rear wheel, E front frame, F front wheel.
"""
from dataclasses import dataclass


@dataclass(frozen=True)
class SymbolInfo:
    """Description of one model symbol."""

    name: str
    description: str
    unit: str
    kind: str  # constant | coordinate | speed | input | state


def _entries():
    c, q, u, i, s = "constant", "coordinate", "speed", "input", "state"
    rows = [
        # --- Moore (2012) bicycle geometry and mass distribution -----------
        ("d1", "perpendicular distance from the rear wheel centre to the steer axis", "m", c),
        ("d2", "distance along the steer axis between the feet of the perpendiculars from the wheel centres", "m", c),
        ("d3", "perpendicular distance from the steer axis to the front wheel centre (fork offset)", "m", c),
        ("l1", "rear-frame mass centre from the rear wheel centre along C.x", "m", c),
        ("l2", "rear-frame mass centre from the rear wheel centre along C.z", "m", c),
        ("l3", "front-frame mass centre from the front wheel centre along E.x", "m", c),
        ("l4", "front-frame mass centre from the front wheel centre along E.z", "m", c),
        ("rr", "rear wheel radius (to the tyre's outer crown)", "m", c),
        ("rf", "front wheel radius (to the tyre's outer crown)", "m", c),
        ("mc", "mass of the rear frame C (with the rigid rider)", "kg", c),
        ("md", "mass of the rear wheel D", "kg", c),
        ("me", "mass of the front frame E (fork and handlebar)", "kg", c),
        ("mf", "mass of the front wheel F", "kg", c),
        ("ic11", "rear-frame moment of inertia about its mass centre, C.x axis", "kg m^2", c),
        ("ic22", "rear-frame moment of inertia about its mass centre, C.y axis", "kg m^2", c),
        ("ic33", "rear-frame moment of inertia about its mass centre, C.z axis", "kg m^2", c),
        ("ic31", "rear-frame product of inertia about its mass centre, C.z-C.x entry", "kg m^2", c),
        ("id11", "rear-wheel moment of inertia about a diameter", "kg m^2", c),
        ("id22", "rear-wheel moment of inertia about its spin axis", "kg m^2", c),
        ("ie11", "front-frame moment of inertia about its mass centre, E.x axis", "kg m^2", c),
        ("ie22", "front-frame moment of inertia about its mass centre, E.y axis", "kg m^2", c),
        ("ie33", "front-frame moment of inertia about its mass centre, E.z axis", "kg m^2", c),
        ("ie31", "front-frame product of inertia about its mass centre, E.z-E.x entry", "kg m^2", c),
        ("if11", "front-wheel moment of inertia about a diameter", "kg m^2", c),
        ("if22", "front-wheel moment of inertia about its spin axis", "kg m^2", c),
        ("g", "acceleration due to gravity", "m/s^2", c),
        # --- tyre geometry and vertical compliance (slip model) ------------
        ("rtr", "rear tyre crown (cross-section) radius of the toroidal tyre", "m", c),
        ("rtf", "front tyre crown (cross-section) radius of the toroidal tyre", "m", c),
        ("kzr", "rear tyre vertical stiffness", "N/m", c),
        ("kzf", "front tyre vertical stiffness", "N/m", c),
        ("czr", "rear tyre vertical damping", "N s/m", c),
        ("czf", "front tyre vertical damping", "N s/m", c),
        ("sigr", "rear tyre relaxation length", "m", c),
        ("sigf", "front tyre relaxation length", "m", c),
        # --- generalised coordinates (Moore 2012) --------------------------
        ("q1", "rear contact point position along N.x", "m", q),
        ("q2", "rear contact point position along N.y", "m", q),
        ("q3", "yaw angle of the rear frame (about N.z)", "rad", q),
        ("q4", "roll angle of the rear frame (about A.x), positive = lean right", "rad", q),
        ("q5", "pitch angle of the rear frame (about B.y)", "rad", q),
        ("q6", "rear wheel rotation angle relative to the rear frame (about C.y)", "rad", q),
        ("q7", "steer angle of the front frame relative to the rear frame (about C.z)", "rad", q),
        ("q8", "front wheel rotation angle relative to the front frame (about E.y)", "rad", q),
        ("q9", "rear tyre vertical compression", "m", q),
        ("q10", "front tyre vertical compression", "m", q),
        # --- generalised speeds: u_i = d q_i / dt --------------------------
        ("u1", "rate of q1: rear contact velocity along N.x", "m/s", u),
        ("u2", "rate of q2: rear contact velocity along N.y", "m/s", u),
        ("u3", "rate of q3: yaw rate", "rad/s", u),
        ("u4", "rate of q4: roll rate", "rad/s", u),
        ("u5", "rate of q5: pitch rate", "rad/s", u),
        ("u6", "rate of q6: rear wheel spin rate relative to the rear frame", "rad/s", u),
        ("u7", "rate of q7: steer rate", "rad/s", u),
        ("u8", "rate of q8: front wheel spin rate relative to the front frame", "rad/s", u),
        ("u9", "rate of q9: rear tyre compression rate", "m/s", u),
        ("u10", "rate of q10: front tyre compression rate", "m/s", u),
        # --- inputs --------------------------------------------------------
        ("T4", "roll torque on the rear frame about A.x (from the ground)", "N m", i),
        ("T6", "rear wheel drive torque, between rear frame and rear wheel (about C.y)", "N m", i),
        ("T7", "rider's active steer torque (voluntary law plus delayed reflex), on the front frame about C.z, "
               "reaction on the rider's upper body G (the rear frame while the hip is locked)", "N m", i),
        ("T_reflex", "rider's delayed reflex steer torque: the reflex law's torque through the delay filter "
                     "(whipple_kick.model.reflex)", "N m", i),
        ("yp", "kick-plate lateral displacement along N.y", "m", i),
        ("vp", "kick-plate lateral velocity along N.y", "m/s", i),
        ("ap", "kick-plate lateral acceleration along N.y", "m/s^2", i),
        # --- tyre force states (slip model, relaxed) ------------------------
        ("fyr", "rear tyre lateral force on the wheel, along the rear lateral axis A.y", "N", s),
        ("fyf", "front tyre lateral force on the wheel, along the front lateral axis", "N", s),
        ("mzr", "rear tyre self-aligning moment on the wheel about the downward normal", "N m", s),
        ("mzf", "front tyre self-aligning moment on the wheel about the downward normal", "N m", s),
        # --- contact-patch tyre states (transients contact_patch and slip_lag) --
        ("slip_patch_r", "rear tyre contact-patch (lagged) slip angle, + = patch sliding right", "rad", s),
        ("slip_patch_f", "front tyre contact-patch (lagged) slip angle, + = patch sliding right", "rad", s),
        ("camber_patch_r", "rear tyre contact-patch (lagged) camber angle, + = top leaning right", "rad", s),
        ("camber_patch_f", "front tyre contact-patch (lagged) camber angle, + = top leaning right", "rad", s),
        # --- carcass tyre states (transient carcass; its lagged camber is camber_patch_*) --
        ("carcass_y_r", "rear tyre lateral carcass deflection: contact patch relative to the rim, along A.y "
                        "(the carcass force on the wheel is ccr times it)", "m", s),
        ("carcass_y_f", "front tyre lateral carcass deflection: contact patch relative to the rim, along the "
                        "front lateral axis", "m", s),
        # --- the reflex delay filter's states (whipple_kick.model.reflex) --------
        ("reflex_1", "reflex delay filter state 1 (controllable canonical form, scaled time t/reflex_delay)", "N m", s),
        ("reflex_2", "reflex delay filter state 2 (controllable canonical form, scaled time t/reflex_delay)", "N m", s),
        ("reflex_3", "reflex delay filter state 3 (controllable canonical form, scaled time t/reflex_delay)", "N m", s),
        ("reflex_4", "reflex delay filter state 4 (controllable canonical form, scaled time t/reflex_delay)", "N m", s),
        # --- cumulative work and dissipation (quadrature states, from 0 at the start) --
        ("W_plate", "cumulative work of the kick plate on the bicycle (tyre force and rear no-slip constraint)", "J", s),
        ("W_steer", "cumulative work of the rider's active steer torque T7 on the bar's rotation relative to "
                    "the upper body", "J", s),
        ("W_wheel", "cumulative work of the rear-wheel torque T6c (T6c u6)", "J", s),
        ("W_zero_slip", "cumulative work of the tyres' zero-slip lateral forces F0 on the patch sliding velocity", "J", s),
        ("W_moment", "cumulative work of the aligning moments (M_z times the wheel's rate about the ground normal)", "J", s),
        ("D_slide", "cumulative sliding dissipation of the contact patches, -(F - F0) V'", "J", s),
        ("D_damper", "cumulative dissipation of the vertical tyre dampers, the rider's arm dampers and the parts' dampers "
                     "(the leaning upper body's hip)",
         "J", s),
        ("E_carcass_r", "rear tyre carcass energy: integral of the power into the lateral carcass compliance", "J", s),
        ("E_carcass_f", "front tyre carcass energy: integral of the power into the lateral carcass compliance", "J", s),
        ("D_carcass", "cumulative dissipation of the carcass tyres' lateral dampers, d (dy/dt)^2", "J", s),
        # --- tyre block: applied loads and its kinematic inputs (plain symbols) --
        ("Fy_r", "lateral force the rear tyre applies to the wheel (along A.y), from the active transient form", "N", i),
        ("Fy_f", "lateral force the front tyre applies to the wheel (along the front lateral axis)", "N", i),
        ("Mz_r", "aligning moment the rear tyre applies to the wheel about the downward normal", "N m", i),
        ("Mz_f", "aligning moment the front tyre applies to the wheel about the downward normal", "N m", i),
        ("vsy_r", "lateral sliding velocity of the rear wheel's material contact point relative to the plate", "m/s", i),
        ("vsy_f", "lateral sliding velocity of the front wheel's material contact point relative to the ground", "m/s", i),
        ("vx_r", "rolling speed of the rear wheel centre (or contact point: slip_speed_point) relative to the plate, "
                 "along the rear heading", "m/s", i),
        ("vx_f", "rolling speed of the front wheel centre (or contact point: slip_speed_point) along the front "
                 "heading", "m/s", i),
        ("camber_r", "rear wheel camber angle, + = top leaning right", "rad", i),
        ("camber_f", "front wheel camber angle, + = top leaning right", "rad", i),
        ("fz_r", "rear tyre normal force (spring-damper, never pulling)", "N", i),
        ("fz_f", "front tyre normal force (spring-damper, never pulling)", "N", i),
        ("vplate_r", "kick-plate velocity along the rear lateral axis A.y", "m/s", i),
        ("wz_r", "rear wheel angular velocity about the downward ground normal", "rad/s", i),
        ("wz_f", "front wheel angular velocity about the downward ground normal", "rad/s", i),
    ]
    rows += [
        # --- slip model: tyre blending, friction, kick plate, controller -------
        ("wr", "weight of the rear tyre's second Magic-Formula coefficient set (pressure interpolation)", "-", c),
        ("wf", "weight of the front tyre's second Magic-Formula coefficient set (pressure interpolation)", "-", c),
        ("mur", "rear tyre friction scale: peak factor D times mur, B divided by mur", "-", c),
        ("muf", "front tyre friction scale: peak factor D times muf, B divided by muf", "-", c),
        ("lamr", "rear tyre lateral-force and moment multiplier (thesis friction mode; 0 switches the tyre's lateral forces off)", "-", c),
        ("lamf", "front tyre lateral-force and moment multiplier (0 switches the tyre's lateral forces off)", "-", c),
        ("kick_t0", "time at which the kick plate starts to move", "s", c),
        ("kick_T", "duration of the kick plate's motion", "s", c),
        ("kick_D", "kick plate displacement (signed: positive along N.y, to the right)", "m", c),
        ("kick_profile", "kick profile: 0 constant acceleration (thesis), 1 minimum-jerk quintic, 2 cubic segment", "-", c),
        ("kick_c0", "cubic-segment plate profile: displacement at kick_t0", "m", c),
        ("kick_c1", "cubic-segment plate profile: velocity at kick_t0", "m/s", c),
        ("kick_c2", "cubic-segment plate profile: half the acceleration at kick_t0", "m/s^2", c),
        ("kick_c3", "cubic-segment plate profile: a sixth of the jerk", "m/s^3", c),
        ("kq3", "steer-torque feedback gain on yaw angle q3", "N m/rad", c),
        ("kq4", "steer-torque feedback gain on roll angle q4", "N m/rad", c),
        ("kq7", "steer-torque feedback gain on steer angle q7", "N m/rad", c),
        ("ku3", "steer-torque feedback gain on yaw rate u3", "N m s/rad", c),
        ("ku4", "steer-torque feedback gain on roll rate u4", "N m s/rad", c),
        ("ku7", "steer-torque feedback gain on steer rate u7", "N m s/rad", c),
        ("vsx_r", "imposed longitudinal sliding velocity of the rear wheel's material contact point relative to "
                  "the plate, along the rear heading (0: rolling without slip; the authors' plate stop leaves "
                  "it non-zero)", "m/s", c),
        ("T6c", "constant rear-wheel torque holding the steady speed, about C.y (the rear frame's right-pointing "
                "axis) on the wheel: + opposes forward rolling (a brake), - drives", "N m", c),
        ("slip_speed_point", "forward speed the tyres' slip angle and relaxation use: 0 the wheel centre's "
                             "(default), 1 the geometric contact point's (the authors' published code)", "-", c),
        ("tyre_transient", "tyre transient form: its index among the declared forms "
                           "(whipple_kick.model.transient.transients())", "-", c),
        ("ccr", "rear carcass lateral stiffness C_Fa(F_z0)/sigma0 (carcass transient)", "N/m", c),
        ("ccf", "front carcass lateral stiffness C_Fa(F_z0)/sigma0 (carcass transient)", "N/m", c),
        ("dcr", "rear carcass lateral damping, parallel to its stiffness (carcass transient)", "N s/m", c),
        ("dcf", "front carcass lateral damping, parallel to its stiffness (carcass transient)", "N s/m", c),
        ("carcass_sliding", "carcass friction limit past the peak: 0 the peak (Coulomb plateau), 1 the steady "
                            "curve at the kinematic slip", "-", c),
        ("carcass_stiffness_scale", "factor on the carcass stiffnesses C_Fa(F_z0)/sigma0 the steady state sets "
                                    "(ccr, ccf)", "-", c),
        ("carcass_viscosity", "sliding viscosity of an undamped carcass tyre's patch past its friction limit "
                              "(regularises the Coulomb plateau)", "N s/m", c),
        # --- the rider's reflexes (the upper body and the arms are declared parts: model/parts.py) --
        ("rq4", "reflex steer-torque gain on roll angle q4 (delayed by reflex_delay)", "N m/rad", c),
        ("rq7", "reflex steer-torque gain on steer angle q7 (delayed by reflex_delay)", "N m/rad", c),
        ("ru4", "reflex steer-torque gain on roll rate u4 (delayed by reflex_delay)", "N m s/rad", c),
        ("ru7", "reflex steer-torque gain on steer rate u7 (delayed by reflex_delay)", "N m s/rad", c),
        ("reflex_delay", "reflex time delay, a (3,4) Pade filter (0: no delay)", "s", c),
    ]
    fy_units = ["-", "N/kN^2", "N/kN", "N/deg", "kN", "1/deg", "1/kN", "-", "deg/deg", "deg/kN",
                "deg", "N/(kN deg)", "N/kN", "N"]
    mz_units = ["-", "N m/kN^2", "N m/kN", "N m/(deg kN^2)", "N m/(deg kN)", "1/kN", "1/deg",
                "1/kN^2", "1/kN", "-", "1/deg", "deg/deg", "deg/kN", "deg", "N m/(kN^2 deg)",
                "N m/(kN deg)", "N m/kN", "N m"]
    for wheel, wname in (("r", "rear"), ("f", "front")):
        for k in (1, 2):
            for i, unit in enumerate(fy_units):
                rows.append((f"a{wheel}{k}_{i}", f"{wname} tyre lateral-force Magic-Formula coefficient a{i}, "
                             f"coefficient set {k} (Pacejka 1989, formula units)", unit, c))
            for i, unit in enumerate(mz_units):
                rows.append((f"c{wheel}{k}_{i}", f"{wname} tyre aligning-moment Magic-Formula coefficient c{i}, "
                             f"coefficient set {k} (Pacejka 1989, formula units)", unit, c))
    return {name: SymbolInfo(name, desc, unit, kind) for name, desc, unit, kind in rows}


#: Every registered symbol by name (the model's parts add theirs: :func:`register`).
REGISTRY = _entries()


def register(rows):
    """Register the symbols of a model part: rows of ``(name, description, unit, kind)``.

    A name registered again with the same description, unit and kind is
    accepted (a part module imported twice); with anything else it is refused.
    """
    for name, description, unit, kind in rows:
        entry = SymbolInfo(name, description, unit, kind)
        if REGISTRY.get(name, entry) != entry:
            raise ValueError(f"symbol {name!r} is already registered as {REGISTRY[name]}")
        REGISTRY[name] = entry

#: Moore's parameters of the classic Carvallo-Whipple model, by name.
CLASSIC_CONSTANTS = (
    "d1", "d2", "d3", "l1", "l2", "l3", "l4", "rf", "rr",
    "mc", "md", "me", "mf",
    "ic11", "ic22", "ic33", "ic31", "id11", "id22",
    "ie11", "ie22", "ie33", "ie31", "if11", "if22", "g",
)


#: Constants of the slip model (classic constants plus tyre, plate and controller).
SLIP_CONSTANTS = CLASSIC_CONSTANTS + (
    "rtr", "rtf", "kzr", "kzf", "czr", "czf", "sigr", "sigf",
    "wr", "wf", "mur", "muf", "lamr", "lamf",
    "kick_t0", "kick_T", "kick_D", "kick_profile", "kick_c0", "kick_c1", "kick_c2", "kick_c3",
    "kq3", "kq4", "kq7", "ku3", "ku4", "ku7", "T6c", "tyre_transient", "vsx_r",
    "slip_speed_point", "ccr", "ccf", "dcr", "dcf", "carcass_sliding", "carcass_viscosity",
    "carcass_stiffness_scale", "rq4", "rq7", "ru4", "ru7", "reflex_delay",
) + tuple(f"{kind}{wheel}{k}_{i}" for wheel in "rf" for k in (1, 2)
          for kind, n in (("a", 14), ("c", 18)) for i in range(n))


def info(name):
    """Return the :class:`SymbolInfo` registered under ``name``."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise KeyError(f"symbol {name!r} is not registered in whipple_kick.model.symbols") from None


def sym(name):
    """Return the (real) SymPy symbol for a registered constant or input."""
    import sympy as sm  # the build side only: the registry itself is plain data

    entry = info(name)
    if entry.kind in ("coordinate", "speed", "state"):
        raise KeyError(f"{name!r} is a {entry.kind}; use dyn()")
    return sm.Symbol(name, real=True)


def dyn(name):
    """Return the dynamicsymbol (function of time) for a registered coordinate, speed or state."""
    import sympy.physics.mechanics as me  # the build side only

    entry = info(name)
    if entry.kind not in ("coordinate", "speed", "state"):
        raise KeyError(f"{name!r} is a {entry.kind}; use sym()")
    return me.dynamicsymbols(name, real=True)


def syms(names):
    """Tuple of :func:`sym` for several names."""
    return tuple(sym(n) for n in names)


def dyns(names):
    """Tuple of :func:`dyn` for several names."""
    return tuple(dyn(n) for n in names)
