"""The slip model's layouts: states, speeds, outputs and parameters by name, and their indices.

The module's names (:data:`STATE_NAMES`, :data:`X`, :data:`OUT`, :data:`P`, ...) are the layout of the
base model: the bicycle with the rigid rider, its arms and its reflex. A model with declared parts
(:mod:`whipple_kick.model.parts`) has a :class:`Layout` that appends each part's coordinates and speeds to
the state after the base model's (quadratures included), its speeds and outputs to the outputs, and its
parameters to the parameters: every base name keeps its index in every model, so code that reads the
bicycle's states by :data:`X` reads them from any model's state.
"""
import functools

from whipple_kick.model import energy, kane, parts, reflex, transient
from whipple_kick.model import symbols as S

COORDINATES = tuple(f"q{i}" for i in range(1, 11))
SPEEDS = tuple(f"u{i}" for i in range(1, 11))
DEPENDENT = ("u5", "u6", "u8")
INDEPENDENT = tuple(n for n in SPEEDS if n not in DEPENDENT)
#: Tyre-state slot names of the thesis' form (kept as aliases in :data:`X`).
TYRE_STATES = transient.FORMS["force_lag"].states
#: Tyre-state slot names of the default form.
PATCH_STATES = transient.FORMS["contact_patch"].states
QUADRATURE_STATES = energy.QUADRATURE_STATES
#: The reflex delay filter's states (:mod:`whipple_kick.model.reflex`): in a model whose reflex is delayed
#: only (:attr:`Layout.REFLEX_STATES`); without a delay the reflex acts undelayed and has no states.
REFLEX_STATES = reflex.STATE_NAMES
#: States integrated for the dynamics of the base model; the quadratures follow them.
DYNAMIC_STATES = COORDINATES + INDEPENDENT + PATCH_STATES
#: Coordinates nothing depends on (Moore's ignorable coordinates: the rear contact's position, the plate
#: being prescribed in time; the axisymmetric wheels' angles): their Jacobian columns are exactly zero
#: (a test), so the compiled Jacobian does not evaluate them.
IGNORABLE = ("q1", "q2", "q6", "q8")
#: Right-hand-side evaluations one compiled Jacobian of the base model costs (the budget counts them).
JACOBIAN_EVALUATIONS = len(DYNAMIC_STATES) + 1 - len(IGNORABLE)
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
    "kinetic_energy": ("J", "kinetic energy of the bicycle and rider"),
    "potential_energy": ("J", "gravitational potential energy"),
    "spring_energy": ("J", "energy stored in the vertical tyre springs and the parts' springs (the leaning upper "
                          "body's hip, the arms)"),
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
#: Outputs evaluated beside the dynamics rather than by them, in groups an outputs call may leave out
#: (:meth:`~whipple_kick.model.slip.call.CompiledRHS.outputs_at`'s ``names``): the plate's prescribed motion
#: (a polynomial of time), the tyres' steady-state curves at the kinematic slip, the friction limits (a search
#: on the curves), the aligning moments (the carcass tyre's second patch-slip solve, at the lagged camber).
#: A study's summary reads none of them. With all four left out a thesis case's outputs cost 41.8 M
#: instructions, against 59.8 M with the moments kept (callgrind, the nine thesis cases, 6 501 samples each:
#: ``scripts/bench_sweep.py cost --callgrind``).
OPTIONAL_OUTPUTS = (("yp", "vp", "ap"), ("fy_ss_r", "fy_ss_f", "mz_ss_r", "mz_ss_f"), ("fy_limit_r", "fy_limit_f"),
                    ("mz_r", "mz_f"))
#: The bit mask asking for every group of :data:`OPTIONAL_OUTPUTS` (bit ``k``: group ``k``).
EVERY_OPTIONAL_GROUP = (1 << len(OPTIONAL_OUTPUTS)) - 1
PARAMETER_NAMES = S.SLIP_CONSTANTS


class StateIndex(dict):
    """Index of each state by name. Every declared tyre form's state names (the thesis' forces, the carcass'
    deflections) are aliases of the four tyre slots, resolved when looked up: a form declared after this
    module was imported (:func:`whipple_kick.model.transient.declare`) has its names here too."""

    def __missing__(self, name):
        slot = transient.slot(name)
        if slot is None:
            raise KeyError(name)
        return self[PATCH_STATES[slot]]

    def __contains__(self, name):
        return dict.__contains__(self, name) or transient.slot(name) is not None

    def get(self, name, default=None):
        return self[name] if name in self else default


X = StateIndex({n: i for i, n in enumerate(STATE_NAMES)})
OUT = {n: i for i, n in enumerate(OUTPUT_NAMES)}
P = {n: i for i, n in enumerate(PARAMETER_NAMES)}

#: Package modules the compiled library is generated from (its cache key hashes them).
_SOURCES = ("compiler", "symbols", "parts", "symbolic/derivation", "symbolic/codegen", "magic_formula", "transient", "carcass", "energy",
            "reflex",
            "slip/__init__", "slip/description", "slip/layout", "slip/compiled", "slip/call", "slip/parameters", "slip/jumps",
            "slip/linear", "symbolic/slip_build")


def tyre_state_names(name=transient.DEFAULT_TRANSIENT):
    """Names of the four tyre-state slots under the transient form ``name``."""
    transient.check(name)
    return transient.FORMS[name].states


#: The state each gain of the rider's voluntary law on the bicycle multiplies (``T7 = -sum(gain * state)``);
#: a part's gains on its own states follow (:attr:`Layout.GAIN_STATES`).
GAIN_STATES = {"kq3": "q3", "kq4": "q4", "kq7": "q7", "ku3": "u3", "ku4": "u4", "ku7": "u7"}


class Layout:
    """The layouts of the model made of the base model, the declared parts ``part_names`` and, with
    ``delayed_reflex``, the reflex's delay filter.

    Attributes have the names of the module's base-layout constants
    (``STATE_NAMES``, ``X``, ``OUT``, ``P``, ``SPEEDS``, ``INDEPENDENT``, ...)
    and extend them: the delay filter's states (``REFLEX_STATES``, empty
    without the delay) and the parts' coordinates and then their speeds
    follow the base states, the parts' speeds and outputs follow the base
    outputs, the parts' parameters follow the base parameters. ``PART_STATES``
    are the parts' states, ``COLUMNS`` their trajectory columns (state ->
    (column, unit)), ``GAIN_STATES`` every gain's state, ``key`` names the
    model (``"rigid"`` for the base model, ``"+delay"`` for the filter).
    """

    def __init__(self, part_names=(), delayed_reflex=False):
        self.parts = parts.named(part_names)
        self.delayed_reflex = bool(delayed_reflex)
        self.key = ("+".join(p.name for p in self.parts) or "rigid") + ("+delay" if delayed_reflex else "")
        coords = tuple(n for p in self.parts for n in p.coordinates)
        speeds = tuple(n for p in self.parts for n in p.speeds)
        self.PART_STATES = coords + speeds
        self.REFLEX_STATES = REFLEX_STATES if delayed_reflex else ()
        self.COORDINATES = COORDINATES + coords
        self.SPEEDS = SPEEDS + speeds
        self.DEPENDENT = DEPENDENT
        self.INDEPENDENT = INDEPENDENT + speeds
        self.DYNAMIC_STATES = DYNAMIC_STATES + self.REFLEX_STATES + self.PART_STATES
        self.STATE_NAMES = STATE_NAMES + self.REFLEX_STATES + self.PART_STATES
        self.OUTPUTS = dict(OUTPUTS)
        for p in self.parts:
            self.OUTPUTS.update(p.outputs)
        self.PART_OUTPUTS = tuple(n for p in self.parts for n in p.outputs)
        self.OUTPUT_NAMES = OUTPUT_NAMES + speeds + self.PART_OUTPUTS
        self.PARAMETER_NAMES = PARAMETER_NAMES + tuple(n for p in self.parts for n in p.parameters)
        self.X = StateIndex(X)
        self.X.update({n: len(STATE_NAMES) + i for i, n in enumerate(self.REFLEX_STATES + self.PART_STATES)})
        self.OUT = {n: i for i, n in enumerate(self.OUTPUT_NAMES)}
        self.P = {n: i for i, n in enumerate(self.PARAMETER_NAMES)}
        self.GAIN_STATES = dict(GAIN_STATES)
        self.COLUMNS = {}
        for p in self.parts:
            self.GAIN_STATES.update(p.gains)
            self.COLUMNS.update(p.columns)
        self.GAIN_NAMES = tuple(self.GAIN_STATES)
        self.JACOBIAN_EVALUATIONS = JACOBIAN_EVALUATIONS + len(self.REFLEX_STATES) + len(self.PART_STATES)
        self.PARTITION = kane.ConstraintPartition(self.SPEEDS, DEPENDENT)

    def __repr__(self):
        return f"Layout({self.key!r})"

    @property
    def part_names(self):
        """Names of the model's parts."""
        return tuple(p.name for p in self.parts)

    def record(self):
        """The layouts as a compiled library's metadata records them (what its loader compares)."""
        return {"states": list(self.STATE_NAMES), "parameters": list(self.PARAMETER_NAMES),
                "outputs": list(self.OUTPUT_NAMES), "dynamic_states": len(self.DYNAMIC_STATES)}

    def fingerprint(self):
        """The parts' declarations and build code, hashed (part of the generated code's cache key)."""
        return " ".join([f"{p.name}:{p.fingerprint()}" for p in self.parts] + ["delay"] * self.delayed_reflex)


def for_parts(part_names=(), delayed_reflex=False):
    """The (shared) :class:`Layout` of the base model with the parts ``part_names`` (in build order, :func:`whipple_kick.model.parts.named`) and,
    with ``delayed_reflex``, the reflex's delay filter: one object per model in a process."""
    return _layout(tuple(p.name for p in parts.named(part_names)), bool(delayed_reflex))


@functools.cache
def _layout(part_names, delayed_reflex):
    return Layout(part_names, delayed_reflex)


BASE = for_parts(())
