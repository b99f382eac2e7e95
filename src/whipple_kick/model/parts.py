"""The rider's degrees of freedom as declared parts of the bicycle-rider system.

The slip model (:func:`whipple_kick.model.symbolic.derivation.slip_equations`)
is the bicycle with a rigid rider lumped into the rear frame and its
reflex; each :class:`Part` adds
to it what it declares: its symbols (with units and descriptions), its
coordinates and speeds, its bodies, joint, springs, dampers and loads (its
``build``, which adds them to a SymPy ``System``: :class:`Mechanics`), its
parameters, the rider's feedback gains on its states, its trajectory
columns, its outputs, how it takes its body from the rider's segments
(:class:`Split`) and how it is drawn. A part is declared once, in its own
module, and the rest follows from the declaration: the derivation, the
generated code and its cache key, the state, parameter and output layouts
(:class:`whipple_kick.model.slip.layout.Layout`), the trajectory's columns,
the gain table, the rider's split (:func:`whipple_kick.library.riders.split_rider`)
and the animation. A model without a part has none of its terms: the rigid
rider is the model without the trunk part, not a locked one.

This follows SymBRiM's split of a rider into models and connections that
each declare their coordinates (Stienstra, SymBRiM documentation), written
for this model's single Kane derivation.

:data:`TRUNK` is the rider's upper body leaning on the hip (Moore 2012, ch. 4,
"Leaning rider extension"); :data:`ARMS` the arms' spring-damper about the
steer axis between the bar and the frame the hands hold (the upper body's
when it leans: it declares that it is built after the trunk, :attr:`Part.after`;
a part that cannot work without another declares it in :attr:`Part.needs`). :func:`merge_into_rear_frame` lumps an upper
body into the rear frame, exactly, for the rigid rider whose arms hold the bar.
"""
from collections.abc import Callable
from dataclasses import dataclass, field
import hashlib
import inspect
import math

import numpy as np

from whipple_kick.errors import InputError
from whipple_kick.model import benchmark
from whipple_kick.model import symbols as S


@dataclass
class Mechanics:
    """What the parts of one derivation add to the bicycle: a SymPy :class:`~sympy.physics.mechanics.System`.

    A part's ``build`` receives this and adds to :attr:`system` what SymPy's
    mechanics API holds: its bodies (``system.add_bodies``, or :meth:`body`),
    joints (``system.add_joints``: a joint brings its coordinates, speeds and
    kinematic differential equations), actuators (``system.add_actuators``:
    a ``TorqueActuator``, a ``LinearSpring`` or ``LinearDamper`` along a
    pathway) and other loads (``system.add_loads``). The system starts with
    the bicycle's four bodies (a joint's parent, :meth:`rigid_body`); the
    derivation reads the parts' bodies, coordinates, speeds, kinematic
    equations and loads back from it, weighs every body the parts added, and
    takes the store of each ``LinearSpring`` and the dissipation of each
    ``LinearDamper`` into the energy balance. What SymPy's system does not
    hold is here: the energy of a spring-damper written as a torque
    (:attr:`spring_energy`, :attr:`damper_dissipation`), the part's declared
    outputs, and the frame the hands hold.

    ``hands_frame`` is the frame the rider's hands react the steer torque and
    the arms on (the rear frame C unless a part carries the upper body), and
    ``hands_angle`` / ``hands_rate`` its rotation [rad] and rate [rad/s] about
    the steer axis C.z relative to the rear frame (the arms' spring stretches
    by the bar's rotation relative to the hands).
    """

    kin: object                 # derivation.Kinematics (frames, points, q, u, the bicycle's bodies, its weights)
    par: dict                   # parameter symbols by name (the base model's and every part's)
    system: object = None       # sympy.physics.mechanics.System in the ground frame N about O (set when None)
    spring_energy: list = field(default_factory=list)        # terms [J] of springs that are not LinearSprings
    damper_dissipation: list = field(default_factory=list)   # terms [W], each >= 0, of dampers that are not
    #                                                          LinearDampers
    outputs: dict = field(default_factory=dict)       # name -> expression (the part's declared outputs)
    hands_frame: object = None
    hands_angle: object = 0
    hands_rate: object = 0

    def __post_init__(self):
        if self.system is None:
            import sympy.physics.mechanics as me

            self.system = me.System(self.kin.frames["N"], self.kin.points["O"])
            self.system.add_bodies(*self.kin.bodies)
        self._bicycle = tuple(self.kin.bodies)

    def coordinate(self, q_name, u_name):
        """A part's coordinate and its speed (``u = dq/dt``) by name: (q, u) dynamicsymbols, for its joint.

        The joint brings them into :attr:`system` (``system.add_joints``); a coordinate no joint carries is
        added with ``system.add_coordinates``, ``add_speeds`` and ``add_kdes`` (``dq/dt - u``).
        """
        return S.dyn(q_name), S.dyn(u_name)

    def body(self, name, point, frame, mass, inertia):
        """Add a rigid body (``inertia`` a dyadic about ``point``, its mass centre) to :attr:`system`; return it.

        The derivation weighs it (every body a part adds).
        """
        import sympy.physics.mechanics as me

        body = me.RigidBody(name, point, frame, mass, (inertia, point))
        self.system.add_bodies(body)
        return body

    def rigid_body(self, name):
        """The system's body called ``name`` (``"rear_frame"``, ``"front_frame"``, a part's), to join to."""
        found = [b for b in self.system.bodies if b.name == name]
        if not found:
            raise KeyError(f"no body {name!r}; bodies: {', '.join(b.name for b in self.system.bodies)}")
        return found[0]

    def added_bodies(self):
        """The bodies the parts added, in the order they were added (the bicycle's four excluded)."""
        return [b for b in self.system.bodies if not any(b is own for own in self._bicycle)]

    def loads(self):
        """The parts' loads as Kane's method takes them: each actuator's (in the order added), then the rest."""
        return [*(load for act in self.system.actuators for load in act.to_loads()), *self.system.loads]

    def actuator_energy(self):
        """(store [J], dissipation rate [W]) of the system's ``LinearSpring`` and ``LinearDamper`` actuators.

        A linear spring of stiffness k and equilibrium length l0 along a pathway of length l stores
        k (l - l0)^2 / 2; a linear damper of damping c dissipates c (dl/dt)^2 >= 0.
        """
        import sympy.physics.mechanics as me

        store, dissipation = [], []
        for act in self.system.actuators:
            if isinstance(act, me.LinearSpring):
                store.append(act.stiffness * (act.pathway.length - act.equilibrium_length) ** 2 / 2)
            elif isinstance(act, me.LinearDamper):
                dissipation.append(act.damping * act.pathway.extension_velocity ** 2)
        # A pathway's extension velocity is d(length)/dt: in the speeds by dq/dt = u.
        return ([e.xreplace(self.kin.qd_to_u) for e in store],
                [e.xreplace(self.kin.qd_to_u) for e in dissipation])


@dataclass(frozen=True)
class Field:
    """A scenario field that sets one of a part's parameters (its CLI flag is ``--`` + the name, dashed).

    Attributes
    ----------
    name : str
        The :class:`whipple_kick.simulate.scenario.Scenario` field (which must exist, with ``default``).
    parameter : str
        The part's parameter it sets.
    label : str
        Words for messages ("hip stiffness").
    unit : str
    low, high : float
        Allowed range, both ends included.
    default : float
        The scenario's default.
    source : str
        Where the default comes from.
    refuse_low : str
        If given, the low end itself is refused while the part is selected, and this says why
        ("leaves a leaning upper body with nothing to hold it up").
    """

    name: str
    parameter: str
    label: str
    unit: str
    low: float
    high: float
    default: float
    source: str
    refuse_low: str = ""


@dataclass(frozen=True)
class Split:
    """How a part takes its body from the rider's Yeadon segments (:func:`whipple_kick.library.riders.split_rider`).

    The rider's segments go to the rear frame unless a part of the model carries them: the parts in their
    build order (:func:`named`) each take the segments they name, a later part from an earlier one (the arms,
    built after the trunk, take the forearms the trunk names).

    Attributes
    ----------
    segments : tuple of str
        The Yeadon segments it carries (``"P"`` pelvis, ``"A2"`` a forearm and hand ...).
    frame : str
        The benchmark body its segments are lumped into (``"H"``: the front frame, they turn with the bar), or
        ``""`` for a body of its own (then :attr:`body`).
    body : callable, optional
        ``body(bench, seat, mass, com, inertia)``: its parameters by name from its segments' mass [kg], mass
        centre (3,) [m] and inertia (3, 3) [kg m^2] about it, in the benchmark frame, ``seat`` (3,) [m] the
        rider's seat point and ``bench`` the bicycle's benchmark parameters.
    rigid : callable, optional
        ``rigid(moore, body)``: the Moore parameters with :attr:`body`'s parameters held by the rear frame, for
        a model without the part whose rider is split for another part (the rigid rider with the arms on the
        bar); without it the segments are lumped into the rear frame.
    moves_with : str
        The model's frame its segments move with, for drawings (``"G"`` the leaning upper body, ``"E"`` the
        front frame; the rest of the rider moves with the rear frame ``"C"``).
    """

    segments: tuple
    frame: str = ""
    body: Callable = None
    rigid: Callable = None
    moves_with: str = "C"

    def __post_init__(self):
        if bool(self.frame) == (self.body is not None):
            raise ValueError("a part's split lumps its segments into a frame or makes a body of its own, one of them")


@dataclass(frozen=True)
class Part:
    """One declared part of the bicycle-rider system.

    Attributes
    ----------
    name : str
        Short name (the generated model's cache key and layouts name it).
    description : str
        What it is, one line.
    source : str
        Where its mechanics and parameter meanings come from.
    symbols : tuple
        ``(name, description, unit, kind)`` rows it registers (:func:`whipple_kick.model.symbols.register`).
    coordinates, speeds : tuple of str
        Its generalised coordinates and speeds (``u = dq/dt``), appended to the system's in this order.
    parameters : tuple of str
        Its constants, appended to the parameter vector in this order (its gains included).
    gains : dict
        The rider's feedback gains on its states: gain name -> state name (``T7 = -sum(gain * state)``).
    columns : dict
        Trajectory column of each of its states: state -> (column name, unit).
    outputs : dict
        Its named outputs: name -> (unit, description); ``build`` sets each in ``Mechanics.outputs``.
    build : callable
        ``build(mechanics)``: adds its coordinates, bodies, joint, loads, energy terms and outputs.
    selected_by : tuple
        ``(scenario field, value)`` that puts the part into a run's model (``("rider_body", "leaning")``);
        empty for a part used from Python only.
    fields : tuple of Field
        The scenario fields that set its parameters (validated, given CLI flags and refused while the part
        is not selected, all from this declaration).
    title : str
        Its name in messages ("the leaning upper body").
    needs : tuple of str
        Parts it requires: a model with it and without one of them is refused (:func:`named`).
    after : tuple of str
        Parts it reads what they build from when the model has them (the arms read the hands' frame the trunk
        sets): they are built before it, whatever the order of declaration (:func:`named`).
    values : dict
        Values of its parameters that neither its fields nor its gains set (name -> value, in the units of its
        symbols; their sources cited where the part is declared): a run whose scenario selects it takes them.
        The trunk's come from the rider's segments instead (:attr:`from_rider`).
    from_rider : tuple of str
        Its parameters a run takes from the rider's segments (the upper body that
        :func:`whipple_kick.library.riders.split_rider` splits off, by the same names), where the bicycle's
        rider has them (``whipple_kick.simulate.assembly.rider_body``).
    split : Split, optional
        How it takes its body from the rider's segments (:func:`whipple_kick.library.riders.split_rider`).
    pose : callable, optional
        For a part whose segments move with a frame of its own (``split.moves_with``, the upper body's G):
        ``pose(body, states, rear_rotation, rear_origin)`` gives that frame's rotation (n, 3, 3) and origin
        (n, 3) in the ground frame at n drawn instants, from the run's body parameters by name, the part's
        states by name (n,) and the rear frame's rotation and wheel-centre origin; a point p given in the
        rear frame's axes at the part's rest (from the rear wheel centre) is drawn at ``origin + rotation @ p``
        (:func:`whipple_kick.figures.animation.build_scene`).
    """

    name: str
    description: str
    source: str
    symbols: tuple
    coordinates: tuple
    speeds: tuple
    parameters: tuple
    gains: dict
    columns: dict
    outputs: dict
    build: Callable
    selected_by: tuple = ()
    fields: tuple = ()
    title: str = ""
    needs: tuple = ()
    after: tuple = ()
    values: dict = field(default_factory=dict)
    from_rider: tuple = ()
    split: Split = None
    pose: Callable = None

    def __post_init__(self):
        if self.name in self.needs + self.after:
            raise ValueError(f"part {self.name!r} names itself among the parts it needs or is built after")
        S.register(self.symbols)
        missing = [n for n in self.coordinates + self.speeds + self.parameters if n not in S.REGISTRY]
        if missing:
            raise ValueError(f"part {self.name!r}: {missing} are neither declared by it nor registered")
        unknown = [g for g in self.gains if g not in self.parameters]
        if unknown:
            raise ValueError(f"part {self.name!r}: gains {unknown} are not among its parameters")
        unknown = [f.parameter for f in self.fields if f.parameter not in self.parameters]
        if unknown:
            raise ValueError(f"part {self.name!r}: fields set {unknown}, which are not among its parameters")
        for what, names in (("values", tuple(self.values)), ("from_rider", self.from_rider)):
            others = set(self.gains) | {f.parameter for f in self.fields} | (set(self.values) & set(self.from_rider))
            unknown = [n for n in names if n not in self.parameters or n in others]
            if unknown:
                raise ValueError(f"part {self.name!r}: {what} {unknown} are not among its parameters that nothing "
                                 "else (a gain, a field, the other of values and from_rider) sets")
        if self.fields and not self.selected_by:
            raise ValueError(f"part {self.name!r} has scenario fields but no selected_by that selects it")

    def selected(self, scenario):
        """Whether ``scenario`` puts this part into its run's model (:attr:`selected_by`; a scenario without
        that field, one not made by ``whipple_kick.simulate.scenario.with_parts``, does not)."""
        return bool(self.selected_by) and getattr(scenario, self.selected_by[0], None) == self.selected_by[1]

    def field_parameters(self, scenario):
        """The part's parameters that ``scenario``'s fields set, by name, with its :attr:`values`."""
        return {**{n: float(v) for n, v in self.values.items()},
                **{f.parameter: float(getattr(scenario, f.name)) for f in self.fields}}

    def fingerprint(self):
        """Hash of the declaration and the source of ``build`` (part of the generated code's cache key).

        ``needs`` and ``after`` change no equation: the build order they set is in the key as the order of
        the parts (:meth:`whipple_kick.model.slip.layout.Layout.fingerprint`).
        """
        text = repr((self.name, self.symbols, self.coordinates, self.speeds, self.parameters, self.gains,
                     self.outputs)) + inspect.getsource(self.build)
        return hashlib.sha256(text.encode()).hexdigest()[:12]


#: Every declared part by name, in declaration order (a model's parts take :func:`named`'s order, not this).
REGISTRY: dict = {}


def declare(part):
    """Add ``part`` to :data:`REGISTRY` (again under the same name: the later declaration) and return it."""
    REGISTRY[part.name] = part
    return part


def named(names):
    """The parts called ``names`` in the order they are built and laid out.

    Each part comes after the parts it needs or is built after (:attr:`Part.needs`, :attr:`Part.after`),
    and otherwise in the order of their names, so the order of declaration (and of ``names``) changes
    nothing. Unknown names are refused (KeyError), and so is a part whose needed part is not among
    ``names`` (:class:`~whipple_kick.errors.InputError`, one line naming both and how to select it).
    """
    unknown = [n for n in names if n not in REGISTRY]
    if unknown:
        raise KeyError(f"no declared part {unknown[0]!r}; known: {', '.join(REGISTRY) or 'none'}")
    chosen = {n: REGISTRY[n] for n in sorted(set(names))}
    for part in chosen.values():
        for need in part.needs:
            if need not in chosen:
                raise InputError(f"{_words(part)} needs {_words(need)}, which the model lacks"
                                 + (f"; select it with {_selection(need)}" if _selection(need) else ""))
    order, placed = [], set()
    while len(order) < len(chosen):
        ready = [p for n, p in chosen.items() if n not in placed
                 and all(b in placed for b in p.needs + p.after if b in chosen)]
        if not ready:
            raise ValueError(f"parts {sorted(set(chosen) - placed)} need or follow each other in a circle")
        order.append(ready[0])   # the first by name among those whose predecessors are placed
        placed.add(ready[0].name)
    return tuple(order)


def _words(part):
    """A part (or a part's name) in messages: its title and name."""
    part = REGISTRY.get(part) if isinstance(part, str) else part
    return f"{part.title or part.name} (part {part.name!r})" if part is not None else "an undeclared part"


def _selection(name):
    """How a scenario selects part ``name`` ("rider_body 'leaning'"), or "" for a part used from Python only."""
    part = REGISTRY.get(name)
    return f"{part.selected_by[0]} {part.selected_by[1]!r}" if part is not None and part.selected_by else ""


def _hinge_rotation(hip_tilt):
    """Rotation matrix whose columns are the hip frame H's axes in the rear frame C (H turned about C.y)."""
    c, s = np.cos(hip_tilt), np.sin(hip_tilt)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _parallel_axis(mass, offset):
    """Inertia [kg m^2] a point mass at ``offset`` [m] adds about the origin."""
    d = np.asarray(offset, dtype=float)
    return mass * (d @ d * np.eye(3) - np.outer(d, d))


def merge_into_rear_frame(moore, body):
    """Moore parameters with the upper body of ``body`` (the trunk's placement and inertia) in the rear frame.

    The upper body at zero lean is a rigid part of the rear frame: its mass,
    mass centre and inertia are combined with the rear frame's (Moore's
    ``mc l1 l2 ic11 ic22 ic33 ic31``, about the combined mass centre, in the
    rear frame's axes), exactly as a locked hip would hold it. For the rigid
    rider whose forearms turn with the bar (the rest of the rider is then
    the rear frame plus this upper body).

    Parameters
    ----------
    moore : mapping
        Moore parameters of the bicycle whose rear frame lacks the upper body.
    body : mapping
        At least the trunk's placement and inertia (``hip_tilt lh1 lh3 mt lt1 lt3 it11 it22 it33 it31``).

    Returns
    -------
    dict
        ``moore`` with the rear frame's seven entries replaced.
    """
    out = dict(moore)
    mc, mt = float(moore["mc"]), float(body["mt"])
    R = _hinge_rotation(float(body["hip_tilt"]))   # G = H at zero lean
    r_c = np.array([moore["l1"], 0.0, moore["l2"]], dtype=float)
    r_g = np.array([body["lh1"], 0.0, body["lh3"]], dtype=float) + R @ np.array([body["lt1"], 0.0, body["lt3"]])
    mass = mc + mt
    r = (mc * r_c + mt * r_g) / mass
    I_c = np.array([[moore["ic11"], 0.0, moore["ic31"]], [0.0, moore["ic22"], 0.0],
                    [moore["ic31"], 0.0, moore["ic33"]]], dtype=float)
    I_g = np.array([[body["it11"], 0.0, body["it31"]], [0.0, body["it22"], 0.0],
                    [body["it31"], 0.0, body["it33"]]], dtype=float)
    inertia = I_c + _parallel_axis(mc, r_c - r) + R @ I_g @ R.T + _parallel_axis(mt, r_g - r)
    out.update(mc=mass, l1=float(r[0]), l2=float(r[2]), ic11=float(inertia[0, 0]), ic22=float(inertia[1, 1]),
               ic33=float(inertia[2, 2]), ic31=float(inertia[0, 2]))
    return out


# ------------------------------------------------------------------ the trunk

_TRUNK_BODY = ("hip_tilt", "lh1", "lh3", "mt", "lt1", "lt3", "it11", "it22", "it33", "it31")


def trunk_body(lam, hinge, offset, mass, inertia):
    """The trunk's placement and inertia (:data:`_TRUNK_BODY`) from an upper body hinged on a horizontal axis.

    ``lam`` [rad] is the bicycle's steer axis tilt (Moore's rear frame C is the benchmark frame pitched by
    it: turning C about C.y by ``-lam`` makes the hinge axis H.x horizontal), ``hinge`` (x, z) [m] the hinge
    point from the rear wheel centre and ``offset`` (x, z) [m] the body's mass centre from the hinge, both in
    benchmark axes, ``mass`` [kg] and ``inertia`` (3, 3) [kg m^2] about the mass centre in benchmark axes
    (G is level with them at zero lean).
    """
    c_x, c_z = benchmark._pitch_matrix(lam)
    hinge = np.asarray(hinge, dtype=float)
    return {"hip_tilt": -lam, "lh1": float(hinge @ c_x), "lh3": float(hinge @ c_z),
            "mt": mass, "lt1": float(offset[0]), "lt3": float(offset[1]),
            "it11": float(inertia[0][0]), "it22": float(inertia[1][1]), "it33": float(inertia[2][2]),
            "it31": float(inertia[0][2])}


def _split_trunk(bench, seat, mass, com, inertia):
    """The trunk from its Yeadon segments: hinged at the rider's seat point (the top of the seat post, where
    yeadon's origin sits), Moore's (2012, ch. 4) upper-body hinge near the saddle."""
    hinge = (seat - np.array([0.0, 0.0, -bench["rR"]]))[[0, 2]]
    arm = com - seat
    return trunk_body(bench["lam"], hinge, arm[[0, 2]], mass, inertia)


def _trunk_pose(body, states, rear_rotation, rear_origin):
    """The upper body G's rotation and origin at the drawn instants (:attr:`Part.pose`).

    G is the rear frame C turned by the lean q11 about the hip axis H.x, which is C.x turned about C.y by
    ``hip_tilt``, through the hip point (``lh1``, 0, ``lh3``) in C from the rear wheel centre.
    """
    tilt = body["hip_tilt"]
    axis = np.array([math.cos(tilt), 0.0, -math.sin(tilt)])    # H.x in C (sympy's orient_axis about C.y)
    hinge = np.array([body["lh1"], 0.0, body["lh3"]])
    lean = np.asarray(states["q11"], dtype=float)
    cross = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    turn = (np.eye(3) + np.sin(lean)[:, None, None] * cross
            + (1.0 - np.cos(lean))[:, None, None] * (cross @ cross))          # Rodrigues: about H.x by q11
    rotation = rear_rotation @ turn
    origin = rear_origin + rear_rotation @ hinge - rotation @ hinge
    return rotation, origin


def _build_trunk(m):
    """The upper body G on the hip, a revolute joint about H.x (SymPy's ``PinJoint``), with its spring-damper
    (a ``TorqueActuator`` at the joint); the hands on G."""
    import sympy.physics.mechanics as me

    kin, b = m.kin, m.par
    N, C = kin.frames["N"], kin.frames["C"]
    q11, u11 = m.coordinate("q11", "u11")
    # H is fixed in the rear frame, turned about C.y by hip_tilt so that H.x can be horizontal.
    H = me.ReferenceFrame("H")
    H.orient_axis(C, C.y, b["hip_tilt"])
    G = me.ReferenceFrame("G")
    do = kin.points["do"]
    ho = do.locatenew("ho", b["lh1"] * C.x + b["lh3"] * C.z)
    ho.v2pt_theory(do, N, C)
    go = me.Point("go")
    upper_body = m.body("upper_body", go, G, b["mt"],
                        me.inertia(G, b["it11"], b["it22"], b["it33"], 0, 0, b["it31"]))
    # The joint turns G about H.x by q11 at rate u11 and puts the hip point of G (lt1, lt3 from go) on ho.
    hip = me.PinJoint("hip", m.rigid_body("rear_frame"), upper_body, coordinates=q11, speeds=u11,
                      parent_point=ho, child_point=-(b["lt1"] * G.x + b["lt3"] * G.z), parent_interframe=H,
                      joint_axis=H.x)
    go.v2pt_theory(ho, N, G)   # the joint gives go's velocity in the rear frame; Kane's method reads it in N
    m.system.add_joints(hip)   # brings q11, u11 and dq11/dt = u11
    kin.frames.update(H=H, G=G)
    kin.points.update(ho=ho, go=go)
    hip_torque = -(b["kh"] * q11 + b["ch"] * u11)   # on G about H.x, reacted on the rear frame
    m.system.add_actuators(me.TorqueActuator.at_pin_joint(hip_torque, hip))
    # The hands hold the bar from G: the bar turns relative to G about C.z by q7 - (H.x . C.z) q11
    # (H.x . C.z is constant), so the arms' spring is exact.
    axis_share = H.x.dot(C.z)
    m.hands_frame, m.hands_angle, m.hands_rate = G, axis_share * q11, axis_share * u11
    m.spring_energy.append(b["kh"] * q11**2 / 2)
    m.damper_dissipation.append(b["ch"] * u11**2)
    m.outputs["hip_torque"] = hip_torque


TRUNK = declare(Part(
    name="trunk",
    description="the rider's upper body (pelvis, trunk, head, upper arms) leaning on a hip spring-damper",
    source="Moore (2012), Human Control of a Bicycle, ch. 4 'Leaning rider extension'; segments from the "
           "rider's own Yeadon model (whipple_kick.library.riders.split_rider)",
    symbols=(
        ("q11", "rider's upper-body lean relative to the rear frame, about the hip axis H.x (positive = lean "
                "right)", "rad", "coordinate"),
        ("u11", "rate of q11: upper-body lean rate relative to the rear frame", "rad/s", "speed"),
        ("hip_tilt", "angle about C.y from the rear frame's C.x axis to the hip (lean) axis H.x: minus the steer "
                     "axis tilt puts H.x horizontal in the nominal configuration", "rad", "constant"),
        ("lh1", "hip (lean-axis) point from the rear wheel centre along C.x", "m", "constant"),
        ("lh3", "hip (lean-axis) point from the rear wheel centre along C.z", "m", "constant"),
        ("mt", "mass of the rider's upper body G", "kg", "constant"),
        ("lt1", "upper-body mass centre from the hip point along G.x", "m", "constant"),
        ("lt3", "upper-body mass centre from the hip point along G.z (negative: above the hip)", "m", "constant"),
        ("it11", "upper-body moment of inertia about its mass centre, G.x axis", "kg m^2", "constant"),
        ("it22", "upper-body moment of inertia about its mass centre, G.y axis", "kg m^2", "constant"),
        ("it33", "upper-body moment of inertia about its mass centre, G.z axis", "kg m^2", "constant"),
        ("it31", "upper-body product of inertia about its mass centre, G.z-G.x entry", "kg m^2", "constant"),
        ("kh", "hip lean stiffness: torque on the upper body about H.x per radian of q11", "N m/rad", "constant"),
        ("ch", "hip lean damping: torque on the upper body about H.x per rad/s of u11", "N m s/rad", "constant"),
        ("kq11", "steer-torque feedback gain on upper-body lean q11", "N m/rad", "constant"),
        ("ku11", "steer-torque feedback gain on upper-body lean rate u11", "N m s/rad", "constant"),
    ),
    coordinates=("q11",),
    speeds=("u11",),
    parameters=(*_TRUNK_BODY, "kh", "ch", "kq11", "ku11"),
    gains={"kq11": "q11", "ku11": "u11"},
    columns={"q11": ("upper_body_lean", "rad"), "u11": ("upper_body_lean_rate", "rad/s")},
    outputs={"hip_torque": ("N m", "torque of the hip spring-damper on the upper body about the lean axis")},
    build=_build_trunk,
    selected_by=("rider_body", "leaning"),
    fields=(
        Field("hip_stiffness", "kh", "hip stiffness", "N m/rad", 0.0, 1e6, 128.0,
              "Moore (2012, Human Control of a Bicycle, PhD thesis, UC Davis, ch. 4, 'Leaning rider extension', "
              "from de Lorenzo and Hubbard)",
              refuse_low="leaves a leaning upper body with nothing to hold it up"),
        Field("hip_damping", "ch", "hip damping", "N m s/rad", 0.0, 1e5, 50.0,
              "Moore (2012, ch. 4, 'Leaning rider extension', from de Lorenzo and Hubbard)"),
    ),
    title="the leaning upper body",
    from_rider=_TRUNK_BODY,   # the rider's own upper body: its placement on the hip and its inertia
    # Pelvis, thorax, chest-head, the upper arms and the forearms and hands (which a part the model has built
    # after it takes: the arms on the bar); the legs stay in the rear frame. Without the trunk, a rider split
    # for another part holds its upper body rigidly in the rear frame.
    split=Split(segments=("P", "T", "C", "A1", "B1", "A2", "B2"), body=_split_trunk,
                rigid=merge_into_rear_frame, moves_with="G"),
    pose=_trunk_pose,   # drawn leaning on the hip
))


# ------------------------------------------------------------------ the arms

def _build_arms(m):
    """The arms' spring-damper about the steer axis, between the bar E and the frame the hands hold.

    Built after the trunk when the model has it (``after=("trunk",)``), so the hands' frame is the upper
    body's when it leans.
    """
    import sympy.physics.mechanics as me

    kin, b = m.kin, m.par
    C, E = kin.frames["C"], kin.frames["E"]
    # The bar turns relative to the hands' frame by q7 less that frame's own turn about C.z (exact).
    arm_angle = S.dyn("q7") - m.hands_angle
    arm_rate = S.dyn("u7") - m.hands_rate
    arm_torque = -(b["ka"] * arm_angle + b["ca"] * arm_rate)   # on the bar E about C.z, reacted on the hands
    m.system.add_actuators(me.TorqueActuator(arm_torque, C.z, E, m.hands_frame))
    m.spring_energy.append(b["ka"] * arm_angle**2 / 2)
    m.damper_dissipation.append(b["ca"] * arm_rate**2)
    m.outputs["arm_steer_torque"] = arm_torque


ARMS = declare(Part(
    name="arms",
    description="the rider's arms holding the bar: a spring-damper about the steer axis between the bar and the "
                "frame the hands hold (the forearms' mass turns with the bar)",
    source="Moore (2012), Human Control of a Bicycle, ch. 4 (the arms as a passive steer impedance); forearms "
           "from the rider's own Yeadon model (whipple_kick.library.riders.split_rider)",
    symbols=(
        ("ka", "arm stiffness about the steer axis: torque on the bar per radian of the bar's rotation relative "
               "to the frame the hands hold (the upper body, or the rear frame without one)", "N m/rad", "constant"),
        ("ca", "arm damping about the steer axis, per rad/s of the bar's rotation relative to the hands' frame",
         "N m s/rad", "constant"),
    ),
    coordinates=(),
    speeds=(),
    parameters=("ka", "ca"),
    gains={},
    columns={},
    outputs={"arm_steer_torque": ("N m", "passive torque of the rider's arms on the bar about the steer axis")},
    build=_build_arms,
    selected_by=("arms", "on"),
    fields=(
        Field("arm_stiffness", "ka", "arm stiffness", "N m/rad", 0.0, 1e5, 0.0,
              "no published value was at hand (docs/experiments.md, the identification of the rider's body)"),
        Field("arm_damping", "ca", "arm damping", "N m s/rad", 0.0, 1e4, 0.0,
              "no published value was at hand (docs/experiments.md, the identification of the rider's body)"),
    ),
    title="the arms on the bar",
    after=("trunk",),   # the hands hold the upper body when it leans: the trunk sets the hands' frame first
    # The forearms and hands turn with the bar (their inertia about the steer axis is the arms' inertia
    # moving with it): lumped into the benchmark front frame H.
    split=Split(segments=("A2", "B2"), frame="H", moves_with="E"),
))


def selected(scenario):
    """The declared parts ``scenario`` puts into its run's model."""
    return tuple(p for p in REGISTRY.values() if p.selected(scenario))


def fields():
    """Every declared part's scenario fields, in declaration order."""
    return tuple(f for p in REGISTRY.values() for f in p.fields)
