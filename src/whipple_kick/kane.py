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
        ud_ind = np.linalg.solve(T.T @ M @ T, T.T @ (f - M @ t0))
        return T @ ud_ind + t0
