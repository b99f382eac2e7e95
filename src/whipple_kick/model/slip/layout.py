"""The slip model's layout: states, speeds, outputs and parameters by name, and their indices."""


from whipple_kick.model import energy, kane, reflex, transient
from whipple_kick.model import symbols as S

COORDINATES = tuple(f"q{i}" for i in range(1, 12))
SPEEDS = tuple(f"u{i}" for i in range(1, 12))
DEPENDENT = ("u5", "u6", "u8")
INDEPENDENT = tuple(n for n in SPEEDS if n not in DEPENDENT)
#: Tyre-state slot names of the thesis' form (kept as aliases in :data:`X`).
TYRE_STATES = transient.STATES["force_lag"]
#: Tyre-state slot names of the default form.
PATCH_STATES = transient.STATES["contact_patch"]
QUADRATURE_STATES = energy.QUADRATURE_STATES
#: The reflex delay filter's states (:mod:`whipple_kick.model.reflex`).
REFLEX_STATES = reflex.STATE_NAMES
#: States integrated for the dynamics; the quadratures follow them.
DYNAMIC_STATES = COORDINATES + INDEPENDENT + PATCH_STATES + REFLEX_STATES
#: States that stay at 0 and drive nothing while the rider's hip is locked (the rigid rider).
HIP_STATES = ("q11", "u11")
#: Coordinates nothing depends on (Moore's ignorable coordinates: the rear contact's position, the plate
#: being prescribed in time; the axisymmetric wheels' angles): their Jacobian columns are exactly zero
#: (a test), so the compiled Jacobian does not evaluate them.
IGNORABLE = ("q1", "q2", "q6", "q8")
#: Right-hand-side evaluations one compiled Jacobian costs (the budget counts them).
#: (The hip's and the reflex filter's columns are skipped too while the hip is locked and the delay is 0,
#: as in the default rider: the count is for that rider.)
JACOBIAN_EVALUATIONS = len(DYNAMIC_STATES) + 1 - len(IGNORABLE) - len(HIP_STATES) - len(REFLEX_STATES)
STATE_NAMES = DYNAMIC_STATES + QUADRATURE_STATES
#: Named outputs the C function writes when asked, after all ten speeds: name -> (unit, what it is).
OUTPUTS = {
    "yp": ("m", "kick-plate lateral displacement along N.y"),
    "vp": ("m/s", "kick-plate lateral velocity"),
    "ap": ("m/s^2", "kick-plate lateral acceleration"),
    "slip_r": ("rad", "rear kinematic slip angle atan(vsy/|vx|), + = contact sliding right"),
    "slip_f": ("rad", "front kinematic slip angle atan(vsy/|vx|), + = contact sliding right"),
    "camber_r": ("rad", "rear wheel camber, + = top leaning right"),
    "camber_f": ("rad", "front wheel camber, + = top leaning right"),
    "vx_r": ("m/s", "rear wheel rolling speed relative to the plate, along its heading"),
    "vx_f": ("m/s", "front wheel rolling speed along its heading"),
    "fz_r": ("N", "rear tyre normal force"),
    "fz_f": ("N", "front tyre normal force"),
    "fy_ss_r": ("N", "rear steady lateral force at the kinematic slip and camber"),
    "fy_ss_f": ("N", "front steady lateral force at the kinematic slip and camber"),
    "mz_ss_r": ("N m", "rear steady aligning moment at the kinematic slip and camber"),
    "mz_ss_f": ("N m", "front steady aligning moment at the kinematic slip and camber"),
    "T7": ("N m", "rider's active steer torque: the voluntary law plus the delayed reflex"),
    "T_reflex": ("N m", "rider's delayed reflex steer torque (part of T7)"),
    "reflex_input": ("N m", "rider's reflex steer torque before the delay"),
    "arm_torque": ("N m", "passive torque of the rider's arms on the bar about the steer axis"),
    "hip_torque": ("N m", "torque of the hip spring-damper on the upper body about the lean axis"),
    "kinetic_energy": ("J", "kinetic energy of the bicycle and rider"),
    "potential_energy": ("J", "gravitational potential energy"),
    "spring_energy": ("J", "energy stored in the vertical tyre springs and, with a rider's body, in the hip "
                          "and arm springs"),
    "holonomic": ("m", "front contact height above the ground (the holonomic constraint's residual)"),
    "sliding_power": ("W", "power of the tyres' lateral forces on the contacts' sliding, F vsy"),
    "fy_r": ("N", "lateral force the rear tyre applies to the bicycle"),
    "fy_f": ("N", "lateral force the front tyre applies to the bicycle"),
    "mz_r": ("N m", "aligning moment the rear tyre applies to the bicycle"),
    "mz_f": ("N m", "aligning moment the front tyre applies to the bicycle"),
    "sigma_r": ("m", "rear relaxation length in use"),
    "sigma_f": ("m", "front relaxation length in use"),
    "patch_slip_r": ("rad", "slip angle the rear steady curve is evaluated at: the contact patch's (the kinematic "
                            "slip in force_lag)"),
    "patch_slip_f": ("rad", "slip angle the front steady curve is evaluated at: the contact patch's (the kinematic "
                            "slip in force_lag)"),
    "fy_limit_r": ("N", "rear friction limit on the side of its force: the steady curve's extreme at the current "
                        "load and camber (patch slip within the carcass tyre's cap)"),
    "fy_limit_f": ("N", "front friction limit on the side of its force: the steady curve's extreme at the current "
                        "load and camber (patch slip within the carcass tyre's cap)"),
}
#: Every output by position: the ten speeds (dependent ones included), then :data:`OUTPUTS`.
OUTPUT_NAMES = SPEEDS + tuple(OUTPUTS)
PARAMETER_NAMES = S.SLIP_CONSTANTS
X = {n: i for i, n in enumerate(STATE_NAMES)}
X.update({n: X[m] for n, m in zip(TYRE_STATES, PATCH_STATES, strict=True)})
X.update({n: X[m] for n, m in zip(transient.STATES["carcass"], PATCH_STATES, strict=True)})
OUT = {n: i for i, n in enumerate(OUTPUT_NAMES)}
P = {n: i for i, n in enumerate(PARAMETER_NAMES)}

#: Package modules the compiled library is generated from (its cache key hashes them).
_SOURCES = ("symbols", "symbolic/derivation", "symbolic/codegen", "magic_formula", "transient", "carcass", "energy",
            "reflex",
            "slip/__init__", "slip/layout", "slip/compiled", "slip/call", "slip/parameters", "slip/jumps",
            "slip/linear", "symbolic/slip_build")
_PARTITION = kane.ConstraintPartition(SPEEDS, DEPENDENT)


def tyre_state_names(name=transient.DEFAULT_TRANSIENT):
    """Names of the four tyre-state slots under the transient form ``name``."""
    transient.check(name)
    return transient.STATES[name]
