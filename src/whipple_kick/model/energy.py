"""Energy accounting of the slip model: cumulative works and dissipations.

The compiled model integrates, beside the dynamic states, ten pure
quadratures (:data:`QUADRATURE_STATES`, zero at the start of a run except
the carcass tyre's stored energy, which starts at c y^2/2): the work done on
the bicycle by the kick plate, the steer torque, the rear-wheel torque, the
tyres' zero-slip forces and their aligning moments; the dissipation of the
contact patches' sliding, of the vertical tyre dampers (and, with a
rider's body, the hip and arm dampers: ``damper_dissipation``) and of the
carcass tyre's lateral dampers; and the energy stored in each tyre's lateral
carcass compliance.
They obey, at every instant,

    d(KE + PE + springs + carcass_r + carcass_f)/dt
        = plate + steer + wheel + zero-slip + moment - sliding - dampers - carcass dampers,

where ``springs`` (``spring_energy``) are the vertical tyre springs and,
with a body, the rider's hip and arm springs, so :func:`balance_residual`
of a trajectory stays at integration accuracy (the plate stop's impulse adds its work to the plate's column; see
:func:`whipple_kick.model.kane.impulsive_projection`). The split of the tyre's
power is defined in :mod:`whipple_kick.model.transient`; docs/validation.md gives
the argument and the measured sizes.
"""

from . import symbols as S

#: Quadrature states appended to the dynamic states, in this order.
QUADRATURE_STATES = ("W_plate", "W_steer", "W_wheel", "W_zero_slip", "W_moment", "D_slide", "D_damper",
                     "E_carcass_r", "E_carcass_f", "D_carcass")
#: Trajectory column and unit of each quadrature state.
COLUMNS = {
    "W_plate": ("plate_work", "J"), "W_steer": ("steer_work", "J"),
    "W_wheel": ("rear_wheel_torque_work", "J"), "W_zero_slip": ("zero_slip_force_work", "J"),
    "W_moment": ("aligning_moment_work", "J"), "D_slide": ("sliding_dissipation", "J"),
    "D_damper": ("damper_dissipation", "J"), "E_carcass_r": ("carcass_energy_rear", "J"),
    "E_carcass_f": ("carcass_energy_front", "J"),
    "D_carcass": ("carcass_damper_dissipation", "J"),
}
#: Quadratures that are stored energies (the carcass tyre's start at c y^2/2 and equal it throughout);
#: the others are works and dissipations, counted from the kick start.
STORED_QUADRATURES = ("E_carcass_r", "E_carcass_f")
CUMULATIVE = tuple(n for n in QUADRATURE_STATES if n not in STORED_QUADRATURES)
#: Stored energies (trajectory columns) on the left of the balance.
STORED = ("kinetic_energy", "potential_energy", "spring_energy", "carcass_energy_rear", "carcass_energy_front")
#: Works (+) and dissipations (-) on its right.
SUPPLIED = ("plate_work", "steer_work", "rear_wheel_torque_work", "zero_slip_force_work", "aligning_moment_work")
DISSIPATED = ("sliding_dissipation", "damper_dissipation", "carcass_damper_dissipation")


def common_rates(extra, u, t6):
    """Rates of the quadratures that do not depend on the transient form.

    Parameters
    ----------
    extra : mapping
        :func:`whipple_kick.model.symbolic.derivation.slip_equations`' ``extra`` (plain symbols).
    u : mapping
        Speed symbols by name (``u6``, ``u7``).
    t6 : sympy.Symbol
        The rear-wheel torque T6c.

    Returns
    -------
    dict
        ``W_plate`` (the tyre force's part; the rear no-slip constraint's
        part is added numerically, see :func:`whipple_kick.model.kane.constraint_power`),
        ``W_steer``, ``W_wheel``, ``W_moment``, ``D_damper``.
    """
    import sympy as sm


    fy_r, mz_r, mz_f, t7 = S.syms(["Fy_r", "Mz_r", "Mz_f", "T7"])
    vplate_r, wz_r, wz_f = S.syms(["vplate_r", "wz_r", "wz_f"])
    return {
        "W_plate": fy_r * vplate_r,
        # The rider's torque acts between the bar and the frame the hands hold: its power is the
        # torque times the bar's rate relative to that frame (u7 without a part that carries the hands).
        "W_steer": t7 * sm.sympify(extra["steer_relative_rate"]),
        "W_wheel": t6 * u["u6"],
        "W_moment": mz_r * wz_r + mz_f * wz_f,
        "D_damper": sm.sympify(extra["damper_dissipation_rate"]),
    }


def balance_residual(frame):
    """Energy balance residual [J] at every sample of a trajectory table.

    ``stored - stored[0] - (supplied - dissipated)``: zero to integration
    accuracy when every term is accounted for.

    Parameters
    ----------
    frame : pandas.DataFrame
        Trajectory with the columns of :data:`STORED`, :data:`SUPPLIED`
        and :data:`DISSIPATED`.

    Returns
    -------
    numpy.ndarray
    """
    stored = sum(frame[c].to_numpy() for c in STORED)
    supplied = sum(frame[c].to_numpy() for c in SUPPLIED) - sum(frame[c].to_numpy() for c in DISSIPATED)
    return stored - stored[0] - (supplied - supplied[0])
