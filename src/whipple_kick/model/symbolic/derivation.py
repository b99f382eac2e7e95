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

from whipple_kick.model import parts
from whipple_kick.model import symbols as S


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
        compressions q9 (rear) and q10 (front) as extra coordinates (the
        rider's parts add theirs: :mod:`whipple_kick.model.parts`).

    Returns
    -------
    Kinematics
    """
    names_q = [f"q{i}" for i in range(1, 11 if tyre_model else 9)]
    q = S.dyns(names_q)
    u = S.dyns([n.replace("q", "u") for n in names_q])
    q1, q2, q3, q4, q5, q6, q7, q8 = q[:8]
    u1, u2, u3, u4, u5, u6, u7, u8 = u[:8]
    qd_to_u = {qi.diff(me.dynamicsymbols._t): ui for qi, ui in zip(q, u, strict=True)}
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

    frames = dict(N=N, A=A, B=B, C=C, D=D, E=E, F=F)
    points = dict(O=O, dn=dn, do=do, co=co, ce=ce, fo=fo, eo=eo, fn=fn, dn_mat=dn_mat, fn_mat=fn_mat)
    return Kinematics(
        q=q, u=u,
        frames=frames,
        points=points,
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
    kdes = [qi.diff(me.dynamicsymbols._t) - ui for qi, ui in zip(kin.q, kin.u, strict=True)]
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
    a0 = rows.subs(dict.fromkeys(u, 0))   # rows are linear in u
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


def kick_plate_motion(t):
    """Prescribed lateral motion of the kick plate: (y, dy/dt, d2y/dt2) as SymPy expressions.

    Profile 0 (thesis Section 8.4): constant acceleration ``2 D / T^2`` from
    ``kick_t0`` for ``kick_T`` seconds, then held at ``D`` (the plate stops
    instantly, as in the thesis' Figure 8.5). Profile 1: minimum-jerk quintic
    ``D (10 s^3 - 15 s^4 + 6 s^5)``, ``s = (t - t0)/T``, with finite jerk.
    Profile 2: one cubic segment ``c0 + c1 tau + c2 tau^2 + c3 tau^3``,
    ``tau = t - t0``, at all times; a tabulated y(t) is followed exactly by
    integrating one spline segment at a time with its coefficients.
    """
    t0, T, D, profile = S.syms(["kick_t0", "kick_T", "kick_D", "kick_profile"])
    c0, c1, c2, c3 = S.syms(["kick_c0", "kick_c1", "kick_c2", "kick_c3"])
    tau = t - t0
    s = tau / T
    acc = 2 * D / T**2
    const = (acc * tau**2 / 2, acc * tau, acc)
    smooth = (D * (10 * s**3 - 15 * s**4 + 6 * s**5),
              D * (30 * s**2 - 60 * s**3 + 30 * s**4) / T,
              D * (60 * s - 180 * s**2 + 120 * s**3) / T**2)
    segment = (c0 + c1 * tau + c2 * tau**2 + c3 * tau**3, c1 + 2 * c2 * tau + 3 * c3 * tau**2,
               2 * c2 + 6 * c3 * tau)
    out = []
    for k in range(3):
        after = D if k == 0 else sm.S(0)
        moving = sm.Piecewise((const[k], profile < sm.Rational(1, 2)), (smooth[k], True))
        once = sm.Piecewise((sm.S(0), tau < 0), (moving, tau < T), (after, True))
        out.append(sm.Piecewise((segment[k], profile > sm.Rational(3, 2)), (once, True)))
    return tuple(out)


def normal_force(compression, compression_rate, stiffness, damping):
    """Normal force of a tyre's vertical spring-damper: never pulling, zero off the ground.

    ``max(0, kz q + cz dq/dt)`` while the tyre is compressed (q > 0); 0 when
    it is not (q <= 0): a lifted wheel carries no force, however fast it
    closes on the ground (the damper acts only in contact).

    Parameters
    ----------
    compression, compression_rate : sympy.Expr
        Tyre compression q [m] and its rate dq/dt [m/s].
    stiffness, damping : sympy.Expr
        Vertical stiffness kz [N/m] and damping cz [N s/m].

    Returns
    -------
    sympy.Expr
        The normal force [N].

    Example
    -------
    >>> import sympy as sm
    >>> q, dq = sm.symbols("q dq", real=True)
    >>> fz = normal_force(q, dq, 1e5, 300.0)
    >>> float(fz.subs({q: -0.01, dq: 5.0})), float(fz.subs({q: 0.004, dq: 0.0}))
    (0.0, 400.0)
    """
    return sm.Piecewise((sm.Max(0, stiffness * compression + damping * compression_rate), compression > 0),
                        (0, True))


def _slip_speed(centre_vel, contact_vel, heading, contact_weight):
    """Forward speed along ``heading``: the wheel centre's, or with ``contact_weight`` 1 the contact point's."""
    centre = centre_vel.dot(heading)
    return centre + contact_weight * (contact_vel.dot(heading) - centre)


def take_parts(kin, mech, chosen):
    """Read what the parts ``chosen`` built into ``mech.system`` (:class:`whipple_kick.model.parts.Mechanics`)
    into ``kin``: their coordinates and speeds after the bicycle's, their bodies with their weights.

    The system's coordinates and speeds must be the parts' declared ones in the parts' order, and its
    kinematic differential equations ``dq/dt = u`` (the convention of every speed here); a build that adds
    others is refused (ValueError naming them).
    """
    system = mech.system
    t = me.dynamicsymbols._t
    q, u = tuple(system.q), tuple(system.u)
    for what, got, declared in (("coordinates", q, [n for p in chosen for n in p.coordinates]),
                                ("speeds", u, [n for p in chosen for n in p.speeds])):
        names = [s.func.__name__ for s in got]
        if names != declared:
            raise ValueError(f"the parts' builds gave the system the {what} {names}; they declare {declared}")
    rates = sm.solve(list(system.kdes), [qi.diff(t) for qi in q], dict=True) if q else [{}]
    if len(rates) != 1 or any(sm.simplify(rates[0].get(qi.diff(t), sm.nan) - ui) != 0
                              for qi, ui in zip(q, u, strict=True)):
        raise ValueError(f"the parts' kinematic differential equations {list(system.kdes)} are not "
                         f"dq/dt = u for {[s.func.__name__ for s in q]}")
    kin.q, kin.u = (*kin.q, *q), (*kin.u, *u)
    kin.qd_to_u.update({qi.diff(t): ui for qi, ui in zip(q, u, strict=True)})
    g, down = mech.par["g"], kin.frames["N"].z
    for body in mech.added_bodies():   # every body a part adds has its weight
        kin.bodies.append(body)
        kin.gravity_loads.append((body.masscenter, body.mass * g * down))


def slip_equations(part_names=()):
    """Derive the slip model: toroidal tyres, vertical compliance, lateral tyre loads as inputs.

    Constraints: rolling without longitudinal slip at both wheels (the rear
    relative to the kick plate, less a constant imposed slide ``vsx_r``,
    normally 0) and the front contact on the ground.
    Dependent speeds u5 (pitch rate), u6, u8 (wheel spin rates);
    independent u1, u2, u3, u4, u7, u9, u10 and the parts' speeds. The
    rider is in the rear frame and holds the bar through the arms'
    spring-damper about the steer axis; each part of ``part_names``
    (:mod:`whipple_kick.model.parts`, e.g. ``"trunk"``: the upper body
    leaning on the hip, which then holds the bar) adds its coordinates,
    bodies, joint and loads. The lateral forces and aligning
    moments the tyres apply (``Fy_r Fy_f Mz_r Mz_f``) stay symbols here:
    Kane's forcing is linear in them, and the tyre's transient form
    (:mod:`whipple_kick.model.transient`) computes them from its own states and
    the kinematic quantities in ``extra``.

    Parameters
    ----------
    part_names : tuple of str
        Declared parts to include (:data:`whipple_kick.model.parts.REGISTRY`).

    Returns
    -------
    EquationsOfMotion
        ``inputs`` = (plate velocity, plate acceleration, Fy_r, Fy_f, Mz_r,
        Mz_f); ``extra`` holds named expressions: the tyre block's inputs
        (``vsy_* vx_* camber_* fz_*``), the power kinematics (``vplate_r``
        plate velocity along the rear lateral axis, ``wz_*`` wheel rates
        about the ground normal), the plate motion ``yp vp ap``, the steer
        torque ``T7``, the spring energy and the damper dissipation rate
        (the normal force acts on the material contact points, whose
        velocity along the ground normal is u9 and u10: at the rear by the
        geometry, checked symbolically, at the front by the constraint).
    """
    kin = kinematics(tyre_model=True)
    N, A, C, D, E, F = (kin.frames[k] for k in "NACDEF")
    chosen = parts.named(part_names)
    par = {n: S.sym(n) for n in S.SLIP_CONSTANTS + tuple(n for p in chosen for n in p.parameters)}
    mech = parts.Mechanics(kin=kin, par=par, hands_frame=C)
    for part in chosen:
        part.build(mech)
    take_parts(kin, mech, chosen)
    q, u = kin.q, kin.u
    Q = {qi.func.__name__: qi for qi in q}
    U = {ui.func.__name__: ui for ui in u}
    Fy_r, Fy_f, Mz_r, Mz_f = S.syms(["Fy_r", "Fy_f", "Mz_r", "Mz_f"])
    yp, vp, ap = kick_plate_motion(sm.Symbol("t", real=True))
    vp_s, ap_s = S.syms(["vp", "ap"])   # placeholders, replaced by the profile at code generation

    # Normal forces: linear spring-damper on the compression, never pulling,
    # and only while the tyre touches the ground (q > 0): a lifted wheel
    # closing on the ground must not be pushed by its damper before contact.
    fz_r, fz_f = (normal_force(Q[q], U[u], par[kz], par[cz])
                  for q, u, kz, cz in (("q9", "u9", "kzr", "czr"), ("q10", "u10", "kzf", "czf")))

    # The rider's active steer torque: the voluntary full-state feedback T = -K x
    # (LQR convention), on the bicycle's states and the parts' (their declared gains),
    # plus the delayed reflex torque, which the compiled code computes from the delay
    # filter's states (whipple_kick.model.reflex).
    T_reflex = S.sym("T_reflex")
    gains = {"kq4": "q4", "kq7": "q7", "ku4": "u4", "ku7": "u7", "kq3": "q3", "ku3": "u3"}
    for part in chosen:
        gains.update(part.gains)
    T7 = -sum(par[g] * (Q | U)[state] for g, state in gains.items()) + T_reflex
    # The reflex acts on what the rider feels, undelayed here; the filter delays it.
    reflex_input = -(par["rq4"] * Q["q4"] + par["rq7"] * Q["q7"] + par["ru4"] * U["u4"] + par["ru7"] * U["u7"])
    T6 = par["T6c"]
    # The rider's torque acts between the bar E and the frame the hands hold (the
    # rear frame, or a part's: the leaning upper body), about the steer axis C.z.
    # The bar turns relative to that frame by q7 less the frame's own turn about
    # C.z (exact), and the torque's power is the torque times this relative rate.
    # (The arms' spring-damper, a part, acts between the same two frames.)
    steer_relative_rate = U["u7"] - mech.hands_rate

    dn_mat, fn_mat = kin.points["dn_mat"], kin.points["fn_mat"]
    loads = list(kin.gravity_loads)
    loads += [
        (dn_mat, -fz_r * A.z + Fy_r * kin.rear_lateral),
        (fn_mat, -fz_f * A.z + Fy_f * kin.front_lateral),
        (D, Mz_r * A.z + T6 * C.y),
        (F, Mz_f * A.z),
        (C, -T6 * C.y),
        (mech.hands_frame, -T7 * C.z),
        (E, T7 * C.z),
        *mech.loads(),
    ]
    mass_matrix, forcing = kane_full(kin, loads)

    # Velocities relative to the ground under each wheel (the rear one moves).
    plate_vel = vp_s * N.y
    v_r_slide = dn_mat.vel(N) - plate_vel
    v_f_slide = fn_mat.vel(N)
    rows = [
        # vsx_r: an imposed constant longitudinal slide (0: rolling without
        # slip); only the published code's plate stop makes it non-zero.
        v_r_slide.dot(kin.rear_heading) - par["vsx_r"],
        fn_mat.vel(N).dot(kin.front_heading_scaled),
        kin.holonomic_rate,
    ]
    A_c, a0, b = constraint_terms(rows, kin, time_terms={vp_s: ap_s})

    # Spring energy counts only while the tyre is compressed; the damper
    # dissipates Fz dq/dt - kz max(q, 0) dq/dt >= 0 in every branch of
    # normal_force (docs/validation.md).
    # The parts' springs (the hip's, the arms', the system's LinearSprings) store energy, their dampers
    # dissipate it.
    store, dissipation = mech.actuator_energy()
    spring = ((par["kzr"] * sm.Max(0, Q["q9"])**2 + par["kzf"] * sm.Max(0, Q["q10"])**2) / 2
              + sum(mech.spring_energy) + sum(store))
    damper = (fz_r * U["u9"] - par["kzr"] * sm.Max(0, Q["q9"]) * U["u9"]
              + fz_f * U["u10"] - par["kzf"] * sm.Max(0, Q["q10"]) * U["u10"]
              + sum(mech.damper_dissipation) + sum(dissipation))
    extra = {
        "yp": yp, "vp": vp, "ap": ap,
        # Inputs of the tyre block (model convention: slip > 0 slides to the
        # right, camber > 0 leans right), rolling speeds along each heading.
        "vsy_r": v_r_slide.dot(kin.rear_lateral), "vsy_f": v_f_slide.dot(kin.front_lateral),
        # The forward speed the slip angle and the relaxation use: the wheel
        # centre's (slip_speed_point 0, the default) or the geometric contact
        # point's (1, as the thesis authors' published code takes it).
        "vx_r": _slip_speed(kin.points["do"].vel(N) - plate_vel, kin.points["dn"].vel(N) - plate_vel,
                            kin.rear_heading, par["slip_speed_point"]),
        "vx_f": _slip_speed(kin.points["fo"].vel(N),
                            kin.points["fn"].pos_from(kin.points["O"]).dt(N).xreplace(kin.qd_to_u),
                            kin.front_heading, par["slip_speed_point"]),
        "camber_r": sm.asin(kin.frames["B"].y.dot(A.z)), "camber_f": sm.asin(E.y.dot(A.z)),
        "fz_r": fz_r, "fz_f": fz_f,
        # Power kinematics of the energy accounting.
        "vplate_r": plate_vel.dot(kin.rear_lateral),
        "wz_r": D.ang_vel_in(N).dot(A.z), "wz_f": F.ang_vel_in(N).dot(A.z),
        "T7": T7, "spring_energy": spring, "damper_dissipation_rate": damper,
        "steer_relative_rate": steer_relative_rate, "reflex_input": reflex_input,
        **mech.outputs,
    }
    return EquationsOfMotion(
        q=q, u=u, dependent=("u5", "u6", "u8"), inputs=(vp_s, ap_s, Fy_r, Fy_f, Mz_r, Mz_f),
        mass_matrix=mass_matrix, forcing=forcing,
        constraint_matrix=A_c, constraint_offset=a0, constraint_accel=b,
        holonomic=kin.holonomic,
        kinetic_energy=kinetic_energy(kin), potential_energy=potential_energy(kin),
        extra=extra,
    )
