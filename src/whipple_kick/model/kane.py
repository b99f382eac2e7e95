"""The numerical half of Kane's method: eliminating the dependent speeds.

Given, at one instant, Kane's equations for the full set of speeds
``M du/dt = f`` and the velocity constraints ``A u + a0 = 0`` with their
derivative ``A du/dt + b = 0``, this module returns the dependent speeds and
all accelerations. With ``u = T u_ind + t0`` (``T`` stacks the identity on
the independent speeds and ``C = -A_dep^-1 A_ind`` on the dependent ones),
Kane's equations are ``T^T (f - M du/dt) = 0``. Works with real or complex
arrays (complex-step linearisation).
"""
import numpy as np


class ConstraintPartition:
    """Index bookkeeping for independent and dependent speeds.

    Parameters
    ----------
    speed_names : sequence of str
        Names of all speeds, in the order of the equations.
    dependent : sequence of str
        Names of the dependent speeds, in the order they are solved.
    """

    def __init__(self, speed_names, dependent):
        self.names = tuple(speed_names)
        self.dependent = tuple(dependent)
        self.independent = tuple(n for n in self.names if n not in self.dependent)
        self.dep = np.array([self.names.index(n) for n in self.dependent])
        self.ind = np.array([self.names.index(n) for n in self.independent])

    def dependent_speeds(self, A, a0, u_ind):
        """Solve ``A u + a0 = 0`` for the dependent speeds; return all speeds."""
        u = np.zeros(len(self.names), dtype=np.result_type(A, u_ind))
        u[self.ind] = u_ind
        u[self.dep] = -np.linalg.solve(A[:, self.dep], A[:, self.ind] @ u_ind + a0)
        return u

    def accelerations(self, M, f, A, b):
        """Kane's reduced equations; return du/dt for all speeds."""
        A_dep = A[:, self.dep]
        sol = np.linalg.solve(A_dep, np.column_stack([A[:, self.ind], b]))
        C = -sol[:, :-1]
        d = -sol[:, -1]
        n = len(self.names)
        T = np.zeros((n, len(self.ind)), dtype=C.dtype)
        T[self.ind, np.arange(len(self.ind))] = 1.0
        T[self.dep, :] = C
        t0 = np.zeros(n, dtype=d.dtype)
        t0[self.dep] = d
        Mr, r = T.T @ M @ T, T.T @ (f - M @ t0)
        ud_ind = np.linalg.solve(Mr, r)
        return T @ ud_ind + t0


def constraint_power(M, f, u, udot):
    """Power of the constraint forces, ``u @ (M du/dt - f)`` [W].

    Kane's full equations read ``M du/dt = f + A^T lambda``, so this is
    ``lambda . (A u) = -lambda . a0``: zero for fixed constraints, the work
    rate of a moving one (the rear no-slip constraint on the kick plate).
    """
    return float(np.dot(u, M @ udot - f))


def impulsive_projection(M, A, u_minus, a0_plus):
    """Speeds just after a jump of the constraint offset, by the impulse it takes.

    Solves ``M (u+ - u-) = A^T L`` with ``A u+ + a0_plus = 0`` (the
    generalised momentum jump carried by the constraints' impulse ``L``) as
    one KKT system, so ``M`` need only be positive definite on the null
    space of ``A`` (the slip model's front compression rate u10 carries no
    mass: it moves the contact point, not a body).

    Parameters
    ----------
    M : ndarray (n, n)
        Mass matrix of all speeds, symmetric positive semi-definite.
    A : ndarray (m, n)
        Constraint matrix (unchanged by the jump).
    u_minus : ndarray (n,)
        All speeds just before (satisfying the constraints with the old offset).
    a0_plus : ndarray (m,)
        Constraint offset just after.

    Returns
    -------
    u_plus : ndarray (n,)
    impulse : ndarray (m,)
        ``L``. With ``a0_minus = -A u_minus`` the kinetic energy ``u M u / 2``
        changes by ``-1/2 L . (a0_plus + a0_minus)``, the work of the impulse.
    """
    n, m = M.shape[0], A.shape[0]
    kkt = np.block([[M, -A.T], [A, np.zeros((m, m))]])
    sol = np.linalg.solve(kkt, np.concatenate([np.zeros(n), -(A @ u_minus + a0_plus)]))
    return u_minus + sol[:n], sol[n:]
