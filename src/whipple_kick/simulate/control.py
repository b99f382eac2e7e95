"""The LQR steer-torque "rider" designed on the linearised classic model.

State ``x = [q4, q7, u4, u7]`` (roll, steer, roll rate, steer rate), input
the steer torque ``T7``. The law is ``T7 = -K x`` (python-control's
``lqr`` convention), ``K = [kq4, kq7, ku4, ku7]``. Thesis eq. 8.4 prints the
law without the minus sign; with the signs of its Table 8.4 gains (kq4 < 0,
kq7 > 0) only ``-K x`` stabilises, which ``tests/simulate/test_control.py`` proves on
the linear and the nonlinear model.

The design solves the continuous algebraic Riccati equation with SciPy
(``scipy.linalg.solve_continuous_are``, about 1 ms for the 4-state model):
python-control costs more than a second to import and is not needed at run
time. It stays the library of the control-analysis API
(:meth:`whipple_kick.studies.stability.LinearModel.state_space` returns a
``control.StateSpace``) and the tests' oracle: ``control.lqr`` gives the
same gains (``tests/simulate/test_control.py``).
"""
import functools
import math
import warnings

import numpy as np
from scipy.linalg import solve_continuous_are, solve_continuous_lyapunov
from scipy.optimize import minimize

from whipple_kick.errors import ConvergenceWarning, InputError, check_range
from whipple_kick.library import thesis
from whipple_kick.model import classic, parts, slip

from . import steady

GAIN_ORDER = ("kq4", "kq7", "ku4", "ku7")
#: Gains of :func:`heading_lqr_gains`, whose state adds the yaw angle q3.
HEADING_GAIN_ORDER = ("kq3",) + GAIN_ORDER

#: Thesis Table 8.4: gains used for the Chapter 8 simulations, per rear load
#: [N]; units N m/rad (kq4, kq7) and N m s/rad (ku4, ku7). Applied as
#: T7 = -(kq4 q4 + kq7 q7 + ku4 u4 + ku7 u7).
#: One row per load of :data:`whipple_kick.library.thesis.LOADS_N` (570, 635, 701 N), keyed by the whole newtons.
THESIS_GAINS = dict(zip((round(load) for load in thesis.LOADS_N), (
    {"kq4": -18.619, "kq7": 14.721, "ku4": -6.2915, "ku7": 1.5647},
    {"kq4": -19.5679, "kq7": 15.4934, "ku4": -6.7665, "ku7": 1.5876},
    {"kq4": -20.5164, "kq7": 16.2624, "ku4": -7.3074, "ku7": 1.600},
), strict=True))


def lqr_gains(moore, speed=3.0, Q=None, R=1.0):
    """LQR gains on the linearised classic model of ``moore`` at ``speed``.

    Parameters
    ----------
    moore : mapping
        Moore parameters (bicycle with rider) by name.
    speed : float
        Design speed [m/s], > 0.
    Q : array_like (4, 4), optional
        State weight (default identity).
    R : float
        Steer-torque weight (default 1).

    Returns
    -------
    K : ndarray, shape (4,)
        ``[kq4, kq7, ku4, ku7]`` for ``T7 = -K x``.
    poles : ndarray, shape (4,), complex
        Closed-loop eigenvalues of ``A - B K``.
    """
    check_range("design speed", speed, 0.0, None, "m/s", low_open=True)
    A, B = classic.linear_state_space(moore, speed)
    return _solve_lqr(A, B[:, [1]], _weight(Q), R)


def _solve_lqr(A, b, Qm, R):
    """LQR for one input: (K as a flat array, closed-loop poles).

    ``K = R^-1 b^T P`` with ``P`` the stabilising solution of the continuous
    algebraic Riccati equation ``A^T P + P A - P b R^-1 b^T P + Q = 0``.
    """
    Rm = np.atleast_2d(check_range("R", R, 0.0, None, "(weight)", low_open=True))
    P = solve_continuous_are(A, b, Qm, Rm)
    K = np.linalg.solve(Rm, b.T @ P)
    return K.ravel(), np.linalg.eigvals(A - b @ K)


def heading_state_space(moore, speed):
    """Classic model with the yaw angle as a fifth state, for a heading-holding rider.

    Returns
    -------
    A : ndarray, shape (5, 5)
        For x = [q3, q4, q7, u4, u7]; the q3 row is
        :func:`classic.yaw_rate_map` (q3 itself enters nothing: yaw is cyclic).
    b : ndarray, shape (5, 1)
        Steer-torque column.
    """
    A4, B4 = classic.linear_state_space(moore, speed)
    A = np.zeros((5, 5))
    A[1:, 1:] = A4
    A[0, 1:] = classic.yaw_rate_map(moore, speed)
    b = np.zeros((5, 1))
    b[1:, 0] = B4[:, 1]
    return A, b


def heading_lqr_gains(moore, speed=3.0, Q=None, R=1.0):
    """LQR rider who also steers back to the heading held before a disturbance.

    Same design as :func:`lqr_gains` on the state x = [q3, q4, q7, u4, u7]
    of :func:`heading_state_space`: ``T7 = -K x``. Not the thesis' rider
    (its law has no yaw term); made to measure what holding a heading
    changes. Use the gains with ``simulation.run(..., gains=...)`` on a
    scenario whose steady motion is straight (e.g. symmetric tyres).
    Parameters as for :func:`lqr_gains`, with ``Q`` 5x5.

    Returns
    -------
    K : ndarray, shape (5,)
        ``[kq3, kq4, kq7, ku4, ku7]`` (:data:`HEADING_GAIN_ORDER`).
    poles : ndarray, shape (5,), complex
        Closed-loop eigenvalues.
    """
    check_range("design speed", speed, 0.0, None, "m/s", low_open=True)
    A, b = heading_state_space(moore, speed)
    return _solve_lqr(A, b, _weight(Q, size=5), R)


def _weight(Q, size=4):
    Qm = np.eye(size) if Q is None else np.asarray(Q, dtype=float)
    if Qm.shape != (size, size):
        raise InputError(f"Q must be {size}x{size}, got shape {Qm.shape}")
    return Qm


def gains_dict(K, scale=1.0):
    """Gains by name (``kq4 kq7 ku4 ku7``) from an array of exactly four, scaled by ``scale``.

    Raises
    ------
    InputError
        ``K`` does not hold exactly four gains (a 5-gain heading design is
        :data:`HEADING_GAIN_ORDER`: name it with ``dict(zip(HEADING_GAIN_ORDER, K))``).

    Example
    -------
    >>> gains_dict([-12.0, 9.0, -4.0, 1.0], scale=0.5)
    {'kq4': -6.0, 'kq7': 4.5, 'ku4': -2.0, 'ku7': 0.5}
    """
    values = np.ravel(K)
    if values.size != len(GAIN_ORDER):
        raise InputError(f"gains_dict needs exactly {len(GAIN_ORDER)} gains ({', '.join(GAIN_ORDER)}), "
                         f"got {values.size}")
    return {name: float(scale * k) for name, k in zip(GAIN_ORDER, values, strict=True)}


def thesis_gains(rear_load_n):
    """Table 8.4 gains for one of the thesis' rear loads (:data:`whipple_kick.library.thesis.LOADS_N`)."""
    load = check_range("rear load", rear_load_n, 0.0, None, "N", low_open=True)
    key = int(round(load))
    if key not in THESIS_GAINS or abs(load - key) > 1e-9:
        raise InputError(f"thesis gains exist for rear loads {thesis.loads_text(last=' and ')} N only, "
                         f"got {rear_load_n} N")
    return dict(THESIS_GAINS[key])


def closed_loop_matrix(moore, speed, K):
    """``A - B_T7 K`` of the linearised classic model."""
    A, B = classic.linear_state_space(moore, speed)
    return A - B[:, [1]] @ np.atleast_2d(np.ravel(K))


def closed_loop_poles(moore, speed, gains):
    """Closed-loop poles [1/s] of the linearised classic (no-slip) model with gains by name.

    The rider's law is ``T7 = -(kq3 q3 + kq4 q4 + kq7 q7 + ku3 u3 + ku4 u4 + ku7 u7)``
    (missing gains 0). The yaw rate is a fixed combination of the four states
    (:func:`classic.yaw_rate_map`), so ``ku3`` folds into the other gains; a
    yaw-angle gain ``kq3`` adds the yaw angle as a fifth state
    (:func:`heading_state_space`), otherwise the yaw angle is left out
    (its pole is 0 whatever the rider does).

    Parameters
    ----------
    moore : mapping
        Moore parameters of the bicycle with rider (the plant of the run).
    speed : float
        Forward speed [m/s], > 0.
    gains : mapping
        Gains by name (N m/rad, N m s/rad).

    Returns
    -------
    ndarray, complex
        Sorted by decreasing real part.

    Example
    -------
    >>> from whipple_kick import benchmark, control
    >>> moore = benchmark.to_moore(benchmark.meijaard2007_parameters())
    >>> poles = control.closed_loop_poles(moore, 5.0, {})     # no rider: the benchmark at 5 m/s
    >>> bool(poles[0].real < 0)                                 # self-stable there
    True
    """
    check_range("speed", speed, 0.0, None, "m/s", low_open=True)
    g = {name: float(gains.get(name, 0.0)) for name in ("kq3", "kq4", "kq7", "ku3", "ku4", "ku7")}
    yaw = classic.yaw_rate_map(moore, speed)
    K4 = np.array([g["kq4"], g["kq7"], g["ku4"], g["ku7"]]) + g["ku3"] * yaw
    if g["kq3"]:
        A, b = heading_state_space(moore, speed)
        poles = np.linalg.eigvals(A - b @ np.r_[g["kq3"], K4][None, :])
    else:
        poles = np.linalg.eigvals(closed_loop_matrix(moore, speed, K4))
    return poles[np.argsort(-poles.real, kind="stable")]



def output_feedback_lqr(A, b, C, Q=None, R=1.0, K0=None, X0=None):
    """LQR-optimal gains of a law that feeds back only what the rider feels: ``u = -K C x``.

    Minimises the LQR cost ``integral(y^T Q y + R u^2) dt`` with ``y = C x``,
    averaged over initial states of covariance ``X0`` (Levine and Athans
    1970, "On the determination of the optimal constant output feedback
    gains for linear multivariable systems", IEEE Trans. Automatic Control
    15(1):44-48): ``J = trace(P X0)``, ``(A - b K C)^T P + P (A - b K C) + C^T
    (Q + K^T R K) C = 0``, by BFGS with the exact gradient ``2 (R K C - b^T P)
    L C^T``, ``L`` the closed loop's Lyapunov solution for ``X0``. With
    ``C`` the identity it is the full-state LQR.

    Parameters
    ----------
    A : ndarray (n, n)
        The model's state matrix (the rider's law left out).
    b : ndarray (n, 1)
        Its steer-torque column.
    C : ndarray (m, n)
        Picks the felt states.
    Q : ndarray (m, m), optional
        Weight on the felt states (default identity, as :func:`lqr_gains`).
    R : float
        Weight on the steer torque.
    K0 : array_like (m,), optional
        A stabilising start (default zeros; the open loop must then be stable).
    X0 : ndarray (n, n), optional
        Initial-state covariance (default ``C^T C`` plus 1e-3 on every state, so
        the states the rider does not feel count a little).

    Returns
    -------
    K : ndarray (m,)
    poles : ndarray, complex
        Eigenvalues of ``A - b K C``.

    Raises
    ------
    InputError
        ``K0`` does not stabilise the model.
    """
    A, b, C = (np.asarray(v, dtype=float) for v in (A, b, C))
    n, m = A.shape[0], C.shape[0]
    Qm = np.eye(m) if Q is None else np.asarray(Q, dtype=float)
    X0 = C.T @ C + 1e-3 * np.eye(n) if X0 is None else np.asarray(X0, dtype=float)
    K = np.zeros(m) if K0 is None else np.asarray(K0, dtype=float).ravel()

    def cost(k):
        acl = A - b @ k[None, :] @ C
        if np.max(np.linalg.eigvals(acl).real) >= -1e-9:
            return np.inf, np.zeros(m)
        weight = C.T @ (Qm + R * np.outer(k, k)) @ C
        P = solve_continuous_lyapunov(acl.T, -weight)
        L = solve_continuous_lyapunov(acl, -X0)
        grad = 2.0 * ((R * k[None, :] @ C - b.T @ P) @ L @ C.T).ravel()
        return float(np.trace(P @ X0)), grad

    if not np.isfinite(cost(K)[0]):
        raise InputError("the start gains do not stabilise the model the rider is designed on")
    # BFGS steps that leave the stable set get an infinite cost and are shortened by the line search.
    best = minimize(cost, K, jac=True, method="BFGS", options={"gtol": 1e-8, "maxiter": 500})
    k = best.x if np.isfinite(best.fun) and best.fun <= cost(K)[0] else K
    # BFGS' own status is no verdict: it stops with "precision loss" at optima whose gradient is ~1e-7 of the
    # cost, and with "success" only below gtol. The gradient at the gains returned decides.
    J, grad = cost(k)
    gradient = relative_gradient(J, grad, k)
    if not gradient <= GRADIENT_TOLERANCE:
        warnings.warn(f"the output-feedback LQR design did not converge: relative gradient {gradient:.2g} > "
                      f"{GRADIENT_TOLERANCE:g} after {best.nit} BFGS iterations ({best.message}); the gains "
                      "stabilise the model but are not its LQR optimum", ConvergenceWarning, stacklevel=2)
    return k, np.linalg.eigvals(A - b @ k[None, :] @ C)


#: Largest :func:`relative_gradient` at which :func:`output_feedback_lqr` counts as converged: a change of the
#: gains by a fraction e of their size changes the cost by at most 1e-4 e of itself (to first order), so a 1 %
#: change by 1e-6 of the cost. The designs of scripts/output_feedback_convergence.py (arms, reflex, leaning
#: body; 14 optimisations, 12 of them ending in BFGS' "precision loss") reach at most 2.5e-6.
GRADIENT_TOLERANCE = 1e-4


def relative_gradient(cost, gradient, gains):
    """``|gradient| max(|gains|, 1) / |cost|``: the cost's relative change per relative change of the gains.

    Dimensionless, so one tolerance (:data:`GRADIENT_TOLERANCE`) serves
    gains and costs of any size; infinite for an infinite cost (an unstable
    closed loop).

    Example
    -------
    >>> f"{relative_gradient(100.0, np.array([1e-6, 0.0]), np.array([20.0, 0.0])):.1e}"
    '2.0e-07'
    """
    if not np.isfinite(cost) or cost == 0.0:
        return math.inf
    return float(np.linalg.norm(gradient) * max(float(np.linalg.norm(gains)), 1.0) / abs(cost))


def stabilising_gains(A, b, C, K0, margin=0.05):
    """Gains of ``u = -K C x`` near ``K0`` that make ``A - b K C`` stable (spectral abscissa below ``-margin``).

    Minimises the closed loop's largest real part by Nelder-Mead from ``K0``
    (and from ``K0`` scaled by 2, 0.5 and -1 if that fails): the start
    :func:`output_feedback_lqr` needs when the model differs much from the
    one ``K0`` was designed on.

    Raises
    ------
    InputError
        No such gains were found.
    """
    A, b, C = (np.asarray(v, dtype=float) for v in (A, b, C))
    K0 = np.asarray(K0, dtype=float).ravel()

    def abscissa(k):
        return float(np.max(np.linalg.eigvals(A - b @ k[None, :] @ C).real))

    for start in (K0, 2.0 * K0, 0.5 * K0, -K0):
        if abscissa(start) < -margin:
            return start
        found = minimize(lambda k: abscissa(k) + 1e-4 * float(k @ k) ** 0.5, start, method="Nelder-Mead",
                         options={"xatol": 1e-6, "fatol": 1e-9, "maxiter": 4000, "adaptive": True})
        if abscissa(found.x) < -margin:
            return found.x
    raise InputError("no gains of the rider's law were found that stabilise the model it is designed on")


# ----------------------------------------------------- the design on the simulated model

@functools.lru_cache(maxsize=256)
def _whipple_lqr(design_items, speed):
    K, poles = lqr_gains(dict(design_items), speed)
    return tuple(np.ravel(K)), tuple(np.ravel(poles))


def whipple_lqr(design, speed):
    """:func:`lqr_gains` of the bicycle with rider ``design`` at ``speed``, once per process for each pair.

    A sweep over pressures or kicks designs the same rider once per process.

    Returns
    -------
    K : ndarray, shape (4,)
        The gains in :data:`GAIN_ORDER`.
    poles : ndarray
        The closed loop's eigenvalues.
    """
    K, poles = _whipple_lqr(tuple(sorted(design.items())), float(speed))
    return np.array(K), np.array(poles)


@functools.lru_cache(maxsize=256)
def _classic_poles(moore_items, speed, gains_items):
    return tuple(closed_loop_poles(dict(moore_items), speed, dict(gains_items)))


def classic_closed_loop_poles(moore, speed, gains):
    """:func:`closed_loop_poles`, once per process for each bicycle, speed and gains.

    The no-slip model's poles depend on those only: a sweep over tyres or
    kicks computes them once per process (~3 ms a case).
    """
    return np.asarray(_classic_poles(tuple(sorted(moore.items())), float(speed), tuple(sorted(gains.items()))))


def lqr_on_simulated_model(spec, moore, design, body, rear, front, model):
    """The LQR rider designed on the model the run simulates (``lqr_model="simulated"``).

    The model of the run (its tyres, carcass, body, arms and reflex) with
    symmetric tyres, linearised about upright straight running at the design
    speed at constant speed (:func:`whipple_kick.model.slip.heading_linearisation`);
    the law feeds back roll, steer and their rates, and the upper body's lean
    and its rate when it leans (:func:`whipple_kick.model.slip.parameters.gain_states`),
    with gains LQR-optimal for that law (identity weights on those states,
    1 on the torque, as the Whipple design), found from the Whipple design's
    gains by :func:`whipple_kick.simulate.control.output_feedback_lqr`. Where the
    Whipple gains do not stabilise the model, the arms' and the reflex's
    gains are brought in from 0 in steps, each design starting from the last.

    Parameters
    ----------
    spec : whipple_kick.simulate.scenario.DesignSpec
        What the design reads of the run (speed, lean, heading, gain scale, the model's options).
    moore, design : dict
        The bicycle as simulated, and with the whole rider lumped (the Whipple design's model).
    body : dict
        The rider's body parameters (:func:`whipple_kick.simulate.assembly.rider_body`).
    rear, front : Tyre
        The run's tyres.
    model : whipple_kick.model.slip.Model
        The run's model (:func:`whipple_kick.simulate.assembly.model_of`).

    Returns
    -------
    gains : dict
        By name (:func:`whipple_kick.model.slip.parameters.gain_names`), times ``gain_scale``.
    poles : ndarray
        The design's closed-loop eigenvalues.
    """
    speed = spec.speed
    felt, K = simulated_design_start(spec, design, model.parts)
    scaled = SCALED_BODY_GAINS
    models = {}

    def design_model(share):
        """(A, b, C) of the design model with ``share`` of the ``scaled`` gains, built once per share."""
        if share not in models:
            models[share] = _linear_design_model(spec, moore, rear, front, body, felt, share, scaled, model)
        return models[share]

    def stabilises(gains, share):
        A, b, C = design_model(share)
        return bool(np.max(np.linalg.eigvals(A - b @ gains[None, :] @ C).real) < 0.0)

    # Continuation: the share of the arms' and reflex's gains grows while the gains still stabilise the
    # next model; where they do not, they are re-optimised at the last share they did (a larger margin).
    done, step = (1.0, 1.0) if stabilises(K, 1.0) else (0.0, 0.25)
    if not stabilises(K, done):   # the body alone (forearms on the bar, a leaning trunk) defeats the Whipple design
        K = stabilising_gains(*design_model(done), K)
    optimised_at = None
    while done < 1.0:
        share = min(1.0, done + step)
        if stabilises(K, share):
            done, step = share, step * 2.0
        elif optimised_at != done:
            K, _ = output_feedback_lqr(*design_model(done), K0=K)
            optimised_at = done
        elif step < 1e-3:
            raise InputError(f"no stabilising LQR rider was found on the model simulated at {speed:g} m/s "
                             f"(the design lost stability at {share:.1%} of the arms' and reflex's gains)")
        else:
            step /= 2.0
    K, poles = output_feedback_lqr(*design_model(1.0), K0=K)
    gains = dict.fromkeys(slip.gain_names(), 0.0)
    gains.update({name: float(spec.gain_scale * k) for name, k in zip(felt, K, strict=True)})
    return gains, poles


#: The body's gains (arms, reflex) the design on the simulated model brings in by continuation.
SCALED_BODY_GAINS = ("ka", "ca", "rq4", "rq7", "ru4", "ru7")


def simulated_design_start(spec, design, part_names):
    """The gains the design on the simulated model feeds back (``felt``) and its starting gains (Whipple design).

    ``part_names`` are the simulated model's parts (``slip.Model.parts``): each part's declared gains
    (:attr:`whipple_kick.model.parts.Part.gains`: the upper body's lean and lean rate) are fed back too,
    from 0.
    """
    speed = spec.speed
    felt = (["kq4", "kq7", "ku4", "ku7"] + [g for part in parts.named(part_names) for g in part.gains]
            + (["kq3"] if spec.heading else []))
    K = np.r_[whipple_lqr(design, speed)[0], np.zeros(len(felt) - 4)]
    if spec.heading:   # start from the Whipple model's heading design (its yaw gain holds the heading)
        whipple = dict(zip(HEADING_GAIN_ORDER, heading_lqr_gains(design, speed)[0], strict=True))
        K = np.array([whipple.get(name, 0.0) for name in felt])
    return felt, K


def _linear_design_model(spec, moore, rear, front, body, felt, share, scaled, model):
    """(A, b, C) of the design model with ``share`` of the ``scaled`` body gains (C picks the ``felt`` states)."""
    part = {k: (v * share if k in scaled else v) for k, v in body.items()}

    options = slip.ModelOptions(**dict(spec.model_options), symmetric_tyres=True)
    params = slip.model_parameters(moore, rear, front, options, model=model, body=part)
    up = steady.upright_state(params, spec.speed)
    rhs = slip.CompiledRHS(up.params)
    A, b = slip.heading_linearisation(rhs, up.x)
    names = list(slip.LINEAR_STATES) + list(slip.linear.body_states(rhs))
    keep = [i for i, n in enumerate(names) if n != "v_fwd"]   # constant speed
    A, b = A[np.ix_(keep, keep)], b[keep]
    names = [names[i] for i in keep]
    if "kq3" in felt:   # the heading q3 as a state: dq3/dt = u3 (nothing else depends on it)
        n = len(names)
        A = np.block([[A, np.zeros((n, 1))], [np.eye(n)[[names.index("u3")]], np.zeros((1, 1))]])
        b = np.vstack([b, [[0.0]]])
        names.append("q3")
    C = np.zeros((len(felt), len(names)))
    states = slip.gain_states()
    for row, gain in enumerate(felt):
        C[row, names.index(states[gain])] = 1.0
    return A, b, C
