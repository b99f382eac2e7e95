"""The steady motion before the kick, found robustly, or the physical reason there is none.

:func:`whipple_kick.slip.steady_state` solves the steady equations by
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
2. steady turns: starts at leans of +-1 to +-30 deg, each with the yaw rate
   of a balanced turn (g tan(lean) / v) and its kinematic steer angle; of the
   motions found, the one with the smallest lean (the closest to upright
   running);
3. continuation in the tyres' offsets: symmetric tyres (exactly upright,
   always solvable), then the offsets scaled up to their measured size,
   each solve starting from the previous one;
4. continuation in speed from neighbouring speeds where a steady motion is
   found, with the same rider and tyres.

If none succeeds, :class:`NoSteadyMotion` says why in physical terms (how far
the offset continuation got, the lean there, the real closed-loop pole that
reaches zero, and whether the symmetric closed loop is stable at that speed),
in one line, never with the solver's own message.

Example
-------
>>> from whipple_kick import Scenario, assembly, slip, steady
>>> sc = Scenario()
>>> moore, design, _ = assembly.build_bicycle(sc)
>>> rear, front, _ = assembly.build_tyres(sc)
>>> gains, _ = assembly.controller_gains(sc, design)
>>> found = steady.find_steady_state(slip.model_parameters(moore, rear, front, gains=gains), 3.0)
>>> found.route
'direct'
"""
from dataclasses import dataclass
import math

import numpy as np

from . import slip
from .errors import InputError

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
    steady : whipple_kick.slip.SteadyState
        As returned by :func:`whipple_kick.slip.steady_state`.
    route : str
        ``"direct"``, ``"steady turn started at L deg of lean (of n found)"``,
        ``"offset continuation (n steps)"`` or ``"speed continuation from
        v m/s (n steps)"``.
    solves : int
        Calls of :func:`whipple_kick.slip.steady_state` spent.
    """

    steady: "slip.SteadyState"
    route: str
    solves: int


def offset_scaled(params, fraction):
    """``params`` with every tyre's zero-slip offsets multiplied by ``fraction``.

    The offsets are the Magic-Formula coefficients that shift the curves at
    zero slip and camber (:data:`whipple_kick.slip.FY_OFFSET_INDICES`,
    :data:`whipple_kick.slip.MZ_OFFSET_INDICES`), in both coefficient slots
    of both wheels; ``fraction`` 0 gives symmetric tyres.
    """
    out = dict(params)
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
        """:func:`slip.steady_state`, or None if it finds nothing (or the budget is spent)."""
        if self.solves >= MAX_SOLVES:
            return None
        self.solves += 1
        if guess is not None:
            guess = {name: (0.0 if abs(value) < _ROUND_OFF else value) for name, value in guess.items()}
        try:
            return slip.steady_state(params, speed, guess=guess)
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


def find_steady_state(params, speed, *, advice=None):
    """Steady motion at ``speed`` [m/s]: the direct solve, then steady turns, then continuation (see the module).

    Parameters
    ----------
    params : mapping
        Slip-model parameters (:func:`whipple_kick.slip.model_parameters`),
        with the rider's gains.
    speed : float
        Forward speed [m/s], > 0.
    advice : str, optional
        What the user can change, appended to the error (e.g. "choose another
        design speed or speed").

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
    if direct is not None:
        return Found(direct, "direct", counter.solves)
    turns = {}
    for lean in TURN_LEANS_DEG:
        found = counter.solve(params, speed, turn_guess(params, speed, math.radians(lean)))
        if found is not None:
            turns.setdefault(round(math.degrees(found.unknowns["q4"]), 6), (lean, found))
    if turns:
        lean, found = turns[min(turns, key=abs)]
        return Found(found, f"steady turn started at {lean:+g} deg of lean (of {len(turns)} found)", counter.solves)
    # Offsets: from symmetric tyres (exactly upright) up to the measured offsets.
    found, last, fraction, steps = _continue(
        counter, lambda s, guess: counter.solve(offset_scaled(params, s), speed, guess), 0.0, 1.0, 0.25)
    if found is not None:
        return Found(found, f"offset continuation ({steps} steps)", counter.solves)
    # Neighbouring speeds: a steady motion there, followed to this speed.
    for step in NEIGHBOUR_STEPS:
        start = speed + step
        if start < _MIN_START_SPEED or counter.solves >= MAX_SOLVES:
            continue
        found_v, _, _, steps_v = _continue(
            counter, lambda v, guess: counter.solve(params, v, guess), start, speed, abs(step) / 4)
        if found_v is not None:
            return Found(found_v, f"speed continuation from {start:g} m/s ({steps_v} steps)", counter.solves)
    raise NoSteadyMotion(diagnosis(params, speed, last, fraction, advice, counter.solves >= MAX_SOLVES))


def turn_guess(params, speed, lean):
    """Starting values of a balanced steady turn at ``lean`` [rad]: yaw rate and kinematic steer.

    Yaw rate g tan(lean) / v (the lean that balances the turn's lateral
    acceleration); steer angle u3 w / (v cos(lam)) from the rolling
    kinematics (wheelbase w, steer-axis tilt lam of the bicycle).
    """
    from .benchmark import from_moore
    bench = from_moore({name: params[name] for name in slip.S.CLASSIC_CONSTANTS})
    yaw_rate = params["g"] * math.tan(lean) / speed
    return {"q4": lean, "u3": yaw_rate, "q7": yaw_rate * bench["w"] / (speed * math.cos(bench["lam"]))}


def lateral_poles(params, x):
    """Closed-loop poles [1/s] of the slip model about the steady state ``x``, at constant speed.

    The heading-frame linearisation (:func:`whipple_kick.slip.linear_state_space`)
    with the forward-speed row and column removed: the speed is held by the
    rear-wheel torque, and its own slow mode is not the rider's balance.
    Sorted by decreasing real part.
    """
    A, B, K = slip.linear_state_space(params, x)
    keep = [i for i, name in enumerate(slip.LINEAR_STATES) if name != "v_fwd"]
    poles = np.linalg.eigvals((A - B @ K)[np.ix_(keep, keep)])
    return poles[np.argsort(-poles.real, kind="stable")]


def _poles_or_none(params, x, speed=None):
    """:func:`lateral_poles` about ``x`` (or about the direct steady solve at ``speed``), None if that fails."""
    try:
        if x is None:
            found = slip.steady_state(params, speed)
            params, x = found.params, found.x
        return lateral_poles(params, x)
    except (FloatingPointError, InputError):
        return None


def _nearest_real_pole(poles):
    if poles is None:
        return None
    real = poles[np.abs(poles.imag) < 1e-9].real
    return float(real[np.argmin(np.abs(real))]) if real.size else None


def diagnosis(params, speed, last, fraction, advice=None, exhausted=False):
    """One line saying why no steady motion was found (see :func:`find_steady_state`).

    ``last`` is the last steady motion of the continuation in the tyre
    offsets and ``fraction`` how far it got; ``exhausted`` that the search
    spent :data:`MAX_SOLVES`.
    """
    text = f"no steady motion at {speed:g} m/s: "
    if (last is None or fraction <= 0.0) and exhausted:
        text += f"the search stopped after {MAX_SOLVES} solves"
    elif last is None or fraction <= 0.0:
        text += "not even with symmetric tyres"
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
    if exhausted and last is not None and fraction > 0.0:
        text += f"; the search stopped after {MAX_SOLVES} solves"
    elif TURN_LEANS_DEG and not exhausted:
        text += (f"; nor from steady turns of {min(map(abs, TURN_LEANS_DEG)):g}-{max(TURN_LEANS_DEG):g} "
                 "deg of lean")
    if advice:
        text += f"; {advice}"
    return text
