"""Piecewise LSODA integration of the compiled slip model.

The kick plate's acceleration (and, for the thesis profile, its velocity)
jumps at the start and end of the kick. Asking an adaptive integrator to
step over such a jump costs accuracy and steps; instead each smooth piece
is integrated on its own and the state is carried across the breakpoint.
A fall (|roll| beyond a limit) ends the run as an event, not an error.
"""
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from . import slip


@dataclass
class Trajectory:
    """Samples of one run."""

    t: np.ndarray            # times [s], shape (n,)
    x: np.ndarray            # states, shape (n, len(slip.STATE_NAMES))
    fell: bool               # the roll limit was reached
    fall_time: float | None  # time of the fall event [s]
    nfev: int                # right-hand-side evaluations
    message: str

    def state(self, name):
        """Time history of one state by name."""
        return self.x[:, slip.X[name]]


def default_atol(rtol):
    """Absolute tolerances per state, scaled to each state's typical size.

    Angles and displacements (~1e-2..1) and speeds (~1) get ``rtol`` x 1e-2
    of their scale; the tyre force states (~100 N) x 1e2 more.
    """
    atol = np.full(len(slip.STATE_NAMES), rtol * 1e-2)
    for name in ("q9", "q10", "u9", "u10"):
        atol[slip.X[name]] = rtol * 1e-4   # compressions are millimetres
    for name in slip.TYRE_STATES:
        atol[slip.X[name]] = rtol
    return atol


def integrate(rhs, x0, t_end, t_start=0.0, breakpoints=(), rtol=1e-10, atol=None,
              output_rate=1000.0, fall_angle=np.deg2rad(45.0)):
    """Integrate ``rhs`` from ``x0`` piecewise between breakpoints.

    Parameters
    ----------
    rhs : slip.CompiledRHS
        Compiled right-hand side with its parameters.
    x0 : array_like
        Initial state (:data:`slip.STATE_NAMES`).
    t_end, t_start : float
        Time span [s].
    breakpoints : iterable of float
        Times where the input is not smooth (integration restarts there).
    rtol : float
        LSODA relative tolerance.
    atol : array_like, optional
        Absolute tolerances (default :func:`default_atol`).
    output_rate : float
        Sample rate of the output [Hz].
    fall_angle : float
        |roll| limit [rad] ending the run.

    Returns
    -------
    Trajectory
    """
    atol = default_atol(rtol) if atol is None else atol
    n_samples = int(round((t_end - t_start) * output_rate)) + 1
    samples = np.linspace(t_start, t_end, n_samples)
    edges = [t_start] + sorted(b for b in set(breakpoints) if t_start < b < t_end) + [t_end]
    roll = slip.X["q4"]

    def fall(t, x):
        return fall_angle - abs(x[roll])
    fall.terminal = True
    fall.direction = -1

    ts, xs, nfev = [], [], 0
    x = np.asarray(x0, dtype=float)
    fell, fall_time, message = False, None, "completed"
    for a, b in zip(edges[:-1], edges[1:]):
        last = b == edges[-1]
        inside = samples[(samples >= a) & ((samples <= b) if last else (samples < b))]
        # Always evaluate at the piece's end so the exact end state carries over.
        t_eval = inside if (inside.size and inside[-1] == b) else np.append(inside, b)
        sol = solve_ivp(rhs, (a, b), x, method="LSODA", t_eval=t_eval, events=fall,
                        rtol=rtol, atol=atol)
        nfev += sol.nfev
        keep = np.isin(sol.t, inside)
        ts.append(sol.t[keep])
        xs.append(sol.y.T[keep])
        if sol.status < 0:
            message = f"integration failed at t = {sol.t[-1] if sol.t.size else a:.6g} s: {sol.message}"
            break
        if sol.status == 1:
            fell, fall_time = True, float(sol.t_events[0][0])
            ts.append(np.array([fall_time]))
            xs.append(sol.y_events[0][:1])
            message = f"fell: |roll| reached {np.rad2deg(fall_angle):.0f} deg at t = {fall_time:.4f} s"
            break
        x = sol.y[:, -1]
    t = np.concatenate(ts) if ts else np.array([])
    X = np.concatenate(xs) if xs else np.empty((0, len(x)))
    if X.size and not np.all(np.isfinite(X)):
        raise FloatingPointError("non-finite state in the integration result")
    return Trajectory(t, X, fell, fall_time, nfev, message)
