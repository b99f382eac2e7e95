"""Results of one run: the trajectory table with units, the response metrics and the summary.

The fourth step of a run (:func:`whipple_kick.simulate.simulation.run`): the
integrated :class:`~whipple_kick.simulate.integration.Solution` becomes a
:class:`Result`, the time histories as a pandas DataFrame (:func:`trajectory_frame`,
columns and units in :data:`UNITS`) and a JSON-ready summary
(:func:`summarise`): outcome, set-up, steady state, peaks, energy balance,
the recovery and the Section 8.3 metrics of :mod:`whipple_kick.simulate.analysis`,
numerics. Nothing in a result is NaN (:func:`clean`).
"""
from collections.abc import Mapping
from dataclasses import dataclass, field
import functools
import json
import math
import pathlib

import numpy as np
import pandas as pd

from whipple_kick import fileio
from whipple_kick.errors import InputError, SimulationError
from whipple_kick.model import carcass, energy, parts, slip, symbols, transient
from whipple_kick.model.slip.call import optional_groups
from whipple_kick.simulate import criteria, lsoda, provenance

from . import analysis
from . import assembly as assembly_module
from .integration import sample_times
from .scenario import THESIS_DESIGN_SPEED, Scenario

#: Significant digits of trajectory.csv's floats: a relative round-off of at most 5e-13, far below the
#: integration's own error (rtol 1e-10 by default) and the float32 regression references (~6e-8), and
#: about 2.5 times faster to write than every float's 17-digit repr.
TRAJECTORY_CSV_DIGITS = 13

# Moore's coordinates and speeds, named for the trajectory table: state -> (column, unit). q5 is
# Moore's pitch of the rear frame (its rotation about the rear wheel axle, 0 when the frame's reference
# line is level; about 14.7 deg for the default bicycle), hence "frame_pitch"; u1, u2 are the rear
# contact's velocity along the fixed ground axes N.x, N.y, not along the heading (see HEADING_COLUMNS).
COORDINATE_COLUMNS = {
    "q1": ("x_rear", "m"), "q2": ("y_rear", "m"), "q3": ("yaw", "rad"), "q4": ("roll", "rad"),
    "q5": ("frame_pitch", "rad"), "q6": ("rear_wheel_angle", "rad"), "q7": ("steer", "rad"),
    "q8": ("front_wheel_angle", "rad"), "q9": ("compression_rear", "m"),
    "q10": ("compression_front", "m"),
}
SPEED_COLUMNS = {
    "u1": ("velocity_x_fixed", "m/s"), "u2": ("velocity_y_fixed", "m/s"), "u3": ("yaw_rate", "rad/s"),
    "u4": ("roll_rate", "rad/s"), "u5": ("frame_pitch_rate", "rad/s"), "u6": ("rear_wheel_rate", "rad/s"), "u7": ("steer_rate", "rad/s"),
    "u8": ("front_wheel_rate", "rad/s"), "u9": ("compression_rate_rear", "m/s"),
    "u10": ("compression_rate_front", "m/s"),
}
#: The rear contact's velocity along the heading (yaw q3) [m/s]: forward and lateral (the drift).
HEADING_COLUMNS = {"forward_speed": "m/s", "lateral_speed": "m/s"}
#: The force and moment each tyre applies to the bicycle (in every transient form): output -> column.
APPLIED_COLUMNS = {"fy_r": "fy_rear", "fy_f": "fy_front", "mz_r": "mz_rear", "mz_f": "mz_front"}
#: The other named outputs of the compiled model: output -> column (units: :data:`whipple_kick.model.slip.OUTPUTS`).
OUTPUT_COLUMNS = {
    "slip_r": "slip_rear", "slip_f": "slip_front", "camber_r": "camber_rear", "camber_f": "camber_front",
    "vx_r": "rolling_speed_rear", "vx_f": "rolling_speed_front", "fz_r": "fz_rear", "fz_f": "fz_front",
    "fy_ss_r": "fy_steady_rear", "fy_ss_f": "fy_steady_front", "mz_ss_r": "mz_steady_rear",
    "mz_ss_f": "mz_steady_front", "T7": "steer_torque", "yp": "plate_y", "vp": "plate_velocity",
    "ap": "plate_acceleration", "kinetic_energy": "kinetic_energy", "potential_energy": "potential_energy",
    "spring_energy": "spring_energy", "sliding_power": "sliding_power", "holonomic": "holonomic_residual",
    "sigma_r": "relaxation_length_rear", "sigma_f": "relaxation_length_front",
    "fy_limit_r": "fy_limit_rear", "fy_limit_f": "fy_limit_front",
    "T_reflex": "reflex_steer_torque", "reflex_input": "reflex_undelayed_torque",
}
#: Contact-patch states (transient forms contact_patch and slip_lag; the carcass has the camber ones
#: and its patch slip as the output ``patch_slip_*``): state -> column.
PATCH_STATE_COLUMNS = {"slip_patch_r": "slip_patch_rear", "slip_patch_f": "slip_patch_front",
                       "camber_patch_r": "camber_patch_rear", "camber_patch_f": "camber_patch_front"}
#: The slip the steady curves are evaluated at (contact-patch and carcass forms): output -> column (as the forms
#: declare their columns, :attr:`whipple_kick.model.transient.Form.columns`).
PATCH_OUTPUT_COLUMNS = {name: col for col, source, name, _ in transient.FORMS["contact_patch"].columns
                        if source == "output"}
#: The carcass tyre's deflection states (transient carcass only): state -> column.
CARCASS_STATE_COLUMNS = {name: col for col, source, name, _ in transient.FORMS["carcass"].columns
                         if name.startswith("carcass_y")}
#: Energy balance residual column [J] (:func:`whipple_kick.model.energy.balance_residual`).
BALANCE_COLUMN = "energy_balance_residual"
#: Unit of each trajectory column of the bicycle (from :data:`whipple_kick.model.slip.OUTPUTS` and the energy
#: columns); :data:`UNITS` adds the declared parts' and tyre forms' columns.
_BICYCLE_UNITS = {"time": "s", **dict(COORDINATE_COLUMNS.values()), **dict(SPEED_COLUMNS.values()), **HEADING_COLUMNS,
                  **dict.fromkeys(PATCH_STATE_COLUMNS.values(), "rad"),
                  **{c: slip.OUTPUTS[o][0] for o, c in {**APPLIED_COLUMNS, **OUTPUT_COLUMNS}.items()},
                  **dict(energy.COLUMNS.values()), BALANCE_COLUMN: "J"}


def part_columns():
    """The declared parts' states (:mod:`whipple_kick.model.parts`): state -> (column, unit), in a run that has
    them; read when called, so a part declared after this module was imported counts too."""
    return {state: column for part in parts.REGISTRY.values() for state, column in part.columns.items()}


def _declared_units():
    """Units of the declared parts' state columns and outputs and of the declared tyre forms' columns, now."""
    return {**{col: unit for form in transient.FORMS.values() for col, _, _, unit in form.columns},
            **dict(part_columns().values()),
            **{o: unit for part in parts.REGISTRY.values() for o, (unit, _) in part.outputs.items()}}


class _Units(Mapping):
    """Unit of every trajectory column by name: the bicycle's, then the declared parts' and tyre forms' columns
    read when asked (a part or form declared after this module was imported counts too)."""

    def __getitem__(self, column):
        if column in _BICYCLE_UNITS:
            return _BICYCLE_UNITS[column]
        return _declared_units()[column]

    def __iter__(self):
        return iter({**_BICYCLE_UNITS, **_declared_units()})

    def __len__(self):
        return len({**_BICYCLE_UNITS, **_declared_units()})

    def __repr__(self):
        return repr(dict(self))


#: Unit of every trajectory column (a read-only mapping that follows the declarations).
UNITS = _Units()


def _column_units(columns):
    """``{column: unit_of(column)}`` for ``columns``, the declared units read once (not once per column)."""
    declared = None
    units = {}
    for column in columns:
        if column in _BICYCLE_UNITS:
            units[column] = _BICYCLE_UNITS[column]
            continue
        declared = _declared_units() if declared is None else declared
        if column not in declared:
            unit_of(column)   # its KeyError
        units[column] = declared[column]
    return units


def unit_of(column):
    """The unit of trajectory column ``column`` (:data:`UNITS`); KeyError naming it if there is none."""
    try:
        return UNITS[column]
    except KeyError:
        raise KeyError(f"no trajectory column {column!r}") from None


#: Columns whose largest absolute values after the kick the summary lists (``max_abs_<column>_absolute_<unit>``).
PEAK_COLUMNS = ("yaw_rate", "roll_rate", "steer_rate", "roll", "steer", "slip_rear", "fy_rear", "fy_front",
                "steer_torque")


@dataclass
class Result:
    """Outcome of :func:`whipple_kick.simulate.simulation.run`.

    Attributes
    ----------
    scenario : Scenario
    trajectory : pandas.DataFrame
        Time histories, columns named as in :data:`UNITS` (time from the kick start); a dict of
        column arrays from ``run(columns=...)`` (:func:`trajectory_columns`, a study's lean path).
    summary : dict
        JSON-ready summary (no NaN): outcome, model set-up, steady state,
        peaks, recovery metrics, numerics.
    """

    scenario: "object"
    trajectory: "object"
    summary: dict = field(default_factory=dict)

    #: :attr:`status` by ``summary["outcome"]``, as :func:`scipy.integrate.solve_ivp` numbers its ends: 0 the
    #: run reached its end, 1 a termination event ended it (the fall), -1 the integration failed.
    STATUS = {"completed": 0, "fell": 1, "failed": -1}  # noqa: RUF012 -- a constant table, never changed

    @property
    def status(self) -> int:
        """How the run ended: 0 it reached its end, 1 the bicycle fell (an event), -1 the integration failed.

        Example
        -------
        >>> import whipple_kick as wk
        >>> result = wk.run(wk.Scenario(duration=0.5))
        >>> result.status, result.success, result.message
        (0, True, 'completed')
        """
        return self.STATUS[self.summary["outcome"]]

    @property
    def success(self) -> bool:
        """False when the integration failed numerically (then the result holds the run up to the failure).

        A fall is a success in this sense, as a terminal event is for
        :func:`scipy.integrate.solve_ivp`: the model did what it should.
        """
        return self.status >= 0

    @property
    def message(self) -> str:
        """One line on how the run ended ("completed", the fall and its time, or the numerical failure)."""
        return self.summary["message"]

    def save(self, folder) -> list:
        """Write the run into ``folder`` as ``simulate`` does: trajectory.csv, summary.json, scenario.toml.

        Each file is written atomically; the folder is created if needed.
        trajectory.csv holds every column with its unit in the header
        (:func:`with_units`), to :data:`TRAJECTORY_CSV_DIGITS` significant
        digits; scenario.toml reruns the run (``simulate --scenario``,
        :meth:`whipple_kick.simulate.scenario.Scenario.from_file`).

        Returns
        -------
        list of str
            The names of the files written.

        Example
        -------
        >>> import whipple_kick as wk
        >>> result = wk.run(wk.Scenario(duration=1.0))
        >>> result.save("kick_run")
        ['trajectory.csv', 'summary.json', 'scenario.toml']
        """
        out = pathlib.Path(folder)
        out.mkdir(parents=True, exist_ok=True)
        fileio.write_csv(with_units(self.trajectory), out / TRAJECTORY_FILE, significant_digits=TRAJECTORY_CSV_DIGITS)
        fileio.write_atomic(out / SUMMARY_FILE, json.dumps(self.summary, indent=2, allow_nan=False) + "\n")
        self.scenario.to_file(out / SCENARIO_FILE, note=_scenario_note(self.summary))
        return [TRAJECTORY_FILE, SUMMARY_FILE, SCENARIO_FILE]

    @classmethod
    def load(cls, folder) -> "Result":
        """The :class:`Result` of a run folder written by :meth:`save` (or ``simulate``).

        The summary is the one written (exactly), the trajectory equals the
        run's to trajectory.csv's precision (relative 5e-13), the scenario is
        the summary's (file paths in it as the run was given them; the
        folder's scenario.toml has them absolute, to rerun it from anywhere);
        figures, metrics and :meth:`save` work on it as on the result
        :func:`whipple_kick.run` returned. The input files need not exist.

        Raises
        ------
        InputError
            ``folder`` is not a run folder (no summary.json or trajectory.csv) or a file in it is unreadable.

        Example
        -------
        >>> import whipple_kick as wk
        >>> result = wk.Result.load("kick_run")        # doctest: +SKIP
        >>> result.summary["recovered"], result.trajectory["yaw_rate"].iloc[-1]   # doctest: +SKIP
        (True, 0.0945...)
        """
        path = pathlib.Path(folder)
        if not path.is_dir():
            raise InputError(f"run folder {str(path)!r} {'is not a folder' if path.exists() else 'does not exist'}")
        for name in (SUMMARY_FILE, TRAJECTORY_FILE):
            if not (path / name).is_file():
                raise InputError(f"{str(path)!r} is not a run folder: it has no {name} (simulate writes "
                                 f"{TRAJECTORY_FILE} and {SUMMARY_FILE})")
        try:
            summary = json.loads((path / SUMMARY_FILE).read_text(encoding="utf-8"))
            scenario = Scenario(**summary["scenario"])
        except (ValueError, KeyError, TypeError) as exc:
            raise InputError(f"{str(path / SUMMARY_FILE)!r} is not a run summary: {exc}") from None
        except OSError as exc:   # no permission: the input cannot be read (not an output failure)
            raise InputError(f"{str(path / SUMMARY_FILE)!r} cannot be read: {exc.strerror or exc}") from None
        trajectory = read_trajectory(path / TRAJECTORY_FILE)
        check_trajectory(trajectory, summary, scenario, path / TRAJECTORY_FILE)
        return cls(scenario=scenario, trajectory=trajectory, summary=summary)


#: The files of a run folder (:meth:`Result.save`).
TRAJECTORY_FILE = "trajectory.csv"
SUMMARY_FILE = "summary.json"
SCENARIO_FILE = "scenario.toml"


def _scenario_note(summary):
    """What scenario.toml cannot rerun of a run made with Python objects (custom tyres or gains), or None."""
    custom = [what for what, used in (
        ("tyre objects", str(summary.get("tyres", {}).get("name", "")).startswith("custom")),
        ("steer-torque gains", summary.get("controller", {}).get("type") == "custom gains")) if used]
    if not custom:
        return None
    return (f"this run used custom {' and '.join(custom)} given in Python (wk.run(..., tyres=, gains=)); "
            "this file alone does not reproduce them")


def trajectory_frame(solution, tyre_transient="carcass"):
    """DataFrame of states and named outputs at every sample of a :class:`~whipple_kick.simulate.integration.Solution`.

    The patch slip and camber are columns in the contact-patch and carcass
    forms, the carcass deflections in the carcass form; the energy columns
    and the balance residual (:mod:`whipple_kick.model.energy`) in every form.

    Raises
    ------
    SimulationError
        A value is not finite (never NaN in a result).
    """
    traj = solution.states
    outs = solution.outputs()
    layout = frame_layout(tyre_transient, solution.model)
    # One float64 block, column by column (Fortran order: each column contiguous), instead of a dict of
    # columns that pandas copies into a block: a sweep builds ~1e4 of these tables.
    values = np.empty((traj.t.size, len(layout)), order="F")
    for k, entry in enumerate(layout):
        if entry[1] != "derived":
            values[:, k] = _source(entry, traj, outs)
    values[:, 0] = traj.t
    column = {name: k for k, (name, _, _) in enumerate(layout)}
    speeds = heading_speeds(*(values[:, column[c]] for c in ("yaw", "velocity_x_fixed", "velocity_y_fixed")))
    for name in HEADING_COLUMNS:
        values[:, column[name]] = speeds[name]
    # No negative zeros (a switched-off torque, -(0 x), is -0.0): trajectory.csv's rounded "-0" would read
    # back as 0 and a loaded result would not save the same bytes.
    values += 0.0
    frame = pd.DataFrame(values, columns=[name for name, _, _ in layout], copy=False)
    residual = energy.balance_residual(frame)
    frame[BALANCE_COLUMN] = residual
    if not (np.all(np.isfinite(values)) and np.all(np.isfinite(residual))):
        raise SimulationError("non-finite values in the trajectory")
    return frame


def trajectory_columns(solution, tyre_transient="carcass", names=None):
    """Columns of :func:`trajectory_frame` as plain arrays, without the table: the lean path of a study.

    The same values bit for bit (the same sources, the same arithmetic), the
    same refusal of a non-finite value in any of the table's columns it
    evaluates; only the DataFrame is not built, and of the columns only
    ``names`` and those :func:`summarise` reads (:func:`summary_columns`) are
    kept. The optional output groups
    (:data:`whipple_kick.model.slip.layout.OPTIONAL_OUTPUTS`: the plate's
    motion, the steady curves, the friction limits, the aligning moments)
    are evaluated, and checked, only where a kept column is in them. A sweep that
    keeps no trajectory needs nothing else (the table and its pandas
    look-ups were ~6 ms of a ~140 ms case when measured).

    Parameters
    ----------
    solution : whipple_kick.simulate.integration.Solution
    tyre_transient : str
    names : iterable of str or "all", optional
        Columns wanted beside the summary's ("all": every column of the table, in its order).

    Returns
    -------
    dict
        ``{column: 1-D float64 array}``: the table's columns in the table's order.

    Raises
    ------
    SimulationError
        A value in one of the table's columns is not finite (as :func:`trajectory_frame`).
    """
    traj = solution.states
    layout = frame_layout(tyre_transient, solution.model)
    every = column_names(tyre_transient, solution.model)
    asked = set(every) if names == "all" else set(names or ())
    unknown = asked - set(every)
    if unknown:
        raise InputError(f"trajectory column(s) {sorted(unknown)} do not exist; available: {', '.join(every)}")
    wanted = asked | (set(summary_columns(tyre_transient)) & set(every))
    # Only the optional output groups a wanted column is in are evaluated (the others are NaN, and not read):
    # the summary reads none of them (the aligning moments' group saves the carcass' second solve per wheel).
    output_names = solution.model.OUTPUT_NAMES
    needed = {output_names[index] for name, source, index in layout
              if source == "output" and (name in wanted or name in _HEADING_SOURCES)}
    outs = solution.outputs(names=needed)
    evaluated = optional_groups(needed)   # the groups outputs_at evaluates for these names
    left_out = {name for k, group in enumerate(slip.layout.OPTIONAL_OUTPUTS) if not evaluated >> k & 1
                for name in group}
    # The finite check covers the table's columns, as trajectory_frame's does, not the outputs it leaves out
    # (the whole arrays first: no copy of the columns when all is finite, as it nearly always is); of the
    # optional groups, those evaluated.
    states = sorted({index for _, source, index in layout if source == "state"})
    outputs = sorted({index for _, source, index in layout if source == "output" and output_names[index] not in left_out})
    if not (_all_finite(traj.x, states) and _all_finite(outs, outputs) and np.all(np.isfinite(traj.t))):
        raise SimulationError("non-finite values in the trajectory")
    source = {name: entry for name, *entry in layout}
    columns = {"time": traj.t + 0.0}
    for kind, values in (("state", traj.x), ("output", outs)):
        columns.update(_copied(values, [(name, index) for name, k, index in layout if k == kind and name in wanted]))
    if wanted & set(HEADING_COLUMNS):
        yaw, vx, vy = (_source((c, *source[c]), traj, outs) for c in _HEADING_SOURCES)
        columns.update({name: value + 0.0 for name, value in heading_speeds(yaw, vx, vy).items()})
    residual = energy.balance_residual({name: _Column(columns[name]) for name in _BALANCE_INPUTS})
    if not np.all(np.isfinite(residual)):
        raise SimulationError("non-finite values in the trajectory")
    columns[BALANCE_COLUMN] = residual
    return {name: columns[name] for name in every if name in wanted}


#: The columns :data:`HEADING_COLUMNS` are computed from (:func:`heading_speeds`).
_HEADING_SOURCES = ("yaw", "velocity_x_fixed", "velocity_y_fixed")


class _Column:
    """An array seen as a table column (``.to_numpy()``), for :func:`whipple_kick.model.energy.balance_residual`.

    That function reads table columns; its module is one of the sources that key the compiled model's cache,
    so the lean path adapts to it instead of changing it (which would rebuild the model for every user).
    """

    __slots__ = ("values",)

    def __init__(self, values):
        self.values = values

    def to_numpy(self):
        return self.values


def _all_finite(values, columns):
    """Whether ``values[:, columns]`` is finite everywhere (``values``: a 2-D array of samples by column).

    Every column is summed at once, as the product of a row of ones with
    ``values`` (one matrix-vector product over the whole array, without a
    copy, a mask or a pass per run of columns: the sums of strided 2-D views
    cost ~3 M instructions a case): a sum is finite only where every term is
    (a product with 1 is the term itself; a NaN or an infinity carries
    through), so only a column whose sum is not (a non-finite term, or
    finite terms overflowing) is looked at value by value. The columns not
    asked about (the outputs left out, NaN) are not looked at.
    """
    with np.errstate(over="ignore", invalid="ignore"):   # an overflowing sum, inf - inf: not the caller's to hear
        sums = np.ones(values.shape[0]) @ values
    return all(np.isfinite(values[:, k]).all() for k in columns if not math.isfinite(sums[k]))


def _copied(values, entries):
    """``{name: values[:, index] + 0.0}`` for the ``(name, index)`` entries (+ 0.0: no -0.0, as in the table).

    The columns are copied in one gather, each a contiguous row of the copy,
    and + 0.0 is added in place: the same values as a copy of each column
    plus 0.0, at half the cost.
    """
    if not entries:
        return {}
    block = values.T[[index for _, index in entries]]
    block += 0.0
    return {name: row for (name, _), row in zip(entries, block, strict=True)}


def _values(frame, column):
    """One column of a trajectory table or of :func:`trajectory_columns`' mapping as an array (no copy)."""
    return np.asarray(frame[column])


def _after_kick(time):
    """Which samples are at or after the kick start (``time >= 0``): a slice where they are the last ones, as in
    every run (the columns' views then, not masked copies: the same values in the same order), else the mask."""
    after = time >= 0.0
    first = time.size - int(np.count_nonzero(after))
    return slice(first, None) if after[first:].all() else after


def _source(entry, traj, outs):
    """The values of one ``(name, source, index)`` entry of :func:`frame_layout` (a state or an output)."""
    _, source, index = entry
    return traj.x[:, index] if source == "state" else outs[:, index]


def heading_speeds(yaw, vx_fixed, vy_fixed):
    """The rear contact's velocity along the heading (:data:`HEADING_COLUMNS`) from yaw and the fixed-axes velocity."""
    return {"forward_speed": np.cos(yaw) * vx_fixed + np.sin(yaw) * vy_fixed,
            "lateral_speed": -np.sin(yaw) * vx_fixed + np.cos(yaw) * vy_fixed}


#: The energy balance's inputs (:func:`whipple_kick.model.energy.balance_residual`).
_BALANCE_INPUTS = frozenset((*energy.STORED, *energy.SUPPLIED, *energy.DISSIPATED))


def summary_columns(tyre_transient="carcass"):
    """The trajectory columns :func:`summarise` reads (the metrics, recovery, peaks, tyre ranges, energy, numerics,
    and those the declared criteria's functions read, :attr:`whipple_kick.simulate.criteria.Criterion.columns`)."""
    # The patch slip (the tyre extrapolation's), where the form has it among its declared columns.
    declared = {col for col, _, _, _ in transient.FORMS[tyre_transient].columns}
    patch = [c for c in ("slip_patch_rear", "slip_patch_front") if c in declared]
    return ("time", *analysis.COLUMNS, *RECOVERY_STATES, *PEAK_COLUMNS, *patch, "slip_rear", "slip_front",
            "fz_rear", "fz_front", *[c for c, _ in energy.COLUMNS.values()], *_BALANCE_INPUTS,
            "holonomic_residual", BALANCE_COLUMN, *(c for k in criteria.CRITERIA.values() for c in k.columns_read))


def column_names(tyre_transient="carcass", model=slip.layout.BASE):
    """The names of :func:`trajectory_frame`'s columns, in order."""
    return [name for name, _, _ in frame_layout(tyre_transient, model)] + [BALANCE_COLUMN]


@functools.cache
def frame_layout(tyre_transient="carcass", model=slip.layout.BASE):
    """The columns of :func:`trajectory_frame` before the balance residual: ``(name, source, index)``.

    ``source`` is ``"state"`` (``index`` into the state vector), ``"output"``
    (into the model's ``OUTPUT_NAMES``) or ``"derived"`` (time, and the
    heading speeds from yaw and the fixed-axes velocity). ``model``: the
    run's :class:`~whipple_kick.model.slip.layout.Layout`; its parts' states
    follow the bicycle's coordinates and speeds, their outputs the others.
    """
    layout = [("time", "derived", None)]
    layout += [(name, "state", slip.X[q]) for q, (name, _) in COORDINATE_COLUMNS.items()]
    layout += [(model.COLUMNS[q][0], "state", model.X[q]) for p in model.parts for q in p.coordinates]
    layout += [(name, "output", slip.OUT[u]) for u, (name, _) in SPEED_COLUMNS.items()]   # u5 u6 u8 too
    layout += [(model.COLUMNS[u][0], "state", model.X[u]) for p in model.parts for u in p.speeds]
    layout += [(name, "derived", None) for name in HEADING_COLUMNS]
    layout += [(name, "output", slip.OUT[o]) for o, name in APPLIED_COLUMNS.items()]
    # The tyre form's own columns (the patch slip is an output: the state itself in the contact forms).
    layout += [(col, source, (slip.X if source == "state" else slip.OUT)[name])
               for col, source, name, _ in transient.FORMS[tyre_transient].columns]
    layout += [(name, "output", slip.OUT[o]) for o, name in OUTPUT_COLUMNS.items()]
    layout += [(o, "output", model.OUT[o]) for o in model.PART_OUTPUTS]
    layout += [(name, "state", slip.X[state]) for state, (name, _) in energy.COLUMNS.items()]
    return tuple(layout)


def with_units(frame):
    """``frame`` with each column named ``"<name> [<unit>]"`` (units from :data:`UNITS`), as in trajectory.csv.

    Example
    -------
    >>> import pandas as pd
    >>> list(with_units(pd.DataFrame({"time": [0.0], "roll": [0.1]})).columns)
    ['time [s]', 'roll [rad]']
    """
    return frame.rename(columns={c: f"{c} [{unit_of(c)}]" for c in frame.columns})


def check_trajectory(frame, summary, scenario, path):
    """Refuse a trajectory table that is not the whole run its summary describes (one-line InputError).

    The run's samples are known from the scenario and the summary: every
    multiple of 1/``output_rate`` from ``-settle`` to ``end_time_s``
    (:func:`whipple_kick.simulate.integration.sample_times`; a fall or a failure
    ends the run early and adds its own last sample). A table cut short (an
    interrupted copy, a full disk), one with a row missing, a row of text or
    an empty cell (a row cut in the middle) is refused, naming what is wrong.
    Times are compared to 1e-9 s: trajectory.csv keeps 13 significant digits.
    """
    where = f"{str(path)!r}"
    if "time" not in frame:
        raise InputError(f"{where} has no time column ('time [s]'): not a trajectory of simulate")
    if frame.empty:   # the header alone (a copy cut after its first line): every column reads as text
        raise InputError(f"{where} is empty: it has the header but no rows (a truncated or damaged file)")
    if not all(str(t).startswith(("float", "int")) for t in frame.dtypes):
        bad = next(c for c, t in frame.dtypes.items() if not str(t).startswith(("float", "int")))
        raise InputError(f"{where}: column {bad!r} holds a value that is not a number (a damaged file)")
    values = frame.to_numpy(dtype=float)
    if values.size and not np.isfinite(values).all():
        row = int(np.flatnonzero(~np.isfinite(values).all(axis=1))[0])
        raise InputError(f"{where}: row {row + 2} has an empty or non-finite cell (a damaged or truncated file)")
    time = frame["time"].to_numpy(dtype=float)
    tol = 1e-9
    try:
        end = float(summary["end_time_s"])
    except (KeyError, TypeError, ValueError):
        raise InputError(f"{str(path.parent / SUMMARY_FILE)!r} has no end_time_s: not a run summary") from None
    expected = sample_times(scenario)
    expected = expected[expected <= end + tol]
    if not time.size or abs(time[-1] - end) > tol or abs(time[0] - expected[0]) > tol:
        last = f"{time[-1]:g} s" if time.size else "no rows"
        raise InputError(f"{where} is truncated or not this run's: it ends at {last} with {time.size} rows, but "
                         f"{SUMMARY_FILE} says the run went from {expected[0]:g} to {end:g} s "
                         f"({expected.size} samples at {scenario.output_rate:g} Hz or more)")
    if np.any(np.diff(time) < 0.0):
        raise InputError(f"{where}: the time column decreases (a damaged file)")
    found = np.searchsorted(time, expected - tol)
    missing = (found >= time.size) | (np.abs(time[np.minimum(found, time.size - 1)] - expected) > tol)
    if missing.any():
        raise InputError(f"{where} misses {int(missing.sum())} of the run's {expected.size} samples (the first at "
                         f"time {expected[missing][0]:g} s): a damaged file")


def read_trajectory(path):
    """trajectory.csv as a DataFrame with the plain column names of :attr:`Result.trajectory` (units dropped).

    ``pandas.read_csv(path)`` reads the same file with the units in the names (``"roll [rad]"``).
    """
    frame = fileio.read_csv(path, "trajectory")
    return frame.rename(columns=lambda c: c.split(" [", 1)[0])


def response_metrics(df, baseline, x0, scenario, traj):
    """Section 8.3 metrics (``metrics``, ``unavailable``) and the recovery of a (possibly partial) run."""
    fall_roll = math.radians(scenario.fall_angle_deg)
    ended = None
    if traj.fell and traj.fall_time < 0.0:
        # A rider unstable enough to fall while riding steadily (linear_stability says so): no kick response.
        ended = f"fell {-traj.fall_time:.3f} s before the kick start: there is no response to the kick"
    elif traj.fell:
        ended = f"fell {traj.fall_time:.3f} s after the kick start"
    elif traj.failed:
        ended = "the integration failed before the end of the run"
    if traj.fell and traj.fall_time < 0.0:
        return no_response_metrics(ended), {"time_s": None, "reason": ended, "signals": {}}
    try:
        metrics = analysis.kick_metrics(df, t_kick=0.0, baseline=baseline, include_spectra=False,
                                        fall_roll=fall_roll)
        rec = analysis.recovery(df, 0.0, rate_baselines(x0), ended=ended)
    except InputError as exc:   # a failure so early that too little of the response exists
        metrics = no_response_metrics(f"no response to analyse: {exc}")
        rec = {"time_s": None, "reason": ended or str(exc), "signals": {}}
    # The fall is the integrator's exact event (summary fell, fall_time_s): kick_metrics' own estimate of it,
    # from |roll| up to the limit, is left out of the summary (DUPLICATE_METRICS).
    unavailable = metrics.setdefault("unavailable", {})
    if ended is not None and metrics.get("last_peak_time") is not None:
        # The last peak above 8 % before a fall or a failure is not the end of the response.
        metrics["last_peak_time"], unavailable["last_peak_time"] = None, ended
    return metrics, rec


def no_response_metrics(reason):
    """The metrics of a run without a response to analyse (say a fall before the kick): every one unavailable.

    The same keys as :func:`whipple_kick.simulate.analysis.kick_metrics` gives (no peaks, each
    peak metric None), so tables of runs keep their columns; ``unavailable`` names ``reason`` for each.
    """
    keys = ["peak_times", "peak_values", "last_peak_time",
            *(f"{name}_{a}_{b}" for a, b in analysis.PEAK_PAIRS for name in ("log_decrement", "damping_ratio",
                                                                              "period")), "period"]
    return {"n_peaks": 0, "peak_times": [], "peak_values": [], "peak_stop_reason": reason,
            **dict.fromkeys(keys[2:]), "unavailable": dict.fromkeys(keys, reason)}


#: The recovery's signals and the states they are: column -> state.
RECOVERY_STATES = {"yaw_rate": "u3", "roll_rate": "u4", "steer_rate": "u7"}


def rate_baselines(x0):
    """Steady value [rad/s] of each recovery signal (:data:`RECOVERY_STATES`) in the state ``x0``."""
    return {name: float(x0[slip.X[state]]) for name, state in RECOVERY_STATES.items()}


def unit_suffix(unit):
    """A unit as a key suffix, as every summary key ends: ``"rad/s"`` -> ``"rad_s"``, ``"N m"`` -> ``"n_m"``.

    Example
    -------
    >>> unit_suffix("rad/s"), unit_suffix("N m"), unit_suffix("m/s^2")
    ('rad_s', 'n_m', 'm_s2')
    """
    return unit.lower().replace("/", "_").replace(" ", "_").replace("^", "")


#: Summary keys of the :func:`whipple_kick.simulate.analysis.kick_metrics` entries renamed to carry their unit and
#: reference (CHANGELOG.md lists old -> new); the ``period_*`` entries get ``_s``, dimensionless ones
#: (``n_peaks``, ``log_decrement_*``, ``damping_ratio_*``) keep their names.
METRIC_KEYS = {"peak_times": "yaw_rate_peak_times_s", "peak_values": "yaw_rate_peaks_from_steady_rad_s",
               "last_peak_time": "last_peak_time_s"}
#: kick_metrics entries the summary holds once elsewhere: ``fell``, ``fall_time_s`` at the top, the largest
#: absolute values in ``peaks``.
DUPLICATE_METRICS = ("fell", "fall_time", *(f"max_abs_{name}" for name in PEAK_COLUMNS))


def metric_key(name):
    """The summary key of a :func:`whipple_kick.simulate.analysis.kick_metrics` entry (:data:`METRIC_KEYS`).

    Example
    -------
    >>> metric_key("last_peak_time"), metric_key("period_1_3"), metric_key("damping_ratio_1_3")
    ('last_peak_time_s', 'period_1_3_s', 'damping_ratio_1_3')
    """
    return METRIC_KEYS.get(name, f"{name}_s" if name.startswith("period") else name)


def _summary_metrics(metrics):
    """(metrics, unavailable) of the summary: keys renamed by :func:`metric_key`, duplicates left out."""
    values = {metric_key(k): v for k, v in metrics.items() if k != "unavailable" and k not in DUPLICATE_METRICS}
    missing = {metric_key(k): v for k, v in metrics["unavailable"].items() if k not in DUPLICATE_METRICS}
    return values, missing


def _recovery_section(recovery, baselines):
    """The recovery with each signal's first peak named "from steady", its steady value and its 5 % band."""
    signals = {}
    for name, entry in recovery["signals"].items():
        peak = entry["first_peak_rad_s"]
        signals[name] = {"first_peak_from_steady_rad_s": peak, "steady_rad_s": baselines[name],
                         "band_rad_s": None if peak is None else analysis.SETTLING_FRACTION * abs(peak),
                         "time_s": entry["time_s"], "reason": entry["reason"]}
    return {**recovery, "signals": signals}


def clean(value):
    """JSON-ready copy: numpy scalars/arrays to Python, NaN/inf refused."""
    kind = type(value)
    # The summary's most common leaves first, by exact type (a Python float or string is its own copy): the same
    # values as the checks below give them, some 500 per case.
    if kind is float:
        if not math.isfinite(value):
            raise SimulationError(f"non-finite value {value} in the summary")
        return value
    if kind is str or value is None:
        return value
    if kind is dict:
        return _clean_dict(value)
    if isinstance(value, dict):
        return {str(k): clean(v) for k, v in value.items()}
    if kind is list or kind is tuple:
        return [v if type(v) is float and math.isfinite(v) else clean(v) for v in value]
    if isinstance(value, (list, tuple, np.ndarray)):
        return [clean(v) for v in value]
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        v = float(value)
        if not math.isfinite(v):
            raise SimulationError(f"non-finite value {v} in the summary")
        return v
    if isinstance(value, complex):
        return [clean(value.real), clean(value.imag)]
    return value


def _clean_dict(value):
    """:func:`clean` of a dict: its string keys and its finite float, string, None, bool and int leaves as they
    are (each its own copy, as clean gives it), without a call per leaf; the rest through clean."""
    out = {}
    for k, v in value.items():
        kind = type(v)
        if kind is str or v is None or kind is bool or kind is int or (kind is float and math.isfinite(v)):
            out[k if type(k) is str else str(k)] = v
        else:
            out[k if type(k) is str else str(k)] = clean(v)
    return out


def _rear_wheel_torque(steady, start_outputs):
    """Summary entries of the steady rear-wheel torque T6c: value, sign convention, role, and what it balances.

    ``start_outputs`` is ``(dx, outputs)`` of the compiled model at ``steady``.
    """
    dx, out = start_outputs
    torque = float(steady.params["T6c"])
    power = {name: float(dx[slip.X[state]]) for name, state in (
        ("rear_wheel_torque", "W_wheel"), ("zero_slip_forces", "W_zero_slip"), ("aligning_moments", "W_moment"),
        ("sliding", "D_slide"))}
    power["sliding"] = -power["sliding"]   # dissipation enters the balance with a minus
    role = "none" if torque == 0.0 else ("brake" if torque * out[slip.OUT["u6"]] < 0.0 else "drive")
    return {
        "rear_wheel_torque_n_m": torque,
        "rear_wheel_torque_convention": ("on the rear wheel about the rear frame's C.y axis (pointing to the "
                                         "rider's right); + opposes forward rolling (the wheel spins about -C.y)"),
        "rear_wheel_torque_role": role,
        "steady_power_w": power,
    }


def _energy_summary(df, jumps, scenario):
    """Totals of the energy accounting after the kick, the balance residual and the velocity jumps."""
    after = _values(df, "time") >= 0.0
    totals = {f"{column}_j": float(_values(df, column)[-1]) for column, _ in energy.COLUMNS.values()}
    # The stored energy at the last sample and at the first one after the kick start, each summed as the
    # whole column's sum would (the same terms, the same order), without the column.
    kick = int(after.argmax()) if after.size else 0
    stored = [sum(_values(df, c)[k] for c in energy.STORED) for k in (-1, kick)]
    dissipation = _values(df, "sliding_dissipation") + _values(df, "damper_dissipation")
    residual = np.abs(_values(df, BALANCE_COLUMN))
    return {
        "convention": ("works done ON the bicycle and dissipations, cumulative from the kick start (J); "
                       "stored = kinetic + potential + springs (vertical tyre springs, and with a rider's body the hip "
                       "and arm springs) + carcasses; dampers = vertical tyre dampers and, with a body, the hip "
                       "and arm dampers; balance residual = "
                       "change of stored - (works - dissipations)"),
        **totals,
        "stored_change_after_kick_j": float(stored[0] - stored[1]) if after.size and after[kick] else 0.0,
        "balance_residual_max_abs_j": float(residual.max()),
        "dissipation_largest_decrease_j": float(max(0.0, -np.diff(dissipation).min())) if after.size > 1 else 0.0,
        "plate_stop": scenario.plate_stop,
        "velocity_jumps": jumps,
    }


# ------------------------------------------------------------------ the summary

def summarise(scenario, kick, assembly, solution, frame, *, custom_tyres=False) -> dict:
    """The JSON-ready summary of a run, section by section (see :func:`whipple_kick.simulate.simulation.run`).

    Parameters
    ----------
    scenario : whipple_kick.simulate.scenario.Scenario
    kick : whipple_kick.library.inputs.Kick
    assembly : whipple_kick.simulate.assembly.Assembly
    solution : whipple_kick.simulate.integration.Solution
    frame : pandas.DataFrame or dict
        :func:`trajectory_frame` of the solution, or :func:`trajectory_columns` (the same summary).
    custom_tyres : bool
        The run used the caller's tyre objects (not the scenario's tyre and pressures).

    Returns
    -------
    dict
        No NaN, numpy types converted (:func:`clean`).
    """
    traj = solution.states
    baseline = float(assembly.reference.x[slip.X["u3"]])
    # Derivatives and outputs at the start state, read by the steady and carcass sections.
    start_outputs = slip.CompiledRHS(assembly.start.params).outputs(0.0, assembly.start.x)
    metrics, recovery = response_metrics(frame, baseline, assembly.reference.x, scenario, traj)
    # kick_metrics' largest absolute values after the kick (DUPLICATE_METRICS) are the peaks section's: the same
    # samples, the same maximum; it has them where it had a response to analyse.
    largest = {name: metrics[f"max_abs_{name}"] for name in PEAK_COLUMNS if metrics.get(f"max_abs_{name}") is not None}
    recovery = _recovery_section(recovery, rate_baselines(assembly.reference.x))
    metrics, unavailable = _summary_metrics(metrics)
    summary = {
        "outcome": "failed" if traj.failed else "fell" if traj.fell else "completed",
        # Recovered: yaw, roll and steer rates all settled within 5 % of their first peaks (recovery.time_s).
        "recovered": not (traj.failed or traj.fell) and recovery["time_s"] is not None,
        "fell": bool(traj.fell),
        "fall_time_s": traj.fall_time,
        "fall_reason": traj.fall_reason,
        "end_time_s": float(_values(frame, "time")[-1]),
        "message": traj.message,
        "bicycle": _bicycle_section(assembly, start_outputs),
        "tyres": {**_tyres_section(scenario, assembly, custom_tyres),
                  "carcass": _carcass_section(scenario, assembly, start_outputs),
                  "extrapolation": extrapolation(frame, assembly.rear, assembly.front)},
        "controller": _controller_section(scenario, assembly),
        "linear_stability": assembly.stability,
        "kick": kick.summary(scenario.kick_direction),
        "steady_state": _steady_section(scenario, assembly, baseline, start_outputs),
        "peaks": _peaks(frame, largest),
        "energy": _energy_summary(frame, solution.jumps, scenario),
        "recovery": recovery,
        "metrics": metrics,
        "metrics_unavailable": unavailable,
        "numerics": _numerics_section(scenario, solution, frame),
        "scenario": scenario.to_dict(),
        "units": _column_units(column_names(scenario.tyre_transient, solution.model)),
        "provenance": provenance.record(provenance.input_files(scenario, custom_tyres)),
    }
    # The declared criteria the sections above do not report (criteria.summary_section): their values [s].
    summary["criteria"] = criteria.summary_section(summary, frame)
    return clean(summary)


#: What the bicycle section's two kinds of load are (summary.json says it beside them; docs/simulate.md).
LOADS_ARE = ("static_load_* and rear_load_share: rigid-contact statics of the upright bicycle with its rider, no tyre "
             "compression (what the rider is sized for: fz_n, rear_load_share); steady_load_* and "
             "steady_rear_load_share: the tyres' normal forces in the steady motion the run starts from (tyres "
             "compressed, frame pitched, a steady turn's lean)")


def _bicycle_section(assembly, start_outputs):
    """The bicycle with its rider (:func:`~whipple_kick.simulate.assembly.build_bicycle`'s info) and the run's steady
    normal loads beside its static ones, each named for which it is (:data:`LOADS_ARE`)."""
    _, out = start_outputs
    rear, front = float(out[slip.OUT["fz_r"]]), float(out[slip.OUT["fz_f"]])
    return {**assembly.bicycle, "steady_load_rear_n": rear, "steady_load_front_n": front,
            "steady_rear_load_share": rear / (rear + front), "loads_are": LOADS_ARE}


def _tyres_section(scenario, assembly, custom_tyres):
    rear, front = scenario.pressures
    return {
        "name": f"custom: rear {assembly.rear!r}, front {assembly.front!r}" if custom_tyres else scenario.tyre,
        "coefficient_set": scenario.coefficient_set,
        "friction": scenario.friction, "symmetric": scenario.symmetric_tyres,
        "transient": scenario.tyre_transient,
        "pressure_rear_kpa": None if custom_tyres else rear,
        "pressure_front_kpa": None if custom_tyres else front,
        "notes": assembly.tyre_notes,
        # The tyre files' own warnings about their data (custom tyre objects may have none).
        "data_warnings": sorted({w for w in (getattr(assembly.rear, "data_warning", None),
                                             getattr(assembly.front, "data_warning", None)) if w}),
    }


def _carcass_section(scenario, assembly, start_outputs):
    """The carcass tyre's stiffness, the load it is taken at (the run's start) and its options; None otherwise."""
    if scenario.tyre_transient != "carcass":
        return None
    # The loads the stiffness was taken at: those of the state the run starts from (the kick start).
    _, out = start_outputs
    params = assembly.params
    return {
        "stiffness_rear_n_per_m": params["ccr"], "stiffness_front_n_per_m": params["ccf"],
        "reference_load_rear_n": float(out[slip.OUT["fz_r"]]), "reference_load_front_n": float(out[slip.OUT["fz_f"]]),
        "reference_load_is": "each wheel's normal load in the steady motion the run starts from: "
                             "stiffness = cornering stiffness there / relaxation length",
        "sliding": scenario.carcass_sliding, "damping_n_s_per_m": scenario.carcass_damping,
        "sliding_viscosity_n_s_per_m": params["carcass_viscosity"],
        "patch_slip_cap_deg": carcass.PATCH_SLIP_CAP_DEG,
    }


def extrapolation(frame, rear, front):
    """Where a run leaves the ranges its tyre fits were measured over (after the kick start).

    Per wheel: the measured ``|slip|`` and load range (the tyre file's
    ``[measured]`` table, None when it has none) and the time [s] the patch
    slip (the slip the steady curve is evaluated at), the kinematic slip and
    the normal load spend outside them, with their extremes.

    Parameters
    ----------
    frame : pandas.DataFrame or dict
        A trajectory table (:func:`trajectory_frame`) or its columns (:func:`trajectory_columns`).
    rear, front : whipple_kick.library.tyres.Tyre

    Returns
    -------
    dict
        ``rear`` and ``front``.
    """
    rows = _after_kick(_values(frame, "time"))

    def after(column):   # the column's values after the kick start (no copy of the whole table)
        return _values(frame, column)[rows]

    t = after("time")
    dt = np.diff(t, append=t[-1]) if t.size else t

    def seconds(mask):
        return float(np.sum(dt[mask]))

    def beyond(values, largest, limit):
        # seconds(values > limit): none is beyond where their largest is not (then the sum of none, 0.0)
        return seconds(values > limit) if largest > limit else 0.0

    out = {}
    for wheel, tyre in (("rear", rear), ("front", front)):
        measured = getattr(tyre, "measured", None)
        patch_column = f"slip_patch_{wheel}" if f"slip_patch_{wheel}" in frame else f"slip_{wheel}"
        kinematic = np.degrees(np.abs(after(f"slip_{wheel}")))
        # Where the form has no patch slip, it is the kinematic slip: the same values, computed once.
        patch = kinematic if patch_column == f"slip_{wheel}" else np.degrees(np.abs(after(patch_column)))
        load = after(f"fz_{wheel}")
        entry = {"max_abs_patch_slip_deg": float(patch.max(initial=0.0)),
                 "max_abs_kinematic_slip_deg": float(kinematic.max(initial=0.0)),
                 # The true extremes over the run after the kick (None when it has no such sample): an
                 # ``initial`` of 0 would make every minimum of a positive load 0.
                 "max_load_n": float(load.max()) if load.size else None,
                 "min_load_n": float(load.min()) if load.size else None}
        if measured is None:
            entry["measured"] = None
        else:
            slip_limit, low, high = measured["slip_deg"], measured["load_min"], measured["load_max"]
            kinematic_beyond = beyond(kinematic, entry["max_abs_kinematic_slip_deg"], slip_limit)
            inside = load.size and low <= entry["min_load_n"] and entry["max_load_n"] <= high   # no sample outside
            entry.update({
                "measured": {"slip_deg": slip_limit, "load_n": [low, high]},
                "patch_slip_beyond_s": (kinematic_beyond if patch is kinematic
                                        else beyond(patch, entry["max_abs_patch_slip_deg"], slip_limit)),
                "kinematic_slip_beyond_s": kinematic_beyond,
                "load_outside_s": 0.0 if inside else seconds((load < low) | (load > high)),
                "duration_s": float(t[-1] - t[0]) if t.size else 0.0,
            })
        out[wheel] = entry
    return out


def extrapolation_line(summary):
    """One line saying where the run's tyre data were extrapolated (None when nothing is known)."""
    parts = []
    for wheel, e in (summary["tyres"].get("extrapolation") or {}).items():
        m = e.get("measured")
        if not m or e["max_load_n"] is None:   # no tyre data, or no sample after the kick start
            continue
        parts.append(f"{wheel}: patch slip beyond +-{m['slip_deg']:g} deg for {e['patch_slip_beyond_s']:.2f} s "
                     f"(max {e['max_abs_patch_slip_deg']:.0f} deg; kinematic slip max "
                     f"{e['max_abs_kinematic_slip_deg']:.0f} deg), load outside {m['load_n'][0]:g}-"
                     f"{m['load_n'][1]:g} N for {e['load_outside_s']:.2f} of {e['duration_s']:.2f} s "
                     f"(max {e['max_load_n']:.0f} N)")
    return "tyre fits extrapolated: " + "; ".join(parts) if parts else None


def _controller_section(scenario, assembly):
    kind, gains = assembly.controller, assembly.gains
    poles = assembly.design_poles
    return {
        "type": kind, "gain_scale": None if kind == "custom gains" else scenario.gain_scale,
        "design_speed_m_s": {"lqr": scenario.lqr_design_speed, "thesis": THESIS_DESIGN_SPEED}.get(kind),
        "rider": assembly_module.who_rides(scenario, kind),
        "gains": gains,
        "gain_units": {name: symbols.info(name).unit for name in gains},
        "law": assembly_module.control_law(gains),
        # The LQR design's own poles, at its design speed (at the run's speed, for the gains used:
        # linear_stability.poles_no_slip_model_1_s).
        "design_poles_1_s": None if poles is None else [[p.real, p.imag] for p in poles],
        "warning": None if kind == "custom gains" else assembly_module.thesis_gains_warning(scenario.gains_spec),
    }


def _steady_section(scenario, assembly, baseline, start_outputs):
    start, reference = assembly.start, assembly.reference
    x0 = start.x
    if scenario.start == "steady":
        found_by = assembly.found.route
    else:
        found_by = (f"upright start (start 'upright'): not a steady motion, the tyres' zero-slip forces act from "
                    f"t = 0 (largest lateral acceleration there {start.unknowns['largest_rate']:.3g} m/s^2 or "
                    f"rad/s^2); yaw-rate peaks and recovery are measured from "
                    + (f"the steady motion's yaw rate {baseline:.4g} rad/s" if reference is not start
                       else "upright running (no steady motion with these tyres)"))
    return {
        "speed_m_s": scenario.speed,
        "roll_rad": float(x0[slip.X["q4"]]), "steer_rad": float(x0[slip.X["q7"]]),
        "pitch_rad": float(x0[slip.X["q5"]]), "yaw_rate_rad_s": float(x0[slip.X["u3"]]),
        "yaw_rate_baseline_rad_s": baseline,
        "lateral_drift_m_s": float(x0[slip.X["u2"]]),
        "compression_rear_m": float(x0[slip.X["q9"]]), "compression_front_m": float(x0[slip.X["q10"]]),
        # the leaning rider's steady lean at the hip (0 without the trunk part, and from an upright start)
        "upper_body_lean_rad": float(start.unknowns.get("q11", 0.0)),
        # An upright start's front contact below the ground (+; start_pitch "uncompressed": the authors' code).
        "front_contact_below_ground_m": start.unknowns.get("front_contact_offset_m"),
        **_rear_wheel_torque(start, start_outputs),
        "residual": float(start.residual),
        "found_by": found_by,
    }


#: The summary's key of each peak column's largest absolute value (the bicycle's columns: their units are fixed).
_PEAK_KEYS = {name: f"max_abs_{name}_absolute_{unit_suffix(_BICYCLE_UNITS[name])}" for name in PEAK_COLUMNS}


def _peaks(frame, known):
    """The largest absolute value of each of :data:`PEAK_COLUMNS` after the kick (0 without a sample there), those
    of ``known`` ({column: value}, found already) as they are."""
    after = _after_kick(_values(frame, "time")) if len(known) < len(_PEAK_KEYS) else None
    return {key: known[name] if name in known else float(np.max(np.abs(_values(frame, name)[after]), initial=0.0))
            for name, key in _PEAK_KEYS.items()}


def _numerics_section(scenario, solution, frame):
    traj = solution.states
    return {
        "method": "LSODA", "rtol": scenario.rtol, "piecewise": scenario.piecewise,
        "plate_stop": scenario.plate_stop, "kick_heading": scenario.kick_heading,
        "breakpoints_s": list(solution.breakpoints), "nfev": int(traj.nfev), "njev": int(traj.njev),
        # What the budget counts: LSODA's evaluations and those inside its Jacobians.
        "evaluations": int(traj.evaluations),
        "budget": {"allowance": lsoda.DEFAULT_BUDGET.allowance,
                   "per_simulated_second": lsoda.DEFAULT_BUDGET.per_second},
        "integration_wall_s": solution.wall_s,
        "max_abs_holonomic_m": float(np.max(np.abs(_values(frame, "holonomic_residual")))),
        "model_hash": slip.model_hash(solution.model),
    }


# ------------------------------------------------------------------ comparing runs

#: Rows of :func:`compare_table`: the results by their sweep-table names
#: (:func:`flatten_summary`), then the set-up.
COMPARE_ROWS = (
    "outcome", "recovered", "fall_time_s", "fall_reason", "recovery.time_s", "recovery.last_to_settle",
    *(f"recovery.signals.{name}.time_s" for name in RECOVERY_STATES),
    *(f"recovery.signals.{name}.first_peak_from_steady_rad_s" for name in RECOVERY_STATES),
    "last_peak_time_s", "damping_ratio_1_3", "period_s",
    *(f"peaks.max_abs_{name}_absolute_{unit_suffix(UNITS[name])}" for name in PEAK_COLUMNS),
    "tyres.name", "tyres.pressure_rear_kpa", "tyres.pressure_front_kpa", "tyres.transient",
    "bicycle.static_load_rear_n", "steady_state.speed_m_s", "controller.type", "controller.gain_scale",
    "kick.displacement_m", "kick.duration_s", "kick.direction", "end_time_s",
)


def run_labels(results):
    """A short label per run: the scenario fields in which the runs differ (``"pressure_kpa=300"``), else "run k".

    Example
    -------
    >>> from whipple_kick.simulate.scenario import Scenario
    >>> runs = [Result(Scenario(pressure_kpa=p), None) for p in (300.0, 400.0)]
    >>> run_labels(runs)
    ['pressure_kpa=300', 'pressure_kpa=400']
    """
    fields = [r.scenario.to_dict() for r in results]
    differ = [name for name in fields[0] if len({repr(f[name]) for f in fields}) > 1] if fields else []
    labels = [", ".join(f"{name}={f[name]:g}" if isinstance(f[name], float) else f"{name}={f[name]}"
                        for name in differ) for f in fields]
    if not differ or len(set(labels)) < len(labels):
        return [f"run {k + 1}" for k in range(len(results))]
    return labels


def checked_labels(results, labels=None):
    """``labels`` as a list, one per run (default :func:`run_labels`); InputError when the counts differ."""
    labels = run_labels(results) if labels is None else list(labels)
    if len(labels) != len(results):
        raise InputError(f"{len(labels)} labels for {len(results)} runs; give one label per run")
    return labels


def compare_table(results, labels=None):
    """The runs' results side by side: one row per quantity (:data:`COMPARE_ROWS`), one column per run.

    Parameters
    ----------
    results : sequence of Result
    labels : sequence of str, optional
        Column names (default :func:`run_labels`).

    Returns
    -------
    pandas.DataFrame
        Index ``quantity`` (the summary's names, units in them); None where a
        run has no value (e.g. the fall time of a run that recovered).

    Example
    -------
    >>> import whipple_kick as wk
    >>> runs = [wk.run(wk.Scenario(controller=c, duration=3.0)) for c in ("lqr", "off")]
    >>> compare_table(runs).loc["outcome"].tolist()
    ['completed', 'fell']
    """
    labels = checked_labels(results, labels)
    columns = {}
    for label, result in zip(labels, results, strict=True):
        flat = flatten_summary(result.summary)
        columns[label] = [flat.get(row) for row in COMPARE_ROWS]
    frame = pd.DataFrame(columns, index=pd.Index(COMPARE_ROWS, name="quantity"), dtype=object)
    return frame.where(frame.notna(), None)


#: Summary sections a table leaves out (the provenance goes once into a sweep's manifest).
_SKIPPED_SECTIONS = ("scenario", "units", "provenance")   # provenance: once, in the manifest


def _flat_value(value):
    """A summary value as a table cell, or the sentinel ``_SKIP`` for what is not a scalar."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return _SKIP


_SKIP = object()


def flatten_summary(summary):
    """Scalar results of a :func:`whipple_kick.run` summary as one flat dict.

    The Section 8.3 metrics (``summary["metrics"]``) keep their own names
    (``last_peak_time_s``, ``damping_ratio_1_3``, ``period_s``, ...); the
    yaw-rate peak times and values are JSON lists in ``yaw_rate_peak_times_s`` and
    ``yaw_rate_peaks_from_steady_rad_s``, the reasons for unavailable metrics a JSON object in
    ``metrics_unavailable``. Every other scalar is named by its path, e.g.
    ``recovery.time_s`` (the recovery time), ``recovery.signals.roll_rate.time_s``,
    ``peaks.max_abs_roll_absolute_rad``, ``linear_stability.stable``, ``steady_state.roll_rad``, ``controller.gains.kq4``,
    ``bicycle.rider_mass_kg``, ``numerics.nfev``. Lists elsewhere (the
    closed-loop poles, the tyre notes) are left out.
    """
    flat = {}
    for key, value in summary.get("metrics", {}).items():
        if isinstance(value, list):
            flat[key] = json.dumps(value)
        elif _flat_value(value) is not _SKIP:
            flat[key] = value
    flat["metrics_unavailable"] = json.dumps(summary.get("metrics_unavailable", {}), sort_keys=True)

    def walk(prefix, node):
        for key, value in node.items():
            name = f"{prefix}{key}"
            if isinstance(value, dict):
                walk(name + ".", value)
            elif _flat_value(value) is not _SKIP:
                flat[name] = value

    for key, value in summary.items():
        if key in _SKIPPED_SECTIONS or key in ("metrics", "metrics_unavailable"):
            continue
        if isinstance(value, dict):
            walk(key + ".", value)
        elif _flat_value(value) is not _SKIP:
            flat.setdefault(key, value)   # top-level "fell" equals metrics' "fell"
    return flat
