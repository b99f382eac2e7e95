"""Integration of one run: the display-only settle, the kick, the plate stop and a table's pieces.

The third step of a run (:func:`whipple_kick.simulate.simulation.run`): from the
:class:`~whipple_kick.simulate.assembly.Assembly` (parameters and start state) and
the :class:`~whipple_kick.library.inputs.Kick`, :func:`integrate_run` integrates the
compiled slip model on the run's output grid (:func:`sample_times`) with
the LSODA engine (:func:`whipple_kick.simulate.lsoda.integrate`), piece by piece:
the settle before the kick on its own (display only, with the heading fixed
at the kick), the kick and the rest of the run across the kick's
breakpoints, the constant-acceleration profile's instant plate stop as a
velocity jump (:func:`whipple_kick.model.slip.velocity_jump`), a kick table as one
parameter set per table interval. A fall (``|roll|`` or ``|steer|`` beyond its
limit, :func:`end_limits`) ends it as an event. The result is one
:class:`Solution`, handed to :mod:`whipple_kick.simulate.results`.
"""
from dataclasses import dataclass, field, replace
import functools
import math
import time

import numpy as np

from whipple_kick.errors import SimulationError
from whipple_kick.library import inputs
from whipple_kick.model import energy, slip
from whipple_kick.simulate import lsoda

from .steady import advance_steady


@dataclass
class Solution:
    """The integrated run.

    Attributes
    ----------
    states : whipple_kick.simulate.lsoda.StateHistory
        Samples from -settle to the end (or the fall, or the failure); time
        from the kick start; quadratures 0 at the kick start.
    rhs : slip.CompiledRHS or list of them
        The compiled model(s) that produced the samples.
    owner : ndarray of int or None
        With a list of ``rhs``: which one produced each sample.
    breakpoints : tuple of float
        Where the integrator was restarted [s].
    jumps : list of dict
        One per velocity jump (:func:`whipple_kick.model.slip.velocity_jump`'s info).
    wall_s : float
        Wall time of the integration [s].
    """

    states: lsoda.StateHistory
    rhs: object
    owner: np.ndarray | None
    breakpoints: tuple
    jumps: list = field(default_factory=list)
    wall_s: float = 0.0

    @property
    def model(self):
        """The :class:`~whipple_kick.model.slip.layout.Layout` of the compiled model that produced the samples."""
        return (self.rhs[0] if isinstance(self.rhs, (list, tuple)) else self.rhs).layout

    def outputs(self, via_rhs=False, names=None) -> np.ndarray:
        """The compiled model's named outputs (:data:`whipple_kick.model.slip.OUTPUT_NAMES`) at every sample.

        ``via_rhs``: from the whole right-hand side at each sample (the reference); ``names``: the outputs
        needed, the optional groups holding none of them left out, NaN
        (:meth:`whipple_kick.model.slip.CompiledRHS.outputs_at`).
        """
        traj = self.states
        if self.owner is None:
            return self.rhs.outputs_at(traj.t, traj.x, via_rhs, names)
        # Each piece's compiled model evaluates the samples it produced.
        owner = np.asarray(self.owner)
        outs = np.empty((traj.t.size, len(self.model.OUTPUT_NAMES)))
        for k in np.unique(owner):
            rows = owner == k
            outs[rows] = self.rhs[k].outputs_at(traj.t[rows], traj.x[rows], via_rhs, names)
        return outs


def integrate_run(assembly, scenario, kick) -> Solution:
    """Integrate one run from its assembled model (see the module notes).

    Parameters
    ----------
    assembly : whipple_kick.simulate.assembly.Assembly
    scenario : whipple_kick.simulate.scenario.Scenario
    kick : whipple_kick.library.inputs.Kick

    Returns
    -------
    Solution

    Raises
    ------
    SimulationError
        The compiled model failed at a state (e.g. a singular matrix).
    """
    started = time.perf_counter()
    try:
        traj, rhs, owner, breakpoints, jumps = _integrate(assembly.start, scenario, kick)
    except FloatingPointError as exc:
        raise SimulationError(f"integration failed: {exc}") from None
    return Solution(traj, rhs, owner, breakpoints, jumps, time.perf_counter() - started)


def sample_times(scenario):
    """The run's output times [s]: the multiples of 1/``output_rate`` on the kick's clock, plus -settle and duration.

    On the kick's clock (t = 0 at the nominal kick start), so the samples
    after the kick do not depend on ``settle``: k / rate for the integers k
    with -settle <= k / rate <= duration, and the run's ends if they fall
    between multiples. Read-only: one array per process for each
    (rate, settle, duration), which every run of a sweep shares.

    Example
    -------
    >>> from whipple_kick.simulate.scenario import Scenario
    >>> sample_times(Scenario(settle=0.002, duration=0.003, output_rate=1000.0)).tolist()
    [-0.002, -0.001, 0.0, 0.001, 0.002, 0.003]
    """
    rate, settle, duration = scenario.output_rate, scenario.settle, scenario.duration
    return _sample_times(rate, settle, duration, lsoda._exact_key(rate, settle, duration))


@functools.lru_cache(maxsize=16)
def _sample_times(rate, settle, duration, _exactly):
    """:func:`sample_times` of these fields (``_exactly``: :func:`whipple_kick.simulate.lsoda._exact_key`)."""
    t_start, t_end = 0.0 - settle, duration   # no -0.0
    tiny = 1e-9   # of a sample spacing: a product like 0.5 * 1000 is an integer to round-off
    k = np.arange(math.ceil(t_start * rate - tiny), math.floor(t_end * rate + tiny) + 1)
    times = k / rate
    times = times[(times > t_start + tiny / rate) & (times < t_end - tiny / rate)]
    times = np.concatenate([[t_start], times, [t_end]])
    times.flags.writeable = False
    return times


def end_limits(scenario):
    """The limits that end a run as lost (``lsoda.integrate`` keywords): ``|roll|`` and ``|steer|`` [rad]."""
    return {"fall_angle": math.radians(scenario.fall_angle_deg),
            "steer_limit": None if scenario.steer_limit_deg is None else math.radians(scenario.steer_limit_deg)}


def _integrate(steady, scenario, kick):
    """Integrate one run: the display-only settle, then the kick from the exact steady state.

    ``kick_heading="fixed"`` (piecewise): the post-kick run starts at the
    kick start from ``steady.x`` (heading N.x, rear contact at the origin),
    so nothing after the kick depends on ``settle``; the settle segment
    starts from the steady motion moved back by ``settle``
    (:func:`whipple_kick.simulate.steady.advance_steady`) and is integrated on its own.
    ``piecewise=False`` integrates from -settle (from that moved-back state,
    or from ``steady.x`` with ``kick_heading="settled"``) in one LSODA run.
    The constant-acceleration profile's plate stop is a velocity jump
    (:func:`whipple_kick.model.slip.velocity_jump`) in piecewise runs. The
    works and dissipations are shifted to be 0 at the kick start (the
    carcass energies stay what the carcasses hold).

    Returns
    -------
    traj : lsoda.StateHistory
    rhs : slip.CompiledRHS or list of them
    owner : ndarray of int or None
        With a list of ``rhs``: which one produced each sample.
    breakpoints : tuple of float
    jumps : list of dict
        One per velocity jump (:func:`whipple_kick.model.slip.velocity_jump`'s info).
    """
    kick_T, table, kick_start = kick.duration, kick.table, kick.start
    limits = end_limits(scenario)
    # piecewise=False is the comparison case: one LSODA run across the kick,
    # not even restarted at the integrator's chunk boundaries.
    chunk = lsoda.DEFAULT_CHUNK if scenario.piecewise else math.inf
    samples = sample_times(scenario)
    t_start, t_end = float(samples[0]), scenario.duration
    rhs = slip.CompiledRHS(steady.params)   # the plate at rest at the kick start (a table's first row)
    # An upright start is no steady motion: nothing to move back along, it is where the run starts.
    fixed = scenario.kick_heading == "fixed" and scenario.start == "steady"
    x_start = advance_steady(rhs, steady.x, t_start - kick_start, t=kick_start) if fixed else steady.x
    jumps, jump_map = [], {}
    stop = kick_start + kick_T
    kept = table is None and scenario.piecewise and scenario.kick_profile == "constant" \
        and scenario.plate_stop == "keep_speeds"
    if table is None:
        breakpoints = (kick_start, stop) if scenario.piecewise else ()
        if scenario.piecewise and scenario.kick_profile == "constant" and not kept:
            def plate_stop(t, x):
                x, info = slip.velocity_jump(rhs, t, x, impulse=scenario.plate_stop == "impulse")
                jumps.append(info)
                return x
            jump_map = {stop: plate_stop}
    else:
        breakpoints = tuple(float(t) for t in table.times if -scenario.settle < t < scenario.duration)

    def run_from(x, a, rows, before=None):
        # ``before``: the settle, joined to the result (by lsoda.integrate itself where one call makes the run).
        if kept and a < stop:
            traj, rhs_out, owner = _integrate_kept_speeds(rhs, steady.params, x, (a, kick_start), rows, stop,
                                                          scenario, chunk, jumps)
        elif table is None:
            return lsoda.integrate(rhs, x, t_end, t_start=a, breakpoints=breakpoints, rtol=scenario.rtol,
                                   **limits, chunk=chunk, samples=rows, jumps=jump_map, before=before), rhs, None
        else:
            # The drive torque T6c found for the steady motion stays in every piece's parameters.
            traj, rhs_out, owner = _integrate_table(steady.params, x, table, scenario, chunk, t_start=a)
        return (traj if before is None else lsoda.join([before, traj])), rhs_out, owner

    if not (fixed and scenario.piecewise) or kick_start <= t_start:
        traj, rhs_out, owner = run_from(steady.x if kick_start <= t_start else x_start, t_start, samples)
        return _from_kick_start(traj, kick_start), rhs_out, owner, breakpoints, jumps
    # The samples before the kick and from it: the increasing samples split by binary search (views).
    kick_row = int(np.searchsorted(samples, kick_start, "left"))
    settle = lsoda.integrate(rhs, x_start, kick_start, t_start=t_start, rtol=scenario.rtol, **limits,
                                 chunk=chunk, samples=samples[:kick_row])
    quad = [slip.X[n] for n in energy.CUMULATIVE]
    settle.x[:, quad] -= settle.end_state[quad]   # cumulative from the kick start (in place: the states are this run's own)
    if settle.fell or settle.failed:
        # The steady motion did not last through the settle (it fell or the integration failed before
        # the kick): that is the run's outcome, and there is no kick to integrate.
        return settle, rhs, None, breakpoints, jumps
    traj, rhs_out, owner = run_from(steady.x, kick_start, samples[kick_row:], before=settle)
    if owner is not None:
        # The settle's samples belong to the model of the plate at rest before the table.
        rhs_out = [rhs] + list(rhs_out)
        owner = np.concatenate([np.zeros(settle.t.size, dtype=int), np.asarray(owner) + 1])
    return traj, rhs_out, owner, breakpoints, jumps


def _integrate_kept_speeds(rhs, params, x, span, rows, stop, scenario, chunk, jumps):
    """Integrate across the plate stop keeping every speed (``plate_stop="keep_speeds"``).

    Up to the stop with ``rhs``; from it with the rear constraint imposing
    the slide that keeps the speeds continuous
    (:func:`whipple_kick.model.slip.kept_speeds_slide`), as the authors' code's
    acceleration-level constraint does. ``span`` is (start time, kick start)
    [s]; the kick start is a breakpoint. Appends the stop's info to ``jumps``.

    Returns
    -------
    traj : lsoda.StateHistory
    rhs : list of slip.CompiledRHS
        Before and after the stop.
    owner : ndarray of int
        Which of them produced each sample.
    """
    limits = end_limits(scenario)
    rows = np.asarray(rows, dtype=float)
    t_start, kick_start = span
    first = lsoda.integrate(rhs, x, stop, t_start=t_start, breakpoints=(kick_start,), rtol=scenario.rtol,
                                **limits, chunk=chunk, samples=rows[rows < stop])
    if first.fell or first.failed:
        return first, [rhs], np.zeros(first.t.size, dtype=int)
    x_stop = first.end_state
    slide = slip.kept_speeds_slide(rhs, stop, x_stop)
    after = slip.CompiledRHS(params.replace(vsx_r=slide))
    ke = [r.outputs(t, x_stop)[1][slip.OUT["kinetic_energy"]]
          for r, t in ((rhs, np.nextafter(stop, -np.inf)), (after, stop))]
    jumps.append({"time_s": float(stop), "kinetic_energy_change_j": float(ke[1] - ke[0]), "impulse_work_j": None,
                  "constraint_impulse_n_s": None, "rear_slide_m_s": slide})
    second = lsoda.integrate(after, x_stop, scenario.duration, t_start=stop, rtol=scenario.rtol,
                                 **limits, chunk=chunk, samples=rows[rows >= stop])
    return lsoda.join([first, second]), [rhs, after], np.concatenate([np.zeros(first.t.size, dtype=int), np.ones(second.t.size, dtype=int)])


def _from_kick_start(traj, kick_start):
    """``traj`` with the quadratures shifted to be 0 at the kick start (interpolated between samples)."""
    if traj.t.size == 0:
        return traj
    x = traj.x.copy()
    for name in energy.CUMULATIVE:
        j = slip.X[name]
        x[:, j] -= np.interp(kick_start, traj.t, traj.x[:, j])
    return replace(traj, x=x)


def _integrate_table(params, x0, table, scenario, chunk, t_start=None):
    """Integrate a tabulated kick piece by piece on the run's global output grid.

    Each piece (rest before, one spline segment per table interval, rest
    after) has its own parameter set and compiled right-hand side; each is
    one :func:`whipple_kick.simulate.lsoda.integrate` call on the samples not yet
    produced, starting from the previous piece's exact end state. The run
    starts at ``t_start`` (default -settle) from ``x0``.

    Returns
    -------
    trajectory : lsoda.StateHistory
    rhs : list of slip.CompiledRHS
        One per piece.
    piece : ndarray of int
        Index into ``rhs`` of the piece that produced each sample.
    """
    t_end = scenario.duration
    pending = sample_times(scenario)
    t_start = pending[0] if t_start is None else t_start
    pending = pending[pending >= t_start]
    limits = end_limits(scenario)
    trajs, owner, rhss = [], [], []
    x = np.asarray(x0, dtype=float)
    for k, (a, b, t0, coefficients) in enumerate(table.pieces(t_start, t_end)):
        rhs = slip.CompiledRHS(inputs.segment_parameters(params, t0, coefficients))
        rhss.append(rhs)
        traj = lsoda.integrate(rhs, x, b, t_start=a, rtol=scenario.rtol, **limits,
                                   chunk=chunk, samples=pending)
        trajs.append(traj)
        owner.append(np.full(traj.t.size, k))
        if traj.t.size:
            pending = pending[pending > traj.t[-1]]
        x = traj.end_state
        if traj.fell or traj.failed:
            break
    return lsoda.join(trajs), rhss, np.concatenate(owner).astype(int)
