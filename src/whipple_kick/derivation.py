"""Symbolic derivation of the bicycle's equations of motion by Kane's method.

Both models in whipple_kick come from one kinematic description
(:func:`kinematics`):

* the **classic** Carvallo-Whipple model: knife-edge wheels rolling without
  slip, longitudinally and laterally;
* the **slip** model: toroidal tyres with vertical compression coordinates,
  rolling without longitudinal slip only, lateral force and self-aligning
  moment from the tyre model.

How Kane's method is applied
----------------------------
Kane's equations with dependent speeds read ``T^T (F_r + F_r^*) = 0``, where
``F_r`` and ``F_r^*`` are the generalised active and inertia forces for the
full set of speeds ``u`` (here ``u_i = dq_i/dt``) and ``T`` maps the
independent speeds to all speeds through the velocity constraints
``A(q) u + a0 = 0``. SymPy's :class:`~sympy.physics.mechanics.KanesMethod`
forms ``F_r + F_r^*`` for the full set of speeds, giving
``M(q) du/dt = f(q, u, inputs)``; the constraint elimination (``T``) is done
numerically at evaluation time, from the symbolic constraint matrix ``A``,
its offset ``a0`` and the acceleration-constraint remainder ``b``:

    A du/dt + b = 0,   b = d/dt(A) u + d/dt(a0).

Solving the constraints symbolically (Cramer's rule) makes the expressions
explode; solving them numerically with a pivoted LU is exact to round-off,
fast, and keeps the derivation under a minute.
"""
from dataclasses import dataclass, field

import sympy as sm
import sympy.physics.mechanics as me

from . import symbols as S


@dataclass
class Kinematics:
    """Frames, points and kinematic quantities shared by both models."""

    q: tuple          # generalised coordinates (dynamicsymbols)
    u: tuple          # generalised speeds, u_i = dq_i/dt
    frames: dict      # N, A, B, C, D, E, F
    points: dict      # O, dn, do, co, ce, fo, eo, fn, dn_mat, fn_mat
    holonomic: sm.Expr            # front contact height above ground (z down): must be 0
    rear_heading: me.Vector       # unit, ground plane, along the rear wheel's heading
    rear_lateral: me.Vector       # unit, ground plane, to the right of the rear heading
    front_heading: me.Vector
    front_lateral: me.Vector
    front_heading_scaled: me.Vector   # front_heading * |E.y x A.z| (no square root)
    front_lateral_scaled: me.Vector
    holonomic_rate: sm.Expr       # d(holonomic)/dt, linear in the speeds
    qd_to_u: dict                 # {dq_i/dt: u_i}
    bodies: list = field(default_factory=list)
    gravity_loads: list = field(default_factory=list)


def kinematics(tyre_model=False):
    """Build Moore's frames and points.

    Parameters
    ----------
    tyre_model : bool
        False: knife-edge wheels, coordinates q1..q8 (classic model).
        True: toroidal tyres of crown radii ``rtr``/``rtf`` with vertical
        compressions q9 (rear) and q10 (front) as extra coordinates.

    Returns
    -------
    Kinematics
    """
    names_q = [f"q{i}" for i in range(1, 11 if tyre_model else 9)]
    q = S.dyns(names_q)
    u = S.dyns([n.replace("q", "u") for n in names_q])
    q1, q2, q3, q4, q5, q6, q7, q8 = q[:8]
    u1, u2, u3, u4, u5, u6, u7, u8 = u[:8]
    qd_to_u = {qi.diff(me.dynamicsymbols._t): ui for qi, ui in zip(q, u)}
    p = {n: S.sym(n) for n in S.CLASSIC_CONSTANTS}

    N = me.ReferenceFrame("N")
    A = me.ReferenceFrame("A")
    B = me.ReferenceFrame("B")
    C = me.ReferenceFrame("C")
    D = me.ReferenceFrame("D")
    E = me.ReferenceFrame("E")
    F = me.ReferenceFrame("F")
    A.orient_axis(N, N.z, q3)
    B.orient_axis(A, A.x, q4)
    C.orient_axis(B, B.y, q5)
    D.orient_axis(C, C.y, q6)
    E.orient_axis(C, C.z, q7)
    F.orient_axis(E, E.y, q8)
    # Angular velocities written directly in the speeds keeps them compact.
    A.set_ang_vel(N, u3 * N.z)
    B.set_ang_vel(A, u4 * A.x)
    C.set_ang_vel(B, u5 * B.y)
    D.set_ang_vel(C, u6 * C.y)
    E.set_ang_vel(C, u7 * C.z)
    F.set_ang_vel(E, u8 * E.y)

    O = me.Point("O")
    O.set_vel(N, 0)
    dn = O.locatenew("dn", q1 * N.x + q2 * N.y)   # rear contact (geometric), on the ground
    dn.set_vel(N, u1 * N.x + u2 * N.y)

    if tyre_model:
        rtr, rtf = S.sym("rtr"), S.sym("rtf")
        q9, q10 = q[8], q[9]
        # Wheel centre: up the ground normal by the crown radius less the
        # compression, then up the wheel plane by the crown circle's radius.
        do = dn.locatenew("do", -(rtr - q9) * A.z - (p["rr"] - rtr) * B.z)
        do.set_vel(N, dn.vel(N) + do.pos_from(dn).dt(N).subs(qd_to_u))
    else:
        do = dn.locatenew("do", -p["rr"] * B.z)
        do.set_vel(N, dn.vel(N) + do.pos_from(dn).dt(N).subs(qd_to_u))

    co = do.locatenew("co", p["l1"] * C.x + p["l2"] * C.z)
    co.v2pt_theory(do, N, C)
    ce = do.locatenew("ce", p["d1"] * C.x)
    ce.v2pt_theory(do, N, C)
    fo = ce.locatenew("fo", p["d2"] * E.z + p["d3"] * E.x)
    fo.v2pt_theory(ce, N, E)
    eo = fo.locatenew("eo", p["l3"] * E.x + p["l4"] * E.z)
    eo.v2pt_theory(fo, N, E)

    # Unit vector in the front wheel plane pointing most nearly down: the
    # direction from the wheel centre to the lowest point of the rim circle.
    ey_az = E.y.dot(A.z)
    horiz = sm.sqrt(1 - ey_az**2)
    down_in_plane = (A.z - ey_az * E.y) / horiz
    if tyre_model:
        fn = fo.locatenew("fn", (p["rf"] - rtf) * down_in_plane + (rtf - q10) * A.z)
    else:
        fn = fo.locatenew("fn", p["rf"] * down_in_plane)
    holonomic = fn.pos_from(dn).dot(A.z)

    # Material points of the wheels at the contacts: forces act here and the
    # no-slip constraints are on their velocities.
    dn_mat = me.Point("dn_mat")
    dn_mat.set_pos(dn, 0)
    dn_mat.set_vel(N, do.vel(N) + D.ang_vel_in(N).cross(dn.pos_from(do)))
    fn_mat = me.Point("fn_mat")
    fn_mat.set_pos(fn, 0)
    fn_mat.set_vel(N, fo.vel(N) + F.ang_vel_in(N).cross(fn.pos_from(fo)))

    front_heading = E.y.cross(A.z) / horiz
    front_lateral = A.z.cross(front_heading)
    # The same directions scaled by |E.y x A.z|: free of square roots, used
    # for the constraint rows (scaling a constraint row does not change it,
    # and keeps its time derivative small).
    front_heading_scaled = E.y.cross(A.z)
    front_lateral_scaled = A.z.cross(front_heading_scaled)

    # Rate of the holonomic constraint. The material point of the wheel at
    # the contact moves vertically exactly as the lowest point of the rim
    # (or of the tyre's crown) does, because the surface is horizontal there;
    # with a compliant tyre the contact point sits q10 above that lowest point.
    holonomic_rate = fn_mat.vel(N).dot(A.z) - (u[9] if tyre_model else 0)

    bodies, gravity = [], []
    for name, frame, point, mass, inertia in (
        ("rear_frame", C, co, "mc", me.inertia(C, p["ic11"], p["ic22"], p["ic33"], 0, 0, p["ic31"])),
        ("rear_wheel", D, do, "md", me.inertia(C, p["id11"], p["id22"], p["id11"])),
        ("front_frame", E, eo, "me", me.inertia(E, p["ie11"], p["ie22"], p["ie33"], 0, 0, p["ie31"])),
        ("front_wheel", F, fo, "mf", me.inertia(E, p["if11"], p["if22"], p["if11"])),
    ):
        bodies.append(me.RigidBody(name, point, frame, p[mass], (inertia, point)))
        gravity.append((point, p[mass] * p["g"] * N.z))

    return Kinematics(
        q=q, u=u,
        frames=dict(N=N, A=A, B=B, C=C, D=D, E=E, F=F),
        points=dict(O=O, dn=dn, do=do, co=co, ce=ce, fo=fo, eo=eo, fn=fn,
                    dn_mat=dn_mat, fn_mat=fn_mat),
        holonomic=holonomic,
        rear_heading=A.x, rear_lateral=A.y,
        front_heading=front_heading, front_lateral=front_lateral,
        front_heading_scaled=front_heading_scaled, front_lateral_scaled=front_lateral_scaled,
        holonomic_rate=holonomic_rate,
        qd_to_u=qd_to_u, bodies=bodies, gravity_loads=gravity,
    )


@dataclass
class EquationsOfMotion:
    """Everything the numeric evaluation needs, as SymPy expressions.

    ``mass_matrix @ du/dt = forcing`` are Kane's equations for the full set of
    speeds (no constraint forces); ``constraint_matrix @ u + constraint_offset
    = 0`` are the velocity constraints and ``constraint_matrix @ du/dt +
    constraint_accel = 0`` their time derivative.
    """

    q: tuple
    u: tuple
    dependent: tuple              # names of the dependent speeds
    inputs: tuple                 # input symbols appearing in forcing
    mass_matrix: sm.Matrix
    forcing: sm.Matrix
    constraint_matrix: sm.Matrix
    constraint_offset: sm.Matrix
    constraint_accel: sm.Matrix
    holonomic: sm.Expr
    kinetic_energy: sm.Expr
    potential_energy: sm.Expr
    extra: dict = field(default_factory=dict)   # named output expressions


def kane_full(kin, loads):
    """Kane's ``F_r + F_r^* = 0`` for all speeds: returns (mass matrix, forcing)."""
    kdes = [qi.diff(me.dynamicsymbols._t) - ui for qi, ui in zip(kin.q, kin.u)]
    kane = me.KanesMethod(kin.frames["N"], q_ind=list(kin.q), u_ind=list(kin.u), kd_eqs=kdes)
    kane.kanes_equations(kin.bodies, loads)
    return kane.mass_matrix, kane.forcing


def constraint_terms(rows, kin, time_terms=None):
    """Split velocity constraints ``rows`` (linear in u) into A, a0 and the acceleration remainder b.

    Parameters
    ----------
    rows : list of sympy.Expr
        Velocity constraint expressions, linear in the speeds.
    kin : Kinematics
    time_terms : dict, optional
        ``{symbol: its time derivative}`` for prescribed inputs appearing in
        the constraint offset (e.g. the kick-plate velocity ``vp: ap``).
    """
    u = sm.Matrix(kin.u)
    q = sm.Matrix(kin.q)
    rows = sm.Matrix(rows)
    A = rows.jacobian(u)
    a0 = rows.subs({ui: 0 for ui in u})   # rows are linear in u
    # d/dt(A u + a0) with dq/dt = u: (d(A u + a0)/dq) u + d(a0)/dt|explicit inputs.
    b = (A * u + a0).jacobian(q) * u
    for s, sdot in (time_terms or {}).items():
        b += a0.diff(s) * sdot
    return A, a0, b


def potential_energy(kin):
    """Gravitational potential energy (z down, so height = -z)."""
    N = kin.frames["N"]
    O = kin.points["O"]
    # weight (force . N.z = m g) times height (-z)
    return sum(force.dot(N.z) * (-point.pos_from(O).dot(N.z)) for point, force in kin.gravity_loads)


def kinetic_energy(kin):
    """Kinetic energy of the four bodies."""
    N = kin.frames["N"]
    return sum(body.kinetic_energy(N) for body in kin.bodies)


def classic_equations():
    """Derive the classic Carvallo-Whipple model (both wheels roll without slip).

    Inputs: roll torque ``T4`` (on the rear frame, from the ground), rear wheel
    torque ``T6`` and steer torque ``T7`` (between rear and front frame).
    Dependent speeds: u1, u2, u3, u5, u8; independent: u4, u6, u7.
    """
    kin = kinematics(tyre_model=False)
    N, A, C, D, E = (kin.frames[k] for k in "NACDE")
    T4, T6, T7 = S.syms(["T4", "T6", "T7"])
    loads = list(kin.gravity_loads)
    loads += [
        (C, T4 * A.x - T6 * C.y - T7 * C.z),
        (D, T6 * C.y),
        (E, T7 * C.z),
    ]
    mass_matrix, forcing = kane_full(kin, loads)
    v_r = kin.points["dn_mat"].vel(N)
    v_f = kin.points["fn_mat"].vel(N)
    rows = [
        v_r.dot(kin.rear_heading),
        v_r.dot(kin.rear_lateral),
        v_f.dot(kin.front_heading_scaled),
        v_f.dot(kin.front_lateral_scaled),
        kin.holonomic_rate,
    ]
    A_c, a0, b = constraint_terms(rows, kin)
    return EquationsOfMotion(
        q=kin.q, u=kin.u, dependent=("u1", "u2", "u3", "u5", "u8"),
        inputs=(T4, T6, T7),
        mass_matrix=mass_matrix, forcing=forcing,
        constraint_matrix=A_c, constraint_offset=a0, constraint_accel=b,
        holonomic=kin.holonomic,
        kinetic_energy=kinetic_energy(kin), potential_energy=potential_energy(kin),
    )
