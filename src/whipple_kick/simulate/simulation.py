"""One kick-plate run end to end: scenario in, time histories and summary out.

:func:`run` reads top-down as the run's data flow, each step handing a
finished object to the next:

1. the scenario is checked and its kick described (:mod:`whipple_kick.simulate.scenario`,
   :mod:`whipple_kick.library.inputs`),
2. the model is assembled: bicycle with rider, tyres, gains, parameters,
   steady motion (:mod:`whipple_kick.simulate.assembly`),
3. it is integrated across the kick (:mod:`whipple_kick.simulate.integration`),
4. the results are tabulated and summarised (:mod:`whipple_kick.simulate.results`).

Time is measured from the start of the kick: the run starts at ``-settle``
(steady running shown before the kick) and ends at ``duration`` (or at the
fall). docs/simulate.md lists every decision.
"""
from collections.abc import Mapping
import time
import warnings

from whipple_kick.errors import SimulationError, UnstableRiderWarning
from whipple_kick.library import inputs
from whipple_kick.simulate import assembly, integration, results

from .results import Result
from .scenario import Scenario

__all__ = ["Result", "Scenario", "SimulationError", "run"]


def run(scenario: Scenario, *, tyres: tuple | None = None, gains: Mapping | None = None,
        columns=None) -> Result:
    """Run one kick-plate simulation.

    Parameters
    ----------
    scenario : Scenario
        What to run (validated here).
    tyres : (rear, front), optional
        Tyre objects to use instead of the scenario's tyre and pressures,
        e.g. :func:`whipple_kick.library.tyres.linear_tyre` or a :class:`~whipple_kick.library.tyres.Tyre`
        loaded with other options. The summary names them. They replace the
        scenario's ``tyre``, pressures, ``coefficient_set`` and ``friction``,
        which must then stay at their defaults (one given is refused, not
        ignored).
    gains : mapping, optional
        Steer-torque gains by name (``kq4 kq7 ku4 ku7``, the yaw gains
        ``kq3 ku3`` and, for a leaning rider, the upper body's lean gains
        ``kq11 ku11``; N m/rad, N m s/rad; missing ones are 0) instead of the
        scenario's controller; the law is still ``T7 = -K x``. The
        scenario's controller fields (``controller``, ``design_speed``,
        ``gain_scale``, ``thesis_load_n``, ``lqr_model``, ``lqr_heading``)
        must stay at their defaults: the gains replace them. A yaw-angle gain
        (e.g. from :func:`whipple_kick.simulate.control.heading_lqr_gains`) needs a
        straight steady motion, so tyres without zero-slip offsets.
    columns : iterable of str or "all", optional
        The lean path of a study (:func:`whipple_kick.studies.sweep_engine.run_case`): no trajectory
        table is built, ``result.trajectory`` is a dict of these columns' arrays (and the summary's own,
        :func:`whipple_kick.simulate.results.trajectory_columns`); the summary is the same. Default: the
        whole table, a DataFrame.

    Returns
    -------
    Result
        Also when the integration failed numerically (never NaN in a
        result): e.g. it stalled beyond
        :data:`whipple_kick.simulate.lsoda.DEFAULT_BUDGET`. Then
        ``result.success`` is False, ``result.message`` says where and why,
        and the trajectory and summary hold the run up to the failure
        (``result.status``: 0 completed, 1 fell, -1 failed).

    Raises
    ------
    InputError
        A field is out of range, unknown or conflicting;
        :class:`whipple_kick.simulate.steady.NoSteadyMotion` (an InputError) when
        there is no steady motion to start from, with the physical reason.
    SimulationError
        Only where nothing could be computed to return: the compiled model
        failed at the start state, or no finite summary could be made.

    Warns
    -----
    UnstableRiderWarning
        Before the integration, when the rider in use is linearly unstable at
        the run's speed (``summary["linear_stability"]`` holds the same line).

    Example
    -------
    >>> import whipple_kick as wk
    >>> result = wk.run(wk.Scenario(duration=1.0))
    >>> result.summary["outcome"], result.summary["linear_stability"]["stable"]
    ('completed', True)
    """
    started = time.perf_counter()
    kick = inputs.kick_of(scenario.validate())
    model = assembly.assemble(scenario, kick, tyres=tyres, gains=gains)
    if not model.stability["stable"]:
        # Said before the long part, the integration; a valid run all the same (the bicycle may well fall).
        warnings.warn(model.stability["message"], UnstableRiderWarning, stacklevel=2)
    solution = integration.integrate_run(model, scenario, kick)
    if columns is None:
        frame = results.trajectory_frame(solution, scenario.tyre_transient)
    else:
        frame = results.trajectory_columns(solution, scenario.tyre_transient, columns)
    summary = results.summarise(scenario, kick, model, solution, frame, custom_tyres=tyres is not None)
    summary["numerics"]["wall_s"] = time.perf_counter() - started
    return Result(scenario=scenario, trajectory=frame, summary=summary)
