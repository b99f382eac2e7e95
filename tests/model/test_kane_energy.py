"""kane.impulsive_projection and energy.balance_residual on two-degree-of-freedom examples solved by hand."""
import numpy as np
import pandas as pd
import pytest

from whipple_kick.model import energy, kane


def test_impulsive_projection_of_two_masses_whose_relative_speed_is_imposed():
    """Two masses m1, m2 on a line; the constraint u1 - u2 + a0 = 0 (a moving guide imposes their
    relative speed). Before: both at v, a0- = 0. The offset jumps to a0+ = -w.

    The constraint's impulse L acts as A^T L = (L, -L): m1 (u1+ - v) = L, m2 (u2+ - v) = -L, and
    u1+ - u2+ = w gives L/m1 + L/m2 = w, so L = mu w with mu = m1 m2 / (m1 + m2), and
    u1+ = v + w m2 / (m1 + m2), u2+ = v - w m1 / (m1 + m2) (momentum m1 u1 + m2 u2 is kept).
    Kinetic energy: KE+ - KE- = v w (m1 m2 - m2 m1) / (m1 + m2) + w^2 m1 m2 / (2 (m1 + m2))
    = mu w^2 / 2, which is -1/2 L (a0+ + a0-) = -1/2 mu w (-w + 0), the work of the impulse.
    """
    m1, m2, v, w = 2.0, 3.0, 1.5, 0.4
    M = np.diag([m1, m2])
    A = np.array([[1.0, -1.0]])
    u_plus, L = kane.impulsive_projection(M, A, np.array([v, v]), np.array([-w]))
    mu = m1 * m2 / (m1 + m2)
    np.testing.assert_allclose(u_plus, [v + w * m2 / (m1 + m2), v - w * m1 / (m1 + m2)], rtol=1e-14)
    np.testing.assert_allclose(L, [mu * w], rtol=1e-14)
    ke = lambda u: 0.5 * u @ M @ u
    assert ke(u_plus) - ke(np.array([v, v])) == pytest.approx(0.5 * mu * w ** 2, rel=1e-13)
    assert ke(u_plus) - ke(np.array([v, v])) == pytest.approx(-0.5 * L[0] * (-w + 0.0), rel=1e-13)
    assert m1 * u_plus[0] + m2 * u_plus[1] == pytest.approx((m1 + m2) * v, rel=1e-15)


def test_impulsive_projection_with_a_massless_speed_tied_by_a_constraint():
    """As above plus a third speed u3 of no mass tied to u1 (u1 - u3 = 0): M is singular, but positive
    definite on the constraints' null space. Row 3 of M du = A^T L reads 0 = -L2, so L2 = 0, u1 and u2
    jump as before and u3+ = u1+."""
    m1, m2, v, w = 2.0, 3.0, 1.5, 0.4
    M = np.diag([m1, m2, 0.0])
    A = np.array([[1.0, -1.0, 0.0], [1.0, 0.0, -1.0]])
    u_plus, L = kane.impulsive_projection(M, A, np.array([v, v, v]), np.array([-w, 0.0]))
    u1 = v + w * m2 / (m1 + m2)
    np.testing.assert_allclose(u_plus, [u1, v - w * m1 / (m1 + m2), u1], rtol=1e-14)
    np.testing.assert_allclose(L, [m1 * m2 / (m1 + m2) * w, 0.0], rtol=1e-14, atol=1e-15)


def _frame(t, m=2.0, c=0.8, F=1.5, k=5.0, m2=0.5, y0=0.1, offset=0.0):
    """Trajectory table of two independent degrees of freedom with closed-form energies.

    (1) A block of mass m pushed by a constant force F against a viscous damper c, from rest:
    v = (F/c)(1 - e^(-c t/m)), x = (F/c)(t - (m/c)(1 - e^(-c t/m))); the force's work F x, the
    damper's dissipation D = int c v^2 dt = (F^2/c)(t - 2 (m/c)(1 - e^(-c t/m)) + (m/(2c))(1 - e^(-2 c t/m))),
    and m dv/dt = F - c v gives d(m v^2/2)/dt = F v - c v^2: KE = F x - D exactly.
    (2) An undamped oscillator m2, k: y = y0 cos(w t), w^2 = k/m2, whose kinetic plus spring energy
    stays k y0^2 / 2. ``offset`` is added to every column (a table not starting at zero).
    """
    e1, e2 = np.exp(-c * t / m), np.exp(-2 * c * t / m)
    v = F / c * (1 - e1)
    x = F / c * (t - m / c * (1 - e1))
    dissipation = F ** 2 / c * (t - 2 * m / c * (1 - e1) + m / (2 * c) * (1 - e2))
    om = np.sqrt(k / m2)
    y, ydot = y0 * np.cos(om * t), -y0 * om * np.sin(om * t)
    columns = {name: np.zeros_like(t) for name in energy.STORED + energy.SUPPLIED + energy.DISSIPATED}
    columns.update(kinetic_energy=0.5 * m * v ** 2 + 0.5 * m2 * ydot ** 2, spring_energy=0.5 * k * y ** 2,
                   plate_work=F * x, damper_dissipation=dissipation)
    return pd.DataFrame({name: value + offset for name, value in columns.items()}), dissipation


def test_balance_residual_of_a_damped_pushed_block_and_an_oscillator_is_zero():
    t = np.linspace(0.0, 5.0, 501)
    frame, _ = _frame(t)
    np.testing.assert_allclose(energy.balance_residual(frame), 0.0, atol=1e-13)
    # Every column may start anywhere: only changes from the first sample count.
    np.testing.assert_allclose(energy.balance_residual(_frame(t, offset=7.0)[0]), 0.0, atol=1e-12)


def test_balance_residual_shows_a_term_left_out_with_its_sign():
    """Leaving the damper out makes the residual -D (energy seemingly lost); counting it as supplied
    work instead of dissipation makes it -2 D."""
    t = np.linspace(0.0, 5.0, 501)
    frame, dissipation = _frame(t)
    np.testing.assert_allclose(energy.balance_residual(frame.assign(damper_dissipation=0.0)), -dissipation,
                               atol=1e-13)
    wrong_sign = frame.assign(steer_work=frame["damper_dissipation"], damper_dissipation=0.0)
    np.testing.assert_allclose(energy.balance_residual(wrong_sign), -2 * dissipation, atol=1e-13)


def test_item14_spring_and_damper_descriptions_name_the_body():
    """Issue 31 item 14: with a body, spring_energy and damper_dissipation include the arm springs and dampers
    and the parts' (the leaning upper body's hip: derivation.py sums them in); their descriptions said tyre
    springs only."""
    from whipple_kick.model import slip, symbols

    spring = slip.OUTPUTS["spring_energy"][1]
    damper = symbols.info("D_damper").description
    for text in (spring, damper):
        assert "tyre" in text and "arm" in text and "part" in text, text
