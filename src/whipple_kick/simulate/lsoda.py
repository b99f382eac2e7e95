"""Piecewise LSODA integration of the compiled slip model.

The kick plate's acceleration (and, for the thesis profile, its velocity)
jumps at the start and end of the kick. Asking an adaptive integrator to
step over such a jump costs accuracy and steps; instead each smooth piece
is integrated on its own and the state is carried across the breakpoint,
through a jump map where the caller gives one (the plate stop's impulse).
A fall (``|roll|`` beyond a limit) ends the run as an event, not an error.
LSODA's stiff steps use the compiled model's Jacobian (forward differences
in C over the dynamic states, one foreign call; the energy quadratures feed
nothing back). For the compiled model LSODA runs in C
(:mod:`whipple_kick.simulate.lsoda_c`): the fast path one call per piece, the
roll and steer limits checked in C, and the careful path (a fall, LSODA's
trouble, the budget) one call per chunk, stepped, sampled and its fall found
in C; elsewhere (another SciPy release, no C compiler, any other ``f(t, x)``)
it calls the compiled model through ``CompiledRHS.fast``
(:mod:`whipple_kick.model.rhs_call`: one foreign call per evaluation).

No integration runs for ever: a :class:`Budget` bounds the right-hand-side
evaluations per simulated second (those LSODA makes and those inside each
Jacobian: a forward-difference Jacobian of the compiled model costs one
evaluation per dynamic state and one more). An integration that stalls (the step size
collapsing, e.g. when a wheel unloads in a fall and the tyre forces switch
faster than any step can follow) ends as a reported failure with the samples
it produced so far, in bounded time.
"""
import collections
from dataclasses import dataclass, replace
import functools
import itertools
import math
import warnings

import numpy as np
from scipy.integrate import LSODA, odeint
from scipy.integrate._ode import lsoda as ode_lsoda
from scipy.optimize import brentq

from whipple_kick.model import slip
from whipple_kick.model.transient import DEFAULT_TRANSIENT, FORMS
from whipple_kick.simulate import lsoda_c


@dataclass
class StateHistory:
    """The integrated states at the samples of one run, with its outcome and work counters.

    Not to be confused with :attr:`whipple_kick.simulate.results.Result.trajectory`, the table of named columns
    computed from it (:func:`whipple_kick.simulate.results.trajectory_frame`).
    """

    t: np.ndarray            # times [s], shape (n,)
    x: np.ndarray            # states, shape (n, the model's state count)
    fell: bool               # the roll limit (or the steer limit) was reached
    fall_time: float | None  # time of the fall event [s]
    nfev: int                # right-hand-side evaluations by LSODA (those inside Jacobians not counted)
    message: str
    end_state: np.ndarray | None = None   # exact state at t_end (or at the fall, or where it failed)
    failed: bool = False     # the integration failed (stalled, non-finite derivative); samples end there
    njev: int = 0            # Jacobian evaluations
    evaluations: int = 0     # all right-hand-side evaluations, the Jacobians' included (what the budget counts)
    fall_reason: str | None = None   # "roll" or "steer": which limit ended the run

    def state(self, name):
        """Time history of one state by name."""
        return self.x[:, slip.X[name]]


def join(pieces):
    """One trajectory of consecutive pieces (each starting where the previous ended).

    The samples are concatenated and the work counters (``nfev``, ``njev``,
    ``evaluations``) summed; how the run ended (fall, failure, message, end
    state) is the last piece's. The one place pieces are merged, so that no
    counter is lost (a hand-made StateHistory once reported 0 Jacobians).
    """
    pieces = list(pieces)
    return replace(pieces[-1], t=np.concatenate([p.t for p in pieces]), x=np.concatenate([p.x for p in pieces]),
                   **_summed_counters(pieces))


def _summed_counters(pieces):
    """The work counters of consecutive pieces, summed (:func:`join`, and :func:`integrate` after ``before``)."""
    return {name: sum(getattr(p, name) for p in pieces) for name in ("nfev", "njev", "evaluations")}


#: Fast-path chunk length [s]: each chunk is one odeint (LSODA restarted), and
#: a chunk in which a limit is passed is redone with events. Restarting is not
#: the cost it looks: on the 6 s default run (compiled Jacobian, medians of 5,
#: wall relative to 0.5 s) chunks of 0.5 / 1 / 2 s / one run per piece take
#: 1.00 / 1.31 / 1.39 / 1.36 (8835 / 12089 / 12865 / 13154 evaluations) at rtol
#: 1e-10 and 1.00 / 0.95 / 1.50 / 1.53 (22757 / 17659 / 24390 / 24778) at 1e-12;
#: with ``tyre_transient="force_lag"`` 1.00 / 0.86 / 0.86 / 0.77 at 1e-10 and
#: 1.00 / 1.19 / 1.13 / 1.39 at 1e-12. A long LSODA run makes more Jacobians
#: (63 against 224 at 1e-10; its switch between the Adams and the stiff method
#: decides), so 0.5 s stays: never much worse, and redoing a chunk after a fall
#: is cheap.
#: (Starting each chunk with the previous chunk's last step moved these
#: counts by -35 % to +62 % case by case: no consistent gain, not used.)
DEFAULT_CHUNK = 0.5


#: Absolute tolerance of the energy quadratures [J]: so large that they never
#: control LSODA's step (they are pure quadratures of the dynamic states, so
#: their accuracy follows the dynamic states' steps).
QUADRATURE_ATOL = 1e6


def default_atol(rtol, transient=DEFAULT_TRANSIENT, n_states=len(slip.STATE_NAMES)):
    """Absolute tolerances per state, scaled to each state's typical size.

    Angles and displacements (~1e-2..1) and speeds (~1) get ``rtol`` x 1e-2
    of their scale, the compressions x 1e-4; the tyre slots by their form's
    declared sizes (:attr:`whipple_kick.model.transient.Form.scales`), never
    finer than an angle's: the ``force_lag`` form's forces (~100 N) get
    ``rtol``; the energy quadratures :data:`QUADRATURE_ATOL`. ``n_states``:
    the model's state count (the parts' states, angles and rates, follow the base model's).
    """
    atol = np.full(n_states, rtol * 1e-2)
    for name in ("q9", "q10", "u9", "u10"):
        atol[slip.X[name]] = rtol * 1e-4   # compressions are millimetres
    # The tyre slots by their form's declared sizes, never finer than an angle's (a force ~100 N gets rtol).
    for name, scale in zip(slip.PATCH_STATES, FORMS[transient].scales, strict=True):
        atol[slip.X[name]] = rtol * (1e-2 * max(scale, 1.0))
    for name in slip.QUADRATURE_STATES:
        atol[slip.X[name]] = QUADRATURE_ATOL
    return atol


@functools.lru_cache(maxsize=32)
def _tolerances(rtol, transient, n_states, _exactly):
    """:func:`default_atol` and the Jacobian's step scale ``atol / rtol``, read-only, once per process.

    Every run of a sweep asks for the same ones (twice per run). ``_exactly`` tells keys apart that compare equal
    but are not the same number (``0.0``, ``-0.0``; an int): :func:`_exact_key`.
    """
    atol = default_atol(rtol, transient, n_states)
    scale = atol / rtol
    atol.flags.writeable = scale.flags.writeable = False
    return atol, scale


def _exact_key(*values):
    """What tells apart numbers that compare equal (``0.0 == -0.0``, ``1 == 1.0``) in a cache key."""
    return tuple((type(v), math.copysign(1.0, v) if isinstance(v, float) else 0.0) for v in values)


@dataclass(frozen=True)
class Budget:
    """Most right-hand-side evaluations one :func:`integrate` call may spend.

    ``allowance + per_second * (t - t_start)`` evaluations may have been
    spent by the time the integration reaches ``t``, and the last
    ``stall_window`` evaluations must have advanced the time by at least
    ``stall_progress``; otherwise it has stalled (the step size collapsing)
    and ends as a failure. Deterministic (evaluations, not wall time).

    The defaults are set from measured runs (``scripts/envelope_study.py
    budget``, docs/simulate.md "No run hangs"; evaluations counted as here,
    the C Jacobian's included, per call): no completed or falling run of the
    kick, tolerance and speed grids, a 151-row kick table or the thesis
    preset spent more than 12.1 % of the limit at any point (the most: the
    thesis preset falling at 1.92 m/s, 400 kPa, 35 153 evaluations in
    2.83 s), and none advanced less than 1.03 s in any 20 000 consecutive
    evaluations, 1030 times the stall threshold; none of the 288 runs of the
    speed envelope with the LQR riders tripped it. The stalls found (the
    thesis' set-up at 1.92-2 m/s and 500 kPa: a front wheel unloading in a
    fall, steps of 1e-8 s) end after about 0.6-1.5 s of wall time.

    Attributes
    ----------
    allowance : int
        Evaluations free of the rate (the start of a piece, a fall's last steps).
    per_second : float
        Evaluations per simulated second [1/s].
    stall_window : int
        Evaluations over which progress is judged.
    stall_progress : float
        Least simulated time [s] ``stall_window`` evaluations must advance.
    """

    allowance: int = 100_000
    per_second: float = 100_000.0
    stall_window: int = 20_000
    stall_progress: float = 1e-3

    def limit(self, simulated):
        """Evaluations allowed after ``simulated`` seconds [s] of integration."""
        return self.allowance + self.per_second * max(0.0, simulated)


DEFAULT_BUDGET = Budget()


def _careful_chunk(rhs, x, times, rtol, atol, fall, spent, budget, t_start, jac=None):
    """Integrate one chunk with LSODA stepped from Python, the fall event and the budget (the careful path).

    For a compiled model where the driver builds, :func:`_careful_chunk_in_c` does the same in C; this is
    the path for any other ``f(t, x)``, and the fallback.

    The same solver, step by step, as ``solve_ivp(method="LSODA", t_eval=times,
    events=fall)`` (samples from each step's dense output, the fall time by
    Brent's method on it to 4 ulp), but a failure keeps the samples up to the
    last accepted step, and the evaluation budget is checked after every step.

    Returns
    -------
    times, states : ndarray
        Samples produced (those of ``times`` up to the end, the fall or the failure).
    end : (t, x)
        Last time and exact state reached (the fall event's, if it fell).
    status : {"completed", "fell", "failed"}
    message : str or None
        Why it failed.
    counts : (nfev, njev, evaluations)
        LSODA's evaluations, its Jacobians, and all evaluations (the
        Jacobians' included: :func:`_evaluations`), as the budget counts them.
    """
    solver = LSODA(rhs, times[0], x, times[-1], rtol=rtol, atol=atol, jac=jac)

    def counts():
        return solver.nfev, solver.njev, _evaluations(jac, solver.nfev, solver.njev)
    out_t, out_x = [times[:1]], [np.asarray(x, dtype=float)[None, :]]
    nxt, g_old = 1, fall(times[0], x)
    if g_old <= 0.0:   # already at or past a limit where the chunk starts: that is the fall
        return times[:1], np.asarray(x, dtype=float)[None, :], (times[0], np.asarray(x, dtype=float)), "fell", \
            None, (0, 0, 0)
    recent = collections.deque([(0, times[0])])   # (evaluations, time) after the steps of the last window
    while True:
        try:
            trouble = solver.step()
        except FloatingPointError as exc:
            trouble = str(exc)
            solver.status = "failed"
        if solver.status == "failed":
            return (np.concatenate(out_t), np.concatenate(out_x), (solver.t, solver.y), "failed",
                    f"LSODA stopped at t = {solver.t:.6g} s: {trouble}", counts())
        t_new, end, status = solver.t, (solver.t, solver.y), None
        dense = None
        g_new = fall(t_new, solver.y)
        if g_old >= 0.0 >= g_new:   # |roll| rose through the limit (the event's direction)
            dense = solver.dense_output()
            t_fall = brentq(lambda t, dense=dense: fall(t, dense(t)), solver.t_old, t_new,
                            xtol=4 * np.finfo(float).eps, rtol=4 * np.finfo(float).eps)
            t_new, end, status = t_fall, (t_fall, dense(t_fall)), "fell"
        g_old = g_new
        upto = int(np.searchsorted(times, t_new, side="right"))
        if upto > nxt:
            dense = solver.dense_output() if dense is None else dense
            out_t.append(times[nxt:upto])
            out_x.append(dense(times[nxt:upto]).T)
            nxt = upto
        if status is None and solver.status == "finished":
            status = "completed"
        if status is not None:
            return np.concatenate(out_t), np.concatenate(out_x), end, status, None, counts()
        used = counts()[2]
        recent.append((used, t_new))
        while len(recent) > 1 and recent[1][0] <= used - budget.stall_window:
            recent.popleft()
        why = None
        if spent + used > budget.limit(t_new - t_start):
            why = "budget"
        elif recent[0][0] <= used - budget.stall_window and t_new - recent[0][1] < budget.stall_progress:
            why = "stall"
        if why is not None:
            return (np.concatenate(out_t), np.concatenate(out_x), end, "failed",
                    _stall_message(why, budget, spent, used, t_new, t_start, recent[0], solver.step_size),
                    counts())


def _stall_message(why, budget, spent, used, t_new, t_start, window, step_size):
    """Why a careful chunk stopped at ``t_new`` [s]: ``why`` "budget" (``spent + used`` evaluations over the
    budget) or "stall" (``used`` less ``window``'s evaluations advanced it less than the stall window allows
    since ``window``'s time), with the last step's size [s]. The one wording of both careful paths."""
    if why == "budget":
        why = (f"{spent + used} right-hand-side evaluations for {t_new - t_start:.4g} s simulated, "
               f"more than the budget {budget.allowance} + {budget.per_second:g}/s")
    else:
        why = (f"{used - window[0]} right-hand-side evaluations advanced it only "
               f"{t_new - window[1]:.2g} s (at least {budget.stall_progress:g} s per "
               f"{budget.stall_window} evaluations)")
    return f"integration stalled at t = {t_new:.6g} s: {why}; last step {step_size:.2g} s"


def _careful_chunk_in_c(chunks_in_c, rhs, x, times, rtol, atol, fall, spent, budget, t_start, jac):
    """:func:`_careful_chunk` in C (:meth:`whipple_kick.simulate.lsoda_c.FastChunks.careful`), the same return.

    The same arguments after ``chunks_in_c``, whose own tolerances, limits and model C uses (``rtol``,
    ``atol`` and ``fall`` are those; they are not read here).

    The same steps, evaluation counts, ending and messages; the samples, the fall time and the state at the
    fall from the same interpolant evaluated in another order (Horner's rule, not ``np.dot``), so equal to
    round-off (``tests/simulate/test_lsoda_c.py``). What scipy raises in the Python path (brentq on a NaN
    margin or without a sign change; a non-``FloatingPointError`` from the model cannot happen in C) is
    raised here with scipy's words. ``rhs`` and ``jac`` (the Python callables of the same model) only word
    a model failure: re-evaluated where C saw it fail, they raise the Python path's error.
    """
    if not np.all(np.isfinite(x)):   # scipy's LSODA refuses such a start (the Python path raises this)
        raise ValueError("All components of the initial state `y0` must be finite.")
    out = chunks_in_c.careful(times, x, spent)
    status, samples, end = out.status, out.samples, out.end
    sample_t = times[:len(samples)]
    if status in ("completed", "fell"):
        return sample_t, samples, end, status, None, out.counts
    if status == "root_nan":
        raise ValueError(f"The function value at x={out.failed[0]} is NaN; solver cannot continue.")
    if status == "root_signs":
        raise ValueError("f(a) and f(b) must have different signs")
    if status == "root_iterations":
        raise RuntimeError("Failed to converge after 100 iterations.")
    if status in ("budget", "stall"):
        message = _stall_message(status, budget, spent, out.counts[2], out.step, t_start, out.window, out.step_size)
    else:
        if status == "model":
            t_failed, x_failed, which = out.failed
            trouble = f"the compiled model failed at t = {t_failed:.6g} s"   # unless its Python call says more
            try:
                (jac if which == "jacobian" else rhs)(t_failed, x_failed)
            except FloatingPointError as exc:
                trouble = str(exc)
        else:   # istate < 0, as scipy's ode warns and its LSODA solver object words it
            warnings.warn(f"lsoda: {ode_lsoda.messages.get(out.istate, f'Unexpected istate={out.istate:d}')}",
                          stacklevel=2)
            trouble = "Unexpected istate in LSODA."
        message = f"LSODA stopped at t = {out.step:.6g} s: {trouble}"
    return sample_t, samples, end, "failed", message, out.counts


def _evaluations(jac, nfev, njev):
    """Right-hand-side evaluations LSODA's ``nfev`` calls and ``njev`` Jacobians cost.

    A Jacobian with an ``evaluations`` attribute (the compiled model's
    forward differences: one evaluation per dynamic state and one more) costs
    that many; without a Jacobian LSODA differences itself and counts those
    evaluations in ``nfev``.
    """
    return int(nfev) + int(njev) * int(getattr(jac, "evaluations", 0))


class _PastTheLimit(Exception):
    """Raised inside the fast path once the roll limit (the fall angle) or the steer limit is passed."""


def _guarded(rhs, roll_index, fall_angle, steer_index, steer_limit):
    """``f(t, x)`` that raises :class:`_PastTheLimit` once ``|roll|`` or ``|steer|`` passes its limit.

    Odeint has no events, and integrating a fallen bicycle onwards is wasted
    work, so the fast path stops as soon as a limit is passed.
    """
    if hasattr(rhs, "guarded"):   # the compiled model: the limits are checked in C
        return rhs.guarded(roll_index, fall_angle, _PastTheLimit, steer_index, steer_limit)

    def guarded(t, x):   # any f(t, x), e.g. the NumPy oracle
        if abs(x[roll_index]) > fall_angle or abs(x[steer_index]) > steer_limit:
            raise _PastTheLimit
        return rhs(t, x)
    return guarded


def _within_limits(states, roll_index, fall_angle, steer_index, steer_limit):
    """Whether every row of ``states`` has ``|roll|`` and ``|steer|`` inside their limits."""
    return bool(np.all(np.abs(states[:, roll_index]) < fall_angle) and np.all(np.abs(states[:, steer_index]) < steer_limit))


def _fast_chunk(guarded, x, times, rtol, atol, mxstep, jac=None):
    """Integrate one chunk of ``guarded`` (:func:`_guarded`) with odeint's LSODA (the step loop stays in Fortran).

    Returns ``(states, (nfev, njev, evaluations))``, or ``None`` if a limit was passed or
    LSODA reported trouble, e.g. more than ``mxstep`` steps between two
    samples (the caller then integrates the chunk carefully).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            y, info = odeint(guarded, x, times, Dfun=jac, rtol=rtol, atol=atol, tfirst=True, full_output=True,
                             mxstep=mxstep)
        except (_PastTheLimit, FloatingPointError):
            return None
    if info["message"] != "Integration successful." or not np.all(np.isfinite(y)):
        return None
    nfev, njev = int(info["nfe"][-1]), int(info["nje"][-1])
    return y, (nfev, njev, _evaluations(jac, nfev, njev))


def _chunks_in_c(rhs, jac, rtol, atol, mxstep, limits, budget, t_start):
    """The fast path's chunk loop in C (:class:`whipple_kick.simulate.lsoda_c.FastChunks`) for a compiled model, else None.

    None for any other ``f(t, x)`` (the NumPy oracle, a test's function) or where the driver cannot be built: the
    chunks then run through ``odeint`` (:func:`_fast_chunk`), the same numbers.
    """
    if jac is None or not hasattr(getattr(rhs, "lib", None), "wk_slip_jacobian"):
        return None
    lib = lsoda_c.driver()
    if lib is None:
        return None
    return lsoda_c.FastChunks(lib, rhs, jac, rtol, atol, mxstep, limits, budget, t_start)


def _piece_samples(samples, a, b, eps):
    """The samples within ``eps`` [s] of a piece's start ``a``, those of its end ``b`` (not ``a``'s), those inside.

    The same samples as the tests ``|s - a| <= eps``, ``|s - b| <= eps and s > a + eps`` and
    ``a + eps < s < b - eps`` on all of them, in a fraction of the time: ``samples`` increases, so each set is a
    run of it (``s - a`` rounded does not decrease with ``s``) found by binary search, a view; the first two are
    tested on the candidates within ``4 eps`` only, beyond which no sample passes the test.
    """
    w = 4 * eps
    start_a, start_b, stop_inside = np.searchsorted(samples, (a - w, b - w, b - eps), "left").tolist()
    stop_a, stop_b, start_inside = np.searchsorted(samples, (a + w, b + w, a + eps), "right").tolist()
    near_a, near_b = samples[start_a:stop_a], samples[start_b:stop_b]
    return (near_a[np.abs(near_a - a) <= eps], near_b[(np.abs(near_b - b) <= eps) & (near_b > a + eps)],
            samples[start_inside:stop_inside])


def integrate(rhs, x0, t_end, t_start=0.0, breakpoints=(), rtol=1e-10, atol=None,
              output_rate=1000.0, fall_angle=np.deg2rad(45.0), chunk=None, samples=None,
              budget=None, jumps=None, steer_limit=None, before=None):
    """Integrate ``rhs`` from ``x0`` piecewise between breakpoints with LSODA.

    Each smooth piece is integrated in chunks of about ``chunk`` seconds
    with LSODA as :func:`scipy.integrate.odeint` runs it: for a compiled
    model all the chunks of a piece in one C call (:mod:`whipple_kick.simulate.lsoda_c`,
    the same numbers), otherwise through ``odeint``. A chunk in which the roll limit is crossed (or in
    which LSODA reports trouble) is integrated again from its start with
    the same LSODA stepped one step at a time (:class:`scipy.integrate.LSODA`,
    as ``solve_ivp`` does; for a compiled model the same steps in C, the
    samples and the fall time equal to round-off) and a fall event, which gives the exact fall
    time. Numerical
    trouble there (LSODA giving up, a non-finite derivative, or more
    evaluations than ``budget`` allows) ends the integration as a failure:
    the trajectory is returned with ``failed=True``, the samples up to the
    last accepted step and a message saying where and why.

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
        ``|roll|`` limit [rad] ending the run.
    steer_limit : float, optional
        ``|steer|`` limit [rad] ending the run too (None: no limit). Past 90 deg
        the front wheel rolls backwards, which the tyre model does not
        describe, and no rider recovers from it.
    chunk : float, optional
        Length of the fast-path chunks [s] (default :data:`DEFAULT_CHUNK`;
        ``inf`` for one LSODA run per piece).
    samples : array_like, optional
        Output times [s] (increasing); those in ``[t_start, t_end]`` are
        returned. Default: ``output_rate`` from ``t_start``. A sample within
        a billionth of the sample spacing of a piece's edge is given the
        state at that edge rather than a sub-ulp integration of its own.
    budget : Budget, optional
        Evaluation budget of this call (default: :data:`DEFAULT_BUDGET` as it
        is when the call is made).
    jumps : mapping, optional
        ``{breakpoint: g(t, x) -> x}``: the state leaving the piece that
        ends at the breakpoint is mapped by ``g`` before the next piece
        starts (a sample at the breakpoint gets the mapped state).
    before : StateHistory, optional
        A run that ends before ``t_start`` and whose samples come first: the result is
        ``join([before, this call's])``, without copying this call's samples again.

    Returns
    -------
    StateHistory
        With ``end_state`` the exact state at ``t_end`` (or at the fall, or
        where it failed), whether or not that is a sample time.

    Example
    -------
    >>> import numpy as np
    >>> from whipple_kick import lsoda
    >>> def decay(t, x):            # any f(t, x) of the state layout's length
    ...     return -x
    >>> x0 = np.full(len(lsoda.slip.STATE_NAMES), 1e-3)
    >>> traj = lsoda.integrate(decay, x0, 1.0, output_rate=10.0)
    >>> round(float(traj.x[-1, 0] / 1e-3), 6), traj.failed
    (0.367879, False)
    """
    transient = getattr(rhs, "transient", DEFAULT_TRANSIENT)
    plain = getattr(rhs, "fast", rhs)   # the compiled model's one-foreign-call f(t, x)
    if atol is None:
        atol, scale = _tolerances(rtol, transient, len(x0), _exact_key(rtol))
    else:
        atol = np.asarray(atol, dtype=float)
        scale = atol / rtol
    jac = rhs.jacobian_function(scale) if hasattr(rhs, "jacobian_function") else None
    jumps = dict(jumps or {})
    budget = DEFAULT_BUDGET if budget is None else budget
    chunk = DEFAULT_CHUNK if chunk is None else chunk
    if samples is None:
        n_samples = int(round((t_end - t_start) * output_rate)) + 1
        samples = np.linspace(t_start, t_end, n_samples)
    else:
        samples = np.asarray(samples, dtype=float)
        # Those in [t_start, t_end]: a run of the increasing samples, found by binary search (a view, no copy).
        samples = samples[np.searchsorted(samples, t_start, "left"):np.searchsorted(samples, t_end, "right")]
    spacing = np.min(np.diff(samples)) if samples.size > 1 else (t_end - t_start)
    eps = 1e-9 * spacing + 1e-14 * max(abs(t_start), abs(t_end))
    edges = [t_start] + sorted(b for b in set(breakpoints) if t_start < b < t_end) + [t_end]
    roll = slip.X["q4"]

    steer = slip.X["q7"]
    steer_limit = np.inf if steer_limit is None else float(steer_limit)

    def fall(t, x):
        # The first of the two limits to be reached ends the run (the min of two margins).
        return min(fall_angle - abs(x[roll]), steer_limit - abs(x[steer]))
    fall.terminal = True
    fall.direction = -1
    # The fast path gives up (and the careful path takes over, with the budget) after more steps
    # between two samples than a quarter of the stall window's evaluations (a step costs 1 to ~25
    # evaluations, a stiff one with a new Jacobian the most), so a stall wastes about one window
    # here; a legitimate interval needs far fewer steps (docs/simulate.md).
    mxstep = max(1, budget.stall_window // 4)
    chunks_in_c = _chunks_in_c(rhs, jac, rtol, atol, mxstep, (roll, fall_angle, steer, steer_limit), budget, t_start)
    # odeint's f (once per integration, not per chunk), where the chunks do not run in C.
    guarded = _guarded(rhs, roll, fall_angle, steer, steer_limit) if chunks_in_c is None else None

    nfev = njev = spent = 0   # LSODA's evaluations, Jacobians, all evaluations (the budget's count)
    last_t = -np.inf   # time of the last emitted sample (chunks share end points)
    # The result's rows, written once each as they come (every sample, and a fall's time beyond them), instead
    # of a list of pieces concatenated at the end; the C chunk loop writes its samples straight into them. Row 0
    # of `x_rows` is spare: that loop writes a chunk's start state one row before the chunk's first sample.
    head = 0 if before is None else before.t.size
    t_out, x_rows = np.empty(head + samples.size + 2), np.empty((head + samples.size + 3, len(x0)))
    x_out = x_rows[1:]
    t_out[:head], x_out[:head] = (before.t, before.x) if head else (0.0, 0.0)
    filled = head
    # Rows whose finiteness is still to be checked, as [start, stop) runs: all but those the C chunk loop wrote in
    # place (it checked them, as the odeint path checks each chunk's states).
    unchecked = [[0, head]]

    def put(times, states):
        nonlocal filled, last_t
        t_out[filled:filled + times.size] = times
        x_out[filled:filled + times.size] = states
        if unchecked[-1][1] == filled:
            unchecked[-1][1] += times.size
        else:
            unchecked.append([filled, filled + times.size])
        filled += times.size
        last_t = times[-1]

    def emit(times, states, member=None):
        # Sample membership (``member``, where the caller knows it) by binary search (times are sorted and
        # taken from `samples`, or piece edges).
        if member is None:
            at = np.minimum(np.searchsorted(samples, times), samples.size - 1)
            member = samples[at] == times if samples.size else np.zeros(times.size, bool)
        keep = member & (times > last_t)
        rows = np.flatnonzero(keep)
        if rows.size == 0:
            return
        if rows[-1] - rows[0] + 1 == rows.size:   # one run of rows (nearly always: all but a chunk's first)
            put(times[rows[0]:rows[-1] + 1], states[rows[0]:rows[-1] + 1])
        else:
            put(times[rows], states[rows])

    x = np.asarray(x0, dtype=float)
    fell, fall_time, message, failed, fall_reason = False, None, "completed", False, None
    done = False
    rows_address, row_bytes = (x_rows.ctypes.data, x_rows.strides[0]) if chunks_in_c is not None else (None, None)
    for a, b in itertools.pairwise(edges):
        at_a, at_b, inside = _piece_samples(samples, a, b, eps)
        emit(at_a, np.repeat(x[None, :], at_a.size, axis=0))
        # Chunk boundaries: the piece's start, sample times about `chunk`
        # apart, and the piece's end (so the exact end state carries over).
        grid = np.concatenate([[a], inside, [b]])
        # Which of the grid's times are samples: those inside are, taken from them; the piece's ends may not be.
        on_grid = np.ones(grid.size, bool)
        ends = np.minimum(np.searchsorted(samples, (a, b)), samples.size - 1)
        on_grid[[0, -1]] = samples[ends] == (a, b) if samples.size else False
        if np.isinf(chunk):
            cuts = [0, len(grid) - 1]
        else:
            marks = np.searchsorted(grid, a + chunk * np.arange(1, int(np.ceil((b - a) / chunk))))
            cuts = sorted({0, len(grid) - 1, *(int(m) for m in marks if 0 < m < len(grid) - 1)})
        k = 0
        while k < len(cuts) - 1:
            if chunks_in_c is not None:
                # The chunks of the piece in one C call, up to the first that the careful path must redo.
                counts = np.array([nfev, njev, spent], dtype=np.int64)
                # Grid row g goes to x_rows' row filled + g - cuts[k]: the chunks' first sample to the result's
                # next row; the start state to the row before, the last row emitted (kept: put back below).
                start, spare = x, x_rows[filled].copy()
                into = rows_address + (filled - cuts[k]) * row_bytes
                ran, _, x = chunks_in_c(grid, cuts[k:], x, counts, into=into)
                x_rows[filled] = spare
                nfev, njev, spent = (int(v) for v in counts)
                if ran:
                    j = cuts[k + ran]
                    stop = j if j == len(grid) - 1 else j + 1   # the piece's end: after the jump map (below)
                    if stop > cuts[k] + 1 and on_grid[cuts[k] + 1:stop].all() and grid[cuts[k] + 1] > last_t:
                        # Every row after the start is a sample (the grid's inner times are): in place already.
                        t_out[filled:filled + stop - cuts[k] - 1] = grid[cuts[k] + 1:stop]
                        filled += stop - cuts[k] - 1
                        last_t = grid[stop - 1]
                    else:
                        states = x_rows[filled:filled + j - cuts[k] + 1].copy()
                        states[0] = start
                        emit(grid[cuts[k]:stop], states[:stop - cuts[k]], on_grid[cuts[k]:stop])
                    k += ran
                    if k == len(cuts) - 1:
                        break
            i0, i1 = cuts[k], cuts[k + 1]
            k += 1
            times = grid[i0:i1 + 1]
            # A sample at the piece's end is emitted after the jump map (below).
            last = -1 if i1 == len(grid) - 1 else None
            fast = None if chunks_in_c is not None else _fast_chunk(guarded, x, times, rtol, atol, mxstep, jac)
            # The guard sees only the states LSODA evaluates; a sample (the chunk's end above all)
            # interpolated past a limit must still go to the careful path, or the fall is missed.
            if fast is not None and spent + fast[1][2] <= budget.limit(times[-1] - t_start) \
                    and _within_limits(fast[0], roll, fall_angle, steer, steer_limit):
                y, (n, nj, used) = fast
                nfev, njev, spent = nfev + n, njev + nj, spent + used
                emit(times[:last], y[:last], on_grid[i0:i1 + 1][:last])
                x = y[-1]
                continue
            # A failed fast attempt is redone here, so only this attempt counts against the budget.
            arguments = (plain, x, times, rtol, atol, fall, spent, budget, t_start, jac)
            sample_t, sample_x, (t_reached, x), status, why, (n, nj, used) = (
                _careful_chunk(*arguments) if chunks_in_c is None else _careful_chunk_in_c(chunks_in_c, *arguments))
            nfev, njev, spent = nfev + n, njev + nj, spent + used
            if status == "completed" and last is not None and sample_t.size and sample_t[-1] == times[-1]:
                sample_t, sample_x = sample_t[:-1], sample_x[:-1]
            emit(sample_t, sample_x)
            if status == "fell":
                fell, fall_time = True, float(t_reached)
                if fall_time > last_t:
                    put(np.array([fall_time]), x[None, :])
                if fall_angle - abs(x[roll]) <= steer_limit - abs(x[steer]):
                    fall_reason = "roll"
                    message = f"fell: |roll| reached {np.rad2deg(fall_angle):.0f} deg at t = {fall_time:.4f} s"
                else:
                    fall_reason = "steer"
                    message = (f"lost: |steer| reached {np.rad2deg(steer_limit):.0f} deg (the fork turned over) "
                               f"at t = {fall_time:.4f} s")
            elif status == "failed":
                failed, message = True, why
            if status != "completed":
                done = True
                break
        if done:
            break
        if b in jumps:
            x = np.asarray(jumps[b](b, x), dtype=float)
        emit(at_b, np.repeat(x[None, :], at_b.size, axis=0))
    t, X = t_out[:filled], x_out[:filled]
    if not all(np.isfinite(X[start:stop]).all() for start, stop in unchecked):
        raise FloatingPointError("non-finite state in the integration result")
    history = StateHistory(t, X, fell, fall_time, nfev, message, end_state=np.asarray(x, dtype=float), failed=failed,
                           njev=njev, evaluations=spent, fall_reason=fall_reason)
    return history if before is None else replace(history, **_summed_counters((before, history)))
