"""The plate stop: the speeds across a jump of the plate's velocity (impulse, or kept as the authors' code keeps them)."""

import numpy as np

from whipple_kick.model import kane

from .layout import OUT, P, X


def kept_speeds_slide(rhs, t, x):
    """The rear slide ``vsx_r`` [m/s] that keeps every speed across a plate-velocity jump at ``t``.

    The thesis authors' published code integrates all speeds as states and
    enforces the rear no-slip condition only through its time derivative, so
    when the plate stops instantly no speed jumps and the condition is left
    violated by a constant: the rear contact keeps sliding along its heading,
    relative to the stopped plate, at the plate's velocity before the stop
    times sin(yaw) (0.204 m/s in their 500 kPa run). This returns that slide
    (``rhs``'s own ``vsx_r`` included), to be imposed by the rear constraint
    for the rest of the run.

    Parameters
    ----------
    rhs : CompiledRHS
        Whose plate velocity jumps at ``t`` (``t`` itself belongs to after).
    t : float
        Time of the jump [s].
    x : array_like
        State arriving at ``t``.

    Returns
    -------
    float
    """
    x = np.asarray(x, dtype=float)
    L = rhs.layout
    ind = [L.X[n] for n in L.INDEPENDENT]
    _, A, a0_plus = rhs.impulse_terms(t, x)
    _, _, a0_minus = rhs.impulse_terms(np.nextafter(t, -np.inf), x)
    u = L.PARTITION.dependent_speeds(A, a0_minus, x[ind])
    residual = A @ u + a0_plus
    # The rear row (vsx_r enters it as -vsx_r) is the only one the plate appears in.
    return float(rhs.p[P["vsx_r"]] + residual[0])


def velocity_jump(rhs, t, x, impulse=True):
    """Carry the state across a jump of the plate velocity at ``t`` (the plate stop).

    Parameters
    ----------
    rhs : CompiledRHS
        Whose plate velocity jumps at ``t`` (``t`` itself belongs to after).
    t : float
        Time of the jump [s].
    x : array_like
        State arriving at ``t``.
    impulse : bool
        True: the rear no-slip constraint's impulse
        (:func:`whipple_kick.model.kane.impulsive_projection`) sets all speeds and
        its work is added to the plate's work W_plate. False: the
        independent speeds are kept and only the dependent ones re-solved.

    Returns
    -------
    x_after : ndarray
    info : dict
        ``time_s``, ``kinetic_energy_change_j`` (from the kinetic-energy
        expression before and after), ``impulse_work_j`` (``-1/2 L.(a0+ + a0-)``,
        the same change computed from the impulse: an independent check;
        None without impulse) and ``constraint_impulse_n_s`` (``L``).
    """
    x = np.array(x, dtype=float)
    before = np.nextafter(t, -np.inf)
    M, A, a0_plus = rhs.impulse_terms(t, x)
    _, _, a0_minus = rhs.impulse_terms(before, x)
    L = rhs.layout
    ind = [L.X[n] for n in L.INDEPENDENT]
    ke_before = rhs.outputs(before, x)[1][OUT["kinetic_energy"]]
    work, impulse_value = None, None
    if impulse:
        u_minus = L.PARTITION.dependent_speeds(A, a0_minus, x[ind])
        u_plus, impulse_value = kane.impulsive_projection(M, A, u_minus, a0_plus)
        x[ind] = u_plus[L.PARTITION.ind]
        work = float(-0.5 * impulse_value @ (a0_plus + a0_minus))
        x[X["W_plate"]] += work
    ke_after = rhs.outputs(t, x)[1][OUT["kinetic_energy"]]
    return x, {"time_s": float(t), "kinetic_energy_change_j": float(ke_after - ke_before),
               "impulse_work_j": work,
               "constraint_impulse_n_s": None if impulse_value is None else [float(v) for v in impulse_value]}
