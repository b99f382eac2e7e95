"""Piecewise LSODA integration of the compiled slip model.

The kick plate's acceleration (and, for the thesis profile, its velocity)
jumps at the start and end of the kick. Asking an adaptive integrator to
step over such a jump costs accuracy and steps; instead each smooth piece
is integrated on its own and the state is carried across the breakpoint,
through a jump map where the caller gives one (the plate stop's impulse).
A fall (|roll| beyond a limit) ends the run as an event, not an error.
LSODA's stiff steps use the compiled model's Jacobian (forward differences
in C over the dynamic states; the energy quadratures feed nothing back).
"""
from dataclasses import dataclass

import numpy as np
import warnings

from scipy.integrate import odeint, solve_ivp

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
    end_state: np.ndarray | None = None   # exact state at t_end (or at the fall)

    def state(self, name):
        """Time history of one state by name."""
        return self.x[:, slip.X[name]]


#: Fast-path chunk length [s]. Measured on the 6 s base case (median of 7):
#: 0.25 / 0.5 / 1 / 2 s / one run give 0.125 / 0.139 / 0.164 / 0.175 / 0.174 s
#: at rtol 1e-12 and 0.045 / 0.041 / 0.033 / 0.030 / 0.028 s at rtol 1e-8;
#: 0.5 s balances the two, and keeps redoing a chunk after a fall cheap.
DEFAULT_CHUNK = 0.5


#: Absolute tolerance of the energy quadratures [J]: so large that they never
#: control LSODA's step (they are pure quadratures of the dynamic states, so
#: their accuracy follows the dynamic states' steps).
QUADRATURE_ATOL = 1e6


def default_atol(rtol, transient="contact_patch"):
    """Absolute tolerances per state, scaled to each state's typical size.

    Angles and displacements (~1e-2..1) and speeds (~1) get ``rtol`` x 1e-2
    of their scale, the compressions x 1e-4; the tyre slots are angles too
    except in the ``force_lag`` form, whose force states (~100 N) get
    ``rtol``; the energy quadratures :data:`QUADRATURE_ATOL`.
    """
    atol = np.full(len(slip.STATE_NAMES), rtol * 1e-2)
    for name in ("q9", "q10", "u9", "u10"):
        atol[slip.X[name]] = rtol * 1e-4   # compressions are millimetres
    if transient == "force_lag":
        for name in slip.TYRE_STATES:
            atol[slip.X[name]] = rtol
    for name in slip.QUADRATURE_STATES:
        atol[slip.X[name]] = QUADRATURE_ATOL
    return atol


def _careful_chunk(rhs, x, times, rtol, atol, fall, jac):
    """Integrate one chunk with solve_ivp's LSODA and the fall event (exact event time)."""
    sol = solve_ivp(rhs, (times[0], times[-1]), x, method="LSODA", t_eval=times, events=fall,
                    rtol=rtol, atol=atol, jac=jac)
    return sol


class _PastTheLimit(Exception):
    """Raised inside the fast path once the roll limit is passed."""


def _fast_chunk(rhs, x, times, rtol, atol, roll_index, fall_angle, jac):
    """Integrate one chunk with odeint's LSODA (the step loop stays in Fortran).

    Returns ``(states, nfev)``, or ``None`` if the roll limit was passed or
    LSODA reported trouble (the caller then integrates the chunk carefully).
    """
    # Stop as soon as the bicycle is past the limit: odeint has no events,
    # and integrating a fallen bicycle onwards is wasted work.
    if hasattr(rhs, "guarded"):
        guarded = rhs.guarded(roll_index, fall_angle, _PastTheLimit)
    else:   # any f(t, x), e.g. the NumPy oracle
        def guarded(t, x):
            if abs(x[roll_index]) > fall_angle:
                raise _PastTheLimit
            return rhs(t, x)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            y, info = odeint(guarded, x, times, Dfun=jac, rtol=rtol, atol=atol, tfirst=True, full_output=True,
                             mxstep=100000)
        except (_PastTheLimit, FloatingPointError):
            return None
    if info["message"] != "Integration successful." or not np.all(np.isfinite(y)):
        return None
    return y, int(info["nfe"][-1])


def integrate(rhs, x0, t_end, t_start=0.0, breakpoints=(), rtol=1e-10, atol=None,
              output_rate=1000.0, fall_angle=np.deg2rad(45.0), chunk=None, samples=None, jumps=None):
    """Integrate ``rhs`` from ``x0`` piecewise between breakpoints with LSODA.

    Each smooth piece is integrated in chunks of about ``chunk`` seconds
    with ODEPACK's LSODA through :func:`scipy.integrate.odeint`, whose step
    loop runs in Fortran. A chunk in which the roll limit is crossed (or in
    which LSODA reports trouble) is integrated again from its start with
    :func:`scipy.integrate.solve_ivp` (the same LSODA, stepped from Python)
    and a terminal event, which gives the exact fall time.

    Parameters
    ----------
    rhs : slip.CompiledRHS or callable
        Compiled right-hand side with its parameters, or any ``f(t, x)``.
    x0 : array_like
        Initial state (:data:`slip.STATE_NAMES`).
    t_end, t_start : float
        Time span [s].
    breakpoints : iterable of float
        Times where the input is not smooth (integration restarts there).
    rtol : float
        LSODA relative tolerance.
    atol : array_like, optional
        Absolute tolerances (default :func:`default_atol` of the form of
        ``rhs``). With a compiled ``rhs`` its C Jacobian is used, with steps
        scaled by ``atol / rtol`` (each state's typical size).
    output_rate : float
        Sample rate of the output [Hz] (when ``samples`` is not given).
    fall_angle : float
        |roll| limit [rad] ending the run.
    chunk : float, optional
        Length of the fast-path chunks [s] (default :data:`DEFAULT_CHUNK`;
        ``inf`` for one LSODA run per piece).
    samples : array_like, optional
        Output times [s] (increasing); those in ``[t_start, t_end]`` are
        returned. Default: ``output_rate`` from ``t_start``. A sample within
        a billionth of the sample spacing of a piece's edge is given the
        state at that edge rather than a sub-ulp integration of its own.
    jumps : mapping, optional
        ``{breakpoint: g(t, x) -> x}``: the state leaving the piece that
        ends at the breakpoint is mapped by ``g`` before the next piece
        starts (a sample at the breakpoint gets the mapped state).

    Returns
    -------
    Trajectory
        With ``end_state`` the exact state at ``t_end`` (or at the fall),
        whether or not ``t_end`` is a sample time.
    """
    transient = getattr(rhs, "transient", "contact_patch")
    atol = default_atol(rtol, transient) if atol is None else np.asarray(atol, dtype=float)
    jac = rhs.jacobian_function(atol / rtol) if hasattr(rhs, "jacobian_function") else None
    jumps = dict(jumps or {})
    chunk = DEFAULT_CHUNK if chunk is None else chunk
    if samples is None:
        n_samples = int(round((t_end - t_start) * output_rate)) + 1
        samples = np.linspace(t_start, t_end, n_samples)
    else:
        samples = np.asarray(samples, dtype=float)
        samples = samples[(samples >= t_start) & (samples <= t_end)]
    spacing = np.min(np.diff(samples)) if samples.size > 1 else (t_end - t_start)
    eps = 1e-9 * spacing + 1e-14 * max(abs(t_start), abs(t_end))
    edges = [t_start] + sorted(b for b in set(breakpoints) if t_start < b < t_end) + [t_end]
    roll = slip.X["q4"]

    def fall(t, x):
        return fall_angle - abs(x[roll])
    fall.terminal = True
    fall.direction = -1

    ts, xs, nfev = [], [], 0
    last_t = -np.inf   # time of the last emitted sample (chunks share end points)

    def emit(times, states):
        nonlocal last_t
        keep = np.isin(times, samples) & (times > last_t)
        if keep.any():
            ts.append(times[keep])
            xs.append(states[keep])
            last_t = times[keep][-1]

    x = np.asarray(x0, dtype=float)
    fell, fall_time, message = False, None, "completed"
    done = False
    for a, b in zip(edges[:-1], edges[1:]):
        at_a = samples[np.abs(samples - a) <= eps]
        at_b = samples[(np.abs(samples - b) <= eps) & (samples > a + eps)]
        inside = samples[(samples > a + eps) & (samples < b - eps)]
        emit(at_a, np.repeat(x[None, :], at_a.size, axis=0))
        # Chunk boundaries: the piece's start, sample times about `chunk`
        # apart, and the piece's end (so the exact end state carries over).
        grid = np.concatenate([[a], inside, [b]])
        if np.isinf(chunk):
            cuts = [0, len(grid) - 1]
        else:
            marks = np.searchsorted(grid, a + chunk * np.arange(1, int(np.ceil((b - a) / chunk))))
            cuts = sorted({0, len(grid) - 1, *(int(m) for m in marks if 0 < m < len(grid) - 1)})
        for i0, i1 in zip(cuts[:-1], cuts[1:]):
            times = grid[i0:i1 + 1]
            # A sample at the piece's end is emitted after the jump map (below).
            last = -1 if i1 == len(grid) - 1 else None
            fast = _fast_chunk(rhs, x, times, rtol, atol, roll, fall_angle, jac)
            if fast is not None:
                y, n = fast
                nfev += n
                emit(times[:last], y[:last])
                x = y[-1]
                continue
            sol = _careful_chunk(rhs, x, times, rtol, atol, fall, jac)
            nfev += sol.nfev
            emit(sol.t[:last] if sol.status != 1 else sol.t, sol.y.T[:last] if sol.status != 1 else sol.y.T)
            if sol.status == 1:
                fell, fall_time = True, float(sol.t_events[0][0])
                x = sol.y_events[0][0]
                if fall_time > last_t:
                    ts.append(np.array([fall_time]))
                    xs.append(x[None, :])
                message = f"fell: |roll| reached {np.rad2deg(fall_angle):.0f} deg at t = {fall_time:.4f} s"
                done = True
                break
            if sol.status < 0:
                raise FloatingPointError(
                    f"integration failed at t = {sol.t[-1] if sol.t.size else times[0]:.6g} s: {sol.message}")
            x = sol.y[:, -1]
        if done:
            break
        if b in jumps:
            x = np.asarray(jumps[b](b, x), dtype=float)
        emit(at_b, np.repeat(x[None, :], at_b.size, axis=0))
    t = np.concatenate(ts) if ts else np.array([])
    X = np.concatenate(xs) if xs else np.empty((0, len(x)))
    if X.size and not np.all(np.isfinite(X)):
        raise FloatingPointError("non-finite state in the integration result")
    return Trajectory(t, X, fell, fall_time, nfev, message, end_state=x)
