"""The slip model linearised in the heading frame (finite differences or from one compiled Jacobian)."""
import functools

import numpy as np

from whipple_kick.errors import InputError
from whipple_kick.model import transient
import whipple_kick.model.slip.layout as layouts  # the module by its full name, not through the package

from .call import CompiledRHS
from .layout import (
    OUT,
    PATCH_STATES,
    SPEEDS,
    STATE_NAMES,
    P,
    X,
    tyre_state_names,
)

# ---------------------------------------------------------------- linearisation

#: States of the linearisation in the heading frame: every dynamic state
#: except the ignorable position q1, q2 and wheel angles q6, q8, the yaw angle
#: q3 (the model is invariant to heading while the plate is at rest), the
#: dependent pitch q5, with the rear-contact velocity [m/s] resolved in the
#: heading frame: ``v_fwd`` along N.x and ``v_lat`` along N.y, both turned by
#: the yaw angle q3 about N.z (N.z points down, so ``v_lat`` > 0 is a drift to
#: the right). The last four are the tyre slots, named here for the default
#: transient form (:func:`linear_states` names them for any). See :func:`linearize`.
LINEAR_STATES = ("q4", "q7", "q9", "q10", "v_fwd", "v_lat", "u3", "u4", "u7", "u9", "u10") + PATCH_STATES


def linear_states(name=transient.DEFAULT_TRANSIENT):
    """:data:`LINEAR_STATES` with the tyre slots named for the transient form ``name``."""
    return LINEAR_STATES[:-len(PATCH_STATES)] + tyre_state_names(name)


def body_states(model):
    """The rider body's states a linearisation of ``model`` includes, after :data:`LINEAR_STATES`.

    The model's parts' states (the leaning upper body's lean and its rate);
    the reflex filter's states when the delay is not 0 (a zero delay's states
    drive nothing and stay put: they would only add zero eigenvalues).

    Parameters
    ----------
    model : CompiledRHS or whipple_kick.model.slip.description.Parameters
        The compiled model, or its parameters (with their model).
    """
    L = model.layout if isinstance(model, CompiledRHS) else model.model.layout
    return L.PART_STATES + L.REFLEX_STATES


def solve_pitch(rhs, x, tol=1e-14, max_iter=30):
    """Return ``x`` with q5 re-solved so the front contact is on the ground (Newton)."""
    x = np.array(x, dtype=float)
    h_step = 1e-7
    pitch, holonomic = X["q5"], OUT["holonomic"]
    for _ in range(max_iter):
        h = rhs.outputs_view(0.0, x)[1][holonomic]
        xp = x.copy()
        xp[pitch] += h_step
        slope = (rhs.outputs_view(0.0, xp)[1][holonomic] - h) / h_step
        step = h / slope
        x[pitch] -= step
        if abs(step) < tol:
            return x
    raise FloatingPointError(f"pitch did not converge (last step {abs(step):.3g} rad)")


def heading_state(x):
    """The :data:`LINEAR_STATES` values of a full state ``x`` (velocities along the heading)."""
    c, s = np.cos(x[X["q3"]]), np.sin(x[X["q3"]])
    u1, u2 = x[X["u1"]], x[X["u2"]]
    z = np.asarray(x, dtype=float)[_HEADING_SLOTS]   # v_fwd, v_lat (u1, u2 there) are set below
    z[LINEAR_STATES.index("v_fwd")] = c * u1 + s * u2
    z[LINEAR_STATES.index("v_lat")] = -s * u1 + c * u2
    return z


def _heading_derivative(rhs, x_ref, z, t, resolve_pitch):
    """d/dt of the heading-frame state ``z`` (yaw set to 0; pitch re-solved if a coordinate moved)."""
    x = np.array(x_ref, dtype=float)
    x[X["q3"]] = 0.0
    x[_HEADING_SLOTS] = z   # v_fwd, v_lat into u1, u2 (yaw 0), the others into their own slots
    if resolve_pitch:
        x = solve_pitch(rhs, x)
    dx = rhs(t, x)
    u1, u2, u3 = x[_U1], x[_U2], x[_U3]
    rates = dx[_HEADING_SLOTS]
    # Rotating-frame rates at q3 = 0: d(v_fwd)/dt = u1' + u3 u2, d(v_lat)/dt = u2' - u3 u1.
    rates[_I_FWD] = dx[_U1] + u3 * u2
    rates[_I_LAT] = dx[_U2] - u3 * u1
    return rates


def linearize(rhs, x, step=1e-7, t=0.0, columns=None):
    """Jacobian of the slip model in the heading frame, about the state ``x``.

    Resolving the rear-contact velocity along the heading removes the yaw
    angle from the equations (the plate must be at rest), so a steady turn,
    which rotates u1 and u2, is an equilibrium of the linearised system and
    its eigenvalues are exact. States :data:`LINEAR_STATES`; perturbed
    coordinates re-solve the pitch so every evaluated state satisfies the
    holonomic constraint. Central differences.

    Parameters
    ----------
    rhs : CompiledRHS
    x : array_like
        Full state (e.g. ``SteadyState.x``); its q3 is ignored.
    step : float
        Relative finite-difference step (tyre force states use 100 times it).
    t : float
        Time [s] at which to evaluate (the plate must be at rest then).
    columns : sequence of int, optional
        Only these columns (indices into :data:`LINEAR_STATES`), each
        computed exactly as in the whole Jacobian (default all).

    Returns
    -------
    ndarray, shape (15, 15), or (15, len(columns))
    """
    z0 = heading_state(x)
    x = solve_pitch(rhs, x)   # once for the reference; again only when a coordinate is perturbed
    columns = range(z0.size) if columns is None else list(columns)
    J = np.empty((z0.size, len(columns)))
    # The tyre slots by their form's declared sizes, never below an angle's (force_lag's ~100 N: 100 times larger).
    slot_scale = {n: max(scale, 1.0) for n, scale in zip(PATCH_STATES, transient.FORMS[rhs.transient].scales,
                                                           strict=True)}
    for col, j in enumerate(columns):
        name = LINEAR_STATES[j]
        h = step * max(1.0, abs(z0[j])) * slot_scale.get(name, 1.0)
        zp, zm = z0.copy(), z0.copy()
        zp[j] += h
        zm[j] -= h
        moved = name.startswith("q")
        J[:, col] = (_heading_derivative(rhs, x, zp, t, moved) - _heading_derivative(rhs, x, zm, t, moved)) / (2 * h)
    return J


#: Row of the constraint matrix A (:meth:`CompiledRHS.impulse_terms`) that is the
#: holonomic constraint's rate: its entries are d(front contact height)/dq_i,
#: since u_i = dq_i/dt (derivation.slip_equations: rear no-slip, front no-slip, holonomic).
HOLONOMIC_ROW = 2


@functools.cache
def _difference_scales(form, n_states=len(STATE_NAMES)):
    """Typical size of each state for the C Jacobian's steps ``1.5e-8 max(|x_j|, scale_j)``.

    Angles [rad] and speeds [m/s, rad/s] 1, compressions 1e-3 m, the tyre
    slots their form's declared sizes (the force-lag states 100 N, N m). Steps about 1.5e-8 of these keep forward
    differences at ~1e-7 relative (round-off ~eps/step times the terms'
    size, truncation ~step/2 times the curvature), and the compression's
    step stays far below a tyre's static compression even at 1e10 N/m
    (6e-8 m), so the normal force's kink is never crossed. (The integrator's
    scales, 100 to 1e4 times smaller, serve LSODA's Newton iteration but
    leave 1e-5 round-off here.) Read-only.
    """
    scale = np.ones(n_states)
    for name in ("q9", "q10"):
        scale[X[name]] = 1e-3
    # The tyre slots by their form's declared sizes (force_lag 100 N; the carcass' deflections ~1e-2 m at the
    # friction limit).
    scale[[X[s] for s in PATCH_STATES]] = transient.FORMS[form].scales
    scale.flags.writeable = False
    return scale


#: Full-state slot of each heading-frame state (v_fwd, v_lat are u1, u2 at zero yaw).
_HEADING_SLOTS = np.array([X[{"v_fwd": "u1", "v_lat": "u2"}.get(n, n)] for n in LINEAR_STATES])
#: Heading-frame coordinates the front contact height depends on (pitch q5 follows them).
_PITCH_DRIVERS = [(LINEAR_STATES.index(n), SPEEDS.index("u" + n[1:])) for n in ("q4", "q7", "q9", "q10")]
_I_FWD, _I_LAT, _I_U3 = (LINEAR_STATES.index(n) for n in ("v_fwd", "v_lat", "u3"))
_U1, _U2, _U3 = X["u1"], X["u2"], X["u3"]


def heading_linearisation(rhs, x, t=0.0):
    """The Jacobian of :func:`linearize` and the steer-torque column, from one C Jacobian.

    The same heading-frame linear model as :func:`linearize` (states
    :data:`LINEAR_STATES`), obtained by the chain rule instead of by
    perturbing the heading-frame state: with ``x(z)`` the full state of a
    heading-frame state ``z`` (yaw 0, ``u1 = v_fwd``, ``u2 = v_lat``, pitch
    on the holonomic constraint), ``dz'/dz = S J E + R E``, where ``J`` is
    the compiled model's own Jacobian (:meth:`CompiledRHS.jacobian_function`,
    forward differences in C, steps :func:`_difference_scales`), ``E =
    dx/dz`` embeds ``z`` (its pitch row ``-h_q / h_q5`` is the exact gradient
    of the front contact height, :data:`HOLONOMIC_ROW`), ``S`` picks the rows
    and ``R`` holds the rotating-frame terms of ``v_fwd' = u1' + u3 u2``,
    ``v_lat' = u2' - u3 u1``. About 25 right-hand-side evaluations' worth of
    time instead of about 110 (``scripts/bench_stability.py``); agrees with
    :func:`linearize` to 1e-7 of each column's largest entry
    (``tests/studies/test_stability.py``).

    With a leaning rider or a delayed reflex, the states of :func:`body_states`
    follow :data:`LINEAR_STATES` in ``A`` and ``B``.

    The steer-torque column is exact: the model is affine in the steer
    torque ``T7 = -(... + ku7 u7)`` and its coefficient depends on the
    coordinates only, so two evaluations that differ only in ``ku7`` give it.

    Parameters
    ----------
    rhs : CompiledRHS
    x : array_like
        Full state (e.g. ``SteadyState.x``); its q3 is ignored, u1 and u2 are
        resolved along the heading. The plate must be at rest at ``t``.
    t : float
        Time [s].

    Returns
    -------
    A : ndarray, shape (15, 15)
        ``d(dz/dt)/dz`` of the model as parametrised (closed loop when
        ``rhs`` carries the rider's gains).
    B : ndarray, shape (15, 1)
        Per unit steer torque T7 [N m].

    Example
    -------
    >>> A, B = heading_linearisation(CompiledRHS(steady.params), steady.x)   # doctest: +SKIP
    """
    z = heading_state(x)
    x0 = np.array(x, dtype=float)
    x0[X["q3"]] = 0.0
    x0[X["u1"]], x0[X["u2"]] = z[_I_FWD], z[_I_LAT]
    if abs(rhs.outputs(t, x0)[1][OUT["holonomic"]]) > 1e-13:   # a steady state is on it already
        x0 = solve_pitch(rhs, x0)
    L = rhs.layout
    J = rhs.jacobian_function(_difference_scales(rhs.transient, len(L.STATE_NAMES)))(t, x0)
    h_q = rhs.impulse_terms(t, x0)[1][HOLONOMIC_ROW]
    slots = np.concatenate([_HEADING_SLOTS, [L.X[n] for n in body_states(rhs)]]).astype(int)
    # A = S J E: the picked columns of J, plus the pitch column times dq5/dz.
    A = J[np.ix_(slots, slots)]
    pitch_column = J[slots, X["q5"]]
    for j, k in _PITCH_DRIVERS:
        A[:, j] -= pitch_column * (h_q[k] / h_q[SPEEDS.index("u5")])
    u1, u2, u3 = x0[X["u1"]], x0[X["u2"]], x0[X["u3"]]
    A[_I_FWD, _I_U3] += u2
    A[_I_FWD, _I_LAT] += u3
    A[_I_LAT, _I_U3] -= u1
    A[_I_LAT, _I_FWD] -= u3
    # Steer-torque column: with u7 moved to u7 + 1 (any value != 0 would do), raising
    # ku7 by 1 changes T7 by -(u7 + 1) and nothing else.
    x0[X["u7"]] += 1.0
    k = P["ku7"]
    f_base = rhs(t, x0)
    saved = rhs.p[k]
    try:
        rhs.p[k] = saved + 1.0
        f_bumped = rhs(t, x0)
    finally:
        rhs.p[k] = saved
    B = ((f_base - f_bumped)[slots] / x0[X["u7"]]).reshape(-1, 1)
    return A, B


def linear_state_space(params, x, step=1e-7, rhs=None):
    """Open-loop ``A`` and steer-torque input ``B`` of the slip model about ``x``.

    ``x`` is a steady state of the closed loop with the gains in ``params``
    (the steady steer torque ``-K x`` stays applied as a constant). Because
    the controller enters as ``T7 = -K x``, the closed-loop Jacobian is
    ``A - B K``; ``B`` is the change of that Jacobian when the steer-rate
    gain grows by 1 N m s/rad, so both come from the compiled model.

    Returns
    -------
    A : ndarray (15, 15)
    B : ndarray (15, 1)
        Per unit steer torque T7 [N m].
    K : ndarray (1, 15)
        The gains of ``params`` on :data:`LINEAR_STATES` (so ``A - B K`` is the closed loop).

    ``rhs`` is ``CompiledRHS(params)`` where the caller has it already (it is only read).
    """
    if params.get("kq3", 0.0):
        raise InputError("linear_state_space: a yaw-angle gain kq3 breaks the heading invariance")
    rhs = CompiledRHS(params) if rhs is None else rhs
    A_cl = linearize(rhs, x, step)
    bumped = rhs.replaced(ku7=params["ku7"] + 1.0)
    j = LINEAR_STATES.index("u7")
    # Only the steer-rate column moves with ku7: the bumped model's other 14 columns are not computed.
    B = (A_cl[:, j] - linearize(bumped, x, step, columns=[j])[:, 0]).reshape(-1, 1)
    K = np.zeros((1, len(LINEAR_STATES)))
    for gain, state in layouts.GAIN_STATES.items():
        if state in LINEAR_STATES:   # the bicycle's states (q3 is not one: kq3 is refused above)
            K[0, LINEAR_STATES.index(state)] = params[gain]
    return A_cl + B @ K, B, K
