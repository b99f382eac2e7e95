"""The sweep over speed: linear models of each loop, the classic model beside them, :func:`analyse`."""
from dataclasses import dataclass, field
import math

import numpy as np
import pandas as pd

from whipple_kick.errors import InputError, check_range
from whipple_kick.model import classic, slip
from whipple_kick.simulate import assembly, control, steady
from whipple_kick.simulate.scenario import DEFAULTS
from whipple_kick.simulate.steady import NoSteadyMotion

from ._constants import BODY_GROUPS, GROUPS, LOOPS, MAX_SPEEDS, ZERO_TORQUE_N_M
from .linear import NoRiderDesign, _base_params, _check_loop, _loop_params, _setup, _steady, linearise
from .modes import _wheelbase, mode_content, name_tracks, track
from .report import describe
from .summary import _summarise

#: Scenario fields a linear analysis about the steady motion at each speed does not read: the kick, the
#: run's length, sampling and end, the integration's numerics and the run's start. :func:`analyse` refuses
#: them other than at their defaults (a stability sweep over one would give identical rows).
NOT_ANALYSED = ("kick_displacement", "kick_duration", "kick_accel", "kick_profile", "kick_table", "kick_direction",
                "settle", "duration", "output_rate", "fall_angle_deg", "steer_limit_deg", "rtol", "piecewise",
                "plate_stop", "kick_heading", "start", "start_pitch")


def _refuse_unread(scenario):
    """InputError naming the first field of :data:`NOT_ANALYSED` set other than its default."""
    for name in NOT_ANALYSED:
        if getattr(scenario, name) != DEFAULTS[name]:
            raise InputError(f"{name} = {getattr(scenario, name)!r} is not read by the stability analysis (the "
                             f"linearisation about the steady motion at each speed) and would be ignored: leave it "
                             f"at its default {DEFAULTS[name]!r}")


# ------------------------------------------------------------------ the sweep

class _Loop:
    """Linear models of one loop at any speed, with the steady motion continued between calls."""

    def __init__(self, setup, loop, wheelbase):
        self.setup, self.loop, self.wheelbase = setup, loop, wheelbase
        self.base = _base_params(setup)
        # The eigenvectors' content groups: the rider body's too when its states are linearised.
        body = slip.linear.body_states(self.base)
        self.groups = GROUPS + (BODY_GROUPS if body else ())

    def model(self, speed, guess=None, other=None):
        """LinearModel at ``speed`` (NoSteadyMotion if there is none).

        ``other``: the other loop's steady motion at this speed. Where the
        rider's torque there is zero (upright straight running, symmetric
        tyres: ``T7 = -K x`` with x = 0) it is this loop's steady motion too,
        and no solve is needed.
        """
        params = _loop_params(self.setup, speed, self.loop, self.base)
        if other is not None:
            shared = steady.SteadyState(other.x, params.replace(**{n: other.params[n] for n in steady.STEADY_PARAMETERS}),
                                      other.residual, other.unknowns)
            rhs = slip.CompiledRHS(shared.params)
            if abs(rhs.outputs(0.0, shared.x)[1][slip.OUT["T7"]]) < ZERO_TORQUE_N_M:
                return linearise(params, shared, self.loop, "the other loop's (no steer torque)")
        steady_state, found_by = _steady(params, speed, guess)
        return linearise(params, steady_state, self.loop, found_by)

    def eigen(self, model):
        """(eigenvalues, angle-like eigenvectors as columns, shares per eigenvalue)."""
        lam, vec = np.linalg.eig(model.matrix)
        shares, scaled = mode_content(model, lam, vec, self.wheelbase)
        return lam, scaled, shares


def _classic_eigen(canonical, speed, K=None):
    """Eigenvalues and eigenvectors of the classic model from its canonical matrices (rider gains K)."""
    M, C1, K0, K2 = (canonical[k] for k in ("M", "C1", "K0", "K2"))
    g = canonical["g"]
    Minv = np.linalg.inv(M)
    A = np.zeros((4, 4))
    A[:2, 2:] = np.eye(2)
    A[2:, :2] = -Minv @ (g * K0 + speed**2 * K2)
    A[2:, 2:] = -speed * Minv @ C1
    if K is not None:
        b = np.zeros((4, 1))
        b[2:, 0] = Minv[:, 1]
        A = A - b @ np.atleast_2d(K)
    return np.linalg.eig(A)


def _classic_content(lam, vec, groups=GROUPS):
    """Shares of ``groups`` of the classic model's eigenvectors (roll and steer only)."""
    power = np.abs(vec[:2]) ** 2
    power = power / np.where(power.sum(axis=0) > 0, power.sum(axis=0), 1.0)
    shares = np.zeros((lam.size, len(groups)))
    shares[:, 0], shares[:, 1] = power[0], power[1]
    return vec[:2], shares


@dataclass
class Stability:
    """Outcome of :func:`analyse`.

    Attributes
    ----------
    scenario : whipple_kick.simulate.scenario.Scenario
    speeds : ndarray
        Speeds of the sweep [m/s].
    eigenvalues : pandas.DataFrame
        One row per eigenvalue, loop and speed: ``model`` ("slip" or
        "no-slip"), ``loop``, ``speed_m_s``, ``track`` (the followed
        eigenvalue), ``mode`` (:data:`MODES`), ``real_1_s``, ``imag_1_s``,
        ``frequency_hz``, ``damping_ratio`` and the ``share_*`` of
        :data:`GROUPS`.
    steady : pandas.DataFrame
        The steady motion at each loop and speed (lean, steer, yaw rate,
        drift, rear-wheel torque, how it was found, or why there is none).
    summary : dict
        JSON-ready: per loop the weave and capsize speeds, the stable speed
        ranges, the wobble, each mode's speed range; the same for the no-slip model.
    models : dict
        ``(loop, speed index) -> LinearModel``.
    """

    scenario: object
    speeds: np.ndarray
    eigenvalues: object
    steady: object
    summary: dict = field(default_factory=dict)
    models: dict = field(default_factory=dict)

    def state_space(self, speed, loop="closed"):
        """``control.StateSpace`` of the linear model at the sweep speed nearest ``speed``."""
        _check_loop(loop)
        k = int(np.argmin(np.abs(self.speeds - speed)))
        if (loop, k) not in self.models:
            raise InputError(f"no {loop}-loop model at {self.speeds[k]:g} m/s (no steady motion there, "
                             "or that loop was not analysed)")
        return self.models[loop, k].state_space()


def parse_speeds(text):
    """Speeds [m/s] from ``START:STOP:STEP`` (STOP included when on the grid) or ``V1,V2,...``.

    Parameters
    ----------
    text : str

    Returns
    -------
    ndarray
        Strictly increasing speeds in (0, 15] m/s, at most :data:`MAX_SPEEDS`.

    Raises
    ------
    InputError
        One line naming the text, the rule and the unit.

    Example
    -------
    >>> parse_speeds("1:2:0.5")
    array([1. , 1.5, 2. ])
    """
    text = str(text).strip()
    try:
        parts = [float(p) for p in text.split(":" if ":" in text else ",")]
    except ValueError:
        parts = None
    if parts is None or (":" in text and len(parts) != 3):
        raise InputError(f"speeds {text!r} are not START:STOP:STEP or a comma-separated list (m/s)")
    if ":" not in text:
        return check_speeds(parts)
    start, stop, step = parts
    check_range("speed step", step, 0.0, None, "m/s", low_open=True)
    count = math.floor((stop - start) / step + 1e-9) + 1
    if count < 1:
        raise InputError(f"speeds {text!r}: STOP {stop:g} m/s is below START {start:g} m/s")
    if count > MAX_SPEEDS:
        raise InputError(f"speeds {text!r} give {count} speeds; allowed at most {MAX_SPEEDS}")
    # Rounded to 1e-12 m/s, so that 0.5 + 190 * 0.05 is 10 and not 10.000000000000009.
    return check_speeds(np.round(start + step * np.arange(count), 12))


def check_speeds(speeds):
    """Speeds as a strictly increasing array, each in (0, 15] m/s; InputError otherwise.

    Example
    -------
    >>> check_speeds([1, 2.5])
    array([1. , 2.5])
    """
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    if speeds.size == 0 or speeds.size > MAX_SPEEDS:
        raise InputError(f"give 1 to {MAX_SPEEDS} speeds, got {speeds.size}")
    for v in speeds:
        check_range("speed", float(v), 0.0, 15.0, "m/s", low_open=True)
    if np.any(np.diff(speeds) <= 0):
        raise InputError("speeds must increase strictly (m/s)")
    return speeds


def analyse(scenario, speeds, *, loops=None, tyres=None):
    """Eigenvalues of the slip model and of the no-slip model across ``speeds``, with named modes.

    Parameters
    ----------
    scenario : whipple_kick.simulate.scenario.Scenario
        Bicycle, rider, tyres, controller, the model's options. Its speed is
        not used (``speeds`` are), and its kick, run, integration and start
        fields (:data:`NOT_ANALYSED`) are refused other than at their
        defaults. With the measured tyres' zero-slip offsets the
        steady motions are turns (large ones where the loop has a real
        eigenvalue near zero): ``symmetric_tyres=True`` analyses straight
        running (the ``stability`` command's default).
    speeds : array_like
        Increasing speeds [m/s].
    loops : tuple of str, optional
        Default ``("open", "closed")``, or ``("open",)`` with
        ``controller="off"``.
    tyres : (rear, front), optional
        Tyre objects instead of the scenario's.

    Returns
    -------
    Stability

    Example
    -------
    >>> from whipple_kick import Scenario
    >>> from whipple_kick.studies.stability import analyse
    >>> res = analyse(Scenario(symmetric_tyres=True), [3.0, 3.5, 4.0, 4.5, 5.0], loops=("open",))
    >>> sorted(set(res.eigenvalues["mode"]))
    ['capsize', 'caster', 'lateral_rear', 'relaxation_front', 'relaxation_rear', 'vertical', 'weave', 'wobble']
    """
    _refuse_unread(scenario)
    speeds = check_speeds(speeds)
    loops = _check_loops(scenario, loops)
    setup = _setup(scenario, tyres)
    wheelbase = _wheelbase(setup.moore)
    rows, steady_rows, models, contexts, raw = [], [], {}, {}, {}
    for loop in loops:
        contexts[loop] = _Loop(setup, loop, wheelbase)
        lams, vecs, shares = _sweep_loop(contexts[loop], speeds, models, steady_rows)
        rows += _named_rows("slip", loop, speeds, lams, vecs, shares, raw, groups=contexts[loop].groups,
                            arms=scenario.arms == "on")
    rows += _classic_rows(setup, speeds, loops, raw, groups=contexts[loops[0]].groups)
    result = Stability(scenario, speeds, pd.DataFrame(rows), pd.DataFrame(steady_rows), models=models)
    result.summary = {"title": describe(scenario, setup.info), "scenario": scenario.to_dict(),
                      "bicycle": setup.info, "tyre_notes": setup.notes, "loops": list(loops),
                      **_summarise(result, raw, _refiners(contexts, setup, result))}
    return result


def _check_loops(scenario, loops):
    """The loops to analyse (default: open, and closed unless there is no rider); InputError if impossible."""
    if loops is None:
        loops = ("open",) if scenario.controller == "off" else LOOPS
    for loop in loops:
        _check_loop(loop)
    if "closed" in loops and scenario.controller == "off":
        raise InputError("the closed loop needs a rider: controller 'off' has none (choose lqr or thesis)")
    return tuple(loops)


def _sweep_loop(ctx, speeds, models, steady_rows):
    """Eigenvalues, angle-like eigenvectors and shares at each speed of one loop (None without steady motion).

    The steady motion is continued from the previous speed's solution (or
    taken from the other loop's where the steer torque is zero there);
    ``models`` and ``steady_rows`` receive each speed's model and steady motion.
    """
    lams, vecs, shares, guess = [], [], [], None
    for k, v in enumerate(speeds):
        other = models.get(("open" if ctx.loop == "closed" else "closed", k))
        try:
            model = ctx.model(float(v), guess, None if other is None else other.steady)
        except (NoSteadyMotion, NoRiderDesign) as exc:
            steady_rows.append({"loop": ctx.loop, "speed_m_s": float(v), "found_by": None, "message": str(exc)})
            lams.append(None)
            vecs.append(None)
            shares.append(None)
            guess = None
            continue
        guess = model.steady.unknowns
        models[ctx.loop, k] = model
        steady_rows.append(_steady_row(ctx.loop, v, model))
        lam, vec, share = ctx.eigen(model)
        lams.append(lam)
        vecs.append(vec)
        shares.append(share)
    return lams, vecs, shares


def _steady_row(loop, speed, model):
    x = model.steady.x
    return {"loop": loop, "speed_m_s": float(speed), "found_by": model.found_by, "message": None,
            "roll_rad": float(x[slip.X["q4"]]), "steer_rad": float(x[slip.X["q7"]]),
            "yaw_rate_rad_s": float(x[slip.X["u3"]]), "lateral_velocity_m_s": float(x[slip.X["u2"]]),
            "rear_wheel_torque_n_m": float(model.steady.params["T6c"])}


def _named_rows(model_name, loop, speeds, lams, vecs, shares_all, raw=None, groups=GROUPS, arms=False):
    """Rows of the eigenvalue table for one loop: tracked, then named per branch.

    ``raw``, if given, receives ``(model_name, loop) -> (eigenvalues, vectors,
    track ids)`` per speed, for the summary's refinements. ``groups`` names
    the shares' columns (:data:`GROUPS`, then :data:`BODY_GROUPS` with a
    body); ``arms``: the rider's arms hold the bar (a steer oscillation
    without the front tyre is then the arms' and steer's mode).
    """
    ids = track(lams, vecs)
    if raw is not None:
        raw[model_name, loop] = (lams, vecs, ids)
    points = []
    for k, (lam, cur, shares) in enumerate(zip(lams, ids, shares_all, strict=True)):
        if lam is None:
            continue
        for j in range(lam.size):
            e = complex(lam[j])
            points.append({"model": model_name, "loop": loop, "speed_m_s": float(speeds[k]), "speed_index": k,
                           "track": int(cur[j]), "real": e.imag == 0.0, "real_1_s": e.real, "imag_1_s": e.imag,
                           "frequency_hz": abs(e.imag) / (2 * math.pi),
                           "damping_ratio": -e.real / abs(e) if e != 0 else 0.0, "shares": shares[j],
                           "arms": arms})
    name_tracks(points)
    rows = []
    for p in points:
        shares = p.pop("shares")
        p.pop("real")
        p.pop("arms")
        rows.append({**p, **{f"share_{g}": float(s) for g, s in zip(groups, shares, strict=True)}})
    return rows


def _canonical(setup):
    """The classic model's canonical matrices M, C1, K0, K2 (and g) of the scenario's bicycle (rigid rider)."""
    canonical = classic.canonical_matrices(setup.classic_moore)
    canonical["g"] = float(setup.classic_moore["g"])
    return canonical


def _classic_rows(setup, speeds, loops, raw=None, groups=GROUPS):
    """The no-slip model's eigenvalues, tracked and named like the slip model's (roll and steer content)."""
    canonical = _canonical(setup)
    rows = []
    for loop in loops:
        lams, vecs, shares_all = [], [], []
        for v in speeds:
            K = None
            if loop == "closed":
                K = _classic_gains(setup, v)
            lam, vec = _classic_eigen(canonical, float(v), K)
            scaled, shares = _classic_content(lam, vec, groups)
            lams.append(lam)
            vecs.append(scaled)
            shares_all.append(shares)
        rows += _named_rows("no-slip", loop, speeds, lams, vecs, shares_all, raw, groups=groups)
    return rows


def _classic_gains(setup, speed):
    """The rider's gains on the no-slip model: the scenario's controller on the rigid rider (Whipple design)."""
    gains, _ = assembly.controller_gains(setup.scenario.with_changes(speed=float(speed)).gains_spec, setup.design)
    return np.array([gains.get(n, 0.0) for n in control.GAIN_ORDER])


def _refiners(contexts, setup, result):
    """``(model, loop) -> eigen_at(speed, nearest index)``: eigenvalues and angle-like vectors at any speed."""
    out = {}
    for loop, ctx in contexts.items():
        def slip_at(v, k, ctx=ctx, loop=loop):
            near = result.models.get((loop, k))
            model = ctx.model(float(v), None if near is None else near.steady.unknowns)
            lam, vec, _ = ctx.eigen(model)
            return lam, vec
        out["slip", loop] = slip_at
    canonical = _canonical(setup)
    for loop in contexts:
        def classic_at(v, k, loop=loop):
            lam, vec = _classic_eigen(canonical, float(v), _classic_gains(setup, v) if loop == "closed" else None)
            return lam, _classic_content(lam, vec)[0]
        out["no-slip", loop] = classic_at
    return out
