"""The steady motion before the kick, found robustly, or the physical reason there is none.

:func:`whipple_kick.steady_state` solves the steady equations by
Newton-like iteration from upright straight running. That start is good when
the tyres' zero-slip offsets ask for a small steady lean, and poor when the
rider's closed loop is weak at the run's speed: near a speed where a real
closed-loop pole crosses zero the offsets' steady lean grows without bound
(the static gain is the inverse of that pole), the branch of steady motions
that starts upright with symmetric tyres folds back before the offsets reach
their measured size, and the steady motions that exist are turns on other
branches, at other leans. :func:`find_steady_state` tries, in order and each
only if the previous failed:

1. the direct solve (from upright running);
2. continuation in the tyres' offsets: symmetric tyres (exactly upright,
   always solvable), then the offsets scaled up to their measured size,
   each solve starting from the previous one (the motion connected to
   upright running, where the direct solve's start was too far from it);
3. steady turns: starts at leans of +-1 to +-30 deg, each with the yaw rate
   of a balanced turn (g tan(lean) / v) and its kinematic steer angle; of the
   motions found that are a start (below), the one with the smallest lean;
4. continuation in speed from neighbouring speeds where a steady motion is
   found, with the same rider and tyres.

A motion is taken as a start only if it is near-upright and inside the
tyres' measured slip range (:func:`start_problem`): lean and steer within
:data:`NEAR_UPRIGHT_DEG`, both tyres' slip within :data:`START_SLIP_DEG`. The turn
search finds motions on other branches too (the same tyres and rider hold
steady turns at 20 deg of lean, or at 85 deg of steer with the front tyre
sliding sideways and the rear wheel driving hard); for a run (``hold=True``)
a turn is taken only if the rider's closed loop about it is stable as well.
The direct solve and the two continuations stay on the branch of upright
running, whose stability is the rider's own
(:func:`whipple_kick.simulate.assembly.linear_stability` reports it).

If none succeeds, :class:`NoSteadyMotion` says why in physical terms (how far
the offset continuation got, the lean there, the real closed-loop pole that
reaches zero, and whether the symmetric closed loop is stable at that speed),
in one line, never with the solver's own message.

Example
-------
>>> from whipple_kick import Scenario, assembly, slip, steady
>>> sc = Scenario()
>>> moore, design, _ = assembly.build_bicycle(sc.bicycle_spec)
>>> rear, front, _ = assembly.build_tyres(sc.tyre_spec)
>>> gains, _ = assembly.controller_gains(sc.gains_spec, design)
>>> found = steady.find_steady_state(slip.model_parameters(moore, rear, front, gains=gains), 3.0)
>>> found.route
'direct'
"""
from dataclasses import dataclass
import math

import numpy as np
from scipy.optimize import root

from whipple_kick.errors import InputError, SimulationError
from whipple_kick.model import reflex, slip, transient
from whipple_kick.model import symbols as S
from whipple_kick.model.benchmark import from_moore, steer_axis_tilt

#: Leans [deg] of the steady turns tried when the direct solve fails, smallest first.
TURN_LEANS_DEG = (1.0, -1.0, 2.0, -2.0, 3.0, -3.0, 5.0, -5.0, 8.0, -8.0, 12.0, -12.0, 20.0, -20.0,
                  30.0, -30.0)
#: Speed steps [m/s] to the neighbouring speeds a speed continuation may start from, nearest first.
NEIGHBOUR_STEPS = (-0.5, 0.5, -1.0, 1.0)
#: Smallest step of a continuation parameter (offset fraction [-], speed [m/s]) before giving up.
_MIN_STEP = 1e-3
#: Most solves one :func:`find_steady_state` call may spend (about 5 ms each).
MAX_SOLVES = 400
#: Slowest speed [m/s] a speed continuation may start from.
_MIN_START_SPEED = 0.5
#: Largest absolute lean and steer [deg] of a start ("near-upright"): the rider is an LQR designed on the model
#: linearised about upright straight running, whose small-angle terms err by 1 - cos(10 deg) = 1.5 % at 10 deg;
#: and a start is meant to be the straight running of the experiment, not a turn (the turn search also finds
#: turns at 20 deg of lean, or at 85 deg of steer with the front tyre sliding sideways).
NEAR_UPRIGHT_DEG = 10.0
#: Largest absolute slip [deg] of either tyre in a start: the slip sweep's extent (thesis Section 7.3, slip angles up to
#: 6 deg; the tyre files' ``[measured] slip_deg``). A steady motion with a tyre sliding beyond it is no start.
#: The camber was measured to +-5 deg only (Section 7.3): a start leaning 5-10 deg rests on the fits' camber
#: extrapolation (the default rider with arms, designed on the model simulated, starts at 5.2 deg of lean).
START_SLIP_DEG = 6.0
#: A closed-loop pole whose real part exceeds this [1/s] makes the rider linearly unstable
#: (slower growth, by less than 1 % over a 10 s run, is not reported).
UNSTABLE_REAL_PART = 1e-3
#: A guessed unknown smaller than this (in its SI unit) starts at exactly 0: MINPACK's
#: forward-difference step is relative to each unknown (1.5e-8 |x|, or 1.5e-8 at x = 0),
#: so a round-off lean of 1e-14 rad would get a 1e-22 rad step and a useless Jacobian.
_ROUND_OFF = 1e-10


class NoSteadyMotion(InputError):
    """No steady motion exists near upright running for these inputs (speed, rider, tyres).

    A consequence of the user's choice of speed and rider, so the CLI treats
    it as a user mistake (one line, exit status 2).
    """


@dataclass
class Found:
    """A steady motion and how it was found.

    Attributes
    ----------
    steady : whipple_kick.SteadyState
        As returned by :func:`whipple_kick.steady_state`.
    route : str
        ``"direct"``, ``"steady turn started at L deg of lean (of n found)"``,
        ``"offset continuation (n steps)"`` or ``"speed continuation from
        v m/s (n steps)"``.
    solves : int
        Calls of :func:`whipple_kick.steady_state` spent.
    """

    steady: "SteadyState"
    route: str
    solves: int


def offset_scaled(params, fraction):
    """``params`` with every tyre's zero-slip offsets multiplied by ``fraction``.

    The offsets are the Magic-Formula coefficients that shift the curves at
    zero slip and camber (:data:`whipple_kick.model.slip.FY_OFFSET_INDICES`,
    :data:`whipple_kick.model.slip.MZ_OFFSET_INDICES`), in both coefficient slots
    of both wheels; ``fraction`` 0 gives symmetric tyres.
    """
    out = params.copy()
    for name in params:
        for prefix, indices in (("a", slip.FY_OFFSET_INDICES), ("c", slip.MZ_OFFSET_INDICES)):
            head, _, index = name.partition("_")
            if (len(head) == 3 and head[0] == prefix and head[1] in "rf" and head[2].isdigit()
                    and index.isdigit() and int(index) in indices):
                out[name] = fraction * params[name]
    return out


class _Counter:
    """Counts solves and stops the search when :data:`MAX_SOLVES` is spent."""

    def __init__(self):
        self.solves = 0

    def solve(self, params, speed, guess=None):
        """:func:`steady_state`, or None if it finds nothing (or the budget is spent)."""
        if self.solves >= MAX_SOLVES:
            return None
        self.solves += 1
        if guess is not None:
            guess = {name: (0.0 if abs(value) < _ROUND_OFF else value) for name, value in guess.items()}
        try:
            return steady_state(params, speed, guess=guess)
        except FloatingPointError:
            return None


def _continue(counter, solve_at, start, end, first_step):
    """Follow solutions of ``solve_at(value, guess)`` from ``start`` to ``end``.

    The step doubles after a success and is quartered after a failure, down
    to :data:`_MIN_STEP`. Returns (solution at ``end`` or None, last
    solution reached, value reached, steps taken).
    """
    value, guess, last, steps = start, None, None, 0
    first = solve_at(start, None)
    if first is None:
        return None, None, start, 0
    last, guess = first, first.unknowns
    step = math.copysign(min(abs(first_step), abs(end - start)), end - start)
    while value != end and counter.solves < MAX_SOLVES:
        nxt = end if abs(end - value) <= abs(step) else value + step
        found = solve_at(nxt, guess)
        if found is not None:
            value, last, guess, steps = nxt, found, found.unknowns, steps + 1
            step *= 2.0
        else:
            step /= 4.0
            if abs(step) < _MIN_STEP:
                break
    return (last if value == end else None), last, value, steps


def find_steady_state(params, speed, *, advice=None, hold=True):
    """Steady motion at ``speed`` [m/s] that a run can start from (see the module for the search).

    Parameters
    ----------
    params : mapping
        Slip-model parameters (:func:`whipple_kick.model.slip.model_parameters`),
        with the rider's gains.
    speed : float
        Forward speed [m/s], > 0.
    advice : str, optional
        What the user can change, appended to the error (e.g. "choose another
        design speed or speed").
    hold : bool
        A steady turn found by the turn search must also be held by the
        rider's closed loop (True: a run's start); False for a linear
        analysis, which is about the motion whatever its stability.

    Returns
    -------
    Found

    Raises
    ------
    NoSteadyMotion
        One line: why no steady motion was found, in physical terms.
    """
    counter = _Counter()
    direct = counter.solve(params, speed)
    if direct is not None and start_problem(direct) is None:
        return Found(direct, "direct", counter.solves)
    # Offsets: from symmetric tyres (exactly upright) up to the measured offsets, on the branch of upright running.
    # A step whose motion has left the tyres' measured range counts as a failed step. The last failed step (the
    # smallest step past the point reached) says why the continuation stopped: the range, or no solution (a fold).
    left = {}

    def offset_step(fraction, guess):
        found = counter.solve(offset_scaled(params, fraction), speed, guess)
        problem = None if found is None else start_problem(found)
        if found is None or problem is not None:
            left.update(fraction=fraction, problem=problem)
            return None
        return found

    found, last, fraction, steps = _continue(counter, offset_step, 0.0, 1.0, 0.25)
    if found is not None:
        return Found(found, f"offset continuation ({steps} steps)", counter.solves)
    turns, refused = {}, {}
    for lean in TURN_LEANS_DEG:
        turn = counter.solve(params, speed, turn_guess(params, speed, math.radians(lean)))
        if turn is None:
            continue
        key = (round(math.degrees(turn.unknowns["q4"]), 6), round(math.degrees(turn.unknowns["q7"]), 6))
        problem = start_problem(turn, hold=hold)
        if problem is None:
            turns.setdefault(key, (lean, turn))
        else:
            refused.setdefault(key, problem)
    if turns:
        lean, found = turns[min(turns, key=lambda k: math.hypot(*k))]
        return Found(found, f"steady turn started at {lean:+g} deg of lean (of {len(turns)} found)", counter.solves)
    # Neighbouring speeds: the upright branch there, followed to this speed.
    for step in NEIGHBOUR_STEPS:
        start = speed + step
        if start < _MIN_START_SPEED or counter.solves >= MAX_SOLVES:
            continue
        found_v, _, _, steps_v = _continue(
            counter, lambda v, guess: _start_or_none(counter.solve(params, v, guess)), start, speed, abs(step) / 4)
        if found_v is not None:
            return Found(found_v, f"speed continuation from {start:g} m/s ({steps_v} steps)", counter.solves)
    raise NoSteadyMotion(diagnosis(params, speed, last, fraction, advice, counter.solves >= MAX_SOLVES,
                                   refused=refused, direct=direct, left=left))


def start_problem(steady, hold=False):
    """Why ``steady`` (a :class:`SteadyState`) is no start, in a few words; None if it is one.

    A start is near-upright running (lean and steer within
    :data:`NEAR_UPRIGHT_DEG`) with both tyres inside their measured slip
    range (:data:`START_SLIP_DEG`); with ``hold`` the rider's closed loop
    about it must also be stable (slowest pole's real part <=
    :data:`UNSTABLE_REAL_PART`).
    """
    lean, steer = (math.degrees(steady.unknowns[n]) for n in ("q4", "q7"))
    where = f"lean {lean:+.1f} deg, steer {steer:+.1f} deg"
    if max(abs(lean), abs(steer)) > NEAR_UPRIGHT_DEG:
        return f"{where}: not near-upright (lean and steer within +-{NEAR_UPRIGHT_DEG:g} deg)"
    angles = {name: math.degrees(value) for name, value in (steady.angles or {}).items()}
    for wheel, word in (("r", "rear"), ("f", "front")):
        slip_angle = angles.get(f"slip_{wheel}", 0.0)
        if abs(slip_angle) > START_SLIP_DEG:
            return (f"{where}: the {word} tyre's slip {slip_angle:+.1f} deg is outside the measured "
                    f"+-{START_SLIP_DEG:g} deg")
    if hold:
        poles = _poles_or_none(steady.params, steady.x)
        if poles is None or poles[0].real > UNSTABLE_REAL_PART:
            pole = "" if poles is None else f" (slowest pole {poles[0].real:+.2f} 1/s)"
            return f"{where}: the rider's closed loop about it is unstable{pole}"
    return None


def _start_or_none(steady):
    """``steady`` if it is a start by :func:`start_problem` (without the closed loop's stability), else None."""
    return steady if steady is not None and start_problem(steady) is None else None


def turn_guess(params, speed, lean):
    """Starting values of a balanced steady turn at ``lean`` [rad]: yaw rate and kinematic steer.

    Yaw rate g tan(lean) / v (the lean that balances the turn's lateral
    acceleration); steer angle u3 w / (v cos(lam)) from the rolling
    kinematics (wheelbase w, steer-axis tilt lam of the bicycle).
    """
    bench = from_moore({name: params[name] for name in S.CLASSIC_CONSTANTS})
    yaw_rate = params["g"] * math.tan(lean) / speed
    return {"q4": lean, "u3": yaw_rate, "q7": yaw_rate * bench["w"] / (speed * math.cos(bench["lam"]))}


def lateral_poles(params, x):
    """Closed-loop poles [1/s] of the slip model about the steady state ``x``, at constant speed.

    The heading-frame linearisation (:func:`whipple_kick.model.slip.linear_state_space`)
    with the forward-speed row and column removed: the speed is held by the
    rear-wheel torque, and its own slow mode is not the rider's balance.
    Sorted by decreasing real part.
    """
    rhs = slip.CompiledRHS(params)
    body = slip.linear.body_states(rhs)
    if body:
        # A leaning body or a delayed reflex: the compiled Jacobian's linearisation, which carries their states
        # (the finite differences of linear_state_space perturb the bicycle's states only).
        closed = slip.heading_linearisation(rhs, x)[0]
    else:
        A, B, K = slip.linear_state_space(params, x, rhs=rhs)
        closed = A - B @ K
    keep = [i for i, name in enumerate(slip.LINEAR_STATES + body) if name != "v_fwd"]
    poles = np.linalg.eigvals(closed[np.ix_(keep, keep)])
    return poles[np.argsort(-poles.real, kind="stable")]


def _poles_or_none(params, x, speed=None):
    """:func:`lateral_poles` about ``x`` (or about the direct steady solve at ``speed``), None if that fails."""
    try:
        if x is None:
            found = steady_state(params, speed)
            params, x = found.params, found.x
        return lateral_poles(params, x)
    except (FloatingPointError, InputError):
        return None


def _nearest_real_pole(poles):
    if poles is None:
        return None
    real = poles[np.abs(poles.imag) < 1e-9].real
    return float(real[np.argmin(np.abs(real))]) if real.size else None


def diagnosis(params, speed, last, fraction, advice=None, exhausted=False, *, refused=None, direct=None,
              left=None):
    """One line saying why no steady motion was found (see :func:`find_steady_state`).

    ``last`` is the last steady motion of the continuation in the tyre
    offsets and ``fraction`` how far it got; ``exhausted`` that the search
    spent :data:`MAX_SOLVES`; ``refused`` the steady turns found that are no
    start (:func:`start_problem`'s reason by (lean, steer) in deg); ``direct``
    the direct solve's motion if it found one (and it was no start); ``left``
    where the offset continuation's motion first left the tyres' measured
    range (``fraction`` and ``problem``), if it did.
    """
    text = f"no near-upright steady motion at {speed:g} m/s: "
    if (last is None or fraction <= 0.0) and exhausted:
        text += f"the search stopped after {MAX_SOLVES} solves"
    elif last is None or fraction <= 0.0:
        text += "not even with symmetric tyres"
    elif left and left["problem"] is not None:
        text += (f"continued from symmetric tyres, the steady motion leaves the starts' range past "
                 f"{fraction:.1%} of their zero-slip offsets (at {left['fraction']:.1%}: {left['problem']})")
    else:
        lean = math.degrees(last.unknowns["q4"])
        near = _nearest_real_pole(_poles_or_none(last.params, last.x))
        text += (f"the closed loop cannot hold the steady turn the tyres' zero-slip offsets ask for "
                 f"(continued from symmetric tyres, the steady lean grows to {lean:+.1f} deg at "
                 f"{fraction:.0%} of the offsets")
        text += (f", where a real closed-loop pole has reached {near:+.3f} 1/s)" if near is not None else ")")
    poles = _poles_or_none(offset_scaled(params, 0.0), None, speed)
    if poles is not None:
        slowest = poles[0]
        pole_text = f"{slowest.real:+.2f}" + (f" +- {abs(slowest.imag):.2f}j" if abs(slowest.imag) > 1e-9 else "")
        text += (f"; with symmetric tyres the rider's closed loop is "
                 f"{'unstable' if slowest.real > 0 else 'stable'} at {speed:g} m/s (slowest pole {pole_text} 1/s)")
    if direct is not None:
        text += f"; the direct solve found no start ({start_problem(direct)})"
    if exhausted and last is not None and fraction > 0.0:
        text += f"; the search stopped after {MAX_SOLVES} solves"
    elif refused:
        closest = refused[min(refused, key=lambda k: math.hypot(*k))]
        text += (f"; the {len(refused)} steady turn{'s' if len(refused) > 1 else ''} found from "
                 f"{min(map(abs, TURN_LEANS_DEG)):g}-{max(TURN_LEANS_DEG):g} deg of lean "
                 f"{'are' if len(refused) > 1 else 'is'} no start (closest to upright: {closest})")
    elif TURN_LEANS_DEG and not exhausted:
        text += (f"; nor from steady turns of {min(map(abs, TURN_LEANS_DEG)):g}-{max(TURN_LEANS_DEG):g} "
                 "deg of lean")
    if advice:
        text += f"; {advice}"
    return text


# ------------------------------------------------------------ the steady equations

#: Parameters the steady solve sets (:func:`steady_state`): the rear-wheel torque holding the speed and the
#: carcass stiffnesses at the steady loads.
STEADY_PARAMETERS = ("T6c", "ccr", "ccf")


#: The wheels' angles of a steady motion (:func:`start_problem` checks the slips), as the compiled model's outputs [rad].
WHEEL_ANGLES = ("slip_r", "slip_f", "camber_r", "camber_f")


class SteadyState:
    """Result of :func:`steady_state`."""

    def __init__(self, x, params, residual, unknowns, angles=None):
        self.x = x                  # full state vector (its model's layout: slip.STATE_NAMES and the parts' states)
        self.params = params        # parameters with the holding drive torque T6c
        self.residual = residual    # max |residual| of the steady equations
        self.unknowns = unknowns    # dict of the solved quantities
        self.angles = angles        # the wheels' slip and camber [rad] (slip_r, slip_f, camber_r, camber_f), or None

    def __repr__(self):
        u = ", ".join(f"{k}={v:.3g}" for k, v in self.unknowns.items())
        return f"SteadyState({u}; residual {self.residual:.2g})"


def steady_state(params, speed, tol=1e-13, guess=None):
    """Steady motion at ``speed`` [m/s] with the tyres' offsets balanced.

    Unknowns: roll q4, steer q7, pitch q5, tyre compressions q9, q10, lateral
    drift velocity u2, yaw rate u3 and the rear-wheel torque T6c that holds
    the speed (the tyres' zero-slip offsets exchange energy with the rolling,
    so T6c may brake or drive). The tyre states are at their steady values
    (forces, or patch slip and camber equal to the kinematic ones); the
    quadrature states are 0. Equations: front contact on
    the ground and every acceleration zero in the heading frame
    (du1/dt + u3 u2 = du2/dt - u3 u1 = du3/dt = du4/dt = du7/dt = du9/dt =
    du10/dt = 0), with q3 = 0 so the heading is N.x.

    Parameters
    ----------
    params : mapping
        From :func:`model_parameters`; ``T6c`` is replaced by the solution.
    speed : float
        Forward speed of the rear contact [m/s], > 0.
    guess : mapping, optional
        Starting values of the unknowns by name (e.g. ``SteadyState.unknowns``
        of a neighbouring case); a name not given starts from upright
        running. Continuation (:mod:`whipple_kick.simulate.steady`) passes it.

    Returns
    -------
    SteadyState
    """
    rhs = slip.CompiledRHS(params)
    rr = params["rr"]
    weight = params["g"] * (params["mc"] + params["md"] + params["me"] + params["mf"] + params.get("mt", 0.0))
    L = rhs.layout
    x = np.zeros(len(L.STATE_NAMES))
    x[slip.X["u1"]] = speed
    # The parts' coordinates (a leaning upper body's lean) have their own steady values, their speeds are 0.
    part_coordinates = tuple(n for p in L.parts for n in p.coordinates)
    names = ("q4", "q7", "q5", "q9", "q10", "u2", "u3") + part_coordinates + ("T6c",)
    z0 = np.array([0.0, 0.0, steer_axis_tilt(params), 0.5 * weight / params["kzr"], 0.5 * weight / params["kzf"],
                   0.0, 0.0] + [0.0] * len(part_coordinates) + [0.0])
    if guess is not None:
        z0 = np.array([float(guess.get(name, value)) for name, value in zip(names, z0, strict=True)])
    scale = np.array([1.0, 1.0, 1.0, 1e-3, 1e-3, 1.0, 1.0] + [1.0] * len(part_coordinates) + [1.0])
    # Indices looked up once: the residual runs some 40 times a solve.
    slots = np.array([L.X[name] for name in names[:-1]], dtype=np.intp)
    p, drive = rhs.p, slip.P["T6c"]
    tyre_states = _SteadyTyres(rhs)
    speeds = [slip.X[n] for n in ("u1", "u2", "u3")]
    rates = np.array([slip.X[n] for n in ("u1", "u2", "u3", "u4", "u7", "u9", "u10")]
                     + [L.X[n] for part in L.parts for n in part.speeds], dtype=np.intp)
    holonomic = slip.OUT["holonomic"]

    def state(z):
        xs = x.copy()
        xs.put(slots, z)   # z's first len(slots) values: the state's unknowns (T6c, the last, is a parameter)
        p[drive] = z[-1]
        return tyre_states(xs)

    def residual(zs):
        xs = state(zs * scale)
        dx, out = rhs.outputs_view(0.0, xs)
        u1, u2, u3 = xs.item(speeds[0]), xs.item(speeds[1]), xs.item(speeds[2])
        du1, du2, du3, du4, du7, du9, du10, *du_parts = dx[rates].tolist()
        return np.array([out.item(holonomic) * 1e2, (du1 + u3 * u2) * rr, du2 - u3 * u1, du3, du4, du7,
                         du9 * 1e-2, du10 * 1e-2, *du_parts], dtype=float)

    sol = root(residual, z0 / scale, method="hybr", options={"xtol": tol})
    z = sol.x * scale
    res = float(np.max(np.abs(residual(sol.x))))
    if not np.all(np.isfinite(z)) or res > 1e-8:
        raise FloatingPointError(f"steady state not found at {speed} m/s: {sol.message} (residual {res:.3g})")
    xs = state(z)
    out = rhs.outputs_view(0.0, xs)[1]
    out_params = params.copy()
    out_params["T6c"] = float(z[-1])
    out_params["ccr"], out_params["ccf"] = float(rhs.p[slip.P["ccr"]]), float(rhs.p[slip.P["ccf"]])
    return SteadyState(xs, out_params, res, dict(zip(names, z, strict=True)),
                       {name: float(out[slip.OUT[name]]) for name in WHEEL_ANGLES})


def _steady_tyre_states(rhs, x):
    """``x`` with the tyre slots at their steady values for its kinematics.

    The relaxed forces and moments at the steady curves (``force_lag``), the
    patch slip and camber at the kinematic ones (contact forms), or the
    carcass deflection carrying the steady force and the camber (carcass),
    all at the state's own slip, camber and load. For the carcass tyre the
    stiffnesses ``ccr``/``ccf`` of ``rhs`` are set first from the state's
    loads (:func:`carcass_stiffness`), and its stored-energy quadratures to
    ``c y^2 / 2`` (what the carcass holds at the start).
    """
    return _SteadyTyres(rhs)(np.array(x, dtype=float))


class _SteadyTyres:
    """:func:`_steady_tyre_states` of one compiled model, its indices looked up once (a steady solve sets the
    tyre states some 40 times), in place on a state array of its own."""

    def __init__(self, rhs):
        self.rhs = rhs
        L = rhs.layout
        self.reflex = [L.X[n] for n in L.REFLEX_STATES]
        outputs = transient.FORMS[rhs.transient].steady_outputs
        self.carcass = outputs is None   # the form sets its own: the carcass (the only one), its stiffness from the loads
        if self.carcass:
            P, X, OUT = slip.P, slip.X, slip.OUT
            self.loads = [OUT["fz_r"], OUT["fz_f"]]
            self.wheels = [(OUT[f"fy_ss_{w}"], OUT[f"camber_{w}"], X[f"carcass_y_{w}"], X[f"camber_patch_{w}"],
                            X[f"E_carcass_{w}"]) for w in "rf"]
            self.sigma = np.array([P["sigr"], P["sigf"]], dtype=np.intp)
            self.stiffness_scale, self.ccr, self.ccf = P["carcass_stiffness_scale"], P["ccr"], P["ccf"]
            self.cornering = np.empty(2)   # the compiled cornering stiffnesses' output
            self.pointers = rhs.p.ctypes.data, self.cornering.ctypes.data
        else:
            self.slots = np.array([slip.X[slot] for slot in slip.PATCH_STATES], dtype=np.intp)
            self.values = np.array([slip.OUT[name] for name in outputs], dtype=np.intp)

    def __call__(self, x):
        """``x`` (a float array the caller owns) with its tyre slots set, as :func:`_steady_tyre_states`."""
        rhs = self.rhs
        _, out = rhs.outputs_view(0.0, x)
        # The reflex filter (a delayed reflex's model) in equilibrium with its (steady) input: its output is that input.
        if self.reflex:
            x[self.reflex] = reflex.steady_state(out[slip.OUT["reflex_input"]], rhs.p[slip.P["reflex_delay"]])
        if not self.carcass:
            x[self.slots] = out[self.values]
            return x
        p = rhs.p
        rhs.lib.wk_slip_cornering_stiffness(out.item(self.loads[0]), out.item(self.loads[1]), *self.pointers)
        sigma_r, sigma_f = p.item(self.sigma[0]), p.item(self.sigma[1])
        if sigma_r and sigma_f:   # carcass_stiffness's arithmetic, on Python floats
            scale = p.item(self.stiffness_scale)
            c_r, c_f = self.cornering.item(0) / sigma_r * scale, self.cornering.item(1) / sigma_f * scale
        else:   # on arrays, as there: a zero sigma0 gives inf (a Python float division would raise)
            c_r, c_f = (self.cornering / p[self.sigma] * p[self.stiffness_scale]).tolist()
        p[self.ccr], p[self.ccf] = c_r, c_f
        for c, (force, camber, deflection, camber_patch, energy) in zip((c_r, c_f), self.wheels, strict=True):
            y = out.item(force) / c if c > 0.0 else 0.0
            x[deflection] = y
            x[camber_patch] = out.item(camber)
            x[energy] = 0.5 * c * y * y
        return x


def carcass_stiffness(rhs, fz_rear, fz_front):
    """Carcass lateral stiffnesses (rear, front) [N/m]: ``C_Fa(F_z0) / sigma0`` at the given loads [N].

    ``C_Fa`` is the cornering stiffness ``-dF_y/dslip`` at zero slip and
    camber (of the blended, scaled curve the model evaluates), computed by
    the compiled model.
    """
    out = np.empty(2)
    rhs.lib.wk_slip_cornering_stiffness(float(fz_rear), float(fz_front), rhs.p.ctypes.data, out.ctypes.data)
    return out / np.array([rhs.p[slip.P["sigr"]], rhs.p[slip.P["sigf"]]])


def upright_state(params, speed, tol=1e-13, pitch_without_compression=False):
    """Upright straight running at ``speed`` [m/s]: the start of the thesis authors' published code.

    Roll, steer, yaw and every lateral speed are 0, the rear contact moves
    along N.x at ``speed``, the rear-wheel torque ``T6c`` is 0; pitch and the
    tyre compressions are solved so that the front contact is on the ground
    and both tyres are in vertical equilibrium; the tyre states are at their
    steady values (zero slip and camber: the fits' zero-slip offsets).
    With measured tyres this is NOT a steady motion: the offsets push the
    bicycle off it from the first instant (``unknowns["largest_rate"]`` says
    how hard: the largest ``|acceleration|`` of the lateral speeds u2, u3, u4, u7
    in SI units).

    Parameters
    ----------
    params : mapping
        From :func:`model_parameters` (``T6c`` is set to 0).
    speed : float
        Forward speed [m/s], > 0.
    pitch_without_compression : bool
        Solve the pitch with both tyres uncompressed, as the thesis authors'
        published code does, then only the compressions (vertical
        equilibrium at that pitch). The front contact is then below the
        ground by about the rear compression less the front one
        (``unknowns["front_contact_offset_m"]``, + below); the holonomic
        constraint is kept at that offset for the whole run (only its rate
        is imposed).

    Returns
    -------
    SteadyState
        ``residual`` is that of the solved equations (holonomic and the two
        vertical accelerations, or the two without the holonomic with
        ``pitch_without_compression``), not of the motion.

    Example
    -------
    >>> start = upright_state(params, 3.0)                        # doctest: +SKIP
    >>> float(start.x[slip.X["q4"]]), float(start.params["T6c"])       # doctest: +SKIP
    (0.0, 0.0)
    """
    out_params = params.replace(T6c=0.0)
    rhs = slip.CompiledRHS(out_params)
    weight = params["g"] * (params["mc"] + params["md"] + params["me"] + params["mf"] + params.get("mt", 0.0))
    x = np.zeros(len(rhs.layout.STATE_NAMES))
    x[slip.X["u1"]] = speed
    names = ("q5", "q9", "q10")
    if pitch_without_compression:
        x[slip.X["q5"]] = steer_axis_tilt(params)
        x = slip.solve_pitch(rhs, _steady_tyre_states(rhs, x))
        names = names[1:]

    def state(z):
        xs = x.copy()
        for name, value in zip(names, z, strict=True):
            xs[slip.X[name]] = value
        return _steady_tyre_states(rhs, xs)

    def residual(z):
        dx, out = rhs.outputs(0.0, state(z))
        holonomic = () if pitch_without_compression else (out[slip.OUT["holonomic"]] * 1e2,)
        return np.array([*holonomic, dx[slip.X["u9"]] * 1e-2, dx[slip.X["u10"]] * 1e-2])

    z0 = np.array([steer_axis_tilt(params), 0.5 * weight / params["kzr"],
                   0.5 * weight / params["kzf"]])[-len(names):]
    sol = root(residual, z0, method="hybr", options={"xtol": tol})
    res = float(np.max(np.abs(residual(sol.x))))
    if not np.all(np.isfinite(sol.x)) or res > 1e-8:
        raise FloatingPointError(f"upright start not found at {speed} m/s: {sol.message} (residual {res:.3g})")
    xs = state(sol.x)
    dx, out = rhs.outputs(0.0, xs)
    unknowns = dict(zip(names, (float(v) for v in sol.x), strict=True))
    unknowns["largest_rate"] = float(max(abs(dx[slip.X[n]]) for n in ("u2", "u3", "u4", "u7")))
    unknowns["front_contact_offset_m"] = float(out[slip.OUT["holonomic"]])
    out_params["ccr"], out_params["ccf"] = float(rhs.p[slip.P["ccr"]]), float(rhs.p[slip.P["ccf"]])
    return SteadyState(xs, out_params, res, unknowns)


def advance_steady(rhs, x, tau, t=0.0):
    """The state of the steady motion through ``x``, ``tau`` seconds later (or earlier if < 0).

    In a steady motion every state is constant except the heading, which
    turns at the yaw rate u3, the rear contact, which moves on the circle
    (or line) that the rotating velocity (u1, u2) traces, and the wheel
    angles, which turn at u6 and u8. Used to start the display-only settle
    so that it arrives at ``x`` at the kick. Quadratures are returned unchanged.

    Parameters
    ----------
    rhs : slip.CompiledRHS
    x : array_like
        A steady state (e.g. ``SteadyState.x``).
    tau : float
        Time shift [s].
    t : float
        Time at which ``x`` holds (the plate must be at rest then).

    Returns
    -------
    ndarray
    """
    x = np.array(x, dtype=float)
    _, out = rhs.outputs(t, x)
    w = out[slip.OUT["u3"]]
    theta = w * tau
    # int_0^tau of cos(w s) and sin(w s) ds, without dividing by a zero yaw rate.
    c_int = tau * np.sinc(theta / np.pi)
    s_int = tau * np.sin(theta / 2) * np.sinc(theta / (2 * np.pi))
    u1, u2 = x[slip.X["u1"]], x[slip.X["u2"]]
    c, s = np.cos(theta), np.sin(theta)
    x[slip.X["q1"]] += u1 * c_int - u2 * s_int
    x[slip.X["q2"]] += u1 * s_int + u2 * c_int
    x[slip.X["u1"]], x[slip.X["u2"]] = c * u1 - s * u2, s * u1 + c * u2
    x[slip.X["q3"]] += theta
    x[slip.X["q6"]] += out[slip.OUT["u6"]] * tau
    x[slip.X["q8"]] += out[slip.OUT["u8"]] * tau
    return x


# ------------------------------------------------------------ the run's start

#: What an upright start's stability is judged about when the tyres' offsets allow no steady motion.
SYMMETRIC_ABOUT = "upright running without the tyres' zero-slip offsets"
SYMMETRIC_ROUTE = f"{SYMMETRIC_ABOUT} (no steady motion with them)"


def start_state(params, speed, *, start="steady", start_pitch="compressed", advice=None):
    """The steady motion the rider's stability is judged about, and the state the run starts from.

    With ``start="steady"`` both are the steady motion. With
    ``start="upright"`` the run starts from :func:`upright_state`; stability
    is judged about the steady motion of the same model if there is one,
    else about upright running with the tyres' offsets removed (an exact
    equilibrium).

    Parameters
    ----------
    params : mapping
        The model's parameters (:func:`whipple_kick.model.slip.model_parameters`).
    speed : float
        Forward speed [m/s] (the scenario's ``speed``).
    start, start_pitch : str
        The scenario's ``start`` and ``start_pitch`` (the pitch of an upright start).
    advice : str, optional
        What a user can change if there is no steady motion (the one-line error's end).

    Returns
    -------
    found : Found
    start : SteadyState
    """
    if start == "steady":
        found = find_steady_state(params, speed, advice=advice)
        return found, found.steady
    try:
        upright = upright_state(params, speed, pitch_without_compression=start_pitch == "uncompressed")
    except FloatingPointError as exc:
        raise SimulationError(str(exc)) from None
    try:
        found = find_steady_state(params, speed, advice=advice)
    except NoSteadyMotion:
        symmetric = steady_state(offset_scaled(params, 0.0), speed)
        found = Found(symmetric, SYMMETRIC_ROUTE, 1)
    return found, upright
    return found, start
